/* test_rotation.c: the torque-free rotation kernels (src/bodies/rotation.c) against
   closed forms (isotropic body, symmetric top), against a converged
   reference on the intermediate-axis flip that this file checks for its own
   convergence, and for the orders, invariants and symmetries they claim;
   then that the kernels in lanes, and the world's fast paths built on them,
   give a body the bits of the one-body kernels and of the general paths. */
#include "test_main.h"
#include "bodies/bodies.h"
#include "tumble.h"

#include <math.h>
#include <string.h>

typedef void kernel_fn(double q[4], const double L[3], const double invI[3], double h);

static const struct {
    const char *name;
    kernel_fn *step;
} kernels[] = {
    { "frozen", tb__rotation_frozen },
    { "split2", tb__rotation_split2 },
    { "accurate", tb__rotation_accurate },
};
#define KERNELS ((int)(sizeof kernels / sizeof kernels[0]))

/* ------------------------------------------------------------ helpers -- */

static double qnorm(const double q[4])
{
    return sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
}

static void normalize(double q[4])
{
    const double n = qnorm(q);
    q[0] /= n;
    q[1] /= n;
    q[2] /= n;
    q[3] /= n;
}

/* out = R(q) v (sign = 1) or R(q)^T v (sign = -1), for a unit q. */
static void rotate(const double q[4], double sign, const double v[3], double out[3])
{
    const double p[4] = { 0, v[0], v[1], v[2] };
    double c[4], t[4];
    c[0] = q[0];
    c[1] = -q[1];
    c[2] = -q[2];
    c[3] = -q[3];
    if (sign > 0) {
        tb__quat_mul(q, p, t);
        tb__quat_mul(t, c, t);
    } else {
        tb__quat_mul(c, p, t);
        tb__quat_mul(t, q, t);
    }
    out[0] = t[1];
    out[1] = t[2];
    out[2] = t[3];
}

/* The quaternion of a rotation by `angle` about the unit `axis`. */
static void axis_angle(const double axis[3], double angle, double q[4])
{
    q[0] = cos(angle / 2);
    q[1] = sin(angle / 2) * axis[0];
    q[2] = sin(angle / 2) * axis[1];
    q[3] = sin(angle / 2) * axis[2];
}

/* The unit quaternion of a rotation matrix (Shepperd: divide by the
   largest of the four candidate components). */
static void matrix_to_quaternion(double m[3][3], double q[4])
{
    const double tr = m[0][0] + m[1][1] + m[2][2];
    if (tr >= m[0][0] && tr >= m[1][1] && tr >= m[2][2]) {
        q[0] = 0.5 * sqrt(1 + tr);
        q[1] = (m[2][1] - m[1][2]) / (4 * q[0]);
        q[2] = (m[0][2] - m[2][0]) / (4 * q[0]);
        q[3] = (m[1][0] - m[0][1]) / (4 * q[0]);
    } else if (m[0][0] >= m[1][1] && m[0][0] >= m[2][2]) {
        q[1] = 0.5 * sqrt(1 + m[0][0] - m[1][1] - m[2][2]);
        q[0] = (m[2][1] - m[1][2]) / (4 * q[1]);
        q[2] = (m[0][1] + m[1][0]) / (4 * q[1]);
        q[3] = (m[0][2] + m[2][0]) / (4 * q[1]);
    } else if (m[1][1] >= m[2][2]) {
        q[2] = 0.5 * sqrt(1 - m[0][0] + m[1][1] - m[2][2]);
        q[0] = (m[0][2] - m[2][0]) / (4 * q[2]);
        q[1] = (m[0][1] + m[1][0]) / (4 * q[2]);
        q[3] = (m[1][2] + m[2][1]) / (4 * q[2]);
    } else {
        q[3] = 0.5 * sqrt(1 - m[0][0] - m[1][1] + m[2][2]);
        q[0] = (m[1][0] - m[0][1]) / (4 * q[3]);
        q[1] = (m[0][2] + m[2][0]) / (4 * q[3]);
        q[2] = (m[1][2] + m[2][1]) / (4 * q[3]);
    }
}

/* The angle of a^-1 b, by atan2: acos of a dot product loses everything
   below about 1e-7 rad. */
static double angle_between(const double a[4], const double b[4])
{
    const double c[4] = { a[0], -a[1], -a[2], -a[3] };
    double d[4];
    tb__quat_mul(c, b, d);
    return 2 * atan2(sqrt(d[1] * d[1] + d[2] * d[2] + d[3] * d[3]), fabs(d[0]));
}


static double energy(const double q[4], const double L[3], const double invI[3])
{
    double lb[3];
    rotate(q, -1, L, lb);
    return 0.5 * (invI[0] * lb[0] * lb[0] + invI[1] * lb[1] * lb[1] + invI[2] * lb[2] * lb[2]);
}

/* A body from its principal moments I, body-frame angular velocity w0 and
   orientation q0: fills invI and the world L. */
static void body(const double I[3], const double w0[3], const double q0[4], double invI[3], double L[3])
{
    const double lb[3] = { I[0] * w0[0], I[1] * w0[1], I[2] * w0[2] };
    invI[0] = 1 / I[0];
    invI[1] = 1 / I[1];
    invI[2] = 1 / I[2];
    rotate(q0, 1, lb, L);
}

static void run(kernel_fn *step, double q[4], const double L[3], const double invI[3], double h, long n)
{
    long i;
    for (i = 0; i < n; ++i)
        step(q, L, invI, h);
}

