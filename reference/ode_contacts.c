/* ode_contacts.c: ODE reference runs of scenes with contacts. The scenes
   and the reasons for their settings are in ode_contacts.h. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime under -std=c99 */

#include "ode_contacts.h"
#include "ragdoll.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <ode/ode.h>

/* The reference figures are for double precision; a negative array size
   stops the build otherwise. */
typedef char ode_contacts_dreal_is_double[sizeof(dReal) == sizeof(double) ? 1 : -1];

#define PI 3.14159265358979323846

/* ------------------------------------------------------------- in common -- */

static double seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int finite_positive(double x)
{
    return isfinite(x) && x > 0;
}

/* dInitODE2 only allocates the basic per-thread data; collision data is
   a separate request that the documentation asks for before collision.
   dWorldQuickStep shuffles its constraint rows with dRandInt, whose seed is
   a process-wide global that survives dCloseODE: without the reset a second
   pyramid in the same process sinks and drifts differently from the first.
   0 is the seed ODE starts with, so every run matches a fresh process. */
static int ode_open(void)
{
    if (!dInitODE2(0))
        return 0;
    if (!dAllocateODEDataForThread((unsigned)dAllocateMaskAll)) {
        dCloseODE();
        return 0;
    }
    dRandSetSeed(0);
    return 1;
}

