/* tumble_lua.c: the Lua 5.4 module `tumble`, over the public C API only.

   Types are full userdata with locked metatables: tumble.world owns a
   tb_world; tumble.particle, tumble.tracer, tumble.spring, tumble.body,
   tumble.shape, tumble.field and tumble.force are handles holding a value
   id and, as user value, their world (so a handle keeps its world alive and
   every call checks the id). tumble.snapshot owns a tb_snapshot, freed when
   it is collected, with its world as user value.

   The world's user value is a table holding its Lua callbacks under
   integer keys and the tables handed to them (reused from call to call);
   what the core holds for each callback (tl_callback) is C memory owned by
   the world, so no script, not even with the debug library, can free it
   under the core. Callbacks run under lua_pcall with a traceback handler
   inside a protected C function, so no Lua error ever unwinds through the
   core. While a world steps it is anchored in the registry, so neither the
   collector nor a rewritten stack slot can take it away mid-step.

   The second half of the file holds what a host needs to run scripts it
   does not trust: budgets (tb_lua_newstate: an allocator that counts, a
   count hook that re-arms itself) and the sandbox (tb_lua_sandbox).

   Names: Lua reserves the lua_ and luaL_ prefixes, so the binding's types
   are tl_*. Static functions carry no prefix: a function Lua calls is named
   after its Lua name (module_world for tumble.world, world_step for
   world:step, body_pos for body:pos, handle_* for what every handle has,
   world_gc for a metamethod); every other function starts with a verb
   (check_ raises unless the value is valid, read_ requires a value, opt_
   takes one if present, push_ leaves one on the Lua stack, to_ converts).
   The same rule holds in tumble_main.c. */
#if !defined(_WIN32)
#define _XOPEN_SOURCE 700 /* realpath */
#endif
#include "tumble_lua.h"

#include <errno.h>
#include <lauxlib.h>
#include <lualib.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define WORLD_MT "tumble.world"
#define SNAPSHOT_MT "tumble.snapshot"

enum tl_handle_kind { H_PARTICLE, H_TRACER, H_SPRING, H_FIELD, H_FORCE, H_BODY, H_SHAPE, H_JOINT, H_KINDS };
static const char *const handle_mt[H_KINDS] = {
    "tumble.particle", "tumble.tracer", "tumble.spring", "tumble.field", "tumble.force", "tumble.body",
    "tumble.shape", "tumble.joint"
};

typedef struct tl_callback tl_callback;

typedef struct tl_world {
    const char *tag;  /* &world_tag */
    tb_world *world;  /* NULL once closed */
    double dt;        /* default step, s */
    lua_State *L;     /* while tb_lua_step runs: the thread stepping */
    int next_key;     /* next callback key in the user value table */
    tl_callback *callbacks; /* what the core holds for each Lua callback */
    lua_Alloc alloc;  /* the state's allocator, which made them */
    void *alloc_ud;
    int keeps_callbacks; /* a snapshot was taken: callbacks live until the
                            world closes (forget_callback) */
    const tb_force_args *force_args; /* while a Lua force runs: what its
                            state table's arrays are filled from (read_state) */
    size_t zeroed[3];    /* leading entries of the forces, body forces and
                            body torques tables known to be 0 (run_force) */
    double *masses;      /* [mass_cap] the particle masses the kept s.mass
                            table holds (read_masses): mass_count of them */
    size_t mass_cap, mass_count;
} tl_world;

typedef struct tl_handle {
    const char *tag;  /* &handle_tag */
    int kind;
    uint32_t index1, generation;
    int key;          /* fields and forces written in Lua: their callback key */
} tl_handle;

/* What a C callback needs to find its Lua function (the world's user value
   table at `key`). Allocated with the state's allocator and listed in its
   world, which frees it when the callback is removed or the world closes. */
struct tl_callback {
    tl_world *owner;
    int key;
    tl_callback *next;
};

/* The debug library can give any userdata a tumble metatable: a world and
   a handle are known by their metatable, their size and this tag. */
static const char world_tag = 'w', handle_tag = 'h';

/* Registry key of the anchor table: light userdata tl_world* -> false, or
   the world's userdata while it steps. The key exists from the world's
   creation, so anchoring it at a step sets a value and allocates nothing. */
static const char anchor_key = 0;

/* The budgets' allocator (below): the world's memory goes through it too. */
static void *allocate_counted(void *ud, void *ptr, size_t osize, size_t nsize);
static void *allocate_for_world(void *ud, void *ptr, size_t osize, size_t nsize);

/* ------------------------------------------------------------ helpers -- */

static int add_traceback(lua_State *L)
{
    const char *msg = lua_tostring(L, 1);
    if (!msg) {
        if (luaL_callmeta(L, 1, "__tostring") && lua_type(L, -1) == LUA_TSTRING)
            msg = lua_tostring(L, -1);
        else
            msg = lua_pushfstring(L, "(error object is a %s value)", luaL_typename(L, 1));
    }
    luaL_traceback(L, L, msg, 1);
    return 1;
}

/* Copy the first line of s into a message buffer. */
static void copy_first_line(char *out, size_t size, const char *s)
{
    size_t n = strcspn(s ? s : "", "\n");
    if (n >= size)
        n = size - 1;
    memcpy(out, s ? s : "", n);
    out[n] = 0;
}

/* The world userdata at idx, open or closed, or NULL. */
static tl_world *test_world(lua_State *L, int idx)
{
    tl_world *lw = luaL_testudata(L, idx, WORLD_MT);
    return lw && lua_rawlen(L, idx) == sizeof *lw && lw->tag == &world_tag ? lw : NULL;
}

/* The same, raising unless idx holds one. */
static tl_world *check_world_userdata(lua_State *L, int idx)
{
    tl_world *lw = test_world(L, idx);
    if (!lw)
        luaL_typeerror(L, idx, WORLD_MT);
    return lw;
}

static tl_world *check_world(lua_State *L, int idx)
{
    tl_world *lw = check_world_userdata(L, idx);
    if (!lw->world)
        luaL_error(L, "tumble: the world is closed");
    return lw;
}

static int raise_world_error(lua_State *L, tl_world *lw, const char *fname)
{
    return luaL_error(L, "%s: %s", fname, tb_world_message(lw->world));
}

static void check_options(lua_State *L, int idx, const char *fname, const char *const known[])
{
    luaL_checktype(L, idx, LUA_TTABLE);
    lua_pushnil(L);
    while (lua_next(L, idx)) {
        int i, ok = 0;
        lua_pop(L, 1);
        if (lua_type(L, -1) == LUA_TSTRING)
            for (i = 0; known[i] && !ok; ++i)
                ok = strcmp(known[i], lua_tostring(L, -1)) == 0;
        if (!ok) {
            luaL_Buffer b;
            luaL_buffinit(L, &b);
            for (i = 0; known[i]; ++i) {
                if (i)
                    luaL_addstring(&b, ", ");
                luaL_addstring(&b, known[i]);
            }
            luaL_pushresult(&b);
            luaL_error(L, "%s: unknown option '%s' (known: %s)", fname,
                       lua_type(L, -2) == LUA_TSTRING ? lua_tostring(L, -2) : luaL_typename(L, -2),
                       lua_tostring(L, -1));
        }
    }
}

/* A {x, y, z} table at idx into out. */
static void read_vec3(lua_State *L, int idx, const char *fname, const char *what, double out[3])
{
    int i;
    if (lua_type(L, idx) != LUA_TTABLE)
        luaL_error(L, "%s: '%s' must be a table {x, y, z} (got %s)", fname, what, luaL_typename(L, idx));
    for (i = 0; i < 3; ++i) {
        int isnum;
        lua_rawgeti(L, idx, i + 1);
        out[i] = lua_tonumberx(L, -1, &isnum);
        if (!isnum)
            luaL_error(L, "%s: '%s' must be a table {x, y, z} of numbers (element %d is %s)", fname, what,
                       i + 1, luaL_typename(L, -1));
        lua_pop(L, 1);
    }
}

/* Optional field `key` of the table at idx: a vector, if present. */
static int opt_vec3(lua_State *L, int idx, const char *key, const char *fname, double out[3])
{
    int present = lua_getfield(L, idx, key) != LUA_TNIL;
    if (present)
        read_vec3(L, lua_gettop(L), fname, key, out);
    lua_pop(L, 1);
    return present;
}

static int opt_number(lua_State *L, int idx, const char *key, const char *fname, double *out)
{
    int present = lua_getfield(L, idx, key) != LUA_TNIL;
    if (present) {
        int isnum;
        *out = lua_tonumberx(L, -1, &isnum);
        if (!isnum)
            luaL_error(L, "%s: '%s' must be a number (got %s)", fname, key, luaL_typename(L, -1));
    }
    lua_pop(L, 1);
    return present;
}

/* Three numbers at idx, or one {x, y, z} table. */
static void read_vec3_args(lua_State *L, int idx, const char *fname, double out[3])
{
    if (lua_type(L, idx) == LUA_TTABLE) {
        read_vec3(L, idx, fname, "argument", out);
    } else {
        out[0] = luaL_checknumber(L, idx);
        out[1] = luaL_checknumber(L, idx + 1);
        out[2] = luaL_checknumber(L, idx + 2);
    }
}

static int push_vec3(lua_State *L, const double v[3])
{
    lua_pushnumber(L, v[0]);
    lua_pushnumber(L, v[1]);
    lua_pushnumber(L, v[2]);
    return 3;
}

static void push_vec3_table(lua_State *L, const double v[3])
{
    int k;
    lua_createtable(L, 3, 0);
    for (k = 0; k < 3; ++k) {
        lua_pushnumber(L, v[k]);
        lua_rawseti(L, -2, k + 1);
    }
}

/* ------------------------------------------------------------ handles -- */

static void push_handle(lua_State *L, int world_idx, int kind, uint32_t index1, uint32_t generation, int key)
{
    tl_handle *h;
    world_idx = lua_absindex(L, world_idx);
    h = lua_newuserdatauv(L, sizeof *h, 1);
    h->tag = &handle_tag;
    h->kind = kind;
    h->index1 = index1;
    h->generation = generation;
    h->key = key;
    lua_pushvalue(L, world_idx);
    lua_setiuservalue(L, -2, 1);
    luaL_setmetatable(L, handle_mt[kind]);
}

/* The handle of `kind` at idx, or NULL. */
static tl_handle *test_handle(lua_State *L, int idx, int kind)
{
    tl_handle *h = luaL_testudata(L, idx, handle_mt[kind]);
    return h && lua_rawlen(L, idx) == sizeof *h && h->tag == &handle_tag && h->kind == kind ? h : NULL;
}

/* The handle at idx (of `kind`) and its open world. */
static tl_handle *check_handle(lua_State *L, int idx, int kind, tl_world **lw)
{
    tl_handle *h = test_handle(L, idx, kind);
    if (!h)
        luaL_typeerror(L, idx, handle_mt[kind]);
    lua_getiuservalue(L, idx, 1);
    *lw = test_world(L, -1); /* the debug library can replace it */
    lua_pop(L, 1);
    if (!*lw || !(*lw)->world)
        luaL_error(L, "%s: its world is closed", handle_mt[kind]);
    return h;
}

static tb_particle_id to_particle_id(const tl_handle *h)
{
    tb_particle_id id;
    id.index1 = h->index1;
    id.generation = h->generation;
    return id;
}

static tb_tracer_id to_tracer_id(const tl_handle *h)
{
    tb_tracer_id id;
    id.index1 = h->index1;
    id.generation = h->generation;
    return id;
}

static int get_particle_vec3(lua_State *L, tb_status (*get)(const tb_world *, tb_particle_id, double[3]),
                        const char *fname)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_PARTICLE, &lw);
    double v[3];
    if (get(lw->world, to_particle_id(h), v) != TB_OK)
        return raise_world_error(L, lw, fname);
    return push_vec3(L, v);
}

static int set_particle_vec3(lua_State *L, tb_status (*set)(tb_world *, tb_particle_id, const double[3]),
                        const char *fname)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_PARTICLE, &lw);
    double v[3];
    read_vec3_args(L, 2, fname, v);
    if (set(lw->world, to_particle_id(h), v) != TB_OK)
        return raise_world_error(L, lw, fname);
    return 0;
}

static int particle_pos(lua_State *L) { return get_particle_vec3(L, tb_particle_position, "particle:pos"); }
static int particle_vel(lua_State *L) { return get_particle_vec3(L, tb_particle_velocity, "particle:vel"); }
static int particle_set_pos(lua_State *L) { return set_particle_vec3(L, tb_particle_set_position, "particle:set_pos"); }
static int particle_set_vel(lua_State *L) { return set_particle_vec3(L, tb_particle_set_velocity, "particle:set_vel"); }

static int particle_mass(lua_State *L)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_PARTICLE, &lw);
    double m;
    if (tb_particle_mass(lw->world, to_particle_id(h), &m) != TB_OK)
        return raise_world_error(L, lw, "particle:mass");
    lua_pushnumber(L, m);
    return 1;
}

static int tracer_pos(lua_State *L)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_TRACER, &lw);
    double v[3];
    if (tb_tracer_position(lw->world, to_tracer_id(h), v) != TB_OK)
        return raise_world_error(L, lw, "tracer:pos");
    return push_vec3(L, v);
}

static int tracer_set_pos(lua_State *L)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_TRACER, &lw);
    double v[3];
    read_vec3_args(L, 2, "tracer:set_pos", v);
    if (tb_tracer_set_position(lw->world, to_tracer_id(h), v) != TB_OK)
        return raise_world_error(L, lw, "tracer:set_pos");
    return 0;
}

static tb_body_id to_body_id(const tl_handle *h)
{
    tb_body_id id;
    id.index1 = h->index1;
    id.generation = h->generation;
    return id;
}

static int get_body_vec3(lua_State *L, tb_status (*get)(const tb_world *, tb_body_id, double[3]), const char *fname)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_BODY, &lw);
    double v[3];
    if (get(lw->world, to_body_id(h), v) != TB_OK)
        return raise_world_error(L, lw, fname);
    return push_vec3(L, v);
}

static int set_body_vec3(lua_State *L, tb_status (*set)(tb_world *, tb_body_id, const double[3]), const char *fname)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_BODY, &lw);
    double v[3];
    read_vec3_args(L, 2, fname, v);
    if (set(lw->world, to_body_id(h), v) != TB_OK)
        return raise_world_error(L, lw, fname);
    return 0;
}

