/* soft_step.c: the soft-step contact solver, chosen by settings.substeps
   > 0 (docs/contacts.md, "The soft-step solver"). The step's contacts are
   those tb__contacts_prepare found at the start positions; the bodies
   and particles in them are moved again from the start of the step in
   substeps of h / n, each of which
   1. adds 1/n of the step's external change of momentum (what the
      world's method gave the free motion: P and L for bodies, the
      velocity for particles);
   2. warm starts: every row's impulse of the last substep (of last step,
      for the first) is applied again;
   3. solves every row once, the normal rows soft (a spring-damper of
      `hertz` and `damping_ratio` on the overlap, pushing at most
      `max_push`), speculative where the points are still apart;
   4. moves positions: x by the velocity, q by the torque-free turn of L
      (tb__rotation_split2): symplectic Euler over the substep;
   5. relaxes: every row once more, rigid and without the push, so that the
      push moves positions and leaves no speed.
   After the substeps, points that struck faster than
   `restitution_threshold` are bounced by their normal rows, toward e times
   the approach speed they struck at.
   Rows are per point: a normal row (impulse >= 0) and two friction rows
   within the circle mu times the point's normal impulse. Every row keeps
   the arms of the start of the step (the Jacobian is that of the start
   pose); the separation is recomputed every substep from the bodies'
   displacements and first-order turns at those arms. */
#include "contacts/contacts.h"

#include <math.h>
#include <string.h>

typedef struct tb__soft_body {
    double x[3], q[4];          /* m: pose now */
    double P[3], L[3];          /* N s, N m s: momenta now (particles: P only) */
    double v[3], w[3];          /* m/s, rad/s: velocities now */
    double kick_p[3], kick_l[3];/* N s, N m s: external change of P, L per substep */
    double inv_world[9];        /* R diag(invI) R^T at q (0 for particles) */
    double shift[3], turn[3];   /* m, rad: x - x0 and the first-order turn from q0 */
} tb__soft_body;

enum { TB__SOFT_NORMAL, TB__SOFT_T1, TB__SOFT_T2, TB__SOFT_ROWS };

typedef struct tb__soft_row {
    tb__point *point;
    int32_t a, b;               /* solver bodies, -1: the static world */
    double dir[TB__SOFT_ROWS][3];            /* normal (a to b), tangents */
    double arm_a[TB__SOFT_ROWS][3], arm_b[TB__SOFT_ROWS][3]; /* r x d at each side */
    double ra[3], rb[3];        /* m: the point from each centre at the start */
    double mass[TB__SOFT_ROWS]; /* 1 / (J M^-1 J^T), at the start pose */
    double impulse[TB__SOFT_ROWS]; /* N s: accumulated in the current substep */
    double separation;          /* m: at the start of the step */
    double friction, restitution;
    double approach;            /* m/s (< 0): normal velocity at which the point struck */
    double most;                /* N s: the largest normal impulse of any substep */
    int struck;                 /* the normal row has pushed in some substep */
} tb__soft_row;

/* R diag(inv) R^T for the unit quaternion q */
static void world_inverse(const double q[4], const double inv[3], double out[9])
{
    double R[9];
    int r, col;
    tb__matrix_of(q, R);
    for (r = 0; r < 3; ++r)
        for (col = 0; col < 3; ++col)
            out[3 * r + col] = R[3 * r] * inv[0] * R[3 * col] + R[3 * r + 1] * inv[1] * R[3 * col + 1] +
                               R[3 * r + 2] * inv[2] * R[3 * col + 2];
}

/* The turn from q0 to q, to first order: 2 sin(angle / 2) times the axis */
static void first_turn(const double q[4], const double q0[4], double out[3])
{
    const double q0c[4] = { q0[0], -q0[1], -q0[2], -q0[3] };
    double dq[4];
    int k;
    tb__quat_mul(q, q0c, dq);
    for (k = 0; k < 3; ++k)
        out[k] = (dq[0] < 0 ? -2 : 2) * dq[k + 1];
}

/* Solver body i (>= 0) receives impulse j (N s, world) at arm r. */
static void push(tb__contacts *c, int32_t i, const double j[3], const double r[3])
{
    tb__soft_body *s = &c->soft_bodies[i];
    const double im = c->bodies[i].inv_mass;
    double rj[3], dw[3];
    int k;
    for (k = 0; k < 3; ++k) {
        s->P[k] += j[k];
        s->v[k] += im * j[k];
    }
    if (c->bodies[i].tier != TB__BODIES)
        return;
    tb__cross(r, j, rj);
    tb__mul(s->inv_world, rj, dw);
    for (k = 0; k < 3; ++k) {
        s->L[k] += rj[k];
        s->w[k] += dw[k];
    }
}

