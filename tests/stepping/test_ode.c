/* test_ode.c: ODE reference runs (docs/design.md section 5, third kind of truth).

   Scene: one point mass m under gravity g with linear drag f = -c v, from
   x0 with velocity v0, for T = 10 s at h = 1/60 s. In ODE it is one body
   stepped with dWorldStep, the drag added with dBodyAddForce before every
   step from the body's current velocity. In tumble it is one particle in a
   world with gravity g and linear_drag c.

   Closed form, with k = c/m and the deviation from terminal velocity
   d0 = v0 - g/k (vectors):
       v(t) = g/k + d0 e^{-kt}
       x(t) = x0 + (g/k) t + d0 (1 - e^{-kt}) / k

   Cases:
   - ode_symplectic_euler_matches_dworldstep: tumble's "symplectic_euler"
     follows ODE's trajectory at every step to 1e-12 relative;
   - ode_rk4_beats_dworldstep: tumble's "rk4" ends at least 1000 times closer
     to the closed form than ODE. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <ode/ode.h>

#include "tumble.h"
#include "test_main.h"

/* dDOUBLE is the Debian header default; the comparison is meaningless in
   single precision. A negative array size stops the build otherwise. */
typedef char dreal_is_double[sizeof(dReal) == sizeof(double) ? 1 : -1];

#define STEPS 600                 /* 10 s at 60 Hz */
static const double H = 1.0 / 60; /* s */

/* m = 3 kg so that 1/m is not exact (the kick's h/m rounds as it does in
   ODE); c = 1.5 N s/m, so k = c/m = 0.5 1/s: the velocity relaxes by e^-5 over
   the run, and drag matters as much as gravity. Every component of v0
   moves: x and y only under drag, z under drag and gravity. */
static const double MASS = 3.0;
static const double DRAG = 1.5;
static const double GRAVITY[3] = { 0, 0, -9.81 };
static const double X0[3] = { 0, 0, 1 };
static const double V0[3] = { 10, -4, 15 };

static double norm3(const double a[3])
{
    return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}

static double dist3(const double a[3], const double b[3])
{
    const double d[3] = { a[0] - b[0], a[1] - b[1], a[2] - b[2] };
    return norm3(d);
}

/* The closed form at time t. expm1 keeps 1 - e^{-kt} accurate. */
static void closed_form(double t, double x[3], double v[3])
{
    const double k = DRAG / MASS;
    int i;
    for (i = 0; i < 3; ++i) {
        const double terminal = GRAVITY[i] / k, d0 = V0[i] - terminal;
        v[i] = terminal + d0 * exp(-k * t);
        x[i] = X0[i] + terminal * t - d0 * expm1(-k * t) / k;
    }
}

/* |d0| = |v0 - g/k|, the size of the transient both error estimates scale
   with. */
static double deviation_norm(void)
{
    const double k = DRAG / MASS;
    double d0[3];
    int i;
    for (i = 0; i < 3; ++i)
        d0[i] = V0[i] - GRAVITY[i] / k;
    return norm3(d0);
}

/* ------------------------------------------------------------- ODE side -- */

typedef struct ode_run {
    int init_ok;                 /* dInitODE2 succeeded */
    int double_precision;        /* dCheckConfiguration("ODE_double_precision") */
    int auto_disable;            /* world or body flag: must stay 0 */
    double damping;              /* world and body linear + angular damping: must be 0 */
    int gravity_mode;            /* body feels gravity: must be 1 */
    int disabled_at;             /* first step after which the body was disabled, 0 if never */
    double angular_speed;        /* largest |omega| seen: must stay 0 */
    double x[STEPS + 1][3];      /* m, after each step; [0] is the start */
    double v[STEPS + 1][3];      /* m/s */
} ode_run;

/* Runs the scene in ODE and records everything; asserts nothing, so that an
   assertion failure never skips dCloseODE. ODE aborts on invalid input even
   with a handler, so only valid input is given. */
