-- Reference scene "projectile" of the work-precision benchmark
-- (bench/workprecision/scenes.c builds the same scene in C).
--
-- A 1 kg ball dropped from rest at the origin through air with quadratic
-- drag f = -c |v| v, c = 0.1 N s^2/m^2: terminal speed vt = sqrt(m g / c) =
-- 9.90 m/s, reached (to 1%) after about 2.6 s.
--
-- Truth (closed form, vertical fall from rest):
--   v(t) = -vt tanh(g t / vt),  z(t) = -(vt^2 / g) ln cosh(g t / vt),  x = y = 0.
-- Error measure: |x(T) - x_true(T)| / |z_true(T)| (per metre fallen) at
-- T = 3 s.
local tumble = require "tumble"

local m, g, c = 1, 9.81, 0.1
local vt = math.sqrt(m * g / c)

local w = tumble.world{ gravity = {0, 0, -g}, drag = { quadratic = c }, integrator = "rk4", dt = 1/60 }
w:particle{ pos = {0, 0, 0}, mass = m }

return {
  world = w, duration = 3, record_every = 1/30,
  -- the exact position at time t (s), m
  truth = function(t) return 0, 0, -(vt * vt / g) * math.log(math.cosh(g * t / vt)) end,
}
