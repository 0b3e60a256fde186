/* test_world.c: worlds, ids, allocation and bad input at the C API boundary.
   Every refusal must leave the world exactly as it was: the tests compare a
   fingerprint of the whole observable state before and after. */
#include "test_main.h"
#include "counting_alloc.h"
#include "tumble.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- a fingerprint of everything a user can observe --------------------- */

typedef struct fingerprint {
    double time, gravity[3];
    size_t particles, tracers, springs, bodies, shapes;
    double data[64];
    size_t n;
    char integrator[32];
} fingerprint;

static void take(const tb_world *w, fingerprint *f)
{
    size_t i, np = tb_world_particle_count(w), nt = tb_world_tracer_count(w);
    memset(f, 0, sizeof *f);
    f->time = tb_world_time(w);
    tb_world_gravity(w, f->gravity);
    f->particles = np;
    f->tracers = nt;
    f->springs = tb_world_spring_count(w);
    for (i = 0; i < 3 * np && f->n + 7 <= 64; i += 3) {
        memcpy(f->data + f->n, tb_world_particle_positions(w) + i, 3 * sizeof(double));
        memcpy(f->data + f->n + 3, tb_world_particle_velocities(w) + i, 3 * sizeof(double));
        f->data[f->n + 6] = tb_world_particle_masses(w)[i / 3];
        f->n += 7;
    }
    for (i = 0; i < 3 * nt && f->n + 3 <= 64; i += 3) {
        memcpy(f->data + f->n, tb_world_tracer_positions(w) + i, 3 * sizeof(double));
        f->n += 3;
    }
    f->bodies = tb_world_body_count(w);
    f->shapes = tb_world_shape_count(w);
    for (i = 0; i < f->bodies && f->n + 13 <= 64; ++i) {
        double v[3], omega[3];
        memcpy(f->data + f->n, tb_world_body_positions(w) + 3 * i, 3 * sizeof(double));
        memcpy(f->data + f->n + 3, tb_world_body_orientations(w) + 4 * i, 4 * sizeof(double));
        tb_body_velocity(w, tb_world_body_at(w, i), v);
        tb_body_angular_velocity(w, tb_world_body_at(w, i), omega);
        memcpy(f->data + f->n + 7, v, sizeof v);
        memcpy(f->data + f->n + 10, omega, sizeof omega);
        f->n += 13;
    }
    strncpy(f->integrator, tb_world_integrator(w), sizeof f->integrator - 1);
}

#define assert_unchanged(w, before)                                     \
    do {                                                                \
        fingerprint after_;                                             \
        take((w), &after_);                                             \
        assert_memory_equal(&(before), &after_, sizeof after_);         \
    } while (0)

static tb_world *make_world(const char *integrator)
{
    tb_world_def def = tb_default_world_def();
    tb_world *w = NULL;
    def.integrator = integrator;
    assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
    return w;
}

static tb_particle_id add_particle(tb_world *w, double x, double vx, double mass)
{
    tb_particle_def def = tb_default_particle_def();
    tb_particle_id id;
    def.position[0] = x;
    def.velocity[0] = vx;
    def.mass = mass;
    assert_int_equal(tb_world_add_particle(w, &def, &id), TB_OK);
    return id;
}

/* ---- creation ------------------------------------------------------------ */

static void create_rejects_bad_definitions(void **state)
{
    tb_world_def def = tb_default_world_def();
    tb_world *w = (tb_world *)&def; /* must be reset to NULL on failure */
    char message[TB_MESSAGE_SIZE];
    (void)state;
    def.gravity[1] = NAN;
    assert_int_equal(tb_world_create(&def, &w, message, sizeof message), TB_ERR_ARGUMENT);
    assert_null(w);
    assert_non_null(strstr(message, "gravity"));

    def = tb_default_world_def();
    def.integrator = "leapfrog-9000";
    assert_int_equal(tb_world_create(&def, &w, message, sizeof message), TB_ERR_ARGUMENT);
    assert_non_null(strstr(message, "leapfrog-9000"));

    def = tb_default_world_def();
    def.tolerance = -1e-3;
    assert_int_equal(tb_world_create(&def, &w, message, sizeof message), TB_ERR_ARGUMENT);
    assert_non_null(strstr(message, "tolerance"));

    def = tb_default_world_def();
    def.linear_drag = -1;
    assert_int_equal(tb_world_create(&def, &w, message, sizeof message), TB_ERR_ARGUMENT);
    def.linear_drag = INFINITY;
    assert_int_equal(tb_world_create(&def, &w, message, sizeof message), TB_ERR_ARGUMENT);
    assert_non_null(strstr(message, "drag"));
    assert_int_equal(tb_world_create(NULL, &w, NULL, 0), TB_ERR_ARGUMENT);
}

