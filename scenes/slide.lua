-- A 1 m cube slides at 5 m/s on a plane with friction 0.5 (both shapes: a
-- pair uses sqrt(mu_a mu_b)) and stops after v^2 / (2 mu g) = 2.548 m.
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, -9.81}, dt = 1/60 }
w:shape{ type = "plane", friction = 0.5 }
local box = w:body{ box = {1, 1, 1}, mass = 1, pos = {0, 0, 0.5}, vel = {5, 0, 0} }
w:shape{ type = "box", body = box, half = {0.5, 0.5, 0.5}, friction = 0.5 }

return { world = w, duration = 2, record_every = 1/30 }
