// SPDX-License-Identifier: Apache-2.0
// The C entry points of the calibration model: argument checks, then the
// numerical pieces in camera.cpp, homography.cpp, intrinsics.cpp and
// calib_io.cpp.
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "calibration/calib_internal.hpp"
#include "calibration/calib_model.hpp"
#include "core/error.hpp"
#include "core/options.hpp"
#include "core/utf8_path.hpp"
#include "flatline/calib.h"

using namespace flt;

namespace {
constexpr std::uint32_t k_calib_magic = 0x464c5443u;  // "FLTC"
constexpr std::uint32_t k_max_frame_side = FLT_CALIB_MAX_FRAME_SIDE;

// The argument names of flt_calib_set_intrinsics, for the range checks.
const char *const k_intrinsics_names[12] = {
    "camera[0] (fx)",     "camera[1] (fy)",     "camera[2] (cx)",     "camera[3] (cy)",
    "distortion[0] (k1)", "distortion[1] (k2)", "distortion[2] (p1)", "distortion[3] (p2)",
    "distortion[4] (k3)", "distortion[5] (k4)", "distortion[6] (k5)", "distortion[7] (k6)"};
}  // namespace

struct flt_calib {
    std::uint32_t magic = k_calib_magic;
    bool finished = false;
    calib_model model;
};

namespace {

flt_status check_handle(const char *fn, const flt_calib *calib) {
    if (calib == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'calib' is NULL", fn);
    if (calib->magic != k_calib_magic)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'calib' is not a live flt_calib handle",
                    fn);
    return FLT_OK;
}

// For setters: a finished model is immutable (it may be shared by threads).
flt_status check_mutable(const char *fn, const flt_calib *calib) {
    if (flt_status st = check_handle(fn, calib))
        return st;
    if (calib->finished)
        return fail(FLT_ERR_STATE,
                    "%s: the calibration is finished and immutable; create a "
                    "new one to change it",
                    fn);
    return FLT_OK;
}

flt_status check_finished(const char *fn, const flt_calib *calib) {
    if (flt_status st = check_handle(fn, calib))
        return st;
    if (!calib->finished)
        return fail(FLT_ERR_STATE, "%s: the calibration is not finished (call flt_calib_finish)",
                    fn);
    return FLT_OK;
}

flt_status check_laser(const char *fn, unsigned laser) {
    if (laser >= FLT_CALIB_LASERS)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'laser' = %u is not 0 or 1", fn, laser);
    return FLT_OK;
}

// count x 2 doubles must be addressable.
flt_status check_points(const char *fn, const char *name, const double *pts, std::size_t count) {
    if (count > std::numeric_limits<std::size_t>::max() / (2 * sizeof(double)))
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'count' = %zu overflows the address space", fn, count);
    if (count > 0 && pts == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument '%s' is NULL", fn, name);
    return FLT_OK;
}

// The file's model, with every range of calib.h checked (FLT_ERR_FORMAT
// naming the field): a loaded model is as sane as a set one.
calib_model read_checked_model(const char *text, std::size_t length) {
    calib_model model = read_model(text, length);
    const std::string range = model_range_error(model);
    if (!range.empty())
        throw error(FLT_ERR_FORMAT, ("field " + range).c_str());
    return model;
}

// An array's size as the caller believes it: it must be the one the model has.
flt_status check_count(const char *fn, const char *name, std::size_t count, std::size_t expected) {
    if (count != expected)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument '%s' = %zu, the array has %zu values",
                    fn, name, count, expected);
    return FLT_OK;
}

flt_status check_finite(const char *fn, const char *name, double v) {
    if (!std::isfinite(v))
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument '%s' = %g is not finite", fn, name, v);
    return FLT_OK;
}

}  // namespace

namespace flt {

flt_calib *copy_calib(const flt_calib *calib) {
    return new flt_calib(*calib);
}

}  // namespace flt

extern "C" {

FLT_API flt_status FLT_CALL flt_calib_create(flt_calib **out) {
    const char *fn = "flt_calib_create";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        *out = new flt_calib;
        return FLT_OK;
    });
}

FLT_API void FLT_CALL flt_calib_destroy(flt_calib *calib) {
    guard_void([&] {
        if (calib && calib->magic == k_calib_magic) {
            calib->magic = 0;
            delete calib;
        }
    });
}

