/* sleep.c: islands of resting bodies fall asleep, and wake when something
   reaches them (the rules: include/tumble.h, "Sleep", and docs/contacts.md).

   Each step, after the solve, a body with shapes that is slower than
   sleep_speed (|v| + |w| times its shapes' reach) and moved less than
   sleep_speed times the step adds the step to its rest time (any other
   step resets it). Bodies joined by touching contacts form islands
   (union-find over this step's entries); an island whose every body has
   rested sleep_time falls asleep under one tag, with zero momenta. While
   it sleeps its pairs are not collided but parked, as they were (so no
   end events, and warm starts ready for when it wakes: contact.c, park),
   the solver
   leaves it out, and its pose is put back after the integrator's free
   motion. Worlds with force callbacks never sleep. */
#include "contacts/contacts.h"
#include "joints/joints.h"

#include <math.h>
#include <string.h>

static int sleep_allowed(const tb_world *w)
{
    return w->contacts && isfinite(w->contacts->settings.sleep_time) && w->forces.count == 0;
}

int tb__key_still(const tb_world *w, const tb__contacts *c, uint32_t key)
{
    const tb__shape *s;
    uint32_t slot;
    if (key & TB__PARTICLE_KEY)
        return 0;
    s = &c->shapes[c->ids.slot[key - 1]];
    return !s->body || !tb__ids_lookup(&w->body_ids, s->body, s->body_generation, &slot) || w->body_island[slot];
}

uint32_t tb__proxy_island(const tb_world *w, const tb__contacts *c, size_t k)
{
    return c->owner[k] ? w->body_island[c->owner[k] - 1] : 0;
}

/* Does proxy k move this step: an awake body that is not resting (its
   rest time is 0: it was not slower than the sleep speed last step, or it
   was just added, set or woken), or a particle faster than the sleep
   speed? A resting body wakes nothing, or neighbouring islands within
   each other's bounds, falling asleep at different times, would wake
   each other for ever (test_contacts_sleep.resting_neighbours_let_an_island_sleep). */
static int moving(const tb_world *w, const tb__contacts *c, size_t k)
{
    if (c->proxy[k] & TB__PARTICLE_KEY) {
        const double *v = w->y + w->off[TB__PARTICLE_VEL] + 3 * (c->proxy[k] & ~TB__PARTICLE_KEY);
        return tb__norm3(v) > c->settings.sleep_speed;
    }
    return c->owner[k] && !w->body_island[c->owner[k] - 1] && w->body_rest[c->owner[k] - 1] == 0;
}

int tb__sleep_wakes(const tb_world *w, const tb__contacts *c)
{
    size_t i;
    if (!w->body_sleeping)
        return 0;
    for (i = 0; i < c->pair_count; ++i) {
        const uint32_t a = c->pairs[i].a, b = c->pairs[i].b;
        if ((tb__proxy_island(w, c, a) && moving(w, c, b)) || (tb__proxy_island(w, c, b) && moving(w, c, a)))
            return 1;
    }
    return 0;
}

tb_status tb__sleep_prepare(tb_world *w, tb__contacts *c)
{
    size_t i, b, n = 0;
    int skipped;
    tb_status st;
    if (!w->body_sleeping) { /* (all woken since the last step: no pose to put back) */
        c->pose_count = 0;
        return TB_OK;
    }
    /* wake what moving things reach: their bounds already hold the step's
       motion */
    for (i = 0; i < c->pair_count; ++i) {
        const uint32_t a = c->pairs[i].a, b = c->pairs[i].b;
        const uint32_t ia = tb__proxy_island(w, c, a), ib = tb__proxy_island(w, c, b);
        if (ia && moving(w, c, b))
            tb__wake_island(w, ia);
        else if (ib && moving(w, c, a))
            tb__wake_island(w, ib);
    }
    /* the poses to put back after the free motion, but for those the
       integrator leaves alone: a split method moves bodies by the sweep
       alone, which passes over blocks whose bodies all sleep (so a sleeping
       pile costs no integration either) */
    if ((st = tb__reserve(w, (void **)&c->poses, &c->pose_cap, w->body_sleeping + 1, sizeof *c->poses)) != TB_OK)
        return st;
    skipped = w->method->split && tb__body_sweep_skips_sleeping(w);
    for (b = 0; b < w->body_count && n < w->body_sleeping; b += TB__LANES) {
        const size_t m = w->body_count - b < TB__LANES ? w->body_count - b : TB__LANES;
        if (skipped && tb__body_block_asleep(w, b, m))
            continue;
        for (i = b; i < b + m; ++i)
            if (w->body_island[i]) {
                tb__pose *p = &c->poses[n++];
                p->slot = (uint32_t)i;
                memcpy(p->x, w->y + w->off[TB__BODY_POS] + 3 * i, sizeof p->x);
                memcpy(p->q, w->y + w->off[TB__BODY_ROT] + 4 * i, sizeof p->q);
            }
    }
    c->pose_count = n;
    return TB_OK;
}

