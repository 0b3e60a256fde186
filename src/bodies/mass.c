/* mass.c: mass properties of rigid bodies (tb_mass_*) from uniform-density
   shapes, point masses, closed triangle meshes and full inertia tensors.
   It touches no world, so failures write their reason into the caller's
   buffer instead of a world's message.

   The primitive shapes keep their own axes: moments along x, y, z and the
   identity frame. Every other result comes from a full tensor diagonalised by
   cyclic Jacobi rotations; its principal moments are in ascending order
   (equal moments keep the order of the axes that Jacobi found) and its frame
   is the rotation R whose columns are the matching principal axes in the
   shape's frame, so that tensor = R diag(inertia) R^T with det R = +1. The
   quaternion is given with w >= 0, so the same input always gives the same
   bits. */
#include "tumble.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* C99 has no M_PI. */
static const double pi = 3.14159265358979323846;

/* Relative tolerance of the checks on user tensors: far above rounding (a
   rotated tensor built in double precision is symmetric, and a flat plate
   meets I1 + I2 = I3, to about 1e-16 of its norm) and far below any real
   asymmetry or violation. */
static const double tensor_tolerance = 1e-12;

static tb_status fail(char *message, tb_status status, const char *fmt, ...)
{
    if (message) {
        va_list args;
        va_start(args, fmt);
        vsnprintf(message, TB_MESSAGE_SIZE, fmt, args);
        va_end(args);
    }
    return status;
}

static int positive(double x)
{
    return isfinite(x) && x > 0;
}

/* What a body can take (the input rule, TB_LIMIT in tumble/base.h): a mass
   or moment in [1 / TB_LIMIT, TB_LIMIT]. */
static int in_scale(double x)
{
    return x >= 1 / TB_LIMIT && x <= TB_LIMIT; /* NaN fails */
}

/* ---- diagonalisation -------------------------------------------------------- */

/* Eigenvalues d and eigenvectors (columns of v, row-major) of the symmetric
   3x3 matrix a, by cyclic Jacobi rotations. A rotation is skipped once its
   off-diagonal entry is below eps sqrt(|a_pp a_qq|): dropping it then moves
   the eigenvalues by less than a rounding error relative to themselves
   (Demmel and Veselic 1992), which is the best a tensor known to rounding
   allows. Convergence is quadratic, so a handful of sweeps suffice; the cap
   only guards against pathological (non-finite) input. */
static void jacobi(const double in[9], double d[3], double v[9])
{
    static const int pairs[3][2] = { { 0, 1 }, { 0, 2 }, { 1, 2 } };
    double a[3][3];
    int i, j, sweep;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            a[i][j] = in[3 * i + j];
            v[3 * i + j] = i == j;
        }
    for (sweep = 0; sweep < 64; ++sweep) {
        int k, rotated = 0;
        for (k = 0; k < 3; ++k) {
            const int p = pairs[k][0], q = pairs[k][1], r = 3 - p - q;
            const double apq = a[p][q];
            double theta, t, c, s, arp, arq;
            if (fabs(apq) <= DBL_EPSILON * sqrt(fabs(a[p][p])) * sqrt(fabs(a[q][q])) || apq == 0)
                continue;
            rotated = 1;
            /* t = tan of the rotation angle: the smaller root of
               t^2 + 2 theta t - 1 = 0, which keeps the angle below pi/4 and
               the update stable. For huge theta, theta^2 would overflow and
               t ~ 1 / (2 theta). */
            theta = (a[q][q] - a[p][p]) / (2 * apq);
            if (fabs(theta) > 1e150)
                t = 0.5 / theta;
            else
                t = (theta >= 0 ? 1 : -1) / (fabs(theta) + sqrt(theta * theta + 1));
            c = 1 / sqrt(t * t + 1);
            s = t * c;
            a[p][p] -= t * apq;
            a[q][q] += t * apq;
            a[p][q] = a[q][p] = 0;
            arp = a[r][p];
            arq = a[r][q];
            a[r][p] = a[p][r] = c * arp - s * arq;
            a[r][q] = a[q][r] = s * arp + c * arq;
            for (i = 0; i < 3; ++i) {
                const double vp = v[3 * i + p], vq = v[3 * i + q];
                v[3 * i + p] = c * vp - s * vq;
                v[3 * i + q] = s * vp + c * vq;
            }
        }
        if (!rotated)
            break;
    }
    for (i = 0; i < 3; ++i)
        d[i] = a[i][i];
}

