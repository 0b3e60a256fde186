/* implicit.c: linearised backward Euler for particles (Baraff and Witkin
   1998), one Newton step of backward Euler solved by conjugate gradients:

       (M + h D + h^2 K) dv = h (f0 - h K v0),   v1 = v0 + dv,   x1 = x0 + h v1

   with f0 the forces at the start, K = -df/dx (springs; the geometric
   stiffness of compressed springs is clamped at 0 so K stays definite) and
   D = -df/dv (spring damping, drag). Forces from callbacks enter f0 but not
   the Jacobians: tumble cannot see inside them. Pinned particles keep their
   velocity: their rows are filtered out of the solve (Baraff and Witkin's
   modified CG). Bodies, which this method does not treat implicitly, are
   kicked and drifted like symplectic Euler with the second-order rotation.

   Stable at any step on springs, and dissipative: on a linear spring it is
   exactly backward Euler, which multiplies v^2 + w^2 x^2 by 1 / (1 + (h w)^2)
   each step (energy x0.535 per period at h w = 0.1). */
#include "stepping/stepping.h"
#include "joints/joints.h"
#include "bodies/bodies.h"
#include "forces/forces.h"
#include "particles/particles.h"

#include <math.h>
#include <string.h>

#define CG_TOLERANCE 1e-13 /* relative residual: far below any step's error */

typedef struct system {
    const tb_world *w;
    double h;
    const double *x, *v; /* the start of the step */
    double *scratch;     /* 3n, for the Jacobian products */
} system;

static int pinned(const tb_world *w, size_t i3)
{
    return w->particle_inv_mass[i3 / 3] == 0;
}

/* Drag's velocity Jacobian on u for particle i: c1 u + c2 (|v| u + (v.u) v / |v|). */
static void drag_product(const tb_world *w, const double *v, const double *u, double *out, size_t i)
{
    const double *vi = v + 3 * i, *ui = u + 3 * i;
    const double speed = sqrt(vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]);
    const double vu = speed > 0 ? (vi[0] * ui[0] + vi[1] * ui[1] + vi[2] * ui[2]) / speed : 0;
    int k;
    for (k = 0; k < 3; ++k)
        out[3 * i + k] += w->linear_drag * ui[k] +
                          w->quadratic_drag * (speed * ui[k] + (speed > 0 ? vu * vi[k] : 0));
}

/* out = A u with A = M + h D + h^2 K, pinned rows and columns filtered. */
static void apply(const system *s, const double *u, double *out)
{
    const tb_world *w = s->w;
    const size_t n = 3 * w->particle_count;
    size_t i;
    memset(s->scratch, 0, n * sizeof(double));
    tb__spring_damping_product(w, s->x, u, s->scratch);
    for (i = 0; i < w->particle_count; ++i)
        drag_product(w, s->v, u, s->scratch, i);
    for (i = 0; i < n; ++i)
        out[i] = w->particle_mass[i / 3] * u[i] + s->h * s->scratch[i];
    memset(s->scratch, 0, n * sizeof(double));
    tb__spring_stiffness_product(w, s->x, u, s->scratch, 1);
    for (i = 0; i < n; ++i)
        out[i] = pinned(w, i) ? 0 : out[i] + s->h * s->h * s->scratch[i];
}

/* The diagonal of A, for a Jacobi preconditioner. */
static void diagonal(const system *s, double *d)
{
    const tb_world *w = s->w;
    const double h = s->h;
    size_t i, k;
    for (i = 0; i < w->particle_count; ++i) {
        const double *vi = s->v + 3 * i;
        const double speed = sqrt(vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]);
        for (k = 0; k < 3; ++k)
            d[3 * i + k] = w->particle_mass[i] + h * (w->linear_drag +
                                             w->quadratic_drag * (speed + (speed > 0 ? vi[k] * vi[k] / speed : 0)));
    }
    for (i = 0; i < w->spring_count; ++i) {
        const uint32_t a = w->spring_a[i], b = w->spring_b[i];
        const double *xa = s->x + 3 * a;
        const double *xb = b == TB__ANCHOR ? w->spring_anchor + 3 * i : s->x + 3 * b;
        const double dd[3] = { xa[0] - xb[0], xa[1] - xb[1], xa[2] - xb[2] };
        const double len = sqrt(dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2]);
        const double geometric = len > 0 ? fmax(0, 1 - w->spring_rest[i] / len) : 0;
        if (len == 0)
            continue;
        for (k = 0; k < 3; ++k) {
            const double nk2 = dd[k] * dd[k] / (len * len);
            const double add = h * w->spring_c[i] * nk2 + h * h * w->spring_k[i] * (nk2 + geometric * (1 - nk2));
            d[3 * a + k] += add;
            if (b != TB__ANCHOR)
                d[3 * b + k] += add;
        }
    }
}

