/* particles.c: free-particle throughput against the memory-bound limit.

   For 10^3, 10^5, 10^6 and 10^7 particles, prints the cost of one step per
   particle under every method beside the cost per particle of a streaming
   kernel over the bytes a split step must move (the bandwidth floor),
   measured in the same run, and their ratio. Two scenes: gravity and
   linear drag (every method), and gravity with linear and quadratic drag
   (the split methods). Targets (issue 24): the split methods within 2
   times the stream at 10^3 (in cache) and within 1.2 times at 10^6 and
   10^7, under both scenes. Beside each ratio, the ratio against the same
   streaming kernel in tumble's layout of the particles (four arrays, not
   two): what the step adds over what its layout costs. ODE's dWorldStep
   per free body under the same forces is printed for 10^3 bodies.

   Figures are medians over repeats of about BENCH_REPEAT_SECONDS each
   (measure() in bench.h). The repeats of all cases of one size are
   interleaved, so noise from the machine (other processes, frequency
   changes) falls on every case alike and each ratio compares figures taken
   moments apart. */
#define _POSIX_C_SOURCE 200809L
#define BENCH_NAME "bench_particles"

#include "bench.h"
#include "tumble.h"

#include <ode/ode.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define H (1.0 / 240)         /* s, the step */
#define DRAG 0.1              /* N s/m, linear drag on every particle */
#define QUADRATIC_DRAG 0.01   /* N s^2/m^2, quadratic drag in the second scene */

/* Bytes a semi-implicit Euler step must move per particle: position and
   velocity read and written (2 x 3 doubles each way), mass and inverse mass
   read (2 doubles). 64 bytes read, 48 written. */
#define STATE_DOUBLES 6
#define PARAM_DOUBLES 2
#define STEP_BYTES (8.0 * (2 * STATE_DOUBLES + PARAM_DOUBLES))

/* The initial state of particle (or body) i of a run: a 20 m box, speeds up
   to 5 m/s per axis, masses from 0.5 to 2 kg. */
static void initial(unsigned long long *s, double pos[3], double vel[3], double *mass)
{
    int k;
    for (k = 0; k < 3; ++k) {
        pos[k] = 20 * uniform(s) - 10;
        vel[k] = 10 * uniform(s) - 5;
    }
    *mass = 0.5 + 1.5 * uniform(s);
}

/* ------------------------------------------------- the streaming bound -- */

/* The reference kernel: one pass reads and writes in place STATE_DOUBLES per
   particle of `state` and reads PARAM_DOUBLES per particle of `param`, that
   is exactly the bytes a semi-implicit Euler step must move (STEP_BYTES), in
   the same pattern: contiguous, unit stride, the written data read first.
   Its arithmetic is as little as keeps every byte live (one multiply and one
   add per state double, one add per parameter double into running sums that
   stay in L1), so it runs at the speed the memory allows and nothing else:
   the fair bound on any step that must touch this state.
   When the state fits in a cache it measures that cache's bandwidth.
   It is compiled with the library's flags (-O2, no contraction, no -march).
   GCC 12 at -O2 vectorizes only loops of known trip count over pointers that
   cannot alias, hence the fixed blocks and `restrict`: written as one plain
   loop it runs scalar and is bound by its instructions, not by the memory,
   whenever the state is in cache. With 0 < s < 1 and c > 0 the state converges to c / (1 - s)
   = 1, so nothing overflows or goes subnormal however long it runs. */
#define STREAM_SCALE 0.999
#define STREAM_ADD 1e-3
#define STREAM_BLOCK 32     /* particles */

typedef struct stream_case {
    double *state;          /* [STATE_DOUBLES * n], read and written */
    double *param;          /* [PARAM_DOUBLES * n], read only */
    size_t n;
    int layout;             /* 0: two arrays; 1: tumble's four (stream_layout) */
} stream_case;

