/* rotation.c: torque-free rotation kernels (see rotation.h for the model).

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
   body. Fasso (2003) found this splitting more accurate than splitting into
   three axis rotations; on the flip of NOTES.md at h = 1/60 its Strang step
   is 4 times closer to the exact orientation than the best order of
   R1 R2 R3 R2 R1 (1.7e-4 against 6.7e-4 rad), with 3 axis turns a step
   instead of 5. The outer axis with the larger |c| is A, the one turned
   more often: better than the other way round on every body tried (about 2
   times for the 4th-order compositions).

   Choosing the accurate method: measured on the flip (h = 1/60, 20 s;
   orientation error after 20 s, worst relative energy error over the run,
   ns per step over 1024 bodies on this project's 2-core x86-64, gcc -O2,
   +-15% run to run), all built from the same exact pieces:
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
   The cost is the chain of turns: each needs the momentum the previous one
   left, about 16 ns a turn here, so no composition reaching 1e-6 rad fits
   in 50 ns. Yoshida + projection meets the flip's targets (1e-6 rad, energy
   1e-9) at 2/3 of S6's cost but with a margin of 2 and errors up to 1.4e-4
   rad on other bodies; S6 meets them with margins of 1300 and 9, stays
   within 2.7e-7 rad on every other body tried (12 random bodies at up to 9
   rad/s), and unlike a projected method it stays symplectic and
   time-reversible.

   The kernels relabel the body axes so that A, the middle axis and B become
   axes 0, 1, 2 (a permutation P of the body and world axes alike: the
   relabelled body obeys the same equations, with q's vector part, L and L_b
   multiplied by det P when P is odd), so one straight-line body of code
   serves every order of moments. Turns are computed in the body frame from
   L_b and composed on the right of q (q <- q r); the turn about the world L
   is composed on the left. */
#include "rotation.h"

#include <math.h>

/* ------------------------------------------------ small-angle trigonometry -- */

/* sin x and cos x for |x| <= 1/8 from their Taylor series in u = x^2, through
   x^9 and x^10. The first terms left out, x^11/11! and x^12/12!, are at most
   2.3e-17 of sin x and 1.2e-19 of cos x there: the results are as good as a
   correctly rounded libm's, and no sqrt or range reduction is needed. */
#define TB__SMALL_HALF 0.125

static inline void tb__sincos8(double x, double *s, double *c)
{
    const double u = x * x, u2 = u * u, u4 = u2 * u2;
    /* Estrin's scheme: the same polynomials in fewer dependent steps */
    *s = x + x * u * ((-1.0 / 6 + u * (1.0 / 120)) + u2 * (-1.0 / 5040 + u * (1.0 / 362880)));
    *c = (1 + u * (-1.0 / 2)) + u2 * (1.0 / 24 + u * (-1.0 / 720))
         + u4 * (1.0 / 40320 + u * (-1.0 / 3628800));
}

/* sin(x) / x and cos x from u = x^2 <= 1/16 (|x| <= 1/4), through x^12: the
   first terms left out, x^14/15! and x^14/14!, are below 1e-19. */
#define TB__SMALL_WHOLE 0.25

static inline void tb__sinc_cos4(double u, double *sinc, double *c)
{
    *sinc = 1 + u * (-1.0 / 6 + u * (1.0 / 120 + u * (-1.0 / 5040 + u * (1.0 / 362880
            + u * (-1.0 / 39916800 + u * (1.0 / 6227020800.0))))));
    *c = 1 + u * (-1.0 / 2 + u * (1.0 / 24 + u * (-1.0 / 720 + u * (1.0 / 40320
         + u * (-1.0 / 3628800 + u * (1.0 / 479001600.0))))));
}

/* The quaternion (cos x, (sin x / x) k v) of a rotation by 2 x about v, for
   x^2 = k^2 |v|^2 = u. The polynomial path needs no sqrt; angles 2 x above
   1/2 rad go to libm, out of line. */
static void tb__half_turn_big(double u, double k, const double v[3], double r[4])
{
    const double x = sqrt(u);
    const double f = sin(x) / x * k;
    r[0] = cos(x);
    r[1] = f * v[0];
    r[2] = f * v[1];
    r[3] = f * v[2];
}

