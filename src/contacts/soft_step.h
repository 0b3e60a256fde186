/* soft_step.h: the soft-step solver's bodies, patches and rows (not
   public), shared by soft_step.c (the substeps) and stack_solve.c (the
   normal rows of a stack solved together). docs/contacts.md, "The
   soft step". */
#ifndef TB_SOFT_STEP_H
#define TB_SOFT_STEP_H

#include "contacts/contacts.h"
#include "joints/joints.h"

/* The larger and the smaller of a and b, b when they compare equal (so
   the sign of a zero is b's), a NaN never chosen over a number: fmax and
   fmin as the solver's loops use them, inlined (a library call each
   otherwise). */
static inline double tb__most(double a, double b)
{
    return a > b || b != b ? a : b;
}

static inline double tb__least(double a, double b)
{
    return a < b || b != b ? a : b;
}

/* The fields every row's impulse reads and writes come first, together,
   with the inverse mass, so that an impulse (apply in soft_step.c)
   touches this struct alone. */
typedef struct tb__soft_body {
    double v[3], w[3];          /* m/s, rad/s: velocities now */
    double P[3], L[3];          /* N s, N m s: momenta now (particles: P only) */
    double inv_mass;            /* 1/kg: the solver body's */
    int rotates;                /* a body (not a particle): it has L and w */
    double x[3], q[4];          /* m: pose now */
    double kick_p[3], kick_l[3];/* N s, N m s: external change of P, L per substep */
    double inv_world[9];        /* R diag(invI) R^T at q (0 for particles) */
    double shift[3];            /* m: x - x0 */
    double delta[9];            /* the rotation from q0 to q */
    double v_struck[3];         /* m/s: v before this substep's impacts */
    double struck_at;           /* s into the substep of its impact; < 0: none */
    int pass;                   /* 0: in islands solved together (or alone); 1: in an island
                                   too wide to, with no point deeper than the slop, stepped
                                   apart at twice the rate (wide_islands_apart) */
    int32_t group;              /* a body of its island (union-find, wide_islands_apart) */
    int jointed;                /* an end of a joint met in the substeps (soft_joints.c) */
} tb__soft_body;

/* A manifold: its points' normal rows, then friction (two rows at the
   centre of the points), twist (about the normal, within mu times the
   points' normal impulses times their levers from the centre) and
   rolling resistance (about the tangents, within rho times the normal
   impulse), solved together after the points. */
typedef struct tb__soft_patch {
    tb__entry *entry;
    int32_t a, b;
    size_t first, count;        /* its rows */
    double tangent[2][3];
    double ca[3], cb[3];        /* m: the centre of the points from each side's centre */
    double arm_a[2][3], arm_b[2][3]; /* centre x tangent */
    double spin_a[2][3], spin_b[2][3]; /* the start's inverse inertia times those */
    double turn_a[3][3], turn_b[3][3]; /* ... times the normal and the tangents */
    double tangent_mass[3];     /* the 2 x 2 inverse of J M^-1 J^T: xx, xy, yy */
    double twist_mass;
    double rolling_mass[3];     /* 2 x 2 inverse, about the tangents */
    double friction, rolling;
    double friction_impulse[2], twist_impulse, rolling_impulse[2]; /* N s, N m s: this substep's */
    double settled[2], settled_twist, settled_rolling[2]; /* what settle added */
    int stacked;                /* its normal rows are solved with its stack's (stack_solve.c) */
    int wide;                   /* in an island too wide to solve together, with no point
                                   deeper than the slop: stepped at twice the rate */
} tb__soft_patch;

/* A joint of bodies in contact, met in the substeps (soft_joints.c) */
typedef struct tb__soft_joint {
    uint32_t joint;
    int32_t a, b;               /* solver bodies, -1: what does not move */
    size_t first, count;        /* its rows */
    double lever[3];            /* m: the anchor on a from a's centre, now */
    double reaction[6];         /* N s, N m s: the step's impulse on a, the torque about its anchor */
} tb__soft_joint;

/* One of a soft joint's rows at the poses now (joints.h, tb__joint_row),
   in the contact rows' form: its rate n.(v_b - v_a) + arm_b.w_b -
   arm_a.w_a */
typedef struct tb__soft_joint_row {
    int32_t a, b;               /* solver bodies, -1: what does not move */
    int kind;                   /* TB__ROW_EQUAL, _LIMIT or _MOTOR */
    double normal[3];           /* the linear part on b (on a: its opposite) */
    double arm_a[3], arm_b[3];
    double spin_a[3], spin_b[3];/* the inverse inertia now times those */
    double error;               /* C now: m, rad or a cosine (LIMIT: >= 0 holds) */
    double speed, most;         /* MOTOR: the rate asked; the force's bound */
    double impulse;             /* N s or N m s: this substep's */
    double kept;                /* ... the last substep's, before the last rigid pass */
    double push;                /* N s or N m s: the push of its error over this drift */
} tb__soft_joint_row;

typedef struct tb__soft_row {
    tb__point *point;
    int32_t a, b;               /* solver bodies, -1: the static world */
    double normal[3];           /* a to b */
    double arm_a[3], arm_b[3];  /* r x normal at each side */
    double spin_a[3], spin_b[3];/* the start's inverse inertia times those */
    double ra[3], rb[3];        /* m: the point from each centre at the start */
    double core_a[3], core_b[3];/* m: each side's core point under it from each centre (a
                                   round shape turns about its core, its surface stays) */
    double mass;                /* 1 / (J M^-1 J^T), at the start pose */
    double impulse;             /* N s: accumulated in the current substep */
    double separation;          /* m: at the start of the step */
    double now;                 /* m: the separation now (after the last drift) */
    double lever;               /* m: from the patch's centre (a's side) */
    double restitution;
    double approach;            /* m/s (< 0): normal velocity at which the point struck */
    double most;                /* N s: the largest normal impulse of any substep */
    int struck;                 /* the normal row has pushed in some substep */
    double settled;             /* N s: what settle added */
    double step_impulse;        /* N s: the step's normal impulse, as store keeps it */
    double bounce;              /* N s: this substep's impact impulse (impacts) */
    int bounced;                /* bounced by impacts in some substep */
} tb__soft_row;

