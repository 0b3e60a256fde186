/* tumble_lua.c: the Lua 5.4 module `tumble`, over the public C API only.

   Types are full userdata with locked metatables: tumble.world owns a
   tb_world; tumble.particle, tumble.tracer, tumble.spring, tumble.body,
   tumble.shape, tumble.field and tumble.force are handles holding a value
   id and, as user value, their world (so a handle keeps its world alive and
   every call checks the id).

   The world's user value is a table holding its Lua callbacks under
   integer keys and the tables handed to them (reused from call to call).
   Callbacks run under lua_pcall with a traceback handler inside a protected
   C function, so no Lua error ever unwinds through the core.

   Names: Lua reserves the lua_ and luaL_ prefixes, so the binding's types
   are tl_*. Static functions carry no prefix: a function Lua calls is named
   after its Lua name (module_world for tumble.world, world_step for
   world:step, body_pos for body:pos, handle_* for what every handle has,
   world_gc for a metamethod); every other function starts with a verb
   (check_ raises unless the value is valid, read_ requires a value, opt_
   takes one if present, push_ leaves one on the Lua stack, to_ converts).
   The same rule holds in tumble_main.c. */
#include "tumble_lua.h"

#include <lauxlib.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define WORLD_MT "tumble.world"

enum tl_handle_kind { H_PARTICLE, H_TRACER, H_SPRING, H_FIELD, H_FORCE, H_BODY, H_SHAPE, H_KINDS };
static const char *const handle_mt[H_KINDS] = {
    "tumble.particle", "tumble.tracer", "tumble.spring", "tumble.field", "tumble.force", "tumble.body",
    "tumble.shape"
};

typedef struct tl_world {
    tb_world *world;  /* NULL once closed */
    double dt;        /* default step, s */
    lua_State *L;     /* while tb_lua_step runs: the thread stepping ... */
    int index;        /* ... and the world's absolute stack index there */
    int next_key;     /* next callback key in the user value table */
} tl_world;

typedef struct tl_handle {
    int kind;
    uint32_t index1, generation;
    int key;          /* fields and forces written in Lua: their callback key */
} tl_handle;

/* What a C callback needs to find its Lua function. Lives as a userdata in
   the world's user value table, so its address is stable. */
typedef struct tl_callback {
    tl_world *owner;
    int key;
} tl_callback;

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

static tl_world *check_world(lua_State *L, int idx)
{
    tl_world *lw = luaL_checkudata(L, idx, WORLD_MT);
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
    h->kind = kind;
    h->index1 = index1;
    h->generation = generation;
    h->key = key;
    lua_pushvalue(L, world_idx);
    lua_setiuservalue(L, -2, 1);
    luaL_setmetatable(L, handle_mt[kind]);
}

/* The handle at idx (of `kind`) and its open world. */
static tl_handle *check_handle(lua_State *L, int idx, int kind, tl_world **lw)
{
    tl_handle *h = luaL_checkudata(L, idx, handle_mt[kind]);
    lua_getiuservalue(L, idx, 1);
    *lw = lua_touserdata(L, -1);
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

/* Forget a Lua callback of the world at world_idx: function and record. */
static void forget_callback(lua_State *L, int world_idx, int key)
{
    lua_getiuservalue(L, world_idx, 1);
    lua_pushnil(L);
    lua_rawseti(L, -2, key);
    lua_pushnil(L);
    lua_rawseti(L, -2, -key);
    lua_pop(L, 1);
}

static int handle_remove(lua_State *L)
{
    tl_handle *h;
    int kind, k;
    tl_world *lw;
    tb_status st = TB_OK;
    for (kind = 0; kind < H_KINDS && !luaL_testudata(L, 1, handle_mt[kind]); ++kind)
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
        forget_callback(L, lua_gettop(L), h->key);
        lua_pop(L, 1);
    }
    return 0;
}

static int handle_id(lua_State *L)
{
    tl_handle *h = NULL;
    int kind;
    for (kind = 0; kind < H_KINDS && !h; ++kind)
        h = luaL_testudata(L, 1, handle_mt[kind]);
    if (!h)
        return luaL_typeerror(L, 1, "tumble handle");
    lua_pushinteger(L, (lua_Integer)h->index1);
    lua_pushinteger(L, (lua_Integer)h->generation);
    return 2;
}

static int handle_tostring(lua_State *L)
{
    tl_handle *h = lua_touserdata(L, 1);
    lua_pushfstring(L, "%s %d.%d", handle_mt[h->kind], (int)h->index1, (int)h->generation);
    return 1;
}