static int compare_doubles(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Sorts t in place. */
static double median(double *t, int n)
{
    qsort(t, (size_t)n, sizeof *t, compare_doubles);
    return n % 2 ? t[n / 2] : 0.5 * (t[n / 2 - 1] + t[n / 2]);
}

/* The near callback's state: dSpaceCollide passes one pointer, and nothing
   here may be global (several runs, one after the other, in one process). */
typedef struct near_ctx {
    dWorldID world;
    dJointGroupID group;
    double mu;
    int max_contacts; /* <= NEAR_MAX */
    int contacts;     /* joints made this step */
} near_ctx;

#define NEAR_MAX 16

static void near_callback(void *data, dGeomID a, dGeomID b)
{
    near_ctx *c = data;
    dBodyID ba = dGeomGetBody(a), bb = dGeomGetBody(b);
    dContactGeom g[NEAR_MAX];
    int n, i;

    if (!ba && !bb)
        return;
    n = dCollide(a, b, c->max_contacts, g, sizeof g[0]);
    for (i = 0; i < n; ++i) {
        dContact contact;
        dJointID j;
        memset(&contact, 0, sizeof contact);
        contact.surface.mode = dContactApprox1;
        contact.surface.mu = c->mu;
        contact.geom = g[i];
        j = dJointCreateContact(c->world, c->group, &contact);
        dJointAttach(j, ba, bb);
    }
    c->contacts += n;
}

/* The timed run of the pyramid and the pile: `steps` steps of collision
   (up to max_contacts per pair, friction mu) and dWorldQuickStep, each step
   timed into step_ms, summed up in t. */
static void run_quick(dWorldID world, dSpaceID space, double mu, int max_contacts, double h, int steps,
                      double *step_ms, ode_timing *t)
{
    near_ctx c;
    double collide_ms_sum = 0, sum = 0;
    long contacts_sum = 0;
    int n;

    memset(t, 0, sizeof *t);
    c.world = world;
    c.group = dJointGroupCreate(0);
    c.mu = mu;
    c.max_contacts = max_contacts;
    for (n = 0; n < steps; ++n) {
        double t0, t1, t2;
        c.contacts = 0;
        t0 = seconds();
        dSpaceCollide(space, &c, near_callback);
        t1 = seconds();
        dWorldQuickStep(world, h);
        dJointGroupEmpty(c.group);
        t2 = seconds();
        step_ms[n] = 1e3 * (t2 - t0);
        sum += step_ms[n];
        collide_ms_sum += 1e3 * (t1 - t0);
        contacts_sum += c.contacts;
        if (c.contacts > t->contacts_max)
            t->contacts_max = c.contacts;
    }
    dJointGroupDestroy(c.group);
    t->steps = steps;
    t->ms_mean = steps ? sum / steps : 0;
    t->ms_median = steps ? median(step_ms, steps) : 0;
    t->ms_collide_mean = steps ? collide_ms_sum / steps : 0;
    t->contacts_mean = steps ? (double)contacts_sum / steps : 0;
}

/* The world every contact scene uses: ODE's defaults, named here so that a
   change of default in another ODE version shows up as a change in this
   file rather than in the figures. */
static dWorldID make_world(double gravity)
{
    dWorldID w = dWorldCreate();
    dWorldSetGravity(w, 0, 0, -gravity);
    dWorldSetERP(w, 0.2);
    dWorldSetCFM(w, 1e-10);
    dWorldSetContactSurfaceLayer(w, 0);
    dWorldSetAutoDisableFlag(w, 0);
    return w;
}

/* The pyramid's and the pile's world: QuickStep with the given iterations,
   a hash space holding the ground plane z = 0. */
static dWorldID quick_world(double gravity, int iterations, dSpaceID *space)
{
    dWorldID world = make_world(gravity);
    dWorldSetQuickStepNumIterations(world, iterations);
    *space = dHashSpaceCreate(0);
    dCreatePlane(*space, 0, 0, 1, 0);
    return world;
}

/* --------------------------------------------------------- bouncing ball -- */

ode_ball_def ode_default_ball_def(void)
{
    ode_ball_def d;
    d.hz = 60;
    d.restitution = 0.5;
    d.drop_height = 1;
    d.radius = 0.1;
    d.mass = 1;
    d.bounce_vel = 0.01;
    d.gravity = 9.81;
    d.max_time = 20;
    return d;
}

int ode_ball_run(const ode_ball_def *def, ode_ball_result *out)
{
    dWorldID world;
    dBodyID body;
    dGeomID sphere, plane;
    dJointGroupID group;
    dMass mass;
    double h, prev_z, prev_vz = 0;
    int n, steps, bounced = 0, i;

    memset(out, 0, sizeof *out);
    for (i = 0; i < ODE_BALL_APEXES; ++i)
        out->apex[i] = out->apex_max[i] = out->apex_time[i] = NAN;
    if (!finite_positive(def->hz) || !isfinite(def->restitution) || def->restitution < 0 ||
        def->restitution > 1 || !isfinite(def->drop_height) || def->drop_height < 0 ||
        !finite_positive(def->radius) || !finite_positive(def->mass) ||
        !isfinite(def->bounce_vel) || def->bounce_vel < 0 || !isfinite(def->gravity) ||
        !finite_positive(def->max_time) || def->max_time * def->hz > 1e8)
        return 0;
    if (!ode_open())
        return 0;

    h = 1 / def->hz;
    steps = (int)ceil(def->max_time * def->hz);
    world = make_world(def->gravity);
    plane = dCreatePlane(0, 0, 0, 1, 0);
    body = dBodyCreate(world);
    dMassSetSphereTotal(&mass, def->mass, def->radius);
    dBodySetMass(body, &mass);
    sphere = dCreateSphere(0, def->radius);
    dGeomSetBody(sphere, body);
    dBodySetPosition(body, 0, 0, def->drop_height + def->radius);
    group = dJointGroupCreate(0);
    prev_z = def->drop_height;

    for (n = 1; n <= steps && out->apexes < ODE_BALL_APEXES; ++n) {
        dContactGeom g[4];
        double z, vz;
        int nc = dCollide(sphere, plane, 4, g, sizeof g[0]);
        for (i = 0; i < nc; ++i) {
            dContact contact;
            memset(&contact, 0, sizeof contact);
            contact.surface.mode = dContactBounce;
            contact.surface.mu = 0;
            contact.surface.bounce = def->restitution;
            contact.surface.bounce_vel = def->bounce_vel;
            contact.geom = g[i];
            dJointAttach(dJointCreateContact(world, group, &contact), body, 0);
        }
        bounced |= nc > 0;
        dWorldStep(world, h);
        dJointGroupEmpty(group);
        z = dBodyGetPosition(body)[2] - def->radius;
        vz = dBodyGetLinearVel(body)[2];
        /* Only after a contact, so that the start from rest is no apex. */
        if (bounced && prev_vz > 0 && vz <= 0) {
            out->apex[out->apexes] = z;
            out->apex_max[out->apexes] = z > prev_z ? z : prev_z;
            out->apex_time[out->apexes] = n * h;
            out->apexes++;
            bounced = 0;
        }
        prev_z = z;
        prev_vz = vz;
        out->steps = n;
    }

    dJointGroupDestroy(group);
    dGeomDestroy(sphere);
    dGeomDestroy(plane);
    dBodyDestroy(body);
    dWorldDestroy(world);
    dCloseODE();
    return 1;
}

int ode_ball_apexes(double hz, double restitution, double drop_height, double apex[2])
{
    ode_ball_def def = ode_default_ball_def();
    ode_ball_result r;
    int ok;

    def.hz = hz;
    def.restitution = restitution;
    def.drop_height = drop_height;
    ok = ode_ball_run(&def, &r);
    apex[0] = r.apex[0];
    apex[1] = r.apex[1];
    if (!ok)
        return 0;
    return r.apexes < 2 ? r.apexes : 2;
}

/* ----------------------------------------------------------- sliding box -- */

ode_slide_def ode_default_slide_def(void)
{
    ode_slide_def d;
    d.hz = 60;
    d.speed = 5;
    d.mu = 0.5;
    d.edge = 1;
    d.mass = 1;
    d.gravity = 9.81;
    d.stop_speed = 1e-6;
    d.max_time = 60;
    return d;
}

int ode_slide_run(const ode_slide_def *def, ode_slide_result *out)
{
    dWorldID world;
    dBodyID body;
    dGeomID box, plane;
    dJointGroupID group;
    dMass mass;
    double h, z0;
    int n, steps, i;

    memset(out, 0, sizeof *out);
    out->distance = out->time = NAN;
    if (!finite_positive(def->hz) || !finite_positive(def->speed) || !isfinite(def->mu) ||
        def->mu < 0 || !finite_positive(def->edge) || !finite_positive(def->mass) ||
        !isfinite(def->gravity) || !isfinite(def->stop_speed) || def->stop_speed < 0 ||
        !finite_positive(def->max_time) || def->max_time * def->hz > 1e8)
        return 0;
    if (!ode_open())
        return 0;

    h = 1 / def->hz;
    steps = (int)ceil(def->max_time * def->hz);
    z0 = def->edge / 2;
    world = make_world(def->gravity);
    plane = dCreatePlane(0, 0, 0, 1, 0);
    body = dBodyCreate(world);
    dMassSetBoxTotal(&mass, def->mass, def->edge, def->edge, def->edge);
    dBodySetMass(body, &mass);
    box = dCreateBox(0, def->edge, def->edge, def->edge);
    dGeomSetBody(box, body);
    dBodySetPosition(body, 0, 0, z0);
    dBodySetLinearVel(body, def->speed, 0, 0);
    group = dJointGroupCreate(0);

    for (n = 1; n <= steps; ++n) {
        dContactGeom g[4];
        const dReal *p, *v, *w;
        double wn;
        int nc = dCollide(box, plane, 4, g, sizeof g[0]);
        for (i = 0; i < nc; ++i) {
            dContact contact;
            memset(&contact, 0, sizeof contact);
            contact.surface.mode = dContactApprox1;
            contact.surface.mu = def->mu;
            contact.geom = g[i];
            dJointAttach(dJointCreateContact(world, group, &contact), body, 0);
        }
        dWorldStep(world, h);
        dJointGroupEmpty(group);
        p = dBodyGetPosition(body);
        v = dBodyGetLinearVel(body);
        w = dBodyGetAngularVel(body);
        out->steps = n;
        out->distance = sqrt(p[0] * p[0] + p[1] * p[1]);
        out->time = n * h;
        if (fabs(p[2] - z0) > out->max_height_change)
            out->max_height_change = fabs(p[2] - z0);
        wn = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        if (wn > out->max_angular_speed)
            out->max_angular_speed = wn;
        if (v[0] <= def->stop_speed) {
            out->stopped = 1;
            break;
        }
    }

    dJointGroupDestroy(group);
    dGeomDestroy(box);
    dGeomDestroy(plane);
    dBodyDestroy(body);
    dWorldDestroy(world);
    dCloseODE();
    return 1;
}

double ode_slide_distance(double hz, double speed, double mu)
{
    ode_slide_def def = ode_default_slide_def();
    ode_slide_result r;

    def.hz = hz;
    def.speed = speed;
    def.mu = mu;
    if (!ode_slide_run(&def, &r) || !r.stopped)
        return NAN;
    return r.distance;
}

/* --------------------------------------------------------------- pyramid -- */

ode_pyramid_def ode_default_pyramid_def(void)
{
    ode_pyramid_def d;
    d.levels = 20;
    d.edge = 1;
    d.mass = 1;
    d.gap = 0.01;
    d.hz = 60;
    d.iterations = 20;
    d.mu = 0.6;
    d.max_contacts = 4;
    d.gravity = 9.81;
    d.duration = 10;
    d.auto_disable = 0;
    return d;
}

int ode_pyramid_boxes(int levels)
{
    return levels > 0 && levels <= 10000 ? levels * (levels + 1) / 2 : 0;
}

static int pyramid_def_ok(const ode_pyramid_def *d)
{
    return ode_pyramid_boxes(d->levels) > 0 && finite_positive(d->edge) &&
           finite_positive(d->mass) && isfinite(d->gap) && d->gap >= 0 &&
           finite_positive(d->hz) && d->iterations > 0 && isfinite(d->mu) && d->mu >= 0 &&
           d->max_contacts > 0 && d->max_contacts <= NEAR_MAX && isfinite(d->gravity) &&
           finite_positive(d->duration) && d->duration * d->hz <= 1e8;
}

int ode_pyramid_positions(const ode_pyramid_def *def, double (*pos)[3])
{
    int i, j, k = 0;

    if (!pyramid_def_ok(def))
        return 0;
    for (i = 0; i < def->levels; ++i) {
        const int row = def->levels - i;
        for (j = 0; j < row; ++j, ++k) {
            pos[k][0] = (j - 0.5 * (row - 1)) * (def->edge + def->gap);
            pos[k][1] = 0;
            pos[k][2] = 0.5 * def->edge + i * def->edge;
        }
    }
    return k;
}

int ode_pyramid(const ode_pyramid_def *def, ode_pyramid_result *out)
{
    dWorldID world;
    dSpaceID space;
    dBodyID *bodies;
    double(*pos)[3];
    double *step_ms;
    dMass mass;
    double h;
    int count, steps, i;

    memset(out, 0, sizeof *out);
    if (!pyramid_def_ok(def))
        return 0;
    count = ode_pyramid_boxes(def->levels);
    steps = (int)ceil(def->duration * def->hz);
    pos = malloc((size_t)count * sizeof *pos);
    bodies = malloc((size_t)count * sizeof *bodies);
    step_ms = malloc((size_t)steps * sizeof *step_ms);
    if (!pos || !bodies || !step_ms || !ode_open()) {
        free(pos);
        free(bodies);
        free(step_ms);
        return 0;
    }
    ode_pyramid_positions(def, pos);

    h = 1 / def->hz;
    world = quick_world(def->gravity, def->iterations, &space);
    if (def->auto_disable)
        dWorldSetAutoDisableFlag(world, 1); /* (new bodies take the flag) */
    dMassSetBoxTotal(&mass, def->mass, def->edge, def->edge, def->edge);
    for (i = 0; i < count; ++i) {
        dGeomID g = dCreateBox(space, def->edge, def->edge, def->edge);
        bodies[i] = dBodyCreate(world);
        dBodySetMass(bodies[i], &mass);
        dGeomSetBody(g, bodies[i]);
        dBodySetPosition(bodies[i], pos[i][0], pos[i][1], pos[i][2]);
    }
    run_quick(world, space, def->mu, def->max_contacts, h, steps, step_ms, &out->timing);

    out->boxes = count;
    for (i = 0; i < count; ++i) {
        const dReal *p = dBodyGetPosition(bodies[i]);
        const double d[3] = { p[0] - pos[i][0], p[1] - pos[i][1], p[2] - pos[i][2] };
        const double dist = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (dist > out->max_displacement)
            out->max_displacement = dist;
        if (i == count - 1) {
            out->top_sink = -d[2];
            out->top_drift = sqrt(d[0] * d[0] + d[1] * d[1]);
        }
    }

    /* The space destroys its geoms (cleanup mode is on by default). */
    dSpaceDestroy(space);
    dWorldDestroy(world);
    dCloseODE();
    free(pos);
    free(bodies);
    free(step_ms);
    return 1;
}

/* ------------------------------------------------------------------ pile -- */

ode_pile_def ode_default_pile_def(void)
{
    ode_pile_def d;
    d.count = 1000;
    d.seed = 1;
    d.grid = 10;
    d.spacing = 1.2;
    d.base = 1;
    d.density = 1000;
    d.hz = 60;
    d.iterations = 20;
    d.mu = 0.6;
    d.max_contacts = 4;
    d.gravity = 9.81;
    d.steps = 600;
    d.copies = 1;
    d.copy_pitch = 15;
    return d;
}

void ode_pile_copy_offset(const ode_pile_def *def, int k, double offset[2])
{
    const int side = (int)ceil(sqrt((double)def->copies));
    offset[0] = (k % side - 0.5 * (side - 1)) * def->copy_pitch;
    offset[1] = (k / side - 0.5 * (side - 1)) * def->copy_pitch;
}

static int pile_def_ok(const ode_pile_def *d)
{
    return d->copies >= 1 && d->copies <= 1024 && isfinite(d->copy_pitch) && d->copy_pitch >= 0 &&
           d->count > 0 && d->count <= 10000000 / d->copies && d->grid > 0 && d->grid <= 100000 &&
           finite_positive(d->spacing) && isfinite(d->base) && finite_positive(d->density) &&
           finite_positive(d->hz) && d->iterations > 0 && isfinite(d->mu) && d->mu >= 0 &&
           d->max_contacts > 0 && d->max_contacts <= NEAR_MAX && isfinite(d->gravity) &&
           d->steps > 0;
}

/* Knuth's MMIX constants; the top 53 bits are the best of an LCG's. */
static double lcg_uniform(uint64_t *state)
{
    *state = *state * UINT64_C(6364136223846793005) + UINT64_C(1442695040888963407);
    return (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}

int ode_pile_scene(const ode_pile_def *def, ode_shape *shapes)
{
    uint64_t state;
    int b, k;

    if (!pile_def_ok(def))
        return 0;
    state = def->seed;
    for (b = 0; b < def->count; ++b) {
        ode_shape *s = &shapes[b];
        const int per_layer = def->grid * def->grid;
        const double centre = 0.5 * (def->grid - 1);
        const double rho = def->density;
        double u[7], a, c, t1, t2;

        for (k = 0; k < 7; ++k)
            u[k] = lcg_uniform(&state);
        memset(s, 0, sizeof *s);
        s->kind = (ode_shape_kind)(int)(3 * u[0]);
        if (s->kind == ODE_SHAPE_SPHERE) {
            const double r = 0.5 * (0.2 + 0.4 * u[1]);
            s->radius = r;
            s->mass = 4.0 / 3.0 * PI * r * r * r * rho;
            s->inertia[0] = s->inertia[1] = s->inertia[2] = 0.4 * s->mass * r * r;
        } else if (s->kind == ODE_SHAPE_BOX) {
            const double lx = 0.2 + 0.4 * u[1], ly = 0.2 + 0.4 * u[2], lz = 0.2 + 0.4 * u[3];
            s->half[0] = 0.5 * lx;
            s->half[1] = 0.5 * ly;
            s->half[2] = 0.5 * lz;
            s->mass = rho * lx * ly * lz;
            s->inertia[0] = s->mass * (ly * ly + lz * lz) / 12;
            s->inertia[1] = s->mass * (lx * lx + lz * lz) / 12;
            s->inertia[2] = s->mass * (lx * lx + ly * ly) / 12;
        } else {
            const double r = 0.5 * (0.2 + 0.2 * u[1]), l = 0.2 + 0.4 * u[2];
            const double m1 = PI * r * r * l * rho, m2 = 4.0 / 3.0 * PI * r * r * r * rho;
            s->radius = r;
            s->half[2] = 0.5 * l;
            s->mass = m1 + m2;
            s->inertia[0] = s->inertia[1] = m1 * (0.25 * r * r + l * l / 12) +
                                            m2 * (0.4 * r * r + 0.375 * r * l + 0.25 * l * l);
            s->inertia[2] = (0.5 * m1 + 0.4 * m2) * r * r;
        }
        a = sqrt(1 - u[4]);
        c = sqrt(u[4]);
        t1 = 2 * PI * u[5];
        t2 = 2 * PI * u[6];
        s->orientation[0] = c * cos(t2);
        s->orientation[1] = a * sin(t1);
        s->orientation[2] = a * cos(t1);
        s->orientation[3] = c * sin(t2);
        s->position[0] = (b % def->grid - centre) * def->spacing;
        s->position[1] = (b / def->grid % def->grid - centre) * def->spacing;
        s->position[2] = def->base + (b / per_layer) * def->spacing;
    }
    return def->count;
}

int ode_pile(const ode_pile_def *def, ode_pile_result *out)
{
    dWorldID world;
    dSpaceID space;
    dBodyID *bodies;
    ode_shape *shapes;
    double *step_ms;
    double h;
    int i;

    memset(out, 0, sizeof *out);
    if (!pile_def_ok(def))
        return 0;
    shapes = malloc((size_t)def->count * sizeof *shapes);
    bodies = malloc((size_t)def->count * (size_t)def->copies * sizeof *bodies);
    step_ms = malloc((size_t)def->steps * sizeof *step_ms);
    if (!shapes || !bodies || !step_ms || !ode_open()) {
        free(shapes);
        free(bodies);
        free(step_ms);
        return 0;
    }
    ode_pile_scene(def, shapes);

    h = 1 / def->hz;
    world = quick_world(def->gravity, def->iterations, &space);
    for (i = 0; i < def->count * def->copies; ++i) {
        const ode_shape *s = &shapes[i % def->count];
        double offset[2];
        dGeomID g;
        dMass mass;
        dQuaternion q;
        ode_pile_copy_offset(def, i / def->count, offset);
        if (s->kind == ODE_SHAPE_SPHERE)
            g = dCreateSphere(space, s->radius);
        else if (s->kind == ODE_SHAPE_BOX)
            g = dCreateBox(space, 2 * s->half[0], 2 * s->half[1], 2 * s->half[2]);
        else
            g = dCreateCapsule(space, s->radius, 2 * s->half[2]);
        bodies[i] = dBodyCreate(world);
        dMassSetParameters(&mass, s->mass, 0, 0, 0, s->inertia[0], s->inertia[1],
                           s->inertia[2], 0, 0, 0);
        dBodySetMass(bodies[i], &mass);
        dGeomSetBody(g, bodies[i]);
        dBodySetPosition(bodies[i], s->position[0] + offset[0], s->position[1] + offset[1], s->position[2]);
        q[0] = s->orientation[0];
        q[1] = s->orientation[1];
        q[2] = s->orientation[2];
        q[3] = s->orientation[3];
        dBodySetQuaternion(bodies[i], q);
    }
    run_quick(world, space, def->mu, def->max_contacts, h, def->steps, step_ms, &out->timing);

    out->final_top = -INFINITY;
    for (i = 0; i < def->count * def->copies; ++i) {
        const dReal *p = dBodyGetPosition(bodies[i]), *v = dBodyGetLinearVel(bodies[i]);
        const double speed = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (speed > out->final_max_speed)
            out->final_max_speed = speed;
        out->final_moving += speed > 0.1;
        if (p[2] > out->final_top)
            out->final_top = p[2];
    }

    dSpaceDestroy(space);
    dWorldDestroy(world);
    dCloseODE();
    free(shapes);
    free(bodies);
    free(step_ms);
    return 1;
}

/* --------------------------------------------------------- heavy landing -- */

ode_heavy_def ode_default_heavy_def(void)
{
    ode_heavy_def d;
    d.ratio = 100;
    d.under = 0;
    d.gap = 0.5;
    d.hz = 60;
    d.iterations = 20;
    d.steps = 600;
    d.gravity = 9.81;
    return d;
}

#define HEAVY_MAX_UNDER 16

int ode_heavy_landing(const ode_heavy_def *def, ode_heavy_result *out)
{
    dWorldID world;
    dSpaceID space;
    dBodyID bodies[HEAVY_MAX_UNDER + 2];
    near_ctx c;
    const int n = def->under + 2;
    const double top = 1.5 + def->under;
    int i, k, landed = 0;

    memset(out, 0, sizeof *out);
    if (!(finite_positive(def->ratio) && def->under >= 0 && def->under <= HEAVY_MAX_UNDER && isfinite(def->gap) &&
          def->gap >= 0 && finite_positive(def->hz) && def->iterations > 0 && def->steps > 0 &&
          isfinite(def->gravity)) ||
        !ode_open())
        return 0;
    world = quick_world(def->gravity, def->iterations, &space);
    for (i = 0; i < n; ++i) {
        dMass mass;
        dGeomID g = dCreateBox(space, 1, 1, 1);
        bodies[i] = dBodyCreate(world);
        dMassSetBoxTotal(&mass, i == n - 1 ? def->ratio : 1, 1, 1, 1);
        dBodySetMass(bodies[i], &mass);
        dGeomSetBody(g, bodies[i]);
        dBodySetPosition(bodies[i], 0, 0, 0.5 + i + (i == n - 1 ? def->gap : 0));
    }
    c.world = world;
    c.group = dJointGroupCreate(0);
    c.mu = 0.6;
    c.max_contacts = 4;
    for (k = 0; k < def->steps; ++k) {
        const dReal *p, *v;
        c.contacts = 0;
        dSpaceCollide(space, &c, near_callback);
        dWorldQuickStep(world, 1 / def->hz);
        dJointGroupEmpty(c.group);
        p = dBodyGetPosition(bodies[n - 1]);
        v = dBodyGetLinearVel(bodies[n - 1]);
        landed |= p[2] < top + 0.01;
        if (landed && v[2] > out->rebound)
            out->rebound = v[2];
        out->end = p[2] - top;
        for (i = 0; i < n - 1; ++i) {
            const double below = 0.5 + i - dBodyGetPosition(bodies[i])[2];
            if (below > out->sink)
                out->sink = below;
        }
    }
    dJointGroupDestroy(c.group);
    dSpaceDestroy(space);
    dWorldDestroy(world);
    dCloseODE();
    return 1;
}

/* ------------------------------------------------------------- ragdolls -- */

ode_ragdoll_def ode_default_ragdoll_def(void)
{
    ode_ragdoll_def d;
    d.count = 20;
    d.hz = 60;
    d.iterations = 20;
    d.steps = 360;
    d.gravity = 9.81;
    return d;
}

/* The near callback of the ragdolls: no contacts between bodies a joint
   holds (tumble's default, collide 0) */
static void ragdoll_near(void *data, dGeomID a, dGeomID b)
{
    dBodyID ba = dGeomGetBody(a), bb = dGeomGetBody(b);
    if (ba && bb && dAreConnectedExcluding(ba, bb, dJointTypeContact))
        return;
    near_callback(data, a, b);
}

/* A quaternion turning z onto the axis from p to q (apart along one axis) */
static void capsule_turn(const double p[3], const double q[3], dQuaternion out)
{
    const double h = sqrt(0.5);
    out[0] = 1, out[1] = out[2] = out[3] = 0;
    if (q[0] != p[0])
        out[0] = h, out[2] = h;
    else if (q[1] != p[1])
        out[0] = h, out[1] = -h;
}

int ode_ragdolls(const ode_ragdoll_def *def, ode_ragdoll_result *out)
{
    const int bones = def ? def->count * REF_RAGDOLL_BONES : 0, joints = def ? def->count * REF_RAGDOLL_JOINTS : 0;
    dWorldID world;
    dSpaceID space;
    dBodyID *body;
    dJointID *joint;
    ref_bone *bone;
    near_ctx c;
    double sum = 0, h;
    int i, k, n;

    memset(out, 0, sizeof *out);
    if (!def || def->count < 1 || def->count > 1000 || !finite_positive(def->hz) || def->iterations < 0 ||
        def->steps < 1 || !finite_positive(def->gravity))
        return 0;
    body = malloc((size_t)bones * sizeof *body);
    joint = malloc((size_t)joints * sizeof *joint);
    bone = malloc((size_t)bones * sizeof *bone);
    if (!body || !joint || !bone || !ode_open()) {
        free(body);
        free(joint);
        free(bone);
        return 0;
    }
    h = 1 / def->hz;
    world = quick_world(def->gravity, def->iterations ? def->iterations : 20, &space);
    for (i = 0; i < def->count; ++i) {
        ref_ragdoll_joint js[REF_RAGDOLL_JOINTS];
        double at[3];
        ref_ragdoll_place(i, at);
        ref_ragdoll(at[0], at[1], at[2], bone + i * REF_RAGDOLL_BONES, js);
        for (k = 0; k < REF_RAGDOLL_BONES; ++k) {
            const ref_bone *b = &bone[i * REF_RAGDOLL_BONES + k];
            const double l = ref_bone_length(b);
            dBodyID id = dBodyCreate(world);
            dGeomID g = dCreateCapsule(space, b->radius, l);
            dMass mass;
            dQuaternion q;
            dMassSetCapsuleTotal(&mass, b->mass, 3, b->radius, l);
            dBodySetMass(id, &mass);
            dGeomSetBody(g, id);
            dBodySetPosition(id, (b->p[0] + b->q[0]) / 2, (b->p[1] + b->q[1]) / 2, (b->p[2] + b->q[2]) / 2);
            capsule_turn(b->p, b->q, q);
            dBodySetQuaternion(id, q);
            body[i * REF_RAGDOLL_BONES + k] = id;
        }
        for (k = 0; k < REF_RAGDOLL_JOINTS; ++k) {
            const ref_ragdoll_joint *r = &js[k];
            dBodyID a = body[i * REF_RAGDOLL_BONES + r->a], b = body[i * REF_RAGDOLL_BONES + r->b];
            dJointID j = r->hinge ? dJointCreateHinge(world, 0) : dJointCreateBall(world, 0);
            dJointAttach(j, a, b);
            if (r->hinge) {
                dJointSetHingeAnchor(j, r->anchor[0], r->anchor[1], r->anchor[2]);
                dJointSetHingeAxis(j, r->axis[0], r->axis[1], r->axis[2]);
                dJointSetHingeParam(j, dParamLoStop, r->lower);
                dJointSetHingeParam(j, dParamHiStop, r->upper);
            } else {
                dJointSetBallAnchor(j, r->anchor[0], r->anchor[1], r->anchor[2]);
            }
            joint[i * REF_RAGDOLL_JOINTS + k] = j;
        }
    }
    c.world = world;
    c.group = dJointGroupCreate(0);
    c.mu = 0.8;
    c.max_contacts = 4;
    out->finite = 1;
    for (n = 0; n < def->steps; ++n) {
        const double t0 = seconds();
        c.contacts = 0;
        dSpaceCollide(space, &c, ragdoll_near);
        if (def->iterations)
            dWorldQuickStep(world, h);
        else
            dWorldStep(world, h);
        dJointGroupEmpty(c.group);
        sum += seconds() - t0;
        for (k = 0; k < joints; ++k) {
            dVector3 p, q;
            double d;
            if (dJointGetType(joint[k]) == dJointTypeHinge) {
                dJointGetHingeAnchor(joint[k], p);
                dJointGetHingeAnchor2(joint[k], q);
            } else {
                dJointGetBallAnchor(joint[k], p);
                dJointGetBallAnchor2(joint[k], q);
            }
            d = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
            if (!(d <= out->gap))
                out->gap = isfinite(d) ? d : INFINITY;
        }
        for (k = 0; k < bones; ++k) {
            const dReal *x = dBodyGetPosition(body[k]), *R = dBodyGetRotation(body[k]);
            const ref_bone *b = &bone[k];
            const double l = ref_bone_length(b);
            const double low = x[2] - fabs(R[10]) * l / 2 - b->radius; /* (R[10]: z of the body's z) */
            if (!isfinite(low))
                out->finite = 0;
            else if (-low > out->deepest)
                out->deepest = -low;
        }
    }
    for (k = 0; k < bones; ++k) {
        const dReal *v = dBodyGetLinearVel(body[k]), *w = dBodyGetAngularVel(body[k]);
        dMass m;
        dBodyGetMass(body[k], &m);
        out->kinetic += 0.5 * m.mass * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        {   /* w.I.w with I in the world: R I_body R^T */
            const dReal *R = dBodyGetRotation(body[k]);
            double wb[3], e = 0;
            int a2, b2;
            for (a2 = 0; a2 < 3; ++a2)
                wb[a2] = R[a2] * w[0] + R[4 + a2] * w[1] + R[8 + a2] * w[2];
            for (a2 = 0; a2 < 3; ++a2)
                for (b2 = 0; b2 < 3; ++b2)
                    e += wb[a2] * m.I[4 * a2 + b2] * wb[b2];
            out->kinetic += 0.5 * e;
        }
    }
    out->ms_mean = 1e3 * sum / def->steps;
    dJointGroupDestroy(c.group);
    dSpaceDestroy(space);
    dWorldDestroy(world);
    free(body);
    free(joint);
    free(bone);
    return 1;
}
