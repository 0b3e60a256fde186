-- A box at rest in free space, pushed by a small thruster fixed to one
-- corner (0.25 N along the body's y axis, at body point (0.5, 0, 0)): the
-- push both moves it and spins it about its z axis. The thruster is a Lua
-- force, called once per force evaluation with whole arrays.
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, 0}, integrator = "rk4", dt = 1/120 }
w:body{ box = {1, 0.4, 0.2}, mass = 4 }

-- Rotate a body-frame vector by the quaternion (qw, qx, qy, qz).
local function rotate(qw, qx, qy, qz, x, y, z)
  local tx, ty, tz = 2 * (qy * z - qz * y), 2 * (qz * x - qx * z), 2 * (qx * y - qy * x)
  return x + qw * tx + (qy * tz - qz * ty),
         y + qw * ty + (qz * tx - qx * tz),
         z + qw * tz + (qx * ty - qy * tx)
end

w:force(function(t, s, forces, body_forces, body_torques)
  local b = s.bodies
  for i = 1, b.n do
    local qw, qx, qy, qz = b.rot[4*i-3], b.rot[4*i-2], b.rot[4*i-1], b.rot[4*i]
    local fx, fy, fz = rotate(qw, qx, qy, qz, 0, 0.25, 0)    -- thrust, world frame
    local rx, ry, rz = rotate(qw, qx, qy, qz, 0.5, 0, 0)     -- lever arm, world frame
    body_forces[3*i-2] = body_forces[3*i-2] + fx
    body_forces[3*i-1] = body_forces[3*i-1] + fy
    body_forces[3*i]   = body_forces[3*i]   + fz
    body_torques[3*i-2] = body_torques[3*i-2] + ry * fz - rz * fy
    body_torques[3*i-1] = body_torques[3*i-1] + rz * fx - rx * fz
    body_torques[3*i]   = body_torques[3*i]   + rx * fy - ry * fx
  end
end)

return { world = w, duration = 6, record_every = 1/30 }
