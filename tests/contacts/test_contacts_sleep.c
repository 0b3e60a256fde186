/* test_contacts_sleep.c: sleep. A resting box falls asleep and stays
   put, sleeping bodies wake when something lands on them, is removed from
   under them or changes their motion, islands wake together, sleeping
   pairs are kept and come back as they were, and the sleep settings are
   checked. */
#include "test_main.h"
#include "tumble.h"
#include "contact_scenes.h"

#include <math.h>
#include <string.h>

/* Steps until body id sleeps, at most `limit` steps; returns the steps taken. */
static int steps_to_sleep(tb_world *w, tb_body_id id, int limit)
{
    int n, asleep = 0;
    for (n = 0; n < limit && !asleep; ++n) {
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
        assert_int_equal(tb_body_asleep(w, id, &asleep), TB_OK);
    }
    return n;
}

/* A box set down on the plane rests at once (its speed after a step is
   gravity's kick undone to rounding), so it sleeps after sleep_time, 0.5 s:
   30 steps at 60 Hz, plus the one that starts the count. Asleep, its pose
   must not change by a bit over 5 s, its momenta are zero, and its 4
   contact points are still reported. */
static void resting_box_falls_asleep_and_stays_put(void **state)
{
    tb_world *w = world_on_plane(0.6, 0);
    const double at[3] = { 0, 0, 0.5 };
    tb_body_id id = add_box(w, at, 1, 0.6);
    double x0[3], q0[4], x[3], q[4], P[3], L[3];
    int n, i;
    (void)state;
    n = steps_to_sleep(w, id, 120);
    print_message("resting box asleep after %d steps\n", n);
    assert_in_range(n, 30, 32);
    assert_int_equal(tb_world_sleeping_count(w), 1);
    tb_body_position(w, id, x0);
    tb_body_orientation(w, id, q0);
    for (i = 0; i < 300; ++i)
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
    tb_body_position(w, id, x);
    tb_body_orientation(w, id, q);
    tb_body_momentum(w, id, P, L);
    assert_memory_equal(x, x0, sizeof x);
    assert_memory_equal(q, q0, sizeof q);
    assert_true(P[0] == 0 && P[1] == 0 && P[2] == 0 && L[0] == 0 && L[1] == 0 && L[2] == 0);
    assert_int_equal(tb_world_contact_count(w), 4);
    assert_rel(x[2], 0.5, 1e-9);
    tb_world_destroy(w);
}

/* A ball dropped on a sleeping box wakes it when its bounds reach the box,
   and lands on it: it must come to rest on the top face (z = 1 + r within
   the 5 mm slop), never inside the box; and rest on it, not on a gap:
   within 0.1 mm (measured 0 m to the printed 1e-7 m). Then both sleep
   again. */
static void sleeping_box_wakes_when_a_ball_lands(void **state)
{
    tb_world *w = world_on_plane(0.6, 0);
    const double at[3] = { 0, 0, 0.5 }, drop[3] = { 0.2, 0, 2 };
    tb_body_id box = add_box(w, at, 1, 0.6), ball;
    double x[3], lowest = INFINITY;
    int asleep, woke = 0, i;
    (void)state;
    steps_to_sleep(w, box, 120);
    ball = add_ball(w, drop, 0.1, 0);
    for (i = 0; i < 180; ++i) {
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
        assert_int_equal(tb_body_asleep(w, box, &asleep), TB_OK);
        woke |= !asleep;
        tb_body_position(w, ball, x);
        lowest = fmin(lowest, x[2]);
    }
    tb_body_position(w, ball, x);
    print_message("ball on a sleeping box: box woke %d, ball's lowest centre %.5f m, last %.7f m (top face + r = "
                  "1.1)\n", woke, lowest, x[2]);
    assert_true(woke);
    assert_true(lowest > 1.1 - 0.005);
    assert_true(fabs(x[2] - 1.1) < 1e-4);
    steps_to_sleep(w, ball, 120);
    assert_int_equal(tb_world_sleeping_count(w), 2);
    tb_world_destroy(w);
}

/* Two boxes stacked sleep as one island. Setting the lower one's velocity
   wakes both; removing the lower one (asleep again) wakes the upper one,
   which must then fall to the plane: centre at 0.5 within the slop. */
