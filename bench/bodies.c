/* bodies.c: rigid-body accuracy and throughput, tumble beside ODE.

   Part 1, the intermediate-axis flip of docs/notes.md: I = diag(1, 2, 3) kg m^2,
   w0 = (0.01, 5, 0.01) rad/s in the body frame, q0 = identity, no gravity,
   h = 1/60 s, 20 s. One line per tumble integrator and for ODE's
   dWorldStep (gyroscopic term on, its default):
   - |L| drift: worst relative change of |L| over the run. tumble keeps the
     world L as its state (a torque-free step adds exact zeros to it); ODE's
     is |R I0 R^T w| from its angular velocity.
   - E drift: worst relative change of the kinetic energy over the run (a
     symplectic method's error oscillates: the worst, not the last, counts).
   - orientation: angle of q_ref^-1 q after 20 s, 2 atan2(|v|, |w|), against
     tumble's rk4 at h/128, whose gap to rk4 at h/64 is printed first.
   - ns per body-step over FLIP_BODIES copies of the body in one world (what
     a world's loop pays per body), and ns per step of a world holding the
     body alone (latency, with the world's fixed cost per step).
   Then the targets for tumble's best method (the smallest
   orientation error): |L| drift <= 1e-12, energy drift <= 1e-9,
   orientation <= 1e-6 rad at <= 50 ns per body-step.

   Part 2, throughput: 10^3 and 10^5 free bodies under gravity, each thrown
   with a spin, as spheres (isotropic: tumble skips the gyroscopic work) and
   as boxes (anisotropic), h = 1/60 s: ns per body-step for every tumble
   integrator and for dWorldStep on the same bodies in the same run, and the
   ratio ODE/tumble. Targets: "verlet" at least 20 times faster than ODE,
   "rk4" at least 5 times.

   Figures are medians over BENCH_REPEATS repeats of about
   BENCH_REPEAT_SECONDS each; the repeats of the cases of one table are
   interleaved, so noise from the machine falls on every case alike
   (measure() in bench.h, shared with bench/particles.c). */
#define _POSIX_C_SOURCE 200809L
#define BENCH_NAME "bench_bodies"

#include "bench.h"
#include "tumble.h"

#include <ode/ode.h>
#include <ode/version.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define H (1.0 / 60)           /* s, the step of both parts */
#define FLIP_STEPS 1200        /* 20 s */
#define FLIP_BODIES 1024
#define SPIN 5.0               /* rad/s, largest spin per axis in part 2 */

static const double FLIP_I[3] = { 1, 2, 3 };
static const double FLIP_W0[3] = { 0.01, 5, 0.01 };

static const char *const METHODS[] = { "euler", "symplectic_euler", "verlet", "rk4", "verlet_exact" };
enum { METHOD_COUNT = sizeof METHODS / sizeof METHODS[0] };

/* ------------------------------------------------------ running worlds -- */

typedef struct tumble_case {
    tb_world *world;
    const char *integrator;
} tumble_case;

/* Worlds are shared by the integrators of one table: only the method
   changes. */
static void run_tumble(void *ctx, long steps)
{
    tumble_case *c = ctx;
    long s;
    check(tb_world_set_integrator(c->world, c->integrator), c->world, "set integrator");
    for (s = 0; s < steps; ++s)
        check(tb_world_step(c->world, H), c->world, "step");
}

static void tumble_free(tb_world *w)
{
    const double *x = tb_world_body_positions(w), *q = tb_world_body_orientations(w);
    keep(x[0] + q[4 * tb_world_body_count(w) - 1]);
    tb_world_destroy(w);
}

typedef struct ode_case {
    dWorldID world;
    dBodyID *bodies;
    size_t n;
} ode_case;

static void run_ode(void *ctx, long steps)
{
    ode_case *c = ctx;
    long s;
    for (s = 0; s < steps; ++s)
        if (!dWorldStep(c->world, H)) {
            fprintf(stderr, "bench_bodies: dWorldStep failed\n");
            exit(EXIT_FAILURE);
        }
}

