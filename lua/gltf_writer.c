/* gltf_writer.c: a run as binary glTF 2.0 (.glb) for `tumble run --gltf`.

   The file holds one scene with one root node, "tumble (z up)", that
   turns tumble's z-up world into glTF's y-up one (a quarter turn about
   x); under it, in metres and in world coordinates:
   - a node per body ("body ID", the trajectory's id) at its centre of
     mass and principal axes, with a child node per shape on it at the
     shape's pose in that frame (tb_shape_def.position, orientation);
   - a node per static shape at its world pose; a plane is a square,
     both sides drawn, centred on the point of the plane nearest the
     origin, its half side the larger of 10 m and twice the farthest any
     recorded object comes from that point;
   - a node per particle and per tracer: a small sphere (the contact
     radius of particles when they collide, else 2 cm);
   - a node per spring: a line from (0, 0, 0) to (0, 0, 1) that the node
     turns along the spring and stretches to its length.
   One animation, "run", moves them at the recorded frames, with key
   times the world's time in seconds (so the run plays in real time):
   bodies by translation and rotation, particles and tracers by
   translation, springs by translation, rotation and scale, all LINEAR.
   Between frames a viewer interpolates (slerp for rotations; each
   quaternion's sign is chosen nearest the previous one so that it turns
   the short way); at the frames the poses are the trajectory's, as
   floats (test_gltf.node_translations_match_the_csv, and
   springs_end_where_their_particles_are for the lines).

   Meshes are made here: spheres and capsules as latitude-longitude
   meshes, boxes with flat faces; shapes of the same type and sizes share
   a mesh. Binary data is little-endian, as glTF requires; so is every
   machine tumble builds on (the writer checks). */
#define _POSIX_C_SOURCE 200809L /* open_memstream */
#include "gltf_writer.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Per frame: a body's translation and rotation (x, y, z, w), a particle's
   and a tracer's translation, a spring's translation, rotation and scale. */
enum { BODY_FLOATS = 7, POINT_FLOATS = 3, SPRING_FLOATS = 10 };
/* Latitude-longitude meshes: 24 meridians, 6 bands per hemisphere (15
   degrees each): round enough to read as a ball, 338 vertices at most. */
enum { MERIDIANS = 24, BANDS = 6 };
enum { MAT_STATIC, MAT_BODY, MAT_PARTICLE, MAT_TRACER, MAT_SPRING, MATERIALS };
/* glTF holds floats: positions past this are refused, not turned to Inf. */
#define FLOAT_LIMIT 1e30
/* A .glb's length is a uint32. */
#define GLB_LIMIT 4000000000.0
#define POINT_RADIUS 0.02 /* m: particles that do not collide, tracers */

typedef struct mesh {
    tb_shape_def shape;     /* type and sizes: the key shared meshes match */
    int material, lines;
    size_t vertices, indices;
    size_t position, normal, index; /* byte offsets in geometry */
    float min[3], max[3];
} mesh;

struct gltf_writer {
    size_t bodies, particles, tracers, springs, frame_floats;
    uint32_t *body_index1;  /* [bodies] the trajectory's ids */
    long *spring_a, *spring_b; /* [springs] particle slots; b -1: the anchor */
    double *spring_anchor;  /* [3 * springs] */
    float *times, *data;    /* [frames], [frames * frame_floats] */
    size_t frames, cap;
    unsigned char *geometry; /* the meshes' vertices and indices */
    size_t geometry_size, geometry_cap;
    mesh *meshes;
    size_t mesh_count, mesh_cap;
    char message[256];
};

static int fail(gltf_writer *g, const char *why)
{
    snprintf(g->message, sizeof g->message, "%s", why);
    return -1;
}

gltf_writer *gltf_begin(const tb_world *w)
{
    gltf_writer *g = calloc(1, sizeof *g);
    size_t i, j, n;
    uint32_t *particle_index1 = NULL;
    if (!g)
        return NULL;
    g->bodies = tb_world_body_count(w);
    g->particles = tb_world_particle_count(w);
    g->tracers = tb_world_tracer_count(w);
    g->springs = tb_world_spring_count(w);
    g->frame_floats = BODY_FLOATS * g->bodies + POINT_FLOATS * (g->particles + g->tracers) +
                      SPRING_FLOATS * g->springs;
    n = g->bodies + 1;
    g->body_index1 = malloc(n * sizeof *g->body_index1);
    g->spring_a = malloc((g->springs + 1) * sizeof *g->spring_a);
    g->spring_b = malloc((g->springs + 1) * sizeof *g->spring_b);
    g->spring_anchor = malloc((3 * g->springs + 1) * sizeof *g->spring_anchor);
    particle_index1 = malloc((g->particles + 1) * sizeof *particle_index1);
    if (!g->body_index1 || !g->spring_a || !g->spring_b || !g->spring_anchor || !particle_index1) {
        free(particle_index1);
        gltf_free(g);
        return NULL;
    }
    for (i = 0; i < g->bodies; ++i)
        g->body_index1[i] = tb_world_body_at(w, i).index1;
    for (i = 0; i < g->particles; ++i)
        particle_index1[i] = tb_world_particle_at(w, i).index1;
    /* each spring's ends as particle slots (a spring has at most two) */
    for (i = 0; i < g->springs; ++i) {
        tb_spring_def d;
        g->spring_a[i] = g->spring_b[i] = -1;
        memset(g->spring_anchor + 3 * i, 0, 3 * sizeof(double));
        if (tb_spring_definition(w, tb_world_spring_at(w, i), &d) != TB_OK)
            continue;
        for (j = 0; j < g->particles; ++j) {
            if (particle_index1[j] == d.a.index1)
                g->spring_a[i] = (long)j;
            if (d.b.index1 && particle_index1[j] == d.b.index1)
                g->spring_b[i] = (long)j;
        }
        if (!d.b.index1)
            memcpy(g->spring_anchor + 3 * i, d.anchor, sizeof d.anchor);
    }
    free(particle_index1);
    return g;
}

