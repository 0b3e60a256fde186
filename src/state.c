/* state.c: the state vector y and the integrators' scratch vectors. */
#include "world.h"

#include <string.h>

/* The used parts of y: (offset, length) in doubles. */
static int segments(const tb_world *w, size_t off[3], size_t len[3])
{
    int n = 0;
    if (w->tracer_count) {
        off[n] = w->off_tracer_pos;
        len[n++] = 3 * w->tracer_count;
    }
    if (w->particle_count) {
        off[n] = w->off_particle_pos;
        len[n++] = 3 * w->particle_count;
        off[n] = w->off_particle_vel;
        len[n++] = 3 * w->particle_count;
    }
    return n;
}

static void free_scratch(tb_world *w)
{
    if (w->scratch)
        tb__alloc(w, w->scratch, w->scratch_count * w->y_size * sizeof(double), 0);
    w->scratch = NULL;
    w->scratch_count = 0;
}

tb_status tb__state_resize(tb_world *w, size_t tracer_cap, size_t particle_cap)
{
    size_t size = 3 * tracer_cap + 6 * particle_cap;
    double *y = tb__alloc(w, NULL, 0, size * sizeof(double));
    if (!y)
        return tb__fail(w, TB_ERR_MEMORY, "out of memory for a state of %zu doubles", size);
    if (w->y) {
        memcpy(y, w->y + w->off_tracer_pos, 3 * w->tracer_count * sizeof(double));
        memcpy(y + 3 * tracer_cap, w->y + w->off_particle_pos, 3 * w->particle_count * sizeof(double));
        memcpy(y + 3 * tracer_cap + 3 * particle_cap, w->y + w->off_particle_vel,
               3 * w->particle_count * sizeof(double));
        free_scratch(w);
        tb__alloc(w, w->y, w->y_size * sizeof(double), 0);
    }
    w->y = y;
    w->y_size = size;
    w->off_tracer_pos = 0;
    w->off_particle_pos = 3 * tracer_cap;
    w->off_particle_vel = 3 * tracer_cap + 3 * particle_cap;
    return TB_OK;
}

tb_status tb__state_scratch(tb_world *w, size_t count)
{
    double *s;
    if (w->scratch_count >= count)
        return TB_OK;
    s = tb__alloc(w, NULL, 0, count * w->y_size * sizeof(double));
    if (!s)
        return tb__fail(w, TB_ERR_MEMORY, "out of memory for %zu integrator vectors", count);
    free_scratch(w);
    w->scratch = s;
    w->scratch_count = count;
    return TB_OK;
}

double *tb__scratch_vector(tb_world *w, size_t k)
{
    return w->scratch + k * w->y_size;
}

void tb__state_axpy(const tb_world *w, double *out, const double *base, double a, const double *dir)
{
    size_t off[3], len[3], i;
    int s, n = segments(w, off, len);
    for (s = 0; s < n; ++s) {
        double *o = out + off[s];
        const double *b = base + off[s], *d = dir + off[s];
        for (i = 0; i < len[s]; ++i)
            o[i] = b[i] + a * d[i];
    }
}

void tb__state_copy(const tb_world *w, double *out, const double *in)
{
    size_t off[3], len[3];
    int s, n = segments(w, off, len);
    for (s = 0; s < n; ++s)
        memcpy(out + off[s], in + off[s], len[s] * sizeof(double));
}
