/* ids.c: value ids with generations. Index i (0-based) is handed out as
   index1 = i + 1 so that the all-zero id is null. Free ids form a list
   threaded through `slot`.

   A generation is the world's tag in its top TB__ID_TAG_BITS bits and a
   counter in the bits below. The table stores whole generations, so one
   comparison checks both the object's life and its world: an id of another
   world (another tag) is refused like a removed one, at no cost to the
   lookup. A live id has an odd counter and a free one an even counter, so
   no id can name a free entry, and live generations are never 0. */
#include "world.h"

/* The tag of the next world: a process-wide serial, so that any 2^12
   worlds created one after another carry distinct tags. Several threads may
   create worlds at once, so it is taken with an atomic fetch-and-add: GCC's
   and Clang's builtins (C99 has no atomics, and the builtins compile under
   -std=c99 -Wpedantic), MSVC's interlocked increment, or C11's
   <stdatomic.h>. A compiler with none of them gets a plain counter: two
   worlds created at the same instant on two threads may then share a tag,
   which only weakens the refusal of foreign ids between those two (a tag
   never locates memory). The first world of a process has tag 0, so its
   ids read as small numbers (particle 3.1) in messages. */
#if defined(__GNUC__) || defined(__clang__)
static uint32_t serial;
#define NEXT_SERIAL() __atomic_fetch_add(&serial, 1u, __ATOMIC_RELAXED)
#elif defined(_MSC_VER)
#include <intrin.h>
static volatile long serial;
#define NEXT_SERIAL() ((uint32_t)(_InterlockedIncrement(&serial) - 1))
#elif defined(__STDC_VERSION__) && __STDC_VERSION__ >= 201112L && !defined(__STDC_NO_ATOMICS__)
#include <stdatomic.h>
static atomic_uint serial;
#define NEXT_SERIAL() ((uint32_t)atomic_fetch_add_explicit(&serial, 1u, memory_order_relaxed))
#else
static uint32_t serial;
#define NEXT_SERIAL() (serial++)
#endif

uint32_t tb__ids_new_tag(void)
{
    const uint32_t n = NEXT_SERIAL();
    return (n & ((1u << TB__ID_TAG_BITS) - 1u)) << TB__ID_COUNTER_BITS;
}

tb_status tb__ids_reserve(tb_world *w, tb__ids *ids, size_t capacity)
{
    void **arrays[3];
    size_t sizes[3] = { sizeof(uint32_t), sizeof(uint32_t), sizeof(uint32_t) };
    size_t cap;
    tb_status st;
    if (capacity <= ids->capacity)
        return TB_OK;
    if (capacity >= UINT32_MAX - 1)
        return tb__fail(w, TB_ERR_MEMORY, "too many objects of one kind (%zu)", capacity);
    cap = ids->capacity ? ids->capacity : 8;
    while (cap < capacity)
        cap *= 2;
    if (cap >= UINT32_MAX - 1)
        cap = UINT32_MAX - 2;
    arrays[0] = (void **)&ids->slot;
    arrays[1] = (void **)&ids->generation;
    arrays[2] = (void **)&ids->owner;
    st = tb__grow(w, arrays, sizes, 3, ids->capacity, ids->capacity, cap);
    if (st == TB_OK)
        ids->capacity = (uint32_t)cap;
    return st;
}

void tb__ids_free(tb_world *w, tb__ids *ids)
{
    void **arrays[3];
    size_t sizes[3] = { sizeof(uint32_t), sizeof(uint32_t), sizeof(uint32_t) };
    arrays[0] = (void **)&ids->slot;
    arrays[1] = (void **)&ids->generation;
    arrays[2] = (void **)&ids->owner;
    tb__free_arrays(w, arrays, sizes, 3, ids->capacity);
    ids->capacity = ids->used = ids->free_head = 0;
}

/* The next counter of generation g, its tag kept; the counter wraps from
   its largest value (odd) to 0 (even), so the parity still alternates. */
static uint32_t bump(uint32_t g)
{
    return (g & ~TB__ID_COUNTER_MASK) | ((g + 1u) & TB__ID_COUNTER_MASK);
}

void tb__ids_acquire(tb__ids *ids, uint32_t tag, uint32_t slot, uint32_t *index1, uint32_t *generation)
{
    uint32_t i;
    if (ids->free_head) {
        i = ids->free_head - 1;
        ids->free_head = ids->slot[i];
        ids->generation[i] = bump(ids->generation[i]);
    } else {
        i = ids->used++;
        ids->generation[i] = tag | 1u;
    }
    ids->slot[i] = slot;
    ids->owner[slot] = i;
    *index1 = i + 1;
    *generation = ids->generation[i];
}

int tb__ids_lookup(const tb__ids *ids, uint32_t index1, uint32_t generation, uint32_t *slot)
{
    uint32_t i = index1 - 1;
    if (index1 == 0 || i >= ids->used || ids->generation[i] != generation || !(generation & 1u))
        return 0;
    *slot = ids->slot[i];
    return 1;
}

void tb__ids_release(tb__ids *ids, uint32_t index1)
{
    uint32_t i = index1 - 1;
    ids->generation[i] = bump(ids->generation[i]); /* even: free */
    ids->slot[i] = ids->free_head;
    ids->free_head = index1;
}

void tb__ids_move(tb__ids *ids, uint32_t from, uint32_t to)
{
    uint32_t i = ids->owner[from];
    ids->owner[to] = i;
    ids->slot[i] = to;
}

void tb__ids_at(const tb__ids *ids, uint32_t slot, uint32_t *index1, uint32_t *generation)
{
    uint32_t i = ids->owner[slot];
    *index1 = i + 1;
    *generation = ids->generation[i];
}
