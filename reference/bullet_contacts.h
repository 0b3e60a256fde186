/* bullet_contacts.h: Bullet 3.24 (Debian's libbullet-dev, single precision)
   runs of the pyramid and the pile of ode_contacts.h, for bench_contacts
   to time beside tumble and ODE (issue 18's "Speed to show"). Not a test
   oracle: Bullet is a speed anchor here, not a truth.

   Bullet with its defaults: btDiscreteDynamicsWorld over
   btDefaultCollisionConfiguration, btCollisionDispatcher, btDbvtBroadphase
   and btSequentialImpulseConstraintSolver (10 iterations, split impulse
   for penetrations), shapes with their default collision margins, one
   stepSimulation(1 / hz, 0) a step (one internal step of exactly h).
   What the scenes fix: gravity (0, 0, -g); the static plane z = 0
   (btStaticPlaneShape); each body's mass and principal inertia as
   ode_contacts.h gives them, its shape at its centre along its principal
   axes (spheres btSphereShape, boxes btBoxShape, capsules btCapsuleShapeZ
   of the core length); friction sqrt(mu) on every body and on the plane,
   since Bullet multiplies a pair's coefficients, so that every pair has
   mu; restitution 0. Sleep off: every body DISABLE_DEACTIVATION; on:
   Bullet's deactivation at its defaults (0.8 m/s and 1.0 rad/s for 2 s).

   A step's time is stepSimulation's wall time (CLOCK_MONOTONIC, as
   ode_contacts.c's); the setup is not timed. C callable; no exception
   leaves it (out of memory: the run fails, returning 0). */
#ifndef TB_BULLET_CONTACTS_H
#define TB_BULLET_CONTACTS_H

#include "ode_contacts.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct bullet_run {
    double ms_median;      /* ms, wall time of a step, median over the steps */
    double ms_mean;        /* ms, mean */
    double contacts_mean;  /* contact points a step (the manifolds'), mean */
    int asleep_after;      /* steps until no body was active; -1: never */
    double asleep_ms;      /* ms, median of asleep_steps steps after that (-1: none) */
    double top_sink;       /* m, pyramid: z0 - z of the top cube at the end */
    double top_drift;      /* m, pyramid: its horizontal distance at the end */
    int below;             /* pile: centres below the plane at the end */
} bullet_run;

/* The pyramid of ode_pyramid_def (its levels, edge, mass, gap, hz, mu,
   gravity, duration), sleep on or off; with sleep, asleep_steps more
   steps are timed once every body sleeps. Returns 1 if the run happened,
   0 if def was refused or memory ran out. */
int bullet_pyramid(const ode_pyramid_def *def, int sleep, int asleep_steps, bullet_run *out);

/* The pile of ode_pile_scene's shapes[def->count] (one copy), def->steps
   steps at def->hz. Returns 1 if the run happened, 0 if refused or out of
   memory. */
int bullet_pile(const ode_pile_def *def, const ode_shape *shapes, int sleep, bullet_run *out);

#ifdef __cplusplus
}
#endif

#endif
