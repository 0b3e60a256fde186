/* body_step.c: the body tier's part of the stepping primitives: derive,
   kick and drift, projection, callback motion, and RK4 fused per block of
   bodies. The hot loops run over TB__LANES bodies at a time (bodies.h),
   written so that GCC -O2 vectorises them. */
#include "bodies/bodies.h"

/* dP/dt and dL/dt from the local forces: gravity, damping (seeing P and
   L) and the forces held by the user. */
TB__LANE void local_rates(double m, const double g[3], double cl, double ca, const double *held,
                          const double P[3], const double L[3], double dP[3], double dL[3])
{
    /* written out: the lane loops vectorise only straight code */
    dP[0] = m * g[0] - cl * P[0] + held[0];
    dP[1] = m * g[1] - cl * P[1] + held[1];
    dP[2] = m * g[2] - cl * P[2] + held[2];
    dL[0] = held[3] - ca * L[0];
    dL[1] = held[4] - ca * L[1];
    dL[2] = held[5] - ca * L[2];
}

/* ... and the callbacks' forces of this evaluation. */
static void rates(const tb_world *w, uint32_t s, const double *P, const double *L, double dP[3], double dL[3])
{
    int k;
    local_rates(w->body_mass[s], w->gravity, w->body_damping[2 * s], w->body_damping[2 * s + 1],
                w->body_applied + 6 * s, P, L, dP, dL);
    if (w->force_ready)
        for (k = 0; k < 3; ++k) {
            dP[k] += w->body_force[3 * s + k];
            dL[k] += w->body_force[3 * w->body_count + 3 * s + k];
        }
}

void tb__body_rates(const tb_world *w, uint32_t s, const double *P, const double *L, double dP[3], double dL[3])
{
    rates(w, s, P, L, dP, dL);
}

/* dx/dt = P / M and dq/dt = (0, w) q / 2 = q (0, w_b) / 2, with w = R w_b
   and w_b = diag(invI) R^T L for R = R(q / |q|): the q of a Runge-Kutta
   stage is not unit. R^T L comes straight from q, as
   L + w t + p x t with p = -(x, y, z) and t = (2 / |q|^2) p x L: one
   division, no root, no matrix, no turn back to the world. An isotropic
   body needs no R at all: w = L / I. */
TB__LANE void motion(const double q[4], const double P[3], const double L[3], double inv_mass,
                     const double invI[3], int isotropic, double dx[3], double dq[4])
{
    dx[0] = P[0] * inv_mass;
    dx[1] = P[1] * inv_mass;
    dx[2] = P[2] * inv_mass;
    if (isotropic) {
        const double w0 = invI[0] * L[0], w1 = invI[0] * L[1], w2 = invI[0] * L[2];
        dq[0] = -0.5 * (w0 * q[1] + w1 * q[2] + w2 * q[3]);
        dq[1] = 0.5 * (w0 * q[0] + w1 * q[3] - w2 * q[2]);
        dq[2] = 0.5 * (-w0 * q[3] + w1 * q[0] + w2 * q[1]);
        dq[3] = 0.5 * (w0 * q[2] - w1 * q[1] + w2 * q[0]);
    } else {
        const double w = q[0], x = -q[1], y = -q[2], z = -q[3];
        const double s = 2 / (w * w + x * x + y * y + z * z);
        const double tx = s * (y * L[2] - z * L[1]), ty = s * (z * L[0] - x * L[2]), tz = s * (x * L[1] - y * L[0]);
        const double w0 = invI[0] * (L[0] + w * tx + (y * tz - z * ty));
        const double w1 = invI[1] * (L[1] + w * ty + (z * tx - x * tz));
        const double w2 = invI[2] * (L[2] + w * tz + (x * ty - y * tx));
        dq[0] = -0.5 * (q[1] * w0 + q[2] * w1 + q[3] * w2);
        dq[1] = 0.5 * (q[0] * w0 + q[2] * w2 - q[3] * w1);
        dq[2] = 0.5 * (q[0] * w1 + q[3] * w0 - q[1] * w2);
        dq[3] = 0.5 * (q[0] * w2 + q[1] * w1 - q[2] * w0);
    }
}

