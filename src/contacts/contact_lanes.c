/* contact_lanes.c: the contact solver's sweeps, a batch of manifolds at a
   time (contacts.h, tb__batch). The manifolds of a batch share no moving
   body, so its lanes are independent: each lane runs the same sequence of
   IEEE operations a one-manifold loop would, and the batches run in order.
   The result is the Gauss-Seidel sweep of the order the batches give,
   whatever the instruction set: the loops over lanes are compiled portable,
   AVX2 and AVX-512 (core/core.h, TB__FOR_EACH_ISA) and all give the same
   bits. */
#include "contacts/contacts.h"

#include <math.h>
#include <string.h>

#define W TB__BATCH_LANES

/* Each lane's two sides, held through the batch's points: velocity (or
   position change) and turn, and the inverse masses. */
typedef struct sides {
    double va[3][W], wa[3][W], vb[3][W], wb[3][W], ma[W], mb[W];
} sides;

/* out[k] = from[k][i] for every lane; and a batch's sides gathered from
   the per-body arrays m and scattered back. GCC and Clang build lanes in
   registers and store them whole (a vector load of what was stored lane
   by lane waits for those stores: store forwarding fails). With AVX-512
   they move a side's eight bodies as eight rows of TB__MOTION = 8 doubles
   (a cache line each) turned into columns by a transpose: 24 shuffles
   where lane by lane takes some 200 loads, inserts and extracts, most of
   the cost of a batch of one-point manifolds. With narrower vectors the
   shuffles cost more than they save. Slot 7 of a row is unused and comes
   back 0. */
#if (defined(__clang__) || (defined(__GNUC__) && __GNUC__ >= 12)) && TB__BATCH_LANES == 8 && TB__MOTION == 8
#define TB__ROWS 1
typedef double tb__lanes __attribute__((vector_size(8 * sizeof(double))));

TB__LANE void pick(const double *const *from, int i, double *out)
{
    const tb__lanes v = { from[0][i], from[1][i], from[2][i], from[3][i],
                          from[4][i], from[5][i], from[6][i], from[7][i] };
    memcpy(out, &v, sizeof v);
}

/* rows to columns (and back: it is its own inverse); written out, as
   loops keep the halfway steps in memory */
#define TB__EVEN(x, y) __builtin_shufflevector(x, y, 0, 8, 2, 10, 4, 12, 6, 14)
#define TB__ODD(x, y) __builtin_shufflevector(x, y, 1, 9, 3, 11, 5, 13, 7, 15)
#define TB__LOW_PAIRS(x, y) __builtin_shufflevector(x, y, 0, 1, 8, 9, 4, 5, 12, 13)
#define TB__HIGH_PAIRS(x, y) __builtin_shufflevector(x, y, 2, 3, 10, 11, 6, 7, 14, 15)
#define TB__LOW_HALVES(x, y) __builtin_shufflevector(x, y, 0, 1, 2, 3, 8, 9, 10, 11)
#define TB__HIGH_HALVES(x, y) __builtin_shufflevector(x, y, 4, 5, 6, 7, 12, 13, 14, 15)
TB__LANE void transpose(tb__lanes r[8])
{
    const tb__lanes t0 = TB__EVEN(r[0], r[1]), t1 = TB__ODD(r[0], r[1]);
    const tb__lanes t2 = TB__EVEN(r[2], r[3]), t3 = TB__ODD(r[2], r[3]);
    const tb__lanes t4 = TB__EVEN(r[4], r[5]), t5 = TB__ODD(r[4], r[5]);
    const tb__lanes t6 = TB__EVEN(r[6], r[7]), t7 = TB__ODD(r[6], r[7]);
    const tb__lanes u0 = TB__LOW_PAIRS(t0, t2), u1 = TB__LOW_PAIRS(t1, t3);
    const tb__lanes u2 = TB__HIGH_PAIRS(t0, t2), u3 = TB__HIGH_PAIRS(t1, t3);
    const tb__lanes u4 = TB__LOW_PAIRS(t4, t6), u5 = TB__LOW_PAIRS(t5, t7);
    const tb__lanes u6 = TB__HIGH_PAIRS(t4, t6), u7 = TB__HIGH_PAIRS(t5, t7);
    r[0] = TB__LOW_HALVES(u0, u4), r[4] = TB__HIGH_HALVES(u0, u4);
    r[1] = TB__LOW_HALVES(u1, u5), r[5] = TB__HIGH_HALVES(u1, u5);
    r[2] = TB__LOW_HALVES(u2, u6), r[6] = TB__HIGH_HALVES(u2, u6);
    r[3] = TB__LOW_HALVES(u3, u7), r[7] = TB__HIGH_HALVES(u3, u7);
}

