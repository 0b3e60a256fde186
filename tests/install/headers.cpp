// headers.cpp: the public headers compile as C++ (with warnings as errors)
// and link names stay C.
#include <tumble.h>
#include <tumble_lua.h>

int main()
{
    tb_world_def def = tb_default_world_def();
    tb_world *w = nullptr;
    if (tb_world_create(&def, &w, nullptr, 0) != TB_OK)
        return 1;
    tb_world_destroy(w);
    lua_CFunction open = luaopen_tumble; // the binding's entry point links
    return open == nullptr;
}
