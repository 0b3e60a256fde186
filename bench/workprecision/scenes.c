/* scenes.c: the reference scenes of the work-precision benchmark and their
   truths. They are the Lua scripts of scenes/reference/ built in C (same
   numbers; the scripts document each truth). A truth is a closed form where
   one exists, else a converged reference run (reference()). */
#include "workprecision.h"
#include "pendulum.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The rotation by `angle` about the unit `axis`. */
static void qrot(const double axis[3], double angle, double q[4])
{
    const double s = sin(angle / 2);
    q[0] = cos(angle / 2), q[1] = s * axis[0], q[2] = s * axis[1], q[3] = s * axis[2];
}

static void spring(particle_system *p, int a, int b, const double anchor[3], double k, double c, double rest)
{
    spring_spec *s;
    p->spring = realloc(p->spring, (p->springs + 1) * sizeof *p->spring);
    if (!p->spring) {
        fprintf(stderr, "bench_workprecision: out of memory\n");
        exit(EXIT_FAILURE);
    }
    s = &p->spring[p->springs++];
    s->a = a, s->b = b, s->k = k, s->c = c, s->rest = rest;
    memcpy(s->anchor, anchor ? anchor : (const double[3]){ 0, 0, 0 }, sizeof s->anchor);
}

static size_t particle(particle_system *p, double x, double y, double z, double mass)
{
    const size_t i = p->n++;
    if (i >= MAX_PARTICLES) {
        fprintf(stderr, "bench_workprecision: more than %d particles\n", MAX_PARTICLES);
        exit(EXIT_FAILURE);
    }
    p->x0[3 * i] = x, p->x0[3 * i + 1] = y, p->x0[3 * i + 2] = z;
    p->mass[i] = mass;
    return i;
}

/* The hanging oscillator of scenes/oscillator.lua: m = 0.5 kg on k = 50 N/m
   (w = 10 rad/s) with rest length 1 m from an anchor at the origin, pulled
   A = 0.2 m below equilibrium. With damping c the motion about the
   equilibrium z_eq = -(1 + m g / k) is u(t) = e^(-z w t) (A cos(wd t) +
   z w A / wd sin(wd t)), wd = w sqrt(1 - z^2), z = c / (2 sqrt(k m)). */
#define OSC_K 50.0
#define OSC_M 0.5
#define OSC_A 0.2
static void oscillator(scene *s, double damping)
{
    const double g = 9.81, w = sqrt(OSC_K / OSC_M), zeta = damping / (2 * sqrt(OSC_K * OSC_M));
    const double wd = w * sqrt(1 - zeta * zeta), zeq = -(1 + OSC_M * g / OSC_K), T = s->duration;
    particle_system *p = &s->ps;
    particle(p, 0, 0, zeq - OSC_A, OSC_M);
    spring(p, 0, -1, NULL, OSC_K, damping, 1);
    p->gravity[2] = -g;
    s->kind = PARTICLES;
    s->ode = 1;
    s->scale = OSC_A;
    s->final[2] = zeq - exp(-zeta * w * T) * OSC_A * (cos(wd * T) + zeta * w / wd * sin(wd * T));
}

/* Kepler orbit, GM = 1 m^3/s^2, semi-major axis a = 1 m, eccentricity 0.5,
   from periapsis r_p = a (1 - e) = 0.5 m at v_p = sqrt(GM (1 + e) / r_p) =
   sqrt 3 m/s. Period 2 pi sqrt(a^3 / GM) = 2 pi s; after three whole
   periods the exact position is the start again. */
static void kepler(scene *s)
{
    particle_system *p = &s->ps;
    particle(p, 0.5, 0, 0, 1);
    p->v0[1] = sqrt(3.0);
    p->gm = 1;
    s->kind = PARTICLES;
    s->ode = 1;
    s->scale = 1;
    s->final[0] = 0.5;
}

/* A tracer 1 m from the axis of a rigid vortex turning once every 4 s:
   after 8 s (two turns) it is exactly where it started. */
