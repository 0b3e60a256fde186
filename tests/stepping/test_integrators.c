/* test_integrators.c: each method against the theory of its order and its
   stability function, on problems whose exact solution is known. */
#include "test_main.h"
#include "tumble.h"
#include "particle_worlds.h"

#include <math.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

/* A unit mass on a spring of stiffness w^2 to an anchor at the origin, rest
   length 0, no gravity: x'' = -w^2 x along x. */
static tb_world *oscillator(const char *integrator, double w, double x0, double v0, tb_particle_id *id)
{
    tb_world_def def = tb_default_world_def();
    tb_particle_def p = tb_default_particle_def();
    tb_spring_def s = tb_default_spring_def();
    tb_world *world;
    def.gravity[2] = 0;
    def.integrator = integrator;
    assert_int_equal(tb_world_create(&def, &world, NULL, 0), TB_OK);
    p.position[0] = x0;
    p.velocity[0] = v0;
    assert_int_equal(tb_world_add_particle(world, &p, id), TB_OK);
    s.a = *id;
    s.stiffness = w * w;
    s.rest_length = 0;
    assert_int_equal(tb_world_add_spring(world, &s, NULL), TB_OK);
    return world;
}

/* Error in phase space, |(x, v / w) - exact|, after n steps of T / n.
   dopri5 runs at tolerance 1e100, which accepts every step whole: the
   fixed-step Dormand-Prince method. */
static double oscillator_error(const char *integrator, double T, int n)
{
    const double w = 2, x0 = 1;
    tb_particle_id id;
    tb_world *world = oscillator(integrator, w, x0, 0, &id);
    double x[3], v[3], ex, ev;
    int i;
    if (strcmp(integrator, "dopri5") == 0)
        assert_int_equal(tb_world_set_tolerance(world, 1e100), TB_OK);
    for (i = 0; i < n; ++i)
        assert_int_equal(tb_world_step(world, T / n), TB_OK);
    tb_particle_position(world, id, x);
    tb_particle_velocity(world, id, v);
    tb_world_destroy(world);
    ex = x[0] - x0 * cos(w * T);
    ev = (v[0] + x0 * w * sin(w * T)) / w;
    return sqrt(ex * ex + ev * ev);
}

/* Order p from halving the step: e(h) / e(h/2) = 2^p in the asymptotic
   range. The step counts keep h w small enough to be asymptotic and the
   error far above rounding (RK4 at n = 200 errs about 1e-7). */
static void check_order(const char *integrator, int n, double expected)
{
    const double T = 5;
    double e1 = oscillator_error(integrator, T, n), e2 = oscillator_error(integrator, T, 2 * n);
    double order = log2(e1 / e2);
    print_message("%-17s h = %-8.3g error %.3e -> %.3e, order %.3f\n", integrator, T / n, e1, e2, order);
    assert_true(fabs(order - expected) <= 0.15);
}

static void euler_is_first_order(void **state) { (void)state; check_order("euler", 20000, 1); }
static void symplectic_euler_is_first_order(void **state) { (void)state; check_order("symplectic_euler", 2000, 1); }
static void verlet_is_second_order(void **state) { (void)state; check_order("verlet", 400, 2); }
static void rk4_is_fourth_order(void **state) { (void)state; check_order("rk4", 100, 4); }
/* the orders the header's table gives the other methods: verlet_exact
   translates as verlet; implicit Euler is first order; dopri5's advancing
   solution is fifth */
static void verlet_exact_is_second_order(void **state) { (void)state; check_order("verlet_exact", 400, 2); }
static void implicit_euler_is_first_order(void **state) { (void)state; check_order("implicit_euler", 2000, 1); }
static void dopri5_is_fifth_order(void **state) { (void)state; check_order("dopri5", 25, 5); }

/* Force evaluations a step, as the header's table gives them, counted by a
   callback that adds nothing, over 10 steps of 0.5 s of a particle on a
   spring of w = 2 rad/s (h w = 1, which dopri5 divides at 1e-6):
   euler, symplectic_euler and implicit_euler 1, verlet and verlet_exact 2
   (the end-of-step forces are not reused: they may depend on velocity),
   rk4 4, dopri5 1 + 6 per accepted substep without bodies (first same as
   last), and tb_world_work counts the same. */
