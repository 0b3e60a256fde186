-- A brick (20 x 10 x 5 cm, 2 kg) thrown up with a spin about a skewed axis:
-- its centre of mass flies on a parabola while it tumbles freely.
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, -9.81}, integrator = "verlet", dt = 1/240 }
w:body{
  box = {0.2, 0.1, 0.05}, mass = 2,
  pos = {0, 0, 1}, vel = {2, 0, 6},
  omega = {3, 7, 1},
}

return { world = w, duration = 1.3, record_every = 1/60 }