static void vortex(scene *s)
{
    const double w = 2 * acos(-1.0) / 4;
    s->kind = TRACER;
    s->scale = 1;
    s->tracer_x0[0] = 1;
    s->vortex[2] = w;
    s->final[0] = cos(w * s->duration);
    s->final[1] = sin(w * s->duration);
}

/* A 1 kg ball dropped from rest through air with quadratic drag
   c = 0.1 N s^2/m^2: terminal speed vt = sqrt(m g / c) = 9.90 m/s, and
   z(t) = -(vt^2 / g) ln cosh(g t / vt). Errors are per metre fallen by T. */
static void projectile(scene *s)
{
    const double g = 9.81, m = 1, c = 0.1, vt = sqrt(m * g / c), T = s->duration;
    particle_system *p = &s->ps;
    particle(p, 0, 0, 0, m);
    p->gravity[2] = -g;
    p->quadratic_drag = c;
    s->kind = PARTICLES;
    s->ode = 1;
    s->final[2] = -(vt * vt / g) * log(cosh(g * T / vt));
    s->scale = -s->final[2];
}

/* The rope of scenes/rope.lua: 20 beads of 10 g, 5 cm apart, joined by
   springs k = 2000 N/m (damping 0.05 N s/m), the first tied to an anchor
   2 m up, released horizontally under gravity. The fastest mode is near
   sqrt(4 k / m) = 894 rad/s: split methods need h < 2.2 ms, rk4 h < 3.2 ms. */
static void chain(scene *s)
{
    static const double anchor[3] = { 0, 0, 2 };
    particle_system *p = &s->ps;
    int i;
    for (i = 0; i < 20; ++i) {
        particle(p, 0.05 * (i + 1), 0, 2, 0.01);
        spring(p, i, i - 1, anchor, 2000, 0.05, 0.05);
    }
    p->gravity[2] = -9.81;
    s->kind = PARTICLES;
    s->ode = 1;
    s->scale = 1;
}

/* A damped chain of unequal beads near its stability limits: 20 beads of
   3 to 17 g, 5 cm apart along x, on springs of 1000 to 3000 N/m (rest 5
   cm), each damped at ratio 0.3 with its reduced mass (c = 0.6 sqrt(k mu)),
   the first tied to an anchor 2 m up, released under gravity (the damped
   chain of test_stability.advisor_predicts_damped_chains, hung up). Its
   stiffest mode, 1267 rad/s, is more damped than each spring (the
   advisor sees 0.41), so each method's limit is its damped one: symplectic
   Euler about 1.1 ms, Verlet 1.4 ms, RK4 2.1 ms, and explicit Euler none
   (the transverse modes are undamped). The chart marks the advisor's
   limits (write_meta). */
static void damped_chain(scene *s)
{
    static const double anchor[3] = { 0, 0, 2 };
    particle_system *p = &s->ps;
    int i;
    for (i = 0; i < 20; ++i) {
        const double m = 0.01 * (1 + 0.7 * sin(1.9 * i)), k = 2000 * (1 + 0.5 * cos(2.7 * i));
        const double previous = i > 0 ? p->mass[i - 1] : 0, mu = previous > 0 ? m * previous / (m + previous) : m;
        particle(p, 0.05 * (i + 1), 0, 2, m);
        spring(p, i, i - 1, anchor, k, 2 * 0.3 * sqrt(k * mu), 0.05);
    }
    p->gravity[2] = -9.81;
    s->kind = PARTICLES;
    s->ode = 1;
    s->scale = 1;
    s->limits = 1;
}

/* A small cloth: 8 x 8 particles, 0.5 m square, 0.1 kg, flat 1.5 m up,
   two corners pinned; structural (60 N/m), shear (20 N/m) and bend (5 N/m) springs with
   damping 0.02 N s/m, as in scenes/cloth.lua. Gershgorin bounds the fastest
   mode by sqrt(2 * 340 N/m / 1.56 g) = 660 rad/s. */
