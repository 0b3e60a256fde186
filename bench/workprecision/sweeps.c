/* sweeps.c: the curves of a scene, one a method: the step sweep of a
   fixed-step method or the tolerance sweep of an adaptive one, the timing
   of their points, the fitted orders, and the costs read off the curves at
   an error level. */
#include "workprecision.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define MIN_POINTS 8         /* points of a fixed-step sweep before it may stop at the floor */
#define RUN_CAP 0.4          /* s: no run in a sweep takes longer (this keeps the whole to a few minutes) */
#define SAMPLE_SECONDS 2e-3  /* a timing sample repeats short runs until it has this much stepping */

typedef char slots_hold_a_sweep[SLOTS >= MAX_POINTS && SLOTS >= TOLERANCES ? 1 : -1];

/* The error of one point, from its first run (which also warms caches and
   allocations and tells how long a run takes). Timing comes later, in
   take_sample(). Short runs get more samples (9, 5 or 3), and repeat within
   a sample until it holds SAMPLE_SECONDS of stepping; a long first run
   counts as one sample itself. */
static point first_run(const scene *s, const series *m, long n, double tolerance)
{
    const double h = s->duration / (double)n;
    double state[3 * MAX_PARTICLES];
    point p;
    memset(&p, 0, sizeof p);
    p.steps = n;
    p.h = h;
    p.tolerance = tolerance;
    p.first = timed_run(s, m, h, n, tolerance, &p.done, state, p.plan, &p.substeps);
    p.error = p.done == n ? error_of(s, state, s->final) : NAN;
    p.stable = p.done == n && isfinite(p.error) && p.error <= 1;
    if (!m->adaptive)
        p.evaluations = m->evaluations / h;
    else if (m == &SERIES[DOPRI5] || !strcmp(p.plan, "dopri5"))
        p.evaluations = counted_evaluations(s, h, n, tolerance);
    else {
        int k;
        p.evaluations = NAN;
        for (k = 0; k < SERIES_COUNT; ++k)
            if (!SERIES[k].adaptive && !strcmp(SERIES[k].name, p.plan))
                p.evaluations = (double)SERIES[k].evaluations * (double)p.substeps / h;
    }
    p.want = p.first >= 0.05 ? 3 : p.first >= 0.005 ? 5 : MAX_SAMPLES;
    if (p.first >= 0.05)
        p.sample[p.count++] = p.first;
    p.repeat = p.first >= SAMPLE_SECONDS ? 1 : (int)fmin(1e4, ceil(SAMPLE_SECONDS / fmax(p.first, 1e-7)));
    return p;
}

/* One timing sample of a point: the mean stepping time of p->repeat runs. */
static void take_sample(const scene *s, const series *m, point *p)
{
    double sum = 0;
    long done;
    int k;
    for (k = 0; k < p->repeat; ++k)
        sum += timed_run(s, m, p->h, p->steps, p->tolerance, &done, NULL, NULL, NULL);
    p->sample[p->count++] = sum / p->repeat;
}

/* Cost = median sample / simulated time (of the steps done, for a run that
   stopped early). */
static void finish_point(point *p)
{
    double x[MAX_SAMPLES];
    memcpy(x, p->sample, sizeof x);
    p->cost = p->done > 0 ? median_of(x, p->count) / (p->h * (double)p->done) : NAN;
}

/* Least-squares slope of log error against log h over the asymptotic part
   of a curve: its finest FIT_POINTS stable points with errors between the
   floor (rounding, or the reference's own accuracy) and 1e-2 (0.3 when that
   leaves fewer than three), and before the error stops falling (a halved
   step gaining less than 2^0.5 below 1e-6: rounding has taken over, even if
   above the floor). The finest points, because coarse steps mix in
   higher-order terms: on the stiff chain symplectic Euler falls at order
   1.5 at first and settles to 1. */
