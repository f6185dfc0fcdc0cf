// SPDX-License-Identifier: Apache-2.0
/*
 * Calibration files: exact round trips, and one test per malformed-file
 * case (truncated, missing field, extra field, wrong type, NaN, unknown
 * version, non-invertible homography, and a few more). A failed load must
 * return FLT_ERR_FORMAT, name the field, and give no object.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "calib_synth.h"
#include "flatline/flatline.h"
#include "test_files.h"

/* The first n bytes of s as a new string (strndup, which Windows lacks). */
static char *prefix_copy(const char *s, size_t n) {
    const size_t length = strlen(s) < n ? strlen(s) : n;
    char *copy = malloc(length + 1);
    memcpy(copy, s, length);
    copy[length] = '\0';
    return copy;
}

/* A finished calibration of the synthetic sensor with estimated (so, not
 * round-number) homographies and distortion. */
static flt_calib *make_calibration(void) {
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create(&calib), FLT_OK);
    assert_int_equal(flt_calib_set_frame_size(calib, SYNTH_WIDTH, SYNTH_HEIGHT), FLT_OK);
    assert_int_equal(flt_calib_set_intrinsics(calib, synth_camera, FLT_CALIB_CAMERA_VALUES,
                                              synth_distortion, FLT_CALIB_DISTORTION_COEFFS),
                     FLT_OK);
    uint64_t rng = 5;
    for (unsigned laser = 0; laser < 2; ++laser) {
        double image[2 * 50], plane[2 * 50];
        size_t n = 0;
        for (int j = 0; j < 5; ++j)
            for (int i = 0; i < 10; ++i, ++n) {
                plane[2 * n] = -900 + 200 * i, plane[2 * n + 1] = -100 + 50 * j;
                assert_true(synth_project(plane[2 * n], synth_laser_offset[laser], plane[2 * n + 1],
                                          &image[2 * n], &image[2 * n + 1]));
                image[2 * n] += 0.05 * synth_gauss(&rng);
                image[2 * n + 1] += 0.05 * synth_gauss(&rng);
            }
        assert_int_equal(flt_calib_estimate_homography(calib, laser, n, image, plane, NULL, NULL,
                                                       NULL, NULL, NULL, NULL),
                         FLT_OK);
        assert_int_equal(flt_calib_set_laser_offset(calib, laser, synth_laser_offset[laser]),
                         FLT_OK);
    }
    assert_int_equal(flt_calib_set_encoder_scale(calib, 0.1 / 3), FLT_OK);
    assert_int_equal(flt_calib_set_fiber_grid(calib, -999.9, 2.0 / 3, 3000), FLT_OK);
    assert_int_equal(flt_calib_finish(calib), FLT_OK);
    return calib;
}

/* The saved text of a calibration (malloc'd, NUL-terminated). */
static char *save_text(const flt_calib *calib) {
    size_t length = 0;
    assert_int_equal(flt_calib_save_text(calib, NULL, 0, &length), FLT_ERR_BUFFER_FULL);
    assert_true(length > 500 && length < 4000);
    char *text = malloc(length + 1);
    assert_int_equal(flt_calib_save_text(calib, text, length + 1, &length), FLT_OK);
    assert_int_equal(strlen(text), length);
    return text;
}

/* The text with the first occurrence of `from` replaced by `to`. */
static char *replace(const char *text, const char *from, const char *to) {
    const char *at = strstr(text, from);
    assert_non_null(at);
    const size_t head = (size_t)(at - text);
    char *out = malloc(strlen(text) - strlen(from) + strlen(to) + 1);
    memcpy(out, text, head);
    strcpy(out + head, to);
    strcat(out, at + strlen(from));
    return out;
}