void gltf_free(gltf_writer *g)
{
    if (!g)
        return;
    free(g->body_index1);
    free(g->spring_a);
    free(g->spring_b);
    free(g->spring_anchor);
    free(g->times);
    free(g->data);
    free(g->geometry);
    free(g->meshes);
    free(g);
}

const char *gltf_message(const gltf_writer *g)
{
    return g ? g->message : "out of memory for the glTF writer";
}

size_t gltf_frames(const gltf_writer *g)
{
    return g ? g->frames : 0;
}

/* q (x, y, z, w) as floats, its sign the one nearest prev (NULL: none). */
static void put_rotation(float *out, const double q_wxyz[4], const float *prev)
{
    double s = 1;
    if (prev && prev[0] * q_wxyz[1] + prev[1] * q_wxyz[2] + prev[2] * q_wxyz[3] + prev[3] * q_wxyz[0] < 0)
        s = -1;
    out[0] = (float)(s * q_wxyz[1]);
    out[1] = (float)(s * q_wxyz[2]);
    out[2] = (float)(s * q_wxyz[3]);
    out[3] = (float)(s * q_wxyz[0]);
}

static int in_range(const double *v, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i)
        if (!(fabs(v[i]) <= FLOAT_LIMIT))
            return 0;
    return 1;
}

/* The rotation turning +z onto the unit vector u, (w, x, y, z): half way
   between them, about z x u; a half turn about x when u is -z. */
static void turn_z_onto(const double u[3], double q[4])
{
    double n;
    q[0] = 1 + u[2], q[1] = -u[1], q[2] = u[0], q[3] = 0;
    n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    if (n < 1e-9) {
        q[0] = 0, q[1] = 1, q[2] = 0;
        return;
    }
    q[0] /= n, q[1] /= n, q[2] /= n;
}

int gltf_record(gltf_writer *g, const tb_world *w)
{
    const float t = (float)tb_world_time(w);
    const double *px = tb_world_particle_positions(w), *tx = tb_world_tracer_positions(w);
    float *row, *prev;
    size_t i;
    if (tb_world_body_count(w) != g->bodies || tb_world_particle_count(w) != g->particles ||
        tb_world_tracer_count(w) != g->tracers || tb_world_spring_count(w) != g->springs)
        return fail(g, "the world's objects changed during the run (glTF animates a fixed set)");
    if (g->frames && !(t > g->times[g->frames - 1]))
        return 0; /* the same float time: glTF's keys must increase */
    if (((double)g->frames + 1) * ((double)g->frame_floats + 1) * 4 > GLB_LIMIT)
        return fail(g, "the glTF file would pass 4 GB, the most a .glb holds (record fewer frames with --every)");
    if (g->frames == g->cap) {
        /* at most what the 4 GB check above admits, plus one */
        const double most = GLB_LIMIT / 4 / ((double)g->frame_floats + 1) + 1;
        const size_t cap = (double)(g->cap ? 2 * g->cap : 64) < most ? (g->cap ? 2 * g->cap : 64) : (size_t)most;
        float *times = realloc(g->times, cap * sizeof *times), *data;
        if (!times)
            return fail(g, "out of memory for the glTF frames");
        g->times = times;
        data = realloc(g->data, (cap * g->frame_floats + 1) * sizeof *data);
        if (!data)
            return fail(g, "out of memory for the glTF frames");
        g->data = data;
        g->cap = cap;
    }
    row = g->data + g->frames * g->frame_floats;
    prev = g->frames ? row - g->frame_floats : NULL;
    for (i = 0; i < g->bodies; ++i, row += BODY_FLOATS) {
        const tb_body_id id = tb_world_body_at(w, i);
        double x[3], q[4];
        tb_body_position(w, id, x);
        tb_body_orientation(w, id, q);
        if (!in_range(x, 3))
            return fail(g, "a body is farther than 1e30 m from the origin: glTF holds floats");
        row[0] = (float)x[0], row[1] = (float)x[1], row[2] = (float)x[2];
        put_rotation(row + 3, q, prev ? prev + 3 : NULL);
        if (prev)
            prev += BODY_FLOATS;
    }
    for (i = 0; i < g->particles + g->tracers; ++i, row += POINT_FLOATS) {
        const double *x = i < g->particles ? px + 3 * i : tx + 3 * (i - g->particles);
        if (!in_range(x, 3))
            return fail(g, "a particle or tracer is farther than 1e30 m from the origin: glTF holds floats");
        row[0] = (float)x[0], row[1] = (float)x[1], row[2] = (float)x[2];
    }
    if (prev)
        prev += POINT_FLOATS * (g->particles + g->tracers);
    for (i = 0; i < g->springs; ++i, row += SPRING_FLOATS) {
        const double *a = g->spring_a[i] >= 0 ? px + 3 * g->spring_a[i] : g->spring_anchor + 3 * i;
        const double *b = g->spring_b[i] >= 0 ? px + 3 * g->spring_b[i] : g->spring_anchor + 3 * i;
        double d[3], len, u[3] = { 0, 0, 1 }, q[4];
        d[0] = b[0] - a[0], d[1] = b[1] - a[1], d[2] = b[2] - a[2];
        len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (len > 0)
            u[0] = d[0] / len, u[1] = d[1] / len, u[2] = d[2] / len;
        if (!in_range(a, 3) || !(len <= FLOAT_LIMIT))
            return fail(g, "a spring reaches farther than 1e30 m: glTF holds floats");
        turn_z_onto(u, q);
        row[0] = (float)a[0], row[1] = (float)a[1], row[2] = (float)a[2];
        put_rotation(row + 3, q, prev ? prev + 3 : NULL);
        row[7] = 1, row[8] = 1, row[9] = (float)len;
        if (prev)
            prev += SPRING_FLOATS;
    }
    g->times[g->frames++] = t;
    return 0;
}

