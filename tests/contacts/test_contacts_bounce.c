/* test_contacts_bounce.c: bounces and impacts. Restitution against the
   closed form and against ODE (reference/ode_contacts.c), energy through a
   spinning bounce, a fast body against a thin wall, momentum through a
   collision, the impact speed contact events report, and particles
   sprayed at a sphere. */
#include "test_main.h"
#include "tumble.h"
#include "contact_scenes.h"
#include "ode_contacts.h"

#include <math.h>
#include <string.h>

/* A 0.1 m ball dropped with its lowest point 1 m above the plane,
   restitution 0.5, default settings. Two readings of each apex: `sampled`
   is ODE's (the first step past the top), `top` the top of the ballistic
   arc through the last rising step, z + v^2 / 2g (exact between contacts).
   Verlet is exact under constant gravity and the impact is timed within
   its step, so `top` must be e^2k h0 to rounding (1e-9 asserted); the
   issue's 2 % is what ODE-like first-order contact handling would need. */
static void drop_ball(double hz, double sampled[2], double top[2])
{
    tb_world *w = world_on_plane(0.6, 0);
    const double start[3] = { 0, 0, 1.1 };
    tb_body_id id = add_ball(w, start, 0.1, 0.5);
    assert_int_equal(ball_apexes(w, id, 0.1, hz, sampled, top), 2);
    tb_world_destroy(w);
}

static void ball_bounces_to_e_squared(void **state)
{
    const double truth[2] = { 0.25, 0.0625 };
    double sampled[2], top[2], ode60[2], ode240[2], s240[2], t240[2];
    int k;
    (void)state;
    drop_ball(60, sampled, top);
    drop_ball(240, s240, t240);
    assert_int_equal(ode_ball_apexes(60, 0.5, 1, ode60), 2);
    assert_int_equal(ode_ball_apexes(240, 0.5, 1, ode240), 2);
    for (k = 0; k < 2; ++k) {
        print_message("apex %d: truth %.4f | 60 Hz: tumble top %.12f sampled %.4f, ODE %.4f | 240 Hz: tumble %.4f, "
                      "ODE %.4f\n", k + 1, truth[k], top[k], sampled[k], ode60[k], s240[k], ode240[k]);
        assert_rel(top[k], truth[k], 1e-9);
        assert_rel(t240[k], truth[k], 1e-9);
        /* where ODE is accurate, the two agree; at 60 Hz tumble is closer */
        assert_rel(s240[k], ode240[k], 0.02);
        assert_true(fabs(sampled[k] - truth[k]) < fabs(ode60[k] - truth[k]));
    }
}

/* A plate 1 m square and 10 cm thick, spun about a horizontal axis and
   dropped, strikes the ground with an edge while the edge sweeps down at
   up to 15 m/s and across it at as much. Restitution at most 1 cannot give
   it energy, and no more is allowed than lifting it by 0.1 mm (as for
   random_heaps_never_gain_energy in test_contacts_heaps.c). The bounce is
   solved apart from friction: bounced together with friction that holds
   the edge still, it goes partly into the plate's motion through its
   turn, and the plate rises with 20 to 48% more energy than it was
   dropped with (the 2 by 2 contact mass of normal and friction couple;
   Newton's restitution with sticking friction is known to make energy
   so). The substep's impacts bounce before its friction rows meet the
   edge. */
