/* joints.c: joints between bodies, or a body and the world: what each
   holds (kept in the bodies' principal frames, so it moves with them),
   adding, removing, and reading them. */
#include "joints/joint_work.h"
#include "bodies/bodies.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define JOINT_ARRAYS 7

static void body_removed(tb_world *w, uint32_t body_index1);
static void particle_removed(tb_world *w, uint32_t slot, uint32_t last);

tb_joint_def tb_default_joint_def(void)
{
    tb_joint_def def;
    memset(&def, 0, sizeof def);
    def.type = TB_JOINT_BALL;
    def.axis[2] = 1;
    def.length = -1;
    return def;
}

int tb__joint_row_count(uint32_t type)
{
    static const int rows[] = { 3, 5, 5, 6, 1 }; /* ball, hinge, slider, fixed, distance */
    return type < sizeof rows / sizeof rows[0] ? rows[type] : 0;
}

static void arrays_of(tb_world *w, void **arrays[JOINT_ARRAYS], size_t sizes[JOINT_ARRAYS])
{
    arrays[0] = (void **)&w->joint_type;     sizes[0] = sizeof(uint32_t);
    arrays[1] = (void **)&w->joint_body;     sizes[1] = 2 * sizeof(uint32_t);
    arrays[2] = (void **)&w->joint_anchor;   sizes[2] = 6 * sizeof(double);
    arrays[3] = (void **)&w->joint_frame;    sizes[3] = 18 * sizeof(double);
    arrays[4] = (void **)&w->joint_length;   sizes[4] = sizeof(double);
    arrays[5] = (void **)&w->joint_reaction; sizes[5] = 6 * sizeof(double);
    arrays[6] = (void **)&w->joint_flags;    sizes[6] = sizeof(uint32_t);
}

/* The pose of body slot s (x, R), or the world's for s = -1 */
static void pose_of(const tb_world *w, int32_t s, const double *y, double x[3], double R[9])
{
    static const double identity[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 };
    double q[4];
    if (s < 0) {
        memset(x, 0, 3 * sizeof *x);
        memcpy(R, identity, sizeof identity);
        return;
    }
    memcpy(x, y + w->off[TB__BODY_POS] + 3 * s, 3 * sizeof *x);
    memcpy(q, y + w->off[TB__BODY_ROT] + 4 * s, sizeof q);
    tb__normalise(q); /* a Runge-Kutta stage's q is not unit */
    tb__matrix_of(q, R);
}

static int holds_particle(const tb_world *w, size_t j, int k)
{
    return (w->joint_flags[j] & (k ? TB__JOINT_PARTICLE_B : TB__JOINT_PARTICLE_A)) != 0;
}

/* The end of joint j on side k (0: a, 1: b), as joints.h encodes ends: a
   body's slot, -1 the world, -2 - slot a particle's. A joint's bodies
   and particles are live: a removed one takes its joints. */
static int32_t slot_of(const tb_world *w, size_t j, int k)
{
    const uint32_t index1 = w->joint_body[2 * j + k];
    if (!index1)
        return TB__JOINT_WORLD;
    return holds_particle(w, j, k) ? tb__joint_particle_end(w->particle_ids.slot[index1 - 1])
                                   : (int32_t)w->body_ids.slot[index1 - 1];
}

static int32_t body_slot_of(const tb_world *w, size_t j, int k)
{
    const int32_t s = slot_of(w, j, k);
    return s >= 0 ? s : -1;
}

int32_t tb__joint_end_slot(const tb_world *w, size_t j, int k)
{
    return slot_of(w, j, k);
}

void tb__joint_end_at(const tb_world *w, size_t j, int k, const double *y, const double *seen, tb__joint_end *end)
{
    tb__joint_end_of(w, slot_of(w, j, k), y, seen, end);
}

