/* test_collide.c: the narrowphase (src/collision/collide.c) against closed-form
   contacts for every pair of shapes, then its promises: the normal flips
   and the points stay when a and b swap, features survive a small move,
   and, over random configurations, depths agree with brute-force distances,
   points lie midway between the surfaces and nothing is ever NaN. */
#include "test_main.h"
#include "collision/collision.h"

#include <math.h>
#include <string.h>

#define TOL 1e-12
static const double PI = 3.14159265358979323846;
static const double ID[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 };

/* ------------------------------------------------------------ helpers -- */

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static double norm3(const double a[3]) { return sqrt(dot3(a, a)); }
static double dist3(const double a[3], const double b[3])
{
    const double d[3] = { a[0] - b[0], a[1] - b[1], a[2] - b[2] };
    return norm3(d);
}

/* Row-major rotation by angle about the unit axis (Rodrigues). */
static void rot_axis(double x, double y, double z, double angle, double R[9])
{
    const double n = sqrt(x * x + y * y + z * z), c = cos(angle), s = sin(angle), t = 1 - c;
    x /= n, y /= n, z /= n;
    R[0] = t * x * x + c, R[1] = t * x * y - s * z, R[2] = t * x * z + s * y;
    R[3] = t * x * y + s * z, R[4] = t * y * y + c, R[5] = t * y * z - s * x;
    R[6] = t * x * z - s * y, R[7] = t * y * z + s * x, R[8] = t * z * z + c;
}

static void rot_mul(const double A[9], const double B[9], double out[9])
{
    double C[9];
    int i, j;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j)
            C[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
    memcpy(out, C, sizeof C);
}

/* World point of local l in g. */
static void world(const tb__geom *g, const double l[3], double out[3])
{
    double w[3];
    int i;
    for (i = 0; i < 3; ++i)
        w[i] = g->pos[i] + g->rot[3 * i] * l[0] + g->rot[3 * i + 1] * l[1] + g->rot[3 * i + 2] * l[2];
    memcpy(out, w, sizeof w);
}

static void local(const tb__geom *g, const double p[3], double out[3])
{
    const double d[3] = { p[0] - g->pos[0], p[1] - g->pos[1], p[2] - g->pos[2] };
    int i;
    for (i = 0; i < 3; ++i)
        out[i] = g->rot[i] * d[0] + g->rot[3 + i] * d[1] + g->rot[6 + i] * d[2];
}

static tb__geom sphere(double x, double y, double z, double r)
{
    tb__geom g;
    memset(&g, 0, sizeof g);
    g.kind = TB__SHAPE_SPHERE;
    g.pos[0] = x, g.pos[1] = y, g.pos[2] = z;
    memcpy(g.rot, ID, sizeof ID);
    g.radius = r;
    return g;
}

static tb__geom capsule(double x, double y, double z, const double R[9], double half, double r)
{
    tb__geom g = sphere(x, y, z, r);
    g.kind = TB__SHAPE_CAPSULE;
    memcpy(g.rot, R, sizeof g.rot);
    g.half[2] = half;
    return g;
}

static tb__geom box(double x, double y, double z, const double R[9], double hx, double hy, double hz)
{
    tb__geom g = sphere(x, y, z, 0);
    g.kind = TB__SHAPE_BOX;
    memcpy(g.rot, R, sizeof g.rot);
    g.half[0] = hx, g.half[1] = hy, g.half[2] = hz;
    return g;
}

static tb__geom plane(double nx, double ny, double nz, double offset)
{
    tb__geom g = sphere(0, 0, 0, 0);
    const double n = sqrt(nx * nx + ny * ny + nz * nz);
    g.kind = TB__SHAPE_PLANE;
    g.normal[0] = nx / n, g.normal[1] = ny / n, g.normal[2] = nz / n;
    g.offset = offset;
    return g;
}

/* Rotation taking z to x (a capsule lying along x). */
static void along_x(double R[9]) { rot_axis(0, 1, 0, PI / 2, R); }

static void assert_vec(const double v[3], double x, double y, double z, double tol)
{
    if (!(fabs(v[0] - x) <= tol && fabs(v[1] - y) <= tol && fabs(v[2] - z) <= tol))
        fail_msg("(%.17g, %.17g, %.17g), expected (%.17g, %.17g, %.17g) within %g", v[0], v[1], v[2], x, y, z, tol);
}

/* The point of m at (x, y, z) within tol, or a failure. */
static const tb__contact_point *point_at(const tb__manifold *m, double x, double y, double z, double tol)
{
    const double p[3] = { x, y, z };
    int i;
    for (i = 0; i < m->count; ++i)
        if (dist3(m->point[i].pos, p) <= tol)
            return &m->point[i];
    fail_msg("no point at (%g, %g, %g) among %d", x, y, z, m->count);
    return NULL;
}

static int has_feature(const tb__manifold *m, uint32_t f)
{
    int i;
    for (i = 0; i < m->count; ++i)
        if (m->point[i].feature == f)
            return 1;
    return 0;
}

static double clampd(double x, double lo, double hi) { return x < lo ? lo : x > hi ? hi : x; }

/* Distance from p to the segment of capsule g (its core). */
static double core_distance(const tb__geom *g, const double p[3])
{
    double l[3], q[3] = { 0, 0, 0 };
    local(g, p, l);
    q[2] = clampd(l[2], -g->half[2], g->half[2]);
    return dist3(l, q);
}

/* Distance from p to the solid box g (0 inside). */
static double box_distance(const tb__geom *g, const double p[3])
{
    double l[3], q[3];
    int i;
    local(g, p, l);
    for (i = 0; i < 3; ++i)
        q[i] = clampd(l[i], -g->half[i], g->half[i]);
    return dist3(l, q);
}

/* Distance from p to the solid shape g (0 inside). */
static double solid_distance(const tb__geom *g, const double p[3])
{
    switch (g->kind) {
    case TB__SHAPE_SPHERE: return fmax(0, dist3(p, g->pos) - g->radius);
    case TB__SHAPE_CAPSULE: return fmax(0, core_distance(g, p) - g->radius);
    case TB__SHAPE_BOX: return box_distance(g, p);
    default: return fmax(0, dot3(g->normal, p) - g->offset);
    }
}

static void capsule_end(const tb__geom *g, double t, double out[3])
{
    const double l[3] = { 0, 0, t * g->half[2] };
    world(g, l, out);
}

/* Minimum of a convex function of t in [0, 1] by golden sections. */
static double convex_min(double (*f)(const void *, double), const void *ctx)
{
    const double g = (sqrt(5.0) - 1) / 2;
    double lo = 0, hi = 1, x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo), f1 = f(ctx, x1), f2 = f(ctx, x2);
    int i;
    for (i = 0; i < 200; ++i) {
        if (f1 < f2)
            hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = f(ctx, x1);
        else
            lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = f(ctx, x2);
    }
    return fmin(fmin(f1, f2), fmin(f(ctx, 0), f(ctx, 1)));
}

typedef struct pair_ctx {
    const tb__geom *seg, *other;
} pair_ctx;

/* Distance from the point of the core of c->seg at parameter t to the core
   of c->other (a capsule) or the solid box. */
static double seg_to_other(const void *ctx, double t)
{
    const pair_ctx *c = ctx;
    double p[3];
    capsule_end(c->seg, 2 * t - 1, p);
    return c->other->kind == TB__SHAPE_BOX ? box_distance(c->other, p) : core_distance(c->other, p);
}

