/* snapshot.c: snapshots of a whole world, restoring one, and the state
   hash. A snapshot is a copy of the world's struct and of its contacts'
   struct whose arrays point to blocks of its own. Both structs' arrays are
   listed once, in one order, by list_blocks, which every copy, restore and
   free walks: an array added to either struct must be listed there, or
   named there as scratch with the reason no step reads it before writing
   it, for a restore to continue bit-identically
   (test_snapshot.restore_continues_bit_identically).

   It sits with the step because the guard rolls a refused step back with
   it (tb__rollback_keep, tb__rollback). */
#include "stepping/stepping.h"
#include "bodies/bodies.h"
#include "contacts/contacts.h"
#include "joints/joints.h"
#include "forces/forces.h"

#include <string.h>

/* list_blocks lists some 80 arrays: room for a few more */
#define MAX_BLOCKS 96

struct tb_snapshot {
    tb_world world;        /* the world's struct; its arrays are this snapshot's blocks */
    tb__contacts contacts; /* the contacts' struct; zero when world.contacts is NULL */
    int roomy;             /* a new block holds the world's whole capacity, so the
                              guard's snapshot is taken again into the same memory
                              until an array grows; otherwise what is used */
    int partial;           /* the guard's: arrays no step writes are not copied */
    int has_contacts;      /* the world had a contacts struct */
    int valid;             /* holds a whole take (0: the last one ran out of memory) */
    size_t held[MAX_BLOCKS]; /* bytes allocated for each block (list_blocks' order) */
};

/* One array of a world (or of a snapshot's copy of one). */
typedef struct block {
    void **at;             /* where the struct keeps its pointer */
    size_t used;           /* bytes the next step or a query may read */
    size_t size;           /* bytes the world allocates for it */
    int steady;            /* no step writes it (constants, ids, shapes) */
} block;

static void add(block *b, size_t *n, void *at, size_t used, size_t size, int steady)
{
    b[*n].at = (void **)at;
    b[*n].used = used;
    b[*n].size = size;
    b[*n].steady = steady;
    ++*n;
}

/* An id table's three arrays: slot and generation per id handed out,
   owner per live slot (fewer than the ids handed out). */
static void ids_blocks(block *b, size_t *n, tb__ids *ids)
{
    const size_t used = ids->used * sizeof(uint32_t), size = ids->capacity * sizeof(uint32_t);
    add(b, n, &ids->slot, used, size, 1);
    add(b, n, &ids->generation, used, size, 1);
    add(b, n, &ids->owner, used, size, 1);
}

static void list_blocks_of(block *b, size_t *n, tb__list *list)
{
    add(b, n, &list->items, list->count * list->item_size, list->cap * list->item_size, 1);
    ids_blocks(b, n, &list->ids);
}

/* Every array of world w and contacts c (a zeroed struct when the world
   has none), in a fixed order. Left out, because every step writes them
   before it reads them and a restore keeps the world's own:
   - w->scratch, the integrators' vectors (each method fills what it uses);
   - w->joint_work, the joints' rows and factor (every evaluation and
     projection sets them up before reading them);
   - c's per-step solver room: order_scratch (the key sort's), park_index
     (park's), island_scratch (sleep.c) and the soft step's rows, bodies
     and patches (set_up_rows). The soft rows also point into the
     entries, which a copy could not keep.
   The previous entries are listed, but with nothing used once solved. */