/* The unit quaternion (w, x, y, z) of the rotation matrix m (row-major).
   Of 4w^2 = 1 + m00 + m11 + m22, 4x^2 = 1 + m00 - m11 - m22, ... the largest
   is taken by a square root and the others from off-diagonal sums and
   differences, so no component comes from a small, cancelled square. */
static void quaternion_of(const double m[9], double q[4])
{
    const double tw = 1 + m[0] + m[4] + m[8], tx = 1 + m[0] - m[4] - m[8];
    const double ty = 1 - m[0] + m[4] - m[8], tz = 1 - m[0] - m[4] + m[8];
    double n;
    int i;
    if (tw >= tx && tw >= ty && tw >= tz) {
        const double f = 0.5 / sqrt(tw);
        q[0] = 0.5 * sqrt(tw);
        q[1] = (m[7] - m[5]) * f;
        q[2] = (m[2] - m[6]) * f;
        q[3] = (m[3] - m[1]) * f;
    } else if (tx >= ty && tx >= tz) {
        const double f = 0.5 / sqrt(tx);
        q[0] = (m[7] - m[5]) * f;
        q[1] = 0.5 * sqrt(tx);
        q[2] = (m[3] + m[1]) * f;
        q[3] = (m[2] + m[6]) * f;
    } else if (ty >= tz) {
        const double f = 0.5 / sqrt(ty);
        q[0] = (m[2] - m[6]) * f;
        q[1] = (m[3] + m[1]) * f;
        q[2] = 0.5 * sqrt(ty);
        q[3] = (m[7] + m[5]) * f;
    } else {
        const double f = 0.5 / sqrt(tz);
        q[0] = (m[3] - m[1]) * f;
        q[1] = (m[2] + m[6]) * f;
        q[2] = (m[7] + m[5]) * f;
        q[3] = 0.5 * sqrt(tz);
    }
    /* q and -q are the same rotation: pick one so results are reproducible,
       and renormalise away the rounding of the matrix. */
    n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (q[0] < 0)
        n = -n;
    for (i = 0; i < 4; ++i)
        q[i] /= n;
}

/* Principal moments (ascending) and frame of the symmetric tensor t. */
static void principal(const double t[9], double moments[3], double frame[4])
{
    double v[9], det;
    int i, j, k;
    jacobi(t, moments, v);
    /* Insertion sort of three, moving eigenvector columns along; strict
       comparison keeps equal moments in Jacobi's order. */
    for (i = 1; i < 3; ++i)
        for (j = i; j > 0 && moments[j] < moments[j - 1]; --j) {
            const double m = moments[j];
            moments[j] = moments[j - 1];
            moments[j - 1] = m;
            for (k = 0; k < 3; ++k) {
                const double x = v[3 * k + j];
                v[3 * k + j] = v[3 * k + j - 1];
                v[3 * k + j - 1] = x;
            }
        }
    /* Jacobi rotations keep det = +1 but the swaps flip it; turning an axis
       around makes the frame a proper rotation again. */
    det = v[0] * (v[4] * v[8] - v[5] * v[7]) - v[1] * (v[3] * v[8] - v[5] * v[6])
          + v[2] * (v[3] * v[7] - v[4] * v[6]);
    if (det < 0)
        for (k = 0; k < 3; ++k)
            v[3 * k + 2] = -v[3 * k + 2];
    quaternion_of(v, frame);
}

/* ---- results ---------------------------------------------------------------- */

/* Store a result whose axes are the shape's own, refusing a mass or moment
   that overflowed, underflowed or that no body can take (for example
   rho = 1e300 and r = 1e10). */
