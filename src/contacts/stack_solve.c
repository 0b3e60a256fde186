/* stack_solve.c: the touching normal rows of an island, and its sticking
   friction, solved together, rigid and exactly, in the soft step's solves
   (docs/contacts.md, "Islands solved together").
   A soft row holds a load F at an overlap of F over its own effective
   mass times omega^2: a light body under a heavy one sinks by the mass
   ratio, and a tall stack's interfaces lean under its offsets' moments
   until the lean tips it (a soft interface resists a tilt only by its
   springs). Rows solved one at a time cannot be stiffer than the substep
   follows. Solved together they carry any load without a sink, and a
   tilt must open a gap: a factorisation of J M^-1 J^T plus a small
   compliance (which shares a load between redundant points), then
   conjugate gradients on the rigid rows with that factor as the
   preconditioner (solve_rigid), since the compliance gives by its share
   of each solve's change and a landing's blow is a large change. Which
   points push is found by active sets: a point solved to pull lets go, a
   point let go that approaches is taken in, and the rows are solved
   again.
   - Which islands: every island of bodies joined by the step's patches
     whose band is narrow enough (TB__STACK_WIDTH): a body on the ground,
     a tower, a light plank under a heavy beam. Heaps and walls, whose
     band grows with their size, stay soft, and so does an island with a
     jointed body (its joints are met one at a time in the substeps,
     soft_joints.c): solved together apart from its joints, a sticking
     patch held a box still against the hinge that had to move it, and
     the joint closed its gap by a thousandth a step; with the joints'
     rows in the band, their impulses along directions the rows share
     with the contacts grew from substep to substep, and three ragdolls
     dropped in a pile gained energy (1546 J from 1481 J; docs/notes.md).
   - Which rows: the points within TB__TOUCHING of the slop of touching,
     aiming at no approach, and the friction of each patch that may stick
     (solve_island_once), aiming at no slip: a motion the bodies can
     always make, so the compliance never meets a contradiction. In the
     solves before the drift, a point still apart whose gap closes
     within the substep joins too, aiming at an approach of its gap over
     the substep (levelled per patch): met by its patch's row and then by
     the island one after the other, a box 3 times heavier landing on a
     light one drives it 2.5 mm into the ground, 100 times heavier
     through it (heavy_box_lands_on_light_ones_soft). Such aims can do
     work where they meet nearly opposed surfaces; a solve that raises
     the island's energy is taken back and done without them
     (solve_island). Overlap, and the gap of a touching point, is taken
     out apart from the velocities (tb__stacks_push), levelled per patch:
     pushing within the solve, where friction meets it, rocks a stack
     (offset_tower_stands).
   The rows are ordered island by island along a breadth-first walk of
   its bodies from one end (a stack: bottom to top), each row after the
   first of its two bodies, so the matrix is a band as wide as the rows
   around a body: 8 for a tower of boxes. */
#include "contacts/soft_step.h"

#include <math.h>
#include <string.h>

#define TB__STACK_WIDTH 32
/* active-set rounds of one solve: each refactors the band */
#define TB__STACK_ROUNDS 6
/* conjugate-gradient iterations on the rigid rows after a solve */
#define TB__STACK_KRYLOV 8
/* the rows' compliance, relative to their own inverse mass: it shares a
   load between points that are redundant (a box's four corners on a
   face) and keeps the factor positive */
#define TB__STACK_COMPLIANCE 1e-3
#define TB__NONE ((size_t)-1)

/* A row of the band, by its code: a point's normal row (code < the soft
   rows' count), or one of a patch's two friction rows at its centre
   (2 codes a patch after them) */
typedef struct band_row {
    int32_t a, b;
    const double *dir, *arm_a, *arm_b, *spin_a, *spin_b;
    double *impulse;
    tb__soft_patch *patch;      /* a friction row's patch; NULL: a normal row */
} band_row;

struct tb__stacks {
    size_t island_count;
    size_t *island_start;      /* [island_count + 1]: island k's rows are at
                                  positions island_start[k] .. island_start[k + 1] */
    size_t *order;             /* the soft row at each position */
    size_t *first;             /* the first column of each position's band */
    size_t *offset;            /* where each position's band starts in a and l */
    size_t *position;          /* [rows]: a soft row's position, TB__NONE: soft */
    double *x, *vn0, *push;    /* right side and solution; the rate a solve starts at; the push */
    double *res, *dir, *pre, *image; /* conjugate gradients (solve_rigid): residual, direction,
                                        preconditioned residual, the matrix times the direction */
    double *before;            /* the impulses a solve started from */
    band_row *views;           /* each position's row (view), found once a step */
    size_t *member_start;      /* [island_count + 1]: island k's bodies are members[member_start[k]
                                  .. member_start[k + 1]) */
    int32_t *members;
    unsigned char *solved;     /* the position's row is solved (else held) */
    unsigned char *held;       /* a friction row this solve held at its cone's edge */
    unsigned char *given_up;   /* [island_count]: its factor failed this step; its rows are the
                                  soft ones' */
    unsigned char *factored;   /* the solved rows the factor in l is of */
    unsigned char *current;    /* [island_count]: l is the factor of a as it is, for the
                                  rows in factored */
    size_t row_cap, scratch_cap;
    size_t *body_rows;         /* [2 codes]: the rows of each body, from body_start */
    size_t link_cap;
    size_t *body_start;        /* [bodies + 1] */
    int32_t *body_order, *queue;
    size_t body_cap;
    double *a, *l;             /* the band of J M^-1 J^T, and its factor */
    size_t env_cap;
};

