/* contacts.c: contact throughput and stacking, tumble beside ODE and
   Bullet on the reference scenes of reference/ode_contacts.h (built there
   for ODE, in reference/bullet_contacts.cpp for Bullet, here for tumble,
   from the same layouts), each run in turn, BENCH_RUNS times.

   - pyramid: 210 unit cubes of 1 kg in 20 levels, 1 cm apart in a level, on
     a static plane, mu 0.6 on every shape (a pair uses sqrt(mu_a mu_b), so
     0.6 as in ODE), tumble's default contact settings and integrator, 60 Hz,
     10 s. Wall time of each tb_world_step (the whole step: broadphase,
     narrowphase, integrator, contact solve, events), median
     over the steps, beside ODE's dSpaceCollide + dWorldQuickStep(20) +
     emptying the contact group, timed the same way inside ode_pyramid().
     Then the top cube's sink (z drop) and drift (horizontal) after 10 s,
     and its greatest distance from where it started at any step: the
     pyramid sways out of its plane, so the end alone catches one phase of
     the sway. Targets: ODE/tumble >= 5 and the top cube within 1 cm of
     where it started throughout (the length of its whole displacement).
     Bullet 3.24 with its defaults beside them (bullet_contacts.h: its
     stepSimulation timed the same way), awake and with its deactivation.
   - pile: ode_pile_scene()'s 1000 spheres, boxes and capsules, each with
     ODE's mass, principal inertia and orientation, dropped from a grid;
     the same number of steps as ODE. The pile's cost changes as it falls
     and settles, so the mean over the steps is the figure (median beside
     it); contacts are tumble's touching points (tb_world_contact_count)
     against ODE's contact joints, means over the steps. Then how many of
     tumble's centres end below the plane: none should, and a count there
     means the timing is of a broken run. Bullet beside them, awake: the
     issue's target is 3 times Bullet's speed (Bullet/tumble >= 3).
   - ns per contact point per substep: the median step over (mean
     touching points x substeps), for the pile and the pyramid. This
     charges the whole step to the contacts (collision, integration,
     solve, events), so it is an upper bound on the solver alone.

   - heavy: a unit box 10, 100, 1000 and 10000 times as heavy as the 1 kg
     unit boxes under it dropped 0.5 m onto one of them, and 100 and 1000
     times onto a column of four (ode_heavy_landing: the same scene in ODE,
     QuickStep(20)), 10 s at 60 Hz with tumble's defaults: where the heavy
     box ends against resting on them (through: about minus the column's
     height), how fast it ever rose after it landed (restitution 0: it
     should not), and how deep a box under it went below its place.
     Accuracy, not time.
   - sleep: the pyramid and the pile are run twice, with sleep off (every
     body solved every step: the solver's own cost, the figure held against
     the target) and with the default settings, where resting islands fall
     asleep; that line gives the mean over all steps (waking included) and
     when every body was asleep. ODE runs without its auto-disable beside
     the awake line, and with it (its defaults: 0.01 m/s and rad/s for 10
     steps, by island) beside the sleep line. The pile does not fall
     asleep within its 10 s: balls and capsules that rolled out of it roll
     on across the endless plane (no rolling resistance, in either engine),
     and those still rolling at its edge keep its island awake.
   - asleep (also `bench_contacts --sleep`, alone): the ms per step once
     every body sleeps (the median of 300 steps after the last fell
     asleep, one run): the pyramid, and Bullet's (the issue gives MuJoCo's
     figure, not measured here); a block of 1000 unit cubes in 10
     levels of 10 x 10 columns 1 cm apart (100 islands of 10, a column
     each; it stands in for the pile, which does not fall asleep); and 1000 and 10000 separate cubes, each an island, whose
     difference over 9000 is the cost of one sleeping body a step.

   - scaling (`bench_contacts --scaling OUT`, run by `./dev.sh charts`,
     not by `./dev.sh bench`): the contact cost against the pile's size.
     ode_pile_scene's pile at 1000, 4000 and 16000 shapes, each on a grid
     of 10, 20 and 40 a side so that every pile is 10 layers high and
     falls and lands alike; sleep off, 300 steps at 60 Hz (5 s: it falls
     for about 1.5 s, then lands and spreads). The figure is ns per contact
     point: the whole step's wall time summed over the steps over the
     touching points summed over them (tb_world_contact_count), so it
     charges the broadphase and the integrator to the contacts too, an
     upper bound on the contacts' own cost; a solver whose cost grows with
     the points alone draws a flat line. One run of each; writes
     OUT/contact_scaling.csv, drawn by bench/contact_scaling.gp into
     docs/charts/contact_scaling.png. Then 16 copies of the 1000-shape
     pile side by side (ode_pile_copy_offset: 15 m apart, none meets
     another) in tumble and in ODE's QuickStep(20), 300 steps each: ns per
     contact point in both and ODE/tumble (issue 18: at least 5).

   The machine may be shared: runs alternate tumble and ODE, BENCH_RUNS
   times each, and the figures are medians over those runs, so that a
   burst of load elsewhere does not land on one engine only. The scenes are
   deterministic (ODE's runs reset its random seed), so the runs differ in
   time only. */
