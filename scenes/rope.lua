-- A rope of 20 beads (10 g each) joined by stiff damped springs, tied to an
-- anchor at one end and released horizontally: it falls and swings.
-- Stability: a bead with two springs has its fastest mode near
-- w = sqrt(4 k / m) = 894 rad/s, so a split method needs h < 2 / w = 2.2 ms.
local tumble = require "tumble"

local n, spacing, k, m = 20, 0.05, 2000, 0.01
local w = tumble.world{ gravity = {0, 0, -9.81}, integrator = "verlet", dt = 1/2000 }

local previous = nil
for i = 1, n do
  local bead = w:particle{ pos = {i * spacing, 0, 2}, mass = m }
  w:spring(bead, previous or {0, 0, 2}, { k = k, damping = 0.05, rest = spacing })
  previous = bead
end

return { world = w, duration = 3, record_every = 1/30 }
