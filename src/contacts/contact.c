/* contact.c: a step's contacts. Found at the start positions (proxies,
   the broadphase's pairs, manifolds kept or collided afresh, warm starts
   matched); solved after the integrator's free motion by the soft step
   (soft_step.c); then the step's begin and end events, sleep, and the
   entries of sleeping pairs parked. The model is in docs/contacts.md. */
#include "contacts/contacts.h"
#include "joints/joints.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>


/* ---- placing shapes ------------------------------------------------------- */

void tb__place_shape(const tb__shape *s, const double x[3], const double q[4], tb__geom *g)
{
    double R[9], qs[4], off[3];
    int i;
    memset(g, 0, sizeof *g);
    g->kind = s->kind;
    g->radius = s->radius;
    memcpy(g->half, s->half, sizeof g->half);
    memcpy(g->normal, s->normal, sizeof g->normal);
    g->offset = s->offset;
    if (!x) { /* static: the pose is the world's */
        memcpy(g->pos, s->pos, sizeof g->pos);
        tb__matrix_of(s->rot, g->rot);
        return;
    }
    tb__quat_mul(q, s->rot, qs);
    tb__matrix_of(qs, g->rot);
    tb__matrix_of(q, R);
    tb__mul(R, s->pos, off);
    for (i = 0; i < 3; ++i)
        g->pos[i] = x[i] + off[i];
}

static const double *body_x(const tb_world *w, uint32_t slot)
{
    return w->y + w->off[TB__BODY_POS] + 3 * slot;
}

static const double *body_q(const tb_world *w, uint32_t slot)
{
    return w->y + w->off[TB__BODY_ROT] + 4 * slot;
}

/* ---- the solver's bodies -------------------------------------------------- */

static tb_status map_reserve(tb_world *w, tb__contacts *c)
{
    tb_status st;
    size_t i;
    if ((st = tb__reserve(w, (void **)&c->body_map, &c->body_map_cap, w->body_count + 1, sizeof(int32_t))) !=
        TB_OK)
        return st;
    if ((st = tb__reserve(w, (void **)&c->particle_map, &c->particle_map_cap, w->particle_count + 1,
                                   sizeof(int32_t))) != TB_OK)
        return st;
    for (i = 0; i < w->body_count; ++i)
        c->body_map[i] = -1;
    for (i = 0; i < w->particle_count; ++i)
        c->particle_map[i] = -1;
    c->body_count = 0;
    return TB_OK;
}

tb_status tb__contacts_solver_body(tb_world *w, tb__contacts *c, enum tb__tier tier, uint32_t slot, int32_t *out)
{
    int32_t *map = tier == TB__BODIES ? c->body_map : c->particle_map;
    tb__solver_body *b;
    tb_status st;
    if (tier == TB__PARTICLES && w->particle_inv_mass[slot] == 0) {
        *out = -1;
        return TB_OK;
    }
    if (map[slot] >= 0) {
        *out = map[slot];
        return TB_OK;
    }
    if ((st = tb__reserve(w, (void **)&c->bodies, &c->body_cap, c->body_count + 1, sizeof *b)) != TB_OK)
        return st;
    /* the start of the step; load_bodies sets the rest (no memset: reads
       of what was just zeroed wait for it) */
    b = &c->bodies[c->body_count];
    b->tier = tier;
    b->slot = slot;
    if (tier == TB__BODIES) {
        b->inv_mass = w->body_inv_mass[slot];
        memcpy(b->inv_inertia, w->body_inv_inertia + 3 * slot, sizeof b->inv_inertia);
        memcpy(b->x0, body_x(w, slot), sizeof b->x0);
        memcpy(b->q0, body_q(w, slot), sizeof b->q0);
        tb__body_velocity(w, slot, b->v0, b->w0);
        memcpy(b->p0, w->y + w->off[TB__BODY_MOM] + 3 * slot, sizeof b->p0);
        memcpy(b->l0, w->y + w->off[TB__BODY_ANG] + 3 * slot, sizeof b->l0);
    } else {
        b->inv_mass = w->particle_inv_mass[slot];
        b->inv_inertia[0] = b->inv_inertia[1] = b->inv_inertia[2] = 0;
        memcpy(b->x0, w->y + w->off[TB__PARTICLE_POS] + 3 * slot, sizeof b->x0);
        memcpy(b->v0, w->y + w->off[TB__PARTICLE_VEL] + 3 * slot, sizeof b->v0);
        b->w0[0] = b->w0[1] = b->w0[2] = 0;
        b->q0[0] = 1, b->q0[1] = b->q0[2] = b->q0[3] = 0;
    }
    map[slot] = (int32_t)c->body_count;
    *out = (int32_t)c->body_count++;
    return TB_OK;
}

/* The velocity of the point at r from solver body i at the start of the step. */
static void start_velocity(const tb__contacts *c, int32_t i, const double r[3], double v[3])
{
    if (i < 0) {
        v[0] = v[1] = v[2] = 0;
    } else {
        const tb__solver_body *b = &c->bodies[i];
        tb__cross(b->w0, r, v);
        v[0] += b->v0[0], v[1] += b->v0[1], v[2] += b->v0[2];
    }
}

/* How fast point p of entry e's side b approaches its side a along the
   normal at the start of the step (< 0: approaching), for begin events */
static double approach_of(const tb__contacts *c, const tb__entry *e, const tb__point *p)
{
    double va[3], vb[3];
    start_velocity(c, e->body_a, p->ra, va);
    start_velocity(c, e->body_b, p->rb, vb);
    return tb__dot3(vb, e->normal) - tb__dot3(va, e->normal);
}

/* ---- finding contacts ------------------------------------------------------- */

static uint64_t key_of(uint32_t key_a, uint32_t key_b)
{
    return (uint64_t)key_a << 32 | key_b;
}

/* keys[n] in key order, by bytes from the lowest (a radix sort, linear
   in n), skipping the bytes every key shares; scratch holds n as well. */