/* ---------------------------------------------------- the reference -- */

/* Classic RK4 on the body-frame equations, L_b' = L_b x w_b and
   q' = q (0, w_b) / 2 with w_b = invI L_b, carrying L_b as its own state
   (independent of the kernels, which rebuild L_b from q), q renormalised
   after each step. */
static void euler_rhs(const double lb[3], const double q[4], const double invI[3], double dl[3], double dq[4])
{
    const double w0 = invI[0] * lb[0], w1 = invI[1] * lb[1], w2 = invI[2] * lb[2];
    dl[0] = lb[1] * w2 - lb[2] * w1;
    dl[1] = lb[2] * w0 - lb[0] * w2;
    dl[2] = lb[0] * w1 - lb[1] * w0;
    dq[0] = 0.5 * (-q[1] * w0 - q[2] * w1 - q[3] * w2);
    dq[1] = 0.5 * (q[0] * w0 + q[2] * w2 - q[3] * w1);
    dq[2] = 0.5 * (q[0] * w1 - q[1] * w2 + q[3] * w0);
    dq[3] = 0.5 * (q[0] * w2 + q[1] * w1 - q[2] * w0);
}

static void rk4_reference(const double q0[4], const double L[3], const double invI[3], double T, long n,
                          double q[4])
{
    const double h = T / n;
    double lb[3], k[4][7], sl[3], sq[4];
    long s;
    int i, j;
    memcpy(q, q0, 4 * sizeof *q);
    rotate(q, -1, L, lb);
    for (s = 0; s < n; ++s) {
        for (j = 0; j < 4; ++j) {
            const double c = j == 0 ? 0 : j == 3 ? h : h / 2;
            for (i = 0; i < 3; ++i)
                sl[i] = lb[i] + (j ? c * k[j - 1][i] : 0);
            for (i = 0; i < 4; ++i)
                sq[i] = q[i] + (j ? c * k[j - 1][3 + i] : 0);
            euler_rhs(sl, sq, invI, k[j], k[j] + 3);
        }
        for (i = 0; i < 3; ++i)
            lb[i] += h / 6 * (k[0][i] + 2 * k[1][i] + 2 * k[2][i] + k[3][i]);
        for (i = 0; i < 4; ++i)
            q[i] += h / 6 * (k[0][3 + i] + 2 * k[1][3 + i] + 2 * k[2][3 + i] + k[3][3 + i]);
        normalize(q);
    }
}

/* The flip of docs/notes.md: I = diag(1, 2, 3) kg m^2, w0 = (0.01, 5, 0.01) rad/s
   in the body frame, q0 = identity, 20 s at h = 1/60. */
static const double FLIP_I[3] = { 1, 2, 3 };
static const double FLIP_W[3] = { 0.01, 5, 0.01 };
static const double IDENTITY[4] = { 1, 0, 0, 0 };
#define FLIP_T 20.0
#define FLIP_STEPS 1200L

static void flip(double invI[3], double L[3]) { body(FLIP_I, FLIP_W, IDENTITY, invI, L); }

/* The orientation at 20 s from RK4 at h/64 (76800 steps). Its convergence
   is checked by reference_converges. */
static const double *flip_reference(void)
{
    static double q[4];
    static int done;
    if (!done) {
        double invI[3], L[3];
        flip(invI, L);
        rk4_reference(IDENTITY, L, invI, FLIP_T, 64 * FLIP_STEPS, q);
        done = 1;
    }
    return q;
}

/* RK4 at h/4 ... h/64: the differences between successive halvings must
   fall by 2^4 = 16 (a fourth-order method in its asymptotic range) until
   rounding takes over. Measured: 1.5e-8, 9.3e-10, 5.9e-11, 5.2e-12 for
   h/4 vs h/8 ... h/32 vs h/64, ratios 16.4, 15.8, then 11.3 where rounding
   begins to show: near the separatrix the flip amplifies the rounding of
   10^5 steps to a scatter of up to about 6e-11 rad (seen in both methods
   below, refined further). The h/64 solution is thus within about 1e-10
   rad of the exact one. An independent method, the accurate kernel at h/4
   (order 4, built from exact rotations, L_b rebuilt from q each step,
   truncation error about 7.5e-10 / 4^4 = 3e-12), must agree with it to
   that level too (measured 2.7e-12). */
static void reference_converges(void **state)
{
    double invI[3], L[3], q[5][4], qa[4], d[4];
    long n = 4 * FLIP_STEPS;
    int k;
    (void)state;
    flip(invI, L);
    for (k = 0; k < 5; ++k, n *= 2)
        rk4_reference(IDENTITY, L, invI, FLIP_T, n, q[k]);
    for (k = 0; k < 4; ++k) {
        d[k] = angle_between(q[k], q[k + 1]);
        print_message("RK4 h/%d vs h/%d: %.3e rad\n", 4 << k, 8 << k, d[k]);
    }
    assert_true(d[0] / d[1] > 14 && d[0] / d[1] < 18);
    assert_true(d[1] / d[2] > 14 && d[1] / d[2] < 18);
    assert_true(d[2] / d[3] > 8);
    assert_below(d[3], 5e-11);
    assert_memory_equal(q[4], flip_reference(), sizeof q[4]); /* what the flip tests compare with */

    memcpy(qa, IDENTITY, sizeof qa);
    run(tb__rotation_accurate, qa, L, invI, FLIP_T / (4 * FLIP_STEPS), 4 * FLIP_STEPS);
    print_message("accurate kernel at h/4 vs RK4 at h/64: %.3e rad\n", angle_between(qa, flip_reference()));
    assert_below(angle_between(qa, flip_reference()), 1e-10);
}