/* ------------------------------------------------------------- meshes -- */

static int grow_geometry(gltf_writer *g, size_t more)
{
    if (g->geometry_size + more > g->geometry_cap) {
        size_t cap = g->geometry_cap ? 2 * g->geometry_cap : 65536;
        unsigned char *p;
        while (cap < g->geometry_size + more)
            cap *= 2;
        if (!(p = realloc(g->geometry, cap)))
            return fail(g, "out of memory for the glTF meshes");
        g->geometry = p;
        g->geometry_cap = cap;
    }
    return 0;
}

static void put_floats(gltf_writer *g, const float *v, size_t n)
{
    memcpy(g->geometry + g->geometry_size, v, n * sizeof(float));
    g->geometry_size += n * sizeof(float);
}

/* A mesh's vertices: positions then normals, each count * 3 floats. */
static int add_vertices(gltf_writer *g, mesh *m, const float *pos, const float *nrm, size_t count)
{
    size_t i, k;
    if (grow_geometry(g, 24 * count))
        return -1;
    m->vertices = count;
    m->position = g->geometry_size;
    put_floats(g, pos, 3 * count);
    if (nrm) {
        m->normal = g->geometry_size;
        put_floats(g, nrm, 3 * count);
    }
    for (k = 0; k < 3; ++k)
        m->min[k] = m->max[k] = pos[k];
    for (i = 1; i < count; ++i)
        for (k = 0; k < 3; ++k) {
            if (pos[3 * i + k] < m->min[k])
                m->min[k] = pos[3 * i + k];
            if (pos[3 * i + k] > m->max[k])
                m->max[k] = pos[3 * i + k];
        }
    return 0;
}

static int add_indices(gltf_writer *g, mesh *m, const uint16_t *idx, size_t count)
{
    const size_t bytes = (2 * count + 3) / 4 * 4;
    if (grow_geometry(g, bytes))
        return -1;
    m->index = g->geometry_size;
    m->indices = count;
    memset(g->geometry + g->geometry_size, 0, bytes);
    memcpy(g->geometry + g->geometry_size, idx, 2 * count);
    g->geometry_size += bytes;
    return 0;
}

/* A capsule of radius r whose core runs from z = -h to h (h = 0: a
   sphere): rings of MERIDIANS + 1 vertices (the seam twice) from the top
   pole down, the upper hemisphere raised by h and the lower lowered; a
   capsule has the equator twice, once per hemisphere, and the band
   between is its cylinder. Triangles counter-clockwise seen from
   outside, none at a pole that would have no area. */
static int make_round(gltf_writer *g, mesh *m, double r, double h)
{
    enum { RINGS_MAX = 2 * BANDS + 2, VERTS = RINGS_MAX * (MERIDIANS + 1) };
    float pos[3 * VERTS], nrm[3 * VERTS];
    uint16_t idx[6 * (RINGS_MAX - 1) * MERIDIANS];
    size_t rings = 0, v = 0, n = 0, i, u;
    const double pi = 3.14159265358979323846;
    int band;
    for (band = 0; band <= 2 * BANDS; ++band) {
        const double lat = pi / 2 - pi * band / (2 * BANDS);
        const int copies = band == BANDS && h > 0 ? 2 : 1;
        int c;
        for (c = 0; c < copies; ++c, ++rings) {
            const double lift = band < BANDS || (band == BANDS && c == 0) ? h : -h;
            for (u = 0; u <= MERIDIANS; ++u, ++v) {
                const double lon = 2 * pi * (double)u / MERIDIANS;
                const double nx = cos(lat) * cos(lon), ny = cos(lat) * sin(lon), nz = sin(lat);
                nrm[3 * v] = (float)nx, nrm[3 * v + 1] = (float)ny, nrm[3 * v + 2] = (float)nz;
                pos[3 * v] = (float)(r * nx), pos[3 * v + 1] = (float)(r * ny), pos[3 * v + 2] = (float)(r * nz + lift);
            }
        }
    }
    for (i = 0; i + 1 < rings; ++i)
        for (u = 0; u < MERIDIANS; ++u) {
            const uint16_t a = (uint16_t)(i * (MERIDIANS + 1) + u), b = (uint16_t)(a + 1);
            const uint16_t c = (uint16_t)(a + MERIDIANS + 1), d = (uint16_t)(c + 1);
            if (i + 2 < rings) /* not at the bottom pole */
                idx[n++] = a, idx[n++] = c, idx[n++] = d;
            if (i > 0) /* not at the top pole */
                idx[n++] = a, idx[n++] = d, idx[n++] = b;
        }
    return add_vertices(g, m, pos, nrm, v) || add_indices(g, m, idx, n) ? -1 : 0;
}

