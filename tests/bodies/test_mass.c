/* test_mass.c: mass properties (tb_mass_*) against closed forms, against
   ODE's dMassSet* functions, and against the exact geometry of meshes.

   Most bounds are rounding bounds: a closed form evaluated two ways, each a
   product or sum of at most about ten correctly rounded operations, differs
   by at most about 10 eps = 2.2e-15 relative, so 1e-14 fails on any wrong
   coefficient yet never on rounding. Looser bounds say why where they are. */
#include "test_main.h"
#include "tumble.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <ode/ode.h>

/* dDOUBLE is the Debian header default; the comparison is meaningless in
   single precision. A negative array size stops the build otherwise. */
typedef char dreal_is_double[sizeof(dReal) == sizeof(double) ? 1 : -1];

static const double PI = 3.14159265358979323846;

/* Rounding of closed forms evaluated in two orders (see the top). */
#define FORM_TOL 1e-14

static double rel(double a, double b)
{
    return fabs(a - b) / fabs(b);
}

/* ---- rotations and tensors ---------------------------------------------------- */

/* Rotation matrix (row-major) of the unit quaternion q = (w, x, y, z). */
static void matrix_of(const double q[4], double r[9])
{
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    r[0] = 1 - 2 * (y * y + z * z);
    r[1] = 2 * (x * y - w * z);
    r[2] = 2 * (x * z + w * y);
    r[3] = 2 * (x * y + w * z);
    r[4] = 1 - 2 * (x * x + z * z);
    r[5] = 2 * (y * z - w * x);
    r[6] = 2 * (x * z - w * y);
    r[7] = 2 * (y * z + w * x);
    r[8] = 1 - 2 * (x * x + y * y);
}

/* A fixed, generic rotation: no axis of it is near a coordinate axis. */
static void test_rotation(double r[9])
{
    const double n = sqrt(1.0 + 4 + 9 + 16);
    const double q[4] = { 1 / n, 2 / n, -3 / n, 4 / n };
    matrix_of(q, r);
}

static void rotate(const double r[9], const double v[3], double out[3])
{
    int i;
    for (i = 0; i < 3; ++i)
        out[i] = r[3 * i] * v[0] + r[3 * i + 1] * v[1] + r[3 * i + 2] * v[2];
}

/* t = R diag(d) R^T */
static void rotated_diagonal(const double r[9], const double d[3], double t[9])
{
    int i, j, k;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            t[3 * i + j] = 0;
            for (k = 0; k < 3; ++k)
                t[3 * i + j] += r[3 * i + k] * d[k] * r[3 * j + k];
        }
}

/* The full tensor a tb_mass stands for: R(frame) diag(inertia) R^T. */
static void tensor_of(const tb_mass *m, double t[9])
{
    double r[9];
    matrix_of(m->frame, r);
    rotated_diagonal(r, m->inertia, t);
}

/* Largest entry difference, relative to the largest entry of b. */
static double tensor_error(const double a[9], const double b[9])
{
    double worst = 0, norm = 0;
    int k;
    for (k = 0; k < 9; ++k) {
        worst = fmax(worst, fabs(a[k] - b[k]));
        norm = fmax(norm, fabs(b[k]));
    }
    return worst / norm;
}

static void sort3(double v[3])
{
    int i, j;
    for (i = 1; i < 3; ++i)
        for (j = i; j > 0 && v[j] < v[j - 1]; --j) {
            const double x = v[j];
            v[j] = v[j - 1];
            v[j - 1] = x;
        }
}

/* A result from a diagonalised tensor: moments ascending, frame a unit
   quaternion with w >= 0 (both as src/bodies/mass.c documents). The norm is a sum
   of four squares, good to a few eps. */
static void assert_principal_form(const tb_mass *m)
{
    const double *q = m->frame;
    assert_true(m->inertia[0] <= m->inertia[1] && m->inertia[1] <= m->inertia[2]);
    assert_below(fabs(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] - 1), 4 * DBL_EPSILON);
    assert_true(q[0] >= 0);
}

static void assert_identity_frame(const tb_mass *m)
{
    assert_true(m->frame[0] == 1 && m->frame[1] == 0 && m->frame[2] == 0 && m->frame[3] == 0);
    assert_true(m->centre[0] == 0 && m->centre[1] == 0 && m->centre[2] == 0);
}

/* ---- closed forms --------------------------------------------------------------- */

static void sphere_matches_closed_form(void **state)
{
    const double rho = 7850, r = 0.13;
    const double m = 4.0 / 3.0 * PI * r * r * r * rho;
    tb_mass out;
    (void)state;
    assert_int_equal(tb_mass_sphere(rho, r, &out, NULL), TB_OK);
    assert_rel(out.mass, m, FORM_TOL);
    assert_rel(out.inertia[0], 2.0 / 5.0 * m * r * r, FORM_TOL);
    assert_true(out.inertia[0] == out.inertia[1] && out.inertia[1] == out.inertia[2]);
    assert_identity_frame(&out);
}

static void box_matches_closed_form(void **state)
{
    const double rho = 920, s[3] = { 0.3, 1.7, 2.9 };
    const double m = rho * s[0] * s[1] * s[2];
    tb_mass out;
    (void)state;
    assert_int_equal(tb_mass_box(rho, s, &out, NULL), TB_OK);
    assert_rel(out.mass, m, FORM_TOL);
    assert_rel(out.inertia[0], m * (s[1] * s[1] + s[2] * s[2]) / 12, FORM_TOL);
    assert_rel(out.inertia[1], m * (s[0] * s[0] + s[2] * s[2]) / 12, FORM_TOL);
    assert_rel(out.inertia[2], m * (s[0] * s[0] + s[1] * s[1]) / 12, FORM_TOL);
    assert_identity_frame(&out);
}

static void cylinder_matches_closed_form(void **state)
{
    const double rho = 2700, r = 0.4, l = 1.9;
    const double m = PI * r * r * l * rho;
    tb_mass out;
    (void)state;
    assert_int_equal(tb_mass_cylinder(rho, r, l, &out, NULL), TB_OK);
    assert_rel(out.mass, m, FORM_TOL);
    assert_rel(out.inertia[0], m * (3 * r * r + l * l) / 12, FORM_TOL);
    assert_rel(out.inertia[1], m * (3 * r * r + l * l) / 12, FORM_TOL);
    assert_rel(out.inertia[2], m * r * r / 2, FORM_TOL);
    assert_identity_frame(&out);
}

