/* joint_solve.c: the joints' rows set up and solved (docs/joints.md), for
   bodies and for particles in their places (the solver's nodes: the
   bodies' slots, then the particles'), and the forces of the methods that
   evaluate them (euler, rk4, dopri5): the rows J at the evaluation's
   positions and velocities, the nodes' accelerations a0 under their other
   forces, and the multipliers of (J M^-1 J^T) lambda = -(J a0 + bias), so
   that every row's C'' = 0: the constrained motion as an ordinary
   differential equation, which each method follows to its own order
   (test_joints.rk4_pendulum_keeps_its_order). Every matrix is solved
   directly, by its envelope factor with the rows ordered joint by joint
   (a chain's is a band), so that a light body hung from a heavy one costs
   no iterations; a row that depends on others (a closed loop) is left out
   by the factor. Putting the bodies on their joints is joint_shake.c's. */
#include "joints/joint_work.h"
#include "bodies/bodies.h"
#include "particles/particles.h"

#include <math.h>
#include <string.h>

static tb_status reserve_rows(tb_world *w, struct tb__joint_work *k, size_t rows)
{
    void **arrays[16];
    const size_t sizes[16] = { sizeof(tb__joint_row), 12 * sizeof(double), sizeof(size_t), sizeof(size_t),
                               sizeof(double), 1, sizeof(double), sizeof(double), sizeof(double), sizeof(double), 1,
                               sizeof(size_t), sizeof(size_t), sizeof(size_t), 1, sizeof(double) };
    size_t cap = k->row_cap ? k->row_cap : 16;
    tb_status st;
    if (rows <= k->row_cap && k->rows) /* (room always: a joint of no rows, a spring, still points into it) */
        return TB_OK;
    while (cap < rows)
        cap *= 2;
    arrays[0] = (void **)&k->rows, arrays[1] = (void **)&k->weighted, arrays[2] = (void **)&k->first;
    arrays[3] = (void **)&k->offset, arrays[4] = (void **)&k->x, arrays[5] = (void **)&k->use;
    arrays[6] = (void **)&k->newton, arrays[7] = (void **)&k->total;
    arrays[8] = (void **)&k->rhs, arrays[9] = (void **)&k->clamped, arrays[10] = (void **)&k->state;
    arrays[11] = (void **)&k->packed, arrays[12] = (void **)&k->packed_first, arrays[13] = (void **)&k->packed_offset;
    arrays[14] = (void **)&k->packed_use, arrays[15] = (void **)&k->packed_x;
    if ((st = tb__grow(w, arrays, sizes, 16, 0, k->row_cap, cap)) != TB_OK)
        return st;
    k->row_cap = cap;
    return TB_OK;
}

tb_status tb__joint_reserve(tb_world *w, size_t rows)
{
    struct tb__joint_work *k = w->joint_work;
    tb_status st;
    if (!k) {
        if (!(k = tb__alloc(w, NULL, 0, sizeof *k)))
            return tb__fail(w, TB_ERR_MEMORY, "out of memory for the joints' solve");
        memset(k, 0, sizeof *k);
        w->joint_work = k;
    }
    if ((st = reserve_rows(w, k, rows)) != TB_OK)
        return st;
    if (w->joint_count + 1 > k->joint_cap) {
        void **arrays[4] = { (void **)&k->row_start, (void **)&k->lever, (void **)&k->held_lever,
                             (void **)&k->row_end };
        const size_t sizes[4] = { sizeof(size_t), 3 * sizeof(double), 3 * sizeof(double), sizeof(size_t) };
        const size_t cap = 2 * (w->joint_count + 1);
        if ((st = tb__grow(w, arrays, sizes, 4, 0, k->joint_cap, cap)) != TB_OK)
            return st;
        k->joint_cap = cap;
    }
    if (w->body_count + w->particle_count > k->body_cap) {
        void **arrays[8] = { (void **)&k->accel, (void **)&k->body_row, (void **)&k->stamp, (void **)&k->start,
                             (void **)&k->moved, (void **)&k->kept, (void **)&k->half, (void **)&k->ends };
        const size_t sizes[8] = { 6 * sizeof(double), sizeof(size_t), sizeof(unsigned), 7 * sizeof(double),
                                  sizeof(int32_t), 7 * sizeof(double), 7 * sizeof(double),
                                  sizeof(tb__joint_end) };
        const size_t cap = 2 * (w->body_count + w->particle_count);
        if ((st = tb__grow(w, arrays, sizes, 8, 0, k->body_cap, cap)) != TB_OK)
            return st;
        memset(k->stamp, 0, cap * sizeof *k->stamp);
        k->body_cap = cap;
    }
    return TB_OK;
}

/* An end's index in the per-node arrays: the bodies, then the particles */
size_t tb__joint_node(const tb_world *w, int32_t end)
{
    return end >= 0 ? (size_t)end : w->body_count + tb__joint_particle_slot(end);
}

