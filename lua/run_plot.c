/* run_plot.c: `tumble run --plot FILE.png`. Each recorded frame keeps the
   world's energy terms, momenta and contacts (plot_record); at the end
   gnuplot draws them (plot_draw): the script and the data, as a
   datablock, go down a pipe to `gnuplot`, which writes a 1000 x 900 PNG
   (pngcairo) of two panels, or three with contacts:
   1. energy, J: kinetic (translational and rotational), potential
      (gravity and springs) and their total;
   2. momentum: |P| (kg m/s, left axis) and |L| about the origin
      (kg m^2/s, right axis);
   3. with shapes: the points of contact (left axis) and the deepest
      overlap in mm (right axis), as the last step found them.
   A series that never changes gets a range of its value +- 1 (gnuplot
   would warn of an empty range otherwise). Nothing here needs a file of
   its own: gnuplot writes the PNG where the caller says. */
#define _POSIX_C_SOURCE 200809L /* popen, pclose */
#include "run_plot.h"

#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

enum { T, KINETIC, POTENTIAL, TOTAL, LINEAR, ANGULAR, CONTACTS, OVERLAP, COLUMNS };

struct run_plot {
    double *rows; /* [frames * COLUMNS] */
    size_t frames, cap;
};

int plot_gnuplot_found(void)
{
    const char *path = getenv("PATH"), *p, *end;
    char file[4200];
    if (!path)
        return 0;
    for (p = path; *p; p = *end ? end + 1 : end) {
        end = strchr(p, ':');
        if (!end)
            end = p + strlen(p);
        snprintf(file, sizeof file, "%.*s/gnuplot", end == p ? 1 : (int)(end - p), end == p ? "." : p);
        if (access(file, X_OK) == 0)
            return 1;
    }
    return 0;
}

run_plot *plot_begin(void)
{
    return calloc(1, sizeof(run_plot));
}

void plot_free(run_plot *p)
{
    if (p)
        free(p->rows);
    free(p);
}

int plot_record(run_plot *p, const tb_world *w)
{
    const tb_energy e = tb_world_energy(w);
    double m[3], l[3], *row;
    if (p->frames == p->cap) {
        const size_t cap = p->cap ? 2 * p->cap : 256;
        double *more = cap > ((size_t)-1) / (COLUMNS * sizeof(double)) ? NULL
                                                                       : realloc(p->rows, cap * COLUMNS * sizeof(double));
        if (!more)
            return -1;
        p->rows = more;
        p->cap = cap;
    }
    tb_world_momentum(w, m);
    tb_world_angular_momentum(w, l);
    row = p->rows + COLUMNS * p->frames++;
    row[T] = tb_world_time(w);
    row[KINETIC] = e.kinetic + e.rotational;
    row[POTENTIAL] = e.gravity + e.spring;
    row[TOTAL] = e.total;
    row[LINEAR] = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    row[ANGULAR] = sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
    row[CONTACTS] = (double)tb_world_contact_count(w);
    row[OVERLAP] = 1e3 * tb_world_deepest_overlap(w); /* mm */
    return 0;
}

/* s as a gnuplot string in single quotes, where a quote is doubled. */
static void put_quoted(FILE *g, const char *s)
{
    fputc('\'', g);
    for (; *s; ++s) {
        if (*s == '\'')
            fputc('\'', g);
        if (*s != '\n')
            fputc(*s, g);
    }
    fputc('\'', g);
}

/* `set AXISrange [lo:hi]` over columns [first, last]: their extent, or
   their value +- 1 when they never change. */
static void put_range(FILE *g, const run_plot *p, const char *axis, int first, int last)
{
    double lo = HUGE_VAL, hi = -HUGE_VAL;
    size_t f;
    int c;
    for (f = 0; f < p->frames; ++f)
        for (c = first; c <= last; ++c) {
            const double v = p->rows[COLUMNS * f + c];
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
    if (!(hi > lo)) {
        lo -= 1, hi += 1;
        fprintf(g, "set %srange [%.9g:%.9g]\n", axis, lo, hi);
    } else {
        fprintf(g, "set %srange [*:*]\n", axis);
    }
}

int plot_draw(const run_plot *p, const char *png_path, const char *title, int contacts, char *why, size_t size)
{
    void (*old_pipe)(int);
    FILE *g;
    size_t f;
    int status, written;
    if (!p->frames) {
        snprintf(why, size, "no frame was recorded");
        return -1;
    }
    /* gnuplot dying early must not kill the command with SIGPIPE */
    old_pipe = signal(SIGPIPE, SIG_IGN);
    g = popen("gnuplot", "w");
    if (!g) {
        signal(SIGPIPE, old_pipe);
        snprintf(why, size, "cannot start gnuplot");
        return -1;
    }
    fprintf(g, "set terminal pngcairo size 1000,900 noenhanced font ',10'\nset output ");
    put_quoted(g, png_path);
    fprintf(g, "\n$run << EOD\n");
    for (f = 0; f < p->frames; ++f) {
        const double *r = p->rows + COLUMNS * f;
        fprintf(g, "%.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", r[T], r[KINETIC], r[POTENTIAL], r[TOTAL], r[LINEAR],
                r[ANGULAR], r[CONTACTS], r[OVERLAP]);
    }
    fprintf(g, "EOD\nset multiplot layout %d,1 title ", contacts ? 3 : 2);
    put_quoted(g, title);
    fprintf(g, "\nset grid\nset key top right opaque\nset xlabel 't (s)'\n");
    put_range(g, p, "x", T, T);
    put_range(g, p, "y", KINETIC, TOTAL);
    fprintf(g, "set ylabel 'energy (J)'\n"
               "plot $run using 1:2 with lines lw 2 title 'kinetic', '' using 1:3 with lines lw 2 title "
               "'potential', '' using 1:4 with lines lw 2 dt 2 title 'total'\n");
    put_range(g, p, "y", LINEAR, LINEAR);
    put_range(g, p, "y2", ANGULAR, ANGULAR);
    fprintf(g, "set ylabel 'linear momentum |P| (kg m/s)'\nset y2label 'angular momentum |L| (kg m^2/s)'\n"
               "set ytics nomirror\nset y2tics\n"
               "plot $run using 1:5 with lines lw 2 title '|P|', '' using 1:6 axes x1y2 with lines lw 2 title '|L|'\n");
    if (contacts) {
        put_range(g, p, "y", CONTACTS, CONTACTS);
        put_range(g, p, "y2", OVERLAP, OVERLAP);
        fprintf(g, "set ylabel 'points of contact'\nset y2label 'deepest overlap (mm)'\n"
                   "plot $run using 1:7 with steps lw 2 title 'contacts', '' using 1:8 axes x1y2 with lines lw 2 "
                   "title 'deepest overlap'\n");
    }
    fprintf(g, "unset multiplot\nset output\n");
    written = !ferror(g);
    status = pclose(g);
    signal(SIGPIPE, old_pipe);
    if (!written || status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        if (status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 127)
            snprintf(why, size, "gnuplot could not be run (not on PATH?)");
        else
            snprintf(why, size, "gnuplot failed (%s %d); its messages are above", status != -1 && WIFSIGNALED(status)
                     ? "signal" : "exit status", status == -1 ? -1 : WIFSIGNALED(status) ? WTERMSIG(status)
                     : WEXITSTATUS(status));
        return -1;
    }
    return 0;
}
