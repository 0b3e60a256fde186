-- A crate 100 times the mass of the boxes under it (100 kg on a column of
-- three 1 kg unit boxes), dropped from 0.5 m above them: with restitution 0
-- it stops on the column, which it does not push into the ground (such a
-- landing is solved with the contacts under it; met one contact at a
-- time, the crate went through the boxes).
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, -9.81}, dt = 1/60 }
w:shape{ type = "plane" }
for i = 0, 2 do
  local box = w:body{ box = {1, 1, 1}, mass = 1, pos = {0, 0, 0.5 + i} }
  w:shape{ type = "box", body = box, half = {0.5, 0.5, 0.5} }
end
local crate = w:body{ box = {1, 1, 1}, mass = 100, pos = {0, 0, 3.5 + 0.5} }
w:shape{ type = "box", body = crate, half = {0.5, 0.5, 0.5} }

return { world = w, duration = 3, record_every = 1/30 }
