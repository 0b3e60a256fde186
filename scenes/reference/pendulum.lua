-- Reference scene "pendulum" of the work-precision benchmark
-- (bench/workprecision/scenes.c builds the same scene in C; test_joints
-- and bench_joints swing it too).
--
-- A sphere of radius r = 5 cm and mass m = 1 kg whose centre hangs
-- l = 1 m from a hinge at the origin (axis y), released at rest 170
-- degrees from the bottom, under g = 9.81 m/s^2, for 2 1/4 periods.
--
-- Truth (closed form): a physical pendulum, theta'' = -w0^2 sin theta with
-- w0^2 = m g l / I_p, I_p = 2/5 m r^2 + m l^2. With k = sin(theta0 / 2),
--   sin(theta(t) / 2) = k sn(K(k) - w0 t, k),  period P = 4 K(k) / w0,
-- sn the Jacobi elliptic function and K the complete elliptic integral of
-- the first kind (both by the arithmetic-geometric mean below).
-- Error measure: |x(T) - x_true(T)| / l at T = 9/4 P, where the sphere
-- passes the bottom at its fastest: the error there is the phase error
-- times the speed (at a turning point it would be of its square).
local tumble = require "tumble"

local r, m, l, g = 0.05, 1, 1, 9.81
local theta0 = math.rad(170)
local w0 = math.sqrt(m * g * l / (0.4 * m * r * r + m * l * l))
local k = math.sin(theta0 / 2)

-- The arithmetic-geometric mean of 1 and sqrt(1 - k^2), with its steps'
-- half-differences c_n (converged to rounding well within 40 steps).
local function agm()
  local a, b, c = {1}, {math.sqrt(1 - k * k)}, {k}
  for n = 1, 40 do
    a[n + 1] = (a[n] + b[n]) / 2
    b[n + 1] = math.sqrt(a[n] * b[n])
    c[n + 1] = (a[n] - b[n]) / 2
    if math.abs(c[n + 1]) < 1e-17 then break end
  end
  return a, c
end
local A, C = agm()
local K = math.pi / (2 * A[#A])
local period = 4 * K / w0

-- sn(u, k) by the descending Landen transformation: phi_N = 2^N a_N u,
-- phi_{n-1} = (phi_n + asin(c_n / a_n sin phi_n)) / 2, sn = sin phi_0.
local function sn(u)
  local N = #A - 1
  local phi = 2 ^ N * A[N + 1] * u
  for n = N, 1, -1 do
    phi = (phi + math.asin(C[n + 1] / A[n + 1] * math.sin(phi))) / 2
  end
  return math.sin(phi)
end

local w = tumble.world{ gravity = {0, 0, -g}, integrator = "verlet", dt = 1/60 }
local ball = w:body{ sphere = r, mass = m, pos = {l * math.sin(theta0), 0, -l * math.cos(theta0)} }
w:joint{ type = "hinge", a = ball, anchor = {0, 0, 0}, axis = {0, 1, 0} }

return {
  world = w, duration = 2.25 * period, record_every = 1/60,
  -- the exact position of the sphere's centre at time t (s), m
  truth = function(t)
    local theta = 2 * math.asin(k * sn(K - w0 * t))
    return l * math.sin(theta), 0, -l * math.cos(theta)
  end,
}
