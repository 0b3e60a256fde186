/* test_forces.c: gravity, drag, springs, user forces and fields against
   closed forms. Where a method's discrete solution is itself known in closed
   form, the test asserts it to rounding; against the continuous solution it
   asserts the method's own error formula. */
#include "test_main.h"
#include "tumble.h"
#include "particle_worlds.h"

#include <math.h>
#include <string.h>

static tb_particle_id particle(tb_world *w, const double x[3], const double v[3], double mass, int pinned)
{
    tb_particle_def def = tb_default_particle_def();
    tb_particle_id id;
    memcpy(def.position, x, sizeof def.position);
    memcpy(def.velocity, v, sizeof def.velocity);
    def.mass = mass;
    def.pinned = pinned;
    assert_int_equal(tb_world_add_particle(w, &def, &id), TB_OK);
    return id;
}

static double dist3(const double a[3], const double b[3])
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/* ---- projectile with linear drag ------------------------------------------
   m v' = m g - c v. With k = c / m and v* = g / k the terminal velocity, the
   velocity error of any one-step method obeys v_n - v* = R(-k h)^n (v0 - v*)
   exactly, R being the method's stability function (for Verlet, whose
   closing kick sees the predicted velocity v_n + h a_n, R = 1 - kh + (kh)^2/2,
   the second-order Taylor polynomial, like RK2). */

static const double M = 2, C = 0.8, H = 0.01; /* k = 0.4 1/s */
static const double X0[3] = { 0, 0, 1 }, V0[3] = { 10, -3, 15 };
static const double G = -9.81;

static void projectile_velocity_follows_stability_function(void **state)
{
    const char *names[] = { "euler", "symplectic_euler", "verlet", "rk4" };
    const double z = C / M * H;
    const double R[] = { 1 - z, 1 - z, 1 - z + z * z / 2,
                         1 - z + z * z / 2 - z * z * z / 6 + z * z * z * z / 24 };
    const int n = 300;
    int m, i, k;
    (void)state;
    for (m = 0; m < 4; ++m) {
        tb_world *w = world_with(names[m], G, C, 0);
        tb_particle_id id = particle(w, X0, V0, M, 0);
        double v[3], vstar[3] = { 0, 0, G * M / C };
        for (i = 0; i < n; ++i)
            assert_int_equal(tb_world_step(w, H), TB_OK);
        tb_particle_velocity(w, id, v);
        for (k = 0; k < 3; ++k)
            assert_true(fabs(v[k] - (vstar[k] + pow(R[m], n) * (V0[k] - vstar[k]))) <= 1e-12 * 20);
        tb_world_destroy(w);
    }
}

/* RK4 against the continuous solution
     v(t) = v* + (v0 - v*) e^{-kt},  x(t) = x0 + v* t + (v0 - v*)(1 - e^{-kt}) / k.
   Its velocity error is |R(-kh)^n - e^{-knh}| |v0 - v*| ~ n (kh)^5 / 120
   |v0 - v*|; the position, an integral of it, errs less than t times that. */
static void projectile_rk4_matches_closed_form(void **state)
{
    const double k = C / M, T = 3, z = k * H;
    const int n = 300;
    tb_world *w = world_with("rk4", G, C, 0);
    tb_particle_id id = particle(w, X0, V0, M, 0);
    double x[3], v[3], xe[3], ve[3], vstar[3] = { 0, 0, G / k }, dv0 = 0, bound;
    int i;
    (void)state;
    for (i = 0; i < n; ++i)
        assert_int_equal(tb_world_step(w, H), TB_OK);
    tb_particle_position(w, id, x);
    tb_particle_velocity(w, id, v);
    for (i = 0; i < 3; ++i) {
        ve[i] = vstar[i] + (V0[i] - vstar[i]) * exp(-k * T);
        xe[i] = X0[i] + vstar[i] * T + (V0[i] - vstar[i]) * (1 - exp(-k * T)) / k;
        dv0 += (V0[i] - vstar[i]) * (V0[i] - vstar[i]);
    }
    bound = n * pow(z, 5) / 120 * sqrt(dv0);
    print_message("rk4 error: velocity %.3e, position %.3e (bounds %.3e, %.3e)\n", dist3(v, ve), dist3(x, xe),
                  bound, T * bound);
    assert_below(dist3(v, ve), bound + 1e-13);
    assert_below(dist3(x, xe), T * bound + 1e-13);
    tb_world_destroy(w);
}

