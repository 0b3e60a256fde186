-- Doors: 20 kg leaves on hinges about the vertical with stops at -100 and
-- +100 degrees (docs/joints.md, "Limits, motors, springs, breaking").
-- The first one's motor opens it at 1 rad/s with at most 40 N m until its
-- stop holds it, and a ball thrown at it knocks it back; the second, pushed
-- open at 2 rad/s, is swung shut by a spring of 0.5 Hz with a damping ratio
-- of 0.3; the third, on a slider with stops, is pushed along it and rests
-- on a stop.
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, -9.81}, dt = 1/60 }
w:shape{ type = "plane" }

local function leaf(x)
  local b = w:body{ box = {1, 0.05, 2}, mass = 20, pos = {x + 0.5, 0, 1.01} }
  w:shape{ type = "box", body = b, half = {0.5, 0.025, 1} }
  return b
end

local opened = leaf(0)
w:joint{ type = "hinge", a = opened, anchor = {0, 0, 1.01}, axis = {0, 0, 1},
         lower = math.rad(-100), upper = math.rad(100), motor_speed = 1, max_motor_force = 40 }
local ball = w:body{ sphere = 0.15, mass = 3, pos = {-0.3, 4, 1}, vel = {0, -4, 0} }
w:shape{ type = "sphere", body = ball, radius = 0.15, restitution = 0.3 }

local sprung = leaf(3)
w:joint{ type = "hinge", a = sprung, anchor = {3, 0, 1.01}, axis = {0, 0, 1},
         lower = math.rad(-100), upper = math.rad(100), spring_hz = 0.5, damping_ratio = 0.3 }
sprung:set_vel(0, 1, 0)           -- the centre of a leaf turning at 2 rad/s about the hinge
sprung:set_omega(0, 0, 2)

local sliding = leaf(6)
w:joint{ type = "slider", a = sliding, axis = {1, 0, 0}, lower = -0.5, upper = 1.5 }
sliding:set_vel(1.5, 0, 0)

return { world = w, duration = 8, record_every = 1/20 }
