/* test_gltf.c: `tumble run --gltf` read back. The .glb's container (header,
   a JSON chunk, a BIN chunk, their lengths and padding) is what glTF 2.0
   says, and its animation holds the trajectory: at every recorded frame,
   every body's and particle's node translation (and a body's rotation) is
   the CSV's value rounded to float. Bad paths fail with a message and
   leave no file. The validator and the render are in check.sh. */
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

static char err_text[4096];

static const char *work_dir(void)
{
    static char dir[512];
    if (!dir[0]) {
        char cmd[1100];
        snprintf(dir, sizeof dir, "%s/%ld", WORK_DIR, (long)getpid());
        snprintf(cmd, sizeof cmd, "rm -rf '%s' && mkdir -p '%s'", dir, dir);
        if (system(cmd) != 0)
            fail_msg("cannot make %s", dir);
    }
    return dir;
}

/* The whole file, NUL-terminated; *size its length. */
static char *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    char *buf;
    long n;
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    fseek(f, 0, SEEK_SET);
    buf = malloc((size_t)n + 1);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)n, f), (size_t)n);
    buf[n] = 0;
    fclose(f);
    *size = (size_t)n;
    return buf;
}

/* Run `tumble ARGS` in the work folder; returns its exit status. */
static int tumble(const char *args)
{
    char cmd[2048];
    size_t n;
    char *err;
    int rc;
    snprintf(cmd, sizeof cmd, "cd '%s' && '%s' %s > out.txt 2> err.txt", work_dir(), TUMBLE_EXE, args);
    rc = system(cmd);
    snprintf(cmd, sizeof cmd, "%s/err.txt", work_dir());
    err = slurp(cmd, &n);
    snprintf(err_text, sizeof err_text, "%s", err);
    free(err);
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

/* Files in the work folder whose name holds `part`. */
static int count_files(const char *part)
{
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "ls -a '%s' | grep -c -F -e '%s' > /dev/null", work_dir(), part);
    return system(cmd) == 0;
}

/* ---- a little JSON reader: enough to walk what the writer wrote -------- */

static const char *skip_space(const char *p)
{
    while (*p == ' ' || *p == '\n' || *p == '\r' || *p == '\t')
        ++p;
    return p;
}

/* Past the value at p (a string, number, literal, object or array). */
static const char *skip_value(const char *p)
{
    int depth = 0;
    p = skip_space(p);
    do {
        if (*p == '"') {
            for (++p; *p && *p != '"'; ++p)
                if (*p == '\\' && p[1])
                    ++p;
            if (!*p)
                fail_msg("JSON: unterminated string");
            ++p;
        } else if (*p == '{' || *p == '[') {
            ++depth, ++p;
        } else if (*p == '}' || *p == ']') {
            --depth, ++p;
        } else if (depth == 0) {
            while (*p && !strchr(",}] \n", *p))
                ++p;
        } else if (*p) {
            ++p;
        } else {
            fail_msg("JSON: unexpected end");
        }
    } while (depth > 0);
    return skip_space(p);
}

/* The value of key in the object at p, or NULL. */
static const char *member(const char *p, const char *key)
{
    const size_t n = strlen(key);
    p = skip_space(p);
    if (*p != '{')
        return NULL;
    p = skip_space(p + 1);
    while (*p == '"') {
        const int match = !strncmp(p + 1, key, n) && p[n + 1] == '"';
        p = skip_space(skip_value(p));
        if (*p++ != ':')
            fail_msg("JSON: no ':' after a key");
        if (match)
            return skip_space(p);
        p = skip_value(p);
        if (*p == ',')
            p = skip_space(p + 1);
    }
    return NULL;
}

/* The i-th element of the array at p, or NULL. */
static const char *element(const char *p, size_t i)
{
    p = skip_space(p);
    if (*p != '[')
        return NULL;
    p = skip_space(p + 1);
    while (*p && *p != ']') {
        if (i-- == 0)
            return p;
        p = skip_value(p);
        if (*p == ',')
            p = skip_space(p + 1);
    }
    return NULL;
}

static double number_at(const char *p, const char *what)
{
    char *end;
    double v;
    if (!p)
        fail_msg("JSON: no %s", what);
    v = strtod(p, &end);
    if (end == p)
        fail_msg("JSON: %s is not a number", what);
    return v;
}

static size_t count_of(const char *array)
{
    size_t n = 0;
    while (element(array, n))
        ++n;
    return n;
}

