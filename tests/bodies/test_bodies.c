/* test_bodies.c: rigid bodies through the world API, against closed forms
   and a converged reference that the test checks for its own convergence. */
#include "test_main.h"
#include "tumble.h"

#include <math.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

static tb_world *world_with(const char *integrator, double gz)
{
    tb_world_def def = tb_default_world_def();
    tb_world *w;
    def.integrator = integrator;
    def.gravity[2] = gz;
    assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
    return w;
}

static tb_body_id body(tb_world *w, const double I[3], const double x[3], const double v[3], const double omega[3])
{
    tb_body_def def = tb_default_body_def();
    tb_body_id id;
    memcpy(def.mass.inertia, I, sizeof def.mass.inertia);
    def.mass.mass = 2;
    memcpy(def.position, x, sizeof def.position);
    memcpy(def.velocity, v, sizeof def.velocity);
    memcpy(def.angular_velocity, omega, sizeof def.angular_velocity);
    assert_int_equal(tb_world_add_body(w, &def, &id), TB_OK);
    return id;
}

/* Angle of a^-1 b, robust for tiny angles: 2 atan2(|vector|, |scalar|). */
static double angle_between(const double a[4], const double b[4])
{
    const double s = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    const double x = a[0] * b[1] - a[1] * b[0] - a[2] * b[3] + a[3] * b[2];
    const double y = a[0] * b[2] + a[1] * b[3] - a[2] * b[0] - a[3] * b[1];
    const double z = a[0] * b[3] - a[1] * b[2] + a[2] * b[1] - a[3] * b[0];
    return 2 * atan2(sqrt(x * x + y * y + z * z), fabs(s));
}

static double norm3(const double v[3])
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* Body-frame vector of a world vector: R^T v. */
static void to_body(const double q[4], const double v[3], double out[3])
{
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    const double R[9] = { 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                          2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                          2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y) };
    out[0] = R[0] * v[0] + R[3] * v[1] + R[6] * v[2];
    out[1] = R[1] * v[0] + R[4] * v[1] + R[7] * v[2];
    out[2] = R[2] * v[0] + R[5] * v[1] + R[8] * v[2];
}

static const char *const ALL[] = { "euler", "symplectic_euler", "verlet", "rk4", "verlet_exact" };
#define ALL_COUNT 5

/* ---- closed forms ------------------------------------------------------------ */

/* The centre of mass falls as x0 + v0 t + g t^2 / 2 whatever the spin:
   exact for every second-order or better method (constant acceleration). */
static void centre_of_mass_falls_freely(void **state)
{
    const double I[3] = { 1, 2, 3 }, x0[3] = { 1, 2, 3 }, v0[3] = { 4, -5, 6 }, om[3] = { 0.3, 5, -1 };
    int m, i;
    (void)state;
    for (m = 0; m < ALL_COUNT; ++m) {
        tb_world *w = world_with(ALL[m], -9.81);
        tb_body_id id = body(w, I, x0, v0, om);
        double x[3], t;
        int exact = strcmp(ALL[m], "euler") && strcmp(ALL[m], "symplectic_euler");
        for (i = 0; i < 256; ++i)
            assert_int_equal(tb_world_step(w, 1.0 / 64), TB_OK);
        t = 4;
        tb_body_position(w, id, x);
        if (exact) {
            assert_rel(x[0], x0[0] + v0[0] * t, 1e-14);
            assert_rel(x[2], x0[2] + v0[2] * t - 9.81 * t * t / 2, 1e-14);
        } else { /* first order: off by g t h / 2 */
            assert_rel(fabs(x[2] - (x0[2] + v0[2] * t - 9.81 * t * t / 2)), 9.81 * t / 64 / 2, 1e-9);
        }
        tb_world_destroy(w);
    }
}

