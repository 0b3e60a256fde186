-- The intermediate-axis (Dzhanibekov) flip: a T-handle in free space, spun
-- about its stem with a tiny wobble, flips over and over. It is built from
-- point masses: a crossbar along x at y = 0 and a stem along +y. The mirror
-- symmetry x -> -x makes x, y, z principal; the stem axis y has the middle
-- moment, so spinning about it is unstable.
-- integrator "verlet_exact" turns the body with the accurate free-rotation
-- kernel; compare "verlet" and "rk4" with --integrator.
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, 0}, integrator = "verlet_exact", dt = 1/60 }
local handle = w:body{
  points = {
    {-0.1, 0, 0, 0.2}, {0.1, 0, 0, 0.2},                      -- crossbar
    {0, 0.05, 0, 0.1}, {0, 0.10, 0, 0.1}, {0, 0.15, 0, 0.1},  -- stem
  },
  omega = {0.01, 10, 0.01},
}

return { world = w, duration = 20, record_every = 1/30 }
