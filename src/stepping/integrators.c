/* integrators.c: the stepping methods, each a short function over the
   state-vector primitives (derive, axpy) or the split primitives (prepare
   forces, sweep kicks and drifts). Adding a method touches this file only. */
#include "stepping/stepping.h"
#include "bodies/bodies.h"
#include "forces/forces.h"
#include "particles/particles.h"

#include <math.h>
#include <string.h>

/* y += h F(t, y). Writes y only after its one evaluation. */
static tb_status euler(tb_world *w, double h)
{
    tb_status st = tb__state_scratch(w, 1);
    double *dy;
    if (st != TB_OK)
        return st;
    dy = tb__scratch_vector(w, 0);
    if ((st = tb__derive(w, w->time, w->y, dy)) != TB_OK)
        return st;
    tb__state_axpy(w, w->y, w->y, h, dy);
    tb__project(w, w->y);
    return TB_OK;
}

/* Classic RK4 with three scratch vectors: a stage state, a stage slope and
   the running sum k1 + 2 k2 + 2 k3 + k4. Writes y only at the end, then
   projects it (unit quaternions). Stage states are not projected: the
   quaternion equation q' = (0, w) q / 2, with w computed from q / |q|, keeps
   |q| by itself, and projecting stages perturbs them by O(h^2), which costs
   RK4 its order. When nothing couples objects, the world steps them one
   block at a time through all four stages (tb__fused_rk4), with these very
   operations: the same bits (test_rotation.fast_paths_give_the_general_bits),
   without the passes over the whole state. */
static tb_status rk4(tb_world *w, double h)
{
    const double t = w->time;
    double *stage, *k, *sum;
    tb_status st;
    if (tb__fused_rk4(w, h))
        return TB_OK;
    if ((st = tb__state_scratch(w, 3)) != TB_OK)
        return st;
    stage = tb__scratch_vector(w, 0);
    k = tb__scratch_vector(w, 1);
    sum = tb__scratch_vector(w, 2);
    if ((st = tb__derive(w, t, w->y, sum)) != TB_OK)
        return st;
    tb__state_axpy(w, stage, w->y, h / 2, sum);
    if ((st = tb__derive(w, t + h / 2, stage, k)) != TB_OK)
        return st;
    tb__state_axpy(w, sum, sum, 2, k);
    tb__state_axpy(w, stage, w->y, h / 2, k);
    if ((st = tb__derive(w, t + h / 2, stage, k)) != TB_OK)
        return st;
    tb__state_axpy(w, sum, sum, 2, k);
    tb__state_axpy(w, stage, w->y, h, k);
    if ((st = tb__derive(w, t + h, stage, k)) != TB_OK)
        return st;
    tb__state_axpy(w, sum, sum, 1, k);
    tb__state_axpy(w, w->y, w->y, h / 6, sum);
    tb__project(w, w->y);
    return TB_OK;
}

/* Kick with the forces at the start, then drift with the new velocity.
   Anisotropic bodies turn with w frozen at the start of the drift (first
   order), as in ODE. */
static tb_status symplectic_euler(tb_world *w, double h)
{
    const tb__split_op kick_drift[2] = { { 0, h, TB__ROTATE_FROZEN, 0 }, { 1, h, TB__ROTATE_FROZEN, 0 } };
    tb_status st = tb__split_prepare(w, w->time, NULL);
    if (st != TB_OK)
        return st;
    return tb__split_sweep(w, kick_drift, 2);
}

/* Kick h/2, drift h, evaluate the forces again, kick h/2. The second
   evaluation comes after the state moved: tb_world_step snapshots it when a
   callback could fail there.
   Velocity-dependent forces (drag, damping, callbacks) are evaluated for the
   closing kick at the predicted end velocity v_n + h a_n = 2 v_half - v_n,
   not at v_half: that keeps the method second order with damping (on
   v' = -k v it multiplies by 1 - kh + (kh)^2 / 2 per step) at no extra
   evaluation. Position-only forces never see the difference.
   `rotation` is how the drift turns anisotropic bodies through their free
   motion: "verlet" uses the symmetric axis splitting (second order, keeps
   the energy error bounded), "verlet_exact" the accurate kernel. */
