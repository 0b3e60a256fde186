/* test_contacts_landings.c: bodies landing and coming to rest. Boxes
   dropped on the plane, heavy boxes on light ones (mass ratios up to
   10000), bodies dropped on bodies, a capsule landing beside a box far
   away, planks buried in the ground, and a resting box under every
   integrator. */
#include "test_main.h"
#include "tumble.h"
#include "contact_scenes.h"

#include <math.h>
#include <string.h>

/* The lowest and highest corner of box body id (half extents half, its
   shape at the body's centre) above the plane z = 0. */
static void corner_heights(tb_world *w, tb_body_id id, const double half[3], double *low, double *high)
{
    double x[3], q[4];
    int i;
    tb_body_position(w, id, x);
    tb_body_orientation(w, id, q);
    *low = INFINITY, *high = -INFINITY;
    for (i = 0; i < 8; ++i) {
        const double l[3] = { i & 1 ? half[0] : -half[0], i & 2 ? half[1] : -half[1], i & 4 ? half[2] : -half[2] };
        /* z of R(q) l */
        const double z = 2 * (q[1] * q[3] - q[0] * q[2]) * l[0] + 2 * (q[2] * q[3] + q[0] * q[1]) * l[1] +
                         (1 - 2 * (q[1] * q[1] + q[2] * q[2])) * l[2] + x[2];
        *low = fmin(*low, z), *high = fmax(*high, z);
    }
}

/* 40 unit cubes dropped on the plane one at a time, from up to 0.5 m,
   turned up to 0.8 rad about a tilted axis, restitution 0, 0.2 or 0.4,
   sleep off: after 5 s each lies on the plane, its lowest corner within
   1 um of it (measured at most 3.6e-11 m). The island solve pushes out
   every overlap and brings in-band gaps to touching (stack_solve.c,
   tb__stacks_push): pushing only beyond its touching band, it left cubes
   5 um into the plane or above it. */
static void dropped_boxes_lie_on_the_plane(void **state)
{
    double worst = 0;
    int k;
    (void)state;
    for (k = 0; k < 40; ++k) {
        tb_world *w = world_on_plane(0.6, 0);
        tb_body_def b = tb_default_body_def();
        tb_shape_def s = tb_default_shape_def();
        const double size[3] = { 1, 1, 1 }, turn = 0.02 * k;
        double low, high;
        int t;
        awake(w);
        assert_int_equal(tb_mass_box(1000, size, &b.mass, NULL), TB_OK);
        b.position[2] = 0.5 + 0.013 * k;
        b.orientation[0] = cos(turn / 2), b.orientation[1] = 0.6 * sin(turn / 2), b.orientation[2] = 0.8 * sin(turn / 2);
        assert_int_equal(tb_world_add_body(w, &b, &s.body), TB_OK);
        s.type = TB_SHAPE_BOX, s.half_extents[0] = s.half_extents[1] = s.half_extents[2] = 0.5;
        s.restitution = 0.2 * (k % 3);
        assert_int_equal(tb_world_add_shape(w, &s, NULL), TB_OK);
        for (t = 0; t < 300; ++t)
            assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
        corner_heights(w, s.body, s.half_extents, &low, &high);
        worst = fmax(worst, fabs(low));
        tb_world_destroy(w);
    }
    print_message("40 dropped cubes: lowest corners within %.2e m of the plane\n", worst);
    assert_below(worst, 1e-6);
}

/* A unit box `ratio` times the mass of the unit boxes under it (a column
   of `under` + 1 of 1 kg on the plane) dropped from `gap` above the top
   one, restitution 0, default settings, 10 s at 60 Hz: how fast the
   heavy box ever moved up after it landed, where it ends against its
   place on the column (m), how far any column box ever went below its
   place, and the fastest any box moved, by its step's displacement over
   the step, in the last 2 s. */
