/* world.h: the world struct, which every tier of the core reads and
   writes, and the interface every tier offers the step (not public).

   Names: what a header declares carries a prefix, tb_ (TB_ for macros)
   when public in include/, tb__ (TB__) when private to the library, so no
   name of the library can meet a user's. A function private to one .c
   file (static, static inline or TB__LANE, and the per-instruction-set
   variants a file generates with TB__FOR_EACH_ISA) carries none: without a
   prefix a name says that nothing outside its file calls it.

   The state vector y and its layout are in core/core.h; each tier's own
   functions are in its folder's header (particles/, bodies/, forces/,
   collision/, contacts/, stepping/). Tiers depend downwards only:
   core <- particles, bodies <- forces <- collision <- contacts <- stepping
   <- world.c, the front door. */
#ifndef TB_WORLD_H
#define TB_WORLD_H

#include "core/core.h"

/* The split methods' kicks and drifts, which each tier with velocities
   offers (tb__particle_sweep, tb__body_sweep): a list of operations run
   over one object at a time while its data is in cache. */
typedef enum tb__rotation_kind { TB__ROTATE_FROZEN, TB__ROTATE_SPLIT2, TB__ROTATE_ACCURATE } tb__rotation_kind;
typedef struct tb__split_op {
    int drift;             /* 0: kick, 1: drift */
    double h;              /* s */
    tb__rotation_kind rotation; /* how a drift turns anisotropic bodies */
    /* a kick whose velocity-dependent forces see the predicted velocity
       2 v - v_start, v_start the velocity before the list's first op
       (Verlet's closing kick, as tb__split_extrapolate would give it);
       only in lists for worlds where no global force acts and bodies
       are not velocity-dependent */
    int predicted;
} tb__split_op;

/* An integrator, as the world holds it (stepping/integrators.c defines
   them): what it needs of the world and how it steps. */
typedef struct tb__method {
    const char *name;
    int order;
    int split;             /* kicks and drifts: needs velocities, so no tracers */
    int updates_before_last_evaluation;  /* needs a snapshot to roll back */
    int scratch;           /* state-sized scratch vectors it uses */
    tb_status (*step)(tb_world *w, double h);
    /* Stability (integrators.c, docs/integrators.md): the largest h w it
       survives on the damped oscillator x'' = -w^2 x - 2 z w x' with
       damping ratio z >= 0 (0: no step; INFINITY: any step), and the
       largest h k on the decay v' = -k v. Used by the advisor (advisor.c)
       and the plan of "auto" (auto.c). */
    double (*damped_limit)(double zeta);
    double decay_limit;
    int adaptive;          /* chooses its own substeps: no limit on h */
    /* chooses another method and its substeps for a step h (auto.c), NULL
       for a method that steps by itself */
    tb_status (*plan)(tb_world *w, double h);
} tb__method;

typedef struct tb__contacts tb__contacts;
enum { TB__HEARS_SHAPES, TB__HEARS_JOINTS };
enum { TB__HEARS_SPRINGS, TB__HEARS_PARTICLE_JOINTS };
enum {
    TB__JOINT_COLLIDE = 1, TB__JOINT_PARTICLE_A = 2, TB__JOINT_PARTICLE_B = 4,
    TB__JOINT_LIMIT = 8, TB__JOINT_MOTOR = 16, TB__JOINT_SPRING = 32, TB__JOINT_TWIST = 64,
    TB__JOINT_SOFT = 128 /* this step: its bodies are in contact, it is met in the soft step's
                            substeps (contacts/soft_joints.c), not by SHAKE or the evaluations */
};
/* A joint's drive (world.h, joint_drive): its limits, motor, spring and
   breaking figures, TB__DRIVES of them */
enum {
    TB__DRIVE_LOWER, TB__DRIVE_UPPER, TB__DRIVE_SPEED, TB__DRIVE_MOST, TB__DRIVE_STIFFNESS, TB__DRIVE_DAMPING,
    TB__DRIVE_TARGET, TB__DRIVE_HZ, TB__DRIVE_RATIO, TB__DRIVE_BREAK_FORCE, TB__DRIVE_BREAK_TORQUE,
    TB__DRIVE_TWIST_LOWER, TB__DRIVE_TWIST_UPPER, TB__DRIVES
};
struct tb__split_frame;    /* bodies/bodies.h */

