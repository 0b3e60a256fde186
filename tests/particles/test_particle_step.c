/* test_particle_step.c: the particles' one-pass kernel (particle_step.c,
   compiled in: it is internal) against the general sweep and against the
   route Verlet took before it, bit for bit, under every force a free
   particle feels, on every instruction set the processor runs. */
#include "test_main.h"

#include "particles/particles.h"
#include "tumble.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define H (1.0 / 60)

/* The force combinations of a free particle: gravity alone, with linear,
   quadratic or both drags, and drag without gravity. */
typedef struct forces {
    const char *name;
    double g[3], c1, c2;
} forces;

static const forces FORCES[] = {
    { "gravity", { 0, 0, -9.81 }, 0, 0 },
    { "gravity + linear drag", { 0, 0, -9.81 }, 0.3, 0 },
    { "gravity + quadratic drag", { 0, 0, -9.81 }, 0, 0.05 },
    { "gravity + both drags", { 1.5, -2, -9.81 }, 0.3, 0.05 },
    { "both drags, no gravity", { 0, 0, 0 }, 0.3, 0.05 },
};
#define FORCE_COUNT (sizeof FORCES / sizeof FORCES[0])

/* Counts around the kernel's block of 32 particles: short of one, one, one
   and a part, many and a part. */
static const size_t COUNTS[] = { 1, 31, 32, 33, 1000 };
#define COUNT_COUNT (sizeof COUNTS / sizeof COUNTS[0])