/* Loads `text` expecting FLT_ERR_FORMAT with `needle` in the message. */
static void expect_format_error(const char *text, const char *needle) {
    flt_calib *loaded = (flt_calib *)&loaded; /* not NULL: must be cleared */
    const flt_status st = flt_calib_load_text(text, strlen(text), &loaded);
    print_message("-> %s: %s\n", flt_status_string(st), flt_last_error_message());
    assert_int_equal(st, FLT_ERR_FORMAT);
    assert_null(loaded);
    assert_non_null(strstr(flt_last_error_message(), needle));
}

static char *g_text; /* the valid text, set up per test */

static int setup(void **state) {
    (void)state;
    flt_calib *calib = make_calibration();
    g_text = save_text(calib);
    flt_calib_destroy(calib);
    return 0;
}

static int teardown(void **state) {
    (void)state;
    free(g_text);
    return 0;
}

/* ------------------------------------------------------- round trips */

/* save -> load -> save gives the same bytes, through memory and through a
 * file, and the loaded model maps every point to the bit-identical result
 * (%.17g round-trips doubles exactly; the inverse homography is recomputed
 * from the same bits). */
static void save_load_save_is_byte_identical(void **state) {
    (void)state;
    flt_calib *original = make_calibration();
    char *first = save_text(original);

    flt_calib *loaded = NULL;
    assert_int_equal(flt_calib_load_text(first, strlen(first), &loaded), FLT_OK);
    char *second = save_text(loaded);
    assert_int_equal(strlen(first), strlen(second));
    assert_int_equal(memcmp(first, second, strlen(first)), 0);

    char dir[512], path[600];
    assert_int_equal(tf_temp_dir(dir, sizeof dir, "calib_io"), 0);
    snprintf(path, sizeof path, "%s/sensor.json", dir);
    assert_int_equal(flt_calib_save(loaded, path), FLT_OK);
    flt_calib *from_file = NULL;
    assert_int_equal(flt_calib_load(path, &from_file), FLT_OK);
    char *third = save_text(from_file);
    assert_int_equal(memcmp(first, third, strlen(first) + 1), 0);
    /* the file holds exactly the text */
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    char *bytes = malloc(strlen(first) + 16);
    const size_t got = fread(bytes, 1, strlen(first) + 16, f);
    fclose(f);
    assert_int_equal(got, strlen(first));
    assert_int_equal(memcmp(bytes, first, got), 0);
    remove(path);
    tf_remove(dir);

    /* identical mapping, both directions, both lasers */
    enum { n = 500 };
    double image[2 * n], a[2 * n], b[2 * n];
    uint64_t rng = 11;
    for (size_t i = 0; i < 2 * n; ++i)
        image[i] = SYNTH_WIDTH * synth_uniform(&rng);
    size_t differing = 0;
    for (unsigned laser = 0; laser < 2; ++laser) {
        assert_int_equal(flt_calib_image_to_plane(original, laser, n, image, a), FLT_OK);
        assert_int_equal(flt_calib_image_to_plane(from_file, laser, n, image, b), FLT_OK);
        differing += memcmp(a, b, sizeof a) != 0;
        assert_int_equal(flt_calib_plane_to_image(original, laser, n, a, image), FLT_OK);
        assert_int_equal(flt_calib_plane_to_image(from_file, laser, n, a, b), FLT_OK);
        differing += memcmp(image, b, sizeof b) != 0;
    }
    assert_int_equal(differing, 0);
    /* and a sample value survived exactly */
    double scale;
    assert_int_equal(flt_calib_get_encoder_scale(from_file, &scale), FLT_OK);
    assert_true(scale == 0.1 / 3);

    free(bytes);
    free(first), free(second), free(third);
    flt_calib_destroy(original), flt_calib_destroy(loaded), flt_calib_destroy(from_file);
}

/* Bytes of a file (NUL-terminated; the caller frees), or NULL. */
static char *file_bytes(const char *path) {
    FILE *f = tf_fopen(path, "rb");
    if (!f)
        return NULL;
    char *bytes = malloc(1 << 20);
    const size_t got = fread(bytes, 1, (1 << 20) - 1, f);
    bytes[got] = '\0';
    fclose(f);
    return bytes;
}

