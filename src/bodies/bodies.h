/* bodies.h: rigid bodies (not public): their storage and API
   (bodies.c), their step (body_step.c: derivatives, kicks and drifts in
   blocks of lanes, fused RK4), mass properties (mass.c), and the rotation
   kernels (rotation.c), which are pure functions of their arguments so
   that tests and benchmarks can compile rotation.c alone. */
#ifndef TB_BODIES_H
#define TB_BODIES_H

#include "world.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* ---- rotation kernels (rotation.c) -------------------------------------------

   Torque-free rotation of rigid bodies over one step, as pure kernels.

   The model is docs/design.md, section 2 (docs/rotation.md has the rest):
   q is a unit quaternion (w, x, y, z) taking the body's principal axes to
   the world (R = R(q)); L is the angular momentum about the centre of mass
   in the WORLD frame, kg m^2/s; invI holds the inverse principal moments
   1/I1, 1/I2, 1/I3 in 1/(kg m^2), in the order of the body axes (any order
   of size; finite and >= 0). The body-frame momentum is L_b = R^T L, the
   angular velocity w = R diag(invI) L_b, the kinetic energy
   E = 1/2 sum invI_i L_b,i^2.

   With no torque the world L is constant, so each kernel only advances q
   over a time h (either sign: -h undoes h for the splitting kernels) and
   never touches L. A torque belongs to the caller's kicks of L around these
   drifts. Every kernel turns the body by exact rotations, so |L_b| = |L|
   holds to rounding at any step, and renormalises q (|q| = 1 within 4e-16).
   They read and write nothing else, allocate nothing, call libm only for
   turns beyond their polynomials (noted below) and, in the portable build,
   for fma() (below), and are safe on any thread; q must not alias L or
   invI.

   Each kernel comes twice: for one body, and for TB__LANES bodies side by
   side ("lanes", one array per quantity) in loops of fixed length that GCC
   vectorises at -O2 (two lanes per SSE2 instruction, eight per AVX-512
   one: see tb__isa), where the turns of different bodies also overlap
   instead of each waiting for the last. A lane does the arithmetic of the
   one-body kernel in the same order, so a body gets the same bits alone or
   in lanes, whatever its neighbours
   (test_rotation.lanes_give_the_one_body_bits). The world steps its bodies
   in lanes.

   Where a product meets a sum the kernels call fma(): one rounding, the
   same on every instruction set, so the variants still give the same bits
   (with -ffp-contract=off nothing else is fused). AVX2 and AVX-512 do it
   in one instruction; without them the C library does, exactly, a call
   each, which makes the portable lanes 20 to 80 times slower than the
   widest (the costs below). Processors without AVX2 (before 2013) pay
   that.

   Costs, as bench/rotation.c measures them: per body-step on this
   project's 2-core x86-64 (gcc -O2, no -march), in lanes over 1024 bodies
   (what a world pays) with AVX-512 and with portable C (SSE2, fma()
   through the C library), then for one body stepped alone (each step
   waiting for the last; the one-body kernels run on the widest instruction
   set too), +-20% run to run. Accuracy: on the intermediate-axis flip of
   docs/notes.md at h = 1/60 s over 20 s, as bench/rotation.c measures it
   (test_rotation.split2_on_the_flip and
   test_rotation.accurate_kernel_on_the_flip hold split2 and accurate to
   it). */

/* q <- exp(h w / 2) q with w frozen at the start of the step: one exact turn
   about the start's angular velocity. Order 1 for an asymmetric body (it
   misses the turning of w), exact for an isotropic one, where w is constant.
   libm beyond |w| h = 0.5 rad. 3.6 / 80 ns in lanes (37 ns alone). */
void tb__rotation_frozen(double q[4], const double L[3], const double invI[3], double h);

/* An isotropic body (I1 = I2 = I3 = 1 / inv_inertia) turns about the fixed
   world w = L / I: q <- exp(h w / 2) q, exact. It skips the body-frame
   transform that tb__rotation_frozen needs. */
