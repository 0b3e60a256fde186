/* ode_contacts.h: ODE 0.16.2 reference runs of scenes with contacts, for
   tumble's tests and benchmarks to compare against (docs/design.md section 5,
   third kind of truth). Not a cmocka file: a plain C library over ODE.

   Common to every scene: SI units; z is up; a static plane z = 0 (ODE plane
   geom (0, 0, 1, 0), no body); gravity (0, 0, -g); ODE's double-precision
   defaults unless a scene says otherwise: world ERP 0.2, world CFM 1e-10
   (1e-5 is the single-precision default, and changes the figures), contact
   surface layer 0, no max correcting velocity, no damping, no auto-disable.
   Contact joints are created fresh every step from dCollide and emptied
   after the step (no warm starting: ODE has none).

   Every run calls dInitODE2(0) and dAllocateODEDataForThread, and ends with
   dCloseODE, so it is self-contained. ODE counts these calls, so a caller
   that already initialised ODE stays initialised; the count is a plain
   global, so run one scene at a time (not from two threads at once). Every
   run also resets ODE's random seed (dRandSetSeed(0), its value at load):
   dWorldQuickStep shuffles constraint rows with it, and without the reset a
   run's figures would depend on what ran before it in the process. ODE
   aborts on invalid input even with a handler, so the definitions are
   checked first and refused (return 0) rather than passed on. */
#ifndef TB_ODE_CONTACTS_H
#define TB_ODE_CONTACTS_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" { /* (bullet_contacts.cpp builds the same scenes) */
#endif

/* ------------------------------------------------------------ bouncing ball
   A sphere (radius 0.1 m, mass 1 kg, inertia 0.4 m r^2) starts at rest with
   its lowest point drop_height above the plane: centre at
   z = drop_height + radius. Every step: dCollide(sphere, plane, 4 contacts),
   one contact joint per point with surface.mode = dContactBounce,
   bounce = restitution, bounce_vel (default 0.01 m/s), mu = 0; then
   dWorldStep(1/hz). ODE applies the bounce as a target normal velocity
   -bounce * (approach velocity at the start of the step), from wherever the
   sphere is when a contact is first found: it has usually sunk below the
   plane by then, which is why the apexes fall short of e^2k h0.

   An apex is recorded once per bounce: after a step with a contact, the first
   step whose vertical velocity is <= 0 following one where it was > 0.
   apex[] is the height of the lowest point (centre z - radius) after that
   step, i.e. the first sample past the top: this is what reproduces the
   issue's figures (0.2356, 0.0408 m at 60 Hz, restitution 0.5, 1 m drop).
   apex_max[] is the larger of that sample and the one before it, the
   discrete maximum (0.2370, 0.0415 m for the same run). At 240 Hz the two
   agree (0.2505, 0.0619 m). */

#define ODE_BALL_APEXES 4

typedef struct ode_ball_def {
    double hz;          /* 1/s, step rate: h = 1/hz */
    double restitution; /* surface.bounce, in [0, 1] */
    double drop_height; /* m, lowest point above the plane at the start */
    double radius;      /* m, 0.1 */
    double mass;        /* kg, 1 */
    double bounce_vel;  /* m/s, surface.bounce_vel: 0.01 */
    double gravity;     /* m/s^2, 9.81 */
    double max_time;    /* s, simulated time before giving up: 20 */
} ode_ball_def;

typedef struct ode_ball_result {
    int apexes;                        /* apexes found, up to ODE_BALL_APEXES */
    double apex[ODE_BALL_APEXES];      /* m, lowest point, first sample past the top */
    double apex_max[ODE_BALL_APEXES];  /* m, lowest point, discrete maximum */
    double apex_time[ODE_BALL_APEXES]; /* s, time of the apex[] sample */
    int steps;                         /* steps taken */
} ode_ball_result;

/* The defaults above with hz 60, restitution 0.5, drop height 1 m. */
ode_ball_def ode_default_ball_def(void);

/* Runs until ODE_BALL_APEXES apexes or max_time. Returns 1 if the run
   happened (even with fewer apexes: see out->apexes), 0 if def was refused
   (non-finite, hz <= 0, restitution outside [0, 1], ...) or ODE did not
   initialise. */
int ode_ball_run(const ode_ball_def *def, ode_ball_result *out);

/* The figure: apex[0..1] of the default run at hz, restitution and
   drop height. Returns the number of apexes stored (2 unless refused or the
   ball stopped bouncing); unfilled entries are NAN. */
int ode_ball_apexes(double hz, double restitution, double drop_height, double apex[2]);

