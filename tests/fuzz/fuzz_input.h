// SPDX-License-Identifier: Apache-2.0
/* Reading a fuzzer's bytes as typed values; past the end everything is 0. */
#ifndef FLT_FUZZ_INPUT_H
#define FLT_FUZZ_INPUT_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

typedef struct fuzz_input {
    const uint8_t *p;
    size_t n;
} fuzz_input;

static inline uint8_t fuzz_u8(fuzz_input *in) {
    if (in->n == 0)
        return 0;
    --in->n;
    return *in->p++;
}
static inline uint32_t fuzz_u32(fuzz_input *in) {
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i)
        v |= (uint32_t)fuzz_u8(in) << (8 * i);
    return v;
}
/* A double that is often special: NaN, +-Inf, huge, tiny, negative, zero,
 * or a plain value in [-scale, scale]. */
static inline double fuzz_double(fuzz_input *in, double scale) {
    static const double specials[] = {0.0,    -0.0, 1e300, -1e300, 1e-300,
                                      5e-324, -1.0, 1e9,   -1e9,   0.5};
    uint8_t kind = fuzz_u8(in);
    switch (kind & 15) {
        case 0:
            return NAN;
        case 1:
            return INFINITY;
        case 2:
            return -INFINITY;
        case 3:
            return specials[fuzz_u8(in) % (sizeof specials / sizeof specials[0])];
        case 4: {
            uint64_t bits = (uint64_t)fuzz_u32(in) | ((uint64_t)fuzz_u32(in) << 32);
            double d;
            memcpy(&d, &bits, sizeof d);
            return d; /* any bit pattern */
        }
        default:
            return scale * ((double)(int32_t)fuzz_u32(in) / 2147483648.0);
    }
}

#endif