static int finite_manifold(const tb__manifold *m)
{
    int i, j;
    for (i = 0; i < 3; ++i)
        if (!isfinite(m->normal[i]))
            return 0;
    for (i = 0; i < m->count; ++i) {
        if (!isfinite(m->point[i].depth))
            return 0;
        for (j = 0; j < 3; ++j)
            if (!isfinite(m->point[i].pos[j]))
                return 0;
    }
    return 1;
}

static double deepest(const tb__manifold *m)
{
    double d = -HUGE_VAL;
    int i;
    for (i = 0; i < m->count; ++i)
        d = fmax(d, m->point[i].depth);
    return d;
}

/* Fixed-seed generator (xorshift64*), uniform in [lo, hi); each test
   seeds it, so a case draws the same numbers run alone or with the rest. */
static uint64_t rng_state;
static void seed(uint64_t s) { rng_state = s * 0x9e3779b97f4a7c15u | 1; }
static double uniform(double lo, double hi)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return lo + (hi - lo) * ((rng_state * 2685821657736338717u) >> 11) * (1.0 / 9007199254740992.0);
}

static void random_rot(double R[9])
{
    double q[4], n;
    int i;
    do {
        for (i = 0, n = 0; i < 4; ++i)
            q[i] = uniform(-1, 1), n += q[i] * q[i];
    } while (n > 1 || n < 1e-3);
    n = sqrt(n);
    rot_axis(q[1], q[2], q[3], 2 * acos(q[0] / n), R);
}

/* ------------------------------------------------------- round shapes -- */

static void sphere_sphere_exact(void **state)
{
    (void)state;
    const tb__geom a = sphere(0.1, -0.2, 0.3, 1), b = sphere(1.2, 0.5, 0.1, 0.7);
    tb__manifold m;
    const double d[3] = { 1.1, 0.7, -0.2 }, L = norm3(d);
    assert_int_equal(tb__collide(&a, &b, 0, 0, &m), 1);
    assert_vec(m.normal, d[0] / L, d[1] / L, d[2] / L, TOL);
    assert_rel(m.point[0].depth, 1.7 - L, TOL);
    /* Midway between the surfaces: a's surface at ra along n, b's at L - rb. */
    const double s = (1 + (L - 0.7)) / 2;
    assert_vec(m.point[0].pos, 0.1 + s * d[0] / L, -0.2 + s * d[1] / L, 0.3 + s * d[2] / L, TOL);
}

static void coincident_centres_give_a_fixed_axis(void **state)
{
    (void)state;
    double R[9];
    rot_axis(1, 2, 3, 0.7, R);
    const tb__geom shapes[] = { sphere(1, 2, 3, 0.5), capsule(1, 2, 3, R, 0.6, 0.3), box(1, 2, 3, R, 0.4, 0.5, 0.6) };
    int i, j;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            tb__manifold m, m2;
            assert_true(tb__collide(&shapes[i], &shapes[j], 0, 0, &m) >= 1);
            assert_true(finite_manifold(&m));
            assert_rel(norm3(m.normal), 1, TOL);
            assert_true(deepest(&m) > 0);
            /* A fixed axis: the same answer again. */
            tb__collide(&shapes[i], &shapes[j], 0, 0, &m2);
            assert_memory_equal(&m, &m2, sizeof m);
        }
    tb__manifold m;
    const tb__geom a = sphere(0, 0, 0, 1), b = sphere(0, 0, 0, 2);
    tb__collide(&a, &b, 0, 0, &m);
    assert_rel(m.point[0].depth, 3, TOL);
    /* A sphere at the centre of a box leaves through the nearest face. */
    const tb__geom s = sphere(1, 2, 3, 0.1), bx = box(1, 2, 3, ID, 0.5, 0.3, 0.4);
    tb__collide(&s, &bx, 0, 0, &m);
    assert_rel(m.point[0].depth, 0.4, TOL);
    assert_rel(fabs(m.normal[1]), 1, TOL);
}

static void sphere_rests_on_plane(void **state)
{
    (void)state;
    const tb__geom s = sphere(0.3, 0.4, 0.99, 1), p = plane(0, 0, 1, 0);
    tb__manifold m;
    assert_int_equal(tb__collide(&s, &p, 0, 0, &m), 1);
    assert_vec(m.normal, 0, 0, -1, 0);
    assert_rel(m.point[0].depth, 0.01, 1e-12);
    assert_vec(m.point[0].pos, 0.3, 0.4, -0.005, TOL);
    assert_int_equal(m.point[0].feature, 0);
    /* A tilted plane through (0, 0, 2), the centre 0.5 above it. */
    const tb__geom t = plane(1, 1, 1, 2 / sqrt(3.0));
    const double n = 1 / sqrt(3.0);
    const tb__geom s2 = sphere(0.5 * n, 0.5 * n, 2 + 0.5 * n, 1);
    assert_int_equal(tb__collide(&s2, &t, 0, 0, &m), 1);
    assert_rel(m.point[0].depth, 0.5, 1e-12);
    assert_vec(m.point[0].pos, -0.25 * n, -0.25 * n, 2 - 0.25 * n, TOL);
}

static void margin_gives_speculative_points(void **state)
{
    (void)state;
    tb__manifold m;
    const tb__geom a = sphere(0, 0, 0, 1), b = sphere(2.01, 0, 0, 1);
    assert_int_equal(tb__collide(&a, &b, 0.02, 0, &m), 1);
    assert_rel(m.point[0].depth, -0.01, 1e-12);
    assert_int_equal(tb__collide(&a, &b, 0.005, 0, &m), 0);
    assert_int_equal(tb__collide(&a, &b, 0, 0, &m), 0);

    const tb__geom bx = box(0, 0, 0.51, ID, 1, 1, 0.5), p = plane(0, 0, 1, 0);
    assert_int_equal(tb__collide(&bx, &p, 0.02, 0, &m), 4);
    assert_rel(m.point[3].depth, -0.01, 1e-12);
    assert_int_equal(tb__collide(&bx, &p, 0.005, 0, &m), 0);

    const tb__geom lower = box(0, 0, 0, ID, 1, 1, 1), upper = box(0.2, 0.1, 2.01, ID, 0.5, 0.5, 1);
    assert_int_equal(tb__collide(&lower, &upper, 0.02, 0, &m), 4);
    assert_rel(m.point[2].depth, -0.01, 1e-12);
    assert_int_equal(tb__collide(&lower, &upper, 0.005, 0, &m), 0);

    double R[9];
    along_x(R);
    const tb__geom c = capsule(0, 0, 0.51, R, 1, 0.5);
    assert_int_equal(tb__collide(&c, &p, 0.02, 0, &m), 2);
    assert_rel(m.point[1].depth, -0.01, 1e-12);
    assert_int_equal(tb__collide(&c, &p, 0.005, 0, &m), 0);
}

static void sphere_against_capsule(void **state)
{
    (void)state;
    double R[9];
    tb__manifold m;
    along_x(R);
    const tb__geom c = capsule(0, 0, 0, R, 1, 0.5);
    /* Beside the core: straight across. */
    const tb__geom s = sphere(0.4, 0, 0.7, 0.3);
    assert_int_equal(tb__collide(&s, &c, 0, 0, &m), 1);
    assert_vec(m.normal, 0, 0, -1, TOL);
    assert_rel(m.point[0].depth, 0.1, 1e-12);
    assert_vec(m.point[0].pos, 0.4, 0, 0.45, TOL);
    /* Beyond an end: towards the end of the core. */
    const tb__geom e = sphere(1.3, 0.4, 0, 0.3);
    assert_int_equal(tb__collide(&c, &e, 0, 0, &m), 1);
    assert_vec(m.normal, 0.6, 0.8, 0, TOL);
    assert_rel(m.point[0].depth, 0.3, 1e-12);
    /* Centre on the core: out sideways, never along the core. */
    const tb__geom in = sphere(0.5, 0, 0, 0.3);
    assert_int_equal(tb__collide(&in, &c, 0, 0, &m), 1);
    assert_true(fabs(m.normal[0]) < TOL);
    assert_rel(m.point[0].depth, 0.8, 1e-12);
}

