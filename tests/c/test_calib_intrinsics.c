// SPDX-License-Identifier: Apache-2.0
/*
 * Camera intrinsics from rendered target images: 12 views of a
 * 10 x 7-square chessboard (9 x 6 inner corners, 60 mm squares), and of
 * symmetric and asymmetric circle grids, rendered through
 * the reference camera of tests/c/calib_synth.h (f = 1090.9 px, -15 %
 * barrel distortion in the corners), then detected, refined and calibrated
 * by flt_calib_estimate_intrinsics.
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

#define DEG (3.141592653589793 / 180)

enum { views = 12, squares_x = 10, squares_y = 7 };
static const double square_mm = 60.0;

/* rx, ry, rz (degrees) and the board centre in the camera frame (mm): tilts
 * of 20..35 degrees about both axes and boards in every quadrant, so focal
 * length, principal point and distortion are all observable. */
static const double poses[views][6] = {
    {0, 0, 0, 0, 0, 1000},           {25, 0, 0, 0, -300, 1100},     {-25, 0, 0, 0, 300, 1100},
    {0, 25, 0, -350, 0, 1100},       {0, -25, 0, 350, 0, 1100},     {20, 20, 10, -400, -350, 1200},
    {-20, 20, -10, -400, 350, 1200}, {20, -20, 5, 400, -350, 1200}, {-20, -20, -5, 400, 350, 1200},
    {35, 0, 15, 0, 0, 1300},         {0, 35, -15, 0, 0, 1300},      {-30, -30, 0, 0, 0, 1400},
};

static uint8_t *g_images[views];

static int render_views(void **state) {
    (void)state;
    double *ray_map = malloc(sizeof(double) * 2 * SYNTH_WIDTH * SYNTH_HEIGHT);
    assert_non_null(ray_map);
    synth_ray_map(ray_map);
    for (int v = 0; v < views; ++v) {
        g_images[v] = malloc((size_t)SYNTH_WIDTH * SYNTH_HEIGHT);
        const double *p = poses[v];
        if (!synth_render_chessboard(ray_map, squares_x, squares_y, square_mm, p[0] * DEG,
                                     p[1] * DEG, p[2] * DEG, p + 3, g_images[v]))
            fail_msg("pose %d puts the board outside the image", v);
    }
    free(ray_map);
    return 0;
}

static int free_views(void **state) {
    (void)state;
    for (int v = 0; v < views; ++v)
        free(g_images[v]);
    return 0;
}

/* Focal length within 0.5 % (issue) and reprojection RMS below 0.1 px
 * (issue; the reference lab reached 0.04 px). The renderer's 8 x 8
 * supersampling and 8-bit grey levels leave corner biases of a few
 * hundredths of a pixel (measured RMS 0.065 px, focal error 0.01 %). */