#define CLOTH_N 8
static void cloth(scene *s)
{
    /* row step, column step, stiffness (N/m): structural, shear, bend */
    static const int joins[6][3] = { { 0, 1, 60 }, { 1, 0, 60 }, { 1, 1, 20 },
                                     { 1, -1, 20 }, { 0, 2, 5 }, { 2, 0, 5 } };
    particle_system *p = &s->ps;
    const double size = 0.5, spacing = size / (CLOTH_N - 1), m = 0.1 / (CLOTH_N * CLOTH_N);
    int r, c, j;
    for (r = 0; r < CLOTH_N; ++r)
        for (c = 0; c < CLOTH_N; ++c) {
            const size_t i = particle(p, c * spacing, r * spacing, 1.5, m);
            p->pinned[i] = r == 0 && (c == 0 || c == CLOTH_N - 1);
        }
    for (r = 0; r < CLOTH_N; ++r)
        for (c = 0; c < CLOTH_N; ++c)
            for (j = 0; j < 6; ++j) {
                const int r2 = r + joins[j][0], c2 = c + joins[j][1];
                if (r2 < CLOTH_N && c2 >= 0 && c2 < CLOTH_N)
                    spring(p, r * CLOTH_N + c, r2 * CLOTH_N + c2, NULL, joins[j][2], 0.02,
                           spacing * sqrt((double)(joins[j][0] * joins[j][0] + joins[j][1] * joins[j][1])));
            }
    p->gravity[2] = -9.81;
    s->kind = PARTICLES;
    s->ode = 1;
    s->scale = size;
}

/* The intermediate-axis (Dzhanibekov) flip of scenes/reference/flip.lua:
   I = diag(1, 2, 3) kg m^2, w0 = (0.01, 5, 0.01) rad/s, 20 s (the truth: a
   converged reference). */
static void flip(scene *s)
{
    s->kind = BODY;
    s->ode = 1;
    s->inertia[0] = 1, s->inertia[1] = 2, s->inertia[2] = 3;
    s->omega0[0] = 0.01, s->omega0[1] = 5, s->omega0[2] = 0.01;
}

/* Torque-free symmetric top, I = diag(1, 1, 1.8) kg m^2, w0 = (0.6, -0.2, 4)
   rad/s. With L = I w0 fixed in the world and c = (1/I3 - 1/I1) L3, the
   exact orientation is q(t) = rot(L, |L| t / I1) q0 rot(e3, c t): in the
   body frame w turns about e3 at -c = (I3 - I1) / I1 w3 = 3.2 rad/s. */
static void top(scene *s)
{
    const double e3[3] = { 0, 0, 1 }, q0[4] = { 1, 0, 0, 0 }, T = s->duration;
    double L[3], axis[3], a[4], b[4], qa[4], l;
    int k;
    s->kind = BODY;
    s->ode = 1;
    s->inertia[0] = 1, s->inertia[1] = 1, s->inertia[2] = 1.8;
    s->omega0[0] = 0.6, s->omega0[1] = -0.2, s->omega0[2] = 4;
    for (k = 0; k < 3; ++k)
        L[k] = s->inertia[k] * s->omega0[k];
    l = norm3(L);
    for (k = 0; k < 3; ++k)
        axis[k] = L[k] / l;
    qrot(axis, l * T / s->inertia[0], a);
    qrot(e3, (1 / s->inertia[2] - 1 / s->inertia[0]) * L[2] * T, b);
    qmul(a, q0, qa);
    qmul(qa, b, s->final);
}

/* The 170-degree pendulum of scenes/reference/pendulum.lua (and of
   test_joints and bench_joints): a 5 cm, 1 kg sphere 1 m from a hinge.
   Its period is P = 4 sqrt(I_p / (m g l)) K(sin(theta0 / 2)), I_p =
   2/5 m r^2 + m l^2; after 2 1/4 periods it passes the bottom, at its
   fastest, so the position error there is the phase error times the
   speed (at a turning point it would be of the phase error squared).
   Its floor is 1e-10, not rounding's 1e-12: every step ends with the
   joints' projection, which stops within 1e-14 m of the joint, and 10^4
   steps of that add up to some 1e-11 of phase (rk4 levels off at 2.5e-11
   from 9600 steps on, where dopri5, projected once an outer step, goes
   on to 1.7e-12). */