void tb__body_derive(tb_world *w, const double *y, double *dy)
{
    const double *q = y + w->off[TB__BODY_ROT], *P = y + w->off[TB__BODY_MOM], *L = y + w->off[TB__BODY_ANG];
    uint32_t s;
    for (s = 0; s < w->body_count; ++s) {
        motion(q + 4 * s, P + 3 * s, L + 3 * s, w->body_inv_mass[s], w->body_inv_inertia + 3 * s,
               w->body_frame[s].isotropic, dy + w->off[TB__BODY_POS] + 3 * s, dy + w->off[TB__BODY_ROT] + 4 * s);
        rates(w, s, P + 3 * s, L + 3 * s, dy + w->off[TB__BODY_MOM] + 3 * s, dy + w->off[TB__BODY_ANG] + 3 * s);
    }
}

static int gravity_only(tb_world *w);

/* ---- RK4, fused ---------------------------------------------------------------- */

/* Generic RK4 (integrators.c) makes seven passes over the whole state and
   four over the derivative. When nothing couples objects (no callbacks;
   bodies feel no springs), each body's derivative depends on the body
   alone, so a block of TB__LANES bodies can go through all four stages
   while it sits in L1: one loop over the lanes per stage, which GCC
   vectorises, takes the slope and at once adds it to the sum and makes the
   next stage. Each lane does what the generic method does to its body, in
   the same order: the same bits
   (test_rotation.fast_paths_give_the_general_bits). */
enum { RK_X = 0, RK_Q = 3, RK_P = 7, RK_L = 10, RK_N = 13 };

typedef struct rk_block {
    double y[RK_N][TB__LANES];     /* the block's state at the start: x, q, P, L */
    double stage[RK_N][TB__LANES]; /* a stage's state; at the end, the new state */
    double sum[RK_N][TB__LANES];   /* k1 + 2 k2 + 2 k3 + k4 */
    double held[6][TB__LANES];     /* the held forces and torques (copied in:
                                      GCC vectorises no stride of 6) */
    double n2[TB__LANES];          /* |q|^2 at the end, for project_far */
    double inv_inertia[3][TB__LANES]; /* the constants the stages read, */
    double mg[3][TB__LANES];          /* copied in once, not at every stage */
} rk_block;

/* The bodies' constants, at the block's first body. */
typedef struct rk_params {
    const double *mass, *inv_mass, *damping;
    double gravity[3];
} rk_params;

/* Stage `mode` of lane i: the slope k at the stage's state (at y for the
   first), then what the generic method's axpy passes do with it:
   mode 0: sum = k, stage = y + a k;
   mode 1: sum = sum + b k, stage = y + a k;
   mode 2: sum = sum + b k, stage = y + a sum (the end of the step).
   The stages' positions are left out: no slope reads them. Without
   damping and held forces (`local` 0) dP/dt = m g and dL/dt = 0 (the bits
   local_rates() gives then), so L is left alone. */
TB__LANE void rk_add(rk_block *r, int n, int i, double k, double a, double b, int mode)
{
    const double sum = mode == 0 ? k : r->sum[n][i] + b * k;
    r->sum[n][i] = sum;
    if (n >= RK_Q || mode == 2)
        r->stage[n][i] = r->y[n][i] + a * (mode == 2 ? sum : k);
}

