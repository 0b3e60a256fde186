/* continuous.c: the soft step's last pass, against bodies passing
   through static shapes (docs/contacts.md, "Time of impact"). A step's
   manifolds hold the features closest at its start; a body that turns far
   within the step (a thin plate struck and spun to a radian a step)
   brings others through a static shape that no row holds. So after the
   substeps a body that ends deeper than the slop in a static shape it was
   clear of at the start, and deeper by the slop than its patch's rows
   know, is taken back along its step to where it first comes within half
   the slop of that shape (one that touched it at the start: to where it
   first goes a slop deeper than then): its time of impact, by
   conservative advancement,
   as Box2D v3's continuous pass does for fast bodies. Overlaps the rows
   know are theirs (taken back, bodies sunk under a load landed in their
   neighbours and a dropped heap's capsule went 13 cm into the plane).
   Its velocities stay, scaled down by what gravity gives back of the fall
   it is taken back up: the pass never adds energy
   (test_contacts_stress.heaps_built_overlapping,
   test_contacts_soft.soft_step_spinning_plate_stays_on_the_slab). */
#include "contacts/soft_step.h"

#include <math.h>
#include <string.h>

/* Advances at most: past them the body is taken back to the last, where
   it is still clear (left where it ended, a plate of 2 m spun to 88
   rad/s by its landing, whose advances creep at its sweep of 2.3 m,
   ended 0.15 m under the plane: test_contacts_stress.extreme_heaps) */
#define TB__TOI_STEPS 32

static double dot4(const double a[4], const double b[4])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
}

/* The pose a share t along body i's step: its centre on the line from
   start to end, its orientation on the great arc (normalised linear
   interpolation, whose turn runs at most 4 / pi times its mean rate) */
static void pose_at(const tb__contacts *c, int32_t i, double t, double x[3], double q[4])
{
    const tb__solver_body *b = &c->bodies[i];
    const tb__soft_body *s = &c->soft_bodies[i];
    const double sign = dot4(b->q0, s->q) < 0 ? -1 : 1;
    int k;
    for (k = 0; k < 3; ++k)
        x[k] = b->x0[k] + t * (s->x[k] - b->x0[k]);
    for (k = 0; k < 4; ++k)
        q[k] = b->q0[k] + t * (sign * s->q[k] - b->q0[k]);
    tb__normalise(q);
}

/* The distance between a body's shape at (x, q) and a static one, down
   to -margin... margin (deeper overlaps give their depth, gaps beyond
   margin give margin): the deepest point of their manifold, which never
   exceeds the true distance (exact for points, a separating axis's
   distance for boxes) */
static double distance(const tb__shape *moving, const double x[3], const double q[4], const tb__geom *fixed,
                       double margin)
{
    tb__geom g;
    tb__manifold m;
    double deepest = -margin;
    int k;
    tb__place_shape(moving, x, q, &g);
    if (tb__collide(&g, fixed, margin, 0, &m) == 0) /* no face tolerance: the best axis */
        return margin;
    for (k = 0; k < m.count; ++k)
        deepest = fmax(deepest, m.point[k].depth);
    return -deepest;
}

/* The share of body i's step (0 to 1) at which its shape first comes
   within twice target of the static shape, or, if it touched the shape at
   the start, first goes a slop deeper into it than then (a block lying on
   the plane, struck and spun, dug a corner 0.2 m in), by conservative
   advancement; 1 when it does not, or when it ends no deeper than the
   slop or than `known` (the least separation of the patch's rows) less
   the slop. `sweep`: the most any point of the shape moves over the step
   (m), so that an advance of the distance over it never passes the first
   touch. */
static double impact_share(const tb__contacts *c, int32_t i, const tb__shape *moving, const tb__geom *fixed,
                           double sweep, double target, double known)
{
    const tb__solver_body *b = &c->bodies[i];
    const double slop = c->settings.slop;
    double x[3], q[4], t = 0, end, level;
    int k;
    pose_at(c, i, 1, x, q);
    end = distance(moving, x, q, fixed, slop);
    if (end >= -slop || end >= known - slop)
        return 1; /* not deeper than the slop at the end, or known to the rows */
    level = distance(moving, b->x0, b->q0, fixed, sweep + target);
    level = level > 2 * target ? target : level - slop;
    for (k = 0; k < TB__TOI_STEPS; ++k) {
        double d;
        pose_at(c, i, t, x, q);
        d = distance(moving, x, q, fixed, sweep + target);
        if (d <= level + target)
            return k == 0 ? 1 : t;
        t += (d - level) / sweep;
        if (t >= 1)
            return 1;
    }
    return t;
}

