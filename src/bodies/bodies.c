/* bodies.c: rigid bodies. State (x, q, P, L) lives in the world's state
   vector; mass, principal moments, damping and held forces beside it. This
   file adds, reads, changes and removes bodies and applies forces to them;
   body_step.c moves them. */
#include "bodies/bodies.h"

#include <math.h>
#include <string.h>

/* L = I w for body s at its orientation. A zero comes out as +0, as it
   does in P: every update keeps it so (x + y is -0 only when both are),
   which lets the kicks leave alone the components no force reaches and
   still give the bits of P + h 0 and L + h 0
   (test_rotation.fast_paths_give_the_general_bits). */
static void spin_of(const double q[4], const double inertia[3], const double omega[3], double L[3])
{
    tb__through_inertia(q, inertia, omega, L);
    L[0] += 0.0, L[1] += 0.0, L[2] += 0.0;
}

/* ---- definitions and validation ------------------------------------------ */

tb_body_def tb_default_body_def(void)
{
    tb_body_def def;
    memset(&def, 0, sizeof def);
    def.orientation[0] = 1;
    def.mass.mass = 1;
    def.mass.inertia[0] = def.mass.inertia[1] = def.mass.inertia[2] = 0.1; /* 2/5 m r^2, r = 0.5 m */
    def.mass.frame[0] = 1;
    return def;
}

static int finite_n(const double *v, int n)
{
    int i;
    for (i = 0; i < n; ++i)
        if (!isfinite(v[i]))
            return 0;
    return 1;
}

/* A quaternion that is unit within 1e-6 (users type them by hand). */
static tb_status check_unit(tb_world *w, const double q[4], const char *what)
{
    double n;
    if (!finite_n(q, 4))
        return tb__fail(w, TB_ERR_ARGUMENT, "%s must be finite", what);
    n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(fabs(n - 1) <= 1e-6))
        return tb__fail(w, TB_ERR_ARGUMENT, "%s must be a unit quaternion (w, x, y, z); its norm is %g", what, n);
    return TB_OK;
}

static tb_status check_mass(tb_world *w, const tb_mass *m)
{
    const double *I = m->inertia;
    tb_status st;
    if ((st = tb__check_scale(w, m->mass, "body mass")) != TB_OK)
        return st;
    if (!tb__in_scale(I[0]) || !tb__in_scale(I[1]) || !tb__in_scale(I[2]))
        return tb__fail(w, TB_ERR_ARGUMENT,
                        "body moments of inertia must be finite and > 0, from %g to %g (got %g, %g, %g)",
                        1 / TB_LIMIT, TB_LIMIT, I[0], I[1], I[2]);
    /* A real mass distribution has I1 + I2 >= I3 for every order (equality
       for a flat plate); allow rounding. */
    if (I[0] + I[1] < I[2] * (1 - 1e-12) || I[1] + I[2] < I[0] * (1 - 1e-12) || I[0] + I[2] < I[1] * (1 - 1e-12))
        return tb__fail(w, TB_ERR_ARGUMENT,
                        "body moments of inertia %g, %g, %g break the triangle inequality: no body has them",
                        I[0], I[1], I[2]);
    if ((st = tb__check_values(w, m->centre, 3, "body centre of mass")) != TB_OK)
        return st;
    if ((st = check_unit(w, m->frame, "body mass frame")) != TB_OK)
        return st;
    return TB_OK;
}

static tb_status check_def(tb_world *w, const tb_body_def *def)
{
    tb_status st;
    if (!def)
        return tb__fail(w, TB_ERR_ARGUMENT, "body definition must not be NULL");
    if ((st = tb__check_values(w, def->position, 3, "body position")) != TB_OK ||
        (st = tb__check_values(w, def->velocity, 3, "body velocity")) != TB_OK ||
        (st = tb__check_values(w, def->angular_velocity, 3, "body angular velocity")) != TB_OK)
        return st;
    if ((st = check_unit(w, def->orientation, "body orientation")) != TB_OK)
        return st;
    if ((st = check_mass(w, &def->mass)) != TB_OK)
        return st;
    if ((st = tb__check_coefficient(w, def->linear_damping, "body linear damping")) != TB_OK ||
        (st = tb__check_coefficient(w, def->angular_damping, "body angular damping")) != TB_OK)
        return st;
    return TB_OK;
}

