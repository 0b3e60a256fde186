/* joint_rows.c: the rows each type of joint holds at a pose, from three
   kinds of row (joints.h, tb__joint_row):
   - a point row: t.(p_a - p_b) = 0 for the anchors p_a, p_b and a
     direction t fixed in the world (a ball joint's three axes) or turning
     with a (a slider's two directions across its axis);
   - a distance row: |p_a - p_b| = length;
   - an angle row: u.v = 0 for an axis u of a and an axis v of b, square
     at creation (a hinge's axis against b's two across it; three of them
     fix the relative orientation).
   Each row's Jacobian and its bias (what the motion alone adds to the
   second derivative) are the exact derivatives of its C, so that the
   accelerations the solve gives keep C'' = 0
   (test_joints.joints_hold_every_type). A joint's limits and motor add
   rows along its free coordinate (a hinge's turn, a slider's travel, a
   distance, a ball joint's angle between axes): LIMIT rows C >= 0 and a
   MOTOR row on its rate (test_joint_drives). */
#include "joints/joints.h"
#include "bodies/bodies.h"

#include <math.h>
#include <string.h>

/* What every row of a joint reads: its ends, their anchors and axes in
   the world */
typedef struct ends {
    const tb__joint_end *a, *b;
    double ra[3], rb[3];       /* anchors from the centres */
    double d[3], dd[3];        /* p_a - p_b and its rate */
    double centripetal[3];     /* w_a x (w_a x r_a) - w_b x (w_b x r_b) */
    double fa[3][3], fb[3][3]; /* the joint's axes as a and b hold them */
} ends;

static void sub3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[0] - b[0], out[1] = a[1] - b[1], out[2] = a[2] - b[2];
}

/* w x (w x r) */
static void twice(const double w[3], const double r[3], double out[3])
{
    double t[3];
    tb__cross(w, r, t);
    tb__cross(w, t, out);
}

/* m or rad: a limit this near is reached, and its row holds the
   velocities (far above what the projection leaves, far below a step's
   motion) */
#define REACHED 1e-9

static void row_start(tb__joint_row *row, const ends *e)
{
    row->a = e->a->slot, row->b = e->b->slot;
    row->kind = TB__ROW_EQUAL;
    row->speed = row->most = 0;
    row->reach = REACHED;
}

/* -C: the same row, asked from the other side (an upper limit) */
static void negate(tb__joint_row *row)
{
    int k;
    for (k = 0; k < 3; ++k) {
        row->lin_a[k] = -row->lin_a[k], row->ang_a[k] = -row->ang_a[k];
        row->lin_b[k] = -row->lin_b[k], row->ang_b[k] = -row->ang_b[k];
    }
    row->bias = -row->bias;
    row->error = -row->error;
}

/* t.(p_a - p_b), t fixed in the world, or turning with a */
static void point_row(tb__joint_row *row, const ends *e, const double t[3], int turns)
{
    double lever[3], wt[3], wwt[3];
    int k;
    row_start(row, e);
    for (k = 0; k < 3; ++k)
        row->lin_a[k] = t[k], row->lin_b[k] = -t[k];
    if (turns) /* (t x d) from t's turn, plus r_a x t: (p_b - x_a) x t */
        for (k = 0; k < 3; ++k)
            lever[k] = e->ra[k] - e->d[k];
    else
        for (k = 0; k < 3; ++k)
            lever[k] = e->ra[k];
    tb__cross(lever, t, row->ang_a);
    tb__cross(t, e->rb, row->ang_b);
    row->bias = tb__dot3(t, e->centripetal);
    if (turns) {
        tb__cross(e->a->w, t, wt);
        tb__cross(e->a->w, wt, wwt);
        row->bias += tb__dot3(wwt, e->d) + 2 * tb__dot3(wt, e->dd);
    }
    row->error = tb__dot3(t, e->d);
}

