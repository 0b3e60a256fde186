/* runs.c: the methods measured, and one run of a scene with one of them:
   the scene built in tumble or in ODE (build_ode() says how), advanced by
   fixed steps, its final state and its error against the truth. */
#include "workprecision.h"

#include <ode/ode.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* dDOUBLE is the Debian header default; the comparison is meaningless in
   single precision. A negative array size stops the build otherwise. */
typedef char dreal_is_double[sizeof(dReal) == sizeof(double) ? 1 : -1];

#define ODE_BOUND 1e6        /* ODE runs stop (unstable) once a position leaves 1e6 length scales */

/* In the order of the indices in workprecision.h (RK4, DOPRI5, AUTO, and
   ODE last). A count other than SERIES_COUNT conflicts with the header's
   declaration and stops the build. */
const series SERIES[] = {
    { "euler", "euler", 1, 0, 0 },
    { "symplectic_euler", "symplectic_euler", 1, 0, 0 },
    { "verlet", "verlet", 2, 0, 0 },
    { "rk4", "rk4", 4, 0, 0 },
    { "verlet_exact", "verlet_exact", 2, 0, 0 },
    { "implicit_euler", "implicit_euler", 1, 0, 0 },
    { "dopri5", "dopri5", 0, 1, 0 },
    { "auto", "auto", 0, 1, 0 },
    { "ode", "ODE dWorldStep", 1, 0, 1 },
};

/* One run of a scene in one engine. */
typedef struct sim {
    tb_world *world;
    dWorldID ode;
    dBodyID body[MAX_PARTICLES];            /* NULL for pinned particles */
    const dReal *x[MAX_PARTICLES], *v[MAX_PARTICLES]; /* ODE's own arrays, stable for a body's life */
    double force[3 * MAX_PARTICLES];
} sim;

/* The central attraction of the Kepler scene, over the whole array. */
static tb_status central_force(const tb_force_args *a, void *user)
{
    const double gm = *(const double *)user;
    size_t i;
    for (i = 0; i < a->count; ++i) {
        const double *x = a->positions + 3 * i, r2 = x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
        const double s = gm * a->masses[i] / (r2 * sqrt(r2));
        a->forces[3 * i] -= s * x[0];
        a->forces[3 * i + 1] -= s * x[1];
        a->forces[3 * i + 2] -= s * x[2];
    }
    return TB_OK;
}

/* A force that adds nothing and counts its calls: the force evaluations
   of a run, for dopri5, whose count depends on its controller. */
static tb_status count_evaluation(const tb_force_args *a, void *user)
{
    (void)a;
    ++*(long *)user;
    return TB_OK;
}

/* The scene in a tumble world stepping with `method` (adaptive ones at
   `tolerance`; 0: the world's default). `counter`, when not NULL, counts
   the force evaluations. A world that refuses the method or an object of
   the scene (tracers refuse the split methods) returns its status, with
   the reason in `message`, and leaves r->world NULL. */
