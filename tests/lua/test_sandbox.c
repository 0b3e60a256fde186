/* test_sandbox.c: hostile scenes. Each one ends with its message and exit
   status, bounded by the budgets it is run with (small ones, so every case
   is quick, also under AddressSanitizer), never by a timeout of the test;
   no CSV and no temporary file is left behind. Also: what --trust and the
   budget flags change, signals, two runs writing one file, and the same
   limits for C hosts through the binding (tb_lua_newstate,
   tb_lua_sandbox). */
#define _POSIX_C_SOURCE 200809L
#include "test_main.h"
#include "tumble_lua.h"

#include <dirent.h>
#include <lauxlib.h>
#include <lualib.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#ifndef TUMBLE_EXE
#error "TUMBLE_EXE must name the tumble executable"
#endif

/* The budgets most cases run with: far below the defaults, so a runaway
   scene ends in milliseconds. */
#define BUDGETS "--max-instructions 1M --max-memory 32M"

#define HEADER "local tumble = require 'tumble'\n"

static char err_text[8192], out_text[8192];

/* Each test process works in its own folder, so ctest -j can run cases
   side by side; it is also the scenes' folder, where the sandbox reads. */
static const char *work_dir(void)
{
    static char dir[512];
    if (!dir[0]) {
        char cmd[600];
        snprintf(dir, sizeof dir, "%s/%ld", WORK_DIR, (long)getpid());
        snprintf(cmd, sizeof cmd, "mkdir -p '%s'", dir);
        if (system(cmd) != 0)
            fail_msg("cannot make %s", dir);
    }
    return dir;
}

static void work_path(char *path, size_t size, const char *name)
{
    snprintf(path, size, "%s/%s", work_dir(), name);
}

static void slurp(const char *name, char *buf, size_t size)
{
    char path[1100];
    FILE *f;
    size_t n = 0;
    work_path(path, sizeof path, name);
    f = fopen(path, "r");
    buf[0] = 0;
    if (f) {
        n = fread(buf, 1, size - 1, f);
        fclose(f);
    }
    buf[n] = 0;
}

static void write_file(const char *name, const char *text)
{
    char path[1100];
    FILE *f;
    work_path(path, sizeof path, name);
    f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static int exists(const char *name)
{
    char path[1100];
    work_path(path, sizeof path, name);
    return access(path, F_OK) == 0;
}

/* Start `tumble ARGS` in the work folder, stdout and stderr to out.txt and
   err.txt; returns its pid. */
static pid_t start(const char *args)
{
    char cmd[2048];
    pid_t pid;
    snprintf(cmd, sizeof cmd, "cd '%s' && exec '%s' %s > out.txt 2> err.txt", work_dir(), TUMBLE_EXE, args);
    pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        /* as a shell starts a foreground command: these signals ignored by
           the test's parent would stay ignored across exec */
        signal(SIGINT, SIG_DFL);
        signal(SIGTERM, SIG_DFL);
        signal(SIGHUP, SIG_DFL);
        execl("/bin/sh", "sh", "-c", cmd, (char *)NULL);
        _exit(127);
    }
    return pid;
}

/* Wait for it: its exit status, or 1000 + the signal that killed it. */
static int finish(pid_t pid)
{
    int status;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    slurp("err.txt", err_text, sizeof err_text);
    slurp("out.txt", out_text, sizeof out_text);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 1000 + WTERMSIG(status);
}

static int tumble(const char *args)
{
    return finish(start(args));
}

/* finish(), for the cases that wait on a signal rather than a budget: if
   it has not ended within `seconds`, kill it and fail. */
static int finish_within(pid_t pid, double seconds)
{
    struct timespec ts = { 0, 10000000 };
    int status;
    for (; seconds > 0; seconds -= 0.01) {
        if (waitpid(pid, &status, WNOHANG) == pid) {
            slurp("err.txt", err_text, sizeof err_text);
            return WIFEXITED(status) ? WEXITSTATUS(status) : 1000 + WTERMSIG(status);
        }
        nanosleep(&ts, NULL);
    }
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
    fail_msg("still running after the signal");
    return -1;
}

/* Neither NAME nor a temporary NAME.part.* is in the work folder. */
static void assert_no_output(const char *name)
{
    DIR *d = opendir(work_dir());
    struct dirent *e;
    char prefix[256];
    assert_non_null(d);
    snprintf(prefix, sizeof prefix, "%s.part", name);
    while ((e = readdir(d)) != NULL)
        if (!strcmp(e->d_name, name) || !strncmp(e->d_name, prefix, strlen(prefix)))
            fail_msg("'%s' was left behind", e->d_name);
    closedir(d);
}

/* Write `text` as scene NAME.lua, run it with `args`; it must exit with
   `status`, say `needle` in one line on stderr, and leave no output. */
