/* collide.c: narrowphase (see collision.h for the contract).

   Each pair is computed once, with the kinds in the order sphere, capsule,
   box, plane (a pair given the other way round is computed swapped and its
   normal flipped), and a capsule with a zero-length core is a sphere.

   Round shapes (spheres, capsule cores) meet at their closest core points.
   Boxes use the separating axis test; a face axis is then turned into a
   patch of points by clipping, the way Box2D and ODE do it: the incident
   face of one box against the side planes of the other's reference face,
   or a capsule's core against the side planes of a box face.

   Feature ids: 0 is a lone closest-point contact, whose position moves
   continuously with the shapes; every point of a patch names the features
   that made it, tagged by pair:
     0x10  | end                                   capsule end on a plane
     0x20  | overlap end (bit 1) from b (bit 0)    parallel capsules
     0x40  | corner                                box corner on a plane
     0x100 | face << 4 | end                       capsule core on a box face
                   (end: 0, 1 the core's own ends, 2 + j cut by side plane j)
     0x10000 | ref_is_b << 15 | ref face << 12 | incident face << 9
             | polygon edge in << 3 | edge out     box face on box face
     0x20000 | axis a << 6 | sides a << 4 | axis b << 2 | sides b
                                                   box edge on box edge
   where a face is 2 axis + (1 if on the negative side). */
#include "collision/collision.h"

#include <math.h>
#include <string.h>

/* Segments closer to parallel than this sine give two capsule points. */
#define TB__PARALLEL 0.02
/* A capsule core whose closest direction to a box is within this cosine of
   a face's normal (1.1 degrees) lies on the face: two points, the core
   clipped to the face (reaching out to the closest point if that is just
   beyond the face's edge), rather than one that would come and go with
   rounding as a capsule rests across the edge. */
#define TB__FLAT 0.9998
/* Clipping to a face keeps what lies less than this times the box's size
   (the sum of its half extents) outside the face's sides: 0.1 mm on a 1 m
   box; see clip. */
#define TB__CLIP_TOL 1e-4
/* Edge axes of a smaller cross product than this are skipped by the SAT:
   they duplicate a face axis and normalising them amplifies rounding. */
#define TB__EDGE_MIN 1e-6

/* ------------------------------------------------------------ vectors -- */

static double dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static double len(const double a[3]) { return sqrt(dot(a, a)); }

static void sub(const double a[3], const double b[3], double out[3])
{
    out[0] = a[0] - b[0];
    out[1] = a[1] - b[1];
    out[2] = a[2] - b[2];
}

/* out = a + s b; out may be a or b. */
static void madd(const double a[3], double s, const double b[3], double out[3])
{
    out[0] = a[0] + s * b[0];
    out[1] = a[1] + s * b[1];
    out[2] = a[2] + s * b[2];
}

static void scale(const double a[3], double s, double out[3])
{
    out[0] = s * a[0];
    out[1] = s * a[1];
    out[2] = s * a[2];
}

static void cross(const double a[3], const double b[3], double out[3])
{
    const double c[3] = { a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0] };
    memcpy(out, c, sizeof c);
}

static void mid(const double a[3], const double b[3], double out[3])
{
    out[0] = 0.5 * (a[0] + b[0]);
    out[1] = 0.5 * (a[1] + b[1]);
    out[2] = 0.5 * (a[2] + b[2]);
}

static double clampd(double x, double lo, double hi) { return x < lo ? lo : x > hi ? hi : x; }
static double sign_of(double x) { return x < 0 ? -1.0 : 1.0; }

/* The separating axis tests keep a face axis unless another axis is clearly
   better: by more than the tolerance (a length), a share of the depth and
   a share of the size. So rounding noise in a resting stack does not flip
   the reference face (and the features with it) from step to step
   (test_collide.small_moves_keep_the_features), and an edge lying along a
   face within the tolerance meets it as a face, the points at both ends
   of the line, not as one edge point that jumps from end to end as the
   bodies rock (test_collide.edge_along_a_face_is_a_line_of_points). */
static int clearly_better(double sep, double than, double size, double tolerance)
{
    return sep > than + 0.05 * fabs(than) + 1e-5 * size + tolerance;
}

/* Column j of a row-major rotation: the shape's axis j in the world. */
static void axis(const double rot[9], int j, double out[3])
{
    out[0] = rot[j];
    out[1] = rot[3 + j];
    out[2] = rot[6 + j];
}

/* R^T (p - pos) when `point`, else R^T p. */
static void to_local(const tb__geom *g, const double p[3], int point, double out[3])
{
    const double *R = g->rot;
    double d[3];
    if (point)
        sub(p, g->pos, d);
    else
        memcpy(d, p, sizeof d);
    out[0] = R[0] * d[0] + R[3] * d[1] + R[6] * d[2];
    out[1] = R[1] * d[0] + R[4] * d[1] + R[7] * d[2];
    out[2] = R[2] * d[0] + R[5] * d[1] + R[8] * d[2];
}

