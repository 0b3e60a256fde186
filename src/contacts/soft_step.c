/* soft_step.c: the contact solver (docs/contacts.md, "The soft step").
   The step's contacts are
   those tb__contacts_prepare found at the start positions; the bodies
   and particles in them are moved again from the start of the step in
   n = settings.substeps substeps of h / n (an island too wide to solve
   together and with no deep overlap: apart, at WIDE_RATE times the
   substeps and stiffness, below), each of which
   1. adds half the substep's share of the step's external change of
      momentum (what the world's method gave the free motion: P and L for
      bodies, the velocity for particles);
   2. meets the substep's impacts (impacts, below): points with
      restitution whose gap closes in the substep, and the touching points
      their blows reach, bounced one after the other;
   3. warm starts: every row's impulse of the last substep (of last step,
      for the first) is applied again, but for points apart whose sides
      already part (drop_parting);
   4. solves every patch once (below), the touching points of an island
      narrow enough, and those closing their gaps, together and rigid
      (stack_solve.c, whose overlaps are pushed out around the drift),
      before the patches and again after them, last: the drift then
      moves by velocities the island's rows balance (friction met after
      them tips a sliding box forward, and it slides 1e-4 too far:
      soft_step_slides_to_v2_over_2_mu_g); the other normal rows soft (a
      spring-damper of `hertz` and `damping_ratio` on the overlap, pushing
      at most `max_push`), speculative where the points are still apart;
      a patch whose point closes its gap within the substep (an impact)
      has its normal rows solved together (solve_impact) and is solved
      TB__IMPACT_PASSES times;
   5. moves positions by the velocities the solve left (x by v, q by the
      torque-free turn of L: tb__rotation_split2), and a body an impact
      changed back to where the impact's time within the substep puts it;
      then every row and patch responds through the bodies' inertia at
      their new orientation (respond);
   6. relaxes: every patch once more, its touching points rigid and
      without the push, so that the push moves positions and leaves no
      speed; points still apart are left to the next substep's solve;
   7. adds the other half of the substep's external change.
   The kicks around the drift make it the leapfrog (kick, drift, kick),
   exact for a constant force: free flight, a slide under Coulomb friction
   (soft_step_slides_to_v2_over_2_mu_g), and the rows meet the velocity
   the positions move by. After the substeps one more rigid pass (settle)
   leaves a body at rest at rest, and points that struck faster than
   `restitution_threshold` without being met as impacts are bounced by
   their normal rows, toward e times the approach speed they struck at,
   and a body ending deep in a static shape no row held is taken back to
   its time of impact (continuous.c).
   A patch is one manifold: a normal row per point (impulse >= 0), then,
   at the centre of its points, friction (two rows within the circle mu
   times the points' normal impulses), twist (within mu times the sum of
   each point's impulse times its lever from the centre: none for one
   point, which has no lever, as rigid bodies touch at a point:
   capsule_stood_on_end_keeps_its_spin) and rolling resistance (about the
   tangents, within rho times the normal impulse).
   Every normal row's arms turn with the bodies (its Jacobian is that of
   the pose now: turn_arms), the patches' rows keep the arms of the start
   of the step, and all move the bodies through their inertia at their
   orientation now (taken again after each drift: respond); the
   separation is recomputed every substep from the bodies' displacements
   and their turns since the start, exactly. */
#include "contacts/soft_step.h"

#include <math.h>
#include <string.h>

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

/* The rotation from q0 to q: R(q) R(q0)^T */
static void rotation_since(const double q[4], const double q0[4], double out[9])
{
    const double q0c[4] = { q0[0], -q0[1], -q0[2], -q0[3] };
    double dq[4];
    tb__quat_mul(q, q0c, dq);
    tb__matrix_of(dq, out);
}

/* Solver body i (>= 0) receives an impulse lambda along unit d whose
   angular part is arm (r x d): its spin changes by lambda times spin, the
   start's inverse inertia times arm. Every row responds through the
   inertia of the start pose, as its mass was found; the drift then takes
   w from L at the new orientation. */
static void apply(tb__contacts *c, int32_t i, double lambda, const double d[3], const double arm[3],
                  const double spin[3])
{
    tb__soft_body *s = &c->soft_bodies[i];
    const double im = s->inv_mass * lambda;
    s->P[0] += lambda * d[0], s->P[1] += lambda * d[1], s->P[2] += lambda * d[2];
    s->v[0] += im * d[0], s->v[1] += im * d[1], s->v[2] += im * d[2];
    if (!s->rotates)
        return;
    s->L[0] += lambda * arm[0], s->L[1] += lambda * arm[1], s->L[2] += lambda * arm[2];
    s->w[0] += lambda * spin[0], s->w[1] += lambda * spin[1], s->w[2] += lambda * spin[2];
}

void tb__soft_pair(tb__contacts *c, int32_t a, int32_t b, double lambda, const double d[3], const double arm_a[3],
                   const double arm_b[3], const double spin_a[3], const double spin_b[3])
{
    if (b >= 0)
        apply(c, b, lambda, d, arm_b, spin_b);
    if (a >= 0)
        apply(c, a, -lambda, d, arm_a, spin_a);
}

double tb__soft_relative(const tb__contacts *c, int32_t a, int32_t b, const double d[3], const double arm_a[3],
                         const double arm_b[3])
{
    double r = 0;
    if (b >= 0) {
        const tb__soft_body *s = &c->soft_bodies[b];
        r += tb__dot3(d, s->v) + tb__dot3(arm_b, s->w);
    }
    if (a >= 0) {
        const tb__soft_body *s = &c->soft_bodies[a];
        r -= tb__dot3(d, s->v) + tb__dot3(arm_a, s->w);
    }
    return r;
}

double tb__soft_through(const tb__contacts *c, int32_t i, const double d1[3], const double arm1[3],
                        const double d2[3], const double spin2[3])
{
    const double k = c->bodies[i].inv_mass * tb__dot3(d1, d2);
    return c->bodies[i].tier == TB__BODIES ? k + tb__dot3(arm1, spin2) : k;
}

/* A scalar impulse along row o's normal, equal and opposite on its sides. */
void tb__soft_push(tb__contacts *c, const tb__soft_row *o, double lambda)
{
    tb__soft_pair(c, o->a, o->b, lambda, o->normal, o->arm_a, o->arm_b, o->spin_a, o->spin_b);
}

/* The relative velocity of b against a along row o's normal */
double tb__soft_rate(const tb__contacts *c, const tb__soft_row *o)
{
    return tb__soft_relative(c, o->a, o->b, o->normal, o->arm_a, o->arm_b);
}

/* ... and along the normal, the part of it the substep's external kick gave */
static double kick_rate(const tb__contacts *c, const tb__soft_row *o)
{
    double r = 0, dw[3];
    if (o->b >= 0) {
        const tb__soft_body *s = &c->soft_bodies[o->b];
        tb__mul(s->inv_world, s->kick_l, dw);
        r += c->bodies[o->b].inv_mass * tb__dot3(o->normal, s->kick_p) + tb__dot3(o->arm_b, dw);
    }
    if (o->a >= 0) {
        const tb__soft_body *s = &c->soft_bodies[o->a];
        tb__mul(s->inv_world, s->kick_l, dw);
        r -= c->bodies[o->a].inv_mass * tb__dot3(o->normal, s->kick_p) + tb__dot3(o->arm_a, dw);
    }
    return r;
}

/* The separation now, from the bodies' displacements and first-order
   turns at the start's arms: found again whenever positions move
   (separations), read between */