static inline void tb__half_turn(double u, double k, const double v[3], double r[4])
{
    double sinc, c;
    if (u > TB__SMALL_WHOLE * TB__SMALL_WHOLE) {
        tb__half_turn_big(u, k, v, r);
        return;
    }
    tb__sinc_cos4(u, &sinc, &c);
    sinc *= k;
    r[0] = c;
    r[1] = sinc * v[0];
    r[2] = sinc * v[1];
    r[3] = sinc * v[2];
}

/* ------------------------------------------------------ quaternion algebra -- */

/* v_b = R(q)^T v: v + 2 w (p x v) + 2 p x (p x v) with p = -(x, y, z). */
static inline void tb__to_body(const double q[4], const double v[3], double out[3])
{
    const double w = q[0], x = -q[1], y = -q[2], z = -q[3];
    const double tx = 2 * (y * v[2] - z * v[1]);
    const double ty = 2 * (z * v[0] - x * v[2]);
    const double tz = 2 * (x * v[1] - y * v[0]);
    out[0] = v[0] + w * tx + (y * tz - z * ty);
    out[1] = v[1] + w * ty + (z * tx - x * tz);
    out[2] = v[2] + w * tz + (x * ty - y * tx);
}

/* out = a b (Hamilton product). out may be a or b. */
static inline void tb__qmul(const double a[4], const double b[4], double out[4])
{
    const double w = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    const double x = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    const double y = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    const double z = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
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
static inline void tb__normalize(const double in[4], double q[4])
{
    const double n2 = in[0] * in[0] + in[1] * in[1] + in[2] * in[2] + in[3] * in[3];
    const double f = fabs(n2 - 1) <= 1e-8 ? 1.5 - 0.5 * n2 : 1 / sqrt(n2);
    q[0] = in[0] * f;
    q[1] = in[1] * f;
    q[2] = in[2] * f;
    q[3] = in[3] * f;
}

/* ----------------------------------------------------------------- frozen -- */

/* q <- q exp(h w_b / 2), the same rotation as exp(h w / 2) q with the world
   w = R w_b, without going back to the world frame. */
void tb__rotation_frozen(double q[4], const double L[3], const double invI[3], double h)
{
    double lb[3], w[3], r[4];
    const double k = 0.5 * h;
    tb__to_body(q, L, lb);
    w[0] = invI[0] * lb[0];
    w[1] = invI[1] * lb[1];
    w[2] = invI[2] * lb[2];
    tb__half_turn(k * k * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]), k, w, r);
    tb__qmul(q, r, r);
    tb__normalize(r, q);
}

void tb__rotation_isotropic(double q[4], const double L[3], double inv_inertia, double h)
{
    double w[3], r[4];
    const double k = 0.5 * h;
    w[0] = inv_inertia * L[0];
    w[1] = inv_inertia * L[1];
    w[2] = inv_inertia * L[2];
    tb__half_turn(k * k * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]), k, w, r);
    tb__qmul(r, q, r); /* w is a world vector: turn on the left */
    tb__normalize(r, q);
}

/* -------------------------------------------------------------- splitting -- */

/* The state a composition works on: q and L_b in the relabelled axes. */
typedef struct tb__spin {
    double w, x, y, z;  /* q */
    double l0, l1, l2;  /* L_b, kg m^2/s */
} tb__spin;

/* Turn the body by the angle 2 x about (relabelled) axis 0, for |x| <=
   TB__SMALL_HALF: q <- q (c, s e0) with (c, s) = (cos x, sin x), and
   L_b <- R_0(2x)^T L_b. `last` skips L_b, which the final turn of a step
   leaves unused. */
static inline void tb__turn_a(tb__spin *p, double x, int last)
{
    const double w = p->w, x0 = p->x, y = p->y, z = p->z;
    double s, c;
    tb__sincos8(x, &s, &c);
    p->w = w * c - x0 * s;
    p->x = x0 * c + w * s;
    p->y = y * c + z * s;
    p->z = z * c - y * s;
    if (!last) {
        const double C = 1 - 2 * s * s, S = 2 * s * c, l1 = p->l1, l2 = p->l2;
        p->l1 = C * l1 + S * l2;
        p->l2 = C * l2 - S * l1;
    }
}

