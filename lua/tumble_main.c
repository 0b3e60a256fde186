/* tumble_main.c: the `tumble` command. Runs a Lua scene script and writes
   its trajectory as CSV (and, when asked, a glTF file, gltf_writer.c, and
   a plot, run_plot.c). Errors are one line on stderr and a non-zero exit;
   the output file appears only when the whole run succeeded: rows go to a
   temporary file of its own next to it, renamed over it at the end, and
   removed on failure and on SIGINT, SIGTERM and SIGHUP.

   Scripts run in the binding's sandbox under an instruction and a memory
   budget (tb_lua_newstate, tb_lua_sandbox) unless --trust; every call into
   Lua is protected, so whatever a scene returns ends in a message, never a
   Lua panic. Static functions are named as in tumble_lua.c: each starts
   with a verb. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime, sigaction, mkstemp, fchmod */
#include "tumble_lua.h"
#include "gltf_writer.h"
#include "run_plot.h"

#include <lauxlib.h>
#include <lualib.h>
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* The default budgets: far above what any shipped scene uses (at most
   0.43 M instructions, scenes/push.lua, and 2.5 MiB, scenes/pyramid.lua;
   docs/command.md has them all), yet reached soon: a scene looping for
   ever stops within about 10 s, a memory bomb within about 1 s. */
#define DEFAULT_MAX_INSTRUCTIONS 1000000000.0
#define DEFAULT_MAX_MEMORY (256.0 * 1024 * 1024)

/* The most steps a run may take: past this a typo in a duration, not a
   scene, is the likelier cause, and a step count stays exact in a long. */
#define MAX_STEPS 1e9

static const char usage[] =
    "usage: tumble run SCENE.lua [--out FILE.csv] [--integrator NAME] [--dt SECONDS]\n"
    "                            [--tol TOLERANCE] [--guard FACTOR] [--until SECONDS]\n"
    "                            [--every SECONDS] [--trust] [--max-instructions N]\n"
    "                            [--max-memory BYTES] [--gltf FILE.glb] [--plot FILE.png]\n"
    "                            [--quiet] [--check]\n"
    "       tumble --help | --version\n"
    "\n"
    "Runs a scene script and writes its trajectory as CSV. Options take their\n"
    "value as the next argument or after '=' (--dt=0.01). On a terminal a\n"
    "progress line shows on stderr while a run takes more than a second.\n"
    "\n"
    "  run SCENE.lua      the script builds a world and returns\n"
    "                     { world = w, duration = S, record_every = S }\n"
    "  --out FILE.csv     where to write the trajectory (default: the scene's\n"
    "                     name with .csv, in the current directory); written to\n"
    "                     a temporary FILE.csv.part.XXXXXX and renamed only when\n"
    "                     the run succeeds. --out - writes it to stdout (the\n"
    "                     summary then goes to stderr)\n"
    "  --integrator NAME  override the scene's integrator: %s\n"
    "  --dt SECONDS       override the step (default: the world's dt, 1/60 s\n"
    "                     unless the scene says otherwise)\n"
    "  --tol TOLERANCE    error per simulated second asked of dopri5 and auto,\n"
    "                     relative to 1 + |y| per state value\n"
    "  --guard FACTOR     the blow-up guard: stop when the state stops being\n"
    "                     finite (always on in the command) or when the energy\n"
    "                     grows more than FACTOR (> 1) times in one step; the\n"
    "                     message names the step, the object and the cause\n"
    "  --until SECONDS    override the scene's duration\n"
    "  --every SECONDS    override record_every (default 1/60 s; 0 records\n"
    "                     every step)\n"
    "  --trust            give the script Lua's whole standard library (os, io,\n"
    "                     debug, package): only for scripts you trust. Without\n"
    "                     it the script runs in a sandbox: no os.execute, no\n"
    "                     debug, no binary chunks; require, io.open and io.lines\n"
    "                     read only in the scene's folder\n"
    "  --max-instructions N\n"
    "                     the Lua instructions the scene may run in all (script,\n"
    "                     callbacks, metamethods); default %.0fG, 0: no limit;\n"
    "                     K, M, G multiply by 1e3, 1e6, 1e9\n"
    "  --max-memory BYTES the bytes the scene's Lua and worlds may hold at once;\n"
    "                     default %.0fM, 0: no limit; K, M, G: KiB, MiB, GiB\n"
    "  --gltf FILE.glb    also write the run as binary glTF 2.0: every shape as a\n"
    "                     mesh, bodies, particles, tracers and springs as nodes\n"
    "                     animated at the recorded frames (docs/command.md)\n"
    "  --plot FILE.png    also draw the energy terms, momentum and (with shapes)\n"
    "                     contacts at the recorded frames, with gnuplot\n"
    "  --quiet            print no summary\n"
    "  --check            rerun at dt/2 (dopri5, auto: and tolerance/100), print\n"
    "                     how far the ends differ (about the run's error)\n";

/* The rest of the help: the output (a second string, as C99 promises
   string literals of 4095 characters only). */
static const char usage_output[] =
    "\n"
    "Output: header t,kind,id,x,y,z,vx,vy,vz,qw,qx,qy,qz,wx,wy,wz then one row\n"
    "per object per recorded step, numbers as %.17g. kind is particle, tracer\n"
    "or body; id is the object's id index (as in handle:id()); a tracer's\n"
    "velocity is the field velocity at its position. For bodies x is the\n"
    "centre of mass, q the orientation (world from principal axes) and w the\n"
    "angular velocity in the world frame; the last seven fields are empty for\n"
    "particles and tracers. Steps are recorded at t = 0, every record_every\n"
    "seconds (rounded to whole steps), and at the end.\n"
    "\n"
    "Before the run the stability advisor estimates the largest stable step\n"
    "of the integrator (spring modes and damping, drag) and warns when\n"
    "dt exceeds it, suggesting a step or an integrator.\n"
    "Summary (stdout): steps, simulated time, wall time, the advisor's\n"
    "verdict, the energy drift (E_end - E_start - W) / |E_start| with W\n"
    "the work of contacts, drag and damping (E: kinetic, rotational,\n"
    "gravity, springs, forces' potential), what the Lua used.\n"
    "Exit status: 0 on success, 1 when the scene or the run fails (a budget\n"
    "run out, a duration of more than 1e9 steps), 2 for a bad command line,\n"
    "128 + the signal's number after SIGINT, SIGTERM or SIGHUP (a second\n"
    "signal ends it at once).\n";