/* R v, plus the shape's position when `point`. */
static void to_world(const tb__geom *g, const double v[3], int point, double out[3])
{
    const double *R = g->rot;
    const double w[3] = { R[0] * v[0] + R[1] * v[1] + R[2] * v[2], R[3] * v[0] + R[4] * v[1] + R[5] * v[2],
                          R[6] * v[0] + R[7] * v[1] + R[8] * v[2] };
    if (point)
        madd(w, 1, g->pos, out);
    else
        memcpy(out, w, sizeof w);
}

/* A unit vector perpendicular to unit u, always the same for the same u:
   the fallback normal when two cores coincide. */
static void any_perp(const double u[3], double out[3])
{
    const double x[3] = { 1, 0, 0 }, y[3] = { 0, 1, 0 };
    cross(u, fabs(u[0]) < 0.6 ? x : y, out);
    scale(out, 1 / len(out), out);
}

/* The core segment of a capsule: p0 and d = p1 - p0. */
static void segment(const tb__geom *g, double p0[3], double d[3])
{
    double u[3];
    axis(g->rot, 2, u);
    madd(g->pos, -g->half[2], u, p0);
    scale(u, 2 * g->half[2], d);
}

/* The point of segment p + t d (t in [0, 1], |d| > 0) closest to x. */
static void closest_on_segment(const double p[3], const double d[3], const double x[3], double out[3])
{
    double r[3];
    sub(x, p, r);
    madd(p, clampd(dot(r, d) / dot(d, d), 0, 1), d, out);
}

/* Parameters s, t in [0, 1] of the closest points of the segments p + s d
   and q + t e (Ericson, Real-Time Collision Detection 5.1.9); a zero
   length or parallel segments give one of the closest pairs, never NaN. */
static void closest_segments(const double p[3], const double d[3], const double q[3], const double e[3],
                             double *s, double *t)
{
    double r[3];
    sub(p, q, r);
    const double a = dot(d, d), b = dot(d, e), c = dot(d, r), ee = dot(e, e), f = dot(e, r);
    if (a <= 0 && ee <= 0) {
        *s = *t = 0;
    } else if (a <= 0) {
        *s = 0;
        *t = clampd(f / ee, 0, 1);
    } else if (ee <= 0) {
        *t = 0;
        *s = clampd(-c / a, 0, 1);
    } else {
        const double denom = a * ee - b * b;
        *s = denom > 0 ? clampd((b * f - c * ee) / denom, 0, 1) : 0;
        *t = (b * *s + f) / ee;
        if (*t < 0) {
            *t = 0;
            *s = clampd(-c / a, 0, 1);
        } else if (*t > 1) {
            *t = 1;
            *s = clampd((b - c) / a, 0, 1);
        }
    }
}

/* ---------------------------------------------------------- manifolds -- */

static void add_point(tb__manifold *m, double margin, const double pos[3], double sep, uint32_t feature)
{
    if (!(sep < margin) || m->count == TB__MANIFOLD_POINTS)
        return;
    tb__contact_point *c = &m->point[m->count++];
    memcpy(c->pos, pos, sizeof c->pos);
    c->depth = -sep;
    c->feature = feature;
}

/* Two round cores: point p with radius ra, point q with radius rb. Gives
   the normal from p to q (`fallback` when they coincide), the separation of
   the surfaces and the point midway between them. */
static void round_pair(const double p[3], double ra, const double q[3], double rb, const double fallback[3],
                       double n[3], double *sep, double pos[3])
{
    double d[3], sa[3], sb[3];
    sub(q, p, d);
    const double dist = len(d);
    if (dist > 1e-12 * (ra + rb) && dist > 0)
        scale(d, 1 / dist, n);
    else
        memcpy(n, fallback, 3 * sizeof *n);
    *sep = dot(d, n) - ra - rb;
    madd(p, ra, n, sa);
    madd(q, -rb, n, sb);
    mid(sa, sb, pos);
}

typedef struct tb__candidate {
    double pos[3], sep;
    uint32_t feature;
} tb__candidate;

/* Keeps at most 4 of n candidates, all within margin: the deepest, the
   farthest from it, the farthest from the line of those two, then the one
   that most enlarges their triangle; this keeps both the depth and the
   area of support. Ties go to the earlier candidate, so the choice is
   deterministic. */
static void reduce(const tb__candidate *c, int n, const double normal[3], double margin, tb__manifold *m)
{
    int i, k, pick[4] = { 0, 0, 0, 0 }, count = 0;
    if (n <= TB__MANIFOLD_POINTS) {
        for (i = 0; i < n; ++i)
            add_point(m, margin, c[i].pos, c[i].sep, c[i].feature);
        return;
    }
    for (i = 1; i < n; ++i)
        if (c[i].sep < c[pick[0]].sep)
            pick[0] = i;
    count = 1;
    double best = 0, d[3], e[3], x[3];
    for (i = 0; i < n; ++i) {
        sub(c[i].pos, c[pick[0]].pos, d);
        if (dot(d, d) > best)
            best = dot(d, d), pick[1] = i;
    }
    if (best > 0) {
        const double tiny = 1e-12 * best;
        count = 2;
        best = 0;
        sub(c[pick[1]].pos, c[pick[0]].pos, d);
        for (i = 0; i < n; ++i) {
            sub(c[i].pos, c[pick[0]].pos, e);
            cross(d, e, x);
            if (fabs(dot(x, normal)) > fabs(best))
                best = dot(x, normal), pick[2] = i;
        }
        if (fabs(best) > tiny) {
            /* Triangle t0 t1 t2 counter-clockwise about the normal. */
            const int t[3] = { best > 0 ? pick[0] : pick[1], best > 0 ? pick[1] : pick[0], pick[2] };
            count = 3;
            best = tiny;
            for (i = 0; i < n; ++i)
                for (k = 0; k < 3; ++k) {
                    sub(c[t[(k + 1) % 3]].pos, c[t[k]].pos, d);
                    sub(c[i].pos, c[t[k]].pos, e);
                    cross(d, e, x);
                    if (-dot(x, normal) > best)
                        best = -dot(x, normal), pick[3] = i, count = 4;
                }
        }
    }
    for (i = 0; i < count; ++i)
        add_point(m, margin, c[pick[i]].pos, c[pick[i]].sep, c[pick[i]].feature);
}

