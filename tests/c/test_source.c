// SPDX-License-Identifier: Apache-2.0
/*
 * Frame sources (flatline/source.h): the simulator behind flt_source gives
 * the simulator's own bytes and encoder positions; image sequences read
 * PNG and TIFF files written here, with encoder positions from a CSV file
 * or a fixed step; the encoder modes; bad input. Pixel values and positions
 * are exact (files are lossless, positions are binary fractions), so the
 * tolerances are 0.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <zlib.h>

#include "flatline/flatline.h"
#include "flatline/source.h"
#include "test_files.h"

#define ok(call) assert_int_equal((call), FLT_OK)

static void assert_error(flt_status got, flt_status want, const char *needle) {
    if (got != want)
        fail_msg("status %s, expected %s (%s)", flt_status_string(got), flt_status_string(want),
                 flt_last_error_message());
    if (needle && !strstr(flt_last_error_message(), needle))
        fail_msg("message '%s' does not mention '%s'", flt_last_error_message(), needle);
}

/* --- tiny image writers (PNG through zlib, uncompressed TIFF) ------------- */

static void put32be(uint8_t *p, uint32_t v) {
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
}

static void png_chunk(FILE *f, const char *type, const uint8_t *body, uint32_t n) {
    uint8_t head[8];
    put32be(head, n);
    memcpy(head + 4, type, 4);
    fwrite(head, 1, 8, f);
    if (n)
        fwrite(body, 1, n, f);
    uLong crc = crc32(0, (const Bytef *)type, 4);
    if (n)
        crc = crc32(crc, body, n);
    uint8_t tail[4];
    put32be(tail, (uint32_t)crc);
    fwrite(tail, 1, 4, f);
}

/* 8-bit PNG, grey (channels 1) or RGB (channels 3). */
static void write_png(const char *path, uint32_t w, uint32_t h, int channels,
                      const uint8_t *pixels) {
    FILE *f = tf_fopen(path, "wb");
    assert_non_null(f);
    static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
    fwrite(sig, 1, 8, f);
    uint8_t ihdr[13];
    put32be(ihdr, w);
    put32be(ihdr + 4, h);
    ihdr[8] = 8;
    ihdr[9] = channels == 3 ? 2 : 0;
    ihdr[10] = ihdr[11] = ihdr[12] = 0;
    png_chunk(f, "IHDR", ihdr, 13);
    const size_t row = (size_t)w * channels;
    size_t raw_n = (row + 1) * h;
    uint8_t *raw = malloc(raw_n);
    for (uint32_t y = 0; y < h; ++y) {
        raw[y * (row + 1)] = 0; /* filter: none */
        memcpy(raw + y * (row + 1) + 1, pixels + y * row, row);
    }
    uLongf packed_n = compressBound(raw_n);
    uint8_t *packed = malloc(packed_n);
    assert_int_equal(compress2(packed, &packed_n, raw, raw_n, 6), Z_OK);
    png_chunk(f, "IDAT", packed, (uint32_t)packed_n);
    png_chunk(f, "IEND", NULL, 0);
    fclose(f);
    free(raw);
    free(packed);
}

static void put16le(uint8_t *p, uint16_t v) {
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}
static void put32le(uint8_t *p, uint32_t v) {
    for (int i = 0; i < 4; ++i)
        p[i] = (uint8_t)(v >> (8 * i));
}

/* 16-bit grey baseline TIFF, one uncompressed strip. */
static void write_tiff16(const char *path, uint32_t w, uint32_t h, const uint16_t *pixels) {
    enum { entries = 9 };
    const uint32_t ifd = 8, data = ifd + 2 + entries * 12 + 4;
    uint8_t head[8 + 2 + entries * 12 + 4];
    memset(head, 0, sizeof head);
    head[0] = 'I';
    head[1] = 'I';
    put16le(head + 2, 42);
    put32le(head + 4, ifd);
    put16le(head + 8, entries);
    const uint32_t tags[entries][3] = {{256, 4, w}, {257, 4, h}, {258, 3, 16},
                                       {259, 3, 1}, {262, 3, 1}, {273, 4, data},
                                       {277, 3, 1}, {278, 4, h}, {279, 4, w * h * 2}};
    for (int i = 0; i < entries; ++i) {
        uint8_t *e = head + 10 + 12 * i;
        put16le(e, (uint16_t)tags[i][0]);
        put16le(e + 2, (uint16_t)tags[i][1]);
        put32le(e + 4, 1);
        if (tags[i][1] == 3)
            put16le(e + 8, (uint16_t)tags[i][2]);
        else
            put32le(e + 8, tags[i][2]);
    }
    FILE *f = tf_fopen(path, "wb");
    assert_non_null(f);
    fwrite(head, 1, sizeof head, f);
    for (size_t i = 0; i < (size_t)w * h; ++i) {
        uint8_t b[2];
        put16le(b, pixels[i]);
        fwrite(b, 1, 2, f);
    }
    fclose(f);
}

