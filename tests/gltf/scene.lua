-- The glTF tests' scene (tests/gltf/check.sh, tests/gltf/test_gltf.c):
-- every kind of shape and object the writer draws. Three bodies in a row
-- at x = -1.5, 0, 1.5 m and 1.5 m up (a ball, a spinning box, a tilted
-- capsule) fall onto the ground; a static box stands behind them; two
-- particles on springs (one to an anchor, one between them) swing off to
-- the side, at x >= 2.5 m, clear of the bodies and the gaps between them
-- that the render check looks at.
local tumble = require "tumble"

local w = tumble.world{ gravity = {0, 0, -9.81}, dt = 1/120 }
w:shape{ type = "plane" }
w:shape{ type = "box", pos = {0, 3, 0.25}, half = {1, 0.25, 0.25} }

local ball = w:body{ sphere = 0.3, mass = 1, pos = {-1.5, 0, 1.5} }
w:shape{ type = "sphere", body = ball, radius = 0.3 }
local box = w:body{ box = {0.5, 0.5, 0.5}, mass = 1, pos = {0, 0, 1.5}, omega = {0, 0, 2} }
w:shape{ type = "box", body = box, half = {0.25, 0.25, 0.25} }
local s = math.sqrt(0.5)
local capsule = w:body{ capsule = {0.2, 0.5}, mass = 1, pos = {1.5, 0, 1.5}, rot = {s, 0, s, 0} }
w:shape{ type = "capsule", body = capsule, radius = 0.2, half_length = 0.25 }

local p1 = w:particle{ pos = {2.5, 0.5, 1.5}, mass = 0.2 }
local p2 = w:particle{ pos = {3.0, 0.5, 1.2}, mass = 0.2 }
w:spring(p1, {2.5, 0.5, 2.0}, { k = 40 })
w:spring(p1, p2, { k = 40 })

return { world = w, duration = 1, record_every = 1/20 }
