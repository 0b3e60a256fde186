/* advisor.c: estimate the stiffest mode of a world and the stability limit
   of its integrator, before a run. */
#include "stepping/stepping.h"
#include "bodies/bodies.h"
#include "forces/forces.h"
#include "particles/particles.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* out = P t for the symmetric matrix P: the springs' stiffness K at the
   current positions, or their damping C plus drag D (linear drag, and
   quadratic drag linearised at each particle's speed, d(c2 |v| v)/dv at
   most 2 c2 |v|). `out` is 3n doubles. */
static void product(const tb_world *w, int damping, const double *t, double *out)
{
    const size_t n = 3 * w->particle_count;
    const double *pos = w->y + w->off[TB__PARTICLE_POS];
    const double *vel = w->y + w->off[TB__PARTICLE_VEL];
    size_t i;
    memset(out, 0, n * sizeof(double));
    if (!damping) {
        tb__spring_stiffness_product(w, pos, t, out, 0);
        return;
    }
    tb__spring_damping_product(w, pos, t, out);
    if (w->linear_drag > 0 || w->quadratic_drag > 0)
        for (i = 0; i < n; ++i) {
            const double *v = vel + 3 * (i / 3);
            out[i] += (w->linear_drag + 2 * w->quadratic_drag * sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])) * t[i];
        }
}

/* u.B u for the unit vector z / |z|, B = M^-1/2 P M^-1/2 (s holds the
   M^-1/2 diagonal; t is scratch of 6n: t, then P t). */
static double quotient(tb_world *w, int damping, const double *z, const double *s, double *t)
{
    const size_t n = 3 * w->particle_count;
    double norm = 0, q = 0;
    size_t i;
    for (i = 0; i < n; ++i)
        norm += z[i] * z[i];
    if (norm == 0)
        return 0;
    for (i = 0; i < n; ++i)
        t[i] = s[i] * z[i] / sqrt(norm);
    product(w, damping, t, t + n);
    for (i = 0; i < n; ++i)
        q += t[i] * t[n + i];
    return q;
}

/* Largest eigenvalue of M^-1 P (P as in `product`) by power iteration on
   the symmetric B = M^-1/2 P M^-1/2 (same eigenvalues), with Rayleigh
   quotients, which approach it from below. The start is a sign pattern
   that alternates from slot to slot (the zigzag of a chain), lightly
   scrambled so that it overlaps every mode. `z` and `s` are scratch of 3n
   doubles, `t` of 6n (t, then P t); `z` ends as the estimated mode. The
   world's arrays are not touched: the advisor changes nothing. */
static double largest_mode(tb_world *w, int damping, double *z, double *s, double *t)
{
    const size_t n = 3 * w->particle_count;
    double lambda = 0, previous = -1;
    size_t i;
    int it, calm = 0;
    for (i = 0; i < n; ++i) {
        const unsigned h = (unsigned)(i * 2654435761u) >> 20;
        s[i] = sqrt(w->particle_inv_mass[i / 3]);
        z[i] = ((i / 3) % 2 ? -1.0 : 1.0) * (1 + (double)h / 8192);
    }
    for (it = 0; it < 500 && calm < 10; ++it) {
        double norm = 0, rayleigh = 0;
        for (i = 0; i < n; ++i)
            norm += z[i] * z[i];
        norm = sqrt(norm);
        if (norm == 0)
            return 0;
        for (i = 0; i < n; ++i) {
            z[i] /= norm;
            t[i] = s[i] * z[i];
        }
        product(w, damping, t, t + n);
        for (i = 0; i < n; ++i) {
            const double bz = s[i] * t[n + i];
            rayleigh += z[i] * bz;
            z[i] = bz;
        }
        lambda = rayleigh;
        calm = fabs(lambda - previous) <= 1e-7 * fabs(lambda) ? calm + 1 : 0;
        previous = lambda;
    }
    return lambda > 0 ? lambda : 0;
}

