-- The classic falling-objects demo: spheres, boxes and capsules of random
-- sizes (0.2 to 0.6 m) dropped from a grid onto a plane, where they pile up.
-- Every shape resists rolling by 5 mm (rolling_resistance: the normal force
-- may act that far ahead of a contact), so the balls and capsules that roll
-- off the pile come to rest, as on a real floor, and the pile falls asleep.
local tumble = require "tumble"

local rolling = 0.005
local w = tumble.world{ gravity = {0, 0, -9.81}, dt = 1/60 }
w:shape{ type = "plane", rolling_resistance = rolling }
local random = math.random
for layer = 0, 3 do
  for i = 0, 4 do
    for j = 0, 4 do
      local pos = {1.2 * (i - 2), 1.2 * (j - 2), 1 + 1.2 * layer}
      local kind = random(3)
      if kind == 1 then
        local r = 0.1 + 0.2 * random()
        local b = w:body{ sphere = r, density = 1000, pos = pos }
        w:shape{ type = "sphere", body = b, radius = r, rolling_resistance = rolling }
      elseif kind == 2 then
        local s = {0.2 + 0.4 * random(), 0.2 + 0.4 * random(), 0.2 + 0.4 * random()}
        local b = w:body{ box = s, density = 1000, pos = pos, omega = {random() - 0.5, random() - 0.5, 0} }
        w:shape{ type = "box", body = b, half = {s[1] / 2, s[2] / 2, s[3] / 2}, rolling_resistance = rolling }
      else
        local r, l = 0.1 + 0.1 * random(), 0.2 + 0.4 * random()
        local b = w:body{ capsule = {r, l}, density = 1000, pos = pos, omega = {random() - 0.5, 0, random() - 0.5} }
        w:shape{ type = "capsule", body = b, radius = r, half_length = l / 2, rolling_resistance = rolling }
      end
    end
  end
end

return { world = w, duration = 5, record_every = 1/10 }
