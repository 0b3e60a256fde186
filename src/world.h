/* world.h: the inside of a world, shared by the core's files (not public).

   The mutable state of a world is one vector of doubles, y, cut into flat
   arrays per quantity, in the order of TB__QUANTITIES below:

       y = [ tracer pos | particle pos | particle vel | body pos | body q | body P | body L ]

   Each array is sized by its tier's capacity, so adding an object moves
   nothing until a capacity doubles. Generic integrators (Euler, RK4) treat y
   as one vector and walk its used segments; split integrators (symplectic
   Euler, Verlet) kick and drift the velocity and position arrays in place.
   Constant parameters (masses, spring constants) live outside y, so a
   snapshot of the state is a copy of y. */
#ifndef TB_WORLD_H
#define TB_WORLD_H

#include "tumble.h"
#include "rotation.h"
#include <stdarg.h>

/* The tiers of objects, and the arrays of the state vector y: name, tier,
   doubles per object. This one list drives the layout, resizing and copying
   of y (state.c). */
enum tb__tier { TB__TRACERS, TB__PARTICLES, TB__BODIES, TB__TIERS };

#define TB__QUANTITIES(X)                                                                  \
    X(TRACER_POS, TB__TRACERS, 3)   /* m */                                              \
    X(PARTICLE_POS, TB__PARTICLES, 3) /* m */                                            \
    X(PARTICLE_VEL, TB__PARTICLES, 3) /* m/s */                                          \
    X(BODY_POS, TB__BODIES, 3)      /* m, centre of mass */                              \
    X(BODY_ROT, TB__BODIES, 4)      /* unit quaternion (w, x, y, z), world from principal axes */ \
    X(BODY_MOM, TB__BODIES, 3)      /* kg m/s, linear momentum P */                      \
    X(BODY_ANG, TB__BODIES, 3)      /* kg m^2/s, angular momentum L about the centre, world frame */

enum tb__quantity {
#define TB__ENUM(name, tier, width) TB__##name,
    TB__QUANTITIES(TB__ENUM)
#undef TB__ENUM
    TB__QUANTITY_COUNT
};

typedef struct tb__contacts tb__contacts;

/* ---- ids.c: generation-checked id tables, one per kind of object ------- */
typedef struct tb__ids {
    uint32_t *slot;        /* [capacity] per id: its slot, or the next free id */
    uint32_t *generation;  /* [capacity] per id: bumped on release, never 0 */
    uint32_t *owner;       /* [capacity] per slot: the id index living there */
    uint32_t capacity;     /* ids and slots allocated */
    uint32_t used;         /* ids ever handed out (high-water mark) */
    uint32_t free_head;    /* first free id index + 1, 0 when none */
} tb__ids;

/* ---- the world's small lists: velocity fields and user forces ---------- */
typedef enum tb__field_kind { TB__FIELD_UNIFORM, TB__FIELD_VORTEX, TB__FIELD_CALLBACK } tb__field_kind;

typedef struct tb__field {
    tb__field_kind kind;
    double a[3];           /* uniform: velocity; vortex: omega */
    double b[3];           /* vortex: centre */
    tb_field_fn *fn;
    void *user;
} tb__field;

typedef struct tb__force {
    tb_force_fn *fn;
    void *user;
} tb__force;

/* An ordered list of small items with ids (fields, user forces). Removal
   keeps the order, so sums over the list keep their rounding. */
typedef struct tb__list {
    unsigned char *items;  /* [cap * item_size] */
    size_t count, cap, item_size;
    tb__ids ids;
} tb__list;

