/* soft_joints.c: the joints of bodies in contact, met in the soft step's
   substeps beside the contacts (docs/joints.md, "Joints and contacts").
   A body jointed to a body in contact is a solver body too (the closure
   over the joints, made with the step's contacts), so an island of
   jointed bodies that touches anything is stepped whole by the
   substeps, and its joints are marked TB__JOINT_SOFT for the step: SHAKE
   and the evaluations' solve leave them out, and the substeps carry
   their loads. Each solve meets each joint at the poses now, rigid: its
   motor and limit rows one at a time, then its equality rows together
   (a dense solve of at most six); its error is pushed out over the drift
   apart from the velocities, as the stacks push overlaps. Moved as if
   free by the substeps and put back on its joints after them, a plank
   let a box resting on it sink through in 0.6 s, and the projection had
   to carry every load; now it only takes out what the substeps leave
   (test_joint_drives.jointed_bodies_carry_loads,
   test_lua.dropped_ragdoll_comes_to_rest). */
#include "contacts/soft_step.h"
#include "joints/joints.h"
#include "bodies/bodies.h"

#include <math.h>
#include <string.h>

/* The joints' errors are pushed out at the rate of a spring of this
   multiple of the contacts' hertz, overdamped (each capped at a quarter
   of the substep rate): Box2D v3's joint softness, twice the contact
   hertz at a damping ratio of 2. Aimed at within the velocities' solve,
   as Box2D does, such a spring held a load at an error of the load over
   m_eff omega^2: a light foot's hinge, pressed by the ground, bent by
   0.08 rad */
#define JOINT_HERTZ 2.0
#define JOINT_DAMPING_RATIO 2.0

/* A row whose pivot falls under this share of its diagonal depends on
   the rows before it (a hinge's rows at a singular pose) */
#define DEPENDENT 1e-10

static int32_t root(int32_t *parent, int32_t i)
{
    while (parent[i] != i)
        i = parent[i] = parent[parent[i]];
    return i;
}

/* A joint end's node (the bodies, then the particles), -1 for what does
   not move: the world, a pinned particle, a sleeping body */
static int32_t node_of(const tb_world *w, int32_t end)
{
    if (end == TB__JOINT_WORLD)
        return -1;
    if (tb__joint_is_particle(end)) {
        const uint32_t p = tb__joint_particle_slot(end);
        return w->particle_inv_mass[p] > 0 ? (int32_t)(w->body_count + p) : -1;
    }
    return w->body_island[end] == 0 ? end : -1;
}

/* The solver body of a node (made on first use: tb__contacts_solver_body) */
static tb_status solver_of(tb_world *w, tb__contacts *c, int32_t node, int32_t *out)
{
    if (node < 0) {
        *out = -1;
        return TB_OK;
    }
    if ((size_t)node < w->body_count)
        return tb__contacts_solver_body(w, c, TB__BODIES, (uint32_t)node, out);
    return tb__contacts_solver_body(w, c, TB__PARTICLES, (uint32_t)((size_t)node - w->body_count), out);
}

