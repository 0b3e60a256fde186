/* rotation.c: torque-free rotation kernels (see bodies.h for the model).

   The splitting kernels write the kinetic energy as
       T = a |L|^2 / 2 + c_A L_A^2 / 2 + c_B L_B^2 / 2,   c_i = invI_i - a,
   with a the inverse of the middle principal moment, so the middle axis has
   no term of its own. Each piece has an exact flow:
   - a |L|^2 / 2 turns the body about the fixed world vector L at the rate
     a |L|; it commutes with everything (it leaves L_b alone), so one such
     turn by a h |L| serves the whole step whatever the composition;
   - c_i L_i^2 / 2 turns the body about its principal axis i at the rate
     c_i L_b,i, which that turn does not change.
   A symmetric composition of the two axis flows is a Poisson map (bounded
   energy error, no drift), time-reversible, keeps |L_b| to rounding, and is
   exact whenever c_A or c_B vanishes: for every symmetric top and isotropic
   body. This splitting is more accurate than splitting into three axis
   rotations (Fasso 2003): on the flip of docs/notes.md at h = 1/60 its
   Strang step is 4 times closer to the exact orientation than the best
   order of R1 R2 R3 R2 R1 (1.7e-4 against 6.7e-4 rad), with 3 axis turns a
   step instead of 5. The outer axis with the larger |c| is A, the one
   turned more often: better than the other way round on every body tried
   (about 2 times for the 4th-order compositions).

   The accurate method is Blanes and Moan's S6, the cheapest composition of
   these pieces that meets the flip's targets (1e-6 rad, energy 1e-9)
   without a projection. The comparison (h = 1/60, 20 s; orientation error
   after 20 s, worst relative energy error over the run, ns per step of one
   body per call over 1024 bodies on this project's 2-core x86-64, gcc -O2,
   +-15% run to run):
       composition                      order turns  orientation  energy   ns
       Strang A(h/2) B(h) A(h/2)          2     3     1.7e-4     6.0e-5    55
       Strang, two half steps             2     5     4.2e-5     1.5e-5    85
       Yoshida triple jump                4     7     4.1e-7     3.1e-8   120
       Yoshida + energy projection        4     7     4.9e-7     1e-14    140
       Omelyan PEFRL                      4     9     9.3e-9     5.6e-9   150
       Omelyan PEFRL + energy projection  4     9     1.1e-8     1e-14    200
       Suzuki 5-stage                     4    11     5.9e-9     7.1e-9   215
       Blanes-Moan S6 (chosen)            4    13     7.5e-10    1.1e-10  210
       Yoshida 6th order                  6    15     2.0e-10    7.4e-12   -
       Kahan-Li 6th order                 6    19     2.5e-11    8.5e-13   -
   and, not splittings: RK4 on (L_b, q) from each step's L_b = R^T L,
   1.0e-4 rad at 80 ns; Magnus 4th order with a Taylor L_b and energy
   projection, 2e-8 rad on the flip but up to 1.5e-4 rad on other bodies
   and 5e-6 on near-symmetric ones, where the splittings are nearly exact.
   The code holds the first row (split2) and S6 (accurate): bench/rotation.c
   measures both, and test_rotation.split2_on_the_flip and
   test_rotation.accurate_kernel_on_the_flip hold them to their figures.
   Called for one body, a composition costs its chain of turns, each
   needing the momentum the previous one left; in lanes (below) the turns of
   32 bodies overlap, and with AVX-512 S6 costs a body about a tenth as much
   (bodies.h has each kernel's cost). Yoshida + projection meets the
   targets at 2/3 of S6's cost but with a margin of 2 and errors up to
   1.4e-4 rad on other bodies; S6 meets them with margins of 1300 and 9,
   stays within 2.7e-7 rad on every other body tried (12 random bodies at up
   to 9 rad/s), and unlike a projected method it stays symplectic and
   time-reversible.

   The kernels relabel the body axes so that A, the middle axis and B become
   axes 0, 1, 2 (a permutation P of the body and world axes alike: the
   relabelled body obeys the same equations, with q's vector part, L and L_b
   multiplied by det P when P is odd), so one straight-line body of code
   serves every order of moments. Turns are computed in the body frame from
   L_b. The lanes (the world's path) relabel L_b alone and compose the
   step's turns into one quaternion T, the turn about the world L included
   (r q = q r_b, with r_b the same turn about L_b), then set q <- q T in
   the body's own axes: every body has its own P, and this way only two
   3-vectors a step go through it, with selects the loops vectorise. The
   general path (split_any) relabels q and L and turns q itself: the
   same rotations, rounded differently. */
#include "bodies/bodies.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

/* ------------------------------------------------ small-angle trigonometry -- */

/* sin x and cos x for |x| <= 1/4 as polynomials in u = x^2, no sqrt or
   range reduction needed. sin x is its Taylor series through x^11: the
   first term left out, x^13/13!, is at most 9.6e-18 of sin x there. cos x
   (and sin(x) / x below) is 1 - u/2 (1 - u/6) and then the minimax
   polynomial of degree 3 for the rest, (cos x - 1 + u/2) / u^2, weighted
   by u^2 on 0 <= u <= 1/16 (Remez exchange, 60 digits, rounded to double):
   cos x within 3.1e-19 (sin(x) / x within 2.4e-20) of the exact value,
   where the Taylor series needs a term more, x^12, for 4.3e-20 (1e-19).
   Evaluated in double, both are within 1.5 units in the last place of
   cos x on a dense grid, like the Taylor series (and as good as a
   correctly rounded libm's after the rounding of u). (At 1/8 two terms
   fewer would do, but a body spinning at 45 rad/s about a thin axis would
   then leave the lanes for the slow general path at every step.) */
#define TB__SMALL 0.25
#define TB__COS2 0.04166666666666468       /* 1/24 - 2.0e-15 */
#define TB__COS3 (-0.0013888888885387693)  /* -1/720 + 3.5e-13 */
#define TB__COS4 2.4801569985195017e-05    /* 1/40320 - 1.7e-11 */
#define TB__COS5 (-2.7524717767692497e-07) /* -1/3628800 + 3.3e-10 */
#define TB__SINC2 0.00833333333333318       /* 1/120 - 1.5e-16 */
#define TB__SINC3 (-0.00019841269838576317) /* -1/5040 + 2.7e-14 */
#define TB__SINC4 2.7557305902356644e-06    /* 1/362880 - 1.3e-12 */
#define TB__SINC5 (-2.5027028447633727e-08) /* -1/39916800 + 2.5e-11 */