/* The capsule in expanded form, derived independently of src/bodies/mass.c's
   cap-by-cap parallel-axis sum: with the cylinder mass mc and the two caps'
   mass ms,
     I_perp = mc (3 r^2 + l^2) / 12 + ms (2/5 r^2 + 3/8 r l + 1/4 l^2),
     I_axis = mc r^2 / 2 + 2/5 ms r^2. */
static void capsule_closed_form(double rho, double r, double l, double *m, double *perp, double *axis)
{
    const double mc = PI * r * r * l * rho, ms = 4.0 / 3.0 * PI * r * r * r * rho;
    *m = mc + ms;
    *perp = mc * (3 * r * r + l * l) / 12 + ms * (0.4 * r * r + 0.375 * r * l + 0.25 * l * l);
    *axis = mc * r * r / 2 + 0.4 * ms * r * r;
}

static void capsule_matches_closed_form(void **state)
{
    const double rho = 1100, r[] = { 0.25, 1.0, 0.01 }, l[] = { 1.5, 0.2, 3.0 };
    tb_mass out, ball;
    int k;
    (void)state;
    for (k = 0; k < 3; ++k) {
        double m, perp, axis;
        capsule_closed_form(rho, r[k], l[k], &m, &perp, &axis);
        assert_int_equal(tb_mass_capsule(rho, r[k], l[k], &out, NULL), TB_OK);
        assert_rel(out.mass, m, FORM_TOL);
        assert_rel(out.inertia[0], perp, FORM_TOL);
        assert_rel(out.inertia[1], perp, FORM_TOL);
        assert_rel(out.inertia[2], axis, FORM_TOL);
        assert_identity_frame(&out);
    }
    /* Length 0 is a sphere. */
    assert_int_equal(tb_mass_capsule(rho, 0.5, 0, &out, NULL), TB_OK);
    assert_int_equal(tb_mass_sphere(rho, 0.5, &ball, NULL), TB_OK);
    assert_rel(out.mass, ball.mass, FORM_TOL);
    for (k = 0; k < 3; ++k)
        assert_rel(out.inertia[k], ball.inertia[k], FORM_TOL);
}

/* ---- ODE ---------------------------------------------------------------------- */

/* ODE evaluates the same formulas in another order, so the two agree to
   rounding (FORM_TOL). ODE's capsule formula is
     Ia = M1 (r^2/4 + l^2/12) + M2 (2/5 r^2 + 3/8 r l + 1/4 l^2),
   the exact solid capsule, so it is held to the same bound. */
static void compare_with_ode(const char *shape, const tb_mass *t, const dMass *o, double *worst)
{
    const double got[4] = { t->mass, t->inertia[0], t->inertia[1], t->inertia[2] };
    const double want[4] = { o->mass, o->I[0], o->I[5], o->I[10] };
    int k;
    for (k = 0; k < 4; ++k) {
        *worst = fmax(*worst, rel(got[k], want[k]));
        if (!(rel(got[k], want[k]) <= FORM_TOL))
            fail_msg("%s: quantity %d is %.17g, ODE has %.17g", shape, k, got[k], want[k]);
    }
    for (k = 0; k < 3; ++k)
        assert_true(o->c[k] == 0 && t->centre[k] == 0);
    /* ODE's products of inertia are zero for these shapes too. */
    assert_true(o->I[1] == 0 && o->I[2] == 0 && o->I[6] == 0);
}

static void primitives_match_ode(void **state)
{
    static const double cases[][4] = { /* rho, a, b, c */
                                       { 1000, 0.3, 1.2, 0.7 },
                                       { 7.8e3, 0.05, 0.01, 0.02 },
                                       { 0.5, 2.0, 0.3, 5.0 },
                                       { 1.0 / 3.0, 1.0 / 7.0, 10.0 / 3.0, 0.1 } };
    double worst[4] = { 0, 0, 0, 0 };
    size_t k;
    (void)state;
    dInitODE2(0);
    for (k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        const double rho = cases[k][0], a = cases[k][1], b = cases[k][2], c = cases[k][3];
        const double size[3] = { a, b, c };
        tb_mass t;
        dMass o;
        dMassSetSphere(&o, rho, a);
        assert_int_equal(tb_mass_sphere(rho, a, &t, NULL), TB_OK);
        compare_with_ode("sphere", &t, &o, &worst[0]);
        dMassSetBox(&o, rho, a, b, c);
        assert_int_equal(tb_mass_box(rho, size, &t, NULL), TB_OK);
        compare_with_ode("box", &t, &o, &worst[1]);
        dMassSetCylinder(&o, rho, 3, a, b);
        assert_int_equal(tb_mass_cylinder(rho, a, b, &t, NULL), TB_OK);
        compare_with_ode("cylinder", &t, &o, &worst[2]);
        dMassSetCapsule(&o, rho, 3, a, b);
        assert_int_equal(tb_mass_capsule(rho, a, b, &t, NULL), TB_OK);
        compare_with_ode("capsule", &t, &o, &worst[3]);
    }
    print_message("worst relative difference from ODE: sphere %.2g, box %.2g, cylinder %.2g, capsule %.2g\n",
                  worst[0], worst[1], worst[2], worst[3]);
    dCloseODE();
}

/* ---- point masses ---------------------------------------------------------------- */

/* Unit masses at the corners (+-a, +-b, +-c): C = 8 diag(a^2, b^2, c^2), so
   I = 8 (b^2 + c^2, a^2 + c^2, a^2 + b^2) = (104, 80, 40) for (1, 2, 3). All
   sums are of small integers, exact in double. */
static const double HALF[3] = { 1, 2, 3 };
static const double CORNER_MOMENTS[3] = { 40, 80, 104 }; /* ascending */

static void corners(const double r[9], const double shift[3], double p[24])
{
    int k, i;
    for (k = 0; k < 8; ++k) {
        const double c[3] = { k & 1 ? HALF[0] : -HALF[0], k & 2 ? HALF[1] : -HALF[1], k & 4 ? HALF[2] : -HALF[2] };
        rotate(r, c, p + 3 * k);
        for (i = 0; i < 3; ++i)
            p[3 * k + i] += shift[i];
    }
}