/* The solver's parallel arrays in four groups, each grown together:
   per row of the band (and island), the solve's scratch per row (and
   island), per body, per entry of the band */
#define TB__GROUPS 4
typedef struct group {
    void **arrays[12];
    size_t sizes[12];
    int n;
    size_t *cap;
} group;

static void groups(struct tb__stacks *s, group g[TB__GROUPS])
{
    const group rows = { { (void **)&s->island_start, (void **)&s->order, (void **)&s->first, (void **)&s->offset,
                           (void **)&s->position, (void **)&s->x, (void **)&s->vn0, (void **)&s->push,
                           (void **)&s->solved, (void **)&s->given_up, (void **)&s->factored,
                           (void **)&s->current },
                         { sizeof(size_t), sizeof(size_t), sizeof(size_t), sizeof(size_t), sizeof(size_t),
                           sizeof(double), sizeof(double), sizeof(double), 1, 1, 1, 1 },
                         12, &s->row_cap };
    const group scratch = { { (void **)&s->res, (void **)&s->dir, (void **)&s->pre, (void **)&s->image,
                              (void **)&s->before, (void **)&s->member_start, (void **)&s->views,
                              (void **)&s->held },
                            { sizeof(double), sizeof(double), sizeof(double), sizeof(double), sizeof(double),
                              sizeof(size_t), sizeof(band_row), 1 },
                            8, &s->scratch_cap };
    const group bodies = { { (void **)&s->body_start, (void **)&s->body_order, (void **)&s->queue,
                             (void **)&s->members },
                           { sizeof(size_t), sizeof(int32_t), sizeof(int32_t), sizeof(int32_t) }, 4, &s->body_cap };
    const group band = { { (void **)&s->a, (void **)&s->l }, { sizeof(double), sizeof(double) }, 2, &s->env_cap };
    g[0] = rows, g[1] = scratch, g[2] = bodies, g[3] = band;
}

/* Every array at least the step's size: all or nothing */
static tb_status reserve(tb_world *w, struct tb__stacks *s, size_t rows, size_t bodies, size_t env)
{
    const size_t need[TB__GROUPS] = { rows + 1, rows + 1, bodies + 1, env };
    group g[TB__GROUPS];
    tb_status st;
    int k;
    groups(s, g);
    for (k = 0; k < TB__GROUPS; ++k)
        if (need[k] > *g[k].cap) {
            if ((st = tb__grow(w, g[k].arrays, g[k].sizes, g[k].n, 0, *g[k].cap, 2 * need[k])) != TB_OK)
                return st;
            *g[k].cap = 2 * need[k];
        }
    return tb__reserve(w, (void **)&s->body_rows, &s->link_cap, 2 * rows, sizeof *s->body_rows);
}

static band_row view(const tb__contacts *c, size_t code)
{
    band_row v;
    if (code < c->soft_row_count) {
        tb__soft_row *o = &c->soft_rows[code];
        v.a = o->a, v.b = o->b, v.dir = o->normal, v.arm_a = o->arm_a, v.arm_b = o->arm_b;
        v.spin_a = o->spin_a, v.spin_b = o->spin_b, v.impulse = &o->impulse, v.patch = NULL;
    } else {
        const size_t f = code - c->soft_row_count;
        tb__soft_patch *p = &c->soft_patches[f / 2];
        const int d = (int)(f % 2);
        v.a = p->a, v.b = p->b, v.dir = p->tangent[d], v.arm_a = p->arm_a[d], v.arm_b = p->arm_b[d];
        v.spin_a = p->spin_a[d], v.spin_b = p->spin_b[d], v.impulse = &p->friction_impulse[d], v.patch = p;
    }
    return v;
}

static double band_rate(const tb__contacts *c, const band_row *v)
{
    return tb__soft_relative(c, v->a, v->b, v->dir, v->arm_a, v->arm_b);
}

static void band_push(tb__contacts *c, const band_row *v, double lambda)
{
    tb__soft_pair(c, v->a, v->b, lambda, v->dir, v->arm_a, v->arm_b, v->spin_a, v->spin_b);
}

/* The other side of the row of code from body i (-1: static) */
static int32_t other(const tb__contacts *c, size_t code, int32_t i)
{
    const band_row v = view(c, code);
    return v.a == i ? v.b : v.a;
}

/* Breadth-first from body start over the rows, writing the walk into
   queue[*count ...]; body_order marks the visited with tag. The last
   body reached. */
static int32_t walk(tb__contacts *c, struct tb__stacks *s, int32_t start, int32_t tag, size_t *count)
{
    size_t head = *count, k;
    s->queue[(*count)++] = start;
    s->body_order[start] = tag;
    while (head < *count) {
        const int32_t i = s->queue[head++];
        for (k = s->body_start[i]; k < s->body_start[i + 1]; ++k) {
            const int32_t j = other(c, s->body_rows[k], i);
            if (j >= 0 && s->body_order[j] != tag) {
                s->body_order[j] = tag;
                s->queue[(*count)++] = j;
            }
        }
    }
    return s->queue[*count - 1];
}

/* J M^-1 J^T between rows o and p through body i, with the signs of
   their sides (b +, a -) */