static void defaults_are_documented_values(void **state)
{
    tb_world *w = make_world(NULL);
    double g[3];
    tb_energy e;
    (void)state;
    tb_world_gravity(w, g);
    assert_true(g[0] == 0 && g[1] == 0 && g[2] == -9.81);
    assert_string_equal(tb_world_integrator(w), "verlet");
    assert_true(tb_world_time(w) == 0);
    assert_int_equal(tb_world_particle_count(w), 0);
    e = tb_world_energy(w);
    assert_true(e.total == 0);
    assert_int_equal(tb_world_step(w, 0.01), TB_OK); /* an empty world steps */
    assert_true(tb_world_time(w) == 0.01);
    tb_world_destroy(w);
    tb_world_destroy(NULL);
}

/* ---- ids ----------------------------------------------------------------- */

static void ids_survive_swap_remove_and_go_stale(void **state)
{
    tb_world *w = make_world(NULL);
    tb_particle_id a = add_particle(w, 1, 0, 1), b = add_particle(w, 2, 0, 2), c = add_particle(w, 3, 0, 3);
    tb_particle_id d;
    double x[3], m;
    fingerprint before;
    (void)state;
    assert_int_equal(tb_world_remove_particle(w, a), TB_OK);
    assert_int_equal(tb_world_particle_count(w), 2);
    /* c moved into a's slot; both survivors still answer with their own data */
    assert_int_equal(tb_particle_position(w, c, x), TB_OK);
    assert_true(x[0] == 3);
    assert_int_equal(tb_particle_mass(w, b, &m), TB_OK);
    assert_true(m == 2);
    /* a is stale, and stays stale when its index is reused */
    take(w, &before);
    assert_int_equal(tb_particle_position(w, a, x), TB_ERR_STALE_ID);
    assert_int_equal(tb_world_remove_particle(w, a), TB_ERR_STALE_ID);
    assert_int_equal(tb_particle_set_position(w, a, x), TB_ERR_STALE_ID);
    assert_non_null(strstr(tb_world_message(w), "removed"));
    assert_unchanged(w, before);
    d = add_particle(w, 4, 0, 4);
    assert_int_equal(d.index1, a.index1);
    assert_int_not_equal(d.generation, a.generation);
    assert_int_equal(tb_particle_position(w, a, x), TB_ERR_STALE_ID);
    assert_int_equal(tb_particle_position(w, d, x), TB_OK);
    assert_true(x[0] == 4);
    /* the null id and made-up ids are refused */
    {
        tb_particle_id null_id = { 0, 0 }, forged = { 99, 1 }, free_gen = { a.index1, a.generation + 1 };
        assert_int_equal(tb_particle_position(w, null_id, x), TB_ERR_STALE_ID);
        assert_int_equal(tb_particle_position(w, forged, x), TB_ERR_STALE_ID);
        assert_int_equal(tb_world_remove_particle(w, d), TB_OK);
        free_gen.generation = d.generation + 1; /* the generation a free entry has */
        assert_int_equal(tb_particle_position(w, free_gen, x), TB_ERR_STALE_ID);
    }
    /* slot order ids match */
    assert_true(TB_ID_EQUAL(tb_world_particle_at(w, 0), c) || TB_ID_EQUAL(tb_world_particle_at(w, 1), c));
    assert_true(TB_ID_IS_NULL(tb_world_particle_at(w, 5)));
    tb_world_destroy(w);
}

/* Every kind of id, from the other world or forged, is refused as stale
   by every call that takes one, and the world stays as it was. The two
   worlds hold the same objects made in the same order, so their ids share
   indices and counters: only the world tag tells them apart. */
typedef struct id_set {
    tb_tracer_id tracer;
    tb_particle_id particle, other;
    tb_spring_id spring;
    tb_body_id body;
    tb_shape_id shape;
    tb_field_id field;
    tb_force_id force;
} id_set;

static tb_status no_force(const tb_force_args *args, void *user)
{
    (void)args, (void)user;
    return TB_OK;
}