static tb_status store_axes(const char *shape, double m, const double inertia[3], tb_mass *out, char *message)
{
    tb_mass r;
    if (!in_scale(m) || !in_scale(inertia[0]) || !in_scale(inertia[1]) || !in_scale(inertia[2]))
        return fail(message, TB_ERR_ARGUMENT,
                    "%s mass properties are not representable (mass %g, moments %g %g %g; each must be from %g "
                    "to %g)", shape, m, inertia[0], inertia[1], inertia[2], 1 / TB_LIMIT, TB_LIMIT);
    memset(&r, 0, sizeof r);
    r.mass = m;
    memcpy(r.inertia, inertia, sizeof r.inertia);
    r.frame[0] = 1;
    *out = r;
    return TB_OK;
}

static tb_status refuse_null_mass(const char *function, char *message)
{
    return fail(message, TB_ERR_ARGUMENT, "%s: the tb_mass pointer must not be NULL", function);
}

/* ---- primitive shapes ------------------------------------------------------ */

tb_status tb_mass_sphere(double rho, double radius, tb_mass *mass, char *message)
{
    double m, i[3];
    if (!mass)
        return refuse_null_mass("tb_mass_sphere", message);
    if (!positive(rho))
        return fail(message, TB_ERR_ARGUMENT, "sphere density must be finite and > 0 (got %g)", rho);
    if (!positive(radius))
        return fail(message, TB_ERR_ARGUMENT, "sphere radius must be finite and > 0 (got %g)", radius);
    m = rho * (4.0 / 3.0) * pi * radius * radius * radius;
    i[0] = i[1] = i[2] = 0.4 * m * radius * radius;
    return store_axes("sphere", m, i, mass, message);
}

tb_status tb_mass_box(double rho, const double size[3], tb_mass *mass, char *message)
{
    double m, i[3], s2[3];
    int k;
    if (!mass)
        return refuse_null_mass("tb_mass_box", message);
    if (!positive(rho))
        return fail(message, TB_ERR_ARGUMENT, "box density must be finite and > 0 (got %g)", rho);
    if (!size)
        return fail(message, TB_ERR_ARGUMENT, "box size must not be NULL");
    for (k = 0; k < 3; ++k) {
        if (!positive(size[k]))
            return fail(message, TB_ERR_ARGUMENT, "box size[%d] must be finite and > 0 (got %g)", k, size[k]);
        s2[k] = size[k] * size[k];
    }
    m = rho * size[0] * size[1] * size[2];
    i[0] = m * (s2[1] + s2[2]) / 12;
    i[1] = m * (s2[0] + s2[2]) / 12;
    i[2] = m * (s2[0] + s2[1]) / 12;
    return store_axes("box", m, i, mass, message);
}

tb_status tb_mass_cylinder(double rho, double radius, double length, tb_mass *mass, char *message)
{
    double m, i[3];
    if (!mass)
        return refuse_null_mass("tb_mass_cylinder", message);
    if (!positive(rho))
        return fail(message, TB_ERR_ARGUMENT, "cylinder density must be finite and > 0 (got %g)", rho);
    if (!positive(radius))
        return fail(message, TB_ERR_ARGUMENT, "cylinder radius must be finite and > 0 (got %g)", radius);
    if (!positive(length))
        return fail(message, TB_ERR_ARGUMENT, "cylinder length must be finite and > 0 (got %g)", length);
    m = rho * pi * radius * radius * length;
    i[0] = i[1] = m * (3 * radius * radius + length * length) / 12;
    i[2] = 0.5 * m * radius * radius;
    return store_axes("cylinder", m, i, mass, message);
}

/* The cylinder part plus two hemispheres. A solid hemisphere of mass h has
   its centre of mass 3r/8 from its flat face, and about that centre a moment
   (2/5 - 9/64) h r^2 = 83/320 h r^2 perpendicular to its axis (2/5 h r^2
   about the face, moved by the parallel-axis theorem); each cap's centre
   lies l/2 + 3r/8 from the capsule's. Along the axis, the two caps together
   are a sphere. A length of 0 is a sphere. */
