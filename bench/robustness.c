/* robustness.c: contact scenes of the kinds game developers build and the
   contact tests were not tuned on, run at 60 Hz with the default settings,
   each printed beside the figure the contact redesign must reach (the
   contacts issue of the tracker; docs/contacts.md, "Known limits"). Nothing
   here asserts: it measures today's solver so that a new one is judged on
   the same scenes.

   - wall: 105 bricks (0.4 x 0.2 x 0.2 m, 2 kg) in 7 courses of 15, each
     course shifted a quarter brick from the one under it, struck at the
     middle of its second course by a 10 kg ball (r = 0.15 m) at 5 m/s;
     bricks moved more than 5 cm at 2, 5 and 10 s (target: only the bricks
     the blow reaches). Then the same ball at 0.52 m/s (1.35 J, far less
     than tipping the wall needs): bricks moved and the largest energy above
     the start over 10 s (target: standing, no energy gained).
   - tallwall: the same bricks in 15 courses of 10 (3 m high, 0.2 m
     thick), nothing striking it, kept awake 20 s: the top course's
     largest move from where it was built (down and across) at 5, 10 and
     20 s (target: under 1 cm at 20 s, as for towers and walls).
   - tower: 30 cubes (0.5 m, 1 kg), each placed up to 1 cm off the one below
     and turned up to 3 degrees about the vertical (reproducible draws),
     kept awake 20 s: the top box's horizontal drift at 5, 10 and 20 s
     (target: under 1 cm at 20 s).
   - lever: a beam (3 x 0.3 x 0.1 m) of 100 or 1000 kg laid across a 1 kg
     plank (1 x 0.2 x 0.05 m) on the ground at one end and a static block
     at the other, both tops at the same height: how deep the plank's lowest
     corner is in the ground after 5 s (target: under 5 cm at 1000:1).
   - plate: a 1 cm plate (0.5 x 0.5 x 0.01 m, 1 kg) falling at 30 m/s
     tilted 20 degrees about a random horizontal axis and spun up to
     20 rad/s about a random axis onto a 1 cm static slab (3 x 3 m): runs,
     of 100, whose plate passes through (its centre below the slab while
     over it; sliding off an edge is not passing through) (target: none in
     100).
   - heap: 2000 spheres, boxes and capsules (0.1 to 0.3 m) dropped from a
     grid, each shifted up to 5 cm and turned at random, balls and
     capsules with rolling resistance 0.05 of their radius, onto the ground:
     when the last body falls asleep (target: within 20 s), the fastest
     body and any centre below the floor.
   - bridge: three boxes from the heap as they lay at 19 s (poses to the
     last digit), a 113 kg box laid across two others (one's top edge
     along its bottom face, a corner of the other), all three on the
     ground, kept awake 20 s: how often the top box's rest is reset (|v| +
     |w| times its half diagonal rising past the sleep speed after it was
     below) and when it last was, and the boxes' largest kinetic energy
     after 10 s (target: at rest, held on three points; no reset).
   - boxheap: the heap's generator with every shape a box, 2000 boxes
     of 0.2 to 0.6 m: the same figures (target: asleep within 20 s).
   - cradle: 5 touching balls (1 kg, r = 0.1 m, restitution 1, no gravity,
     no friction) struck end-on at 1 m/s: the last ball's speed and the
     energy after 1 s, as shares of the striker's (target: >= 95% and
     within 5%, never above).

   Each scene prints its mean milliseconds per step too. Scene names
   (wall, tallwall, tower, lever, plate, bridge, cradle, heap, boxheap) on the command line run only
   those; --substeps=N runs them with N substeps (the default: 4), and
   --hertz=F sets the contact stiffness (F = 0: a quarter of the substep
   rate, the stiffest it allows). */
#define _POSIX_C_SOURCE 199309L
#define BENCH_NAME "bench_robustness"
#include "bench.h"
#include "heap_scenes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define H (1.0 / 60)
#define G 9.81
#define PI 3.14159265358979323846

/* --substeps and --hertz: the contact settings for every scene (-1,
   without the option: the default) */
