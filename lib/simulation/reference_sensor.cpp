// SPDX-License-Identifier: Apache-2.0
// flt_calib_create_reference(): the reference sensor (docs/sensor.md) as a
// finished calibration, built through the public calibration API only.
#include <cmath>

#include "core/error.hpp"
#include "flatline/calib.h"
#include "flatline/sim.h"

using namespace flt;

namespace {

constexpr double k_focal_px = 6.0 / 0.0055;       // f = 6 mm, 5.5 um pixels
constexpr double k_cx = 1030.25, k_cy = 1019.75;  // principal point, px
constexpr double k_camera_height_mm = 1140.0;     // above the strip
constexpr double k_offsets_mm[FLT_CALIB_LASERS] = {-50.0, 50.0};
constexpr std::uint32_t k_sensor_side = 2048;
// Barrel distortion of a 6 mm lens on an 11 mm sensor (about -10 % in the
// corners), the same as tests/c/calib_synth.c.
constexpr double k_distortion[FLT_CALIB_DISTORTION_COEFFS] = {-0.08,  0.012, 1.5e-4, -1.0e-4,
                                                              -0.002, 0,     0,      0};

void inverse3(const double m[9], double out[9]) {
    const double det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
                       m[2] * (m[3] * m[7] - m[4] * m[6]);
    out[0] = (m[4] * m[8] - m[5] * m[7]) / det;
    out[1] = (m[2] * m[7] - m[1] * m[8]) / det;
    out[2] = (m[1] * m[5] - m[2] * m[4]) / det;
    out[3] = (m[5] * m[6] - m[3] * m[8]) / det;
    out[4] = (m[0] * m[8] - m[2] * m[6]) / det;
    out[5] = (m[2] * m[3] - m[0] * m[5]) / det;
    out[6] = (m[3] * m[7] - m[4] * m[6]) / det;
    out[7] = (m[1] * m[6] - m[0] * m[7]) / det;
    out[8] = (m[0] * m[4] - m[1] * m[3]) / det;
}

struct calib_owner {
    flt_calib *calib = nullptr;
    ~calib_owner() { flt_calib_destroy(calib); }
};

void check(flt_status st) {
    if (st != FLT_OK)
        throw error(st, flt_last_error_message());
}

}  // namespace

extern "C" {

FLT_API flt_status FLT_CALL flt_calib_create_reference(uint32_t first_row, uint32_t rows,
                                                       double first_x_mm, double pitch_mm,
                                                       size_t fibers, flt_calib **out) {
    const char *fn = "flt_calib_create_reference";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        if (rows == 0 || first_row >= k_sensor_side || rows > k_sensor_side - first_row)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: arguments 'first_row' = %u, 'rows' = %u do not fit "
                        "the %u-row sensor",
                        fn, first_row, rows, k_sensor_side);
        if (!std::isfinite(first_x_mm))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'first_x_mm' = %g is not finite",
                        fn, first_x_mm);
        if (!(pitch_mm > 0) || !std::isfinite(pitch_mm))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'pitch_mm' = %g must be finite and > 0", fn, pitch_mm);
        if (fibers == 0)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'fibers' is 0", fn);
        calib_owner c;
        check(flt_calib_create(&c.calib));
        check(flt_calib_set_frame_size(c.calib, k_sensor_side, rows));
        // Reading out an ROI shifts the image rows, hence the principal point.
        const double cy = k_cy - double(first_row);
        const double camera[4] = {k_focal_px, k_focal_px, k_cx, cy};
        check(flt_calib_set_intrinsics(c.calib, camera, FLT_CALIB_CAMERA_VALUES, k_distortion,
                                       FLT_CALIB_DISTORTION_COEFFS));
        // Camera at (x, s, z) = (0, -h, h) looking at the origin at 45 deg:
        // X_c = x, Y_c = -(s + z)/sqrt2 (image down), Z_c = (s - z + 2h)/sqrt2.
        // On laser plane s = o a plane point (x, z, 1) maps to the camera ray
        // M (x, z, 1); the undistorted pixel is K M (x, z, 1), so the exact
        // image -> plane homography is (K M)^-1.
        const double r = 1.0 / std::sqrt(2.0), h = k_camera_height_mm;
        for (unsigned laser = 0; laser < FLT_CALIB_LASERS; ++laser) {
            const double o = k_offsets_mm[laser];
            const double m[9] = {1, 0, 0, 0, -r, -r * o, 0, -r, r * o + 2 * r * h};
            double g[9];
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    const double k_row[3] = {i == 0 ? k_focal_px : 0.0, i == 1 ? k_focal_px : 0.0,
                                             i == 0   ? k_cx
                                             : i == 1 ? cy
                                                      : 1.0};
                    g[3 * i + j] = k_row[0] * m[j] + k_row[1] * m[3 + j] + k_row[2] * m[6 + j];
                }
            double hom[9];
            inverse3(g, hom);
            check(flt_calib_set_homography(c.calib, laser, hom, FLT_CALIB_HOMOGRAPHY_ENTRIES));
            check(flt_calib_set_laser_offset(c.calib, laser, o));
        }
        check(flt_calib_set_encoder_scale(c.calib, 0.01));
        check(flt_calib_set_fiber_grid(c.calib, first_x_mm, pitch_mm, fibers));
        check(flt_calib_finish(c.calib));
        *out = c.calib;
        c.calib = nullptr;
        return FLT_OK;
    });
}

}  // extern "C"