static void chessboard_views_give_the_camera(void **state) {
    (void)state;
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create(&calib), FLT_OK);
    assert_int_equal(flt_calib_set_frame_size(calib, SYNTH_WIDTH, SYNTH_HEIGHT), FLT_OK);
    double rms = -1, view_rms[views];
    const uint8_t *const *images = (const uint8_t *const *)g_images;
    assert_int_equal(flt_calib_estimate_intrinsics(calib, views, images, SYNTH_WIDTH,
                                                   FLT_TARGET_CHESSBOARD, squares_x - 1,
                                                   squares_y - 1, square_mm, NULL, &rms, view_rms),
                     FLT_OK);
    double cam[4], dist[8];
    assert_int_equal(flt_calib_get_intrinsics(calib, cam, FLT_CALIB_CAMERA_VALUES, dist,
                                              FLT_CALIB_DISTORTION_COEFFS),
                     FLT_OK);
    const double fx_err = cam[0] / synth_camera[0] - 1;
    const double fy_err = cam[1] / synth_camera[1] - 1;
    print_message("rms %.4f px; fx %.3f (%+.4f %%), fy %.3f (%+.4f %%), cx %.2f "
                  "(true %.2f), cy %.2f (true %.2f), k1 %.4f k2 %.4f\n",
                  rms, cam[0], 100 * fx_err, cam[1], 100 * fy_err, cam[2], synth_camera[2], cam[3],
                  synth_camera[3], dist[0], dist[1]);
    size_t found = 0;
    double worst_view = 0;
    for (int v = 0; v < views; ++v) {
        print_message("  view %2d rms %.4f px\n", v, view_rms[v]);
        if (!isnan(view_rms[v])) {
            ++found;
            if (view_rms[v] > worst_view)
                worst_view = view_rms[v];
        }
    }
    assert_int_equal(found, views); /* every rendered board is detected */
    assert_true(fabs(fx_err) < 0.005);
    assert_true(fabs(fy_err) < 0.005);
    assert_true(rms < 0.1);
    /* One view may be worse than the mean: the frontal view at 1000 mm has
     * the largest squares, where the renderer's linearised sub-samples bias
     * corners most (measured 0.094 px). */
    assert_true(worst_view < 0.15);
    /* The principal point: within 0.5 % of the focal length (5 px); its
     * uncertainty is about the focal length's times the image half-size. */
    assert_near(cam[2], synth_camera[2], 5.0);
    assert_near(cam[3], synth_camera[3], 5.0);
    /* The distortion: where the boards were seen (out to ~850 px from the
     * centre along the diagonals) the estimated model must undistort to
     * within 1.5 px of the true one: the principal point itself is only
     * pinned to ~1 px by these views (measured 1.05 px), and that offset
     * passes into the undistorted points (measured worst 0.85 px). The image
     * corners, 1445 px out, are extrapolation and are not judged. */
    flt_calib *true_cam = NULL;
    assert_int_equal(flt_calib_create(&true_cam), FLT_OK);
    assert_int_equal(flt_calib_set_intrinsics(true_cam, synth_camera, FLT_CALIB_CAMERA_VALUES,
                                              synth_distortion, FLT_CALIB_DISTORTION_COEFFS),
                     FLT_OK);
    const double probe[8] = {1030 - 600, 1020 - 600, 1030 + 600, 1020 - 600,
                             1030 - 600, 1020 + 600, 1030 + 600, 1020 + 600};
    double est[8], truth[8], worst_px = 0;
    assert_int_equal(flt_calib_undistort(calib, 4, probe, est), FLT_OK);
    assert_int_equal(flt_calib_undistort(true_cam, 4, probe, truth), FLT_OK);
    for (int i = 0; i < 4; ++i) {
        const double d = hypot(est[2 * i] - truth[2 * i], est[2 * i + 1] - truth[2 * i + 1]);
        if (d > worst_px)
            worst_px = d;
    }
    print_message("undistortion at 850 px radius: worst difference %.3f px\n", worst_px);
    assert_true(worst_px < 1.5);
    flt_calib_destroy(true_cam);
    flt_calib_destroy(calib);
}

/* Intrinsics from 12 views of `target` rendered by `render` (one call per
 * view pose, into images[v]; NULL: the chessboard views rendered for the
 * group); returns the RMS, writes the estimate and the number of views the
 * target was found in. */
typedef int (*render_fn)(const double *ray_map, const double pose[6], uint8_t *image);

