-- Reference scene "flip" of the work-precision benchmark
-- (bench/workprecision/scenes.c builds the same scene in C).
--
-- The intermediate-axis (Dzhanibekov) flip of docs/notes.md: a 1 kg
-- body with principal moments I = diag(1, 2, 3) kg m^2, spun at
-- w0 = (0.01, 5, 0.01) rad/s (body frame, q0 = identity), torque-free and
-- without gravity, for 20 s: it flips over and over about the middle axis.
--
-- Truth: the free rigid body has an exact solution in Jacobi elliptic
-- functions; the benchmark uses a converged reference instead, rk4 at
-- h = 20 / 2^18 s, checked against rk4 at twice that step (they agree to
-- about 2e-11 rad: the flip amplifies rounding that much).
-- Invariants: world angular momentum L = I w0 = (0.01, 10, 0.03) kg m^2/s
-- and kinetic energy w0 . L / 2 = 25.0002 J stay constant.
-- Error measure: the orientation error at T = 20 s, the angle of
-- q_ref^-1 q, computed as 2 atan2(|vector part|, |scalar part|).
-- First-order methods (explicit and symplectic Euler, and ODE's
-- dWorldStep) end 0.7 to 3 rad off at every step the benchmark tries, down
-- to 1.5e-5 s; symplectic Euler needs about 6e-7 s (3e7 steps) to come
-- within 0.02 rad. Use "verlet_exact" (the default here), "verlet" or "rk4".
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, 0}, integrator = "verlet_exact", dt = 1/60 }
w:body{ inertia = {1, 2, 3}, mass = 1, omega = {0.01, 5, 0.01} }

return { world = w, duration = 20, record_every = 1/30 }