static tb_status build_tumble(sim *r, const scene *s, const char *method, double tolerance, long *counter,
                              char *message, size_t size)
{
    tb_world_def def = tb_default_world_def();
    tb_particle_id id[MAX_PARTICLES];
    tb_status st = TB_OK;
    size_t i;
    def.integrator = method;
    def.tolerance = tolerance;
    memset(def.gravity, 0, sizeof def.gravity);
    if (s->kind == PARTICLES) {
        memcpy(def.gravity, s->ps.gravity, sizeof def.gravity);
        def.quadratic_drag = s->ps.quadratic_drag;
    }
    if (s->kind == PENDULUM)
        def.gravity[2] = -s->gravity;
    if ((st = tb_world_create(&def, &r->world, message, size)) != TB_OK)
        return st;
    if (s->kind == PARTICLES) {
        for (i = 0; i < s->ps.n && st == TB_OK; ++i) {
            tb_particle_def p = tb_default_particle_def();
            memcpy(p.position, s->ps.x0 + 3 * i, sizeof p.position);
            memcpy(p.velocity, s->ps.v0 + 3 * i, sizeof p.velocity);
            p.mass = s->ps.mass[i];
            p.pinned = s->ps.pinned[i];
            st = tb_world_add_particle(r->world, &p, &id[i]);
        }
        for (i = 0; i < s->ps.springs && st == TB_OK; ++i) {
            const spring_spec *c = &s->ps.spring[i];
            tb_spring_def d = tb_default_spring_def();
            d.a = id[c->a];
            if (c->b >= 0)
                d.b = id[c->b];
            memcpy(d.anchor, c->anchor, sizeof d.anchor);
            d.stiffness = c->k, d.damping = c->c, d.rest_length = c->rest;
            st = tb_world_add_spring(r->world, &d, NULL);
        }
        if (s->ps.gm > 0 && st == TB_OK)
            st = tb_world_add_force(r->world, central_force, (void *)&s->ps.gm, NULL);
    } else if (s->kind == TRACER) {
        const double centre[3] = { 0, 0, 0 };
        tb_tracer_def t = tb_default_tracer_def();
        memcpy(t.position, s->tracer_x0, sizeof t.position);
        st = tb_world_add_vortex_field(r->world, s->vortex, centre, NULL);
        if (st == TB_OK)
            st = tb_world_add_tracer(r->world, &t, NULL);
    } else if (s->kind == PENDULUM) {
        const double r3 = PENDULUM_RADIUS * PENDULUM_RADIUS * PENDULUM_RADIUS;
        tb_body_def b = tb_default_body_def();
        tb_joint_def j = tb_default_joint_def();
        st = tb_mass_sphere(PENDULUM_MASS / (4.0 / 3 * acos(-1.0) * r3), PENDULUM_RADIUS, &b.mass, NULL);
        b.position[0] = PENDULUM_LENGTH * sin(s->pendulum_start);
        b.position[2] = -PENDULUM_LENGTH * cos(s->pendulum_start);
        if (st == TB_OK)
            st = tb_world_add_body(r->world, &b, &j.a);
        j.type = TB_JOINT_HINGE, j.axis[0] = 0, j.axis[1] = 1, j.axis[2] = 0;
        if (st == TB_OK)
            st = tb_world_add_joint(r->world, &j, NULL);
    } else {
        tb_body_def b = tb_default_body_def();
        memcpy(b.mass.inertia, s->inertia, sizeof b.mass.inertia);
        memcpy(b.angular_velocity, s->omega0, sizeof b.angular_velocity);
        st = tb_world_add_body(r->world, &b, NULL);
    }
    if (counter && st == TB_OK)
        st = tb_world_add_force(r->world, count_evaluation, counter, NULL);
    if (st != TB_OK) {
        snprintf(message, size, "%s", tb_world_message(r->world));
        tb_world_destroy(r->world);
        r->world = NULL;
    }
    return st;
}

/* The same scene as ODE bodies, as an ODE user would build it: gravity a
   world setting, every other force added with dBodyAddForce before each
   dWorldStep from the bodies' current state. Auto-disable off, no damping,
   the gyroscopic term on (ODE's default). Pinned particles are fixed points,
   not bodies. */
static void build_ode(sim *r, const scene *s)
{
    size_t i;
    r->ode = dWorldCreate();
    dWorldSetAutoDisableFlag(r->ode, 0);
    dWorldSetGravity(r->ode, 0, 0, 0);
    if (s->kind == PARTICLES) {
        dWorldSetGravity(r->ode, s->ps.gravity[0], s->ps.gravity[1], s->ps.gravity[2]);
        for (i = 0; i < s->ps.n; ++i) {
            const double *x = s->ps.x0 + 3 * i, *v = s->ps.v0 + 3 * i;
            dMass m;
            r->body[i] = NULL;
            if (s->ps.pinned[i])
                continue;
            r->body[i] = dBodyCreate(r->ode);
            dMassSetSphereTotal(&m, s->ps.mass[i], 0.01);
            dBodySetMass(r->body[i], &m);
            dBodySetPosition(r->body[i], x[0], x[1], x[2]);
            dBodySetLinearVel(r->body[i], v[0], v[1], v[2]);
            dBodySetAutoDisableFlag(r->body[i], 0);
            r->x[i] = dBodyGetPosition(r->body[i]);
            r->v[i] = dBodyGetLinearVel(r->body[i]);
        }
    } else if (s->kind == PENDULUM) {
        dMass m;
        dJointID hinge;
        dWorldSetGravity(r->ode, 0, 0, -s->gravity);
        r->body[0] = dBodyCreate(r->ode);
        dMassSetSphereTotal(&m, PENDULUM_MASS, PENDULUM_RADIUS);
        dBodySetMass(r->body[0], &m);
        dBodySetPosition(r->body[0], PENDULUM_LENGTH * sin(s->pendulum_start), 0,
                         -PENDULUM_LENGTH * cos(s->pendulum_start));
        dBodySetAutoDisableFlag(r->body[0], 0);
        hinge = dJointCreateHinge(r->ode, 0);
        dJointAttach(hinge, r->body[0], 0);
        dJointSetHingeAnchor(hinge, 0, 0, 0);
        dJointSetHingeAxis(hinge, 0, 1, 0);
        r->x[0] = dBodyGetPosition(r->body[0]);
    } else {
        dMass m;
        r->body[0] = dBodyCreate(r->ode);
        dMassSetZero(&m);
        dMassSetParameters(&m, 1, 0, 0, 0, s->inertia[0], s->inertia[1], s->inertia[2], 0, 0, 0);
        dBodySetMass(r->body[0], &m);
        dBodySetAngularVel(r->body[0], s->omega0[0], s->omega0[1], s->omega0[2]);
        dBodySetAutoDisableFlag(r->body[0], 0);
    }
}