static double coupling(const tb__contacts *c, const band_row *o, const band_row *p, int32_t i)
{
    const double so = o->b == i ? 1 : -1, sp = p->b == i ? 1 : -1;
    const double *arm = o->b == i ? o->arm_b : o->arm_a, *spin = p->b == i ? p->spin_b : p->spin_a;
    return so * sp * tb__soft_through(c, i, o->dir, arm, p->dir, spin);
}

/* Island k's band assembled into a: the rows of every body coupled in
   pairs */
static void assemble(tb__contacts *c, struct tb__stacks *s, size_t k)
{
    const size_t from = s->island_start[k], to = s->island_start[k + 1];
    size_t i, m, n;
    for (i = from; i < to; ++i)
        memset(s->a + s->offset[i], 0, (i - s->first[i] + 1) * sizeof *s->a);
    for (i = from; i < to; ++i) {
        const band_row *o = &s->views[i];
        int side;
        for (side = 0; side < 2; ++side) {
            const int32_t b = side ? o->b : o->a;
            if (b < 0)
                continue;
            for (m = s->body_start[b]; m < s->body_start[b + 1]; ++m) {
                n = s->position[s->body_rows[m]];
                if (n <= i) {
                    const band_row *q = &s->views[n];
                    s->a[s->offset[i] + n - s->first[i]] += coupling(c, o, q, b);
                }
            }
        }
        s->a[s->offset[i] + i - s->first[i]] *= 1 + TB__STACK_COMPLIANCE;
    }
    s->current[k] = 0;
}

void tb__stacks_assemble(tb__contacts *c)
{
    size_t k;
    if (c->stacks)
        for (k = 0; k < c->stacks->island_count; ++k)
            assemble(c, c->stacks, k);
}

/* The band of the solved rows factored (L L^T), held rows made the
   identity. 0 if a pivot is not positive. */
static tb__envelope envelope(struct tb__stacks *s)
{
    tb__envelope e;
    e.first = s->first, e.offset = s->offset, e.a = s->a, e.l = s->l, e.use = s->solved, e.drop = 0;
    return e;
}

static int factor(struct tb__stacks *s, size_t k)
{
    const size_t from = s->island_start[k], to = s->island_start[k + 1];
    const tb__envelope e = envelope(s);
    if (s->current[k] && memcmp(s->factored + from, s->solved + from, to - from) == 0)
        return 1; /* the same matrix and rows as the factor in l */
    s->current[k] = 0;
    if (!tb__envelope_factor(&e, from, to))
        return 0;
    memcpy(s->factored + from, s->solved + from, to - from);
    s->current[k] = 1;
    return 1;
}

/* x = (L L^T)^-1 x over island k */
static void substitute_into(struct tb__stacks *s, size_t k, double *x)
{
    const tb__envelope e = envelope(s);
    tb__envelope_solve(&e, s->island_start[k], s->island_start[k + 1], x);
}

static void substitute(struct tb__stacks *s, size_t k)
{
    substitute_into(s, k, s->x);
}

/* out = J M^-1 J^T in, over island k's solved rows, without the
   compliance */
static void band_times(const struct tb__stacks *s, size_t k, const double *in, double *out)
{
    const size_t from = s->island_start[k], to = s->island_start[k + 1];
    size_t i, q;
    for (i = from; i < to; ++i)
        out[i] = 0;
    for (i = from; i < to; ++i) {
        const double *ai = s->a + s->offset[i] - s->first[i];
        if (!s->solved[i])
            continue;
        for (q = s->first[i]; q < i; ++q)
            if (s->solved[q]) {
                out[i] += ai[q] * in[q];
                out[q] += ai[q] * in[i];
            }
        out[i] += ai[i] / (1 + TB__STACK_COMPLIANCE) * in[i];
    }
}

/* Island k's rows placed from position *placed: body by body along the
   walk queue[from .. to), each row after the first of its bodies; its band
   starts at the first row of either body. 0 (and nothing placed) if the
   band is too wide to pay for. */
static int place(tb__contacts *c, struct tb__stacks *s, size_t from, size_t to, size_t *placed, size_t *env)
{
    const size_t start = *placed;
    size_t i, k, n = start, cost = 0, width = *env;
    for (i = from; i < to; ++i)
        s->body_order[s->queue[i]] = (int32_t)(i - from);
    for (i = from; i < to; ++i) {
        const int32_t b = s->queue[i];
        for (k = s->body_start[b]; k < s->body_start[b + 1]; ++k) {
            const size_t r = s->body_rows[k];
            const int32_t o = other(c, r, b);
            if (o < 0 || s->body_order[o] < s->body_order[b])
                s->order[n++] = r;
        }
    }
    /* the first position of each body, then each row's band */
    for (i = from; i < to; ++i)
        s->body_order[s->queue[i]] = -1;
    for (k = start; k < n; ++k) {
        const band_row o = view(c, s->order[k]);
        size_t f = k;
        if (o.a >= 0) {
            if (s->body_order[o.a] < 0)
                s->body_order[o.a] = (int32_t)(k - start);
            f = start + (size_t)s->body_order[o.a];
        }
        if (o.b >= 0) {
            if (s->body_order[o.b] < 0)
                s->body_order[o.b] = (int32_t)(k - start);
            if (start + (size_t)s->body_order[o.b] < f)
                f = start + (size_t)s->body_order[o.b];
        }
        s->first[k] = f;
        s->offset[k] = width;
        width += k - f + 1;
        cost += (k - f) * (k - f);
    }
    if (cost > (size_t)TB__STACK_WIDTH * TB__STACK_WIDTH * (n - start)) {
        for (k = start; k < n; ++k)
            s->position[s->order[k]] = TB__NONE;
        return 0;
    }
    for (k = start; k < n; ++k)
        s->position[s->order[k]] = k;
    *placed = n;
    *env = width;
    return 1;
}