static void ode_free(ode_case *c)
{
    keep(dBodyGetPosition(c->bodies[0])[2] + dBodyGetQuaternion(c->bodies[c->n - 1])[0]);
    dWorldDestroy(c->world);
    free(c->bodies);
}

static tb_world *new_world(const char *integrator, double gz)
{
    tb_world_def def = tb_default_world_def();
    tb_world *w;
    char message[TB_MESSAGE_SIZE];
    def.integrator = integrator;
    def.gravity[2] = gz;
    if (tb_world_create(&def, &w, message, sizeof message) != TB_OK) {
        fprintf(stderr, "bench_bodies: world: %s\n", message);
        exit(EXIT_FAILURE);
    }
    return w;
}

/* ODE's body for given principal moments, thrown. Auto-disable off so that
   every body moves every step; no geoms, joints or contacts. The
   gyroscopic term stays on (ODE's default). */
static dBodyID ode_body(dWorldID world, double mass, const double I[3], const double x[3], const double v[3],
                        const double omega[3])
{
    dBodyID b = dBodyCreate(world);
    dMass m;
    dMassSetZero(&m);
    dMassSetParameters(&m, mass, 0, 0, 0, I[0], I[1], I[2], 0, 0, 0);
    dBodySetMass(b, &m);
    dBodySetPosition(b, x[0], x[1], x[2]);
    dBodySetLinearVel(b, v[0], v[1], v[2]);
    dBodySetAngularVel(b, omega[0], omega[1], omega[2]);
    dBodySetAutoDisableFlag(b, 0);
    return b;
}

/* ----------------------------------------------------- part 1: the flip -- */

typedef struct flip_result {
    double q[4];        /* final orientation */
    double l_drift;     /* worst relative drift of |L| */
    double e_drift;     /* worst relative drift of the energy */
} flip_result;

static tb_world *flip_world(const char *integrator, size_t n)
{
    tb_world *w = new_world(integrator, 0);
    tb_body_def d = tb_default_body_def();
    size_t i;
    memcpy(d.mass.inertia, FLIP_I, sizeof d.mass.inertia);
    memcpy(d.angular_velocity, FLIP_W0, sizeof d.angular_velocity);
    for (i = 0; i < n; ++i)
        check(tb_world_add_body(w, &d, NULL), w, "add body");
    return w;
}

static void flip_tumble(const char *integrator, double h, long steps, flip_result *r)
{
    tb_world *w = flip_world(integrator, 1);
    const tb_body_id id = tb_world_body_at(w, 0);
    double L[3], l0, e0;
    long n;
    memset(r, 0, sizeof *r);
    check(tb_body_momentum(w, id, NULL, L), w, "momentum");
    l0 = norm3(L);
    e0 = tb_world_energy(w).rotational;
    for (n = 0; n < steps; ++n) {
        check(tb_world_step(w, h), w, "step");
        check(tb_body_momentum(w, id, NULL, L), w, "momentum");
        r->l_drift = fmax(r->l_drift, fabs(norm3(L) / l0 - 1));
        r->e_drift = fmax(r->e_drift, fabs(tb_world_energy(w).rotational / e0 - 1));
    }
    check(tb_body_orientation(w, id, r->q), w, "orientation");
    tb_world_destroy(w);
}

/* L = R I0 R^T w and E = w . L / 2 from ODE's state. */
static void ode_momentum(dBodyID b, double L[3], double *energy)
{
    const dReal *R = dBodyGetRotation(b), *w = dBodyGetAngularVel(b); /* R: 3 rows of 4 */
    double lb[3];
    int i;
    for (i = 0; i < 3; ++i)
        lb[i] = FLIP_I[i] * (R[i] * w[0] + R[4 + i] * w[1] + R[8 + i] * w[2]);
    for (i = 0; i < 3; ++i)
        L[i] = R[4 * i] * lb[0] + R[4 * i + 1] * lb[1] + R[4 * i + 2] * lb[2];
    *energy = 0.5 * (w[0] * L[0] + w[1] * L[1] + w[2] * L[2]);
}

