-- A spray of particles (2 cm spheres) fired at a static sphere: they hit it,
-- lose their normal speed (restitution 0.3) and slide off or bounce away.
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, -9.81}, dt = 1/120 }
w:contacts{ particle_radius = 0.02, particle_restitution = 0.3, particle_friction = 0.2 }
w:shape{ type = "sphere", pos = {0, 0, 1}, radius = 0.5 }
w:shape{ type = "plane" }
for i = 0, 199 do
  local a = 2.399963 * i -- golden angle: an even disc of nozzles
  local r = 0.3 * math.sqrt(i / 200)
  w:particle{ pos = {-2, r * math.cos(a), 1.2 + r * math.sin(a)}, vel = {6, 0, 1}, mass = 0.01 }
end

return { world = w, duration = 2, record_every = 1/30 }