static int substeps = -1;
static double hertz = -1;

static tb_world *new_world(double gravity)
{
    tb_world_def def = tb_default_world_def();
    tb_world *w;
    char message[TB_MESSAGE_SIZE];
    def.gravity[2] = -gravity;
    if (tb_world_create(&def, &w, message, sizeof message) != TB_OK) {
        fprintf(stderr, BENCH_NAME ": %s\n", message);
        exit(EXIT_FAILURE);
    }
    if (substeps > 0 || hertz >= 0) {
        tb_contact_settings cs = tb_world_contact_settings(w);
        if (substeps > 0)
            cs.substeps = substeps;
        if (hertz >= 0)
            cs.hertz = hertz > 0 ? hertz : 0.25 * cs.substeps / H;
        check(tb_world_set_contact_settings(w, &cs), w, "soft-step settings");
    }
    return w;
}

static void add_ground(tb_world *w)
{
    tb_shape_def plane = tb_default_shape_def();
    plane.type = TB_SHAPE_PLANE;
    check(tb_world_add_shape(w, &plane, NULL), w, "ground");
}

/* A box body of full sizes `size` and mass m at x, turned by q (NULL:
   upright); a static box when m is 0. */
static tb_body_id add_box(tb_world *w, const double size[3], double m, const double x[3], const double q[4],
                          double restitution)
{
    tb_body_id id = { 0, 0 };
    tb_shape_def s = tb_default_shape_def();
    char message[TB_MESSAGE_SIZE];
    s.type = TB_SHAPE_BOX;
    s.half_extents[0] = size[0] / 2;
    s.half_extents[1] = size[1] / 2;
    s.half_extents[2] = size[2] / 2;
    s.restitution = restitution;
    if (m > 0) {
        tb_body_def b = tb_default_body_def();
        if (tb_mass_box(1000, size, &b.mass, message) != TB_OK || tb_mass_set_total(&b.mass, m, message) != TB_OK) {
            fprintf(stderr, BENCH_NAME ": box mass: %s\n", message);
            exit(EXIT_FAILURE);
        }
        memcpy(b.position, x, sizeof b.position);
        if (q)
            memcpy(b.orientation, q, sizeof b.orientation);
        check(tb_world_add_body(w, &b, &id), w, "box");
        s.body = id;
    } else {
        memcpy(s.position, x, sizeof s.position);
        if (q)
            memcpy(s.orientation, q, sizeof s.orientation);
    }
    check(tb_world_add_shape(w, &s, NULL), w, "box shape");
    return id;
}

static tb_body_id add_ball(tb_world *w, double r, double m, const double x[3], const double v[3],
                           double restitution, double friction, double rolling)
{
    tb_body_id id;
    tb_body_def b = tb_default_body_def();
    tb_shape_def s = tb_default_shape_def();
    char message[TB_MESSAGE_SIZE];
    if (tb_mass_sphere(1000, r, &b.mass, message) != TB_OK || tb_mass_set_total(&b.mass, m, message) != TB_OK) {
        fprintf(stderr, BENCH_NAME ": ball mass: %s\n", message);
        exit(EXIT_FAILURE);
    }
    memcpy(b.position, x, sizeof b.position);
    if (v)
        memcpy(b.velocity, v, sizeof b.velocity);
    check(tb_world_add_body(w, &b, &id), w, "ball");
    s.type = TB_SHAPE_SPHERE;
    s.body = id;
    s.radius = r;
    s.restitution = restitution;
    s.friction = friction;
    s.rolling_resistance = rolling;
    check(tb_world_add_shape(w, &s, NULL), w, "ball shape");
    return id;
}

static void set_awake(tb_world *w)
{
    tb_contact_settings c = tb_world_contact_settings(w);
    c.sleep_time = INFINITY;
    check(tb_world_set_contact_settings(w, &c), w, "settings");
}

/* Steps n times, adding the wall time to *ms (milliseconds) and the count
   to *steps. */