static void sphere_against_box(void **state)
{
    (void)state;
    double R[9];
    tb__manifold m;
    rot_axis(0, 0, 1, 0.3, R);
    const tb__geom b = box(1, 2, 3, R, 1, 2, 3);
    /* Over face +x, over edge (+x, +y), over corner (+x, -y, +z): in the box
       frame, gaps of 0.1, 0.5 and sqrt(0.02 + 0.04 + 0.01). */
    static const double at[3][3] = { { 1.1, 0.5, -1 }, { 1.3, 2.4, 0 }, { 1.1, -2.2, 3.1 } };
    const double gap[3] = { 0.1, 0.5, sqrt(0.01 + 0.04 + 0.01) };
    int i;
    for (i = 0; i < 3; ++i) {
        double c[3], l[3], q[3], n[3];
        int k;
        world(&b, at[i], c);
        const tb__geom s = sphere(c[0], c[1], c[2], 0.6);
        assert_int_equal(tb__collide(&s, &b, 0, 0, &m), 1);
        assert_rel(m.point[0].depth, 0.6 - gap[i], 1e-12);
        /* The normal runs from the centre to the box's closest point. */
        for (k = 0; k < 3; ++k)
            q[k] = clampd(at[i][k], -b.half[k], b.half[k]), l[k] = (q[k] - at[i][k]) / gap[i];
        world(&b, q, q);
        n[0] = R[0] * l[0] + R[1] * l[1], n[1] = R[3] * l[0] + R[4] * l[1], n[2] = l[2];
        assert_vec(m.normal, n[0], n[1], n[2], TOL);
        const double s_ = 0.5 * (gap[i] - 0.6); /* from the box surface, outwards */
        assert_vec(m.point[0].pos, q[0] - s_ * n[0], q[1] - s_ * n[1], q[2] - s_ * n[2], 1e-12);
    }
}

static void sphere_inside_box_leaves_by_nearest_face(void **state)
{
    (void)state;
    tb__manifold m;
    const tb__geom b = box(0, 0, 0, ID, 1, 2, 3);
    /* 0.3 behind +y, 0.5 behind +x: out through +y. */
    const tb__geom s = sphere(0.5, 1.7, -1, 0.2);
    assert_int_equal(tb__collide(&s, &b, 0, 0, &m), 1);
    assert_vec(m.normal, 0, -1, 0, 0);
    assert_rel(m.point[0].depth, 0.5, 1e-12);
    /* Midway between the box face (y = 2) and the sphere's far side (y = 1.5). */
    assert_vec(m.point[0].pos, 0.5, 1.75, -1, TOL);
    assert_int_equal(tb__collide(&b, &s, 0, 0, &m), 1);
    assert_vec(m.normal, 0, 1, 0, 0);
}

/* ------------------------------------------------------------ capsules -- */

static void capsule_lying_on_plane_gives_two_points(void **state)
{
    (void)state;
    double R[9], T[9];
    tb__manifold m;
    const tb__geom p = plane(0, 0, 1, 0);
    along_x(R);
    const tb__geom c = capsule(0.5, 0.2, 0.49, R, 1, 0.5);
    assert_int_equal(tb__collide(&c, &p, 0, 0, &m), 2);
    assert_vec(m.normal, 0, 0, -1, 0);
    assert_rel(point_at(&m, -0.5, 0.2, -0.005, TOL)->depth, 0.01, 1e-12);
    assert_rel(point_at(&m, 1.5, 0.2, -0.005, TOL)->depth, 0.01, 1e-12);
    /* Standing on an end, or tilted: one end only. */
    const tb__geom up = capsule(0, 0, 1.49, ID, 1, 0.5);
    assert_int_equal(tb__collide(&up, &p, 0, 0, &m), 1);
    assert_vec(m.point[0].pos, 0, 0, -0.005, TOL);
    rot_axis(0, 1, 0, 1.0, T);
    const tb__geom tilt = capsule(0, 0, 0.5 + cos(1.0) - 0.01, T, 1, 0.5);
    assert_int_equal(tb__collide(&tilt, &p, 0, 0, &m), 1);
    assert_rel(m.point[0].depth, 0.01, 1e-9);
}

static void capsules_parallel_give_two_points(void **state)
{
    (void)state;
    double R[9];
    tb__manifold m;
    along_x(R);
    const tb__geom a = capsule(0, 0, 0, R, 1, 0.5), b = capsule(0.6, 0, 0.79, R, 1.5, 0.3);
    assert_int_equal(tb__collide(&a, &b, 0, 0, &m), 2);
    assert_vec(m.normal, 0, 0, 1, TOL);
    /* The cores overlap from x = -0.9 to 1; a's surface at 0.5, b's at 0.49. */
    assert_rel(point_at(&m, -0.9, 0, 0.495, TOL)->depth, 0.01, 1e-12);
    assert_rel(point_at(&m, 1, 0, 0.495, TOL)->depth, 0.01, 1e-12);
    /* Collinear, end to end: one point. */
    const tb__geom c = capsule(2.9, 0, 0, R, 1, 0.5);
    assert_int_equal(tb__collide(&a, &c, 0, 0, &m), 1);
    assert_vec(m.normal, 1, 0, 0, TOL);
    assert_rel(m.point[0].depth, 0.1, 1e-12);
    assert_vec(m.point[0].pos, 1.45, 0, 0, TOL);
}

static void capsules_crossed_give_one_point(void **state)
{
    (void)state;
    double Rx[9], Ry[9];
    tb__manifold m;
    along_x(Rx);
    rot_axis(1, 0, 0, -PI / 2, Ry); /* z to y */
    /* a along x, b along y above it at x = 0.3: the cores' closest points
       are (0.3, 0, 0) and (0.3, 0, 0.75). */
    const tb__geom a = capsule(0, 0, 0, Rx, 1, 0.5), b = capsule(0.3, 0.2, 0.75, Ry, 1, 0.3);
    assert_int_equal(tb__collide(&a, &b, 0, 0, &m), 1);
    assert_vec(m.normal, 0, 0, 1, TOL);
    assert_rel(m.point[0].depth, 0.05, 1e-12);
    assert_vec(m.point[0].pos, 0.3, 0, 0.475, TOL);
    /* Skew at 60 degrees, crossing near the end of b. */
    double R60[9];
    rot_axis(0, 0, 1, PI / 3, R60);
    rot_mul(R60, Rx, R60);
    const tb__geom c = capsule(-0.2, 0, 0.7, R60, 0.5, 0.3);
    assert_int_equal(tb__collide(&a, &c, 0, 0, &m), 1);
    assert_vec(m.normal, 0, 0, 1, TOL);
    assert_rel(m.point[0].depth, 0.1, 1e-12);
    assert_vec(m.point[0].pos, -0.2, 0, 0.45, TOL);
}

