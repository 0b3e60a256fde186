/* broadphase.c: sweep and prune over axis-aligned boxes (collision.h). */
#include "collision/collision.h"

#include <math.h>
#include <string.h>

/* A proxy's low end on the sweep axis. Ties go by index, so the sorted
   order is a function of the boxes alone, not of the path the sort took. */
typedef struct tb__sap_key {
    double key;
    uint32_t index;
} tb__sap_key;

/* The sweep's candidates are first tested in floats, four at a time, from
   five arrays in sweep order (lanes): lo0, lo1, lo2, -hi1, -hi2, with 0 the
   sweep axis and 1, 2 the others, so that every test reads x <= y
   (-hi1 <= -lo1' is lo1' <= hi1). Rounding to
   float is monotonic, so that test passes every pair the test in doubles
   passes, in half the bytes; the few that pass are tested again in
   doubles, which alone decide. Each array has TB__SAP_PAD NaNs past its
   end: no test passes on them, so the walk needs no bound check and the
   last group of four needs no tail loop. */
#define TB__SAP_PAD 4
#define TB__SAP_LANES 5

/* A proxy in sweep order: its box and filter, so that the exact test of the
   hits (which lie a few places after the proxy they pair with) reads
   memory next to memory it has just read. */
typedef struct tb__sap_proxy {
    double lo[3], hi[3];
    uint32_t category, mask, group, index;
} tb__sap_proxy;

/* SSE2 where every x86-64 compiler has it; TB__SAP_SCALAR forces the
   portable loop (it gives the same pairs: the doubles decide). */
#if !defined(TB__SAP_SCALAR) && (defined(__SSE2__) || defined(_M_X64) || \
                                 (defined(_M_IX86_FP) && _M_IX86_FP >= 2))
#include <emmintrin.h>
#define TB__SAP_SSE 1

/* For each mask of four lanes, the lanes that are set, first: one store
   writes all four candidate indices and the count keeps those that hit. */
static const uint32_t tb__sap_compact[16][4] = {
    { 0, 0, 0, 0 }, { 0, 0, 0, 0 }, { 1, 0, 0, 0 }, { 0, 1, 0, 0 },
    { 2, 0, 0, 0 }, { 0, 2, 0, 0 }, { 1, 2, 0, 0 }, { 0, 1, 2, 0 },
    { 3, 0, 0, 0 }, { 0, 3, 0, 0 }, { 1, 3, 0, 0 }, { 0, 1, 3, 0 },
    { 2, 3, 0, 0 }, { 0, 2, 3, 0 }, { 1, 2, 3, 0 }, { 0, 1, 2, 3 },
};
static const unsigned char tb__sap_popcount[16] = { 0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4 };
#else
#define TB__SAP_SSE 0
#endif

/* Where the scratch for n proxies lies in the order block, in bytes. Only
   order[0, n) outlives a call, and it stays at the front, so growing the
   block by realloc keeps it. */
typedef struct tb__sap_layout {
    size_t keys, proxies, lanes, hits, counts, next, units; /* units: the block's size in uint32_t */
} tb__sap_layout;

#define TB__SAP_ROUND(x) (((x) + 15) & ~(size_t)15)

/* Past this many moves an insertion sort has met a list that is not nearly
   sorted, and the merge sort (about n log n moves) is cheaper to finish. */
#define TB__SAP_BUDGET(n) (4 * (n) + 64)

/* The best axis must beat the current one's variance by this factor before
   the order is thrown away for a full sort on it: so an axis that wins by a
   little from step to step does not cost a full sort every step. */
#define TB__SAP_SWITCH 2.0