/* A box: four vertices per face with the face's normal; face k's corners
   go counter-clockwise about its outward normal (u x v = n). */
static int make_box(gltf_writer *g, mesh *m, const double half[3])
{
    float pos[72], nrm[72];
    uint16_t idx[36];
    int face, c, k;
    for (face = 0; face < 6; ++face) {
        const int axis = face / 2, s = face % 2 ? -1 : 1;
        const int u = s > 0 ? (axis + 1) % 3 : (axis + 2) % 3, v = s > 0 ? (axis + 2) % 3 : (axis + 1) % 3;
        static const int su[4] = { -1, 1, 1, -1 }, sv[4] = { -1, -1, 1, 1 };
        for (c = 0; c < 4; ++c) {
            float *p = pos + 3 * (4 * face + c), *q = nrm + 3 * (4 * face + c);
            for (k = 0; k < 3; ++k)
                q[k] = 0, p[k] = 0;
            p[axis] = (float)(s * half[axis]);
            p[u] = (float)(su[c] * half[u]);
            p[v] = (float)(sv[c] * half[v]);
            q[axis] = (float)s;
        }
        idx[6 * face] = (uint16_t)(4 * face), idx[6 * face + 1] = (uint16_t)(4 * face + 1);
        idx[6 * face + 2] = (uint16_t)(4 * face + 2), idx[6 * face + 3] = (uint16_t)(4 * face);
        idx[6 * face + 4] = (uint16_t)(4 * face + 2), idx[6 * face + 5] = (uint16_t)(4 * face + 3);
    }
    return add_vertices(g, m, pos, nrm, 24) || add_indices(g, m, idx, 36) ? -1 : 0;
}

/* A plane as a square of half side `half`, in world coordinates. */
static int make_plane(gltf_writer *g, mesh *m, const tb_shape_def *d, double half)
{
    const double *n = d->normal;
    double t1[3], t2[3], c[3], len;
    float pos[12], nrm[12];
    static const uint16_t idx[6] = { 0, 1, 2, 0, 2, 3 };
    static const int s1[4] = { -1, 1, 1, -1 }, s2[4] = { -1, -1, 1, 1 };
    int i, k;
    /* t1: n crossed with the axis it is least along; t2 = n x t1 */
    if (fabs(n[0]) <= fabs(n[1]) && fabs(n[0]) <= fabs(n[2]))
        t1[0] = 0, t1[1] = n[2], t1[2] = -n[1];
    else if (fabs(n[1]) <= fabs(n[2]))
        t1[0] = -n[2], t1[1] = 0, t1[2] = n[0];
    else
        t1[0] = n[1], t1[1] = -n[0], t1[2] = 0;
    len = sqrt(t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]);
    for (k = 0; k < 3; ++k)
        t1[k] /= len, c[k] = d->offset * n[k];
    t2[0] = n[1] * t1[2] - n[2] * t1[1];
    t2[1] = n[2] * t1[0] - n[0] * t1[2];
    t2[2] = n[0] * t1[1] - n[1] * t1[0];
    /* corners counter-clockwise about n: t2 x t1 = -n, so walk t2 then t1 */
    for (i = 0; i < 4; ++i)
        for (k = 0; k < 3; ++k) {
            pos[3 * i + k] = (float)(c[k] + half * (s1[i] * t2[k] + s2[i] * t1[k]));
            nrm[3 * i + k] = (float)n[k];
        }
    return add_vertices(g, m, pos, nrm, 4) || add_indices(g, m, idx, 6) ? -1 : 0;
}

/* A new mesh at the end of the list, zeroed but for its key; NULL when
   out of memory. */
static mesh *new_mesh(gltf_writer *g, const tb_shape_def *d, int material)
{
    mesh *m;
    if (g->mesh_count == g->mesh_cap) {
        size_t cap = g->mesh_cap ? 2 * g->mesh_cap : 16;
        mesh *more = realloc(g->meshes, cap * sizeof *more);
        if (!more)
            return fail(g, "out of memory for the glTF meshes"), NULL;
        g->meshes = more;
        g->mesh_cap = cap;
    }
    m = &g->meshes[g->mesh_count];
    memset(m, 0, sizeof *m);
    m->shape = *d;
    m->material = material;
    return m;
}

/* The mesh for shape d (an equal one's, when there is one), or -1. */
static long mesh_for(gltf_writer *g, const tb_shape_def *d, int material, double plane_half)
{
    mesh *m;
    size_t i;
    for (i = 0; i < g->mesh_count; ++i) {
        const tb_shape_def *e = &g->meshes[i].shape;
        if (!g->meshes[i].lines && g->meshes[i].material == material && e->type == d->type &&
            d->type != TB_SHAPE_PLANE && e->radius == d->radius && e->half_length == d->half_length &&
            e->half_extents[0] == d->half_extents[0] && e->half_extents[1] == d->half_extents[1] &&
            e->half_extents[2] == d->half_extents[2])
            return (long)i;
    }
    if (!(m = new_mesh(g, d, material)))
        return -1;
    if ((d->type == TB_SHAPE_SPHERE && make_round(g, m, d->radius, 0)) ||
        (d->type == TB_SHAPE_CAPSULE && make_round(g, m, d->radius, d->half_length)) ||
        (d->type == TB_SHAPE_BOX && make_box(g, m, d->half_extents)) ||
        (d->type == TB_SHAPE_PLANE && make_plane(g, m, d, plane_half)))
        return -1;
    return (long)g->mesh_count++;
}