tb_status tb__stacks_set_up(tb_world *w, tb__contacts *c)
{
    struct tb__stacks *s = c->stacks;
    const size_t rows = c->soft_row_count, bodies = c->body_count, codes = rows + 2 * c->soft_patch_count;
    size_t i, k, count = 0, placed = 0, env = 0, members = 0;
    tb_status st;
    if (!s) {
        if (!(s = tb__alloc(w, NULL, 0, sizeof *s)))
            return tb__fail(w, TB_ERR_MEMORY, "out of memory for the stack solver");
        memset(s, 0, sizeof *s);
        c->stacks = s;
    }
    s->island_count = 0;
    if (rows == 0 || bodies == 0)
        return TB_OK;
    if ((st = reserve(w, s, codes, bodies, 0)) != TB_OK)
        return st;
    /* the rows of each body: its points' normal rows, then the friction
       rows of its patches with friction */
    memset(s->body_start, 0, (bodies + 1) * sizeof *s->body_start);
    for (i = 0; i < codes; ++i) {
        const band_row o = view(c, i);
        s->position[i] = TB__NONE;
        if (o.patch && !(o.patch->friction > 0))
            continue;
        if (o.a >= 0)
            ++s->body_start[o.a + 1];
        if (o.b >= 0)
            ++s->body_start[o.b + 1];
    }
    for (i = 0; i < bodies; ++i)
        s->body_start[i + 1] += s->body_start[i];
    for (i = 0; i < bodies; ++i)
        s->body_order[i] = (int32_t)s->body_start[i];
    for (i = 0; i < codes; ++i) {
        const band_row o = view(c, i);
        if (o.patch && !(o.patch->friction > 0))
            continue;
        if (o.a >= 0)
            s->body_rows[s->body_order[o.a]++] = i;
        if (o.b >= 0)
            s->body_rows[s->body_order[o.b]++] = i;
    }
    /* islands: a walk from any body, then from the last it reached (an
       end of the island) for the order */
    for (i = 0; i < bodies; ++i)
        s->body_order[i] = -2;
    for (i = 0; i < bodies; ++i) {
        size_t from = count, end;
        int32_t far;
        if (s->body_order[i] != -2 || s->body_start[i] == s->body_start[i + 1])
            continue;
        far = walk(c, s, (int32_t)i, -3, &count);
        count = from;
        walk(c, s, far, -4, &count);
        end = count;
        s->island_start[s->island_count] = placed;
        s->given_up[s->island_count] = 0;
        s->member_start[s->island_count] = members;
        for (k = from; k < end && !c->soft_bodies[s->queue[k]].jointed; ++k)
            ;
        if (k == end && place(c, s, from, end, &placed, &env)) {
            for (k = from; k < end; ++k)
                s->members[members++] = s->queue[k];
            ++s->island_count;
        }
        for (k = from; k < end; ++k)
            s->body_order[s->queue[k]] = -5; /* done */
        count = from;
    }
    s->island_start[s->island_count] = placed;
    s->member_start[s->island_count] = members;
    if ((st = reserve(w, s, codes, bodies, env)) != TB_OK) {
        s->island_count = 0;
        return st;
    }
    for (i = 0; i < placed; ++i)
        s->views[i] = view(c, s->order[i]);
    for (k = 0; k < s->island_count; ++k)
        assemble(c, s, k);
    for (i = 0; i < c->soft_patch_count; ++i) {
        tb__soft_patch *p = &c->soft_patches[i];
        p->stacked = s->position[p->first] != TB__NONE;
    }
    return TB_OK;
}

/* Two unit tangents of n */
static void tangents(const double n[3], double t1[3], double t2[3])
{
    const double a[3] = { fabs(n[0]) < 0.6 ? 1 : 0, fabs(n[0]) < 0.6 ? 0 : 1, 0 };
    double len;
    int k;
    tb__cross(n, a, t1);
    len = sqrt(tb__dot3(t1, t1));
    for (k = 0; k < 3; ++k)
        t1[k] /= len;
    tb__cross(n, t1, t2);
}

/* The velocities the solved rows of positions [from, to), one patch,
   aim at (in x), levelled: the plane over the points' places that best
   fits them (least squares), so that what the rows ask is a motion the
   two bodies can make. Asked point by point, a box's four corners on a
   face ask three motions four things, and solved together the rows would
   push against each other with the difference over their compliance. */