TB__LANE void rk_stage(const rk_params *c, rk_block *r, int i, int isotropic, int local, double a, double b,
                       int mode)
{
    double (*in)[TB__LANES] = mode == 0 ? r->y : r->stage;
    double (*in_l)[TB__LANES] = local ? in : r->y;
    double q[4], P[3], L[3], k[RK_N], invI[3];
    invI[0] = r->inv_inertia[0][i], invI[1] = r->inv_inertia[1][i], invI[2] = r->inv_inertia[2][i];
    q[0] = in[RK_Q][i], q[1] = in[RK_Q + 1][i], q[2] = in[RK_Q + 2][i], q[3] = in[RK_Q + 3][i];
    P[0] = in[RK_P][i], P[1] = in[RK_P + 1][i], P[2] = in[RK_P + 2][i];
    L[0] = in_l[RK_L][i], L[1] = in_l[RK_L + 1][i], L[2] = in_l[RK_L + 2][i];
    motion(q, P, L, c->inv_mass[i], invI, isotropic, k + RK_X, k + RK_Q);
    if (local) {
        double held[6];
        held[0] = r->held[0][i], held[1] = r->held[1][i], held[2] = r->held[2][i];
        held[3] = r->held[3][i], held[4] = r->held[4][i], held[5] = r->held[5][i];
        local_rates(c->mass[i], c->gravity, c->damping[2 * i], c->damping[2 * i + 1], held, P, L, k + RK_P,
                    k + RK_L);
    } else {
        k[RK_P] = r->mg[0][i], k[RK_P + 1] = r->mg[1][i], k[RK_P + 2] = r->mg[2][i];
    }
    /* written out: the lane loops vectorise only straight code */
    rk_add(r, 0, i, k[0], a, b, mode), rk_add(r, 1, i, k[1], a, b, mode), rk_add(r, 2, i, k[2], a, b, mode);
    rk_add(r, 3, i, k[3], a, b, mode), rk_add(r, 4, i, k[4], a, b, mode), rk_add(r, 5, i, k[5], a, b, mode);
    rk_add(r, 6, i, k[6], a, b, mode), rk_add(r, 7, i, k[7], a, b, mode), rk_add(r, 8, i, k[8], a, b, mode);
    rk_add(r, 9, i, k[9], a, b, mode);
    if (local) {
        rk_add(r, 10, i, k[10], a, b, mode), rk_add(r, 11, i, k[11], a, b, mode);
        rk_add(r, 12, i, k[12], a, b, mode);
    }
}

/* A stage of the m lanes; `kind` 1: all isotropic, 0: none, -1: some. The
   loops of fixed length, one for each combination of the constant
   arguments, are the ones GCC vectorises. */
#define RK_LANES(isotropic, local, mode)                           \
    for (i = 0; i < TB__LANES; ++i)                                \
        rk_stage(c, r, i, isotropic, local, a, b, mode)
#define RK_MODES(isotropic, local)                                 \
    do {                                                           \
        if (mode == 0)                                             \
            RK_LANES(isotropic, local, 0);                         \
        else if (mode == 1)                                        \
            RK_LANES(isotropic, local, 1);                         \
        else                                                       \
            RK_LANES(isotropic, local, 2);                         \
    } while (0)

TB__LANE void rk_stages(const rk_params *c, rk_block *restrict r, const tb__split_frame *frame, int kind, int local,
                       int m, double a, double b, int mode)
{
    int i;
    if (m < TB__LANES || kind < 0)
        for (i = 0; i < m; ++i)
            rk_stage(c, r, i, frame[i].isotropic, local, a, b, mode);
    else if (kind && local)
        RK_MODES(1, 1);
    else if (kind)
        RK_MODES(1, 0);
    else if (local)
        RK_MODES(0, 1);
    else
        RK_MODES(0, 0);
}

/* Lane i from and back to the state arrays (pointers at the block's first
   body). */
TB__LANE void rk_get(rk_block *r, int i, const double *x, const double *q, const double *P, const double *L,
                     const double *inv_inertia, double mass, const double g[3])
{
    r->inv_inertia[0][i] = inv_inertia[3 * i], r->inv_inertia[1][i] = inv_inertia[3 * i + 1];
    r->inv_inertia[2][i] = inv_inertia[3 * i + 2];
    r->mg[0][i] = mass * g[0], r->mg[1][i] = mass * g[1], r->mg[2][i] = mass * g[2];
    r->y[RK_X][i] = x[3 * i], r->y[RK_X + 1][i] = x[3 * i + 1], r->y[RK_X + 2][i] = x[3 * i + 2];
    r->y[RK_Q][i] = q[4 * i], r->y[RK_Q + 1][i] = q[4 * i + 1];
    r->y[RK_Q + 2][i] = q[4 * i + 2], r->y[RK_Q + 3][i] = q[4 * i + 3];
    r->y[RK_P][i] = P[3 * i], r->y[RK_P + 1][i] = P[3 * i + 1], r->y[RK_P + 2][i] = P[3 * i + 2];
    r->y[RK_L][i] = L[3 * i], r->y[RK_L + 1][i] = L[3 * i + 1], r->y[RK_L + 2][i] = L[3 * i + 2];
}