tb_status tb__soft_joints_prepare(tb_world *w, tb__contacts *c)
{
    const size_t nodes = w->body_count + w->particle_count;
    size_t j, i;
    int32_t *parent;
    tb_status st;
    c->soft_joint_count = 0;
    for (j = 0; j < w->joint_count; ++j)
        w->joint_flags[j] &= ~(uint32_t)TB__JOINT_SOFT;
    if (w->joint_count == 0 || c->body_count == 0)
        return TB_OK;
    if ((st = tb__reserve(w, (void **)&c->joint_groups, &c->joint_group_cap, 2 * nodes + 1, sizeof(int32_t))) !=
            TB_OK ||
        (st = tb__reserve(w, (void **)&c->soft_joints, &c->soft_joint_cap, w->joint_count + 1,
                          sizeof *c->soft_joints)) != TB_OK)
        return st;
    /* the nodes joined by joints; a group with a solver body in it is
       stepped by the substeps whole (touched: 1) */
    parent = c->joint_groups;
    for (i = 0; i < nodes; ++i)
        parent[i] = (int32_t)i, parent[nodes + i] = 0;
    for (j = 0; j < w->joint_count; ++j) {
        const int32_t a = node_of(w, tb__joint_end_slot(w, j, 0)), b = node_of(w, tb__joint_end_slot(w, j, 1));
        if (a >= 0 && b >= 0)
            parent[root(parent, a)] = root(parent, b);
    }
    for (i = 0; i < c->body_count; ++i) {
        const tb__solver_body *b = &c->bodies[i];
        const size_t node = b->tier == TB__BODIES ? b->slot : w->body_count + b->slot;
        parent[nodes + root(parent, (int32_t)node)] = 1;
    }
    for (j = 0; j < w->joint_count; ++j) {
        const int32_t a = node_of(w, tb__joint_end_slot(w, j, 0)), b = node_of(w, tb__joint_end_slot(w, j, 1));
        const int32_t some = a >= 0 ? a : b;
        tb__soft_joint *s;
        if (some < 0 || !parent[nodes + root(parent, some)])
            continue;
        s = &c->soft_joints[c->soft_joint_count++];
        s->joint = (uint32_t)j;
        if ((st = solver_of(w, c, a, &s->a)) != TB_OK || (st = solver_of(w, c, b, &s->b)) != TB_OK)
            return st;
        w->joint_flags[j] |= TB__JOINT_SOFT;
    }
    return TB_OK;
}

/* ---- the ends now ---------------------------------------------------------- */

/* Joint end k of soft joint s at the substep's poses and velocities: a
   solver body's, or what does not move (from the world's state) */
static void end_now(const tb_world *w, const tb__contacts *c, const tb__soft_joint *s, int k, tb__joint_end *e)
{
    const int32_t i = k ? s->b : s->a;
    const tb__soft_body *b;
    if (i < 0) {
        tb__joint_end_of(w, tb__joint_end_slot(w, s->joint, k), w->y, w->y, e);
        memset(e->v, 0, sizeof e->v);
        memset(e->w, 0, sizeof e->w);
        return;
    }
    b = &c->soft_bodies[i];
    e->slot = tb__joint_end_slot(w, s->joint, k);
    memcpy(e->x, b->x, sizeof e->x);
    memcpy(e->v, b->v, sizeof e->v);
    memcpy(e->w, b->w, sizeof e->w);
    if (b->rotates) {
        tb__matrix_of(b->q, e->R);
    } else {
        memset(e->R, 0, sizeof e->R);
        e->R[0] = e->R[4] = e->R[8] = 1;
    }
}

/* The inverse inertia now of solver body i times v (0: what does not
   move, a particle) */
static void spin_of(const tb__contacts *c, int32_t i, const double v[3], double out[3])
{
    if (i >= 0 && c->soft_bodies[i].rotates)
        tb__mul(c->soft_bodies[i].inv_world, v, out);
    else
        out[0] = out[1] = out[2] = 0;
}

/* Soft joint s's rows at the poses now (their impulses stay) */
static void rows_now(tb_world *w, tb__contacts *c, tb__soft_joint *s)
{
    tb__joint_row rows[TB__JOINT_ROWS];
    tb__joint_end e[2];
    size_t r;
    int d;
    end_now(w, c, s, 0, &e[0]);
    end_now(w, c, s, 1, &e[1]);
    tb__joint_rows(w, s->joint, &e[0], &e[1], rows);
    tb__mul(e[0].R, w->joint_anchor + 6 * s->joint, s->lever);
    for (r = 0; r < s->count; ++r) {
        const tb__joint_row *row = &rows[r];
        tb__soft_joint_row *o = &c->joint_rows[s->first + r];
        o->a = s->a, o->b = s->b;
        o->kind = row->kind;
        for (d = 0; d < 3; ++d) {
            o->normal[d] = row->lin_b[d];
            o->arm_a[d] = -row->ang_a[d];
            o->arm_b[d] = row->ang_b[d];
        }
        spin_of(c, s->a, o->arm_a, o->spin_a);
        spin_of(c, s->b, o->arm_b, o->spin_b);
        o->error = row->error;
        o->speed = row->speed;
        o->most = row->most;
    }
}

