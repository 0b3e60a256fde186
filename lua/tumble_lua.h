/* tumble_lua.h: the Lua 5.4 binding of tumble, written against the public
   C API only. Lua scripts `require "tumble"`; hosts preload it with
   luaL_requiref(L, "tumble", luaopen_tumble, 0).

   Lua force and field callbacks run inside the core's step, so a host that
   steps a world made in Lua goes through tb_lua_step (or
   tb_lua_tracer_velocities), which tells the callbacks which Lua thread and
   stack slot the world lives in. Calling tb_world_step directly on such a
   world makes its Lua callbacks fail cleanly with TB_ERR_CALLBACK. */
#ifndef TUMBLE_LUA_H
#define TUMBLE_LUA_H

#include <lua.h>
#include <signal.h>
#include <stddef.h>
#include "tumble.h"

#if defined(TUMBLE_SHARED) && !defined(_WIN32)
#  define TB_LUA_API __attribute__((visibility("default")))
#elif defined(TUMBLE_SHARED) && defined(TUMBLE_LUA_BUILDING)
#  define TB_LUA_API __declspec(dllexport)
#elif defined(TUMBLE_SHARED)
#  define TB_LUA_API __declspec(dllimport)
#else
#  define TB_LUA_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Opens the module: returns the table with tumble.world, tumble.integrators. */
TB_LUA_API int luaopen_tumble(lua_State *L);

/* The world of the tumble.world userdata at idx; raises a Lua error if the
   value is not a world or the world was closed. */
TB_LUA_API tb_world *tb_lua_check_world(lua_State *L, int idx);

/* The same without raising: NULL unless idx holds an open world. */
TB_LUA_API tb_world *tb_lua_to_world(lua_State *L, int idx);

/* The world's default step in seconds (tumble.world{dt = ...}), or 0 when
   idx holds no open world. */
TB_LUA_API double tb_lua_world_dt(lua_State *L, int idx);

/* tb_world_step and tb_world_tracer_velocities for the world userdata at
   idx, with its Lua callbacks enabled. Never raise a Lua error: failures
   come back as a status, with the reason in tb_world_message(). */
TB_LUA_API tb_status tb_lua_step(lua_State *L, int idx, double h);
TB_LUA_API tb_status tb_lua_tracer_velocities(lua_State *L, int idx, double *velocities);
/* tb_world_energy_with_callbacks for the world at idx: a Lua force that
   returns a number reports it as its potential energy (J). */
TB_LUA_API tb_status tb_lua_energy(lua_State *L, int idx, tb_energy *energy);

/* ---- running scripts that are not trusted ----------------------------------

   A host that runs scene scripts it does not trust makes their state with
   tb_lua_newstate (budgets on instructions and memory) and opens the
   sandbox in it with tb_lua_sandbox (the safe part of the standard
   library). The `tumble` command does both unless given --trust. */

/* Budgets of a Lua state made by tb_lua_newstate. 0 means no limit. */
typedef struct tb_lua_limits {
    /* Lua VM instructions the state may run in all: the script's body,
       every callback and metamethod, in every coroutine; counted in
       batches of 1000, so a run stops at most 1000 past the limit. */
    unsigned long long instructions;
    /* Bytes the state may hold at once: Lua's heap and the memory of the
       worlds made in it (they allocate through the state's allocator). */
    size_t memory;
    /* Optional: while *stop is non-zero the state's Lua code stops as if a
       budget ran out (a signal handler or another thread may set it). It is
       read when the budgets are counted, so only when a budget is set. */
    volatile sig_atomic_t *stop;
} tb_lua_limits;

/* A new Lua state with no library open, held to `limits` (NULL: none).
   When a budget runs out (or *stop is set) the running Lua code raises an
   error, and every further 1 instruction raises it again, so a script's own
   pcall cannot swallow it; tb_lua_limit_error() then says which. A memory
   request past the budget fails as Lua's "not enough memory", and ends the
   run when it fails again after Lua's emergency collection, or at once
   when a world asked for it. Finalizers (__gc) run without the
   instruction count: a sandbox allows none (tb_lua_sandbox). lua_close
   releases everything. NULL when out of memory. */
TB_LUA_API lua_State *tb_lua_newstate(const tb_lua_limits *limits);

/* Replace the limits of a state made by tb_lua_newstate and start counting
   afresh: instructions from 0, a run-out budget cleared. Returns 0, or -1
   when L was not made by tb_lua_newstate. */
TB_LUA_API int tb_lua_set_limits(lua_State *L, const tb_lua_limits *limits);

/* NULL while every budget holds; else why the state's code was stopped,
   e.g. "instruction budget exceeded: more than 1000000 Lua instructions
   (at scene.lua:4)". Also NULL for states not made by tb_lua_newstate. */
TB_LUA_API const char *tb_lua_limit_error(lua_State *L);

/* What the state has used: instructions run (in batches of 1000; 0 when
   no budget is set, as they are not counted then) and the most bytes held
   at once. Returns -1 (and zeros) when L was not made by tb_lua_newstate. */
TB_LUA_API int tb_lua_usage(lua_State *L, unsigned long long *instructions, size_t *peak_memory);

/* Make L's globals a sandbox, in a fresh global table: the base library
   without dofile, loadfile, warn and the binary mode of load,
   setmetatable refusing __gc, collectgarbage limited to "collect",
   "count", "step" and "isrunning"; string (without string.dump), table,
   math, utf8, coroutine; os.clock, os.time, os.date, os.difftime;
   io.open (reading only) and io.lines, and require, both reading only in
   `folder` and below it (relative names are taken from `folder`; NULL: no
   files at all); require "tumble" gives the module. Chunks load as text
   only. The strings' metatable is locked (getmetatable("") is "string").
   Call it on a state of its own, made by tb_lua_newstate, before loading
   the script. Never raises: returns LUA_OK, or an error status with the
   message on the stack. */
TB_LUA_API int tb_lua_sandbox(lua_State *L, const char *folder);

#ifdef __cplusplus
}
#endif
#endif