static void write_text(const char *path, const char *text) {
    FILE *f = tf_fopen(path, "wb");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static uint8_t grey(int frame, uint32_t x, uint32_t y) {
    return (uint8_t)(frame * 40 + x * 3 + y * 5);
}

static char g_dir[256];

static int make_dir(void **state) {
    (void)state;
    return tf_temp_dir(g_dir, sizeof g_dir, "test_source");
}

static int remove_dir(void **state) {
    (void)state;
    return tf_remove_tree(g_dir);
}

/* --- simulator ---------------------------------------------------------------- */

static flt_sim *make_sim(void) {
    flt_calib *calib = NULL;
    /* the reference sensor's rows 892..1147 (both lines), 101 fibers */
    ok(flt_calib_create_reference(892, 256, -1000.0, 20.0, 101, &calib));
    flt_sim *sim = NULL;
    ok(flt_sim_create(calib, NULL, &sim));
    ok(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 5.0, 1800.0));
    flt_calib_destroy(calib);
    return sim;
}

static void test_sim_source_gives_the_simulator_frames(void **state) {
    (void)state;
    flt_sim *a = make_sim(), *b = make_sim();
    flt_source *src = NULL;
    ok(flt_source_create_sim(a, NULL, &src));
    flt_source_kind kind;
    ok(flt_source_kind_of(src, &kind));
    assert_int_equal(kind, FLT_SOURCE_SIMULATOR);
    ok(flt_source_start(src));
    uint8_t *expected = malloc(2048 * 256);
    for (int k = 0; k < 4; ++k) {
        const flt_frame *f = NULL;
        ok(flt_source_next(src, 0, &f));
        const void *pixels;
        uint32_t w, h;
        size_t stride;
        flt_pixel_format format;
        uint64_t block;
        double enc, enc_b;
        ok(flt_frame_info(f, &pixels, &w, &h, &stride, &format, &block, NULL, &enc));
        assert_int_equal(w, 2048);
        assert_int_equal(h, 256);
        assert_int_equal(stride, 2048);
        assert_int_equal(format, FLT_PIXEL_MONO8);
        assert_int_equal(block, (uint64_t)k);
        ok(flt_sim_next_frame(b, expected, 2048 * 256, 2048, &enc_b, 0, NULL, NULL, 0));
        assert_true(enc == enc_b);   /* the simulator's own position */
        assert_true(enc == 3.0 * k); /* frame spacing 3 mm */
        assert_memory_equal(pixels, expected, 2048 * 256);
    }
    uint64_t n = 0;
    ok(flt_source_count(src, FLT_COUNT_FRAMES, &n));
    assert_int_equal(n, 4);
    ok(flt_source_count(src, FLT_COUNT_DROPPED, &n));
    assert_int_equal(n, 0);
    const char *s;
    assert_error(flt_source_camera_string(src, FLT_CAMERA_VENDOR, &s), FLT_ERR_STATE,
                 "not a camera");
    flt_source_destroy(src);
    free(expected);

    /* host encoder: NaN until set, then the value set last */
    flt_options *o = NULL;
    ok(flt_options_create(&o));
    ok(flt_options_set(o, FLT_OPT_SOURCE_ENCODER_MODE, FLT_ENCODER_HOST));
    ok(flt_source_create_sim(a, o, &src));
    ok(flt_source_start(src));
    const flt_frame *f = NULL;
    double enc = 0;
    ok(flt_source_next(src, 0, &f));
    ok(flt_frame_info(f, NULL, NULL, NULL, NULL, NULL, NULL, NULL, &enc));
    assert_true(isnan(enc));
    ok(flt_source_set_encoder(src, 123.5));
    ok(flt_source_next(src, 0, &f));
    ok(flt_frame_info(f, NULL, NULL, NULL, NULL, NULL, NULL, NULL, &enc));
    assert_true(enc == 123.5);
    assert_error(flt_source_set_encoder(src, NAN), FLT_ERR_INVALID_ARGUMENT, "'encoder_mm' = nan");
    flt_source_destroy(src);

    /* fixed step: start + step * frame */
    ok(flt_options_set(o, FLT_OPT_SOURCE_ENCODER_MODE, FLT_ENCODER_FIXED_STEP));
    ok(flt_options_set(o, FLT_OPT_SOURCE_ENCODER_STEP, 2.0));
    ok(flt_options_set(o, FLT_OPT_SOURCE_ENCODER_START, 10.0));
    ok(flt_source_create_sim(a, o, &src));
    ok(flt_source_start(src));
    for (int k = 0; k < 3; ++k) {
        ok(flt_source_next(src, 0, &f));
        ok(flt_frame_info(f, NULL, NULL, NULL, NULL, NULL, NULL, NULL, &enc));
        assert_true(enc == 10.0 + 2.0 * k);
    }
    ok(flt_source_stop(src));
    assert_error(flt_frame_info(f, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL),
                 FLT_ERR_INVALID_ARGUMENT, "not a live frame");
    flt_source_destroy(src);

    ok(flt_options_set(o, FLT_OPT_SOURCE_ENCODER_MODE, FLT_ENCODER_CHUNK));
    assert_error(flt_source_create_sim(a, o, &src), FLT_ERR_INVALID_ARGUMENT,
                 "'source_encoder_mode' = 3");
    assert_null(src);
    assert_error(flt_source_create_sim(NULL, NULL, &src), FLT_ERR_INVALID_ARGUMENT,
                 "'sim' is NULL");
    flt_options_destroy(o);
    flt_sim_destroy(a);
    flt_sim_destroy(b);
}