/* ---- integrators.c ---------------------------------------------------- */
typedef struct tb__method {
    const char *name;
    int order;
    int split;             /* kicks and drifts: needs velocities, so no tracers */
    int updates_before_last_evaluation;  /* needs a snapshot to roll back */
    int scratch;           /* state-sized scratch vectors it uses */
    tb_status (*step)(tb_world *w, double h);
    /* Stability on x' = z x: the largest |h lambda| it survives along the
       imaginary axis (oscillation, 0: none) and along the negative real
       axis (decay). Used by the advisor (advisor.c). */
    double oscillation_limit;
    double decay_limit;
    int adaptive;          /* chooses its own substeps: no limit on h */
    /* chooses another method and its substeps for a step h (auto.c), NULL
       for a method that steps by itself */
    tb_status (*plan)(tb_world *w, double h);
    /* how far a constant force moves positions in one step, as a share s
       of h: x gains s h (F h / m) beside the velocity's h v. 1/2 for the
       methods exact on a constant force, 1 for symplectic (and implicit)
       Euler, which drift with the kicked velocity, 0 for explicit Euler,
       which drifts with the old one. The contact pass moves positions by
       a resting contact's impulse this way, so a body at rest stays put
       (contact.c) */
    double force_lever;
} tb__method;

const tb__method *tb__method_find(const char *name);
const tb__method *tb__method_at(int index); /* NULL past the end */

struct tb_world {
    tb_allocator allocator;
    char message[TB_MESSAGE_SIZE];
    const tb__method *method;
    int stepping;          /* nonzero inside tb_world_step: no structural changes */

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
    double *mass;          /* [particle_cap] kg, 0 when pinned */
    double *inv_mass;      /* [particle_cap] 1/kg, 0 when pinned */
    double *force;         /* [3 * particle_cap] N, forces that are not local */
    int force_ready;       /* w->force and w->body_force hold this evaluation's
                              global forces */
    const double *kick_seen; /* a state vector whose velocities and momenta
                              the velocity-dependent forces of the next kicks
                              see; NULL: the current ones */
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
    tb__split_frame *body_frame; /* [body_cap] the axes and rates the rotation
                                 kernels need, fixed by the moments */
    double *body_lane_frame[4]; /* [body_cap] each: the same as the splitting
                                 lanes read it, one array per number
                                 (tb__lane_frame_of) */
    double *body_rest;        /* [body_cap] s: how long the body has been slow
                                 (sleep.c) */
    uint32_t *body_island;    /* [body_cap] the sleeping island it is in; 0: awake */
    size_t body_damped;       /* bodies with linear or angular damping */
    size_t body_isotropic;    /* bodies with I1 = I2 = I3 */
    int body_held;            /* some body_applied may be nonzero (cleared
                                 once a sweep finds them all zero) */
    tb__ids body_ids;

    /* shapes and contacts (contact.h); NULL until the first shape */
    struct tb__contacts *contacts;

    /* velocity fields for tracers (tb__field), user forces (tb__force) */
    tb__list fields;
    tb__list forces;
};

#define TB__ANCHOR UINT32_MAX

/* ---- base.c: memory and messages ------------------------------------- */
void *tb__alloc(tb_world *w, void *ptr, size_t old_size, size_t new_size);
/* Grow a group of parallel arrays from old_cap to new_cap elements, all or
   nothing: on failure every array is as it was. */
tb_status tb__grow(tb_world *w, void **arrays[], const size_t elem_size[], int n,
                   size_t count, size_t old_cap, size_t new_cap);
void tb__free_arrays(tb_world *w, void **arrays[], const size_t elem_size[], int n, size_t cap);
/* Record a message and return status (for `return tb__fail(...)`). */
tb_status tb__fail(tb_world *w, tb_status status, const char *fmt, ...);
int tb__finite3(const double v[3]);
/* sum a_i b_i over n, in order */
double tb__dot(const double *a, const double *b, size_t n);
tb_status tb__check_busy(tb_world *w, const char *what);

/* ---- ids.c ------------------------------------------------------------ */
tb_status tb__ids_reserve(tb_world *w, tb__ids *ids, size_t capacity);
void tb__ids_free(tb_world *w, tb__ids *ids);
/* Hand out an id for `slot`; capacity must have been reserved. */
void tb__ids_acquire(tb__ids *ids, uint32_t slot, uint32_t *index1, uint32_t *generation);
/* 1 and the slot when the id is live. */
int tb__ids_lookup(const tb__ids *ids, uint32_t index1, uint32_t generation, uint32_t *slot);
void tb__ids_release(tb__ids *ids, uint32_t index1);
/* The object in slot `from` moved to slot `to` (swap-remove). */
void tb__ids_move(tb__ids *ids, uint32_t from, uint32_t to);
void tb__ids_at(const tb__ids *ids, uint32_t slot, uint32_t *index1, uint32_t *generation);

