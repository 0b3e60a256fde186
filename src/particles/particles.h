/* particles.h: the cheap tiers (not public): tracers, massless points
   carried by the velocity fields (tracers.c), and particles, point masses
   with forces (particles.c; their kernels in particle_step.c). Their state is in y (core/core.h); a
   particle's constants and its force accumulator are the world's
   particle_* arrays. */
#ifndef TB_PARTICLES_H
#define TB_PARTICLES_H

#include "world.h"

/* dy = F(t, y) for the particles: dx/dt = v, dv/dt = (global force + local
   forces) / m, the global forces already in w->particle_force
   (particle_step.c, as the rest of this list). */
void tb__particle_derive(tb_world *w, const double *y, double *dy);
/* dv/dt of particle slot s at velocity v: its local forces and, when
   ready, w->particle_force, over its mass (0 when pinned). */
void tb__particle_acceleration(const tb_world *w, size_t s, const double v[3], double out[3]);
/* The split methods' kicks and drifts over every particle: the one-pass
   kernel where it applies, else the general blocked sweep. */
void tb__particle_sweep(tb_world *w, const tb__split_op *ops, int n);
/* The one-pass kernel on instruction set isa (tb__isa() or below), when
   only local forces act, seen at the velocity being kicked, and ops is a
   kick, a kick and a drift, or those and a predicted closing kick. Returns
   whether it applied (0: nothing was done). */
int tb__particle_one_pass(tb_world *w, const tb__split_op *ops, int n, int isa);
/* The general sweep over blocks of particles, for any ops and forces; the
   one-pass kernel gives its bits (test_particle_step). */
void tb__particle_sweep_blocked(tb_world *w, const tb__split_op *ops, int n);
/* The drag's power on the particles (W, <= 0), summed as the one-pass
   kernel sums it (particle_step.c). */
double tb__particle_drag_power(const tb_world *w);
/* Whether a particle force depends on velocity (drag). */
int tb__particle_velocity_dependent(const tb_world *w);

#endif
