-- Reference scene "cloth" of the work-precision benchmark
-- (bench/workprecision/scenes.c builds the same scene in C).
--
-- A small cloth patch: 8 x 8 particles on a 0.5 m square (0.1 kg in all),
-- lying flat 1.5 m up, held by the two corners of its first row,
-- falling and swaying under gravity for 1 s. Structural springs (60 N/m)
-- join neighbours along rows and columns, shear springs (20 N/m) the
-- diagonals, bend springs (5 N/m) skip one particle; all have damping
-- 0.02 N s/m and rest at their initial lengths (as in scenes/cloth.lua).
--
-- Truth: no closed form. The benchmark's reference is rk4 at h = 2^-17 s,
-- checked against rk4 at 2^-16 s (they agree to about 1e-13 m).
-- Error measure: the largest particle position error at T = 1 s, per
-- 0.5 m (the patch's side).
-- Stability: an inner particle has 12 springs, sum(k) = 340 N/m, and mass
-- 1.56 g; Gershgorin bounds its fastest mode by sqrt(2 sum(k) / m) =
-- 660 rad/s, so split methods need h < 3 ms.
local tumble = require "tumble"

local n, size, mass = 8, 0.5, 0.1
local spacing, m = size / (n - 1), mass / (n * n)
local w = tumble.world{ gravity = {0, 0, -9.81}, integrator = "verlet", dt = 1/1000 }

local grid = {}
for row = 1, n do
  grid[row] = {}
  for col = 1, n do
    grid[row][col] = w:particle{
      pos = {(col - 1) * spacing, (row - 1) * spacing, 1.5},
      mass = m,
      pinned = row == 1 and (col == 1 or col == n),
    }
  end
end

-- {row step, column step, stiffness}: structural, shear, bend
local joins = { {0, 1, 60}, {1, 0, 60}, {1, 1, 20}, {1, -1, 20}, {0, 2, 5}, {2, 0, 5} }
for row = 1, n do
  for col = 1, n do
    for _, j in ipairs(joins) do
      local r2, c2 = row + j[1], col + j[2]
      if grid[r2] and grid[r2][c2] then
        w:spring(grid[row][col], grid[r2][c2],
                 { k = j[3], damping = 0.02, rest = spacing * math.sqrt(j[1] * j[1] + j[2] * j[2]) })
      end
    end
  end
end

return { world = w, duration = 1, record_every = 1/100 }