static void sort_keys(tb__key *keys, tb__key *scratch, size_t n)
{
    tb__key *const out = keys;
    int shift;
    for (shift = 0; shift < 64; shift += 8) {
        size_t count[257] = { 0 }, i;
        tb__key *swap;
        for (i = 0; i < n; ++i)
            count[(keys[i].key >> shift & 0xFF) + 1]++;
        if (n == 0 || count[(keys[0].key >> shift & 0xFF) + 1] == n)
            continue;
        for (i = 0; i < 256; ++i)
            count[i + 1] += count[i];
        for (i = 0; i < n; ++i)
            scratch[count[keys[i].key >> shift & 0xFF]++] = keys[i];
        swap = keys, keys = scratch, scratch = swap;
    }
    if (keys != out)
        memcpy(out, keys, n * sizeof *keys);
}

/* Last step's entry between the keys: a binary search among key_a's
   entries, from where they start in key order (a shape has a few; a plane
   may have thousands). */
static const tb__entry *previous_entry(const tb__contacts *c, uint32_t key_a, uint32_t key_b)
{
    const uint64_t key = key_of(key_a, key_b);
    size_t lo, hi;
    if ((size_t)key_a + 1 >= c->previous_starts_count)
        return NULL;
    lo = c->previous_starts[key_a], hi = c->previous_starts[key_a + 1];
    while (lo < hi) {
        const size_t mid = (lo + hi) / 2;
        if (c->previous_order[mid].key < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < c->previous_starts[key_a + 1] && c->previous_order[lo].key == key
               ? &c->previous[c->previous_order[lo].index]
               : NULL;
}

/* Two unit tangents with (t1, t2, n) right-handed, for a unit n: Duff et
   al.'s branch-free basis (JCGT 2017), one division and no square root,
   once per manifold each step (the cross product with the axis least
   along n takes a root, three divisions and a branch on which axis). */
static void tangents(const double n[3], double t1[3], double t2[3])
{
    const double sign = n[2] >= 0 ? 1 : -1, a = -1 / (sign + n[2]), b = n[0] * n[1] * a;
    t1[0] = 1 + sign * n[0] * n[0] * a, t1[1] = sign * b, t1[2] = -sign * n[0];
    t2[0] = b, t2[1] = sign + n[1] * n[1] * a, t2[2] = -n[1];
}

/* The key, side and solver body of a proxy. */
typedef struct side {
    uint32_t key;
    int32_t body;
    double friction, restitution, rolling;
    double core;               /* m: from its surface to its core (a sphere's centre, a
                                  capsule's segment): the radius; 0 for boxes and planes */
} side;

static tb_status side_of(tb_world *w, tb__contacts *c, uint32_t proxy, side *s)
{
    if (proxy & TB__PARTICLE_KEY) {
        const uint32_t slot = proxy & ~TB__PARTICLE_KEY;
        uint32_t gen;
        tb__ids_at(&w->particle_ids, slot, &s->key, &gen);
        s->key |= TB__PARTICLE_KEY;
        s->friction = c->settings.particle_friction;
        s->restitution = c->settings.particle_restitution;
        s->rolling = 0;
        s->core = fmax(c->settings.particle_radius, 0);
        return tb__contacts_solver_body(w, c, TB__PARTICLES, slot, &s->body);
    } else {
        const tb__shape *sh = &c->shapes[proxy];
        uint32_t gen, slot;
        tb__ids_at(&c->ids, proxy, &s->key, &gen);
        s->friction = sh->friction;
        s->restitution = sh->restitution;
        s->rolling = sh->rolling_resistance;
        s->core = sh->kind == TB__SHAPE_SPHERE || sh->kind == TB__SHAPE_CAPSULE ? sh->radius : 0;
        s->body = -1;
        if (sh->body && tb__ids_lookup(&w->body_ids, sh->body, sh->body_generation, &slot) &&
            !w->body_island[slot]) /* (a sleeping body is ground to a slow particle) */
            return tb__contacts_solver_body(w, c, TB__BODIES, slot, &s->body);
        return TB_OK;
    }
}

/* The point at from solver body i's centre at the start of the step (0
   for the static world). */
static void arm_of(const tb__contacts *c, int32_t i, const double at[3], double r[3])
{
    if (i < 0) {
        r[0] = r[1] = r[2] = 0;
    } else {
        const double *x0 = c->bodies[i].x0;
        r[0] = at[0] - x0[0], r[1] = at[1] - x0[1], r[2] = at[2] - x0[2];
    }
}

/* An entry for the manifold m between proxies pa and pb; old: last step's
   entry between them, if known (found), else looked up here. */
static tb_status add_entry(tb_world *w, tb__contacts *c, uint32_t pa, uint32_t pb, const tb__manifold *m,
                           const tb__entry *old, int found)
{
    side a, b;
    tb__entry *e;
    tb_status st;
    int k;
    if ((st = side_of(w, c, pa, &a)) != TB_OK || (st = side_of(w, c, pb, &b)) != TB_OK)
        return st;
    if (a.body < 0 && b.body < 0)
        return TB_OK;
    if ((st = tb__reserve(w, (void **)&c->entries, &c->entry_cap, c->entry_count + 1, sizeof *e)) != TB_OK)
        return st;
    /* every field set here or by collide_pair (no memset: an entry is
       about a kilobyte, and zeroing it stalls the reads that follow) */
    e = &c->entries[c->entry_count++];
    e->key_a = a.key, e->key_b = b.key;
    e->body_a = a.body, e->body_b = b.body;
    memcpy(e->normal, m->normal, sizeof e->normal);
    tangents(m->normal, e->tangent[0], e->tangent[1]);
    e->friction = sqrt(a.friction * b.friction);
    e->restitution = fmax(a.restitution, b.restitution);
    e->rolling = fmax(a.rolling, b.rolling);
    e->core[0] = a.core, e->core[1] = b.core;
    e->count = m->count;
    e->touching = e->asleep = e->cached = e->reused = 0;
    if (!found)
        old = previous_entry(c, a.key, b.key);
    e->struck = 0;
    for (k = 0; k < m->count; ++k) {
        tb__point *p = &e->point[k];
        const double *at = m->point[k].pos;
        int j;
        p->normal_impulse = p->speed = 0;
        p->active = 0;
        p->feature = m->point[k].feature;
        p->separation = -m->point[k].depth;
        memcpy(p->point, at, sizeof p->point);
        arm_of(c, e->body_a, at, p->ra);
        arm_of(c, e->body_b, at, p->rb);
        /* warm start from last step's point: the same pair of features, or
           failing that (a clipped polygon may renumber its corners) the
           nearest point within the slop */
        if (old) {
            int best = -1;
            double nearest = c->settings.slop * c->settings.slop;
            for (j = 0; j < old->count; ++j) {
                const tb__point *o = &old->point[j];
                double d2 = 0;
                int q;
                if (!o->active)
                    continue;
                if (o->feature == p->feature) {
                    best = j;
                    break;
                }
                for (q = 0; q < 3; ++q)
                    d2 += (o->point[q] - p->point[q]) * (o->point[q] - p->point[q]);
                if (d2 < nearest)
                    nearest = d2, best = j;
            }
            if (best >= 0)
                p->normal_impulse = old->point[best].normal_impulse;
        }
    }
    /* the patch's friction, into this step's contact plane */
    if (old) {
        double along = tb__dot3(old->friction_impulse, e->normal);
        for (k = 0; k < 3; ++k)
            e->friction_impulse[k] = old->friction_impulse[k] - along * e->normal[k];
        e->twist_impulse = old->twist_impulse;
        along = tb__dot3(old->rolling_impulse, e->normal);
        for (k = 0; k < 3; ++k)
            e->rolling_impulse[k] = old->rolling_impulse[k] - along * e->normal[k];
    } else {
        e->friction_impulse[0] = e->friction_impulse[1] = e->friction_impulse[2] = e->twist_impulse = 0;
        e->rolling_impulse[0] = e->rolling_impulse[1] = e->rolling_impulse[2] = 0;
    }
    return TB_OK;
}

/* Proxy k neither moves nor is moved this step: static, or asleep. */
static int inert(const tb_world *w, const tb__contacts *c, size_t k)
{
    return c->group[k] == 0xFFFFFFFFu || tb__proxy_island(w, c, k) != 0;
}

/* The entry between two shapes that sleep (or are static) as it was last
   step: touching as it was, its impulses kept for when they wake. */
static tb_status carry_over(tb_world *w, tb__contacts *c, uint32_t shape_a, uint32_t shape_b)
{
    uint32_t key_a, key_b, gen;
    const tb__entry *old;
    tb__entry *e;
    tb_status st;
    tb__ids_at(&c->ids, shape_a, &key_a, &gen);
    tb__ids_at(&c->ids, shape_b, &key_b, &gen);
    if (!(old = previous_entry(c, key_a, key_b)))
        return TB_OK;
    if ((st = tb__reserve(w, (void **)&c->entries, &c->entry_cap, c->entry_count + 1, sizeof *e)) != TB_OK)
        return st;
    e = &c->entries[c->entry_count++];
    *e = *old;
    e->body_a = e->body_b = -1; /* (last step's solver bodies mean nothing now) */
    e->asleep = 1;
    e->struck = 0;
    return TB_OK;
}

/* How far a proxy may move in a step of h: its speed and spin over the
   step, and what gravity adds, plus the slop. */
static double motion_margin(const tb_world *w, const tb__contacts *c, uint32_t proxy, double h)
{
    const double g = tb__norm3(w->gravity) * h * h;
    if (proxy & TB__PARTICLE_KEY) {
        const double *v = w->y + w->off[TB__PARTICLE_VEL] + 3 * (proxy & ~TB__PARTICLE_KEY);
        return h * tb__norm3(v) + g + c->settings.slop;
    } else {
        const tb__shape *s = &c->shapes[proxy];
        uint32_t slot;
        double v[3], wv[3];
        if (!s->body || !tb__ids_lookup(&w->body_ids, s->body, s->body_generation, &slot))
            return c->settings.slop;
        tb__body_velocity(w, slot, v, wv);
        return h * (tb__norm3(v) + tb__norm3(wv) * s->reach) + g + c->settings.slop;
    }
}

/* ---- reusing a manifold ------------------------------------------------------ */

/* A pair whose relative pose moved less than this since its shapes last
   collided keeps that manifold (its points ride on both shapes, their
   separations updated to first order): a resting stack costs no
   narrowphase. A tenth of the slop, so what goes stale (a clipped corner
   that slid, the second order of a turn) stays well below what the
   solver already leaves alone. */
#define TB__REUSE_SLOP_FRACTION 0.1

/* b's frame in a's: rot = Ra^T Rb, pos = Ra^T (xb - xa). */
static void relative_pose(const tb__geom *a, const tb__geom *b, double rot[9], double pos[3])
{
    int i, j;
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j)
            rot[3 * i + j] = a->rot[i] * b->rot[j] + a->rot[3 + i] * b->rot[3 + j] + a->rot[6 + i] * b->rot[6 + j];
        pos[i] = a->rot[i] * (b->pos[0] - a->pos[0]) + a->rot[3 + i] * (b->pos[1] - a->pos[1]) +
                 a->rot[6 + i] * (b->pos[2] - a->pos[2]);
    }
}