TB__LANE void gather_rows(const int32_t *body, const double *m, double (*v)[W], double (*w)[W], double *mass)
{
    tb__lanes r[8];
    int k;
    for (k = 0; k < 8; ++k)
        memcpy(&r[k], m + TB__MOTION * body[k], sizeof r[k]);
    transpose(r);
    for (k = 0; k < 3; ++k)
        memcpy(v[k], &r[k], sizeof r[k]), memcpy(w[k], &r[3 + k], sizeof r[k]);
    memcpy(mass, &r[6], sizeof r[6]);
}

TB__LANE void scatter_rows(const int32_t *body, double *m, const double (*v)[W], const double (*w)[W],
                           const double *mass)
{
    tb__lanes r[8];
    int k;
    for (k = 0; k < 3; ++k)
        memcpy(&r[k], v[k], sizeof r[k]), memcpy(&r[3 + k], w[k], sizeof r[k]);
    memcpy(&r[6], mass, sizeof r[6]);
    memset(&r[7], 0, sizeof r[7]);
    transpose(r);
    for (k = 0; k < 8; ++k)
        memcpy(m + TB__MOTION * body[k], &r[k], sizeof r[k]);
}
#else
#define TB__ROWS 0
TB__LANE void pick(const double *const *from, int i, double *out)
{
    int k;
    for (k = 0; k < W; ++k)
        out[k] = from[k][i];
}
#endif

TB__LANE void gather_lanes(const int32_t *body, const double *m, double (*v)[W], double (*w)[W], double *mass)
{
    const double *rows[W];
    int k, i;
    for (k = 0; k < W; ++k)
        rows[k] = m + TB__MOTION * body[k];
    for (i = 0; i < 3; ++i)
        pick(rows, i, v[i]), pick(rows, 3 + i, w[i]);
    pick(rows, 6, mass);
}

TB__LANE void scatter_lanes(const int32_t *body, double *m, const double (*v)[W], const double (*w)[W])
{
    int k, i;
    for (k = 0; k < W; ++k) {
        double *row = m + TB__MOTION * body[k];
        for (i = 0; i < 3; ++i)
            row[i] = v[i][k], row[3 + i] = w[i][k];
    }
}

/* wide: by rows (AVX-512 only; a constant where it is inlined) */
TB__LANE void gather(const tb__batch *bt, const double *m, sides *s, int wide, int one)
{
#if TB__ROWS
    if (wide) {
        if (!one)
            gather_rows(bt->a, m, s->va, s->wa, s->ma);
        gather_rows(bt->b, m, s->vb, s->wb, s->mb);
        return;
    }
#endif
    (void)wide;
    if (!one)
        gather_lanes(bt->a, m, s->va, s->wa, s->ma);
    gather_lanes(bt->b, m, s->vb, s->wb, s->mb);
}

/* Back in lane order. Lanes on the static world (0) write its zeros back:
   it has no inverse mass and its rows no turn, so nothing moved it. */
TB__LANE void scatter(const tb__batch *bt, double *m, const sides *s, int wide, int one)
{
#if TB__ROWS
    if (wide) {
        if (!one)
            scatter_rows(bt->a, m, (const double(*)[W])s->va, (const double(*)[W])s->wa, s->ma);
        scatter_rows(bt->b, m, (const double(*)[W])s->vb, (const double(*)[W])s->wb, s->mb);
        return;
    }
#endif
    (void)wide;
    if (!one)
        scatter_lanes(bt->a, m, (const double(*)[W])s->va, (const double(*)[W])s->wa);
    scatter_lanes(bt->b, m, (const double(*)[W])s->vb, (const double(*)[W])s->wb);
}

/* Lane k's relative velocity along a row with direction dir (or none, for
   the twist) and arms arm_a, arm_b ([axis][lane]): three dot products
   summed as a tree, so that the sweep's chain of dependent operations
   (each row waits for the last one's push) stays short. one: a batch
   whose every a is the static world (tb__batch), its terms left out (the
   same values: they are zeros). */
#define DOT3(x, y, k) ((x)[0][k] * (y)[0][k] + (x)[1][k] * (y)[1][k] + (x)[2][k] * (y)[2][k])
#define LINEAR(dir, s, k, one)                                                                        \
    ((one) ? (dir)[0][k] * (s)->vb[0][k] + (dir)[1][k] * (s)->vb[1][k] + (dir)[2][k] * (s)->vb[2][k]        \
           : (dir)[0][k] * ((s)->vb[0][k] - (s)->va[0][k]) + (dir)[1][k] * ((s)->vb[1][k] - (s)->va[1][k]) + \
                 (dir)[2][k] * ((s)->vb[2][k] - (s)->va[2][k]))