/* The stiffest spring at the particle where the mode is largest. */
static tb_spring_id culprit(const tb_world *w, const double *z)
{
    tb_spring_id id = { 0, 0 };
    size_t i, best = 0, s;
    double big = -1, stiffest = -1;
    for (i = 0; i < w->particle_count; ++i) {
        const double m = z[3 * i] * z[3 * i] + z[3 * i + 1] * z[3 * i + 1] + z[3 * i + 2] * z[3 * i + 2];
        if (m > big)
            big = m, best = i;
    }
    for (s = 0; s < w->spring_count; ++s)
        if ((w->spring_a[s] == best || w->spring_b[s] == best) && w->spring_k[s] > stiffest) {
            stiffest = w->spring_k[s];
            tb__ids_at(&w->spring_ids, (uint32_t)s, &id.index1, &id.generation);
        }
    return id;
}

double tb__fastest_decay(const tb_world *w)
{
    const double *v = w->y + w->off[TB__PARTICLE_VEL];
    double k = 0;
    size_t i;
    for (i = 0; i < w->particle_count; ++i) {
        const double speed = sqrt(v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1] + v[3 * i + 2] * v[3 * i + 2]);
        /* quadratic drag linearised: d(c2 |v| v)/dv has norm 2 c2 |v| */
        const double rate = (w->linear_drag + 2 * w->quadratic_drag * speed) * w->particle_inv_mass[i];
        if (rate > k)
            k = rate;
    }
    for (i = 0; i < w->body_count; ++i) {
        if (w->body_damping[2 * i] > k)
            k = w->body_damping[2 * i];
        if (w->body_damping[2 * i + 1] > k)
            k = w->body_damping[2 * i + 1];
    }
    return k;
}

static double fastest_spin(const tb_world *w)
{
    const double *L = w->y + w->off[TB__BODY_ANG];
    double fastest = 0;
    size_t i;
    for (i = 0; i < w->body_count; ++i) {
        /* |w| <= |L| / I_min */
        const double *inv = w->body_inv_inertia + 3 * i;
        const double most = fmax(inv[0], fmax(inv[1], inv[2]));
        const double spin = most * sqrt(L[3 * i] * L[3 * i] + L[3 * i + 1] * L[3 * i + 1] + L[3 * i + 2] * L[3 * i + 2]);
        if (spin > fastest)
            fastest = spin;
    }
    return fastest;
}

static int has_damping(const tb_world *w)
{
    size_t i;
    if (w->linear_drag > 0 || w->quadratic_drag > 0)
        return 1;
    for (i = 0; i < w->spring_count; ++i)
        if (w->spring_c[i] > 0)
            return 1;
    return 0;
}

/* A mode of a damped system is a mode of M^-1 K only when C is a
   combination of M and K; in general the damping couples them. The advisor
   takes the two modes that bound the step in practice: the stiffest one
   (the largest eigenvalue w^2 of M^-1 K), with the damping it sees (the
   Rayleigh quotient of M^-1/2 (C + D) M^-1/2 on it, 2 z w), and the most
   damped one (the largest eigenvalue of M^-1 (C + D)), with the stiffness
   it sees. On chains and cloth of unequal masses and springs whose damping
   ratios are 0, 0.3 and 1, the limit this gives is within 10% of the
   measured blow-up (test_stability.advisor_predicts_damped_chains,
   advisor_predicts_damped_cloth). */