static double stream_pass(double *restrict state, const double *restrict param, size_t n)
{
    double sums[PARAM_DOUBLES * STREAM_BLOCK] = { 0 }, total = 0;
    size_t b, k;
    for (b = 0; b + STREAM_BLOCK <= n; b += STREAM_BLOCK) {
        double *s = state + STATE_DOUBLES * b;
        const double *p = param + PARAM_DOUBLES * b;
        for (k = 0; k < STATE_DOUBLES * STREAM_BLOCK; ++k)
            s[k] = s[k] * STREAM_SCALE + STREAM_ADD;
        for (k = 0; k < PARAM_DOUBLES * STREAM_BLOCK; ++k)
            sums[k] += p[k];
    }
    for (k = STATE_DOUBLES * b; k < STATE_DOUBLES * n; ++k) /* the last partial block */
        state[k] = state[k] * STREAM_SCALE + STREAM_ADD;
    for (k = PARAM_DOUBLES * b; k < PARAM_DOUBLES * n; ++k)
        total += param[k];
    for (k = 0; k < PARAM_DOUBLES * STREAM_BLOCK; ++k)
        total += sums[k];
    return total;
}

/* The same bytes and arithmetic in the layout tumble's particles have: four
   arrays, positions and velocities (3 doubles a particle each) read and
   written, masses and inverse masses read, each its own stream. More
   streams over the same bytes can cost more once they leave the cache: the
   ratio against this kernel tells what the layout costs from what the step
   adds. */
static double stream_layout(double *restrict x, double *restrict v, const double *restrict m,
                            const double *restrict im, size_t n)
{
    double sums[PARAM_DOUBLES * STREAM_BLOCK] = { 0 }, total = 0;
    size_t b, k;
    for (b = 0; b + STREAM_BLOCK <= n; b += STREAM_BLOCK) {
        double *xb = x + 3 * b, *vb = v + 3 * b;
        for (k = 0; k < 3 * STREAM_BLOCK; ++k)
            xb[k] = xb[k] * STREAM_SCALE + STREAM_ADD;
        for (k = 0; k < 3 * STREAM_BLOCK; ++k)
            vb[k] = vb[k] * STREAM_SCALE + STREAM_ADD;
        for (k = 0; k < STREAM_BLOCK; ++k)
            sums[k] += m[b + k];
        for (k = 0; k < STREAM_BLOCK; ++k)
            sums[STREAM_BLOCK + k] += im[b + k];
    }
    for (k = 3 * b; k < 3 * n; ++k) { /* the last partial block */
        x[k] = x[k] * STREAM_SCALE + STREAM_ADD;
        v[k] = v[k] * STREAM_SCALE + STREAM_ADD;
    }
    for (k = b; k < n; ++k)
        total += m[k] + im[k];
    for (k = 0; k < PARAM_DOUBLES * STREAM_BLOCK; ++k)
        total += sums[k];
    return total;
}

static void run_stream(void *ctx, long steps)
{
    stream_case *c = ctx;
    long s;
    double sum = 0;
    for (s = 0; s < steps; ++s)
        sum += c->layout ? stream_layout(c->state, c->state + 3 * c->n, c->param, c->param + c->n, c->n)
                         : stream_pass(c->state, c->param, c->n);
    keep(sum);
}

static void stream_init(stream_case *c, size_t n, int layout)
{
    size_t i;
    c->n = n;
    c->layout = layout;
    c->state = xmalloc(STATE_DOUBLES * n * sizeof(double));
    c->param = xmalloc(PARAM_DOUBLES * n * sizeof(double));
    for (i = 0; i < STATE_DOUBLES * n; ++i)
        c->state[i] = 1;
    for (i = 0; i < PARAM_DOUBLES * n; ++i)
        c->param[i] = 1;
}

static void stream_free(stream_case *c)
{
    double sum = 0;
    size_t i;
    for (i = 0; i < STATE_DOUBLES * c->n; ++i)
        sum += c->state[i];
    keep(sum);
    free(c->state);
    free(c->param);
}

/* ------------------------------------------------------------- tumble -- */

typedef struct tumble_case {
    tb_world *world;
    const char *integrator;
} tumble_case;

/* Worlds are shared by the integrators of one size and scene: only the
   method changes. */
static void run_tumble(void *ctx, long steps)
{
    tumble_case *c = ctx;
    long s;
    check(tb_world_set_integrator(c->world, c->integrator), c->world, "set integrator");
    for (s = 0; s < steps; ++s)
        check(tb_world_step(c->world, H), c->world, "step");
}

/* n particles under gravity and linear drag, and quadratic drag too when
   `quadratic` is not 0 (N s^2/m^2). */