static void islands_wake_together(void **state)
{
    tb_world *w = world_on_plane(0.6, 0);
    const double at0[3] = { 0, 0, 0.5 }, at1[3] = { 0, 0, 1.5 }, push[3] = { 0.01, 0, 0 };
    tb_body_id low = add_box(w, at0, 1, 0.6), high = add_box(w, at1, 1, 0.6);
    double x[3];
    int asleep, i;
    (void)state;
    steps_to_sleep(w, high, 240);
    assert_int_equal(tb_world_sleeping_count(w), 2);
    assert_int_equal(tb_body_set_velocity(w, low, push), TB_OK);
    assert_int_equal(tb_body_asleep(w, high, &asleep), TB_OK);
    assert_false(asleep);
    assert_int_equal(tb_world_sleeping_count(w), 0);
    steps_to_sleep(w, high, 240);
    assert_int_equal(tb_world_sleeping_count(w), 2);
    assert_int_equal(tb_world_remove_body(w, low), TB_OK);
    assert_int_equal(tb_body_asleep(w, high, &asleep), TB_OK);
    assert_false(asleep);
    for (i = 0; i < 120; ++i)
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
    tb_body_position(w, high, x);
    assert_true(fabs(x[2] - 0.5) < 0.005);
    tb_world_destroy(w);
}

/* Two boxes 3 mm apart (within each other's bounds, not touching: two
   islands), the second dropped from 10 cm, so it comes to rest later.
   The first falls asleep while the second still rests awake beside it;
   the second then falls asleep too, and both stay asleep. Truth: nothing
   moves, nothing wakes. When any awake body's bounds woke a sleeping
   island, the second woke the first, then the first the second, for
   ever (a heap of 2000 never slept, bench_robustness heap). */
static void resting_neighbours_let_an_island_sleep(void **state)
{
    tb_world *w = world_on_plane(0.6, 0);
    const double at0[3] = { 0, 0, 0.5 }, at1[3] = { 1.003, 0, 0.6 };
    tb_body_id first = add_box(w, at0, 1, 0.6), second = add_box(w, at1, 1, 0.6);
    int i, asleep0 = 0, asleep1 = 0, first_at = -1, both_at = -1;
    (void)state;
    for (i = 1; i <= 300; ++i) {
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
        assert_int_equal(tb_body_asleep(w, first, &asleep0), TB_OK);
        assert_int_equal(tb_body_asleep(w, second, &asleep1), TB_OK);
        if (asleep0 && first_at < 0)
            first_at = i;
        if (asleep0 && asleep1 && both_at < 0)
            both_at = i;
        if (first_at > 0)
            assert_true(asleep0); /* never woken */
        if (both_at > 0)
            assert_true(asleep1);
    }
    print_message("the first box asleep from step %d, both from step %d\n", first_at, both_at);
    assert_true(first_at > 0 && both_at > first_at && both_at <= 90);
    tb_world_destroy(w);
}

/* A column of three boxes asleep: its pairs are parked (contact.c), not
   carried step by step, yet they are the same contacts throughout. Asleep,
   its 12 points are still counted and no event comes, also at another step
   size (which brings the parked pairs back for a step). A ball dropped on
   the top box wakes the column: its pairs come back as they were, so the
   steps that wake it end no contact and begin at most the ball's, and the
   column, warm started, stays where it slept (within 1 mm). */
