/* tumble/types.h: the types the API passes by value or by pointer: the
   opaque world, definitions (tb_*_def) with their defaults, settings,
   callback arguments and callbacks, events and results. Units are SI.
   Each tb_*_def has a tb_default_*_def() in tumble.h: start from it and
   change what you need. */
#ifndef TUMBLE_TYPES_H
#define TUMBLE_TYPES_H

#include "base.h"
#include "id.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A world: made by tb_world_create, freed by tb_world_destroy. */
typedef struct tb_world tb_world;
/* A copy of a whole world (tb_world_snapshot). */
typedef struct tb_snapshot tb_snapshot;

/* ---------------------------------------------------------------- world -- */

typedef struct tb_world_def {
    double gravity[3];       /* m/s^2; default (0, 0, -9.81): z is up */
    double linear_drag;      /* N s/m; every particle feels -c v; default 0 */
    double quadratic_drag;   /* N s^2/m^2; every particle feels -c |v| v; default 0 */
    const char *integrator;  /* a name from tb_integrator_name(); NULL: "verlet" */
    double tolerance;        /* error per second of simulated time asked of the
                                adaptive methods ("dopri5", "auto"), relative to
                                1 + |y| per state component; 0: 1e-6 */
    tb_allocator allocator;  /* all of the world's memory goes through it */
} tb_world_def;

/* -------------------------------------------------------------- tracers -- */

typedef struct tb_tracer_def {
    double position[3];  /* m */
} tb_tracer_def;

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

/* ------------------------------------------------------------ particles -- */

typedef struct tb_particle_def {
    double position[3];  /* m */
    double velocity[3];  /* m/s */
    double mass;         /* kg, from 1e-100 to 1e100 (TB_LIMIT); default 1 */
    int pinned;          /* nonzero: immovable by forces (cloth corners) */
} tb_particle_def;

/* -------------------------------------------------------------- springs -- */

typedef struct tb_spring_def {
    tb_particle_id a;
    tb_particle_id b;        /* null: anchor the spring at `anchor` */
    double anchor[3];        /* m, used when b is null */
    double stiffness;        /* k, N/m, >= 0 */
    double damping;          /* c, N s/m, >= 0 */
    double rest_length;      /* m; negative (the default): the distance at creation */
} tb_spring_def;

/* --------------------------------------------------------- mass properties -- */

/* Mass properties of a rigid body. Diagonalised results list the moments in
   ascending order with tensor = R(frame) diag(inertia) R(frame)^T, det R = +1
   and frame w >= 0; the primitive shapes keep x, y, z order and the identity
   frame. */
typedef struct tb_mass {
    double mass;         /* kg, > 0 */
    double centre[3];    /* m, centre of mass in the shape's own frame */
    double inertia[3];   /* kg m^2, principal moments about the centre of mass */
    double frame[4];     /* unit quaternion (w, x, y, z) turning the principal
                            axes into the shape's frame (identity for the
                            primitive shapes, whose axes are principal) */
} tb_mass;

/* --------------------------------------------------------------- bodies -- */

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

/* ---------------------------------------------------------- user forces -- */

/* Arguments of a force callback: add forces (N) on the particles, forces
   and torques on the bodies. It is called once per force evaluation with
   whole arrays, never per object; the state it sees may be an intermediate
   stage of the integrator. */
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
    double *potential;          /* NULL in a step; when tb_world_energy_with_callbacks
                                   asks, a sum to add this force's potential energy (J)
                                   at these positions to, so that it counts in the
                                   total (optional: a force with none adds nothing) */
} tb_force_args;
typedef tb_status tb_force_fn(const tb_force_args *args, void *user);

/* --------------------------------------------------------------- joints -- */

/* What a joint holds between its two bodies (docs/joints.md):
   - BALL: the anchor points of both bodies together (3 rows);
   - HINGE: a ball joint that also keeps the axis of each body together,
     so the bodies turn about it only (5 rows);
   - SLIDER: the bodies keep their relative orientation and the anchor of
     b stays on the axis through the anchor of a (5 rows);
   - FIXED: the bodies move as one (6 rows);
   - DISTANCE: a rod: the anchors of the two bodies stay `length` apart
     (1 row).
   A particle may take a body's place in a BALL or DISTANCE joint
   (particle_a for a, particle_b for b): the particle is its own anchor.
   A ball joint then holds it at `anchor` on the other side (a point of a
   body, or fixed in the world); a distance joint is a rod between two
   particles, or from a particle to `anchor_b`. */