/* A scalar impulse along row d of row o, equal and opposite on its sides. */
static void push_row(tb__contacts *c, const tb__soft_row *o, int d, double lambda)
{
    double j[3];
    j[0] = lambda * o->dir[d][0], j[1] = lambda * o->dir[d][1], j[2] = lambda * o->dir[d][2];
    if (o->b >= 0)
        push(c, o->b, j, o->rb);
    if (o->a >= 0) {
        j[0] = -j[0], j[1] = -j[1], j[2] = -j[2];
        push(c, o->a, j, o->ra);
    }
}

/* The relative velocity of b against a along row d */
static double rate(const tb__contacts *c, const tb__soft_row *o, int d)
{
    double r = 0;
    if (o->b >= 0) {
        const tb__soft_body *s = &c->soft_bodies[o->b];
        r += tb__dot3(o->dir[d], s->v) + tb__dot3(o->arm_b[d], s->w);
    }
    if (o->a >= 0) {
        const tb__soft_body *s = &c->soft_bodies[o->a];
        r -= tb__dot3(o->dir[d], s->v) + tb__dot3(o->arm_a[d], s->w);
    }
    return r;
}

/* ... and along the normal, the part of it the substep's external kick gave */
static double kick_rate(const tb__contacts *c, const tb__soft_row *o)
{
    double r = 0, dw[3];
    if (o->b >= 0) {
        const tb__soft_body *s = &c->soft_bodies[o->b];
        tb__mul(s->inv_world, s->kick_l, dw);
        r += c->bodies[o->b].inv_mass * tb__dot3(o->dir[0], s->kick_p) + tb__dot3(o->arm_b[0], dw);
    }
    if (o->a >= 0) {
        const tb__soft_body *s = &c->soft_bodies[o->a];
        tb__mul(s->inv_world, s->kick_l, dw);
        r -= c->bodies[o->a].inv_mass * tb__dot3(o->dir[0], s->kick_p) + tb__dot3(o->arm_a[0], dw);
    }
    return r;
}

/* The separation now, from the bodies' displacements and first-order
   turns at the start's arms */
static double separation_now(const tb__contacts *c, const tb__soft_row *o)
{
    double s = o->separation, d[3];
    if (o->b >= 0) {
        const tb__soft_body *b = &c->soft_bodies[o->b];
        tb__cross(b->turn, o->rb, d);
        s += o->dir[0][0] * (b->shift[0] + d[0]) + o->dir[0][1] * (b->shift[1] + d[1]) +
             o->dir[0][2] * (b->shift[2] + d[2]);
    }
    if (o->a >= 0) {
        const tb__soft_body *a = &c->soft_bodies[o->a];
        tb__cross(a->turn, o->ra, d);
        s -= o->dir[0][0] * (a->shift[0] + d[0]) + o->dir[0][1] * (a->shift[1] + d[1]) +
             o->dir[0][2] * (a->shift[2] + d[2]);
    }
    return s;
}

/* The soft constraint's coefficients for a substep of hs: a spring of
   `hertz` (at most a quarter of the substep rate, beyond which a substep
   cannot follow it) with `damping_ratio`, met implicitly over the substep:
   the velocity it aims at is -bias_rate times the overlap, the row's mass
   is scaled by mass_scale, and impulse_scale of the accumulated impulse
   is taken back, so that a held overlap settles where the spring holds
   the load. */
typedef struct soft {
    double bias_rate, mass_scale, impulse_scale;
} soft;

static soft softness(double hertz, double zeta, double hs)
{
    const double f = fmin(hertz, 0.25 / hs), omega = 2 * 3.14159265358979323846 * f;
    const double a1 = 2 * zeta + hs * omega, a2 = hs * omega * a1, a3 = 1 / (1 + a2);
    soft s;
    s.bias_rate = omega / a1;
    s.mass_scale = a2 * a3;
    s.impulse_scale = a3;
    return s;
}

/* One pass over the rows: each point's normal row, then its friction
   rows within the circle mu times its normal impulse. With bias, the
   normal row is soft and pushes overlaps out; without (the relax), it is
   rigid and aims at no approach. A point still apart (s > 0) lets its
   gap close within the substep, never more. */