static void heavy_landing(double ratio, int under, double gap, int sleep, double *rebound, double *end,
                          double *sink, double *jitter)
{
    double last[10][3] = { { 0 } };
    tb_world *w = world_on_plane(0.6, 0);
    tb_body_id column[10], heavy;
    tb_body_def b = tb_default_body_def();
    tb_shape_def s = tb_default_shape_def();
    const double size[3] = { 1, 1, 1 }, top = 0.5 + under + 1;
    int i, k, landed = 0;
    if (!sleep)
        awake(w);
    for (k = 0; k <= under; ++k) {
        const double at[3] = { 0, 0, 0.5 + k };
        column[k] = add_box(w, at, 1, 0.6);
    }
    assert_int_equal(tb_mass_box(ratio, size, &b.mass, NULL), TB_OK);
    b.position[2] = top + gap;
    assert_int_equal(tb_world_add_body(w, &b, &heavy), TB_OK);
    s.type = TB_SHAPE_BOX;
    s.body = heavy;
    s.half_extents[0] = s.half_extents[1] = s.half_extents[2] = 0.5;
    assert_int_equal(tb_world_add_shape(w, &s, NULL), TB_OK);
    *rebound = 0, *sink = 0, *jitter = 0;
    for (i = 0; i < 10 * 60; ++i) {
        double x[3], v[3];
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
        tb_body_velocity(w, heavy, v);
        for (k = 0; k <= under + 1; ++k) { /* the column, then the heavy box */
            tb_body_position(w, k <= under ? column[k] : heavy, x);
            if (k <= under)
                *sink = fmax(*sink, 0.5 + k - x[2]);
            if (i >= 8 * 60)
                *jitter = fmax(*jitter, 60 * hypot(hypot(x[0] - last[k][0], x[1] - last[k][1]), x[2] - last[k][2]));
            memcpy(last[k], x, sizeof x);
        }
        landed |= x[2] < top + 0.01;
        if (landed)
            *rebound = fmax(*rebound, v[2]);
        *end = x[2] - top;
    }
    assert_true(landed);
    tb_world_destroy(w);
}

/* Sequential impulses pass a load between bodies of very different
   masses about one mass ratio's part a pass: left to them, a box 100
   times heavier dropped 0.5 m onto a light box on the ground goes
   through it (ODE's QuickStep, bench_contacts: sinks 8 cm; 1000 times
   heavier, through). Solved with its island (stack_solve.c) the landing
   is met whole. With restitution 0 the heavy box may not rise (bound: the
   sleep speed, 0.05 m/s), must end on the column within a fifth of the
   slop (1 mm), and no box under it may go below its place by more than
   that; at the end no box may jitter (moving faster than 1 mm/s, the
   resting box's bound). Mass ratios 3 to 10000 on one box from 0.1, 0.5
   and 2 m, 100 and 1000 on a column of four, sleep on (the default) and
   off (measured: rising at most 5.0e-11 m/s, ending within 2.9e-13 m of
   its place, light boxes at most 7.5e-14 m under theirs). */
static void heavy_box_lands_on_light_ones(void **state)
{
    static const struct {
        double ratio, gap;
        int under, sleep;
    } cases[] = { { 3, 0.5, 0, 1 },     { 3, 2, 0, 1 },       { 5, 0.5, 0, 1 },     { 5, 2, 0, 1 },
                  { 10, 0.1, 0, 1 },    { 10, 0.5, 0, 1 },    { 10, 2, 0, 1 },      { 100, 0.1, 0, 1 },
                  { 100, 0.5, 0, 1 },   { 100, 2, 0, 1 },     { 1000, 0.1, 0, 1 },  { 1000, 0.5, 0, 1 },
                  { 1000, 2, 0, 1 },    { 10000, 0.5, 0, 1 }, { 100, 0.5, 0, 0 },   { 1000, 0.5, 0, 0 },
                  { 10000, 0.5, 0, 0 }, { 100, 0.5, 3, 1 },   { 1000, 0.5, 3, 1 },  { 100, 0.5, 3, 0 } };
    const double slop = tb_default_contact_settings().slop;
    size_t i;
    (void)state;
    for (i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        double rebound, end, sink, jitter;
        heavy_landing(cases[i].ratio, cases[i].under, cases[i].gap, cases[i].sleep, &rebound, &end, &sink, &jitter);
        print_message("box %g times heavier dropped %g m on %d light (sleep %s): rose at %.2e m/s, ends %+.2e m from "
                      "its place, a light box went %.2e m under its own, fastest at the end %.2e m/s\n",
                      cases[i].ratio, cases[i].gap, cases[i].under + 1, cases[i].sleep ? "on" : "off", rebound, end,
                      sink, jitter);
        assert_below(rebound, 0.05);
        assert_below(fabs(end), 0.2 * slop);
        assert_below(sink, 0.2 * slop);
        assert_below(jitter, 1e-3);
    }
}

