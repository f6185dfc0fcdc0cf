// SPDX-License-Identifier: Apache-2.0
// The calibration file: JSON text, version 1 (documented in calib.h).
//
// A small strict reader instead of a general JSON library: the format is
// fixed, and every error must name the field it concerns ("lasers[1].
// homography[4]"), which generic parsers do not do. Numbers keep their text
// until a field reads them, so a NaN or a fraction is reported against the
// field, not as a syntax error.
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

[[noreturn]] void format_error(const std::string &message) {
    throw error(FLT_ERR_FORMAT, message.c_str());
}

struct node {
    enum kind_t { number, string, word, object, array } kind = number;
    std::string text;                                   // number, string, word
    std::vector<std::pair<std::string, node>> members;  // object, in order
    std::vector<node> items;                            // array
    int line = 0;
};

const char *kind_name(node::kind_t k) {
    switch (k) {
        case node::number:
            return "a number";
        case node::string:
            return "a string";
        case node::word:
            return "a bare word";
        case node::object:
            return "an object";
        case node::array:
            return "an array";
    }
    return "?";
}

class parser {
  public:
    parser(const char *text, std::size_t length) : p_(text), end_(text + length) {}

    node parse_document() {
        skip_space();
        if (p_ == end_)
            format_error("the file is empty");
        node root = parse_value("(top level)", 0);
        skip_space();
        if (p_ != end_)
            format_error("line " + std::to_string(line_) +
                         ": unexpected text after the end of the calibration");
        return root;
    }

  private:
    const char *p_, *end_;
    int line_ = 1;

    void skip_space() {
        while (p_ != end_ && (*p_ == ' ' || *p_ == '\t' || *p_ == '\r' || *p_ == '\n')) {
            if (*p_ == '\n')
                ++line_;
            ++p_;
        }
    }

    [[noreturn]] void truncated(const std::string &path) const {
        format_error("the file ends early (truncated?) inside '" + path + "' at line " +
                     std::to_string(line_));
    }

    [[noreturn]] void unexpected(const std::string &path, const char *expected) {
        std::string found = p_ == end_ ? "end of file" : std::string("'") + *p_ + "'";
        format_error("line " + std::to_string(line_) + ": in '" + path + "' expected " + expected +
                     ", found " + found);
    }

    node parse_value(const std::string &path, int depth) {
        if (depth > 16)
            format_error("'" + path + "' is nested too deeply");
        skip_space();
        if (p_ == end_)
            truncated(path);
        node n;
        n.line = line_;
        const char c = *p_;
        if (c == '{') {
            n.kind = node::object;
            ++p_;
            skip_space();
            if (p_ == end_)
                truncated(path);
            if (*p_ == '}') {
                ++p_;
                return n;
            }
            for (;;) {
                skip_space();
                if (p_ == end_)
                    truncated(path);
                if (*p_ != '"')
                    unexpected(path, "a field name in quotes");
                std::string key = parse_string(path);
                skip_space();
                if (p_ == end_)
                    truncated(path);
                if (*p_ != ':')
                    unexpected(path, "':' after a field name");
                ++p_;
                std::string child;
                if (path != "(top level)") {
                    child = path;
                    child += '.';
                }
                child += key;
                node value = parse_value(child, depth + 1);
                n.members.emplace_back(std::move(key), std::move(value));
                skip_space();
                if (p_ == end_)
                    truncated(path);
                if (*p_ == ',') {
                    ++p_;
                    continue;
                }
                if (*p_ == '}') {
                    ++p_;
                    return n;
                }
                unexpected(path, "',' or '}'");
            }
        }
        if (c == '[') {
            n.kind = node::array;
            ++p_;
            skip_space();
            if (p_ == end_)
                truncated(path);
            if (*p_ == ']') {
                ++p_;
                return n;
            }
            for (;;) {
                n.items.push_back(
                    parse_value(path + "[" + std::to_string(n.items.size()) + "]", depth + 1));
                skip_space();
                if (p_ == end_)
                    truncated(path);
                if (*p_ == ',') {
                    ++p_;
                    continue;
                }
                if (*p_ == ']') {
                    ++p_;
                    return n;
                }
                unexpected(path, "',' or ']'");
            }
        }
        if (c == '"') {
            n.kind = node::string;
            n.text = parse_string(path);
            return n;
        }
        // A number or a bare word (true, null, nan, inf, ...): the token runs
        // to the next delimiter; the field that reads it judges it.
        const char *start = p_;
        while (p_ != end_ && !std::strchr(" \t\r\n,]}:", *p_))
            ++p_;
        if (p_ == start)
            unexpected(path, "a value");
        n.text.assign(start, p_);
        n.kind = is_json_number(n.text) ? node::number : node::word;
        // A number cut off by the end of the file looks complete; the
        // enclosing object's missing '}' reports the truncation.
        return n;
    }

