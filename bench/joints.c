/* joints.c: joints beside ODE, accuracy and cost.

   Part 1, the pendulum of test_joints (a 5 cm, 1 kg sphere 1 m from a
   hinge, released at 170 degrees) at 60 Hz: the period against the
   closed form 4 sqrt(I_p / (m g l)) K(sin(theta0 / 2)) for tumble's
   methods and for ODE's dWorldStep and dWorldQuickStep(20), and the rod's
   length error.

   Part 2, a chain of 100 ball-jointed links (spheres of 1 kg, 2 cm, 10 cm
   apart) with an end weight 1000 times heavier, hanging still and
   released from the horizontal, at 60 and 240 Hz, and with a 100 times
   heavier end released at 60 Hz: the largest joint gap
   over 10 s, and microseconds per step (the mean over the steps) and per
   joint, tumble's default method beside dWorldStep and QuickStep(20).
   Issue 19: ODE holds the chain only at 240 Hz (gap 2e-4 m), at 2.6 to
   3.0 us per joint with QuickStep(20) and about 30 us with dWorldStep;
   tumble should hold it at 60 Hz with every gap under 1 mm. Where a step
   is too long for the links' whip, tumble takes it again in halves
   (step.c): the line says how many steps were (tb_work.rejected) and
   the substeps taken in all, and the mean step's time counts them.

   Part 3, ragdolls (reference/ragdoll.h: 13 capsules, 5 ball joints with
   cones and twist limits, 6 hinges with stops) dropped in a pile on the
   plane, 4 to a layer, 3 and 8 of them, 6 s at 60 Hz: the mean step,
   ns per joint per step, the worst joint error at any step (tumble: its
   rows' largest, m or the cosine of axes that should be square; ODE: the
   distance between its anchors), the kinetic energy at the end (jitter:
   at rest it is 0), the deepest a capsule went into the plane, and for
   tumble the bodies asleep at the end. ODE (ode_ragdolls) with
   QuickStep(20) and dWorldStep; its ball joints have no cone or twist
   limits. Issue 19: a pile of 20, at least 10 times faster than QuickStep
   per joint; tumble's projection over a pile's envelope took more than
   14 minutes for the 20 (docs/joints.md, "Known limits"). */
#define _POSIX_C_SOURCE 200809L
#define BENCH_NAME "bench_joints"

#include "bench.h"
#include "tumble.h"

#include <ode/ode.h>

#include "ode_contacts.h"
#include "pendulum.h"
#include "ragdoll.h"

static const double G = 9.81, PI = 3.14159265358979323846;

/* ---- part 1 ------------------------------------------------------------------ */

#define SWING_SECONDS 20 /* three periods and more */
#define SWING_MOST 4800  /* steps: 20 s at 240 Hz */

static void tumble_swing(const char *method, double start, double h, int steps, double *angle, double *rod,
                         double *us)
{
    tb_world_def def = tb_default_world_def();
    tb_body_def bd = tb_default_body_def();
    tb_joint_def jd = tb_default_joint_def();
    tb_world *w;
    tb_body_id body;
    double t0;
    int s;
    def.gravity[0] = def.gravity[1] = 0, def.gravity[2] = -G;
    check(tb_world_create(&def, &w, NULL, 0), NULL, "world");
    check(tb_world_set_integrator(w, method), w, "integrator");
    check(tb_mass_sphere(1 / (4.0 / 3 * PI * 0.05 * 0.05 * 0.05), 0.05, &bd.mass, NULL), w, "mass");
    bd.position[0] = sin(start), bd.position[2] = -cos(start);
    check(tb_world_add_body(w, &bd, &body), w, "body");
    jd.type = TB_JOINT_HINGE, jd.a = body, jd.axis[0] = 0, jd.axis[1] = 1, jd.axis[2] = 0;
    check(tb_world_add_joint(w, &jd, NULL), w, "joint");
    *rod = 0;
    t0 = seconds();
    for (s = 0; s < steps; ++s) {
        double x[3];
        check(tb_world_step(w, h), w, "step");
        tb_body_position(w, body, x);
        angle[s] = atan2(x[0], -x[2]);
        *rod = fmax(*rod, fabs(norm3(x) - 1));
    }
    *us = 1e6 * (seconds() - t0) / steps;
    tb_world_destroy(w);
}