#define FIT_POINTS 4
static void fit(curve *c, double floor_error)
{
    double hi = 1e-2;
    int pass, i, stable = 0, below = 0, end = c->count;
    c->order = NAN;
    for (i = 0; i < c->count; ++i)
        if (c->p[i].stable) {
            ++stable;
            below += c->p[i].error < floor_error;
        }
    c->at_floor = stable > 0 && below == stable;
    for (i = 1; i < c->count; ++i) {
        const point *p = &c->p[i], *q = &c->p[i - 1];
        if (p->stable && q->stable && p->error < 1e-6 &&
            log(q->error / p->error) < 0.5 * log(q->h / p->h)) {
            end = i;
            break;
        }
    }
    for (pass = 0; pass < 2; ++pass, hi = 0.3) {
        double sx = 0, sy = 0, sxx = 0, sxy = 0;
        int n = 0;
        for (i = end - 1; i >= 0 && n < FIT_POINTS; --i) {
            const point *p = &c->p[i];
            if (!p->stable || p->error < floor_error || p->error > hi)
                continue;
            sx += log(p->h), sy += log(p->error);
            sxx += log(p->h) * log(p->h), sxy += log(p->h) * log(p->error);
            ++n;
        }
        if (n >= 3 || (pass == 1 && n >= 2)) {
            c->order = (n * sxy - sx * sy) / (n * sxx - sx * sx);
            return;
        }
    }
}

/* The tolerance of point i of a tolerance sweep: 10^(-2 - i / 2). */
double sweep_tolerance(int i)
{
    return pow(10, -2 - 0.5 * i);
}

/* A tolerance sweep at the outer step T / N0: on past 1e-9 (the last level
   the issue asks about) until the error is below the floor, or a run would
   take more than RUN_CAP (each tolerance costs about 10^(1/10) to 10^(1/4)
   times the last, so half of RUN_CAP is the limit, as for the fixed steps). */
static void sweep_tolerances(const scene *s, const series *m, double floor_error, curve *c)
{
    int i;
    for (i = 0; i < TOLERANCES; ++i) {
        const point *p;
        c->p[c->count++] = first_run(s, m, s->coarse, sweep_tolerance(i));
        p = &c->p[c->count - 1];
        if (sweep_tolerance(i) < 1.01e-9 && p->stable && p->error < floor_error)
            break;
        if (2 * p->first > RUN_CAP)
            break;
    }
}

/* The curve of method `m`: a tolerance sweep for an adaptive method, else
   a step sweep from N0 steps, doubling, until the error is below the floor
   (once it has MIN_POINTS points), the next run (twice as long) would take
   more than RUN_CAP, or it has MAX_POINTS points. */
static void sweep(const scene *s, const series *m, double floor_error, curve *c)
{
    long n = s->coarse;
    memset(c, 0, sizeof *c);
    c->used = 1;
    c->adaptive = m->adaptive;
    if (m->adaptive) {
        sweep_tolerances(s, m, floor_error, c);
        return;
    }
    while (c->count < MAX_POINTS) {
        const point *p;
        c->p[c->count++] = first_run(s, m, n, 0);
        p = &c->p[c->count - 1];
        if (c->count >= MIN_POINTS && p->stable && p->error < floor_error)
            break;
        if (2 * p->first > RUN_CAP)
            break;
        n *= 2;
    }
}

/* The timing samples of every point of a scene, in rounds: each round
   takes one sample of every point that still wants one, so a burst of
   noise from the machine (other processes, frequency changes) spreads over
   many points and methods instead of landing on all samples of one. */
void timing(const scene *s, curve curves[SERIES_COUNT])
{
    const double t0 = seconds();
    int round, m, i;
    for (round = 0; round < MAX_SAMPLES; ++round)
        for (m = 0; m < SERIES_COUNT; ++m)
            for (i = 0; curves[m].used && i < curves[m].count; ++i)
                if (curves[m].p[i].count < curves[m].p[i].want)
                    take_sample(s, &SERIES[m], &curves[m].p[i]);
    for (m = 0; m < SERIES_COUNT; ++m)
        for (i = 0; curves[m].used && i < curves[m].count; ++i)
            finish_point(&curves[m].p[i]);
    fprintf(stderr, "  timing %.1f s\n", seconds() - t0);
}

/* The cost at which a curve first reaches `target` error, interpolated in
   log-log between the two measured points that straddle it. *bound is set
   when the method's coarsest stable point is already below the target
   (then the cost given is an upper bound). NaN: not reached in the sweep.
   `evaluations` selects that cost measure instead of wall time. */
