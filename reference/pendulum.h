/* pendulum.h: the truth of the pendulum that test_joints, test_ode_joints
   and bench_joints swing (a header only): the period of a sphere of
   radius r and mass m whose centre hangs l from a pivot, released at
   theta0 from the bottom, 4 sqrt(I_p / (m g l)) K(sin(theta0 / 2)) with
   I_p = 2/5 m r^2 + m l^2, and the period read from sampled angles. */
#ifndef TB_REFERENCE_PENDULUM_H
#define TB_REFERENCE_PENDULUM_H

#include <math.h>

/* K(k), the complete elliptic integral of the first kind, by the
   arithmetic-geometric mean (converged to rounding well within 40) */
static inline double ref_elliptic_k(double k)
{
    double a = 1, b = sqrt(1 - k * k);
    int i;
    for (i = 0; i < 40; ++i) {
        const double m = (a + b) / 2;
        b = sqrt(a * b);
        a = m;
    }
    return 3.14159265358979323846 / (2 * a);
}

static inline double ref_pendulum_period(double r, double m, double l, double g, double theta0)
{
    return 4 * sqrt((0.4 * m * r * r + m * l * l) / (m * g * l)) * ref_elliptic_k(sin(theta0 / 2));
}

/* The period from the first and third downward crossings of the bottom
   among angles sampled every h from h on, each placed linearly between
   its two samples (the angle's second derivative is 0 at the bottom:
   the error is the third derivative's, 1e-6 of the period at 60 Hz for a
   1 m pendulum). NAN with fewer than three crossings. */
static inline double ref_crossings_period(const double *angle, int steps, double h)
{
    double at[3];
    int n = 0, s;
    for (s = 1; s < steps && n < 3; ++s)
        if (angle[s - 1] > 0 && angle[s] <= 0)
            at[n++] = (s - 1 + angle[s - 1] / (angle[s - 1] - angle[s])) * h;
    return n == 3 ? (at[2] - at[0]) / 2 : NAN;
}

#endif