/* v through an end's inverse mass (lin) or world inverse inertia (ang; a
   particle turns not) */
static void weigh(const tb_world *w, const tb__joint_end *e, const double lin[3], const double ang[3], double out[6])
{
    double b[3];
    int d;
    if (e->slot < 0) {
        const double inv = tb__joint_is_particle(e->slot) ? w->particle_inv_mass[tb__joint_particle_slot(e->slot)] : 0;
        for (d = 0; d < 3; ++d)
            out[d] = inv * lin[d], out[3 + d] = 0;
        return;
    }
    for (d = 0; d < 3; ++d)
        out[d] = w->body_inv_mass[e->slot] * lin[d];
    tb__mul_transposed(e->R, ang, b);
    for (d = 0; d < 3; ++d)
        b[d] *= w->body_inv_inertia[3 * e->slot + d];
    tb__mul(e->R, b, out + 3);
}

/* Row p times M^-1 times row q, through ends a and b */
static double row_product(const tb_world *w, const tb__joint_row *p, const tb__joint_row *q, const tb__joint_end *a,
                          const tb__joint_end *b)
{
    double m[12];
    weigh(w, a, q->lin_a, q->ang_a, m);
    weigh(w, b, q->lin_b, q->ang_b, m + 6);
    return tb__dot3(p->lin_a, m) + tb__dot3(p->ang_a, m + 3) + tb__dot3(p->lin_b, m + 6) + tb__dot3(p->ang_b, m + 9);
}

double tb__joint_effective_mass(const tb_world *w, size_t j, const tb__joint_row *row, const tb__joint_end *a,
                                const tb__joint_end *b)
{
    tb__joint_row rows[TB__JOINT_ROWS];
    double A[TB__JOINT_ROWS][TB__JOINT_ROWS + 1], inverse = row_product(w, row, row, a, b);
    int n = 0, all = tb__joint_rows(w, j, a, b, rows), r, c, p;
    for (r = 0; r < all; ++r) /* the rows the joint holds (not its limits or motor) */
        if (rows[r].kind == TB__ROW_EQUAL)
            rows[n++] = rows[r];
    /* inverse - (R M^-1 J^T)^T (R M^-1 R^T)^-1 (R M^-1 J^T): the coordinate's
       inverse mass with the joint's rows holding (Gaussian elimination; a row that
       depends on those before it is left out, as the solve leaves it) */
    for (r = 0; r < n; ++r) {
        for (c = 0; c < n; ++c)
            A[r][c] = row_product(w, &rows[r], &rows[c], a, b);
        A[r][n] = row_product(w, &rows[r], row, a, b);
    }
    for (p = 0; p < n; ++p) {
        const double pivot = A[p][p];
        if (!(pivot > DROP * row_product(w, &rows[p], &rows[p], a, b)))
            continue;
        for (r = p + 1; r < n; ++r) {
            const double f = A[r][p] / pivot;
            for (c = p; c <= n; ++c)
                A[r][c] -= f * A[p][c];
        }
        inverse -= A[p][n] * A[p][n] / pivot;
    }
    return inverse > 0 ? 1 / inverse : 0;
}

/* Row i's part through its end on `side`, against the weighted row j */
static double through(const tb__joint_row *ri, int side, const double *wj, const tb__joint_row *rj)
{
    const int32_t s = side ? ri->b : ri->a;
    const double *lin = side ? ri->lin_b : ri->lin_a, *ang = side ? ri->ang_b : ri->ang_a;
    double sum = 0;
    if (s == TB__JOINT_WORLD)
        return 0;
    if (rj->a == s)
        sum += tb__dot3(lin, wj) + tb__dot3(ang, wj + 3);
    if (rj->b == s)
        sum += tb__dot3(lin, wj + 6) + tb__dot3(ang, wj + 9);
    return sum;
}

/* Item m's end on `side`: joint m's, or contact m - joints' */
static int32_t item_end(const tb_world *w, const struct tb__joint_work *k, size_t m, int side)
{
    if (m < w->joint_count)
        return tb__joint_end_slot(w, m, side);
    return side ? k->contacts[m - w->joint_count].b : k->contacts[m - w->joint_count].a;
}

/* The order the joints and contacts (items) are set up in, k->order: as
   added while there are no contacts (a chain as built is a band); with
   them, by a breadth-first walk of the nodes the items join
   (Cuthill-McKee), each item after the later of its two ends, so that an
   item's envelope reaches back only as far as the walk's frontier: a
   pile of ragdolls with its contacts after all the joints had rows as
   wide as the pile (five ragdolls took 85 ms a step) */
