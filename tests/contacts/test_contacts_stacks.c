/* test_contacts_stacks.c: stacks that stand. A column of ten, the same
   under changing steps, staircases and random offset stacks, asleep and
   awake, and the pyramid of reference/ode_contacts.h. */
#include "test_main.h"
#include "tumble.h"
#include "contact_scenes.h"
#include "ode_contacts.h"

#include <math.h>
#include <string.h>

/* Ten unit boxes stacked on the plane, 30 s at 60 Hz, awake, under the
   sweeps (substeps 0; the soft step's: test_contacts_soft.column_of_ten_stands):
   standing means every
   box upright within 0.1 rad and the top box within 2 cm of its height.
   Nothing pushes the column sideways, so it must also stay where it was
   put: every centre within 0.1 mm of the axis (measured 2.1e-5 m with the
   velocity pass's early stop, 1.1e-7 m with every sweep). Rows per
   contact point, met in turn, let it wander 2 cm in 30 s, neighbours 4 mm
   apart; the contact patch's tilt rows hold it. */
static void stack_of_ten_stands(void **state)
{
    tb_world *w = world_on_plane(0.6, 0);
    tb_body_id ids[10];
    double worst = 0, top[3], below[3] = { 0, 0, 0 }, step_off = 0;
    int i, k;
    (void)state;
    awake(w);
    sweeps(w);
    for (k = 0; k < 10; ++k) {
        const double at[3] = { 0, 0, 0.5 + k };
        ids[k] = add_box(w, at, 1, 0.6);
    }
    for (i = 0; i < 30 * 60; ++i)
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
    for (k = 0; k < 10; ++k) {
        double x[3], q[4];
        tb_body_position(w, ids[k], x);
        tb_body_orientation(w, ids[k], q);
        worst = fmax(worst, hypot(x[0], x[1]));
        if (k > 0)
            step_off = fmax(step_off, hypot(x[0] - below[0], x[1] - below[1]));
        memcpy(below, x, sizeof below);
        assert_below(2 * asin(fmin(1, sqrt(q[1] * q[1] + q[2] * q[2]))), 0.1);
    }
    tb_body_position(w, ids[9], top);
    print_message("stack of 10 after 30 s: column wandered %.2e m, largest offset between neighbours %.2e m, top box "
                  "at %.4f m (started 9.5)\n", worst, step_off, top[2]);
    assert_below(worst, 1e-4);
    assert_below(step_off, 1e-4);
    assert_below(fabs(top[2] - 9.5), 0.02);
    tb_world_destroy(w);
}

/* The column stepped at 1/30 s and 1/90 s in turn, as a game's frame
   times might come, must stand as still as stepped at 1/30 s throughout:
   both within 1 um of where they were put (measured 6e-17 and 0 m).
   Last step's impulses are a force times last step's h, so they start
   this step scaled to its h (as Box2D's dtRatio): kept as they are, a
   step of a third starts from three times the force, and the column ends
   6.1e-4 m off (stepped at 0.1 and 0.033 s, 0.3 m). */
static void column_stands_under_changing_steps(void **state)
{
    const double steady = column_after(1.0 / 30, 0, 0), changing = column_after(1.0 / 30, 1, 0);
    (void)state;
    print_message("column of 10 after 10 s: worst box %.2e m off at 1/30 s, %.2e m at 1/30 and 1/90 s in turn\n",
                  steady, changing);
    assert_below(steady, 1e-6);
    assert_below(changing, 1e-6);
}

/* A stack of n boxes (half extents half[i], 500 kg/m^3) built touching
   on the plane, each centred at (x, y) = at[i] and on the one below;
   stepped for steps at 60 Hz, sleep off unless sleep. Returns how far any
   box got from where it was put; every_sweep: velocity_tolerance 0;
   stack: the stack_iterations. Under the sweeps (substeps 0), whose
   mechanisms these tests guard; the soft step's offset stacks are
   test_contacts_soft.offset_tower_stands.
   Checks first that it stands statically:
   what rests on each box has its centre of mass over that box's top face
   (returned in *margin: by how much at the least). */