/* --- image sequences ---------------------------------------------------------------- */

static void test_png_directory_with_encoder_csv(void **state) {
    (void)state;
    enum { W = 40, H = 20 };
    uint8_t pixels[W * H];
    char path[512];
    /* written out of order: the directory is read sorted by name */
    for (int k = 2; k >= 0; --k) {
        for (uint32_t y = 0; y < H; ++y)
            for (uint32_t x = 0; x < W; ++x)
                pixels[y * W + x] = grey(k, x, y);
        snprintf(path, sizeof path, "%s/frame_%02d.png", g_dir, k);
        write_png(path, W, H, 1, pixels);
    }
    snprintf(path, sizeof path, "%s/notes.txt", g_dir);
    write_text(path, "not an image\n");
    char csv[512];
    snprintf(csv, sizeof csv, "%s/encoder.csv", g_dir);
    write_text(csv, "file,encoder_mm\n# recorded on line 3\nframe_00.png,1000.25\n"
                    "frame_01.png,1003.5\r\nframe_02.png, 1006.75\n");
    flt_source *src = NULL;
    ok(flt_source_create_image_dir(g_dir, csv, NULL, &src));
    flt_source_kind kind;
    ok(flt_source_kind_of(src, &kind));
    assert_int_equal(kind, FLT_SOURCE_IMAGES);
    ok(flt_source_start(src));
    const double positions[3] = {1000.25, 1003.5, 1006.75};
    for (int k = 0; k < 3; ++k) {
        const flt_frame *f = NULL;
        ok(flt_source_next(src, 0, &f));
        assert_non_null(f);
        const void *p;
        uint32_t w, h;
        size_t stride;
        flt_pixel_format format;
        uint64_t block;
        double enc;
        ok(flt_frame_info(f, &p, &w, &h, &stride, &format, &block, NULL, &enc));
        assert_int_equal(w, W);
        assert_int_equal(h, H);
        assert_int_equal(format, FLT_PIXEL_MONO8);
        assert_int_equal(block, (uint64_t)k);
        assert_true(enc == positions[k]);
        const uint8_t *px = p;
        for (uint32_t y = 0; y < H; ++y)
            for (uint32_t x = 0; x < W; ++x)
                if (px[y * stride + x] != grey(k, x, y))
                    fail_msg("frame %d pixel (%u, %u) = %u", k, x, y, px[y * stride + x]);
    }
    const flt_frame *f = (const flt_frame *)1;
    ok(flt_source_next(src, 0, &f));
    assert_null(f); /* end of the sequence */
    flt_source_destroy(src);

    /* a CSV naming the wrong file, too few rows, not a number */
    write_text(csv, "frame_00.png,1\nframe_02.png,2\nframe_01.png,3\n");
    assert_error(flt_source_create_image_dir(g_dir, csv, NULL, &src), FLT_ERR_FORMAT,
                 "line 2 names 'frame_02.png', but image 1 is 'frame_01.png'");
    write_text(csv, "1\n2\n");
    assert_error(flt_source_create_image_dir(g_dir, csv, NULL, &src), FLT_ERR_FORMAT,
                 "2 positions for 3 images");
    write_text(csv, "1\nabc\n3\n");
    assert_error(flt_source_create_image_dir(g_dir, csv, NULL, &src), FLT_ERR_FORMAT,
                 "line 2: 'abc' is not a number");
    assert_null(src);
}