typedef struct options {
    const char *scene, *out, *integrator, *gltf, *plot;
    double dt, until, every, tol, guard;
    double max_instructions, max_memory; /* budgets; 0: no limit */
    int quiet, trust, check;
} options;

/* The first SIGINT, SIGTERM or SIGHUP; the Lua budgets' hook reads it too
   (tb_lua_limits.stop), so a scene stuck in Lua stops at once. */
static volatile sig_atomic_t stop_signal;

/* The temporary output, while it exists: a second signal removes it. */
static char temp_path[4200];
static volatile sig_atomic_t temp_made;

static int die(int code, const char *fmt, const char *arg)
{
    fprintf(stderr, "tumble: ");
    fprintf(stderr, fmt, arg);
    fputc('\n', stderr);
    return code;
}

static void print_usage(FILE *f)
{
    char names[256] = "";
    int i;
    for (i = 0; tb_integrator_name(i); ++i) {
        if (i)
            strncat(names, ", ", sizeof names - strlen(names) - 1);
        strncat(names, tb_integrator_name(i), sizeof names - strlen(names) - 1);
    }
    fprintf(f, usage, names, DEFAULT_MAX_INSTRUCTIONS / 1e9, DEFAULT_MAX_MEMORY / (1024 * 1024));
    fputs(usage_output, f);
}

static int parse_number(const char *flag, const char *text, double *out, int allow_zero)
{
    char *end;
    double v;
    if (!text)
        return die(2, "%s needs a number", flag);
    v = strtod(text, &end);
    if (end == text || *end || !isfinite(v) || v < 0 || (v == 0 && !allow_zero))
        return die(2, "bad number '%s' (it must be finite and positive)", text);
    *out = v;
    return 0;
}

/* A budget: a number >= 0 with an optional suffix K, M or G, each `unit`
   times the one before; whole units, at most `most`. */
static int parse_budget(const char *flag, const char *text, double unit, double most, double *out)
{
    char *end;
    double v, scale = 1;
    if (!text)
        return die(2, "%s needs a number", flag);
    v = strtod(text, &end);
    if (end != text && *end && !end[1]) {
        const char *units = strchr("KkMmGg", *end);
        if (units) {
            int k = (int)(units - "KkMmGg") / 2;
            scale = k == 0 ? unit : k == 1 ? unit * unit : unit * unit * unit;
            ++end;
        }
    }
    v = floor(v * scale);
    if (end == text || *end || !(v >= 0 && v <= most))
        return die(2, "bad budget '%s' (a number >= 0, optionally followed by K, M or G)", text);
    *out = v;
    return 0;
}

static int parse_arguments(int argc, char **argv, options *o)
{
    int i, rc;
    memset(o, 0, sizeof *o);
    o->dt = o->until = o->every = o->tol = o->guard = -1;
    o->max_instructions = DEFAULT_MAX_INSTRUCTIONS;
    o->max_memory = DEFAULT_MAX_MEMORY;
    if (argc < 2)
        return print_usage(stderr), 2;
    if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))
        return print_usage(stdout), -1;
    if (!strcmp(argv[1], "--version"))
        return printf("tumble %d.%d.%d\n", TB_VERSION_MAJOR, TB_VERSION_MINOR, TB_VERSION_PATCH), -1;
    if (strcmp(argv[1], "run"))
        return die(2, "unknown command '%s' (try tumble --help)", argv[1]);
    for (i = 2; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL, *eq = strchr(a, '=');
        char name[64];
        int joined = 0; /* --opt=value: the value is in a, not the next argument */
        if (a[0] == '-' && a[1] == '-' && eq) {
            if ((size_t)(eq - a) >= sizeof name)
                return die(2, "unknown option '%s' (try tumble --help)", a);
            memcpy(name, a, (size_t)(eq - a));
            name[eq - a] = 0;
            a = name, v = eq + 1, joined = 1;
            if (!strcmp(a, "--trust") || !strcmp(a, "--quiet") || !strcmp(a, "--help") || !strcmp(a, "--check"))
                return die(2, "%s takes no value", a);
        }
        if (!strcmp(a, "--help") || !strcmp(a, "-h"))
            return print_usage(stdout), -1;
        if (!strcmp(a, "--out")) {
            if (!v || !*v)
                return die(2, "%s needs a file name", a);
            o->out = v, i += !joined;
        } else if (!strcmp(a, "--gltf")) {
            if (!v || !*v)
                return die(2, "%s needs a file name", a);
            o->gltf = v, i += !joined;
        } else if (!strcmp(a, "--plot")) {
            if (!v || !*v)
                return die(2, "%s needs a file name", a);
            o->plot = v, i += !joined;
        } else if (!strcmp(a, "--integrator")) {
            if (!v || !*v)
                return die(2, "%s needs a name", a);
            o->integrator = v, i += !joined;
        } else if (!strcmp(a, "--dt")) {
            if ((rc = parse_number(a, v, &o->dt, 0)))
                return rc;
            i += !joined;
        } else if (!strcmp(a, "--tol")) {
            if ((rc = parse_number(a, v, &o->tol, 0)))
                return rc;
            i += !joined;
        } else if (!strcmp(a, "--guard")) {
            if ((rc = parse_number(a, v, &o->guard, 0)))
                return rc;
            if (!(o->guard > 1))
                return die(2, "--guard must be a factor > 1 (got '%s')", v);
            i += !joined;
        } else if (!strcmp(a, "--until")) {
            if ((rc = parse_number(a, v, &o->until, 1)))
                return rc;
            i += !joined;
        } else if (!strcmp(a, "--every")) {
            if ((rc = parse_number(a, v, &o->every, 1)))
                return rc;
            i += !joined;
        } else if (!strcmp(a, "--trust")) {
            o->trust = 1;
        } else if (!strcmp(a, "--max-instructions")) {
            if ((rc = parse_budget(a, v, 1000, 1e18, &o->max_instructions)))
                return rc;
            i += !joined;
        } else if (!strcmp(a, "--max-memory")) {
            if ((rc = parse_budget(a, v, 1024, (double)((size_t)-1 / 2), &o->max_memory)))
                return rc;
            i += !joined;
        } else if (!strcmp(a, "--quiet")) {
            o->quiet = 1;
        } else if (!strcmp(a, "--check")) {
            o->check = 1;
        } else if (a[0] == '-') {
            return die(2, "unknown option '%s' (try tumble --help)", a);
        } else if (!o->scene) {
            o->scene = a;
        } else {
            return die(2, "unexpected argument '%s'", a);
        }
    }
    if (!o->scene)
        return die(2, "%s", "run needs a scene script");
    return 0;
}