static void run_ode(ode_run *r)
{
    dWorldID world;
    dBodyID body;
    dMass mass;
    int n, i;

    memset(r, 0, sizeof *r);
    r->init_ok = dInitODE2(0) != 0;
    if (!r->init_ok)
        return;
    r->double_precision = dCheckConfiguration("ODE_double_precision") != 0;

    world = dWorldCreate();
    dWorldSetGravity(world, GRAVITY[0], GRAVITY[1], GRAVITY[2]);
    body = dBodyCreate(world);
    dMassSetSphereTotal(&mass, MASS, 0.1); /* the radius only sets the inertia */
    dBodySetMass(body, &mass);
    dBodySetPosition(body, X0[0], X0[1], X0[2]);
    dBodySetLinearVel(body, V0[0], V0[1], V0[2]);
    dBodySetAngularVel(body, 0, 0, 0);

    /* Defaults in 0.16: no auto-disable, no damping, gravity on. */
    r->auto_disable = dWorldGetAutoDisableFlag(world) || dBodyGetAutoDisableFlag(body);
    r->damping = fabs(dWorldGetLinearDamping(world)) + fabs(dWorldGetAngularDamping(world)) +
                 fabs(dBodyGetLinearDamping(body)) + fabs(dBodyGetAngularDamping(body));
    r->gravity_mode = dBodyGetGravityMode(body);

    memcpy(r->x[0], dBodyGetPosition(body), sizeof r->x[0]);
    memcpy(r->v[0], dBodyGetLinearVel(body), sizeof r->v[0]);
    for (n = 1; n <= STEPS; ++n) {
        const dReal *v = dBodyGetLinearVel(body);
        const dReal *w;
        /* The force accumulator is cleared by every step: add the drag anew. */
        dBodyAddForce(body, -DRAG * v[0], -DRAG * v[1], -DRAG * v[2]);
        dWorldStep(world, H);
        memcpy(r->x[n], dBodyGetPosition(body), sizeof r->x[n]);
        memcpy(r->v[n], dBodyGetLinearVel(body), sizeof r->v[n]);
        if (!dBodyIsEnabled(body) && !r->disabled_at)
            r->disabled_at = n;
        w = dBodyGetAngularVel(body);
        for (i = 0; i < 3; ++i)
            if (fabs(w[i]) > r->angular_speed)
                r->angular_speed = fabs(w[i]);
    }

    dBodyDestroy(body);
    dWorldDestroy(world);
    dCloseODE();
}

/* The ODE scene must be the scene described above, or nothing compares. */
static void check_ode_run(const ode_run *r)
{
    assert_true(r->init_ok);
    assert_true(r->double_precision);
    assert_int_equal(r->auto_disable, 0);
    assert_true(r->damping == 0);
    assert_int_equal(r->gravity_mode, 1);
    assert_int_equal(r->disabled_at, 0);
    assert_true(r->angular_speed == 0);
}

/* ---------------------------------------------------------- tumble side -- */

static tb_world *make_world(const char *integrator, tb_particle_id *id)
{
    char message[TB_MESSAGE_SIZE];
    tb_world_def def = tb_default_world_def();
    tb_particle_def p = tb_default_particle_def();
    tb_world *w = NULL;
    tb_status st;
    memcpy(def.gravity, GRAVITY, sizeof def.gravity);
    def.linear_drag = DRAG;
    def.integrator = integrator;
    st = tb_world_create(&def, &w, message, sizeof message);
    if (st != TB_OK)
        fail_msg("tb_world_create(%s): %s", integrator, message);
    memcpy(p.position, X0, sizeof p.position);
    memcpy(p.velocity, V0, sizeof p.velocity);
    p.mass = MASS;
    st = tb_world_add_particle(w, &p, id);
    if (st != TB_OK)
        fail_msg("tb_world_add_particle: %s", tb_world_message(w));
    return w;
}