static void test_tiff16_list_with_fixed_step(void **state) {
    (void)state;
    enum { W = 24, H = 10 };
    uint16_t pixels[W * H];
    char names[3][512];
    const char *paths[3];
    for (int k = 0; k < 3; ++k) {
        for (int i = 0; i < W * H; ++i)
            pixels[i] = (uint16_t)((k * 997 + i * 13) & 0x0FFF);
        snprintf(names[k], sizeof names[k], "%s/t%d.tif", g_dir, k);
        write_tiff16(names[k], W, H, pixels);
        paths[k] = names[k];
    }
    flt_options *o = NULL;
    ok(flt_options_create(&o));
    ok(flt_options_set(o, FLT_OPT_SOURCE_IMAGE_BITS, 12));
    ok(flt_options_set(o, FLT_OPT_SOURCE_ENCODER_STEP, 1.5));
    flt_source *src = NULL;
    ok(flt_source_create_images(paths, 3, NULL, o, &src));
    ok(flt_source_start(src));
    for (int k = 0; k < 3; ++k) {
        const flt_frame *f = NULL;
        ok(flt_source_next(src, 0, &f));
        const void *p;
        size_t stride;
        flt_pixel_format format;
        double enc;
        ok(flt_frame_info(f, &p, NULL, NULL, &stride, &format, NULL, NULL, &enc));
        assert_int_equal(format, FLT_PIXEL_MONO12);
        assert_int_equal(stride, W * 2);
        assert_true(enc == 1.5 * k);
        const uint16_t *px = p;
        for (int i = 0; i < W * H; ++i)
            if (px[i] != ((k * 997 + i * 13) & 0x0FFF))
                fail_msg("tiff %d pixel %d", k, i);
    }
    flt_source_destroy(src);

    /* 10 bits of a 8-bit file, a colour image, a missing file, a size change */
    uint8_t rgb[W * H * 3];
    memset(rgb, 7, sizeof rgb);
    char path[512];
    snprintf(path, sizeof path, "%s/colour.png", g_dir);
    write_png(path, W, H, 3, rgb);
    const char *colour[1] = {path};
    assert_error(flt_source_create_images(colour, 1, NULL, NULL, &src), FLT_ERR_FORMAT,
                 "has 3 channels");
    const char *missing[1] = {"/nonexistent/x.png"};
    assert_error(flt_source_create_images(missing, 1, NULL, NULL, &src), FLT_ERR_IO,
                 "'/nonexistent/x.png' cannot be read");
    ok(flt_options_set(o, FLT_OPT_SOURCE_IMAGE_BITS, 11));
    assert_error(flt_source_create_images(paths, 3, NULL, o, &src), FLT_ERR_INVALID_ARGUMENT,
                 "'source_image_bits' = 11");
    uint8_t small[16 * 8];
    memset(small, 1, sizeof small);
    char other[512];
    snprintf(other, sizeof other, "%s/small.png", g_dir);
    write_png(other, 16, 8, 1, small);
    const char *mixed[3] = {paths[0], other, paths[2]};
    ok(flt_source_create_images(mixed, 3, NULL, NULL, &src));
    ok(flt_source_start(src));
    const flt_frame *f = NULL;
    ok(flt_source_next(src, 0, &f));
    assert_error(flt_source_next(src, 0, &f), FLT_ERR_FORMAT, "is 16 x 8, 8 bits");
    ok(flt_source_next(src, 0, &f)); /* the sequence goes on */
    assert_non_null(f);
    flt_source_destroy(src);
    assert_error(flt_source_create_images(NULL, 1, NULL, NULL, &src), FLT_ERR_INVALID_ARGUMENT,
                 "'paths' is NULL");
    assert_error(flt_source_create_images(paths, 0, NULL, NULL, &src), FLT_ERR_INVALID_ARGUMENT,
                 "'count' is 0");
    const char *with_null[2] = {paths[0], NULL};
    assert_error(flt_source_create_images(with_null, 2, NULL, NULL, &src), FLT_ERR_INVALID_ARGUMENT,
                 "'paths[1]' is NULL");
    assert_error(flt_source_create_image_dir("/nonexistent-dir", NULL, NULL, &src), FLT_ERR_IO,
                 "cannot be opened");
    char empty[600];
    snprintf(empty, sizeof empty, "%s/empty", g_dir);
    assert_int_equal(tf_mkdir(empty), 0);
    assert_error(flt_source_create_image_dir(empty, NULL, NULL, &src), FLT_ERR_NOT_FOUND,
                 "no .png");
    flt_options_destroy(o);
}