static void spinning_plate_bounces_without_gaining_energy(void **state)
{
    static const double cases[][3] = { /* spin (rad/s), restitution, height (m) */
        { 30, 0.9, 1 }, { 30, 0.9, 0.8 }, { 60, 0.9, 1 }, { 20, 1, 1 }, { 10, 1, 1 }, { 30, 1, 0.6 } };
    size_t n;
    (void)state;
    for (n = 0; n < sizeof cases / sizeof cases[0]; ++n) {
        const size_t i = n;
        tb_world *w = world_on_plane(0.6, cases[i][1]);
        tb_body_def b = tb_default_body_def();
        tb_shape_def s = tb_default_shape_def();
        const double size[3] = { 1, 1, 0.1 };
        double start, worst = -INFINITY;
        int t;
        assert_int_equal(tb_mass_box(1000, size, &b.mass, NULL), TB_OK);
        b.position[2] = cases[i][2];
        b.angular_velocity[0] = cases[i][0];
        assert_int_equal(tb_world_add_body(w, &b, &s.body), TB_OK);
        s.type = TB_SHAPE_BOX;
        s.half_extents[0] = s.half_extents[1] = 0.5, s.half_extents[2] = 0.05;
        s.friction = 0.6;
        s.restitution = cases[i][1];
        assert_int_equal(tb_world_add_shape(w, &s, NULL), TB_OK);
        start = tb_world_energy(w).total;
        for (t = 0; t < 300; ++t) {
            assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
            worst = fmax(worst, tb_world_energy(w).total - start);
        }
        print_message("plate spun at %2.0f rad/s, restitution %.1f, dropped from %.1f m: largest energy gain "
                      "%.3g J of %.0f, as lifting it %.2g m\n", cases[i][0], cases[i][1], cases[i][2], worst, start,
                      worst / (b.mass.mass * G));
        assert_true(worst <= 1e-4 * b.mass.mass * G);
        tb_world_destroy(w);
    }
}

/* A 0.1 m sphere at 50 m/s towards a static box 5 cm thick, 60 Hz: it moves
   0.83 m a step, 17 times the box's thickness, and must still stop at it:
   the speculative contact closes the gap exactly (1e-9 m asserted). */
static void fast_sphere_does_not_tunnel(void **state)
{
    tb_world_def def = tb_default_world_def();
    tb_shape_def wall = tb_default_shape_def();
    tb_world *w;
    tb_body_id ball;
    const double start[3] = { -2, 0, 0 }, v0[3] = { 50, 0, 0 };
    double x[3];
    int i;
    (void)state;
    def.gravity[2] = 0;
    assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
    wall.type = TB_SHAPE_BOX;
    wall.half_extents[0] = 0.025, wall.half_extents[1] = wall.half_extents[2] = 1;
    assert_int_equal(tb_world_add_shape(w, &wall, NULL), TB_OK);
    ball = add_ball(w, start, 0.1, 0);
    assert_int_equal(tb_body_set_velocity(w, ball, v0), TB_OK);
    for (i = 0; i < 30; ++i) {
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
        tb_body_position(w, ball, x);
        assert_below(x[0], -0.125 + 1e-9); /* never past the near face */
    }
    print_message("fast sphere: stopped at x = %.15f m (touching at -0.125)\n", x[0]);
    assert_below(fabs(x[0] + 0.125), 1e-9);
    tb_world_destroy(w);
}

/* Two spheres, restitution 1, off-centre at different masses and no
   gravity: equal and opposite impulses keep the momentum to rounding. */
static void collision_keeps_momentum(void **state)
{
    tb_world_def def = tb_default_world_def();
    tb_world *w;
    tb_body_id a, b;
    const double pa[3] = { -1, 0.05, 0 }, pb[3] = { 1, 0, 0.02 }, va[3] = { 6, 0, 0 }, vb[3] = { -3, 0.5, 0 };
    double before[3], after[3], scale;
    int i, k;
    size_t events = 0, n;
    (void)state;
    def.gravity[2] = 0;
    assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
    a = add_ball(w, pa, 0.2, 1);
    b = add_ball(w, pb, 0.3, 1);
    assert_int_equal(tb_body_set_velocity(w, a, va), TB_OK);
    assert_int_equal(tb_body_set_velocity(w, b, vb), TB_OK);
    tb_world_momentum(w, before);
    for (i = 0; i < 60; ++i) {
        const tb_contact_event *ev;
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
        ev = tb_world_contact_events(w, &n);
        for (k = 0; k < (int)n; ++k)
            events += ev[k].type == TB_CONTACT_BEGIN;
    }
    tb_world_momentum(w, after);
    scale = fabs(before[0]) + fabs(before[1]) + fabs(before[2]);
    for (k = 0; k < 3; ++k)
        assert_below(fabs(after[k] - before[k]), 1e-9 * scale);
    {
        double v[3];
        tb_body_velocity(w, a, v);
        assert_true(v[0] < 0); /* it bounced */
    }
    assert_int_equal(events, 1);
    tb_world_destroy(w);
}