static tb_status count_calls(const tb_force_args *args, void *user);
static void each_method_makes_its_force_evaluations(void **state)
{
    const char *names[] = { "euler", "symplectic_euler", "verlet", "rk4", "verlet_exact", "implicit_euler" };
    const long expected[] = { 1, 1, 2, 4, 2, 1 };
    size_t m;
    (void)state;
    for (m = 0; m < 7; ++m) {
        tb_particle_id id;
        tb_world *world = oscillator(m < 6 ? names[m] : "dopri5", 2, 1, 0, &id);
        long calls = 0, want;
        tb_work work;
        int i;
        assert_int_equal(tb_world_add_force(world, count_calls, &calls, NULL), TB_OK);
        for (i = 0; i < 10; ++i)
            assert_int_equal(tb_world_step(world, 0.5), TB_OK);
        work = tb_world_work(world);
        want = m < 6 ? 10 * expected[m] : (long)(work.steps + 6 * (work.substeps + work.rejected));
        print_message("%-17s %ld force evaluations in 10 steps (%llu substeps)\n", m < 6 ? names[m] : "dopri5",
                      calls, (unsigned long long)work.substeps);
        assert_int_equal(calls, want);
        assert_int_equal((long)work.evaluations, calls);
        if (m == 6)
            assert_true(work.substeps > work.steps); /* the tolerance divided the steps */
        tb_world_destroy(world);
    }
}

/* A tracer in the vortex v = w (-y, x, 0) obeys the linear test equation
   z' = i w z with z = x + i y, so a method with stability function R moves it
   by the factor R(i w h) each step: after n steps the radius is exactly
   r0 |R(i w h)|^n, up to rounding. */
static double vortex_radius(const char *integrator, double w, double h, int n, double r0)
{
    tb_world_def def = tb_default_world_def();
    tb_tracer_def t = tb_default_tracer_def();
    double omega[3] = { 0, 0, 0 }, centre[3] = { 0, 0, 0 }, x[3];
    tb_tracer_id id;
    tb_world *world;
    int i;
    omega[2] = w;
    def.integrator = integrator;
    assert_int_equal(tb_world_create(&def, &world, NULL, 0), TB_OK);
    assert_int_equal(tb_world_add_vortex_field(world, omega, centre, NULL), TB_OK);
    t.position[0] = r0;
    t.position[2] = 0.25; /* the axial coordinate must not move */
    assert_int_equal(tb_world_add_tracer(world, &t, &id), TB_OK);
    for (i = 0; i < n; ++i)
        assert_int_equal(tb_world_step(world, h), TB_OK);
    assert_int_equal(tb_tracer_position(world, id, x), TB_OK);
    assert_true(x[2] == 0.25);
    tb_world_destroy(world);
    return hypot(x[0], x[1]);
}

static void vortex_radius_follows_stability_functions(void **state)
{
    const double w = 2 * PI, h = 0.01, r0 = 1.5, th = w * h;
    const int n = 100; /* one turn */
    /* forward Euler: |1 + i th| = sqrt(1 + th^2) */
    const double euler = r0 * pow(1 + th * th, n / 2.0);
    /* RK4: R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24 at z = i th */
    const double re = 1 - th * th / 2 + th * th * th * th / 24, im = th - th * th * th / 6;
    const double rk4 = r0 * pow(re * re + im * im, n / 2.0);
    double r;
    (void)state;
    r = vortex_radius("euler", w, h, n, r0);
    print_message("euler: r / r0 = %.15f (theory %.15f)\n", r / r0, euler / r0);
    assert_rel(r, euler, 1e-12);
    r = vortex_radius("rk4", w, h, n, r0);
    print_message("rk4: 1 - r / r0 = %.6e (theory %.6e)\n", 1 - r / r0, 1 - rk4 / r0);
    assert_rel(r, rk4, 1e-12);
    /* the figure the issue quotes: RK4 loses 4.27e-8 of the radius per turn */
    assert_true(fabs((1 - rk4 / r0) - 4.27e-8) < 0.005e-8);
    /* and forward Euler grows over 10 turns exactly as (1 + th^2)^(n/2) */
    r = vortex_radius("euler", w, h, 10 * n, r0);
    assert_rel(r, r0 * pow(1 + th * th, 10 * n / 2.0), 1e-12);
}

