/* cold_start.c: the normal rows of every contact solved together, by
   conjugate gradients, before the sweeps.

   Sequential impulses pass a load down a chain of contacts a pair at a
   time: the moments that hold an offset stack up must travel from the
   top box to the ground through every patch, and 20 sweeps a step (or
   the few hundred a cold step may take) leave them far short. A
   staircase of 8 boxes 5 cm apart got 4% of the moment its ground patch
   needed from its first step, rocked onto edges and fell; given the
   right moments it stands, because the warm starts then carry them. And
   a slow lean of a whole stack, or a heavy body's weight through a light
   one, is what the sweeps reduce slowest: kept awake, 3 of 40 random
   offset stacks leaned by 1% more a step and fell, and a box 1000 times
   heavier than the one under it went through it.

   So every pair's press and its tilts that have a range of levers are
   solved as equalities, A x = b with A = J M^-1 J^T, by conjugate
   gradients preconditioned by the rows' own masses (Jacobi), from the
   warm starts: a resting scene's answer is that system's (every contact
   pressed, each centre of pressure inside its points, no friction
   needed), which they reach in some sqrt(cond A) iterations where
   Gauss-Seidel takes cond A. A step that starts cold at rest solves it
   through; other steps take stack_iterations of them (2), which cost
   about 5% of a resting pyramid's step. The result is clamped to what
   the rows allow (press >= 0, tilts within the press times their levers'
   range) and pushed on the velocities; the sweeps then take friction,
   and whatever the clamp left, from there. */
#include "contact.h"

#include <math.h>
#include <string.h>

#define ROWS (TB__NORMAL_ROWS * TB__BATCH_LANES)

/* Each normal row's mass where the cold start solves it, 0 elsewhere:
   the Jacobi preconditioner, and the mask of the rows taking part (every
   lane's press; its tilts that have a range of levers). */
static void row_masses(const tb__contacts *c, double *mass)
{
    size_t b;
    int d, k;
    for (b = 0; b < c->batch_count; ++b) {
        const tb__batch *bt = &c->batches[b];
        double *out = mass + b * ROWS;
        for (k = 0; k < TB__BATCH_LANES; ++k) {
            out[k] = bt->mass[TB__ROW_PRESS][k];
            for (d = 0; d < 2; ++d)
                out[(1 + d) * TB__BATCH_LANES + k] = bt->tilting && bt->tilt_high[d][k] > bt->tilt_low[d][k]
                                                         ? bt->mass[TB__ROW_TILT1 + d][k]
                                                         : 0;
        }
    }
}

/* The velocity change of impulses p on every row, J M^-1 J^T p, into q;
   on c->motion, which holds zeros and inverse masses before the position
   pass and is left so. */
static void apply_rows(tb__contacts *c, const double *p, double *q)
{
    size_t i;
    tb__push_normal_rows(c->batches, c->batch_count, c->motion, p, c->isa);
    tb__normal_rates(c->batches, c->batch_count, c->motion, q, c->isa);
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
            const double now = fmax(0, *press + dx[k]);
            dx[k] = now - *press;
            *press = now;
            for (d = 0; d < 2; ++d) {
                double *tilt = &bt->impulse[TB__ROW_TILT1 + d][k];
                double *step = &dx[(1 + d) * TB__BATCH_LANES + k];
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
    double *x = c->cold_rows, *r = x + n, *z = r + n, *p = z + n, *q = p + n, *mass = q + n;
    double rz, pq, alpha, beta, miss, least, next;
    size_t i, b;
    int it, found = 0;
    if (n == 0)
        return 0;
    row_masses(c, mass);
    tb__normal_rates(c->batches, c->batch_count, c->velocity, q, c->isa);
    for (b = 0; b < c->batch_count; ++b)
        for (i = 0; i < ROWS; ++i) {
            const size_t j = b * ROWS + i;
            const double target = i < TB__BATCH_LANES ? c->batches[b].press_target[i] : 0;
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
       different speeds) leave a miss that does not shrink, and the
       iterates drift along what A cannot change: 20 iterations without a
       smaller largest miss end the search (60 bodies built overlapping
       took the whole 320 iterations in 6 steps of their first 2 s, to no
       use). The last iterate is taken: conjugate gradients shrink the
       error in A's norm, not the largest miss, and the iterate with the
       smallest miss held 38 of 40 offset stacks where the last held all. */
    least = miss = worst(r, mass, n);
    tolerance = fmax(tolerance, 1e-13 * miss);
    for (it = 0; it < most && miss > tolerance && it - found <= 20; ++it) {
        apply_rows(c, p, q);
        pq = dot(p, q, n);
        if (!(pq > 0))
            break;
        alpha = rz / pq;
        if (!isfinite(alpha))
            break;
        next = 0, miss = 0;
        for (i = 0; i < n; ++i) {
            x[i] += alpha * p[i];
            r[i] = mass[i] > 0 ? r[i] - alpha * q[i] : 0;
            z[i] = mass[i] * r[i];
            next += r[i] * z[i];
            miss = fabs(r[i]) > miss ? fabs(r[i]) : miss;
        }
        beta = next / rz;
        rz = next;
        for (i = 0; i < n; ++i)
            p[i] = z[i] + beta * p[i];
        if (miss < least)
            least = miss, found = it + 1;
    }
    /* (nothing to add to the sweeps' own start; or a guess that is not
       finite: none taken) */
    if (it == 0 || !isfinite(dot(x, x, n)))
        return it;
    clamp_into(c, x);
    tb__push_normal_rows(c->batches, c->batch_count, c->velocity, x, c->isa);
    return it;
}
