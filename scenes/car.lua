-- A car: a 200 kg box and four 15 kg sphere wheels on hinges whose motors
-- turn them at 6 rad/s (at most 150 N m each), driving over eight planks
-- lying loose on the ground at 2.07 m/s (6 rad/s times the 0.35 m radius,
-- less the tyres' slip), every joint to rounding.
local tumble = require "tumble"
local w = tumble.world{ gravity = {0, 0, -9.81}, dt = 1/60 }
w:shape{ type = "plane", friction = 0.9 }
for i = 1, 8 do
  local p = w:body{ box = {0.3, 2, 0.04}, mass = 2, pos = {3 + 1.0 * i, 0, 0.02} }
  w:shape{ type = "box", body = p, half = {0.15, 1, 0.02}, friction = 0.9 }
end
local chassis = w:body{ box = {2, 1, 0.3}, mass = 200, pos = {0, 0, 0.7} }
w:shape{ type = "box", body = chassis, half = {1, 0.5, 0.15} }
local r = 0.35
for _, x in ipairs{ -0.8, 0.8 } do
  for _, y in ipairs{ -0.7, 0.7 } do
    local wheel = w:body{ sphere = r, mass = 15, pos = {x, y, r} }
    w:shape{ type = "sphere", body = wheel, radius = r, friction = 0.9, rolling_resistance = 0.002 }
    w:joint{ type = "hinge", a = wheel, b = chassis, anchor = {x, y, r}, axis = {0, 1, 0},
            motor_speed = 6, max_motor_force = 150 }
  end
end

return { world = w, duration = 8, record_every = 1/20 }
