-- A 1 m square cloth of 15 x 15 particles (0.4 kg in all), held by its two
-- top corners, falling from horizontal and swaying. Structural springs join
-- neighbours along rows and columns, shear springs join diagonals, bend
-- springs skip one particle. The two top corners are pinned.
-- Stability: an inner particle has 12 springs, sum(k) = 340 N/m, and mass
-- 1.8 g; Gershgorin bounds its fastest mode by w^2 <= 2 sum(k) / m, so
-- w <= 620 rad/s and a split method needs h < 2 / w = 3.2 ms.
local tumble = require "tumble"

local n, size, mass = 15, 1.0, 0.4
local spacing, m = size / (n - 1), mass / (n * n)
local w = tumble.world{ gravity = {0, 0, -9.81}, integrator = "verlet", dt = 1/1000 }

local grid = {}
for row = 1, n do
  grid[row] = {}
  for col = 1, n do
    local corner = row == 1 and (col == 1 or col == n)
    grid[row][col] = w:particle{
      pos = {(col - 1) * spacing, (row - 1) * spacing, 1.5},
      mass = m,
      pinned = corner,
    }
  end
end

local function join(r1, c1, r2, c2, k)
  if grid[r2] and grid[r2][c2] then
    w:spring(grid[r1][c1], grid[r2][c2], { k = k, damping = 0.02 })
  end
end

for row = 1, n do
  for col = 1, n do
    join(row, col, row, col + 1, 60)       -- structural
    join(row, col, row + 1, col, 60)
    join(row, col, row + 1, col + 1, 20)   -- shear
    join(row, col, row + 1, col - 1, 20)
    join(row, col, row, col + 2, 5)        -- bend
    join(row, col, row + 2, col, 5)
  end
end

return { world = w, duration = 3, record_every = 1/30 }
