/* contacts.h: shapes in a world and the contacts between them (not
   public): the shapes' API and storage (shapes.c), finding contacts and
   solving them by the sweeps, substeps 0 (contact.c, with the sweeps'
   lanes in contact_lanes.c and the conjugate-gradient solves in
   cold_start.c), the soft step, the default (soft_step.c, stack_solve.c
   and continuous.c, soft_step.h), and sleep (sleep.c). The
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
    double predicted;          /* m: separation after the free motion */
    double local_a[3], local_b[3]; /* m: the point in each shape's frame, and */
    double separation0;        /* its separation, when the shapes last collided */
    int active;                /* touching after the free motion: solved */
    int matched;               /* it touched last step too (warm started) */
    double friction_impulse[3];/* always 0: both solvers keep friction per patch
                                  (tb__entry.friction_impulse); the state hash reads it */
} tb__point;

/* The solver works on batches of up to TB__BATCH_LANES manifolds that
   share no moving body (a colouring of the step's manifolds), laid out
   lane by lane so that one instruction serves every lane
   (contact_lanes.c). A manifold is a lane, solved as one patch at the
   centre of its touching points, in six rows:
   - the normal: a force row (>= 0) where last step's normal force was
     centred (shift), and a tilt about each tangent (the first along a
     side of the points), within that force times the range of the
     points' levers about that point (the centre of pressure stays within
     the points' bounding rectangle along the tangents: their own
     rectangle for a box's face);
   - friction (as Bepu and PhysX's patch friction): two tangent rows within
     the circle mu times the normal force, and a twist about the normal
     within that times the points' mean distance from the centre.
   The patch shares a tall stack's weight between a pair's points within
   the sweeps, where rows per point, met in turn, leave that share
   unconverged (stack_of_ten_stands). The position pass meets the patch
   too (the press and tilts toward the plane that best levels what the
   points need), then each point's own normal row for what is left. A row
   holds r x d at each anchor and I^-1 (r x d).
   Bodies are indices into the velocity arrays, where 0 is the static
   world (no motion, no inverse mass), so the sweeps never branch on which
   side moves; an empty lane, or a lane without a given point, is all zeros
   on the static world. */
#define TB__BATCH_LANES 8
#define TB__COLOURS 64 /* one bit each in a uint64_t */

/* The patch's rows, in a batch's arrays */
enum { TB__ROW_TANGENT1, TB__ROW_TANGENT2, TB__ROW_TWIST, TB__ROW_TILT1, TB__ROW_TILT2, TB__ROW_PRESS, TB__PATCH_ROWS };

typedef struct tb__lane_point {
    double arm_a[3][TB__BATCH_LANES], arm_b[3][TB__BATCH_LANES]; /* [axis][lane]: its normal row */
    double turn_a[3][TB__BATCH_LANES], turn_b[3][TB__BATCH_LANES];
    double mass[TB__BATCH_LANES];       /* 1 / (J M^-1 J^T) */
    double predicted[TB__BATCH_LANES];  /* m: separation after the free motion */
    double push_target[TB__BATCH_LANES];/* m: the separation the position pass aims for */
    double position_impulse[TB__BATCH_LANES];
    struct tb__point *source[TB__BATCH_LANES]; /* where the impulse goes back to; NULL: none */
} tb__lane_point;