/* Shape frame g's coordinates of the world point p, and back. */
static void to_shape(const tb__geom *g, const double p[3], double out[3])
{
    int i;
    for (i = 0; i < 3; ++i)
        out[i] = g->rot[i] * (p[0] - g->pos[0]) + g->rot[3 + i] * (p[1] - g->pos[1]) + g->rot[6 + i] * (p[2] - g->pos[2]);
}

static void from_shape(const tb__geom *g, const double l[3], double out[3])
{
    int i;
    for (i = 0; i < 3; ++i)
        out[i] = g->pos[i] + g->rot[3 * i] * l[0] + g->rot[3 * i + 1] * l[1] + g->rot[3 * i + 2] * l[2];
}

/* For a round shape (sphere, capsule), how far its core lies from the
   midway point of a contact of separation sep, along the normal (away from
   the other shape): r + sep / 2; 0 for others. A manifold kept from step to
   step carries the core point on a round shape, not a material point of
   its surface: a rolling ball's contact stays under its centre (a carried
   surface point would roll up its side, as far as the reuse allows, and
   the press would turn the ball:
   incline_slides_holds_and_rolls_to_closed_forms). */
static double round_reach(const tb__geom *g, double sep)
{
    return g->kind == TB__SHAPE_SPHERE || g->kind == TB__SHAPE_CAPSULE ? g->radius + 0.5 * sep : 0;
}

/* Last step's manifold old between shapes a and b (b: proxy pb), moved to
   their poses now into m, if they moved little enough since it was found;
   returns whether it was. */