/* Explicit Euler on the oscillator multiplies v^2 + w^2 x^2 by exactly
   1 + (h w)^2 per step: the energy grows geometrically. */
static void euler_energy_grows_as_predicted(void **state)
{
    const double w = 3, h = 0.01 / 3; /* h w = 0.01 */
    tb_particle_id id;
    tb_world *world = oscillator("euler", w, 0.7, 0.4, &id);
    double e0 = tb_world_energy(world).total;
    int i;
    (void)state;
    for (i = 0; i < 2000; ++i)
        assert_int_equal(tb_world_step(world, h), TB_OK);
    assert_rel(tb_world_energy(world).total, e0 * pow(1 + (h * w) * (h * w), 2000), 1e-11);
    tb_world_destroy(world);
}

/* Symplectic methods conserve a modified energy exactly, so the true energy
   only oscillates, within a band set by h w, and never drifts. Over 10^6
   steps the deviation must stay inside that band and be no wider at the end
   than at the start.
   - symplectic Euler conserves Q = v^2 + w^2 x^2 - h w^2 x v; since
     w |x v| <= E, Q / (2 + h w) <= E <= Q / (2 - h w), and with v0 = 0,
     Q = 2 E0: |E/E0 - 1| <= h w / (2 - h w);
   - Verlet conserves v^2 + w^2 x^2 (1 - (h w)^2 / 4): |E/E0 - 1| <=
     (h w)^2 / 4 / (1 - (h w)^2 / 4). */
static void check_bounded(const char *integrator, double band)
{
    const double w = 1, h = 0.1;
    const long n = 1000000, window = 1000;
    tb_particle_id id;
    tb_world *world = oscillator(integrator, w, 1, 0, &id);
    double e0 = tb_world_energy(world).total, early = 0, late = 0;
    long i;
    for (i = 1; i <= n; ++i) {
        double dev;
        assert_int_equal(tb_world_step(world, h), TB_OK);
        if (i > window && i <= n - window)
            continue; /* energies cost a pass: look at both ends only */
        dev = fabs(tb_world_energy(world).total / e0 - 1);
        if (i <= window && dev > early)
            early = dev;
        if (i > n - window && dev > late)
            late = dev;
    }
    print_message("%s: max |E/E0 - 1| %.4e over the first 10^3 steps, %.4e over the last (bound %.4e)\n",
                  integrator, early, late, band);
    assert_below(early, band);
    assert_below(late, band);
    /* no drift: the band at the end is the band at the start (windows of
       ~16 periods sample the extremes equally well) */
    assert_rel(late, early, 0.02);
    tb_world_destroy(world);
}

static void symplectic_euler_energy_stays_bounded(void **state)
{
    (void)state;
    check_bounded("symplectic_euler", 0.1 / (2 - 0.1) * (1 + 1e-9));
}

static void verlet_energy_stays_bounded(void **state)
{
    (void)state;
    check_bounded("verlet", 0.0025 / (1 - 0.0025) * (1 + 1e-9));
}

static tb_status count_calls(const tb_force_args *args, void *user)
{
    (void)args;
    ++*(long *)user;
    return TB_OK;
}

/* A spring of w = 1e10 rad/s under dopri5 at 1/60 s: its stability bound
   (|h w| about 3.3) needs substeps of about 3e-10 s, 5e7 of them, past
   the 1e6 it takes. It is refused with that reason once the controller
   has settled, after a few hundred force evaluations (counted through a
   callback) instead of the 6e6 it took to reach the cap; the world is
   left as it was. The same scene at w = 1e4 takes its ~1000 substeps. */
static void dopri5_refuses_a_stiff_step_quickly(void **state)
{
    tb_particle_id id;
    tb_world *world = oscillator("dopri5", 1e10, 1, 0, &id);
    long calls = 0;
    double x[3];
    (void)state;
    assert_int_equal(tb_world_add_force(world, count_calls, &calls, NULL), TB_OK);
    assert_int_equal(tb_world_step(world, 1.0 / 60), TB_ERR_ARGUMENT);
    print_message("dopri5 on w = 1e10: refused after %ld force evaluations: %s\n", calls, tb_world_message(world));
    assert_non_null(strstr(tb_world_message(world), "too stiff"));
    assert_in_range(calls, 1, 7 * 1000);
    assert_int_equal(tb_particle_position(world, id, x), TB_OK);
    assert_true(x[0] == 1 && tb_world_time(world) == 0);
    tb_world_destroy(world);
    world = oscillator("dopri5", 1e4, 1, 0, &id);
    assert_int_equal(tb_world_step(world, 1.0 / 60), TB_OK);
    tb_world_destroy(world);
}