static void degenerate_capsule_is_a_sphere(void **state)
{
    (void)state;
    double R[9];
    rot_axis(1, 1, 0, 0.4, R);
    const tb__geom c = capsule(0.2, 0.1, 0.9, R, 0, 1), s = sphere(0.2, 0.1, 0.9, 1);
    const tb__geom others[] = { plane(0, 0, 1, 0), box(0, 0, -0.5, R, 1, 1, 1), capsule(1, 0.5, 0, R, 0.5, 0.4),
                                capsule(0.2, 0.1, 0.9, R, 0, 0.5), sphere(0.1, 0.1, 0.2, 0.5) };
    size_t i;
    for (i = 0; i < sizeof others / sizeof others[0]; ++i) {
        tb__manifold mc, ms;
        assert_int_equal(tb__collide(&c, &others[i], 0, 0, &mc), tb__collide(&s, &others[i], 0, 0, &ms));
        assert_true(mc.count >= 1);
        assert_memory_equal(&mc, &ms, sizeof mc);
    }
}

static void capsule_against_box(void **state)
{
    (void)state;
    double R[9], T[9];
    tb__manifold m;
    along_x(R);
    const tb__geom b = box(0, 0, 0, ID, 2, 1, 0.5);
    /* Lying on the top face, overhanging it at x = 2: clipped there. */
    const tb__geom c = capsule(1.5, 0.3, 0.79, R, 1, 0.3);
    assert_int_equal(tb__collide(&c, &b, 0, 0, &m), 2);
    assert_vec(m.normal, 0, 0, -1, 0);
    assert_rel(point_at(&m, 0.5, 0.3, 0.495, TOL)->depth, 0.01, 1e-12);
    assert_rel(point_at(&m, 2, 0.3, 0.495, TOL)->depth, 0.01, 1e-12);
    /* Sunk below its radius (core inside the box): the same two points. */
    const tb__geom deep = capsule(1.5, 0.3, 0.4, R, 1, 0.3);
    assert_int_equal(tb__collide(&deep, &b, 0, 0, &m), 2);
    assert_vec(m.normal, 0, 0, -1, 0);
    assert_rel(point_at(&m, 0.5, 0.3, 0.3, TOL)->depth, 0.4, 1e-12);
    assert_rel(point_at(&m, 2, 0.3, 0.3, TOL)->depth, 0.4, 1e-12);
    /* Standing on its end, tilted: the lower end. */
    rot_axis(0, 1, 0, 0.5, T);
    const tb__geom up = capsule(0.5 * sin(0.5), 0, 0.5 + 0.3 + 0.5 * cos(0.5) - 0.02, T, 0.5, 0.3);
    assert_int_equal(tb__collide(&up, &b, 0, 0, &m), 1);
    assert_rel(m.point[0].depth, 0.02, 1e-12);
    assert_vec(m.point[0].pos, 0, 0, 0.49, TOL);
    /* Across the edge x = 2, z = 0.5 at 45 degrees to both faces, the core
       0.25 out from it (and then 0.25 in) along w = (1, 0, 1) / sqrt 2. */
    double D[9];
    rot_axis(0, 1, 0, -PI / 4, D); /* core along (-1, 0, 1) / sqrt 2 */
    const double k = 0.25 / sqrt(2.0), w = sqrt(0.5);
    const tb__geom e = capsule(2 + k, 0, 0.5 + k, D, 1, 0.3);
    assert_int_equal(tb__collide(&e, &b, 0, 0, &m), 1);
    assert_vec(m.normal, -w, 0, -w, TOL);
    assert_rel(m.point[0].depth, 0.05, 1e-12);
    assert_vec(m.point[0].pos, 2 - 0.025 * w, 0, 0.5 - 0.025 * w, 1e-12);
    const tb__geom e2 = capsule(2 - k, 0, 0.5 - k, D, 1, 0.3);
    assert_int_equal(tb__collide(&e2, &b, 0, 0, &m), 1);
    assert_vec(m.normal, -w, 0, -w, TOL);
    assert_rel(m.point[0].depth, 0.55, 1e-12);
}

/* -------------------------------------------------------------- boxes -- */

static void box_lying_on_plane_gives_four_corners(void **state)
{
    (void)state;
    double R[9];
    tb__manifold m;
    rot_axis(0, 0, 1, 0.4, R);
    const tb__geom b = box(1, 2, 0.49, R, 1, 0.5, 0.5), p = plane(0, 0, 1, 0);
    assert_int_equal(tb__collide(&b, &p, 0, 0, &m), 4);
    int i, sx, sy;
    for (i = 0; i < 4; ++i)
        assert_rel(m.point[i].depth, 0.01, 1e-12);
    for (sx = -1; sx <= 1; sx += 2)
        for (sy = -1; sy <= 1; sy += 2) {
            double c[3];
            const double l[3] = { sx * 1.0, sy * 0.5, -0.5 };
            world(&b, l, c);
            point_at(&m, c[0], c[1], -0.005, TOL);
        }
    /* Thinner than the margin: still the bottom four. */
    const tb__geom thin = box(0, 0, 0.0009, ID, 1, 1, 0.001);
    assert_int_equal(tb__collide(&thin, &p, 0.1, 0, &m), 4);
    for (i = 0; i < 4; ++i)
        assert_rel(m.point[i].depth, 0.0001, 1e-9);
    /* On a corner: one point. */
    double C[9];
    rot_axis(1, 0, 0, PI / 4, C);
    rot_axis(0, 1, 0, atan(1 / sqrt(2.0)), R);
    rot_mul(R, C, C);
    const tb__geom corner = box(0, 0, sqrt(3.0) - 0.02, C, 1, 1, 1);
    assert_int_equal(tb__collide(&corner, &p, 0, 0, &m), 1);
    assert_rel(m.point[0].depth, 0.02, 1e-9);
}

/* A plank 4 m long and 1.8 cm thick, buried in the plane with its length
   5 degrees off level, every corner under the surface: the points are its
   bottom face's, so they span both ends. The 4 deepest of all 8 corners
   are the low end's, top and bottom, and a push there only turns the
   plank: one with a heavy core would sink through the plane for good. */
static void buried_plank_keeps_both_ends(void **state)
{
    (void)state;
    double R[9];
    tb__manifold m;
    rot_axis(0, 1, 0, 5 * PI / 180, R);
    const tb__geom plank = box(0, 0, -0.5, R, 2.03, 0.27, 0.009), p = plane(0, 0, 1, 0);
    int i, j, count = tb__collide(&plank, &p, 0, 0, &m);
    double corner[4][3], span = 0;
    assert_int_equal(count, 4);
    for (i = 0; i < count; ++i) { /* the point is halfway up from its corner */
        const double at[3] = { m.point[i].pos[0], m.point[i].pos[1], m.point[i].pos[2] - 0.5 * m.point[i].depth };
        local(&plank, at, corner[i]);
        assert_true(fabs(corner[i][2] + 0.009) < 1e-12); /* the -z face */
    }
    for (i = 0; i < count; ++i)
        for (j = 0; j < count; ++j)
            span = fmax(span, fabs(corner[i][0] - corner[j][0]));
    assert_true(fabs(span - 2 * 2.03) < 1e-12);
}

static void box_on_box_face_contact(void **state)
{
    (void)state;
    double R[9];
    tb__manifold m;
    rot_axis(0, 0, 1, 0.3, R);
    /* A small box turned 0.3 rad on a big one, 0.01 into it. */
    const tb__geom big = box(0, 0, 0, ID, 2, 2, 1), small = box(0.4, -0.3, 1.49, R, 0.5, 0.4, 0.5);
    assert_int_equal(tb__collide(&big, &small, 0, 0, &m), 4);
    assert_vec(m.normal, 0, 0, 1, 0);
    int sx, sy;
    for (sx = -1; sx <= 1; sx += 2)
        for (sy = -1; sy <= 1; sy += 2) {
            double c[3];
            const double l[3] = { sx * 0.5, sy * 0.4, -0.5 };
            world(&small, l, c);
            assert_rel(point_at(&m, c[0], c[1], 0.995, 1e-12)->depth, 0.01, 1e-12);
        }
}