static size_t list_blocks(tb_world *w, tb__contacts *c, block *b)
{
    const size_t np = w->particle_count, pc = w->particle_cap;
    const size_t ns = w->spring_count, sc = w->spring_cap;
    const size_t nb = w->body_count, bc = w->body_cap;
    const size_t nx = c->proxy_count, xc = c->proxy_cap;
    /* the entries before last step's: once a step has solved its contacts,
       the next one's tb__contacts_prepare makes its own entries the
       previous ones before it reads any, so these are dead (their arrays
       are kept, not their contents); a step that never solved keeps them */
    const size_t previous = c->solved ? 0 : c->previous_count;
    size_t n = 0;
    int k;
    add(b, &n, &w->y, w->y_size * sizeof(double), w->y_size * sizeof(double), 0);
    add(b, &n, &w->particle_mass, np * sizeof(double), pc * sizeof(double), 1);
    add(b, &n, &w->particle_inv_mass, np * sizeof(double), pc * sizeof(double), 1);
    add(b, &n, &w->particle_force, 3 * np * sizeof(double), 3 * pc * sizeof(double), 0);
    ids_blocks(b, &n, &w->tracer_ids);
    ids_blocks(b, &n, &w->particle_ids);
    add(b, &n, &w->spring_a, ns * sizeof(uint32_t), sc * sizeof(uint32_t), 1);
    add(b, &n, &w->spring_b, ns * sizeof(uint32_t), sc * sizeof(uint32_t), 1);
    add(b, &n, &w->spring_anchor, 3 * ns * sizeof(double), 3 * sc * sizeof(double), 1);
    add(b, &n, &w->spring_k, ns * sizeof(double), sc * sizeof(double), 1);
    add(b, &n, &w->spring_c, ns * sizeof(double), sc * sizeof(double), 1);
    add(b, &n, &w->spring_rest, ns * sizeof(double), sc * sizeof(double), 1);
    ids_blocks(b, &n, &w->spring_ids);
    add(b, &n, &w->body_mass, nb * sizeof(double), bc * sizeof(double), 1);
    add(b, &n, &w->body_inv_mass, nb * sizeof(double), bc * sizeof(double), 1);
    add(b, &n, &w->body_inertia, 3 * nb * sizeof(double), 3 * bc * sizeof(double), 1);
    add(b, &n, &w->body_inv_inertia, 3 * nb * sizeof(double), 3 * bc * sizeof(double), 1);
    add(b, &n, &w->body_damping, 2 * nb * sizeof(double), 2 * bc * sizeof(double), 1);
    add(b, &n, &w->body_applied, 6 * nb * sizeof(double), 6 * bc * sizeof(double), 0);
    add(b, &n, &w->body_force, 6 * nb * sizeof(double), 6 * bc * sizeof(double), 0);
    add(b, &n, &w->body_motion, 6 * nb * sizeof(double), 6 * bc * sizeof(double), 0);
    add(b, &n, &w->body_frame, nb * sizeof(tb__split_frame), bc * sizeof(tb__split_frame), 1);
    for (k = 0; k < 4; ++k)
        add(b, &n, &w->body_lane_frame[k], nb * sizeof(double), bc * sizeof(double), 1);
    add(b, &n, &w->body_rest, nb * sizeof(double), bc * sizeof(double), 0);
    add(b, &n, &w->body_island, nb * sizeof(uint32_t), bc * sizeof(uint32_t), 0);
    ids_blocks(b, &n, &w->body_ids);
    list_blocks_of(b, &n, &w->fields);
    list_blocks_of(b, &n, &w->forces);
    {
        const size_t nj = w->joint_count, jc = w->joint_cap;
        add(b, &n, &w->joint_type, nj * sizeof(uint32_t), jc * sizeof(uint32_t), 1);
        add(b, &n, &w->joint_body, 2 * nj * sizeof(uint32_t), 2 * jc * sizeof(uint32_t), 1);
        add(b, &n, &w->joint_anchor, 6 * nj * sizeof(double), 6 * jc * sizeof(double), 1);
        add(b, &n, &w->joint_frame, 18 * nj * sizeof(double), 18 * jc * sizeof(double), 1);
        add(b, &n, &w->joint_length, nj * sizeof(double), jc * sizeof(double), 1);
        add(b, &n, &w->joint_reaction, 6 * nj * sizeof(double), 6 * jc * sizeof(double), 0);
        add(b, &n, &w->joint_flags, nj * sizeof(uint32_t), jc * sizeof(uint32_t), 1);
        add(b, &n, &w->joint_drive, TB__DRIVES * nj * sizeof(double), TB__DRIVES * jc * sizeof(double), 1);
        add(b, &n, &w->joint_warm, TB__JOINT_ROWS * nj * sizeof(double), TB__JOINT_ROWS * jc * sizeof(double), 0);
        ids_blocks(b, &n, &w->joint_ids);
    }

    add(b, &n, &c->shapes, c->shape_count * sizeof(tb__shape), c->shape_cap * sizeof(tb__shape), 1);
    ids_blocks(b, &n, &c->ids);
    add(b, &n, &c->sap.order, c->sap.count * sizeof(uint32_t), c->sap.cap * sizeof(uint32_t), 0);
    add(b, &n, &c->lo, 3 * nx * sizeof(double), 3 * xc * sizeof(double), 0);
    add(b, &n, &c->hi, 3 * nx * sizeof(double), 3 * xc * sizeof(double), 0);
    add(b, &n, &c->category, nx * sizeof(uint32_t), xc * sizeof(uint32_t), 0);
    add(b, &n, &c->mask, nx * sizeof(uint32_t), xc * sizeof(uint32_t), 0);
    add(b, &n, &c->group, nx * sizeof(uint32_t), xc * sizeof(uint32_t), 0);
    add(b, &n, &c->proxy, nx * sizeof(uint32_t), xc * sizeof(uint32_t), 0);
    add(b, &n, &c->margin, nx * sizeof(double), xc * sizeof(double), 0);
    add(b, &n, &c->owner, nx * sizeof(uint32_t), xc * sizeof(uint32_t), 0);
    add(b, &n, &c->still, nx * sizeof(uint32_t), xc * sizeof(uint32_t), 0);
    add(b, &n, &c->geoms, nx * sizeof(tb__geom), xc * sizeof(tb__geom), 0);
    add(b, &n, &c->pairs, c->pair_count * sizeof(tb__pair), c->pair_cap * sizeof(tb__pair), 0);
    add(b, &n, &c->entries, c->entry_count * sizeof(tb__entry), c->entry_cap * sizeof(tb__entry), 0);
    add(b, &n, &c->previous, previous * sizeof(tb__entry), c->previous_cap * sizeof(tb__entry), 0);
    add(b, &n, &c->parked, c->parked_count * sizeof(tb__entry), c->parked_cap * sizeof(tb__entry), 0);
    add(b, &n, &c->order, c->entry_count * sizeof(tb__key), c->order_cap * sizeof(tb__key), 0);
    add(b, &n, &c->previous_order, previous * sizeof(tb__key), c->previous_order_cap * sizeof(tb__key), 0);
    add(b, &n, &c->starts, c->starts_count * sizeof(uint32_t), c->starts_cap * sizeof(uint32_t), 0);
    add(b, &n, &c->previous_starts, (c->solved ? 0 : c->previous_starts_count) * sizeof(uint32_t),
        c->previous_starts_cap * sizeof(uint32_t), 0);
    add(b, &n, &c->bodies, c->body_count * sizeof(tb__solver_body), c->body_cap * sizeof(tb__solver_body), 0);
    add(b, &n, &c->body_map, c->body_map_cap * sizeof(int32_t), c->body_map_cap * sizeof(int32_t), 0);
    add(b, &n, &c->particle_map, c->particle_map_cap * sizeof(int32_t), c->particle_map_cap * sizeof(int32_t), 0);
    add(b, &n, &c->events, c->event_count * sizeof(tb_contact_event), c->event_cap * sizeof(tb_contact_event), 0);
    add(b, &n, &c->poses, c->pose_count * sizeof(tb__pose), c->pose_cap * sizeof(tb__pose), 0);
    return n;
}

