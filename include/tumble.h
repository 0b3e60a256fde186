/* tumble.h: the public C API of tumble, a physics library for virtual worlds.

   A world keeps its state in flat arrays per quantity (positions, velocities,
   masses, ...) and steps it with one of several integrators chosen by name.
   Objects are addressed by generation-checked value ids (tumble/id.h).
   Units are SI, axes right-handed, gravity a world setting.

   Rules that hold for every function below:
   - a function that can fail returns a tb_status; on failure the world is
     unchanged and tb_world_message() holds a one-line reason;
   - NaN or Inf, non-positive masses or steps, negative stiffness, unknown
     names and stale ids are refused, never crash, abort or exit;
   - pointers to state arrays stay valid until the next step or structural
     change (adding or removing an object) of that world;
   - structural changes, setters and nested steps are refused (TB_ERR_BUSY)
     while the world is stepping, that is, from inside a force or field
     callback (callbacks only add to the forces or velocities they are given);
   - worlds share nothing: several may live in one process and each may be
     stepped on its own thread. */
#ifndef TUMBLE_H
#define TUMBLE_H

#include "tumble/base.h"
#include "tumble/id.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tb_world tb_world;

typedef struct tb_field_id { uint32_t index1; uint32_t generation; } tb_field_id;
typedef struct tb_force_id { uint32_t index1; uint32_t generation; } tb_force_id;

/* ---------------------------------------------------------------- world -- */

typedef struct tb_world_def {
    double gravity[3];       /* m/s^2; default (0, 0, -9.81): z is up */
    double linear_drag;      /* N s/m; every particle feels -c v; default 0 */
    double quadratic_drag;   /* N s^2/m^2; every particle feels -c |v| v; default 0 */
    const char *integrator;  /* a name from tb_integrator_name(); NULL: "verlet" */
    double tolerance;        /* error per step asked of adaptive methods ("dopri5"),
                                relative to 1 + |y| per state component; 0: 1e-6 */
    tb_allocator allocator;  /* all of the world's memory goes through it */
} tb_world_def;

/* The defaults above. Start from this and change what you need. */
TB_API tb_world_def tb_default_world_def(void);

/* Create a world. On failure *world is NULL and, when message is not NULL,
   the reason is written to it (at most message_size bytes). */
TB_API tb_status tb_world_create(const tb_world_def *def, tb_world **world,
                                 char *message, size_t message_size);

/* Free the world and everything in it. NULL is ignored. Never call it from
   inside the world's own callbacks. */
TB_API void tb_world_destroy(tb_world *world);

/* The reason for the last failure in this world ("" if none yet). */
TB_API const char *tb_world_message(const tb_world *world);

/* Simulated time in seconds: the sum of all completed steps. */
TB_API double tb_world_time(const tb_world *world);

TB_API tb_status tb_world_set_gravity(tb_world *world, const double gravity[3]);
TB_API void tb_world_gravity(const tb_world *world, double gravity[3]);

/* Drag on every particle: f = -(linear + quadratic |v|) v. Both >= 0. */
TB_API tb_status tb_world_set_drag(tb_world *world, double linear, double quadratic);

/* ----------------------------------------------------------- stepping -- */

