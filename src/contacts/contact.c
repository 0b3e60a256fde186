/* contact.c: a step's contacts. Found at the start positions (proxies,
   the broadphase's pairs, manifolds kept or collided afresh, warm starts
   matched, batches coloured); solved after the integrator's free motion
   (each lane's targets and levers, the solves of cold_start.c, the
   sweeps of contact_lanes.c, the bounce, the position pass); then stored,
   with the step's begin and end events. The model is in docs/contacts.md. */
#include "contacts/contacts.h"

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

/* The solver body of a body or particle slot, made on first use; -1 for
   static things, pinned particles included. */
static tb_status solver_body(tb_world *w, tb__contacts *c, enum tb__tier tier, uint32_t slot, int32_t *out)
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

/* The sweeps' arrays for every solver body and the static world. */
static tb_status reserve_motion(tb_world *w, tb__contacts *c)
{
    const size_t need = c->body_count + 1;
    size_t cap = c->motion_cap;
    double *block;
    if (need <= cap)
        return TB_OK;
    while (cap < need)
        cap = cap ? 2 * cap : 64;
    /* one block for the three arrays, its rows on cache lines (the sweeps
       move whole rows); what they held is not needed again */
    block = tb__alloc(w, NULL, 0, TB__MOTION_BYTES(cap));
    if (!block)
        return tb__fail(w, TB_ERR_MEMORY, "out of memory for the contact solver");
    tb__alloc(w, c->motion_block, TB__MOTION_BYTES(c->motion_cap), 0);
    c->motion_block = block;
    block += (64 - (uintptr_t)block % 64) % 64 / sizeof *block;
    c->velocity = block;
    c->motion = block + TB__MOTION * cap;
    c->momenta = block + 2 * TB__MOTION * cap;
    c->motion_cap = cap;
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

/* How point p of entry e's side b moves against its side a at the start
   of the step. */
static void slip_velocity(const tb__contacts *c, const tb__entry *e, const tb__point *p, double slip[3])
{
    double va[3];
    int i;
    start_velocity(c, e->body_a, p->ra, va);
    start_velocity(c, e->body_b, p->rb, slip);
    for (i = 0; i < 3; ++i)
        slip[i] -= va[i];
}

/* ... its speed, in any direction (a new contact at rest is slower than
   the sleep speed) */
static double slip_of(const tb__contacts *c, const tb__entry *e, const tb__point *p)
{
    double slip[3];
    slip_velocity(c, e, p, slip);
    return tb__norm3(slip);
}

/* ... along the normal (< 0: approaching), for impacts and begin events */
static double approach_of(const tb__contacts *c, const tb__entry *e, const tb__point *p)
{
    double slip[3];
    slip_velocity(c, e, p, slip);
    return tb__dot3(slip, e->normal);
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
        return solver_body(w, c, TB__PARTICLES, slot, &s->body);
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
            return solver_body(w, c, TB__BODIES, slot, &s->body);
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
    e->touching = e->asleep = e->colour = e->cached = e->reused = 0;
    if (!found)
        old = previous_entry(c, a.key, b.key);
    e->struck = 0;
    e->struck_before = old && old->struck;
    for (k = 0; k < m->count; ++k) {
        tb__point *p = &e->point[k];
        const double *at = m->point[k].pos;
        int j;
        p->normal_impulse = p->speed = p->predicted = 0;
        p->active = p->matched = 0;
        p->friction_impulse[0] = p->friction_impulse[1] = p->friction_impulse[2] = 0;
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
            if (best >= 0) {
                p->normal_impulse = old->point[best].normal_impulse;
                memcpy(p->friction_impulse, old->point[best].friction_impulse, sizeof p->friction_impulse);
                p->matched = 1;
            }
        }
    }
    /* the patch's friction, into this step's contact plane */
    if (old) {
        double along = tb__dot3(old->friction_impulse, e->normal);
        for (k = 0; k < 3; ++k)
            e->friction_impulse[k] = old->friction_impulse[k] - along * e->normal[k];
        e->twist_impulse = old->twist_impulse;
        along = tb__dot3(old->tilt_impulse, e->normal);
        for (k = 0; k < 3; ++k)
            e->tilt_impulse[k] = old->tilt_impulse[k] - along * e->normal[k];
        along = tb__dot3(old->rolling_impulse, e->normal);
        for (k = 0; k < 3; ++k)
            e->rolling_impulse[k] = old->rolling_impulse[k] - along * e->normal[k];
    } else {
        e->friction_impulse[0] = e->friction_impulse[1] = e->friction_impulse[2] = e->twist_impulse = 0;
        e->tilt_impulse[0] = e->tilt_impulse[1] = e->tilt_impulse[2] = 0;
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

static tb_status colour_entries(tb_world *w, tb__contacts *c);

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
    uint32_t *index = c->bucket; /* [entry_cap]: free once solved */
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
    int carry, same;
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
        (st = collide_planes(w, c)) != TB_OK)
        return st;
    for (i = 0; i < c->pair_count; ++i) {
        const uint32_t a = c->pairs[i].a, b = c->pairs[i].b;
        const size_t before = c->entry_count;
        if ((c->proxy[a] & TB__PARTICLE_KEY) && (c->proxy[b] & TB__PARTICLE_KEY))
            continue;
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
       for a sweep order that does not depend on how the broadphase found them */
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
    /* the solver's room: batches for the entries, motion for every body */
    if ((st = colour_entries(w, c)) != TB_OK || (st = reserve_motion(w, c)) != TB_OK)
        return st;
    c->prepared = 1;
    return TB_OK;
}

/* ---- solving ---------------------------------------------------------------- */

/* The anchor of solver body i at r after the free motion, to first order in
   its turn; static: the contact point, where it was found. */
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

/* Bodies after the free motion: position, turn, momenta, inverse inertia,
   and the sweeps' velocities. */
static void load_bodies(tb_world *w, tb__contacts *c)
{
    size_t i;
    memset(c->velocity, 0, TB__MOTION * (c->body_count + 1) * sizeof *c->velocity);
    memset(c->motion, 0, TB__MOTION * (c->body_count + 1) * sizeof *c->motion);
    memset(c->momenta, 0, TB__MOTION * (c->body_count + 1) * sizeof *c->momenta);
    for (i = 0; i < c->body_count; ++i) {
        tb__solver_body *b = &c->bodies[i];
        double *v = c->velocity + TB__MOTION * (i + 1);
        int k;
        v[6] = c->motion[TB__MOTION * (i + 1) + 6] = b->inv_mass;
        if (b->tier == TB__BODIES) {
            const double *inv = b->inv_inertia, *q = body_q(w, b->slot);
            const double q0c[4] = { b->q0[0], -b->q0[1], -b->q0[2], -b->q0[3] };
            double R[9], D[9], dq[4];
            memcpy(b->x, body_x(w, b->slot), sizeof b->x);
            double *const P = c->momenta + TB__MOTION * (i + 1), *const L = P + 3;
            memcpy(P, w->y + w->off[TB__BODY_MOM] + 3 * b->slot, 3 * sizeof *P);
            memcpy(L, w->y + w->off[TB__BODY_ANG] + 3 * b->slot, 3 * sizeof *L);
            c->momenta[TB__MOTION * (i + 1) + 6] = 1;
            tb__matrix_of(q, R);
            /* the free motion's turn, q q0^-1 = (cos, sin n) -> 2 sin n */
            tb__quat_mul(q, q0c, dq);
            for (k = 0; k < 3; ++k)
                b->turn[k] = (dq[0] < 0 ? -2 : 2) * dq[k + 1];
            for (k = 0; k < 3; ++k) { /* R diag(inv) R^T */
                D[3 * k + 0] = R[3 * k + 0] * inv[0];
                D[3 * k + 1] = R[3 * k + 1] * inv[1];
                D[3 * k + 2] = R[3 * k + 2] * inv[2];
            }
            for (k = 0; k < 9; ++k) {
                const int r = k / 3, col = k % 3;
                b->inv_world[k] = D[3 * r] * R[3 * col] + D[3 * r + 1] * R[3 * col + 1] + D[3 * r + 2] * R[3 * col + 2];
            }
            for (k = 0; k < 3; ++k)
                v[k] = P[k] * b->inv_mass;
            tb__mul(b->inv_world, L, v + 3);
        } else {
            const double *vp = w->y + w->off[TB__PARTICLE_VEL] + 3 * b->slot;
            memcpy(b->x, w->y + w->off[TB__PARTICLE_POS] + 3 * b->slot, sizeof b->x);
            memset(b->turn, 0, sizeof b->turn);
            memset(b->inv_world, 0, sizeof b->inv_world);
            memcpy(v, vp, 3 * sizeof *v);
        }
    }
}

/* ---- batches ----------------------------------------------------------------- */

/* The highest and the lowest set bit of x != 0 (one instruction each where
   the compiler has them, where a loop scans up to 64 bits an entry). */
static int highest_bit(uint64_t x)
{
#if defined(__GNUC__)
    return 63 - __builtin_clzll(x);
#else
    int n = 0;
    while (x >>= 1)
        ++n;
    return n;
#endif
}

static int lowest_bit(uint64_t x)
{
#if defined(__GNUC__)
    return __builtin_ctzll(x);
#else
    int n = 0;
    while (!(x & 1))
        x >>= 1, ++n;
    return n;
#endif
}

/* Colour the entries to solve (in key order) so that no two of a colour
   share a moving body, or give one TB__COLOURS (a batch of its own) when
   no colour is free at both its bodies. Then room for the batches,
   however many of the points turn out to touch. */
static tb_status colour_entries(tb_world *w, tb__contacts *c)
{
    size_t count[TB__COLOURS + 1] = { 0 }, batches = 0, i;
    tb_status st;
    int k;
    if ((st = tb__reserve(w, (void **)&c->colours, &c->colours_cap, c->body_count + 1,
                                   sizeof *c->colours)) != TB_OK ||
        (st = tb__reserve(w, (void **)&c->bucket, &c->bucket_cap, c->entry_count + 1,
                                   sizeof *c->bucket)) != TB_OK)
        return st;
    memset(c->colours, 0, c->body_count * sizeof *c->colours);
    for (i = 0; i < c->entry_count; ++i) {
        tb__entry *e = &c->entries[c->order[i].index];
        uint64_t used = 0;
        int colour = 0;
        if (e->asleep || e->count == 0) {
            e->colour = -1;
            continue;
        }
        used |= e->body_a >= 0 ? c->colours[e->body_a] : 0;
        used |= e->body_b >= 0 ? c->colours[e->body_b] : 0;
        /* after every colour its bodies already have: the sweep then meets
           any two manifolds that share a body in key order, as a plain
           loop over the entries would, so weight still reaches down a
           stack within a pair of sweeps; past the last colour, the lowest
           free one */
        colour = used ? highest_bit(used) + 1 : 0;
        if (colour == TB__COLOURS)
            colour = ~used ? lowest_bit(~used) : TB__COLOURS;
        if (colour < TB__COLOURS) {
            if (e->body_a >= 0)
                c->colours[e->body_a] |= (uint64_t)1 << colour;
            if (e->body_b >= 0)
                c->colours[e->body_b] |= (uint64_t)1 << colour;
        }
        e->colour = colour;
        count[colour]++;
    }
    for (k = 0; k < TB__COLOURS; ++k) /* (+1: those against the static world apart) */
        batches += count[k] ? (count[k] + TB__BATCH_LANES - 1) / TB__BATCH_LANES + 1 : 0;
    batches += count[TB__COLOURS];
    if ((st = tb__reserve(w, (void **)&c->batches, &c->batch_cap, batches + 1, sizeof *c->batches)) != TB_OK)
        return st;
    if ((st = tb__reserve(w, (void **)&c->settle, &c->settle_cap,
                                   c->batch_cap * TB__PATCH_ROWS * TB__BATCH_LANES, sizeof *c->settle)) != TB_OK)
        return st;
    return tb__reserve(w, (void **)&c->cold_rows, &c->cold_rows_cap,
                                7 * c->batch_cap * TB__NORMAL_ROWS * TB__BATCH_LANES, sizeof *c->cold_rows);
}

/* Lane k's relative velocity along a normal row with arms arm_a, arm_b
   (a point's, or the press's), from the array m. */
static double normal_rate(const tb__batch *bt, const double (*arm_a)[TB__BATCH_LANES],
                          const double (*arm_b)[TB__BATCH_LANES], int k, const double *m)
{
    const double *A = m + TB__MOTION * bt->a[k], *B = m + TB__MOTION * bt->b[k];
    double rate = 0;
    int i;
    for (i = 0; i < 3; ++i)
        rate += bt->dir[0][i][k] * (B[i] - A[i]) + arm_b[i][k] * B[3 + i] - arm_a[i][k] * A[3 + i];
    return rate;
}

static double lane_rate(const tb__batch *bt, const tb__lane_point *p, int k, const double *m)
{
    return normal_rate(bt, (const double(*)[TB__BATCH_LANES])p->arm_a, (const double(*)[TB__BATCH_LANES])p->arm_b,
                       k, m);
}

/* Where the free motion took each point of entry e, and which touch;
   returns how many do. */
static int predict_points(tb__contacts *c, tb__entry *e)
{
    int k, j, touching = 0;
    for (k = 0; k < e->count; ++k) {
        tb__point *p = &e->point[k];
        double pa[3], pb[3], gap[3];
        /* the arms keep their start-of-step direction: a rolling ball's
           contact stays under its centre, not on the material point
           carried round (whose arm would make the normal force spin it
           up); the free motion's turn moves the anchors to first order */
        anchor(c, e->body_a, p->point, p->ra, pa);
        anchor(c, e->body_b, p->point, p->rb, pb);
        /* where the contact point was at the start is where both anchors
           were; the separation grew by their relative motion */
        for (j = 0; j < 3; ++j)
            gap[j] = pb[j] - pa[j];
        p->predicted = p->separation + tb__dot3(gap, e->normal);
        p->speed = 0;
        /* closed, or within a fifth of the slop of it: a resting point must
           not drop out of the solve for a rounding-sized gap */
        p->active = p->predicted <= 0.2 * c->settings.slop;
        if (!p->active)
            p->normal_impulse = 0;
        touching += p->active;
    }
    return touching;
}

/* Whether entry e joins two bodies whose masses differ ratio-fold or
   more (their inverse masses from the sweeps' array, in cache by now). */
static int mismatched(const tb__contacts *c, const tb__entry *e, double ratio)
{
    double ia, ib;
    if (e->body_a < 0 || e->body_b < 0)
        return 0;
    ia = c->velocity[TB__MOTION * (e->body_a + 1) + 6], ib = c->velocity[TB__MOTION * (e->body_b + 1) + 6];
    return ia >= ratio * ib || ib >= ratio * ia;
}

/* The relative normal acceleration a of entry e's two bodies, taken as if
   the one below were held up: the one above then falls onto it under
   gravity across the normal, where their free motions fall together
   (set_up_point). */
static double held_up(const tb__contacts *c, const tb__entry *e, double a)
{
    return fmin(a, -fabs(tb__dot3(c->gravity, e->normal)));
}

/* See set_up_point's landings. */
#define TB__REKEEP_RATIO 2

/* A gap up to this times the slop is touching: rounding, not a gap. */
#define TB__TOUCHING 1e-6

/* A gap between two bodies that touched last step, from this times the
   slop to a fifth of it, lands again as under gravity (set_up_point). */
#define TB__REGAP 0.01

/* No inverse inertia: the static world's, for the rows' set-up. */
static const double no_inertia[9] = { 0 };

/* Point p of entry e as point j of lane k, its row set up: impact timing
   and the position pass's target. fraction: the share of an old overlap
   the position pass takes back this step. *target: the normal velocity
   the point is to reach; *lever, *side_lever: how long its normal and its
   friction impulses act on positions (the patch takes their means).
   Returns whether it is a new contact (an impact). */
static int set_up_point(tb__contacts *c, const tb__entry *e, tb__point *p, tb__batch *bt, int k, int j, double h,
                        double fraction, double *target, double *lever, double *side_lever, double *keep)
{
    const tb_contact_settings *s = &c->settings;
    tb__lane_point *lp = &bt->point[j];
    double tau = h, u = 0, a = 0, disc, den;
    int impact = 0, timed = 0, regap;
    *keep = 1;
    lp->predicted[k] = p->predicted;
    lp->position_impulse[k] = 0;
    /* overlap that was already there is taken back at the rate of a
       spring-damper of the contact hertz and damping ratio, at most
       max_push, so that what an unconverged velocity pass lets sink each
       step settles at a small fixed overlap instead of adding up */
    lp->push_target[k] = p->separation >= 0 ? 0 : p->separation + fmin(fraction * -p->separation, h * s->max_push);
    regap = e->body_a >= 0 && p->matched && p->separation > TB__REGAP * s->slop && p->separation <= 0.2 * s->slop &&
            !mismatched(c, e, TB__MASS_RATIO);
    if (p->separation > 0 && (e->body_a < 0 || !p->matched || p->separation > 0.2 * s->slop || regap)) {
        /* a gap that closes within the step (or the point would not be
           active): when? Its normal motion, s + u t + a t^2 / 2 with the
           free motion's acceleration a, reaches 0 at tau. A point on
           static ground that touched last step and is within a fifth of
           the slop of it is landing again, not striking: it keeps its warm
           start, and its friction holds as at rest. (Held at target 0 from
           the start of the step instead, such a point would rest on its
           gap: dropped_boxes_lie_on_the_plane. Between two moving bodies
           this timing sees their free motion alone and would let a pyramid
           sway, pyramid_stands_and_sleeps: such a point lands again only
           from TB__REGAP of the slop, as below.) */
        u = approach_of(c, e, p);
        a = (lane_rate(bt, lp, k, c->velocity) - u) / h;
        /* Two bodies fall together in their free motion, so between them
           a gap closes only by their approach; but the one below is
           mostly held up, and the one above then falls onto it. A body
           that lands on another ends its landing step a little above it
           (the part of the landing impulse that holds it up acts on
           positions over the whole rest of the step, where for the static
           ground it acts for half of it). Timed again as falling under
           gravity across the normal, such a gap closes in the next step
           (bodies_dropped_on_bodies_rest_on_them: within 0.05 mm, the
           fraction of the slop left alone below). Not so a fresh contact
           (a stack built at rest has gaps of a rounding's size: landing,
           it would lose its warm starts), one within that fraction (a
           resting pyramid's rows would sway), nor one between bodies
           TB__MASS_RATIO times apart: the body under passes its part of
           the load on with the resting lever, and the difference would
           move it by the mass ratio times as much. */
        if (regap)
            a = held_up(c, e, a);
        /* the first root, as 2 s / (-u + sqrt(u^2 - 2 a s)): the usual
           (-u - sqrt(u^2 - 2 a s)) / a takes two nearly equal numbers
           apart and divides by a, and between two bodies falling together
           a is a rounding error (a heavy box's landing on a light one
           would be timed late and press it into the ground:
           heavy_box_lands_on_light_ones) */
        disc = u * u - 2 * a * p->separation;
        den = disc >= 0 ? -u + sqrt(disc) : 0;
        if (den > 0)
            tau = 2 * p->separation / den;
        else
            tau = u < 0 ? -p->separation / u : h;
        if (!(tau >= 0 && tau <= h))
            tau = u < 0 ? fmin(h, -p->separation / u) : h;
        timed = tau < h || p->separation > TB__TOUCHING * s->slop;
    }
    if (timed) {
        const int strikes = !p->matched || p->separation > 0.2 * s->slop;
        const double share = c->rest_lever / h;
        const double vi = -(u + a * tau); /* approach speed at impact */
        const double rest = h - tau;
        p->speed = strikes && vi > 0 ? vi : 0;
        /* a velocity change at tau moves positions over the rest of the
           step, as far as the method lets velocity changes within a step
           act (explicit Euler's positions move with the start velocity:
           not at all; incline_slides_holds_and_rolls_to_closed_forms). A
           bounce is that change alone ((1 + e) vi: the target is its
           rebound carried on by the free motion's acceleration); a landing
           also holds the body up for the rest of the step, which is a
           force acting through it (its share of the time, as at rest).
           With the whole landing impulse over h - tau, a body set down at
           rest (tau 0) would rise g h^2 / 2 and rest on that gap
           (incline_slides_holds_and_rolls_to_closed_forms,
           box_rests_without_drift). */
        *lever = rest * fmin(1, 2 * share);
        if (vi > s->restitution_threshold && e->restitution > 0) {
            *target = e->restitution * vi + a * rest;
        } else {
            /* Between bodies TB__MASS_RATIO times apart in mass the
               landing is solved with the lanes under it (cold_start.c),
               which then act on positions with this lane's lever. The
               part of it that holds the landed body up is its weight
               across the normal, as on the ground, where a, from their
               free motions falling together, is about 0: taken from a,
               it would act for the whole rest of the step and leave the
               body above the one under it, to rest on that gap or to fall
               and land on it again without a lane to carry it. */
            const double fall = mismatched(c, e, TB__MASS_RATIO) ? held_up(c, e, a) : a;
            const double jump = vi > 0 ? vi : 0, held = fall < 0 ? -fall * rest : 0;
            if (jump + held > 0)
                *lever = (jump * *lever + held * share * rest) / (jump + held);
            /* Between bodies TB__REKEEP_RATIO or more times apart in
               mass, the next step starts from the part of the impulse
               that held the landed body up, as a force through a whole
               step, not from the part that stopped it: pushed again at
               the next step's start, that part would go on through the
               body under, which the sweeps carry slowly, and throw the
               landed body back up (heavy_box_lands_on_light_ones: its
               box 3 times heavier). */
            if (strikes && jump + held > 0 && mismatched(c, e, TB__REKEEP_RATIO))
                *keep = rest > 0 ? fmin(1, held / (jump + held) * h / rest) : 0;
            *target = 0;
        }
        *side_lever = strikes ? *lever : c->rest_lever;
        if (strikes) {
            p->normal_impulse = 0;
            impact = 1;
        }
    } else {
        /* a contact force acting through the step, which moves positions
           as the method moves them under any constant force: then the
           free motion's fall and the push back cancel, and a body at rest
           stays put whatever the integrator
           (every_integrator_keeps_a_resting_box_still). So is a gap of a
           rounding's size that the free motion does not close this step
           (two boxes built 1e-16 m apart fall together): timed, its
           impulse would act for no time, and a stack built at rest would
           rise and sink box by box (staircases_stand_still). (A real gap
           that does not close is still timed: resting on it, a body would
           hover above what it rests on.) */
        /* (a gap between two moving bodies held this way, touching last
           step and within TB__REGAP of the slop, is rested on; closing
           every such gap by half a step would keep a resting pyramid's
           sweeps from settling: resting_pyramid_sweeps_stop_early) */
        *lever = *side_lever = c->rest_lever;
        *target = 0;
    }
    return impact;
}

/* Entry e's tangents along a side of its touching points (two points:
   their segment; three or four: from the first point to another, the
   longest of three but shorter of four, where the longest from a corner
   of a rectangle is the diagonal), right handed with the normal: t_2 = n
   x t_1. The patch's tilts turn about them, and along them the points'
   lever ranges bound the points' own rectangle, where along tangents at
   45 degrees to a square's sides they would bound one twice as wide
   across them, and a cube pushed over across a face would stand twice
   the push it should (box_pushed_at_the_top_tips_at_half_its_weight).
   (Friction is the same in any tangents.) */
static void side_tangents(tb__entry *e)
{
    const double *at[TB__MANIFOLD_POINTS];
    double side[3], along, scale;
    int n = 0, i, d;
    for (i = 0; i < e->count; ++i)
        if (e->point[i].active)
            at[n++] = e->point[i].point;
    if (n < 2)
        return;
    {
        double d2[TB__MANIFOLD_POINTS] = { 0 };
        int to = 1;
        for (i = 1; i < n; ++i) {
            for (d = 0; d < 3; ++d)
                d2[i] += (at[i][d] - at[0][d]) * (at[i][d] - at[0][d]);
            to = d2[i] > d2[to] ? i : to;
        }
        if (n == 4) { /* the longer of the other two */
            const int one = to == 1 ? 2 : 1, other = to == 3 ? 2 : 3;
            to = d2[one] >= d2[other] ? one : other;
        }
        for (d = 0; d < 3; ++d)
            side[d] = at[to][d] - at[0][d];
    }
    along = tb__dot3(side, e->normal);
    for (d = 0; d < 3; ++d)
        side[d] -= along * e->normal[d];
    scale = tb__norm3(side);
    if (!(scale > 0))
        return;
    scale = 1 / scale;
    for (d = 0; d < 3; ++d)
        e->tangent[0][d] = side[d] * scale;
    tb__cross(e->normal, e->tangent[0], e->tangent[1]);
}

/* Point at's levers about centre for the tilts about e's tangents: a
   unit normal force there turns b about tangent d by (at - centre) x n .
   t_d = (at - centre) . (n x t_d), where n x t_1 = t_2, n x t_2 = -t_1.
   off: at - centre. */
static void levers_of(const tb__entry *e, const double at[3], const double centre[3], double off[3],
                      double lever[2])
{
    int d;
    for (d = 0; d < 3; ++d)
        off[d] = at[d] - centre[d];
    lever[0] = tb__dot3(off, e->tangent[1]), lever[1] = -tb__dot3(off, e->tangent[0]);
}

/* Entry e's anchors as lane k: each touching point's r from both centres
   in its normal row's arms, and the friction patch's centre in the
   patch's row 0, for tb__set_up_rows; the patch's twist reach. */
static void place_lane(tb__contacts *c, tb__entry *e, tb__batch *bt, int k)
{
    double ca[3] = { 0, 0, 0 }, cb[3] = { 0, 0, 0 }, centre[3] = { 0, 0, 0 }, reach = 0, force = 0;
    double low[2] = { 0, 0 }, high[2] = { 0, 0 };
    int n = 0, i, d;
    bt->a[k] = e->body_a + 1, bt->b[k] = e->body_b + 1;
    bt->inv_world_a[k] = e->body_a >= 0 ? c->bodies[e->body_a].inv_world : no_inertia;
    bt->inv_world_b[k] = e->body_b >= 0 ? c->bodies[e->body_b].inv_world : no_inertia;
    side_tangents(e);
    for (d = 0; d < 3; ++d) {
        const double *dir = d == 0 ? e->normal : e->tangent[d - 1];
        bt->dir[d][0][k] = dir[0], bt->dir[d][1][k] = dir[1], bt->dir[d][2][k] = dir[2];
    }
    for (i = 0; i < e->count; ++i) {
        const tb__point *p = &e->point[i];
        if (!p->active)
            continue;
        for (d = 0; d < 3; ++d) {
            bt->point[n].arm_a[d][k] = p->ra[d], bt->point[n].arm_b[d][k] = p->rb[d];
            ca[d] += p->ra[d], cb[d] += p->rb[d], centre[d] += p->point[d];
        }
        bt->point[n++].source[k] = &e->point[i];
    }
    for (d = 0; d < 3; ++d) {
        ca[d] *= 1.0 / n, cb[d] *= 1.0 / n, centre[d] *= 1.0 / n;
        bt->arm_a[0][d][k] = ca[d], bt->arm_b[0][d][k] = cb[d];
    }
    /* From the points themselves (a static side's arms are all 0): their
       mean distance from the centre across the normal, and the range of
       their levers for each tilt. */
    for (i = 0; i < e->count; ++i)
        if (e->point[i].active) {
            double off[3], along, lever[2];
            levers_of(e, e->point[i].point, centre, off, lever);
            for (d = 0; d < 2; ++d) {
                low[d] = lever[d] < low[d] ? lever[d] : low[d];
                high[d] = lever[d] > high[d] ? lever[d] : high[d];
            }
            along = tb__dot3(off, e->normal);
            for (d = 0; d < 3; ++d)
                off[d] -= along * e->normal[d];
            reach += tb__norm3(off);
        }
    bt->source[k] = e;
    bt->friction[k] = e->friction;
    bt->twist_reach[k] = reach / n;
    /* rolling resistance: the normal force may act that far beyond the
       points too, so that it resists turning over them (a ball's single
       point has no range of its own). The press acts where last step's
       force was centred (its tilts' moment over its force), and the
       tilts' ranges are taken from there: they then carry what changed,
       not the whole moment, which with the press at the points' centre
       they would carry anew through every sweep (for a box resting
       off-centre on another, its weight times the offset). (One point:
       its rolling resistance is a moment about it, the press stays put.) */
    for (i = 0; i < e->count; ++i)
        if (e->point[i].active)
            force += e->point[i].normal_impulse;
    for (d = 0; d < 2; ++d) {
        const double lo = low[d] - e->rolling, hi = high[d] + e->rolling;
        double at = force > 0 && n > 1 ? tb__dot3(e->tilt_impulse, e->tangent[d]) / force : 0;
        at = at < lo ? lo : at > hi ? hi : at;
        bt->shift[d][k] = at;
        bt->tilt_low[d][k] = lo - at, bt->tilt_high[d][k] = hi - at;
    }
    bt->tilting |= n > 1 || e->rolling > 0;
}

void tb__level_turns(double s00, double s01, double s11, double b0, double b1, double turn[2])
{
    /* S's eigenvalues, largest first, and the unit eigenvector u of the
       largest (the other is u turned a quarter) */
    const double half = 0.5 * (s00 + s11), gap = sqrt(0.25 * (s00 - s11) * (s00 - s11) + s01 * s01);
    const double big = half + gap, small = half - gap;
    double u[2], length, along;
    turn[0] = turn[1] = 0;
    if (!(big > 0))
        return;
    if (s01 != 0)
        u[0] = big - s11, u[1] = s01;
    else
        u[0] = s00 >= s11 ? 1 : 0, u[1] = s00 >= s11 ? 0 : 1;
    length = sqrt(u[0] * u[0] + u[1] * u[1]);
    u[0] /= length, u[1] /= length;
    along = (u[0] * b0 + u[1] * b1) / big;
    turn[0] = along * u[0], turn[1] = along * u[1];
    if (small > 1e-9 * big) {
        const double across = (u[0] * b1 - u[1] * b0) / small;
        turn[0] -= across * u[1], turn[1] += across * u[0];
    }
}

/* What the position pass's patch of lane k (n points) aims for: the
   plane c0 + phi_1 l_1 + phi_2 l_2 nearest (least squares) to what each
   point needs, target minus predicted separation, over the points'
   levers l_d about the centre (levers_of): the centre's displacement c0
   and the turns phi_d about the tangents. A box's face against a plane
   or a face needs exactly such a plane. Points on a line (or one point)
   leave the turn across it at 0. */
static void patch_pushes(tb__batch *bt, int k, int n)
{
    const tb__entry *e = bt->source[k];
    double centre[3] = { 0, 0, 0 }, need[TB__MANIFOLD_POINTS];
    double mean = 0, s00 = 0, s01 = 0, s11 = 0, b0 = 0, b1 = 0, turn[2];
    int j, d;
    for (j = 0; j < n; ++j) {
        const tb__lane_point *lp = &bt->point[j];
        need[j] = lp->push_target[k] - lp->predicted[k];
        mean += need[j];
        for (d = 0; d < 3; ++d)
            centre[d] += lp->source[k]->point[d];
    }
    mean /= n;
    for (d = 0; d < 3; ++d)
        centre[d] /= n;
    for (j = 0; j < n; ++j) {
        double off[3], l[2];
        levers_of(e, bt->point[j].source[k]->point, centre, off, l);
        s00 += l[0] * l[0], s01 += l[0] * l[1], s11 += l[1] * l[1];
        b0 += l[0] * (need[j] - mean), b1 += l[1] * (need[j] - mean);
    }
    tb__level_turns(s00, s01, s11, b0, b1, turn);
    bt->patch_push[1][k] = turn[0], bt->patch_push[2][k] = turn[1];
    /* (the press acts at the shifted point: what is needed there) */
    bt->patch_push[0][k] = mean + bt->patch_push[1][k] * bt->shift[0][k] + bt->patch_push[2][k] * bt->shift[1][k];
    for (d = 0; d < 3; ++d)
        bt->patch_impulse[d][k] = 0;
}

/* Lane k's targets, levers and warm-start impulses, its rows set up. */
static void set_up_lane(tb__contacts *c, tb__batch *bt, int k, double h, double fraction, size_t cold[2])
{
    tb__entry *e = bt->source[k];
    /* last step's impulses were a force times its step: the same force
       over this one (column_stands_under_changing_steps) */
    const double scale = c->kept_h > 0 ? h / c->kept_h : 1;
    double lever = 0, side_lever = 0, target = 0, force = 0, keep = 0;
    int j, d, impacts = 0, moving = 0, flying = 0;
    for (j = 0; j < bt->points && bt->point[j].source[k]; ++j) {
        tb__point *p = bt->point[j].source[k];
        double point_target, point_lever, point_side_lever, point_keep;
        const int struck =
            set_up_point(c, e, p, bt, k, j, h, fraction, &point_target, &point_lever, &point_side_lever, &point_keep);
        const int deep = p->separation < -c->settings.slop;
        cold[0] += !p->matched;
        /* at rest: not struck, not deeper than the slop, and (a new point)
           its two sides moving against each other slower than the sleep
           speed; a warm point's rest is in its warm start already.
           Landing: at rest, or struck and not deep. */
        const int still = !struck && !deep && (p->matched || slip_of(c, e, p) <= c->settings.sleep_speed);
        cold[1] += !p->matched && still;
        moving += !still;
        flying += !still && !(struck && !deep);
        impacts += struck;
        lever += point_lever;
        side_lever += point_side_lever;
        target += point_target;
        keep += point_keep;
        force += p->normal_impulse; /* (0 for a point that struck) */
    }
    /* the patch acts on positions for as long as its points touched,
       aims at their mean normal velocity, and starts from their warm
       starts; its friction and tilts start afresh when one of them struck
       this step. One point has no twist, nor tilts without rolling
       resistance: their rows may not be solved at all then (a batch of
       one-point lanes skips them), and what they started from would be
       pushed on every step unchanged
       (capsule_stood_on_end_keeps_its_spin). */
    bt->resting[k] = !moving;
    bt->landing[k] = !flying;
    e->struck = impacts > 0;
    bt->heavy[k] = !flying && mismatched(c, e, impacts || e->struck_before ? TB__MASS_RATIO : TB__MASS_RATIO_RESTING);
    c->heavy_lanes += bt->heavy[k];
    bt->lever[k] = lever / j;
    bt->keep[k] = keep / j;
    bt->side_lever[k] = side_lever / j;
    /* A lane that bounces (its points' mean target > 0) is solved to
       stop first, then bounced by its press alone (tb__bounce), where the
       press acts no faster than it came after the free motion, plus
       twice what gravity adds across the normal in the step: more would
       give the bodies energy. The points' mean asks for more where a body
       spins: one end of its patch strikes while the other leaves, and the
       centre hardly moves (dense_heaps_never_gain_energy). */
    bt->press_target[k] = target < 0 ? target / j : 0;
    bt->bounce[k] = 0;
    if (target > 0) {
        const double came = -normal_rate(bt, (const double(*)[TB__BATCH_LANES])bt->arm_a[TB__ROW_PRESS],
                                         (const double(*)[TB__BATCH_LANES])bt->arm_b[TB__ROW_PRESS], k, c->velocity);
        bt->bounce[k] = fmin(target / j, fmax(0, came) + 2 * fabs(tb__dot3(c->gravity, e->normal)) * h);
        bt->bouncing = 1;
        c->bounces++;
    }
    bt->impulse[TB__ROW_PRESS][k] = force * scale;
    for (d = 0; d < 2; ++d) {
        bt->impulse[TB__ROW_TANGENT1 + d][k] = impacts ? 0 : tb__dot3(e->friction_impulse, e->tangent[d]) * scale;
        bt->impulse[TB__ROW_TILT1 + d][k] =
            impacts || (j == 1 && !(e->rolling > 0))
                ? 0
                : (tb__dot3(e->tilt_impulse, e->tangent[d]) - force * bt->shift[d][k]) * scale;
    }
    bt->impulse[TB__ROW_TWIST][k] = impacts || j == 1 ? 0 : e->twist_impulse * scale;
    patch_pushes(bt, k, j);
}

/* A placed batch's rows, then its lanes' targets and warm starts. */
static void finish_batch(tb__contacts *c, tb__batch *bt, double h, double fraction, size_t cold[2])
{
    int k;
    tb__set_up_rows(bt, 1, c->velocity, c->isa);
    for (k = 0; k < TB__BATCH_LANES; ++k)
        if (bt->source[k])
            set_up_lane(c, bt, k, h, fraction, cold);
}

/* An entry's place among the batches: by colour, then against the static
   world (side a) or not, then by how many points touch, most first. */
static size_t bucket_of(const tb__entry *e)
{
    return ((size_t)e->colour * 2 + (e->body_a < 0)) * TB__MANIFOLD_POINTS + TB__MANIFOLD_POINTS - (size_t)e->touching;
}

/* Whether the batch that starts at c->bucket[i] (of n) is full, with as
   many points in every lane: then the lanes set every field of it, and it
   needs no zeroing first (a batch is some 12 kB, which the lanes write
   whole anyway). */
static int full_batch(const tb__contacts *c, size_t i, size_t n)
{
    const tb__entry *first = &c->entries[c->bucket[i]], *last;
    size_t j;
    if (i + TB__BATCH_LANES > n || first->colour == TB__COLOURS)
        return 0;
    for (j = 1; j < TB__BATCH_LANES; ++j)
        if (bucket_of(&c->entries[c->bucket[i + j]]) / TB__MANIFOLD_POINTS !=
            bucket_of(first) / TB__MANIFOLD_POINTS)
            return 0;
    last = &c->entries[c->bucket[i + TB__BATCH_LANES - 1]];
    return last->touching == first->touching;
}

/* The touching entries into batches: by colour, and within a colour those
   against the static world apart (the sweeps skip their side a), and by
   how many points touch, most first, so that a batch's lanes mostly have
   as many points as its first; each lane's touching points packed. Then
   their rows, in lanes, and their targets. Counts the touching points,
   those without last step's impulses (cold[0]), and of those the ones
   at rest, not striking (cold[1]). */
static void set_up_batches(tb__contacts *c, double h, size_t *points, size_t cold[2])
{
    enum { CLASSES = TB__MANIFOLD_POINTS, BUCKETS = (TB__COLOURS + 1) * 2 * CLASSES };
    const tb_contact_settings *s = &c->settings;
    const double omega = 2 * 3.14159265358979323846 * s->hertz;
    const double fraction = fmin(1, h * omega / (2 * s->damping_ratio + h * omega));
    size_t start[BUCKETS + 1] = { 0 }, i, n = 0;
    size_t last = SIZE_MAX; /* the last batch's colour and side */
    int lane = TB__BATCH_LANES, k;
    tb__batch *bt = NULL;
    for (i = 0; i < c->entry_count; ++i) {
        tb__entry *e = &c->entries[c->order[i].index];
        if (e->colour < 0)
            continue;
        /* (make_events sets touching again after the solve) */
        if ((e->touching = predict_points(c, e)) > 0)
            start[bucket_of(e) + 1]++;
        *points += (size_t)e->touching;
    }
    for (i = 0; i < BUCKETS; ++i)
        start[i + 1] += start[i];
    for (i = 0; i < c->entry_count; ++i) {
        const uint32_t index = c->order[i].index;
        const tb__entry *e = &c->entries[index];
        if (e->colour >= 0 && e->touching) {
            c->bucket[start[bucket_of(e)]++] = index;
            ++n;
        }
    }
    c->batch_count = 0;
    for (i = 0; i < n; ++i) {
        tb__entry *e = &c->entries[c->bucket[i]];
        if (lane == TB__BATCH_LANES || bucket_of(e) / CLASSES != last || e->colour == TB__COLOURS) {
            /* a new batch: its first lane has the most points; empty lanes
               are on the static world. The last one is finished first,
               while its entries are still in cache (finished after every
               batch is placed, they would be fetched again) */
            if (bt)
                finish_batch(c, bt, h, fraction, cold);
            bt = &c->batches[c->batch_count++];
            if (!full_batch(c, i, n)) {
                memset(bt, 0, offsetof(tb__batch, point) + (size_t)e->touching * sizeof(tb__lane_point));
                for (k = 0; k < TB__BATCH_LANES; ++k)
                    bt->inv_world_a[k] = bt->inv_world_b[k] = no_inertia;
            }
            bt->points = e->touching;
            bt->one_sided = e->body_a < 0;
            bt->tilting = bt->bouncing = 0;
            last = bucket_of(e) / CLASSES;
            lane = 0;
        }
        place_lane(c, e, bt, lane++);
    }
    if (bt)
        finish_batch(c, bt, h, fraction, cold);
}

/* The impulse totals back to the points and entries, for the next step's
   warm start. */
static void keep_impulses(tb__contacts *c)
{
    size_t b;
    int k, i, n;
    for (b = 0; b < c->batch_count; ++b) {
        const tb__batch *bt = &c->batches[b];
        for (k = 0; k < TB__BATCH_LANES; ++k) {
            tb__entry *e = bt->source[k];
            if (!e)
                continue;
            for (i = 0; i < 3; ++i) {
                e->friction_impulse[i] = bt->impulse[TB__ROW_TANGENT1][k] * e->tangent[0][i] +
                                         bt->impulse[TB__ROW_TANGENT2][k] * e->tangent[1][i];
                e->tilt_impulse[i] =
                    bt->keep[k] *
                    ((bt->impulse[TB__ROW_TILT1][k] + bt->impulse[TB__ROW_PRESS][k] * bt->shift[0][k]) * e->tangent[0][i] +
                     (bt->impulse[TB__ROW_TILT2][k] + bt->impulse[TB__ROW_PRESS][k] * bt->shift[1][k]) * e->tangent[1][i]);
            }
            e->twist_impulse = bt->impulse[TB__ROW_TWIST][k];
            /* the press's force, shared by the points, so that the points
               still touching next step bring their share */
            for (n = 0; n < bt->points && bt->point[n].source[k]; ++n)
                ;
            for (i = 0; i < n; ++i)
                bt->point[i].source[k]->normal_impulse = bt->keep[k] * bt->impulse[TB__ROW_PRESS][k] / n;
        }
    }
}

static void store_bodies(tb_world *w, tb__contacts *c)
{
    size_t i;
    for (i = 0; i < c->body_count; ++i) {
        const tb__solver_body *b = &c->bodies[i];
        const double *dp = c->motion + TB__MOTION * (i + 1), *dtheta = dp + 3;
        int k;
        if (b->tier == TB__BODIES) {
            double *x = w->y + w->off[TB__BODY_POS] + 3 * b->slot, *q = w->y + w->off[TB__BODY_ROT] + 4 * b->slot;
            const double turn[4] = { 0, 0.5 * dtheta[0], 0.5 * dtheta[1], 0.5 * dtheta[2] };
            double dq[4];
            for (k = 0; k < 3; ++k)
                x[k] += dp[k];
            tb__quat_mul(turn, q, dq);
            for (k = 0; k < 4; ++k)
                q[k] += dq[k];
            tb__normalise(q);
            memcpy(w->y + w->off[TB__BODY_MOM] + 3 * b->slot, c->momenta + TB__MOTION * (i + 1), 3 * sizeof(double));
            memcpy(w->y + w->off[TB__BODY_ANG] + 3 * b->slot, c->momenta + TB__MOTION * (i + 1) + 3,
                   3 * sizeof(double));
        } else {
            double *x = w->y + w->off[TB__PARTICLE_POS] + 3 * b->slot, *v = w->y + w->off[TB__PARTICLE_VEL] + 3 * b->slot;
            for (k = 0; k < 3; ++k) {
                x[k] += dp[k];
                v[k] = c->velocity[TB__MOTION * (i + 1) + k];
            }
        }
    }
}

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

/* Where point p of entry e is at the end of the step, on side a. */
static void final_point(const tb__contacts *c, const tb__entry *e, const tb__point *p, double out[3])
{
    anchor(c, e->body_a, p->point, p->ra, out);
    if (e->body_a >= 0) {
        const double *dp = c->motion + TB__MOTION * (e->body_a + 1), *dtheta = dp + 3;
        double turn[3];
        tb__cross(dtheta, p->ra, turn);
        out[0] += dp[0] + turn[0], out[1] += dp[1] + turn[1], out[2] += dp[2] + turn[2];
    }
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
                final_point(c, e, p, ev->point);
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

/* The sum of every manifold's normal impulse, to see the sweeps settle. */
static double total_press(const tb__contacts *c)
{
    double sum = 0;
    size_t b;
    int k;
    for (b = 0; b < c->batch_count; ++b)
        for (k = 0; k < TB__BATCH_LANES; ++k)
            sum += c->batches[b].impulse[TB__ROW_PRESS][k];
    return sum;
}

/* Whether a pair of sweeps left every row's impulse within tolerance
   times its mass (the velocity it enforces within tolerance) of what
   c->settle held before it. */
static int settled(const tb__contacts *c, double tolerance)
{
    size_t b;
    int i;
    for (b = 0; b < c->batch_count; ++b) {
        const double *now = &c->batches[b].impulse[0][0], *mass = &c->batches[b].mass[0][0];
        const double *before = c->settle + b * TB__PATCH_ROWS * TB__BATCH_LANES;
        int over = 0;
        for (i = 0; i < TB__PATCH_ROWS * TB__BATCH_LANES; ++i)
            over |= fabs(now[i] - before[i]) > tolerance * mass[i];
        if (over)
            return 0;
    }
    return 1;
}

/* The velocity sweeps, in pairs (a forward and a backward), up to most;
   they stop once a pair changed no enforced velocity by more than
   tolerance (0: never), looked at after sweeps 4, 8, 12 and so on (each
   look copies every impulse first, a cost wasted where nothing settles,
   as in a falling pile). A resting pyramid of 210 boxes then takes 6.63
   sweeps a step on average, not 20 (resting_pyramid_sweeps_stop_early),
   and moves as with every sweep done (pyramid_stands_and_sleeps). Returns
   how many sweeps ran. */
static int sweep_until_settled(tb__contacts *c, int most, double tolerance)
{
    const size_t per_batch = TB__PATCH_ROWS * TB__BATCH_LANES;
    int it;
    for (it = 0; it < most; it += 2) {
        const int check = tolerance > 0 && it % 4 == 2 && it + 2 <= most;
        size_t b;
        if (check)
            for (b = 0; b < c->batch_count; ++b)
                memcpy(c->settle + b * per_batch, c->batches[b].impulse, sizeof c->batches[b].impulse);
        tb__sweep_velocities(c->batches, c->batch_count, c->velocity, it & 1, c->isa);
        if (it + 1 < most)
            tb__sweep_velocities(c->batches, c->batch_count, c->velocity, (it + 1) & 1, c->isa);
        if (check && settled(c, tolerance))
            return it + 2;
    }
    return most;
}

#define TB__COLD_TIMES 16
#define TB__COLD_SETTLED 1e-3

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

void tb__contacts_solve(tb_world *w, double h, double force_lever)
{
    tb__contacts *c = w->contacts;
    size_t points = 0, cold[2] = { 0, 0 };
    int it, iterations;
    if (!c->prepared)
        return;
    tb__sleep_restore(w, c);
    if (c->settings.substeps > 0) {
        /* the soft-step solver (soft_step.c); out of memory, the free
           motion stands */
        if (tb__soft_step(w, c, h) == TB_OK)
            goto solved;
        load_bodies(w, c);
        memset(c->motion, 0, TB__MOTION * (c->body_count + 1) * sizeof *c->motion);
        c->soft_row_count = 0;
        goto solved;
    }
    load_bodies(w, c);
    c->rest_lever = force_lever * h;
    memcpy(c->gravity, w->gravity, sizeof c->gravity);
    c->heavy_lanes = c->bounces = 0;
    set_up_batches(c, h, &points, cold);
    tb__push_impulses(c->batches, c->batch_count, c->velocity, TB__PUSH_VELOCITY, c->isa);
    iterations = c->settings.velocity_iterations;
    /* more than one in eight of the touching points new and at rest (a
       scene built touching): the normal rows of the lanes at rest solved
       together first (cold_start.c). Landings are left to the sweeps: they
       strike, and the next step starts warm (a falling pile's cold steps
       are landings, and solved whole they cost many iterations for
       nothing), but for a body landing on one of a very different mass:
       those lanes and the ones near them are solved together
       (tb__heavy_landings) */
    if (8 * cold[1] > points)
        tb__cold_start(c, TB__COLD_TIMES * iterations, c->settings.velocity_tolerance, 1);
    else if (c->heavy_lanes)
        tb__heavy_landings(c, iterations, c->settings.velocity_tolerance);
    else if (c->settings.stack_iterations > 0)
        /* every step, whatever the warm starts left (tolerance 0): a
           stack at rest leaves every row within velocity_tolerance, and
           its lean grows below it
           (awake_offset_stacks_stay_up_with_stack_iterations) */
        tb__cold_start(c, c->settings.stack_iterations, 0, 0);
    it = sweep_until_settled(c, iterations, c->settings.velocity_tolerance);
    if (8 * cold[0] > points) {
        /* more than one in eight of the touching points without last
           step's impulses to start from (a scene just built, a crowd or a
           body landing) need more sweeps to reach them: in pairs, until
           the total normal impulse changes by less than TB__COLD_SETTLED
           of itself in a pair, or TB__COLD_TIMES times the sweeps. A box
           landing on a light one would otherwise press it into the ground
           (heavy_box_lands_on_light_ones: its box 3 times heavier). */
        double before = total_press(c), after;
        for (; it + 1 < TB__COLD_TIMES * iterations; it += 2) {
            tb__sweep_velocities(c->batches, c->batch_count, c->velocity, it & 1, c->isa);
            tb__sweep_velocities(c->batches, c->batch_count, c->velocity, (it + 1) & 1, c->isa);
            after = total_press(c);
            if (fabs(after - before) <= TB__COLD_SETTLED * after)
                break;
            before = after;
        }
    }
    c->sweeps = it;
    if (c->bounces)
        tb__bounce(c->batches, c->batch_count, c->velocity, c->isa);
    /* the impulses' whole effect: momenta, and positions over their lever
       times */
    tb__push_impulses(c->batches, c->batch_count, c->momenta, TB__PUSH_MOMENTA, c->isa);
    tb__push_impulses(c->batches, c->batch_count, c->motion, TB__PUSH_MOTION, c->isa);
    keep_impulses(c);
    c->kept_h = h;
    for (it = 0; it < c->settings.position_iterations; ++it)
        tb__sweep_positions(c->batches, c->batch_count, c->motion, it & 1, c->isa);
    store_bodies(w, c);
solved:
    if (make_events(w, c) != TB_OK)
        c->event_count = 0; /* out of memory for events: the step itself stands */
    tb__sleep_update(w, c, h);
    park(w, c, h);
    c->prepared = 0;
    c->solved = 1;
}
