/* tumble.h: the public C API of tumble, a physics library for virtual worlds.

   This header holds the functions, grouped by area. The types they take are
   in tumble/types.h, the ids in tumble/id.h, status codes, allocator and
   export macro in tumble/base.h; the guide is docs/guide.md.

   A world keeps its state in flat arrays per quantity (positions,
   velocities, masses, ...) and steps it with one of several integrators
   chosen by name. Objects are addressed by generation-checked value ids.
   Units are SI, axes right-handed, gravity a world setting.

   Rules that hold for every function below (the test that checks each
   claim in this header is named beside it, executable.case, a ctest
   entry):
   - a function that can fail returns a tb_status; on failure the world is
     unchanged and tb_world_message() holds a one-line reason
     (test_inputs.overflowing_inputs_are_refused_or_stay_finite, under
     every integrator);
   - NaN or Inf, non-positive masses or steps, negative stiffness, unknown
     names and stale ids (removed, or made by another world) are refused,
     never crash, abort or exit; so is any number outside the input rule
     (TB_LIMIT in tumble/base.h: at most 1e100 in magnitude, masses, moments,
     sizes and steps at least 1e-100, and what tumble derives from them at
     once, such as momentum and energy, at most 1e100;
     test_world.bad_particles_are_refused, bad_springs_are_refused,
     bad_steps_and_settings_are_refused, test_bodies.bad_bodies_are_refused);
   - a NULL pointer is refused (TB_ERR_ARGUMENT) unless a function says it
     may be NULL; a NULL world too: status functions return
     TB_ERR_ARGUMENT, the others 0, NULL, a null id or zeros (void
     functions write nothing), and tb_world_message(NULL) says why
     (test_inputs.null_pointers_are_refused); stale ids too
     (test_world.ids_survive_swap_remove_and_go_stale,
     ids_of_another_world_are_stale);
   - pointers to state arrays stay valid until the next step or structural
     change (adding or removing an object) of that world;
   - structural changes, setters and nested steps are refused (TB_ERR_BUSY)
     while the world is stepping, that is, from inside a force or field
     callback (callbacks only add to the forces or velocities they are given;
     test_world.structural_changes_are_refused_while_stepping);
   - worlds share nothing: several may live in one process and each may be
     stepped on its own thread (test_world.worlds_are_independent,
     test_world_threads.worlds_on_threads_keep_their_ids). */
#ifndef TUMBLE_H
#define TUMBLE_H

#include "tumble/base.h"
#include "tumble/id.h"
#include "tumble/types.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------- world -- */

/* The defaults documented in tb_world_def
   (test_world.defaults_are_documented_values). */
TB_API tb_world_def tb_default_world_def(void);

/* Create a world. On failure *world is NULL and, when message is not NULL,
   the reason is written to it (at most message_size bytes). */
TB_API tb_status tb_world_create(const tb_world_def *def, tb_world **world,
                                 char *message, size_t message_size);

/* Free the world and everything in it. NULL is ignored. Never call it from
   inside the world's own callbacks. */
TB_API void tb_world_destroy(tb_world *world);

/* The reason for the last failure in this world ("" if none yet). */
TB_API const char *tb_world_message(const tb_world *world);

/* Simulated time in seconds: the sum of all completed steps. */
TB_API double tb_world_time(const tb_world *world);

/* Gravity in m/s^2, for every particle and body. */
TB_API tb_status tb_world_set_gravity(tb_world *world, const double gravity[3]);
TB_API void tb_world_gravity(const tb_world *world, double gravity[3]);

/* Drag on every particle: f = -(linear + quadratic |v|) v. Both >= 0
   (test_forces.projectile_rk4_matches_closed_form,
   test_truths.quadratic_drag_throw_and_fall_at_each_order). */
TB_API tb_status tb_world_set_drag(tb_world *world, double linear, double quadratic);

/* ----------------------------------------------------------- stepping -- */

