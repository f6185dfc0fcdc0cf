// SPDX-License-Identifier: Apache-2.0
// Feature access over a register port: register reads and writes with bit
// fields, byte order and range checks (the registers a user maps by
// address); the GenICam engine (lib/sources/genicam/) behind the
// feature_engine interface; and the layer that puts the user's mapped
// registers in front of the engine.
#include "sources/camera/features.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/error.hpp"
#include "sources/source.hpp"
#include "sources/genicam/node_map.hpp"
#include "sources/genicam/text.hpp"
#include "sources/camera/byte_order.hpp"

namespace flt::sources {

namespace {

std::uint64_t read_bits(register_port &port, const register_view &r) {
    std::uint8_t b[8] = {0};
    port.read(r.address, b, r.length);
    if (!r.little_endian)
        std::reverse(b, b + r.length);
    std::uint64_t raw = get_le(b, r.length);
    const int width = r.msb - r.lsb + 1;
    raw >>= r.lsb;
    if (width < 64)
        raw &= (std::uint64_t(1) << width) - 1;
    return raw;
}

void write_bits(register_port &port, const register_view &r, std::uint64_t raw) {
    std::uint8_t b[8] = {0};
    const int width = r.msb - r.lsb + 1;
    const bool whole = r.lsb == 0 && width == int(8 * r.length);
    std::uint64_t word = 0;
    if (!whole) {
        // read-modify-write of a bit field
        port.read(r.address, b, r.length);
        if (!r.little_endian)
            std::reverse(b, b + r.length);
        word = get_le(b, r.length);
        const std::uint64_t mask = (width < 64 ? (std::uint64_t(1) << width) - 1 : ~0ull) << r.lsb;
        word = (word & ~mask) | ((raw << r.lsb) & mask);
    } else {
        word = raw;
    }
    put_le(b, r.length, word);
    if (!r.little_endian)
        std::reverse(b, b + r.length);
    port.write(r.address, b, r.length);
}

}  // namespace

std::int64_t read_int(register_port &port, const register_view &r, const std::string &feature) {
    if (r.is_float) {
        const double d = read_float(port, r, feature);
        if (std::fabs(d) >= 9.2e18)
            raise(FLT_ERR_NUMERIC, "feature '%s': %g does not fit a 64-bit integer",
                  feature.c_str(), d);
        return std::int64_t(std::llround(d));
    }
    std::uint64_t raw = read_bits(port, r);
    const int width = r.msb - r.lsb + 1;
    if (r.is_signed && width < 64 && (raw >> (width - 1)) & 1)
        raw |= ~0ull << width;
    return std::int64_t(raw);
}

void write_int(register_port &port, const register_view &r, const std::string &feature,
               std::int64_t value) {
    if (r.is_float)
        return write_float(port, r, feature, double(value));
    const int width = r.msb - r.lsb + 1;
    if (width < 64) {
        const std::int64_t lo = r.is_signed ? -(std::int64_t(1) << (width - 1)) : 0;
        const std::int64_t hi = r.is_signed ? (std::int64_t(1) << (width - 1)) - 1
                                            : std::int64_t((std::uint64_t(1) << width) - 1);
        if (value < lo || value > hi)
            raise(FLT_ERR_INVALID_ARGUMENT,
                  "feature '%s': value %lld does not fit its %d-bit register", feature.c_str(),
                  (long long)value, width);
    }
    write_bits(port, r, std::uint64_t(value));
}

double read_float(register_port &port, const register_view &r, const std::string &feature) {
    if (!r.is_float)
        return double(read_int(port, r, feature));
    std::uint8_t b[8] = {0};
    port.read(r.address, b, r.length);
    if (!r.little_endian)
        std::reverse(b, b + r.length);
    double d;
    if (r.length == 4) {
        float f;
        const std::uint32_t bits = get_le32(b);
        std::memcpy(&f, &bits, 4);
        d = f;
    } else {
        const std::uint64_t bits = get_le64(b);
        std::memcpy(&d, &bits, 8);
    }
    // NaN or an infinity in the camera's register is no value: refused,
    // never passed on as a number.
    if (!std::isfinite(d))
        raise(FLT_ERR_NUMERIC, "feature '%s': its register at 0x%llx holds %s, not a value",
              feature.c_str(), (unsigned long long)r.address, d != d ? "NaN" : "an infinity");
    return d;
}

void write_float(register_port &port, const register_view &r, const std::string &feature,
                 double value) {
    if (!std::isfinite(value))
        raise(FLT_ERR_INVALID_ARGUMENT, "feature '%s': value %g is not finite", feature.c_str(),
              value);
    if (!r.is_float) {
        if (std::fabs(value) > 9.0e18)
            raise(FLT_ERR_INVALID_ARGUMENT, "feature '%s': value %g is out of range",
                  feature.c_str(), value);
        return write_int(port, r, feature, std::llround(value));
    }
    std::uint8_t b[8] = {0};
    if (r.length == 4) {
        // Converting a double beyond float's range is undefined behaviour.
        if (std::fabs(value) > double(std::numeric_limits<float>::max()))
            raise(FLT_ERR_INVALID_ARGUMENT,
                  "feature '%s': value %g is out of the range of its 32-bit float register",
                  feature.c_str(), value);
        const float f = float(value);
        std::uint32_t bits;
        std::memcpy(&bits, &f, 4);
        put_le32(b, bits);
    } else {
        std::uint64_t bits;
        std::memcpy(&bits, &value, 8);
        put_le64(b, bits);
    }
    if (!r.little_endian)
        std::reverse(b, b + r.length);
    port.write(r.address, b, r.length);
}

// --- the engine ------------------------------------------------------------------

namespace {

// lib/sources/genicam/'s node map behind the feature_engine interface. A
// feature the engine refuses (the description is wrong or ambiguous there,
// or a formula fails) gets the way out named: a register by address.
class genicam_engine final : public feature_engine {
  public:
    genicam_engine(const std::string &xml, register_port &port) {
        map_.load(genicam::xml_document(xml));
        map_.bind(&port);
    }

