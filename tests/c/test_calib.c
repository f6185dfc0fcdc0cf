// SPDX-License-Identifier: Apache-2.0
/*
 * Calibration model: handle life cycle and argument checks, laser-plane
 * homographies on the synthetic reference sensor (tests/c/calib_synth.h),
 * the lens model, geometry, and concurrent mapping.
 */
#include <math.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "calib_synth.h"
#include "flatline/flatline.h"

/* The laser planes' measuring field: the full strip width the camera sees
 * (|x| <= 1200 mm, inside the +-1500 mm the image spans at z = 0) and the
 * height range of the gauge (|z| <= 100 mm). */
#define FOV_X_MM 1200.0
#define FOV_Z_MM 100.0

/* Calibration correspondences: a target stepped through the measuring field
 * every 100 mm in x and 50 mm in z (25 x 5 = 125 points per laser). */
static size_t make_correspondences(unsigned laser, double noise_px, double outlier_fraction,
                                   uint64_t seed, double *image_px, double *plane_mm,
                                   int *is_outlier) {
    uint64_t rng = seed;
    size_t n = 0;
    for (double z = -FOV_Z_MM; z <= FOV_Z_MM + 1e-9; z += 50.0)
        for (double x = -FOV_X_MM; x <= FOV_X_MM + 1e-9; x += 100.0) {
            double u, v;
            assert_true(synth_project(x, synth_laser_offset[laser], z, &u, &v));
            assert_true(u > 0 && u < SYNTH_WIDTH - 1 && v > 0 && v < SYNTH_HEIGHT - 1);
            u += noise_px * synth_gauss(&rng);
            v += noise_px * synth_gauss(&rng);
            int outlier = synth_uniform(&rng) < outlier_fraction;
            if (outlier) {
                /* A mis-identified target point: 5 to 50 px off. */
                const double d = 5 + 45 * synth_uniform(&rng);
                const double a = 6.283185307179586 * synth_uniform(&rng);
                u += d * cos(a), v += d * sin(a);
            }
            if (is_outlier)
                is_outlier[n] = outlier;
            image_px[2 * n] = u, image_px[2 * n + 1] = v;
            plane_mm[2 * n] = x, plane_mm[2 * n + 1] = z;
            ++n;
        }
    return n;
}

enum { max_points = 256 };

static void set_geometry(flt_calib *calib) {
    assert_int_equal(flt_calib_set_frame_size(calib, SYNTH_WIDTH, SYNTH_HEIGHT), FLT_OK);
    assert_int_equal(flt_calib_set_laser_offset(calib, 0, synth_laser_offset[0]), FLT_OK);
    assert_int_equal(flt_calib_set_laser_offset(calib, 1, synth_laser_offset[1]), FLT_OK);
    assert_int_equal(flt_calib_set_encoder_scale(calib, 0.0125), FLT_OK);
    assert_int_equal(flt_calib_set_fiber_grid(calib, -1000.0, 2.0, 1001), FLT_OK);
}

/* Builds and finishes a calibration of the synthetic sensor with the true
 * intrinsics and estimated homographies. */
static flt_calib *calibrate_sensor(double noise_px, double outlier_fraction,
                                   const flt_options *options, double rms_px[2], double rms_mm[2],
                                   size_t misclassified[2]) {
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create(&calib), FLT_OK);
    set_geometry(calib);
    assert_int_equal(flt_calib_set_intrinsics(calib, synth_camera, FLT_CALIB_CAMERA_VALUES,
                                              synth_distortion, FLT_CALIB_DISTORTION_COEFFS),
                     FLT_OK);
    for (unsigned laser = 0; laser < 2; ++laser) {
        double image[2 * max_points], plane[2 * max_points];
        double res_px[max_points], res_mm[max_points];
        uint8_t inlier[max_points];
        int outlier[max_points];
        const size_t n = make_correspondences(laser, noise_px, outlier_fraction, 1234 + laser,
                                              image, plane, outlier);
        double rp, rm;
        assert_int_equal(flt_calib_estimate_homography(calib, laser, n, image, plane, options,
                                                       res_px, res_mm, inlier, &rp, &rm),
                         FLT_OK);
        if (rms_px)
            rms_px[laser] = rp;
        if (rms_mm)
            rms_mm[laser] = rm;
        size_t wrong = 0;
        for (size_t i = 0; i < n; ++i)
            wrong += (inlier[i] != 0) == (outlier[i] != 0);
        if (misclassified)
            misclassified[laser] = wrong;
    }
    assert_int_equal(flt_calib_finish(calib), FLT_OK);
    return calib;
}