static void sleeping_pairs_are_kept_and_come_back(void **state)
{
    tb_world *w = world_on_plane(0.6, 0);
    const double at[3][3] = { { 0, 0, 0.5 }, { 0, 0, 1.5 }, { 0, 0, 2.5 } }, drop[3] = { 0, 0, 3.3 };
    tb_body_id box[3];
    double x0[3], x[3];
    size_t events;
    int i, k, asleep = 1, woke = 0;
    (void)state;
    for (k = 0; k < 3; ++k)
        box[k] = add_box(w, at[k], 1, 0.6);
    steps_to_sleep(w, box[2], 240);
    assert_int_equal(tb_world_sleeping_count(w), 3);
    assert_int_equal(tb_world_contact_count(w), 12);
    tb_body_position(w, box[2], x0);
    for (i = 0; i < 20; ++i) {
        assert_int_equal(tb_world_step(w, i < 10 ? 1.0 / 60 : 1.0 / 120), TB_OK);
        tb_world_contact_events(w, &events);
        assert_int_equal(events, 0);
        assert_int_equal(tb_world_contact_count(w), 12);
        assert_int_equal(tb_world_sleeping_count(w), 3);
    }
    add_ball(w, drop, 0.2, 0);
    for (i = 0; i < 60; ++i) {
        const tb_contact_event *ev;
        int begun = 0, ended = 0;
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
        ev = tb_world_contact_events(w, &events);
        for (k = 0; k < (int)events; ++k) {
            begun += ev[k].type == TB_CONTACT_BEGIN;
            ended += ev[k].type == TB_CONTACT_END;
        }
        if (asleep)
            assert_true(ended == 0 && begun <= 1);
        assert_int_equal(tb_body_asleep(w, box[0], &asleep), TB_OK);
        woke |= !asleep;
    }
    assert_true(woke);
    tb_body_position(w, box[2], x);
    print_message("column woken by a ball: top box moved %.2e m\n",
                  sqrt((x[0] - x0[0]) * (x[0] - x0[0]) + (x[1] - x0[1]) * (x[1] - x0[1]) + (x[2] - x0[2]) * (x[2] - x0[2])));
    assert_true(fabs(x[0] - x0[0]) < 1e-3 && fabs(x[1] - x0[1]) < 1e-3 && fabs(x[2] - x0[2]) < 1e-3);
    tb_world_destroy(w);
}

/* 40 boxes asleep, in blocks of 32 that the split sweep passes over and
   whose poses sleep then neither keeps nor puts back (body_step.c): under
   verlet and symplectic Euler their poses stay the same to the bit and
   their momenta zero, while a box falling beside them (in the second
   block, which is swept) falls. */
static void sleeping_blocks_stay_put(void **state)
{
    static const char *methods[2] = { "verlet", "symplectic_euler" };
    int k;
    (void)state;
    for (k = 0; k < 2; ++k) {
        tb_world *w = world_on_plane(0.6, 0);
        tb_body_id id[40], falling;
        double x0[40][3], x[3], P[3], L[3];
        const double high[3] = { -5, 0, 20 };
        int i;
        assert_int_equal(tb_world_set_integrator(w, methods[k]), TB_OK);
        for (i = 0; i < 40; ++i) {
            const double at[3] = { 2.0 * (i % 8), 2.0 * (i / 8), 0.5 };
            id[i] = add_box(w, at, 1, 0.6);
        }
        steps_to_sleep(w, id[39], 120);
        assert_int_equal(tb_world_sleeping_count(w), 40);
        falling = add_box(w, high, 1, 0.6); /* (a new shape wakes every island) */
        steps_to_sleep(w, id[39], 120);
        assert_int_equal(tb_world_sleeping_count(w), 40);
        for (i = 0; i < 40; ++i)
            tb_body_position(w, id[i], x0[i]);
        for (i = 0; i < 60; ++i)
            assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
        assert_int_equal(tb_world_sleeping_count(w), 40);
        for (i = 0; i < 40; ++i) {
            tb_body_position(w, id[i], x);
            tb_body_momentum(w, id[i], P, L);
            assert_memory_equal(x, x0[i], sizeof x);
            assert_true(P[0] == 0 && P[1] == 0 && P[2] == 0 && L[0] == 0 && L[1] == 0 && L[2] == 0);
        }
        tb_body_position(w, falling, x);
        assert_true(x[2] < 15); /* (it fell for 1.5 s: 11 m) */
        tb_world_destroy(w);
    }
}

/* Everything asleep, then woken all at once: a box asleep on a static box
   (a plane 5 m lower) must fall when the static box is removed, and a box
   asleep on the plane must slide when gravity turns 8 m/s^2 sideways
   (friction 0.6 holds up to 5.9). The sleeping poses are put back after
   each step's free motion, so the wake must drop them even when nothing is
   left asleep: kept from the step before the wake, they hold both boxes
   where they slept, for good. */