typedef enum tb_joint_type {
    TB_JOINT_BALL,
    TB_JOINT_HINGE,
    TB_JOINT_SLIDER,
    TB_JOINT_FIXED,
    TB_JOINT_DISTANCE
} tb_joint_type;

typedef struct tb_joint_def {
    tb_joint_type type;
    tb_body_id a;            /* null when particle_a is given */
    tb_body_id b;            /* null (and particle_b null): the joint holds a to the world */
    tb_particle_id particle_a, particle_b; /* a particle in a's or b's place (BALL, DISTANCE) */
    double anchor[3];        /* m, a world point at creation, fixed in a and in b
                                (or the world); DISTANCE: the end on a */
    double anchor_b[3];      /* m, DISTANCE only: the end on b (or in the world),
                                a world point at creation */
    double axis[3];          /* HINGE, SLIDER: the axis in the world at creation,
                                any length but 0; default (0, 0, 1) */
    double length;           /* m, DISTANCE: the rod's length; negative (the
                                default): the distance at creation */
    int collide;             /* nonzero: the shapes of a and b collide with each
                                other; 0 (the default): they pass through */
    /* A limit (enable_limit) keeps the joint's free coordinate within
       [lower, upper] (tb_joint_position): HINGE, the angle (rad, within
       [-pi, pi]) a has turned about the axis relative to b since
       creation; SLIDER, how far a's anchor has moved along the axis from
       b's (m); DISTANCE, the distance (m; the rod's fixed length goes: a
       rope is lower 0, upper its length); BALL, a cone: the angle between
       a's and b's copies of `axis` at most upper (rad, within (0, pi);
       lower unused). */
    int enable_limit;
    double lower, upper;
    /* BALL: a twist limit (enable_twist) keeps the turn of a about the
       axis relative to b (rad, 0 at creation; its part about the axis
       once the swing between the axes is taken out) within [twist_lower,
       twist_upper], each within [-pi, pi]: a ragdoll's shoulder. */
    int enable_twist;
    double twist_lower, twist_upper;
    /* A motor (HINGE, SLIDER) drives the free coordinate's rate towards
       motor_speed (rad/s or m/s) with at most max_motor_force (N m or N,
       >= 0). */
    int enable_motor;
    double motor_speed, max_motor_force;
    /* A spring (HINGE, SLIDER, DISTANCE) pulls the free coordinate towards
       spring_target (rad or m; DISTANCE: towards `length`, and the rod's
       fixed length goes) at spring_hz (> 0) with spring_damping_ratio
       (>= 0): its stiffness and damping are those numbers times the
       effective mass along the coordinate at creation. */
    int enable_spring;
    double spring_hz, spring_damping_ratio, spring_target;
    /* The joint breaks (is removed after the step; its id turns stale)
       when its reaction force exceeds break_force (N) or its torque
       break_torque (N m); 0 (the default): never. */
    double break_force, break_torque;
} tb_joint_def;

/* ------------------------------------------------------ shapes, contacts -- */

typedef enum tb_shape_type { TB_SHAPE_SPHERE, TB_SHAPE_CAPSULE, TB_SHAPE_BOX, TB_SHAPE_PLANE } tb_shape_type;

/* A shape on a body has its pose in the body's principal frame (centre of
   mass at the origin; for a body made with tb_mass_sphere/box/cylinder/
   capsule, the solid's own centred frame); a static one in the world.
   Planes are static only. */
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
                                 rolling resistance length), and a spin about the
                                 normal by the same torque; default 0 (a
                                 ball rolls on for ever); >= 0; a pair uses the larger */
    uint32_t category;        /* bits this shape is; default 1 */
    uint32_t mask;            /* bits it collides with; default all. A pair collides
                                 when each one's category meets the other's mask */
} tb_shape_def;

/* How contacts are solved; the passes they tune are described in
   docs/contacts.md. */