/* A scene in the engine of `m`; a refusal here ends the program, since
   refused() has kept such methods out of the sweeps. */
static void build(sim *r, const scene *s, const series *m, double tolerance, long *counter)
{
    char message[TB_MESSAGE_SIZE];
    memset(r, 0, sizeof *r);
    if (m->ode)
        build_ode(r, s);
    else if (build_tumble(r, s, m->name, tolerance, counter, message, sizeof message) != TB_OK) {
        fprintf(stderr, "bench_workprecision: %s with %s: %s\n", s->name, m->name, message);
        exit(EXIT_FAILURE);
    }
}

/* Whether the scene's world refuses method `m` (the reason in `message`). */
int refused(const scene *s, const series *m, char *message, size_t size)
{
    sim r;
    if (m->ode) {
        if (s->ode)
            return 0;
        snprintf(message, size, "ODE has no massless tracers");
        return 1;
    }
    memset(&r, 0, sizeof r);
    if (build_tumble(&r, s, m->name, 0, NULL, message, size) != TB_OK)
        return 1;
    tb_world_destroy(r.world);
    return 0;
}

static void release(sim *r)
{
    if (r->world)
        tb_world_destroy(r->world);
    if (r->ode)
        dWorldDestroy(r->ode);
}

/* Forces on the ODE bodies from springs, drag and the central attraction.
   Returns 0 when the state is no longer finite or has left ODE_BOUND
   scales: ODE asserts (and aborts) on some non-finite input, so a run that
   blows up is stopped here and counted unstable. */
static int ode_forces(sim *r, const scene *s)
{
    static const double zero[3] = { 0, 0, 0 };
    const particle_system *p = &s->ps;
    const double bound = ODE_BOUND * s->scale;
    size_t i, k;
    memset(r->force, 0, 3 * p->n * sizeof(double));
    for (i = 0; i < p->springs; ++i) {
        const spring_spec *c = &p->spring[i];
        const double *xa = r->x[c->a], *va = r->v[c->a];
        const double *xb = c->b < 0 ? c->anchor : r->body[c->b] ? r->x[c->b] : p->x0 + 3 * c->b;
        const double *vb = c->b < 0 || !r->body[c->b] ? zero : r->v[c->b];
        double d[3], len, mag;
        if (!r->body[c->a]) { /* tumble's springs start at a; a pinned a only pulls b */
            xa = p->x0 + 3 * c->a;
            va = zero;
        }
        for (k = 0; k < 3; ++k)
            d[k] = xa[k] - xb[k];
        len = norm3(d);
        if (len == 0)
            continue;
        mag = c->k * (len - c->rest) + c->c * ((va[0] - vb[0]) * d[0] + (va[1] - vb[1]) * d[1] +
                                               (va[2] - vb[2]) * d[2]) / len;
        for (k = 0; k < 3; ++k) {
            r->force[3 * c->a + k] -= mag * d[k] / len;
            if (c->b >= 0)
                r->force[3 * c->b + k] += mag * d[k] / len;
        }
    }
    for (i = 0; i < p->n; ++i) {
        const double *x = r->x[i], *v = r->v[i];
        double *f = r->force + 3 * i;
        if (!r->body[i])
            continue;
        if (p->quadratic_drag > 0) {
            const double c = p->quadratic_drag * norm3(v);
            for (k = 0; k < 3; ++k)
                f[k] -= c * v[k];
        }
        if (p->gm > 0) {
            const double r2 = x[0] * x[0] + x[1] * x[1] + x[2] * x[2], c = p->gm * p->mass[i] / (r2 * sqrt(r2));
            for (k = 0; k < 3; ++k)
                f[k] -= c * x[k];
        }
        if (!(isfinite(f[0]) && isfinite(f[1]) && isfinite(f[2]) && fabs(x[0]) < bound && fabs(x[1]) < bound &&
              fabs(x[2]) < bound))
            return 0;
        dBodyAddForce(r->body[i], f[0], f[1], f[2]);
    }
    return 1;
}

/* Step n times by h; returns the steps done (fewer when tumble refused a
   step or ODE's run was stopped). This is what the clock measures. */
