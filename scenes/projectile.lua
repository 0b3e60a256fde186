-- A 2 kg ball thrown from 1 m up at (9, 0, 12) m/s through air with linear
-- drag (c = 0.1 N s/m, so k = c/m = 0.05 1/s). The README's default scene.
-- Closed form: v(t) = g/k + (v0 - g/k) e^(-kt),
--              x(t) = x0 + (g/k) t + (v0 - g/k) (1 - e^(-kt)) / k.
local tumble = require "tumble"

local w = tumble.world{
  gravity = {0, 0, -9.81},
  drag = { linear = 0.1 },
  integrator = "verlet",
  dt = 1/240,
}
w:particle{ pos = {0, 0, 1}, vel = {9, 0, 12}, mass = 2 }

return { world = w, duration = 2.5, record_every = 1/30 }