static void flip_ode_world(ode_case *c, size_t n)
{
    const double zero[3] = { 0, 0, 0 };
    size_t i;
    c->n = n;
    c->world = dWorldCreate();
    c->bodies = xmalloc(n * sizeof *c->bodies);
    dWorldSetGravity(c->world, 0, 0, 0);
    dWorldSetAutoDisableFlag(c->world, 0);
    for (i = 0; i < n; ++i)
        c->bodies[i] = ode_body(c->world, 1, FLIP_I, zero, zero, FLIP_W0);
}

static void flip_ode(flip_result *r)
{
    ode_case c;
    double L[3], l0, e0, e;
    int n;
    memset(r, 0, sizeof *r);
    flip_ode_world(&c, 1);
    ode_momentum(c.bodies[0], L, &e0);
    l0 = norm3(L);
    for (n = 0; n < FLIP_STEPS; ++n) {
        dWorldStep(c.world, H);
        ode_momentum(c.bodies[0], L, &e);
        r->l_drift = fmax(r->l_drift, fabs(norm3(L) / l0 - 1));
        r->e_drift = fmax(r->e_drift, fabs(e / e0 - 1));
    }
    memcpy(r->q, dBodyGetQuaternion(c.bodies[0]), sizeof r->q);
    ode_free(&c);
}

static const char *met(int ok)
{
    return ok ? "met" : "NOT met";
}

