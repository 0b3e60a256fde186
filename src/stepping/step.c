/* step.c: the step driver (tb_world_step), the world's method and
   tolerance, and the primitives the methods are written in, each of which
   hands its part to the tiers. */
#include "stepping/stepping.h"
#include "bodies/bodies.h"
#include "contacts/contacts.h"
#include "forces/forces.h"
#include "joints/joints.h"
#include "particles/particles.h"

#include <math.h>
#include <string.h>

static tb_status refuse_split_with_tracers(tb_world *w, const tb__method *m)
{
    if (m->split && w->tracer_count)
        return tb__fail(w, TB_ERR_ARGUMENT,
                        "integrator '%s' kicks velocities and tracers have none: "
                        "use 'euler' or 'rk4' for a world with tracers", m->name);
    return TB_OK;
}

tb_status tb_world_set_integrator(tb_world *w, const char *name)
{
    const tb__method *m = name ? tb__method_find(name) : NULL;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if (!m)
        return tb__fail(w, TB_ERR_ARGUMENT, "unknown integrator '%s'", name ? name : "(null)");
    if ((st = tb__check_busy(w, "change the integrator")) != TB_OK)
        return st;
    if ((st = refuse_split_with_tracers(w, m)) != TB_OK)
        return st;
    w->method = m;
    return TB_OK;
}

tb_status tb_world_set_tolerance(tb_world *w, double tolerance)
{
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "change the tolerance")) != TB_OK ||
        (st = tb__check_scale(w, tolerance, "tolerance")) != TB_OK)
        return st;
    w->tolerance = tolerance;
    w->adaptive_h = 0; /* a new tolerance starts the step-size search afresh */
    return TB_OK;
}

double tb_world_tolerance(const tb_world *w)
{
    TB__NEED_WORLD(w, 0);
    return w->tolerance;
}

const char *tb_world_integrator(const tb_world *w)
{
    TB__NEED_WORLD(w, NULL);
    return w->method->name;
}

tb_status tb__derive(tb_world *w, double t, const double *y, double *dy)
{
    tb_status st = TB_OK;
    ++w->work.evaluations;
    if (w->tracer_count && (st = tb__tracer_derive(w, t, y, dy)) != TB_OK)
        return st;
    if ((st = tb__global_forces(w, t, y, y)) != TB_OK || (st = tb__joint_forces(w, y, y)) != TB_OK)
        return st;
    if (w->particle_count)
        tb__particle_derive(w, y, dy);
    if (w->body_count)
        tb__body_derive(w, y, dy);
    return TB_OK;
}

void tb__project(tb_world *w, double *y)
{
    if (w->body_count)
        tb__body_project(w, y);
}

tb_status tb__split_prepare(tb_world *w, double t, const double *seen)
{
    w->kick_seen = seen;
    ++w->work.evaluations;
    tb_status st;
    /* (no joint forces but the springs': the split methods' drifts hold
       the joints, tb__split_sweep) */
    if ((st = tb__global_forces(w, t, w->y, seen ? seen : w->y)) != TB_OK)
        return st;
    if (w->joint_count)
        tb__joint_spring_forces(w, w->y, seen ? seen : w->y);
    return TB_OK;
}

/* The ops in one pass over the particles and one over the bodies */
static void sweep(tb_world *w, const tb__split_op *ops, int n)
{
    if (n > 0 && w->particle_count)
        tb__particle_sweep(w, ops, n);
    if (n > 0 && w->body_count)
        tb__body_sweep(w, ops, n);
}

tb_status tb__split_sweep(tb_world *w, const tb__split_op *ops, int n)
{
    tb_status st;
    int i;
    for (i = 0; i < n && w->joint_count; ++i)
        if (ops[i].drift) { /* (the last op) the kicks before it, then the drift held on the joints */
            sweep(w, ops, i);
            if ((st = tb__joints_hold(w, ops[i].h)) != TB_OK)
                return st;
            sweep(w, ops + i, n - i);
            return tb__joints_shake(w, ops[i].h, ops[i].rotation);
        }
    sweep(w, ops, n);
    return TB_OK;
}

/* RK4 one block of objects at a time through all four stages, when nothing
   couples objects: only bodies, no springs, no callbacks (which might see
   every object). Returns whether it stepped. */
int tb__fused_rk4(tb_world *w, double h)
{
    if (!w->body_count || w->tracer_count || w->particle_count || w->forces.count || w->joint_count)
        return 0;
    w->force_ready = 0; /* what tb__global_forces finds with no springs or callbacks */
    w->work.evaluations += 4; /* each body's four stages */
    tb__body_rk4(w, h);
    return 1;
}

int tb__split_velocity_dependent(const tb_world *w)
{
    return w->forces.count > 0 || w->joint_count > 0 || tb__particle_velocity_dependent(w) ||
           tb__body_velocity_dependent(w);
}

void tb__split_extrapolate(const tb_world *w, double *saved)
{
    static const enum tb__quantity rates[] = { TB__PARTICLE_VEL, TB__BODY_MOM, TB__BODY_ANG };
    const size_t counts[] = { w->particle_count, w->body_count, w->body_count };
    size_t k, i;
    for (k = 0; k < 3; ++k) {
        double *s = saved + w->off[rates[k]];
        const double *v = w->y + w->off[rates[k]];
        for (i = 0; i < 3 * counts[k]; ++i)
            s[i] = 2 * v[i] - s[i];
    }
}

/* Halvings of a step whose joints the projection cannot meet, at most
   (2^5 = 32 steps in its place) */
#define MOST_HALVINGS 5

/* One step of h from the state, contacts and joints included; on failure
   the caller puts the world back */
