// SPDX-License-Identifier: Apache-2.0
/*
 * The synthetic sensor of the calibration tests: the reference camera
 * (2048 x 2048 px, f = 6 mm, 5.5 um pixels, barrel distortion of a 6 mm lens)
 * mounted 1140 mm above the strip and 1140 mm behind the lasers along travel,
 * so it sees the laser lines at 45 degrees (the triangulation angle), and two
 * vertical laser planes at s = -50 mm and s = +50 mm (Delta-d = 100 mm).
 *
 * World frame: x across (mm), s along travel (mm), z up (mm), strip at z = 0.
 * The camera model here is written independently of the library's.
 */
#ifndef FLT_TEST_CALIB_SYNTH_H
#define FLT_TEST_CALIB_SYNTH_H

#include <stddef.h>
#include <stdint.h>

#define SYNTH_WIDTH            2048
#define SYNTH_HEIGHT           2048
#define SYNTH_FOCAL_PX         (6.0 / 0.0055) /* 1090.9 px */
#define SYNTH_CAMERA_HEIGHT_MM 1140.0

/* fx, fy, cx, cy (px) and k1 k2 p1 p2 k3 k4 k5 k6 of the reference camera. */
extern const double synth_camera[4];
extern const double synth_distortion[8];
/* Laser offsets along travel, mm: planes at s = offset. */
extern const double synth_laser_offset[2];

/* World (x, s, z) mm -> raw image (u, v) px through the reference camera.
 * Returns 0 if the point is behind the camera. */
int synth_project(double x, double s, double z, double *u, double *v);

/* A deterministic Gaussian with standard deviation 1 (xorshift + Box-Muller). */
double synth_gauss(uint64_t *state);
/* Uniform in [0, 1). */
double synth_uniform(uint64_t *state);

/* Renders a chessboard of squares_x x squares_y squares of side square_mm
 * (inner corners (squares_x - 1) x (squares_y - 1)), with a white margin of
 * one square, seen by the reference camera at pose (rotation rx, ry, rz in
 * radians about the board's own x, y, z axes applied in that order, then the
 * board's centre at t_mm in the camera frame, mm), into an 8-bit SYNTH_WIDTH x
 * SYNTH_HEIGHT image. Each pixel integrates 8 x 8 sub-samples so edges are
 * anti-aliased. ray_map: per pixel the undistorted normalised ray (x, y),
 * 2 doubles per pixel, from synth_ray_map(). Returns 0 if any corner of the
 * board falls outside the image. */
int synth_render_chessboard(const double *ray_map, int squares_x, int squares_y, double square_mm,
                            double rx, double ry, double rz, const double t_mm[3], uint8_t *image);

/* Renders a grid of columns x rows dark circles of radius_mm on white,
 * centres pitch_mm apart in OpenCV's layout (asymmetric: the rows alternate
 * by pitch_mm and a row's circles are 2 * pitch_mm apart), with white one
 * pitch around the outermost circles and a white margin of one pitch beyond,
 * at the pose of synth_render_chessboard (t_mm: the board's centre). Returns
 * 0 if the board falls outside the image. */
int synth_render_circle_grid(const double *ray_map, int columns, int rows, double pitch_mm,
                             double radius_mm, int asymmetric, double rx, double ry, double rz,
                             const double t_mm[3], uint8_t *image);

/* Fills ray_map (2 * SYNTH_WIDTH * SYNTH_HEIGHT doubles) with each pixel's
 * undistorted normalised coordinates, by inverting the distortion with
 * Newton's method (independent of the library). */
void synth_ray_map(double *ray_map);

/* cmocka 1.1.5 has no assert_double_equal: |a - b| <= tol, printing both.
 * Needs <math.h> and <cmocka.h> first. */
#define assert_near(a, b, tol)                                                 \
  do {                                                                         \
    const double a_ = (a), b_ = (b);                                           \
    if (!(fabs(a_ - b_) <= (tol)))                                             \
      fail_msg("%s = %.17g, expected %.17g +- %g", #a, a_, b_, (double)(tol)); \
  } while (0)

#endif
