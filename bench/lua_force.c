/* lua_force.c: what a Lua force callback costs per particle, beside the
   same force in C and the same Lua loop over plain tables.

   The force is the particle part of the guide's example of a Lua force
   (docs/guide.md, section 7): every particle pulled towards the z axis,
   f -= k m (x, y, 0), written as the guide writes it. For 10^4 and 10^5
   particles under symplectic_euler (one force evaluation a step) it times
   a step of the world with the Lua force (through tb_lua_step), with the
   same force in C (tb_world_add_force), and with no force, and prints the
   force's cost per particle per evaluation: the step's time less that of
   the world without it. Beside them, the Lua function called on plain Lua
   tables of the same numbers, without the binding: Lua's own speed, which
   the binding can approach but not beat. Target (issue 24): the Lua force
   at most 80 ns per particle per evaluation.

   The Lua state is a plain one with the standard libraries (a trusted
   host): no budgets, whose count hook slows every Lua instruction
   (docs/command.md). Medians of interleaved repeats (bench.h). */
#define _POSIX_C_SOURCE 200809L
#define BENCH_NAME "bench_lua_force"

#include "bench.h"
#include "tumble.h"
#include "tumble_lua.h"

#include <lauxlib.h>
#include <lualib.h>

#include <stdio.h>
#include <stdlib.h>

#define H (1.0 / 240) /* s */
#define PULL 4.0      /* 1/s^2, the k of the guide's force */

/* The scene and the force, as a scene script writes them; `n` is set
   before it runs. It leaves three worlds of the same particles as globals:
   `w` with the Lua force, `cw` for the same force in C (added by main),
   `plain` with none; and `pure(reps)`, which calls the force's function
   `reps` times on plain Lua tables of the same numbers. */
static const char scene[] =
    "local tumble = require 'tumble'\n"
    "local function place(i) return math.cos(i), math.sin(i), i / n end\n"
    "local function world()\n"
    "  local w = tumble.world{ gravity = {0, 0, 0}, integrator = 'symplectic_euler', dt = 1/240 }\n"
    "  for i = 1, n do\n"
    "    local x, y, z = place(i)\n"
    "    w:particle{ pos = {x, y, z}, vel = {0, 0, 0.1}, mass = 1 + i % 3 }\n"
    "  end\n"
    "  return w\n"
    "end\n"
    "local k = 4   -- 1/s^2: every particle is pulled towards the z axis\n"
    "local function force(t, s, forces)\n"
    "  for i = 1, s.n do\n"
    "    forces[3*i - 2] = forces[3*i - 2] - k * s.mass[i] * s.pos[3*i - 2]\n"
    "    forces[3*i - 1] = forces[3*i - 1] - k * s.mass[i] * s.pos[3*i - 1]\n"
    "  end\n"
    "end\n"
    "w, cw, plain = world(), world(), world()\n"
    "w:force(force)\n"
    "local s, f = { n = n, pos = {}, vel = {}, mass = {} }, {}\n"
    "for i = 1, n do\n"
    "  local x, y, z = place(i)\n"
    "  s.pos[3*i - 2], s.pos[3*i - 1], s.pos[3*i] = x, y, z\n"
    "  s.vel[3*i - 2], s.vel[3*i - 1], s.vel[3*i] = 0, 0, 0.1\n"
    "  s.mass[i] = 1 + i % 3\n"
    "  f[3*i - 2], f[3*i - 1], f[3*i] = 0, 0, 0\n"
    "end\n"
    "function pure(reps)\n"
    "  for _ = 1, reps do force(0, s, f) end\n"
    "end\n";

/* The same pull in C. */
static tb_status pull(const tb_force_args *a, void *user)
{
    size_t i;
    (void)user;
    for (i = 0; i < a->count; ++i) {
        a->forces[3 * i] -= PULL * a->masses[i] * a->positions[3 * i];
        a->forces[3 * i + 1] -= PULL * a->masses[i] * a->positions[3 * i + 1];
    }
    return TB_OK;
}

typedef struct step_case {
    lua_State *L;
    int world; /* stack index of its world */
} step_case;

