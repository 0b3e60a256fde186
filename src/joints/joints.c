/* joints.c: joints between bodies, or a body and the world: what each
   holds (kept in the bodies' principal frames, so it moves with them),
   adding, removing, and reading them. */
#include "joints/joint_work.h"
#include "bodies/bodies.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define JOINT_ARRAYS 9
#define PI 3.14159265358979323846

static void body_removed(tb_world *w, uint32_t body_index1);
static void wake_ends(tb_world *w, uint32_t j);
static tb_status check_drive(tb_world *w, const tb_joint_def *def, int particle);
static void particle_removed(tb_world *w, uint32_t slot, uint32_t last);

tb_joint_def tb_default_joint_def(void)
{
    tb_joint_def def;
    memset(&def, 0, sizeof def);
    def.type = TB_JOINT_BALL;
    def.axis[2] = 1;
    def.length = -1;
    return def;
}

int tb__joint_row_count(uint32_t type)
{
    static const int rows[] = { 3, 5, 5, 6, 1 }; /* ball, hinge, slider, fixed, distance */
    return type < sizeof rows / sizeof rows[0] ? rows[type] : 0;
}

int tb__joint_rows_of(const tb_world *w, size_t j)
{
    const uint32_t type = w->joint_type[j], flags = w->joint_flags[j];
    int n = tb__joint_row_count(type);
    if (type == TB_JOINT_DISTANCE && (flags & (TB__JOINT_LIMIT | TB__JOINT_SPRING)))
        n = 0;
    if (flags & TB__JOINT_LIMIT)
        n += type == TB_JOINT_BALL ? 1 : 2;
    if (flags & TB__JOINT_MOTOR)
        n += 1;
    if (flags & TB__JOINT_TWIST)
        n += 2;
    return n;
}

static void arrays_of(tb_world *w, void **arrays[JOINT_ARRAYS], size_t sizes[JOINT_ARRAYS])
{
    arrays[0] = (void **)&w->joint_type;     sizes[0] = sizeof(uint32_t);
    arrays[1] = (void **)&w->joint_body;     sizes[1] = 2 * sizeof(uint32_t);
    arrays[2] = (void **)&w->joint_anchor;   sizes[2] = 6 * sizeof(double);
    arrays[3] = (void **)&w->joint_frame;    sizes[3] = 18 * sizeof(double);
    arrays[4] = (void **)&w->joint_length;   sizes[4] = sizeof(double);
    arrays[5] = (void **)&w->joint_reaction; sizes[5] = 6 * sizeof(double);
    arrays[6] = (void **)&w->joint_flags;    sizes[6] = sizeof(uint32_t);
    arrays[7] = (void **)&w->joint_drive;    sizes[7] = TB__DRIVES * sizeof(double);
    arrays[8] = (void **)&w->joint_warm;     sizes[8] = TB__JOINT_ROWS * sizeof(double);
}

/* The pose of body slot s (x, R), or the world's for s = -1 */
static void pose_of(const tb_world *w, int32_t s, const double *y, double x[3], double R[9])
{
    static const double identity[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 };
    double q[4];
    if (s < 0) {
        memset(x, 0, 3 * sizeof *x);
        memcpy(R, identity, sizeof identity);
        return;
    }
    memcpy(x, y + w->off[TB__BODY_POS] + 3 * s, 3 * sizeof *x);
    memcpy(q, y + w->off[TB__BODY_ROT] + 4 * s, sizeof q);
    tb__normalise(q); /* a Runge-Kutta stage's q is not unit */
    tb__matrix_of(q, R);
}

static int holds_particle(const tb_world *w, size_t j, int k)
{
    return (w->joint_flags[j] & (k ? TB__JOINT_PARTICLE_B : TB__JOINT_PARTICLE_A)) != 0;
}

/* The end of joint j on side k (0: a, 1: b), as joints.h encodes ends: a
   body's slot, -1 the world, -2 - slot a particle's. A joint's bodies
   and particles are live: a removed one takes its joints. */
static int32_t slot_of(const tb_world *w, size_t j, int k)
{
    const uint32_t index1 = w->joint_body[2 * j + k];
    if (!index1)
        return TB__JOINT_WORLD;
    return holds_particle(w, j, k) ? tb__joint_particle_end(w->particle_ids.slot[index1 - 1])
                                   : (int32_t)w->body_ids.slot[index1 - 1];
}

static int32_t body_slot_of(const tb_world *w, size_t j, int k)
{
    const int32_t s = slot_of(w, j, k);
    return s >= 0 ? s : -1;
}