tb_status tb_mass_capsule(double rho, double radius, double length, tb_mass *mass, char *message)
{
    double mc, ms, d, i[3];
    if (!mass)
        return refuse_null_mass("tb_mass_capsule", message);
    if (!positive(rho))
        return fail(message, TB_ERR_ARGUMENT, "capsule density must be finite and > 0 (got %g)", rho);
    if (!positive(radius))
        return fail(message, TB_ERR_ARGUMENT, "capsule radius must be finite and > 0 (got %g)", radius);
    if (!(isfinite(length) && length >= 0))
        return fail(message, TB_ERR_ARGUMENT, "capsule length must be finite and >= 0 (got %g)", length);
    mc = rho * pi * radius * radius * length;               /* cylinder */
    ms = rho * (4.0 / 3.0) * pi * radius * radius * radius; /* both caps */
    d = 0.5 * length + 0.375 * radius;
    i[0] = i[1] = mc * (3 * radius * radius + length * length) / 12 + ms * (83.0 / 320.0 * radius * radius + d * d);
    i[2] = 0.5 * mc * radius * radius + 0.4 * ms * radius * radius;
    return store_axes("capsule", mc + ms, i, mass, message);
}

/* ---- tensors ---------------------------------------------------------------- */

/* The smallest moment, relative to the largest, that a tensor summed from n
   terms can resolve: each term rounds by about eps of the largest moment, and
   by Weyl's inequality an error E in the entries moves every eigenvalue by up
   to |E|. Below 1e-12 (a rod a million times longer than it is thick) a
   body is too slender to simulate in any case. */
static double summed_floor(size_t n)
{
    return fmax(1e-12, 4 * (double)n * DBL_EPSILON);
}

/* Store mass, centre and the principal form of a symmetric tensor, refusing
   a tensor whose smallest moment is at most `min_ratio` times its largest (see
   summed_floor) with the reason `singular`. `what` names the caller. */
static tb_status store_tensor(const char *what, double m, const double centre[3], const double tensor[9],
                              double min_ratio, const char *singular, tb_mass *out, char *message)
{
    tb_mass r;
    int k;
    for (k = 0; k < 9; ++k)
        if (!isfinite(tensor[k]))
            return fail(message, TB_ERR_ARGUMENT, "%s: inertia tensor is not finite", what);
    if (!in_scale(m))
        return fail(message, TB_ERR_ARGUMENT, "%s: mass is not representable (%g; it must be from %g to %g)", what,
                    m, 1 / TB_LIMIT, TB_LIMIT);
    for (k = 0; k < 3; ++k)
        if (!(fabs(centre[k]) <= TB_LIMIT))
            return fail(message, TB_ERR_ARGUMENT, "%s: centre of mass %g is past the limit %g", what, centre[k],
                        TB_LIMIT);
    principal(tensor, r.inertia, r.frame);
    if (!(r.inertia[0] > min_ratio * r.inertia[2]) || !(r.inertia[2] > 0))
        return fail(message, TB_ERR_ARGUMENT,
                    "%s: %s (principal moments %g %g %g)", what, singular, r.inertia[0], r.inertia[1], r.inertia[2]);
    /* With moments ascending only I1 + I2 >= I3 can fail. The tolerance lets
       a flat plate (I3 = I1 + I2 up to rounding) pass. */
    if (r.inertia[0] + r.inertia[1] < r.inertia[2] * (1 - tensor_tolerance))
        return fail(message, TB_ERR_ARGUMENT,
                    "%s: principal moments %g %g %g break the triangle inequality I1 + I2 >= I3", what,
                    r.inertia[0], r.inertia[1], r.inertia[2]);
    if (!in_scale(r.inertia[0]) || !in_scale(r.inertia[2]))
        return fail(message, TB_ERR_ARGUMENT, "%s: principal moments %g %g %g are not from %g to %g", what,
                    r.inertia[0], r.inertia[1], r.inertia[2], 1 / TB_LIMIT, TB_LIMIT);
    r.mass = m;
    memcpy(r.centre, centre, sizeof r.centre);
    *out = r;
    return TB_OK;
}

/* The inertia tensor of a mass distribution about its centre from its
   second moments C = integral of rho r r^T: I = tr(C) 1 - C. */
static void inertia_of_covariance(const double c[9], double t[9])
{
    const double trace = c[0] + c[4] + c[8];
    int k;
    for (k = 0; k < 9; ++k)
        t[k] = (k % 4 == 0 ? trace : 0) - c[k];
}

