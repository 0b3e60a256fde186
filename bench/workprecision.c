/* workprecision.c: how much accuracy each integrator buys for its cost, on
   reference scenes with a known truth, beside ODE's dWorldStep.

   For every scene, every applicable fixed-step method runs over a geometric
   sweep of step sizes h = T / N (N doubling from the scene's coarsest N0, so
   every run ends exactly at T). The adaptive methods ("dopri5", "auto") run
   instead over a sweep of the world tolerance, 1e-2 down to 1e-12 by
   factors of sqrt 10, at one fixed outer step H = T / N0: the coarsest step
   of the fixed sweeps. That outer step is the one fixed-step runs can
   never exceed, so an adaptive method there has the same freedom as they
   have and the comparison at equal error measures its controller or plan,
   not the outer step: a display frame of 1/60 s instead would put a floor
   of 60 steps per simulated second under the adaptive methods that the
   fixed sweeps do not have (Verlet is exact to rounding on the symmetric
   top at 2 steps/s), and on the stiff scenes N0 is finer than 1/60 s
   anyway. For each run it records:
   - error: the scene's error measure at t = T against the truth (closed
     form, or a converged reference computed here and checked by halving);
   - seconds_per_sim_second: median wall time of the stepping alone (world
     built and freed outside the clock) divided by T. The first run of a
     point gives its error and warms up; then 9, 5 or 3 timing samples
     (fewer for longer runs), each repeating a short run until it holds 2 ms
     of stepping. Samples are taken in rounds over all points of a scene,
     so a burst of noise from the machine spreads over many points instead
     of landing on every sample of one;
   - evaluations_per_sim_second: force evaluations per simulated second
     (euler 1, symplectic_euler 1, verlet 2, verlet_exact 2, rk4 4,
     implicit_euler 1 plus its linear solve, per step; dWorldStep 1).
     dopri5's are counted, rejected substeps included, by a force callback
     that adds nothing, in a separate untimed run (the callback leaves its
     trajectory bit for bit as it was); auto's follow from its plan
     (tb_world_auto_choice), or are counted as dopri5's when it chose that;
   - stable: 0 when the state went non-finite, the error exceeds 1, or a
     step was refused (tumble) or stopped by the run's guard (ODE). Such
     runs are kept and drawn, not dropped: where a method fails is part of
     the chart.

   A fixed-step series stops, once it has MIN_POINTS points, when its error
   is below the floor (1e-12, where rounding takes over, or ten times a
   converged reference's own uncertainty); and in any case when the next
   run would take more than RUN_CAP seconds, or after MAX_POINTS points. A
   tolerance sweep stops below the floor once it has passed tolerance 1e-9,
   or at RUN_CAP.

   Methods a scene's world refuses (the split methods, implicit_euler among
   them, on the tracer, which has no velocity to kick) are left out, with
   the world's reason printed.

   Output (the directory is the first argument, default bench/out):
   - workprecision.csv: scene, method, h, error, seconds_per_sim_second,
     evaluations_per_sim_second, stable, tolerance (0 for fixed steps),
     plan (what auto chose: method x substeps per outer step);
   - workprecision_meta.gp: titles, axis labels and legend entries with the
     fitted orders, loaded by bench/workprecision.gp, which draws the charts;
   - on stdout, per scene and per error level 1e-2 ... 1e-10: tumble's
     cheapest fixed-step method and its cost, ODE's cost, and their ratio
     (costs interpolated along each method's curve in log-log); then, per
     scene and tolerance 1e-3, 1e-6 and 1e-9, each adaptive run's error and
     cost against the cheapest fixed-step method at the error it achieved,
     and whether it is within ADAPTIVE_TARGET times that cost (the issue's
     target, counted on the smooth scenes: all but the stiff chain and
     cloth, whose lines are printed but not counted).

   Errors are dimensionless: positions are divided by the scene's length
   scale (stated per scene), orientations are angles in radians.

   The scenes are the Lua scripts of scenes/reference/ built in C (same
   numbers; the scripts document each truth). ODE builds every scene but
   the tracer (ODE has no massless points moved by a field): gravity as its
   world setting, every other force added with dBodyAddForce before each
   dWorldStep, as an ODE user would. It takes about a minute and a half. */
#define _POSIX_C_SOURCE 200809L
#define BENCH_NAME "bench_workprecision"

#include "bench.h"
#include "tumble.h"

#include <ode/ode.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* dDOUBLE is the Debian header default; the comparison is meaningless in
   single precision. A negative array size stops the build otherwise. */
typedef char dreal_is_double[sizeof(dReal) == sizeof(double) ? 1 : -1];

#define MIN_POINTS 8
#define MAX_POINTS 16
#define TOLERANCES 21        /* 1e-2 ... 1e-12 by factors of sqrt 10 */
#define SLOTS 21             /* points a curve holds: max(MAX_POINTS, TOLERANCES) */
#define ADAPTIVE_TARGET 2.0  /* the issue: adaptive cost <= 2x the best fixed-step cost at its error */
#define RUN_CAP 0.4          /* s: no run in a sweep takes longer (keeps the whole under ~3 min) */
#define FLOOR 1e-12          /* below this, errors are rounding, not method */
#define SAMPLE_SECONDS 2e-3  /* a timing sample repeats short runs until it has this much stepping */
#define ODE_BOUND 1e6        /* ODE runs stop (unstable) once a position leaves 1e6 length scales */
#define MAX_PARTICLES 64
#define PLAN_SIZE 16         /* bytes for the name of the method auto chose */

/* The rotation by `angle` about the unit `axis`. */
static void qrot(const double axis[3], double angle, double q[4])
{
    const double s = sin(angle / 2);
    q[0] = cos(angle / 2), q[1] = s * axis[0], q[2] = s * axis[1], q[3] = s * axis[2];
}

/* ------------------------------------------------------------ scenes -- */

enum kind { PARTICLES, TRACER, BODY };

typedef struct spring_spec {
    int a, b;            /* particle indices; b < 0: tied to `anchor` */
    double anchor[3];    /* m */
    double k, c, rest;   /* N/m, N s/m, m */
} spring_spec;

/* Everything a particle scene holds, in one description that builds both
   the tumble world and the ODE world, so the two engines see one scene. */
typedef struct particle_system {
    size_t n;
    double x0[3 * MAX_PARTICLES], v0[3 * MAX_PARTICLES], mass[MAX_PARTICLES]; /* m, m/s, kg */
    int pinned[MAX_PARTICLES];
    size_t springs;
    spring_spec *spring;
    double gravity[3];       /* m/s^2 */
    double quadratic_drag;   /* N s^2/m^2 */
    double gm;               /* m^3/s^2: > 0 adds -gm m x / |x|^3 towards the origin (a force callback) */
} particle_system;