static void ode_swing(int quick, double start, double h, int steps, double *angle, double *rod, double *us)
{
    dWorldID world;
    dBodyID body;
    dJointID hinge;
    dMass mass;
    double t0;
    int s;
    dInitODE2(0);
    world = dWorldCreate();
    dWorldSetGravity(world, 0, 0, -G);
    dWorldSetQuickStepNumIterations(world, 20);
    body = dBodyCreate(world);
    dMassSetSphereTotal(&mass, 1, 0.05);
    dBodySetMass(body, &mass);
    dBodySetPosition(body, sin(start), 0, -cos(start));
    hinge = dJointCreateHinge(world, 0);
    dJointAttach(hinge, body, 0);
    dJointSetHingeAnchor(hinge, 0, 0, 0);
    dJointSetHingeAxis(hinge, 0, 1, 0);
    *rod = 0;
    t0 = seconds();
    for (s = 0; s < steps; ++s) {
        const dReal *x;
        if (quick)
            dWorldQuickStep(world, h);
        else
            dWorldStep(world, h);
        x = dBodyGetPosition(body);
        angle[s] = atan2(x[0], -x[2]);
        *rod = fmax(*rod, fabs(sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) - 1));
    }
    *us = 1e6 * (seconds() - t0) / steps;
    dWorldDestroy(world);
    dCloseODE();
}

/* The same pendulum by rk4 in its own coordinate, the angle (theta'' =
   -(m g l / I_p) sin theta, as a joint-coordinate engine steps it): what
   the method itself gives, beside what tumble's rk4 gives in the bodies'
   coordinates */
static void angle_rk4(double start, double h, int steps, double *angle)
{
    const double rate = G / (0.4 * 0.05 * 0.05 + 1); /* m g l / I_p, m = l = 1 */
    double a = start, v = 0;
    int s, k;
    for (s = 0; s < steps; ++s) {
        double da[4], dv[4];
        for (k = 0; k < 4; ++k) {
            const double f = k == 0 ? 0 : k == 3 ? h : h / 2;
            const double at = k ? a + f * da[k - 1] : a, vt = k ? v + f * dv[k - 1] : v;
            da[k] = vt;
            dv[k] = -rate * sin(at);
        }
        a += h / 6 * (da[0] + 2 * da[1] + 2 * da[2] + da[3]);
        v += h / 6 * (dv[0] + 2 * dv[1] + 2 * dv[2] + dv[3]);
        angle[s] = a;
    }
}

static void pendulum(void)
{
    static double angle[SWING_MOST];
    const char *methods[] = { "verlet", "symplectic_euler", "rk4", "dopri5" };
    const double start = 170 * PI / 180, rates[2] = { 60, 240 };
    const double closed = ref_pendulum_period(0.05, 1, 1, G, start);
    double rod, us, period;
    int m, r;
    printf("pendulum  170 degrees, 1 m, closed-form period %.9f s (target: the default within 1e-3 at 60 Hz)\n",
           closed);
    for (r = 0; r < 2; ++r) {
        const double h = 1 / rates[r];
        const int steps = (int)(SWING_SECONDS * rates[r]);
        for (m = 0; m < 4; ++m) {
            tumble_swing(methods[m], start, h, steps, angle, &rod, &us);
            period = ref_crossings_period(angle, steps, h);
            printf("pendulum  %3.0f Hz tumble %-16s period %+.3e, rod length within %.1e m, %.2f us/step\n",
                   rates[r], methods[m], (period - closed) / closed, rod, us);
        }
        for (m = 0; m < 2; ++m) {
            ode_swing(m, start, h, steps, angle, &rod, &us);
            period = ref_crossings_period(angle, steps, h);
            printf("pendulum  %3.0f Hz ODE %-19s period %+.3e, rod length within %.1e m, %.2f us/step\n", rates[r],
                   m ? "QuickStep(20)" : "dWorldStep", (period - closed) / closed, rod, us);
        }
        angle_rk4(start, h, steps, angle);
        period = ref_crossings_period(angle, steps, h);
        printf("pendulum  %3.0f Hz rk4 on the angle alone  period %+.3e (the method in joint coordinates)\n",
               rates[r], (period - closed) / closed);
    }
}

