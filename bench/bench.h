/* bench.h: what the benchmark programs share. Every function is static
   inline, so a program that does not use one pays nothing and gets no
   warning for it.

   A program defines BENCH_NAME (its executable's name, for messages)
   before including this header, and _POSIX_C_SOURCE (for clock_gettime)
   before any header.

   - the build it measures: TB_BENCH_COMPILER, TB_BENCH_BUILD and
     TB_BENCH_ODE come from bench/CMakeLists.txt; bench_print_build()
     prints the cpu, compiler and build lines of every program's header,
     bench_print_asserts() the asserts line;
   - seconds(), a monotonic clock; median_of() and compare_doubles();
   - keep(x): folds a result into a volatile sink, so no work is dead;
   - xmalloc() and check(): out of memory and a refused tumble call end
     the program with a message;
   - uniform(): reproducible pseudo-random numbers;
   - norm3(), qmul() and angle_between() on 3-vectors and quaternions;
   - bench_case and measure(): the interleaved repeats of
     bench/particles.c and bench/bodies.c, and median() of a case. */
#ifndef TB_BENCH_H
#define TB_BENCH_H

#include "tumble.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifndef BENCH_NAME
#error "define BENCH_NAME (the program's name, for messages) before including bench.h"
#endif

/* ------------------------------------------------------------- the build -- */

#ifndef TB_BENCH_COMPILER
#ifdef __VERSION__
#define TB_BENCH_COMPILER "cc " __VERSION__
#else
#define TB_BENCH_COMPILER "unknown compiler"
#endif
#endif
#ifndef TB_BENCH_ODE
#define TB_BENCH_ODE "?"
#endif

/* The cpu, compiler and build lines of a program's header. */
static inline void bench_print_build(void)
{
    char line[256], cpu[256] = "unknown";
    FILE *f = fopen("/proc/cpuinfo", "r");
    while (f && fgets(line, sizeof line, f)) {
        char *colon = strchr(line, ':');
        if (strncmp(line, "model name", 10) == 0 && colon) {
            strncpy(cpu, colon + 2, sizeof cpu - 1);
            cpu[strcspn(cpu, "\n")] = 0;
            break;
        }
    }
    if (f)
        fclose(f);
    printf("cpu       %s\n", cpu);
    printf("compiler  %s\n", TB_BENCH_COMPILER);
#ifdef TB_BENCH_BUILD
    printf("build     %s\n", TB_BENCH_BUILD);
#else
    printf("build     flags not passed in (TB_BENCH_BUILD); this file: %s, %s\n",
#ifdef __OPTIMIZE__
           "optimised",
#else
           "NOT optimised",
#endif
#ifdef __FAST_MATH__
           "-ffast-math"
#else
           "no -ffast-math"
#endif
    );
#endif
}

static inline void bench_print_asserts(void)
{
#ifdef NDEBUG
    printf("asserts   off (NDEBUG)\n");
#else
    printf("asserts   on\n");
#endif
}

/* ------------------------------------------------------------ utilities -- */

static inline double seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static inline int compare_doubles(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The median of x[0..n), which it sorts. */
static inline double median_of(double *x, int n)
{
    qsort(x, (size_t)n, sizeof *x, compare_doubles);
    return x[n / 2];
}

/* Results are folded in here so that no work is dead. */
static inline void keep(double x)
{
    static volatile double sink;
    sink = sink + x;
}

static inline void *xmalloc(size_t size)
{
    void *p = malloc(size ? size : 1);
    if (!p) {
        fprintf(stderr, BENCH_NAME ": out of memory (%zu bytes)\n", size);
        exit(EXIT_FAILURE);
    }
    return p;
}

static inline void check(tb_status st, const tb_world *w, const char *what)
{
    if (st != TB_OK) {
        fprintf(stderr, BENCH_NAME ": %s: %s: %s\n", what, tb_status_name(st), w ? tb_world_message(w) : "");
        exit(EXIT_FAILURE);
    }
}

/* Reproducible pseudo-random numbers in [0, 1) (xorshift64*), so that every
   run and ODE start from the same state. */
static inline double uniform(unsigned long long *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (double)((*s * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}

/* ---------------------------------------------- vectors and quaternions -- */

static inline double norm3(const double a[3])
{
    return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}

/* out = a b for quaternions (w, x, y, z); out may be a or b. */
static inline void qmul(const double a[4], const double b[4], double out[4])
{
    double r[4];
    r[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    r[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    r[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    r[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    memcpy(out, r, sizeof r);
}

/* Angle of a^-1 b for unit quaternions, 2 atan2(|vector part|, |scalar
   part|): acos of the dot product loses everything below 1e-7 rad
   (docs/notes.md), and these errors go down to 1e-13. */
static inline double angle_between(const double a[4], const double b[4])
{
    const double s = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    const double x = a[0] * b[1] - a[1] * b[0] - a[2] * b[3] + a[3] * b[2];
    const double y = a[0] * b[2] + a[1] * b[3] - a[2] * b[0] - a[3] * b[1];
    const double z = a[0] * b[3] - a[1] * b[2] + a[2] * b[1] - a[3] * b[0];
    return 2 * atan2(sqrt(x * x + y * y + z * z), fabs(s));
}

/* ------------------------------------------------- interleaved repeats -- */

/* Figures are medians over BENCH_REPEATS repeats of about
   BENCH_REPEAT_SECONDS each: long enough to dwarf the clock, short enough
   for a whole program in well under a minute. measure() interleaves the
   repeats of all its cases, so noise from the machine (other processes,
   frequency changes) falls on every case alike and each ratio compares
   figures taken moments apart. */
#define BENCH_REPEATS 7
#define BENCH_REPEAT_SECONDS 0.1

typedef void run_fn(void *ctx, long steps);

typedef struct bench_case {
    run_fn *run;
    void *ctx;
    double items;              /* particles or bodies per step */
    long steps;                /* per repeat, set by calibrate() */
    double ns[BENCH_REPEATS];  /* ns per item-step, one per repeat */
} bench_case;

static inline double time_run(const bench_case *c, long steps)
{
    const double t0 = seconds();
    c->run(c->ctx, steps);
    return seconds() - t0;
}

/* Warm up (page faults, caches, scratch arrays, branch predictors) and
   choose the steps per repeat: double them until a run takes 20 ms, then
   scale to BENCH_REPEAT_SECONDS. */
static inline void calibrate(bench_case *c)
{
    long steps = 1;
    double s;
    while ((s = time_run(c, steps)) < 0.02)
        steps *= 2;
    c->steps = (long)((double)steps * BENCH_REPEAT_SECONDS / s);
    if (c->steps < 1)
        c->steps = 1;
}

static inline void measure(bench_case *cases, int n)
{
    int r, i;
    for (i = 0; i < n; ++i)
        calibrate(&cases[i]);
    for (r = 0; r < BENCH_REPEATS; ++r)
        for (i = 0; i < n; ++i)
            cases[i].ns[r] = 1e9 * time_run(&cases[i], cases[i].steps) / ((double)cases[i].steps * cases[i].items);
}

/* The median ns per item-step of a measured case. */
static inline double median(const bench_case *c)
{
    double x[BENCH_REPEATS];
    memcpy(x, c->ns, sizeof x);
    return median_of(x, BENCH_REPEATS);
}

#endif
