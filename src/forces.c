/* forces.c: user force callbacks, called once per force evaluation with the
   whole particle arrays, in the order they were added. */
#include "world.h"

#include <string.h>

tb_status tb_world_add_force(tb_world *w, tb_force_fn *fn, void *user, tb_force_id *id)
{
    tb__force f;
    tb_force_id made;
    tb_status st = tb__check_busy(w, "add a force");
    if (st != TB_OK)
        return st;
    if (!fn)
        return tb__fail(w, TB_ERR_ARGUMENT, "force callback must not be NULL");
    f.fn = fn;
    f.user = user;
    st = tb__list_add(w, &w->forces, &f, &made.index1, &made.generation);
    if (st == TB_OK && id)
        *id = made;
    return st;
}

tb_status tb_world_remove_force(tb_world *w, tb_force_id id)
{
    tb_status st = tb__check_busy(w, "remove a force");
    if (st == TB_OK)
        st = tb__list_remove(w, &w->forces, id.index1, id.generation, "force");
    return st;
}

tb_status tb__user_forces(tb_world *w, double t, const double *pos, const double *vel, double *force)
{
    size_t k;
    for (k = 0; k < w->forces.count; ++k) {
        const tb__force *f = TB__LIST_AT(&w->forces, tb__force, k);
        char message[TB_MESSAGE_SIZE];
        tb_force_args args;
        tb_status st;
        message[0] = 0;
        args.time = t;
        args.count = w->particle_count;
        args.positions = pos;
        args.velocities = vel;
        args.masses = w->mass;
        args.forces = force;
        args.message = message;
        st = f->fn(&args, f->user);
        if (st != TB_OK)
            return tb__fail(w, TB_ERR_CALLBACK, "force callback failed: %s",
                            message[0] ? message : tb_status_name(st));
    }
    return TB_OK;
}