/* A constant torque tau about a principal axis: L = tau t, angle
   tau t^2 / (2 I). Kick-drift-kick integrates a constant angular
   acceleration exactly (the drift turns by h w_half), so Verlet matches to
   rounding; RK4 on the quaternion errs by O(h^4). */
static void constant_torque_spins_up(void **state)
{
    const double I[3] = { 1.5, 2, 3 }, zero[3] = { 0, 0, 0 }, tau[3] = { 0.25, 0, 0 };
    const char *names[] = { "verlet", "verlet_exact", "rk4" };
    const double bounds[] = { 1e-12, 1e-12, 1e-9 };
    int m, i;
    (void)state;
    for (m = 0; m < 3; ++m) {
        tb_world *w = world_with(names[m], 0);
        tb_body_id id = body(w, I, zero, zero, zero);
        double q[4], omega[3], L[3], t = 2, theta = tau[0] * t * t / (2 * I[0]), exact[4];
        for (i = 0; i < 128; ++i) {
            assert_int_equal(tb_body_apply_torque(w, id, tau), TB_OK);
            assert_int_equal(tb_world_step(w, 1.0 / 64), TB_OK);
        }
        tb_body_momentum(w, id, NULL, L);
        tb_body_angular_velocity(w, id, omega);
        tb_body_orientation(w, id, q);
        assert_rel(L[0], tau[0] * t, 1e-14);
        assert_rel(omega[0], tau[0] * t / I[0], 1e-14);
        exact[0] = cos(theta / 2), exact[1] = sin(theta / 2), exact[2] = exact[3] = 0;
        print_message("%s: angle error %.3e rad after %.3f rad\n", names[m], angle_between(q, exact), theta);
        assert_below(angle_between(q, exact), bounds[m]);
        /* the held torque was cleared: without it, w stays put */
        assert_int_equal(tb_world_step(w, 1.0 / 64), TB_OK);
        tb_body_angular_velocity(w, id, L);
        assert_rel(L[0], omega[0], 1e-15);
        tb_world_destroy(w);
    }
}

/* A torque-free symmetric top (I1 = I2): Euler's equations give
   w1' = -Omega w2, w2' = Omega w1 with Omega = (I3 - I1) / I1 w3, so in the
   body frame w turns about the symmetry axis at Omega, keeping w3:
     w_b(t) = (a cos(Omega t) - b sin(Omega t), a sin(Omega t) + b cos(Omega t), w3),
   (a, b) the initial transverse components. Bounds: "verlet" and
   "verlet_exact" split the kinetic energy into a symmetric top plus axis
   rotations, so a symmetric top is solved exactly: rounding only (1e-12
   relative). RK4 is fourth order: its global error is about
   N (h |w|)^5 / 120 relative after N steps (3.4e-6 here). */
static void symmetric_top_precesses(void **state)
{
    const double I[3] = { 1, 1, 1.8 }, zero[3] = { 0, 0, 0 }, om0[3] = { 0.6, -0.2, 4 };
    const double Omega = (I[2] - I[0]) / I[0] * om0[2], T = 5;
    const char *names[] = { "verlet", "verlet_exact", "rk4" };
    const double h = 1.0 / 60, rk4_estimate = 300 * pow(h * norm3(om0), 5) / 120;
    const double bounds[] = { 1e-12, 1e-12, rk4_estimate };
    int m, i;
    (void)state;
    for (m = 0; m < 3; ++m) {
        tb_world *w = world_with(names[m], 0);
        tb_body_id id = body(w, I, zero, zero, om0);
        double q[4], L[3], Lb[3], wb[3], exact[3], err;
        for (i = 0; i < 300; ++i)
            assert_int_equal(tb_world_step(w, h), TB_OK);
        tb_body_orientation(w, id, q);
        tb_body_momentum(w, id, NULL, L);
        to_body(q, L, Lb);
        for (i = 0; i < 3; ++i)
            wb[i] = Lb[i] / I[i];
        exact[0] = om0[0] * cos(Omega * T) - om0[1] * sin(Omega * T);
        exact[1] = om0[0] * sin(Omega * T) + om0[1] * cos(Omega * T);
        exact[2] = om0[2];
        err = sqrt((wb[0] - exact[0]) * (wb[0] - exact[0]) + (wb[1] - exact[1]) * (wb[1] - exact[1]) +
                   (wb[2] - exact[2]) * (wb[2] - exact[2]));
        print_message("%s: body-frame w error %.3e rad/s after %.2f rad of precession\n", names[m], err, Omega * T);
        assert_below(err, bounds[m] * norm3(om0));
        tb_world_destroy(w);
    }
}