typedef struct tb_contact_settings {
    double hertz;                 /* 1/s: stiffness of the push that resolves old overlaps; default 30 */
    double damping_ratio;         /* of that push; default 10 */
    double max_push;              /* m/s: the fastest it separates overlaps; default 3 */
    double restitution_threshold; /* m/s: slower impacts do not bounce; default 1 */
    double slop;                  /* m: overlap left alone, against jitter; default 0.005 */
    double particle_radius;       /* m: particles collide with shapes as spheres of this
                                     radius (0: points); < 0 (default -1): they do not */
    double particle_friction;     /* default 0.6 */
    double particle_restitution;  /* default 0 */
    double sleep_speed;           /* m/s: a body slower than this (|v| + |w| times its
                                     shapes' reach), and that moved less than this times
                                     the step in it (a push out of an overlap moves a
                                     body without giving it speed), is resting; default 0.05 */
    double sleep_time;            /* s: an island of touching bodies that all rest this
                                     long falls asleep; default 0.5, INFINITY: never */
    int substeps;                 /* the soft-step solver's substeps a step; an island
                                     too wide to solve together, with no particle and no
                                     overlap deeper than the slop, takes twice as many at
                                     twice the hertz (docs/contacts.md); default 4; >= 1 */
} tb_contact_settings;

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

/* --------------------------------------------------------------- advisor -- */

/* The advisor's estimate of the largest stable step. The method's limit is
   min(c_osc / stiffest, c_decay / decay), with c_osc = 2 for the split
   methods, 2 sqrt 2 for RK4 and 0 for explicit Euler (unstable on any
   oscillation), and c_decay = 2 (2.785 for RK4). */
typedef struct tb_advice {
    double stiffest;          /* rad/s, the fastest spring oscillation (0: none) */
    double damping_ratio;     /* its damping ratio z (springs' damping and drag) */
    double decay;             /* 1/s, the fastest decay: drag, body damping, and the
                                 most damped mode of the springs (0: none) */
    double fastest_spin;      /* rad/s, the fastest body spin (information) */
    double limit;             /* s, the largest stable step of the integrator with
                                 damping counted; INFINITY when nothing limits it
                                 (and for the adaptive methods), 0 when no step is
                                 stable */
    int exceeded;             /* the step asked about is above the limit */
    tb_spring_id spring;      /* the stiffest mode's stiffest spring (null: none) */
    char text[TB_MESSAGE_SIZE]; /* one line: the verdict, and a step or method to use */
} tb_advice;

/* The work a world's steps did (tb_world_work), counted since it was made
   over the steps it kept (a step undone by the guard or refused is not
   counted; a restore puts the counts back with the rest). */
typedef struct tb_work {
    uint64_t steps;           /* completed steps */
    uint64_t substeps;        /* the substeps they took: 1 a step for the fixed-step
                                 methods, the chosen method's under "auto", the
                                 accepted ones of "dopri5" */
    uint64_t rejected;        /* substeps "dopri5" rejected and took again smaller, and
                                 steps (or halves) whose joints the projection could
                                 not meet, taken again as two halves */
    uint64_t evaluations;     /* force evaluations made (each runs every force
                                 callback once; a rejected substep's count) */
    double contact_work;      /* J, the energy the contact solver changed (its impulses
                                 and position corrections; negative: removed) */
    double damping_work;      /* J, the work of drag, spring damping and body damping
                                 (negative), by the trapezoid rule on their power at
                                 each step's start and end: second order in h */
} tb_work;

/* ---------------------------------------------------------- diagnostics -- */

typedef struct tb_energy {
    double kinetic;          /* J, translational: sum of m v^2 / 2 */
    double rotational;       /* J, bodies: sum of L . w / 2 */
    double gravity;          /* J, sum of -m g . x (zero at the origin) */
    double spring;           /* J, sum of k (|d| - rest)^2 / 2 */
    double total;            /* J, all of the above and `potential` */
    double potential;        /* J, what force callbacks report as their potential
                                energy (tb_world_energy_with_callbacks; 0 otherwise) */
} tb_energy;

#ifdef __cplusplus
}
#endif
#endif
