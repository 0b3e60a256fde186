/* auto.c: the plan of integrator "auto": from what the world contains, the
   cheapest method and number of equal substeps per step whose estimated
   local error meets the world's tolerance.

   Each candidate method of order p makes a local error of about
   C (r s)^(p+1) per substep s on a mode of rate r, relative to the mode's
   size: the first term its stability function R(z) misses of e^z on
   oscillations (z = i w s), decays (z = -k s) and spins. The rates come from
   the scene: the stiffest spring mode (the advisor's power iteration), the
   fastest drag or damping decay, the fastest body spin, vortex fields.
   Gravity and other constant forces cost the split methods nothing (Verlet
   is exact on them), and isotropic bodies turn exactly under the split
   methods. What the plan cannot see (force callbacks, field callbacks,
   joints) goes to "dopri5", which measures its own error. The plan is
   made when the step, the tolerance or the set of objects changes. */
#include "stepping/stepping.h"
#include "bodies/bodies.h"
#include "forces/forces.h"
#include "particles/particles.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* A candidate: the constants of its leading local error terms and its cost
   per substep, in force evaluations (Verlet's two kicks share one). */
typedef struct candidate {
    const char *name;
    double cost;           /* per substep in a world of particles */
    double body_cost;      /* ... and of bodies (measured, rk4 = 4) */
    int order;             /* on oscillations and decays */
    double c_oscillation;  /* local error (w s)^(p+1) times this */
    double c_decay;        /* local error (k s)^(p+1) times this */
    int spin_order;        /* on anisotropic bodies' free rotation; 0: exact */
    double c_spin;
    int iso_spin_order;    /* on isotropic bodies' rotation; 0: exact */
} candidate;

/* Verlet: the leading term of R(z) - e^z on the imaginary axis is
   (w s)^3 / 12 in the phase and (w s)^3 / 6 in the energy-conjugate
   variable; on a decay (k s)^3 / 6. Its axis splitting errs by about
   (W s)^3 / 12 on a fast-spinning asymmetric body (measured on the flip).
   RK4 misses z^5 / 120. verlet_exact's composed rotation is fourth order
   with a small constant (1.5e-7 (W s)^5 measured on the flip; 1e-6 kept).
   dopri5's controller keeps |y5 - y4| ~ (r s)^5 / 600 below the tolerance. */
static const candidate candidates[] = {
    { "verlet", 1.6, 2.9, 2, 1.0 / 6, 1.0 / 6, 2, 1.0 / 12, 0 },
    { "verlet_exact", 1.6, 8.5, 2, 1.0 / 6, 1.0 / 6, 4, 1e-6, 0 },
    { "rk4", 4.0, 4.0, 4, 1.0 / 120, 1.0 / 120, 4, 1.0 / 120, 4 },
    { "dopri5", 9.0, 17.0, 4, 1.0 / 600, 1.0 / 600, 4, 1.0 / 600, 4 },
};
#define CANDIDATES ((int)(sizeof candidates / sizeof candidates[0]))

/* The rates that set the error of a step. */
typedef struct rates {
    double oscillation;    /* rad/s: springs, vortex fields */
    double decay;          /* 1/s: drag, spring and body damping */
    double spin;           /* rad/s: anisotropic bodies */
    double iso_spin;       /* rad/s: isotropic bodies and symmetric tops, which
                              the split methods turn exactly (only RK-type
                              methods err) */
    int unknown;           /* callbacks: rates the plan cannot see */
    tb__modes modes;       /* what limits each method's step (advisor.c) */
    double vortex;         /* rad/s, the fastest vortex field: an undamped turn */
} rates;

static tb_status scene_rates(tb_world *w, rates *r)
{
    size_t i;
    tb_status st;
    memset(r, 0, sizeof *r);
    if ((st = tb__modes_of(w, &r->modes)) != TB_OK)
        return st;
    r->oscillation = r->modes.omega;
    r->decay = r->modes.decay;
    /* quadratic drag at rest has no rate yet; it reaches its largest near
       terminal speed, sqrt(m g / c2), where d(c2 |v| v)/dv / m = 2 sqrt(g c2 / m) */
    if (w->quadratic_drag > 0)
        for (i = 0; i < w->particle_count; ++i)
            r->decay = fmax(r->decay, 2 * sqrt(tb__norm3(w->gravity) * w->quadratic_drag * w->particle_inv_mass[i]));
    for (i = 0; i < w->spring_count; ++i) {
        const double ma = w->particle_inv_mass[w->spring_a[i]];
        const double mb = w->spring_b[i] == TB__ANCHOR ? 0 : w->particle_inv_mass[w->spring_b[i]];
        r->decay = fmax(r->decay, w->spring_c[i] * (ma + mb));
    }
    for (i = 0; i < w->body_count; ++i) {
        const double *inv = w->body_inv_inertia + 3 * i;
        const double spin = fmax(inv[0], fmax(inv[1], inv[2])) * tb__norm3(w->y + w->off[TB__BODY_ANG] + 3 * i);
        if (inv[0] == inv[1] || inv[1] == inv[2] || inv[0] == inv[2])
            r->iso_spin = fmax(r->iso_spin, spin);
        else
            r->spin = fmax(r->spin, spin);
    }
    /* joints' rates are not estimated (a pendulum's depends on its swing,
       a chain's on its tension), so they count as unseen: under a plan
       blind to them a 170-degree pendulum erred by half its length at
       every tolerance (bench_workprecision, "pendulum") */
    r->unknown = w->forces.count > 0 || w->joint_count > 0;
    for (i = 0; i < w->fields.count; ++i) {
        const tb__field *f = TB__LIST_AT(&w->fields, tb__field, i);
        if (f->kind == TB__FIELD_CALLBACK)
            r->unknown = 1;
        else if (f->kind == TB__FIELD_VORTEX)
            r->vortex = fmax(r->vortex, tb__norm3(f->a));
    }
    r->oscillation = fmax(r->oscillation, r->vortex);
    return TB_OK;
}

/* The substeps n of a step h whose errors add up to at most tol h on one
   rate (the tolerance is an error per second of simulated time, as
   dopri5's): n C (r h / n)^(p+1) <= tol h. */
static double substeps_for(double rate, double h, double c, int order, double tol)
{
    if (rate <= 0 || c <= 0 || order == 0)
        return 1;
    return pow(c * pow(rate * h, order + 1) / tol, 1.0 / order);
}

tb_status tb__auto_plan(tb_world *w, double h)
{
    return tb__auto_plan_why(w, h, NULL, 0);
}

tb_status tb__auto_plan_why(tb_world *w, double h, char *why, size_t size)
{
    rates r;
    tb_status st;
    int i, best = -1;
    size_t len = 0;
    double best_cost = INFINITY;
    if ((st = scene_rates(w, &r)) != TB_OK)
        return st;
    if (why && size) {
        why[0] = 0;
        if (r.unknown)
            len = (size_t)snprintf(why, size, "%s hide their rates, so only dopri5, which measures its "
                                              "error; ", w->joint_count ? "joints" : "callbacks");
        if (w->tracer_count && len < size)
            len += (size_t)snprintf(why + len, size - len, "tracers rule out the split methods; ");
        if (len < size)
            len += (size_t)snprintf(why + len, size - len, "estimated cost per step (rk4's = 4):");
    }
    for (i = 0; i < CANDIDATES; ++i) {
        const candidate *c = &candidates[i];
        const tb__method *m = tb__method_find(c->name);
        double n = 1, cost;
        if (m->split && w->tracer_count)
            continue;
        if (r.unknown && !m->adaptive)
            continue;
        if (!m->adaptive) {
            /* 0.8 of the tolerance: C is only the leading term (rk4 at
               1e-9 on the oscillator errs 8% past it without this margin,
               test_integrators.auto_meets_its_tolerance_per_step) */
            const double tol = 0.8 * w->tolerance * h;
            n = fmax(n, substeps_for(r.oscillation, h, c->c_oscillation, c->order, tol));
            n = fmax(n, substeps_for(r.decay, h, c->c_decay, c->order, tol));
            n = fmax(n, substeps_for(r.spin, h, c->c_spin, c->spin_order, tol));
            n = fmax(n, substeps_for(r.iso_spin, h, c->c_spin, c->iso_spin_order, tol));
            /* each substep within 0.9 of the method's damped limit */
            double limit = tb__limit_of(m, &r.modes, NULL);
            if (r.vortex > 0)
                limit = fmin(limit, m->damped_limit(0) / r.vortex);
            if (r.decay > 0)
                limit = fmin(limit, m->decay_limit / r.decay);
            n = fmax(n, h / (0.9 * limit));
        } else {
            /* dopri5 keeps each substep s within tol s: C (r s)^5 <= tol s
               gives s = (tol / (C r^5))^(1/4); how many it takes, for the
               comparison */
            const double rate = fmax(fmax(r.oscillation, r.decay), fmax(r.spin, r.iso_spin));
            if (rate > 0)
                n = fmax(n, h / pow(w->tolerance / (c->c_oscillation * pow(rate, c->order + 1)), 1.0 / c->order));
        }
        n = ceil(n * (1 - 1e-12));
        cost = n * (w->body_count > w->particle_count ? c->body_cost : c->cost);
        if (why && len < size)
            len += (size_t)snprintf(why + len, size - len, m->adaptive ? " %s about %.3g x %.3g substeps = %.3g,"
                                                                       : " %s %.3g x %.3g = %.3g,",
                                    c->name, cost / n, n, cost);
        if (cost < best_cost) {
            best_cost = cost;
            best = i;
            w->auto_substeps = m->adaptive ? 1 : (n > 1e6 ? 1000000 : (long)n);
        }
    }
    if (why && len > 0 && len < size && why[len - 1] == ',')
        why[len - 1] = 0;
    if (best < 0)
        return tb__fail(w, TB_ERR_ARGUMENT, "auto: no method can step this world");
    w->auto_method = tb__method_find(candidates[best].name);
    return TB_OK;
}