static int body_pos(lua_State *L) { return get_body_vec3(L, tb_body_position, "body:pos"); }
static int body_vel(lua_State *L) { return get_body_vec3(L, tb_body_velocity, "body:vel"); }
static int body_omega(lua_State *L) { return get_body_vec3(L, tb_body_angular_velocity, "body:omega"); }
static int body_set_pos(lua_State *L) { return set_body_vec3(L, tb_body_set_position, "body:set_pos"); }
static int body_set_vel(lua_State *L) { return set_body_vec3(L, tb_body_set_velocity, "body:set_vel"); }
static int body_set_omega(lua_State *L) { return set_body_vec3(L, tb_body_set_angular_velocity, "body:set_omega"); }
static int body_torque(lua_State *L) { return set_body_vec3(L, tb_body_apply_torque, "body:torque"); }

/* body:asleep(): true while it sleeps; body:wake() */
static int body_asleep(lua_State *L)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_BODY, &lw);
    int asleep;
    if (tb_body_asleep(lw->world, to_body_id(h), &asleep) != TB_OK)
        return raise_world_error(L, lw, "body:asleep");
    lua_pushboolean(L, asleep);
    return 1;
}

static int body_wake(lua_State *L)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_BODY, &lw);
    if (tb_body_wake(lw->world, to_body_id(h)) != TB_OK)
        return raise_world_error(L, lw, "body:wake");
    return 0;
}

static int body_rot(lua_State *L)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_BODY, &lw);
    double q[4];
    int k;
    if (tb_body_orientation(lw->world, to_body_id(h), q) != TB_OK)
        return raise_world_error(L, lw, "body:rot");
    for (k = 0; k < 4; ++k)
        lua_pushnumber(L, q[k]);
    return 4;
}

static void read_quat(lua_State *L, int idx, const char *fname, double q[4])
{
    int k;
    if (lua_type(L, idx) != LUA_TTABLE)
        luaL_error(L, "%s: the orientation must be a table {w, x, y, z}", fname);
    for (k = 0; k < 4; ++k) {
        int isnum;
        lua_rawgeti(L, idx, k + 1);
        q[k] = lua_tonumberx(L, -1, &isnum);
        if (!isnum)
            luaL_error(L, "%s: the orientation must be a table {w, x, y, z} of numbers", fname);
        lua_pop(L, 1);
    }
}

static int body_set_rot(lua_State *L)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_BODY, &lw);
    double q[4];
    read_quat(L, 2, "body:set_rot", q);
    if (tb_body_set_orientation(lw->world, to_body_id(h), q) != TB_OK)
        return raise_world_error(L, lw, "body:set_rot");
    return 0;
}

static int body_momentum(lua_State *L)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_BODY, &lw);
    double p[3], l[3];
    if (tb_body_momentum(lw->world, to_body_id(h), p, l) != TB_OK)
        return raise_world_error(L, lw, "body:momentum");
    push_vec3(L, p);
    push_vec3(L, l);
    return 6;
}

static int body_mass(lua_State *L)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_BODY, &lw);
    double m, I[3];
    if (tb_body_mass(lw->world, to_body_id(h), &m, I) != TB_OK)
        return raise_world_error(L, lw, "body:mass");
    lua_pushnumber(L, m);
    return 1 + push_vec3(L, I);
}

/* body:push(force, point): a force (N, world) at a world point, held for the
   next step; body:push_local(force, body_point) takes the point in the
   body's principal frame. */
static int apply_body_force(lua_State *L, int local, const char *fname)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_BODY, &lw);
    double f[3], p[3];
    tb_status st;
    read_vec3(L, 2, fname, "force", f);
    read_vec3(L, 3, fname, "point", p);
    st = local ? tb_body_apply_force_at_body_point(lw->world, to_body_id(h), f, p)
               : tb_body_apply_force(lw->world, to_body_id(h), f, p);
    if (st != TB_OK)
        return raise_world_error(L, lw, fname);
    return 0;
}

static int body_push(lua_State *L) { return apply_body_force(L, 0, "body:push"); }
static int body_push_local(lua_State *L) { return apply_body_force(L, 1, "body:push_local"); }

/* Forget a Lua callback of the world at world_idx: its function and the
   record the core held. Once the world has taken a snapshot, a restore
   may bring back a force or field removed since, with its record as the
   core's user pointer: both then stay until the world closes
   (test_lua.snapshots_restore_and_hash). */
static void forget_callback(lua_State *L, int world_idx, tl_world *lw, int key)
{
    tl_callback **link = &lw->callbacks;
    if (lw->keeps_callbacks)
        return;
    while (*link && (*link)->key != key)
        link = &(*link)->next;
    if (*link) {
        tl_callback *cb = *link;
        *link = cb->next;
        lw->alloc(lw->alloc_ud, cb, sizeof *cb, 0);
    }
    if (lua_getiuservalue(L, world_idx, 1) == LUA_TTABLE) {
        lua_pushnil(L);
        lua_rawseti(L, -2, key);
    }
    lua_pop(L, 1);
}

/* Free every callback record of a world (when it closes), and the masses
   its forces' s.mass holds. */
static void free_callbacks(tl_world *lw)
{
    while (lw->callbacks) {
        tl_callback *cb = lw->callbacks;
        lw->callbacks = cb->next;
        lw->alloc(lw->alloc_ud, cb, sizeof *cb, 0);
    }
    if (lw->masses)
        lw->alloc(lw->alloc_ud, lw->masses, lw->mass_cap * sizeof *lw->masses, 0);
    lw->masses = NULL;
    lw->mass_cap = lw->mass_count = 0;
}

static int handle_remove(lua_State *L)
{
    tl_handle *h;
    int kind, k;
    tl_world *lw;
    tb_status st = TB_OK;
    for (kind = 0; kind < H_KINDS && !test_handle(L, 1, kind); ++kind)
        ;
    if (kind == H_KINDS)
        return luaL_typeerror(L, 1, "tumble handle");
    h = check_handle(L, 1, kind, &lw);
    k = h->kind;
    if (k == H_PARTICLE) {
        st = tb_world_remove_particle(lw->world, to_particle_id(h));
    } else if (k == H_TRACER) {
        st = tb_world_remove_tracer(lw->world, to_tracer_id(h));
    } else if (k == H_SPRING) {
        tb_spring_id id;
        id.index1 = h->index1;
        id.generation = h->generation;
        st = tb_world_remove_spring(lw->world, id);
    } else if (k == H_BODY) {
        st = tb_world_remove_body(lw->world, to_body_id(h));
    } else if (k == H_JOINT) {
        tb_joint_id id;
        id.index1 = h->index1;
        id.generation = h->generation;
        st = tb_world_remove_joint(lw->world, id);
    } else if (k == H_SHAPE) {
        tb_shape_id id;
        id.index1 = h->index1;
        id.generation = h->generation;
        st = tb_world_remove_shape(lw->world, id);
    } else if (k == H_FIELD) {
        tb_field_id id;
        id.index1 = h->index1;
        id.generation = h->generation;
        st = tb_world_remove_field(lw->world, id);
    } else {
        tb_force_id id;
        id.index1 = h->index1;
        id.generation = h->generation;
        st = tb_world_remove_force(lw->world, id);
    }
    if (st != TB_OK)
        return raise_world_error(L, lw, "remove");
    if (h->key) {
        lua_getiuservalue(L, 1, 1); /* the handle's world */
        forget_callback(L, lua_gettop(L), lw, h->key);
        lua_pop(L, 1);
    }
    return 0;
}

/* The handle of any kind at idx, or NULL. The metamethods check it too:
   the debug library can hand them any value. */
static tl_handle *to_handle(lua_State *L, int idx)
{
    tl_handle *h = NULL;
    int kind;
    for (kind = 0; kind < H_KINDS && !h; ++kind)
        h = test_handle(L, idx, kind);
    return h;
}

static int handle_id(lua_State *L)
{
    tl_handle *h = to_handle(L, 1);
    if (!h)
        return luaL_typeerror(L, 1, "tumble handle");
    lua_pushinteger(L, (lua_Integer)h->index1);
    lua_pushinteger(L, (lua_Integer)h->generation);
    return 2;
}

static int handle_tostring(lua_State *L)
{
    tl_handle *h = to_handle(L, 1);
    if (!h)
        return luaL_typeerror(L, 1, "tumble handle");
    lua_pushfstring(L, "%s %I.%I", handle_mt[h->kind], (lua_Integer)h->index1, (lua_Integer)h->generation);
    return 1;
}

static int handle_eq(lua_State *L)
{
    tl_handle *a = to_handle(L, 1), *b = to_handle(L, 2);
    if (!a || !b) {
        lua_pushboolean(L, 0);
        return 1;
    }
    lua_getiuservalue(L, 1, 1);
    lua_getiuservalue(L, 2, 1);
    lua_pushboolean(L, a->kind == b->kind && a->index1 == b->index1 && a->generation == b->generation &&
                           lua_rawequal(L, -1, -2));
    return 1;
}

static const luaL_Reg particle_methods[] = {
    { "pos", particle_pos }, { "vel", particle_vel }, { "mass", particle_mass },
    { "set_pos", particle_set_pos }, { "set_vel", particle_set_vel },
    { "remove", handle_remove }, { "id", handle_id }, { NULL, NULL }
};
static const luaL_Reg tracer_methods[] = {
    { "pos", tracer_pos }, { "set_pos", tracer_set_pos },
    { "remove", handle_remove }, { "id", handle_id }, { NULL, NULL }
};
static const luaL_Reg body_methods[] = {
    { "pos", body_pos }, { "rot", body_rot }, { "vel", body_vel }, { "omega", body_omega },
    { "momentum", body_momentum }, { "mass", body_mass },
    { "set_pos", body_set_pos }, { "set_rot", body_set_rot }, { "set_vel", body_set_vel },
    { "set_omega", body_set_omega }, { "push", body_push }, { "push_local", body_push_local },
    { "torque", body_torque }, { "asleep", body_asleep }, { "wake", body_wake },
    { "remove", handle_remove }, { "id", handle_id }, { NULL, NULL }
};
static const luaL_Reg plain_methods[] = {
    { "remove", handle_remove }, { "id", handle_id }, { NULL, NULL }
};

static tb_joint_id to_joint_id(const tl_handle *h)
{
    tb_joint_id id;
    id.index1 = h->index1;
    id.generation = h->generation;
    return id;
}

/* joint:reaction(): fx, fy, fz, tx, ty, tz, the force (N) and torque (N m,
   about the joint's anchor) on body a over the last step */
static int joint_reaction(lua_State *L)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_JOINT, &lw);
    double f[3], t[3];
    if (tb_joint_reaction(lw->world, to_joint_id(h), f, t) != TB_OK)
        return raise_world_error(L, lw, "joint:reaction");
    push_vec3(L, f);
    return push_vec3(L, t) + 3;
}

/* joint:error(): how far it is from holding (m, or a sine for axes) */
static int joint_error(lua_State *L)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_JOINT, &lw);
    double e;
    if (tb_joint_error(lw->world, to_joint_id(h), &e) != TB_OK)
        return raise_world_error(L, lw, "joint:error");
    lua_pushnumber(L, e);
    return 1;
}

/* joint:position(): the free coordinate (rad or m) and its rate
   (tb_joint_position) */
static int joint_position(lua_State *L)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_JOINT, &lw);
    double at, rate;
    if (tb_joint_position(lw->world, to_joint_id(h), &at, &rate) != TB_OK)
        return raise_world_error(L, lw, "joint:position");
    lua_pushnumber(L, at);
    lua_pushnumber(L, rate);
    return 2;
}

/* Argument i of a joint setter: a number */
static double setter_number(lua_State *L, int i, const char *fname)
{
    int isnum;
    const double v = lua_tonumberx(L, i, &isnum);
    if (!isnum)
        luaL_error(L, "%s: argument %d must be a number (got %s)", fname, i - 1, luaL_typename(L, i));
    return v;
}

/* A joint setter of two numbers, or nil for off: its name and the C call */
typedef tb_status joint_pair_setter(tb_world *world, tb_joint_id id, int enable, double first, double second);

static int set_joint_pair(lua_State *L, const char *fname, joint_pair_setter *set)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_JOINT, &lw);
    const int on = !lua_isnoneornil(L, 2);
    const double first = on ? setter_number(L, 2, fname) : 0;
    const double second = on ? setter_number(L, 3, fname) : 0;
    if (set(lw->world, to_joint_id(h), on, first, second) != TB_OK)
        return raise_world_error(L, lw, fname);
    return 0;
}

/* joint:set_limit(lower, upper) (a ball joint's cone: set_limit(0,
   angle)); joint:set_limit(nil): no limit */
static int joint_set_limit(lua_State *L)
{
    return set_joint_pair(L, "joint:set_limit", tb_joint_set_limit);
}

/* joint:set_twist(lower, upper) (a ball joint's); joint:set_twist(nil):
   no twist limit */
static int joint_set_twist(lua_State *L)
{
    return set_joint_pair(L, "joint:set_twist", tb_joint_set_twist_limit);
}

/* joint:set_motor(speed, max_force); joint:set_motor(nil): no motor */
static int joint_set_motor(lua_State *L)
{
    return set_joint_pair(L, "joint:set_motor", tb_joint_set_motor);
}

/* joint:set_spring(hz, damping_ratio, target); joint:set_spring(nil): no
   spring */
static int joint_set_spring(lua_State *L)
{
    tl_world *lw;
    tl_handle *h = check_handle(L, 1, H_JOINT, &lw);
    const int on = !lua_isnoneornil(L, 2);
    const double hz = on ? setter_number(L, 2, "joint:set_spring") : 0;
    const double ratio = on && !lua_isnoneornil(L, 3) ? setter_number(L, 3, "joint:set_spring") : 0;
    const double target = on && !lua_isnoneornil(L, 4) ? setter_number(L, 4, "joint:set_spring") : 0;
    if (tb_joint_set_spring(lw->world, to_joint_id(h), on, hz, ratio, target) != TB_OK)
        return raise_world_error(L, lw, "joint:set_spring");
    return 0;
}

static const luaL_Reg joint_methods[] = {
    { "reaction", joint_reaction }, { "error", joint_error }, { "position", joint_position },
    { "set_limit", joint_set_limit }, { "set_motor", joint_set_motor }, { "set_spring", joint_set_spring },
    { "set_twist", joint_set_twist },
    { "remove", handle_remove }, { "id", handle_id }, { NULL, NULL }
};

/* ------------------------------------------------ callbacks into Lua -- */