/* ------------------------------------------------------- round shapes -- */

static void sphere_sphere(const tb__geom *a, const tb__geom *b, double margin, double tolerance, tb__manifold *m)
{
    (void)tolerance;
    static const double up[3] = { 0, 0, 1 };
    double pos[3], sep;
    round_pair(a->pos, a->radius, b->pos, b->radius, up, m->normal, &sep, pos);
    add_point(m, margin, pos, sep, 0);
}

static void sphere_capsule(const tb__geom *a, const tb__geom *b, double margin, double tolerance, tb__manifold *m)
{
    (void)tolerance;
    double p0[3], d[3], q[3], r[3], perp[3], pos[3], sep;
    segment(b, p0, d);
    closest_on_segment(p0, d, a->pos, q);
    axis(b->rot, 2, r);
    any_perp(r, perp);
    round_pair(a->pos, a->radius, q, b->radius, perp, m->normal, &sep, pos);
    add_point(m, margin, pos, sep, 0);
}

static void capsule_capsule(const tb__geom *a, const tb__geom *b, double margin, double tolerance, tb__manifold *m)
{
    (void)tolerance;
    double pa[3], da[3], pb[3], db[3], ua[3], ub[3], c[3], ab[3], p[3], q[3], pos[3], sep, s, t;
    segment(a, pa, da);
    segment(b, pb, db);
    axis(a->rot, 2, ua);
    axis(b->rot, 2, ub);
    sub(b->pos, a->pos, ab);
    closest_segments(pa, da, pb, db, &s, &t);
    madd(pa, s, da, p);
    madd(pb, t, db, q);
    /* Crossing cores: the normal of both segments, turned towards b. */
    cross(ua, ub, c);
    const double sine = len(c);
    if (sine > TB__EDGE_MIN)
        scale(c, 1 / sine, c);
    else
        any_perp(ua, c);
    scale(c, sign_of(dot(c, ab)), c);
    round_pair(p, a->radius, q, b->radius, c, m->normal, &sep, pos);
    if (!(sep < margin))
        return;
    if (sine < TB__PARALLEL) {
        /* Near parallel: a point at each end of the stretch of a's core that
           b's core overlaps, so that one capsule lying on another rests. */
        const double ha = a->half[2], hb = b->half[2];
        const double c0 = dot(ab, ua) - hb * fabs(dot(ua, ub)), c1 = dot(ab, ua) + hb * fabs(dot(ua, ub));
        const double end[2] = { c0 > -ha ? c0 : -ha, c1 < ha ? c1 : ha };
        const int from_b[2] = { c0 > -ha, c1 < ha };
        int k;
        if (end[1] - end[0] > 1e-3 * (ha + hb)) {
            for (k = 0; k < 2; ++k) {
                double pk[3], qk[3], nk[3], posk[3], sepk;
                madd(a->pos, end[k], ua, pk);
                closest_on_segment(pb, db, pk, qk);
                round_pair(pk, a->radius, qk, b->radius, m->normal, nk, &sepk, posk);
                add_point(m, margin, posk, sepk, 0x20u | (uint32_t)(k << 1 | from_b[k]));
            }
            if (m->count)
                return;
        }
    }
    add_point(m, margin, pos, sep, 0);
}

/* --------------------------------------------------------- planes -- */

/* A core point p of radius r against plane b; the normal is -b->normal. */
static void point_plane(const double p[3], double r, const tb__geom *b, double margin, uint32_t feature,
                        tb__manifold *m)
{
    const double dist = dot(b->normal, p) - b->offset;
    double pos[3];
    madd(p, -0.5 * (r + dist), b->normal, pos);
    add_point(m, margin, pos, dist - r, feature);
}

static void round_plane(const tb__geom *a, const tb__geom *b, double margin, double tolerance, tb__manifold *m)
{
    (void)tolerance;
    scale(b->normal, -1, m->normal);
    if (a->kind == TB__SHAPE_SPHERE) {
        point_plane(a->pos, a->radius, b, margin, 0, m);
    } else {
        double p0[3], d[3], p1[3];
        segment(a, p0, d);
        madd(p0, 1, d, p1);
        point_plane(p0, a->radius, b, margin, 0x10, m);
        point_plane(p1, a->radius, b, margin, 0x11, m);
    }
}

