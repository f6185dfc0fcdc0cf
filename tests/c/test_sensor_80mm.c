// SPDX-License-Identifier: Apache-2.0
/*
 * A sensor that is not the reference one, end to end: its lasers are 80 mm
 * apart (not 100 mm), it is calibrated through the public API from
 * image/plane correspondences, the simulator renders its camera frames, the
 * extractor turns them into profile rows, a reconstructor created from the
 * calibration (flt_recon_create_from_calib) rebuilds the strip and the
 * flatness metrics measure it. Heights and I-Units are checked against the
 * simulator's ground truth, and the same rows reconstructed for a 100 mm
 * sensor (the laser_spacing default) must be measurably wrong, so the test
 * can see the mistake it guards against.
 *
 * Frames are rows 892..1147 of the reference camera (an ROI readout, as in
 * test_extractor.c): both lines and +-40 mm of height fit, and rendering
 * costs an eighth of the full sensor.
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

#define ROI_FIRST 892
#define ROI_ROWS  256
#define W         2048
#define SPACING   80.0 /* mm between the laser planes */
/* 20 mm apart, x = -980 .. 980 mm: inside the 2000 mm strip, whose edge
 * is a kink of the simulated wavy edges (the shape is held constant beyond
 * it), which a fiber on it would measure as a few tenths of a mm of error
 * whatever the spacing. */
#define FIBERS    99
#define PITCH     20.0
#define FRAMES    1200 /* 3 mm apart: 3.6 m of strip */

/* The camera of the reference sensor (tests/c/calib_synth.c, written
 * independently of the library) with laser planes at s = -40 and +40 mm.
 * The homographies are estimated, as on a real line, from points of each
 * plane (a 21 x 9 grid, x -1000..1000 mm, z -40..40 mm) and their exact
 * images. */
static flt_calib *sensor_80mm(void) {
    flt_calib *c = NULL;
    assert_int_equal(flt_calib_create(&c), FLT_OK);
    assert_int_equal(flt_calib_set_frame_size(c, W, ROI_ROWS), FLT_OK);
    /* Reading out an ROI moves the principal point with it. */
    const double camera[4] = {synth_camera[0], synth_camera[1], synth_camera[2],
                              synth_camera[3] - ROI_FIRST};
    assert_int_equal(flt_calib_set_intrinsics(c, camera, FLT_CALIB_CAMERA_VALUES, synth_distortion,
                                              FLT_CALIB_DISTORTION_COEFFS),
                     FLT_OK);
    const double offset[2] = {-0.5 * SPACING, 0.5 * SPACING};
    enum { NX = 21, NZ = 9, N = NX * NZ };
    double image[2 * N], plane[2 * N];
    for (unsigned laser = 0; laser < 2; ++laser) {
        for (int i = 0; i < NX; ++i)
            for (int j = 0; j < NZ; ++j) {
                const int p = i * NZ + j;
                plane[2 * p] = -1000.0 + 100.0 * i;
                plane[2 * p + 1] = -40.0 + 10.0 * j;
                assert_true(synth_project(plane[2 * p], offset[laser], plane[2 * p + 1],
                                          &image[2 * p], &image[2 * p + 1]));
                image[2 * p + 1] -= ROI_FIRST;
            }
        double rms_mm = 0;
        assert_int_equal(flt_calib_estimate_homography(c, laser, N, image, plane, NULL, NULL, NULL,
                                                       NULL, NULL, &rms_mm),
                         FLT_OK);
        /* Exact correspondences: only the undistortion's 1e-9 px is left. */
        assert_true(rms_mm < 1e-6);
        assert_int_equal(flt_calib_set_laser_offset(c, laser, offset[laser]), FLT_OK);
    }
    assert_int_equal(flt_calib_set_encoder_scale(c, 0.01), FLT_OK);
    assert_int_equal(flt_calib_set_fiber_grid(c, -980.0, PITCH, FIBERS), FLT_OK);
    assert_int_equal(flt_calib_finish(c), FLT_OK);
    double spacing = 0;
    assert_int_equal(flt_calib_laser_spacing(c, &spacing), FLT_OK);
    assert_true(spacing == SPACING);
    return c;
}

/* The measured strip: rows, their truth and the extractor's output. */
typedef struct strip {
    double s[FRAMES];
    double *height, *slope, *truth;
    uint8_t *valid;
} strip;

/* A centre buckle of 8 mm at 1600 mm along travel and wavy edges of 5 mm at
 * 400 mm: the short waves are where the secant slope over Delta-d differs
 * most from one over another distance (by sinc(pi d / P)), so a wrong
 * spacing shows there. Rendered frames with the simulator's default line,
 * speckle and shot noise, no motion: what is left is the extractor's noise
 * and the spacing. */