TB__LANE double cos_poly(double u, double u2, double u4)
{
    /* Estrin's scheme: Horner's chain of dependent operations would be
       the critical path of the lanes */
    return fma(u4, fma(u, TB__COS5, TB__COS4), fma(u2, fma(u, TB__COS3, TB__COS2), fma(u, -1.0 / 2, 1)));
}

TB__LANE void sincos4(double x, double *s, double *c)
{
    const double u = x * x, u2 = u * u, u4 = u2 * u2;
    const double odd = fma(u4, -1.0 / 39916800, fma(u2, fma(u, 1.0 / 362880, -1.0 / 5040), fma(u, 1.0 / 120, -1.0 / 6)));
    *s = fma(x * u, odd, x);
    *c = cos_poly(u, u2, u4);
}

/* sin(x) / x and cos x from u = x^2 <= 1/16 (|x| <= 1/4). */
TB__LANE void sinc_cos4(double u, double *sinc, double *c)
{
    const double u2 = u * u, u4 = u2 * u2;
    *sinc = fma(u4, fma(u, TB__SINC5, TB__SINC4), fma(u2, fma(u, TB__SINC3, TB__SINC2), fma(u, -1.0 / 6, 1)));
    *c = cos_poly(u, u2, u4);
}

/* The quaternion (cos x, (sin x / x) k v) of a rotation by 2 x about v, for
   x^2 = k^2 |v|^2 = u. The polynomial path needs no sqrt; angles 2 x above
   1/2 rad go to libm, out of line. */
static void half_turn_big(double u, double k, const double v[3], double r[4])
{
    const double x = sqrt(u);
    const double f = sin(x) / x * k;
    r[0] = cos(x);
    r[1] = f * v[0];
    r[2] = f * v[1];
    r[3] = f * v[2];
}

/* The polynomial path of half_turn, u <= 1/16. */
TB__LANE void turn_poly(double u, double k, const double v[3], double r[4])
{
    double sinc, c;
    sinc_cos4(u, &sinc, &c);
    sinc *= k;
    r[0] = c;
    r[1] = sinc * v[0];
    r[2] = sinc * v[1];
    r[3] = sinc * v[2];
}

TB__LANE void half_turn(double u, double k, const double v[3], double r[4])
{
    if (u > TB__SMALL * TB__SMALL)
        half_turn_big(u, k, v, r);
    else
        turn_poly(u, k, v, r);
}

/* ------------------------------------------------------ quaternion algebra -- */

/* v_b = R(q)^T v: v + 2 w (p x v) + 2 p x (p x v) with p = -(x, y, z),
   written with t = -2 (p x v) = 2 (x, y, z) x v: v - w t + (x, y, z) x t.
   The negations are exact, so this is the same arithmetic to the bit,
   without them. */
TB__LANE void to_body(const double q[4], const double v[3], double out[3])
{
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    const double tx = 2 * fma(y, v[2], -(z * v[1]));
    const double ty = 2 * fma(z, v[0], -(x * v[2]));
    const double tz = 2 * fma(x, v[1], -(y * v[0]));
    out[0] = fma(-w, tx, v[0]) + fma(y, tz, -(z * ty));
    out[1] = fma(-w, ty, v[1]) + fma(z, tx, -(x * tz));
    out[2] = fma(-w, tz, v[2]) + fma(x, ty, -(y * tx));
}

/* out = a b (Hamilton product). out may be a or b. */
TB__LANE void qmul(const double a[4], const double b[4], double out[4])
{
    const double w = fma(a[0], b[0], -(a[1] * b[1])) - fma(a[2], b[2], a[3] * b[3]);
    const double x = fma(a[0], b[1], a[1] * b[0]) + fma(a[2], b[3], -(a[3] * b[2]));
    const double y = fma(a[0], b[2], -(a[1] * b[3])) + fma(a[2], b[0], a[3] * b[1]);
    const double z = fma(a[0], b[3], a[1] * b[2]) + fma(a[3], b[0], -(a[2] * b[1]));
    out[0] = w;
    out[1] = x;
    out[2] = y;
    out[3] = z;
}

/* Scale q to unit length. Every kernel starts from a unit q and applies unit
   rotations, so |q|^2 = 1 + e with e a few rounding errors; one Newton step
   for 1/sqrt, 1 - e/2, then leaves 3 e^2 / 8, far below rounding. A q
   further off (e > 1e-8, say from a caller that does not keep it unit) gets
   the full division by its norm. */
TB__LANE double norm2(const double q[4])
{
    return fma(q[0], q[0], q[1] * q[1]) + fma(q[2], q[2], q[3] * q[3]);
}

TB__LANE void scale(const double in[4], double f, double q[4])
{
    q[0] = in[0] * f;
    q[1] = in[1] * f;
    q[2] = in[2] * f;
    q[3] = in[3] * f;
}

TB__LANE void normalize(const double in[4], double q[4])
{
    const double n2 = norm2(in);
    scale(in, fabs(n2 - 1) <= 1e-8 ? fma(-0.5, n2, 1.5) : 1 / sqrt(n2), q);
}

/* The lanes take the Newton step without looking: they only hold unit q
   (bodies.h), which the exact turns keep within a few rounding errors, so
   normalize would take it too. */

TB__LANE void newton(const double in[4], double q[4])
{
    scale(in, fma(-0.5, norm2(in), 1.5), q);
}

/* -------------------------------------------------- frozen and isotropic -- */

/* q <- q exp(h w_b / 2), the same rotation as exp(h w / 2) q with the world
   w = R w_b, without going back to the world frame. */
TB__LANE double frozen_turn(const double q[4], const double L[3], const double invI[3], double k,
                            double w[3])
{
    double lb[3];
    to_body(q, L, lb);
    w[0] = invI[0] * lb[0];
    w[1] = invI[1] * lb[1];
    w[2] = invI[2] * lb[2];
    return k * k * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
}

