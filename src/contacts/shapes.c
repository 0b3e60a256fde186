/* shapes.c: shapes attached to bodies or static, the contact settings,
   and the last step's events and touching points: the public side of the
   contacts tier, whose tb__contacts it allocates and frees. */
#include "contacts/contacts.h"

#include <math.h>
#include <string.h>

tb_shape_def tb_default_shape_def(void)
{
    tb_shape_def def;
    memset(&def, 0, sizeof def);
    def.type = TB_SHAPE_SPHERE;
    def.orientation[0] = 1;
    def.radius = 0.5;
    def.half_extents[0] = def.half_extents[1] = def.half_extents[2] = 0.5;
    def.normal[2] = 1;
    def.friction = 0.6;
    def.category = 1;
    def.mask = 0xFFFFFFFFu;
    return def;
}

tb_contact_settings tb_default_contact_settings(void)
{
    tb_contact_settings s;
    memset(&s, 0, sizeof s);
    s.hertz = 30;
    s.damping_ratio = 10;
    s.max_push = 3;
    s.restitution_threshold = 1;
    s.slop = 0.005;
    s.particle_radius = -1;
    s.particle_friction = 0.6;
    s.sleep_speed = 0.05;
    s.sleep_time = 0.5;
    s.substeps = 4;
    return s;
}

static void remove_slot(tb__contacts *c, uint32_t slot);

/* The shapes of a removed body go with it. */
static void body_removed(tb_world *w, uint32_t body_index1)
{
    tb__contacts *c = w->contacts;
    size_t i;
    if (!c)
        return;
    for (i = c->shape_count; i-- > 0;)
        if (c->shapes[i].body == body_index1)
            remove_slot(c, (uint32_t)i);
}

static tb_status contacts_of(tb_world *w, tb__contacts **out)
{
    if (!w->contacts) {
        tb__contacts *c = tb__alloc(w, NULL, 0, sizeof *c);
        if (!c)
            return tb__fail(w, TB_ERR_MEMORY, "out of memory for shapes");
        memset(c, 0, sizeof *c);
        c->settings = tb_default_contact_settings();
        w->contacts = c;
        w->body_removed[TB__HEARS_SHAPES] = body_removed;
    }
    *out = w->contacts;
    return TB_OK;
}

void tb__contacts_free(tb_world *w)
{
    tb__contacts *c = w->contacts;
    if (!c)
        return;
    tb__alloc(w, c->shapes, c->shape_cap * sizeof *c->shapes, 0);
    tb__ids_free(w, &c->ids);
    tb__sap_free(w, &c->sap);
    tb__alloc(w, c->lo, 3 * c->proxy_cap * sizeof(double), 0);
    tb__alloc(w, c->hi, 3 * c->proxy_cap * sizeof(double), 0);
    tb__alloc(w, c->category, c->proxy_cap * sizeof(uint32_t), 0);
    tb__alloc(w, c->mask, c->proxy_cap * sizeof(uint32_t), 0);
    tb__alloc(w, c->group, c->proxy_cap * sizeof(uint32_t), 0);
    tb__alloc(w, c->proxy, c->proxy_cap * sizeof(uint32_t), 0);
    tb__alloc(w, c->margin, c->proxy_cap * sizeof(double), 0);
    tb__alloc(w, c->geoms, c->proxy_cap * sizeof(tb__geom), 0);
    tb__alloc(w, c->pairs, c->pair_cap * sizeof *c->pairs, 0);
    tb__alloc(w, c->entries, c->entry_cap * sizeof *c->entries, 0);
    tb__alloc(w, c->previous, c->previous_cap * sizeof *c->previous, 0);
    tb__alloc(w, c->order, c->order_cap * sizeof *c->order, 0);
    tb__alloc(w, c->previous_order, c->previous_order_cap * sizeof *c->previous_order, 0);
    tb__alloc(w, c->order_scratch, c->order_scratch_cap * sizeof *c->order_scratch, 0);
    tb__alloc(w, c->starts, c->starts_cap * sizeof *c->starts, 0);
    tb__alloc(w, c->previous_starts, c->previous_starts_cap * sizeof *c->previous_starts, 0);
    tb__alloc(w, c->park_index, c->park_index_cap * sizeof *c->park_index, 0);
    tb__alloc(w, c->owner, c->proxy_cap * sizeof(uint32_t), 0);
    tb__alloc(w, c->still, c->proxy_cap * sizeof(uint32_t), 0);
    tb__alloc(w, c->parked, c->parked_cap * sizeof *c->parked, 0);
    tb__alloc(w, c->poses, c->pose_cap * sizeof *c->poses, 0);
    tb__alloc(w, c->island_scratch, c->island_scratch_cap * sizeof(double), 0);
    tb__alloc(w, c->bodies, c->body_cap * sizeof *c->bodies, 0);
    tb__alloc(w, c->body_map, c->body_map_cap * sizeof(int32_t), 0);
    tb__alloc(w, c->particle_map, c->particle_map_cap * sizeof(int32_t), 0);
    tb__alloc(w, c->events, c->event_cap * sizeof *c->events, 0);
    tb__soft_free(w, c);
    tb__alloc(w, c, sizeof *c, 0);
    w->contacts = NULL;
}