static int sap_layout_of(size_t n, tb__sap_layout *l)
{
    const size_t per = sizeof(uint32_t) + sizeof(tb__sap_key) + sizeof(tb__sap_proxy) +
                       TB__SAP_LANES * sizeof(float) + sizeof(uint32_t) + 2 * sizeof(size_t) + sizeof(uint32_t);
    if (n > (SIZE_MAX / 4 - 256) / per)
        return 0;
    l->keys = TB__SAP_ROUND(n * sizeof(uint32_t));
    l->proxies = TB__SAP_ROUND(l->keys + n * sizeof(tb__sap_key));
    l->lanes = TB__SAP_ROUND(l->proxies + n * sizeof(tb__sap_proxy));
    l->hits = TB__SAP_ROUND(l->lanes + TB__SAP_LANES * (n + TB__SAP_PAD) * sizeof(float));
    l->counts = TB__SAP_ROUND(l->hits + (n + 2 * TB__SAP_PAD) * sizeof(uint32_t));
    l->next = TB__SAP_ROUND(l->counts + 2 * n * sizeof(size_t));
    l->units = TB__SAP_ROUND(l->next + (n + 1) * sizeof(uint32_t)) / sizeof(uint32_t);
    return 1;
}

/* The axis along which the box centres spread most (variance), or the
   current one unless another beats it clearly. Infinite boxes (planes) have
   no centre and are left out. */
static int sap_axis(size_t n, const double *lo, const double *hi, int current, int fresh)
{
    double sum[3] = { 0, 0, 0 }, sq[3] = { 0, 0, 0 }, shift[3], var[3];
    size_t used[3] = { 0, 0, 0 }, i;
    int d, best = 0;
    /* shifting by one centre keeps sq - sum^2/m from cancelling when the
       scene is far from the origin */
    for (d = 0; d < 3; ++d) {
        const double c = lo[d] + hi[d];
        shift[d] = isfinite(c) ? c : 0;
    }
    /* a sample of a few hundred boxes tells the spread as well as all of
       them, at a fraction of the cost of a call */
    for (i = 0; i < n; i += n / 256 + 1) {
        for (d = 0; d < 3; ++d) {
            const double c = lo[3 * i + d] + hi[3 * i + d] - shift[d];
            if (isfinite(c)) {
                sum[d] += c;
                sq[d] += c * c;
                used[d]++;
            }
        }
    }
    for (d = 0; d < 3; ++d) {
        var[d] = used[d] ? (sq[d] - sum[d] * sum[d] / (double)used[d]) / (double)used[d] : 0;
        if (var[d] > var[best])
            best = d;
    }
    if (fresh || var[best] > TB__SAP_SWITCH * var[current])
        return best;
    return current;
}

static int sap_less(const tb__sap_key *x, const tb__sap_key *y)
{
    return x->key < y->key || (x->key == y->key && x->index < y->index);
}

/* 1 when sorted; 0 when it gave up after `budget` moves, the keys then a
   permutation of what they were. */
static int sap_insertion_sort(tb__sap_key *a, size_t n, size_t budget)
{
    size_t i, j, moves = 0;
    for (i = 1; i < n; ++i) {
        const tb__sap_key t = a[i];
        if (!sap_less(&t, &a[i - 1]))
            continue;
        j = i;
        do {
            a[j] = a[j - 1];
            --j;
        } while (j > 0 && sap_less(&t, &a[j - 1]));
        a[j] = t;
        moves += i - j;
        if (moves > budget)
            return 0;
    }
    return 1;
}

/* Bottom-up merge sort, runs of 8 by insertion first; tmp holds n keys. */
static void sap_merge_sort(tb__sap_key *a, tb__sap_key *tmp, size_t n)
{
    tb__sap_key *src = a, *dst = tmp, *swap;
    size_t width, start;
    for (start = 0; start < n; start += 8)
        sap_insertion_sort(a + start, n - start < 8 ? n - start : 8, SIZE_MAX);
    for (width = 8; width < n; width *= 2) {
        for (start = 0; start < n; start += 2 * width) {
            const size_t mid = n - start < width ? n : start + width;
            const size_t end = n - start < 2 * width ? n : start + 2 * width;
            size_t i = start, j = mid, k = start;
            while (i < mid && j < end)
                dst[k++] = sap_less(&src[j], &src[i]) ? src[j++] : src[i++];
            while (i < mid)
                dst[k++] = src[i++];
            while (j < end)
                dst[k++] = src[j++];
        }
        swap = src;
        src = dst;
        dst = swap;
    }
    if (src != a)
        memcpy(a, src, n * sizeof *a);
}