static void populate(tb_world *w, id_set *ids)
{
    tb_tracer_def t = tb_default_tracer_def();
    tb_spring_def sp = tb_default_spring_def();
    tb_body_def bd = tb_default_body_def();
    tb_shape_def sh = tb_default_shape_def();
    const double u[3] = { 1, 0, 0 };
    assert_int_equal(tb_world_add_tracer(w, &t, &ids->tracer), TB_OK);
    ids->particle = add_particle(w, 0, 1, 1);
    ids->other = add_particle(w, 1, 0, 2);
    sp.a = ids->particle, sp.b = ids->other, sp.stiffness = 3;
    assert_int_equal(tb_world_add_spring(w, &sp, &ids->spring), TB_OK);
    bd.position[2] = 5;
    assert_int_equal(tb_world_add_body(w, &bd, &ids->body), TB_OK);
    sh.body = ids->body;
    assert_int_equal(tb_world_add_shape(w, &sh, &ids->shape), TB_OK);
    assert_int_equal(tb_world_add_uniform_field(w, u, &ids->field), TB_OK);
    assert_int_equal(tb_world_add_force(w, no_force, NULL, &ids->force), TB_OK);
}

#define assert_stale(w, call)                                                       \
    do {                                                                            \
        assert_int_equal((call), TB_ERR_STALE_ID);                                  \
        assert_non_null(strstr(tb_world_message(w), "another world"));              \
    } while (0)

/* Every call that takes an id, each given the ids of `ids`. */
static void all_refused(tb_world *w, const id_set *ids)
{
    double v[4] = { 1, 0, 0, 0 }, m;
    int asleep;
    tb_spring_def sp = tb_default_spring_def();
    tb_shape_def sh = tb_default_shape_def();
    fingerprint before;
    take(w, &before);
    assert_stale(w, tb_tracer_position(w, ids->tracer, v));
    assert_stale(w, tb_tracer_set_position(w, ids->tracer, v));
    assert_stale(w, tb_world_remove_tracer(w, ids->tracer));
    assert_stale(w, tb_particle_position(w, ids->particle, v));
    assert_stale(w, tb_particle_velocity(w, ids->particle, v));
    assert_stale(w, tb_particle_mass(w, ids->particle, &m));
    assert_stale(w, tb_particle_set_position(w, ids->particle, v));
    assert_stale(w, tb_particle_set_velocity(w, ids->particle, v));
    assert_stale(w, tb_world_remove_particle(w, ids->particle));
    sp.a = ids->particle, sp.stiffness = 1; /* anchored */
    assert_stale(w, tb_world_add_spring(w, &sp, NULL));
    sp.a = tb_world_particle_at(w, 0), sp.b = ids->other;
    if (!TB_ID_IS_NULL(sp.b)) /* a null b anchors the spring */
        assert_stale(w, tb_world_add_spring(w, &sp, NULL));
    assert_stale(w, tb_world_remove_spring(w, ids->spring));
    assert_stale(w, tb_body_position(w, ids->body, v));
    assert_stale(w, tb_body_orientation(w, ids->body, v));
    assert_stale(w, tb_body_velocity(w, ids->body, v));
    assert_stale(w, tb_body_angular_velocity(w, ids->body, v));
    assert_stale(w, tb_body_momentum(w, ids->body, v, NULL));
    assert_stale(w, tb_body_mass(w, ids->body, &m, NULL));
    assert_stale(w, tb_body_set_position(w, ids->body, v));
    assert_stale(w, tb_body_set_orientation(w, ids->body, v));
    assert_stale(w, tb_body_set_velocity(w, ids->body, v));
    assert_stale(w, tb_body_set_angular_velocity(w, ids->body, v));
    assert_stale(w, tb_body_apply_force(w, ids->body, v, v));
    assert_stale(w, tb_body_apply_force_at_body_point(w, ids->body, v, v));
    assert_stale(w, tb_body_apply_torque(w, ids->body, v));
    assert_stale(w, tb_body_asleep(w, ids->body, &asleep));
    assert_stale(w, tb_body_wake(w, ids->body));
    sh.body = ids->body;
    if (!TB_ID_IS_NULL(sh.body)) /* a null body makes a static shape */
        assert_stale(w, tb_world_add_shape(w, &sh, NULL));
    assert_stale(w, tb_world_remove_body(w, ids->body));
    assert_stale(w, tb_world_remove_shape(w, ids->shape));
    assert_stale(w, tb_world_remove_field(w, ids->field));
    assert_stale(w, tb_world_remove_force(w, ids->force));
    assert_unchanged(w, before);
}