/* ---- quadratic drag: falling from rest --------------------------------------
   m v' = -m g - c2 |v| v. With vt = sqrt(m g / c2):
     v(t) = -vt tanh(g t / vt),  z(t) = z0 - (vt^2 / g) ln cosh(g t / vt).
   RK4 at h g / vt ~ 0.02 errs by about (h g / vt)^4 relative. */
static void quadratic_drag_reaches_terminal_velocity(void **state)
{
    const double m = 1.5, c2 = 0.3, g = 9.81, h = 0.005, T = 4, vt = sqrt(m * g / c2);
    const double zero[3] = { 0, 0, 0 }, top[3] = { 0, 0, 100 };
    tb_world *w = world_with("rk4", -g, 0, c2);
    tb_particle_id id = particle(w, top, zero, m, 0);
    double x[3], v[3], ve = -vt * tanh(g * T / vt), ze = 100 - vt * vt / g * log(cosh(g * T / vt));
    int i;
    (void)state;
    for (i = 0; i < (int)(T / h + 0.5); ++i)
        assert_int_equal(tb_world_step(w, h), TB_OK);
    tb_particle_position(w, id, x);
    tb_particle_velocity(w, id, v);
    print_message("v = %.12f (exact %.12f), z = %.12f (exact %.12f)\n", v[2], ve, x[2], ze);
    assert_rel(v[2], ve, pow(h * g / vt, 4));
    assert_rel(x[2], ze, pow(h * g / vt, 4));
    assert_true(v[0] == 0 && v[1] == 0);
    tb_world_destroy(w);
}

/* ---- spring-mass against the cosine -----------------------------------------
   A mass on a spring of rest length 1 anchored at the origin, displaced by A
   along x: x(t) = 1 + A cos(w t). Velocity Verlet's recurrence gives exactly
   x_n = 1 + A cos(w~ t_n) with cos(w~ h) = 1 - (w h)^2 / 2, so it matches that
   to rounding and differs from the true cosine by at most A t |w~ - w|. */
static void spring_mass_follows_the_cosine(void **state)
{
    const double k = 100, m = 0.25, w0 = sqrt(k / m), h = 1e-3, A = 0.1, T = 2;
    const double wd = acos(1 - (w0 * h) * (w0 * h) / 2) / h;
    const double x0[3] = { 1 + A, 0, 0 }, zero[3] = { 0, 0, 0 };
    tb_world *w = world_with("verlet", 0, 0, 0);
    tb_particle_id id = particle(w, x0, zero, m, 0);
    tb_spring_def s = tb_default_spring_def();
    double x[3], worst_discrete = 0, worst_true = 0;
    int i, n = (int)(T / h + 0.5);
    (void)state;
    s.a = id;
    s.stiffness = k;
    s.rest_length = 1;
    assert_int_equal(tb_world_add_spring(w, &s, NULL), TB_OK);
    for (i = 1; i <= n; ++i) {
        assert_int_equal(tb_world_step(w, h), TB_OK);
        tb_particle_position(w, id, x);
        worst_discrete = fmax(worst_discrete, fabs(x[0] - (1 + A * cos(wd * i * h))));
        worst_true = fmax(worst_true, fabs(x[0] - (1 + A * cos(w0 * i * h))));
    }
    print_message("verlet vs its discrete cosine %.3e, vs the true cosine %.3e (bound %.3e)\n", worst_discrete,
                  worst_true, A * T * (wd - w0));
    assert_below(worst_discrete, 1e-12);
    assert_below(worst_true, A * T * (wd - w0) * (1 + 1e-6) + 1e-12);
    tb_world_destroy(w);
}

