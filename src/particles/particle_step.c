/* particle_step.c: the kernels that move particles under their local
   forces (gravity, linear and quadratic drag) and the global ones (springs,
   callbacks) gathered in w->particle_force: derive for generic methods,
   kick and drift for split methods.

   Built with -fno-math-errno -fno-trapping-math (CMakeLists.txt), so that
   the quadratic drag's square root is one instruction that vectorises;
   neither flag changes a value. */
#include "particles/particles.h"

#include <math.h>
#include <string.h>

/* Particles per block of the general sweep: positions and velocities of a
   block (2 x 6 KiB) stay in L1 between its kick and its drift. */
#define BLOCK 256

/* Particles per block of the one-pass kernel: loops of a fixed length
   (3 x LANES doubles), which GCC -O2 vectorises on every instruction set. */
#define LANES 32

/* The drag coefficient at velocity v: c1 + c2 |v|, or c1 alone when there
   is no quadratic drag (no square root, and c1 to the bit). */
static double drag_at(double c1, double c2, double vx, double vy, double vz)
{
    return c2 != 0 ? c1 + c2 * sqrt(vx * vx + vy * vy + vz * vz) : c1;
}

/* Acceleration of `count` particles from slot b from the global forces `f`
   (or none) and the local ones, gravity and drag:
   a = (f + m g - (c1 + c2 |v|) v) / m, scaled and added to `out` (a kick:
   v += h a) or assigned (derive). `f`, `v` (the velocity the drag sees) and
   `out` point at particle b; `v` may be `out` itself. */
static void accelerate(const tb_world *w, size_t b, size_t count, const double *f, const double *v, double *out,
                       double scale, int add)
{
    const double *m = w->particle_mass + b, *im = w->particle_inv_mass + b;
    const double gx = w->gravity[0], gy = w->gravity[1], gz = w->gravity[2];
    const double c1 = w->linear_drag, c2 = w->quadratic_drag;
    size_t i;
    for (i = 0; i < count; ++i) {
        const double vx = v[3 * i], vy = v[3 * i + 1], vz = v[3 * i + 2];
        const double drag = drag_at(c1, c2, vx, vy, vz);
        double fx = m[i] * gx - drag * vx, fy = m[i] * gy - drag * vy, fz = m[i] * gz - drag * vz;
        const double s = scale * im[i];
        if (f) {
            fx += f[3 * i];
            fy += f[3 * i + 1];
            fz += f[3 * i + 2];
        }
        if (add) {
            out[3 * i] += s * fx;
            out[3 * i + 1] += s * fy;
            out[3 * i + 2] += s * fz;
        } else {
            out[3 * i] = s * fx;
            out[3 * i + 1] = s * fy;
            out[3 * i + 2] = s * fz;
        }
    }
}

void tb__particle_acceleration(const tb_world *w, size_t s, const double v[3], double out[3])
{
    accelerate(w, s, 1, w->force_ready ? w->particle_force + 3 * s : NULL, v, out, 1, 0);
}

void tb__particle_derive(tb_world *w, const double *y, double *dy)
{
    const double *vel = y + w->off[TB__PARTICLE_VEL];
    memcpy(dy + w->off[TB__PARTICLE_POS], vel, 3 * w->particle_count * sizeof(double));
    accelerate(w, 0, w->particle_count, w->force_ready ? w->particle_force : NULL, vel,
               dy + w->off[TB__PARTICLE_VEL], 1, 0);
}

int tb__particle_velocity_dependent(const tb_world *w)
{
    return (w->particle_count && (w->linear_drag != 0 || w->quadratic_drag != 0)) || w->spring_damped > 0;
}

/* ------------------------------------------------- the general sweep -- */

void tb__particle_sweep_blocked(tb_world *w, const tb__split_op *ops, int n)
{
    double *pos = w->y + w->off[TB__PARTICLE_POS], *vel = w->y + w->off[TB__PARTICLE_VEL];
    const double *f = w->force_ready ? w->particle_force : NULL;
    const double *seen = w->kick_seen ? w->kick_seen + w->off[TB__PARTICLE_VEL] : vel;
    double start[3 * BLOCK], predicted[3 * BLOCK];
    size_t b, i;
    int k;
    for (b = 0; b < w->particle_count; b += BLOCK) {
        const size_t e = b + BLOCK < w->particle_count ? b + BLOCK : w->particle_count;
        memcpy(start, vel + 3 * b, 3 * (e - b) * sizeof(double));
        for (k = 0; k < n; ++k) {
            const double h = ops[k].h;
            if (ops[k].drift) {
                for (i = 3 * b; i < 3 * e; ++i)
                    pos[i] += h * vel[i];
            } else if (ops[k].predicted && tb__particle_velocity_dependent(w)) {
                /* 2 v - v_start: what tb__split_extrapolate computes */
                for (i = 0; i < 3 * (e - b); ++i)
                    predicted[i] = 2 * vel[3 * b + i] - start[i];
                accelerate(w, b, e - b, f ? f + 3 * b : NULL, predicted, vel + 3 * b, h, 1);
            } else {
                accelerate(w, b, e - b, f ? f + 3 * b : NULL, seen + 3 * b, vel + 3 * b, h, 1);
            }
        }
    }
}