/* -------------------------------------------------------------- sliding box
   A cube (edge 1 m, mass 1 kg, its own inertia) rests on the plane, centre
   at z = edge/2, orientation identity, and is given velocity (speed, 0, 0).
   Every step: dCollide(box, plane, 4 contacts), one contact joint per point
   with surface.mode = dContactApprox1 (the friction bound is mu times the
   normal force of the same solve: Coulomb; without it ODE takes mu as a
   force in newtons and the box slides 6.2 m), mu, no bounce; then
   dWorldStep(1/hz). It stops when the velocity along the start direction is
   <= stop_speed (1e-6 m/s), which also catches a reversal; ODE's friction
   brings it to rest within about 1e-10 m/s, so the threshold does not move
   the figure. The distance is the horizontal displacement of the centre.

   ODE gives exactly the discrete Coulomb sum: the speed drops by mu g h per
   step and the position moves by h times the new speed, so
   d = h sum_{k=1..K} (v0 - k mu g h), K = floor(v0 / (mu g h)). */

typedef struct ode_slide_def {
    double hz;         /* 1/s */
    double speed;      /* m/s, initial, along +x: 5 */
    double mu;         /* Coulomb friction coefficient: 0.5 */
    double edge;       /* m, cube edge: 1 */
    double mass;       /* kg: 1 */
    double gravity;    /* m/s^2: 9.81 */
    double stop_speed; /* m/s: 1e-6 */
    double max_time;   /* s: 60 */
} ode_slide_def;

typedef struct ode_slide_result {
    double distance;          /* m, horizontal distance of the centre */
    double time;              /* s, to the step where it stopped */
    int steps;                /* steps taken */
    int stopped;              /* 0 if max_time ran out first */
    double max_height_change; /* m, largest |z - z0| seen: the box must not hop */
    double max_angular_speed; /* rad/s, largest |omega| seen: nor tip */
} ode_slide_result;

/* Defaults above with hz 60. */
ode_slide_def ode_default_slide_def(void);

/* Returns 1 if the run happened, 0 if def was refused or ODE did not
   initialise. */
int ode_slide_run(const ode_slide_def *def, ode_slide_result *out);

/* The figure: distance (m) for the default box at hz, speed and mu;
   NAN if refused or the box did not stop within max_time. */
double ode_slide_distance(double hz, double speed, double mu);

/* ------------------------------------------------------ stepping, in common
   The pyramid and the pile share this: a hash space (dHashSpaceCreate,
   default levels -3..10) holding the plane and every geom, dSpaceCollide
   with a near callback that skips pairs with no body and makes up to
   max_contacts points per pair (dCollide), each one contact joint with
   surface.mode = dContactApprox1 and mu; then dWorldQuickStep(1/hz) with
   `iterations` iterations (SOR w 1.3, ODE's default); then the contact group
   is emptied. The wall time of a step is all three (clock_gettime
   CLOCK_MONOTONIC); the setup is not timed. */

typedef struct ode_timing {
    double ms_mean;         /* ms, wall time of a step, mean over the steps */
    double ms_median;       /* ms, median over the steps */
    double ms_collide_mean; /* ms, the dSpaceCollide share, mean */
    double contacts_mean;   /* contact joints per step, mean */
    int contacts_max;       /* most contact joints in one step */
    int steps;
} ode_timing;

/* ----------------------------------------------------------------- pyramid
   A 2D pyramid of cubes in the plane y = 0: level i (0 at the bottom) holds
   levels - i cubes, centres at
       x = (j - 0.5 (levels - i - 1)) (edge + gap),  j = 0 .. levels - i - 1
       z = edge / 2 + i edge
   so each level sits half a pitch in from the one below; neighbours in a
   level are `gap` apart (0.01 m), levels touch exactly. Orientation
   identity, at rest. Default 20 levels: 210 cubes of edge 1 m, 1 kg. The
   top cube is the last one. With gap 0 the side faces touch at depth 0 and
   ODE reports side contacts or not by round-off (1673 contacts a step on
   average, up to 2340, against a steady 1545 to 1580 with 0.01 m); the top
   cube sinks the same 0.050 m in 10 s for any gap from 0 to 0.05 m. The
   sink is robust; the top cube's drift is not: it goes from 0.012 to
   0.097 m between ODE random seeds (see dRandSetSeed above), so compare
   drift only loosely. */

typedef struct ode_pyramid_def {
    int levels;       /* 20 */
    double edge;      /* m: 1 */
    double mass;      /* kg per cube: 1 */
    double gap;       /* m, between neighbours in a level: 0.01 */
    double hz;        /* 1/s: 60 */
    int iterations;   /* dWorldQuickStepNumIterations: 20 */
    double mu;        /* 0.6 */
    int max_contacts; /* per pair: 4 */
    double gravity;   /* m/s^2: 9.81 */
    double duration;  /* s: 10 */
    int auto_disable; /* 0; 1: ODE's auto-disable at its defaults (bodies slower
                         than 0.01 m/s and 0.01 rad/s for 10 steps rest, by
                         island), for comparing with tumble's sleep */
} ode_pyramid_def;

