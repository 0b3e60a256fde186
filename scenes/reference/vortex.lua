-- Reference scene "vortex" of the work-precision benchmark
-- (bench/workprecision/scenes.c builds the same scene in C).
--
-- A tracer 1 m from the axis of a rigid vortex v = omega x (x - c) about z,
-- turning once every 4 s (omega = pi/2 rad/s).
--
-- Truth (closed form): a rotation by omega t about the axis,
--   x(t) = (cos(omega t), sin(omega t), 0); after T = 8 s (two turns) the
--   tracer is where it started.
-- Error measure: |x(T) - x_true(T)| / 1 m at T = 8 s.
-- Tracers have no velocity to kick, so only "euler" and "rk4" apply (the
-- split methods refuse tracers). Explicit Euler spirals outwards at every
-- step; rk4 is stable for h omega < 2.83 (h < 1.8 s).
local tumble = require "tumble"

local omega = 2 * math.pi / 4

local w = tumble.world{ integrator = "rk4", dt = 1/20 }
w:field{ vortex = {0, 0, omega}, centre = {0, 0, 0} }
w:tracer{ pos = {1, 0, 0} }

return {
  world = w, duration = 8, record_every = 1/20,
  -- the exact position at time t (s), m
  truth = function(t) return math.cos(omega * t), math.sin(omega * t), 0 end,
}
