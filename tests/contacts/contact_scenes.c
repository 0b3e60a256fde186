/* contact_scenes.c: the scene helpers of contact_scenes.h. */
#include "test_main.h"
#include "contact_scenes.h"

#include <math.h>
#include <string.h>

tb_world *world_on_plane(double friction, double restitution)
{
    tb_world_def def = tb_default_world_def();
    tb_shape_def plane = tb_default_shape_def();
    tb_world *w;
    def.gravity[2] = -G;
    assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
    plane.type = TB_SHAPE_PLANE;
    plane.friction = friction;
    plane.restitution = restitution;
    assert_int_equal(tb_world_add_shape(w, &plane, NULL), TB_OK);
    return w;
}

tb_body_id add_box(tb_world *w, const double centre[3], double edge, double friction)
{
    tb_body_def b = tb_default_body_def();
    tb_shape_def s = tb_default_shape_def();
    const double size[3] = { edge, edge, edge };
    tb_body_id id;
    assert_int_equal(tb_mass_box(1 / (edge * edge * edge), size, &b.mass, NULL), TB_OK); /* 1 kg */
    memcpy(b.position, centre, sizeof b.position);
    assert_int_equal(tb_world_add_body(w, &b, &id), TB_OK);
    s.type = TB_SHAPE_BOX;
    s.body = id;
    s.half_extents[0] = s.half_extents[1] = s.half_extents[2] = edge / 2;
    s.friction = friction;
    assert_int_equal(tb_world_add_shape(w, &s, NULL), TB_OK);
    return id;
}

tb_body_id add_ball(tb_world *w, const double centre[3], double radius, double restitution)
{
    tb_body_def b = tb_default_body_def();
    tb_shape_def s = tb_default_shape_def();
    tb_body_id id;
    assert_int_equal(tb_mass_sphere(1 / (4.0 / 3 * 3.14159265358979323846 * radius * radius * radius), radius,
                                    &b.mass, NULL), TB_OK);
    memcpy(b.position, centre, sizeof b.position);
    assert_int_equal(tb_world_add_body(w, &b, &id), TB_OK);
    s.body = id;
    s.radius = radius;
    s.restitution = restitution;
    assert_int_equal(tb_world_add_shape(w, &s, NULL), TB_OK);
    return id;
}