tb_status tb__modes_of(tb_world *w, tb__modes *modes)
{
    const size_t n = 3 * w->particle_count;
    double *z, *s, *t;
    tb_status st;
    memset(modes, 0, sizeof *modes);
    modes->decay = tb__fastest_decay(w);
    if (!w->particle_count)
        return TB_OK;
    /* four vectors of 3n: a state vector holds at least 6n doubles
       (positions and velocities), so two of them are enough */
    if ((st = tb__state_scratch(w, 2)) != TB_OK)
        return st;
    z = tb__scratch_vector(w, 0);
    s = z + n;
    t = tb__scratch_vector(w, 1);
    if (w->spring_count) {
        modes->omega = sqrt(largest_mode(w, 0, z, s, t));
        modes->spring = culprit(w, z);
        if (modes->omega > 0)
            modes->zeta = fmax(0, quotient(w, 1, z, s, t)) / (2 * modes->omega);
    }
    if (has_damping(w)) {
        modes->damped_rate = largest_mode(w, 1, z, s, t);
        if (w->spring_count && modes->damped_rate > 0)
            modes->damped_omega = sqrt(fmax(0, quotient(w, 0, z, s, t)));
    }
    return TB_OK;
}

/* min(L(z) / w) over the two modes and c_decay / k over the decay, with L
   the method's damped limit (integrators.c). A mode with no stiffness is
   a pure decay at its rate. */
double tb__limit_of(const tb__method *m, const tb__modes *r, int *cause)
{
    double limit = INFINITY, l;
    int why = 0;
    if (r->omega > 0 && (l = m->damped_limit(r->zeta) / r->omega) < limit)
        limit = l, why = 1;
    if (r->damped_rate > 0) {
        l = r->damped_omega > 0 ? m->damped_limit(r->damped_rate / (2 * r->damped_omega)) / r->damped_omega
                                : m->decay_limit / r->damped_rate;
        /* where damping follows stiffness the two modes are one: it is
           named as the stiffest unless clearly below */
        if (l < limit)
            why = l < 0.999 * limit ? 2 : why, limit = l;
    }
    if (r->decay > 0 && (l = m->decay_limit / r->decay) < limit)
        limit = l, why = 3;
    if (cause)
        *cause = why;
    return limit;
}

/* "stiffest spring mode 891.8 rad/s, damping ratio 0.3" or the decay that binds */
static void describe_cause(const tb__modes *r, int cause, char *out, size_t size)
{
    if (cause == 1)
        snprintf(out, size, "stiffest spring mode %.4g rad/s, damping ratio %.3g", r->omega, r->zeta);
    else if (cause == 2 && r->damped_omega > 0)
        snprintf(out, size, "most damped mode: decay %.4g 1/s, %.4g rad/s", r->damped_rate, r->damped_omega);
    else
        snprintf(out, size, "fastest decay %.4g 1/s", cause == 2 ? r->damped_rate : r->decay);
}