/* The scratch that list_blocks leaves out moved from src to dst (its
   pointers, capacities, and no content: the counts that say what it holds
   are set to none). */
static void carry_scratch(tb__contacts *dst, const tb__contacts *src)
{
    dst->order_scratch = src->order_scratch, dst->order_scratch_cap = src->order_scratch_cap;
    dst->park_index = src->park_index, dst->park_index_cap = src->park_index_cap;
    dst->island_scratch = src->island_scratch, dst->island_scratch_cap = src->island_scratch_cap;
    dst->soft_rows = src->soft_rows, dst->soft_row_cap = src->soft_row_cap, dst->soft_row_count = 0;
    dst->soft_bodies = src->soft_bodies, dst->soft_body_cap = src->soft_body_cap;
    dst->soft_patches = src->soft_patches, dst->soft_patch_cap = src->soft_patch_cap, dst->soft_patch_count = 0;
    dst->wide_rows = src->wide_rows, dst->wide_row_cap = src->wide_row_cap;
    dst->wide_patches = src->wide_patches, dst->wide_patch_cap = src->wide_patch_cap;
    dst->stacks = src->stacks; /* stack_solve.c's: set up again every step */
    dst->soft_joints = src->soft_joints, dst->soft_joint_cap = src->soft_joint_cap, dst->soft_joint_count = 0;
    dst->joint_rows = src->joint_rows, dst->joint_row_cap = src->joint_row_cap, dst->joint_row_count = 0;
    dst->joint_groups = src->joint_groups, dst->joint_group_cap = src->joint_group_cap;
}