/* RMS and max distance (mm) between the true plane points of a dense grid
 * over the measuring field and their images mapped back onto the plane. */
static void field_error(const flt_calib *calib, unsigned laser, double *rms, double *max) {
    enum { nx = 121, nz = 41 };
    static double image[2 * nx * nz], plane[2 * nx * nz];
    size_t n = 0;
    for (int j = 0; j < nz; ++j)
        for (int i = 0; i < nx; ++i) {
            const double x = -FOV_X_MM + 2 * FOV_X_MM * i / (nx - 1);
            const double z = -FOV_Z_MM + 2 * FOV_Z_MM * j / (nz - 1);
            assert_true(
                synth_project(x, synth_laser_offset[laser], z, &image[2 * n], &image[2 * n + 1]));
            plane[2 * n] = x, plane[2 * n + 1] = z;
            ++n;
        }
    assert_int_equal(flt_calib_image_to_plane(calib, laser, n, image, image), FLT_OK);
    double sum = 0;
    *max = 0;
    for (size_t i = 0; i < n; ++i) {
        const double d = hypot(image[2 * i] - plane[2 * i], image[2 * i + 1] - plane[2 * i + 1]);
        sum += d * d;
        if (!(d <= *max))
            *max = d;
    }
    *rms = sqrt(sum / n);
}

/* ------------------------------------------------------------------ tests */

/* Noise-free correspondences: the true image->plane map of a pinhole camera
 * is exactly a homography, so only rounding remains. 1e-6 mm is the
 * goal; double rounding through Newton undistortion (1e-10 px) and the
 * fit is ~1e-9 mm. */
static void homography_noise_free_is_exact(void **state) {
    (void)state;
    double rms_px[2], rms_mm[2];
    flt_calib *calib = calibrate_sensor(0.0, 0.0, NULL, rms_px, rms_mm, NULL);
    for (unsigned laser = 0; laser < 2; ++laser) {
        double rms, max;
        field_error(calib, laser, &rms, &max);
        print_message("laser %u noise-free: fit rms %.3g px %.3g mm; field rms %.3g "
                      "mm max %.3g mm\n",
                      laser, rms_px[laser], rms_mm[laser], rms, max);
        assert_true(max < 1e-6);
        assert_true(rms_px[laser] < 1e-6);
    }
    flt_calib_destroy(calib);
}

/* 0.05 px noise per axis: each point lands ~0.1 mm off on the plane
 * (1.5 mm/px across, 2.1 mm/px along z at 45 degrees); 125 points pin the
 * 8 parameters down to ~0.1 * sqrt(8/125) = 0.025 mm RMS. Bound: 0.05 mm
 * (issue). The fit's own reprojection RMS must match the injected noise:
 * sqrt(2) * 0.05 * sqrt((125 - 4) / 125) ~ 0.07 px, within 20 %. */
static void homography_with_noise_is_within_bound(void **state) {
    (void)state;
    double rms_px[2], rms_mm[2];
    flt_calib *calib = calibrate_sensor(0.05, 0.0, NULL, rms_px, rms_mm, NULL);
    for (unsigned laser = 0; laser < 2; ++laser) {
        double rms, max;
        field_error(calib, laser, &rms, &max);
        print_message("laser %u 0.05 px noise: fit rms %.4f px %.4f mm; field rms "
                      "%.4f mm max %.4f mm\n",
                      laser, rms_px[laser], rms_mm[laser], rms, max);
        assert_true(rms <= 0.05);
        assert_true(fabs(rms_px[laser] - 0.0696) < 0.2 * 0.0696);
    }
    flt_calib_destroy(calib);
}

/* 10 % gross outliers (5..50 px off): without RANSAC the map is ruined
 * (> 1 mm); with it the same 0.05 mm bound holds and every outlier is
 * rejected. Inliers may be lost only beyond the 1 px threshold = 14 sigma:
 * none. */