/* Integrators, by name. Costs are per step; bodies' rotations are noted
   where the methods differ (a body's rotation is its free motion: with L as
   state, kicks change L and drifts turn q through the torque-free motion).
     "euler"            explicit (forward) Euler. Order 1, 1 force evaluation.
                        Unstable on undamped oscillations at any step.
     "symplectic_euler" semi-implicit Euler: kick v (P, L) with the forces at
                        the start, then drift x with the new v. Order 1, 1
                        evaluation; ODE's dWorldStep for free bodies (the
                        centre of mass matches it to rounding). Bodies turn
                        with w frozen over the step (order 1). Oscillations
                        stay bounded for h w < 2.
     "verlet"           velocity Verlet: kick h/2, drift h, kick h/2. Order 2,
                        2 evaluations (the end-of-step forces are not reused
                        because they may depend on velocity). Bounded for
                        h w < 2. Drag, damping and callbacks are evaluated for
                        the closing kick at the predicted end velocity
                        v_n + h a_n, which keeps order 2 with damping. Bodies
                        turn by a symmetric splitting of their kinetic energy
                        into exact rotations (order 2, |L| exact, energy error
                        bounded; exact for spheres and symmetric tops).
     "rk4"              classic Runge-Kutta on (x, q, P, L). Order 4, 4
                        evaluations; slightly dissipative; stable on
                        oscillations for h w < 2 sqrt 2. Quaternions are
                        renormalised at the end of each step.
     "verlet_exact"     "verlet" whose drift turns anisotropic bodies with a
                        fourth-order composition of the same exact rotations
                        (13 per step): |L| exact, energy error ~1e-10 and
                        orientation within 1e-9 rad on the intermediate-axis
                        flip at 60 Hz over 20 s. Costs about 2x "verlet" per
                        anisotropic body; the same as "verlet" otherwise.
     "implicit_euler"   linearised backward Euler for particles (Baraff and
                        Witkin): one conjugate-gradient solve of
                        (M + h D + h^2 K) dv = h (f0 - h K v0) per step, with
                        the springs' stiffness K and the damping and drag
                        Jacobian D; callbacks enter the forces but not the
                        Jacobians. Order 1, 1 evaluation plus the solve.
                        Stable at any step on springs and drag, and it damps:
                        a spring's v^2 + w^2 x^2 shrinks by 1 / (1 + (h w)^2)
                        per step (x0.535 per period at h w = 0.1). Bodies are
                        kicked and drifted as in "verlet"'s rotation.
     "dopri5"           Dormand-Prince 5(4), error-controlled: each step of h
                        is taken in as many substeps as the tolerance needs
                        (tb_world_set_tolerance), each checked by the embedded
                        fourth-order solution (RMS of the local error over
                        the state, scaled by tolerance (1 + |y|)). Order 5,
                        6 evaluations per accepted substep (the seventh is
                        reused); the substep size carries over between steps.
     "auto"             picks, from what the world contains, the cheapest of
                        "verlet", "verlet_exact", "rk4" and "dopri5" and a
                        number of equal substeps whose estimated local error
                        per step meets the tolerance (same norm as "dopri5"):
                        each method errs by about C (r s)^(p+1) per substep s
                        on the scene's fastest rates r (stiffest spring mode,
                        drag and damping, body spin, vortex fields; gravity
                        costs the split methods nothing). Force and field
                        callbacks hide their rates, so worlds with them get
                        "dopri5". The choice is made again when the step, the
                        tolerance or the set of objects changes, and is
                        shown by tb_world_auto_choice.
   The split methods ("symplectic_euler", "verlet", "verlet_exact",
   "implicit_euler") need a velocity to kick: tracers have none, so a world holding tracers refuses
   them (and a world using them refuses tracers). "euler" and "rk4" move
   tracers, particles and bodies alike. Force callbacks run once per force
   evaluation. */
TB_API int tb_integrator_count(void);
TB_API const char *tb_integrator_name(int index);   /* NULL past the end */
TB_API int tb_integrator_order(int index);           /* 0 past the end */

TB_API tb_status tb_world_set_integrator(tb_world *world, const char *name);
/* The tolerance of adaptive methods (finite, > 0). */
TB_API tb_status tb_world_set_tolerance(tb_world *world, double tolerance);
TB_API double tb_world_tolerance(const tb_world *world);
TB_API const char *tb_world_integrator(const tb_world *world);

/* What "auto" chose for its last step: the method's name (NULL before the
   first step) and the substeps per step. */
TB_API const char *tb_world_auto_choice(const tb_world *world, long *substeps);

/* Advance by h seconds (finite, > 0). If a callback fails, the step is
   abandoned and the state is bit-identical to what it was before. */
TB_API tb_status tb_world_step(tb_world *world, double h);

/* The blow-up guard; off (0) by default, because it copies the state every
   step. When on, a step that leaves any position, velocity, orientation or
   momentum non-finite is undone and returns TB_ERR_UNSTABLE with a message
   naming the step, the object and the likely cause (the advisor's verdict,
   e.g. "step 0.02 s exceeds the limit 0.0126 s of symplectic_euler ...
   spring 17"); the world is back at the state before that step.
   energy_growth: 0 turns the guard off, INFINITY checks finiteness only,
   a factor > 1 also stops a step in which the kinetic, rotational and
   spring energy grows by more than that factor beyond what gravity
   released (forces that do work, such as callbacks, must fit in it; a
   world starting at rest is not checked until it moves). */
TB_API tb_status tb_world_set_guard(tb_world *world, double energy_growth);
TB_API double tb_world_guard(const tb_world *world);

/* -------------------------------------------------------------- tracers -- */
/* Tracers are massless points with only a position, carried by the sum of
   the world's velocity fields: dx/dt = v(x, t). */