/* ---------------------------------------------- the one-pass kernel -- */

/* The common case of a sweep: only the local forces (no springs or
   callbacks), seen at the velocity being kicked, and the ops a kick, a kick
   and a drift (symplectic Euler), or those and Verlet's closing kick at the
   predicted velocity 2 v - v_start. One pass does them all on each
   particle while it is in registers: the same arithmetic as the general
   sweep, in the same order, so the same bits
   (test_particle_step.one_pass_gives_the_general_bits), with no state copy
   and no second pass. Asked (w->damping_sums), the same pass sums the
   drag's power at the velocities it starts from and ends with, as
   tb__damping_power would (diagnostics.c), so the step's damping work
   costs no passes of its own. Streaming 10^6 particles with linear drag it
   runs within about 1.2 times the memory bandwidth of its four arrays
   (bench/particles.c prints both ratios). */
typedef struct one_pass {
    double hk, hd, hc;     /* s: the kick, the drift, the closing kick */
    double g[3];           /* m/s^2 */
    double c1, c2;         /* N s/m, N s^2/m^2 */
} one_pass;

/* The drag's power on a free particle at velocity u, less the sign:
   (c1 + c2 |u|) |u|^2, or c1 |u|^2 without quadratic drag (the same
   number for any finite |u|, without the square root). */
TB__LANE double drag_power(double c1, double c2, int quadratic, double ux, double uy, double uz)
{
    const double u2 = ux * ux + uy * uy + uz * uz;
    return (quadratic ? c1 + c2 * sqrt(u2) : c1) * u2;
}

/* The drag's power is summed in POWER_LANES partial sums, particle i into
   sum i % POWER_LANES, added up in order at the end: the one-pass kernel
   sums so in vectors within its pass, and tb__particle_drag_power in a
   plain loop, to the same bits
   (test_particle_step.split_steps_give_the_general_bits). */
#define POWER_LANES 8

TB__LANE double add_lanes(const double *lanes)
{
    double p = 0;
    int j;
    for (j = 0; j < POWER_LANES; ++j)
        p += lanes[j];
    return p;
}

double tb__particle_drag_power(const tb_world *w)
{
    const double *v = w->y + w->off[TB__PARTICLE_VEL], *im = w->particle_inv_mass;
    const int quadratic = w->quadratic_drag != 0;
    double lanes[POWER_LANES] = { 0 };
    size_t i;
    for (i = 0; i < w->particle_count; ++i)
        lanes[i % POWER_LANES] -= im[i] > 0 ? drag_power(w->linear_drag, w->quadratic_drag, quadratic, v[3 * i],
                                                         v[3 * i + 1], v[3 * i + 2])
                                            : 0;
    return add_lanes(lanes);
}

/* Particle i, its velocity and position in locals: the kick, the drift
   (ops >= 2) and the closing kick (ops == 3), whose drag sees 2 v - v_start
   when `predict`, else v; with `power`, the drag's power at the start and
   the end into *start and *end. The general sweep's arithmetic, operation
   for operation. Inlined into loops of LANES particles, which GCC
   vectorises across particles, with `quadratic`, `ops`, `predict` and
   `power` constants, so each case is a loop of its own without branches. */
TB__LANE void particle(const one_pass *k, int quadratic, int ops, int predict, int power, double *restrict x,
                       double *restrict v, const double *restrict mass, const double *restrict inv_mass, size_t i,
                       double *restrict start, double *restrict end)
{
    const double ux = v[3 * i], uy = v[3 * i + 1], uz = v[3 * i + 2], m = mass[i], im = inv_mass[i];
    const double gx = k->g[0], gy = k->g[1], gz = k->g[2], c1 = k->c1, c2 = k->c2;
    double d = quadratic ? c1 + c2 * sqrt(ux * ux + uy * uy + uz * uz) : c1, s = k->hk * im;
    double vx = ux + s * (m * gx - d * ux), vy = uy + s * (m * gy - d * uy), vz = uz + s * (m * gz - d * uz);
    if (ops >= 2) {
        x[3 * i] += k->hd * vx;
        x[3 * i + 1] += k->hd * vy;
        x[3 * i + 2] += k->hd * vz;
    }
    if (ops == 3) {
        const double px = predict ? 2 * vx - ux : vx, py = predict ? 2 * vy - uy : vy,
                     pz = predict ? 2 * vz - uz : vz;
        d = quadratic ? c1 + c2 * sqrt(px * px + py * py + pz * pz) : c1;
        s = k->hc * im;
        vx += s * (m * gx - d * px);
        vy += s * (m * gy - d * py);
        vz += s * (m * gz - d * pz);
    }
    v[3 * i] = vx;
    v[3 * i + 1] = vy;
    v[3 * i + 2] = vz;
    if (power) { /* pinned particles: none */
        *start = im > 0 ? drag_power(c1, c2, quadratic, ux, uy, uz) : 0;
        *end = im > 0 ? drag_power(c1, c2, quadratic, vx, vy, vz) : 0;
    }
}

