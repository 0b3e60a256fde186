/* particle_worlds.h: what the particle tests share (test_forces,
   test_integrators, test_truths): a world with gravity along z and drag,
   steps covering a time, and the gravity of a central mass as a force
   callback. Include after
   test_main.h and tumble.h. Static inline, so a test that uses only one of
   them compiles without a warning. */
#ifndef TB_PARTICLE_WORLDS_H
#define TB_PARTICLE_WORLDS_H

#include <math.h>

/* A world stepping with `integrator`, gravity (0, 0, gz) m/s^2, drag
   f = -(linear + quadratic |v|) v. */
static inline tb_world *world_with(const char *integrator, double gz, double linear, double quadratic)
{
    tb_world_def def = tb_default_world_def();
    tb_world *w;
    def.integrator = integrator;
    def.gravity[2] = gz;
    def.linear_drag = linear;
    def.quadratic_drag = quadratic;
    assert_int_equal(tb_world_create(&def, &w, NULL, 0), TB_OK);
    return w;
}

/* n equal steps covering T seconds. */
static inline void step_through(tb_world *w, double T, long n)
{
    long i;
    for (i = 0; i < n; ++i)
        assert_int_equal(tb_world_step(w, T / (double)n), TB_OK);
}

/* Gravity of GM = 1 m^3/s^2 towards the origin on every particle:
   f = -m x / |x|^3. */
static inline tb_status central_gravity(const tb_force_args *a, void *user)
{
    size_t i;
    int k;
    (void)user;
    for (i = 0; i < a->count; ++i) {
        const double *x = a->positions + 3 * i;
        const double r2 = x[0] * x[0] + x[1] * x[1] + x[2] * x[2], r3 = r2 * sqrt(r2);
        for (k = 0; k < 3; ++k)
            a->forces[3 * i + k] -= a->masses[i] * x[k] / r3;
    }
    return TB_OK;
}

#endif
