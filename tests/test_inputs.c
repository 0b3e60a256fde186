/* test_inputs.c: the input rule at the C API boundary (TB_LIMIT in
   tumble/base.h) and NULL pointers.

   A probe calls one setter or definition with a tiny, huge or overflowing
   value in a small scene (particles on a spring, a body with a box on a
   plane) and its twin, built the same way and left alone. A refused call
   must name what it refused and leave the world as its twin, bit for bit,
   before and after a step (so no hidden state, such as a held force,
   changed either). An accepted one must leave a sound state after the
   next step with every integrator (finite, within the guard's runaway
   bound, bodies' orientations unit), or, where the step is far past the
   method's stability limit (a spring of 1e95 N/m at 60 Hz, RK4 turning a
   body by 1e97 rad), be refused by the guard with the world as it was and
   the world able to step on. */
#include "test_main.h"
#include "tumble.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

/* ---- the scene and what can be seen of it ----------------------------------- */

typedef struct scene {
    tb_world *w;
    tb_particle_id p, q;
    tb_spring_id spring;
    tb_body_id body;
} scene;

static void build(scene *s, const char *integrator)
{
    tb_world_def def = tb_default_world_def();
    tb_particle_def pd = tb_default_particle_def();
    tb_spring_def sd = tb_default_spring_def();
    tb_body_def bd = tb_default_body_def();
    tb_shape_def sh = tb_default_shape_def();
    def.integrator = integrator;
    assert_int_equal(tb_world_create(&def, &s->w, NULL, 0), TB_OK);
    pd.position[2] = 3;
    assert_int_equal(tb_world_add_particle(s->w, &pd, &s->p), TB_OK);
    pd.position[0] = 1;
    pd.velocity[1] = 0.5;
    assert_int_equal(tb_world_add_particle(s->w, &pd, &s->q), TB_OK);
    sd.a = s->p, sd.b = s->q, sd.stiffness = 10;
    assert_int_equal(tb_world_add_spring(s->w, &sd, &s->spring), TB_OK);
    bd.position[2] = 0.5;
    bd.angular_velocity[0] = 0.3;
    assert_int_equal(tb_world_add_body(s->w, &bd, &s->body), TB_OK);
    sh.type = TB_SHAPE_BOX;
    sh.body = s->body;
    assert_int_equal(tb_world_add_shape(s->w, &sh, NULL), TB_OK);
    sh = tb_default_shape_def();
    sh.type = TB_SHAPE_PLANE;
    assert_int_equal(tb_world_add_shape(s->w, &sh, NULL), TB_OK);
}

#define SEEN 256

/* Everything the API shows of the world, in a fixed order. */
static size_t look(const tb_world *w, double out[SEEN])
{
    size_t n = 0, i, k;
    const tb_energy e = tb_world_energy(w);
    double g[3];
    out[n++] = tb_world_time(w);
    tb_world_gravity(w, g);
    for (k = 0; k < 3; ++k)
        out[n++] = g[k];
    out[n++] = (double)tb_world_particle_count(w);
    out[n++] = (double)tb_world_body_count(w);
    out[n++] = (double)tb_world_spring_count(w);
    out[n++] = (double)tb_world_shape_count(w);
    {
        const tb_contact_settings cs = tb_world_contact_settings(w);
        out[n++] = cs.hertz, out[n++] = cs.sleep_time, out[n++] = (double)cs.substeps;
        out[n++] = tb_world_tolerance(w);
    }
    for (i = 0; i < tb_world_particle_count(w) && n + 7 <= SEEN; ++i) {
        for (k = 0; k < 3; ++k) {
            out[n++] = tb_world_particle_positions(w)[3 * i + k];
            out[n++] = tb_world_particle_velocities(w)[3 * i + k];
        }
        out[n++] = tb_world_particle_masses(w)[i];
    }
    for (i = 0; i < tb_world_body_count(w) && n + 20 <= SEEN; ++i) {
        double P[3], L[3], m, I[3];
        const tb_body_id id = tb_world_body_at(w, i);
        for (k = 0; k < 3; ++k)
            out[n++] = tb_world_body_positions(w)[3 * i + k];
        for (k = 0; k < 4; ++k)
            out[n++] = tb_world_body_orientations(w)[4 * i + k];
        assert_int_equal(tb_body_momentum(w, id, P, L), TB_OK);
        assert_int_equal(tb_body_mass(w, id, &m, I), TB_OK);
        for (k = 0; k < 3; ++k)
            out[n++] = P[k], out[n++] = L[k], out[n++] = I[k];
        out[n++] = m;
    }
    out[n++] = e.total;
    return n;
}

/* Finite, within the guard's runaway bound (1e150), unit orientations. */
static void assert_sound(const tb_world *w, const char *what)
{
    double seen[SEEN];
    const size_t n = look(w, seen);
    size_t i;
    for (i = 0; i < n - 1; ++i) /* the energy (last) may be past 1e150 */
        if (!(fabs(seen[i]) <= 1e150))
            fail_msg("%s: value %zu of the world is %g after a step", what, i, seen[i]);
    for (i = 0; i < tb_world_body_count(w); ++i) {
        const double *q = tb_world_body_orientations(w) + 4 * i;
        const double n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
        if (!(fabs(n2 - 1) <= 1e-6))
            fail_msg("%s: body %zu's |q|^2 is %g after a step", what, i, n2);
    }
    assert_true(isfinite(tb_world_energy(w).total));
}

