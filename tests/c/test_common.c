// SPDX-License-Identifier: Apache-2.0
/* The conventions every component relies on: status names, the thread-local
 * error message, versions, and the options bag. */
#include <math.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#include <flatline/flatline.h>

static void status_strings_name_every_code(void **state) {
    (void)state;
    assert_string_equal(flt_status_string(FLT_OK), "FLT_OK");
    assert_string_equal(flt_status_string(FLT_ERR_INVALID_ARGUMENT), "FLT_ERR_INVALID_ARGUMENT");
    assert_string_equal(flt_status_string(FLT_ERR_STATE), "FLT_ERR_STATE");
    assert_string_equal(flt_status_string(FLT_ERR_BUFFER_FULL), "FLT_ERR_BUFFER_FULL");
    assert_string_equal(flt_status_string(FLT_ERR_INTERNAL), "FLT_ERR_INTERNAL");
    assert_string_equal(flt_status_string((flt_status)-12345), "FLT_ERR_UNKNOWN");
    /* Every code from -1 to -10 has its own name. */
    for (int c = -1; c >= -10; --c)
        assert_string_not_equal(flt_status_string((flt_status)c), "FLT_ERR_UNKNOWN");
}

static void version_agrees_with_header(void **state) {
    (void)state;
    assert_int_equal(flt_version(), FLT_VERSION_NUMBER);
    assert_string_equal(flt_version_string(), FLT_VERSION_STRING);
    assert_true(FLT_VERSION_CHECK(0, 1, 0));
    assert_false(FLT_VERSION_CHECK(999, 0, 0));
}

static void error_message_names_argument_and_is_cleared(void **state) {
    (void)state;
    flt_options *opts = NULL;
    assert_int_equal(flt_options_create(&opts), FLT_OK);
    assert_string_equal(flt_last_error_message(), "");
    assert_int_equal(flt_options_set(opts, FLT_OPT_HEIGHT_SIGMA, -1.0), FLT_ERR_INVALID_ARGUMENT);
    assert_int_equal(flt_last_error_status(), FLT_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(flt_last_error_message(), "height_sigma"));
    assert_non_null(strstr(flt_last_error_message(), "-1"));
    /* The next successful call clears it. */
    double v = 0;
    assert_int_equal(flt_options_get(opts, FLT_OPT_HEIGHT_SIGMA, &v), FLT_OK);
    assert_string_equal(flt_last_error_message(), "");
    assert_int_equal(flt_last_error_status(), FLT_OK);
    assert_true(v == 2.5); /* unchanged by the failed set */
    flt_options_destroy(opts);
}

static void *fail_in_thread(void *arg) {
    (void)arg;
    flt_option key;
    if (flt_option_find("no_such_option_in_thread", &key) == FLT_OK)
        return (void *)1;
    return NULL;
}

static void error_message_is_thread_local(void **state) {
    (void)state;
    flt_option key;
    assert_int_equal(flt_option_find("no_such_option_here", &key), FLT_ERR_NOT_FOUND);
    pthread_t t;
    assert_int_equal(pthread_create(&t, NULL, fail_in_thread, NULL), 0);
    pthread_join(t, NULL);
    /* The other thread's failure did not overwrite ours. */
    assert_non_null(strstr(flt_last_error_message(), "no_such_option_here"));
}

static void options_enforce_bounds_nan_and_integers(void **state) {
    (void)state;
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_LASER_SPACING, NAN), FLT_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(flt_last_error_message(), "NaN"));
    assert_int_equal(flt_options_set(o, FLT_OPT_LAG_KNOTS, 2.5), FLT_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(flt_last_error_message(), "whole number"));
    /* Below the bound (-1: "derived from latency_mm" is the least). */
    assert_int_equal(flt_options_set(o, FLT_OPT_LAG_KNOTS, -2), FLT_ERR_INVALID_ARGUMENT);
    /* An unknown key is not found, by set, get and info alike. */
    assert_int_equal(flt_options_set(o, (flt_option)12345, 1.0), FLT_ERR_NOT_FOUND);
    double unused;
    assert_int_equal(flt_options_get(o, (flt_option)12345, &unused), FLT_ERR_NOT_FOUND);
    assert_int_equal(flt_option_info((flt_option)12345, NULL, NULL, NULL, NULL, NULL),
                     FLT_ERR_NOT_FOUND);
    assert_int_equal(flt_options_set(NULL, FLT_OPT_LAG_KNOTS, 1.0), FLT_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(flt_last_error_message(), "'options'"));
    assert_int_equal(flt_options_set(o, FLT_OPT_LAG_KNOTS, 7), FLT_OK);
    double v = 0;
    assert_int_equal(flt_options_get(o, FLT_OPT_LAG_KNOTS, &v), FLT_OK);
    assert_true(v == 7.0);
    assert_int_equal(flt_options_get(o, FLT_OPT_LAG_KNOTS, NULL), FLT_ERR_INVALID_ARGUMENT);
    flt_options_destroy(o);
    flt_options_destroy(NULL); /* no-op */
    assert_int_equal(flt_options_create(NULL), FLT_ERR_INVALID_ARGUMENT);
}

