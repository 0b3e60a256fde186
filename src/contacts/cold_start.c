/* cold_start.c: the normal rows (press and tilts) of many lanes solved
   together before the sweeps, where the sweeps pass loads too slowly.

   Sequential impulses pass a load down a chain of contacts a pair at a
   time: the moments that hold an offset stack up must travel from the
   top box to the ground through every patch, and the sweeps of a step
   leave them far short. Given the right moments from its first step, such
   a stack stands, because the warm starts then carry them.

   So the press of every lane concerned and its tilts that have a range of
   levers are solved as equalities, A x = b with A = J M^-1 J^T, by
   conjugate gradients preconditioned by the rows' own masses (Jacobi): a
   resting scene's answer is that system's (every contact pressed, each
   centre of pressure inside its points, no friction needed), which they
   reach in some sqrt(cond A) iterations where Gauss-Seidel takes cond A.
   The result is clamped to what the rows allow (press >= 0, tilts within
   the press times their levers' range) and pushed on the velocities,
   where it met the rows and the clamp left it sound; the sweeps then take
   friction, and whatever is left, from there. It runs on:
   - the lanes at rest, in a step where many contacts start at rest
     without last step's impulses (a scene built touching;
     staircases_stand_still, random_offset_stacks_stand);
   - the lanes at rest, stack_iterations iterations before the sweeps of
     every step that runs neither of the others (none by default): stacks
     of boxes each offset from the one below, kept awake, lean slowly as a
     whole, which the sweeps reduce slowest. 8 hold them
     (awake_offset_stacks_stay_up_with_stack_iterations), for about 40%
     more of an awake pyramid's step (the setting, include/tumble/types.h);
   - the lanes near a body landing on one TB__MASS_RATIO times lighter or
     heavier, in that step and the next, or resting on one
     TB__MASS_RATIO_RESTING times lighter or heavier, landing ones too
     (tb__heavy_landings). The sweeps pass the landing to the light body
     about one mass ratio's part a sweep, so they stop the heavy one late,
     and the landing's warm starts then throw it back up; solved together,
     the landing stops both, and the next step sheds the landing's
     impulses from the warm starts again (heavy_box_lands_on_light_ones).
     Such a solve is taken only where it met its rows, leaves none further
     from what it may do, and takes kinetic energy out (met, it does;
     clamped, it need not). */
#include "contacts/contacts.h"

#include <math.h>
#include <string.h>

#define ROWS (TB__NORMAL_ROWS * TB__BATCH_LANES)

/* Row i of every batch in the solve (tb__batch.in_solve), in order: the
   others take no part, and their rows are not read. */
#define EACH_ROW(c, b, i)                              \
    for ((b) = 0; (b) < (c)->batch_count; ++(b))       \
        if ((c)->batches[(b)].in_solve)                \
            for ((i) = (b) * ROWS; (i) < ((b) + 1) * ROWS; ++(i))

static double dot(const tb__contacts *c, const double *u, const double *v)
{
    double sum = 0;
    size_t b, i;
    EACH_ROW(c, b, i)
    sum += u[i] * v[i];
    return sum;
}

/* Whether lane k of bt is in the heavy landings' solve: landing, and on
   a body of the rings (heavy_rings). */
static int reached(const tb__batch *bt, int k, const uint64_t *ring)
{
    return bt->source[k] && bt->landing[k] && (ring[bt->a[k]] || ring[bt->b[k]]);
}

/* Each normal row's mass where the cold start solves it, 0 elsewhere:
   the Jacobi preconditioner, and the mask of the rows taking part: the
   press of every lane at rest (landings: every lane reached), and its
   tilts that have a range of levers. (Outside the heavy landings, a lane
   that struck or landed this step is left to the sweeps: its speed and
   its lever differ from those of the lanes at rest on the same body, and
   solved with them, the iterates grow pushes and pulls that cancel in
   speed but not in position. So is a lane with a point deeper than the
   slop, or a new one whose sides move faster than the sleep speed:
   bodies built overlapping, or thrown together, are not at rest, and
   solved as if they were, they can be thrown off.) */