static double largest(const double v[3])
{
    return fmax(fabs(v[0]), fmax(fabs(v[1]), fabs(v[2])));
}

/* What a body of mass m moving with momentum P has (the input rule,
   TB_LIMIT): P itself and the kinetic energy |P|^2 / 2m. */
static tb_status check_linear(tb_world *w, double m, const double P[3])
{
    tb_status st = tb__check_derived(w, largest(P), "body momentum m v", "kg m/s");
    return st != TB_OK ? st : tb__check_derived(w, 0.5 * tb__dot3(P, P) / m, "body kinetic energy m v^2 / 2", "J");
}

/* ... and what a body of principal moments I at the unit orientation q
   has with angular momentum L: L itself and the energy w.L / 2. */
static tb_status check_angular(tb_world *w, const double I[3], const double q[4], const double L[3])
{
    double inv[3], omega[3];
    int k;
    tb_status st = tb__check_derived(w, largest(L), "body angular momentum I w", "kg m^2/s");
    if (st != TB_OK)
        return st;
    for (k = 0; k < 3; ++k)
        inv[k] = 1 / I[k];
    tb__through_inertia(q, inv, L, omega);
    return tb__check_derived(w, 0.5 * tb__dot3(L, omega), "body rotational energy w.I.w / 2", "J");
}

/* ---- adding and removing ----------------------------------------------------- */

#define BODY_ARRAYS 15
static void arrays_of(tb_world *w, void **arrays[BODY_ARRAYS], size_t sizes[BODY_ARRAYS])
{
    arrays[0] = (void **)&w->body_mass;        sizes[0] = sizeof(double);
    arrays[1] = (void **)&w->body_inv_mass;    sizes[1] = sizeof(double);
    arrays[2] = (void **)&w->body_inertia;     sizes[2] = 3 * sizeof(double);
    arrays[3] = (void **)&w->body_inv_inertia; sizes[3] = 3 * sizeof(double);
    arrays[4] = (void **)&w->body_damping;     sizes[4] = 2 * sizeof(double);
    arrays[5] = (void **)&w->body_applied;     sizes[5] = 6 * sizeof(double);
    arrays[6] = (void **)&w->body_force;       sizes[6] = 6 * sizeof(double);
    arrays[7] = (void **)&w->body_motion;      sizes[7] = 6 * sizeof(double);
    arrays[8] = (void **)&w->body_frame;       sizes[8] = sizeof(tb__split_frame);
    arrays[9] = (void **)&w->body_rest;        sizes[9] = sizeof(double);
    arrays[10] = (void **)&w->body_island;     sizes[10] = sizeof(uint32_t);
    arrays[11] = (void **)&w->body_lane_frame[0]; sizes[11] = sizeof(double);
    arrays[12] = (void **)&w->body_lane_frame[1]; sizes[12] = sizeof(double);
    arrays[13] = (void **)&w->body_lane_frame[2]; sizes[13] = sizeof(double);
    arrays[14] = (void **)&w->body_lane_frame[3]; sizes[14] = sizeof(double);
}

static tb_status grow(tb_world *w)
{
    size_t cap = w->body_cap ? 2 * w->body_cap : 8;
    void **arrays[BODY_ARRAYS];
    size_t sizes[BODY_ARRAYS];
    tb_status st;
    arrays_of(w, arrays, sizes);
    if ((st = tb__ids_reserve(w, &w->body_ids, cap)) != TB_OK)
        return st;
    if ((st = tb__state_resize(w, TB__BODIES, cap)) != TB_OK)
        return st;
    if ((st = tb__grow(w, arrays, sizes, BODY_ARRAYS, w->body_count, w->body_cap, cap)) != TB_OK)
        return st;
    w->body_cap = cap;
    return TB_OK;
}

void tb__bodies_free(tb_world *w)
{
    void **arrays[BODY_ARRAYS];
    size_t sizes[BODY_ARRAYS];
    arrays_of(w, arrays, sizes);
    tb__free_arrays(w, arrays, sizes, BODY_ARRAYS, w->body_cap);
    tb__ids_free(w, &w->body_ids);
    w->body_count = w->body_cap = w->body_damped = w->body_isotropic = 0;
    w->body_held = 0;
}

static double *at(const tb_world *w, enum tb__quantity q, size_t width, uint32_t slot)
{
    return w->y + w->off[q] + width * slot;
}

