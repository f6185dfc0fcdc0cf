// SPDX-License-Identifier: Apache-2.0
/* "No allocation in per-frame hot paths": counts every malloc/calloc/realloc
 * made by libflatline (and the C++ runtime under it) while the simulator
 * renders frames and profile rows and the extractor turns frames into rows,
 * in Mono8 and in 16-bit words (Mono16 and Mono12), with spurious
 * reflections so that the rejection paths (further candidates, the shape
 * and continuity checks) run too. The counting allocator
 * (alloc_count.h) sees the shared library's calls too; a control shows
 * that it does. Not built under
 * sanitizers, which own malloc. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include <flatline/flatline.h>

#include "alloc_count.h"

/* The reference sensor's rows 892..1147 (both lines), as in test_extractor. */
enum { W = 2048, ROWS = 256, FIBERS = 201, FRAMES = 12 };

static void start_counting(void) {
    g_allocations = 0;
    g_counting = 1;
}

static size_t stop_counting(void) {
    g_counting = 0;
    return g_allocations;
}

/* Renders FRAMES frames at `bit_depth` and extracts each (the first frame
 * also places the automatic bands), and generates profile rows, counting
 * allocations after the create calls. */
static void frames_and_rows_allocate_nothing(int bit_depth) {
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create_reference(892, ROWS, -1000, 10, FIBERS, &calib), FLT_OK);
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_SIM_BIT_DEPTH, bit_depth), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_SIM_REFLECTIONS, 20), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_SIM_HEAVE_SIGMA, 1.0), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_SIM_SEED, 3), FLT_OK);

    /* Control: the counter sees the library's allocations. */
    flt_sim *sim = NULL;
    flt_extractor *ex = NULL;
    start_counting();
    assert_int_equal(flt_sim_create(calib, o, &sim), FLT_OK);
    assert_int_equal(flt_extractor_create(calib, NULL, &ex), FLT_OK);
    const size_t at_create = stop_counting();
    assert_true(at_create >= 10);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 12, 1800), FLT_OK);
    flt_pixel_format format;
    assert_int_equal(flt_sim_pixel_format(sim, &format), FLT_OK);
    assert_int_equal((int)format, bit_depth);

    const size_t bytes = bit_depth == 8 ? 1 : 2;
    const size_t stride = bytes * (W + 8); /* padded rows */
    void *frame = malloc(stride * ROWS);
    double *truth = malloc(sizeof(double) * FIBERS), *peaks = malloc(sizeof(double) * 2 * W);
    double *height = malloc(sizeof(double) * FIBERS), *slope = malloc(sizeof(double) * FIBERS);
    double *encoder = malloc(sizeof(double) * 64), *s = malloc(sizeof(double) * 64);
    double *row_height = malloc(sizeof(double) * 64 * FIBERS);
    double *row_slope = malloc(sizeof(double) * 64 * FIBERS);
    double *row_truth = malloc(sizeof(double) * 64 * FIBERS);
    uint8_t *valid = malloc(FIBERS), *row_valid = malloc(64 * FIBERS);
    size_t valid_count = 0;

    start_counting();
    flt_status st = FLT_OK;
    for (int f = 0; f < FRAMES && st == FLT_OK; ++f) {
        double e, row_s;
        st = flt_sim_next_frame(sim, frame, stride * ROWS, stride, &e, FIBERS, truth, peaks,
                                2 * (size_t)W);
        if (st == FLT_OK)
            st = flt_extractor_process(ex, frame, format, W, ROWS, stride, e, FIBERS, &row_s,
                                       height, slope, valid);
        if (st == FLT_OK)
            st = flt_extractor_peaks(ex, W, peaks);
        for (size_t k = 0; k < FIBERS; ++k)
            valid_count += valid[k];
    }
    if (st == FLT_OK)
        st = flt_sim_next_rows(sim, 64, FIBERS, encoder, s, row_height, row_slope, row_valid,
                               row_truth);
    const size_t per_frame = stop_counting();
    assert_int_equal(st, FLT_OK);

    print_message("%d-bit: %zu allocations at create (control), %zu over %d frames "
                  "(render + extract) and 64 profile rows; %.1f%% of fibers valid\n",
                  bit_depth, at_create, per_frame, FRAMES,
                  100.0 * (double)valid_count / (FRAMES * FIBERS));
    assert_int_equal(per_frame, 0);
    /* Real rows, not all-invalid ones (the reflections reject < 10 %). */
    assert_true(valid_count >= 0.8 * FRAMES * FIBERS);

    free(frame), free(truth), free(peaks), free(height), free(slope), free(encoder), free(s);
    free(row_height), free(row_slope), free(row_truth), free(valid), free(row_valid);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_options_destroy(o);
    flt_calib_destroy(calib);
}

static void mono8_allocates_nothing_per_frame(void **state) {
    (void)state;
    frames_and_rows_allocate_nothing(8);
}

static void mono16_allocates_nothing_per_frame(void **state) {
    (void)state;
    frames_and_rows_allocate_nothing(16);
}

static void mono12_allocates_nothing_per_frame(void **state) {
    (void)state;
    frames_and_rows_allocate_nothing(12);
}

/* The counter must be in place, or every count below would be 0. */
static int install_counter(void **state) {
    (void)state;
    return alloc_count_install() >= 1 ? 0 : -1;
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(mono8_allocates_nothing_per_frame),
        cmocka_unit_test(mono16_allocates_nothing_per_frame),
        cmocka_unit_test(mono12_allocates_nothing_per_frame),
    };
    return cmocka_run_group_tests(tests, install_counter, NULL);
}
