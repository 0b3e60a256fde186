/* contacts.h: shapes in a world and the contacts between them (not
   public): the shapes' API and storage (shapes.c), finding contacts and
   their events (contact.c), solving them by the soft step (soft_step.c,
   stack_solve.c and continuous.c, soft_step.h), and sleep (sleep.c). The
   model is described in docs/contacts.md.
   A world holds a pointer to one tb__contacts, allocated with its first
   shape or contact settings: a world without shapes pays nothing. */
#ifndef TB_CONTACTS_H
#define TB_CONTACTS_H

#include "world.h"
#include "bodies/bodies.h"
#include "collision/collision.h"

typedef struct tb__shape {
    tb__shape_kind kind;
    uint32_t body;         /* body id index1, 0: static */
    uint32_t body_generation;
    double pos[3];         /* m: in the body's principal frame (static: world) */
    double rot[4];         /* body (or world) from shape */
    double radius;         /* m: sphere, capsule */
    double half[3];        /* m: box half extents; capsule: half[2] = half length */
    double normal[3];      /* plane */
    double offset;         /* m, plane */
    double friction, restitution;
    double rolling_resistance; /* m */
    uint32_t category, mask;
    double reach;          /* m: how far the shape reaches from the body's centre */
} tb__shape;

/* One contact point, as it is found and kept from step to step. */
typedef struct tb__point {
    uint32_t feature;
    double normal_impulse;     /* N s, kept from step to step (warm start) */
    double point[3];           /* m, world: where the contact was found */
    double ra[3], rb[3];       /* m: the point from each centre at the start of the
                                  step, world (0 on a static side) */
    double separation;         /* m, at the start of the step (< 0: overlap) */
    double speed;              /* m/s: the approach speed of an impact, 0 otherwise */
    double local_a[3], local_b[3]; /* m: the point in each shape's frame, and */
    double separation0;        /* its separation, when the shapes last collided */
    int active;                /* touching after the free motion: solved */
} tb__point;

/* The points between two shapes (or a shape and a particle). */
typedef struct tb__entry {
    uint32_t key_a, key_b;     /* shape id index1s; key_b | TB__PARTICLE_KEY for a particle */
    int32_t body_a, body_b;    /* solver bodies, -1: static */
    double normal[3], tangent[2][3];
    double friction, restitution;
    double rolling;            /* m: the pair's rolling resistance */
    double core[2];            /* m: each side's depth from its surface to its core (a
                                  sphere's centre, a capsule's segment; 0: box, plane) */
    double friction_impulse[3];/* N s, world: the patch's, kept from step to step */
    double twist_impulse;      /* N m s, about the normal */
    double rolling_impulse[3]; /* N m s, world: the soft step's rolling resistance, kept */
    int count;
    int touching;
    int asleep;                /* carried over unsolved (then parked: contact.c, park): both
                                  sides sleep or are static */
    int cached;                /* the fields below hold the last collision */
    int struck;                /* a point of it struck this step */
    int reused;                /* this step's manifold is the last collision's, moved */
    double cache_rot[9];       /* b's shape frame in a's when the shapes last collided */
    double cache_pos[3];       /* m: b's shape centre then, in a's frame */
    double cache_normal[3];    /* the normal then, in a's frame */
    uint64_t found;            /* where the step found it: TB__FOUND_PLANE or
                                  TB__FOUND_PAIR; entries are made in this order */
    tb__point point[TB__MANIFOLD_POINTS];
} tb__entry;

/* tb__entry.found: plane shape slot i against proxy k, then the
   broadphase's pairs (a, b) in their order. Entries are appended in
   increasing order of it, so a parked entry (sleep.c) has its place among
   a step's entries without being one of them (tb_world_hash walks both in
   this order: test_snapshot.contact_scene_hash_is_recorded). */
#define TB__FOUND_PLANE(i, k) ((uint64_t)(i) << 31 | (uint64_t)(k))
#define TB__FOUND_PAIR(a, b) ((uint64_t)1 << 62 | (uint64_t)(a) << 31 | (uint64_t)(b))

/* Collision's face tolerance, as a share of the slop (tb__collide; Box2D
   keeps its reference face by the same tenth of its linear slop): an edge
   lying along a face within it touches the face along a line, a point at
   each end. One edge point would jump from end to end as the bodies
   rock, and each jump's new overlap, pushed out, adds energy
   (test_contacts_heaps.box_across_two_rests). */
