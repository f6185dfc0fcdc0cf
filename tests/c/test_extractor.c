// SPDX-License-Identifier: Apache-2.0
/*
 * Frame-to-profile extractor against the simulated sensor's ground truth:
 * peak accuracy, height accuracy and validity, spurious reflections, end to
 * end through the reconstructor, 16-bit frames, determinism, bad input.
 *
 * Frames are the reference sensor's rows 892..1147 (an ROI readout): both
 * lines and +-50 mm of height fit, and rendering costs an eighth of the full
 * 2048 x 2048 sensor, which keeps the whole file under ~20 s.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "flatline/flatline.h"
#include "sweep.h"
#include "sheet.h"

#define ROI_FIRST 892
#define ROI_ROWS  256
#define W         2048

#define assert_near(a, b, tol)                                                 \
  do {                                                                         \
    const double a_ = (a), b_ = (b);                                           \
    if (!(fabs(a_ - b_) <= (tol)))                                             \
      fail_msg("%s = %.17g, expected %.17g +- %g", #a, a_, b_, (double)(tol)); \
  } while (0)

static flt_calib *reference(size_t fibers, double pitch) {
    flt_calib *calib = NULL;
    const double first_x = -0.5 * pitch * (double)(fibers - 1);
    assert_int_equal(
        flt_calib_create_reference(ROI_FIRST, ROI_ROWS, first_x, pitch, fibers, &calib), FLT_OK);
    return calib;
}

static flt_sim *make_sim(const flt_calib *calib, int n, const flt_option *keys,
                         const double *values) {
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    for (int i = 0; i < n; ++i)
        assert_int_equal(flt_options_set(o, keys[i], values[i]), FLT_OK);
    flt_sim *sim = NULL;
    assert_int_equal(flt_sim_create(calib, o, &sim), FLT_OK);
    flt_options_destroy(o);
    return sim;
}

static flt_extractor *make_extractor(const flt_calib *calib, int n, const flt_option *keys,
                                     const double *values) {
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    for (int i = 0; i < n; ++i)
        assert_int_equal(flt_options_set(o, keys[i], values[i]), FLT_OK);
    flt_extractor *ex = NULL;
    assert_int_equal(flt_extractor_create(calib, o, &ex), FLT_OK);
    flt_options_destroy(o);
    return ex;
}

/* An extractor whose laser 0 reads rows 0..127 of the frame and laser 1
 * rows 128..255: for frames drawn by hand, a line in each half. */
static flt_extractor *halves_extractor(const flt_calib *calib) {
    const flt_option keys[] = {FLT_OPT_EXTRACT_LASER0_FIRST_ROW, FLT_OPT_EXTRACT_LASER0_ROWS,
                               FLT_OPT_EXTRACT_LASER1_FIRST_ROW, FLT_OPT_EXTRACT_LASER1_ROWS};
    const double values[] = {0, 128, 128, 128};
    flt_extractor *ex = make_extractor(calib, 4, keys, values);
    return ex;
}

static double sheet_at(const flt_sim *sim, double x, double s) {
    double z;
    assert_int_equal(flt_sim_surface(sim, 1, &x, &s, &z), FLT_OK);
    return z;
}

/* ------------------------------------------------------------------ tests */

/* Known sub-pixel centres (the simulator reports each column's exact line
 * row), line sigma 1.5, 2 and 3 px with a Savitzky-Golay window of about 5
 * sigma (9, 11, 15 rows), the default speckle (contrast 0.05 per pixel),
 * shot noise of a 10000 e- well, 8-bit: RMS error of the peak rows <= 1/16 px
 * (the goal; the reference's typical error). 4 frames x 2 lasers x
 * 2048 columns per sigma: the RMS estimate is good to 1 %. */
static void peak_rows_within_a_sixteenth_of_a_pixel(void **state) {
    (void)state;
    flt_calib *calib = reference(101, 20);
    const double sigmas[] = {1.5, 2.0, 3.0}, windows[] = {9, 11, 15};
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    double truth_rows[2 * W], rows[2 * W];
    for (int si = 0; si < 3; ++si) {
        const flt_option keys[] = {FLT_OPT_SIM_LINE_SIGMA, FLT_OPT_EXTRACT_SG_WINDOW};
        const double values[] = {sigmas[si], windows[si]};
        flt_sim *sim = make_sim(calib, 1, keys, values);
        assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 12, 1800), FLT_OK);
        flt_extractor *ex = make_extractor(calib, 1, keys + 1, values + 1);
        double sum2 = 0;
        size_t count = 0, valid = 0;
        for (int f = 0; f < 4; ++f) {
            double e, s, h[101], g[101];
            assert_int_equal(flt_sim_next_frame(sim, frame, (size_t)W * ROI_ROWS, W, &e, 0, NULL,
                                                truth_rows, 2 * (size_t)W),
                             FLT_OK);
            assert_int_equal(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e,
                                                   101, &s, h, g, NULL),
                             FLT_OK);
            assert_int_equal(flt_extractor_peaks(ex, W, rows), FLT_OK);
            for (size_t i = 0; i < 2 * W; ++i) {
                if (!(truth_rows[i] == truth_rows[i]))
                    continue;
                ++count;
                if (!(rows[i] == rows[i]))
                    continue;
                ++valid;
                const double d = rows[i] - truth_rows[i];
                sum2 += d * d;
            }
        }
        const double rms = sqrt(sum2 / valid);
        print_message("line sigma %.1f px: peak RMS error %.4f px (1/%.0f), %.3f%% of "
                      "columns valid\n",
                      sigmas[si], rms, 1 / rms, 100.0 * valid / count);
        assert_true(rms <= 1.0 / 16);
        assert_true(valid >= 0.995 * count);
        flt_extractor_destroy(ex);
        flt_sim_destroy(sim);
    }
    free(frame);
    flt_calib_destroy(calib);
}

/* Height accuracy with noise-free motion: each laser's z on the fiber grid
 * against the sheet at that laser's material position, 2 sigma <= 0.1 mm
 * (the goal; the reference reached 0.25 mm, industry asks 0.35),
 * and >= 99.5 % of fibers valid on a clean sheet. Also the row operators:
 * height and slope equal the combination of the two lasers' z. */
static void heights_within_0_1_mm_two_sigma(void **state) {
    (void)state;
    enum { N = 501, FRAMES = 20 };
    flt_calib *calib = reference(N, 4.0); /* -1000 .. 1000 mm */
    const flt_option keys[] = {FLT_OPT_SIM_START};
    const double values[] = {200};
    flt_sim *sim = make_sim(calib, 1, keys, values);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 12, 1800), FLT_OK);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, 8, 900), FLT_OK);
    flt_extractor *ex = make_extractor(calib, 0, NULL, NULL);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    double sum = 0, sum2 = 0;
    size_t count = 0, valid_count = 0;
    for (int f = 0; f < FRAMES; ++f) {
        double e, s, h[N], g[N], z[2 * N];
        uint8_t valid[N];
        assert_int_equal(
            flt_sim_next_frame(sim, frame, (size_t)W * ROI_ROWS, W, &e, 0, NULL, NULL, 0), FLT_OK);
        assert_int_equal(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s,
                                               h, g, valid),
                         FLT_OK);
        assert_near(s, e, 1e-12);
        assert_int_equal(flt_extractor_laser_profiles(ex, N, z), FLT_OK);
        for (size_t k = 0; k < N; ++k) {
            ++count;
            if (!valid[k]) {
                assert_true(isnan(h[k]) && isnan(g[k]));
                continue;
            }
            ++valid_count;
            assert_near(h[k], 0.5 * (z[k] + z[N + k]), 1e-12);
            assert_near(g[k], (z[k] - z[N + k]) / 100, 1e-14); /* laser 0 is ahead */
            const double x = -1000 + 4.0 * (double)k;
            for (unsigned laser = 0; laser < 2; ++laser) {
                const double d = z[laser * N + k] - sheet_at(sim, x, e - (laser ? 50 : -50));
                sum += d, sum2 += d * d;
            }
        }
    }
    const double n = 2.0 * valid_count, mean = sum / n;
    const double sigma = sqrt(sum2 / n - mean * mean);
    print_message("height error: mean %.4f mm, 2 sigma %.4f mm, %.3f%% of fibers valid\n", mean,
                  2 * sigma, 100.0 * valid_count / count);
    assert_true(2 * sigma <= 0.1);
    assert_true(fabs(mean) <= 0.05); /* no bias beyond half the bound */
    assert_true(valid_count >= 0.995 * count);
    free(frame);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