typedef struct tb__batch {
    int32_t a[TB__BATCH_LANES], b[TB__BATCH_LANES];
    int points;                         /* the most points of any lane */
    int one_sided;                      /* every lane's a is the static world: the sweeps
                                           skip side a (a plane's contacts) */
    int tilting;                        /* some lane resists tilts: its points have a range
                                           across a tangent, or it resists rolling */
    double dir[3][3][TB__BATCH_LANES];  /* [row][axis][lane]: the manifold's normal, tangents */
    double friction[TB__BATCH_LANES];
    /* the patch, TB__PATCH_ROWS rows: the tangent and press rows at the
       centre; the twist and tilts turn about the normal and the tangents
       (their arms are those directions themselves) */
    double arm_a[TB__PATCH_ROWS][3][TB__BATCH_LANES], arm_b[TB__PATCH_ROWS][3][TB__BATCH_LANES]; /* [row][axis][lane] */
    double turn_a[TB__PATCH_ROWS][3][TB__BATCH_LANES], turn_b[TB__PATCH_ROWS][3][TB__BATCH_LANES];
    double mass[TB__PATCH_ROWS][TB__BATCH_LANES];
    double impulse[TB__PATCH_ROWS][TB__BATCH_LANES]; /* N s (twist, tilts: N m s), accumulated */
    double press_target[TB__BATCH_LANES];/* m/s: the normal velocity to reach at the centre */
    double bounce[TB__BATCH_LANES];     /* m/s: for a lane that bounces (> 0), the normal
                                           velocity its press reaches after the sweeps */
    int bouncing;                       /* some lane bounces */
    double tilt_low[2][TB__BATCH_LANES], tilt_high[2][TB__BATCH_LANES]; /* m: the range of the
                                           points' levers for each tilt (a unit normal force's
                                           moment about tangent d, from the centre), widened by
                                           the rolling resistance on both sides */
    double twist_reach[TB__BATCH_LANES];/* m: mean distance of the points from the centre */
    double shift[2][TB__BATCH_LANES];   /* m: where the press acts, as levers from the centre
                                           (the tilts' ranges are then from there): last
                                           step's centre of pressure */
    double lever[TB__BATCH_LANES];      /* s: how long the patch's normal rows (press, tilts) act
                                           on positions */
    double side_lever[TB__BATCH_LANES]; /* s: ... and its friction rows (tangents, twist) */
    double keep[TB__BATCH_LANES];       /* the share of its normal impulses to start the next
                                           step from */
    int resting[TB__BATCH_LANES];       /* every point at rest: none struck this step or is
                                           deeper than the slop, and the new ones' sides move
                                           slower than the sleep speed (cold_start.c) */
    int landing[TB__BATCH_LANES];       /* every point at rest or struck this step, none deeper
                                           than the slop */
    int heavy[TB__BATCH_LANES];         /* landing, between two bodies whose masses differ
                                           TB__MASS_RATIO-fold or more where a point of it struck
                                           this step or the last, TB__MASS_RATIO_RESTING-fold
                                           where none did (cold_start.c) */
    int in_solve;                       /* some lane's normal rows are in the cold start's
                                           solve (its kernels pass over the other batches) */
    /* the position pass's patch, met before the points' own rows: what the
       centre's normal displacement must reach (m), then the turns about
       the tangents (rad) of the least-squares plane through what each
       point needs; and their accumulated position impulses */
    double patch_push[3][TB__BATCH_LANES], patch_impulse[3][TB__BATCH_LANES];
    struct tb__entry *source[TB__BATCH_LANES]; /* NULL: an empty lane */
    const double *inv_world_a[TB__BATCH_LANES], *inv_world_b[TB__BATCH_LANES]; /* I^-1, 9 each */
    tb__lane_point point[TB__MANIFOLD_POINTS];
} tb__batch;

/* contact_lanes.c: a sweep over the batches on the velocity array m, and
   a position sweep (normal rows only) on the position-change array;
   backwards: the batches last to first, each one's rows reversed (the
   position sweep: its points, after the patch). isa: tb__isa() or below,
   the same bits each. */
void tb__sweep_velocities(tb__batch *batches, size_t n, double *m, int backwards, int isa);
void tb__sweep_positions(tb__batch *batches, size_t n, double *m, int backwards, int isa);

/* Restitution, after the velocity sweeps: the press row of every lane
   that bounces, once, toward its bounce target, with friction and tilts
   left as the sweeps left them (as Box2D v3 bounces after its solve).
   Bounced within the sweeps, a sticking friction row would carry part of
   the bounce through the body's turn into its motion and give it energy
   (spinning_plate_bounces_without_gaining_energy). */