/* The soft constraint's coefficients for a substep of hs: a spring of
   `hertz` (at most a quarter of the substep rate, beyond which a substep
   cannot follow it) with damping ratio zeta, met implicitly over the
   substep: the velocity it aims at is -bias_rate times the error, the
   row's mass is scaled by mass_scale, and impulse_scale of the
   accumulated impulse is taken back, so that a held overlap settles
   where the spring holds the load. */
typedef struct tb__softness {
    double bias_rate, mass_scale, impulse_scale;
} tb__softness;
tb__softness tb__soft_softness(double hertz, double zeta, double hs);

/* soft_joints.c: each soft joint's rows at the start poses, their
   impulses from last step's forces (the warm start), no reaction yet;
   the rows again at the poses now (after a drift); a share of their
   impulses applied again; every joint of the pass under way solved
   once, rigid; their errors pushed out over the drift (sign +1 before
   it, -1 after it: taken back); a substep's impulses added to the
   reactions (last 0), or what the last rigid pass added (last 1); the
   forces and reactions stored */
tb_status tb__soft_joints_load(tb_world *w, tb__contacts *c, double hs);
void tb__soft_joints_now(tb_world *w, tb__contacts *c);
void tb__soft_joints_warm(tb__contacts *c, double share);
void tb__soft_joints_solve(tb__contacts *c, double hs);
void tb__soft_joints_push(tb__contacts *c, double rate, int sign);
void tb__soft_joints_count(tb__contacts *c, int last);
/* The last rigid pass's impulses begin at 0 (begin 1: the last
   substep's, kept, are not its to take back), and are then added to
   them (0) */
void tb__soft_joints_settle(tb__contacts *c, int begin);
void tb__soft_joints_store(tb_world *w, tb__contacts *c, double h, double hs);
/* The rate (1/s) the joints' errors are pushed out at, with contacts of
   `hertz` in substeps of hs */
double tb__soft_joints_rate(double hertz, double hs);

/* The relative velocity of b against a along row o's normal */
double tb__soft_rate(const tb__contacts *c, const tb__soft_row *o);
/* Row o's separation now, from the bodies' motion since the start (found
   after each drift) */
double tb__soft_separation(const tb__contacts *c, const tb__soft_row *o);
/* An impulse lambda along d, equal and opposite on bodies b (+) and a (-)
   (-1: the static world), with each side's arm and spin */
void tb__soft_pair(tb__contacts *c, int32_t a, int32_t b, double lambda, const double d[3], const double arm_a[3],
                   const double arm_b[3], const double spin_a[3], const double spin_b[3]);
/* The relative velocity of b against a along d, with each side's arm */
double tb__soft_relative(const tb__contacts *c, int32_t a, int32_t b, const double d[3], const double arm_a[3],
                         const double arm_b[3]);
/* J M^-1 J^T between two rows through solver body i: the row along d1
   with arm r x d1 on i meets the row along d2 whose spin on i is spin2
   (i's inverse inertia times its arm); the sides' signs are the caller's */
double tb__soft_through(const tb__contacts *c, int32_t i, const double d1[3], const double arm1[3],
                        const double d2[3], const double spin2[3]);
/* Solver body i's q changed: normalised, and its rotation since the
   start, its inverse inertia and w at the new orientation */
void tb__soft_turned(tb__contacts *c, size_t i);
/* continuous.c: after the substeps, each body that ends deeper than the
   slop in a static shape, where no row held it, taken back to its time
   of impact, its energy kept from rising */
void tb__soft_continuous(tb_world *w, tb__contacts *c);
/* A scalar impulse along row o's normal, equal and opposite on its sides */
void tb__soft_push(tb__contacts *c, const tb__soft_row *o, double lambda);
/* After row o's impulse changed in a substep of hs, at the normal velocity
   vn and separation s it was solved at: whether and how fast it struck,
   and its largest impulse */
void tb__soft_note(tb__contacts *c, tb__soft_row *o, double vn, double s, double hs);

/* A point within this share of the slop of touching touches, in a
   stacked patch: its row is solved with its island's (stack_solve.c), a
   point further apart by the patch's own speculative row. Held apart or
   not by rounding, a face's corners would rock a body about the others;
   solved with the island, a gap closing within the substep would meet
   a whole touching row of bodies as one (newtons_cradle). */
#define TB__TOUCHING 1e-3

/* stack_solve.c: the touching normal rows of islands whose band is
   narrow enough, solved together (their patches marked stacked), and the
   push of their overlaps */
tb_status tb__stacks_set_up(tb_world *w, tb__contacts *c);
/* Every narrow island's rows solved (with bias: before the drift, its
   points closing their gaps too) */
void tb__stacks_solve(tb__contacts *c, double hs, int bias);
/* The bands again, from the rows' responses now */
void tb__stacks_assemble(tb__contacts *c);
void tb__stacks_push(tb__contacts *c, double bias_rate, int sign);
void tb__stacks_free(tb_world *w, tb__contacts *c);

#endif