/* ---------------------------------------------------------- closed forms -- */

/* An isotropic body turns about the constant w = L / I at a constant rate:
   q(t) = exp(t w / 2) q0. Every kernel is exact there, at small steps (the
   polynomial path) and at steps of more than 1/2 rad (libm's path). */
static void isotropic_bodies_rotate_exactly(void **state)
{
    static const double steps[2] = { 1.0 / 60, 0.4 };
    const double I[3] = { 0.8, 0.8, 0.8 }, w0[3] = { 1.5, -2, 2.5 };
    double q0[4] = { 0.6, -0.2, 0.5, 0.3 }, invI[3], L[3], axis[3], exact[4], turn[4];
    int k, s;
    (void)state;
    normalize(q0);
    body(I, w0, q0, invI, L);
    for (s = 0; s < 2; ++s) {
        const long n = 120;
        const double t = n * steps[s], rate = tb__norm3(L) / I[0];
        axis[0] = L[0] / tb__norm3(L);
        axis[1] = L[1] / tb__norm3(L);
        axis[2] = L[2] / tb__norm3(L);
        axis_angle(axis, rate * t, turn);
        tb__quat_mul(turn, q0, exact);
        for (k = 0; k < KERNELS; ++k) {
            double q[4];
            memcpy(q, q0, sizeof q);
            run(kernels[k].step, q, L, invI, steps[s], n);
            print_message("%-8s h = %.4f: %.2e rad from the closed form after %.0f rad\n",
                          kernels[k].name, steps[s], angle_between(q, exact), rate * t);
            assert_below(angle_between(q, exact), 1e-13);
        }
        {   /* the isotropic kernel, which turns about the world w directly */
            double q[4];
            long i;
            memcpy(q, q0, sizeof q);
            for (i = 0; i < n; ++i)
                tb__rotation_isotropic(q, L, invI[0], steps[s]);
            print_message("%-8s h = %.4f: %.2e rad from the closed form\n", "isotropic", steps[s],
                          angle_between(q, exact));
            assert_below(angle_between(q, exact), 1e-13);
        }
    }
}

/* A symmetric top (I1 = I2 about its symmetry axis s) has the closed form
       q(t) = exp(t a L / 2) q0 exp(t (invI_s - a) L_s e_s / 2),   a = 1/I1,
   a turn about the world L and one about the body's symmetry axis; in the
   body frame w precesses about e_s at Omega = (I_s - I1)/I1 * w_s. Both
   splitting kernels split T into exactly these two turns, so they follow it
   to rounding whatever the step: small steps and steps beyond the
   polynomials (at 0.3 s the steps take libm's path). The symmetry axis
   takes each place in turn, with the third moment larger and smaller than
   the two equal ones, to exercise the relabelling's ties. */
static void check_top(kernel_fn *step, const char *name, int sym, double Is, double h, long n)
{
    double I[3] = { 2, 2, 2 }, w0[3] = { 1.2, -0.7, 0.9 }, q0[4] = { 0.3, 0.8, -0.1, 0.4 };
    double invI[3], L[3], q[4], exact[4], turn[4], axis[3], es[3] = { 0, 0, 0 }, lb[3], w[3];
    const double t = h * n;
    double omega, phase, err_w, err_q, wp0, wq0;
    int o1 = (sym + 1) % 3, o2 = (sym + 2) % 3;
    I[sym] = Is;
    w0[sym] = 4;
    normalize(q0);
    body(I, w0, q0, invI, L);
    memcpy(q, q0, sizeof q);
    run(step, q, L, invI, h, n);

    axis[0] = L[0] / tb__norm3(L);
    axis[1] = L[1] / tb__norm3(L);
    axis[2] = L[2] / tb__norm3(L);
    axis_angle(axis, t * invI[o1] * tb__norm3(L), turn);
    tb__quat_mul(turn, q0, exact);
    es[sym] = 1;
    axis_angle(es, t * (invI[sym] - invI[o1]) * I[sym] * w0[sym], turn);
    tb__quat_mul(exact, turn, exact);
    err_q = angle_between(q, exact);

    /* w in the body frame: (w_o1 + i w_o2)(t) = (w_o1 + i w_o2)(0) e^{i Omega t} */
    rotate(q, -1, L, lb);
    w[0] = invI[0] * lb[0];
    w[1] = invI[1] * lb[1];
    w[2] = invI[2] * lb[2];
    omega = (I[sym] - I[o1]) / I[o1] * w0[sym];
    phase = omega * t;
    wp0 = w0[o1] * cos(phase) - w0[o2] * sin(phase);
    wq0 = w0[o1] * sin(phase) + w0[o2] * cos(phase);
    err_w = sqrt((w[o1] - wp0) * (w[o1] - wp0) + (w[o2] - wq0) * (w[o2] - wq0) + (w[sym] - w0[sym]) * (w[sym] - w0[sym]))
            / tb__norm3(w0);
    print_message("%-8s I_%d = %.1f h = %.3f: precession %5.1f rad, w off by %.2e, q off by %.2e rad\n", name, sym,
                  Is, h, phase, err_w, err_q);
    assert_below(err_w, 1e-12);
    assert_below(err_q, 1e-12);
}