static void box_on_box_turned_45_degrees(void **state)
{
    (void)state;
    double R[9];
    tb__manifold m;
    rot_axis(0, 0, 1, PI / 4, R);
    const tb__geom a = box(0, 0, 0, ID, 1, 1, 1), b = box(0, 0, 1.99, R, 1, 1, 1);
    /* The faces overlap in a regular octagon; four of its corners are kept. */
    assert_int_equal(tb__collide(&a, &b, 0, 0, &m), 4);
    assert_vec(m.normal, 0, 0, 1, 0);
    int i, j;
    double area = 0;
    for (i = 0; i < 4; ++i) {
        double lb[3];
        const double *p = m.point[i].pos;
        assert_rel(m.point[i].depth, 0.01, 1e-12);
        assert_rel(p[2], 0.995, 1e-14);
        assert_below(fmax(fabs(p[0]), fabs(p[1])), 1 + 1e-12);
        local(&b, p, lb);
        assert_below(fmax(fabs(lb[0]), fabs(lb[1])), 1 + 1e-12);
        /* A corner of the octagon: on the boundary of one of the squares. */
        assert_true(fabs(fmax(fabs(p[0]), fabs(p[1])) - 1) < 1e-12 || fabs(fmax(fabs(lb[0]), fabs(lb[1])) - 1) < 1e-12);
        for (j = 0; j < i; ++j)
            assert_true(dist3(p, m.point[j].pos) > 0.5);
    }
    /* They span a good part of the octagon (area 8 (sqrt 2 - 1) = 3.31). */
    for (i = 0; i < 4; ++i)
        for (j = i + 1; j < 4; ++j)
            area = fmax(area, dist3(m.point[i].pos, m.point[j].pos));
    assert_true(area > 2);
}

static void boxes_crossing_edge_to_edge(void **state)
{
    (void)state;
    double Ra[9], Rb[9];
    tb__manifold m;
    /* a's top edge runs along x at z = sqrt 2; b's bottom edge along y. */
    rot_axis(1, 0, 0, PI / 4, Ra);
    rot_axis(0, 1, 0, PI / 4, Rb);
    const double r2 = sqrt(2.0), depth = 0.03;
    const tb__geom a = box(0, 0, 0, Ra, 1, 1, 1), b = box(0.1, -0.2, 2 * r2 - depth, Rb, 1, 1, 1);
    assert_int_equal(tb__collide(&a, &b, 0, 0, &m), 1);
    assert_vec(m.normal, 0, 0, 1, 1e-12);
    assert_rel(m.point[0].depth, depth, 1e-12);
    assert_vec(m.point[0].pos, 0.1, 0, r2 - depth / 2, 1e-12); /* edges at y = 0, x = 0.1 */
    assert_true(m.point[0].feature >= 0x20000u);
}

/* A box pressed into the top face of a large box at random orientations:
   the face of the large box is the reference, so the deepest point is the
   deepest corner, exactly, and every point lies on the small box's surface
   with its depth below the top face. */
static void random_box_on_box_matches_corners(void **state)
{
    (void)state;
    seed(1);
    const tb__geom big = box(0, 0, -1, ID, 3, 3, 1);
    int trial, i, k;
    for (trial = 0; trial < 500; ++trial) {
        double R[9], low = HUGE_VAL;
        random_rot(R);
        tb__geom b = box(uniform(-1, 1), uniform(-1, 1), 0, R, uniform(0.2, 0.5), uniform(0.2, 0.5), uniform(0.2, 0.5));
        for (k = 0; k < 8; ++k) {
            double c[3];
            const double l[3] = { k & 1 ? b.half[0] : -b.half[0], k & 2 ? b.half[1] : -b.half[1],
                                  k & 4 ? b.half[2] : -b.half[2] };
            world(&b, l, c);
            low = fmin(low, c[2]);
        }
        const double depth = uniform(-0.05, 0.1), margin = 0.1;
        b.pos[2] -= low + depth;
        tb__manifold m;
        assert_true(tb__collide(&big, &b, margin, 0, &m) >= 1);
        assert_vec(m.normal, 0, 0, 1, 0);
        assert_rel(deepest(&m), depth, 1e-9);
        for (i = 0; i < m.count; ++i) {
            const double *p = m.point[i].pos, d = m.point[i].depth;
            const double on_b[3] = { p[0], p[1], p[2] - 0.5 * d };
            assert_true(d <= depth + 1e-12 && d > -margin);
            assert_rel(p[2], -0.5 * d, 1e-9);
            assert_below(box_distance(&b, on_b), 1e-9);
        }
    }
}

/* Identical boxes stacked flush, then jittered by less than the clipping
   tolerance: still the 4 corners, with the same features. */
static void flush_stack_keeps_four_corners(void **state)
{
    (void)state;
    seed(2);
    const tb__geom lower = box(0, 0, 0, ID, 0.5, 0.5, 0.5);
    tb__geom upper = box(0, 0, 0.999, ID, 0.5, 0.5, 0.5);
    tb__manifold m0, m1;
    double T[9];
    int j, trial;
    assert_int_equal(tb__collide(&lower, &upper, 0, 0, &m0), 4);
    for (j = 0; j < 4; ++j)
        assert_rel(m0.point[j].depth, 0.001, 1e-9);
    for (trial = 0; trial < 50; ++trial) {
        tb__geom u = upper;
        u.pos[0] += uniform(-3e-5, 3e-5), u.pos[1] += uniform(-3e-5, 3e-5);
        rot_axis(0, 0, 1, uniform(-3e-5, 3e-5), T);
        rot_mul(T, u.rot, u.rot);
        assert_int_equal(tb__collide(&lower, &u, 0, 0, &m1), 4);
        for (j = 0; j < 4; ++j)
            assert_true(has_feature(&m1, m0.point[j].feature));
    }
}

/* Boxes touching exactly face to face (turned by half and three quarter
   turns, so the zeros of the rotations are rounded): nothing at margin 0,
   where no face point is closer than the margin and the edge axis, as
   close by rounding, must not put a point on edges that do not cross; the
   patch x in [0.75, 1], z in [0.25, 0.75] on y = -0.5 within a margin. */
static void touching_boxes_give_the_patch_or_nothing(void **state)
{
    (void)state;
    double Ra[9], Rb[9];
    tb__manifold m;
    int sx, sz;
    rot_axis(1, 0, 0, 4 * PI / 4, Ra);
    rot_axis(0, 1, 0, 6 * PI / 4, Rb);
    const tb__geom a = box(0.25, -0.75, 0.5, Ra, 0.75, 0.25, 0.25), b = box(1, 0, 0.5, Rb, 0.5, 0.5, 0.25);
    assert_int_equal(tb__collide(&a, &b, 0, 0, &m), 0);
    assert_int_equal(tb__collide(&a, &b, 0.01, 0, &m), 4);
    assert_vec(m.normal, 0, 1, 0, 1e-12);
    for (sx = 0; sx < 2; ++sx)
        for (sz = 0; sz < 2; ++sz)
            assert_true(fabs(point_at(&m, 0.75 + 0.25 * sx, -0.5, 0.25 + 0.5 * sz, 1e-12)->depth) < 1e-12);
}

