/* counting_alloc.h: a world allocator for tests that counts what it hands
   out and can be told to fail, so that a test sees every byte come back
   and every allocation failure handled. */
#ifndef TB_COUNTING_ALLOC_H
#define TB_COUNTING_ALLOC_H

#include <stdlib.h>

/* fail_after: allocations allowed before every further one fails (-1:
   never); size_mismatch: some old_size disagreed with the block's. */
typedef struct budget { long live_bytes, allocations, fail_after; int size_mismatch; } budget;

/* Each block carries its size in a header so the test can check old_size. */
static void *counting_realloc(void *user, void *ptr, size_t old_size, size_t new_size)
{
    budget *b = user;
    size_t *p = ptr ? (size_t *)ptr - 2 : NULL;
    if (p && p[0] != old_size)
        b->size_mismatch = 1;
    if (new_size == 0) {
        if (p) {
            b->live_bytes -= (long)old_size;
            free(p);
        }
        return NULL;
    }
    if (b->fail_after >= 0 && b->allocations >= b->fail_after)
        return NULL;
    b->allocations++;
    p = realloc(p, new_size + 2 * sizeof(size_t));
    if (!p)
        return NULL;
    b->live_bytes += (long)new_size - (long)old_size;
    p[0] = new_size;
    return p + 2;
}

#endif
