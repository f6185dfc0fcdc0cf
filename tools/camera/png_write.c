/* SPDX-License-Identifier: Apache-2.0 */
#include "png_write.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#  include <windows.h>
#endif

FILE *utf8_fopen(const char *path, const char *mode) {
#ifdef _WIN32
    wchar_t wpath[1024], wmode[8];
    if (!MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, path, -1, wpath, 1024) ||
        !MultiByteToWideChar(CP_UTF8, 0, mode, -1, wmode, 8))
        return NULL;
    return _wfopen(wpath, wmode);
#else
    return fopen(path, mode);
#endif
}

static uint32_t g_crc_table[256];

static void crc_init(void) {
    for (uint32_t n = 0; n < 256; ++n) {
        uint32_t c = n;
        for (int k = 0; k < 8; ++k)
            c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
        g_crc_table[n] = c;
    }
}

static uint32_t crc_update(uint32_t crc, const uint8_t *p, size_t n) {
    for (size_t i = 0; i < n; ++i)
        crc = g_crc_table[(crc ^ p[i]) & 0xFF] ^ (crc >> 8);
    return crc;
}

static void put_be32(uint8_t *p, uint32_t v) {
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
}

/* A chunk streamed out: header, data in pieces, then the CRC. */
typedef struct chunk_writer {
    FILE *f;
    uint32_t crc;
    int failed;
} chunk_writer;

static void chunk_begin(chunk_writer *w, const char type[4], uint32_t length) {
    uint8_t head[8];
    put_be32(head, length);
    memcpy(head + 4, type, 4);
    if (fwrite(head, 1, 8, w->f) != 8)
        w->failed = 1;
    w->crc = crc_update(0xFFFFFFFFu, head + 4, 4);
}

static void chunk_data(chunk_writer *w, const uint8_t *p, size_t n) {
    if (n && fwrite(p, 1, n, w->f) != n)
        w->failed = 1;
    w->crc = crc_update(w->crc, p, n);
}

static void chunk_end(chunk_writer *w) {
    uint8_t tail[4];
    put_be32(tail, w->crc ^ 0xFFFFFFFFu);
    if (fwrite(tail, 1, 4, w->f) != 4)
        w->failed = 1;
}

int png_write(const char *path, const png_image_desc *image, char *why, size_t why_size) {
    const png_image_desc *im = image;
    if (!im || !im->pixels || im->width == 0 || im->height == 0 ||
        (im->channels != 1 && im->channels != 3) || (im->bit_depth != 8 && im->bit_depth != 16)) {
        snprintf(why, why_size, "no image to write");
        return -1;
    }
    const size_t sample_bytes = (size_t)im->bit_depth / 8;
    const size_t row_bytes = (size_t)im->width * (size_t)im->channels * sample_bytes;
    if (im->stride < row_bytes || row_bytes > 0x7FFFFFFF / 2) {
        snprintf(why, why_size, "image rows of %zu bytes, stride %zu", row_bytes, im->stride);
        return -1;
    }
    /* The zlib stream: 2 header bytes, stored blocks of at most 65535
     * bytes (5 bytes of header each), the Adler-32. */
    const uint64_t raw = (uint64_t)(row_bytes + 1) * im->height;
    const uint64_t blocks = (raw + 65534) / 65535;
    const uint64_t zlen = 2 + raw + 5 * blocks + 4;
    if (zlen > 0x7FFFFFFFu) {
        snprintf(why, why_size, "image too large for one PNG chunk (%llu bytes)",
                 (unsigned long long)raw);
        return -1;
    }
    FILE *f = utf8_fopen(path, "wb");
    if (!f) {
        snprintf(why, why_size, "cannot create '%s': %s", path, strerror(errno));
        return -1;
    }
    crc_init();
    static const uint8_t signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    chunk_writer w = {f, 0, 0};
    if (fwrite(signature, 1, 8, f) != 8)
        w.failed = 1;

    uint8_t ihdr[13];
    put_be32(ihdr, im->width);
    put_be32(ihdr + 4, im->height);
    ihdr[8] = (uint8_t)im->bit_depth;
    ihdr[9] = im->channels == 3 ? 2 : 0; /* colour type: RGB or grey */
    ihdr[10] = ihdr[11] = ihdr[12] = 0;  /* deflate, adaptive filters, no interlace */
    chunk_begin(&w, "IHDR", 13);
    chunk_data(&w, ihdr, 13);
    chunk_end(&w);

    if (im->significant_bits > 0 && im->significant_bits < im->bit_depth) {
        uint8_t sbit[3];
        for (int c = 0; c < im->channels; ++c)
            sbit[c] = (uint8_t)im->significant_bits;
        chunk_begin(&w, "sBIT", (uint32_t)im->channels);
        chunk_data(&w, sbit, (size_t)im->channels);
        chunk_end(&w);
    }

    chunk_begin(&w, "IDAT", (uint32_t)zlen);
    static const uint8_t zhead[2] = {0x78, 0x01};
    chunk_data(&w, zhead, 2);
    uint32_t adler_a = 1, adler_b = 0;
    uint8_t *row = malloc(row_bytes + 1);
    if (!row) {
        fclose(f);
        snprintf(why, why_size, "out of memory");
        return -1;
    }
    /* The filtered rows (filter byte 0, samples big-endian) flow through
     * the stored blocks: `left` bytes remain in the current block. */
    uint64_t remaining = raw;
    size_t left = 0;
    for (uint32_t y = 0; y < im->height; ++y) {
        const uint8_t *src = (const uint8_t *)im->pixels + (size_t)y * im->stride;
        row[0] = 0;
        if (sample_bytes == 1) {
            memcpy(row + 1, src, row_bytes);
        } else {
            const uint16_t *s16 = (const uint16_t *)(const void *)src;
            for (size_t i = 0; i < row_bytes / 2; ++i) {
                row[1 + 2 * i] = (uint8_t)(s16[i] >> 8);
                row[2 + 2 * i] = (uint8_t)s16[i];
            }
        }
        size_t at = 0;
        while (at < row_bytes + 1) {
            if (left == 0) {
                left = remaining > 65535 ? 65535 : (size_t)remaining;
                uint8_t bh[5];
                bh[0] = remaining <= 65535 ? 1 : 0; /* BFINAL, BTYPE 00 (stored) */
                bh[1] = (uint8_t)left;
                bh[2] = (uint8_t)(left >> 8);
                bh[3] = (uint8_t)~left;
                bh[4] = (uint8_t)(~left >> 8);
                chunk_data(&w, bh, 5);
            }
            size_t n = row_bytes + 1 - at;
            if (n > left)
                n = left;
            chunk_data(&w, row + at, n);
            for (size_t i = 0; i < n; ++i) {
                adler_a = (adler_a + row[at + i]) % 65521u;
                adler_b = (adler_b + adler_a) % 65521u;
            }
            at += n;
            left -= n;
            remaining -= n;
        }
    }
    free(row);
    uint8_t adler[4];
    put_be32(adler, (adler_b << 16) | adler_a);
    chunk_data(&w, adler, 4);
    chunk_end(&w);

    chunk_begin(&w, "IEND", 0);
    chunk_end(&w);
    if (fclose(f) != 0)
        w.failed = 1;
    if (w.failed) {
        snprintf(why, why_size, "cannot write '%s': %s", path, strerror(errno));
        return -1;
    }
    return 0;
}