tb_status tb__soft_joints_load(tb_world *w, tb__contacts *c, double hs)
{
    size_t i, rows = 0, r;
    tb_status st;
    for (i = 0; i < c->soft_joint_count; ++i)
        rows += (size_t)tb__joint_rows_of(w, c->soft_joints[i].joint);
    if ((st = tb__reserve(w, (void **)&c->joint_rows, &c->joint_row_cap, rows + 1, sizeof *c->joint_rows)) != TB_OK)
        return st;
    c->joint_row_count = 0;
    for (i = 0; i < c->body_count; ++i)
        c->soft_bodies[i].jointed = 0;
    for (i = 0; i < c->soft_joint_count; ++i) {
        tb__soft_joint *s = &c->soft_joints[i];
        if (s->a >= 0)
            c->soft_bodies[s->a].jointed = 1;
        if (s->b >= 0)
            c->soft_bodies[s->b].jointed = 1;
        const double *force = w->joint_warm + TB__JOINT_ROWS * s->joint;
        s->first = c->joint_row_count;
        s->count = (size_t)tb__joint_rows_of(w, s->joint);
        c->joint_row_count += s->count;
        rows_now(w, c, s);
        for (r = 0; r < s->count; ++r)
            c->joint_rows[s->first + r].impulse = force[r] * hs;
        memset(s->reaction, 0, sizeof s->reaction);
    }
    return TB_OK;
}

/* Whether soft joint s moves bodies of the pass under way */
static int in_pass(const tb__contacts *c, const tb__soft_joint *s)
{
    const int32_t i = s->a >= 0 ? s->a : s->b;
    return i >= 0 && c->soft_bodies[i].pass == c->soft_pass;
}

void tb__soft_joints_now(tb_world *w, tb__contacts *c)
{
    size_t i;
    for (i = 0; i < c->soft_joint_count; ++i)
        if (in_pass(c, &c->soft_joints[i]))
            rows_now(w, c, &c->soft_joints[i]);
}

static void push(tb__contacts *c, const tb__soft_joint_row *o, double lambda)
{
    tb__soft_pair(c, o->a, o->b, lambda, o->normal, o->arm_a, o->arm_b, o->spin_a, o->spin_b);
}

static double rate(const tb__contacts *c, const tb__soft_joint_row *o)
{
    return tb__soft_relative(c, o->a, o->b, o->normal, o->arm_a, o->arm_b);
}

/* A limit apart (beyond the touching band) whose sides already part
   keeps no impulse, as a contact's point does (drop_parting in
   soft_step.c): its last impulse given again would be a blow (a
   landing's, through a knee's stop, threw a ragdoll up with more than
   its energy) */
void tb__soft_joints_warm(tb__contacts *c, double share)
{
    const double touch = TB__TOUCHING * c->settings.slop;
    size_t i, r;
    for (i = 0; i < c->soft_joint_count; ++i) {
        const tb__soft_joint *s = &c->soft_joints[i];
        for (r = s->first; in_pass(c, s) && r < s->first + s->count; ++r) {
            tb__soft_joint_row *o = &c->joint_rows[r];
            if (o->kind == TB__ROW_LIMIT && o->impulse != 0 && o->error > touch && rate(c, o) > 0)
                o->impulse = 0;
            if (o->impulse != 0)
                push(c, o, share * o->impulse);
        }
    }
}

