/* envelope.c: factors of matrices stored by their envelope: each row
   from its first nonzero column to the diagonal, and for a matrix that
   is not symmetric each column from the same row down to it (core.h,
   tb__envelope). The Cholesky factor L L^T of a symmetric positive
   definite one, and L U of one near it (without pivoting), have the same
   envelope, so a band (a stack of bodies, a chain of joints) costs its
   rows times the band's width squared. Rows left out are factored as the
   identity, so a solve over the others needs no copy of the matrix. */
#include "core/core.h"

#include <math.h>

static int used(const tb__envelope *e, size_t i)
{
    return !e->use || e->use[i];
}

int tb__envelope_factor(const tb__envelope *e, size_t from, size_t to)
{
    size_t i, j, q;
    for (i = from; i < to; ++i) {
        double *li = e->l + e->offset[i] - e->first[i];
        const double *ai = e->a + e->offset[i] - e->first[i];
        double d;
        for (j = e->first[i]; j < i; ++j) {
            const double *lj = e->l + e->offset[j] - e->first[j];
            double sum = used(e, i) && used(e, j) ? ai[j] : 0;
            for (q = e->first[i] > e->first[j] ? e->first[i] : e->first[j]; q < j; ++q)
                sum -= li[q] * lj[q];
            li[j] = sum / lj[j];
        }
        d = used(e, i) ? ai[i] : 1;
        for (q = e->first[i]; q < i; ++q)
            d -= li[q] * li[q];
        if (e->drop > 0 && used(e, i) && !(d > e->drop * ai[i])) {
            /* the row depends on those before it: left out */
            e->use[i] = 0;
            for (q = e->first[i]; q < i; ++q)
                li[q] = 0;
            d = 1;
        }
        if (!(d > 0))
            return 0;
        li[i] = sqrt(d);
    }
    return 1;
}

void tb__envelope_solve(const tb__envelope *e, size_t from, size_t to, double *x)
{
    size_t i, q;
    for (i = from; i < to; ++i) {
        const double *li = e->l + e->offset[i] - e->first[i];
        double sum = x[i];
        for (q = e->first[i]; q < i; ++q)
            sum -= li[q] * x[q];
        x[i] = sum / li[i];
    }
    for (i = to; i-- > from;) {
        const double *li = e->l + e->offset[i] - e->first[i];
        x[i] /= li[i];
        for (q = e->first[i]; q < i; ++q)
            x[q] -= li[q] * x[i];
    }
}

int tb__envelope_lu(const tb__envelope *e, double *upper, size_t from, size_t to)
{
    size_t i, j, q;
    double *lo = (double *)e->a; /* factored in place (the caller's a is its own) */
    for (i = from; i < to; ++i) {
        double *li = lo + e->offset[i] - e->first[i], *ui = upper + e->offset[i] - e->first[i];
        const double diagonal = li[i];
        double d;
        for (j = e->first[i]; j < i; ++j) {
            const double *lj = lo + e->offset[j] - e->first[j], *uj = upper + e->offset[j] - e->first[j];
            double below = li[j], above = ui[j];
            if (!used(e, i) || !used(e, j)) {
                li[j] = ui[j] = 0;
                continue;
            }
            for (q = e->first[i] > e->first[j] ? e->first[i] : e->first[j]; q < j; ++q) {
                below -= li[q] * uj[q];
                above -= lj[q] * ui[q];
            }
            li[j] = below / lj[j];
            ui[j] = above;
        }
        d = used(e, i) ? li[i] : 1;
        for (q = e->first[i]; q < i; ++q)
            d -= li[q] * ui[q];
        if (e->drop > 0 && used(e, i) && !(fabs(d) > e->drop * fabs(diagonal))) {
            e->use[i] = 0;
            for (q = e->first[i]; q < i; ++q)
                li[q] = ui[q] = 0;
            d = 1;
        }
        if (!(d != 0) || !isfinite(d))
            return 0;
        li[i] = d;
    }
    return 1;
}

void tb__envelope_lu_solve(const tb__envelope *e, const double *upper, size_t from, size_t to, double *x)
{
    size_t i, q;
    for (i = from; i < to; ++i) {
        const double *li = e->a + e->offset[i] - e->first[i];
        double sum = x[i];
        for (q = e->first[i]; q < i; ++q)
            sum -= li[q] * x[q];
        x[i] = sum;
    }
    for (i = to; i-- > from;) {
        const double *li = e->a + e->offset[i] - e->first[i], *ui = upper + e->offset[i] - e->first[i];
        x[i] /= li[i];
        for (q = e->first[i]; q < i; ++q)
            x[q] -= ui[q] * x[i];
    }
}
