-- Reference scene "top" of the work-precision benchmark
-- (bench/workprecision/scenes.c builds the same scene in C).
--
-- A torque-free symmetric top: a 1 kg body with principal moments
-- I = diag(1, 1, 1.8) kg m^2, spun at w0 = (0.6, -0.2, 4) rad/s (body frame,
-- q0 = identity), no gravity, for 10 s.
--
-- Truth (closed form): L = I w0 = (0.6, -0.2, 7.2) kg m^2/s is fixed in the
-- world; with c = (1/I3 - 1/I1) L3 = -3.2 rad/s,
--   q(t) = rot(L / |L|, |L| t / I1) q0 rot(e3, c t),
-- rot(axis, angle) the quaternion of that rotation: the symmetry axis
-- precesses about L at |L| / I1, and in the body frame w turns about e3 at
-- (I3 - I1) / I1 w3 = 3.2 rad/s.
-- Error measure: the orientation error at T = 10 s, the angle of
-- q_true^-1 q, computed as 2 atan2(|vector part|, |scalar part|).
-- "verlet" and "verlet_exact" split the kinetic energy into exactly this
-- symmetric-top motion: they are exact to rounding at any step.
local tumble = require "tumble"

local I1, I3 = 1, 1.8
local w = tumble.world{ gravity = {0, 0, 0}, integrator = "verlet", dt = 1/60 }
w:body{ inertia = {I1, I1, I3}, mass = 1, omega = {0.6, -0.2, 4} }

local L = {I1 * 0.6, I1 * -0.2, I3 * 4}
local l = math.sqrt(L[1] ^ 2 + L[2] ^ 2 + L[3] ^ 2)
local c = (1 / I3 - 1 / I1) * L[3]

local function rot(x, y, z, angle)
  local s = math.sin(angle / 2)
  return math.cos(angle / 2), s * x, s * y, s * z
end

-- Quaternion product a b, components (w, x, y, z).
local function mul(aw, ax, ay, az, bw, bx, by, bz)
  return aw * bw - ax * bx - ay * by - az * bz,
         aw * bx + ax * bw + ay * bz - az * by,
         aw * by - ax * bz + ay * bw + az * bx,
         aw * bz + ax * by - ay * bx + az * bw
end

return {
  world = w, duration = 10, record_every = 1/60,
  -- the exact orientation (w, x, y, z) at time t (s); q0 is the identity
  truth = function(t)
    local aw, ax, ay, az = rot(L[1] / l, L[2] / l, L[3] / l, l * t / I1)
    local bw, bx, by, bz = rot(0, 0, 1, c * t)
    return mul(aw, ax, ay, az, bw, bx, by, bz)
  end,
}