    std::string parse_string(const std::string &path) {
        ++p_;  // opening quote
        std::string s;
        while (p_ != end_ && *p_ != '"') {
            if (*p_ == '\n')
                format_error("line " + std::to_string(line_) + ": a string in '" + path +
                             "' runs past the end of the line");
            if (*p_ == '\\')
                format_error("line " + std::to_string(line_) +
                             ": escapes are not used in a "
                             "calibration file ('" +
                             path + "')");
            s += *p_++;
        }
        if (p_ == end_)
            truncated(path);
        ++p_;  // closing quote
        return s;
    }

    static bool is_json_number(const std::string &t) {
        std::size_t i = 0, n = t.size();
        auto digits = [&] {
            std::size_t b = i;
            while (i < n && t[i] >= '0' && t[i] <= '9')
                ++i;
            return i > b;
        };
        if (i < n && t[i] == '-')
            ++i;
        if (!digits())
            return false;
        if (i < n && t[i] == '.') {
            ++i;
            if (!digits())
                return false;
        }
        if (i < n && (t[i] == 'e' || t[i] == 'E')) {
            ++i;
            if (i < n && (t[i] == '+' || t[i] == '-'))
                ++i;
            if (!digits())
                return false;
        }
        return i == n;
    }
};

// ------------------------------------------------------------------ schema

std::string join(const std::string &path, const char *key) {
    return path.empty() ? std::string(key) : path + "." + key;
}

void expect_kind(const node &n, node::kind_t kind, const std::string &path) {
    if (n.kind == kind)
        return;
    format_error("field '" + path + "' (line " + std::to_string(n.line) + ") must be " +
                 kind_name(kind) + ", found " + kind_name(n.kind) +
                 (n.kind == node::word ? " '" + n.text + "'" : std::string()));
}

// Checks that obj has exactly the fields `names`, each once; returns them in
// that order.
std::vector<const node *> fields(const node &obj, const std::string &path,
                                 std::initializer_list<const char *> names) {
    expect_kind(obj, node::object, path.empty() ? "(top level)" : path);
    for (std::size_t i = 0; i < obj.members.size(); ++i) {
        const std::string &key = obj.members[i].first;
        bool known = false;
        for (const char *name : names)
            known |= key == name;
        if (!known)
            format_error("unknown field '" + join(path, key.c_str()) + "' (line " +
                         std::to_string(obj.members[i].second.line) + ")");
        for (std::size_t j = 0; j < i; ++j)
            if (obj.members[j].first == key)
                format_error("duplicate field '" + join(path, key.c_str()) + "' (line " +
                             std::to_string(obj.members[i].second.line) + ")");
    }
    std::vector<const node *> out;
    for (const char *name : names) {
        const node *found = nullptr;
        for (const auto &m : obj.members)
            if (m.first == name)
                found = &m.second;
        if (!found)
            format_error("missing field '" + join(path, name) + "'");
        out.push_back(found);
    }
    return out;
}

double number(const node &n, const std::string &path) {
    if (n.kind == node::word) {
        std::string lower;
        for (char c : n.text)
            lower += char(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
        if (lower.find("nan") != std::string::npos)
            format_error("field '" + path + "' is NaN (line " + std::to_string(n.line) + ")");
        if (lower.find("inf") != std::string::npos)
            format_error("field '" + path + "' is infinite (line " + std::to_string(n.line) + ")");
    }
    expect_kind(n, node::number, path);
    // parse_double reads the C syntax whatever LC_NUMERIC says (strtod
    // would stop at the '.' of "1090.9" under a decimal-comma locale). The
    // token is a JSON number (is_json_number), so it only fails on range.
    double v = 0;
    if (!parse_double(n.text, v))
        format_error("field '" + path + "' = " + n.text + " is outside the range of a double");
    return v;
}

double positive(const node &n, const std::string &path) {
    const double v = number(n, path);
    if (!(v > 0))
        format_error("field '" + path + "' = " + n.text + " must be > 0");
    return v;
}

std::uint64_t integer(const node &n, const std::string &path, double min_value, double max_value) {
    const double v = number(n, path);
    if (v != std::floor(v))
        format_error("field '" + path + "' = " + n.text + " must be a whole number");
    if (v < min_value || v > max_value) {
        char range[96];
        format_c(range, sizeof range, " is outside [%.17g, %.17g]", min_value, max_value);
        format_error("field '" + path + "' = " + n.text + range);
    }
    return std::uint64_t(v);
}

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
    const node root = parser(text, length).parse_document();
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