static double uniform(unsigned long long *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (double)((*s * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}

/* n particles at random places and speeds (up to 30 m/s, where quadratic
   drag matters), masses 0.1 to 10 kg, every seventh pinned. */
static tb_world *particle_world(const forces *f, size_t n, const char *integrator, unsigned long long seed)
{
    tb_world_def def = tb_default_world_def();
    tb_particle_def p = tb_default_particle_def();
    tb_world *w;
    size_t i;
    int k;
    memcpy(def.gravity, f->g, sizeof def.gravity);
    def.linear_drag = f->c1;
    def.quadratic_drag = f->c2;
    def.integrator = integrator;
    assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
    for (i = 0; i < n; ++i) {
        for (k = 0; k < 3; ++k) {
            p.position[k] = 20 * uniform(&seed) - 10;
            p.velocity[k] = 60 * uniform(&seed) - 30;
        }
        p.mass = 0.1 + 9.9 * uniform(&seed);
        p.pinned = i % 7 == 3;
        assert_int_equal(tb_world_add_particle(w, &p, NULL), TB_OK);
    }
    return w;
}

static void assert_same_particles(const tb_world *a, const tb_world *b, const char *what)
{
    const size_t n = tb_world_particle_count(a);
    if (memcmp(tb_world_particle_positions(a), tb_world_particle_positions(b), 3 * n * sizeof(double)) ||
        memcmp(tb_world_particle_velocities(a), tb_world_particle_velocities(b), 3 * n * sizeof(double)))
        fail_msg("%s: not the same bits", what);
}

/* Verlet's route before the one-pass kernel (integrators.c): copy the
   state, kick h/2 and drift h, extrapolate the copy's velocities to
   2 v - v_n, and kick h/2 with the drag seeing them, each a general sweep. */
static void old_verlet_route(tb_world *w, double h)
{
    const tb__split_op kick_drift[2] = { { 0, h / 2, TB__ROTATE_SPLIT2, 0 }, { 1, h, TB__ROTATE_SPLIT2, 0 } };
    const tb__split_op kick[1] = { { 0, h / 2, TB__ROTATE_SPLIT2, 0 } };
    double *predicted = malloc(w->y_size * sizeof(double));
    double *pv = predicted + w->off[TB__PARTICLE_VEL];
    const double *v = w->y + w->off[TB__PARTICLE_VEL];
    size_t i;
    assert_non_null(predicted);
    memcpy(predicted, w->y, w->y_size * sizeof(double));
    tb__particle_sweep_blocked(w, kick_drift, 2);
    for (i = 0; i < 3 * w->particle_count; ++i)
        pv[i] = 2 * v[i] - pv[i];
    if (tb__particle_velocity_dependent(w))
        w->kick_seen = predicted;
    tb__particle_sweep_blocked(w, kick, 1);
    w->kick_seen = NULL;
    free(predicted);
}

/* The one-pass kernel on each instruction set against the general sweep
   with the same ops (a kick; a kick and a drift: symplectic Euler; and
   Verlet's kick, drift and closing kick at the predicted velocity) and
   against Verlet's old route, over 20 steps of random particles under
   each force combination: the same operations in the same order, so
   equal bits, compared with memcmp. */
static void one_pass_gives_the_general_bits(void **state)
{
    const tb__split_op lists[3][3] = {
        { { 0, H, TB__ROTATE_FROZEN, 0 } },
        { { 0, H, TB__ROTATE_FROZEN, 0 }, { 1, H, TB__ROTATE_FROZEN, 0 } },
        { { 0, H / 2, TB__ROTATE_SPLIT2, 0 }, { 1, H, TB__ROTATE_SPLIT2, 0 }, { 0, H / 2, TB__ROTATE_SPLIT2, 1 } },
    };
    size_t f, c;
    int isa, ops, step, compared = 0;
    (void)state;
    for (f = 0; f < FORCE_COUNT; ++f)
        for (c = 0; c < COUNT_COUNT; ++c)
            for (isa = 0; isa <= tb__isa(); ++isa)
                for (ops = 1; ops <= 3; ++ops) {
                    tb_world *fast = particle_world(&FORCES[f], COUNTS[c], NULL, 7 + c);
                    tb_world *general = particle_world(&FORCES[f], COUNTS[c], NULL, 7 + c);
                    tb_world *old = particle_world(&FORCES[f], COUNTS[c], NULL, 7 + c);
                    for (step = 0; step < 20; ++step) {
                        assert_true(tb__particle_one_pass(fast, lists[ops - 1], ops, isa));
                        tb__particle_sweep_blocked(general, lists[ops - 1], ops);
                        if (ops == 3)
                            old_verlet_route(old, H);
                    }
                    assert_same_particles(fast, general, FORCES[f].name);
                    if (ops == 3)
                        assert_same_particles(fast, old, FORCES[f].name);
                    ++compared;
                    tb_world_destroy(fast);
                    tb_world_destroy(general);
                    tb_world_destroy(old);
                }
    print_message("%d runs of 20 sweeps compared (%zu force combinations, %zu counts, instruction sets 0..%d, "
                  "3 op lists): every one the same bits\n", compared, FORCE_COUNT, COUNT_COUNT, tb__isa());
}

/* A force callback that adds nothing: its world takes the general route
   (forces gathered before each kick, Verlet's state copy and second
   evaluation), and a force of 0 added changes no sum but the sign of a
   zero, which random particles do not have. */
static tb_status add_nothing(const tb_force_args *args, void *user)
{
    (void)args;
    (void)user;
    return TB_OK;
}

/* Whole steps through tb_world_step, under verlet and symplectic_euler,
   with each force combination, a uniform velocity field (it carries
   tracers only, so it leaves particles on the one-pass kernel) and a few
   free bodies: 100 steps against the same world with a callback that adds
   nothing, which takes the general route. Equal bits, and the same drag's
   work (tb_work.damping_work), which the one-pass kernel sums in its pass
   and the general route in passes of its own. */
static void split_steps_give_the_general_bits(void **state)
{
    static const char *const methods[] = { "verlet", "symplectic_euler", "verlet_exact" };
    const double wind[3] = { 1, 0, 0 };
    double fast_work, general_work;
    size_t f;
    int m, step, k;
    (void)state;
    for (f = 0; f < FORCE_COUNT; ++f)
        for (m = 0; m < 3; ++m) {
            tb_world *fast = particle_world(&FORCES[f], 333, methods[m], 11);
            tb_world *general = particle_world(&FORCES[f], 333, methods[m], 11);
            tb_body_def b = tb_default_body_def();
            assert_int_equal(tb_world_add_uniform_field(fast, wind, NULL), TB_OK);
            assert_int_equal(tb_world_add_uniform_field(general, wind, NULL), TB_OK);
            assert_int_equal(tb_world_add_force(general, add_nothing, NULL, NULL), TB_OK);
            for (k = 0; k < 40; ++k) {
                b.position[0] = k;
                b.velocity[1] = 0.5 * k;
                b.angular_velocity[2] = 0.1 * k;
                assert_int_equal(tb_world_add_body(fast, &b, NULL), TB_OK);
                assert_int_equal(tb_world_add_body(general, &b, NULL), TB_OK);
            }
            for (step = 0; step < 100; ++step) {
                assert_int_equal(tb_world_step(fast, H), TB_OK);
                assert_int_equal(tb_world_step(general, H), TB_OK);
            }
            assert_same_particles(fast, general, FORCES[f].name);
            /* the drag's work, summed by the kernel on the one side and by
               tb__damping_power's passes on the other */
            fast_work = tb_world_work(fast).damping_work;
            general_work = tb_world_work(general).damping_work;
            assert_memory_equal(&fast_work, &general_work, sizeof fast_work);
            assert_memory_equal(fast->y + fast->off[TB__BODY_POS], general->y + general->off[TB__BODY_POS],
                                3 * 40 * sizeof(double));
            assert_memory_equal(fast->y + fast->off[TB__BODY_ROT], general->y + general->off[TB__BODY_ROT],
                                4 * 40 * sizeof(double));
            assert_memory_equal(fast->y + fast->off[TB__BODY_MOM], general->y + general->off[TB__BODY_MOM],
                                3 * 40 * sizeof(double));
            assert_memory_equal(fast->y + fast->off[TB__BODY_ANG], general->y + general->off[TB__BODY_ANG],
                                3 * 40 * sizeof(double));
            print_message("%-16s %-26s 100 steps of 333 particles and 40 bodies: the same bits "
                          "(drag's work %.17g J)\n", methods[m], FORCES[f].name, fast_work);
            tb_world_destroy(fast);
            tb_world_destroy(general);
        }
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(one_pass_gives_the_general_bits),
    cmocka_unit_test(split_steps_give_the_general_bits),
};
TB_TEST_MAIN(tests)