/* The one-body kernels are templates as the lanes are, compiled for each
   instruction set (below): with fma() in their arithmetic (bodies.h),
   the portable build calls the C library for every one. */
TB__LANE void frozen_one(double q[4], const double L[3], const double invI[3], double h)
{
    double w[3], r[4];
    const double k = 0.5 * h;
    half_turn(frozen_turn(q, L, invI, k, w), k, w, r);
    qmul(q, r, r);
    normalize(r, q);
}

TB__LANE double isotropic_turn(const double L[3], double inv_inertia, double k, double w[3])
{
    w[0] = inv_inertia * L[0];
    w[1] = inv_inertia * L[1];
    w[2] = inv_inertia * L[2];
    return k * k * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
}

TB__LANE void isotropic_one(double q[4], const double L[3], double inv_inertia, double h)
{
    double w[3], r[4];
    const double k = 0.5 * h;
    half_turn(isotropic_turn(L, inv_inertia, k, w), k, w, r);
    qmul(r, q, r); /* w is a world vector: turn on the left */
    normalize(r, q);
}

/* In lanes, in two passes: the turns r, and whether each is within the
   polynomial (u <= 1/16), then, if all are, q <- r q (or q r) with the
   Newton step; otherwise the block goes through the one-body kernel, which
   takes the same path for the lanes within the polynomial. */
typedef struct tb__turn_lanes {
    double w[TB__LANES], x[TB__LANES], y[TB__LANES], z[TB__LANES], u[TB__LANES];
} tb__turn_lanes;

TB__LANE void turn_put(tb__turn_lanes *t, int i, double u, double k, const double w[3])
{
    double r[4];
    turn_poly(u, k, w, r);
    t->w[i] = r[0];
    t->x[i] = r[1];
    t->y[i] = r[2];
    t->z[i] = r[3];
    t->u[i] = u;
}

TB__LANE int turns_small(const tb__turn_lanes *t)
{
    int i;
    for (i = 0; i < TB__LANES; ++i)
        if (!(t->u[i] <= TB__SMALL * TB__SMALL))
            return 0;
    return 1;
}

/* The two kernels in lanes, as templates for each instruction set
   (TB__KERNELS below). */
TB__LANE void isotropic_lanes_t(double *restrict q, const double *restrict L, const double *restrict invI,
                                double h, int n)
{
    const double k = 0.5 * h;
    int i;
    if (n == TB__LANES) {
        double l[3][TB__LANES], inv[TB__LANES];
        tb__turn_lanes t;
        /* L and invI one array per component first: the turns then run
           on whole vectors, not on the stride of 3 */
        for (i = 0; i < TB__LANES; ++i)
            l[0][i] = L[3 * i], l[1][i] = L[3 * i + 1], l[2][i] = L[3 * i + 2], inv[i] = invI[3 * i];
        for (i = 0; i < TB__LANES; ++i) {
            double w[3], li[3];
            li[0] = l[0][i], li[1] = l[1][i], li[2] = l[2][i];
            turn_put(&t, i, isotropic_turn(li, inv[i], k, w), k, w);
        }
        if (turns_small(&t)) {
            for (i = 0; i < TB__LANES; ++i) {
                double r[4];
                r[0] = t.w[i], r[1] = t.x[i], r[2] = t.y[i], r[3] = t.z[i];
                qmul(r, q + 4 * i, r);
                newton(r, q + 4 * i);
            }
            return;
        }
    }
    for (i = 0; i < n; ++i)
        isotropic_one(q + 4 * i, L + 3 * i, invI[3 * i], h);
}

TB__LANE void frozen_lanes_t(double *restrict q, const double *restrict L, const double *restrict invI,
                             double h, int n)
{
    const double k = 0.5 * h;
    int i;
    if (n == TB__LANES) {
        double v[10][TB__LANES];
        tb__turn_lanes t;
        for (i = 0; i < TB__LANES; ++i) { /* one array per component, as above */
            v[0][i] = q[4 * i], v[1][i] = q[4 * i + 1], v[2][i] = q[4 * i + 2], v[3][i] = q[4 * i + 3];
            v[4][i] = L[3 * i], v[5][i] = L[3 * i + 1], v[6][i] = L[3 * i + 2];
            v[7][i] = invI[3 * i], v[8][i] = invI[3 * i + 1], v[9][i] = invI[3 * i + 2];
        }
        for (i = 0; i < TB__LANES; ++i) {
            double w[3], qi[4], li[3], ii[3];
            qi[0] = v[0][i], qi[1] = v[1][i], qi[2] = v[2][i], qi[3] = v[3][i];
            li[0] = v[4][i], li[1] = v[5][i], li[2] = v[6][i];
            ii[0] = v[7][i], ii[1] = v[8][i], ii[2] = v[9][i];
            turn_put(&t, i, frozen_turn(qi, li, ii, k, w), k, w);
        }
        if (turns_small(&t)) {
            for (i = 0; i < TB__LANES; ++i) {
                double r[4], qi[4];
                qi[0] = v[0][i], qi[1] = v[1][i], qi[2] = v[2][i], qi[3] = v[3][i];
                r[0] = t.w[i], r[1] = t.x[i], r[2] = t.y[i], r[3] = t.z[i];
                qmul(qi, r, r);
                newton(r, q + 4 * i);
            }
            return;
        }
    }
    for (i = 0; i < n; ++i)
        frozen_one(q + 4 * i, L + 3 * i, invI + 3 * i, h);
}

/* -------------------------------------------------------------- splitting -- */

/* Blanes and Moan, "Practical symplectic partitioned Runge-Kutta and
   Runge-Kutta-Nystrom methods", J. Comput. Appl. Math. 142 (2002), table 2,
   S6: order 4 with 6 evaluations of B,
       A(a1) B(b1) A(a2) B(b2) A(a3) B(b3) A(a4) B(b3) A(a3) B(b2) A(a2) B(b1) A(a1),
   a4 = 1 - 2 (a1 + a2 + a3), b3 = 1/2 - b1 - b2. Its error constants are
   about 100 times smaller than the Yoshida triple jump's; among the 4th- and
   6th-order compositions tried (table at the top) it is the cheapest to
   reach 1e-9 rad on the flip. Largest |coefficient|: b3 = 0.434. */