static void woken_world_moves_again(void **state)
{
    tb_world_def def = tb_default_world_def();
    tb_shape_def floor = tb_default_shape_def(), plane = tb_default_shape_def();
    const double at[3] = { 0, 0, 0.5 }, sideways[3] = { 8, 0, -G };
    tb_shape_id under;
    tb_world *w;
    tb_body_id box;
    double x[3];
    int i;
    (void)state;
    def.gravity[2] = -G;
    assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
    plane.type = TB_SHAPE_PLANE, plane.offset = -5;
    assert_int_equal(tb_world_add_shape(w, &plane, NULL), TB_OK);
    floor.type = TB_SHAPE_BOX, floor.half_extents[0] = floor.half_extents[1] = floor.half_extents[2] = 1;
    floor.position[2] = -1;
    assert_int_equal(tb_world_add_shape(w, &floor, &under), TB_OK);
    box = add_box(w, at, 1, 0.6);
    assert_int_equal(steps_to_sleep(w, box, 120) < 120, 1);
    for (i = 0; i < 10; ++i) /* asleep a while */
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
    assert_int_equal(tb_world_remove_shape(w, under), TB_OK);
    for (i = 0; i < 120; ++i)
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
    tb_body_position(w, box, x);
    assert_below(fabs(x[2] + 4.5), 1e-3); /* on the plane */
    assert_int_equal(steps_to_sleep(w, box, 120) < 120, 1);
    for (i = 0; i < 10; ++i)
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
    assert_int_equal(tb_world_set_gravity(w, sideways), TB_OK);
    for (i = 0; i < 60; ++i)
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
    tb_body_position(w, box, x);
    /* 1 s of 8 - 0.6 g = 2.114 m/s^2 from rest: 1.057 m */
    print_message("woken box: fell to %.4f m, slid %.6f m in 1 s (%.6f)\n", x[2], x[0], 0.5 * (8 - 0.6 * G));
    assert_rel(x[0], 0.5 * (8 - 0.6 * G), 1e-3);
    tb_world_destroy(w);
}

/* The header's list of what wakes a sleeping island, one trigger at a
   time on a column of two boxes asleep on the plane (one island): each
   of the bottom box's setters, a held force, a force at a body point and
   a held torque, removing the top box, new contact settings, a new shape
   and new gravity wake both boxes by the end of the next step; a particle
   (colliding as a sphere of 5 cm) thrown at the top box faster than
   sleep_speed wakes them when it reaches them. A step with none of these leaves them asleep. */
enum { SET_POSITION, SET_ORIENTATION, SET_VELOCITY, SET_SPIN, FORCE, FORCE_AT_POINT, TORQUE, REMOVE_TOP,
       SETTINGS, SHAPE, GRAVITY, PARTICLE, NOTHING, TRIGGERS };

static void pull(tb_world *w, tb_body_id bottom, tb_body_id top, int trigger)
{
    const double x[3] = { 0, 0, 0.5 }, q[4] = { 1, 0, 0, 0 }, zero[3] = { 0, 0, 0 }, f[3] = { 0.1, 0, 0 };
    const double g[3] = { 0, 0, -9.8 }, far[3] = { 10, 0, 0.5 };
    tb_contact_settings cs = tb_world_contact_settings(w);
    tb_particle_def p = tb_default_particle_def();
    switch (trigger) {
    case SET_POSITION: assert_int_equal(tb_body_set_position(w, bottom, x), TB_OK); break;
    case SET_ORIENTATION: assert_int_equal(tb_body_set_orientation(w, bottom, q), TB_OK); break;
    case SET_VELOCITY: assert_int_equal(tb_body_set_velocity(w, bottom, zero), TB_OK); break;
    case SET_SPIN: assert_int_equal(tb_body_set_angular_velocity(w, bottom, zero), TB_OK); break;
    case FORCE: assert_int_equal(tb_body_apply_force(w, bottom, f, x), TB_OK); break;
    case FORCE_AT_POINT: assert_int_equal(tb_body_apply_force_at_body_point(w, bottom, f, zero), TB_OK); break;
    case TORQUE: assert_int_equal(tb_body_apply_torque(w, bottom, f), TB_OK); break;
    case REMOVE_TOP: assert_int_equal(tb_world_remove_body(w, top), TB_OK); break;
    case SETTINGS: cs.hertz += 1; assert_int_equal(tb_world_set_contact_settings(w, &cs), TB_OK); break;
    case SHAPE: add_box(w, far, 1, 0.6); break;
    case GRAVITY: assert_int_equal(tb_world_set_gravity(w, g), TB_OK); break;
    case PARTICLE:
        p.position[0] = -1, p.position[2] = 1.5, p.velocity[0] = 3; /* reaches the top box in about 0.3 s */
        assert_int_equal(tb_world_add_particle(w, &p, NULL), TB_OK);
        break;
    default: break;
    }
}