void tb__joint_end_of(const tb_world *w, int32_t slot, const double *y, const double *seen, tb__joint_end *end)
{
    int d;
    end->slot = slot;
    pose_of(w, end->slot >= 0 ? end->slot : -1, y, end->x, end->R);
    memset(end->v, 0, sizeof end->v);
    memset(end->w, 0, sizeof end->w);
    if (tb__joint_is_particle(end->slot)) {
        const uint32_t p = tb__joint_particle_slot(end->slot);
        memcpy(end->x, y + w->off[TB__PARTICLE_POS] + 3 * p, sizeof end->x);
        memcpy(end->v, seen + w->off[TB__PARTICLE_VEL] + 3 * p, sizeof end->v);
    } else if (end->slot >= 0) {
        const double *P = seen + w->off[TB__BODY_MOM] + 3 * end->slot, *L = seen + w->off[TB__BODY_ANG] + 3 * end->slot;
        const double *inv = w->body_inv_inertia + 3 * end->slot;
        double Lb[3];
        for (d = 0; d < 3; ++d)
            end->v[d] = P[d] * w->body_inv_mass[end->slot];
        tb__mul_transposed(end->R, L, Lb);
        for (d = 0; d < 3; ++d)
            Lb[d] *= inv[d];
        tb__mul(end->R, Lb, end->w);
    }
}

/* Two unit vectors square to the unit n and to each other, (n, t1, t2)
   right-handed */
static void square_to(const double n[3], double t1[3], double t2[3])
{
    const double a[3] = { fabs(n[0]) < 0.6 ? 1 : 0, fabs(n[0]) < 0.6 ? 0 : 1, 0 };
    double l;
    tb__cross(n, a, t1);
    l = tb__norm3(t1);
    t1[0] /= l, t1[1] /= l, t1[2] /= l;
    tb__cross(n, t1, t2);
}

/* The world point p, and the world frame's rows, in the frame of end
   (x, R): R^T (p - x) and R^T f */
static void into_frame(const double x[3], const double R[9], const double p[3], const double frame[9],
                       double local[3], double local_frame[9])
{
    const double d[3] = { p[0] - x[0], p[1] - x[1], p[2] - x[2] };
    int k;
    tb__mul_transposed(R, d, local);
    for (k = 0; k < 3; ++k)
        tb__mul_transposed(R, frame + 3 * k, local_frame + 3 * k);
}

/* One side of a joint: a body, a particle, or (side b only) neither: the
   world. *slot as joints.h encodes ends. */
static tb_status check_side(tb_world *w, tb_body_id body, tb_particle_id particle, int k, int32_t *slot)
{
    const char *side = k ? "b" : "a";
    uint32_t s;
    if (!TB_ID_IS_NULL(body) && !TB_ID_IS_NULL(particle))
        return tb__fail(w, TB_ERR_ARGUMENT, "joint side %s: a body or a particle, not both", side);
    if (!TB_ID_IS_NULL(particle)) {
        if (!tb__ids_lookup(&w->particle_ids, particle.index1, particle.generation, &s))
            return tb__fail(w, TB_ERR_STALE_ID, "joint particle %s: particle id %u.%u is removed or from another "
                            "world", side, particle.index1, particle.generation);
        *slot = tb__joint_particle_end(s);
        return TB_OK;
    }
    if (TB_ID_IS_NULL(body)) {
        if (!k)
            return tb__fail(w, TB_ERR_STALE_ID, "joint body a: body id %u.%u is null, removed or from another world",
                            body.index1, body.generation);
        *slot = TB__JOINT_WORLD;
        return TB_OK;
    }
    if (tb__body_find(w, body, &s) != TB_OK)
        return tb__fail(w, TB_ERR_STALE_ID, "joint body %s: %s", side, tb_world_message(w));
    *slot = (int32_t)s;
    return TB_OK;
}