static strip *measure(const flt_calib *calib) {
    strip *m = calloc(1, sizeof *m);
    const size_t n = (size_t)FRAMES * FIBERS;
    m->height = malloc(n * sizeof(double));
    m->slope = malloc(n * sizeof(double));
    m->truth = malloc(n * sizeof(double));
    m->valid = malloc(n);
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_SIM_SEED, 11), FLT_OK);
    flt_sim *sim = NULL;
    assert_int_equal(flt_sim_create(calib, o, &sim), FLT_OK);
    flt_options_destroy(o);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 8.0, 1600.0), FLT_OK);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, 5.0, 400.0), FLT_OK);
    flt_extractor *ex = NULL;
    assert_int_equal(flt_extractor_create(calib, NULL, &ex), FLT_OK);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    for (size_t f = 0; f < FRAMES; ++f) {
        double e;
        assert_int_equal(flt_sim_next_frame(sim, frame, (size_t)W * ROI_ROWS, W, &e, FIBERS,
                                            m->truth + f * FIBERS, NULL, 0),
                         FLT_OK);
        assert_int_equal(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e,
                                               FIBERS, &m->s[f], m->height + f * FIBERS,
                                               m->slope + f * FIBERS, m->valid + f * FIBERS),
                         FLT_OK);
    }
    free(frame);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    return m;
}

static void strip_free(strip *m) {
    free(m->height), free(m->slope), free(m->truth), free(m->valid), free(m);
}

/* Streams the strip through a reconstructor as one sheet, in blocks of 50
 * rows as frames arrive, and returns every row's z (in order). */
static void stream(flt_recon *rc, const strip *m, double *z, uint8_t *flags) {
    size_t pulled = 0;
    double s_out[FRAMES];
    for (size_t f = 0; f < FRAMES; f += 50) {
        const size_t rows = FRAMES - f < 50 ? FRAMES - f : 50;
        assert_int_equal(flt_recon_push(rc, rows, FIBERS, m->s + f, m->height + f * FIBERS,
                                        m->slope + f * FIBERS, m->valid + f * FIBERS),
                         FLT_OK);
        size_t got = 0;
        assert_int_equal(flt_recon_pull(rc, FRAMES - pulled, FIBERS, s_out + pulled,
                                        z + pulled * FIBERS, flags + pulled * FIBERS, &got),
                         FLT_OK);
        pulled += got;
    }
    assert_int_equal(flt_recon_end_sheet(rc), FLT_OK);
    size_t got = 0;
    assert_int_equal(flt_recon_pull(rc, FRAMES - pulled, FIBERS, s_out + pulled,
                                    z + pulled * FIBERS, flags + pulled * FIBERS, &got),
                     FLT_OK);
    pulled += got;
    assert_int_equal(pulled, FRAMES);
    for (size_t r = 0; r < FRAMES; ++r)
        assert_true(s_out[r] == m->s[r]);
}

/* Max and RMS of |z - truth| over every row and fiber; the number of NaNs. */
static void errors(const strip *m, const double *z, double *max_err, double *rms, size_t *nans) {
    double sum2 = 0;
    *max_err = 0;
    *nans = 0;
    for (size_t i = 0; i < (size_t)FRAMES * FIBERS; ++i) {
        const double d = fabs(z[i] - m->truth[i]);
        if (d != d) {
            ++*nans;
            continue;
        }
        if (d > *max_err)
            *max_err = d;
        sum2 += d * d;
    }
    *rms = sqrt(sum2 / ((double)FRAMES * FIBERS));
}

/* Per-fiber I-Units of a whole sheet. */
static void i_units(const flt_calib *calib, const double *s, const double *z, const uint8_t *flags,
                    double *out) {
    flt_flatness *fl = NULL;
    assert_int_equal(flt_flatness_create_from_calib(calib, NULL, &fl), FLT_OK);
    assert_int_equal(flt_flatness_evaluate(fl, FRAMES, FIBERS, s, z, flags), FLT_OK);
    uint8_t fiber_flags[FIBERS];
    assert_int_equal(
        flt_flatness_fiber_results(fl, FIBERS, NULL, out, NULL, NULL, NULL, fiber_flags), FLT_OK);
    for (size_t k = 0; k < FIBERS; ++k)
        assert_int_equal(fiber_flags[k] & FLT_FIBER_NO_DATA, 0);
    flt_flatness_destroy(fl);
}