static void box_corner(const tb__geom *g, int i, double out[3])
{
    const double l[3] = { i & 1 ? g->half[0] : -g->half[0], i & 2 ? g->half[1] : -g->half[1],
                          i & 4 ? g->half[2] : -g->half[2] };
    to_world(g, l, 1, out);
}

/* The corners of the face most against the plane that are within the
   margin, deepest first. That face holds the deepest corner and spans the
   box's widest support: a box lying flat keeps its bottom face even when
   it is thinner than the margin, and a long thin box buried in the plane
   (every corner below it) keeps both its ends. The 4 deepest of all 8
   corners can be one end of such a box, top and bottom, and a push there
   only turns it (test_collide.buried_plank_keeps_both_ends). */
static void box_plane(const tb__geom *a, const tb__geom *b, double margin, double tolerance, tb__manifold *m)
{
    (void)tolerance;
    tb__candidate c[4];
    double along[3];
    int i, j, k = 0, n = 0, side;
    scale(b->normal, -1, m->normal);
    for (i = 0; i < 3; ++i) {
        double ax[3];
        axis(a->rot, i, ax);
        along[i] = dot(b->normal, ax);
        if (fabs(along[i]) > fabs(along[k]))
            k = i;
    }
    side = along[k] < 0 ? 1 << k : 0; /* corner bit k set: the + face */
    for (i = 0; i < 8; ++i) {
        double p[3];
        if ((i & (1 << k)) != side)
            continue;
        box_corner(a, i, p);
        const double sep = dot(b->normal, p) - b->offset;
        if (!(sep < margin))
            continue;
        for (j = n++; j > 0 && c[j - 1].sep > sep; --j)
            c[j] = c[j - 1];
        madd(p, -0.5 * sep, b->normal, c[j].pos);
        c[j].sep = sep;
        c[j].feature = 0x40u | (uint32_t)i;
    }
    for (i = 0; i < n; ++i)
        add_point(m, margin, c[i].pos, c[i].sep, c[i].feature);
}

/* ---------------------------------------------------- round and box -- */

/* Sphere centre outside the box: to its closest point; inside: out through
   the face it is least deep behind. */
static void sphere_box(const tb__geom *a, const tb__geom *b, double margin, double tolerance, tb__manifold *m)
{
    (void)tolerance;
    const double *h = b->half;
    double l[3], q[3], d[3], n[3], sa[3], pos[3], sep;
    int i, k = 0;
    to_local(b, a->pos, 1, l);
    for (i = 0; i < 3; ++i)
        q[i] = clampd(l[i], -h[i], h[i]);
    sub(q, l, d);
    const double dist = len(d);
    if (dist > 1e-12 * (h[0] + h[1] + h[2] + a->radius) && dist > 0) {
        scale(d, 1 / dist, n);
        sep = dist - a->radius;
    } else {
        for (i = 1; i < 3; ++i)
            if (h[i] - fabs(l[i]) < h[k] - fabs(l[k]))
                k = i;
        memset(n, 0, sizeof n);
        n[k] = -sign_of(l[k]);
        memcpy(q, l, sizeof q);
        q[k] = -n[k] * h[k];
        sep = -(h[k] - fabs(l[k])) - a->radius;
    }
    madd(l, a->radius, n, sa);
    mid(sa, q, pos);
    to_world(b, pos, 1, pos);
    to_world(b, n, 0, m->normal);
    add_point(m, margin, pos, sep, 0);
}

/* Clips a capsule's core (box frame: p0 + t d, t in [0, 1]) to the side
   planes of box face (k, side), keeping an end less than TB__CLIP_TOL out
   as box_face keeps a corner, and adds a point for each end of what is
   left. An end short of t_near, the core's closest point to the box just
   beyond the face's edge (-1: none), is moved to it, so that the deepest
   point is exact. Returns the number of points added. */
static int capsule_face(const double p0[3], const double d[3], double r, const tb__geom *b, int k, double side,
                        double t_near, double margin, tb__manifold *m)
{
    const double *h = b->half, tol = TB__CLIP_TOL * (h[0] + h[1] + h[2]);
    double t[2] = { 0, 1 };
    uint32_t code[2] = { 0, 1 };
    int i, j, e, count = m->count;
    for (j = 0; j < 4; ++j) {
        /* Side plane j: s x_i <= h_i, i.e. s d_i t <= h_i - s p0_i; the end
           of the core that goes furthest out is cut if it is beyond tol. */
        i = (k + 1 + j / 2) % 3;
        const double s = j & 1 ? -1.0 : 1.0, slope = s * d[i], room = h[i] - s * p0[i];
        const int end = slope > 0;
        if (slope * end - room <= tol)
            continue;
        if (slope == 0)
            return 0;
        if (end ? room / slope < t[1] : room / slope > t[0])
            t[end] = room / slope, code[end] = 2u + (uint32_t)j;
    }
    if (t[0] > t[1])
        return 0;
    if (t_near >= 0)
        t[0] = t_near < t[0] ? t_near : t[0], t[1] = t_near > t[1] ? t_near : t[1];
    for (e = 0; e < (t[1] - t[0] > 1e-9 ? 2 : 1); ++e) {
        /* From q, the closest point of the face's plane within the face,
           to the core; negative when the core is behind the face. */
        double p[3], q[3], diff[3], n[3], pos[3];
        madd(p0, t[e], d, p);
        for (i = 0; i < 3; ++i)
            q[i] = i == k ? side * h[k] : clampd(p[i], -h[i], h[i]);
        sub(p, q, diff);
        const double dist = sign_of(side * diff[k]) * len(diff);
        if (dist != 0)
            scale(diff, 1 / dist, n);
        else
            n[0] = n[1] = n[2] = 0, n[k] = side;
        madd(p, -r, n, p);
        mid(p, q, pos);
        to_world(b, pos, 1, pos);
        add_point(m, margin, pos, dist - r, 0x100u | (uint32_t)(2 * k + (side < 0)) << 4 | code[e]);
    }
    return m->count - count;
}