typedef struct tb_tracer_def {
    double position[3];  /* m */
} tb_tracer_def;

TB_API tb_tracer_def tb_default_tracer_def(void);
TB_API tb_status tb_world_add_tracer(tb_world *world, const tb_tracer_def *def, tb_tracer_id *id);
TB_API tb_status tb_world_remove_tracer(tb_world *world, tb_tracer_id id);
TB_API tb_status tb_tracer_position(const tb_world *world, tb_tracer_id id, double position[3]);
TB_API tb_status tb_tracer_set_position(tb_world *world, tb_tracer_id id, const double position[3]);

TB_API size_t tb_world_tracer_count(const tb_world *world);
/* Flat array of 3 * count positions (m), in slot order. */
TB_API const double *tb_world_tracer_positions(const tb_world *world);
TB_API tb_tracer_id tb_world_tracer_at(const tb_world *world, size_t slot);
/* The field velocity (m/s) at each tracer now, 3 * count values. Calls the
   field callbacks, so it can fail like a step. */
TB_API tb_status tb_world_tracer_velocities(tb_world *world, double *velocities);

/* ---------------------------------------------------------------- fields -- */

/* Arguments of a velocity-field callback: add the field's velocity at each
   position to `velocities`. Return TB_OK, or fail with a reason in message. */
typedef struct tb_field_args {
    double time;                /* s */
    size_t count;
    const double *positions;    /* 3 * count, m */
    double *velocities;         /* 3 * count, m/s: add to it */
    char *message;              /* TB_MESSAGE_SIZE bytes */
} tb_field_args;
typedef tb_status tb_field_fn(const tb_field_args *args, void *user);

/* v = u everywhere. */
TB_API tb_status tb_world_add_uniform_field(tb_world *world, const double velocity[3], tb_field_id *id);
/* Rigid rotation: v = omega x (x - centre); omega in rad/s. */
TB_API tb_status tb_world_add_vortex_field(tb_world *world, const double omega[3],
                                           const double centre[3], tb_field_id *id);
TB_API tb_status tb_world_add_field(tb_world *world, tb_field_fn *fn, void *user, tb_field_id *id);
TB_API tb_status tb_world_remove_field(tb_world *world, tb_field_id id);

/* ------------------------------------------------------------ particles -- */
/* Point masses: dv/dt = f / m. A pinned particle has infinite inertia: it
   takes no force, keeps its velocity, and counts as mass 0 in diagnostics. */

typedef struct tb_particle_def {
    double position[3];  /* m */
    double velocity[3];  /* m/s */
    double mass;         /* kg, finite and > 0; default 1 */
    int pinned;          /* nonzero: immovable by forces (cloth corners) */
} tb_particle_def;

TB_API tb_particle_def tb_default_particle_def(void);
/* Adding a particle may move the state arrays. Removing one also removes
   the springs attached to it. */
TB_API tb_status tb_world_add_particle(tb_world *world, const tb_particle_def *def, tb_particle_id *id);
TB_API tb_status tb_world_remove_particle(tb_world *world, tb_particle_id id);
TB_API tb_status tb_particle_position(const tb_world *world, tb_particle_id id, double position[3]);
TB_API tb_status tb_particle_velocity(const tb_world *world, tb_particle_id id, double velocity[3]);
TB_API tb_status tb_particle_mass(const tb_world *world, tb_particle_id id, double *mass);
TB_API tb_status tb_particle_set_position(tb_world *world, tb_particle_id id, const double position[3]);
TB_API tb_status tb_particle_set_velocity(tb_world *world, tb_particle_id id, const double velocity[3]);

TB_API size_t tb_world_particle_count(const tb_world *world);
/* Flat arrays in slot order: 3 * count positions (m), 3 * count velocities
   (m/s), count masses (kg, 0 for pinned particles). */
TB_API const double *tb_world_particle_positions(const tb_world *world);
TB_API const double *tb_world_particle_velocities(const tb_world *world);
TB_API const double *tb_world_particle_masses(const tb_world *world);
TB_API tb_particle_id tb_world_particle_at(const tb_world *world, size_t slot);

/* -------------------------------------------------------------- springs -- */
/* Hooke springs with damping along their axis:
     f_a = -(k (|d| - rest) + c (v_a - v_b) . n) n,  d = x_a - x_b, n = d / |d|,
   and f_b = -f_a. With a null `b` the spring ties `a` to the fixed `anchor`. */

