/* rotation.h: torque-free rotation of rigid bodies over one step, as pure
   kernels (rotation.c). Internal to the core, not public.

   The model is DESIGN.md section 2: q is a unit quaternion (w, x, y, z)
   taking the body's principal axes to the world (R = R(q)); L is the angular
   momentum about the centre of mass in the WORLD frame, kg m^2/s; invI holds
   the inverse principal moments 1/I1, 1/I2, 1/I3 in 1/(kg m^2), in the order
   of the body axes (any order of size; finite and >= 0). The body-frame
   momentum is L_b = R^T L, the angular velocity w = R diag(invI) L_b, the
   kinetic energy E = 1/2 sum invI_i L_b,i^2.

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
   instead of each waiting for the last. A
   lane does the arithmetic of the one-body kernel in the same order, so a
   body gets the same bits alone or in lanes, whatever its neighbours
   (tests/test_rotation.c checks it). The world steps its bodies in lanes.

   Where a product meets a sum the kernels call fma(): one rounding, the
   same on every instruction set, so the variants still give the same bits
   (with -ffp-contract=off nothing else is fused). AVX2 and AVX-512 do it
   in one instruction, which took a fifth off the splitting kernels (1000
   boxes under "verlet": 9.8 to 7.9 ns a body-step); without them the C
   library does, exactly, a call each, which makes the portable lanes 8 to
   80 times slower. Processors without AVX2 (before 2013) pay that.

   Costs: per body-step on this project's 2-core x86-64 (gcc -O2, no
   -march), in lanes over 1024 bodies (what a world pays) with AVX-512 and
   with portable C (SSE2, fma() through the C library), then for one body
   stepped alone (each step waiting for the last; the one-body kernels
   run on the widest instruction set too), +-20% run to run.
   Accuracy: on the intermediate-axis flip of NOTES.md at h = 1/60 s over
   20 s (bench/rotation.c). */
#ifndef TB_ROTATION_H
#define TB_ROTATION_H

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
   turns per piece keep the units busy (at 8 lanes the turns were
   latency-bound: 57 ns for accurate against 22 at 32; 64 and 128 were
   no faster). */
#define TB__LANES 32

/* For the definition of a piece of the work of one lane: it must be
   inlined into the loops over lanes for GCC to vectorise those, whatever
   its size. */
#if defined(__GNUC__)
#define TB__LANE static inline __attribute__((always_inline))
#else
#define TB__LANE static inline
#endif

/* The loops over lanes are compiled for several instruction sets and
   chosen at run time (tb__isa): portable C (SSE2 on x86-64, two lanes an
   instruction), AVX2 (four) and AVX-512 (eight), on x86-64 with GCC or
   Clang. Every variant gives the same bits (rotation.c). */
enum { TB__ISA_PORTABLE = 0, TB__ISA_AVX2 = 1, TB__ISA_AVX512 = 2 };
#if defined(__GNUC__) && defined(__x86_64__)
#define TB__X86_DISPATCH 1
#define TB__TARGET_AVX2 __attribute__((target("avx2,fma")))
#if defined(__clang__)
#define TB__TARGET_AVX512 __attribute__((target("avx512f")))
#else
/* GCC's generic tuning would split AVX-512 loops into 256-bit halves */
#define TB__TARGET_AVX512 __attribute__((target("avx512f,prefer-vector-width=512")))
#endif
#else
#define TB__X86_DISPATCH 0
#endif

/* The widest instruction set this processor runs, for the isa arguments
   below (which take any value up to it). */
int tb__isa(void);

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

#endif