typedef struct scene {
    const char *name;        /* the CSV's and the charts' key */
    const char *title;       /* chart title */
    const char *short_title; /* panel title in the overview */
    const char *error_label; /* chart y label */
    const char *truth;       /* how the truth is known, printed */
    enum kind kind;
    double duration;         /* s */
    long coarse;             /* N0: steps of the coarsest run */
    long reference_steps;    /* > 0: converged reference by rk4 at this many steps */
    int ode;                 /* the scene can be built in ODE */
    int stiff;               /* stiff springs: not in the adaptive target (it is about smooth scenes) */
    double scale;            /* m: position errors are divided by it */
    particle_system ps;      /* PARTICLES */
    double tracer_x0[3];     /* TRACER: m */
    double vortex[3];        /* TRACER: rad/s, about the origin */
    double inertia[3];       /* BODY: kg m^2, principal; 1 kg, q0 = identity, at rest, no gravity */
    double omega0[3];        /* BODY: rad/s, body frame = world frame at t = 0 */
    double final[3 * MAX_PARTICLES]; /* the truth at t = T: positions, or a quaternion */
    double reference_gap;    /* converged references: error measure between N and N/2 */
} scene;

static void spring(particle_system *p, int a, int b, const double anchor[3], double k, double c, double rest)
{
    spring_spec *s;
    p->spring = realloc(p->spring, (p->springs + 1) * sizeof *p->spring);
    if (!p->spring) {
        fprintf(stderr, "bench_workprecision: out of memory\n");
        exit(EXIT_FAILURE);
    }
    s = &p->spring[p->springs++];
    s->a = a, s->b = b, s->k = k, s->c = c, s->rest = rest;
    memcpy(s->anchor, anchor ? anchor : (const double[3]){ 0, 0, 0 }, sizeof s->anchor);
}

static size_t particle(particle_system *p, double x, double y, double z, double mass)
{
    const size_t i = p->n++;
    if (i >= MAX_PARTICLES) {
        fprintf(stderr, "bench_workprecision: more than %d particles\n", MAX_PARTICLES);
        exit(EXIT_FAILURE);
    }
    p->x0[3 * i] = x, p->x0[3 * i + 1] = y, p->x0[3 * i + 2] = z;
    p->mass[i] = mass;
    return i;
}

/* The hanging oscillator of scenes/oscillator.lua: m = 0.5 kg on k = 50 N/m
   (w = 10 rad/s) with rest length 1 m from an anchor at the origin, pulled
   A = 0.2 m below equilibrium. With damping c the motion about the
   equilibrium z_eq = -(1 + m g / k) is u(t) = e^(-z w t) (A cos(wd t) +
   z w A / wd sin(wd t)), wd = w sqrt(1 - z^2), z = c / (2 sqrt(k m)). */
#define OSC_K 50.0
#define OSC_M 0.5
#define OSC_A 0.2
static void oscillator(scene *s, double damping)
{
    const double g = 9.81, w = sqrt(OSC_K / OSC_M), zeta = damping / (2 * sqrt(OSC_K * OSC_M));
    const double wd = w * sqrt(1 - zeta * zeta), zeq = -(1 + OSC_M * g / OSC_K), T = s->duration;
    particle_system *p = &s->ps;
    particle(p, 0, 0, zeq - OSC_A, OSC_M);
    spring(p, 0, -1, NULL, OSC_K, damping, 1);
    p->gravity[2] = -g;
    s->kind = PARTICLES;
    s->ode = 1;
    s->scale = OSC_A;
    s->final[2] = zeq - exp(-zeta * w * T) * OSC_A * (cos(wd * T) + zeta * w / wd * sin(wd * T));
}

/* Kepler orbit, GM = 1 m^3/s^2, semi-major axis a = 1 m, eccentricity 0.5,
   from periapsis r_p = a (1 - e) = 0.5 m at v_p = sqrt(GM (1 + e) / r_p) =
   sqrt 3 m/s. Period 2 pi sqrt(a^3 / GM) = 2 pi s; after three whole
   periods the exact position is the start again. */
static void kepler(scene *s)
{
    particle_system *p = &s->ps;
    particle(p, 0.5, 0, 0, 1);
    p->v0[1] = sqrt(3.0);
    p->gm = 1;
    s->kind = PARTICLES;
    s->ode = 1;
    s->scale = 1;
    s->final[0] = 0.5;
}

/* A tracer 1 m from the axis of a rigid vortex turning once every 4 s:
   after 8 s (two turns) it is exactly where it started. */
static void vortex(scene *s)
{
    const double w = 2 * acos(-1.0) / 4;
    s->kind = TRACER;
    s->scale = 1;
    s->tracer_x0[0] = 1;
    s->vortex[2] = w;
    s->final[0] = cos(w * s->duration);
    s->final[1] = sin(w * s->duration);
}

/* A 1 kg ball dropped from rest through air with quadratic drag
   c = 0.1 N s^2/m^2: terminal speed vt = sqrt(m g / c) = 9.90 m/s, and
   z(t) = -(vt^2 / g) ln cosh(g t / vt). Errors are per metre fallen by T. */
static void projectile(scene *s)
{
    const double g = 9.81, m = 1, c = 0.1, vt = sqrt(m * g / c), T = s->duration;
    particle_system *p = &s->ps;
    particle(p, 0, 0, 0, m);
    p->gravity[2] = -g;
    p->quadratic_drag = c;
    s->kind = PARTICLES;
    s->ode = 1;
    s->final[2] = -(vt * vt / g) * log(cosh(g * T / vt));
    s->scale = -s->final[2];
}

/* The rope of scenes/rope.lua: 20 beads of 10 g, 5 cm apart, joined by
   springs k = 2000 N/m (damping 0.05 N s/m), the first tied to an anchor
   2 m up, released horizontally under gravity. The fastest mode is near
   sqrt(4 k / m) = 894 rad/s: split methods need h < 2.2 ms, rk4 h < 3.2 ms. */
static void chain(scene *s)
{
    static const double anchor[3] = { 0, 0, 2 };
    particle_system *p = &s->ps;
    int i;
    for (i = 0; i < 20; ++i) {
        particle(p, 0.05 * (i + 1), 0, 2, 0.01);
        spring(p, i, i - 1, anchor, 2000, 0.05, 0.05);
    }
    p->gravity[2] = -9.81;
    s->kind = PARTICLES;
    s->ode = 1;
    s->scale = 1;
}

/* A small cloth: 8 x 8 particles, 0.5 m square, 0.1 kg, flat 1.5 m up,
   two corners pinned; structural (60 N/m), shear (20 N/m) and bend (5 N/m) springs with
   damping 0.02 N s/m, as in scenes/cloth.lua. Gershgorin bounds the fastest
   mode by sqrt(2 * 340 N/m / 1.56 g) = 660 rad/s. */