typedef struct ode_pyramid_result {
    ode_timing timing;
    int boxes;               /* levels (levels + 1) / 2 */
    double top_sink;         /* m, z0 - z of the top cube at the end */
    double top_drift;        /* m, horizontal distance of the top cube */
    double max_displacement; /* m, largest distance any cube moved */
} ode_pyramid_result;

ode_pyramid_def ode_default_pyramid_def(void);

/* Number of cubes: levels (levels + 1) / 2. */
int ode_pyramid_boxes(int levels);

/* Fills pos[ode_pyramid_boxes(levels)] with the centres, bottom level first,
   left to right (the order the run creates the bodies in). Returns the count,
   0 if def was refused. */
int ode_pyramid_positions(const ode_pyramid_def *def, double (*pos)[3]);

/* Builds the scene, steps it for duration, times the steps. Returns 1 if the
   run happened, 0 if def was refused, memory ran out or ODE did not
   initialise. */
int ode_pyramid(const ode_pyramid_def *def, ode_pyramid_result *out);

/* --------------------------------------------------------------------- pile
   `count` mixed shapes dropped onto the plane from a grid, generated by
   ode_pile_scene() so that tumble builds exactly the same scene:

   - random numbers: a 64-bit LCG, state = state * 6364136223846793005 +
     1442695040888963407 (mod 2^64), starting from state = seed; each draw
     advances the state first and returns (state >> 11) * 2^-53, in [0, 1).
   - body b draws exactly seven numbers u0..u6, in order, whatever its kind:
     kind = floor(3 u0): 0 sphere, 1 box, 2 capsule;
       sphere:  diameter 0.2 + 0.4 u1 (u2, u3 unused);
       box:     edges 0.2 + 0.4 u1, 0.2 + 0.4 u2, 0.2 + 0.4 u3 along its x, y, z;
       capsule: diameter 0.2 + 0.2 u1, core (cylinder) length 0.2 + 0.4 u2,
                along its z axis (u3 unused), so 0.4 to 1.0 m long;
     orientation (w, x, y, z), Shoemake's uniform rotation:
       a = sqrt(1 - u4), b = sqrt(u4), t1 = 2 pi u5, t2 = 2 pi u6,
       q = (b cos t2, a sin t1, a cos t1, b sin t2).
   - position: a grid of `grid` x `grid` per layer, pitch `spacing` (1.2 m:
     no shape reaches 0.6 m from its centre, so nothing overlaps at the start):
       layer = b / grid^2, row = (b / grid) % grid, col = b % grid,
       x = (col - 0.5 (grid - 1)) spacing, y = (row - 0.5 (grid - 1)) spacing,
       z = base + layer spacing   (base 1 m).
   - mass: uniform density (1000 kg/m^3); mass and principal inertia about
     the centre along the shape's axes with ODE's formulas (dMassSetSphere,
     dMassSetBox, dMassSetCapsule with direction 3, which the run uses via
     dMassSetParameters so both engines get the same numbers):
       sphere  m = 4/3 pi r^3 rho,  I = 0.4 m r^2 (all three);
       box     m = rho lx ly lz,    Ixx = m (ly^2 + lz^2) / 12, ...;
       capsule m1 = pi r^2 l rho (cylinder), m2 = 4/3 pi r^3 rho (caps),
               Ixx = Iyy = m1 (r^2/4 + l^2/12)
                           + m2 (0.4 r^2 + 0.375 r l + 0.25 l^2),
               Izz = (0.5 m1 + 0.4 m2) r^2.
   All start at rest. Stepping as in "stepping, in common" above. */

typedef enum ode_shape_kind {
    ODE_SHAPE_SPHERE = 0,
    ODE_SHAPE_BOX = 1,
    ODE_SHAPE_CAPSULE = 2
} ode_shape_kind;

typedef struct ode_shape {
    ode_shape_kind kind;
    double radius;         /* m: sphere and capsule, else 0 */
    double half[3];        /* m: box half edges; capsule: half[2] is half the
                              core length (half[0] = half[1] = 0); sphere: 0 */
    double position[3];    /* m, centre (= centre of mass) */
    double orientation[4]; /* unit quaternion (w, x, y, z), world from shape */
    double mass;           /* kg */
    double inertia[3];     /* kg m^2, principal, along the shape's x, y, z */
} ode_shape;