static void homography_ransac_rejects_outliers(void **state) {
    (void)state;
    flt_options *opts = NULL;
    assert_int_equal(flt_options_create(&opts), FLT_OK);
    assert_int_equal(flt_options_set(opts, FLT_OPT_CALIB_RANSAC, 1), FLT_OK);

    flt_calib *plain = calibrate_sensor(0.05, 0.10, NULL, NULL, NULL, NULL);
    double rms_plain, max_plain;
    field_error(plain, 0, &rms_plain, &max_plain);
    print_message("10%% outliers without RANSAC: field rms %.3f mm\n", rms_plain);
    assert_true(rms_plain > 1.0);
    flt_calib_destroy(plain);

    size_t wrong[2];
    flt_calib *calib = calibrate_sensor(0.05, 0.10, opts, NULL, NULL, wrong);
    for (unsigned laser = 0; laser < 2; ++laser) {
        double rms, max;
        field_error(calib, laser, &rms, &max);
        print_message("laser %u 10%% outliers + RANSAC: field rms %.4f mm max %.4f "
                      "mm, misclassified %zu\n",
                      laser, rms, max, wrong[laser]);
        assert_true(rms <= 0.05);
        assert_int_equal(wrong[laser], 0);
    }
    flt_calib_destroy(calib);
    flt_options_destroy(opts);
}

/* Residual reports: per point, px and mm agree with the RMS reported. */
static void homography_residuals_are_consistent(void **state) {
    (void)state;
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create(&calib), FLT_OK);
    assert_int_equal(flt_calib_set_intrinsics(calib, synth_camera, FLT_CALIB_CAMERA_VALUES,
                                              synth_distortion, FLT_CALIB_DISTORTION_COEFFS),
                     FLT_OK);
    double image[2 * max_points], plane[2 * max_points];
    double res_px[max_points], res_mm[max_points], rms_px, rms_mm;
    const size_t n = make_correspondences(0, 0.05, 0.0, 99, image, plane, NULL);
    assert_int_equal(flt_calib_estimate_homography(calib, 0, n, image, plane, NULL, res_px, res_mm,
                                                   NULL, &rms_px, &rms_mm),
                     FLT_OK);
    double sp = 0, sm = 0;
    for (size_t i = 0; i < n; ++i)
        sp += res_px[i] * res_px[i], sm += res_mm[i] * res_mm[i];
    assert_near(sqrt(sp / n), rms_px, 1e-12);
    assert_near(sqrt(sm / n), rms_mm, 1e-12);
    /* mm per px on this plane is 1.5..2.1 (see above): the ratio says the
     * two reports measure the same residual in their own units. */
    const double ratio = rms_mm / rms_px;
    print_message("residual ratio %.3f mm/px\n", ratio);
    assert_true(ratio > 1.2 && ratio < 2.6);
    flt_calib_destroy(calib);
}

/* The lens model inverts itself to 1e-9 px over the whole frame, corners
 * (15 % distortion) included, and agrees with the independent model of the
 * test support to 1e-9 px. */