void tb__rotation_isotropic(double q[4], const double L[3], double inv_inertia, double h);

/* Order 2: Strang splitting of T into a turn about the world L and turns
   about two principal axes (rotation.c), A(h/2) B(h) A(h/2). A Poisson map:
   energy error bounded with no drift (6.0e-5 on the flip), exact for
   symmetric tops and for isotropic bodies (which it hands to
   tb__rotation_isotropic), time-reversible; 1.7e-4 rad on the flip. libm
   only for a turn of more than 1/2 rad in one piece (at h = 1/60 s, a
   spin of about 30 rad/s relative to the turn about L). 11 / 210 ns in
   lanes (76 ns alone). */
void tb__rotation_split2(double q[4], const double L[3], const double invI[3], double h);

/* Order 4: the same splitting composed by Blanes and Moan's S6, 13 axis
   turns a step. Also a Poisson map, exact for isotropic bodies and
   symmetric tops, time-reversible. On the flip: energy within 1.1e-10 at
   every step, 7.5e-10 rad after 20 s. libm as for split2. 19 / 1600 ns
   in lanes (250 ns alone: 13 dependent turns). */
void tb__rotation_accurate(double q[4], const double L[3], const double invI[3], double h);

/* ---- bodies in lanes ----------------------------------------------------- */

/* 32: with eight lanes an AVX-512 instruction, four independent chains of
   turns per piece keep the units busy; at 8 lanes the turns are
   latency-bound, and 64 or 128 lanes are no faster. */
#define TB__LANES 32

/* Lanes hold unit q only (within 5e-9, as the world keeps them): they
   renormalise with the Newton step alone, which the one-body kernels take
   for such q too. */

/* The isotropic and frozen kernels for bodies k < n <= TB__LANES, stored as
   the world stores them: q[4 k], L[3 k], invI[3 k] (for isotropic bodies
   only invI[3 k] is read). A body whose turn is beyond the polynomials
   sends its block of lanes through the one-body kernel. */
void tb__isotropic_lanes(double *q, const double *L, const double *invI, double h, int n, int isa);
void tb__frozen_lanes(double *q, const double *L, const double *invI, double h, int n, int isa);

/* The splitting kernels for bodies k < n <= TB__LANES, stored as the
   world stores them: q[4 k], L[3 k], invI[3 k]. Each body gets the bits of
   tb__rotation_split2 (tb__rotation_accurate) alone: the lanes relabel
   every body's axes themselves, with selects (rotation.c); an isotropic
   body, or one whose turns went beyond the polynomials, is redone by the
   one-body kernel's general path. */
void tb__split2_lanes(double *q, const double *L, const double *invI, double h, int n, int isa);
void tb__accurate_lanes(double *q, const double *L, const double *invI, double h, int n, int isa);

/* The lanes' relabelling of a body (rotation.c), which they otherwise work
   out from invI at every step: the rates a, c_A, c_B and a code for the
   axes. The world keeps these four numbers for each body, one array each,
   and passes the block's pointers in a tb__lane_frames below; the kernels
   then give the same bits as above, without the relabelling's arithmetic. */
void tb__lane_frame_of(const double invI[3], double *a, double *ca, double *cb, double *code);
typedef struct tb__lane_frames {
    const double *a, *ca, *cb, *code;
} tb__lane_frames;
void tb__split2_lanes_framed(double *q, const double *L, const double *invI, const tb__lane_frames *frame, double h,
                             int n, int isa);
void tb__accurate_lanes_framed(double *q, const double *L, const double *invI, const tb__lane_frames *frame,
                               double h, int n, int isa);

/* How the splitting kernels relabel a body's axes (rotation.c): which
   play A, middle and B, and the rates. The lanes read it as
   tb__lane_frame_of gives it (above); the general path and the world's
   isotropic test read it from here (tb__split_frame_of, once per body). */