static void level(const tb__contacts *c, struct tb__stacks *s, size_t from, size_t to)
{
    double t1[3], t2[3], u[2] = { 0, 0 }, mean = 0, cov[3] = { 0, 0, 0 }, cross[2] = { 0, 0 }, g[2] = { 0, 0 };
    double count = 0, det;
    size_t i;
    tangents(c->soft_rows[s->order[from]].normal, t1, t2);
    for (i = from; i < to; ++i) {
        const tb__soft_row *o = &c->soft_rows[s->order[i]];
        const double *r = o->a >= 0 ? o->ra : o->rb;
        if (!s->solved[i])
            continue;
        u[0] += tb__dot3(r, t1), u[1] += tb__dot3(r, t2), mean += s->x[i], count += 1;
    }
    if (count < 2)
        return;
    u[0] /= count, u[1] /= count, mean /= count;
    for (i = from; i < to; ++i) {
        const tb__soft_row *o = &c->soft_rows[s->order[i]];
        const double *r = o->a >= 0 ? o->ra : o->rb;
        const double d0 = tb__dot3(r, t1) - u[0], d1 = tb__dot3(r, t2) - u[1], e = s->x[i] - mean;
        if (!s->solved[i])
            continue;
        cov[0] += d0 * d0, cov[1] += d0 * d1, cov[2] += d1 * d1;
        cross[0] += d0 * e, cross[1] += d1 * e;
    }
    det = cov[0] * cov[2] - cov[1] * cov[1];
    if (det > 1e-9 * (cov[0] + cov[2]) * (cov[0] + cov[2])) {
        g[0] = (cov[2] * cross[0] - cov[1] * cross[1]) / det;
        g[1] = (cov[0] * cross[1] - cov[1] * cross[0]) / det;
    } else if (cov[0] + cov[2] > 0) {
        /* the points on a line: a slope along it */
        const double along = (cross[0] * cov[0] + cross[1] * cov[1]) != 0 || cov[0] >= cov[2] ? 0 : 1;
        const double dir[2] = { along ? cov[1] : cov[0], along ? cov[2] : cov[1] };
        const double dd = dir[0] * dir[0] + dir[1] * dir[1];
        if (dd > 0) {
            const double slope = (dir[0] * cross[0] + dir[1] * cross[1]) /
                                 (dir[0] * (cov[0] * dir[0] + cov[1] * dir[1]) + dir[1] * (cov[1] * dir[0] + cov[2] * dir[1]));
            g[0] = slope * dir[0], g[1] = slope * dir[1];
        }
    }
    for (i = from; i < to; ++i) {
        const tb__soft_row *o = &c->soft_rows[s->order[i]];
        const double *r = o->a >= 0 ? o->ra : o->rb;
        if (s->solved[i])
            s->x[i] = mean + g[0] * (tb__dot3(r, t1) - u[0]) + g[1] * (tb__dot3(r, t2) - u[1]);
    }
}

/* Every patch's aims in x over island k levelled (level) */
static void level_patches(const tb__contacts *c, struct tb__stacks *s, size_t k)
{
    const size_t from = s->island_start[k], to = s->island_start[k + 1];
    size_t i, patch;
    for (patch = from, i = from + 1; i <= to; ++i) {
        /* a patch's normal rows are next to each other, with the same
           bodies and normal; friction rows are not levelled */
        const tb__soft_row *o = s->order[patch] < c->soft_row_count ? &c->soft_rows[s->order[patch]] : NULL;
        const tb__soft_row *p = i < to && s->order[i] < c->soft_row_count ? &c->soft_rows[s->order[i]] : NULL;
        if (o && p && p->a == o->a && p->b == o->b && memcmp(p->normal, o->normal, sizeof p->normal) == 0)
            continue;
        if (o)
            level(c, s, patch, i);
        patch = i;
    }
}

/* Island k's factor failed (a pivot not positive: rounding beyond the
   compliance): its patches' rows are the soft ones' for the rest of the
   step, as if the island were too wide */
static void give_up(tb__contacts *c, struct tb__stacks *s, size_t k)
{
    const size_t from = s->island_start[k], to = s->island_start[k + 1];
    size_t i;
    s->given_up[k] = 1;
    for (i = 0; i < c->soft_patch_count; ++i) {
        tb__soft_patch *p = &c->soft_patches[i];
        const size_t at = s->position[p->first];
        if (at != TB__NONE && at >= from && at < to)
            p->stacked = 0;
    }
}

/* The normal impulse of patch p's points: the solve's where the row is
   solved (x), else what it holds; and its bounce */
static double patch_press(const tb__contacts *c, const struct tb__stacks *s, const tb__soft_patch *p)
{
    double n = 0;
    size_t k;
    for (k = 0; k < p->count; ++k) {
        const tb__soft_row *o = &c->soft_rows[p->first + k];
        const size_t at = s->position[p->first + k];
        n += (at != TB__NONE && s->solved[at] ? tb__most(s->x[at], 0) : o->impulse) + o->bounce;
    }
    return n;
}

/* What patch p's points push now: their normal impulses and bounces */
static double pressing(const tb__contacts *c, const tb__soft_patch *p)
{
    double press = 0;
    size_t k;
    for (k = 0; k < p->count; ++k)
        press += c->soft_rows[p->first + k].impulse + c->soft_rows[p->first + k].bounce;
    return press;
}

/* Whether position i holds the first of a patch's two friction rows, the
   second right after it */
static int friction_pair(const tb__contacts *c, const struct tb__stacks *s, size_t i)
{
    return s->views[i].patch && (s->order[i] - c->soft_row_count) % 2 == 0 && s->order[i + 1] == s->order[i] + 1;
}

/* The friction pair at position i given the impulses f0 and f1 */
static void set_pair(tb__contacts *c, struct tb__stacks *s, size_t i, double f0, double f1)
{
    int d;
    for (d = 0; d < 2; ++d) {
        const band_row *w = &s->views[i + d];
        const double f = d ? f1 : f0;
        band_push(c, w, f - *w->impulse);
        *w->impulse = f;
    }
}