static void expect_failure(const char *name, const char *text, const char *args, int status, const char *needle)
{
    char file[256], cmd[1024], csv[256];
    int rc;
    snprintf(file, sizeof file, "%s.lua", name);
    snprintf(csv, sizeof csv, "%s.csv", name);
    write_file(file, text);
    snprintf(cmd, sizeof cmd, "run %s --out %s %s", file, csv, args);
    rc = tumble(cmd);
    if (rc != status)
        fail_msg("%s: exit status %d, expected %d; stderr: %s", name, rc, status, err_text);
    if (!strstr(err_text, needle))
        fail_msg("%s: stderr does not say '%s': %s", name, needle, err_text);
    if (strncmp(err_text, "tumble: ", 8) || strchr(err_text, '\n') != err_text + strlen(err_text) - 1)
        fail_msg("%s: stderr is not one line starting with 'tumble: ': %s", name, err_text);
    assert_no_output(csv);
}

/* A world with one particle and rk4, for callbacks to live in. */
#define WORLD HEADER "local w = tumble.world{ integrator = 'rk4', dt = 0.01 }\nlocal p = w:particle{}\n"
#define RETURN "return { world = w, duration = 1 }\n"

/* Loops for ever, where a count hook reaches them: in the script, in a
   force and a field, in __index of the returned table, in __tostring of
   an error object and of a printed value, in a coroutine, and inside
   pcall (which cannot swallow the budget). */
static void loops_end_at_the_instruction_budget(void **state)
{
    static const struct { const char *name, *text; } loops[] = {
        { "body", "while true do end\n" },
        { "force", WORLD "w:force(function() while true do end end)\n" RETURN },
        { "field", WORLD "w:tracer{}\nw:field(function() while true do end end)\n" RETURN },
        { "index", "return setmetatable({}, { __index = function() while true do end end })\n" },
        { "tostring_error", WORLD "w:force(function() error(setmetatable({}, { __tostring = function() "
                                  "while true do end end })) end)\n" RETURN },
        { "tostring_print", "print(setmetatable({}, { __tostring = function() while true do end end }))\n" },
        { "coroutine", "coroutine.wrap(function() while true do end end)()\n" },
        { "pcall", "while true do pcall(function() while true do end end) end\n" },
        { "xpcall", "while true do xpcall(function() while true do end end, function() while true do end end) end\n" },
        { "close", "do local x <close> = setmetatable({}, { __close = function() while true do end end }) end\n" },
        /* after the hook's error Lua keeps hooks off until a pcall: the
           handler and a killed coroutine's __close must not run then */
        { "wrap_close", "coroutine.wrap(function()\n"
                        "  local x <close> = setmetatable({}, { __close = function() while true do end end })\n"
                        "  while true do end\nend)()\n" },
        { "close_coroutine", "local co = coroutine.create(function()\n"
                             "  local x <close> = setmetatable({}, { __close = function() while true do end end })\n"
                             "  while true do end\nend)\n"
                             "local closer <close> = setmetatable({}, { __close = function() coroutine.close(co) end })\n"
                             "coroutine.resume(co)\n" },
    };
    size_t k;
    (void)state;
    for (k = 0; k < sizeof loops / sizeof loops[0]; ++k) {
        char name[64];
        snprintf(name, sizeof name, "loop_%s", loops[k].name);
        expect_failure(name, loops[k].text, BUDGETS, 1,
                       "instruction budget exceeded: more than 1000000 Lua instructions");
        assert_non_null(strstr(err_text, "raise it with --max-instructions"));
    }
    /* where it stopped: the file and line, and in a callback the time */
    expect_failure("loop_where", WORLD "w:force(function(t)\n  while t > 0.5 do end\nend)\n" RETURN, BUDGETS, 1,
                   "loop_where.lua: at t = 0.");
    assert_non_null(strstr(err_text, "(at loop_where.lua:5)"));
}

/* Finalizers run with the count hook off: the sandbox refuses __gc, also
   a __gc put in the metatable after setmetatable (Lua ignores it then). */
static void finalizers_are_refused(void **state)
{
    (void)state;
    expect_failure("gc", "setmetatable({}, { __gc = function() while true do end end })\ncollectgarbage()\n",
                   BUDGETS, 1, "no __gc metamethod");
    expect_failure("gc_late", HEADER "local mt = {}\nlocal t = setmetatable({}, mt)\n"
                   "mt.__gc = function() while true do end end\nt = nil\ncollectgarbage()\n"
                   "return { world = tumble.world{ integrator = 'rk4' }, duration = -1 }\n", BUDGETS, 1,
                   "needs 'duration'");
}

/* Memory bombs: Lua tables and strings (also with pcall catching every
   refusal), a world's own memory, and inside a callback. */