static void pendulum(scene *s)
{
    const double g = 9.81, start = 170 * acos(-1.0) / 180;
    const double period = ref_pendulum_period(PENDULUM_RADIUS, PENDULUM_MASS, PENDULUM_LENGTH, g, start);
    s->kind = PENDULUM;
    s->ode = 1;
    s->scale = PENDULUM_LENGTH;
    s->pendulum_start = start;
    s->gravity = g;
    s->duration = 2.25 * period;
    s->final[2] = -PENDULUM_LENGTH;
    s->floor = 1e-10;
}

/* The scenes' names, titles and step ranges; each scene's function above
   adds its content and its truth. */
int make_scenes(scene *scenes)
{
    int count = 0;

    memset(scenes, 0, SCENE_COUNT * sizeof *scenes);
    scenes[count].name = "oscillator";
    scenes[count].short_title = "harmonic oscillator";
    scenes[count].title = "harmonic oscillator: w = 10 rad/s, amplitude A = 0.2 m, 10 s";
    scenes[count].error_label = "position error / A at t = 10 s";
    scenes[count].truth = "closed form z(t) = z_eq - A cos(w t)";
    scenes[count].duration = 10, scenes[count].coarse = 40;
    oscillator(&scenes[count++], 0);

    scenes[count].name = "damped";
    scenes[count].short_title = "damped oscillator";
    scenes[count].title = "damped oscillator: w = 10 rad/s, damping ratio 0.05, A = 0.2 m, 4 s";
    scenes[count].error_label = "position error / A at t = 4 s";
    scenes[count].truth = "closed form (underdamped)";
    scenes[count].duration = 4, scenes[count].coarse = 16;
    oscillator(&scenes[count++], 0.1 * sqrt(OSC_K * OSC_M));

    scenes[count].name = "kepler";
    scenes[count].short_title = "Kepler orbit, e = 0.5";
    scenes[count].title = "Kepler orbit: eccentricity 0.5, a = 1 m, 3 periods from periapsis "
                          "(there symplectic Euler's O(h) error cancels)";
    scenes[count].error_label = "position error / a after 3 periods";
    scenes[count].truth = "closed form: after whole periods the orbit is back at periapsis";
    scenes[count].duration = 6 * acos(-1.0), scenes[count].coarse = 48;
    kepler(&scenes[count++]);

    scenes[count].name = "vortex";
    scenes[count].short_title = "tracer in a vortex";
    scenes[count].title = "tracer in a rigid vortex: 1 m from the axis, two turns in 8 s";
    scenes[count].error_label = "position error / radius at t = 8 s";
    scenes[count].truth = "closed form: a rotation by w t";
    scenes[count].duration = 8, scenes[count].coarse = 4;
    vortex(&scenes[count++]);

    scenes[count].name = "projectile";
    scenes[count].short_title = "fall with quadratic drag";
    scenes[count].title = "fall with quadratic drag: terminal speed 9.9 m/s, from rest, 3 s";
    scenes[count].error_label = "position error / distance fallen at t = 3 s";
    scenes[count].truth = "closed form z(t) = -(vt^2/g) ln cosh(g t / vt)";
    scenes[count].duration = 3, scenes[count].coarse = 3;
    projectile(&scenes[count++]);

    scenes[count].name = "chain";
    scenes[count].short_title = "stiff chain, 20 beads";
    scenes[count].title = "stiff chain: 20 beads, k = 2000 N/m, fastest mode ~894 rad/s, 1 s";
    scenes[count].error_label = "largest bead position error / 1 m at t = 1 s";
    scenes[count].truth = "converged reference: rk4 at h = 1/2^19 s";
    scenes[count].duration = 1, scenes[count].coarse = 250, scenes[count].reference_steps = 1L << 19;
    scenes[count].stiff = 1;
    chain(&scenes[count++]);

    scenes[count].name = "damped_chain";
    scenes[count].short_title = "damped chain, stability limits";
    scenes[count].title = "damped chain: 20 beads of 3-17 g, k = 1000-3000 N/m, damping ratio 0.3, 1 s; "
                          "dotted: stability limits";
    scenes[count].error_label = "largest bead position error / 1 m at t = 1 s";
    scenes[count].truth = "converged reference: rk4 at h = 1/2^19 s";
    scenes[count].duration = 1, scenes[count].coarse = 250, scenes[count].reference_steps = 1L << 19;
    scenes[count].stiff = 1;
    damped_chain(&scenes[count++]);

    scenes[count].name = "cloth";
    scenes[count].short_title = "cloth patch, 8 x 8";
    scenes[count].title = "cloth patch: 8 x 8 particles, 0.5 m, 306 springs, two corners pinned, 1 s";
    scenes[count].error_label = "largest particle position error / 0.5 m at t = 1 s";
    scenes[count].truth = "converged reference: rk4 at h = 1/2^17 s";
    scenes[count].duration = 1, scenes[count].coarse = 200, scenes[count].reference_steps = 1L << 17;
    scenes[count].stiff = 1;
    cloth(&scenes[count++]);

    scenes[count].name = "flip";
    scenes[count].short_title = "intermediate-axis flip";
    scenes[count].title = "intermediate-axis flip: I = diag(1, 2, 3) kg m^2, w0 = (0.01, 5, 0.01) rad/s, 20 s";
    scenes[count].error_label = "orientation error at t = 20 s (rad)";
    scenes[count].truth = "converged reference: rk4 at h = 20/2^18 s";
    scenes[count].duration = 20, scenes[count].coarse = 40, scenes[count].reference_steps = 1L << 18;
    flip(&scenes[count++]);

    scenes[count].name = "top";
    scenes[count].short_title = "torque-free symmetric top";
    scenes[count].title = "torque-free symmetric top: I = diag(1, 1, 1.8) kg m^2, w0 = (0.6, -0.2, 4) rad/s, 10 s";
    scenes[count].error_label = "orientation error at t = 10 s (rad)";
    scenes[count].truth = "closed form: q(t) = rot(L, |L| t / I1) q0 rot(e3, (1/I3 - 1/I1) L3 t)";
    scenes[count].duration = 10, scenes[count].coarse = 20;
    top(&scenes[count++]);

    scenes[count].name = "pendulum";
    scenes[count].short_title = "pendulum, 170 degrees";
    scenes[count].title = "pendulum on a hinge: 5 cm, 1 kg sphere 1 m from the pivot, released at 170 degrees, "
                          "2 1/4 periods (11.0 s)";
    scenes[count].error_label = "position error / 1 m at the bottom after 2 1/4 periods";
    scenes[count].truth = "closed form: the period 4 sqrt(I_p / (m g l)) K(sin(theta0 / 2))";
    scenes[count].coarse = 150;
    pendulum(&scenes[count++]);

    return count;
}

void free_scenes(scene *scenes, int count)
{
    int i;
    for (i = 0; i < count; ++i)
        free(scenes[i].ps.spring);
}

/* The truth of a scene without a closed form: tumble's rk4 at
   reference_steps, checked against rk4 at half as many steps. */
void reference(scene *s)
{
    const long steps = s->reference_steps;
    const double t0 = seconds();
    double half[3 * MAX_PARTICLES], t;
    long done, done_half = 0;
    timed_run(s, &SERIES[RK4], s->duration / (double)steps, steps, 0, &done, s->final, NULL, NULL);
    if (done == steps)
        timed_run(s, &SERIES[RK4], s->duration / (double)(steps / 2), steps / 2, 0, &done_half, half, NULL, NULL);
    if (done != steps || done_half != steps / 2) {
        fprintf(stderr, "bench_workprecision: the %s reference run failed\n", s->name);
        exit(EXIT_FAILURE);
    }
    s->reference_gap = error_of(s, half, s->final);
    t = seconds() - t0;
    fprintf(stderr, "  reference %s: rk4 at %ld steps vs %ld: gap %.2e (%.1f s)\n", s->name, s->reference_steps,
            s->reference_steps / 2, s->reference_gap, t);
}