/* The closest points p of segment p0 + t d (t in [0, 1]) and q of the box
   |x_i| <= h_i; returns p's t. The squared distance is convex in t, and
   quadratic between the crossings of the slab planes: each piece is
   minimised in closed form. */
static double closest_segment_box(const double p0[3], const double d[3], const double h[3], double p[3],
                                  double q[3])
{
    double ts[8] = { 0, 1 }, best = HUGE_VAL, bt = 0, diff[3];
    int i, j, k, nt = 2;
    for (i = 0; i < 3; ++i)
        for (j = -1; j <= 1 && d[i] != 0; j += 2) {
            const double t = (j * h[i] - p0[i]) / d[i];
            if (t > 0 && t < 1) {
                for (k = nt++; k > 0 && ts[k - 1] > t; --k)
                    ts[k] = ts[k - 1];
                ts[k] = t;
            }
        }
    for (k = 0; k + 1 < nt; ++k) {
        double A = 0, B = 0, t = ts[k];
        for (i = 0; i < 3; ++i) {
            const double x = p0[i] + 0.5 * (ts[k] + ts[k + 1]) * d[i];
            if (fabs(x) > h[i])
                A += d[i] * d[i], B += d[i] * (p0[i] - sign_of(x) * h[i]);
        }
        if (A > 0)
            t = clampd(-B / A, ts[k], ts[k + 1]);
        madd(p0, t, d, p);
        for (i = 0; i < 3; ++i)
            q[i] = clampd(p[i], -h[i], h[i]);
        sub(q, p, diff);
        if (dot(diff, diff) < best)
            best = dot(diff, diff), bt = t;
    }
    madd(p0, bt, d, p);
    for (i = 0; i < 3; ++i)
        q[i] = clampd(p[i], -h[i], h[i]);
    return bt;
}

/* A capsule's core (box frame: p0 + t d) that enters box b: the separating
   axes of a segment and a box, the box's face normals and the core's
   direction crossed with the box's edges (the facet normals of their
   Minkowski sum, so the least penetration is exact). A face gives the core
   clipped to it; an edge, one point between the core and the edge. */
static void capsule_in_box(const double p0[3], const double d[3], double r, const tb__geom *b, double margin,
                           double tolerance, tb__manifold *m)
{
    const double *h = b->half;
    double c[3], u[3], L[3], n[3], p[3], q[3], diff[3], pos[3];
    double face_sep = -HUGE_VAL, edge_sep = -HUGE_VAL, edge_n[3] = { 0, 0, 0 };
    int i, face = 0, edge = -1;
    const double hl = 0.5 * len(d);
    madd(p0, 0.5, d, c);
    scale(d, hl > 0 ? 0.5 / hl : 0, u);
    for (i = 0; i < 3; ++i) {
        const double s = fabs(c[i]) - h[i] - hl * fabs(u[i]);
        if (s > face_sep)
            face_sep = s, face = i;
        const double e[3] = { i == 0, i == 1, i == 2 };
        cross(u, e, L);
        if (len(L) < TB__EDGE_MIN)
            continue;
        scale(L, 1 / len(L), L);
        const double se = fabs(dot(c, L)) - h[0] * fabs(L[0]) - h[1] * fabs(L[1]) - h[2] * fabs(L[2]);
        if (se > edge_sep)
            edge_sep = se, edge = i, scale(L, -sign_of(dot(c, L)), edge_n);
    }
    if (edge < 0 || !clearly_better(edge_sep, face_sep, h[0] + h[1] + h[2] + hl, tolerance)) {
        memset(n, 0, sizeof n);
        n[face] = -sign_of(c[face]);
        to_world(b, n, 0, m->normal);
        capsule_face(p0, d, r, b, face, sign_of(c[face]), -1, margin, m);
        return;
    }
    /* The box's edge along axis `edge` furthest towards the core. */
    double e0[3], de[3] = { 0, 0, 0 }, s, t;
    for (i = 0; i < 3; ++i)
        e0[i] = i == edge ? -h[i] : -sign_of(edge_n[i]) * h[i];
    de[edge] = 2 * h[edge];
    closest_segments(p0, d, e0, de, &s, &t);
    madd(p0, s, d, p);
    madd(e0, t, de, q);
    sub(q, p, diff);
    madd(p, r, edge_n, p);
    mid(p, q, pos);
    to_world(b, pos, 1, pos);
    to_world(b, edge_n, 0, m->normal);
    add_point(m, margin, pos, dot(diff, edge_n) - r, 0);
}

