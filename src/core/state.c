/* state.c: the state vector y and the integrators' scratch vectors. */
#include "world.h"

#include <math.h>
#include <string.h>

static const struct { enum tb__tier tier; size_t width; } quantities[TB__QUANTITY_COUNT] = {
#define TB__ROW(name, tier, width) { tier, width },
    TB__QUANTITIES(TB__ROW)
#undef TB__ROW
};

static size_t count_of(const tb_world *w, enum tb__tier tier)
{
    return tier == TB__TRACERS ? w->tracer_count : tier == TB__PARTICLES ? w->particle_count : w->body_count;
}

static size_t cap_of(const tb_world *w, enum tb__tier tier)
{
    return tier == TB__TRACERS ? w->tracer_cap : tier == TB__PARTICLES ? w->particle_cap : w->body_cap;
}

/* The used parts of y: (offset, length) in doubles. */
static int segments(const tb_world *w, size_t off[TB__QUANTITY_COUNT], size_t len[TB__QUANTITY_COUNT])
{
    int k, n = 0;
    for (k = 0; k < TB__QUANTITY_COUNT; ++k) {
        size_t used = quantities[k].width * count_of(w, quantities[k].tier);
        if (used) {
            off[n] = w->off[k];
            len[n++] = used;
        }
    }
    return n;
}

/* An empty state (and its scratch) points here rather than at NULL, so
   that y + offset stays defined arithmetic before the first object
   (fuzz_api's regressions). Nothing is ever written to it: every loop over
   an empty state runs zero times. */
double tb__empty_state[1];

static void free_scratch(tb_world *w)
{
    if (w->scratch && w->scratch != tb__empty_state)
        tb__alloc(w, w->scratch, w->scratch_count * w->y_size * sizeof(double), 0);
    w->scratch = tb__empty_state;
    w->scratch_count = 0;
}

void tb__state_init(tb_world *w)
{
    w->y = tb__empty_state;
    w->y_size = 0;
    w->scratch = tb__empty_state;
    w->scratch_count = 0;
}

void tb__state_free(tb_world *w)
{
    free_scratch(w);
    if (w->y && w->y != tb__empty_state)
        tb__alloc(w, w->y, w->y_size * sizeof(double), 0);
    w->y = NULL;
    w->scratch = NULL;
}

tb_status tb__state_resize(tb_world *w, enum tb__tier tier, size_t cap)
{
    size_t off[TB__QUANTITY_COUNT], size = 0;
    double *y;
    int k;
    for (k = 0; k < TB__QUANTITY_COUNT; ++k) {
        off[k] = size;
        size += quantities[k].width * (quantities[k].tier == tier ? cap : cap_of(w, quantities[k].tier));
    }
    y = size ? tb__alloc(w, NULL, 0, size * sizeof(double)) : tb__empty_state;
    if (!y)
        return tb__fail(w, TB_ERR_MEMORY, "out of memory for a state of %zu doubles", size);
    free_scratch(w); /* its vectors have the old state's size */
    if (w->y && w->y != tb__empty_state) {
        for (k = 0; k < TB__QUANTITY_COUNT; ++k)
            memcpy(y + off[k], w->y + w->off[k],
                   quantities[k].width * count_of(w, quantities[k].tier) * sizeof(double));
        tb__alloc(w, w->y, w->y_size * sizeof(double), 0);
    }
    w->y = y;
    w->y_size = size;
    memcpy(w->off, off, sizeof off);
    return TB_OK;
}

tb_status tb__state_scratch(tb_world *w, size_t count)
{
    double *s;
    if (w->scratch_count >= count)
        return TB_OK;
    if (count * w->y_size == 0) { /* an empty state: nothing to hold */
        free_scratch(w);
        w->scratch_count = count;
        return TB_OK;
    }
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

/* o = b + a d over n doubles, o == b or apart from both: GCC -O2 vectorises
   only loops of a fixed count it can see through, so the work goes in
   blocks of AXPY_BLOCK with restrict pointers, the rest one by one. The
   same arithmetic either way. */
#define AXPY_BLOCK 8

static void axpy_apart(double *restrict o, const double *restrict b, double a, const double *restrict d, size_t n)
{
    size_t i = 0, k;
    for (; i + AXPY_BLOCK <= n; i += AXPY_BLOCK)
        for (k = 0; k < AXPY_BLOCK; ++k)
            o[i + k] = b[i + k] + a * d[i + k];
    for (; i < n; ++i)
        o[i] = b[i] + a * d[i];
}

static void axpy_in_place(double *restrict o, double a, const double *restrict d, size_t n)
{
    size_t i = 0, k;
    for (; i + AXPY_BLOCK <= n; i += AXPY_BLOCK)
        for (k = 0; k < AXPY_BLOCK; ++k)
            o[i + k] = o[i + k] + a * d[i + k];
    for (; i < n; ++i)
        o[i] = o[i] + a * d[i];
}

void tb__state_axpy(const tb_world *w, double *out, const double *base, double a, const double *dir)
{
    size_t off[TB__QUANTITY_COUNT], len[TB__QUANTITY_COUNT];
    int s, n = segments(w, off, len);
    for (s = 0; s < n; ++s) {
        if (out == base)
            axpy_in_place(out + off[s], a, dir + off[s], len[s]);
        else
            axpy_apart(out + off[s], base + off[s], a, dir + off[s], len[s]);
    }
}

void tb__state_copy(const tb_world *w, double *out, const double *in)
{
    size_t off[TB__QUANTITY_COUNT], len[TB__QUANTITY_COUNT];
    int s, n = segments(w, off, len);
    for (s = 0; s < n; ++s)
        memcpy(out + off[s], in + off[s], len[s] * sizeof(double));
}

double tb__state_error_norm(const tb_world *w, const double *err, const double *y0, const double *y1, double tol)
{
    size_t off[TB__QUANTITY_COUNT], len[TB__QUANTITY_COUNT], i, count = 0;
    double sum = 0;
    int s, n = segments(w, off, len);
    for (s = 0; s < n; ++s)
        for (i = off[s]; i < off[s] + len[s]; ++i) {
            const double scale = tol * (1 + fmax(fabs(y0[i]), fabs(y1[i])));
            sum += (err[i] / scale) * (err[i] / scale);
            ++count;
        }
    return count ? sqrt(sum / (double)count) : 0;
}

void tb__state_scale(const tb_world *w, double *out, double a, const double *in)
{
    size_t off[TB__QUANTITY_COUNT], len[TB__QUANTITY_COUNT], i;
    int s, n = segments(w, off, len);
    for (s = 0; s < n; ++s)
        for (i = off[s]; i < off[s] + len[s]; ++i)
            out[i] = a * in[i];
}

void tb__state_move(tb_world *w, enum tb__tier tier, size_t from, size_t to)
{
    int k;
    for (k = 0; k < TB__QUANTITY_COUNT; ++k)
        if (quantities[k].tier == tier)
            memcpy(w->y + w->off[k] + quantities[k].width * to, w->y + w->off[k] + quantities[k].width * from,
                   quantities[k].width * sizeof(double));
}