/* Integrators, by name (what each does to bodies' rotations, and the
   derivations: docs/integrators.md). Stability on x'' = -w^2 x - 2 z w x',
   damping ratio z:
     name                order  force evaluations    stable for h w below
     "euler"               1    1                    2 z (z <= 1): never undamped
     "symplectic_euler"    1    1                    2 (sqrt(1 + z^2) - z)
                                                     (ODE's dWorldStep)
     "verlet"              2    2                    2 / (z + sqrt(1 - 3 z^2))
                                                     for z <= 1/2, 1 / z above:
                                                     2, 1.73 at 0.3, 1 at 1
     "rk4"                 4    4                    2 sqrt 2 undamped, 2.79 at
                                                     z = 1; damps slightly
     "verlet_exact"        2    2                    as "verlet"; bodies turn to
                                                     4th order, ~2x "verlet" per
                                                     anisotropic body
     "implicit_euler"      1    1 + a CG solve       any step on springs and drag
                                                     (it damps them, and slows a
                                                     mode to atan(h w) / h)
     "dopri5"              5    6 or 7 per substep   substeps meet the tolerance
                                                     (each stable below 0.997
                                                     undamped, 3.2 at z = 0.3)
     "auto"                -    the chosen method's  the cheapest of verlet,
                                                     verlet_exact, rk4, dopri5 and
                                                     substeps that meet the
                                                     tolerance; "dopri5" when the
                                                     world has callbacks
   Orders: test_integrators.euler_is_first_order and the cases beside it
   (to dopri5_is_fifth_order; verlet_exact's 4th order rotation:
   test_rotation.orders_are_as_claimed); evaluations:
   test_integrators.each_method_makes_its_force_evaluations; limits:
   test_stability.damped_limits_match_simulation (dopri5's undamped limit
   is bracketed between 0.95 and 1.5 there) and the boundary cases beside
   it; implicit Euler: test_stability.implicit_euler_survives_100x_the_limit,
   implicit_euler_slows_oscillations; auto's choices:
   test_integrators.auto_picks_from_what_the_scene_contains; the cost of
   verlet_exact per anisotropic body is bench_bodies' (docs/benchmarks.md).
   The split methods (symplectic_euler, verlet, verlet_exact, implicit_euler)
   kick a velocity, which tracers lack: a world holding tracers refuses them,
   and a world using them refuses tracers
   (test_world.tracers_and_split_methods_exclude_each_other). Force
   callbacks run once per force evaluation
   (test_integrators.each_method_makes_its_force_evaluations). */
TB_API int tb_integrator_count(void);
TB_API const char *tb_integrator_name(int index);   /* NULL past the end */
TB_API int tb_integrator_order(int index);           /* 0 past the end */

TB_API tb_status tb_world_set_integrator(tb_world *world, const char *name);
/* The error per second of simulated time asked of adaptive methods
   ("dopri5", "auto"), relative to 1 + |y| per state component: a substep
   of s seconds may add an estimated error of tolerance x s, so a run of
   T seconds ends about tolerance x T off, times what the problem itself
   does to errors (docs/integrators.md): from 0.05 to 5 times on an orbit
   and a tumbling body (test_integrators.dopri5_global_error_follows_tolerance),
   0.003 to 0.02 on a smooth field and a charge in crossed fields
   (test_truths.time_dependent_field_follows_its_closed_form,
   charge_drifts_in_crossed_fields);
   from 1e-100 to 1e100. */
TB_API tb_status tb_world_set_tolerance(tb_world *world, double tolerance);
TB_API double tb_world_tolerance(const tb_world *world);
TB_API const char *tb_world_integrator(const tb_world *world);

/* What "auto" chose for its last step: the method's name (NULL before the
   first step) and the substeps per step. The choice is made again when the
   step, the tolerance or the set of objects changes
   (test_integrators.auto_picks_from_what_the_scene_contains,
   auto_meets_its_tolerance_per_step). */
TB_API const char *tb_world_auto_choice(const tb_world *world, long *substeps);

/* The work of the steps taken so far: steps, substeps, substeps rejected
   by "dopri5", force evaluations, and the energy the contacts and drag
   and damping changed (tb_work); zeros for NULL
   (test_integrators.each_method_makes_its_force_evaluations,
   energy_accounting_adds_up). */
TB_API tb_work tb_world_work(const tb_world *world);

/* Advance by h seconds (finite, from 1e-100 to 1e100). If a callback
   fails, the step is abandoned and the state is bit-identical to what it
   was before (test_world.failing_callback_leaves_state_bit_identical). */
TB_API tb_status tb_world_step(tb_world *world, double h);

