-- Joints: a double pendulum on ball joints, a chain of five links hung from
-- a beam that turns on a hinge, and a pendulum on a hinge released at 170
-- degrees, whose period is within 3.3e-4 of the closed form at 60 Hz and
-- whose rod keeps its length to rounding (docs/joints.md; the tests:
-- tests/joints/test_joints.c, and test_command runs this scene).
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, -9.81}, dt = 1/60 }

-- the double pendulum, released from the horizontal
local upper = w:body{ sphere = 0.05, mass = 1, pos = {-3, 0, 0} }
local lower = w:body{ sphere = 0.05, mass = 1, pos = {-2, 0, 0} }
w:joint{ a = upper, anchor = {-4, 0, 0} }
w:joint{ a = lower, b = upper, anchor = {-3, 0, 0} }

-- a beam on a hinge about y, and a chain of five links hung from its end
local beam = w:body{ box = {1, 0.1, 0.1}, mass = 2, pos = {0.5, 0, 0} }
w:joint{ type = "hinge", a = beam, anchor = {0, 0, 0}, axis = {0, 1, 0} }
local above = beam
for i = 1, 5 do
  local link = w:body{ capsule = {0.02, 0.16}, mass = 0.2, pos = {1, 0, -0.2 * i + 0.1} }
  w:joint{ a = link, b = above, anchor = {1, 0, -0.2 * (i - 1)} }
  above = link
end

-- the pendulum on a hinge, 170 degrees from the bottom (the last body)
local a = math.rad(170)
local bob = w:body{ sphere = 0.05, mass = 1, pos = {4 + math.sin(a), 0, -math.cos(a)} }
w:joint{ type = "hinge", a = bob, anchor = {4, 0, 0}, axis = {0, 1, 0} }

return { world = w, duration = 5, record_every = 1/20 }