/* ---- the probes ------------------------------------------------------------- */

typedef tb_status probe_fn(scene *s, double value);

typedef struct probe {
    const char *name;
    probe_fn *fn;
    double value;
    const char *named;   /* what a refusal's message names; NULL: must be accepted */
    probe_fn *prepare;   /* NULL, or what both the world and its twin get first */
} probe;

static tb_status particle_mass(scene *s, double m)
{
    tb_particle_def d = tb_default_particle_def();
    d.mass = m;
    return tb_world_add_particle(s->w, &d, NULL);
}

static tb_status heavy_fast_particle(scene *s, double v)
{
    tb_particle_def d = tb_default_particle_def();
    d.mass = 1e100;
    d.velocity[0] = v;
    return tb_world_add_particle(s->w, &d, NULL);
}

static tb_status particle_velocity(scene *s, double v)
{
    tb_particle_def d = tb_default_particle_def();
    d.velocity[2] = v;
    return tb_world_add_particle(s->w, &d, NULL);
}

static tb_status light_fast_particle(scene *s, double v)
{
    tb_particle_def d = tb_default_particle_def();
    d.mass = 1e-100;
    d.velocity[2] = v;
    return tb_world_add_particle(s->w, &d, NULL);
}

static tb_status particle_position(scene *s, double x)
{
    tb_particle_def d = tb_default_particle_def();
    d.position[1] = x;
    return tb_world_add_particle(s->w, &d, NULL);
}

static tb_status set_particle_velocity(scene *s, double v)
{
    const double vel[3] = { v, 0, 0 };
    return tb_particle_set_velocity(s->w, s->p, vel);
}

static tb_status set_particle_position(scene *s, double x)
{
    const double pos[3] = { 0, x, 0 };
    return tb_particle_set_position(s->w, s->p, pos);
}

static tb_status body_mass(scene *s, double m)
{
    tb_body_def d = tb_default_body_def();
    d.mass.mass = m;
    d.position[0] = 5;
    return tb_world_add_body(s->w, &d, NULL);
}

static tb_status body_inertia(scene *s, double i)
{
    tb_body_def d = tb_default_body_def();
    d.mass.inertia[0] = d.mass.inertia[1] = d.mass.inertia[2] = i;
    d.position[0] = 5;
    return tb_world_add_body(s->w, &d, NULL);
}

static tb_status heavy_fast_body(scene *s, double v)
{
    tb_body_def d = tb_default_body_def();
    d.mass.mass = 1e300;
    d.velocity[0] = v;
    return tb_world_add_body(s->w, &d, NULL);
}

static tb_status body_velocity(scene *s, double v)
{
    tb_body_def d = tb_default_body_def();
    d.velocity[0] = v;
    d.position[0] = 5;
    return tb_world_add_body(s->w, &d, NULL);
}

static tb_status body_spin(scene *s, double omega)
{
    tb_body_def d = tb_default_body_def();
    d.angular_velocity[0] = omega;
    d.angular_velocity[1] = 0.3 * omega;
    d.position[0] = 5;
    d.mass.inertia[1] = 0.15; /* not isotropic: the splitting kernels' general path */
    return tb_world_add_body(s->w, &d, NULL);
}

static tb_status light_body_spin(scene *s, double omega)
{
    tb_body_def d = tb_default_body_def();
    d.mass.inertia[0] = d.mass.inertia[1] = d.mass.inertia[2] = 1e-100;
    d.angular_velocity[2] = omega;
    d.position[0] = 5;
    return tb_world_add_body(s->w, &d, NULL);
}

static tb_status body_position(scene *s, double x)
{
    tb_body_def d = tb_default_body_def();
    d.position[0] = x;
    return tb_world_add_body(s->w, &d, NULL);
}

static tb_status body_centre(scene *s, double x)
{
    tb_body_def d = tb_default_body_def();
    d.position[0] = 9e99;
    d.mass.centre[0] = x;
    return tb_world_add_body(s->w, &d, NULL);
}

static tb_status body_damping(scene *s, double c)
{
    tb_body_def d = tb_default_body_def();
    d.angular_damping = c;
    d.position[0] = 5;
    return tb_world_add_body(s->w, &d, NULL);
}

static tb_status set_body_velocity(scene *s, double v)
{
    const double vel[3] = { 0, v, 0 };
    return tb_body_set_velocity(s->w, s->body, vel);
}

static tb_status set_body_spin(scene *s, double omega)
{
    const double w[3] = { 0, 0, omega };
    return tb_body_set_angular_velocity(s->w, s->body, w);
}

static tb_status set_body_position(scene *s, double x)
{
    const double pos[3] = { 0, 0, x };
    return tb_body_set_position(s->w, s->body, pos);
}

/* A thin rod spun fast about its long axis: L small. Turned so that the
   same spin is about a short axis, L = I w would be 1e120. */
static tb_status add_spinning_rod(scene *s, double omega)
{
    tb_body_def d = tb_default_body_def();
    d.mass.inertia[0] = 1e-50, d.mass.inertia[1] = d.mass.inertia[2] = 1e50;
    d.angular_velocity[0] = omega;
    d.position[0] = 5;
    return tb_world_add_body(s->w, &d, NULL);
}

static tb_status turn_the_rod(scene *s, double omega)
{
    const double turned[4] = { sqrt(0.5), 0, 0, sqrt(0.5) };
    (void)omega;
    return tb_body_set_orientation(s->w, tb_world_body_at(s->w, 1), turned);
}