static long advance(sim *r, const scene *s, double h, long n)
{
    long i;
    if (r->world) {
        for (i = 0; i < n; ++i)
            if (tb_world_step(r->world, h) != TB_OK)
                return i;
        return n;
    }
    for (i = 0; i < n; ++i) {
        if (s->kind == PARTICLES) {
            if (!ode_forces(r, s))
                return i;
        } else if (s->kind == PENDULUM) {
            const dReal *x = r->x[0];
            if (!(isfinite(x[0]) && isfinite(x[1]) && isfinite(x[2]) && norm3(x) < ODE_BOUND * s->scale))
                return i;
        } else {
            const dReal *w = dBodyGetAngularVel(r->body[0]);
            if (!(isfinite(w[0]) && isfinite(w[1]) && isfinite(w[2])))
                return i;
        }
        if (!dWorldStep(r->ode, h))
            return i;
    }
    return n;
}

/* The final state: 3 n positions (the pendulum's sphere's), or the body's
   orientation (w, x, y, z). */
static void final_state(const sim *r, const scene *s, double *out)
{
    size_t i;
    if (r->world) {
        if (s->kind == PARTICLES)
            memcpy(out, tb_world_particle_positions(r->world), 3 * s->ps.n * sizeof(double));
        else if (s->kind == TRACER)
            memcpy(out, tb_world_tracer_positions(r->world), 3 * sizeof(double));
        else if (s->kind == PENDULUM)
            memcpy(out, tb_world_body_positions(r->world), 3 * sizeof(double));
        else
            memcpy(out, tb_world_body_orientations(r->world), 4 * sizeof(double));
        return;
    }
    if (s->kind == PARTICLES) {
        for (i = 0; i < s->ps.n; ++i)
            memcpy(out + 3 * i, r->body[i] ? r->x[i] : s->ps.x0 + 3 * i, 3 * sizeof(double));
    } else if (s->kind == PENDULUM) {
        memcpy(out, r->x[0], 3 * sizeof(double));
    } else {
        const dReal *q = dBodyGetQuaternion(r->body[0]);
        for (i = 0; i < 4; ++i)
            out[i] = q[i];
    }
}

/* The error measure of a final state against a truth: the largest position
   error of a moving particle (or the tracer) per length scale, or the
   orientation angle. NaN when the state is not finite. */
double error_of(const scene *s, const double *state, const double *truth)
{
    double worst = 0;
    size_t i, n = s->kind == PARTICLES ? s->ps.n : 1;
    if (s->kind == BODY) {
        double e = angle_between(state, truth);
        return isfinite(state[0] + state[1] + state[2] + state[3]) ? e : NAN;
    }
    for (i = 0; i < n; ++i) {
        const double *a = state + 3 * i, *b = truth + 3 * i;
        const double d[3] = { a[0] - b[0], a[1] - b[1], a[2] - b[2] };
        const double e = norm3(d) / s->scale;
        if (s->kind == PARTICLES && s->ps.pinned[i])
            continue;
        if (!isfinite(e))
            return NAN;
        worst = fmax(worst, e);
    }
    return worst;
}

/* One run: build (not timed), step (timed), final state, free. `plan`
   (PLAN_SIZE bytes) and `substeps`, when not NULL, get what "auto" chose
   (its plan is made in the first step, so the clock includes it once). */
double timed_run(const scene *s, const series *m, double h, long n, double tolerance, long *done, double *state,
                 char *plan, long *substeps)
{
    sim r;
    double t0, t;
    build(&r, s, m, tolerance, NULL);
    t0 = seconds();
    *done = advance(&r, s, h, n);
    t = seconds() - t0;
    if (state)
        final_state(&r, s, state);
    if (plan) {
        const char *name = r.world ? tb_world_auto_choice(r.world, substeps) : NULL;
        snprintf(plan, PLAN_SIZE, "%s", name ? name : "");
    }
    release(&r);
    return t;
}

/* Force evaluations per simulated second of a run of dopri5, counted
   (rejected substeps included). Untimed. */
double counted_evaluations(const scene *s, double h, long n, double tolerance)
{
    sim r;
    long count = 0, done;
    build(&r, s, &SERIES[DOPRI5], tolerance, &count);
    done = advance(&r, s, h, n);
    release(&r);
    return done > 0 ? (double)count / (h * (double)done) : NAN;
}

/* The advisor's stability limit (s) of method `m` on the scene as built,
   for the scene's coarsest step: damping counted (tb_world_advise);
   INFINITY when nothing limits it or the method is adaptive or ODE's, NAN
   when the world refuses the method. */
double advised_limit(const scene *s, const series *m)
{
    sim r;
    tb_advice advice;
    char message[TB_MESSAGE_SIZE];
    double limit = NAN;
    if (m->adaptive || m->ode)
        return INFINITY;
    memset(&r, 0, sizeof r);
    if (build_tumble(&r, s, m->name, 0, NULL, message, sizeof message) != TB_OK)
        return NAN;
    if (tb_world_advise(r.world, s->duration / (double)s->coarse, &advice) == TB_OK)
        limit = advice.limit;
    tb_world_destroy(r.world);
    return limit;
}
