/* isa.c: the widest instruction set this processor runs (core.h). */
#include "core/core.h"

int tb__isa(void)
{
#if TB__X86_DISPATCH
    __builtin_cpu_init(); /* cheap once done; needed if called before constructors */
    if (__builtin_cpu_supports("avx512f"))
        return TB__ISA_AVX512;
    if (__builtin_cpu_supports("avx2"))
        return TB__ISA_AVX2;
#endif
    return TB__ISA_PORTABLE;
}