static tb_status check_def(tb_world *w, const tb_joint_def *def, int32_t *sa, int32_t *sb)
{
    tb_status st;
    if (!def)
        return tb__fail(w, TB_ERR_ARGUMENT, "joint definition must not be NULL");
    if (tb__joint_row_count((uint32_t)def->type) == 0)
        return tb__fail(w, TB_ERR_ARGUMENT, "unknown joint type %d", (int)def->type);
    if ((st = check_side(w, def->a, def->particle_a, 0, sa)) != TB_OK ||
        (st = check_side(w, def->b, def->particle_b, 1, sb)) != TB_OK)
        return st;
    if (*sa == *sb)
        return tb__fail(w, TB_ERR_ARGUMENT, "a joint cannot join a %s to itself", *sa >= 0 ? "body" : "particle");
    if ((tb__joint_is_particle(*sa) || tb__joint_is_particle(*sb)) && def->type != TB_JOINT_BALL &&
        def->type != TB_JOINT_DISTANCE)
        return tb__fail(w, TB_ERR_ARGUMENT, "a particle has no orientation: it takes part in ball and distance "
                        "joints only");
    if ((st = tb__check_values(w, def->anchor, 3, "joint anchor")) != TB_OK)
        return st;
    if (def->type == TB_JOINT_DISTANCE &&
        ((st = tb__check_values(w, def->anchor_b, 3, "joint anchor_b")) != TB_OK ||
         (st = tb__check_values(w, &def->length, 1, "joint length")) != TB_OK))
        return st;
    if ((def->type == TB_JOINT_HINGE || def->type == TB_JOINT_SLIDER) &&
        (st = tb__check_values(w, def->axis, 3, "joint axis")) != TB_OK)
        return st;
    return TB_OK;
}

/* Where side k's end of a new joint is: a particle's position, else the
   anchor it names */
static const double *end_point(const tb_world *w, int32_t slot, const double *anchor)
{
    return tb__joint_is_particle(slot) ? w->y + w->off[TB__PARTICLE_POS] + 3 * tb__joint_particle_slot(slot) : anchor;
}

tb_status tb_world_add_joint(tb_world *w, const tb_joint_def *def, tb_joint_id *id)
{
    double frame[9], xa[3], Ra[9], xb[3], Rb[9], n, length = 0;
    const double *anchor_a, *anchor_b;
    tb_joint_id made;
    tb_status st;
    uint32_t j;
    int32_t sa, sb;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "add a joint")) != TB_OK || (st = check_def(w, def, &sa, &sb)) != TB_OK)
        return st;
    /* a particle is its own anchor; a ball joint holds it at `anchor` on
       the other side */
    anchor_a = end_point(w, sa, def->anchor);
    anchor_b = end_point(w, sb, def->type == TB_JOINT_DISTANCE ? def->anchor_b : def->anchor);
    /* the joint's axes: the axis (z for the types that have none), then two
       square to it */
    n = def->type == TB_JOINT_HINGE || def->type == TB_JOINT_SLIDER ? tb__norm3(def->axis) : 1;
    if (!(n > 0) || !isfinite(n))
        return tb__fail(w, TB_ERR_ARGUMENT, "joint axis (%g, %g, %g) has no direction", def->axis[0], def->axis[1],
                        def->axis[2]);
    if (def->type == TB_JOINT_HINGE || def->type == TB_JOINT_SLIDER)
        frame[0] = def->axis[0] / n, frame[1] = def->axis[1] / n, frame[2] = def->axis[2] / n;
    else
        frame[0] = 0, frame[1] = 0, frame[2] = 1;
    square_to(frame, frame + 3, frame + 6);
    if (def->type == TB_JOINT_DISTANCE) {
        const double d[3] = { anchor_a[0] - anchor_b[0], anchor_a[1] - anchor_b[1], anchor_a[2] - anchor_b[2] };
        length = def->length >= 0 ? def->length : tb__norm3(d);
        if (!tb__in_scale(length))
            return tb__fail(w, TB_ERR_ARGUMENT, "distance joint length %g m: it must be from %g to %g m (its ends "
                            "apart)", length, 1 / TB_LIMIT, TB_LIMIT);
    }
    if (w->joint_count == w->joint_cap) {
        const size_t cap = w->joint_cap ? 2 * w->joint_cap : 8;
        void **arrays[JOINT_ARRAYS];
        size_t sizes[JOINT_ARRAYS];
        arrays_of(w, arrays, sizes);
        if ((st = tb__ids_reserve(w, &w->joint_ids, cap)) != TB_OK ||
            (st = tb__grow(w, arrays, sizes, JOINT_ARRAYS, w->joint_count, w->joint_cap, cap)) != TB_OK)
            return st;
        w->joint_cap = cap;
    }
    j = (uint32_t)w->joint_count++;
    w->body_removed[TB__HEARS_JOINTS] = body_removed;
    w->particle_removed[TB__HEARS_PARTICLE_JOINTS] = particle_removed;
    w->joint_type[j] = (uint32_t)def->type;
    w->joint_body[2 * j] = tb__joint_is_particle(sa) ? def->particle_a.index1 : def->a.index1;
    w->joint_body[2 * j + 1] = tb__joint_is_particle(sb) ? def->particle_b.index1 : sb >= 0 ? def->b.index1 : 0;
    w->joint_flags[j] = (def->collide ? TB__JOINT_COLLIDE : 0) |
                        (tb__joint_is_particle(sa) ? TB__JOINT_PARTICLE_A : 0) |
                        (tb__joint_is_particle(sb) ? TB__JOINT_PARTICLE_B : 0);
    /* a particle's end is the particle: its anchor is 0 in an unturned frame */
    pose_of(w, sa >= 0 ? sa : -1, w->y, xa, Ra);
    pose_of(w, sb >= 0 ? sb : -1, w->y, xb, Rb);
    if (tb__joint_is_particle(sa))
        memcpy(xa, anchor_a, sizeof xa);
    if (tb__joint_is_particle(sb))
        memcpy(xb, anchor_b, sizeof xb);
    into_frame(xa, Ra, anchor_a, frame, w->joint_anchor + 6 * j, w->joint_frame + 18 * j);
    into_frame(xb, Rb, anchor_b, frame, w->joint_anchor + 6 * j + 3, w->joint_frame + 18 * j + 9);
    w->joint_length[j] = length;
    memset(w->joint_reaction + 6 * j, 0, 6 * sizeof(double));
    if (sa >= 0)
        tb__wake_body(w, (uint32_t)sa);
    if (sb >= 0)
        tb__wake_body(w, (uint32_t)sb);
    tb__ids_acquire(&w->joint_ids, w->id_tag, j, &made.index1, &made.generation);
    if (id)
        *id = made;
    return TB_OK;
}

