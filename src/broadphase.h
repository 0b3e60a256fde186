/* broadphase.h: which shapes' boxes overlap, by sweep and prune. Internal.

   One axis is swept: the proxies are kept sorted by the low end of their box
   on it, from call to call, so that a step in which things moved a little
   re-sorts in about n (insertion sort on a nearly sorted list) and the sweep
   only looks at boxes whose extents on that axis overlap. The pairs come out
   sorted by (a, b) whatever the history of the sort, so a scene gives the
   same pairs in the same order from run to run.

   Memory: the block behind `order` is cap uint32_t long. Its first count
   entries are the kept order; the rest is this module's scratch (the sort
   keys, the boxes and filters in sweep order, the sweep's hits, the pair
   sort's counters), so that once it has seen its largest n a call
   allocates nothing. The pair buffer past *count is the scratch of the
   pair sort, so *cap may end up to about twice *count. */
#ifndef TB_BROADPHASE_H
#define TB_BROADPHASE_H

#include "world.h"

typedef struct tb__pair { uint32_t a, b; } tb__pair;   /* proxy indices, a < b */

typedef struct tb__sap {
    uint32_t *order;   /* [cap] proxies sorted by their low end on the sweep axis; kept between calls so that re-sorting a nearly sorted list (insertion sort) costs about n */
    size_t count, cap;
    int axis;          /* 0, 1, 2: chosen as the axis of largest spread of box centres, re-chosen when it changes a lot (then a full sort) */
} tb__sap;

/* The pairs of the n proxies whose boxes [lo, hi] (3n doubles each) overlap (touching counts) and whose filters accept each other:
   (category[a] & mask[b]) != 0 and (category[b] & mask[a]) != 0, and group[a] != group[b] (shapes of one body share a group and never collide;
   all static shapes share one group). Written to *pairs (grown with the world's allocator, *cap its capacity), sorted by (a, b), *count of them.
   On allocation failure: TB_ERR_MEMORY with a message, and *pairs / *cap still valid. */
/* Start from a zeroed tb__sap. n may change between calls (the proxies
   renumbered by swap-remove). category, mask and group may each be NULL:
   every bit set, and every proxy in a group of its own. Boxes must not hold
   NaN (which pairs then come out is unspecified, but the call stays safe).
   On failure *count is 0 and the sap stays usable; n >= UINT32_MAX is
   TB_ERR_ARGUMENT. */
tb_status tb__sap_pairs(tb_world *w, tb__sap *sap, size_t n, const double *lo, const double *hi,
                        const uint32_t *category, const uint32_t *mask, const uint32_t *group,
                        tb__pair **pairs, size_t *count, size_t *cap);

/* Free the sap's memory and zero it (the pair buffer is the caller's). */
void tb__sap_free(tb_world *w, tb__sap *sap);

#endif