/* The same about (relabelled) axis 2: q <- q (c, s e2). */
static inline void tb__turn_b(tb__spin *p, double x)
{
    const double w = p->w, x0 = p->x, y = p->y, z = p->z;
    double s, c, C, S, l0, l1;
    tb__sincos8(x, &s, &c);
    p->w = w * c - z * s;
    p->x = x0 * c + y * s;
    p->y = y * c - x0 * s;
    p->z = z * c + w * s;
    C = 1 - 2 * s * s;
    S = 2 * s * c;
    l0 = p->l0;
    l1 = p->l1;
    p->l0 = C * l0 + S * l1;
    p->l1 = C * l1 - S * l0;
}

/* The exact flow of c_A L_A^2 / 2 over the time g h is a turn about axis A
   by g h c_A L_A: with ka = h c_A / 2 the half angle is g ka L_A. */
#define TB__A(p, g, ka) tb__turn_a(p, ((g) * (ka)) * (p)->l0, 0)
#define TB__A_LAST(p, g, ka) tb__turn_a(p, ((g) * (ka)) * (p)->l0, 1)
#define TB__B(p, g, kb) tb__turn_b(p, ((g) * (kb)) * (p)->l2)

/* Any composition A(ga[0]) B(gb[0]) A(ga[1]) ... B(gb[n-2]) A(ga[n-1]) with
   libm's sin and cos, for turns too large for the polynomials: taken when
   max |c| |L| h exceeds 0.25 rad (split2) or 0.57 rad (accurate), that is
   beyond about 15 or 34 rad/s of relative spin at h = 1/60. Slower (two
   libm calls a turn), otherwise the same. */
static void tb__compose_big(tb__spin *p, const double *ga, const double *gb, int n,
                            double ka, double kb)
{
    int i;
    for (i = 0; i < n; ++i) {
        double w = p->w, x0 = p->x, y = p->y, z = p->z, x, s, c, C, S, l0, l1, l2;
        x = ga[i] * ka * p->l0;
        s = sin(x);
        c = cos(x);
        p->w = w * c - x0 * s;
        p->x = x0 * c + w * s;
        p->y = y * c + z * s;
        p->z = z * c - y * s;
        C = 1 - 2 * s * s;
        S = 2 * s * c;
        l1 = p->l1;
        l2 = p->l2;
        p->l1 = C * l1 + S * l2;
        p->l2 = C * l2 - S * l1;
        if (i == n - 1)
            break;
        w = p->w, x0 = p->x, y = p->y, z = p->z;
        x = gb[i] * kb * p->l2;
        s = sin(x);
        c = cos(x);
        p->w = w * c - z * s;
        p->x = x0 * c + y * s;
        p->y = y * c - x0 * s;
        p->z = z * c + w * s;
        C = 1 - 2 * s * s;
        S = 2 * s * c;
        l0 = p->l0;
        l1 = p->l1;
        p->l0 = C * l0 + S * l1;
        p->l1 = C * l1 - S * l0;
    }
}

/* What a splitting kernel needs besides the composition itself. */
typedef struct tb__frame {
    int ax[3];      /* relabelled axis n is the body's axis ax[n] */
    double sign;    /* det P: -1 when the relabelling is an odd permutation */
    double ka, kb;  /* h c_A / 2, h c_B / 2: half angle per unit momentum of a full step */
    int fast;       /* every turn of the composition is small enough for tb__sincos8 */
} tb__frame;

/* Relabel (A, middle, B) -> (0, 1, 2), turn q about the world L by a h |L|,
   and load the relabelled q and L_b. `reach` bounds the composition's
   coefficients g (|angle| <= reach |h c| |L_b,i|) for the choice of the
   polynomial path; the check uses |L| >= |L_b,i|, so it needs no sqrt. */