/* Saving onto an existing file replaces it (a calibration is saved again
 * after every recalibration). The file is written beside the target and
 * renamed over it; Windows' rename refuses an existing target, which
 * failed this save with FLT_ERR_IO there. */
static void save_replaces_an_existing_file(void **state) {
    (void)state;
    flt_calib *a = make_calibration();
    flt_calib *b = NULL;
    assert_int_equal(flt_calib_create_reference(0, 1024, -500, 2, 501, &b), FLT_OK);
    char *text_a = save_text(a), *text_b = save_text(b);
    assert_true(strcmp(text_a, text_b) != 0);
    char dir[512], path[600], tmp[620];
    assert_int_equal(tf_temp_dir(dir, sizeof dir, "calib_replace"), 0);
    snprintf(path, sizeof path, "%s/sensor.json", dir);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    assert_int_equal(flt_calib_save(a, path), FLT_OK);
    assert_int_equal(flt_calib_save(b, path), FLT_OK);
    char *on_disk = file_bytes(path);
    assert_non_null(on_disk);
    assert_string_equal(on_disk, text_b);
    assert_false(tf_exists(tmp)); /* no temporary left behind */
    /* and again over the second one */
    assert_int_equal(flt_calib_save(a, path), FLT_OK);
    free(on_disk);
    on_disk = file_bytes(path);
    assert_string_equal(on_disk, text_a);
    assert_int_equal(tf_remove(path), 0);
    assert_int_equal(tf_remove(dir), 0);
    free(on_disk), free(text_a), free(text_b);
    flt_calib_destroy(a), flt_calib_destroy(b);
}

/* Paths are UTF-8 (calib.h). A file saved as "Jürgen ø 測.json" in a folder
 * "Kalibrierung-Größe" is exactly that name on disk (checked with the
 * platform's UTF-16 calls on Windows, where the narrow C calls would have
 * read the bytes in the ANSI code page and made "JÃ¼rgen ..."), and a file
 * created under a non-ASCII name by the test is loaded by its UTF-8 path. */
static void utf8_paths_name_the_files(void **state) {
    (void)state;
    flt_calib *calib = make_calibration();
    char *text = save_text(calib);
    char base[512], dir[600], path[700], other[700];
    assert_int_equal(tf_temp_dir(base, sizeof base, "calib_utf8"), 0);
    snprintf(dir, sizeof dir,
             "%s/Kalibrierung-Gr\xc3\xb6\xc3\x9f"
             "e",
             base);
    assert_int_equal(tf_mkdir(dir), 0);
    snprintf(path, sizeof path, "%s/J\xc3\xbcrgen \xc3\xb8 \xe6\xb8\xac.json", dir);
    assert_int_equal(flt_calib_save(calib, path), FLT_OK);
    char *on_disk = file_bytes(path); /* opened by its real (UTF-16) name */
    assert_non_null(on_disk);
    assert_string_equal(on_disk, text);
    flt_calib *loaded = NULL;
    assert_int_equal(flt_calib_load(path, &loaded), FLT_OK);
    flt_calib_destroy(loaded);
    loaded = NULL;
    /* a file the library did not write */
    snprintf(other, sizeof other, "%s/\xc3\xa9talonnage-\xce\xb1\xce\xb2.json", dir);
    FILE *f = tf_fopen(other, "wb");
    assert_non_null(f);
    fwrite(text, 1, strlen(text), f);
    fclose(f);
    assert_int_equal(flt_calib_load(other, &loaded), FLT_OK);
    char *again = save_text(loaded);
    assert_string_equal(again, text);
    assert_int_equal(tf_remove(other), 0);
    assert_int_equal(tf_remove(path), 0);
    assert_int_equal(tf_remove(dir), 0);
    assert_int_equal(tf_remove(base), 0);
    free(again), free(on_disk), free(text);
    flt_calib_destroy(loaded), flt_calib_destroy(calib);
}