static tb_status verlet_with(tb_world *w, double h, tb__rotation_kind rotation)
{
    const tb__split_op kick_drift[2] = { { 0, h / 2, rotation, 0 }, { 1, h, rotation, 0 } };
    const tb__split_op kick[1] = { { 0, h / 2, rotation, 0 } };
    double *predicted = NULL;
    tb_status st;
    if (w->forces.count == 0 && w->spring_count == 0 && w->joint_count == 0 && !tb__body_velocity_dependent(w)) {
        /* Only local forces: gravity, drag on particles, held forces on
           bodies. Each object's closing kick depends on that object alone,
           so one sweep does the three ops on each particle, or block of
           bodies, while it sits in registers or L1; a particle's closing
           kick sees its predicted velocity 2 v_half - v_n computed there,
           without the copy of the state. The same operations, the same
           bits (test_particle_step.split_steps_give_the_general_bits),
           in one pass over the arrays instead of three. */
        const tb__split_op kick_drift_kick[3] = { { 0, h / 2, rotation, 0 }, { 1, h, rotation, 0 },
                                                  { 0, h / 2, rotation, 1 } };
        if ((st = tb__split_prepare(w, w->time, NULL)) != TB_OK)
            return st;
        return tb__split_sweep(w, kick_drift_kick, 3);
    }
    if (tb__split_velocity_dependent(w)) {
        if ((st = tb__state_scratch(w, 1)) != TB_OK)
            return st;
        predicted = tb__scratch_vector(w, 0);
        tb__state_copy(w, predicted, w->y);
    }
    if ((st = tb__split_prepare(w, w->time, NULL)) != TB_OK || (st = tb__split_sweep(w, kick_drift, 2)) != TB_OK)
        return st;
    if (predicted)
        tb__split_extrapolate(w, predicted);
    st = tb__split_prepare(w, w->time + h, predicted);
    if (st == TB_OK)
        st = tb__split_sweep(w, kick, 1);
    w->kick_seen = NULL;
    return st;
}

static tb_status verlet(tb_world *w, double h)
{
    return verlet_with(w, h, TB__ROTATE_SPLIT2);
}

static tb_status verlet_exact(tb_world *w, double h)
{
    return verlet_with(w, h, TB__ROTATE_ACCURATE);
}

/* name, order, split, updates before its last evaluation, scratch vectors */
/* Linearised backward Euler (implicit.c): one conjugate-gradient solve per
   step; stable at any step on springs and drag, and dissipative. */
static tb_status implicit_euler(tb_world *w, double h)
{
    return tb__implicit_step(w, h);
}

/* Dormand-Prince 5(4): the fifth-order solution advances, the embedded
   fourth-order one estimates the local error. The tolerance is an error per
   unit of simulated time: a substep of s seconds is accepted when its
   estimated error, relative to 1 + |y| per component, is at most
   tolerance x s, so that the errors a run adds up stay near
   tolerance x T after T seconds whatever the frame step, and a frame step
   is divided whenever its estimate asks (test_integrators.dopri5_global_
   error_follows_tolerance). With err the estimate over tolerance x s, the
   controller sets h <- h min(5, max(0.2, 0.9 err^(-1/4))) (the estimate
   grows as s^5, the bound as s); a rejected substep (err > 1, or a
   non-finite state) is retried smaller from the same state. The running
   state lives in scratch and is written to the world only at the end, so a
   failing callback leaves the world as it was. */
static const double DP_C[7] = { 0, 1.0 / 5, 3.0 / 10, 4.0 / 5, 8.0 / 9, 1, 1 };
static const double DP_A[7][6] = {
    { 0 },
    { 1.0 / 5 },
    { 3.0 / 40, 9.0 / 40 },
    { 44.0 / 45, -56.0 / 15, 32.0 / 9 },
    { 19372.0 / 6561, -25360.0 / 2187, 64448.0 / 6561, -212.0 / 729 },
    { 9017.0 / 3168, -355.0 / 33, 46732.0 / 5247, 49.0 / 176, -5103.0 / 18656 },
    { 35.0 / 384, 0, 500.0 / 1113, 125.0 / 192, -2187.0 / 6784, 11.0 / 84 },
};
/* fifth-order weights minus fourth-order ones */
static const double DP_E[7] = { 71.0 / 57600, 0, -71.0 / 16695, 71.0 / 1920, -17253.0 / 339200, 22.0 / 525,
                                -1.0 / 40 };
#define DP_MAX_SUBSTEPS 1000000
#define DP_SETTLE 100

