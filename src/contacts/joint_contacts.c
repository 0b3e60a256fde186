/* joint_contacts.c: the contact points of the islands that have joints,
   handed to the joints' projection after the contacts' solve (joints.h,
   tb__joint_contact; docs/joints.md, "Joints and contacts"). The soft
   step moves a jointed body as if free, so a load on a jointed plank
   pushed the plank off its joints, the projection put it back, and the
   load sank through (a box fell through a cantilevered plank in 0.6 s).
   Solved with the joints' rows in the projection, each touching point
   only pushes and keeps its sides from approaching (a LIMIT row), so
   the joints carry the load exactly, in one direct solve. An island is
   the bodies joined by joints or by contact rows; every contact row of
   an island with a joint goes (test_joint_drives.jointed_bodies_carry_loads). */
#include "contacts/soft_step.h"
#include "joints/joint_work.h"

#include <string.h>

static int32_t root(int32_t *parent, int32_t i)
{
    while (parent[i] != i)
        i = parent[i] = parent[parent[i]];
    return i;
}

static void join(int32_t *parent, int32_t a, int32_t b)
{
    if (a >= 0 && b >= 0)
        parent[root(parent, a)] = root(parent, b);
}

/* A joint's end (joints.h) as the contacts' solver body, -1: none */
static int32_t solver_body(const tb__contacts *c, const tb_world *w, int32_t end)
{
    if (end >= 0)
        return (size_t)end < w->body_count ? c->body_map[end] : -1;
    if (tb__joint_is_particle(end))
        return c->particle_map ? c->particle_map[tb__joint_particle_slot(end)] : -1;
    return -1;
}

/* Solver body i as a joint end, its anchor for the point p (world, at the
   start of the step) in its principal frame, and where the anchor was at
   the start; the static world: the point itself, fixed */
static int32_t end_of(const tb__contacts *c, int32_t i, const double p[3], double anchor[3], double at[3])
{
    const tb__solver_body *b;
    double d[3], q[4], R[9];
    int k;
    if (i < 0) {
        memset(anchor, 0, 3 * sizeof *anchor);
        memset(at, 0, 3 * sizeof *at);
        return TB__JOINT_WORLD;
    }
    b = &c->bodies[i];
    for (k = 0; k < 3; ++k)
        d[k] = p[k] - b->x0[k];
    memcpy(at, p, 3 * sizeof *at);
    if (b->tier != TB__BODIES) { /* a particle is its own point */
        memset(anchor, 0, 3 * sizeof *anchor);
        memcpy(at, b->x0, 3 * sizeof *at);
        return tb__joint_particle_end(b->slot);
    }
    memcpy(q, b->q0, sizeof q);
    tb__normalise(q);
    tb__matrix_of(q, R);
    tb__mul_transposed(R, d, anchor);
    return (int32_t)b->slot;
}

/* Room for one more contact row */
static tb_status more(tb_world *w, struct tb__joint_work *k, tb__joint_contact **t)
{
    tb_status st;
    if ((st = tb__reserve(w, (void **)&k->contacts, &k->contact_cap, k->contact_count + 1, sizeof *k->contacts)) !=
        TB_OK)
        return st;
    *t = &k->contacts[k->contact_count++];
    return TB_OK;
}

/* A patch's rows: each point's normal (a LIMIT row), and while its
   points pressed, its friction along its two tangents at their centre
   (FRICTION rows within mu times the step's normal impulse of its
   points, the soft step's): the slip's speed held at 0 as far as that
   impulse stops it. (The slip the soft step made within the step stays:
   docs/joints.md, "Joints and contacts".) */