/* A unit box, or a ball of radius 0.5 m, of 1 kg dropped from gap onto a
   1 kg unit box on the plane, default settings, 5 s at 60 Hz: where it
   ends against resting on the box (m). */
static double dropped_on_a_box(double gap, int ball)
{
    tb_world *w = world_on_plane(0.6, 0);
    const double below[3] = { 0, 0, 0.5 }, above[3] = { 0, 0, 1.5 + gap };
    tb_body_id top;
    double x[3];
    int i;
    add_box(w, below, 1, 0.6);
    top = ball ? add_ball(w, above, 0.5, 0) : add_box(w, above, 1, 0.6);
    for (i = 0; i < 5 * 60; ++i)
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
    tb_body_position(w, top, x);
    tb_world_destroy(w);
    return x[2] - 1.5;
}

/* Boxes and balls dropped on a box come to rest on it: their touching
   points are solved with their island, rigid, so the truth, resting on
   it, is met to rounding (measured 0 m); bound: no gap over 1%
   of the slop, no overlap over the slop. */
static void bodies_dropped_on_bodies_rest_on_them(void **state)
{
    static const double gaps[] = { 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1, 2 };
    const double slop = tb_default_contact_settings().slop;
    size_t i;
    int ball;
    double most = 0, least = 0;
    (void)state;
    for (i = 0; i < sizeof gaps / sizeof gaps[0]; ++i)
        for (ball = 0; ball < 2; ++ball) {
            const double end = dropped_on_a_box(gaps[i], ball);
            most = fmax(most, end);
            least = fmin(least, end);
        }
    print_message("boxes and balls dropped 0.05 to 2 m on a box: from %.2e m into it to %.2e m above it\n", -least,
                  most);
    assert_below(most, 0.01 * slop);
    assert_below(-least, slop);
}

/* Manifolds that share no moving body are independent: a capsule falling
   tilted onto the plane, end first, must move to the bit the same with or
   without a box resting far away (nothing of one island's solve may reach
   another's). */
static tb_body_id drop_capsule(tb_world *w)
{
    tb_body_def b = tb_default_body_def();
    tb_shape_def s = tb_default_shape_def();
    const double turn = 0.3; /* rad about y: one end 0.12 m lower */
    tb_body_id id;
    assert_int_equal(tb_mass_capsule(1000, 0.1, 0.4, &b.mass, NULL), TB_OK);
    b.position[2] = 0.45;
    b.orientation[0] = cos(turn / 2), b.orientation[2] = sin(turn / 2);
    assert_int_equal(tb_world_add_body(w, &b, &id), TB_OK);
    s.type = TB_SHAPE_CAPSULE;
    s.body = id;
    s.radius = 0.1;
    s.half_length = 0.2;
    assert_int_equal(tb_world_add_shape(w, &s, NULL), TB_OK);
    return id;
}

static void far_box_leaves_a_capsule_alone(void **state)
{
    tb_world *alone = world_on_plane(0.6, 0), *beside = world_on_plane(0.6, 0);
    const double far[3] = { 10, 0, 0.5 };
    tb_body_id a, b;
    int i, k, touched = 0;
    (void)state;
    awake(alone);
    awake(beside);
    a = drop_capsule(alone);
    add_box(beside, far, 1, 0.6);
    b = drop_capsule(beside);
    for (i = 0; i < 60; ++i) {
        double xa[3], xb[3], qa[4], qb[4];
        assert_int_equal(tb_world_step(alone, 1.0 / 60), TB_OK);
        assert_int_equal(tb_world_step(beside, 1.0 / 60), TB_OK);
        tb_body_position(alone, a, xa), tb_body_position(beside, b, xb);
        tb_body_orientation(alone, a, qa), tb_body_orientation(beside, b, qb);
        for (k = 0; k < 3; ++k)
            assert_true(xa[k] == xb[k]);
        for (k = 0; k < 4; ++k)
            assert_true(qa[k] == qb[k]);
        touched += tb_world_contact_count(alone) > 0;
    }
    assert_true(touched > 30); /* it landed and lay there */
    tb_world_destroy(alone);
    tb_world_destroy(beside);
}

