/* workprecision.h: what the parts of bench_workprecision share (main.c
   describes the program). One job a file:
   - scenes.c: the reference scenes and their truths;
   - runs.c: the methods, and one run of a scene in tumble or ODE: building
     it, advancing it, its final state and its error;
   - sweeps.c: the step and tolerance sweeps of a scene, their timing, the
     fitted orders and the costs read off the curves;
   - report.c: the CSV, gnuplot's meta file, the printed figures and the
     verdicts on the adaptive target;
   - main.c: the order of it all.

   Every file includes this header before any other: it defines
   _POSIX_C_SOURCE, which bench.h's clock needs ahead of every system
   header. */
#ifndef TB_BENCH_WORKPRECISION_H
#define TB_BENCH_WORKPRECISION_H

#define _POSIX_C_SOURCE 200809L
#define BENCH_NAME "bench_workprecision"

#include "bench.h"
#include "tumble.h"

#include <stddef.h>
#include <stdio.h>

#define MAX_POINTS 16        /* points of a fixed-step sweep, at most */
#define TOLERANCES 21        /* 1e-2 ... 1e-12 by factors of sqrt 10 */
#define SLOTS 21             /* points a curve holds: max(MAX_POINTS, TOLERANCES) */
#define FLOOR 1e-12          /* below this, errors are rounding, not method */
#define MAX_PARTICLES 64
#define PLAN_SIZE 16         /* bytes for the name of the method auto chose */
#define MAX_SAMPLES 9        /* timing samples of a point, at most */
#define SCENE_COUNT 11

/* ------------------------------------------------------------ scenes -- */

enum kind { PARTICLES, TRACER, BODY, PENDULUM };

/* PENDULUM: a sphere of PENDULUM_RADIUS and PENDULUM_MASS whose centre
   hangs PENDULUM_LENGTH from a hinge at the origin (axis y), released at
   rest at the scene's pendulum_start from the bottom, under gravity g */
#define PENDULUM_RADIUS 0.05 /* m */
#define PENDULUM_MASS 1.0    /* kg */
#define PENDULUM_LENGTH 1.0  /* m */

typedef struct spring_spec {
    int a, b;            /* particle indices; b < 0: tied to `anchor` */
    double anchor[3];    /* m */
    double k, c, rest;   /* N/m, N s/m, m */
} spring_spec;

/* Everything a particle scene holds, in one description that builds both
   the tumble world and the ODE world, so the two engines see one scene. */
typedef struct particle_system {
    size_t n;
    double x0[3 * MAX_PARTICLES], v0[3 * MAX_PARTICLES], mass[MAX_PARTICLES]; /* m, m/s, kg */
    int pinned[MAX_PARTICLES];
    size_t springs;
    spring_spec *spring;
    double gravity[3];       /* m/s^2 */
    double quadratic_drag;   /* N s^2/m^2 */
    double gm;               /* m^3/s^2: > 0 adds -gm m x / |x|^3 towards the origin (a force callback) */
} particle_system;

typedef struct scene {
    const char *name;        /* the CSV's and the charts' key */
    const char *title;       /* chart title */
    const char *short_title; /* panel title in the overview */
    const char *error_label; /* chart y label */
    const char *truth;       /* how the truth is known, printed */
    enum kind kind;
    double duration;         /* s */
    long coarse;             /* N0: steps of the coarsest run */
    long reference_steps;    /* > 0: converged reference by rk4 at this many steps */
    int ode;                 /* the scene can be built in ODE */
    int stiff;               /* stiff springs: not in the adaptive target (it is about smooth scenes) */
    int limits;              /* the chart marks each method's stability limit (the advisor's) */
    double scale;            /* m: position errors are divided by it */
    double floor;            /* errors below this are the scene's rounding, not the method's (0: FLOOR) */
    particle_system ps;      /* PARTICLES */
    double tracer_x0[3];     /* TRACER: m */
    double vortex[3];        /* TRACER: rad/s, about the origin */
    double inertia[3];       /* BODY: kg m^2, principal; 1 kg, q0 = identity, at rest, no gravity */
    double omega0[3];        /* BODY: rad/s, body frame = world frame at t = 0 */
    double pendulum_start;   /* PENDULUM: rad from the bottom */
    double gravity;          /* PENDULUM: m/s^2, along -z */
    double final[3 * MAX_PARTICLES]; /* the truth at t = T: positions, or a quaternion */
    double reference_gap;    /* converged references: error measure between N and N/2 */
} scene;