#define TB__FACE_TOLERANCE 0.1

#define TB__PARTICLE_KEY 0x80000000u

/* A body or particle that takes part in contacts this step. */
typedef struct tb__solver_body {
    enum tb__tier tier;
    uint32_t slot;
    double inv_mass;
    double inv_inertia[3];     /* principal moments' inverses (0 for particles) */
    double x0[3], q0[4];       /* pose at the start of the step */
    double v0[3], w0[3];       /* velocities at the start of the step */
    double p0[3], l0[3];       /* N s, N m s: a body's momenta at the start of the step */
    double x[3];               /* position at the end of the step */
    double turn[3];            /* its rotation over the step (vector: 2 sin(angle/2) n), for
                                  the events' points */
} tb__solver_body;

/* A sleeping body's pose, put back after the free motion. */
typedef struct tb__pose {
    uint32_t slot;
    double x[3], q[4];
} tb__pose;

/* A contact entry's place in key order. */
typedef struct tb__key {
    uint64_t key;              /* key_a << 32 | key_b */
    uint32_t index;            /* into entries */
} tb__key;

struct tb__contacts {
    tb__shape *shapes;         /* [shape_cap] */
    size_t shape_count, shape_cap;
    size_t planes;             /* how many of the shapes are planes */
    tb__ids ids;
    tb_contact_settings settings;

    /* broadphase proxies: non-plane shapes, then particles */
    tb__sap sap;
    double *lo, *hi;           /* [3 * proxy_cap] */
    uint32_t *category, *mask, *group, *proxy; /* [proxy_cap]; proxy: shape slot, or
                                  particle slot | TB__PARTICLE_KEY */
    double *margin;            /* [proxy_cap] m: how far the proxy may move this step */
    uint32_t *owner;           /* [proxy_cap] body slot + 1; 0: static or a particle */
    uint32_t *still;           /* [proxy_cap] the sleep tag of the island its body slept in
                                  when its geom, bounds and margin were made (0: awake or
                                  none): kept while that island sleeps, for steps of still_h */
    double still_h;            /* s */
    uint64_t shape_version;    /* counts shapes added and removed */
    uint64_t proxy_version;    /* ... when the proxies were last made, */
    size_t shape_proxies;      /* and how many of them are shapes' (the first) */
    tb__geom *geoms;           /* [proxy_cap]: the proxies' shapes placed in the world */
    size_t proxy_count, proxy_cap;
    tb__pair *pairs;
    size_t pair_count, pair_cap;

    /* contact entries of this step and of the last one, in the order found,
       and their indices in key order */
    tb__entry *entries, *previous;
    size_t entry_count, entry_cap, previous_count, previous_cap;
    tb__key *order, *previous_order, *order_scratch;
    size_t order_cap, previous_order_cap, order_scratch_cap;
    uint32_t *starts, *previous_starts; /* [key_a]: where key_a's entries start in (previous_)order */
    size_t starts_cap, previous_starts_cap, starts_count, previous_starts_count;

    uint32_t *park_index;      /* [entry_count + 1]: park's scratch */
    size_t park_index_cap;
    double kept_h;             /* s: the step the kept impulses were solved for (0: none) */

    tb__solver_body *bodies;
    size_t body_count, body_cap;
    int32_t *body_map;         /* [map_cap] body slot -> solver body, -1 */
    int32_t *particle_map;     /* [map_cap2] particle slot -> solver body, -1 */
    size_t body_map_cap, particle_map_cap;

    tb_contact_event *events;
    size_t event_count, event_cap;
    size_t touching_points;