static int handle_eq(lua_State *L)
{
    tl_handle *a = lua_touserdata(L, 1), *b = lua_touserdata(L, 2);
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

/* ------------------------------------------------ callbacks into Lua -- */

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

static void fill_array(lua_State *L, int table_idx, const double *values, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        lua_pushnumber(L, values ? values[i] : 0.0);
        lua_rawseti(L, table_idx, (lua_Integer)i + 1);
    }
}

/* Add the numbers of the table at idx, 1..n, to out. */
static void add_from_table(lua_State *L, int table_idx, double *out, size_t n, const char *what)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        int isnum;
        double v;
        lua_rawgeti(L, table_idx, (lua_Integer)i + 1);
        v = lua_tonumberx(L, -1, &isnum);
        if (!isnum)
            luaL_error(L, "%s[%d] is %s, not a number", what, (int)i + 1, luaL_typename(L, -1));
        out[i] += v;
        lua_pop(L, 1);
    }
}

/* What run_force and run_field get through lua_pcall, as light userdata. */
typedef struct tl_force_call { tl_callback *cb; const tb_force_args *args; } tl_force_call;
typedef struct tl_field_call { tl_callback *cb; const tb_field_args *args; } tl_field_call;

/* Call a Lua force, under lua_pcall: (call record, the world's table).
   fn(t, state, forces, body_forces, body_torques): state = {n, pos, vel,
   mass, bodies = {n, pos, rot, vel, omega, mass}} in flat arrays; forces,
   body_forces and body_torques flat arrays of zeros to add to. */
static int run_force(lua_State *L)
{
    tl_force_call *c = lua_touserdata(L, 1);
    const tb_force_args *a = c->args;
    const int t = 2; /* the world's table */
    int state;
    lua_rawgeti(L, t, c->cb->key);
    lua_pushnumber(L, a->time);
    state = get_scratch_table(L, t, "force_state");
    lua_pushinteger(L, (lua_Integer)a->count);
    lua_setfield(L, state, "n");
    fill_array(L, get_scratch_table(L, state, "pos"), a->positions, 3 * a->count);
    fill_array(L, get_scratch_table(L, state, "vel"), a->velocities, 3 * a->count);
    fill_array(L, get_scratch_table(L, state, "mass"), a->masses, a->count);
    lua_settop(L, state);
    {
        int bodies = get_scratch_table(L, state, "bodies");
        lua_pushinteger(L, (lua_Integer)a->body_count);
        lua_setfield(L, bodies, "n");
        fill_array(L, get_scratch_table(L, bodies, "pos"), a->body_positions, 3 * a->body_count);
        fill_array(L, get_scratch_table(L, bodies, "rot"), a->body_orientations, 4 * a->body_count);
        fill_array(L, get_scratch_table(L, bodies, "vel"), a->body_velocities, 3 * a->body_count);
        fill_array(L, get_scratch_table(L, bodies, "omega"), a->body_angular_velocities, 3 * a->body_count);
        fill_array(L, get_scratch_table(L, bodies, "mass"), a->body_masses, a->body_count);
        lua_settop(L, state);
    }
    fill_array(L, get_scratch_table(L, t, "force_out"), NULL, 3 * a->count);
    fill_array(L, get_scratch_table(L, t, "body_force_out"), NULL, 3 * a->body_count);
    fill_array(L, get_scratch_table(L, t, "body_torque_out"), NULL, 3 * a->body_count);
    lua_call(L, 5, 0);
    lua_getfield(L, t, "force_out");
    add_from_table(L, lua_gettop(L), a->forces, 3 * a->count, "forces");
    if (a->body_count) {
        lua_getfield(L, t, "body_force_out");
        add_from_table(L, lua_gettop(L), a->body_forces, 3 * a->body_count, "body_forces");
        lua_getfield(L, t, "body_torque_out");
        add_from_table(L, lua_gettop(L), a->body_torques, 3 * a->body_count, "body_torques");
    }
    return 0;
}

/* Call a Lua field, under lua_pcall: (call record, the world's table).
   fn(t, pos, vel): pos flat positions, vel a flat array of 3n zeros to add to. */
static int run_field(lua_State *L)
{
    tl_field_call *c = lua_touserdata(L, 1);
    const tb_field_args *a = c->args;
    const int t = 2; /* the world's table */
    int vel;
    lua_rawgeti(L, t, c->cb->key);
    lua_pushnumber(L, a->time);
    fill_array(L, get_scratch_table(L, t, "field_pos"), a->positions, 3 * a->count);
    vel = get_scratch_table(L, t, "field_out");
    fill_array(L, vel, NULL, 3 * a->count);
    lua_call(L, 3, 0);
    lua_getfield(L, t, "field_out");
    add_from_table(L, lua_gettop(L), a->velocities, 3 * a->count, "vel");
    return 0;
}