/* The blow-up guard. energy_growth 0 (the default) turns it off, since it
   copies what a step can change every step; INFINITY undoes any step that leaves the
   state non-finite, a position, velocity, angular velocity or momentum
   past 1e150 (a runaway, far beyond what the input rule admits) or an
   orientation that is no longer a unit quaternion; a factor > 1 also undoes a step in which
   kinetic, rotational and spring energy grow by more than that factor
   beyond what gravity released (forces that do work must fit in it; a
   world starting at rest is checked once it moves). Such a step returns
   TB_ERR_UNSTABLE, with the advisor's verdict naming the step, the object
   and the cause; the world is back where the step began, solver caches
   and sleep included (as tb_world_restore puts it back), and steps again
   (with a smaller step, or once the cause is fixed). With the guard on, a
   step copies what it can change first (about the cost of a snapshot,
   without the constants: bench_snapshot). Tests:
   test_stability.guard_stops_a_blow_up_and_names_its_cause,
   guard_stops_a_runaway_and_the_world_steps_on, guard_names_the_damped_limit,
   guard_lets_stable_runs_through, test_snapshot.refused_step_leaves_no_trace. */
TB_API tb_status tb_world_set_guard(tb_world *world, double energy_growth);
TB_API double tb_world_guard(const tb_world *world);

/* ------------------------------------------------------------ snapshots -- */
/* A snapshot is a copy of everything the world owns: the state, the
   objects and their ids, settings, the contact solver's caches and warm
   starts, sleep, the last step's events, time and step count. Restoring it
   puts the world back exactly: stepping on continues bit-identically to
   the run that took the snapshot, ids made since are stale and ids
   removed since are live again. Its memory comes from the world's
   allocator, which it keeps: it may outlive its world.
   Taking one (tb_world_snapshot) and restoring one are refused while the
   world is stepping (TB_ERR_BUSY); a snapshot of another world is refused
   (TB_ERR_ARGUMENT); out of memory (TB_ERR_MEMORY), the world is
   unchanged. The world's message, guard snapshot and integrator scratch
   are its own and stay (test_snapshot.restore_continues_bit_identically,
   restore_brings_back_ids, foreign_and_busy_restores_are_refused,
   failed_allocations_leave_the_world_unchanged). */
TB_API tb_status tb_world_snapshot(tb_world *world, tb_snapshot **snapshot);
/* Take a snapshot of this world again into an existing one, reusing its
   memory where the world's arrays still fit (a rollback host keeping a
   ring of snapshots allocates nothing once they have grown). Out of
   memory, the snapshot is left empty: tb_world_restore refuses it until it
   is taken again. */
TB_API tb_status tb_world_snapshot_into(tb_world *world, tb_snapshot *snapshot);
TB_API tb_status tb_world_restore(tb_world *world, const tb_snapshot *snapshot);
/* Free a snapshot (NULL is ignored). */
TB_API void tb_snapshot_destroy(tb_snapshot *snapshot);
/* The bytes it holds, and the world time it was taken at (0 for NULL). */
TB_API size_t tb_snapshot_size(const tb_snapshot *snapshot);
TB_API double tb_snapshot_time(const tb_snapshot *snapshot);

/* A 64-bit FNV-1a hash of what the next step's result depends on, over
   bit patterns in a fixed order: object counts, step count, time, the used
   state vector, sleep (rest times, islands) and every contact's warm
   starts. Two worlds built and stepped by the same calls in the same order
   have the same hash, whatever the build type, compiler or instruction set
   (test_snapshot.contact_scene_hash_is_recorded; docs/guide.md, section
   14). 0 for NULL. */
TB_API uint64_t tb_world_hash(const tb_world *world);

/* -------------------------------------------------------------- tracers -- */
/* Tracers are massless points carried by the sum of the world's velocity
   fields: dx/dt = v(x, t). */

TB_API tb_tracer_def tb_default_tracer_def(void);
TB_API tb_status tb_world_add_tracer(tb_world *world, const tb_tracer_def *def, tb_tracer_id *id);
TB_API tb_status tb_world_remove_tracer(tb_world *world, tb_tracer_id id);
TB_API tb_status tb_tracer_position(const tb_world *world, tb_tracer_id id, double position[3]);
TB_API tb_status tb_tracer_set_position(tb_world *world, tb_tracer_id id, const double position[3]);