int32_t tb__joint_end_slot(const tb_world *w, size_t j, int k)
{
    return slot_of(w, j, k);
}

void tb__joint_end_at(const tb_world *w, size_t j, int k, const double *y, const double *seen, tb__joint_end *end)
{
    tb__joint_end_of(w, slot_of(w, j, k), y, seen, end);
}

void tb__joint_end_of(const tb_world *w, int32_t slot, const double *y, const double *seen, tb__joint_end *end)
{
    int d;
    end->slot = slot;
    pose_of(w, end->slot >= 0 ? end->slot : -1, y, end->x, end->R);
    memset(end->v, 0, sizeof end->v);
    memset(end->w, 0, sizeof end->w);
    if (tb__joint_is_particle(end->slot)) {
        const uint32_t p = tb__joint_particle_slot(end->slot);
        memcpy(end->x, y + w->off[TB__PARTICLE_POS] + 3 * p, sizeof end->x);
        memcpy(end->v, seen + w->off[TB__PARTICLE_VEL] + 3 * p, sizeof end->v);
    } else if (end->slot >= 0) {
        const double *P = seen + w->off[TB__BODY_MOM] + 3 * end->slot, *L = seen + w->off[TB__BODY_ANG] + 3 * end->slot;
        const double *inv = w->body_inv_inertia + 3 * end->slot;
        double Lb[3];
        for (d = 0; d < 3; ++d)
            end->v[d] = P[d] * w->body_inv_mass[end->slot];
        tb__mul_transposed(end->R, L, Lb);
        for (d = 0; d < 3; ++d)
            Lb[d] *= inv[d];
        tb__mul(end->R, Lb, end->w);
    }
}

/* Two unit vectors square to the unit n and to each other, (n, t1, t2)
   right-handed */
static void square_to(const double n[3], double t1[3], double t2[3])
{
    const double a[3] = { fabs(n[0]) < 0.6 ? 1 : 0, fabs(n[0]) < 0.6 ? 0 : 1, 0 };
    double l;
    tb__cross(n, a, t1);
    l = tb__norm3(t1);
    t1[0] /= l, t1[1] /= l, t1[2] /= l;
    tb__cross(n, t1, t2);
}

/* The world point p, and the world frame's rows, in the frame of end
   (x, R): R^T (p - x) and R^T f */
static void into_frame(const double x[3], const double R[9], const double p[3], const double frame[9],
                       double local[3], double local_frame[9])
{
    const double d[3] = { p[0] - x[0], p[1] - x[1], p[2] - x[2] };
    int k;
    tb__mul_transposed(R, d, local);
    for (k = 0; k < 3; ++k)
        tb__mul_transposed(R, frame + 3 * k, local_frame + 3 * k);
}

/* One side of a joint: a body, a particle, or (side b only) neither: the
   world. *slot as joints.h encodes ends. */
static tb_status check_side(tb_world *w, tb_body_id body, tb_particle_id particle, int k, int32_t *slot)
{
    const char *side = k ? "b" : "a";
    uint32_t s;
    if (!TB_ID_IS_NULL(body) && !TB_ID_IS_NULL(particle))
        return tb__fail(w, TB_ERR_ARGUMENT, "joint side %s: a body or a particle, not both", side);
    if (!TB_ID_IS_NULL(particle)) {
        if (!tb__ids_lookup(&w->particle_ids, particle.index1, particle.generation, &s))
            return tb__fail(w, TB_ERR_STALE_ID, "joint particle %s: particle id %u.%u is removed or from another "
                            "world", side, particle.index1, particle.generation);
        *slot = tb__joint_particle_end(s);
        return TB_OK;
    }
    if (TB_ID_IS_NULL(body)) {
        if (!k)
            return tb__fail(w, TB_ERR_STALE_ID, "joint body a: body id %u.%u is null, removed or from another world",
                            body.index1, body.generation);
        *slot = TB__JOINT_WORLD;
        return TB_OK;
    }
    if (tb__body_find(w, body, &s) != TB_OK)
        return tb__fail(w, TB_ERR_STALE_ID, "joint body %s: %s", side, tb_world_message(w));
    *slot = (int32_t)s;
    return TB_OK;
}

