/* core.h: what every tier of the core stands on (not public): memory and
   messages through the world, generation-checked ids, ordered lists, the
   state vector's layout, and the choice of instruction set for the loops
   over lanes. Nothing here knows of particles, bodies or contacts beyond
   the list of state arrays. */
#ifndef TB_CORE_H
#define TB_CORE_H

#include "tumble.h"

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

/* ---- the state vector (state.c) -------------------------------------------

   The mutable state of a world is one vector of doubles, y, cut into flat
   arrays per quantity, in the order of TB__QUANTITIES below:

       y = [ tracer pos | particle pos | particle vel | body pos | body q | body P | body L ]

   Each array is sized by its tier's capacity, so adding an object moves
   nothing until a capacity doubles. Generic integrators (Euler, RK4) treat y
   as one vector and walk its used segments; split integrators (symplectic
   Euler, Verlet) kick and drift the velocity and position arrays in place.
   Constant parameters (masses, spring constants) live outside y, so a
   snapshot of the state is a copy of y. */

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

/* Lay y out for `cap` objects of `tier`, the other tiers keeping theirs. */
/* An empty state vector (and its scratch) points at tb__empty_state, never
   at NULL, so that y + offset is defined before the first object; it is
   never written and never freed (state.c, snapshot.c). */
extern double tb__empty_state[1];
/* A new world's empty state; and freeing the state and scratch for good */
void tb__state_init(tb_world *w);
void tb__state_free(tb_world *w);
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

/* ---- ids (ids.c): generation-checked id tables, one per kind of object ----
   A generation holds the world's tag in its top TB__ID_TAG_BITS bits and a
   counter of the entry's lives below: 2^12 worlds created one after another
   have distinct tags, and an entry's live generation comes back after 2^19
   reuses (live counters are odd). */
#define TB__ID_TAG_BITS 12
#define TB__ID_COUNTER_BITS (32 - TB__ID_TAG_BITS)
#define TB__ID_COUNTER_MASK ((1u << TB__ID_COUNTER_BITS) - 1u)

typedef struct tb__ids {
    uint32_t *slot;        /* [capacity] per id: its slot, or the next free id */
    uint32_t *generation;  /* [capacity] per id: the world's tag | a counter bumped
                              on acquire and release (odd: live, never 0) */
    uint32_t *owner;       /* [capacity] per slot: the id index living there */
    uint32_t capacity;     /* ids and slots allocated */
    uint32_t used;         /* ids ever handed out (high-water mark) */
    uint32_t free_head;    /* first free id index + 1, 0 when none */
} tb__ids;

tb_status tb__ids_reserve(tb_world *w, tb__ids *ids, size_t capacity);
void tb__ids_free(tb_world *w, tb__ids *ids);
/* A new world's tag (already shifted into the generation's top bits);
   safe to call from several threads at once. */
uint32_t tb__ids_new_tag(void);
/* Hand out an id for `slot` in the world with tag `tag` (w->id_tag);
   capacity must have been reserved. */
void tb__ids_acquire(tb__ids *ids, uint32_t tag, uint32_t slot, uint32_t *index1, uint32_t *generation);
/* 1 and the slot when the id is live (and of this table's world). */
int tb__ids_lookup(const tb__ids *ids, uint32_t index1, uint32_t generation, uint32_t *slot);
void tb__ids_release(tb__ids *ids, uint32_t index1);
/* The object in slot `from` moved to slot `to` (swap-remove). */
void tb__ids_move(tb__ids *ids, uint32_t from, uint32_t to);
void tb__ids_at(const tb__ids *ids, uint32_t slot, uint32_t *index1, uint32_t *generation);

/* ---- lists (list.c) ----------------------------------------------------------
   An ordered list of small items with ids (fields, user forces). Removal
   keeps the order, so sums over the list keep their rounding. */
typedef struct tb__list {
    unsigned char *items;  /* [cap * item_size] */
    size_t count, cap, item_size;
    tb__ids ids;
} tb__list;

tb_status tb__list_add(tb_world *w, tb__list *list, const void *item, uint32_t *index1, uint32_t *generation);
tb_status tb__list_remove(tb_world *w, tb__list *list, uint32_t index1, uint32_t generation, const char *what);
void tb__list_free(tb_world *w, tb__list *list);
#define TB__LIST_AT(list, type, i) ((type *)(void *)((list)->items + (i) * (list)->item_size))

/* ---- memory and messages (memory.c) --------------------------------------- */
void *tb__alloc(tb_world *w, void *ptr, size_t old_size, size_t new_size);
/* Grow a group of parallel arrays from old_cap to new_cap elements, all or
   nothing: on failure every array is as it was. */
tb_status tb__grow(tb_world *w, void **arrays[], const size_t elem_size[], int n,
                   size_t count, size_t old_cap, size_t new_cap);
/* Grow one array to hold at least `need` items of `size` bytes (doubling,
   from 16), its first *cap items kept; on failure it is as it was. */
tb_status tb__reserve(tb_world *w, void **array, size_t *cap, size_t need, size_t size);
void tb__free_arrays(tb_world *w, void **arrays[], const size_t elem_size[], int n, size_t cap);
/* Record a message and return status (for `return tb__fail(...)`). */
tb_status tb__fail(tb_world *w, tb_status status, const char *fmt, ...);
int tb__finite3(const double v[3]);

/* ---- the input rule (memory.c; TB_LIMIT in tumble/base.h) -------------------
   Each check returns TB_OK, or TB_ERR_ARGUMENT with a message naming `what`
   and the value. */