#define TB__BM_A1 0.0792036964311957
#define TB__BM_A2 0.353172906049774
#define TB__BM_A3 (-0.0420650803577195)
#define TB__BM_A4 (1 - 2 * (TB__BM_A1 + TB__BM_A2 + TB__BM_A3))
#define TB__BM_B1 0.209515106613362
#define TB__BM_B2 (-0.143851773179818)
#define TB__BM_B3 (0.5 - TB__BM_B1 - TB__BM_B2)

/* The relabelling of a body with inverse moments i (see the top): which
   axis has the middle moment (mid0: axis 0, mid1: axis 1, neither: axis
   2; with ties the first of 1, 0, 2), whether A is the axis after it
   cyclically (up_a: then det P = -1) or the one before, and the rates.
   Minima, maxima and selects, no branches or indices, so that the loops
   over lanes vectorise it. The world keeps it for each body as the lanes
   read it, four numbers in four arrays (frame_put): loaded so, it costs
   less than working it out at every step (about 30 operations per 8 lanes
   with AVX-512, and the transposition of invI) or than reading it from a
   tb__split_frame, one struct per body. */
typedef struct tb__relabel {
    int mid0, mid1, up_a, isotropic;
    double a, ca, cb;
} tb__relabel;

/* x86's minpd and maxpd, exactly */
TB__LANE double minpd(double x, double y)
{
    return y < x ? y : x;
}

TB__LANE double maxpd(double x, double y)
{
    return y > x ? y : x;
}

TB__LANE void relabel_of(const double i[3], tb__relabel *r)
{
    const double lo01 = minpd(i[0], i[1]), hi01 = maxpd(i[0], i[1]);
    const double lo = minpd(lo01, i[2]), hi = maxpd(hi01, i[2]);
    const double a = maxpd(lo01, minpd(hi01, i[2])); /* the median */
    const int m1 = i[1] == a, m0 = (!m1) & (i[0] == a);
    const double up = m1 ? i[2] : m0 ? i[1] : i[0];
    const int hi_a = hi - a > a - lo; /* A: the outer axis with the larger |c| */
    r->mid0 = m0;
    r->mid1 = m1;
    r->up_a = hi_a == (up == hi); /* A comes after the middle axis */
    r->a = a;
    r->ca = (hi_a ? hi : lo) - a;
    r->cb = (hi_a ? lo : hi) - a;
    r->isotropic = r->ca == 0; /* |ca| >= |cb|: both moments equal the middle one */
}

/* A body-frame vector v in the relabelled axes: (v_A, v_mid, v_B) when P
   is even; when it is odd, (v_A, -v_mid, v_B), which turns the relabelled
   frame right-handed again as det P (v_A, v_mid, v_B) would (the general
   path's choice): the two frames differ by a half turn about the middle
   axis, D = diag(-1, 1, -1), and every operation of a composition (turns
   by odd polynomials of angles proportional to L_A or L_B, products of
   quaternions, turns of L_b) commutes with D exactly, as negation is
   exact. The same bits, with one negation in place of three. mid0, mid1:
   the middle axis is 0, 1 (neither: 2). */
TB__LANE void relabel_in(int mid0, int mid1, int up_a, const double v[3], double out[3])
{
    const double m0 = mid0 ? v[0] : v[2], up0 = mid0 ? v[1] : v[0], down0 = mid0 ? v[2] : v[1];
    const double m = mid1 ? v[1] : m0, up = mid1 ? v[2] : up0, down = mid1 ? v[0] : down0;
    out[0] = up_a ? up : down;
    out[1] = up_a ? -m : m;
    out[2] = up_a ? down : up;
}

/* ... and back. */
TB__LANE void relabel_out(int mid0, int mid1, int up_a, const double in[3], double out[3])
{
    const double m = up_a ? -in[1] : in[1];
    const double up = up_a ? in[0] : in[2];
    const double down = up_a ? in[2] : in[0];
    const double o0 = mid0 ? m : up, o1 = mid0 ? up : down, o2 = mid0 ? down : m;
    out[0] = mid1 ? down : o0;
    out[1] = mid1 ? m : o1;
    out[2] = mid1 ? up : o2;
}

/* The frame the general path (split_any) works in: the same choice. */
void tb__split_frame_of(const double invI[3], tb__split_frame *f)
{
    tb__relabel r;
    int m;
    relabel_of(invI, &r);
    m = r.mid1 ? 1 : r.mid0 ? 0 : 2;
    f->ax[1] = (unsigned char)m;
    f->ax[r.up_a ? 0 : 2] = (unsigned char)(m == 2 ? 0 : m + 1);
    f->ax[r.up_a ? 2 : 0] = (unsigned char)(m == 0 ? 2 : m - 1);
    f->sign = r.up_a ? -1 : 1;
    f->a = r.a;
    f->ca = r.ca;
    f->cb = r.cb;
    f->isotropic = (unsigned char)r.isotropic;
}

/* The state a composition works on, in the relabelled axes: the quaternion
   the turns act on (q in the general path, T in the lanes) and L_b. */
typedef struct tb__spin {
    double w, x, y, z;  /* q or T */
    double l0, l1, l2;  /* L_b, kg m^2/s */
} tb__spin;

/* Turn the body by the angle 2 x about (relabelled) axis 0, given s = sin x
   and c = cos x: q <- q (c, s e0) (or T), and L_b <- R_0(2x)^T L_b. `last`
   skips L_b, which the final turn of a step leaves unused. */
TB__LANE void turn_a(tb__spin *p, double s, double c, int last)
{
    const double w = p->w, x0 = p->x, y = p->y, z = p->z;
    p->w = fma(w, c, -(x0 * s));
    p->x = fma(x0, c, w * s);
    p->y = fma(y, c, z * s);
    p->z = fma(z, c, -(y * s));
    if (!last) {
        const double C = fma(-2 * s, s, 1), S = 2 * s * c, l1 = p->l1, l2 = p->l2;
        p->l1 = fma(C, l1, S * l2);
        p->l2 = fma(C, l2, -(S * l1));
    }
}