/* dopri5 keeps the estimated error of each substep of s seconds within
   tolerance x s (relative to 1 + |y|); over T = 5 s of the oscillator
   (w = 2, taken in outer steps of 0.5 s, h w = 1) the global error stays
   within tolerance x T (measured 0.29, 0.065 and 0.011 tol T at 1e-4,
   1e-7 and 1e-10: the fifth-order solution advances, so the error falls
   a little faster than the tolerance). */
static void dopri5_error_follows_tolerance(void **state)
{
    const double tols[] = { 1e-4, 1e-7, 1e-10 };
    size_t k;
    (void)state;
    for (k = 0; k < 3; ++k) {
        const double w0 = 2, T = 5;
        tb_particle_id id;
        tb_world *world = oscillator("dopri5", w0, 1, 0, &id);
        double x[3], v[3], err;
        int i;
        assert_int_equal(tb_world_set_tolerance(world, tols[k]), TB_OK);
        for (i = 0; i < 10; ++i)
            assert_int_equal(tb_world_step(world, T / 10), TB_OK);
        tb_particle_position(world, id, x);
        tb_particle_velocity(world, id, v);
        err = hypot(x[0] - cos(w0 * T), (v[0] + w0 * sin(w0 * T)) / w0);
        print_message("dopri5 tol %.0e: error %.3e (%.3f tol T)\n", tols[k], err, err / (tols[k] * T));
        assert_below(err, tols[k] * T);
        tb_world_destroy(world);
    }
}

/* ---- the tolerance against the global error --------------------------------- */

/* Kepler orbit, a = 1 m, eccentricity 0.5, from periapsis (0.5 m, at
   sqrt 3 m/s); after 10 periods (T = 20 pi s) it is back at the start. The
   error is the distance from it, in frames of H. */
static double kepler_error(double tol, double H, tb_work *work)
{
    const double T = 20 * PI;
    const long n = (long)ceil(T / H);
    tb_world_def def = tb_default_world_def();
    tb_particle_def p = tb_default_particle_def();
    tb_world *w;
    tb_particle_id id;
    double x[3];
    def.gravity[2] = 0;
    def.integrator = "dopri5";
    def.tolerance = tol;
    assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
    p.position[0] = 0.5;
    p.velocity[1] = sqrt(3.0);
    assert_int_equal(tb_world_add_particle(w, &p, &id), TB_OK);
    assert_int_equal(tb_world_add_force(w, central_gravity, NULL, NULL), TB_OK);
    step_through(w, T, n);
    tb_particle_position(w, id, x);
    *work = tb_world_work(w);
    tb_world_destroy(w);
    return hypot(x[0] - 0.5, x[1]);
}

/* The angle (rad) of the turn from a to b, accurate for small angles. */
static double turn_between(const double a[4], const double b[4])
{
    const double w = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    const double x = a[0] * b[1] - a[1] * b[0] - (a[2] * b[3] - a[3] * b[2]);
    const double y = a[0] * b[2] - a[2] * b[0] - (a[3] * b[1] - a[1] * b[3]);
    const double z = a[0] * b[3] - a[3] * b[0] - (a[1] * b[2] - a[2] * b[1]);
    return 2 * atan2(sqrt(x * x + y * y + z * z), fabs(w));
}

/* A box-like body, I = diag(1, 2, 3) kg m^2, tumbling from w = (4, 1, 2)
   rad/s (about its least axis, away from the unstable middle one), for
   T = 20 s in n steps; its orientation at the end. */
