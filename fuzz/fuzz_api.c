/* fuzz_api.c: a libFuzzer target for the C API. The input is decoded into
   a world and a sequence of calls: adds (joints too), removes (of live, removed and
   never-made ids), setters with hostile numbers, contact settings, steps.
   Every call may fail, but none may crash or leak, and with the guard on
   (the world starts with it checking finiteness; the input may change
   it) no step may return TB_OK with a non-finite position (issue 23: no
   input that overflows into NaN). Without the guard an explicit method on
   a stiff force may blow up to Inf and say so only through the state. The adaptive methods (dopri5, auto) are left out:
   refusing a step they cannot take costs seconds (docs/testing.md,
   "Fuzzing"). */
#include "tumble.h"
#include "fuzz_input.h"

#include <stdlib.h>

#define MOST 32 /* of each kind of object an input may make */

typedef struct made {
    tb_particle_id particle[MOST];
    tb_body_id body[MOST];
    tb_shape_id shape[MOST];
    tb_spring_id spring[MOST];
    tb_joint_id joint[MOST];
    unsigned particles, bodies, shapes, springs, joints;
} made;

/* Every body and particle position finite after a step that succeeded */
static void check_finite(const tb_world *w)
{
    const double *x = tb_world_body_positions(w);
    size_t i, n = 3 * tb_world_body_count(w);
    for (i = 0; i < n; ++i)
        if (!isfinite(x[i]))
            abort();
    x = tb_world_particle_positions(w);
    n = 3 * tb_world_particle_count(w);
    for (i = 0; i < n; ++i)
        if (!isfinite(x[i]))
            abort();
}

static void add_particle(tb_world *w, fuzz_input *in, made *m)
{
    tb_particle_def d = tb_default_particle_def();
    tb_particle_id id;
    fuzz_vector(in, d.position);
    fuzz_vector(in, d.velocity);
    d.mass = fuzz_double(in);
    d.pinned = (int)fuzz_below(in, 2);
    if (tb_world_add_particle(w, &d, &id) == TB_OK && m->particles < MOST)
        m->particle[m->particles++] = id;
}

static void add_body(tb_world *w, fuzz_input *in, made *m)
{
    tb_body_def d = tb_default_body_def();
    tb_body_id id;
    double size[3];
    fuzz_vector(in, size);
    if (fuzz_below(in, 2))
        (void)tb_mass_box(fuzz_double(in), size, &d.mass, NULL);
    else
        (void)tb_mass_sphere(fuzz_double(in), size[0], &d.mass, NULL);
    fuzz_vector(in, d.position);
    fuzz_vector(in, d.velocity);
    fuzz_vector(in, d.angular_velocity);
    if (fuzz_below(in, 4) == 0) {
        d.orientation[0] = fuzz_double(in), d.orientation[1] = fuzz_double(in);
        d.orientation[2] = fuzz_double(in), d.orientation[3] = fuzz_double(in);
    }
    if (tb_world_add_body(w, &d, &id) == TB_OK && m->bodies < MOST)
        m->body[m->bodies++] = id;
}

static void add_shape(tb_world *w, fuzz_input *in, made *m)
{
    tb_shape_def d = tb_default_shape_def();
    tb_shape_id id;
    d.type = (tb_shape_type)fuzz_below(in, 4);
    if (m->bodies && fuzz_below(in, 4))
        d.body = m->body[fuzz_below(in, m->bodies)];
    if (fuzz_below(in, 2))
        fuzz_vector(in, d.position);
    d.radius = fuzz_below(in, 2) ? fuzz_double(in) : d.radius;
    d.half_length = fuzz_below(in, 2) ? fuzz_double(in) : d.half_length;
    if (fuzz_below(in, 2))
        fuzz_vector(in, d.half_extents);
    if (fuzz_below(in, 4) == 0)
        fuzz_vector(in, d.normal);
    d.offset = fuzz_below(in, 2) ? fuzz_double(in) : 0;
    d.friction = fuzz_below(in, 2) ? fuzz_double(in) : d.friction;
    d.restitution = fuzz_below(in, 2) ? fuzz_double(in) : 0;
    d.rolling_resistance = fuzz_below(in, 4) == 0 ? fuzz_double(in) : 0;
    if (tb_world_add_shape(w, &d, &id) == TB_OK && m->shapes < MOST)
        m->shape[m->shapes++] = id;
}

