-- A double pendulum: two 1 kg spheres on 1 m rods (distance joints),
-- released from the horizontal, stepped by dopri5 at a tolerance of 1e-10:
-- the joint forces are solved in every evaluation, so the method keeps its
-- order and the energy holds (test_joints.double_pendulum_keeps_its_energy:
-- within 3e-13 J over 10 s at 1e-12). Run it with --integrator verlet to
-- see the default: the rods hold to rounding, the energy within the
-- method's own swing.
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, -9.81}, integrator = "dopri5", tolerance = 1e-10, dt = 1/60 }
local upper = w:body{ sphere = 0.05, mass = 1, pos = {1, 0, 0} }
local lower = w:body{ sphere = 0.05, mass = 1, pos = {2, 0, 0} }
w:joint{ type = "distance", a = upper, anchor = {1, 0, 0}, anchor_b = {0, 0, 0} }
w:joint{ type = "distance", a = lower, b = upper, anchor = {2, 0, 0}, anchor_b = {1, 0, 0} }
return { world = w, duration = 10, record_every = 1/30 }
