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

/* The line in the field, per frame: a narrow strip wandering over the
 * roller table, coils with heads and tails, glints at the edges, lines at
 * 1.5 x full scale blooming; the extractor's edges, flags and saturation;
 * the reconstructor with the flags (push, end of sheet, pull) and the
 * streamed flatness on the strip (a window evaluated on the way). Nothing
 * allocates once created. */
static void the_line_in_the_field_allocates_nothing_per_frame(void **state) {
    (void)state;
    enum { N = 40 };
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create_reference(892, ROWS, -1000, 10, FIBERS, &calib), FLT_OK);
    const flt_option keys[] = {
        FLT_OPT_SIM_SURROUND,     FLT_OPT_SIM_STRIP_WIDTH,   FLT_OPT_SIM_WANDER_AMPLITUDE,
        FLT_OPT_SIM_WANDER_SIGMA, FLT_OPT_SIM_COIL_LENGTH,   FLT_OPT_SIM_COIL_GAP,
        FLT_OPT_SIM_SECOND_WIDTH, FLT_OPT_SIM_EDGE_GLINTS,   FLT_OPT_SIM_LINE_PEAK,
        FLT_OPT_SIM_BLOOMING,     FLT_OPT_SIM_FRAME_SPACING, FLT_OPT_SIM_START};
    const double values[] = {2, 1200, 40, 10, 6000, 600, 900, 0.5, 1.5, 1, 200, 5000};
    flt_options *so = NULL, *eo = NULL;
    assert_int_equal(flt_options_create(&so), FLT_OK);
    for (int i = 0; i < 12; ++i)
        assert_int_equal(flt_options_set(so, keys[i], values[i]), FLT_OK);
    assert_int_equal(flt_options_create(&eo), FLT_OK);
    assert_int_equal(flt_options_set(eo, FLT_OPT_EXTRACT_LASER0_FIRST_ROW, 128), FLT_OK);
    assert_int_equal(flt_options_set(eo, FLT_OPT_EXTRACT_LASER0_ROWS, 112), FLT_OK);
    assert_int_equal(flt_options_set(eo, FLT_OPT_EXTRACT_LASER1_FIRST_ROW, 64), FLT_OK);
    assert_int_equal(flt_options_set(eo, FLT_OPT_EXTRACT_LASER1_ROWS, 64), FLT_OK);
    flt_sim *sim = NULL;
    flt_extractor *ex = NULL;
    flt_recon *recon = NULL;
    flt_flatness *flat = NULL;
    assert_int_equal(flt_sim_create(calib, so, &sim), FLT_OK);
    assert_int_equal(flt_extractor_create(calib, eo, &ex), FLT_OK);
    assert_int_equal(flt_recon_create(FIBERS, NULL, &recon), FLT_OK);
    assert_int_equal(flt_flatness_create_from_calib(calib, NULL, &flat), FLT_OK);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, 6, 1500), FLT_OK);
    uint8_t *frame = malloc((size_t)W * ROWS), *flags = malloc(N * FIBERS),
            *out_flags = malloc(N * FIBERS);
    double *s = malloc(N * sizeof(double)), *h = malloc(N * FIBERS * sizeof(double)),
           *g = malloc(N * FIBERS * sizeof(double)), *z = malloc(N * FIBERS * sizeof(double)),
           *s_out = malloc(N * sizeof(double)), *left = malloc(N * sizeof(double)),
           *right = malloc(N * sizeof(double));
    size_t on_strip = 0, saturated_frames = 0, windows = 0;

    start_counting();
    flt_status st = FLT_OK;
    for (int f = 0; f < N && st == FLT_OK; ++f) {
        double e, width, centre, fraction;
        unsigned strip_flags;
        size_t peaks, saturated;
        st = flt_sim_next_frame(sim, frame, (size_t)W * ROWS, W, &e, 0, NULL, NULL, 0);
        if (st == FLT_OK)
            st = flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROWS, W, e, FIBERS, &s[f],
                                       h + (size_t)f * FIBERS, g + (size_t)f * FIBERS, NULL);
        if (st == FLT_OK)
            st = flt_extractor_fiber_flags(ex, FIBERS, flags + (size_t)f * FIBERS);
        if (st == FLT_OK)
            st = flt_extractor_strip(ex, 2, &left[f], &right[f], &width, &centre, &strip_flags);
        if (st == FLT_OK)
            st = flt_extractor_saturation(ex, 2, &peaks, &saturated, &fraction);
        saturated_frames += fraction > 0.9;
        for (size_t k = 0; k < FIBERS; ++k)
            on_strip += flags[(size_t)f * FIBERS + k] == 0;
    }
    if (st == FLT_OK)
        st = flt_recon_push_flagged(recon, N, FIBERS, s, h, g, flags);
    if (st == FLT_OK)
        st = flt_recon_end_sheet(recon);
    size_t pulled = 0, fed = 0;
    if (st == FLT_OK)
        st = flt_recon_pull(recon, N, FIBERS, s_out, z, out_flags, &pulled);
    while (st == FLT_OK && fed < pulled) {
        size_t used = 0;
        int evaluated = 0;
        st = flt_flatness_push_strip(flat, pulled - fed, FIBERS, s_out + fed, z + fed * FIBERS,
                                     out_flags + fed * FIBERS, left + fed, right + fed, &used,
                                     &evaluated);
        fed += used;
        windows += (size_t)evaluated;
    }
    const size_t per_frame = stop_counting();
    assert_int_equal(st, FLT_OK);
    print_message("the line in the field: %zu allocations over %d frames (render, extract, "
                  "edges, flags, saturation), the reconstructor with flags and %zu streamed "
                  "window(s) on the strip; %zu fibers on the strip, %zu saturated frames\n",
                  per_frame, N, windows, on_strip, saturated_frames);
    assert_int_equal(per_frame, 0);
    /* It did the work: strip, saturation, a head or tail and a window. */
    assert_true(on_strip > N * 50 && saturated_frames > N / 2 && windows >= 1);
    assert_int_equal(pulled, N);
    free(frame), free(flags), free(out_flags), free(s), free(h), free(g), free(z), free(s_out);
    free(left), free(right);
    flt_flatness_destroy(flat);
    flt_recon_destroy(recon);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_options_destroy(so);
    flt_options_destroy(eo);
    flt_calib_destroy(calib);
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
        cmocka_unit_test(the_line_in_the_field_allocates_nothing_per_frame),
    };
    return cmocka_run_group_tests(tests, install_counter, NULL);
}