static void symmetric_top_precesses(void **state)
{
    static const double third[2] = { 3.5, 1.0 };
    int sym, k;
    (void)state;
    for (sym = 0; sym < 3; ++sym)
        for (k = 0; k < 2; ++k) {
            check_top(tb__rotation_split2, "split2", sym, third[k], 1.0 / 60, 600);
            check_top(tb__rotation_accurate, "accurate", sym, third[k], 1.0 / 60, 600);
            check_top(tb__rotation_split2, "split2", sym, third[k], 0.3, 40);
            check_top(tb__rotation_accurate, "accurate", sym, third[k], 0.3, 40);
        }
}

/* ------------------------------------------------------------- orders -- */

/* Error after 2 s on an asymmetric body with w of 5 to 10 rad/s, against RK4
   at 2^16 steps (0.5 ms; it agrees with 2^17 steps to 7e-14 rad). Each pair
   of step counts sits in its method's asymptotic range with the error far
   above rounding (measured: frozen 1.8e-2 -> 9.2e-3, split2 1.9e-5 ->
   4.8e-6, accurate 9.0e-10 -> 5.6e-11). split2 at 4 -> 8 steps (h = 0.5 and
   0.25 s, turns beyond the polynomials, so libm's path) must show order 2
   as well (measured 4.9e-3 -> 1.2e-3). */
static void check_order(kernel_fn *step, const char *name, long n, double expected)
{
    const double T = 2, invI[3] = { 1, 0.5, 1.0 / 3 }, lb0[3] = { 2, 3, -1.5 };
    double q0[4] = { 0.9, 0.1, -0.3, 0.2 }, L[3], ref[4], q1[4], q2[4], e1, e2;
    normalize(q0);
    rotate(q0, 1, lb0, L);
    rk4_reference(q0, L, invI, T, 1L << 16, ref);
    memcpy(q1, q0, sizeof q1);
    memcpy(q2, q0, sizeof q2);
    run(step, q1, L, invI, T / n, n);
    run(step, q2, L, invI, T / (2 * n), 2 * n);
    e1 = angle_between(q1, ref);
    e2 = angle_between(q2, ref);
    print_message("%-8s h = %.5f: %.3e -> %.3e rad, order %.3f\n", name, T / n, e1, e2, log2(e1 / e2));
    assert_true(fabs(log2(e1 / e2) - expected) <= 0.15);
}

static void orders_are_as_claimed(void **state)
{
    (void)state;
    check_order(tb__rotation_frozen, "frozen", 512, 1);
    check_order(tb__rotation_split2, "split2", 64, 2);
    check_order(tb__rotation_split2, "split2", 4, 2);
    check_order(tb__rotation_accurate, "accurate", 32, 4);
}

/* -------------------------------------------------------------- the flip -- */

/* |L_b| = |R^T L| is |L| up to rounding whatever the rotation: every kernel
   only ever rotates the body. Measured worst over the 1200 steps: a few
   1e-16. */
static void flip_keeps_momentum_norm(void **state)
{
    double invI[3], L[3], lb[3];
    int k;
    long s;
    (void)state;
    flip(invI, L);
    for (k = 0; k < KERNELS; ++k) {
        double q[4], worst = 0;
        memcpy(q, IDENTITY, sizeof q);
        for (s = 0; s < FLIP_STEPS; ++s) {
            kernels[k].step(q, L, invI, FLIP_T / FLIP_STEPS);
            rotate(q, -1, L, lb);
            worst = fmax(worst, fabs(tb__norm3(lb) / tb__norm3(L) - 1));
        }
        print_message("%-8s worst relative drift of |L_b| %.2e\n", kernels[k].name, worst);
        assert_below(worst, 1e-12);
    }
}

/* The targets of the issue for the best method on the flip at h = 1/60:
   energy drift <= 1e-9, orientation error <= 1e-6 rad. Measured: energy
   within 1.1e-10 of its start at every step, orientation 7.5e-10 rad from
   the reference (whose own error is about 1e-10). The arithmetic is
   deterministic (no contraction, no libm on this path), so the tighter
   bounds below only move when the method does. */
static void accurate_kernel_on_the_flip(void **state)
{
    double invI[3], L[3], q[4], e0, worst = 0, err;
    long s;
    (void)state;
    flip(invI, L);
    memcpy(q, IDENTITY, sizeof q);
    e0 = energy(q, L, invI);
    for (s = 0; s < FLIP_STEPS; ++s) {
        tb__rotation_accurate(q, L, invI, FLIP_T / FLIP_STEPS);
        worst = fmax(worst, fabs(energy(q, L, invI) / e0 - 1));
    }
    err = angle_between(q, flip_reference());
    print_message("accurate: worst energy error %.2e, orientation error %.2e rad\n", worst, err);
    assert_below(worst, 1e-9);
    assert_below(err, 1e-6);
    assert_below(worst, 2e-10);
    assert_below(err, 1.5e-9);
}

/* split2 and the flip: order 2 at h = 1/60 is still 1000 times closer to
   the reference than ODE's 1.6 rad (measured 1.7e-4 rad). */
static void split2_on_the_flip(void **state)
{
    double invI[3], L[3], q[4], err;
    (void)state;
    flip(invI, L);
    memcpy(q, IDENTITY, sizeof q);
    run(tb__rotation_split2, q, L, invI, FLIP_T / FLIP_STEPS, FLIP_STEPS);
    err = angle_between(q, flip_reference());
    print_message("split2: orientation error %.2e rad\n", err);
    assert_below(err, 2e-4);
}