typedef struct tb__split_frame {
    double a;            /* 1/(kg m^2): inverse middle moment, the rate of the turn about L per |L| */
    double ca, cb;       /* invI_A - a, invI_B - a, with |ca| >= |cb| */
    double sign;         /* det P: -1 when the relabelling is an odd permutation */
    unsigned char ax[3]; /* relabelled axis n is the body's axis ax[n] */
    unsigned char isotropic; /* I1 = I2 = I3: tb__rotation_isotropic does it cheaper */
} tb__split_frame;

void tb__split_frame_of(const double invI[3], tb__split_frame *f);


/* ---- small vector, quaternion and matrix helpers ----------------------------
   Shared by the body tier and what moves bodies around it (contacts,
   auto). q = (w, x, y, z). */


/* Rotation matrix (row-major) of a unit quaternion. */
static inline void tb__matrix_of(const double q[4], double R[9])
{
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    R[0] = 1 - 2 * (y * y + z * z);
    R[1] = 2 * (x * y - w * z);
    R[2] = 2 * (x * z + w * y);
    R[3] = 2 * (x * y + w * z);
    R[4] = 1 - 2 * (x * x + z * z);
    R[5] = 2 * (y * z - w * x);
    R[6] = 2 * (x * z - w * y);
    R[7] = 2 * (y * z + w * x);
    R[8] = 1 - 2 * (x * x + y * y);
}

static inline void tb__mul(const double R[9], const double v[3], double out[3])
{
    out[0] = R[0] * v[0] + R[1] * v[1] + R[2] * v[2];
    out[1] = R[3] * v[0] + R[4] * v[1] + R[5] * v[2];
    out[2] = R[6] * v[0] + R[7] * v[1] + R[8] * v[2];
}

static inline void tb__mul_transposed(const double R[9], const double v[3], double out[3])
{
    out[0] = R[0] * v[0] + R[3] * v[1] + R[6] * v[2];
    out[1] = R[1] * v[0] + R[4] * v[1] + R[7] * v[2];
    out[2] = R[2] * v[0] + R[5] * v[1] + R[8] * v[2];
}