/* J M^-1 J^T between rows o and p */
static double through(const tb__contacts *c, const tb__soft_joint_row *o, const tb__soft_joint_row *p)
{
    double k = 0;
    if (o->a >= 0)
        k += c->soft_bodies[o->a].inv_mass * tb__dot3(o->normal, p->normal) + tb__dot3(o->arm_a, p->spin_a);
    if (o->b >= 0)
        k += c->soft_bodies[o->b].inv_mass * tb__dot3(o->normal, p->normal) + tb__dot3(o->arm_b, p->spin_b);
    return k;
}

/* x = K^-1 b for the m rows rows[at[0 .. m)] together, by Cholesky, a row
   that depends on those before it left out (0) */
static void solve_block(const tb__contacts *c, const tb__soft_joint_row *rows, const size_t *at, int m, double *x)
{
    double K[TB__JOINT_ROWS][TB__JOINT_ROWS];
    int p, q, t;
    for (p = 0; p < m; ++p)
        for (q = 0; q <= p; ++q)
            K[p][q] = through(c, &rows[at[p]], &rows[at[q]]);
    for (p = 0; p < m; ++p) {
        const double diagonal = K[p][p];
        double d = diagonal;
        for (q = 0; q < p; ++q)
            d -= K[p][q] * K[p][q];
        if (!(d > DEPENDENT * diagonal)) {
            for (q = 0; q <= p; ++q)
                K[p][q] = 0;
            continue;
        }
        K[p][p] = sqrt(d);
        for (t = p + 1; t < m; ++t) {
            double u = K[t][p];
            for (q = 0; q < p; ++q)
                u -= K[t][q] * K[p][q];
            K[t][p] = u / K[p][p];
        }
    }
    for (p = 0; p < m; ++p) { /* L y = b */
        double u = x[p];
        for (q = 0; q < p; ++q)
            u -= K[p][q] * x[q];
        x[p] = K[p][p] > 0 ? u / K[p][p] : 0;
    }
    for (p = m - 1; p >= 0; --p) { /* L^T x = y */
        double u = x[p];
        for (q = p + 1; q < m; ++q)
            u -= K[q][p] * x[q];
        x[p] = K[p][p] > 0 ? u / K[p][p] : 0;
    }
}

/* Joint s's velocities solved once, rigid: its motor and limit rows one
   at a time (a motor toward its speed within its force, a limit at no
   approach where it is reached, and closing its gap within the substep
   at most where it is not), then its equality rows together at no rate.
   Its error is taken out apart (tb__soft_joints_push). */
static void solve_joint(tb__contacts *c, tb__soft_joint *s, double hs)
{
    tb__soft_joint_row *rows = c->joint_rows + s->first;
    double x[TB__JOINT_ROWS];
    size_t eq[TB__JOINT_ROWS], r;
    int m = 0, p;
    for (r = 0; r < s->count; ++r) {
        tb__soft_joint_row *o = &rows[r];
        const double k = through(c, o, o);
        double total;
        if (o->kind == TB__ROW_EQUAL) {
            eq[m++] = r;
            continue;
        }
        if (!(k > 0))
            continue;
        if (o->kind == TB__ROW_MOTOR)
            total = tb__most(-o->most * hs, tb__least(o->impulse - (rate(c, o) - o->speed) / k, o->most * hs));
        else /* a limit: C >= 0 */
            total = tb__most(o->impulse - (rate(c, o) + tb__most(o->error, 0) / hs) / k, 0);
        push(c, o, total - o->impulse);
        o->impulse = total;
    }
    for (p = 0; p < m; ++p)
        x[p] = -rate(c, &rows[eq[p]]);
    solve_block(c, rows, eq, m, x);
    for (p = 0; p < m; ++p) {
        rows[eq[p]].impulse += x[p];
        push(c, &rows[eq[p]], x[p]);
    }
}

double tb__soft_joints_rate(double hertz, double hs)
{
    return tb__soft_softness(JOINT_HERTZ * hertz, JOINT_DAMPING_RATIO, hs).bias_rate;
}

void tb__soft_joints_solve(tb__contacts *c, double hs)
{
    size_t i;
    for (i = 0; i < c->soft_joint_count; ++i)
        if (in_pass(c, &c->soft_joints[i]))
            solve_joint(c, &c->soft_joints[i], hs);
}

