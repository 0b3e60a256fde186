/* fields.c: velocity fields that carry tracers, summed in the order added. */
#include "forces/forces.h"

#include <stdio.h>
#include <string.h>

static tb_status add(tb_world *w, const tb__field *f, tb_field_id *id)
{
    tb_field_id made;
    tb_status st = tb__check_busy(w, "add a field");
    if (st == TB_OK)
        st = tb__list_add(w, &w->fields, f, &made.index1, &made.generation);
    if (st == TB_OK && id)
        *id = made;
    return st;
}

tb_status tb_world_add_uniform_field(tb_world *w, const double velocity[3], tb_field_id *id)
{
    tb__field f;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    memset(&f, 0, sizeof f);
    if ((st = tb__check_values(w, velocity, 3, "uniform field velocity")) != TB_OK)
        return st;
    f.kind = TB__FIELD_UNIFORM;
    memcpy(f.a, velocity, sizeof f.a);
    return add(w, &f, id);
}

tb_status tb_world_add_vortex_field(tb_world *w, const double omega[3], const double centre[3], tb_field_id *id)
{
    tb__field f;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    memset(&f, 0, sizeof f);
    if ((st = tb__check_values(w, omega, 3, "vortex field omega")) != TB_OK ||
        (st = tb__check_values(w, centre, 3, "vortex field centre")) != TB_OK)
        return st;
    f.kind = TB__FIELD_VORTEX;
    memcpy(f.a, omega, sizeof f.a);
    memcpy(f.b, centre, sizeof f.b);
    return add(w, &f, id);
}

tb_status tb_world_add_field(tb_world *w, tb_field_fn *fn, void *user, tb_field_id *id)
{
    tb__field f;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    memset(&f, 0, sizeof f);
    if (!fn)
        return tb__fail(w, TB_ERR_ARGUMENT, "field callback must not be NULL");
    f.kind = TB__FIELD_CALLBACK;
    f.fn = fn;
    f.user = user;
    return add(w, &f, id);
}

tb_status tb_world_remove_field(tb_world *w, tb_field_id id)
{
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    st = tb__check_busy(w, "remove a field");
    if (st == TB_OK)
        st = tb__list_remove(w, &w->fields, id.index1, id.generation, "field");
    return st;
}

tb_status tb__field_velocities(tb_world *w, double t, size_t n, const double *pos, double *vel)
{
    size_t k, i;
    memset(vel, 0, 3 * n * sizeof(double));
    for (k = 0; k < w->fields.count; ++k) {
        const tb__field *f = TB__LIST_AT(&w->fields, tb__field, k);
        if (f->kind == TB__FIELD_UNIFORM) {
            for (i = 0; i < n; ++i) {
                vel[3 * i + 0] += f->a[0];
                vel[3 * i + 1] += f->a[1];
                vel[3 * i + 2] += f->a[2];
            }
        } else if (f->kind == TB__FIELD_VORTEX) {
            const double *om = f->a, *c = f->b;
            for (i = 0; i < n; ++i) {
                double rx = pos[3 * i] - c[0], ry = pos[3 * i + 1] - c[1], rz = pos[3 * i + 2] - c[2];
                vel[3 * i + 0] += om[1] * rz - om[2] * ry;
                vel[3 * i + 1] += om[2] * rx - om[0] * rz;
                vel[3 * i + 2] += om[0] * ry - om[1] * rx;
            }
        } else {
            char message[TB_MESSAGE_SIZE];
            tb_field_args args;
            tb_status st;
            message[0] = 0;
            args.time = t;
            args.count = n;
            args.positions = pos;
            args.velocities = vel;
            args.message = message;
            st = f->fn(&args, f->user);
            if (st != TB_OK)
                return tb__fail(w, TB_ERR_CALLBACK, "field callback failed: %s",
                                message[0] ? message : tb_status_name(st));
        }
    }
    return TB_OK;
}

/* The tracers move with the fields: their velocities are the fields' sum. */
tb_status tb_world_tracer_velocities(tb_world *w, double *velocities)
{
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "evaluate tracer velocities")) != TB_OK)
        return st;
    if (!velocities)
        return tb__null(w, "tb_world_tracer_velocities", "the output");
    w->stepping = 1; /* callbacks may not add or remove objects meanwhile */
    st = tb__field_velocities(w, w->time, w->tracer_count, w->y + w->off[TB__TRACER_POS], velocities);
    w->stepping = 0;
    return st;
}

tb_status tb__tracer_derive(tb_world *w, double t, const double *y, double *dy)
{
    return tb__field_velocities(w, t, w->tracer_count, y + w->off[TB__TRACER_POS], dy + w->off[TB__TRACER_POS]);
}
