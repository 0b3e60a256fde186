/* tumble/base.h: what every other part of the API rests on: the export
   macro, the version, status codes, the allocator hook and the size of a
   message buffer. */
#ifndef TUMBLE_BASE_H
#define TUMBLE_BASE_H

#include <stddef.h>
#include <stdint.h>

#if defined(TUMBLE_SHARED)
#  if defined(_WIN32)
#    if defined(TUMBLE_BUILDING)
#      define TB_API __declspec(dllexport)
#    else
#      define TB_API __declspec(dllimport)
#    endif
#  else
#    define TB_API __attribute__((visibility("default")))
#  endif
#else
#  define TB_API
#endif

#define TB_VERSION_MAJOR 0
#define TB_VERSION_MINOR 1
#define TB_VERSION_PATCH 0

#ifdef __cplusplus
extern "C" {
#endif

/* Every call that can fail returns a status; on failure the world is left as
   it was and tb_world_message() says why in one line. */
typedef enum tb_status {
    TB_OK = 0,
    TB_ERR_ARGUMENT,   /* NaN/Inf, bad mass, bad step, unknown name, ... */
    TB_ERR_STALE_ID,   /* the id is null, removed, or from another world */
    TB_ERR_MEMORY,     /* the allocator returned NULL */
    TB_ERR_CALLBACK,   /* a user force or field callback reported failure */
    TB_ERR_BUSY,       /* a structural change was asked for during a step */
    TB_ERR_UNSTABLE    /* the blow-up guard stopped a step (tb_world_set_guard) */
} tb_status;

/* A short constant name for a status ("ok", "argument", ...). */
TB_API const char *tb_status_name(tb_status status);

/* Allocator hook in the style of lua_Alloc: new_size 0 frees ptr and returns
   NULL; otherwise it behaves as realloc. old_size is the size previously
   asked for ptr (0 when ptr is NULL). `user` is handed back untouched. */
typedef void *tb_realloc_fn(void *user, void *ptr, size_t old_size, size_t new_size);

typedef struct tb_allocator {
    tb_realloc_fn *realloc; /* NULL: the C library's realloc and free */
    void *user;
} tb_allocator;

/* Longest message a world keeps, including the terminating zero. */
#define TB_MESSAGE_SIZE 512

/* The input rule. Every number given to tumble (a definition's field, a
   setter's value, a step) must be finite and at most TB_LIMIT in magnitude;
   one tumble divides by (a mass, a moment of inertia, a size, a step) also
   at least 1 / TB_LIMIT; and what tumble derives from them at once (inverse
   mass and moments, momentum m v and I w, kinetic energy m v^2 / 2 and
   w.I.w / 2, a spring's force and energy, a held force's torque) must also
   be at most TB_LIMIT. The products of two or three such numbers that a step
   and the diagnostics form (m g.x, k d^2, |P|^2 / m) then stay below 1e300,
   short of DBL_MAX (1.8e308). A value that breaks the rule is refused with
   TB_ERR_ARGUMENT and a message naming it. The bound lies far beyond any
   physical scene in SI units (the observable universe is 1e27 m across and
   weighs 1e53 kg; an electron weighs 1e-30 kg). */
#define TB_LIMIT 1e100

#ifdef __cplusplus
}
#endif
#endif