static void points_at_box_corners(void **state)
{
    static const double identity[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 }, zero[3] = { 0, 0, 0 };
    const double ones[8] = { 1, 1, 1, 1, 1, 1, 1, 1 };
    const double want[9] = { 104, 0, 0, 0, 80, 0, 0, 0, 40 };
    double p[24], t[9];
    tb_mass m;
    int k;
    (void)state;
    corners(identity, zero, p);
    assert_int_equal(tb_mass_points(8, p, ones, &m, NULL), TB_OK);
    assert_principal_form(&m);
    assert_true(m.mass == 8);
    for (k = 0; k < 3; ++k) {
        assert_true(m.centre[k] == 0);
        assert_true(m.inertia[k] == CORNER_MOMENTS[k]); /* diagonal input: no rotation, exact */
    }
    /* Moments ascending means the frame swaps x and z: a half turn about
       (x + z)/sqrt 2, whose quaternion has entries 1/sqrt 2, so R D R^T
       rebuilds the diagonal tensor to a few eps, not exactly. */
    tensor_of(&m, t);
    assert_below(tensor_error(t, want), 4 * DBL_EPSILON);
}

/* The same corners turned by a generic rotation Q and moved by s: the same
   moments, centre s, and a frame with R D R^T = Q diag(104, 80, 40) Q^T.
   Q's entries are rounded (eps each), which perturbs the positions by
   about 4 eps |p| and the tensor by twice that relative; Jacobi adds a few
   eps. 1e-13 is ten times that margin. */
static void points_rotated_keep_moments_and_frame(void **state)
{
    const double shift[3] = { 5, -6, 7 }, ones[8] = { 1, 1, 1, 1, 1, 1, 1, 1 };
    const double d[3] = { 104, 80, 40 };
    double q[9], p[24], want[9], t[9];
    tb_mass m;
    int k;
    (void)state;
    test_rotation(q);
    corners(q, shift, p);
    assert_int_equal(tb_mass_points(8, p, ones, &m, NULL), TB_OK);
    assert_principal_form(&m);
    for (k = 0; k < 3; ++k) {
        assert_rel(m.inertia[k], CORNER_MOMENTS[k], 1e-13);
        /* The weighted mean of positions of size |s| ~ 10 rounds by a few
           eps |s| ~ 1e-15 per operation. */
        assert_below(fabs(m.centre[k] - shift[k]), 1e-13);
    }
    rotated_diagonal(q, d, want);
    tensor_of(&m, t);
    print_message("rotated corners: tensor error %.2g\n", tensor_error(t, want));
    assert_below(tensor_error(t, want), 1e-13);
}

/* Unequal masses at scattered points: the frame must rebuild the tensor the
   header defines, computed here directly from its formula. */
static void points_reproduce_their_tensor(void **state)
{
    const double p[] = { 0.3, -1.2, 2.0, 1.5, 0.4, -0.7, -2.2, 0.9, 0.1, 0.6, 1.8, -1.1, -0.4, -0.5, 0.8 };
    const double mass[] = { 1.5, 0.25, 3.0, 0.8, 2.2 };
    double total = 0, c[3] = { 0, 0, 0 }, want[9] = { 0 }, t[9];
    tb_mass m;
    int n, i, j;
    (void)state;
    for (n = 0; n < 5; ++n) {
        total += mass[n];
        for (i = 0; i < 3; ++i)
            c[i] += mass[n] * p[3 * n + i];
    }
    for (i = 0; i < 3; ++i)
        c[i] /= total;
    for (n = 0; n < 5; ++n) {
        const double r[3] = { p[3 * n] - c[0], p[3 * n + 1] - c[1], p[3 * n + 2] - c[2] };
        const double rr = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        for (i = 0; i < 3; ++i)
            for (j = 0; j < 3; ++j)
                want[3 * i + j] += mass[n] * ((i == j ? rr : 0) - r[i] * r[j]);
    }
    assert_int_equal(tb_mass_points(5, p, mass, &m, NULL), TB_OK);
    assert_principal_form(&m);
    assert_rel(m.mass, total, FORM_TOL);
    for (i = 0; i < 3; ++i)
        assert_below(fabs(m.centre[i] - c[i]), 1e-15);
    tensor_of(&m, t);
    /* Jacobi is backward stable: the rebuilt tensor errs by a few eps of
       its norm. */
    print_message("scattered points: tensor error %.2g\n", tensor_error(t, want));
    assert_below(tensor_error(t, want), 1e-14);
}

static void points_collinear_refused(void **state)
{
    /* Along a generic direction, so the computed smallest moment is a
       rounding residue, not an exact zero. */
    const double line[] = { 0, 0, 0, 0.1, 0.7, 0.3, 0.2, 1.4, 0.6, 0.3, 2.1, 0.9 };
    const double mass[] = { 1, 2, 3, 4 };
    char message[TB_MESSAGE_SIZE];
    tb_mass m;
    size_t count;
    (void)state;
    for (count = 1; count <= 4; ++count) {
        message[0] = 0;
        assert_int_equal(tb_mass_points(count, line, mass, &m, message), TB_ERR_ARGUMENT);
        assert_non_null(strstr(message, "collinear"));
    }
    /* A fourth point just off the line makes it a body again. */
    {
        const double body[] = { 0, 0, 0, 0.1, 0.7, 0.3, 0.2, 1.4, 0.6, 0.3, 2.1, 1.0 };
        assert_int_equal(tb_mass_points(4, body, mass, &m, NULL), TB_OK);
    }
}

/* ---- meshes ----------------------------------------------------------------------- */

/* A box mesh: corner k has coordinate i at +size/2 when bit i of k is set.
   Each face has tangent axes u, v with e_u x e_v its outward normal, and
   corners (-,-), (+,-), (+,+), (-,+) in (u, v): counter-clockwise from
   outside. */
static void box_mesh(const double size[3], const double r[9], const double shift[3], double v[24], uint32_t t[36])
{
    int k, s, i, n = 0;
    for (k = 0; k < 8; ++k) {
        double c[3];
        for (i = 0; i < 3; ++i)
            c[i] = (k >> i & 1 ? 0.5 : -0.5) * size[i];
        rotate(r, c, v + 3 * k);
        for (i = 0; i < 3; ++i)
            v[3 * k + i] += shift[i];
    }
    for (k = 0; k < 3; ++k)
        for (s = 0; s < 2; ++s) {
            const int u = s ? (k + 1) % 3 : (k + 2) % 3, w = s ? (k + 2) % 3 : (k + 1) % 3;
            const int base = s << k;
            const uint32_t q[4] = { (uint32_t)base, (uint32_t)(base | 1 << u), (uint32_t)(base | 1 << u | 1 << w),
                                    (uint32_t)(base | 1 << w) };
            t[n++] = q[0], t[n++] = q[1], t[n++] = q[2];
            t[n++] = q[0], t[n++] = q[2], t[n++] = q[3];
        }
}