#define STACK_MOST 8
static double offset_stack(int n, const double (*half)[3], const double (*at)[2], int sleep, int every_sweep,
                           int stack, int steps, double *margin)
{
    tb_world *w = world_on_plane(0.6, 0);
    tb_contact_settings cs = tb_world_contact_settings(w);
    tb_body_id ids[STACK_MOST];
    double base[STACK_MOST], mass[STACK_MOST], worst = 0, z = 0;
    int i, j;
    cs.sleep_time = sleep ? cs.sleep_time : INFINITY;
    cs.velocity_tolerance = every_sweep ? 0 : cs.velocity_tolerance;
    cs.stack_iterations = stack;
    cs.substeps = 0;
    assert_int_equal(tb_world_set_contact_settings(w, &cs), TB_OK);
    *margin = INFINITY;
    for (i = 0; i < n; ++i) {
        tb_body_def b = tb_default_body_def();
        tb_shape_def s = tb_default_shape_def();
        const double size[3] = { 2 * half[i][0], 2 * half[i][1], 2 * half[i][2] };
        assert_int_equal(tb_mass_box(500, size, &b.mass, NULL), TB_OK);
        mass[i] = b.mass.mass;
        b.position[0] = at[i][0], b.position[1] = at[i][1], b.position[2] = base[i] = z + half[i][2];
        z += size[2];
        assert_int_equal(tb_world_add_body(w, &b, &ids[i]), TB_OK);
        s.type = TB_SHAPE_BOX, s.body = ids[i];
        memcpy(s.half_extents, half[i], sizeof s.half_extents);
        assert_int_equal(tb_world_add_shape(w, &s, NULL), TB_OK);
    }
    for (i = 0; i + 1 < n; ++i) {
        double above = 0, centre[2] = { 0, 0 };
        for (j = i + 1; j < n; ++j) {
            above += mass[j];
            centre[0] += mass[j] * at[j][0], centre[1] += mass[j] * at[j][1];
        }
        for (j = 0; j < 2; ++j)
            *margin = fmin(*margin, half[i][j] - fabs(centre[j] / above - at[i][j]));
    }
    for (i = 0; i < steps; ++i)
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
    for (i = 0; i < n; ++i) {
        double x[3];
        tb_body_position(w, ids[i], x);
        worst = fmax(worst, sqrt((x[0] - at[i][0]) * (x[0] - at[i][0]) + (x[1] - at[i][1]) * (x[1] - at[i][1]) +
                                 (x[2] - base[i]) * (x[2] - base[i])));
    }
    tb_world_destroy(w);
    return worst;
}

/* Staircases of boxes 0.6 x 0.6 x 0.4 m, sleep off, 10 s: 5 boxes each
   10 cm along x from the one under it, and 8 each 5 cm along x and y.
   Statically they stand (by 5 and 10 cm), so the truth is still: every
   box within 1 mm of where it was put (measured 2e-18 and 3e-17 m). What
   holds them up:
   - sequential impulses carry the moments that hold an offset stack up
     from the top box to the ground patch by patch, and a cold first step
     gives the staircase of 8 along x 4% of the moment its ground needs:
     it rocks onto edges and falls. So the first step's normal rows are
     solved together (cold_start.c);
   - boxes built 1e-16 m apart fall together in the free motion, so their
     gap never closes within the step: such a point rests. Timed as a
     landing, it would act on positions for no time, and in the first step
     each box of the diagonal staircase would rise or sink by up to 1 cm;
   - the press acts where last step's normal force was centred (shift in
     contacts.h), the tilts' ranges measured from there.
   The staircase of 8 runs again with every sweep done (velocity_tolerance
   0): the first step's conjugate gradients must stop at rounding there,
   since run past it they throw the staircase 1e12 m. */