tb_status tb_mass_from_tensor(double total_mass, const double centre[3], const double tensor[9], tb_mass *mass,
                              char *message)
{
    double sym[9], norm = 0, worst = 0;
    int i, j;
    if (!mass)
        return refuse_null_mass("tb_mass_from_tensor", message);
    if (!positive(total_mass))
        return fail(message, TB_ERR_ARGUMENT, "mass must be finite and > 0 (got %g)", total_mass);
    if (!centre || !tensor)
        return fail(message, TB_ERR_ARGUMENT, "centre and tensor must not be NULL");
    for (i = 0; i < 3; ++i)
        if (!isfinite(centre[i]))
            return fail(message, TB_ERR_ARGUMENT, "centre of mass is not finite");
    for (i = 0; i < 9; ++i) {
        if (!isfinite(tensor[i]))
            return fail(message, TB_ERR_ARGUMENT, "inertia tensor is not finite (entry %d is %g)", i, tensor[i]);
        norm = fmax(norm, fabs(tensor[i]));
    }
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            worst = fmax(worst, fabs(tensor[3 * i + j] - tensor[3 * j + i]));
            /* Average the two halves: the rounding in a tensor built as
               R D R^T need not be symmetric, and Jacobi reads one half. */
            sym[3 * i + j] = 0.5 * tensor[3 * i + j] + 0.5 * tensor[3 * j + i];
        }
    if (worst > tensor_tolerance * norm)
        return fail(message, TB_ERR_ARGUMENT, "inertia tensor is not symmetric (entries differ by %g of %g)", worst,
                    norm);
    /* A user tensor is exact as given: only moments in its own rounding
       (a few eps of the largest) are refused as singular. */
    return store_tensor("tb_mass_from_tensor", total_mass, centre, sym, 16 * DBL_EPSILON,
                        "inertia tensor is not positive definite", mass, message);
}

tb_status tb_mass_set_total(tb_mass *mass, double total_mass, char *message)
{
    double scale, inertia[3];
    int k;
    if (!mass)
        return refuse_null_mass("tb_mass_set_total", message);
    if (!in_scale(total_mass))
        return fail(message, TB_ERR_ARGUMENT, "total mass must be finite and > 0, from %g to %g (got %g)",
                    1 / TB_LIMIT, TB_LIMIT, total_mass);
    if (!positive(mass->mass))
        return fail(message, TB_ERR_ARGUMENT, "current mass must be finite and > 0 (got %g)", mass->mass);
    scale = total_mass / mass->mass;
    for (k = 0; k < 3; ++k) {
        inertia[k] = mass->inertia[k] * scale;
        if (!positive(mass->inertia[k]) || !in_scale(inertia[k]))
            return fail(message, TB_ERR_ARGUMENT, "moment %d (%g kg m^2) cannot be scaled by %g", k,
                        mass->inertia[k], scale);
    }
    mass->mass = total_mass;
    memcpy(mass->inertia, inertia, sizeof inertia);
    return TB_OK;
}

/* ---- point masses ----------------------------------------------------------- */

tb_status tb_mass_points(size_t count, const double *positions, const double *masses, tb_mass *mass,
                         char *message)
{
    double total = 0, centre[3] = { 0, 0, 0 }, cov[9] = { 0 }, tensor[9];
    size_t n;
    int i, j;
    if (!mass)
        return refuse_null_mass("tb_mass_points", message);
    if (count == 0 || !positions || !masses)
        return fail(message, TB_ERR_ARGUMENT, "points need a count > 0 and non-NULL positions and masses");
    for (n = 0; n < count; ++n) {
        if (!positive(masses[n]))
            return fail(message, TB_ERR_ARGUMENT, "point %zu: mass must be finite and > 0 (got %g)", n, masses[n]);
        for (i = 0; i < 3; ++i)
            if (!isfinite(positions[3 * n + i]))
                return fail(message, TB_ERR_ARGUMENT, "point %zu: position is not finite", n);
        total += masses[n];
        for (i = 0; i < 3; ++i)
            centre[i] += masses[n] * positions[3 * n + i];
    }
    if (!isfinite(total) || !isfinite(centre[0]) || !isfinite(centre[1]) || !isfinite(centre[2]))
        return fail(message, TB_ERR_ARGUMENT, "points: total mass or first moment overflows");
    for (i = 0; i < 3; ++i)
        centre[i] /= total;
    /* Second pass about the centre, not the origin: I = sum m p p^T - M c c^T
       would cancel catastrophically for a body far from the origin. */
    for (n = 0; n < count; ++n) {
        const double r[3] = { positions[3 * n] - centre[0], positions[3 * n + 1] - centre[1],
                              positions[3 * n + 2] - centre[2] };
        for (i = 0; i < 3; ++i)
            for (j = 0; j < 3; ++j)
                cov[3 * i + j] += masses[n] * r[i] * r[j];
    }
    inertia_of_covariance(cov, tensor);
    /* Collinear points have I1 = 0 exactly, but it computes as
       tr(C) - lambda_max(C), which cancels to rounding. */
    return store_tensor("tb_mass_points", total, centre, tensor, summed_floor(count),
                        "the points are collinear or fewer than 3, so the tensor is singular", mass, message);
}

