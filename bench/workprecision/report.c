/* report.c: what the benchmark writes: the CSV of every run, gnuplot's
   meta file (titles, labels, legends) for bench/workprecision.gp, and on
   stdout the header, each scene's figures against ODE and the verdicts on
   the adaptive target. */
#include "workprecision.h"

#include <ode/ode.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#define ADAPTIVE_TARGET 2.0  /* the target: adaptive cost <= 2x the best fixed-step cost at its error */

/* The header of stdout: what is compared, the build, how costs are
   measured, and the library's integrators that the benchmark does not
   measure. */
void print_header(void)
{
    int i, m;
    printf("tumble work-precision: error at the final time against cost, beside ODE %s (%s)\n", TB_BENCH_ODE,
           dCheckConfiguration("ODE_double_precision") ? "double" : "NOT double");
    bench_print_build();
    bench_print_asserts();
    printf("cost      median wall time of the steps per simulated second (s/s); evaluations per simulated s\n"
           "          (euler 1, symplectic_euler 1, verlet 2, verlet_exact 2, rk4 4, implicit_euler 1 and a\n"
           "          linear solve, dWorldStep 1 per step; dopri5 counted; auto by its plan)\n"
           "          fixed-step methods sweep h = T/N0, T/2N0, ...; dopri5 and auto sweep the tolerance\n"
           "          1e-2 ... 1e-12 at the outer step h = T/N0 (the coarsest fixed step)\n"
           "          costs at an error level are interpolated in log-log along each method's curve;\n"
           "          '<=' marks a method already below the level at its coarsest stable step (an upper\n"
           "          bound); a ratio '~' compares two such runs, the cheapest stable ones; figures in\n"
           "          (~...) extrapolate ODE beyond its finest run along its fitted order (not measured)\n\n");
    /* Integrators the library has beyond those measured here. */
    for (i = 0; tb_integrator_name(i); ++i) {
        for (m = 0; m < ODE && strcmp(tb_integrator_name(i), SERIES[m].name); ++m)
            ;
        if (m == ODE)
            printf("note      integrator '%s' is not in this benchmark yet\n\n", tb_integrator_name(i));
    }
}

/* `dir`, made if it is missing; 0 when it cannot be. */
static int ensure_dir(const char *dir)
{
    if (mkdir(dir, 0777) == 0 || errno == EEXIST)
        return 1;
    fprintf(stderr, "bench_workprecision: cannot create '%s': %s\n", dir, strerror(errno));
    return 0;
}

/* workprecision.csv and workprecision_meta.gp in `dir`, created, with
   their first lines. 0 when they cannot be written (the reason on stderr). */
int open_outputs(const char *dir, const scene *scenes, int count, FILE **csv, FILE **meta)
{
    char path[4096];
    int i;
    if (!ensure_dir(dir))
        return 0;
    snprintf(path, sizeof path, "%s/workprecision.csv", dir);
    *csv = fopen(path, "w");
    snprintf(path, sizeof path, "%s/workprecision_meta.gp", dir);
    *meta = fopen(path, "w");
    if (!*csv || !*meta) {
        fprintf(stderr, "bench_workprecision: cannot write into '%s'\n", dir);
        return 0;
    }
    fprintf(*csv, "scene,method,h,error,seconds_per_sim_second,evaluations_per_sim_second,stable,tolerance,plan\n");
    fprintf(*meta, "# written by bench_workprecision: titles, labels and legends for bench/workprecision.gp\n");
    fprintf(*meta, "scenes = '");
    for (i = 0; i < count; ++i)
        fprintf(*meta, "%s%s", i ? " " : "", scenes[i].name);
    fprintf(*meta, "'\n");
    return 1;
}

/* Closes both files; 0 when either has an error (the reason on stderr). */
int close_outputs(const char *dir, FILE *csv, FILE *meta)
{
    if (ferror(csv) | fclose(csv) | ferror(meta) | fclose(meta)) {
        fprintf(stderr, "bench_workprecision: error writing into '%s'\n", dir);
        return 0;
    }
    return 1;
}