static void part_flip(void)
{
    flip_result ref, ref2, res[METHOD_COUNT + 1];
    bench_case cases[2 * (METHOD_COUNT + 1)];
    tumble_case many[METHOD_COUNT], one[METHOD_COUNT];
    ode_case ode_many, ode_one;
    double err[METHOD_COUNT + 1];
    int m, best = 0, count = 0, any = 0;

    flip_tumble("rk4", H / 128, 128L * FLIP_STEPS, &ref);
    flip_tumble("rk4", H / 64, 64L * FLIP_STEPS, &ref2);
    for (m = 0; m < METHOD_COUNT; ++m)
        flip_tumble(METHODS[m], H, FLIP_STEPS, &res[m]);
    flip_ode(&res[METHOD_COUNT]);
    for (m = 0; m <= METHOD_COUNT; ++m)
        err[m] = angle_between(ref.q, res[m].q);

    many[0].world = flip_world("rk4", FLIP_BODIES);
    one[0].world = flip_world("rk4", 1);
    for (m = 0; m < METHOD_COUNT; ++m) {
        many[m].world = many[0].world;
        one[m].world = one[0].world;
        many[m].integrator = one[m].integrator = METHODS[m];
        cases[count].run = run_tumble, cases[count].ctx = &many[m], cases[count++].items = FLIP_BODIES;
        cases[count].run = run_tumble, cases[count].ctx = &one[m], cases[count++].items = 1;
    }
    flip_ode_world(&ode_many, FLIP_BODIES);
    flip_ode_world(&ode_one, 1);
    cases[count].run = run_ode, cases[count].ctx = &ode_many, cases[count++].items = FLIP_BODIES;
    cases[count].run = run_ode, cases[count].ctx = &ode_one, cases[count++].items = 1;
    measure(cases, count);

    printf("1. flip: I = diag(1, 2, 3) kg m^2, w0 = (0.01, 5, 0.01) rad/s (body), q0 = 1, h = 1/60 s, 20 s\n");
    printf("   reference: rk4 at h/128; rk4 at h/64 differs from it by %.2e rad\n", angle_between(ref.q, ref2.q));
    printf("   drifts are the worst over the run (tumble: its world L, the state; ODE: |R I0 R^T w|);\n"
           "   orientation is after 20 s\n\n");
    printf("%-18s %11s %11s %13s %17s %15s\n", "method", "|L| drift", "E drift", "orient. rad",
           "ns/body-step", "ns/step");
    printf("%-18s %11s %11s %13s %17s %15s\n", "", "", "", "", "(1024 bodies)", "(1 body)");
    for (m = 0; m <= METHOD_COUNT; ++m)
        printf("%-18s %11.2e %11.2e %13.3e %17.1f %15.1f\n", m < METHOD_COUNT ? METHODS[m] : "ODE dWorldStep",
               res[m].l_drift, res[m].e_drift, err[m], median(&cases[2 * m]), median(&cases[2 * m + 1]));
    for (m = 1; m < METHOD_COUNT; ++m)
        if (err[m] < err[best])
            best = m;
    {
        const double ns = median(&cases[2 * best]);
        const int l_ok = res[best].l_drift <= 1e-12, e_ok = res[best].e_drift <= 1e-9;
        const int q_ok = err[best] <= 1e-6, t_ok = ns <= 50;
        printf("\ntarget    tumble's best (%s): |L| drift %.1e <= 1e-12 %s; E drift %.1e <= 1e-9 %s;\n"
               "          orientation %.1e <= 1e-6 rad %s; %.0f ns/body-step <= 50 %s: %s\n",
               METHODS[best], res[best].l_drift, met(l_ok), res[best].e_drift, met(e_ok), err[best], met(q_ok), ns,
               met(t_ok), met(l_ok && e_ok && q_ok && t_ok));
        printf("          (one body alone: %.0f ns/step)\n", median(&cases[2 * best + 1]));
        printf("          methods meeting all four:");
        for (m = 0; m < METHOD_COUNT; ++m)
            if (res[m].l_drift <= 1e-12 && res[m].e_drift <= 1e-9 && err[m] <= 1e-6 && median(&cases[2 * m]) <= 50) {
                printf(" %s", METHODS[m]);
                any = 1;
            }
        printf("%s\n", any ? "" : " none");
        printf("          %.2g times closer than ODE (%.2g rad); MuJoCo 4.0 RK4 (docs/notes.md): |L| 1.7e-8, E 3.4e-8,\n"
               "          2.3e-6 rad at ~1300 ns\n", err[METHOD_COUNT] / err[best], err[METHOD_COUNT]);
    }
    tumble_free(many[0].world);
    tumble_free(one[0].world);
    ode_free(&ode_many);
    ode_free(&ode_one);
}

/* ------------------------------------------------ part 2: throughput -- */

enum kind { SPHERES, BOXES };

/* Body i of a run: a 20 m box of positions, speeds up to 5 m/s, masses
   0.5 to 2 kg, spins up to SPIN rad/s per axis; spheres of radius 0.1 to
   0.5 m (I = 2/5 m r^2), boxes with sides 0.25 to 1 m. */
static void free_body(unsigned long long *s, enum kind kind, double x[3], double v[3], double omega[3],
                      double *mass, double I[3])
{
    int k;
    for (k = 0; k < 3; ++k) {
        x[k] = 20 * uniform(s) - 10;
        v[k] = 10 * uniform(s) - 5;
        omega[k] = SPIN * (2 * uniform(s) - 1);
    }
    *mass = 0.5 + 1.5 * uniform(s);
    if (kind == SPHERES) {
        const double r = 0.1 + 0.4 * uniform(s);
        I[0] = I[1] = I[2] = 0.4 * *mass * r * r;
    } else {
        double a[3];
        for (k = 0; k < 3; ++k)
            a[k] = 0.25 + 0.75 * uniform(s);
        I[0] = *mass * (a[1] * a[1] + a[2] * a[2]) / 12;
        I[1] = *mass * (a[0] * a[0] + a[2] * a[2]) / 12;
        I[2] = *mass * (a[0] * a[0] + a[1] * a[1]) / 12;
    }
}

