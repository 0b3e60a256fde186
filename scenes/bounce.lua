-- Balls dropped from 1 m on a plane, restitution 0, 0.25, 0.5, 0.75 and 0.9:
-- each bounces to e^2 of its previous height (impacts are timed within the
-- step, so this holds at 60 Hz; tests/contacts/test_contacts_bounce.c checks it).
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, -9.81}, dt = 1/60 }
w:shape{ type = "plane", normal = {0, 0, 1}, offset = 0 }
for i, e in ipairs{0, 0.25, 0.5, 0.75, 0.9} do
  local ball = w:body{ sphere = 0.1, mass = 1, pos = {0.5 * i, 0, 1.1} }
  w:shape{ type = "sphere", body = ball, radius = 0.1, restitution = e }
end

return { world = w, duration = 4, record_every = 1/60 }