static tb_status order_items(tb_world *w, struct tb__joint_work *k, size_t items)
{
    const size_t nodes = w->body_count + w->particle_count, none = (size_t)-1;
    size_t *head, *incident, *rank, *queue, *bucket, m, n, next = 0;
    tb_status st;
    int side;
    if ((st = tb__reserve(w, (void **)&k->order, &k->order_cap, 4 * items + 4 * nodes + 3, sizeof *k->order)) != TB_OK)
        return st;
    if (k->contact_count == 0) {
        for (m = 0; m < items; ++m)
            k->order[m] = m;
        return TB_OK;
    }
    incident = k->order + items, head = incident + 2 * items, rank = head + nodes + 1, queue = rank + nodes;
    bucket = queue + nodes;
    memset(head, 0, (nodes + 1) * sizeof *head);
    for (m = 0; m < items; ++m)
        for (side = 0; side < 2; ++side)
            if (item_end(w, k, m, side) != TB__JOINT_WORLD)
                ++head[tb__joint_node(w, item_end(w, k, m, side)) + 1];
    for (n = 0; n < nodes; ++n)
        head[n + 1] += head[n];
    for (n = 0; n < nodes; ++n)
        rank[n] = head[n]; /* (the fill's cursor, for now) */
    for (m = 0; m < items; ++m)
        for (side = 0; side < 2; ++side)
            if (item_end(w, k, m, side) != TB__JOINT_WORLD)
                incident[rank[tb__joint_node(w, item_end(w, k, m, side))]++] = m;
    for (n = 0; n < nodes; ++n)
        rank[n] = none;
    for (m = 0; m < items; ++m) /* a walk from each item's ends not yet reached, in the items' order */
        for (side = 0; side < 2; ++side) {
            const int32_t s = item_end(w, k, m, side);
            size_t front = 0, back = 0, i;
            if (s == TB__JOINT_WORLD || rank[tb__joint_node(w, s)] != none)
                continue;
            rank[tb__joint_node(w, s)] = next++;
            queue[back++] = tb__joint_node(w, s);
            while (front < back) {
                const size_t at = queue[front++];
                for (i = head[at]; i < head[at + 1]; ++i) {
                    int other;
                    for (other = 0; other < 2; ++other) {
                        const int32_t e = item_end(w, k, incident[i], other);
                        if (e != TB__JOINT_WORLD && rank[tb__joint_node(w, e)] == none) {
                            rank[tb__joint_node(w, e)] = next++;
                            queue[back++] = tb__joint_node(w, e);
                        }
                    }
                }
            }
        }
    /* a counting sort of the items by the later rank of their ends, stable */
    memset(bucket, 0, (nodes + 2) * sizeof *bucket);
    for (m = 0; m < items; ++m) {
        size_t key = 0;
        for (side = 0; side < 2; ++side)
            if (item_end(w, k, m, side) != TB__JOINT_WORLD && rank[tb__joint_node(w, item_end(w, k, m, side))] + 1 > key)
                key = rank[tb__joint_node(w, item_end(w, k, m, side))] + 1;
        incident[m] = key;
        ++bucket[key + 1];
    }
    for (n = 0; n <= nodes; ++n)
        bucket[n + 1] += bucket[n];
    for (m = 0; m < items; ++m)
        k->order[bucket[incident[m]]++] = m;
    return TB_OK;
}