/* ---- conservation -------------------------------------------------------------- */

/* Torque-free and gravity-free: world P and L are exactly constant for the
   split methods (their kicks add exact zeros), |L| constant to 1e-12 for
   every method that rotates by unit quaternions, over 10^4 steps. */
static void torque_free_body_keeps_momenta(void **state)
{
    const double I[3] = { 1, 2, 3 }, x0[3] = { 0, 0, 0 }, v0[3] = { 1, 2, 3 }, om[3] = { 0.4, 3, -1 };
    const char *names[] = { "symplectic_euler", "verlet", "verlet_exact" };
    int m, i, k;
    (void)state;
    for (m = 0; m < 3; ++m) {
        tb_world *w = world_with(names[m], 0);
        tb_body_id id = body(w, I, x0, v0, om);
        double P0[3], L0[3], P[3], L[3], q[4], Lb[3], Lb0[3];
        tb_body_momentum(w, id, P0, L0);
        tb_body_orientation(w, id, q);
        to_body(q, L0, Lb0);
        for (i = 0; i < 10000; ++i)
            assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
        tb_body_momentum(w, id, P, L);
        for (k = 0; k < 3; ++k) {
            assert_true(P[k] == P0[k]);
            assert_true(L[k] == L0[k]);
        }
        /* the body-frame L has turned but kept its length */
        tb_body_orientation(w, id, q);
        to_body(q, L, Lb);
        assert_rel(norm3(Lb), norm3(Lb0), 1e-12);
        tb_world_destroy(w);
    }
}

/* ---- the intermediate-axis flip --------------------------------------------------- */

/* I = diag(1, 2, 3), w0 = (0.01, 5, 0.01) in the body frame, q0 = identity,
   20 s. Reference: tumble's RK4 at h/64 and h/128 must agree to 1e-9 rad
   (the test checks it), then the h/128 run is the truth. */
static void flip_run(const char *integrator, double h, int steps, double q[4], double *energy_drift,
                     double *l_drift)
{
    const double I[3] = { 1, 2, 3 }, zero[3] = { 0, 0, 0 }, om[3] = { 0.01, 5, 0.01 };
    tb_world *w = world_with(integrator, 0);
    tb_body_id id = body(w, I, zero, zero, om);
    double e0 = tb_world_energy(w).rotational, L0[3], L[3], Lb[3];
    int i;
    tb_body_momentum(w, id, NULL, L0);
    for (i = 0; i < steps; ++i)
        assert_int_equal(tb_world_step(w, h), TB_OK);
    tb_body_orientation(w, id, q);
    tb_body_momentum(w, id, NULL, L);
    to_body(q, L, Lb);
    *energy_drift = fabs(tb_world_energy(w).rotational / e0 - 1);
    *l_drift = fabs(norm3(Lb) / norm3(L0) - 1);
    tb_world_destroy(w);
}