/* A snapshot's blocks: where it keeps each pointer, and the bytes it
   holds of what it copied (the sizes are the world's at the take). */
static size_t snapshot_blocks(tb_snapshot *s, block *b)
{
    const size_t n = list_blocks(&s->world, &s->contacts, b);
    size_t i;
    for (i = 0; i < n; ++i)
        if (s->partial && b[i].steady)
            b[i].used = 0;
    return n;
}

static void free_blocks(tb_snapshot *s)
{
    block b[MAX_BLOCKS];
    const size_t n = snapshot_blocks(s, b);
    size_t i;
    for (i = 0; i < n; ++i) {
        if (*b[i].at)
            tb__alloc(&s->world, *b[i].at, s->held[i], 0);
        *b[i].at = NULL;
        s->held[i] = 0;
    }
    s->valid = 0;
}

static void free_snapshot(tb_snapshot *s)
{
    tb_world owner;
    if (!s)
        return;
    free_blocks(s);
    owner.allocator = s->world.allocator;
    tb__alloc(&owner, s, sizeof *s, 0);
}

/* Copy world w into snapshot s, into the blocks of its last take where
   they are large enough (a roomy snapshot allocates a block at the
   world's capacity, an exact one at what it uses). Out of memory:
   TB_ERR_MEMORY, s left empty (valid 0), w untouched. */
static tb_status take(tb_world *w, tb_snapshot *s)
{
    static const tb__contacts none;
    block from[MAX_BLOCKS], had[MAX_BLOCKS], to[MAX_BLOCKS];
    void *kept[MAX_BLOCKS];
    size_t held[MAX_BLOCKS];
    size_t n, i;
    n = snapshot_blocks(s, had);
    for (i = 0; i < n; ++i) {
        kept[i] = *had[i].at;
        held[i] = s->held[i];
    }
    s->world = *w;
    s->world.rollback = NULL;
    s->world.retake = NULL;
    s->world.joint_work = NULL;
    s->world.scratch = NULL;
    s->world.scratch_count = 0;
    s->world.kick_seen = NULL;
    s->world.damping_sums = NULL;
    s->world.contacts = NULL;
    s->has_contacts = w->contacts != NULL;
    s->contacts = w->contacts ? *w->contacts : none;
    carry_scratch(&s->contacts, &none);
    n = snapshot_blocks(s, to);
    list_blocks(w, w->contacts ? w->contacts : (tb__contacts *)&none, from);
    for (i = 0; i < n; ++i) {
        *to[i].at = NULL;
        s->held[i] = 0;
    }
    for (i = 0; i < n; ++i) {
        void *p = kept[i];
        size_t size = held[i];
        if (p && size < to[i].used) {
            tb__alloc(w, p, size, 0);
            p = NULL;
        }
        kept[i] = NULL;
        if (!p && to[i].used) {
            size = s->roomy ? to[i].size : to[i].used;
            if (!(p = tb__alloc(w, NULL, 0, size))) {
                size_t j;
                for (j = i + 1; j < n; ++j) /* what remains of the last take */
                    if (kept[j])
                        tb__alloc(w, kept[j], held[j], 0);
                free_blocks(s);
                return tb__fail(w, TB_ERR_MEMORY, "out of memory for a snapshot (%zu bytes)", size);
            }
        }
        *to[i].at = p;
        s->held[i] = p ? size : 0;
        if (to[i].used)
            memcpy(p, *from[i].at, to[i].used);
    }
    s->valid = 1;
    return TB_OK;
}