static const double IDENTITY[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 }, ORIGIN[3] = { 0, 0, 0 };

/* Axis-aligned boxes: 12 triangles, reference point at the origin: each
   result is a short sum of exact-ish products, to rounding (FORM_TOL). */
static void mesh_box_matches_box(void **state)
{
    const double sizes[2][3] = { { 1, 1, 1 }, { 0.7, 1.9, 3.1 } };
    const double rho = 640;
    int s, k;
    (void)state;
    for (s = 0; s < 2; ++s) {
        double v[24], want_t[9], got_t[9], want_i[3];
        uint32_t t[36];
        tb_mass got, want;
        box_mesh(sizes[s], IDENTITY, ORIGIN, v, t);
        assert_int_equal(tb_mass_mesh(rho, 8, v, 12, t, &got, NULL), TB_OK);
        assert_int_equal(tb_mass_box(rho, sizes[s], &want, NULL), TB_OK);
        assert_principal_form(&got);
        assert_rel(got.mass, want.mass, FORM_TOL);
        memcpy(want_i, want.inertia, sizeof want_i);
        sort3(want_i);
        for (k = 0; k < 3; ++k) {
            assert_rel(got.inertia[k], want_i[k], FORM_TOL);
            assert_below(fabs(got.centre[k]), 1e-16);
        }
        tensor_of(&got, got_t);
        tensor_of(&want, want_t);
        assert_below(tensor_error(got_t, want_t), FORM_TOL);
    }
}

/* The 0.7 x 1.9 x 3.1 box turned by Q and moved by s: the same moments,
   centre s and R D R^T = Q D_box Q^T. Vertices carry rounding of about
   eps |s| ~ 1e-14 m, 1.5e-14 of the smallest half-side, and moments are
   quadratic in them; 1e-13 leaves a few times that margin. */
static void mesh_moved_box_keeps_moments_and_frame(void **state)
{
    const double size[3] = { 0.7, 1.9, 3.1 }, shift[3] = { 12.5, -30, 7.25 }, rho = 640;
    double q[9], v[24], want_t[9], got_t[9], want_i[3], worst = 0, worst_centre = 0;
    uint32_t t[36];
    tb_mass got, box;
    int k;
    (void)state;
    test_rotation(q);
    box_mesh(size, q, shift, v, t);
    assert_int_equal(tb_mass_mesh(rho, 8, v, 12, t, &got, NULL), TB_OK);
    assert_int_equal(tb_mass_box(rho, size, &box, NULL), TB_OK);
    assert_principal_form(&got);
    assert_rel(got.mass, box.mass, 1e-13);
    memcpy(want_i, box.inertia, sizeof want_i);
    sort3(want_i);
    for (k = 0; k < 3; ++k) {
        worst = fmax(worst, rel(got.inertia[k], want_i[k]));
        assert_rel(got.inertia[k], want_i[k], 1e-13);
        worst_centre = fmax(worst_centre, fabs(got.centre[k] - shift[k]));
        assert_below(fabs(got.centre[k] - shift[k]), 1e-13); /* eps |s| = 7e-15 */
    }
    rotated_diagonal(q, box.inertia, want_t);
    tensor_of(&got, got_t);
    print_message("moved box: worst moment error %.2g, tensor error %.2g, centre error %.2g m\n", worst,
                  tensor_error(got_t, want_t), worst_centre);
    assert_below(tensor_error(got_t, want_t), 1e-13);
}

/* A square pyramid (base side a in the plane z = 0, apex at height h),
   moved by s. Its centroid is h/4 above the base but the mean of its
   corners h/5, so the shift of second moments to the centroid matters.
   Closed forms: V = a^2 h / 3, I_axis = m a^2 / 10,
   I_perp = m (a^2 / 20 + 3 h^2 / 80) about the centroid. Coordinates up to
   |s| ~ 5 round by eps |s| ~ 1e-15, a few eps of the size: 1e-13. */
static void mesh_pyramid_matches_closed_form(void **state)
{
    const double a = 1.2, h = 2.1, rho = 300, s[3] = { 3, -4, 5 };
    const double v[15] = { s[0] - a / 2, s[1] - a / 2, s[2], s[0] + a / 2, s[1] - a / 2, s[2],
                           s[0] + a / 2, s[1] + a / 2, s[2], s[0] - a / 2, s[1] + a / 2, s[2],
                           s[0],         s[1],         s[2] + h };
    /* Base seen from below (outside) is clockwise in xy; sides counter-clockwise. */
    const uint32_t t[18] = { 0, 2, 1, 0, 3, 2, 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4 };
    const double m = rho * a * a * h / 3, perp = m * (a * a / 20 + 3 * h * h / 80), axis = m * a * a / 10;
    tb_mass got;
    double t_got[9];
    const double t_want[9] = { perp, 0, 0, 0, perp, 0, 0, 0, axis };
    (void)state;
    assert_int_equal(tb_mass_mesh(rho, 5, v, 6, t, &got, NULL), TB_OK);
    assert_principal_form(&got);
    assert_rel(got.mass, m, 1e-13);
    assert_below(fabs(got.centre[0] - s[0]), 1e-13);
    assert_below(fabs(got.centre[1] - s[1]), 1e-13);
    assert_rel(got.centre[2], s[2] + h / 4, 1e-13);
    tensor_of(&got, t_got);
    print_message("pyramid: tensor error %.2g\n", tensor_error(t_got, t_want));
    assert_below(tensor_error(t_got, t_want), 1e-13);
}

/* Icosphere: the icosahedron, each level cutting every triangle in four
   and pushing the new vertices out to the unit sphere. */
typedef struct sphere_mesh {
    size_t vertex_count, triangle_count;
    double *v;
    uint32_t *t;
} sphere_mesh;