/* The world's user value is its table unless the debug library replaced it. */
static void check_world_table(lua_State *L, int idx)
{
    if (!lua_istable(L, idx))
        luaL_error(L, "tumble: the world's table of callbacks is gone (replaced through the debug library)");
}

/* A table in the world's table under `name`, made if missing. */
static int get_scratch_table(lua_State *L, int table_idx, const char *name)
{
    if (lua_getfield(L, table_idx, name) != LUA_TTABLE) {
        lua_pop(L, 1);
        lua_newtable(L);
        lua_pushvalue(L, -1);
        lua_setfield(L, table_idx, name);
    }
    return lua_gettop(L);
}

/* What a Lua force reads is filled in when it first reads it in a call,
   not before: the state table's arrays (s.pos, s.vel, s.mass) and the
   bodies' (s.bodies.pos, ...), each a table kept in the world's table and
   filled again only in a call that reads it. A force that reads positions
   and masses costs the copies of those alone (bench/lua_force.c). The
   state tables' __index (read_state) fills a field and sets it in the
   table, so the call's further reads are plain table reads; run_force
   takes the fields out again before the next call. */
typedef struct tl_array {
    const char *key;      /* in s, or in s.bodies */
    const char *kept;     /* the table's key in the world's table */
} tl_array;
static const tl_array particle_arrays[] = { { "pos", "force_pos" }, { "vel", "force_vel" },
                                            { "mass", "force_mass" }, { "bodies", "force_bodies" } };
static const tl_array body_arrays[] = { { "pos", "body_pos" }, { "rot", "body_rot" }, { "vel", "body_vel" },
                                        { "omega", "body_omega" }, { "mass", "body_mass" } };
#define PARTICLE_ARRAYS 4
#define BODY_ARRAYS 5

static int read_state(lua_State *L);

/* The state table `name` in the world's table (at table_idx), made if
   missing with a locked metatable whose __index is read_state (upvalues:
   the world's userdata at world_idx, `bodies`); its arrays are taken out,
   so that this call's reads fill them afresh. */
static int get_state_table(lua_State *L, int table_idx, int world_idx, const char *name, int bodies)
{
    const int state = get_scratch_table(L, table_idx, name);
    const tl_array *arrays = bodies ? body_arrays : particle_arrays;
    int k;
    if (!lua_getmetatable(L, state)) {
        lua_createtable(L, 0, 2);
        lua_pushvalue(L, world_idx);
        lua_pushinteger(L, bodies);
        lua_pushcclosure(L, read_state, 2);
        lua_setfield(L, -2, "__index");
        lua_pushboolean(L, 0);
        lua_setfield(L, -2, "__metatable");
        lua_setmetatable(L, state);
    } else {
        lua_pop(L, 1);
    }
    for (k = 0; k < (bodies ? BODY_ARRAYS : PARTICLE_ARRAYS); ++k) {
        lua_pushnil(L);
        lua_setfield(L, state, arrays[k].key);
    }
    return state;
}

static void fill_array(lua_State *L, int table_idx, const double *values, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        lua_pushnumber(L, values ? values[i] : 0.0);
        lua_rawseti(L, table_idx, (lua_Integer)i + 1);
    }
}

/* Add the numbers of the table at idx, 1..n, to out; with `reset`, put 0
   back where a number was not 0, so the table is zeros again. They are
   read CHUNK at a time onto the stack, popped together. */
#define CHUNK 16
static void add_from_table(lua_State *L, int table_idx, double *out, size_t n, const char *what, int reset)
{
    double v[CHUNK];
    size_t i, j, m;
    luaL_checkstack(L, CHUNK, "reading a callback's numbers");
    for (i = 0; i < n; i += m) {
        m = n - i < CHUNK ? n - i : CHUNK;
        for (j = 0; j < m; ++j)
            lua_rawgeti(L, table_idx, (lua_Integer)(i + j) + 1);
        for (j = 0; j < m; ++j) {
            const int at = (int)j - (int)m;
            int isnum;
            v[j] = lua_tonumberx(L, at, &isnum);
            if (!isnum)
                luaL_error(L, "%s[%d] is %s, not a number", what, (int)(i + j) + 1, luaL_typename(L, at));
            out[i + j] += v[j];
        }
        lua_pop(L, (int)m);
        for (j = 0; reset && j < m; ++j)
            if (v[j] != 0 || signbit(v[j])) {
                lua_pushnumber(L, 0);
                lua_rawseti(L, table_idx, (lua_Integer)(i + j) + 1);
            }
    }
}

/* s.mass lives across calls: masses change only with the set of particles
   (none while the world steps), so the kept table is filled again only
   when they differ from the copy of what it holds, or it was made anew. */
static void read_masses(lua_State *L, tl_world *lw, int world, const char *kept, const tb_force_args *a)
{
    const size_t bytes = a->count * sizeof(double);
    const int made = lua_getfield(L, world, kept) != LUA_TTABLE;
    int table;
    lua_pop(L, 1);
    table = get_scratch_table(L, world, kept);
    if (!made && lw->mass_count == a->count && (!bytes || memcmp(lw->masses, a->masses, bytes) == 0))
        return;
    if (lw->mass_cap < a->count) {
        double *copy = lw->alloc(lw->alloc_ud, lw->masses, lw->mass_cap * sizeof(double), bytes);
        if (!copy)
            luaL_error(L, "not enough memory");
        lw->masses = copy;
        lw->mass_cap = a->count;
    }
    lw->mass_count = 0; /* until the table holds them */
    fill_array(L, table, a->masses, a->count);
    if (bytes)
        memcpy(lw->masses, a->masses, bytes);
    lw->mass_count = a->count;
}

/* __index of a state table, upvalues (the world's userdata, 0 for s or 1
   for s.bodies): outside a call, or for another key, nil. */
static int read_state(lua_State *L)
{
    tl_world *lw = test_world(L, lua_upvalueindex(1));
    const int bodies = (int)lua_tointeger(L, lua_upvalueindex(2));
    const tb_force_args *a = lw ? lw->force_args : NULL;
    const char *key = lua_type(L, 2) == LUA_TSTRING ? lua_tostring(L, 2) : "";
    const tl_array *arrays = bodies ? body_arrays : particle_arrays;
    const int count = bodies ? BODY_ARRAYS : PARTICLE_ARRAYS;
    const double *values;
    size_t length;
    int k, world;
    for (k = 0; k < count && strcmp(arrays[k].key, key) != 0; ++k)
        ;
    if (!a || k == count)
        return 0;
    if (bodies) {
        const double *v[BODY_ARRAYS] = { a->body_positions, a->body_orientations, a->body_velocities,
                                         a->body_angular_velocities, a->body_masses };
        const size_t widths[BODY_ARRAYS] = { 3, 4, 3, 3, 1 };
        values = v[k];
        length = widths[k] * a->body_count;
    } else {
        const double *v[PARTICLE_ARRAYS] = { a->positions, a->velocities, a->masses, NULL };
        const size_t widths[PARTICLE_ARRAYS] = { 3, 3, 1, 0 };
        values = v[k];
        length = widths[k] * a->count;
    }
    lua_getiuservalue(L, lua_upvalueindex(1), 1);
    world = lua_gettop(L);
    check_world_table(L, world);
    if (!bodies && k == 3) { /* s.bodies: a state table of its own */
        get_state_table(L, world, lua_upvalueindex(1), arrays[k].kept, 1);
        lua_pushinteger(L, (lua_Integer)a->body_count);
        lua_setfield(L, -2, "n");
    } else if (!bodies && k == 2) {
        read_masses(L, lw, world, arrays[k].kept, a);
    } else {
        fill_array(L, get_scratch_table(L, world, arrays[k].kept), values, length);
    }
    lua_pushvalue(L, 2);
    lua_pushvalue(L, -2);
    lua_rawset(L, 1);
    return 1;
}

/* What run_force and run_field get through lua_pcall, as light userdata. */
typedef struct tl_force_call { tl_callback *cb; const tb_force_args *args; } tl_force_call;
typedef struct tl_field_call { tl_callback *cb; const tb_field_args *args; } tl_field_call;

/* Make entries from + 1 .. n of the table at idx 0. */
static void zero_from(lua_State *L, int table_idx, size_t from, size_t n)
{
    size_t i;
    for (i = from; i < n; ++i) {
        lua_pushnumber(L, 0);
        lua_rawseti(L, table_idx, (lua_Integer)i + 1);
    }
}

/* Call a Lua force, under lua_pcall: (call record, the world's table, the
   world's userdata). fn(t, state, forces, body_forces, body_torques):
   state = {n, pos, vel, mass, bodies = {n, pos, rot, vel, omega, mass}} in
   flat arrays, filled when first read (read_state); forces, body_forces and
   body_torques flat arrays of zeros to add to, kept from call to call: what
   a call wrote is read and the entries it set put back to 0, so a call
   costs the entries it writes, not the zeroing of all of them. */
static int run_force(lua_State *L)
{
    static const char *const outs[3] = { "force_out", "body_force_out", "body_torque_out" };
    static const char *const what[3] = { "forces", "body_forces", "body_torques" };
    tl_force_call *c = lua_touserdata(L, 1);
    const tb_force_args *a = c->args;
    tl_world *lw = c->cb->owner;
    const int t = 2; /* the world's table */
    const size_t lengths[3] = { 3 * a->count, 3 * a->body_count, 3 * a->body_count };
    double *const into[3] = { a->forces, a->body_forces, a->body_torques };
    int state, k, top;
    check_world_table(L, t);
    lua_rawgeti(L, t, c->cb->key);
    lua_pushnumber(L, a->time);
    state = get_state_table(L, t, 3, "force_state", 0);
    lua_pushinteger(L, (lua_Integer)a->count);
    lua_setfield(L, state, "n");
    for (k = 0; k < 3; ++k) { /* zeros: the entries past those known to be 0 */
        if (lua_getfield(L, t, outs[k]) != LUA_TTABLE)
            lw->zeroed[k] = 0; /* a table made now (get_scratch_table) */
        lua_pop(L, 1);
        zero_from(L, get_scratch_table(L, t, outs[k]), lw->zeroed[k], lengths[k]);
        lw->zeroed[k] = 0; /* the call may write any of them */
    }
    lw->force_args = a; /* until run_protected puts back what it was */
    lua_call(L, 5, a->potential ? 1 : 0);
    if (a->potential) { /* asked for the energy: a number returned is the force's potential */
        if (lua_type(L, -1) == LUA_TNUMBER)
            *a->potential += lua_tonumber(L, -1);
        else if (!lua_isnil(L, -1))
            return luaL_error(L, "a force returns its potential energy (a number, J) or nothing (got %s)",
                              luaL_typename(L, -1));
        lua_pop(L, 1);
    }
    check_world_table(L, t);
    top = lua_gettop(L);
    for (k = 0; k < 3; ++k) {
        if (lengths[k])
            add_from_table(L, get_scratch_table(L, t, outs[k]), into[k], lengths[k], what[k], 1);
        lw->zeroed[k] = lengths[k];
        lua_settop(L, top);
    }
    return 0;
}

/* Call a Lua field, under lua_pcall: (call record, the world's table, the
   world's userdata).
   fn(t, pos, vel): pos flat positions, vel a flat array of 3n zeros to add to. */
static int run_field(lua_State *L)
{
    tl_field_call *c = lua_touserdata(L, 1);
    const tb_field_args *a = c->args;
    const int t = 2; /* the world's table */
    int vel;
    check_world_table(L, t);
    lua_rawgeti(L, t, c->cb->key);
    lua_pushnumber(L, a->time);
    fill_array(L, get_scratch_table(L, t, "field_pos"), a->positions, 3 * a->count);
    vel = get_scratch_table(L, t, "field_out");
    fill_array(L, vel, NULL, 3 * a->count);
    lua_call(L, 3, 0);
    check_world_table(L, t);
    add_from_table(L, get_scratch_table(L, t, "field_out"), a->velocities, 3 * a->count, "vel", 0);
    return 0;
}

/* Run `run` (run_force or run_field) on the thread stepping the world, with
   a traceback handler; a Lua error becomes TB_ERR_CALLBACK and its first
   line the message. The world's force_args are what they were before, after
   an error too, so no state table reads a finished call's arrays. */
static tb_status run_protected(tl_callback *cb, lua_CFunction run, void *call, char *message)
{
    lua_State *L = cb->owner->L;
    const tb_force_args *outer;
    int top, rc;
    if (!L) {
        copy_first_line(message, TB_MESSAGE_SIZE,
                        "a Lua callback ran outside tb_lua_step (use it to step Lua worlds)");
        return TB_ERR_CALLBACK;
    }
    if (!lua_checkstack(L, 8)) {
        copy_first_line(message, TB_MESSAGE_SIZE, "Lua stack overflow");
        return TB_ERR_CALLBACK;
    }
    top = lua_gettop(L);
    lua_pushcfunction(L, add_traceback);
    lua_pushcfunction(L, run);
    lua_pushlightuserdata(L, call);
    /* The world's table, through its anchor: no stack slot, which a script
       could rewrite (debug.setlocal), holds the world. */
    lua_rawgetp(L, LUA_REGISTRYINDEX, &anchor_key);
    if (lua_istable(L, -1))
        lua_rawgetp(L, -1, cb->owner);
    else
        lua_pushnil(L);
    if (lua_touserdata(L, -1) == cb->owner)
        lua_getiuservalue(L, -1, 1);
    else
        lua_pushnil(L);
    lua_replace(L, top + 4); /* the table; the world's userdata (or nil) after it */
    outer = cb->owner->force_args;
    rc = lua_pcall(L, 3, 0, top + 1);
    cb->owner->force_args = outer; /* also after an error: no call runs now */
    if (rc != LUA_OK)
        copy_first_line(message, TB_MESSAGE_SIZE,
                        lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1) : "(error object is not a string)");
    lua_settop(L, top);
    return rc == LUA_OK ? TB_OK : TB_ERR_CALLBACK;
}

/* The tb_force_fn and tb_field_fn the core holds for a Lua function; user
   is its tl_callback. */
static tb_status call_lua_force(const tb_force_args *args, void *user)
{
    tl_force_call c;
    c.cb = user;
    c.args = args;
    return run_protected(c.cb, run_force, &c, args->message);
}

static tb_status call_lua_field(const tb_field_args *args, void *user)
{
    tl_field_call c;
    c.cb = user;
    c.args = args;
    return run_protected(c.cb, run_field, &c, args->message);
}

/* Store the function at fn_idx in the world's table; returns the record,
   listed in the world before anything can raise, so it is never lost. */