static void memory_bombs_end_at_the_memory_budget(void **state)
{
    static const struct { const char *name, *text; } bombs[] = {
        { "tables", "local t = {}\nfor i = 1, 1e9 do t[i] = {i, i, i} end\n" },
        { "strings", "local s = 'x'\nwhile true do pcall(function() s = s .. s end) end\n" },
        { "caught", "local t = {}\nfor i = 1, 1e9 do pcall(function() t[#t + 1] = string.rep('x', 1e6) .. i end) end\n" },
        { "world", HEADER "local w = tumble.world{}\nwhile true do pcall(w.particle, w, {}) end\n" },
        { "callback", WORLD "local keep = {}\nw:force(function() for i = 1, 1e9 do keep[#keep + 1] = {i} end end)\n"
                            RETURN },
        { "rep", "local ok = pcall(string.rep, 'x', 1e9)\nwhile true do end\n" },
    };
    size_t k;
    (void)state;
    for (k = 0; k < sizeof bombs / sizeof bombs[0]; ++k) {
        char name[64];
        snprintf(name, sizeof name, "bomb_%s", bombs[k].name);
        expect_failure(name, bombs[k].text, "--max-instructions 100M --max-memory 8M", 1,
                       "memory budget exceeded: more than 8388608 bytes");
        assert_non_null(strstr(err_text, "raise it with --max-memory"));
    }
}

/* The returned table is read in a protected call: its metamethods may
   raise or return nonsense, and the command says so. */
static void erroring_metamethods_on_the_returned_table(void **state)
{
    (void)state;
    expect_failure("meta_index", "return setmetatable({}, { __index = function() error('no such key') end })\n",
                   BUDGETS, 1, "meta_index.lua:1: no such key");
    expect_failure("meta_duration", HEADER "local w = tumble.world{}\nw:particle{}\n"
                   "return setmetatable({ world = w }, { __index = function(t, k)\n"
                   "  if k == 'duration' then error('duration refused') end end })\n",
                   BUDGETS, 1, "duration refused");
    expect_failure("meta_error_object", "error(setmetatable({}, { __index = function() error('x') end }))\n",
                   BUDGETS, 1, "error object is a table value");
    expect_failure("meta_world", "return { world = setmetatable({}, { __index = error }), duration = 1 }\n",
                   BUDGETS, 1, "has no 'world'");
    expect_failure("meta_closed", HEADER "local w = tumble.world{}\n"
                   "return setmetatable({ duration = 1 }, { __index = function(t, k) if k == 'world' then\n"
                   "  w:close() return w end end })\n", BUDGETS, 1, "closed");
    expect_failure("meta_number", HEADER "local w = tumble.world{}\n"
                   "return { world = w, duration = setmetatable({}, { __tonumber = error }) }\n",
                   BUDGETS, 1, "needs 'duration'");
}

/* Callbacks that step, close, add or remove while their world steps. */
static void reentrant_steps_and_removals_in_callbacks(void **state)
{
    static const struct { const char *name, *body, *needle; } calls[] = {
        { "step", "w:step()", "cannot step while the world is stepping" },
        { "close", "w:close()", "cannot close a world while it is stepping" },
        { "remove_particle", "p:remove()", "cannot remove a particle while the world is stepping" },
        { "remove_force", "me:remove()", "cannot remove a force while the world is stepping" },
        { "add", "w:body{ sphere = 1 }", "cannot add a body while the world is stepping" },
        { "other_world", "local v = tumble.world{ integrator = 'rk4' }; v:particle{}; "
                         "v:force(function() w:step() end); v:step()", "cannot step while the world is stepping" },
    };
    size_t k;
    (void)state;
    for (k = 0; k < sizeof calls / sizeof calls[0]; ++k) {
        char name[64], text[1024];
        snprintf(name, sizeof name, "reenter_%s", calls[k].name);
        snprintf(text, sizeof text, WORLD "local me\nme = w:force(function() %s end)\n" RETURN, calls[k].body);
        expect_failure(name, text, BUDGETS, 1, calls[k].needle);
        assert_non_null(strstr(err_text, "at t = 0 s"));
    }
}

/* Chunks load as text only: no string.dump, no binary mode, and a
   precompiled scene is refused. */
static void binary_chunks_are_refused(void **state)
{
    (void)state;
    expect_failure("dump", "return load(string.dump(function() end))\n", BUDGETS, 1, "field 'dump'");
    expect_failure("binary_mode", "return load('\\27Lua', 'x', 'b')\n", BUDGETS, 1, "text chunks only");
    expect_failure("binary_text", "return assert(load('\\27LuaT\\0\\25\\147\\r\\n\\26\\n'))\n", BUDGETS, 1,
                   "attempt to load a binary chunk");
    expect_failure("binary_scene", "\033LuaT\0", BUDGETS, 1, "attempt to load a binary chunk");
}

/* Recursion ends with Lua's own stack limits. */
static void deep_recursion_ends_with_a_message(void **state)
{
    (void)state;
    /* Lua's stack of a million slots takes some 40 MB */
    const char *budgets = "--max-instructions 10M --max-memory 128M";
    expect_failure("recurse_lua", "local function f(n) return 1 + f(n + 1) end\nreturn f(1)\n", budgets, 1,
                   "stack overflow");
    expect_failure("recurse_index", "local t = setmetatable({}, {})\n"
                   "getmetatable(t).__index = function(t, k) return t[k] end\nreturn t.x\n", budgets, 1,
                   "stack overflow");
    write_file("cycle.lua", "return require 'cycle'\n");
    expect_failure("recurse_require", "return require 'cycle'\n", budgets, 1, "stack overflow");
    expect_failure("recurse_callback", WORLD "local function f() return f() + 1 end\nw:force(f)\n" RETURN,
                   budgets, 1, "stack overflow");
}

