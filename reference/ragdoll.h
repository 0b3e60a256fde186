/* ragdoll.h: the ragdoll of scenes/ragdoll.lua as data (a header only),
   for bench_joints' pile in tumble and in ODE (ode_ragdolls): thirteen
   capsules (pelvis, chest, head, upper and lower arms, thighs, shins and
   feet) on five ball joints (waist, neck, shoulders, hips: a cone and a
   twist range about the axis) and six hinges with stops (elbows, knees,
   ankles), standing with its pelvis at (x, y, z). */
#ifndef TB_REFERENCE_RAGDOLL_H
#define TB_REFERENCE_RAGDOLL_H

#include <math.h>

#define REF_RAGDOLL_BONES 13
#define REF_RAGDOLL_JOINTS 12

/* A capsule from p to q (apart along one axis) of radius r and mass m */
typedef struct ref_bone {
    double p[3], q[3], radius, mass;
} ref_bone;

/* A joint of bone a to bone b at anchor: a ball (cone: the largest angle
   between a's and b's copies of the axis, twist: the range of turn about
   it) or a hinge about axis (lower, upper: its stops, the angle a has
   turned relative to b) */
typedef struct ref_ragdoll_joint {
    int hinge;
    int a, b;
    double anchor[3], axis[3];
    double cone, twist[2];
    double lower, upper;
} ref_ragdoll_joint;

/* A bone's length, p to q */
static inline double ref_bone_length(const ref_bone *b)
{
    return fabs(b->q[0] - b->p[0]) + fabs(b->q[1] - b->p[1]) + fabs(b->q[2] - b->p[2]);
}

static inline void ref_ragdoll_bone(ref_bone *b, double x, double y, double z, const double p[3],
                                    const double q[3], double radius, double mass)
{
    int k;
    const double at[3] = { x, y, z };
    for (k = 0; k < 3; ++k)
        b->p[k] = at[k] + p[k], b->q[k] = at[k] + q[k];
    b->radius = radius, b->mass = mass;
}

static inline void ref_ragdoll_joint_at(ref_ragdoll_joint *j, int hinge, int a, int b, double x, double y, double z,
                                        const double anchor[3], const double axis[3], double cone, double t0,
                                        double t1, double lower, double upper)
{
    int k;
    const double at[3] = { x, y, z };
    j->hinge = hinge, j->a = a, j->b = b;
    for (k = 0; k < 3; ++k)
        j->anchor[k] = at[k] + anchor[k], j->axis[k] = axis[k];
    j->cone = cone, j->twist[0] = t0, j->twist[1] = t1, j->lower = lower, j->upper = upper;
}

/* The bones and joints of a ragdoll whose pelvis is at (x, y, z) */
static inline void ref_ragdoll(double x, double y, double z, ref_bone bones[REF_RAGDOLL_BONES],
                               ref_ragdoll_joint joints[REF_RAGDOLL_JOINTS])
{
    static const double up[3] = { 0, 0, 1 }, down[3] = { 0, 0, -1 }, across[3] = { 0, 1, 0 };
    int side, n = 3, m = 2;
    {
        const double p0[3] = { 0, -0.12, 0 }, q0[3] = { 0, 0.12, 0 }, p1[3] = { 0, 0, 0.15 }, q1[3] = { 0, 0, 0.45 };
        const double p2[3] = { 0, 0, 0.62 }, q2[3] = { 0, 0, 0.72 }, waist[3] = { 0, 0, 0.05 }, neck[3] = { 0, 0, 0.55 };
        ref_ragdoll_bone(&bones[0], x, y, z, p0, q0, 0.1, 8);   /* pelvis */
        ref_ragdoll_bone(&bones[1], x, y, z, p1, q1, 0.14, 15); /* chest */
        ref_ragdoll_bone(&bones[2], x, y, z, p2, q2, 0.1, 5);   /* head */
        ref_ragdoll_joint_at(&joints[0], 0, 1, 0, x, y, z, waist, up, 0.5, -0.5, 0.5, 0, 0);
        ref_ragdoll_joint_at(&joints[1], 0, 2, 1, x, y, z, neck, up, 0.6, -1, 1, 0, 0);
    }
    for (side = -1; side <= 1; side += 2) {
        const double s = side, outward[3] = { 0, s, 0 };
        const double up0[3] = { 0, s * 0.25, 0.45 }, up1[3] = { 0, s * 0.5, 0.45 };
        const double lo0[3] = { 0, s * 0.55, 0.45 }, lo1[3] = { 0, s * 0.8, 0.45 };
        const double th0[3] = { 0, s * 0.12, -0.15 }, th1[3] = { 0, s * 0.12, -0.55 };
        const double sh0[3] = { 0, s * 0.12, -0.62 }, sh1[3] = { 0, s * 0.12, -0.98 };
        const double ft0[3] = { 0.02, s * 0.12, -1.06 }, ft1[3] = { 0.18, s * 0.12, -1.06 };
        const double shoulder[3] = { 0, s * 0.2, 0.45 }, elbow[3] = { 0, s * 0.525, 0.45 };
        const double hip[3] = { 0, s * 0.12, -0.07 }, knee[3] = { 0, s * 0.12, -0.585 }, ankle[3] = { 0, s * 0.12, -1.02 };
        const int upper = n, lower = n + 1, thigh = n + 2, shin = n + 3, foot = n + 4;
        ref_ragdoll_bone(&bones[upper], x, y, z, up0, up1, 0.05, 2);
        ref_ragdoll_bone(&bones[lower], x, y, z, lo0, lo1, 0.045, 1.5);
        ref_ragdoll_bone(&bones[thigh], x, y, z, th0, th1, 0.07, 7);
        ref_ragdoll_bone(&bones[shin], x, y, z, sh0, sh1, 0.06, 4);
        ref_ragdoll_bone(&bones[foot], x, y, z, ft0, ft1, 0.04, 1);
        ref_ragdoll_joint_at(&joints[m++], 0, upper, 1, x, y, z, shoulder, outward, 1.2, -1, 1, 0, 0);
        ref_ragdoll_joint_at(&joints[m++], 1, lower, upper, x, y, z, elbow, up, 0, 0, 0, side > 0 ? 0 : -2.5,
                             side > 0 ? 2.5 : 0);
        ref_ragdoll_joint_at(&joints[m++], 0, thigh, 0, x, y, z, hip, down, 1.0, -0.5, 0.5, 0, 0);
        ref_ragdoll_joint_at(&joints[m++], 1, shin, thigh, x, y, z, knee, across, 0, 0, 0, 0, 2.3);
        ref_ragdoll_joint_at(&joints[m++], 1, foot, shin, x, y, z, ankle, across, 0, 0, 0, -0.6, 0.6);
        n += 5;
    }
}

/* Where ragdoll i of a pile stands: four to a layer, 0.6 m apart with
   the offset of 0.3 m that scenes/ragdoll.lua's three have, each layer
   1.2 m above the last, the first's pelvis at 2.6 m */
static inline void ref_ragdoll_place(int i, double at[3])
{
    at[0] = 0.6 * (i % 2) + 0.3 * sin(i + 1.0);
    at[1] = 0.6 * ((i / 2) % 2) + 0.3 * cos(i + 1.0);
    at[2] = 2.6 + 1.2 * (i / 4);
}

#endif