static void undistort_inverts_distortion(void **state) {
    (void)state;
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create(&calib), FLT_OK);
    assert_int_equal(flt_calib_set_intrinsics(calib, synth_camera, FLT_CALIB_CAMERA_VALUES,
                                              synth_distortion, FLT_CALIB_DISTORTION_COEFFS),
                     FLT_OK);
    assert_int_equal(flt_calib_set_frame_size(calib, SYNTH_WIDTH, SYNTH_HEIGHT), FLT_OK);
    enum { n = 33 * 33 };
    static double raw[2 * n], ideal[2 * n];
    size_t k = 0;
    for (int j = 0; j < 33; ++j)
        for (int i = 0; i < 33; ++i) {
            raw[2 * k] = i * (SYNTH_WIDTH - 1) / 32.0;
            raw[2 * k + 1] = j * (SYNTH_HEIGHT - 1) / 32.0;
            ++k;
        }
    assert_int_equal(flt_calib_undistort(calib, n, raw, ideal), FLT_OK);
    /* Re-distort the ideal points with the test's own model: project the
     * ray (x, y, 1) through synth_project's camera = distort + K. */
    double worst = 0;
    for (size_t i = 0; i < n; ++i) {
        const double x = (ideal[2 * i] - synth_camera[2]) / synth_camera[0];
        const double y = (ideal[2 * i + 1] - synth_camera[3]) / synth_camera[1];
        const double *d = synth_distortion;
        const double r2 = x * x + y * y;
        const double radial = 1 + d[0] * r2 + d[1] * r2 * r2 + d[4] * r2 * r2 * r2;
        const double xd = x * radial + 2 * d[2] * x * y + d[3] * (r2 + 2 * x * x);
        const double yd = y * radial + d[2] * (r2 + 2 * y * y) + 2 * d[3] * x * y;
        const double e = hypot(synth_camera[0] * xd + synth_camera[2] - raw[2 * i],
                               synth_camera[1] * yd + synth_camera[3] - raw[2 * i + 1]);
        if (!(e <= worst))
            worst = e;
    }
    /* The raw corner, 1445 px from the centre, is an ideal point ~1710 px
     * out, where the radial factor is 1 - 0.155: a shift of ~265 px. */
    const double corner_shift = hypot(ideal[0] - raw[0], ideal[1] - raw[1]);
    print_message("undistort: worst round trip %.3g px, corner shift %.1f px\n", worst,
                  corner_shift);
    assert_true(worst < 1e-9);
    assert_near(corner_shift, 265.0, 10.0);
    flt_calib_destroy(calib);
}

/* plane -> image -> plane is the identity to 1e-9 mm, and NaN stays NaN. */
static void mapping_round_trip_and_nan(void **state) {
    (void)state;
    flt_calib *calib = calibrate_sensor(0.0, 0.0, NULL, NULL, NULL, NULL);
    double pts[2 * 5] = {-1000, -80, 0, 0, 1000, 80, 500, -20, NAN, 3};
    double img[2 * 5], back[2 * 5];
    for (unsigned laser = 0; laser < 2; ++laser) {
        assert_int_equal(flt_calib_plane_to_image(calib, laser, 5, pts, img), FLT_OK);
        assert_int_equal(flt_calib_image_to_plane(calib, laser, 5, img, back), FLT_OK);
        for (int i = 0; i < 4; ++i) {
            assert_near(back[2 * i], pts[2 * i], 1e-9);
            assert_near(back[2 * i + 1], pts[2 * i + 1], 1e-9);
            double u, v; /* and the image point is where the true camera sees it */
            assert_true(
                synth_project(pts[2 * i], synth_laser_offset[laser], pts[2 * i + 1], &u, &v));
            assert_near(img[2 * i], u, 1e-6);
            assert_near(img[2 * i + 1], v, 1e-6);
        }
        assert_true(isnan(back[8]) && isnan(back[9]));
    }
    /* count 0 with NULL arrays is a no-op */
    assert_int_equal(flt_calib_image_to_plane(calib, 0, 0, NULL, NULL), FLT_OK);
    flt_calib_destroy(calib);
}

static void geometry_round_trips(void **state) {
    (void)state;
    flt_calib *calib = calibrate_sensor(0.0, 0.0, NULL, NULL, NULL, NULL);
    double spacing, offset, scale, first, pitch;
    size_t count;
    uint32_t w, h;
    assert_int_equal(flt_calib_laser_spacing(calib, &spacing), FLT_OK);
    assert_near(spacing, 100.0, 0.0);
    assert_int_equal(flt_calib_get_laser_offset(calib, 1, &offset), FLT_OK);
    assert_near(offset, 50.0, 0.0);
    assert_int_equal(flt_calib_get_encoder_scale(calib, &scale), FLT_OK);
    assert_near(scale, 0.0125, 0.0);
    assert_int_equal(flt_calib_get_fiber_grid(calib, &first, &pitch, &count), FLT_OK);
    assert_near(first, -1000.0, 0.0);
    assert_near(pitch, 2.0, 0.0);
    assert_int_equal(count, 1001);
    assert_int_equal(flt_calib_get_frame_size(calib, &w, &h), FLT_OK);
    assert_int_equal(w, 2048);
    double cam[4], dist[8];
    assert_int_equal(flt_calib_get_intrinsics(calib, cam, FLT_CALIB_CAMERA_VALUES, dist,
                                              FLT_CALIB_DISTORTION_COEFFS),
                     FLT_OK);
    assert_near(cam[0], SYNTH_FOCAL_PX, 0.0);
    assert_near(dist[0], -0.08, 0.0);
    flt_calib_destroy(calib);
}

