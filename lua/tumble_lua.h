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

#ifdef __cplusplus
}
#endif
#endif