static void row_masses(tb__contacts *c, double *mass, int landings)
{
    const uint64_t *ring = c->colours;
    size_t b;
    int d, k;
    for (b = 0; b < c->batch_count; ++b) {
        tb__batch *bt = &c->batches[b];
        double *out = mass + b * ROWS;
        bt->in_solve = !landings;
        for (k = 0; k < TB__BATCH_LANES; ++k) {
            const int resting = landings ? reached(bt, k, ring) : bt->source[k] && bt->resting[k];
            bt->in_solve |= resting;
            out[k] = resting ? bt->mass[TB__ROW_PRESS][k] : 0;
            for (d = 0; d < 2; ++d)
                out[(1 + d) * TB__BATCH_LANES + k] =
                    resting && bt->tilting && bt->tilt_high[d][k] > bt->tilt_low[d][k] ? bt->mass[TB__ROW_TILT1 + d][k]
                                                                                       : 0;
        }
    }
}

/* The landing lanes in the heavy lanes' solve: marked by solver body + 1
   in c->colours (free in the solve), ring 1 for a heavy lane's bodies and
   r + 1 for those a landing lane joins to one of ring r, ring by ring for
   as long as the batches they reach stay within a budget: the load of a
   body landing on a light one goes down whatever is under it, so the
   rings reach as far as the budget lets them
   (heavy_box_lands_on_light_ones: its column of four), but a crowd is not
   solved whole for one landing in it (each step of a falling pile would
   pay for a solve of the whole pile). The solve's cost goes by batches: a
   lane's neighbours are in other batches (they share a body), so a few
   hundred lanes can reach every batch. */
#define TB__HEAVY_BATCHES 32 /* the budget: this many batches, or an eighth of the step's */
static size_t batches_reached(const tb__contacts *c)
{
    const uint64_t *ring = c->colours;
    size_t b, count = 0;
    int k, any;
    for (b = 0; b < c->batch_count; ++b) {
        const tb__batch *bt = &c->batches[b];
        for (k = 0, any = 0; k < TB__BATCH_LANES; ++k)
            any |= reached(bt, k, ring);
        count += (size_t)any;
    }
    return count;
}

static void heavy_rings(tb__contacts *c)
{
    uint64_t *ring = c->colours;
    size_t b, budget;
    uint64_t r;
    int k, grew = 1;
    memset(ring, 0, (c->body_count + 1) * sizeof *ring);
    for (b = 0; b < c->batch_count; ++b)
        for (k = 0; k < TB__BATCH_LANES; ++k) {
            if (c->batches[b].source[k] && c->batches[b].heavy[k])
                ring[c->batches[b].a[k]] = ring[c->batches[b].b[k]] = 1;
        }
    ring[0] = 0;
    budget = c->batch_count / 8 > TB__HEAVY_BATCHES ? c->batch_count / 8 : TB__HEAVY_BATCHES;
    for (r = 1; grew; ++r) {
        grew = 0;
        for (b = 0; b < c->batch_count; ++b)
            for (k = 0; k < TB__BATCH_LANES; ++k) {
                const tb__batch *bt = &c->batches[b];
                const int32_t a = bt->a[k], o = bt->b[k];
                if (!bt->source[k] || !bt->landing[k] || !a || !o)
                    continue;
                if (ring[a] == r && !ring[o])
                    ring[o] = r + 1, grew = 1;
                else if (ring[o] == r && !ring[a])
                    ring[a] = r + 1, grew = 1;
            }
        if (grew && batches_reached(c) > budget) { /* this ring is one too many */
            size_t i;
            for (i = 1; i <= c->body_count; ++i)
                ring[i] = ring[i] == r + 1 ? 0 : ring[i];
            break;
        }
    }
}

/* The velocity change of impulses p on every row, J M^-1 J^T p, into q;
   on c->motion, which holds zeros and inverse masses before the position
   pass and is left so. */
static void apply_rows(tb__contacts *c, const double *p, double *q)
{
    size_t b;
    int k;
    tb__push_normal_rows(c->batches, c->batch_count, c->motion, p, c->isa);
    tb__normal_rates(c->batches, c->batch_count, c->motion, q, c->isa);
    memset(c->motion, 0, 6 * sizeof *c->motion);
    for (b = 0; b < c->batch_count; ++b)
        if (c->batches[b].in_solve)
            for (k = 0; k < TB__BATCH_LANES; ++k) {
                memset(c->motion + TB__MOTION * c->batches[b].a[k], 0, 6 * sizeof *c->motion);
                memset(c->motion + TB__MOTION * c->batches[b].b[k], 0, 6 * sizeof *c->motion);
            }
}