/* The springs' line: (0, 0, 0) to (0, 0, 1), no normals, no indices. */
static long line_mesh(gltf_writer *g)
{
    static const float pos[6] = { 0, 0, 0, 0, 0, 1 };
    const tb_shape_def none = tb_default_shape_def(); /* its key: no shape's */
    mesh *m = new_mesh(g, &none, MAT_SPRING);
    if (!m)
        return -1;
    m->lines = 1;
    return add_vertices(g, m, pos, NULL, 2) ? -1 : (long)g->mesh_count++;
}

/* -------------------------------------------------------------- writing -- */

/* The half side of a plane's square: 10 m, or twice the farthest a
   recorded object or a static shape comes from its centre. */
static double plane_half(const gltf_writer *g, const tb_world *w, const tb_shape_def *d)
{
    double c[3], far2 = 0;
    size_t f, i, k;
    for (k = 0; k < 3; ++k)
        c[k] = d->offset * d->normal[k];
    for (f = 0; f < g->frames; ++f) {
        const float *row = g->data + f * g->frame_floats;
        for (i = 0; i < g->bodies + g->particles + g->tracers + g->springs; ++i) {
            const float *p = i < g->bodies ? row + BODY_FLOATS * i
                             : i < g->bodies + g->particles + g->tracers
                                 ? row + BODY_FLOATS * g->bodies + POINT_FLOATS * (i - g->bodies)
                                 : row + BODY_FLOATS * g->bodies + POINT_FLOATS * (g->particles + g->tracers) +
                                       SPRING_FLOATS * (i - g->bodies - g->particles - g->tracers);
            double r2 = 0;
            for (k = 0; k < 3; ++k)
                r2 += (p[k] - c[k]) * (p[k] - c[k]);
            if (r2 > far2)
                far2 = r2;
        }
    }
    for (i = 0; i < tb_world_shape_count(w); ++i) {
        tb_shape_def s;
        double r2 = 0;
        if (tb_shape_definition(w, tb_world_shape_at(w, i), &s) != TB_OK || s.type == TB_SHAPE_PLANE ||
            s.body.index1)
            continue;
        for (k = 0; k < 3; ++k)
            r2 += (s.position[k] - c[k]) * (s.position[k] - c[k]);
        if (r2 > far2)
            far2 = r2;
    }
    return 2 * sqrt(far2) > 10 ? 2 * sqrt(far2) : 10;
}

static void put_vec(FILE *j, const char *key, const float *v, int n)
{
    int k;
    fprintf(j, ",\"%s\":[", key);
    for (k = 0; k < n; ++k)
        fprintf(j, "%s%.9g", k ? "," : "", (double)v[k]);
    fputc(']', j);
}

/* A node's pose from frame 0 (a viewer shows it without the animation). */
static void put_pose(FILE *j, const float *t, const float *r, const float *s)
{
    put_vec(j, "translation", t, 3);
    if (r)
        put_vec(j, "rotation", r, 4);
    if (s)
        put_vec(j, "scale", s, 3);
}

/* Accessor and buffer view entries are written as the layout is laid:
   `views` and `accessors` are the JSON arrays' texts so far. */
typedef struct layout {
    FILE *views, *accessors;
    size_t view_count, accessor_count;
} layout;

static size_t add_view(layout *l, size_t offset, size_t length, int target)
{
    fprintf(l->views, "%s{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu", l->view_count ? "," : "", offset,
            length);
    if (target)
        fprintf(l->views, ",\"target\":%d", target);
    fputc('}', l->views);
    return l->view_count++;
}

/* type "SCALAR", "VEC3"...; component 5126 float, 5123 unsigned short */
static size_t add_accessor(layout *l, size_t view, size_t offset, int component, size_t count, const char *type,
                           const float *min, const float *max, int dims)
{
    fprintf(l->accessors, "%s{\"bufferView\":%zu,\"byteOffset\":%zu,\"componentType\":%d,\"count\":%zu,\"type\":\"%s\"",
            l->accessor_count ? "," : "", view, offset, component, count, type);
    if (min) {
        put_vec(l->accessors, "min", min, dims);
        put_vec(l->accessors, "max", max, dims);
    }
    fputc('}', l->accessors);
    return l->accessor_count++;
}

static int little_endian(void)
{
    const uint32_t one = 1;
    unsigned char b;
    memcpy(&b, &one, 1);
    return b == 1;
}

static void put_u32(FILE *f, uint32_t v)
{
    unsigned char b[4];
    b[0] = (unsigned char)v, b[1] = (unsigned char)(v >> 8), b[2] = (unsigned char)(v >> 16),
    b[3] = (unsigned char)(v >> 24);
    fwrite(b, 1, 4, f);
}