/* ---- list.c ------------------------------------------------------------ */
tb_status tb__list_add(tb_world *w, tb__list *list, const void *item, uint32_t *index1, uint32_t *generation);
tb_status tb__list_remove(tb_world *w, tb__list *list, uint32_t index1, uint32_t generation, const char *what);
void tb__list_free(tb_world *w, tb__list *list);
#define TB__LIST_AT(list, type, i) ((type *)(void *)((list)->items + (i) * (list)->item_size))

/* ---- state.c: the state vector ----------------------------------------- */
/* Lay y out for `cap` objects of `tier`, the other tiers keeping theirs. */
tb_status tb__state_resize(tb_world *w, enum tb__tier tier, size_t cap);
tb_status tb__state_scratch(tb_world *w, size_t count);
double *tb__scratch_vector(tb_world *w, size_t k);
/* out = base + a * dir over the used part of the state. out may be base. */
void tb__state_axpy(const tb_world *w, double *out, const double *base, double a, const double *dir);
void tb__state_copy(const tb_world *w, double *out, const double *in);
/* Copy every state array's entry of object `from` of `tier` over `to`
   (swap-remove), as the field list TB__QUANTITIES says. */
void tb__state_move(tb_world *w, enum tb__tier tier, size_t from, size_t to);
/* out = a in over the used part of the state. */
void tb__state_scale(const tb_world *w, double *out, double a, const double *in);
/* RMS over the used state of err_i / (tol (1 + max(|y0_i|, |y1_i|))): an
   embedded pair's error estimate measured against a tolerance that is
   absolute near zero and relative for large values. <= 1 means accept. */
double tb__state_error_norm(const tb_world *w, const double *err, const double *y0, const double *y1, double tol);

/* ---- stepping primitives (world.c over tracers.c, particles.c, bodies.c) -- */
/* The methods use only these; each tier supplies its part. */

/* dy = F(t, y), the whole state's derivative. */
tb_status tb__derive(tb_world *w, double t, const double *y, double *dy);
/* Put y back on its constraints after a generic stage (unit quaternions). */
void tb__project(tb_world *w, double *y);
/* RK4 fused: when nothing couples objects (no springs, no callbacks), each
   object's derivative depends on the object alone, so the step can go
   object by object through all four stages, with the generic method's
   arithmetic (the same bits) but none of its passes over the whole state.
   1 when it stepped the world, 0 when the world needs the generic method
   (coupling forces, or objects of a tier that offers no fused step: today
   only bodies do, in body_step.c). */
/* RK4 through all stages one block at a time, when the world allows it
   (world.c decides; the body tier does the work). */
int tb__fused_rk4(tb_world *w, double h);
void tb__body_rk4(tb_world *w, double h);

/* Split methods: kicks and drifts. tb__split_prepare evaluates the forces
   that are not local to one object (springs, callbacks) at the current
   positions, with velocities and momenta taken from `seen` (a state vector,
   or NULL for the current state); the kicks of tb__split_sweep add the local
   forces (gravity, drag, damping, held forces), also seeing `seen`. */
typedef enum tb__rotation_kind { TB__ROTATE_FROZEN, TB__ROTATE_SPLIT2, TB__ROTATE_ACCURATE } tb__rotation_kind;
typedef struct tb__split_op {
    int drift;             /* 0: kick, 1: drift */
    double h;              /* s */
    tb__rotation_kind rotation; /* how a drift turns anisotropic bodies */
} tb__split_op;
tb_status tb__split_prepare(tb_world *w, double t, const double *seen);
void tb__split_sweep(tb_world *w, const tb__split_op *ops, int n);
/* Whether any force depends on velocity (drag, damping, callbacks). */
int tb__split_velocity_dependent(const tb_world *w);
/* saved = 2 y - saved on the velocities and momenta: with saved = y_n and
   the current state after a half kick, this predicts the end-of-step ones. */
void tb__split_extrapolate(const tb_world *w, double *saved);