static uint32_t midpoint(sphere_mesh *s, uint32_t *nb, uint32_t *mid, unsigned char *deg, uint32_t a, uint32_t b)
{
    double *p;
    double n;
    int k, i;
    /* Vertices of an icosphere meet at most 6 edges. */
    for (k = 0; k < deg[a]; ++k)
        if (nb[6 * a + k] == b)
            return mid[6 * a + k];
    p = s->v + 3 * s->vertex_count;
    for (i = 0; i < 3; ++i)
        p[i] = 0.5 * (s->v[3 * a + i] + s->v[3 * b + i]);
    n = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (i = 0; i < 3; ++i)
        p[i] /= n;
    assert_true(deg[a] < 6 && deg[b] < 6);
    nb[6 * a + deg[a]] = b, mid[6 * a + deg[a]++] = (uint32_t)s->vertex_count;
    nb[6 * b + deg[b]] = a, mid[6 * b + deg[b]++] = (uint32_t)s->vertex_count;
    return (uint32_t)s->vertex_count++;
}

static sphere_mesh icosphere(int levels)
{
    static const uint32_t faces[20][3] = { { 0, 11, 5 }, { 0, 5, 1 },  { 0, 1, 7 },   { 0, 7, 10 }, { 0, 10, 11 },
                                           { 1, 5, 9 },  { 5, 11, 4 }, { 11, 10, 2 }, { 10, 7, 6 }, { 7, 1, 8 },
                                           { 3, 9, 4 },  { 3, 4, 2 },  { 3, 2, 6 },   { 3, 6, 8 },  { 3, 8, 9 },
                                           { 4, 9, 5 },  { 2, 4, 11 }, { 6, 2, 10 },  { 8, 6, 7 },  { 9, 8, 1 } };
    const double g = (1 + sqrt(5.0)) / 2;
    const double corner[12][3] = { { -1, g, 0 }, { 1, g, 0 }, { -1, -g, 0 }, { 1, -g, 0 },
                                   { 0, -1, g }, { 0, 1, g }, { 0, -1, -g }, { 0, 1, -g },
                                   { g, 0, -1 }, { g, 0, 1 }, { -g, 0, -1 }, { -g, 0, 1 } };
    size_t max_t = 20, max_v, f;
    sphere_mesh s;
    int l, k, i;
    for (l = 0; l < levels; ++l)
        max_t *= 4;
    max_v = max_t / 2 + 2; /* Euler: V - E + F = 2 with E = 3F/2 */
    s.v = malloc(3 * max_v * sizeof *s.v);
    s.t = malloc(3 * max_t * sizeof *s.t);
    assert_non_null(s.v);
    assert_non_null(s.t);
    for (k = 0; k < 12; ++k) {
        const double n = sqrt(1 + g * g);
        for (i = 0; i < 3; ++i)
            s.v[3 * k + i] = corner[k][i] / n;
    }
    s.vertex_count = 12;
    s.triangle_count = 20;
    for (f = 0; f < 20; ++f) {
        /* Orient outward whatever the table's order: a face of a convex body
           around the origin faces out when (b - a) x (c - a) . a > 0. */
        const double *a = s.v + 3 * faces[f][0], *b = s.v + 3 * faces[f][1], *c = s.v + 3 * faces[f][2];
        const double e[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] }, h[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
        const double x[3] = { e[1] * h[2] - e[2] * h[1], e[2] * h[0] - e[0] * h[2], e[0] * h[1] - e[1] * h[0] };
        const int out = x[0] * a[0] + x[1] * a[1] + x[2] * a[2] > 0;
        s.t[3 * f] = faces[f][0];
        s.t[3 * f + 1] = faces[f][out ? 1 : 2];
        s.t[3 * f + 2] = faces[f][out ? 2 : 1];
    }
    for (l = 0; l < levels; ++l) {
        const size_t n = s.triangle_count;
        uint32_t *nb = malloc(6 * max_v * sizeof *nb), *mid = malloc(6 * max_v * sizeof *mid);
        unsigned char *deg = calloc(max_v, 1);
        uint32_t *old = malloc(3 * n * sizeof *old);
        assert_true(nb && mid && deg && old);
        memcpy(old, s.t, 3 * n * sizeof *old);
        for (f = 0; f < n; ++f) {
            const uint32_t a = old[3 * f], b = old[3 * f + 1], c = old[3 * f + 2];
            const uint32_t ab = midpoint(&s, nb, mid, deg, a, b), bc = midpoint(&s, nb, mid, deg, b, c),
                           ca = midpoint(&s, nb, mid, deg, c, a);
            const uint32_t child[4][3] = { { a, ab, ca }, { b, bc, ab }, { c, ca, bc }, { ab, bc, ca } };
            memcpy(s.t + 12 * f, child, sizeof child);
        }
        s.triangle_count = 4 * n;
        free(nb);
        free(mid);
        free(deg);
        free(old);
    }
    assert_true(s.vertex_count == max_v);
    return s;
}

/* The smallest distance from the centre to a face plane: the polyhedron
   holds the ball of that radius. */
static double inradius(const sphere_mesh *s)
{
    double r = 1;
    size_t f;
    for (f = 0; f < s->triangle_count; ++f) {
        const double *a = s->v + 3 * s->t[3 * f], *b = s->v + 3 * s->t[3 * f + 1], *c = s->v + 3 * s->t[3 * f + 2];
        const double e[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] }, h[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
        const double x[3] = { e[1] * h[2] - e[2] * h[1], e[2] * h[0] - e[0] * h[2], e[0] * h[1] - e[1] * h[0] };
        r = fmin(r, (x[0] * a[0] + x[1] * a[1] + x[2] * a[2]) / sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]));
    }
    return r;
}

/* Icospheres of 20 to 20480 triangles against the unit ball.
   - Bracket: the polyhedron lies between the ball of its inradius and the
     unit ball, so its mass and (inertia being monotone under inclusion)
     every principal moment lie between those balls' values. Rounding is
     far below the gaps (5e-4 relative or more).
   - Rate: the inscribed polyhedron misses a cap of height ~ h^2 over each
     face, so the volume error is O(h^2) and halving h (one level) divides
     it by 4 + O(h^2), the mass and every moment alike. So the distance of
     that ratio from 4 must itself shrink by about 4 a level once h is
     small: by at least 3 is asserted from level 3 on (measured 3.7 to 4.0;
     3.1 to 3.4 between the two coarsest pairs), and below 0.01 at the
     finest level (measured ratios 3.12, 3.74, 3.93, 3.98, 3.996 for the
     mass; 2.79, 3.61, 3.90, 3.97, 3.993 for the moments).
   - Symmetry: the icosphere keeps the icosahedron's rotations, which leave
     no quadratic form but the identity invariant, so its tensor is
     isotropic; the moments may differ only by summation rounding, at most
     about (triangle count) eps relative. */