/* Change one id of every kind the same way. */
#define FORGE_ALL(set, member, expr)                                      \
    do {                                                                 \
        (set).tracer.member = (expr)((set).tracer.member);                 \
        (set).particle.member = (expr)((set).particle.member);             \
        (set).other.member = (expr)((set).other.member);                   \
        (set).spring.member = (expr)((set).spring.member);                 \
        (set).body.member = (expr)((set).body.member);                     \
        (set).shape.member = (expr)((set).shape.member);                   \
        (set).field.member = (expr)((set).field.member);                   \
        (set).force.member = (expr)((set).force.member);                   \
    } while (0)

static uint32_t next_life(uint32_t g) { return g + 2; }        /* what the entry's next life will carry */
static uint32_t free_life(uint32_t g) { return g + 1; }        /* what a free entry carries */
static uint32_t top_bit(uint32_t g) { return g ^ 0x80000000u; } /* another world's tag */
static uint32_t low_tag(uint32_t g) { return g ^ 0x00100000u; }
static uint32_t zero(uint32_t g) { (void)g; return 0; }
static uint32_t far_index(uint32_t i) { return i + 1000; }
static uint32_t last_index(uint32_t i) { (void)i; return UINT32_MAX; }

static void ids_of_another_world_are_stale(void **state)
{
    tb_world *a = make_world("rk4"), *b = make_world("rk4");
    id_set in_a, in_b, forged;
    int k;
    uint32_t (*const forge_generation[])(uint32_t) = { next_life, free_life, top_bit, low_tag, zero };
    uint32_t (*const forge_index[])(uint32_t) = { far_index, last_index, zero };
    (void)state;
    populate(a, &in_a);
    populate(b, &in_b);
    /* the same index in both worlds, told apart by the generation alone */
    assert_int_equal(in_a.body.index1, in_b.body.index1);
    assert_int_not_equal(in_a.body.generation, in_b.body.generation);
    all_refused(b, &in_a);
    all_refused(a, &in_b);
    for (k = 0; k < (int)(sizeof forge_generation / sizeof forge_generation[0]); ++k) {
        forged = in_b;
        FORGE_ALL(forged, generation, forge_generation[k]);
        all_refused(b, &forged);
    }
    for (k = 0; k < (int)(sizeof forge_index / sizeof forge_index[0]); ++k) {
        forged = in_b;
        FORGE_ALL(forged, index1, forge_index[k]);
        all_refused(b, &forged);
    }
    /* each world still answers to its own ids, and both step */
    {
        double x[3];
        assert_int_equal(tb_particle_position(a, in_a.particle, x), TB_OK);
        assert_int_equal(tb_body_position(b, in_b.body, x), TB_OK);
        assert_int_equal(tb_world_step(a, 0.01), TB_OK);
        assert_int_equal(tb_world_step(b, 0.01), TB_OK);
        assert_int_equal(tb_world_remove_shape(b, in_b.shape), TB_OK);
        assert_int_equal(tb_world_remove_force(b, in_b.force), TB_OK);
        assert_int_equal(tb_world_remove_field(b, in_b.field), TB_OK);
        assert_int_equal(tb_world_remove_spring(b, in_b.spring), TB_OK);
        assert_int_equal(tb_world_remove_body(b, in_b.body), TB_OK);
        assert_int_equal(tb_world_remove_particle(b, in_b.particle), TB_OK);
        assert_int_equal(tb_world_remove_tracer(b, in_b.tracer), TB_OK);
    }
    tb_world_destroy(a);
    tb_world_destroy(b);
}

/* A world's ids carry its tag through every life of an entry: reused 1000
   times, an entry's id is never one of another world. */
static void reused_entries_keep_their_world(void **state)
{
    tb_world *a = make_world(NULL), *b = make_world(NULL);
    tb_particle_id pa = add_particle(a, 0, 0, 1), pb = add_particle(b, 0, 0, 1);
    double x[3];
    int i;
    (void)state;
    for (i = 0; i < 1000; ++i) {
        assert_int_equal(tb_world_remove_particle(a, pa), TB_OK);
        pa = add_particle(a, i, 0, 1);
        assert_int_equal(tb_particle_position(b, pa, x), TB_ERR_STALE_ID);
        assert_int_equal(tb_particle_position(a, pb, x), TB_ERR_STALE_ID);
    }
    assert_int_equal(pa.index1, pb.index1);
    assert_int_equal(tb_particle_position(a, pa, x), TB_OK);
    assert_true(x[0] == 999);
    tb_world_destroy(a);
    tb_world_destroy(b);
}