/* One row per run of the scene (main.c lists the columns). */
void write_csv(FILE *f, const scene *s, const curve curves[SERIES_COUNT])
{
    int m, i;
    for (m = 0; m < SERIES_COUNT; ++m)
        for (i = 0; curves[m].used && i < curves[m].count; ++i) {
            const point *p = &curves[m].p[i];
            fprintf(f, "%s,%s,%.17g,%.6e,%.6e,%.6e,%d,%.3g,", s->name, SERIES[m].name, p->h, p->error, p->cost,
                    p->evaluations, p->stable, p->tolerance);
            if (p->plan[0])
                fprintf(f, "%s x %ld", p->plan, p->substeps);
            fputc('\n', f);
        }
}

/* name = 'text' as gnuplot reads it: a quote inside single quotes is
   doubled. */
static void gp_string(FILE *f, const char *prefix, const char *name, const char *text)
{
    fprintf(f, "%s_%s = '", prefix, name);
    for (; *text; ++text) {
        if (*text == '\'')
            fputc('\'', f);
        fputc(*text, f);
    }
    fputs("'\n", f);
}

/* Wall seconds per step of a fixed-step curve: the median over its stable
   points of cost x h (cost is per simulated second); NaN without one. */
static double seconds_per_step(const curve *c)
{
    double v[SLOTS], t;
    int i, j, n = 0;
    for (i = 0; i < c->count; ++i)
        if (c->p[i].stable)
            v[n++] = c->p[i].cost * c->p[i].h;
    for (i = 1; i < n; ++i) /* insertion sort: a handful of points */
        for (j = i; j > 0 && v[j - 1] > v[j]; --j)
            t = v[j], v[j] = v[j - 1], v[j - 1] = t;
    return n ? (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2])) : NAN;
}

/* Legends and labels for bench/workprecision.gp, one variable per string;
   gnuplot reads them back with value("name"). On a scene that marks
   stability limits, each fixed-step method's advised limit h_max goes into
   its legend, and where it is finite and the method has stable runs, the
   cost a run at h_max would have (seconds per step / h_max, on the chart's
   axis) into limit_SCENE_METHOD, its name into limited_SCENE. ODE's
   dWorldStep gets symplectic Euler's limit, the same method. */
void write_meta(FILE *f, const scene *s, const curve curves[SERIES_COUNT])
{
    char limited[256] = "";
    int m;
    gp_string(f, "title", s->name, s->title);
    gp_string(f, "short", s->name, s->short_title);
    gp_string(f, "ylabel", s->name, s->error_label);
    fprintf(f, "methods_%s = '", s->name);
    for (m = 0; m < SERIES_COUNT; ++m)
        if (curves[m].used)
            fprintf(f, "%s%s", m ? " " : "", SERIES[m].name);
    fprintf(f, "'\n");
    for (m = 0; m < SERIES_COUNT; ++m) {
        const curve *c = &curves[m];
        if (!c->used)
            continue;
        if (c->adaptive) /* the slope against evaluations is no order when auto switches methods */
            fprintf(f, "key_%s_%s = '%s: tol sweep, h = %.3g s%s'\n", s->name, SERIES[m].name, SERIES[m].label,
                    s->duration / (double)s->coarse, stable_points(c) ? "" : " (no run with error <= 1)");
        else if (s->limits) {
            /* dWorldStep is symplectic Euler (test_ode): its limit is that one's */
            const series *as = SERIES[m].ode ? &SERIES[SYMPLECTIC_EULER] : &SERIES[m];
            const double h = advised_limit(s, as), step = seconds_per_step(c);
            char order[32] = "order n/a";
            if (isfinite(c->order))
                snprintf(order, sizeof order, "order %.1f", c->order);
            if (h > 0 && isfinite(h) && isfinite(step)) {
                const size_t used = strlen(limited);
                fprintf(f, "limit_%s_%s = %.6e\n", s->name, SERIES[m].name, step / h);
                snprintf(limited + used, sizeof limited - used, "%s%s", used ? " " : "", SERIES[m].name);
            }
            if (h > 0 && isfinite(h))
                fprintf(f, "key_%s_%s = '%s: %s, limit h %.3g ms'\n", s->name, SERIES[m].name, SERIES[m].label,
                        order, 1e3 * h);
            else
                fprintf(f, "key_%s_%s = '%s: %s, %s'\n", s->name, SERIES[m].name, SERIES[m].label, order,
                        h == 0 ? "no stable step" : "no limit");
        } else if (isfinite(c->order))
            fprintf(f, "key_%s_%s = '%s: order %.1f'\n", s->name, SERIES[m].name, SERIES[m].label, c->order);
        else if (c->at_floor)
            fprintf(f, "key_%s_%s = '%s: exact to rounding'\n", s->name, SERIES[m].name, SERIES[m].label);
        else if (!stable_points(c))
            fprintf(f, "key_%s_%s = '%s: no run with error <= 1'\n", s->name, SERIES[m].name, SERIES[m].label);
        else
            fprintf(f, "key_%s_%s = '%s: order n/a'\n", s->name, SERIES[m].name, SERIES[m].label);
    }
    if (limited[0])
        fprintf(f, "limited_%s = '%s'\n", s->name, limited);
}