typedef struct tb_spring_def {
    tb_particle_id a;
    tb_particle_id b;        /* null: anchor the spring at `anchor` */
    double anchor[3];        /* m, used when b is null */
    double stiffness;        /* k, N/m, >= 0 */
    double damping;          /* c, N s/m, >= 0 */
    double rest_length;      /* m; negative (the default): the distance at creation */
} tb_spring_def;

TB_API tb_spring_def tb_default_spring_def(void);
TB_API tb_status tb_world_add_spring(tb_world *world, const tb_spring_def *def, tb_spring_id *id);
TB_API tb_status tb_world_remove_spring(tb_world *world, tb_spring_id id);
TB_API size_t tb_world_spring_count(const tb_world *world);

/* --------------------------------------------------------- mass properties -- */
/* Mass properties of a rigid body: its mass, centre of mass and principal
   moments of inertia, and the principal frame. Computed from shapes of
   uniform density, from point masses, from a closed triangle mesh, or from a
   full inertia tensor (diagonalised). These functions touch no world: on
   failure they return TB_ERR_ARGUMENT (tb_mass_mesh also TB_ERR_MEMORY: it
   sorts edges in scratch from malloc) and, when `message` is not NULL, write
   a one-line reason into it (TB_MESSAGE_SIZE bytes); *mass is untouched.
   Diagonalised results list the moments in ascending order with
   tensor = R(frame) diag(inertia) R(frame)^T, det R = +1 and frame w >= 0;
   the primitive shapes keep x, y, z order and the identity frame. */

typedef struct tb_mass {
    double mass;         /* kg, > 0 */
    double centre[3];    /* m, centre of mass in the shape's own frame */
    double inertia[3];   /* kg m^2, principal moments about the centre of mass */
    double frame[4];     /* unit quaternion (w, x, y, z) turning the principal
                            axes into the shape's frame (identity for the
                            primitive shapes, whose axes are principal) */
} tb_mass;

/* Solid sphere of radius r (m) and density rho (kg/m^3). */
TB_API tb_status tb_mass_sphere(double rho, double radius, tb_mass *mass, char *message);
/* Solid box with full side lengths size[3] (m), centred, axes along x, y, z. */
TB_API tb_status tb_mass_box(double rho, const double size[3], tb_mass *mass, char *message);
/* Solid cylinder of radius r and length l along z, centred. */
TB_API tb_status tb_mass_cylinder(double rho, double radius, double length, tb_mass *mass, char *message);
/* Capsule: a cylinder of radius r and length l >= 0 along z with two
   hemispherical caps (total length l + 2 r), centred; l = 0 is a sphere. */
TB_API tb_status tb_mass_capsule(double rho, double radius, double length, tb_mass *mass, char *message);
/* Point masses m_i (kg, > 0) at p_i (3 * count values, m): M = sum m_i,
   c = sum m_i p_i / M, I = sum m_i (r_i.r_i 1 - r_i r_i^T) with r_i = p_i - c,
   then diagonalised. Fewer than 3 non-collinear points give a singular
   tensor and are refused. */
TB_API tb_status tb_mass_points(size_t count, const double *positions, const double *masses,
                                tb_mass *mass, char *message);
/* Closed triangle mesh of uniform density: vertices (3 * vertex_count, m),
   triangles (3 * triangle_count vertex indices, counter-clockwise seen from
   outside). Open meshes (an edge not shared by exactly two triangles in
   opposite directions) and inside-out meshes (negative volume) are refused. */
TB_API tb_status tb_mass_mesh(double rho, size_t vertex_count, const double *vertices,
                              size_t triangle_count, const uint32_t *triangles, tb_mass *mass, char *message);
/* From a mass, a centre of mass and a full symmetric inertia tensor about
   that centre (row-major 3x3, kg m^2): diagonalised into principal moments
   and frame. A tensor that is not symmetric positive definite, or whose
   principal moments break the triangle inequality (I1 + I2 >= I3 for every
   order), is refused. */
TB_API tb_status tb_mass_from_tensor(double total_mass, const double centre[3], const double tensor[9],
                                     tb_mass *mass, char *message);
/* Scale to a given total mass (kg, finite and > 0), keeping the shape. */
TB_API tb_status tb_mass_set_total(tb_mass *mass, double total_mass, char *message);

