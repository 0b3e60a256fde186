/* tracers.c: massless points moved by the velocity fields, dx/dt = v(x, t). */
#include "particles/particles.h"

#include <string.h>

tb_tracer_def tb_default_tracer_def(void)
{
    tb_tracer_def def;
    memset(&def, 0, sizeof def);
    return def;
}

static tb_status find(const tb_world *w, tb_tracer_id id, uint32_t *slot)
{
    if (!tb__ids_lookup(&w->tracer_ids, id.index1, id.generation, slot))
        return tb__fail((tb_world *)w, TB_ERR_STALE_ID, "tracer id %u.%u is null, removed or from another world",
                        id.index1, id.generation);
    return TB_OK;
}

tb_status tb_world_add_tracer(tb_world *w, const tb_tracer_def *def, tb_tracer_id *id)
{
    tb_status st;
    uint32_t slot;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "add a tracer")) != TB_OK)
        return st;
    if (!def)
        return tb__fail(w, TB_ERR_ARGUMENT, "tracer definition must not be NULL");
    if ((st = tb__check_values(w, def->position, 3, "tracer position")) != TB_OK)
        return st;
    if (w->method->split)
        return tb__fail(w, TB_ERR_ARGUMENT,
                        "integrator '%s' kicks velocities and tracers have none: "
                        "use 'euler' or 'rk4' for a world with tracers", w->method->name);
    if (w->tracer_count == w->tracer_cap) {
        size_t cap = w->tracer_cap ? 2 * w->tracer_cap : 8;
        if ((st = tb__ids_reserve(w, &w->tracer_ids, cap)) != TB_OK)
            return st;
        if ((st = tb__state_resize(w, TB__TRACERS, cap)) != TB_OK)
            return st;
        w->tracer_cap = cap;
    }
    slot = (uint32_t)w->tracer_count++;
    memcpy(w->y + w->off[TB__TRACER_POS] + 3 * slot, def->position, 3 * sizeof(double));
    {
        tb_tracer_id made;
        tb__ids_acquire(&w->tracer_ids, w->id_tag, slot, &made.index1, &made.generation);
        if (id)
            *id = made;
    }
    return TB_OK;
}

tb_status tb_world_remove_tracer(tb_world *w, tb_tracer_id id)
{
    tb_status st;
    uint32_t slot, last;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "remove a tracer")) != TB_OK)
        return st;
    if ((st = find(w, id, &slot)) != TB_OK)
        return st;
    last = (uint32_t)w->tracer_count - 1;
    if (slot != last) {
        tb__state_move(w, TB__TRACERS, last, slot);
        tb__ids_move(&w->tracer_ids, last, slot);
    }
    tb__ids_release(&w->tracer_ids, id.index1);
    w->tracer_count--;
    return TB_OK;
}

tb_status tb_tracer_position(const tb_world *w, tb_tracer_id id, double position[3])
{
    uint32_t slot;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = find(w, id, &slot)) != TB_OK)
        return st;
    if (!position)
        return tb__null((tb_world *)w, "tb_tracer_position", "the output");
    memcpy(position, w->y + w->off[TB__TRACER_POS] + 3 * slot, 3 * sizeof(double));
    return TB_OK;
}

tb_status tb_tracer_set_position(tb_world *w, tb_tracer_id id, const double position[3])
{
    uint32_t slot;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    st = tb__check_busy(w, "set a tracer's position");
    if (st == TB_OK)
        st = find(w, id, &slot);
    if (st == TB_OK)
        st = tb__check_values(w, position, 3, "tracer position");
    if (st != TB_OK)
        return st;
    memcpy(w->y + w->off[TB__TRACER_POS] + 3 * slot, position, 3 * sizeof(double));
    return TB_OK;
}

size_t tb_world_tracer_count(const tb_world *w)
{
    TB__NEED_WORLD(w, 0);
    return w->tracer_count;
}

const double *tb_world_tracer_positions(const tb_world *w)
{
    TB__NEED_WORLD(w, NULL);
    return w->y ? w->y + w->off[TB__TRACER_POS] : NULL;
}

tb_tracer_id tb_world_tracer_at(const tb_world *w, size_t slot)
{
    tb_tracer_id id = { 0, 0 };
    if (w && slot < w->tracer_count)
        tb__ids_at(&w->tracer_ids, (uint32_t)slot, &id.index1, &id.generation);
    return id;
}