TB_API size_t tb_world_tracer_count(const tb_world *world);
/* Flat array of 3 * count positions (m), in slot order. */
TB_API const double *tb_world_tracer_positions(const tb_world *world);
TB_API tb_tracer_id tb_world_tracer_at(const tb_world *world, size_t slot);
/* The field velocity (m/s) at each tracer now, 3 * count values (not
   NULL). Calls the field callbacks, so it can fail like a step
   (test_forces.fields_add_up). */
TB_API tb_status tb_world_tracer_velocities(tb_world *world, double *velocities);

/* ---------------------------------------------------------------- fields -- */

/* v = u everywhere (m/s). */
TB_API tb_status tb_world_add_uniform_field(tb_world *world, const double velocity[3], tb_field_id *id);
/* Rigid rotation: v = omega x (x - centre); omega in rad/s
   (test_integrators.vortex_radius_follows_stability_functions). */
TB_API tb_status tb_world_add_vortex_field(tb_world *world, const double omega[3],
                                           const double centre[3], tb_field_id *id);
/* A field computed by fn (see tb_field_args), called with whole arrays. */
TB_API tb_status tb_world_add_field(tb_world *world, tb_field_fn *fn, void *user, tb_field_id *id);
TB_API tb_status tb_world_remove_field(tb_world *world, tb_field_id id);

/* ------------------------------------------------------------ particles -- */
/* Point masses: dv/dt = f / m. A pinned particle has infinite inertia: it
   takes no force, keeps its velocity, and counts as mass 0 in diagnostics
   (test_forces.pinned_particles_do_not_move). */

TB_API tb_particle_def tb_default_particle_def(void);
/* Adding a particle may move the state arrays. Removing one also removes
   the springs attached to it (test_world.removing_a_particle_removes_its_springs). */
TB_API tb_status tb_world_add_particle(tb_world *world, const tb_particle_def *def, tb_particle_id *id);
TB_API tb_status tb_world_remove_particle(tb_world *world, tb_particle_id id);
TB_API tb_status tb_particle_position(const tb_world *world, tb_particle_id id, double position[3]);
TB_API tb_status tb_particle_velocity(const tb_world *world, tb_particle_id id, double velocity[3]);
TB_API tb_status tb_particle_mass(const tb_world *world, tb_particle_id id, double *mass);
TB_API tb_status tb_particle_set_position(tb_world *world, tb_particle_id id, const double position[3]);
TB_API tb_status tb_particle_set_velocity(tb_world *world, tb_particle_id id, const double velocity[3]);

TB_API size_t tb_world_particle_count(const tb_world *world);
/* Flat arrays in slot order: 3 * count positions (m), 3 * count velocities
   (m/s), count masses (kg, 0 for pinned particles). */
TB_API const double *tb_world_particle_positions(const tb_world *world);
TB_API const double *tb_world_particle_velocities(const tb_world *world);
TB_API const double *tb_world_particle_masses(const tb_world *world);
TB_API tb_particle_id tb_world_particle_at(const tb_world *world, size_t slot);

/* -------------------------------------------------------------- springs -- */
/* Hooke springs with damping along their axis:
     f_a = -(k (|d| - rest) + c (v_a - v_b) . n) n,  d = x_a - x_b, n = d / |d|,
   and f_b = -f_a. With a null `b` the spring ties `a` to the fixed `anchor`
   (test_forces.damped_spring_matches_closed_form,
   two_body_spring_conserves_momentum, two_body_spring_oscillates_at_reduced_mass_frequency). */

TB_API tb_spring_def tb_default_spring_def(void);
TB_API tb_status tb_world_add_spring(tb_world *world, const tb_spring_def *def, tb_spring_id *id);
TB_API tb_status tb_world_remove_spring(tb_world *world, tb_spring_id id);
TB_API size_t tb_world_spring_count(const tb_world *world);
/* The spring in slot 0 .. tb_world_spring_count() - 1, to walk them all
   (a removal moves the last spring into the freed slot); the null id past
   the end. */
TB_API tb_spring_id tb_world_spring_at(const tb_world *world, size_t slot);
/* What a spring is, as the world holds it: its ends (b null and the
   anchor for an anchored spring), stiffness, damping and rest length (the
   distance at creation when it was added with a negative one), so that a
   host can draw it. TB_ERR_STALE_ID for a removed or foreign id
   (test_forces.springs_read_back). */