static void intermediate_axis_flip_against_reference(void **state)
{
    const double h = 1.0 / 60;
    const int n = 1200;
    double ref[4], ref2[4], q[4], e, l, gap;
    int m;
    (void)state;
    flip_run("rk4", h / 64, n * 64, ref2, &e, &l);
    flip_run("rk4", h / 128, n * 128, ref, &e, &l);
    gap = angle_between(ref, ref2);
    print_message("reference: rk4 at h/64 and h/128 differ by %.3e rad (h/128 errs ~1/16 of that)\n", gap);
    assert_below(gap, 1e-9);
    for (m = 1; m < ALL_COUNT; ++m) {
        flip_run(ALL[m], h, n, q, &e, &l);
        print_message("%-17s |L| drift %.2e  energy drift %.2e  orientation error %.3e rad\n", ALL[m], l, e,
                      angle_between(q, ref));
        if (!strcmp(ALL[m], "verlet_exact")) {
            assert_below(l, 1e-12);
            assert_below(e, 1e-9);
            assert_below(angle_between(q, ref), 1e-6);
        }
    }
}

/* ---- forces at points ----------------------------------------------------------------- */

/* A push f at a point r from the centre over one step h gives dP = h f and
   dL = h r x f, exactly, for every method (the held force is constant). The
   same push at a body-frame point gives the same after rotating the point. */
static void off_centre_push_adds_torque(void **state)
{
    const double I[3] = { 1, 2, 3 }, x0[3] = { 1, 1, 1 }, zero[3] = { 0, 0, 0 };
    const double f[3] = { 0, 3, 0 }, p[3] = { 1.5, 1, 1 }, h = 0.01; /* r = (0.5, 0, 0): r x f = (0, 0, 1.5) */
    int m;
    (void)state;
    for (m = 0; m < ALL_COUNT; ++m) {
        tb_world *w = world_with(ALL[m], 0);
        tb_body_id id = body(w, I, x0, zero, zero);
        double P[3], L[3];
        assert_int_equal(tb_body_apply_force(w, id, f, p), TB_OK);
        assert_int_equal(tb_world_step(w, h), TB_OK);
        tb_body_momentum(w, id, P, L);
        assert_rel(P[1], h * 3, 1e-15);
        assert_rel(L[2], h * 1.5, 1e-15);
        assert_true(L[0] == 0 && L[1] == 0);
        tb_world_destroy(w);
    }
    {
        tb_world *w = world_with("verlet", 0);
        tb_body_def def = tb_default_body_def();
        const double local[3] = { 0, 0.5, 0 }, push[3] = { 2, 0, 0 };
        tb_body_id id;
        double L[3];
        /* turned 90 degrees about z: body y is world -x */
        def.orientation[0] = cos(PI / 4), def.orientation[3] = sin(PI / 4);
        assert_int_equal(tb_world_add_body(w, &def, &id), TB_OK);
        assert_int_equal(tb_body_apply_force_at_body_point(w, id, push, local), TB_OK);
        assert_int_equal(tb_world_step(w, h), TB_OK);
        tb_body_momentum(w, id, NULL, L);
        /* r = (-0.5, 0, 0), r x f = 0: pushing along the lever arm turns nothing */
        assert_true(fabs(L[2]) < 1e-16 && fabs(L[1]) < 1e-16);
        tb_world_destroy(w);
    }
}

/* ---- bad input ---------------------------------------------------------------------- */