static void run(tb_world *w, int n, double *ms, long *steps)
{
    double t0 = seconds();
    int i;
    for (i = 0; i < n; ++i)
        check(tb_world_step(w, H), w, "step");
    *ms += 1e3 * (seconds() - t0);
    *steps += n;
}

static void axis_turn(const double axis[3], double angle, double q[4])
{
    const double n = norm3(axis), s = sin(angle / 2) / n;
    q[0] = cos(angle / 2);
    q[1] = axis[0] * s;
    q[2] = axis[1] * s;
    q[3] = axis[2] * s;
}

/* ------------------------------------------------------------------ wall -- */

#define COURSES 7
#define PER_COURSE 15
#define TALL_COURSES 15
#define TALL_PER_COURSE 10
static const double brick[3] = { 0.4, 0.2, 0.2 };

/* courses of per bricks (2 kg) on the ground, each course shifted a
   quarter brick from the one under it: ids and places into bricks and
   start */
static void build_wall(tb_world *w, int courses, int per, tb_body_id *bricks, double (*start)[3])
{
    int c, i;
    for (c = 0; c < courses; ++c)
        for (i = 0; i < per; ++i) {
            const double x[3] = { (i - (per - 1) / 2.0 + (c % 2 ? 0.25 : 0)) * brick[0], 0, (c + 0.5) * brick[2] };
            bricks[c * per + i] = add_box(w, brick, 2, x, NULL, 0);
            memcpy(start[c * per + i], x, sizeof start[0]);
        }
}

static void wall(double speed)
{
    tb_body_id bricks[COURSES * PER_COURSE];
    double start[COURSES * PER_COURSE][3], e0, gained = 0, ms = 0;
    long steps = 0;
    tb_world *w = new_world(G);
    int k, second;
    add_ground(w);
    build_wall(w, COURSES, PER_COURSE, bricks, start);
    {
        const double x[3] = { 0, -1.0, 1.5 * brick[2] }, v[3] = { 0, speed, 0 };
        add_ball(w, 0.15, 10, x, v, 0, 0.6, 0);
    }
    e0 = tb_world_energy(w).total;
    printf("wall      105 bricks, 10 kg ball at %.2f m/s (%.2f J):", speed, 0.5 * 10 * speed * speed);
    for (second = 1; second <= 10; ++second) {
        int moved = 0;
        for (k = 0; k < 60; ++k) {
            run(w, 1, &ms, &steps);
            gained = fmax(gained, tb_world_energy(w).total - e0);
        }
        if (second != 2 && second != 5 && second != 10)
            continue;
        for (k = 0; k < COURSES * PER_COURSE; ++k) {
            double x[3], d[3];
            check(tb_body_position(w, bricks[k], x), w, "brick");
            d[0] = x[0] - start[k][0], d[1] = x[1] - start[k][1], d[2] = x[2] - start[k][2];
            moved += norm3(d) > 0.05;
        }
        printf(" %2d s: %3d moved,", second, moved);
    }
    printf(" most energy above the start %.3g J, %.3f ms/step\n", gained, ms / (double)steps);
    tb_world_destroy(w);
}

static void tall_wall(void)
{
    tb_body_id bricks[TALL_COURSES * TALL_PER_COURSE];
    double start[TALL_COURSES * TALL_PER_COURSE][3], ms = 0;
    long steps = 0;
    tb_world *w = new_world(G);
    int k, second;
    add_ground(w);
    set_awake(w);
    build_wall(w, TALL_COURSES, TALL_PER_COURSE, bricks, start);
    printf("tallwall  150 bricks in 15 courses of 10, awake: the top course moved");
    for (second = 1; second <= 20; ++second) {
        double most = 0;
        run(w, 60, &ms, &steps);
        if (second != 5 && second != 10 && second != 20)
            continue;
        for (k = (TALL_COURSES - 1) * TALL_PER_COURSE; k < TALL_COURSES * TALL_PER_COURSE; ++k) {
            double x[3], d[3];
            check(tb_body_position(w, bricks[k], x), w, "brick");
            d[0] = x[0] - start[k][0], d[1] = x[1] - start[k][1], d[2] = x[2] - start[k][2];
            most = fmax(most, norm3(d));
        }
        printf(" %2d s %.4f m,", second, most);
    }
    printf(" %.3f ms/step\n", ms / (double)steps);
    tb_world_destroy(w);
}

