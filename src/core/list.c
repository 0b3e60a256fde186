/* list.c: small ordered lists of items addressed by ids. */
#include "world.h"

#include <string.h>

tb_status tb__list_add(tb_world *w, tb__list *list, const void *item, uint32_t *index1, uint32_t *generation)
{
    tb_status st;
    if (list->count == list->cap) {
        size_t cap = list->cap ? 2 * list->cap : 4;
        void **arrays[1];
        size_t sizes[1];
        arrays[0] = (void **)&list->items;
        sizes[0] = list->item_size;
        if ((st = tb__ids_reserve(w, &list->ids, cap)) != TB_OK)
            return st;
        if ((st = tb__grow(w, arrays, sizes, 1, list->count, list->cap, cap)) != TB_OK)
            return st;
        list->cap = cap;
    }
    memcpy(list->items + list->count * list->item_size, item, list->item_size);
    tb__ids_acquire(&list->ids, w->id_tag, (uint32_t)list->count, index1, generation);
    list->count++;
    return TB_OK;
}

tb_status tb__list_remove(tb_world *w, tb__list *list, uint32_t index1, uint32_t generation, const char *what)
{
    uint32_t slot, i;
    if (!tb__ids_lookup(&list->ids, index1, generation, &slot))
        return tb__fail(w, TB_ERR_STALE_ID, "%s id %u.%u is null, removed or from another world",
                        what, index1, generation);
    memmove(list->items + slot * list->item_size, list->items + (slot + 1) * list->item_size,
            (list->count - slot - 1) * list->item_size);
    for (i = slot + 1; i < list->count; ++i)
        tb__ids_move(&list->ids, i, i - 1);
    tb__ids_release(&list->ids, index1);
    list->count--;
    return TB_OK;
}

void tb__list_free(tb_world *w, tb__list *list)
{
    if (list->items)
        tb__alloc(w, list->items, list->cap * list->item_size, 0);
    list->items = NULL;
    list->count = list->cap = 0;
    tb__ids_free(w, &list->ids);
}