static void sensor_80mm_end_to_end(void **state) {
    (void)state;
    flt_calib *calib = sensor_80mm();
    strip *m = measure(calib);
    size_t valid = 0;
    for (size_t i = 0; i < (size_t)FRAMES * FIBERS; ++i)
        valid += m->valid[i];
    const size_t n = (size_t)FRAMES * FIBERS;
    double *z = malloc(n * sizeof(double)), *z100 = malloc(n * sizeof(double));
    uint8_t *flags = malloc(n), *flags100 = malloc(n);

    /* The reconstructor takes 80 mm and 101 fibers from the calibration. */
    flt_recon *rc = NULL;
    assert_int_equal(flt_recon_create_from_calib(calib, NULL, &rc), FLT_OK);
    double spacing = 0, knots = 0;
    size_t fibers = 0;
    assert_int_equal(flt_recon_get_option(rc, FLT_OPT_LASER_SPACING, &spacing), FLT_OK);
    assert_int_equal(flt_recon_get_option(rc, FLT_OPT_KNOT_SPACING, &knots), FLT_OK);
    assert_int_equal(flt_recon_fibers(rc, &fibers), FLT_OK);
    assert_true(spacing == SPACING && knots == SPACING && fibers == FIBERS);
    stream(rc, m, z, flags);
    flt_recon_destroy(rc);

    /* The same rows, reconstructed as if the lasers were 100 mm apart: what
     * flt_recon_create(fibers, NULL, ...) did for this sensor. */
    assert_int_equal(flt_recon_create(FIBERS, NULL, &rc), FLT_OK);
    stream(rc, m, z100, flags100);
    flt_recon_destroy(rc);

    double max_err, rms, max100, rms100;
    size_t nans, nans100;
    errors(m, z, &max_err, &rms, &nans);
    errors(m, z100, &max100, &rms100, &nans100);
    print_message("80 mm sensor, %.3f%% of samples valid: heights max error %.3f mm, RMS "
                  "%.4f mm; reconstructed for 100 mm: max %.3f mm, RMS %.4f mm\n",
                  100.0 * (double)valid / (double)n, max_err, rms, max100, rms100);
    assert_int_equal(nans, 0);
    /* The extractor's heights are good to 0.06 mm (2 sigma, test_extractor),
     * a sigma of 0.03 mm per sample; the spline averages each height with
     * its neighbours and leans on the slopes, so the RMS stays below
     * 0.02 mm (measured: 0.010) and the worst of 118,800 samples, about
     * 4.5 sigma of one sample, below 0.1 mm (measured: 0.047). */
    assert_true(rms <= 0.02);
    assert_true(max_err <= 0.1);
    /* The wrong spacing misreads each wave's slope by sinc(pi 80 / P) /
     * sinc(pi 100 / P): 4 % on the 400 mm edge waves of 5 mm, about 0.2 mm
     * (measured: max 0.19, RMS 0.047). It must stand out of the noise. */
    assert_true(max100 >= 3 * max_err);
    assert_true(rms100 >= 3 * rms);

    /* I-Units of the reconstruction against those of the truth on the same
     * rows. The outer fibers carry about 125 I (9.2 mm peak to peak at
     * 400 mm); I-Units are quadratic in the wave height, so a height error
     * of e on an amplitude of H gives 2 e / H of them: 2 * 0.02 / 9.2 = 0.4 %
     * of I, plus the noise's own (positive) arc length, well under 1 I at
     * 3 mm rows for 0.03 mm of smoothed noise. 1 % of the largest + 1 I. */
    double iu[FIBERS], iu_true[FIBERS], iu100[FIBERS];
    i_units(calib, m->s, z, flags, iu);
    i_units(calib, m->s, m->truth, NULL, iu_true);
    i_units(calib, m->s, z100, flags100, iu100);
    double largest = 0, worst = 0, worst100 = 0;
    for (size_t k = 0; k < FIBERS; ++k) {
        largest = fmax(largest, iu_true[k]);
        worst = fmax(worst, fabs(iu[k] - iu_true[k]));
        worst100 = fmax(worst100, fabs(iu100[k] - iu_true[k]));
    }
    const double tolerance = 0.01 * largest + 1.0;
    print_message("I-Units: largest %.1f I, worst error %.2f I (tolerance %.2f); for 100 mm "
                  "%.2f I\n",
                  largest, worst, tolerance, worst100);
    assert_true(largest > 100); /* the waves are there (measured: 0.27 I off, 100 mm: 10.6 I) */
    assert_true(worst <= tolerance);
    assert_true(worst100 > tolerance);

    free(z), free(z100), free(flags), free(flags100);
    strip_free(m);
    flt_calib_destroy(calib);
}

/* The calibration decides the spacing; an option that agrees with it is
 * accepted and one that does not is refused with both numbers. */
static void laser_spacing_option_must_agree(void **state) {
    (void)state;
    flt_calib *calib = sensor_80mm();
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    flt_recon *rc = NULL;
    assert_int_equal(flt_options_set(o, FLT_OPT_LASER_SPACING, 100.0), FLT_OK);
    assert_int_equal(flt_recon_create_from_calib(calib, o, &rc), FLT_ERR_INVALID_ARGUMENT);
    assert_null(rc);
    const char *msg = flt_last_error_message();
    assert_non_null(strstr(msg, "'laser_spacing' = 100 mm disagrees with the 80 mm"));
    /* An agreeing value is accepted, and the other options apply. */
    assert_int_equal(flt_options_set(o, FLT_OPT_LASER_SPACING, 80.0), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_KNOT_SPACING, 40.0), FLT_OK);
    assert_int_equal(flt_recon_create_from_calib(calib, o, &rc), FLT_OK);
    double knots = 0;
    assert_int_equal(flt_recon_get_option(rc, FLT_OPT_KNOT_SPACING, &knots), FLT_OK);
    assert_true(knots == 40.0);
    flt_recon_destroy(rc);
    flt_options_destroy(o);
    flt_calib_destroy(calib);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(sensor_80mm_end_to_end),
        cmocka_unit_test(laser_spacing_option_must_agree),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