static tb_status check_def(tb_world *w, const tb_joint_def *def, int32_t *sa, int32_t *sb)
{
    tb_status st;
    if (!def)
        return tb__fail(w, TB_ERR_ARGUMENT, "joint definition must not be NULL");
    if (tb__joint_row_count((uint32_t)def->type) == 0)
        return tb__fail(w, TB_ERR_ARGUMENT, "unknown joint type %d", (int)def->type);
    if ((st = check_side(w, def->a, def->particle_a, 0, sa)) != TB_OK ||
        (st = check_side(w, def->b, def->particle_b, 1, sb)) != TB_OK)
        return st;
    if (*sa == *sb)
        return tb__fail(w, TB_ERR_ARGUMENT, "a joint cannot join a %s to itself", *sa >= 0 ? "body" : "particle");
    if ((tb__joint_is_particle(*sa) || tb__joint_is_particle(*sb)) && def->type != TB_JOINT_BALL &&
        def->type != TB_JOINT_DISTANCE)
        return tb__fail(w, TB_ERR_ARGUMENT, "a particle has no orientation: it takes part in ball and distance "
                        "joints only");
    if ((st = tb__check_values(w, def->anchor, 3, "joint anchor")) != TB_OK)
        return st;
    if (def->type == TB_JOINT_DISTANCE &&
        ((st = tb__check_values(w, def->anchor_b, 3, "joint anchor_b")) != TB_OK ||
         (st = tb__check_values(w, &def->length, 1, "joint length")) != TB_OK))
        return st;
    if ((def->type == TB_JOINT_HINGE || def->type == TB_JOINT_SLIDER || def->type == TB_JOINT_BALL) &&
        (st = tb__check_values(w, def->axis, 3, "joint axis")) != TB_OK)
        return st;
    return check_drive(w, def, tb__joint_is_particle(*sa) || tb__joint_is_particle(*sb));
}

/* A joint's limits, motor, spring and breaking figures as the types and
   their units allow (tb_joint_def) */
static tb_status check_limit(tb_world *w, uint32_t type, int particle, int enable, double lower, double upper)
{
    const double both[2] = { lower, upper };
    tb_status st;
    if (!enable)
        return TB_OK;
    if (type == TB_JOINT_FIXED || (type == TB_JOINT_BALL && particle))
        return tb__fail(w, TB_ERR_ARGUMENT, "a %s joint has no limit", type == TB_JOINT_FIXED ? "fixed" : "particle's "
                        "ball");
    if ((st = tb__check_values(w, type == TB_JOINT_BALL ? &upper : both, type == TB_JOINT_BALL ? 1 : 2,
                               "joint limit")) != TB_OK)
        return st;
    if (type == TB_JOINT_BALL)
        return upper > 0 && upper < PI ? TB_OK
                                       : tb__fail(w, TB_ERR_ARGUMENT, "ball joint cone %g rad: it must be above 0 and "
                                                  "below pi", upper);
    if (lower > upper)
        return tb__fail(w, TB_ERR_ARGUMENT, "joint limit: lower %g above upper %g", lower, upper);
    if (type == TB_JOINT_HINGE && (lower < -PI || upper > PI))
        return tb__fail(w, TB_ERR_ARGUMENT, "hinge limits %g to %g rad: they must be within -pi to pi", lower, upper);
    if (type == TB_JOINT_DISTANCE && (lower < 0 || upper > TB_LIMIT))
        return tb__fail(w, TB_ERR_ARGUMENT, "distance joint limits %g to %g m: they must be from 0 to %g m", lower,
                        upper, TB_LIMIT);
    return TB_OK;
}

static tb_status check_twist(tb_world *w, uint32_t type, int particle, int enable, double lower, double upper)
{
    const double both[2] = { lower, upper };
    tb_status st;
    if (!enable)
        return TB_OK;
    if (type != TB_JOINT_BALL || particle)
        return tb__fail(w, TB_ERR_ARGUMENT, "only a ball joint between bodies has a twist limit");
    if ((st = tb__check_values(w, both, 2, "joint twist limit")) != TB_OK)
        return st;
    if (lower > upper)
        return tb__fail(w, TB_ERR_ARGUMENT, "joint twist limit: lower %g above upper %g", lower, upper);
    if (lower < -PI || upper > PI)
        return tb__fail(w, TB_ERR_ARGUMENT, "twist limits %g to %g rad: they must be within -pi to pi", lower, upper);
    return TB_OK;
}

static tb_status check_motor(tb_world *w, uint32_t type, int enable, double speed, double most)
{
    tb_status st;
    if (!enable)
        return TB_OK;
    if (type != TB_JOINT_HINGE && type != TB_JOINT_SLIDER)
        return tb__fail(w, TB_ERR_ARGUMENT, "only hinge and slider joints have motors");
    if ((st = tb__check_values(w, &speed, 1, "joint motor speed")) != TB_OK ||
        (st = tb__check_values(w, &most, 1, "joint max_motor_force")) != TB_OK)
        return st;
    return most >= 0 ? TB_OK : tb__fail(w, TB_ERR_ARGUMENT, "joint max_motor_force %g: it must be 0 or more", most);
}