#define ANGULAR(arm_a, arm_b, s, k, one) \
    ((one) ? DOT3(arm_b, (s)->wb, k) : DOT3(arm_b, (s)->wb, k) - DOT3(arm_a, (s)->wa, k))
#define RATE(dir, arm_a, arm_b, s, k, one) (LINEAR(dir, s, k, one) + ANGULAR(arm_a, arm_b, s, k, one))

/* An impulse l on lane k along a row: -l on a, +l on b; the linear part
   along dir (skipped for the twist, LINEAR_PUSH 0), the turn along
   turn_a, turn_b. (Written out: a loop over the axes inside the loop over
   lanes keeps GCC from vectorising the lanes.) */
#define ANGULAR_PUSH(turn_a, turn_b, s, k, l, one) \
    do {                                           \
        if (!(one)) {                              \
            (s)->wa[0][k] -= (l) * (turn_a)[0][k]; \
            (s)->wa[1][k] -= (l) * (turn_a)[1][k]; \
            (s)->wa[2][k] -= (l) * (turn_a)[2][k]; \
        }                                          \
        (s)->wb[0][k] += (l) * (turn_b)[0][k];     \
        (s)->wb[1][k] += (l) * (turn_b)[1][k];     \
        (s)->wb[2][k] += (l) * (turn_b)[2][k];     \
    } while (0)
#define PUSH(dir, turn_a, turn_b, s, k, l, one)       \
    do {                                              \
        const double lb_ = (l) * (s)->mb[k];          \
        if (!(one)) {                                 \
            const double la_ = (l) * (s)->ma[k];      \
            (s)->va[0][k] -= la_ * (dir)[0][k];       \
            (s)->va[1][k] -= la_ * (dir)[1][k];       \
            (s)->va[2][k] -= la_ * (dir)[2][k];       \
        }                                             \
        (s)->vb[0][k] += lb_ * (dir)[0][k];           \
        (s)->vb[1][k] += lb_ * (dir)[1][k];           \
        (s)->vb[2][k] += lb_ * (dir)[2][k];           \
        ANGULAR_PUSH(turn_a, turn_b, s, k, l, one);   \
    } while (0)

/* The friction of every lane's patch: the two tangent rows at the centre,
   within the circle mu times the patch's normal force, then the twist
   within that times the twist reach. An empty lane has zero masses and
   friction, so its impulses stay 0. */
TB__LANE void friction_patch(tb__batch *restrict bt, sides *restrict s, int one)
{
    enum { T1 = TB__ROW_TANGENT1, T2 = TB__ROW_TANGENT2, TW = TB__ROW_TWIST };
    double t0[W], t1[W], len2[W], limit[W], limit2[W];
    int k, outside = 0;
    for (k = 0; k < W; ++k) {
        limit[k] = bt->friction[k] * bt->impulse[TB__ROW_PRESS][k];
        t0[k] = bt->impulse[T1][k] - bt->mass[T1][k] * RATE(bt->dir[1], bt->arm_a[T1], bt->arm_b[T1], s, k, one);
        t1[k] = bt->impulse[T2][k] - bt->mass[T2][k] * RATE(bt->dir[2], bt->arm_a[T2], bt->arm_b[T2], s, k, one);
        len2[k] = t0[k] * t0[k] + t1[k] * t1[k];
        limit2[k] = limit[k] * limit[k];
    }
    for (k = 0; k < W; ++k)
        outside |= len2[k] > limit2[k];
    /* Outside the circle, scaled back onto it. The square root and the
       division are the slowest operations of the sweep, and resting
       contacts mostly stay inside: they are done only when some lane is
       out, and then in every lane (len2 = 0 gives an unused infinity or
       NaN), as a branch per lane would keep the lanes from one
       instruction. */
    if (outside)
        for (k = 0; k < W; ++k) {
            const double scale = limit[k] / sqrt(len2[k]);
            t0[k] = len2[k] > limit2[k] ? t0[k] * scale : t0[k];
            t1[k] = len2[k] > limit2[k] ? t1[k] * scale : t1[k];
        }
    for (k = 0; k < W; ++k) {
        const double d0 = t0[k] - bt->impulse[T1][k], d1 = t1[k] - bt->impulse[T2][k];
        PUSH(bt->dir[1], bt->turn_a[T1], bt->turn_b[T1], s, k, d0, one);
        PUSH(bt->dir[2], bt->turn_a[T2], bt->turn_b[T2], s, k, d1, one);
        bt->impulse[T1][k] = t0[k], bt->impulse[T2][k] = t1[k];
    }
    /* a batch of one-point manifolds (its first lane has the most points)
       has no reach to twist with */
    if (bt->points > 1)
        for (k = 0; k < W; ++k) {
            const double reach = limit[k] * bt->twist_reach[k];
            double twist = bt->impulse[TW][k] - bt->mass[TW][k] * ANGULAR(bt->dir[0], bt->dir[0], s, k, one), dt;
            twist = twist > reach ? reach : twist < -reach ? -reach : twist;
            dt = twist - bt->impulse[TW][k];
            ANGULAR_PUSH(bt->turn_a[TW], bt->turn_b[TW], s, k, dt, one);
            bt->impulse[TW][k] = twist;
        }
}