/* ---- part 2 ------------------------------------------------------------------ */

#define LINKS 100
#define CHAIN_SECONDS 10

typedef struct chain_run {
    double gap;      /* m, the largest joint gap over the run (Inf: not finite) */
    double us;       /* median microseconds a step */
    int survived;    /* steps before a gap past 1 m or a refused step */
    long halved;     /* tumble: steps (or halves) taken again in halves (tb_work.rejected) */
    long substeps;   /* tumble: the steps those made */
} chain_run;

/* A step's largest gap into the run; 0 once the chain is lost */
static int note(chain_run *run, double gap, int s)
{
    run->gap = fmax(run->gap, gap);
    if (!(gap < 1))
        return 0;
    run->survived = s + 1;
    return 1;
}

/* The mean of the steps' times, in microseconds (a mean, not a median:
   the steps tumble takes again in halves are a fifth of a released
   chain's, and their cost is the chain's) */
static void finish(chain_run *run, const double *times)
{
    double sum = 0;
    int s;
    for (s = 0; s < run->survived; ++s)
        sum += times[s];
    run->us = run->survived ? 1e6 * sum / run->survived : NAN;
}

static void link_position(int i, int across, double x[3])
{
    x[0] = across ? (i + 1) * 0.1 : 0, x[1] = 0, x[2] = across ? 0 : -(i + 1) * 0.1;
}

static chain_run tumble_chain(double hz, int across, double end)
{
    tb_world_def def = tb_default_world_def();
    tb_world *w;
    tb_body_id body[LINKS];
    static double times[CHAIN_SECONDS * 240];
    const int steps = (int)(CHAIN_SECONDS * hz);
    chain_run run = { 0, 0, 0, 0, 0 };
    int i, s;
    def.gravity[0] = def.gravity[1] = 0, def.gravity[2] = -G;
    check(tb_world_create(&def, &w, NULL, 0), NULL, "world");
    for (i = 0; i < LINKS; ++i) {
        tb_body_def bd = tb_default_body_def();
        tb_joint_def jd = tb_default_joint_def();
        const double m = i == LINKS - 1 ? end : 1;
        check(tb_mass_sphere(m / (4.0 / 3 * PI * 8e-6), 0.02, &bd.mass, NULL), w, "mass");
        link_position(i, across, bd.position);
        check(tb_world_add_body(w, &bd, &body[i]), w, "body");
        jd.a = body[i];
        if (i)
            jd.b = body[i - 1];
        link_position(i - 1, across, jd.anchor);
        check(tb_world_add_joint(w, &jd, NULL), w, "joint");
    }
    for (s = 0; s < steps; ++s) {
        const double t0 = seconds();
        double gap = 0;
        if (tb_world_step(w, 1 / hz) != TB_OK)
            break;
        times[s] = seconds() - t0;
        for (i = 0; i < (int)tb_world_joint_count(w); ++i) {
            double e;
            tb_joint_error(w, tb_world_joint_at(w, (size_t)i), &e);
            gap = isfinite(e) ? fmax(gap, e) : INFINITY;
        }
        if (!note(&run, gap, s))
            break;
    }
    finish(&run, times);
    run.halved = (long)tb_world_work(w).rejected;
    run.substeps = (long)tb_world_work(w).substeps;
    tb_world_destroy(w);
    return run;
}

