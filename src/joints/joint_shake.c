/* joint_shake.c: the bodies and particles put on their joints
   (docs/joints.md): the projection after every step (tb__joints_project:
   Newton steps that move each node through its inverse mass and inertia,
   then the velocities' components along the rows taken out by an
   impulse, both lowest in kinetic-energy norm and of the order of the
   step's own error), and SHAKE through the split methods' drifts
   (tb__joints_hold, tb__joints_shake: the impulses along the rows held at
   the drift's start that bring the drifted poses onto the joints, by
   Newton steps on a matrix that is not symmetric; where it finds none, a
   mode faster than the step, the step taken implicitly: the free drift
   projected, its impulse added; test_joints.released_chains_hold;
   where even that projection cannot meet them, it says so, and step.c
   takes the step again in halves). A Newton step that leaves the error
   larger goes half the way. Limits
   join where passed (and in SHAKE while they push), motors only in the
   velocities' projection (test_joint_drives). */
#include "joints/joint_work.h"
#include "bodies/bodies.h"

#include <math.h>
#include <string.h>

/* Newton steps of the projection at most: each doubles the error's digits
   near the joints, and from farther (the free drift of an implicit step)
   each takes off a share */
#define PROJECTION_STEPS 30
/* SHAKE's steps at most: each takes the error down by about the turn of
   the rows over the step */
#define SHAKE_STEPS 40
/* halvings of a Newton step that left the error larger, at most */
#define BACKTRACKS 6
/* m (or the cosine of square axes): SHAKE left more than this unmet */
#define UNMET 1e-10
/* ... and an error this small is met: rounding on metre-sized joints (a
   larger world stops where a step no longer halves its error) */
#define MET 1e-14
/* an error left this far under the largest coordinate is the poses'
   rounding, which no step can take out (a joint's error is a difference
   of coordinates, each rounded to about 1e-16 of itself) */
#define ROUNDING 1e-12

/* The rows set up last (with their weighted copies, if asked) kept in
   k->held, which SHAKE's Newton steps and the projection's trials apply
   while each trial sets the rows up again */
static tb_status keep_rows(tb_world *w, struct tb__joint_work *k, size_t rows, int weighted)
{
    tb_status st;
    if ((st = tb__reserve(w, (void **)&k->held, &k->held_cap, rows + 1, sizeof *k->held)) != TB_OK ||
        (st = tb__reserve(w, (void **)&k->held_weighted, &k->held_weighted_cap, rows + 1, sizeof *k->held_weighted)) !=
            TB_OK)
        return st;
    memcpy(k->held, k->rows, rows * sizeof *k->held);
    if (weighted)
        memcpy(k->held_weighted, k->weighted, rows * sizeof *k->held_weighted);
    return TB_OK;
}

/* The largest coordinate of a moved end: the scale of the rounding in
   its poses */
static double farthest(const tb_world *w, const struct tb__joint_work *k)
{
    const double *x = w->y + w->off[TB__BODY_POS], *px = w->y + w->off[TB__PARTICLE_POS];
    double most = 0;
    size_t i;
    int d;
    for (i = 0; i < k->moved_count; ++i) {
        const int32_t s = k->moved[i];
        const double *at = tb__joint_is_particle(s) ? px + 3 * tb__joint_particle_slot(s) : x + 3 * s;
        for (d = 0; d < 3; ++d)
            most = fmax(most, fabs(at[d]));
    }
    return most;
}

/* The moved ends put on their joints by Newton steps that move each
   through its inverse mass and inertia (lowest in kinetic-energy norm),
   until the error is met (MET), or below UNMET no step halves it
   (rounding); a step that leaves it larger goes half the way, up to
   BACKTRACKS times, since the turns of light bodies outrun the step's
   linear model. With h > 0, each step's impulse over h (J^T delta / h,
   what moved the ends) goes to their momenta and the reactions too: the
   step of an implicit method (tb__joints_shake). w->joints_unmet says
   whether it left more than rounding (step.c then takes the step again
   in halves). */
