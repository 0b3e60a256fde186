-- The Lua module by LuaRocks: `luarocks --lua-version 5.4 make` in the
-- source tree builds tumble.so (the binding and the core in one module) and
-- installs it where require "tumble" finds it. docs/guide.md documents the
-- binding.
rockspec_format = "3.0"
package = "tumble"
version = "0.1.0-1"
source = { url = "git+https://example.invalid/tumble.git", tag = "v0.1.0" }
description = {
    summary = "A physics library for virtual worlds",
    detailed = "Tracers, particles, springs and rigid bodies with contacts, stepped by a C99 core.",
    license = "MIT",
}
dependencies = { "lua >= 5.4, < 5.5" }
build = {
    type = "builtin",
    modules = {
        tumble = {
            sources = {
            "src/world.c",
            "src/core/memory.c",
            "src/core/ids.c",
            "src/core/list.c",
            "src/core/state.c",
            "src/core/isa.c",
            "src/core/envelope.c",
            "src/particles/tracers.c",
            "src/particles/particles.c",
            "src/particles/particle_step.c",
            "src/bodies/bodies.c",
            "src/bodies/body_step.c",
            "src/bodies/mass.c",
            "src/bodies/rotation.c",
            "src/forces/springs.c",
            "src/forces/fields.c",
            "src/forces/forces.c",
            "src/joints/joints.c",
            "src/joints/joint_rows.c",
            "src/joints/joint_solve.c",
            "src/joints/joint_shake.c",
            "src/stepping/step.c",
            "src/stepping/integrators.c",
            "src/stepping/implicit.c",
            "src/stepping/auto.c",
            "src/stepping/advisor.c",
            "src/stepping/guard.c",
            "src/stepping/diagnostics.c",
            "src/stepping/snapshot.c",
            "src/collision/broadphase.c",
            "src/collision/collide.c",
            "src/contacts/shapes.c",
            "src/contacts/contact.c",
            "src/contacts/sleep.c",
            "src/contacts/soft_step.c", "src/contacts/stack_solve.c", "src/contacts/joint_contacts.c", "src/contacts/soft_joints.c",
            "src/contacts/continuous.c",
            "lua/tumble_lua.c",
            },
            incdirs = { "include", "src", "lua" },
            defines = { "TUMBLE_SHARED", "TUMBLE_LUA_BUILDING" },
            libraries = { "m" },
        },
    },
}
