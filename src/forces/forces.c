/* forces.c: user force callbacks, called once per force evaluation with the
   whole particle arrays, in the order they were added. */
#include "forces/forces.h"
#include "bodies/bodies.h"

#include <string.h>

tb_status tb_world_add_force(tb_world *w, tb_force_fn *fn, void *user, tb_force_id *id)
{
    tb__force f;
    tb_force_id made;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    st = tb__check_busy(w, "add a force");
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
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    st = tb__check_busy(w, "remove a force");
    if (st == TB_OK)
        st = tb__list_remove(w, &w->forces, id.index1, id.generation, "force");
    return st;
}

static tb_status user_forces(tb_world *w, double t, const double *y, const double *seen, double *potential)
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
        args.positions = y + w->off[TB__PARTICLE_POS];
        args.velocities = seen + w->off[TB__PARTICLE_VEL];
        args.masses = w->particle_mass;
        args.forces = w->particle_force;
        args.body_count = w->body_count;
        args.body_positions = y + w->off[TB__BODY_POS];
        args.body_orientations = y + w->off[TB__BODY_ROT];
        args.body_velocities = w->body_motion;
        args.body_angular_velocities = w->body_motion ? w->body_motion + 3 * w->body_count : NULL;
        args.body_masses = w->body_mass;
        args.body_forces = w->body_force;
        args.body_torques = w->body_force ? w->body_force + 3 * w->body_count : NULL;
        args.message = message;
        args.potential = potential;
        st = f->fn(&args, f->user);
        if (st != TB_OK)
            return tb__fail(w, TB_ERR_CALLBACK, "force callback failed: %s",
                            message[0] ? message : tb_status_name(st));
    }
    return TB_OK;
}

/* Springs and callbacks are the forces that couple objects or that tumble
   cannot see inside; they are evaluated once for all objects before any
   kick. Local forces (gravity, drag, damping) are added inside the kicks. */
tb_status tb__global_forces(tb_world *w, double t, const double *y, const double *seen)
{
    const int callbacks = w->forces.count > 0;
    w->force_ready = w->spring_count > 0 || callbacks;
    if (!w->force_ready)
        return TB_OK;
    if (w->particle_count)
        memset(w->particle_force, 0, 3 * w->particle_count * sizeof(double));
    if (w->body_count) {
        memset(w->body_force, 0, 6 * w->body_count * sizeof(double));
        if (callbacks)
            tb__body_motion(w, y, seen);
    }
    if (w->spring_count)
        tb__spring_forces(w, y + w->off[TB__PARTICLE_POS], seen + w->off[TB__PARTICLE_VEL], w->particle_force);
    return callbacks ? user_forces(w, t, y, seen, NULL) : TB_OK;
}

tb_status tb__force_potential(tb_world *w, double *potential)
{
    tb_status st;
    /* the forces go where a step's would and are cleared after: no step
       reads them before computing them again */
    if (w->body_count)
        tb__body_motion(w, w->y, w->y);
    st = user_forces(w, w->time, w->y, w->y, potential);
    if (w->particle_count)
        memset(w->particle_force, 0, 3 * w->particle_count * sizeof(double));
    if (w->body_count)
        memset(w->body_force, 0, 6 * w->body_count * sizeof(double));
    w->force_ready = 0;
    return st;
}
