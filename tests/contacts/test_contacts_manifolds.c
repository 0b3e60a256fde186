/* test_contacts_manifolds.c: manifolds kept from step to step. A resting
   pair keeps last step's manifold, moved with its shapes, which must
   agree with colliding them afresh; what moves is collided every step. */
#include "test_main.h"
#include "contacts/contacts.h"
#include "tumble.h"
#include "contact_scenes.h"

#include <math.h>
#include <string.h>

static tb_world *plane_world(double restitution)
{
    tb_world_def def = tb_default_world_def();
    tb_shape_def plane = tb_default_shape_def();
    tb_contact_settings s = tb_default_contact_settings();
    tb_world *w;
    char message[TB_MESSAGE_SIZE];
    assert_int_equal(tb_world_create(&def, &w, message, sizeof message), TB_OK);
    plane.type = TB_SHAPE_PLANE;
    plane.restitution = restitution;
    assert_int_equal(tb_world_add_shape(w, &plane, NULL), TB_OK);
    s.sleep_time = INFINITY; /* the solver itself, every step */
    assert_int_equal(tb_world_set_contact_settings(w, &s), TB_OK);
    return w;
}

/* A pyramid of `levels` unit cubes 1 cm apart, as the bench's. */
static int add_pyramid(tb_world *w, int levels, tb_body_id *ids)
{
    const double none[3] = { 0, 0, 0 };
    int level, i, n = 0;
    for (level = 0; level < levels; ++level)
        for (i = 0; i < levels - level; ++i) {
            const double at[3] = { (i - (levels - level - 1) / 2.0) * 1.01, 0, 0.5 + level };
            tb_body_id id = add_solid(w, TB_SHAPE_BOX, at, none, none, 1);
            if (ids)
                ids[n] = id;
            ++n;
        }
    return n;
}

/* The shape with id index1 key, placed in the world as this step's
   narrowphase placed it; returns how far it could move this step. */
static double geom_of(const tb__contacts *c, uint32_t key, tb__geom *g)
{
    const uint32_t slot = c->ids.slot[key - 1];
    const tb__shape *s = &c->shapes[slot];
    size_t k;
    if (s->kind == TB__SHAPE_PLANE) {
        memset(g, 0, sizeof *g);
        g->kind = TB__SHAPE_PLANE;
        memcpy(g->normal, s->normal, sizeof g->normal);
        g->offset = s->offset;
        g->rot[0] = g->rot[4] = g->rot[8] = 1;
        return 0;
    }
    for (k = 0; k < c->proxy_count; ++k)
        if (c->proxy[k] == slot) {
            *g = c->geoms[k];
            return c->margin[k];
        }
    fail_msg("shape %u has no proxy", key);
    return 0;
}

static double distance(const double a[3], const double b[3])
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/* Reused manifolds of this step against the shapes collided afresh (with
   this step's margins): every fresh point must be among the reused ones
   (by its pair of features, or failing that, when the clipping took the
   other box's face as reference, the nearest), at the same separation;
   a reused point the fresh collision leaves out must lie beyond the
   margin, as the fresh one does, unless it found one point only. Returns how many entries were reused;
   the worst differences out (the normal only where the features all
   match, that is where both took the same face's normal). */
