/*
 * Camera intrinsics from rendered chessboard images: 12 views of a
 * 10 x 7-square board (9 x 6 inner corners, 60 mm squares) rendered through
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
    {0, 0, 0, 0, 0, 1000},          {25, 0, 0, 0, -300, 1100},
    {-25, 0, 0, 0, 300, 1100},      {0, 25, 0, -350, 0, 1100},
    {0, -25, 0, 350, 0, 1100},      {20, 20, 10, -400, -350, 1200},
    {-20, 20, -10, -400, 350, 1200}, {20, -20, 5, 400, -350, 1200},
    {-20, -20, -5, 400, 350, 1200}, {35, 0, 15, 0, 0, 1300},
    {0, 35, -15, 0, 0, 1300},       {-30, -30, 0, 0, 0, 1400},
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
        if (!synth_render_chessboard(ray_map, squares_x, squares_y, square_mm,
                                     p[0] * DEG, p[1] * DEG, p[2] * DEG, p + 3,
                                     g_images[v]))
            fail_msg("pose %d puts the board outside the image", v);
    }
    free(ray_map);
    return 0;
}

static int free_views(void **state) {
    (void)state;
    for (int v = 0; v < views; ++v) free(g_images[v]);
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
                                                   squares_y - 1, square_mm, NULL, &rms,
                                                   view_rms),
                     FLT_OK);
    double cam[4], dist[8];
    assert_int_equal(flt_calib_get_intrinsics(calib, cam, dist), FLT_OK);
    const double fx_err = cam[0] / synth_camera[0] - 1;
    const double fy_err = cam[1] / synth_camera[1] - 1;
    print_message("rms %.4f px; fx %.3f (%+.4f %%), fy %.3f (%+.4f %%), cx %.2f "
                  "(true %.2f), cy %.2f (true %.2f), k1 %.4f k2 %.4f\n",
                  rms, cam[0], 100 * fx_err, cam[1], 100 * fy_err, cam[2],
                  synth_camera[2], cam[3], synth_camera[3], dist[0], dist[1]);
    size_t found = 0;
    double worst_view = 0;
    for (int v = 0; v < views; ++v) {
        print_message("  view %2d rms %.4f px\n", v, view_rms[v]);
        if (!isnan(view_rms[v])) {
            ++found;
            if (view_rms[v] > worst_view) worst_view = view_rms[v];
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
    assert_int_equal(flt_calib_set_intrinsics(true_cam, synth_camera, synth_distortion),
                     FLT_OK);
    const double probe[8] = {1030 - 600, 1020 - 600, 1030 + 600, 1020 - 600,
                             1030 - 600, 1020 + 600, 1030 + 600, 1020 + 600};
    double est[8], truth[8], worst_px = 0;
    assert_int_equal(flt_calib_undistort(calib, 4, probe, est), FLT_OK);
    assert_int_equal(flt_calib_undistort(true_cam, 4, probe, truth), FLT_OK);
    for (int i = 0; i < 4; ++i) {
        const double d = hypot(est[2 * i] - truth[2 * i], est[2 * i + 1] - truth[2 * i + 1]);
        if (d > worst_px) worst_px = d;
    }
    print_message("undistortion at 850 px radius: worst difference %.3f px\n", worst_px);
    assert_true(worst_px < 1.5);
    flt_calib_destroy(true_cam);
    flt_calib_destroy(calib);
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
                                                   squares_y - 1, square_mm, NULL, NULL,
                                                   view_rms),
                     FLT_ERR_NUMERIC);
    assert_non_null(strstr(flt_last_error_message(), "found in 2 of 4 views"));
    assert_int_equal(flt_calib_get_intrinsics(calib, NULL, NULL), FLT_ERR_STATE);
    /* bad arguments are named */
    assert_int_equal(flt_calib_estimate_intrinsics(calib, 4, images, 100,
                                                   FLT_TARGET_CHESSBOARD, 9, 6, 60.0,
                                                   NULL, NULL, NULL),
                     FLT_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(flt_last_error_message(), "'stride' = 100"));
    flt_calib_destroy(calib);
    free(blank);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(chessboard_views_give_the_camera),
        cmocka_unit_test(views_without_target_are_skipped),
    };
    return cmocka_run_group_tests(tests, render_views, free_views);
}