static tb_status advance(tb_world *w, double h)
{
    tb_status st;
    double power = 0, sums[2] = { 0, 0 };
    const int damped = tb__is_damped(w);
    int summed;
    tb__joints_begin_step(w);
    if (tb__contacts_active(w) && (st = tb__contacts_prepare(w, h)) != TB_OK)
        return st;
    /* the drag's power at the start (and, without contacts, at the end)
       comes from the particles' sweep when it is the whole step: the same
       sums, without two passes of their own */
    summed = damped && tb__one_pass_step(w);
    if (damped && !summed)
        power = tb__damping_power(w);
    w->damping_sums = summed ? sums : NULL;
    w->stepping = 1;
    st = tb__method_step(w, w->method, h);
    w->stepping = 0;
    w->damping_sums = NULL;
    if (st != TB_OK)
        return st;
    if (tb__contacts_active(w)) {
        /* what the solve changes of the energy is the contacts' work; it
           changes only the bodies and particles in contact */
        const double before = tb__contacts_energy(w);
        tb__contacts_solve(w, h);
        w->work.contact_work += tb__contacts_energy(w) - before;
    }
    /* the bodies back on their joints, with the contact points of their
       islands (joint_shake.c, joint_contacts.c); the soft step carried
       the loads of those in contact (soft_joints.c) */
    if (w->joint_count && ((tb__contacts_active(w) && (st = tb__contacts_for_joints(w)) != TB_OK) ||
                           (st = tb__joints_project(w, h)) != TB_OK))
        return st;
    if (summed)
        w->work.damping_work += h / 2 * (sums[0] + (tb__contacts_active(w) ? tb__damping_power(w) : sums[1]));
    else if (damped)
        w->work.damping_work += h / 2 * (power + tb__damping_power(w));
    return TB_OK;
}

/* A step of h; where the projection cannot put the bodies back on their
   joints (a motion of the joints faster than the step holds, such as the
   links of a chain whipping a heavy weight round, turned them further in
   the step than any Newton step can undo), the step is taken again as
   two halves, and so on MOST_HALVINGS times: the substeps the motion
   needs, only where it needs them (test_joints.heavy_chain_holds_at_60_hz).
   Only from poses on their joints: joints no poses meet (a closed loop
   that does not close) would be halved in vain. Worlds with contacts
   step whole (their events are per step). */
static tb_status advance_held(tb_world *w, double h, int halvings)
{
    tb_status st;
    uint64_t evaluations;
    double t;
    if (!w->joint_count || w->joints_unmet || tb__contacts_active(w) || halvings == MOST_HALVINGS)
        return advance(w, h);
    if ((st = tb__retake_keep(w)) != TB_OK)
        return st;
    if ((st = advance(w, h)) != TB_OK || !w->joints_unmet)
        return st;
    evaluations = w->work.evaluations; /* (the attempt's are work done) */
    if ((st = tb__retake(w)) != TB_OK)
        return st;
    w->work.evaluations = evaluations;
    ++w->work.rejected;
    if ((st = advance_held(w, h / 2, halvings + 1)) != TB_OK)
        return st;
    t = w->time; /* the second half starts half way (the step adds h to the time) */
    w->time += h / 2;
    st = advance_held(w, h / 2, halvings + 1);
    w->time = t;
    return st;
}

/* A step can fail inside a callback. Methods that write the state only after
   their last force evaluation leave it untouched by construction; the others
   get a copy of the state to roll back to, taken only when something can
   fail. The guard keeps a copy of all the step can change (snapshot.c), so
   that a refused step, or a failed one, leaves no trace: not in the
   contacts' caches, not in sleep (test_snapshot.refused_step_leaves_no_trace). */
tb_status tb_world_step(tb_world *w, double h)
{
    tb_status st;
    int snapshot, guard = w && w->guard != 0;
    double *saved = NULL;
    tb_work work;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    work = w->work; /* a failed step leaves the counts as they were */
    if ((st = tb__check_scale(w, h, "step")) != TB_OK)
        return st;
    if ((st = tb__check_busy(w, "step")) != TB_OK)
        return st;
    if ((st = refuse_split_with_tracers(w, w->method)) != TB_OK)
        return st;
    snapshot = !guard && w->method->updates_before_last_evaluation && w->forces.count > 0;
    if (guard && (st = tb__rollback_keep(w)) != TB_OK)
        return st;
    if (snapshot) {
        if ((st = tb__state_scratch(w, (size_t)w->method->scratch + 1)) != TB_OK)
            return st;
        saved = tb__scratch_vector(w, (size_t)w->method->scratch);
        tb__state_copy(w, saved, w->y);
    }
    if ((st = advance_held(w, h, 0)) != TB_OK) {
        w->work = work;
        if (guard && tb__rollback(w) != TB_OK)
            tb__state_copy(w, w->y, tb__rollback_state(w)); /* out of memory: the state at least */
        else if (snapshot)
            tb__state_copy(w, w->y, saved);
        return st;
    }
    if (guard && (st = tb__guard_check(w, h)) != TB_OK) {
        w->work = work;
        return st; /* rolled back, held forces kept */
    }
    if (w->joint_count) /* over their breaking force in this step */
        tb__joints_break(w);
    if (w->body_count && w->body_held) /* held forces last one step, as in ODE */
        memset(w->body_applied, 0, 6 * w->body_count * sizeof(double));
    {   /* compensated sum: t after n steps of h is n h to the last bit */
        const double add = h - w->time_carry, sum = w->time + add;
        w->time_carry = (sum - w->time) - add;
        w->time = sum;
    }
    ++w->steps;
    ++w->work.steps;
    return TB_OK;
}

tb_work tb_world_work(const tb_world *w)
{
    if (!w) {
        const tb_work none = { 0, 0, 0, 0, 0, 0 };
        return none;
    }
    return w->work;
}