static tb_status project_positions(tb_world *w, double h)
{
    double *x = w->y + w->off[TB__BODY_POS], *q = w->y + w->off[TB__BODY_ROT];
    double *px = w->y + w->off[TB__PARTICLE_POS];
    struct tb__joint_work *k;
    double most, next = 0;
    size_t rows, i;
    tb_status st;
    int step, tries, d;
    if ((st = tb__joint_set_up(w, w->y, w->y, 0, TB__SET_UP_MATRIX, &rows)) != TB_OK)
        return st;
    k = w->joint_work;
    most = tb__joint_largest_error(k, rows);
    for (step = 0; step < PROJECTION_STEPS && most > MET; ++step) {
        double share = 1;
        /* (the trials set up the rows alone) */
        if (step > 0 && (st = tb__joint_set_up(w, w->y, w->y, 0, TB__SET_UP_MATRIX, &rows)) != TB_OK)
            return st;
        for (i = 0; i < rows; ++i) { /* the joints, and the limits passed */
            k->x[i] = -k->rows[i].error;
            k->use[i] = k->rows[i].kind == TB__ROW_EQUAL || (k->rows[i].kind == TB__ROW_LIMIT && k->rows[i].error < 0);
        }
        tb__joint_solve(k, rows, 0);
        memcpy(k->newton, k->x, rows * sizeof *k->newton);
        if ((st = keep_rows(w, k, rows, 1)) != TB_OK) /* (SHAKE's room, unused after it) */
            return st;
        tb__joint_keep(w, k, k->kept, 1, 1);
        for (tries = 0; tries < BACKTRACKS; ++tries, share /= 2) {
            /* each node's move summed over the rows, then made as one
               translation and one turn (turns made row by row would not
               sum: a light body's rows turn it by radians that cancel) */
            for (i = 0; i < k->moved_count; ++i)
                memset(k->accel + 6 * tb__joint_node(w, k->moved[i]), 0, 6 * sizeof *k->accel);
            for (i = 0; i < rows; ++i) {
                const tb__joint_row *r = &k->held[i];
                const double *m = k->held_weighted[i];
                int side;
                for (side = 0; side < 2; ++side) {
                    const int32_t s = side ? r->b : r->a;
                    double *move;
                    if (s == TB__JOINT_WORLD)
                        continue;
                    move = k->accel + 6 * tb__joint_node(w, s);
                    for (d = 0; d < 6; ++d)
                        move[d] += m[6 * side + d] * share * k->newton[i];
                }
            }
            for (i = 0; i < k->moved_count; ++i) {
                const int32_t s = k->moved[i];
                const double *move = k->accel + 6 * tb__joint_node(w, s);
                if (tb__joint_is_particle(s)) {
                    for (d = 0; d < 3; ++d)
                        px[3 * tb__joint_particle_slot(s) + d] += move[d];
                    continue;
                }
                for (d = 0; d < 3; ++d)
                    x[3 * s + d] += move[d];
                tb__rotation_isotropic(q + 4 * s, move + 3, 1, 1);
            }
            if ((st = tb__joint_set_up(w, w->y, w->y, 0, TB__SET_UP_ROWS, &rows)) != TB_OK)
                return st;
            next = tb__joint_largest_error(k, rows);
            if (next < most)
                break;
            tb__joint_keep(w, k, k->kept, 1, 0);
        }
        if (!(next < most))
            break; /* no share helped: the poses as they were */
        if (h > 0) { /* what moved the ends, over h */
            for (i = 0; i < rows; ++i)
                k->x[i] = share * k->newton[i] / h;
            tb__joint_apply(w, k->held, rows, k->x, 0);
            tb__joint_add_reactions(w, k, k->held, k->lever);
        }
        if (!(next < 0.5 * most) && next < UNMET)
            break; /* rounding */
        most = next;
    }
    w->joints_unmet = !(most <= UNMET || most <= ROUNDING * farthest(w, k));
    return TB_OK;
}

/* The projection (tb__joints_project) of every joint's ends */
static tb_status project(tb_world *w, double h)
{
    struct tb__joint_work *k;
    size_t rows, i, j;
    tb_status st;
    if ((st = project_positions(w, 0)) != TB_OK)
        return st;
    /* velocities: the rows' rates taken out by an impulse */
    if ((st = tb__joint_set_up(w, w->y, w->y, 0, TB__SET_UP_MATRIX, &rows)) != TB_OK)
        return st;
    k = w->joint_work;
    tb__joint_rates(w, k, rows);
    for (i = 0; i < rows; ++i) { /* the joints, the limits reached, the motors' speeds */
        const tb__joint_row *r = &k->rows[i];
        k->x[i] = (r->kind == TB__ROW_MOTOR ? r->speed : 0) - k->x[i];
        k->use[i] = r->kind != TB__ROW_LIMIT || r->error <= r->reach; /* (friction too) */
    }
    for (j = 0; j < w->joint_count; ++j) /* the soft step's motors are met in its substeps */
        for (i = k->row_start[j]; (w->joint_flags[j] & TB__JOINT_SOFT) && i < k->row_end[j]; ++i)
            k->use[i] &= k->rows[i].kind != TB__ROW_MOTOR;
    /* (a split method's motors have their first half before its drift) */
    tb__joint_solve(k, rows, k->impulses ? h / 2 : h);
    if (k->impulses) { /* the step's impulses over its length: the force */
        tb__joint_add_reactions(w, k, k->rows, k->lever);
        for (i = 0; i < 6 * w->joint_count; ++i)
            if (!(w->joint_flags[i / 6] & TB__JOINT_SOFT)) /* (the soft step's are forces) */
                w->joint_reaction[i] /= h;
        k->impulses = 0;
    }
    tb__joint_apply(w, k->rows, rows, k->x, 0);
    k->contact_count = 0; /* (the contacts' points are this projection's) */
    return TB_OK;
}