/* --------------------------------------------------------------- bodies -- */
/* Rigid bodies. State: centre of mass x, orientation q (unit quaternion
   (w, x, y, z) turning the body's principal axes into the world), linear
   momentum P and angular momentum L (world frame, about the centre of mass):
     v = P / M,  w = R diag(1/I) R^T L,  dx/dt = v,  dq/dt = (0, w) q / 2,
     dP/dt = f,  dL/dt = tau.
   Keeping L (not w) as state means a torque-free body keeps L exactly and
   every rotation error lives in the orientation. Positions and orientations
   read back are those of the centre of mass and the principal axes. */

typedef struct tb_body_def {
    double position[3];         /* m: where the shape's frame origin goes */
    double orientation[4];      /* unit quaternion (w, x, y, z): world from shape
                                   frame; default identity */
    double velocity[3];         /* m/s, of the centre of mass */
    double angular_velocity[3]; /* rad/s, world frame */
    tb_mass mass;               /* default: 1 kg solid sphere of radius 0.5 m */
    double linear_damping;      /* 1/s: dP/dt gains -c P; default 0 */
    double angular_damping;     /* 1/s: dL/dt gains -c L; default 0 */
} tb_body_def;

TB_API tb_body_def tb_default_body_def(void);
/* The body's centre of mass goes to position + R(orientation) mass.centre
   and its principal axes to orientation * mass.frame. Refused: non-finite
   values, a quaternion whose norm is not 1 within 1e-6 (it is then
   normalised exactly), mass or moments that are not finite and > 0, moments
   that break the triangle inequality, negative damping. */
TB_API tb_status tb_world_add_body(tb_world *world, const tb_body_def *def, tb_body_id *id);
TB_API tb_status tb_world_remove_body(tb_world *world, tb_body_id id);

TB_API tb_status tb_body_position(const tb_world *world, tb_body_id id, double position[3]);
TB_API tb_status tb_body_orientation(const tb_world *world, tb_body_id id, double orientation[4]);
TB_API tb_status tb_body_velocity(const tb_world *world, tb_body_id id, double velocity[3]);
TB_API tb_status tb_body_angular_velocity(const tb_world *world, tb_body_id id, double angular_velocity[3]);
/* Linear momentum P (kg m/s) and angular momentum L about the centre of
   mass (kg m^2/s), world frame. Either pointer may be NULL. */
TB_API tb_status tb_body_momentum(const tb_world *world, tb_body_id id, double linear[3], double angular[3]);
TB_API tb_status tb_body_mass(const tb_world *world, tb_body_id id, double *mass, double inertia[3]);
TB_API tb_status tb_body_set_position(tb_world *world, tb_body_id id, const double position[3]);
TB_API tb_status tb_body_set_orientation(tb_world *world, tb_body_id id, const double orientation[4]);
TB_API tb_status tb_body_set_velocity(tb_world *world, tb_body_id id, const double velocity[3]);
TB_API tb_status tb_body_set_angular_velocity(tb_world *world, tb_body_id id, const double angular_velocity[3]);

/* Forces and torques held for the next step, then cleared (as in ODE): a
   force f (N) at a world point p (m) also adds the torque (p - x) x f; at a
   point given in the body's principal frame, p = x + R p_body. A torque is
   in N m, world frame. */
TB_API tb_status tb_body_apply_force(tb_world *world, tb_body_id id, const double force[3], const double point[3]);
TB_API tb_status tb_body_apply_force_at_body_point(tb_world *world, tb_body_id id, const double force[3],
                                                   const double body_point[3]);
TB_API tb_status tb_body_apply_torque(tb_world *world, tb_body_id id, const double torque[3]);

TB_API size_t tb_world_body_count(const tb_world *world);
/* Flat arrays in slot order: 3 * count centres of mass (m), 4 * count
   orientations (w, x, y, z). */
TB_API const double *tb_world_body_positions(const tb_world *world);
TB_API const double *tb_world_body_orientations(const tb_world *world);
TB_API tb_body_id tb_world_body_at(const tb_world *world, size_t slot);

/* ---------------------------------------------------------- user forces -- */

/* Arguments of a force callback: add forces (N) on the particles, forces
   and torques on the bodies. It is called once per force evaluation with
   whole arrays, never per object.
   The state it sees may be an intermediate stage of the integrator. */