tb_status tb__joint_set_up(tb_world *w, const double *y, const double *seen, int forces, int make, size_t *count)
{
    const int shake = make == TB__SET_UP_SHAKE;
    struct tb__joint_work *k;
    size_t rows = 0, j, t, i, q, env = 0;
    tb_status st;
    for (j = 0; j < w->joint_count; ++j)
        rows += (size_t)tb__joint_rows_of(w, j);
    if (w->joint_work)
        rows += w->joint_work->contact_count;
    if ((st = tb__joint_reserve(w, rows)) != TB_OK)
        return st;
    k = w->joint_work;
    ++k->now;
    if (k->now == 0) { /* the stamps wrapped: none is this set-up's */
        memset(k->stamp, 0, k->body_cap * sizeof *k->stamp);
        k->now = 1;
    }
    rows = 0;
    k->moved_count = 0;
    if ((st = order_items(w, k, w->joint_count + k->contact_count)) != TB_OK)
        return st;
    for (t = 0; t < w->joint_count + k->contact_count; ++t) { /* the joints and the contacts */
        const size_t j = k->order[t];
        const tb__joint_contact *contact = j < w->joint_count ? NULL : &k->contacts[j - w->joint_count];
        tb__joint_end e[2];
        size_t first = rows;
        int n, r, side;
        if (!contact && (w->joint_flags[j] & TB__JOINT_SOFT) && !k->projecting) { /* the soft step's */
            k->row_start[j] = k->row_end[j] = rows;
            continue;
        }
        for (side = 0; side < 2; ++side) { /* each end once a set-up */
            const int32_t s = contact ? (side ? contact->b : contact->a) : tb__joint_end_slot(w, j, side);
            if (s == TB__JOINT_WORLD) {
                tb__joint_end_of(w, s, y, seen, &e[side]);
                continue;
            }
            if (k->stamp[tb__joint_node(w, s)] != k->now)
                tb__joint_end_of(w, s, y, seen, &k->ends[tb__joint_node(w, s)]);
            e[side] = k->ends[tb__joint_node(w, s)];
        }
        if (contact) {
            tb__joint_contact_row(contact, &e[0], &e[1], k->rows + rows);
            n = 1;
        } else {
            k->row_start[j] = rows;
            tb__mul(e[0].R, w->joint_anchor + 6 * j, k->lever + 3 * j);
            n = tb__joint_rows(w, j, &e[0], &e[1], k->rows + rows);
        }
        for (r = 0; r < n && make != TB__SET_UP_ROWS; ++r) {
            const tb__joint_row *row = shake ? &k->held[rows + r] : &k->rows[rows + r];
            double (*out)[12] = shake ? k->held_weighted : k->weighted;
            weigh(w, &e[0], row->lin_a, row->ang_a, out[rows + r]);
            weigh(w, &e[1], row->lin_b, row->ang_b, out[rows + r] + 6);
        }
        /* the envelope: from the first row of any joint before this one
           that moves one of its bodies */
        for (side = 0; side < 2; ++side) {
            const int32_t s = e[side].slot;
            size_t at;
            if (s == TB__JOINT_WORLD)
                continue;
            at = tb__joint_node(w, s);
            if (k->stamp[at] == k->now) {
                first = k->body_row[at] < first ? k->body_row[at] : first;
                continue;
            }
            k->stamp[at] = k->now;
            k->body_row[at] = rows;
            k->moved[k->moved_count++] = s;
            if (forces && s >= 0) {
                const double *P = seen + w->off[TB__BODY_MOM] + 3 * s, *L = seen + w->off[TB__BODY_ANG] + 3 * s;
                double dP[3], dL[3], wl[3], out[6];
                int d;
                tb__body_rates(w, (uint32_t)s, P, L, dP, dL);
                tb__cross(e[side].w, L, wl);
                for (d = 0; d < 3; ++d)
                    dL[d] -= wl[d]; /* I alpha = tau - w x L */
                weigh(w, &e[side], dP, dL, out);
                memcpy(k->accel + 6 * at, out, sizeof out);
            } else if (forces) {
                tb__particle_acceleration(w, tb__joint_particle_slot(s), e[side].v, k->accel + 6 * at);
                memset(k->accel + 6 * at + 3, 0, 3 * sizeof *k->accel);
            }
        }
        for (r = 0; r < n; ++r) {
            k->first[rows + r] = first;
            k->offset[rows + r] = env;
            env += rows + r - first + 1;
        }
        rows += (size_t)n;
        if (!contact)
            k->row_end[j] = rows;
    }
    *count = rows;
    if (make == TB__SET_UP_ROWS)
        return TB_OK;
    if ((st = tb__reserve(w, (void **)&k->a, &k->env_cap, 5 * env + 1, sizeof(double))) != TB_OK)
        return st;
    k->l = k->a + env, k->upper = k->l + env, k->kept_a = k->upper + env, k->kept_l = k->kept_a + env;
    for (i = 0; i < rows; ++i) {
        double *ai = k->a + k->offset[i] - k->first[i], *ui = k->upper + k->offset[i] - k->first[i];
        double (*weighted)[12] = shake ? k->held_weighted : k->weighted;
        for (q = k->first[i]; q <= i; ++q)
            ai[q] = through(&k->rows[i], 0, weighted[q], &k->rows[q]) +
                    through(&k->rows[i], 1, weighted[q], &k->rows[q]);
        for (q = k->first[i]; shake && q < i; ++q) /* B_qi = J_q M^-1 H_i^T */
            ui[q] = through(&k->rows[q], 0, weighted[i], &k->held[i]) +
                    through(&k->rows[q], 1, weighted[i], &k->held[i]);
        k->use[i] = 1;
    }
    return TB_OK;
}

