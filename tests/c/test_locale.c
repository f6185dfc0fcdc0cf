// SPDX-License-Identifier: Apache-2.0
/*
 * Numbers in text do not depend on the process locale. An HMI in a
 * decimal-comma country calls setlocale(LC_ALL, "de_DE.UTF-8"); printf's
 * %g then writes "1090,9" and strtod stops at the '.' of "1090.9". The
 * library's calibration files, the copies the extractor and the simulator
 * make through that text, and its error messages must read and write the
 * same text under every locale.
 *
 * Round trips are exact: a value saved under one locale and loaded under
 * the other is the same double, bit for bit (tolerance 0: the writer writes
 * the shortest text that reads back as the same double).
 *
 * Needs the de_DE.UTF-8 locale (.ci/deps generates it); without it every
 * test is skipped with a message.
 */
#include <locale.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "calib_synth.h"
#include "flatline/flatline.h"

static const char *const k_german[] = {"de_DE.UTF-8", "de_DE.utf8", "German_Germany.1252"};

/* Switches the whole process to a German locale; skips the test when the
 * machine has none. */
static void use_german(void) {
    for (size_t i = 0; i < sizeof k_german / sizeof k_german[0]; ++i)
        if (setlocale(LC_ALL, k_german[i])) {
            /* The locale really uses a decimal comma (else the test tests nothing). */
            char probe[16];
            snprintf(probe, sizeof probe, "%.1f", 1.5);
            assert_string_equal(probe, "1,5");
            return;
        }
    print_message("SKIPPED: the de_DE.UTF-8 locale is not installed (on Debian: apt-get "
                  "install locales; enable de_DE.UTF-8 in /etc/locale.gen; locale-gen)\n");
    skip();
}

static void use_c(void) {
    assert_non_null(setlocale(LC_ALL, "C"));
}

static int restore_c(void **state) {
    (void)state;
    setlocale(LC_ALL, "C");
    return 0;
}

/* A finished calibration of the synthetic sensor with estimated (so, not
 * round-number) homographies, and fractional offsets, scale and grid. */
static flt_calib *make_calibration(void) {
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create(&calib), FLT_OK);
    assert_int_equal(flt_calib_set_frame_size(calib, SYNTH_WIDTH, SYNTH_HEIGHT), FLT_OK);
    assert_int_equal(flt_calib_set_intrinsics(calib, synth_camera, FLT_CALIB_CAMERA_VALUES,
                                              synth_distortion, FLT_CALIB_DISTORTION_COEFFS),
                     FLT_OK);
    uint64_t rng = 11;
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
        assert_int_equal(
            flt_calib_set_laser_offset(calib, laser, synth_laser_offset[laser] + 0.125 / 3),
            FLT_OK);
    }
    assert_int_equal(flt_calib_set_encoder_scale(calib, 0.1 / 3), FLT_OK);
    assert_int_equal(flt_calib_set_fiber_grid(calib, -999.9, 2.0 / 3, 3000), FLT_OK);
    assert_int_equal(flt_calib_finish(calib), FLT_OK);
    return calib;
}

/* The saved text (malloc'd, NUL-terminated). */
static char *save_text(const flt_calib *calib) {
    size_t length = 0;
    assert_int_equal(flt_calib_save_text(calib, NULL, 0, &length), FLT_ERR_BUFFER_FULL);
    char *text = malloc(length + 1);
    assert_non_null(text);
    assert_int_equal(flt_calib_save_text(calib, text, length + 1, &length), FLT_OK);
    return text;
}

static flt_calib *load_text(const char *text) {
    flt_calib *calib = NULL;
    const flt_status st = flt_calib_load_text(text, strlen(text), &calib);
    if (st != FLT_OK)
        print_message("load: %s\n", flt_last_error_message());
    assert_int_equal(st, FLT_OK);
    return calib;
}

/* No number in the text is written with a decimal comma: a ',' is always
 * followed by a newline (JSON's separators, one field per line). */
static void assert_no_decimal_comma(const char *text) {
    for (const char *p = strchr(text, ','); p; p = strchr(p + 1, ','))
        if (p[1] != '\n' && p[1] != ' ') {
            print_message("decimal comma at: %.40s\n", p - 10 > text ? p - 10 : text);
            fail();
        }
    /* And a fraction is written with '.': fx = 6 / 0.0055 px is not whole. */
    assert_non_null(strstr(text, "1090.9"));
}

/* Pixels mapped onto both laser planes: the model a caller would use. */
static void map_pixels(const flt_calib *calib, double plane[2][2 * 4]) {
    const double image[2 * 4] = {100.5, 300.25, 1023.5, 1100.75, 1900.125, 1500.5, 640, 2000};
    for (unsigned laser = 0; laser < 2; ++laser)
        assert_int_equal(flt_calib_image_to_plane(calib, laser, 4, image, plane[laser]), FLT_OK);
}

