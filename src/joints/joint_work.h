/* joint_work.h: what the joints' solve shares between its files (not
   outside src/joints/): the rows and factors of a pass over the joints
   (joint_solve.c sets them up and solves them; joint_shake.c puts the
   bodies on their joints with them; joints.c keeps the pairs whose
   shapes pass through each other in it). */
#ifndef TB_JOINT_WORK_H
#define TB_JOINT_WORK_H

#include "joints/joints.h"

/* A row's pivot under DROP times its diagonal: it depends on the rows
   before it (a closed loop's last joint), and is left out */
#define DROP 1e-10

struct tb__joint_work {
    tb__joint_row *rows;
    double (*weighted)[12];  /* [rows] M^-1 J^T: lin_a, ang_a, lin_b, ang_b, each through its body */
    size_t *first, *offset;  /* [rows] the envelope (core.h) */
    double *x;               /* [rows] right side, then multipliers */
    double *newton, *total;  /* [rows] a Newton step's multipliers; those taken so far */
    unsigned char *use;      /* [rows] 0: left out */
    double *rhs, *clamped;   /* [rows] a bounded solve's right side; the multipliers held at bounds */
    unsigned char *state;    /* [rows] a bounded solve's: free, at a bound, left out */
    size_t *packed, *packed_first, *packed_offset; /* [rows] the kept rows packed (solve_kept): each
                                                      row's place, and the packed envelope */
    unsigned char *packed_use;
    double *packed_x;
    double *kept_a, *kept_l; /* the packed matrix and factor (in a's block) */
    size_t row_cap;
    size_t *row_start, *row_end; /* [joints] each joint's rows */
    size_t *order;           /* the items (joints, then contacts) in the order set up, and the
                                walk's scratch (order_items) */
    size_t order_cap;
    double *lever;           /* [3 joints] the anchor on a from a's centre */
    double *held_lever;      /* [3 joints] ... at the start of the drift */
    size_t joint_cap;
    double *a, *l, *upper;   /* the envelope of J M^-1 J^T, its factor; SHAKE's matrix's
                                upper part (tb__joints_shake); kept_a and kept_l: one block */
    size_t env_cap;
    /* per node (node(): the bodies' slots, then the particles'): */
    double *accel;           /* [6 nodes] a0 and alpha0 under the other forces, or v and w */
    size_t *body_row;        /* [nodes] the first row that moves the node */
    unsigned *stamp;         /* [nodes] the set-up that last wrote the two above */
    double *start;           /* [7 nodes] x and q at the start of a drift (tb__joints_hold) */
    int32_t *moved;          /* [nodes] the ends the joints move, moved_count of them */
    double *kept;            /* [7 nodes] a Newton step's starting poses or momenta */
    double *half;            /* [7 nodes] the momenta SHAKE started from */
    tb__joint_end *ends;     /* [nodes] each end at this set-up's state */
    size_t moved_count;
    size_t body_cap;         /* nodes */
    unsigned now;            /* this set-up's stamp */
    int projecting;          /* the projection's set-ups: the joints the soft step met
                                (TB__JOINT_SOFT) are put on their joints too */
    int impulses;            /* the reactions hold impulses of this step's drifts
                                (tb__joints_shake), for the projection to finish */
    uint64_t *apart;         /* [apart_count] the body pairs whose shapes pass through each
                                other (tb__joints_apart), sorted */
    size_t apart_count, apart_cap;
    tb__joint_contact *contacts; /* [contact_count] contact points set up after the joints' rows,
                                    each a row (the projection's, after the contacts' solve) */
    size_t contact_count, contact_cap;
    int32_t *island;         /* [2 contacts' solver bodies] scratch of tb__contacts_for_joints */
    size_t island_cap;
    tb__joint_row *held;     /* [rows] the rows at the start of the drift */
    double (*held_weighted)[12]; /* [rows] ... through the inertia now (SHAKE's) */
    size_t held_cap, held_weighted_cap, held_count;
};

/* Room for `rows` rows and the world's joints and nodes */
tb_status tb__joint_reserve(tb_world *w, size_t rows);
/* An end's index in the per-node arrays: the bodies, then the particles */
size_t tb__joint_node(const tb_world *w, int32_t end);
/* What a set-up makes besides the rows: their weighted copies, envelope
   and matrix (J M^-1 J^T); SHAKE's, the rows now through the inertia now
   times the held rows (tb__joints_shake), not symmetric; or nothing (a
   Newton trial's, which reads the rows' errors alone) */
enum { TB__SET_UP_MATRIX, TB__SET_UP_SHAKE, TB__SET_UP_ROWS };
/* Every joint's rows at positions from y, velocities from seen, and what
   `make` names; with `forces`, the nodes' accelerations under their
   other forces too. *count: the rows. */
tb_status tb__joint_set_up(tb_world *w, const double *y, const double *seen, int forces, int make, size_t *count);
/* k->x = (J M^-1 J^T)^-1 k->x over the rows k->use keeps, those left out
   (or that the factor leaves out) at 0; each within what its row allows:
   a LIMIT row's at least 0, a MOTOR row's within +-most h, a FRICTION
   row's within +-most (an active set: rows past a bound held there,
   rows held whose rates the others break taken back) */
void tb__joint_solve(struct tb__joint_work *k, size_t rows, double h);
/* A row's rate at the velocities of the ends set up with it */
double tb__joint_row_rate(const tb_world *w, const struct tb__joint_work *k, const tb__joint_row *row);
/* J^T x added to the ends: as forces (forces 1), or as impulses */
void tb__joint_apply(tb_world *w, const tb__joint_row *rows, size_t count, const double *x, int forces);
/* Each joint's rows times k->x added to its reaction (the torque about
   its anchor on a, lever from a's centre) */
void tb__joint_add_reactions(tb_world *w, const struct tb__joint_work *k, const tb__joint_row *rows,
                             const double *lever);
/* k->x = J v: the rows' rates at the velocities they were set up with
   (k->accel holds the ends' motion after it) */
void tb__joint_rates(const tb_world *w, struct tb__joint_work *k, size_t rows);
/* The largest |C| of the rows */
double tb__joint_largest_error(const struct tb__joint_work *k, size_t rows);
/* The moved ends' poses (poses 1: a body's x and q, a particle's x) or
   momenta (0: a body's P and L, a particle's v) kept into buffer (keep
   1), or put back from it (keep 0) */
void tb__joint_keep(tb_world *w, struct tb__joint_work *k, double *buffer, int poses, int keep);

#endif