/* 12-bit data in 16-bit words (Mono12) through the same path: the same
 * bound, 2 sigma <= 0.1 mm. */
static void mono12_frames_give_the_same_accuracy(void **state) {
    (void)state;
    enum { N = 201, FRAMES = 6 };
    flt_calib *calib = reference(N, 10.0);
    const flt_option keys[] = {FLT_OPT_SIM_BIT_DEPTH};
    const double values[] = {12};
    flt_sim *sim = make_sim(calib, 1, keys, values);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_QUARTER_BUCKLE, 10, 1200), FLT_OK);
    flt_pixel_format format;
    assert_int_equal(flt_sim_pixel_format(sim, &format), FLT_OK);
    assert_int_equal(format, FLT_PIXEL_MONO12);
    flt_extractor *ex = make_extractor(calib, 0, NULL, NULL);
    /* a padded stride: 4 px of padding per row */
    const size_t stride = 2 * (W + 4);
    uint16_t *frame = malloc(stride * ROI_ROWS);
    double sum2 = 0;
    size_t n = 0;
    for (int f = 0; f < FRAMES; ++f) {
        double e, s, h[N], g[N], z[2 * N];
        assert_int_equal(
            flt_sim_next_frame(sim, frame, stride * ROI_ROWS, stride, &e, 0, NULL, NULL, 0),
            FLT_OK);
        assert_int_equal(
            flt_extractor_process(ex, frame, format, W, ROI_ROWS, stride, e, N, &s, h, g, NULL),
            FLT_OK);
        assert_int_equal(flt_extractor_laser_profiles(ex, N, z), FLT_OK);
        for (size_t k = 0; k < N; ++k)
            for (unsigned laser = 0; laser < 2; ++laser) {
                const double zk = z[laser * N + k];
                if (!(zk == zk))
                    continue;
                const double d =
                    zk - sheet_at(sim, -1000 + 10.0 * (double)k, e - (laser ? 50 : -50));
                sum2 += d * d, ++n;
            }
    }
    const double rms = sqrt(sum2 / n);
    print_message("Mono12: height error 2 sigma %.4f mm over %zu laser points\n", 2 * rms, n);
    assert_true(2 * rms <= 0.1);
    assert_true(n >= 0.995 * 2 * N * FRAMES);
    free(frame);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

/* Spurious reflections, 20 per frame (half dim secondary reflections of the
 * line, 15-60 % of its peak, half saturating glints), over 40 frames: a
 * fiber may be rejected but must not be wrong. The bound: <= 0.1 %
 * of fibers off by more than 1 mm. Run with the default line (sigma 2 px,
 * Savitzky-Golay window 11) and with the widest line of the peak test
 * (sigma 3 px, window 15), where the window reaches furthest into a
 * reflection beside the line. Harsher than the goal: no kept column peak
 * may be off by more than 1 px (2.1 mm of z on the reference sensor), so a
 * wrong peak cannot hide in a fiber whose neighbours were rejected. And it
 * still measures: < 10 % of fibers rejected (measured 7.7 % and 8.7 %). */
static void reflections_run(double line_sigma, double sg_window) {
    enum { N = 501, FRAMES = 40 };
    flt_calib *calib = reference(N, 4.0);
    const flt_option keys[] = {FLT_OPT_SIM_REFLECTIONS, FLT_OPT_SIM_SEED, FLT_OPT_SIM_LINE_SIGMA,
                               FLT_OPT_EXTRACT_SG_WINDOW};
    const double values[] = {20, 11, line_sigma, sg_window};
    flt_sim *sim = make_sim(calib, 3, keys, values);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 12, 1800), FLT_OK);
    flt_extractor *ex = make_extractor(calib, 1, keys + 3, values + 3);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    double *truth_rows = malloc(sizeof(double) * 2 * W), *rows = malloc(sizeof(double) * 2 * W);
    size_t wrong = 0, invalid = 0, total = 0;
    double worst_peak = 0;
    for (int f = 0; f < FRAMES; ++f) {
        double e, s, h[N], g[N], truth[N];
        uint8_t valid[N];
        assert_int_equal(flt_sim_next_frame(sim, frame, (size_t)W * ROI_ROWS, W, &e, 0, NULL,
                                            truth_rows, 2 * (size_t)W),
                         FLT_OK);
        assert_int_equal(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s,
                                               h, g, valid),
                         FLT_OK);
        assert_int_equal(flt_extractor_peaks(ex, W, rows), FLT_OK);
        for (size_t i = 0; i < 2 * W; ++i) {
            const double d = fabs(rows[i] - truth_rows[i]);
            if (d > worst_peak)
                worst_peak = d; /* NaN (rejected) compares false */
        }
        for (size_t k = 0; k < N; ++k) {
            const double x = -1000 + 4.0 * (double)k;
            truth[k] = 0.5 * (sheet_at(sim, x, s + 50) + sheet_at(sim, x, s - 50));
            ++total;
            if (!valid[k]) {
                ++invalid;
                continue;
            }
            if (fabs(h[k] - truth[k]) > 1.0)
                ++wrong;
        }
    }
    print_message("reflections, line sigma %.0f px: %.3f%% of fibers wrong by > 1 mm (bound "
                  "0.1%%), %.2f%% rejected; worst kept peak off by %.2f px\n",
                  line_sigma, 100.0 * wrong / total, 100.0 * invalid / total, worst_peak);
    assert_true(wrong <= total / 1000);
    assert_true(worst_peak <= 1.0);
    assert_true(invalid < total / 10); /* it still measures */
    free(frame), free(truth_rows), free(rows);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

static void spurious_reflections_are_rejected_not_measured(void **state) {
    (void)state;
    reflections_run(2.0, 11);
    reflections_run(3.0, 15);
}

/* End to end on the reference sheet (tests/c/sheet.h: 12 mm, 1800 mm along,
 * 1500 mm across) with the reference noise: rigid heave 2.5 mm per frame,
 * roll eccentricity 0.5 mm at 50 mm, 1/16 px peak noise per laser, frames
 * every 3 mm -> extractor -> flt_reconstruct with default options: max error
 * <= 0.5 mm (the goal). The sheet is 5400 mm (3 periods) rather than
 * the reference 9000 mm and the fibers 10 mm apart: each fiber is
 * reconstructed from its own samples (plus the frame's rigid line), so
 * neither shortcut changes the physics, and they keep the run to seconds. */