static tb_status check_shape(tb_world *w, const tb_shape_def *def)
{
    const double qn = sqrt(def->orientation[0] * def->orientation[0] + def->orientation[1] * def->orientation[1] +
                           def->orientation[2] * def->orientation[2] + def->orientation[3] * def->orientation[3]);
    uint32_t slot;
    tb_status st;
    if ((st = tb__check_values(w, def->position, 3, "shape position")) != TB_OK)
        return st;
    if (!(fabs(qn - 1) <= 1e-6))
        return tb__fail(w, TB_ERR_ARGUMENT, "shape: orientation must be a unit quaternion (its norm is %g)", qn);
    if (!(def->friction >= 0 && def->friction <= TB_LIMIT) ||
        !(def->restitution >= 0 && def->restitution <= 1) ||
        !(def->rolling_resistance >= 0 && def->rolling_resistance <= TB_LIMIT))
        return tb__fail(w, TB_ERR_ARGUMENT,
                        "shape: friction and rolling_resistance must be finite and >= 0, at most %g, restitution in "
                        "[0, 1] (got %g, %g, %g)",
                        TB_LIMIT, def->friction, def->rolling_resistance, def->restitution);
    switch (def->type) {
    case TB_SHAPE_SPHERE:
        if (!tb__in_scale(def->radius))
            return tb__fail(w, TB_ERR_ARGUMENT, "sphere: radius must be finite and > 0, from %g to %g (got %g)",
                            1 / TB_LIMIT, TB_LIMIT, def->radius);
        break;
    case TB_SHAPE_CAPSULE:
        if (!tb__in_scale(def->radius) || !(def->half_length >= 0 && def->half_length <= TB_LIMIT))
            return tb__fail(w, TB_ERR_ARGUMENT,
                            "capsule: radius must be > 0 and half_length >= 0, both finite, from %g (radius) to %g "
                            "(got %g, %g)",
                            1 / TB_LIMIT, TB_LIMIT, def->radius, def->half_length);
        break;
    case TB_SHAPE_BOX:
        if (!tb__in_scale(def->half_extents[0]) || !tb__in_scale(def->half_extents[1]) ||
            !tb__in_scale(def->half_extents[2]))
            return tb__fail(w, TB_ERR_ARGUMENT,
                            "box: half extents must be finite and > 0, from %g to %g (got %g, %g, %g)", 1 / TB_LIMIT,
                            TB_LIMIT, def->half_extents[0], def->half_extents[1], def->half_extents[2]);
        break;
    case TB_SHAPE_PLANE: {
        const double n = sqrt(def->normal[0] * def->normal[0] + def->normal[1] * def->normal[1] +
                              def->normal[2] * def->normal[2]);
        if (!tb__finite3(def->normal) || !(fabs(n - 1) <= 1e-6))
            return tb__fail(w, TB_ERR_ARGUMENT, "plane: the normal must be a unit vector (|n| = %g)", n);
        if ((st = tb__check_values(w, &def->offset, 1, "plane offset")) != TB_OK)
            return st;
        if (!TB_ID_IS_NULL(def->body))
            return tb__fail(w, TB_ERR_ARGUMENT, "plane: planes are static (give no body)");
        break;
    }
    default:
        return tb__fail(w, TB_ERR_ARGUMENT, "shape: unknown type %d", (int)def->type);
    }
    if (!TB_ID_IS_NULL(def->body) && !tb__ids_lookup(&w->body_ids, def->body.index1, def->body.generation, &slot))
        return tb__fail(w, TB_ERR_STALE_ID, "shape: body id %u.%u is removed or from another world",
                        def->body.index1, def->body.generation);
    return TB_OK;
}