static uint32_t u32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

/* The glTF file split into its JSON (NUL-terminated) and BIN chunks. */
typedef struct glb {
    char *file, *json;
    const unsigned char *bin;
    size_t bin_size;
} glb;

/* Read and check the container: magic "glTF", version 2, the length the
   file has, a JSON chunk padded to 4 bytes with spaces, then a BIN chunk
   of the buffer's byteLength (padded to 4) ending the file. */
static glb read_glb(const char *path)
{
    glb g;
    size_t size, json_size;
    const unsigned char *b;
    g.file = slurp(path, &size);
    b = (const unsigned char *)g.file;
    assert_true(size >= 28);
    assert_memory_equal(b, "glTF", 4);
    assert_int_equal(u32(b + 4), 2);
    assert_int_equal(u32(b + 8), size);
    json_size = u32(b + 12);
    assert_int_equal(json_size % 4, 0);
    assert_memory_equal(b + 16, "JSON", 4);
    assert_true(20 + json_size + 8 <= size);
    g.json = malloc(json_size + 1);
    assert_non_null(g.json);
    memcpy(g.json, b + 20, json_size);
    g.json[json_size] = 0;
    g.bin_size = u32(b + 20 + json_size);
    assert_memory_equal(b + 24 + json_size, "BIN\0", 4);
    assert_int_equal(g.bin_size % 4, 0);
    assert_int_equal(28 + json_size + g.bin_size, size);
    g.bin = b + 28 + json_size;
    assert_true(g.bin_size >= (size_t)number_at(member(element(member(g.json, "buffers"), 0), "byteLength"),
                                                "buffers[0].byteLength"));
    return g;
}

/* Floats count * n of the accessor (n per element), checked to lie in the BIN chunk. */
static const float *accessor_floats(const glb *g, size_t accessor, size_t count, size_t n)
{
    const char *a = element(member(g->json, "accessors"), accessor), *view;
    size_t offset;
    assert_non_null(a);
    assert_int_equal((long)number_at(member(a, "componentType"), "componentType"), 5126);
    assert_int_equal((size_t)number_at(member(a, "count"), "count"), count);
    view = element(member(g->json, "bufferViews"), (size_t)number_at(member(a, "bufferView"), "bufferView"));
    assert_non_null(view);
    offset = (size_t)number_at(member(view, "byteOffset"), "byteOffset") +
             (member(a, "byteOffset") ? (size_t)number_at(member(a, "byteOffset"), "byteOffset") : 0);
    assert_int_equal(offset % 4, 0);
    assert_true(offset + 4 * n * count <= g->bin_size);
    return (const float *)(const void *)(g->bin + offset);
}

/* The output floats of the animation channel moving `node` along `path`. */
static const float *channel(const glb *g, size_t node, const char *path, size_t frames, size_t n, size_t *input)
{
    const char *anim = element(member(g->json, "animations"), 0), *c;
    size_t i;
    char quoted[32];
    snprintf(quoted, sizeof quoted, "\"%s\"", path);
    for (i = 0; (c = element(member(anim, "channels"), i)) != NULL; ++i) {
        const char *target = member(c, "target");
        if ((size_t)number_at(member(target, "node"), "node") == node &&
            !strncmp(member(target, "path"), quoted, strlen(quoted))) {
            const char *s = element(member(anim, "samplers"), (size_t)number_at(member(c, "sampler"), "sampler"));
            assert_int_equal(strncmp(member(s, "interpolation"), "\"LINEAR\"", 8), 0);
            *input = (size_t)number_at(member(s, "input"), "input");
            return accessor_floats(g, (size_t)number_at(member(s, "output"), "output"), frames, n);
        }
    }
    fail_msg("no %s channel for node %zu", path, node);
    return NULL;
}

/* The tests' scene, tests/gltf/scene.lua: at every frame of its 21, the
   three bodies' and two particles' translations, and the bodies'
   rotations up to sign, equal the CSV's numbers rounded to float: within
   half a float ulp, 2^-24 relative (floats carry 24 bits). The key times
   are the CSV's t to the same precision. */