static double estimate_from(render_fn render, flt_calib_target target, uint32_t columns,
                            uint32_t rows, double pitch_mm, const flt_options *options,
                            double cam[4], double dist[8], size_t *found,
                            double *undistort_worst_px) {
    uint8_t *images[views];
    if (render) {
        double *ray_map = malloc(sizeof(double) * 2 * SYNTH_WIDTH * SYNTH_HEIGHT);
        assert_non_null(ray_map);
        synth_ray_map(ray_map);
        for (int v = 0; v < views; ++v) {
            images[v] = malloc((size_t)SYNTH_WIDTH * SYNTH_HEIGHT);
            assert_non_null(images[v]);
            const double pose[6] = {poses[v][0] * DEG, poses[v][1] * DEG, poses[v][2] * DEG,
                                    poses[v][3],       poses[v][4],       poses[v][5]};
            if (!render(ray_map, pose, images[v]))
                fail_msg("pose %d puts the target outside the image", v);
        }
        free(ray_map);
    } else {
        for (int v = 0; v < views; ++v)
            images[v] = g_images[v];
    }
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create(&calib), FLT_OK);
    assert_int_equal(flt_calib_set_frame_size(calib, SYNTH_WIDTH, SYNTH_HEIGHT), FLT_OK);
    double rms = -1, view_rms[views];
    assert_int_equal(flt_calib_estimate_intrinsics(calib, views, (const uint8_t *const *)images,
                                                   SYNTH_WIDTH, target, columns, rows, pitch_mm,
                                                   options, &rms, view_rms),
                     FLT_OK);
    assert_int_equal(flt_calib_get_intrinsics(calib, cam, FLT_CALIB_CAMERA_VALUES, dist,
                                              FLT_CALIB_DISTORTION_COEFFS),
                     FLT_OK);
    *found = 0;
    for (int v = 0; v < views; ++v)
        *found += !isnan(view_rms[v]);
    /* How far the estimated model undistorts from the true one where the
     * targets were seen (see chessboard_views_give_the_camera). */
    flt_calib *true_cam = NULL;
    assert_int_equal(flt_calib_create(&true_cam), FLT_OK);
    assert_int_equal(flt_calib_set_intrinsics(true_cam, synth_camera, FLT_CALIB_CAMERA_VALUES,
                                              synth_distortion, FLT_CALIB_DISTORTION_COEFFS),
                     FLT_OK);
    const double probe[8] = {1030 - 600, 1020 - 600, 1030 + 600, 1020 - 600,
                             1030 - 600, 1020 + 600, 1030 + 600, 1020 + 600};
    double est[8], truth[8];
    assert_int_equal(flt_calib_undistort(calib, 4, probe, est), FLT_OK);
    assert_int_equal(flt_calib_undistort(true_cam, 4, probe, truth), FLT_OK);
    *undistort_worst_px = 0;
    for (int i = 0; i < 4; ++i)
        *undistort_worst_px = fmax(*undistort_worst_px, hypot(est[2 * i] - truth[2 * i],
                                                              est[2 * i + 1] - truth[2 * i + 1]));
    flt_calib_destroy(true_cam);
    if (render)
        for (int v = 0; v < views; ++v)
            free(images[v]);
    flt_calib_destroy(calib);
    return rms;
}

static int render_circles(const double *ray_map, const double p[6], uint8_t *image) {
    /* 9 x 6 circles of 15 mm radius, 60 mm apart: the chessboard's extent. */
    return synth_render_circle_grid(ray_map, 9, 6, 60.0, 15.0, 0, p[0], p[1], p[2], p + 3, image);
}

static int render_asymmetric_circles(const double *ray_map, const double p[6], uint8_t *image) {
    /* OpenCV's 4 x 11 asymmetric pattern, 30 mm half-distance, 10 mm radius. */
    return synth_render_circle_grid(ray_map, 4, 11, 30.0, 10.0, 1, p[0], p[1], p[2], p + 3, image);
}

/* Circle grids, symmetric and asymmetric, through the same poses: every
 * view found, focal length within 0.5 % (the goal) and the
 * undistortion within the chessboard's 1.5 px. Blob centroids average
 * hundreds of pixels, so they are far less noisy than chessboard corners
 * (measured RMS 0.006 px, focal 0.016 %); the RMS bound, 0.05 px, leaves
 * room for the renderer's quantisation on other machines' libm. */