struct tb_world {
    tb_allocator allocator;
    char message[TB_MESSAGE_SIZE];
    const tb__method *method;
    int stepping;          /* nonzero inside tb_world_step: no structural changes */
    uint32_t id_tag;       /* this world's tag in the top bits of every id's
                              generation (core/ids.c) */

    double time;           /* s */
    double time_carry;     /* s, the rounding lost from `time` (Kahan sum) */
    double gravity[3];     /* m/s^2 */
    double linear_drag;    /* N s/m */
    double tolerance;      /* local error per step asked of adaptive methods */
    double adaptive_h;     /* s, the last step size an adaptive method chose */
    double quadratic_drag; /* N s^2/m^2 */

    /* integrator "auto" (auto.c): the method and substeps it chose, and
       what it chose them for (step, tolerance, object counts) */
    const tb__method *auto_method;
    long auto_substeps;
    double auto_key[8];

    /* the blow-up guard (guard.c): 0 off; INFINITY: finiteness only; > 1:
       also the largest energy growth per step */
    double guard;
    unsigned long steps;   /* completed steps, for messages */
    tb_work work;          /* what the kept steps did (tb_world_work) */

    /* state vector and the offsets of its arrays (in doubles) */
    double *y;
    size_t y_size;
    size_t off[TB__QUANTITY_COUNT]; /* where each array starts in y */

    /* scratch for integrators: scratch_count vectors of y_size doubles */
    double *scratch;
    size_t scratch_count;

    /* tracers */
    size_t tracer_count, tracer_cap;
    tb__ids tracer_ids;

    /* particles: constants and the force accumulator */
    size_t particle_count, particle_cap;
    double *particle_mass;     /* [particle_cap] kg, 0 when pinned */
    double *particle_inv_mass; /* [particle_cap] 1/kg, 0 when pinned */
    double *particle_force;    /* [3 * particle_cap] N, forces that are not local */
    int force_ready;       /* w->particle_force and w->body_force hold this
                              evaluation's global forces */
    const double *kick_seen; /* a state vector whose velocities and momenta
                              the velocity-dependent forces of the next kicks
                              see; NULL: the current ones */
    double *damping_sums;  /* [2] W: while a step asks it (step.c), where the
                              particles' one-pass kernel puts the drag's power
                              at the step's start and end; NULL otherwise */
    tb__ids particle_ids;

    /* springs: endpoints are particle slots, kept right on swap-remove */
    size_t spring_count, spring_cap;
    uint32_t *spring_a;    /* [spring_cap] slot */
    uint32_t *spring_b;    /* [spring_cap] slot, or TB__ANCHOR */
    double *spring_anchor; /* [3 * spring_cap] m */
    double *spring_k;      /* [spring_cap] N/m */
    double *spring_c;      /* [spring_cap] N s/m */
    double *spring_rest;   /* [spring_cap] m */
    size_t spring_damped;  /* springs with damping != 0 (so no step scans them) */
    tb__ids spring_ids;