typedef struct tb_force_args {
    double time;                /* s */
    size_t count;               /* particles */
    const double *positions;    /* 3 * count, m */
    const double *velocities;   /* 3 * count, m/s */
    const double *masses;       /* count, kg (0 for pinned) */
    double *forces;             /* 3 * count, N: add to it */
    size_t body_count;
    const double *body_positions;        /* 3 * body_count, m, centres of mass */
    const double *body_orientations;     /* 4 * body_count, (w, x, y, z) */
    const double *body_velocities;       /* 3 * body_count, m/s */
    const double *body_angular_velocities; /* 3 * body_count, rad/s, world */
    const double *body_masses;           /* body_count, kg */
    double *body_forces;        /* 3 * body_count, N at the centre of mass: add to it */
    double *body_torques;       /* 3 * body_count, N m, world frame: add to it */
    char *message;              /* TB_MESSAGE_SIZE bytes */
} tb_force_args;
typedef tb_status tb_force_fn(const tb_force_args *args, void *user);

TB_API tb_status tb_world_add_force(tb_world *world, tb_force_fn *fn, void *user, tb_force_id *id);
TB_API tb_status tb_world_remove_force(tb_world *world, tb_force_id id);

/* ------------------------------------------------------ shapes, contacts -- */
/* Shapes make things collide. A shape is attached to a body (it moves with
   it; its pose is given in the body's frame: centre of mass at the origin,
   axes along the principal axes, which for a body made with
   tb_mass_sphere/box/cylinder/capsule is the solid's own centred frame) or
   is static (pose in the world). Planes are static only. A world without shapes pays nothing for
   collision.

   A step with shapes: (1) contacts are found at the start positions, with
   speculative points for gaps the step may close (fast objects do not pass
   through thin ones); (2) the integrator moves everything as if nothing
   touched (any method); (3) a velocity pass of sequential impulses, warm
   started from the last step (its impulses scaled to this step's length,
   so steps may change from frame to frame), solves each pair of shapes as one patch
   over its touching points: v_n >= 0 where last step's normal force was
   centred, no tilt of one shape on the other
   while the centre of pressure can stay among the points (the weight a
   tall stack carries is shared between them in one step, not point by
   point over many sweeps: a column of 10 boxes stands still, of 20
   stands), Coulomb friction
   (|f_t| <= mu times the pair's normal force, and a twist about the
   normal up to that times the points' mean distance from the centre: the
   sliding force of friction at every point, in fewer rows), and
   moves positions as those impulses would have over the step: for resting
   and sliding contact as the integrator moves positions under a constant
   force (h/2 times the impulse for the methods exact on one: verlet, rk4,
   dopri5; h for symplectic and implicit Euler, 0 for explicit Euler), so
   that the free motion's fall and the push back cancel and a body at rest
   stays put under any method; by the time left after impact for a new
   contact (the impact is timed within the step, so a ball bounces to e^2
   of its height at any step size; not at all under explicit Euler, whose
   positions move with the velocity the step started with); a pair that
   strikes is solved to stop, then bounced by its normal force alone, after
   the sweeps (as Box2D v3 does: bounced while friction held the contact
   still, a spinning body took energy from nowhere), its centre leaving no
   faster than it came plus what gravity adds in the step; the
   sweeps alternate direction, so weight reaches the bottom of a stack
   within a pair of sweeps whatever order the points come in. A step where
   many contacts start at rest without last step's impulses (a scene built
   touching) first solves the normal force and tilts of every pair at rest
   together, by conjugate gradients, for the sweeps to start from: the
   moments that hold up a stack of boxes each offset from the one below
   reach the ground at once, where sweeps pass them down a pair at a time
   (staircases and random stacks of 8 built at rest stand to 1e-11 m;
   before, 9 of 12 fell). Kept awake for long (sleep off), 3 of 40 random
   stacks of 8 lean after 10 s or so and fall (with sleep on they fall
   asleep standing): the sweeps let a stack's lean grow from rounding by 2
   to 3% a step; stack_iterations of the same solve before each step's
   sweeps (8: all 40 stay within 1e-11 m for 30 s, for about 40% more of
   an awake pyramid's step) hold them. The
   same solve takes a body landing on one 10 or more times lighter or
   heavier (or resting on one 100 or more times), with the contacts
   under it: a box 10 to 10000 times heavier dropped on a light one stops
   on it (the sweeps alone threw it back up, and from 100 times it went
   through); (4) a
   position pass pushes overlaps apart without adding velocity: rigidly for
   gaps that closed, softly (contact_hertz, damping ratio) for overlaps
   that were already there; each pair first as a patch (its centre pushed
   and turned to the plane that best levels what its points need, so a
   long body comes out of an overlap whole instead of see-sawing end to
   end), then point by point. Momentum is exchanged by equal and opposite
   impulses, so it is conserved to rounding. Sleeping bodies (see "Sleep"
   below) are left out of (1) to (4) and keep their pose. A box against a
   plane touches at the corners of its face most against it that are in
   reach: a long thin box buried in the ground keeps both ends.
   Cost: a pair of shapes whose relative pose moved less than a tenth of
   the slop since they last collided keeps that manifold, its points
   carried on both shapes and their separations updated (a resting stack
   costs almost no narrowphase). The sweeps run on batches of up to 8
   manifolds that share no moving body, one instruction for all 8 where
   the processor has AVX2 or AVX-512; manifolds that share a body are met
   in the same order as in a plain loop, and every instruction set gives
   the same bits. */