static void end_to_end_reference_sheet_within_half_a_millimetre(void **state) {
    (void)state;
    FLT_SWEEP_NOT_UNDER_SANITIZERS();
    enum { N = 151, FRAMES = 1800 };
    flt_calib *calib = reference(N, 10.0); /* -750 .. 750 mm */
    const flt_option keys[] = {FLT_OPT_SIM_HEAVE_SIGMA,
                               FLT_OPT_SIM_ECCENTRICITY_AMPLITUDE,
                               FLT_OPT_SIM_ECCENTRICITY_PERIOD,
                               FLT_OPT_SIM_PEAK_SIGMA,
                               FLT_OPT_SIM_START,
                               FLT_OPT_SIM_SEED};
    const double values[] = {2.5, 0.5, 50, 1.0 / 16, 0, 5};
    flt_sim *sim = make_sim(calib, 6, keys, values);
    /* The reference surface as a 10 mm x 10 mm height map (bilinear error
     * < 2e-3 mm; the truth is the map itself, so it does not matter). */
    enum { MR = 560, MC = 171 };
    double *map = malloc(sizeof(double) * MR * MC);
    for (int r = 0; r < MR; ++r)
        for (int c = 0; c < MC; ++c)
            map[r * MC + c] = test_surface(-850 + 10.0 * c, -100 + 10.0 * r);
    assert_int_equal(flt_sim_set_height_map(sim, MR, MC, -100, 10, -850, 10, map), FLT_OK);
    free(map);
    flt_extractor *ex = make_extractor(calib, 0, NULL, NULL);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    double *s = malloc(FRAMES * sizeof(double));
    double *h = malloc(sizeof(double) * FRAMES * N), *g = malloc(sizeof(double) * FRAMES * N);
    double *truth = malloc(sizeof(double) * FRAMES * N), *z = malloc(sizeof(double) * FRAMES * N);
    uint8_t *valid = malloc(FRAMES * N);
    size_t valid_count = 0;
    for (int f = 0; f < FRAMES; ++f) {
        double e;
        assert_int_equal(flt_sim_next_frame(sim, frame, (size_t)W * ROI_ROWS, W, &e, N,
                                            truth + (size_t)f * N, NULL, 0),
                         FLT_OK);
        assert_int_equal(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N,
                                               &s[f], h + (size_t)f * N, g + (size_t)f * N,
                                               valid + (size_t)f * N),
                         FLT_OK);
        for (size_t k = 0; k < N; ++k)
            valid_count += valid[(size_t)f * N + k];
    }
    assert_int_equal(flt_reconstruct(NULL, FRAMES, N, s, h, g, valid, z, NULL), FLT_OK);
    double max_err = 0, sum2 = 0;
    for (size_t i = 0; i < (size_t)FRAMES * N; ++i) {
        const double d = fabs(z[i] - truth[i]);
        if (!(d <= max_err))
            max_err = d;
        sum2 += d * d;
    }
    print_message("end to end: max error %.3f mm, RMS %.3f mm, %.3f%% of samples valid\n", max_err,
                  sqrt(sum2 / ((double)FRAMES * N)), 100.0 * valid_count / ((double)FRAMES * N));
    assert_true(max_err <= 0.5);
    free(frame), free(s), free(h), free(g), free(truth), free(z), free(valid);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

/* Laser 0's peaks in rows[0, W): those at or below patch_row (on a patch)
 * and the others kept (on the line); returns the farthest of these from
 * line_row, px. */
static double line_and_patches(const double *rows, double line_row, double patch_row,
                               size_t *on_line, size_t *on_patch) {
    double worst = 0;
    for (uint32_t u = 0; u < W; ++u) {
        if (rows[u] >= patch_row)
            ++*on_patch;
        else if (rows[u] == rows[u]) {
            ++*on_line;
            worst = fmax(worst, fabs(rows[u] - line_row));
        }
    }
    return worst;
}

/* A line beside a bright, wide patch of background (a calibration target's
 * white field next to a line over one of its black marks; a lit strip):
 * the patch is brighter than the line, but it is no peak. Its brightest
 * pixel rises only a few counts of noise above the patch around it (too
 * faint above its background: extract_min_peak, 0.1 of full scale) and
 * the patch is wider than extract_max_width; either way all of it is
 * passed over and the line beside it is measured. Before, a ripple on the
 * patch was taken for the peak (or the candidates ran out inside the
 * patch): no column found the line. Bound: every column finds the line
 * within 0.1 px of its true row (noise-free line, sigma 2 px, on a flat
 * dark background: the Savitzky-Golay centre of a Gaussian is exact to
 * well under 0.05 px) and none reports a peak on the patch. */
static void line_beside_a_bright_patch_is_found(void **state) {
    (void)state;
    enum { N = 101 };
    flt_calib *calib = reference(N, 20.0);
    flt_extractor *ex = halves_extractor(calib);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    assert_non_null(frame);
    const double line_row = 40.3, line_sigma = 2.0;
    unsigned seed = 12345;
    for (uint32_t v = 0; v < ROI_ROWS; ++v)
        for (uint32_t u = 0; u < W; ++u) {
            double g = 25.0; /* the dark background, counts */
            /* Laser 0: the patch (rows 56..103: 48 rows, 180 +- 4 counts
             * of noise) 16 rows below a line of 110 counts above the
             * background; laser 1: the same line alone. */
            if (v >= 56 && v < 104) {
                seed = seed * 1103515245u + 12345u;
                g = 176.0 + (double)((seed >> 16) % 9);
            }
            const double d0 = ((double)v - line_row) / line_sigma;
            const double d1 = ((double)v - (line_row + 128)) / line_sigma;
            g += 110.0 * (exp(-0.5 * d0 * d0) + exp(-0.5 * d1 * d1));
            frame[(size_t)v * W + u] = (uint8_t)lround(g);
        }
    double e = 0, s, h[N], g[N], rows[2 * W];
    assert_int_equal(
        flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s, h, g, NULL),
        FLT_OK);
    assert_int_equal(flt_extractor_peaks(ex, W, rows), FLT_OK);
    size_t on_line = 0, on_patch = 0;
    const double worst = line_and_patches(rows, line_row, 50, &on_line, &on_patch);
    printf("line beside a bright patch: %zu of %d columns on the line (worst %.3f px), "
           "%zu on the patch\n",
           on_line, W, worst, on_patch);
    assert_int_equal(on_patch, 0);
    assert_int_equal(on_line, W);
    assert_true(worst <= 0.1);
    free(frame);
    flt_extractor_destroy(ex);
    flt_calib_destroy(calib);
}

/* A thin line (sigma 0.8 px, 120 counts, noise-free) on a background of
 * 100 counts that drops to 30 five rows below it (the edge of a dark patch
 * of the strip, or of a board's print), in both lasers' halves, near the
 * rows where they see z = 0 (laser 0's line in rows 128..255 at 150.3,
 * laser 1's in rows 0..127 at 105.3); drawn there, 0.3 rows higher and,
 * without the drop, there again. The default 11-row window reaches the drop and reads the line
 * 0.16-0.59 px too high (a parabola fitted over rows that hold the step);
 * a window the line's size (5 rows) does not reach it. Bound: every
 * column's peak within 0.02 px of its row, and the fibers' heights the
 * same with and without the drop to 0.02 of the height of a row (the
 * 1-row shift between the two lines gives that height; the remainder is
 * the narrow window's pixel locking on a noise-free line, < 0.01 px). */