/* x = A^-1 x over the rows k->use keeps, those left out at 0 */
static void solve_kept(struct tb__joint_work *k, size_t rows)
{
    tb__envelope e;
    size_t i, q, n = 0, env = 0;
    for (i = 0; i < rows; ++i)
        n += k->use[i] != 0;
    if (n == rows) {
        e.first = k->first, e.offset = k->offset, e.a = k->a, e.l = k->l, e.use = k->use, e.drop = DROP;
        (void)tb__envelope_factor(&e, 0, rows); /* with drop, no pivot fails */
        for (i = 0; i < rows; ++i)
            if (!k->use[i])
                k->x[i] = 0;
        tb__envelope_solve(&e, 0, rows, k->x);
        return;
    }
    /* the kept rows alone, their envelope packed (a row left out costs
       its factor's loops otherwise: a pile's contact points mostly) */
    for (i = 0, n = 0; i < rows; ++i)
        if (k->use[i])
            k->packed[i] = n++;
    for (i = 0, n = 0; i < rows; ++i) {
        const double *ai = k->a + k->offset[i] - k->first[i];
        size_t count = 0;
        if (!k->use[i])
            continue;
        k->packed_first[n] = (size_t)-1;
        for (q = k->first[i]; q <= i; ++q)
            if (k->use[q]) {
                if (k->packed_first[n] == (size_t)-1)
                    k->packed_first[n] = k->packed[q];
                k->kept_a[env + count++] = ai[q];
            }
        k->packed_offset[n] = env;
        k->packed_use[n] = 1;
        k->packed_x[n] = k->x[i];
        env += count, ++n;
    }
    e.first = k->packed_first, e.offset = k->packed_offset, e.a = k->kept_a, e.l = k->kept_l;
    e.use = k->packed_use, e.drop = DROP;
    (void)tb__envelope_factor(&e, 0, n);
    for (i = 0; i < n; ++i)
        if (!k->packed_use[i])
            k->packed_x[i] = 0;
    tb__envelope_solve(&e, 0, n, k->packed_x);
    for (i = 0; i < rows; ++i) {
        k->x[i] = k->use[i] ? k->packed_x[k->packed[i]] : 0;
        if (k->use[i] && !k->packed_use[k->packed[i]]) /* left out by the factor */
            k->use[i] = 0;
    }
}

/* out = A x for the symmetric A whose lower envelope is k->a */
static void times_matrix(const struct tb__joint_work *k, size_t rows, const double *x, double *out)
{
    size_t i, q;
    memset(out, 0, rows * sizeof *out);
    for (i = 0; i < rows; ++i) {
        const double *ai = k->a + k->offset[i] - k->first[i];
        for (q = k->first[i]; q < i; ++q) {
            out[i] += ai[q] * x[q];
            out[q] += ai[q] * x[i];
        }
        out[i] += ai[i] * x[i];
    }
}

/* The most a MOTOR row's (its force over h) or a FRICTION row's (its
   impulse) multiplier may be either way */
static double bound(const tb__joint_row *r, double h)
{
    return r->kind == TB__ROW_MOTOR ? r->most * h : r->most;
}

/* A bounded solve's passes at most (else 8 + 2 per bounded row): each
   refactors the envelope, and an input of fuzz_api's (jointed bodies in
   a heap of contact rows, hostile figures) took 17 s over 24 steps
   uncapped, 8 s at 48 passes, 5 s at 24; the last pass's multipliers
   are then held within their bounds (below) */
#define MOST_PASSES 24

static int two_sided(const tb__joint_row *r)
{
    return r->kind == TB__ROW_MOTOR || r->kind == TB__ROW_FRICTION;
}

/* A bounded solve's row states */
enum { FREE, HELD_OUT, AT_UPPER, AT_LOWER, NOT_ASKED };

void tb__joint_solve(struct tb__joint_work *k, size_t rows, double h)
{
    size_t i, bounded = 0, pass, passes;
    double scale = 0, tolerance;
    for (i = 0; i < rows; ++i) {
        k->state[i] = k->use[i] ? FREE : NOT_ASKED;
        bounded += k->use[i] && k->rows[i].kind != TB__ROW_EQUAL;
    }
    if (!bounded) {
        solve_kept(k, rows);
        return;
    }
    /* an active set: each pass solves the free rows with those at a bound
       held there; rows past a bound are held at it, and held rows whose
       rate the others' multipliers break (a limit pulled through, a
       motor past its speed) are freed, until no row moves: a few passes
       for the few rows at a bound */
    memcpy(k->rhs, k->x, rows * sizeof *k->rhs);
    for (i = 0; i < rows; ++i)
        scale = fmax(scale, fabs(k->rhs[i]));
    tolerance = 1e-12 * scale;
    passes = 8 + 2 * bounded < MOST_PASSES ? 8 + 2 * bounded : MOST_PASSES;
    for (pass = 0; pass < passes; ++pass) {
        int changed = 0;
        for (i = 0; i < rows; ++i) {
            const double most = bound(&k->rows[i], h);
            k->clamped[i] = k->state[i] == AT_UPPER ? most : k->state[i] == AT_LOWER ? -most : 0;
        }
        times_matrix(k, rows, k->clamped, k->x);
        for (i = 0; i < rows; ++i) {
            k->use[i] = k->state[i] == FREE;
            k->x[i] = k->use[i] ? k->rhs[i] - k->x[i] : 0;
        }
        solve_kept(k, rows);
        for (i = 0; i < rows; ++i) {
            const tb__joint_row *r = &k->rows[i];
            if (k->state[i] == AT_UPPER || k->state[i] == AT_LOWER)
                k->x[i] = k->clamped[i];
            else if (k->state[i] == FREE && k->use[i] && r->kind == TB__ROW_LIMIT && k->x[i] < 0)
                k->state[i] = HELD_OUT, changed = 1;
            else if (k->state[i] == FREE && k->use[i] && two_sided(r) && fabs(k->x[i]) > bound(r, h))
                k->state[i] = k->x[i] > 0 ? AT_UPPER : AT_LOWER, changed = 1;
        }
        if (!changed) { /* the held rows' rates under these multipliers */
            times_matrix(k, rows, k->x, k->clamped);
            for (i = 0; i < rows; ++i) {
                const double left = k->clamped[i] - k->rhs[i]; /* what the row's rate misses */
                if ((k->state[i] == HELD_OUT && left < -tolerance) || (k->state[i] == AT_UPPER && left > tolerance) ||
                    (k->state[i] == AT_LOWER && left < -tolerance))
                    k->state[i] = FREE, changed = 1;
                else if (k->state[i] == FREE && !k->use[i] && two_sided(&k->rows[i]) &&
                         fabs(left) > tolerance) /* a motor the factor left out, on the coordinate of a
                                                    limit that holds: it pushes as it can */
                    k->state[i] = left < 0 ? AT_UPPER : AT_LOWER, changed = 1;
            }
        }
        if (!changed)
            break;
        if (pass + 1 == passes) /* cycling: the last multipliers, within bounds */
            for (i = 0; i < rows; ++i) {
                const double most = bound(&k->rows[i], h);
                if (k->state[i] == FREE && k->rows[i].kind == TB__ROW_LIMIT)
                    k->x[i] = fmax(k->x[i], 0);
                else if (k->state[i] == FREE && two_sided(&k->rows[i]))
                    k->x[i] = fmax(-most, fmin(most, k->x[i]));
            }
    }
    for (i = 0; i < rows; ++i)
        k->use[i] = k->state[i] != NOT_ASKED;
}

