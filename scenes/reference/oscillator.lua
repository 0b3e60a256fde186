-- Reference scene "oscillator" of the work-precision benchmark
-- (bench/workprecision/scenes.c builds the same scene in C).
--
-- A 0.5 kg mass hanging from an anchor at the origin on a spring
-- (k = 50 N/m, rest length 1 m), pulled A = 0.2 m below its equilibrium and
-- let go: w = sqrt(k / m) = 10 rad/s, period 0.628 s.
--
-- Truth (closed form): gravity shifts the equilibrium to
-- z_eq = -(1 + m g / k), and z(t) = z_eq - A cos(w t); x = y = 0.
-- Error measure: |x(T) - x_true(T)| / A at T = 10 s.
-- Stability: split methods need h w < 2 (h < 0.2 s), rk4 h w < 2.83;
-- explicit Euler grows the amplitude at every step size.
local tumble = require "tumble"

local k, m, g, A = 50, 0.5, 9.81, 0.2
local omega, z_eq = math.sqrt(k / m), -(1 + m * g / k)

local w = tumble.world{ gravity = {0, 0, -g}, integrator = "rk4", dt = 1/100 }
local bob = w:particle{ pos = {0, 0, z_eq - A}, mass = m }
w:spring(bob, {0, 0, 0}, { k = k, rest = 1 })

return {
  world = w, duration = 10, record_every = 1/50,
  -- the exact position at time t (s), m
  truth = function(t) return 0, 0, z_eq - A * math.cos(omega * t) end,
}