/* The drop's first contact begins with the impact speed sqrt(2 g h0),
   found from the energy over the gap in the substep it closes in, exact
   under gravity alone: 1e-12 (a point that only bounced reported no
   begin before). */
static void events_report_impacts(void **state)
{
    (void)state;
    {
        tb_world *w = world_on_plane(0.6, 0);
        const double start[3] = { 0, 0, 1.1 };
        int i, begins = 0, ends = 0;
        double speed = 0;
        add_ball(w, start, 0.1, 0.5);
        for (i = 0; i < 90; ++i) {
            size_t n, k;
            const tb_contact_event *ev;
            assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
            ev = tb_world_contact_events(w, &n);
            for (k = 0; k < n; ++k) {
                if (ev[k].type == TB_CONTACT_BEGIN && begins++ == 0)
                    speed = ev[k].speed;
                ends += ev[k].type == TB_CONTACT_END;
                assert_false(TB_ID_IS_NULL(ev[k].a));
                assert_false(TB_ID_IS_NULL(ev[k].b));
            }
        }
        print_message("first impact at %.15f m/s (sqrt(2 g h0) = %.15f), %d begins, %d ends\n", speed, sqrt(2 * G),
                      begins, ends);
        assert_rel(speed, sqrt(2 * G), 1e-12);
        assert_true(begins >= 2 && ends >= 1);
        tb_world_destroy(w);
    }
}

/* The spray scene (scenes/spray.lua) in C: 200 particles of radius 2 cm at
   6 m/s into a static 0.5 m sphere, restitution 0.3, 2 s at 120 Hz. At
   every step no particle may be inside the sphere or below the plane by
   more than the slop (5 mm; measured: none at all), and every particle
   must hit the sphere, since the nozzles' disc (0.3 m across, aimed at its
   centre) lies inside its outline: at least 200 begin events with the
   sphere (measured 201: a particle may come back for a second touch). */
static void spray_stays_outside_the_sphere(void **state)
{
    tb_world *w = world_on_plane(0.6, 0);
    tb_shape_def ball = tb_default_shape_def();
    tb_contact_settings cs = tb_world_contact_settings(w);
    const double centre[3] = { 0, 0, 1 }, R = 0.5, r = 0.02, slop = cs.slop;
    double deepest = 0, lowest = INFINITY;
    size_t hits = 0;
    int i, n;
    (void)state;
    cs.particle_radius = r, cs.particle_restitution = 0.3, cs.particle_friction = 0.2;
    assert_int_equal(tb_world_set_contact_settings(w, &cs), TB_OK);
    ball.type = TB_SHAPE_SPHERE;
    ball.radius = R;
    memcpy(ball.position, centre, sizeof ball.position);
    assert_int_equal(tb_world_add_shape(w, &ball, NULL), TB_OK);
    for (i = 0; i < 200; ++i) {
        tb_particle_def p = tb_default_particle_def();
        const double a = 2.399963 * i, rr = 0.3 * sqrt(i / 200.0);
        p.position[0] = -2, p.position[1] = rr * cos(a), p.position[2] = 1.2 + rr * sin(a);
        p.velocity[0] = 6, p.velocity[2] = 1;
        p.mass = 0.01;
        assert_int_equal(tb_world_add_particle(w, &p, NULL), TB_OK);
    }
    for (n = 0; n < 240; ++n) {
        const tb_contact_event *ev;
        size_t count, k;
        const double *x;
        assert_int_equal(tb_world_step(w, 1.0 / 120), TB_OK);
        ev = tb_world_contact_events(w, &count);
        for (k = 0; k < count; ++k)
            hits += ev[k].type == TB_CONTACT_BEGIN && ev[k].a.index1 == 2 && !TB_ID_IS_NULL(ev[k].particle);
        x = tb_world_particle_positions(w);
        for (k = 0; k < 200; ++k) {
            const double *p = x + 3 * k;
            const double d = sqrt((p[0] - centre[0]) * (p[0] - centre[0]) + (p[1] - centre[1]) * (p[1] - centre[1]) +
                                  (p[2] - centre[2]) * (p[2] - centre[2]));
            deepest = fmax(deepest, R + r - d);
            lowest = fmin(lowest, p[2] - r);
        }
    }
    print_message("spray: %zu of 200 particles hit the sphere, deepest in it %.2e m, lowest below the plane "
                  "%.2e m\n", hits, deepest, -lowest);
    assert_below(deepest, slop);
    assert_true(lowest > -slop);
    assert_true(hits >= 200);
    tb_world_destroy(w);
}