static tb_status check_spring(tb_world *w, uint32_t type, int enable, double hz, double ratio, double target)
{
    const double v[3] = { hz, ratio, target };
    tb_status st;
    if (!enable)
        return TB_OK;
    if (type != TB_JOINT_HINGE && type != TB_JOINT_SLIDER && type != TB_JOINT_DISTANCE)
        return tb__fail(w, TB_ERR_ARGUMENT, "only hinge, slider and distance joints have springs");
    if ((st = tb__check_values(w, v, 3, "joint spring")) != TB_OK)
        return st;
    if (!(hz > 0) || !(ratio >= 0))
        return tb__fail(w, TB_ERR_ARGUMENT, "joint spring: spring_hz %g must be above 0 and spring_damping_ratio %g "
                        "0 or more", hz, ratio);
    if (type == TB_JOINT_HINGE && fabs(target) > PI)
        return tb__fail(w, TB_ERR_ARGUMENT, "hinge spring target %g rad: it must be within -pi to pi", target);
    return TB_OK;
}

static tb_status check_drive(tb_world *w, const tb_joint_def *def, int particle)
{
    const double breaking[2] = { def->break_force, def->break_torque };
    tb_status st;
    if ((st = check_limit(w, (uint32_t)def->type, particle, def->enable_limit, def->lower, def->upper)) != TB_OK ||
        (st = check_twist(w, (uint32_t)def->type, particle, def->enable_twist, def->twist_lower, def->twist_upper)) !=
            TB_OK ||
        (st = check_motor(w, (uint32_t)def->type, def->enable_motor, def->motor_speed, def->max_motor_force)) !=
            TB_OK ||
        (st = check_spring(w, (uint32_t)def->type, def->enable_spring, def->spring_hz, def->spring_damping_ratio,
                           def->spring_target)) != TB_OK ||
        (st = tb__check_values(w, breaking, 2, "joint break_force and break_torque")) != TB_OK)
        return st;
    if (breaking[0] < 0 || breaking[1] < 0)
        return tb__fail(w, TB_ERR_ARGUMENT, "joint break_force %g and break_torque %g must be 0 or more",
                        breaking[0], breaking[1]);
    return TB_OK;
}

/* Joint j's spring's stiffness and damping from its frequency and ratio
   and the effective mass along its coordinate now; 0 when nothing can
   move along it */
static void spring_from_hz(tb_world *w, uint32_t j)
{
    double *drive = w->joint_drive + TB__DRIVES * j;
    const double omega = 2 * PI * drive[TB__DRIVE_HZ];
    tb__joint_end a, b;
    tb__joint_row row;
    double mass = 0;
    tb__joint_end_at(w, j, 0, w->y, w->y, &a);
    tb__joint_end_at(w, j, 1, w->y, w->y, &b);
    if (tb__joint_coordinate(w, j, &a, &b, &row))
        mass = tb__joint_effective_mass(w, j, &row, &a, &b);
    drive[TB__DRIVE_STIFFNESS] = mass * omega * omega;
    drive[TB__DRIVE_DAMPING] = 2 * mass * drive[TB__DRIVE_RATIO] * omega;
}

/* Where side k's end of a new joint is: a particle's position, else the
   anchor it names */
static const double *end_point(const tb_world *w, int32_t slot, const double *anchor)
{
    return tb__joint_is_particle(slot) ? w->y + w->off[TB__PARTICLE_POS] + 3 * tb__joint_particle_slot(slot) : anchor;
}

/* Joint j's drive from def: limits, motor, spring (its stiffness from the
   effective mass now), breaking */