static double separation_from_motion(const tb__contacts *c, const tb__soft_row *o)
{
    double s = o->separation, d[3];
    if (o->b >= 0) {
        const tb__soft_body *b = &c->soft_bodies[o->b];
        tb__mul(b->delta, o->core_b, d);
        s += o->normal[0] * (b->shift[0] + d[0] - o->core_b[0]) + o->normal[1] * (b->shift[1] + d[1] - o->core_b[1]) +
             o->normal[2] * (b->shift[2] + d[2] - o->core_b[2]);
    }
    if (o->a >= 0) {
        const tb__soft_body *a = &c->soft_bodies[o->a];
        tb__mul(a->delta, o->core_a, d);
        s -= o->normal[0] * (a->shift[0] + d[0] - o->core_a[0]) + o->normal[1] * (a->shift[1] + d[1] - o->core_a[1]) +
             o->normal[2] * (a->shift[2] + d[2] - o->core_a[2]);
    }
    return s;
}

double tb__soft_separation(const tb__contacts *c, const tb__soft_row *o)
{
    (void)c;
    return o->now;
}

/* Every row's separation now, after the positions moved */
static void separations(tb__contacts *c)
{
    size_t i;
    for (i = 0; i < c->soft_row_count; ++i)
        c->soft_rows[i].now = separation_from_motion(c, &c->soft_rows[i]);
}

typedef tb__softness soft; /* (soft_step.h) */

tb__softness tb__soft_softness(double hertz, double zeta, double hs)
{
    const double f = tb__least(hertz, 0.25 / hs), omega = 2 * 3.14159265358979323846 * f;
    const double a1 = 2 * zeta + hs * omega, a2 = hs * omega * a1, a3 = 1 / (1 + a2);
    soft s;
    s.bias_rate = omega / a1;
    s.mass_scale = a2 * a3;
    s.impulse_scale = a3;
    return s;
}

/* An angular impulse lambda about axis d (N m s), equal and opposite on
   a patch's sides; spin_a and spin_b: the start's inverse inertia times
   d on each side. */
static void turn_patch(tb__contacts *c, const tb__soft_patch *p, const double d[3], const double spin_a[3],
                       const double spin_b[3], double lambda)
{
    if (p->b >= 0 && c->soft_bodies[p->b].rotates) {
        tb__soft_body *s = &c->soft_bodies[p->b];
        s->L[0] += lambda * d[0], s->L[1] += lambda * d[1], s->L[2] += lambda * d[2];
        s->w[0] += lambda * spin_b[0], s->w[1] += lambda * spin_b[1], s->w[2] += lambda * spin_b[2];
    }
    if (p->a >= 0 && c->soft_bodies[p->a].rotates) {
        tb__soft_body *s = &c->soft_bodies[p->a];
        s->L[0] -= lambda * d[0], s->L[1] -= lambda * d[1], s->L[2] -= lambda * d[2];
        s->w[0] -= lambda * spin_a[0], s->w[1] -= lambda * spin_a[1], s->w[2] -= lambda * spin_a[2];
    }
}

/* The relative spin of b against a about axis d */
static double spin(const tb__contacts *c, const tb__soft_patch *p, const double d[3])
{
    double r = 0;
    if (p->b >= 0)
        r += tb__dot3(d, c->soft_bodies[p->b].w);
    if (p->a >= 0)
        r -= tb__dot3(d, c->soft_bodies[p->a].w);
    return r;
}

/* A friction impulse (along the tangents) at the patch's centre */
static void push_centre(tb__contacts *c, const tb__soft_patch *p, double l1, double l2)
{
    int d;
    const double l[2] = { l1, l2 };
    for (d = 0; d < 2; ++d)
        if (l[d] != 0)
            tb__soft_pair(c, p->a, p->b, l[d], p->tangent[d], p->arm_a[d], p->arm_b[d], p->spin_a[d], p->spin_b[d]);
}

/* The relative velocity of b against a at the centre along tangent d */
static double slip(const tb__contacts *c, const tb__soft_patch *p, int d)
{
    return tb__soft_relative(c, p->a, p->b, p->tangent[d], p->arm_a[d], p->arm_b[d]);
}

/* A point's normal row; its accumulated impulse. With bias, soft: it
   pushes overlaps out; without (the relax), rigid and aiming at no
   approach. A point still apart (s > 0) lets its gap close within the
   substep, never more: positions move by the velocity the solve leaves. */
static double solve_normal(tb__contacts *c, tb__soft_row *o, double hs, const soft *sf, int bias, int *closing,
                           int stacked)
{
    const double max_push = c->settings.max_push;
    const double s = tb__soft_separation(c, o), vn = tb__soft_rate(c, o);
    double target, mass_scale = 1, impulse_scale = 0, lambda, total;
    *closing |= bias && s >= 0 && vn * hs < -s;
    if (s > 0 && bias) {
        target = s / hs;
    } else if (s > 0) {
        return o->impulse;
    } else if (bias) {
        target = tb__most(sf->bias_rate * s, -max_push);
        if (!stacked) {
            mass_scale = sf->mass_scale;
            impulse_scale = sf->impulse_scale;
        }
    } else {
        target = 0;
    }
    lambda = -o->mass * mass_scale * (vn + target) - impulse_scale * o->impulse;
    total = tb__most(o->impulse + lambda, 0);
    lambda = total - o->impulse;
    o->impulse = total;
    tb__soft_push(c, o, lambda);
    tb__soft_note(c, o, vn, s, hs);
    return total;
}

void tb__soft_note(tb__contacts *c, tb__soft_row *o, double vn, double s, double hs)
{
    if (o->impulse > 0 && !o->struck) {
        /* the speed it struck at: from the start of this substep (u,
           before its half kick, and s) under the kick's acceleration a,
           u^2 - 2 a s at the surface, within what the substep's
           velocities span */
        const double kick = kick_rate(c, o), u = vn - 0.5 * kick, a = kick / hs;
        double approach = vn;
        if (s > 0) {
            const double fastest = tb__least(u, u + kick);
            approach = tb__most(-sqrt(tb__most(u * u - 2 * a * s, 0)), fastest);
        }
        o->struck = 1;
        o->approach = tb__least(approach, 0);
    }
    o->most = tb__most(o->most, o->impulse);
}

/* A pair of rows that share a disc: the accumulated impulse (acc) less
   mass (2 x 2: xx, xy, yy) times the rates (r1, r2), cut back to the disc
   of radius limit, into out. */
static void disc_step(const double mass[3], const double acc[2], double r1, double r2, double limit, double out[2])
{
    double len;
    out[0] = acc[0] - (mass[0] * r1 + mass[1] * r2);
    out[1] = acc[1] - (mass[1] * r1 + mass[2] * r2);
    len = sqrt(out[0] * out[0] + out[1] * out[1]);
    if (len > limit) {
        const double f = limit > 0 ? limit / len : 0;
        out[0] *= f, out[1] *= f;
    }
}

/* The passes over an impact's rows (solve_patches) */
#define TB__IMPACT_PASSES 4
/* the compliance of an impact's rows solved together, relative to their
   own inverse mass: it shares the blow between points that are
   redundant (a face's four corners) */
#define TB__IMPACT_COMPLIANCE 1e-3

/* J M^-1 J^T between rows o and q of one patch (same bodies, same normal) */
static double row_coupling(const tb__contacts *c, const tb__soft_row *o, const tb__soft_row *q)
{
    double k = 0;
    if (o->b >= 0)
        k += tb__soft_through(c, o->b, o->normal, o->arm_b, q->normal, q->spin_b);
    if (o->a >= 0)
        k += tb__soft_through(c, o->a, o->normal, o->arm_a, q->normal, q->spin_a);
    return k;
}

/* x = A^-1 b for the rows of set (bits) of the n x n matrix a, by
   elimination without pivots (a is positive definite); 0 if a pivot is
   not positive */