static void plane_against_plane_is_empty(void **state)
{
    (void)state;
    tb__manifold m;
    const tb__geom a = plane(0, 0, 1, 0), b = plane(0, 0, -1, 1);
    assert_int_equal(tb__collide(&a, &b, 1, 0, &m), 0);
}

/* ------------------------------------------------------- symmetries -- */

/* Configurations whose manifold is unique (no choice among equal points). */
static int configurations(tb__geom a[], tb__geom b[])
{
    double Rx[9], Ry[9], Rz[9], Ra[9], Rb[9];
    int n = 0;
    along_x(Rx);
    rot_axis(1, 0, 0, -PI / 2, Ry);
    rot_axis(0, 0, 1, 0.3, Rz);
    rot_axis(1, 0, 0, PI / 4, Ra);
    rot_axis(0, 1, 0, PI / 4, Rb);
    a[n] = sphere(0, 0, 0, 1), b[n++] = sphere(1.2, 0.5, 0.1, 0.7);
    a[n] = sphere(0, 0, 0.9, 1), b[n++] = plane(0, 0.1, 1, 0);
    a[n] = sphere(1.1, 0.2, 0.3, 0.5), b[n++] = box(0, 0, 0, Rz, 1, 1, 1);
    a[n] = sphere(0.5, 0.2, 0.7, 0.3), b[n++] = capsule(0, 0, 0, Rx, 1, 0.5);
    a[n] = capsule(0, 0, 0.49, Rx, 1, 0.5), b[n++] = plane(0, 0, 1, 0);
    a[n] = capsule(0, 0, 0, Rx, 1, 0.5), b[n++] = capsule(0.3, 0.2, 0.75, Ry, 1, 0.3);
    a[n] = capsule(0, 0, 0, Rx, 1, 0.5), b[n++] = capsule(0.6, 0, 0.79, Rx, 1.5, 0.3);
    a[n] = capsule(1.5, 0.3, 0.79, Rx, 1, 0.3), b[n++] = box(0, 0, 0, ID, 2, 1, 0.5);
    a[n] = box(0, 0, 0.49, Rz, 1, 0.5, 0.5), b[n++] = plane(0, 0, 1, 0);
    a[n] = box(0, 0, 0, ID, 2, 2, 1), b[n++] = box(0.4, -0.3, 1.49, Rz, 0.5, 0.4, 0.5);
    a[n] = box(0, 0, 0, Ra, 1, 1, 1), b[n++] = box(0.1, -0.2, 2 * sqrt(2.0) - 0.03, Rb, 1, 1, 1);
    return n;
}

static void swapping_flips_the_normal_only(void **state)
{
    (void)state;
    tb__geom a[16], b[16];
    const int n = configurations(a, b);
    int i, j;
    for (i = 0; i < n; ++i) {
        tb__manifold ab, ba;
        assert_true(tb__collide(&a[i], &b[i], 0.01, 0, &ab) > 0);
        assert_int_equal(tb__collide(&b[i], &a[i], 0.01, 0, &ba), ab.count);
        assert_vec(ba.normal, -ab.normal[0], -ab.normal[1], -ab.normal[2], 1e-14);
        for (j = 0; j < ab.count; ++j) {
            const double *p = ab.point[j].pos;
            assert_rel(point_at(&ba, p[0], p[1], p[2], 1e-12)->depth, ab.point[j].depth, 1e-9);
        }
    }
}

static void small_moves_keep_the_features(void **state)
{
    (void)state;
    tb__geom a[16], b[16];
    const int n = configurations(a, b);
    double T[9];
    int i, j, moved = 0;
    rot_axis(0.3, -0.5, 0.8, 1e-3, T);
    for (i = 0; i < n; ++i) {
        tb__manifold m0, m1;
        tb__geom c = a[i]; /* never a plane */
        tb__collide(&a[i], &b[i], 0.01, 0, &m0);
        c.pos[0] += 1e-4, c.pos[1] -= 2e-4, c.pos[2] += 1e-5;
        rot_mul(T, c.rot, c.rot);
        tb__collide(&c, &b[i], 0.01, 0, &m1);
        if (m1.count != m0.count)
            fail_msg("configuration %d: %d points, then %d", i, m0.count, m1.count);
        for (j = 0; j < m0.count; ++j)
            if (!has_feature(&m1, m0.point[j].feature))
                fail_msg("configuration %d: feature %#x lost", i, (unsigned)m0.point[j].feature);
        ++moved;
    }
    assert_int_equal(moved, n);
    /* Distinct features within a manifold. */
    for (i = 0; i < n; ++i) {
        tb__manifold m;
        int k;
        tb__collide(&a[i], &b[i], 0.01, 0, &m);
        for (j = 0; j < m.count; ++j)
            for (k = 0; k < j; ++k)
                assert_true(m.point[j].feature != m.point[k].feature);
    }
}

/* A box laid across another's top edge, its bottom face tilted 4 degrees
   about the edge's direction and turned 1 mrad about its own long axis, so
   that the edge lies along the face to 0.4 mm over the face's 0.4 m
   width: with the contact layer's tolerance (a tenth of the 5 mm slop)
   the face is the reference and the manifold is the line of contact, a
   point at each end, not one edge point (which, as the box rocked, jumped
   from end to end: bench_robustness bridge). */
static void edge_along_a_face_is_a_line_of_points(void **state)
{
    (void)state;
    const tb__geom a = box(0, 0, 0, ID, 0.5, 0.5, 0.5);
    double tilt[9], turn[9], R[9];
    tb__geom b;
    tb__manifold m;
    int k;
    rot_axis(0, 1, 0, 4 * PI / 180, tilt);
    rot_axis(1, 0, 0, 1e-3, turn);
    rot_mul(tilt, turn, R);
    b = box(0, 0, 0, R, 0.5, 0.2, 0.1);
    /* its bottom face 20 um into the edge's middle, (0.5, 0, 0.5) */
    for (k = 0; k < 3; ++k)
        b.pos[k] = (k == 1 ? 0 : 0.5) + R[3 * k + 2] * (0.1 - 2e-5);
    assert_int_equal(tb__collide(&a, &b, 0.01, 5e-4, &m), 2);
    assert_true(dot3(m.normal, (const double[3]){ R[2], R[5], R[8] }) > 1 - 1e-12); /* b's bottom face */
    for (k = 0; k < 2; ++k) {
        assert_true(fabs(m.point[k].pos[0] - 0.5) < 1e-3 && fabs(m.point[k].pos[2] - 0.5) < 1e-3); /* on the edge */
    }
    /* the ends 20 um in, +- 0.2 m times the 1 mrad turn */
    assert_true(fabs(fmax(m.point[0].depth, m.point[1].depth) - 2.2e-4) < 2e-6);
    assert_true(fabs(fmin(m.point[0].depth, m.point[1].depth) + 1.8e-4) < 2e-6);
    assert_true(fabs(m.point[0].pos[1] - m.point[1].pos[1]) > 0.39); /* the face's width, 0.4 m */
}

/* A box's bottom edge lying on another box's top face and across its top
   edge, dipping 4 mm along its 0.6 m so that its end beyond the face is
   6 mm down: the separating axes' shallowest is the two edges' (2 mm, at
   the crossing), not the face's (6 mm, the end over the side). The edge
   touches the face along a line, from the crossing to its other end 2 mm
   above the face: the face's two points hold it, where the crossing point
   alone would leave it free to rock and the choice would flip from step
   to step as it rocked (a heap of 2000 boxes never slept). */
