/* contact.c: finding contacts at the start of a step and solving them after
   the integrator's free motion (the scheme is in tumble.h, "shapes,
   contacts"). */
#include "contact.h"
#include "body_math.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>


/* ---- placing shapes ------------------------------------------------------- */

/* The shape in the world, for a body at x with orientation q. */
static void place(const tb__shape *s, const double x[3], const double q[4], tb__geom *g)
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
        matrix_of(s->rot, g->rot);
        return;
    }
    quat_mul(q, s->rot, qs);
    matrix_of(qs, g->rot);
    matrix_of(q, R);
    mul(R, s->pos, off);
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

/* v and w of body slot s from its momenta. */
static void body_velocity(const tb_world *w, uint32_t s, double v[3], double wv[3])
{
    const double *P = w->y + w->off[TB__BODY_MOM] + 3 * s, *L = w->y + w->off[TB__BODY_ANG] + 3 * s;
    const double *inv = w->body_inv_inertia + 3 * s;
    double R[9], Lb[3];
    int k;
    for (k = 0; k < 3; ++k)
        v[k] = P[k] * w->body_inv_mass[s];
    matrix_of(body_q(w, s), R);
    mul_transposed(R, L, Lb);
    for (k = 0; k < 3; ++k)
        Lb[k] *= inv[k];
    mul(R, Lb, wv);
}

/* ---- the solver's bodies -------------------------------------------------- */

