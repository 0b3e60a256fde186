/* cold_start.c: a first guess for a step whose contacts start without
   last step's impulses (a scene just built, a crowd landing).

   Sequential impulses spread a load down a chain of contacts slowly: the
   moments that hold an offset stack up must travel from the top box to
   the ground through every patch, and 20 sweeps a step (or the few
   hundred a cold step may take) leave them far short. A staircase of 8
   boxes 5 cm apart got 4% of the moment its ground patch needed from its
   first step, rocked onto edges and fell; given the right moments it
   stands (0.2 mm in 10 s), because the warm starts then carry them.

   So before the sweeps, the normal rows (every lane's press, and its
   tilts that have a range of levers) are solved as equalities, A x = b
   with A = J M^-1 J^T, by conjugate gradients preconditioned by the rows'
   own masses (Jacobi). A resting scene's answer is that system's: every
   contact pressed, no friction needed, each centre of pressure inside
   its points. Conjugate gradients reach it in some sqrt(cond A)
   iterations where Gauss-Seidel takes cond A. The result is clamped to
   what the rows allow (press >= 0, tilts within the press times their
   levers' range) and pushed on the velocities; the sweeps then take
   friction, and whatever the clamp left, from there. */
#include "contact.h"

#include <math.h>
#include <string.h>

#define ROWS (TB__PATCH_ROWS * TB__BATCH_LANES)

/* Each row's mass where the cold start solves it, 0 elsewhere: the
   Jacobi preconditioner, and the mask of the rows taking part. */
static void row_masses(const tb__contacts *c, double *mass)
{
    size_t b;
    int row, k;
    for (b = 0; b < c->batch_count; ++b) {
        const tb__batch *bt = &c->batches[b];
        double *out = mass + b * ROWS;
        memset(out, 0, ROWS * sizeof *out);
        for (k = 0; k < TB__BATCH_LANES; ++k) {
            out[TB__ROW_PRESS * TB__BATCH_LANES + k] = bt->mass[TB__ROW_PRESS][k];
            for (row = 0; row < 2; ++row)
                if (bt->tilting && bt->tilt_high[row][k] > bt->tilt_low[row][k])
                    out[(TB__ROW_TILT1 + row) * TB__BATCH_LANES + k] = bt->mass[TB__ROW_TILT1 + row][k];
        }
    }
}

/* The velocity change of impulses p on every row, J M^-1 J^T p, into q;
   on c->motion, which holds zeros and inverse masses before the position
   pass and is left so. */
static void apply_rows(tb__contacts *c, const double *p, double *q)
{
    size_t i;
    tb__push_rows(c->batches, c->batch_count, c->motion, p, c->isa);
    tb__row_rates(c->batches, c->batch_count, c->motion, q, c->isa);
    for (i = 0; i <= c->body_count; ++i)
        memset(c->motion + TB__MOTION * i, 0, 6 * sizeof *c->motion);
}

static double dot(const double *a, const double *b, size_t n)
{
    double sum = 0;
    size_t i;
    for (i = 0; i < n; ++i)
        sum += a[i] * b[i];
    return sum;
}

/* The most any solved row's velocity misses its target by. */
static double worst(const double *r, const double *mass, size_t n)
{
    double most = 0;
    size_t i;
    for (i = 0; i < n; ++i)
        if (mass[i] > 0 && fabs(r[i]) > most)
            most = fabs(r[i]);
    return most;
}

/* The solution x clamped into the batches' impulses; x becomes what they
   changed by, for pushing. */
static void clamp_into(tb__contacts *c, double *x)
{
    size_t b;
    int k, d;
    for (b = 0; b < c->batch_count; ++b) {
        tb__batch *bt = &c->batches[b];
        double *dx = x + b * ROWS;
        for (k = 0; k < TB__BATCH_LANES; ++k) {
            double *press = &bt->impulse[TB__ROW_PRESS][k];
            const double now = fmax(0, *press + dx[TB__ROW_PRESS * TB__BATCH_LANES + k]);
            dx[TB__ROW_PRESS * TB__BATCH_LANES + k] = now - *press;
            *press = now;
            for (d = 0; d < 2; ++d) {
                double *tilt = &bt->impulse[TB__ROW_TILT1 + d][k];
                double *step = &dx[(TB__ROW_TILT1 + d) * TB__BATCH_LANES + k];
                const double low = now * bt->tilt_low[d][k], high = now * bt->tilt_high[d][k];
                double turn = *tilt + *step;
                turn = turn > high ? high : turn < low ? low : turn;
                *step = turn - *tilt;
                *tilt = turn;
            }
        }
    }
}

int tb__cold_start(tb__contacts *c, int most, double tolerance)
{
    const size_t n = c->batch_count * ROWS;
    double *x = c->cold_rows, *r = x + n, *z = r + n, *p = z + n, *q = p + n, *mass = q + n, *best = mass + n;
    double rz, pq, alpha, beta, miss, least;
    size_t i, b;
    int it, found = 0;
    if (n == 0)
        return 0;
    row_masses(c, mass);
    tb__row_rates(c->batches, c->batch_count, c->velocity, q, c->isa);
    for (b = 0; b < c->batch_count; ++b)
        for (i = 0; i < ROWS; ++i) {
            const size_t j = b * ROWS + i;
            const double target =
                i / TB__BATCH_LANES == TB__ROW_PRESS ? c->batches[b].press_target[i % TB__BATCH_LANES] : 0;
            r[j] = mass[j] > 0 ? target - q[j] : 0;
        }
    for (i = 0; i < n; ++i) {
        x[i] = 0;
        p[i] = z[i] = mass[i] * r[i];
    }
    rz = dot(r, z, n);
    /* past rounding's reach the directions lose their meaning and the
       steps grow without bound (with tolerance 0, 320 iterations threw a
       pyramid 1e12 m): no further than 1e-13 of where the misses began.
       Rows that cannot all be met (two patches on one body asking for
       different speeds) leave a miss that does not shrink: the iterate
       that missed least is the one taken, and 20 iterations that miss
       more end the search (60 bodies built overlapping took the whole
       320 iterations in 6 steps of their first 2 s, to no use). */
    least = miss = worst(r, mass, n);
    tolerance = fmax(tolerance, 1e-13 * miss);
    memset(best, 0, n * sizeof *best);
    for (it = 0; it < most && miss > tolerance && it - found <= 20; ++it) {
        apply_rows(c, p, q);
        pq = dot(p, q, n);
        if (!(pq > 0))
            break;
        alpha = rz / pq;
        if (!isfinite(alpha))
            break;
        for (i = 0; i < n; ++i) {
            x[i] += alpha * p[i];
            r[i] = mass[i] > 0 ? r[i] - alpha * q[i] : 0;
            z[i] = mass[i] * r[i];
        }
        beta = dot(r, z, n) / rz;
        rz *= beta;
        for (i = 0; i < n; ++i)
            p[i] = z[i] + beta * p[i];
        if ((miss = worst(r, mass, n)) < least) {
            least = miss, found = it + 1;
            memcpy(best, x, n * sizeof *best);
        }
    }
    x = best;
    /* (a guess only: one that is not finite is not taken) */
    if (!isfinite(dot(x, x, n)))
        return it;
    clamp_into(c, x);
    tb__push_rows(c->batches, c->batch_count, c->velocity, x, c->isa);
    return it;
}