static int reuse(const tb__contacts *c, const tb__geom *a, const tb__geom *b, uint32_t pb, const tb__entry *old,
                 tb__manifold *m)
{
    const double near = TB__REUSE_SLOP_FRACTION * c->settings.slop;
    const int round_a = round_reach(a, 0) > 0, round_b = round_reach(b, 0) > 0;
    double rot[9], pos[3], moved = 0, trace = 0, turn;
    int i, k;
    relative_pose(a, b, rot, pos);
    for (i = 0; i < 3; ++i)
        moved += (pos[i] - old->cache_pos[i]) * (pos[i] - old->cache_pos[i]);
    for (i = 0; i < 9; ++i)
        trace += rot[i] * old->cache_rot[i];
    /* 3 - trace = 2 (1 - cos angle), about angle^2; b's points turn by
       at most its reach times the angle */
    turn = c->shapes[pb].reach * c->shapes[pb].reach * (3 - trace);
    if (!(moved < near * near && turn < near * near))
        return 0;
    for (i = 0; i < 3; ++i)
        m->normal[i] = a->rot[3 * i] * old->cache_normal[0] + a->rot[3 * i + 1] * old->cache_normal[1] +
                       a->rot[3 * i + 2] * old->cache_normal[2];
    m->count = old->count;
    for (k = 0; k < old->count; ++k) {
        const tb__point *o = &old->point[k];
        double on_a[3], on_b[3], gap = 0;
        from_shape(a, o->local_a, on_a);
        from_shape(b, o->local_b, on_b);
        /* a round side keeps its core point (collide_pair): its surface is
           r from it along the normal now, wherever it rolled */
        for (i = 0; i < 3; ++i) {
            on_a[i] += round_reach(a, o->separation0) * m->normal[i];
            on_b[i] -= round_reach(b, o->separation0) * m->normal[i];
        }
        for (i = 0; i < 3; ++i)
            gap += (on_b[i] - on_a[i]) * m->normal[i];
        /* midway, across the normal where a round side says: a point
           carried on the other side stays where it touched while the round
           one rolls or slides on */
        for (i = 0; i < 3; ++i)
            m->point[k].pos[i] = round_b && !round_a   ? on_b[i] - 0.5 * gap * m->normal[i]
                                 : round_a && !round_b ? on_a[i] + 0.5 * gap * m->normal[i]
                                                       : 0.5 * (on_a[i] + on_b[i]);
        m->point[k].depth = -(o->separation0 + gap);
        m->point[k].feature = o->feature;
    }
    return 1;
}

/* The manifold of shapes a and b (proxies pa and pb) as an entry: last
   step's moved along if it can be (particles are always collided: a point
   costs little), else collided afresh. */
static tb_status collide_pair(tb_world *w, tb__contacts *c, const tb__geom *a, const tb__geom *b, uint32_t pa,
                              uint32_t pb, double margin)
{
    const size_t before = c->entry_count;
    const int shapes = !((pa | pb) & TB__PARTICLE_KEY);
    const tb__entry *old = NULL;
    tb__manifold m;
    tb__entry *e;
    tb_status st;
    int i, k, kept = 0;
    if (shapes) {
        uint32_t key_a, key_b, gen;
        tb__ids_at(&c->ids, pa, &key_a, &gen);
        tb__ids_at(&c->ids, pb, &key_b, &gen);
        old = previous_entry(c, key_a, key_b);
        kept = old && old->cached && reuse(c, a, b, pb, old, &m);
    }
    if (!kept && !tb__collide(a, b, margin, TB__FACE_TOLERANCE * c->settings.slop, &m))
        return TB_OK;
    if ((st = add_entry(w, c, pa, pb, &m, old, shapes)) != TB_OK || c->entry_count == before)
        return st;
    e = &c->entries[before];
    e->cached = shapes;
    e->reused = kept;
    if (!e->cached)
        return TB_OK;
    if (kept) { /* the reference stays the last collision */
        memcpy(e->cache_rot, old->cache_rot, sizeof e->cache_rot);
        memcpy(e->cache_pos, old->cache_pos, sizeof e->cache_pos);
        memcpy(e->cache_normal, old->cache_normal, sizeof e->cache_normal);
        for (k = 0; k < e->count; ++k) {
            memcpy(e->point[k].local_a, old->point[k].local_a, sizeof e->point[k].local_a);
            memcpy(e->point[k].local_b, old->point[k].local_b, sizeof e->point[k].local_b);
            e->point[k].separation0 = old->point[k].separation0;
        }
        return TB_OK;
    }
    relative_pose(a, b, e->cache_rot, e->cache_pos);
    for (k = 0; k < 3; ++k)
        e->cache_normal[k] = a->rot[k] * m.normal[0] + a->rot[3 + k] * m.normal[1] + a->rot[6 + k] * m.normal[2];
    for (k = 0; k < m.count; ++k) {
        double core_a[3], core_b[3];
        const double sep = -m.point[k].depth;
        for (i = 0; i < 3; ++i) {
            core_a[i] = m.point[k].pos[i] - round_reach(a, sep) * m.normal[i];
            core_b[i] = m.point[k].pos[i] + round_reach(b, sep) * m.normal[i];
        }
        to_shape(a, core_a, e->point[k].local_a);
        to_shape(b, core_b, e->point[k].local_b);
        e->point[k].separation0 = sep;
    }
    return TB_OK;
}


/* Where each key_a's entries start in order[n] (keys run to the ids
   handed out), for previous_entry. */
static tb_status index_order(tb_world *w, const tb__contacts *c, const tb__key *order, size_t n, uint32_t **starts,
                             size_t *cap, size_t *starts_count)
{
    const size_t count = (size_t)c->ids.used + 2;
    size_t i;
    tb_status st;
    if (n == 0) { /* (previous_entry finds nothing without a pass over the keys) */
        *starts_count = 0;
        return TB_OK;
    }
    if ((st = tb__reserve(w, (void **)starts, cap, count, sizeof **starts)) != TB_OK)
        return st;
    memset(*starts, 0, count * sizeof **starts);
    for (i = 0; i < n; ++i)
        (*starts)[(order[i].key >> 32) + 1]++;
    for (i = 0; i + 1 < count; ++i)
        (*starts)[i + 1] += (*starts)[i];
    *starts_count = count;
    return TB_OK;
}

/* ... of this step's entries, for the next step */
static tb_status index_keys(tb_world *w, tb__contacts *c)
{
    return index_order(w, c, c->order, c->entry_count, &c->starts, &c->starts_cap, &c->starts_count);
}

