-- Twelve tracers on a line, carried by a rigid vortex v = omega x (x - c)
-- that turns once every 4 s. Tracers have no velocity to kick, so the scene
-- uses RK4 (the split methods refuse tracers). Exactly, every radius is
-- constant; RK4 at this step loses about 4e-9 of it per turn.
local tumble = require "tumble"

local w = tumble.world{ integrator = "rk4", dt = 1/100 }
w:field{ vortex = {0, 0, 2 * math.pi / 4}, centre = {0, 0, 0} }
for i = 1, 12 do
  w:tracer{ pos = {0.25 * i, 0, 0} }
end

return { world = w, duration = 8, record_every = 1/20 }