static void removing_a_particle_removes_its_springs(void **state)
{
    tb_world *w = make_world(NULL);
    tb_particle_id a = add_particle(w, 0, 0, 1), b = add_particle(w, 1, 0, 1), c = add_particle(w, 2, 0, 1);
    tb_spring_def def = tb_default_spring_def();
    tb_spring_id ab, bc, ca;
    tb_energy e;
    (void)state;
    def.stiffness = 10;
    def.a = a, def.b = b;
    assert_int_equal(tb_world_add_spring(w, &def, &ab), TB_OK);
    def.a = b, def.b = c;
    assert_int_equal(tb_world_add_spring(w, &def, &bc), TB_OK);
    def.a = c, def.b = a, def.rest_length = 1; /* stretched by 1 m: 5 J */
    assert_int_equal(tb_world_add_spring(w, &def, &ca), TB_OK);
    e = tb_world_energy(w);
    assert_rel(e.spring, 5.0, 1e-15);
    assert_int_equal(tb_world_remove_particle(w, b), TB_OK);
    assert_int_equal(tb_world_spring_count(w), 1);
    assert_int_equal(tb_world_remove_spring(w, ab), TB_ERR_STALE_ID);
    /* the surviving spring still joins a and c (c moved slots) */
    e = tb_world_energy(w);
    assert_rel(e.spring, 5.0, 1e-15);
    assert_int_equal(tb_world_remove_spring(w, ca), TB_OK);
    assert_int_equal(tb_world_spring_count(w), 0);
    tb_world_destroy(w);
}

/* ---- bad input ------------------------------------------------------------ */