/* Whether patch p's friction may stick: its centre's slip stopped by the
   patch alone (its tangent mass) within the cone of what its points
   push now. A patch that slides is left to its own pass, which meets
   the slip's direction exactly (soft_step_slides_to_v2_over_2_mu_g). */
static int sticks(const tb__contacts *c, const tb__soft_patch *p)
{
    double slip[2], stop[2];
    int d;
    for (d = 0; d < 2; ++d) {
        const band_row v = view(c, c->soft_row_count + 2 * (size_t)(p - c->soft_patches) + (size_t)d);
        slip[d] = band_rate(c, &v);
    }
    stop[0] = p->tangent_mass[0] * slip[0] + p->tangent_mass[1] * slip[1];
    stop[1] = p->tangent_mass[1] * slip[0] + p->tangent_mass[2] * slip[1];
    return hypot(p->friction_impulse[0] - stop[0], p->friction_impulse[1] - stop[1]) <= p->friction * pressing(c, p);
}

/* The approach speed position i's normal row allows: none where it
   touches, its gap over the substep where it is still apart */
static double allowed(const tb__contacts *c, const struct tb__stacks *s, size_t i, double hs, int bias)
{
    const double sep = s->order[i] < c->soft_row_count ? tb__soft_separation(c, &c->soft_rows[s->order[i]]) : 0;
    return bias && sep > TB__TOUCHING * c->settings.slop ? sep / hs : 0;
}

/* Whether position i's normal row is solved with its island: it touches
   (at first; later, if it approaches), or its gap closes within the
   substep at the rate now */
static int closes(const tb__contacts *c, const struct tb__stacks *s, size_t i, double hs, double touch, int first,
                  int bias)
{
    const tb__soft_row *o = &c->soft_rows[s->order[i]];
    const double sep = tb__soft_separation(c, o), rate = tb__soft_rate(c, o);
    if (sep <= touch)
        return first || rate < -1e-12;
    return bias && rate * hs < -sep;
}

/* The change of island k's solved impulses that meets the change of
   their rates in x (J M^-1 J^T dx = x), into x: the factor's solve,
   whose compliance gives by its share of the change, then conjugate
   gradients on the rigid rows with the factor as the preconditioner,
   whose only slow modes are those the compliance holds (a body far
   heavier than those its rows' compliance is scaled by) */
static void solve_rigid(struct tb__stacks *s, size_t k)
{
    const size_t from = s->island_start[k], to = s->island_start[k + 1];
    double rz = 0, scale = 0, least = 0, enough;
    size_t i;
    int it;
    for (i = from; i < to; ++i) {
        s->res[i] = s->x[i];
        scale = tb__most(scale, fabs(s->x[i]));
    }
    substitute(s, k);
    band_times(s, k, s->x, s->image);
    for (i = from; i < to; ++i) {
        s->res[i] = s->solved[i] ? s->res[i] - s->image[i] : 0;
        s->pre[i] = s->res[i];
        least = tb__most(least, fabs(s->res[i]));
    }
    /* met to a nanometre a second, or to rounding */
    enough = tb__most(1e-9, 1e-13 * scale);
    if (least <= enough)
        return;
    substitute_into(s, k, s->pre);
    for (i = from; i < to; ++i) {
        s->dir[i] = s->pre[i];
        rz += s->res[i] * s->pre[i];
    }
    for (it = 0; it < TB__STACK_KRYLOV && rz > 0; ++it) {
        double pq = 0, dd = 0, alpha, next = 0, most = 0;
        band_times(s, k, s->dir, s->image);
        for (i = from; i < to; ++i) {
            pq += s->dir[i] * s->image[i];
            dd += s->a[s->offset[i] + i - s->first[i]] * s->dir[i] * s->dir[i];
        }
        /* a direction the rows barely move (its curvature under 1e-7 of
           its diagonal's) lies along redundant points: no step on it */
        if (!(pq > 1e-7 * dd))
            break;
        alpha = rz / pq;
        for (i = from; i < to; ++i)
            most = tb__most(most, fabs(s->res[i] - alpha * s->image[i]));
        /* a step that does not halve the residual has met what the rows
           cannot be given (rounding beyond what a motion can meet):
           the iterate stands, as along the rows' redundant directions
           the step would be any size */
        if (!(most < 0.5 * least))
            break;
        least = most;
        for (i = from; i < to; ++i) {
            s->x[i] += alpha * s->dir[i];
            s->res[i] -= alpha * s->image[i];
        }
        if (least <= enough)
            break; /* met: no next direction is needed */
        memcpy(s->pre + from, s->res + from, (to - from) * sizeof *s->pre);
        substitute_into(s, k, s->pre);
        for (i = from; i < to; ++i)
            next += s->res[i] * s->pre[i];
        for (i = from; i < to; ++i)
            s->dir[i] = s->pre[i] + next / rz * s->dir[i];
        rz = next;
    }
}

/* Island k's rows solved together and rigid: its touching points aiming
   at no approach, and the friction of its patches at no slip where it
   sticks (within the cone, mu times the patch's normal impulse): a motion
   the bodies can always make (the push of overlaps is tb__stacks_push's);
   with `bias`, the points whose gap closes within the substep too,
   aiming at an approach of the gap over the substep. Whether any such
   point was solved. Friction solved
   one patch at a time after the normal rows lets a box rock about the
   patch's centre while the centre holds, and it creeps down an incline
   (soft_step_box_holds_on_an_incline). A patch whose friction would
   leave the cone slides: held at the cone's edge along the solve's
   direction, and the patch's own pass then meets it exactly. */
