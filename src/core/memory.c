/* memory.c: memory through the world's allocator, messages, small checks. */
#include "world.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *tb_status_name(tb_status status)
{
    switch (status) {
    case TB_OK: return "ok";
    case TB_ERR_ARGUMENT: return "argument";
    case TB_ERR_STALE_ID: return "stale id";
    case TB_ERR_MEMORY: return "memory";
    case TB_ERR_CALLBACK: return "callback";
    case TB_ERR_BUSY: return "busy";
    case TB_ERR_UNSTABLE: return "unstable";
    }
    return "unknown";
}

void *tb__alloc(tb_world *w, void *ptr, size_t old_size, size_t new_size)
{
    if (w->allocator.realloc)
        return w->allocator.realloc(w->allocator.user, ptr, old_size, new_size);
    if (new_size == 0) {
        free(ptr);
        return NULL;
    }
    return realloc(ptr, new_size);
}

tb_status tb__grow(tb_world *w, void **arrays[], const size_t elem_size[], int n,
                   size_t count, size_t old_cap, size_t new_cap)
{
    void *fresh[16];
    int i;
    if (n > 16)
        return tb__fail(w, TB_ERR_MEMORY, "internal: too many parallel arrays");
    for (i = 0; i < n; ++i) {
        if (new_cap > SIZE_MAX / elem_size[i])
            fresh[i] = NULL;
        else
            fresh[i] = tb__alloc(w, NULL, 0, new_cap * elem_size[i]);
        if (!fresh[i]) {
            while (i-- > 0)
                tb__alloc(w, fresh[i], new_cap * elem_size[i], 0);
            return tb__fail(w, TB_ERR_MEMORY, "out of memory growing arrays to %zu elements", new_cap);
        }
    }
    for (i = 0; i < n; ++i) {
        if (count)
            memcpy(fresh[i], *arrays[i], count * elem_size[i]);
        if (*arrays[i])
            tb__alloc(w, *arrays[i], old_cap * elem_size[i], 0);
        *arrays[i] = fresh[i];
    }
    return TB_OK;
}

tb_status tb__reserve(tb_world *w, void **array, size_t *cap, size_t need, size_t size)
{
    size_t n = *cap ? *cap : 16;
    void *p;
    if (need <= *cap)
        return TB_OK;
    while (n < need && n <= SIZE_MAX / 2)
        n *= 2;
    if (n < need || n > SIZE_MAX / size)
        return tb__fail(w, TB_ERR_MEMORY, "%zu items of %zu bytes overflow the address space", need, size);
    p = tb__alloc(w, *array, *cap * size, n * size);
    if (!p)
        return tb__fail(w, TB_ERR_MEMORY, "out of memory for %zu items of %zu bytes", n, size);
    *array = p;
    *cap = n;
    return TB_OK;
}

void tb__free_arrays(tb_world *w, void **arrays[], const size_t elem_size[], int n, size_t cap)
{
    int i;
    for (i = 0; i < n; ++i) {
        if (*arrays[i])
            tb__alloc(w, *arrays[i], cap * elem_size[i], 0);
        *arrays[i] = NULL;
    }
}

tb_status tb__fail(tb_world *w, tb_status status, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    vsnprintf(w->message, sizeof w->message, fmt, args);
    va_end(args);
    return status;
}

double tb__dot(const double *a, const double *b, size_t n)
{
    double sum = 0;
    size_t i;
    for (i = 0; i < n; ++i)
        sum += a[i] * b[i];
    return sum;
}

int tb__finite3(const double v[3])
{
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

tb_status tb__check_busy(tb_world *w, const char *what)
{
    if (w->stepping)
        return tb__fail(w, TB_ERR_BUSY, "cannot %s while the world is stepping", what);
    return TB_OK;
}

int tb__bounded(double x)
{
    return fabs(x) <= TB_LIMIT; /* NaN fails */
}

tb_status tb__check_values(tb_world *w, const double *v, size_t n, const char *what)
{
    size_t i;
    if (!v)
        return tb__fail(w, TB_ERR_ARGUMENT, "%s must not be NULL", what);
    for (i = 0; i < n; ++i)
        if (!tb__bounded(v[i])) {
            if (n == 1)
                return tb__fail(w, TB_ERR_ARGUMENT, "%s must be finite and at most %g in magnitude (got %g)", what,
                                TB_LIMIT, v[i]);
            return tb__fail(w, TB_ERR_ARGUMENT,
                            "%s must be finite and at most %g in magnitude (component %zu is %g)", what, TB_LIMIT,
                            i, v[i]);
        }
    return TB_OK;
}

int tb__in_scale(double x)
{
    return x >= 1 / TB_LIMIT && x <= TB_LIMIT; /* NaN fails */
}

tb_status tb__check_scale(tb_world *w, double x, const char *what)
{
    if (!tb__in_scale(x))
        return tb__fail(w, TB_ERR_ARGUMENT, "%s must be finite and > 0, from %g to %g (got %g)", what, 1 / TB_LIMIT,
                        TB_LIMIT, x);
    return TB_OK;
}

tb_status tb__check_coefficient(tb_world *w, double x, const char *what)
{
    if (!(x >= 0 && x <= TB_LIMIT))
        return tb__fail(w, TB_ERR_ARGUMENT, "%s must be finite and >= 0, at most %g (got %g)", what, TB_LIMIT, x);
    return TB_OK;
}

tb_status tb__check_derived(tb_world *w, double x, const char *what, const char *unit)
{
    if (!(fabs(x) <= TB_LIMIT))
        return tb__fail(w, TB_ERR_ARGUMENT, "%s would be %g %s, past the limit %g", what, x, unit, TB_LIMIT);
    return TB_OK;
}

tb_status tb__null(tb_world *w, const char *function, const char *what)
{
    return tb__fail(w, TB_ERR_ARGUMENT, "%s: %s must not be NULL", function, what);
}