static void bad_particles_are_refused(void **state)
{
    tb_world *w = make_world(NULL);
    tb_particle_def def = tb_default_particle_def();
    tb_particle_id id = add_particle(w, 1, 2, 3);
    const double bad_masses[] = { 0, -1, NAN, INFINITY, -0.0 };
    double nanv[3] = { 0, NAN, 0 }, infv[3] = { INFINITY, 0, 0 };
    fingerprint before;
    size_t i;
    (void)state;
    take(w, &before);
    for (i = 0; i < sizeof bad_masses / sizeof bad_masses[0]; ++i) {
        def = tb_default_particle_def();
        def.mass = bad_masses[i];
        assert_int_equal(tb_world_add_particle(w, &def, NULL), TB_ERR_ARGUMENT);
        assert_non_null(strstr(tb_world_message(w), "mass"));
    }
    def = tb_default_particle_def();
    def.position[2] = NAN;
    assert_int_equal(tb_world_add_particle(w, &def, NULL), TB_ERR_ARGUMENT);
    def = tb_default_particle_def();
    def.velocity[0] = -INFINITY;
    assert_int_equal(tb_world_add_particle(w, &def, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_world_add_particle(w, NULL, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_particle_set_position(w, id, nanv), TB_ERR_ARGUMENT);
    assert_int_equal(tb_particle_set_velocity(w, id, infv), TB_ERR_ARGUMENT);
    assert_non_null(strstr(tb_world_message(w), "finite"));
    assert_unchanged(w, before);
    tb_world_destroy(w);
}

static void bad_steps_and_settings_are_refused(void **state)
{
    tb_world *w = make_world(NULL);
    const double bad_steps[] = { 0, -0.01, NAN, INFINITY, -INFINITY };
    double g[3] = { 0, INFINITY, 0 };
    fingerprint before;
    size_t i;
    (void)state;
    add_particle(w, 1, 2, 3);
    take(w, &before);
    for (i = 0; i < sizeof bad_steps / sizeof bad_steps[0]; ++i) {
        assert_int_equal(tb_world_step(w, bad_steps[i]), TB_ERR_ARGUMENT);
        assert_non_null(strstr(tb_world_message(w), "step"));
    }
    assert_int_equal(tb_world_set_integrator(w, "rk5"), TB_ERR_ARGUMENT);
    assert_non_null(strstr(tb_world_message(w), "rk5"));
    assert_int_equal(tb_world_set_integrator(w, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_world_set_gravity(w, g), TB_ERR_ARGUMENT);
    assert_int_equal(tb_world_set_drag(w, -0.5, 0), TB_ERR_ARGUMENT);
    assert_int_equal(tb_world_set_drag(w, 0, NAN), TB_ERR_ARGUMENT);
    assert_int_equal(tb_world_set_tolerance(w, 0), TB_ERR_ARGUMENT);
    assert_int_equal(tb_world_set_tolerance(w, -1e-6), TB_ERR_ARGUMENT);
    assert_int_equal(tb_world_set_tolerance(w, NAN), TB_ERR_ARGUMENT);
    assert_non_null(strstr(tb_world_message(w), "tolerance"));
    assert_unchanged(w, before);
    tb_world_destroy(w);
}

static void bad_springs_are_refused(void **state)
{
    tb_world *w = make_world(NULL);
    tb_particle_id a = add_particle(w, 0, 0, 1), b = add_particle(w, 1, 0, 1), gone = add_particle(w, 2, 0, 1);
    tb_spring_def def;
    fingerprint before;
    (void)state;
    assert_int_equal(tb_world_remove_particle(w, gone), TB_OK);
    take(w, &before);

    def = tb_default_spring_def();
    def.a = a, def.b = gone, def.stiffness = 1;
    assert_int_equal(tb_world_add_spring(w, &def, NULL), TB_ERR_STALE_ID); /* names a missing particle */
    def.a = gone, def.b = a;
    assert_int_equal(tb_world_add_spring(w, &def, NULL), TB_ERR_STALE_ID);
    def.a = a, def.b = b, def.stiffness = -1;
    assert_int_equal(tb_world_add_spring(w, &def, NULL), TB_ERR_ARGUMENT);
    assert_non_null(strstr(tb_world_message(w), "stiffness"));
    def.stiffness = NAN;
    assert_int_equal(tb_world_add_spring(w, &def, NULL), TB_ERR_ARGUMENT);
    def.stiffness = 1, def.damping = -2;
    assert_int_equal(tb_world_add_spring(w, &def, NULL), TB_ERR_ARGUMENT);
    def.damping = 0, def.rest_length = INFINITY;
    assert_int_equal(tb_world_add_spring(w, &def, NULL), TB_ERR_ARGUMENT);
    def.rest_length = -1, def.b = a;
    assert_int_equal(tb_world_add_spring(w, &def, NULL), TB_ERR_ARGUMENT); /* to itself */
    def.b.index1 = 0, def.anchor[0] = NAN;
    assert_int_equal(tb_world_add_spring(w, &def, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_world_add_spring(w, NULL, NULL), TB_ERR_ARGUMENT);
    assert_unchanged(w, before);
    tb_world_destroy(w);
}

static void tracers_and_split_methods_exclude_each_other(void **state)
{
    tb_world *w = make_world("verlet");
    tb_tracer_def def = tb_default_tracer_def();
    tb_tracer_id id;
    double omega[3] = { 0, 0, 1 }, centre[3] = { 0, 0, 0 }, bad[3] = { NAN, 0, 0 };
    fingerprint before;
    (void)state;
    assert_int_equal(tb_world_add_tracer(w, &def, &id), TB_ERR_ARGUMENT);
    assert_non_null(strstr(tb_world_message(w), "rk4"));
    assert_int_equal(tb_world_set_integrator(w, "rk4"), TB_OK);
    assert_int_equal(tb_world_add_tracer(w, &def, &id), TB_OK);
    take(w, &before);
    assert_int_equal(tb_world_set_integrator(w, "symplectic_euler"), TB_ERR_ARGUMENT);
    assert_int_equal(tb_world_add_vortex_field(w, bad, centre, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_world_add_uniform_field(w, bad, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_world_add_field(w, NULL, NULL, NULL), TB_ERR_ARGUMENT);
    def.position[0] = INFINITY;
    assert_int_equal(tb_world_add_tracer(w, &def, NULL), TB_ERR_ARGUMENT);
    assert_int_equal(tb_tracer_set_position(w, id, bad), TB_ERR_ARGUMENT);
    assert_unchanged(w, before);
    assert_int_equal(tb_world_add_vortex_field(w, omega, centre, NULL), TB_OK);
    assert_int_equal(tb_world_remove_tracer(w, id), TB_OK);
    assert_int_equal(tb_world_remove_tracer(w, id), TB_ERR_STALE_ID);
    assert_int_equal(tb_world_set_integrator(w, "symplectic_euler"), TB_OK);
    tb_world_destroy(w);
}

/* ---- callbacks: failure rolls back, structure is frozen ------------------- */

typedef struct flaky {
    int calls, fail_at, tried_add;
    tb_status add_status, set_status, gravity_status, step_status;
    tb_world *w;
} flaky;

static tb_status flaky_force(const tb_force_args *args, void *user)
{
    flaky *f = user;
    size_t i;
    if (++f->calls == f->fail_at) {
        strcpy(args->message, "flaky force gave up");
        return TB_ERR_CALLBACK;
    }
    for (i = 0; i < args->count; ++i)
        args->forces[3 * i + 1] += 0.5 * args->positions[3 * i]; /* something state-dependent */
    if (f->tried_add) {
        tb_particle_def def = tb_default_particle_def();
        double g[3] = { 0, 0, 0 };
        f->add_status = tb_world_add_particle(f->w, &def, NULL);
        f->set_status = tb_particle_set_position(f->w, tb_world_particle_at(f->w, 0), g);
        f->gravity_status = tb_world_set_gravity(f->w, g);
        f->step_status = tb_world_step(f->w, 0.1);
        f->tried_add = 0;
    }
    return TB_OK;
}

static void failing_callback_leaves_state_bit_identical(void **state)
{
    int m;
    (void)state;
    for (m = 0; m < tb_integrator_count(); ++m) {
        const char *name = tb_integrator_name(m);
        int evaluations = 0, k;
        /* count the evaluations of one step, then fail at each one in turn */
        for (k = 0; k <= evaluations + 1; ++k) {
            tb_world *w = make_world(name);
            tb_spring_def sdef = tb_default_spring_def();
            flaky f;
            fingerprint before;
            memset(&f, 0, sizeof f);
            sdef.a = add_particle(w, 1, 2, 3);
            sdef.b = add_particle(w, 2, -1, 1);
            sdef.stiffness = 40;
            sdef.damping = 0.3;
            assert_int_equal(tb_world_add_spring(w, &sdef, NULL), TB_OK);
            assert_int_equal(tb_world_add_force(w, flaky_force, &f, NULL), TB_OK);
            assert_int_equal(tb_world_step(w, 0.01), TB_OK); /* move off the initial state */
            if (k == 0) {
                int before_calls = f.calls;
                assert_int_equal(tb_world_step(w, 0.01), TB_OK);
                evaluations = f.calls - before_calls;
                if (strcmp(name, "dopri5") && strcmp(name, "auto")) /* adaptive: as its substeps need */
                    assert_int_equal(evaluations, !strcmp(name, "rk4") ? 4 : !strncmp(name, "verlet", 6) ? 2 : 1);
                tb_world_destroy(w);
                continue;
            }
            if (k > evaluations) {
                tb_world_destroy(w);
                break;
            }
            take(w, &before);
            f.fail_at = f.calls + k;
            assert_int_equal(tb_world_step(w, 0.01), TB_ERR_CALLBACK);
            assert_non_null(strstr(tb_world_message(w), "flaky force gave up"));
            assert_unchanged(w, before);
            tb_world_destroy(w);
        }
    }
}

static void structural_changes_are_refused_while_stepping(void **state)
{
    tb_world *w = make_world("rk4");
    flaky f;
    double x[3];
    (void)state;
    memset(&f, 0, sizeof f);
    f.w = w;
    f.tried_add = 1;
    add_particle(w, 1, 0, 1);
    assert_int_equal(tb_world_add_force(w, flaky_force, &f, NULL), TB_OK);
    assert_int_equal(tb_world_step(w, 0.01), TB_OK);
    assert_int_equal(f.add_status, TB_ERR_BUSY);
    assert_int_equal(f.set_status, TB_ERR_BUSY);
    assert_int_equal(f.gravity_status, TB_ERR_BUSY);
    assert_int_equal(f.step_status, TB_ERR_BUSY);
    assert_int_equal(tb_world_particle_count(w), 1);
    assert_int_equal(tb_particle_position(w, tb_world_particle_at(w, 0), x), TB_OK);
    tb_world_destroy(w);
}

/* ---- allocation ----------------------------------------------------------- */

static void allocator_hooks_see_every_byte(void **state)
{
    budget b = { 0, 0, -1, 0 };
    tb_world_def def = tb_default_world_def();
    tb_world *w;
    int i;
    (void)state;
    def.allocator.realloc = counting_realloc;
    def.allocator.user = &b;
    def.integrator = "rk4";
    assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
    for (i = 0; i < 100; ++i) {
        tb_tracer_def t = tb_default_tracer_def();
        add_particle(w, i, 0, 1);
        assert_int_equal(tb_world_add_tracer(w, &t, NULL), TB_OK);
    }
    assert_int_equal(tb_world_step(w, 0.01), TB_OK);
    assert_true(b.live_bytes > 0);
    tb_world_destroy(w);
    assert_int_equal(b.live_bytes, 0);
    assert_false(b.size_mismatch);
}

static void out_of_memory_is_a_status_not_a_crash(void **state)
{
    long limit;
    (void)state;
    /* Fail the n-th allocation for every n until a run completes. */
    for (limit = 0; limit < 200; ++limit) {
        budget b = { 0, 0, -1, 0 };
        tb_world_def def = tb_default_world_def();
        tb_world *w;
        int i, done = 1;
        b.fail_after = limit;
        def.allocator.realloc = counting_realloc;
        def.allocator.user = &b;
        def.integrator = "rk4";
        if (tb_world_create(&def, &w, NULL, 0) != TB_OK)
            continue;
        for (i = 0; i < 40 && done; ++i) {
            tb_particle_def p = tb_default_particle_def();
            size_t n = tb_world_particle_count(w);
            tb_status st = tb_world_add_particle(w, &p, NULL);
            if (st != TB_OK) {
                assert_int_equal(st, TB_ERR_MEMORY);
                assert_int_equal(tb_world_particle_count(w), n);
                done = 0;
            }
        }
        if (done && tb_world_step(w, 0.01) != TB_OK) {
            assert_true(tb_world_time(w) == 0);
            done = 0;
        }
        tb_world_destroy(w);
        assert_int_equal(b.live_bytes, 0);
        assert_false(b.size_mismatch);
        if (done)
            return;
    }
    fail_msg("no run completed within 200 allocations");
}

/* A world with nothing in it steps under every integrator, with the guard
   on and off, and its time advances: the empty state and its scratch are a
   sentinel, not an allocation of zero bytes (which the allocator may
   answer with NULL, once read as out of memory). The same after its only
   particle is removed. */
static void empty_world_steps_under_every_method(void **state)
{
    int k;
    (void)state;
    for (k = 0; k < tb_integrator_count(); ++k) {
        tb_world_def def = tb_default_world_def();
        tb_particle_def p = tb_default_particle_def();
        tb_particle_id id;
        tb_world *w;
        int guard;
        def.integrator = tb_integrator_name(k);
        assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
        for (guard = 0; guard < 2; ++guard) {
            assert_int_equal(tb_world_set_guard(w, guard ? INFINITY : 0), TB_OK);
            assert_int_equal(tb_world_step(w, 0.01), TB_OK);
        }
        assert_int_equal(tb_world_add_particle(w, &p, &id), TB_OK);
        assert_int_equal(tb_world_remove_particle(w, id), TB_OK);
        assert_int_equal(tb_world_step(w, 0.01), TB_OK);
        assert_rel(tb_world_time(w), 0.03, 1e-12);
        tb_world_destroy(w);
    }
}

static void worlds_are_independent(void **state)
{
    tb_world *a = make_world("symplectic_euler"), *b = make_world("symplectic_euler");
    tb_particle_id pa = add_particle(a, 0, 1, 1), pb;
    double x[3];
    (void)state;
    pb = add_particle(b, 0, 1, 1);
    assert_int_equal(pa.index1, pb.index1); /* the same index in both tables */
    assert_int_equal(tb_world_step(a, 0.5), TB_OK);
    assert_int_equal(tb_particle_position(b, pa, x), TB_ERR_STALE_ID); /* a's id means nothing to b */
    assert_non_null(strstr(tb_world_message(b), "another world"));
    assert_int_equal(tb_particle_position(b, pb, x), TB_OK);
    assert_true(x[0] == 0);
    assert_int_equal(tb_particle_position(a, pa, x), TB_OK);
    assert_true(x[0] == 0.5);
    tb_world_destroy(a);
    tb_world_destroy(b);
}

static const struct CMUnitTest tests[] = {
    cmocka_unit_test(create_rejects_bad_definitions),
    cmocka_unit_test(defaults_are_documented_values),
    cmocka_unit_test(ids_survive_swap_remove_and_go_stale),
    cmocka_unit_test(ids_of_another_world_are_stale),
    cmocka_unit_test(reused_entries_keep_their_world),
    cmocka_unit_test(removing_a_particle_removes_its_springs),
    cmocka_unit_test(bad_particles_are_refused),
    cmocka_unit_test(bad_steps_and_settings_are_refused),
    cmocka_unit_test(bad_springs_are_refused),
    cmocka_unit_test(tracers_and_split_methods_exclude_each_other),
    cmocka_unit_test(failing_callback_leaves_state_bit_identical),
    cmocka_unit_test(structural_changes_are_refused_while_stepping),
    cmocka_unit_test(allocator_hooks_see_every_byte),
    cmocka_unit_test(out_of_memory_is_a_status_not_a_crash),
    cmocka_unit_test(empty_world_steps_under_every_method),
    cmocka_unit_test(worlds_are_independent),
};
TB_TEST_MAIN(tests)