static chain_run ode_chain(double hz, int across, int quick, double end)
{
    dWorldID world;
    dBodyID body[LINKS];
    dJointID joint[LINKS];
    dMass mass;
    static double times[CHAIN_SECONDS * 240];
    const int steps = (int)(CHAIN_SECONDS * hz);
    chain_run run = { 0, 0, 0, 0, 0 };
    int i, s;
    dInitODE2(0);
    world = dWorldCreate();
    dWorldSetGravity(world, 0, 0, -G);
    dWorldSetQuickStepNumIterations(world, 20);
    for (i = 0; i < LINKS; ++i) {
        double x[3], a[3];
        body[i] = dBodyCreate(world);
        dMassSetSphereTotal(&mass, i == LINKS - 1 ? end : 1, 0.02);
        dBodySetMass(body[i], &mass);
        link_position(i, across, x);
        dBodySetPosition(body[i], x[0], x[1], x[2]);
        joint[i] = dJointCreateBall(world, 0);
        dJointAttach(joint[i], body[i], i ? body[i - 1] : 0);
        link_position(i - 1, across, a);
        dJointSetBallAnchor(joint[i], a[0], a[1], a[2]);
    }
    for (s = 0; s < steps; ++s) {
        const double t0 = seconds();
        double gap = 0;
        if (quick)
            dWorldQuickStep(world, 1 / hz);
        else
            dWorldStep(world, 1 / hz);
        times[s] = seconds() - t0;
        for (i = 0; i < LINKS; ++i) {
            dVector3 p1, p2;
            double d;
            dJointGetBallAnchor(joint[i], p1);
            dJointGetBallAnchor2(joint[i], p2);
            d = sqrt((p1[0] - p2[0]) * (p1[0] - p2[0]) + (p1[1] - p2[1]) * (p1[1] - p2[1]) +
                     (p1[2] - p2[2]) * (p1[2] - p2[2]));
            gap = isfinite(d) ? fmax(gap, d) : INFINITY;
        }
        if (!note(&run, gap, s))
            break;
    }
    finish(&run, times);
    dWorldDestroy(world);
    dCloseODE();
    return run;
}

static void print_chain(const char *who, double hz, int across, chain_run r)
{
    const int steps = (int)(CHAIN_SECONDS * hz);
    char halved[64] = "";
    if (r.halved)
        snprintf(halved, sizeof halved, " (%ld halved: %ld substeps)", r.halved, r.substeps);
    printf("chain     %-22s %3.0f Hz %-10s %s gap %.1e m%s, %.1f us/step, %.3f us/joint%s\n", who, hz,
           across ? "released" : "hanging", r.survived == steps ? "held:" : "LOST:", r.gap,
           r.survived == steps ? "" : " (past 1 m)", r.us, r.us / LINKS, halved);
}

static void chain(void)
{
    const double rates[2] = { 60, 240 };
    int k, across;
    printf("chain     %d ball-jointed links of 1 kg, 10 cm apart, the end 1000 kg, %d s (target: held at 60 Hz, "
           "every gap under 1 mm)\n", LINKS, CHAIN_SECONDS);
    for (across = 0; across < 2; ++across)
        for (k = 0; k < 2; ++k) {
            print_chain("tumble verlet", rates[k], across, tumble_chain(rates[k], across, 1000));
            print_chain("ODE dWorldStep", rates[k], across, ode_chain(rates[k], across, 0, 1000));
            print_chain("ODE QuickStep(20)", rates[k], across, ode_chain(rates[k], across, 1, 1000));
        }
    printf("chain     the same with the end 100 kg, released at 60 Hz\n");
    print_chain("tumble verlet", 60, 1, tumble_chain(60, 1, 100));
    print_chain("ODE dWorldStep", 60, 1, ode_chain(60, 1, 0, 100));
    print_chain("ODE QuickStep(20)", 60, 1, ode_chain(60, 1, 1, 100));
}

/* ---- part 3 ------------------------------------------------------------------ */

#define PILE_SECONDS 6

typedef struct pile_run {
    double us, gap, kinetic, deepest;
    int asleep, bodies, finite;
} pile_run;