static void solve_rows(tb__contacts *c, double hs, const soft *sf, int bias)
{
    const double max_push = c->settings.max_push;
    size_t i;
    for (i = 0; i < c->soft_row_count; ++i) {
        tb__soft_row *o = &c->soft_rows[i];
        const double s = separation_now(c, o), vn = rate(c, o, TB__SOFT_NORMAL);
        double target, mass_scale = 1, impulse_scale = 0, lambda, total, t1, t2, limit, len;
        if (s > 0) {
            target = s / hs;
        } else if (bias) {
            target = fmax(sf->bias_rate * s, -max_push);
            mass_scale = sf->mass_scale;
            impulse_scale = sf->impulse_scale;
        } else {
            target = 0;
        }
        lambda = -o->mass[0] * mass_scale * (vn + target) - impulse_scale * o->impulse[0];
        total = fmax(o->impulse[0] + lambda, 0);
        lambda = total - o->impulse[0];
        o->impulse[0] = total;
        push_row(c, o, TB__SOFT_NORMAL, lambda);
        if (total > 0 && !o->struck) {
            /* the speed it struck at: from the start of this substep (u, s)
               under the kick's acceleration a, u^2 - 2 a s at the surface,
               within what the substep's velocities span */
            const double kick = kick_rate(c, o), u = vn - kick, a = kick / hs;
            double approach = vn;
            if (s > 0) {
                const double fastest = fmin(u, u + kick);
                approach = fmax(-sqrt(fmax(u * u - 2 * a * s, 0)), fastest);
            }
            o->struck = 1;
            o->approach = fmin(approach, 0);
        }
        o->most = fmax(o->most, total);
        /* friction */
        limit = o->friction * total;
        t1 = o->impulse[1] - o->mass[1] * rate(c, o, TB__SOFT_T1);
        t2 = o->impulse[2] - o->mass[2] * rate(c, o, TB__SOFT_T2);
        len = sqrt(t1 * t1 + t2 * t2);
        if (len > limit) {
            const double f = limit > 0 ? limit / len : 0;
            t1 *= f, t2 *= f;
        }
        push_row(c, o, TB__SOFT_T1, t1 - o->impulse[1]);
        push_row(c, o, TB__SOFT_T2, t2 - o->impulse[2]);
        o->impulse[1] = t1, o->impulse[2] = t2;
    }
}

static double row_mass(const tb__contacts *c, const tb__soft_row *o, int d)
{
    double k = 0, t[3];
    if (o->b >= 0) {
        const tb__soft_body *s = &c->soft_bodies[o->b];
        tb__mul(s->inv_world, o->arm_b[d], t);
        k += c->bodies[o->b].inv_mass + tb__dot3(o->arm_b[d], t);
    }
    if (o->a >= 0) {
        const tb__soft_body *s = &c->soft_bodies[o->a];
        tb__mul(s->inv_world, o->arm_a[d], t);
        k += c->bodies[o->a].inv_mass + tb__dot3(o->arm_a[d], t);
    }
    return k > 0 ? 1 / k : 0;
}

/* The bodies back at the start of the step, with the step's external
   change of momentum (the free motion's, over the start's) cut into n
   kicks. */
static void load(tb_world *w, tb__contacts *c, int n)
{
    size_t i;
    for (i = 0; i < c->body_count; ++i) {
        const tb__solver_body *b = &c->bodies[i];
        tb__soft_body *s = &c->soft_bodies[i];
        int k;
        memcpy(s->x, b->x0, sizeof s->x);
        memcpy(s->q, b->q0, sizeof s->q);
        memset(s->shift, 0, sizeof s->shift);
        memset(s->turn, 0, sizeof s->turn);
        if (b->tier == TB__BODIES) {
            const double *P = w->y + w->off[TB__BODY_MOM] + 3 * b->slot, *L = w->y + w->off[TB__BODY_ANG] + 3 * b->slot;
            for (k = 0; k < 3; ++k) {
                s->P[k] = b->p0[k], s->L[k] = b->l0[k];
                s->kick_p[k] = (P[k] - b->p0[k]) / n;
                s->kick_l[k] = (L[k] - b->l0[k]) / n;
            }
            world_inverse(s->q, b->inv_inertia, s->inv_world);
        } else {
            const double *v = w->y + w->off[TB__PARTICLE_VEL] + 3 * b->slot;
            for (k = 0; k < 3; ++k) {
                s->P[k] = b->v0[k] / b->inv_mass, s->L[k] = 0;
                s->kick_p[k] = (v[k] - b->v0[k]) / (b->inv_mass * n);
                s->kick_l[k] = 0;
            }
            memset(s->inv_world, 0, sizeof s->inv_world);
        }
        memcpy(s->v, b->v0, sizeof s->v);
        memcpy(s->w, b->w0, sizeof s->w);
    }
}