/* Damped: m x'' = -k x - c x', underdamped, x(0) = A, x'(0) = 0:
     x(t) = A e^{-zeta w t} (cos wd t + zeta w / wd sin wd t).
   RK4 with w h = 0.02 errs by about t w (w h)^4 / 120 relative. */
static void damped_spring_matches_closed_form(void **state)
{
    const double k = 400, m = 1, c = 4, A = 0.2, h = 1e-3, T = 1;
    const double w0 = sqrt(k / m), zeta = c / (2 * sqrt(k * m)), wd = w0 * sqrt(1 - zeta * zeta);
    const double x0[3] = { 0, 0, -(1 + A) }, zero[3] = { 0, 0, 0 }, anchor[3] = { 0, 0, 0 };
    tb_world *w = world_with("rk4", 0, 0, 0);
    tb_particle_id id = particle(w, x0, zero, m, 0);
    tb_spring_def s = tb_default_spring_def();
    double x[3], exact;
    int i;
    (void)state;
    s.a = id;
    memcpy(s.anchor, anchor, sizeof s.anchor);
    s.stiffness = k;
    s.damping = c;
    s.rest_length = 1;
    assert_int_equal(tb_world_add_spring(w, &s, NULL), TB_OK);
    for (i = 0; i < (int)(T / h + 0.5); ++i)
        assert_int_equal(tb_world_step(w, h), TB_OK);
    tb_particle_position(w, id, x);
    exact = A * exp(-zeta * w0 * T) * (cos(wd * T) + zeta * w0 / wd * sin(wd * T));
    print_message("damped: displacement %.12f, exact %.12f\n", -(x[2] + 1), exact);
    assert_true(fabs(-(x[2] + 1) - exact) <= A * T * w0 * pow(w0 * h, 4) / 120);
    tb_world_destroy(w);
}

/* Two free masses on one damped spring, tumbling in 3D: the spring's forces
   on them are equal and opposite, so total momentum is conserved up to the
   rounding of m (f / m) per kick, about 1e-16 relative per step. */
static void two_body_spring_conserves_momentum(void **state)
{
    const double xa[3] = { 0, 0, 0 }, xb[3] = { 1.2, 0.1, 0 }, va[3] = { 0.3, 1, -2 }, vb[3] = { -0.1, 0.5, 4 };
    const char *names[] = { "symplectic_euler", "verlet", "rk4" };
    int m, i;
    (void)state;
    for (m = 0; m < 3; ++m) {
        tb_world *w = world_with(names[m], 0, 0, 0);
        tb_spring_def s = tb_default_spring_def();
        double p0[3], p[3], scale;
        s.a = particle(w, xa, va, 1, 0);
        s.b = particle(w, xb, vb, 3, 0);
        s.stiffness = 50;
        s.damping = 0.7;
        s.rest_length = 1;
        assert_int_equal(tb_world_add_spring(w, &s, NULL), TB_OK);
        tb_world_momentum(w, p0);
        scale = fabs(p0[0]) + fabs(p0[1]) + fabs(p0[2]);
        for (i = 0; i < 2000; ++i)
            assert_int_equal(tb_world_step(w, 1e-3), TB_OK);
        tb_world_momentum(w, p);
        for (i = 0; i < 3; ++i)
            assert_true(fabs(p[i] - p0[i]) <= 2000 * 1e-16 * scale * 10);
        tb_world_destroy(w);
    }
}