static tl_callback *keep_callback(lua_State *L, int world_idx, tl_world *lw, int fn_idx)
{
    tl_callback *cb;
    if (lua_getiuservalue(L, world_idx, 1) != LUA_TTABLE)
        check_world_table(L, -1);
    cb = lw->alloc(lw->alloc_ud, NULL, 0, sizeof *cb);
    if (!cb)
        luaL_error(L, "not enough memory");
    cb->owner = lw;
    cb->key = ++lw->next_key;
    cb->next = lw->callbacks;
    lw->callbacks = cb;
    lua_pushvalue(L, fn_idx);
    lua_rawseti(L, -2, cb->key);
    lua_pop(L, 1);
    return cb;
}

/* -------------------------------------------------------------- world -- */

static const char *const world_options[] = { "gravity", "integrator", "dt", "drag", "tolerance", "guard", NULL };
static const char *const drag_options[] = { "linear", "quadratic", NULL };
static const char *const particle_options[] = { "pos", "vel", "mass", "pinned", NULL };
static const char *const tracer_options[] = { "pos", NULL };
static const char *const spring_options[] = { "k", "damping", "rest", NULL };
static const char *const field_options[] = { "uniform", "vortex", "centre", NULL };

static void read_drag(lua_State *L, int idx, const char *fname, double *linear, double *quadratic)
{
    check_options(L, idx, fname, drag_options);
    opt_number(L, idx, "linear", fname, linear);
    opt_number(L, idx, "quadratic", fname, quadratic);
}

static int module_world(lua_State *L)
{
    tb_world_def def = tb_default_world_def();
    char message[TB_MESSAGE_SIZE];
    tl_world *lw;
    double dt = 1.0 / 60;
    int top;
    if (lua_isnoneornil(L, 1))
        lua_newtable(L);
    lua_settop(L, 1);
    check_options(L, 1, "tumble.world", world_options);
    opt_vec3(L, 1, "gravity", "tumble.world", def.gravity);
    opt_number(L, 1, "dt", "tumble.world", &dt);
    opt_number(L, 1, "tolerance", "tumble.world", &def.tolerance);
    if (!(isfinite(dt) && dt > 0))
        return luaL_error(L, "tumble.world: 'dt' must be finite and > 0 (got %f)", dt);
    if (lua_getfield(L, 1, "integrator") != LUA_TNIL) {
        if (lua_type(L, -1) != LUA_TSTRING)
            return luaL_error(L, "tumble.world: 'integrator' must be a string");
        def.integrator = lua_tostring(L, -1);
    }
    top = lua_gettop(L);
    if (lua_getfield(L, 1, "drag") != LUA_TNIL)
        read_drag(L, lua_gettop(L), "tumble.world: drag", &def.linear_drag, &def.quadratic_drag);
    lua_settop(L, top);
    lw = lua_newuserdatauv(L, sizeof *lw, 1);
    memset(lw, 0, sizeof *lw);
    lw->tag = &world_tag;
    lw->dt = dt;
    lw->alloc = lua_getallocf(L, &lw->alloc_ud);
    lua_newtable(L);
    lua_setiuservalue(L, -2, 1);
    luaL_setmetatable(L, WORLD_MT);
    /* its key in the anchor table, so that stepping allocates nothing */
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &anchor_key) != LUA_TTABLE)
        return luaL_error(L, "tumble.world: the module was not opened in this Lua state");
    lua_pushboolean(L, 0);
    lua_rawsetp(L, -2, lw);
    lua_pop(L, 1);
    /* The world's memory counts against the Lua state's allocator; under a
       memory budget, a request the budget refuses ends the run. */
    def.allocator.realloc = lw->alloc == allocate_counted ? allocate_for_world : (tb_realloc_fn *)lw->alloc;
    def.allocator.user = lw->alloc_ud;
    if (tb_world_create(&def, &lw->world, message, sizeof message) != TB_OK)
        return luaL_error(L, "tumble.world: %s", message);
    if (lua_getfield(L, 1, "guard") != LUA_TNIL) {
        /* true: finiteness only; a number: also the energy growth factor */
        const double g = lua_isboolean(L, -1) ? (lua_toboolean(L, -1) ? HUGE_VAL : 0) : lua_tonumber(L, -1);
        if ((!lua_isboolean(L, -1) && !lua_isnumber(L, -1)) || tb_world_set_guard(lw->world, g) != TB_OK)
            return luaL_error(L, "tumble.world: 'guard' must be true, false or a factor > 1 (the largest "
                                 "energy growth per step)");
    }
    lua_pop(L, 1);
    return 1;
}

static int world_close(lua_State *L)
{
    tl_world *lw = check_world_userdata(L, 1);
    if (lw->L)
        return luaL_error(L, "tumble: cannot close a world while it is stepping");
    tb_world_destroy(lw->world);
    lw->world = NULL;
    free_callbacks(lw);
    return 0;
}

/* The collector never finalizes a stepping world (it is anchored), so a
   stepping world here is a direct call (debug.getmetatable(w).__gc(w)),
   refused like world:close(). */
static int world_gc(lua_State *L)
{
    tl_world *lw = check_world_userdata(L, 1);
    if (lw->L)
        return luaL_error(L, "tumble: cannot collect a world while it is stepping");
    tb_world_destroy(lw->world);
    lw->world = NULL;
    free_callbacks(lw);
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &anchor_key) == LUA_TTABLE) {
        lua_pushnil(L);
        lua_rawsetp(L, -2, lw);
    }
    lua_pop(L, 1);
    return 0;
}

static int world_tostring(lua_State *L)
{
    tl_world *lw = check_world_userdata(L, 1);
    if (!lw->world)
        lua_pushliteral(L, "tumble.world (closed)");
    else
        lua_pushfstring(L, "tumble.world (%s, %d particles, %d tracers, %d springs, %d bodies, t = %f s)",
                        tb_world_integrator(lw->world), (int)tb_world_particle_count(lw->world),
                        (int)tb_world_tracer_count(lw->world), (int)tb_world_spring_count(lw->world),
                        (int)tb_world_body_count(lw->world), tb_world_time(lw->world));
    return 1;
}

static int world_particle(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    tb_particle_def def = tb_default_particle_def();
    tb_particle_id id;
    check_options(L, 2, "world:particle", particle_options);
    opt_vec3(L, 2, "pos", "world:particle", def.position);
    opt_vec3(L, 2, "vel", "world:particle", def.velocity);
    opt_number(L, 2, "mass", "world:particle", &def.mass);
    lua_getfield(L, 2, "pinned");
    def.pinned = lua_toboolean(L, -1);
    lua_pop(L, 1);
    if (tb_world_add_particle(lw->world, &def, &id) != TB_OK)
        return raise_world_error(L, lw, "world:particle");
    push_handle(L, 1, H_PARTICLE, id.index1, id.generation, 0);
    return 1;
}

static int world_tracer(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    tb_tracer_def def = tb_default_tracer_def();
    tb_tracer_id id;
    check_options(L, 2, "world:tracer", tracer_options);
    opt_vec3(L, 2, "pos", "world:tracer", def.position);
    if (tb_world_add_tracer(lw->world, &def, &id) != TB_OK)
        return raise_world_error(L, lw, "world:tracer");
    push_handle(L, 1, H_TRACER, id.index1, id.generation, 0);
    return 1;
}

/* The key of a body table that gives the body's mass properties, in the
   order of read_mass's keys[]; MASS_DEFAULT when the table gives none. */
enum tl_mass_source {
    MASS_DEFAULT = -1,
    MASS_SPHERE, MASS_BOX, MASS_CYLINDER, MASS_CAPSULE, MASS_POINTS, MASS_MESH, MASS_INERTIA, MASS_SOURCES
};

/* Mass properties from a body definition table: `inertia = {I1, I2, I3}`
   (principal moments, with `mass`), or one shape (`sphere = r`,
   `box = {x, y, z}`, `cylinder = {r, l}`, `capsule = {r, l}`,
   `points = {{x, y, z, m}, ...}`, `mesh = {vertices = {...}, triangles =
   {...}}` with 1-based indices) with `density` or `mass`. */
static void read_mass(lua_State *L, int idx, tb_mass *m)
{
    static const char *const keys[MASS_SOURCES] = { "sphere", "box", "cylinder", "capsule", "points", "mesh",
                                                    "inertia" };
    const char *fname = "world:body";
    char message[TB_MESSAGE_SIZE];
    double density = 1, total = 0, I[3], v[3];
    int has_density = opt_number(L, idx, "density", fname, &density);
    int has_mass = opt_number(L, idx, "mass", fname, &total);
    int k, found = MASS_DEFAULT, top = lua_gettop(L);
    tb_status st = TB_OK;
    for (k = 0; k < MASS_SOURCES; ++k) {
        if (lua_getfield(L, idx, keys[k]) != LUA_TNIL) {
            if (found != MASS_DEFAULT)
                luaL_error(L, "%s: give one shape, not both '%s' and '%s'", fname, keys[found], keys[k]);
            found = k;
        }
        lua_pop(L, 1);
    }
    if (has_density && has_mass)
        luaL_error(L, "%s: give 'density' or 'mass', not both", fname);
    if (found == MASS_DEFAULT) { /* perhaps scaled to another mass below */
        tb_body_def d = tb_default_body_def();
        *m = d.mass;
        if (has_density)
            luaL_error(L, "%s: 'density' needs a shape", fname);
    } else if (found == MASS_INERTIA) {
        lua_getfield(L, idx, "inertia");
        read_vec3(L, lua_gettop(L), fname, "inertia", I);
        if (has_density)
            luaL_error(L, "%s: 'inertia' goes with 'mass', not 'density'", fname);
        memset(m, 0, sizeof *m);
        m->mass = has_mass ? total : 1;
        memcpy(m->inertia, I, sizeof I);
        m->frame[0] = 1;
        has_mass = 0;
    } else {
        lua_getfield(L, idx, keys[found]);
        /* lua_rawgeti and lua_rawlen need a table and do not check for one,
           so the sources read with them are checked here. */
        if ((found == MASS_CYLINDER || found == MASS_CAPSULE || found == MASS_POINTS) && !lua_istable(L, -1))
            luaL_error(L, "%s: '%s' must be a table (got %s)", fname, keys[found], luaL_typename(L, -1));
        if (found == MASS_SPHERE) {
            st = tb_mass_sphere(density, luaL_checknumber(L, -1), m, message);
        } else if (found == MASS_BOX) {
            read_vec3(L, lua_gettop(L), fname, "box", v);
            st = tb_mass_box(density, v, m, message);
        } else if (found == MASS_CYLINDER || found == MASS_CAPSULE) {
            double r, l;
            lua_rawgeti(L, -1, 1);
            lua_rawgeti(L, -2, 2);
            r = luaL_checknumber(L, -2);
            l = luaL_checknumber(L, -1);
            lua_pop(L, 2);
            st = found == MASS_CYLINDER ? tb_mass_cylinder(density, r, l, m, message)
                                        : tb_mass_capsule(density, r, l, m, message);
        } else if (found == MASS_POINTS) {
            size_t n = lua_rawlen(L, -1), i;
            double *pos = lua_newuserdatauv(L, 4 * n * sizeof(double) + 1, 0), *mass = pos + 3 * n;
            for (i = 0; i < n; ++i) {
                int j;
                lua_rawgeti(L, -2, (lua_Integer)i + 1);
                if (lua_type(L, -1) != LUA_TTABLE)
                    luaL_error(L, "%s: points must be {{x, y, z, m}, ...}", fname);
                for (j = 0; j < 4; ++j) {
                    lua_rawgeti(L, -1, j + 1);
                    *(j < 3 ? &pos[3 * i + j] : &mass[i]) = luaL_checknumber(L, -1);
                    lua_pop(L, 1);
                }
                lua_pop(L, 1);
            }
            st = tb_mass_points(n, pos, mass, m, message);
        } else { /* MASS_MESH */
            int mesh = lua_gettop(L);
            size_t nv, nt, i;
            double *vertices;
            uint32_t *triangles;
            lua_getfield(L, mesh, "vertices");
            lua_getfield(L, mesh, "triangles");
            if (!lua_istable(L, -2) || !lua_istable(L, -1))
                luaL_error(L, "%s: mesh needs 'vertices' (flat x, y, z) and 'triangles' (flat 1-based indices)", fname);
            nv = lua_rawlen(L, -2);
            nt = lua_rawlen(L, -1);
            if (nv % 3 || nt % 3)
                luaL_error(L, "%s: mesh vertices and triangles must come in threes", fname);
            vertices = lua_newuserdatauv(L, nv * sizeof(double) + 1, 0);
            triangles = lua_newuserdatauv(L, nt * sizeof(uint32_t) + 1, 0);
            for (i = 0; i < nv; ++i) {
                lua_rawgeti(L, mesh + 1, (lua_Integer)i + 1);
                vertices[i] = luaL_checknumber(L, -1);
                lua_pop(L, 1);
            }
            for (i = 0; i < nt; ++i) {
                lua_Integer index;
                lua_rawgeti(L, mesh + 2, (lua_Integer)i + 1);
                index = luaL_checkinteger(L, -1);
                if (index < 1 || (size_t)index > nv / 3)
                    luaL_error(L, "%s: mesh triangle index %d is out of range", fname, (int)index);
                triangles[i] = (uint32_t)(index - 1);
                lua_pop(L, 1);
            }
            st = tb_mass_mesh(density, nv / 3, vertices, nt / 3, triangles, m, message);
        }
        if (st != TB_OK)
            luaL_error(L, "%s: %s", fname, message);
    }
    if (has_mass && tb_mass_set_total(m, total, message) != TB_OK)
        luaL_error(L, "%s: %s", fname, message);
    lua_settop(L, top);
}

static const char *const body_options[] = {
    "pos", "rot", "vel", "omega", "mass", "density", "inertia", "sphere", "box", "cylinder", "capsule",
    "points", "mesh", "linear_damping", "angular_damping", NULL
};

static int world_body(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    tb_body_def def = tb_default_body_def();
    tb_body_id id;
    check_options(L, 2, "world:body", body_options);
    read_mass(L, 2, &def.mass);
    opt_vec3(L, 2, "pos", "world:body", def.position);
    opt_vec3(L, 2, "vel", "world:body", def.velocity);
    opt_vec3(L, 2, "omega", "world:body", def.angular_velocity);
    if (lua_getfield(L, 2, "rot") != LUA_TNIL)
        read_quat(L, lua_gettop(L), "world:body", def.orientation);
    lua_pop(L, 1);
    opt_number(L, 2, "linear_damping", "world:body", &def.linear_damping);
    opt_number(L, 2, "angular_damping", "world:body", &def.angular_damping);
    if (tb_world_add_body(lw->world, &def, &id) != TB_OK)
        return raise_world_error(L, lw, "world:body");
    push_handle(L, 1, H_BODY, id.index1, id.generation, 0);
    return 1;
}