FLT_API flt_status FLT_CALL flt_calib_finish(flt_calib *calib) {
    const char *fn = "flt_calib_finish";
    return guard(fn, [&] {
        if (flt_status st = check_mutable(fn, calib))
            return st;
        if (const char *missing = missing_part(calib->model))
            return fail(FLT_ERR_STATE, "%s: the calibration lacks %s", fn, missing);
        const calib_model &m = calib->model;
        const std::string spacing =
            spacing_range_error("the laser offsets", m.offset_mm[0], m.offset_mm[1]);
        if (!spacing.empty())
            return fail(FLT_ERR_STATE, "%s: %s; set them further apart", fn, spacing.c_str());
        calib->finished = true;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_is_finished(const flt_calib *calib, int *out) {
    const char *fn = "flt_calib_is_finished";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, calib))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = calib->finished ? 1 : 0;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_set_frame_size(flt_calib *calib, uint32_t width,
                                                     uint32_t height) {
    const char *fn = "flt_calib_set_frame_size";
    return guard(fn, [&] {
        if (flt_status st = check_mutable(fn, calib))
            return st;
        if (width == 0 || width > k_max_frame_side)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'width' = %u is outside [1, %u]",
                        fn, width, k_max_frame_side);
        if (height == 0 || height > k_max_frame_side)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'height' = %u is outside [1, %u]",
                        fn, height, k_max_frame_side);
        calib->model.width = width;
        calib->model.height = height;
        calib->model.has_frame = true;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_get_frame_size(const flt_calib *calib, uint32_t *width_out,
                                                     uint32_t *height_out) {
    const char *fn = "flt_calib_get_frame_size";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, calib))
            return st;
        FLT_CHECK_NOT_NULL(fn, width_out);
        FLT_CHECK_NOT_NULL(fn, height_out);
        if (!calib->model.has_frame)
            return fail(FLT_ERR_STATE, "%s: the frame size is not set", fn);
        *width_out = calib->model.width;
        *height_out = calib->model.height;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_set_intrinsics(flt_calib *calib, const double *camera,
                                                     size_t camera_count, const double *distortion,
                                                     size_t distortion_count) {
    const char *fn = "flt_calib_set_intrinsics";
    return guard(fn, [&] {
        if (flt_status st = check_mutable(fn, calib))
            return st;
        FLT_CHECK_NOT_NULL(fn, camera);
        if (flt_status st = check_count(fn, "camera_count", camera_count, FLT_CALIB_CAMERA_VALUES))
            return st;
        if (distortion)
            if (flt_status st = check_count(fn, "distortion_count", distortion_count,
                                            FLT_CALIB_DISTORTION_COEFFS))
                return st;
        static const char *const names[4] = {"camera[0] (fx)", "camera[1] (fy)", "camera[2] (cx)",
                                             "camera[3] (cy)"};
        for (int k = 0; k < 4; ++k)
            if (flt_status st = check_finite(fn, names[k], camera[k]))
                return st;
        if (!(camera[0] > 0) || !(camera[1] > 0))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'camera' has fx = %g, fy = %g; both must be "
                        "> 0 px",
                        fn, camera[0], camera[1]);
        camera_model cam;
        cam.fx = camera[0], cam.fy = camera[1], cam.cx = camera[2], cam.cy = camera[3];
        if (distortion)
            for (int k = 0; k < FLT_CALIB_DISTORTION_COEFFS; ++k) {
                if (!std::isfinite(distortion[k]))
                    return fail(FLT_ERR_INVALID_ARGUMENT,
                                "%s: argument 'distortion[%d]' = %g is not finite", fn, k,
                                distortion[k]);
                cam.distortion[k] = distortion[k];
            }
        const std::string range = camera_range_error(cam, k_intrinsics_names);
        if (!range.empty())
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument %s", fn, range.c_str());
        calib->model.camera = cam;
        calib->model.has_camera = true;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_get_intrinsics(const flt_calib *calib, double *camera_out,
                                                     size_t camera_count, double *distortion_out,
                                                     size_t distortion_count) {
    const char *fn = "flt_calib_get_intrinsics";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, calib))
            return st;
        if (camera_out)
            if (flt_status st =
                    check_count(fn, "camera_count", camera_count, FLT_CALIB_CAMERA_VALUES))
                return st;
        if (distortion_out)
            if (flt_status st = check_count(fn, "distortion_count", distortion_count,
                                            FLT_CALIB_DISTORTION_COEFFS))
                return st;
        if (!calib->model.has_camera)
            return fail(FLT_ERR_STATE, "%s: the intrinsics are not set", fn);
        const camera_model &c = calib->model.camera;
        if (camera_out) {
            camera_out[0] = c.fx, camera_out[1] = c.fy;
            camera_out[2] = c.cx, camera_out[3] = c.cy;
        }
        if (distortion_out)
            std::memcpy(distortion_out, c.distortion, sizeof c.distortion);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_estimate_intrinsics(
    flt_calib *calib, size_t views, const uint8_t *const *images, size_t stride,
    flt_calib_target target, uint32_t columns, uint32_t rows, double pitch_mm,
    const flt_options *options, double *rms_px_out, double *view_rms_px_out) {
    const char *fn = "flt_calib_estimate_intrinsics";
    return guard(fn, [&] {
        if (flt_status st = check_mutable(fn, calib))
            return st;
        if (flt_status st = check_option_component(fn, options, {FLT_OPT_CALIB_RANSAC}))
            return st;
        const calib_model &m = calib->model;
        if (!m.has_frame)
            return fail(FLT_ERR_STATE, "%s: set the frame size (flt_calib_set_frame_size) first",
                        fn);
        if (views == 0)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'views' is 0", fn);
        FLT_CHECK_NOT_NULL(fn, images);
        for (std::size_t v = 0; v < views; ++v)
            if (images[v] == nullptr)
                return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'images[%zu]' is NULL", fn, v);
        if (stride < m.width)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'stride' = %zu is less than the frame width "
                        "%u",
                        fn, stride, m.width);
        if (stride > std::size_t(INT32_MAX) / m.height)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'stride' = %zu is too large", fn,
                        stride);
        const int raw_target = enum_arg(target);  // any int, from C
        if (raw_target != FLT_TARGET_CHESSBOARD && raw_target != FLT_TARGET_CIRCLE_GRID &&
            raw_target != FLT_TARGET_ASYMMETRIC_CIRCLE_GRID)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'target' = %d is not a flt_calib_target", fn, raw_target);
        if (columns < 3 || columns > 1000)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'columns' = %u is outside [3, 1000]", fn, columns);
        if (rows < 3 || rows > 1000)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'rows' = %u is outside [3, 1000]",
                        fn, rows);
        if (!std::isfinite(pitch_mm) || !(pitch_mm > 0))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'pitch_mm' = %g must be finite and > 0", fn, pitch_mm);
        const bool rational = option_value(options, FLT_OPT_CALIB_RATIONAL_DISTORTION) != 0;
        intrinsics_fit fit;
        try {
            fit = estimate_intrinsics(m.width, m.height, views, images, stride, target, columns,
                                      rows, pitch_mm, rational);
        } catch (const error &e) {
            return fail(e.status, "%s: %s", fn, e.what());
        }
        static const char *const names[12] = {"fx", "fy", "cx", "cy", "k1", "k2",
                                              "p1", "p2", "k3", "k4", "k5", "k6"};
        const std::string range = camera_range_error(fit.camera, names);
        if (!range.empty())
            return fail(FLT_ERR_NUMERIC,
                        "%s: the estimate failed: its %s (see calib.h for the ranges); the "
                        "intrinsics are unchanged",
                        fn, range.c_str());
        calib->model.camera = fit.camera;
        calib->model.has_camera = true;
        if (rms_px_out)
            *rms_px_out = fit.rms_px;
        if (view_rms_px_out)
            for (std::size_t v = 0; v < views; ++v)
                view_rms_px_out[v] = fit.view_rms_px[v];
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_set_homography(flt_calib *calib, unsigned laser,
                                                     const double *h, size_t h_count) {
    const char *fn = "flt_calib_set_homography";
    return guard(fn, [&] {
        if (flt_status st = check_mutable(fn, calib))
            return st;
        if (flt_status st = check_laser(fn, laser))
            return st;
        FLT_CHECK_NOT_NULL(fn, h);
        if (flt_status st = check_count(fn, "h_count", h_count, FLT_CALIB_HOMOGRAPHY_ENTRIES))
            return st;
        for (int k = 0; k < 9; ++k)
            if (!std::isfinite(h[k]))
                return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'h[%d]' = %g is not finite", fn,
                            k, h[k]);
        if (!homography_invertible(h))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'h' is not invertible (singular or nearly "
                        "so)",
                        fn);
        const std::string range = homography_range_error("h", h);
        if (!range.empty())
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument %s", fn, range.c_str());
        calib_model &m = calib->model;
        std::memcpy(m.h[laser], h, sizeof m.h[laser]);
        homography_inverse(m.h[laser], m.h_inv[laser]);
        m.has_homography[laser] = true;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_get_homography(const flt_calib *calib, unsigned laser,
                                                     double *h_out, size_t h_count) {
    const char *fn = "flt_calib_get_homography";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, calib))
            return st;
        if (flt_status st = check_laser(fn, laser))
            return st;
        FLT_CHECK_NOT_NULL(fn, h_out);
        if (flt_status st = check_count(fn, "h_count", h_count, FLT_CALIB_HOMOGRAPHY_ENTRIES))
            return st;
        if (!calib->model.has_homography[laser])
            return fail(FLT_ERR_STATE, "%s: laser %u's homography is not set", fn, laser);
        std::memcpy(h_out, calib->model.h[laser], sizeof calib->model.h[laser]);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_estimate_homography(
    flt_calib *calib, unsigned laser, size_t count, const double *image_px, const double *plane_mm,
    const flt_options *options, double *residual_px_out, double *residual_mm_out,
    uint8_t *inlier_out, double *rms_px_out, double *rms_mm_out) {
    const char *fn = "flt_calib_estimate_homography";
    return guard(fn, [&] {
        if (flt_status st = check_mutable(fn, calib))
            return st;
        if (flt_status st = check_option_component(fn, options, {FLT_OPT_CALIB_RANSAC}))
            return st;
        if (flt_status st = check_laser(fn, laser))
            return st;
        FLT_CHECK_NOT_NULL(fn, image_px);
        FLT_CHECK_NOT_NULL(fn, plane_mm);
        if (flt_status st = check_points(fn, "image_px", image_px, count))
            return st;
        if (count < 4)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'count' = %zu; a homography needs at least 4 "
                        "correspondences",
                        fn, count);
        calib_model &m = calib->model;
        if (!m.has_camera)
            return fail(FLT_ERR_STATE,
                        "%s: set or estimate the intrinsics first (the image points "
                        "are undistorted through them)",
                        fn);
        for (std::size_t i = 0; i < 2 * count; ++i) {
            if (!std::isfinite(image_px[i]))
                return fail(FLT_ERR_INVALID_ARGUMENT, "%s: image_px[%zu][%zu] = %g is not finite",
                            fn, i / 2, i % 2, image_px[i]);
            if (!std::isfinite(plane_mm[i]))
                return fail(FLT_ERR_INVALID_ARGUMENT, "%s: plane_mm[%zu][%zu] = %g is not finite",
                            fn, i / 2, i % 2, plane_mm[i]);
        }
        std::vector<double> undistorted(2 * count);
        for (std::size_t i = 0; i < count; ++i) {
            undistort_pixel(m.camera, image_px[2 * i], image_px[2 * i + 1], &undistorted[2 * i],
                            &undistorted[2 * i + 1]);
            if (!std::isfinite(undistorted[2 * i]))
                return fail(FLT_ERR_NUMERIC,
                            "%s: image_px[%zu] = (%g, %g) cannot be undistorted "
                            "with these intrinsics",
                            fn, i, image_px[2 * i], image_px[2 * i + 1]);
        }
        ransac_params ransac;
        ransac.enabled = option_value(options, FLT_OPT_CALIB_RANSAC) != 0;
        ransac.threshold_px = option_value(options, FLT_OPT_CALIB_RANSAC_THRESHOLD);
        ransac.iterations = long(option_value(options, FLT_OPT_CALIB_RANSAC_ITERATIONS));
        ransac.seed = std::uint32_t(option_value(options, FLT_OPT_CALIB_RANSAC_SEED));
        homography_fit fit;
        try {
            fit = fit_homography(count, undistorted.data(), plane_mm, ransac);
        } catch (const error &e) {
            return fail(e.status, "%s: laser %u: %s", fn, laser, e.what());
        }
        const std::string range = homography_range_error("homography", fit.h);
        if (!range.empty())
            return fail(FLT_ERR_NUMERIC, "%s: laser %u: the estimated %s; the model is unchanged",
                        fn, laser, range.c_str());
        std::memcpy(m.h[laser], fit.h, sizeof fit.h);
        homography_inverse(m.h[laser], m.h_inv[laser]);
        m.has_homography[laser] = true;
        for (std::size_t i = 0; i < count; ++i) {
            if (residual_px_out)
                residual_px_out[i] = fit.residual_px[i];
            if (residual_mm_out)
                residual_mm_out[i] = fit.residual_mm[i];
            if (inlier_out)
                inlier_out[i] = fit.inlier[i];
        }
        if (rms_px_out)
            *rms_px_out = fit.rms_px;
        if (rms_mm_out)
            *rms_mm_out = fit.rms_mm;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_set_laser_offset(flt_calib *calib, unsigned laser,
                                                       double offset_mm) {
    const char *fn = "flt_calib_set_laser_offset";
    return guard(fn, [&] {
        if (flt_status st = check_mutable(fn, calib))
            return st;
        if (flt_status st = check_laser(fn, laser))
            return st;
        if (flt_status st = check_finite(fn, "offset_mm", offset_mm))
            return st;
        const std::string range = offset_range_error("offset_mm", offset_mm);
        if (!range.empty())
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument %s", fn, range.c_str());
        calib->model.offset_mm[laser] = offset_mm;
        calib->model.has_offset[laser] = true;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_get_laser_offset(const flt_calib *calib, unsigned laser,
                                                       double *out) {
    const char *fn = "flt_calib_get_laser_offset";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, calib))
            return st;
        if (flt_status st = check_laser(fn, laser))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (!calib->model.has_offset[laser])
            return fail(FLT_ERR_STATE, "%s: laser %u's offset is not set", fn, laser);
        *out = calib->model.offset_mm[laser];
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_laser_spacing(const flt_calib *calib, double *out) {
    const char *fn = "flt_calib_laser_spacing";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, calib))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        const calib_model &m = calib->model;
        if (!m.has_offset[0] || !m.has_offset[1])
            return fail(FLT_ERR_STATE, "%s: both laser offsets must be set", fn);
        *out = m.offset_mm[1] - m.offset_mm[0];
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_set_encoder_scale(flt_calib *calib,
                                                        double encoder_mm_per_count) {
    const char *fn = "flt_calib_set_encoder_scale";
    return guard(fn, [&] {
        if (flt_status st = check_mutable(fn, calib))
            return st;
        if (flt_status st = check_finite(fn, "encoder_mm_per_count", encoder_mm_per_count))
            return st;
        if (encoder_mm_per_count == 0)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'encoder_mm_per_count' is 0", fn);
        const std::string range = encoder_range_error("encoder_mm_per_count", encoder_mm_per_count);
        if (!range.empty())
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument %s", fn, range.c_str());
        calib->model.encoder_mm_per_count = encoder_mm_per_count;
        calib->model.has_encoder = true;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_get_encoder_scale(const flt_calib *calib, double *out) {
    const char *fn = "flt_calib_get_encoder_scale";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, calib))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (!calib->model.has_encoder)
            return fail(FLT_ERR_STATE, "%s: the encoder scale is not set", fn);
        *out = calib->model.encoder_mm_per_count;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_set_fiber_grid(flt_calib *calib, double first_x_mm,
                                                     double pitch_mm, size_t count) {
    const char *fn = "flt_calib_set_fiber_grid";
    return guard(fn, [&] {
        if (flt_status st = check_mutable(fn, calib))
            return st;
        if (flt_status st = check_finite(fn, "first_x_mm", first_x_mm))
            return st;
        if (!std::isfinite(pitch_mm) || !(pitch_mm > 0))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'pitch_mm' = %g must be finite and > 0", fn, pitch_mm);
        if (count == 0 || count > FLT_MAX_FIBERS)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'count' = %zu is outside [1, %d]",
                        fn, count, FLT_MAX_FIBERS);
        static const char *const names[3] = {"first_x_mm", "pitch_mm", "count"};
        const std::string range =
            fiber_grid_range_error(names, first_x_mm, pitch_mm, double(count));
        if (!range.empty())
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument %s", fn, range.c_str());
        calib_model &m = calib->model;
        m.first_x_mm = first_x_mm, m.pitch_mm = pitch_mm, m.fiber_count = count;
        m.has_fibers = true;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_get_fiber_grid(const flt_calib *calib, double *first_x_mm_out,
                                                     double *pitch_mm_out, size_t *count_out) {
    const char *fn = "flt_calib_get_fiber_grid";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, calib))
            return st;
        FLT_CHECK_NOT_NULL(fn, first_x_mm_out);
        FLT_CHECK_NOT_NULL(fn, pitch_mm_out);
        FLT_CHECK_NOT_NULL(fn, count_out);
        const calib_model &m = calib->model;
        if (!m.has_fibers)
            return fail(FLT_ERR_STATE, "%s: the fiber grid is not set", fn);
        *first_x_mm_out = m.first_x_mm;
        *pitch_mm_out = m.pitch_mm;
        *count_out = m.fiber_count;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_image_to_plane(const flt_calib *calib, unsigned laser,
                                                     size_t count, const double *image_px,
                                                     double *plane_out) {
    const char *fn = "flt_calib_image_to_plane";
    return guard(fn, [&] {
        if (flt_status st = check_finished(fn, calib))
            return st;
        if (flt_status st = check_laser(fn, laser))
            return st;
        if (flt_status st = check_points(fn, "image_px", image_px, count))
            return st;
        if (flt_status st = check_points(fn, "plane_out", plane_out, count))
            return st;
        const calib_model &m = calib->model;
        for (std::size_t i = 0; i < count; ++i) {
            double u, v;
            undistort_pixel(m.camera, image_px[2 * i], image_px[2 * i + 1], &u, &v);
            // NaN propagates through the homography: invalid stays invalid.
            homography_apply(m.h[laser], u, v, &plane_out[2 * i], &plane_out[2 * i + 1]);
        }
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_plane_to_image(const flt_calib *calib, unsigned laser,
                                                     size_t count, const double *plane_mm,
                                                     double *image_out) {
    const char *fn = "flt_calib_plane_to_image";
    return guard(fn, [&] {
        if (flt_status st = check_finished(fn, calib))
            return st;
        if (flt_status st = check_laser(fn, laser))
            return st;
        if (flt_status st = check_points(fn, "plane_mm", plane_mm, count))
            return st;
        if (flt_status st = check_points(fn, "image_out", image_out, count))
            return st;
        const calib_model &m = calib->model;
        for (std::size_t i = 0; i < count; ++i) {
            double u, v;
            homography_apply(m.h_inv[laser], plane_mm[2 * i], plane_mm[2 * i + 1], &u, &v);
            distort_pixel(m.camera, u, v, &image_out[2 * i], &image_out[2 * i + 1]);
        }
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_undistort(const flt_calib *calib, size_t count,
                                                const double *image_px, double *undistorted_out) {
    const char *fn = "flt_calib_undistort";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, calib))
            return st;
        if (flt_status st = check_points(fn, "image_px", image_px, count))
            return st;
        if (flt_status st = check_points(fn, "undistorted_out", undistorted_out, count))
            return st;
        if (!calib->model.has_camera)
            return fail(FLT_ERR_STATE, "%s: the intrinsics are not set", fn);
        for (std::size_t i = 0; i < count; ++i)
            undistort_pixel(calib->model.camera, image_px[2 * i], image_px[2 * i + 1],
                            &undistorted_out[2 * i], &undistorted_out[2 * i + 1]);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_save_text(const flt_calib *calib, char *text_out,
                                                size_t capacity, size_t *length_out) {
    const char *fn = "flt_calib_save_text";
    return guard(fn, [&] {
        if (flt_status st = check_finished(fn, calib))
            return st;
        FLT_CHECK_NOT_NULL(fn, length_out);
        if (capacity > 0 && text_out == nullptr)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'text_out' is NULL but capacity = %zu", fn, capacity);
        const std::string text = write_model(calib->model);
        *length_out = text.size();
        if (capacity < text.size() + 1)
            return fail(FLT_ERR_BUFFER_FULL,
                        "%s: the text needs %zu bytes with its NUL; capacity = %zu", fn,
                        text.size() + 1, capacity);
        std::memcpy(text_out, text.c_str(), text.size() + 1);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_save(const flt_calib *calib, const char *path) {
    const char *fn = "flt_calib_save";
    return guard(fn, [&] {
        if (flt_status st = check_finished(fn, calib))
            return st;
        FLT_CHECK_NOT_NULL(fn, path);
        const std::string text = write_model(calib->model);
        // Written beside the target, then renamed over it: a reader never
        // sees half a file, and an existing file is replaced (on Windows
        // too, where rename refuses an existing target: replace_file).
        const std::string tmp = std::string(path) + ".tmp";
        std::FILE *f = open_file(tmp, "wb");
        if (!f)
            return fail(FLT_ERR_IO, "%s: cannot create '%.300s': %s", fn, tmp.c_str(),
                        std::strerror(errno));
        const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size();
        const bool closed = std::fclose(f) == 0;
        if (!written || !closed) {
            remove_file(tmp);
            return fail(FLT_ERR_IO, "%s: cannot write '%.300s'", fn, tmp.c_str());
        }
        if (const std::error_code err = replace_file(tmp, path)) {
            remove_file(tmp);
            return fail(FLT_ERR_IO, "%s: cannot rename onto '%.300s': %s", fn, path,
                        err.message().c_str());
        }
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_load_text(const char *text, size_t length, flt_calib **out) {
    const char *fn = "flt_calib_load_text";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        if (length > 0)
            FLT_CHECK_NOT_NULL(fn, text);
        // A calibration is about 1.5 kB; refuse anything absurd before parsing.
        if (length > FLT_CALIB_MAX_FILE_BYTES)
            return fail(FLT_ERR_FORMAT,
                        "%s: argument 'length' = %zu is more than %d bytes; not a calibration", fn,
                        length, FLT_CALIB_MAX_FILE_BYTES);
        // Parse into a local model; the handle exists only once it is whole.
        calib_model model;
        try {
            model = read_checked_model(text ? text : "", length);
        } catch (const error &e) {
            return fail(e.status, "%s: %s", fn, e.what());
        }
        auto handle = std::make_unique<flt_calib>();
        handle->model = model;
        handle->finished = true;
        *out = handle.release();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_calib_load(const char *path, flt_calib **out) {
    const char *fn = "flt_calib_load";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        FLT_CHECK_NOT_NULL(fn, path);
        std::FILE *f = open_file(path, "rb");
        if (!f)
            return fail(FLT_ERR_IO, "%s: cannot open '%.300s': %s", fn, path, std::strerror(errno));
        std::string text;
        char chunk[4096];
        std::size_t got;
        // A calibration is about 1.5 kB; refuse anything absurd before reading it.
        constexpr std::size_t k_max_bytes = FLT_CALIB_MAX_FILE_BYTES;
        while ((got = std::fread(chunk, 1, sizeof chunk, f)) > 0) {
            text.append(chunk, got);
            if (text.size() > k_max_bytes) {
                std::fclose(f);
                return fail(FLT_ERR_FORMAT,
                            "%s: '%.300s' is larger than %zu bytes; not a "
                            "calibration file",
                            fn, path, k_max_bytes);
            }
        }
        const bool read_error = std::ferror(f) != 0;
        std::fclose(f);
        if (read_error)
            return fail(FLT_ERR_IO, "%s: cannot read '%.300s'", fn, path);
        calib_model model;
        try {
            model = read_checked_model(text.data(), text.size());
        } catch (const error &e) {
            return fail(e.status, "%s: '%.200s': %s", fn, path, e.what());
        }
        auto handle = std::make_unique<flt_calib>();
        handle->model = model;
        handle->finished = true;
        *out = handle.release();
        return FLT_OK;
    });
}

}  // extern "C"