/* The same about (relabelled) axis 2: q <- q (c, s e2). `l0_only` skips
   L_b's component 1, which a turn before the last A reads no more. */
TB__LANE void turn_b(tb__spin *p, double s, double c, int l0_only)
{
    const double w = p->w, x0 = p->x, y = p->y, z = p->z;
    const double C = fma(-2 * s, s, 1), S = 2 * s * c, l0 = p->l0, l1 = p->l1;
    p->w = fma(w, c, -(z * s));
    p->x = fma(x0, c, y * s);
    p->y = fma(y, c, -(x0 * s));
    p->z = fma(z, c, w * s);
    p->l0 = fma(C, l0, S * l1);
    if (!l0_only)
        p->l1 = fma(C, l1, -(S * l0));
}

/* The relabelling as the lanes read it, one number per quantity: the
   rates a, c_A, c_B and a code +-(1 + the middle axis), negative when A
   comes after the middle axis (det P = -1). The world keeps these for its
   bodies (tb__lane_frame_of); the other callers' lanes work them out from
   invI first, in a loop of their own. */
TB__LANE void frame_put(const double invI[3], double *a, double *ca, double *cb, double *code)
{
    tb__relabel r;
    relabel_of(invI, &r);
    *a = r.a;
    *ca = r.ca;
    *cb = r.cb;
    *code = r.up_a ? (r.mid1 ? -2.0 : r.mid0 ? -1.0 : -3.0) : (r.mid1 ? 2.0 : r.mid0 ? 1.0 : 3.0);
}

void tb__lane_frame_of(const double invI[3], double *a, double *ca, double *cb, double *code)
{
    frame_put(invI, a, ca, cb, code);
}

/* Bodies in lanes for the splitting kernels, one array per quantity. The
   lanes leave q alone until the last piece: they compose the step's turns
   into one quaternion T in the relabelled body frame (each turn on the
   right, as it would turn q) and then set q <- q T. The turn about the
   world L, on the left of q, is the turn about L_b on the right. */
typedef struct tb__spin_lanes {
    double w[TB__LANES], x[TB__LANES], y[TB__LANES], z[TB__LANES]; /* T */
    double l0[TB__LANES], l1[TB__LANES], l2[TB__LANES];             /* L_b, relabelled */
    double ka[TB__LANES], kb[TB__LANES]; /* half angle per unit L_A, L_B */
    double k[TB__LANES], u[TB__LANES];   /* the turn about L: k = a h / 2, u = (k |L|)^2 */
    double sinc[TB__LANES];              /* ... and sin(x) / x of its half angle x */
    double big[TB__LANES];               /* largest squared half angle so far */
    double q[4][TB__LANES];              /* q at the start */
    double code[TB__LANES];              /* the relabelling (frame_put) */
} tb__spin_lanes;

/* A composition in lanes runs piece by piece: each piece is one loop over
   all lanes (GCC vectorises the fixed-length one; the other serves a
   partial block, or one body, with the same arithmetic), so the lanes'
   chains of dependent turns overlap instead of one waiting for the last:
   a whole composition per loop iteration would be too long for the
   processor to look past. Between pieces the lanes stay in L1. A partial
   block of a multiple of TB__GROUP lanes runs in groups of that fixed
   length, which GCC vectorises too (a block of any other size is padded
   to one: split_block). */
#define TB__GROUP 8
#define TB__EACH_LANE(i, n, lane)                                          \
    do {                                                                   \
        if ((n) == TB__LANES) {                                            \
            for ((i) = 0; (i) < TB__LANES; ++(i)) {                        \
                lane;                                                      \
            }                                                              \
        } else if ((n) % TB__GROUP == 0) {                                 \
            int g_, j_;                                                    \
            for (g_ = 0; g_ < (n); g_ += TB__GROUP)                        \
                for (j_ = 0; j_ < TB__GROUP; ++j_) {                       \
                    (i) = g_ + j_;                                         \
                    lane;                                                  \
                }                                                          \
        } else {                                                           \
            for ((i) = 0; (i) < (n); ++(i)) {                              \
                lane;                                                      \
            }                                                              \
        }                                                                  \
    } while (0)

TB__LANE void spin_get(const tb__spin_lanes *lanes, int i, tb__spin *p)
{
    p->w = lanes->w[i], p->x = lanes->x[i], p->y = lanes->y[i], p->z = lanes->z[i];
    p->l0 = lanes->l0[i], p->l1 = lanes->l1[i], p->l2 = lanes->l2[i];
}

TB__LANE void spin_put(tb__spin_lanes *lanes, int i, const tb__spin *p)
{
    lanes->w[i] = p->w, lanes->x[i] = p->x, lanes->y[i] = p->y, lanes->z[i] = p->z;
    lanes->l0[i] = p->l0, lanes->l1[i] = p->l1, lanes->l2[i] = p->l2;
}

/* The relabelling's selects from its code. */
TB__LANE void code_masks(double code, int *mid0, int *mid1, int *up_a)
{
    const double m = fabs(code);
    *mid0 = m == 1;
    *mid1 = m == 2;
    *up_a = code < 0;
}

/* The first piece, straight from the world's arrays: body i relabelled by
   its frame (fa, fca, fcb, fcode: frame_put), its q kept, its L_b from
   q and L. hh = h / 2; ha multiplies c_A (the composition's coefficients
   for A then need no multiplication of their own when all are equal). big
   starts at the turn about L's own u: an isotropic body starts with
   HUGE_VAL, as the lanes do not finish it (tb__rotation_isotropic is its
   kernel). */