/* world:shape{ type = "sphere" | "capsule" | "box" | "plane", body = b (none:
   static), pos, rot, radius, half_length, half = {x, y, z}, normal, offset,
   friction, restitution, rolling_resistance, category, mask } */
static const char *const shape_options[] = { "type", "body", "pos", "rot", "radius", "half_length", "half",
                                             "normal", "offset", "friction", "restitution",
                                             "rolling_resistance", "category",
                                             "mask", NULL };

static int world_shape(lua_State *L)
{
    static const char *const types[] = { "sphere", "capsule", "box", "plane", NULL };
    tl_world *lw = check_world(L, 1), *other;
    tb_shape_def def = tb_default_shape_def();
    tb_shape_id id;
    double bits;
    check_options(L, 2, "world:shape", shape_options);
    lua_getfield(L, 2, "type");
    def.type = (tb_shape_type)luaL_checkoption(L, -1, NULL, types);
    lua_pop(L, 1);
    if (lua_getfield(L, 2, "body") != LUA_TNIL) {
        tl_handle *b = check_handle(L, lua_gettop(L), H_BODY, &other);
        if (other != lw)
            return luaL_error(L, "world:shape: the body belongs to another world");
        def.body = to_body_id(b);
    }
    lua_pop(L, 1);
    opt_vec3(L, 2, "pos", "world:shape", def.position);
    if (lua_getfield(L, 2, "rot") != LUA_TNIL)
        read_quat(L, lua_gettop(L), "world:shape", def.orientation);
    lua_pop(L, 1);
    opt_number(L, 2, "radius", "world:shape", &def.radius);
    opt_number(L, 2, "half_length", "world:shape", &def.half_length);
    opt_vec3(L, 2, "half", "world:shape", def.half_extents);
    opt_vec3(L, 2, "normal", "world:shape", def.normal);
    opt_number(L, 2, "offset", "world:shape", &def.offset);
    opt_number(L, 2, "friction", "world:shape", &def.friction);
    opt_number(L, 2, "restitution", "world:shape", &def.restitution);
    opt_number(L, 2, "rolling_resistance", "world:shape", &def.rolling_resistance);
    bits = def.category;
    opt_number(L, 2, "category", "world:shape", &bits);
    def.category = (uint32_t)bits;
    bits = def.mask;
    opt_number(L, 2, "mask", "world:shape", &bits);
    def.mask = (uint32_t)bits;
    if (tb_world_add_shape(lw->world, &def, &id) != TB_OK)
        return raise_world_error(L, lw, "world:shape");
    push_handle(L, 1, H_SHAPE, id.index1, id.generation, 0);
    return 1;
}

/* world:joint{ type = "ball" | "hinge" | "slider" | "fixed" | "distance",
   a = body or particle, b = body or particle (none: the world), anchor =
   {x, y, z}, anchor_b, axis, length, collide = boolean, lower, upper (a
   limit: hinge lower and upper default to -pi and pi, distance lower to
   0; slider needs both), cone (a ball joint's limit), twist = {lower,
   upper} (a ball joint's twist limit), motor_speed and
   max_motor_force (a motor: both), spring_hz, damping_ratio, target (a
   spring), break_force, break_torque } (tb_joint_def) */
static const char *const joint_options[] = { "type", "a", "b", "anchor", "anchor_b", "axis", "length", "collide",
                                             "lower", "upper", "cone", "twist", "motor_speed", "max_motor_force",
                                             "spring_hz", "damping_ratio", "target", "break_force", "break_torque",
                                             NULL };

/* The limit, motor, spring and breaking options of world:joint */
static void joint_drive_options(lua_State *L, tb_joint_def *def)
{
    const char *fname = "world:joint";
    const double pi = 3.14159265358979323846;
    int lower, upper, speed, most;
    def->lower = def->type == TB_JOINT_HINGE ? -pi : 0;
    def->upper = def->type == TB_JOINT_HINGE ? pi : 0;
    lower = opt_number(L, 2, "lower", fname, &def->lower);
    upper = opt_number(L, 2, "upper", fname, &def->upper);
    if (opt_number(L, 2, "cone", fname, &def->upper))
        upper = lower = 1;
    if ((lower || upper) && def->type == TB_JOINT_SLIDER && !(lower && upper))
        luaL_error(L, "%s: a slider's limit needs both 'lower' and 'upper'", fname);
    if ((lower || upper) && def->type == TB_JOINT_DISTANCE && !upper)
        luaL_error(L, "%s: a distance joint's limit needs 'upper'", fname);
    def->enable_limit = lower || upper;
    if (lua_getfield(L, 2, "twist") != LUA_TNIL) {
        double both[2];
        int k;
        if (!lua_istable(L, -1))
            luaL_error(L, "%s: 'twist' must be a table {lower, upper} of numbers", fname);
        for (k = 0; k < 2; ++k) {
            int isnum;
            lua_rawgeti(L, -1, k + 1);
            both[k] = lua_tonumberx(L, -1, &isnum);
            lua_pop(L, 1);
            if (!isnum)
                luaL_error(L, "%s: 'twist' must be a table {lower, upper} of numbers", fname);
        }
        def->enable_twist = 1, def->twist_lower = both[0], def->twist_upper = both[1];
    }
    lua_pop(L, 1);
    speed = opt_number(L, 2, "motor_speed", fname, &def->motor_speed);
    most = opt_number(L, 2, "max_motor_force", fname, &def->max_motor_force);
    if (speed != most)
        luaL_error(L, "%s: a motor needs both 'motor_speed' and 'max_motor_force'", fname);
    def->enable_motor = speed;
    def->enable_spring = opt_number(L, 2, "spring_hz", fname, &def->spring_hz);
    opt_number(L, 2, "damping_ratio", fname, &def->spring_damping_ratio);
    opt_number(L, 2, "target", fname, &def->spring_target);
    opt_number(L, 2, "break_force", fname, &def->break_force);
    opt_number(L, 2, "break_torque", fname, &def->break_torque);
}

static int world_joint(lua_State *L)
{
    static const char *const types[] = { "ball", "hinge", "slider", "fixed", "distance", NULL };
    static const char *const ends[] = { "a", "b" };
    tl_world *lw = check_world(L, 1), *other;
    tb_joint_def def = tb_default_joint_def();
    tb_joint_id id;
    int k;
    check_options(L, 2, "world:joint", joint_options);
    lua_getfield(L, 2, "type");
    def.type = (tb_joint_type)luaL_checkoption(L, -1, "ball", types);
    lua_pop(L, 1);
    for (k = 0; k < 2; ++k) {
        if (lua_getfield(L, 2, ends[k]) != LUA_TNIL) {
            /* a body, or a particle in its place (ball and distance joints) */
            const int particle = test_handle(L, lua_gettop(L), H_PARTICLE) != NULL;
            tl_handle *h = check_handle(L, lua_gettop(L), particle ? H_PARTICLE : H_BODY, &other);
            if (other != lw)
                return luaL_error(L, "world:joint: %s belongs to another world", ends[k]);
            if (particle && k)
                def.particle_b = to_particle_id(h);
            else if (particle)
                def.particle_a = to_particle_id(h);
            else if (k)
                def.b = to_body_id(h);
            else
                def.a = to_body_id(h);
        } else if (k == 0) {
            return luaL_error(L, "world:joint: 'a' (a body or a particle) is required");
        }
        lua_pop(L, 1);
    }
    opt_vec3(L, 2, "anchor", "world:joint", def.anchor);
    opt_vec3(L, 2, "anchor_b", "world:joint", def.anchor_b);
    opt_vec3(L, 2, "axis", "world:joint", def.axis);
    opt_number(L, 2, "length", "world:joint", &def.length);
    lua_getfield(L, 2, "collide");
    def.collide = lua_toboolean(L, -1);
    lua_pop(L, 1);
    joint_drive_options(L, &def);
    if (tb_world_add_joint(lw->world, &def, &id) != TB_OK)
        return raise_world_error(L, lw, "world:joint");
    push_handle(L, 1, H_JOINT, id.index1, id.generation, 0);
    return 1;
}

/* world:contacts{ hertz, damping_ratio, max_push, restitution_threshold,
   slop, particle_radius, particle_friction, particle_restitution,
   sleep_speed, sleep_time, substeps }: change the contact settings
   (sleep_time = math.huge: never sleep; substeps: the soft step's, >= 1,
   the default 4) */
static const char *const contact_options[] = { "hertz", "damping_ratio", "max_push", "restitution_threshold",
                                               "slop", "particle_radius", "particle_friction", "particle_restitution",
                                               "sleep_speed", "sleep_time", "substeps", NULL };

static int world_contacts(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    tb_contact_settings cs = tb_world_contact_settings(lw->world);
    double ss = cs.substeps;
    check_options(L, 2, "world:contacts", contact_options);
    opt_number(L, 2, "hertz", "world:contacts", &cs.hertz);
    opt_number(L, 2, "damping_ratio", "world:contacts", &cs.damping_ratio);
    opt_number(L, 2, "max_push", "world:contacts", &cs.max_push);
    opt_number(L, 2, "restitution_threshold", "world:contacts", &cs.restitution_threshold);
    opt_number(L, 2, "slop", "world:contacts", &cs.slop);
    opt_number(L, 2, "particle_radius", "world:contacts", &cs.particle_radius);
    opt_number(L, 2, "particle_friction", "world:contacts", &cs.particle_friction);
    opt_number(L, 2, "particle_restitution", "world:contacts", &cs.particle_restitution);
    opt_number(L, 2, "sleep_speed", "world:contacts", &cs.sleep_speed);
    opt_number(L, 2, "sleep_time", "world:contacts", &cs.sleep_time);
    opt_number(L, 2, "substeps", "world:contacts", &ss);
    if (!(ss >= 1 && ss <= 1e6 && ss == floor(ss)))
        return luaL_error(L, "world:contacts: substeps must be a whole number from 1 to 1000000 (got %f)", ss);
    cs.substeps = (int)ss;
    if (tb_world_set_contact_settings(lw->world, &cs) != TB_OK)
        return raise_world_error(L, lw, "world:contacts");
    return 0;
}

/* t[name] = v on the table at the top of the stack */
static void set_number(lua_State *L, const char *name, double v)
{
    lua_pushnumber(L, v);
    lua_setfield(L, -2, name);
}

static void set_integer(lua_State *L, const char *name, lua_Integer v)
{
    lua_pushinteger(L, v);
    lua_setfield(L, -2, name);
}

/* world:events(): the contacts that began or ended in the last step, as
   { type = "begin" | "end", a = shape index, b = shape index or nil,
     particle = particle index or nil, speed, point = {x, y, z},
     normal = {x, y, z} } (indices as in handle:id()) */
static int world_events(lua_State *L)
{
    size_t n, i;
    const tb_contact_event *ev = tb_world_contact_events(check_world(L, 1)->world, &n);
    lua_createtable(L, (int)n, 0);
    for (i = 0; i < n; ++i) {
        lua_createtable(L, 0, 7);
        lua_pushstring(L, ev[i].type == TB_CONTACT_BEGIN ? "begin" : "end");
        lua_setfield(L, -2, "type");
        set_integer(L, "a", (lua_Integer)ev[i].a.index1);
        if (!TB_ID_IS_NULL(ev[i].b)) {
            set_integer(L, "b", (lua_Integer)ev[i].b.index1);
        }
        if (!TB_ID_IS_NULL(ev[i].particle)) {
            set_integer(L, "particle", (lua_Integer)ev[i].particle.index1);
        }
        set_number(L, "speed", ev[i].speed);
        push_vec3_table(L, ev[i].point);
        lua_setfield(L, -2, "point");
        push_vec3_table(L, ev[i].normal);
        lua_setfield(L, -2, "normal");
        lua_rawseti(L, -2, (lua_Integer)i + 1);
    }
    return 1;
}

/* world:spring(a, b_or_point, {k = N/m, damping = N s/m, rest = m}) */
static int world_spring(lua_State *L)
{
    tl_world *lw = check_world(L, 1), *other;
    tb_spring_def def = tb_default_spring_def();
    tb_spring_id id;
    tl_handle *a = check_handle(L, 2, H_PARTICLE, &other);
    if (other != lw)
        return luaL_error(L, "world:spring: particle a belongs to another world");
    def.a = to_particle_id(a);
    if (lua_type(L, 3) == LUA_TTABLE) {
        read_vec3(L, 3, "world:spring", "anchor", def.anchor);
    } else {
        tl_handle *b = check_handle(L, 3, H_PARTICLE, &other);
        if (other != lw)
            return luaL_error(L, "world:spring: particle b belongs to another world");
        def.b = to_particle_id(b);
    }
    if (!lua_isnoneornil(L, 4)) {
        check_options(L, 4, "world:spring", spring_options);
        opt_number(L, 4, "k", "world:spring", &def.stiffness);
        opt_number(L, 4, "damping", "world:spring", &def.damping);
        opt_number(L, 4, "rest", "world:spring", &def.rest_length);
    }
    if (tb_world_add_spring(lw->world, &def, &id) != TB_OK)
        return raise_world_error(L, lw, "world:spring");
    push_handle(L, 1, H_SPRING, id.index1, id.generation, 0);
    return 1;
}

static int world_drag(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    double linear = 0, quadratic = 0;
    read_drag(L, 2, "world:drag", &linear, &quadratic);
    if (tb_world_set_drag(lw->world, linear, quadratic) != TB_OK)
        return raise_world_error(L, lw, "world:drag");
    return 0;
}

/* world:field{uniform = v} | world:field{vortex = omega, centre = c} | world:field(fn) */
static int world_field(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    tb_field_id id;
    tb_status st;
    int key = 0;
    if (lua_type(L, 2) == LUA_TFUNCTION) {
        tl_callback *cb = keep_callback(L, 1, lw, 2);
        key = cb->key;
        st = tb_world_add_field(lw->world, call_lua_field, cb, &id);
        if (st != TB_OK)
            forget_callback(L, 1, lw, key);
    } else {
        double v[3], c[3] = { 0, 0, 0 };
        check_options(L, 2, "world:field", field_options);
        opt_vec3(L, 2, "centre", "world:field", c);
        if (opt_vec3(L, 2, "uniform", "world:field", v))
            st = tb_world_add_uniform_field(lw->world, v, &id);
        else if (opt_vec3(L, 2, "vortex", "world:field", v))
            st = tb_world_add_vortex_field(lw->world, v, c, &id);
        else
            return luaL_error(L, "world:field: give {uniform = {x, y, z}}, {vortex = omega, centre = c} or a function");
    }
    if (st != TB_OK)
        return raise_world_error(L, lw, "world:field");
    push_handle(L, 1, H_FIELD, id.index1, id.generation, key);
    return 1;
}

