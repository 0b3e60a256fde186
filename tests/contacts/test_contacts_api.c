/* test_contacts_api.c: the interface around contacts. Bad shapes and
   contact settings are refused, and ids stay honest while bodies, shapes
   and particles come and go between steps. */
#include "test_main.h"
#include "tumble.h"
#include "contact_scenes.h"

#include <math.h>
#include <string.h>

static void bad_shapes_are_refused(void **state)
{
    tb_world *w = world_on_plane(0.6, 0);
    const double at[3] = { 0, 0, 3 };
    tb_body_id body = add_box(w, at, 1, 0.6);
    tb_shape_def d;
    tb_contact_settings cs = tb_default_contact_settings();
    const size_t shapes = tb_world_shape_count(w);
    (void)state;
    d = tb_default_shape_def(), d.radius = 0;
    assert_int_equal(tb_world_add_shape(w, &d, NULL), TB_ERR_ARGUMENT);
    d = tb_default_shape_def(), d.radius = -1;
    assert_int_equal(tb_world_add_shape(w, &d, NULL), TB_ERR_ARGUMENT);
    d = tb_default_shape_def(), d.radius = NAN;
    assert_int_equal(tb_world_add_shape(w, &d, NULL), TB_ERR_ARGUMENT);
    d = tb_default_shape_def(), d.type = TB_SHAPE_BOX, d.half_extents[1] = 0;
    assert_int_equal(tb_world_add_shape(w, &d, NULL), TB_ERR_ARGUMENT);
    d = tb_default_shape_def(), d.type = TB_SHAPE_CAPSULE, d.half_length = -0.1;
    assert_int_equal(tb_world_add_shape(w, &d, NULL), TB_ERR_ARGUMENT);
    d = tb_default_shape_def(), d.position[0] = INFINITY;
    assert_int_equal(tb_world_add_shape(w, &d, NULL), TB_ERR_ARGUMENT);
    d = tb_default_shape_def(), d.type = TB_SHAPE_PLANE, d.normal[2] = 2;
    assert_int_equal(tb_world_add_shape(w, &d, NULL), TB_ERR_ARGUMENT);
    assert_non_null(strstr(tb_world_message(w), "unit"));
    d = tb_default_shape_def(), d.type = TB_SHAPE_PLANE, d.body = body;
    assert_int_equal(tb_world_add_shape(w, &d, NULL), TB_ERR_ARGUMENT);
    d = tb_default_shape_def(), d.restitution = 1.5;
    assert_int_equal(tb_world_add_shape(w, &d, NULL), TB_ERR_ARGUMENT);
    d = tb_default_shape_def(), d.orientation[0] = 0.5;
    assert_int_equal(tb_world_add_shape(w, &d, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_world_shape_count(w), shapes);
    cs.hertz = 0;
    assert_int_equal(tb_world_set_contact_settings(w, &cs), TB_ERR_ARGUMENT);
    cs = tb_default_contact_settings(), cs.substeps = 0;
    assert_int_equal(tb_world_set_contact_settings(w, &cs), TB_ERR_ARGUMENT);
    assert_non_null(strstr(tb_world_message(w), "substeps"));
    cs = tb_default_contact_settings(), cs.substeps = -1;
    assert_int_equal(tb_world_set_contact_settings(w, &cs), TB_ERR_ARGUMENT);
    cs = tb_default_contact_settings(), cs.slop = -1e-6;
    assert_int_equal(tb_world_set_contact_settings(w, &cs), TB_ERR_ARGUMENT);
    cs.slop = NAN;
    assert_int_equal(tb_world_set_contact_settings(w, &cs), TB_ERR_ARGUMENT);
    assert_true(tb_world_contact_settings(w).substeps == tb_default_contact_settings().substeps);
    /* a removed body takes its shapes with it; its id goes stale */
    assert_int_equal(tb_world_remove_body(w, body), TB_OK);
    assert_int_equal(tb_world_shape_count(w), shapes - 1);
    d = tb_default_shape_def(), d.body = body;
    assert_int_equal(tb_world_add_shape(w, &d, NULL), TB_ERR_STALE_ID);
    {
        tb_shape_id stale = { 77, 1 };
        assert_int_equal(tb_world_remove_shape(w, stale), TB_ERR_STALE_ID);
    }
    tb_world_destroy(w);
}

/* Every shape reads back as it was defined (a host draws from this):
   walked by slot, each kind's fields equal the definition's, the
   orientation normalised; a removed id, another world's id and a NULL
   output are refused with the world's message. */
static void shapes_read_back_as_defined(void **state)
{
    tb_world *w = world_on_plane(0.5, 0), *other = world_on_plane(0.5, 0);
    const double start[3] = { 0, 0, 2 };
    tb_body_id body = add_box(w, start, 1, 0.7);
    tb_shape_def made[3], got;
    tb_shape_id ids[3];
    size_t k, found = 0;
    (void)state;
    for (k = 0; k < 3; ++k) {
        made[k] = tb_default_shape_def();
        made[k].body = body;
        made[k].position[0] = 0.1 * (double)k;
    }
    made[0].type = TB_SHAPE_SPHERE, made[0].radius = 0.25, made[0].restitution = 0.5;
    made[1].type = TB_SHAPE_CAPSULE, made[1].radius = 0.1, made[1].half_length = 0.3;
    made[1].orientation[0] = sqrt(0.5) * (1 + 1e-8), made[1].orientation[1] = sqrt(0.5); /* normalised on the way in */
    made[2].type = TB_SHAPE_BOX, made[2].half_extents[0] = 0.1, made[2].half_extents[1] = 0.2;
    made[2].half_extents[2] = 0.3, made[2].rolling_resistance = 0.01, made[2].category = 4, made[2].mask = 6;
    for (k = 0; k < 3; ++k)
        assert_int_equal(tb_world_add_shape(w, &made[k], &ids[k]), TB_OK);
    for (k = 0; k < tb_world_shape_count(w); ++k) {
        const tb_shape_id id = tb_world_shape_at(w, k);
        size_t j;
        assert_int_equal(tb_shape_definition(w, id, &got), TB_OK);
        for (j = 0; j < 3; ++j) {
            if (id.index1 != ids[j].index1)
                continue;
            ++found;
            assert_int_equal(got.type, made[j].type);
            assert_true(got.body.index1 == body.index1 && got.body.generation == body.generation);
            assert_true(got.position[0] == made[j].position[0] && got.radius == made[j].radius);
            assert_true(got.restitution == made[j].restitution && got.friction == made[j].friction);
            assert_true(got.rolling_resistance == made[j].rolling_resistance);
            assert_true(got.category == made[j].category && got.mask == made[j].mask);
        }
    }
    assert_int_equal(found, 3);
    assert_int_equal(tb_shape_definition(w, ids[1], &got), TB_OK);
    assert_rel(got.half_length, 0.3, 0);
    assert_rel(got.orientation[0], made[1].orientation[0] / hypot(made[1].orientation[0], made[1].orientation[1]),
               1e-15);
    assert_rel(got.orientation[1], made[1].orientation[1] / hypot(made[1].orientation[0], made[1].orientation[1]),
               1e-15);
    assert_int_equal(tb_shape_definition(w, ids[2], &got), TB_OK);
    assert_true(got.half_extents[0] == 0.1 && got.half_extents[1] == 0.2 && got.half_extents[2] == 0.3);
    assert_int_equal(tb_shape_definition(w, tb_world_shape_at(w, 0), &got), TB_OK); /* the plane */
    assert_int_equal(got.type, TB_SHAPE_PLANE);
    assert_true(got.body.index1 == 0 && got.normal[2] == 1);
    assert_int_equal(tb_world_shape_at(w, tb_world_shape_count(w)).index1, 0);
    assert_int_equal(tb_shape_definition(w, ids[0], NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_shape_definition(other, ids[0], &got), TB_ERR_STALE_ID);
    assert_int_equal(tb_world_remove_shape(w, ids[0]), TB_OK);
    assert_int_equal(tb_shape_definition(w, ids[0], &got), TB_ERR_STALE_ID);
    assert_non_null(strstr(tb_world_message(w), "removed"));
    tb_world_destroy(w);
    tb_world_destroy(other);
}

/* Three runs of 300 steps in which, between steps, bodies (a box, sphere
   or capsule, sometimes with a second shape), shapes and particles are
   added and removed at random, velocities, poses, forces and torques set
   on random bodies, contact settings changed: every live id answers,
   every removed id is refused as stale, NaN is refused, and the state stays
   finite. Under AddressSanitizer in CI this also watches the arrays the
   contacts keep by slot while slots move under them. */
static void structural_churn_keeps_ids_honest(void **state)
{
    int run;
    (void)state;
    for (run = 1; run <= 3; ++run) {
        uint64_t rng = (uint64_t)run * 0x9E3779B97F4A7C15u;
        tb_world *w = world_on_plane(0.6, 0);
        tb_body_id bodies[200], gone[200];
        tb_shape_id shapes[400];
        tb_particle_id particles[200];
        int nb = 0, ng = 0, ns = 0, np = 0, t, o, i;
        for (t = 0; t < 300; ++t) {
            for (o = 0; o < 4; ++o) {
                const double r = uniform(&rng);
                if (r < 0.25 && nb < 200) {
                    tb_body_def b = tb_default_body_def();
                    tb_shape_def s = tb_default_shape_def();
                    const double size[3] = { 0.4, 0.3, 0.2 };
                    s.type = (tb_shape_type)(int)(3 * uniform(&rng));
                    s.radius = 0.1 + 0.2 * uniform(&rng), s.half_length = 0.3 * uniform(&rng);
                    s.half_extents[0] = 0.2, s.half_extents[1] = 0.15, s.half_extents[2] = 0.1;
                    assert_int_equal(tb_mass_box(500, size, &b.mass, NULL), TB_OK);
                    for (i = 0; i < 3; ++i)
                        b.position[i] = 4 * (uniform(&rng) - 0.5), b.velocity[i] = 6 * (uniform(&rng) - 0.5);
                    b.position[2] = 0.3 + 3 * uniform(&rng);
                    assert_int_equal(tb_world_add_body(w, &b, &bodies[nb]), TB_OK);
                    s.body = bodies[nb++];
                    assert_int_equal(tb_world_add_shape(w, &s, &shapes[ns++]), TB_OK);
                    if (uniform(&rng) < 0.3 && ns < 400) {
                        s.type = TB_SHAPE_SPHERE, s.radius = 0.1, s.position[0] = 0.3;
                        assert_int_equal(tb_world_add_shape(w, &s, &shapes[ns++]), TB_OK);
                    }
                } else if (r < 0.35 && nb > 0) {
                    i = (int)(nb * uniform(&rng));
                    assert_int_equal(tb_world_remove_body(w, bodies[i]), TB_OK);
                    if (ng < 200)
                        gone[ng++] = bodies[i];
                    bodies[i] = bodies[--nb];
                } else if (r < 0.42 && ns > 0) { /* its body may be gone: then it is too */
                    const tb_status st = tb_world_remove_shape(w, shapes[i = (int)(ns * uniform(&rng))]);
                    assert_true(st == TB_OK || st == TB_ERR_STALE_ID);
                    assert_int_equal(tb_world_remove_shape(w, shapes[i]), TB_ERR_STALE_ID);
                    shapes[i] = shapes[--ns];
                } else if (r < 0.55 && nb > 0) {
                    const double v[3] = { uniform(&rng) - 0.5, 0, 5 * uniform(&rng) },
                                 f[3] = { 100 * (uniform(&rng) - 0.5), 0, 200 * uniform(&rng) };
                    double at[3];
                    i = (int)(nb * uniform(&rng));
                    assert_int_equal(tb_body_set_velocity(w, bodies[i], v), TB_OK);
                    assert_int_equal(tb_body_position(w, bodies[i], at), TB_OK);
                    at[0] += 0.1;
                    assert_int_equal(tb_body_apply_force(w, bodies[i], f, at), TB_OK);
                } else if (r < 0.65 && np < 200) {
                    tb_particle_def q = tb_default_particle_def();
                    q.position[2] = 1 + 2 * uniform(&rng), q.velocity[0] = 10 * (uniform(&rng) - 0.5);
                    assert_int_equal(tb_world_add_particle(w, &q, &particles[np++]), TB_OK);
                } else if (r < 0.7 && np > 0) {
                    i = (int)(np * uniform(&rng));
                    assert_int_equal(tb_world_remove_particle(w, particles[i]), TB_OK);
                    particles[i] = particles[--np];
                } else if (r < 0.75) {
                    tb_contact_settings cs = tb_world_contact_settings(w);
                    cs.particle_radius = uniform(&rng) < 0.5 ? -1 : 0.02;
                    cs.sleep_time = uniform(&rng) < 0.3 ? INFINITY : 0.3;
                    assert_int_equal(tb_world_set_contact_settings(w, &cs), TB_OK);
                } else if (r < 0.85 && nb > 0) {
                    const double bad[3] = { NAN, 0, 0 };
                    assert_int_equal(tb_body_set_velocity(w, bodies[(int)(nb * uniform(&rng))], bad),
                                     TB_ERR_ARGUMENT);
                } else if (ng > 0) {
                    double x[3];
                    assert_int_equal(tb_body_position(w, gone[(int)(ng * uniform(&rng))], x), TB_ERR_STALE_ID);
                }
            }
            assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
            for (i = 0; i < nb; ++i) {
                double x[3];
                assert_int_equal(tb_body_position(w, bodies[i], x), TB_OK);
                assert_true(isfinite(x[0] + x[1] + x[2]));
            }
        }
        assert_int_equal(tb_world_body_count(w), (size_t)nb);
        tb_world_destroy(w);
    }
}

/* The deepest overlap is what the step found at its start: a unit box
   sunk 5 cm into the plane reads 0.05 m at its first step (the box's four
   bottom corners, exact to rounding), none before a step, and once the
   position pass has lifted it and it rests, at most the slop the solver
   leaves alone (5 mm) plus rounding (tb_world_deepest_overlap, which
   `tumble run --plot` draws). */
static void deepest_overlap_is_read(void **state)
{
    tb_world *w = world_on_plane(0.6, 0);
    const double at[3] = { 0, 0, 0.45 };
    const tb_contact_settings cs = tb_default_contact_settings();
    int i;
    (void)state;
    add_box(w, at, 1, 0.6);
    assert_true(tb_world_deepest_overlap(w) == 0);
    assert_true(tb_world_deepest_overlap(NULL) == 0);
    assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
    assert_int_equal(tb_world_contact_count(w), 4);
    assert_float_equal(tb_world_deepest_overlap(w), 0.05, 1e-12);
    for (i = 0; i < 120; ++i)
        assert_int_equal(tb_world_step(w, 1.0 / 60), TB_OK);
    assert_true(tb_world_deepest_overlap(w) > 0);
    assert_true(tb_world_deepest_overlap(w) <= cs.slop + 1e-9);
    tb_world_destroy(w);
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(deepest_overlap_is_read),
    cmocka_unit_test(structural_churn_keeps_ids_honest),
    cmocka_unit_test(bad_shapes_are_refused),
    cmocka_unit_test(shapes_read_back_as_defined),
};

TB_TEST_MAIN(tests)