static void draw_thin_line(uint8_t *frame, double shift, int drop) {
    for (uint32_t v = 0; v < ROI_ROWS; ++v)
        for (uint32_t u = 0; u < W; ++u) {
            const double line_row = (v < 128 ? 105.3 : 150.3) + shift;
            const double d = ((double)v - line_row) / 0.8;
            const double background = drop && (double)v >= line_row + 5 ? 30.0 : 100.0;
            frame[(size_t)v * W + u] = (uint8_t)lround(background + 120.0 * exp(-0.5 * d * d));
        }
}

static void thin_line_is_centred_at_its_own_scale(void **state) {
    (void)state;
    enum { N = 101 };
    flt_calib *calib = reference(N, 20.0);
    const flt_option keys[] = {FLT_OPT_EXTRACT_LASER0_FIRST_ROW, FLT_OPT_EXTRACT_LASER0_ROWS,
                               FLT_OPT_EXTRACT_LASER1_FIRST_ROW, FLT_OPT_EXTRACT_LASER1_ROWS};
    const double values[] = {128, 128, 0, 128};
    flt_extractor *ex = make_extractor(calib, 4, keys, values);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    assert_non_null(frame);
    const double shift[3] = {0, -0.3, 0};
    const int drop[3] = {1, 1, 0};
    double h[3][N], g[N], rows[2 * W], s;
    double worst_row = 0;
    for (int k = 0; k < 3; ++k) {
        draw_thin_line(frame, shift[k], drop[k]);
        assert_int_equal(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, 0.0, N,
                                               &s, h[k], g, NULL),
                         FLT_OK);
        assert_int_equal(flt_extractor_peaks(ex, W, rows), FLT_OK);
        for (size_t u = 0; u < 2 * (size_t)W; ++u)
            worst_row = fmax(worst_row, fabs(rows[u] - ((u < W ? 150.3 : 105.3) + shift[k])));
    }
    double worst_height = 0, row_height = INFINITY;
    size_t valid = 0;
    for (size_t k = 0; k < N; ++k) {
        if (!(h[0][k] == h[0][k]) || !(h[1][k] == h[1][k]) || !(h[2][k] == h[2][k]))
            continue;
        ++valid;
        row_height = fmin(row_height, fabs(h[0][k] - h[1][k]) / 0.3);
        worst_height = fmax(worst_height, fabs(h[0][k] - h[2][k]));
    }
    printf("thin line beside a drop: worst peak %.4f px off; heights with and without the drop "
           "%.5f mm apart (a row: %.4f mm) over %zu fibers\n",
           worst_row, worst_height, row_height, valid);
    assert_true(valid >= N - 2);
    assert_true(worst_row <= 0.02);
    assert_true(worst_height <= 0.02 * row_height);
    free(frame);
    flt_extractor_destroy(ex);
    flt_calib_destroy(calib);
}

/* A line across the image at 35 degrees (0.7 rows per column), up for
 * 1024 columns and down for the next 1024 (a frame of 1024 rows, sensor
 * rows 512..1535; both lasers read all of it), sigma 2 px, over a print of
 * alternating bright and dark stretches of 20 columns: over the bright
 * ones it saturates (peak 2x full scale), over the dark ones it rises 150
 * counts; 5 counts of noise. The saturated stretches are shorter than a
 * run that vouches for the line, so the glint check judges every column
 * near them by its unsaturated neighbours, of which one side's are
 * missing at each stretch's end. Read as a plain median, those neighbours
 * sit up to 0.7 rows per column of imbalance off the column's peak and the
 * check removed nearly every column; along the slope it keeps them.
 * Bound: at least 95 % of the columns within 0.1 px of the line (the
 * apex's +-12 columns see both slopes and are 1.2 % of them), none
 * farther than 1 px (a plateau's middle on a noise-free slope is exact to
 * about 0.05 px; the noise adds a few hundredths). */
enum { SLOPE_ROWS = 1024 };

static double apex_row(uint32_t u) {
    return 60.5 + 0.7 * (double)(u < 1024 ? u : 2048 - u);
}

static void sloping_saturated_line_is_kept(void **state) {
    (void)state;
    enum { N = 101 };
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create_reference(512, SLOPE_ROWS, -1000, 20.0, N, &calib), FLT_OK);
    const flt_option keys[] = {FLT_OPT_EXTRACT_LASER0_FIRST_ROW, FLT_OPT_EXTRACT_LASER0_ROWS,
                               FLT_OPT_EXTRACT_LASER1_FIRST_ROW, FLT_OPT_EXTRACT_LASER1_ROWS,
                               FLT_OPT_EXTRACT_STRIP_MIN_Z};
    const double values[] = {0, SLOPE_ROWS, 0, SLOPE_ROWS, -1000};
    flt_extractor *ex = make_extractor(calib, 5, keys, values);
    uint8_t *frame = malloc((size_t)W * SLOPE_ROWS);
    assert_non_null(frame);
    unsigned seed = 777;
    for (uint32_t v = 0; v < SLOPE_ROWS; ++v)
        for (uint32_t u = 0; u < W; ++u) {
            const double d = ((double)v - apex_row(u)) / 2.0;
            const double peak = (u / 20) % 2 ? 150.0 : 510.0;
            seed = seed * 1103515245u + 12345u;
            const double g = 30.0 + peak * exp(-0.5 * d * d) + (double)((seed >> 16) % 11) - 5.0;
            frame[(size_t)v * W + u] = (uint8_t)lround(fmin(255.0, fmax(0.0, g)));
        }
    double s, h[N], g[N], rows[2 * W];
    assert_int_equal(
        flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, SLOPE_ROWS, W, 0.0, N, &s, h, g, NULL),
        FLT_OK);
    assert_int_equal(flt_extractor_peaks(ex, W, rows), FLT_OK);
    size_t close = 0, far = 0;
    for (uint32_t u = 0; u < W; ++u) {
        const double error = fabs(rows[u] - apex_row(u));
        close += error <= 0.1;
        far += error > 1.0;
    }
    printf("a line at 35 degrees over bright and dark stretches: %zu of %d columns within 0.1 px, "
           "%zu farther than 1 px\n",
           close, W, far);
    assert_true(close >= 95 * W / 100);
    assert_int_equal(far, 0);
    free(frame);
    flt_extractor_destroy(ex);
    flt_calib_destroy(calib);
}

/* Several bright patches in a band (a tall band over a board's white
 * fields, or a lit strip with bright marks), each brighter than the line:
 * each is rejected as too wide and passed over whole, and the line is the
 * fifth candidate of every column. Laser 0's line at row 30.3, 110 counts
 * over a background of 25; four patches of 16 rows (rows 50, 70, 90 and
 * 110 on) at 190, 180, 170 and 160 counts, +-4 of noise; laser 1 the same
 * line alone. With 3 candidates per column no column found the line.
 * Bound: every column finds it within 0.1 px (as beside one patch) and
 * none reports a peak on a patch. */
