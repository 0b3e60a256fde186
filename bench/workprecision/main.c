/* bench_workprecision: how much accuracy each integrator buys for its cost, on
   reference scenes with a known truth, beside ODE's dWorldStep.

   For every scene, every applicable fixed-step method runs over a geometric
   sweep of step sizes h = T / N (N doubling from the scene's coarsest N0, so
   every run ends exactly at T). The adaptive methods ("dopri5", "auto") run
   instead over a sweep of the world tolerance, 1e-2 down to 1e-12 by
   factors of sqrt 10, at one fixed outer step H = T / N0: the coarsest step
   of the fixed sweeps. That outer step is the one fixed-step runs can
   never exceed, so an adaptive method there has the same freedom as they
   have and the comparison at equal error measures its controller or plan,
   not the outer step: a display frame of 1/60 s instead would put a floor
   of 60 steps per simulated second under the adaptive methods that the
   fixed sweeps do not have (Verlet is exact to rounding on the symmetric
   top at 2 steps/s), and on the stiff scenes N0 is finer than 1/60 s
   anyway. For each run it records:
   - error: the scene's error measure at t = T against the truth (closed
     form, or a converged reference computed here and checked by halving);
   - seconds_per_sim_second: median wall time of the stepping alone (world
     built and freed outside the clock) divided by T. The first run of a
     point gives its error and warms up; then 9, 5 or 3 timing samples
     (fewer for longer runs), each repeating a short run until it holds 2 ms
     of stepping. Samples are taken in rounds over all points of a scene,
     so a burst of noise from the machine spreads over many points instead
     of landing on every sample of one;
   - evaluations_per_sim_second: force evaluations per simulated second
     (euler 1, symplectic_euler 1, verlet 2, verlet_exact 2, rk4 4,
     implicit_euler 1 plus its linear solve, per step; dWorldStep 1).
     dopri5's are counted, rejected substeps included, by a force callback
     that adds nothing, in a separate untimed run (a force of zero leaves
     the trajectory the same to the bit); auto's follow from its plan
     (tb_world_auto_choice), or are counted as dopri5's when it chose that;
   - stable: 0 when the final state is not finite, the error exceeds 1, or
     a step is refused (tumble) or stopped by the run's guard (ODE). Such
     runs are kept and drawn, not dropped: where a method fails is part of
     the chart.

   A fixed-step series stops, once it has MIN_POINTS points, when its error
   is below the floor (1e-12, where rounding takes over, a scene's own
   where its steps' rounding adds up to more (the pendulum's projections:
   1e-10), or ten times a converged reference's own uncertainty); and in
   any case when the next
   run would take more than RUN_CAP seconds, or after MAX_POINTS points. A
   tolerance sweep stops below the floor once it has passed tolerance 1e-9,
   or at RUN_CAP. RUN_CAP keeps the whole to a few minutes; it also makes
   how far a sweep reaches, and so the cheapest method at an error level,
   depend on the machine's speed.

   Methods a scene's world refuses (the split methods, implicit_euler among
   them, on the tracer, which has no velocity to kick) are left out, with
   the world's reason printed.

   Output (the directory is the first argument, default bench/out):
   - workprecision.csv: scene, method, h, error, seconds_per_sim_second,
     evaluations_per_sim_second, stable, tolerance (0 for fixed steps),
     plan (what auto chose: method x substeps per outer step);
   - workprecision_meta.gp: titles, axis labels and legend entries with the
     fitted orders, loaded by bench/workprecision.gp, which draws the charts;
   - on stdout, per scene and per error level 1e-2 ... 1e-10: tumble's
     cheapest fixed-step method and its cost, ODE's cost, and their ratio
     (costs interpolated along each method's curve in log-log); then, per
     scene and tolerance 1e-3, 1e-6 and 1e-9, each adaptive run's error and
     cost against the cheapest fixed-step method at the error it achieved,
     and whether it is within ADAPTIVE_TARGET times that cost (the issue's
     target, counted on the smooth scenes: all but the stiff chains and
     cloth, whose lines are printed but not counted). On the damped
     chain, each fixed-step method's legend gives the advisor's damped
     stability limit, which the chart marks (report.c, write_meta).

   Errors are dimensionless: positions are divided by the scene's length
   scale (stated per scene), orientations are angles in radians.

   The scenes are the Lua scripts of scenes/reference/ built in C (same
   numbers; the scripts document each truth). ODE builds every scene but
   the tracer (ODE has no massless points moved by a field): gravity as its
   world setting, every other force added with dBodyAddForce before each
   dWorldStep, as an ODE user would.

   The parts of the program, one job a file, are listed in
   workprecision.h. */
#include "workprecision.h"

#include <ode/ode.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "bench/out";
    scene scenes[SCENE_COUNT];
    curve *curves;
    char summary[4096] = "";
    static tally adaptive; /* zeroed; large */
    FILE *csv, *meta;
    int i, count, losses = 0;
    double t0 = seconds();

    count = make_scenes(scenes);
    if (!open_outputs(dir, scenes, count, &csv, &meta))
        return EXIT_FAILURE;
    print_header();
    dInitODE2(0);
    curves = xmalloc((size_t)count * SERIES_COUNT * sizeof *curves);
    for (i = 0; i < count; ++i) {
        scene *s = &scenes[i];
        curve *c = curves + (size_t)i * SERIES_COUNT;
        double floor_error = fmax(FLOOR, s->floor);
        char refusals[1024];
        fprintf(stderr, "%s\n", s->name);
        if (s->reference_steps > 0) {
            reference(s);
            floor_error = fmax(floor_error, 10 * s->reference_gap);
        }
        sweep_scene(s, floor_error, c, refusals, sizeof refusals);
        timing(s, c);
        write_csv(csv, s, c);
        write_meta(meta, s, c);
        losses += print_figures(s, c, refusals, summary, sizeof summary);
        print_adaptive(s, c, &adaptive);
    }
    dCloseODE();

    print_summary(losses, summary, &adaptive);
    printf("\nwrote %s/workprecision.csv and %s/workprecision_meta.gp in %.0f s\n", dir, dir, seconds() - t0);
    free_scenes(scenes, count);
    free(curves);
    return close_outputs(dir, csv, meta) ? 0 : EXIT_FAILURE;
}
