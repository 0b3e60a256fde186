local tumble = require "tumble"
local w = tumble.world{ dt = 1 / 60 }
w:shape{ type = "plane" }
local b = w:body{ pos = { 0, 0, 1 }, mass = 1 }
w:shape{ type = "sphere", body = b, radius = 0.5 }
return { world = w, duration = 1 }