TB__LANE void lane_load(tb__spin_lanes *lanes, int i, const double *q, const double *L, const double *fa,
                        const double *fca, const double *fcb, const double *fcode, double hh, double ha)
{
    const double code = fcode[i], ca = fca[i], k = hh * fa[i];
    double qi[4], li[3], lb[3], lr[3], u;
    int mid0, mid1, up_a;
    code_masks(code, &mid0, &mid1, &up_a);
    qi[0] = q[4 * i], qi[1] = q[4 * i + 1], qi[2] = q[4 * i + 2], qi[3] = q[4 * i + 3];
    li[0] = L[3 * i], li[1] = L[3 * i + 1], li[2] = L[3 * i + 2];
    lanes->q[0][i] = qi[0], lanes->q[1][i] = qi[1], lanes->q[2][i] = qi[2], lanes->q[3][i] = qi[3];
    to_body(qi, li, lb);
    relabel_in(mid0, mid1, up_a, lb, lr);
    lanes->ka[i] = ha * ca;
    lanes->kb[i] = hh * fcb[i];
    lanes->k[i] = k;
    u = k * k * (li[0] * li[0] + li[1] * li[1] + li[2] * li[2]);
    lanes->u[i] = u;
    lanes->l0[i] = lr[0], lanes->l1[i] = lr[1], lanes->l2[i] = lr[2];
    lanes->big[i] = ca == 0 ? HUGE_VAL : u; /* ca = 0: isotropic (|ca| >= |cb|) */
    lanes->code[i] = code;
}

/* Then T = the turn about L_b by the angle a h |L|: a loop of its own, as
   one with the piece above holds too many numbers for the registers. A turn
   beyond the polynomial (or not finite) has marked the lane to be redone
   (big). */
TB__LANE void lane_begin(tb__spin_lanes *lanes, int i)
{
    const double k = lanes->k[i], u = lanes->u[i];
    double sinc, c;
    sinc_cos4(u, &sinc, &c);
    lanes->sinc[i] = sinc;
    sinc *= k;
    lanes->w[i] = c, lanes->x[i] = sinc * lanes->l0[i], lanes->y[i] = sinc * lanes->l1[i];
    lanes->z[i] = sinc * lanes->l2[i];
}

/* The exact flow of c_A L_A^2 / 2 over the time g h is a turn about axis A
   by g h c_A L_A: with ka = h c_A / 2 the half angle is g ka L_A (B: the
   same with kb and L_B). The lanes take every angle to the polynomial and
   note the largest square (the polynomial's own x^2): a lane that went
   beyond it is redone afterwards. A NaN never replaces big, as a NaN big
   (from the turn about L) stays. */
TB__LANE double lane_angle(tb__spin_lanes *lanes, int i, double x)
{
    const double u = x * x, big = lanes->big[i];
    lanes->big[i] = u > big ? u : big;
    return x;
}

TB__LANE void lane_a(tb__spin_lanes *lanes, int i, double g)
{
    tb__spin p;
    double s, c;
    spin_get(lanes, i, &p);
    sincos4(lane_angle(lanes, i, (g * lanes->ka[i]) * p.l0), &s, &c);
    turn_a(&p, s, c, 0);
    spin_put(lanes, i, &p);
}

TB__LANE void lane_b(tb__spin_lanes *lanes, int i, double g, int l0_only)
{
    tb__spin p;
    double s, c;
    spin_get(lanes, i, &p);
    sincos4(lane_angle(lanes, i, (g * lanes->kb[i]) * p.l2), &s, &c);
    turn_b(&p, s, c, l0_only);
    spin_put(lanes, i, &p);
}

/* The last piece, into the world's array: the last turn about A, T back
   in the body's own axes, q <- q T and the Newton step. */
TB__LANE double lane_end(tb__spin_lanes *lanes, int i, double g, double *q)
{
    tb__spin p;
    double s, c, t[4], qi[4];
    int mid0, mid1, up_a;
    spin_get(lanes, i, &p);
    sincos4(lane_angle(lanes, i, (g * lanes->ka[i]) * p.l0), &s, &c);
    turn_a(&p, s, c, 1);
    t[0] = p.w;
    code_masks(lanes->code[i], &mid0, &mid1, &up_a);
    {
        const double tr[3] = { p.x, p.y, p.z };
        relabel_out(mid0, mid1, up_a, tr, t + 1);
    }
    qi[0] = lanes->q[0][i], qi[1] = lanes->q[1][i], qi[2] = lanes->q[2][i], qi[3] = lanes->q[3][i];
    qmul(qi, t, t);
    newton(t, t);
    q[4 * i] = t[0], q[4 * i + 1] = t[1], q[4 * i + 2] = t[2], q[4 * i + 3] = t[3];
    return lanes->big[i];
}

/* Any composition A(ga[0]) B(gb[0]) A(ga[1]) ... B(gb[n-2]) A(ga[n-1]) of
   one body that the lanes cannot take: turns beyond the polynomials (libm
   for those), or a q off unit length (the full normalisation). The same
   rotations as the lanes, the plain way: q and L relabelled, q turned
   itself. */
TB__LANE void sincos_any(double x, double *s, double *c)
{
    if (fabs(x) <= TB__SMALL) {
        sincos4(x, s, c);
    } else {
        *s = sin(x);
        *c = cos(x);
    }
}

TB__LANE void split_any(double q[4], const double L[3], const tb__split_frame *f, double h, const double *ga,
                        const double *gb, int n)
{
    const double sign = f->sign, ka = 0.5 * h * f->ca, kb = 0.5 * h * f->cb, k = 0.5 * h * f->a;
    double r[4], lb[3], Lr[3], qr[4];
    tb__spin p;
    int i;
    qr[0] = q[0];
    for (i = 0; i < 3; ++i) {
        qr[1 + i] = sign * q[1 + f->ax[i]];
        Lr[i] = sign * L[f->ax[i]];
    }
    to_body(qr, Lr, lb);
    half_turn(k * k * (Lr[0] * Lr[0] + Lr[1] * Lr[1] + Lr[2] * Lr[2]), k, Lr, r);
    qmul(r, qr, r);
    p.w = r[0], p.x = r[1], p.y = r[2], p.z = r[3];
    p.l0 = lb[0], p.l1 = lb[1], p.l2 = lb[2];
    for (i = 0; i < n; ++i) {
        double s, c;
        sincos_any(ga[i] * ka * p.l0, &s, &c);
        turn_a(&p, s, c, i == n - 1);
        if (i == n - 1)
            break;
        sincos_any(gb[i] * kb * p.l2, &s, &c);
        turn_b(&p, s, c, 0);
    }
    r[0] = p.w;
    r[1 + f->ax[0]] = sign * p.x;
    r[1 + f->ax[1]] = sign * p.y;
    r[1 + f->ax[2]] = sign * p.z;
    normalize(r, q);
}

