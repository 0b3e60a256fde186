/* particles.c: point masses: adding, removing, reading and setting them.
   The kernels that move them are in particle_step.c. */
#include "particles/particles.h"

#include <math.h>
#include <string.h>

tb_particle_def tb_default_particle_def(void)
{
    tb_particle_def def;
    memset(&def, 0, sizeof def);
    def.mass = 1;
    return def;
}

static tb_status find(const tb_world *w, tb_particle_id id, uint32_t *slot)
{
    if (!tb__ids_lookup(&w->particle_ids, id.index1, id.generation, slot))
        return tb__fail((tb_world *)w, TB_ERR_STALE_ID,
                        "particle id %u.%u is null, removed or from another world", id.index1, id.generation);
    return TB_OK;
}

/* The derived quantities of a particle of mass m (kg) moving at v: its
   momentum m v and kinetic energy m v^2 / 2 (the input rule, TB_LIMIT). */
static tb_status check_motion(tb_world *w, double m, const double v[3])
{
    tb_status st;
    const double p = m * fmax(fabs(v[0]), fmax(fabs(v[1]), fabs(v[2])));
    if ((st = tb__check_derived(w, p, "particle momentum m v", "kg m/s")) != TB_OK)
        return st;
    return tb__check_derived(w, 0.5 * m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]),
                             "particle kinetic energy m v^2 / 2", "J");
}

static tb_status grow(tb_world *w)
{
    size_t cap = w->particle_cap ? 2 * w->particle_cap : 8;
    void **arrays[3];
    size_t sizes[3] = { sizeof(double), sizeof(double), 3 * sizeof(double) };
    tb_status st;
    arrays[0] = (void **)&w->particle_mass;
    arrays[1] = (void **)&w->particle_inv_mass;
    arrays[2] = (void **)&w->particle_force;
    /* Each step leaves things consistent if the next one fails: the state may
       be laid out for more particles than the arrays hold, never fewer. */
    if ((st = tb__ids_reserve(w, &w->particle_ids, cap)) != TB_OK)
        return st;
    if ((st = tb__state_resize(w, TB__PARTICLES, cap)) != TB_OK)
        return st;
    if ((st = tb__grow(w, arrays, sizes, 3, w->particle_count, w->particle_cap, cap)) != TB_OK)
        return st;
    w->particle_cap = cap;
    return TB_OK;
}

tb_status tb_world_add_particle(tb_world *w, const tb_particle_def *def, tb_particle_id *id)
{
    tb_status st;
    uint32_t slot;
    tb_particle_id made;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "add a particle")) != TB_OK)
        return st;
    if (!def)
        return tb__fail(w, TB_ERR_ARGUMENT, "particle definition must not be NULL");
    if ((st = tb__check_values(w, def->position, 3, "particle position")) != TB_OK ||
        (st = tb__check_values(w, def->velocity, 3, "particle velocity")) != TB_OK ||
        (st = tb__check_scale(w, def->mass, "particle mass")) != TB_OK ||
        (st = check_motion(w, def->mass, def->velocity)) != TB_OK)
        return st;
    if (w->particle_count == w->particle_cap && (st = grow(w)) != TB_OK)
        return st;
    slot = (uint32_t)w->particle_count++;
    memcpy(w->y + w->off[TB__PARTICLE_POS] + 3 * slot, def->position, 3 * sizeof(double));
    memcpy(w->y + w->off[TB__PARTICLE_VEL] + 3 * slot, def->velocity, 3 * sizeof(double));
    w->particle_mass[slot] = def->pinned ? 0 : def->mass;
    w->particle_inv_mass[slot] = def->pinned ? 0 : 1 / def->mass;
    tb__ids_acquire(&w->particle_ids, w->id_tag, slot, &made.index1, &made.generation);
    if (id)
        *id = made;
    return TB_OK;
}