/* Capsule core clear of the box: its exact closest points, or two points
   when it lies over a face; core inside: capsule_in_box. */
static void capsule_box(const tb__geom *a, const tb__geom *b, double margin, double tolerance, tb__manifold *m)
{
    const double *h = b->half, r = a->radius;
    double p0[3], d[3], p[3], q[3], diff[3], n[3], pos[3];
    int k;
    segment(a, p0, d);
    to_local(b, p0, 1, p0);
    to_local(b, d, 0, d);
    const double t = closest_segment_box(p0, d, h, p, q);
    sub(q, p, diff);
    const double dist = len(diff);
    if (dist > 1e-9 * (h[0] + h[1] + h[2] + len(d) + r)) {
        if (dist - r >= margin)
            return;
        scale(diff, 1 / dist, n);
        k = fabs(n[0]) >= fabs(n[1]) && fabs(n[0]) >= fabs(n[2]) ? 0 : fabs(n[1]) >= fabs(n[2]) ? 1 : 2;
        if (fabs(n[k]) >= TB__FLAT && capsule_face(p0, d, r, b, k, -sign_of(n[k]), t, margin, m)) {
            memset(n, 0, sizeof n);
            n[k] = sign_of(diff[k]);
        } else {
            madd(p, r, n, p);
            mid(p, q, pos);
            to_world(b, pos, 1, pos);
            add_point(m, margin, pos, dist - r, 0);
        }
        to_world(b, n, 0, m->normal);
        return;
    }
    capsule_in_box(p0, d, r, b, margin, tolerance, m);
}

/* ------------------------------------------------------- box and box -- */

typedef struct tb__box {
    const double *c, *h;
    double ax[3][3];
} tb__box;

static void box_of(const tb__geom *g, tb__box *b)
{
    int i;
    b->c = g->pos;
    b->h = g->half;
    for (i = 0; i < 3; ++i)
        axis(g->rot, i, b->ax[i]);
}

/* Half the width of box b along unit L. */
static double box_radius(const tb__box *b, const double L[3])
{
    return b->h[0] * fabs(dot(b->ax[0], L)) + b->h[1] * fabs(dot(b->ax[1], L)) + b->h[2] * fabs(dot(b->ax[2], L));
}

/* A vertex of the clipped polygon, named by the polygon edges that meet
   there: incident face edges 0-3, reference side planes 4-7. */
typedef struct tb__vertex {
    double p[3];
    int in, out;
} tb__vertex;

#define TB__CLIP_MAX 16

/* Sutherland-Hodgman: the part of polygon v (n vertices) with
   dot(pn, x) <= off; plane `id` names the new edge. A vertex less than tol
   outside is kept as it is: identical boxes stacked flush then keep their
   4 corners (and features) under rounding and jitter, instead of trading
   each corner for a cluster of nearby intersections
   (test_collide.flush_stack_keeps_four_corners). */
static int clip(const tb__vertex *v, int n, const double pn[3], double off, double tol, int id, tb__vertex *out)
{
    int i, count = 0;
    for (i = 0; i < n; ++i) {
        const tb__vertex *a = &v[(i + n - 1) % n], *b = &v[i];
        const double da = dot(pn, a->p) - off, db = dot(pn, b->p) - off;
        const int in_a = da <= tol, in_b = db <= tol;
        if (in_a != in_b && (in_a ? da : db) < 0 && count < TB__CLIP_MAX) {
            tb__vertex *x = &out[count++];
            double ab[3];
            sub(b->p, a->p, ab);
            madd(a->p, da / (da - db), ab, x->p);
            x->in = in_a ? a->out : id;
            x->out = in_a ? id : a->out;
        }
        if (in_b && count < TB__CLIP_MAX)
            out[count++] = *b;
    }
    return count;
}

/* Face `k` of ref (the side facing inc) as the reference face: inc's face
   most against it, clipped to its side planes; points on inc's face. */