/* J^T x added to the ends: as forces to the evaluation's (forces 1:
   w->body_force, w->particle_force), or as impulses to the bodies'
   momenta and the particles' velocities */
void tb__joint_apply(tb_world *w, const tb__joint_row *rows, size_t count, const double *x, int forces)
{
    double *P = w->y + w->off[TB__BODY_MOM], *L = w->y + w->off[TB__BODY_ANG], *v = w->y + w->off[TB__PARTICLE_VEL];
    size_t i;
    int d, side;
    for (i = 0; i < count; ++i)
        for (side = 0; side < 2; ++side) {
            const int32_t s = side ? rows[i].b : rows[i].a;
            const double *lin = side ? rows[i].lin_b : rows[i].lin_a, *ang = side ? rows[i].ang_b : rows[i].ang_a;
            if (s >= 0 && forces) {
                for (d = 0; d < 3; ++d) {
                    w->body_force[3 * s + d] += lin[d] * x[i];
                    w->body_force[3 * w->body_count + 3 * s + d] += ang[d] * x[i];
                }
            } else if (s >= 0) {
                for (d = 0; d < 3; ++d) {
                    P[3 * s + d] += lin[d] * x[i];
                    L[3 * s + d] += ang[d] * x[i];
                }
            } else if (tb__joint_is_particle(s)) {
                const uint32_t p = tb__joint_particle_slot(s);
                for (d = 0; d < 3; ++d) {
                    if (forces)
                        w->particle_force[3 * p + d] += lin[d] * x[i];
                    else
                        v[3 * p + d] += w->particle_inv_mass[p] * (lin[d] * x[i]);
                }
            }
        }
}

/* Each joint's rows times the multipliers in k->x, added to its reaction:
   the force on a, and the torque on a about its anchor (lever from a's
   centre) */
void tb__joint_add_reactions(tb_world *w, const struct tb__joint_work *k, const tb__joint_row *rows,
                             const double *lever)
{
    size_t i, j;
    int d;
    for (j = 0; j < w->joint_count; ++j) {
        double *reaction = w->joint_reaction + 6 * j, force[3] = { 0, 0, 0 }, turn[3];
        if (w->joint_flags[j] & TB__JOINT_SOFT) /* (the soft step's: soft_joints.c) */
            continue;
        for (i = k->row_start[j]; i < k->row_end[j]; ++i)
            for (d = 0; d < 3; ++d) {
                force[d] += rows[i].lin_a[d] * k->x[i];
                reaction[3 + d] += rows[i].ang_a[d] * k->x[i];
            }
        tb__cross(lever + 3 * j, force, turn);
        for (d = 0; d < 3; ++d) {
            reaction[d] += force[d];
            reaction[3 + d] -= turn[d];
        }
    }
}

/* J times the motion of the ends in m (6 per node: linear, then
   angular) */
static double row_times(const tb_world *w, const tb__joint_row *r, const double *m)
{
    double sum = 0;
    if (r->a != TB__JOINT_WORLD) {
        const double *ma = m + 6 * tb__joint_node(w, r->a);
        sum += tb__dot3(r->lin_a, ma) + tb__dot3(r->ang_a, ma + 3);
    }
    if (r->b != TB__JOINT_WORLD) {
        const double *mb = m + 6 * tb__joint_node(w, r->b);
        sum += tb__dot3(r->lin_b, mb) + tb__dot3(r->ang_b, mb + 3);
    }
    return sum;
}