tb_status tb_world_remove_particle(tb_world *w, tb_particle_id id)
{
    tb_status st;
    uint32_t slot, last;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "remove a particle")) != TB_OK)
        return st;
    if ((st = find(w, id, &slot)) != TB_OK)
        return st;
    last = (uint32_t)w->particle_count - 1;
    {
        int k;
        for (k = 0; k < 2; ++k)
            if (w->particle_removed[k])
                w->particle_removed[k](w, slot, last);
    }
    if (slot != last) {
        tb__state_move(w, TB__PARTICLES, last, slot);
        w->particle_mass[slot] = w->particle_mass[last];
        w->particle_inv_mass[slot] = w->particle_inv_mass[last];
        tb__ids_move(&w->particle_ids, last, slot);
    }
    tb__ids_release(&w->particle_ids, id.index1);
    w->particle_count--;
    return TB_OK;
}

static tb_status get3(const tb_world *w, tb_particle_id id, enum tb__quantity q, double out[3], const char *what)
{
    uint32_t slot;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = find(w, id, &slot)) != TB_OK)
        return st;
    if (!out)
        return tb__null((tb_world *)w, what, "the output");
    memcpy(out, w->y + w->off[q] + 3 * slot, 3 * sizeof(double));
    return TB_OK;
}

static tb_status set3(tb_world *w, tb_particle_id id, enum tb__quantity q, const double in[3], const char *what)
{
    uint32_t slot;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    st = tb__check_busy(w, "set a particle's state");
    if (st == TB_OK)
        st = find(w, id, &slot);
    if (st == TB_OK)
        st = tb__check_values(w, in, 3, what);
    if (st == TB_OK && q == TB__PARTICLE_VEL)
        st = check_motion(w, w->particle_mass[slot], in);
    if (st != TB_OK)
        return st;
    memcpy(w->y + w->off[q] + 3 * slot, in, 3 * sizeof(double));
    return TB_OK;
}

tb_status tb_particle_position(const tb_world *w, tb_particle_id id, double position[3])
{
    return get3(w, id, TB__PARTICLE_POS, position, "tb_particle_position");
}

tb_status tb_particle_velocity(const tb_world *w, tb_particle_id id, double velocity[3])
{
    return get3(w, id, TB__PARTICLE_VEL, velocity, "tb_particle_velocity");
}

tb_status tb_particle_set_position(tb_world *w, tb_particle_id id, const double position[3])
{
    return set3(w, id, TB__PARTICLE_POS, position, "particle position");
}

tb_status tb_particle_set_velocity(tb_world *w, tb_particle_id id, const double velocity[3])
{
    return set3(w, id, TB__PARTICLE_VEL, velocity, "particle velocity");
}

tb_status tb_particle_mass(const tb_world *w, tb_particle_id id, double *mass)
{
    uint32_t slot;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = find(w, id, &slot)) != TB_OK)
        return st;
    if (!mass)
        return tb__null((tb_world *)w, "tb_particle_mass", "the output");
    *mass = w->particle_mass[slot];
    return TB_OK;
}

size_t tb_world_particle_count(const tb_world *w)
{
    TB__NEED_WORLD(w, 0);
    return w->particle_count;
}

const double *tb_world_particle_positions(const tb_world *w)
{
    TB__NEED_WORLD(w, NULL);
    return w->y ? w->y + w->off[TB__PARTICLE_POS] : NULL;
}

const double *tb_world_particle_velocities(const tb_world *w)
{
    TB__NEED_WORLD(w, NULL);
    return w->y ? w->y + w->off[TB__PARTICLE_VEL] : NULL;
}

const double *tb_world_particle_masses(const tb_world *w)
{
    TB__NEED_WORLD(w, NULL);
    return w->particle_mass;
}

tb_particle_id tb_world_particle_at(const tb_world *w, size_t slot)
{
    tb_particle_id id = { 0, 0 };
    if (w && slot < w->particle_count)
        tb__ids_at(&w->particle_ids, (uint32_t)slot, &id.index1, &id.generation);
    return id;
}