/* Every lane's press row: the normal velocity where the press acts
   (tb__batch.shift) >= target[k] (only: in the lanes whose target > 0,
   the others keep their impulse); the sweeps' target is the mean of the
   points' (0 for a lane that bounces: tb__bounce). An empty lane has zero
   masses, so its impulse stays 0. */
TB__LANE void press_toward(tb__batch *restrict bt, sides *restrict s, const double *target, int only, int one)
{
    enum { P = TB__ROW_PRESS };
    int k;
    for (k = 0; k < W; ++k) {
        const double old = bt->impulse[P][k];
        double total = old - bt->mass[P][k] * (RATE(bt->dir[0], bt->arm_a[P], bt->arm_b[P], s, k, one) - target[k]);
        double dn;
        total = total > 0 ? total : 0;
        total = !only || target[k] > 0 ? total : old;
        dn = total - old;
        PUSH(bt->dir[0], bt->turn_a[P], bt->turn_b[P], s, k, dn, one);
        bt->impulse[P][k] = total;
    }
}

TB__LANE void press(tb__batch *restrict bt, sides *restrict s, int one)
{
    press_toward(bt, s, bt->press_target, 0, one);
}

/* Every lane's tilt about tangent d, toward a turn of one side on the
   other of target, within its press's force (press) times the range of
   the points' levers, widened by the rolling resistance (a lane with one
   point, or points on a line, has no range across it and without rolling
   resistance does not resist that tilt); impulse: the row's accumulated
   impulses. The velocity pass and the position pass's patch share it. */
TB__LANE void tilt(tb__batch *restrict bt, sides *restrict s, int d, const double *press, const double *target,
                   double *impulse, int one)
{
    const int r = TB__ROW_TILT1 + d;
    int k;
    for (k = 0; k < W; ++k) {
        const double high = press[k] * bt->tilt_high[d][k], low = press[k] * bt->tilt_low[d][k];
        double turn = impulse[k] - bt->mass[r][k] * (ANGULAR(bt->dir[1 + d], bt->dir[1 + d], s, k, one) - target[k]);
        double dt;
        turn = turn > high ? high : turn;
        turn = turn < low ? low : turn;
        dt = turn - impulse[k];
        ANGULAR_PUSH(bt->turn_a[r], bt->turn_b[r], s, k, dt, one);
        impulse[k] = turn;
    }
}

/* The tilts of the velocity pass: no turn of one side on the other. */
TB__LANE void tilts(tb__batch *restrict bt, sides *restrict s, int one)
{
    static const double none[W] = { 0 };
    int d;
    if (!bt->tilting)
        return;
    for (d = 0; d < 2; ++d)
        tilt(bt, s, d, bt->impulse[TB__ROW_PRESS], none, bt->impulse[TB__ROW_TILT1 + d], one);
}

/* A position row's accumulated impulse, old before, once it is met: the
   rate now toward target, never pulling, and left alone by a row that
   never pushed and is not short of its target (idle). */
TB__LANE double position_total(double old, double mass, double now, double target)
{
    double total = old - mass * (now - target);
    total = total > 0 ? total : 0;
    return now >= target && old == 0 ? 0 : total;
}

/* One point of every lane in the position pass: the normal row only, on
   (dp, dtheta), toward push_target; a row that never pushed and is not
   short of its target is left alone. */
TB__LANE void position_point(const tb__batch *restrict bt, tb__lane_point *restrict p, sides *restrict s,
                             int one)
{
    int k;
    for (k = 0; k < W; ++k) {
        const double now = p->predicted[k] + RATE(bt->dir[0], p->arm_a, p->arm_b, s, k, one);
        const double total = position_total(p->position_impulse[k], p->mass[k], now, p->push_target[k]);
        const double dn = total - p->position_impulse[k];
        PUSH(bt->dir[0], p->turn_a, p->turn_b, s, k, dn, one);
        p->position_impulse[k] = total;
    }
}

