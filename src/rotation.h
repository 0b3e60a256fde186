/* rotation.h: torque-free rotation of one rigid body over one step, as pure
   kernels (rotation.c). Internal to the core, not public.

   The model is DESIGN.md section 2: q is a unit quaternion (w, x, y, z)
   taking the body's principal axes to the world (R = R(q)); L is the angular
   momentum about the centre of mass in the WORLD frame, kg m^2/s; invI holds
   the inverse principal moments 1/I1, 1/I2, 1/I3 in 1/(kg m^2), in the order
   of the body axes, any order of size, all >= 0 and finite. The body-frame
   momentum is L_b = R^T L, the angular velocity w = R diag(invI) L_b, and the
   kinetic energy E = 1/2 sum invI_i L_b,i^2.

   With no torque the world L is constant, so each kernel only advances q over
   a time h (any sign; h < 0 runs backwards) and leaves L to the caller.
   Every kernel keeps |q| = 1 to rounding (it renormalises) and rotates the
   body exactly, so |L_b| = |L| holds to rounding whatever the step. They read
   and write nothing else, allocate nothing and are safe on any thread; q may
   not alias L or invI. Costs are for gcc -O2 on a 2-core x86-64 (see
   bench/rotation.c); the accuracies quoted are on the intermediate-axis flip
   of NOTES.md at h = 1/60 s over 20 s. */
#ifndef TB_ROTATION_H
#define TB_ROTATION_H

/* q <- exp(h w / 2) q with w frozen at its value at the start of the step:
   one exact rotation about the start's angular velocity. Order 1 for an
   asymmetric body (it ignores the gyroscopic turning of w), exact for an
   isotropic one (w is then constant). About 20 ns. */
void tb__rotation_frozen(double q[4], const double L[3], const double invI[3], double h);

/* Order 2, time-symmetric splitting of the kinetic energy into exactly
   solvable rotations: with a = invI of the middle moment,
       T = a |L|^2 / 2 + c_A L_A^2 / 2 + c_B L_B^2 / 2,  c = invI - a,
   where |L|^2 / 2 generates a rotation about the fixed world L and each
   other term a rotation about one principal axis; Strang composition
   A(h/2) B(h) A(h/2) (Fasso 2003's "symmetric top" splitting). A Poisson
   map: |L_b| exact, energy error bounded with no drift (6e-5 on the flip),
   exact for isotropic bodies and symmetric tops. About 50 ns. */
void tb__rotation_split2(double q[4], const double L[3], const double invI[3], double h);

/* Order 4: the same splitting composed with the 6-stage coefficients of
   Blanes and Moan (2002, "S6"), 13 axis rotations a step. Still a Poisson
   map and exact for isotropic bodies and symmetric tops; on the flip the
   energy error stays below 2e-10 and the orientation is within 1e-9 rad of
   the exact solution after 20 s. About 250 ns. */
void tb__rotation_accurate(double q[4], const double L[3], const double invI[3], double h);

#endif
