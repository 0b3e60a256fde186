/* rotation.c: accuracy and cost of torque-free rotation on the
   intermediate-axis flip (docs/notes.md): I = diag(1, 2, 3) kg m^2,
   w0 = (0.01, 5, 0.01) rad/s in the body frame, q0 = identity, 20 s at
   h = 1/60 s.

   One line per method: tumble's rotation kernels (src/rotation.c), ODE's
   dWorldStep on the same body, and two RK4 lines: RK4 on (L_b, q) with L_b
   carried as state (what MuJoCo's RK4 does with its body-frame angular
   velocity), and RK4 on q alone with the world L held fixed and w rebuilt
   from each stage's q (what a generic RK4 over tumble's state (q, L) does).
   Columns:
   - |L| drift: relative change of |L| over the run, worst over all steps.
     The kernels keep the world L itself; their column is |R(q)^T L| / |L|,
     the momentum the orientation implies. ODE's is |I_world w|.
   - E drift: relative change of the kinetic energy at the end of the run,
     and its worst over all steps (a symplectic method's error oscillates).
   - orientation: angle of q_ref^-1 q after 20 s, 2 atan2(|v|, |w|), against
     RK4 at h/64 whose convergence is printed first.
   - ns/step: one body stepped 1200 times in a row (each step waits for the
     last: latency), median of REPEATS runs; for the kernels and RK4, ns per
     body-step over 1024 independent bodies one call per body, also a
     median; and for tumble's kernels, ns per body-step over the same bodies
     in lanes, TB__LANES at a time, as a world steps them (rotation.h):
     compiled as portable C, then for the widest instruction set this
     processor runs, which the world chooses (the same bits). */
#define _POSIX_C_SOURCE 200809L
#define BENCH_NAME "bench_rotation"

#include "bench.h"
#include "bodies/bodies.h"

#include <ode/ode.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define T_END 20.0
#define STEPS 1200L
#define H (T_END / STEPS)
#define REPEATS 31
#define BODIES 1024

static const double I_BODY[3] = { 1, 2, 3 };
static const char *const isa_names[] = { "portable", "AVX2", "AVX-512" };
static const double W0[3] = { 0.01, 5, 0.01 };

/* ------------------------------------------------------- quaternions -- */

static void normalize(double q[4])
{
    const double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    q[0] /= n;
    q[1] /= n;
    q[2] /= n;
    q[3] /= n;
}

/* out = R(q)^T v */
static void to_body(const double q[4], const double v[3], double out[3])
{
    const double c[4] = { q[0], -q[1], -q[2], -q[3] }, p[4] = { 0, v[0], v[1], v[2] };
    double t[4];
    qmul(c, p, t);
    qmul(t, q, t);
    memcpy(out, t + 1, 3 * sizeof *out);
}

static double energy_b(const double lb[3], const double invI[3])
{
    return 0.5 * (invI[0] * lb[0] * lb[0] + invI[1] * lb[1] * lb[1] + invI[2] * lb[2] * lb[2]);
}

/* ----------------------------------------------------------- the RK4s -- */

/* Body-frame Euler equations: L_b' = L_b x w_b, q' = q (0, w_b) / 2. */
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