/* Saved under `save_german`, loaded under the other locale: the loaded model
 * saves the same text and maps pixels to the same millimetres, bit for bit. */
static void round_trip(int save_german) {
    flt_calib *original = make_calibration();
    double expected[2][2 * 4];
    map_pixels(original, expected);

    if (save_german)
        use_german();
    else
        use_c();
    char *text = save_text(original);
    assert_no_decimal_comma(text);

    if (save_german)
        use_c();
    else
        use_german();
    flt_calib *loaded = load_text(text);
    char *again = save_text(loaded);
    /* The shortest round-trip text is unique per double: equal texts mean
     * every value came back bit-identical. */
    assert_string_equal(again, text);
    double mapped[2][2 * 4];
    map_pixels(loaded, mapped);
    assert_memory_equal(mapped, expected, sizeof expected);

    free(again);
    free(text);
    flt_calib_destroy(loaded);
    flt_calib_destroy(original);
}

static void saved_german_loads_in_c(void **state) {
    (void)state;
    round_trip(1);
}

static void saved_in_c_loads_german(void **state) {
    (void)state;
    round_trip(0);
}

/* The same through a file (flt_calib_save / flt_calib_load). */
static void file_round_trip_german(void **state) {
    (void)state;
    flt_calib *original = make_calibration();
    char *expected = save_text(original);
    char path[64];
    snprintf(path, sizeof path, "test_locale_%u.json", (unsigned)(uintptr_t)&path % 100000u);
    use_german();
    assert_int_equal(flt_calib_save(original, path), FLT_OK);
    use_c();
    flt_calib *loaded = NULL;
    assert_int_equal(flt_calib_load(path, &loaded), FLT_OK);
    use_german();
    flt_calib *loaded_german = NULL;
    assert_int_equal(flt_calib_load(path, &loaded_german), FLT_OK);
    use_c();
    char *a = save_text(loaded), *b = save_text(loaded_german);
    assert_string_equal(a, expected);
    assert_string_equal(b, expected);
    remove(path);
    free(a);
    free(b);
    free(expected);
    flt_calib_destroy(loaded);
    flt_calib_destroy(loaded_german);
    flt_calib_destroy(original);
}

/* The extractor and the simulator copy a calibration through its text;
 * under German they are created and use the same model. */
static void components_copy_the_model_under_german(void **state) {
    (void)state;
    flt_calib *calib = make_calibration();
    use_german();
    flt_extractor *ex = NULL;
    flt_status st = flt_extractor_create(calib, NULL, &ex);
    if (st != FLT_OK)
        print_message("extractor: %s\n", flt_last_error_message());
    assert_int_equal(st, FLT_OK);
    flt_sim *sim = NULL;
    st = flt_sim_create(calib, NULL, &sim);
    if (st != FLT_OK)
        print_message("sim: %s\n", flt_last_error_message());
    assert_int_equal(st, FLT_OK);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

/* A field written with a decimal comma (a file from a locale-dependent
 * writer) is refused with the field's name, not read as a cut number. */
static void decimal_comma_in_a_file_is_refused(void **state) {
    (void)state;
    flt_calib *calib = make_calibration();
    char *text = save_text(calib);
    char *at = strstr(text, "1090.9");
    assert_non_null(at);
    at[4] = ',';
    use_german();
    flt_calib *loaded = (flt_calib *)&loaded;
    assert_int_equal(flt_calib_load_text(text, strlen(text), &loaded), FLT_ERR_FORMAT);
    assert_null(loaded);
    print_message("-> %s\n", flt_last_error_message());
    free(text);
    flt_calib_destroy(calib);
}

/* Error messages write numbers with '.' whatever the locale. */
static void messages_use_a_decimal_point(void **state) {
    (void)state;
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create(&calib), FLT_OK);
    use_german();
    assert_int_equal(flt_calib_set_fiber_grid(calib, -999.5, -0.25, 10), FLT_ERR_INVALID_ARGUMENT);
    const char *message = flt_last_error_message();
    print_message("-> %s\n", message);
    assert_non_null(strstr(message, "-0.25"));
    assert_null(strstr(message, "-0,25"));
    flt_calib_destroy(calib);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(saved_german_loads_in_c, restore_c),
        cmocka_unit_test_teardown(saved_in_c_loads_german, restore_c),
        cmocka_unit_test_teardown(file_round_trip_german, restore_c),
        cmocka_unit_test_teardown(components_copy_the_model_under_german, restore_c),
        cmocka_unit_test_teardown(decimal_comma_in_a_file_is_refused, restore_c),
        cmocka_unit_test_teardown(messages_use_a_decimal_point, restore_c),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