static void line_below_four_bright_patches_is_found(void **state) {
    (void)state;
    enum { N = 101 };
    flt_calib *calib = reference(N, 20.0);
    flt_extractor *ex = halves_extractor(calib);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    assert_non_null(frame);
    const double line_row = 30.3, line_sigma = 2.0;
    unsigned seed = 777;
    for (uint32_t v = 0; v < ROI_ROWS; ++v)
        for (uint32_t u = 0; u < W; ++u) {
            double g = 25.0;
            for (int patch = 0; patch < 4; ++patch)
                if (v >= 50u + 20u * (uint32_t)patch && v < 66u + 20u * (uint32_t)patch) {
                    seed = seed * 1103515245u + 12345u;
                    g = 186.0 - 10.0 * patch + (double)((seed >> 16) % 9);
                }
            const double d0 = ((double)v - line_row) / line_sigma;
            const double d1 = ((double)v - (line_row + 128)) / line_sigma;
            g += 110.0 * (exp(-0.5 * d0 * d0) + exp(-0.5 * d1 * d1));
            frame[(size_t)v * W + u] = (uint8_t)lround(g);
        }
    double e = 0, s, h[N], g[N], rows[2 * W];
    assert_int_equal(
        flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s, h, g, NULL),
        FLT_OK);
    assert_int_equal(flt_extractor_peaks(ex, W, rows), FLT_OK);
    size_t on_line = 0, on_patch = 0;
    const double worst = line_and_patches(rows, line_row, 45, &on_line, &on_patch);
    printf("line below four bright patches: %zu of %d columns on the line (worst %.3f px), "
           "%zu on a patch\n",
           on_line, W, worst, on_patch);
    assert_int_equal(on_patch, 0);
    assert_int_equal(on_line, W);
    assert_true(worst <= 0.1);
    free(frame);
    flt_extractor_destroy(ex);
    flt_calib_destroy(calib);
}

/* A reflection brighter than the line where the line is dim (over a dark
 * patch of the strip): its peaks continue each other, so no column alone
 * looks wrong, but as a run they leave the line and come back
 * (reject_detours, lib/extraction/README.md), and the line under it is
 * read where it is still a peak (look_under_detours). Laser 0's line at
 * row 40.3, 110 counts over a background of 25, dimmed to 30 counts in
 * columns 1000..1039 and to 10 counts (below extract_min_peak, 26 counts:
 * no peak) in columns 1500..1539, where a reflection of 90 counts lies at
 * row 70.6, as wide as the line (the shape check cannot tell them apart;
 * without the continuity check those columns read the reflection, 30 px
 * off). Bound: no peak more than 0.1 px off the line; the 40 columns over
 * the 30-count stretch are read on the line, the 40 over the 10-count one
 * have no peak, the 1968 others are kept. */
static void a_reflection_over_a_dim_stretch_is_no_line(void **state) {
    (void)state;
    enum { N = 101 };
    flt_calib *calib = reference(N, 20.0);
    flt_extractor *ex = halves_extractor(calib);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    assert_non_null(frame);
    const double line_row = 40.3, line_sigma = 2.0, glare_row = 70.6, glare_sigma = 2.0;
    for (uint32_t v = 0; v < ROI_ROWS; ++v)
        for (uint32_t u = 0; u < W; ++u) {
            const int dim = u >= 1000 && u < 1040, dimmer = u >= 1500 && u < 1540;
            const double d0 = ((double)v - line_row) / line_sigma;
            const double d1 = ((double)v - (line_row + 128)) / line_sigma;
            const double dr = ((double)v - glare_row) / glare_sigma;
            double g = 25.0 +
                       (dim      ? 30.0
                        : dimmer ? 10.0
                                 : 110.0) *
                           exp(-0.5 * d0 * d0) +
                       110.0 * exp(-0.5 * d1 * d1);
            if (dim || dimmer)
                g += 90.0 * exp(-0.5 * dr * dr);
            frame[(size_t)v * W + u] = (uint8_t)lround(g);
        }
    double e = 0, s, h[N], g[N], rows[2 * W];
    assert_int_equal(
        flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s, h, g, NULL),
        FLT_OK);
    assert_int_equal(flt_extractor_peaks(ex, W, rows), FLT_OK);
    size_t kept = 0, under = 0, under_dimmer = 0;
    double worst = 0;
    for (uint32_t u = 0; u < W; ++u) {
        if (!(rows[u] == rows[u]))
            continue;
        worst = fmax(worst, fabs(rows[u] - line_row));
        ++kept;
        under += u >= 1000 && u < 1040;
        under_dimmer += u >= 1500 && u < 1540;
    }
    print_message("a reflection over a dim stretch: %zu of %d columns kept (%zu under the "
                  "reflection over the 30-count line, %zu over the 10-count one), worst %.3f "
                  "px off the line\n",
                  kept, W, under, under_dimmer, worst);
    assert_true(worst <= 0.1);
    assert_int_equal(under, 40);
    assert_int_equal(under_dimmer, 0);
    assert_int_equal(kept, W - 40);
    free(frame);
    flt_extractor_destroy(ex);
    flt_calib_destroy(calib);
}

/* A speck nothing continues is no line: where the line is missing for 100
 * columns, a line-shaped speck 3 columns wide lies 30 rows off it. The
 * line is 30 columns away on one side and 67 on the other, too far on one
 * side for the detour check (a chord needs the line within 32 columns on
 * both sides), so before the stray check the speck's columns read 30 px off
 * the line. A 6-column piece of the line within the gap, which continues
 * the line beyond it, stays. */
static void a_speck_nothing_continues_is_no_line(void **state) {
    (void)state;
    enum { N = 101 };
    flt_calib *calib = reference(N, 20.0);
    flt_extractor *ex = halves_extractor(calib);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    assert_non_null(frame);
    const double line_row = 40.3, line_sigma = 2.0, speck_row = 70.6;
    for (uint32_t v = 0; v < ROI_ROWS; ++v)
        for (uint32_t u = 0; u < W; ++u) {
            const int missing = u >= 1000 && u < 1100 && !(u >= 1070 && u < 1076);
            const int speck = u >= 1030 && u < 1033;
            const double d0 = ((double)v - line_row) / line_sigma;
            const double d1 = ((double)v - (line_row + 128)) / line_sigma;
            const double ds = ((double)v - speck_row) / line_sigma;
            double g =
                25.0 + (missing ? 0.0 : 110.0) * exp(-0.5 * d0 * d0) + 110.0 * exp(-0.5 * d1 * d1);
            if (speck)
                g += 90.0 * exp(-0.5 * ds * ds);
            frame[(size_t)v * W + u] = (uint8_t)lround(g);
        }
    double e = 0, s, h[N], g[N], rows[2 * W];
    assert_int_equal(
        flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s, h, g, NULL),
        FLT_OK);
    assert_int_equal(flt_extractor_peaks(ex, W, rows), FLT_OK);
    size_t kept = 0, speck_kept = 0, piece_kept = 0;
    double worst = 0;
    for (uint32_t u = 0; u < W; ++u) {
        if (!(rows[u] == rows[u]))
            continue;
        ++kept;
        speck_kept += u >= 1030 && u < 1033;
        piece_kept += u >= 1070 && u < 1076;
        if (!(u >= 1030 && u < 1033))
            worst = fmax(worst, fabs(rows[u] - line_row));
    }
    print_message("a speck nothing continues: %zu of %d columns kept (%zu of the speck's 3, "
                  "%zu of the line's 6-column piece in the gap), worst %.3f px off the line\n",
                  kept, W, speck_kept, piece_kept, worst);
    assert_true(worst <= 0.1);
    assert_int_equal(speck_kept, 0);
    assert_int_equal(piece_kept, 6);
    assert_int_equal(kept, W - 100 + 6);
    free(frame);
    flt_extractor_destroy(ex);
    flt_calib_destroy(calib);
}