tb_status tb_world_add_body(tb_world *w, const tb_body_def *def, tb_body_id *id)
{
    tb_status st;
    uint32_t s;
    tb_body_id made;
    double R[9], c[3], q[4], x[3], P[3], L[3];
    int k;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "add a body")) != TB_OK)
        return st;
    if ((st = check_def(w, def)) != TB_OK)
        return st;
    /* the centre of mass and the principal axes, placed by the shape pose */
    memcpy(q, def->orientation, sizeof q);
    tb__normalise(q);
    tb__matrix_of(q, R);
    tb__mul(R, def->mass.centre, c);
    for (k = 0; k < 3; ++k)
        x[k] = def->position[k] + c[k];
    {
        double frame[4];
        memcpy(frame, def->mass.frame, sizeof frame);
        tb__normalise(frame);
        tb__quat_mul(q, frame, q);
        tb__normalise(q);
    }
    for (k = 0; k < 3; ++k)
        P[k] = def->mass.mass * def->velocity[k] + 0.0; /* +0: see spin_of */
    spin_of(q, def->mass.inertia, def->angular_velocity, L);
    if ((st = tb__check_values(w, x, 3, "body centre of mass, placed,")) != TB_OK ||
        (st = check_linear(w, def->mass.mass, P)) != TB_OK ||
        (st = check_angular(w, def->mass.inertia, q, L)) != TB_OK)
        return st;
    if (w->body_count == w->body_cap && (st = grow(w)) != TB_OK)
        return st;
    s = (uint32_t)w->body_count++;
    memcpy(at(w, TB__BODY_POS, 3, s), x, sizeof x);
    memcpy(at(w, TB__BODY_ROT, 4, s), q, sizeof q);
    memcpy(at(w, TB__BODY_MOM, 3, s), P, sizeof P);
    memcpy(at(w, TB__BODY_ANG, 3, s), L, sizeof L);
    w->body_mass[s] = def->mass.mass;
    w->body_inv_mass[s] = 1 / def->mass.mass;
    for (k = 0; k < 3; ++k) {
        w->body_inertia[3 * s + k] = def->mass.inertia[k];
        w->body_inv_inertia[3 * s + k] = 1 / def->mass.inertia[k];
    }
    tb__split_frame_of(w->body_inv_inertia + 3 * s, &w->body_frame[s]);
    tb__lane_frame_of(w->body_inv_inertia + 3 * s, &w->body_lane_frame[0][s], &w->body_lane_frame[1][s],
                      &w->body_lane_frame[2][s], &w->body_lane_frame[3][s]);
    w->body_isotropic += w->body_frame[s].isotropic;
    w->body_damping[2 * s] = def->linear_damping;
    w->body_damping[2 * s + 1] = def->angular_damping;
    w->body_damped += def->linear_damping != 0 || def->angular_damping != 0;
    memset(w->body_applied + 6 * s, 0, 6 * sizeof(double));
    w->body_rest[s] = 0;
    w->body_island[s] = 0;
    tb__ids_acquire(&w->body_ids, w->id_tag, s, &made.index1, &made.generation);
    if (id)
        *id = made;
    return TB_OK;
}

void tb__body_velocity(const tb_world *w, uint32_t s, double v[3], double wv[3])
{
    const double *P = w->y + w->off[TB__BODY_MOM] + 3 * s, *L = w->y + w->off[TB__BODY_ANG] + 3 * s;
    const double *inv = w->body_inv_inertia + 3 * s;
    double R[9], Lb[3];
    int k;
    for (k = 0; k < 3; ++k)
        v[k] = P[k] * w->body_inv_mass[s];
    tb__matrix_of(w->y + w->off[TB__BODY_ROT] + 4 * s, R);
    tb__mul_transposed(R, L, Lb);
    for (k = 0; k < 3; ++k)
        Lb[k] *= inv[k];
    tb__mul(R, Lb, wv);
}

void tb__wake_island(tb_world *w, uint32_t island)
{
    size_t s;
    for (s = 0; s < w->body_count; ++s)
        if (w->body_island[s] == island) {
            w->body_island[s] = 0;
            w->body_rest[s] = 0;
            w->body_sleeping--;
        }
}

void tb__wake_body(tb_world *w, uint32_t s)
{
    w->body_rest[s] = 0;
    if (w->body_island[s])
        tb__wake_island(w, w->body_island[s]);
}

