// SPDX-License-Identifier: Apache-2.0
// The physically meaningful ranges of the calibration (flatline/calib.h,
// "Physically meaningful ranges"), checked in one place for the setters
// (calib.cpp, which name the argument) and the loader (which names the
// field of the file). Each check returns "" when the value is in range,
// else the end of a message: "'<name>' = <value> is outside [<lo>, <hi>] <unit>".
#include <cmath>
#include <cstdio>
#include <string>

#include "calibration/calib_model.hpp"

namespace flt {
namespace {

std::string outside(const char *name, double value, double lo, double hi, const char *unit) {
    char text[256];
    std::snprintf(text, sizeof text, "'%s' = %.15g is outside [%g, %g] %s", name, value, lo, hi,
                  unit);
    return text;
}

// "" when lo <= value <= hi (NaN is outside).
std::string in_range(const char *name, double value, double lo, double hi, const char *unit) {
    if (value >= lo && value <= hi)
        return std::string();
    return outside(name, value, lo, hi, unit);
}

}  // namespace

std::string frame_range_error(const char *width_name, const char *height_name, double width,
                              double height) {
    std::string e = in_range(width_name, width, 1, FLT_CALIB_MAX_FRAME_SIDE, "px");
    if (e.empty())
        e = in_range(height_name, height, 1, FLT_CALIB_MAX_FRAME_SIDE, "px");
    return e;
}

std::string camera_range_error(const camera_model &cam, const char *const names[12]) {
    const double values[12] = {cam.fx,
                               cam.fy,
                               cam.cx,
                               cam.cy,
                               cam.distortion[0],
                               cam.distortion[1],
                               cam.distortion[2],
                               cam.distortion[3],
                               cam.distortion[4],
                               cam.distortion[5],
                               cam.distortion[6],
                               cam.distortion[7]};
    for (int i = 0; i < 12; ++i) {
        std::string e;
        if (i < 2) {
            e = in_range(names[i], values[i], FLT_CALIB_MIN_FOCAL_PX, FLT_CALIB_MAX_FOCAL_PX, "px");
        } else if (i < 4) {
            e = in_range(names[i], values[i], -FLT_CALIB_MAX_PRINCIPAL_PX,
                         FLT_CALIB_MAX_PRINCIPAL_PX, "px");
        } else {
            // OpenCV order k1 k2 p1 p2 k3 k4 k5 k6: p1, p2 are tangential.
            const bool tangential = i == 6 || i == 7;
            const double limit = tangential ? FLT_CALIB_MAX_TANGENTIAL : FLT_CALIB_MAX_RADIAL;
            e = in_range(names[i], values[i], -limit, limit, "(dimensionless)");
        }
        if (!e.empty())
            return e;
    }
    return std::string();
}

std::string homography_range_error(const char *name, const double h[9]) {
    double largest = 0;
    for (int k = 0; k < 9; ++k) {
        if (!std::isfinite(h[k])) {
            char text[160];
            std::snprintf(text, sizeof text, "'%s[%d]' = %g is not finite", name, k, h[k]);
            return text;
        }
        largest = std::fmax(largest, std::fabs(h[k]));
    }
    if (!(largest >= FLT_CALIB_MIN_HOMOGRAPHY_SCALE && largest <= FLT_CALIB_MAX_HOMOGRAPHY_SCALE)) {
        char text[256];
        std::snprintf(text, sizeof text,
                      "'%s' has its largest |entry| = %g outside [%g, %g] (scale the "
                      "homography: it is defined up to scale)",
                      name, largest, FLT_CALIB_MIN_HOMOGRAPHY_SCALE,
                      FLT_CALIB_MAX_HOMOGRAPHY_SCALE);
        return text;
    }
    if (!homography_invertible(h))
        return std::string("'") + name + "' is not invertible (singular or nearly so)";
    return std::string();
}

std::string offset_range_error(const char *name, double offset_mm) {
    return in_range(name, offset_mm, -FLT_CALIB_MAX_OFFSET_MM, FLT_CALIB_MAX_OFFSET_MM, "mm");
}

std::string spacing_range_error(const char *names, double offset0, double offset1) {
    const double spacing = std::fabs(offset1 - offset0);
    if (spacing >= FLT_CALIB_MIN_LASER_SPACING_MM)
        return std::string();
    char text[256];
    std::snprintf(text, sizeof text,
                  "%s are %.15g and %.15g mm: the lasers are %g mm apart along travel, less "
                  "than %g mm",
                  names, offset0, offset1, spacing, FLT_CALIB_MIN_LASER_SPACING_MM);
    return text;
}

std::string encoder_range_error(const char *name, double mm_per_count) {
    const double magnitude = std::fabs(mm_per_count);
    if (magnitude >= FLT_CALIB_MIN_ENCODER_MM && magnitude <= FLT_CALIB_MAX_ENCODER_MM)
        return std::string();
    char text[256];
    std::snprintf(text, sizeof text, "'%s' = %.15g: its magnitude is outside [%g, %g] mm per count",
                  name, mm_per_count, FLT_CALIB_MIN_ENCODER_MM, FLT_CALIB_MAX_ENCODER_MM);
    return text;
}

std::string fiber_grid_range_error(const char *const names[3], double first_x_mm, double pitch_mm,
                                   double count) {
    std::string e = in_range(names[0], first_x_mm, -FLT_CALIB_MAX_X_MM, FLT_CALIB_MAX_X_MM, "mm");
    if (e.empty())
        e = in_range(names[1], pitch_mm, FLT_CALIB_MIN_PITCH_MM, FLT_CALIB_MAX_PITCH_MM, "mm");
    if (e.empty())
        e = in_range(names[2], count, 1, FLT_MAX_FIBERS, "(fibers)");
    if (!e.empty())
        return e;
    // Every fiber within the range: the last one is the farthest out.
    const double last = first_x_mm + (count - 1) * pitch_mm;
    if (last > FLT_CALIB_MAX_X_MM) {
        char text[320];
        std::snprintf(text, sizeof text,
                      "'%s' = %.15g, '%s' = %.15g and '%s' = %.15g put the last fiber at "
                      "x = %g mm, beyond %g mm",
                      names[0], first_x_mm, names[1], pitch_mm, names[2], count, last,
                      FLT_CALIB_MAX_X_MM);
        return text;
    }
    return std::string();
}

std::string model_range_error(const calib_model &m) {
    static const char *const camera_names[12] = {"camera.fx",
                                                 "camera.fy",
                                                 "camera.cx",
                                                 "camera.cy",
                                                 "camera.distortion.k1",
                                                 "camera.distortion.k2",
                                                 "camera.distortion.p1",
                                                 "camera.distortion.p2",
                                                 "camera.distortion.k3",
                                                 "camera.distortion.k4",
                                                 "camera.distortion.k5",
                                                 "camera.distortion.k6"};
    static const char *const homography_names[FLT_CALIB_LASERS] = {"lasers[0].homography",
                                                                   "lasers[1].homography"};
    static const char *const offset_names[FLT_CALIB_LASERS] = {"lasers[0].offset_mm",
                                                               "lasers[1].offset_mm"};
    static const char *const grid_names[3] = {"fibers.first_x_mm", "fibers.pitch_mm",
                                              "fibers.count"};
    std::string e = frame_range_error("frame.width", "frame.height", m.width, m.height);
    if (e.empty())
        e = camera_range_error(m.camera, camera_names);
    for (int l = 0; l < FLT_CALIB_LASERS && e.empty(); ++l) {
        e = homography_range_error(homography_names[l], m.h[l]);
        if (e.empty())
            e = offset_range_error(offset_names[l], m.offset_mm[l]);
    }
    if (e.empty())
        e = spacing_range_error("'lasers[0].offset_mm' and 'lasers[1].offset_mm'", m.offset_mm[0],
                                m.offset_mm[1]);
    if (e.empty())
        e = encoder_range_error("encoder_mm_per_count", m.encoder_mm_per_count);
    if (e.empty())
        e = fiber_grid_range_error(grid_names, m.first_x_mm, m.pitch_mm, double(m.fiber_count));
    return e;
}

}  // namespace flt