/* Separation of two masses moving only along the spring: 1 + A cos(wr t). */
static void two_body_spring_oscillates_at_reduced_mass_frequency(void **state)
{
    const double k = 50, m1 = 1, m2 = 3, mu = m1 * m2 / (m1 + m2), wr = sqrt(k / mu), h = 1e-3, T = 1.5, A = 0.2;
    const double xa[3] = { 0, 0, 0 }, xb[3] = { 1 + A, 0, 0 }, zero[3] = { 0, 0, 0 };
    tb_world *w = world_with("rk4", 0, 0, 0);
    tb_spring_def s = tb_default_spring_def();
    double a[3], b[3];
    int i;
    (void)state;
    s.a = particle(w, xa, zero, m1, 0);
    s.b = particle(w, xb, zero, m2, 0);
    s.stiffness = k;
    s.rest_length = 1;
    assert_int_equal(tb_world_add_spring(w, &s, NULL), TB_OK);
    for (i = 0; i < (int)(T / h + 0.5); ++i)
        assert_int_equal(tb_world_step(w, h), TB_OK);
    tb_particle_position(w, s.a, a);
    tb_particle_position(w, s.b, b);
    /* RK4 phase error ~ t wr (wr h)^4 / 120, times the amplitude */
    assert_true(fabs((b[0] - a[0]) - (1 + A * cos(wr * T))) <= A * T * wr * pow(wr * h, 4) / 120 + 1e-13);
    /* the centre of mass stays put */
    assert_true(fabs((m1 * a[0] + m2 * b[0]) / (m1 + m2) - m2 * (1 + A) / (m1 + m2)) <= 1e-13);
    tb_world_destroy(w);
}

/* ---- gravity, pinned particles, user forces, fields ------------------------ */

/* Under constant acceleration Verlet and RK4 are exact (the solution is a
   quadratic); both must give x0 + v0 t + g t^2 / 2 and keep the energy. */
static void free_fall_is_exact_for_verlet_and_rk4(void **state)
{
    const char *names[] = { "verlet", "rk4" };
    const double x0[3] = { 1, 2, 3 }, v0[3] = { 4, -5, 6 };
    int m, i;
    (void)state;
    for (m = 0; m < 2; ++m) {
        tb_world *w = world_with(names[m], G, 0, 0);
        tb_particle_id id = particle(w, x0, v0, 0.5, 0);
        double x[3], e0 = tb_world_energy(w).total, t;
        for (i = 0; i < 1000; ++i)
            assert_int_equal(tb_world_step(w, 1.0 / 64), TB_OK); /* exact in binary */
        t = tb_world_time(w);
        assert_true(t == 1000.0 / 64);
        tb_particle_position(w, id, x);
        assert_rel(x[0], x0[0] + v0[0] * t, 1e-13);
        assert_rel(x[2], x0[2] + v0[2] * t + G * t * t / 2, 1e-13);
        {   /* kinetic and potential energy reach ~5 kJ and cancel to 34 J:
               bound the rounding by the size of the terms */
            tb_energy e = tb_world_energy(w);
            assert_below(fabs(e.total - e0), 1e-13 * (fabs(e.kinetic) + fabs(e.gravity)));
        }
        tb_world_destroy(w);
    }
}

static void pinned_particles_do_not_move(void **state)
{
    const double x0[3] = { 0, 0, 0 }, x1[3] = { 0, 0, -1 }, zero[3] = { 0, 0, 0 };
    tb_world *w = world_with("verlet", G, 0.1, 0.1);
    tb_spring_def s = tb_default_spring_def();
    double x[3], p[3], m;
    int i;
    (void)state;
    s.a = particle(w, x0, zero, 1, 1);
    s.b = particle(w, x1, zero, 1, 0);
    s.stiffness = 100;
    assert_int_equal(tb_world_add_spring(w, &s, NULL), TB_OK);
    for (i = 0; i < 500; ++i)
        assert_int_equal(tb_world_step(w, 0.01), TB_OK);
    tb_particle_position(w, s.a, x);
    assert_true(x[0] == 0 && x[1] == 0 && x[2] == 0);
    tb_particle_mass(w, s.a, &m);
    assert_true(m == 0);
    tb_particle_position(w, s.b, x);
    assert_true(x[2] < -1); /* the free end sags under gravity */
    tb_world_momentum(w, p); /* the pinned end carries none: all of it is the free end's m v */
    tb_particle_velocity(w, s.b, x);
    assert_true(p[0] == 1 * x[0] && p[1] == 1 * x[1] && p[2] == 1 * x[2]);
    tb_world_destroy(w);
}

