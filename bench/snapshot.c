/* snapshot.c: the cost of tb_world_snapshot and tb_world_restore per body,
   and of the guard's copy per step, on a pile of 1000 bodies: 10 x 10
   columns of boxes and spheres, 10 high, on a plane (each body touches the
   one below and above: about 1000 contacts with warm starts).
   - rest: sleep on, run until every body sleeps;
   - awake: sleep off, after 1 s, every contact solved each step.
   For rollback networking at 60 Hz a frame has 16.7 ms; a snapshot every
   frame and a restore with a resimulation now and then must be a small
   part of that. Measures; asserts nothing. */
#define _POSIX_C_SOURCE 199309L
#define BENCH_NAME "bench_snapshot"
#include "bench.h"

#define SIDE 10
#define HIGH 10
#define BODIES (SIDE * SIDE * HIGH)
#define REPEATS 41
#define H (1.0 / 60)

static tb_world *pile(int sleep)
{
    tb_world_def def = tb_default_world_def();
    tb_shape_def plane = tb_default_shape_def();
    tb_contact_settings cs = tb_default_contact_settings();
    tb_world *w;
    char message[TB_MESSAGE_SIZE];
    int i, j, k;
    if (tb_world_create(&def, &w, message, sizeof message) != TB_OK) {
        fprintf(stderr, BENCH_NAME ": %s\n", message);
        exit(EXIT_FAILURE);
    }
    plane.type = TB_SHAPE_PLANE;
    check(tb_world_add_shape(w, &plane, NULL), w, "plane");
    if (!sleep)
        cs.sleep_time = INFINITY;
    check(tb_world_set_contact_settings(w, &cs), w, "settings");
    for (i = 0; i < SIDE; ++i)
        for (j = 0; j < SIDE; ++j)
            for (k = 0; k < HIGH; ++k) {
                tb_body_def b = tb_default_body_def();
                tb_shape_def s = tb_default_shape_def();
                const double edge[3] = { 0.5, 0.5, 0.5 };
                tb_body_id id;
                const int ball = (i + j + k) % 4 == 3 && k == HIGH - 1; /* spheres on some tops */
                if (ball) {
                    check(tb_mass_sphere(500, 0.25, &b.mass, NULL), w, "mass");
                    s.type = TB_SHAPE_SPHERE;
                    s.radius = 0.25;
                } else {
                    check(tb_mass_box(500, edge, &b.mass, NULL), w, "mass");
                    s.type = TB_SHAPE_BOX;
                    s.half_extents[0] = s.half_extents[1] = s.half_extents[2] = 0.25;
                }
                b.position[0] = 0.8 * i;
                b.position[1] = 0.8 * j;
                b.position[2] = 0.25 + 0.5 * k;
                check(tb_world_add_body(w, &b, &id), w, "body");
                s.body = id;
                check(tb_world_add_shape(w, &s, NULL), w, "shape");
            }
    return w;
}

/* Median ns per body of a snapshot taken afresh (allocated, then
   destroyed), of one taken again into the memory of the last
   (tb_world_snapshot_into, a rollback host's ring), and of a restore (into
   the world it came from, which has stepped on: the realistic rollback);
   and the snapshot's bytes per body. */
static void measure_pile(tb_world *w, const char *what)
{
    double fresh[REPEATS], again[REPEATS], back[REPEATS];
    tb_snapshot *s, *ring;
    size_t bytes;
    int r;
    check(tb_world_snapshot(w, &s), w, "snapshot");
    check(tb_world_snapshot(w, &ring), w, "snapshot");
    bytes = tb_snapshot_size(s);
    for (r = 0; r < REPEATS; ++r) {
        tb_snapshot *t;
        double t0 = seconds();
        check(tb_world_snapshot(w, &t), w, "snapshot");
        fresh[r] = seconds() - t0;
        tb_snapshot_destroy(t);
        t0 = seconds();
        check(tb_world_snapshot_into(w, ring), w, "snapshot again");
        again[r] = seconds() - t0;
        check(tb_world_step(w, H), w, "step");
        t0 = seconds();
        check(tb_world_restore(w, s), w, "restore");
        back[r] = seconds() - t0;
    }
    printf("%-6s  snapshot %5.0f ns/body (into the last one's memory %4.0f)   restore %4.0f ns/body   "
           "size %5.0f bytes/body   (%zu asleep)\n",
           what, 1e9 * median_of(fresh, REPEATS) / BODIES, 1e9 * median_of(again, REPEATS) / BODIES,
           1e9 * median_of(back, REPEATS) / BODIES, (double)bytes / BODIES, tb_world_sleeping_count(w));
    tb_snapshot_destroy(ring);
    tb_snapshot_destroy(s);
}

/* The guard's price: median ms per step with the guard off and on (it
   copies what the step can change first), over the same steps. */
static void measure_guard(tb_world *w)
{
    double off[REPEATS], on[REPEATS];
    tb_snapshot *s;
    int r;
    check(tb_world_snapshot(w, &s), w, "snapshot");
    for (r = 0; r < REPEATS; ++r) {
        double t0;
        check(tb_world_restore(w, s), w, "restore");
        check(tb_world_set_guard(w, 0), w, "guard");
        t0 = seconds();
        check(tb_world_step(w, H), w, "step");
        off[r] = seconds() - t0;
        check(tb_world_restore(w, s), w, "restore");
        check(tb_world_set_guard(w, INFINITY), w, "guard");
        t0 = seconds();
        check(tb_world_step(w, H), w, "step");
        on[r] = seconds() - t0;
    }
    printf("guard   step %.3f ms off, %.3f ms on (awake pile): the copy costs %.0f ns/body a step\n",
           1e3 * median_of(off, REPEATS), 1e3 * median_of(on, REPEATS),
           1e9 * (median_of(on, REPEATS) - median_of(off, REPEATS)) / BODIES);
    tb_snapshot_destroy(s);
}

int main(void)
{
    tb_world *rest = pile(1), *awake = pile(0);
    int i;
    bench_print_build();
    printf("pile    %d bodies (%d x %d columns of %d), 60 Hz\n", BODIES, SIDE, SIDE, HIGH);
    for (i = 0; i < 600 && tb_world_sleeping_count(rest) < BODIES; ++i)
        check(tb_world_step(rest, H), rest, "step");
    for (i = 0; i < 60; ++i)
        check(tb_world_step(awake, H), awake, "step");
    measure_pile(rest, "rest");
    measure_pile(awake, "awake");
    measure_guard(awake);
    tb_world_destroy(rest);
    tb_world_destroy(awake);
    return 0;
}
