/* joints.h: joints between bodies, and particles in their places (not
   public): their storage, API and the pairs whose shapes pass through
   each other (joints.c), the rows each type holds at a pose
   (joint_rows.c), their rows solved and their forces in every evaluation
   (joint_solve.c), and the bodies put on them: the projection after each
   step and SHAKE through the split methods' drifts (joint_shake.c; the
   three share joint_work.h). docs/joints.md has the model. */
#ifndef TB_JOINTS_H
#define TB_JOINTS_H

#include "world.h"

/* A joint's most rows (HINGE or SLIDER with limits and a motor) */
#define TB__JOINT_ROWS 8

/* A joint's end: a body's slot (>= 0), the world (TB__JOINT_WORLD), or a
   particle's slot p as -2 - p */
#define TB__JOINT_WORLD (-1)
static inline int32_t tb__joint_particle_end(uint32_t p)
{
    return -2 - (int32_t)p;
}
static inline int tb__joint_is_particle(int32_t end)
{
    return end <= -2;
}
static inline uint32_t tb__joint_particle_slot(int32_t end)
{
    return (uint32_t)(-2 - end);
}

/* One end of a joint at a state: a body's pose and velocities, a
   particle's (unturned, no spin), or the world's (at rest, at the
   origin, unturned) */
typedef struct tb__joint_end {
    int32_t slot;          /* as above */
    double x[3], R[9];     /* m: centre of mass; world from principal axes */
    double v[3], w[3];     /* m/s, rad/s */
} tb__joint_end;

/* One row of a joint: a function C of the two poses that the joint keeps
   at 0. Its rate is dC/dt = lin_a.v_a + ang_a.w_a + lin_b.v_b + ang_b.w_b
   (the Jacobian J), and its second derivative J times the accelerations
   plus `bias`, what the motion alone adds (dJ/dt times the velocities). */
/* What a row asks: EQUAL, C = 0 (its multiplier either way); LIMIT,
   C >= 0 (it only pushes); MOTOR, a rate of `speed` (a velocity row, its
   force within +-most); FRICTION, a contact's slip of 0 (a velocity row,
   its impulse within +-most) */
enum { TB__ROW_EQUAL, TB__ROW_LIMIT, TB__ROW_MOTOR, TB__ROW_FRICTION };

typedef struct tb__joint_row {
    int32_t a, b;          /* ends, as above */
    int kind;              /* TB__ROW_... */
    double reach;          /* LIMIT: the error at or below which it holds the velocities */
    double speed, most;    /* MOTOR: the rate asked; the force's bound (N or N m) */
    double lin_a[3], ang_a[3], lin_b[3], ang_b[3];
    double bias;           /* 1/s^2 times C's unit */
    double error;          /* C now: m, or the cosine of axes that should be square */
} tb__joint_row;

/* A contact point of an island that has joints, handed to the joints'
   projection after the contacts' solve (contacts/joint_contacts.c) as a
   LIMIT row that only pushes: n.(p_b - p_a) + offset >= 0 for the point
   p fixed in each end at the end of the solve and the normal n (a to b)
   fixed in the world, so that a body on a jointed one is carried by the
   joints in the same solve (test_joint_drives.jointed_bodies_carry_loads) */
typedef struct tb__joint_contact {
    int32_t a, b;          /* ends, as joint ends */
    int kind;              /* TB__ROW_LIMIT: a point's normal; TB__ROW_FRICTION: a patch's
                              slip along `normal` (a tangent), its impulse within +-most */
    double most;           /* N s */
    double anchor_a[3], anchor_b[3]; /* m: the point in a's principal frame, in b's */
    double normal[3];
    double offset;         /* m: the separation the points start at, plus the overlap left alone */
    double reach;          /* m: at or below this C the velocities are held (a touching point) */
} tb__joint_contact;

/* ---- joints.c ------------------------------------------------------------ */
/* The rows a joint of this type holds without limits or motors (0: no
   such type); the rows joint j holds */
int tb__joint_row_count(uint32_t type);
int tb__joint_rows_of(const tb_world *w, size_t j);
/* The end of joint j's side k (0: a, 1: b) at positions from y and
   momenta from seen */