/* ---- parked entries ---------------------------------------------------------

   A pair whose sides both sleep (or are static) is left as it was: not
   collided, not solved, its impulses kept for when it wakes. Such an
   entry is moved out of the step's entries into c->parked once, after the
   step its island fell asleep in, and stays there untouched while the
   island sleeps: a sleeping pile costs no narrowphase and no copy per
   pair a step (bench_contacts' asleep lines). It comes back among the
   previous entries when a side wakes, before the narrowphase looks for it,
   so the woken pair starts warm and its events are those of a pair that
   was there all along (test_contacts_sleep). What a parked entry holds is
   what carrying it over every step would hold (carry_over), and the state
   hash walks it in its found place (TB__FOUND_PLANE): the bits of every
   step are those of carrying. */

static int active_points(const tb__entry *e)
{
    int k, n = 0;
    for (k = 0; k < e->count; ++k)
        n += e->point[k].active;
    return n;
}

/* Park every entry of this step that was carried over (its sides both
   sleep or are static), keeping c->parked in found order, and index the
   entries left for the next step. The entries of an island that fell
   asleep in this step are left as they are, and the next step carries
   them over (c->unparked), to be parked after it: the state after each
   step is the one carrying gives, to the bit (the step an island falls
   asleep in, its entries are still this step's, not yet carried). Out of
   memory: nothing is parked, and the next step carries over instead. */
static void park(tb_world *w, tb__contacts *c, double h)
{
    uint32_t *index = c->park_index;
    size_t i, n = 0, kept = 0, from, to;
    c->unparked = 0;
    c->parked_h = h;
    c->parked_sleeping = w->body_sleeping;
    if (!w->body_sleeping)
        return;
    for (i = 0; i < c->entry_count; ++i) {
        const tb__entry *e = &c->entries[i];
        index[i] = UINT32_MAX;
        if (e->asleep)
            index[i] = 0, ++n;
        else if (tb__key_still(w, c, e->key_a) && tb__key_still(w, c, e->key_b))
            c->unparked = 1;
    }
    if (n == 0)
        return;
    if (tb__reserve(w, (void **)&c->parked, &c->parked_cap, c->parked_count + n, sizeof *c->parked) != TB_OK) {
        c->unparked = 1;
        return;
    }
    /* merged from the back: both lists are in found order */
    from = c->parked_count, to = c->parked_count + n, i = c->entry_count;
    while (to > from) { /* (then the new ones are all placed) */
        tb__entry *e;
        while (index[i - 1] == UINT32_MAX)
            --i;
        if (from > 0 && c->parked[from - 1].found > c->entries[i - 1].found) {
            c->parked[--to] = c->parked[--from];
            continue;
        }
        e = &c->parked[--to];
        *e = c->entries[--i];
        e->body_a = e->body_b = -1; /* as carry_over leaves it */
        e->asleep = 1;
        e->struck = 0;
        c->parked_points += (size_t)active_points(e);
    }
    c->parked_count += n;
    /* the rest moved down, the key order kept with their new places */
    for (i = 0; i < c->entry_count; ++i)
        if (index[i] == UINT32_MAX) {
            index[i] = (uint32_t)kept;
            if (kept != i)
                c->entries[kept] = c->entries[i];
            ++kept;
        } else {
            index[i] = UINT32_MAX;
        }
    for (i = 0, n = 0; i < c->entry_count; ++i)
        if (index[c->order[i].index] != UINT32_MAX) {
            c->order[n].key = c->order[i].key;
            c->order[n++].index = index[c->order[i].index];
        }
    c->entry_count = kept;
    if (index_keys(w, c) != TB_OK)
        c->starts_count = 0; /* out of memory: the next step starts cold */
}

/* Before the narrowphase: the parked entries with a side awake again
   (every one when the step changed, as the bounds they were found in
   did) back among the previous entries; then those with both sides still
   are found again by the broadphase and carried over (carry_over). */
static tb_status unpark(tb_world *w, tb__contacts *c, double h)
{
    const int all = h != c->parked_h;
    size_t i, kept = 0, n = c->previous_count;
    tb_status st;
    if (!c->parked_count || (!all && w->body_sleeping == c->parked_sleeping))
        return TB_OK;
    if ((st = tb__reserve(w, (void **)&c->previous, &c->previous_cap, n + c->parked_count, sizeof *c->previous)) !=
            TB_OK ||
        (st = tb__reserve(w, (void **)&c->previous_order, &c->previous_order_cap, n + c->parked_count,
                          sizeof *c->previous_order)) != TB_OK ||
        (st = tb__reserve(w, (void **)&c->order_scratch, &c->order_scratch_cap, n + c->parked_count,
                          sizeof *c->order_scratch)) != TB_OK)
        return st;
    for (i = 0; i < c->parked_count; ++i) {
        const tb__entry *e = &c->parked[i];
        if (all || !tb__key_still(w, c, e->key_a) || !tb__key_still(w, c, e->key_b)) {
            c->parked_points -= (size_t)active_points(e);
            c->previous[n] = *e;
            c->previous_order[n].key = key_of(e->key_a, e->key_b);
            c->previous_order[n].index = (uint32_t)n;
            ++n;
        } else {
            if (kept != i)
                c->parked[kept] = *e;
            ++kept;
        }
    }
    c->parked_count = kept;
    c->parked_h = h;
    c->parked_sleeping = w->body_sleeping;
    if (n == c->previous_count)
        return TB_OK;
    c->previous_count = n;
    c->unparked = 1;
    sort_keys(c->previous_order, c->order_scratch, n);
    return index_order(w, c, c->previous_order, n, &c->previous_starts, &c->previous_starts_cap,
                       &c->previous_starts_count);
}

/* Planes against every proxy whose box reaches them. (Before the pairs:
   planes are usually the first shapes, so the entries then come out in
   key order and need no sort.) */
