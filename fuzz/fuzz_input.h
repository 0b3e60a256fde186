/* fuzz_input.h: the fuzz targets' reader of their input: bytes, small
   counts and doubles drawn from a byte string, with the doubles that break
   arithmetic (0, denormals, huge, NaN, Inf) more likely than raw bits. The
   reader returns zeros once the input runs out. */
#ifndef TUMBLE_FUZZ_INPUT_H
#define TUMBLE_FUZZ_INPUT_H
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

typedef struct fuzz_input {
    const uint8_t *data;
    size_t size, at;
} fuzz_input;

static int fuzz_more(const fuzz_input *in)
{
    return in->at < in->size;
}

static unsigned fuzz_byte(fuzz_input *in)
{
    return in->at < in->size ? in->data[in->at++] : 0;
}

/* 0 .. n - 1 */
static unsigned fuzz_below(fuzz_input *in, unsigned n)
{
    return n ? fuzz_byte(in) % n : 0;
}

static double fuzz_double(fuzz_input *in)
{
    static const double special[] = { 0, -0.0, 1, -1, 0.5, 1e-3, 10, 1e6, 1e150, 1e300, 5e-324, 1e-300, DBL_MAX, 0.1 };
    const unsigned pick = fuzz_byte(in);
    double x;
    uint64_t bits = 0;
    size_t k;
    if (pick < sizeof special / sizeof special[0])
        return special[pick];
    if (pick == 0xF0)
        return NAN;
    if (pick == 0xF1)
        return INFINITY;
    if (pick == 0xF2)
        return -INFINITY;
    if (pick < 0x80) /* small and ordinary: -8 .. 8 in steps of 1/16 */
        return ((double)fuzz_byte(in) - 128) / 16;
    for (k = 0; k < 8; ++k)
        bits = bits << 8 | fuzz_byte(in);
    memcpy(&x, &bits, sizeof x);
    return x;
}

static void fuzz_vector(fuzz_input *in, double v[3])
{
    v[0] = fuzz_double(in), v[1] = fuzz_double(in), v[2] = fuzz_double(in);
}
#endif