void tb__wake_all(tb_world *w)
{
    size_t s;
    if (!w->body_sleeping)
        return;
    for (s = 0; s < w->body_count; ++s) {
        w->body_island[s] = 0;
        w->body_rest[s] = 0;
    }
    w->body_sleeping = 0;
}

tb_status tb__body_find(const tb_world *w, tb_body_id id, uint32_t *slot)
{
    if (!tb__ids_lookup(&w->body_ids, id.index1, id.generation, slot))
        return tb__fail((tb_world *)w, TB_ERR_STALE_ID, "body id %u.%u is null, removed or from another world",
                        id.index1, id.generation);
    return TB_OK;
}

tb_status tb_world_remove_body(tb_world *w, tb_body_id id)
{
    void **arrays[BODY_ARRAYS];
    size_t sizes[BODY_ARRAYS], k;
    uint32_t s, last;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "remove a body")) != TB_OK)
        return st;
    if ((st = tb__body_find(w, id, &s)) != TB_OK)
        return st;
    tb__wake_body(w, s); /* what it held up must fall */
    last = (uint32_t)w->body_count - 1;
    w->body_damped -= w->body_damping[2 * s] != 0 || w->body_damping[2 * s + 1] != 0;
    w->body_isotropic -= w->body_frame[s].isotropic;
    if (s != last) {
        arrays_of(w, arrays, sizes);
        for (k = 0; k < BODY_ARRAYS; ++k) {
            unsigned char *base = *arrays[k];
            memcpy(base + s * sizes[k], base + last * sizes[k], sizes[k]);
        }
        tb__state_move(w, TB__BODIES, last, s);
        tb__ids_move(&w->body_ids, last, s);
    }
    tb__ids_release(&w->body_ids, id.index1);
    w->body_count--;
    for (k = 0; k < 2; ++k)
        if (w->body_removed[k])
            w->body_removed[k](w, id.index1);
    return TB_OK;
}

/* ---- reading and writing ------------------------------------------------------ */

/* Getters share their checks: a world, a live id and somewhere to write. */
static tb_status readable(const tb_world *w, tb_body_id id, const void *out, const char *function, uint32_t *s)
{
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__body_find(w, id, s)) != TB_OK)
        return st;
    if (!out)
        return tb__null((tb_world *)w, function, "the output");
    return TB_OK;
}

tb_status tb_body_position(const tb_world *w, tb_body_id id, double position[3])
{
    uint32_t s;
    tb_status st = readable(w, id, position, "tb_body_position", &s);
    if (st == TB_OK)
        memcpy(position, at(w, TB__BODY_POS, 3, s), 3 * sizeof(double));
    return st;
}

tb_status tb_body_orientation(const tb_world *w, tb_body_id id, double orientation[4])
{
    uint32_t s;
    tb_status st = readable(w, id, orientation, "tb_body_orientation", &s);
    if (st == TB_OK)
        memcpy(orientation, at(w, TB__BODY_ROT, 4, s), 4 * sizeof(double));
    return st;
}

tb_status tb_body_velocity(const tb_world *w, tb_body_id id, double velocity[3])
{
    uint32_t s;
    tb_status st = readable(w, id, velocity, "tb_body_velocity", &s);
    int k;
    if (st == TB_OK)
        for (k = 0; k < 3; ++k)
            velocity[k] = at(w, TB__BODY_MOM, 3, s)[k] * w->body_inv_mass[s];
    return st;
}

tb_status tb_body_angular_velocity(const tb_world *w, tb_body_id id, double angular_velocity[3])
{
    uint32_t s;
    tb_status st = readable(w, id, angular_velocity, "tb_body_angular_velocity", &s);
    if (st == TB_OK)
        tb__through_inertia(at(w, TB__BODY_ROT, 4, s), w->body_inv_inertia + 3 * s, at(w, TB__BODY_ANG, 3, s),
                        angular_velocity);
    return st;
}

tb_status tb_body_momentum(const tb_world *w, tb_body_id id, double linear[3], double angular[3])
{
    uint32_t s;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    st = tb__body_find(w, id, &s);
    if (st == TB_OK && linear)
        memcpy(linear, at(w, TB__BODY_MOM, 3, s), 3 * sizeof(double));
    if (st == TB_OK && angular)
        memcpy(angular, at(w, TB__BODY_ANG, 3, s), 3 * sizeof(double));
    return st;
}