void tb__joint_end_at(const tb_world *w, size_t j, int k, const double *y, const double *seen, tb__joint_end *end);
/* ... in two parts: which end (as above), and that end at a state */
int32_t tb__joint_end_slot(const tb_world *w, size_t j, int k);
void tb__joint_end_of(const tb_world *w, int32_t slot, const double *y, const double *seen, tb__joint_end *end);
void tb__joints_free(tb_world *w);

/* ---- joint_rows.c -------------------------------------------------------- */
/* A contact's row between its ends (tb__joint_contact) */
void tb__joint_contact_row(const tb__joint_contact *contact, const tb__joint_end *a, const tb__joint_end *b,
                           tb__joint_row *row);
/* Joint j's rows between ends a and b; returns how many */
int tb__joint_rows(const tb_world *w, size_t j, const tb__joint_end *a, const tb__joint_end *b, tb__joint_row *rows);
/* The row of joint j's free coordinate (tb_joint_position: HINGE, the
   angle a has turned about the axis relative to b; SLIDER, a's anchor
   along the axis from b's; DISTANCE, the distance; BALL, the angle
   between a's and b's copies of the axis), its value as the row's error;
   0 for FIXED, which has none */
int tb__joint_coordinate(const tb_world *w, size_t j, const tb__joint_end *a, const tb__joint_end *b,
                         tb__joint_row *row);
/* How far a row is from what it asks: |C| (EQUAL), the overshoot of a
   limit (LIMIT), 0 (MOTOR) */
double tb__joint_row_violation(const tb__joint_row *row);

/* ---- joint_solve.c --------------------------------------------------------- */
/* Add the joints' forces at positions from y and momenta from seen to
   w->body_force (making it ready if nothing else had): the forces that
   give the accelerations the joints allow, from the bodies' other forces
   of this evaluation. Each joint's reaction is kept. */
tb_status tb__joint_forces(tb_world *w, const double *y, const double *seen);
/* The joints' springs' forces at positions from y and momenta from seen
   added to w->body_force and w->particle_force (making them ready if
   nothing else had) */
void tb__joint_spring_forces(tb_world *w, const double *y, const double *seen);
/* The effective mass along a row at the ends' poses with joint j's own
   rows holding: 1 / (J M^-1 J^T) after those rows take their part */
double tb__joint_effective_mass(const tb_world *w, size_t j, const tb__joint_row *row, const tb__joint_end *a,
                                const tb__joint_end *b);
/* The joints whose reactions over the last step exceed their breaking
   force or torque are removed (the bodies they held woken) */
void tb__joints_break(tb_world *w);
/* A step begins: no drift's impulses are in the reactions yet (a step
   that failed may have left some) */
void tb__joints_begin_step(tb_world *w);
void tb__joint_work_free(tb_world *w);

/* ---- joint_shake.c --------------------------------------------------------- */
/* Put the bodies back on their joints after a step: positions (Newton
   steps, each body moved through its inverse mass and inertia), then the
   velocities' components along the rows taken out. After a split
   method's step (tb__joints_shake), each joint's reaction becomes its
   impulses over the step of length h, as a force. */
tb_status tb__joints_project(tb_world *w, double h);
/* The split methods' drift: tb__joints_hold keeps the rows and the
   jointed bodies' poses before it; tb__joints_shake, after it, finds the
   impulses along those rows that bring the drifted poses onto the joints
   (SHAKE), drifting the bodies again from the kept poses with rotation.
   The velocities' part (RATTLE's) is the projection's at the end of the
   step. Motors act half before the drift of h, half in the projection. */
tb_status tb__joints_hold(tb_world *w, double h);
tb_status tb__joints_shake(tb_world *w, double h, tb__rotation_kind rotation);

/* ---- joints.c: which bodies' shapes pass through each other --------------- */
/* The pairs of bodies a joint holds whose shapes pass through each other
   (tb_joint_def.collide 0), found once a step before the contacts
   (tb__joints_apart_prepare); whether bodies of id indices a and b are
   such a pair */
tb_status tb__joints_apart_prepare(tb_world *w);
int tb__joints_apart(const tb_world *w, uint32_t a, uint32_t b);

#endif