static const double tb__strang_a[2] = { 0.5, 0.5 };
static const double tb__strang_b[1] = { 1.0 };
static const double tb__bm_a[7] = { TB__BM_A1, TB__BM_A2, TB__BM_A3, TB__BM_A4,
                                    TB__BM_A3, TB__BM_A2, TB__BM_A1 };
static const double tb__bm_b[6] = { TB__BM_B1, TB__BM_B2, TB__BM_B3,
                                    TB__BM_B3, TB__BM_B2, TB__BM_B1 };

/* One body the general way: an isotropic one by its own kernel (exact,
   and what the lanes send it to, whatever the method), any other by
   split_any. */
TB__LANE void split_general(double q[4], const double L[3], const double invI[3], double h, int accurate)
{
    tb__split_frame f;
    tb__split_frame_of(invI, &f);
    if (f.isotropic)
        isotropic_one(q, L, invI[0], h);
    else if (accurate)
        split_any(q, L, &f, h, tb__bm_a, tb__bm_b, 7);
    else
        split_any(q, L, &f, h, tb__strang_a, tb__strang_b, 2);
}

/* The lanes that the polynomials did not serve, or that are isotropic,
   again from their q at the start, the general way. Rare: at h = 1/60 s it
   takes a body spinning at 30 rad/s relative to its turn about L (60
   about A), or an isotropic body among others. */
TB__LANE void lanes_redo(double *q, const double *L, const double *invI, double h, int n, int accurate,
                         const tb__spin_lanes *lanes)
{
    int i, k;
    for (i = 0; i < n; ++i)
        if (!(lanes->big[i] <= TB__SMALL * TB__SMALL)) {
            for (k = 0; k < 4; ++k)
                q[4 * i + k] = lanes->q[k][i];
            split_general(q + 4 * i, L + 3 * i, invI + 3 * i, h, accurate);
        }
}

/* ----------------------------------------------------------- compositions -- */

/* A block's frames: f[0..3][i] = a, c_A, c_B, code of body i (pointers at
   the block). */
TB__LANE void split2_lanes_t(double *restrict q, const double *restrict L, const double *restrict invI,
                             const double *restrict fa, const double *restrict fca, const double *restrict fcb,
                             const double *restrict fcode, double h, int n)
{
    tb__spin_lanes p;
    const double hh = 0.5 * h;
    double redo = 0; /* 1: some lane is to be redone (a double: every instruction set vectorises this) */
    int i;
    /* A(h/2) B(h) A(h/2), the turn about L (which commutes) in the first
       piece; B's turn of L_b,1 is left out: the last A reads L_b,0 alone.
       ka is h/2 c_A / 2 = h c_A / 4 (the halving is exact), so both A
       turns take g = 1, which costs nothing. */
    TB__EACH_LANE(i, n, lane_load(&p, i, q, L, fa, fca, fcb, fcode, hh, 0.5 * hh));
    TB__EACH_LANE(i, n, lane_begin(&p, i));
    TB__EACH_LANE(i, n, lane_a(&p, i, 1.0));
    TB__EACH_LANE(i, n, lane_b(&p, i, 1.0, 1));
    TB__EACH_LANE(i, n, redo = lane_end(&p, i, 1.0, q) <= TB__SMALL * TB__SMALL ? redo : 1);
    if (redo != 0)
        lanes_redo(q, L, invI, h, n, 0, &p);
}

TB__LANE void accurate_lanes_t(double *restrict q, const double *restrict L, const double *restrict invI,
                               const double *restrict fa, const double *restrict fca,
                               const double *restrict fcb, const double *restrict fcode, double h, int n)
{
    tb__spin_lanes p;
    const double hh = 0.5 * h;
    double redo = 0; /* 1: some lane is to be redone (a double: every instruction set vectorises this) */
    int i, j;
    TB__EACH_LANE(i, n, lane_load(&p, i, q, L, fa, fca, fcb, fcode, hh, hh));
    TB__EACH_LANE(i, n, lane_begin(&p, i));
    for (j = 0; j < 6; ++j) { /* the loops of fixed length inside are what count */
        const double ga = tb__bm_a[j], gb = tb__bm_b[j];
        TB__EACH_LANE(i, n, lane_a(&p, i, ga));
        TB__EACH_LANE(i, n, lane_b(&p, i, gb, 0));
    }
    TB__EACH_LANE(i, n, redo = lane_end(&p, i, TB__BM_A1, q) <= TB__SMALL * TB__SMALL ? redo : 1);
    if (redo != 0)
        lanes_redo(q, L, invI, h, n, 1, &p);
}

/* A splitting kernel for a block of n bodies with their frames (f, or
   NULL: from invI, in a loop of its own). A block of more than one body
   and of no multiple of TB__GROUP is padded to the next one with copies of
   its first body: every lane does the arithmetic of one body whatever its
   neighbours, so the real lanes get the same bits. */
TB__LANE void split_unpadded(double *restrict q, const double *restrict L, const double *restrict invI,
                             const tb__lane_frames *f, double h, int n, int accurate)
{
    double frame[4][TB__LANES];
    int i;
    if (!f) {
        TB__EACH_LANE(i, n, frame_put(invI + 3 * i, &frame[0][i], &frame[1][i], &frame[2][i], &frame[3][i]));
        if (accurate)
            accurate_lanes_t(q, L, invI, frame[0], frame[1], frame[2], frame[3], h, n);
        else
            split2_lanes_t(q, L, invI, frame[0], frame[1], frame[2], frame[3], h, n);
    } else if (accurate) {
        accurate_lanes_t(q, L, invI, f->a, f->ca, f->cb, f->code, h, n);
    } else {
        split2_lanes_t(q, L, invI, f->a, f->ca, f->cb, f->code, h, n);
    }
}