#define _POSIX_C_SOURCE 200809L
#define BENCH_NAME "bench_contacts"

#include "bench.h"
#include "bullet_contacts.h"
#include "ode_contacts.h"
#include "tumble.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define BENCH_RUNS 5

/* Box2D v3's published figure, for scale only: 2D, single precision, its
   soft step solver with substeps rather than iterations. */
#define BOX2D_NS_PER_CONTACT 23

typedef struct timing {
    double ms_median;     /* ms per step */
    double ms_mean;
    double contacts_mean; /* touching points after a step */
    int asleep_after;     /* steps until every body slept; -1: never */
    size_t awake_at_end;  /* bodies still awake after the last step */
} timing;

static tb_world *new_world(double gravity, const char *what)
{
    tb_world_def def = tb_default_world_def();
    tb_world *w;
    char message[TB_MESSAGE_SIZE];
    def.gravity[0] = def.gravity[1] = 0;
    def.gravity[2] = -gravity;
    if (tb_world_create(&def, &w, message, sizeof message) != TB_OK) {
        fprintf(stderr, BENCH_NAME ": %s world: %s\n", what, message);
        exit(EXIT_FAILURE);
    }
    return w;
}

static void add_plane(tb_world *w, double friction)
{
    tb_shape_def plane = tb_default_shape_def();
    plane.type = TB_SHAPE_PLANE;
    plane.friction = friction;
    check(tb_world_add_shape(w, &plane, NULL), w, "plane");
}

/* --substeps=N: every scene's contacts with N substeps (-1, without the
   option: the default settings, 4) */
static int substeps = -1;

/* ode_heavy_landing's scene in tumble (the default settings, but for
   --substeps). */
static void tumble_heavy(const ode_heavy_def *d, ode_heavy_result *out)
{
    tb_world *w = new_world(d->gravity, "heavy");
    tb_body_id ids[18];
    const double top = 1.5 + d->under, size[3] = { 1, 1, 1 };
    int i, k, landed = 0;
    memset(out, 0, sizeof *out);
    if (substeps > 0) {
        tb_contact_settings cs = tb_world_contact_settings(w);
        cs.substeps = substeps;
        check(tb_world_set_contact_settings(w, &cs), w, "heavy settings");
    }
    add_plane(w, 0.6);
    for (i = 0; i < d->under + 2 && i < 18; ++i) {
        tb_body_def b = tb_default_body_def();
        tb_shape_def s = tb_default_shape_def();
        check(tb_mass_box(i == d->under + 1 ? d->ratio : 1, size, &b.mass, NULL), w, "heavy mass");
        b.position[2] = 0.5 + i + (i == d->under + 1 ? d->gap : 0);
        check(tb_world_add_body(w, &b, &ids[i]), w, "heavy body");
        s.type = TB_SHAPE_BOX;
        s.body = ids[i];
        s.half_extents[0] = s.half_extents[1] = s.half_extents[2] = 0.5;
        check(tb_world_add_shape(w, &s, NULL), w, "heavy shape");
    }
    for (k = 0; k < d->steps; ++k) {
        double x[3], v[3];
        check(tb_world_step(w, 1 / d->hz), w, "heavy step");
        check(tb_body_position(w, ids[d->under + 1], x), w, "heavy position");
        check(tb_body_velocity(w, ids[d->under + 1], v), w, "heavy velocity");
        landed |= x[2] < top + 0.01;
        if (landed && v[2] > out->rebound)
            out->rebound = v[2];
        out->end = x[2] - top;
        for (i = 0; i <= d->under; ++i) {
            check(tb_body_position(w, ids[i], x), w, "column position");
            if (0.5 + i - x[2] > out->sink)
                out->sink = 0.5 + i - x[2];
        }
    }
    tb_world_destroy(w);
}

/* Steps w `steps` times at h, timing each step alone. watch (or NULL):
   a body whose greatest distance from `from` over the steps goes to
   *farthest, read between the timed steps. */