tb_status tb__joints_project(tb_world *w, double h)
{
    tb_status st;
    if (w->joint_count == 0)
        return TB_OK;
    if (!w->joint_work && (st = tb__joint_reserve(w, 0)) != TB_OK)
        return st;
    /* every joint, those the soft step met too: it leaves their errors
       of the order of its pushes' (contacts/soft_joints.c) */
    w->joint_work->projecting = 1;
    st = project(w, h);
    w->joint_work->projecting = 0;
    return st;
}

/* ---- the split methods' drift (SHAKE, with the velocities' part at the
   end of the step: RATTLE) ------------------------------------------------------ */

/* The motors' first half before a drift of h: each motor row's rate
   brought to its speed with at most half the step's impulse (most h / 2),
   with the joints' rows' rates taken out together, so that the drift
   moves at the motor's speed (a motor acting only after the step let the
   kick's forces slow the drift through the joints: an arm lifted against
   its weight turned 6% slower than its motor's speed at 240 Hz;
   test_ode_joints.motorised_hinge_agrees_with_ode). The joints' part is
   along the rows SHAKE then acts on, so SHAKE's total impulse, and the
   step, are as they were. The second half is the velocities'
   projection's. */
static void motors_before_drift(tb_world *w, struct tb__joint_work *k, size_t rows, double h)
{
    size_t i;
    int motors = 0;
    for (i = 0; i < rows; ++i)
        motors |= k->rows[i].kind == TB__ROW_MOTOR;
    if (!motors)
        return;
    tb__joint_rates(w, k, rows);
    for (i = 0; i < rows; ++i) {
        const tb__joint_row *r = &k->rows[i];
        k->x[i] = (r->kind == TB__ROW_MOTOR ? r->speed : 0) - k->x[i];
        k->use[i] = r->kind != TB__ROW_LIMIT;
    }
    tb__joint_solve(k, rows, h / 2);
    tb__joint_apply(w, k->rows, rows, k->x, 0);
    tb__joint_add_reactions(w, k, k->rows, k->lever);
}

tb_status tb__joints_hold(tb_world *w, double h)
{
    struct tb__joint_work *k;
    size_t rows;
    tb_status st;
    if (w->joint_count == 0)
        return TB_OK;
    if ((st = tb__joint_set_up(w, w->y, w->y, 0, TB__SET_UP_MATRIX, &rows)) != TB_OK)
        return st;
    k = w->joint_work;
    if ((st = keep_rows(w, k, rows, 0)) != TB_OK)
        return st;
    memcpy(k->held_lever, k->lever, 3 * w->joint_count * sizeof *k->lever);
    k->held_count = rows;
    if (!k->impulses) { /* the step's first drift */
        memset(w->joint_reaction, 0, 6 * w->joint_count * sizeof *w->joint_reaction);
        k->impulses = 1;
    }
    motors_before_drift(w, k, rows, h);
    tb__joint_keep(w, k, k->start, 1, 1); /* the poses the drift starts from */
    return TB_OK;
}

/* End s drifted again over h from where the drift started, with the
   momenta (velocity) it has now, a body turned as the drift turned it */
static void drift_again(tb_world *w, const struct tb__joint_work *k, int32_t s, double h, tb__rotation_kind rotation)
{
    const double *start = k->start + 7 * tb__joint_node(w, s);
    int d;
    if (tb__joint_is_particle(s)) {
        const uint32_t p = tb__joint_particle_slot(s);
        double *x = w->y + w->off[TB__PARTICLE_POS] + 3 * p;
        const double *v = w->y + w->off[TB__PARTICLE_VEL] + 3 * p;
        for (d = 0; d < 3; ++d)
            x[d] = start[d] + h * v[d];
    } else {
        double *x = w->y + w->off[TB__BODY_POS] + 3 * s, *q = w->y + w->off[TB__BODY_ROT] + 4 * s;
        const double *P = w->y + w->off[TB__BODY_MOM] + 3 * s, *L = w->y + w->off[TB__BODY_ANG] + 3 * s;
        const double *inv = w->body_inv_inertia + 3 * s;
        for (d = 0; d < 3; ++d)
            x[d] = start[d] + h * (P[d] * w->body_inv_mass[s]);
        memcpy(q, start + 3, 4 * sizeof(double));
        if (rotation == TB__ROTATE_FROZEN)
            tb__rotation_frozen(q, L, inv, h);
        else if (rotation == TB__ROTATE_ACCURATE)
            tb__rotation_accurate(q, L, inv, h);
        else
            tb__rotation_split2(q, L, inv, h);
    }
}