/* Body i taken back to share t of its step, its energy kept from rising:
   its kinetic energy at most what it was less what gravity gives back,
   counted at its new orientation, where the same L may spin it faster (a
   rod's L turned onto its axis, of thousands of times less inertia, spun
   it from 292 to 12110 rad/s: test_contacts_stress.extreme_heaps) */
static void take_back(tb_world *w, tb__contacts *c, int32_t i, double t)
{
    const tb__solver_body *b = &c->bodies[i];
    tb__soft_body *s = &c->soft_bodies[i];
    const double before = 0.5 * (tb__dot3(s->P, s->v) + tb__dot3(s->L, s->w));
    double x[3], q[4], kinetic, rise, scale;
    int k;
    pose_at(c, i, t, x, q);
    /* what gravity gives back of the fall from x to the end */
    rise = 0;
    for (k = 0; k < 3; ++k)
        rise -= w->gravity[k] * (x[k] - s->x[k]);
    rise /= b->inv_mass;
    memcpy(s->x, x, sizeof s->x);
    memcpy(s->q, q, sizeof s->q);
    for (k = 0; k < 3; ++k)
        s->shift[k] = s->x[k] - b->x0[k];
    tb__soft_turned(c, (size_t)i);
    kinetic = 0.5 * (tb__dot3(s->P, s->v) + tb__dot3(s->L, s->w));
    if (kinetic <= before - rise || kinetic <= 0)
        return;
    scale = sqrt(fmax(before - rise, 0) / kinetic);
    for (k = 0; k < 3; ++k) {
        s->P[k] *= scale, s->v[k] *= scale;
        s->L[k] *= scale, s->w[k] *= scale;
    }
}

void tb__soft_continuous(tb_world *w, tb__contacts *c)
{
    const double target = 0.25 * c->settings.slop;
    size_t p;
    for (p = 0; p < c->soft_patch_count; ++p) {
        const tb__soft_patch *pa = &c->soft_patches[p];
        const tb__entry *e = pa->entry;
        const int32_t i = e->body_a >= 0 ? e->body_a : e->body_b;
        const uint32_t fixed_key = e->body_a >= 0 ? e->key_b : e->key_a;
        const uint32_t moving_key = e->body_a >= 0 ? e->key_a : e->key_b;
        const tb__shape *fixed, *moving;
        const tb__solver_body *b;
        const tb__soft_body *s;
        double sweep, turn, t, known = INFINITY, moved[3];
        size_t r;
        int k;
        tb__geom g;
        if ((e->body_a >= 0) == (e->body_b >= 0) || (moving_key & TB__PARTICLE_KEY) || (fixed_key & TB__PARTICLE_KEY))
            continue; /* two bodies, or none, or a particle */
        b = &c->bodies[i], s = &c->soft_bodies[i];
        if (b->tier != TB__BODIES)
            continue;
        fixed = &c->shapes[c->ids.slot[fixed_key - 1]];
        moving = &c->shapes[c->ids.slot[moving_key - 1]];
        if (fixed->body)
            continue; /* a sleeping body's shape: its pose is not the shape's own */
        turn = 2 * acos(fmin(fabs(dot4(b->q0, s->q)), 1));
        for (k = 0; k < 3; ++k)
            moved[k] = s->x[k] - b->x0[k];
        sweep = tb__norm3(moved) + 4 / 3.14159265358979323846 * turn * moving->reach;
        if (!(sweep > target))
            continue;
        for (r = 0; r < pa->count; ++r)
            known = fmin(known, tb__soft_separation(c, &c->soft_rows[pa->first + r]));
        tb__place_shape(fixed, NULL, NULL, &g);
        t = impact_share(c, i, moving, &g, sweep, target, known);
        if (t < 1)
            take_back(w, c, i, t);
    }
}
