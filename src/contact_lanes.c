/* contact_lanes.c: the contact solver's sweeps, a batch of manifolds at a
   time (contact.h, tb__batch). The manifolds of a batch share no moving
   body, so its lanes are independent: each lane runs the same sequence of
   IEEE operations a one-manifold loop would, and the batches run in order.
   The result is the Gauss-Seidel sweep of the order the batches give,
   whatever the instruction set: the loops over lanes are compiled portable,
   AVX2 and AVX-512 (rotation.h) and all give the same bits. */
#include "contact.h"
#include "rotation.h"

#include <math.h>

#define W TB__BATCH_LANES

/* Each lane's two sides, held through the batch's points: velocity (or
   position change) and turn, and the inverse masses. */
typedef struct sides {
    double va[3][W], wa[3][W], vb[3][W], wb[3][W], ma[W], mb[W];
} sides;

TB__LANE void gather(const tb__batch *bt, const double *m, sides *s)
{
    int k, i;
    for (k = 0; k < W; ++k) {
        const double *A = m + TB__MOTION * bt->a[k], *B = m + TB__MOTION * bt->b[k];
        for (i = 0; i < 3; ++i) {
            s->va[i][k] = A[i], s->wa[i][k] = A[3 + i];
            s->vb[i][k] = B[i], s->wb[i][k] = B[3 + i];
        }
        s->ma[k] = A[6], s->mb[k] = B[6];
    }
}

/* Back in lane order. Lanes on the static world (0) write its zeros back:
   it has no inverse mass and its rows no turn, so nothing moved it. */
TB__LANE void scatter(const tb__batch *bt, double *m, const sides *s)
{
    int k, i;
    for (k = 0; k < W; ++k) {
        double *A = m + TB__MOTION * bt->a[k], *B = m + TB__MOTION * bt->b[k];
        for (i = 0; i < 3; ++i) {
            A[i] = s->va[i][k], A[3 + i] = s->wa[i][k];
            B[i] = s->vb[i][k], B[3 + i] = s->wb[i][k];
        }
    }
}

/* Lane k's relative velocity along row d of point p: three dot products
   summed as a tree, so that the sweep's chain of dependent operations
   (each point's rows wait for the last one's push) stays short. */
#define DOT3(x, y, k) ((x)[0][k] * (y)[0][k] + (x)[1][k] * (y)[1][k] + (x)[2][k] * (y)[2][k])
#define RATE(bt, p, s, d, k)                                                                                    \
    (((bt)->dir[d][0][k] * ((s)->vb[0][k] - (s)->va[0][k]) + (bt)->dir[d][1][k] * ((s)->vb[1][k] - (s)->va[1][k]) + \
      (bt)->dir[d][2][k] * ((s)->vb[2][k] - (s)->va[2][k])) +                                                   \
     (DOT3((p)->arm_b[d], (s)->wb, k) - DOT3((p)->arm_a[d], (s)->wa, k)))

/* An impulse l along row d of point p on lane k: -l on a, +l on b.
   (Written out: a loop over the axes inside the loop over lanes keeps GCC
   from vectorising the lanes.) */
#define PUSH(bt, p, s, d, k, l)                                        \
    do {                                                               \
        const double la_ = (l) * (s)->ma[k], lb_ = (l) * (s)->mb[k];   \
        (s)->va[0][k] -= la_ * (bt)->dir[d][0][k];                     \
        (s)->va[1][k] -= la_ * (bt)->dir[d][1][k];                     \
        (s)->va[2][k] -= la_ * (bt)->dir[d][2][k];                     \
        (s)->wa[0][k] -= (l) * (p)->turn_a[d][0][k];                   \
        (s)->wa[1][k] -= (l) * (p)->turn_a[d][1][k];                   \
        (s)->wa[2][k] -= (l) * (p)->turn_a[d][2][k];                   \
        (s)->vb[0][k] += lb_ * (bt)->dir[d][0][k];                     \
        (s)->vb[1][k] += lb_ * (bt)->dir[d][1][k];                     \
        (s)->vb[2][k] += lb_ * (bt)->dir[d][2][k];                     \
        (s)->wb[0][k] += (l) * (p)->turn_b[d][0][k];                   \
        (s)->wb[1][k] += (l) * (p)->turn_b[d][1][k];                   \
        (s)->wb[2][k] += (l) * (p)->turn_b[d][2][k];                   \
    } while (0)