TB__LANE void rk_put(rk_block *r, int i, double *x, double *q, double *P, double *L, int local)
{
    double qi[4], f;
    x[3 * i] = r->stage[RK_X][i], x[3 * i + 1] = r->stage[RK_X + 1][i], x[3 * i + 2] = r->stage[RK_X + 2][i];
    P[3 * i] = r->stage[RK_P][i], P[3 * i + 1] = r->stage[RK_P + 1][i], P[3 * i + 2] = r->stage[RK_P + 2][i];
    if (local) {
        L[3 * i] = r->stage[RK_L][i], L[3 * i + 1] = r->stage[RK_L + 1][i];
        L[3 * i + 2] = r->stage[RK_L + 2][i];
    }
    qi[0] = r->stage[RK_Q][i], qi[1] = r->stage[RK_Q + 1][i];
    qi[2] = r->stage[RK_Q + 2][i], qi[3] = r->stage[RK_Q + 3][i];
    f = tb__newton_scale(qi, &r->n2[i]); /* tb__project_unit() with tb__project_near's path */
    q[4 * i] = qi[0] * f, q[4 * i + 1] = qi[1] * f, q[4 * i + 2] = qi[2] * f, q[4 * i + 3] = qi[3] * f;
}

TB__LANE void rk_load(rk_block *restrict r, const double *restrict x, const double *restrict q,
                      const double *restrict P, const double *restrict L, const double *restrict held,
                      const rk_params *c, const double *restrict inv_inertia, int m, int local)
{
    const double *restrict mass = c->mass;
    int i, k;
    if (m == TB__LANES)
        for (i = 0; i < TB__LANES; ++i)
            rk_get(r, i, x, q, P, L, inv_inertia, mass[i], c->gravity);
    else
        for (i = 0; i < m; ++i)
            rk_get(r, i, x, q, P, L, inv_inertia, mass[i], c->gravity);
    for (i = 0; i < m && local; ++i)
        for (k = 0; k < 6; ++k)
            r->held[k][i] = held[6 * i + k];
}

TB__LANE void rk_store(rk_block *restrict r, double *restrict x, double *restrict q, double *restrict P,
                       double *restrict L, int m, int local)
{
    int i, k;
    if (m == TB__LANES && local)
        for (i = 0; i < TB__LANES; ++i)
            rk_put(r, i, x, q, P, L, 1);
    else if (m == TB__LANES)
        for (i = 0; i < TB__LANES; ++i)
            rk_put(r, i, x, q, P, L, 0);
    else
        for (i = 0; i < m; ++i)
            rk_put(r, i, x, q, P, L, local);
    for (i = 0; i < m; ++i)
        if (!TB__PROJECT_NEAR(r->n2[i])) {
            for (k = 0; k < 4; ++k)
                q[4 * i + k] = r->stage[RK_Q + k][i];
            tb__project_far(q + 4 * i);
        }
}

TB__LANE void rk4_block(tb_world *w, size_t b, int m, double h, int local)
{
    double *x = w->y + w->off[TB__BODY_POS] + 3 * b, *q = w->y + w->off[TB__BODY_ROT] + 4 * b;
    double *P = w->y + w->off[TB__BODY_MOM] + 3 * b, *L = w->y + w->off[TB__BODY_ANG] + 3 * b;
    const double *held = w->body_applied + 6 * b;
    const tb__split_frame *frame = w->body_frame + b;
    rk_params c;
    rk_block r;
    int i, k, iso = 0, kind;
    c.mass = w->body_mass + b;
    c.inv_mass = w->body_inv_mass + b;
    c.damping = w->body_damping + 2 * b;
    for (k = 0; k < 3; ++k) /* m (g + 0) is m g - 0 P + 0 to the bit, even for g = -0 */
        c.gravity[k] = local ? w->gravity[k] : w->gravity[k] + 0.0;
    rk_load(&r, x, q, P, L, held, &c, w->body_inv_inertia + 3 * b, m, local);
    for (i = 0; i < m; ++i)
        iso += frame[i].isotropic;
    kind = iso == m ? 1 : iso == 0 ? 0 : -1;
    rk_stages(&c, &r, frame, kind, local, m, h / 2, 0, 0);
    rk_stages(&c, &r, frame, kind, local, m, h / 2, 2, 1);
    rk_stages(&c, &r, frame, kind, local, m, h, 2, 1);
    rk_stages(&c, &r, frame, kind, local, m, h / 6, 1, 2);
    rk_store(&r, x, q, P, L, m, local);
}