/* The sandbox: no process, no environment, no debug, no package; files
   are read in the scene's folder only, through require, io.open and
   io.lines. */
static void the_sandbox_keeps_to_the_scenes_folder(void **state)
{
    static const struct { const char *name, *text, *needle; } escapes[] = {
        { "execute", "os.execute('touch escaped')\n", "field 'execute'" },
        { "getenv", "return os.getenv('HOME')\n", "field 'getenv'" },
        { "remove", "os.remove('x')\n", "field 'remove'" },
        { "exit", "os.exit(0)\n", "field 'exit'" },
        { "popen", "io.popen('ls')\n", "field 'popen'" },
        { "debug", "debug.sethook()\n", "global 'debug'" },
        { "package", "package.loadlib('x', 'y')\n", "global 'package'" },
        { "dofile", "dofile('/etc/passwd')\n", "global 'dofile'" },
        { "loadfile", "loadfile('/etc/passwd')\n", "global 'loadfile'" },
        { "open_absolute", "assert(io.open('/etc/passwd'))\n", "outside the scene's folder" },
        { "open_up", "assert(io.open('../x.lua'))\n", "outside the scene's folder" },
        { "open_link", "assert(io.open('link_out'))\n", "outside the scene's folder" },
        { "open_write", "io.open('x.txt', 'w')\n", "for reading only" },
        { "open_fifo", "assert(io.open('fifo'))\n", "not a regular file" },
        { "open_folder", "assert(io.open('.'))\n", "scene's folder" },
        { "open_append", "io.open('x.txt', 'a+')\n", "for reading only" },
        { "lines_out", "for l in io.lines('/etc/passwd') do end\n", "outside the scene's folder" },
        { "lines_stdin", "for l in io.lines() do end\n", "bad argument" },
        { "require_up", "require '..x'\n", "bad module name" },
        { "require_absolute", "require '/etc/passwd'\n", "bad module name" },
        { "require_missing", "require 'no_such_module'\n", "no module 'no_such_module'" },
        { "require_io", "local io = require 'io'\nio.popen('ls')\n", "field 'popen'" },
        { "collect_stop", "collectgarbage('stop')\n", "allows only" },
        { "string_meta", "getmetatable('').__index = function() end\n", "index a string value" },
        { "warn", "warn('@on')\n", "global 'warn'" },
    };
    size_t k;
    char target[1100], link[1100];
    (void)state;
    work_path(link, sizeof link, "link_out");
    snprintf(target, sizeof target, "%s/../outside.txt", work_dir());
    write_file("../outside.txt", "secret\n");
    unlink(link);
    assert_int_equal(symlink(target, link), 0);
    work_path(link, sizeof link, "fifo");
    unlink(link);
    assert_int_equal(mkfifo(link, 0600), 0);
    for (k = 0; k < sizeof escapes / sizeof escapes[0]; ++k) {
        char name[64];
        snprintf(name, sizeof name, "escape_%s", escapes[k].name);
        expect_failure(name, escapes[k].text, BUDGETS, 1, escapes[k].needle);
    }
    assert_false(exists("escaped"));
    /* what a scene may do: require a module of its folder, which reads a
       data file there with io.open and io.lines */
    write_file("data.txt", "3\n1 2 3\n");
    write_file("helper.lua", HEADER "local f = assert(io.open('data.txt'))\nlocal n = f:read('n')\nf:close()\n"
                             "local lines = 0\nfor l in io.lines('data.txt') do lines = lines + 1 end\n"
                             "assert(lines == 2)\n"
                             "return { make = function() local w = tumble.world{}\n"
                             "  for i = 1, n do w:particle{ pos = {i, 0, 0} } end return w end }\n");
    write_file("uses_helper.lua", "local helper = require 'helper'\nassert(require 'helper' == helper)\n"
                                  "assert(getmetatable('') == 'string' and not string.dump)\n"
                                  "assert(os.time() and os.clock() and os.date('%Y'))\n"
                                  "return { world = helper.make(), duration = 0.1 }\n");
    assert_int_equal(tumble("run uses_helper.lua --out helper.csv " BUDGETS), 0);
    assert_non_null(strstr(out_text, "3 particles"));
    assert_non_null(strstr(out_text, "lua         sandboxed"));
}

/* --trust gives the whole library (and keeps the budgets); the debug
   library then reaches the binding's objects, and nothing it does to them
   crashes the command. */