/* The most any solved row's velocity misses its target by. */
static double worst(const tb__contacts *c, const double *r, const double *mass)
{
    double most = 0;
    size_t b, i;
    EACH_ROW(c, b, i)
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
        if (!bt->in_solve)
            continue;
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

/* The most any solved row misses what it may do, with the batches'
   impulses and the rows' rates given: a row within its bounds must meet
   its target, one at a bound may only err the way the bound holds it
   (a press at 0 may separate, a tilt at its limit may turn on). */
static double violation(const tb__contacts *c, const double *rate, const double *mass)
{
    double most = 0;
    size_t b;
    int k, d;
    for (b = 0; b < c->batch_count; ++b) {
        const tb__batch *bt = &c->batches[b];
        const double *row = rate + b * ROWS, *m = mass + b * ROWS;
        for (k = 0; k < TB__BATCH_LANES; ++k) {
            const double press = bt->impulse[TB__ROW_PRESS][k];
            double e = row[k] - bt->press_target[k], miss;
            if (m[k] > 0) {
                miss = press <= 0 ? fmax(0, -e) : fabs(e);
                most = fmax(most, miss);
            }
            for (d = 0; d < 2; ++d) {
                const double tilt = bt->impulse[TB__ROW_TILT1 + d][k];
                if (!(m[(1 + d) * TB__BATCH_LANES + k] > 0))
                    continue;
                e = row[(1 + d) * TB__BATCH_LANES + k];
                miss = tilt <= press * bt->tilt_low[d][k]    ? fmax(0, -e)
                       : tilt >= press * bt->tilt_high[d][k] ? fmax(0, e)
                                                             : fabs(e);
                most = fmax(most, miss);
            }
        }
    }
    return most;
}

/* The batches' normal impulses (press, tilts) into rows, or (back) the
   rows into them. */
static void copy_normal(tb__contacts *c, double *rows, int back)
{
    const size_t size = TB__BATCH_LANES * sizeof *rows;
    size_t b;
    int d;
    for (b = 0; b < c->batch_count; ++b)
        for (d = 0; d < TB__NORMAL_ROWS; ++d) {
            double *mine = c->batches[b].impulse[d ? TB__ROW_TILT1 + d - 1 : TB__ROW_PRESS];
            double *row = rows + (b * TB__NORMAL_ROWS + d) * TB__BATCH_LANES;
            memcpy(back ? mine : row, back ? row : mine, size);
        }
}

/* What a landing solve added, x, passes through the lanes under it at
   the instant of the landing, not over the step as a resting lane's load
   does: on positions it acts from then on, for the landing lanes' lever.
   The rows' totals are pushed on positions with their own levers after
   the sweeps; the difference for x is pushed on c->motion here (rows:
   scratch). Without it, a heavy box landing on a column of light ones
   pushes them into each other and the ground
   (heavy_box_lands_on_light_ones). */
static void impact_levers(tb__contacts *c, const double *x, double *rows)
{
    double sum = 0;
    size_t b, i, landed = 0;
    int k;
    for (b = 0; b < c->batch_count; ++b)
        for (k = 0; k < TB__BATCH_LANES; ++k)
            if (c->batches[b].source[k] && c->batches[b].heavy[k] && c->batches[b].source[k]->struck)
                sum += c->batches[b].lever[k], landed++;
    if (!landed)
        return; /* (the step after a landing: x corrects resting loads) */
    EACH_ROW(c, b, i) {
        const tb__batch *bt = &c->batches[b];
        k = (int)(i % TB__BATCH_LANES);
        rows[i] = bt->source[k] && !bt->source[k]->struck ? x[i] * (sum / (double)landed - bt->lever[k]) : 0;
    }
    tb__push_normal_rows(c->batches, c->batch_count, c->motion, rows, c->isa);
}

static int solve(tb__contacts *c, int most, double tolerance, int whole, int landings)
{
    const size_t n = c->batch_count * ROWS;
    double *x = c->cold_rows, *r = x + n, *z = r + n, *p = z + n, *q = p + n, *mass = q + n, *rate = mass + n;
    double rz, pq, alpha, beta, miss, least, next, start, was, gain;
    size_t b, i;
    int it, found = 0;
    if (n == 0)
        return 0;
    row_masses(c, mass, landings);
    tb__normal_rates(c->batches, c->batch_count, c->velocity, rate, c->isa);
    /* Every row aims at 0, no relative motion, whatever its own target (a
       gap closing between two bodies): then b = -J v lies where A = J
       M^-1 J^T reaches, and conjugate gradients preconditioned by D (the
       rows' masses) give the solution nearest 0 in D^-1's measure. Rows
       asking for speeds that do not fit together (two patches on one
       body) would put a part of b where A cannot reach, which the
       iterates grow without bound, as pushes and pulls that cancel in
       speed and that the warm starts carry on from step to step. */
    EACH_ROW(c, b, i)
    r[i] = mass[i] > 0 ? -rate[i] : 0;
    EACH_ROW(c, b, i) {
        x[i] = 0;
        p[i] = z[i] = mass[i] * r[i];
    }
    rz = dot(c, r, z);
    /* past rounding's reach the directions lose their meaning and the
       steps grow without bound: no further than 1e-13 of where the misses
       began, and not once the largest miss has grown a thousandfold.
       Rows that cannot all be met (two patches on one body asking for
       different speeds) leave a miss that does not shrink, and the
       iterates drift along what A cannot change: 20 iterations without a
       smaller largest miss end the search (bodies built overlapping would
       otherwise take every iteration, to no use). The last iterate is
       taken: conjugate gradients shrink the error in A's norm, not the
       largest miss, so an earlier iterate that misses less is not the
       better guess. */
    start = least = miss = worst(c, r, mass);
    tolerance = fmax(tolerance, 1e-13 * miss);
    for (it = 0; it < most && miss > tolerance && it - found <= 20 && miss <= 1e3 * start; ++it) {
        apply_rows(c, p, q);
        pq = dot(c, p, q);
        if (!(pq > 0))
            break;
        alpha = rz / pq;
        if (!isfinite(alpha))
            break;
        next = 0, miss = 0;
        EACH_ROW(c, b, i) {
            x[i] += alpha * p[i];
            r[i] = mass[i] > 0 ? r[i] - alpha * q[i] : 0;
            z[i] = mass[i] * r[i];
            next += r[i] * z[i];
            miss = fabs(r[i]) > miss ? fabs(r[i]) : miss;
        }
        beta = next / rz;
        rz = next;
        EACH_ROW(c, b, i)
        p[i] = z[i] + beta * p[i];
        if (miss < least)
            least = miss, found = it + 1;
    }
    /* (nothing to add to the sweeps' own start, or a guess that is not
       finite: none taken. Nor is a whole solve that did not meet its rows,
       to a thousandth of the miss it began from at the least: rows that
       could not all be met, as in heaps of bodies built overlapping, are
       left to the sweeps.) */
    if (it == 0 || !isfinite(dot(c, x, x)) || (whole && !(miss <= fmax(tolerance, 1e-3 * start))))
        return -it;
    /* Met, each row's speed changes by what it missed. Clamped, a row the
       solve had pull instead of push changes by less, and a body may then
       be thrown off: rows that share bodies can pull and push by amounts
       that cancel, however closely the solve met them. The clamped guess
       is tried on the scratch motion first, and not taken where it leaves
       some row more than twice as far from what it may do as the warm
       starts left the farthest: a thrown body's row is left several times
       as far off, a resting scene's little more than the warm starts left
       it. */
    was = violation(c, rate, mass);
    copy_normal(c, z, 0);
    clamp_into(c, x);
    apply_rows(c, x, q);
    gain = dot(c, x, rate) + 0.5 * dot(c, x, q); /* kinetic energy: x J v + x A x / 2 */
    EACH_ROW(c, b, i)
    q[i] += rate[i];
    /* Landings are held to more: no row further off than before, and no
       kinetic energy gained (met, the solve only takes it away; clamped,
       it may not): a landing's solve that met its rows to a thousandth
       of its start can still leave a row twice as far off, or give
       energy, and throw bodies off. */
    if (!(violation(c, q, mass) <= (landings ? 1 : 2) * was) || (landings && !(gain <= 0))) {
        copy_normal(c, z, 1); /* (as they were, to the bit) */
        return -it;
    }
    tb__push_normal_rows(c->batches, c->batch_count, c->velocity, x, c->isa);
    if (landings)
        impact_levers(c, x, q);
    return it;
}

int tb__cold_start(tb__contacts *c, int most, double tolerance, int whole)
{
    return solve(c, most, tolerance, whole, 0);
}

int tb__heavy_landings(tb__contacts *c, int most, double tolerance)
{
    heavy_rings(c);
    return solve(c, most, tolerance, 1, 1);
}