/* ----------------------------------------------------------------- tower -- */

static void tower(void)
{
    static const double cube[3] = { 0.5, 0.5, 0.5 };
    unsigned long long seed = 30;
    tb_body_id top = { 0, 0 };
    double placed[3] = { 0, 0, 0 }, ms = 0;
    long steps = 0;
    tb_world *w = new_world(G);
    int i, second;
    add_ground(w);
    set_awake(w);
    for (i = 0; i < 30; ++i) {
        const double r = 0.01 * sqrt(uniform(&seed)), a = 2 * PI * uniform(&seed);
        const double yaw = (2 * uniform(&seed) - 1) * 3 * PI / 180, up[3] = { 0, 0, 1 };
        double q[4];
        if (i > 0)
            placed[0] += r * cos(a), placed[1] += r * sin(a);
        placed[2] = (i + 0.5) * cube[2];
        axis_turn(up, yaw, q);
        top = add_box(w, cube, 1, placed, q, 0);
    }
    printf("tower     30 cubes offset up to 1 cm and 3 deg, awake: top drift");
    for (second = 1; second <= 20; ++second) {
        run(w, 60, &ms, &steps);
        if (second == 5 || second == 10 || second == 20) {
            double x[3];
            check(tb_body_position(w, top, x), w, "top");
            printf(" %2d s %.4f m,", second, hypot(x[0] - placed[0], x[1] - placed[1]));
        }
    }
    printf(" %.3f ms/step\n", ms / (double)steps);
    tb_world_destroy(w);
}

/* ----------------------------------------------------------------- lever -- */

static void lever(double ratio)
{
    static const double plank[3] = { 1.0, 0.2, 0.05 }, beam[3] = { 3.0, 0.3, 0.1 };
    const double block[3] = { 0.4, 0.4, plank[2] };
    double ms = 0, lowest = INFINITY;
    long steps = 0;
    tb_world *w = new_world(G);
    tb_body_id light;
    int k;
    add_ground(w);
    {
        const double x[3] = { -1.2, 0, plank[2] / 2 }, b[3] = { 1.3, 0, block[2] / 2 };
        const double y[3] = { 0, 0, plank[2] + beam[2] / 2 };
        light = add_box(w, plank, 1, x, NULL, 0);
        add_box(w, block, 0, b, NULL, 0);
        add_box(w, beam, ratio, y, NULL, 0);
    }
    run(w, 300, &ms, &steps);
    {
        double x[3], q[4], R[9];
        check(tb_body_position(w, light, x), w, "plank");
        check(tb_body_orientation(w, light, q), w, "plank");
        R[6] = 2 * (q[1] * q[3] - q[0] * q[2]);
        R[7] = 2 * (q[2] * q[3] + q[0] * q[1]);
        R[8] = 1 - 2 * (q[1] * q[1] + q[2] * q[2]);
        for (k = 0; k < 8; ++k) {
            const double c[3] = { (k & 1 ? 0.5 : -0.5) * plank[0], (k & 2 ? 0.5 : -0.5) * plank[1],
                                  (k & 4 ? 0.5 : -0.5) * plank[2] };
            lowest = fmin(lowest, x[2] + R[6] * c[0] + R[7] * c[1] + R[8] * c[2]);
        }
    }
    printf("lever     beam %5.0f times the plank under it: the plank's lowest corner %.4f m into the ground "
           "after 5 s, %.3f ms/step\n", ratio, fmax(0, -lowest), ms / (double)steps);
    tb_world_destroy(w);
}

/* ----------------------------------------------------------------- plate -- */