static void tumble_run(const char *integrator, double tol, double h, long n, double q[4], tb_work *work)
{
    tb_world_def def = tb_default_world_def();
    tb_body_def b = tb_default_body_def();
    tb_world *w;
    tb_body_id id;
    long i;
    def.gravity[2] = 0;
    def.integrator = integrator;
    def.tolerance = tol;
    assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
    b.mass.inertia[0] = 1, b.mass.inertia[1] = 2, b.mass.inertia[2] = 3;
    b.angular_velocity[0] = 4, b.angular_velocity[1] = 1, b.angular_velocity[2] = 2;
    assert_int_equal(tb_world_add_body(w, &b, &id), TB_OK);
    for (i = 0; i < n; ++i)
        assert_int_equal(tb_world_step(w, h), TB_OK);
    tb_body_orientation(w, id, q);
    if (work)
        *work = tb_world_work(w);
    tb_world_destroy(w);
}

/* The tolerance is an error per second of simulated time: after T seconds
   the global error is about tolerance x T, whatever the frame step. On the
   Kepler orbit (position, m; T = 62.8 s) and the tumbling body
   (orientation, rad, against RK4 at 1/30720 s, itself checked to 1e-10
   rad by halving; T = 20 s), in frames of 0.1 s, the error at tolerances
   1e-4, 1e-6, 1e-8 and 1e-10 lies within [0.05, 5] tolerance x T
   (measured 0.096 to 1.7 on the orbit, 0.56 to 2.8 on the body); in 60 Hz
   frames, which cap the substeps, within 5 tolerance x T. The work counts
   follow the method: with bodies, whose quaternions are projected after
   each substep, every substep evaluates 7 stages (6 when it retries a
   rejected one, whose first stage it keeps); without, the first stage of a
   substep is the last of the one before (first same as last), so a step
   costs 1 + 6 per substep. */
static void dopri5_global_error_follows_tolerance(void **state)
{
    const double tols[] = { 1e-4, 1e-6, 1e-8, 1e-10 }, T = 20, h = 1.0 / 60;
    double ref[4], ref2[4], gap;
    size_t k;
    int frames;
    (void)state;
    tumble_run("rk4", 0, h / 256, 1200 * 256, ref2, NULL);
    tumble_run("rk4", 0, h / 512, 1200 * 512, ref, NULL);
    gap = turn_between(ref, ref2);
    print_message("tumbling body: reference rk4 at 1/15360 and 1/30720 s differ by %.3g rad\n", gap);
    assert_below(gap, 1e-10);
    for (frames = 0; frames < 2; ++frames) {
        const double H = frames == 0 ? 0.1 : h, low = frames == 0 ? 0.05 : 0;
        for (k = 0; k < sizeof tols / sizeof tols[0]; ++k) {
            tb_work work;
            double q[4], orbit, body;
            orbit = kepler_error(tols[k], H, &work);
            print_message("H %.4f tol %.0e: Kepler error %.3g m = %.3g tol T (%llu substeps, %llu rejected, "
                          "%llu evaluations)\n", H, tols[k], orbit, orbit / (tols[k] * 20 * PI),
                          (unsigned long long)work.substeps, (unsigned long long)work.rejected,
                          (unsigned long long)work.evaluations);
            assert_true(work.evaluations == work.steps + 6 * (work.substeps + work.rejected));
            assert_below(orbit, 5 * tols[k] * 20 * PI);
            assert_true(orbit >= low * tols[k] * 20 * PI);
            tumble_run("dopri5", tols[k], H, (long)round(T / H), q, &work);
            body = turn_between(q, ref);
            print_message("H %.4f tol %.0e: body error %.3g rad = %.3g tol T (%llu substeps, %llu rejected, "
                          "%llu evaluations)\n", H, tols[k], body, body / (tols[k] * T),
                          (unsigned long long)work.substeps, (unsigned long long)work.rejected,
                          (unsigned long long)work.evaluations);
            assert_true(work.evaluations == 7 * work.substeps + 6 * work.rejected);
            assert_below(body, 5 * tols[k] * T);
            assert_true(body >= low * tols[k] * T);
        }
    }
}

/* ---- energy accounting -------------------------------------------------------- */

/* Gravity of GM = 1 m^3/s^2 at the origin that reports its potential
   -GM m / r when asked. */
static tb_status central_gravity_with_potential(const tb_force_args *a, void *user)
{
    size_t i;
    tb_status st = central_gravity(a, user);
    for (i = 0; a->potential && i < a->count; ++i) {
        const double *x = a->positions + 3 * i;
        *a->potential -= a->masses[i] / sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    }
    return st;
}

