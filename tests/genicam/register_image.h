/* SPDX-License-Identifier: Apache-2.0 */
/*
 * Test helper: the register contents a GenICam description is evaluated
 * against, without a camera. Both the library's test (test_genicam_files.c)
 * and the independent evaluator built on aravis (aravis_eval.c) read
 * registers through this one function, so their values can be compared.
 *
 * Images:
 *   0       every byte 0
 *   1 .. 3  pseudo-random bytes (a hash of the image and the address)
 *   4       small 32-bit little-endian words: each aligned word holds 0..3
 *   5       the same small words, big endian
 * Small words make enumerations and booleans match their entries often;
 * random bytes reach every bit of masks, signs and formulas.
 */
#ifndef FLT_TEST_REGISTER_IMAGE_H
#define FLT_TEST_REGISTER_IMAGE_H

#include <stdint.h>

#define FLT_REGISTER_IMAGES 6

static inline uint64_t flt_image_hash(uint64_t x) {
    /* splitmix64's finaliser */
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

static inline uint8_t flt_image_byte(unsigned image, uint64_t address) {
    if (image == 0)
        return 0;
    if (image <= 3)
        return (uint8_t)flt_image_hash(address * 4 + image);
    {
        const uint64_t word = address >> 2;
        const unsigned offset = (unsigned)(address & 3);
        const uint8_t value = (uint8_t)(flt_image_hash(word * 8 + image) & 3);
        if (image == 4)
            return offset == 0 ? value : 0;
        return offset == 3 ? value : 0;
    }
}

#endif
