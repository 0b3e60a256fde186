/* fuzz_scene.c: a libFuzzer target for scene scripts. The input is run as
   a scene in the sandbox with budgets, as `tumble run` runs one (1e6
   instructions, 32 MiB), and the world it returns is stepped up to 60
   times at its own step. Whatever the script does, the run ends with a
   status: no crash, no leak, no hang, no PANIC. */
#include "tumble_lua.h"

#include <lauxlib.h>
#include <lua.h>
#include <stdint.h>

/* Under lua_pcall, argument 1 the input as a light userdata, 2 its size:
   run it and leave the world (or nil) on the stack. */
static int run_scene(lua_State *L)
{
    const char *text = lua_touserdata(L, 1);
    const size_t size = (size_t)lua_tointeger(L, 2);
    if (luaL_loadbufferx(L, text, size, "=fuzz", "t") != LUA_OK)
        return lua_error(L);
    lua_call(L, 0, 1);
    if (!lua_istable(L, -1))
        return 0;
    lua_getfield(L, -1, "world");
    return 1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    tb_lua_limits limits = { 1000000, 32u << 20, NULL };
    lua_State *L = tb_lua_newstate(&limits);
    int i;
    if (!L)
        return 0;
    if (tb_lua_sandbox(L, NULL) == LUA_OK) {
        lua_pushcfunction(L, run_scene);
        lua_pushlightuserdata(L, (void *)data);
        lua_pushinteger(L, (lua_Integer)size);
        if (lua_pcall(L, 2, 1, 0) == LUA_OK && tb_lua_to_world(L, -1)) {
            const int idx = lua_gettop(L);
            double dt = tb_lua_world_dt(L, idx);
            if (!(dt > 0 && dt <= 1))
                dt = 1.0 / 60;
            for (i = 0; i < 60 && !tb_lua_limit_error(L); ++i)
                if (tb_lua_step(L, idx, dt) != TB_OK)
                    break;
        }
    }
    lua_close(L);
    return 0;
}