    /* sleep.c (the count of bodies asleep is the world's body_sleeping) */
    uint32_t next_island;      /* the last tag given to an island */
    tb__pose *poses;
    size_t pose_count, pose_cap;
    double *island_scratch;
    size_t island_scratch_cap;
    /* entries parked while both their sides sleep or are static (sleep.c):
       out of the step's entries, so a sleeping pair costs nothing a step;
       in found order */
    tb__entry *parked;
    size_t parked_count, parked_cap;
    size_t parked_points;      /* their touching points (tb_world_contact_count) */
    double parked_h;           /* s: the step they were found at */
    size_t parked_sleeping;    /* w->body_sleeping when last parked or looked at */
    int unparked;              /* some came back this step (carry_over looks for them) */
    /* soft_step.c: the soft-step solver's rows and bodies */
    struct tb__soft_row *soft_rows;
    size_t soft_row_count, soft_row_cap;
    struct tb__soft_body *soft_bodies;
    size_t soft_body_cap;
    struct tb__soft_patch *soft_patches;
    size_t soft_patch_count, soft_patch_cap;
    struct tb__soft_row *wide_rows;       /* the rows and patches reordered, narrow islands' */
    struct tb__soft_patch *wide_patches;  /* first (soft_step.c, wide_islands_apart) */
    size_t wide_row_cap, wide_patch_cap;
    int soft_pass;             /* the bodies the soft step's loops move now (tb__soft_body.pass) */
    struct tb__stacks *stacks; /* stack_solve.c: rows solved together */
    struct tb__soft_joint *soft_joints; /* soft_joints.c: the joints of bodies in contact */
    size_t soft_joint_count, soft_joint_cap;
    struct tb__soft_joint_row *joint_rows; /* ... and their rows */
    size_t joint_row_count, joint_row_cap;
    int32_t *joint_groups;     /* [2 nodes] soft_joints.c's scratch */
    size_t joint_group_cap;
    int prepared;              /* entries hold this step's contacts, to solve */
    int solved;                /* entries hold the last step's solved contacts */
};

/* ---- around the integrator's step (contact.c, shapes.c) --------------------- */
/* Whether the world has shapes to collide. */
int tb__contacts_active(const tb_world *w);
/* joint_contacts.c: after this step's solve, the contact points of the
   islands with joints handed to the joints' projection (joints.h,
   tb__joint_contact) */
tb_status tb__contacts_for_joints(tb_world *w);
/* The solver body of a body or particle slot, made on first use; -1 for
   static things, pinned particles included */
tb_status tb__contacts_solver_body(tb_world *w, tb__contacts *c, enum tb__tier tier, uint32_t slot, int32_t *out);
/* soft_joints.c: with the step's contacts found, every body jointed to a
   solver body made one, and the joints between them marked
   TB__JOINT_SOFT: met in the soft step's substeps this step */
tb_status tb__soft_joints_prepare(tb_world *w, tb__contacts *c);
/* Before the integrator: find this step's contacts at the start positions. */
tb_status tb__contacts_prepare(tb_world *w, double h);
/* After the integrator's free motion: solve the contacts (the soft
   step), then events and sleep. */
void tb__contacts_solve(tb_world *w, double h);
/* The energy (J) of what the solve may change: the prepared step's
   bodies and particles in contact, and with a particle among them the
   springs' (springs join particles). Its change over the solve is the
   contacts' work (tb_work), found without a pass over the world: a
   sleeping pile costs nothing (docs/contacts.md, "Sleep"). */
double tb__contacts_energy(const tb_world *w);
/* Shape s in the world, for a body at x with orientation q (x NULL: a
   static shape, posed in the world) */
void tb__place_shape(const tb__shape *s, const double x[3], const double q[4], tb__geom *g);
void tb__contacts_free(tb_world *w);

/* soft_step.c: the step's contacts solved by the soft-step solver: the
   bodies and particles in them moved again from the start of the step in
   settings.substeps substeps, then stored. Events and sleep stay with
   tb__contacts_solve. */
tb_status tb__soft_step(tb_world *w, tb__contacts *c, double h);
void tb__soft_free(tb_world *w, tb__contacts *c);

/* sleep.c: the sleep tag of proxy k's body (0: awake, static, particle);
   before the narrowphase, wake what moving proxies reach and keep the
   sleeping poses; after the integrator, put them back; after the solve,
   rest times and islands. */
uint32_t tb__proxy_island(const tb_world *w, const tb__contacts *c, size_t k);
/* Whether shape key's side of a contact neither moves nor is moved: a
   static shape, or its body asleep. */
int tb__key_still(const tb_world *w, const tb__contacts *c, uint32_t key);
tb_status tb__sleep_prepare(tb_world *w, tb__contacts *c);
/* Whether tb__sleep_prepare would wake an island: some pair of this
   step's has a sleeping side and a moving one. */
int tb__sleep_wakes(const tb_world *w, const tb__contacts *c);
void tb__sleep_restore(tb_world *w, tb__contacts *c);
void tb__sleep_update(tb_world *w, tb__contacts *c, double h);

#endif