static void remove_slot(tb_world *w, uint32_t j)
{
    const uint32_t last = (uint32_t)w->joint_count - 1;
    uint32_t index1, generation;
    tb__ids_at(&w->joint_ids, j, &index1, &generation);
    if (j != last) {
        void **arrays[JOINT_ARRAYS];
        size_t sizes[JOINT_ARRAYS], k;
        arrays_of(w, arrays, sizes);
        for (k = 0; k < JOINT_ARRAYS; ++k) {
            unsigned char *base = *arrays[k];
            memcpy(base + j * sizes[k], base + last * sizes[k], sizes[k]);
        }
        tb__ids_move(&w->joint_ids, last, j);
    }
    tb__ids_release(&w->joint_ids, index1);
    w->joint_count--;
}

static tb_status find(const tb_world *w, tb_joint_id id, uint32_t *j)
{
    if (!tb__ids_lookup(&w->joint_ids, id.index1, id.generation, j))
        return tb__fail((tb_world *)w, TB_ERR_STALE_ID, "joint id %u.%u is null, removed or from another world",
                        id.index1, id.generation);
    return TB_OK;
}

tb_status tb_world_remove_joint(tb_world *w, tb_joint_id id)
{
    tb_status st;
    uint32_t j;
    int k;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "remove a joint")) != TB_OK || (st = find(w, id, &j)) != TB_OK)
        return st;
    for (k = 0; k < 2; ++k) /* what it held may fall */
        if (body_slot_of(w, j, k) >= 0)
            tb__wake_body(w, (uint32_t)body_slot_of(w, j, k));
    remove_slot(w, j);
    return TB_OK;
}

size_t tb_world_joint_count(const tb_world *w)
{
    TB__NEED_WORLD(w, 0);
    return w->joint_count;
}

tb_joint_id tb_world_joint_at(const tb_world *w, size_t slot)
{
    tb_joint_id id = { 0, 0 };
    if (w && slot < w->joint_count)
        tb__ids_at(&w->joint_ids, (uint32_t)slot, &id.index1, &id.generation);
    return id;
}

