-- A pyramid of unit boxes (1 kg each) resting on a plane: `levels` rows, the
-- bottom one `levels` boxes wide, 1 cm apart, each row offset by half a box
-- (the benchmark's scene, bench/contacts.c, at 20 levels: 210 boxes).
local tumble = require "tumble"

local levels = 10
local w = tumble.world{ gravity = {0, 0, -9.81}, dt = 1/60 }
w:shape{ type = "plane" }
for row = 0, levels - 1 do
  local n = levels - row
  for j = 0, n - 1 do
    local box = w:body{ box = {1, 1, 1}, mass = 1, pos = {(j - (n - 1) / 2) * 1.01, 0, 0.5 + row} }
    w:shape{ type = "box", body = box, half = {0.5, 0.5, 0.5} }
  end
end

return { world = w, duration = 5, record_every = 1/10 }