typedef struct ode_pile_def {
    int count;        /* shapes: 1000 */
    uint64_t seed;    /* LCG start: 1 */
    int grid;         /* shapes per row and rows per layer: 10 */
    double spacing;   /* m, grid pitch: 1.2 */
    double base;      /* m, z of the lowest layer: 1 */
    double density;   /* kg/m^3: 1000 */
    double hz;        /* 1/s: 60 */
    int iterations;   /* 20 */
    double mu;        /* 0.6 */
    int max_contacts; /* per pair: 4 */
    double gravity;   /* m/s^2: 9.81 */
    int steps;        /* steps to run and time: 600 (10 s) */
    int copies;       /* separate piles side by side, each the scene above: 1 */
    double copy_pitch;/* m between the copies' centres, on a square grid: 15 (a
                         pile of grid 10 spans 11 m, so copies never meet) */
} ode_pile_def;

typedef struct ode_pile_result {
    ode_timing timing;
    double final_max_speed; /* m/s, fastest shape at the end */
    int final_moving;       /* shapes faster than 0.1 m/s at the end: nearly
                               all spheres and capsules rolling away over the
                               plane (ODE has no rolling friction here) */
    double final_top;       /* m, highest centre at the end: the pile's height */
} ode_pile_result;

ode_pile_def ode_default_pile_def(void);

/* Fills shapes[def->count] as described above. Pure C, no ODE call. Returns
   the count, 0 if def was refused. */
int ode_pile_scene(const ode_pile_def *def, ode_shape *shapes);

/* Where copy k (0 .. copies - 1) of the pile sits: added to every shape's x
   and y. The copies make a square grid of copy_pitch, centred on the
   origin. Pure C. */
void ode_pile_copy_offset(const ode_pile_def *def, int k, double offset[2]);

/* Builds the scene from ode_pile_scene (def->copies of it, placed by
   ode_pile_copy_offset), steps it def->steps times, times the steps.
   Returns 1 if the run happened, 0 if def was refused, memory ran out or
   ODE did not initialise. */
int ode_pile(const ode_pile_def *def, ode_pile_result *out);

/* ------------------------------------------------------- heavy landing
   A column of `under` + 1 unit boxes of 1 kg on the plane, and a unit box
   `ratio` times as heavy dropped from `gap` above the top one (centre at
   1.5 + under + gap), all in a line; QuickStep with `iterations`, up to 4
   contacts a pair, dContactApprox1 with mu 0.6, no bounce; `steps` steps
   of 1/hz. The heavy box's end against resting on the column, its fastest
   rise after it first came within 1 cm of that, and the deepest any
   column box went below its place. */
typedef struct ode_heavy_def {
    double ratio;   /* the heavy box's mass, kg (the others: 1 kg) */
    int under;      /* boxes under the one it lands on */
    double gap;     /* m */
    double hz;      /* 1/s */
    int iterations; /* QuickStep's */
    int steps;
    double gravity; /* m/s^2 */
} ode_heavy_def;

typedef struct ode_heavy_result {
    double end;     /* m: heavy box's centre z minus 1.5 + under, at the end */
    double rebound; /* m/s: its fastest upward speed after it landed */
    double sink;    /* m: deepest a column box went below its place */
} ode_heavy_result;

/* ratio 100, under 0, gap 0.5, 60 Hz, 20 iterations, 600 steps, g 9.81 */
ode_heavy_def ode_default_heavy_def(void);

/* Returns 1 if the run happened, 0 if def was refused or ODE did not
   initialise. */
int ode_heavy_landing(const ode_heavy_def *def, ode_heavy_result *out);

/* ------------------------------------------------------------ ragdolls
   `count` ragdolls of ragdoll.h dropped in a pile (ref_ragdoll_place) on
   the plane, mu 0.8, up to 4 contacts a pair, none between bodies a joint
   holds; ODE's ball joints have no cone or twist limits (its hinges have
   their stops, dParamLoStop and HiStop); QuickStep with `iterations`, or
   dWorldStep (iterations 0); `steps` steps of 1/hz. The mean wall time of
   a step (collision and step), the worst distance between a joint's two
   anchors at any step, the kinetic energy at the end, and the deepest
   any capsule went into the plane. */
typedef struct ode_ragdoll_def {
    int count;
    double hz;      /* 1/s */
    int iterations; /* QuickStep's; 0: dWorldStep */
    int steps;
    double gravity; /* m/s^2 */
} ode_ragdoll_def;

typedef struct ode_ragdoll_result {
    double ms_mean;  /* ms a step */
    double gap;      /* m: the worst joint's anchors apart */
    double kinetic;  /* J at the end */
    double deepest;  /* m: the deepest point of a capsule under the plane */
    int finite;      /* 0: a pose or speed became non-finite */
} ode_ragdoll_result;

/* 20 ragdolls, 60 Hz, QuickStep(20), 360 steps, g 9.81 */
ode_ragdoll_def ode_default_ragdoll_def(void);

/* Returns 1 if the run happened, 0 if def was refused or ODE did not
   initialise. */
int ode_ragdolls(const ode_ragdoll_def *def, ode_ragdoll_result *out);

#ifdef __cplusplus
}
#endif

#endif