#define CLOTH_N 8
static void cloth(scene *s)
{
    /* row step, column step, stiffness (N/m): structural, shear, bend */
    static const int joins[6][3] = { { 0, 1, 60 }, { 1, 0, 60 }, { 1, 1, 20 },
                                     { 1, -1, 20 }, { 0, 2, 5 }, { 2, 0, 5 } };
    particle_system *p = &s->ps;
    const double size = 0.5, spacing = size / (CLOTH_N - 1), m = 0.1 / (CLOTH_N * CLOTH_N);
    int r, c, j;
    for (r = 0; r < CLOTH_N; ++r)
        for (c = 0; c < CLOTH_N; ++c) {
            const size_t i = particle(p, c * spacing, r * spacing, 1.5, m);
            p->pinned[i] = r == 0 && (c == 0 || c == CLOTH_N - 1);
        }
    for (r = 0; r < CLOTH_N; ++r)
        for (c = 0; c < CLOTH_N; ++c)
            for (j = 0; j < 6; ++j) {
                const int r2 = r + joins[j][0], c2 = c + joins[j][1];
                if (r2 < CLOTH_N && c2 >= 0 && c2 < CLOTH_N)
                    spring(p, r * CLOTH_N + c, r2 * CLOTH_N + c2, NULL, joins[j][2], 0.02,
                           spacing * sqrt((double)(joins[j][0] * joins[j][0] + joins[j][1] * joins[j][1])));
            }
    p->gravity[2] = -9.81;
    s->kind = PARTICLES;
    s->ode = 1;
    s->scale = size;
}

/* The intermediate-axis flip of NOTES.md: I = diag(1, 2, 3) kg m^2,
   w0 = (0.01, 5, 0.01) rad/s, 20 s (the truth: a converged reference). */
static void flip(scene *s)
{
    s->kind = BODY;
    s->ode = 1;
    s->inertia[0] = 1, s->inertia[1] = 2, s->inertia[2] = 3;
    s->omega0[0] = 0.01, s->omega0[1] = 5, s->omega0[2] = 0.01;
}

/* Torque-free symmetric top, I = diag(1, 1, 1.8) kg m^2, w0 = (0.6, -0.2, 4)
   rad/s. With L = I w0 fixed in the world and c = (1/I3 - 1/I1) L3, the
   exact orientation is q(t) = rot(L, |L| t / I1) q0 rot(e3, c t): in the
   body frame w turns about e3 at -c = (I3 - I1) / I1 w3 = 3.2 rad/s. */
static void top(scene *s)
{
    const double e3[3] = { 0, 0, 1 }, q0[4] = { 1, 0, 0, 0 }, T = s->duration;
    double L[3], axis[3], a[4], b[4], qa[4], l;
    int k;
    s->kind = BODY;
    s->ode = 1;
    s->inertia[0] = 1, s->inertia[1] = 1, s->inertia[2] = 1.8;
    s->omega0[0] = 0.6, s->omega0[1] = -0.2, s->omega0[2] = 4;
    for (k = 0; k < 3; ++k)
        L[k] = s->inertia[k] * s->omega0[k];
    l = norm3(L);
    for (k = 0; k < 3; ++k)
        axis[k] = L[k] / l;
    qrot(axis, l * T / s->inertia[0], a);
    qrot(e3, (1 / s->inertia[2] - 1 / s->inertia[0]) * L[2] * T, b);
    qmul(a, q0, qa);
    qmul(qa, b, s->final);
}

/* ------------------------------------------------------------ methods -- */

typedef struct series {
    const char *name;        /* tumble's integrator name, or "ode" */
    const char *label;       /* for the legend */
    int evaluations;         /* force evaluations per step (adaptive: counted per run) */
    int adaptive;            /* swept over the tolerance at the outer step T / N0, not over h */
    int ode;
} series;

