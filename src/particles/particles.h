/* particles.h: the cheap tiers (not public): tracers, massless points
   carried by the velocity fields (tracers.c), and particles, point masses
   with forces (particles.c). Their state is in y (core/core.h); a
   particle's constants and its force accumulator are the world's
   particle_* arrays. */
#ifndef TB_PARTICLES_H
#define TB_PARTICLES_H

#include "world.h"

/* dy = F(t, y) for the particles: dx/dt = v, dv/dt = (global force + local
   forces) / m, the global forces already in w->particle_force. */
void tb__particle_derive(tb_world *w, const double *y, double *dy);
/* The split methods' kicks and drifts over every particle. */
void tb__particle_sweep(tb_world *w, const tb__split_op *ops, int n);
/* Whether a particle force depends on velocity (drag). */
int tb__particle_velocity_dependent(const tb_world *w);

#endif