/* The position pass's patch of every lane: the press row at the centre
   toward the mean of what the points need, then the tilts toward the
   turns that level them, within what non-negative forces at the points
   can give (the press impulse times the levers' range). Rows per point
   alone meet a long body's ends in turn, each push turning it and sinking
   the other end (heavy_plank_comes_out_whole). */
TB__LANE void position_patch(tb__batch *restrict bt, sides *restrict s, int one)
{
    enum { P = TB__ROW_PRESS };
    int k, d;
    for (k = 0; k < W; ++k) {
        const double now = RATE(bt->dir[0], bt->arm_a[P], bt->arm_b[P], s, k, one);
        const double total = position_total(bt->patch_impulse[0][k], bt->mass[P][k], now, bt->patch_push[0][k]);
        const double dn = total - bt->patch_impulse[0][k];
        PUSH(bt->dir[0], bt->turn_a[P], bt->turn_b[P], s, k, dn, one);
        bt->patch_impulse[0][k] = total;
    }
    if (!bt->tilting)
        return;
    for (d = 0; d < 2; ++d)
        tilt(bt, s, d, bt->patch_impulse[0], bt->patch_push[1 + d], bt->patch_impulse[1 + d], one);
}

TB__LANE void velocity_batch(tb__batch *bt, double *m, int backwards, int wide, int one)
{
    sides s;
    gather(bt, m, &s, wide, one);
    /* a backward sweep is the forward one reversed (friction last): a pair
       of sweeps is then symmetric Gauss-Seidel, which leans a tall stack
       less than friction first both ways */
    if (!backwards) {
        friction_patch(bt, &s, one);
        press(bt, &s, one);
        tilts(bt, &s, one);
    } else {
        tilts(bt, &s, one);
        press(bt, &s, one);
        friction_patch(bt, &s, one);
    }
    scatter(bt, m, &s, wide, one);
}

/* Every batch (backwards: the last first) through one of two copies of
   batch_fn, with side a or without (one-sided batches). */
#define EACH_BATCH(batches, n, backwards, batch_fn, m, wide)              \
    do {                                                                  \
        size_t i_;                                                        \
        for (i_ = 0; i_ < (n); ++i_) {                                    \
            tb__batch *bt_ = &(batches)[(backwards) ? (n) - 1 - i_ : i_]; \
            if (bt_->one_sided)                                           \
                batch_fn(bt_, m, backwards, wide, 1);                     \
            else                                                          \
                batch_fn(bt_, m, backwards, wide, 0);                     \
        }                                                                 \
    } while (0)

TB__LANE void velocity_batches(tb__batch *batches, size_t n, double *m, int backwards, int wide)
{
    EACH_BATCH(batches, n, backwards, velocity_batch, m, wide);
}

TB__LANE void position_batch(tb__batch *bt, double *m, int backwards, int wide, int one)
{
    sides s;
    int j;
    gather(bt, m, &s, wide, one);
    position_patch(bt, &s, one);
    for (j = 0; j < bt->points; ++j)
        position_point(bt, &bt->point[backwards ? bt->points - 1 - j : j], &s, one);
    scatter(bt, m, &s, wide, one);
}

TB__LANE void position_batches(tb__batch *batches, size_t n, double *m, int backwards, int wide)
{
    EACH_BATCH(batches, n, backwards, position_batch, m, wide);
}

/* Lane k's part of a row along dir for one side: r x dir (r, [axis][lane],
   the anchor; NULL: a twist, dir itself where the side moves) into arm,
   I^-1 (r x dir) into turn; returns their dot, the side's turning share of
   the row's 1 / mass. arm and turn are the caller's own arrays, so that
   the lanes can become one instruction. */
TB__LANE double side_row(const double (*r)[W], const double (*dir)[W], const double (*inv)[W], double moving,
                         double (*arm)[W], double (*turn)[W], int k)
{
    double a0, a1, a2, t0, t1, t2;
    if (r) {
        a0 = r[1][k] * dir[2][k] - r[2][k] * dir[1][k];
        a1 = r[2][k] * dir[0][k] - r[0][k] * dir[2][k];
        a2 = r[0][k] * dir[1][k] - r[1][k] * dir[0][k];
    } else {
        a0 = moving * dir[0][k], a1 = moving * dir[1][k], a2 = moving * dir[2][k];
    }
    t0 = inv[0][k] * a0 + inv[1][k] * a1 + inv[2][k] * a2;
    t1 = inv[3][k] * a0 + inv[4][k] * a1 + inv[5][k] * a2;
    t2 = inv[6][k] * a0 + inv[7][k] * a1 + inv[8][k] * a2;
    arm[0][k] = a0, arm[1][k] = a1, arm[2][k] = a2;
    turn[0][k] = t0, turn[1][k] = t1, turn[2][k] = t2;
    return a0 * t0 + a1 * t1 + a2 * t2;
}