/* Life cycle rules: finish names what is missing; a finished model refuses
 * changes; an unfinished one refuses mapping; bad arguments are named. */
static void life_cycle_and_bad_arguments(void **state) {
    (void)state;
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create(NULL), FLT_ERR_INVALID_ARGUMENT);
    assert_int_equal(flt_calib_create(&calib), FLT_OK);
    assert_int_equal(flt_calib_finish(calib), FLT_ERR_STATE);
    assert_non_null(strstr(flt_last_error_message(), "frame size"));
    double pt[2] = {1000, 1000}, out[2];
    assert_int_equal(flt_calib_image_to_plane(calib, 0, 1, pt, out), FLT_ERR_STATE);
    assert_int_equal(flt_calib_set_frame_size(calib, 0, 10), FLT_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(flt_last_error_message(), "'width' = 0"));
    const double bad_cam[4] = {-5, 1000, 1024, 1024};
    assert_int_equal(flt_calib_set_intrinsics(calib, bad_cam, FLT_CALIB_CAMERA_VALUES, NULL, 0),
                     FLT_ERR_INVALID_ARGUMENT);
    const double singular[9] = {1, 2, 3, 2, 4, 6, 0, 0, 1};
    assert_int_equal(flt_calib_set_homography(calib, 0, singular, FLT_CALIB_HOMOGRAPHY_ENTRIES),
                     FLT_ERR_INVALID_ARGUMENT);
    const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    assert_int_equal(flt_calib_set_homography(calib, 2, identity, FLT_CALIB_HOMOGRAPHY_ENTRIES),
                     FLT_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(flt_last_error_message(), "'laser' = 2"));
    assert_int_equal(flt_calib_set_laser_offset(calib, 0, NAN), FLT_ERR_INVALID_ARGUMENT);
    assert_int_equal(flt_calib_set_encoder_scale(calib, 0.0), FLT_ERR_INVALID_ARGUMENT);
    assert_int_equal(flt_calib_set_fiber_grid(calib, 0, -2, 10), FLT_ERR_INVALID_ARGUMENT);
    /* homography before intrinsics: state error */
    double img[8] = {0, 0, 1, 0, 0, 1, 1, 1}, pl[8] = {0, 0, 1, 0, 0, 1, 1, 1};
    assert_int_equal(
        flt_calib_estimate_homography(calib, 0, 4, img, pl, NULL, NULL, NULL, NULL, NULL, NULL),
        FLT_ERR_STATE);
    /* collinear correspondences are degenerate */
    assert_int_equal(
        flt_calib_set_intrinsics(calib, synth_camera, FLT_CALIB_CAMERA_VALUES, NULL, 0), FLT_OK);
    double line_img[10] = {0, 0, 1, 1, 2, 2, 3, 3, 4, 4};
    double line_pl[10] = {0, 0, 1, 0, 2, 0, 3, 0, 4, 0};
    assert_int_equal(flt_calib_estimate_homography(calib, 0, 5, line_img, line_pl, NULL, NULL, NULL,
                                                   NULL, NULL, NULL),
                     FLT_ERR_NUMERIC);
    assert_int_equal(
        flt_calib_estimate_homography(calib, 0, 3, img, pl, NULL, NULL, NULL, NULL, NULL, NULL),
        FLT_ERR_INVALID_ARGUMENT);
    flt_calib_destroy(calib);
    flt_calib_destroy(NULL); /* no-op */

    calib = calibrate_sensor(0.0, 0.0, NULL, NULL, NULL, NULL);
    int finished = 0;
    assert_int_equal(flt_calib_is_finished(calib, &finished), FLT_OK);
    assert_int_equal(finished, 1);
    assert_int_equal(flt_calib_set_encoder_scale(calib, 1.0), FLT_ERR_STATE);
    assert_int_equal(flt_calib_finish(calib), FLT_ERR_STATE);
    double scale;
    assert_int_equal(flt_calib_get_encoder_scale(calib, &scale), FLT_OK);
    assert_near(scale, 0.0125, 0.0); /* the failed set changed nothing */
    flt_calib_destroy(calib);

    /* the calibration options are registered by name */
    flt_option key;
    assert_int_equal(flt_option_find("calib_ransac_threshold", &key), FLT_OK);
    assert_int_equal(key, FLT_OPT_CALIB_RANSAC_THRESHOLD);
}