/* Make order[0, n) a permutation of 0..n-1 after the proxies changed:
   keep the kept order of the indices still below n (after a swap-remove
   most of them still name the same boxes, so the list stays nearly sorted)
   and append the others. seen: n scratch entries. */
static void sap_renumber(uint32_t *order, size_t kept, size_t n, size_t *seen)
{
    size_t k, m = 0, valid;
    uint32_t i;
    /* compact first: seen may overlay the kept entries past n */
    for (k = 0; k < kept && m < n; ++k)
        if (order[k] < n)
            order[m++] = order[k];
    memset(seen, 0, n * sizeof *seen);
    valid = 0;
    for (k = 0; k < m; ++k) {
        i = order[k];
        if (!seen[i]) {
            seen[i] = 1;
            order[valid++] = i;
        }
    }
    for (i = 0; i < n; ++i)
        if (!seen[i])
            order[valid++] = i;
}

static int pair_less(tb__pair x, tb__pair y)
{
    return x.a < y.a || (x.a == y.a && x.b < y.b);
}

/* Sort by (a, b): two stable counting passes, by b then by a (both < n),
   whose counts are taken in one pass. tmp: count pairs; counts: 2n
   entries. Short or sorted lists skip them. */
static void sap_sort_pairs(tb__pair *p, size_t count, tb__pair *tmp, size_t *counts, size_t n)
{
    size_t *by_a = counts, *by_b = counts + n;
    size_t k, sum_a, sum_b;
    for (k = 1; k < count && !pair_less(p[k], p[k - 1]); ++k)
        ;
    if (k >= count)
        return;
    if (count <= 32) {
        for (; k < count; ++k) {
            const tb__pair t = p[k];
            size_t j = k;
            while (j > 0 && pair_less(t, p[j - 1])) {
                p[j] = p[j - 1];
                --j;
            }
            p[j] = t;
        }
        return;
    }
    memset(counts, 0, 2 * n * sizeof *counts);
    for (k = 0; k < count; ++k) {
        by_a[p[k].a]++;
        by_b[p[k].b]++;
    }
    for (k = 0, sum_a = 0, sum_b = 0; k < n; ++k) {
        const size_t ca = by_a[k], cb = by_b[k];
        by_a[k] = sum_a;
        by_b[k] = sum_b;
        sum_a += ca;
        sum_b += cb;
    }
    for (k = 0; k < count; ++k)
        tmp[by_b[p[k].b]++] = p[k];
    for (k = 0; k < count; ++k)
        p[by_a[tmp[k].a]++] = tmp[k];
}

tb_status tb__sap_pairs(tb_world *w, tb__sap *sap, size_t n, const double *lo, const double *hi,
                        const uint32_t *category, const uint32_t *mask, const uint32_t *group,
                        tb__pair **pairs, size_t *count, size_t *cap)
{
    return tb__sap_moving_pairs(w, sap, n, lo, hi, category, mask, group, NULL, pairs, count, cap);
}

