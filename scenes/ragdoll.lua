-- Ragdolls: thirteen capsules each (pelvis, chest, head, upper and lower
-- arms, thighs, shins and feet) on ball joints with cones at the neck,
-- waist, shoulders and hips and hinges with stops at the elbows, knees and
-- ankles, dropped in a pile of three on the ground (which does not yet come to
-- rest: docs/joints.md, "Known limits"). The ball joints limit their twist
-- too. Their joints are met in the
-- contacts' substeps, then put back on them with the contact points of
-- their islands (docs/joints.md, "Joints and contacts"). The ground resists
-- rolling (5 mm): a capsule rolls without loss, and a leg can rock on its
-- foot for ever.
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, -9.81}, dt = 1/60 }
w:shape{ type = "plane", friction = 0.8, rolling_resistance = 0.005 }

-- a capsule of radius r and mass m from p to q, p and q apart along x, y or z
local function bone(p, q, r, m)
  local d = {q[1] - p[1], q[2] - p[2], q[3] - p[3]}
  local l = math.abs(d[1]) + math.abs(d[2]) + math.abs(d[3])
  local h = math.sqrt(0.5)
  local rot = {1, 0, 0, 0}                  -- a capsule's axis is its z: turned onto d
  if d[1] ~= 0 then rot = {h, 0, h, 0} elseif d[2] ~= 0 then rot = {h, -h, 0, 0} end
  local b = w:body{ capsule = {r, l}, mass = m, pos = {(p[1] + q[1]) / 2, (p[2] + q[2]) / 2, (p[3] + q[3]) / 2},
                    rot = rot }
  w:shape{ type = "capsule", body = b, radius = r, half_length = l / 2 }
  return b
end

local function ragdoll(x, y, z)
  local function at(dx, dy, dz) return {x + dx, y + dy, z + dz} end
  local pelvis = bone(at(0, -0.12, 0), at(0, 0.12, 0), 0.1, 8)
  local chest = bone(at(0, 0, 0.15), at(0, 0, 0.45), 0.14, 15)
  local head = bone(at(0, 0, 0.62), at(0, 0, 0.72), 0.1, 5)
  w:joint{ type = "ball", a = chest, b = pelvis, anchor = at(0, 0, 0.05), axis = {0, 0, 1}, cone = 0.5,
           twist = {-0.5, 0.5} }
  w:joint{ type = "ball", a = head, b = chest, anchor = at(0, 0, 0.55), axis = {0, 0, 1}, cone = 0.6,
           twist = {-1, 1} }
  for _, side in ipairs{ -1, 1 } do
    local upper = bone(at(0, side * 0.25, 0.45), at(0, side * 0.5, 0.45), 0.05, 2)
    local lower = bone(at(0, side * 0.55, 0.45), at(0, side * 0.8, 0.45), 0.045, 1.5)
    w:joint{ type = "ball", a = upper, b = chest, anchor = at(0, side * 0.2, 0.45), axis = {0, side, 0}, cone = 1.2,
             twist = {-1, 1} }
    w:joint{ type = "hinge", a = lower, b = upper, anchor = at(0, side * 0.525, 0.45), axis = {0, 0, 1},
             lower = side > 0 and 0 or -2.5, upper = side > 0 and 2.5 or 0 }
    local thigh = bone(at(0, side * 0.12, -0.15), at(0, side * 0.12, -0.55), 0.07, 7)
    local shin = bone(at(0, side * 0.12, -0.62), at(0, side * 0.12, -0.98), 0.06, 4)
    local foot = bone(at(0.02, side * 0.12, -1.06), at(0.18, side * 0.12, -1.06), 0.04, 1)
    w:joint{ type = "ball", a = thigh, b = pelvis, anchor = at(0, side * 0.12, -0.07), axis = {0, 0, -1}, cone = 1.0,
             twist = {-0.5, 0.5} }
    w:joint{ type = "hinge", a = shin, b = thigh, anchor = at(0, side * 0.12, -0.585), axis = {0, 1, 0},
             lower = 0, upper = 2.3 }
    w:joint{ type = "hinge", a = foot, b = shin, anchor = at(0, side * 0.12, -1.02), axis = {0, 1, 0},
             lower = -0.6, upper = 0.6 }
  end
end

for i = 1, 3 do
  ragdoll(0.3 * math.sin(i), 0.3 * math.cos(i), 1.3 + 1.3 * i)
end
return { world = w, duration = 6, record_every = 1/20 }