static tb_status constant_push(const tb_force_args *args, void *user)
{
    const double *f = user;
    size_t i;
    for (i = 0; i < args->count; ++i)
        if (args->masses[i] > 0) {
            args->forces[3 * i] += f[0];
            args->forces[3 * i + 1] += f[1];
            args->forces[3 * i + 2] += f[2];
        }
    return TB_OK;
}

/* A C callback force F on mass m: x = x0 + v0 t + F t^2 / (2 m), exact for
   Verlet; removing the callback stops the push. */
static void c_force_callback_pushes(void **state)
{
    double push[3] = { 3, 0, -1.5 };
    const double x0[3] = { 0, 0, 0 }, v0[3] = { 1, 0, 0 };
    tb_world *w = world_with("verlet", 0, 0, 0);
    tb_particle_id id = particle(w, x0, v0, 1.5, 0);
    tb_force_id f;
    double x[3], v[3];
    int i;
    (void)state;
    assert_int_equal(tb_world_add_force(w, constant_push, push, &f), TB_OK);
    for (i = 0; i < 64; ++i)
        assert_int_equal(tb_world_step(w, 1.0 / 64), TB_OK);
    tb_particle_position(w, id, x);
    assert_rel(x[0], 1 + 3 / 1.5 / 2, 1e-14);
    assert_rel(x[2], -1.5 / 1.5 / 2, 1e-14);
    assert_int_equal(tb_world_remove_force(w, f), TB_OK);
    assert_int_equal(tb_world_remove_force(w, f), TB_ERR_STALE_ID);
    tb_particle_velocity(w, id, v);
    assert_int_equal(tb_world_step(w, 0.5), TB_OK);
    tb_particle_velocity(w, id, x);
    assert_true(x[0] == v[0] && x[2] == v[2]);
    tb_world_destroy(w);
}

static tb_status shear_field(const tb_field_args *args, void *user)
{
    size_t i;
    (void)user;
    for (i = 0; i < args->count; ++i)
        args->velocities[3 * i] += args->positions[3 * i + 1]; /* u = (y, 0, 0) */
    return TB_OK;
}

/* Fields add up: a uniform drift plus a shear u = (y, 0, 0) from a callback.
   With y' = 1 the exact path is x = x0 + y0 t + t^2 / 2 + t, which RK4
   integrates exactly (polynomial of degree 2). */
static void fields_add_up(void **state)
{
    tb_world *w = world_with("rk4", G, 0, 0);
    tb_tracer_def t = tb_default_tracer_def();
    double up[3] = { 1, 1, 0 }, x[3], v[3];
    tb_tracer_id id;
    tb_field_id uniform;
    int i;
    (void)state;
    t.position[1] = 0.5;
    assert_int_equal(tb_world_add_tracer(w, &t, &id), TB_OK);
    assert_int_equal(tb_world_add_uniform_field(w, up, &uniform), TB_OK);
    assert_int_equal(tb_world_add_field(w, shear_field, NULL, NULL), TB_OK);
    for (i = 0; i < 32; ++i)
        assert_int_equal(tb_world_step(w, 1.0 / 16), TB_OK);
    tb_tracer_position(w, id, x);
    assert_rel(x[0], 0.5 * 2 + 2.0 + 2.0, 1e-14); /* t = 2 */
    assert_rel(x[1], 2.5, 1e-14);
    assert_int_equal(tb_world_tracer_velocities(w, v), TB_OK);
    assert_rel(v[0], 1 + 2.5, 1e-14);
    assert_int_equal(tb_world_remove_field(w, uniform), TB_OK);
    assert_int_equal(tb_world_tracer_velocities(w, v), TB_OK);
    assert_rel(v[0], 2.5, 1e-14);
    assert_true(v[1] == 0);
    tb_world_destroy(w);
}

