/* guard.c: the blow-up guard. After a step it looks for a state that is no
   longer finite, has run away past any plausible magnitude or holds an
   orientation that is no longer a unit quaternion, or (when asked) energy
   that grew faster than the physics allows, names the object and the likely
   cause, and rolls the world back to the snapshot the step took first
   (snapshot.c).
   It is off by default because it needs that copy every step; the tumble
   command turns it on. */
#include "stepping/stepping.h"
#include "bodies/bodies.h"
#include "forces/forces.h"
#include "particles/particles.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static const struct {
    enum tb__tier tier;
    int width;
} quantities[] = {
#define TB__DESCRIBE(name, tier, width) { tier, width },
    TB__QUANTITIES(TB__DESCRIBE)
#undef TB__DESCRIBE
};

static const char *const tier_names[TB__TIERS] = { "tracer", "particle", "body" };
static const char *const quantity_names[TB__QUANTITY_COUNT] = {
    "position", "position", "velocity", "position", "orientation", "momentum", "angular momentum"
};

static size_t tier_count(const tb_world *w, enum tb__tier tier)
{
    return tier == TB__TRACERS ? w->tracer_count : tier == TB__PARTICLES ? w->particle_count : w->body_count;
}

static const tb__ids *tier_ids(const tb_world *w, enum tb__tier tier)
{
    return tier == TB__TRACERS ? &w->tracer_ids : tier == TB__PARTICLES ? &w->particle_ids : &w->body_ids;
}

static unsigned id_of(const tb_world *w, enum tb__tier tier, size_t slot)
{
    uint32_t index1, generation;
    tb__ids_at(tier_ids(w, tier), (uint32_t)slot, &index1, &generation);
    return (unsigned)index1;
}

/* The guard's bound on the state's magnitudes: far beyond what the input
   rule admits (TB_LIMIT, 1e100), so a world the rule accepts runs a long
   way before it meets it, and short of 1e154, past which the squares a
   step forms (distances, energies) are no longer finite. A state past it is
   a runaway whose next steps would be noise, then Inf. */
#define RUNAWAY 1e150

/* How far |q|^2 of a body may be from 1 after a step: every method leaves
   it within 1e-8 (the lanes renormalise to 5e-9); a turn whose arithmetic
   overflowed leaves 0 or garbage. */
#define UNIT_SLACK 1e-6

/* The first number of state y that is not finite or past RUNAWAY, or the
   first body whose orientation is not a unit quaternion or whose velocity
   or angular velocity is past RUNAWAY, as "particle 17's velocity is not
   finite". 0 when the state is sound. */
static int find_unsound(const tb_world *w, const double *y, char *out, size_t size)
{
    int q;
    size_t s;
    for (q = 0; q < TB__QUANTITY_COUNT; ++q) {
        const double *a = y + w->off[q];
        const size_t n = tier_count(w, quantities[q].tier) * (size_t)quantities[q].width;
        size_t i;
        for (i = 0; i < n; ++i)
            if (!(fabs(a[i]) <= RUNAWAY)) {
                const size_t slot = i / (size_t)quantities[q].width;
                if (isfinite(a[i]))
                    snprintf(out, size, "%s %u's %s is %g, past %g (a runaway)", tier_names[quantities[q].tier],
                             id_of(w, quantities[q].tier, slot), quantity_names[q], a[i], RUNAWAY);
                else
                    snprintf(out, size, "%s %u's %s is not finite", tier_names[quantities[q].tier],
                             id_of(w, quantities[q].tier, slot), quantity_names[q]);
                return 1;
            }
    }
    for (s = 0; s < w->body_count; ++s) {
        const double *r = y + w->off[TB__BODY_ROT] + 4 * s;
        const double n2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3];
        const double *P = y + w->off[TB__BODY_MOM] + 3 * s, *L = y + w->off[TB__BODY_ANG] + 3 * s;
        const double *inv = w->body_inv_inertia + 3 * s;
        const double p = fmax(fabs(P[0]), fmax(fabs(P[1]), fabs(P[2])));
        const double l = fmax(fabs(L[0]), fmax(fabs(L[1]), fabs(L[2])));
        if (!(fabs(n2 - 1) <= UNIT_SLACK)) {
            snprintf(out, size, "body %u's orientation is no longer a unit quaternion (|q| = %g)",
                     id_of(w, TB__BODIES, s), sqrt(n2));
            return 1;
        }
        /* the rates a light body gets from bounded momenta: v = P / m, and
           w = R diag(1/I) R^T L, worked out only when its bound
           |w| <= sqrt(3) |L|_max max(1/I) could pass RUNAWAY */
        if (!(p * w->body_inv_mass[s] <= RUNAWAY)) {
            snprintf(out, size, "body %u's velocity is %g m/s, past %g (a runaway)", id_of(w, TB__BODIES, s),
                     p * w->body_inv_mass[s], RUNAWAY);
            return 1;
        }
        if (!(1.7320508075688772 * l * fmax(inv[0], fmax(inv[1], inv[2])) <= RUNAWAY)) {
            double omega[3], fastest;
            tb__through_inertia(r, inv, L, omega);
            fastest = fmax(fabs(omega[0]), fmax(fabs(omega[1]), fabs(omega[2])));
            if (!(fastest <= RUNAWAY)) {
                snprintf(out, size, "body %u's angular velocity is %g rad/s, past %g (a runaway)",
                         id_of(w, TB__BODIES, s), fastest, RUNAWAY);
                return 1;
            }
        }
    }
    return 0;
}

