-- require_module.lua: a stock lua5.4 loads the module tumble.so (ctest
-- lua_module.require, with LUA_CPATH at the build folder) and runs a ball
-- dropped on a plane for 2 s: it must rest one radius up. Argument 1: the
-- project's version, which _VERSION must name.
local tumble = require "tumble"
assert(tumble._VERSION == "tumble " .. arg[1], "_VERSION is " .. tostring(tumble._VERSION))
local w = tumble.world{ gravity = { 0, 0, -9.81 }, dt = 1 / 60 }
w:shape{ type = "plane" }
local ball = w:body{ sphere = 0.5, mass = 1, pos = { 0, 0, 1 } }
w:shape{ type = "sphere", body = ball, radius = 0.5 }
for _ = 1, 120 do w:step() end
local _, _, z = ball:pos()
assert(math.abs(z - 0.5) < 1e-3, "the ball rests at z = " .. z)
print(tumble._VERSION .. ": ball at z = " .. string.format("%.4f", z))