static void edge_on_a_face_across_its_edge_keeps_the_line(void **state)
{
    (void)state;
    const tb__geom a = box(0, 0, 0, ID, 0.5, 0.5, 0.5);
    const double h = 0.1, half = 0.3, dip = asin(0.004 / half), cross = 0.002;
    double roll[9], pitch[9], yaw[9], R[9], under[3], mid[3];
    tb__geom b;
    tb__manifold m;
    int k, inner;
    rot_axis(1, 0, 0, PI / 4, roll); /* its local edge (x, -h, -h) straight under its centre */
    rot_axis(0, 1, 0, dip, pitch);   /* its +x end down */
    rot_axis(0, 0, 1, PI / 6, yaw);  /* across a's edge at 30 degrees */
    rot_mul(pitch, roll, R);
    rot_mul(yaw, R, R);
    b = box(0, 0, 0, R, half, h, h);
    /* the edge's middle on a's top edge (y = 0.5), 2 mm into the face */
    mid[0] = 0, mid[1] = 0.5, mid[2] = 0.5 - cross;
    world(&b, (const double[3]){ 0, -h, -h }, under);
    for (k = 0; k < 3; ++k)
        b.pos[k] = mid[k] - under[k];
    assert_int_equal(tb__collide(&a, &b, 0.01, 5e-4, &m), 2);
    assert_true(m.normal[2] > 1 - 1e-12); /* a's top face */
    inner = m.point[0].pos[1] < m.point[1].pos[1] ? 0 : 1;
    /* the crossing, 2 mm in, and the end over the face, 2 mm above it */
    assert_true(fabs(m.point[1 - inner].depth - cross) < 1e-9 && fabs(m.point[1 - inner].pos[1] - 0.5) < 1e-9);
    assert_true(fabs(m.point[inner].depth + cross) < 1e-9);
    assert_true(fabs(m.point[inner].pos[1] - (0.5 - half * cos(dip) * sin(PI / 6))) < 1e-9);
}

/* ------------------------------------------------------------- random -- */

/* A random shape; on a grid, its position and sizes are multiples of 0.25
   and it is turned by a multiple of 45 degrees about a coordinate axis, so
   that faces and edges are parallel, centres coincide and features touch
   exactly. */
static tb__geom random_shape(int kind, int grid)
{
    double R[9];
    const int ax = (int)uniform(0, 3);
    if (grid)
        rot_axis(ax == 0, ax == 1, ax == 2, (int)uniform(0, 8) * PI / 4, R);
    else
        random_rot(R);
#define TB_PICK(lo, hi) (grid ? 0.25 * (int)uniform(4 * (lo), 4 * (hi) + 1) : uniform(lo, hi))
    const double x = TB_PICK(-1, 1), y = TB_PICK(-1, 1), z = TB_PICK(-1, 1);
    switch (kind) {
    case TB__SHAPE_SPHERE: return sphere(x, y, z, TB_PICK(0.25, 1));
    case TB__SHAPE_CAPSULE:
        return capsule(x, y, z, R, uniform(0, 1) < 0.1 ? 0 : TB_PICK(0.25, 1), TB_PICK(0.25, 0.75));
    case TB__SHAPE_BOX: return box(x, y, z, R, TB_PICK(0.25, 1), TB_PICK(0.25, 1), TB_PICK(0.25, 1));
    default: return plane(R[2], R[5], R[8], TB_PICK(-1, 1));
    }
#undef TB_PICK
}

/* The exact separation of a and b where it is cheap to find by brute force
   (NAN otherwise): the deepest point must report it. */
static double brute_separation(const tb__geom *a, const tb__geom *b)
{
    if (a->kind > b->kind) {
        const tb__geom *t = a;
        a = b, b = t;
    }
    const int round_a = a->kind == TB__SHAPE_SPHERE || (a->kind == TB__SHAPE_CAPSULE && a->half[2] == 0);
    const int round_b = b->kind == TB__SHAPE_SPHERE || (b->kind == TB__SHAPE_CAPSULE && b->half[2] == 0);
    if (round_a && round_b)
        return dist3(a->pos, b->pos) - a->radius - b->radius;
    if (round_a && b->kind == TB__SHAPE_CAPSULE)
        return core_distance(b, a->pos) - a->radius - b->radius;
    if (b->kind == TB__SHAPE_PLANE) {
        double s = HUGE_VAL, p[3];
        int i;
        if (round_a)
            return dot3(b->normal, a->pos) - b->offset - a->radius;
        for (i = 0; i < (a->kind == TB__SHAPE_BOX ? 8 : 2); ++i) {
            if (a->kind == TB__SHAPE_BOX) {
                const double l[3] = { i & 1 ? a->half[0] : -a->half[0], i & 2 ? a->half[1] : -a->half[1],
                                      i & 4 ? a->half[2] : -a->half[2] };
                world(a, l, p);
            } else {
                capsule_end(a, i ? 1 : -1, p);
            }
            s = fmin(s, dot3(b->normal, p) - b->offset - (a->kind == TB__SHAPE_BOX ? 0 : a->radius));
        }
        return s;
    }
    if (round_a && b->kind == TB__SHAPE_BOX) {
        double l[3], pen = HUGE_VAL;
        int i;
        const double d = box_distance(b, a->pos);
        if (d > 0)
            return d - a->radius;
        local(b, a->pos, l);
        for (i = 0; i < 3; ++i)
            pen = fmin(pen, b->half[i] - fabs(l[i]));
        return -pen - a->radius;
    }
    if (a->kind == TB__SHAPE_CAPSULE && (b->kind == TB__SHAPE_CAPSULE || b->kind == TB__SHAPE_BOX)) {
        const pair_ctx c = { a, b };
        const double d = convex_min(seg_to_other, &c);
        if (d > 1e-6) /* overlapping cores: a penetration, not a distance */
            return d - a->radius - (b->kind == TB__SHAPE_CAPSULE ? b->radius : 0);
    }
    return NAN;
}

/* A capsule without a core is a sphere. */
static int kind_of(const tb__geom *g)
{
    return g->kind == TB__SHAPE_CAPSULE && g->half[2] == 0 ? TB__SHAPE_SPHERE : (int)g->kind;
}