static size_t compare_reused(const tb_world *w, double *separation, double *point, double *normal)
{
    const tb__contacts *c = w->contacts;
    size_t i, reused = 0;
    for (i = 0; i < c->entry_count; ++i) {
        const tb__entry *e = &c->entries[i];
        tb__geom a, b;
        tb__manifold fresh;
        double margin;
        int k, j, same = 1, found[TB__MANIFOLD_POINTS] = { 0 };
        if (!e->reused)
            continue;
        ++reused;
        margin = geom_of(c, e->key_a, &a) + geom_of(c, e->key_b, &b);
        tb__collide(&a, &b, margin, 0, &fresh);
        for (j = 0; j < fresh.count; ++j) {
            const tb__contact_point *f = &fresh.point[j];
            int match = -1;
            for (k = 0; k < e->count; ++k)
                if (e->point[k].feature == f->feature)
                    match = k;
            if (match < 0) {
                same = 0;
                for (k = 0; k < e->count; ++k)
                    if (match < 0 || distance(e->point[k].point, f->pos) < distance(e->point[match].point, f->pos))
                        match = k;
            }
            assert_true(match >= 0);
            found[match] = 1;
            *point = fmax(*point, distance(e->point[match].point, f->pos));
            *separation = fmax(*separation, fabs(-f->depth - e->point[match].separation));
        }
        /* (where the boxes' faces nearly tie with a pair of their edges,
           the fresh collision may take the edges, one point, which a
           manifold kept from a face collision does not) */
        for (k = 0; k < e->count && fresh.count > 1; ++k)
            if (!found[k])
                assert_true(e->point[k].separation > margin - 1e-6);
        for (j = 0; same && j < 3; ++j)
            *normal = fmax(*normal, fabs(fresh.normal[j] - e->normal[j]));
    }
    return reused;
}

/* A pyramid of 210 resting (sleep off, so it creeps and rocks a little)
   for 5 s: nine in ten pairs or more keep last step's manifold, and
   every kept one agrees with a fresh collision. A pair is kept while its relative pose
   has moved less than a tenth of the slop (0.5 mm) since it was last
   collided, turns included (turn times reach): the separations then
   differ by the second order of the turn (under 1e-6 m for these), the
   points by what slid and turned (each under 0.5 mm, so under 1 mm
   together; clipped corners move no more than the shapes do), the normal
   by the turn (under 0.5 mm over a reach of 0.87 m: 6e-4). */
static void reused_manifolds_match_fresh_ones(void **state)
{
    tb_world *w = plane_world(0);
    double separation = 0, point = 0, normal = 0;
    size_t reused = 0, entries = 0;
    int i;
    (void)state;
    add_pyramid(w, 20, NULL);
    for (i = 0; i < 300; ++i) {
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
        reused += compare_reused(w, &separation, &point, &normal);
        entries += w->contacts->entry_count;
    }
    print_message("pyramid, 5 s: %zu of %zu manifolds reused; worst differences from a fresh collision: separation "
                  "%.2e m, point %.2e m, normal %.2e\n", reused, entries, separation, point, normal);
    assert_true(reused > 0.9 * entries); /* measured 99.6% */
    assert_below(separation, 1e-6);
    assert_below(point, 1e-3);
    assert_below(normal, 6e-4);
    tb_world_destroy(w);
}

/* What moves is collided every step: a box sliding at 5 m/s and a ball
   rolling at 2 m/s never keep a manifold, however long they touch. */
static void moving_pairs_are_collided_afresh(void **state)
{
    tb_world *w = plane_world(0);
    const double box[3] = { 0, 0, 0.5 }, ball[3] = { 0, 3, 0.25 }, slide[3] = { 5, 0, 0 }, roll[3] = { 2, 0, 0 },
                 none[3] = { 0, 0, 0 }, spin[3] = { 0, 8, 0 };
    size_t touching = 0;
    int i;
    (void)state;
    add_solid(w, TB_SHAPE_BOX, box, slide, none, 1);
    add_solid(w, TB_SHAPE_SPHERE, ball, roll, spin, 0.5);
    for (i = 0; i < 30; ++i) {
        size_t k;
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
        for (k = 0; k < w->contacts->entry_count; ++k) {
            assert_false(w->contacts->entries[k].reused);
            touching += w->contacts->entries[k].touching;
        }
    }
    assert_int_equal(touching, 2 * 30);
    tb_world_destroy(w);
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(reused_manifolds_match_fresh_ones),
    cmocka_unit_test(moving_pairs_are_collided_afresh),
};

TB_TEST_MAIN(tests)