/* Fills `scenes` (SCENE_COUNT of them) and returns how many it made. */
int make_scenes(scene *scenes);
void free_scenes(scene *scenes, int count);

/* The truth of a scene without a closed form (reference_steps > 0). */
void reference(scene *s);

/* ------------------------------------------------------- methods, runs -- */

typedef struct series {
    const char *name;        /* tumble's integrator name, or "ode" */
    const char *label;       /* for the legend */
    int evaluations;         /* force evaluations per step (adaptive: counted per run) */
    int adaptive;            /* swept over the tolerance at the outer step T / N0, not over h */
    int ode;
} series;

/* ODE last: the ODE comparison and the legend strip rely on it. */
enum { SERIES_COUNT = 9, SYMPLECTIC_EULER = 1, RK4 = 3, DOPRI5 = 6, AUTO = 7, ODE = SERIES_COUNT - 1 };
extern const series SERIES[SERIES_COUNT];

int refused(const scene *s, const series *m, char *message, size_t size);
double error_of(const scene *s, const double *state, const double *truth);
double timed_run(const scene *s, const series *m, double h, long n, double tolerance, long *done, double *state,
                 char *plan, long *substeps);
double counted_evaluations(const scene *s, double h, long n, double tolerance);
double advised_limit(const scene *s, const series *m);

/* ------------------------------------------------------------ sweeps -- */

typedef struct point {
    long steps, done;                   /* asked for, and done before a refusal or a stop */
    double h, error, cost, evaluations; /* s, -, s per simulated s, per simulated s */
    double tolerance;                   /* adaptive methods; 0 for fixed steps */
    char plan[PLAN_SIZE];               /* auto: the method it chose */
    long substeps;                      /* auto: its substeps per outer step */
    int stable;
    double first;                       /* wall time of the first run, s */
    int want, count, repeat;            /* timing samples wanted and taken; runs per sample */
    double sample[MAX_SAMPLES];         /* s of stepping per run */
} point;

typedef struct curve {
    int used;                /* the method applies to the scene */
    int adaptive;            /* points are tolerances at one outer step, not steps */
    int count;
    point p[SLOTS];
    double order;            /* fitted slope of log error against log h; NaN: none (and
                                for tolerance sweeps, which have no h to fit against) */
    int at_floor;            /* there are stable points and all are below the floor */
} curve;

void sweep_scene(const scene *s, double floor_error, curve curves[SERIES_COUNT], char *refusals, size_t size);
void timing(const scene *s, curve curves[SERIES_COUNT]);
double sweep_tolerance(int i);
int stable_points(const curve *c);
double cost_at(const curve *c, double target, int evaluations, int *bound);
double cost_extrapolated(const curve *c, double target);
int cheapest_fixed(const curve curves[SERIES_COUNT], double target, double *cost, int *bound);

/* ------------------------------------------------------------ report -- */

/* The adaptive target, tallied over the smooth scenes: per method (auto,
   dopri5), lines met, NOT met, and without a fixed-step method to compare
   with (none reaches the error the adaptive run achieved). */
enum { MET, NOT_MET, NO_COMPARISON };
typedef struct tally {
    int count[2][3];
    char missed[8192];       /* the NOT met lines, for the summary */
} tally;

int open_outputs(const char *dir, const scene *scenes, int count, FILE **csv, FILE **meta);
int close_outputs(const char *dir, FILE *csv, FILE *meta);
void print_header(void);
void write_csv(FILE *f, const scene *s, const curve curves[SERIES_COUNT]);
void write_meta(FILE *f, const scene *s, const curve curves[SERIES_COUNT]);
int print_figures(const scene *s, const curve curves[SERIES_COUNT], const char *refusals, char *summary,
                  size_t size);
void print_adaptive(const scene *s, const curve curves[SERIES_COUNT], tally *t);
void print_summary(int losses, const char *summary, const tally *t);

#endif