/* Every pair of kinds, in general position and on the grid. */
static void random_pairs_agree_with_brute_force(void **state)
{
    (void)state;
    seed(3);
    int ka, kb, trial, checked = 0, touching = 0;
    for (ka = 0; ka < TB__SHAPE_KINDS; ++ka)
        for (kb = 0; kb < TB__SHAPE_KINDS; ++kb)
            for (trial = 0; trial < 1000; ++trial) {
                const int grid = trial % 4 >= 2;
                const tb__geom a = random_shape(ka, grid), b = random_shape(kb, grid);
                const double margin = trial % 2 ? 0.1 : 0;
                tb__manifold m, s;
                int i;
                tb__collide(&a, &b, margin, 0, &m);
                assert_true(m.count >= 0 && m.count <= TB__MANIFOLD_POINTS);
                assert_true(finite_manifold(&m));
                if (ka == TB__SHAPE_PLANE && kb == TB__SHAPE_PLANE) {
                    assert_int_equal(m.count, 0);
                    continue;
                }
                if (m.count) {
                    ++touching;
                    assert_rel(norm3(m.normal), 1, 1e-12);
                }
                for (i = 0; i < m.count; ++i) {
                    const double *p = m.point[i].pos, d = m.point[i].depth;
                    assert_true(d > -margin);
                    /* Midway: within half the gap or depth of both shapes;
                       but the gap of a speculative edge-edge point is along
                       the normal, and its edges' closest points may be
                       further apart (the boxes' separating axis is only a
                       lower bound of their distance). */
                    const int boxes = ka == TB__SHAPE_BOX && kb == TB__SHAPE_BOX;
                    const double near = boxes && d < 0 && m.point[i].feature >= 0x20000u ? margin : 0.5 * fabs(d);
                    /* An incident corner within the clipping tolerance of
                       the reference face's side is kept (collide.c:
                       TB__CLIP_TOL). */
                    const double tol = boxes ? 1e-4 * 3 : 1e-9;
                    if (!(solid_distance(&a, p) <= near + tol && solid_distance(&b, p) <= near + tol))
                        fail_msg("kinds %d %d, point %d of %d (feature %#x): %.17g and %.17g from the shapes, "
                                 "depth %.17g", ka, kb, i, m.count, (unsigned)m.point[i].feature,
                                 solid_distance(&a, p), solid_distance(&b, p), d);
                }
                const double sep = brute_separation(&a, &b);
                if (!isnan(sep)) {
                    ++checked;
                    if (sep < margin - 1e-9) {
                        assert_true(m.count > 0);
                        /* The deepest point is the shapes' separation; none
                           claims them closer. Near-parallel capsules give two
                           points that are at most as deep. */
                        const double slack = m.count == 2 && ka == kb ? HUGE_VAL : 0;
                        const double low = -sep - 1e-9 - slack, d = deepest(&m);
                        if (!(d >= low && d <= -sep + 1e-9))
                            fail_msg("kinds %d %d: deepest %.17g, separation %.17g", ka, kb, d, sep);
                    } else if (sep > margin + 1e-9) {
                        assert_int_equal(m.count, 0);
                    }
                }
                /* Swapped: the normal flips; points and depths stay (the same
                   bits when the kinds differ: the pair is computed one way).
                   Two boxes may take the other's reference face, so only
                   single points of round shapes with apart cores are
                   compared. */
                tb__collide(&b, &a, margin, 0, &s);
                if (kind_of(&a) != kind_of(&b)) {
                    assert_int_equal(s.count, m.count);
                    assert_vec(s.normal, -m.normal[0], -m.normal[1], -m.normal[2], 0);
                    assert_memory_equal(s.point, m.point, sizeof m.point);
                } else if (m.count == 1 && kind_of(&a) != TB__SHAPE_BOX && sep + a.radius + b.radius > 1e-9) {
                    /* (Cores that touch share a fixed fallback axis.) */
                    assert_int_equal(s.count, 1);
                    assert_vec(s.normal, -m.normal[0], -m.normal[1], -m.normal[2], 1e-9);
                    assert_vec(s.point[0].pos, m.point[0].pos[0], m.point[0].pos[1], m.point[0].pos[2], 1e-9);
                    assert_rel(s.point[0].depth, m.point[0].depth, 1e-9);
                }
            }
    assert_true(checked > 5000);
    assert_true(touching > 4000);
}

static void random_overlapping_boxes_touch(void **state)
{
    (void)state;
    seed(4);
    int trial, k, overlapping = 0;
    for (trial = 0; trial < 3000; ++trial) {
        const tb__geom a = random_shape(TB__SHAPE_BOX, trial % 2), b = random_shape(TB__SHAPE_BOX, trial % 2);
        tb__manifold m;
        int inside = 0;
        /* A corner of one inside the other: certainly overlapping. */
        for (k = 0; k < 16 && !inside; ++k) {
            const tb__geom *g = k < 8 ? &a : &b, *o = k < 8 ? &b : &a;
            double p[3], l2[3];
            const double l[3] = { k & 1 ? g->half[0] : -g->half[0], k & 2 ? g->half[1] : -g->half[1],
                                  k & 4 ? g->half[2] : -g->half[2] };
            world(g, l, p);
            local(o, p, l2);
            inside = fabs(l2[0]) < o->half[0] - 1e-9 && fabs(l2[1]) < o->half[1] - 1e-9
                     && fabs(l2[2]) < o->half[2] - 1e-9;
        }
        tb__collide(&a, &b, 0, 0, &m);
        assert_true(finite_manifold(&m));
        if (inside) {
            ++overlapping;
            assert_true(m.count > 0);
            assert_true(deepest(&m) > 0);
        }
    }
    assert_true(overlapping > 500);
}

/* ------------------------------------------------------------- bounds -- */

static void bounds_contain_the_shape(void **state)
{
    (void)state;
    seed(5);
    int trial, k, i;
    for (trial = 0; trial < 300; ++trial) {
        const tb__geom g = random_shape(trial % 3, 0);
        double lo[3], hi[3], tlo[3] = { HUGE_VAL, HUGE_VAL, HUGE_VAL }, thi[3] = { -HUGE_VAL, -HUGE_VAL, -HUGE_VAL };
        tb__geom_bounds(&g, lo, hi);
        /* The extreme points: box corners, capsule ends pushed out by the
           radius along each world axis, sphere centre likewise. */
        for (k = 0; k < 8; ++k) {
            double p[3];
            if (g.kind == TB__SHAPE_BOX) {
                const double l[3] = { k & 1 ? g.half[0] : -g.half[0], k & 2 ? g.half[1] : -g.half[1],
                                      k & 4 ? g.half[2] : -g.half[2] };
                world(&g, l, p);
            } else {
                capsule_end(&g, k & 1 ? 1 : -1, p);
            }
            for (i = 0; i < 3; ++i) {
                tlo[i] = fmin(tlo[i], p[i] - g.radius);
                thi[i] = fmax(thi[i], p[i] + g.radius);
            }
        }
        for (i = 0; i < 3; ++i) {
            assert_true(lo[i] <= tlo[i] + 1e-12 && hi[i] >= thi[i] - 1e-12);
            assert_true(lo[i] >= tlo[i] - 1e-12 && hi[i] <= thi[i] + 1e-12); /* tight */
        }
    }
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(sphere_sphere_exact),
    cmocka_unit_test(coincident_centres_give_a_fixed_axis),
    cmocka_unit_test(sphere_rests_on_plane),
    cmocka_unit_test(margin_gives_speculative_points),
    cmocka_unit_test(sphere_against_capsule),
    cmocka_unit_test(sphere_against_box),
    cmocka_unit_test(sphere_inside_box_leaves_by_nearest_face),
    cmocka_unit_test(capsule_lying_on_plane_gives_two_points),
    cmocka_unit_test(capsules_parallel_give_two_points),
    cmocka_unit_test(capsules_crossed_give_one_point),
    cmocka_unit_test(degenerate_capsule_is_a_sphere),
    cmocka_unit_test(capsule_against_box),
    cmocka_unit_test(box_lying_on_plane_gives_four_corners),
    cmocka_unit_test(buried_plank_keeps_both_ends),
    cmocka_unit_test(box_on_box_face_contact),
    cmocka_unit_test(box_on_box_turned_45_degrees),
    cmocka_unit_test(boxes_crossing_edge_to_edge),
    cmocka_unit_test(random_box_on_box_matches_corners),
    cmocka_unit_test(flush_stack_keeps_four_corners),
    cmocka_unit_test(touching_boxes_give_the_patch_or_nothing),
    cmocka_unit_test(plane_against_plane_is_empty),
    cmocka_unit_test(swapping_flips_the_normal_only),
    cmocka_unit_test(small_moves_keep_the_features),
    cmocka_unit_test(edge_along_a_face_is_a_line_of_points),
    cmocka_unit_test(edge_on_a_face_across_its_edge_keeps_the_line),
    cmocka_unit_test(random_pairs_agree_with_brute_force),
    cmocka_unit_test(random_overlapping_boxes_touch),
    cmocka_unit_test(bounds_contain_the_shape),
};

TB_TEST_MAIN(tests)
