// SPDX-License-Identifier: Apache-2.0
// Feature access over a register port: register reads and writes with bit
// fields, byte order and range checks; the engine of this release (the
// simple node kinds with constant addresses, u3v/genicam.hpp); and the
// layer that puts the user's mapped registers in front of the engine.
#include "sources/features.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/error.hpp"
#include "sources/source.hpp"
#include "sources/u3v/genicam.hpp"
#include "sources/u3v/protocol.hpp"

namespace flt::sources {

using u3v::get_u32;
using u3v::get_u64;
using u3v::get_uint;
using u3v::put_u32;
using u3v::put_u64;
using u3v::put_uint;

namespace {

std::uint64_t read_bits(register_port &port, const register_view &r) {
    std::uint8_t b[8] = {0};
    port.read(r.address, b, r.length);
    if (!r.little_endian)
        std::reverse(b, b + r.length);
    std::uint64_t raw = get_uint(b, r.length);
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
        word = get_uint(b, r.length);
        const std::uint64_t mask = (width < 64 ? (std::uint64_t(1) << width) - 1 : ~0ull) << r.lsb;
        word = (word & ~mask) | ((raw << r.lsb) & mask);
    } else {
        word = raw;
    }
    put_uint(b, r.length, word);
    if (!r.little_endian)
        std::reverse(b, b + r.length);
    port.write(r.address, b, r.length);
}

}  // namespace

std::int64_t read_int(register_port &port, const register_view &r, const std::string &feature) {
    if (r.is_float)
        return std::int64_t(std::llround(read_float(port, r, feature)));
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
    if (r.length == 4) {
        float f;
        const std::uint32_t bits = get_u32(b);
        std::memcpy(&f, &bits, 4);
        return f;
    }
    double d;
    const std::uint64_t bits = get_u64(b);
    std::memcpy(&d, &bits, 8);
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
        put_u32(b, bits);
    } else {
        std::uint64_t bits;
        std::memcpy(&bits, &value, 8);
        put_u64(b, bits);
    }
    if (!r.little_endian)
        std::reverse(b, b + r.length);
    port.write(r.address, b, r.length);
}

// --- the engine of this release -----------------------------------------------

namespace {

// The simple node kinds with constant addresses, as u3v::genicam_map
// resolves them (IntReg, MaskedIntReg, Integer, Float, FloatReg,
// Enumeration, Command, Boolean); formulas and computed addresses fail
// with the node that stopped the resolution.
class simple_engine final : public feature_engine {
  public:
    simple_engine(const std::string &xml, register_port &port) : port_(port) { map_.parse(xml); }

    feature_kind kind_of(const std::string &feature) override {
        const u3v::feature_access a = map_.resolve(feature);
        const std::string &k = a.node ? a.node->kind : std::string();
        if (k == "Enumeration")
            return feature_kind::enumeration;
        if (k == "Command")
            return feature_kind::command;
        if (k == "Boolean")
            return feature_kind::boolean;
        if (k == "Float" || k == "FloatReg")
            return feature_kind::floating;
        if (k == "Integer" || k == "IntReg" || k == "MaskedIntReg")
            return feature_kind::integer;
        return feature_kind::other;
    }

    std::int64_t get_int(const std::string &feature) override {
        const u3v::feature_access a = map_.resolve(feature);
        if (a.kind == u3v::feature_access::constant)
            return a.constant_value;
        return read_int(port_, view_of(a), feature);
    }

    void set_int(const std::string &feature, std::int64_t value) override {
        const u3v::feature_access a = map_.resolve(feature);
        if (a.kind == u3v::feature_access::constant)
            raise(FLT_ERR_INVALID_ARGUMENT, "feature '%s' is a constant (%lld) and cannot be set",
                  feature.c_str(), (long long)a.constant_value);
        write_int(port_, view_of(a), feature, value);
    }

    double get_float(const std::string &feature) override {
        const u3v::feature_access a = map_.resolve(feature);
        if (a.kind == u3v::feature_access::constant)
            return a.constant_float;
        return read_float(port_, view_of(a), feature);
    }

    void set_float(const std::string &feature, double value) override {
        if (!std::isfinite(value))
            raise(FLT_ERR_INVALID_ARGUMENT, "feature '%s': value %g is not finite", feature.c_str(),
                  value);
        const u3v::feature_access a = map_.resolve(feature);
        if (a.kind == u3v::feature_access::constant)
            raise(FLT_ERR_INVALID_ARGUMENT, "feature '%s' is a constant and cannot be set",
                  feature.c_str());
        write_float(port_, view_of(a), feature, value);
    }

    void set_enum(const std::string &feature, const std::string &entry) override {
        const u3v::feature_access a = map_.resolve(feature);
        const u3v::genicam_node *n = a.node;
        if (!n || n->kind != "Enumeration")
            raise(FLT_ERR_INVALID_ARGUMENT,
                  "feature '%s' is not an XML Enumeration; set its integer value with "
                  "flt_source_set_int()",
                  feature.c_str());
        for (const auto &e : n->entries)
            if (e.first == entry)
                return set_int(feature, e.second);
        std::string names;
        for (const auto &e : n->entries)
            names += (names.empty() ? "" : ", ") + e.first;
        raise(FLT_ERR_NOT_FOUND, "feature '%s' has no entry '%.64s' (entries: %.200s)",
              feature.c_str(), entry.c_str(), names.c_str());
    }

    void execute(const std::string &feature) override {
        const u3v::feature_access a = map_.resolve(feature);
        if (!a.node || a.node->kind != "Command")
            raise(FLT_ERR_INVALID_ARGUMENT, "feature '%s' is a %s, not a Command", feature.c_str(),
                  a.node ? a.node->kind.c_str() : "constant");
        const std::int64_t value = a.node->p_command_value.empty()
                                       ? a.node->command_value
                                       : get_int(a.node->p_command_value);
        set_int(feature, value);
    }

  private:
    static register_view view_of(const u3v::feature_access &a) {
        register_view r;
        r.address = a.address;
        r.length = a.length;
        r.little_endian = a.little_endian;
        r.is_signed = a.is_signed;
        r.is_float = a.kind == u3v::feature_access::float_register;
        r.lsb = a.lsb;
        r.msb = a.msb;
        return r;
    }

    register_port &port_;
    u3v::genicam_map map_;
};

}  // namespace

std::unique_ptr<feature_engine> make_feature_engine(const std::string &xml, register_port &port) {
    return std::make_unique<simple_engine>(xml, port);
}

// --- the layer -----------------------------------------------------------------

const register_view *feature_layer::mapped(const std::string &feature) const {
    auto it = mapped_.find(feature);
    return it == mapped_.end() ? nullptr : &it->second;
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
    if (const register_view *r = mapped(feature))
        return write_int(port_, *r, feature, value);
    engine_->set_int(feature, value);
}

double feature_layer::get_float(const std::string &feature) {
    if (const register_view *r = mapped(feature))
        return read_float(port_, *r, feature);
    return engine_->get_float(feature);
}

void feature_layer::set_float(const std::string &feature, double value) {
    if (const register_view *r = mapped(feature))
        return write_float(port_, *r, feature, value);
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
    if (const register_view *r = mapped(feature))
        return write_int(port_, *r, feature, 1);
    engine_->execute(feature);
}

void feature_layer::map_feature(const std::string &feature, std::uint64_t address,
                                std::uint32_t length, bool is_float) {
    register_view r;
    r.address = address;
    r.length = length;
    r.is_float = is_float;
    r.lsb = 0;
    r.msb = int(8 * length) - 1;
    mapped_[feature] = r;
}

}  // namespace flt::sources
