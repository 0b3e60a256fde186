/* collide.h: narrowphase, the contact points between two shapes placed in
   the world. Pure geometry: no world, no allocation. Internal.

   Every pair of shape kinds is handled in either order; the manifold's
   normal always points from shape a to shape b, and a point is reported
   while the shapes are closer than `margin` (speculative contacts: a point
   with a negative depth is a gap the solver must not let close by more than
   the gap itself). */
#ifndef TB_COLLIDE_H
#define TB_COLLIDE_H

#include <stdint.h>

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
   plane gives 0. */
int tb__collide(const tb__geom *a, const tb__geom *b, double margin, tb__manifold *m);

/* The axis-aligned box around g, tight for every kind but the plane, which
   gets all of space (+-HUGE_VAL). */
void tb__geom_bounds(const tb__geom *g, double lo[3], double hi[3]);

#endif