static void set_drive(tb_world *w, uint32_t j, const tb_joint_def *def)
{
    double *drive = w->joint_drive + TB__DRIVES * j;
    memset(drive, 0, TB__DRIVES * sizeof *drive);
    w->joint_flags[j] |= (def->enable_limit ? TB__JOINT_LIMIT : 0) | (def->enable_motor ? TB__JOINT_MOTOR : 0) |
                         (def->enable_spring ? TB__JOINT_SPRING : 0) | (def->enable_twist ? TB__JOINT_TWIST : 0);
    if (def->enable_limit)
        drive[TB__DRIVE_LOWER] = def->lower, drive[TB__DRIVE_UPPER] = def->upper;
    if (def->enable_twist)
        drive[TB__DRIVE_TWIST_LOWER] = def->twist_lower, drive[TB__DRIVE_TWIST_UPPER] = def->twist_upper;
    if (def->enable_motor)
        drive[TB__DRIVE_SPEED] = def->motor_speed, drive[TB__DRIVE_MOST] = def->max_motor_force;
    if (def->enable_spring) {
        drive[TB__DRIVE_HZ] = def->spring_hz, drive[TB__DRIVE_RATIO] = def->spring_damping_ratio;
        drive[TB__DRIVE_TARGET] = def->type == TB_JOINT_DISTANCE ? w->joint_length[j] : def->spring_target;
        spring_from_hz(w, j);
    }
    drive[TB__DRIVE_BREAK_FORCE] = def->break_force, drive[TB__DRIVE_BREAK_TORQUE] = def->break_torque;
}

tb_status tb_world_add_joint(tb_world *w, const tb_joint_def *def, tb_joint_id *id)
{
    double frame[9], xa[3], Ra[9], xb[3], Rb[9], n, length = 0;
    const double *anchor_a, *anchor_b;
    tb_joint_id made;
    tb_status st;
    uint32_t j;
    int32_t sa, sb;
    int axial;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "add a joint")) != TB_OK || (st = check_def(w, def, &sa, &sb)) != TB_OK)
        return st;
    /* a particle is its own anchor; a ball joint holds it at `anchor` on
       the other side */
    anchor_a = end_point(w, sa, def->anchor);
    anchor_b = end_point(w, sb, def->type == TB_JOINT_DISTANCE ? def->anchor_b : def->anchor);
    /* the joint's axes: the axis (z for the types that have none), then two
       square to it */
    axial = def->type == TB_JOINT_HINGE || def->type == TB_JOINT_SLIDER || def->type == TB_JOINT_BALL;
    n = axial ? tb__norm3(def->axis) : 1;
    if (!(n > 0) || !isfinite(n))
        return tb__fail(w, TB_ERR_ARGUMENT, "joint axis (%g, %g, %g) has no direction", def->axis[0], def->axis[1],
                        def->axis[2]);
    if (axial)
        frame[0] = def->axis[0] / n, frame[1] = def->axis[1] / n, frame[2] = def->axis[2] / n;
    else
        frame[0] = 0, frame[1] = 0, frame[2] = 1;
    square_to(frame, frame + 3, frame + 6);
    if (def->type == TB_JOINT_DISTANCE) {
        const double d[3] = { anchor_a[0] - anchor_b[0], anchor_a[1] - anchor_b[1], anchor_a[2] - anchor_b[2] };
        length = def->length >= 0 ? def->length : tb__norm3(d);
        if (!tb__in_scale(length))
            return tb__fail(w, TB_ERR_ARGUMENT, "distance joint length %g m: it must be from %g to %g m (its ends "
                            "apart)", length, 1 / TB_LIMIT, TB_LIMIT);
    }
    if (w->joint_count == w->joint_cap) {
        const size_t cap = w->joint_cap ? 2 * w->joint_cap : 8;
        void **arrays[JOINT_ARRAYS];
        size_t sizes[JOINT_ARRAYS];
        arrays_of(w, arrays, sizes);
        if ((st = tb__ids_reserve(w, &w->joint_ids, cap)) != TB_OK ||
            (st = tb__grow(w, arrays, sizes, JOINT_ARRAYS, w->joint_count, w->joint_cap, cap)) != TB_OK)
            return st;
        w->joint_cap = cap;
    }
    j = (uint32_t)w->joint_count++;
    w->body_removed[TB__HEARS_JOINTS] = body_removed;
    w->particle_removed[TB__HEARS_PARTICLE_JOINTS] = particle_removed;
    w->joint_type[j] = (uint32_t)def->type;
    w->joint_body[2 * j] = tb__joint_is_particle(sa) ? def->particle_a.index1 : def->a.index1;
    w->joint_body[2 * j + 1] = tb__joint_is_particle(sb) ? def->particle_b.index1 : sb >= 0 ? def->b.index1 : 0;
    w->joint_flags[j] = (def->collide ? TB__JOINT_COLLIDE : 0) |
                        (tb__joint_is_particle(sa) ? TB__JOINT_PARTICLE_A : 0) |
                        (tb__joint_is_particle(sb) ? TB__JOINT_PARTICLE_B : 0);
    /* a particle's end is the particle: its anchor is 0 in an unturned frame */
    pose_of(w, sa >= 0 ? sa : -1, w->y, xa, Ra);
    pose_of(w, sb >= 0 ? sb : -1, w->y, xb, Rb);
    if (tb__joint_is_particle(sa))
        memcpy(xa, anchor_a, sizeof xa);
    if (tb__joint_is_particle(sb))
        memcpy(xb, anchor_b, sizeof xb);
    into_frame(xa, Ra, anchor_a, frame, w->joint_anchor + 6 * j, w->joint_frame + 18 * j);
    into_frame(xb, Rb, anchor_b, frame, w->joint_anchor + 6 * j + 3, w->joint_frame + 18 * j + 9);
    w->joint_length[j] = length;
    memset(w->joint_reaction + 6 * j, 0, 6 * sizeof(double));
    memset(w->joint_warm + TB__JOINT_ROWS * j, 0, TB__JOINT_ROWS * sizeof(double));
    set_drive(w, j, def);
    if (sa >= 0)
        tb__wake_body(w, (uint32_t)sa);
    if (sb >= 0)
        tb__wake_body(w, (uint32_t)sb);
    tb__ids_acquire(&w->joint_ids, w->id_tag, j, &made.index1, &made.generation);
    if (id)
        *id = made;
    return TB_OK;
}