TB__LANE void split_block(double *restrict q, const double *restrict L, const double *restrict invI,
                          const tb__lane_frames *f, double h, int n, int accurate)
{
    int i;
    if (n > 1 && n % TB__GROUP != 0) {
        const int m = (n / TB__GROUP + 1) * TB__GROUP;
        double qp[4 * TB__LANES], Lp[3 * TB__LANES], ip[3 * TB__LANES], fp[4][TB__LANES];
        tb__lane_frames padded;
        int k;
        for (i = 0; i < m; ++i) {
            const int from = i < n ? i : 0;
            for (k = 0; k < 4; ++k)
                qp[4 * i + k] = q[4 * from + k];
            for (k = 0; k < 3; ++k) {
                Lp[3 * i + k] = L[3 * from + k];
                ip[3 * i + k] = invI[3 * from + k];
            }
            if (f)
                fp[0][i] = f->a[from], fp[1][i] = f->ca[from], fp[2][i] = f->cb[from], fp[3][i] = f->code[from];
        }
        padded.a = fp[0], padded.ca = fp[1], padded.cb = fp[2], padded.code = fp[3];
        split_unpadded(qp, Lp, ip, f ? &padded : NULL, h, m, accurate);
        for (i = 0; i < 4 * n; ++i)
            q[i] = qp[i];
    } else {
        split_unpadded(q, L, invI, f, h, n, accurate);
    }
}

/* ------------------------------------------------ instruction sets -- */

/* The lanes kernels are compiled once for each instruction set (the same C
   through the templates above) and chosen at run time. Contraction stays
   off (-ffp-contract=off, and C99 mode's default): every variant does the
   same IEEE operations in the same order, so all give the same bits
   (test_rotation.lanes_give_the_one_body_bits), and the wider ones only do
   more lanes per instruction. */
#define TB__KERNELS(isa, attr, id)                                                                    \
    attr static void isotropic_##isa(double *q, const double *L, const double *invI, double h, int n) \
    {                                                                                                 \
        isotropic_lanes_t(q, L, invI, h, n);                                                          \
    }                                                                                                 \
    attr static void frozen_##isa(double *q, const double *L, const double *invI, double h, int n)    \
    {                                                                                                 \
        frozen_lanes_t(q, L, invI, h, n);                                                             \
    }                                                                                                 \
    attr static void split2_##isa(double *q, const double *L, const double *invI,                     \
                                  const tb__lane_frames *f, double h, int n)                          \
    {                                                                                                 \
        split_block(q, L, invI, f, h, n, 0);                                                          \
    }                                                                                                 \
    attr static void accurate_##isa(double *q, const double *L, const double *invI,                   \
                                    const tb__lane_frames *f, double h, int n)                        \
    {                                                                                                 \
        split_block(q, L, invI, f, h, n, 1);                                                          \
    }                                                                                                 \
    attr static void one_frozen_##isa(double *q, const double *L, const double *invI, double h)       \
    {                                                                                                 \
        frozen_one(q, L, invI, h);                                                                    \
    }                                                                                                 \
    attr static void one_isotropic_##isa(double *q, const double *L, double inv, double h)            \
    {                                                                                                 \
        isotropic_one(q, L, inv, h);                                                                  \
    }                                                                                                 \
    attr static void one_general_##isa(double *q, const double *L, const double *invI, double h,      \
                                       int accurate)                                                  \
    {                                                                                                 \
        split_general(q, L, invI, h, accurate);                                                       \
    }

TB__FOR_EACH_ISA(TB__KERNELS)

void tb__isotropic_lanes(double *q, const double *L, const double *invI, double h, int n, int isa)
{
    TB__DISPATCH(isa, isotropic, (q, L, invI, h, n));
}

void tb__frozen_lanes(double *q, const double *L, const double *invI, double h, int n, int isa)
{
    TB__DISPATCH(isa, frozen, (q, L, invI, h, n));
}

void tb__split2_lanes(double *q, const double *L, const double *invI, double h, int n, int isa)
{
    TB__DISPATCH(isa, split2, (q, L, invI, NULL, h, n));
}

void tb__accurate_lanes(double *q, const double *L, const double *invI, double h, int n, int isa)
{
    TB__DISPATCH(isa, accurate, (q, L, invI, NULL, h, n));
}

void tb__split2_lanes_framed(double *q, const double *L, const double *invI, const tb__lane_frames *frame, double h,
                             int n, int isa)
{
    TB__DISPATCH(isa, split2, (q, L, invI, frame, h, n));
}

void tb__accurate_lanes_framed(double *q, const double *L, const double *invI, const tb__lane_frames *frame,
                               double h, int n, int isa)
{
    TB__DISPATCH(isa, accurate, (q, L, invI, frame, h, n));
}

/* --------------------------------------------------------- one body -- */

/* One body by the lanes code (so it gets the bits it would get in a
   block), or the general way for a q off unit length. */

/* A q off unit length (a careless caller; never the world's) goes the
   general way, for its full normalisation. */
#define TB__NEAR_UNIT(q) (fabs(norm2(q) - 1) <= 5e-9)

void tb__rotation_split2(double q[4], const double L[3], const double invI[3], double h)
{
    const int isa = tb__isa();
    if (TB__NEAR_UNIT(q))
        TB__DISPATCH(isa, split2, (q, L, invI, NULL, h, 1));
    else
        TB__DISPATCH(isa, one_general, (q, L, invI, h, 0));
}

void tb__rotation_accurate(double q[4], const double L[3], const double invI[3], double h)
{
    const int isa = tb__isa();
    if (TB__NEAR_UNIT(q))
        TB__DISPATCH(isa, accurate, (q, L, invI, NULL, h, 1));
    else
        TB__DISPATCH(isa, one_general, (q, L, invI, h, 1));
}

void tb__rotation_frozen(double q[4], const double L[3], const double invI[3], double h)
{
    const int isa = tb__isa();
    TB__DISPATCH(isa, one_frozen, (q, L, invI, h));
}

void tb__rotation_isotropic(double q[4], const double L[3], double inv_inertia, double h)
{
    const int isa = tb__isa();
    TB__DISPATCH(isa, one_isotropic, (q, L, inv_inertia, h));
}