static tb_status collide_planes(tb_world *w, tb__contacts *c)
{
    size_t i, k, before, planes = 0;
    tb_status st;
    for (i = 0; i < c->shape_count && planes < c->planes; ++i) {
        const tb__shape *s = &c->shapes[i];
        tb__geom plane;
        if (s->kind != TB__SHAPE_PLANE)
            continue;
        ++planes;
        tb__place_shape(s, NULL, NULL, &plane);
        for (k = 0; k < c->proxy_count; ++k) {
            const double *lo = c->lo + 3 * k, *hi = c->hi + 3 * k;
            double nearest = 0;
            int j;
            /* (a sleeping proxy's pair is parked: first, as the cheapest) */
            if (c->still[k] && !c->unparked &&
                (c->still[k] == UINT32_MAX || w->body_island[c->owner[k] - 1] == c->still[k]))
                continue;
            if (!(s->category & c->mask[k]) || !(c->category[k] & s->mask) || c->group[k] == 0xFFFFFFFFu)
                continue;
            for (j = 0; j < 3; ++j) /* the box corner deepest along -n */
                nearest += s->normal[j] * (s->normal[j] > 0 ? lo[j] : hi[j]);
            if (nearest > s->offset)
                continue;
            before = c->entry_count;
            /* a still pair: parked, unless it came back this step */
            if (inert(w, c, k))
                st = c->unparked ? carry_over(w, c, (uint32_t)i, c->proxy[k]) : TB_OK;
            else
                st = collide_pair(w, c, &plane, &c->geoms[k], (uint32_t)i, c->proxy[k], c->margin[k]);
            if (st != TB_OK)
                return st;
            if (c->entry_count > before)
                c->entries[before].found = TB__FOUND_PLANE(i, k);
        }
    }
    return TB_OK;
}

/* Proxy k for shape i: placed, its filter, margin and bounds; kept as it
   is when its body sleeps in the island it slept in when it was made
   (still). */
static void make_proxy(tb_world *w, tb__contacts *c, size_t k, uint32_t i, double h)
{
    const tb__shape *s = &c->shapes[i];
    tb__geom *g = &c->geoms[k];
    uint32_t slot;
    int j;
    if (s->body && tb__ids_lookup(&w->body_ids, s->body, s->body_generation, &slot)) {
        const uint32_t island = w->body_island[slot];
        if (island && c->still[k] == island && c->owner[k] == slot + 1 && c->proxy[k] == i)
            return;
        tb__place_shape(s, body_x(w, slot), body_q(w, slot), g);
        c->owner[k] = slot + 1;
        c->still[k] = island;
    } else {
        tb__place_shape(s, NULL, NULL, g);
        c->owner[k] = 0;
        c->still[k] = UINT32_MAX; /* static: still, but never kept */
    }
    c->proxy[k] = i;
    c->category[k] = s->category;
    c->mask[k] = s->mask;
    c->group[k] = s->body ? s->body : 0xFFFFFFFFu;
    c->margin[k] = motion_margin(w, c, c->proxy[k], h);
    tb__geom_bounds(g, c->lo + 3 * k, c->hi + 3 * k);
    for (j = 0; j < 3; ++j) {
        c->lo[3 * k + j] -= c->margin[k];
        c->hi[3 * k + j] += c->margin[k];
    }
}

