/* contact_scenes.h: what the contact tests (test_contacts_*.c) build their
   scenes from: a world on a plane, unit boxes and balls of 1 kg, random
   numbers, sleep switched off. */
#ifndef TB_CONTACT_SCENES_H
#define TB_CONTACT_SCENES_H

#include "tumble.h"

#include <stdint.h>

static const double G = 9.81;

/* A world under gravity (0, 0, -G) with a static plane z = 0 of the
   given friction and restitution. */
tb_world *world_on_plane(double friction, double restitution);

/* A box of edge `edge` and 1 kg at centre, its shape of the given friction. */
tb_body_id add_box(tb_world *w, const double centre[3], double edge, double friction);

/* A ball of the given radius and 1 kg at centre, its shape of the given
   restitution. */
tb_body_id add_ball(tb_world *w, const double centre[3], double radius, double restitution);

/* Steps ball `id` (radius r) at rate hz until it has passed two apexes,
   at most 4 s. For each, `sampled` (may be NULL) is the height of its
   lowest point at the first step past the top (ODE's reading) and `top`
   the top of the ballistic arc through the last rising step, z + v^2 / 2g
   (exact between contacts). Returns how many apexes it saw. */
int ball_apexes(tb_world *w, tb_body_id id, double r, double hz, double sampled[2], double top[2]);

/* A box (type TB_SHAPE_BOX, edge `size`) or ball (diameter `size`) of
   density 1 at `at`, moving at v and spinning at spin (NULL: none). */
tb_body_id add_solid(tb_world *w, tb_shape_type type, const double at[3], const double v[3], const double spin[3],
                     double size);

/* A 1 m cube (1 kg) set on a plane, both mu = 0.5, pushed at 5 m/s along
   x and stepped at hz with `substeps` substeps until it
   stops (3 s at most): the distance it slid. kept: the world and the box
   are handed back instead of destroyed. */
double slide(double hz, int substeps, tb_world **kept, tb_body_id *box);

/* A unit cube (1 kg, I_z = 1/6 kg m^2) set on a plane, both mu = 0.5,
   spun at 10 rad/s about the vertical and stepped 12 times at 60 Hz with
   `substeps`: the world, the box, and the closed-form spin after those
   steps under a twist friction of mu m g r (r = sqrt(1/2) m),
   10 - 12 mu g r h / I_z. */
tb_world *spun_box(int substeps, tb_body_id *box, double *expected);

/* Uniform in [0, 1) from a 64-bit LCG (Knuth's MMIX constants). */
double uniform(uint64_t *state);

/* Sleep off: tests of the solver's own resting behaviour. */
void awake(tb_world *w);

/* Steps w for `seconds` at steps of h, or of h and h / 3 in turn (a
   game's frame times changing). */
void step_changing(tb_world *w, double seconds, double h, int changing);

/* How far the worst box of a column of 10 unit boxes (mu 0.6, sleep off)
   is from where it was put after 10 s of step_changing, with `substeps`
   substeps. */
double column_after(double h, int changing, int substeps);

#endif
