/* body_math.h: small vector, quaternion and matrix helpers shared by the
   body tier (bodies.c, body_step.c) and what moves bodies around it
   (contact.c, auto.c). q = (w, x, y, z). Internal. */
#ifndef TB_BODY_MATH_H
#define TB_BODY_MATH_H

#include "rotation.h"

#include <math.h>
#include <string.h>

/* Rotation matrix (row-major) of a unit quaternion. */
static inline void matrix_of(const double q[4], double R[9])
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

static inline void mul(const double R[9], const double v[3], double out[3])
{
    out[0] = R[0] * v[0] + R[1] * v[1] + R[2] * v[2];
    out[1] = R[3] * v[0] + R[4] * v[1] + R[5] * v[2];
    out[2] = R[6] * v[0] + R[7] * v[1] + R[8] * v[2];
}

static inline void mul_transposed(const double R[9], const double v[3], double out[3])
{
    out[0] = R[0] * v[0] + R[3] * v[1] + R[6] * v[2];
    out[1] = R[1] * v[0] + R[4] * v[1] + R[7] * v[2];
    out[2] = R[2] * v[0] + R[5] * v[1] + R[8] * v[2];
}

static inline void quat_mul(const double a[4], const double b[4], double out[4])
{
    double r[4];
    r[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    r[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    r[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    r[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    memcpy(out, r, sizeof r);
}

static inline void normalise(double q[4])
{
    const double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    q[0] /= n, q[1] /= n, q[2] /= n, q[3] /= n;
}

/* q <- q / |q| after a generic step (project). Three Newton steps for
   1 / |q| from 1 are exact to rounding (7e-18) while |q|^2 is within 1e-2
   of 1, which it is after any step a method keeps stable, and they
   vectorise, where sqrt (which may set errno) does not; a q further off is
   divided by its root. newton_scale returns the factor and |q|^2. */
TB__LANE double newton_scale(const double q[4], double *n2)
{
    double f;
    *n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
    f = 1.5 - 0.5 * *n2;
    f = f * (1.5 - 0.5 * *n2 * f * f);
    return f * (1.5 - 0.5 * *n2 * f * f);
}

#define PROJECT_NEAR(n2) (fabs((n2) - 1) <= 1e-2)

static inline int project_near(double q[4])
{
    double n2;
    const double f = newton_scale(q, &n2);
    if (!PROJECT_NEAR(n2))
        return 0;
    q[0] *= f, q[1] *= f, q[2] *= f, q[3] *= f;
    return 1;
}

static inline void project_far(double q[4])
{
    const double f = 1 / sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    q[0] *= f, q[1] *= f, q[2] *= f, q[3] *= f;
}

static inline void project(double q[4])
{
    if (!project_near(q))
        project_far(q);
}

/* w = R diag(scale) R^T v: with scale = 1/I it turns L into w, with I the
   other way. `q` need not be exactly unit (RK stages): it is normalised. */
static inline void through_inertia(const double q[4], const double scale[3], const double v[3], double out[3])
{
    double u[4], R[9], b[3];
    memcpy(u, q, sizeof u);
    normalise(u);
    matrix_of(u, R);
    mul_transposed(R, v, b);
    b[0] *= scale[0], b[1] *= scale[1], b[2] *= scale[2];
    mul(R, b, out);
}

static inline double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline double norm3(const double a[3])
{
    return sqrt(dot3(a, a));
}

static inline void cross(const double a[3], const double b[3], double out[3])
{
    double r[3];
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
    memcpy(out, r, sizeof r);
}

#endif