double cost_at(const curve *c, double target, int evaluations, int *bound)
{
    int i;
    *bound = 0;
    for (i = 0; i < c->count; ++i) {
        const point *p = &c->p[i], *q = i > 0 ? &c->p[i - 1] : NULL;
        const double cost = evaluations ? p->evaluations : p->cost;
        if (!p->stable || p->error > target)
            continue;
        if (!q || !q->stable || !(q->error > target)) {
            *bound = 1;
            return cost;
        }
        {
            const double qc = evaluations ? q->evaluations : q->cost;
            const double t = (log(target) - log(q->error)) / (log(p->error) - log(q->error));
            return exp(log(qc) + t * (log(cost) - log(qc)));
        }
    }
    return NAN;
}

/* Beyond a curve's finest stable point, along its fitted order: wall cost
   per simulated second goes as 1/h, the error as h^order. Only two decades
   of error past the last measurement, and NaN when there is no order to go
   by: further out it would be a guess. */
double cost_extrapolated(const curve *c, double target)
{
    int i;
    if (!(c->order > 0.5))
        return NAN;
    for (i = c->count - 1; i >= 0; --i)
        if (c->p[i].stable && c->p[i].error > target)
            return c->p[i].error <= 100 * target ? c->p[i].cost * pow(c->p[i].error / target, 1 / c->order) : NAN;
    return NAN;
}

/* The points of a curve whose runs are stable. */
int stable_points(const curve *c)
{
    int i, n = 0;
    for (i = 0; i < c->count; ++i)
        n += c->p[i].stable;
    return n;
}

/* The cheapest fixed-step tumble method at `target` error: its index (-1:
   none reaches it within its measured points), cost and whether that cost
   is an upper bound (*bound, see cost_at). */
int cheapest_fixed(const curve curves[SERIES_COUNT], double target, double *cost, int *bound)
{
    int m, b, best = -1;
    for (m = 0; m < SERIES_COUNT; ++m) {
        double c;
        if (!curves[m].used || SERIES[m].adaptive || SERIES[m].ode)
            continue;
        c = cost_at(&curves[m], target, 0, &b);
        if (isfinite(c) && (best < 0 || c < *cost))
            best = m, *cost = c, *bound = b;
    }
    return best;
}

/* The sweeps of every method of a scene, and their fitted orders, with
   their progress on stderr. Methods the scene's world refuses are left
   out, named in `refusals` with the world's reason. */
void sweep_scene(const scene *s, double floor_error, curve curves[SERIES_COUNT], char *refusals, size_t size)
{
    char reason[TB_MESSAGE_SIZE] = "", message[TB_MESSAGE_SIZE];
    curve *c = curves;
    int m;
    refusals[0] = 0;
    for (m = 0; m < SERIES_COUNT; ++m) {
        const double t = seconds();
        memset(&c[m], 0, sizeof c[m]);
        if (refused(s, &SERIES[m], message, sizeof message)) {
            /* one reason is enough: the split methods fail alike */
            const size_t used = strlen(refusals);
            if (SERIES[m].ode)
                snprintf(refusals + used, size - used, "%s%s (%s)", used ? "; " : "", SERIES[m].name, message);
            else
                snprintf(refusals + used, size - used, "%s%s", used ? ", " : "", SERIES[m].name);
            if (!reason[0] && !SERIES[m].ode)
                snprintf(reason, sizeof reason, "%s", message);
            continue;
        }
        sweep(s, &SERIES[m], floor_error, &c[m]);
        if (!SERIES[m].adaptive)
            fit(&c[m], floor_error);
        else
            c[m].order = NAN;
        if (SERIES[m].adaptive)
            fprintf(stderr, "  %-16s %2d points, tolerance down to %.0e, %.1f s\n", SERIES[m].name, c[m].count,
                    c[m].p[c[m].count - 1].tolerance, seconds() - t);
        else
            fprintf(stderr, "  %-16s %2d points, N up to %ld, %.1f s\n", SERIES[m].name, c[m].count,
                    c[m].p[c[m].count - 1].steps, seconds() - t);
    }
    if (reason[0]) {
        const size_t used = strlen(refusals);
        snprintf(refusals + used, size - used, "; tumble: %s", reason);
    }
}