static tb_status patch_rows(tb_world *w, const tb__contacts *c, struct tb__joint_work *k, const tb__soft_patch *patch)
{
    double pressed = 0;
    size_t r;
    tb_status st;
    for (r = patch->first; r < patch->first + patch->count; ++r) {
        const tb__soft_row *o = &c->soft_rows[r];
        tb__joint_contact *t;
        double on_a[3], on_b[3], at_a[3], at_b[3];
        int d;
        if ((st = more(w, k, &t)) != TB_OK)
            return st;
        pressed += o->step_impulse;
        /* each side's core point (a round shape turns about it), as the
           soft step finds the separation from the motion */
        for (d = 0; d < 3; ++d) {
            on_a[d] = (o->a >= 0 ? c->bodies[o->a].x0[d] : 0) + o->core_a[d];
            on_b[d] = (o->b >= 0 ? c->bodies[o->b].x0[d] : 0) + o->core_b[d];
        }
        t->kind = TB__ROW_LIMIT;
        t->most = 0;
        t->a = end_of(c, o->a, on_a, t->anchor_a, at_a);
        t->b = end_of(c, o->b, on_b, t->anchor_b, at_b);
        memcpy(t->normal, o->normal, sizeof t->normal);
        /* C = n.(p_b - p_a) + offset: the separation at the start, plus the
           overlap the contacts leave alone; held when touching */
        t->offset = o->separation - tb__dot3(o->normal, at_b) + tb__dot3(o->normal, at_a) + c->settings.slop;
        t->reach = c->settings.slop;
    }
    if (patch->friction > 0 && pressed > 0)
        for (r = 0; r < 2; ++r) {
            tb__joint_contact *t;
            double on_a[3], on_b[3], at_a[3], at_b[3];
            int d;
            if ((st = more(w, k, &t)) != TB_OK)
                return st;
            for (d = 0; d < 3; ++d) {
                on_a[d] = (patch->a >= 0 ? c->bodies[patch->a].x0[d] : 0) + patch->ca[d];
                on_b[d] = (patch->b >= 0 ? c->bodies[patch->b].x0[d] : 0) + patch->cb[d];
            }
            t->kind = TB__ROW_FRICTION;
            t->most = patch->friction * pressed;
            t->a = end_of(c, patch->a, on_a, t->anchor_a, at_a);
            t->b = end_of(c, patch->b, on_b, t->anchor_b, at_b);
            memcpy(t->normal, patch->tangent[r], sizeof t->normal);
            t->offset = t->reach = 0;
        }
    return TB_OK;
}

tb_status tb__contacts_for_joints(tb_world *w)
{
    tb__contacts *c = w->contacts;
    struct tb__joint_work *k;
    int32_t *parent, *jointed;
    size_t i, j;
    tb_status st;
    if (w->joint_count == 0 || !c || c->soft_row_count == 0 || c->body_count == 0)
        return TB_OK;
    if ((st = tb__joint_reserve(w, 0)) != TB_OK)
        return st;
    k = w->joint_work;
    k->contact_count = 0;
    if ((st = tb__reserve(w, (void **)&k->island, &k->island_cap, 2 * c->body_count, sizeof *k->island)) != TB_OK)
        return st;
    parent = k->island, jointed = k->island + c->body_count;
    for (i = 0; i < c->body_count; ++i)
        parent[i] = (int32_t)i, jointed[i] = 0;
    for (i = 0; i < c->soft_row_count; ++i)
        join(parent, c->soft_rows[i].a, c->soft_rows[i].b);
    for (j = 0; j < w->joint_count; ++j)
        join(parent, solver_body(c, w, tb__joint_end_slot(w, j, 0)), solver_body(c, w, tb__joint_end_slot(w, j, 1)));
    for (j = 0; j < w->joint_count; ++j) {
        int side;
        for (side = 0; side < 2; ++side) {
            const int32_t s = solver_body(c, w, tb__joint_end_slot(w, j, side));
            if (s >= 0)
                jointed[root(parent, s)] = 1;
        }
    }
    for (i = 0; i < c->soft_patch_count; ++i) {
        const tb__soft_patch *patch = &c->soft_patches[i];
        const int32_t any = patch->a >= 0 ? patch->a : patch->b;
        if (any >= 0 && jointed[root(parent, any)] && (st = patch_rows(w, c, k, patch)) != TB_OK)
            return st;
    }
    return TB_OK;
}