static int world_force(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    tl_callback *cb;
    tb_force_id id;
    luaL_checktype(L, 2, LUA_TFUNCTION);
    cb = keep_callback(L, 1, lw, 2);
    if (tb_world_add_force(lw->world, call_lua_force, cb, &id) != TB_OK) {
        forget_callback(L, 1, lw, cb->key);
        return raise_world_error(L, lw, "world:force");
    }
    push_handle(L, 1, H_FORCE, id.index1, id.generation, cb->key);
    return 1;
}

static int world_step(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    double h = luaL_optnumber(L, 2, lw->dt);
    if (tb_lua_step(L, 1, h) != TB_OK)
        return raise_world_error(L, lw, "world:step");
    return 0;
}

static int world_time(lua_State *L)
{
    lua_pushnumber(L, tb_world_time(check_world(L, 1)->world));
    return 1;
}

static int world_dt(lua_State *L)
{
    lua_pushnumber(L, check_world(L, 1)->dt);
    return 1;
}

static int world_set_dt(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    double dt = luaL_checknumber(L, 2);
    if (!(isfinite(dt) && dt > 0))
        return luaL_error(L, "world:set_dt: step must be finite and > 0 (got %f)", dt);
    lw->dt = dt;
    return 0;
}

static int world_integrator(lua_State *L)
{
    lua_pushstring(L, tb_world_integrator(check_world(L, 1)->world));
    return 1;
}

static int world_set_integrator(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    if (tb_world_set_integrator(lw->world, luaL_checkstring(L, 2)) != TB_OK)
        return raise_world_error(L, lw, "world:set_integrator");
    return 0;
}

static int world_set_tolerance(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    if (tb_world_set_tolerance(lw->world, luaL_checknumber(L, 2)) != TB_OK)
        return raise_world_error(L, lw, "world:set_tolerance");
    return 0;
}

/* world:set_guard(true | false | factor) */
static int world_set_guard(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    const double g = lua_isboolean(L, 2) ? (lua_toboolean(L, 2) ? HUGE_VAL : 0) : luaL_checknumber(L, 2);
    if (tb_world_set_guard(lw->world, g) != TB_OK)
        return raise_world_error(L, lw, "world:set_guard");
    return 0;
}

/* The method and substeps "auto" chose for its last step (nil before). */
static int world_auto_choice(lua_State *L)
{
    long substeps;
    const char *name = tb_world_auto_choice(check_world(L, 1)->world, &substeps);
    if (!name)
        return 0;
    lua_pushstring(L, name);
    lua_pushinteger(L, (lua_Integer)substeps);
    return 2;
}

/* world:advise([dt]): the advisor's verdict for a step dt (the world's
   dt when omitted) as a table {limit, exceeded, stiffest, damping_ratio,
   decay, fastest_spin, spring (index, nil when none), text}; changes
   nothing (tb_world_advise). */
static int world_advise(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    const double dt = lua_isnoneornil(L, 2) ? lw->dt : luaL_checknumber(L, 2);
    tb_advice a;
    if (tb_world_advise(lw->world, dt, &a) != TB_OK)
        return raise_world_error(L, lw, "world:advise");
    lua_createtable(L, 0, 8);
    set_number(L, "limit", a.limit);
    lua_pushboolean(L, a.exceeded);
    lua_setfield(L, -2, "exceeded");
    set_number(L, "stiffest", a.stiffest);
    set_number(L, "damping_ratio", a.damping_ratio);
    set_number(L, "decay", a.decay);
    set_number(L, "fastest_spin", a.fastest_spin);
    if (!TB_ID_IS_NULL(a.spring)) {
        set_integer(L, "spring", (lua_Integer)a.spring.index1);
    }
    lua_pushstring(L, a.text);
    lua_setfield(L, -2, "text");
    return 1;
}

/* world:work(): {steps, substeps, rejected, evaluations, contact_work,
   damping_work} (tb_world_work) */
static int world_work(lua_State *L)
{
    const tb_work k = tb_world_work(check_world(L, 1)->world);
    lua_createtable(L, 0, 6);
    set_integer(L, "steps", (lua_Integer)k.steps);
    set_integer(L, "substeps", (lua_Integer)k.substeps);
    set_integer(L, "rejected", (lua_Integer)k.rejected);
    set_integer(L, "evaluations", (lua_Integer)k.evaluations);
    set_number(L, "contact_work", k.contact_work);
    set_number(L, "damping_work", k.damping_work);
    return 1;
}

static int world_gravity(lua_State *L)
{
    double g[3];
    tb_world_gravity(check_world(L, 1)->world, g);
    return push_vec3(L, g);
}

static int world_set_gravity(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    double g[3];
    read_vec3_args(L, 2, "world:set_gravity", g);
    if (tb_world_set_gravity(lw->world, g) != TB_OK)
        return raise_world_error(L, lw, "world:set_gravity");
    return 0;
}

/* w:energy(): with the potential the Lua forces return (inside a callback,
   where they cannot run again, without it) */
static int world_energy(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    tb_energy e;
    if (lw->L)
        e = tb_world_energy(lw->world);
    else if (tb_lua_energy(L, 1, &e) != TB_OK)
        return raise_world_error(L, lw, "world:energy");
    lua_createtable(L, 0, 6);
    set_number(L, "potential", e.potential);
    set_number(L, "kinetic", e.kinetic);
    set_number(L, "rotational", e.rotational);
    set_number(L, "gravity", e.gravity);
    set_number(L, "spring", e.spring);
    set_number(L, "total", e.total);
    return 1;
}

static int world_momentum(lua_State *L)
{
    double p[3];
    tb_world_momentum(check_world(L, 1)->world, p);
    return push_vec3(L, p);
}

static int world_angular_momentum(lua_State *L)
{
    double l[3];
    tb_world_angular_momentum(check_world(L, 1)->world, l);
    return push_vec3(L, l);
}

/* particles, tracers, springs, bodies */
static int world_counts(lua_State *L)
{
    tb_world *w = check_world(L, 1)->world;
    lua_pushinteger(L, (lua_Integer)tb_world_particle_count(w));
    lua_pushinteger(L, (lua_Integer)tb_world_tracer_count(w));
    lua_pushinteger(L, (lua_Integer)tb_world_spring_count(w));
    lua_pushinteger(L, (lua_Integer)tb_world_body_count(w));
    return 4;
}

/* ---- snapshots: a userdata owning a tb_snapshot, with its world as user
   value (a restore must find the callbacks the world keeps) -------------- */

typedef struct tl_snapshot {
    const char *tag;       /* &snapshot_tag */
    tb_snapshot *snapshot; /* NULL once collected */
} tl_snapshot;

static const char snapshot_tag = 's';

/* The snapshot at idx, raising unless idx holds a live one. */
static tl_snapshot *check_snapshot(lua_State *L, int idx)
{
    tl_snapshot *ls = luaL_testudata(L, idx, SNAPSHOT_MT);
    if (!ls || lua_rawlen(L, idx) != sizeof *ls || ls->tag != &snapshot_tag)
        luaL_typeerror(L, idx, SNAPSHOT_MT);
    if (!ls->snapshot)
        luaL_error(L, "tumble: the snapshot was freed");
    return ls;
}

/* w:snapshot([s]): a new snapshot, or s taken again in its own memory.
   A new userdata is made before the copy, so no error can lose it. */
static int world_snapshot(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    tl_snapshot *ls;
    if (!lua_isnoneornil(L, 2)) {
        ls = check_snapshot(L, 2);
        if (tb_world_snapshot_into(lw->world, ls->snapshot) != TB_OK)
            return raise_world_error(L, lw, "world:snapshot");
        lw->keeps_callbacks = 1;
        lua_settop(L, 2);
        return 1;
    }
    ls = lua_newuserdatauv(L, sizeof *ls, 1);
    ls->tag = &snapshot_tag;
    ls->snapshot = NULL;
    luaL_setmetatable(L, SNAPSHOT_MT);
    lua_pushvalue(L, 1);
    lua_setiuservalue(L, -2, 1);
    if (tb_world_snapshot(lw->world, &ls->snapshot) != TB_OK)
        return raise_world_error(L, lw, "world:snapshot");
    lw->keeps_callbacks = 1;
    return 1;
}

static int world_restore(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    tl_snapshot *ls = check_snapshot(L, 2);
    if (tb_world_restore(lw->world, ls->snapshot) != TB_OK)
        return raise_world_error(L, lw, "world:restore");
    return 0;
}

/* w:hash(): tb_world_hash as 16 hexadecimal digits (a Lua integer would
   print negative for half the hashes) */
static int world_hash(lua_State *L)
{
    char hex[17];
    snprintf(hex, sizeof hex, "%016llx", (unsigned long long)tb_world_hash(check_world(L, 1)->world));
    lua_pushstring(L, hex);
    return 1;
}

static int snapshot_size(lua_State *L)
{
    lua_pushinteger(L, (lua_Integer)tb_snapshot_size(check_snapshot(L, 1)->snapshot));
    return 1;
}

static int snapshot_time(lua_State *L)
{
    lua_pushnumber(L, tb_snapshot_time(check_snapshot(L, 1)->snapshot));
    return 1;
}

static int snapshot_gc(lua_State *L)
{
    tl_snapshot *ls = luaL_testudata(L, 1, SNAPSHOT_MT);
    if (ls && lua_rawlen(L, 1) == sizeof *ls && ls->tag == &snapshot_tag) {
        tb_snapshot_destroy(ls->snapshot);
        ls->snapshot = NULL;
    }
    return 0;
}

static const luaL_Reg snapshot_methods[] = { { "size", snapshot_size }, { "time", snapshot_time }, { NULL, NULL } };

static const luaL_Reg world_methods[] = {
    { "particle", world_particle }, { "tracer", world_tracer }, { "spring", world_spring },
    { "body", world_body }, { "joint", world_joint }, { "angular_momentum", world_angular_momentum },
    { "shape", world_shape }, { "contacts", world_contacts }, { "events", world_events },
    { "drag", world_drag }, { "field", world_field }, { "force", world_force },
    { "step", world_step }, { "time", world_time }, { "dt", world_dt }, { "set_dt", world_set_dt },
    { "integrator", world_integrator }, { "set_integrator", world_set_integrator },
    { "set_tolerance", world_set_tolerance }, { "set_guard", world_set_guard },
    { "auto_choice", world_auto_choice }, { "advise", world_advise }, { "work", world_work },
    { "gravity", world_gravity }, { "set_gravity", world_set_gravity },
    { "energy", world_energy }, { "momentum", world_momentum }, { "counts", world_counts },
    { "snapshot", world_snapshot }, { "restore", world_restore }, { "hash", world_hash },
    { "close", world_close }, { NULL, NULL }
};

/* ------------------------------------------------------------- module -- */

static int module_integrators(lua_State *L)
{
    int i, n = tb_integrator_count();
    lua_createtable(L, n, 0);
    for (i = 0; i < n; ++i) {
        lua_pushstring(L, tb_integrator_name(i));
        lua_rawseti(L, -2, i + 1);
    }
    return 1;
}

static void create_metatable(lua_State *L, const char *name, const luaL_Reg *methods)
{
    luaL_newmetatable(L, name);
    lua_newtable(L);
    luaL_setfuncs(L, methods, 0);
    lua_setfield(L, -2, "__index");
    lua_pushstring(L, name);
    lua_setfield(L, -2, "__metatable"); /* scripts cannot reach or swap it */
}

int luaopen_tumble(lua_State *L)
{
    static const luaL_Reg funcs[] = {
        { "world", module_world }, { "integrators", module_integrators }, { NULL, NULL }
    };
    static const luaL_Reg *const kind_methods[H_KINDS] = {
        particle_methods, tracer_methods, plain_methods, plain_methods, plain_methods, body_methods,
        plain_methods, joint_methods
    };
    int k;
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &anchor_key) != LUA_TTABLE) {
        lua_newtable(L);
        lua_rawsetp(L, LUA_REGISTRYINDEX, &anchor_key);
    }
    lua_pop(L, 1);
    create_metatable(L, WORLD_MT, world_methods);
    lua_pushcfunction(L, world_gc);
    lua_setfield(L, -2, "__gc");
    lua_pushcfunction(L, world_close);
    lua_setfield(L, -2, "__close");
    lua_pushcfunction(L, world_tostring);
    lua_setfield(L, -2, "__tostring");
    lua_pop(L, 1);
    create_metatable(L, SNAPSHOT_MT, snapshot_methods);
    lua_pushcfunction(L, snapshot_gc);
    lua_setfield(L, -2, "__gc");
    lua_pop(L, 1);
    for (k = 0; k < H_KINDS; ++k) {
        create_metatable(L, handle_mt[k], kind_methods[k]);
        lua_pushcfunction(L, handle_tostring);
        lua_setfield(L, -2, "__tostring");
        lua_pushcfunction(L, handle_eq);
        lua_setfield(L, -2, "__eq");
        lua_pop(L, 1);
    }
    luaL_newlib(L, funcs);
    lua_pushfstring(L, "%d.%d.%d", TB_VERSION_MAJOR, TB_VERSION_MINOR, TB_VERSION_PATCH);
    lua_setfield(L, -2, "version");
    lua_pushfstring(L, "tumble %d.%d.%d", TB_VERSION_MAJOR, TB_VERSION_MINOR, TB_VERSION_PATCH);
    lua_setfield(L, -2, "_VERSION");
    return 1;
}

/* ------------------------------------------------------ host entries -- */

tb_world *tb_lua_check_world(lua_State *L, int idx)
{
    return check_world(L, idx)->world;
}

tb_world *tb_lua_to_world(lua_State *L, int idx)
{
    tl_world *lw = test_world(L, idx);
    return lw ? lw->world : NULL;
}

double tb_lua_world_dt(lua_State *L, int idx)
{
    tl_world *lw = test_world(L, idx);
    return lw && lw->world ? lw->dt : 0;
}

/* Set the world's anchor to the world at idx (anchor) or back to false.
   The key exists since the world was made, so this allocates nothing and
   cannot raise; returns 0 if the anchor table or the key is missing. */