static void run_timed(tb_world *w, double h, int steps, timing *t, const tb_body_id *watch, const double from[3],
                      double *farthest)
{
    double *ms = xmalloc((size_t)steps * sizeof *ms), sum = 0, contacts = 0;
    int n;
    t->asleep_after = -1;
    for (n = 0; n < steps; ++n) {
        const double t0 = seconds();
        check(tb_world_step(w, h), w, "step");
        ms[n] = 1e3 * (seconds() - t0);
        if (watch) {
            double x[3], d;
            check(tb_body_position(w, *watch, x), w, "watched body");
            d = sqrt((x[0] - from[0]) * (x[0] - from[0]) + (x[1] - from[1]) * (x[1] - from[1]) +
                     (x[2] - from[2]) * (x[2] - from[2]));
            *farthest = n == 0 || d > *farthest ? d : *farthest;
        }
        sum += ms[n];
        contacts += (double)tb_world_contact_count(w);
        if (t->asleep_after < 0 && tb_world_sleeping_count(w) == tb_world_body_count(w))
            t->asleep_after = n + 1;
    }
    t->awake_at_end = tb_world_body_count(w) - tb_world_sleeping_count(w);
    t->ms_mean = sum / steps;
    t->contacts_mean = contacts / steps;
    t->ms_median = median_of(ms, steps);
    free(ms);
}

/* --------------------------------------------------------------- asleep -- */

/* Steps timed once every body sleeps (ASLEEP_STEPS), and the most steps
   waited for that (60 s at 60 Hz). */
#define ASLEEP_STEPS 300
#define ASLEEP_WAIT 3600

/* Steps w until every body sleeps (at most ASLEEP_WAIT steps), then
   `steps` more, each timed alone: their median in ms, or -1 when the
   bodies did not all fall asleep or one woke during the timed steps (a
   figure of a world not asleep). */
static double asleep_ms(tb_world *w, double h, int steps)
{
    double *ms, result;
    int n;
    for (n = 0; n < ASLEEP_WAIT && tb_world_sleeping_count(w) < tb_world_body_count(w); ++n)
        check(tb_world_step(w, h), w, "step to sleep");
    if (tb_world_sleeping_count(w) < tb_world_body_count(w))
        return -1;
    ms = xmalloc((size_t)steps * sizeof *ms);
    for (n = 0; n < steps; ++n) {
        const double t0 = seconds();
        check(tb_world_step(w, h), w, "asleep step");
        ms[n] = 1e3 * (seconds() - t0);
        if (tb_world_sleeping_count(w) < tb_world_body_count(w)) {
            free(ms);
            return -1;
        }
    }
    result = median_of(ms, steps);
    free(ms);
    return result;
}

/* n cubes of `edge` m and 1000 kg/m^3 on the plane in columns of
   `levels`, the columns `pitch` m apart on a square grid, asleep: the ms
   per step (asleep_ms). Columns further apart than the edge are islands of
   their own. */
static double boxes_asleep_ms(int n, int levels, double edge, double pitch)
{
    tb_world *w = new_world(9.81, "sleeping boxes");
    const int columns = (n + levels - 1) / levels, side = (int)ceil(sqrt((double)columns));
    const double size[3] = { edge, edge, edge };
    tb_body_def b = tb_default_body_def();
    tb_shape_def s = tb_default_shape_def();
    double result;
    int i;
    add_plane(w, 0.6);
    check(tb_mass_box(1000, size, &b.mass, NULL), w, "box mass");
    s.type = TB_SHAPE_BOX;
    s.half_extents[0] = s.half_extents[1] = s.half_extents[2] = edge / 2;
    s.friction = 0.6;
    for (i = 0; i < n; ++i) {
        const int column = i / levels;
        b.position[0] = pitch * (column % side), b.position[1] = pitch * (column / side);
        b.position[2] = edge / 2 + edge * (i % levels);
        check(tb_world_add_body(w, &b, &s.body), w, "box");
        check(tb_world_add_shape(w, &s, NULL), w, "box shape");
    }
    result = asleep_ms(w, 1 / 60.0, ASLEEP_STEPS);
    tb_world_destroy(w);
    return result;
}

/* ------------------------------------------------------------- pyramid -- */

typedef struct pyramid_run {
    timing t;
    double sink, drift; /* m, top cube, at the end */
    double farthest;    /* m: the top cube's greatest distance from its start
                           during the run (it sways: the end catches one phase) */
} pyramid_run;

/* Sleep on (the default) or off (every body solved every step). */
static void set_sleep(tb_world *w, int sleep)
{
    tb_contact_settings cs = tb_default_contact_settings();
    if (substeps > 0)
        cs.substeps = substeps;
    if (!sleep)
        cs.sleep_time = INFINITY;
    check(tb_world_set_contact_settings(w, &cs), w, "contact settings");
}

/* asleep (or NULL): after the run, the ms per step once every body sleeps
   (asleep_ms), -1 if they never all did. */