TB_API tb_status tb_spring_definition(const tb_world *world, tb_spring_id id, tb_spring_def *def);

/* --------------------------------------------------------- mass properties -- */
/* Mass properties (tb_mass) from shapes of uniform density rho (kg/m^3),
   point masses, a closed triangle mesh or a full inertia tensor. They touch
   no world: on failure they return TB_ERR_ARGUMENT (tb_mass_mesh also
   TB_ERR_MEMORY: it sorts edges in scratch from malloc), write a one-line
   reason into `message` when it is not NULL (TB_MESSAGE_SIZE bytes), and
   leave *mass untouched. A result no body could take is refused: a mass
   or a principal moment outside [1e-100, 1e100], a centre past 1e100
   (the input rule, TB_LIMIT). Tests: test_mass, against closed forms
   and ODE's dMass functions (test_mass.primitives_match_ode). */

/* Solid sphere of radius r (m). */
TB_API tb_status tb_mass_sphere(double rho, double radius, tb_mass *mass, char *message);
/* Solid box with full side lengths size[3] (m), centred, axes along x, y, z. */
TB_API tb_status tb_mass_box(double rho, const double size[3], tb_mass *mass, char *message);
/* Solid cylinder of radius r and length l along z, centred. */
TB_API tb_status tb_mass_cylinder(double rho, double radius, double length, tb_mass *mass, char *message);
/* Capsule: a cylinder of radius r and length l >= 0 along z with two
   hemispherical caps (total length l + 2 r), centred; l = 0 is a sphere. */
TB_API tb_status tb_mass_capsule(double rho, double radius, double length, tb_mass *mass, char *message);
/* Point masses m_i (kg, > 0) at p_i (3 * count values, m): M = sum m_i,
   c = sum m_i p_i / M, I = sum m_i (r_i.r_i 1 - r_i r_i^T) with r_i = p_i - c,
   then diagonalised. Fewer than 3 non-collinear points give a singular
   tensor and are refused. */
TB_API tb_status tb_mass_points(size_t count, const double *positions, const double *masses,
                                tb_mass *mass, char *message);
/* Closed triangle mesh: vertices (3 * vertex_count, m), triangles
   (3 * triangle_count vertex indices, counter-clockwise seen from outside).
   Open meshes (an edge not shared by exactly two triangles in opposite
   directions) and inside-out meshes (negative volume) are refused. */
TB_API tb_status tb_mass_mesh(double rho, size_t vertex_count, const double *vertices,
                              size_t triangle_count, const uint32_t *triangles, tb_mass *mass, char *message);
/* From a mass, a centre of mass and a full symmetric inertia tensor about
   that centre (row-major 3x3, kg m^2), diagonalised. A tensor that is not
   symmetric positive definite, or whose principal moments break the
   triangle inequality (I1 + I2 >= I3 for every order), is refused. */
TB_API tb_status tb_mass_from_tensor(double total_mass, const double centre[3], const double tensor[9],
                                     tb_mass *mass, char *message);
/* Scale to a given total mass (kg, from 1e-100 to 1e100), keeping the shape. */
TB_API tb_status tb_mass_set_total(tb_mass *mass, double total_mass, char *message);

/* --------------------------------------------------------------- bodies -- */
/* Rigid bodies. State: centre of mass x, orientation q (unit quaternion
   (w, x, y, z) turning the body's principal axes into the world), linear
   momentum P and angular momentum L (world frame, about the centre of mass):
     v = P / M,  w = R diag(1/I) R^T L,  dx/dt = v,  dq/dt = (0, w) q / 2,
     dP/dt = f,  dL/dt = tau.
   Keeping L (not w) as state means a torque-free body keeps L exactly and
   every rotation error lives in the orientation (L to rounding:
   test_bodies.torque_free_body_keeps_momenta). Positions and orientations
   read back are those of the centre of mass and the principal axes. */