static void bad_bodies_are_refused(void **state)
{
    const double I[3] = { 1, 2, 3 }, zero[3] = { 0, 0, 0 };
    tb_world *w = world_with("verlet", -9.81);
    tb_body_id id = body(w, I, zero, zero, zero), gone = body(w, I, zero, zero, zero);
    tb_body_def def;
    double q[4], x[3], before[16], after[16];
    const double nanv[3] = { NAN, 0, 0 }, bad_q[4] = { 1, 1, 0, 0 }, zero_q[4] = { 0, 0, 0, 0 };
    (void)state;
    assert_int_equal(tb_world_remove_body(w, gone), TB_OK);
    tb_body_position(w, id, before);
    tb_body_orientation(w, id, before + 3);
    tb_body_momentum(w, id, before + 7, before + 10);

    def = tb_default_body_def();
    def.orientation[0] = 0;
    assert_int_equal(tb_world_add_body(w, &def, NULL), TB_ERR_ARGUMENT); /* zero quaternion */
    assert_non_null(strstr(tb_world_message(w), "unit quaternion"));
    def = tb_default_body_def();
    def.orientation[1] = 0.5;
    assert_int_equal(tb_world_add_body(w, &def, NULL), TB_ERR_ARGUMENT); /* norm 1.118 */
    def = tb_default_body_def();
    def.mass.mass = 0;
    assert_int_equal(tb_world_add_body(w, &def, NULL), TB_ERR_ARGUMENT);
    def.mass.mass = -2;
    assert_int_equal(tb_world_add_body(w, &def, NULL), TB_ERR_ARGUMENT);
    def = tb_default_body_def();
    def.mass.inertia[1] = 0;
    assert_int_equal(tb_world_add_body(w, &def, NULL), TB_ERR_ARGUMENT);
    def.mass.inertia[1] = -1;
    assert_int_equal(tb_world_add_body(w, &def, NULL), TB_ERR_ARGUMENT);
    def = tb_default_body_def();
    def.mass.inertia[0] = 1, def.mass.inertia[1] = 1, def.mass.inertia[2] = 3; /* 1 + 1 < 3 */
    assert_int_equal(tb_world_add_body(w, &def, NULL), TB_ERR_ARGUMENT);
    assert_non_null(strstr(tb_world_message(w), "triangle"));
    def = tb_default_body_def();
    def.position[1] = INFINITY;
    assert_int_equal(tb_world_add_body(w, &def, NULL), TB_ERR_ARGUMENT);
    def = tb_default_body_def();
    def.angular_velocity[2] = NAN;
    assert_int_equal(tb_world_add_body(w, &def, NULL), TB_ERR_ARGUMENT);
    def = tb_default_body_def();
    def.angular_damping = -1;
    assert_int_equal(tb_world_add_body(w, &def, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_world_add_body(w, NULL, NULL), TB_ERR_ARGUMENT);

    assert_int_equal(tb_body_set_position(w, id, nanv), TB_ERR_ARGUMENT);
    assert_int_equal(tb_body_set_velocity(w, id, nanv), TB_ERR_ARGUMENT);
    assert_int_equal(tb_body_set_angular_velocity(w, id, nanv), TB_ERR_ARGUMENT);
    assert_int_equal(tb_body_set_orientation(w, id, bad_q), TB_ERR_ARGUMENT);
    assert_int_equal(tb_body_set_orientation(w, id, zero_q), TB_ERR_ARGUMENT);
    assert_int_equal(tb_body_apply_force(w, id, nanv, zero), TB_ERR_ARGUMENT);
    assert_int_equal(tb_body_apply_force(w, id, zero, nanv), TB_ERR_ARGUMENT);
    assert_int_equal(tb_body_apply_torque(w, id, nanv), TB_ERR_ARGUMENT);
    assert_int_equal(tb_body_position(w, gone, x), TB_ERR_STALE_ID);
    assert_int_equal(tb_body_orientation(w, gone, q), TB_ERR_STALE_ID);
    assert_int_equal(tb_body_set_position(w, gone, zero), TB_ERR_STALE_ID);
    assert_int_equal(tb_body_apply_torque(w, gone, zero), TB_ERR_STALE_ID);
    assert_int_equal(tb_world_remove_body(w, gone), TB_ERR_STALE_ID);
    assert_non_null(strstr(tb_world_message(w), "removed"));

    assert_int_equal(tb_world_body_count(w), 1);
    tb_body_position(w, id, after);
    tb_body_orientation(w, id, after + 3);
    tb_body_momentum(w, id, after + 7, after + 10);
    assert_memory_equal(before, after, 13 * sizeof(double));
    /* nothing was held either: a step moves it by gravity alone */
    assert_int_equal(tb_world_step(w, 0.5), TB_OK);
    tb_body_momentum(w, id, after + 7, after + 10);
    assert_rel(after[9], -9.81 * 2 * 0.5, 1e-15);
    assert_true(after[10] == 0 && after[11] == 0 && after[12] == 0);
    tb_world_destroy(w);
}

/* Removing a body keeps the others' ids and state (swap-remove). */
static void bodies_survive_swap_remove(void **state)
{
    const double I[3] = { 1, 2, 3 }, zero[3] = { 0, 0, 0 }, xa[3] = { 1, 0, 0 }, xc[3] = { 3, 0, 0 };
    const double oc[3] = { 0, 0, 2 };
    tb_world *w = world_with("rk4", 0);
    tb_body_id a = body(w, I, xa, zero, zero), b = body(w, I, zero, zero, zero), c = body(w, I, xc, zero, oc);
    double x[3], om[3];
    (void)state;
    (void)b;
    assert_int_equal(tb_world_remove_body(w, a), TB_OK);
    assert_int_equal(tb_body_position(w, c, x), TB_OK);
    assert_true(x[0] == 3);
    assert_int_equal(tb_body_angular_velocity(w, c, om), TB_OK);
    assert_rel(om[2], 2, 1e-15);
    assert_int_equal(tb_world_step(w, 0.1), TB_OK);
    tb_world_destroy(w);
}

/* Diagnostics: rotational energy L . w / 2 and angular momentum about the
   origin, sum (x x P + L) for bodies plus m x x v for particles. In free
   flight (no gravity, no torque) the total about the origin is conserved:
   straight lines keep x x P, and L is the state. */
static void diagnostics_add_up(void **state)
{
    const double I[3] = { 1, 2, 3 }, x0[3] = { 1, -2, 0.5 }, v0[3] = { 0.5, 1, -1 }, om[3] = { 2, 0, 0 };
    tb_world *w = world_with("verlet", 0);
    tb_particle_def p = tb_default_particle_def();
    tb_energy e;
    double l0[3], l[3], expected[3];
    int i;
    (void)state;
    body(w, I, x0, v0, om); /* mass 2, w along a principal axis: L = (2, 0, 0) */
    p.position[1] = 3;
    p.velocity[0] = 1;
    p.mass = 0.5;
    assert_int_equal(tb_world_add_particle(w, &p, NULL), TB_OK);
    e = tb_world_energy(w);
    assert_rel(e.rotational, 0.5 * I[0] * om[0] * om[0], 1e-15);
    assert_rel(e.kinetic, 0.5 * 2 * (0.25 + 1 + 1) + 0.5 * 0.5 * 1, 1e-15);
    /* x x P of the body: (1, -2, 0.5) x (1, 2, -2) = (3, 2.5, 4); L = (2, 0, 0);
       the particle: (0, 3, 0) x (0.5, 0, 0) = (0, 0, -1.5) */
    expected[0] = 3 + 2, expected[1] = 2.5, expected[2] = 4 - 1.5;
    tb_world_angular_momentum(w, l0);
    for (i = 0; i < 3; ++i)
        assert_rel(l0[i], expected[i], 1e-15);
    for (i = 0; i < 600; ++i)
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
    tb_world_angular_momentum(w, l);
    for (i = 0; i < 3; ++i)
        assert_true(fabs(l[i] - l0[i]) <= 1e-12 * 10);
    tb_world_destroy(w);
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(diagnostics_add_up),
    cmocka_unit_test(centre_of_mass_falls_freely),
    cmocka_unit_test(constant_torque_spins_up),
    cmocka_unit_test(symmetric_top_precesses),
    cmocka_unit_test(torque_free_body_keeps_momenta),
    cmocka_unit_test(intermediate_axis_flip_against_reference),
    cmocka_unit_test(off_centre_push_adds_torque),
    cmocka_unit_test(bad_bodies_are_refused),
    cmocka_unit_test(bodies_survive_swap_remove),
};
TB_TEST_MAIN(tests)