static void tumble_pyramid(const ode_pyramid_def *d, int sleep, pyramid_run *out, double *asleep)
{
    const int count = ode_pyramid_boxes(d->levels);
    const int steps = (int)ceil(d->duration * d->hz);
    double(*pos)[3] = xmalloc((size_t)count * sizeof *pos);
    tb_world *w = new_world(d->gravity, "pyramid");
    tb_body_def b = tb_default_body_def();
    tb_shape_def s = tb_default_shape_def();
    const double size[3] = { d->edge, d->edge, d->edge };
    tb_body_id top = { 0, 0 };
    double x[3];
    int i;

    if (ode_pyramid_positions(d, pos) != count) {
        fprintf(stderr, BENCH_NAME ": pyramid refused\n");
        exit(EXIT_FAILURE);
    }
    set_sleep(w, sleep);
    add_plane(w, d->mu);
    check(tb_mass_box(d->mass / (d->edge * d->edge * d->edge), size, &b.mass, NULL), NULL, "box mass");
    s.type = TB_SHAPE_BOX;
    s.half_extents[0] = s.half_extents[1] = s.half_extents[2] = d->edge / 2;
    s.friction = d->mu;
    for (i = 0; i < count; ++i) { /* ODE's order: the top cube is the last */
        memcpy(b.position, pos[i], sizeof b.position);
        check(tb_world_add_body(w, &b, &top), w, "cube");
        s.body = top;
        check(tb_world_add_shape(w, &s, NULL), w, "cube shape");
    }
    run_timed(w, 1 / d->hz, steps, &out->t, &top, pos[count - 1], &out->farthest);
    check(tb_body_position(w, top, x), w, "top cube");
    out->sink = pos[count - 1][2] - x[2];
    out->drift = hypot(x[0] - pos[count - 1][0], x[1] - pos[count - 1][1]);
    if (asleep)
        *asleep = asleep_ms(w, 1 / d->hz, ASLEEP_STEPS);
    tb_world_destroy(w);
    free(pos);
}

/* ---------------------------------------------------------------- pile -- */

/* Returns how many centres are below the plane at the end: none should
   be (the smallest shape reaches 0.1 m from its centre), so any count
   says the run is not one to time. */
static int tumble_pile(const ode_pile_def *d, const ode_shape *shapes, int sleep, timing *t)
{
    tb_world *w = new_world(d->gravity, "pile");
    const double *x;
    int i, below = 0;
    set_sleep(w, sleep);
    add_plane(w, d->mu);
    for (i = 0; i < d->count * d->copies; ++i) {
        const ode_shape *o = &shapes[i % d->count];
        double offset[2];
        tb_body_def b = tb_default_body_def();
        tb_shape_def s = tb_default_shape_def();
        tb_body_id id;
        /* ODE's numbers, not tumble's own tb_mass_*: the same bodies to the
           last bit. The principal frame is the shape's, so the shape sits at
           the body's origin with no turn of its own. */
        b.mass.mass = o->mass;
        memcpy(b.mass.inertia, o->inertia, sizeof b.mass.inertia);
        b.mass.centre[0] = b.mass.centre[1] = b.mass.centre[2] = 0;
        b.mass.frame[0] = 1, b.mass.frame[1] = b.mass.frame[2] = b.mass.frame[3] = 0;
        memcpy(b.position, o->position, sizeof b.position);
        ode_pile_copy_offset(d, i / d->count, offset); /* (the copies: ODE's places) */
        b.position[0] += offset[0], b.position[1] += offset[1];
        memcpy(b.orientation, o->orientation, sizeof b.orientation);
        check(tb_world_add_body(w, &b, &id), w, "pile body");
        s.body = id;
        s.friction = d->mu;
        switch (o->kind) {
        case ODE_SHAPE_SPHERE:
            s.type = TB_SHAPE_SPHERE;
            s.radius = o->radius;
            break;
        case ODE_SHAPE_BOX:
            s.type = TB_SHAPE_BOX;
            memcpy(s.half_extents, o->half, sizeof s.half_extents);
            break;
        case ODE_SHAPE_CAPSULE: /* both along z; half[2] is half the core */
            s.type = TB_SHAPE_CAPSULE;
            s.radius = o->radius;
            s.half_length = o->half[2];
            break;
        }
        check(tb_world_add_shape(w, &s, NULL), w, "pile shape");
    }
    run_timed(w, 1 / d->hz, d->steps, t, NULL, NULL, NULL);
    x = tb_world_body_positions(w);
    for (i = 0; i < d->count * d->copies; ++i)
        below += x[3 * i + 2] < 0;
    tb_world_destroy(w);
    return below;
}

/* ---------------------------------------------------------------- main -- */

static const char *met(int ok)
{
    return ok ? "met" : "NOT met";
}