/* 1 / mass, 0 for a row that nothing can move */
#define ROW_MASS(mass) ((mass) > 0 ? 1 / (mass) : 0)

/* A row of every lane: anchors ra, rb (NULL: a twist) along dir, into
   the arms, turns and 1 / mass given (which may be where the anchors
   were). */
TB__LANE void lane_rows(const double (*ra)[W], const double (*rb)[W], const double (*dir)[W],
                        const double (*ia)[W], const double (*ib)[W], const double *sum, const double *moving_a,
                        const double *moving_b, double (*arm_a)[W], double (*arm_b)[W], double (*turn_a)[W],
                        double (*turn_b)[W], double *mass)
{
    double a[3][W], b[3][W], ta[3][W], tb[3][W], m[W];
    int k;
    for (k = 0; k < W; ++k) {
        const double inverse = sum[k] + side_row(ra, dir, ia, moving_a[k], a, ta, k) +
                               side_row(rb, dir, ib, moving_b[k], b, tb, k);
        m[k] = ROW_MASS(inverse);
    }
    memcpy(arm_a, a, sizeof a), memcpy(arm_b, b, sizeof b);
    memcpy(turn_a, ta, sizeof ta), memcpy(turn_b, tb, sizeof tb);
    memcpy(mass, m, sizeof m);
}

TB__LANE void rows_batches(tb__batch *batches, size_t n, const double *m)
{
    size_t b;
    for (b = 0; b < n; ++b) {
        tb__batch *bt = &batches[b];
        double ia[9][W], ib[9][W], sum[W], moving_a[W], moving_b[W], ca[3][W], cb[3][W];
        const double none[W] = { 0 };
        int i, j, k;
        for (i = 0; i < 9; ++i)
            pick(bt->inv_world_a, i, ia[i]), pick(bt->inv_world_b, i, ib[i]);
        for (k = 0; k < W; ++k) {
            sum[k] = m[TB__MOTION * bt->a[k] + 6] + m[TB__MOTION * bt->b[k] + 6];
            moving_a[k] = bt->a[k] != 0, moving_b[k] = bt->b[k] != 0;
        }
        for (j = 0; j < bt->points; ++j) {
            tb__lane_point *p = &bt->point[j];
            /* a lane with fewer points than the batch's first has no row
               here: no inverse mass either, so its mass is 0 (its zero
               arms alone would leave a row between the two centres) */
            double point_sum[W];
            for (k = 0; k < W; ++k)
                point_sum[k] = p->source[k] ? sum[k] : 0;
            lane_rows((const double(*)[W])p->arm_a, (const double(*)[W])p->arm_b, (const double(*)[W])bt->dir[0],
                      (const double(*)[W])ia, (const double(*)[W])ib, point_sum, none, none, p->arm_a, p->arm_b,
                      p->turn_a, p->turn_b, p->mass);
        }
        /* the patch: both tangent rows at the centre held in row 0, then
           the twist */
        memcpy(ca, bt->arm_a[0], sizeof ca), memcpy(cb, bt->arm_b[0], sizeof cb);
        for (i = 0; i < 2; ++i)
            lane_rows((const double(*)[W])ca, (const double(*)[W])cb, (const double(*)[W])bt->dir[i + 1],
                      (const double(*)[W])ia, (const double(*)[W])ib, sum, none, none, bt->arm_a[i], bt->arm_b[i],
                      bt->turn_a[i], bt->turn_b[i], bt->mass[i]);
        lane_rows(NULL, NULL, (const double(*)[W])bt->dir[0], (const double(*)[W])ia, (const double(*)[W])ib, none,
                  moving_a, moving_b, bt->arm_a[2], bt->arm_b[2], bt->turn_a[2], bt->turn_b[2], bt->mass[2]);
        /* the tilts about the tangents, and the press at the centre */
        for (i = 0; i < 2; ++i)
            lane_rows(NULL, NULL, (const double(*)[W])bt->dir[1 + i], (const double(*)[W])ia,
                      (const double(*)[W])ib, none, moving_a, moving_b, bt->arm_a[TB__ROW_TILT1 + i],
                      bt->arm_b[TB__ROW_TILT1 + i], bt->turn_a[TB__ROW_TILT1 + i], bt->turn_b[TB__ROW_TILT1 + i],
                      bt->mass[TB__ROW_TILT1 + i]);
        /* the press where last step's force was centred: shift_1 along
           t_2 and -shift_2 along t_1 (a lever is (point - centre) . (n x t)) */
        for (i = 0; i < 3; ++i)
            for (k = 0; k < W; ++k) {
                const double along = bt->shift[0][k] * bt->dir[2][i][k] - bt->shift[1][k] * bt->dir[1][i][k];
                ca[i][k] += along, cb[i][k] += along;
            }
        lane_rows((const double(*)[W])ca, (const double(*)[W])cb, (const double(*)[W])bt->dir[0],
                  (const double(*)[W])ia, (const double(*)[W])ib, sum, none, none, bt->arm_a[TB__ROW_PRESS],
                  bt->arm_b[TB__ROW_PRESS], bt->turn_a[TB__ROW_PRESS], bt->turn_b[TB__ROW_PRESS],
                  bt->mass[TB__ROW_PRESS]);
    }
}