TB_API tb_body_def tb_default_body_def(void);
/* The body's centre of mass goes to position + R(orientation) mass.centre
   and its principal axes to orientation * mass.frame. Refused: values
   outside the input rule (mass and moments outside [1e-100, 1e100], the
   rest past 1e100, and so momentum P = m v and L = I w and the energies
   m v^2 / 2 and w.I.w / 2), a quaternion whose norm is not 1 within 1e-6
   (it is then normalised exactly), moments that break the triangle
   inequality, negative damping (test_bodies.bad_bodies_are_refused). */
TB_API tb_status tb_world_add_body(tb_world *world, const tb_body_def *def, tb_body_id *id);
/* Removing a body removes its shapes. */
TB_API tb_status tb_world_remove_body(tb_world *world, tb_body_id id);

TB_API tb_status tb_body_position(const tb_world *world, tb_body_id id, double position[3]);
TB_API tb_status tb_body_orientation(const tb_world *world, tb_body_id id, double orientation[4]);
TB_API tb_status tb_body_velocity(const tb_world *world, tb_body_id id, double velocity[3]);
TB_API tb_status tb_body_angular_velocity(const tb_world *world, tb_body_id id, double angular_velocity[3]);
/* Linear momentum P (kg m/s) and angular momentum L about the centre of
   mass (kg m^2/s), world frame. Either pointer may be NULL. */
TB_API tb_status tb_body_momentum(const tb_world *world, tb_body_id id, double linear[3], double angular[3]);
/* Mass (kg) and principal moments (kg m^2); either pointer may be NULL. */
TB_API tb_status tb_body_mass(const tb_world *world, tb_body_id id, double *mass, double inertia[3]);
TB_API tb_status tb_body_set_position(tb_world *world, tb_body_id id, const double position[3]);
TB_API tb_status tb_body_set_orientation(tb_world *world, tb_body_id id, const double orientation[4]);
TB_API tb_status tb_body_set_velocity(tb_world *world, tb_body_id id, const double velocity[3]);
/* Setters refuse a state whose momentum or energy breaks the input rule;
   an orientation keeps the angular velocity, so L = I w is checked anew. */
TB_API tb_status tb_body_set_angular_velocity(tb_world *world, tb_body_id id, const double angular_velocity[3]);

/* Forces and torques held for the next step, then cleared (as in ODE): a
   force f (N) at a world point p (m) also adds the torque (p - x) x f; at a
   point given in the body's principal frame, p = x + R p_body. A torque is
   in N m, world frame. A force whose torque, or whose sum with what the
   body already holds, passes 1e100 is refused (the input rule).
   Tests: test_bodies.off_centre_push_adds_torque (dP = h f, dL = h r x f
   under every method, at world and body points), constant_torque_spins_up
   (cleared after the step). */
TB_API tb_status tb_body_apply_force(tb_world *world, tb_body_id id, const double force[3], const double point[3]);
TB_API tb_status tb_body_apply_force_at_body_point(tb_world *world, tb_body_id id, const double force[3],
                                                   const double body_point[3]);
TB_API tb_status tb_body_apply_torque(tb_world *world, tb_body_id id, const double torque[3]);

TB_API size_t tb_world_body_count(const tb_world *world);
/* Flat arrays in slot order: 3 * count centres of mass (m), 4 * count
   orientations (w, x, y, z). */
TB_API const double *tb_world_body_positions(const tb_world *world);
TB_API const double *tb_world_body_orientations(const tb_world *world);
TB_API tb_body_id tb_world_body_at(const tb_world *world, size_t slot);

/* ---------------------------------------------------------- user forces -- */

/* A force computed by fn (see tb_force_args), called once per force
   evaluation with whole arrays (test_forces.c_force_callback_pushes,
   test_integrators.each_method_makes_its_force_evaluations). */
TB_API tb_status tb_world_add_force(tb_world *world, tb_force_fn *fn, void *user, tb_force_id *id);
TB_API tb_status tb_world_remove_force(tb_world *world, tb_force_id id);

/* --------------------------------------------------------------- joints -- */
/* Joints hold bodies together, or a body to the world, and particles in
   the bodies' places in ball and distance joints (tb_joint_def;
   test_joints.particles_hang_on_rods). Each
   force evaluation of every integrator solves their forces from the
   bodies' other forces and motion (the accelerations the joints allow,
   exactly), and after each step the bodies are put back on the joints,
   positions then velocities; how, and what each integrator's order
   becomes: docs/joints.md (test_joints.pendulum_period_matches_closed_form,
   rk4_pendulum_keeps_its_order, double_pendulum_keeps_its_energy,
   joints_hold_every_type). The shapes of two bodies a joint holds pass
   through each other unless tb_joint_def.collide is set
   (test_joints.jointed_bodies_pass_through_each_other). A removed body
   takes its joints with it (test_joints.removing_a_body_removes_its_joints). */