    /* rigid bodies: constants, held user forces, callback forces */
    size_t body_count, body_cap;
    double *body_mass;        /* [body_cap] kg */
    double *body_inv_mass;    /* [body_cap] 1/kg */
    double *body_inertia;     /* [3 * body_cap] kg m^2, principal moments */
    double *body_inv_inertia; /* [3 * body_cap] 1/(kg m^2) */
    double *body_damping;     /* [2 * body_cap] 1/s: linear, angular */
    double *body_applied;     /* [6 * body_cap] N, N m: force and torque held
                                 for the next step (tb_body_apply_*) */
    double *body_force;       /* [6 * body_cap] N, N m: callback force and
                                 torque of this evaluation */
    double *body_motion;      /* [6 * body_cap] m/s, rad/s: v and w shown to
                                 callbacks */
    struct tb__split_frame *body_frame; /* [body_cap] the axes and rates the rotation
                                 kernels need, fixed by the moments */
    double *body_lane_frame[4]; /* [body_cap] each: the same as the splitting
                                 lanes read it, one array per number
                                 (tb__lane_frame_of) */
    double *body_rest;        /* [body_cap] s: how long the body has been slow
                                 (sleep.c) */
    uint32_t *body_island;    /* [body_cap] the sleeping island it is in; 0: awake */
    size_t body_sleeping;     /* bodies asleep (sleep.c puts them to sleep,
                                 bodies.c wakes them) */
    size_t body_damped;       /* bodies with linear or angular damping */
    size_t body_isotropic;    /* bodies with I1 = I2 = I3 */
    int body_held;            /* some body_applied may be nonzero (cleared
                                 once a sweep finds them all zero) */
    tb__ids body_ids;

    /* joints (joints/joints.h): their ends are body id indices (0: the
       world), found again each evaluation, so a body's swap-remove moves
       nothing here */
    size_t joint_count, joint_cap;
    uint32_t *joint_type;     /* [joint_cap] tb_joint_type */
    uint32_t *joint_body;     /* [2 * joint_cap] index1 of a, of b (0: the world): a body's, or a
                                 particle's where joint_flags says so */
    double *joint_anchor;     /* [6 * joint_cap] m: the anchor in a's principal frame, in b's
                                 (or the world) */
    double *joint_frame;      /* [18 * joint_cap] the joint's axes (axis, then two across it,
                                 by rows) in a's principal frame, in b's (or the world) */
    double *joint_length;     /* [joint_cap] m, DISTANCE */
    double *joint_reaction;   /* [6 * joint_cap] N, N m: on a, at the last evaluation */
    uint32_t *joint_flags;    /* [joint_cap] TB__JOINT_COLLIDE (a's and b's shapes collide),
                                 TB__JOINT_PARTICLE_A, _B (that side is a particle),
                                 TB__JOINT_LIMIT, _MOTOR, _SPRING, _TWIST (enabled),
                                 TB__JOINT_SOFT (met in the soft step this step) */
    double *joint_drive;      /* [TB__DRIVES * joint_cap] limits (rad or m), motor (rad/s or m/s;
                                 N m or N), spring (N m/rad or N/m, N m s/rad or N s/m, the
                                 target; Hz and ratio as given), breaking (N, N m) */
    double *joint_warm;       /* [TB__JOINT_ROWS * joint_cap] N or N m: each row's force in the
                                 soft step's last substep, its next step's warm start */
    tb__ids joint_ids;
    int joints_unmet;         /* the last projection left some end off its joints (beyond
                                 rounding): a step from here is not taken again in halves
                                 (step.c) */
    struct tb__joint_work *joint_work; /* the solve's rows and factor (joint_work.h): scratch
                                 that every evaluation writes before it reads */

    /* shapes and contacts (contacts/contacts.h); NULL until the first shape */
    struct tb__contacts *contacts;

    /* Tiers above particles and bodies that refer to them hear of their
       removal here (set when they first hold such a reference), so the
       lower tier calls no upper one: springs keep particle slots, shapes
       keep body ids, and so do joints (one listener each: TB__HEARS_SHAPES,
       TB__HEARS_JOINTS; for particles TB__HEARS_SPRINGS,
       TB__HEARS_PARTICLE_JOINTS). NULL: nobody listens. */
    void (*particle_removed[2])(tb_world *w, uint32_t slot, uint32_t last);
    void (*body_removed[2])(tb_world *w, uint32_t body_index1);

    /* velocity fields for tracers (tb__field), user forces (tb__force) */
    tb__list fields;
    tb__list forces;

    /* the guard's snapshot of the world before the step (snapshot.c),
       taken again into the same memory every step; NULL until the guard
       first runs */
    struct tb_snapshot *rollback;
    /* the world before an attempt at a step that may be taken again in
       halves (step.c); NULL until first needed */
    struct tb_snapshot *retake;
};

#endif