static tb_world *particle_world(size_t n, double quadratic)
{
    tb_world_def def = tb_default_world_def();
    tb_particle_def p = tb_default_particle_def();
    unsigned long long seed = 0x9E3779B97F4A7C15ULL;
    tb_world *w;
    char message[TB_MESSAGE_SIZE];
    size_t i;
    def.integrator = "symplectic_euler";
    def.linear_drag = DRAG;
    def.quadratic_drag = quadratic;
    if (tb_world_create(&def, &w, message, sizeof message) != TB_OK) {
        fprintf(stderr, "bench_particles: world: %s\n", message);
        exit(EXIT_FAILURE);
    }
    for (i = 0; i < n; ++i) {
        initial(&seed, p.position, p.velocity, &p.mass);
        check(tb_world_add_particle(w, &p, NULL), w, "add particle");
    }
    return w;
}

static void world_free(tb_world *w)
{
    const double *x = tb_world_particle_positions(w);
    keep(x[0] + x[3 * tb_world_particle_count(w) - 1]);
    tb_world_destroy(w);
}

/* ---------------------------------------------------------------- ODE -- */

/* The same particles as ODE free bodies (small spheres): gravity is a world
   setting there too, and the drag is a force added before every step, as an
   ODE user would. Auto-disable is off so that every body moves every step;
   there are no geoms, joints or contacts. ODE still integrates each body's
   rotation (at rest here): that is part of what a rigid-body step costs. */
typedef struct ode_case {
    dWorldID world;
    dBodyID *bodies;
    size_t n;
} ode_case;

static void run_ode(void *ctx, long steps)
{
    ode_case *c = ctx;
    long s;
    size_t i;
    for (s = 0; s < steps; ++s) {
        for (i = 0; i < c->n; ++i) {
            const dReal *v = dBodyGetLinearVel(c->bodies[i]);
            dBodyAddForce(c->bodies[i], -DRAG * v[0], -DRAG * v[1], -DRAG * v[2]);
        }
        if (!dWorldStep(c->world, H)) {
            fprintf(stderr, "bench_particles: dWorldStep failed\n");
            exit(EXIT_FAILURE);
        }
    }
}

static void ode_init(ode_case *c, size_t n)
{
    unsigned long long seed = 0x9E3779B97F4A7C15ULL; /* the particles' seed */
    size_t i;
    c->n = n;
    c->world = dWorldCreate();
    c->bodies = xmalloc(n * sizeof *c->bodies);
    dWorldSetGravity(c->world, 0, 0, -9.81);
    dWorldSetAutoDisableFlag(c->world, 0);
    for (i = 0; i < n; ++i) {
        double pos[3], vel[3], mass;
        dMass m;
        initial(&seed, pos, vel, &mass);
        c->bodies[i] = dBodyCreate(c->world);
        dMassSetSphereTotal(&m, mass, 0.05);
        dBodySetMass(c->bodies[i], &m);
        dBodySetPosition(c->bodies[i], pos[0], pos[1], pos[2]);
        dBodySetLinearVel(c->bodies[i], vel[0], vel[1], vel[2]);
        dBodySetAutoDisableFlag(c->bodies[i], 0);
    }
}

static void ode_free(ode_case *c)
{
    keep(dBodyGetPosition(c->bodies[0])[2]);
    dWorldDestroy(c->world);
    free(c->bodies);
}

/* ---------------------------------------------------------------- main -- */

/* The split methods, held to the targets under both scenes; every method
   runs the linear-drag scene. At 10^7 particles the methods with many
   state-sized scratch vectors (implicit_euler 4, dopri5 and auto 10: 3 to
   8 GB beside the 0.8 GB state) are left out. */
static const char *const split_methods[] = { "symplectic_euler", "verlet", "verlet_exact" };
#define SPLIT_COUNT 3
#define LARGE 10000000
#define MAX_CASES 17

static int runs_at(const char *method, size_t n)
{
    return n < LARGE || (strcmp(method, "implicit_euler") != 0 && strcmp(method, "dopri5") != 0 &&
                         strcmp(method, "auto") != 0);
}

static void print_header(void)
{
    printf("tumble particle throughput, ns per particle-step (median of %d repeats of ~%.2f s)\n",
           BENCH_REPEATS, BENCH_REPEAT_SECONDS);
    bench_print_build();
    bench_print_asserts();
    printf("scenes    gravity (0, 0, -9.81) m/s^2, masses 0.5..2 kg, h = 1/240 s; linear drag %g N s/m "
           "(\"linear\"), and that with quadratic drag %g N s^2/m^2 (\"quadratic\")\n", DRAG, QUADRATIC_DRAG);
    printf("stream    in place a = s a + c over %d doubles per particle, %d more read: %.0f bytes per particle, in two\n"
           "          arrays (the target's floor) and in tumble's layout of four (positions, velocities, masses,\n"
           "          inverse masses)\n\n", STATE_DOUBLES, PARAM_DOUBLES, STEP_BYTES);
}