static void remove_slot(tb_world *w, uint32_t j)
{
    const uint32_t last = (uint32_t)w->joint_count - 1;
    uint32_t index1, generation;
    tb__ids_at(&w->joint_ids, j, &index1, &generation);
    if (j != last) {
        void **arrays[JOINT_ARRAYS];
        size_t sizes[JOINT_ARRAYS], k;
        arrays_of(w, arrays, sizes);
        for (k = 0; k < JOINT_ARRAYS; ++k) {
            unsigned char *base = *arrays[k];
            memcpy(base + j * sizes[k], base + last * sizes[k], sizes[k]);
        }
        tb__ids_move(&w->joint_ids, last, j);
    }
    tb__ids_release(&w->joint_ids, index1);
    w->joint_count--;
}

static tb_status find(const tb_world *w, tb_joint_id id, uint32_t *j)
{
    if (!tb__ids_lookup(&w->joint_ids, id.index1, id.generation, j))
        return tb__fail((tb_world *)w, TB_ERR_STALE_ID, "joint id %u.%u is null, removed or from another world",
                        id.index1, id.generation);
    return TB_OK;
}

tb_status tb_world_remove_joint(tb_world *w, tb_joint_id id)
{
    tb_status st;
    uint32_t j;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "remove a joint")) != TB_OK || (st = find(w, id, &j)) != TB_OK)
        return st;
    wake_ends(w, j); /* what it held may fall */
    remove_slot(w, j);
    return TB_OK;
}

size_t tb_world_joint_count(const tb_world *w)
{
    TB__NEED_WORLD(w, 0);
    return w->joint_count;
}

tb_joint_id tb_world_joint_at(const tb_world *w, size_t slot)
{
    tb_joint_id id = { 0, 0 };
    if (w && slot < w->joint_count)
        tb__ids_at(&w->joint_ids, (uint32_t)slot, &id.index1, &id.generation);
    return id;
}

tb_status tb_joint_reaction(const tb_world *w, tb_joint_id id, double force[3], double torque[3])
{
    tb_status st;
    uint32_t j;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if (!force || !torque)
        return tb__null((tb_world *)w, "tb_joint_reaction", "force or torque");
    if ((st = find(w, id, &j)) != TB_OK)
        return st;
    memcpy(force, w->joint_reaction + 6 * j, 3 * sizeof(double));
    memcpy(torque, w->joint_reaction + 6 * j + 3, 3 * sizeof(double));
    return TB_OK;
}

tb_status tb_joint_error(const tb_world *w, tb_joint_id id, double *error)
{
    tb__joint_end a, b;
    tb__joint_row rows[TB__JOINT_ROWS];
    tb_status st;
    uint32_t j;
    int n, k;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if (!error)
        return tb__null((tb_world *)w, "tb_joint_error", "error");
    if ((st = find(w, id, &j)) != TB_OK)
        return st;
    tb__joint_end_at(w, j, 0, w->y, w->y, &a);
    tb__joint_end_at(w, j, 1, w->y, w->y, &b);
    n = tb__joint_rows(w, j, &a, &b, rows);
    *error = 0;
    for (k = 0; k < n; ++k)
        *error = fmax(*error, tb__joint_row_violation(&rows[k]));
    return TB_OK;
}