/* The figures of one scene: its fitted orders, then per error level
   tumble's cheapest fixed-step method and its cost, ODE's cost and their
   ratio. Returns the number of error levels at which tumble's cheapest
   fixed-step method is not cheaper than ODE (listed in `summary`). */
int print_figures(const scene *s, const curve curves[SERIES_COUNT], const char *refusals, char *summary,
                  size_t size)
{
    static const double levels[] = { 1e-2, 1e-4, 1e-6, 1e-8, 1e-10 };
    const curve *ode = curves[ODE].used ? &curves[ODE] : NULL;
    int l, m, losses = 0;
    printf("%s: %s\n", s->name, s->title);
    printf("  truth: %s\n", s->truth);
    if (refusals[0])
        printf("  left out: %s\n", refusals);
    printf("  fitted orders:");
    for (m = 0; m < SERIES_COUNT; ++m)
        if (curves[m].used && !curves[m].adaptive) {
            if (isfinite(curves[m].order))
                printf(" %s %.2f;", SERIES[m].name, curves[m].order);
            else
                printf(" %s %s;", SERIES[m].name,
                       curves[m].at_floor ? "rounding" : !stable_points(&curves[m]) ? "no stable run" : "n/a");
        }
    printf("\n");
    printf("  %-7s %-16s %12s %12s %14s %14s\n", "error", "cheapest fixed", "cost s/s", "evals/s", "ODE cost s/s",
           "ODE/tumble");
    for (l = 0; l < (int)(sizeof levels / sizeof levels[0]); ++l) {
        int best_bound = 0, ode_bound = 0, extrapolated = 0, b;
        double best_cost = NAN, ode_cost = NAN, evals = NAN;
        char cost_text[32], ode_text[48], ratio_text[48];
        const int best = cheapest_fixed(curves, levels[l], &best_cost, &best_bound);
        if (best >= 0)
            evals = cost_at(&curves[best], levels[l], 1, &b);
        if (ode) {
            ode_cost = cost_at(ode, levels[l], 0, &ode_bound);
            if (!isfinite(ode_cost)) {
                ode_cost = cost_extrapolated(ode, levels[l]);
                extrapolated = isfinite(ode_cost);
            }
        }
        if (best >= 0)
            snprintf(cost_text, sizeof cost_text, "%s%.3g", best_bound ? "<=" : "", best_cost);
        else
            snprintf(cost_text, sizeof cost_text, "-");
        if (!ode)
            snprintf(ode_text, sizeof ode_text, "(no ODE)");
        else if (isfinite(ode_cost))
            snprintf(ode_text, sizeof ode_text, "%s%.3g%s", extrapolated ? "(~" : ode_bound ? "<=" : "", ode_cost,
                     extrapolated ? ")" : "");
        else
            snprintf(ode_text, sizeof ode_text, "not reached");
        ratio_text[0] = 0;
        if (best >= 0 && ode && isfinite(ode_cost)) {
            const double ratio = ode_cost / best_cost;
            /* An upper bound on tumble's cost makes the ratio a lower bound,
               one on ODE's an upper bound; with both, it compares the two
               cheapest stable runs ("~"). */
            snprintf(ratio_text, sizeof ratio_text, "%s%.3g%s%s",
                     extrapolated ? "(~" : best_bound ? (ode_bound ? "~" : ">=") : (ode_bound ? "<=" : ""), ratio,
                     extrapolated ? ")" : "", ratio <= 1 ? "  NOT cheaper" : "");
            if (ratio <= 1) {
                size_t used = strlen(summary);
                snprintf(summary + used, size - used, "  %s at %.0e: %s %.3g s/s, ODE %.3g s/s%s (ratio %.3g)\n",
                         s->name, levels[l], SERIES[best].name, best_cost, ode_cost,
                         extrapolated ? " extrapolated" : "", ratio);
                ++losses;
            }
        } else if (best >= 0 && ode) {
            snprintf(ratio_text, sizeof ratio_text, "ODE not reached");
        }
        if (best >= 0)
            printf("  %-7.0e %-16s %12s %12.3g %14s %14s%s\n", levels[l], SERIES[best].name, cost_text, evals,
                   ode_text, ratio_text, levels[l] < 10 * s->reference_gap ? "  (below the reference's accuracy)" : "");
        else
            printf("  %-7.0e %-16s %12s %12s %14s\n", levels[l], "not reached", "-", "-", ode_text);
    }
    printf("\n");
    return losses;
}