void tb__joint_rates(const tb_world *w, struct tb__joint_work *k, size_t rows)
{
    size_t i, n;
    for (i = 0; i < k->moved_count; ++i) { /* the ends' v and w, set up with the rows */
        n = tb__joint_node(w, k->moved[i]);
        memcpy(k->accel + 6 * n, k->ends[n].v, 3 * sizeof *k->accel);
        memcpy(k->accel + 6 * n + 3, k->ends[n].w, 3 * sizeof *k->accel);
    }
    for (i = 0; i < rows; ++i)
        k->x[i] = row_times(w, &k->rows[i], k->accel);
}

double tb__joint_row_rate(const tb_world *w, const struct tb__joint_work *k, const tb__joint_row *r)
{
    double sum = 0;
    if (r->a != TB__JOINT_WORLD) {
        const tb__joint_end *a = &k->ends[tb__joint_node(w, r->a)];
        sum += tb__dot3(r->lin_a, a->v) + tb__dot3(r->ang_a, a->w);
    }
    if (r->b != TB__JOINT_WORLD) {
        const tb__joint_end *b = &k->ends[tb__joint_node(w, r->b)];
        sum += tb__dot3(r->lin_b, b->v) + tb__dot3(r->ang_b, b->w);
    }
    return sum;
}

/* The evaluation's forces ready to be added to (w->force_ready), from 0
   if nothing had made them */
static void forces_ready(tb_world *w)
{
    if (!w->force_ready) {
        if (w->particle_count)
            memset(w->particle_force, 0, 3 * w->particle_count * sizeof(double));
        if (w->body_count)
            memset(w->body_force, 0, 6 * w->body_count * sizeof(double));
    }
    w->force_ready = 1;
}

void tb__joint_spring_forces(tb_world *w, const double *y, const double *seen)
{
    size_t j;
    for (j = 0; j < w->joint_count; ++j) {
        const double *drive = w->joint_drive + TB__DRIVES * j;
        tb__joint_end a, b;
        tb__joint_row row;
        double off, rate, force;
        if (!(w->joint_flags[j] & TB__JOINT_SPRING))
            continue;
        forces_ready(w);
        tb__joint_end_at(w, j, 0, y, seen, &a);
        tb__joint_end_at(w, j, 1, y, seen, &b);
        if (!tb__joint_coordinate(w, j, &a, &b, &row))
            continue;
        off = row.error - drive[TB__DRIVE_TARGET];
        if (w->joint_type[j] == TB_JOINT_HINGE) /* the shorter way round */
            off = remainder(off, 2 * 3.14159265358979323846);
        rate = tb__dot3(row.lin_a, a.v) + tb__dot3(row.ang_a, a.w) + tb__dot3(row.lin_b, b.v) +
               tb__dot3(row.ang_b, b.w);
        force = -(drive[TB__DRIVE_STIFFNESS] * off + drive[TB__DRIVE_DAMPING] * rate);
        tb__joint_apply(w, &row, 1, &force, 1);
    }
}

tb_status tb__joint_forces(tb_world *w, const double *y, const double *seen)
{
    struct tb__joint_work *k;
    size_t rows, i;
    tb_status st;
    if (w->joint_count == 0)
        return TB_OK;
    forces_ready(w); /* (before the rates: they read body_force from now) */
    tb__joint_spring_forces(w, y, seen);
    if ((st = tb__joint_set_up(w, y, seen, 1, 0, &rows)) != TB_OK)
        return st;
    k = w->joint_work;
    for (i = 0; i < rows; ++i) {
        const tb__joint_row *r = &k->rows[i];
        k->x[i] = -(row_times(w, r, k->accel) + r->bias);
        /* a limit holds where it is reached and not leaving; a motor acts
           on the velocities after the step (tb__joints_project) */
        if (two_sided(r) || (r->kind == TB__ROW_LIMIT && (r->error > 0 || tb__joint_row_rate(w, k, r) > 0)))
            k->use[i] = 0;
    }
    tb__joint_solve(k, rows, 1);
    memset(w->joint_reaction, 0, 6 * w->joint_count * sizeof *w->joint_reaction);
    tb__joint_add_reactions(w, k, k->rows, k->lever);
    k->impulses = 0;
    tb__joint_apply(w, k->rows, rows, k->x, 1);
    return TB_OK;
}

/* The largest |C| of the rows */
double tb__joint_largest_error(const struct tb__joint_work *k, size_t rows)
{
    double e = 0;
    size_t i;
    for (i = 0; i < rows; ++i)
        e = fmax(e, tb__joint_row_violation(&k->rows[i]));
    return e;
}