static int solve_island_once(tb__contacts *c, struct tb__stacks *s, size_t k, double hs, int bias)
{
    const size_t from = s->island_start[k], to = s->island_start[k + 1];
    const double tiny = 1e-12, touch = TB__TOUCHING * c->settings.slop;
    size_t i, round;
    int changed = 1, closing = 0;
    for (i = from; i < to; ++i) {
        const band_row *v = &s->views[i];
        s->vn0[i] = band_rate(c, v);
        s->solved[i] = v->patch ? sticks(c, v->patch) : closes(c, s, i, hs, touch, 1, bias);
        s->held[i] = 0;
    }
    for (round = 0; round < TB__STACK_ROUNDS && changed; ++round) {
        const int last = round + 1 == TB__STACK_ROUNDS;
        changed = 0;
        if (!factor(s, k)) {
            give_up(c, s, k);
            return closing;
        }
        for (i = from; i < to; ++i) {
            const band_row *v = &s->views[i];
            const double gap = s->solved[i] ? allowed(c, s, i, hs, bias) : 0;
            s->x[i] = s->solved[i] ? -band_rate(c, v) - gap : 0;
            closing |= gap > 0;
        }
        /* what a patch's points closing their gaps ask, levelled: a
           motion the bodies can make (else the compliance alone would
           hold the difference, with impulses of the difference over it) */
        if (closing)
            level_patches(c, s, k);
        /* the change, solved rigid (solve_rigid): the impulses the
           last solve left keep their share of a load between redundant
           points, so it stays from substep to substep */
        solve_rigid(s, k);
        for (i = from; i < to; ++i)
            if (s->solved[i])
                s->x[i] += *s->views[i].impulse;
        /* a point solved to pull lets go; in the last round the solve
           stands, stopped where its first pulling point lets go (below;
           the next solve of the substep starts from it) */
        for (i = from; i < to && !last; ++i) {
            const band_row *v = &s->views[i];
            if (!v->patch && s->solved[i] && s->x[i] < -tiny * (c->soft_rows[s->order[i]].mass + 1)) {
                s->solved[i] = 0;
                changed = 1;
                band_push(c, v, -*v->impulse);
                *v->impulse = 0;
            }
        }
        if (changed)
            continue;
        /* in the last round, a point solved to pull stops the step where
           its impulse reaches zero: every row moves that share of the way
           from its impulse to the solve's, so the impulses stay a point
           on the way to this active set's solution, and a projection
           still takes energy away (cut at no pull alone, the others kept
           at theirs, a pair of nearly opposed rows that met each other
           with 3000 N s threw a body at 29 m/s:
           test_contacts_stress.dropped_heaps_of_60) */
        if (last) {
            double share = 1;
            for (i = from; i < to; ++i) {
                const band_row *v = &s->views[i];
                if (!v->patch && s->solved[i] && s->x[i] < 0)
                    share = tb__least(share, *v->impulse / (*v->impulse - s->x[i]));
            }
            if (share < 1)
                for (i = from; i < to; ++i)
                    if (s->solved[i]) {
                        const band_row *v = &s->views[i];
                        s->x[i] = *v->impulse + share * (s->x[i] - *v->impulse);
                        if (!v->patch && !(s->x[i] > 0))
                            s->x[i] = 0;
                    }
        }
        /* friction beyond its cone slides, held at the cone's edge */
        for (i = from; i + 1 < to; ++i) {
            double f, most, cut;
            if (!friction_pair(c, s, i) || !s->solved[i] || !s->solved[i + 1])
                continue;
            f = hypot(s->x[i], s->x[i + 1]);
            most = s->views[i].patch->friction * patch_press(c, s, s->views[i].patch);
            if (f <= most * (1 + 1e-12))
                continue;
            cut = f > 0 ? most / f : 0;
            set_pair(c, s, i, s->x[i] * cut, s->x[i + 1] * cut);
            s->solved[i] = s->solved[i + 1] = 0;
            s->held[i] = s->held[i + 1] = 1;
            changed = !last;
        }
        if (changed)
            continue;
        for (i = from; i < to; ++i) {
            const band_row *v = &s->views[i];
            const double total = v->patch ? s->x[i] : tb__most(s->x[i], 0);
            if (!s->solved[i])
                continue;
            band_push(c, v, total - *v->impulse);
            *v->impulse = total;
        }
        /* a touching point let go that now approaches is taken in */
        for (i = from; i < to; ++i) {
            const band_row *v = &s->views[i];
            if (s->solved[i] || v->patch)
                continue;
            if (closes(c, s, i, hs, touch, 0, bias)) {
                s->solved[i] = 1;
                changed = 1;
            }
        }
    }
    /* friction held at a cone's edge stays within the cone of what its
       points push at the end: a point let go after its friction was held
       takes its share of the cone with it (held at the old cone, a light
       body squeezed in a crowd was thrown at 10 m/s:
       test_contacts_heaps.crowds_built_overlapping_stay_calm) */
    for (i = from; i + 1 < to; ++i) {
        double f0, f1, f, most;
        if (!s->held[i] || !friction_pair(c, s, i))
            continue;
        f0 = *s->views[i].impulse, f1 = *s->views[i + 1].impulse;
        f = hypot(f0, f1);
        most = s->views[i].patch->friction * tb__most(pressing(c, s->views[i].patch), 0);
        if (f > most * (1 + 1e-12))
            set_pair(c, s, i, f0 * most / f, f1 * most / f);
    }
    return closing;
}