/* A dim stretch of the line between two confident pieces of it: a line
 * 110 counts over a background of 25, which over a 50-column dark patch
 * (background 8) rises only 14 counts, under extract_min_peak (0.1 of
 * full scale, 26 counts), with noise of 1.5 counts on every pixel. The
 * pieces on both sides say where the line runs, and there it stands 9
 * noise deviations out: at least 48 of those 50 columns are kept, with an
 * RMS error of at most 0.16 px and none beyond 0.5 px (the centre, a
 * Gaussian-weighted centroid of the line's width, scatters by 0.125 px
 * under this noise: 1.5 counts x 1.24 / (14 x 1.2 x sqrt(pi) / 2); the
 * bounds allow for 50 samples and 4 deviations). Before, none was kept.
 * A second dark patch where the line does not
 * show at all keeps no peak (noise alone reaches 5 deviations of the
 * gap's own noise about once in 3.5 million samples), nor does a dim
 * stretch longer than 64 columns (not bridged: too far to predict). */
static void a_dim_stretch_between_pieces_of_the_line_is_kept(void **state) {
    (void)state;
    enum { N = 101 };
    flt_calib *calib = reference(N, 20.0);
    flt_extractor *ex = halves_extractor(calib);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    assert_non_null(frame);
    const double line_sigma = 1.2;
    uint64_t rng = 0x9E3779B97F4A7C15ull;
    for (uint32_t v = 0; v < ROI_ROWS; ++v)
        for (uint32_t u = 0; u < W; ++u) {
            const double row = 40.3 + 0.01 * ((double)u - 1000.0);
            const int dim = (u >= 1000 && u < 1050) || (u >= 1500 && u < 1590);
            const int absent = u >= 1300 && u < 1350;
            const double d0 = ((double)v - row) / line_sigma;
            const double d1 = ((double)v - (40.3 + 128)) / line_sigma;
            double g = (dim || absent ? 8.0 : 25.0) + 110.0 * exp(-0.5 * d1 * d1);
            if (v < 128)
                g += (absent ? 0.0 : dim ? 14.0 : 110.0) * exp(-0.5 * d0 * d0);
            /* Gaussian noise, sigma 1.5: twelve uniforms summed. */
            double n = -6.0;
            for (int k = 0; k < 12; ++k) {
                rng = rng * 6364136223846793005ull + 1442695040888963407ull;
                n += (double)(rng >> 11) / 9007199254740992.0;
            }
            frame[(size_t)v * W + u] = (uint8_t)lround(fmin(255.0, fmax(0.0, g + 1.5 * n)));
        }
    double e = 0, s, h[N], g[N], rows[2 * W];
    assert_int_equal(
        flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s, h, g, NULL),
        FLT_OK);
    assert_int_equal(flt_extractor_peaks(ex, W, rows), FLT_OK);
    size_t dim_kept = 0, absent_kept = 0, long_kept = 0;
    double worst = 0, sum2 = 0;
    for (uint32_t u = 0; u < W; ++u) {
        if (!(rows[u] == rows[u]))
            continue;
        const double off = fabs(rows[u] - (40.3 + 0.01 * ((double)u - 1000.0)));
        if (u >= 1000 && u < 1050)
            ++dim_kept, sum2 += off * off, worst = fmax(worst, off);
        absent_kept += u >= 1300 && u < 1350;
        long_kept += u >= 1500 && u < 1590;
    }
    print_message("a dim stretch between pieces of the line: %zu of its 50 columns kept, RMS "
                  "%.3f px, worst %.3f px; %zu of 50 kept where the line is absent, %zu of 90 in "
                  "a stretch too long to bridge\n",
                  dim_kept, dim_kept ? sqrt(sum2 / (double)dim_kept) : 0.0, worst, absent_kept,
                  long_kept);
    assert_true(dim_kept >= 48);
    assert_true(sqrt(sum2 / (double)dim_kept) <= 0.16);
    assert_true(worst <= 0.5);
    assert_int_equal(absent_kept, 0);
    assert_int_equal(long_kept, 0);
    free(frame);
    flt_extractor_destroy(ex);
    flt_calib_destroy(calib);
}

/* The same frame gives the same bytes, in one extractor and in another. */
/* The same camera with its image's x axis running the other way across the
 * strip (a camera turned round on its mount, or a homography whose x
 * points the other way): the columns' x then falls along the row, and each
 * fiber's columns are gathered from the other end. Through a calibration
 * whose homographies negate x and whose fiber grid is the same fibers
 * numbered from the other side, every fiber must read what it reads
 * through the reference calibration: the same validity and the same
 * heights (the sums are the same numbers with dx negated, so the bound is
 * a few units of rounding, 1e-9 mm), on frames of a buckled strip with
 * wavy edges that fill the fiber grid and reach past it. */
static void a_camera_turned_round_reads_the_same_fibers(void **state) {
    (void)state;
    enum { N = 401, FRAMES = 4 };
    const double pitch = 5.0, first_x = -1000.0;
    flt_calib *calib = reference(N, pitch);
    double cam[4], dist[8], h[2][9], offset[2], scale;
    uint32_t fw, fh;
    assert_int_equal(flt_calib_get_intrinsics(calib, cam, FLT_CALIB_CAMERA_VALUES, dist,
                                              FLT_CALIB_DISTORTION_COEFFS),
                     FLT_OK);
    assert_int_equal(flt_calib_get_frame_size(calib, &fw, &fh), FLT_OK);
    assert_int_equal(flt_calib_get_encoder_scale(calib, &scale), FLT_OK);
    flt_calib *turned = NULL;
    assert_int_equal(flt_calib_create(&turned), FLT_OK);
    assert_int_equal(flt_calib_set_frame_size(turned, fw, fh), FLT_OK);
    assert_int_equal(flt_calib_set_intrinsics(turned, cam, FLT_CALIB_CAMERA_VALUES, dist,
                                              FLT_CALIB_DISTORTION_COEFFS),
                     FLT_OK);
    for (unsigned laser = 0; laser < 2; ++laser) {
        assert_int_equal(flt_calib_get_homography(calib, laser, h[laser], 9), FLT_OK);
        for (int i = 0; i < 3; ++i)
            h[laser][i] = -h[laser][i]; /* x' = -x */
        assert_int_equal(flt_calib_set_homography(turned, laser, h[laser], 9), FLT_OK);
        assert_int_equal(flt_calib_get_laser_offset(calib, laser, &offset[laser]), FLT_OK);
        assert_int_equal(flt_calib_set_laser_offset(turned, laser, offset[laser]), FLT_OK);
    }
    assert_int_equal(flt_calib_set_encoder_scale(turned, scale), FLT_OK);
    /* Fiber k' of the turned grid is fiber N - 1 - k' of the reference's. */
    assert_int_equal(flt_calib_set_fiber_grid(turned, -(first_x + pitch * (N - 1)), pitch, N),
                     FLT_OK);
    assert_int_equal(flt_calib_finish(turned), FLT_OK);
    flt_sim *sim = make_sim(calib, 0, NULL, NULL);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 12, 1800), FLT_OK);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, 8, 900), FLT_OK);
    flt_extractor *ex = make_extractor(calib, 0, NULL, NULL);
    flt_extractor *ex_turned = make_extractor(turned, 0, NULL, NULL);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    size_t valid_count = 0;
    double worst = 0;
    for (int f = 0; f < FRAMES; ++f) {
        double e, s, s2, hgt[N], g[N], hgt2[N], g2[N];
        uint8_t valid[N], valid2[N];
        assert_int_equal(
            flt_sim_next_frame(sim, frame, (size_t)W * ROI_ROWS, W, &e, 0, NULL, NULL, 0), FLT_OK);
        assert_int_equal(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s,
                                               hgt, g, valid),
                         FLT_OK);
        assert_int_equal(flt_extractor_process(ex_turned, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e,
                                               N, &s2, hgt2, g2, valid2),
                         FLT_OK);
        for (size_t k = 0; k < N; ++k) {
            const size_t k2 = N - 1 - k;
            assert_int_equal(valid[k], valid2[k2]);
            if (!valid[k])
                continue;
            ++valid_count;
            worst = fmax(worst, fabs(hgt[k] - hgt2[k2]));
            worst = fmax(worst, fabs(g[k] - g2[k2]) * 100);
        }
    }
    print_message(
        "camera turned round: %zu of %d fibers valid through both, heights within %.3g mm\n",
        valid_count, FRAMES * N, worst);
    assert_true(valid_count >= (size_t)(0.99 * FRAMES * N));
    assert_true(worst <= 1e-9);
    free(frame);
    flt_extractor_destroy(ex_turned);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_calib_destroy(turned);
    flt_calib_destroy(calib);
}