/* A Poisson map conserves a modified energy exactly, so the true energy
   only oscillates in a band that does not widen: over 60000 steps (1000 s,
   about 230 flips) the band of the last 6000 steps must be no wider than
   that of the first 6000 (measured: 6.03e-5 both), and both within 1e-4. */
static void split2_energy_does_not_drift(void **state)
{
    const long n = 60000, window = 6000;
    double invI[3], L[3], q[4], e0, early = 0, late = 0;
    long s;
    (void)state;
    flip(invI, L);
    memcpy(q, IDENTITY, sizeof q);
    e0 = energy(q, L, invI);
    for (s = 0; s < n; ++s) {
        double d;
        tb__rotation_split2(q, L, invI, FLIP_T / FLIP_STEPS);
        d = fabs(energy(q, L, invI) / e0 - 1);
        if (s < window)
            early = fmax(early, d);
        if (s >= n - window)
            late = fmax(late, d);
    }
    print_message("split2: energy band %.3e over the first %ld steps, %.3e over the last\n", early, window, late);
    assert_below(early, 1e-4);
    assert_below(late, early * 1.01);
}

/* --------------------------------------------------------- properties -- */

/* |q| = 1 to rounding after every one of 10^4 steps, for every kernel, on
   an asymmetric body spinning at about 9 rad/s; a q that starts 1e-6 off
   unit length (a careless caller) is put back in one step. */
static void quaternion_stays_unit(void **state)
{
    const double I[3] = { 0.4, 1.1, 0.7 }, w0[3] = { 3, -8, 2 };
    double q0[4] = { 0.2, 0.4, -0.7, 0.5 }, invI[3], L[3];
    int k;
    long s;
    (void)state;
    normalize(q0);
    body(I, w0, q0, invI, L);
    for (k = 0; k < KERNELS; ++k) {
        double q[4], worst = 0;
        memcpy(q, q0, sizeof q);
        for (s = 0; s < 10000; ++s) {
            kernels[k].step(q, L, invI, 1.0 / 60);
            worst = fmax(worst, fabs(qnorm(q) - 1));
        }
        print_message("%-8s worst | |q| - 1 | over 10^4 steps: %.2e\n", kernels[k].name, worst);
        assert_below(worst, 1e-15);
        q[0] *= 1 + 1e-6;
        kernels[k].step(q, L, invI, 1.0 / 60);
        assert_below(fabs(qnorm(q) - 1), 1e-15);
    }
}

/* The kernels relabel the principal axes internally (middle moment, larger
   and smaller |invI - a|). Describing the same physical body with its axes
   listed in another order (a proper rotation P of the body frame: q' = q p,
   moments permuted) must give the same motion: R(q'_t) = R(q_t) P. */
static void axis_order_does_not_matter(void **state)
{
    /* the six orders of (x, y, z), with a sign on the last axis for the odd
       ones so that P stays a rotation; p is P's quaternion */
    static const int perm[6][3] = { { 0, 1, 2 }, { 1, 2, 0 }, { 2, 0, 1 }, { 1, 0, 2 }, { 0, 2, 1 }, { 2, 1, 0 } };
    const double I[3] = { 0.5, 1.3, 2.2 }, w0[3] = { 0.3, 6, -0.4 };
    double q0[4] = { 0.8, -0.3, 0.2, 0.4 }, invI[3], L[3];
    int k, j;
    (void)state;
    normalize(q0);
    body(I, w0, q0, invI, L);
    for (k = 1; k < KERNELS; ++k) {
        double q[4];
        memcpy(q, q0, sizeof q);
        run(kernels[k].step, q, L, invI, 1.0 / 60, 600);
        for (j = 1; j < 6; ++j) {
            double P[3][3] = { { 0 } }, p[4], invI2[3], q2[4], qp[4];
            const double sign = j >= 3 ? -1 : 1;
            int n;
            /* column n of P is the old axis perm[n] (negated for n = 2 when odd) */
            for (n = 0; n < 3; ++n) {
                P[perm[j][n]][n] = n == 2 ? sign : 1;
                invI2[n] = invI[perm[j][n]];
            }
            matrix_to_quaternion(P, p);
            tb__quat_mul(q0, p, q2);
            run(kernels[k].step, q2, L, invI2, 1.0 / 60, 600);
            tb__quat_mul(q, p, qp);
            print_message("%-8s order (%d %d %d): %.2e rad\n", kernels[k].name, perm[j][0], perm[j][1], perm[j][2],
                          angle_between(qp, q2));
            assert_below(angle_between(qp, q2), 1e-12);
        }
    }
}

/* The relabelling (rotation.c) for every order of the moments, ties
   included: a permutation of the axes with the middle moment in the
   middle, A the outer axis with the larger |invI - a|, sign its parity,
   and isotropic exactly when all three are equal. */
