/* test_contacts_stacks.c: stacks that stand. A column of ten, the same
   under changing steps, staircases and random offset stacks, asleep and
   awake, and the pyramid of reference/ode_contacts.h. */
#include "test_main.h"
#include "tumble.h"
#include "contact_scenes.h"
#include "ode_contacts.h"

#include <math.h>
#include <string.h>

/* Ten unit boxes stacked on the plane, 30 s at 60 Hz, awake (10 s with
   tighter bounds: test_contacts_soft.column_of_ten_stands): standing
   means every box upright within 0.1 rad and the top box within 2 cm of
   its height. Nothing pushes the column sideways, so it must also stay
   where it was put: every centre within 0.1 mm of the axis (measured
   4.3e-16 m). */
static void stack_of_ten_stands(void **state)
{
    tb_world *w = world_on_plane(0.6, 0);
    tb_body_id ids[10];
    double worst = 0, top[3], below[3] = { 0, 0, 0 }, step_off = 0;
    int i, k;
    (void)state;
    awake(w);
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

/* A stack of n boxes (half extents half[i], 500 kg/m^3) built touching
   on the plane, each centred at (x, y) = at[i] and on the one below;
   stepped for steps at 60 Hz, sleep off unless sleep. Returns how far any
   box got from where it was put. Checks first that it stands statically:
   what rests on each box has its centre of mass over that box's top face
   (returned in *margin: by how much at the least). */
#define STACK_MOST 8
static double offset_stack(int n, const double (*half)[3], const double (*at)[2], int sleep, int steps,
                           double *margin)
{
    tb_world *w = world_on_plane(0.6, 0);
    tb_contact_settings cs = tb_world_contact_settings(w);
    tb_body_id ids[STACK_MOST];
    double base[STACK_MOST], mass[STACK_MOST], worst = 0, z = 0;
    int i, j;
    cs.sleep_time = sleep ? cs.sleep_time : INFINITY;
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
   box within 1 mm of where it was put (measured 1.5e-17 and 2.2e-12 m). Patch
   by patch, rows carry the moments that hold an offset stack up from the
   top box to the ground slowly, and a cold first step gives the
   staircase of 8 along x 4% of the moment its ground needs: it rocks onto
   edges and falls. A stack's island is solved together (stack_solve.c). */
static void staircases_stand_still(void **state)
{
    double half[STACK_MOST][3], at[STACK_MOST][2], margin, five, eight;
    int i;
    (void)state;
    for (i = 0; i < STACK_MOST; ++i) {
        half[i][0] = half[i][1] = 0.3, half[i][2] = 0.2;
        at[i][0] = 0.1 * i, at[i][1] = 0;
    }
    five = offset_stack(5, (const double(*)[3])half, (const double(*)[2])at, 0, 600, &margin);
    assert_true(margin >= 0.05 - 1e-12);
    for (i = 0; i < STACK_MOST; ++i)
        at[i][0] = at[i][1] = 0.05 * i;
    eight = offset_stack(8, (const double(*)[3])half, (const double(*)[2])at, 0, 600, &margin);
    assert_true(margin >= 0.1 - 1e-12);
    print_message("staircases after 10 s: worst box %.3e m (5 at 10 cm), %.3e m (8 at 5 cm diagonal)\n", five, eight);
    assert_below(five, 1e-3);
    assert_below(eight, 1e-3);
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
   offset_stack (sleep, steps): how far any box of any
   of them got from where it was put; *least: by how much the least
   stable of them stands statically. */
static double random_stacks(uint64_t seed, int count, int sleep, int steps, double *least)
{
    double worst = 0;
    int i;
    *least = INFINITY;
    for (i = 0; i < count; ++i) {
        double half[STACK_MOST][3], at[STACK_MOST][2], margin;
        random_stack(&seed, half, at);
        worst = fmax(worst, offset_stack(STACK_MOST, (const double(*)[3])half, (const double(*)[2])at, sleep, steps,
                                         &margin));
        *least = fmin(*least, margin);
    }
    return worst;
}

/* 12 random stacks of 8 (random_stack), each standing statically by 5 cm
   at the least, with the default settings (sleep on), 10 s: every box
   within 1 mm of where it was put (measured 6.1e-5 m). */
static void random_offset_stacks_stand(void **state)
{
    double least;
    const double worst = random_stacks(12345, 12, 1, 600, &least);
    (void)state;
    print_message("12 random offset stacks of 8 after 10 s: worst box %.3e m (statically standing by %.3f m at the least)\n",
                  worst, least);
    assert_true(least > 0.05);
    assert_below(worst, 1e-3);
}

/* 40 random stacks of 8 (random_stack) kept awake (sleep off) for 30 s.
   Statically each stands (by 5 cm at the least), so the truth is that
   every box stays where it was put. Sequential impulses alone let a lean
   of a whole stack grow from rounding, by 2 to 3% a step, until the
   stack falls (the sweeps: 3 of the 40 from 10 s or so on); solved with
   its island (stack_solve.c) none falls. Bound: issue 18's for towers
   with placement errors, 1 cm, here for any box and over 30 s (measured
   2.0e-3 m: one stack's top box ratchets as a point under it lets go and
   comes back every 3 s, its island's twist slipping patch by patch:
   docs/contacts.md, "Known limits"; 12 of the 40 stay within 1e-6 m). */
static void awake_offset_stacks_stand(void **state)
{
    double least;
    const double worst = random_stacks(777, 40, 0, 1800, &least);
    (void)state;
    print_message("40 random offset stacks of 8 awake for 30 s: worst box %.3e m\n", worst);
    assert_true(least > 0);
    assert_below(worst, 0.01);
}

/* The pyramid (reference/ode_contacts.h's layout: 20 levels, 210
   unit cubes 1 cm apart, mu 0.6), 10 s at 60 Hz. It must fall asleep,
   and its top cube end within 1 cm of where it started (the issue's
   bound) across and down, no cube 2 cm across. Down, the rigid truth is
   no sink at all (ODE's top cube sinks 5 cm), but the island is too wide
   to solve together, and its rows hold each point's load at an overlap
   of the load over m_eff omega^2, summed up the 20 levels: 2.71 cm at the
   step's 4 substeps and 30 Hz (Box3D 2.76 cm on the same pyramid;
   docs/notes.md, "Wide islands under soft rows"); stepped apart at twice
   the rate and stiffness (soft_step.c, WIDE_RATE), 7.17 mm. */
static void pyramid_stands_and_sleeps(void **state)
{
    const ode_pyramid_def d = ode_default_pyramid_def();
    const int count = ode_pyramid_boxes(d.levels);
    double(*pos)[3] = test_malloc((size_t)count * sizeof *pos);
    tb_body_id *ids = test_malloc((size_t)count * sizeof *ids);
    int i;
    (void)state;
    assert_int_equal(ode_pyramid_positions(&d, pos), count);
    {
        tb_world *w = world_on_plane(d.mu, 0);
        double worst = 0, sink = 0, top = 0;
        int asleep_at = -1;
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
        print_message("pyramid of %d: asleep after %d steps, top cube moved %.2e m across, most any cube "
                      "%.2e m, deepest sink %.2e m\n", count, asleep_at, top, worst, sink);
        assert_in_range(asleep_at, 1, (int)(d.duration * d.hz));
        assert_below(sink, 0.01);
        assert_below(top, 0.01);
        assert_below(worst, 0.02);
        tb_world_destroy(w);
    }
    test_free(pos);
    test_free(ids);
}

/* A running-bond wall of `courses` x `per` bricks (0.4 x 0.2 x 0.2 m,
   2 kg, mu 0.6) along x on the plane, each course shifted a quarter
   brick from the one below: ids and start positions out. */
static void add_wall(tb_world *w, int courses, int per, tb_body_id *ids, double (*start)[3])
{
    const double brick[3] = { 0.4, 0.2, 0.2 };
    int c, i;
    for (c = 0; c < courses; ++c)
        for (i = 0; i < per; ++i) {
            tb_body_def b = tb_default_body_def();
            tb_shape_def s = tb_default_shape_def();
            double *x = start[per * c + i];
            x[0] = (i - (per - 1) / 2.0 + (c % 2 ? 0.25 : 0)) * brick[0], x[1] = 0, x[2] = (c + 0.5) * brick[2];
            assert_int_equal(tb_mass_box(125, brick, &b.mass, NULL), TB_OK); /* 2 kg */
            memcpy(b.position, x, sizeof b.position);
            assert_int_equal(tb_world_add_body(w, &b, &ids[per * c + i]), TB_OK);
            s.type = TB_SHAPE_BOX, s.body = ids[per * c + i];
            s.half_extents[0] = 0.2, s.half_extents[1] = s.half_extents[2] = 0.1;
            assert_int_equal(tb_world_add_shape(w, &s, NULL), TB_OK);
        }
}

/* How far brick k of a wall moved from start[k] (m) */
static double brick_moved(tb_world *w, tb_body_id id, const double start[3])
{
    double x[3];
    tb_body_position(w, id, x);
    return sqrt((x[0] - start[0]) * (x[0] - start[0]) + (x[1] - start[1]) * (x[1] - start[1]) +
                (x[2] - start[2]) * (x[2] - start[2]));
}

/* A wall of 150 bricks in 15 courses of 10 (add_wall), kept awake 20 s:
   nothing pushes it, so it must stand, the top course within 1 cm of
   where it was built (issue 18's figure for walls). On soft rows a course
   resists a tilt by a stiffness that does not grow with the load above
   it, and at the step's own rate the wall sank 3.1 cm and buckled,
   falling at 4 s (bench_robustness tallwall; docs/notes.md, "Wide
   islands under soft rows"); its island, too wide to solve together, is
   stepped at twice the rate and stiffness (soft_step.c, WIDE_RATE):
   measured 9.2 mm, nearly all of it the courses' sink. */
static void tall_wall_stands(void **state)
{
    tb_world *w = world_on_plane(0.6, 0);
    tb_body_id ids[150];
    double start[150][3], most = 0;
    int i, k;
    (void)state;
    awake(w);
    add_wall(w, 15, 10, ids, start);
    for (i = 0; i < 20 * 60; ++i)
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
    for (k = 140; k < 150; ++k)
        most = fmax(most, brick_moved(w, ids[k], start[k]));
    print_message("wall of 15 courses of 10, awake 20 s: top course moved %.2e m at the most\n", most);
    assert_below(most, 0.01);
    tb_world_destroy(w);
}

/* A wall of 105 bricks in 7 courses of 15 (add_wall), default settings,
   struck at the middle of its second course by a 10 kg ball (r 0.15 m,
   mu 0.6, restitution 0) at 5 m/s (125 J), or pushed there at 0.52 m/s
   (1.35 J, against the 10.3 J that tipping the wall over needs), 10 s.
   The blow reaches the bricks the ball touches: it spans the three lowest
   courses and at most two bricks of each, so at most 6 bricks may move
   more than 5 cm (measured 2); the push moves none (measured 0). Neither
   may add energy: the total never above its start by more than lifting
   every body 0.1 mm (measured: always below it, by at least lifting every
   body 0.49 mm, the courses settling into their soft overlaps). The solver before the soft
   step lost one brick and then the whole wall 2 s later, and under the
   push rocked the wall harder and harder until it fell at 7 s, its
   energy rising above the start. */
static void struck_wall(double speed, int *moved, double *gained)
{
    tb_world *w = world_on_plane(0.6, 0);
    tb_body_def b = tb_default_body_def();
    tb_shape_def s = tb_default_shape_def();
    tb_body_id ids[105];
    double start[105][3], e0, weight;
    int i, k;
    add_wall(w, 7, 15, ids, start);
    assert_int_equal(tb_mass_sphere(1000, 0.15, &b.mass, NULL), TB_OK);
    assert_int_equal(tb_mass_set_total(&b.mass, 10, NULL), TB_OK);
    b.position[1] = -1, b.position[2] = 0.3, b.velocity[1] = speed;
    assert_int_equal(tb_world_add_body(w, &b, &s.body), TB_OK);
    s.type = TB_SHAPE_SPHERE, s.radius = 0.15;
    assert_int_equal(tb_world_add_shape(w, &s, NULL), TB_OK);
    weight = (105 * 2 + 10) * G;
    e0 = tb_world_energy(w).total;
    *gained = -INFINITY;
    for (i = 0; i < 10 * 60; ++i) {
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
        *gained = fmax(*gained, tb_world_energy(w).total - e0);
    }
    *moved = 0;
    for (k = 0; k < 105; ++k)
        *moved += brick_moved(w, ids[k], start[k]) > 0.05;
    *gained /= weight; /* as lifting every body (m) */
    tb_world_destroy(w);
}

static void struck_wall_loses_only_what_the_blow_reaches(void **state)
{
    int moved, pushed;
    double gained, push_gained;
    (void)state;
    struck_wall(5, &moved, &gained);
    struck_wall(0.52, &pushed, &push_gained);
    print_message("wall of 7 courses of 15: struck at 5 m/s, %d bricks moved, energy at most %.2e m of lift above "
                  "the start; pushed at 0.52 m/s, %d moved, %.2e m\n", moved, gained, pushed, push_gained);
    assert_true(moved <= 6);
    assert_int_equal(pushed, 0);
    assert_below(gained, 1e-4);
    assert_below(push_gained, 1e-4);
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(pyramid_stands_and_sleeps),
    cmocka_unit_test(stack_of_ten_stands),
    cmocka_unit_test(staircases_stand_still),
    cmocka_unit_test(random_offset_stacks_stand),
    cmocka_unit_test(awake_offset_stacks_stand),
    cmocka_unit_test(tall_wall_stands),
    cmocka_unit_test(struck_wall_loses_only_what_the_blow_reaches),
};

TB_TEST_MAIN(tests)
