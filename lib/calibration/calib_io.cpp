// SPDX-License-Identifier: Apache-2.0
// The calibration file: JSON text, version 1 (documented in calib.h), read
// by the library's strict JSON reader (core/json.hpp): the format is fixed,
// and every error names the field it concerns ("lasers[1].homography[4]").
// Numbers keep their text until a field reads them, so a NaN or a fraction
// is reported against the field, not as a syntax error.
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "calibration/calib_model.hpp"
#include "core/error.hpp"
#include "core/json.hpp"
#include "core/number_text.hpp"

namespace flt {
namespace {

// ------------------------------------------------------------------ writer

// The shortest text that reads back bit-identical, '.' whatever the locale.
void append_double(std::string &s, double v) {
    s += format_double(v);
}

void append_field(std::string &s, const char *indent, const char *name, double v,
                  bool last = false) {
    s += indent;
    s += '"';
    s += name;
    s += "\": ";
    append_double(s, v);
    s += last ? "\n" : ",\n";
}

// ------------------------------------------------------------------ reader
// lib/core's strict JSON reader (core/json.hpp). A calibration file holds
// 50 values; 256 bound the work a file of millions of tiny values
// could cost long before its 64 KiB limit.
constexpr std::size_t k_max_values = 256;

}  // namespace

std::string write_model(const calib_model &m) {
    static const char *const dist_names[FLT_CALIB_DISTORTION_COEFFS] = {"k1", "k2", "p1", "p2",
                                                                        "k3", "k4", "k5", "k6"};
    std::string s;
    s += "{\n";
    s += "  \"format\": \"flatline-calibration\",\n";
    s += "  \"version\": " + std::to_string(FLT_CALIB_FORMAT_VERSION) + ",\n";
    s += "  \"frame\": {\n";
    s += "    \"width\": " + std::to_string(m.width) + ",\n";
    s += "    \"height\": " + std::to_string(m.height) + "\n";
    s += "  },\n";
    s += "  \"camera\": {\n";
    append_field(s, "    ", "fx", m.camera.fx);
    append_field(s, "    ", "fy", m.camera.fy);
    append_field(s, "    ", "cx", m.camera.cx);
    append_field(s, "    ", "cy", m.camera.cy);
    s += "    \"distortion\": {\n";
    for (int k = 0; k < FLT_CALIB_DISTORTION_COEFFS; ++k)
        append_field(s, "      ", dist_names[k], m.camera.distortion[k],
                     k + 1 == FLT_CALIB_DISTORTION_COEFFS);
    s += "    }\n";
    s += "  },\n";
    s += "  \"lasers\": [\n";
    for (int l = 0; l < FLT_CALIB_LASERS; ++l) {
        s += "    {\n";
        append_field(s, "      ", "offset_mm", m.offset_mm[l]);
        s += "      \"homography\": [";
        for (int k = 0; k < 9; ++k) {
            s += k % 3 == 0 ? "\n        " : " ";
            append_double(s, m.h[l][k]);
            if (k < 8)
                s += ",";
        }
        s += "\n      ]\n";
        s += l + 1 == FLT_CALIB_LASERS ? "    }\n" : "    },\n";
    }
    s += "  ],\n";
    append_field(s, "  ", "encoder_mm_per_count", m.encoder_mm_per_count);
    s += "  \"fibers\": {\n";
    append_field(s, "    ", "first_x_mm", m.first_x_mm);
    append_field(s, "    ", "pitch_mm", m.pitch_mm);
    s += "    \"count\": " + std::to_string(m.fiber_count) + "\n";
    s += "  }\n";
    s += "}\n";
    return s;
}

calib_model read_model(const char *text, std::size_t length) {
    using json::expect_kind;
    using json::fields;
    using json::format_error;
    using json::integer;
    using json::node;
    using json::number;
    using json::positive;
    const node root = json::parse(text, length, "the calibration file", k_max_values);
    expect_kind(root, node::object, "(top level)");
    // The version decides what else must be there, so it is read first: a
    // newer file reports its version, not its new fields.
    const node *version = nullptr, *format = nullptr;
    for (const auto &m : root.members) {
        if (m.first == "version")
            version = &m.second;
        if (m.first == "format")
            format = &m.second;
    }
    if (!format)
        format_error("missing field 'format'");
    expect_kind(*format, node::string, "format");
    if (format->text != "flatline-calibration")
        format_error("field 'format' = \"" + format->text + "\" is not \"flatline-calibration\"");
    if (!version)
        format_error("missing field 'version'");
    const std::uint64_t v = integer(*version, "version", 0, 1e9);
    if (v != FLT_CALIB_FORMAT_VERSION)
        format_error("field 'version' = " + std::to_string(v) +
                     " is a version this library cannot read (it reads " +
                     std::to_string(FLT_CALIB_FORMAT_VERSION) + ")");

    const auto top = fields(
        root, "",
        {"format", "version", "frame", "camera", "lasers", "encoder_mm_per_count", "fibers"});
    calib_model m;

    const auto frame = fields(*top[2], "frame", {"width", "height"});
    m.width = std::uint32_t(integer(*frame[0], "frame.width", 1, FLT_CALIB_MAX_FRAME_SIDE));
    m.height = std::uint32_t(integer(*frame[1], "frame.height", 1, FLT_CALIB_MAX_FRAME_SIDE));
    m.has_frame = true;

    const auto cam = fields(*top[3], "camera", {"fx", "fy", "cx", "cy", "distortion"});
    m.camera.fx = positive(*cam[0], "camera.fx");
    m.camera.fy = positive(*cam[1], "camera.fy");
    m.camera.cx = number(*cam[2], "camera.cx");
    m.camera.cy = number(*cam[3], "camera.cy");
    const auto dist =
        fields(*cam[4], "camera.distortion", {"k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"});
    static const char *const dist_paths[FLT_CALIB_DISTORTION_COEFFS] = {
        "camera.distortion.k1", "camera.distortion.k2", "camera.distortion.p1",
        "camera.distortion.p2", "camera.distortion.k3", "camera.distortion.k4",
        "camera.distortion.k5", "camera.distortion.k6"};
    for (int k = 0; k < FLT_CALIB_DISTORTION_COEFFS; ++k)
        m.camera.distortion[k] = number(*dist[std::size_t(k)], dist_paths[k]);
    m.has_camera = true;

    const node &lasers = *top[4];
    expect_kind(lasers, node::array, "lasers");
    if (lasers.items.size() != FLT_CALIB_LASERS)
        format_error("field 'lasers' has " + std::to_string(lasers.items.size()) +
                     " entries; a sensor has " + std::to_string(FLT_CALIB_LASERS));
    for (int l = 0; l < FLT_CALIB_LASERS; ++l) {
        const std::string lp = "lasers[" + std::to_string(l) + "]";
        const auto laser = fields(lasers.items[std::size_t(l)], lp, {"offset_mm", "homography"});
        m.offset_mm[l] = number(*laser[0], lp + ".offset_mm");
        m.has_offset[l] = true;
        const node &h = *laser[1];
        expect_kind(h, node::array, lp + ".homography");
        if (h.items.size() != 9)
            format_error("field '" + lp + ".homography' has " + std::to_string(h.items.size()) +
                         " entries, not 9");
        for (int k = 0; k < 9; ++k)
            m.h[l][k] =
                number(h.items[std::size_t(k)], lp + ".homography[" + std::to_string(k) + "]");
        if (!homography_invertible(m.h[l]))
            format_error("field '" + lp + ".homography' is not invertible");
        homography_inverse(m.h[l], m.h_inv[l]);
        m.has_homography[l] = true;
    }
    if (m.offset_mm[0] == m.offset_mm[1])
        format_error("fields 'lasers[0].offset_mm' and 'lasers[1].offset_mm' are "
                     "equal; the lasers must be apart along travel");

    m.encoder_mm_per_count = number(*top[5], "encoder_mm_per_count");
    if (m.encoder_mm_per_count == 0)
        format_error("field 'encoder_mm_per_count' is 0");
    m.has_encoder = true;

    const auto fib = fields(*top[6], "fibers", {"first_x_mm", "pitch_mm", "count"});
    m.first_x_mm = number(*fib[0], "fibers.first_x_mm");
    m.pitch_mm = positive(*fib[1], "fibers.pitch_mm");
    m.fiber_count = std::size_t(integer(*fib[2], "fibers.count", 1, FLT_MAX_FIBERS));
    m.has_fibers = true;
    return m;
}

const char *missing_part(const calib_model &m) {
    if (!m.has_frame)
        return "the frame size (flt_calib_set_frame_size)";
    if (!m.has_camera)
        return "the intrinsics (flt_calib_set_intrinsics or _estimate_intrinsics)";
    if (!m.has_homography[0])
        return "laser 0's homography";
    if (!m.has_homography[1])
        return "laser 1's homography";
    if (!m.has_offset[0])
        return "laser 0's offset (flt_calib_set_laser_offset)";
    if (!m.has_offset[1])
        return "laser 1's offset (flt_calib_set_laser_offset)";
    if (m.offset_mm[0] == m.offset_mm[1])
        return "distinct laser offsets (both are equal)";
    if (!m.has_encoder)
        return "the encoder scale (flt_calib_set_encoder_scale)";
    if (!m.has_fibers)
        return "the fiber grid (flt_calib_set_fiber_grid)";
    return nullptr;
}

}  // namespace flt