static void add_spring(tb_world *w, fuzz_input *in, made *m)
{
    tb_spring_def d = tb_default_spring_def();
    tb_spring_id id;
    if (!m->particles)
        return;
    d.a = m->particle[fuzz_below(in, m->particles)];
    if (fuzz_below(in, 2))
        d.b = m->particle[fuzz_below(in, m->particles)];
    else
        fuzz_vector(in, d.anchor);
    d.stiffness = fuzz_double(in);
    d.damping = fuzz_below(in, 2) ? fuzz_double(in) : 0;
    d.rest_length = fuzz_below(in, 2) ? fuzz_double(in) : -1;
    if (tb_world_add_spring(w, &d, &id) == TB_OK && m->springs < MOST)
        m->spring[m->springs++] = id;
}

static void add_joint(tb_world *w, fuzz_input *in, made *m)
{
    tb_joint_def d = tb_default_joint_def();
    tb_joint_id id;
    d.type = (tb_joint_type)fuzz_below(in, 6); /* 5: not a type */
    d.a = m->body[fuzz_below(in, m->bodies)];
    if (fuzz_below(in, 2))
        d.b = m->body[fuzz_below(in, m->bodies)];
    if (m->particles && fuzz_below(in, 3) == 0) /* particles in the bodies' places (both: refused) */
        d.particle_a = m->particle[fuzz_below(in, m->particles)];
    if (m->particles && fuzz_below(in, 3) == 0)
        d.particle_b = m->particle[fuzz_below(in, m->particles)];
    fuzz_vector(in, d.anchor);
    if (fuzz_below(in, 2))
        fuzz_vector(in, d.axis);
    if (d.type == TB_JOINT_DISTANCE) {
        fuzz_vector(in, d.anchor_b);
        d.length = fuzz_below(in, 2) ? fuzz_double(in) : -1;
    }
    if (fuzz_below(in, 3) == 0) /* drives: limits, a motor, a spring, breaking */
        d.enable_limit = 1, d.lower = fuzz_double(in), d.upper = fuzz_double(in);
    if (fuzz_below(in, 3) == 0)
        d.enable_motor = 1, d.motor_speed = fuzz_double(in), d.max_motor_force = fuzz_double(in);
    if (fuzz_below(in, 3) == 0)
        d.enable_spring = 1, d.spring_hz = fuzz_double(in), d.spring_damping_ratio = fuzz_double(in),
        d.spring_target = fuzz_double(in);
    if (fuzz_below(in, 4) == 0)
        d.break_force = fuzz_double(in), d.break_torque = fuzz_double(in);
    if (fuzz_below(in, 4) == 0)
        d.enable_twist = 1, d.twist_lower = fuzz_double(in), d.twist_upper = fuzz_double(in);
    if (tb_world_add_joint(w, &d, &id) == TB_OK && m->joints < MOST)
        m->joint[m->joints++] = id;
}

/* Removes one of the ids made (it may be gone already: stale) */
static void remove_one(tb_world *w, fuzz_input *in, made *m)
{
    switch (fuzz_below(in, 4)) {
    case 0:
        if (m->particles)
            (void)tb_world_remove_particle(w, m->particle[fuzz_below(in, m->particles)]);
        break;
    case 1:
        if (m->bodies)
            (void)tb_world_remove_body(w, m->body[fuzz_below(in, m->bodies)]);
        break;
    case 2:
        if (m->shapes)
            (void)tb_world_remove_shape(w, m->shape[fuzz_below(in, m->shapes)]);
        break;
    default:
        if (m->joints && fuzz_below(in, 2))
            (void)tb_world_remove_joint(w, m->joint[fuzz_below(in, m->joints)]);
        else if (m->springs)
            (void)tb_world_remove_spring(w, m->spring[fuzz_below(in, m->springs)]);
    }
}