static tb_status push(scene *s, double f)
{
    const double force[3] = { f, 0, 0 }, at[3] = { 0, 0, 0.5 };
    return tb_body_apply_force(s->w, s->body, force, at);
}

static tb_status push_far_out(scene *s, double x)
{
    const double force[3] = { 0, 1e60, 0 }, at[3] = { x, 0, 0.5 };
    return tb_body_apply_force(s->w, s->body, force, at);
}

static tb_status push_up(scene *s, double f)
{
    const double force[3] = { 0, 0, f }, at[3] = { 0, 0, 0 };
    return tb_body_apply_force_at_body_point(s->w, s->body, force, at);
}

static tb_status twist(scene *s, double t)
{
    const double torque[3] = { 0, t, 0 };
    return tb_body_apply_torque(s->w, s->body, torque);
}

static tb_status spring_stiffness(scene *s, double k)
{
    tb_spring_def d = tb_default_spring_def();
    d.a = s->p, d.stiffness = k, d.anchor[2] = 13; /* stretched 10 m */
    d.rest_length = 0;
    return tb_world_add_spring(s->w, &d, NULL);
}

static tb_status spring_rest(scene *s, double rest)
{
    tb_spring_def d = tb_default_spring_def();
    d.a = s->p, d.stiffness = 1e-150 > 0 ? 1 : 0, d.rest_length = rest;
    return tb_world_add_spring(s->w, &d, NULL);
}

static tb_status spring_anchor(scene *s, double x)
{
    tb_spring_def d = tb_default_spring_def();
    d.a = s->p, d.stiffness = 1, d.anchor[0] = x;
    return tb_world_add_spring(s->w, &d, NULL);
}

static tb_status spring_damping(scene *s, double c)
{
    tb_spring_def d = tb_default_spring_def();
    d.a = s->p, d.b = s->q, d.damping = c;
    return tb_world_add_spring(s->w, &d, NULL);
}

/* the scene's body held to the world by a joint */
static tb_status joint_anchor(scene *s, double x)
{
    tb_joint_def d = tb_default_joint_def();
    d.a = s->body, d.anchor[0] = x;
    return tb_world_add_joint(s->w, &d, NULL);
}

static tb_status joint_axis(scene *s, double x)
{
    tb_joint_def d = tb_default_joint_def();
    d.type = TB_JOINT_HINGE, d.a = s->body, d.axis[1] = x;
    return tb_world_add_joint(s->w, &d, NULL);
}

static tb_status joint_length(scene *s, double length)
{
    tb_joint_def d = tb_default_joint_def();
    d.type = TB_JOINT_DISTANCE, d.a = s->body, d.anchor_b[2] = 1, d.length = length;
    return tb_world_add_joint(s->w, &d, NULL);
}

/* the scene's body on a hinge to the world with a limit, a motor, a
   spring or a breaking force of the value given */
static tb_status hinge_with(scene *s, double value, int what)
{
    tb_joint_def d = tb_default_joint_def();
    d.type = TB_JOINT_HINGE, d.a = s->body, d.anchor[2] = 0.5;
    switch (what) {
    case 0: d.enable_limit = 1, d.lower = -value, d.upper = value; break;
    case 1: d.enable_motor = 1, d.motor_speed = value, d.max_motor_force = 10; break;
    case 2: d.enable_motor = 1, d.motor_speed = 1, d.max_motor_force = value; break;
    case 3: d.enable_spring = 1, d.spring_hz = value, d.spring_damping_ratio = 0.5; break;
    default: d.break_force = value; break;
    }
    return tb_world_add_joint(s->w, &d, NULL);
}

static tb_status joint_limit(scene *s, double x) { return hinge_with(s, x, 0); }
static tb_status joint_motor_speed(scene *s, double x) { return hinge_with(s, x, 1); }
static tb_status joint_motor_force(scene *s, double x) { return hinge_with(s, x, 2); }
static tb_status joint_spring_hz(scene *s, double x) { return hinge_with(s, x, 3); }
static tb_status joint_break_force(scene *s, double x) { return hinge_with(s, x, 4); }

static tb_status shape_radius(scene *s, double r)
{
    tb_shape_def d = tb_default_shape_def();
    d.radius = r;
    d.position[0] = 20;
    return tb_world_add_shape(s->w, &d, NULL);
}

static tb_status shape_box(scene *s, double h)
{
    tb_shape_def d = tb_default_shape_def();
    d.type = TB_SHAPE_BOX;
    d.half_extents[1] = h;
    d.position[0] = 20;
    return tb_world_add_shape(s->w, &d, NULL);
}

static tb_status shape_position(scene *s, double x)
{
    tb_shape_def d = tb_default_shape_def();
    d.position[2] = x;
    return tb_world_add_shape(s->w, &d, NULL);
}

static tb_status shape_friction(scene *s, double mu)
{
    tb_shape_def d = tb_default_shape_def();
    d.friction = mu;
    d.position[0] = 20;
    return tb_world_add_shape(s->w, &d, NULL);
}

static tb_status plane_offset(scene *s, double offset)
{
    tb_shape_def d = tb_default_shape_def();
    d.type = TB_SHAPE_PLANE;
    d.offset = offset;
    return tb_world_add_shape(s->w, &d, NULL);
}

static tb_status gravity(scene *s, double g)
{
    const double v[3] = { 0, 0, g };
    return tb_world_set_gravity(s->w, v);
}

