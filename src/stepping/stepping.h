/* stepping.h: the step and its methods (not public): the step driver and
   the primitives the methods are written in (step.c), the integrators
   (integrators.c, implicit.c), the automatic choice of method (auto.c),
   the stability advisor (advisor.c), the blow-up guard (guard.c) and the
   energy and momentum diagnostics (diagnostics.c). The methods know
   nothing of tracers, particles or bodies: they call the primitives,
   which each tier supplies its part of. */
#ifndef TB_STEPPING_H
#define TB_STEPPING_H

#include "world.h"

/* ---- integrators.c ------------------------------------------------------- */
const tb__method *tb__method_find(const char *name);
const tb__method *tb__method_at(int index); /* NULL past the end */
/* m->step, counting a fixed-step method's substep (the adaptive ones count
   their own) in w->work. */
tb_status tb__method_step(tb_world *w, const tb__method *m, double h);
/* Whether the world's method moves the particles in one sweep of their
   one-pass kernel this step, with nothing else velocity-dependent: then
   that sweep can sum the drag's power (w->damping_sums). */
int tb__one_pass_step(const tb_world *w);

/* ---- the primitives (step.c) ----------------------------------------------- */
/* dy = F(t, y), the whole state's derivative. */
tb_status tb__derive(tb_world *w, double t, const double *y, double *dy);
/* Put y back on its constraints after a generic stage (unit quaternions). */
void tb__project(tb_world *w, double *y);
/* RK4 fused: when nothing couples objects (no springs, no callbacks), each
   object's derivative depends on the object alone, so the step can go
   object by object through all four stages, with the generic method's
   arithmetic (the same bits) but none of its passes over the whole state.
   1 when it stepped the world, 0 when the world needs the generic method
   (coupling forces, or objects of a tier that offers no fused step: only
   bodies offer one, tb__body_rk4). */
int tb__fused_rk4(tb_world *w, double h);
/* Split methods: kicks and drifts. tb__split_prepare evaluates the forces
   that are not local to one object (springs, callbacks) at the current
   positions, with velocities and momenta taken from `seen` (a state vector,
   or NULL for the current state); the kicks of tb__split_sweep add the local
   forces (gravity, drag, damping, held forces), also seeing `seen`. */
tb_status tb__split_prepare(tb_world *w, double t, const double *seen);
/* The ops over every object; a list that drifts holds the bodies and
   particles on their joints through its drift (joints.h:
   tb__joints_hold, shake), which must be its last op then. */
tb_status tb__split_sweep(tb_world *w, const tb__split_op *ops, int n);
/* Whether any force depends on velocity (drag, damping, callbacks). */
int tb__split_velocity_dependent(const tb_world *w);
/* saved = 2 y - saved on the velocities and momenta: with saved = y_n and
   the current state after a half kick, this predicts the end-of-step ones. */
void tb__split_extrapolate(const tb_world *w, double *saved);

/* ---- implicit.c: linearised backward Euler --------------------------------- */
/* The particles' linear solve; the whole step (bodies kicked and drifted). */
tb_status tb__implicit_particles(tb_world *w, double h);
tb_status tb__implicit_step(tb_world *w, double h);

/* ---- advisor.c, auto.c, guard.c, diagnostics.c ---------------------------- */
/* What limits a world's step (advisor.c): its stiffest spring mode and how
   damped it is, its most damped mode and how stiff it is, and the fastest
   decay of drag and body damping. */
typedef struct tb__modes {
    double omega;          /* rad/s, the stiffest mode of M^-1 K (0: none) */
    double zeta;           /* its damping ratio: (u.M^-1/2 (C + D) M^-1/2 u) / (2 omega) */
    double damped_rate;    /* 1/s, the largest eigenvalue of M^-1 (C + D) (0: none) */
    double damped_omega;   /* rad/s, the stiffness that most damped mode sees */
    double decay;          /* 1/s, the fastest decay of drag and body damping */
    tb_spring_id spring;   /* the stiffest spring where the stiffest mode is largest */
} tb__modes;
/* The modes by power iteration (two scratch state vectors). */
tb_status tb__modes_of(tb_world *w, tb__modes *modes);
/* The stability limit (s) of method m on them: the least of its damped
   limit on the stiffest mode, on the most damped mode, and its decay limit
   on the fastest decay. *cause (may be NULL) is set to 1, 2 or 3 for the one
   that binds, 0 when nothing limits the step. */
double tb__limit_of(const tb__method *m, const tb__modes *modes, int *cause);
/* The fastest drag or damping decay rate (1/s) of particles and bodies. */
double tb__fastest_decay(const tb_world *w);
/* Choose w->auto_method and w->auto_substeps for steps of h; the _why
   form also writes why (may be NULL): each candidate's estimated cost. */
tb_status tb__auto_plan(tb_world *w, double h);
tb_status tb__auto_plan_why(tb_world *w, double h, char *why, size_t size);
/* After a step from the guard's snapshot (tb__rollback_keep): TB_OK, or
   the world rolled back to the snapshot and TB_ERR_UNSTABLE with a message
   naming the step, the object and the likely cause. */
tb_status tb__guard_check(tb_world *w, double h);
/* The energies of state y (any state vector of the world). */
tb_energy tb__energy_of(const tb_world *w, const double *y);
/* Whether drag, spring damping or body damping take energy, and the power
   (W, <= 0) they take at the current state (tb_work.damping_work). */
int tb__is_damped(const tb_world *w);
double tb__damping_power(const tb_world *w);

/* ---- snapshot.c: the guard's rollback ----------------------------------------
   tb__rollback_keep copies what a step can change into w->rollback, into
   the memory of the last copy (nothing allocated while no array grows);
   tb__rollback_state is that copy's state vector (the layout of w->y: no
   step resizes it); tb__rollback puts the world back as it was, all or
   nothing (it allocates only to give an array the step grew its old
   capacity back, so it can fail only then); tb__rollback_free frees it. */
tb_status tb__rollback_keep(tb_world *w);
const double *tb__rollback_state(const tb_world *w);
tb_status tb__rollback(tb_world *w);
void tb__rollback_free(tb_world *w);
/* The same for the attempt at a step that step.c may take again in
   halves, in w->retake */
tb_status tb__retake_keep(tb_world *w);
tb_status tb__retake(tb_world *w);
void tb__retake_free(tb_world *w);

#endif