static void every_order_of_moments_is_relabelled(void **state)
{
    static const double values[4] = { 0.5, 1, 2, 1e300 };
    int n;
    (void)state;
    for (n = 0; n < 64; ++n) {
        const double invI[3] = { values[n % 4], values[n / 4 % 4], values[n / 16] };
        tb__split_frame f;
        int odd;
        tb__split_frame_of(invI, &f);
        assert_true(f.ax[0] < 3 && f.ax[1] < 3 && f.ax[2] < 3);
        assert_true(f.ax[0] != f.ax[1] && f.ax[1] != f.ax[2] && f.ax[0] != f.ax[2]);
        odd = (f.ax[0] > f.ax[1]) + (f.ax[0] > f.ax[2]) + (f.ax[1] > f.ax[2]);
        assert_true(f.sign == (odd % 2 ? -1 : 1));
        assert_true(f.a == invI[f.ax[1]]);
        assert_true(f.ca == invI[f.ax[0]] - f.a && f.cb == invI[f.ax[2]] - f.a && fabs(f.ca) >= fabs(f.cb));
        assert_true((f.ca <= 0 && f.cb >= 0) || (f.ca >= 0 && f.cb <= 0)); /* a is the middle one */
        assert_int_equal(f.isotropic, invI[0] == invI[1] && invI[1] == invI[2]);
    }
}

/* The splitting kernels are symmetric compositions: a step of -h undoes a
   step of h, so 600 steps forward and 600 back return to the start up to
   rounding. (frozen is not symmetric: it is left out.) */
static void splitting_is_time_reversible(void **state)
{
    const double I[3] = { 1, 2, 3 }, w0[3] = { 2, 4, -3 };
    double q0[4] = { 0.5, 0.5, -0.5, 0.5 }, invI[3], L[3];
    int k;
    (void)state;
    body(I, w0, q0, invI, L);
    for (k = 1; k < KERNELS; ++k) {
        double q[4];
        memcpy(q, q0, sizeof q);
        run(kernels[k].step, q, L, invI, 1.0 / 60, 600);
        run(kernels[k].step, q, L, invI, -1.0 / 60, 600);
        print_message("%-8s back to the start within %.2e rad\n", kernels[k].name, angle_between(q, q0));
        assert_below(angle_between(q, q0), 1e-12);
    }
}

/* Steps too large for the polynomials (the libm path: h = 0.5 s turns the
   body by about 1 rad about an axis per piece) are still exact rotations:
   |q| = 1, |L_b| = |L|, a step back undoes a step forward; and accurate at
   h = 0.5 s is where its order says (measured 3.0e-6 rad after 2 s on the
   body of orders_are_as_claimed, 2.2e-7 at h = 0.25 s). */
static void large_steps_stay_exact(void **state)
{
    const double invI[3] = { 1, 0.5, 1.0 / 3 }, lb0[3] = { 2, 3, -1.5 };
    double q0[4] = { 0.9, 0.1, -0.3, 0.2 }, L[3], lb[3], ref[4];
    int k;
    (void)state;
    normalize(q0);
    rotate(q0, 1, lb0, L);
    rk4_reference(q0, L, invI, 2, 1L << 16, ref);
    for (k = 1; k < KERNELS; ++k) {
        double q[4], worst_q = 0, worst_l = 0;
        int s;
        memcpy(q, q0, sizeof q);
        for (s = 0; s < 4; ++s) {
            kernels[k].step(q, L, invI, 0.5);
            rotate(q, -1, L, lb);
            worst_q = fmax(worst_q, fabs(qnorm(q) - 1));
            worst_l = fmax(worst_l, fabs(tb__norm3(lb) / tb__norm3(L) - 1));
        }
        print_message("%-8s h = 0.5: %.2e rad from the reference after 2 s; | |q| - 1 | %.1e, |L_b| %.1e\n",
                      kernels[k].name, angle_between(q, ref), worst_q, worst_l);
        assert_below(worst_q, 1e-15);
        assert_below(worst_l, 1e-15);
        if (k == 2)
            assert_below(angle_between(q, ref), 4e-6);
        run(kernels[k].step, q, L, invI, -0.5, 4);
        print_message("%-8s back to the start within %.2e rad\n", kernels[k].name, angle_between(q, q0));
        assert_below(angle_between(q, q0), 1e-14);
    }
}


/* ------------------------------------------------------------- lanes -- */

