/* rotation.h: torque-free rotation of one rigid body over one step, as pure
   kernels (rotation.c). Internal to the core, not public.

   The model is DESIGN.md section 2: q is a unit quaternion (w, x, y, z)
   taking the body's principal axes to the world (R = R(q)); L is the angular
   momentum about the centre of mass in the WORLD frame, kg m^2/s; invI holds
   the inverse principal moments 1/I1, 1/I2, 1/I3 in 1/(kg m^2), in the order
   of the body axes (any order of size; finite and >= 0). The body-frame
   momentum is L_b = R^T L, the angular velocity w = R diag(invI) L_b, the
   kinetic energy E = 1/2 sum invI_i L_b,i^2.

   With no torque the world L is constant, so each kernel only advances q
   over a time h (either sign: -h undoes h for the splitting kernels) and
   never touches L. A torque belongs to the caller's kicks of L around these
   drifts. Every kernel turns the body by exact rotations, so |L_b| = |L|
   holds to rounding at any step, and renormalises q (|q| = 1 within 4e-16).
   They read and write nothing else, allocate nothing, call libm only for
   turns beyond their polynomials (noted below), and are safe on any thread;
   q must not alias L or invI.

   Costs: per step on this project's 2-core x86-64 (gcc -O2, no -march),
   first in a loop over 1024 bodies, then for one body stepped alone (each
   step waiting for the last). Accuracy: on the intermediate-axis flip of
   NOTES.md at h = 1/60 s over 20 s (bench/rotation.c). */
#ifndef TB_ROTATION_H
#define TB_ROTATION_H

/* q <- exp(h w / 2) q with w frozen at the start of the step: one exact turn
   about the start's angular velocity. Order 1 for an asymmetric body (it
   misses the turning of w), exact for an isotropic one, where w is constant.
   libm beyond |w| h = 0.5 rad. 23 ns (45 ns alone). */
void tb__rotation_frozen(double q[4], const double L[3], const double invI[3], double h);

/* An isotropic body (I1 = I2 = I3 = 1 / inv_inertia) turns about the fixed
   world w = L / I: q <- exp(h w / 2) q, exact. It skips the body-frame
   transform that tb__rotation_frozen needs. */
void tb__rotation_isotropic(double q[4], const double L[3], double inv_inertia, double h);

/* Order 2: Strang splitting of T into a turn about the world L and turns
   about two principal axes (rotation.c), A(h/2) B(h) A(h/2). A Poisson map:
   energy error bounded with no drift (6.0e-5 on the flip), exact for
   isotropic bodies and symmetric tops, time-reversible; 1.7e-4 rad on the
   flip. libm beyond max |invI_i - invI_mid| |L| h = 0.25 rad. 55 ns (75 ns
   alone). */
void tb__rotation_split2(double q[4], const double L[3], const double invI[3], double h);

/* Order 4: the same splitting composed by Blanes and Moan's S6, 13 axis
   turns a step. Also a Poisson map, exact for isotropic bodies and
   symmetric tops, time-reversible. On the flip: energy within 1.1e-10 at
   every step, 7.5e-10 rad after 20 s. libm beyond max |invI_i - invI_mid|
   |L| h = 0.57 rad. 210 ns (235 ns alone). */
void tb__rotation_accurate(double q[4], const double L[3], const double invI[3], double h);

#endif