double uniform(uint64_t *state)
{
    *state = *state * 6364136223846793005u + 1442695040888963407u;
    return (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}

void awake(tb_world *w)
{
    tb_contact_settings s = tb_world_contact_settings(w);
    s.sleep_time = INFINITY;
    assert_int_equal(tb_world_set_contact_settings(w, &s), TB_OK);
}

tb_body_id add_solid(tb_world *w, tb_shape_type type, const double at[3], const double v[3], const double spin[3],
                     double size)
{
    tb_body_def b = tb_default_body_def();
    tb_shape_def s = tb_default_shape_def();
    const double edge[3] = { size, size, size };
    tb_body_id id;
    if (type == TB_SHAPE_BOX) {
        assert_int_equal(tb_mass_box(1, edge, &b.mass, NULL), TB_OK);
        s.half_extents[0] = s.half_extents[1] = s.half_extents[2] = size / 2;
    } else {
        assert_int_equal(tb_mass_sphere(1, size / 2, &b.mass, NULL), TB_OK);
        s.radius = size / 2;
    }
    memcpy(b.position, at, sizeof b.position);
    memcpy(b.velocity, v, sizeof b.velocity);
    if (spin)
        memcpy(b.angular_velocity, spin, sizeof b.angular_velocity);
    assert_int_equal(tb_world_add_body(w, &b, &id), TB_OK);
    s.type = type;
    s.body = id;
    assert_int_equal(tb_world_add_shape(w, &s, NULL), TB_OK);
    return id;
}

double slide(double hz, int substeps, tb_world **kept, tb_body_id *box)
{
    tb_world *w = world_on_plane(0.5, 0);
    const double start[3] = { 0, 0, 0.5 };
    const double v0[3] = { 5, 0, 0 };
    tb_body_id id = add_box(w, start, 1, 0.5);
    tb_contact_settings s = tb_world_contact_settings(w);
    double x[3], v[3];
    int i;
    s.substeps = substeps;
    assert_int_equal(tb_world_set_contact_settings(w, &s), TB_OK);
    assert_int_equal(tb_body_set_velocity(w, id, v0), TB_OK);
    for (i = 0; i < 3 * hz; ++i) {
        assert_int_equal(tb_world_step(w, 1 / hz), TB_OK);
        tb_body_velocity(w, id, v);
        if (v[0] <= 1e-6)
            break;
    }
    tb_body_position(w, id, x);
    if (kept)
        *kept = w, *box = id;
    else
        tb_world_destroy(w);
    return x[0];
}

tb_world *spun_box(int substeps, tb_body_id *box, double *expected)
{
    const double mu = 0.5, h = 1.0 / 60, r = sqrt(0.5), inertia = 1.0 / 6;
    const double start[3] = { 0, 0, 0.5 }, spin[3] = { 0, 0, 10 };
    tb_world *w = world_on_plane(mu, 0);
    tb_contact_settings s = tb_world_contact_settings(w);
    int i;
    *box = add_box(w, start, 1, mu);
    *expected = 10 - 12 * mu * G * r * h / inertia;
    s.substeps = substeps;
    assert_int_equal(tb_world_set_contact_settings(w, &s), TB_OK);
    /* 1 s at rest first (awake), settled on its face */
    awake(w);
    for (i = 0; i < 60; ++i)
        assert_int_equal(tb_world_step(w, h), TB_OK);
    assert_int_equal(tb_body_set_angular_velocity(w, *box, spin), TB_OK);
    for (i = 0; i < 12; ++i)
        assert_int_equal(tb_world_step(w, h), TB_OK);
    return w;
}

int ball_apexes(tb_world *w, tb_body_id id, double r, double hz, double sampled[2], double top[2])
{
    double previous_v = 0, previous_top = 0;
    int n = 0, i;
    for (i = 0; i < 4 * hz && n < 2; ++i) {
        double x[3], v[3];
        assert_int_equal(tb_world_step(w, 1 / hz), TB_OK);
        tb_body_position(w, id, x);
        tb_body_velocity(w, id, v);
        if (previous_v > 0 && v[2] <= 0) {
            if (sampled)
                sampled[n] = x[2] - r;
            top[n++] = previous_top;
        }
        previous_top = x[2] - r + (v[2] > 0 ? v[2] * v[2] / (2 * G) : 0);
        previous_v = v[2];
    }
    return n;
}

void step_changing(tb_world *w, double seconds, double h, int changing)
{
    double t = 0;
    int n = 0;
    while (t < seconds - 1e-9) {
        const double step = changing && n++ % 2 ? h / 3 : h;
        assert_int_equal(tb_world_step(w, step), TB_OK);
        t += step;
    }
}

double column_after(double h, int changing, int substeps)
{
    tb_world *w = world_on_plane(0.6, 0);
    tb_contact_settings cs;
    tb_body_id ids[10];
    double worst = 0, x[3];
    int i;
    awake(w);
    cs = tb_world_contact_settings(w);
    cs.substeps = substeps;
    assert_int_equal(tb_world_set_contact_settings(w, &cs), TB_OK);
    for (i = 0; i < 10; ++i) {
        const double at[3] = { 0, 0, 0.5 + i };
        ids[i] = add_box(w, at, 1, 0.6);
    }
    step_changing(w, 10, h, changing);
    for (i = 0; i < 10; ++i) {
        tb_body_position(w, ids[i], x);
        worst = fmax(worst, fabs(x[2] - (0.5 + i)) + hypot(x[0], x[1]));
    }
    tb_world_destroy(w);
    return worst;
}