void tb__bounce(tb__batch *batches, size_t n, double *m, int isa);

/* The rows of every batch from its lanes' anchors: on entry each point's
   arm_a, arm_b hold its r from each centre, the patch's row 0 the
   centre's; I^-1 from inv_world_a, _b, inverse masses from slot 6 of m.
   Fills every arm, turn and mass. */
void tb__set_up_rows(tb__batch *batches, size_t n, const double *m, int isa);

/* Every row's accumulated impulse pushed once into m, batch by batch:
   TB__PUSH_VELOCITY, on the velocities (the warm start);
   TB__PUSH_MOTION, on the position changes, times each row's lever time;
   TB__PUSH_MOMENTA, on the momenta (P, L; slot 6 holds 1 for a moving
   body), by the rows' arms. */
enum { TB__PUSH_VELOCITY, TB__PUSH_MOTION, TB__PUSH_MOMENTA };
void tb__push_impulses(tb__batch *batches, size_t n, double *m, int what, int isa);

/* For the cold start's conjugate gradients (cold_start.c), the normal
   rows of every batch (its press, then its two tilts) as [batch][row][lane]
   arrays of TB__NORMAL_ROWS * TB__BATCH_LANES doubles: the impulses given
   pushed on the velocities m, as TB__PUSH_VELOCITY pushes the batches'
   own; and each row's rate on m (the relative velocity the sweeps hold it
   to), into out. */
#define TB__NORMAL_ROWS 3
void tb__push_normal_rows(const tb__batch *batches, size_t n, double *m, const double *rows, int isa);
void tb__normal_rates(const tb__batch *batches, size_t n, const double *m, double *out, int isa);

/* contact.c: the turns (phi_1, phi_2) that best level a patch, the
   least-squares solution of S phi = b with S = [s00 s01; s01 s11] the
   sums of the points' lever products: by S's pseudo-inverse, a direction
   whose spread is under 1e-9 of the largest left unturned. (A test of
   det against s00 s11 would let points all but on a line, their levers
   across it of a rounding's size, be turned by millions of radians:
   patch_turns_are_least_squares.) */
void tb__level_turns(double s00, double s01, double s11, double b0, double b1, double turn[2]);

/* cold_start.c: the normal rows of the lanes at rest solved as
   equalities by conjugate gradients from the warm starts, up to most
   iterations or until every row is within tolerance of stopping, clamped
   and pushed on c->velocity, before the sweeps: where the result leaves
   no row much further from what it may do than the warm starts did, and
   (whole) where it met them. Returns the iterations taken (negated: the
   guess was not taken). */
int tb__cold_start(tb__contacts *c, int most, double tolerance, int whole);

/* The same for the lanes landing near the heavy ones (tb__batch), where
   their solve met every row, leaves none further off and takes no
   kinetic energy into the step: a heavy body landing on a light one, and
   the step after. */
int tb__heavy_landings(tb__contacts *c, int most, double tolerance);

/* Sequential impulses pass a load between bodies of very different masses
   slowly: a light body under a heavy one needs about as many sweeps as
   the ratio of their masses to carry it. A landing between bodies this
   many times apart in mass is solved with the lanes near it (cold_start.c,
   heavy_box_lands_on_light_ones). */
#define TB__MASS_RATIO 10
/* ... and resting, from this ratio on: where a step's sweeps take out
   less than a fifth of what knocked the pair off, and a heavy body left
   to them sinks through a light one (heavy_box_lands_on_light_ones, its
   10000 times heavier box with sleep off). */