static inline void tb__quat_mul(const double a[4], const double b[4], double out[4])
{
    double r[4];
    r[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    r[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    r[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    r[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    memcpy(out, r, sizeof r);
}

static inline void tb__normalise(double q[4])
{
    const double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    q[0] /= n, q[1] /= n, q[2] /= n, q[3] /= n;
}

/* q <- q / |q| after a generic step (project). Three Newton steps for
   1 / |q| from 1 are exact to rounding (7e-18) while |q|^2 is within 1e-2
   of 1, which it is after any step a method keeps stable, and they
   vectorise, where sqrt (which may set errno) does not; a q further off is
   divided by its root. tb__newton_scale returns the factor and |q|^2. */
TB__LANE double tb__newton_scale(const double q[4], double *n2)
{
    double f;
    *n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
    f = 1.5 - 0.5 * *n2;
    f = f * (1.5 - 0.5 * *n2 * f * f);
    return f * (1.5 - 0.5 * *n2 * f * f);
}

#define TB__PROJECT_NEAR(n2) (fabs((n2) - 1) <= 1e-2)

static inline int tb__project_near(double q[4])
{
    double n2;
    const double f = tb__newton_scale(q, &n2);
    if (!TB__PROJECT_NEAR(n2))
        return 0;
    q[0] *= f, q[1] *= f, q[2] *= f, q[3] *= f;
    return 1;
}

/* A q whose squares overflow (a turn of h |w| beyond about 1e38 through
   RK4's polynomial) or underflow is first divided by its largest
   component, so that it still comes back unit rather than zero or NaN;
   every other q takes the one division by its root. */
static inline void tb__project_far(double q[4])
{
    double n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], f;
    if (!(n2 <= DBL_MAX && n2 >= DBL_MIN)) {
        const double m = fmax(fmax(fabs(q[0]), fabs(q[1])), fmax(fabs(q[2]), fabs(q[3])));
        if (m > 0 && m <= DBL_MAX) {
            q[0] /= m, q[1] /= m, q[2] /= m, q[3] /= m;
            n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
        }
    }
    f = 1 / sqrt(n2);
    q[0] *= f, q[1] *= f, q[2] *= f, q[3] *= f;
}

static inline void tb__project_unit(double q[4])
{
    if (!tb__project_near(q))
        tb__project_far(q);
}

/* w = R diag(scale) R^T v: with scale = 1/I it turns L into w, with I the
   other way. `q` need not be exactly unit (RK stages): it is normalised. */
static inline void tb__through_inertia(const double q[4], const double scale[3], const double v[3], double out[3])
{
    double u[4], R[9], b[3];
    memcpy(u, q, sizeof u);
    tb__normalise(u);
    tb__matrix_of(u, R);
    tb__mul_transposed(R, v, b);
    b[0] *= scale[0], b[1] *= scale[1], b[2] *= scale[2];
    tb__mul(R, b, out);
}

static inline double tb__dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline double tb__norm3(const double a[3])
{
    return sqrt(tb__dot3(a, a));
}

static inline void tb__cross(const double a[3], const double b[3], double out[3])
{
    double r[3];
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
    memcpy(out, r, sizeof r);
}


/* ---- the body tier (bodies.c, body_step.c) --------------------------------- */
/* The slot of a live body id, or TB_ERR_STALE_ID with a message. */
tb_status tb__body_find(const tb_world *w, tb_body_id id, uint32_t *slot);
/* v and w of body slot s from its momenta. */
void tb__body_velocity(const tb_world *w, uint32_t s, double v[3], double omega[3]);
/* Wake body slot s and the island it sleeps in (if it sleeps); wake every
   body. Sleep itself (who falls asleep) is the contacts' (sleep.c). */
void tb__wake_body(tb_world *w, uint32_t s);
void tb__wake_island(tb_world *w, uint32_t island);
void tb__wake_all(tb_world *w);
void tb__bodies_free(tb_world *w);
/* Add the bodies' energies and momenta (about the origin) to the totals. */
void tb__body_energy(const tb_world *w, const double *y, tb_energy *e);
/* ... of body slot s alone, added into e */
void tb__body_energy_at(const tb_world *w, const double *y, size_t s, tb_energy *e);
void tb__body_momenta(const tb_world *w, double linear[3], double angular[3]);

/* dP/dt and dL/dt of body slot s at momenta P, L: gravity, damping, held
   forces, and w->body_force when it is ready. */
void tb__body_rates(const tb_world *w, uint32_t s, const double *P, const double *L, double dP[3], double dL[3]);
/* dy = F(t, y) for the bodies, their callback forces already in w->body_force. */
void tb__body_derive(tb_world *w, const double *y, double *dy);
/* The split methods' kicks and drifts over every body, in blocks of lanes;
   a block whose bodies all sleep is passed over when
   tb__body_sweep_skips_sleeping (sleep puts their poses back after the
   integrator anyway, and no force on an awake body can see where they
   would have drifted). */
void tb__body_sweep(tb_world *w, const tb__split_op *ops, int n);
int tb__body_sweep_skips_sleeping(const tb_world *w);
/* Whether bodies [b, b + m) all sleep. */
int tb__body_block_asleep(const tb_world *w, size_t b, size_t m);
/* Whether a body force depends on velocity (damping). */
int tb__body_velocity_dependent(const tb_world *w);
/* Put the bodies' q of y back on unit length after a generic stage. */
void tb__body_project(tb_world *w, double *y);
/* v and w of every body of state y (momenta from seen) into
   w->body_motion, for callbacks. */
void tb__body_motion(tb_world *w, const double *y, const double *seen);
/* RK4 through all four stages one block of bodies at a time, with the
   generic method's arithmetic (the same bits): for worlds where nothing
   couples objects (stepping decides). */
void tb__body_rk4(tb_world *w, double h);

#endif