/* -------------------------------------------------------------- scaling -- */

/* 16 separate copies of the 1000-shape pile side by side (15 m apart: no
   copy meets another), beside ODE's QuickStep(20) on the same 16 (sleep
   off, 300 steps, one run each): cost per contact point against the
   single pile's, and the ratio to ODE. Non-zero if a run failed. */
static int copies(void)
{
    ode_pile_def d = ode_default_pile_def();
    ode_pile_result r;
    ode_shape *shapes = xmalloc((size_t)d.count * sizeof *shapes);
    timing t;
    int below;
    d.copies = 16, d.steps = 300;
    if (ode_pile_scene(&d, shapes) != d.count) {
        fprintf(stderr, BENCH_NAME ": pile scene refused\n");
        free(shapes);
        return 1;
    }
    below = tumble_pile(&d, shapes, 0, &t);
    free(shapes);
    if (!ode_pile(&d, &r)) {
        fprintf(stderr, BENCH_NAME ": ODE's copies did not run\n");
        return 1;
    }
    printf("copies    16 piles of %d shapes side by side: tumble %.2f ms/step, %.0f contact points per step, %.0f ns "
           "per contact point, centres below the plane %d | ODE %.2f ms/step, %.0f contacts, %.0f ns per contact | "
           "ODE/tumble %.2f (target >= 5)\n",
           d.count, t.ms_mean, t.contacts_mean, 1e6 * t.ms_mean / t.contacts_mean, below, r.timing.ms_mean,
           r.timing.contacts_mean, 1e6 * r.timing.ms_mean / r.timing.contacts_mean, r.timing.ms_mean / t.ms_mean);
    return 0;
}

static int scaling(const char *folder)
{
    static const int counts[3] = { 1000, 4000, 16000 }, grids[3] = { 10, 20, 40 };
    char path[4096];
    FILE *f;
    int k;
    snprintf(path, sizeof path, "%s/contact_scaling.csv", folder);
    if (!(f = fopen(path, "w"))) {
        fprintf(stderr, BENCH_NAME ": cannot write %s\n", path);
        return EXIT_FAILURE;
    }
    printf("tumble contact cost against the pile's size (sleep off, 300 steps at 60 Hz, one run each)\n");
    bench_print_build();
    bench_print_asserts();
    fprintf(f, "shapes,grid,steps,ms_per_step,contacts_per_step,ns_per_contact,below\n");
    for (k = 0; k < 3; ++k) {
        ode_pile_def d = ode_default_pile_def();
        ode_shape *shapes;
        timing t;
        int below;
        d.count = counts[k], d.grid = grids[k], d.steps = 300;
        shapes = xmalloc((size_t)d.count * sizeof *shapes);
        if (ode_pile_scene(&d, shapes) != d.count) {
            fprintf(stderr, BENCH_NAME ": pile scene refused\n");
            return EXIT_FAILURE;
        }
        below = tumble_pile(&d, shapes, 0, &t);
        printf("scaling   %5d shapes (grid %d): %.2f ms/step, %.0f contact points per step, %.0f ns per contact "
               "point, centres below the plane %d\n", d.count, d.grid, t.ms_mean, t.contacts_mean,
               1e6 * t.ms_mean / t.contacts_mean, below);
        fprintf(f, "%d,%d,%d,%.6g,%.6g,%.6g,%d\n", d.count, d.grid, d.steps, t.ms_mean, t.contacts_mean,
                1e6 * t.ms_mean / t.contacts_mean, below);
        fflush(stdout);
        free(shapes);
    }
    if (fclose(f) != 0) {
        fprintf(stderr, BENCH_NAME ": cannot write %s\n", path);
        return EXIT_FAILURE;
    }
    printf("wrote %s\n", path);
    return copies() ? EXIT_FAILURE : EXIT_SUCCESS;
}

/* The asleep lines: the ms per step once every body sleeps, one run each
   (`bench_contacts --sleep` prints them alone): the pyramid; a block of
   1000 unit cubes, 10 levels of 10 x 10 columns 1 cm apart, 100 islands
   of 10 (it stands in for the pile, which does not fall asleep: see
   "sleep" above); and 1000 and 10000
   separate cubes of 0.5 m, 1 m apart, each an island of its own, whose
   difference is the cost of a sleeping body. */