static void mesh_sphere_converges(void **state)
{
    const double rho = 1000;
    double previous = 0, previous_inertia = 0, deviation = 0, deviation_inertia = 0;
    int level;
    (void)state;
    for (level = 0; level <= 5; ++level) {
        sphere_mesh s = icosphere(level);
        const double r_in = inradius(&s);
        tb_mass got, ball, inner;
        double error, error_inertia;
        int k;
        assert_int_equal(tb_mass_mesh(rho, s.vertex_count, s.v, s.triangle_count, s.t, &got, NULL), TB_OK);
        assert_int_equal(tb_mass_sphere(rho, 1, &ball, NULL), TB_OK);
        assert_int_equal(tb_mass_sphere(rho, r_in, &inner, NULL), TB_OK);
        assert_principal_form(&got);
        assert_true(inner.mass < got.mass && got.mass < ball.mass);
        for (k = 0; k < 3; ++k) {
            assert_true(inner.inertia[k] < got.inertia[k] && got.inertia[k] < ball.inertia[k]);
            assert_below(fabs(got.centre[k]), 1e-15);
        }
        assert_below(rel(got.inertia[0], got.inertia[2]), (double)s.triangle_count * DBL_EPSILON);
        error = rel(got.mass, ball.mass);
        error_inertia = rel(got.inertia[0], ball.inertia[0]);
        print_message("level %d: %5zu triangles, mass error %.4e (ratio %.3f), inertia error %.4e (ratio %.3f), "
                      "anisotropy %.2g\n",
                      level, s.triangle_count, error, level ? previous / error : 0.0, error_inertia,
                      level ? previous_inertia / error_inertia : 0.0, rel(got.inertia[0], got.inertia[2]));
        if (level >= 1) {
            const double dev = fabs(previous / error - 4), dev_inertia = fabs(previous_inertia / error_inertia - 4);
            if (level >= 3) {
                assert_below(dev, deviation / 3);
                assert_below(dev_inertia, deviation_inertia / 3);
            }
            deviation = dev;
            deviation_inertia = dev_inertia;
        }
        previous_inertia = error_inertia;
        previous = error;
        free(s.v);
        free(s.t);
    }
    assert_below(deviation, 0.01);
    assert_below(deviation_inertia, 0.01);
}

static void assert_mesh_refused(size_t vertex_count, const double *v, size_t triangle_count, const uint32_t *t,
                                const char *needle)
{
    char message[TB_MESSAGE_SIZE];
    tb_mass m, sentinel;
    memset(&m, 0xa5, sizeof m);
    sentinel = m;
    message[0] = 0;
    assert_int_equal(tb_mass_mesh(1000, vertex_count, v, triangle_count, t, &m, message), TB_ERR_ARGUMENT);
    if (!strstr(message, needle))
        fail_msg("message \"%s\" does not mention \"%s\"", message, needle);
    assert_memory_equal(&m, &sentinel, sizeof m);
}

static void mesh_open_refused(void **state)
{
    const double size[3] = { 1, 2, 3 };
    double v[24];
    uint32_t t[36];
    (void)state;
    box_mesh(size, IDENTITY, ORIGIN, v, t);
    assert_mesh_refused(8, v, 11, t, "open"); /* last triangle dropped */
    assert_mesh_refused(8, v, 11, t + 3, "open"); /* first triangle dropped */
}

static void mesh_inside_out_refused(void **state)
{
    const double size[3] = { 1, 2, 3 };
    double v[24];
    uint32_t t[36];
    int k;
    (void)state;
    box_mesh(size, IDENTITY, ORIGIN, v, t);
    for (k = 0; k < 12; ++k) {
        const uint32_t x = t[3 * k + 1];
        t[3 * k + 1] = t[3 * k + 2];
        t[3 * k + 2] = x;
    }
    assert_mesh_refused(8, v, 12, t, "inside out");
    /* Flipping back one triangle only makes it inconsistent. */
    t[1] ^= t[2], t[2] ^= t[1], t[1] ^= t[2];
    assert_mesh_refused(8, v, 12, t, "twice");
}

static void mesh_bad_indices_and_vertices_refused(void **state)
{
    const double size[3] = { 1, 2, 3 };
    /* Two triangles back to back: closed and consistent, but flat. */
    const double flat_v[9] = { 0, 0, 0, 1, 0, 0, 0, 1, 0 };
    const uint32_t flat_t[6] = { 0, 1, 2, 0, 2, 1 };
    double v[24];
    uint32_t t[36];
    (void)state;
    box_mesh(size, IDENTITY, ORIGIN, v, t);
    t[5] = 8;
    assert_mesh_refused(8, v, 12, t, "vertex 8");
    t[5] = 0xffffffffu;
    assert_mesh_refused(8, v, 12, t, "vertex 4294967295");
    box_mesh(size, IDENTITY, ORIGIN, v, t);
    t[1] = t[0];
    assert_mesh_refused(8, v, 12, t, "repeats");
    box_mesh(size, IDENTITY, ORIGIN, v, t);
    v[7] = NAN;
    assert_mesh_refused(8, v, 12, t, "not finite");
    v[7] = -INFINITY;
    assert_mesh_refused(8, v, 12, t, "not finite");
    box_mesh(size, IDENTITY, ORIGIN, v, t);
    assert_mesh_refused(8, v, 0, t, "triangles");
    assert_mesh_refused(8, NULL, 12, t, "NULL");
    assert_mesh_refused(8, v, 12, NULL, "NULL");
    assert_mesh_refused(3, flat_v, 2, flat_t, "no volume");
}

/* ---- full tensors ------------------------------------------------------------------ */

/* Q diag(d) Q^T is rounded entry by entry (a few eps of |d|); by Weyl's
   inequality the moments come back within that, and Jacobi adds a few eps
   more: 1e-14 relative to the smallest moment (2 here, a third of the
   largest) is a margin of about 5. */
