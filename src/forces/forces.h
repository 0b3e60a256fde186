/* forces.h: what acts on the particles and bodies (not public): springs
   between particles or to anchors (springs.c), velocity fields that carry
   tracers (fields.c), and user force callbacks (forces.c). */
#ifndef TB_FORCES_H
#define TB_FORCES_H

#include "world.h"

/* A spring's second end when it is a fixed point, not a particle slot. */
#define TB__ANCHOR UINT32_MAX

typedef enum tb__field_kind { TB__FIELD_UNIFORM, TB__FIELD_VORTEX, TB__FIELD_CALLBACK } tb__field_kind;

typedef struct tb__field {
    tb__field_kind kind;
    double a[3];           /* uniform: velocity; vortex: omega */
    double b[3];           /* vortex: centre */
    tb_field_fn *fn;
    void *user;
} tb__field;

typedef struct tb__force {
    tb_force_fn *fn;
    void *user;
} tb__force;

/* ---- springs.c ----------------------------------------------------------- */
void tb__spring_forces(const tb_world *w, const double *pos, const double *vel, double *force);
/* out = K u, the springs' stiffness matrix at pos times u (definite: only
   the part that is positive semi-definite, for conjugate gradients). */
void tb__spring_stiffness_product(const tb_world *w, const double *pos, const double *u, double *out, int definite);
/* out = C u, the springs' damping matrix at pos times u. */
void tb__spring_damping_product(const tb_world *w, const double *pos, const double *u, double *out);
double tb__spring_energy(const tb_world *w, const double *pos);
void tb__springs_free(tb_world *w);

/* ---- fields.c -------------------------------------------------------------- */
/* vel = the sum of the fields at the n positions pos, at time t. */
tb_status tb__field_velocities(tb_world *w, double t, size_t n, const double *pos, double *vel);
/* dy = F(t, y) for the tracers: their velocities are the fields'. */
tb_status tb__tracer_derive(tb_world *w, double t, const double *y, double *dy);

/* ---- forces.c -------------------------------------------------------------- */
/* Forces not local to one object (springs, callbacks) at positions from y,
   velocities from seen, into w->particle_force and w->body_force. */
tb_status tb__global_forces(tb_world *w, double t, const double *y, const double *seen);
/* The force callbacks at the current state with tb_force_args.potential
   set: *potential gains what they report; their forces are thrown away. */
tb_status tb__force_potential(tb_world *w, double *potential);

#endif