/* Kinetic, rotational and spring energy (never negative), and the gravity
   potential, of the state y. */
static void energies(const tb_world *w, const double *y, double *positive, double *gravity)
{
    const tb_energy e = tb__energy_of(w, y);
    *positive = e.kinetic + e.rotational + e.spring;
    *gravity = e.gravity;
}

/* The object whose kinetic energy grew the most over the step. */
static void biggest_gain(const tb_world *w, const double *before, char *out, size_t size)
{
    double best = -INFINITY;
    size_t i, k;
    enum tb__tier tier = TB__PARTICLES;
    size_t slot = 0;
    for (i = 0; i < w->particle_count; ++i) {
        const double *v1 = w->y + w->off[TB__PARTICLE_VEL] + 3 * i;
        const double *v0 = before + w->off[TB__PARTICLE_VEL] + 3 * i;
        double gain = 0;
        for (k = 0; k < 3; ++k)
            gain += w->particle_mass[i] * (v1[k] * v1[k] - v0[k] * v0[k]) / 2;
        if (gain > best)
            best = gain, tier = TB__PARTICLES, slot = i;
    }
    for (i = 0; i < w->body_count; ++i) {
        const double *p1 = w->y + w->off[TB__BODY_MOM] + 3 * i;
        const double *p0 = before + w->off[TB__BODY_MOM] + 3 * i;
        double gain = 0;
        for (k = 0; k < 3; ++k)
            gain += w->body_inv_mass[i] * (p1[k] * p1[k] - p0[k] * p0[k]) / 2;
        if (gain > best)
            best = gain, tier = TB__BODIES, slot = i;
    }
    if (best > -INFINITY)
        snprintf(out, size, "%s %u gained the most", tier_names[tier], id_of(w, tier, slot));
    else
        snprintf(out, size, "no particle or body moved");
}

tb_status tb__guard_check(tb_world *w, double h)
{
    char what[256], cause[TB_MESSAGE_SIZE];
    const double *before = tb__rollback_state(w);
    tb_advice advice;
    if (!find_unsound(w, w->y, what, sizeof what)) {
        double p0, u0, p1, u1, allowed;
        if (!(w->guard > 1 && w->guard < INFINITY))
            return TB_OK;
        energies(w, before, &p0, &u0);
        energies(w, w->y, &p1, &u1);
        /* gravity may turn its potential into motion; beyond that, the
           energy may grow by the factor asked (forces that do work, such as
           callbacks, must fit in it) */
        allowed = w->guard * (p0 + fmax(0, u0 - u1));
        if (!(p1 > allowed) || allowed == 0)
            return TB_OK;
        {
            char who[64];
            biggest_gain(w, before, who, sizeof who);
            snprintf(what, sizeof what, "the energy grew %.3g times in one step (guard %g; %s)",
                     p0 > 0 ? p1 / p0 : INFINITY, w->guard, who);
        }
    }
    /* back to the world before the step, caches and sleep included, then
       ask the advisor why; out of memory to give a grown contact array its
       old capacity back, the state at least */
    if (tb__rollback(w) != TB_OK)
        tb__state_copy(w, w->y, before);
    memset(&advice, 0, sizeof advice);
    {
        char was[256];
        int advised = 0;
        if (find_unsound(w, before, was, sizeof was)) /* the guard came on after the harm was done */
            snprintf(cause, sizeof cause, "the state was unsound before this step already (%s): set it anew, no "
                     "step can mend it", was);
        else if ((advised = tb_world_advise(w, h, &advice) == TB_OK) && advice.exceeded)
            snprintf(cause, sizeof cause, "%s", advice.text);
        else if (advised && h > 0.9 * advice.limit) /* the estimate errs by up to 10% (test_stability) */
            snprintf(cause, sizeof cause, "step %g s is %.0f%% of the estimated limit %.4g s of %s, within the "
                     "estimate's 10%% margin: use a smaller step", h, 100 * h / advice.limit, advice.limit,
                     w->method->name);
        else if (advice.fastest_spin * h > 1) /* the advisor's limits leave spins out */
            snprintf(cause, sizeof cause, "the fastest body spins at %g rad/s, %g rad in a step of %g s: use a "
                     "smaller step", advice.fastest_spin, advice.fastest_spin * h, h);
        else
            snprintf(cause, sizeof cause, "no stability limit of %s is exceeded: look at the forces on it "
                     "(callbacks, applied forces, huge velocities)", w->method->name);
    }
    return tb__fail(w, TB_ERR_UNSTABLE, "step %lu (t = %.6g s): %s; %s. The world is back at t = %.6g s",
                    w->steps + 1, w->time + h, what, cause, w->time);
}

tb_status tb_world_set_guard(tb_world *w, double energy_growth)
{
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    st = tb__check_busy(w, "change the guard");
    if (st != TB_OK)
        return st;
    if (!(energy_growth == 0 || energy_growth > 1)) /* NaN fails both */
        return tb__fail(w, TB_ERR_ARGUMENT,
                        "guard must be 0 (off), > 1 (the largest energy growth per step) or inf "
                        "(finiteness only) (got %g)", energy_growth);
    w->guard = energy_growth;
    return TB_OK;
}

double tb_world_guard(const tb_world *w)
{
    TB__NEED_WORLD(w, 0);
    return w->guard;
}