/* Energy that adds up. The Kepler orbit (1 kg from periapsis 0.5 m at
   sqrt 3 m/s) has E = v^2 / 2 - GM / r = -0.5 J exactly, which the total
   reaches only with the callback's potential (-2 J); after 10 periods at
   60 Hz under rk4 it has drifted by what the integrator made (measured
   below). A damped spring (z = 0.1) under verlet and a particle thrown
   through linear and quadratic drag lose what tb_work.damping_work says,
   to the trapezoid rule's O(h^2); a ball bouncing at restitution 0.5 under
   verlet loses what contact_work says. */
static void energy_accounting_adds_up(void **state)
{
    (void)state;
    {
        tb_world_def def = tb_default_world_def();
        tb_particle_def p = tb_default_particle_def();
        tb_world *w;
        tb_energy e0, e1;
        long i;
        def.gravity[2] = 0;
        def.integrator = "rk4";
        assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
        p.position[0] = 0.5;
        p.velocity[1] = sqrt(3.0);
        assert_int_equal(tb_world_add_particle(w, &p, NULL), TB_OK);
        assert_int_equal(tb_world_add_force(w, central_gravity_with_potential, NULL, NULL), TB_OK);
        assert_int_equal(tb_world_energy_with_callbacks(w, &e0), TB_OK);
        assert_rel(e0.total, -0.5, 1e-15);
        assert_rel(e0.potential, -2, 1e-15);
        assert_rel(tb_world_energy(w).total, 1.5, 1e-15); /* without the callback: kinetic alone */
        for (i = 0; i < 3770; ++i) /* 10 periods of 2 pi s at 60 Hz */
            assert_int_equal(tb_world_step(w, 20 * PI / 3770), TB_OK);
        assert_int_equal(tb_world_energy_with_callbacks(w, &e1), TB_OK);
        print_message("Kepler, rk4 at 60 Hz: E %.15g -> %.15g J (drift %.3g)\n", e0.total, e1.total,
                      e1.total / e0.total - 1);
        assert_below(fabs(e1.total / e0.total - 1), 1e-6);
        tb_world_destroy(w);
    }
    {   /* damped spring, then drag */
        int k;
        for (k = 0; k < 2; ++k) {
            tb_world_def def = tb_default_world_def();
            tb_particle_def p = tb_default_particle_def();
            tb_spring_def sp = tb_default_spring_def();
            tb_world *w;
            tb_particle_id id;
            tb_work work;
            double e0, e1;
            int i;
            def.gravity[2] = k == 0 ? 0 : -9.81;
            def.linear_drag = k == 0 ? 0 : 0.2;
            def.quadratic_drag = k == 0 ? 0 : 0.05;
            assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
            p.position[0] = 1;
            p.velocity[2] = k == 0 ? 0 : 10;
            p.velocity[0] = k == 0 ? 0 : 5;
            assert_int_equal(tb_world_add_particle(w, &p, &id), TB_OK);
            if (k == 0) {
                sp.a = id, sp.stiffness = 9, sp.damping = 2 * 0.1 * 3, sp.rest_length = 0;
                assert_int_equal(tb_world_add_spring(w, &sp, NULL), TB_OK);
            }
            e0 = tb_world_energy(w).total;
            for (i = 0; i < 5000; ++i)
                assert_int_equal(tb_world_step(w, 1e-3), TB_OK);
            e1 = tb_world_energy(w).total;
            work = tb_world_work(w);
            print_message("%s, verlet at 1 ms: energy change %.9g J, damping work %.9g J (off by %.2g)\n",
                          k == 0 ? "damped spring" : "drag", e1 - e0, work.damping_work,
                          (e1 - e0) / work.damping_work - 1);
            assert_rel(work.damping_work, e1 - e0, 1e-5);
            assert_true(work.contact_work == 0);
            tb_world_destroy(w);
        }
    }
    {   /* a bouncing ball */
        tb_world_def def = tb_default_world_def();
        tb_shape_def ground = tb_default_shape_def(), ball = tb_default_shape_def();
        tb_body_def b = tb_default_body_def();
        tb_world *w;
        tb_work work;
        double e0, e1;
        int i;
        assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
        ground.type = TB_SHAPE_PLANE;
        assert_int_equal(tb_world_add_shape(w, &ground, NULL), TB_OK);
        b.position[2] = 1.5;
        assert_int_equal(tb_world_add_body(w, &b, &ball.body), TB_OK);
        ball.restitution = 0.5;
        assert_int_equal(tb_world_add_shape(w, &ball, NULL), TB_OK);
        e0 = tb_world_energy(w).total;
        for (i = 0; i < 90; ++i)
            assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
        e1 = tb_world_energy(w).total;
        work = tb_world_work(w);
        print_message("bouncing ball, verlet at 60 Hz: energy change %.9g J, contact work %.9g J (off by %.2g)\n",
                      e1 - e0, work.contact_work, (e1 - e0) / work.contact_work - 1);
        assert_true(work.contact_work < 0);
        assert_rel(work.contact_work, e1 - e0, 1e-9);
        tb_world_destroy(w);
    }
}

