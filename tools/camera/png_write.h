/* SPDX-License-Identifier: Apache-2.0 */
/*
 * A PNG writer with no dependency: grey or RGB, 8 or 16 bits, the image
 * data in stored (uncompressed) deflate blocks. A frame of a laser-line
 * camera is written once per snapshot, so size matters less than a tool
 * that builds anywhere the library does (no zlib or libpng to find on
 * Windows).
 */
#ifndef FLATLINE_TOOLS_PNG_WRITE_H
#define FLATLINE_TOOLS_PNG_WRITE_H

#include <stddef.h>
#include <stdint.h>

/* The image: `height` rows `stride` bytes apart; a row holds `width`
 * pixels of `channels` (1 grey, 3 RGB) samples of `bit_depth` bits (8, or
 * 16 as host-order uint16_t). `significant_bits` (1 .. bit_depth, or 0 for
 * all) goes into an sBIT chunk: a Mono12 frame written as 16-bit samples
 * says that only 12 bits carry data. */
typedef struct png_image_desc {
    const void *pixels;
    uint32_t width, height;
    size_t stride;
    int channels, bit_depth, significant_bits;
} png_image_desc;

/* Writes the image to `path` (UTF-8; on Windows opened by its UTF-16
 * name). Returns 0, or -1 with a reason in why[why_size]. */
int png_write(const char *path, const png_image_desc *image, char *why, size_t why_size);

/* fopen() of a UTF-8 path (Windows: _wfopen of its UTF-16 form). */
#include <stdio.h>
FILE *utf8_fopen(const char *path, const char *mode);

#endif
