-- A chain of 30 links (10 cm, 1 kg spheres at the link ends) on ball
-- joints, hung from a point with a 10 kg weight at its end and released
-- from the horizontal: at 60 Hz under verlet every joint holds to rounding
-- (test_joints.released_chains_hold), where ODE and MuJoCo blow up on such
-- chains; the swing loses energy on the steps SHAKE takes implicitly (38%
-- in 6 s here: docs/joints.md, "Known limits").
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, -9.81}, dt = 1/60 }
local above = nil
for i = 1, 30 do
  local link = w:body{ sphere = 0.02, mass = i == 30 and 10 or 1, pos = {0.1 * i, 0, 3} }
  w:joint{ a = link, b = above, anchor = {0.1 * (i - 1), 0, 3} }
  above = link
end
return { world = w, duration = 6, record_every = 1/30 }