/* A plank of wood 4.06 m long, 0.54 m wide and 1.8 cm thick (1000 kg/m^3,
   39.5 kg), its centre `depth` under the plane and its length `tilt` rad
   off level. heavy: instead a heavy core, 145 kg with principal moments
   12, 5.8 and 8.4 kg m^2, far below the plank's own (a push at one end
   mostly turns it). */
static tb_body_id add_plank(tb_world *w, double depth, double tilt, int heavy)
{
    tb_body_def b = tb_default_body_def();
    tb_shape_def s = tb_default_shape_def();
    const double size[3] = { 4.06, 0.54, 0.018 };
    tb_body_id id;
    assert_int_equal(tb_mass_box(1000, size, &b.mass, NULL), TB_OK);
    if (heavy) {
        b.mass.mass = 145;
        b.mass.inertia[0] = 12, b.mass.inertia[1] = 5.8, b.mass.inertia[2] = 8.4;
    }
    b.position[2] = -depth;
    b.orientation[0] = cos(tilt / 2), b.orientation[2] = sin(tilt / 2);
    assert_int_equal(tb_world_add_body(w, &b, &id), TB_OK);
    s.type = TB_SHAPE_BOX;
    s.body = id;
    s.half_extents[0] = 2.03, s.half_extents[1] = 0.27, s.half_extents[2] = 0.009;
    assert_int_equal(tb_world_add_shape(w, &s, NULL), TB_OK);
    return id;
}

/* The lowest and highest of a plank's corners above the plane z = 0. */
static void plank_heights(tb_world *w, tb_body_id id, double *low, double *high)
{
    const double half[3] = { 2.03, 0.27, 0.009 };
    corner_heights(w, id, half, low, high);
}

/* The plank buried half a metre deep and 5 degrees off level, every
   corner under the surface, default settings: the contact pass pushes it
   out (at most max_push, 3 m/s) and it comes to lie flat on the plane.
   Speed alone does not show that it rests: a push of overlaps leaves it
   at zero while it lifts a body, and judged by speed alone the plank
   falls asleep with a corner 6.6 mm deep (a heavier one 0.4 m deep). So
   it must not sleep while any corner is deeper than the slop (5 mm), and
   after 5 s it lies asleep on the surface, within 0.1 mm of flat. */
static void buried_plank_comes_out_before_it_sleeps(void **state)
{
    (void)state;
    {
        tb_world *w = world_on_plane(0.6, 0);
        tb_body_id id = add_plank(w, 0.5, 5 * 3.14159265358979323846 / 180, 0);
        double low, high;
        int i, asleep;
        for (i = 0; i < 300; ++i) {
            assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
            assert_int_equal(tb_body_asleep(w, id, &asleep), TB_OK);
            plank_heights(w, id, &low, &high);
            if (asleep && low < -0.005)
                fail_msg("asleep at step %d with a corner %.4f m deep", i, -low);
        }
        print_message("buried plank after 5 s: corners from %.2e to %.5f m, asleep %d\n", low, high, asleep);
        assert_true(asleep);
        assert_below(fabs(low), 1e-4);
        assert_below(fabs(high - 0.018), 1e-4);
        tb_world_destroy(w);
    }
}

/* The plank with a heavy core, buried half a metre deep and 5 degrees off
   level (sleep off): its overlaps are pushed out together, levelled per
   patch (tb__stacks_push), so the plank comes out whole, as fast as the
   push allows (max_push, 3 m/s: 10 steps), and lies flat on the surface
   within 0.1 mm after 2 s. Rows per point alone meet its ends in turn,
   each push turning it and sinking the other end: it comes out by about
   1% of its depth a step, and is still 15 cm deep after 2 s. */