/* One adaptive run against the cheapest fixed-step method at the error it
   achieved; writes "<method>(plan): error E cost C s/s" into `run`, the
   fixed method and its cost into `fixed`, and the ratio into `ratio`.
   Returns MET, NOT_MET or NO_COMPARISON. */
static int judge(const scene *s, const curve curves[SERIES_COUNT], int a, int i, char *run, char *fixed,
                 char *ratio, size_t size)
{
    const curve *c = &curves[a];
    const point *p = i < c->count ? &c->p[i] : NULL;
    char plan[48] = "";
    double fixed_cost = NAN, r;
    int bound = 0, best;
    if (p && p->plan[0])
        snprintf(plan, sizeof plan, "(%s x %ld)", p->plan, p->substeps);
    if (!p) {
        snprintf(run, size, "%s: not run (RUN_CAP)", SERIES[a].name);
        snprintf(fixed, size, "-");
        snprintf(ratio, size, "%s -", SERIES[a].name);
        return NOT_MET;
    }
    if (!p->stable) {
        snprintf(run, size, "%s%s: FAILED (error %.2g%s)", SERIES[a].name, plan, p->error,
                 p->done < p->steps ? ", a step refused" : "");
        snprintf(fixed, size, "-");
        snprintf(ratio, size, "%s -", SERIES[a].name);
        return NOT_MET;
    }
    snprintf(run, size, "%s%s: error %.2g cost %.2g s/s%s", SERIES[a].name, plan, p->error, p->cost,
             p->error < 10 * s->reference_gap ? " (below the reference's accuracy)" : "");
    best = cheapest_fixed(curves, p->error, &fixed_cost, &bound);
    if (best < 0) {
        snprintf(fixed, size, "none reaches %.2g", p->error);
        snprintf(ratio, size, "%s n/a", SERIES[a].name);
        return NO_COMPARISON;
    }
    r = p->cost / fixed_cost;
    /* a bound on the fixed cost (already below that error at its coarsest
       stable step) makes the ratio a lower bound */
    snprintf(fixed, size, "%s %s%.2g", SERIES[best].name, bound ? "<=" : "", fixed_cost);
    snprintf(ratio, size, "%s %s%.2g", SERIES[a].name, bound ? ">=" : "", r);
    return r <= ADAPTIVE_TARGET ? MET : NOT_MET;
}

/* Per tolerance 1e-3, 1e-6 and 1e-9: auto and dopri5 against the cheapest
   fixed-step method at the error each achieved (interpolated along the
   fixed methods' measured curves, never extrapolated). Stiff scenes are
   printed but not counted. */