/* ------------------------------------------------------- thread safety */

enum { thread_points = 20000, thread_rounds = 10, thread_count = 4 };

struct thread_job {
    const flt_calib *calib;
    const double *image;    /* thread_points x 2 */
    const double *expected; /* thread_points x 2, single-threaded result */
    size_t mismatches;
    int status;
};

static void *map_concurrently(void *arg) {
    struct thread_job *job = arg;
    double *out = malloc(sizeof(double) * 2 * thread_points);
    double *back = malloc(sizeof(double) * 2 * thread_points);
    job->mismatches = 0;
    job->status = FLT_OK;
    for (int round = 0; round < thread_rounds; ++round) {
        const unsigned laser = (unsigned)round % 2;
        flt_status st = flt_calib_image_to_plane(job->calib, laser, thread_points, job->image, out);
        if (st != FLT_OK)
            job->status = st;
        st = flt_calib_plane_to_image(job->calib, laser, thread_points, out, back);
        if (st != FLT_OK)
            job->status = st;
        for (size_t i = 0; i < 2 * thread_points; ++i)
            if (memcmp(&out[i], &job->expected[laser * 2 * thread_points + i], sizeof(double)) != 0)
                ++job->mismatches;
    }
    free(out);
    free(back);
    return NULL;
}

/* A finished calibration is shared by 4 threads mapping at once; every
 * result is bit-identical to the single-threaded one. */
static void finished_calibration_is_shared_by_threads(void **state) {
    (void)state;
    flt_calib *calib = calibrate_sensor(0.05, 0.0, NULL, NULL, NULL, NULL);
    double *image = malloc(sizeof(double) * 2 * thread_points);
    double *expected = malloc(sizeof(double) * 4 * thread_points);
    uint64_t rng = 7;
    for (size_t i = 0; i < thread_points; ++i) {
        image[2 * i] = SYNTH_WIDTH * synth_uniform(&rng);
        image[2 * i + 1] = 900 + 200 * synth_uniform(&rng);
    }
    for (unsigned laser = 0; laser < 2; ++laser)
        assert_int_equal(flt_calib_image_to_plane(calib, laser, thread_points, image,
                                                  expected + laser * 2 * thread_points),
                         FLT_OK);
    pthread_t threads[thread_count];
    struct thread_job jobs[thread_count];
    for (int t = 0; t < thread_count; ++t) {
        jobs[t].calib = calib, jobs[t].image = image, jobs[t].expected = expected;
        assert_int_equal(pthread_create(&threads[t], NULL, map_concurrently, &jobs[t]), 0);
    }
    size_t mismatches = 0;
    for (int t = 0; t < thread_count; ++t) {
        assert_int_equal(pthread_join(threads[t], NULL), 0);
        assert_int_equal(jobs[t].status, FLT_OK);
        mismatches += jobs[t].mismatches;
    }
    assert_int_equal(mismatches, 0);
    free(image);
    free(expected);
    flt_calib_destroy(calib);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(homography_noise_free_is_exact),
        cmocka_unit_test(homography_with_noise_is_within_bound),
        cmocka_unit_test(homography_ransac_rejects_outliers),
        cmocka_unit_test(homography_residuals_are_consistent),
        cmocka_unit_test(undistort_inverts_distortion),
        cmocka_unit_test(mapping_round_trip_and_nan),
        cmocka_unit_test(geometry_round_trips),
        cmocka_unit_test(life_cycle_and_bad_arguments),
        cmocka_unit_test(finished_calibration_is_shared_by_threads),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