TB_API tb_joint_def tb_default_joint_def(void);
TB_API tb_status tb_world_add_joint(tb_world *world, const tb_joint_def *def, tb_joint_id *id);
TB_API tb_status tb_world_remove_joint(tb_world *world, tb_joint_id id);
TB_API size_t tb_world_joint_count(const tb_world *world);
/* The joint in slot 0 .. tb_world_joint_count() - 1; the null id past the
   end (a removal moves the last joint into the freed slot). */
TB_API tb_joint_id tb_world_joint_at(const tb_world *world, size_t slot);
/* The force (N) and torque (N m, about the joint's anchor on a) the joint
   exerted on body a over the last step (the split methods: its impulses
   over the step's length; the others: at the last force evaluation); b
   feels the opposite (test_joints.reaction_carries_the_weight). Zeros
   before the first step. */
TB_API tb_status tb_joint_reaction(const tb_world *world, tb_joint_id id, double force[3], double torque[3]);
/* How far the joint is from holding now: the largest of its rows' errors
   (m for points, and for axes that should be square the cosine between
   them) (test_joints.joints_hold_every_type). */
TB_API tb_status tb_joint_error(const tb_world *world, tb_joint_id id, double *error);
/* The joint's free coordinate now and its rate (rate may be NULL): HINGE,
   the angle (rad) a has turned about the axis relative to b since
   creation; SLIDER, how far (m) a's anchor has moved along the axis from
   b's; DISTANCE, the distance (m); BALL, the angle (rad) between a's and
   b's copies of the axis. A fixed joint has none: TB_ERR_ARGUMENT. */
TB_API tb_status tb_joint_position(const tb_world *world, tb_joint_id id, double *position, double *rate);
/* A joint's limit, motor and spring switched and set between steps, as
   tb_joint_def has them (limits: test_joint_drives.limits_stop_the_swing,
   twist_stops_the_turn;
   motors: motor_turns_at_its_speed; springs: springs_ring_at_their_hz).
   The bodies are woken. */
TB_API tb_status tb_joint_set_limit(tb_world *world, tb_joint_id id, int enable, double lower, double upper);
TB_API tb_status tb_joint_set_twist_limit(tb_world *world, tb_joint_id id, int enable, double lower, double upper);
TB_API tb_status tb_joint_set_motor(tb_world *world, tb_joint_id id, int enable, double speed, double max_force);
TB_API tb_status tb_joint_set_spring(tb_world *world, tb_joint_id id, int enable, double hz, double damping_ratio,
                                     double target);

/* ------------------------------------------------------ shapes, contacts -- */
/* Shapes make bodies and particles collide; a world without shapes pays
   nothing for collision. How contacts are found and solved: docs/contacts.md. */

TB_API tb_shape_def tb_default_shape_def(void);
/* Refused: sizes outside [1e-100, 1e100] (half_length and offset: past
   1e100), a plane normal that is not unit within 1e-6, a plane on a body,
   a stale body, friction < 0, restitution outside [0, 1],
   rolling_resistance < 0 or not finite, a non-unit orientation, any value
   past the input rule (test_contacts_api.bad_shapes_are_refused). */
TB_API tb_status tb_world_add_shape(tb_world *world, const tb_shape_def *def, tb_shape_id *id);
TB_API tb_status tb_world_remove_shape(tb_world *world, tb_shape_id id);
TB_API size_t tb_world_shape_count(const tb_world *world);
/* The shape in slot 0 .. tb_world_shape_count() - 1, to walk them all (a
   removal moves the last shape into the freed slot); the null id past the
   end. */
TB_API tb_shape_id tb_world_shape_at(const tb_world *world, size_t slot);
/* What a shape is, as the world holds it: the definition it was added with
   (the orientation normalised; a box's half_length 0, a capsule's
   half_extents 0), so that a host can draw it at its body's pose.
   TB_ERR_STALE_ID for a removed or foreign id
   (test_contacts_api.shapes_read_back_as_defined). */