/* finite and |x| <= TB_LIMIT */
int tb__bounded(double x);
/* n values (NULL refused), each finite and within TB_LIMIT */
tb_status tb__check_values(tb_world *w, const double *v, size_t n, const char *what);
/* a value tumble divides by: finite and in [1 / TB_LIMIT, TB_LIMIT] */
int tb__in_scale(double x);
tb_status tb__check_scale(tb_world *w, double x, const char *what);
/* a coefficient: finite and in [0, TB_LIMIT] */
tb_status tb__check_coefficient(tb_world *w, double x, const char *what);
/* a derived quantity (momentum, energy, ...) of magnitude x, with its unit */
tb_status tb__check_derived(tb_world *w, double x, const char *what, const char *unit);
/* TB_ERR_ARGUMENT naming the function when a pointer it needs is NULL. */
tb_status tb__null(tb_world *w, const char *function, const char *what);
/* A NULL world has no message to write: the call returns `value` at once
   (TB_ERR_ARGUMENT for a call that returns a status, the documented
   neutral value otherwise), and tb_world_message(NULL) says why. */
#define TB__NEED_WORLD(w, value) \
    do {                         \
        if (!(w))                \
            return (value);      \
    } while (0)
/* sum a_i b_i over n, in order */
double tb__dot(const double *a, const double *b, size_t n);
/* TB_ERR_BUSY with a message while the world is stepping (inside a callback). */
tb_status tb__check_busy(tb_world *w, const char *what);

/* ---- envelope factors (envelope.c) ------------------------------------------
   A symmetric positive definite matrix stored by rows, each from its
   first column to the diagonal: A_ij = a[offset[i] + j - first[i]] for
   first[i] <= j <= i; its factor L (L L^T = A) goes in l with the same
   layout. The rows of a factor or solve are from .. to - 1 of the
   arrays, with first[i] >= from. */
typedef struct tb__envelope {
    const size_t *first, *offset;
    const double *a;
    double *l;
    unsigned char *use;    /* NULL: every row; else a row with use[i] 0 is left
                              out, factored as the identity (its x must be 0) */
    double drop;           /* > 0: a row whose pivot falls to drop times its
                              diagonal depends on the rows before it and is left
                              out (use[i] set to 0); 0: no row is dropped */
} tb__envelope;
/* 0 when a pivot is not positive (then l holds part of a factor). */
int tb__envelope_factor(const tb__envelope *e, size_t from, size_t to);
/* x = (L L^T)^-1 x */
void tb__envelope_solve(const tb__envelope *e, size_t from, size_t to, double *x);
/* A matrix that is not symmetric: its lower triangle (with the diagonal)
   in e->a, its upper one by columns in `upper` (A_ji = upper[offset[i] +
   j - first[i]] for first[i] <= j < i), both overwritten by L U (L unit
   lower, in e->a below the diagonal; U by columns in upper, its diagonal
   in e->a's). No pivoting: for matrices near a positive definite one. 0
   when a pivot is 0 or not finite (with drop, a row whose pivot falls to
   drop times its diagonal is left out instead). */
int tb__envelope_lu(const tb__envelope *e, double *upper, size_t from, size_t to);
void tb__envelope_lu_solve(const tb__envelope *e, const double *upper, size_t from, size_t to, double *x);

/* ---- instruction sets (isa.c) ---------------------------------------------

   The loops over lanes (rotation kernels, body sweeps, the particles'
   one-pass kernel) are compiled once per instruction set and chosen at
   run time: portable C (SSE2 on x86-64, two lanes an instruction), AVX2
   (four) and AVX-512 (eight), on x86-64 with GCC or Clang. Every variant
   does the same operations in the same order, so all give the same bits
   (test_rotation.lanes_give_the_one_body_bits,
   test_particle_step's comparisons on every instruction set).

   TB__FOR_EACH_ISA(GEN) expands GEN(suffix, attribute, isa) once per
   instruction set this build can dispatch to; a file defines its variants
   with it and calls one with TB__DISPATCH(isa, name, (args)), which calls
   name_<suffix> args for isa. */
enum { TB__ISA_PORTABLE = 0, TB__ISA_AVX2 = 1, TB__ISA_AVX512 = 2 };

/* The widest instruction set this processor runs (any value up to it may
   be passed where an isa is taken). */
int tb__isa(void);

/* For the definition of a piece of the work of one lane: it must be
   inlined into the loops over lanes for GCC to vectorise those, whatever
   its size. */
#if defined(__GNUC__)
#define TB__LANE static inline __attribute__((always_inline))
#else
#define TB__LANE static inline
#endif

#if defined(__GNUC__) && defined(__x86_64__)
#define TB__X86_DISPATCH 1
#define TB__TARGET_AVX2 __attribute__((target("avx2,fma")))
#if defined(__clang__)
#define TB__TARGET_AVX512 __attribute__((target("avx512f")))
#else
/* GCC's generic tuning would split AVX-512 loops into 256-bit halves */
#define TB__TARGET_AVX512 __attribute__((target("avx512f,prefer-vector-width=512")))
#endif
#define TB__FOR_EACH_ISA(GEN)                   \
    GEN(portable, , TB__ISA_PORTABLE)           \
    GEN(avx2, TB__TARGET_AVX2, TB__ISA_AVX2)    \
    GEN(avx512, TB__TARGET_AVX512, TB__ISA_AVX512)
#define TB__DISPATCH(isa, name, args)    \
    do {                                 \
        if ((isa) == TB__ISA_AVX512)     \
            name##_avx512 args;          \
        else if ((isa) == TB__ISA_AVX2)  \
            name##_avx2 args;            \
        else                             \
            name##_portable args;        \
    } while (0)
#else
#define TB__X86_DISPATCH 0
#define TB__FOR_EACH_ISA(GEN) GEN(portable, , TB__ISA_PORTABLE)
#define TB__DISPATCH(isa, name, args) ((void)(isa), name##_portable args)
#endif

#endif