static pile_run tumble_pile(int count)
{
    const double h = 1.0 / 60;
    tb_world_def def = tb_default_world_def();
    tb_shape_def ground = tb_default_shape_def();
    tb_world *w;
    tb_body_id *body = malloc((size_t)count * REF_RAGDOLL_BONES * sizeof *body);
    ref_bone *bone = malloc((size_t)count * REF_RAGDOLL_BONES * sizeof *bone);
    pile_run run = { 0, 0, 0, 0, 0, 0, 1 };
    double sum = 0;
    int i, k, s;
    if (!body || !bone) {
        fprintf(stderr, "bench_joints: out of memory\n");
        exit(1);
    }
    def.gravity[0] = def.gravity[1] = 0, def.gravity[2] = -G;
    check(tb_world_create(&def, &w, NULL, 0), NULL, "world");
    ground.type = TB_SHAPE_PLANE;
    ground.friction = 0.8;
    check(tb_world_add_shape(w, &ground, NULL), w, "plane");
    for (i = 0; i < count; ++i) {
        ref_ragdoll_joint js[REF_RAGDOLL_JOINTS];
        double at[3];
        ref_ragdoll_place(i, at);
        ref_ragdoll(at[0], at[1], at[2], bone + i * REF_RAGDOLL_BONES, js);
        for (k = 0; k < REF_RAGDOLL_BONES; ++k) {
            const ref_bone *b = &bone[i * REF_RAGDOLL_BONES + k];
            const double l = ref_bone_length(b);
            const double r2 = sqrt(0.5);
            tb_body_def bd = tb_default_body_def();
            tb_shape_def sd = tb_default_shape_def();
            int d;
            check(tb_mass_capsule(1, b->radius, l, &bd.mass, NULL), w, "mass");
            check(tb_mass_set_total(&bd.mass, b->mass, NULL), w, "mass");
            for (d = 0; d < 3; ++d)
                bd.position[d] = (b->p[d] + b->q[d]) / 2;
            if (b->q[0] != b->p[0]) /* a capsule's axis is its z: turned onto p to q */
                bd.orientation[0] = r2, bd.orientation[1] = 0, bd.orientation[2] = r2, bd.orientation[3] = 0;
            else if (b->q[1] != b->p[1])
                bd.orientation[0] = r2, bd.orientation[1] = -r2, bd.orientation[2] = 0, bd.orientation[3] = 0;
            check(tb_world_add_body(w, &bd, &body[i * REF_RAGDOLL_BONES + k]), w, "body");
            sd.type = TB_SHAPE_CAPSULE;
            sd.body = body[i * REF_RAGDOLL_BONES + k];
            sd.radius = b->radius;
            sd.half_length = l / 2;
            check(tb_world_add_shape(w, &sd, NULL), w, "capsule");
        }
        for (k = 0; k < REF_RAGDOLL_JOINTS; ++k) {
            const ref_ragdoll_joint *r = &js[k];
            tb_joint_def jd = tb_default_joint_def();
            jd.type = r->hinge ? TB_JOINT_HINGE : TB_JOINT_BALL;
            jd.a = body[i * REF_RAGDOLL_BONES + r->a];
            jd.b = body[i * REF_RAGDOLL_BONES + r->b];
            memcpy(jd.anchor, r->anchor, sizeof jd.anchor);
            memcpy(jd.axis, r->axis, sizeof jd.axis);
            jd.enable_limit = 1;
            jd.lower = r->hinge ? r->lower : 0;
            jd.upper = r->hinge ? r->upper : r->cone;
            if (!r->hinge)
                jd.enable_twist = 1, jd.twist_lower = r->twist[0], jd.twist_upper = r->twist[1];
            check(tb_world_add_joint(w, &jd, NULL), w, "joint");
        }
    }
    for (s = 0; s < PILE_SECONDS * 60; ++s) {
        const double t0 = seconds();
        if (tb_world_step(w, h) != TB_OK) {
            run.finite = 0;
            break;
        }
        sum += seconds() - t0;
        for (i = 0; i < (int)tb_world_joint_count(w); ++i) {
            double e;
            tb_joint_error(w, tb_world_joint_at(w, (size_t)i), &e);
            run.gap = isfinite(e) ? fmax(run.gap, e) : INFINITY;
        }
        for (k = 0; k < count * REF_RAGDOLL_BONES; ++k) {
            const ref_bone *b = &bone[k];
            const double l = ref_bone_length(b);
            double x[3], q[4], low;
            tb_body_position(w, body[k], x);
            tb_body_orientation(w, body[k], q);
            low = x[2] - fabs(1 - 2 * (q[1] * q[1] + q[2] * q[2])) * l / 2 - b->radius;
            run.finite &= isfinite(low);
            run.deepest = fmax(run.deepest, -low);
        }
    }
    for (k = 0; k < count * REF_RAGDOLL_BONES; ++k) {
        double m, inertia[3], v[3], om[3], P[3], L[3];
        int asleep = 0;
        tb_body_velocity(w, body[k], v);
        tb_body_angular_velocity(w, body[k], om);
        tb_body_momentum(w, body[k], P, L);
        tb_body_mass(w, body[k], &m, inertia);
        run.kinetic += 0.5 * (P[0] * v[0] + P[1] * v[1] + P[2] * v[2] + L[0] * om[0] + L[1] * om[1] + L[2] * om[2]);
        tb_body_asleep(w, body[k], &asleep);
        run.asleep += asleep;
    }
    run.bodies = count * REF_RAGDOLL_BONES;
    run.us = 1e6 * sum / (s ? s : 1);
    tb_world_destroy(w);
    free(body);
    free(bone);
    return run;
}