static void staircases_stand_still(void **state)
{
    double half[STACK_MOST][3], at[STACK_MOST][2], margin, five, eight, every;
    int i;
    (void)state;
    for (i = 0; i < STACK_MOST; ++i) {
        half[i][0] = half[i][1] = 0.3, half[i][2] = 0.2;
        at[i][0] = 0.1 * i, at[i][1] = 0;
    }
    five = offset_stack(5, (const double(*)[3])half, (const double(*)[2])at, 0, 0, 0, 600, &margin);
    assert_true(margin >= 0.05 - 1e-12);
    for (i = 0; i < STACK_MOST; ++i)
        at[i][0] = at[i][1] = 0.05 * i;
    eight = offset_stack(8, (const double(*)[3])half, (const double(*)[2])at, 0, 0, 0, 600, &margin);
    assert_true(margin >= 0.1 - 1e-12);
    every = offset_stack(8, (const double(*)[3])half, (const double(*)[2])at, 0, 1, 0, 600, &margin);
    print_message("staircases after 10 s: worst box %.3e m (5 at 10 cm), %.3e m (8 at 5 cm diagonal), "
                  "%.3e m (the same, every sweep)\n", five, eight, every);
    assert_below(five, 1e-3);
    assert_below(eight, 1e-3);
    assert_below(every, 1e-3);
}

/* A stack of STACK_MOST boxes of random sizes (half extents 0.15 to 0.5 m
   across, 0.1 to 0.4 m high), each offset from the one below by up to a
   quarter of the smaller of the two across: it stands statically. */
static void random_stack(uint64_t *seed, double (*half)[3], double (*at)[2])
{
    int i, d;
    for (i = 0; i < STACK_MOST; ++i) {
        half[i][0] = 0.15 + 0.35 * uniform(seed);
        half[i][1] = 0.15 + 0.35 * uniform(seed);
        half[i][2] = 0.1 + 0.3 * uniform(seed);
        for (d = 0; d < 2; ++d)
            at[i][d] = i == 0 ? 0 : at[i - 1][d] + (uniform(seed) - 0.5) * 0.5 * fmin(half[i - 1][d], half[i][d]);
    }
}

/* count random stacks of 8 (random_stack) from seed, each stepped by
   offset_stack (sleep, stack iterations, steps): how far any box of any
   of them got from where it was put; *least: by how much the least
   stable of them stands statically. */
static double random_stacks(uint64_t seed, int count, int sleep, int stack, int steps, double *least)
{
    double worst = 0;
    int i;
    *least = INFINITY;
    for (i = 0; i < count; ++i) {
        double half[STACK_MOST][3], at[STACK_MOST][2], margin;
        random_stack(&seed, half, at);
        worst = fmax(worst, offset_stack(STACK_MOST, (const double(*)[3])half, (const double(*)[2])at, sleep, 0, stack,
                                         steps, &margin));
        *least = fmin(*least, margin);
    }
    return worst;
}

/* 12 random stacks of 8 (random_stack), each standing statically by 5 cm
   at the least, with the default settings (sleep on), 10 s: every box
   within 1 mm of where it was put (measured 2e-11 m). The cold start
   (cold_start.c) holds them: without it 9 of the 12 fall. */
static void random_offset_stacks_stand(void **state)
{
    double least;
    const double worst = random_stacks(12345, 12, 1, 0, 600, &least);
    (void)state;
    print_message("12 random offset stacks of 8 after 10 s: worst box %.3e m (statically standing by %.3f m at the least)\n",
                  worst, least);
    assert_true(least > 0.05);
    assert_below(worst, 1e-3);
}

/* 40 random stacks of 8 (random_stack) kept awake (sleep off) for 30 s
   with 8 stack iterations a step. Statically each stands (by 5 cm at the
   least), so every box stays where it was put: within a micron (measured
   2.3e-12 m). With the sweeps alone (stack_iterations 0, the default), a
   lean of a whole stack grows from rounding, by 2 to 3% a step (the
   sweeps reduce it slowest), until the stack falls: 3 of the 40 from 10 s
   or so on; one of them at 40 s even with every sweep of 20 done. The
   stack iterations run at every step, even where the warm starts leave
   every row within velocity_tolerance, as a stack at rest always does:
   skipping them there lets boxes move up to 7.4e-5 m, growing (with 4
   iterations one stack can fall, at 38 s under some rounding). Run at
   every step, 4 still let a lean grow, 80-fold in 6 s up to 1.4e-4 m in
   60 s; 8 hold it. */