tb_status tb_joint_position(const tb_world *w, tb_joint_id id, double *position, double *rate)
{
    tb__joint_end a, b;
    tb__joint_row row;
    tb_status st;
    uint32_t j;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if (!position)
        return tb__null((tb_world *)w, "tb_joint_position", "position");
    if ((st = find(w, id, &j)) != TB_OK)
        return st;
    tb__joint_end_at(w, j, 0, w->y, w->y, &a);
    tb__joint_end_at(w, j, 1, w->y, w->y, &b);
    if (!tb__joint_coordinate(w, j, &a, &b, &row))
        return tb__fail((tb_world *)w, TB_ERR_ARGUMENT, "a fixed joint has no free coordinate");
    *position = row.error;
    if (rate) {
        *rate = tb__dot3(row.lin_a, a.v) + tb__dot3(row.ang_a, a.w) + tb__dot3(row.lin_b, b.v) +
                tb__dot3(row.ang_b, b.w);
        if (w->joint_type[j] == TB_JOINT_BALL) /* d(acos c)/dt */
            *rate = row.error > 0 ? -*rate / sin(row.error) : 0;
    }
    return TB_OK;
}

/* The bodies joint j holds, woken: what drives them changed (and its rows
   with it: the soft step's warm start is dropped) */
static void wake_ends(tb_world *w, uint32_t j)
{
    int k;
    memset(w->joint_warm + TB__JOINT_ROWS * j, 0, TB__JOINT_ROWS * sizeof(double));
    for (k = 0; k < 2; ++k)
        if (body_slot_of(w, j, k) >= 0)
            tb__wake_body(w, (uint32_t)body_slot_of(w, j, k));
}

/* A setter's joint: found, not during a step */
static tb_status settable(tb_world *w, tb_joint_id id, const char *what, uint32_t *j)
{
    tb_status st;
    if ((st = tb__check_busy(w, what)) != TB_OK || (st = find(w, id, j)) != TB_OK)
        return st;
    return TB_OK;
}

static int holds_a_particle(const tb_world *w, uint32_t j)
{
    return (w->joint_flags[j] & (TB__JOINT_PARTICLE_A | TB__JOINT_PARTICLE_B)) != 0;
}

/* Joint j's drive `flag` on or off with its two values (0 when off), its
   bodies woken to feel it */
static void set_drive_pair(tb_world *w, uint32_t j, uint32_t flag, int enable, int first, double a, int second,
                           double b)
{
    w->joint_flags[j] = (w->joint_flags[j] & ~flag) | (enable ? flag : 0);
    w->joint_drive[TB__DRIVES * j + (size_t)first] = enable ? a : 0;
    w->joint_drive[TB__DRIVES * j + (size_t)second] = enable ? b : 0;
    wake_ends(w, j);
}

tb_status tb_joint_set_limit(tb_world *w, tb_joint_id id, int enable, double lower, double upper)
{
    tb_status st;
    uint32_t j;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = settable(w, id, "set a joint's limit", &j)) != TB_OK ||
        (st = check_limit(w, w->joint_type[j], holds_a_particle(w, j), enable, lower, upper)) != TB_OK)
        return st;
    set_drive_pair(w, j, TB__JOINT_LIMIT, enable, TB__DRIVE_LOWER, lower, TB__DRIVE_UPPER, upper);
    return TB_OK;
}

tb_status tb_joint_set_twist_limit(tb_world *w, tb_joint_id id, int enable, double lower, double upper)
{
    tb_status st;
    uint32_t j;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = settable(w, id, "set a joint's twist limit", &j)) != TB_OK ||
        (st = check_twist(w, w->joint_type[j], holds_a_particle(w, j), enable, lower, upper)) != TB_OK)
        return st;
    set_drive_pair(w, j, TB__JOINT_TWIST, enable, TB__DRIVE_TWIST_LOWER, lower, TB__DRIVE_TWIST_UPPER, upper);
    return TB_OK;
}

tb_status tb_joint_set_motor(tb_world *w, tb_joint_id id, int enable, double speed, double max_force)
{
    tb_status st;
    uint32_t j;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = settable(w, id, "set a joint's motor", &j)) != TB_OK ||
        (st = check_motor(w, w->joint_type[j], enable, speed, max_force)) != TB_OK)
        return st;
    set_drive_pair(w, j, TB__JOINT_MOTOR, enable, TB__DRIVE_SPEED, speed, TB__DRIVE_MOST, max_force);
    return TB_OK;
}