static tb_snapshot *new_snapshot(tb_world *w)
{
    tb_snapshot *s = tb__alloc(w, NULL, 0, sizeof *s);
    if (s) {
        memset(s, 0, sizeof *s);
        s->world.allocator = w->allocator;
    }
    return s;
}

/* Restore snapshot s into w, all or nothing. */
static tb_status restore(tb_world *w, const tb_snapshot *s)
{
    static const tb__contacts none;
    tb_snapshot *src = (tb_snapshot *)s; /* list_blocks takes the struct to point into; s is only read */
    block have[MAX_BLOCKS], want[MAX_BLOCKS], put[MAX_BLOCKS];
    void *fresh[MAX_BLOCKS];
    tb__contacts *c = w->contacts, *made = NULL;
    tb_world nw;
    tb__contacts nc;
    size_t n, i;
    n = snapshot_blocks(src, want);
    list_blocks(w, c ? c : (tb__contacts *)&none, have);
    /* everything that can fail first: the arrays whose size differs */
    memset(fresh, 0, sizeof fresh);
    if (s->has_contacts && !c) {
        made = tb__alloc(w, NULL, 0, sizeof *made);
        if (!made)
            return tb__fail(w, TB_ERR_MEMORY, "out of memory restoring a snapshot");
        memset(made, 0, sizeof *made);
    }
    {
        /* the world's arrays take the snapshot's capacities (its struct's
           counts and caps come back whole) */
        block cap[MAX_BLOCKS];
        tb_world tw = s->world;
        tb__contacts tc = s->contacts;
        list_blocks(&tw, &tc, cap);
        for (i = 0; i < n; ++i) {
            if (s->partial && want[i].steady)
                continue;
            if (cap[i].size && !(*have[i].at && have[i].size == cap[i].size)) {
                fresh[i] = tb__alloc(w, NULL, 0, cap[i].size);
                if (!fresh[i]) {
                    size_t j;
                    for (j = 0; j < i; ++j)
                        if (fresh[j])
                            tb__alloc(w, fresh[j], cap[j].size, 0);
                    if (made)
                        tb__alloc(w, made, sizeof *made, 0);
                    return tb__fail(w, TB_ERR_MEMORY, "out of memory restoring a snapshot (%zu bytes)",
                                    cap[i].size);
                }
            }
        }
        /* nothing fails from here */
        if (!s->has_contacts && c) {
            tb__contacts_free(w); /* frees every array of it, listed or not */
            c = NULL;
            list_blocks(w, (tb__contacts *)&none, have);
        }
        nw = s->world;
        nc = s->contacts;
        list_blocks(&nw, &nc, put);
        for (i = 0; i < n; ++i) {
            void *p;
            if (s->partial && want[i].steady) {
                p = *have[i].at; /* the same size: no step resizes it */
            } else if (fresh[i]) {
                if (*have[i].at && *have[i].at != (void *)tb__empty_state)
                    tb__alloc(w, *have[i].at, have[i].size, 0);
                p = fresh[i];
            } else if (cap[i].size) {
                p = *have[i].at;
            } else {
                if (*have[i].at && *have[i].at != (void *)tb__empty_state)
                    tb__alloc(w, *have[i].at, have[i].size, 0);
                p = NULL;
            }
            if (p && want[i].used)
                memcpy(p, *want[i].at, want[i].used);
            *put[i].at = p;
        }
    }
    /* what is the world's own, not the snapshot's */
    nw.allocator = w->allocator;
    memcpy(nw.message, w->message, sizeof nw.message);
    nw.stepping = 0;
    nw.rollback = w->rollback;
    nw.retake = w->retake;
    nw.joint_work = w->joint_work;
    nw.kick_seen = NULL; /* between steps it is always NULL (integrators.c clears it) */
    nw.damping_sums = NULL; /* and so is this (step.c) */
    if (!nw.y)
        nw.y = tb__empty_state; /* an empty state (core.h) */
    if (nw.y_size == w->y_size) {
        nw.scratch = w->scratch;
        nw.scratch_count = w->scratch_count;
    } else {
        if (w->scratch && w->scratch != tb__empty_state)
            tb__alloc(w, w->scratch, w->scratch_count * w->y_size * sizeof(double), 0);
        nw.scratch = tb__empty_state;
        nw.scratch_count = 0;
    }
    if (s->has_contacts) {
        tb__contacts *into = c ? c : made;
        carry_scratch(&nc, c ? c : &none);
        *into = nc;
        nw.contacts = into;
    } else {
        nw.contacts = NULL;
    }
    *w = nw;
    return TB_OK;
}