static int set_anchor(lua_State *L, int idx, tl_world *lw, int anchor)
{
    int ok;
    if (lua_rawgetp(L, LUA_REGISTRYINDEX, &anchor_key) != LUA_TTABLE) {
        lua_pop(L, 1);
        return 0;
    }
    ok = lua_rawgetp(L, -1, lw) != LUA_TNIL;
    lua_pop(L, 1);
    if (ok) {
        if (anchor)
            lua_pushvalue(L, idx);
        else
            lua_pushboolean(L, 0);
        lua_rawsetp(L, -2, lw);
    }
    lua_pop(L, 1);
    return ok;
}

/* The core call run_with_callbacks makes: a step, the tracers'
   velocities, or the energy with the callbacks' potential. */
static tb_status core_call(tl_world *lw, double h, double *velocities, tb_energy *energy)
{
    if (energy)
        return tb_world_energy_with_callbacks(lw->world, energy);
    return velocities ? tb_world_tracer_velocities(lw->world, velocities) : tb_world_step(lw->world, h);
}

/* Run a core call with the world's Lua callbacks pointed at thread L, the
   world anchored for the call. */
static tb_status run_with_callbacks(lua_State *L, int idx, double h, double *velocities, tb_energy *energy)
{
    tl_world *lw = test_world(L, idx);
    tb_status st;
    if (!lw || !lw->world)
        return TB_ERR_ARGUMENT;
    if (lw->L) /* nested: the core refuses it as busy */
        return core_call(lw, h, velocities, energy);
    idx = lua_absindex(L, idx);
    if (!lua_checkstack(L, 4) || !set_anchor(L, idx, lw, 1))
        return TB_ERR_MEMORY;
    lw->L = L;
    st = core_call(lw, h, velocities, energy);
    lw->L = NULL;
    set_anchor(L, idx, lw, 0);
    return st;
}

tb_status tb_lua_step(lua_State *L, int idx, double h)
{
    return run_with_callbacks(L, idx, h, NULL, NULL);
}

tb_status tb_lua_tracer_velocities(lua_State *L, int idx, double *velocities)
{
    return run_with_callbacks(L, idx, 0, velocities, NULL);
}

tb_status tb_lua_energy(lua_State *L, int idx, tb_energy *energy)
{
    return run_with_callbacks(L, idx, 0, NULL, energy);
}

/* ------------------------------------------------------------ budgets -- */

/* The instructions between two counts: a hook call costs about as much as
   a few dozen instructions, and a budget overshoots by at most this. */
#define HOOK_COUNT 1000

enum tl_trip { TRIP_NONE, TRIP_INSTRUCTIONS, TRIP_MEMORY, TRIP_STOP };

/* The allocator's user data of a state made by tb_lua_newstate: the budgets
   and what has been used. It lives until lua_close frees the state's last
   block (blocks back to 0), and frees itself then. */
typedef struct tl_budget {
    tb_lua_limits limits;
    unsigned long long executed; /* instructions counted */
    size_t used, peak;           /* bytes held now, and at most */
    size_t blocks;               /* blocks held */
    int opened;                  /* lua_newstate returned: the state's block is held */
    int trip;                    /* enum tl_trip: why the code was stopped */
    int where_known;             /* the message names where it stopped */
    int refused;                 /* the last request was refused ... */
    void *refused_ptr;           /* ... this one */
    size_t refused_size;
    int warn_on, warn_continued; /* lua_setwarnf's switch and a message being continued */
    char message[256];
} tl_budget;

static void set_trip(tl_budget *b, int why)
{
    if (b->trip)
        return;
    b->trip = why;
    if (why == TRIP_INSTRUCTIONS)
        snprintf(b->message, sizeof b->message, "instruction budget exceeded: more than %llu Lua instructions",
                 b->limits.instructions);
    else if (why == TRIP_MEMORY)
        snprintf(b->message, sizeof b->message, "memory budget exceeded: more than %llu bytes",
                 (unsigned long long)b->limits.memory);
    else
        snprintf(b->message, sizeof b->message, "stopped by the host");
}

/* One request to the allocator. A request past the memory budget is
   refused. Lua's own allocations then collect all garbage and ask again
   at once: if that succeeds, the run goes on. Anything else ends the run:
   the same request refused again, another request instead (the refusal
   became an error: lauxlib's buffers ask once), a count of the hook or
   tb_lua_limit_error before either, or any refusal of a world's request
   (the core has no collection to wait for). */
static void *serve(tl_budget *b, void *ptr, size_t osize, size_t nsize, int from_world)
{
    void *p;
    int grows;
    if (!ptr)
        osize = 0; /* Lua passes the type of the new object there */
    grows = nsize > osize;
    if (grows && b->refused && !(b->refused_ptr == ptr && b->refused_size == nsize))
        set_trip(b, TRIP_MEMORY);
    if (nsize == 0) {
        free(ptr);
        if (ptr) {
            b->used -= osize < b->used ? osize : b->used;
            if (--b->blocks == 0 && b->opened)
                free(b); /* lua_close freed the state's own block, the last */
        }
        return NULL;
    }
    if (grows && b->limits.memory && nsize - osize > b->limits.memory - (b->used < b->limits.memory ? b->used : b->limits.memory)) {
        if (from_world || b->refused)
            set_trip(b, TRIP_MEMORY);
        b->refused = 1;
        b->refused_ptr = ptr;
        b->refused_size = nsize;
        return NULL;
    }
    p = realloc(ptr, nsize);
    if (!p)
        return NULL;
    if (grows)
        b->refused = 0;
    if (!ptr)
        ++b->blocks;
    b->used = b->used - osize + nsize;
    if (b->used > b->peak)
        b->peak = b->used;
    return p;
}

static void *allocate_counted(void *ud, void *ptr, size_t osize, size_t nsize)
{
    return serve(ud, ptr, osize, nsize, 0);
}

static void *allocate_for_world(void *ud, void *ptr, size_t osize, size_t nsize)
{
    return serve(ud, ptr, osize, nsize, 1);
}

static tl_budget *get_budget(lua_State *L)
{
    void *ud;
    return lua_getallocf(L, &ud) == allocate_counted ? ud : NULL;
}

/* The count hook: counts, and once a budget has run out raises an error
   and re-arms itself to run at every instruction, so the error comes back
   at the first instruction after any pcall that caught it. */
static void count_instructions(lua_State *L, lua_Debug *ar)
{
    tl_budget *b = get_budget(L);
    if (!b)
        return;
    b->executed += (unsigned long long)lua_gethookcount(L);
    if (!b->trip) {
        if (b->limits.instructions && b->executed > b->limits.instructions)
            set_trip(b, TRIP_INSTRUCTIONS);
        else if (b->limits.stop && *b->limits.stop)
            set_trip(b, TRIP_STOP);
        else if (b->refused)
            set_trip(b, TRIP_MEMORY);
        else
            return;
    }
    if (!b->where_known && lua_getinfo(L, "Sl", ar)) {
        size_t n = strlen(b->message);
        b->where_known = 1;
        snprintf(b->message + n, sizeof b->message - n, " (at %s:%d)", ar->short_src, ar->currentline);
    }
    lua_sethook(L, count_instructions, LUA_MASKCOUNT, 1);
    lua_pushstring(L, b->message);
    lua_error(L);
}

static void set_hook(lua_State *L, const tl_budget *b)
{
    const unsigned long long n = b->limits.instructions;
    if (n || b->limits.memory)
        lua_sethook(L, count_instructions, LUA_MASKCOUNT, n && n < HOOK_COUNT ? (int)n : HOOK_COUNT);
    else
        lua_sethook(L, NULL, 0, 0);
}

/* What luaL_newstate installs, for a state made with lua_newstate. */
static int report_panic(lua_State *L)
{
    fprintf(stderr, "PANIC: unprotected error in call to Lua API (%s)\n",
            lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1) : "error object is not a string");
    return 0;
}

static void print_warning(void *ud, const char *message, int to_continue)
{
    tl_budget *b = ud;
    if (!b->warn_continued && message[0] == '@') {
        if (!strcmp(message, "@on"))
            b->warn_on = 1;
        else if (!strcmp(message, "@off"))
            b->warn_on = 0;
        return;
    }
    if (b->warn_on) {
        if (!b->warn_continued)
            fputs("Lua warning: ", stderr);
        fputs(message, stderr);
        if (!to_continue)
            fputc('\n', stderr);
    }
    b->warn_continued = to_continue;
}

lua_State *tb_lua_newstate(const tb_lua_limits *limits)
{
    tl_budget *b = calloc(1, sizeof *b);
    lua_State *L;
    if (!b)
        return NULL;
    if (limits)
        b->limits = *limits;
    L = lua_newstate(allocate_counted, b);
    if (!L) {
        free(b);
        return NULL;
    }
    b->opened = 1;
    lua_atpanic(L, report_panic);
    lua_setwarnf(L, print_warning, b);
    set_hook(L, b);
    return L;
}

int tb_lua_set_limits(lua_State *L, const tb_lua_limits *limits)
{
    tl_budget *b = get_budget(L);
    if (!b)
        return -1;
    memset(&b->limits, 0, sizeof b->limits);
    if (limits)
        b->limits = *limits;
    b->executed = 0;
    b->trip = TRIP_NONE;
    b->where_known = 0;
    b->refused = 0;
    b->message[0] = 0;
    set_hook(L, b);
    return 0;
}

const char *tb_lua_limit_error(lua_State *L)
{
    tl_budget *b = get_budget(L);
    if (b && b->refused)
        set_trip(b, TRIP_MEMORY);
    return b && b->trip ? b->message : NULL;
}

int tb_lua_usage(lua_State *L, unsigned long long *instructions, size_t *peak_memory)
{
    tl_budget *b = get_budget(L);
    if (instructions)
        *instructions = b ? b->executed : 0;
    if (peak_memory)
        *peak_memory = b ? b->peak : 0;
    return b ? 0 : -1;
}

/* ------------------------------------------------------------ sandbox -- */

#if defined(_WIN32)
#include <stdlib.h>
#define PATH_SIZE 4096
#define resolve_path(path, buf) _fullpath((buf), (path), PATH_SIZE)
#define is_absolute(name) ((name)[0] == '/' || (name)[0] == '\\' || ((name)[0] && (name)[1] == ':'))
#define is_regular_file(path) 1
#else
#include <limits.h>
#include <sys/stat.h>
/* Only regular files: opening a FIFO would wait in C, out of the budget's
   reach, for a writer that never comes. */
static int is_regular_file(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}
#ifdef PATH_MAX
#define PATH_SIZE PATH_MAX
#else
#define PATH_SIZE 4096
#endif
#define resolve_path(path, buf) realpath((path), (buf))
#define is_absolute(name) ((name)[0] == '/')
#endif

/* Push the real path of file `name` (taken from the folder at folder_idx
   when relative) when it lies inside that folder, links and ".." resolved,
   and return it; else push nothing, return NULL and say why. */
static const char *push_path_in_folder(lua_State *L, int folder_idx, const char *name, const char **why)
{
    const char *folder = lua_tostring(L, folder_idx);
    char real[PATH_SIZE];
    size_t n;
    if (!folder) {
        *why = "the sandbox reads no files (it was given no folder)";
        return NULL;
    }
    n = strlen(folder);
    if (is_absolute(name))
        lua_pushstring(L, name);
    else
        lua_pushfstring(L, "%s/%s", folder, name);
    if (!resolve_path(lua_tostring(L, -1), real)) {
        /* missing: say "outside" when the name alone says so, and whether
           a file outside exists stays unsaid */
        const char *path = lua_tostring(L, -1), *p;
        int outside = strncmp(path, folder, n) != 0;
        *why = strerror(errno);
        for (p = path; *p && !outside; ++p)
            outside = p[0] == '.' && p[1] == '.' && (p == path || p[-1] == '/') && (!p[2] || p[2] == '/');
        if (outside)
            *why = "outside the scene's folder (the sandbox reads files only there)";
        lua_pop(L, 1);
        return NULL;
    }
    lua_pop(L, 1);
    if (strncmp(real, folder, n) || !(real[n] == '/' || (n && folder[n - 1] == '/'))) {
        *why = "outside the scene's folder (the sandbox reads files only there)";
        return NULL;
    }
    if (!is_regular_file(real)) {
        *why = "not a regular file";
        return NULL;
    }
    return lua_pushstring(L, real);
}

/* require(name): "tumble" and the safe libraries, or NAME.lua (dots are
   folders) or NAME/init.lua in the scene's folder, loaded as text once.
   Upvalues: the table of loaded modules, the folder. */
static int sandbox_require(lua_State *L)
{
    static const char *const forms[] = { "%s.lua", "%s/init.lua" };
    const char *name = luaL_checkstring(L, 1), *path = NULL, *why = NULL, *first_why = NULL;
    size_t i, n = strlen(name);
    int ok = n > 0 && n < 256, k;
    lua_settop(L, 1);
    lua_pushvalue(L, 1);
    if (lua_rawget(L, lua_upvalueindex(1)) != LUA_TNIL)
        return 1;
    lua_pop(L, 1);
    for (i = 0; i < n && ok; ++i) {
        const char c = name[i];
        ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
             (c == '.' && i > 0 && i + 1 < n && name[i + 1] != '.');
    }
    if (!ok)
        return luaL_error(L, "require: bad module name '%s' (letters, digits, '_', '-', and dots between them)",
                          name);
    luaL_gsub(L, name, ".", "/"); /* 2 */
    for (k = 0; k < 2 && !path; ++k) {
        lua_pushfstring(L, forms[k], lua_tostring(L, 2));
        path = push_path_in_folder(L, lua_upvalueindex(2), lua_tostring(L, -1), &why);
        if (!first_why)
            first_why = why;
        if (path)
            lua_remove(L, -2);
        else
            lua_pop(L, 1);
    }
    if (!path)
        return luaL_error(L, "require: no module '%s' in the scene's folder (%s.lua: %s)", name, lua_tostring(L, 2),
                          first_why);
    /* 3: the path */
    if (luaL_loadfilex(L, path, "t") != LUA_OK)
        return lua_error(L);
    lua_pushvalue(L, 1);
    lua_pushvalue(L, 3);
    lua_call(L, 2, 1);
    if (lua_isnil(L, -1)) {
        lua_pop(L, 1);
        lua_pushboolean(L, 1);
    }
    lua_pushvalue(L, 1);
    lua_pushvalue(L, -2);
    lua_rawset(L, lua_upvalueindex(1));
    lua_pushvalue(L, 3);
    return 2;
}