/* The rows of every point of the awake entries, in key order; warm
   started from the impulses kept last step (a step's total, cut into n
   substeps and scaled by h / h_last). */
static tb_status set_up_rows(tb_world *w, tb__contacts *c, double h, int n)
{
    const double scale = c->kept_h > 0 ? h / c->kept_h / n : 0;
    size_t i, count = 0;
    tb_status st;
    for (i = 0; i < c->entry_count; ++i)
        if (!c->entries[i].asleep)
            count += (size_t)c->entries[i].count;
    if ((st = tb__reserve(w, (void **)&c->soft_rows, &c->soft_row_cap, count + 1, sizeof *c->soft_rows)) != TB_OK)
        return st;
    c->soft_row_count = 0;
    for (i = 0; i < c->entry_count; ++i) {
        tb__entry *e = &c->entries[c->order[i].index];
        int k, d;
        if (e->asleep)
            continue;
        for (k = 0; k < e->count; ++k) {
            tb__point *p = &e->point[k];
            tb__soft_row *o = &c->soft_rows[c->soft_row_count++];
            o->point = p;
            o->a = e->body_a, o->b = e->body_b;
            memcpy(o->dir[0], e->normal, sizeof o->dir[0]);
            memcpy(o->dir[1], e->tangent[0], sizeof o->dir[1]);
            memcpy(o->dir[2], e->tangent[1], sizeof o->dir[2]);
            memcpy(o->ra, p->ra, sizeof o->ra);
            memcpy(o->rb, p->rb, sizeof o->rb);
            for (d = 0; d < TB__SOFT_ROWS; ++d) {
                tb__cross(o->ra, o->dir[d], o->arm_a[d]);
                tb__cross(o->rb, o->dir[d], o->arm_b[d]);
                o->mass[d] = row_mass(c, o, d);
            }
            o->separation = p->separation;
            o->friction = e->friction;
            o->restitution = e->restitution;
            o->approach = 0;
            o->most = 0;
            o->struck = 0;
            o->impulse[0] = scale * p->normal_impulse;
            o->impulse[1] = scale * tb__dot3(p->friction_impulse, o->dir[1]);
            o->impulse[2] = scale * tb__dot3(p->friction_impulse, o->dir[2]);
            p->speed = 0;
        }
    }
    return TB_OK;
}

/* Every row's accumulated impulse applied again */
static void warm_start(tb__contacts *c)
{
    size_t i;
    for (i = 0; i < c->soft_row_count; ++i) {
        const tb__soft_row *o = &c->soft_rows[i];
        int d;
        for (d = 0; d < TB__SOFT_ROWS; ++d)
            if (o->impulse[d] != 0)
                push_row(c, o, d, o->impulse[d]);
    }
}

/* The kick of a substep: 1/n of the step's external change */
static void kick(tb__contacts *c)
{
    size_t i;
    for (i = 0; i < c->body_count; ++i) {
        tb__soft_body *s = &c->soft_bodies[i];
        const double im = c->bodies[i].inv_mass;
        double dw[3];
        int k;
        tb__mul(s->inv_world, s->kick_l, dw);
        for (k = 0; k < 3; ++k) {
            s->P[k] += s->kick_p[k], s->v[k] += im * s->kick_p[k];
            s->L[k] += s->kick_l[k], s->w[k] += dw[k];
        }
    }
}

/* Positions over hs: x by the velocity, q by the torque-free turn of L
   (symplectic Euler over the substep: the kick first, then the drift);
   then the inverse inertia and w at the new orientation. */
static void drift(tb__contacts *c, double hs)
{
    size_t i;
    for (i = 0; i < c->body_count; ++i) {
        const tb__solver_body *b = &c->bodies[i];
        tb__soft_body *s = &c->soft_bodies[i];
        int k;
        for (k = 0; k < 3; ++k) {
            s->x[k] += hs * s->v[k];
            s->shift[k] = s->x[k] - b->x0[k];
        }
        if (b->tier == TB__BODIES) {
            tb__rotation_split2(s->q, s->L, b->inv_inertia, hs);
            tb__normalise(s->q);
            first_turn(s->q, b->q0, s->turn);
            world_inverse(s->q, b->inv_inertia, s->inv_world);
            tb__mul(s->inv_world, s->L, s->w);
        }
    }
}