static void options_are_found_by_name_and_enumerated(void **state) {
    (void)state;
    flt_option key;
    assert_int_equal(flt_option_find("knot_spacing", &key), FLT_OK);
    assert_int_equal(key, FLT_OPT_KNOT_SPACING);
    assert_int_equal(flt_option_find("Knot_Spacing", &key), FLT_ERR_NOT_FOUND);
    /* A typo gets the closest name; a name like none gets none. */
    assert_int_equal(flt_option_find("rigid_motoin", &key), FLT_ERR_NOT_FOUND);
    assert_non_null(strstr(flt_last_error_message(), "did you mean 'rigid_motion'?"));
    assert_int_equal(flt_option_find("gauge_worker", &key), FLT_ERR_NOT_FOUND);
    assert_non_null(strstr(flt_last_error_message(), "did you mean 'gauge_workers'?"));
    assert_int_equal(flt_option_find("banana", &key), FLT_ERR_NOT_FOUND);
    assert_null(strstr(flt_last_error_message(), "did you mean"));
    assert_int_equal(flt_option_find(NULL, &key), FLT_ERR_INVALID_ARGUMENT);
    size_t count = 0;
    for (size_t i = 0;; ++i) {
        flt_option k;
        if (flt_option_at(i, &k) != FLT_OK)
            break;
        const char *name = NULL;
        double lo, hi, def;
        int integer;
        assert_int_equal(flt_option_info(k, &name, &lo, &hi, &def, &integer), FLT_OK);
        assert_true(lo <= def && def <= hi);
        flt_option back;
        assert_int_equal(flt_option_find(name, &back), FLT_OK);
        assert_int_equal(back, k);
        ++count;
    }
    assert_true(count >= 8); /* the eight reconstructor options at least */
    assert_int_equal(flt_last_error_status(), FLT_ERR_NOT_FOUND); /* the end */
    double def = 0;
    assert_int_equal(flt_option_info(FLT_OPT_LASER_SPACING, NULL, NULL, NULL, &def, NULL), FLT_OK);
    assert_true(def == 100.0);
}

/* Every option whose value is a choice names each of its whole values once,
 * in order, with the C enumerator's value; every other option has none. */
static void choices_name_every_value_of_a_choice_option(void **state) {
    (void)state;
    size_t with_choices = 0;
    for (size_t i = 0;; ++i) {
        flt_option k;
        if (flt_option_at(i, &k) != FLT_OK)
            break;
        const char *option = NULL;
        double lo, hi;
        int integer;
        assert_int_equal(flt_option_info(k, &option, &lo, &hi, NULL, &integer), FLT_OK);
        size_t n = 0;
        const char *name;
        int value;
        while (flt_option_choice_at(k, n, &name, &value) == FLT_OK) {
            assert_int_equal(value, (int)lo + (int)n);
            assert_true(strlen(name) > 0);
            for (size_t j = 0; j < n; ++j) {
                const char *other;
                assert_int_equal(flt_option_choice_at(k, j, &other, NULL), FLT_OK);
                assert_true(strcmp(other, name) != 0);
            }
            ++n;
        }
        assert_int_equal(flt_last_error_status(), FLT_ERR_NOT_FOUND);
        if (n > 0) {
            ++with_choices;
            assert_true(integer);
            assert_true(lo == 0 && hi == (double)(n - 1)); /* every value named */
        }
    }
    /* robust, flat_reference, source_encoder_mode, sim_surround, flat_drive_side,
     * flat_zones_on, gauge_overflow, record_frames */
    assert_int_equal(with_choices, 8);
    const char *name;
    int value;
    assert_int_equal(flt_option_choice_at(FLT_OPT_ROBUST, FLT_ROBUST_TUKEY, &name, &value), FLT_OK);
    assert_string_equal(name, "tukey");
    assert_int_equal(value, FLT_ROBUST_TUKEY);
    assert_int_equal(
        flt_option_choice_at(FLT_OPT_FLAT_REFERENCE, FLT_FLAT_REFERENCE_MEAN, &name, &value),
        FLT_OK);
    assert_string_equal(name, "mean");
    assert_int_equal(
        flt_option_choice_at(FLT_OPT_SOURCE_ENCODER_MODE, FLT_ENCODER_CHUNK, &name, &value),
        FLT_OK);
    assert_string_equal(name, "chunk");
    assert_int_equal(
        flt_option_choice_at(FLT_OPT_SIM_SURROUND, FLT_SIM_SURROUND_ROLLER_TABLE, &name, &value),
        FLT_OK);
    assert_string_equal(name, "roller_table");
    assert_int_equal(flt_option_choice_at(FLT_OPT_FLAT_ZONES_ON, FLT_ZONES_ON_GRID, &name, &value),
                     FLT_OK);
    assert_string_equal(name, "grid");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(status_strings_name_every_code),
        cmocka_unit_test(version_agrees_with_header),
        cmocka_unit_test(error_message_names_argument_and_is_cleared),
        cmocka_unit_test(error_message_is_thread_local),
        cmocka_unit_test(options_enforce_bounds_nan_and_integers),
        cmocka_unit_test(choices_name_every_value_of_a_choice_option),
        cmocka_unit_test(options_are_found_by_name_and_enumerated),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
