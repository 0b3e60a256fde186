/* world.h: the inside of a world, shared by the core's files (not public).

   The mutable state of a world is one vector of doubles, y, cut into flat
   arrays per quantity:

       y = [ tracer positions | particle positions | particle velocities ]
             3 * tracer_cap      3 * particle_cap     3 * particle_cap

   Each array is sized by its tier's capacity, so adding an object moves
   nothing until a capacity doubles. Generic integrators (Euler, RK4) treat y
   as one vector and walk its used segments; split integrators (symplectic
   Euler, Verlet) kick and drift the velocity and position arrays in place.
   Constant parameters (masses, spring constants) live outside y, so a
   snapshot of the state is a copy of y. */
#ifndef TB_WORLD_H
#define TB_WORLD_H

#include "tumble.h"
#include <stdarg.h>

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
} tb__method;

const tb__method *tb__method_find(const char *name);

struct tb_world {
    tb_allocator allocator;
    char message[TB_MESSAGE_SIZE];
    const tb__method *method;
    int stepping;          /* nonzero inside tb_world_step: no structural changes */

    double time;           /* s */
    double time_carry;     /* s, the rounding lost from `time` (Kahan sum) */
    double gravity[3];     /* m/s^2 */
    double linear_drag;    /* N s/m */
    double quadratic_drag; /* N s^2/m^2 */

    /* state vector and the offsets of its arrays (in doubles) */
    double *y;
    size_t y_size;
    size_t off_tracer_pos, off_particle_pos, off_particle_vel;

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
    int force_ready;       /* w->force holds this evaluation's global forces */
    const double *kick_velocity; /* [3 * particle_count] the velocities that
                              velocity-dependent forces of the next kicks see;
                              NULL: the current ones */
    tb__ids particle_ids;

    /* springs: endpoints are particle slots, kept right on swap-remove */
    size_t spring_count, spring_cap;
    uint32_t *spring_a;    /* [spring_cap] slot */
    uint32_t *spring_b;    /* [spring_cap] slot, or TB__ANCHOR */
    double *spring_anchor; /* [3 * spring_cap] m */
    double *spring_k;      /* [spring_cap] N/m */
    double *spring_c;      /* [spring_cap] N s/m */
    double *spring_rest;   /* [spring_cap] m */
    tb__ids spring_ids;

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
tb_status tb__state_resize(tb_world *w, size_t tracer_cap, size_t particle_cap);
tb_status tb__state_scratch(tb_world *w, size_t count);
double *tb__scratch_vector(tb_world *w, size_t k);
/* out = base + a * dir over the used part of the state. out may be base. */
void tb__state_axpy(const tb_world *w, double *out, const double *base, double a, const double *dir);
void tb__state_copy(const tb_world *w, double *out, const double *in);

/* ---- stepping primitives (tracers.c, particles.c) ---------------------- */
/* dy = F(t, y), the whole state's derivative. */
tb_status tb__derive(tb_world *w, double t, const double *y, double *dy);
tb_status tb__tracer_derive(tb_world *w, double t, const double *y, double *dy);
tb_status tb__particle_derive(tb_world *w, double t, const double *y, double *dy);
/* The forces that are not local to one particle (springs, callbacks) at the
   state (pos, vel), into w->force. Sets *any to whether there were any. */
tb_status tb__particle_global_forces(tb_world *w, double t, const double *pos,
                                     const double *vel, int *any);

/* Split methods: a list of kicks and drifts swept over the particles in
   blocks that stay in cache. Kicks use w->force (see tb__particle_prepare)
   plus the local forces (gravity, drag) at the moment of the kick. */
typedef struct tb__split_op { int drift; double h; } tb__split_op;
/* velocity: what damping and drag see, in this evaluation and the kicks
   after it (3 * particle_count values); NULL: the current velocities. */
tb_status tb__particle_prepare(tb_world *w, double t, const double *velocity);
/* Whether any force depends on velocity (drag, spring damping, callbacks). */
int tb__particle_velocity_dependent(const tb_world *w);
/* saved = 2 v - saved on the particle velocities: with saved = v_n and the
   current v = v_n + h/2 a_n, this predicts v_{n+1} = v_n + h a_n. */
void tb__particle_extrapolate_velocity(const tb_world *w, double *saved);
void tb__particle_sweep(tb_world *w, const tb__split_op *ops, int n);

/* ---- springs.c, forces.c, fields.c ------------------------------------- */
void tb__spring_forces(const tb_world *w, const double *pos, const double *vel, double *force);
void tb__springs_detach(tb_world *w, uint32_t slot);
void tb__springs_move(tb_world *w, uint32_t from, uint32_t to);
double tb__spring_energy(const tb_world *w);
tb_status tb__user_forces(tb_world *w, double t, const double *pos, const double *vel, double *force);
tb_status tb__field_velocities(tb_world *w, double t, size_t n, const double *pos, double *vel);
void tb__springs_free(tb_world *w);

#endif