/* Reproducible numbers in [0, 1) (xorshift64*). */
static double uniform(unsigned long long *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (double)((*s * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}

/* Body k of the lane tests: every order of the moments (so every
   relabelling and its sign), symmetric tops and isotropic bodies, a unit q,
   spins from slow to beyond the polynomials (the libm path). */
static void lane_body(unsigned long long *s, int k, double q[4], double L[3], double invI[3])
{
    static const double shapes[6][3] = { { 1, 2, 3 }, { 3, 1, 2 }, { 2, 3, 1 }, { 1, 3, 2 }, { 2, 2, 3 }, { 1.5, 1.5, 1.5 } };
    const double spin = k % 11 == 5 ? 120 : 8;
    int i;
    for (i = 0; i < 3; ++i) {
        invI[i] = 1 / (shapes[k % 6][i] * (0.5 + uniform(s)));
        L[i] = spin * (2 * uniform(s) - 1);
    }
    if (k % 6 == 5)
        invI[1] = invI[2] = invI[0];
    if (k % 6 == 4)
        invI[1] = invI[0];
    for (i = 0; i < 4; ++i)
        q[i] = 2 * uniform(s) - 1;
    normalize(q);
}

/* The kernels in lanes, compiled for instruction set `isa`, give every
   body the bits of the one-body kernel (portable C): full blocks and
   partial ones, with bodies beyond the polynomials among them, over many
   steps. */
static void lanes_match_one_body(int isa)
{
    enum { N = 3 * TB__LANES + 5, STEPS = 50 };
    static double q[N][4], L[N][3], invI[N][3], one[N][4], frame[4][N];
    unsigned long long seed = 42;
    int kind, k, s;
    /* kinds 4 and 5: split2 and accurate with the world's frames
       (rotation.h) */
    for (kind = 0; kind < 6; ++kind) {
        for (k = 0; k < N; ++k) {
            lane_body(&seed, k, q[k], L[k], invI[k]);
            if (kind == 0) /* the isotropic kernel reads invI[0] alone */
                invI[k][1] = invI[k][2] = invI[k][0];
            memcpy(one[k], q[k], sizeof one[k]);
            tb__lane_frame_of(invI[k], &frame[0][k], &frame[1][k], &frame[2][k], &frame[3][k]);
        }
        for (s = 0; s < STEPS; ++s) {
            const double h = s % 7 == 3 ? -1.0 / 60 : 1.0 / 60;
            int b;
            for (b = 0; b < N; b += TB__LANES) {
                const int n = N - b < TB__LANES ? N - b : TB__LANES;
                if (kind == 0)
                    tb__isotropic_lanes(q[b], L[b], invI[b], h, n, isa);
                else if (kind == 1)
                    tb__frozen_lanes(q[b], L[b], invI[b], h, n, isa);
                else if (kind == 2)
                    tb__split2_lanes(q[b], L[b], invI[b], h, n, isa);
                else if (kind == 3)
                    tb__accurate_lanes(q[b], L[b], invI[b], h, n, isa);
                else {
                    tb__lane_frames f;
                    f.a = frame[0] + b, f.ca = frame[1] + b, f.cb = frame[2] + b, f.code = frame[3] + b;
                    if (kind == 4)
                        tb__split2_lanes_framed(q[b], L[b], invI[b], &f, h, n, isa);
                    else
                        tb__accurate_lanes_framed(q[b], L[b], invI[b], &f, h, n, isa);
                }
            }
            for (k = 0; k < N; ++k) {
                if (kind == 0)
                    tb__rotation_isotropic(one[k], L[k], invI[k][0], h);
                else
                    kernels[kind < 4 ? kind - 1 : kind - 3].step(one[k], L[k], invI[k], h);
            }
        }
        for (k = 0; k < N; ++k)
            assert_memory_equal(q[k], one[k], sizeof q[k]);
    }
}

/* ... for every instruction set this processor runs: the wider ones must
   give the portable bits (rotation.c), so a world's results do not depend
   on the machine's vector unit. */
static void lanes_give_the_one_body_bits(void **state)
{
    int isa;
    (void)state;
    for (isa = TB__ISA_PORTABLE; isa <= tb__isa(); ++isa) {
        lanes_match_one_body(isa);
        print_message("lanes for %s: the one-body bits\n",
                      isa == TB__ISA_AVX512 ? "AVX-512" : isa == TB__ISA_AVX2 ? "AVX2" : "portable C");
    }
}

/* ---------------------------------------------- the world's fast paths -- */

static tb_status no_force(const tb_force_args *args, void *user)
{
    (void)args;
    (void)user;
    return TB_OK;
}

/* Body k's principal moments as a unit-mass box of random sides: isotropic
   for k % 6 = 5, a symmetric top for k % 6 = 4. */
static void random_box(unsigned long long *seed, int k, double inertia[3])
{
    double a[3];
    int i;
    for (i = 0; i < 3; ++i)
        a[i] = k % 6 == 5 ? 1 : 0.25 + uniform(seed);
    if (k % 6 == 4)
        a[1] = a[0];
    inertia[0] = (a[1] * a[1] + a[2] * a[2]) / 12;
    inertia[1] = (a[0] * a[0] + a[2] * a[2]) / 12;
    inertia[2] = (a[0] * a[0] + a[1] * a[1]) / 12;
}

/* Bodies of every kind, some with -0 in their velocities, some damped, in
   a world whose gravity has a -0 component; `callback` adds a force
   callback that adds nothing, which sends the world through the general
   paths (the per-body kicks, the generic RK4). */
static tb_world *mixed_world(const char *integrator, int damped, int callback)
{
    tb_world_def def = tb_default_world_def();
    tb_world *w;
    unsigned long long seed = 7;
    int k, i;
    def.integrator = integrator;
    def.gravity[0] = -0.0;
    assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
    for (k = 0; k < 2 * TB__LANES + 3; ++k) {
        tb_body_def b = tb_default_body_def();
        double L[3], invI[3];
        lane_body(&seed, k, b.orientation, L, invI);
        random_box(&seed, k, b.mass.inertia);
        for (i = 0; i < 3; ++i) {
            b.position[i] = 10 * uniform(&seed);
            b.velocity[i] = k % 4 == 1 ? -0.0 : 4 * uniform(&seed) - 2;
            b.angular_velocity[i] = k % 4 == 1 ? -0.0 : L[i] / 4;
        }
        b.mass.mass = 0.5 + uniform(&seed);
        if (damped && k % 5 == 2)
            b.angular_damping = b.linear_damping = 0.3;
        assert_int_equal(tb_world_add_body(w, &b, NULL), TB_OK);
    }
    if (callback)
        assert_int_equal(tb_world_add_force(w, no_force, NULL, NULL), TB_OK);
    return w;
}

/* The sweeps in blocks (gravity alone: kicks of P alone, lanes) and the
   fused RK4 give the bits of the general paths, for every integrator, with
   and without damping and held forces. */
static void fast_paths_give_the_general_bits(void **state)
{
    int m, damped;
    (void)state;
    for (m = 0; m < tb_integrator_count(); ++m)
        for (damped = 0; damped < 2 && strcmp(tb_integrator_name(m), "auto"); ++damped) {
            /* (auto sends worlds with callbacks to dopri5: not the same method) */
            tb_world *w[2];
            size_t n, k;
            int c, s;
            for (c = 0; c < 2; ++c)
                w[c] = mixed_world(tb_integrator_name(m), damped, c);
            n = tb_world_body_count(w[0]);
            for (s = 0; s < 120; ++s)
                for (c = 0; c < 2; ++c) {
                    if (damped && s % 3 == 0) {
                        const double f[3] = { 1, -2, 0.5 }, at[3] = { 0.1, 0, -0.2 };
                        assert_int_equal(tb_body_apply_force_at_body_point(w[c], tb_world_body_at(w[c], 4), f, at),
                                         TB_OK);
                    }
                    assert_int_equal(tb_world_step(w[c], 1.0 / 60), TB_OK);
                }
            print_message("%-16s %s: same bits\n", tb_integrator_name(m), damped ? "damped, held forces" : "gravity alone");
            assert_memory_equal(tb_world_body_positions(w[0]), tb_world_body_positions(w[1]), 3 * n * sizeof(double));
            assert_memory_equal(tb_world_body_orientations(w[0]), tb_world_body_orientations(w[1]),
                                4 * n * sizeof(double));
            for (k = 0; k < n; ++k) {
                double P[2][3], L[2][3];
                for (c = 0; c < 2; ++c)
                    assert_int_equal(tb_body_momentum(w[c], tb_world_body_at(w[c], k), P[c], L[c]), TB_OK);
                assert_memory_equal(P[0], P[1], sizeof P[0]);
                assert_memory_equal(L[0], L[1], sizeof L[0]);
            }
            for (c = 0; c < 2; ++c)
                tb_world_destroy(w[c]);
        }
}

/* A world turns its free bodies by the lanes with the frames it keeps
   (rotation.h), and verlet does kick, drift and kick in one sweep
   (integrators.c): each body gets the bits of the one-body kernel, full
   blocks and a partial one, through steps of two sizes. */
static void world_turns_give_the_one_body_bits(void **state)
{
    enum { N = 2 * TB__LANES + 5, STEPS = 40 };
    static const char *const methods[2] = { "verlet", "verlet_exact" };
    static double q[N][4], L[N][3], invI[N][3];
    int m;
    (void)state;
    for (m = 0; m < 2; ++m) {
        tb_world_def def = tb_default_world_def();
        tb_world *w;
        unsigned long long seed = 11;
        const double *wq;
        int k, i, s;
        def.integrator = methods[m];
        def.gravity[2] = 0;
        assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
        for (k = 0; k < N; ++k) {
            tb_body_def b = tb_default_body_def();
            double qk[4], lk[3], ik[3];
            lane_body(&seed, k, qk, lk, ik);
            memcpy(b.orientation, qk, sizeof qk);
            random_box(&seed, k, b.mass.inertia);
            for (i = 0; i < 3; ++i) {
                b.angular_velocity[i] = lk[i] * (k % 11 == 5 ? 4 : 1); /* some beyond the polynomials */
                invI[k][i] = 1 / b.mass.inertia[i];
            }
            assert_int_equal(tb_world_add_body(w, &b, NULL), TB_OK);
            assert_int_equal(tb_body_momentum(w, tb_world_body_at(w, (size_t)k), NULL, L[k]), TB_OK);
            memcpy(q[k], tb_world_body_orientations(w) + 4 * k, sizeof q[k]);
        }
        for (s = 0; s < STEPS; ++s) {
            const double h = s >= 20 && s < 25 ? 1.0 / 30 : 1.0 / 60;
            assert_int_equal(tb_world_step(w, h), TB_OK);
            for (k = 0; k < N; ++k)
                kernels[m + 1].step(q[k], L[k], invI[k], h);
        }
        wq = tb_world_body_orientations(w);
        for (k = 0; k < N; ++k)
            assert_memory_equal(wq + 4 * k, q[k], sizeof q[k]);
        print_message("%-12s the one-body bits for %d bodies\n", methods[m], N);
        tb_world_destroy(w);
    }
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(reference_converges),
    cmocka_unit_test(isotropic_bodies_rotate_exactly),
    cmocka_unit_test(symmetric_top_precesses),
    cmocka_unit_test(orders_are_as_claimed),
    cmocka_unit_test(flip_keeps_momentum_norm),
    cmocka_unit_test(accurate_kernel_on_the_flip),
    cmocka_unit_test(split2_on_the_flip),
    cmocka_unit_test(split2_energy_does_not_drift),
    cmocka_unit_test(quaternion_stays_unit),
    cmocka_unit_test(axis_order_does_not_matter),
    cmocka_unit_test(every_order_of_moments_is_relabelled),
    cmocka_unit_test(splitting_is_time_reversible),
    cmocka_unit_test(large_steps_stay_exact),
    cmocka_unit_test(lanes_give_the_one_body_bits),
    cmocka_unit_test(fast_paths_give_the_general_bits),
    cmocka_unit_test(world_turns_give_the_one_body_bits),
};

TB_TEST_MAIN(tests)