static int solve_set(double a[TB__MANIFOLD_POINTS][TB__MANIFOLD_POINTS], const double b[], int n, unsigned set,
                     double x[])
{
    double m[TB__MANIFOLD_POINTS][TB__MANIFOLD_POINTS + 1];
    int idx[TB__MANIFOLD_POINTS], k = 0, i, j, r;
    for (i = 0; i < n; ++i)
        if (set >> i & 1u)
            idx[k++] = i;
    for (i = 0; i < k; ++i) {
        for (j = 0; j < k; ++j)
            m[i][j] = a[idx[i]][idx[j]];
        m[i][k] = b[idx[i]];
    }
    for (i = 0; i < k; ++i) {
        if (!(m[i][i] > 0))
            return 0;
        for (r = i + 1; r < k; ++r) {
            const double f = m[r][i] / m[i][i];
            for (j = i; j <= k; ++j)
                m[r][j] -= f * m[i][j];
        }
    }
    for (i = 0; i < n; ++i)
        x[i] = 0;
    for (i = k; i-- > 0;) {
        double sum = m[i][k];
        for (j = i + 1; j < k; ++j)
            sum -= m[i][j] * x[idx[j]];
        x[idx[i]] = sum / m[i][i];
    }
    return 1;
}

/* An impact's normal rows (patch p's points, one of which closes its gap
   within the substep) solved together, rigid: the impulses >= 0 with
   which every point approaches no faster than its gap closes (an overlap
   at the push's rate), pushing only where it then meets that speed
   (the complementary set, found among the subsets of the points). Solved
   one after another, a flat face's first corner takes the blow and tips
   the body, which lands rocking and slides away
   (dropped_boxes_lie_on_the_plane, woken_world_moves_again). 0 (and
   nothing done) if no set is consistent. */
static int solve_impact(tb__contacts *c, tb__soft_patch *p, double hs, const soft *sf)
{
    const int n = (int)p->count;
    double a[TB__MANIFOLD_POINTS][TB__MANIFOLD_POINTS], b[TB__MANIFOLD_POINTS], x[TB__MANIFOLD_POINTS];
    double vn[TB__MANIFOLD_POINTS], sep[TB__MANIFOLD_POINTS];
    unsigned set;
    int i, j;
    if (n > TB__MANIFOLD_POINTS)
        return 0;
    for (i = 0; i < n; ++i) {
        const tb__soft_row *o = &c->soft_rows[p->first + i];
        double target;
        sep[i] = tb__soft_separation(c, o), vn[i] = tb__soft_rate(c, o);
        if (p->stacked && sep[i] <= TB__TOUCHING * c->settings.slop)
            return 0; /* its touching points are its island's */
        target = sep[i] > 0 ? sep[i] / hs : tb__most(sf->bias_rate * sep[i], -c->settings.max_push);
        for (j = 0; j < n; ++j)
            a[i][j] = row_coupling(c, o, &c->soft_rows[p->first + j]);
        a[i][i] *= 1 + TB__IMPACT_COMPLIANCE;
        b[i] = -(vn[i] + target);
    }
    for (i = 0; i < n; ++i)
        for (j = 0; j < n; ++j)
            b[i] += a[i][j] * c->soft_rows[p->first + j].impulse;
    /* the largest sets first: most often every point pushes */
    for (set = (1u << n) - 1; set + 1 > 0; --set) {
        int ok = solve_set(a, b, n, set, x);
        for (i = 0; i < n && ok; ++i) {
            double w = -b[i];
            for (j = 0; j < n; ++j)
                w += a[i][j] * x[j];
            ok = (set >> i & 1u) ? x[i] >= 0 : w >= -1e-12 * (1 + fabs(b[i]));
        }
        if (!ok)
            continue;
        for (i = 0; i < n; ++i) {
            tb__soft_row *o = &c->soft_rows[p->first + i];
            const double lambda = x[i] - o->impulse;
            o->impulse = x[i];
            tb__soft_push(c, o, lambda);
            tb__soft_note(c, o, vn[i], sep[i], hs);
        }
        return 1;
    }
    return 0;
}

/* Patch p once: its points, then its twist, rolling resistance and
   friction. Whether a point still apart (or just touching) closes its gap
   within the substep: an impact, whose rows a single pass leaves
   coupled. */
static int solve_patch(tb__contacts *c, tb__soft_patch *p, double hs, const soft *sf, int bias, int normals_done)
{
    int closing = 0;
    const double *n = c->soft_rows[p->first].normal;
    double total = 0, twist_limit = 0, t[2];
    size_t k;
    for (k = 0; k < p->count; ++k) {
        tb__soft_row *o = &c->soft_rows[p->first + k];
        const int stacked = p->stacked && tb__soft_separation(c, o) <= TB__TOUCHING * c->settings.slop;
        const double f =
            (stacked || normals_done ? o->impulse : solve_normal(c, o, hs, sf, bias, &closing, p->stacked)) + o->bounce;
        total += f;
        twist_limit += o->lever * f;
    }
    if (p->friction > 0 || p->rolling > 0) {
        /* rolling resistance resists a spin about the normal as it does
           a roll, up to rho times the normal impulse
           (soft_step_spinning_ball_keeps_its_spin: to the closed form) */
        const double old = p->twist_impulse, most = p->friction * twist_limit + p->rolling * total;
        const double next = tb__least(tb__most(old - p->twist_mass * spin(c, p, n), -most), most);
        p->twist_impulse = next;
        turn_patch(c, p, n, p->turn_a[0], p->turn_b[0], next - old);
    }
    if (p->rolling > 0) {
        disc_step(p->rolling_mass, p->rolling_impulse, spin(c, p, p->tangent[0]), spin(c, p, p->tangent[1]),
                  p->rolling * total, t);
        turn_patch(c, p, p->tangent[0], p->turn_a[1], p->turn_b[1], t[0] - p->rolling_impulse[0]);
        turn_patch(c, p, p->tangent[1], p->turn_a[2], p->turn_b[2], t[1] - p->rolling_impulse[1]);
        p->rolling_impulse[0] = t[0], p->rolling_impulse[1] = t[1];
    }
    disc_step(p->tangent_mass, p->friction_impulse, slip(c, p, 0), slip(c, p, 1), p->friction * total, t);
    push_centre(c, p, t[0] - p->friction_impulse[0], t[1] - p->friction_impulse[1]);
    p->friction_impulse[0] = t[0], p->friction_impulse[1] = t[1];
    return closing;
}

/* Whether a point of patch p still apart closes its gap within the
   substep at the velocities now */
static int closes(const tb__contacts *c, const tb__soft_patch *p, double hs)
{
    size_t k;
    for (k = 0; k < p->count; ++k) {
        const tb__soft_row *o = &c->soft_rows[p->first + k];
        const double s = tb__soft_separation(c, o);
        if (s >= 0 && tb__soft_rate(c, o) * hs < -s)
            return 1;
    }
    return 0;
}

/* One pass over the patches. A patch with a point that closes its gap
   within the substep is an impact: its normal rows are solved together
   (solve_impact; its touching points are its island's where it is
   stacked, and then one after another), then its friction, twist and
   rolling resistance, TB__IMPACT_PASSES times: in one pass the rows met
   later (another point, the friction at the centre) spin the body and
   drive the points met first through the surface, at any speed a
   spinning body brings (soft_step_spinning_plate_stays_on_the_slab). A
   point found closing only within the pass has its patch passed over
   the same way, one row after another. */