/* The blocks, compiled for each instruction set (core/core.h); all give
   the same bits. */
#define RK4_BLOCKS(isa, attr, id)                                                                             \
    attr static void rk4_##isa(tb_world *w, double h, int local)                                            \
    {                                                                                                       \
        size_t b;                                                                                           \
        for (b = 0; b < w->body_count; b += TB__LANES)                                                      \
            rk4_block(w, b, w->body_count - b < TB__LANES ? (int)(w->body_count - b) : TB__LANES, h, local); \
    }
TB__FOR_EACH_ISA(RK4_BLOCKS)

void tb__body_rk4(tb_world *w, double h)
{
    const int local = !gravity_only(w), isa = tb__isa();
    TB__DISPATCH(isa, rk4, (w, h, local));
}

/* Turn bodies [b, b + m) of a block through their free motion over h. */
static void turn(tb_world *w, size_t b, size_t m, const tb__split_op *op, int isa)
{
    double *q = w->y + w->off[TB__BODY_ROT] + 4 * b;
    const double *L = w->y + w->off[TB__BODY_ANG] + 3 * b, *invI = w->body_inv_inertia + 3 * b;
    const tb__split_frame *frame = w->body_frame + b;
    tb__lane_frames frames;
    const double h = op->h;
    size_t s, iso = w->body_isotropic == w->body_count ? m : 0;
    if (w->body_isotropic && iso == 0)
        for (s = 0; s < m; ++s)
            iso += frame[s].isotropic;
    /* an isotropic body turns about a fixed axis, exactly and cheaply, with
       no gyroscopic work (the splitting lanes send it there too) */
    frames.a = w->body_lane_frame[0] + b, frames.ca = w->body_lane_frame[1] + b;
    frames.cb = w->body_lane_frame[2] + b, frames.code = w->body_lane_frame[3] + b;
    if (iso == m)
        tb__isotropic_lanes(q, L, invI, h, (int)m, isa);
    else if (op->rotation == TB__ROTATE_SPLIT2)
        tb__split2_lanes_framed(q, L, invI, &frames, h, (int)m, isa);
    else if (op->rotation == TB__ROTATE_ACCURATE)
        tb__accurate_lanes_framed(q, L, invI, &frames, h, (int)m, isa);
    else if (iso == 0)
        tb__frozen_lanes(q, L, invI, h, (int)m, isa);
    else
        for (s = 0; s < m; ++s) /* (one body at a time, on this instruction set) */
            if (frame[s].isotropic)
                tb__isotropic_lanes(q + 4 * s, L + 3 * s, invI + 3 * s, h, 1, isa);
            else
                tb__frozen_lanes(q + 4 * s, L + 3 * s, invI + 3 * s, h, 1, isa);
}

/* A block's per-body numbers spread to the layout of its 3-vectors:
   out[3 i + k] = in[i]. The loops over the block's vectors can then run
   straight over 3 TB__LANES numbers, instead of gathering each component
   at a stride of 3 (a shuffle per number). */
TB__LANE void spread3(const double *restrict in, double *restrict out)
{
    int i;
    for (i = 0; i < TB__LANES; ++i)
        out[3 * i] = out[3 * i + 1] = out[3 * i + 2] = in[i];
}

/* x += h v = h P / m for bodies [0, m) of a block (pointers at the
   block). */