static void tensor_rotated_diagonal_comes_back(void **state)
{
    const double sets[3][3] = { { 4, 2, 3 }, { 2, 2, 3 }, { 5, 3, 3 } }; /* generic, and with a double moment */
    const double centre[3] = { 0.1, -0.2, 0.3 };
    int s, k;
    (void)state;
    for (s = 0; s < 3; ++s) {
        double q[9], t[9], back[9], want[3];
        tb_mass m;
        test_rotation(q);
        rotated_diagonal(q, sets[s], t);
        assert_int_equal(tb_mass_from_tensor(2.5, centre, t, &m, NULL), TB_OK);
        assert_principal_form(&m);
        assert_true(m.mass == 2.5);
        assert_memory_equal(m.centre, centre, sizeof centre);
        memcpy(want, sets[s], sizeof want);
        sort3(want);
        for (k = 0; k < 3; ++k)
            assert_rel(m.inertia[k], want[k], 1e-14);
        tensor_of(&m, back);
        print_message("set %d: tensor error %.2g\n", s, tensor_error(back, t));
        assert_below(tensor_error(back, t), 1e-14);
    }
    /* Many orientations, so that every branch of the matrix-to-quaternion
       conversion and both signs of w come up. */
    for (k = 0; k < 64; ++k) {
        const double raw[4] = { (k & 3) - 1.5, (k >> 2 & 3) - 1.2, (k >> 4 & 3) - 1.7, 0.3 * k - 9 };
        const double n = sqrt(raw[0] * raw[0] + raw[1] * raw[1] + raw[2] * raw[2] + raw[3] * raw[3]);
        const double q4[4] = { raw[0] / n, raw[1] / n, raw[2] / n, raw[3] / n };
        double q[9], t[9], back[9];
        tb_mass m;
        matrix_of(q4, q);
        rotated_diagonal(q, sets[0], t);
        assert_int_equal(tb_mass_from_tensor(1, centre, t, &m, NULL), TB_OK);
        assert_principal_form(&m);
        assert_rel(m.inertia[0], 2, 1e-14);
        assert_rel(m.inertia[2], 4, 1e-14);
        tensor_of(&m, back);
        assert_below(tensor_error(back, t), 1e-14);
    }
    /* A diagonal tensor needs no rotation: moments exact, frame a pure
       permutation that sorts them. */
    {
        const double t[9] = { 3, 0, 0, 0, 1, 0, 0, 0, 2 };
        double back[9];
        tb_mass m;
        assert_int_equal(tb_mass_from_tensor(1, centre, t, &m, NULL), TB_OK);
        assert_true(m.inertia[0] == 1 && m.inertia[1] == 2 && m.inertia[2] == 3);
        tensor_of(&m, back);
        assert_below(tensor_error(back, t), 4 * DBL_EPSILON);
    }
}

static void assert_tensor_refused(const double t[9], const char *needle)
{
    const double centre[3] = { 0, 0, 0 };
    char message[TB_MESSAGE_SIZE];
    tb_mass m, sentinel;
    memset(&m, 0x5a, sizeof m);
    sentinel = m;
    message[0] = 0;
    assert_int_equal(tb_mass_from_tensor(1, centre, t, &m, message), TB_ERR_ARGUMENT);
    if (!strstr(message, needle))
        fail_msg("message \"%s\" does not mention \"%s\"", message, needle);
    assert_memory_equal(&m, &sentinel, sizeof m);
}

static void tensor_bad_tensors_refused(void **state)
{
    const double asymmetric[9] = { 2, 0.1, 0, 0, 2, 0, 0, 0, 2 };
    const double indefinite[9] = { 2, 0, 0, 0, 2, 0, 0, 0, -1 };
    const double singular[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 0 };
    const double nan[9] = { 1, 0, 0, 0, NAN, 0, 0, 0, 1 };
    const double inf[9] = { 1, 0, 0, 0, 1, INFINITY, 0, INFINITY, 1 };
    const double lopsided[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 2.5 };
    /* Just past a flat plate: 1e-10 beyond I1 + I2, far above the 1e-12
       tolerance, so still refused. */
    const double barely[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 2 * (1 + 1e-10) };
    double q[9], t[9];
    const double d[3] = { 2, 1, 1 }; /* I1 + I2 = 2 < 2.5 after rotation below */
    (void)state;
    assert_tensor_refused(asymmetric, "symmetric");
    assert_tensor_refused(indefinite, "positive definite");
    assert_tensor_refused(singular, "positive definite");
    assert_tensor_refused(nan, "finite");
    assert_tensor_refused(inf, "finite");
    assert_tensor_refused(lopsided, "triangle");
    assert_tensor_refused(barely, "triangle");
    test_rotation(q);
    rotated_diagonal(q, d, t);
    t[8] += 0.5; /* breaks the triangle inequality in a rotated frame */
    assert_tensor_refused(t, "triangle");
}

/* A thin rectangular plate of sides a, b in the xy plane: (m b^2/12,
   m a^2/12, m (a^2 + b^2)/12), I3 = I1 + I2 up to rounding, also turned by
   Q, where rounding pushes I3 either way by a few eps. A tensor rounded
   within 1e-15 of symmetric is accepted too. */
static void tensor_thin_plate_accepted(void **state)
{
    const double m = 3, a = 0.7, b = 1.3, centre[3] = { 0, 0, 0 };
    const double d[3] = { m * b * b / 12, m * a * a / 12, m * (a * a + b * b) / 12 };
    const double flat[9] = { d[0], 0, 0, 0, d[1], 0, 0, 0, d[2] };
    double q[9], t[9];
    tb_mass out;
    (void)state;
    assert_int_equal(tb_mass_from_tensor(m, centre, flat, &out, NULL), TB_OK);
    test_rotation(q);
    rotated_diagonal(q, d, t);
    t[1] *= 1 + 1e-15;
    assert_int_equal(tb_mass_from_tensor(m, centre, t, &out, NULL), TB_OK);
    assert_rel(out.inertia[2], d[2], 1e-14);
}

static void set_total_scales_mass_and_inertia(void **state)
{
    const double size[3] = { 0.5, 1.5, 2.5 }, total = 7;
    tb_mass m;
    double before[4];
    (void)state;
    assert_int_equal(tb_mass_box(1, size, &m, NULL), TB_OK);
    memcpy(before, m.frame, sizeof before);
    assert_int_equal(tb_mass_set_total(&m, total, NULL), TB_OK);
    assert_true(m.mass == total);
    assert_rel(m.inertia[0], total * (size[1] * size[1] + size[2] * size[2]) / 12, FORM_TOL);
    assert_rel(m.inertia[1], total * (size[0] * size[0] + size[2] * size[2]) / 12, FORM_TOL);
    assert_rel(m.inertia[2], total * (size[0] * size[0] + size[1] * size[1]) / 12, FORM_TOL);
    assert_memory_equal(m.frame, before, sizeof before);
}

/* ---- bad input everywhere ------------------------------------------------------------ */

/* Each call must fail with TB_ERR_ARGUMENT, say why, and leave the output
   byte for byte as it was. */