static void trust_gives_the_whole_library(void **state)
{
    static const struct { const char *name, *text; } attacks[] = {
        /* empty the world's table of callbacks, collect, step */
        { "callbacks", WORLD "w:force(function() end)\nfor k in pairs(debug.getuservalue(w)) do "
                       "debug.getuservalue(w)[k] = nil end\ncollectgarbage()\n" RETURN },
        /* call the world's __gc while it steps */
        { "gc", WORLD "w:force(function() debug.getmetatable(w).__gc(w) end)\n" RETURN },
        /* metamethods called with anything */
        { "tostring", WORLD "debug.getmetatable(p).__tostring(42)\n" RETURN },
        { "eq", WORLD "assert(debug.getmetatable(p).__eq(p, 42) == false)\n"
                "debug.getmetatable(w).__close(p)\n" RETURN },
        /* user values replaced */
        { "uservalue", WORLD "debug.setuservalue(w, 5)\nw:force(function() end)\n" RETURN },
        { "uservalue_step", WORLD "w:force(function() debug.setuservalue(w, 5) end)\n" RETURN },
        { "handle_world", WORLD "debug.setuservalue(p, w:particle{})\np:pos()\n" RETURN },
        { "scratch", WORLD "w:force(function() debug.getuservalue(w).force_out = 5 end)\n" RETURN },
        /* metatables swapped */
        /* metatables swapped, and put back (a world or file left without
           its own has no finalizer, and leaks) */
        { "world_as_handle", WORLD "local mt = debug.getmetatable(w)\n"
                             "debug.setmetatable(w, debug.getmetatable(p))\n"
                             "assert(not pcall(tostring, w) and not pcall(p.pos, w) and not pcall(w.remove, w))\n"
                             "debug.setmetatable(w, mt)\n" RETURN },
        { "handle_as_world", WORLD "local mt = debug.getmetatable(p)\n"
                             "debug.setmetatable(p, debug.getmetatable(w))\n"
                             "assert(not pcall(tostring, p) and not pcall(w.step, p) and not pcall(w.close, p))\n"
                             "debug.setmetatable(p, mt)\n" RETURN },
        { "file_as_handle", WORLD "local f = io.tmpfile()\nlocal mt = debug.getmetatable(f)\n"
                            "debug.setmetatable(f, debug.getmetatable(p))\n"
                            "assert(not pcall(tostring, f) and not pcall(p.pos, f) and not pcall(p.id, f))\n"
                            "debug.setmetatable(f, mt)\nf:close()\n" RETURN },
        /* the stack slot of the stepping world, its only reference, set
           to nil, then a collection (the world's anchor keeps it) */
        { "setlocal", HEADER "local function make()\n"
                      "  local w = tumble.world{ integrator = 'rk4' }\n  w:particle{}\n  local step = w.step\n"
                      "  w:force(function()\n    for level = 2, 8 do\n"
                      "      local info = debug.getinfo(level, 'f')\n"
                      "      if info and info.func == step then debug.setlocal(level, 1, nil) end\n"
                      "    end\n    collectgarbage(); collectgarbage()\n  end)\n  return w\nend\n"
                      "make():step()\ncollectgarbage()\n"
                      "return { world = tumble.world{}, duration = -1 }\n" },
    };
    size_t k;
    (void)state;
    write_file("trusted.lua", HEADER "assert(os.getenv('PATH') and debug.traceback and package.path)\n"
                              "assert(io.open('/etc/passwd'))\n"
                              "local w = tumble.world{}\nw:particle{}\nreturn { world = w, duration = 0.1 }\n");
    assert_int_equal(tumble("run trusted.lua --out trusted.csv " BUDGETS), 1);
    assert_non_null(strstr(err_text, "field 'getenv'"));
    assert_int_equal(tumble("run trusted.lua --out trusted.csv --trust " BUDGETS), 0);
    assert_non_null(strstr(out_text, "lua         trusted"));
    expect_failure("trusted_loop", "while true do end\n", "--trust " BUDGETS, 1, "instruction budget exceeded");
    for (k = 0; k < sizeof attacks / sizeof attacks[0]; ++k) {
        char file[64], args[256], path[1100];
        int rc;
        snprintf(file, sizeof file, "attack_%s.lua", attacks[k].name);
        write_file(file, attacks[k].text);
        snprintf(args, sizeof args, "run %s --out attack.csv --trust " BUDGETS, file);
        work_path(path, sizeof path, "attack.csv");
        unlink(path);
        rc = tumble(args);
        if (rc != 0 && rc != 1)
            fail_msg("%s: exit status %d (signals: 1000 + the signal); stderr: %s", file, rc, err_text);
        if (rc == 1 && strncmp(err_text, "tumble: ", 8))
            fail_msg("%s: %s", file, err_text);
        if (rc == 1)
            assert_no_output("attack.csv");
    }
}

/* The budget flags: 0 lifts a budget, suffixes scale it, bad values are
   a usage error; the summary reports what was used. */