TB__LANE void drift(double *restrict x, const double *restrict P, const double *restrict inv_mass, double h,
                    size_t m)
{
    size_t i;
    if (m == TB__LANES) {
        double inv3[3 * TB__LANES];
        spread3(inv_mass, inv3);
        for (i = 0; i < 3 * TB__LANES; ++i)
            x[i] += h * P[i] * inv3[i];
    } else {
        for (i = 0; i < 3 * m; ++i)
            x[i] += h * P[i] * inv_mass[i / 3];
    }
}

/* A kick of gravity alone (as kick_gravity) and then a drift, in one pass
   over the block: what a split method's sweep mostly does; close: and then
   the same kick again (verlet's closing kick, when nothing the drift
   changes moves the forces: integrators.c). The operations of
   kick_gravity, drift and kick_gravity one after the other, the same
   bits, with P, the masses and the kick h m g gone through once. */
TB__LANE void kick_drift(double *restrict x, double *restrict P, const double *restrict mass,
                         const double *restrict inv_mass, double hk, double hd, const double *restrict g3, int close)
{
    double m3[3 * TB__LANES], inv3[3 * TB__LANES];
    int i;
    spread3(mass, m3);
    spread3(inv_mass, inv3);
    for (i = 0; i < 3 * TB__LANES; ++i) {
        const double kick = hk * (m3[i] * g3[i]), p = P[i] + kick;
        x[i] += hd * p * inv3[i];
        P[i] = close ? p + kick : p;
    }
}

/* The kick of a world where gravity is the only force on bodies: P gains
   h m g, L nothing. g3 is (g + 0) repeated TB__LANES times: m (g + 0) is
   what rates() gives with its other terms zero (m g - 0 P + 0), to the
   bit, even for a component of g that is -0. */
TB__LANE void kick_gravity(double *restrict P, const double *restrict mass, double h, const double *restrict g3,
                           size_t m)
{
    size_t i;
    if (m == TB__LANES) {
        double m3[3 * TB__LANES];
        spread3(mass, m3);
        for (i = 0; i < 3 * TB__LANES; ++i)
            P[i] += h * (m3[i] * g3[i]);
    } else {
        for (i = 0; i < 3 * m; ++i)
            P[i] += h * (mass[i / 3] * g3[i]);
    }
}

static void kick(tb_world *w, size_t b, size_t m, double h)
{
    double *P = w->y + w->off[TB__BODY_MOM], *L = w->y + w->off[TB__BODY_ANG];
    const double *Pseen = w->kick_seen ? w->kick_seen + w->off[TB__BODY_MOM] : P;
    const double *Lseen = w->kick_seen ? w->kick_seen + w->off[TB__BODY_ANG] : L;
    size_t s;
    int k;
    for (s = b; s < b + m; ++s) {
        double dP[3], dL[3];
        rates(w, (uint32_t)s, Pseen + 3 * s, Lseen + 3 * s, dP, dL);
        for (k = 0; k < 3; ++k) {
            P[3 * s + k] += h * dP[k];
            L[3 * s + k] += h * dL[k];
        }
    }
}

/* Whether kicks see gravity alone: no damping, no held forces, no callback
   forces. Held forces last one step (tb_world_step clears them), so the
   flag that some may be held is dropped once they are all zero. */
static int gravity_only(tb_world *w)
{
    if (w->body_held) {
        size_t i;
        for (i = 0; i < 6 * w->body_count && w->body_applied[i] == 0; ++i)
            ;
        w->body_held = i < 6 * w->body_count;
    }
    return w->body_damped == 0 && !w->body_held && !(w->force_ready && (w->forces.count > 0 || w->joint_count > 0));
}

/* A block of bodies that all sleep is left alone by the sweep: sleep.c
   puts a sleeping pose back after the integrator (and so needs to keep
   none for such a block when the method is a split one), and their drift
   can reach an awake body only through a spring, whose force verlet
   evaluates again after the drift (test_contacts_sleep,
   test_snapshot.contact_scene_hash_is_recorded). */
int tb__body_sweep_skips_sleeping(const tb_world *w)
{
    /* springs and joints are the forces between bodies: verlet's second
       evaluation would see a sleeping body's drift */
    return w->body_sleeping >= TB__LANES && w->spring_count == 0 && w->joint_count == 0;
}