/* Write the JSON into j; returns the BIN chunk's length, or 0 on failure. */
static size_t write_json(gltf_writer *g, const tb_world *w, FILE *j, layout *l)
{
    static const float colours[MATERIALS][3] = {
        { 0.55f, 0.57f, 0.6f },  /* static: grey */
        { 0.9f, 0.45f, 0.1f },   /* bodies: orange */
        { 0.15f, 0.4f, 0.95f },  /* particles: blue */
        { 0.1f, 0.75f, 0.3f },   /* tracers: green */
        { 0.95f, 0.9f, 0.2f },   /* springs: yellow */
    };
    static const char *const names[MATERIALS] = { "static", "body", "particle", "tracer", "spring" };
    static const char *const types[] = { "sphere", "capsule", "box", "plane" };
    const size_t shapes = tb_world_shape_count(w), points = g->particles + g->tracers;
    const size_t first_point = 1 + g->bodies, first_spring = first_point + points;
    const size_t first_shape = first_spring + g->springs;
    const tb_contact_settings cs = tb_world_contact_settings(w);
    const float *row0 = g->data;
    long *shape_mesh = malloc((shapes + 1) * sizeof *shape_mesh), *shape_body = malloc((shapes + 1) * sizeof *shape_body);
    long particle_mesh = -1, tracer_mesh = -1, spring_mesh = -1;
    size_t i, k, *mesh_accessor = NULL, offset, times;
    int first;

    if (!shape_mesh || !shape_body) {
        free(shape_mesh), free(shape_body);
        return fail(g, "out of memory for the glTF shapes"), 0;
    }
    /* meshes: the shapes', then a sphere for particles and tracers, a line for springs */
    for (i = 0; i < shapes; ++i) {
        tb_shape_def d;
        shape_mesh[i] = -2, shape_body[i] = -1;
        if (tb_shape_definition(w, tb_world_shape_at(w, i), &d) != TB_OK)
            continue;
        if (!in_range(d.position, 3) || !in_range(&d.offset, 1) || !in_range(&d.radius, 1) ||
            !in_range(&d.half_length, 1) || !in_range(d.half_extents, 3))
            goto too_far;
        for (k = 0; d.body.index1 && k < g->bodies; ++k)
            if (g->body_index1[k] == d.body.index1)
                shape_body[i] = (long)k;
        if ((shape_mesh[i] = mesh_for(g, &d, d.body.index1 ? MAT_BODY : MAT_STATIC,
                                      d.type == TB_SHAPE_PLANE ? plane_half(g, w, &d) : 0)) < 0)
            goto failed;
    }
    if (g->particles) {
        tb_shape_def d = tb_default_shape_def();
        d.radius = cs.particle_radius > 0 && cs.particle_radius <= FLOAT_LIMIT ? cs.particle_radius : POINT_RADIUS;
        if ((particle_mesh = mesh_for(g, &d, MAT_PARTICLE, 0)) < 0)
            goto failed;
    }
    if (g->tracers) {
        tb_shape_def d = tb_default_shape_def();
        d.radius = POINT_RADIUS;
        if ((tracer_mesh = mesh_for(g, &d, MAT_TRACER, 0)) < 0)
            goto failed;
    }
    if (g->springs && (spring_mesh = line_mesh(g)) < 0)
        goto failed;

    /* the geometry's views and accessors: POSITION, NORMAL, indices */
    if (!(mesh_accessor = malloc((3 * g->mesh_count + 1) * sizeof *mesh_accessor)))
        goto failed;
    for (i = 0; i < g->mesh_count; ++i) {
        const mesh *m = &g->meshes[i];
        size_t v = add_view(l, m->position, 12 * m->vertices, 34962);
        mesh_accessor[3 * i] = add_accessor(l, v, 0, 5126, m->vertices, "VEC3", m->min, m->max, 3);
        if (!m->lines) {
            v = add_view(l, m->normal, 12 * m->vertices, 34962);
            mesh_accessor[3 * i + 1] = add_accessor(l, v, 0, 5126, m->vertices, "VEC3", NULL, NULL, 0);
            v = add_view(l, m->index, 2 * m->indices, 34963);
            mesh_accessor[3 * i + 2] = add_accessor(l, v, 0, 5123, m->indices, "SCALAR", NULL, NULL, 0);
        }
    }
    /* the animation's data after the geometry: key times, then each
       object's channels, frame after frame */
    offset = g->geometry_size;
    if (g->frame_floats) {
        const size_t view = add_view(l, offset, 4 * g->frames * (g->frame_floats + 1), 0);
        times = add_accessor(l, view, 0, 5126, g->frames, "SCALAR", g->times, g->times + g->frames - 1, 1);
        offset = 4 * g->frames;
        for (i = 0; i < g->bodies; ++i) {
            add_accessor(l, view, offset, 5126, g->frames, "VEC3", NULL, NULL, 0), offset += 12 * g->frames;
            add_accessor(l, view, offset, 5126, g->frames, "VEC4", NULL, NULL, 0), offset += 16 * g->frames;
        }
        for (i = 0; i < points; ++i)
            add_accessor(l, view, offset, 5126, g->frames, "VEC3", NULL, NULL, 0), offset += 12 * g->frames;
        for (i = 0; i < g->springs; ++i) {
            add_accessor(l, view, offset, 5126, g->frames, "VEC3", NULL, NULL, 0), offset += 12 * g->frames;
            add_accessor(l, view, offset, 5126, g->frames, "VEC4", NULL, NULL, 0), offset += 16 * g->frames;
            add_accessor(l, view, offset, 5126, g->frames, "VEC3", NULL, NULL, 0), offset += 12 * g->frames;
        }
        offset += g->geometry_size;
    } else {
        times = 0;
    }

    fprintf(j, "{\"asset\":{\"version\":\"2.0\",\"generator\":\"tumble %d.%d.%d\"},\"scene\":0,"
               "\"scenes\":[{\"name\":\"run\",\"nodes\":[0]}],\"nodes\":[",
            TB_VERSION_MAJOR, TB_VERSION_MINOR, TB_VERSION_PATCH);
    /* node 0: the root, z up to y up: a quarter turn about x */
    fprintf(j, "{\"name\":\"tumble (z up)\",\"rotation\":[-0.707106781,0,0,0.707106781]");
    first = 1;
    for (i = 1; i < first_shape; ++i)
        fprintf(j, "%s%zu", first ? ",\"children\":[" : ",", i), first = 0;
    for (i = 0; i < shapes; ++i)
        if (shape_mesh[i] >= 0 && shape_body[i] < 0)
            fprintf(j, "%s%zu", first ? ",\"children\":[" : ",", first_shape + i), first = 0;
    fprintf(j, "%s}", first ? "" : "]");
    for (i = 0; i < g->bodies; ++i) {
        fprintf(j, ",{\"name\":\"body %u\"", (unsigned)g->body_index1[i]);
        put_pose(j, row0 + BODY_FLOATS * i, row0 + BODY_FLOATS * i + 3, NULL);
        first = 1;
        for (k = 0; k < shapes; ++k)
            if (shape_mesh[k] >= 0 && shape_body[k] == (long)i)
                fprintf(j, "%s%zu", first ? ",\"children\":[" : ",", first_shape + k), first = 0;
        fprintf(j, "%s}", first ? "" : "]");
    }
    for (i = 0; i < points; ++i) {
        const int particle = i < g->particles;
        fprintf(j, ",{\"name\":\"%s %u\",\"mesh\":%ld", particle ? "particle" : "tracer",
                particle ? (unsigned)tb_world_particle_at(w, i).index1
                         : (unsigned)tb_world_tracer_at(w, i - g->particles).index1,
                particle ? particle_mesh : tracer_mesh);
        put_pose(j, row0 + BODY_FLOATS * g->bodies + POINT_FLOATS * i, NULL, NULL);
        fputc('}', j);
    }
    for (i = 0; i < g->springs; ++i) {
        const float *s = row0 + BODY_FLOATS * g->bodies + POINT_FLOATS * points + SPRING_FLOATS * i;
        fprintf(j, ",{\"name\":\"spring %u\",\"mesh\":%ld", (unsigned)tb_world_spring_at(w, i).index1, spring_mesh);
        put_pose(j, s, s + 3, s + 7);
        fputc('}', j);
    }
    for (i = 0; i < shapes; ++i) {
        tb_shape_def d;
        float t[3], r[4];
        if (shape_mesh[i] < 0 || tb_shape_definition(w, tb_world_shape_at(w, i), &d) != TB_OK) {
            fprintf(j, ",{\"name\":\"shape %u (unread)\"}", (unsigned)tb_world_shape_at(w, i).index1);
            continue;
        }
        fprintf(j, ",{\"name\":\"shape %u (%s)\",\"mesh\":%ld", (unsigned)tb_world_shape_at(w, i).index1,
                types[d.type], shape_mesh[i]);
        if (d.type != TB_SHAPE_PLANE) { /* a plane's square is in world coordinates */
            for (k = 0; k < 3; ++k)
                t[k] = (float)d.position[k];
            put_rotation(r, d.orientation, NULL);
            put_pose(j, t, r, NULL);
        }
        fputc('}', j);
    }
    fprintf(j, "]%s", g->mesh_count ? ",\"meshes\":[" : ""); /* glTF refuses an empty array */
    for (i = 0; i < g->mesh_count; ++i) {
        const mesh *m = &g->meshes[i];
        fprintf(j, "%s{\"name\":\"%s\",\"primitives\":[{\"attributes\":{\"POSITION\":%zu", i ? "," : "",
                m->lines ? "spring line" : types[m->shape.type], mesh_accessor[3 * i]);
        if (m->lines)
            fprintf(j, "},\"mode\":1");
        else
            fprintf(j, ",\"NORMAL\":%zu},\"indices\":%zu,\"mode\":4", mesh_accessor[3 * i + 1],
                    mesh_accessor[3 * i + 2]);
        fprintf(j, ",\"material\":%d}]}", m->material);
    }
    fprintf(j, "%s\"materials\":[", g->mesh_count ? "]," : ",");
    for (i = 0; i < MATERIALS; ++i)
        fprintf(j, "%s{\"name\":\"%s\",\"doubleSided\":%s,\"pbrMetallicRoughness\":{\"baseColorFactor\":[%.3g,%.3g,%.3g,1],"
                   "\"metallicFactor\":0,\"roughnessFactor\":0.8}}",
                i ? "," : "", names[i], i == MAT_STATIC ? "true" : "false", (double)colours[i][0],
                (double)colours[i][1], (double)colours[i][2]);
    fprintf(j, "]");
    if (g->frame_floats) {
        size_t s = 0, a = times + 1;
        fprintf(j, ",\"animations\":[{\"name\":\"run\",\"channels\":[");
        for (i = 0; i < g->bodies; ++i, s += 2)
            fprintf(j, "%s{\"sampler\":%zu,\"target\":{\"node\":%zu,\"path\":\"translation\"}},"
                       "{\"sampler\":%zu,\"target\":{\"node\":%zu,\"path\":\"rotation\"}}",
                    s ? "," : "", s, 1 + i, s + 1, 1 + i);
        for (i = 0; i < points; ++i, ++s)
            fprintf(j, "%s{\"sampler\":%zu,\"target\":{\"node\":%zu,\"path\":\"translation\"}}", s ? "," : "", s,
                    first_point + i);
        for (i = 0; i < g->springs; ++i, s += 3)
            fprintf(j, "%s{\"sampler\":%zu,\"target\":{\"node\":%zu,\"path\":\"translation\"}},"
                       "{\"sampler\":%zu,\"target\":{\"node\":%zu,\"path\":\"rotation\"}},"
                       "{\"sampler\":%zu,\"target\":{\"node\":%zu,\"path\":\"scale\"}}",
                    s ? "," : "", s, first_spring + i, s + 1, first_spring + i, s + 2, first_spring + i);
        fprintf(j, "],\"samplers\":[");
        for (i = 0; i < s; ++i)
            fprintf(j, "%s{\"input\":%zu,\"output\":%zu,\"interpolation\":\"LINEAR\"}", i ? "," : "", times, a + i);
        fprintf(j, "]}]");
    }
    fclose(l->accessors), l->accessors = NULL;
    fclose(l->views), l->views = NULL;
    free(shape_mesh), free(shape_body), free(mesh_accessor);
    return offset ? offset : 4;

too_far:
    fail(g, "a shape is farther than 1e30 m from the origin, or larger: glTF holds floats");
failed:
    free(shape_mesh), free(shape_body), free(mesh_accessor);
    return 0;
}