/* A tracer in the vortex: RK methods of the Dormand-Prince pair on the
   rotation z' = i w z keep the radius to the tolerance. */
static void dopri5_moves_tracers(void **state)
{
    const double r = vortex_radius("dopri5", 2 * PI, 0.1, 10, 1.5); /* one turn in 10 outer steps */
    (void)state;
    print_message("dopri5 vortex: radius error %.3e after one turn\n", fabs(r / 1.5 - 1));
    assert_below(fabs(r / 1.5 - 1), 1e-6 * 10);
}


/* ---- auto ------------------------------------------------------------------- */

/* "auto" plans substeps from the spring's rate so that each step of
   h = 0.5 s (h w = 1) errs by at most the tolerance times h (an error per
   second of simulated time, relative to 1 + |y|, the norm of dopri5). The
   local error of every step is measured against the exact flow from that
   step's start. */
static void auto_meets_its_tolerance_per_step(void **state)
{
    const double tols[] = { 1e-3, 1e-6, 1e-9 };
    size_t k;
    (void)state;
    for (k = 0; k < 3; ++k) {
        const double w0 = 2, H = 0.5;
        tb_particle_id id;
        tb_world *world = oscillator("auto", w0, 1, 0, &id);
        const char *name;
        long substeps;
        double worst = 0;
        int i;
        assert_int_equal(tb_world_set_tolerance(world, tols[k]), TB_OK);
        for (i = 0; i < 10; ++i) {
            double x0[3], v0[3], x[3], v[3], ex, ev;
            tb_particle_position(world, id, x0);
            tb_particle_velocity(world, id, v0);
            assert_int_equal(tb_world_step(world, H), TB_OK);
            tb_particle_position(world, id, x);
            tb_particle_velocity(world, id, v);
            ex = x0[0] * cos(w0 * H) + v0[0] / w0 * sin(w0 * H);
            ev = -x0[0] * w0 * sin(w0 * H) + v0[0] * cos(w0 * H);
            worst = fmax(worst, sqrt(0.5 * (pow((x[0] - ex) / (1 + fabs(ex)), 2) + pow((v[0] - ev) / (1 + fabs(ev)), 2))));
        }
        name = tb_world_auto_choice(world, &substeps);
        assert_non_null(name);
        print_message("auto tol %.0e: %s x %ld substeps, worst local error %.3e (%.2f tol h)\n", tols[k], name,
                      substeps, worst, worst / (tols[k] * H));
        assert_below(worst, tols[k] * H);
        tb_world_destroy(world);
    }
}

static const char *auto_choice_after_a_step(tb_world *world, double h, double tol, long *substeps)
{
    assert_int_equal(tb_world_set_integrator(world, "auto"), TB_OK);
    assert_int_equal(tb_world_set_tolerance(world, tol), TB_OK);
    assert_int_equal(tb_world_step(world, h), TB_OK);
    return tb_world_auto_choice(world, substeps);
}

static tb_status push_nothing(const tb_force_args *args, void *user)
{
    (void)args, (void)user;
    return TB_OK;
}

/* What the scene contains decides: Verlet is exact for a sphere under
   gravity (one substep at any tolerance); callbacks hide their rates, so
   dopri5; tracers have no velocity to kick, so never a split method; a
   fast asymmetric spin at a tight tolerance needs verlet_exact's rotation. */