/* The first apex (truth e^2 h0 = 0.25 m) and the second (e^4 h0) of
   drop_ball's scene at `hz` under `method`. */
static void apexes_under(const char *method, double hz, double top[2])
{
    tb_world *w = world_on_plane(0.6, 0);
    const double start[3] = { 0, 0, 1.1 };
    tb_body_id id = add_ball(w, start, 0.1, 0.5);
    assert_int_equal(tb_world_set_integrator(w, method), TB_OK);
    assert_int_equal(ball_apexes(w, id, 0.1, hz, NULL, top), 2);
    tb_world_destroy(w);
}

/* Bounce heights depend on the method: the step's motion in contact is
   the substeps' leapfrog, but the flight between bounces is the method's.
   The methods exact under constant gravity (verlet, verlet_exact, rk4,
   dopri5, and auto, which plans verlet here) reach e^2k h0 to rounding at
   any rate (1e-9 asserted at 30, 60 and 240 Hz). Symplectic and implicit
   Euler (the same steps here: no springs or drag) fall short at first
   order: the shortfall shrinks 4 times from 60 to 240 Hz (asserted: order
   within 0.15 of 1; measured 9.5% and 2.65% on the first apex).
   Explicit Euler misses both ways and converges at first order only from
   about 240 Hz (2.7% and 0.68% over at 240 and 960 Hz: order 0.99,
   asserted within 0.3 of 1). */
static void bounce_heights_follow_each_method(void **state)
{
    const char *exact[] = { "verlet", "verlet_exact", "rk4", "dopri5", "auto" };
    const char *first[] = { "symplectic_euler", "implicit_euler" };
    const double truth[2] = { 0.25, 0.0625 }, rates[3] = { 30, 60, 240 };
    double top[2], slow[2], fast[2], p;
    size_t m, k;
    int j;
    (void)state;
    for (m = 0; m < 5; ++m)
        for (k = 0; k < 3; ++k) {
            apexes_under(exact[m], rates[k], top);
            for (j = 0; j < 2; ++j)
                assert_rel(top[j], truth[j], 1e-9);
        }
    for (m = 0; m < 2; ++m) {
        apexes_under(first[m], 60, slow);
        apexes_under(first[m], 240, fast);
        for (j = 0; j < 2; ++j) {
            p = log(fabs(slow[j] / truth[j] - 1) / fabs(fast[j] / truth[j] - 1)) / log(4);
            print_message("%-17s apex %d: %+.3e at 60 Hz, %+.3e at 240 Hz: order %.3f\n", first[m], j + 1,
                          slow[j] / truth[j] - 1, fast[j] / truth[j] - 1, p);
            assert_true(slow[j] < truth[j] && fast[j] < truth[j]);
            assert_below(fabs(p - 1), 0.15);
        }
    }
    apexes_under("euler", 240, slow);
    apexes_under("euler", 960, fast);
    p = log(fabs(slow[0] / truth[0] - 1) / fabs(fast[0] / truth[0] - 1)) / log(4);
    print_message("euler             apex 1: %+.3e at 240 Hz, %+.3e at 960 Hz: order %.3f\n", slow[0] / truth[0] - 1,
                  fast[0] / truth[0] - 1, p);
    assert_below(fabs(p - 1), 0.3);
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(spray_stays_outside_the_sphere),
    cmocka_unit_test(ball_bounces_to_e_squared),
    cmocka_unit_test(bounce_heights_follow_each_method),
    cmocka_unit_test(spinning_plate_bounces_without_gaining_energy),
    cmocka_unit_test(fast_sphere_does_not_tunnel),
    cmocka_unit_test(collision_keeps_momentum),
    cmocka_unit_test(events_report_impacts),
};

TB_TEST_MAIN(tests)