static void on_signal(int sig)
{
    if (stop_signal) { /* the second: leave at once */
        if (temp_made)
            unlink(temp_path);
        _exit(128 + sig);
    }
    stop_signal = sig;
}

/* Catch SIGINT, SIGTERM and SIGHUP, unless ignored (as nohup leaves SIGHUP). */
static void catch_signals(void)
{
    static const int signals[] = { SIGINT, SIGTERM, SIGHUP };
    struct sigaction sa, old;
    size_t k;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART;
    for (k = 0; k < sizeof signals / sizeof signals[0]; ++k)
        if (sigaction(signals[k], NULL, &old) == 0 && old.sa_handler != SIG_IGN)
            sigaction(signals[k], &sa, NULL);
}

static const char *signal_name(int sig)
{
    return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : "a signal";
}

static int add_traceback(lua_State *L)
{
    const char *msg = lua_tostring(L, 1);
    if (!msg)
        msg = lua_pushfstring(L, "(error object is a %s value)", luaL_typename(L, 1));
    luaL_traceback(L, L, msg, 1);
    return 1;
}

/* Print the first line of the Lua error on top of the stack. */
static int die_with_lua_error(lua_State *L, const char *prefix)
{
    const char *msg = lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1) : NULL;
    size_t n = strcspn(msg ? msg : "", "\n");
    fprintf(stderr, "tumble: %s%.*s\n", prefix, (int)n, msg ? msg : "(no message)");
    return 1;
}

/* When a signal came or a budget ran out: say so (with the world's time
   when w is given) and return the exit status; else 0. */
static int report_stop(lua_State *L, const options *o, tb_world *w)
{
    const char *why = tb_lua_limit_error(L);
    char at[64] = "";
    if (w)
        snprintf(at, sizeof at, "at t = %.17g s: ", tb_world_time(w));
    if (stop_signal) {
        fprintf(stderr, "tumble: %s: %sinterrupted by %s; no output written\n", o->scene, at,
                signal_name(stop_signal));
        return 128 + stop_signal;
    }
    if (why) {
        fprintf(stderr, "tumble: %s: %s%s; raise it with %s\n", o->scene, at, why,
                strncmp(why, "memory", 6) ? "--max-instructions" : "--max-memory");
        return 1;
    }
    return 0;
}

/* Read the whole file: scenes load as text, never as bytecode. */
static char *read_file(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    char *buf = NULL;
    size_t cap = 0, n = 0, got;
    if (!f)
        return NULL;
    do {
        if (n == cap) {
            char *more = realloc(buf, cap ? 2 * cap : 65536);
            if (!more) {
                free(buf);
                fclose(f);
                return NULL;
            }
            buf = more;
            cap = cap ? 2 * cap : 65536;
        }
        got = fread(buf + n, 1, cap - n, f);
        n += got;
    } while (got > 0);
    if (ferror(f)) {
        free(buf);
        buf = NULL;
    }
    fclose(f);
    *size = n;
    return buf;
}