static void heavy_plank_comes_out_whole(void **state)
{
    tb_world *w = world_on_plane(0.6, 0);
    tb_body_id id = add_plank(w, 0.5, 5 * 3.14159265358979323846 / 180, 1);
    double low, high;
    int i;
    (void)state;
    awake(w);
    for (i = 0; i < 120; ++i)
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
    plank_heights(w, id, &low, &high);
    print_message("heavy-core plank after 2 s: corners from %.2e to %.5f m\n", low, high);
    assert_below(fabs(low), 1e-4);
    assert_below(fabs(high - 0.018), 1e-4);
    tb_world_destroy(w);
}

/* A body at rest stays put under every integrator: a body in contact
   moves by the substeps' leapfrog whatever the method, which takes only
   its free change of momentum from it. A cube set on the plane keeps its
   height within 0.1 mm and its speed under 1 mm/s for 2 s, and the
   plank laid flat 5 cm under the plane comes out to lie on it within 0.1
   mm in 3 s. (Sleep off: the solver's own resting.) */
static void every_integrator_keeps_a_resting_box_still(void **state)
{
    int m;
    (void)state;
    for (m = 0; m < tb_integrator_count(); ++m) {
        const char *name = tb_integrator_name(m);
        tb_world *w = world_on_plane(0.6, 0);
        const double at[3] = { 3, 0, 0.5 };
        tb_body_id cube, plank;
        double x[3], v[3], low, high;
        int i;
        assert_int_equal(tb_world_set_integrator(w, name), TB_OK);
        awake(w);
        cube = add_box(w, at, 1, 0.6);
        plank = add_plank(w, 0.05, 0, 0);
        for (i = 0; i < 180; ++i) {
            assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
            if (i == 119) {
                tb_body_position(w, cube, x);
                tb_body_velocity(w, cube, v);
                if (!(fabs(x[2] - 0.5) < 1e-4 && sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) < 1e-3))
                    fail_msg("%s: the cube at %.6f m, %.3g m/s", name, x[2],
                             sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
            }
        }
        plank_heights(w, plank, &low, &high);
        print_message("%-16s cube at %.7f m; plank corners from %.2e to %.7f m\n", name, x[2], low, high);
        if (!(fabs(low) < 1e-4 && fabs(high - 0.018) < 1e-4))
            fail_msg("%s: the plank's corners from %.4f to %.4f m", name, low, high);
        tb_world_destroy(w);
    }
}

/* The README's C example, as it is printed there: a default ball (1 kg,
   radius 0.5 m, restitution 0) dropped from 2 m onto the default plane, 120
   steps at 60 Hz; the README says it prints "z = 0.5000": on the ground,
   its centre one radius up, to the 4 decimals printed (bound 5e-5 m). It
   lands at 0.55 s and stays, since the default restitution is 0. */
static void readme_example_ball_ends_on_the_ground(void **state)
{
    tb_world_def def = tb_default_world_def();
    tb_shape_def ground = tb_default_shape_def(), s = tb_default_shape_def();
    tb_body_def b = tb_default_body_def();
    tb_body_id ball;
    tb_world *w;
    double x[3];
    int i;
    (void)state;
    assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
    ground.type = TB_SHAPE_PLANE;
    assert_int_equal(tb_world_add_shape(w, &ground, NULL), TB_OK);
    b.position[2] = 2;
    assert_int_equal(tb_world_add_body(w, &b, &ball), TB_OK);
    s.body = ball;
    assert_int_equal(tb_world_add_shape(w, &s, NULL), TB_OK);
    for (i = 0; i < 120; ++i)
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
    assert_int_equal(tb_body_position(w, ball, x), TB_OK);
    print_message("README example: z = %.4f m (%.3e from 0.5)\n", x[2], x[2] - 0.5);
    assert_below(fabs(x[2] - 0.5), 5e-5);
    tb_world_destroy(w);
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(dropped_boxes_lie_on_the_plane),
    cmocka_unit_test(buried_plank_comes_out_before_it_sleeps),
    cmocka_unit_test(heavy_plank_comes_out_whole),
    cmocka_unit_test(every_integrator_keeps_a_resting_box_still),
    cmocka_unit_test(heavy_box_lands_on_light_ones),
    cmocka_unit_test(bodies_dropped_on_bodies_rest_on_them),
    cmocka_unit_test(far_box_leaves_a_capsule_alone),
    cmocka_unit_test(readme_example_ball_ends_on_the_ground),
};

TB_TEST_MAIN(tests)