int gltf_write(gltf_writer *g, const tb_world *w, FILE *f)
{
    char *json = NULL, *views = NULL, *accessors = NULL;
    size_t json_size = 0, views_size = 0, accessors_size = 0, bin, padded_json, f_i, i, k;
    layout l;
    FILE *j;
    int rc = -1;
    if (!little_endian())
        return fail(g, "glTF's binary data is little-endian and this machine is not");
    if (!g->frames)
        return fail(g, "no frame was recorded");
    memset(&l, 0, sizeof l);
    j = open_memstream(&json, &json_size);
    l.views = open_memstream(&views, &views_size);
    l.accessors = open_memstream(&accessors, &accessors_size);
    if (!j || !l.views || !l.accessors) {
        fail(g, "out of memory for the glTF JSON");
        goto done;
    }
    bin = write_json(g, w, j, &l);
    if (!bin)
        goto done;
    if (l.accessor_count) /* glTF refuses empty arrays: an empty world has none */
        fprintf(j, ",\"accessors\":[%s],\"bufferViews\":[%s]", accessors, views);
    fprintf(j, ",\"buffers\":[{\"byteLength\":%zu}]}", bin);
    if (fclose(j) != 0 || !json) {
        j = NULL;
        fail(g, "out of memory for the glTF JSON");
        goto done;
    }
    j = NULL;
    padded_json = (json_size + 3) / 4 * 4;
    if (12.0 + 8 + (double)padded_json + 8 + (double)bin > GLB_LIMIT) {
        fail(g, "the glTF file would pass 4 GB, the most a .glb holds (record fewer frames with --every)");
        goto done;
    }
    /* header, the JSON chunk (padded with spaces), the BIN chunk */
    fwrite("glTF", 1, 4, f);
    put_u32(f, 2);
    put_u32(f, (uint32_t)(12 + 8 + padded_json + 8 + bin));
    put_u32(f, (uint32_t)padded_json);
    fwrite("JSON", 1, 4, f);
    fwrite(json, 1, json_size, f);
    fwrite("   ", 1, padded_json - json_size, f);
    put_u32(f, (uint32_t)bin);
    fwrite("BIN", 1, 4, f); /* with its terminating zero: "BIN\0" */
    if (g->geometry_size) /* NULL without meshes */
        fwrite(g->geometry, 1, g->geometry_size, f);
    if (g->frame_floats) {
        const size_t points = g->particles + g->tracers;
        fwrite(g->times, sizeof(float), g->frames, f);
        /* object after object, each channel frame after frame */
        for (i = 0; i < g->bodies; ++i)
            for (k = 0; k < 2; ++k)
                for (f_i = 0; f_i < g->frames; ++f_i)
                    fwrite(g->data + f_i * g->frame_floats + BODY_FLOATS * i + 3 * k, sizeof(float), 3 + k, f);
        for (i = 0; i < points; ++i)
            for (f_i = 0; f_i < g->frames; ++f_i)
                fwrite(g->data + f_i * g->frame_floats + BODY_FLOATS * g->bodies + POINT_FLOATS * i, sizeof(float), 3,
                       f);
        for (i = 0; i < g->springs; ++i)
            for (k = 0; k < 3; ++k)
                for (f_i = 0; f_i < g->frames; ++f_i)
                    fwrite(g->data + f_i * g->frame_floats + BODY_FLOATS * g->bodies + POINT_FLOATS * points +
                               SPRING_FLOATS * i + (k == 0 ? 0 : k == 1 ? 3 : 7),
                           sizeof(float), k == 1 ? 4 : 3, f);
    } else if (!g->geometry_size) {
        fwrite("\0\0\0\0", 1, 4, f); /* a buffer has at least one byte */
    }
    rc = 0;
done:
    if (j)
        fclose(j);
    if (l.views)
        fclose(l.views);
    if (l.accessors)
        fclose(l.accessors);
    free(json), free(views), free(accessors);
    return rc;
}