static tb_status dopri5(tb_world *w, double H)
{
    double *k[7], *y, *next, *err, *swap, h, done = 0;
    int have_k1 = 0, j, s;
    long substeps = 0;
    tb_status st = tb__state_scratch(w, 10);
    if (st != TB_OK)
        return st;
    for (j = 0; j < 7; ++j)
        k[j] = tb__scratch_vector(w, (size_t)j);
    y = tb__scratch_vector(w, 7);
    next = tb__scratch_vector(w, 8);
    err = tb__scratch_vector(w, 9);
    tb__state_copy(w, y, w->y);
    h = w->adaptive_h > 0 ? w->adaptive_h : H;
    while (done < H) {
        const double t = w->time + done;
        const int last = h >= H - done;
        const double step = last ? H - done : h;
        double e;
        if (++substeps > DP_MAX_SUBSTEPS || step <= 1e-14 * (1 + fabs(t)))
            return tb__fail(w, TB_ERR_ARGUMENT,
                            "dopri5: the substep fell to %g s at t = %.17g s: too stiff for tolerance %g "
                            "(try implicit_euler)", step, t, w->tolerance);
        /* Past DP_SETTLE substeps the controller has found the size this
           state allows; a step that would need more than DP_MAX_SUBSTEPS of
           it is refused now rather than after them (seconds of work for
           the same refusal: test_integrators.dopri5_refuses_a_stiff_step_
           quickly) */
        if (substeps > DP_SETTLE && substeps + (H - done) / step > DP_MAX_SUBSTEPS)
            return tb__fail(w, TB_ERR_ARGUMENT,
                            "dopri5: tolerance %g needs substeps of about %g s at t = %.17g s, %.3g of them for "
                            "the rest of this step (at most %d): too stiff (try implicit_euler, a looser "
                            "tolerance or a shorter step)", w->tolerance, step, t, (H - done) / step,
                            DP_MAX_SUBSTEPS);
        if (!have_k1 && (st = tb__derive(w, t, y, k[0])) != TB_OK)
            return st;
        have_k1 = 1;
        for (s = 1; s < 7; ++s) {
            tb__state_axpy(w, next, y, step * DP_A[s][0], k[0]);
            for (j = 1; j < s; ++j)
                if (DP_A[s][j] != 0)
                    tb__state_axpy(w, next, next, step * DP_A[s][j], k[j]);
            if ((st = tb__derive(w, t + DP_C[s] * step, next, k[s])) != TB_OK)
                return st;
        }
        tb__state_scale(w, err, step * DP_E[0], k[0]);
        for (j = 2; j < 7; ++j)
            tb__state_axpy(w, err, err, step * DP_E[j], k[j]);
        e = tb__state_error_norm(w, err, y, next, w->tolerance * step);
        if (!(e <= 1)) { /* rejected, or not finite: shrink and retry */
            ++w->work.rejected;
            h = step * (isfinite(e) ? fmax(0.2, 0.9 * pow(e, -0.25)) : 0.2);
            continue;
        }
        ++w->work.substeps;
        tb__project(w, next);
        swap = y, y = next, next = swap;
        /* first same as last: the seventh stage is the next first, unless
           projecting moved the state */
        swap = k[0], k[0] = k[6], k[6] = swap;
        have_k1 = w->body_count == 0;
        done = last ? H : done + step;
        if (!last || step == h)
            h = step * fmin(5, fmax(0.2, 0.9 * pow(fmax(e, 1e-10), -0.25)));
    }
    w->adaptive_h = h;
    tb__state_copy(w, w->y, y);
    return TB_OK;
}

/* "auto": the plan (auto.c) names a method and a number of equal substeps;
   it is made again when the step, the tolerance or the set of objects
   changes. The substeps see their own times; the driver adds h at the end. */
static tb_status auto_step(tb_world *w, double h)
{
    const double key[8] = { h, w->tolerance, (double)w->tracer_count, (double)w->particle_count,
                            (double)w->spring_count, (double)w->body_count, (double)w->forces.count,
                            (double)w->fields.count };
    const double t0 = w->time;
    tb_status st = TB_OK;
    long i;
    if (!w->auto_method || memcmp(key, w->auto_key, sizeof key) != 0) {
        if ((st = w->method->plan(w, h)) != TB_OK)
            return st;
        memcpy(w->auto_key, key, sizeof key);
    }
    for (i = 0; i < w->auto_substeps && st == TB_OK; ++i) {
        w->time = t0 + (double)i * (h / (double)w->auto_substeps);
        st = tb__method_step(w, w->auto_method, h / (double)w->auto_substeps);
    }
    w->time = t0;
    return st;
}