/* Runs the scene with an integrator; position and velocity at the end. */
static void run_tumble(const char *integrator, double x[3], double v[3])
{
    tb_particle_id id;
    tb_world *w = make_world(integrator, &id);
    int n;
    for (n = 1; n <= STEPS; ++n)
        assert_int_equal(tb_world_step(w, H), TB_OK);
    assert_int_equal(tb_particle_position(w, id, x), TB_OK);
    assert_int_equal(tb_particle_velocity(w, id, v), TB_OK);
    tb_world_destroy(w);
}

/* ---------------------------------------------------------------- cases -- */

/* For a free body ODE's dWorldStep is semi-implicit Euler, and so is
   tumble's "symplectic_euler": per step, per component,
       f = m g - c v;   v += (h / m) f;   x += h v.
   ODE 0.16.2 (ode/src/step.cpp) sums the accumulator as (-c v) + m g (it
   skips the zero components of g; tumble adds m 0 = 0, which changes no
   bit), and
   updates lvel += (h * invMass) * facc, then pos += h * lvel (dxStepBody):
   the same operations, so the runs should agree to the last bit (the
   measured worst mismatch is printed).

   Why 1e-12 relative, measured against max(|ODE|, 1) at every step: if the
   two differed only in the order of their roundings, each step would add a
   few half-ulps (1.1e-16 relative) and the velocity map (factor 1 - kh < 1 per
   step) does not amplify them, so after 600 steps they would be at most
   about 600 x 4 x 1.1e-16 = 3e-13 apart. Any difference in the method
   itself is far larger: drifting with the old velocity instead of the new
   one moves x by h^2 |a| per step (|a| = 18 m/s^2 at the start): 5e-3 m,
   4e-3 relative, after the first step. */
static void ode_symplectic_euler_matches_dworldstep(void **state)
{
    static ode_run ode;
    tb_particle_id id;
    tb_world *w;
    double worst = 0, x[3], v[3];
    int n, worst_step = 0, identical = 0;
    (void)state;

    run_ode(&ode);
    check_ode_run(&ode);
    w = make_world("symplectic_euler", &id);
    for (n = 1; n <= STEPS; ++n) {
        double ex, ev;
        assert_int_equal(tb_world_step(w, H), TB_OK);
        assert_int_equal(tb_particle_position(w, id, x), TB_OK);
        assert_int_equal(tb_particle_velocity(w, id, v), TB_OK);
        ex = dist3(x, ode.x[n]) / fmax(norm3(ode.x[n]), 1);
        ev = dist3(v, ode.v[n]) / fmax(norm3(ode.v[n]), 1);
        if (ex > worst || ev > worst) {
            worst = fmax(ex, ev);
            worst_step = n;
        }
        if (memcmp(x, ode.x[n], sizeof x) == 0 && memcmp(v, ode.v[n], sizeof v) == 0)
            ++identical;
    }
    tb_world_destroy(w);
    print_message("symplectic_euler vs dWorldStep: worst relative mismatch %.3g (step %d; 0: none), "
                  "%d of %d steps bit-identical\n", worst, worst_step, identical, STEPS);
    assert_below(worst, 1e-12);
}