static void tb__split_begin(tb__frame *f, tb__spin *p, const double q[4], const double L[3],
                            const double invI[3], double h, double reach)
{
    double lb[3], r[4], a, ca, cb, bound;
    int m, up, down;
    /* the middle moment (ties: any of the equal ones) */
    if ((invI[0] <= invI[1] && invI[1] <= invI[2]) || (invI[2] <= invI[1] && invI[1] <= invI[0]))
        m = 1;
    else if ((invI[1] <= invI[0] && invI[0] <= invI[2]) || (invI[2] <= invI[0] && invI[0] <= invI[1]))
        m = 0;
    else
        m = 2;
    a = invI[m];
    up = m == 2 ? 0 : m + 1;
    down = m == 0 ? 2 : m - 1;
    /* A = the outer axis with the larger |c|. (up, m, down) is an odd
       permutation of (0, 1, 2) for every m, (down, m, up) an even one. */
    if (fabs(invI[up] - a) > fabs(invI[down] - a)) {
        f->ax[0] = up;
        f->ax[2] = down;
        f->sign = -1;
    } else {
        f->ax[0] = down;
        f->ax[2] = up;
        f->sign = 1;
    }
    f->ax[1] = m;
    ca = invI[f->ax[0]] - a;
    cb = invI[f->ax[2]] - a;
    f->ka = 0.5 * h * ca;
    f->kb = 0.5 * h * cb;
    bound = 0.5 * reach * h * (fabs(ca) > fabs(cb) ? ca : cb); /* |c_A| >= |c_B| but for rounding */
    f->fast = bound * bound * (L[0] * L[0] + L[1] * L[1] + L[2] * L[2])
              <= TB__SMALL_HALF * TB__SMALL_HALF;

    /* L_b from the q of the start: the turn about L leaves it unchanged */
    tb__to_body(q, L, lb);
    {
        const double k = 0.5 * a * h;
        tb__half_turn(k * k * (L[0] * L[0] + L[1] * L[1] + L[2] * L[2]), k, L, r);
        tb__qmul(r, q, r); /* world frame: on the left */
    }
    p->w = r[0];
    p->x = f->sign * r[1 + f->ax[0]];
    p->y = f->sign * r[1 + f->ax[1]];
    p->z = f->sign * r[1 + f->ax[2]];
    p->l0 = f->sign * lb[f->ax[0]];
    p->l1 = f->sign * lb[f->ax[1]];
    p->l2 = f->sign * lb[f->ax[2]];
}

static void tb__split_end(const tb__frame *f, const tb__spin *p, double q[4])
{
    double r[4];
    r[0] = p->w;
    r[1 + f->ax[0]] = f->sign * p->x;
    r[1 + f->ax[1]] = f->sign * p->y;
    r[1 + f->ax[2]] = f->sign * p->z;
    tb__normalize(r, q);
}

/* ----------------------------------------------------------------- split2 -- */

static const double tb__strang_a[2] = { 0.5, 0.5 };
static const double tb__strang_b[1] = { 1.0 };

void tb__rotation_split2(double q[4], const double L[3], const double invI[3], double h)
{
    tb__frame f;
    tb__spin p;
    tb__split_begin(&f, &p, q, L, invI, h, 1.0);
    if (f.fast) {
        TB__A(&p, 0.5, f.ka);
        TB__B(&p, 1.0, f.kb);
        TB__A_LAST(&p, 0.5, f.ka);
    } else {
        tb__compose_big(&p, tb__strang_a, tb__strang_b, 2, f.ka, f.kb);
    }
    tb__split_end(&f, &p, q);
}

/* --------------------------------------------------------------- accurate -- */

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
#define TB__BM_REACH 0.44

static const double tb__bm_a[7] = { TB__BM_A1, TB__BM_A2, TB__BM_A3, TB__BM_A4,
                                    TB__BM_A3, TB__BM_A2, TB__BM_A1 };
static const double tb__bm_b[6] = { TB__BM_B1, TB__BM_B2, TB__BM_B3,
                                    TB__BM_B3, TB__BM_B2, TB__BM_B1 };

void tb__rotation_accurate(double q[4], const double L[3], const double invI[3], double h)
{
    tb__frame f;
    tb__spin p;
    tb__split_begin(&f, &p, q, L, invI, h, TB__BM_REACH);
    if (f.fast) {
        TB__A(&p, TB__BM_A1, f.ka);
        TB__B(&p, TB__BM_B1, f.kb);
        TB__A(&p, TB__BM_A2, f.ka);
        TB__B(&p, TB__BM_B2, f.kb);
        TB__A(&p, TB__BM_A3, f.ka);
        TB__B(&p, TB__BM_B3, f.kb);
        TB__A(&p, TB__BM_A4, f.ka);
        TB__B(&p, TB__BM_B3, f.kb);
        TB__A(&p, TB__BM_A3, f.ka);
        TB__B(&p, TB__BM_B2, f.kb);
        TB__A(&p, TB__BM_A2, f.ka);
        TB__B(&p, TB__BM_B1, f.kb);
        TB__A_LAST(&p, TB__BM_A1, f.ka);
    } else {
        tb__compose_big(&p, tb__bm_a, tb__bm_b, 7, f.ka, f.kb);
    }
    tb__split_end(&f, &p, q);
}