/* Springs read back as they were made: ends, anchor, coefficients and the
   rest length the world took (the distance at creation for a negative
   one); after a particle's removal its springs are gone and the rest keep
   their ends (tb_spring_definition, as the command's glTF output reads
   them). */
static void springs_read_back(void **state)
{
    tb_world *w = world_with("verlet", 0, 0, 0);
    const double xa[3] = { 0, 0, 0 }, xb[3] = { 3, 4, 0 }, xc[3] = { 0, 0, 2 }, zero[3] = { 0, 0, 0 };
    tb_particle_id a = particle(w, xa, zero, 1, 0), b = particle(w, xb, zero, 1, 0), c = particle(w, xc, zero, 1, 0);
    tb_spring_def d = tb_default_spring_def(), got;
    tb_spring_id s1, s2;
    (void)state;
    d.a = a, d.b = b, d.stiffness = 7, d.damping = 0.5;
    assert_int_equal(tb_world_add_spring(w, &d, &s1), TB_OK);
    d = tb_default_spring_def();
    d.a = c, d.anchor[0] = 1, d.anchor[1] = 2, d.anchor[2] = 3, d.stiffness = 2, d.rest_length = 0.25;
    assert_int_equal(tb_world_add_spring(w, &d, &s2), TB_OK);
    assert_int_equal(tb_world_spring_at(w, 0).index1, s1.index1);
    assert_int_equal(tb_world_spring_at(w, 1).index1, s2.index1);
    assert_int_equal(tb_world_spring_at(w, 2).index1, 0); /* past the end */
    assert_int_equal(tb_spring_definition(w, s1, &got), TB_OK);
    assert_int_equal(got.a.index1, a.index1);
    assert_int_equal(got.b.index1, b.index1);
    assert_true(got.stiffness == 7 && got.damping == 0.5);
    assert_true(got.rest_length == 5); /* |(3, 4, 0)|, exact */
    assert_int_equal(tb_spring_definition(w, s2, &got), TB_OK);
    assert_int_equal(got.a.index1, c.index1);
    assert_int_equal(got.b.index1, 0);
    assert_true(got.anchor[0] == 1 && got.anchor[1] == 2 && got.anchor[2] == 3 && got.rest_length == 0.25);
    assert_int_equal(tb_spring_definition(w, s1, NULL), TB_ERR_ARGUMENT);
    /* removing a takes s1 with it; c moves into a's slot and s2 follows */
    assert_int_equal(tb_world_remove_particle(w, a), TB_OK);
    assert_int_equal(tb_spring_definition(w, s1, &got), TB_ERR_STALE_ID);
    assert_int_equal(tb_world_spring_count(w), 1);
    assert_int_equal(tb_spring_definition(w, tb_world_spring_at(w, 0), &got), TB_OK);
    assert_int_equal(got.a.index1, c.index1);
    assert_int_equal(got.a.generation, c.generation);
    tb_world_destroy(w);
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(projectile_velocity_follows_stability_function),
    cmocka_unit_test(projectile_rk4_matches_closed_form),
    cmocka_unit_test(quadratic_drag_reaches_terminal_velocity),
    cmocka_unit_test(spring_mass_follows_the_cosine),
    cmocka_unit_test(damped_spring_matches_closed_form),
    cmocka_unit_test(two_body_spring_conserves_momentum),
    cmocka_unit_test(two_body_spring_oscillates_at_reduced_mass_frequency),
    cmocka_unit_test(free_fall_is_exact_for_verlet_and_rk4),
    cmocka_unit_test(pinned_particles_do_not_move),
    cmocka_unit_test(c_force_callback_pushes),
    cmocka_unit_test(fields_add_up),
    cmocka_unit_test(springs_read_back),
};
TB_TEST_MAIN(tests)