tb_status tb_world_advise(tb_world *w, double h, tb_advice *advice)
{
    tb_status st;
    tb__modes r;
    const tb__method *best = NULL;
    double best_limit = 0;
    int i, cause = 0;
    char why[128];
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if (!advice)
        return tb__null(w, "tb_world_advise", "the advice to write");
    if ((st = tb__check_scale(w, h, "step")) != TB_OK)
        return st;
    if ((st = tb__check_busy(w, "advise")) != TB_OK)
        return st;
    if ((st = tb__modes_of(w, &r)) != TB_OK)
        return st;
    memset(advice, 0, sizeof *advice);
    advice->stiffest = r.omega;
    advice->damping_ratio = r.zeta;
    advice->decay = fmax(r.decay, r.damped_rate);
    advice->spring = r.spring;
    advice->fastest_spin = fastest_spin(w);
    advice->limit = w->method->adaptive ? INFINITY : tb__limit_of(w->method, &r, &cause);
    advice->exceeded = h > advice->limit;
    for (i = 0; tb__method_at(i); ++i) {
        const tb__method *m = tb__method_at(i);
        const double limit = tb__limit_of(m, &r, NULL);
        if (limit > best_limit && !m->adaptive && !(m->split && w->tracer_count))
            best_limit = limit, best = m;
    }
    if (w->method->plan) {
        /* the plan for h, made and put back: the world keeps the plan its
           steps made, so that asking (as the guard does after a refused
           step) changes nothing (test_snapshot.refused_step_leaves_no_trace) */
        const tb__method *kept = w->auto_method;
        const long kept_substeps = w->auto_substeps;
        const char *name;
        long substeps;
        char costs[320];
        int len;
        st = tb__auto_plan_why(w, h, costs, sizeof costs);
        name = w->auto_method ? w->auto_method->name : "?";
        substeps = w->auto_substeps;
        w->auto_method = kept, w->auto_substeps = kept_substeps;
        if (st != TB_OK)
            return st;
        len = snprintf(advice->text, sizeof advice->text,
                       "%s picks %s with %ld substep%s of %.4g s for tolerance %g (stiffest mode %.4g rad/s, "
                       "damping ratio %.3g, decay %.4g 1/s, spin %.4g rad/s)", w->method->name, name, substeps,
                       substeps == 1 ? "" : "s", h / (double)substeps, w->tolerance, advice->stiffest,
                       advice->damping_ratio, advice->decay, advice->fastest_spin);
        if (len > 0 && (size_t)len < sizeof advice->text) /* and why: the costs it compared */
            snprintf(advice->text + len, sizeof advice->text - (size_t)len, "; %s", costs);
    } else if (w->method->adaptive) {
        const double substep = tb__limit_of(w->method, &r, &cause);
        if (substep < INFINITY) {
            describe_cause(&r, cause, why, sizeof why);
            snprintf(advice->text, sizeof advice->text,
                     "%s chooses its own substeps for tolerance %g; stability keeps them below %.4g s (%s)",
                     w->method->name, w->tolerance, substep, why);
        } else
            snprintf(advice->text, sizeof advice->text, "%s chooses its own substeps for tolerance %g",
                     w->method->name, w->tolerance);
    } else if (advice->limit == INFINITY && w->method->damped_limit(0) == INFINITY) {
        snprintf(advice->text, sizeof advice->text,
                 "%s is stable at any step; it damps modes faster than 1/h (stiffest %.4g rad/s) and slows "
                 "them: a mode of w rad/s turns at atan(h w) / h", w->method->name, advice->stiffest);
    } else if (advice->limit == INFINITY) {
        snprintf(advice->text, sizeof advice->text, "no spring or drag limits the step of %s", w->method->name);
    } else if (!advice->exceeded) {
        describe_cause(&r, cause, why, sizeof why);
        snprintf(advice->text, sizeof advice->text, "step %g s is %.2g%% of the limit %.4g s of %s (%s)", h,
                 100 * h / advice->limit, advice->limit, w->method->name, why);
    } else {
        int len;
        describe_cause(&r, cause, why, sizeof why);
        len = advice->limit > 0
                  ? snprintf(advice->text, sizeof advice->text,
                             "step %g s exceeds the limit %.4g s of %s (%s): use dt <= %.4g s", h, advice->limit,
                             w->method->name, why, 0.9 * advice->limit)
                  : snprintf(advice->text, sizeof advice->text,
                             "%s is unstable at any step on undamped oscillations (stiffest mode %.4g rad/s)",
                             w->method->name, advice->stiffest);
        if (len > 0 && (size_t)len < sizeof advice->text && best && best != w->method && best_limit >= h)
            snprintf(advice->text + len, sizeof advice->text - (size_t)len,
                     best_limit == INFINITY ? " or integrator '%s' (stable at any step; it damps and slows oscillations)"
                                            : " or integrator '%s' (limit %.4g s)",
                     best->name, best_limit);
        if (!TB_ID_IS_NULL(advice->spring)) {
            len = (int)strlen(advice->text);
            snprintf(advice->text + len, sizeof advice->text - (size_t)len,
                     "; the stiffest mode (%.4g rad/s) is largest at spring %u", advice->stiffest,
                     (unsigned)advice->spring.index1);
        }
    }
    return TB_OK;
}
