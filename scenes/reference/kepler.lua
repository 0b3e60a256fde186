-- Reference scene "kepler" of the work-precision benchmark
-- (bench/workprecision/scenes.c builds the same scene in C).
--
-- A 1 kg planet around a fixed centre at the origin, GM = 1 m^3/s^2, on an
-- orbit of semi-major axis a = 1 m and eccentricity e = 0.5, started at
-- periapsis r_p = a (1 - e) = 0.5 m with speed sqrt(GM (1 + e) / r_p) =
-- sqrt(3) m/s. The attraction -GM m x / |x|^3 is a force callback.
--
-- Truth (closed form):
--   energy E = -GM m / (2 a) = -0.5 J, angular momentum
--   |L| = m sqrt(GM a (1 - e^2)) = 0.866 kg m^2/s, period P = 2 pi sqrt(a^3 / GM)
--   = 2 pi s; the position at any t from Kepler's equation M = E - e sin E
--   with mean anomaly M = 2 pi t / P: x = a (cos E - e), y = a sqrt(1 - e^2) sin E.
-- Error measure: |x(T) - x_true(T)| / a at T = 3 P (whole periods: the exact
-- position is the start again).
-- Note: from periapsis, after whole periods, symplectic Euler's first-order
-- error cancels (it is velocity Verlet started from a velocity nudged by
-- h/2 a(x0), which is radial there and so leaves the period unchanged to
-- first order): it converges at order 2 on this measure.
local tumble = require "tumble"

local GM, a, e = 1, 1, 0.5
local period = 2 * math.pi * math.sqrt(a ^ 3 / GM)

-- No gravity field: the central body's pull is the only force.
local w = tumble.world{ gravity = {0, 0, 0}, integrator = "rk4", dt = period / 400 }
w:particle{ pos = {a * (1 - e), 0, 0}, vel = {0, math.sqrt(GM * (1 + e) / (a * (1 - e))), 0}, mass = 1 }

-- Once per force evaluation, over the whole arrays; it returns its
-- potential energy -GM m / r, which the energy line counts.
w:force(function(t, s, f)
  local u = 0
  for i = 1, s.n do
    local x, y, z = s.pos[3*i-2], s.pos[3*i-1], s.pos[3*i]
    local r2 = x * x + y * y + z * z
    local c = GM * s.mass[i] / (r2 * math.sqrt(r2))
    f[3*i-2] = f[3*i-2] - c * x
    f[3*i-1] = f[3*i-1] - c * y
    f[3*i]   = f[3*i]   - c * z
    u = u - GM * s.mass[i] / math.sqrt(r2)
  end
  return u
end)

return {
  world = w, duration = 3 * period, record_every = period / 100,
  -- the exact position at time t (s), m: Newton's method on Kepler's equation
  truth = function(t)
    local M = 2 * math.pi * t / period
    local E = M
    for _ = 1, 50 do
      local dE = (E - e * math.sin(E) - M) / (1 - e * math.cos(E))
      E = E - dE
      if math.abs(dE) < 1e-15 then break end
    end
    return a * (math.cos(E) - e), a * math.sqrt(1 - e * e) * math.sin(E), 0
  end,
}
