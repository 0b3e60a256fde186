-- A 0.5 kg mass hanging on a spring (k = 50 N/m, rest 1 m) from an anchor
-- at the origin, pulled 0.2 m below its equilibrium and let go. Gravity
-- shifts the equilibrium to 1 + m g / k below the anchor; the motion is
-- z(t) = -(1 + m g / k) - 0.2 cos(w t) with w = sqrt(k / m) = 10 rad/s.
local tumble = require "tumble"

local k, m, g = 50, 0.5, 9.81
local w = tumble.world{ gravity = {0, 0, -g}, integrator = "verlet", dt = 1/1000 }
local bob = w:particle{ pos = {0, 0, -(1 + m * g / k) - 0.2}, mass = m }
w:spring(bob, {0, 0, 0}, { k = k, rest = 1 })

return { world = w, duration = 5, record_every = 1/100 }
