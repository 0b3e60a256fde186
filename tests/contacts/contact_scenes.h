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

/* Uniform in [0, 1) from a 64-bit LCG (Knuth's MMIX constants). */
double uniform(uint64_t *state);

/* Sleep off: tests of the solver's own resting behaviour. */
void awake(tb_world *w);

#endif