#define TB__MASS_RATIO_RESTING 100

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
    double tilt_impulse[3];    /* N m s, world, in the contact plane: the tilts', kept from
                                  step to step */
    double rolling_impulse[3]; /* N m s, world: the soft step's rolling resistance, kept */
    int count;
    int touching;
    int asleep;                /* carried over unsolved: both sides sleep or are static */
    int colour;                /* its batches' colour, TB__COLOURS: a batch of its own */
    int cached;                /* the fields below hold the last collision */
    int struck, struck_before; /* a point of it struck this step, last step */
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
    double inv_world[9];       /* R diag(inv_inertia) R^T, after the free motion */
    double x0[3], q0[4];       /* pose at the start of the step */
    double v0[3], w0[3];       /* velocities at the start of the step */
    double p0[3], l0[3];       /* N s, N m s: a body's momenta at the start of the step */
    double x[3];               /* position after the free motion */
    double turn[3];            /* the free motion's rotation over the step (vector) */
} tb__solver_body;

/* The sweeps' per-body arrays: TB__MOTION doubles per solver body + 1 (0 is
   the static world): a velocity (v, w) or position change (dp, dtheta),
   then the inverse mass; one cache line each. */
#define TB__MOTION 8
/* the three arrays' block, with room to start them on a 64-byte line */
#define TB__MOTION_BYTES(cap) (3 * TB__MOTION * (cap) * sizeof(double) + 64)

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

    tb__batch *batches;        /* the touching manifolds of this step */
    size_t batch_count, batch_cap;
    double *settle;            /* [batch_cap * TB__PATCH_ROWS * TB__BATCH_LANES]: the batches'
                                  impulses before a pair of sweeps */
    size_t settle_cap;
    double *cold_rows;         /* [7 * batch_cap * TB__NORMAL_ROWS * TB__BATCH_LANES]: the cold
                                  start's vectors (cold_start.c) */
    size_t cold_rows_cap;
    uint64_t *colours;         /* [body_count + 1]: the colours a solver body's manifolds
                                  took; in the solve, the cold start's rings (cold_start.c) */
    size_t colours_cap;
    uint32_t *bucket;          /* [entry_cap]: entries by colour, then points */
    size_t bucket_cap;
    int isa;                   /* the sweeps' instruction set (tb__isa) */
    int sweeps;                /* velocity sweeps the last step took (for tests; of a cold
                                  step's extra sweeps, the pair that settled is not counted) */
    size_t heavy_lanes;        /* lanes of this step that are heavy (tb__batch) */
    size_t bounces;            /* lanes of this step that bounce */
    double kept_h;             /* s: the step the kept impulses were solved for (0: none) */
    double gravity[3];         /* m/s^2: the world's, this step */
    double rest_lever;         /* s: how long a resting contact's impulse acts on positions
                                  this step, as a constant force would under the world's
                                  method (tb__force_lever times h) */
    double *velocity, *motion, *momenta; /* [TB__MOTION * motion_cap] each, one block: see
                                  TB__MOTION (momenta: P, L, then 1 or 0 for the static world) */
    double *motion_block;      /* the block as allocated: TB__MOTION_BYTES(motion_cap) */
    size_t motion_cap;

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
    struct tb__stacks *stacks; /* stack_solve.c: rows solved together */
    int prepared;              /* entries hold this step's contacts, to solve */
    int solved;                /* entries hold the last step's solved contacts */
};

/* ---- around the integrator's step (contact.c, shapes.c) --------------------- */
/* Whether the world has shapes to collide. */
int tb__contacts_active(const tb_world *w);
/* Before the integrator: find this step's contacts at the start positions. */
tb_status tb__contacts_prepare(tb_world *w, double h);
/* After the integrator's free motion: solve the contacts. force_lever is
   how far the step's method moves positions under a constant force, as a
   share of h (tb__force_lever, stepping/stepping.h; tb__method in
   world.h): a resting contact's impulse moves positions by that lever, so
   a body at rest stays put under every method. */
void tb__contacts_solve(tb_world *w, double h, double force_lever);
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

/* soft_step.c: the step's contacts solved by the soft-step solver
   (settings.substeps > 0) instead of the sweeps: the bodies and particles
   in them moved again from the start of the step in substeps, then
   stored. Events and sleep stay with tb__contacts_solve. */
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