/* |p_a - p_b| - length */
static void distance_row(tb__joint_row *row, const ends *e, double length)
{
    const double r = tb__norm3(e->d);
    double n[3], along;
    int k;
    if (r > 0)
        for (k = 0; k < 3; ++k)
            n[k] = e->d[k] / r;
    else /* the ends met: any direction; the row holds them apart along it */
        n[0] = e->fa[0][0], n[1] = e->fa[0][1], n[2] = e->fa[0][2];
    point_row(row, e, n, 0);
    along = tb__dot3(n, e->dd);
    if (r > 0)
        row->bias += (tb__dot3(e->dd, e->dd) - along * along) / r;
    row->error = r - length;
}

/* u.v for u an axis of a, v one of b */
static void angle_row(tb__joint_row *row, const ends *e, const double u[3], const double v[3])
{
    double wu[3], wv[3], t[3];
    int k;
    row_start(row, e);
    for (k = 0; k < 3; ++k)
        row->lin_a[k] = row->lin_b[k] = 0;
    tb__cross(u, v, row->ang_a);
    tb__cross(v, u, row->ang_b);
    tb__cross(e->a->w, u, wu);
    tb__cross(e->b->w, v, wv);
    twice(e->a->w, u, t);
    row->bias = tb__dot3(t, v) + 2 * tb__dot3(wu, wv);
    twice(e->b->w, v, t);
    row->bias += tb__dot3(u, t);
    row->error = tb__dot3(u, v);
}

/* a and b keep their relative orientation: each axis square to the next
   one of the other */
static int orientation_rows(tb__joint_row *rows, const ends *e)
{
    angle_row(&rows[0], e, e->fa[0], e->fb[1]);
    angle_row(&rows[1], e, e->fa[1], e->fb[2]);
    angle_row(&rows[2], e, e->fa[2], e->fb[0]);
    return 3;
}

/* The angle a has turned about the axis relative to b: the angle of a's
   second axis from b's in the plane of b's two across the axis (0 at
   creation, right-handed about the axis); its rate is the axis times
   w_a - w_b, exactly while the hinge holds the axes together */
static void turn_row(tb__joint_row *row, const ends *e)
{
    double wa[3], dw[3];
    int k;
    row_start(row, e);
    for (k = 0; k < 3; ++k) {
        row->lin_a[k] = row->lin_b[k] = 0;
        row->ang_a[k] = e->fa[0][k], row->ang_b[k] = -e->fa[0][k];
        dw[k] = e->a->w[k] - e->b->w[k];
    }
    tb__cross(e->a->w, e->fa[0], wa); /* the axis turns with a */
    row->bias = tb__dot3(wa, dw);
    row->error = atan2(tb__dot3(e->fa[1], e->fb[2]), tb__dot3(e->fa[1], e->fb[1]));
}

static int ball_rows(tb__joint_row *rows, const ends *e)
{
    static const double axes[3][3] = { { 1, 0, 0 }, { 0, 1, 0 }, { 0, 0, 1 } };
    int k;
    for (k = 0; k < 3; ++k)
        point_row(&rows[k], e, axes[k], 0);
    return 3;
}

/* A ball joint's twist: the turn of a about the axis relative to b with
   the swing between the axes taken out (the twist of the swing-twist
   split of the relative rotation in b's frame: 2 atan2(q_x, q_w) for its
   quaternion q, x the axis), 0 at creation; its rate is the mean axis
   times w_a - w_b, exactly while the axes are together (the limit's
   Newton steps and the cone's rows carry the rest) */