static void asleep_lines(void)
{
    const ode_pyramid_def pd = ode_default_pyramid_def();
    static const int counts[2] = { 1000, 10000 };
    pyramid_run pyr;
    double ms, each[2];
    int k;
    bullet_run bullet;
    tumble_pyramid(&pd, 1, &pyr, &ms);
    if (!bullet_pyramid(&pd, 1, ASLEEP_STEPS, &bullet))
        bullet.asleep_ms = -1, bullet.asleep_after = -1;
    printf("asleep    pyramid %d boxes, every body asleep: %.4f ms/step (median of %d steps after all slept at step "
           "%d; -1: not asleep) | Bullet %s %.4f ms/step (asleep at step %d) | MuJoCo 0.033 (issue 18's figure)\n",
           ode_pyramid_boxes(pd.levels), ms, ASLEEP_STEPS, pyr.t.asleep_after, TB_BENCH_BULLET, bullet.asleep_ms,
           bullet.asleep_after);
    fflush(stdout);
    ms = boxes_asleep_ms(1000, 10, 1, 1.01);
    printf("asleep    block of 1000 cubes (10 levels of 10 x 10, an island a column), every body asleep: %.4f ms/step "
           "(median of %d steps)\n", ms, ASLEEP_STEPS);
    fflush(stdout);
    for (k = 0; k < 2; ++k)
        each[k] = boxes_asleep_ms(counts[k], 1, 0.5, 1);
    printf("asleep    %d separate cubes asleep: %.4f ms/step, %d: %.4f ms/step (medians of %d steps), "
           "%.1f ns per sleeping body (from the difference)\n",
           counts[0], each[0], counts[1], each[1], ASLEEP_STEPS,
           1e6 * (each[1] - each[0]) / (counts[1] - counts[0]));
}

