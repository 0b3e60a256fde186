/* particles.c: particle throughput against the memory-bound limit.

   For 10^3, 10^5 and 10^6 particles under gravity and linear drag, prints
   the cost of one step per particle with semi-implicit Euler beside the cost
   per particle of a streaming kernel over the same bytes, measured in the
   same run, and their ratio. Targets (from the issue): at most 1 ns per
   particle-step at 10^3, and within 1.5 times the streaming figure at 10^6.
   Velocity Verlet and RK4 are printed for information, and so is ODE's
   dWorldStep per free body under the same forces, for 10^3 bodies.

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

#define H (1.0 / 240)         /* s, the step */
#define DRAG 0.1              /* N s/m, linear drag on every particle */
#define MAX_CASES 5

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

static void run_stream(void *ctx, long steps)
{
    stream_case *c = ctx;
    long s;
    double sum = 0;
    for (s = 0; s < steps; ++s)
        sum += stream_pass(c->state, c->param, c->n);
    keep(sum);
}

static void stream_init(stream_case *c, size_t n)
{
    size_t i;
    c->n = n;
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

/* Worlds are shared by the integrators of one size: only the method changes. */
static void run_tumble(void *ctx, long steps)
{
    tumble_case *c = ctx;
    long s;
    check(tb_world_set_integrator(c->world, c->integrator), c->world, "set integrator");
    for (s = 0; s < steps; ++s)
        check(tb_world_step(c->world, H), c->world, "step");
}

static tb_world *particle_world(size_t n)
{
    tb_world_def def = tb_default_world_def();
    tb_particle_def p = tb_default_particle_def();
    unsigned long long seed = 0x9E3779B97F4A7C15ULL;
    tb_world *w;
    char message[TB_MESSAGE_SIZE];
    size_t i;
    def.integrator = "symplectic_euler";
    def.linear_drag = DRAG;
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

static void print_header(void)
{
    printf("tumble particle throughput, ns per particle-step (median of %d repeats of ~%.2f s)\n",
           BENCH_REPEATS, BENCH_REPEAT_SECONDS);
    bench_print_build();
    bench_print_asserts();
    printf("scene     gravity (0, 0, -9.81) m/s^2, linear drag %g N s/m, masses 0.5..2 kg, h = 1/240 s\n",
           DRAG);
    printf("stream    in place a = s a + c over %d doubles per particle, %d more read: %.0f bytes per particle\n\n",
           STATE_DOUBLES, PARAM_DOUBLES, STEP_BYTES);
}

int main(void)
{
    static const size_t sizes[] = { 1000, 100000, 1000000 };
    static const char *const methods[] = { "symplectic_euler", "verlet", "rk4" };
    enum { SIZES = sizeof sizes / sizeof sizes[0], METHODS = sizeof methods / sizeof methods[0] };
    double small_ns = 0, large_ratio = 0;
    int z, m;

    print_header();
    dInitODE2(0);
    for (z = 0; z < SIZES; ++z) {
        const size_t n = sizes[z];
        bench_case cases[MAX_CASES];
        tumble_case tumble[METHODS];
        stream_case stream;
        ode_case ode;
        double stream_ns, euler_ns;
        int count = 0;

        stream_init(&stream, n);
        cases[count].run = run_stream;
        cases[count++].ctx = &stream;
        tumble[0].world = particle_world(n);
        for (m = 0; m < METHODS; ++m) {
            tumble[m].world = tumble[0].world;
            tumble[m].integrator = methods[m];
            cases[count].run = run_tumble;
            cases[count++].ctx = &tumble[m];
        }
        if (n == 1000) { /* ODE's figure is per body and flat in n: one size is enough */
            ode_init(&ode, n);
            cases[count].run = run_ode;
            cases[count++].ctx = &ode;
        }
        for (m = 0; m < count; ++m)
            cases[m].items = (double)n;
        measure(cases, count);

        stream_ns = median(&cases[0]);
        euler_ns = median(&cases[1]);
        for (m = 0; m < METHODS; ++m) {
            const double ns = median(&cases[1 + m]);
            printf("particles %-9zu %-16s %7.2f ns/particle-step   stream %5.2f ns/particle (%3.0f GB/s)   ratio %5.2f\n",
                   n, methods[m], ns, stream_ns, STEP_BYTES / stream_ns, ns / stream_ns);
        }
        if (count > 1 + METHODS) {
            const double ns = median(&cases[1 + METHODS]);
            printf("bodies    %-9zu %-16s %7.2f ns/body-step       ODE/tumble %.0f (ODE %s, double)\n",
                   n, "ODE dWorldStep", ns, ns / euler_ns, TB_BENCH_ODE);
            ode_free(&ode);
        }
        printf("\n");
        if (n == 1000)
            small_ns = euler_ns;
        if (n == 1000000)
            large_ratio = euler_ns / stream_ns;
        world_free(tumble[0].world);
        stream_free(&stream);
    }
    dCloseODE();

    printf("target    10^3 particles: %.2f ns/particle-step <= 1: %s\n", small_ns,
           small_ns <= 1 ? "met" : "NOT met");
    printf("target    10^6 particles: ratio %.2f <= 1.5: %s\n", large_ratio,
           large_ratio <= 1.5 ? "met" : "NOT met");
    return 0;
}