/* The press row of every bouncing lane toward its bounce target
   (tb__bounce). */
TB__LANE void bounce_batches(tb__batch *batches, size_t n, double *m, int wide)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        tb__batch *bt = &batches[i];
        sides s;
        if (!bt->bouncing)
            continue;
        gather(bt, m, &s, wide, 0);
        press_toward(bt, &s, bt->bounce, 1, 0);
        scatter(bt, m, &s, wide, 0);
    }
}

/* Every batch's impulse totals into m (tb__push_impulses). */
TB__LANE void push_batches(tb__batch *batches, size_t n, double *m, int what, int wide)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        tb__batch *bt = &batches[i];
        const int momenta = what == TB__PUSH_MOMENTA, motion = what == TB__PUSH_MOTION, one = 0;
        double(*ta)[3][W] = momenta ? bt->arm_a : bt->turn_a, (*tb)[3][W] = momenta ? bt->arm_b : bt->turn_b;
        double l[TB__PATCH_ROWS][W];
        sides s;
        int k, d;
        gather(bt, m, &s, wide, one);
        for (d = 0; d < TB__PATCH_ROWS; ++d) /* (the friction rows come before the tilts) */
            for (k = 0; k < W; ++k)
                l[d][k] = !motion ? bt->impulse[d][k]
                          : d < TB__ROW_TILT1 ? bt->side_lever[k] * bt->impulse[d][k]
                                              : bt->lever[k] * bt->impulse[d][k];
        for (k = 0; k < W; ++k) {
            PUSH(bt->dir[1], ta[TB__ROW_TANGENT1], tb[TB__ROW_TANGENT1], &s, k, l[TB__ROW_TANGENT1][k], one);
            PUSH(bt->dir[2], ta[TB__ROW_TANGENT2], tb[TB__ROW_TANGENT2], &s, k, l[TB__ROW_TANGENT2][k], one);
            ANGULAR_PUSH(ta[TB__ROW_TWIST], tb[TB__ROW_TWIST], &s, k, l[TB__ROW_TWIST][k], one);
            ANGULAR_PUSH(ta[TB__ROW_TILT1], tb[TB__ROW_TILT1], &s, k, l[TB__ROW_TILT1][k], one);
            ANGULAR_PUSH(ta[TB__ROW_TILT2], tb[TB__ROW_TILT2], &s, k, l[TB__ROW_TILT2][k], one);
            PUSH(bt->dir[0], ta[TB__ROW_PRESS], tb[TB__ROW_PRESS], &s, k, l[TB__ROW_PRESS][k], one);
        }
        scatter(bt, m, &s, wide, one);
    }
}

/* The normal rows (press, then the tilts) of every batch in the cold
   start's solve (tb__batch.in_solve), as [batch][TB__NORMAL_ROWS][lane]
   arrays: impulses given pushed on the velocities m, and each row's rate
   (the relative velocity it holds) on m into out, as the sweeps see them
   (0 for a batch outside the solve). */