int tb__body_block_asleep(const tb_world *w, size_t b, size_t m)
{
    size_t s;
    for (s = b; s < b + m && w->body_island[s]; ++s)
        ;
    return s == b + m;
}

/* The sweep goes over blocks of TB__LANES consecutive bodies, applying the
   ops in order to each block while it sits in L1: kicks and drifts in
   loops of fixed length over the block, which GCC vectorises, and turns by
   the kernels in lanes (bodies.h), which take the block as it is stored. */
TB__LANE void sweep_blocks(tb_world *w, const tb__split_op *ops, int n, int only_gravity, int isa)
{
    const int skip_sleeping = tb__body_sweep_skips_sleeping(w);
    double *x = w->y + w->off[TB__BODY_POS], *P = w->y + w->off[TB__BODY_MOM], g3[3 * TB__LANES];
    size_t b;
    int i;
    for (i = 0; i < TB__LANES; ++i) {
        g3[3 * i] = w->gravity[0] + 0.0;
        g3[3 * i + 1] = w->gravity[1] + 0.0;
        g3[3 * i + 2] = w->gravity[2] + 0.0;
    }
    for (b = 0; b < w->body_count; b += TB__LANES) {
        const size_t m = w->body_count - b < TB__LANES ? w->body_count - b : TB__LANES;
        if (skip_sleeping && tb__body_block_asleep(w, b, m))
            continue;
        for (i = 0; i < n; ++i) {
            if (only_gravity && m == TB__LANES && !ops[i].drift && i + 1 < n && ops[i + 1].drift) {
                /* (a kick of gravity leaves L alone: the turn may come after it) */
                const int close = i + 2 < n && !ops[i + 2].drift && ops[i + 2].h == ops[i].h;
                kick_drift(x + 3 * b, P + 3 * b, w->body_mass + b, w->body_inv_mass + b, ops[i].h, ops[i + 1].h, g3,
                           close);
                turn(w, b, m, &ops[i + 1], isa);
                i += 1 + close;
                continue;
            }
            if (!ops[i].drift) {
                if (only_gravity)
                    kick_gravity(P + 3 * b, w->body_mass + b, ops[i].h, g3, m);
                else
                    kick(w, b, m, ops[i].h);
                continue;
            }
            drift(x + 3 * b, P + 3 * b, w->body_inv_mass + b, ops[i].h, m);
            turn(w, b, m, &ops[i], isa);
        }
    }
}

/* ... compiled for each instruction set, as the lanes are: the kicks and
   drifts vectorise with the same bits on each. */
#define SWEEP_BLOCKS(isa, attr, isa_id)                                                        \
    attr static void sweep_##isa(tb_world *w, const tb__split_op *ops, int n, int only_gravity) \
    {                                                                                          \
        sweep_blocks(w, ops, n, only_gravity, isa_id);                                         \
    }
TB__FOR_EACH_ISA(SWEEP_BLOCKS)

void tb__body_sweep(tb_world *w, const tb__split_op *ops, int n)
{
    const int only_gravity = gravity_only(w), isa = tb__isa();
    TB__DISPATCH(isa, sweep, (w, ops, n, only_gravity));
}

int tb__body_velocity_dependent(const tb_world *w)
{
    return w->body_damped > 0;
}

void tb__body_project(tb_world *w, double *y)
{
    double *q = y + w->off[TB__BODY_ROT];
    size_t s;
    for (s = 0; s < w->body_count; ++s)
        tb__project_unit(q + 4 * s);
}

void tb__body_motion(tb_world *w, const double *y, const double *seen)
{
    const double *q = y + w->off[TB__BODY_ROT];
    const double *P = seen + w->off[TB__BODY_MOM], *L = seen + w->off[TB__BODY_ANG];
    double *v = w->body_motion, *omega = w->body_motion + 3 * w->body_count;
    size_t s;
    int k;
    for (s = 0; s < w->body_count; ++s) {
        for (k = 0; k < 3; ++k)
            v[3 * s + k] = P[3 * s + k] * w->body_inv_mass[s];
        tb__through_inertia(q + 4 * s, w->body_inv_inertia + 3 * s, L + 3 * s, omega + 3 * s);
    }
}