/* One classic RK4 step on (L_b, q), L_b carried as state; q renormalised. */
static void rk4_carried(double lb[3], double q[4], const double invI[3], double h)
{
    double k[4][7], sl[3], sq[4];
    int i, j;
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

/* One classic RK4 step on q alone: the world L is fixed, each stage
   rebuilds w_b = invI R(q_stage)^T L from its (renormalised) q. */
static void rk4_fixed_l(double q[4], const double L[3], const double invI[3], double h)
{
    double k[4][4], sq[4], lb[3], dl[3];
    int i, j;
    for (j = 0; j < 4; ++j) {
        const double c = j == 0 ? 0 : j == 3 ? h : h / 2;
        for (i = 0; i < 4; ++i)
            sq[i] = q[i] + (j ? c * k[j - 1][i] : 0);
        normalize(sq);
        to_body(sq, L, lb);
        euler_rhs(lb, sq, invI, dl, k[j]);
    }
    for (i = 0; i < 4; ++i)
        q[i] += h / 6 * (k[0][i] + 2 * k[1][i] + 2 * k[2][i] + k[3][i]);
    normalize(q);
}

/* ---------------------------------------------------------- the runs -- */

typedef struct result {
    const char *name;
    double l_drift, e_end, e_worst, angle, ns, ns_many, ns_portable, ns_lanes;
} result;

static void flip_state(double invI[3], double L[3], double q[4])
{
    int i;
    for (i = 0; i < 3; ++i) {
        invI[i] = 1 / I_BODY[i];
        L[i] = I_BODY[i] * W0[i]; /* q0 = identity: world = body */
    }
    q[0] = 1;
    q[1] = q[2] = q[3] = 0;
}

/* Many independent bodies: the flip with its w0 nudged per body, so that
   nothing is shared between them but the code. */
static void many_states(double *q, double *L, double *invI)
{
    int b, i;
    for (b = 0; b < BODIES; ++b) {
        flip_state(invI + 3 * b, L + 3 * b, q + 4 * b);
        for (i = 0; i < 3; ++i)
            L[3 * b + i] *= 1 + 1e-3 * (double)((b * (i + 3)) % 17);
    }
}

typedef void kernel_fn(double q[4], const double L[3], const double invI[3], double h);

/* The bodies b < BODIES through a kernel in lanes, as the world does:
   frozen (kernel 0), split2 (1) or accurate (2), straight on the arrays. */
static void step_lanes(int kernel, double *q, const double *L, const double *invI, double h, int isa)
{
    int b;
    for (b = 0; b < BODIES; b += TB__LANES)
        if (kernel == 0)
            tb__frozen_lanes(q + 4 * b, L + 3 * b, invI + 3 * b, h, TB__LANES, isa);
        else if (kernel == 1)
            tb__split2_lanes(q + 4 * b, L + 3 * b, invI + 3 * b, h, TB__LANES, isa);
        else
            tb__accurate_lanes(q + 4 * b, L + 3 * b, invI + 3 * b, h, TB__LANES, isa);
}

static void run_kernel(result *r, kernel_fn *step, int lanes, const double ref[4])
{
    static double qs[4 * BODIES], Ls[3 * BODIES], Is[3 * BODIES];
    double invI[3], L[3], q[4], lb[3], e0, e = 0, ns[REPEATS], many[REPEATS];
    long s;
    int k, b, isa;
    flip_state(invI, L, q);
    e0 = energy_b(L, invI);
    r->l_drift = r->e_worst = 0;
    for (s = 0; s < STEPS; ++s) {
        step(q, L, invI, H);
        to_body(q, L, lb);
        e = energy_b(lb, invI);
        r->l_drift = fmax(r->l_drift, fabs(norm3(lb) / norm3(L) - 1));
        r->e_worst = fmax(r->e_worst, fabs(e / e0 - 1));
    }
    r->e_end = fabs(e / e0 - 1);
    r->angle = angle_between(ref, q);
    for (k = 0; k < REPEATS; ++k) {
        double t0;
        flip_state(invI, L, q);
        t0 = seconds();
        for (s = 0; s < STEPS; ++s)
            step(q, L, invI, H);
        ns[k] = 1e9 * (seconds() - t0) / STEPS;
        keep(q[0]);
    }
    r->ns = median_of(ns, REPEATS);
    many_states(qs, Ls, Is);
    for (k = 0; k < REPEATS; ++k) {
        const double t0 = seconds();
        for (s = 0; s < 4; ++s)
            for (b = 0; b < BODIES; ++b)
                step(qs + 4 * b, Ls + 3 * b, Is + 3 * b, H);
        many[k] = 1e9 * (seconds() - t0) / (4.0 * BODIES);
    }
    keep(qs[0]);
    r->ns_many = median_of(many, REPEATS);
    r->ns_portable = r->ns_lanes = -1;
    if (lanes < 0)
        return;
    for (isa = TB__ISA_PORTABLE; isa <= tb__isa(); isa = isa == TB__ISA_PORTABLE ? tb__isa() : isa + 1) {
        many_states(qs, Ls, Is);
        for (k = 0; k < REPEATS; ++k) {
            const double t0 = seconds();
            for (s = 0; s < 4; ++s)
                step_lanes(lanes, qs, Ls, Is, H, isa);
            many[k] = 1e9 * (seconds() - t0) / (4.0 * BODIES);
        }
        keep(qs[0]);
        if (isa == TB__ISA_PORTABLE)
            r->ns_portable = median_of(many, REPEATS);
        r->ns_lanes = median_of(many, REPEATS);
        if (isa == TB__ISA_PORTABLE && tb__isa() == TB__ISA_PORTABLE)
            break;
    }
}

static void run_rk4_carried(result *r, const double ref[4])
{
    static double qs[4 * BODIES], Ls[3 * BODIES], Is[3 * BODIES];
    double invI[3], L[3], q[4], lb[3], l0, e0, e = 0, ns[REPEATS], many[REPEATS];
    long s;
    int k, b;
    flip_state(invI, L, q);
    memcpy(lb, L, sizeof lb);
    l0 = norm3(lb);
    e0 = energy_b(lb, invI);
    r->l_drift = r->e_worst = 0;
    for (s = 0; s < STEPS; ++s) {
        rk4_carried(lb, q, invI, H);
        e = energy_b(lb, invI);
        r->l_drift = fmax(r->l_drift, fabs(norm3(lb) / l0 - 1));
        r->e_worst = fmax(r->e_worst, fabs(e / e0 - 1));
    }
    r->e_end = fabs(e / e0 - 1);
    r->angle = angle_between(ref, q);
    for (k = 0; k < REPEATS; ++k) {
        double t0;
        flip_state(invI, lb, q);
        t0 = seconds();
        for (s = 0; s < STEPS; ++s)
            rk4_carried(lb, q, invI, H);
        ns[k] = 1e9 * (seconds() - t0) / STEPS;
        keep(q[0]);
    }
    r->ns = median_of(ns, REPEATS);
    many_states(qs, Ls, Is); /* q0 = identity: L is also L_b */
    for (k = 0; k < REPEATS; ++k) {
        const double t0 = seconds();
        for (s = 0; s < 4; ++s)
            for (b = 0; b < BODIES; ++b)
                rk4_carried(Ls + 3 * b, qs + 4 * b, Is + 3 * b, H);
        many[k] = 1e9 * (seconds() - t0) / (4.0 * BODIES);
    }
    keep(qs[0]);
    r->ns_many = median_of(many, REPEATS);
    r->ns_portable = r->ns_lanes = -1;
}

static void rk4_fixed_l_kernel(double q[4], const double L[3], const double invI[3], double h)
{
    rk4_fixed_l(q, L, invI, h);
}

/* ODE: one free body, no gravity, gyroscopic mode on (its default). */
static void ode_setup(dWorldID *world, dBodyID *body)
{
    dMass m;
    *world = dWorldCreate();
    dWorldSetGravity(*world, 0, 0, 0);
    dWorldSetAutoDisableFlag(*world, 0);
    *body = dBodyCreate(*world);
    dMassSetZero(&m);
    dMassSetParameters(&m, 1, 0, 0, 0, I_BODY[0], I_BODY[1], I_BODY[2], 0, 0, 0);
    dBodySetMass(*body, &m);
    dBodySetAngularVel(*body, W0[0], W0[1], W0[2]); /* q0 = identity: world = body */
}

/* |L| and E of an ODE body: L = R I R^T w from its rotation and world w. */
static void ode_momentum(dBodyID body, double *l, double *e)
{
    const dReal *R = dBodyGetRotation(body), *w = dBodyGetAngularVel(body);
    double wb[3], L[3];
    int i;
    for (i = 0; i < 3; ++i) /* R is 3x4, row-major: wb = R^T w */
        wb[i] = R[0 * 4 + i] * w[0] + R[1 * 4 + i] * w[1] + R[2 * 4 + i] * w[2];
    for (i = 0; i < 3; ++i)
        L[i] = R[i * 4 + 0] * I_BODY[0] * wb[0] + R[i * 4 + 1] * I_BODY[1] * wb[1] + R[i * 4 + 2] * I_BODY[2] * wb[2];
    *l = norm3(L);
    *e = 0.5 * (I_BODY[0] * wb[0] * wb[0] + I_BODY[1] * wb[1] * wb[1] + I_BODY[2] * wb[2] * wb[2]);
}

static void run_ode(result *r, const double ref[4])
{
    dWorldID world;
    dBodyID body;
    double l0, e0, l, e = 0, q[4], ns[REPEATS];
    long s;
    int k, i;
    ode_setup(&world, &body);
    ode_momentum(body, &l0, &e0);
    r->l_drift = r->e_worst = 0;
    for (s = 0; s < STEPS; ++s) {
        dWorldStep(world, H);
        ode_momentum(body, &l, &e);
        r->l_drift = fmax(r->l_drift, fabs(l / l0 - 1));
        r->e_worst = fmax(r->e_worst, fabs(e / e0 - 1));
    }
    r->e_end = fabs(e / e0 - 1);
    for (i = 0; i < 4; ++i)
        q[i] = dBodyGetQuaternion(body)[i]; /* (w, x, y, z) */
    r->angle = angle_between(ref, q);
    dWorldDestroy(world);
    for (k = 0; k < REPEATS; ++k) {
        double t0;
        ode_setup(&world, &body);
        t0 = seconds();
        for (s = 0; s < STEPS; ++s)
            dWorldStep(world, H);
        ns[k] = 1e9 * (seconds() - t0) / STEPS;
        keep(dBodyGetQuaternion(body)[0]);
        dWorldDestroy(world);
    }
    r->ns = median_of(ns, REPEATS);
    r->ns_many = r->ns_portable = r->ns_lanes = -1;
}

/* ----------------------------------------------------------------- main -- */

static void print_header(void)
{
    printf("torque-free rotation: the intermediate-axis flip, I = diag(1, 2, 3) kg m^2,\n"
           "w0 = (0.01, 5, 0.01) rad/s (body), q0 = identity, %.0f s at h = 1/%.0f s\n", T_END, 1 / H);
    bench_print_build();
    printf("ODE       %s, %s precision\n\n", TB_BENCH_ODE,
           dCheckConfiguration("ODE_double_precision") ? "double" : "single");
}

int main(void)
{
    double ref[4], half[4], invI[3], L[3], q0[4];
    result r[7];
    int n = 0, i;

    print_header();
    dInitODE2(0);

    flip_state(invI, L, q0);
    {
        double lb[3];
        long s;
        memcpy(ref, q0, sizeof ref);
        memcpy(lb, L, sizeof lb);
        for (s = 0; s < 64 * STEPS; ++s)
            rk4_carried(lb, ref, invI, H / 64);
        memcpy(half, q0, sizeof half);
        memcpy(lb, L, sizeof lb);
        for (s = 0; s < 32 * STEPS; ++s)
            rk4_carried(lb, half, invI, H / 32);
    }
    printf("reference: RK4 on (L_b, q) at h/64; it differs from h/32 by %.1e rad\n\n", angle_between(ref, half));

    r[n].name = "tumble frozen (order 1)";
    run_kernel(&r[n++], tb__rotation_frozen, 0, ref);
    r[n].name = "tumble split2 (order 2)";
    run_kernel(&r[n++], tb__rotation_split2, 1, ref);
    r[n].name = "tumble accurate (order 4)";
    run_kernel(&r[n++], tb__rotation_accurate, 2, ref);
    r[n].name = "RK4 on (L_b, q), MuJoCo-like";
    run_rk4_carried(&r[n++], ref);
    r[n].name = "RK4 on q, world L fixed";
    run_kernel(&r[n++], rk4_fixed_l_kernel, -1, ref);
    r[n].name = "ODE dWorldStep";
    run_ode(&r[n++], ref);

    printf("%-30s %10s %10s %10s %12s %9s %13s %9s %9s\n", "method", "|L| drift", "E drift", "E worst",
           "orientation", "ns/step", "ns/body-step", "lanes", "lanes");
    printf("%-30s %10s %10s %10s %12s %9s %13s %9s %9s\n", "", "(worst)", "(at 20 s)", "", "(rad)", "(1 body)",
           "(1024 bodies)", "portable", isa_names[tb__isa()]);
    for (i = 0; i < n; ++i) {
        printf("%-30s %10.1e %10.1e %10.1e %12.1e %9.1f ", r[i].name, r[i].l_drift, r[i].e_end, r[i].e_worst,
               r[i].angle, r[i].ns);
        if (r[i].ns_many >= 0)
            printf("%13.1f ", r[i].ns_many);
        else
            printf("%13s ", "-");
        if (r[i].ns_lanes >= 0)
            printf("%9.1f %9.1f\n", r[i].ns_portable, r[i].ns_lanes);
        else
            printf("%9s %9s\n", "-", "-");
    }
    printf("\nmedians of %d repeats; tumble's targets for its best method: |L| drift <= 1e-12, energy drift\n"
           "<= 1e-9, orientation <= 1e-6 rad, <= 50 ns per step\n", REPEATS);
    dCloseODE();
    return 0;
}