void tb__joint_keep(tb_world *w, struct tb__joint_work *k, double *buffer, int poses, int keep)
{
    size_t i;
    for (i = 0; i < k->moved_count; ++i) {
        const int32_t s = k->moved[i];
        double *kept = buffer + 7 * tb__joint_node(w, s), *a, *b = NULL;
        int n1 = 3, n2 = poses ? 4 : 3;
        if (s >= 0) {
            a = w->y + w->off[poses ? TB__BODY_POS : TB__BODY_MOM] + 3 * s;
            b = w->y + (poses ? w->off[TB__BODY_ROT] + 4 * (size_t)s : w->off[TB__BODY_ANG] + 3 * (size_t)s);
        } else {
            a = w->y + w->off[poses ? TB__PARTICLE_POS : TB__PARTICLE_VEL] + 3 * tb__joint_particle_slot(s);
            n2 = 0;
        }
        memcpy(keep ? kept : a, keep ? a : kept, (size_t)n1 * sizeof *a);
        if (n2)
            memcpy(keep ? kept + n1 : b, keep ? b : kept + n1, (size_t)n2 * sizeof *b);
    }
}

void tb__joints_begin_step(tb_world *w)
{
    size_t j;
    for (j = 0; j < w->joint_count; ++j) /* (the contacts mark theirs: soft_joints.c) */
        w->joint_flags[j] &= ~(uint32_t)TB__JOINT_SOFT;
    if (w->joint_work)
        w->joint_work->impulses = 0, w->joint_work->contact_count = 0;
}

void tb__joint_work_free(tb_world *w)
{
    struct tb__joint_work *k = w->joint_work;
    if (!k)
        return;
    tb__alloc(w, k->rows, k->row_cap * sizeof *k->rows, 0);
    tb__alloc(w, k->weighted, k->row_cap * sizeof *k->weighted, 0);
    tb__alloc(w, k->first, k->row_cap * sizeof *k->first, 0);
    tb__alloc(w, k->offset, k->row_cap * sizeof *k->offset, 0);
    tb__alloc(w, k->x, k->row_cap * sizeof *k->x, 0);
    tb__alloc(w, k->use, k->row_cap, 0);
    tb__alloc(w, k->newton, k->row_cap * sizeof *k->newton, 0);
    tb__alloc(w, k->total, k->row_cap * sizeof *k->total, 0);
    tb__alloc(w, k->rhs, k->row_cap * sizeof *k->rhs, 0);
    tb__alloc(w, k->clamped, k->row_cap * sizeof *k->clamped, 0);
    tb__alloc(w, k->state, k->row_cap, 0);
    tb__alloc(w, k->packed, k->row_cap * sizeof *k->packed, 0);
    tb__alloc(w, k->packed_first, k->row_cap * sizeof *k->packed_first, 0);
    tb__alloc(w, k->packed_offset, k->row_cap * sizeof *k->packed_offset, 0);
    tb__alloc(w, k->packed_use, k->row_cap, 0);
    tb__alloc(w, k->packed_x, k->row_cap * sizeof *k->packed_x, 0);
    tb__alloc(w, k->row_start, k->joint_cap * sizeof *k->row_start, 0);
    tb__alloc(w, k->row_end, k->joint_cap * sizeof *k->row_end, 0);
    tb__alloc(w, k->order, k->order_cap * sizeof *k->order, 0);
    tb__alloc(w, k->lever, k->joint_cap * 3 * sizeof *k->lever, 0);
    tb__alloc(w, k->held_lever, k->joint_cap * 3 * sizeof *k->held_lever, 0);
    tb__alloc(w, k->a, k->env_cap * sizeof *k->a, 0);
    tb__alloc(w, k->accel, k->body_cap * 6 * sizeof *k->accel, 0);
    tb__alloc(w, k->body_row, k->body_cap * sizeof *k->body_row, 0);
    tb__alloc(w, k->stamp, k->body_cap * sizeof *k->stamp, 0);
    tb__alloc(w, k->start, k->body_cap * 7 * sizeof *k->start, 0);
    tb__alloc(w, k->moved, k->body_cap * sizeof *k->moved, 0);
    tb__alloc(w, k->kept, k->body_cap * 7 * sizeof *k->kept, 0);
    tb__alloc(w, k->half, k->body_cap * 7 * sizeof *k->half, 0);
    tb__alloc(w, k->ends, k->body_cap * sizeof *k->ends, 0);
    tb__alloc(w, k->held, k->held_cap * sizeof *k->held, 0);
    tb__alloc(w, k->contacts, k->contact_cap * sizeof *k->contacts, 0);
    tb__alloc(w, k->island, k->island_cap * sizeof *k->island, 0);
    tb__alloc(w, k->apart, k->apart_cap * sizeof *k->apart, 0);
    tb__alloc(w, k->held_weighted, k->held_weighted_cap * sizeof *k->held_weighted, 0);
    tb__alloc(w, k, sizeof *k, 0);
    w->joint_work = NULL;
}