#define SEED 0x9E3779B97F4A7C15ULL

static tb_world *free_world(size_t n, enum kind kind)
{
    tb_world *w = new_world("verlet", -9.81);
    tb_body_def d = tb_default_body_def();
    unsigned long long seed = SEED;
    size_t i;
    for (i = 0; i < n; ++i) {
        free_body(&seed, kind, d.position, d.velocity, d.angular_velocity, &d.mass.mass, d.mass.inertia);
        check(tb_world_add_body(w, &d, NULL), w, "add body");
    }
    return w;
}

static void free_ode_world(ode_case *c, size_t n, enum kind kind)
{
    unsigned long long seed = SEED;
    size_t i;
    c->n = n;
    c->world = dWorldCreate();
    c->bodies = xmalloc(n * sizeof *c->bodies);
    dWorldSetGravity(c->world, 0, 0, -9.81);
    dWorldSetAutoDisableFlag(c->world, 0);
    for (i = 0; i < n; ++i) {
        double x[3], v[3], omega[3], mass, I[3];
        free_body(&seed, kind, x, v, omega, &mass, I);
        c->bodies[i] = ode_body(c->world, mass, I, x, v, omega);
    }
}

/* The memory bound of a verlet step at 10^5 bodies, whose state (about
   30 MB) has left the caches of a core: the bytes a step must move per
   body, streamed at the bandwidth measured beside it. With gravity alone
   a step is one sweep (integrators.c), which reads x, P, q and L (13
   doubles), the mass and the inverse mass (2) and writes x, P and q back
   (10 doubles); spheres also read their inverse moments (3: the lines of
   invI), boxes the frames the world keeps for the lanes (4,
   rotation.h). */
#define VERLET_BYTES(kind) ((13 + 2 + 10 + ((kind) == SPHERES ? 3 : 4)) * 8)

typedef struct stream_case {
    double *x, *y;
    size_t n;
} stream_case;

/* y += s x: two doubles read and one written, 24 bytes an element, the
   mix of a sweep. GCC vectorises it; it runs at the memory's pace. */
static void run_stream(void *ctx, long steps)
{
    stream_case *c = ctx;
    long k;
    size_t i;
    for (k = 0; k < steps; ++k) {
        const double s = 1e-9 * (double)(k + 1);
        for (i = 0; i < c->n; ++i)
            c->y[i] += s * c->x[i];
    }
}

typedef struct verdict {
    double verlet_ratio, rk4_ratio;
} verdict;

static verdict part_throughput(size_t n, enum kind kind)
{
    static const char *const names[] = { "spheres", "boxes" };
    const size_t bytes = VERLET_BYTES(kind);
    bench_case cases[METHOD_COUNT + 2];
    tumble_case tumble[METHOD_COUNT];
    ode_case ode;
    stream_case stream;
    verdict v = { 0, 0 };
    double ode_ns, bound = 0;
    int m, count = METHOD_COUNT + 1;
    size_t i;

    tumble[0].world = free_world(n, kind);
    for (m = 0; m < METHOD_COUNT; ++m) {
        tumble[m].world = tumble[0].world;
        tumble[m].integrator = METHODS[m];
        cases[m].run = run_tumble, cases[m].ctx = &tumble[m], cases[m].items = (double)n;
    }
    free_ode_world(&ode, n, kind);
    cases[METHOD_COUNT].run = run_ode, cases[METHOD_COUNT].ctx = &ode, cases[METHOD_COUNT].items = (double)n;
    /* a pass over bytes per body times n bytes, timed per body: the time a
       body-step's bytes take at the measured bandwidth */
    stream.n = n * bytes / 24;
    stream.x = xmalloc(stream.n * sizeof *stream.x);
    stream.y = xmalloc(stream.n * sizeof *stream.y);
    for (i = 0; i < stream.n; ++i)
        stream.x[i] = stream.y[i] = 1;
    if (n >= 100000) {
        cases[count].run = run_stream, cases[count].ctx = &stream, cases[count++].items = (double)n;
    }
    measure(cases, count);
    if (count > METHOD_COUNT + 1)
        bound = median(&cases[METHOD_COUNT + 1]);

    ode_ns = median(&cases[METHOD_COUNT]);
    for (m = 0; m < METHOD_COUNT; ++m) {
        const double ns = median(&cases[m]);
        printf("%-8zu %-8s %-18s %12.2f %11.1f", n, names[kind], METHODS[m], ns, ode_ns / ns);
        if (bound > 0 && !strcmp(METHODS[m], "verlet"))
            printf("   memory bound %.2f ns (%zu B at %.1f GB/s)%s", bound, bytes, (double)bytes / bound,
                   ns < 1.25 * bound ? ": at the bound" : "");
        printf("\n");
        if (!strcmp(METHODS[m], "verlet"))
            v.verlet_ratio = ode_ns / ns;
        if (!strcmp(METHODS[m], "rk4"))
            v.rk4_ratio = ode_ns / ns;
    }
    printf("%-8zu %-8s %-18s %12.2f   (%ld steps a repeat)\n\n", n, names[kind], "ODE dWorldStep", ode_ns,
           cases[METHOD_COUNT].steps);
    keep(stream.y[0]);
    free(stream.x);
    free(stream.y);
    tumble_free(tumble[0].world);
    ode_free(&ode);
    return v;
}