static tb_status drag(scene *s, double c)
{
    return tb_world_set_drag(s->w, 0, c);
}

static tb_status tolerance(scene *s, double t)
{
    return tb_world_set_tolerance(s->w, t);
}

static tb_status step(scene *s, double h)
{
    return tb_world_step(s->w, h);
}

static tb_status hertz(scene *s, double hz)
{
    tb_contact_settings c = tb_default_contact_settings();
    c.hertz = hz;
    return tb_world_set_contact_settings(s->w, &c);
}

static tb_status substeps(scene *s, double n)
{
    tb_contact_settings c = tb_default_contact_settings();
    c.substeps = (int)n;
    return tb_world_set_contact_settings(s->w, &c);
}

static tb_status sleep_time(scene *s, double t)
{
    tb_contact_settings c = tb_default_contact_settings();
    c.sleep_time = t;
    return tb_world_set_contact_settings(s->w, &c);
}

static tb_status uniform_field(scene *s, double v)
{
    const double u[3] = { v, 0, 0 };
    return tb_world_add_uniform_field(s->w, u, NULL);
}

static tb_status vortex_field(scene *s, double omega)
{
    const double o[3] = { 0, 0, omega }, c[3] = { 0, 0, 0 };
    return tb_world_add_vortex_field(s->w, o, c, NULL);
}

static const probe probes[] = {
    /* particles */
    { "particle mass 5e-309 (1/m is Inf)", particle_mass, 5e-309, "particle mass", NULL },
    { "particle mass 1e-320", particle_mass, 1e-320, "particle mass", NULL },
    { "particle mass 1e-100", particle_mass, 1e-100, NULL, NULL },
    { "particle mass 1e300", particle_mass, 1e300, "particle mass", NULL },
    { "particle of 1e100 kg at 1e10 m/s", heavy_fast_particle, 1e10, "momentum", NULL },
    { "particle of 1e100 kg at 1e-10 m/s", heavy_fast_particle, 1e-10, NULL, NULL },
    { "particle velocity 1e308", particle_velocity, 1e308, "particle velocity", NULL },
    { "particle velocity 1e60 (m v^2 / 2 = 5e119)", particle_velocity, 1e60, "kinetic energy", NULL },
    { "particle velocity 1e40", particle_velocity, 1e40, NULL, NULL },
    { "particle of 1e-100 kg at 1e100 m/s", light_fast_particle, 1e100, NULL, NULL },
    { "particle position 1e101", particle_position, 1e101, "particle position", NULL },
    { "particle position 1e100", particle_position, 1e100, NULL, NULL },
    { "set particle velocity 1e308", set_particle_velocity, 1e308, "particle velocity", NULL },
    { "set particle velocity 1e51", set_particle_velocity, 1e51, "kinetic energy", NULL },
    { "set particle position -1e300", set_particle_position, -1e300, "particle position", NULL },
    /* bodies */
    { "body mass 5e-309", body_mass, 5e-309, "body mass", NULL },
    { "body mass 1e-100", body_mass, 1e-100, NULL, NULL },
    { "body inertia 1e-320", body_inertia, 1e-320, "moments of inertia", NULL },
    { "body inertia 1e300", body_inertia, 1e300, "moments of inertia", NULL },
    { "body inertia 1e-100", body_inertia, 1e-100, NULL, NULL },
    { "body of 1e300 kg at 1e10 m/s", heavy_fast_body, 1e10, "body mass", NULL },
    { "body velocity 1e308", body_velocity, 1e308, "body velocity", NULL },
    { "body velocity 1e60", body_velocity, 1e60, "kinetic energy", NULL },
    { "body velocity 1e45", body_velocity, 1e45, NULL, NULL },
    { "body spin 1e200 rad/s", body_spin, 1e200, "body angular velocity", NULL },
    { "body spin 1e60 rad/s (w.I.w / 2 = 6e118)", body_spin, 1e60, "rotational energy", NULL },
    { "body spin 1e45 rad/s", body_spin, 1e45, NULL, NULL },
    { "body spin 1e200 rad/s, I = 1e-100", light_body_spin, 1e200, "body angular velocity", NULL },
    { "body spin 1e30 rad/s, I = 1e-100", light_body_spin, 1e30, NULL, NULL },
    { "body spin 1e99 rad/s, I = 1e-100 (rk4 overflows)", light_body_spin, 1e99, NULL, NULL },
    { "body position 1e101", body_position, 1e101, "body position", NULL },
    { "body centre placed past 1e100", body_centre, 2e99, "placed", NULL },
    { "body damping 1e300", body_damping, 1e300, "angular damping", NULL },
    { "set body velocity 1e308", set_body_velocity, 1e308, "body velocity", NULL },
    { "set body velocity 1e80", set_body_velocity, 1e80, "kinetic energy", NULL },
    { "set body spin 1e200", set_body_spin, 1e200, "body angular velocity", NULL },
    { "set body spin 1e40", set_body_spin, 1e40, NULL, NULL },
    { "set body position 1e150", set_body_position, 1e150, "body position", NULL },
    { "turn a rod spun at 1e70 rad/s about its axis", turn_the_rod, 1e70, "angular momentum", add_spinning_rod },
    { "apply force 1e308", push, 1e308, "force", NULL },
    { "apply force 1e90", push, 1e90, NULL, NULL },
    { "apply force 1e60 at 1e99 m (torque 1e159)", push_far_out, 1e99, "torque", NULL },
    { "apply force 6e99 twice (held 1.2e100)", push_up, 6e99, "held", push_up },
    { "apply torque 1e101", twist, 1e101, "torque", NULL },
    /* springs */
    { "spring stiffness 1e300", spring_stiffness, 1e300, "stiffness", NULL },
    { "spring stiffness 1e100 stretched 10 m", spring_stiffness, 1e100, "spring force", NULL },
    { "spring stiffness 1e95 stretched 10 m (energy 5e96)", spring_stiffness, 1e95, NULL, NULL },
    { "spring rest length 1e200", spring_rest, 1e200, "rest length", NULL },
    { "spring anchor 1e308", spring_anchor, 1e308, "anchor", NULL },
    { "spring damping 1e300", spring_damping, 1e300, "damping", NULL },
    /* joints */
    { "joint anchor 1e308", joint_anchor, 1e308, "joint anchor", NULL },
    { "joint anchor 1e90 m from the body", joint_anchor, 1e90, NULL, NULL },
    { "hinge axis 1e308", joint_axis, 1e308, "joint axis", NULL },
    { "hinge axis 1e-300 long", joint_axis, 1e-300, NULL, NULL },
    { "distance joint length 1e200", joint_length, 1e200, "length", NULL },
    { "distance joint length 1e90", joint_length, 1e90, NULL, NULL },
    { "hinge limits +-1e200 rad", joint_limit, 1e200, "joint limit", NULL },
    { "hinge limits +-4 rad", joint_limit, 4, "within -pi to pi", NULL },
    { "hinge limits +-1e-300 rad", joint_limit, 1e-300, NULL, NULL },
    { "hinge motor 1e200 rad/s", joint_motor_speed, 1e200, "motor speed", NULL },
    { "hinge motor 1e50 N m", joint_motor_force, 1e50, NULL, NULL },
    { "hinge motor 1e200 N m", joint_motor_force, 1e200, "max_motor_force", NULL },
    { "hinge spring 1e200 Hz", joint_spring_hz, 1e200, "joint spring", NULL },
    { "hinge spring 1e-300 Hz", joint_spring_hz, 1e-300, NULL, NULL },
    { "breaking force 1e200 N", joint_break_force, 1e200, "break_force", NULL },
    { "breaking force 1e-300 N", joint_break_force, 1e-300, NULL, NULL },
    /* shapes */
    { "sphere radius 1e-320", shape_radius, 1e-320, "radius", NULL },
    { "sphere radius 1e200", shape_radius, 1e200, "radius", NULL },
    { "box half extent 1e300", shape_box, 1e300, "half extents", NULL },
    { "shape position 1e200", shape_position, 1e200, "shape position", NULL },
    { "shape friction 1e300", shape_friction, 1e300, "friction", NULL },
    { "plane offset 1e308", plane_offset, 1e308, "plane offset", NULL },
    /* the world */
    { "gravity 1e300", gravity, 1e300, "gravity", NULL },
    { "gravity 1e30", gravity, 1e30, NULL, NULL },
    { "drag 1e300", drag, 1e300, "drag", NULL },
    { "tolerance 1e-300", tolerance, 1e-300, "tolerance", NULL },
    { "step 1e-300", step, 1e-300, "step", NULL },
    { "step 1e300", step, 1e300, "step", NULL },
    { "contact hertz 1e300", hertz, 1e300, "hertz", NULL },
    { "contact substeps INT_MAX", substeps, (double)INT_MAX, "substeps", NULL },
    { "contact substeps 0", substeps, 0, "substeps", NULL },
    { "sleep time 1e300", sleep_time, 1e300, "sleep_time", NULL },
    { "uniform field 1e308", uniform_field, 1e308, "uniform field", NULL },
    { "vortex field 1e200 rad/s", vortex_field, 1e200, "vortex field", NULL },
};