/* After the substeps: each point that struck faster than the threshold,
   toward e times the speed it struck at, by its normal row alone. */
static void restitution(tb__contacts *c)
{
    const double threshold = c->settings.restitution_threshold;
    size_t i;
    for (i = 0; i < c->soft_row_count; ++i) {
        tb__soft_row *o = &c->soft_rows[i];
        double lambda, total;
        if (o->restitution == 0 || !o->struck || o->approach > -threshold || o->most == 0)
            continue;
        lambda = -o->mass[0] * (rate(c, o, TB__SOFT_NORMAL) + o->restitution * o->approach);
        total = fmax(o->impulse[0] + lambda, 0);
        push_row(c, o, TB__SOFT_NORMAL, total - o->impulse[0]);
        o->impulse[0] = total;
    }
}

/* The bodies' end state into the world; the solver bodies' pose at the
   end (x, turn) and no further motion, for the events' points. */
static void store(tb_world *w, tb__contacts *c, int n)
{
    size_t i;
    for (i = 0; i < c->body_count; ++i) {
        tb__solver_body *b = &c->bodies[i];
        const tb__soft_body *s = &c->soft_bodies[i];
        if (b->tier == TB__BODIES) {
            memcpy(w->y + w->off[TB__BODY_POS] + 3 * b->slot, s->x, sizeof s->x);
            memcpy(w->y + w->off[TB__BODY_ROT] + 4 * b->slot, s->q, sizeof s->q);
            memcpy(w->y + w->off[TB__BODY_MOM] + 3 * b->slot, s->P, sizeof s->P);
            memcpy(w->y + w->off[TB__BODY_ANG] + 3 * b->slot, s->L, sizeof s->L);
        } else {
            memcpy(w->y + w->off[TB__PARTICLE_POS] + 3 * b->slot, s->x, sizeof s->x);
            memcpy(w->y + w->off[TB__PARTICLE_VEL] + 3 * b->slot, s->v, sizeof s->v);
        }
        memcpy(b->x, s->x, sizeof b->x);
        memcpy(b->turn, s->turn, sizeof b->turn);
    }
    memset(c->motion, 0, TB__MOTION * (c->body_count + 1) * sizeof *c->motion);
    /* the impulses of the step, for the next one's warm start; a point
       touches if its normal row pushed in some substep */
    for (i = 0; i < c->soft_row_count; ++i) {
        const tb__soft_row *o = &c->soft_rows[i];
        tb__point *p = o->point;
        int k;
        p->normal_impulse = n * o->impulse[0];
        for (k = 0; k < 3; ++k)
            p->friction_impulse[k] = n * (o->impulse[1] * o->dir[1][k] + o->impulse[2] * o->dir[2][k]);
        p->active = o->most > 0;
        p->speed = o->struck && o->approach < 0 && p->active ? -o->approach : 0;
    }
}

tb_status tb__soft_step(tb_world *w, tb__contacts *c, double h)
{
    const int n = c->settings.substeps;
    const double hs = h / n;
    const soft sf = softness(c->settings.hertz, c->settings.damping_ratio, hs);
    tb_status st;
    int i;
    if ((st = tb__reserve(w, (void **)&c->soft_bodies, &c->soft_body_cap, c->body_count + 1,
                          sizeof *c->soft_bodies)) != TB_OK)
        return st;
    load(w, c, n);
    if ((st = set_up_rows(w, c, h, n)) != TB_OK)
        return st;
    for (i = 0; i < n; ++i) {
        kick(c);
        warm_start(c);
        solve_rows(c, hs, &sf, 1);
        drift(c, hs);
        solve_rows(c, hs, &sf, 0);
    }
    restitution(c);
    store(w, c, n);
    c->kept_h = h;
    c->sweeps = 0;
    return TB_OK;
}

void tb__soft_free(tb_world *w, tb__contacts *c)
{
    tb__alloc(w, c->soft_rows, c->soft_row_cap * sizeof *c->soft_rows, 0);
    tb__alloc(w, c->soft_bodies, c->soft_body_cap * sizeof *c->soft_bodies, 0);
}
