// SPDX-License-Identifier: Apache-2.0
// Internal: the calibration model behind flt_calib, and the numerical pieces
// the C entry points (calib.cpp) and the file reader (calib_io.cpp) share.
//
// Plain arrays, not Eigen members: the model is copied by value when a file
// is loaded and must not depend on alignment (fixed-size Eigen members
// align to EIGEN_MAX_ALIGN_BYTES, which may differ between translation units
// built with different instruction sets, and a mismatch corrupts the heap).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "flatline/calib.h"

namespace flt {

// OpenCV's pinhole camera: fx, fy, cx, cy in px, distortion in OpenCV order
// k1 k2 p1 p2 k3 k4 k5 k6 (normalised image coordinates, dimensionless).
struct camera_model {
    double fx = 0, fy = 0, cx = 0, cy = 0;
    double distortion[FLT_CALIB_DISTORTION_COEFFS] = {0, 0, 0, 0, 0, 0, 0, 0};
};

// Applies lens distortion to an ideal pixel (u, v) -> raw pixel.
void distort_pixel(const camera_model &cam, double u, double v, double *u_out, double *v_out);
// Inverts distort_pixel by damped Newton iteration; NaN where it fails.
void undistort_pixel(const camera_model &cam, double u, double v, double *u_out, double *v_out);

struct calib_model {
    bool has_frame = false;
    std::uint32_t width = 0, height = 0;  // px

    bool has_camera = false;
    camera_model camera;

    // h: undistorted (u, v, 1) px -> (x, z, 1) mm; h_inv is its inverse,
    // computed once from h, so a loaded model maps exactly as the saved one.
    bool has_homography[FLT_CALIB_LASERS] = {false, false};
    double h[FLT_CALIB_LASERS][9] = {};
    double h_inv[FLT_CALIB_LASERS][9] = {};

    bool has_offset[FLT_CALIB_LASERS] = {false, false};
    double offset_mm[FLT_CALIB_LASERS] = {0, 0};

    bool has_encoder = false;
    double encoder_mm_per_count = 0;

    bool has_fibers = false;
    double first_x_mm = 0, pitch_mm = 0;
    std::size_t fiber_count = 0;
};

// Homography helpers (homography.cpp). All 3x3 matrices are row-major.
// True if h is finite and its reciprocal condition number is above the
// threshold below which we call it non-invertible.
bool homography_invertible(const double h[9]);
// inv = h^-1, scaled to unit Frobenius norm.
void homography_inverse(const double h[9], double inv[9]);
// Applies a homography to (a, b, 1); NaN when the result is at infinity.
void homography_apply(const double h[9], double a, double b, double *a_out, double *b_out);

struct homography_fit {
    double h[9];                      // undistorted px -> plane mm
    std::vector<double> residual_px;  // per correspondence
    std::vector<double> residual_mm;
    std::vector<std::uint8_t> inlier;
    double rms_px = 0, rms_mm = 0;  // over the inliers
};

struct ransac_params {
    bool enabled = false;
    double threshold_px = 1.0;
    long iterations = 1000;
    std::uint32_t seed = 1;
};

// Fits the homography from undistorted image points (n x 2, px) to plane
// points (n x 2, mm). Throws flt::error(FLT_ERR_NUMERIC) if degenerate.
homography_fit fit_homography(std::size_t n, const double *image_px, const double *plane_mm,
                              const ransac_params &ransac);

// Intrinsics from target images (intrinsics.cpp); throws flt::error.
struct intrinsics_fit {
    camera_model camera;
    double rms_px = 0;
    std::vector<double> view_rms_px;  // NaN where the target was not found
};
intrinsics_fit estimate_intrinsics(std::uint32_t width, std::uint32_t height, std::size_t views,
                                   const std::uint8_t *const *images, std::size_t stride,
                                   flt_calib_target target, std::uint32_t columns,
                                   std::uint32_t rows, double pitch_mm, bool rational);

// The file format (calib_io.cpp). write_model needs a complete model.
std::string write_model(const calib_model &model);
// Parses and validates; throws flt::error(FLT_ERR_FORMAT) naming the field.
calib_model read_model(const char *text, std::size_t length);

// Checks a model for completeness; returns nullptr or the missing part.
const char *missing_part(const calib_model &model);

// The ranges of calib.h ("Physically meaningful ranges"), calib_limits.cpp.
// Each returns "" when the values are in range, else the end of a message
// naming the value ("'fibers.pitch_mm' = 1e-300 is outside [0.001, 10000]
// mm"); the names are the caller's (an argument, or a field of the file).
std::string frame_range_error(const char *width_name, const char *height_name, double width,
                              double height);
// names: fx, fy, cx, cy, then the 8 distortion coefficients (OpenCV order).
std::string camera_range_error(const camera_model &cam, const char *const names[12]);
// Finite, largest |entry| within the scale range, invertible.
std::string homography_range_error(const char *name, const double h[9]);
std::string offset_range_error(const char *name, double offset_mm);
// The two offsets at least FLT_CALIB_MIN_LASER_SPACING_MM apart; `names`
// introduces them ("'lasers[0].offset_mm' and 'lasers[1].offset_mm'").
std::string spacing_range_error(const char *names, double offset0, double offset1);
std::string encoder_range_error(const char *name, double mm_per_count);
// names: first x, pitch, count.
std::string fiber_grid_range_error(const char *const names[3], double first_x_mm, double pitch_mm,
                                   double count);
// Every range of a whole model, named as the fields of the file; "" when
// the model is in range (calib.cpp, for the loader).
std::string model_range_error(const calib_model &model);

}  // namespace flt