/* The format is documented in calib.h: the fields appear in that order. */
static void text_has_documented_layout(void **state) {
    (void)state;
    const char *order[] = {"\"format\": \"flatline-calibration\"",
                           "\"version\": 1",
                           "\"frame\"",
                           "\"camera\"",
                           "\"distortion\"",
                           "\"lasers\"",
                           "\"offset_mm\"",
                           "\"homography\"",
                           "\"encoder_mm_per_count\"",
                           "\"fibers\""};
    const char *at = g_text;
    size_t found = 0;
    for (size_t i = 0; i < sizeof order / sizeof *order; ++i) {
        const char *next = strstr(at, order[i]);
        if (next)
            at = next, ++found;
    }
    assert_int_equal(found, sizeof order / sizeof *order);
}

static void unfinished_calibration_cannot_be_saved(void **state) {
    (void)state;
    flt_calib *calib = NULL;
    size_t length;
    assert_int_equal(flt_calib_create(&calib), FLT_OK);
    assert_int_equal(flt_calib_save_text(calib, NULL, 0, &length), FLT_ERR_STATE);
    flt_calib_destroy(calib);
}

/* ------------------------------------------------------- malformed files */

static void truncated_file_is_rejected(void **state) {
    (void)state;
    /* cut inside the second laser's homography */
    const char *cut = strstr(strstr(g_text, "\"homography\"") + 1, "\"homography\"");
    char *text = prefix_copy(g_text, (size_t)(cut - g_text) + 30);
    expect_format_error(text, "truncated");
    expect_format_error(text, "lasers[1].homography");
    free(text);
    /* cut after the last number but before the closing braces */
    text = prefix_copy(g_text, strlen(g_text) - 6);
    expect_format_error(text, "truncated");
    free(text);
    expect_format_error("", "empty");
}

static void missing_field_is_rejected(void **state) {
    (void)state;
    const char *fy = strstr(g_text, "    \"fy\": ");
    const char *eol = strchr(fy, '\n');
    char *line = prefix_copy(fy, (size_t)(eol - fy + 1));
    char *text = replace(g_text, line, "");
    expect_format_error(text, "missing field 'camera.fy'");
    free(line), free(text);
}

static void extra_field_is_rejected(void **state) {
    (void)state;
    char *text = replace(g_text, "\"fibers\": {", "\"fibers\": {\"colour\": 1, ");
    expect_format_error(text, "unknown field 'fibers.colour'");
    free(text);
}

static void duplicate_field_is_rejected(void **state) {
    (void)state;
    char *text = replace(g_text, "\"frame\": {", "\"frame\": {\"width\": 2048, ");
    expect_format_error(text, "duplicate field 'frame.width'");
    free(text);
}

static void wrong_type_is_rejected(void **state) {
    (void)state;
    char *text = replace(g_text, "\"cx\": ", "\"cx\": \"centre\", \"was\": ");
    /* the string is reported against camera.cx before the extra field */
    flt_calib *loaded = NULL;
    assert_int_equal(flt_calib_load_text(text, strlen(text), &loaded), FLT_ERR_FORMAT);
    assert_null(loaded);
    free(text);
    const char *w = strstr(g_text, "\"width\": 2048");
    assert_non_null(w);
    text = replace(g_text, "\"width\": 2048", "\"width\": \"2048\"");
    expect_format_error(text, "field 'frame.width' (line 5) must be a number, found a string");
    free(text);
    text = replace(g_text, "\"height\": 2048", "\"height\": 2048.5");
    expect_format_error(text, "field 'frame.height' = 2048.5 must be a whole number");
    free(text);
    const char *e = strstr(g_text, "\"encoder_mm_per_count\": ");
    char *field = prefix_copy(e, (size_t)(strchr(e, ',') - e));
    text = replace(g_text, field, "\"encoder_mm_per_count\": true");
    expect_format_error(text, "field 'encoder_mm_per_count' (line 42) must be a number, "
                              "found a bare word 'true'");
    free(text), free(field);
}

