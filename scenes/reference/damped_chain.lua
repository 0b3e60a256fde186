-- Reference scene "damped_chain" of the work-precision benchmark
-- (bench/workprecision/scenes.c builds the same scene in C).
--
-- A damped chain of unequal beads: 20 beads of 3 to 17 g, 5 cm apart along
-- x, on springs of 1000 to 3000 N/m (rest 5 cm), each damped at ratio 0.3
-- with its reduced mass, c = 0.6 sqrt(k mu), the first tied to an anchor
-- 2 m up, released straight under gravity: it falls and swings. (The
-- damped chain of test_stability.advisor_predicts_damped_chains, hung up.)
--
-- Truth: no closed form. The benchmark's reference is rk4 at h = 2^-19 s,
-- checked against rk4 at 2^-18 s.
-- Error measure: the largest bead position error at T = 1 s, per metre.
-- Stability: the stiffest mode (1267 rad/s) is more damped than each
-- spring, and the limits are the damped ones: the advisor gives symplectic
-- Euler 1.06 ms, Verlet 1.41 ms, RK4 2.13 ms and explicit Euler 0.64 ms
-- (`tumble run` prints its verdict); the benchmark's chart marks them.
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, -9.81}, integrator = "verlet", dt = 1/2000 }

local previous, previous_mass = nil, 0
for i = 0, 19 do
  local m, k = 0.01 * (1 + 0.7 * math.sin(1.9 * i)), 2000 * (1 + 0.5 * math.cos(2.7 * i))
  local mu = previous and m * previous_mass / (m + previous_mass) or m
  local bead = w:particle{ pos = {0.05 * (i + 1), 0, 2}, mass = m }
  w:spring(bead, previous or {0, 0, 2}, { k = k, damping = 2 * 0.3 * math.sqrt(k * mu), rest = 0.05 })
  previous, previous_mass = bead, m
end

return { world = w, duration = 1, record_every = 1/100 }