/* ---- closed triangle meshes ------------------------------------------------- */

static int compare_edges(const void *a, const void *b)
{
    const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Every directed edge (a, b) must occur exactly once and its reverse (b, a)
   exactly once: then the mesh is closed and its triangles agree on which
   side is out. Sorting the 3T directed edges finds both in O(T log T). */
static tb_status check_closed(size_t triangle_count, const uint32_t *triangles, char *message)
{
    const size_t n = 3 * triangle_count;
    uint64_t *edges;
    size_t k;
    tb_status st = TB_OK;
    if (triangle_count > SIZE_MAX / (3 * sizeof *edges))
        return fail(message, TB_ERR_MEMORY, "mesh: %zu triangles do not fit in memory", triangle_count);
    edges = malloc(n * sizeof *edges);
    if (!edges)
        return fail(message, TB_ERR_MEMORY, "mesh: out of memory for the edge check (%zu triangles)",
                    triangle_count);
    for (k = 0; k < n; ++k) {
        const uint32_t a = triangles[k], b = triangles[k % 3 == 2 ? k - 2 : k + 1];
        edges[k] = (uint64_t)a << 32 | b;
    }
    qsort(edges, n, sizeof *edges, compare_edges);
    for (k = 0; k < n && st == TB_OK; ++k) {
        const uint64_t reverse = edges[k] << 32 | edges[k] >> 32;
        const unsigned long a = (unsigned long)(edges[k] >> 32), b = (unsigned long)(edges[k] & 0xffffffffu);
        if (k + 1 < n && edges[k + 1] == edges[k])
            st = fail(message, TB_ERR_ARGUMENT,
                      "mesh: edge %lu->%lu occurs twice (triangles inconsistently oriented, or an edge "
                      "shared by more than two triangles)", a, b);
        else if (!bsearch(&reverse, edges, n, sizeof *edges, compare_edges))
            st = fail(message, TB_ERR_ARGUMENT,
                      "mesh: edge %lu->%lu has no opposite edge %lu->%lu (the mesh is open or "
                      "inconsistently oriented)", a, b, b, a);
    }
    free(edges);
    return st;
}

/* Volume integrals by the divergence theorem, cut into tetrahedra: each
   triangle (a, b, c) and a reference point o span a tetrahedron of signed
   volume det[a b c] / 6 (positions relative to o), and the signed volumes
   of a closed mesh add up to its volume wherever o is. Over a tetrahedron
   with vertices p0..p3, volume V and s = sum p_k:
     integral of x     = V s / 4,
     integral of x x^T = V / 20 (sum p_k p_k^T + s s^T).
   With o at the mean corner the terms stay the size of the body, so a
   mesh far from the origin loses no precision. */
tb_status tb_mass_mesh(double rho, size_t vertex_count, const double *vertices, size_t triangle_count,
                       const uint32_t *triangles, tb_mass *mass, char *message)
{
    double o[3] = { 0, 0, 0 }, six_volume = 0, bound = 0, first[3] = { 0, 0, 0 }, second[9] = { 0 };
    double volume, g[3], cov[9], tensor[9];
    size_t t, k;
    int i, j;
    tb_status st;
    if (!mass)
        return refuse_null_mass("tb_mass_mesh", message);
    if (!positive(rho))
        return fail(message, TB_ERR_ARGUMENT, "mesh density must be finite and > 0 (got %g)", rho);
    if (triangle_count == 0 || !triangles || !vertices)
        return fail(message, TB_ERR_ARGUMENT, "mesh needs triangles and non-NULL vertex and index arrays");
    for (k = 0; k < vertex_count; ++k)
        for (i = 0; i < 3; ++i)
            if (!isfinite(vertices[3 * k + i]))
                return fail(message, TB_ERR_ARGUMENT, "mesh: vertex %zu is not finite", k);
    for (t = 0; t < triangle_count; ++t) {
        const uint32_t *v = triangles + 3 * t;
        for (i = 0; i < 3; ++i)
            if (v[i] >= vertex_count)
                return fail(message, TB_ERR_ARGUMENT, "mesh: triangle %zu uses vertex %lu of only %zu", t,
                            (unsigned long)v[i], vertex_count);
        if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0])
            return fail(message, TB_ERR_ARGUMENT, "mesh: triangle %zu repeats a vertex", t);
    }
    st = check_closed(triangle_count, triangles, message);
    if (st != TB_OK)
        return st;

    for (t = 0; t < 3 * triangle_count; ++t)
        for (i = 0; i < 3; ++i)
            o[i] += vertices[3 * (size_t)triangles[t] + i];
    for (i = 0; i < 3; ++i)
        o[i] /= (double)(3 * triangle_count);

    for (t = 0; t < triangle_count; ++t) {
        double p[3][3], s[3], d;
        for (k = 0; k < 3; ++k)
            for (i = 0; i < 3; ++i)
                p[k][i] = vertices[3 * (size_t)triangles[3 * t + k] + i] - o[i];
        d = p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1]) - p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0])
            + p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0]);
        six_volume += d;
        /* Hadamard: |det| <= |a| |b| |c|; it scales the rounding of the sum. */
        bound += sqrt(p[0][0] * p[0][0] + p[0][1] * p[0][1] + p[0][2] * p[0][2])
                 * sqrt(p[1][0] * p[1][0] + p[1][1] * p[1][1] + p[1][2] * p[1][2])
                 * sqrt(p[2][0] * p[2][0] + p[2][1] * p[2][1] + p[2][2] * p[2][2]);
        for (i = 0; i < 3; ++i) {
            s[i] = p[0][i] + p[1][i] + p[2][i];
            first[i] += d * s[i];
        }
        for (i = 0; i < 3; ++i)
            for (j = i; j < 3; ++j)
                second[3 * i + j] += d * (p[0][i] * p[0][j] + p[1][i] * p[1][j] + p[2][i] * p[2][j] + s[i] * s[j]);
    }
    /* The sum carries rounding of about eps |a||b||c| per term and a closed
       flat mesh cancels to that: a volume under 1e-10 of the bound (a body
       1e-10 times thinner than it is wide) cannot be told from zero. */
    if (!isfinite(six_volume) || !isfinite(bound))
        return fail(message, TB_ERR_ARGUMENT, "mesh: volume integrals overflow");
    if (fabs(six_volume) <= 1e-10 * bound)
        return fail(message, TB_ERR_ARGUMENT, "mesh encloses no volume (flat or degenerate): %g m^3",
                    six_volume / 6);
    if (six_volume < 0)
        return fail(message, TB_ERR_ARGUMENT,
                    "mesh is inside out (volume %g m^3): triangles must be counter-clockwise seen from outside",
                    six_volume / 6);

    volume = six_volume / 6;
    for (i = 0; i < 3; ++i)
        g[i] = first[i] / (4 * six_volume); /* (first / 24) / volume */
    /* Second moments about the centroid: about o less V g g^T. */
    for (i = 0; i < 3; ++i)
        for (j = i; j < 3; ++j)
            cov[3 * i + j] = cov[3 * j + i] = rho * (second[3 * i + j] / 120 - volume * g[i] * g[j]);
    inertia_of_covariance(cov, tensor);
    for (i = 0; i < 3; ++i)
        g[i] += o[i];
    return store_tensor("tb_mass_mesh", rho * volume, g, tensor, summed_floor(triangle_count),
                        "the mesh is too slender to resolve its inertia", mass, message);
}