    bool has(const std::string &feature) override { return map_.has(feature); }

    feature_kind kind_of(const std::string &feature) override {
        return hinted([&] {
            switch (map_.interface_of(feature)) {
                case genicam::interface_kind::integer:
                    return feature_kind::integer;
                case genicam::interface_kind::floating:
                    return feature_kind::floating;
                case genicam::interface_kind::enumeration:
                    return feature_kind::enumeration;
                case genicam::interface_kind::command:
                    return feature_kind::command;
                case genicam::interface_kind::boolean:
                    return feature_kind::boolean;
                default:
                    return feature_kind::other;
            }
        });
    }
    std::int64_t get_int(const std::string &feature) override {
        return hinted([&] { return map_.get_int(feature); });
    }
    void set_int(const std::string &feature, std::int64_t value) override {
        hinted([&] {
            map_.set_int(feature, value);
            return 0;
        });
    }
    double get_float(const std::string &feature) override {
        return hinted([&] { return map_.get_float(feature); });
    }
    void set_float(const std::string &feature, double value) override {
        hinted([&] {
            map_.set_float(feature, value);
            return 0;
        });
    }
    void set_enum(const std::string &feature, const std::string &entry) override {
        hinted([&] {
            map_.set_enum(feature, entry);
            return 0;
        });
    }
    void execute(const std::string &feature) override {
        hinted([&] {
            map_.execute(feature);
            return 0;
        });
    }

  private:
    // Every call reads the camera afresh: a camera changes registers on its
    // own (status, automatic exposure, what a selector shows), and a feature
    // call costs its GenCP transactions only when the user makes it. Within
    // one call the cache holds, so a formula reading a register twice, a
    // bound check and a read-modify-write read it once.
    template <class F> auto hinted(F &&call) -> decltype(call()) {
        map_.invalidate();
        try {
            return call();
        } catch (const error &e) {
            if (e.status != FLT_ERR_FORMAT && e.status != FLT_ERR_NUMERIC &&
                e.status != FLT_ERR_NOT_FOUND)
                throw;
            std::string message = e.what();
            if (message.find("memory image") == std::string::npos)
                message += "; flt_source_map_feature() gives a feature a register instead";
            throw error(e.status, message.c_str());
        }
    }

    genicam::node_map map_;
};

}  // namespace

std::unique_ptr<feature_engine> make_feature_engine(const std::string &xml, register_port &port) {
    return std::make_unique<genicam_engine>(xml, port);
}

// --- the layer -----------------------------------------------------------------

const register_view *feature_layer::mapped(const std::string &feature) const {
    auto it = mapped_.find(feature);
    return it == mapped_.end() ? nullptr : &it->second;
}

bool feature_layer::has(const std::string &feature) {
    return mapped(feature) || engine_->has(feature);
}

feature_kind feature_layer::kind_of(const std::string &feature) {
    if (const register_view *r = mapped(feature))
        return r->is_float ? feature_kind::floating : feature_kind::integer;
    return engine_->kind_of(feature);
}

std::int64_t feature_layer::get_int(const std::string &feature) {
    if (const register_view *r = mapped(feature))
        return read_int(port_, *r, feature);
    return engine_->get_int(feature);
}

void feature_layer::set_int(const std::string &feature, std::int64_t value) {
    if (const register_view *r = mapped(feature)) {
        write_int(port_, *r, feature, value);
        return;
    }
    engine_->set_int(feature, value);
}

double feature_layer::get_float(const std::string &feature) {
    if (const register_view *r = mapped(feature))
        return read_float(port_, *r, feature);
    return engine_->get_float(feature);
}

void feature_layer::set_float(const std::string &feature, double value) {
    if (const register_view *r = mapped(feature)) {
        write_float(port_, *r, feature, value);
        return;
    }
    engine_->set_float(feature, value);
}

void feature_layer::set_enum(const std::string &feature, const std::string &entry) {
    if (mapped(feature))
        raise(FLT_ERR_INVALID_ARGUMENT,
              "feature '%s' is not an XML Enumeration; set its integer value with "
              "flt_source_set_int()",
              feature.c_str());
    engine_->set_enum(feature, entry);
}

void feature_layer::execute(const std::string &feature) {
    if (const register_view *r = mapped(feature)) {
        write_int(port_, *r, feature, 1);
        return;
    }
    engine_->execute(feature);
}

void feature_layer::map_feature(const std::string &feature, std::uint64_t address,
                                std::uint32_t length, bool is_float) {
    register_view r;
    r.address = address;
    r.length = length;
    r.is_float = is_float;
    r.little_endian = !big_endian_;
    r.lsb = 0;
    r.msb = int(8 * length) - 1;
    mapped_[feature] = r;
}

}  // namespace flt::sources