tb_status tb__contacts_prepare(tb_world *w, double h)
{
    tb__contacts *c = w->contacts;
    const int particles = c->settings.particle_radius >= 0;
    const size_t bodies_shapes = c->shape_count - c->planes;
    const size_t n = bodies_shapes + (particles ? w->particle_count : 0);
    size_t i, k, cap;
    int carry, same, apart;
    tb__entry *swap;
    tb__key *swap_order;
    uint32_t *swap_starts;
    tb_status st;
    /* last step's entries become the previous ones (for warm starting and
       events), unless that step never got to solve them */
    if (c->solved) {
        swap = c->previous, c->previous = c->entries, c->entries = swap;
        cap = c->previous_cap, c->previous_cap = c->entry_cap, c->entry_cap = cap;
        swap_order = c->previous_order, c->previous_order = c->order, c->order = swap_order;
        cap = c->previous_order_cap, c->previous_order_cap = c->order_cap, c->order_cap = cap;
        swap_starts = c->previous_starts, c->previous_starts = c->starts, c->starts = swap_starts;
        cap = c->previous_starts_cap, c->previous_starts_cap = c->starts_cap, c->starts_cap = cap;
        c->previous_starts_count = c->starts_count;
        c->previous_count = c->entry_count;
    }
    c->entry_count = 0;
    c->prepared = c->solved = 0;
    if ((st = map_reserve(w, c)) != TB_OK)
        return st;
    /* (grown only when they must: the proxies kept from last step, the
       sleeping ones, are copied along) */
    if (n > c->proxy_cap) {
        size_t old = c->proxy_cap, want = n;
        void **arrays[10];
        size_t sizes[10] = { 3 * sizeof(double), 3 * sizeof(double), sizeof(uint32_t), sizeof(uint32_t),
                             sizeof(uint32_t), sizeof(uint32_t), sizeof(double), sizeof(tb__geom), sizeof(uint32_t),
                             sizeof(uint32_t) };
        size_t new_cap = old ? old : 16;
        while (new_cap < want)
            new_cap *= 2;
        arrays[0] = (void **)&c->lo, arrays[1] = (void **)&c->hi, arrays[2] = (void **)&c->category;
        arrays[3] = (void **)&c->mask, arrays[4] = (void **)&c->group, arrays[5] = (void **)&c->proxy;
        arrays[6] = (void **)&c->margin, arrays[7] = (void **)&c->geoms, arrays[8] = (void **)&c->owner;
        arrays[9] = (void **)&c->still;
        if ((st = tb__grow(w, arrays, sizes, 10, c->proxy_count, old, new_cap)) != TB_OK)
            return st;
        for (k = old; k < new_cap; ++k)
            c->still[k] = 0;
        c->proxy_cap = new_cap;
    }
    /* proxies: every shape but planes, then the particles. A shape whose
       body sleeps in the island it slept in when its proxy was last made
       (still) keeps its geom, bounds and margin: its pose has not changed,
       nor its speed (0), the step or the gravity (a change of either wakes
       every island, and the step is compared), so they would come out
       the same bits (test_snapshot.contact_scene_hash_is_recorded) */
    if (h != c->still_h)
        for (k = 0; k < c->proxy_count; ++k)
            c->still[k] = 0;
    c->still_h = h;
    /* With no shape added or removed since, the proxies are last step's
       shapes in last step's places, and one whose body (owner) still sleeps
       under its tag is kept without a look at its shape */
    same = c->proxy_version == c->shape_version;
    c->proxy_version = c->shape_version;
    if (same) {
        for (k = 0; k < c->shape_proxies; ++k) {
            const uint32_t tag = c->still[k], owner = c->owner[k];
            if (!(tag && tag != UINT32_MAX && owner && owner <= w->body_count && w->body_island[owner - 1] == tag))
                make_proxy(w, c, k, c->proxy[k], h);
        }
        c->proxy_count = c->shape_proxies;
    } else {
        for (i = 0, c->proxy_count = 0; i < c->shape_count; ++i)
            if (c->shapes[i].kind != TB__SHAPE_PLANE)
                make_proxy(w, c, c->proxy_count++, (uint32_t)i, h);
    }
    c->shape_proxies = c->proxy_count;
    if (particles)
        for (i = 0; i < w->particle_count; ++i) {
            tb__geom *g;
            int j;
            k = c->proxy_count++;
            g = &c->geoms[k];
            memset(g, 0, sizeof *g);
            g->kind = TB__SHAPE_SPHERE;
            g->radius = c->settings.particle_radius;
            memcpy(g->pos, w->y + w->off[TB__PARTICLE_POS] + 3 * i, sizeof g->pos);
            g->rot[0] = g->rot[4] = g->rot[8] = 1;
            c->proxy[k] = (uint32_t)i | TB__PARTICLE_KEY;
            c->owner[k] = 0;
            c->category[k] = 0xFFFFFFFFu;
            c->mask[k] = 0xFFFFFFFFu;
            c->group[k] = 0xFFFFFFFEu; /* particles never meet each other */
            c->still[k] = 0;
            c->margin[k] = motion_margin(w, c, c->proxy[k], h);
            tb__geom_bounds(g, c->lo + 3 * k, c->hi + 3 * k);
            for (j = 0; j < 3; ++j) {
                c->lo[3 * k + j] -= c->margin[k];
                c->hi[3 * k + j] += c->margin[k];
            }
        }
    /* The broadphase leaves out the pairs of two still proxies (sleeping or
       static), whose entries are parked, unless the step carries such pairs
       over (some came back from the parked ones: unpark), or an awake
       proxy reaches a sleeping one: then the waking below, which goes pair
       by pair, and the woken pairs' collisions need every pair, and it
       runs again for them (test_contacts_sleep.islands_wake_together) */
    carry = c->unparked || (c->parked_count && h != c->parked_h);
    if ((st = tb__sap_moving_pairs(w, &c->sap, c->proxy_count, c->lo, c->hi, c->category, c->mask, c->group,
                                   carry ? NULL : c->still, &c->pairs, &c->pair_count, &c->pair_cap)) != TB_OK)
        return st;
    if (!carry && tb__sleep_wakes(w, c) &&
        (st = tb__sap_pairs(w, &c->sap, c->proxy_count, c->lo, c->hi, c->category, c->mask, c->group, &c->pairs,
                            &c->pair_count, &c->pair_cap)) != TB_OK)
        return st;
    if ((st = tb__sleep_prepare(w, c)) != TB_OK || (st = unpark(w, c, h)) != TB_OK ||
        (st = collide_planes(w, c)) != TB_OK || (st = tb__joints_apart_prepare(w)) != TB_OK)
        return st;
    apart = w->joint_count > 0;
    for (i = 0; i < c->pair_count; ++i) {
        const uint32_t a = c->pairs[i].a, b = c->pairs[i].b;
        const size_t before = c->entry_count;
        if ((c->proxy[a] & TB__PARTICLE_KEY) && (c->proxy[b] & TB__PARTICLE_KEY))
            continue;
        if (apart && !(c->proxy[a] & TB__PARTICLE_KEY) && !(c->proxy[b] & TB__PARTICLE_KEY) &&
            tb__joints_apart(w, c->group[a], c->group[b]))
            continue; /* bodies a joint holds pass through each other */
        if (inert(w, c, a) && inert(w, c, b))
            st = c->unparked ? carry_over(w, c, c->proxy[a], c->proxy[b]) : TB_OK;
        else
            st = collide_pair(w, c, &c->geoms[a], &c->geoms[b], c->proxy[a], c->proxy[b],
                              c->margin[a] + c->margin[b]);
        if (st != TB_OK)
            return st;
        if (c->entry_count > before)
            c->entries[before].found = TB__FOUND_PAIR(a, b);
    }
    /* the entries in key order: for finding them next step, for events, and
       for a solve order that does not depend on how the broadphase found them */
    if ((st = tb__reserve(w, (void **)&c->order, &c->order_cap, c->entry_count + 1, sizeof *c->order)) !=
            TB_OK ||
        (st = tb__reserve(w, (void **)&c->order_scratch, &c->order_scratch_cap, c->entry_count + 1,
                                   sizeof *c->order_scratch)) != TB_OK)
        return st;
    for (i = 0, k = 0; i < c->entry_count; ++i) {
        c->order[i].key = key_of(c->entries[i].key_a, c->entries[i].key_b);
        c->order[i].index = (uint32_t)i;
        k += i > 0 && c->order[i].key < c->order[i - 1].key;
    }
    if (k) /* (out of order: shapes were removed and their ids reused, or a plane came late) */
        sort_keys(c->order, c->order_scratch, c->entry_count);
    if ((st = index_keys(w, c)) != TB_OK)
        return st;
    /* the bodies jointed to those in contact (soft_joints.c) */
    if ((st = tb__soft_joints_prepare(w, c)) != TB_OK)
        return st;
    /* room to park this step's entries after the solve */
    if ((st = tb__reserve(w, (void **)&c->park_index, &c->park_index_cap, c->entry_count + 1,
                          sizeof *c->park_index)) != TB_OK)
        return st;
    c->prepared = 1;
    return TB_OK;
}

/* ---- solving ---------------------------------------------------------------- */

/* Where the point at r from solver body i is at the end of the step (its
   position and turn, to first order in the turn; static: the contact point,
   where it was found), for events. */
static void anchor(const tb__contacts *c, int32_t i, const double fixed[3], const double r[3], double out[3])
{
    if (i < 0) {
        memcpy(out, fixed, 3 * sizeof(double));
    } else {
        const tb__solver_body *b = &c->bodies[i];
        double turn[3];
        tb__cross(b->turn, r, turn);
        out[0] = b->x[0] + r[0] + turn[0];
        out[1] = b->x[1] + r[1] + turn[1];
        out[2] = b->x[2] + r[2] + turn[2];
    }
}

