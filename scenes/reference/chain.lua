-- Reference scene "chain" of the work-precision benchmark
-- (bench/workprecision/scenes.c builds the same scene in C).
--
-- A stiff chain: 20 beads of 10 g, 5 cm apart along x, joined by springs
-- k = 2000 N/m (damping 0.05 N s/m, rest 5 cm), the first tied to an anchor
-- 2 m up, released straight under gravity: it falls and swings.
-- (The rope of scenes/rope.lua, run for 1 s.)
--
-- Truth: no closed form. The benchmark's reference is rk4 at h = 2^-19 s,
-- checked against rk4 at 2^-18 s (they agree to about 1e-12 m).
-- Error measure: the largest bead position error at T = 1 s, per metre.
-- Stability: a bead with two springs has its fastest mode near
-- sqrt(4 k / m) = 894 rad/s: split methods need h < 2.2 ms, rk4 h < 3.2 ms;
-- the chain's own pendulum motion is 300 times slower, hence "stiff".
local tumble = require "tumble"

local n, spacing, k, m = 20, 0.05, 2000, 0.01
local w = tumble.world{ gravity = {0, 0, -9.81}, integrator = "verlet", dt = 1/2000 }

local previous = nil
for i = 1, n do
  local bead = w:particle{ pos = {i * spacing, 0, 2}, mass = m }
  w:spring(bead, previous or {0, 0, 2}, { k = k, damping = 0.05, rest = spacing })
  previous = bead
end

return { world = w, duration = 1, record_every = 1/100 }