TB_API tb_status tb_shape_definition(const tb_world *world, tb_shape_id id, tb_shape_def *def);

TB_API tb_contact_settings tb_default_contact_settings(void);
/* Refused: values outside the ranges tb_contact_settings gives or the
   input rule, and substeps outside 1 to 1000000. */
TB_API tb_status tb_world_set_contact_settings(tb_world *world, const tb_contact_settings *settings);
TB_API tb_contact_settings tb_world_contact_settings(const tb_world *world);

/* The contacts that began and ended in the last step, valid until the next
   step or structural change; count may be NULL
   (test_contacts_bounce.events_report_impacts). */
TB_API const tb_contact_event *tb_world_contact_events(const tb_world *world, size_t *count);
/* Points of contact that are touching now (after the last step). */
TB_API size_t tb_world_contact_count(const tb_world *world);
/* The deepest overlap (m, >= 0) among those points, as the last step found
   it at its start, before solving (0: none overlaps, or no step yet;
   test_contacts_api.deepest_overlap_is_read). */
TB_API double tb_world_deepest_overlap(const tb_world *world);

/* Sleep: an island of bodies joined by touching contacts that rests for
   sleep_time falls asleep: it keeps its pose with zero velocity, costs no
   narrowphase and no solver work (the integrator still passes over it),
   and is static ground for slow particles. It
   wakes, whole, when the bounds of an awake body that is not resting (it
   was not slower than sleep_speed last step, or was just added, set or
   woken) or of a particle faster than sleep_speed reach it, when any of
   its state is set or a force or torque applied, when one of its bodies
   is removed, and when gravity, shapes or contact settings change
   (test_contacts_sleep.every_listed_trigger_wakes_an_island,
   resting_box_falls_asleep_and_stays_put, islands_wake_together); an
   awake body at rest beside it does not wake it
   (test_contacts_sleep.resting_neighbours_let_an_island_sleep). Worlds
   with force callbacks never sleep: a callback's force is unknown to the
   rest test (test_contacts_sleep.sleep_settings). */
TB_API tb_status tb_body_asleep(const tb_world *world, tb_body_id id, int *asleep);
TB_API tb_status tb_body_wake(tb_world *world, tb_body_id id);
TB_API size_t tb_world_sleeping_count(const tb_world *world);

/* --------------------------------------------------------------- advisor -- */

/* Before a run: the stability limit of the world's integrator for a step h
   (as tb_world_step takes it), damping counted: the method's damped limit
   on the stiffest spring mode (power iteration on M^-1 K, pinned particles
   excluded) with the damping ratio it sees, on the most damped mode, and
   its decay limit on the fastest drag or body damping (docs/integrators.md;
   within 10% of the measured blow-up on damped chains and cloth,
   test_stability.advisor_predicts_damped_chains, advisor_predicts_damped_cloth;
   explicit Euler on an undamped chain: 0, advisor_refuses_bad_steps).
   Changes nothing. */
TB_API tb_status tb_world_advise(tb_world *world, double h, tb_advice *advice);

/* tb_world_energy with the potential energy force callbacks report
   (tb_force_args.potential) in energy->potential and the total: each
   callback runs once at the current state, its forces thrown away. A
   callback that fails fails this call (TB_ERR_CALLBACK), *energy
   untouched; refused while stepping (TB_ERR_BUSY). Lua worlds: the
   binding's w:energy() and tb_lua_energy
   (test_integrators.energy_accounting_adds_up,
   test_lua.energy_from_lua_counts_callbacks). */
TB_API tb_status tb_world_energy_with_callbacks(tb_world *world, tb_energy *energy);

/* ---------------------------------------------------------- diagnostics -- */

TB_API tb_energy tb_world_energy(const tb_world *world);
/* Total linear momentum, kg m/s. */
TB_API void tb_world_momentum(const tb_world *world, double momentum[3]);
/* Total angular momentum about the world origin, kg m^2/s:
   sum m x x v over particles, sum (x x P + L) over bodies
   (test_bodies.diagnostics_add_up). */
TB_API void tb_world_angular_momentum(const tb_world *world, double angular[3]);

#ifdef __cplusplus
}
#endif
#endif
