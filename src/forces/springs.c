/* springs.c: Hooke springs with axial damping between two particles or
   between a particle and a fixed anchor. */
#include "forces/forces.h"

#include <math.h>
#include <string.h>

static void particle_removed(tb_world *w, uint32_t slot, uint32_t last);

tb_spring_def tb_default_spring_def(void)
{
    tb_spring_def def;
    memset(&def, 0, sizeof def);
    def.rest_length = -1;
    return def;
}

static void arrays_of(tb_world *w, void **arrays[6], size_t sizes[6])
{
    arrays[0] = (void **)&w->spring_a;      sizes[0] = sizeof(uint32_t);
    arrays[1] = (void **)&w->spring_b;      sizes[1] = sizeof(uint32_t);
    arrays[2] = (void **)&w->spring_anchor; sizes[2] = 3 * sizeof(double);
    arrays[3] = (void **)&w->spring_k;      sizes[3] = sizeof(double);
    arrays[4] = (void **)&w->spring_c;      sizes[4] = sizeof(double);
    arrays[5] = (void **)&w->spring_rest;   sizes[5] = sizeof(double);
}

static double distance(const double *a, const double *b)
{
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

tb_status tb_world_add_spring(tb_world *w, const tb_spring_def *def, tb_spring_id *id)
{
    tb_status st;
    uint32_t a, b = TB__ANCHOR, s;
    const double *pos, *pb;
    double rest, stretch;
    tb_spring_id made;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    pos = w->y ? w->y + w->off[TB__PARTICLE_POS] : NULL;
    if ((st = tb__check_busy(w, "add a spring")) != TB_OK)
        return st;
    if (!def)
        return tb__fail(w, TB_ERR_ARGUMENT, "spring definition must not be NULL");
    if (!tb__ids_lookup(&w->particle_ids, def->a.index1, def->a.generation, &a))
        return tb__fail(w, TB_ERR_STALE_ID, "spring end a: particle id %u.%u is null, removed or from another world",
                        def->a.index1, def->a.generation);
    if (!TB_ID_IS_NULL(def->b) && !tb__ids_lookup(&w->particle_ids, def->b.index1, def->b.generation, &b))
        return tb__fail(w, TB_ERR_STALE_ID, "spring end b: particle id %u.%u is removed or from another world",
                        def->b.index1, def->b.generation);
    if (a == b)
        return tb__fail(w, TB_ERR_ARGUMENT, "a spring cannot join a particle to itself");
    if (b == TB__ANCHOR && (st = tb__check_values(w, def->anchor, 3, "spring anchor")) != TB_OK)
        return st;
    if ((st = tb__check_coefficient(w, def->stiffness, "spring stiffness")) != TB_OK ||
        (st = tb__check_coefficient(w, def->damping, "spring damping")) != TB_OK ||
        (st = tb__check_values(w, &def->rest_length, 1, "spring rest length")) != TB_OK)
        return st;
    /* what it starts with: its rest length (the distance, by default), and
       the force and energy of its stretch */
    pb = b == TB__ANCHOR ? def->anchor : pos + 3 * b;
    rest = def->rest_length >= 0 ? def->rest_length : distance(pos + 3 * a, pb);
    stretch = fabs(distance(pos + 3 * a, pb) - rest);
    if ((st = tb__check_derived(w, rest, "spring rest length", "m")) != TB_OK ||
        (st = tb__check_derived(w, def->stiffness * stretch, "spring force k |d - rest|", "N")) != TB_OK ||
        (st = tb__check_derived(w, 0.5 * def->stiffness * stretch * stretch, "spring energy k (d - rest)^2 / 2",
                                "J")) != TB_OK)
        return st;
    if (w->spring_count == w->spring_cap) {
        size_t cap = w->spring_cap ? 2 * w->spring_cap : 8;
        void **arrays[6];
        size_t sizes[6];
        arrays_of(w, arrays, sizes);
        if ((st = tb__ids_reserve(w, &w->spring_ids, cap)) != TB_OK)
            return st;
        if ((st = tb__grow(w, arrays, sizes, 6, w->spring_count, w->spring_cap, cap)) != TB_OK)
            return st;
        w->spring_cap = cap;
    }
    s = (uint32_t)w->spring_count++;
    w->particle_removed[TB__HEARS_SPRINGS] = particle_removed;
    w->spring_a[s] = a;
    w->spring_b[s] = b;
    memcpy(w->spring_anchor + 3 * s, def->anchor, 3 * sizeof(double));
    w->spring_k[s] = def->stiffness;
    w->spring_c[s] = def->damping;
    w->spring_damped += def->damping != 0;
    w->spring_rest[s] = rest;
    tb__ids_acquire(&w->spring_ids, w->id_tag, s, &made.index1, &made.generation);
    if (id)
        *id = made;
    return TB_OK;
}

static void remove_slot(tb_world *w, uint32_t s)
{
    uint32_t last = (uint32_t)w->spring_count - 1, index1, generation;
    tb__ids_at(&w->spring_ids, s, &index1, &generation);
    w->spring_damped -= w->spring_c[s] != 0;
    if (s != last) {
        w->spring_a[s] = w->spring_a[last];
        w->spring_b[s] = w->spring_b[last];
        memcpy(w->spring_anchor + 3 * s, w->spring_anchor + 3 * last, 3 * sizeof(double));
        w->spring_k[s] = w->spring_k[last];
        w->spring_c[s] = w->spring_c[last];
        w->spring_rest[s] = w->spring_rest[last];
        tb__ids_move(&w->spring_ids, last, s);
    }
    tb__ids_release(&w->spring_ids, index1);
    w->spring_count--;
}

tb_status tb_world_remove_spring(tb_world *w, tb_spring_id id)
{
    tb_status st;
    uint32_t s;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if ((st = tb__check_busy(w, "remove a spring")) != TB_OK)
        return st;
    if (!tb__ids_lookup(&w->spring_ids, id.index1, id.generation, &s))
        return tb__fail(w, TB_ERR_STALE_ID, "spring id %u.%u is null, removed or from another world",
                        id.index1, id.generation);
    remove_slot(w, s);
    return TB_OK;
}

size_t tb_world_spring_count(const tb_world *w)
{
    TB__NEED_WORLD(w, 0);
    return w->spring_count;
}

tb_spring_id tb_world_spring_at(const tb_world *w, size_t slot)
{
    tb_spring_id id = { 0, 0 };
    if (w && slot < w->spring_count)
        tb__ids_at(&w->spring_ids, (uint32_t)slot, &id.index1, &id.generation);
    return id;
}

tb_status tb_spring_definition(const tb_world *w, tb_spring_id id, tb_spring_def *def)
{
    uint32_t s;
    TB__NEED_WORLD(w, TB_ERR_ARGUMENT);
    if (!def)
        return tb__null((tb_world *)w, "tb_spring_definition", "the output");
    if (!tb__ids_lookup(&w->spring_ids, id.index1, id.generation, &s))
        return tb__fail((tb_world *)w, TB_ERR_STALE_ID, "spring id %u.%u is null, removed or from another world",
                        id.index1, id.generation);
    memset(def, 0, sizeof *def);
    tb__ids_at(&w->particle_ids, w->spring_a[s], &def->a.index1, &def->a.generation);
    if (w->spring_b[s] != TB__ANCHOR)
        tb__ids_at(&w->particle_ids, w->spring_b[s], &def->b.index1, &def->b.generation);
    else
        memcpy(def->anchor, w->spring_anchor + 3 * s, sizeof def->anchor);
    def->stiffness = w->spring_k[s];
    def->damping = w->spring_c[s];
    def->rest_length = w->spring_rest[s];
    return TB_OK;
}

/* A particle was removed from slot `slot`, the last one moved into it:
   its springs go with it, and springs of the moved one follow it. */
static void particle_removed(tb_world *w, uint32_t slot, uint32_t last)
{
    size_t s = w->spring_count;
    while (s-- > 0)
        if (w->spring_a[s] == slot || w->spring_b[s] == slot)
            remove_slot(w, (uint32_t)s);
    if (slot == last)
        return;
    for (s = 0; s < w->spring_count; ++s) {
        if (w->spring_a[s] == last)
            w->spring_a[s] = slot;
        if (w->spring_b[s] == last)
            w->spring_b[s] = slot;
    }
}

void tb__springs_free(tb_world *w)
{
    void **arrays[6];
    size_t sizes[6];
    arrays_of(w, arrays, sizes);
    tb__free_arrays(w, arrays, sizes, 6, w->spring_cap);
    tb__ids_free(w, &w->spring_ids);
    w->spring_count = w->spring_cap = w->spring_damped = 0;
}

void tb__spring_forces(const tb_world *w, const double *pos, const double *vel, double *force)
{
    static const double zero[3] = { 0, 0, 0 };
    size_t s;
    for (s = 0; s < w->spring_count; ++s) {
        const uint32_t a = w->spring_a[s], b = w->spring_b[s];
        const double *xa = pos + 3 * a, *va = vel + 3 * a;
        const double *xb = b == TB__ANCHOR ? w->spring_anchor + 3 * s : pos + 3 * b;
        const double *vb = b == TB__ANCHOR ? zero : vel + 3 * b;
        const double dx = xa[0] - xb[0], dy = xa[1] - xb[1], dz = xa[2] - xb[2];
        const double len = sqrt(dx * dx + dy * dy + dz * dz);
        double nx, ny, nz, mag;
        if (len == 0) /* no direction: a coincident pair pushes nowhere */
            continue;
        nx = dx / len;
        ny = dy / len;
        nz = dz / len;
        mag = -(w->spring_k[s] * (len - w->spring_rest[s]) +
                w->spring_c[s] * ((va[0] - vb[0]) * nx + (va[1] - vb[1]) * ny + (va[2] - vb[2]) * nz));
        force[3 * a] += mag * nx;
        force[3 * a + 1] += mag * ny;
        force[3 * a + 2] += mag * nz;
        if (b != TB__ANCHOR) {
            force[3 * b] -= mag * nx;
            force[3 * b + 1] -= mag * ny;
            force[3 * b + 2] -= mag * nz;
        }
    }
}

double tb__spring_energy(const tb_world *w, const double *pos)
{
    double e = 0;
    size_t s;
    for (s = 0; s < w->spring_count; ++s) {
        const uint32_t b = w->spring_b[s];
        const double *xb = b == TB__ANCHOR ? w->spring_anchor + 3 * s : pos + 3 * b;
        const double stretch = distance(pos + 3 * w->spring_a[s], xb) - w->spring_rest[s];
        e += 0.5 * w->spring_k[s] * stretch * stretch;
    }
    return e;
}

/* out += K u, with K = -d(spring forces)/dx at positions `pos`: for a spring
   of length L along n, the block k (n n^T + (1 - rest / L)(1 - n n^T)) acts
   on the difference of its ends' displacements (an anchor does not move).
   The second term, the geometric stiffness of a stretched spring, vanishes
   at rest length; for a compressed spring it is negative, and `definite`
   clamps it at 0 so that K stays positive semi-definite (what a conjugate
   gradient solve needs). Damping is left out: K is the stiffness that sets
   the oscillation frequencies. */
void tb__spring_stiffness_product(const tb_world *w, const double *pos, const double *u, double *out, int definite)
{
    size_t s;
    for (s = 0; s < w->spring_count; ++s) {
        const uint32_t a = w->spring_a[s], b = w->spring_b[s];
        const double *xa = pos + 3 * a;
        const double *xb = b == TB__ANCHOR ? w->spring_anchor + 3 * s : pos + 3 * b;
        const double d[3] = { xa[0] - xb[0], xa[1] - xb[1], xa[2] - xb[2] };
        const double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        double du[3], n[3], along, geometric, f[3];
        int k;
        if (len == 0)
            continue;
        for (k = 0; k < 3; ++k) {
            n[k] = d[k] / len;
            du[k] = u[3 * a + k] - (b == TB__ANCHOR ? 0 : u[3 * b + k]);
        }
        along = n[0] * du[0] + n[1] * du[1] + n[2] * du[2];
        geometric = 1 - w->spring_rest[s] / len;
        if (definite && geometric < 0)
            geometric = 0;
        for (k = 0; k < 3; ++k)
            f[k] = w->spring_k[s] * (n[k] * along + geometric * (du[k] - n[k] * along));
        for (k = 0; k < 3; ++k) {
            out[3 * a + k] += f[k];
            if (b != TB__ANCHOR)
                out[3 * b + k] -= f[k];
        }
    }
}

/* out += D u, D = -d(spring forces)/dv: each spring's damping c n n^T on the
   difference of its ends' velocities. */
void tb__spring_damping_product(const tb_world *w, const double *pos, const double *u, double *out)
{
    size_t s;
    for (s = 0; s < w->spring_count; ++s) {
        const uint32_t a = w->spring_a[s], b = w->spring_b[s];
        const double *xa = pos + 3 * a;
        const double *xb = b == TB__ANCHOR ? w->spring_anchor + 3 * s : pos + 3 * b;
        const double d[3] = { xa[0] - xb[0], xa[1] - xb[1], xa[2] - xb[2] };
        const double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        double along = 0;
        int k;
        if (len == 0 || w->spring_c[s] == 0)
            continue;
        for (k = 0; k < 3; ++k)
            along += d[k] / len * (u[3 * a + k] - (b == TB__ANCHOR ? 0 : u[3 * b + k]));
        for (k = 0; k < 3; ++k) {
            const double f = w->spring_c[s] * along * d[k] / len;
            out[3 * a + k] += f;
            if (b != TB__ANCHOR)
                out[3 * b + k] -= f;
        }
    }
}