static void nan_is_rejected(void **state) {
    (void)state;
    const char *k1 = strstr(g_text, "\"k1\": ");
    const char *comma = strchr(k1, ',');
    char *field = prefix_copy(k1, (size_t)(comma - k1));
    char *text = replace(g_text, field, "\"k1\": NaN");
    expect_format_error(text, "field 'camera.distortion.k1' is NaN");
    free(text);
    text = replace(g_text, field, "\"k1\": -inf");
    expect_format_error(text, "field 'camera.distortion.k1' is infinite");
    free(text);
    text = replace(g_text, field, "\"k1\": 1e999");
    expect_format_error(text, "camera.distortion.k1' = 1e999 is outside the range");
    free(text);
    free(field);
}

static void unknown_version_is_rejected(void **state) {
    (void)state;
    char *text = replace(g_text, "\"version\": 1,", "\"version\": 2,");
    expect_format_error(text, "field 'version' = 2 is a version this library cannot read");
    free(text);
    text = replace(g_text, "\"flatline-calibration\"", "\"something-else\"");
    expect_format_error(text, "field 'format'");
    free(text);
}

static void non_invertible_homography_is_rejected(void **state) {
    (void)state;
    /* laser 1's homography replaced by a rank-2 matrix (row 2 = 2 x row 1) */
    const char *h = strstr(strstr(g_text, "\"homography\": [") + 1, "\"homography\": [");
    const char *end = strchr(h, ']');
    char *old = prefix_copy(h, (size_t)(end - h + 1));
    char *text = replace(g_text, old, "\"homography\": [1, 2, 3, 2, 4, 6, 0, 0, 1]");
    expect_format_error(text, "field 'lasers[1].homography' is not invertible");
    free(text);
    text = replace(g_text, old, "\"homography\": [1, 0, 0, 0, 1, 0, 0, 0]");
    expect_format_error(text, "'lasers[1].homography' has 8 entries, not 9");
    free(text);
    free(old);
}

static void other_malformations_are_rejected(void **state) {
    (void)state;
    char *text = replace(g_text, "\"fx\": ", "\"fx\": -");
    expect_format_error(text, "field 'camera.fx' = -");
    free(text);
    text = replace(g_text, "\"count\": 3000", "\"count\": 0");
    expect_format_error(text, "field 'fibers.count' = 0 is outside");
    free(text);
    size_t n = strlen(g_text);
    text = malloc(n + 8);
    strcpy(text, g_text);
    strcat(text, "{}\n");
    expect_format_error(text, "unexpected text after the end");
    free(text);
    /* a file that does not exist is an I/O error, not a format error */
    flt_calib *loaded = (flt_calib *)&loaded;
    assert_int_equal(flt_calib_load("/nonexistent/calib.json", &loaded), FLT_ERR_IO);
    assert_null(loaded);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(save_load_save_is_byte_identical),
        cmocka_unit_test_setup_teardown(text_has_documented_layout, setup, teardown),
        cmocka_unit_test(unfinished_calibration_cannot_be_saved),
        cmocka_unit_test(save_replaces_an_existing_file),
        cmocka_unit_test(utf8_paths_name_the_files),
        cmocka_unit_test_setup_teardown(truncated_file_is_rejected, setup, teardown),
        cmocka_unit_test_setup_teardown(missing_field_is_rejected, setup, teardown),
        cmocka_unit_test_setup_teardown(extra_field_is_rejected, setup, teardown),
        cmocka_unit_test_setup_teardown(duplicate_field_is_rejected, setup, teardown),
        cmocka_unit_test_setup_teardown(wrong_type_is_rejected, setup, teardown),
        cmocka_unit_test_setup_teardown(nan_is_rejected, setup, teardown),
        cmocka_unit_test_setup_teardown(unknown_version_is_rejected, setup, teardown),
        cmocka_unit_test_setup_teardown(non_invertible_homography_is_rejected, setup, teardown),
        cmocka_unit_test_setup_teardown(other_malformations_are_rejected, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