/* The kinetic energy of island k's bodies */
static double island_energy(const tb__contacts *c, const struct tb__stacks *s, size_t k)
{
    double e = 0;
    size_t i;
    for (i = s->member_start[k]; i < s->member_start[k + 1]; ++i) {
        const int32_t b = s->members[i];
        const tb__soft_body *sb = &c->soft_bodies[b];
        if (c->bodies[b].inv_mass > 0)
            e += 0.5 * tb__dot3(sb->v, sb->v) / c->bodies[b].inv_mass;
        if (c->bodies[b].tier == TB__BODIES)
            e += 0.5 * tb__dot3(sb->w, sb->L);
    }
    return e;
}

/* Island k solved (solve_island_once), with the points closing their
   gaps where that takes no energy. Aiming at no approach, the solve is a
   projection of the bodies' velocities and takes energy away; a point
   closing its gap aims at an approach, and where such aims meet nearly
   opposed surfaces the impulses that meet them exactly can do work (they
   throw a body between the ground and a wall's foot at 80 m/s:
   test_contacts_stress.dropped_heaps_of_60): such a solve is taken back
   and the island solved without them, their patches' own rows meeting
   them one at a time. */
static void solve_island(tb__contacts *c, struct tb__stacks *s, size_t k, double hs, int bias)
{
    const size_t from = s->island_start[k], to = s->island_start[k + 1];
    size_t i;
    if (bias) {
        const double energy = island_energy(c, s, k);
        for (i = from; i < to; ++i)
            s->before[i] = *s->views[i].impulse;
        if (solve_island_once(c, s, k, hs, 1) && !s->given_up[k] &&
            island_energy(c, s, k) > energy * (1 + 1e-9) + 1e-14) {
            for (i = from; i < to; ++i) {
                const band_row *v = &s->views[i];
                band_push(c, v, s->before[i] - *v->impulse);
                *v->impulse = s->before[i];
            }
            solve_island_once(c, s, k, hs, 0);
        }
    } else {
        solve_island_once(c, s, k, hs, 0);
    }
    if (s->given_up[k])
        return;
    for (i = from; i < to; ++i)
        if (s->solved[i] && s->order[i] < c->soft_row_count) {
            tb__soft_row *o = &c->soft_rows[s->order[i]];
            tb__soft_note(c, o, s->vn0[i], tb__soft_separation(c, o), hs);
        }
}

void tb__stacks_solve(tb__contacts *c, double hs, int bias)
{
    struct tb__stacks *s = c->stacks;
    size_t k;
    if (!s)
        return;
    for (k = 0; k < s->island_count; ++k)
        if (!s->given_up[k])
            solve_island(c, s, k, hs, bias);
}

/* The push of every stacked island's overlaps, as velocities that move
   positions over the drift and are then taken back (sign +1, then -1):
   impulses that bring each overlapping or touching point to its surface
   at the soft rows' rate (bias_rate times the separation, at most
   max_push), levelled per patch; left alone, the touching band's 5 um
   stayed (dropped_boxes_lie_on_the_plane),
   solved together with the rows the last solve held. Pushed as velocities
   within the solve, the rows' friction would meet them and rock a stack
   it stands on. */
void tb__stacks_push(tb__contacts *c, double bias_rate, int sign)
{
    struct tb__stacks *s = c->stacks;
    const double max_push = c->settings.max_push, touch = TB__TOUCHING * c->settings.slop;
    size_t k, i;
    if (!s)
        return;
    for (k = 0; k < s->island_count; ++k) {
        const size_t from = s->island_start[k], to = s->island_start[k + 1];
        if (s->given_up[k])
            continue;
        if (sign < 0) {
            for (i = from; i < to; ++i)
                if (s->push[i] != 0) {
                    const band_row *v = &s->views[i];
                    band_push(c, v, -s->push[i]);
                }
            continue;
        }
        for (i = from; i < to; ++i) {
            const double sep = s->order[i] < c->soft_row_count ? tb__soft_separation(c, &c->soft_rows[s->order[i]]) : 0;
            s->x[i] = s->solved[i] && sep < touch ? -tb__most(bias_rate * sep, -max_push) : 0;
        }
        level_patches(c, s, k);
        substitute(s, k);
        for (i = from; i < to; ++i) {
            s->push[i] = s->solved[i] ? s->x[i] : 0;
            if (s->push[i] != 0) {
                const band_row *v = &s->views[i];
                band_push(c, v, s->push[i]);
            }
        }
    }
}

void tb__stacks_free(tb_world *w, tb__contacts *c)
{
    struct tb__stacks *s = c->stacks;
    group g[TB__GROUPS];
    int k;
    if (!s)
        return;
    groups(s, g);
    for (k = 0; k < TB__GROUPS; ++k)
        tb__free_arrays(w, g[k].arrays, g[k].sizes, g[k].n, *g[k].cap);
    tb__alloc(w, s->body_rows, s->link_cap * sizeof *s->body_rows, 0);
    tb__alloc(w, s, sizeof *s, 0);
    c->stacks = NULL;
}