const char *tb_world_auto_choice(const tb_world *w, long *substeps)
{
    if (!w) {
        if (substeps)
            *substeps = 0;
        return NULL;
    }
    if (substeps)
        *substeps = w->auto_method ? w->auto_substeps : 0;
    return w->auto_method ? w->auto_method->name : NULL;
}

/* ---- stability on the damped oscillator ------------------------------------
   Each method's largest a = h w on x'' = -w^2 x - 2 z w x' (damping ratio
   z >= 0). A step maps (x, v) by a 2 x 2 amplification matrix G(a, z) with
   trace T and determinant D; it is bounded while both eigenvalues of G lie
   in the unit disc, that is (Jury) while |D| < 1, 1 - T + D > 0 and
   1 + T + D > 0. The derivations are in docs/integrators.md; each limit is
   checked against a bisection of simulated runs on a single damped spring
   (test_stability.damped_limits_match_simulation). */

/* Explicit Euler: T = 2 - 2 a z, D = 1 - 2 a z + a^2, so D < 1 needs
   a < 2 z (z <= 1); for z > 1 the fast real root -w (z + sqrt(z^2 - 1))
   needs a (z + sqrt(z^2 - 1)) < 2. Undamped: no step. */
static double euler_limit(double z)
{
    return z <= 1 ? 2 * z : 2 / (z + sqrt(z * z - 1));
}

/* Symplectic Euler (damping taken at the start): T = 2 - a^2 - 2 a z,
   D = 1 - 2 a z; 1 + T + D > 0 gives a^2 + 4 a z < 4, a < 2 (sqrt(1 + z^2) - z),
   which is below D's bound 1 / z. */
static double symplectic_limit(double z)
{
    return 2 / (sqrt(1 + z * z) + z);
}

/* tumble's Verlet, whose closing kick sees the damping at the predicted
   velocity v_n + h a_n: 1 - T + D = a^2 (1 - a z) and
   1 + T + D = 4 - 4 a z - a^2 (1 - 4 z^2); the first binds for z >= 1/2
   (a < 1 / z), the second below (a < 2 / (z + sqrt(1 - 3 z^2))). Both give 2
   at z = 0 and z = 1/2, and the limit dips to 1.73 at z = 0.3 between. */
static double verlet_limit(double z)
{
    return z <= 0.5 ? 2 / (z + sqrt(1 - 3 * z * z)) : 1 / z;
}

/* The Runge-Kutta methods multiply each eigenvector of the oscillator by
   R(h lambda), R their stability polynomial (coefficients c[0..n-1]) and
   lambda = w (-z +- sqrt(z^2 - 1)): the eigenvalues of G are R(a lambda / w),
   and its spectral radius is their largest modulus. No closed form gives
   where it passes 1, so the limit is found by scanning a in steps of 1/50 of
   the fast root's scale (the unstable bands are far wider) and bisecting the
   first crossing: about 200 polynomial evaluations. */
static double growth(const double *c, int n, double a, double z)
{
    double most = 0;
    int root, k;
    for (root = 0; root < 2; ++root) {
        double re, im = 0, pr = 0, pi = 0;
        if (z < 1) {
            re = -z, im = sqrt(1 - z * z); /* the conjugate root has the same |R| */
            if (root)
                break;
        } else
            re = root ? -(z + sqrt(z * z - 1)) : -1 / (z + sqrt(z * z - 1));
        re *= a, im *= a;
        for (k = n - 1; k >= 0; --k) { /* Horner: p = p mu + c[k] */
            const double t = pr * re - pi * im + c[k];
            pi = pr * im + pi * re;
            pr = t;
        }
        most = fmax(most, sqrt(pr * pr + pi * pi));
    }
    return most;
}