static void print_pile(const char *who, int count, pile_run r, double per_joint_ns, const char *ratio)
{
    char asleep[64] = "";
    if (r.bodies)
        snprintf(asleep, sizeof asleep, ", %d of %d asleep", r.asleep, r.bodies);
    printf("ragdolls  %-20s %2d: %s%.1f us/step, %.0f ns/joint/step%s, worst joint %.1e, kinetic %.2e J at %d s, "
           "deepest %.4f m%s\n", who, count, r.finite ? "" : "NOT FINITE: ", r.us, per_joint_ns, ratio, r.gap,
           r.kinetic, PILE_SECONDS, r.deepest, asleep);
}

static void ragdolls(void)
{
    static const int counts[2] = { 3, 8 };
    int k;
    printf("ragdolls  13 capsules, 12 joints each, dropped in a pile, 4 to a layer, %d s at 60 Hz (target: 10 times "
           "QuickStep's speed per joint, at rest without jitter, joints within 1 mm, none through the ground)\n",
           PILE_SECONDS);
    for (k = 0; k < 2; ++k) {
        const int joints = counts[k] * REF_RAGDOLL_JOINTS;
        const pile_run t = tumble_pile(counts[k]);
        ode_ragdoll_def d = ode_default_ragdoll_def();
        ode_ragdoll_result o[2];
        int m;
        char ratio[64];
        print_pile("tumble verlet", counts[k], t, 1e3 * t.us / joints, "");
        d.count = counts[k];
        d.steps = PILE_SECONDS * 60;
        for (m = 0; m < 2; ++m) {
            pile_run r = { 0, 0, 0, 0, 0, 0, 1 };
            d.iterations = m ? 0 : 20;
            if (!ode_ragdolls(&d, &o[m])) {
                printf("ragdolls  ODE did not run\n");
                return;
            }
            r.us = 1e3 * o[m].ms_mean, r.gap = o[m].gap, r.kinetic = o[m].kinetic, r.deepest = o[m].deepest;
            r.finite = o[m].finite;
            snprintf(ratio, sizeof ratio, " (tumble/ODE %.2f)", t.us / r.us);
            print_pile(m ? "ODE dWorldStep" : "ODE QuickStep(20)", counts[k], r, 1e3 * r.us / joints, ratio);
        }
    }
}

int main(void)
{
    setvbuf(stdout, NULL, _IOLBF, 0);
    printf("tumble joints beside ODE %s (double)\n", TB_BENCH_ODE);
    bench_print_build();
    bench_print_asserts();
    pendulum();
    chain();
    ragdolls();
    return 0;
}