tb_status tb_joint_set_spring(tb_world *w, tb_joint_id id, int enable, double hz, double damping_ratio,
                              double target)
{
    double *drive;
    tb_status st;
    uint32_t j;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = settable(w, id, "set a joint's spring", &j)) != TB_OK ||
        (st = check_spring(w, w->joint_type[j], enable, hz, damping_ratio, target)) != TB_OK)
        return st;
    drive = w->joint_drive + TB__DRIVES * j;
    w->joint_flags[j] = (w->joint_flags[j] & ~(uint32_t)TB__JOINT_SPRING) | (enable ? TB__JOINT_SPRING : 0);
    drive[TB__DRIVE_HZ] = enable ? hz : 0;
    drive[TB__DRIVE_RATIO] = enable ? damping_ratio : 0;
    drive[TB__DRIVE_TARGET] = !enable ? 0 : w->joint_type[j] == TB_JOINT_DISTANCE ? w->joint_length[j] : target;
    drive[TB__DRIVE_STIFFNESS] = drive[TB__DRIVE_DAMPING] = 0;
    if (enable)
        spring_from_hz(w, j);
    wake_ends(w, j);
    return TB_OK;
}

void tb__joints_break(tb_world *w)
{
    size_t j = w->joint_count;
    while (j-- > 0) {
        const double *drive = w->joint_drive + TB__DRIVES * j, *reaction = w->joint_reaction + 6 * j;
        const double force = drive[TB__DRIVE_BREAK_FORCE], torque = drive[TB__DRIVE_BREAK_TORQUE];
        if ((force > 0 && tb__norm3(reaction) > force) || (torque > 0 && tb__norm3(reaction + 3) > torque)) {
            wake_ends(w, (uint32_t)j);
            remove_slot(w, (uint32_t)j);
        }
    }
}

/* A removed body or particle takes its joints with it */
static void remove_holding(tb_world *w, uint32_t index1, int particle)
{
    size_t j = w->joint_count;
    int k;
    while (j-- > 0)
        for (k = 0; k < 2; ++k)
            if (w->joint_body[2 * j + k] == index1 && holds_particle(w, j, k) == particle) {
                remove_slot(w, (uint32_t)j);
                break;
            }
}

static void body_removed(tb_world *w, uint32_t body_index1)
{
    remove_holding(w, body_index1, 0);
}

/* (called before the particle's id is released: its slot names it) */
static void particle_removed(tb_world *w, uint32_t slot, uint32_t last)
{
    (void)last;
    remove_holding(w, w->particle_ids.owner[slot] + 1, 1);
}

void tb__joints_free(tb_world *w)
{
    void **arrays[JOINT_ARRAYS];
    size_t sizes[JOINT_ARRAYS];
    arrays_of(w, arrays, sizes);
    tb__free_arrays(w, arrays, sizes, JOINT_ARRAYS, w->joint_cap);
    tb__ids_free(w, &w->joint_ids);
    tb__joint_work_free(w);
    w->joint_count = w->joint_cap = 0;
}

/* ---- which bodies' shapes pass through each other ------------------------------ */

static uint64_t pair_key(uint32_t a, uint32_t b)
{
    return a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
}

static int by_key(const void *x, const void *y)
{
    const uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return a < b ? -1 : a > b;
}

tb_status tb__joints_apart_prepare(tb_world *w)
{
    struct tb__joint_work *k;
    tb_status st;
    size_t j;
    if (w->joint_count == 0)
        return TB_OK;
    if ((st = tb__joint_reserve(w, 0)) != TB_OK)
        return st;
    k = w->joint_work;
    if ((st = tb__reserve(w, (void **)&k->apart, &k->apart_cap, w->joint_count, sizeof *k->apart)) != TB_OK)
        return st;
    k->apart_count = 0;
    for (j = 0; j < w->joint_count; ++j)
        if (!(w->joint_flags[j] & (TB__JOINT_COLLIDE | TB__JOINT_PARTICLE_A | TB__JOINT_PARTICLE_B)) &&
            w->joint_body[2 * j + 1])
            k->apart[k->apart_count++] = pair_key(w->joint_body[2 * j], w->joint_body[2 * j + 1]);
    qsort(k->apart, k->apart_count, sizeof *k->apart, by_key);
    return TB_OK;
}

int tb__joints_apart(const tb_world *w, uint32_t a, uint32_t b)
{
    const struct tb__joint_work *k = w->joint_work;
    const uint64_t key = pair_key(a, b);
    size_t lo = 0, hi;
    if (w->joint_count == 0 || !k || k->apart_count == 0)
        return 0;
    hi = k->apart_count;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        if (k->apart[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < k->apart_count && k->apart[lo] == key;
}