/* ---- advisor.c, auto.c, guard.c ---------------------------------------- */
/* The stiffest spring mode w (rad/s) by power iteration, and the stiffest
   spring where that mode is largest. Uses two scratch state vectors. */
tb_status tb__stiffest_mode(tb_world *w, double *omega, tb_spring_id *culprit);
/* The fastest drag or damping decay rate (1/s) of particles and bodies. */
double tb__fastest_decay(const tb_world *w);
/* The force_lever of the step just taken (auto: of the method it chose,
   over its substeps). */
double tb__force_lever(const tb_world *w);

/* Choose w->auto_method and w->auto_substeps for steps of h. */
tb_status tb__auto_plan(tb_world *w, double h);
/* After a step from the state `before`: TB_OK, or TB_ERR_UNSTABLE with a
   message naming the step, the object and the likely cause (the caller
   rolls back). */
tb_status tb__guard_check(tb_world *w, const double *before, double h);
/* contact.c, shapes.c: collision around the integrator's step */
int tb__contacts_active(const tb_world *w);
tb_status tb__contacts_prepare(tb_world *w, double h);
void tb__contacts_solve(tb_world *w, double h);
void tb__contacts_free(tb_world *w);
void tb__shapes_of_body_removed(tb_world *w, uint32_t body_index1);
/* bodies.c: the slot of a live body id, or TB_ERR_STALE_ID with a message */
tb_status tb__body_find(const tb_world *w, tb_body_id id, uint32_t *slot);
/* sleep.c: wake body slot s and the island it sleeps in (if it sleeps). */
void tb__wake_body(tb_world *w, uint32_t s);
void tb__wake_all(tb_world *w);

/* ---- the tiers' parts ----------------------------------------------------- */
tb_status tb__tracer_derive(tb_world *w, double t, const double *y, double *dy);
void tb__particle_derive(tb_world *w, const double *y, double *dy);
void tb__particle_sweep(tb_world *w, const tb__split_op *ops, int n);
int tb__particle_velocity_dependent(const tb_world *w);
void tb__body_derive(tb_world *w, const double *y, double *dy);
void tb__body_sweep(tb_world *w, const tb__split_op *ops, int n);
int tb__body_velocity_dependent(const tb_world *w);
void tb__body_project(tb_world *w, double *y);
/* v and w of every body of state y into w->body_motion, for callbacks. */
void tb__body_motion(tb_world *w, const double *y, const double *seen);
void tb__bodies_free(tb_world *w);
/* Add the bodies' energies and momenta (about the origin) to the totals. */
void tb__body_energy(const tb_world *w, const double *y, tb_energy *e);
void tb__body_momenta(const tb_world *w, double linear[3], double angular[3]);
/* Forces not local to one object at positions from y, velocities from seen,
   into w->force (particles) and w->body_force (bodies). */
tb_status tb__global_forces(tb_world *w, double t, const double *y, const double *seen);
/* ---- springs.c, forces.c, fields.c ------------------------------------- */
void tb__spring_forces(const tb_world *w, const double *pos, const double *vel, double *force);
void tb__spring_stiffness_product(const tb_world *w, const double *pos, const double *u, double *out, int definite);
void tb__spring_damping_product(const tb_world *w, const double *pos, const double *u, double *out);
/* implicit.c: linearised backward Euler for particles; the whole step
   (bodies kicked and drifted) in tb__implicit_step */
tb_status tb__implicit_particles(tb_world *w, double h);
tb_status tb__implicit_step(tb_world *w, double h);
void tb__springs_detach(tb_world *w, uint32_t slot);
void tb__springs_move(tb_world *w, uint32_t from, uint32_t to);
double tb__spring_energy(const tb_world *w, const double *pos);
/* diagnostics.c: the energies of state y (any state vector of the world) */
tb_energy tb__energy_of(const tb_world *w, const double *y);
tb_status tb__user_forces(tb_world *w, double t, const double *y, const double *seen);
tb_status tb__field_velocities(tb_world *w, double t, size_t n, const double *pos, double *vel);
void tb__springs_free(tb_world *w);

#endif