static void budget_flags(void **state)
{
    (void)state;
    write_file("counts.lua", HEADER "local x = 0\nfor i = 1, 1e6 do x = x + i end\n"
                             "local w = tumble.world{}\nw:particle{}\nreturn { world = w, duration = 0.1 }\n");
    assert_int_equal(tumble("run counts.lua --out counts.csv --max-instructions 1M"), 1);
    assert_non_null(strstr(err_text, "more than 1000000 Lua instructions"));
    assert_no_output("counts.csv");
    assert_int_equal(tumble("run counts.lua --out counts.csv --max-instructions 2.5M"), 0);
    assert_non_null(strstr(out_text, "of 2500000, peak memory"));
    assert_int_equal(tumble("run counts.lua --out counts.csv --max-instructions 0 --max-memory 0"), 0);
    assert_non_null(strstr(out_text, "instructions not counted"));
    assert_non_null(strstr(out_text, "(no limit)"));
    assert_int_equal(tumble("run counts.lua --out counts.csv"), 0); /* the defaults */
    assert_non_null(strstr(out_text, "of 1000000000, peak memory"));
    assert_non_null(strstr(out_text, " of 256 MiB"));
    assert_int_equal(tumble("run counts.lua --out counts.csv --max-memory 16K"), 1);
    assert_non_null(strstr(err_text, "memory budget exceeded: more than 16384 bytes"));
    assert_int_equal(tumble("run counts.lua --out counts.csv --max-memory 1K"), 1);
    assert_non_null(strstr(err_text, "--max-memory"));
    assert_int_equal(tumble("run counts.lua --max-memory -1"), 2);
    assert_non_null(strstr(err_text, "bad budget '-1'"));
    assert_int_equal(tumble("run counts.lua --max-instructions 1X"), 2);
    assert_int_equal(tumble("run counts.lua --max-instructions"), 2);
    assert_int_equal(tumble("run counts.lua --max-memory 1e300"), 2);
    assert_int_equal(tumble("--help"), 0);
    assert_non_null(strstr(out_text, "--max-instructions N"));
    assert_non_null(strstr(out_text, "default 1G"));
    assert_non_null(strstr(out_text, "default 256M"));
    assert_non_null(strstr(out_text, "--trust"));
}

/* Durations past 1e9 steps are refused before anything is written. */
static void absurd_durations_are_refused(void **state)
{
    (void)state;
    expect_failure("forever", HEADER "return { world = tumble.world{}, duration = 1e300 }\n", BUDGETS, 1,
                   "the command takes at most 1e9");
    expect_failure("long", HEADER "return { world = tumble.world{ dt = 0.01 }, duration = 1e7 + 1 }\n", BUDGETS, 1,
                   "1e+09 steps");
    expect_failure("tiny_dt", HEADER "return { world = tumble.world{}, duration = 1 }\n", "--dt 1e-300 " BUDGETS, 1,
                   "at most 1e9");
    expect_failure("until", HEADER "return { world = tumble.world{}, duration = 1 }\n", "--until 1e300 " BUDGETS, 1,
                   "at most 1e9");
}

/* A failed run leaves an older CSV as it was. */
static void a_failed_run_keeps_the_old_csv(void **state)
{
    char text[64];
    (void)state;
    write_file("kept.csv", "old,contents\n");
    write_file("kept.lua", WORLD "w:force(function(t) if t > 0.1 then error('late failure') end end)\n" RETURN);
    assert_int_equal(tumble("run kept.lua --out kept.csv " BUDGETS), 1);
    assert_non_null(strstr(err_text, "late failure"));
    slurp("kept.csv", text, sizeof text);
    assert_string_equal(text, "old,contents\n");
}

/* Poll (10 ms apart, at most `tries` times) for a temporary output. */
static int wait_for_temp(const char *csv, int tries)
{
    char prefix[256];
    snprintf(prefix, sizeof prefix, "%s.part.", csv);
    while (tries-- > 0) {
        DIR *d = opendir(work_dir());
        struct dirent *e;
        int found = 0;
        struct timespec ts = { 0, 10000000 };
        while (d && (e = readdir(d)) != NULL)
            found |= !strncmp(e->d_name, prefix, strlen(prefix));
        if (d)
            closedir(d);
        if (found)
            return 1;
        nanosleep(&ts, NULL);
    }
    return 0;
}

/* SIGINT, SIGTERM and SIGHUP mid-run: the temporary file is removed and
   the exit status is 128 + the signal. The scene would run for 1e6 s. */
static void signals_remove_the_temporary_file(void **state)
{
    static const int signals[] = { SIGINT, SIGTERM, SIGHUP };
    static const char *const names[] = { "SIGINT", "SIGTERM", "SIGHUP" };
    size_t k;
    (void)state;
    write_file("endless.lua", WORLD "w:force(function(t, s, f) f[3] = f[3] + 1 end)\n"
                              "return { world = w, duration = 1e6, record_every = 0 }\n");
    for (k = 0; k < 3; ++k) {
        pid_t pid = start("run endless.lua --out endless.csv --max-instructions 50M");
        int rc;
        if (!wait_for_temp("endless.csv", 3000)) {
            kill(pid, SIGKILL);
            finish(pid);
            fail_msg("no temporary output appeared: %s", err_text);
        }
        kill(pid, signals[k]);
        rc = finish_within(pid, 30);
        assert_int_equal(rc, 128 + signals[k]);
        assert_non_null(strstr(err_text, names[k]));
        assert_non_null(strstr(err_text, "no output written"));
        assert_no_output("endless.csv");
    }
}

