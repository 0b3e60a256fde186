/* ids.c: value ids with generations. Index i (0-based) is handed out as
   index1 = i + 1 so that the all-zero id is null. Free ids form a list
   threaded through `slot`. A live id has an odd generation and a free one an
   even generation, so no id can name a free entry, and live generations are
   never 0. */
#include "world.h"

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

void tb__ids_acquire(tb__ids *ids, uint32_t slot, uint32_t *index1, uint32_t *generation)
{
    uint32_t i;
    if (ids->free_head) {
        i = ids->free_head - 1;
        ids->free_head = ids->slot[i];
        ids->generation[i] += 1;
    } else {
        i = ids->used++;
        ids->generation[i] = 1;
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
    ids->generation[i] += 1; /* even: free; wraps from UINT32_MAX to 0, still even */
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