static void box_face(const tb__box *ref, const tb__box *inc, int k, int ref_is_b, double margin, tb__manifold *m)
{
    tb__vertex poly[2][TB__CLIP_MAX];
    tb__candidate c[TB__CLIP_MAX];
    double d[3], n[3], fc[3];
    int i, j, f = 0, count = 4, cur = 0;
    sub(inc->c, ref->c, d);
    const double side = sign_of(dot(d, ref->ax[k]));
    scale(ref->ax[k], side, n);
    for (i = 1; i < 3; ++i)
        if (fabs(dot(n, inc->ax[i])) > fabs(dot(n, inc->ax[f])))
            f = i;
    const double fside = -sign_of(dot(n, inc->ax[f]));
    const int u = (f + 1) % 3, v = (f + 2) % 3;
    madd(inc->c, fside * inc->h[f], inc->ax[f], fc);
    for (i = 0; i < 4; ++i) {
        /* Counter-clockwise corners (+,+) (-,+) (-,-) (+,-); edge i runs
           from corner i to corner i + 1. */
        madd(fc, (i == 0 || i == 3 ? 1 : -1) * inc->h[u], inc->ax[u], poly[0][i].p);
        madd(poly[0][i].p, (i < 2 ? 1 : -1) * inc->h[v], inc->ax[v], poly[0][i].p);
        poly[0][i].in = (i + 3) % 4;
        poly[0][i].out = i;
    }
    const double tol = TB__CLIP_TOL * (ref->h[0] + ref->h[1] + ref->h[2]);
    for (j = 0; j < 4 && count; ++j) {
        const int t = (k + 1 + j / 2) % 3;
        const double s = j & 1 ? -1.0 : 1.0, pn[3] = { s * ref->ax[t][0], s * ref->ax[t][1], s * ref->ax[t][2] };
        count = clip(poly[cur], count, pn, dot(pn, ref->c) + ref->h[t], tol, 4 + j, poly[1 - cur]);
        cur = 1 - cur;
    }
    const double face = dot(n, ref->c) + ref->h[k];
    const uint32_t tag = 0x10000u | (uint32_t)ref_is_b << 15 | (uint32_t)(2 * k + (side < 0)) << 12
                         | (uint32_t)(2 * f + (fside < 0)) << 9;
    for (i = j = 0; i < count; ++i) {
        const double sep = dot(n, poly[cur][i].p) - face;
        if (!(sep < margin))
            continue;
        madd(poly[cur][i].p, -0.5 * sep, n, c[j].pos);
        c[j].sep = sep;
        c[j].feature = tag | (uint32_t)(poly[cur][i].in << 3 | poly[cur][i].out);
        ++j;
    }
    scale(n, ref_is_b ? -1.0 : 1.0, m->normal);
    reduce(c, j, m->normal, margin, m);
}

/* Edge i of a against edge j of b, along unit L (from a to b): one point
   midway between the edges' closest points (none if crossing_only and
   either closest point is an end of its edge). */
static void box_edge(const tb__box *a, const tb__box *b, int i, int j, const double L[3], int crossing_only,
                     double margin, tb__manifold *m)
{
    double pa[3], pb[3], da[3], db[3], qa[3], qb[3], pos[3], s, t;
    uint32_t sides_a = 0, sides_b = 0;
    int k;
    memcpy(pa, a->c, sizeof pa);
    memcpy(pb, b->c, sizeof pb);
    for (k = 1; k < 3; ++k) {
        const int ka = (i + k) % 3, kb = (j + k) % 3;
        const double sa = sign_of(dot(a->ax[ka], L)), sb = -sign_of(dot(b->ax[kb], L));
        madd(pa, sa * a->h[ka], a->ax[ka], pa);
        madd(pb, sb * b->h[kb], b->ax[kb], pb);
        sides_a |= (uint32_t)(sa > 0) << (k - 1);
        sides_b |= (uint32_t)(sb > 0) << (k - 1);
    }
    madd(pa, -a->h[i], a->ax[i], pa);
    madd(pb, -b->h[j], b->ax[j], pb);
    scale(a->ax[i], 2 * a->h[i], da);
    scale(b->ax[j], 2 * b->h[j], db);
    closest_segments(pa, da, pb, db, &s, &t);
    if (crossing_only && !(s > 0 && s < 1 && t > 0 && t < 1))
        return;
    madd(pa, s, da, qa);
    madd(pb, t, db, qb);
    mid(qa, qb, pos);
    sub(qb, qa, db);
    memcpy(m->normal, L, sizeof m->normal);
    add_point(m, margin, pos, dot(db, L),
              0x20000u | (uint32_t)i << 6 | sides_a << 4 | (uint32_t)j << 2 | sides_b);
}

/* Separating axes: 3 face normals of each box and the 9 cross products of
   their edges; a face of a is kept unless a face of b or an edge pair is
   clearly better. */