static void same_frame_same_bytes(void **state) {
    (void)state;
    enum { N = 101 };
    flt_calib *calib = reference(N, 20.0);
    const flt_option keys[] = {FLT_OPT_SIM_REFLECTIONS};
    const double values[] = {10};
    flt_sim *sim = make_sim(calib, 1, keys, values);
    flt_extractor *a = make_extractor(calib, 0, NULL, NULL),
                  *b = make_extractor(calib, 0, NULL, NULL);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    double e, s[3], h[3][N], g[3][N], pa[2 * W], pb[2 * W];
    assert_int_equal(flt_sim_next_frame(sim, frame, (size_t)W * ROI_ROWS, W, &e, 0, NULL, NULL, 0),
                     FLT_OK);
    assert_int_equal(flt_extractor_process(a, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s[0],
                                           h[0], g[0], NULL),
                     FLT_OK);
    assert_int_equal(flt_extractor_peaks(a, W, pa), FLT_OK);
    assert_int_equal(flt_extractor_process(a, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s[1],
                                           h[1], g[1], NULL),
                     FLT_OK);
    assert_int_equal(flt_extractor_process(b, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s[2],
                                           h[2], g[2], NULL),
                     FLT_OK);
    assert_int_equal(flt_extractor_peaks(b, W, pb), FLT_OK);
    assert_memory_equal(h[0], h[1], sizeof h[0]);
    assert_memory_equal(h[0], h[2], sizeof h[0]);
    assert_memory_equal(g[0], g[2], sizeof g[0]);
    assert_memory_equal(pa, pb, sizeof pa);
    free(frame);
    flt_extractor_destroy(a), flt_extractor_destroy(b);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

static void expect_error(flt_status st, flt_status code, const char *needle) {
    assert_int_equal(st, code);
    if (!strstr(flt_last_error_message(), needle))
        fail_msg("message '%s' lacks '%s'", flt_last_error_message(), needle);
}

/* A frame with one line (one laser on while commissioning): the line's
 * laser is the one whose plane puts it within -+extract_strip_min_z (of two,
 * the one that puts it at most half as far from the pass line), and the
 * other band goes where the calibration puts the other line at the same
 * height. Frames of the reference ROI with one laser's band blanked (its
 * rows replaced by the frame's first row, background and noise only): the
 * bands found lie within 3 rows of those two lines give (the other line's
 * row is predicted, not seen: its centre from the calibration, against the
 * brightest row of the sums), and the extractor reads the next two-line
 * frame as the one whose bands came from two lines: heights within 0.02 mm,
 * the same fibers valid (the bands hold the lines far from their ends, so
 * only the column maps' fitting interval moves). A line at a row that
 * could be either laser's (z = 50 mm through one plane, -45 mm through the
 * other: neither twice the other) is refused with a message saying so. */
static void one_line_places_both_bands(void **state) {
    (void)state;
    enum { N = 101 };
    flt_calib *calib = reference(N, 20.0);
    flt_sim *sim = make_sim(calib, 0, NULL, NULL);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS), *one = malloc((size_t)W * ROI_ROWS);
    double e, s, h[2][N], g[N];
    uint8_t valid[2][N];
    assert_int_equal(flt_sim_next_frame(sim, frame, (size_t)W * ROI_ROWS, W, &e, 0, NULL, NULL, 0),
                     FLT_OK);
    flt_extractor *two = make_extractor(calib, 0, NULL, NULL);
    assert_int_equal(flt_extractor_process(two, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s,
                                           h[0], g, valid[0]),
                     FLT_OK);
    uint32_t first[2], rows[2];
    for (unsigned laser = 0; laser < 2; ++laser)
        assert_int_equal(flt_extractor_band(two, laser, &first[laser], &rows[laser]), FLT_OK);
    for (unsigned lit = 0; lit < 2; ++lit) {
        const unsigned dark = 1 - lit;
        memcpy(one, frame, (size_t)W * ROI_ROWS);
        for (uint32_t v = first[dark]; v < first[dark] + rows[dark]; ++v)
            memcpy(one + (size_t)v * W, frame, W);
        flt_extractor *ex = make_extractor(calib, 0, NULL, NULL);
        assert_int_equal(flt_extractor_process(ex, one, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s,
                                               h[1], g, valid[1]),
                         FLT_OK);
        for (unsigned laser = 0; laser < 2; ++laser) {
            uint32_t f, r;
            assert_int_equal(flt_extractor_band(ex, laser, &f, &r), FLT_OK);
            print_message("laser %u alone: laser %u's band rows %u + %u (from two lines: %u + "
                          "%u)\n",
                          lit, laser, f, r, first[laser], rows[laser]);
            assert_true(abs((int)f - (int)first[laser]) <= 3);
            assert_true(abs((int)(f + r) - (int)(first[laser] + rows[laser])) <= 3);
        }
        /* The dark laser's band shows no line: every fiber off the strip. */
        for (size_t k = 0; k < N; ++k)
            assert_int_equal(valid[1][k], 0);
        assert_int_equal(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s,
                                               h[1], g, valid[1]),
                         FLT_OK);
        double worst = 0;
        size_t n_valid = 0;
        for (size_t k = 0; k < N; ++k) {
            assert_int_equal(valid[1][k], valid[0][k]);
            if (valid[0][k])
                worst = fmax(worst, fabs(h[1][k] - h[0][k])), ++n_valid;
        }
        print_message("  the next two-line frame: %zu fibers valid, heights within %.4f mm of "
                      "the two-line bands'\n",
                      n_valid, worst);
        assert_true(n_valid >= N - 2);
        assert_true(worst <= 0.02);
        flt_extractor_destroy(ex);
    }
    /* A line either laser could cast: rows 994-1042 of the reference
     * camera lie within -+100 mm for both planes; row 1018 is ROI row 126. */
    memset(one, 10, (size_t)W * ROI_ROWS);
    for (int dv = -4; dv <= 4; ++dv)
        memset(one + (size_t)(126 + dv) * W, (int)(10 + 150 * exp(-0.5 * dv * dv / 2.25)), W);
    flt_extractor *ex = make_extractor(calib, 0, NULL, NULL);
    expect_error(
        flt_extractor_process(ex, one, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s, h[1], g, NULL),
        FLT_ERR_NUMERIC, "either laser's");
    print_message("a line at row 1018: %s\n", flt_last_error_message());
    /* ... and the extractor is still usable: the next frame places the bands. */
    assert_int_equal(
        flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s, h[1], g, NULL),
        FLT_OK);
    flt_extractor_destroy(ex);
    flt_extractor_destroy(two);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
    free(frame), free(one);
}