static void solve_patches(tb__contacts *c, double hs, const soft *sf, int bias)
{
    size_t i;
    for (i = 0; i < c->soft_patch_count; ++i) {
        tb__soft_patch *p = &c->soft_patches[i];
        int pass;
        if (bias && closes(c, p, hs)) {
            for (pass = 0; pass < TB__IMPACT_PASSES; ++pass)
                solve_patch(c, p, hs, sf, bias, solve_impact(c, p, hs, sf));
            continue;
        }
        if (solve_patch(c, p, hs, sf, bias, 0))
            for (pass = 1; pass < TB__IMPACT_PASSES; ++pass)
                solve_patch(c, p, hs, sf, bias, 0);
    }
}

/* 1 / (J M^-1 J^T) of row o, from its spins (row_response) */
static double row_mass(const tb__contacts *c, const tb__soft_row *o)
{
    double k = 0;
    if (o->b >= 0)
        k += c->bodies[o->b].inv_mass + tb__dot3(o->arm_b, o->spin_b);
    if (o->a >= 0)
        k += c->bodies[o->a].inv_mass + tb__dot3(o->arm_a, o->spin_a);
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
        s->pass = 0;
        s->inv_mass = b->inv_mass;
        s->rotates = b->tier == TB__BODIES;
        memcpy(s->x, b->x0, sizeof s->x);
        memcpy(s->q, b->q0, sizeof s->q);
        memset(s->shift, 0, sizeof s->shift);
        memset(s->delta, 0, sizeof s->delta);
        s->delta[0] = s->delta[4] = s->delta[8] = 1;
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
/* The start's inverse world inertia of solver body i times v (0 for the
   static world and particles) */
static void start_spin(const tb__contacts *c, int32_t i, const double v[3], double out[3])
{
    if (i >= 0 && c->bodies[i].tier == TB__BODIES) {
        tb__mul(c->soft_bodies[i].inv_world, v, out);
    } else {
        out[0] = out[1] = out[2] = 0;
    }
}

static void patch_response(tb__contacts *c, tb__soft_patch *p);

/* A row's spins and mass, through the inertia of the start */
static void row_response(tb__contacts *c, tb__soft_row *o)
{
    start_spin(c, o->a, o->arm_a, o->spin_a);
    start_spin(c, o->b, o->arm_b, o->spin_b);
    o->mass = row_mass(c, o);
}

/* 2 x 2 symmetric inverse of (xx, xy, yy) */
static void invert2(const double k[3], double out[3])
{
    const double det = k[0] * k[2] - k[1] * k[1];
    if (det > 0 && isfinite(det)) {
        out[0] = k[2] / det, out[1] = -k[1] / det, out[2] = k[0] / det;
    } else {
        out[0] = out[1] = out[2] = 0;
    }
}

/* d1 . (the sides' inverse world inertia) axis d, from the patch's turns */
static double angular_inverse(const tb__soft_patch *p, const double d1[3], int d)
{
    double k = 0;
    if (p->b >= 0)
        k += tb__dot3(d1, p->turn_b[d]);
    if (p->a >= 0)
        k += tb__dot3(d1, p->turn_a[d]);
    return k;
}

/* A patch's centre, arms and masses, at the start pose */
static void set_up_patch(tb__contacts *c, tb__soft_patch *p)
{
    size_t r;
    int d, q;
    memset(p->ca, 0, sizeof p->ca);
    memset(p->cb, 0, sizeof p->cb);
    for (r = 0; r < p->count; ++r)
        for (q = 0; q < 3; ++q) {
            p->ca[q] += c->soft_rows[p->first + r].ra[q] / (double)p->count;
            p->cb[q] += c->soft_rows[p->first + r].rb[q] / (double)p->count;
        }
    for (r = 0; r < p->count; ++r) {
        tb__soft_row *o = &c->soft_rows[p->first + r];
        double dr[3];
        for (q = 0; q < 3; ++q) /* a static side's arms are 0 */
            dr[q] = p->a >= 0 ? o->ra[q] - p->ca[q] : o->rb[q] - p->cb[q];
        o->lever = sqrt(tb__dot3(dr, dr));
    }
    for (d = 0; d < 2; ++d) {
        tb__cross(p->ca, p->tangent[d], p->arm_a[d]);
        tb__cross(p->cb, p->tangent[d], p->arm_b[d]);
    }
    patch_response(c, p);
}

/* A patch's spins and masses, through the inertia of the start */
static void patch_response(tb__contacts *c, tb__soft_patch *p)
{
    double k[3], im = 0;
    int d, e;
    for (d = 0; d < 2; ++d) {
        start_spin(c, p->a, p->arm_a[d], p->spin_a[d]);
        start_spin(c, p->b, p->arm_b[d], p->spin_b[d]);
    }
    for (d = 0; d < 3; ++d) {
        const double *axis = d == 0 ? c->soft_rows[p->first].normal : p->tangent[d - 1];
        start_spin(c, p->a, axis, p->turn_a[d]);
        start_spin(c, p->b, axis, p->turn_b[d]);
    }
    if (p->a >= 0)
        im += c->bodies[p->a].inv_mass;
    if (p->b >= 0)
        im += c->bodies[p->b].inv_mass;
    for (d = 0; d < 2; ++d)
        for (e = d; e < 2; ++e) {
            double sum = d == e ? im : 0;
            if (p->b >= 0)
                sum += tb__dot3(p->arm_b[d], p->spin_b[e]);
            if (p->a >= 0)
                sum += tb__dot3(p->arm_a[d], p->spin_a[e]);
            k[d + e] = sum;
        }
    invert2(k, p->tangent_mass);
    {
        const double kt = angular_inverse(p, c->soft_rows[p->first].normal, 0);
        p->twist_mass = kt > 0 ? 1 / kt : 0;
    }
    k[0] = angular_inverse(p, p->tangent[0], 1);
    k[1] = angular_inverse(p, p->tangent[0], 2);
    k[2] = angular_inverse(p, p->tangent[1], 2);
    invert2(k, p->rolling_mass);
}

/* The rows of every point of the awake entries, in key order, and a patch
   per entry; warm started from the impulses kept last step (a step's
   total, cut into n substeps and scaled by h / h_last). */
static tb_status set_up_rows(tb_world *w, tb__contacts *c, double h, int n)
{
    /* a normal row's impulse carries a load, a force through the step:
       scaled by h / h_last. Friction, twist and rolling resistance in a
       body at rest mostly take back what the substep's other rows leave,
       impulses rather than forces: carried as last step's impulse a
       substep, unscaled (scaled, steps of 1/30 and 1/90 s in turn rocked
       a column of 10 over 5 cm in 10 s:
       soft_step_column_stands_under_changing_steps) */
    const double scale = c->kept_h > 0 ? h / c->kept_h / n : 0, carry = c->kept_h > 0 ? 1.0 / n : 0;
    size_t i, count = 0, patches = 0;
    tb_status st;
    for (i = 0; i < c->entry_count; ++i)
        if (!c->entries[i].asleep && c->entries[i].count > 0)
            count += (size_t)c->entries[i].count, ++patches;
    if ((st = tb__reserve(w, (void **)&c->soft_rows, &c->soft_row_cap, count + 1, sizeof *c->soft_rows)) != TB_OK ||
        (st = tb__reserve(w, (void **)&c->soft_patches, &c->soft_patch_cap, patches + 1, sizeof *c->soft_patches)) !=
            TB_OK)
        return st;
    c->soft_row_count = c->soft_patch_count = 0;
    for (i = 0; i < c->entry_count; ++i) {
        tb__entry *e = &c->entries[c->order[i].index];
        tb__soft_patch *pa;
        int k, d;
        if (e->asleep || e->count == 0)
            continue;
        pa = &c->soft_patches[c->soft_patch_count++];
        pa->entry = e;
        pa->a = e->body_a, pa->b = e->body_b;
        pa->first = c->soft_row_count;
        pa->count = (size_t)e->count;
        memcpy(pa->tangent, e->tangent, sizeof pa->tangent);
        pa->friction = e->friction;
        pa->rolling = e->rolling;
        pa->stacked = 0;
        for (d = 0; d < 2; ++d) {
            pa->friction_impulse[d] = carry * tb__dot3(e->friction_impulse, e->tangent[d]);
            pa->rolling_impulse[d] = carry * tb__dot3(e->rolling_impulse, e->tangent[d]);
        }
        pa->twist_impulse = carry * e->twist_impulse;
        memset(pa->settled, 0, sizeof pa->settled);
        memset(pa->settled_rolling, 0, sizeof pa->settled_rolling);
        pa->settled_twist = 0;
        for (k = 0; k < e->count; ++k) {
            tb__point *p = &e->point[k];
            tb__soft_row *o = &c->soft_rows[c->soft_row_count++];
            o->point = p;
            o->a = e->body_a, o->b = e->body_b;
            memcpy(o->normal, e->normal, sizeof o->normal);
            memcpy(o->ra, p->ra, sizeof o->ra);
            memcpy(o->rb, p->rb, sizeof o->rb);
            for (d = 0; d < 3; ++d) {
                /* the point is midway between the surfaces */
                o->core_a[d] = o->ra[d] - (0.5 * p->separation + e->core[0]) * o->normal[d];
                o->core_b[d] = o->rb[d] + (0.5 * p->separation + e->core[1]) * o->normal[d];
            }
            tb__cross(o->ra, o->normal, o->arm_a);
            tb__cross(o->rb, o->normal, o->arm_b);
            row_response(c, o);
            o->separation = p->separation;
            o->restitution = e->restitution;
            o->approach = 0;
            o->most = 0;
            o->struck = 0;
            o->impulse = scale * p->normal_impulse;
            o->settled = 0;
            o->bounce = 0;
            o->bounced = 0;
            p->speed = 0;
        }
        set_up_patch(c, pa);
    }
    return TB_OK;
}

/* A share of every row's and patch's accumulated impulse applied again
   (1: the warm start) */
static void push_share(tb__contacts *c, double share)
{
    size_t i;
    for (i = 0; i < c->soft_row_count; ++i) {
        const tb__soft_row *o = &c->soft_rows[i];
        if (o->impulse != 0)
            tb__soft_push(c, o, share * o->impulse);
    }
    for (i = 0; i < c->soft_patch_count; ++i) {
        const tb__soft_patch *p = &c->soft_patches[i];
        push_centre(c, p, share * p->friction_impulse[0], share * p->friction_impulse[1]);
        if (p->twist_impulse != 0)
            turn_patch(c, p, c->soft_rows[p->first].normal, p->turn_a[0], p->turn_b[0], share * p->twist_impulse);
        if (p->rolling_impulse[0] != 0 || p->rolling_impulse[1] != 0) {
            turn_patch(c, p, p->tangent[0], p->turn_a[1], p->turn_b[1], share * p->rolling_impulse[0]);
            turn_patch(c, p, p->tangent[1], p->turn_a[2], p->turn_b[2], share * p->rolling_impulse[1]);
        }
    }
}

/* Patch p's friction, twist and rolling resistance impulses times f */
static void scale_patch(tb__soft_patch *p, double f)
{
    p->friction_impulse[0] *= f, p->friction_impulse[1] *= f;
    p->twist_impulse *= f;
    p->rolling_impulse[0] *= f, p->rolling_impulse[1] *= f;
}

/* Before the warm start: a point apart (beyond the touching band) whose
   sides already part keeps no impulse, and a patch whose points all do
   keeps no friction, twist or rolling resistance: it can carry no force,
   and its last impulse given again is a blow: a 0.16 kg plate squeezed
   against a wall by an 18 kg ball, given its 63 N s again after the ball
   had gone, left at 392 m/s (test_contacts_stress's smallest failing
   scenes). */
static void drop_parting(tb__contacts *c)
{
    const double touch = TB__TOUCHING * c->settings.slop;
    size_t i, k;
    for (i = 0; i < c->soft_patch_count; ++i) {
        tb__soft_patch *p = &c->soft_patches[i];
        int parting = 1;
        for (k = 0; k < p->count; ++k) {
            tb__soft_row *o = &c->soft_rows[p->first + k];
            if (o->impulse != 0 && tb__soft_separation(c, o) > touch && tb__soft_rate(c, o) > 0)
                o->impulse = 0;
            parting &= o->impulse == 0;
        }
        if (parting)
            scale_patch(p, 0);
    }
}

/* Half the kick of a substep: 1/2n of the step's external change */
static void half_kick(tb__contacts *c)
{
    size_t i;
    for (i = 0; i < c->body_count; ++i) {
        tb__soft_body *s = &c->soft_bodies[i];
        if (s->pass != c->soft_pass)
            continue;
        const double im = c->bodies[i].inv_mass;
        double dw[3];
        int k;
        tb__mul(s->inv_world, s->kick_l, dw);
        for (k = 0; k < 3; ++k) {
            s->P[k] += 0.5 * s->kick_p[k], s->v[k] += 0.5 * im * s->kick_p[k];
            s->L[k] += 0.5 * s->kick_l[k], s->w[k] += 0.5 * dw[k];
        }
    }
}

void tb__soft_turned(tb__contacts *c, size_t i)
{
    const tb__solver_body *b = &c->bodies[i];
    tb__soft_body *s = &c->soft_bodies[i];
    tb__normalise(s->q);
    rotation_since(s->q, b->q0, s->delta);
    world_inverse(s->q, b->inv_inertia, s->inv_world);
    tb__mul(s->inv_world, s->L, s->w);
}

/* Positions over hs: x by the velocity, q by the torque-free turn of L
   (between the substep's half kicks). */
static void drift(tb__contacts *c, double hs)
{
    size_t i;
    for (i = 0; i < c->body_count; ++i) {
        const tb__solver_body *b = &c->bodies[i];
        tb__soft_body *s = &c->soft_bodies[i];
        int k;
        if (s->pass != c->soft_pass)
            continue;
        for (k = 0; k < 3; ++k) {
            s->x[k] += hs * s->v[k];
            s->shift[k] = s->x[k] - b->x0[k];
        }
        if (b->tier == TB__BODIES) {
            tb__rotation_split2(s->q, s->L, b->inv_inertia, hs);
            tb__soft_turned(c, i);
        }
    }
}

/* ---- impacts ---------------------------------------------------------- */

/* The impacts of a substep, before its solve: every point with restitution
   whose gap closes within the substep faster than the threshold, and every
   touching point the blow then reaches, bounced one after the other, each
   toward e times the speed it meets the other side at, in passes until
   none approaches faster than the threshold (TB__IMPACT_ROUNDS at most).
   A blow so passes along bodies already touching as a row of separate
   collisions (newtons_cradle). The impulse of each point is kept apart
   from the rows' (bounce): the soft rows never take it back, and friction
   meets the point with it. A struck point's bounce happens tau into the
   substep: the speed it strikes at is taken from the energy over its gap,
   and its target carries what the kicks around the drift add after it, so
   that with the positions moved back by the change of velocity times tau
   (impacts_moved) the substep ends exactly where and as fast as a bounce
   at tau would under a constant force (ball_bounces_near_e_squared). */
#define TB__IMPACT_ROUNDS 32

/* The first t >= 0 with s + u t + a t^2 / 2 = 0 (s > 0), in the form that
   does not subtract nearly equal numbers, and the speed it closes at then;
   a negative t: never. */
static double impact_time(double s, double u, double a, double *speed)
{
    const double disc = u * u - 2 * a * s, root = sqrt(tb__most(disc, 0));
    *speed = root;
    return disc >= 0 && root - u > 0 ? 2 * s / (root - u) : -1;
}

static int impacts(tb__contacts *c, double hs)
{
    /* with a threshold of 0, a point must still approach by more than
       rounding to be met again, or the passes would not end */
    const double threshold = tb__most(c->settings.restitution_threshold, 1e-9);
    size_t i;
    int round, any = 0, changed = 1;
    for (i = 0; i < c->body_count; ++i)
        c->soft_bodies[i].struck_at = -1;
    for (i = 0; i < c->soft_row_count; ++i) {
        tb__soft_row *o = &c->soft_rows[i];
        o->bounce = 0;
    }
    for (round = 0; round < TB__IMPACT_ROUNDS && changed; ++round) {
        changed = 0;
        for (i = 0; i < c->soft_row_count; ++i) {
            tb__soft_row *o = &c->soft_rows[i];
            double s, vn, target, tau = -1, lambda, speed = 0;
            int k;
            if (o->restitution == 0 || (vn = tb__soft_rate(c, o)) > -threshold)
                continue;
            s = tb__soft_separation(c, o);
            if (s > 0) {
                /* a gap closing in the substep: when, and how fast */
                const double kick = kick_rate(c, o), u = vn - 0.5 * kick, a = kick / hs;
                tau = impact_time(s, u, a, &speed);
                /* a gap that closes at the substep's end, to rounding, is
                   this substep's: the next would find it touching, and
                   its row would meet the bodies it touches as one
                   (newtons_cradle) */
                if (tau < 0 || tau > hs * (1 + 1e-9) || speed < threshold)
                    continue;
                target = o->restitution * speed + a * (0.5 * hs - tau);
            } else {
                /* touching: met by a blow this substep (a body of it struck) */
                const double ta = o->a >= 0 ? c->soft_bodies[o->a].struck_at : -1;
                const double tb = o->b >= 0 ? c->soft_bodies[o->b].struck_at : -1;
                if (ta < 0 && tb < 0)
                    continue;
                tau = tb__most(ta, tb);
                target = -o->restitution * vn;
                speed = -vn;
            }
            lambda = o->mass * (target - vn);
            if (!(lambda > 0))
                continue;
            for (k = 0; k < 2; ++k) {
                const int32_t b = k ? o->b : o->a;
                tb__soft_body *sb;
                if (b < 0)
                    continue;
                sb = &c->soft_bodies[b];
                if (sb->struck_at < 0) {
                    memcpy(sb->v_struck, sb->v, sizeof sb->v_struck);
                    sb->struck_at = tau;
                }
            }
            tb__soft_push(c, o, lambda);
            o->bounce += lambda;
            if (!o->struck) {
                /* the speed it struck at, for its event */
                o->struck = 1;
                o->approach = -speed;
            }
            o->bounced = 1;
            changed = any = 1;
        }
    }
    return any;
}

/* After the drift: each body an impact changed moved back by its change
   of velocity times the time into the substep the impact came at. Not
   turned back by its change of spin so: a turn changes the energy of a
   body whose inertia is far from round (w is taken from L at the new
   orientation), and a thin bar spun up by a corner's blow gained 2777 J
   in one substep by it (heaps_built_overlapping). The drift
   turns it by the spin after the blow over the whole substep, which keeps
   its energy. */
static void impacts_moved(tb__contacts *c)
{
    size_t i;
    for (i = 0; i < c->body_count; ++i) {
        const tb__solver_body *b = &c->bodies[i];
        tb__soft_body *s = &c->soft_bodies[i];
        int k;
        if (s->pass != c->soft_pass)
            continue;
        if (s->struck_at <= 0)
            continue;
        for (k = 0; k < 3; ++k) {
            s->x[k] -= (s->v[k] - s->v_struck[k]) * s->struck_at;
            s->shift[k] = s->x[k] - b->x0[k];
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
        if (o->restitution == 0 || o->bounced || !o->struck || o->approach > -threshold || o->most == 0)
            continue;
        lambda = -o->mass * (tb__soft_rate(c, o) + o->restitution * o->approach);
        total = tb__most(o->impulse + lambda, 0);
        tb__soft_push(c, o, total - o->impulse);
        o->impulse = total;
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
        if (s->pass != c->soft_pass)
            continue;
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
        if (b->tier == TB__BODIES)
            first_turn(s->q, b->q0, b->turn);
        else
            memset(b->turn, 0, sizeof b->turn);
    }
    /* the impulses of the step, for the next one's warm start (+ 0.0: a
       zero kept as +0, whichever sign the clamps (tb__most) gave it, which a
       compiler may choose either way: the state hash reads the bits,
       test_snapshot.contact_scene_hash_is_recorded); a point touches if
       its normal row pushed in some substep */
    for (i = 0; i < c->soft_row_count; ++i) {
        tb__soft_row *o = &c->soft_rows[i];
        tb__point *p = o->point;
        p->normal_impulse = o->step_impulse = n * tb__most(o->impulse - o->settled, 0) + 0.0;
        p->active = o->most > 0 || o->bounced; /* a bounce alone touched too */
        p->speed = o->struck && o->approach < 0 && p->active ? -o->approach : 0;
    }
    for (i = 0; i < c->soft_patch_count; ++i) {
        const tb__soft_patch *pa = &c->soft_patches[i];
        tb__entry *e = pa->entry;
        int k;
        for (k = 0; k < 3; ++k) {
            e->friction_impulse[k] = n * ((pa->friction_impulse[0] - pa->settled[0]) * pa->tangent[0][k] +
                                          (pa->friction_impulse[1] - pa->settled[1]) * pa->tangent[1][k]) +
                                     0.0;
            e->rolling_impulse[k] = n * ((pa->rolling_impulse[0] - pa->settled_rolling[0]) * pa->tangent[0][k] +
                                         (pa->rolling_impulse[1] - pa->settled_rolling[1]) * pa->tangent[1][k]) +
                                    0.0;
        }
        e->twist_impulse = n * (pa->twist_impulse - pa->settled_twist) + 0.0;
    }
}

/* A last rigid pass after the step's final half kick: a body at rest
   ends the step at rest. The next step's first substep starts without
   that impulse (its half kick meets a body at rest), so its warm start
   leaves it out: what each row adds here is kept apart (settled) and
   taken off what store keeps. */
static void settle(tb__contacts *c, double hs, const soft *sf)
{
    size_t i;
    for (i = 0; i < c->soft_row_count; ++i)
        c->soft_rows[i].settled = c->soft_rows[i].impulse;
    for (i = 0; i < c->soft_patch_count; ++i) {
        tb__soft_patch *p = &c->soft_patches[i];
        memcpy(p->settled, p->friction_impulse, sizeof p->settled);
        p->settled_twist = p->twist_impulse;
        memcpy(p->settled_rolling, p->rolling_impulse, sizeof p->settled_rolling);
    }
    /* half the last substep's impulses first: what holds a body at rest
       against the final half kick, so that one pass leaves a body in a
       wide island at rest, not falling at g hs / 2
       (soft_step_slides_to_v2_over_2_mu_g: 2.1e-6 of the closed form) */
    push_share(c, 0.5);
    for (i = 0; i < c->soft_row_count; ++i)
        c->soft_rows[i].impulse *= 1.5;
    for (i = 0; i < c->soft_patch_count; ++i)
        scale_patch(&c->soft_patches[i], 1.5);
    tb__stacks_solve(c, hs, 0);
    solve_patches(c, hs, sf, 0);
    for (i = 0; i < c->soft_row_count; ++i)
        c->soft_rows[i].settled = c->soft_rows[i].impulse - c->soft_rows[i].settled;
    for (i = 0; i < c->soft_patch_count; ++i) {
        tb__soft_patch *p = &c->soft_patches[i];
        int d;
        for (d = 0; d < 2; ++d) {
            p->settled[d] = p->friction_impulse[d] - p->settled[d];
            p->settled_rolling[d] = p->rolling_impulse[d] - p->settled_rolling[d];
        }
        p->settled_twist = p->twist_impulse - p->settled_twist;
    }
}

/* After the drift, every row and patch responds through the bodies'
   inertia at their new orientation: a thin body's inverse inertia turns
   with it (a bar's about its axis is thousands of times its others), and
   a row pushing through the old one would change w by what L's change
   does not give, which the next drift, taking w from L, turns into energy
   (smallest_failing_scenes_pass' bar). */
/* After a substep: a patch whose points bounced keeps, as the next
   substep's warm start, only the share of its friction, twist and
   rolling resistance that its rows' pushes back (the bounce's share is a
   blow, not a force that lasts): warm started whole, a rod's rim
   friction from a bounce would spin it up again in every substep
   (smallest_failing_scenes_pass' rod). */
static void unbounce(tb__contacts *c)
{
    size_t i, k;
    for (i = 0; i < c->soft_patch_count; ++i) {
        tb__soft_patch *p = &c->soft_patches[i];
        double pushed = 0, bounced = 0;
        for (k = 0; k < p->count; ++k) {
            pushed += c->soft_rows[p->first + k].impulse;
            bounced += c->soft_rows[p->first + k].bounce;
        }
        if (!(bounced > 0))
            continue;
        scale_patch(p, pushed / (pushed + bounced));
    }
}

/* Row o's arms at the bodies' turns now: the point's core on each side,
   turned with its body, across the normal, so that the row's rate is the
   rate its separation (separation_from_motion) changes at. With the
   start's arms a thin bar spun at 725 rad/s about its axis by a corner's
   blow saw that corner rise at 29 m/s while it fell 9 cm into the plane
   in a substep (heaps_built_overlapping). */
static void turn_arms(const tb__contacts *c, tb__soft_row *o)
{
    double d[3];
    if (o->b >= 0) {
        tb__mul(c->soft_bodies[o->b].delta, o->core_b, d);
        tb__cross(d, o->normal, o->arm_b);
    }
    if (o->a >= 0) {
        tb__mul(c->soft_bodies[o->a].delta, o->core_a, d);
        tb__cross(d, o->normal, o->arm_a);
    }
}

static void respond(tb__contacts *c)
{
    size_t i;
    for (i = 0; i < c->body_count; ++i) {
        tb__soft_body *s = &c->soft_bodies[i];
        if (s->pass == c->soft_pass)
            tb__mul(s->inv_world, s->L, s->w); /* the push taken back through the old inertia */
    }
    for (i = 0; i < c->soft_row_count; ++i) {
        turn_arms(c, &c->soft_rows[i]);
        row_response(c, &c->soft_rows[i]);
    }
    for (i = 0; i < c->soft_patch_count; ++i)
        patch_response(c, &c->soft_patches[i]);
    tb__stacks_assemble(c);
}

/* The root of solver body i's group (path halving) */
static int32_t group_of(tb__soft_body *b, int32_t i)
{
    while (b[i].group != i) {
        b[i].group = b[b[i].group].group;
        i = b[i].group;
    }
    return i;
}

/* Islands too wide to solve together (the step's patches that no island
   solve holds: tb__stacks_set_up) set apart: the rows and patches
   reordered, those of the other islands first, in their order
   (*narrow_rows, *narrow_patches of them), and the bodies of the wide
   islands marked for the second pass. Whether there are any. An island
   is whole on one side: all its patches are stacked, or none. */
static tb_status wide_islands_apart(tb_world *w, tb__contacts *c, size_t *narrow_rows, size_t *narrow_patches,
                                    int *any)
{
    size_t i, k, rows = 0, patches = 0;
    int side;
    tb_status st;
    tb__soft_row *swap_rows;
    tb__soft_patch *swap_patches;
    size_t cap;
    *any = 0;
    /* the wide islands without a deep overlap, a particle or a joint:
       pass marks a particle, a jointed body and a body with a point
       deeper than the slop, group joins an island's bodies */
    for (i = 0; i < c->body_count; ++i) {
        c->soft_bodies[i].group = (int32_t)i;
        c->soft_bodies[i].pass = c->bodies[i].tier != TB__BODIES || c->soft_bodies[i].jointed;
    }
    for (i = 0; i < c->soft_patch_count; ++i) {
        const tb__soft_patch *p = &c->soft_patches[i];
        int deep = 0;
        for (k = 0; k < p->count; ++k)
            deep |= c->soft_rows[p->first + k].separation < -c->settings.slop;
        if (deep && p->a >= 0)
            c->soft_bodies[p->a].pass = 1;
        if (deep && p->b >= 0)
            c->soft_bodies[p->b].pass = 1;
        if (!p->stacked && p->a >= 0 && p->b >= 0)
            c->soft_bodies[group_of(c->soft_bodies, p->a)].group = group_of(c->soft_bodies, p->b);
    }
    for (i = 0; i < c->body_count; ++i)
        if (c->soft_bodies[i].pass)
            c->soft_bodies[group_of(c->soft_bodies, (int32_t)i)].pass = 1;
    for (i = 0; i < c->soft_patch_count; ++i) {
        tb__soft_patch *p = &c->soft_patches[i];
        const int32_t body = p->a >= 0 ? p->a : p->b;
        p->wide = !p->stacked && body >= 0 && !c->soft_bodies[group_of(c->soft_bodies, body)].pass;
        *any |= p->wide;
    }
    for (i = 0; i < c->body_count; ++i)
        c->soft_bodies[i].pass = 0;
    if (!*any)
        return TB_OK;
    if ((st = tb__reserve(w, (void **)&c->wide_rows, &c->wide_row_cap, c->soft_row_count + 1, sizeof *c->wide_rows)) !=
            TB_OK ||
        (st = tb__reserve(w, (void **)&c->wide_patches, &c->wide_patch_cap, c->soft_patch_count + 1,
                          sizeof *c->wide_patches)) != TB_OK)
        return st;
    for (side = 0; side < 2; ++side) {
        if (side == 1)
            *narrow_rows = rows, *narrow_patches = patches;
        for (i = 0; i < c->soft_patch_count; ++i) {
            const tb__soft_patch *p = &c->soft_patches[i];
            tb__soft_patch *q;
            if (p->wide != side)
                continue;
            q = &c->wide_patches[patches++];
            *q = *p;
            q->first = rows;
            for (k = 0; k < p->count; ++k)
                c->wide_rows[rows++] = c->soft_rows[p->first + k];
            if (side == 1) {
                if (p->a >= 0)
                    c->soft_bodies[p->a].pass = 1;
                if (p->b >= 0)
                    c->soft_bodies[p->b].pass = 1;
            }
        }
    }
    swap_rows = c->soft_rows, c->soft_rows = c->wide_rows, c->wide_rows = swap_rows;
    cap = c->soft_row_cap, c->soft_row_cap = c->wide_row_cap, c->wide_row_cap = cap;
    swap_patches = c->soft_patches, c->soft_patches = c->wide_patches, c->wide_patches = swap_patches;
    cap = c->soft_patch_cap, c->soft_patch_cap = c->wide_patch_cap, c->wide_patch_cap = cap;
    return TB_OK;
}

/* The substeps of the rows and patches in c->soft_rows and soft_patches
   now, moving the bodies of pass c->soft_pass: n substeps of h / n with
   rows of stiffness `hertz`, then the last rigid pass, restitution, the
   time of impact, and the step's end stored. set_up: the islands to
   solve together are to be found (else they are the rows'). */
static tb_status substeps(tb_world *w, tb__contacts *c, double h, int n, double hertz, int set_up)
{
    const double hs = h / n;
    const soft sf = tb__soft_softness(hertz, c->settings.damping_ratio, hs);
    const double joint_rate = tb__soft_joints_rate(hertz, hs);
    tb_status st;
    int i, struck;
    if (set_up && (st = tb__stacks_set_up(w, c)) != TB_OK)
        return st;
    for (i = 0; i < n; ++i) {
        half_kick(c);
        /* impacts before the warm start: an impact is an approach the
           free motion brings; a push the last substep's impulses give
           again is met by the solve (bounced, it made a dense heap's
           energy grow tenfold in three steps:
           test_contacts_heaps.dense_heaps_never_gain_energy under the
           soft step) */
        struck = impacts(c, hs);
        drop_parting(c);
        push_share(c, 1);
        tb__soft_joints_warm(c, 1);
        tb__soft_joints_solve(c, hs);
        tb__stacks_solve(c, hs, 1);
        solve_patches(c, hs, &sf, 1);
        tb__stacks_solve(c, hs, 1);
        tb__stacks_push(c, sf.bias_rate, 1);
        tb__soft_joints_push(c, joint_rate, 1);
        drift(c, hs);
        tb__soft_joints_push(c, joint_rate, -1);
        tb__stacks_push(c, sf.bias_rate, -1);
        if (struck)
            impacts_moved(c);
        separations(c);
        tb__soft_joints_now(w, c);
        respond(c);
        /* the relax: the joints again after the contacts, so that the
           drift moves jointed bodies by velocities their joints allow
           (met only before the contacts, a light limb's velocity was the
           contacts', and a ragdoll at rest crept at 2 cm/s and never
           slept) */
        tb__soft_joints_solve(c, hs);
        tb__stacks_solve(c, hs, 0);
        solve_patches(c, hs, &sf, 0);
        tb__soft_joints_solve(c, hs);
        if (struck)
            unbounce(c);
        half_kick(c);
        tb__soft_joints_count(c, 0);
    }
    tb__soft_joints_settle(c, 1); /* (the last rigid pass, around the contacts') */
    tb__soft_joints_solve(c, hs);
    settle(c, hs, &sf);
    tb__soft_joints_solve(c, hs);
    tb__soft_joints_settle(c, 0);
    tb__soft_joints_count(c, 1);
    restitution(c);
    tb__soft_continuous(w, c);
    store(w, c, n);
    if (c->soft_pass == 0) /* (the joints' islands are stepped at the step's rate) */
        tb__soft_joints_store(w, c, h, hs);
    return TB_OK;
}

/* An island too wide to solve together keeps soft rows, which hold a load
   at an overlap of the load over m_eff omega^2 and resist a tilt by a
   stiffness that does not grow with the load above them: a pyramid of 20
   levels sank 2.7 cm and a wall of 15 courses buckled and fell in 4 s.
   omega is capped at a quarter of the substep rate, so such an island is
   stepped apart with WIDE_RATE times the substeps at WIDE_RATE times the
   stiffness (the same share of its cap): rows four times stiffer, a
   quarter of the sink (the pyramid 7.2 mm, test_contacts_stacks.
   pyramid_stands_and_sleeps), the wall standing (9.2 mm down after 20 s,
   test_contacts_stacks.tall_wall_stands), at 1.4 to 1.8 times their cost.
   Not an island with a point deeper than the slop: stiffer rows push
   deep overlaps apart harder where they conflict, and crowds built
   overlapping threw bodies faster than free fall in 12 of 30 crowds
   instead of 3 (test_contacts_heaps.crowds_built_overlapping_stay_calm,
   over 30 seeds). Islands solved together are rigid and need no more. */
#define WIDE_RATE 2

tb_status tb__soft_step(tb_world *w, tb__contacts *c, double h)
{
    const int n = c->settings.substeps;
    size_t narrow_rows = 0, narrow_patches = 0, rows, patches, i;
    tb_status st;
    int wide;
    if ((st = tb__reserve(w, (void **)&c->soft_bodies, &c->soft_body_cap, c->body_count + 1,
                          sizeof *c->soft_bodies)) != TB_OK)
        return st;
    load(w, c, n);
    if ((st = tb__soft_joints_load(w, c, h / n)) != TB_OK)
        return st;
    if ((st = set_up_rows(w, c, h, n)) != TB_OK)
        return st;
    separations(c);
    if ((st = tb__stacks_set_up(w, c)) != TB_OK || (st = wide_islands_apart(w, c, &narrow_rows, &narrow_patches,
                                                                             &wide)) != TB_OK)
        return st;
    c->soft_pass = 0;
    if (!wide) {
        st = substeps(w, c, h, n, c->settings.hertz, 0);
        c->kept_h = h;
        return st;
    }
    rows = c->soft_row_count, patches = c->soft_patch_count;
    c->soft_row_count = narrow_rows, c->soft_patch_count = narrow_patches;
    if ((st = substeps(w, c, h, n, c->settings.hertz, 1)) != TB_OK)
        return st;
    /* the wide islands: their rows and patches alone, their warm starts
       and kicks cut into WIDE_RATE times the substeps */
    c->soft_pass = 1;
    c->soft_rows += narrow_rows, c->soft_row_count = rows - narrow_rows;
    c->soft_patches += narrow_patches, c->soft_patch_count = patches - narrow_patches;
    for (i = 0; i < c->soft_row_count; ++i)
        c->soft_rows[i].impulse /= WIDE_RATE;
    for (i = 0; i < c->soft_patch_count; ++i) {
        c->soft_patches[i].first -= narrow_rows;
        scale_patch(&c->soft_patches[i], 1.0 / WIDE_RATE);
    }
    for (i = 0; i < c->body_count; ++i)
        if (c->soft_bodies[i].pass == 1) {
            int k;
            for (k = 0; k < 3; ++k)
                c->soft_bodies[i].kick_p[k] /= WIDE_RATE, c->soft_bodies[i].kick_l[k] /= WIDE_RATE;
        }
    st = substeps(w, c, h, WIDE_RATE * n, WIDE_RATE * c->settings.hertz, 1);
    for (i = 0; i < c->soft_patch_count; ++i)
        c->soft_patches[i].first += narrow_rows;
    c->soft_rows -= narrow_rows, c->soft_row_count = rows;
    c->soft_patches -= narrow_patches, c->soft_patch_count = patches;
    c->soft_pass = 0;
    c->kept_h = h;
    return st;
}

void tb__soft_free(tb_world *w, tb__contacts *c)
{
    tb__stacks_free(w, c);
    tb__alloc(w, c->soft_joints, c->soft_joint_cap * sizeof *c->soft_joints, 0);
    tb__alloc(w, c->joint_groups, c->joint_group_cap * sizeof *c->joint_groups, 0);
    tb__alloc(w, c->joint_rows, c->joint_row_cap * sizeof *c->joint_rows, 0);
    tb__alloc(w, c->wide_patches, c->wide_patch_cap * sizeof *c->wide_patches, 0);
    tb__alloc(w, c->wide_rows, c->wide_row_cap * sizeof *c->wide_rows, 0);
    tb__alloc(w, c->soft_patches, c->soft_patch_cap * sizeof *c->soft_patches, 0);
    tb__alloc(w, c->soft_rows, c->soft_row_cap * sizeof *c->soft_rows, 0);
    tb__alloc(w, c->soft_bodies, c->soft_body_cap * sizeof *c->soft_bodies, 0);
}