static void twist_row(tb__joint_row *row, const ends *e)
{
    double M[3][3], axis[3], qw, qx, norm, wa[3], dw[3];
    int i, k;
    for (i = 0; i < 3; ++i) /* a's axes in b's frame */
        for (k = 0; k < 3; ++k)
            M[i][k] = tb__dot3(e->fb[i], e->fa[k]);
    /* the quaternion's w and x from the trace and the antisymmetric part
       about x (scaled alike: only their ratio is read) */
    qw = 1 + M[0][0] + M[1][1] + M[2][2];
    qx = M[2][1] - M[1][2];
    row_start(row, e);
    for (k = 0; k < 3; ++k)
        axis[k] = e->fa[0][k] + e->fb[0][k];
    norm = tb__norm3(axis);
    for (k = 0; k < 3; ++k) {
        axis[k] = norm > 0 ? axis[k] / norm : e->fa[0][k];
        row->lin_a[k] = row->lin_b[k] = 0;
        row->ang_a[k] = axis[k], row->ang_b[k] = -axis[k];
        dw[k] = e->a->w[k] - e->b->w[k];
    }
    tb__cross(e->a->w, e->fa[0], wa);
    row->bias = 0.5 * tb__dot3(wa, dw);
    row->error = 2 * atan2(qx, qw + (qw == 0 && qx == 0));
    if (row->error > 3.14159265358979323846) /* the shorter way round */
        row->error -= 2 * 3.14159265358979323846;
}

/* Joint j's free coordinate (joints.h, tb__joint_coordinate); 0 for
   FIXED */
static int coordinate_row(const tb_world *w, size_t j, const ends *e, tb__joint_row *row)
{
    switch (w->joint_type[j]) {
    case TB_JOINT_HINGE:
        turn_row(row, e);
        return 1;
    case TB_JOINT_SLIDER: /* a's anchor along a's axis from b's */
        point_row(row, e, e->fa[0], 1);
        return 1;
    case TB_JOINT_DISTANCE:
        distance_row(row, e, 0);
        return 1;
    case TB_JOINT_BALL: /* the cosine of the angle between the axes */
        angle_row(row, e, e->fa[0], e->fb[0]);
        return 1;
    default:
        return 0;
    }
}

/* The limits' rows (C = coordinate - lower >= 0, upper - coordinate >= 0;
   a ball joint's cone: cos(angle) - cos(upper) >= 0) and the motor's
   row (a rate along the coordinate), after the joint's own */
static int drive_rows(const tb_world *w, size_t j, const ends *e, tb__joint_row *rows)
{
    const double *drive = w->joint_drive + TB__DRIVES * j;
    const uint32_t flags = w->joint_flags[j];
    tb__joint_row row;
    int n = 0;
    if (flags & TB__JOINT_TWIST) { /* a ball joint's twist */
        twist_row(&row, e);
        row.kind = TB__ROW_LIMIT;
        rows[n] = row;
        rows[n++].error -= drive[TB__DRIVE_TWIST_LOWER];
        rows[n] = row;
        negate(&rows[n]);
        rows[n++].error += drive[TB__DRIVE_TWIST_UPPER];
    }
    if (!(flags & (TB__JOINT_LIMIT | TB__JOINT_MOTOR)) || !coordinate_row(w, j, e, &row))
        return n;
    if (flags & TB__JOINT_LIMIT) {
        row.kind = TB__ROW_LIMIT;
        rows[n] = row;
        if (w->joint_type[j] == TB_JOINT_BALL) {
            rows[n++].error -= cos(drive[TB__DRIVE_UPPER]);
        } else {
            rows[n++].error -= drive[TB__DRIVE_LOWER];
            rows[n] = row;
            negate(&rows[n]);
            rows[n++].error += drive[TB__DRIVE_UPPER];
        }
    }
    if (flags & TB__JOINT_MOTOR) {
        row.kind = TB__ROW_MOTOR;
        row.error = 0;
        row.speed = drive[TB__DRIVE_SPEED];
        row.most = drive[TB__DRIVE_MOST];
        rows[n++] = row;
    }
    return n;
}

double tb__joint_row_violation(const tb__joint_row *row)
{
    if (row->kind == TB__ROW_EQUAL)
        return fabs(row->error);
    return row->kind == TB__ROW_LIMIT && row->error < 0 ? -row->error : 0;
}

