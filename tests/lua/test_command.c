/* test_command.c: the `tumble` command as a user runs it. Every scene runs
   and writes CSV rows that parse; broken scripts and bad arguments exit
   non-zero with a one-line message and leave no file behind. */
#define _POSIX_C_SOURCE 200809L
#include "test_main.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#ifndef TUMBLE_EXE
#error "TUMBLE_EXE must name the tumble executable"
#endif

static char err_text[4096], out_text[8192];

/* Each test process works in its own folder, so ctest -j can run cases
   side by side. */
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

static void slurp(const char *path, char *buf, size_t size)
{
    FILE *f = fopen(path, "r");
    size_t n = 0;
    buf[0] = 0;
    if (f) {
        n = fread(buf, 1, size - 1, f);
        fclose(f);
    }
    buf[n] = 0;
}

static int exists(const char *path)
{
    return access(path, F_OK) == 0;
}

/* Run `tumble ARGS` in WORK_DIR; returns its exit status. */
static int tumble(const char *args)
{
    char cmd[2048];
    int rc;
    snprintf(cmd, sizeof cmd, "cd '%s' && '%s' %s > out.txt 2> err.txt", work_dir(), TUMBLE_EXE, args);
    rc = system(cmd);
    snprintf(cmd, sizeof cmd, "%s/err.txt", work_dir());
    slurp(cmd, err_text, sizeof err_text);
    snprintf(cmd, sizeof cmd, "%s/out.txt", work_dir());
    slurp(cmd, out_text, sizeof out_text);
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

static void write_file(const char *name, const char *text)
{
    char path[1100];
    FILE *f;
    snprintf(path, sizeof path, "%s/%s", work_dir(), name);
    f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static void work_path(char *path, size_t size, const char *name)
{
    snprintf(path, size, "%s/%s", work_dir(), name);
}

static double number(const char *field, const char *what)
{
    char *end;
    double v = strtod(field, &end);
    if (end == field || *end || !isfinite(v))
        fail_msg("%s '%s' is not a finite number", what, field);
    return v;
}

/* Parse a trajectory: header, then rows of 16 fields, the last 7 empty for
   particles and tracers. Returns the row count and the last row's numbers
   in last[] (t, id, x, y, z, vx, vy, vz, then qw, qx, qy, qz, wx, wy, wz for
   bodies). */
static long parse_csv(const char *path, const char *kind, double last[15])
{
    FILE *f = fopen(path, "r");
    char line[1024];
    long rows = 0;
    double t_prev = -1;
    assert_non_null(f);
    assert_non_null(fgets(line, sizeof line, f));
    assert_string_equal(line, "t,kind,id,x,y,z,vx,vy,vz,qw,qx,qy,qz,wx,wy,wz\n");
    while (fgets(line, sizeof line, f)) {
        char *fields[16], *p = line;
        int n = 0, k, body;
        line[strcspn(line, "\n")] = 0;
        /* split on every comma: empty fields count */
        fields[n++] = p;
        while ((p = strchr(p, ',')) != NULL) {
            *p++ = 0;
            if (n == 16) {
                n = 17; /* too many */
                break;
            }
            fields[n++] = p;
        }
        if (n != 16)
            fail_msg("row %ld has %d fields, not 16", rows + 1, n);
        body = !strcmp(fields[1], "body");
        for (k = 9; k < 16; ++k)
            if (!body && fields[k][0])
                fail_msg("row %ld: field %d should be empty for a %s", rows + 1, k + 1, fields[1]);
        if (body)
            for (k = 9; k < 16; ++k)
                last[k - 1] = number(fields[k], "a body field");
        if (strcmp(fields[1], kind))
            fail_msg("row %ld has kind '%s', expected '%s'", rows + 1, fields[1], kind);
        last[0] = number(fields[0], "t");
        if (last[0] < t_prev)
            fail_msg("time goes backwards at row %ld", rows + 1);
        t_prev = last[0];
        last[1] = number(fields[2], "id");
        for (k = 3; k < 9; ++k)
            last[k - 1] = number(fields[k], "a coordinate");
        ++rows;
    }
    fclose(f);
    return rows;
}

/* Run a shipped scene and check its CSV: rows = objects x recorded steps. */
static long run_scene(const char *scene, const char *kind, long objects, long records, double last[15])
{
    char args[1024], csv[1024];
    long rows;
    snprintf(args, sizeof args, "run '%s/%s.lua' --out %s.csv", SCENES_DIR, scene, scene);
    assert_int_equal(tumble(args), 0);
    assert_non_null(strstr(out_text, "steps"));
    assert_non_null(strstr(out_text, "wall"));
    assert_non_null(strstr(out_text, "relative drift"));
    work_path(csv, sizeof csv, scene);
    strcat(csv, ".csv");
    rows = parse_csv(csv, kind, last);
    assert_int_equal(rows, objects * records);
    strcat(csv, ".part");
    assert_false(exists(csv));
    return rows;
}

/* The default scene: a ball with linear drag. Its last row must match the
   closed form to Verlet's second-order error, about
   t (k h)^2 |v0 - g/k| / 6 = 3.8e-6 m here (measured 3.3e-6 m in z);
   1e-5 m leaves room for the next-order terms and no more. */
static void projectile_scene(void **state)
{
    double last[15], t, k = 0.05, gk = -9.81 / 0.05, x, z;
    (void)state;
    run_scene("projectile", "particle", 1, 76, last); /* t = 0, 1/30 ... 2.5 */
    t = last[0];
    assert_rel(t, 2.5, 1e-15);
    x = 9 * (1 - exp(-k * t)) / k;
    z = 1 + gk * t + (12 - gk) * (1 - exp(-k * t)) / k;
    assert_true(fabs(last[2] - x) < 1e-5);
    assert_true(fabs(last[4] - z) < 1e-5);
}

static void vortex_scene(void **state)
{
    double last[15];
    (void)state;
    run_scene("vortex", "tracer", 12, 161, last); /* 8 s every 1/20 s */
    /* tracer 12 started at radius 3: RK4 keeps it to 1e-8 over two turns */
    assert_true(fabs(hypot(last[2], last[3]) - 0.25 * last[1]) < 1e-8);
    /* its CSV velocity is the field's: |v| = omega r */
    assert_rel(hypot(last[5], last[6]), 2 * 3.14159265358979 / 4 * 0.25 * last[1], 1e-8);
}

static void oscillator_scene(void **state)
{
    double last[15];
    (void)state;
    run_scene("oscillator", "particle", 1, 501, last);
}

static void rope_scene(void **state)
{
    double last[15];
    (void)state;
    run_scene("rope", "particle", 20, 91, last);
}

static void cloth_scene(void **state)
{
    double last[15];
    (void)state;
    run_scene("cloth", "particle", 225, 92, last); /* every 33 steps of 1 ms, and the end */
}

/* Bodies: rows carry orientation and angular velocity. The flip conserves
   |L| = |I w| (world frame) along the whole run; checked on the last row
   through w and q: L_b = I R^T w. */
static void flip_scene(void **state)
{
    double last[15];
    (void)state;
    run_scene("flip", "body", 1, 601, last); /* 20 s every 1/30 s */
    assert_rel(hypot(hypot(last[8], last[9]), hypot(last[10], last[11])), 1, 1e-12); /* unit q */
}

static void top_scene(void **state)
{
    double last[15];
    (void)state;
    run_scene("top", "body", 1, 601, last);
}

static void tumbling_box_scene(void **state)
{
    double last[15];
    (void)state;
    run_scene("tumbling_box", "body", 1, 79, last);
    /* the centre of mass flies on a parabola: z(1.3) = 1 + 6 t - g t^2 / 2 */
    assert_rel(last[4], 1 + 6 * 1.3 - 9.81 * 1.3 * 1.3 / 2, 1e-12);
}

static void push_scene(void **state)
{
    double last[15];
    (void)state;
    run_scene("push", "body", 1, 181, last);
    assert_true(last[14] > 0); /* the thruster spun it up about +z */
}

/* The shapes beside the trajectory: bounce.lua (a plane and five balls of
   0.1 m on bodies) writes bounce.shapes.csv with its header and a row per
   shape: the plane static with its normal, each ball a sphere of radius
   0.1 on a body whose id is one of the trajectory's body ids. */
static void shapes_are_written_beside_the_trajectory(void **state)
{
    char args[2048], path[1100], line[1024];
    FILE *f;
    int rows = 0, spheres = 0, planes = 0;
    (void)state;
    snprintf(args, sizeof args, "run '%s/bounce.lua' --until 0.1 --out bounce.csv", SCENES_DIR);
    assert_int_equal(tumble(args), 0);
    assert_non_null(strstr(out_text, "shapes      6"));
    work_path(path, sizeof path, "bounce.shapes.csv");
    f = fopen(path, "r");
    assert_non_null(f);
    assert_non_null(fgets(line, sizeof line, f));
    assert_string_equal(line, "shape,type,body,x,y,z,qw,qx,qy,qz,radius,half_length,hx,hy,hz,nx,ny,nz,offset\n");
    while (fgets(line, sizeof line, f)) {
        unsigned id, body;
        char type[16];
        double r, nz;
        ++rows;
        assert_int_equal(sscanf(line, "%u,%15[a-z],%u,%*g,%*g,%*g,%*g,%*g,%*g,%*g,%lg,%*g,%*g,%*g,%*g,%*g,%*g,%lg",
                                &id, type, &body, &r, &nz), 5);
        if (!strcmp(type, "plane")) {
            ++planes;
            assert_true(body == 0 && nz == 1);
        } else {
            ++spheres;
            assert_string_equal(type, "sphere");
            assert_true(body >= 1 && body <= 5 && r == 0.1);
        }
    }
    fclose(f);
    assert_true(rows == 6 && planes == 1 && spheres == 5);
}

/* The PNG's width and height from its header: the 8-byte signature, then
   the IHDR chunk (length 13, "IHDR", width, height big-endian). 0 and 0
   when it is no PNG. */
static void png_size(const char *path, unsigned long *width, unsigned long *height)
{
    static const unsigned char signature[8] = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n' };
    unsigned char b[24];
    FILE *f = fopen(path, "rb");
    *width = *height = 0;
    if (!f)
        return;
    if (fread(b, 1, sizeof b, f) == sizeof b && !memcmp(b, signature, 8) && !memcmp(b + 12, "IHDR", 4)) {
        *width = (unsigned long)b[16] << 24 | (unsigned long)b[17] << 16 | (unsigned long)b[18] << 8 | b[19];
        *height = (unsigned long)b[20] << 24 | (unsigned long)b[21] << 16 | (unsigned long)b[22] << 8 | b[23];
    }
    fclose(f);
}

/* --plot: gnuplot draws a 1000 x 900 PNG (run_plot.c sets that size for
   two panels and for three), for a scene with contacts and one without,
   through a temporary file that does not stay; without gnuplot on PATH
   the command says so before running, with status 1 and no file. */
static void plot_is_drawn_with_gnuplot(void **state)
{
    char args[2048], path[1100];
    unsigned long width, height;
    const char *scenes[] = { "bounce.lua' --until 1", "projectile.lua'" };
    int k;
    (void)state;
    for (k = 0; k < 2; ++k) {
        snprintf(args, sizeof args, "run '%s/%s --out run.csv --plot run.png", SCENES_DIR, scenes[k]);
        assert_int_equal(tumble(args), 0);
        assert_non_null(strstr(out_text, "plot        run.png"));
        work_path(path, sizeof path, "run.png");
        png_size(path, &width, &height);
        assert_int_equal(width, 1000);
        assert_int_equal(height, 900);
        remove(path);
        snprintf(args, sizeof args, "ls -a '%s' | grep -q -F .part", work_dir());
        assert_int_equal(system(args), 256); /* grep found none: status 1 */
    }
    snprintf(args, sizeof args, "cd '%s' && PATH=/nonexistent '%s' run '%s/bounce.lua' --out nogp.csv --plot nogp.png "
                                "2> err.txt", work_dir(), TUMBLE_EXE, SCENES_DIR);
    k = system(args);
    assert_true(WIFEXITED(k) && WEXITSTATUS(k) == 1);
    work_path(path, sizeof path, "err.txt");
    slurp(path, err_text, sizeof err_text);
    assert_string_equal(err_text, "tumble: --plot draws with gnuplot, which is not on PATH (on Debian: apt-get "
                                  "install gnuplot-nox)\n");
    work_path(path, sizeof path, "nogp.png");
    assert_false(exists(path));
    work_path(path, sizeof path, "nogp.csv");
    assert_false(exists(path));
}

/* The reference scenes of the work-precision benchmark run as scenes too. */
static void reference_scenes_run(void **state)
{
    static const char *const names[] = { "oscillator", "damped", "kepler", "vortex", "projectile",
                                         "chain", "damped_chain", "cloth", "flip", "top", "pendulum" };
    size_t k;
    (void)state;
    for (k = 0; k < sizeof names / sizeof names[0]; ++k) {
        char args[1024], csv[1024];
        double last[15];
        snprintf(args, sizeof args, "run '%s/reference/%s.lua' --out ref.csv --quiet", SCENES_DIR, names[k]);
        if (tumble(args) != 0)
            fail_msg("reference scene %s failed: %s", names[k], err_text);
        work_path(csv, sizeof csv, "ref.csv");
        assert_true(parse_csv(csv, !strcmp(names[k], "vortex") ? "tracer"
                                   : !strcmp(names[k], "flip") || !strcmp(names[k], "top") ||
                                             !strcmp(names[k], "pendulum")
                                         ? "body"
                                                                                            : "particle",
                              last) > 0);
    }
}

static void broken_script_names_its_line(void **state)
{
    char csv[1024];
    (void)state;
    write_file("broken.lua", "local tumble = require 'tumble'\nlocal w = tumble.world{}\nw:explode()\n");
    assert_int_equal(tumble("run broken.lua --out broken.csv"), 1);
    assert_non_null(strstr(err_text, "broken.lua:3:"));
    assert_int_equal(strchr(err_text, '\n') - err_text + 1, (long)strlen(err_text)); /* one line */
    write_file("syntax.lua", "local x = 1\nlocal y = = 2\n");
    assert_int_equal(tumble("run syntax.lua --out broken.csv"), 1);
    assert_non_null(strstr(err_text, "syntax.lua:2:"));
    write_file("nothing.lua", "return 42\n");
    assert_int_equal(tumble("run nothing.lua --out broken.csv"), 1);
    assert_non_null(strstr(err_text, "must return a table"));
    write_file("closed.lua", "local tumble = require 'tumble'\nlocal w <close> = tumble.world{}\n"
                             "return { world = w, duration = 1 }\n");
    assert_int_equal(tumble("run closed.lua --out broken.csv"), 1);
    assert_non_null(strstr(err_text, "<close>"));
    work_path(csv, sizeof csv, "broken.csv");
    assert_false(exists(csv));
}

/* A force that fails half way: exit 1, the message names the file, line
   and time, and neither the CSV nor its partial file exists. */
static void failure_mid_run_leaves_no_file(void **state)
{
    char csv[1024];
    (void)state;
    write_file("fails.lua", "local tumble = require 'tumble'\n"
                            "local w = tumble.world{ dt = 0.01 }\n"
                            "w:particle{}\n"
                            "w:force(function(t, s, f)\n"
                            "  if t > 0.5 then error('the engine fell off') end\n"
                            "end)\n"
                            "return { world = w, duration = 1 }\n");
    assert_int_equal(tumble("run fails.lua --out fails.csv"), 1);
    assert_non_null(strstr(err_text, "fails.lua:5: the engine fell off"));
    assert_non_null(strstr(err_text, "t = 0.5"));
    work_path(csv, sizeof csv, "fails.csv");
    assert_false(exists(csv));
    strcat(csv, ".part");
    assert_false(exists(csv));
}

static void bad_arguments_are_refused(void **state)
{
    char scene[1024], args[2048];
    (void)state;
    snprintf(scene, sizeof scene, "'%s/projectile.lua'", SCENES_DIR);
    snprintf(args, sizeof args, "run %s --dt -1", scene);
    assert_int_equal(tumble(args), 2);
    assert_non_null(strstr(err_text, "-1"));
    snprintf(args, sizeof args, "run %s --dt fast", scene);
    assert_int_equal(tumble(args), 2);
    snprintf(args, sizeof args, "run %s --until", scene);
    assert_int_equal(tumble(args), 2);
    snprintf(args, sizeof args, "run %s --tol 0", scene);
    assert_int_equal(tumble(args), 2);
    snprintf(args, sizeof args, "run %s --frobnicate", scene);
    assert_int_equal(tumble(args), 2);
    assert_non_null(strstr(err_text, "--frobnicate"));
    snprintf(args, sizeof args, "run %s --integrator leapfrog --out bad.csv", scene);
    assert_int_equal(tumble(args), 1);
    assert_non_null(strstr(err_text, "leapfrog"));
    assert_int_equal(tumble("run no-such-scene.lua"), 1);
    assert_non_null(strstr(err_text, "no-such-scene.lua"));
    assert_int_equal(tumble("fly"), 2);
    assert_int_equal(tumble(""), 2);
    snprintf(args, sizeof args, "%s/bad.csv", work_dir());
    assert_false(exists(args));
}

static void overrides_and_help(void **state)
{
    char args[2048], csv[1024];
    double last[15];
    (void)state;
    snprintf(args, sizeof args, "run '%s/projectile.lua' --integrator rk4 --dt 0.01 --until 1 --every 0.5 "
             "--out over.csv", SCENES_DIR);
    assert_int_equal(tumble(args), 0);
    assert_non_null(strstr(out_text, "rk4, dt 0.01 s"));
    assert_non_null(strstr(out_text, "steps       100"));
    work_path(csv, sizeof csv, "over.csv");
    assert_int_equal(parse_csv(csv, "particle", last), 3); /* t = 0, 0.5, 1 */
    snprintf(args, sizeof args, "run '%s/oscillator.lua' --integrator dopri5 --tol 1e-9 --dt 0.1 --out tol.csv",
             SCENES_DIR);
    assert_int_equal(tumble(args), 0);
    assert_non_null(strstr(out_text, "tolerance 1e-09"));
    assert_int_equal(tumble("--help"), 0);
    assert_non_null(strstr(out_text, "--tol"));
    assert_non_null(strstr(out_text, "t,kind,id,x,y,z,vx,vy,vz"));
    assert_non_null(strstr(out_text, "symplectic_euler"));
    assert_non_null(strstr(out_text, "--until"));
    assert_non_null(strstr(out_text, "--guard"));
    assert_int_equal(tumble("run --help"), 0);
    assert_non_null(strstr(out_text, "--max-memory"));
}

/* The README: "On a terminal a run longer than a second shows a progress
   line on stderr", and never into a pipe or a file. A scene whose force
   callback spends 3 ms of processor time an evaluation runs 400 steps of
   symplectic Euler (one evaluation each): 1.2 s. Under `script`, which
   gives it a terminal, the line shows; with stderr in a file it does
   not. */
static void progress_shows_on_a_terminal_only(void **state)
{
    char cmd[2048], path[1100], text[8192];
    int rc;
    (void)state;
    write_file("slow.lua", "local tumble = require 'tumble'\n"
                           "local w = tumble.world{ gravity = {0, 0, -9.81}, integrator = 'symplectic_euler' }\n"
                           "w:particle{ pos = {0, 0, 0} }\n"
                           "w:force(function() local t0 = os.clock() while os.clock() - t0 < 0.003 do end end)\n"
                           "return { world = w, duration = 4, record_every = 1 }\n");
    snprintf(cmd, sizeof cmd, "cd '%s' && script -qec \"'%s' run slow.lua --dt 0.01 --out slow.csv\" /dev/null "
             "> tty.txt 2>&1", work_dir(), TUMBLE_EXE);
    rc = system(cmd);
    assert_true(WIFEXITED(rc) && WEXITSTATUS(rc) == 0);
    work_path(path, sizeof path, "tty.txt");
    slurp(path, text, sizeof text);
    assert_non_null(strstr(text, "tumble: t = "));
    assert_non_null(strstr(text, " steps/s, about "));
    assert_int_equal(tumble("run slow.lua --dt 0.01 --out slow.csv"), 0);
    assert_null(strstr(err_text, "tumble: t = "));
    assert_null(strstr(out_text, "tumble: t = "));
}

/* The number after `label` in the summary. */
static double summary_number(const char *label)
{
    const char *at = strstr(out_text, label);
    if (!at)
        fail_msg("no '%s' in the summary: %s", label, out_text);
    return strtod(at + strlen(label), NULL);
}

/* The guide's printed examples against their closed forms (docs/guide.md,
   sections 1, 4, 10 and 11; the scripts are the guide's):
   - a throw under verlet, exact under constant gravity: 600 steps, 76 rows
     (every 8 steps and the last), energy drift within 1e-14 (rounding);
   - two 0.1 kg particles on a 200 N/m spring with damping 0.1 N s/m at
     --dt 0.05: the stiffest mode is the pair's, w = sqrt(k / mu) = 63.25
     rad/s, damping ratio c / (2 sqrt(k mu)) = 0.0158, and Verlet's damped
     limit 2 / (z + sqrt(1 - 3 z^2)) / w = 0.03114 s, advice 0.9 of it;
   - a ball dropped with its lowest point 1 m up, restitution 0.5, at 60
     Hz: impacts at sqrt(2 g) e^k m/s (4.43, 2.21, 1.11, 0.55 to the two
     decimals printed), reported at the end of the step in which the
     closed-form impact time falls;
   - the same ball at 240 Hz, written to a file by the script, which only
     --trust allows: apexes e^2 = 0.25 m and e^4 = 0.0625 m (to the four
     decimals printed), at the first step past the closed-form apex
     times. */
static void guide_examples_print_their_closed_forms(void **state)
{
    const double g = 9.81, w = sqrt(200 / 0.05), z = 0.1 / (2 * sqrt(200 * 0.05));
    const double limit = 2 / (z + sqrt(1 - 3 * z * z)) / w;
    char want[256], path[1100], text[1024];
    double t_impact = sqrt(2 / g), v = sqrt(2 * g), t_apex;
    int k;
    (void)state;
    write_file("throw.lua", "local tumble = require 'tumble'\n"
                            "local w = tumble.world{ dt = 1/240 }\n"
                            "w:particle{ pos = {0, 0, 1}, vel = {9, 0, 12}, mass = 2 }\n"
                            "return { world = w, duration = 2.5, record_every = 1/30 }\n");
    assert_int_equal(tumble("run throw.lua"), 0);
    assert_non_null(strstr(out_text, "steps       600,"));
    assert_non_null(strstr(out_text, "wrote       throw.csv (76 rows)"));
    assert_below(fabs(summary_number("relative drift ")), 1e-14);

    write_file("springs.lua", "local tumble = require 'tumble'\n"
                              "local w = tumble.world{ dt = 1/1000 }\n"
                              "local a = w:particle{ pos = {0, 0, 1}, mass = 0.1 }\n"
                              "local b = w:particle{ pos = {0.2, 0, 1}, mass = 0.1 }\n"
                              "w:spring(a, {0, 0, 2}, { k = 50 })\n"
                              "w:spring(a, b, { k = 200, damping = 0.1, rest = 0.25 })\n"
                              "return { world = w, duration = 3, record_every = 1/100 }\n");
    assert_int_equal(tumble("run springs.lua --dt 0.05"), 0);
    snprintf(want, sizeof want, "exceeds the limit %.4g s of verlet (stiffest spring mode %.2f rad/s, damping "
             "ratio %.3g): use dt <= %.4g s", limit, w, z, 0.9 * limit);
    print_message("guide's advice: %s\n", want);
    assert_non_null(strstr(err_text, want));

    write_file("events.lua", "local tumble = require 'tumble'\n"
                             "local w = tumble.world{}\n"
                             "local floor = w:shape{ type = 'plane' }\n"
                             "local ball = w:body{ sphere = 0.1, mass = 1, pos = {0, 0, 1.1} }\n"
                             "local skin = w:shape{ type = 'sphere', body = ball, radius = 0.1, restitution = 0.5 }\n"
                             "for i = 1, 90 do\n"
                             "  w:step()\n"
                             "  for _, e in ipairs(w:events()) do\n"
                             "    print(string.format('%.3f s: %s, shapes %d and %d, %.2f m/s', w:time(), e.type, e.a,"
                             " e.b, e.speed))\n"
                             "  end\n"
                             "end\n"
                             "return { world = w, duration = 0 }\n");
    assert_int_equal(tumble("run events.lua --out events.csv"), 0);
    for (k = 0; k < 4; ++k) {
        snprintf(want, sizeof want, "%.3f s: begin, shapes 1 and 2, %.2f m/s", ceil(t_impact * 60) / 60, v);
        print_message("guide's events: %s\n", want);
        assert_non_null(strstr(out_text, want));
        t_impact += 2 * 0.5 * v / g; /* the rebound at e v rises and falls back */
        v *= 0.5;
    }

    write_file("apexes.lua", "local tumble = require 'tumble'\n"
                             "local w = tumble.world{ dt = 1/240 }\n"
                             "w:shape{ type = 'plane' }\n"
                             "local ball = w:body{ sphere = 0.1, mass = 1, pos = {0, 0, 1.1} }\n"
                             "w:shape{ type = 'sphere', body = ball, radius = 0.1, restitution = 0.5 }\n"
                             "local out = assert(io.open('apexes.txt', 'w'))\n"
                             "local rising = false\n"
                             "for i = 1, 4 * 240 do\n"
                             "  w:step()\n"
                             "  local _, _, vz = ball:vel()\n"
                             "  if rising and vz <= 0 then\n"
                             "    local _, _, z = ball:pos()\n"
                             "    out:write(string.format('%.3f s: %.4f m\\n', w:time(), z - 0.1))\n"
                             "  end\n"
                             "  rising = vz > 0\n"
                             "end\n"
                             "out:close()\n"
                             "return { world = w, duration = 0 }\n");
    assert_int_equal(tumble("run apexes.lua --out apexes.csv"), 1); /* the sandbox opens no file to write */
    assert_non_null(strstr(err_text, "for reading only"));
    assert_int_equal(tumble("run apexes.lua --trust --out apexes.csv"), 0);
    work_path(path, sizeof path, "apexes.txt");
    slurp(path, text, sizeof text);
    t_apex = sqrt(2 / g) + 0.5 * sqrt(2 * g) / g;
    snprintf(want, sizeof want, "%.3f s: 0.2500 m\n%.3f s: 0.0625 m\n", ceil(t_apex * 240) / 240,
             ceil((t_apex + 0.5 * sqrt(2 * g) / g + 0.25 * sqrt(2 * g) / g) * 240) / 240);
    print_message("guide's apexes:\n%s", want);
    assert_true(strncmp(text, want, strlen(want)) == 0);
}

/* --check reruns at dt / 2 (the adaptive methods also at tolerance / 100)
   and estimates the run's error from the difference; on the oscillator
   scene (z(t) = -(1 + m g / k) - 0.2 cos(10 t), 5 s) the estimate must be
   within 10% of the error against that closed form, under verlet, rk4,
   dopri5 and auto (measured 1.1%, 1.1%, 0.7% and 0.1%). */
static void check_estimates_the_error(void **state)
{
    const char *runs[] = { "--dt 0.01", "--integrator rk4 --dt 0.02", "--integrator dopri5 --dt 0.1 --tol 1e-5",
                           "--integrator auto --tol 1e-4" };
    const char *labels[] = { "this run's error is about ", "this run's error is about ", "the ends differ by ",
                             "the ends differ by " };
    size_t k;
    (void)state;
    for (k = 0; k < 4; ++k) {
        char args[2048], csv[1024];
        double last[15], estimate, error;
        snprintf(args, sizeof args, "run '%s/oscillator.lua' %s --check --out check.csv", SCENES_DIR, runs[k]);
        assert_int_equal(tumble(args), 0);
        estimate = summary_number(labels[k]);
        work_path(csv, sizeof csv, "check.csv");
        assert_true(parse_csv(csv, "particle", last) > 0);
        assert_true(fabs(last[0] - 5) < 1e-9);
        error = fabs(last[4] - (-(1 + 0.5 * 9.81 / 50) - 0.2 * cos(10 * 5.0)));
        print_message("%s: --check estimates %.4g m, the closed form says %.4g m\n", runs[k], estimate, error);
        assert_true(fabs(estimate / error - 1) < 0.1);
    }
}

/* Pipes and joined values: --opt=value takes the same values as
   --opt value; --out - writes the CSV alone to stdout and the summary to
   stderr (the projectile at --every 0.5 for 1 s: header and 3 rows); a
   flag given a value is refused; an output that cannot be made names the
   system's reason. */
static void pipes_and_joined_values(void **state)
{
    char args[2048], *line;
    int rows = 0;
    (void)state;
    snprintf(args, sizeof args, "run '%s/projectile.lua' --dt=0.01 --until=1 --every=0.5 --out=-", SCENES_DIR);
    assert_int_equal(tumble(args), 0);
    assert_true(!strncmp(out_text, "t,kind,id,x,y,z,vx,vy,vz,qw,qx,qy,qz,wx,wy,wz\n", 46));
    for (line = out_text; (line = strchr(line, '\n')) != NULL; ++line)
        ++rows;
    assert_int_equal(rows, 4);
    assert_non_null(strstr(err_text, "steps       100"));
    assert_non_null(strstr(err_text, "wrote       stdout (3 rows)"));
    snprintf(args, sizeof args, "run '%s/projectile.lua' --quiet=1", SCENES_DIR);
    assert_int_equal(tumble(args), 2);
    assert_non_null(strstr(err_text, "--quiet takes no value"));
    snprintf(args, sizeof args, "run '%s/projectile.lua' --out=", SCENES_DIR);
    assert_int_equal(tumble(args), 2);
    snprintf(args, sizeof args, "run '%s/projectile.lua' --out /nonexistent-folder/x.csv", SCENES_DIR);
    assert_int_equal(tumble(args), 1);
    assert_non_null(strstr(err_text, "No such file or directory"));
}


/* The command guards every run: the rope stepped at twice its split-method
   limit stops with the step, the particle and the advisor's cause, and
   writes no file. auto plans its method and substeps and says which. */
static void blow_up_is_stopped_and_auto_plans(void **state)
{
    char args[2048], csv[1024];
    (void)state;
    snprintf(args, sizeof args, "run '%s/rope.lua' --dt 0.0045 --out blown.csv", SCENES_DIR);
    assert_int_equal(tumble(args), 1);
    assert_non_null(strstr(err_text, "step "));
    assert_non_null(strstr(err_text, "particle "));
    assert_non_null(strstr(err_text, "exceeds the limit"));
    assert_non_null(strstr(err_text, "spring "));
    work_path(csv, sizeof csv, "blown.csv");
    assert_false(exists(csv));
    snprintf(args, sizeof args, "run '%s/rope.lua' --dt 0.0045 --guard 1.01 --out blown.csv", SCENES_DIR);
    assert_int_equal(tumble(args), 1);
    assert_non_null(strstr(err_text, "energy grew"));
    snprintf(args, sizeof args, "run '%s/rope.lua' --integrator auto --tol 1e-6 --until 0.5 --out auto.csv",
             SCENES_DIR);
    assert_int_equal(tumble(args), 0);
    assert_non_null(strstr(out_text, "integrator  auto: "));
    assert_non_null(strstr(out_text, "tolerance 1e-06"));
    assert_non_null(strstr(out_text, "auto picks"));
}


/* Scenes with contacts: the slide stops at v^2 / (2 mu g) = 2.548 m (its
   last row; to mu g h^2 / 2 = 0.68 mm at 60 Hz, see test_contacts_friction),
   the balls of the bounce scene never sink below the plane by more than
   the slop, the heavy crate ends on its column of three within a fifth of
   the slop (its centre at 3.5 m; by the sweeps alone it goes through
   them), and the other three run. */
/* The joints' scene: the hinge pendulum (the last body) keeps its rod's
   length, 1 m from its pivot at (4, 0, 0), to the CSV's 17 digits and
   rounding */
static void joint_scene(void **state)
{
    double last[15];
    (void)state;
    run_scene("pendulum", "body", 9, 101, last);
    assert_below(fabs(sqrt((last[2] - 4) * (last[2] - 4) + last[3] * last[3] + last[4] * last[4]) - 1), 1e-12);
}

/* The other joints' scenes, each by its last body: the chain's 10 kg end
   within its 3 m of the pivot; the double pendulum's lower sphere within
   its 2 m, and its energy within 1e-6 J of the start (dopri5 at 1e-10:
   1.3e-10 J); the car's last wheel past the planks (2.07 m/s for 8 s);
   the bridge's last crate on the deck, not through it (the ground is at
   0.15 m); the slider door within its stop (its centre at most 8 m); a
   ragdoll's last foot above the ground by at most the slop into it. */
static void joint_scenes(void **state)
{
    double last[15], energy = 1;
    const char *arrow;
    char args[1024];
    (void)state;
    run_scene("chain", "body", 30, 181, last);
    assert_true(sqrt(last[2] * last[2] + last[3] * last[3] + (last[4] - 3) * (last[4] - 3)) < 3 + 1e-12);
    run_scene("double_pendulum", "body", 2, 301, last);
    assert_true(sqrt(last[2] * last[2] + last[3] * last[3] + last[4] * last[4]) < 2 + 1e-12);
    assert_non_null(arrow = strstr(out_text, "0 J -> "));
    energy = strtod(arrow + 7, NULL);
    assert_below(fabs(energy), 1e-6);
    run_scene("car", "body", 13, 161, last);
    assert_true(last[2] > 14);
    run_scene("bridge", "body", 28, 121, last);
    assert_true(last[4] > 1);
    run_scene("door", "body", 4, 161, last);
    assert_true(last[2] < 8 + 1e-9 && last[2] > 6);
    snprintf(args, sizeof args, "run '%s/ragdoll.lua' --until 1 --out ragdoll.csv", SCENES_DIR);
    assert_int_equal(tumble(args), 0);
    work_path(args, sizeof args, "ragdoll");
    strcat(args, ".csv");
    assert_int_equal(parse_csv(args, "body", last), 39 * 21);
    assert_true(last[4] > 0.04 - 0.005 - 1e-3);
}

static void contact_scenes(void **state)
{
    double last[15];
    (void)state;
    run_scene("slide", "body", 1, 61, last);
    assert_true(fabs(last[2] - 25 / (2 * 0.5 * 9.81)) < 0.5 * 9.81 / 3600 / 2); /* x */
    run_scene("bounce", "body", 5, 241, last);
    assert_true(last[4] > 0.1 - 0.005); /* z of the last ball */
    run_scene("heavy", "body", 4, 91, last);
    assert_true(fabs(last[4] - 3.5) < 0.2 * 0.005); /* z of the crate */
    run_scene("pyramid", "body", 55, 51, last);
    run_scene("pile", "body", 100, 51, last);
    run_scene("spray", "particle", 200, 61, last);
    assert_true(last[4] > -0.005); /* z: on or above the plane */
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(contact_scenes),
    cmocka_unit_test(joint_scene),
    cmocka_unit_test(joint_scenes),
    cmocka_unit_test(pipes_and_joined_values),
    cmocka_unit_test(shapes_are_written_beside_the_trajectory),
    cmocka_unit_test(plot_is_drawn_with_gnuplot),
    cmocka_unit_test(blow_up_is_stopped_and_auto_plans),
    cmocka_unit_test(projectile_scene),
    cmocka_unit_test(vortex_scene),
    cmocka_unit_test(oscillator_scene),
    cmocka_unit_test(rope_scene),
    cmocka_unit_test(cloth_scene),
    cmocka_unit_test(flip_scene),
    cmocka_unit_test(top_scene),
    cmocka_unit_test(tumbling_box_scene),
    cmocka_unit_test(push_scene),
    cmocka_unit_test(reference_scenes_run),
    cmocka_unit_test(broken_script_names_its_line),
    cmocka_unit_test(failure_mid_run_leaves_no_file),
    cmocka_unit_test(bad_arguments_are_refused),
    cmocka_unit_test(overrides_and_help),
    cmocka_unit_test(progress_shows_on_a_terminal_only),
    cmocka_unit_test(guide_examples_print_their_closed_forms),
    cmocka_unit_test(check_estimates_the_error),
};
TB_TEST_MAIN(tests)
