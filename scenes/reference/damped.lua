-- Reference scene "damped" of the work-precision benchmark
-- (bench/workprecision/scenes.c builds the same scene in C).
--
-- The hanging oscillator of oscillator.lua (m = 0.5 kg, k = 50 N/m, rest
-- 1 m, w = 10 rad/s, released A = 0.2 m below equilibrium) with a damped
-- spring: c = 0.5 N s/m, damping ratio z = c / (2 sqrt(k m)) = 0.05.
--
-- Truth (closed form, underdamped): with wd = w sqrt(1 - z^2) and
-- z_eq = -(1 + m g / k),
--   z(t) = z_eq - A e^(-z w t) (cos(wd t) + z w / wd sin(wd t)),  x = y = 0.
-- Error measure: |x(T) - x_true(T)| / A at T = 4 s.
-- The damping is velocity-dependent: "verlet" evaluates it at the predicted
-- end-of-step velocity, which keeps it second order.
-- Stability: symplectic Euler needs h w < 2 (sqrt(1 + z^2) - z) = 1.90.
local tumble = require "tumble"

local k, m, g, A, c = 50, 0.5, 9.81, 0.2, 0.5
local omega = math.sqrt(k / m)
local zeta = c / (2 * math.sqrt(k * m))
local wd, z_eq = omega * math.sqrt(1 - zeta * zeta), -(1 + m * g / k)

local w = tumble.world{ gravity = {0, 0, -g}, integrator = "rk4", dt = 1/100 }
local bob = w:particle{ pos = {0, 0, z_eq - A}, mass = m }
w:spring(bob, {0, 0, 0}, { k = k, damping = c, rest = 1 })

return {
  world = w, duration = 4, record_every = 1/50,
  -- the exact position at time t (s), m
  truth = function(t)
    local decay = A * math.exp(-zeta * omega * t)
    return 0, 0, z_eq - decay * (math.cos(wd * t) + zeta * omega / wd * math.sin(wd * t))
  end,
}
