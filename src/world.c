/* world.c: the front door: creating and destroying worlds, and the
   settings that belong to no tier (gravity, drag). */
#include "world.h"
#include "bodies/bodies.h"
#include "contacts/contacts.h"
#include "stepping/stepping.h"
#include "forces/forces.h"
#include "joints/joints.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

tb_world_def tb_default_world_def(void)
{
    tb_world_def def;
    memset(&def, 0, sizeof def);
    def.gravity[2] = -9.81;
    return def;
}

static tb_status check_drag(tb_world *w, double linear, double quadratic)
{
    if (!(linear >= 0 && linear <= TB_LIMIT) || !(quadratic >= 0 && quadratic <= TB_LIMIT))
        return tb__fail(w, TB_ERR_ARGUMENT,
                        "drag coefficients must be finite and >= 0, at most %g (got linear %g, quadratic %g)",
                        TB_LIMIT, linear, quadratic);
    return TB_OK;
}

tb_status tb_world_create(const tb_world_def *def, tb_world **world, char *message, size_t message_size)
{
    tb_world scratch, *w;
    tb_status st = TB_OK;

    /* Validate on a stack copy so the failure message has somewhere to go. */
    memset(&scratch, 0, sizeof scratch);
    if (world)
        *world = NULL;
    if (!def || !world)
        st = tb__fail(&scratch, TB_ERR_ARGUMENT, "tb_world_create needs a definition and an output pointer");
    else if ((st = tb__check_values(&scratch, def->gravity, 3, "gravity")) != TB_OK)
        ;
    else if ((st = check_drag(&scratch, def->linear_drag, def->quadratic_drag)) != TB_OK)
        ;
    else if (def->tolerance != 0 && (st = tb__check_scale(&scratch, def->tolerance, "tolerance")) != TB_OK)
        ;
    else if (!tb__method_find(def->integrator ? def->integrator : "verlet"))
        st = tb__fail(&scratch, TB_ERR_ARGUMENT, "unknown integrator '%s'", def->integrator);
    if (st == TB_OK) {
        scratch.allocator = def->allocator;
        w = tb__alloc(&scratch, NULL, 0, sizeof *w);
        if (!w) {
            st = tb__fail(&scratch, TB_ERR_MEMORY, "out of memory creating a world");
        } else {
            memset(w, 0, sizeof *w);
            w->allocator = def->allocator;
            w->id_tag = tb__ids_new_tag();
            tb__state_init(w);
            w->method = tb__method_find(def->integrator ? def->integrator : "verlet");
            memcpy(w->gravity, def->gravity, sizeof w->gravity);
            w->linear_drag = def->linear_drag;
            w->tolerance = def->tolerance != 0 ? def->tolerance : 1e-6;
            w->fields.item_size = sizeof(tb__field);
            w->forces.item_size = sizeof(tb__force);
            w->quadratic_drag = def->quadratic_drag;
            *world = w;
        }
    }
    if (st != TB_OK && message && message_size)
        snprintf(message, message_size, "%s", scratch.message);
    return st;
}

void tb_world_destroy(tb_world *w)
{
    void **arrays[3];
    size_t sizes[3] = { sizeof(double), sizeof(double), 3 * sizeof(double) };
    if (!w)
        return;
    tb__state_free(w);
    tb__bodies_free(w);
    tb__contacts_free(w);
    arrays[0] = (void **)&w->particle_mass;
    arrays[1] = (void **)&w->particle_inv_mass;
    arrays[2] = (void **)&w->particle_force;
    tb__free_arrays(w, arrays, sizes, 3, w->particle_cap);
    tb__ids_free(w, &w->tracer_ids);
    tb__ids_free(w, &w->particle_ids);
    tb__springs_free(w);
    tb__joints_free(w);
    tb__list_free(w, &w->fields);
    tb__list_free(w, &w->forces);
    tb__rollback_free(w);
    tb__retake_free(w);
    tb__alloc(w, w, sizeof *w, 0);
}

const char *tb_world_message(const tb_world *w)
{
    TB__NEED_WORLD(w, "the world pointer is NULL");
    return w->message;
}

double tb_world_time(const tb_world *w)
{
    TB__NEED_WORLD(w, 0);
    return w->time;
}

tb_status tb_world_set_gravity(tb_world *w, const double gravity[3])
{
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if (w->stepping)
        return tb__check_busy(w, "change gravity");
    if ((st = tb__check_values(w, gravity, 3, "gravity")) != TB_OK)
        return st;
    memcpy(w->gravity, gravity, sizeof w->gravity);
    tb__wake_all(w); /* resting was under the old gravity */
    return TB_OK;
}

void tb_world_gravity(const tb_world *w, double gravity[3])
{
    if (w && gravity)
        memcpy(gravity, w->gravity, sizeof w->gravity);
}

tb_status tb_world_set_drag(tb_world *w, double linear, double quadratic)
{
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    st = tb__check_busy(w, "change drag");
    if (st == TB_OK)
        st = check_drag(w, linear, quadratic);
    if (st == TB_OK) {
        w->linear_drag = linear;
        w->quadratic_drag = quadratic;
    }
    return st;
}