/* Steps through tb_lua_step, which lets Lua callbacks run (the other two
   worlds have none, and take the same path). */
static void run_step(void *ctx, long steps)
{
    step_case *c = ctx;
    long s;
    for (s = 0; s < steps; ++s)
        check(tb_lua_step(c->L, c->world, H), tb_lua_to_world(c->L, c->world), "step");
}

static void run_pure(void *ctx, long steps)
{
    step_case *c = ctx;
    lua_getglobal(c->L, "pure");
    lua_pushinteger(c->L, steps);
    if (lua_pcall(c->L, 1, 0, 0) != LUA_OK) {
        fprintf(stderr, BENCH_NAME ": %s\n", lua_tostring(c->L, -1));
        exit(EXIT_FAILURE);
    }
}

/* A Lua state holding the scene for n particles, its three worlds on the
   stack at 1 (Lua force), 2 (C force) and 3 (none). */
static lua_State *scene_state(size_t n)
{
    lua_State *L = luaL_newstate();
    static const char *const worlds[] = { "w", "cw", "plain" };
    int k;
    if (!L) {
        fprintf(stderr, BENCH_NAME ": no Lua state\n");
        exit(EXIT_FAILURE);
    }
    luaL_openlibs(L);
    luaL_requiref(L, "tumble", luaopen_tumble, 0);
    lua_pop(L, 1);
    lua_pushinteger(L, (lua_Integer)n);
    lua_setglobal(L, "n");
    if (luaL_loadbufferx(L, scene, sizeof scene - 1, "=scene", "t") != LUA_OK || lua_pcall(L, 0, 0, 0) != LUA_OK) {
        fprintf(stderr, BENCH_NAME ": scene: %s\n", lua_tostring(L, -1));
        exit(EXIT_FAILURE);
    }
    for (k = 0; k < 3; ++k)
        lua_getglobal(L, worlds[k]);
    check(tb_world_add_force(tb_lua_check_world(L, 2), pull, NULL, NULL), tb_lua_to_world(L, 2), "C force");
    return L;
}

int main(void)
{
    static const size_t sizes[] = { 10000, 100000 };
    double worst = 0;
    size_t z;
    printf("a Lua force over particles, ns per particle per force evaluation (median of %d repeats of ~%.2f s)\n",
           BENCH_REPEATS, BENCH_REPEAT_SECONDS);
    bench_print_build();
    bench_print_asserts();
    printf("force     the guide's: f -= k m (x, y, 0) for every particle, in Lua through the binding, the same in C,\n"
           "          and the Lua function alone on plain Lua tables; symplectic_euler (one evaluation a step),\n"
           "          the force's cost = the step less the step of the same world without it\n\n");
    for (z = 0; z < sizeof sizes / sizeof sizes[0]; ++z) {
        const size_t n = sizes[z];
        lua_State *L = scene_state(n);
        step_case c[4];
        bench_case cases[4];
        double lua_ns, c_ns, pure_ns, none_ns;
        int k;
        for (k = 0; k < 4; ++k) {
            c[k].L = L;
            c[k].world = k < 3 ? k + 1 : 0;
            cases[k].run = k < 3 ? run_step : run_pure;
            cases[k].ctx = &c[k];
            cases[k].items = (double)n;
        }
        measure(cases, 4);
        none_ns = median(&cases[2]);
        lua_ns = median(&cases[0]) - none_ns;
        c_ns = median(&cases[1]) - none_ns;
        pure_ns = median(&cases[3]);
        printf("lua-force %-7zu Lua %6.1f ns/particle-evaluation | C %5.2f (Lua/C %5.1f) | the Lua loop alone %6.1f "
               "(binding %5.1f) | step without the force %5.2f\n",
               n, lua_ns, c_ns, lua_ns / c_ns, pure_ns, lua_ns - pure_ns, none_ns);
        worst = lua_ns > worst ? lua_ns : worst;
        lua_close(L);
    }
    printf("\ntarget    the Lua force at most 80 ns per particle per evaluation: worst %.1f: %s\n", worst,
           worst <= 80 ? "met" : "NOT met");
    return 0;
}