static void box_box(const tb__geom *ga, const tb__geom *gb, double margin, double tolerance, tb__manifold *m)
{
    tb__box a, b;
    double d[3], L[3], edge_L[3] = { 0, 0, 0 };
    double sep_a = -HUGE_VAL, sep_b = -HUGE_VAL, sep_e = -HUGE_VAL;
    int i, j, fa = 0, fb = 0, ea = -1, eb = -1;
    box_of(ga, &a);
    box_of(gb, &b);
    sub(b.c, a.c, d);
    for (i = 0; i < 3; ++i) {
        const double s = fabs(dot(d, a.ax[i])) - a.h[i] - box_radius(&b, a.ax[i]);
        if (s > sep_a)
            sep_a = s, fa = i;
    }
    for (j = 0; j < 3; ++j) {
        const double s = fabs(dot(d, b.ax[j])) - b.h[j] - box_radius(&a, b.ax[j]);
        if (s > sep_b)
            sep_b = s, fb = j;
    }
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            cross(a.ax[i], b.ax[j], L);
            const double l = len(L);
            if (l < TB__EDGE_MIN)
                continue;
            scale(L, sign_of(dot(d, L)) / l, L);
            const double s = dot(d, L) - box_radius(&a, L) - box_radius(&b, L);
            if (s > sep_e)
                sep_e = s, ea = i, eb = j, memcpy(edge_L, L, sizeof L);
        }
    if (!(sep_a < margin && sep_b < margin && sep_e < margin))
        return;
    const double size = a.h[0] + a.h[1] + a.h[2] + b.h[0] + b.h[1] + b.h[2];
    const int use_b = clearly_better(sep_b, sep_a, size, tolerance);
    if (ea < 0 || !clearly_better(sep_e, use_b ? sep_b : sep_a, size, tolerance)) {
        if (use_b)
            box_face(&b, &a, fb, 1, margin, m);
        else
            box_face(&a, &b, fa, 0, margin, m);
        if (m->count || ea < 0)
            return;
        /* No face point within the margin: the edges, if they cross. */
        box_edge(&a, &b, ea, eb, edge_L, 1, margin, m);
        return;
    }
    /* The edges' axis is the shallowest, but an edge may lie along the
       face, touching it along a line: the face's points hold it along its
       length, where the one crossing point would leave it free to rock and
       the choice would flip between the two from step to step (a heap of
       boxes never slept: test_collide.edge_on_a_face_across_its_edge_keeps_
       the_line). They are taken when there are two or more, none deeper
       than the edges' overlap by more than the tolerance, and the face's
       normal turns the push out of that overlap aside by less than the
       tolerance. */
    {
        const double *n_face = use_b ? b.ax[fb] : a.ax[fa];
        double aside[3];
        tb__manifold face;
        cross(edge_L, n_face, aside);
        face.count = 0;
        if (fmax(-sep_e, 0) * len(aside) <= tolerance) {
            if (use_b)
                box_face(&b, &a, fb, 1, margin, &face);
            else
                box_face(&a, &b, fa, 0, margin, &face);
        }
        if (face.count >= 2) {
            double deepest = -HUGE_VAL;
            for (i = 0; i < face.count; ++i)
                deepest = fmax(deepest, face.point[i].depth);
            if (deepest <= -sep_e + tolerance) {
                *m = face;
                return;
            }
        }
    }
    box_edge(&a, &b, ea, eb, edge_L, 0, margin, m);
}

/* ----------------------------------------------------------- dispatch -- */

typedef void tb__pair_fn(const tb__geom *a, const tb__geom *b, double margin, double tolerance, tb__manifold *m);

/* By the kinds of a and b, a's kind not after b's; plane and plane: none. */
static tb__pair_fn *const pair_fns[TB__SHAPE_KINDS][TB__SHAPE_KINDS] = {
    { sphere_sphere, sphere_capsule, sphere_box, round_plane },
    { NULL, capsule_capsule, capsule_box, round_plane },
    { NULL, NULL, box_box, box_plane },
    { NULL, NULL, NULL, NULL },
};

/* A capsule with no core length is a sphere (the segment code would
   otherwise divide by its zero length). */
static const tb__geom *as_sphere(const tb__geom *g, tb__geom *copy)
{
    if (g->kind != TB__SHAPE_CAPSULE || g->half[2] > 1e-12 * g->radius)
        return g;
    *copy = *g;
    copy->kind = TB__SHAPE_SPHERE;
    return copy;
}

/* The radius of a ball about g's centre that holds it (a plane: none). */
static double bounding_radius(const tb__geom *g)
{
    switch (g->kind) {
    case TB__SHAPE_SPHERE: return g->radius;
    case TB__SHAPE_CAPSULE: return g->half[2] + g->radius;
    case TB__SHAPE_BOX: return sqrt(dot(g->half, g->half));
    default: return HUGE_VAL;
    }
}

int tb__collide(const tb__geom *a, const tb__geom *b, double margin, double tolerance, tb__manifold *m)
{
    const double reach = bounding_radius(a) + bounding_radius(b) + margin;
    tb__geom ca, cb;
    double d[3];
    memset(m, 0, sizeof *m);
    /* balls about the two further apart than the margin: so are the
       shapes (an eighth of a pile's pairs overlap in their boxes alone) */
    sub(b->pos, a->pos, d);
    if (reach < HUGE_VAL && dot(d, d) > reach * reach)
        return 0;
    a = as_sphere(a, &ca);
    b = as_sphere(b, &cb);
    if (a->kind <= b->kind) {
        if (pair_fns[a->kind][b->kind])
            pair_fns[a->kind][b->kind](a, b, margin, tolerance, m);
    } else if (pair_fns[b->kind][a->kind]) {
        pair_fns[b->kind][a->kind](b, a, margin, tolerance, m);
        scale(m->normal, -1, m->normal);
    }
    return m->count;
}

void tb__geom_bounds(const tb__geom *g, double lo[3], double hi[3])
{
    int i;
    for (i = 0; i < 3; ++i) {
        const double *R = g->rot + 3 * i;
        double e;
        switch (g->kind) {
        case TB__SHAPE_SPHERE: e = g->radius; break;
        case TB__SHAPE_CAPSULE: e = fabs(R[2]) * g->half[2] + g->radius; break;
        case TB__SHAPE_BOX: e = fabs(R[0]) * g->half[0] + fabs(R[1]) * g->half[1] + fabs(R[2]) * g->half[2]; break;
        default: lo[i] = -HUGE_VAL, hi[i] = HUGE_VAL; continue;
        }
        lo[i] = g->pos[i] - e;
        hi[i] = g->pos[i] + e;
    }
}