static void set_something(tb_world *w, fuzz_input *in, made *m)
{
    double v[4];
    fuzz_vector(in, v);
    v[3] = fuzz_double(in);
    if (m->bodies && fuzz_below(in, 3)) {
        const tb_body_id id = m->body[fuzz_below(in, m->bodies)];
        switch (fuzz_below(in, 7)) {
        case 0: (void)tb_body_set_position(w, id, v); break;
        case 1: (void)tb_body_set_velocity(w, id, v); break;
        case 2: (void)tb_body_set_angular_velocity(w, id, v); break;
        case 3: (void)tb_body_set_orientation(w, id, v); break;
        case 4: (void)tb_body_apply_force(w, id, v, v + 1); break;
        case 5: (void)tb_body_apply_torque(w, id, v); break;
        default: (void)tb_body_wake(w, id);
        }
    } else if (m->joints && fuzz_below(in, 3) == 0) { /* a joint's drive, on or off (it may be gone) */
        const tb_joint_id id = m->joint[fuzz_below(in, m->joints)];
        const int on = (int)fuzz_below(in, 2);
        switch (fuzz_below(in, 4)) {
        case 0: (void)tb_joint_set_limit(w, id, on, v[0], v[1]); break;
        case 1: (void)tb_joint_set_motor(w, id, on, v[0], v[1]); break;
        case 2: (void)tb_joint_set_twist_limit(w, id, on, v[0], v[1]); break;
        default: (void)tb_joint_set_spring(w, id, on, v[0], v[1], v[2]);
        }
    } else if (m->particles && fuzz_below(in, 2)) {
        const tb_particle_id id = m->particle[fuzz_below(in, m->particles)];
        if (fuzz_below(in, 2))
            (void)tb_particle_set_position(w, id, v);
        else
            (void)tb_particle_set_velocity(w, id, v);
    } else {
        switch (fuzz_below(in, 3)) {
        case 0: (void)tb_world_set_gravity(w, v); break;
        case 1: (void)tb_world_set_drag(w, v[0], v[1]); break;
        default: (void)tb_world_set_guard(w, v[0]);
        }
    }
}

static void set_contacts(tb_world *w, fuzz_input *in)
{
    tb_contact_settings s = tb_world_contact_settings(w);
    s.substeps = (int)fuzz_below(in, 5);
    s.particle_radius = fuzz_below(in, 2) ? fuzz_double(in) : s.particle_radius;
    s.sleep_time = fuzz_below(in, 2) ? fuzz_double(in) : s.sleep_time;
    s.hertz = fuzz_below(in, 4) == 0 ? fuzz_double(in) : s.hertz;
    (void)tb_world_set_contact_settings(w, &s);
}

static void set_method(tb_world *w, fuzz_input *in)
{
    const char *name = tb_integrator_name((int)fuzz_below(in, (unsigned)tb_integrator_count()));
    if (name && strcmp(name, "dopri5") != 0 && strcmp(name, "auto") != 0)
        (void)tb_world_set_integrator(w, name);
}

static void step(tb_world *w, fuzz_input *in)
{
    static const double steps[] = { 1.0 / 60, 1.0 / 240, 1e-3, 0.1 };
    const unsigned pick = fuzz_below(in, 5);
    const double h = pick < 4 ? steps[pick] : fuzz_double(in);
    tb_advice advice;
    if (fuzz_below(in, 8) == 0)
        (void)tb_world_advise(w, h, &advice);
    if (tb_world_step(w, h) == TB_OK && tb_world_guard(w) > 0)
        check_finite(w);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_input in = { data, size, 0 };
    tb_world_def def = tb_default_world_def();
    tb_world *w;
    made m;
    int calls = 0, steps = 0;
    memset(&m, 0, sizeof m);
    if (tb_world_create(&def, &w, NULL, 0) != TB_OK)
        return 0;
    (void)tb_world_set_guard(w, INFINITY);
    while (fuzz_more(&in) && calls++ < 200) {
        switch (fuzz_below(&in, 10)) {
        case 0: add_particle(w, &in, &m); break;
        case 1: add_body(w, &in, &m); break;
        case 2: add_shape(w, &in, &m); break;
        case 3:
            if (m.bodies && fuzz_below(&in, 2))
                add_joint(w, &in, &m);
            else
                add_spring(w, &in, &m);
            break;
        case 4: remove_one(w, &in, &m); break;
        case 5: set_something(w, &in, &m); break;
        case 6: set_contacts(w, &in); break;
        case 7: set_method(w, &in); break;
        default:
            if (steps++ < 24)
                step(w, &in);
        }
    }
    (void)tb_world_energy(w);
    tb_world_destroy(w);
    return 0;
}