/* Errors at T = STEPS h (10 s up to the rounding of h, 1e-15 s, which moves
   x by 2e-14 m: nothing next to the errors below).

   Leading-order error analysis along d0 (both schemes propagate the
   deviation d_n = v_n - g/k by a polynomial R(kh) instead of e^{-kh}):
   - ODE (semi-implicit Euler): R = 1 - kh, so v is off by d(t) t k^2 h / 2,
     and each drift x += h v_{n+1} is short by h (kh) d_n / 2; together
       err_ode ~ (h/2) |d0| (2 - (2 + kT) e^{-kT})          = 0.59 m;
   - RK4 is the degree-4 Taylor polynomial of the exact affine flow: v is
     off by d(t) t k^5 h^4 / 120, and each position increment misses
     h (kh)^4 d_n / 120; the two nearly cancel and leave
       err_rk4 ~ |d0| k^4 h^4 T e^{-kT} / 120                = 9.8e-11 m.
   The next terms are O(kh) = 0.8 % of these. The predicted ratio is 6e9.

   Bounds: the ratio >= 1000 leaves a margin of 6e6 for rounding
   and fails for any first-order method (velocity Verlet taking the closing
   drag at the half-step velocity, a first-order scheme, measured 0.15 m, a
   ratio of 4). It alone does not prove the
   fourth order, so err_rk4 <= 1.5 x estimate is asserted too: a third-order
   method would be about 1/(kh) = 120 times the estimate. The 50 % leaves
   room for the O(kh) terms and for rounding, at most one ulp of |x|
   (< 256 m: 2.8e-14 m) per step, 1.7e-11 m = 17 % over 600 steps.
   ODE's own error must match its estimate within 5 % (next terms 0.8 %):
   this checks the closed form and the scene, so that the ratio compares the
   right things. */
static void ode_rk4_beats_dworldstep(void **state)
{
    static ode_run ode;
    const double k = DRAG / MASS, T = STEPS * H, d0 = deviation_norm();
    const double estimate_ode = H / 2 * d0 * (2 - (2 + k * T) * exp(-k * T));
    const double estimate_rk4 = d0 * pow(k * H, 4) * T * exp(-k * T) / 120;
    double x_exact[3], v_exact[3], x[3], v[3], err_ode, err_rk4;
    (void)state;

    run_ode(&ode);
    check_ode_run(&ode);
    closed_form(T, x_exact, v_exact);
    err_ode = dist3(ode.x[STEPS], x_exact);
    run_tumble("rk4", x, v);
    err_rk4 = dist3(x, x_exact);
    print_message("position error at t = %g s: dWorldStep %.4g m (estimate %.4g), "
                  "rk4 %.4g m (estimate %.4g), ratio %.3g\n",
                  T, err_ode, estimate_ode, err_rk4, estimate_rk4, err_ode / err_rk4);
    assert_rel(err_ode, estimate_ode, 0.05);
    assert_below(err_rk4, 1.5 * estimate_rk4);
    if (!(err_ode >= 1000 * err_rk4))
        fail_msg("dWorldStep error %.4g m is only %.3g times rk4's %.4g m (need 1000)", err_ode,
                 err_ode / err_rk4, err_rk4);
}

/* tumble's "verlet" takes the closing drag at the predicted end velocity
   v_n + h a_n, so it is second order with drag: its error is O(kh) = 1/120
   of a first-order method's times a constant of order one (the velocity
   Verlet that evaluates the drag at the half-step velocity is first order
   and lands at 0.15 m, a ratio of 4). Asserting a ratio of at least 100
   separates the two orders with room to spare; measured about 2e4. */
static void ode_verlet_beats_dworldstep(void **state)
{
    static ode_run ode;
    const double T = STEPS * H;
    double x_exact[3], v_exact[3], x[3], v[3], err_ode, err_verlet;
    (void)state;

    run_ode(&ode);
    check_ode_run(&ode);
    closed_form(T, x_exact, v_exact);
    err_ode = dist3(ode.x[STEPS], x_exact);
    run_tumble("verlet", x, v);
    err_verlet = dist3(x, x_exact);
    print_message("position error at t = %g s: dWorldStep %.4g m, verlet %.4g m, ratio %.3g\n", T, err_ode,
                  err_verlet, err_ode / err_verlet);
    if (!(err_ode >= 100 * err_verlet))
        fail_msg("dWorldStep error %.4g m is only %.3g times verlet's %.4g m (need 100)", err_ode,
                 err_ode / err_verlet, err_verlet);
}

const struct CMUnitTest tests[] = {
    cmocka_unit_test(ode_symplectic_euler_matches_dworldstep),
    cmocka_unit_test(ode_rk4_beats_dworldstep),
    cmocka_unit_test(ode_verlet_beats_dworldstep),
};

TB_TEST_MAIN(tests)