/* Call the function in upvalue 1 with every argument; return what it does. */
static int call_original(lua_State *L)
{
    lua_pushvalue(L, lua_upvalueindex(1));
    lua_insert(L, 1);
    lua_call(L, lua_gettop(L) - 1, LUA_MULTRET);
    return lua_gettop(L);
}

/* io.open(name [, "r" | "rb"]) and io.lines(name, ...): files in the
   folder only, for reading. Upvalues: the io library's function, the folder. */
static int sandbox_io_open(lua_State *L)
{
    const char *name = luaL_checkstring(L, 1), *mode = luaL_optstring(L, 2, "r"), *why = NULL;
    if (strcmp(mode, "r") && strcmp(mode, "rb"))
        return luaL_error(L, "io.open: the sandbox opens files for reading only (mode 'r' or 'rb', not '%s')", mode);
    lua_settop(L, 2);
    if (!push_path_in_folder(L, lua_upvalueindex(2), name, &why)) {
        luaL_pushfail(L);
        lua_pushfstring(L, "%s: %s", name, why);
        return 2;
    }
    lua_replace(L, 1);
    return call_original(L);
}

static int sandbox_io_lines(lua_State *L)
{
    const char *name = luaL_checkstring(L, 1), *why = NULL;
    if (!push_path_in_folder(L, lua_upvalueindex(2), name, &why))
        return luaL_error(L, "io.lines: %s: %s", name, why);
    lua_replace(L, 1);
    return call_original(L);
}

/* load(chunk [, name [, mode [, env]]]): text only. */
static int sandbox_load(lua_State *L)
{
    const char *mode = luaL_optstring(L, 3, "t");
    if (strcmp(mode, "t"))
        return luaL_error(L, "load: the sandbox loads text chunks only (mode 't', not '%s')", mode);
    if (lua_gettop(L) < 3)
        lua_settop(L, 3);
    lua_pushliteral(L, "t");
    lua_replace(L, 3);
    return call_original(L);
}

/* string.find, match, gmatch and gsub in the sandbox: Lua's matcher runs
   in C, where the instruction budget cannot stop it, and with q
   repetitions that backtrack ('*', '+', '-') it may try about n^(q + 1)
   positions on a subject of n bytes (n^q when anchored with '^'): a single
   repetition on 1e5 bytes passes, two on 2 KB, an anchored trim on 2 KB. Patterns whose bound passes
   PATTERN_WORK are refused with the reason (test_sandbox.
   costly_patterns_are_refused); a plain find and patterns without
   repetitions pass untouched. Upvalues: the string library's function,
   and whether it is find (whose fourth argument asks for a plain find). */
#define PATTERN_WORK 1e10
static int sandbox_pattern(lua_State *L)
{
    size_t n, m, k;
    const char *pattern = (luaL_checklstring(L, 1, &n), luaL_checklstring(L, 2, &m));
    double work = m > 0 && pattern[0] == '^' ? 1 : (double)n + 1; /* anchored: one start */
    int repeats = 0, in_set = 0;
    if (lua_toboolean(L, lua_upvalueindex(2)) && lua_toboolean(L, 4))
        return call_original(L); /* string.find(s, p, init, true): no pattern */
    for (k = 0; k < m; ++k) {
        const char c = pattern[k];
        if (c == '%' && k + 1 < m) {
            if (!in_set && (pattern[k + 1] == 'b' || pattern[k + 1] == 'f'))
                k += 2; /* %bxy, %f[set]: no repetition of their own */
            else
                ++k;
        } else if (in_set) {
            in_set = c != ']' || pattern[k - 1] == '[' || (pattern[k - 1] == '^' && pattern[k - 2] == '[');
        } else if (c == '[') {
            in_set = 1;
        } else if ((c == '*' || c == '+' || c == '-') && k > 0) {
            ++repeats;
            work *= (double)n + 1;
        }
    }
    if (repeats > 0 && work > PATTERN_WORK)
        return luaL_error(L, "a pattern with %d repetition%s on a subject of %I bytes: the sandbox refuses "
                             "matches that could take more than 1e10 steps (run with --trust to allow it)",
                          repeats, repeats == 1 ? "" : "s", (lua_Integer)n);
    return call_original(L);
}

/* setmetatable(t, mt) with no __gc in mt: finalizers run with the count
   hook off, so no budget could stop a loop in one. Lua marks a table for
   finalization only when its metatable has __gc at this call, so a __gc
   added to mt afterwards never runs. */
static int sandbox_setmetatable(lua_State *L)
{
    if (lua_type(L, 2) == LUA_TTABLE) {
        lua_pushliteral(L, "__gc");
        if (lua_rawget(L, 2) != LUA_TNIL)
            return luaL_error(L, "setmetatable: the sandbox allows no __gc metamethod (finalizers run outside "
                                 "the instruction budget)");
        lua_pop(L, 1);
    }
    return call_original(L);
}

static int sandbox_collectgarbage(lua_State *L)
{
    static const char *const allowed[] = { "collect", "count", "step", "isrunning", NULL };
    const char *option = luaL_optstring(L, 1, "collect");
    int k;
    for (k = 0; allowed[k] && strcmp(allowed[k], option); ++k)
        ;
    if (!allowed[k])
        return luaL_error(L, "collectgarbage: the sandbox allows only \"collect\", \"count\", \"step\" and "
                             "\"isrunning\" (not \"%s\")", option);
    return call_original(L);
}

/* After a budget has run out, the error leaves through the count hook, and
   Lua keeps hooks off until the error reaches a pcall: a message handler
   (xpcall) and the __close handlers of a coroutine killed by the error
   (closed by coroutine.close or coroutine.wrap) would run without a count.
   So then the sandbox's xpcall passes the error on without calling the
   handler, and its coroutine.close and coroutine.wrap do not close. */
static int is_over_budget(lua_State *L)
{
    tl_budget *b = get_budget(L);
    return b && b->trip;
}

/* The message handler xpcall gets: upvalue 1 is the script's. */
static int sandbox_handler(lua_State *L)
{
    if (is_over_budget(L))
        return 1;
    lua_pushvalue(L, lua_upvalueindex(1));
    lua_insert(L, 1);
    lua_call(L, lua_gettop(L) - 1, 1);
    return 1;
}

static int sandbox_xpcall(lua_State *L)
{
    luaL_checktype(L, 2, LUA_TFUNCTION);
    lua_pushvalue(L, 2);
    lua_pushcclosure(L, sandbox_handler, 1);
    lua_replace(L, 2);
    return call_original(L);
}

static int sandbox_coroutine_close(lua_State *L)
{
    tl_budget *b = get_budget(L);
    if (b && b->trip) {
        lua_pushstring(L, b->message);
        return lua_error(L);
    }
    return call_original(L);
}

/* The function coroutine.wrap returns (as Lua's own, but closing the dead
   coroutine only while the budgets hold); upvalue 1: the coroutine. */
static int sandbox_wrapped(lua_State *L)
{
    lua_State *co = lua_tothread(L, lua_upvalueindex(1));
    int n = lua_gettop(L), results, status;
    if (!lua_checkstack(co, n))
        return luaL_error(L, "too many arguments to resume");
    lua_xmove(L, co, n);
    status = lua_resume(co, L, n, &results);
    n = results;
    if (status == LUA_OK || status == LUA_YIELD) {
        if (!lua_checkstack(L, n + 1)) {
            lua_pop(co, n);
            return luaL_error(L, "too many results to resume");
        }
        lua_xmove(co, L, n);
        return n;
    }
    lua_xmove(co, L, 1); /* the error */
    status = lua_status(co);
    if (status != LUA_OK && status != LUA_YIELD && !is_over_budget(L)) {
        status = lua_resetthread(co); /* close its to-be-closed variables */
        lua_xmove(co, L, 1);
    }
    if (status != LUA_ERRMEM && lua_type(L, -1) == LUA_TSTRING) {
        luaL_where(L, 1);
        lua_insert(L, -2);
        lua_concat(L, 2);
    }
    return lua_error(L);
}

static int sandbox_coroutine_wrap(lua_State *L)
{
    lua_State *co;
    luaL_checktype(L, 1, LUA_TFUNCTION);
    co = lua_newthread(L);
    lua_pushvalue(L, 1);
    lua_xmove(L, co, 1);
    lua_pushcclosure(L, sandbox_wrapped, 1);
    return 1;
}

/* Replace global `name` (in the table at g) by f with the old value as its
   upvalue (and the value at extra_idx as the second, if extra_idx). */
static void wrap_function(lua_State *L, int g, const char *name, lua_CFunction f, int extra_idx)
{
    lua_getfield(L, g, name);
    if (extra_idx)
        lua_pushvalue(L, extra_idx);
    lua_pushcclosure(L, f, extra_idx ? 2 : 1);
    lua_setfield(L, g, name);
}

/* Open library `open` as global `name` and as loaded[name]; leaves it on
   the stack. */
static void open_library(lua_State *L, int g, int loaded, const char *name, lua_CFunction open)
{
    lua_pushcfunction(L, open);
    lua_call(L, 0, 1);
    lua_pushvalue(L, -1);
    lua_setfield(L, g, name);
    lua_pushvalue(L, -1);
    lua_setfield(L, loaded, name);
}

/* Copy the fields `names` of the table at from into the table on top. */
static void copy_fields(lua_State *L, int from, const char *const names[])
{
    int k;
    for (k = 0; names[k]; ++k) {
        lua_getfield(L, from, names[k]);
        lua_setfield(L, -2, names[k]);
    }
}

/* Under lua_pcall: argument 1 is the folder as a light userdata (a C
   string, or NULL). */
static int open_sandbox(lua_State *L)
{
    static const char *const removed[] = { "dofile", "loadfile", "warn", NULL };
    static const char *const os_names[] = { "clock", "time", "date", "difftime", NULL };
    const char *folder = lua_touserdata(L, 1);
    char real[PATH_SIZE];
    int g, loaded, folder_idx, k;
    lua_settop(L, 0);
    if (folder) {
        if (!resolve_path(folder, real))
            return luaL_error(L, "tumble: the sandbox's folder '%s': %s", folder, strerror(errno));
        lua_pushstring(L, real);
    } else {
        lua_pushnil(L);
    }
    folder_idx = 1;
    lua_newtable(L); /* 2: the loaded modules */
    loaded = 2;
    lua_newtable(L); /* 3: the new globals */
    g = 3;
    lua_pushvalue(L, g);
    lua_rawseti(L, LUA_REGISTRYINDEX, LUA_RIDX_GLOBALS);

    lua_pushcfunction(L, luaopen_base); /* fills the globals, as _G */
    lua_call(L, 0, 1);
    lua_setfield(L, loaded, "_G");
    for (k = 0; removed[k]; ++k) {
        lua_pushnil(L);
        lua_setfield(L, g, removed[k]);
    }
    wrap_function(L, g, "load", sandbox_load, 0);
    wrap_function(L, g, "setmetatable", sandbox_setmetatable, 0);
    wrap_function(L, g, "collectgarbage", sandbox_collectgarbage, 0);
    wrap_function(L, g, "xpcall", sandbox_xpcall, 0);

    open_library(L, g, loaded, LUA_STRLIBNAME, luaopen_string);
    lua_pushnil(L);
    lua_setfield(L, -2, "dump");
    {
        static const char *const matchers[] = { "find", "match", "gmatch", "gsub", NULL };
        const int lib = lua_gettop(L);
        for (k = 0; matchers[k]; ++k) {
            lua_getfield(L, lib, matchers[k]);
            lua_pushboolean(L, k == 0);
            lua_pushcclosure(L, sandbox_pattern, 2);
            lua_setfield(L, lib, matchers[k]);
        }
    }
    lua_pop(L, 1);
    lua_pushliteral(L, ""); /* lock the strings' metatable, which every string shares */
    if (lua_getmetatable(L, -1)) {
        lua_pushliteral(L, "string");
        lua_setfield(L, -2, "__metatable");
        lua_pop(L, 1);
    }
    lua_pop(L, 1);
    open_library(L, g, loaded, LUA_TABLIBNAME, luaopen_table);
    lua_pop(L, 1);
    open_library(L, g, loaded, LUA_MATHLIBNAME, luaopen_math);
    lua_pop(L, 1);
    open_library(L, g, loaded, LUA_UTF8LIBNAME, luaopen_utf8);
    lua_pop(L, 1);
    open_library(L, g, loaded, LUA_COLIBNAME, luaopen_coroutine);
    wrap_function(L, lua_gettop(L), "close", sandbox_coroutine_close, 0);
    lua_pushcfunction(L, sandbox_coroutine_wrap);
    lua_setfield(L, -2, "wrap");
    lua_pop(L, 1);

    lua_pushcfunction(L, luaopen_os); /* os: the clock and the calendar */
    lua_call(L, 0, 1);
    lua_newtable(L);
    copy_fields(L, lua_gettop(L) - 1, os_names);
    lua_pushvalue(L, -1);
    lua_setfield(L, g, LUA_OSLIBNAME);
    lua_setfield(L, loaded, LUA_OSLIBNAME);
    lua_pop(L, 1);

    lua_pushcfunction(L, luaopen_io); /* io: reading in the folder */
    lua_call(L, 0, 1);
    lua_newtable(L);
    lua_getfield(L, -2, "open");
    lua_pushvalue(L, folder_idx);
    lua_pushcclosure(L, sandbox_io_open, 2);
    lua_setfield(L, -2, "open");
    lua_getfield(L, -2, "lines");
    lua_pushvalue(L, folder_idx);
    lua_pushcclosure(L, sandbox_io_lines, 2);
    lua_setfield(L, -2, "lines");
    lua_pushvalue(L, -1);
    lua_setfield(L, g, LUA_IOLIBNAME);
    lua_setfield(L, loaded, LUA_IOLIBNAME);
    lua_pop(L, 1);

    luaL_requiref(L, "tumble", luaopen_tumble, 0);
    lua_setfield(L, loaded, "tumble");
    lua_pushvalue(L, loaded);
    lua_pushvalue(L, folder_idx);
    lua_pushcclosure(L, sandbox_require, 2);
    lua_setfield(L, g, "require");
    return 0;
}

int tb_lua_sandbox(lua_State *L, const char *folder)
{
    if (!lua_checkstack(L, 2))
        return LUA_ERRMEM;
    lua_pushcfunction(L, open_sandbox);
    lua_pushlightuserdata(L, (void *)folder);
    return lua_pcall(L, 1, 0, 0);
}