tb_status tb_body_mass(const tb_world *w, tb_body_id id, double *mass, double inertia[3])
{
    uint32_t s;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    st = tb__body_find(w, id, &s);
    if (st == TB_OK && mass)
        *mass = w->body_mass[s];
    if (st == TB_OK && inertia)
        memcpy(inertia, w->body_inertia + 3 * s, 3 * sizeof(double));
    return st;
}

/* Setters share their checks: a world that is not stepping, a live id and
   n values within the input rule. */
static tb_status writable(tb_world *w, tb_body_id id, const double *v, int n, const char *what, uint32_t *s)
{
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    st = tb__check_busy(w, "set a body's state");
    if (st == TB_OK)
        st = tb__body_find(w, id, s);
    if (st == TB_OK)
        st = tb__check_values(w, v, (size_t)n, what);
    return st;
}

tb_status tb_body_set_position(tb_world *w, tb_body_id id, const double position[3])
{
    uint32_t s;
    tb_status st = writable(w, id, position, 3, "body position", &s);
    if (st == TB_OK) {
        memcpy(at(w, TB__BODY_POS, 3, s), position, 3 * sizeof(double));
        tb__wake_body(w, s);
    }
    return st;
}

/* Keeps the angular velocity: L is recomputed for the new orientation. */
tb_status tb_body_set_orientation(tb_world *w, tb_body_id id, const double orientation[4])
{
    uint32_t s;
    double omega[3], q[4], L[3];
    tb_status st = writable(w, id, orientation, 4, "body orientation", &s);
    if (st == TB_OK)
        st = check_unit(w, orientation, "body orientation");
    if (st != TB_OK)
        return st;
    tb__through_inertia(at(w, TB__BODY_ROT, 4, s), w->body_inv_inertia + 3 * s, at(w, TB__BODY_ANG, 3, s), omega);
    memcpy(q, orientation, sizeof q);
    tb__normalise(q);
    spin_of(q, w->body_inertia + 3 * s, omega, L);
    if ((st = check_angular(w, w->body_inertia + 3 * s, q, L)) != TB_OK)
        return st;
    memcpy(at(w, TB__BODY_ROT, 4, s), q, sizeof q);
    memcpy(at(w, TB__BODY_ANG, 3, s), L, sizeof L);
    tb__wake_body(w, s);
    return TB_OK;
}

tb_status tb_body_set_velocity(tb_world *w, tb_body_id id, const double velocity[3])
{
    uint32_t s;
    double P[3];
    int k;
    tb_status st = writable(w, id, velocity, 3, "body velocity", &s);
    if (st != TB_OK)
        return st;
    for (k = 0; k < 3; ++k)
        P[k] = w->body_mass[s] * velocity[k] + 0.0; /* +0: see spin_of */
    if ((st = check_linear(w, w->body_mass[s], P)) != TB_OK)
        return st;
    memcpy(at(w, TB__BODY_MOM, 3, s), P, sizeof P);
    tb__wake_body(w, s);
    return TB_OK;
}

tb_status tb_body_set_angular_velocity(tb_world *w, tb_body_id id, const double angular_velocity[3])
{
    uint32_t s;
    double L[3];
    tb_status st = writable(w, id, angular_velocity, 3, "body angular velocity", &s);
    if (st != TB_OK)
        return st;
    spin_of(at(w, TB__BODY_ROT, 4, s), w->body_inertia + 3 * s, angular_velocity, L);
    if ((st = check_angular(w, w->body_inertia + 3 * s, at(w, TB__BODY_ROT, 4, s), L)) != TB_OK)
        return st;
    memcpy(at(w, TB__BODY_ANG, 3, s), L, sizeof L);
    tb__wake_body(w, s);
    return TB_OK;
}

/* Add a force (NULL: none) and a torque to what body slot s holds for the
   next step, refusing sums past the input rule. */
static tb_status add_held(tb_world *w, uint32_t s, const double force[3], const double torque[3])
{
    double *held = w->body_applied + 6 * s, sum[6];
    tb_status st;
    int k;
    for (k = 0; k < 3; ++k) {
        sum[k] = force ? held[k] + force[k] : held[k];
        sum[3 + k] = held[3 + k] + torque[k];
    }
    if ((st = tb__check_derived(w, largest(torque), "torque of the force", "N m")) != TB_OK ||
        (st = tb__check_derived(w, largest(sum), "force held for the next step", "N")) != TB_OK ||
        (st = tb__check_derived(w, largest(sum + 3), "torque held for the next step", "N m")) != TB_OK)
        return st;
    memcpy(held, sum, sizeof sum);
    w->body_held = 1;
    tb__wake_body(w, s);
    return TB_OK;
}