/* What every row of joint j reads, from its ends */
static void ends_of(const tb_world *w, size_t j, const tb__joint_end *a, const tb__joint_end *b, ends *out)
{
    const double *anchor = w->joint_anchor + 6 * j, *frame = w->joint_frame + 18 * j;
    double pa[3], pb[3], va[3], vb[3];
    int k;
    out->a = a, out->b = b;
    tb__mul(a->R, anchor, out->ra);
    tb__mul(b->R, anchor + 3, out->rb);
    for (k = 0; k < 3; ++k) {
        tb__mul(a->R, frame + 3 * k, out->fa[k]);
        tb__mul(b->R, frame + 9 + 3 * k, out->fb[k]);
        pa[k] = a->x[k] + out->ra[k];
        pb[k] = b->x[k] + out->rb[k];
    }
    sub3(pa, pb, out->d);
    tb__cross(a->w, out->ra, va);
    tb__cross(b->w, out->rb, vb);
    for (k = 0; k < 3; ++k)
        out->dd[k] = (a->v[k] + va[k]) - (b->v[k] + vb[k]);
    twice(a->w, out->ra, va);
    twice(b->w, out->rb, vb);
    sub3(va, vb, out->centripetal);
}

void tb__joint_contact_row(const tb__joint_contact *contact, const tb__joint_end *a, const tb__joint_end *b,
                           tb__joint_row *row)
{
    const double t[3] = { -contact->normal[0], -contact->normal[1], -contact->normal[2] };
    double va[3], vb[3];
    ends e;
    int k;
    memset(&e, 0, sizeof e);
    e.a = a, e.b = b;
    tb__mul(a->R, contact->anchor_a, e.ra);
    tb__mul(b->R, contact->anchor_b, e.rb);
    for (k = 0; k < 3; ++k)
        e.d[k] = (a->x[k] + e.ra[k]) - (b->x[k] + e.rb[k]);
    tb__cross(a->w, e.ra, va);
    tb__cross(b->w, e.rb, vb);
    for (k = 0; k < 3; ++k)
        e.dd[k] = (a->v[k] + va[k]) - (b->v[k] + vb[k]);
    twice(a->w, e.ra, va);
    twice(b->w, e.rb, vb);
    sub3(va, vb, e.centripetal);
    point_row(row, &e, t, 0); /* n.(p_b - p_a) */
    row->kind = contact->kind;
    row->error += contact->offset;
    row->reach = contact->reach;
    if (contact->kind == TB__ROW_FRICTION) /* a velocity row only */
        row->error = 0, row->most = contact->most;
}

int tb__joint_coordinate(const tb_world *w, size_t j, const tb__joint_end *a, const tb__joint_end *b,
                         tb__joint_row *row)
{
    ends e;
    int n;
    ends_of(w, j, a, b, &e);
    n = coordinate_row(w, j, &e, row);
    if (n && w->joint_type[j] == TB_JOINT_BALL) /* the angle, not its cosine */
        row->error = acos(fmax(-1, fmin(1, row->error)));
    return n;
}

int tb__joint_rows(const tb_world *w, size_t j, const tb__joint_end *a, const tb__joint_end *b, tb__joint_row *rows)
{
    ends e;
    int n = 0;
    ends_of(w, j, a, b, &e);
    switch (w->joint_type[j]) {
    case TB_JOINT_BALL:
        n = ball_rows(rows, &e);
        break;
    case TB_JOINT_HINGE:
        n = ball_rows(rows, &e);
        angle_row(&rows[n++], &e, e.fa[0], e.fb[1]);
        angle_row(&rows[n++], &e, e.fa[0], e.fb[2]);
        break;
    case TB_JOINT_SLIDER:
        point_row(&rows[n++], &e, e.fa[1], 1);
        point_row(&rows[n++], &e, e.fa[2], 1);
        n += orientation_rows(rows + n, &e);
        break;
    case TB_JOINT_FIXED:
        n = ball_rows(rows, &e);
        n += orientation_rows(rows + n, &e);
        break;
    case TB_JOINT_DISTANCE: /* a rod, unless limits or a spring hold it instead */
        if (!(w->joint_flags[j] & (TB__JOINT_LIMIT | TB__JOINT_SPRING)))
            distance_row(&rows[n++], &e, w->joint_length[j]);
        break;
    default:
        break;
    }
    return n + drive_rows(w, j, &e, rows + n);
}