int main(void)
{
    static const size_t sizes[] = { 1000, 100000, 1000000, LARGE };
    enum { SIZES = sizeof sizes / sizeof sizes[0] };
    double worst_small = 0, worst_large = 0; /* the split methods' largest ratios */
    int z, m;

    print_header();
    dInitODE2(0);
    for (z = 0; z < SIZES; ++z) {
        const size_t n = sizes[z];
        bench_case cases[MAX_CASES];
        tumble_case tumble[MAX_CASES];
        const char *scene[MAX_CASES];
        tb_world *linear = particle_world(n, 0), *quadratic = particle_world(n, QUADRATIC_DRAG);
        stream_case stream, layout;
        ode_case ode;
        double stream_ns, layout_ns, verlet_ns = 0;
        int count = 0, first = 2, ode_at = -1;

        stream_init(&stream, n, 0);
        stream_init(&layout, n, 1);
        cases[count].run = run_stream;
        cases[count++].ctx = &stream;
        cases[count].run = run_stream;
        cases[count++].ctx = &layout;
        for (m = 0; m < tb_integrator_count(); ++m)
            if (runs_at(tb_integrator_name(m), n)) {
                tumble[count].world = linear;
                tumble[count].integrator = tb_integrator_name(m);
                scene[count] = "linear";
                cases[count].run = run_tumble;
                cases[count].ctx = &tumble[count];
                ++count;
            }
        for (m = 0; m < SPLIT_COUNT; ++m) {
            tumble[count].world = quadratic;
            tumble[count].integrator = split_methods[m];
            scene[count] = "quadratic";
            cases[count].run = run_tumble;
            cases[count].ctx = &tumble[count];
            ++count;
        }
        if (n == 1000) { /* ODE's figure is per body and flat in n: one size is enough */
            ode_init(&ode, n);
            ode_at = count;
            cases[count].run = run_ode;
            cases[count++].ctx = &ode;
        }
        for (m = 0; m < count; ++m)
            cases[m].items = (double)n;
        measure(cases, count);

        stream_ns = median(&cases[0]);
        layout_ns = median(&cases[1]);
        for (m = first; m < count; ++m) {
            const double ns = median(&cases[m]), ratio = ns / stream_ns;
            int split = 0, k;
            if (m == ode_at)
                continue;
            for (k = 0; k < SPLIT_COUNT; ++k)
                split |= strcmp(tumble[m].integrator, split_methods[k]) == 0;
            if (!strcmp(tumble[m].integrator, "verlet") && !strcmp(scene[m], "linear"))
                verlet_ns = ns;
            if (split && n == 1000)
                worst_small = ratio > worst_small ? ratio : worst_small;
            if (split && n >= 1000000)
                worst_large = ratio > worst_large ? ratio : worst_large;
            printf("particles %-9zu %-16s %-9s %8.2f ns/particle-step   stream %5.2f ns/particle (%3.0f GB/s)   "
                   "ratio %5.2f   in tumble's layout %5.2f, ratio %5.2f\n", n, tumble[m].integrator, scene[m], ns,
                   stream_ns, STEP_BYTES / stream_ns, ratio, layout_ns, ns / layout_ns);
        }
        if (ode_at >= 0) {
            const double ns = median(&cases[ode_at]);
            printf("bodies    %-9zu %-26s %8.2f ns/body-step       ODE/tumble verlet %.0f (ODE %s, double)\n",
                   n, "ODE dWorldStep", ns, ns / verlet_ns, TB_BENCH_ODE);
            ode_free(&ode);
        }
        printf("\n");
        fflush(stdout);
        world_free(linear);
        world_free(quadratic);
        stream_free(&stream);
        stream_free(&layout);
    }
    dCloseODE();

    printf("target    split methods (symplectic_euler, verlet, verlet_exact; both scenes) within 2 times the "
           "stream at 10^3: worst ratio %.2f: %s\n", worst_small, worst_small <= 2 ? "met" : "NOT met");
    printf("target    split methods within 1.2 times the stream at 10^6 and 10^7: worst ratio %.2f: %s\n",
           worst_large, worst_large <= 1.2 ? "met" : "NOT met");
    return 0;
}