/* Paths are UTF-8 (source.h): a folder, images and an encoder CSV with
 * non-ASCII names are found and read by those names, and the CSV's file
 * names are compared as UTF-8. On Windows the narrow C calls and
 * cv::imread would read the bytes in the ANSI code page and miss them. */
static void test_utf8_paths(void **state) {
    (void)state;
    enum { W = 12, H = 6 };
    char dir[512], path[3][600], csv[600];
    /* "Bänder-テスト", "bild-ä0.png", "Geber-ö.csv" */
    snprintf(dir, sizeof dir, "%s/B\xc3\xa4nder-\xe3\x83\x86\xe3\x82\xb9\xe3\x83\x88", g_dir);
    assert_int_equal(tf_mkdir(dir), 0);
    uint8_t pixels[W * H];
    for (int k = 0; k < 3; ++k) {
        for (uint32_t y = 0; y < H; ++y)
            for (uint32_t x = 0; x < W; ++x)
                pixels[y * W + x] = grey(k, x, y);
        snprintf(path[k], sizeof path[k], "%s/bild-\xc3\xa4%d.png", dir, k);
        write_png(path[k], W, H, 1, pixels);
    }
    snprintf(csv, sizeof csv, "%s/Geber-\xc3\xb6.csv", dir);
    write_text(csv, "bild-\xc3\xa4"
                    "0.png,10\nbild-\xc3\xa4"
                    "1.png,20\nbild-\xc3\xa4"
                    "2.png,30\n");
    for (int by_list = 0; by_list < 2; ++by_list) {
        flt_source *src = NULL;
        const char *list[3] = {path[0], path[1], path[2]};
        if (by_list)
            ok(flt_source_create_images(list, 3, csv, NULL, &src));
        else
            ok(flt_source_create_image_dir(dir, csv, NULL, &src));
        ok(flt_source_start(src));
        for (int k = 0; k < 3; ++k) {
            const flt_frame *f = NULL;
            ok(flt_source_next(src, 0, &f));
            assert_non_null(f);
            const void *p;
            size_t stride;
            double enc;
            ok(flt_frame_info(f, &p, NULL, NULL, &stride, NULL, NULL, NULL, &enc));
            assert_true(enc == 10.0 * (k + 1));
            const uint8_t *px = p;
            for (uint32_t y = 0; y < H; ++y)
                for (uint32_t x = 0; x < W; ++x)
                    if (px[y * stride + x] != grey(k, x, y))
                        fail_msg("%s: frame %d pixel (%u, %u)", by_list ? "list" : "folder", k, x,
                                 y);
        }
        flt_source_destroy(src);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sim_source_gives_the_simulator_frames),
        cmocka_unit_test(test_png_directory_with_encoder_csv),
        cmocka_unit_test(test_tiff16_list_with_fixed_step),
        cmocka_unit_test(test_utf8_paths),
    };
    return cmocka_run_group_tests(tests, make_dir, remove_dir);
}