tb_status tb_joint_reaction(const tb_world *w, tb_joint_id id, double force[3], double torque[3])
{
    tb_status st;
    uint32_t j;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if (!force || !torque)
        return tb__null((tb_world *)w, "tb_joint_reaction", "force or torque");
    if ((st = find(w, id, &j)) != TB_OK)
        return st;
    memcpy(force, w->joint_reaction + 6 * j, 3 * sizeof(double));
    memcpy(torque, w->joint_reaction + 6 * j + 3, 3 * sizeof(double));
    return TB_OK;
}

tb_status tb_joint_error(const tb_world *w, tb_joint_id id, double *error)
{
    tb__joint_end a, b;
    tb__joint_row rows[TB__JOINT_ROWS];
    tb_status st;
    uint32_t j;
    int n, k;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if (!error)
        return tb__null((tb_world *)w, "tb_joint_error", "error");
    if ((st = find(w, id, &j)) != TB_OK)
        return st;
    tb__joint_end_at(w, j, 0, w->y, w->y, &a);
    tb__joint_end_at(w, j, 1, w->y, w->y, &b);
    n = tb__joint_rows(w, j, &a, &b, rows);
    *error = 0;
    for (k = 0; k < n; ++k)
        *error = fmax(*error, fabs(rows[k].error));
    return TB_OK;
}

/* A removed body or particle takes its joints with it */
static void remove_holding(tb_world *w, uint32_t index1, int particle)
{
    size_t j = w->joint_count;
    int k;
    while (j-- > 0)
        for (k = 0; k < 2; ++k)
            if (w->joint_body[2 * j + k] == index1 && holds_particle(w, j, k) == particle) {
                remove_slot(w, (uint32_t)j);
                break;
            }
}

static void body_removed(tb_world *w, uint32_t body_index1)
{
    remove_holding(w, body_index1, 0);
}

/* (called before the particle's id is released: its slot names it) */
static void particle_removed(tb_world *w, uint32_t slot, uint32_t last)
{
    (void)last;
    remove_holding(w, w->particle_ids.owner[slot] + 1, 1);
}

void tb__joints_free(tb_world *w)
{
    void **arrays[JOINT_ARRAYS];
    size_t sizes[JOINT_ARRAYS];
    arrays_of(w, arrays, sizes);
    tb__free_arrays(w, arrays, sizes, JOINT_ARRAYS, w->joint_cap);
    tb__ids_free(w, &w->joint_ids);
    tb__joint_work_free(w);
    w->joint_count = w->joint_cap = 0;
}

/* ---- which bodies' shapes pass through each other ------------------------------ */

static uint64_t pair_key(uint32_t a, uint32_t b)
{
    return a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
}

static int by_key(const void *x, const void *y)
{
    const uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return a < b ? -1 : a > b;
}

tb_status tb__joints_apart_prepare(tb_world *w)
{
    struct tb__joint_work *k;
    tb_status st;
    size_t j;
    if (w->joint_count == 0)
        return TB_OK;
    if ((st = tb__joint_reserve(w, 0)) != TB_OK)
        return st;
    k = w->joint_work;
    if ((st = tb__reserve(w, (void **)&k->apart, &k->apart_cap, w->joint_count, sizeof *k->apart)) != TB_OK)
        return st;
    k->apart_count = 0;
    for (j = 0; j < w->joint_count; ++j)
        if (!(w->joint_flags[j] & (TB__JOINT_COLLIDE | TB__JOINT_PARTICLE_A | TB__JOINT_PARTICLE_B)) &&
            w->joint_body[2 * j + 1])
            k->apart[k->apart_count++] = pair_key(w->joint_body[2 * j], w->joint_body[2 * j + 1]);
    qsort(k->apart, k->apart_count, sizeof *k->apart, by_key);
    return TB_OK;
}

int tb__joints_apart(const tb_world *w, uint32_t a, uint32_t b)
{
    const struct tb__joint_work *k = w->joint_work;
    const uint64_t key = pair_key(a, b);
    size_t lo = 0, hi;
    if (w->joint_count == 0 || !k || k->apart_count == 0)
        return 0;
    hi = k->apart_count;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        if (k->apart[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < k->apart_count && k->apart[lo] == key;
}
