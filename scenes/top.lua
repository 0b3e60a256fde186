-- A symmetric top (a solid cylinder, 5 cm radius, 2 cm thick) spinning
-- torque-free about an axis tilted from its symmetry axis: the symmetry
-- axis precesses around the fixed angular momentum, and in the body frame
-- the angular velocity turns at (I3 - I1) / I1 w3.
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, 0}, integrator = "verlet_exact", dt = 1/120 }
w:body{ cylinder = {0.05, 0.02}, density = 7800, omega = {2, 0, 30} }

return { world = w, duration = 10, record_every = 1/60 }