tb_status tb__sap_moving_pairs(tb_world *w, tb__sap *sap, size_t n, const double *lo, const double *hi,
                               const uint32_t *category, const uint32_t *mask, const uint32_t *group,
                               const uint32_t *still, tb__pair **pairs, size_t *count, size_t *cap)
{
    tb__sap_layout layout;
    tb__sap_key *keys;
    tb__sap_proxy *proxy;
    float *lane[TB__SAP_LANES];
    size_t *counts;
    uint32_t *order, *hits, *next;
    tb__pair *out;
    size_t k, m, found, room;
    int axis, a1, a2, fits, d;
    tb_status status;

    *count = 0;
    if (n >= UINT32_MAX)
        return tb__fail(w, TB_ERR_ARGUMENT, "broadphase: %zu proxies, at most %lu", n,
                        (unsigned long)UINT32_MAX - 1);
    if (!sap_layout_of(n, &layout))
        return tb__fail(w, TB_ERR_MEMORY, "broadphase: %zu proxies overflow the address space", n);
    if (sap->axis < 0 || sap->axis > 2) {
        sap->axis = 0;
        sap->count = 0;
    }
    if (n == 0) {
        sap->count = 0;
        return TB_OK;
    }
    /* every proxy still: no pair is wanted, and the kept order stays as it
       is (it only speeds the next sort) */
    if (still) {
        for (k = 0; k < n && still[k]; ++k)
            ;
        if (k == n)
            return TB_OK;
    }
    status = tb__reserve(w, (void **)&sap->order, &sap->cap, layout.units, sizeof(uint32_t));
    if (status != TB_OK)
        return status;
    order = sap->order;
    keys = (tb__sap_key *)(void *)((unsigned char *)order + layout.keys);
    proxy = (tb__sap_proxy *)(void *)((unsigned char *)order + layout.proxies);
    lane[0] = (float *)(void *)((unsigned char *)order + layout.lanes);
    for (d = 1; d < TB__SAP_LANES; ++d)
        lane[d] = lane[d - 1] + n + TB__SAP_PAD;
    hits = (uint32_t *)(void *)((unsigned char *)order + layout.hits);
    counts = (size_t *)(void *)((unsigned char *)order + layout.counts);
    next = (uint32_t *)(void *)((unsigned char *)order + layout.next);

    axis = sap_axis(n, lo, hi, sap->axis, sap->count == 0);
    /* the world renumbers by swap-remove: a kept order still fits when n
       is unchanged and it names no proxy past n */
    fits = n == sap->count;
    for (k = 0; fits && k < n; ++k)
        fits = order[k] < n;
    if (!fits)
        sap_renumber(order, sap->count, n, counts);
    for (k = 0; k < n; ++k) {
        keys[k].key = lo[3 * (size_t)order[k] + axis];
        keys[k].index = order[k];
    }
    if (axis != sap->axis || !sap_insertion_sort(keys, n, TB__SAP_BUDGET(n)))
        sap_merge_sort(keys, (tb__sap_key *)(void *)proxy, n);

    a1 = (axis + 1) % 3;
    a2 = (axis + 2) % 3;
    for (k = 0; k < n; ++k) {
        const size_t i = keys[k].index;
        tb__sap_proxy *p = &proxy[k];
        order[k] = (uint32_t)i;
        for (d = 0; d < 3; ++d) {
            p->lo[d] = lo[3 * i + d];
            p->hi[d] = hi[3 * i + d];
        }
        /* no filter: every bit, a group of its own */
        p->category = category ? category[i] : UINT32_MAX;
        p->mask = mask ? mask[i] : UINT32_MAX;
        p->group = group ? group[i] : (uint32_t)i;
        p->index = (uint32_t)i;
        lane[0][k] = (float)p->lo[axis];
        lane[1][k] = (float)p->lo[a1];
        lane[2][k] = (float)p->lo[a2];
        lane[3][k] = -(float)p->hi[a1];
        lane[4][k] = -(float)p->hi[a2];
    }
    for (d = 0; d < TB__SAP_LANES; ++d)
        for (k = n; k < n + TB__SAP_PAD; ++k)
            lane[d][k] = (float)NAN;
    sap->count = n;
    sap->axis = axis;
    /* next[k]: the first place from k on whose proxy is not still (n:
       none), so that a still proxy with none in its reach is passed over
       in one test (a sleeping pile costs no sweep) */
    next[n] = (uint32_t)n;
    for (k = n; k-- > 0;)
        next[k] = still && still[order[k]] ? next[k + 1] : (uint32_t)k;

    /* the sweep: every box after this one in the order whose low end is
       not past this one's high end overlaps it on the sweep axis. Whether
       such a candidate also overlaps on the other two is a coin toss that
       a branch predictor loses, so that test is branch-free and only
       collects the hits; the hits are then tested exactly. */
    found = 0;
    out = *pairs;
    room = *cap;
    for (k = 0; k < n; ++k) {
        const tb__sap_proxy p = proxy[k];
        const double *plo = p.lo, *phi = p.hi;
        const float top = (float)phi[axis];
        const int p_still = next[k] != k;
        size_t h = 0, j;
        if (p_still && (next[k + 1] == n || !(lane[0][next[k + 1]] <= top)))
            continue;
#if TB__SAP_SSE
        const __m128 y0 = _mm_set1_ps(top), y1 = _mm_set1_ps((float)phi[a1]), y2 = _mm_set1_ps((float)phi[a2]),
                     y3 = _mm_set1_ps(-(float)plo[a1]), y4 = _mm_set1_ps(-(float)plo[a2]);
        /* lane[0] is sorted: once its first value is past the top, so are
           all after it */
        for (m = k + 1; lane[0][m] <= top; m += 4) {
            __m128 t = _mm_cmple_ps(_mm_loadu_ps(lane[0] + m), y0);
            unsigned bits;
            t = _mm_and_ps(t, _mm_cmple_ps(_mm_loadu_ps(lane[1] + m), y1));
            t = _mm_and_ps(t, _mm_cmple_ps(_mm_loadu_ps(lane[2] + m), y2));
            t = _mm_and_ps(t, _mm_cmple_ps(_mm_loadu_ps(lane[3] + m), y3));
            t = _mm_and_ps(t, _mm_cmple_ps(_mm_loadu_ps(lane[4] + m), y4));
            bits = (unsigned)_mm_movemask_ps(t);
            _mm_storeu_si128((__m128i *)(void *)(hits + h),
                             _mm_add_epi32(_mm_set1_epi32((int)m),
                                           _mm_loadu_si128((const __m128i *)(const void *)tb__sap_compact[bits])));
            h += tb__sap_popcount[bits];
        }
#else
        const float y1 = (float)phi[a1], y2 = (float)phi[a2], y3 = -(float)plo[a1], y4 = -(float)plo[a2];
        for (m = k + 1; lane[0][m] <= top; ++m) {
            hits[h] = (uint32_t)m;
            h += (size_t)((lane[1][m] <= y1) & (lane[2][m] <= y2) & (lane[3][m] <= y3) & (lane[4][m] <= y4));
        }
#endif
        for (j = 0; j < h; ++j) {
            const tb__sap_proxy *q = &proxy[hits[j]];
            const uint32_t a = p.index < q->index ? p.index : q->index;
            const uint32_t b = p.index < q->index ? q->index : p.index;
            if (!(q->lo[0] <= phi[0] && plo[0] <= q->hi[0] && q->lo[1] <= phi[1] && plo[1] <= q->hi[1] &&
                  q->lo[2] <= phi[2] && plo[2] <= q->hi[2]))
                continue;
            if (!(p.category & q->mask) || !(q->category & p.mask) || p.group == q->group)
                continue;
            if (p_still && next[hits[j]] != hits[j])
                continue;
            if (found == room) {
                status = tb__reserve(w, (void **)pairs, cap, found + 1, sizeof(tb__pair));
                if (status != TB_OK)
                    return status;
                out = *pairs;
                room = *cap;
            }
            out[found].a = a;
            out[found].b = b;
            ++found;
        }
    }

    /* the pair sort borrows the buffer past the pairs */
    if (found > 32 && room / 2 < found) {
        status = tb__reserve(w, (void **)pairs, cap, 2 * found, sizeof(tb__pair));
        if (status != TB_OK)
            return status;
        out = *pairs;
    }
    /* no pairs: nothing to sort, and out may be NULL (fuzz_api's
       regressions) */
    if (found > 1)
        sap_sort_pairs(out, found, out + found, counts, n);
    *count = found;
    return TB_OK;
}

void tb__sap_free(tb_world *w, tb__sap *sap)
{
    if (sap->order)
        tb__alloc(w, sap->order, sap->cap * sizeof(uint32_t), 0);
    sap->order = NULL;
    sap->count = 0;
    sap->cap = 0;
    sap->axis = 0;
}
