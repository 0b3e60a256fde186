/* joints.c: joints between bodies, or a body and the world: what each
   holds (kept in the bodies' principal frames, so it moves with them),
   adding, removing, and reading them. */
#include "joints/joints.h"
#include "bodies/bodies.h"

#include <math.h>
#include <string.h>

#define JOINT_ARRAYS 7

static void body_removed(tb_world *w, uint32_t body_index1);

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
    arrays[6] = (void **)&w->joint_collide;  sizes[6] = sizeof(uint32_t);
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

/* The slot of the body joint j holds on side k (0: a, 1: b); -1: the
   world. A joint's bodies are live: a removed body takes its joints. */
static int32_t slot_of(const tb_world *w, size_t j, int k)
{
    const uint32_t index1 = w->joint_body[2 * j + k];
    return index1 ? (int32_t)w->body_ids.slot[index1 - 1] : -1;
}

void tb__joint_end_at(const tb_world *w, size_t j, int k, const double *y, const double *seen, tb__joint_end *end)
{
    int d;
    end->slot = slot_of(w, j, k);
    pose_of(w, end->slot, y, end->x, end->R);
    memset(end->v, 0, sizeof end->v);
    memset(end->w, 0, sizeof end->w);
    if (end->slot >= 0) {
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

static tb_status check_def(tb_world *w, const tb_joint_def *def, uint32_t *sa, int32_t *sb)
{
    tb_status st;
    uint32_t s;
    if (!def)
        return tb__fail(w, TB_ERR_ARGUMENT, "joint definition must not be NULL");
    if (tb__joint_row_count((uint32_t)def->type) == 0)
        return tb__fail(w, TB_ERR_ARGUMENT, "unknown joint type %d", (int)def->type);
    if ((st = tb__body_find(w, def->a, sa)) != TB_OK)
        return tb__fail(w, TB_ERR_STALE_ID, "joint body a: %s", tb_world_message(w));
    *sb = -1;
    if (!TB_ID_IS_NULL(def->b)) {
        if ((st = tb__body_find(w, def->b, &s)) != TB_OK)
            return tb__fail(w, TB_ERR_STALE_ID, "joint body b: %s", tb_world_message(w));
        if (s == *sa)
            return tb__fail(w, TB_ERR_ARGUMENT, "a joint cannot join a body to itself");
        *sb = (int32_t)s;
    }
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

tb_status tb_world_add_joint(tb_world *w, const tb_joint_def *def, tb_joint_id *id)
{
    double frame[9], xa[3], Ra[9], xb[3], Rb[9], n, length = 0;
    const double *anchor_b;
    tb_joint_id made;
    tb_status st;
    uint32_t sa, j;
    int32_t sb;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "add a joint")) != TB_OK || (st = check_def(w, def, &sa, &sb)) != TB_OK)
        return st;
    anchor_b = def->type == TB_JOINT_DISTANCE ? def->anchor_b : def->anchor;
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
        const double d[3] = { def->anchor[0] - anchor_b[0], def->anchor[1] - anchor_b[1],
                              def->anchor[2] - anchor_b[2] };
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
    w->joint_type[j] = (uint32_t)def->type;
    w->joint_body[2 * j] = def->a.index1;
    w->joint_body[2 * j + 1] = sb >= 0 ? def->b.index1 : 0;
    pose_of(w, (int32_t)sa, w->y, xa, Ra);
    pose_of(w, sb, w->y, xb, Rb);
    into_frame(xa, Ra, def->anchor, frame, w->joint_anchor + 6 * j, w->joint_frame + 18 * j);
    into_frame(xb, Rb, anchor_b, frame, w->joint_anchor + 6 * j + 3, w->joint_frame + 18 * j + 9);
    w->joint_length[j] = length;
    w->joint_collide[j] = def->collide != 0;
    memset(w->joint_reaction + 6 * j, 0, 6 * sizeof(double));
    tb__wake_body(w, sa);
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
        if (slot_of(w, j, k) >= 0)
            tb__wake_body(w, (uint32_t)slot_of(w, j, k));
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

/* A removed body takes its joints with it */
static void body_removed(tb_world *w, uint32_t body_index1)
{
    size_t j = w->joint_count;
    while (j-- > 0)
        if (w->joint_body[2 * j] == body_index1 || w->joint_body[2 * j + 1] == body_index1)
            remove_slot(w, (uint32_t)j);
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