static void every_listed_trigger_wakes_an_island(void **state)
{
    int trigger;
    (void)state;
    for (trigger = 0; trigger < TRIGGERS; ++trigger) {
        tb_world *w = world_on_plane(0.6, 0);
        const double low[3] = { 0, 0, 0.5 }, high[3] = { 0, 0, 1.5 };
        tb_body_id bottom = add_box(w, low, 1, 0.6), top = add_box(w, high, 1, 0.6);
        int asleep = 1, i, steps = trigger == PARTICLE || trigger == NOTHING ? 30 : 1;
        tb_contact_settings cs = tb_world_contact_settings(w);
        cs.particle_radius = 0.05; /* particles collide (they do not by default) */
        assert_int_equal(tb_world_set_contact_settings(w, &cs), TB_OK);
        assert_int_equal(steps_to_sleep(w, top, 200) < 200, 1);
        assert_int_equal(tb_world_sleeping_count(w), 2);
        pull(w, bottom, top, trigger);
        for (i = 0; i < steps && asleep; ++i) {
            assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
            assert_int_equal(tb_body_asleep(w, bottom, &asleep), TB_OK);
        }
        print_message("trigger %2d: %s after %d step(s)\n", trigger, asleep ? "asleep" : "awake", i);
        assert_int_equal(asleep, trigger == NOTHING);
        tb_world_destroy(w);
    }
}

/* Sleep is off with sleep_time = INFINITY and in worlds with a force
   callback; bad sleep settings are refused and the old ones kept. */
static tb_status no_force(const tb_force_args *args, void *user)
{
    (void)args, (void)user;
    return TB_OK;
}

static void sleep_settings(void **state)
{
    tb_world *w = world_on_plane(0.6, 0);
    const double at[3] = { 0, 0, 0.5 };
    tb_body_id id = add_box(w, at, 1, 0.6);
    tb_contact_settings s = tb_default_contact_settings(), bad;
    (void)state;
    s.sleep_time = INFINITY;
    assert_int_equal(tb_world_set_contact_settings(w, &s), TB_OK);
    assert_int_equal(steps_to_sleep(w, id, 120), 120);
    assert_int_equal(tb_world_sleeping_count(w), 0);
    s.sleep_time = 0.5;
    assert_int_equal(tb_world_set_contact_settings(w, &s), TB_OK);
    assert_int_equal(tb_world_add_force(w, no_force, NULL, NULL), TB_OK);
    assert_int_equal(steps_to_sleep(w, id, 120), 120);
    bad = s, bad.sleep_time = 0;
    assert_int_equal(tb_world_set_contact_settings(w, &bad), TB_ERR_ARGUMENT);
    bad = s, bad.sleep_time = NAN;
    assert_int_equal(tb_world_set_contact_settings(w, &bad), TB_ERR_ARGUMENT);
    assert_non_null(strstr(tb_world_message(w), "sleep_time"));
    bad = s, bad.sleep_speed = -1;
    assert_int_equal(tb_world_set_contact_settings(w, &bad), TB_ERR_ARGUMENT);
    assert_non_null(strstr(tb_world_message(w), "sleep_speed")); /* the message names the field */
    assert_true(tb_world_contact_settings(w).sleep_speed == 0.05);
    tb_world_destroy(w);
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(resting_box_falls_asleep_and_stays_put),
    cmocka_unit_test(sleeping_box_wakes_when_a_ball_lands),
    cmocka_unit_test(islands_wake_together),
    cmocka_unit_test(resting_neighbours_let_an_island_sleep),
    cmocka_unit_test(sleeping_pairs_are_kept_and_come_back),
    cmocka_unit_test(sleeping_blocks_stay_put),
    cmocka_unit_test(woken_world_moves_again),
    cmocka_unit_test(sleep_settings),
    cmocka_unit_test(every_listed_trigger_wakes_an_island),
};

TB_TEST_MAIN(tests)