static const char *const integrators[] = { "euler", "symplectic_euler", "verlet", "rk4", "verlet_exact",
                                           "implicit_euler", "dopri5", "auto" };

static void overflowing_inputs_are_refused_or_stay_finite(void **state)
{
    size_t k, m;
    int refused = 0, accepted = 0, step_refused = 0;
    (void)state;
    for (k = 0; k < sizeof probes / sizeof probes[0]; ++k) {
        const probe *pr = &probes[k];
        for (m = 0; m < sizeof integrators / sizeof integrators[0]; ++m) {
            scene probed, twin;
            double a[SEEN], b[SEEN];
            size_t na, nb;
            tb_status st;
            char what[160];
            snprintf(what, sizeof what, "%s (%s)", pr->name, integrators[m]);
            build(&probed, integrators[m]);
            build(&twin, integrators[m]);
            if (pr->prepare) {
                assert_int_equal(pr->prepare(&probed, pr->value), TB_OK);
                assert_int_equal(pr->prepare(&twin, pr->value), TB_OK);
            }
            st = pr->fn(&probed, pr->value);
            if (pr->named) {
                if (st != TB_ERR_ARGUMENT)
                    fail_msg("%s: status %s, expected a refusal", what, tb_status_name(st));
                if (!strstr(tb_world_message(probed.w), pr->named))
                    fail_msg("%s: the message \"%s\" does not name %s", what, tb_world_message(probed.w),
                             pr->named);
                if (m == 0)
                    print_message("%s: %s\n", pr->name, tb_world_message(probed.w));
                /* as its twin, before and after a step */
                na = look(probed.w, a), nb = look(twin.w, b);
                assert_int_equal(na, nb);
                assert_memory_equal(a, b, na * sizeof a[0]);
                st = tb_world_step(probed.w, 1.0 / 60);
                assert_int_equal(tb_world_step(twin.w, 1.0 / 60), st);
                if (st != TB_OK) { /* the scene itself cannot be stepped so: the same refusal */
                    print_message("%s: then the step is refused: %s\n", what, tb_world_message(twin.w));
                    assert_string_equal(tb_world_message(probed.w), tb_world_message(twin.w));
                }
                na = look(probed.w, a), nb = look(twin.w, b);
                assert_memory_equal(a, b, na * sizeof a[0]);
                ++refused;
            } else {
                if (st != TB_OK)
                    fail_msg("%s: refused (%s)", what, tb_world_message(probed.w));
                /* the twin, guarded, takes the same value and step: it is
                   sound, or the guard (or an adaptive method) refuses it
                   with the world as it was, and a smaller step is sound */
                assert_int_equal(tb_world_set_guard(twin.w, INFINITY), TB_OK);
                assert_int_equal(pr->fn(&twin, pr->value), TB_OK);
                na = look(twin.w, a);
                st = tb_world_step(twin.w, 1.0 / 60);
                if (st == TB_OK) {
                    assert_sound(twin.w, what);
                    /* unguarded, the same step gives the same state */
                    assert_int_equal(tb_world_step(probed.w, 1.0 / 60), TB_OK);
                    na = look(twin.w, a), nb = look(probed.w, b);
                    assert_memory_equal(a, b, na * sizeof a[0]);
                    ++accepted;
                } else {
                    print_message("%s, guarded: the step is refused: %s\n", what, tb_world_message(twin.w));
                    nb = look(twin.w, b);
                    assert_int_equal(na, nb);
                    assert_memory_equal(a, b, na * sizeof a[0]);
                    st = tb_world_step(twin.w, 1e-60);
                    if (st != TB_OK && strstr(tb_world_message(twin.w), "try implicit_euler")) {
                        /* an adaptive method takes no substep below 1e-14 s: do as it says */
                        assert_int_equal(tb_world_set_integrator(twin.w, "implicit_euler"), TB_OK);
                        st = tb_world_step(twin.w, 1.0 / 60);
                    }
                    if (st != TB_OK)
                        fail_msg("%s: stuck: a smaller step is refused too: %s", what, tb_world_message(twin.w));
                    assert_sound(twin.w, what);
                    ++step_refused;
                }
            }
            tb_world_destroy(probed.w);
            tb_world_destroy(twin.w);
        }
    }
    print_message("over %d integrators: %d refusals, %d accepted extremes stepped soundly, %d steps refused\n",
                  (int)(sizeof integrators / sizeof integrators[0]), refused, accepted, step_refused);
}