TB__LANE void push_normal_batches(const tb__batch *batches, size_t n, double *m, const double *rows, int wide)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        const tb__batch *bt = &batches[i];
        const double(*l)[W] = (const double(*)[W])(rows + i * TB__NORMAL_ROWS * W);
        sides s;
        int k;
        if (!bt->in_solve)
            continue;
        gather(bt, m, &s, wide, 0);
        for (k = 0; k < W; ++k) {
            ANGULAR_PUSH(bt->turn_a[TB__ROW_TILT1], bt->turn_b[TB__ROW_TILT1], &s, k, l[1][k], 0);
            ANGULAR_PUSH(bt->turn_a[TB__ROW_TILT2], bt->turn_b[TB__ROW_TILT2], &s, k, l[2][k], 0);
            PUSH(bt->dir[0], bt->turn_a[TB__ROW_PRESS], bt->turn_b[TB__ROW_PRESS], &s, k, l[0][k], 0);
        }
        scatter(bt, m, &s, wide, 0);
    }
}

TB__LANE void normal_rates_batches(const tb__batch *batches, size_t n, const double *m, double *out, int wide)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        const tb__batch *bt = &batches[i];
        double(*rate)[W] = (double(*)[W])(out + i * TB__NORMAL_ROWS * W);
        sides s;
        int k;
        if (!bt->in_solve) {
            memset(rate, 0, TB__NORMAL_ROWS * W * sizeof **rate);
            continue;
        }
        gather(bt, m, &s, wide, 0);
        for (k = 0; k < W; ++k) {
            rate[0][k] = RATE(bt->dir[0], bt->arm_a[TB__ROW_PRESS], bt->arm_b[TB__ROW_PRESS], &s, k, 0);
            rate[1][k] = ANGULAR(bt->dir[1], bt->dir[1], &s, k, 0);
            rate[2][k] = ANGULAR(bt->dir[2], bt->dir[2], &s, k, 0);
        }
    }
}

#define TB__SWEEPS(isa, attr, id)                                                                      \
    attr static void velocity_##isa(tb__batch *batches, size_t n, double *m, int backwards)        \
    {                                                                                              \
        velocity_batches(batches, n, m, backwards, (id) == TB__ISA_AVX512);                                         \
    }                                                                                              \
    attr static void position_##isa(tb__batch *batches, size_t n, double *m, int backwards)        \
    {                                                                                              \
        position_batches(batches, n, m, backwards, (id) == TB__ISA_AVX512);                                         \
    }                                                                                              \
    attr static void bounce_##isa(tb__batch *batches, size_t n, double *m)                         \
    {                                                                                              \
        bounce_batches(batches, n, m, (id) == TB__ISA_AVX512);                                                       \
    }                                                                                              \
    attr static void push_##isa(tb__batch *batches, size_t n, double *m, int what)                 \
    {                                                                                              \
        push_batches(batches, n, m, what, (id) == TB__ISA_AVX512);                                                  \
    }                                                                                              \
    attr static void push_normal_##isa(const tb__batch *batches, size_t n, double *m, const double *rows) \
    {                                                                                              \
        push_normal_batches(batches, n, m, rows, (id) == TB__ISA_AVX512);                                           \
    }                                                                                              \
    attr static void normal_rates_##isa(const tb__batch *batches, size_t n, const double *m, double *out) \
    {                                                                                              \
        normal_rates_batches(batches, n, m, out, (id) == TB__ISA_AVX512);                                           \
    }                                                                                              \
    attr static void rows_##isa(tb__batch *batches, size_t n, const double *m)                     \
    {                                                                                              \
        rows_batches(batches, n, m);                                                               \
    }

TB__FOR_EACH_ISA(TB__SWEEPS)

void tb__sweep_velocities(tb__batch *batches, size_t n, double *m, int backwards, int isa)
{
    TB__DISPATCH(isa, velocity, (batches, n, m, backwards));
}

void tb__sweep_positions(tb__batch *batches, size_t n, double *m, int backwards, int isa)
{
    TB__DISPATCH(isa, position, (batches, n, m, backwards));
}

void tb__bounce(tb__batch *batches, size_t n, double *m, int isa)
{
    TB__DISPATCH(isa, bounce, (batches, n, m));
}

void tb__push_impulses(tb__batch *batches, size_t n, double *m, int what, int isa)
{
    TB__DISPATCH(isa, push, (batches, n, m, what));
}

void tb__push_normal_rows(const tb__batch *batches, size_t n, double *m, const double *rows, int isa)
{
    TB__DISPATCH(isa, push_normal, (batches, n, m, rows));
}

void tb__normal_rates(const tb__batch *batches, size_t n, const double *m, double *out, int isa)
{
    TB__DISPATCH(isa, normal_rates, (batches, n, m, out));
}

void tb__set_up_rows(tb__batch *batches, size_t n, const double *m, int isa)
{
    TB__DISPATCH(isa, rows, (batches, n, m));
}