static tb_status map_reserve(tb_world *w, tb__contacts *c)
{
    tb_status st;
    size_t i;
    if ((st = tb__contacts_reserve(w, (void **)&c->body_map, &c->body_map_cap, w->body_count + 1, sizeof(int32_t))) !=
        TB_OK)
        return st;
    if ((st = tb__contacts_reserve(w, (void **)&c->particle_map, &c->particle_map_cap, w->particle_count + 1,
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
    if (tier == TB__PARTICLES && w->inv_mass[slot] == 0) {
        *out = -1;
        return TB_OK;
    }
    if (map[slot] >= 0) {
        *out = map[slot];
        return TB_OK;
    }
    if ((st = tb__contacts_reserve(w, (void **)&c->bodies, &c->body_cap, c->body_count + 1, sizeof *b)) != TB_OK)
        return st;
    b = &c->bodies[c->body_count];
    memset(b, 0, sizeof *b);
    b->tier = tier;
    b->slot = slot;
    if (tier == TB__BODIES) {
        b->inv_mass = w->body_inv_mass[slot];
        memcpy(b->inv_inertia, w->body_inv_inertia + 3 * slot, sizeof b->inv_inertia);
        memcpy(b->x0, body_x(w, slot), sizeof b->x0);
        memcpy(b->q0, body_q(w, slot), sizeof b->q0);
    } else {
        b->inv_mass = w->inv_mass[slot];
        memcpy(b->x0, w->y + w->off[TB__PARTICLE_POS] + 3 * slot, sizeof b->x0);
        b->q0[0] = 1;
    }
    map[slot] = (int32_t)c->body_count;
    *out = (int32_t)c->body_count++;
    return TB_OK;
}

/* The body's velocities at the start of the step (before the solve has
   filled v and w): read from the state. */
static void start_velocity(const tb_world *w, const tb__contacts *c, int32_t i, const double r[3], double v[3])
{
    double lin[3] = { 0, 0, 0 }, ang[3] = { 0, 0, 0 };
    if (i >= 0) {
        const tb__solver_body *b = &c->bodies[i];
        if (b->tier == TB__BODIES)
            body_velocity(w, b->slot, lin, ang);
        else
            memcpy(lin, w->y + w->off[TB__PARTICLE_VEL] + 3 * b->slot, sizeof lin);
    }
    cross(ang, r, v);
    v[0] += lin[0], v[1] += lin[1], v[2] += lin[2];
}

/* ---- finding contacts ------------------------------------------------------- */

static int entry_order(const void *pa, const void *pb)
{
    const tb__entry *a = pa, *b = pb;
    if (a->key_a != b->key_a)
        return a->key_a < b->key_a ? -1 : 1;
    return a->key_b < b->key_b ? -1 : a->key_b > b->key_b;
}

static const tb__entry *previous_entry(const tb__contacts *c, uint32_t key_a, uint32_t key_b)
{
    size_t lo = 0, hi = c->previous_count;
    while (lo < hi) {
        const size_t mid = (lo + hi) / 2;
        const tb__entry *e = &c->previous[mid];
        if (e->key_a < key_a || (e->key_a == key_a && e->key_b < key_b))
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < c->previous_count && c->previous[lo].key_a == key_a && c->previous[lo].key_b == key_b
               ? &c->previous[lo]
               : NULL;
}

static void tangents(const double n[3], double t1[3], double t2[3])
{
    /* the axis least along n, crossed with it */
    const double ax = fabs(n[0]), ay = fabs(n[1]), az = fabs(n[2]);
    double a[3] = { 0, 0, 0 }, len;
    a[ax <= ay && ax <= az ? 0 : ay <= az ? 1 : 2] = 1;
    cross(n, a, t1);
    len = norm3(t1);
    t1[0] /= len, t1[1] /= len, t1[2] /= len;
    cross(n, t1, t2);
}

/* The key, side and solver body of a proxy. */
typedef struct side {
    uint32_t key;
    int32_t body;
    double friction, restitution;
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
        return solver_body(w, c, TB__PARTICLES, slot, &s->body);
    } else {
        const tb__shape *sh = &c->shapes[proxy];
        uint32_t gen, slot;
        tb__ids_at(&c->ids, proxy, &s->key, &gen);
        s->friction = sh->friction;
        s->restitution = sh->restitution;
        s->body = -1;
        if (sh->body && tb__ids_lookup(&w->body_ids, sh->body, sh->body_generation, &slot))
            return solver_body(w, c, TB__BODIES, slot, &s->body);
        return TB_OK;
    }
}

/* An entry for the manifold m between proxies pa and pb. */
static tb_status add_entry(tb_world *w, tb__contacts *c, uint32_t pa, uint32_t pb, const tb__manifold *m)
{
    side a, b;
    tb__entry *e;
    const tb__entry *old;
    tb_status st;
    int k;
    if ((st = side_of(w, c, pa, &a)) != TB_OK || (st = side_of(w, c, pb, &b)) != TB_OK)
        return st;
    if (a.body < 0 && b.body < 0)
        return TB_OK;
    if ((st = tb__contacts_reserve(w, (void **)&c->entries, &c->entry_cap, c->entry_count + 1, sizeof *e)) != TB_OK)
        return st;
    e = &c->entries[c->entry_count++];
    memset(e, 0, sizeof *e);
    e->key_a = a.key, e->key_b = b.key;
    e->body_a = a.body, e->body_b = b.body;
    memcpy(e->normal, m->normal, sizeof e->normal);
    tangents(e->normal, e->tangent[0], e->tangent[1]);
    e->friction = sqrt(a.friction * b.friction);
    e->restitution = fmax(a.restitution, b.restitution);
    e->count = m->count;
    old = previous_entry(c, a.key, b.key);
    for (k = 0; k < m->count; ++k) {
        tb__point *p = &e->point[k];
        const double *at = m->point[k].pos;
        double va[3], vb[3];
        int j;
        p->feature = m->point[k].feature;
        p->separation = -m->point[k].depth;
        memcpy(p->point, at, sizeof p->point);
        for (j = 0; j < 3; ++j) {
            p->ra[j] = e->body_a >= 0 ? at[j] - c->bodies[e->body_a].x0[j] : 0;
            p->rb[j] = e->body_b >= 0 ? at[j] - c->bodies[e->body_b].x0[j] : 0;
        }
        start_velocity(w, c, e->body_a, p->ra, va);
        start_velocity(w, c, e->body_b, p->rb, vb);
        for (j = 0; j < 3; ++j)
            vb[j] -= va[j];
        p->approach = dot3(vb, e->normal);
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
                p->tangent_impulse[0] = old->point[best].tangent_impulse[0];
                p->tangent_impulse[1] = old->point[best].tangent_impulse[1];
                p->matched = 1;
            }
        }
    }
    return TB_OK;
}

/* How far a proxy may move in a step of h: its speed and spin over the
   step, and what gravity adds, plus the slop. */
static double motion_margin(const tb_world *w, const tb__contacts *c, uint32_t proxy, double h)
{
    const double g = norm3(w->gravity) * h * h;
    if (proxy & TB__PARTICLE_KEY) {
        const double *v = w->y + w->off[TB__PARTICLE_VEL] + 3 * (proxy & ~TB__PARTICLE_KEY);
        return h * norm3(v) + g + c->settings.slop;
    } else {
        const tb__shape *s = &c->shapes[proxy];
        uint32_t slot;
        double v[3], wv[3];
        if (!s->body || !tb__ids_lookup(&w->body_ids, s->body, s->body_generation, &slot))
            return c->settings.slop;
        body_velocity(w, slot, v, wv);
        return h * (norm3(v) + norm3(wv) * s->reach) + g + c->settings.slop;
    }
}

tb_status tb__contacts_prepare(tb_world *w, double h)
{
    tb__contacts *c = w->contacts;
    const int particles = c->settings.particle_radius >= 0;
    const size_t bodies_shapes = c->shape_count - c->planes;
    const size_t n = bodies_shapes + (particles ? w->particle_count : 0);
    size_t i, k, cap;
    tb__entry *swap;
    tb_status st;
    /* last step's entries become the previous ones (for warm starting and
       events), unless that step never got to solve them */
    if (c->solved) {
        swap = c->previous, c->previous = c->entries, c->entries = swap;
        cap = c->previous_cap, c->previous_cap = c->entry_cap, c->entry_cap = cap;
        c->previous_count = c->entry_count;
    }
    c->entry_count = 0;
    c->prepared = c->solved = 0;
    if ((st = map_reserve(w, c)) != TB_OK)
        return st;
    if (n + c->shape_count > c->proxy_cap) {
        size_t old = c->proxy_cap, want = n;
        void **arrays[8];
        size_t sizes[8] = { 3 * sizeof(double), 3 * sizeof(double), sizeof(uint32_t), sizeof(uint32_t),
                            sizeof(uint32_t), sizeof(uint32_t), sizeof(double), sizeof(tb__geom) };
        size_t new_cap = old ? old : 16;
        while (new_cap < want)
            new_cap *= 2;
        arrays[0] = (void **)&c->lo, arrays[1] = (void **)&c->hi, arrays[2] = (void **)&c->category;
        arrays[3] = (void **)&c->mask, arrays[4] = (void **)&c->group, arrays[5] = (void **)&c->proxy;
        arrays[6] = (void **)&c->margin, arrays[7] = (void **)&c->geoms;
        if ((st = tb__grow(w, arrays, sizes, 8, 0, old, new_cap)) != TB_OK)
            return st;
        c->proxy_cap = new_cap;
    }
    /* proxies: every shape but planes, then the particles */
    c->proxy_count = 0;
    for (i = 0; i < c->shape_count; ++i) {
        const tb__shape *s = &c->shapes[i];
        uint32_t slot;
        tb__geom *g;
        if (s->kind == TB__SHAPE_PLANE)
            continue;
        k = c->proxy_count++;
        g = &c->geoms[k];
        if (s->body && tb__ids_lookup(&w->body_ids, s->body, s->body_generation, &slot))
            place(s, body_x(w, slot), body_q(w, slot), g);
        else
            place(s, NULL, NULL, g);
        c->proxy[k] = (uint32_t)i;
        c->category[k] = s->category;
        c->mask[k] = s->mask;
        c->group[k] = s->body ? s->body : 0xFFFFFFFFu;
    }
    if (particles)
        for (i = 0; i < w->particle_count; ++i) {
            tb__geom *g;
            k = c->proxy_count++;
            g = &c->geoms[k];
            memset(g, 0, sizeof *g);
            g->kind = TB__SHAPE_SPHERE;
            g->radius = c->settings.particle_radius;
            memcpy(g->pos, w->y + w->off[TB__PARTICLE_POS] + 3 * i, sizeof g->pos);
            g->rot[0] = g->rot[4] = g->rot[8] = 1;
            c->proxy[k] = (uint32_t)i | TB__PARTICLE_KEY;
            c->category[k] = 0xFFFFFFFFu;
            c->mask[k] = 0xFFFFFFFFu;
            c->group[k] = 0xFFFFFFFEu; /* particles never meet each other */
        }
    for (k = 0; k < c->proxy_count; ++k) {
        int j;
        c->margin[k] = motion_margin(w, c, c->proxy[k], h);
        tb__geom_bounds(&c->geoms[k], c->lo + 3 * k, c->hi + 3 * k);
        for (j = 0; j < 3; ++j) {
            c->lo[3 * k + j] -= c->margin[k];
            c->hi[3 * k + j] += c->margin[k];
        }
    }
    if ((st = tb__sap_pairs(w, &c->sap, c->proxy_count, c->lo, c->hi, c->category, c->mask, c->group, &c->pairs,
                            &c->pair_count, &c->pair_cap)) != TB_OK)
        return st;
    for (i = 0; i < c->pair_count; ++i) {
        const uint32_t a = c->pairs[i].a, b = c->pairs[i].b;
        tb__manifold m;
        if ((c->proxy[a] & TB__PARTICLE_KEY) && (c->proxy[b] & TB__PARTICLE_KEY))
            continue;
        if (tb__collide(&c->geoms[a], &c->geoms[b], c->margin[a] + c->margin[b], &m) &&
            (st = add_entry(w, c, c->proxy[a], c->proxy[b], &m)) != TB_OK)
            return st;
    }
    /* planes against every proxy whose box reaches them */
    for (i = 0; i < c->shape_count; ++i) {
        const tb__shape *s = &c->shapes[i];
        tb__geom plane;
        if (s->kind != TB__SHAPE_PLANE)
            continue;
        place(s, NULL, NULL, &plane);
        for (k = 0; k < c->proxy_count; ++k) {
            const double *lo = c->lo + 3 * k, *hi = c->hi + 3 * k;
            double nearest = 0;
            tb__manifold m;
            int j;
            if (!(s->category & c->mask[k]) || !(c->category[k] & s->mask) || c->group[k] == 0xFFFFFFFFu)
                continue;
            for (j = 0; j < 3; ++j) /* the box corner deepest along -n */
                nearest += s->normal[j] * (s->normal[j] > 0 ? lo[j] : hi[j]);
            if (nearest > s->offset)
                continue;
            if (tb__collide(&plane, &c->geoms[k], c->margin[k], &m) &&
                (st = add_entry(w, c, (uint32_t)i, c->proxy[k], &m)) != TB_OK)
                return st;
        }
    }
    if (c->entry_count > 1) /* (qsort wants a valid pointer even for nothing) */
        qsort(c->entries, c->entry_count, sizeof *c->entries, entry_order);
    c->prepared = 1;
    return TB_OK;
}

/* ---- solving ---------------------------------------------------------------- */

/* Move the body's pose as an impulse J at r would over `lever` seconds. */
static void shift(tb__contacts *c, int32_t i, const double r[3], const double J[3], double scale)
{
    tb__solver_body *b;
    double t[3], dw[3];
    int k;
    if (i < 0)
        return;
    b = &c->bodies[i];
    for (k = 0; k < 3; ++k)
        b->dp[k] += scale * J[k] * b->inv_mass;
    if (b->tier != TB__BODIES)
        return;
    cross(r, J, t);
    mul(b->inv_world, t, dw);
    for (k = 0; k < 3; ++k)
        b->dtheta[k] += scale * dw[k];
}

/* The anchor's current world position: the pose after the free motion,
   plus the corrections so far. */
static void anchor(const tb__contacts *c, int32_t i, const double fixed[3], const double r[3], double out[3])
{
    if (i < 0) { /* static: the contact point, where it was found */
        memcpy(out, fixed, 3 * sizeof(double));
    } else {
        const tb__solver_body *b = &c->bodies[i];
        double turn[3], angle[3];
        angle[0] = b->turn[0] + b->dtheta[0], angle[1] = b->turn[1] + b->dtheta[1], angle[2] = b->turn[2] + b->dtheta[2];
        cross(angle, r, turn);
        out[0] = b->x[0] + r[0] + b->dp[0] + turn[0];
        out[1] = b->x[1] + r[1] + b->dp[1] + turn[1];
        out[2] = b->x[2] + r[2] + b->dp[2] + turn[2];
    }
}

/* Separation of point p now: along n, between the two anchors. */
static double separation_now(const tb__contacts *c, const tb__entry *e, const tb__point *p)
{
    double a[3], b[3], d[3];
    anchor(c, e->body_a, p->point, p->ra, a);
    anchor(c, e->body_b, p->point, p->rb, b);
    d[0] = b[0] - a[0], d[1] = b[1] - a[1], d[2] = b[2] - a[2];
    return p->separation + dot3(d, e->normal);
}

/* Bodies after the free motion: position, turn, velocities, momenta,
   inverse inertia. */
static void load_bodies(tb_world *w, tb__contacts *c)
{
    size_t i;
    for (i = 0; i < c->body_count; ++i) {
        tb__solver_body *b = &c->bodies[i];
        int k;
        memcpy(b->x, b->tier == TB__BODIES ? body_x(w, b->slot) : w->y + w->off[TB__PARTICLE_POS] + 3 * b->slot,
               sizeof b->x);
        if (b->tier == TB__BODIES) {
            const double *inv = b->inv_inertia;
            double D[9];
            memcpy(b->P, w->y + w->off[TB__BODY_MOM] + 3 * b->slot, sizeof b->P);
            memcpy(b->L, w->y + w->off[TB__BODY_ANG] + 3 * b->slot, sizeof b->L);
            matrix_of(body_q(w, b->slot), b->R);
            {   /* the free motion's turn, q q0^-1 = (cos, sin n) -> 2 sin n */
                const double *q = body_q(w, b->slot);
                const double q0c[4] = { b->q0[0], -b->q0[1], -b->q0[2], -b->q0[3] };
                double dq[4];
                quat_mul(q, q0c, dq);
                for (k = 0; k < 3; ++k)
                    b->turn[k] = (dq[0] < 0 ? -2 : 2) * dq[k + 1];
            }
            for (k = 0; k < 3; ++k) { /* R diag(inv) R^T */
                D[3 * k + 0] = b->R[3 * k + 0] * inv[0];
                D[3 * k + 1] = b->R[3 * k + 1] * inv[1];
                D[3 * k + 2] = b->R[3 * k + 2] * inv[2];
            }
            for (k = 0; k < 9; ++k) {
                const int r = k / 3, col = k % 3;
                b->inv_world[k] = D[3 * r] * b->R[3 * col] + D[3 * r + 1] * b->R[3 * col + 1] +
                                  D[3 * r + 2] * b->R[3 * col + 2];
            }
            for (k = 0; k < 3; ++k)
                b->v[k] = b->P[k] * b->inv_mass;
            mul(b->inv_world, b->L, b->w);
        } else {
            const double *v = w->y + w->off[TB__PARTICLE_VEL] + 3 * b->slot;
            memset(b->turn, 0, sizeof b->turn);
            for (k = 0; k < 3; ++k) {
                b->v[k] = v[k];
                b->P[k] = v[k] / b->inv_mass;
            }
        }
        memset(b->dp, 0, sizeof b->dp);
        memset(b->dtheta, 0, sizeof b->dtheta);
    }
}

/* The precomputed rows of point p (see tb__point). */
static void set_rows(const tb__contacts *c, const tb__entry *e, tb__point *p)
{
    int d, k;
    for (d = 0; d < 3; ++d) {
        const double *dir = d == 0 ? e->normal : e->tangent[d - 1];
        for (k = 0; k < 2; ++k) {
            const int32_t i = k ? e->body_b : e->body_a;
            double *arm = k ? p->arm_b[d] : p->arm_a[d], *turn = k ? p->turn_b[d] : p->turn_a[d];
            if (i < 0 || c->bodies[i].tier != TB__BODIES) {
                memset(arm, 0, 3 * sizeof(double));
                memset(turn, 0, 3 * sizeof(double));
                continue;
            }
            cross(k ? p->rb : p->ra, dir, arm);
            mul(c->bodies[i].inv_world, arm, turn);
        }
    }
}

/* Relative velocity of the anchors along row d. */
static double row_velocity(const tb__contacts *c, const tb__entry *e, const tb__point *p, int d, const double *dir)
{
    double v = 0;
    if (e->body_b >= 0) {
        const tb__solver_body *b = &c->bodies[e->body_b];
        v += dot3(dir, b->v) + dot3(p->arm_b[d], b->w);
    }
    if (e->body_a >= 0) {
        const tb__solver_body *a = &c->bodies[e->body_a];
        v -= dot3(dir, a->v) + dot3(p->arm_a[d], a->w);
    }
    return v;
}

/* An impulse lambda along row d: -lambda on a, +lambda on b. */
static void row_impulse(tb__contacts *c, const tb__entry *e, const tb__point *p, int d, const double *dir,
                        double lambda)
{
    int k, j;
    for (k = 0; k < 2; ++k) {
        const int32_t i = k ? e->body_b : e->body_a;
        const double l = k ? lambda : -lambda;
        const double *arm = k ? p->arm_b[d] : p->arm_a[d], *turn = k ? p->turn_b[d] : p->turn_a[d];
        tb__solver_body *b;
        if (i < 0)
            continue;
        b = &c->bodies[i];
        for (j = 0; j < 3; ++j) {
            b->P[j] += l * dir[j];
            b->v[j] += l * dir[j] * b->inv_mass;
            b->L[j] += l * arm[j];
            b->w[j] += l * turn[j];
        }
    }
}

/* 1 / (J M^-1 J^T) of row d: the impulse that changes its velocity by 1. */
static double row_mass(const tb__contacts *c, const tb__entry *e, const tb__point *p, int d)
{
    double k = 0;
    if (e->body_a >= 0)
        k += c->bodies[e->body_a].inv_mass + dot3(p->arm_a[d], p->turn_a[d]);
    if (e->body_b >= 0)
        k += c->bodies[e->body_b].inv_mass + dot3(p->arm_b[d], p->turn_b[d]);
    return k > 0 ? 1 / k : 0;
}

/* Where the free motion took each point; its impact timing and targets. */
static void set_up_points(tb__contacts *c, double h)
{
    const tb_contact_settings *s = &c->settings;
    size_t i;
    for (i = 0; i < c->entry_count; ++i) {
        tb__entry *e = &c->entries[i];
        int k, j;
        for (k = 0; k < e->count; ++k) {
            tb__point *p = &e->point[k];
            double pa[3], pb[3], d[3];
            /* the arms keep their start-of-step direction: a rolling ball's
               contact stays under its centre, not on the material point
               carried round (whose arm would make the normal force spin it
               up); the free motion's turn moves the anchors to first order */
            anchor(c, e->body_a, p->point, p->ra, pa);
            anchor(c, e->body_b, p->point, p->rb, pb);
            /* where the contact point was at the start is where both
               anchors were; the separation grew by their relative motion */
            for (j = 0; j < 3; ++j)
                d[j] = pb[j] - pa[j];
            p->predicted = p->separation + dot3(d, e->normal);
            set_rows(c, e, p);
            p->normal_mass = row_mass(c, e, p, 0);
            p->tangent_mass[0] = row_mass(c, e, p, 1);
            p->tangent_mass[1] = row_mass(c, e, p, 2);
            /* closed, or within a fifth of the slop of it: a resting point
               must not drop out of the solve for a rounding-sized gap */
            p->active = p->predicted <= 0.2 * s->slop;
            p->speed = 0;
            p->position_impulse = 0;
            if (!p->active) {
                p->normal_impulse = p->tangent_impulse[0] = p->tangent_impulse[1] = 0;
                continue;
            }
            if ((p->separation > 0 && !p->matched) || p->separation > 0.2 * s->slop) {
                /* a new contact: when in the step did the gap close? Its
                   normal motion, s + u t + a t^2 / 2 with the free motion's
                   acceleration a, reaches 0 at tau */
                const double u = p->approach, vn = row_velocity(c, e, p, 0, e->normal), a = (vn - u) / h;
                double tau, disc, vi;
                disc = u * u - 2 * a * p->separation;
                if (a != 0 && disc >= 0)
                    tau = (-u - sqrt(disc)) / a;
                else
                    tau = u < 0 ? -p->separation / u : h;
                if (!(tau >= 0 && tau <= h))
                    tau = u < 0 ? fmin(h, -p->separation / u) : h;
                vi = -(u + a * tau); /* approach speed at impact */
                p->speed = fmax(vi, 0);
                p->lever = h - tau;
                p->target = vi > s->restitution_threshold && e->restitution > 0
                                ? e->restitution * vi + a * (h - tau)
                                : 0;
                p->normal_impulse = p->tangent_impulse[0] = p->tangent_impulse[1] = 0;
            } else {
                p->lever = h / 2; /* a contact force acting through the step */
                p->target = 0;
            }
        }
    }
}

/* One Gauss-Seidel sweep over the touching points: friction first, within
   the circle mu * normal impulse, then the normal, v_n >= target. */
static void solve_velocities(tb__contacts *c)
{
    size_t n;
    for (n = 0; n < c->entry_count; ++n) {
        tb__entry *e = &c->entries[n];
        int k;
        for (k = 0; k < e->count; ++k) {
            tb__point *p = &e->point[k];
            double lambda, total, limit, t0, t1, len;
            if (!p->active)
                continue;
            limit = e->friction * p->normal_impulse;
            t0 = p->tangent_impulse[0] - p->tangent_mass[0] * row_velocity(c, e, p, 1, e->tangent[0]);
            t1 = p->tangent_impulse[1] - p->tangent_mass[1] * row_velocity(c, e, p, 2, e->tangent[1]);
            len = sqrt(t0 * t0 + t1 * t1);
            if (len > limit && len > 0)
                t0 *= limit / len, t1 *= limit / len;
            row_impulse(c, e, p, 1, e->tangent[0], t0 - p->tangent_impulse[0]);
            row_impulse(c, e, p, 2, e->tangent[1], t1 - p->tangent_impulse[1]);
            p->tangent_impulse[0] = t0, p->tangent_impulse[1] = t1;
            lambda = -p->normal_mass * (row_velocity(c, e, p, 0, e->normal) - p->target);
            total = fmax(p->normal_impulse + lambda, 0);
            row_impulse(c, e, p, 0, e->normal, total - p->normal_impulse);
            p->normal_impulse = total;
        }
    }
}

static void warm_start(tb__contacts *c)
{
    size_t i;
    for (i = 0; i < c->entry_count; ++i) {
        const tb__entry *e = &c->entries[i];
        int k;
        for (k = 0; k < e->count; ++k) {
            const tb__point *p = &e->point[k];
            if (!p->active)
                continue;
            row_impulse(c, e, p, 0, e->normal, p->normal_impulse);
            row_impulse(c, e, p, 1, e->tangent[0], p->tangent_impulse[0]);
            row_impulse(c, e, p, 2, e->tangent[1], p->tangent_impulse[1]);
        }
    }
}

/* Positions move as the impulses would have moved them over their lever
   time. */
static void apply_levers(tb__contacts *c)
{
    size_t i;
    for (i = 0; i < c->entry_count; ++i) {
        const tb__entry *e = &c->entries[i];
        int k, j;
        for (k = 0; k < e->count; ++k) {
            const tb__point *p = &e->point[k];
            double J[3];
            if (!p->active)
                continue;
            for (j = 0; j < 3; ++j)
                J[j] = p->normal_impulse * e->normal[j] + p->tangent_impulse[0] * e->tangent[0][j] +
                       p->tangent_impulse[1] * e->tangent[1][j];
            shift(c, e->body_a, p->ra, J, -p->lever);
            shift(c, e->body_b, p->rb, J, p->lever);
        }
    }
}

/* Push overlaps apart (positions only): gaps that closed this step are
   closed rigidly; overlap that was already there is taken back at the rate
   of a spring-damper of the contact hertz and damping ratio, at most
   max_push, so that what an unconverged velocity pass lets sink each step
   settles at a small fixed overlap instead of adding up. */
static void solve_positions(tb__contacts *c, double h)
{
    const tb_contact_settings *s = &c->settings;
    const double omega = 2 * 3.14159265358979323846 * s->hertz;
    const double rate = omega / (2 * s->damping_ratio + h * omega); /* 1/s */
    const double fraction = fmin(1, h * rate);
    size_t i;
    for (i = 0; i < c->entry_count; ++i) {
        tb__entry *e = &c->entries[i];
        int k, j;
        for (k = 0; k < e->count; ++k) {
            tb__point *p = &e->point[k];
            double target, now, lambda, total, J[3];
            if (p->separation >= 0)
                target = 0;
            else
                target = p->separation + fmin(fraction * -p->separation, h * s->max_push);
            now = separation_now(c, e, p);
            if (now >= target && p->position_impulse == 0)
                continue;
            lambda = -p->normal_mass * (now - target);
            total = fmax(p->position_impulse + lambda, 0);
            lambda = total - p->position_impulse;
            p->position_impulse = total;
            for (j = 0; j < 3; ++j)
                J[j] = lambda * e->normal[j];
            shift(c, e->body_a, p->ra, J, -1);
            shift(c, e->body_b, p->rb, J, 1);
        }
    }
}

static void store_bodies(tb_world *w, tb__contacts *c)
{
    size_t i;
    for (i = 0; i < c->body_count; ++i) {
        const tb__solver_body *b = &c->bodies[i];
        int k;
        if (b->tier == TB__BODIES) {
            double *x = w->y + w->off[TB__BODY_POS] + 3 * b->slot, *q = w->y + w->off[TB__BODY_ROT] + 4 * b->slot;
            const double turn[4] = { 0, 0.5 * b->dtheta[0], 0.5 * b->dtheta[1], 0.5 * b->dtheta[2] };
            double dq[4];
            for (k = 0; k < 3; ++k)
                x[k] += b->dp[k];
            quat_mul(turn, q, dq);
            for (k = 0; k < 4; ++k)
                q[k] += dq[k];
            normalise(q);
            memcpy(w->y + w->off[TB__BODY_MOM] + 3 * b->slot, b->P, sizeof b->P);
            memcpy(w->y + w->off[TB__BODY_ANG] + 3 * b->slot, b->L, sizeof b->L);
        } else {
            double *x = w->y + w->off[TB__PARTICLE_POS] + 3 * b->slot, *v = w->y + w->off[TB__PARTICLE_VEL] + 3 * b->slot;
            for (k = 0; k < 3; ++k) {
                x[k] += b->dp[k];
                v[k] = b->v[k];
            }
        }
    }
}

/* A zeroed event of `type` between the keys, appended to the list. */
static tb_status push_event(tb_world *w, tb__contacts *c, tb_contact_event_type type, const tb__entry *e,
                            tb_contact_event **out)
{
    tb_status st = tb__contacts_reserve(w, (void **)&c->events, &c->event_cap, c->event_count + 1, sizeof **out);
    if (st != TB_OK)
        return st;
    *out = &c->events[c->event_count++];
    memset(*out, 0, sizeof **out);
    (*out)->type = type;
    (*out)->a.index1 = e->key_a;
    (*out)->b.index1 = e->key_b;
    return TB_OK;
}

/* Begin and end events: entries touching now against last step's. */
static tb_status make_events(tb_world *w, tb__contacts *c)
{
    size_t i, j = 0;
    tb_status st;
    c->event_count = 0;
    c->touching_points = 0;
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
    /* merge the two sorted lists */
    for (i = 0; i <= c->entry_count; ++i) {
        const tb__entry *e = i < c->entry_count ? &c->entries[i] : NULL;
        while (j < c->previous_count &&
               (!e || entry_order(&c->previous[j], e) < 0)) { /* gone: ended if it touched */
            const tb__entry *old = &c->previous[j++];
            tb_contact_event *ev;
            if (old->touching && (st = push_event(w, c, TB_CONTACT_END, old, &ev)) != TB_OK)
                return st;
        }
        if (!e)
            break;
        {
            const int was = j < c->previous_count && entry_order(&c->previous[j], e) == 0 && c->previous[j].touching;
            if (j < c->previous_count && entry_order(&c->previous[j], e) == 0)
                ++j;
            if (e->touching != was) {
                tb_contact_event *ev;
                int k;
                if ((st = push_event(w, c, e->touching ? TB_CONTACT_BEGIN : TB_CONTACT_END, e, &ev)) != TB_OK)
                    return st;
                memcpy(ev->normal, e->normal, sizeof ev->normal);
                for (k = 0; k < e->count; ++k)
                    if (e->point[k].active) {
                        ev->speed = fmax(ev->speed, e->point[k].speed > 0 ? e->point[k].speed
                                                                         : fmax(0, -e->point[k].approach));
                        anchor(c, e->body_a, e->point[k].point, e->point[k].ra, ev->point);
                    }
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

/* Touching points, and those of them that did not touch last step. */
static void count_points(const tb__contacts *c, size_t *active, size_t *cold)
{
    size_t i;
    int k;
    *active = *cold = 0;
    for (i = 0; i < c->entry_count; ++i)
        for (k = 0; k < c->entries[i].count; ++k) {
            const tb__point *p = &c->entries[i].point[k];
            *active += p->active;
            *cold += p->active && !p->matched;
        }
}

void tb__contacts_solve(tb_world *w, double h)
{
    tb__contacts *c = w->contacts;
    size_t active, cold;
    int it, iterations;
    if (!c->prepared)
        return;
    load_bodies(w, c);
    set_up_points(c, h);
    warm_start(c);
    /* a contact without last step's impulses to start from needs more
       sweeps to reach them: a stack built at rest would otherwise sink and
       lean in its first steps */
    count_points(c, &active, &cold);
    iterations = c->settings.velocity_iterations * (8 * cold > active ? 4 : 1);
    for (it = 0; it < iterations; ++it)
        solve_velocities(c);
    apply_levers(c);
    for (it = 0; it < c->settings.position_iterations; ++it)
        solve_positions(c, h);
    store_bodies(w, c);
    if (make_events(w, c) != TB_OK)
        c->event_count = 0; /* out of memory for events: the step itself stands */
    c->prepared = 0;
    c->solved = 1;
}