/* ---- NULL pointers ------------------------------------------------------------ */

static tb_status no_field(const tb_field_args *args, void *user)
{
    (void)args, (void)user;
    return TB_OK;
}

static tb_status no_force(const tb_force_args *args, void *user)
{
    (void)args, (void)user;
    return TB_OK;
}

/* A refusal for a NULL the header does not allow: TB_ERR_ARGUMENT, a
   message that says what was NULL (when there is a world to hold it). */
#define assert_null_refused(w, call)                                                   \
    do {                                                                               \
        assert_int_equal((call), TB_ERR_ARGUMENT);                                     \
        if (w)                                                                         \
            assert_non_null(strstr(tb_world_message(w), "NULL"));                      \
    } while (0)

/* Every public function that takes a pointer, given NULL for each one in
   turn: a NULL world and each other argument the header does not allow to
   be NULL are refused, and nothing changes; the ones it allows work. */
static void null_pointers_are_refused(void **state)
{
    scene s;
    tb_world *const none = NULL;
    const tb_world_def wd = tb_default_world_def();
    const tb_tracer_def td = tb_default_tracer_def();
    const tb_particle_def pd = tb_default_particle_def();
    const tb_body_def bd = tb_default_body_def();
    const tb_shape_def sd = tb_default_shape_def();
    const tb_contact_settings cs = tb_default_contact_settings();
    tb_spring_def spd = tb_default_spring_def();
    const double v[3] = { 0, 0, 1 }, q[4] = { 1, 0, 0, 0 }, tensor[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 };
    const double points[9] = { 0, 0, 0, 1, 0, 0, 0, 1, 0 }, masses[3] = { 1, 1, 1 };
    const uint32_t tri[3] = { 0, 1, 2 };
    const tb_tracer_id tracer = { 1, 1 };
    const tb_field_id field = { 1, 1 };
    const tb_force_id force = { 1, 1 };
    const tb_shape_id shape = { 1, 1 };
    double out[4], seen_before[SEEN], seen_after[SEEN], m;
    int flag;
    long substeps = 7;
    size_t count = 7, n;
    tb_world *made = (tb_world *)&count;
    tb_mass mass;
    tb_advice advice;
    tb_energy e;
    (void)state;
    build(&s, "verlet");
    spd.a = s.p;
    n = look(s.w, seen_before);

    /* the world */
    assert_null_refused(none, tb_world_create(NULL, &made, NULL, 0));
    assert_null(made);
    assert_null_refused(none, tb_world_create(&wd, NULL, NULL, 0));
    tb_world_destroy(NULL);
    assert_non_null(strstr(tb_world_message(NULL), "NULL"));
    assert_true(tb_world_time(NULL) == 0);
    assert_null_refused(none, tb_world_set_gravity(NULL, v));
    assert_null_refused(s.w, tb_world_set_gravity(s.w, NULL));
    out[0] = 42;
    tb_world_gravity(NULL, out);
    assert_true(out[0] == 42); /* nothing written */
    tb_world_gravity(s.w, NULL);
    assert_null_refused(none, tb_world_set_drag(NULL, 0, 0));
    assert_null_refused(none, tb_world_set_integrator(NULL, "rk4"));
    assert_int_equal(tb_world_set_integrator(s.w, NULL), TB_ERR_ARGUMENT);
    assert_null_refused(none, tb_world_set_tolerance(NULL, 1e-6));
    assert_true(tb_world_tolerance(NULL) == 0);
    assert_null(tb_world_integrator(NULL));
    assert_null(tb_world_auto_choice(NULL, &substeps));
    assert_int_equal(substeps, 0);
    assert_null(tb_world_auto_choice(s.w, NULL)); /* allowed: no step taken by auto */
    assert_null_refused(none, tb_world_step(NULL, 0.01));
    assert_null_refused(none, tb_world_set_guard(NULL, 2));
    assert_true(tb_world_guard(NULL) == 0);

    /* tracers and fields */
    assert_null_refused(none, tb_world_add_tracer(NULL, &td, NULL));
    assert_null_refused(s.w, tb_world_add_tracer(s.w, NULL, NULL));
    assert_null_refused(none, tb_world_remove_tracer(NULL, tracer));
    assert_null_refused(none, tb_tracer_position(NULL, tracer, out));
    assert_null_refused(none, tb_tracer_set_position(NULL, tracer, v));
    assert_int_equal(tb_world_tracer_count(NULL), 0);
    assert_null(tb_world_tracer_positions(NULL));
    assert_true(TB_ID_IS_NULL(tb_world_tracer_at(NULL, 0)));
    assert_null_refused(none, tb_world_tracer_velocities(NULL, out));
    assert_null_refused(s.w, tb_world_tracer_velocities(s.w, NULL));
    assert_null_refused(none, tb_world_add_uniform_field(NULL, v, NULL));
    assert_null_refused(s.w, tb_world_add_uniform_field(s.w, NULL, NULL));
    assert_null_refused(none, tb_world_add_vortex_field(NULL, v, v, NULL));
    assert_null_refused(s.w, tb_world_add_vortex_field(s.w, NULL, v, NULL));
    assert_null_refused(s.w, tb_world_add_vortex_field(s.w, v, NULL, NULL));
    assert_null_refused(none, tb_world_add_field(NULL, no_field, NULL, NULL));
    assert_null_refused(s.w, tb_world_add_field(s.w, NULL, NULL, NULL));
    assert_null_refused(none, tb_world_remove_field(NULL, field));

    /* particles and springs */
    assert_null_refused(none, tb_world_add_particle(NULL, &pd, NULL));
    assert_null_refused(s.w, tb_world_add_particle(s.w, NULL, NULL));
    assert_null_refused(none, tb_world_remove_particle(NULL, s.p));
    assert_null_refused(none, tb_particle_position(NULL, s.p, out));
    assert_null_refused(s.w, tb_particle_position(s.w, s.p, NULL));
    assert_null_refused(none, tb_particle_velocity(NULL, s.p, out));
    assert_null_refused(s.w, tb_particle_velocity(s.w, s.p, NULL));
    assert_null_refused(none, tb_particle_mass(NULL, s.p, &m));
    assert_null_refused(s.w, tb_particle_mass(s.w, s.p, NULL));
    assert_null_refused(none, tb_particle_set_position(NULL, s.p, v));
    assert_null_refused(s.w, tb_particle_set_position(s.w, s.p, NULL));
    assert_null_refused(none, tb_particle_set_velocity(NULL, s.p, v));
    assert_null_refused(s.w, tb_particle_set_velocity(s.w, s.p, NULL));
    assert_int_equal(tb_world_particle_count(NULL), 0);
    assert_null(tb_world_particle_positions(NULL));
    assert_null(tb_world_particle_velocities(NULL));
    assert_null(tb_world_particle_masses(NULL));
    assert_true(TB_ID_IS_NULL(tb_world_particle_at(NULL, 0)));
    assert_null_refused(none, tb_world_add_spring(NULL, &spd, NULL));
    assert_null_refused(s.w, tb_world_add_spring(s.w, NULL, NULL));
    assert_null_refused(none, tb_world_remove_spring(NULL, s.spring));
    assert_int_equal(tb_world_spring_count(NULL), 0);

    /* mass properties: no world, the message buffer may be NULL */
    assert_int_equal(tb_mass_sphere(1, 1, NULL, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_box(1, NULL, &mass, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_box(1, v, NULL, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_cylinder(1, 1, 1, NULL, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_capsule(1, 1, 1, NULL, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_points(3, NULL, masses, &mass, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_points(3, points, NULL, &mass, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_points(3, points, masses, NULL, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_mesh(1, 3, NULL, 1, tri, &mass, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_mesh(1, 3, points, 1, NULL, &mass, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_mesh(1, 3, points, 1, tri, NULL, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_from_tensor(1, NULL, tensor, &mass, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_from_tensor(1, v, NULL, &mass, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_from_tensor(1, v, tensor, NULL, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_mass_set_total(NULL, 1, NULL), TB_ERR_ARGUMENT);

    /* bodies */
    assert_null_refused(none, tb_world_add_body(NULL, &bd, NULL));
    assert_null_refused(s.w, tb_world_add_body(s.w, NULL, NULL));
    assert_null_refused(none, tb_world_remove_body(NULL, s.body));
    assert_null_refused(none, tb_body_position(NULL, s.body, out));
    assert_null_refused(s.w, tb_body_position(s.w, s.body, NULL));
    assert_null_refused(none, tb_body_orientation(NULL, s.body, out));
    assert_null_refused(s.w, tb_body_orientation(s.w, s.body, NULL));
    assert_null_refused(none, tb_body_velocity(NULL, s.body, out));
    assert_null_refused(s.w, tb_body_velocity(s.w, s.body, NULL));
    assert_null_refused(none, tb_body_angular_velocity(NULL, s.body, out));
    assert_null_refused(s.w, tb_body_angular_velocity(s.w, s.body, NULL));
    assert_null_refused(none, tb_body_momentum(NULL, s.body, out, out));
    assert_int_equal(tb_body_momentum(s.w, s.body, NULL, NULL), TB_OK); /* allowed */
    assert_null_refused(none, tb_body_mass(NULL, s.body, &m, out));
    assert_int_equal(tb_body_mass(s.w, s.body, NULL, NULL), TB_OK); /* allowed */
    assert_null_refused(none, tb_body_set_position(NULL, s.body, v));
    assert_null_refused(s.w, tb_body_set_position(s.w, s.body, NULL));
    assert_null_refused(none, tb_body_set_orientation(NULL, s.body, q));
    assert_null_refused(s.w, tb_body_set_orientation(s.w, s.body, NULL));
    assert_null_refused(none, tb_body_set_velocity(NULL, s.body, v));
    assert_null_refused(s.w, tb_body_set_velocity(s.w, s.body, NULL));
    assert_null_refused(none, tb_body_set_angular_velocity(NULL, s.body, v));
    assert_null_refused(s.w, tb_body_set_angular_velocity(s.w, s.body, NULL));
    assert_null_refused(none, tb_body_apply_force(NULL, s.body, v, v));
    assert_null_refused(s.w, tb_body_apply_force(s.w, s.body, NULL, v));
    assert_null_refused(s.w, tb_body_apply_force(s.w, s.body, v, NULL));
    assert_null_refused(none, tb_body_apply_force_at_body_point(NULL, s.body, v, v));
    assert_null_refused(s.w, tb_body_apply_force_at_body_point(s.w, s.body, NULL, v));
    assert_null_refused(s.w, tb_body_apply_force_at_body_point(s.w, s.body, v, NULL));
    assert_null_refused(none, tb_body_apply_torque(NULL, s.body, v));
    assert_null_refused(s.w, tb_body_apply_torque(s.w, s.body, NULL));
    assert_int_equal(tb_world_body_count(NULL), 0);
    assert_null(tb_world_body_positions(NULL));
    assert_null(tb_world_body_orientations(NULL));
    assert_true(TB_ID_IS_NULL(tb_world_body_at(NULL, 0)));

    /* user forces, shapes, contacts, sleep */
    assert_null_refused(none, tb_world_add_force(NULL, no_force, NULL, NULL));
    assert_null_refused(s.w, tb_world_add_force(s.w, NULL, NULL, NULL));
    assert_null_refused(none, tb_world_remove_force(NULL, force));
    assert_null_refused(none, tb_world_add_shape(NULL, &sd, NULL));
    assert_null_refused(s.w, tb_world_add_shape(s.w, NULL, NULL));
    assert_null_refused(none, tb_world_remove_shape(NULL, shape));
    assert_int_equal(tb_world_shape_count(NULL), 0);
    assert_null_refused(none, tb_world_set_contact_settings(NULL, &cs));
    assert_null_refused(s.w, tb_world_set_contact_settings(s.w, NULL));
    assert_true(tb_world_contact_settings(NULL).hertz == cs.hertz);
    assert_null(tb_world_contact_events(NULL, &count));
    assert_int_equal(count, 0);
    (void)tb_world_contact_events(s.w, NULL); /* allowed */
    assert_int_equal(tb_world_contact_count(NULL), 0);
    assert_null_refused(none, tb_body_asleep(NULL, s.body, &flag));
    assert_null_refused(s.w, tb_body_asleep(s.w, s.body, NULL));
    assert_null_refused(none, tb_body_wake(NULL, s.body));
    assert_int_equal(tb_world_sleeping_count(NULL), 0);

    /* advisor, diagnostics */
    assert_null_refused(none, tb_world_advise(NULL, 0.01, &advice));
    assert_null_refused(s.w, tb_world_advise(s.w, 0.01, NULL));
    e = tb_world_energy(NULL);
    assert_true(e.total == 0 && e.kinetic == 0);
    out[0] = 42;
    tb_world_momentum(NULL, out);
    tb_world_angular_momentum(NULL, out);
    assert_true(out[0] == 42);
    tb_world_momentum(s.w, NULL);
    tb_world_angular_momentum(s.w, NULL);

    /* nothing changed, and the world steps */
    assert_int_equal(look(s.w, seen_after), n);
    assert_memory_equal(seen_before, seen_after, n * sizeof seen_before[0]);
    assert_int_equal(tb_world_step(s.w, 0.01), TB_OK);
    tb_world_destroy(s.w);
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(overflowing_inputs_are_refused_or_stay_finite),
    cmocka_unit_test(null_pointers_are_refused),
};
TB_TEST_MAIN(tests)