static void awake_offset_stacks_stay_up_with_stack_iterations(void **state)
{
    double least;
    const double worst = random_stacks(777, 40, 0, 8, 1800, &least);
    (void)state;
    print_message("40 random offset stacks of 8 awake for 30 s, 8 stack iterations: worst box %.3e m\n", worst);
    assert_true(least > 0);
    assert_below(worst, 1e-6);
}

/* The pyramid (reference/ode_contacts.h's layout: 20 levels, 210
   unit cubes 1 cm apart, mu 0.6), 10 s at 60 Hz, under the default soft
   step and under the sweeps (substeps 0) with every sweep done
   (velocity_tolerance 0). It must fall asleep, and its top cube end
   within 1 cm of where it started across (the bound), no cube 2
   cm. Down, the rigid truth is no sink at all:
   - the sweeps solve the island's rows rigidly, so no cube sinks 1 cm
     (measured 1.7e-5 m; ODE's top cube sinks 5 cm). Their first step's
     conjugate gradients must stop at rounding, since run past it they
     throw the pyramid 1e12 m.
   - the soft step's island is too wide to solve together, and its rows
     hold each point's load at an overlap of the load over m_eff omega^2
     (0.28 mm a cube's weight at 30 Hz), summed up the 20 levels: the top
     sinks 2.71 cm (Box3D 2.76 cm on the same pyramid; docs/notes.md,
     "Wide islands under soft rows"). The bound, 3 cm, is that compliance
     and guards it from growing; it misses the truth, as docs/contacts.md
     says. */
static void pyramid_stands_and_sleeps(void **state)
{
    const ode_pyramid_def d = ode_default_pyramid_def();
    const int count = ode_pyramid_boxes(d.levels);
    double(*pos)[3] = test_malloc((size_t)count * sizeof *pos);
    tb_body_id *ids = test_malloc((size_t)count * sizeof *ids);
    int i, sweeps;
    (void)state;
    assert_int_equal(ode_pyramid_positions(&d, pos), count);
    for (sweeps = 0; sweeps < 2; ++sweeps) {
        tb_world *w = world_on_plane(d.mu, 0);
        tb_contact_settings cs = tb_world_contact_settings(w);
        double worst = 0, sink = 0, top = 0;
        int asleep_at = -1;
        if (sweeps)
            cs.substeps = 0, cs.velocity_tolerance = 0;
        assert_int_equal(tb_world_set_contact_settings(w, &cs), TB_OK);
        for (i = 0; i < count; ++i)
            ids[i] = add_box(w, pos[i], d.edge, d.mu);
        for (i = 0; i < (int)(d.duration * d.hz); ++i) {
            assert_int_equal(tb_world_step(w, 1 / d.hz), TB_OK);
            if (asleep_at < 0 && tb_world_sleeping_count(w) == (size_t)count)
                asleep_at = i + 1;
        }
        for (i = 0; i < count; ++i) {
            double x[3], across;
            tb_body_position(w, ids[i], x);
            across = hypot(x[0] - pos[i][0], x[1] - pos[i][1]);
            worst = fmax(worst, across);
            sink = fmax(sink, pos[i][2] - x[2]);
            if (i == count - 1)
                top = across;
        }
        print_message("pyramid of %d (%s): asleep after %d steps, top cube moved %.2e m across, most any cube "
                      "%.2e m, deepest sink %.2e m\n", count, sweeps ? "sweeps, every sweep" : "soft step", asleep_at,
                      top, worst, sink);
        assert_in_range(asleep_at, 1, (int)(d.duration * d.hz));
        assert_below(sink, sweeps ? 0.01 : 0.03);
        assert_below(top, 0.01);
        assert_below(worst, 0.02);
        tb_world_destroy(w);
    }
    test_free(pos);
    test_free(ids);
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(pyramid_stands_and_sleeps),
    cmocka_unit_test(stack_of_ten_stands),
    cmocka_unit_test(staircases_stand_still),
    cmocka_unit_test(random_offset_stacks_stand),
    cmocka_unit_test(awake_offset_stacks_stay_up_with_stack_iterations),
    cmocka_unit_test(column_stands_under_changing_steps),
};

TB_TEST_MAIN(tests)