/* One point of every lane: friction first, within the circle mu times
   the normal impulse, then the normal, v_n >= target. A lane without this
   point has zero masses and friction, so its impulses stay 0. */
TB__LANE void velocity_point(const tb__batch *restrict bt, tb__lane_point *restrict p, sides *restrict s)
{
    double t0[W], t1[W], len2[W], limit[W], limit2[W];
    int k, outside = 0;
    for (k = 0; k < W; ++k) {
        limit[k] = bt->friction[k] * p->impulse[0][k];
        t0[k] = p->impulse[1][k] - p->mass[1][k] * RATE(bt, p, s, 1, k);
        t1[k] = p->impulse[2][k] - p->mass[2][k] * RATE(bt, p, s, 2, k);
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
        const double d0 = t0[k] - p->impulse[1][k], d1 = t1[k] - p->impulse[2][k];
        double total, dn;
        PUSH(bt, p, s, 1, k, d0);
        PUSH(bt, p, s, 2, k, d1);
        p->impulse[1][k] = t0[k], p->impulse[2][k] = t1[k];
        total = p->impulse[0][k] - p->mass[0][k] * (RATE(bt, p, s, 0, k) - p->target[k]);
        total = total > 0 ? total : 0;
        dn = total - p->impulse[0][k];
        PUSH(bt, p, s, 0, k, dn);
        p->impulse[0][k] = total;
    }
}

/* One point of every lane in the position pass: the normal row only, on
   (dp, dtheta), toward push_target; a row that never pushed and is not
   short of its target is left alone. */
TB__LANE void position_point(const tb__batch *restrict bt, tb__lane_point *restrict p, sides *restrict s)
{
    int k;
    for (k = 0; k < W; ++k) {
        const double now = p->predicted[k] + RATE(bt, p, s, 0, k);
        const double old = p->position_impulse[k];
        double total = old - p->mass[0][k] * (now - p->push_target[k]);
        double dn;
        total = total > 0 ? total : 0;
        total = now >= p->push_target[k] && old == 0 ? 0 : total; /* idle */
        dn = total - p->position_impulse[k];
        PUSH(bt, p, s, 0, k, dn);
        p->position_impulse[k] = total;
    }
}

TB__LANE void velocity_batches(tb__batch *batches, size_t n, double *m, int backwards)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        tb__batch *bt = &batches[backwards ? n - 1 - i : i];
        sides s;
        int j;
        gather(bt, m, &s);
        for (j = 0; j < bt->points; ++j)
            velocity_point(bt, &bt->point[backwards ? bt->points - 1 - j : j], &s);
        scatter(bt, m, &s);
    }
}

TB__LANE void position_batches(tb__batch *batches, size_t n, double *m)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        tb__batch *bt = &batches[i];
        sides s;
        int j;
        gather(bt, m, &s);
        for (j = 0; j < bt->points; ++j)
            position_point(bt, &bt->point[j], &s);
        scatter(bt, m, &s);
    }
}

#define TB__SWEEPS(isa, attr)                                                                      \
    attr static void velocity_##isa(tb__batch *batches, size_t n, double *m, int backwards)        \
    {                                                                                              \
        velocity_batches(batches, n, m, backwards);                                                \
    }                                                                                              \
    attr static void position_##isa(tb__batch *batches, size_t n, double *m)                       \
    {                                                                                              \
        position_batches(batches, n, m);                                                           \
    }

TB__SWEEPS(portable, )
#if TB__X86_DISPATCH
TB__SWEEPS(avx2, TB__TARGET_AVX2)
TB__SWEEPS(avx512, TB__TARGET_AVX512)
#endif

void tb__sweep_velocities(tb__batch *batches, size_t n, double *m, int backwards, int isa)
{
#if TB__X86_DISPATCH
    if (isa == TB__ISA_AVX512)
        velocity_avx512(batches, n, m, backwards);
    else if (isa == TB__ISA_AVX2)
        velocity_avx2(batches, n, m, backwards);
    else
#endif
        velocity_portable(batches, n, m, backwards);
    (void)isa;
}

void tb__sweep_positions(tb__batch *batches, size_t n, double *m, int isa)
{
#if TB__X86_DISPATCH
    if (isa == TB__ISA_AVX512)
        position_avx512(batches, n, m);
    else if (isa == TB__ISA_AVX2)
        position_avx2(batches, n, m);
    else
#endif
        position_portable(batches, n, m);
    (void)isa;
}
