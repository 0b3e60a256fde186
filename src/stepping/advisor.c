/* advisor.c: estimate the stiffest mode of a world and the stability limit
   of its integrator, before a run. */
#include "stepping/stepping.h"
#include "bodies/bodies.h"
#include "forces/forces.h"
#include "particles/particles.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Largest eigenvalue of M^-1 K by power iteration on the symmetric
   B = M^-1/2 K M^-1/2 (same eigenvalues), with Rayleigh quotients, which
   approach it from below. The start is a sign pattern that alternates from
   slot to slot (the zigzag of a chain), lightly scrambled so that it
   overlaps every mode. `z`, `s`, `t` are scratch of 3n doubles; `z` ends as
   the estimated mode. */
static double largest_mode(const tb_world *w, double *z, double *s, double *t)
{
    const size_t n = 3 * w->particle_count;
    const double *pos = w->y + w->off[TB__PARTICLE_POS];
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
        memset(w->particle_force, 0, n * sizeof(double)); /* K t, in the force scratch */
        tb__spring_stiffness_product(w, pos, t, w->particle_force, 0);
        for (i = 0; i < n; ++i) {
            const double bz = s[i] * w->particle_force[i];
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

tb_status tb__stiffest_mode(tb_world *w, double *omega, tb_spring_id *spring)
{
    const size_t n = 3 * w->particle_count;
    double *z, *s, *t;
    /* three vectors of 3n: a state vector holds at least 6n doubles
       (positions and velocities), so two of them are enough */
    tb_status st = tb__state_scratch(w, 2);
    if (st != TB_OK)
        return st;
    z = tb__scratch_vector(w, 0);
    s = z + n;
    t = tb__scratch_vector(w, 1);
    *omega = sqrt(largest_mode(w, z, s, t));
    *spring = culprit(w, z);
    return TB_OK;
}

/* The limit of method m on this world: min(c_osc / w, c_decay / k). */
static double limit_of(const tb__method *m, double omega, double decay)
{
    double limit = INFINITY;
    if (omega > 0)
        limit = m->oscillation_limit / omega;
    if (decay > 0)
        limit = fmin(limit, m->decay_limit / decay);
    return limit;
}

tb_status tb_world_advise(tb_world *w, double h, tb_advice *advice)
{
    tb_status st;
    const tb__method *best = NULL;
    double best_limit = 0;
    int i;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if (!advice)
        return tb__null(w, "tb_world_advise", "the advice to write");
    if ((st = tb__check_scale(w, h, "step")) != TB_OK)
        return st;
    if ((st = tb__check_busy(w, "advise")) != TB_OK)
        return st;
    memset(advice, 0, sizeof *advice);
    if (w->spring_count && (st = tb__stiffest_mode(w, &advice->stiffest, &advice->spring)) != TB_OK)
        return st;
    advice->decay = tb__fastest_decay(w);
    advice->fastest_spin = fastest_spin(w);
    advice->limit = limit_of(w->method, advice->stiffest, advice->decay);
    advice->exceeded = h > advice->limit;
    for (i = 0; tb__method_at(i); ++i) {
        const tb__method *m = tb__method_at(i);
        const double limit = limit_of(m, advice->stiffest, advice->decay);
        if (limit > best_limit && !m->adaptive && !(m->split && w->tracer_count))
            best_limit = limit, best = m;
    }
    if (w->method->plan) {
        if ((st = w->method->plan(w, h)) != TB_OK)
            return st;
        snprintf(advice->text, sizeof advice->text,
                 "%s picks %s with %ld substep%s of %.4g s for tolerance %g (stiffest mode %.4g rad/s, "
                 "decay %.4g 1/s, spin %.4g rad/s)", w->method->name, w->auto_method->name, w->auto_substeps,
                 w->auto_substeps == 1 ? "" : "s", h / (double)w->auto_substeps, w->tolerance, advice->stiffest,
                 advice->decay, advice->fastest_spin);
    } else if (w->method->adaptive) {
        snprintf(advice->text, sizeof advice->text,
                 "%s chooses its own substeps for tolerance %g (stiffest mode %.4g rad/s)", w->method->name,
                 w->tolerance, advice->stiffest);
    } else if (advice->limit == INFINITY && w->method->oscillation_limit == INFINITY) {
        snprintf(advice->text, sizeof advice->text,
                 "%s is stable at any step; it damps modes faster than 1/h (stiffest %.4g rad/s)", w->method->name,
                 advice->stiffest);
    } else if (advice->limit == INFINITY) {
        snprintf(advice->text, sizeof advice->text, "no spring or drag limits the step of %s", w->method->name);
    } else if (!advice->exceeded) {
        const int by_springs = advice->stiffest > 0 &&
                               advice->limit == w->method->oscillation_limit / advice->stiffest;
        char cause[96];
        if (by_springs)
            snprintf(cause, sizeof cause, "stiffest spring mode %.4g rad/s", advice->stiffest);
        else
            snprintf(cause, sizeof cause, "fastest drag decay %.4g 1/s", advice->decay);
        snprintf(advice->text, sizeof advice->text, "step %g s is %.2g%% of the limit %.4g s of %s (%s)", h,
                 100 * h / advice->limit, advice->limit, w->method->name, cause);
    } else {
        int len = advice->limit > 0
                      ? snprintf(advice->text, sizeof advice->text,
                                 "step %g s exceeds the limit %.4g s of %s: use dt <= %.4g s", h, advice->limit,
                                 w->method->name, 0.9 * advice->limit)
                      : snprintf(advice->text, sizeof advice->text,
                                 "%s is unstable at any step on oscillations (stiffest mode %.4g rad/s)",
                                 w->method->name, advice->stiffest);
        if (len > 0 && (size_t)len < sizeof advice->text && best && best != w->method && best_limit >= h)
            snprintf(advice->text + len, sizeof advice->text - (size_t)len,
                     best_limit == INFINITY ? " or integrator '%s' (stable at any step, dissipative)"
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