/* ---------------------------------------------------------------- main -- */

static void print_header(void)
{
    printf("tumble rigid bodies beside ODE %s (%s): medians of %d repeats of ~%.2f s\n", dODE_VERSION,
           dCheckConfiguration("ODE_double_precision") ? "double" : "NOT double", BENCH_REPEATS,
           BENCH_REPEAT_SECONDS);
    bench_print_build();
    bench_print_asserts();
    /* the same test as tb__isa() (src/rotation.c), which is internal */
#if defined(__GNUC__) && defined(__x86_64__)
    printf("lanes     %s (chosen at run time; every choice gives the same bits)\n",
           __builtin_cpu_supports("avx512f") ? "AVX-512" : __builtin_cpu_supports("avx2") ? "AVX2" : "portable C");
#else
    printf("lanes     portable C\n");
#endif
    printf("\n");
}

int main(void)
{
    static const size_t sizes[] = { 1000, 100000 };
    verdict v[2][2];
    int z, k, verlet_ok = 1, rk4_ok = 1;

    dInitODE2(0);
    print_header();
    part_flip();

    printf("\n2. free bodies under gravity, thrown with spins up to %g rad/s per axis, h = 1/60 s\n\n", SPIN);
    printf("%-8s %-8s %-18s %12s %11s\n", "bodies", "kind", "method", "ns/body-step", "ODE/tumble");
    for (z = 0; z < 2; ++z)
        for (k = 0; k < 2; ++k)
            v[z][k] = part_throughput(sizes[z], (enum kind)k);
    for (z = 0; z < 2; ++z)
        for (k = 0; k < 2; ++k) {
            verlet_ok &= v[z][k].verlet_ratio >= 20;
            rk4_ok &= v[z][k].rk4_ratio >= 5;
        }
    printf("target    verlet >= 20x faster than ODE: spheres %.0fx, %.0fx; boxes %.0fx, %.0fx (10^3, 10^5): %s\n",
           v[0][0].verlet_ratio, v[1][0].verlet_ratio, v[0][1].verlet_ratio, v[1][1].verlet_ratio, met(verlet_ok));
    printf("target    rk4 >= 5x faster than ODE:     spheres %.0fx, %.0fx; boxes %.0fx, %.0fx (10^3, 10^5): %s\n",
           v[0][0].rk4_ratio, v[1][0].rk4_ratio, v[0][1].rk4_ratio, v[1][1].rk4_ratio, met(rk4_ok));
    dCloseODE();
    return 0;
}