/* Bad input: the status, a message naming the argument, and an extractor
 * that still works afterwards. */
static void bad_input_is_rejected_by_name(void **state) {
    (void)state;
    enum { N = 11 };
    flt_calib *calib = reference(N, 100.0);
    flt_sim *sim = make_sim(calib, 0, NULL, NULL);
    flt_extractor *ex = make_extractor(calib, 0, NULL, NULL), *none = NULL;
    uint8_t *frame = malloc((size_t)W * ROI_ROWS + 1);
    double e, s, h[N], g[N], peaks[2 * W];
    assert_int_equal(flt_sim_next_frame(sim, frame, (size_t)W * ROI_ROWS, W, &e, 0, NULL, NULL, 0),
                     FLT_OK);
    expect_error(flt_extractor_create(NULL, NULL, &none), FLT_ERR_INVALID_ARGUMENT, "'calib'");
    expect_error(flt_extractor_create(calib, NULL, NULL), FLT_ERR_INVALID_ARGUMENT, "'out'");
    flt_calib *unfinished = NULL;
    assert_int_equal(flt_calib_create(&unfinished), FLT_OK);
    expect_error(flt_extractor_create(unfinished, NULL, &none), FLT_ERR_STATE, "not finished");
    flt_calib_destroy(unfinished);
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    expect_error(flt_options_set(o, FLT_OPT_EXTRACT_MIN_PEAK, NAN), FLT_ERR_INVALID_ARGUMENT,
                 "'extract_min_peak' is NaN");
    assert_int_equal(flt_options_set(o, FLT_OPT_EXTRACT_SG_WINDOW, 8), FLT_OK);
    expect_error(flt_extractor_create(calib, o, &none), FLT_ERR_INVALID_ARGUMENT,
                 "'extract_sg_window' = 8");
    assert_int_equal(flt_options_set(o, FLT_OPT_EXTRACT_SG_WINDOW, 7), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_EXTRACT_LASER0_FIRST_ROW, 200), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_EXTRACT_LASER0_ROWS, 100), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_EXTRACT_LASER1_ROWS, 100), FLT_OK);
    expect_error(flt_extractor_create(calib, o, &none), FLT_ERR_INVALID_ARGUMENT,
                 "'extract_laser0_first_row' = 200");
    assert_null(none);
    flt_options_destroy(o);
    expect_error(flt_extractor_peaks(ex, W, peaks), FLT_ERR_STATE, "no frame");
    expect_error(
        flt_extractor_process(NULL, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s, h, g, NULL),
        FLT_ERR_INVALID_ARGUMENT, "'extractor'");
    expect_error(
        flt_extractor_process(ex, NULL, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s, h, g, NULL),
        FLT_ERR_INVALID_ARGUMENT, "'frame'");
    expect_error(
        flt_extractor_process(ex, frame, (flt_pixel_format)9, W, ROI_ROWS, W, e, N, &s, h, g, NULL),
        FLT_ERR_INVALID_ARGUMENT, "'format' = 9");
    expect_error(
        flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W - 1, ROI_ROWS, W, e, N, &s, h, g, NULL),
        FLT_ERR_INVALID_ARGUMENT, "'width' x 'height' = 2047 x 256");
    expect_error(
        flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W - 1, e, N, &s, h, g, NULL),
        FLT_ERR_INVALID_ARGUMENT, "'stride_bytes' = 2047");
    expect_error(
        flt_extractor_process(ex, frame, FLT_PIXEL_MONO16, W, ROI_ROWS, W, e, N, &s, h, g, NULL),
        FLT_ERR_INVALID_ARGUMENT, "'stride_bytes' = 2048");
    expect_error(flt_extractor_process(ex, frame + 1, FLT_PIXEL_MONO16, W, ROI_ROWS, 2 * W, e, N,
                                       &s, h, g, NULL),
                 FLT_ERR_INVALID_ARGUMENT, "2-byte aligned 'frame'");
    expect_error(
        flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, NAN, N, &s, h, g, NULL),
        FLT_ERR_INVALID_ARGUMENT, "'encoder_mm' = nan");
    expect_error(
        flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N + 1, &s, h, g, NULL),
        FLT_ERR_INVALID_ARGUMENT, "'fibers' = 12");
    expect_error(
        flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s, NULL, g, NULL),
        FLT_ERR_INVALID_ARGUMENT, "'height_out'");
    /* An automatic band needs two lines: a black frame is a numeric error. */
    uint8_t *black = calloc((size_t)W * ROI_ROWS, 1);
    expect_error(
        flt_extractor_process(ex, black, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s, h, g, NULL),
        FLT_ERR_NUMERIC, "two laser lines");
    free(black);
    uint32_t first, rows;
    expect_error(flt_extractor_band(ex, 0, &first, &rows), FLT_ERR_STATE, "automatic");
    /* still usable */
    assert_int_equal(
        flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e, N, &s, h, g, NULL),
        FLT_OK);
    assert_string_equal(flt_last_error_message(), "");
    assert_int_equal(flt_extractor_band(ex, 1, &first, &rows), FLT_OK);
    assert_true(rows >= 32);
    expect_error(flt_extractor_band(ex, 2, &first, &rows), FLT_ERR_INVALID_ARGUMENT, "'laser' = 2");
    flt_extractor_destroy(NULL);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
    free(frame);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(peak_rows_within_a_sixteenth_of_a_pixel),
        cmocka_unit_test(heights_within_0_1_mm_two_sigma),
        cmocka_unit_test(mono12_frames_give_the_same_accuracy),
        cmocka_unit_test(spurious_reflections_are_rejected_not_measured),
        cmocka_unit_test(end_to_end_reference_sheet_within_half_a_millimetre),
        cmocka_unit_test(line_beside_a_bright_patch_is_found),
        cmocka_unit_test(line_below_four_bright_patches_is_found),
        cmocka_unit_test(thin_line_is_centred_at_its_own_scale),
        cmocka_unit_test(sloping_saturated_line_is_kept),
        cmocka_unit_test(a_reflection_over_a_dim_stretch_is_no_line),
        cmocka_unit_test(a_speck_nothing_continues_is_no_line),
        cmocka_unit_test(a_dim_stretch_between_pieces_of_the_line_is_kept),
        cmocka_unit_test(a_camera_turned_round_reads_the_same_fibers),
        cmocka_unit_test(same_frame_same_bytes),
        cmocka_unit_test(one_line_places_both_bands),
        cmocka_unit_test(bad_input_is_rejected_by_name),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