tb_status tb_world_add_shape(tb_world *w, const tb_shape_def *def, tb_shape_id *id)
{
    tb__contacts *c;
    tb__shape *s;
    tb_shape_id made;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "add a shape")) != TB_OK)
        return st;
    if (!def)
        return tb__null(w, "tb_world_add_shape", "the definition");
    if ((st = check_shape(w, def)) != TB_OK)
        return st;
    if ((st = contacts_of(w, &c)) != TB_OK)
        return st;
    if ((st = tb__reserve(w, (void **)&c->shapes, &c->shape_cap, c->shape_count + 1, sizeof *s)) != TB_OK)
        return st;
    if ((st = tb__ids_reserve(w, &c->ids, c->shape_count + 1)) != TB_OK)
        return st;
    s = &c->shapes[c->shape_count];
    memset(s, 0, sizeof *s);
    s->kind = def->type == TB_SHAPE_SPHERE    ? TB__SHAPE_SPHERE
              : def->type == TB_SHAPE_CAPSULE ? TB__SHAPE_CAPSULE
              : def->type == TB_SHAPE_BOX     ? TB__SHAPE_BOX
                                              : TB__SHAPE_PLANE;
    s->body = def->body.index1;
    s->body_generation = def->body.generation;
    memcpy(s->pos, def->position, sizeof s->pos);
    memcpy(s->rot, def->orientation, sizeof s->rot);
    tb__normalise(s->rot);
    s->radius = def->radius;
    if (def->type == TB_SHAPE_BOX)
        memcpy(s->half, def->half_extents, sizeof s->half);
    if (def->type == TB_SHAPE_CAPSULE)
        s->half[2] = def->half_length;
    memcpy(s->normal, def->normal, sizeof s->normal);
    s->offset = def->offset;
    s->friction = def->friction;
    s->restitution = def->restitution;
    s->rolling_resistance = def->rolling_resistance;
    s->category = def->category;
    s->mask = def->mask;
    s->reach = sqrt(s->pos[0] * s->pos[0] + s->pos[1] * s->pos[1] + s->pos[2] * s->pos[2]) +
               (s->kind == TB__SHAPE_BOX ? sqrt(s->half[0] * s->half[0] + s->half[1] * s->half[1] +
                                                s->half[2] * s->half[2])
                                         : s->radius + s->half[2]);
    c->planes += s->kind == TB__SHAPE_PLANE;
    tb__ids_acquire(&c->ids, w->id_tag, (uint32_t)c->shape_count, &made.index1, &made.generation);
    c->shape_count++;
    c->shape_version++;
    tb__wake_all(w); /* it may reach into what sleeps */
    if (id)
        *id = made;
    return TB_OK;
}

static void remove_slot(tb__contacts *c, uint32_t slot)
{
    const uint32_t last = (uint32_t)c->shape_count - 1;
    uint32_t index1, generation;
    tb__ids_at(&c->ids, slot, &index1, &generation);
    c->planes -= c->shapes[slot].kind == TB__SHAPE_PLANE;
    c->shape_version++;
    if (slot != last) {
        c->shapes[slot] = c->shapes[last];
        tb__ids_move(&c->ids, last, slot);
    }
    tb__ids_release(&c->ids, index1);
    c->shape_count--;
}

tb_status tb_world_remove_shape(tb_world *w, tb_shape_id id)
{
    uint32_t slot;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "remove a shape")) != TB_OK)
        return st;
    if (!w->contacts || !tb__ids_lookup(&w->contacts->ids, id.index1, id.generation, &slot))
        return tb__fail(w, TB_ERR_STALE_ID, "shape id %u.%u is null, removed or from another world", id.index1,
                        id.generation);
    remove_slot(w->contacts, slot);
    tb__wake_all(w); /* what it held up must fall */
    return TB_OK;
}


int tb__contacts_active(const tb_world *w)
{
    return w->contacts && w->contacts->shape_count > 0;
}

size_t tb_world_shape_count(const tb_world *w)
{
    TB__NEED_WORLD(w, 0);
    return w->contacts ? w->contacts->shape_count : 0;
}

tb_shape_id tb_world_shape_at(const tb_world *w, size_t slot)
{
    tb_shape_id id = { 0, 0 };
    if (w && w->contacts && slot < w->contacts->shape_count)
        tb__ids_at(&w->contacts->ids, (uint32_t)slot, &id.index1, &id.generation);
    return id;
}