static void plate(int runs)
{
    static const double size[3] = { 0.5, 0.5, 0.01 }, slab[3] = { 3, 3, 0.01 };
    unsigned long long seed = 7;
    int r, through = 0;
    double ms = 0;
    long steps = 0;
    for (r = 0; r < runs; ++r) {
        tb_world *w = new_world(G);
        tb_body_def b = tb_default_body_def();
        tb_shape_def s = tb_default_shape_def();
        const double slab_at[3] = { 0, 0, 1.0 }, a = 2 * PI * uniform(&seed);
        const double tilt_axis[3] = { cos(a), sin(a), 0 };
        double spin_axis[3], x[3], spin;
        char message[TB_MESSAGE_SIZE];
        tb_body_id id;
        add_ground(w);
        add_box(w, slab, 0, slab_at, NULL, 0);
        if (tb_mass_box(1000, size, &b.mass, message) != TB_OK || tb_mass_set_total(&b.mass, 1, message) != TB_OK)
            exit(EXIT_FAILURE);
        b.position[2] = 1.5;
        axis_turn(tilt_axis, 20 * PI / 180, b.orientation);
        b.velocity[2] = -30;
        spin_axis[0] = 2 * uniform(&seed) - 1, spin_axis[1] = 2 * uniform(&seed) - 1,
        spin_axis[2] = 2 * uniform(&seed) - 1;
        spin = 20 * uniform(&seed) / norm3(spin_axis);
        b.angular_velocity[0] = spin * spin_axis[0], b.angular_velocity[1] = spin * spin_axis[1],
        b.angular_velocity[2] = spin * spin_axis[2];
        check(tb_world_add_body(w, &b, &id), w, "plate");
        s.type = TB_SHAPE_BOX;
        s.body = id;
        s.half_extents[0] = size[0] / 2, s.half_extents[1] = size[1] / 2, s.half_extents[2] = size[2] / 2;
        check(tb_world_add_shape(w, &s, NULL), w, "plate shape");
        {
            int t, below = 0;
            for (t = 0; t < 60; ++t) {
                run(w, 1, &ms, &steps);
                check(tb_body_position(w, id, x), w, "plate");
                below |= x[2] < slab_at[2] - slab[2] / 2 && fabs(x[0]) < (slab[0] - size[0]) / 2 &&
                         fabs(x[1]) < (slab[1] - size[1]) / 2;
            }
            through += below;
        }
        tb_world_destroy(w);
    }
    printf("plate     1 cm plate at 30 m/s, tilted 20 deg, spun up to 20 rad/s onto a 1 cm slab: %d of %d "
           "through, %.3f ms/step\n", through, runs, ms / (double)steps);
}

/* ------------------------------------------------------------------ heap -- */

/* A uniformly random rotation (Shoemake's), from three draws */
static void random_turn(unsigned long long *seed, double q[4])
{
    const double u = uniform(seed), a = 2 * PI * uniform(seed), b = 2 * PI * uniform(seed);
    q[0] = sqrt(1 - u) * sin(a), q[1] = sqrt(1 - u) * cos(a);
    q[2] = sqrt(u) * sin(b), q[3] = sqrt(u) * cos(b);
}

/* The round shapes' rolling resistance, a share of their radius (Box3D's
   rule, rho = its coefficient times the radius): with none, a ball on a
   heap rolls on for ever in every engine, and Box3D's heaps of spheres or
   capsules sleep at 16 to 18 s only with its samples' 0.05
   (docs/notes.md, "Box3D's soft contacts"). */
#define ROLLING 0.05

