/* run_plot.h: a run's energy, momentum and contacts over time, drawn by
   gnuplot as one PNG, for `tumble run --plot`. What it draws is in
   docs/command.md, "The plot". */
#ifndef RUN_PLOT_H
#define RUN_PLOT_H

#include "tumble.h"

typedef struct run_plot run_plot;

/* Whether a gnuplot executable is on PATH. */
int plot_gnuplot_found(void);
/* An empty record; NULL when out of memory. */
run_plot *plot_begin(void);
/* Add the world's figures now (tb_world_energy, tb_world_momentum,
   tb_world_angular_momentum, tb_world_contact_count,
   tb_world_deepest_overlap). 0, or -1 when out of memory. */
int plot_record(run_plot *p, const tb_world *w);
/* Have gnuplot draw the record into png_path (an existing file it
   overwrites), titled `title`, with the contacts' panel when `contacts`.
   0, or -1 with a one-line reason in why. */
int plot_draw(const run_plot *p, const char *png_path, const char *title, int contacts, char *why, size_t size);
void plot_free(run_plot *p);

#endif