/* A scene stuck in Lua stops at the signal too: the budgets' hook reads
   it. With no budget there is no hook, and a second signal ends the run
   at once. */
static void a_stuck_scene_stops_at_a_signal(void **state)
{
    struct timespec ts = { 0, 200000000 };
    pid_t pid;
    (void)state;
    write_file("stuck.lua", "while true do end\n");
    pid = start("run stuck.lua --out stuck.csv --max-instructions 5G");
    nanosleep(&ts, NULL);
    kill(pid, SIGTERM);
    assert_int_equal(finish_within(pid, 30), 128 + SIGTERM);
    assert_non_null(strstr(err_text, "interrupted by SIGTERM"));
    pid = start("run stuck.lua --out stuck.csv --max-instructions 0 --max-memory 0");
    nanosleep(&ts, NULL);
    kill(pid, SIGINT);
    nanosleep(&ts, NULL);
    kill(pid, SIGINT);
    assert_int_equal(finish_within(pid, 30), 128 + SIGINT);
    assert_no_output("stuck.csv");
}

/* Two runs writing one --out at once: each writes its own temporary file
   and renames it whole, so the CSV is one run's, complete. */
static void two_runs_writing_one_csv(void **state)
{
    char args[1024], line[256], path[1100];
    pid_t a, b;
    long rows = 0;
    FILE *f;
    (void)state;
    snprintf(args, sizeof args, "run '%s/rope.lua' --out same.csv --quiet", SCENES_DIR);
    a = start(args);
    snprintf(args, sizeof args, "run '%s/cloth.lua' --out same.csv --quiet", SCENES_DIR);
    b = start(args);
    assert_int_equal(finish(a), 0);
    assert_int_equal(finish(b), 0);
    work_path(path, sizeof path, "same.csv");
    f = fopen(path, "r");
    assert_non_null(f);
    assert_non_null(fgets(line, sizeof line, f));
    assert_string_equal(line, "t,kind,id,x,y,z,vx,vy,vz,qw,qx,qy,qz,wx,wy,wz\n");
    while (fgets(line, sizeof line, f)) {
        assert_non_null(strchr(line, '\n'));
        ++rows;
    }
    fclose(f);
    if (rows != 20 * 91 && rows != 225 * 92) /* rope's rows or cloth's (test_command) */
        fail_msg("%ld rows: neither rope's nor cloth's", rows);
    assert_int_equal(wait_for_temp("same.csv", 1), 0);
}

/* ---------------------------------------------------------- C hosts -- */

/* Load and run `code` in L; NULL or the first line of the error. */
static const char *run(lua_State *L, const char *code)
{
    static char message[512];
    int base = lua_gettop(L);
    if (luaL_loadbufferx(L, code, strlen(code), "=host", "t") != LUA_OK || lua_pcall(L, 0, 0, 0) != LUA_OK) {
        const char *m = lua_tostring(L, -1);
        snprintf(message, sizeof message, "%.*s", (int)strcspn(m ? m : "?", "\n"), m ? m : "?");
        lua_settop(L, base);
        return message;
    }
    lua_settop(L, base);
    return NULL;
}

static void expect(lua_State *L, const char *code, const char *needle)
{
    const char *err = run(L, code);
    if (needle && (!err || !strstr(err, needle)))
        fail_msg("expected an error with '%s', got %s", needle, err ? err : "none");
    if (!needle && err)
        fail_msg("unexpected error: %s", err);
}

/* Lua's pattern matcher runs in C, out of the instruction budget's reach:
   the sandbox refuses matches whose bound n^(q + 1) (n^q anchored) passes
   1e10 steps, with the reason, and lets plain finds, a repetition on 1e4
   bytes and ordinary trims through. Without the check the first refused match
   below runs for hours. */
static void costly_patterns_are_refused(void **state)
{
    lua_State *L = tb_lua_newstate(NULL);
    (void)state;
    assert_non_null(L);
    assert_int_equal(tb_lua_sandbox(L, NULL), LUA_OK);
    expect(L, "local s = ('a'):rep(1e5)\n"
              "assert(s:find('a', 1, true) == 1 and not s:find('b') and select(2, s:gsub('a', 'b')) == 1e5)\n"
              "assert(('  hi  '):match('^%s*(.-)%s*$') == 'hi')\n"
              "assert(#(('x'):rep(500)):match('^%s*(.-)%s*$') == 500)\n"
              "local n = 0 for w in ('one two'):gmatch('%a+') do n = n + 1 end assert(n == 2)\n"
              "assert(#s:sub(1, 1e4):match('a*') == 1e4)\n", NULL);
    expect(L, "local s = ('a'):rep(1e5) return s:find(('a-'):rep(10) .. 'b')", "10 repetitions on a subject of 100000");
    expect(L, "local s = ('a'):rep(1e5) return string.match(s, '.-.-b')", "the sandbox refuses");
    expect(L, "local s = ('a'):rep(1e5) for w in s:gmatch('a*a*b') do end", "the sandbox refuses");
    expect(L, "local s = ('a'):rep(1e5) return s:gsub('[a-]*a*b', '')", "the sandbox refuses");
    expect(L, "local s = ('a'):rep(1e6) return s:find('a*b')", "1 repetition on a subject of 1000000");
    lua_close(L);
}