static void heap(int count, int boxes)
{
    unsigned long long seed = 2000;
    double ms = 0, fastest = 0, lowest = INFINITY;
    long steps = 0;
    tb_world *w = new_world(G);
    int i, side = (int)ceil(sqrt(count / 10.0)), asleep_at = -1, second;
    add_ground(w);
    for (i = 0; i < count; ++i) {
        /* a grid, each shape shifted up to 5 cm and turned at random (in
           exact columns, a solver exact enough stacks balls on balls) */
        const double x[3] = { 0.7 * (i % side - side / 2.0) + 0.1 * (uniform(&seed) - 0.5),
                              0.7 * ((i / side) % side - side / 2.0) + 0.1 * (uniform(&seed) - 0.5),
                              0.5 + 0.7 * (i / (side * side)) };
        const double r = 0.1 + 0.2 * uniform(&seed), drawn = uniform(&seed), kind = boxes ? 0.5 : drawn;
        double q[4];
        random_turn(&seed, q);
        if (kind < 0.4) {
            add_ball(w, r, 1000 * 4.18879 * r * r * r, x, NULL, 0, 0.6, ROLLING * r);
        } else if (kind < 0.8) {
            const double size[3] = { 2 * r, 2 * (0.1 + 0.2 * uniform(&seed)), 2 * (0.1 + 0.2 * uniform(&seed)) };
            add_box(w, size, 1000 * size[0] * size[1] * size[2], x, q, 0);
        } else {
            tb_body_def b = tb_default_body_def();
            tb_shape_def s = tb_default_shape_def();
            tb_body_id id;
            char message[TB_MESSAGE_SIZE];
            const double half = 0.05 + 0.15 * uniform(&seed), rc = 0.5 * r;
            if (tb_mass_capsule(1000, rc, 2 * half, &b.mass, message) != TB_OK)
                exit(EXIT_FAILURE);
            memcpy(b.position, x, sizeof b.position);
            memcpy(b.orientation, q, sizeof b.orientation);
            check(tb_world_add_body(w, &b, &id), w, "capsule");
            s.type = TB_SHAPE_CAPSULE;
            s.body = id;
            s.radius = rc;
            s.half_length = half;
            s.rolling_resistance = ROLLING * rc;
            check(tb_world_add_shape(w, &s, NULL), w, "capsule shape");
        }
    }
    for (second = 1; second <= 20 && asleep_at < 0; ++second) {
        run(w, 60, &ms, &steps);
        if (tb_world_sleeping_count(w) == tb_world_body_count(w))
            asleep_at = second;
    }
    for (i = 0; i < (int)tb_world_body_count(w); ++i) {
        double v[3], x[3];
        const tb_body_id id = tb_world_body_at(w, (size_t)i);
        check(tb_body_velocity(w, id, v), w, "body");
        check(tb_body_position(w, id, x), w, "body");
        fastest = fmax(fastest, norm3(v));
        lowest = fmin(lowest, x[2]);
    }
    printf("%s %d %s: all asleep %s%d s, awake at the end %zu, fastest %.3g m/s, lowest centre %.3f m, "
           "%.3f ms/step\n", boxes ? "boxheap  " : "heap     ", count, boxes ? "boxes" : "shapes",
           asleep_at < 0 ? "not within " : "after ", asleep_at < 0 ? 20 : asleep_at,
           tb_world_body_count(w) - tb_world_sleeping_count(w), fastest, lowest, ms / (double)steps);
    tb_world_destroy(w);
}

/* ---------------------------------------------------------------- bridge -- */

static void bridge(void)
{
    tb_world *w = new_world(G);
    tb_body_id ids[3];
    double ms = 0, rest = 0, reach, most = 0, last_reset = 0;
    long steps = 0;
    int i, resets = 0;
    add_ground(w);
    set_awake(w);
    for (i = 0; i < 3; ++i) {
        const double size[3] = { 2 * HEAP_BRIDGE[i][7], 2 * HEAP_BRIDGE[i][8], 2 * HEAP_BRIDGE[i][9] };
        ids[i] = add_box(w, size, 1000 * size[0] * size[1] * size[2], HEAP_BRIDGE[i], HEAP_BRIDGE[i] + 3, 0);
    }
    reach = norm3(HEAP_BRIDGE[0] + 7);
    for (i = 1; i <= 20 * 60; ++i) {
        double v[3], om[3], speed;
        run(w, 1, &ms, &steps);
        check(tb_body_velocity(w, ids[0], v), w, "top box");
        check(tb_body_angular_velocity(w, ids[0], om), w, "top box");
        speed = norm3(v) + norm3(om) * reach;
        if (speed < tb_default_contact_settings().sleep_speed) {
            rest += H;
        } else {
            if (rest > 0)
                ++resets, last_reset = i * H;
            rest = 0;
        }
        if (i > 10 * 60) {
            const tb_energy e = tb_world_energy(w);
            most = fmax(most, e.kinetic + e.rotational);
        }
    }
    printf("bridge    a box laid across two, awake: its rest reset %d times, the last at %.2f s, "
           "the boxes' largest kinetic energy after 10 s %.4f J, %.3f ms/step\n",
           resets, last_reset, most, ms / (double)steps);
    tb_world_destroy(w);
}