/* ---- the public API ---------------------------------------------------------- */

tb_status tb_world_snapshot(tb_world *w, tb_snapshot **out)
{
    tb_snapshot *s;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if (!out)
        return tb__null(w, "tb_world_snapshot", "out");
    *out = NULL;
    if ((st = tb__check_busy(w, "take a snapshot")) != TB_OK)
        return st;
    if (!(s = new_snapshot(w)))
        return tb__fail(w, TB_ERR_MEMORY, "out of memory for a snapshot");
    if ((st = take(w, s)) != TB_OK) {
        free_snapshot(s);
        return st;
    }
    *out = s;
    return TB_OK;
}

tb_status tb_world_restore(tb_world *w, const tb_snapshot *s)
{
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if (!s)
        return tb__null(w, "tb_world_restore", "snapshot");
    if ((st = tb__check_busy(w, "restore a snapshot")) != TB_OK)
        return st;
    if (s->world.id_tag != w->id_tag)
        return tb__fail(w, TB_ERR_ARGUMENT, "the snapshot was taken of another world");
    if (!s->valid)
        return tb__fail(w, TB_ERR_ARGUMENT, "the snapshot is empty: taking it again ran out of memory");
    return restore(w, s);
}

tb_status tb_world_snapshot_into(tb_world *w, tb_snapshot *s)
{
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if (!s)
        return tb__null(w, "tb_world_snapshot_into", "snapshot");
    if ((st = tb__check_busy(w, "take a snapshot")) != TB_OK)
        return st;
    if (s->world.id_tag != w->id_tag || s->partial)
        return tb__fail(w, TB_ERR_ARGUMENT, "the snapshot was taken of another world");
    return take(w, s);
}

void tb_snapshot_destroy(tb_snapshot *s)
{
    free_snapshot(s);
}

size_t tb_snapshot_size(const tb_snapshot *s)
{
    block b[MAX_BLOCKS];
    size_t n, i, bytes;
    if (!s)
        return 0;
    n = snapshot_blocks((tb_snapshot *)s, b);
    bytes = sizeof *s;
    for (i = 0; i < n; ++i)
        bytes += s->held[i];
    return bytes;
}

double tb_snapshot_time(const tb_snapshot *s)
{
    return s ? s->world.time : 0;
}

/* ---- the guard's rollback ------------------------------------------------------ */

/* A snapshot kept in *slot and taken again into the same memory: of what
   a step writes only */
static tb_status keep_in(tb_world *w, tb_snapshot **slot, const char *whose)
{
    if (!*slot) {
        if (!(*slot = new_snapshot(w)))
            return tb__fail(w, TB_ERR_MEMORY, "out of memory for %s", whose);
        (*slot)->roomy = 1;
        (*slot)->partial = 1;
    }
    return take(w, *slot);
}

tb_status tb__rollback_keep(tb_world *w)
{
    return keep_in(w, &w->rollback, "the guard's snapshot");
}

const double *tb__rollback_state(const tb_world *w)
{
    return w->rollback->world.y;
}

tb_status tb__rollback(tb_world *w)
{
    /* allocates only for an array the refused step grew (contacts found),
       to give it back its old capacity */
    return restore(w, w->rollback);
}

void tb__rollback_free(tb_world *w)
{
    free_snapshot(w->rollback);
    w->rollback = NULL;
}

/* ---- a step taken again in halves (step.c) -------------------------------------- */

tb_status tb__retake_keep(tb_world *w)
{
    return keep_in(w, &w->retake, "a step's retake");
}

tb_status tb__retake(tb_world *w)
{
    return restore(w, w->retake);
}

void tb__retake_free(tb_world *w)
{
    free_snapshot(w->retake);
    w->retake = NULL;
}

/* ---- the state hash -------------------------------------------------------------- */

#define FNV_OFFSET 14695981039346656037ull
#define FNV_PRIME 1099511628211ull