int main(int argc, char **argv)
{
    const ode_pyramid_def pd = ode_default_pyramid_def();
    const ode_pile_def ld = ode_default_pile_def();
    ode_shape *shapes = xmalloc((size_t)ld.count * sizeof *shapes);
    /* per run: tumble, ODE; medians of steps for the pyramid, means for
       the pile */
    double pyr_ms[BENCH_RUNS], pyr_ode_ms[BENCH_RUNS], pyr_ode_mean[BENCH_RUNS];
    double pyr_sleep_ms[BENCH_RUNS], pile_sleep_ms[BENCH_RUNS], pyr_ode_sleep_ms[BENCH_RUNS];
    /* Bullet's, the same runs: the pyramid awake (median) and with sleep
       (mean), the pile awake (mean, median) */
    double pyr_bullet_ms[BENCH_RUNS], pyr_bullet_sleep_ms[BENCH_RUNS], pile_bullet_ms[BENCH_RUNS],
        pile_bullet_median_ms[BENCH_RUNS];
    bullet_run pyr_bullet, pyr_bullet_sleep, pile_bullet;
    double pile_ms[BENCH_RUNS], pile_median_ms[BENCH_RUNS], pile_ode_ms[BENCH_RUNS], pile_ode_median_ms[BENCH_RUNS];
    pyramid_run pyr, pyr_sleep;
    ode_pyramid_result pyr_ode, pyr_ode_sleep;
    ode_pyramid_def pd_sleep = pd;
    timing pile, pile_sleep;
    ode_pile_result pile_ode;
    double t_ms, o_ms, ratio;
    int r, below = 0;

    if (argc >= 2 && !strncmp(argv[argc - 1], "--substeps=", 11)) {
        substeps = atoi(argv[argc - 1] + 11);
        --argc;
        if (substeps < 1) {
            fprintf(stderr, BENCH_NAME ": --substeps must be 1 or more\n");
            free(shapes);
            return 2;
        }
    }
    if (argc == 3 && !strcmp(argv[1], "--scaling")) {
        free(shapes);
        return scaling(argv[2]);
    }
    if (argc == 2 && !strcmp(argv[1], "--sleep")) {
        free(shapes);
        asleep_lines();
        return 0;
    }
    if (argc != 1) {
        fprintf(stderr, "usage: " BENCH_NAME " [--scaling FOLDER | --sleep] [--substeps=N]\n");
        free(shapes);
        return 2;
    }

    printf("tumble contacts beside ODE %s (double) and Bullet %s (float): medians over %d alternating runs of each "
           "scene\n", TB_BENCH_ODE, TB_BENCH_BULLET,
           BENCH_RUNS);
    bench_print_build();
    bench_print_asserts();
    printf("soft-step solver: %d substeps\n", substeps > 0 ? substeps : tb_default_contact_settings().substeps);
    printf("\n");
    fflush(stdout);

    /* The scenes are deterministic: sink, drift and contact counts are the
       same in every run, so the last run's are printed. */
    for (r = 0; r < BENCH_RUNS; ++r) {
        tumble_pyramid(&pd, 0, &pyr, NULL);
        if (!ode_pyramid(&pd, &pyr_ode)) {
            fprintf(stderr, BENCH_NAME ": ODE pyramid refused or failed\n");
            return EXIT_FAILURE;
        }
        if (!bullet_pyramid(&pd, 0, 0, &pyr_bullet) || !bullet_pyramid(&pd, 1, 0, &pyr_bullet_sleep)) {
            fprintf(stderr, BENCH_NAME ": Bullet pyramid refused or failed\n");
            return EXIT_FAILURE;
        }
        pyr_bullet_ms[r] = pyr_bullet.ms_median;
        pyr_bullet_sleep_ms[r] = pyr_bullet_sleep.ms_mean;
        tumble_pyramid(&pd, 1, &pyr_sleep, NULL);
        pd_sleep.auto_disable = 1;
        if (!ode_pyramid(&pd_sleep, &pyr_ode_sleep)) {
            fprintf(stderr, BENCH_NAME ": ODE pyramid with auto-disable refused or failed\n");
            return EXIT_FAILURE;
        }
        pyr_ode_sleep_ms[r] = pyr_ode_sleep.timing.ms_mean;
        pyr_ms[r] = pyr.t.ms_median;
        pyr_sleep_ms[r] = pyr_sleep.t.ms_mean;
        pyr_ode_ms[r] = pyr_ode.timing.ms_median;
        pyr_ode_mean[r] = pyr_ode.timing.ms_mean;
    }
    t_ms = median_of(pyr_ms, BENCH_RUNS);
    o_ms = median_of(pyr_ode_ms, BENCH_RUNS);
    ratio = o_ms / t_ms;
    printf("pyramid   %d boxes  awake (sleep off) tumble %5.2f ms/step (median of steps over %g s)  top box sink %.3f m drift %.3f m | "
           "ODE QuickStep(%d) %.2f ms/step sink %.3f m drift %.3f m | ODE/tumble %.1f (target >= 5): %s  "
           "top box within 1 cm throughout (farthest %.3f m): %s\n",
           ode_pyramid_boxes(pd.levels), t_ms, pd.duration, pyr.sink, pyr.drift, pd.iterations, o_ms,
           pyr_ode.top_sink, pyr_ode.top_drift, ratio, met(ratio >= 5), pyr.farthest, met(pyr.farthest <= 0.01));
    t_ms = median_of(pyr_sleep_ms, BENCH_RUNS);
    o_ms = median_of(pyr_ode_sleep_ms, BENCH_RUNS);
    printf("pyramid   %d boxes  default (sleep on) tumble %5.2f ms/step (mean over %g s; median %.3f), all asleep after "
           "%d steps, top box sink %.3f m drift %.3f m | ODE with its auto-disable %.2f ms/step (mean; without %.2f), "
           "sink %.3f m drift %.3f m | ODE/tumble %.1f (target >= 5): %s  top box within 1 cm throughout (farthest %.3f m): %s\n",
           ode_pyramid_boxes(pd.levels), t_ms, pd.duration, pyr_sleep.t.ms_median, pyr_sleep.t.asleep_after,
           pyr_sleep.sink, pyr_sleep.drift, o_ms, median_of(pyr_ode_mean, BENCH_RUNS), pyr_ode_sleep.top_sink,
           pyr_ode_sleep.top_drift, o_ms / t_ms, met(o_ms / t_ms >= 5), pyr_sleep.farthest, met(pyr_sleep.farthest <= 0.01));
    printf("pyramid   %d boxes  Bullet %s: awake %.2f ms/step (median), %.0f contact points, top box sink %.3f m drift "
           "%.3f m | Bullet/tumble %.1f; sleep on %.2f ms/step (mean), all asleep after %d steps, top box sink %.3f m | "
           "Bullet/tumble %.1f\n",
           ode_pyramid_boxes(pd.levels), TB_BENCH_BULLET, median_of(pyr_bullet_ms, BENCH_RUNS), pyr_bullet.contacts_mean,
           pyr_bullet.top_sink, pyr_bullet.top_drift, median_of(pyr_bullet_ms, BENCH_RUNS) / median_of(pyr_ms, BENCH_RUNS),
           median_of(pyr_bullet_sleep_ms, BENCH_RUNS), pyr_bullet_sleep.asleep_after, pyr_bullet_sleep.top_sink,
           median_of(pyr_bullet_sleep_ms, BENCH_RUNS) / t_ms);
    fflush(stdout);

    if (ode_pile_scene(&ld, shapes) != ld.count) {
        fprintf(stderr, BENCH_NAME ": pile scene refused\n");
        return EXIT_FAILURE;
    }
    for (r = 0; r < BENCH_RUNS; ++r) {
        below = tumble_pile(&ld, shapes, 0, &pile);
        below += tumble_pile(&ld, shapes, 1, &pile_sleep);
        pile_sleep_ms[r] = pile_sleep.ms_mean;
        if (!ode_pile(&ld, &pile_ode)) {
            fprintf(stderr, BENCH_NAME ": ODE pile refused or failed\n");
            return EXIT_FAILURE;
        }
        pile_ms[r] = pile.ms_mean;
        pile_median_ms[r] = pile.ms_median;
        pile_ode_ms[r] = pile_ode.timing.ms_mean;
        pile_ode_median_ms[r] = pile_ode.timing.ms_median;
        if (!bullet_pile(&ld, shapes, 0, &pile_bullet)) {
            fprintf(stderr, BENCH_NAME ": Bullet pile refused or failed\n");
            return EXIT_FAILURE;
        }
        pile_bullet_ms[r] = pile_bullet.ms_mean;
        pile_bullet_median_ms[r] = pile_bullet.ms_median;
    }
    t_ms = median_of(pile_ms, BENCH_RUNS);
    o_ms = median_of(pile_ode_ms, BENCH_RUNS);
    printf("pile      %d shapes awake (sleep off) tumble %.2f ms/step (mean of %d steps; median %.2f), contacts per step %.0f, "
           "centres below the plane at the end %d%s | ODE %.2f ms/step (median %.2f), contacts %.0f | ODE/tumble %.1f "
           "(target >= 5): %s\n",
           ld.count, t_ms, ld.steps, median_of(pile_median_ms, BENCH_RUNS), pile.contacts_mean, below,
           below ? " (sank through the plane)" : "", o_ms, median_of(pile_ode_median_ms, BENCH_RUNS),
           pile_ode.timing.contacts_mean, o_ms / t_ms, met(o_ms / t_ms >= 5));
    printf("pile      %d shapes Bullet %s: awake %.2f ms/step (mean; median %.2f), %.0f contact points, centres below "
           "the plane at the end %d | Bullet/tumble %.1f (target >= 3): %s\n",
           ld.count, TB_BENCH_BULLET, median_of(pile_bullet_ms, BENCH_RUNS), median_of(pile_bullet_median_ms, BENCH_RUNS),
           pile_bullet.contacts_mean, pile_bullet.below, median_of(pile_bullet_ms, BENCH_RUNS) / t_ms,
           met(median_of(pile_bullet_ms, BENCH_RUNS) / t_ms >= 3));
    t_ms = median_of(pile_sleep_ms, BENCH_RUNS);
    printf("pile      %d shapes default (sleep on) tumble %.2f ms/step (mean of %d steps; median %.3f), all asleep after "
           "%d steps (-1: not within the run; awake at the end: %zu) | ODE/tumble %.1f\n",
           ld.count, t_ms, ld.steps, pile_sleep.ms_median, pile_sleep.asleep_after, pile_sleep.awake_at_end,
           o_ms / t_ms);

    fflush(stdout);
    asleep_lines();
    fflush(stdout);

    /* the whole step's time over its points and substeps */
    {
        const int n = substeps > 0 ? substeps : tb_default_contact_settings().substeps;
        printf("contacts  ns per contact point per substep, for the whole step (collision, integration, solve, "
               "events): pile %.1f (%.0f points x %d substeps), pyramid %.1f (%.0f points) (Box2D v3 publishes about "
               "%d ns per contact per substep, 2D float)\n",
               1e6 * median_of(pile_ms, BENCH_RUNS) / (pile.contacts_mean * n), pile.contacts_mean, n,
               1e6 * median_of(pyr_ms, BENCH_RUNS) / (pyr.t.contacts_mean * n), pyr.t.contacts_mean,
               BOX2D_NS_PER_CONTACT);
    }
    {
        static const struct {
            double ratio;
            int under;
        } heavy[] = { { 10, 0 }, { 100, 0 }, { 1000, 0 }, { 10000, 0 }, { 100, 3 }, { 1000, 3 } };
        size_t i;
        for (i = 0; i < sizeof heavy / sizeof heavy[0]; ++i) {
            ode_heavy_def hd = ode_default_heavy_def();
            ode_heavy_result tr, orr;
            hd.ratio = heavy[i].ratio;
            hd.under = heavy[i].under;
            tumble_heavy(&hd, &tr);
            if (!ode_heavy_landing(&hd, &orr)) {
                fprintf(stderr, BENCH_NAME ": ODE heavy landing refused or failed\n");
                return EXIT_FAILURE;
            }
            printf("heavy     box %5.0f times heavier dropped 0.5 m on %d light: tumble ends %+.2e m from its place, rose "
                   "at %.2f m/s, a light box went %.2e m under its own | ODE QuickStep(20) %+.2e m, %.2f m/s, %.2e m\n",
                   hd.ratio, hd.under + 1, tr.end, tr.rebound, tr.sink, orr.end, orr.rebound, orr.sink);
        }
    }
    free(shapes);
    return 0;
}