/* ODE last: the ODE comparison and the legend strip rely on it. */
static const series SERIES[] = {
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
enum { SERIES_COUNT = sizeof SERIES / sizeof SERIES[0], RK4 = 3, DOPRI5 = 6, AUTO = 7, ODE = SERIES_COUNT - 1 };

/* --------------------------------------------------------- simulation -- */

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
static int refused(const scene *s, const series *m, char *message, size_t size)
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

/* The final state: 3 n positions, or the body's orientation (w, x, y, z). */
static void final_state(const sim *r, const scene *s, double *out)
{
    size_t i;
    if (r->world) {
        if (s->kind == PARTICLES)
            memcpy(out, tb_world_particle_positions(r->world), 3 * s->ps.n * sizeof(double));
        else if (s->kind == TRACER)
            memcpy(out, tb_world_tracer_positions(r->world), 3 * sizeof(double));
        else
            memcpy(out, tb_world_body_orientations(r->world), 4 * sizeof(double));
        return;
    }
    if (s->kind == PARTICLES) {
        for (i = 0; i < s->ps.n; ++i)
            memcpy(out + 3 * i, r->body[i] ? r->x[i] : s->ps.x0 + 3 * i, 3 * sizeof(double));
    } else {
        const dReal *q = dBodyGetQuaternion(r->body[0]);
        for (i = 0; i < 4; ++i)
            out[i] = q[i];
    }
}

/* The error measure of a final state against a truth: the largest position
   error of a moving particle (or the tracer) per length scale, or the
   orientation angle. NaN when the state is not finite. */
static double error_of(const scene *s, const double *state, const double *truth)
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
static double timed_run(const scene *s, const series *m, double h, long n, double tolerance, long *done,
                        double *state, char *plan, long *substeps)
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
static double counted_evaluations(const scene *s, double h, long n, double tolerance)
{
    sim r;
    long count = 0, done;
    build(&r, s, &SERIES[DOPRI5], tolerance, &count);
    done = advance(&r, s, h, n);
    release(&r);
    return done > 0 ? (double)count / (h * (double)done) : NAN;
}

/* --------------------------------------------------------- the sweeps -- */

#define MAX_SAMPLES 9

typedef struct point {
    long steps, done;                   /* asked for, and done before a refusal or a stop */
    double h, error, cost, evaluations; /* s, -, s per simulated s, per simulated s */
    double tolerance;                   /* adaptive methods; 0 for fixed steps */
    char plan[PLAN_SIZE];               /* auto: the method it chose */
    long substeps;                      /* auto: its substeps per outer step */
    int stable;
    double first;                       /* wall time of the first run, s */
    int want, count, repeat;            /* timing samples wanted and taken; runs per sample */
    double sample[MAX_SAMPLES];         /* s of stepping per run */
} point;

typedef struct curve {
    int used;                /* the method applies to the scene */
    int adaptive;            /* points are tolerances at one outer step, not steps */
    int count;
    point p[SLOTS];
    double order;            /* fitted slope of log error against log h; NaN: none (and
                                for tolerance sweeps, which have no h to fit against) */
    int at_floor;            /* there are stable points and all are below the floor */
} curve;

/* The error of one point, from its first run (which also warms caches and
   allocations and tells how long a run takes). Timing comes later, in
   take_sample(). Short runs get more samples (9, 5 or 3), and repeat within
   a sample until it holds SAMPLE_SECONDS of stepping; a long first run
   counts as one sample itself. */
static point first_run(const scene *s, const series *m, long n, double tolerance)
{
    const double h = s->duration / (double)n;
    double state[3 * MAX_PARTICLES];
    point p;
    memset(&p, 0, sizeof p);
    p.steps = n;
    p.h = h;
    p.tolerance = tolerance;
    p.first = timed_run(s, m, h, n, tolerance, &p.done, state, p.plan, &p.substeps);
    p.error = p.done == n ? error_of(s, state, s->final) : NAN;
    p.stable = p.done == n && isfinite(p.error) && p.error <= 1;
    if (!m->adaptive)
        p.evaluations = m->evaluations / h;
    else if (m == &SERIES[DOPRI5] || !strcmp(p.plan, "dopri5"))
        p.evaluations = counted_evaluations(s, h, n, tolerance);
    else {
        int k;
        p.evaluations = NAN;
        for (k = 0; k < SERIES_COUNT; ++k)
            if (!SERIES[k].adaptive && !strcmp(SERIES[k].name, p.plan))
                p.evaluations = (double)SERIES[k].evaluations * (double)p.substeps / h;
    }
    p.want = p.first >= 0.05 ? 3 : p.first >= 0.005 ? 5 : MAX_SAMPLES;
    if (p.first >= 0.05)
        p.sample[p.count++] = p.first;
    p.repeat = p.first >= SAMPLE_SECONDS ? 1 : (int)fmin(1e4, ceil(SAMPLE_SECONDS / fmax(p.first, 1e-7)));
    return p;
}

static void take_sample(const scene *s, const series *m, point *p)
{
    double sum = 0;
    long done;
    int k;
    for (k = 0; k < p->repeat; ++k)
        sum += timed_run(s, m, p->h, p->steps, p->tolerance, &done, NULL, NULL, NULL);
    p->sample[p->count++] = sum / p->repeat;
}

/* Cost = median sample / simulated time (of the steps done, for a run that
   stopped early). */
static void finish_point(point *p)
{
    double x[MAX_SAMPLES];
    memcpy(x, p->sample, sizeof x);
    p->cost = p->done > 0 ? median_of(x, p->count) / (p->h * (double)p->done) : NAN;
}

/* Least-squares slope of log error against log h over the asymptotic part
   of a curve: its finest FIT_POINTS stable points with errors between the
   floor (rounding, or the reference's own accuracy) and 1e-2 (0.3 when that
   leaves fewer than three), and before the error stops falling (a halved
   step gaining less than 2^0.5 below 1e-6: rounding has taken over, even if
   above the floor). The finest points, because coarse steps mix in
   higher-order terms: on the stiff chain symplectic Euler falls at order
   1.5 at first and settles to 1. */
#define FIT_POINTS 4
static void fit(curve *c, double floor_error)
{
    double hi = 1e-2;
    int pass, i, stable = 0, below = 0, end = c->count;
    c->order = NAN;
    for (i = 0; i < c->count; ++i)
        if (c->p[i].stable) {
            ++stable;
            below += c->p[i].error < floor_error;
        }
    c->at_floor = stable > 0 && below == stable;
    for (i = 1; i < c->count; ++i) {
        const point *p = &c->p[i], *q = &c->p[i - 1];
        if (p->stable && q->stable && p->error < 1e-6 &&
            log(q->error / p->error) < 0.5 * log(q->h / p->h)) {
            end = i;
            break;
        }
    }
    for (pass = 0; pass < 2; ++pass, hi = 0.3) {
        double sx = 0, sy = 0, sxx = 0, sxy = 0;
        int n = 0;
        for (i = end - 1; i >= 0 && n < FIT_POINTS; --i) {
            const point *p = &c->p[i];
            if (!p->stable || p->error < floor_error || p->error > hi)
                continue;
            sx += log(p->h), sy += log(p->error);
            sxx += log(p->h) * log(p->h), sxy += log(p->h) * log(p->error);
            ++n;
        }
        if (n >= 3 || (pass == 1 && n >= 2)) {
            c->order = (n * sxy - sx * sy) / (n * sxx - sx * sx);
            return;
        }
    }
}

/* The tolerance of point i of a tolerance sweep: 10^(-2 - i / 2). */
static double sweep_tolerance(int i)
{
    return pow(10, -2 - 0.5 * i);
}

/* A tolerance sweep at the outer step T / N0: on past 1e-9 (the last level
   the issue asks about) until the error is below the floor, or a run would
   take more than RUN_CAP (each tolerance costs about 10^(1/10) to 10^(1/4)
   times the last, so half of RUN_CAP is the limit, as for the fixed steps). */
static void sweep_tolerances(const scene *s, const series *m, double floor_error, curve *c)
{
    int i;
    for (i = 0; i < TOLERANCES; ++i) {
        const point *p;
        c->p[c->count++] = first_run(s, m, s->coarse, sweep_tolerance(i));
        p = &c->p[c->count - 1];
        if (sweep_tolerance(i) < 1.01e-9 && p->stable && p->error < floor_error)
            break;
        if (2 * p->first > RUN_CAP)
            break;
    }
}

static void sweep(const scene *s, const series *m, double floor_error, curve *c)
{
    long n = s->coarse;
    memset(c, 0, sizeof *c);
    c->used = 1;
    c->adaptive = m->adaptive;
    if (m->adaptive) {
        sweep_tolerances(s, m, floor_error, c);
        return;
    }
    while (c->count < MAX_POINTS) {
        const point *p;
        c->p[c->count++] = first_run(s, m, n, 0);
        p = &c->p[c->count - 1];
        if (c->count >= MIN_POINTS && p->stable && p->error < floor_error)
            break;
        if (2 * p->first > RUN_CAP)
            break;
        n *= 2;
    }
}

/* The timing samples of every point of a scene, in rounds: each round
   takes one sample of every point that still wants one, so a burst of
   noise from the machine (other processes, frequency changes) spreads over
   many points and methods instead of landing on all samples of one. */
static void timing(const scene *s, curve curves[SERIES_COUNT])
{
    const double t0 = seconds();
    int round, m, i;
    for (round = 0; round < MAX_SAMPLES; ++round)
        for (m = 0; m < SERIES_COUNT; ++m)
            for (i = 0; curves[m].used && i < curves[m].count; ++i)
                if (curves[m].p[i].count < curves[m].p[i].want)
                    take_sample(s, &SERIES[m], &curves[m].p[i]);
    for (m = 0; m < SERIES_COUNT; ++m)
        for (i = 0; curves[m].used && i < curves[m].count; ++i)
            finish_point(&curves[m].p[i]);
    fprintf(stderr, "  timing %.1f s\n", seconds() - t0);
}

/* The cost at which a curve first reaches `target` error, interpolated in
   log-log between the two measured points that straddle it. *bound is set
   when the method's coarsest stable point is already below the target
   (then the cost given is an upper bound). NaN: not reached in the sweep.
   `evaluations` selects that cost measure instead of wall time. */
static double cost_at(const curve *c, double target, int evaluations, int *bound)
{
    int i;
    *bound = 0;
    for (i = 0; i < c->count; ++i) {
        const point *p = &c->p[i], *q = i > 0 ? &c->p[i - 1] : NULL;
        const double cost = evaluations ? p->evaluations : p->cost;
        if (!p->stable || p->error > target)
            continue;
        if (!q || !q->stable || !(q->error > target)) {
            *bound = 1;
            return cost;
        }
        {
            const double qc = evaluations ? q->evaluations : q->cost;
            const double t = (log(target) - log(q->error)) / (log(p->error) - log(q->error));
            return exp(log(qc) + t * (log(cost) - log(qc)));
        }
    }
    return NAN;
}

/* Beyond a curve's finest stable point, along its fitted order: wall cost
   per simulated second goes as 1/h, the error as h^order. Only two decades
   of error past the last measurement, and NaN when there is no order to go
   by: further out it would be a guess. */
static double cost_extrapolated(const curve *c, double target)
{
    int i;
    if (!(c->order > 0.5))
        return NAN;
    for (i = c->count - 1; i >= 0; --i)
        if (c->p[i].stable && c->p[i].error > target)
            return c->p[i].error <= 100 * target ? c->p[i].cost * pow(c->p[i].error / target, 1 / c->order) : NAN;
    return NAN;
}

/* --------------------------------------------------------- references -- */

/* The truth of a scene without a closed form: tumble's rk4 at
   reference_steps, checked against rk4 at half as many steps. */
static void reference(scene *s)
{
    const long steps = s->reference_steps;
    const double t0 = seconds();
    double half[3 * MAX_PARTICLES], t;
    long done, done_half = 0;
    timed_run(s, &SERIES[RK4], s->duration / (double)steps, steps, 0, &done, s->final, NULL, NULL);
    if (done == steps)
        timed_run(s, &SERIES[RK4], s->duration / (double)(steps / 2), steps / 2, 0, &done_half, half, NULL, NULL);
    if (done != steps || done_half != steps / 2) {
        fprintf(stderr, "bench_workprecision: the %s reference run failed\n", s->name);
        exit(EXIT_FAILURE);
    }
    s->reference_gap = error_of(s, half, s->final);
    t = seconds() - t0;
    fprintf(stderr, "  reference %s: rk4 at %ld steps vs %ld: gap %.2e (%.1f s)\n", s->name, s->reference_steps,
            s->reference_steps / 2, s->reference_gap, t);
}

/* ------------------------------------------------------------ output -- */

static void print_header(void)
{
    printf("tumble work-precision: error at the final time against cost, beside ODE %s (%s)\n", TB_BENCH_ODE,
           dCheckConfiguration("ODE_double_precision") ? "double" : "NOT double");
    bench_print_build();
    bench_print_asserts();
    printf("cost      median wall time of the steps per simulated second (s/s); evaluations per simulated s\n"
           "          (euler 1, symplectic_euler 1, verlet 2, verlet_exact 2, rk4 4, implicit_euler 1 and a\n"
           "          linear solve, dWorldStep 1 per step; dopri5 counted; auto by its plan)\n"
           "          fixed-step methods sweep h = T/N0, T/2N0, ...; dopri5 and auto sweep the tolerance\n"
           "          1e-2 ... 1e-12 at the outer step h = T/N0 (the coarsest fixed step)\n"
           "          costs at an error level are interpolated in log-log along each method's curve;\n"
           "          '<=' marks a method already below the level at its coarsest stable step (an upper\n"
           "          bound); a ratio '~' compares two such runs, the cheapest stable ones; figures in\n"
           "          (~...) extrapolate ODE beyond its finest run along its fitted order (not measured)\n\n");
}

static int ensure_dir(const char *dir)
{
    if (mkdir(dir, 0777) == 0 || errno == EEXIST)
        return 1;
    fprintf(stderr, "bench_workprecision: cannot create '%s': %s\n", dir, strerror(errno));
    return 0;
}

static void write_csv(FILE *f, const scene *s, const curve curves[SERIES_COUNT])
{
    int m, i;
    for (m = 0; m < SERIES_COUNT; ++m)
        for (i = 0; curves[m].used && i < curves[m].count; ++i) {
            const point *p = &curves[m].p[i];
            fprintf(f, "%s,%s,%.17g,%.6e,%.6e,%.6e,%d,%.3g,", s->name, SERIES[m].name, p->h, p->error, p->cost,
                    p->evaluations, p->stable, p->tolerance);
            if (p->plan[0])
                fprintf(f, "%s x %ld", p->plan, p->substeps);
            fputc('\n', f);
        }
}

static int stable_points(const curve *c)
{
    int i, n = 0;
    for (i = 0; i < c->count; ++i)
        n += c->p[i].stable;
    return n;
}

/* name = 'text' as gnuplot reads it: a quote inside single quotes is
   doubled. */
static void gp_string(FILE *f, const char *prefix, const char *name, const char *text)
{
    fprintf(f, "%s_%s = '", prefix, name);
    for (; *text; ++text) {
        if (*text == '\'')
            fputc('\'', f);
        fputc(*text, f);
    }
    fputs("'\n", f);
}

/* Legends and labels for bench/workprecision.gp, one variable per string;
   gnuplot reads them back with value("name"). */
static void write_meta(FILE *f, const scene *s, const curve curves[SERIES_COUNT])
{
    int m;
    gp_string(f, "title", s->name, s->title);
    gp_string(f, "short", s->name, s->short_title);
    gp_string(f, "ylabel", s->name, s->error_label);
    fprintf(f, "methods_%s = '", s->name);
    for (m = 0; m < SERIES_COUNT; ++m)
        if (curves[m].used)
            fprintf(f, "%s%s", m ? " " : "", SERIES[m].name);
    fprintf(f, "'\n");
    for (m = 0; m < SERIES_COUNT; ++m) {
        const curve *c = &curves[m];
        if (!c->used)
            continue;
        if (c->adaptive) /* the slope against evaluations is no order when auto switches methods */
            fprintf(f, "key_%s_%s = '%s: tol sweep, h = %.3g s%s'\n", s->name, SERIES[m].name, SERIES[m].label,
                    s->duration / (double)s->coarse, stable_points(c) ? "" : " (no run with error <= 1)");
        else if (isfinite(c->order))
            fprintf(f, "key_%s_%s = '%s: order %.1f'\n", s->name, SERIES[m].name, SERIES[m].label, c->order);
        else if (c->at_floor)
            fprintf(f, "key_%s_%s = '%s: exact to rounding'\n", s->name, SERIES[m].name, SERIES[m].label);
        else if (!stable_points(c))
            fprintf(f, "key_%s_%s = '%s: no run with error <= 1'\n", s->name, SERIES[m].name, SERIES[m].label);
        else
            fprintf(f, "key_%s_%s = '%s: order n/a'\n", s->name, SERIES[m].name, SERIES[m].label);
    }
}

/* The cheapest fixed-step tumble method at `target` error: its index (-1:
   none reaches it within its measured points), cost and whether that cost
   is an upper bound (*bound, see cost_at). */
static int cheapest_fixed(const curve curves[SERIES_COUNT], double target, double *cost, int *bound)
{
    int m, b, best = -1;
    for (m = 0; m < SERIES_COUNT; ++m) {
        double c;
        if (!curves[m].used || SERIES[m].adaptive || SERIES[m].ode)
            continue;
        c = cost_at(&curves[m], target, 0, &b);
        if (isfinite(c) && (best < 0 || c < *cost))
            best = m, *cost = c, *bound = b;
    }
    return best;
}

/* The figures for one scene. Returns the number of error levels at
   which tumble's cheapest fixed-step method is not cheaper than ODE. */
static int print_figures(const scene *s, const curve curves[SERIES_COUNT], const char *refusals, char *summary,
                         size_t size)
{
    static const double levels[] = { 1e-2, 1e-4, 1e-6, 1e-8, 1e-10 };
    const curve *ode = curves[ODE].used ? &curves[ODE] : NULL;
    int l, m, losses = 0;
    printf("%s: %s\n", s->name, s->title);
    printf("  truth: %s\n", s->truth);
    if (refusals[0])
        printf("  left out: %s\n", refusals);
    printf("  fitted orders:");
    for (m = 0; m < SERIES_COUNT; ++m)
        if (curves[m].used && !curves[m].adaptive) {
            if (isfinite(curves[m].order))
                printf(" %s %.2f;", SERIES[m].name, curves[m].order);
            else
                printf(" %s %s;", SERIES[m].name,
                       curves[m].at_floor ? "rounding" : !stable_points(&curves[m]) ? "no stable run" : "n/a");
        }
    printf("\n");
    printf("  %-7s %-16s %12s %12s %14s %14s\n", "error", "cheapest fixed", "cost s/s", "evals/s", "ODE cost s/s",
           "ODE/tumble");
    for (l = 0; l < (int)(sizeof levels / sizeof levels[0]); ++l) {
        int best_bound = 0, ode_bound = 0, extrapolated = 0, b;
        double best_cost = NAN, ode_cost = NAN, evals = NAN;
        char cost_text[32], ode_text[48], ratio_text[48];
        const int best = cheapest_fixed(curves, levels[l], &best_cost, &best_bound);
        if (best >= 0)
            evals = cost_at(&curves[best], levels[l], 1, &b);
        if (ode) {
            ode_cost = cost_at(ode, levels[l], 0, &ode_bound);
            if (!isfinite(ode_cost)) {
                ode_cost = cost_extrapolated(ode, levels[l]);
                extrapolated = isfinite(ode_cost);
            }
        }
        if (best >= 0)
            snprintf(cost_text, sizeof cost_text, "%s%.3g", best_bound ? "<=" : "", best_cost);
        else
            snprintf(cost_text, sizeof cost_text, "-");
        if (!ode)
            snprintf(ode_text, sizeof ode_text, "(no ODE)");
        else if (isfinite(ode_cost))
            snprintf(ode_text, sizeof ode_text, "%s%.3g%s", extrapolated ? "(~" : ode_bound ? "<=" : "", ode_cost,
                     extrapolated ? ")" : "");
        else
            snprintf(ode_text, sizeof ode_text, "not reached");
        ratio_text[0] = 0;
        if (best >= 0 && ode && isfinite(ode_cost)) {
            const double ratio = ode_cost / best_cost;
            /* An upper bound on tumble's cost makes the ratio a lower bound,
               one on ODE's an upper bound; with both, it compares the two
               cheapest stable runs ("~"). */
            snprintf(ratio_text, sizeof ratio_text, "%s%.3g%s%s",
                     extrapolated ? "(~" : best_bound ? (ode_bound ? "~" : ">=") : (ode_bound ? "<=" : ""), ratio,
                     extrapolated ? ")" : "", ratio <= 1 ? "  NOT cheaper" : "");
            if (ratio <= 1) {
                size_t used = strlen(summary);
                snprintf(summary + used, size - used, "  %s at %.0e: %s %.3g s/s, ODE %.3g s/s%s (ratio %.3g)\n",
                         s->name, levels[l], SERIES[best].name, best_cost, ode_cost,
                         extrapolated ? " extrapolated" : "", ratio);
                ++losses;
            }
        } else if (best >= 0 && ode) {
            snprintf(ratio_text, sizeof ratio_text, "ODE not reached");
        }
        if (best >= 0)
            printf("  %-7.0e %-16s %12s %12.3g %14s %14s%s\n", levels[l], SERIES[best].name, cost_text, evals,
                   ode_text, ratio_text, levels[l] < 10 * s->reference_gap ? "  (below the reference's accuracy)" : "");
        else
            printf("  %-7.0e %-16s %12s %12s %14s\n", levels[l], "not reached", "-", "-", ode_text);
    }
    printf("\n");
    return losses;
}

/* The adaptive target, tallied over the smooth scenes: per method (auto,
   dopri5), lines met, NOT met, and without a fixed-step method to compare
   with (none reaches the error the adaptive run achieved). */
enum { MET, NOT_MET, NO_COMPARISON };
typedef struct tally {
    int count[2][3];
    char missed[8192];       /* the NOT met lines, for the summary */
} tally;

/* One adaptive run against the cheapest fixed-step method at the error it
   achieved; writes "<method>(plan): error E cost C s/s" into `run`, the
   fixed method and its cost into `fixed`, and the ratio into `ratio`.
   Returns MET, NOT_MET or NO_COMPARISON. */
static int judge(const scene *s, const curve curves[SERIES_COUNT], int a, int i, char *run, char *fixed,
                 char *ratio, size_t size)
{
    const curve *c = &curves[a];
    const point *p = i < c->count ? &c->p[i] : NULL;
    char plan[48] = "";
    double fixed_cost = NAN, r;
    int bound = 0, best;
    if (p && p->plan[0])
        snprintf(plan, sizeof plan, "(%s x %ld)", p->plan, p->substeps);
    if (!p) {
        snprintf(run, size, "%s: not run (RUN_CAP)", SERIES[a].name);
        snprintf(fixed, size, "-");
        snprintf(ratio, size, "%s -", SERIES[a].name);
        return NOT_MET;
    }
    if (!p->stable) {
        snprintf(run, size, "%s%s: FAILED (error %.2g%s)", SERIES[a].name, plan, p->error,
                 p->done < p->steps ? ", a step refused" : "");
        snprintf(fixed, size, "-");
        snprintf(ratio, size, "%s -", SERIES[a].name);
        return NOT_MET;
    }
    snprintf(run, size, "%s%s: error %.2g cost %.2g s/s%s", SERIES[a].name, plan, p->error, p->cost,
             p->error < 10 * s->reference_gap ? " (below the reference's accuracy)" : "");
    best = cheapest_fixed(curves, p->error, &fixed_cost, &bound);
    if (best < 0) {
        snprintf(fixed, size, "none reaches %.2g", p->error);
        snprintf(ratio, size, "%s n/a", SERIES[a].name);
        return NO_COMPARISON;
    }
    r = p->cost / fixed_cost;
    /* a bound on the fixed cost (already below that error at its coarsest
       stable step) makes the ratio a lower bound */
    snprintf(fixed, size, "%s %s%.2g", SERIES[best].name, bound ? "<=" : "", fixed_cost);
    snprintf(ratio, size, "%s %s%.2g", SERIES[a].name, bound ? ">=" : "", r);
    return r <= ADAPTIVE_TARGET ? MET : NOT_MET;
}

/* Per tolerance 1e-3, 1e-6 and 1e-9: auto and dopri5 against the cheapest
   fixed-step method at the error each achieved (interpolated along the
   fixed methods' measured curves, never extrapolated). Stiff scenes are
   printed but not counted. */
static void print_adaptive(const scene *s, const curve curves[SERIES_COUNT], tally *t)
{
    static const int levels[] = { 2, 8, 14 }; /* indices of 1e-3, 1e-6, 1e-9 in the sweep */
    static const char *const verdicts[] = { "met", "NOT met", "no fixed method to compare" };
    static const int methods[2] = { AUTO, DOPRI5 };
    int l, k;
    if (!curves[AUTO].used && !curves[DOPRI5].used)
        return;
    for (l = 0; l < (int)(sizeof levels / sizeof levels[0]); ++l) {
        char run[2][160], fixed[2][160], ratio[2][160]; /* one size: judge() gets one */
        int verdict[2];
        for (k = 0; k < 2; ++k)
            verdict[k] = judge(s, curves, methods[k], levels[l], run[k], fixed[k], ratio[k], sizeof run[k]);
        printf("adaptive  %s  tol %.0e  %s | %s | best fixed at those errors: %s, %s s/s | "
               "ratio %s %s (target <= %g): auto %s, dopri5 %s%s\n",
               s->name, sweep_tolerance(levels[l]), run[0], run[1], fixed[0], fixed[1], ratio[0], ratio[1],
               ADAPTIVE_TARGET, verdicts[verdict[0]], verdicts[verdict[1]], s->stiff ? "  [stiff scene: not counted]" : "");
        if (s->stiff)
            continue;
        for (k = 0; k < 2; ++k)
            ++t->count[k][verdict[k]];
        if (verdict[0] == NOT_MET || verdict[1] == NOT_MET) {
            size_t used = strlen(t->missed);
            snprintf(t->missed + used, sizeof t->missed - used, "  %s tol %.0e:%s%s\n", s->name,
                     sweep_tolerance(levels[l]), verdict[0] == NOT_MET ? " auto" : "",
                     verdict[1] == NOT_MET ? " dopri5" : "");
        }
    }
    /* A plan that the tolerance does not move (a rate it cannot see, such
       as quadratic drag from rest) can pass the cost target while ignoring
       the tolerance: say so when the error stays put from 1e-3 to 1e-9 and
       is far above what local errors of 1e-9 per outer step add up to (the
       factor 1000 covers the different norms of error and tolerance). */
    if (curves[AUTO].count > levels[2]) {
        const point *loose = &curves[AUTO].p[levels[0]], *tight = &curves[AUTO].p[levels[2]];
        if (loose->stable && tight->stable && tight->error > 0.5 * loose->error &&
            tight->error > 1000 * (double)tight->steps * tight->tolerance)
            printf("note      %s: auto ignores the tolerance here: error %.2g at 1e-3 (%s x %ld) and %.2g at "
                   "1e-9 (%s x %ld), over %ld outer steps\n", s->name, loose->error, loose->plan, loose->substeps,
                   tight->error, tight->plan, tight->substeps, tight->steps);
    }
    printf("\n");
}

/* ---------------------------------------------------------------- main -- */

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "bench/out";
    scene scenes[9];
    curve *curves;
    char path[4096], summary[4096] = "";
    static tally adaptive; /* zeroed; large */
    FILE *csv, *meta;
    int i, m, count = 0, losses = 0;
    double t0 = seconds();

    memset(scenes, 0, sizeof scenes);
    scenes[count].name = "oscillator";
    scenes[count].short_title = "harmonic oscillator";
    scenes[count].title = "harmonic oscillator: w = 10 rad/s, amplitude A = 0.2 m, 10 s";
    scenes[count].error_label = "position error / A at t = 10 s";
    scenes[count].truth = "closed form z(t) = z_eq - A cos(w t)";
    scenes[count].duration = 10, scenes[count].coarse = 40;
    oscillator(&scenes[count++], 0);

    scenes[count].name = "damped";
    scenes[count].short_title = "damped oscillator";
    scenes[count].title = "damped oscillator: w = 10 rad/s, damping ratio 0.05, A = 0.2 m, 4 s";
    scenes[count].error_label = "position error / A at t = 4 s";
    scenes[count].truth = "closed form (underdamped)";
    scenes[count].duration = 4, scenes[count].coarse = 16;
    oscillator(&scenes[count++], 0.1 * sqrt(OSC_K * OSC_M));

    scenes[count].name = "kepler";
    scenes[count].short_title = "Kepler orbit, e = 0.5";
    scenes[count].title = "Kepler orbit: eccentricity 0.5, a = 1 m, 3 periods from periapsis "
                          "(there symplectic Euler's O(h) error cancels)";
    scenes[count].error_label = "position error / a after 3 periods";
    scenes[count].truth = "closed form: after whole periods the orbit is back at periapsis";
    scenes[count].duration = 6 * acos(-1.0), scenes[count].coarse = 48;
    kepler(&scenes[count++]);

    scenes[count].name = "vortex";
    scenes[count].short_title = "tracer in a vortex";
    scenes[count].title = "tracer in a rigid vortex: 1 m from the axis, two turns in 8 s";
    scenes[count].error_label = "position error / radius at t = 8 s";
    scenes[count].truth = "closed form: a rotation by w t";
    scenes[count].duration = 8, scenes[count].coarse = 4;
    vortex(&scenes[count++]);

    scenes[count].name = "projectile";
    scenes[count].short_title = "fall with quadratic drag";
    scenes[count].title = "fall with quadratic drag: terminal speed 9.9 m/s, from rest, 3 s";
    scenes[count].error_label = "position error / distance fallen at t = 3 s";
    scenes[count].truth = "closed form z(t) = -(vt^2/g) ln cosh(g t / vt)";
    scenes[count].duration = 3, scenes[count].coarse = 3;
    projectile(&scenes[count++]);

    scenes[count].name = "chain";
    scenes[count].short_title = "stiff chain, 20 beads";
    scenes[count].title = "stiff chain: 20 beads, k = 2000 N/m, fastest mode ~894 rad/s, 1 s";
    scenes[count].error_label = "largest bead position error / 1 m at t = 1 s";
    scenes[count].truth = "converged reference: rk4 at h = 1/2^19 s";
    scenes[count].duration = 1, scenes[count].coarse = 250, scenes[count].reference_steps = 1L << 19;
    scenes[count].stiff = 1;
    chain(&scenes[count++]);

    scenes[count].name = "cloth";
    scenes[count].short_title = "cloth patch, 8 x 8";
    scenes[count].title = "cloth patch: 8 x 8 particles, 0.5 m, 306 springs, two corners pinned, 1 s";
    scenes[count].error_label = "largest particle position error / 0.5 m at t = 1 s";
    scenes[count].truth = "converged reference: rk4 at h = 1/2^17 s";
    scenes[count].duration = 1, scenes[count].coarse = 200, scenes[count].reference_steps = 1L << 17;
    scenes[count].stiff = 1;
    cloth(&scenes[count++]);

    scenes[count].name = "flip";
    scenes[count].short_title = "intermediate-axis flip";
    scenes[count].title = "intermediate-axis flip: I = diag(1, 2, 3) kg m^2, w0 = (0.01, 5, 0.01) rad/s, 20 s";
    scenes[count].error_label = "orientation error at t = 20 s (rad)";
    scenes[count].truth = "converged reference: rk4 at h = 20/2^18 s";
    scenes[count].duration = 20, scenes[count].coarse = 40, scenes[count].reference_steps = 1L << 18;
    flip(&scenes[count++]);

    scenes[count].name = "top";
    scenes[count].short_title = "torque-free symmetric top";
    scenes[count].title = "torque-free symmetric top: I = diag(1, 1, 1.8) kg m^2, w0 = (0.6, -0.2, 4) rad/s, 10 s";
    scenes[count].error_label = "orientation error at t = 10 s (rad)";
    scenes[count].truth = "closed form: q(t) = rot(L, |L| t / I1) q0 rot(e3, (1/I3 - 1/I1) L3 t)";
    scenes[count].duration = 10, scenes[count].coarse = 20;
    top(&scenes[count++]);

    if (!ensure_dir(dir))
        return EXIT_FAILURE;
    snprintf(path, sizeof path, "%s/workprecision.csv", dir);
    csv = fopen(path, "w");
    snprintf(path, sizeof path, "%s/workprecision_meta.gp", dir);
    meta = fopen(path, "w");
    if (!csv || !meta) {
        fprintf(stderr, "bench_workprecision: cannot write into '%s'\n", dir);
        return EXIT_FAILURE;
    }
    fprintf(csv, "scene,method,h,error,seconds_per_sim_second,evaluations_per_sim_second,stable,tolerance,plan\n");
    fprintf(meta, "# written by bench_workprecision: titles, labels and legends for bench/workprecision.gp\n");
    fprintf(meta, "scenes = '");
    for (i = 0; i < count; ++i)
        fprintf(meta, "%s%s", i ? " " : "", scenes[i].name);
    fprintf(meta, "'\n");

    print_header();
    dInitODE2(0);
    /* Integrators the library has beyond those measured here. */
    for (i = 0; tb_integrator_name(i); ++i) {
        for (m = 0; m < ODE && strcmp(tb_integrator_name(i), SERIES[m].name); ++m)
            ;
        if (m == ODE)
            printf("note      integrator '%s' is not in this benchmark yet\n\n", tb_integrator_name(i));
    }
    curves = xmalloc((size_t)count * SERIES_COUNT * sizeof *curves);
    for (i = 0; i < count; ++i) {
        scene *s = &scenes[i];
        curve *c = curves + (size_t)i * SERIES_COUNT;
        double floor_error = FLOOR;
        char refusals[1024] = "", reason[TB_MESSAGE_SIZE] = "", message[TB_MESSAGE_SIZE];
        fprintf(stderr, "%s\n", s->name);
        if (s->reference_steps > 0) {
            reference(s);
            floor_error = fmax(FLOOR, 10 * s->reference_gap);
        }
        for (m = 0; m < SERIES_COUNT; ++m) {
            const double t = seconds();
            memset(&c[m], 0, sizeof c[m]);
            if (refused(s, &SERIES[m], message, sizeof message)) {
                /* one reason is enough: the split methods fail alike */
                const size_t used = strlen(refusals);
                if (SERIES[m].ode)
                    snprintf(refusals + used, sizeof refusals - used, "%s%s (%s)", used ? "; " : "",
                             SERIES[m].name, message);
                else
                    snprintf(refusals + used, sizeof refusals - used, "%s%s", used ? ", " : "", SERIES[m].name);
                if (!reason[0] && !SERIES[m].ode)
                    snprintf(reason, sizeof reason, "%s", message);
                continue;
            }
            sweep(s, &SERIES[m], floor_error, &c[m]);
            if (!SERIES[m].adaptive)
                fit(&c[m], floor_error);
            else
                c[m].order = NAN;
            if (SERIES[m].adaptive)
                fprintf(stderr, "  %-16s %2d points, tolerance down to %.0e, %.1f s\n", SERIES[m].name, c[m].count,
                        c[m].p[c[m].count - 1].tolerance, seconds() - t);
            else
                fprintf(stderr, "  %-16s %2d points, N up to %ld, %.1f s\n", SERIES[m].name, c[m].count,
                        c[m].p[c[m].count - 1].steps, seconds() - t);
        }
        timing(s, c);
        write_csv(csv, s, c);
        write_meta(meta, s, c);
        if (reason[0]) {
            const size_t used = strlen(refusals);
            snprintf(refusals + used, sizeof refusals - used, "; tumble: %s", reason);
        }
        losses += print_figures(s, c, refusals, summary, sizeof summary);
        print_adaptive(s, c, &adaptive);
    }
    dCloseODE();

    if (losses)
        printf("not cheaper than ODE (tumble's cheapest fixed-step method against dWorldStep):\n%s", summary);
    else
        printf("tumble's cheapest fixed-step method is cheaper than ODE at every error level that both reach\n");
    printf("\nadaptive target: cost <= %g x the cheapest fixed-step method at the error reached, tolerances\n"
           "1e-3, 1e-6 and 1e-9, smooth scenes (all but chain and cloth):\n", ADAPTIVE_TARGET);
    for (m = 0; m < 2; ++m)
        printf("  %-6s met %d, NOT met %d, no fixed method reaching its error %d\n", m ? "dopri5" : "auto",
               adaptive.count[m][MET], adaptive.count[m][NOT_MET], adaptive.count[m][NO_COMPARISON]);
    if (adaptive.missed[0])
        printf("NOT met:\n%s", adaptive.missed);
    printf("\nwrote %s/workprecision.csv and %s/workprecision_meta.gp in %.0f s\n", dir, dir, seconds() - t0);
    for (i = 0; i < count; ++i)
        free(scenes[i].ps.spring);
    free(curves);
    if (ferror(csv) | fclose(csv) | ferror(meta) | fclose(meta)) {
        fprintf(stderr, "bench_workprecision: error writing into '%s'\n", dir);
        return EXIT_FAILURE;
    }
    return 0;
}