tb_status tb__joints_shake(tb_world *w, double h, tb__rotation_kind rotation)
{
    struct tb__joint_work *k = w->joint_work;
    double most, next = 0;
    size_t rows, i;
    tb_status st;
    int step, tries, rounding;
    if (w->joint_count == 0 || !k || k->held_count == 0)
        return TB_OK;
    if ((st = tb__joint_set_up(w, w->y, w->y, 0, TB__SET_UP_SHAKE, &rows)) != TB_OK)
        return st;
    most = tb__joint_largest_error(k, rows);
    memset(k->total, 0, rows * sizeof *k->total);
    tb__joint_keep(w, k, k->half, 0, 1);
    for (step = 0; step < SHAKE_STEPS && most > MET; ++step) {
        double share = 1;
        tb__envelope e;
        /* (the trials set up the rows alone) */
        if (step > 0 && (st = tb__joint_set_up(w, w->y, w->y, 0, TB__SET_UP_SHAKE, &rows)) != TB_OK)
            return st;
        /* Newton's step: the impulse along the held rows whose drift
           takes C out to first order, through the matrix of the rows now
           times the held ones (not symmetric: with the symmetric one of
           the rows now, their turn over the step, times a light body's
           inverse inertia, stalled it) */
        e.first = k->first, e.offset = k->offset, e.a = k->a, e.l = NULL, e.use = k->use, e.drop = DROP;
        for (i = 0; i < rows; ++i) /* the joints, and the limits passed or pushing */
            k->use[i] = k->rows[i].kind == TB__ROW_EQUAL ||
                        (k->rows[i].kind == TB__ROW_LIMIT && (k->rows[i].error < 0 || k->total[i] > 0));
        (void)tb__envelope_lu(&e, k->upper, 0, rows); /* with drop, no pivot fails */
        for (i = 0; i < rows; ++i)
            k->newton[i] = k->use[i] ? -k->rows[i].error / h : 0;
        tb__envelope_lu_solve(&e, k->upper, 0, rows, k->newton);
        for (i = 0; i < rows; ++i) /* a limit pushes only: one that would pull lets go */
            if (k->rows[i].kind == TB__ROW_LIMIT && k->total[i] + k->newton[i] < 0)
                k->newton[i] = -k->total[i];
        tb__joint_keep(w, k, k->kept, 0, 1);
        /* a step that leaves the error larger goes a share of the way
           (the links of a chain whipping its light end round turn by more
           within a step than its linear model holds) */
        for (tries = 0; tries < BACKTRACKS; ++tries, share /= 2) {
            for (i = 0; i < rows; ++i)
                k->x[i] = share * k->newton[i];
            tb__joint_apply(w, k->held, rows, k->x, 0);
            for (i = 0; i < k->moved_count; ++i)
                drift_again(w, k, k->moved[i], h, rotation);
            if ((st = tb__joint_set_up(w, w->y, w->y, 0, TB__SET_UP_ROWS, &rows)) != TB_OK)
                return st;
            next = tb__joint_largest_error(k, rows);
            if (next < most)
                break;
            tb__joint_keep(w, k, k->kept, 0, 0);
        }
        if (!(next < most)) { /* no share helped: the drift as it was */
            for (i = 0; i < k->moved_count; ++i)
                drift_again(w, k, k->moved[i], h, rotation);
            break;
        }
        for (i = 0; i < rows; ++i)
            k->total[i] += share * k->newton[i];
        rounding = !(next < 0.5 * most) && next < UNMET; /* no step halves it */
        most = next;
        if (rounding)
            break;
    }
    k->held_count = 0;
    if (most > UNMET) {
        /* no impulses along the held rows meet the joints: a mode of the
           joints faster than the step holds (a light link spinning under
           a chain's tension) turned them too far. The step is taken as an
           implicit method takes it: the free drift put on the joints, its
           displacement's impulse added to the momenta (backward Euler on
           the joints: that mode is damped, not followed) */
        tb__joint_keep(w, k, k->half, 0, 0);
        for (i = 0; i < k->moved_count; ++i)
            drift_again(w, k, k->moved[i], h, rotation);
        return project_positions(w, h);
    }
    memcpy(k->x, k->total, rows * sizeof *k->x);
    tb__joint_add_reactions(w, k, k->held, k->held_lever);
    return TB_OK;
}

