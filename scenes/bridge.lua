-- A rope bridge: 20 planks of 0.5 m on hinges, hung with slack between
-- posts 9.5 m apart, and eight 5 kg crates dropped on it. The contact
-- points of the bridge's island are solved with its joints, so the
-- planks carry the crates (docs/joints.md, "Joints and contacts";
-- test_joint_drives.jointed_bodies_carry_loads).
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, -9.81}, dt = 1/60 }
w:shape{ type = "plane" }
local n, span, sag = 20, 9.5, 0.8
local function height(x) return 2 - sag * (1 - ((x - span / 2) / (span / 2)) ^ 2) end
local previous = nil
for i = 1, n do
  local x0, x1 = span * (i - 1) / n, span * i / n
  local plank = w:body{ box = {0.48, 1, 0.05}, mass = 2, pos = {(x0 + x1) / 2, 0, (height(x0) + height(x1)) / 2} }
  w:shape{ type = "box", body = plank, half = {0.24, 0.5, 0.025} }
  w:joint{ type = "hinge", a = plank, b = previous, anchor = {x0, 0, height(x0)}, axis = {0, 1, 0} }
  previous = plank
end
w:joint{ type = "ball", a = previous, anchor = {span, 0, 2} }
for k = 1, 8 do
  local crate = w:body{ box = {0.3, 0.3, 0.3}, mass = 5, pos = {0.5 + k, 0, 2.5 + 0.4 * k} }
  w:shape{ type = "box", body = crate, half = {0.15, 0.15, 0.15} }
end
return { world = w, duration = 6, record_every = 1/20 }