static uint64_t mix(uint64_t h, const void *data, size_t n)
{
    const unsigned char *p = data;
    size_t i;
    for (i = 0; i < n; ++i) {
        h ^= p[i];
        h *= FNV_PRIME;
    }
    return h;
}

static uint64_t mix_u64(uint64_t h, uint64_t v)
{
    unsigned char b[8];
    int i;
    for (i = 0; i < 8; ++i) /* little-endian, whatever the machine's order */
        b[i] = (unsigned char)(v >> (8 * i));
    return mix(h, b, 8);
}

static uint64_t mix_doubles(uint64_t h, const double *v, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        uint64_t bits;
        memcpy(&bits, &v[i], sizeof bits);
        h = mix_u64(h, bits);
    }
    return h;
}

static const size_t widths[TB__QUANTITY_COUNT] = {
#define TB__WIDTH(name, tier, width) width,
    TB__QUANTITIES(TB__WIDTH)
#undef TB__WIDTH
};
static const enum tb__tier tiers[TB__QUANTITY_COUNT] = {
#define TB__TIER(name, tier, width) tier,
    TB__QUANTITIES(TB__TIER)
#undef TB__TIER
};

uint64_t tb_world_hash(const tb_world *w)
{
    uint64_t h = FNV_OFFSET;
    size_t counts[TB__TIERS], i, k;
    int q;
    TB__NEED_WORLD(w, 0);
    counts[0] = w->tracer_count, counts[1] = w->particle_count, counts[2] = w->body_count;
    h = mix_u64(h, counts[0]);
    h = mix_u64(h, counts[1]);
    h = mix_u64(h, counts[2]);
    h = mix_u64(h, w->spring_count);
    h = mix_u64(h, w->steps);
    h = mix_doubles(h, &w->time, 1);
    h = mix_doubles(h, &w->time_carry, 1);
    for (q = 0; q < TB__QUANTITY_COUNT && w->y; ++q)
        h = mix_doubles(h, w->y + w->off[q], widths[q] * counts[tiers[q]]);
    h = mix_doubles(h, w->body_rest, w->body_count);
    for (i = 0; i < w->body_count; ++i)
        h = mix_u64(h, w->body_island[i]);
    h = mix_u64(h, w->body_sleeping);
    if (w->joint_count) { /* (worlds without joints keep the hashes they had) */
        h = mix_u64(h, w->joint_count);
        h = mix_u64(h, (uint64_t)w->joints_unmet); /* (whether the next step may be halved) */
        h = mix_doubles(h, w->joint_reaction, 6 * w->joint_count);
        h = mix_doubles(h, w->joint_warm, TB__JOINT_ROWS * w->joint_count);
    }
    if (w->contacts) {
        const tb__contacts *c = w->contacts;
        size_t j = 0;
        h = mix_u64(h, c->shape_count);
        h = mix_u64(h, c->entry_count + c->parked_count);
        h = mix_u64(h, c->next_island);
        h = mix_doubles(h, &c->kept_h, 1);
        /* the step's entries and the parked ones (contact.c), merged in the
           order the step found them (tb__entry.found): the entries a step
           would have if it carried the sleeping pairs over */
        for (i = 0; i < c->entry_count || j < c->parked_count;) {
            const tb__entry *e = j < c->parked_count && (i == c->entry_count || c->parked[j].found < c->entries[i].found)
                                     ? &c->parked[j++]
                                     : &c->entries[i++];
            h = mix_u64(h, (uint64_t)e->key_a << 32 | e->key_b);
            h = mix_u64(h, (uint64_t)(uint32_t)e->count << 32 | (uint32_t)e->touching);
            h = mix_u64(h, (uint64_t)(uint32_t)e->asleep << 32 | (uint32_t)e->struck);
            h = mix_doubles(h, e->friction_impulse, 3);
            h = mix_doubles(h, &e->twist_impulse, 1);
            h = mix_doubles(h, e->rolling_impulse, 3);
            for (k = 0; k < (size_t)e->count && k < TB__MANIFOLD_POINTS; ++k) {
                const tb__point *p = &e->point[k];
                h = mix_u64(h, p->feature);
                h = mix_doubles(h, &p->normal_impulse, 1);
            }
        }
    }
    return h;
}