tb_status tb_shape_definition(const tb_world *w, tb_shape_id id, tb_shape_def *def)
{
    const tb__shape *s;
    uint32_t slot;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if (!def)
        return tb__null((tb_world *)w, "tb_shape_definition", "the output");
    if (!w->contacts || !tb__ids_lookup(&w->contacts->ids, id.index1, id.generation, &slot))
        return tb__fail((tb_world *)w, TB_ERR_STALE_ID, "shape id %u.%u is null, removed or from another world",
                        id.index1, id.generation);
    s = &w->contacts->shapes[slot];
    memset(def, 0, sizeof *def);
    def->type = s->kind == TB__SHAPE_SPHERE    ? TB_SHAPE_SPHERE
                : s->kind == TB__SHAPE_CAPSULE ? TB_SHAPE_CAPSULE
                : s->kind == TB__SHAPE_BOX     ? TB_SHAPE_BOX
                                               : TB_SHAPE_PLANE;
    def->body.index1 = s->body;
    def->body.generation = s->body ? s->body_generation : 0;
    memcpy(def->position, s->pos, sizeof def->position);
    memcpy(def->orientation, s->rot, sizeof def->orientation);
    def->radius = s->radius;
    if (s->kind == TB__SHAPE_BOX)
        memcpy(def->half_extents, s->half, sizeof def->half_extents);
    if (s->kind == TB__SHAPE_CAPSULE)
        def->half_length = s->half[2];
    memcpy(def->normal, s->normal, sizeof def->normal);
    def->offset = s->offset;
    def->friction = s->friction;
    def->restitution = s->restitution;
    def->rolling_resistance = s->rolling_resistance;
    def->category = s->category;
    def->mask = s->mask;
    return TB_OK;
}

/* The most substeps a step may take: far beyond any use (the default is
   4), and small enough that the solver's multiples of them stay ints. */
#define MAX_SUBSTEPS 1000000

static tb_status check_settings(tb_world *w, const tb_contact_settings *s)
{
    tb_status st;
    if (!s)
        return tb__fail(w, TB_ERR_ARGUMENT, "contact settings must not be NULL");
    if ((st = tb__check_scale(w, s->hertz, "contact settings: hertz")) != TB_OK ||
        (st = tb__check_coefficient(w, s->damping_ratio, "contact settings: damping_ratio")) != TB_OK ||
        (st = tb__check_scale(w, s->max_push, "contact settings: max_push")) != TB_OK ||
        (st = tb__check_coefficient(w, s->restitution_threshold, "contact settings: restitution_threshold")) != TB_OK ||
        (st = tb__check_coefficient(w, s->slop, "contact settings: slop")) != TB_OK ||
        (st = tb__check_values(w, &s->particle_radius, 1, "contact settings: particle_radius")) != TB_OK ||
        (st = tb__check_coefficient(w, s->particle_friction, "contact settings: particle_friction")) != TB_OK ||
        (st = tb__check_coefficient(w, s->sleep_speed, "contact settings: sleep_speed")) != TB_OK)
        return st;
    if (s->substeps < 1 || s->substeps > MAX_SUBSTEPS)
        return tb__fail(w, TB_ERR_ARGUMENT, "contact settings: substeps must be from 1 to %d (got %d)",
                        MAX_SUBSTEPS, s->substeps);
    if (!(s->particle_restitution >= 0 && s->particle_restitution <= 1))
        return tb__fail(w, TB_ERR_ARGUMENT, "contact settings: particle_restitution must be in [0, 1] (got %g)",
                        s->particle_restitution);
    if (!(s->sleep_time > 0 && (s->sleep_time <= TB_LIMIT || s->sleep_time == INFINITY)))
        return tb__fail(w, TB_ERR_ARGUMENT,
                        "contact settings: sleep_time must be > 0, at most %g, or INFINITY (never sleep) (got %g)",
                        TB_LIMIT, s->sleep_time);
    return TB_OK;
}

tb_status tb_world_set_contact_settings(tb_world *w, const tb_contact_settings *s)
{
    tb__contacts *c;
    tb_status st;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "change the contact settings")) != TB_OK)
        return st;
    if ((st = check_settings(w, s)) != TB_OK)
        return st;
    if ((st = contacts_of(w, &c)) != TB_OK)
        return st;
    c->settings = *s;
    tb__wake_all(w); /* what rests under the old settings may not under the new */
    return TB_OK;
}

tb_contact_settings tb_world_contact_settings(const tb_world *w)
{
    return w && w->contacts ? w->contacts->settings : tb_default_contact_settings();
}

const tb_contact_event *tb_world_contact_events(const tb_world *w, size_t *count)
{
    if (count)
        *count = w && w->contacts ? w->contacts->event_count : 0;
    return w && w->contacts ? w->contacts->events : NULL;
}

size_t tb_world_contact_count(const tb_world *w)
{
    return w && w->contacts ? w->contacts->touching_points : 0;
}

double tb_world_deepest_overlap(const tb_world *w)
{
    double deepest = 0;
    size_t i;
    int k;
    if (!w || !w->contacts)
        return 0;
    for (i = 0; i < w->contacts->entry_count + w->contacts->parked_count; ++i) { /* (parked: contact.c) */
        const tb__entry *e = i < w->contacts->entry_count ? &w->contacts->entries[i]
                                                          : &w->contacts->parked[i - w->contacts->entry_count];
        for (k = 0; k < e->count; ++k)
            if (e->point[k].active && -e->point[k].separation > deepest)
                deepest = -e->point[k].separation;
    }
    return deepest;
}