static tb_status hold(tb_world *w, tb_body_id id, const double force[3], const double point[3], int body_frame)
{
    uint32_t s;
    double r[3], tau[3];
    int k;
    tb_status st = writable(w, id, force, 3, "force", &s);
    if (st == TB_OK)
        st = tb__check_values(w, point, 3, "the point of a force");
    if (st != TB_OK)
        return st;
    if (body_frame) {
        double R[9];
        tb__matrix_of(at(w, TB__BODY_ROT, 4, s), R);
        tb__mul(R, point, r);
    } else {
        for (k = 0; k < 3; ++k)
            r[k] = point[k] - at(w, TB__BODY_POS, 3, s)[k];
    }
    tb__cross(r, force, tau);
    return add_held(w, s, force, tau);
}

tb_status tb_body_apply_force(tb_world *w, tb_body_id id, const double force[3], const double point[3])
{
    return hold(w, id, force, point, 0);
}

tb_status tb_body_apply_force_at_body_point(tb_world *w, tb_body_id id, const double force[3],
                                            const double body_point[3])
{
    return hold(w, id, force, body_point, 1);
}

tb_status tb_body_apply_torque(tb_world *w, tb_body_id id, const double torque[3])
{
    uint32_t s;
    tb_status st = writable(w, id, torque, 3, "torque", &s);
    return st != TB_OK ? st : add_held(w, s, NULL, torque);
}

size_t tb_world_body_count(const tb_world *w)
{
    TB__NEED_WORLD(w, 0);
    return w->body_count;
}

const double *tb_world_body_positions(const tb_world *w)
{
    TB__NEED_WORLD(w, NULL);
    return w->y ? w->y + w->off[TB__BODY_POS] : NULL;
}

const double *tb_world_body_orientations(const tb_world *w)
{
    TB__NEED_WORLD(w, NULL);
    return w->y ? w->y + w->off[TB__BODY_ROT] : NULL;
}

tb_body_id tb_world_body_at(const tb_world *w, size_t slot)
{
    tb_body_id id = { 0, 0 };
    if (w && slot < w->body_count)
        tb__ids_at(&w->body_ids, (uint32_t)slot, &id.index1, &id.generation);
    return id;
}

/* ---- diagnostics ----------------------------------------------------------------- */

void tb__body_energy_at(const tb_world *w, const double *y, size_t s, tb_energy *e)
{
    const double *x = y + w->off[TB__BODY_POS] + 3 * s, *q = y + w->off[TB__BODY_ROT] + 4 * s;
    const double *p = y + w->off[TB__BODY_MOM] + 3 * s, *l = y + w->off[TB__BODY_ANG] + 3 * s;
    const double *g = w->gravity;
    double omega[3];
    tb__through_inertia(q, w->body_inv_inertia + 3 * s, l, omega);
    e->kinetic += 0.5 * (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) * w->body_inv_mass[s];
    e->rotational += 0.5 * (l[0] * omega[0] + l[1] * omega[1] + l[2] * omega[2]);
    e->gravity -= w->body_mass[s] * (g[0] * x[0] + g[1] * x[1] + g[2] * x[2]);
}

void tb__body_energy(const tb_world *w, const double *y, tb_energy *e)
{
    size_t s;
    for (s = 0; s < w->body_count; ++s)
        tb__body_energy_at(w, y, s, e);
}

void tb__body_momenta(const tb_world *w, double linear[3], double angular[3])
{
    const double *x = w->y + w->off[TB__BODY_POS];
    const double *P = w->y + w->off[TB__BODY_MOM], *L = w->y + w->off[TB__BODY_ANG];
    size_t s;
    int k;
    for (s = 0; s < w->body_count; ++s) {
        double xp[3];
        tb__cross(x + 3 * s, P + 3 * s, xp);
        for (k = 0; k < 3; ++k) {
            linear[k] += P[3 * s + k];
            angular[k] += xp[k] + L[3 * s + k];
        }
    }
}