/* ---------------------------------------------------------------- cradle -- */

static void cradle(int balls)
{
    tb_body_id id[5];
    double ms = 0, e0, v[3];
    long steps = 0;
    tb_world *w = new_world(0);
    int i;
    for (i = 0; i < balls; ++i) {
        const double x[3] = { i == 0 ? -0.3 : 0.2 * i, 0, 1 }, u[3] = { i == 0 ? 1 : 0, 0, 0 };
        id[i] = add_ball(w, 0.1, 1, x, u, 1, 0, 0);
    }
    {
        tb_contact_settings c = tb_world_contact_settings(w);
        c.restitution_threshold = 0;
        check(tb_world_set_contact_settings(w, &c), w, "settings");
    }
    e0 = tb_world_energy(w).total;
    run(w, 60, &ms, &steps);
    check(tb_body_velocity(w, id[balls - 1], v), w, "last ball");
    printf("cradle    %d balls, e = 1, striker at 1 m/s: after 1 s the last ball at %.4f of the striker's speed, "
           "energy %.4f of the start, %.3f ms/step\n", balls, v[0], tb_world_energy(w).total / e0,
           ms / (double)steps);
    tb_world_destroy(w);
}

/* Scene names on the command line run only those scenes. */
static int wanted(int argc, char **argv, const char *name)
{
    int i;
    int named = 0;
    for (i = 1; i < argc; ++i) {
        if (strncmp(argv[i], "--", 2) == 0)
            continue;
        named = 1;
        if (strcmp(argv[i], name) == 0)
            return 1;
    }
    return !named;
}

int main(int argc, char **argv)
{
    int i;
    for (i = 1; i < argc; ++i) {
        if (strncmp(argv[i], "--substeps=", 11) == 0) {
            substeps = atoi(argv[i] + 11);
            if (substeps < 1) {
                fprintf(stderr, BENCH_NAME ": --substeps must be 1 or more\n");
                return 2;
            }
        }
        else if (strncmp(argv[i], "--hertz=", 8) == 0)
            hertz = atof(argv[i] + 8);
        else if (strncmp(argv[i], "--", 2) == 0) {
            fprintf(stderr, BENCH_NAME ": unknown option %s (--substeps=N, --hertz=F)\n", argv[i]);
            return 2;
        }
    }
    printf("bench_robustness: contact scenes at 60 Hz, default settings (targets in the source's header)\n");
    {
        const int n = substeps > 0 ? substeps : tb_default_contact_settings().substeps;
        if (hertz < 0)
            printf("soft-step solver: %d substeps, contact stiffness the default\n", n);
        else
            printf("soft-step solver: %d substeps, contact stiffness %g Hz\n", n, hertz > 0 ? hertz : 0.25 * n / H);
    }
    bench_print_build();
    if (wanted(argc, argv, "wall")) {
        wall(5.0);
        wall(sqrt(2 * 1.35 / 10));
    }
    if (wanted(argc, argv, "tallwall"))
        tall_wall();
    if (wanted(argc, argv, "tower")) {
        tower();
    }
    if (wanted(argc, argv, "lever")) {
        lever(100);
        lever(1000);
    }
    if (wanted(argc, argv, "plate"))
        plate(100);
    if (wanted(argc, argv, "bridge"))
        bridge();
    if (wanted(argc, argv, "cradle")) {
        cradle(2);
        cradle(5);
    }
    if (wanted(argc, argv, "heap"))
        heap(2000, 0);
    if (wanted(argc, argv, "boxheap"))
        heap(2000, 1);
    return 0;
}