tb_status tb__implicit_particles(tb_world *w, double h)
{
    const size_t n = 3 * w->particle_count;
    double *x = w->y + w->off[TB__PARTICLE_POS], *v = w->y + w->off[TB__PARTICLE_VEL];
    double *b, *r, *z, *p, *q, *dv, *d, rz, bb, scale;
    system s;
    size_t i;
    /* CG ends within n iterations in exact arithmetic; rounding delays it
       on ill-conditioned systems (an 8 x 8 cloth at 30 to 100 times its
       explicit limit takes up to 211 for n = 192, which a cap of
       max(200, n) refused: test_truths.hanging_cloth_balances_every_node),
       so the cap leaves room: 2 n + 200. A step it does not fit fails. */
    const int max_it = (int)(2 * n + 200);
    int it;
    tb_status st = tb__state_scratch(w, 4);
    if (st != TB_OK)
        return st;
    /* eight vectors of 3n in four state-sized ones (each holds >= 6n) */
    b = tb__scratch_vector(w, 0), r = b + n;
    z = tb__scratch_vector(w, 1), p = z + n;
    q = tb__scratch_vector(w, 2), dv = q + n;
    d = tb__scratch_vector(w, 3), s.scratch = d + n;
    s.w = w, s.h = h, s.x = x, s.v = v;

    /* b = h (f0 - h K v0), f0 the global forces plus gravity and drag */
    memset(s.scratch, 0, n * sizeof(double));
    tb__spring_stiffness_product(w, x, v, s.scratch, 1);
    for (i = 0; i < w->particle_count; ++i) {
        const double *vi = v + 3 * i;
        const double speed = sqrt(vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]);
        const double drag = w->linear_drag + w->quadratic_drag * speed;
        int k;
        for (k = 0; k < 3; ++k) {
            const size_t j = 3 * i + k;
            const double f = (w->force_ready ? w->particle_force[j] : 0) + w->particle_mass[i] * w->gravity[k] - drag * vi[k];
            b[j] = pinned(w, j) ? 0 : h * (f - h * s.scratch[j]);
        }
    }
    diagonal(&s, d);

    /* The solve is linear in b: it runs on b / 2^e, 2^e near max|b_i|, and
       scales dv back, so that a state decayed to subnormal numbers
       (implicit Euler damps a spring by 1 / (1 + (h w)^2) a step) does not
       underflow the dot products to 0 / 0 (test_stability.damped_limits_
       match_simulation). Scaling by a power of 2 is exact: the same bits
       as an unscaled solve wherever that one worked. */
    scale = 0;
    for (i = 0; i < n; ++i)
        scale = fmax(scale, fabs(b[i]));
    if (scale > 0) {
        int e;
        (void)frexp(scale, &e);
        scale = ldexp(1, e);
        for (i = 0; i < n; ++i)
            b[i] /= scale;
    } else
        scale = 1;

    /* preconditioned conjugate gradients from dv = 0 */
    memset(dv, 0, n * sizeof(double));
    memcpy(r, b, n * sizeof(double));
    for (i = 0; i < n; ++i)
        z[i] = pinned(w, i) ? 0 : r[i] / d[i];
    memcpy(p, z, n * sizeof(double));
    rz = tb__dot(r, z, n);
    bb = tb__dot(b, b, n);
    for (it = 0; it < max_it && tb__dot(r, r, n) > CG_TOLERANCE * CG_TOLERANCE * bb; ++it) {
        double alpha, rz_next;
        apply(&s, p, q);
        alpha = rz / tb__dot(p, q, n);
        for (i = 0; i < n; ++i) {
            dv[i] += alpha * p[i];
            r[i] -= alpha * q[i];
        }
        for (i = 0; i < n; ++i)
            z[i] = pinned(w, i) ? 0 : r[i] / d[i];
        rz_next = tb__dot(r, z, n);
        for (i = 0; i < n; ++i)
            p[i] = z[i] + rz_next / rz * p[i];
        rz = rz_next;
    }
    if (!(tb__dot(r, r, n) <= CG_TOLERANCE * CG_TOLERANCE * bb) || !isfinite(rz))
        return tb__fail(w, TB_ERR_ARGUMENT,
                        "implicit_euler: conjugate gradients did not converge in %d iterations "
                        "(relative residual %.3g)", it, bb > 0 ? sqrt(tb__dot(r, r, n) / bb) : 0.0);
    for (i = 0; i < n; ++i) {
        v[i] += scale * dv[i];
        x[i] += h * v[i];
    }
    return TB_OK;
}

/* The whole step: particles implicitly, bodies by a kick and a drift;
   both held on their joints through it (tb__joints_hold, shake). */
tb_status tb__implicit_step(tb_world *w, double h)
{
    const tb__split_op kick_drift[2] = { { 0, h, TB__ROTATE_SPLIT2, 0 }, { 1, h, TB__ROTATE_SPLIT2, 0 } };
    tb_status st = tb__split_prepare(w, w->time, NULL);
    if (st == TB_OK && w->joint_count)
        st = tb__joints_hold(w, h);
    if (st == TB_OK && w->particle_count)
        st = tb__implicit_particles(w, h);
    if (st == TB_OK && w->body_count)
        tb__body_sweep(w, kick_drift, 2);
    if (st == TB_OK && w->joint_count)
        st = tb__joints_shake(w, h, TB__ROTATE_SPLIT2);
    return st;
}