/* Bodies where the free motion left them, when the soft step could not
   run (out of memory): their positions and turns over the step, for the
   events' points. */
static void free_motion_stands(tb_world *w, tb__contacts *c)
{
    size_t i;
    for (i = 0; i < c->body_count; ++i) {
        tb__solver_body *b = &c->bodies[i];
        int k;
        if (b->tier == TB__BODIES) {
            const double q0c[4] = { b->q0[0], -b->q0[1], -b->q0[2], -b->q0[3] };
            double dq[4];
            memcpy(b->x, body_x(w, b->slot), sizeof b->x);
            /* the free motion's turn, q q0^-1 = (cos, sin n) -> 2 sin n */
            tb__quat_mul(body_q(w, b->slot), q0c, dq);
            for (k = 0; k < 3; ++k)
                b->turn[k] = (dq[0] < 0 ? -2 : 2) * dq[k + 1];
        } else {
            memcpy(b->x, w->y + w->off[TB__PARTICLE_POS] + 3 * b->slot, sizeof b->x);
            memset(b->turn, 0, sizeof b->turn);
        }
    }
}

/* ---- events ------------------------------------------------------------------ */

/* A zeroed event of `type` between the keys, appended to the list. */
static tb_status push_event(tb_world *w, tb__contacts *c, tb_contact_event_type type, const tb__entry *e,
                            tb_contact_event **out)
{
    tb_status st = tb__reserve(w, (void **)&c->events, &c->event_cap, c->event_count + 1, sizeof **out);
    if (st != TB_OK)
        return st;
    *out = &c->events[c->event_count++];
    memset(*out, 0, sizeof **out);
    (*out)->type = type;
    (*out)->a.index1 = e->key_a;
    (*out)->b.index1 = e->key_b;
    return TB_OK;
}


/* Begin and end events: entries touching now against last step's, both
   walked in key order. */
static tb_status make_events(tb_world *w, tb__contacts *c)
{
    size_t i, j = 0;
    tb_status st;
    c->event_count = 0;
    c->touching_points = c->parked_points;
    for (i = 0; i < c->entry_count; ++i) {
        tb__entry *e = &c->entries[i];
        int k;
        e->touching = 0;
        for (k = 0; k < e->count; ++k)
            if (e->point[k].active) {
                e->touching = 1;
                c->touching_points++;
            }
    }
    for (i = 0; i <= c->entry_count; ++i) {
        const uint64_t key = i < c->entry_count ? c->order[i].key : UINT64_MAX;
        const tb__entry *e = i < c->entry_count ? &c->entries[c->order[i].index] : NULL;
        int was = 0;
        while (j < c->previous_count && c->previous_order[j].key < key) { /* gone: ended if it touched */
            const tb__entry *old = &c->previous[c->previous_order[j++].index];
            tb_contact_event *ev;
            if (old->touching && (st = push_event(w, c, TB_CONTACT_END, old, &ev)) != TB_OK)
                return st;
        }
        if (!e)
            break;
        if (j < c->previous_count && c->previous_order[j].key == key)
            was = c->previous[c->previous_order[j++].index].touching;
        if (e->touching != was) {
            tb_contact_event *ev;
            int k;
            if ((st = push_event(w, c, e->touching ? TB_CONTACT_BEGIN : TB_CONTACT_END, e, &ev)) != TB_OK)
                return st;
            memcpy(ev->normal, e->normal, sizeof ev->normal);
            for (k = 0; k < e->count; ++k) {
                const tb__point *p = &e->point[k];
                if (!p->active)
                    continue;
                ev->speed = fmax(ev->speed, p->speed > 0 ? p->speed : fmax(0, -approach_of(c, e, p)));
                anchor(c, e->body_a, p->point, p->ra, ev->point);
            }
        }
    }
    /* ids: index1 to full ids (generations), particles apart */
    for (i = 0; i < c->event_count; ++i) {
        tb_contact_event *ev = &c->events[i];
        const uint32_t ka = ev->a.index1, kb = ev->b.index1;
        ev->a.generation = c->ids.generation[ka - 1];
        if (kb & TB__PARTICLE_KEY) {
            ev->particle.index1 = kb & ~TB__PARTICLE_KEY;
            ev->particle.generation = w->particle_ids.generation[ev->particle.index1 - 1];
            ev->b.index1 = 0;
        } else if (kb) {
            ev->b.generation = c->ids.generation[kb - 1];
        }
    }
    return TB_OK;
}

double tb__contacts_energy(const tb_world *w)
{
    const tb__contacts *c = w->contacts;
    const double *g = w->gravity;
    tb_energy e = { 0, 0, 0, 0, 0, 0 };
    size_t i;
    int particles = 0;
    if (!c || !(c->prepared || c->solved)) /* the step's bodies, before or after its solve */
        return 0;
    for (i = 0; i < c->body_count; ++i) {
        const tb__solver_body *b = &c->bodies[i];
        if (b->tier == TB__BODIES) {
            tb__body_energy_at(w, w->y, b->slot, &e);
        } else {
            const double *x = w->y + w->off[TB__PARTICLE_POS] + 3 * b->slot;
            const double *v = w->y + w->off[TB__PARTICLE_VEL] + 3 * b->slot, m = w->particle_mass[b->slot];
            e.kinetic += 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            e.gravity -= m * (g[0] * x[0] + g[1] * x[1] + g[2] * x[2]);
            particles = 1;
        }
    }
    if (particles && w->spring_count)
        e.spring = tb_world_energy(w).spring;
    return e.kinetic + e.rotational + e.gravity + e.spring;
}

void tb__contacts_solve(tb_world *w, double h)
{
    tb__contacts *c = w->contacts;
    if (!c->prepared)
        return;
    tb__sleep_restore(w, c);
    /* the soft step (soft_step.c); out of memory, the free motion stands */
    if (tb__soft_step(w, c, h) != TB_OK) {
        free_motion_stands(w, c);
        c->soft_row_count = 0;
    }
    if (make_events(w, c) != TB_OK)
        c->event_count = 0; /* out of memory for events: the step itself stands */
    tb__sleep_update(w, c, h);
    park(w, c, h);
    c->prepared = 0;
    c->solved = 1;
}