void print_adaptive(const scene *s, const curve curves[SERIES_COUNT], tally *t)
{
    static const int levels[] = { 2, 8, 14 }; /* indices of 1e-3, 1e-6, 1e-9 in the sweep */
    static const char *const verdicts[] = { "met", "NOT met", "no fixed method to compare" };
    static const int methods[2] = { AUTO, DOPRI5 };
    int l, k;
    if (!curves[AUTO].used && !curves[DOPRI5].used)
        return;
    for (l = 0; l < (int)(sizeof levels / sizeof levels[0]); ++l) {
        char run[2][160], fixed[2][160], ratio[2][160]; /* one size: judge() gets one */
        int verdict[2];
        for (k = 0; k < 2; ++k)
            verdict[k] = judge(s, curves, methods[k], levels[l], run[k], fixed[k], ratio[k], sizeof run[k]);
        printf("adaptive  %s  tol %.0e  %s | %s | best fixed at those errors: %s, %s s/s | "
               "ratio %s %s (target <= %g): auto %s, dopri5 %s%s\n",
               s->name, sweep_tolerance(levels[l]), run[0], run[1], fixed[0], fixed[1], ratio[0], ratio[1],
               ADAPTIVE_TARGET, verdicts[verdict[0]], verdicts[verdict[1]], s->stiff ? "  [stiff scene: not counted]" : "");
        if (s->stiff)
            continue;
        for (k = 0; k < 2; ++k)
            ++t->count[k][verdict[k]];
        if (verdict[0] == NOT_MET || verdict[1] == NOT_MET) {
            size_t used = strlen(t->missed);
            snprintf(t->missed + used, sizeof t->missed - used, "  %s tol %.0e:%s%s\n", s->name,
                     sweep_tolerance(levels[l]), verdict[0] == NOT_MET ? " auto" : "",
                     verdict[1] == NOT_MET ? " dopri5" : "");
        }
    }
    /* A plan that the tolerance does not move (a rate it cannot see, such
       as quadratic drag from rest) can pass the cost target while ignoring
       the tolerance: say so when the error stays put from 1e-3 to 1e-9 and
       is far above what local errors of 1e-9 per outer step add up to (the
       factor 1000 covers the different norms of error and tolerance). */
    if (curves[AUTO].count > levels[2]) {
        const point *loose = &curves[AUTO].p[levels[0]], *tight = &curves[AUTO].p[levels[2]];
        if (loose->stable && tight->stable && tight->error > 0.5 * loose->error &&
            tight->error > 1000 * (double)tight->steps * tight->tolerance)
            printf("note      %s: auto ignores the tolerance here: error %.2g at 1e-3 (%s x %ld) and %.2g at "
                   "1e-9 (%s x %ld), over %ld outer steps\n", s->name, loose->error, loose->plan, loose->substeps,
                   tight->error, tight->plan, tight->substeps, tight->steps);
    }
    printf("\n");
}

/* The closing lines: the levels at which tumble is not cheaper than ODE,
   and the tally of the adaptive target. */
void print_summary(int losses, const char *summary, const tally *t)
{
    int m;
    if (losses)
        printf("not cheaper than ODE (tumble's cheapest fixed-step method against dWorldStep):\n%s", summary);
    else
        printf("tumble's cheapest fixed-step method is cheaper than ODE at every error level that both reach\n");
    printf("\nadaptive target: cost <= %g x the cheapest fixed-step method at the error reached, tolerances\n"
           "1e-3, 1e-6 and 1e-9, smooth scenes (all but the stiff ones: chain, damped_chain, cloth):\n",
           ADAPTIVE_TARGET);
    for (m = 0; m < 2; ++m)
        printf("  %-6s met %d, NOT met %d, no fixed method reaching its error %d\n", m ? "dopri5" : "auto",
               t->count[m][MET], t->count[m][NOT_MET], t->count[m][NO_COMPARISON]);
    if (t->missed[0])
        printf("NOT met:\n%s", t->missed);
}