typedef struct refusal {
    tb_mass m, sentinel;
    char message[TB_MESSAGE_SIZE];
} refusal;

static tb_mass *arm(refusal *r)
{
    memset(&r->m, 0xa5, sizeof r->m);
    r->sentinel = r->m;
    memset(r->message, 0, sizeof r->message);
    return &r->m;
}

static void refused(refusal *r, tb_status st, const char *what)
{
    if (st != TB_ERR_ARGUMENT)
        fail_msg("%s: status %d, expected TB_ERR_ARGUMENT", what, (int)st);
    if (r->message[0] == 0)
        fail_msg("%s: no message", what);
    if (memcmp(&r->m, &r->sentinel, sizeof r->m) != 0)
        fail_msg("%s: output changed (message: %s)", what, r->message);
}

static void bad_input_leaves_mass_untouched(void **state)
{
    const double bad[] = { 0, -1, -0.0, NAN, INFINITY, -INFINITY };
    const double good = 1.5, centre[3] = { 0, 0, 0 }, tensor[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 };
    const double pts[9] = { 0, 0, 0, 1, 0, 0, 0, 1, 0 };
    refusal r;
    tb_mass ok;
    size_t k;
    int i;
    (void)state;
    for (k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
        const double b = bad[k];
        double size[3] = { good, good, good }, p[9], masses[3] = { 1, 1, 1 };
        refused(&r, tb_mass_sphere(b, good, arm(&r), r.message), "sphere density");
        refused(&r, tb_mass_sphere(good, b, arm(&r), r.message), "sphere radius");
        refused(&r, tb_mass_box(b, size, arm(&r), r.message), "box density");
        for (i = 0; i < 3; ++i) {
            size[i] = b;
            refused(&r, tb_mass_box(good, size, arm(&r), r.message), "box size");
            size[i] = good;
        }
        refused(&r, tb_mass_cylinder(b, good, good, arm(&r), r.message), "cylinder density");
        refused(&r, tb_mass_cylinder(good, b, good, arm(&r), r.message), "cylinder radius");
        refused(&r, tb_mass_cylinder(good, good, b, arm(&r), r.message), "cylinder length");
        refused(&r, tb_mass_capsule(b, good, good, arm(&r), r.message), "capsule density");
        refused(&r, tb_mass_capsule(good, b, good, arm(&r), r.message), "capsule radius");
        if (!(b == 0)) /* a capsule of length 0 is a sphere */
            refused(&r, tb_mass_capsule(good, good, b, arm(&r), r.message), "capsule length");
        for (i = 0; i < 3; ++i) {
            masses[i] = b;
            refused(&r, tb_mass_points(3, pts, masses, arm(&r), r.message), "point mass");
            masses[i] = 1;
        }
        if (!isfinite(b)) {
            for (i = 0; i < 9; ++i) {
                memcpy(p, pts, sizeof p);
                p[i] = b;
                refused(&r, tb_mass_points(3, p, masses, arm(&r), r.message), "point position");
            }
            for (i = 0; i < 3; ++i) {
                double c[3] = { 0, 0, 0 };
                c[i] = b;
                refused(&r, tb_mass_from_tensor(good, c, tensor, arm(&r), r.message), "tensor centre");
            }
        }
        refused(&r, tb_mass_from_tensor(b, centre, tensor, arm(&r), r.message), "tensor mass");
        {
            const double cube[3] = { 1, 1, 1 };
            double v[24];
            uint32_t t[36];
            box_mesh(cube, IDENTITY, ORIGIN, v, t);
            refused(&r, tb_mass_mesh(b, 8, v, 12, t, arm(&r), r.message), "mesh density");
        }
        assert_int_equal(tb_mass_sphere(1, 1, &ok, NULL), TB_OK);
        r.m = r.sentinel = ok;
        memset(r.message, 0, sizeof r.message);
        refused(&r, tb_mass_set_total(&r.m, b, r.message), "set_total");
        /* A mass that is itself bad cannot be scaled. */
        r.m.mass = b;
        r.sentinel = r.m;
        memset(r.message, 0, sizeof r.message);
        refused(&r, tb_mass_set_total(&r.m, 2, r.message), "set_total of a bad mass");
    }
    /* Overflow and underflow of the result are refused, not returned. */
    refused(&r, tb_mass_sphere(1e300, 1e10, arm(&r), r.message), "sphere overflow");
    refused(&r, tb_mass_sphere(1e-300, 1e-10, arm(&r), r.message), "sphere underflow");
    refused(&r, tb_mass_points(0, pts, pts, arm(&r), r.message), "no points");
    refused(&r, tb_mass_points(3, NULL, pts, arm(&r), r.message), "NULL positions");
    refused(&r, tb_mass_box(1, NULL, arm(&r), r.message), "NULL size");
    refused(&r, tb_mass_from_tensor(1, NULL, tensor, arm(&r), r.message), "NULL centre");
    /* A NULL output or NULL message is survived. */
    assert_int_equal(tb_mass_sphere(1, 1, NULL, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_set_total(NULL, 1, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_sphere(NAN, 1, &ok, NULL), TB_ERR_ARGUMENT);
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(sphere_matches_closed_form),
    cmocka_unit_test(box_matches_closed_form),
    cmocka_unit_test(cylinder_matches_closed_form),
    cmocka_unit_test(capsule_matches_closed_form),
    cmocka_unit_test(primitives_match_ode),
    cmocka_unit_test(points_at_box_corners),
    cmocka_unit_test(points_rotated_keep_moments_and_frame),
    cmocka_unit_test(points_reproduce_their_tensor),
    cmocka_unit_test(points_collinear_refused),
    cmocka_unit_test(mesh_box_matches_box),
    cmocka_unit_test(mesh_moved_box_keeps_moments_and_frame),
    cmocka_unit_test(mesh_pyramid_matches_closed_form),
    cmocka_unit_test(mesh_sphere_converges),
    cmocka_unit_test(mesh_open_refused),
    cmocka_unit_test(mesh_inside_out_refused),
    cmocka_unit_test(mesh_bad_indices_and_vertices_refused),
    cmocka_unit_test(tensor_rotated_diagonal_comes_back),
    cmocka_unit_test(tensor_bad_tensors_refused),
    cmocka_unit_test(tensor_thin_plate_accepted),
    cmocka_unit_test(set_total_scales_mass_and_inertia),
    cmocka_unit_test(bad_input_leaves_mass_untouched),
};
TB_TEST_MAIN(tests)