static double polynomial_limit(const double *c, int n, double z)
{
    const double scale = z < 1 ? 1 : 1 / (z + sqrt(z * z - 1)); /* a at which |a lambda| = 1 */
    double lo = 0, hi = 0;
    int i;
    for (i = 1; i <= 400; ++i) {
        hi = i * scale / 50;
        if (growth(c, n, hi, z) > 1 + 1e-12)
            break;
        lo = hi;
    }
    if (i > 400)
        return INFINITY;
    for (i = 0; i < 50; ++i) {
        const double mid = 0.5 * (lo + hi);
        if (growth(c, n, mid, z) > 1 + 1e-12)
            hi = mid;
        else
            lo = mid;
    }
    return lo;
}

/* RK4: R = 1 + mu + mu^2/2 + mu^3/6 + mu^4/24; 2 sqrt 2 at z = 0, 2.835 at
   z = 0.3, 2.785 at z = 1. */
static double rk4_limit(double z)
{
    static const double c[5] = { 1, 1, 1.0 / 2, 1.0 / 6, 1.0 / 24 };
    return polynomial_limit(c, 5, z);
}

/* Dormand-Prince 5: R = the degree-5 Taylor polynomial + mu^6 / 600; 0.997 at
   z = 0 (just above it the growth is 1e-6 a step), 3.22 at z = 0.3, 3.31 at
   z = 1. A limit on each substep, which the controller usually keeps far
   below for accuracy. */
static double dopri5_limit(double z)
{
    static const double c[7] = { 1, 1, 1.0 / 2, 1.0 / 6, 1.0 / 24, 1.0 / 120, 1.0 / 600 };
    return polynomial_limit(c, 7, z);
}

/* Backward Euler is A-stable: bounded at any step for z >= 0. "auto" keeps
   its substeps within the chosen method's limit, so its step has none. */
static double no_limit(double z)
{
    (void)z;
    return INFINITY;
}

/* decay limits h k on v' = -k v: 2 for the Euler methods and Verlet
   (|1 - hk + (hk)^2/2| <= 1), 2.785 for RK4, 3.307 for dopri5 */
static const tb__method methods[] = {
    { "euler", 1, 0, 0, 1, euler, euler_limit, 2, 0, NULL },
    { "symplectic_euler", 1, 1, 0, 0, symplectic_euler, symplectic_limit, 2, 0, NULL },
    { "verlet", 2, 1, 1, 1, verlet, verlet_limit, 2, 0, NULL },
    { "rk4", 4, 0, 0, 3, rk4, rk4_limit, 2.785293563405282, 0, NULL },
    { "verlet_exact", 2, 1, 1, 1, verlet_exact, verlet_limit, 2, 0, NULL },
    { "implicit_euler", 1, 1, 0, 4, implicit_euler, no_limit, INFINITY, 0, NULL },
    { "dopri5", 5, 0, 0, 10, dopri5, dopri5_limit, 3.306567898702859, 1, NULL },
    { "auto", 0, 0, 1, 10, auto_step, no_limit, INFINITY, 1, tb__auto_plan },
};
#define METHOD_COUNT ((int)(sizeof methods / sizeof methods[0]))

/* symplectic_euler always sweeps once; verlet and verlet_exact do in the
   case of their first branch. Springs and callbacks make the particles'
   kicks take the general sweep; damped bodies add their own power. */
int tb__one_pass_step(const tb_world *w)
{
    const tb__method *m = w->method;
    return w->particle_count > 0 && w->forces.count == 0 && w->spring_count == 0 &&
           !tb__body_velocity_dependent(w) &&
           (m->step == symplectic_euler || m->step == verlet || m->step == verlet_exact);
}

tb_status tb__method_step(tb_world *w, const tb__method *m, double h)
{
    const tb_status st = m->step(w, h);
    if (st == TB_OK && !m->adaptive)
        ++w->work.substeps;
    return st;
}

const tb__method *tb__method_find(const char *name)
{
    int i;
    for (i = 0; name && i < METHOD_COUNT; ++i)
        if (strcmp(methods[i].name, name) == 0)
            return &methods[i];
    return NULL;
}

const tb__method *tb__method_at(int index)
{
    return index >= 0 && index < METHOD_COUNT ? &methods[index] : NULL;
}

int tb_integrator_count(void)
{
    return METHOD_COUNT;
}

const char *tb_integrator_name(int index)
{
    return index >= 0 && index < METHOD_COUNT ? methods[index].name : NULL;
}

int tb_integrator_order(int index)
{
    return index >= 0 && index < METHOD_COUNT ? methods[index].order : 0;
}