void tb__sleep_restore(tb_world *w, tb__contacts *c)
{
    size_t i;
    for (i = 0; i < c->pose_count; ++i) {
        const tb__pose *p = &c->poses[i];
        memcpy(w->y + w->off[TB__BODY_POS] + 3 * p->slot, p->x, sizeof p->x);
        memcpy(w->y + w->off[TB__BODY_ROT] + 4 * p->slot, p->q, sizeof p->q);
        memset(w->y + w->off[TB__BODY_MOM] + 3 * p->slot, 0, 3 * sizeof(double));
        memset(w->y + w->off[TB__BODY_ANG] + 3 * p->slot, 0, 3 * sizeof(double));
    }
}

static uint32_t root_of(uint32_t *link, uint32_t s)
{
    while (link[s] != s)
        s = link[s] = link[link[s]];
    return s;
}

void tb__sleep_update(tb_world *w, tb__contacts *c, double h)
{
    const size_t n = w->body_count;
    size_t i;
    uint32_t *link, *tag;
    double *reach, *least;
    /* (every body asleep: none can fall asleep, and the passes below would
       look at each only to pass it over) */
    if (!sleep_allowed(w) || n == 0 || w->body_sleeping == n)
        return;
    if (tb__reserve(w, (void **)&c->island_scratch, &c->island_scratch_cap, 3 * n, sizeof(double)) != TB_OK)
        return; /* out of memory: nothing falls asleep this step */
    reach = c->island_scratch, least = reach + n, link = (uint32_t *)(least + n), tag = link + n;
    for (i = 0; i < n; ++i) {
        reach[i] = 0;
        least[i] = INFINITY;
        link[i] = (uint32_t)i;
        tag[i] = 0;
    }
    /* the reach of the awake bodies' shapes, from their proxies (every
       shape of a body has one, made this step) */
    for (i = 0; i < c->proxy_count; ++i) {
        const uint32_t owner = c->owner[i];
        if (owner && !w->body_island[owner - 1])
            reach[owner - 1] = fmax(reach[owner - 1], c->shapes[c->proxy[i]].reach);
    }
    /* rest times */
    for (i = 0; i < n; ++i) {
        double v[3], omega[3];
        if (w->body_island[i] || reach[i] == 0)
            continue;
        tb__body_velocity(w, (uint32_t)i, v, omega);
        w->body_rest[i] = tb__norm3(v) + tb__norm3(omega) * reach[i] < c->settings.sleep_speed ? w->body_rest[i] + h : 0;
    }
    /* ... and that moved slower than that over the step: the push out of
       overlaps moves a body without giving it speed
       (buried_plank_comes_out_before_it_sleeps) */
    for (i = 0; i < c->body_count; ++i) {
        const tb__solver_body *b = &c->bodies[i];
        const double *x, *q;
        double dx[3], turn[4];
        const double q0c[4] = { b->q0[0], -b->q0[1], -b->q0[2], -b->q0[3] };
        int k;
        if (b->tier != TB__BODIES || w->body_island[b->slot] || w->body_rest[b->slot] == 0)
            continue;
        x = w->y + w->off[TB__BODY_POS] + 3 * b->slot, q = w->y + w->off[TB__BODY_ROT] + 4 * b->slot;
        for (k = 0; k < 3; ++k)
            dx[k] = x[k] - b->x0[k];
        tb__quat_mul(q, q0c, turn); /* (cos, sin n) of half the step's turn */
        if (tb__norm3(dx) + 2 * tb__norm3(turn + 1) * reach[b->slot] >= c->settings.sleep_speed * h)
            w->body_rest[b->slot] = 0;
    }
    /* islands: bodies joined by touching contacts this step */
    for (i = 0; i < c->entry_count; ++i) {
        const tb__entry *e = &c->entries[i];
        const tb__solver_body *a, *b;
        if (!e->touching || e->asleep || e->body_a < 0 || e->body_b < 0)
            continue;
        a = &c->bodies[e->body_a], b = &c->bodies[e->body_b];
        if (a->tier == TB__BODIES && b->tier == TB__BODIES)
            link[root_of(link, a->slot)] = root_of(link, b->slot);
    }
    /* ... and by joints: an island sleeps whole. A body without shapes
       (no reach to rest by) or tied to a particle (particles never sleep)
       keeps its island awake (test_joints.jointed_bodies_sleep_together) */
    for (i = 0; i < w->joint_count; ++i) {
        const int32_t a = tb__joint_end_slot(w, i, 0), b = tb__joint_end_slot(w, i, 1);
        if (a >= 0 && b >= 0)
            link[root_of(link, (uint32_t)a)] = root_of(link, (uint32_t)b);
    }
    for (i = 0; i < n; ++i)
        if (!w->body_island[i] && reach[i] > 0) {
            const uint32_t r = root_of(link, (uint32_t)i);
            least[r] = fmin(least[r], w->body_rest[i]);
        }
    for (i = 0; i < w->joint_count; ++i) {
        const int32_t a = tb__joint_end_slot(w, i, 0), b = tb__joint_end_slot(w, i, 1);
        const int32_t ends[2] = { a, b };
        int k;
        for (k = 0; k < 2; ++k)
            if (ends[k] >= 0 && (reach[ends[k]] == 0 || tb__joint_is_particle(ends[1 - k])))
                least[root_of(link, (uint32_t)ends[k])] = 0;
    }
    /* islands that all rested long enough fall asleep, tagged by a fresh
       number (kept apart from 0, which means awake) */
    for (i = 0; i < n; ++i) {
        uint32_t r;
        if (w->body_island[i] || reach[i] == 0)
            continue;
        r = root_of(link, (uint32_t)i);
        if (!(least[r] >= c->settings.sleep_time))
            continue;
        if (!tag[r]) { /* the island's first body */
            if (++c->next_island == 0)
                ++c->next_island;
            tag[r] = c->next_island;
        }
        w->body_island[i] = tag[r];
        memset(w->y + w->off[TB__BODY_MOM] + 3 * i, 0, 3 * sizeof(double));
        memset(w->y + w->off[TB__BODY_ANG] + 3 * i, 0, 3 * sizeof(double));
        w->body_sleeping++;
    }
}

tb_status tb_body_asleep(const tb_world *w, tb_body_id id, int *asleep)
{
    uint32_t s;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    st = tb__body_find(w, id, &s);
    if (st != TB_OK)
        return st;
    if (!asleep)
        return tb__null((tb_world *)w, "tb_body_asleep", "the output");
    *asleep = w->body_island[s] != 0;
    return TB_OK;
}

tb_status tb_body_wake(tb_world *w, tb_body_id id)
{
    uint32_t s;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "wake a body")) != TB_OK || (st = tb__body_find(w, id, &s)) != TB_OK)
        return st;
    tb__wake_body(w, s);
    return TB_OK;
}

size_t tb_world_sleeping_count(const tb_world *w)
{
    TB__NEED_WORLD(w, 0);
    return w->body_sleeping;
}