/* Before the drift (sign +1): each joint's error taken out at `rate`
   (1/s), its equality rows and the limits past their bounds aiming at
   -rate C together from the rates now, as a velocity that moves the
   positions over the drift and is then taken back (sign -1) without a
   trace in the momenta, as the stacks' push does with overlaps
   (tb__stacks_push, which pushes the rows it solves). */
void tb__soft_joints_push(tb__contacts *c, double rate_now, int sign)
{
    size_t i, r, at[TB__JOINT_ROWS];
    double x[TB__JOINT_ROWS];
    int m, p;
    for (i = 0; i < c->soft_joint_count; ++i) {
        tb__soft_joint *s = &c->soft_joints[i];
        tb__soft_joint_row *rows = c->joint_rows + s->first;
        if (!in_pass(c, s))
            continue;
        if (sign < 0) {
            for (r = 0; r < s->count; ++r)
                if (rows[r].push != 0)
                    push(c, &rows[r], -rows[r].push);
            continue;
        }
        for (r = 0, m = 0; r < s->count; ++r) {
            tb__soft_joint_row *o = &rows[r];
            o->push = 0;
            if (o->kind == TB__ROW_EQUAL || (o->kind == TB__ROW_LIMIT && o->error < 0))
                at[m++] = r;
        }
        for (p = 0; p < m; ++p)
            x[p] = -rate_now * rows[at[p]].error - rate(c, &rows[at[p]]);
        solve_block(c, rows, at, m, x);
        for (p = 0; p < m; ++p) {
            rows[at[p]].push = x[p];
            push(c, &rows[at[p]], x[p]);
        }
    }
}

/* The impulse a substep's rows gave (their accumulated impulses) added
   to each joint's reaction on a: the force, and the torque about a's
   anchor */
void tb__soft_joints_count(tb__contacts *c, int last)
{
    size_t i, r;
    int d;
    for (i = 0; i < c->soft_joint_count; ++i) {
        tb__soft_joint *s = &c->soft_joints[i];
        double f[3] = { 0, 0, 0 }, turn[3];
        if (!in_pass(c, s))
            continue;
        for (r = s->first; r < s->first + s->count; ++r) {
            tb__soft_joint_row *o = &c->joint_rows[r];
            const double lambda = last ? o->impulse - o->kept : o->impulse;
            if (!last)
                o->kept = o->impulse;
            for (d = 0; d < 3; ++d) {
                f[d] -= lambda * o->normal[d];
                s->reaction[3 + d] -= lambda * o->arm_a[d];
            }
        }
        tb__cross(s->lever, f, turn);
        for (d = 0; d < 3; ++d) {
            s->reaction[d] += f[d];
            s->reaction[3 + d] -= turn[d];
        }
    }
}

void tb__soft_joints_settle(tb__contacts *c, int begin)
{
    size_t i, r;
    for (i = 0; i < c->soft_joint_count; ++i) {
        const tb__soft_joint *s = &c->soft_joints[i];
        for (r = s->first; in_pass(c, s) && r < s->first + s->count; ++r)
            c->joint_rows[r].impulse = begin ? 0 : c->joint_rows[r].kept + c->joint_rows[r].impulse;
    }
}

void tb__soft_joints_store(tb_world *w, tb__contacts *c, double h, double hs)
{
    size_t i, r;
    for (i = 0; i < c->soft_joint_count; ++i) {
        const tb__soft_joint *s = &c->soft_joints[i];
        double *force = w->joint_warm + TB__JOINT_ROWS * s->joint;
        if (!in_pass(c, s))
            continue;
        for (r = 0; r < s->count; ++r)
            force[r] = c->joint_rows[s->first + r].kept / hs + 0.0;
        for (r = 0; r < 6; ++r)
            w->joint_reaction[6 * s->joint + r] = s->reaction[r] / h;
    }
}