static void node_translations_match_the_csv(void **state)
{
    char path[1200], *csv, *line, *save = NULL;
    size_t size, nodes, node, frames, checked = 0, input = 0, k;
    const float *times;
    double worst = 0; /* the largest relative difference of a translation */
    glb g;
    (void)state;
    assert_int_equal(tumble("run '" SCENE "' --out run.csv --gltf run.glb --quiet"), 0);
    snprintf(path, sizeof path, "%s/run.glb", work_dir());
    g = read_glb(path);
    /* the root turns z up into glTF's y up */
    assert_non_null(strstr(g.json, "\"name\":\"tumble (z up)\",\"rotation\":[-0.707106781,0,0,0.707106781]"));
    nodes = count_of(member(g.json, "nodes"));
    assert_int_equal(nodes, 1 + 3 + 2 + 2 + 5); /* root, bodies, particles, springs, shapes */
    frames = (size_t)number_at(member(element(member(g.json, "accessors"),
                                              (size_t)number_at(member(element(member(element(member(g.json,
                                                  "animations"), 0), "samplers"), 0), "input"), "input")), "count"),
                               "the key times' count");
    assert_int_equal(frames, 21); /* 1 s recorded every 1/20 s, and t = 0 */
    snprintf(path, sizeof path, "%s/run.csv", work_dir());
    csv = slurp(path, &size);
    for (node = 1; node < nodes; ++node) {
        const char *name = member(element(member(g.json, "nodes"), node), "name");
        const int body = !strncmp(name, "\"body ", 6), particle = !strncmp(name, "\"particle ", 10);
        const float *t, *q = NULL;
        unsigned id;
        char kind[16], *copy;
        size_t frame = 0;
        if (!body && !particle)
            continue;
        id = (unsigned)atoi(name + (body ? 6 : 10));
        t = channel(&g, node, "translation", frames, 3, &input);
        times = accessor_floats(&g, input, frames, 1);
        if (body)
            q = channel(&g, node, "rotation", frames, 4, &input);
        /* the CSV's rows of this object, in time order, one per frame */
        copy = malloc(size + 1);
        assert_non_null(copy);
        memcpy(copy, csv, size + 1);
        for (line = strtok_r(copy, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
            double v[14];
            unsigned row_id;
            if (sscanf(line, "%lf,%15[a-z],%u,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &v[0], kind, &row_id, &v[1],
                       &v[2], &v[3], &v[4], &v[5], &v[6], &v[7], &v[8], &v[9], &v[10]) < 6 ||
                row_id != id || strcmp(kind, body ? "body" : "particle"))
                continue;
            assert_true(frame < frames);
            assert_rel(times[frame], v[0], 0x1p-24);
            for (k = 0; k < 3; ++k) {
                assert_rel(t[3 * frame + k], v[1 + k], 0x1p-24);
                if (v[1 + k] != 0 && fabs(t[3 * frame + k] - v[1 + k]) / fabs(v[1 + k]) > worst)
                    worst = fabs(t[3 * frame + k] - v[1 + k]) / fabs(v[1 + k]);
            }
            if (body) { /* glTF's (x, y, z, w) against the CSV's (w, x, y, z), up to sign */
                const double s = q[4 * frame + 3] * v[7] < 0 ? -1 : 1;
                for (k = 0; k < 4; ++k)
                    assert_below(fabs(s * q[4 * frame + k] - v[7 + (k + 1) % 4]), 0x1p-24 * fabs(v[7 + (k + 1) % 4]) + 1e-300);
            }
            ++frame, ++checked;
        }
        assert_int_equal(frame, frames);
        free(copy);
    }
    assert_int_equal(checked, 5 * frames);
    print_message("%zu frames of 3 bodies and 2 particles: translations within %.3g relative of the CSV (bound "
                  "2^-24 = %.3g)\n", frames, worst, 0x1p-24);
    free(csv);
    free(g.json);
    free(g.file);
}

/* The CSV's positions of particle `id`, frame after frame, into x[3 * frames]. */
static size_t csv_particle(const char *csv, unsigned id, double *x, size_t frames)
{
    const char *line = csv;
    size_t n = 0;
    while (line && *line) {
        double t, p[3];
        unsigned row_id;
        char kind[16];
        if (sscanf(line, "%lf,%15[a-z],%u,%lf,%lf,%lf", &t, kind, &row_id, &p[0], &p[1], &p[2]) == 6 &&
            !strcmp(kind, "particle") && row_id == id && n < frames) {
            memcpy(x + 3 * n, p, sizeof p);
            ++n;
        }
        line = strchr(line, '\n');
        line = line ? line + 1 : NULL;
    }
    return n;
}

/* A spring's node carries a line from (0, 0, 0) to (0, 0, 1): at every
   frame its translation T, rotation R and scale (1, 1, L) put the line's
   ends at T and T + L R z, which must be the spring's ends. The scene's
   spring 1 runs from particle 1 to the anchor (2.5, 0.5, 2), spring 2 from
   particle 1 to particle 2. Bound: the ends are floats, and R z is a
   float quaternion's turn of z (unit to about 2^-23), times L < 1 m: 1e-6
   m covers both with room and is far below any real error (a spring drawn
   from the wrong end is off by its length, 0.3 m and more). */
static void springs_end_where_their_particles_are(void **state)
{
    char path[1200], *csv;
    size_t size, frames = 21, input = 0, f, s, node;
    double p1[3 * 21], p2[3 * 21], worst = 0;
    const double anchor[3] = { 2.5, 0.5, 2.0 };
    glb g;
    (void)state;
    assert_int_equal(tumble("run '" SCENE "' --out springs.csv --gltf springs.glb --quiet"), 0);
    snprintf(path, sizeof path, "%s/springs.glb", work_dir());
    g = read_glb(path);
    snprintf(path, sizeof path, "%s/springs.csv", work_dir());
    csv = slurp(path, &size);
    assert_int_equal(csv_particle(csv, 1, p1, frames), frames);
    assert_int_equal(csv_particle(csv, 2, p2, frames), frames);
    for (s = 1; s <= 2; ++s) {
        const float *t, *r, *sc;
        char name[32];
        snprintf(name, sizeof name, "\"spring %zu\"", s);
        for (node = 0; element(member(g.json, "nodes"), node); ++node)
            if (!strncmp(member(element(member(g.json, "nodes"), node), "name"), name, strlen(name)))
                break;
        assert_non_null(element(member(g.json, "nodes"), node));
        t = channel(&g, node, "translation", frames, 3, &input);
        r = channel(&g, node, "rotation", frames, 4, &input);
        sc = channel(&g, node, "scale", frames, 3, &input);
        for (f = 0; f < frames; ++f) {
            const float *q = r + 4 * f; /* (x, y, z, w): R z is R's third column */
            const double z[3] = { 2 * (q[0] * q[2] + q[3] * q[1]), 2 * (q[1] * q[2] - q[3] * q[0]),
                                  1 - 2 * (q[0] * q[0] + q[1] * q[1]) };
            const double *end = s == 1 ? anchor : p2 + 3 * f;
            int k;
            assert_true(sc[3 * f] == 1 && sc[3 * f + 1] == 1);
            for (k = 0; k < 3; ++k) {
                assert_below(fabs(t[3 * f + k] - p1[3 * f + k]), 1e-6);
                assert_below(fabs(t[3 * f + k] + sc[3 * f + 2] * z[k] - end[k]), 1e-6);
                if (fabs(t[3 * f + k] + sc[3 * f + 2] * z[k] - end[k]) > worst)
                    worst = fabs(t[3 * f + k] + sc[3 * f + 2] * z[k] - end[k]);
            }
        }
    }
    print_message("2 springs over %zu frames: the far end within %.3g m of its particle or anchor (bound 1e-6 m)\n",
                  frames, worst);
    free(csv);
    free(g.json);
    free(g.file);
}

/* A folder that does not exist is refused before the run, a folder as the
   file after it; neither leaves a file or a .part behind, and a missing
   value is a usage error. */
static void bad_paths_fail_cleanly(void **state)
{
    (void)state;
    assert_int_equal(tumble("run '" SCENE "' --out bad.csv --gltf /nonexistent/bad.glb"), 1);
    assert_non_null(strstr(err_text, "tumble: --gltf /nonexistent/bad.glb: cannot write in '/nonexistent': No such file"));
    assert_false(count_files("bad."));
    assert_int_equal(tumble("run '" SCENE "' --out bad.csv --gltf ."), 1);
    assert_non_null(strstr(err_text, "tumble: cannot write '.': "));
    assert_false(count_files(".part"));
    assert_int_equal(tumble("run '" SCENE "' --gltf"), 2);
    assert_non_null(strstr(err_text, "--gltf needs a file name"));
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(node_translations_match_the_csv),
    cmocka_unit_test(springs_end_where_their_particles_are),
    cmocka_unit_test(bad_paths_fail_cleanly),
};

TB_TEST_MAIN(tests)