typedef enum tb_shape_type { TB_SHAPE_SPHERE, TB_SHAPE_CAPSULE, TB_SHAPE_BOX, TB_SHAPE_PLANE } tb_shape_type;

typedef struct tb_shape_def {
    tb_shape_type type;
    tb_body_id body;          /* null: static */
    double position[3];       /* m: centre, in the body's principal frame (static: world) */
    double orientation[4];    /* unit quaternion: body (or world) from shape; default identity */
    double radius;            /* m: sphere, capsule; > 0 */
    double half_length;       /* m: capsule, half its core segment along the shape's z; >= 0 */
    double half_extents[3];   /* m: box; > 0 */
    double normal[3];         /* plane: unit outward normal; default (0, 0, 1) */
    double offset;            /* m, plane: points x with normal . x = offset */
    double friction;          /* Coulomb coefficient >= 0; default 0.6; a pair uses sqrt(mu_a mu_b) */
    double restitution;       /* 0 to 1; default 0; a pair uses the larger */
    double rolling_resistance;/* m: how far ahead of a rolling contact its normal force
                                 acts, so that rolling is resisted by a torque up to this
                                 times the normal force (ODE's rho, a tyre's or a ball's
                                 rolling resistance length); default 0 (a ball rolls on
                                 for ever); >= 0; a pair uses the larger */
    uint32_t category;        /* bits this shape is; default 1 */
    uint32_t mask;            /* bits it collides with; default all. A pair collides
                                 when each one's category meets the other's mask */
} tb_shape_def;

TB_API tb_shape_def tb_default_shape_def(void);
/* Refused: sizes <= 0 or not finite, a plane normal that is not unit within
   1e-6, a plane on a body, a stale body, friction < 0, restitution outside
   [0, 1], rolling_resistance < 0 or not finite, a non-unit orientation. */
TB_API tb_status tb_world_add_shape(tb_world *world, const tb_shape_def *def, tb_shape_id *id);
TB_API tb_status tb_world_remove_shape(tb_world *world, tb_shape_id id);
TB_API size_t tb_world_shape_count(const tb_world *world);
/* Removing a body removes its shapes. */

typedef struct tb_contact_settings {
    double hertz;                 /* 1/s: stiffness of the push that resolves old overlaps; default 30 */
    double damping_ratio;         /* of that push; default 10 */
    double max_push;              /* m/s: the fastest it separates overlaps; default 3 */
    double restitution_threshold; /* m/s: slower impacts do not bounce; default 1 */
    double slop;                  /* m: overlap left alone, against jitter; default 0.005 */
    int velocity_iterations;      /* the most sweeps of the velocity pass; default 20 (a
                                     step where many contacts start touching without last
                                     step's impulses sweeps on, up to 16 times as many,
                                     until their total normal impulse settles) */
    double velocity_tolerance;    /* m/s (rad/s for turns): the velocity pass stops early,
                                     after 4 sweeps or more, once a pair of sweeps changed
                                     no velocity it enforces by more than this; default
                                     1e-6; 0: always velocity_iterations sweeps */
    int position_iterations;      /* sweeps of the position pass (each pair as a patch,
                                     then its points); default 3 */
    int stack_iterations;         /* conjugate-gradient iterations on the normal force and
                                     tilts of every pair at rest, together, before the
                                     sweeps of each step: they hold stacks of boxes each
                                     offset from the one below kept awake for long, which
                                     the sweeps alone let lean and fall; 8 hold 40 random
                                     stacks of 8 to 1e-11 m and cost about 40% of an
                                     awake pyramid's step; default 0 (none) */
    double particle_radius;       /* m: particles collide with shapes as spheres of this
                                     radius (0: points); < 0 (default -1): they do not */
    double particle_friction;     /* default 0.6 */
    double particle_restitution;  /* default 0 */
    double sleep_speed;           /* m/s: a body slower than this (|v| + |w| times its
                                     shapes' reach), and that moved less than this times
                                     the step in it (the position pass lifts a buried body
                                     without giving it speed), is resting; default 0.05 */
    double sleep_time;            /* s: an island of touching bodies that all rest this
                                     long falls asleep; default 0.5, INFINITY: never */
} tb_contact_settings;

