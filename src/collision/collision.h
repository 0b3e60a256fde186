/* collision.h: geometry for contacts (not public): which boxes overlap
   (broadphase.c, sweep and prune) and the contact points between two
   placed shapes (collide.c). It knows shapes only as placed geometry: the
   shapes of a world and their bodies are the contacts' (contacts/). */
#ifndef TB_COLLISION_H
#define TB_COLLISION_H

#include "world.h"

/* ---- narrowphase (collide.c) ------------------------------------------------

   The contact points between two shapes placed in the world. Pure
   geometry: no world, no allocation.

   Every pair of shape kinds is handled in either order; the manifold's
   normal always points from shape a to shape b, and a point is reported
   while the shapes are closer than `margin` (speculative contacts: a point
   with a negative depth is a gap the solver must not let close by more than
   the gap itself). */


typedef enum tb__shape_kind {
    TB__SHAPE_SPHERE,
    TB__SHAPE_CAPSULE,
    TB__SHAPE_BOX,
    TB__SHAPE_PLANE,   /* static only: the half-space n.x <= offset is solid */
    TB__SHAPE_KINDS
} tb__shape_kind;

/* A shape placed in the world. */
typedef struct tb__geom {
    tb__shape_kind kind;
    double pos[3];     /* m, world: centre of sphere, capsule or box */
    double rot[9];     /* world from shape, row-major: column j is the shape's
                          axis j in world coordinates (box and capsule) */
    double half[3];    /* m: box half extents; capsule: half[2] is the half
                          length of its core segment, along the shape's z axis */
    double radius;     /* m: sphere and capsule */
    double normal[3];  /* plane: unit outward normal */
    double offset;     /* m, plane: n.x = offset on the surface */
} tb__geom;

typedef struct tb__contact_point {
    double pos[3];     /* m, world: midway between the two surfaces */
    double depth;      /* m: > 0 overlap, < 0 gap (speculative) */
    uint32_t feature;  /* the same value for the same pair of features from
                          step to step (for warm starting) */
} tb__contact_point;

#define TB__MANIFOLD_POINTS 4

typedef struct tb__manifold {
    double normal[3];  /* unit, world, from a to b */
    int count;         /* 0 to TB__MANIFOLD_POINTS */
    tb__contact_point point[TB__MANIFOLD_POINTS];
} tb__manifold;

/* Fill m with the contact points of a and b closer than margin (m >= 0);
   returns m->count (m->normal means nothing when it is 0). Plane against
   plane gives 0. A face is the reference unless another axis separates
   the shapes by more than tolerance (m >= 0) beyond it: an edge lying
   along a face within it gives the points of the line, not one. */
int tb__collide(const tb__geom *a, const tb__geom *b, double margin, double tolerance, tb__manifold *m);

/* The axis-aligned box around g, tight for every kind but the plane, which
   gets all of space (+-HUGE_VAL). */
void tb__geom_bounds(const tb__geom *g, double lo[3], double hi[3]);


/* ---- broadphase (broadphase.c) ------------------------------------------------

   Which shapes' boxes overlap, by sweep and prune.

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

/* The same, but for the pairs of two proxies whose still[] entries are both
   non-zero (a sleeping or static shape against another: pairs the caller
   keeps as they were): those are left out, and a still proxy with no other
   proxy in its reach along the sweep axis costs one test. still NULL: every
   pair, as tb__sap_pairs. */
tb_status tb__sap_moving_pairs(tb_world *w, tb__sap *sap, size_t n, const double *lo, const double *hi,
                               const uint32_t *category, const uint32_t *mask, const uint32_t *group,
                               const uint32_t *still, tb__pair **pairs, size_t *count, size_t *cap);

/* Free the sap's memory and zero it (the pair buffer is the caller's). */
void tb__sap_free(tb_world *w, tb__sap *sap);

#endif
