/* test_broadphase.c: the sweep and prune (src/collision/broadphase.c) against a
   brute-force O(n^2) pair list, exactly, through the paths its kept order
   takes: first sort, small moves (insertion sort), large moves and axis
   changes (full sort), proxies removed by swap-remove and added; then the
   edges of the overlap test (touching), the filters, the output order, and
   its memory (allocation failures, no allocation in steady state). */
#include "test_main.h"
#include "counting_alloc.h"
#include "collision/collision.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------ helpers -- */

typedef struct rng { uint64_t s; } rng;

/* splitmix64: a fixed seed gives the same scenes everywhere */
static double uniform(rng *r, double a, double b)
{
    uint64_t z = (r->s += 0x9E3779B97F4A7C15u);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9u;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBu;
    z ^= z >> 31;
    return a + (b - a) * (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

static uint32_t below(rng *r, uint32_t n)
{
    return (uint32_t)uniform(r, 0, n);
}

#define MAX_PROXIES 1200

typedef struct scene {
    size_t n;
    double lo[3 * MAX_PROXIES], hi[3 * MAX_PROXIES];
    uint32_t category[MAX_PROXIES], mask[MAX_PROXIES], group[MAX_PROXIES];
    int filtered;      /* pass the filter arrays, else NULL */
} scene;

/* Box i: centre uniform in [0, extent[d]], half size in [0, half]. */
static void random_box(scene *s, size_t i, rng *r, const double extent[3], double half)
{
    int d;
    for (d = 0; d < 3; ++d) {
        const double c = uniform(r, 0, extent[d]), h = uniform(r, 0, half);
        s->lo[3 * i + d] = c - h;
        s->hi[3 * i + d] = c + h;
    }
    s->category[i] = 1;
    s->mask[i] = UINT32_MAX;
    s->group[i] = (uint32_t)i;
}

static void random_scene(scene *s, size_t n, rng *r, const double extent[3], double half)
{
    size_t i;
    s->n = n;
    s->filtered = 0;
    for (i = 0; i < n; ++i)
        random_box(s, i, r, extent, half);
}

static void move_box(scene *s, size_t i, const double by[3])
{
    int d;
    for (d = 0; d < 3; ++d) {
        s->lo[3 * i + d] += by[d];
        s->hi[3 * i + d] += by[d];
    }
}

static void jitter(scene *s, rng *r, double step)
{
    size_t i;
    for (i = 0; i < s->n; ++i) {
        const double by[3] = { uniform(r, -step, step), uniform(r, -step, step), uniform(r, -step, step) };
        move_box(s, i, by);
    }
}

/* What the world does on removal: the last proxy takes the freed slot. */
static void swap_remove(scene *s, size_t k)
{
    const size_t last = s->n - 1;
    memcpy(&s->lo[3 * k], &s->lo[3 * last], 3 * sizeof(double));
    memcpy(&s->hi[3 * k], &s->hi[3 * last], 3 * sizeof(double));
    s->category[k] = s->category[last];
    s->mask[k] = s->mask[last];
    s->group[k] = s->group[last];
    s->n = last;
}

static int accepts(const scene *s, size_t a, size_t b)
{
    if (!s->filtered)
        return 1;
    return (s->category[a] & s->mask[b]) && (s->category[b] & s->mask[a]) && s->group[a] != s->group[b];
}

static int overlap(const scene *s, size_t a, size_t b)
{
    int d;
    for (d = 0; d < 3; ++d)
        if (!(s->lo[3 * a + d] <= s->hi[3 * b + d] && s->lo[3 * b + d] <= s->hi[3 * a + d]))
            return 0;
    return 1;
}

/* The reference: every pair, in (a, b) order. out holds n(n-1)/2. */
static size_t brute_force(const scene *s, tb__pair *out)
{
    size_t a, b, count = 0;
    for (a = 0; a < s->n; ++a)
        for (b = a + 1; b < s->n; ++b)
            if (overlap(s, a, b) && accepts(s, a, b)) {
                out[count].a = (uint32_t)a;
                out[count].b = (uint32_t)b;
                ++count;
            }
    return count;
}

/* ---- a world, a sap and a pair buffer, through a counting allocator ---- */

typedef struct fixture {
    budget mem;
    tb_world *w;
    tb__sap sap;
    tb__pair *pairs;
    size_t count, cap;
    tb__pair *expected; /* brute force, MAX_PROXIES^2 / 2 */
} fixture;

static fixture *fixture_new(void)
{
    fixture *f = calloc(1, sizeof *f);
    tb_world_def def = tb_default_world_def();
    assert_non_null(f);
    f->mem.fail_after = -1;
    def.allocator.realloc = counting_realloc;
    def.allocator.user = &f->mem;
    assert_int_equal(tb_world_create(&def, &f->w, NULL, 0), TB_OK);
    f->expected = malloc((size_t)MAX_PROXIES * MAX_PROXIES / 2 * sizeof(tb__pair));
    assert_non_null(f->expected);
    return f;
}

static void fixture_free(fixture *f)
{
    tb__sap_free(f->w, &f->sap);
    assert_null(f->sap.order);
    if (f->pairs)
        tb__alloc(f->w, f->pairs, f->cap * sizeof(tb__pair), 0);
    tb_world_destroy(f->w);
    assert_int_equal(f->mem.live_bytes, 0);
    assert_false(f->mem.size_mismatch);
    free(f->expected);
    free(f);
}

static tb_status find_pairs(fixture *f, const scene *s)
{
    return tb__sap_pairs(f->w, &f->sap, s->n, s->lo, s->hi, s->filtered ? s->category : NULL,
                         s->filtered ? s->mask : NULL, s->filtered ? s->group : NULL, &f->pairs,
                         &f->count, &f->cap);
}

/* The kept order is a permutation of the proxies, sorted by low end on the
   sweep axis, ties by index (so it does not depend on the calls before). */
static void check_order(const fixture *f, const scene *s)
{
    unsigned char *seen = calloc(s->n + 1, 1);
    size_t k;
    assert_non_null(seen);
    assert_int_equal(f->sap.count, s->n);
    assert_true(f->sap.axis >= 0 && f->sap.axis <= 2);
    for (k = 0; k < s->n; ++k) {
        const uint32_t i = f->sap.order[k];
        assert_true(i < s->n);
        assert_false(seen[i]);
        seen[i] = 1;
        if (k > 0) {
            const uint32_t prev = f->sap.order[k - 1];
            const double x = s->lo[3 * prev + f->sap.axis], y = s->lo[3 * i + f->sap.axis];
            assert_true(x < y || (x == y && prev < i));
        }
    }
    free(seen);
}

/* The call gives exactly the brute-force pairs, in the same order. */
static void check_pairs(fixture *f, const scene *s)
{
    size_t expected, k;
    assert_int_equal(find_pairs(f, s), TB_OK);
    expected = brute_force(s, f->expected);
    for (k = 0; k < f->count && k < expected; ++k)
        if (f->pairs[k].a != f->expected[k].a || f->pairs[k].b != f->expected[k].b)
            fail_msg("n = %zu: pair %zu is (%u, %u), expected (%u, %u)", s->n, k, (unsigned)f->pairs[k].a,
                     (unsigned)f->pairs[k].b, (unsigned)f->expected[k].a, (unsigned)f->expected[k].b);
    if (f->count != expected)
        fail_msg("n = %zu: %zu pairs, expected %zu", s->n, f->count, expected);
    if (s->n > 0)
        check_order(f, s);
}

static scene *scene_new(void)
{
    scene *s = calloc(1, sizeof *s);
    assert_non_null(s);
    return s;
}

/* -------------------------------------------------------------- tests -- */

static void random_boxes_match_brute_force(void **state)
{
    static const size_t sizes[] = { 2, 3, 7, 50, 300, 1000 };
    static const double halves[] = { 0.05, 0.5, 3 };
    const double extent[3] = { 10, 10, 10 };
    fixture *f = fixture_new(), *fresh;
    scene *s = scene_new();
    rng r = { 1 };
    size_t i, j;
    (void)state;
    for (i = 0; i < sizeof sizes / sizeof sizes[0]; ++i)
        for (j = 0; j < sizeof halves / sizeof halves[0]; ++j) {
            random_scene(s, sizes[i], &r, extent, halves[j]);
            /* one sap kept through all the scenes, and a fresh one */
            check_pairs(f, s);
            fresh = fixture_new();
            check_pairs(fresh, s);
            fixture_free(fresh);
        }
    fixture_free(f);
    free(s);
}

static void small_moves_keep_matching(void **state)
{
    const double extent[3] = { 20, 10, 10 };
    fixture *f = fixture_new();
    scene *s = scene_new();
    rng r = { 2 };
    int step, axis;
    (void)state;
    random_scene(s, 500, &r, extent, 0.5);
    check_pairs(f, s);
    axis = f->sap.axis;
    assert_int_equal(axis, 0);
    for (step = 0; step < 60; ++step) {
        jitter(s, &r, 0.05);
        check_pairs(f, s);
        assert_int_equal(f->sap.axis, axis);
    }
    fixture_free(f);
    free(s);
}

static void large_moves_and_axis_changes(void **state)
{
    static const double extents[][3] = {
        { 100, 5, 5 }, { 5, 5, 100 }, { 5, 100, 5 }, { 100, 5, 5 }, { 30, 30, 30 },
    };
    static const int axes[] = { 0, 2, 1, 0, -1 };
    fixture *f = fixture_new();
    scene *s = scene_new();
    rng r = { 3 };
    size_t e, i;
    (void)state;
    random_scene(s, 400, &r, extents[0], 1);
    for (e = 0; e < sizeof axes / sizeof axes[0]; ++e) {
        /* the same proxies carried somewhere else: the kept order is useless */
        for (i = 0; i < s->n; ++i)
            random_box(s, i, &r, extents[e], 1);
        check_pairs(f, s);
        if (axes[e] >= 0)
            assert_int_equal(f->sap.axis, axes[e]);
        jitter(s, &r, 0.1);
        check_pairs(f, s);
    }
    /* a few boxes teleported in a scene otherwise at rest */
    for (i = 0; i < 20; ++i) {
        const size_t k = below(&r, (uint32_t)s->n);
        const double by[3] = { uniform(&r, -20, 20), uniform(&r, -20, 20), uniform(&r, -20, 20) };
        move_box(s, k, by);
        check_pairs(f, s);
    }
    /* the boxes reversed along the sweep axis: the worst insertion sort */
    for (i = 0; i < s->n; ++i) {
        int d;
        for (d = 0; d < 3; ++d) {
            const double l = s->lo[3 * i + d];
            s->lo[3 * i + d] = -s->hi[3 * i + d];
            s->hi[3 * i + d] = -l;
        }
    }
    check_pairs(f, s);
    fixture_free(f);
    free(s);
}

static void proxies_removed_and_added(void **state)
{
    const double extent[3] = { 10, 10, 10 };
    fixture *f = fixture_new();
    scene *s = scene_new();
    rng r = { 4 };
    int i;
    (void)state;
    random_scene(s, 300, &r, extent, 0.6);
    check_pairs(f, s);
    for (i = 0; i < 40; ++i) { /* one at a time, from anywhere, the last included */
        swap_remove(s, i % 7 == 0 ? s->n - 1 : below(&r, (uint32_t)s->n));
        check_pairs(f, s);
    }
    for (i = 0; i < 40; ++i) { /* added one at a time, while the rest move */
        random_box(s, s->n, &r, extent, 0.6);
        s->n++;
        jitter(s, &r, 0.02);
        check_pairs(f, s);
    }
    while (s->n > 10) /* many at once */
        swap_remove(s, below(&r, (uint32_t)s->n));
    check_pairs(f, s);
    while (s->n < 700) {
        random_box(s, s->n, &r, extent, 0.6);
        s->n++;
    }
    check_pairs(f, s);
    /* an order naming a proxy past n with n unchanged is rebuilt, not trusted */
    f->sap.order[3] = (uint32_t)s->n + 5;
    check_pairs(f, s);
    /* a sap whose axis is not an axis starts over */
    f->sap.axis = 7;
    check_pairs(f, s);
    /* down to one, to none, and back */
    s->n = 1;
    check_pairs(f, s);
    s->n = 0;
    check_pairs(f, s);
    s->n = 200;
    check_pairs(f, s);
    fixture_free(f);
    free(s);
}

/* Box 0 is [0, 1]^3; box 1 is beside it along axis d, below or above,
   touching or one ulp away; two far boxes along axis e make e the sweep
   axis, and box 1 starts before or after box 0 on it, so that each side of
   each test in the sweep meets the touching faces. */
static void touching_boxes_count(void **state)
{
    fixture *f = fixture_new();
    scene *s = scene_new();
    int d, e, below, before, apart, c;
    (void)state;
    s->n = 4;
    for (d = 0; d < 3; ++d)
        for (e = 0; e < 3; ++e)
            for (below = 0; below < 2; ++below)
                for (before = 0; before < 2; ++before)
                    for (apart = 0; apart < 2; ++apart) {
                        for (c = 0; c < 3; ++c) {
                            s->lo[c] = 0;
                            s->hi[c] = 1;
                            s->lo[3 + c] = c == e && before ? -0.25 : 0.25;
                            s->hi[3 + c] = 0.75;
                            s->lo[6 + c] = s->lo[9 + c] = 0;
                            s->hi[6 + c] = s->hi[9 + c] = 1;
                        }
                        s->lo[6 + e] = -1001;
                        s->hi[6 + e] = -1000;
                        s->lo[9 + e] = 1000;
                        s->hi[9 + e] = 1001;
                        if (below) {
                            s->lo[3 + d] = -1;
                            s->hi[3 + d] = apart ? nextafter(0, -1) : 0;
                        } else {
                            s->lo[3 + d] = apart ? nextafter(1, 2) : 1;
                            s->hi[3 + d] = 2;
                        }
                        check_pairs(f, s);
                        assert_int_equal(f->sap.axis, e);
                        assert_int_equal(f->count, apart ? 0 : 1);
                    }
    /* corner to corner, and points (empty boxes) on a face and on each other */
    for (e = 0; e < 3; ++e) {
        s->lo[e] = 0;
        s->hi[e] = 1;
        s->lo[3 + e] = 1;
        s->hi[3 + e] = 3;
        s->lo[6 + e] = s->hi[6 + e] = e == 0 ? 0 : 0.5;
        s->lo[9 + e] = s->hi[9 + e] = e == 0 ? 0 : 0.5;
    }
    s->n = 4;
    check_pairs(f, s);
    assert_int_equal(f->count, 4); /* (0,1) (0,2) (0,3) (2,3) */
    assert_true(f->pairs[0].a == 0 && f->pairs[0].b == 1);
    assert_true(f->pairs[3].a == 2 && f->pairs[3].b == 3);
    fixture_free(f);
    free(s);
}

static void filters_exclude_exactly(void **state)
{
    /* identical boxes: only the filters decide */
    static const struct { uint32_t category, mask, group; } proxies[] = {
        { 1, 2, 10 },          /* 0 */
        { 2, 1, 11 },          /* 1: with 0 both ways */
        { 1, 1, 12 },          /* 2: 0 wants it, it does not want 0 */
        { 2, 1, 10 },          /* 3: would pair with 0, same group */
        { 4, UINT32_MAX, 13 }, /* 4: wants everything, wanted by 5 and 7 */
        { 1, 4, 14 },          /* 5: with 4 */
        { 0, UINT32_MAX, 15 }, /* 6: no category, no pairs */
        { 2, 4, 16 },          /* 7: with 4; wants not 0, which wants it */
    };
    static const tb__pair expected[] = { { 0, 1 }, { 4, 5 }, { 4, 7 } };
    const double extent[3] = { 6, 6, 6 };
    fixture *f = fixture_new();
    scene *s = scene_new();
    rng r = { 5 };
    size_t i;
    int d;
    (void)state;
    s->n = sizeof proxies / sizeof proxies[0];
    s->filtered = 1;
    for (i = 0; i < s->n; ++i) {
        for (d = 0; d < 3; ++d) {
            s->lo[3 * i + d] = -1;
            s->hi[3 * i + d] = 1;
        }
        s->category[i] = proxies[i].category;
        s->mask[i] = proxies[i].mask;
        s->group[i] = proxies[i].group;
    }
    check_pairs(f, s);
    assert_int_equal(f->count, sizeof expected / sizeof expected[0]);
    for (i = 0; i < f->count; ++i)
        assert_true(f->pairs[i].a == expected[i].a && f->pairs[i].b == expected[i].b);

    /* random filters: few bits, few groups, so every rule bites */
    random_scene(s, 600, &r, extent, 0.7);
    s->filtered = 1;
    for (i = 0; i < s->n; ++i) {
        s->category[i] = 1u << below(&r, 4);
        s->mask[i] = below(&r, 16);
        s->group[i] = below(&r, 40);
    }
    check_pairs(f, s);
    /* and the unfiltered count is larger: the filters did remove pairs */
    {
        const size_t filtered = f->count;
        s->filtered = 0;
        check_pairs(f, s);
        assert_true(f->count > 2 * filtered);
    }
    fixture_free(f);
    free(s);
}

static void missing_filters_accept_everything(void **state)
{
    /* four identical boxes; a NULL array is every bit set, or a group per
       proxy */
    static const uint32_t category[] = { 1, 0, 2, 2 }, mask[] = { 0, 1, 2, 2 }, group[] = { 5, 5, 5, 6 };
    static const struct { int category, mask, group; size_t count; tb__pair first; } cases[] = {
        { 0, 0, 0, 6, { 0, 1 } }, /* no filter */
        { 1, 0, 0, 3, { 0, 2 } }, /* 1 has no category */
        { 0, 1, 0, 3, { 1, 2 } }, /* 0 wants nothing */
        { 0, 0, 1, 3, { 0, 3 } }, /* 0, 1, 2 share a group */
        { 1, 1, 1, 1, { 2, 3 } },
    };
    fixture *f = fixture_new();
    scene *s = scene_new();
    size_t i;
    (void)state;
    for (i = 0; i < 12; ++i)
        s->hi[i] = 1;
    for (i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        assert_int_equal(tb__sap_pairs(f->w, &f->sap, 4, s->lo, s->hi, cases[i].category ? category : NULL,
                                       cases[i].mask ? mask : NULL, cases[i].group ? group : NULL, &f->pairs,
                                       &f->count, &f->cap),
                         TB_OK);
        assert_int_equal(f->count, cases[i].count);
        assert_true(f->pairs[0].a == cases[i].first.a && f->pairs[0].b == cases[i].first.b);
    }
    fixture_free(f);
    free(s);
}

static void output_is_sorted(void **state)
{
    fixture *f = fixture_new();
    scene *s = scene_new();
    static const size_t sizes[] = { 4, 7, 40, 400 };
    size_t i, j, n;
    int d;
    (void)state;
    /* a row of overlapping boxes numbered across the sweep direction, so
       the sweep finds pairs far from (a, b) order; short and long lists */
    for (j = 0; j < sizeof sizes / sizeof sizes[0]; ++j) {
        s->n = n = sizes[j];
        for (i = 0; i < n; ++i)
            for (d = 0; d < 3; ++d) {
                const double c = d == 0 ? (double)((i * 37) % n) : 0;
                s->lo[3 * i + d] = c - 2.5;
                s->hi[3 * i + d] = c + 2.5;
            }
        check_pairs(f, s);
        assert_true(f->count > 0);
        for (i = 0; i < f->count; ++i) {
            assert_true(f->pairs[i].a < f->pairs[i].b);
            if (i > 0)
                assert_true(f->pairs[i - 1].a < f->pairs[i].a ||
                            (f->pairs[i - 1].a == f->pairs[i].a && f->pairs[i - 1].b < f->pairs[i].b));
        }
    }
    fixture_free(f);
    free(s);
}

static void no_proxies_and_one(void **state)
{
    fixture *f = fixture_new();
    scene *s = scene_new();
    (void)state;
    /* no boxes at all: nothing is read */
    assert_int_equal(tb__sap_pairs(f->w, &f->sap, 0, NULL, NULL, NULL, NULL, NULL, &f->pairs, &f->count,
                                   &f->cap),
                     TB_OK);
    assert_int_equal(f->count, 0);
    s->n = 1;
    s->hi[0] = s->hi[1] = s->hi[2] = 1;
    check_pairs(f, s);
    assert_int_equal(f->count, 0);
    assert_int_equal(f->sap.order[0], 0);
    s->n = 0;
    check_pairs(f, s);
    assert_int_equal(f->count, 0);
    fixture_free(f);
    free(s);
}

static void identical_boxes_pair_with_all(void **state)
{
    fixture *f = fixture_new();
    scene *s = scene_new();
    size_t i, a, b, k;
    int d;
    (void)state;
    s->n = 150;
    /* first a row numbered against the sweep, so that the kept order is
       not the index order when the boxes come together */
    for (i = 0; i < s->n; ++i)
        for (d = 0; d < 3; ++d) {
            s->lo[3 * i + d] = d == 0 ? -3.0 * (double)i : 1;
            s->hi[3 * i + d] = s->lo[3 * i + d] + 1;
        }
    check_pairs(f, s);
    assert_int_equal(f->sap.axis, 0);
    for (i = 0; i < s->n; ++i)
        for (d = 0; d < 3; ++d) {
            s->lo[3 * i + d] = 1;
            s->hi[3 * i + d] = 2;
        }
    check_pairs(f, s);
    assert_int_equal(f->count, s->n * (s->n - 1) / 2);
    for (a = 0, k = 0; a < s->n; ++a)
        for (b = a + 1; b < s->n; ++b, ++k)
            assert_true(f->pairs[k].a == a && f->pairs[k].b == b);
    /* all low ends equal on the sweep axis (x: the centres spread most
       there), apart on y: ties everywhere, no pairs */
    for (i = 0; i < s->n; ++i) {
        s->lo[3 * i] = 0;
        s->hi[3 * i] = 1000 + 100.0 * (double)i;
        s->lo[3 * i + 1] = 3.0 * (double)i;
        s->hi[3 * i + 1] = 3.0 * (double)i + 1;
    }
    check_pairs(f, s);
    assert_int_equal(f->sap.axis, 0);
    assert_int_equal(f->count, 0);
    fixture_free(f);
    free(s);
}

static void infinite_and_huge_boxes_are_fine(void **state)
{
    const double extent[3] = { 10, 10, 10 };
    fixture *f = fixture_new();
    scene *s = scene_new();
    rng r = { 6 };
    int d;
    (void)state;
    random_scene(s, 200, &r, extent, 0.5);
    /* a ground plane: everything below z = 2 */
    for (d = 0; d < 3; ++d) {
        s->lo[d] = -INFINITY;
        s->hi[d] = d == 2 ? 2 : INFINITY;
    }
    /* and boxes past the range of a float, which the sweep's first test
       sees in floats */
    for (d = 0; d < 3; ++d) {
        s->lo[3 + d] = -1e300;
        s->hi[3 + d] = d == 0 ? -1e299 : 1e300;
        s->lo[6 + d] = d == 1 ? 3e38 : 1;
        s->hi[6 + d] = d == 1 ? 1e300 : 9;
    }
    check_pairs(f, s);
    jitter(s, &r, 0.05);
    s->hi[2] = 2; /* the plane does not move */
    s->lo[0] = s->lo[1] = s->lo[2] = -INFINITY;
    s->hi[0] = s->hi[1] = INFINITY;
    check_pairs(f, s);
    fixture_free(f);
    free(s);
}

static void steady_state_allocates_nothing(void **state)
{
    const double extent[3] = { 10, 10, 10 };
    fixture *f = fixture_new();
    scene *s = scene_new();
    rng r = { 7 };
    long before;
    int step;
    (void)state;
    random_scene(s, 800, &r, extent, 0.5);
    check_pairs(f, s);
    jitter(s, &r, 0.01);
    check_pairs(f, s);
    before = f->mem.allocations;
    for (step = 0; step < 30; ++step) {
        jitter(s, &r, 0.01);
        check_pairs(f, s);
    }
    assert_int_equal(f->mem.allocations, before);
    /* and removing proxies needs no memory either */
    swap_remove(s, 17);
    swap_remove(s, 400);
    check_pairs(f, s);
    assert_int_equal(f->mem.allocations, before);
    fixture_free(f);
    free(s);
}

static void out_of_memory_is_reported_and_leaks_nothing(void **state)
{
    const double extent[3] = { 10, 10, 10 };
    scene *s = scene_new();
    long limit;
    (void)state;
    /* Fail the n-th allocation after the world's own, for every n, until a
       run of calls that grows everything completes. */
    for (limit = 0; limit < 100; ++limit) {
        fixture *f = fixture_new();
        rng r = { 8 };
        static const size_t sizes[] = { 5, 60, 900, 900, 1000 };
        static const double halves[] = { 0.5, 0.5, 0.3, 1.5, 1.5 };
        size_t k, failures = 0;
        f->mem.fail_after = f->mem.allocations + limit;
        for (k = 0; k < sizeof sizes / sizeof sizes[0]; ++k) {
            tb_status st;
            random_scene(s, sizes[k], &r, extent, halves[k]);
            st = find_pairs(f, s);
            if (st != TB_OK) {
                assert_int_equal(st, TB_ERR_MEMORY);
                assert_int_equal(f->count, 0);
                assert_true(strlen(tb_world_message(f->w)) > 0);
                ++failures;
                /* the sap and the buffer are still good: with memory again
                   the same call succeeds */
                f->mem.fail_after = -1;
            }
            check_pairs(f, s);
        }
        fixture_free(f); /* checks live bytes and the sizes handed back */
        if (!failures) {
            assert_true(limit > 2); /* the sap and the pairs did allocate */
            free(s);
            return;
        }
    }
    free(s);
    fail_msg("no run completed within 100 allocations");
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(random_boxes_match_brute_force),
    cmocka_unit_test(small_moves_keep_matching),
    cmocka_unit_test(large_moves_and_axis_changes),
    cmocka_unit_test(proxies_removed_and_added),
    cmocka_unit_test(touching_boxes_count),
    cmocka_unit_test(filters_exclude_exactly),
    cmocka_unit_test(missing_filters_accept_everything),
    cmocka_unit_test(output_is_sorted),
    cmocka_unit_test(no_proxies_and_one),
    cmocka_unit_test(identical_boxes_pair_with_all),
    cmocka_unit_test(infinite_and_huge_boxes_are_fine),
    cmocka_unit_test(steady_state_allocates_nothing),
    cmocka_unit_test(out_of_memory_is_reported_and_leaks_nothing),
};

TB_TEST_MAIN(tests)