TB_API tb_contact_settings tb_default_contact_settings(void);
TB_API tb_status tb_world_set_contact_settings(tb_world *world, const tb_contact_settings *settings);
TB_API tb_contact_settings tb_world_contact_settings(const tb_world *world);

typedef enum tb_contact_event_type { TB_CONTACT_BEGIN, TB_CONTACT_END } tb_contact_event_type;
typedef struct tb_contact_event {
    tb_contact_event_type type;
    tb_shape_id a;            /* the first shape */
    tb_shape_id b;            /* the second shape (null when a particle touches a) */
    tb_particle_id particle;  /* the particle (null for shape pairs) */
    double speed;             /* m/s: the approach speed at impact (begin events) */
    double point[3];          /* m, world: a contact point (begin events) */
    double normal[3];         /* unit, from a to b (begin events) */
} tb_contact_event;

/* The contacts that began and ended in the last step, valid until the next
   step or structural change. */
TB_API const tb_contact_event *tb_world_contact_events(const tb_world *world, size_t *count);
/* Points of contact that are touching now (after the last step). */
TB_API size_t tb_world_contact_count(const tb_world *world);

/* Sleep: bodies with shapes that rest together (an island: bodies joined
   by touching contacts) for sleep_time fall asleep. A sleeping body keeps
   its pose with zero velocity, costs no narrowphase and no solver work
   (the integrator still passes over it), and acts as static ground for
   slow particles. It wakes, with its whole island, when an awake body's
   bounds (or a particle faster than sleep_speed) reach its own, when any of
   its state is set or a force or torque applied, when a body of its island
   is removed, and when gravity, shapes or contact settings change. Worlds
   with force callbacks never sleep: a callback's force is unknown to the
   rest test. */
TB_API tb_status tb_body_asleep(const tb_world *world, tb_body_id id, int *asleep);
TB_API tb_status tb_body_wake(tb_world *world, tb_body_id id);
TB_API size_t tb_world_sleeping_count(const tb_world *world);

/* --------------------------------------------------------------- advisor -- */
/* Before a run: how large a step the world's integrator can take. The
   stiffest spring mode w is estimated by power iteration on M^-1 K (the
   springs' stiffness at the current positions, pinned particles excluded),
   the fastest decay k from drag; the method's limit is then
   min(c_osc / w, c_decay / k), with c_osc = 2 for the split methods,
   2 sqrt 2 for RK4 and 0 for explicit Euler (unstable on any oscillation),
   and c_decay = 2 (2.785 for RK4). */
typedef struct tb_advice {
    double stiffest;          /* rad/s, the fastest spring oscillation (0: none) */
    double decay;             /* 1/s, the fastest drag decay rate (0: none) */
    double fastest_spin;      /* rad/s, the fastest body spin (information) */
    double limit;             /* s, the largest stable step of the integrator;
                                 INFINITY when nothing limits it, 0 when no step is stable */
    int exceeded;             /* the step asked about is above the limit */
    tb_spring_id spring;      /* the stiffest mode's stiffest spring (null: none) */
    char text[TB_MESSAGE_SIZE]; /* one line: the verdict, and a step or method to use */
} tb_advice;

/* Estimate the stability limit of the world's integrator for a step h
   (finite, > 0). Does not change the world. */
TB_API tb_status tb_world_advise(tb_world *world, double h, tb_advice *advice);

/* ---------------------------------------------------------- diagnostics -- */

typedef struct tb_energy {
    double kinetic;          /* J, translational: sum of m v^2 / 2 */
    double rotational;       /* J, bodies: sum of L . w / 2 */
    double gravity;          /* J, sum of -m g . x (zero at the origin) */
    double spring;           /* J, sum of k (|d| - rest)^2 / 2 */
    double total;            /* J */
} tb_energy;

TB_API tb_energy tb_world_energy(const tb_world *world);
/* Total linear momentum, kg m/s. */
TB_API void tb_world_momentum(const tb_world *world, double momentum[3]);
/* Total angular momentum about the world origin, kg m^2/s:
   sum m x x v over particles, sum (x x P + L) over bodies. */
TB_API void tb_world_angular_momentum(const tb_world *world, double angular[3]);

#ifdef __cplusplus
}
#endif
#endif