/* Particles [0, n) in blocks of LANES (a loop of fixed length, which GCC
   -O2 vectorises) and the rest one by one. With `power` the powers are
   summed as tb__particle_drag_power sums them: sums[0] the start's,
   sums[1] the end's. */
TB__LANE void particles(const one_pass *in, int quadratic, int ops, int predict, int power, double *restrict x,
                        double *restrict v, const double *restrict m, const double *restrict im, size_t n,
                        double *sums)
{
    const one_pass k = *in; /* a local copy: no store to x or v can change it */
    double start[LANES], end[LANES], lanes0[POWER_LANES] = { 0 }, lanes1[POWER_LANES] = { 0 };
    size_t b, i, j;
    for (b = 0; b + LANES <= n; b += LANES) { /* b is a multiple of POWER_LANES */
        for (i = 0; i < LANES; ++i)
            particle(&k, quadratic, ops, predict, power, x, v, m, im, b + i, start + i, end + i);
        for (i = 0; power && i < LANES; i += POWER_LANES)
            for (j = 0; j < POWER_LANES; ++j) {
                lanes0[j] -= start[i + j];
                lanes1[j] -= end[i + j];
            }
    }
    for (i = b; i < n; ++i) {
        particle(&k, quadratic, ops, predict, power, x, v, m, im, i, start, end);
        if (power) {
            lanes0[i % POWER_LANES] -= start[0];
            lanes1[i % POWER_LANES] -= end[0];
        }
    }
    if (power)
        sums[0] = add_lanes(lanes0), sums[1] = add_lanes(lanes1);
}

/* ... with the constants of each case: `power` when the sums are asked. */
TB__LANE void particles_summing(const one_pass *k, int quadratic, int ops, int predict, double *restrict x,
                                double *restrict v, const double *restrict m, const double *restrict im, size_t n,
                                double *sums)
{
    if (sums)
        particles(k, quadratic, ops, predict, 1, x, v, m, im, n, sums);
    else
        particles(k, quadratic, ops, predict, 0, x, v, m, im, n, sums);
}

/* Quadratic drag is velocity-dependent: its closing kick always predicts. */
TB__LANE void one_pass_all(const one_pass *k, int ops, int predict, double *restrict x, double *restrict v,
                           const double *restrict m, const double *restrict im, size_t n, double *sums)
{
    const int quadratic = k->c2 != 0;
    if (ops == 3 && quadratic)
        particles_summing(k, 1, 3, 1, x, v, m, im, n, sums);
    else if (ops == 3 && predict)
        particles_summing(k, 0, 3, 1, x, v, m, im, n, sums);
    else if (ops == 3)
        particles_summing(k, 0, 3, 0, x, v, m, im, n, sums);
    else if (ops == 2 && quadratic)
        particles_summing(k, 1, 2, 0, x, v, m, im, n, sums);
    else if (ops == 2)
        particles_summing(k, 0, 2, 0, x, v, m, im, n, sums);
    else if (quadratic)
        particles_summing(k, 1, 1, 0, x, v, m, im, n, sums);
    else
        particles_summing(k, 0, 1, 0, x, v, m, im, n, sums);
}

#define ONE_PASS(isa, attr, isa_id)                                                                          \
    attr static void one_pass_##isa(const one_pass *k, int ops, int predict, double *restrict x,              \
                                    double *restrict v, const double *restrict m, const double *restrict im, \
                                    size_t n, double *sums)                                                  \
    {                                                                                                        \
        one_pass_all(k, ops, predict, x, v, m, im, n, sums);                                                 \
    }
TB__FOR_EACH_ISA(ONE_PASS)

int tb__particle_one_pass(tb_world *w, const tb__split_op *ops, int n, int isa)
{
    one_pass k;
    int c;
    if (w->force_ready || w->kick_seen || n < 1 || n > 3 || ops[0].drift || ops[0].predicted ||
        (n >= 2 && !ops[1].drift) || (n == 3 && (ops[2].drift || !ops[2].predicted)))
        return 0;
    k.hk = ops[0].h;
    k.hd = n >= 2 ? ops[1].h : 0;
    k.hc = n == 3 ? ops[2].h : 0;
    for (c = 0; c < 3; ++c)
        k.g[c] = w->gravity[c];
    k.c1 = w->linear_drag;
    k.c2 = w->quadratic_drag;
    TB__DISPATCH(isa, one_pass, (&k, n, tb__particle_velocity_dependent(w), w->y + w->off[TB__PARTICLE_POS],
                                 w->y + w->off[TB__PARTICLE_VEL], w->particle_mass, w->particle_inv_mass,
                                 w->particle_count, w->damping_sums));
    return 1;
}

void tb__particle_sweep(tb_world *w, const tb__split_op *ops, int n)
{
    if (!tb__particle_one_pass(w, ops, n, tb__isa()))
        tb__particle_sweep_blocked(w, ops, n);
}