/* The same limits through the binding: a budget that pcall cannot
   swallow, a memory budget, tb_lua_set_limits starting afresh, a
   sandbox with no folder, and a Lua force stepped by tb_lua_step. */
static void c_hosts_get_the_same_limits(void **state)
{
    tb_lua_limits limits;
    unsigned long long used;
    size_t peak;
    lua_State *L, *plain;
    tb_world *w;
    (void)state;
    memset(&limits, 0, sizeof limits);
    limits.instructions = 100000;
    limits.memory = 4 << 20;
    L = tb_lua_newstate(&limits);
    assert_non_null(L);
    assert_int_equal(tb_lua_sandbox(L, NULL), LUA_OK);
    assert_null(tb_lua_limit_error(L));
    expect(L, "assert(not io.open('x'))\nassert(select(2, io.open('x')):find('no folder'))\n"
              "assert(not string.dump and not debug and not os.execute)\n"
              "local tumble = require 'tumble'\nassert(tumble.world)\n", NULL);
    expect(L, "for i = 1, 1e3 do pcall(function() while true do end end) end\nerror('escaped')\n",
           "instruction budget exceeded");
    assert_non_null(strstr(tb_lua_limit_error(L), "more than 100000 Lua instructions (at host:1)"));
    expect(L, "local x = 1", "instruction budget exceeded"); /* and it stays exceeded */
    assert_int_equal(tb_lua_usage(L, &used, &peak), 0);
    assert_true(used > 100000 && used < 110000);
    assert_true(peak > 0 && peak <= limits.memory);

    limits.instructions = 0;
    assert_int_equal(tb_lua_set_limits(L, &limits), 0); /* afresh */
    assert_null(tb_lua_limit_error(L));
    expect(L, "local t = {} for i = 1, 1e7 do t[i] = i end", "not enough memory");
    assert_non_null(strstr(tb_lua_limit_error(L), "memory budget exceeded: more than 4194304 bytes"));

    limits.memory = 0;
    limits.instructions = 100000;
    assert_int_equal(tb_lua_set_limits(L, &limits), 0);
    expect(L, "local tumble = require 'tumble'\n"
              "w = tumble.world{ integrator = 'rk4' }\nw:particle{}\n"
              "w:force(function(t) if t > 0.015 then while true do end end end)\n", NULL);
    lua_getglobal(L, "w");
    w = tb_lua_check_world(L, -1);
    assert_int_equal(tb_lua_step(L, -1, 0.01), TB_OK);
    assert_int_equal(tb_lua_step(L, -1, 0.01), TB_ERR_CALLBACK);
    assert_non_null(strstr(tb_world_message(w), "instruction budget exceeded"));
    assert_non_null(tb_lua_limit_error(L));
    lua_close(L);

    /* a state made elsewhere has no budgets to report */
    plain = luaL_newstate();
    assert_non_null(plain);
    assert_null(tb_lua_limit_error(plain));
    assert_int_equal(tb_lua_set_limits(plain, &limits), -1);
    assert_int_equal(tb_lua_usage(plain, &used, &peak), -1);
    lua_close(plain);
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(loops_end_at_the_instruction_budget),
    cmocka_unit_test(costly_patterns_are_refused),
    cmocka_unit_test(finalizers_are_refused),
    cmocka_unit_test(memory_bombs_end_at_the_memory_budget),
    cmocka_unit_test(erroring_metamethods_on_the_returned_table),
    cmocka_unit_test(reentrant_steps_and_removals_in_callbacks),
    cmocka_unit_test(binary_chunks_are_refused),
    cmocka_unit_test(deep_recursion_ends_with_a_message),
    cmocka_unit_test(the_sandbox_keeps_to_the_scenes_folder),
    cmocka_unit_test(trust_gives_the_whole_library),
    cmocka_unit_test(budget_flags),
    cmocka_unit_test(absurd_durations_are_refused),
    cmocka_unit_test(a_failed_run_keeps_the_old_csv),
    cmocka_unit_test(signals_remove_the_temporary_file),
    cmocka_unit_test(a_stuck_scene_stops_at_a_signal),
    cmocka_unit_test(two_runs_writing_one_csv),
    cmocka_unit_test(c_hosts_get_the_same_limits),
};
TB_TEST_MAIN(tests)