/* Run `run` (run_force or run_field) on the thread stepping the world, with
   a traceback handler; a Lua error becomes TB_ERR_CALLBACK and its first
   line the message. */
static tb_status run_protected(tl_callback *cb, lua_CFunction run, void *call, char *message)
{
    lua_State *L = cb->owner->L;
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
    /* Stack indices belong to a call frame: fetch the world's table here, in
       the frame that tb_lua_step was called from, and hand it to `run`. */
    lua_getiuservalue(L, cb->owner->index, 1);
    rc = lua_pcall(L, 2, 0, top + 1);
    if (rc != LUA_OK)
        copy_first_line(message, TB_MESSAGE_SIZE, lua_tostring(L, -1));
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

/* Store the function at fn_idx in the world's table; returns the record. */
static tl_callback *keep_callback(lua_State *L, int world_idx, tl_world *lw, int fn_idx)
{
    tl_callback *cb;
    int key = ++lw->next_key;
    lua_getiuservalue(L, world_idx, 1);
    lua_pushvalue(L, fn_idx);
    lua_rawseti(L, -2, key);
    cb = lua_newuserdatauv(L, sizeof *cb, 0);
    cb->owner = lw;
    cb->key = key;
    lua_rawseti(L, -2, -key);
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
    lw->dt = dt;
    lua_newtable(L);
    lua_setiuservalue(L, -2, 1);
    luaL_setmetatable(L, WORLD_MT);
    /* The world's memory counts against the Lua state's allocator. */
    def.allocator.realloc = (tb_realloc_fn *)lua_getallocf(L, &def.allocator.user);
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
    tl_world *lw = luaL_checkudata(L, 1, WORLD_MT);
    if (lw->L)
        return luaL_error(L, "tumble: cannot close a world while it is stepping");
    tb_world_destroy(lw->world);
    lw->world = NULL;
    return 0;
}

static int world_gc(lua_State *L)
{
    tl_world *lw = luaL_checkudata(L, 1, WORLD_MT);
    tb_world_destroy(lw->world);
    lw->world = NULL;
    return 0;
}

static int world_tostring(lua_State *L)
{
    tl_world *lw = luaL_checkudata(L, 1, WORLD_MT);
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

/* world:contacts{ hertz, damping_ratio, max_push, restitution_threshold,
   slop, velocity_iterations, velocity_tolerance, position_iterations,
   stack_iterations, particle_radius, particle_friction,
   particle_restitution, sleep_speed, sleep_time }:
   change the contact settings (sleep_time = math.huge: never sleep) */
static const char *const contact_options[] = { "hertz", "damping_ratio", "max_push", "restitution_threshold",
                                               "slop", "velocity_iterations", "velocity_tolerance",
                                               "position_iterations", "stack_iterations",
                                               "particle_radius", "particle_friction", "particle_restitution",
                                               "sleep_speed", "sleep_time", NULL };

static int world_contacts(lua_State *L)
{
    tl_world *lw = check_world(L, 1);
    tb_contact_settings cs = tb_world_contact_settings(lw->world);
    double vi = cs.velocity_iterations, pi = cs.position_iterations, si = cs.stack_iterations;
    check_options(L, 2, "world:contacts", contact_options);
    opt_number(L, 2, "hertz", "world:contacts", &cs.hertz);
    opt_number(L, 2, "damping_ratio", "world:contacts", &cs.damping_ratio);
    opt_number(L, 2, "max_push", "world:contacts", &cs.max_push);
    opt_number(L, 2, "restitution_threshold", "world:contacts", &cs.restitution_threshold);
    opt_number(L, 2, "slop", "world:contacts", &cs.slop);
    opt_number(L, 2, "velocity_iterations", "world:contacts", &vi);
    opt_number(L, 2, "velocity_tolerance", "world:contacts", &cs.velocity_tolerance);
    opt_number(L, 2, "position_iterations", "world:contacts", &pi);
    opt_number(L, 2, "stack_iterations", "world:contacts", &si);
    opt_number(L, 2, "particle_radius", "world:contacts", &cs.particle_radius);
    opt_number(L, 2, "particle_friction", "world:contacts", &cs.particle_friction);
    opt_number(L, 2, "particle_restitution", "world:contacts", &cs.particle_restitution);
    opt_number(L, 2, "sleep_speed", "world:contacts", &cs.sleep_speed);
    opt_number(L, 2, "sleep_time", "world:contacts", &cs.sleep_time);
    cs.velocity_iterations = vi >= 0 && vi < 1e6 ? (int)vi : 0;
    cs.position_iterations = pi >= 0 && pi < 1e6 ? (int)pi : -1;
    cs.stack_iterations = si >= 0 && si < 1e6 ? (int)si : -1;
    if (tb_world_set_contact_settings(lw->world, &cs) != TB_OK)
        return raise_world_error(L, lw, "world:contacts");
    return 0;
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
        lua_pushinteger(L, (lua_Integer)ev[i].a.index1);
        lua_setfield(L, -2, "a");
        if (!TB_ID_IS_NULL(ev[i].b)) {
            lua_pushinteger(L, (lua_Integer)ev[i].b.index1);
            lua_setfield(L, -2, "b");
        }
        if (!TB_ID_IS_NULL(ev[i].particle)) {
            lua_pushinteger(L, (lua_Integer)ev[i].particle.index1);
            lua_setfield(L, -2, "particle");
        }
        lua_pushnumber(L, ev[i].speed);
        lua_setfield(L, -2, "speed");
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
            forget_callback(L, 1, key);
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
        forget_callback(L, 1, cb->key);
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

static int world_energy(lua_State *L)
{
    tb_energy e = tb_world_energy(check_world(L, 1)->world);
    lua_createtable(L, 0, 5);
    lua_pushnumber(L, e.kinetic);
    lua_setfield(L, -2, "kinetic");
    lua_pushnumber(L, e.rotational);
    lua_setfield(L, -2, "rotational");
    lua_pushnumber(L, e.gravity);
    lua_setfield(L, -2, "gravity");
    lua_pushnumber(L, e.spring);
    lua_setfield(L, -2, "spring");
    lua_pushnumber(L, e.total);
    lua_setfield(L, -2, "total");
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

static const luaL_Reg world_methods[] = {
    { "particle", world_particle }, { "tracer", world_tracer }, { "spring", world_spring },
    { "body", world_body }, { "angular_momentum", world_angular_momentum },
    { "shape", world_shape }, { "contacts", world_contacts }, { "events", world_events },
    { "drag", world_drag }, { "field", world_field }, { "force", world_force },
    { "step", world_step }, { "time", world_time }, { "dt", world_dt }, { "set_dt", world_set_dt },
    { "integrator", world_integrator }, { "set_integrator", world_set_integrator },
    { "set_tolerance", world_set_tolerance }, { "set_guard", world_set_guard },
    { "auto_choice", world_auto_choice },
    { "gravity", world_gravity }, { "set_gravity", world_set_gravity },
    { "energy", world_energy }, { "momentum", world_momentum }, { "counts", world_counts },
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
        plain_methods
    };
    int k;
    create_metatable(L, WORLD_MT, world_methods);
    lua_pushcfunction(L, world_gc);
    lua_setfield(L, -2, "__gc");
    lua_pushcfunction(L, world_close);
    lua_setfield(L, -2, "__close");
    lua_pushcfunction(L, world_tostring);
    lua_setfield(L, -2, "__tostring");
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
    return 1;
}

/* ------------------------------------------------------ host entries -- */

tb_world *tb_lua_check_world(lua_State *L, int idx)
{
    return check_world(L, idx)->world;
}

tb_world *tb_lua_to_world(lua_State *L, int idx)
{
    tl_world *lw = luaL_testudata(L, idx, WORLD_MT);
    return lw ? lw->world : NULL;
}

double tb_lua_world_dt(lua_State *L, int idx)
{
    tl_world *lw = luaL_testudata(L, idx, WORLD_MT);
    return lw && lw->world ? lw->dt : 0;
}

/* Run a core call with the world's Lua callbacks pointed at (L, idx). */
static tb_status run_with_callbacks(lua_State *L, int idx, double h, double *velocities)
{
    tl_world *lw = luaL_testudata(L, idx, WORLD_MT);
    tb_status st;
    if (!lw || !lw->world)
        return TB_ERR_ARGUMENT;
    if (lw->L) /* nested: the core refuses it as busy */
        return velocities ? tb_world_tracer_velocities(lw->world, velocities) : tb_world_step(lw->world, h);
    lw->L = L;
    lw->index = lua_absindex(L, idx);
    st = velocities ? tb_world_tracer_velocities(lw->world, velocities) : tb_world_step(lw->world, h);
    lw->L = NULL;
    return st;
}

tb_status tb_lua_step(lua_State *L, int idx, double h)
{
    return run_with_callbacks(L, idx, h, NULL);
}

tb_status tb_lua_tracer_velocities(lua_State *L, int idx, double *velocities)
{
    return run_with_callbacks(L, idx, 0, velocities);
}