static void auto_picks_from_what_the_scene_contains(void **state)
{
    tb_world_def def = tb_default_world_def();
    tb_body_def b = tb_default_body_def();
    tb_tracer_def t = tb_default_tracer_def();
    const double omega[3] = { 0, 0, 3 }, centre[3] = { 0, 0, 0 };
    tb_world *world;
    long n;
    (void)state;
    assert_int_equal(tb_world_create(&def, &world, NULL, 0), TB_OK);
    b.velocity[0] = 3;
    b.angular_velocity[2] = 2;
    assert_int_equal(tb_world_add_body(world, &b, NULL), TB_OK);
    assert_string_equal(auto_choice_after_a_step(world, 1.0 / 60, 1e-12, &n), "verlet");
    assert_int_equal(n, 1);
    assert_int_equal(tb_world_add_force(world, push_nothing, NULL, NULL), TB_OK);
    assert_string_equal(auto_choice_after_a_step(world, 1.0 / 60, 1e-6, &n), "dopri5");
    tb_world_destroy(world);

    def.integrator = "auto"; /* a world of tracers refuses the default, verlet */
    assert_int_equal(tb_world_create(&def, &world, NULL, 0), TB_OK);
    def.integrator = NULL;
    assert_int_equal(tb_world_add_vortex_field(world, omega, centre, NULL), TB_OK);
    t.position[0] = 1;
    assert_int_equal(tb_world_add_tracer(world, &t, NULL), TB_OK);
    assert_string_equal(auto_choice_after_a_step(world, 0.1, 1e-6, &n), "rk4");
    tb_world_destroy(world);

    /* the intermediate-axis flip: I = diag(1, 2, 3), w = (0.01, 5, 0.01) */
    assert_int_equal(tb_world_create(&def, &world, NULL, 0), TB_OK);
    b = tb_default_body_def();
    b.mass.inertia[0] = 1, b.mass.inertia[1] = 2, b.mass.inertia[2] = 3;
    b.angular_velocity[0] = 0.01, b.angular_velocity[1] = 5, b.angular_velocity[2] = 0.01;
    assert_int_equal(tb_world_add_body(world, &b, NULL), TB_OK);
    assert_string_equal(auto_choice_after_a_step(world, 1.0 / 60, 1e-9, &n), "verlet_exact");
    {   /* the advice says why: every candidate's estimated cost */
        tb_advice advice;
        assert_int_equal(tb_world_advise(world, 1.0 / 60, &advice), TB_OK);
        print_message("%s\n", advice.text);
        assert_non_null(strstr(advice.text, "auto picks verlet_exact"));
        assert_non_null(strstr(advice.text, "cost per step"));
        assert_non_null(strstr(advice.text, " verlet 2.9 x "));
        assert_non_null(strstr(advice.text, " rk4 4 x "));
        assert_non_null(strstr(advice.text, " dopri5 about "));
    }
    assert_string_equal(auto_choice_after_a_step(world, 1.0 / 60, 1e-1, &n), "verlet");
    tb_world_destroy(world);
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(auto_meets_its_tolerance_per_step),
    cmocka_unit_test(auto_picks_from_what_the_scene_contains),
    cmocka_unit_test(dopri5_error_follows_tolerance),
    cmocka_unit_test(dopri5_global_error_follows_tolerance),
    cmocka_unit_test(energy_accounting_adds_up),
    cmocka_unit_test(dopri5_moves_tracers),
    cmocka_unit_test(dopri5_refuses_a_stiff_step_quickly),
    cmocka_unit_test(euler_is_first_order),
    cmocka_unit_test(symplectic_euler_is_first_order),
    cmocka_unit_test(verlet_is_second_order),
    cmocka_unit_test(rk4_is_fourth_order),
    cmocka_unit_test(verlet_exact_is_second_order),
    cmocka_unit_test(implicit_euler_is_first_order),
    cmocka_unit_test(dopri5_is_fifth_order),
    cmocka_unit_test(each_method_makes_its_force_evaluations),
    cmocka_unit_test(vortex_radius_follows_stability_functions),
    cmocka_unit_test(euler_energy_grows_as_predicted),
    cmocka_unit_test(symplectic_euler_energy_stays_bounded),
    cmocka_unit_test(verlet_energy_stays_bounded),
};
TB_TEST_MAIN(tests)