static void circle_grid_views_give_the_camera(void **state) {
    (void)state;
    const struct {
        const char *name;
        render_fn render;
        flt_calib_target target;
        uint32_t columns, rows;
        double pitch;
    } cases[] = {
        {"symmetric 9 x 6", render_circles, FLT_TARGET_CIRCLE_GRID, 9, 6, 60.0},
        {"asymmetric 4 x 11", render_asymmetric_circles, FLT_TARGET_ASYMMETRIC_CIRCLE_GRID, 4, 11,
         30.0},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        double cam[4], dist[8], worst_px;
        size_t found = 0;
        const double rms =
            estimate_from(cases[c].render, cases[c].target, cases[c].columns, cases[c].rows,
                          cases[c].pitch, NULL, cam, dist, &found, &worst_px);
        const double fx_err = cam[0] / synth_camera[0] - 1;
        const double fy_err = cam[1] / synth_camera[1] - 1;
        print_message("%s circles: found in %zu of %d views, rms %.4f px; fx %+.4f %%, "
                      "fy %+.4f %%, cx %.2f (true %.2f), cy %.2f (true %.2f), k1 %.4f; "
                      "undistortion within %.3f px\n",
                      cases[c].name, found, views, rms, 100 * fx_err, 100 * fy_err, cam[2],
                      synth_camera[2], cam[3], synth_camera[3], dist[0], worst_px);
        assert_int_equal(found, views);
        assert_true(fabs(fx_err) < 0.005);
        assert_true(fabs(fy_err) < 0.005);
        assert_true(rms < 0.05);
        assert_true(worst_px < 1.5);
    }
}

/* The rational model (k4..k6 free): the chessboard views, the same bounds
 * as the default model. Its coefficients are not unique (numerator and
 * denominator trade off: measured k1 -4.9, k4 -4.8 for a true k1 -0.08,
 * k4 0), so the model is judged by what it does: the focal length, the
 * reprojection RMS and the undistortion against the true camera. */
static void rational_distortion_gives_the_camera(void **state) {
    (void)state;
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_CALIB_RATIONAL_DISTORTION, 1), FLT_OK);
    double cam[4], dist[8], worst_px;
    size_t found = 0;
    const double rms = estimate_from(NULL, FLT_TARGET_CHESSBOARD, squares_x - 1, squares_y - 1,
                                     square_mm, o, cam, dist, &found, &worst_px);
    flt_options_destroy(o);
    const double fx_err = cam[0] / synth_camera[0] - 1;
    print_message("rational model: rms %.4f px; fx %+.4f %%; k1 %.4f k2 %.4f k3 %.4f "
                  "k4 %.4f k5 %.4f k6 %.4f; undistortion within %.3f px\n",
                  rms, 100 * fx_err, dist[0], dist[1], dist[4], dist[5], dist[6], dist[7],
                  worst_px);
    assert_int_equal(found, views);
    assert_true(fabs(fx_err) < 0.005);
    assert_true(rms < 0.1);
    assert_true(worst_px < 1.5);
}

/* Views without a target are reported as NaN and skipped; fewer than 3
 * usable views fail and leave the model without intrinsics. */
static void views_without_target_are_skipped(void **state) {
    (void)state;
    uint8_t *blank = calloc((size_t)SYNTH_WIDTH * SYNTH_HEIGHT, 1);
    const uint8_t *images[4] = {g_images[0], blank, g_images[1], blank};
    double view_rms[4];
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create(&calib), FLT_OK);
    assert_int_equal(flt_calib_set_frame_size(calib, SYNTH_WIDTH, SYNTH_HEIGHT), FLT_OK);
    assert_int_equal(flt_calib_estimate_intrinsics(calib, 4, images, SYNTH_WIDTH,
                                                   FLT_TARGET_CHESSBOARD, squares_x - 1,
                                                   squares_y - 1, square_mm, NULL, NULL, view_rms),
                     FLT_ERR_NUMERIC);
    assert_non_null(strstr(flt_last_error_message(), "found in 2 of 4 views"));
    assert_int_equal(flt_calib_get_intrinsics(calib, NULL, 0, NULL, 0), FLT_ERR_STATE);
    /* bad arguments are named */
    assert_int_equal(flt_calib_estimate_intrinsics(calib, 4, images, 100, FLT_TARGET_CHESSBOARD, 9,
                                                   6, 60.0, NULL, NULL, NULL),
                     FLT_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(flt_last_error_message(), "'stride' = 100"));
    flt_calib_destroy(calib);
    free(blank);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(chessboard_views_give_the_camera),
        cmocka_unit_test(views_without_target_are_skipped),
        cmocka_unit_test(circle_grid_views_give_the_camera),
        cmocka_unit_test(rational_distortion_gives_the_camera),
    };
    return cmocka_run_group_tests(tests, render_views, free_views);
}