static double read_clock(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Rows for every object at the current time. Returns rows written or -1. */
static long record_rows(FILE *f, lua_State *L, int world_idx, tb_world *w, double **tracer_vel, size_t *cap)
{
    const double t = tb_world_time(w);
    size_t i, n = tb_world_tracer_count(w);
    long rows = 0;
    if (n) {
        const double *x;
        if (*cap < 3 * n) {
            double *more = realloc(*tracer_vel, 3 * n * sizeof(double));
            if (!more)
                return -1;
            *tracer_vel = more;
            *cap = 3 * n;
        }
        if (tb_lua_tracer_velocities(L, world_idx, *tracer_vel) != TB_OK)
            return -1;
        x = tb_world_tracer_positions(w);
        for (i = 0; i < n; ++i, ++rows) {
            const double *p = x + 3 * i, *v = *tracer_vel + 3 * i;
            fprintf(f, "%.17g,tracer,%u,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,,,,,,,\n", t,
                    (unsigned)tb_world_tracer_at(w, i).index1, p[0], p[1], p[2], v[0], v[1], v[2]);
        }
    }
    n = tb_world_particle_count(w);
    if (n) {
        const double *x = tb_world_particle_positions(w), *vel = tb_world_particle_velocities(w);
        for (i = 0; i < n; ++i, ++rows) {
            const double *p = x + 3 * i, *v = vel + 3 * i;
            fprintf(f, "%.17g,particle,%u,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,,,,,,,\n", t,
                    (unsigned)tb_world_particle_at(w, i).index1, p[0], p[1], p[2], v[0], v[1], v[2]);
        }
    }
    n = tb_world_body_count(w);
    for (i = 0; i < n; ++i, ++rows) {
        tb_body_id id = tb_world_body_at(w, i);
        double x[3], q[4], v[3], om[3];
        tb_body_position(w, id, x);
        tb_body_orientation(w, id, q);
        tb_body_velocity(w, id, v);
        tb_body_angular_velocity(w, id, om);
        fprintf(f, "%.17g,body,%u,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n",
                t, (unsigned)id.index1, x[0], x[1], x[2], v[0], v[1], v[2], q[0], q[1], q[2], q[3], om[0], om[1],
                om[2]);
    }
    return rows;
}

/* The scene's name without directory and extension, plus ".csv". */
static void make_out_path(const char *scene, char *out, size_t size)
{
    const char *base = strrchr(scene, '/'), *dot;
    size_t n;
    base = base ? base + 1 : scene;
    dot = strrchr(base, '.');
    n = dot && dot != base ? (size_t)(dot - base) : strlen(base);
    snprintf(out, size, "%.*s.csv", (int)n, base);
}

static double read_scene_number(lua_State *L, int idx, const char *key, double fallback, int *bad)
{
    double v = fallback;
    int isnum = 1;
    if (lua_getfield(L, idx, key) != LUA_TNIL)
        v = lua_tonumberx(L, -1, &isnum);
    lua_pop(L, 1);
    if (!isnum || !isfinite(v) || v < 0)
        *bad = 1;
    return v;
}

/* What load_scene reads and finds. */
typedef struct scene {
    const options *o;
    const char *text;
    size_t size;
    double duration, every;
    int bad;
} scene;

/* Under lua_pcall, argument 1 the scene record: load the script as text,
   run it, read its table (whose fields may run metamethods); returns the
   world. */
static int load_scene(lua_State *L)
{
    scene *s = lua_touserdata(L, 1);
    const options *o = s->o;
    int t;
    lua_pushfstring(L, "@%s", o->scene);
    if (luaL_loadbufferx(L, s->text, s->size, lua_tostring(L, -1), "t") != LUA_OK)
        return lua_error(L);
    lua_call(L, 0, 1);
    if (!lua_istable(L, -1))
        return luaL_error(L, "%s: the scene must return a table { world = w, duration = seconds }", o->scene);
    t = lua_gettop(L);
    lua_getfield(L, t, "world");
    if (!luaL_testudata(L, -1, "tumble.world"))
        return luaL_error(L, "%s: the scene's table has no 'world' (a tumble.world)", o->scene);
    if (!tb_lua_to_world(L, -1))
        return luaL_error(L, "%s: the scene's world is closed (a `local w <close>` closes it when the script "
                             "returns: scenes that return their world must not use <close>)", o->scene);
    s->duration = o->until >= 0 ? o->until : read_scene_number(L, t, "duration", -1, &s->bad);
    s->every = o->every >= 0 ? o->every : read_scene_number(L, t, "record_every", 1.0 / 60, &s->bad);
    lua_pushvalue(L, t + 1);
    return 1;
}

/* Under lua_pcall: the whole standard library (--trust) and the module,
   then math.randomseed(0). Lua 5.4 seeds math.random from the clock: the
   fixed seed makes scenes repeatable. */
static int open_libraries(lua_State *L)
{
    if (lua_toboolean(L, 1)) {
        luaL_openlibs(L);
        luaL_requiref(L, "tumble", luaopen_tumble, 0);
    }
    lua_getglobal(L, "math");
    lua_getfield(L, -1, "randomseed");
    lua_pushinteger(L, 0);
    lua_call(L, 1, 0);
    return 0;
}

/* Prepare the state: the sandbox in the scene's folder, or --trust's
   libraries. Returns 0 or the exit status. */
static int prepare_state(lua_State *L, const options *o)
{
    int rc = LUA_OK;
    if (!o->trust) {
        char folder[4096];
        const char *slash = strrchr(o->scene, '/');
        if (!slash)
            snprintf(folder, sizeof folder, ".");
        else
            snprintf(folder, sizeof folder, "%.*s", slash == o->scene ? 1 : (int)(slash - o->scene), o->scene);
        rc = tb_lua_sandbox(L, folder);
    }
    if (rc == LUA_OK) {
        lua_pushcfunction(L, open_libraries);
        lua_pushboolean(L, o->trust);
        rc = lua_pcall(L, 1, 0, 0);
    }
    if (rc != LUA_OK) {
        int stopped = report_stop(L, o, NULL);
        return stopped ? stopped : die_with_lua_error(L, "cannot prepare Lua: ");
    }
    lua_settop(L, 0);
    return 0;
}

/* Make the temporary output next to out_path, named out_path.part.XXXXXX
   (mkstemp), with the permissions a new file gets. */
static FILE *open_temp(const char *out_path)
{
    mode_t mask = umask(0);
    FILE *f;
    int fd;
    umask(mask);
    snprintf(temp_path, sizeof temp_path, "%s.part.XXXXXX", out_path);
    fd = mkstemp(temp_path);
    if (fd < 0)
        return NULL;
    temp_made = 1;
    if (fchmod(fd, 0666 & ~mask) != 0 || !(f = fdopen(fd, "w"))) {
        close(fd);
        unlink(temp_path);
        temp_made = 0;
        return NULL;
    }
    return f;
}

static void remove_temp(void)
{
    if (temp_made)
        remove(temp_path);
    temp_made = 0;
}

/* The shapes beside the trajectory: FILE.csv's FILE.shapes.csv (or
   FILE.shapes.csv beside any other name), one row per shape as the world
   holds it at the end of the run: its id, type, body (the trajectory's
   body id; 0: static), pose in the body's principal frame (static: world),
   sizes (0 where the type has none) and a plane's normal and offset. Written through a temporary file
   and renamed, as the trajectory is. Returns 0, or 1 with a message. */
static int write_shapes(const char *out_path, tb_world *w)
{
    static const char *const types[] = { "sphere", "capsule", "box", "plane" };
    char path[4200];
    size_t n = strlen(out_path), i;
    FILE *f;
    int failed;
    if (n >= 4 && !strcmp(out_path + n - 4, ".csv"))
        n -= 4;
    snprintf(path, sizeof path, "%.*s.shapes.csv", (int)n, out_path);
    if (!(f = open_temp(path))) {
        fprintf(stderr, "tumble: cannot write a temporary file next to '%s': %s\n", path, strerror(errno));
        return 1;
    }
    fprintf(f, "shape,type,body,x,y,z,qw,qx,qy,qz,radius,half_length,hx,hy,hz,nx,ny,nz,offset\n");
    for (i = 0; i < tb_world_shape_count(w); ++i) {
        tb_shape_def d;
        if (tb_shape_definition(w, tb_world_shape_at(w, i), &d) != TB_OK)
            continue;
        fprintf(f, "%u,%s,%u,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,"
                   "%.17g,%.17g\n",
                (unsigned)tb_world_shape_at(w, i).index1, types[d.type], (unsigned)d.body.index1, d.position[0],
                d.position[1], d.position[2], d.orientation[0], d.orientation[1], d.orientation[2],
                d.orientation[3], d.type == TB_SHAPE_SPHERE || d.type == TB_SHAPE_CAPSULE ? d.radius : 0,
                d.half_length, d.half_extents[0], d.half_extents[1], d.half_extents[2],
                d.type == TB_SHAPE_PLANE ? d.normal[0] : 0, d.type == TB_SHAPE_PLANE ? d.normal[1] : 0,
                d.type == TB_SHAPE_PLANE ? d.normal[2] : 0, d.offset);
    }
    failed = ferror(f) | fclose(f);
    if (failed || rename(temp_path, path)) {
        const int why = errno;
        remove_temp();
        fprintf(stderr, "tumble: cannot write '%s': %s\n", path, strerror(why));
        return 1;
    }
    temp_made = 0;
    return 0;
}

/* Before the run: can a file be made in path's folder? Returns 0, or 1
   with a message, so that a long run does not end in a folder it cannot
   write. */
static int check_folder(const char *flag, const char *path)
{
    char folder[4200];
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(folder, sizeof folder, ".");
    else
        snprintf(folder, sizeof folder, "%.*s", slash == path ? 1 : (int)(slash - path), path);
    if (access(folder, W_OK) != 0) {
        fprintf(stderr, "tumble: %s %s: cannot write in '%s': %s\n", flag, path, folder, strerror(errno));
        return 1;
    }
    return 0;
}

/* The run as binary glTF (gltf_writer.c), through a temporary file
   renamed at the end as the trajectory is; a signal while it is written
   removes it. Returns 0, or the exit status with a message. */
static int write_gltf(const char *path, gltf_writer *g, tb_world *w)
{
    FILE *f = open_temp(path);
    int failed, why;
    if (!f) {
        fprintf(stderr, "tumble: cannot write a temporary file next to '%s': %s\n", path, strerror(errno));
        return 1;
    }
    if (gltf_write(g, w, f)) {
        fclose(f);
        remove_temp();
        fprintf(stderr, "tumble: --gltf %s: %s\n", path, gltf_message(g));
        return 1;
    }
    failed = ferror(f) | fclose(f);
    why = errno;
    if (stop_signal) {
        remove_temp();
        fprintf(stderr, "tumble: %s: interrupted by %s; not written\n", path, signal_name(stop_signal));
        return 128 + stop_signal;
    }
    if (failed || rename(temp_path, path)) {
        if (!failed)
            why = errno;
        remove_temp();
        fprintf(stderr, "tumble: cannot write '%s': %s\n", path, strerror(why));
        return 1;
    }
    temp_made = 0;
    return 0;
}

/* The plot (run_plot.c): gnuplot draws into a temporary file of ours,
   renamed at the end; a signal while it draws removes it. Returns 0, or
   the exit status with a message. */
static int write_plot(const char *path, run_plot *p, const char *title, int contacts)
{
    char why[256];
    FILE *f = open_temp(path);
    if (!f) {
        fprintf(stderr, "tumble: cannot write a temporary file next to '%s': %s\n", path, strerror(errno));
        return 1;
    }
    fclose(f);
    if (plot_draw(p, temp_path, title, contacts, why, sizeof why) && !stop_signal) {
        remove_temp();
        fprintf(stderr, "tumble: --plot %s: %s\n", path, why);
        return 1;
    }
    if (stop_signal) {
        remove_temp();
        fprintf(stderr, "tumble: %s: interrupted by %s; not written\n", path, signal_name(stop_signal));
        return 128 + stop_signal;
    }
    if (rename(temp_path, path)) {
        const int why_errno = errno;
        remove_temp();
        fprintf(stderr, "tumble: cannot write '%s': %s\n", path, strerror(why_errno));
        return 1;
    }
    temp_made = 0;
    return 0;
}

/* --check: the positions (m) and orientations of every particle, tracer
   and body, in slot order, appended to out (room for them all). */
static size_t copy_pose(const tb_world *w, double *out)
{
    const size_t np = tb_world_particle_count(w), nt = tb_world_tracer_count(w), nb = tb_world_body_count(w);
    if (np)
        memcpy(out, tb_world_particle_positions(w), 3 * np * sizeof(double));
    if (nt)
        memcpy(out + 3 * np, tb_world_tracer_positions(w), 3 * nt * sizeof(double));
    if (nb) {
        memcpy(out + 3 * (np + nt), tb_world_body_positions(w), 3 * nb * sizeof(double));
        memcpy(out + 3 * (np + nt + nb), tb_world_body_orientations(w), 4 * nb * sizeof(double));
    }
    return 3 * (np + nt + nb) + 4 * nb;
}

/* --check: restore the start, run to the same time at h / 2 (the
   adaptive methods also at a tolerance 100 times tighter: a frame step
   that passes both tolerances would give the same run), and print the
   largest distance (m) and turn (rad) between the two runs' ends. Both
   errors fall with the step (tolerance) as the method's order (in
   proportion), so the difference is close to the first run's error
   (docs/command.md). Lua state the scene's callbacks keep is not rewound. */
static int check_run(lua_State *L, int world_idx, tb_world *w, const tb_snapshot *start, double dt, long steps,
                     FILE *report)
{
    const size_t np = tb_world_particle_count(w), nt = tb_world_tracer_count(w), nb = tb_world_body_count(w);
    const char *name = tb_world_integrator(w);
    const int adaptive = !strcmp(name, "dopri5") || !strcmp(name, "auto");
    const size_t count = 3 * (np + nt + nb) + 4 * nb;
    double *first = malloc(2 * (count ? count : 1) * sizeof(double)), *second, far = 0, turn = 0, share;
    size_t i;
    long step;
    if (!first)
        return die(1, "%s", "--check: out of memory");
    second = first + count;
    copy_pose(w, first);
    if (tb_world_restore(w, start) != TB_OK ||
        (adaptive && tb_world_set_tolerance(w, tb_world_tolerance(w) / 100) != TB_OK)) {
        free(first);
        return die(1, "--check: %s", tb_world_message(w));
    }
    for (step = 0; step < 2 * steps; ++step)
        if (stop_signal || tb_lua_limit_error(L) || tb_lua_step(L, world_idx, dt / 2) != TB_OK) {
            free(first);
            fprintf(stderr, "tumble: --check: the rerun stopped at t = %.17g s: %s\n", tb_world_time(w),
                    stop_signal ? "interrupted" : tb_world_message(w));
            return 1;
        }
    copy_pose(w, second);
    for (i = 0; i < np + nt + nb; ++i)
        far = fmax(far, sqrt(pow(first[3 * i] - second[3 * i], 2) + pow(first[3 * i + 1] - second[3 * i + 1], 2) +
                             pow(first[3 * i + 2] - second[3 * i + 2], 2)));
    for (i = 0; i < nb; ++i) { /* the turn between two unit quaternions: 2 atan2(|vector part of a* b|, |a.b|) */
        const double *a = first + 3 * (np + nt + nb) + 4 * i, *b = second + 3 * (np + nt + nb) + 4 * i;
        const double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
        const double x = a[0] * b[1] - a[1] * b[0] - (a[2] * b[3] - a[3] * b[2]);
        const double y = a[0] * b[2] - a[2] * b[0] - (a[3] * b[1] - a[1] * b[3]);
        const double z = a[0] * b[3] - a[3] * b[0] - (a[1] * b[2] - a[2] * b[1]);
        turn = fmax(turn, 2 * atan2(sqrt(x * x + y * y + z * z), fabs(d)));
    }
    free(first);
    /* a method of order p errs by e at h and e / 2^p at h / 2: the
       difference is e (1 - 2^-p); the adaptive ones' error follows the
       tolerance, so at tol / 100 the difference is nearly all of e */
    for (i = 0; tb_integrator_name((int)i) && strcmp(tb_integrator_name((int)i), name); ++i)
        continue;
    share = adaptive ? 1 : 1 - pow(2, -tb_integrator_order((int)i));
    if (adaptive)
        fprintf(report, "check       rerun at dt %.6g s, tolerance %g: the ends differ by %.3g m", dt / 2,
                tb_world_tolerance(w), far);
    else
        fprintf(report, "check       rerun at dt %.6g s: the ends differ by %.3g m", dt / 2, far);
    if (nb)
        fprintf(report, " and %.3g rad", turn);
    if (share < 1) {
        fprintf(report, "; this run's error is about %.3g m", far / share);
        if (nb)
            fprintf(report, " and %.3g rad", turn / share);
        fprintf(report, " (order %d: the difference / %.4g)\n", tb_integrator_order((int)i), share);
    } else
        fprintf(report, ", about this run's error\n");
    return 0;
}

/* Run the scene whose text is in s (read by main). */
static int run_scene(lua_State *L, const options *o, scene *s)
{
    char out_path[4096];
    size_t cap = 0;
    tb_world *w;
    tb_energy e0, e1;
    tb_work work0, work1;
    double dt, duration, every, t0, wall, *tracer_vel = NULL, n;
    long steps, step, every_steps, rows = 0, r, substeps;
    int world_idx, have_advice, rc, failed, unwritten, to_stdout, write_error;
    /* a progress line on a terminal, never into a pipe or a file */
    const int progress = !o->quiet && isatty(STDERR_FILENO);
    double shown;
    tb_advice advice;
    tb_snapshot *start = NULL;
    FILE *f, *report;
    gltf_writer *gw = NULL;
    run_plot *pr = NULL;
    int gltf_failed = 0, plot_failed = 0;

    lua_pushcfunction(L, add_traceback);
    lua_pushcfunction(L, load_scene);
    lua_pushlightuserdata(L, s);
    rc = lua_pcall(L, 1, 1, 1);
    if ((rc != LUA_OK || tb_lua_limit_error(L) || stop_signal) && (failed = report_stop(L, o, NULL)) != 0)
        return failed;
    if (rc != LUA_OK)
        return die_with_lua_error(L, "");
    world_idx = lua_gettop(L);
    w = tb_lua_to_world(L, world_idx);
    if (!w) /* the table's metamethods closed it after handing it over */
        return die(1, "%s: the scene's world is closed", o->scene);

    if (o->integrator && tb_world_set_integrator(w, o->integrator) != TB_OK)
        return die(1, "%s", tb_world_message(w));
    if (o->tol > 0 && tb_world_set_tolerance(w, o->tol) != TB_OK)
        return die(1, "%s", tb_world_message(w));
    /* the command always guards against blow-up: scenes are small, and a
       clear message beats a file of NaN */
    if (tb_world_set_guard(w, o->guard > 1 ? o->guard : (tb_world_guard(w) > 1 ? tb_world_guard(w) : HUGE_VAL))
        != TB_OK)
        return die(1, "%s", tb_world_message(w));
    dt = o->dt > 0 ? o->dt : tb_lua_world_dt(L, world_idx);
    duration = s->duration;
    every = s->every;
    if (s->bad || duration < 0)
        return die(1, "%s: the scene's table needs 'duration' (and 'record_every', if given) as seconds >= 0",
                   o->scene);
    n = ceil(duration / dt - 1e-9);
    if (!(n <= MAX_STEPS)) {
        fprintf(stderr, "tumble: %s: a duration of %g s at dt %g s is %.3g steps; the command takes at most 1e9 "
                        "(shorten the duration or lengthen the step)\n", o->scene, duration, dt, n);
        return 1;
    }
    steps = n > 0 ? (long)n : 0;
    n = every > 0 ? floor(every / dt + 0.5) : 1;
    every_steps = n >= 1 ? (n <= MAX_STEPS ? (long)n : (long)MAX_STEPS + 1) : 1;

    if (o->out)
        snprintf(out_path, sizeof out_path, "%s", o->out);
    else
        make_out_path(o->scene, out_path, sizeof out_path);
    if (o->check && tb_world_snapshot(w, &start) != TB_OK)
        return die(1, "--check: %s", tb_world_message(w));
    /* Before running: would this step blow up? Warn, but run as asked. */
    have_advice = tb_world_advise(w, dt, &advice) == TB_OK;
    if (have_advice && advice.exceeded)
        fprintf(stderr, "tumble: warning: %s\n", advice.text);
    to_stdout = !strcmp(out_path, "-");
    report = to_stdout ? stderr : stdout;
    if (o->gltf && !(gw = gltf_begin(w)))
        return die(1, "%s", "out of memory for the glTF writer");
    if (o->plot && !(pr = plot_begin())) {
        gltf_free(gw);
        return die(1, "%s", "out of memory for the plot");
    }
    f = to_stdout ? stdout : open_temp(out_path);
    if (!f) {
        fprintf(stderr, "tumble: cannot write a temporary file next to '%s': %s\n", out_path, strerror(errno));
        gltf_free(gw);
        plot_free(pr);
        return 1;
    }
    fprintf(f, "t,kind,id,x,y,z,vx,vy,vz,qw,qx,qy,qz,wx,wy,wz\n");

    work0 = tb_world_work(w);
    t0 = read_clock();
    /* the energy runs the force callbacks: their failure is the run's */
    r = tb_lua_energy(L, world_idx, &e0) == TB_OK ? record_rows(f, L, world_idx, w, &tracer_vel, &cap) : -1;
    if (r >= 0 && gw && gltf_record(gw, w))
        r = -1, gltf_failed = 1;
    if (r >= 0 && pr && plot_record(pr, w))
        r = -1, plot_failed = 1;
    shown = t0 + 1; /* a progress line from the first second on */
    for (step = 1; r >= 0 && step <= steps; ++step) {
        rows += r;
        r = 0;
        if (stop_signal || tb_lua_limit_error(L) || tb_lua_step(L, world_idx, dt) != TB_OK) {
            r = -1;
            break;
        }
        if (step % every_steps == 0 || step == steps) {
            r = record_rows(f, L, world_idx, w, &tracer_vel, &cap);
            if (r >= 0 && gw && gltf_record(gw, w))
                r = -1, gltf_failed = 1;
            if (r >= 0 && pr && plot_record(pr, w))
                r = -1, plot_failed = 1;
        }
        if (progress && step % 64 == 0 && read_clock() >= shown) {
            const double spent = read_clock() - t0, rate = (double)step / spent;
            fprintf(stderr, "\rtumble: t = %.4g of %.4g s, %.3g steps/s, about %.0f s left\033[K",
                    tb_world_time(w), (double)steps * dt, rate, (double)(steps - step) / rate);
            shown = read_clock() + 0.25;
        }
    }
    if (r >= 0 && tb_lua_energy(L, world_idx, &e1) != TB_OK)
        r = -1;
    if (progress && shown > t0 + 1)
        fprintf(stderr, "\r\033[K"); /* the line goes once the run ends */
    wall = read_clock() - t0;
    free(tracer_vel);
    failed = r < 0 || stop_signal || tb_lua_limit_error(L);
    unwritten = to_stdout ? (fflush(f) != 0) | ferror(f) : ferror(f) | fclose(f);
    write_error = errno;
    if (failed || unwritten) {
        remove_temp();
        if ((rc = report_stop(L, o, w)) == 0 && gltf_failed)
            fprintf(stderr, "tumble: --gltf %s: at t = %.17g s: %s\n", o->gltf, tb_world_time(w), gltf_message(gw));
        else if (rc == 0 && plot_failed)
            fprintf(stderr, "tumble: --plot %s: out of memory for the plot's frames\n", o->plot);
        gltf_free(gw);
        plot_free(pr);
        if (rc != 0 || gltf_failed || plot_failed)
            return rc ? rc : 1;
        if (r < 0)
            fprintf(stderr, "tumble: %s: at t = %.17g s: %s\n", o->scene, tb_world_time(w), tb_world_message(w));
        else
            fprintf(stderr, "tumble: error writing '%s': %s\n", to_stdout ? "stdout" : temp_path,
                    strerror(write_error));
        return 1;
    }
    rows += r;
    if (!to_stdout && rename(temp_path, out_path)) {
        const int why = errno;
        remove_temp();
        fprintf(stderr, "tumble: cannot rename to '%s': %s\n", out_path, strerror(why));
        gltf_free(gw);
        plot_free(pr);
        return 1;
    }
    temp_made = 0;
    rc = to_stdout ? 0 : write_shapes(out_path, w);
    if (!rc && gw)
        rc = write_gltf(o->gltf, gw, w);
    if (!rc && pr)
        rc = write_plot(o->plot, pr, o->scene, tb_world_shape_count(w) > 0);
    if (rc) {
        gltf_free(gw);
        plot_free(pr);
        return rc;
    }
    work1 = tb_world_work(w);
    if (!o->quiet) {
        unsigned long long executed;
        size_t peak;
        char budget[64];
        fprintf(report, "scene       %s\n", o->scene);
        if (tb_world_auto_choice(w, &substeps))
            fprintf(report, "integrator  auto: %s, %ld substep%s per step, dt %.6g s, tolerance %g\n",
                   tb_world_auto_choice(w, NULL), substeps, substeps == 1 ? "" : "s", dt, tb_world_tolerance(w));
        else
            fprintf(report, "integrator  %s, dt %.6g s\n", tb_world_integrator(w), dt);
        fprintf(report, "objects     %zu particles, %zu tracers, %zu springs, %zu bodies\n", tb_world_particle_count(w),
               tb_world_tracer_count(w), tb_world_spring_count(w), tb_world_body_count(w));
        fprintf(report, "steps       %ld, simulated %.6g s, wall %.3f ms (%.3g us/step)\n", steps, tb_world_time(w),
               1e3 * wall, steps ? 1e6 * wall / (double)steps : 0.0);
        /* the drift is the integrator's: what contacts, drag and damping
           took is counted apart (tb_work), the callbacks' potential in */
        const double contacts = work1.contact_work - work0.contact_work;
        const double damping = work1.damping_work - work0.damping_work;
        const double drift = e1.total - e0.total - contacts - damping;
        fprintf(report, "energy      %.9g J -> %.9g J", e0.total, e1.total);
        if (contacts != 0 || damping != 0)
            fprintf(report, ", contacts %.6g J, drag and damping %.6g J", contacts, damping);
        if (e0.total != 0)
            fprintf(report, ", relative drift %.3e", drift / fabs(e0.total));
        else
            fprintf(report, ", relative drift n/a (starts at 0)");
        fprintf(report, "%s\n", e0.potential != 0 || e1.potential != 0 ? " (force callbacks' potential in)" : "");
        if (have_advice)
            fprintf(report, "stability   %s\n", advice.text);
        tb_lua_usage(L, &executed, &peak);
        if (o->max_instructions > 0)
            snprintf(budget, sizeof budget, "%llu of %.0f", executed, o->max_instructions);
        else if (o->max_memory > 0)
            snprintf(budget, sizeof budget, "%llu (no limit)", executed);
        else
            snprintf(budget, sizeof budget, "not counted");
        fprintf(report, "lua         %s, instructions %s, peak memory %.3g MiB", o->trust ? "trusted" : "sandboxed", budget,
               (double)peak / (1024 * 1024));
        if (o->max_memory > 0)
            fprintf(report, " of %.4g MiB\n", o->max_memory / (1024 * 1024));
        else
            fprintf(report, " (no limit)\n");
        fprintf(report, "wrote       %s (%ld rows)\n", to_stdout ? "stdout" : out_path, rows);
        if (!to_stdout && tb_world_shape_count(w))
            fprintf(report, "shapes      %zu, beside it in .shapes.csv\n", tb_world_shape_count(w));
        if (gw)
            fprintf(report, "gltf        %s (%zu frames)\n", o->gltf, gltf_frames(gw));
        if (pr)
            fprintf(report, "plot        %s\n", o->plot);
    }
    gltf_free(gw);
    plot_free(pr);
    if (start) {
        rc = check_run(L, world_idx, w, start, dt, steps, report);
        tb_snapshot_destroy(start);
        return rc;
    }
    return 0;
}

int main(int argc, char **argv)
{
    options o;
    tb_lua_limits limits;
    lua_State *L;
    scene s;
    int rc = parse_arguments(argc, argv, &o);
    if (rc)
        return rc < 0 ? 0 : rc;
    /* what the outputs need, before a run that may be long */
    if ((o.gltf && check_folder("--gltf", o.gltf)) || (o.plot && check_folder("--plot", o.plot)))
        return 1;
    if (o.plot && !plot_gnuplot_found())
        return die(1, "%s", "--plot draws with gnuplot, which is not on PATH (on Debian: apt-get install gnuplot-nox)");
    memset(&s, 0, sizeof s);
    s.o = &o;
    s.text = read_file(o.scene, &s.size);
    if (!s.text)
        return die(1, "cannot read scene '%s'", o.scene);
    catch_signals();
    memset(&limits, 0, sizeof limits);
    limits.instructions = (unsigned long long)o.max_instructions;
    limits.memory = (size_t)o.max_memory;
    limits.stop = &stop_signal;
    L = tb_lua_newstate(&limits);
    if (!L) {
        free((char *)s.text);
        return die(1, "%s", o.max_memory > 0 ? "cannot create a Lua state within the memory budget; raise it with "
                                               "--max-memory" : "cannot create a Lua state (out of memory)");
    }
    rc = prepare_state(L, &o);
    if (!rc)
        rc = run_scene(L, &o, &s);
    free((char *)s.text);
    lua_close(L);
    return rc;
}
