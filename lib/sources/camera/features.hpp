// SPDX-License-Identifier: Apache-2.0
// Internal: GenICam features by name over a camera's register space, for
// every transport. Three pieces:
//
//   register_port    the device's registers as GenICam's Port node sees
//                    them (flt::genicam::register_port); each transport's
//                    control channel implements it (u3v/control.hpp: GenCP
//                    READMEM/WRITEMEM; GigE Vision: GVCP READMEM/WRITEMEM).
//   feature_engine   the GenICam engine: parses the camera's description
//                    and evaluates features through a register_port.
//                    make_feature_engine() returns the engine of
//                    lib/sources/genicam/ (every node kind, formulas,
//                    selectors, access modes, the register cache).
//   feature_layer    what a camera's feature calls go through: registers
//                    the user mapped by address (flt_source_map_feature)
//                    first, then the engine.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include "sources/genicam/port.hpp"

namespace flt::sources {

// A device's register space. Both calls throw flt::error with the status
// and the reason (timeout, a device status, an unplug...).
using register_port = genicam::register_port;

enum class feature_kind { integer, floating, enumeration, command, boolean, other };

// A GenICam engine bound to one device's description and port. Every call
// throws flt::error naming the feature and the node chain: FLT_ERR_NOT_FOUND
// (no such feature or entry), FLT_ERR_FORMAT (the description is wrong or
// ambiguous there), FLT_ERR_NUMERIC (a formula fails for the registers'
// values), FLT_ERR_STATE (the access mode forbids it: not implemented, not
// available, locked, read-only), FLT_ERR_INVALID_ARGUMENT (a value outside
// the feature's bounds or a type it does not have), and whatever the port
// throws.
class feature_engine {
  public:
    virtual ~feature_engine() = default;
    virtual bool has(const std::string &feature) = 0;
    virtual feature_kind kind_of(const std::string &feature) = 0;
    virtual std::int64_t get_int(const std::string &feature) = 0;
    virtual void set_int(const std::string &feature, std::int64_t value) = 0;
    virtual double get_float(const std::string &feature) = 0;
    virtual void set_float(const std::string &feature, double value) = 0;
    virtual void set_enum(const std::string &feature, const std::string &entry) = 0;
    virtual void execute(const std::string &feature) = 0;
};

// The engine for the description `xml` (already unzipped), reading and
// writing through `port` (which must outlive it). Throws FLT_ERR_FORMAT
// for a description that cannot be parsed.
std::unique_ptr<feature_engine> make_feature_engine(const std::string &xml, register_port &port);

// A register holding a feature's value: `length` bytes at `address`, the
// value in bits lsb..msb, an IEEE float when is_float (4 or 8 bytes).
struct register_view {
    std::uint64_t address = 0;
    std::uint32_t length = 4;
    bool little_endian = true, is_signed = false, is_float = false;
    int lsb = 0, msb = 31;
};

// Integer and float access to a register_view (also what the engine of
// this release uses for the register nodes it resolves).
std::int64_t read_int(register_port &port, const register_view &r, const std::string &feature);
void write_int(register_port &port, const register_view &r, const std::string &feature,
               std::int64_t value);
double read_float(register_port &port, const register_view &r, const std::string &feature);
void write_float(register_port &port, const register_view &r, const std::string &feature,
                 double value);

class feature_layer {
  public:
    // `big_endian`: registers mapped by address hold big-endian values (GigE
    // Vision) instead of little-endian ones (USB3 Vision).
    feature_layer(register_port &port, std::unique_ptr<feature_engine> engine,
                  bool big_endian = false)
        : port_(port), engine_(std::move(engine)), big_endian_(big_endian) {}

    std::int64_t get_int(const std::string &feature);
    void set_int(const std::string &feature, std::int64_t value);
    double get_float(const std::string &feature);
    void set_float(const std::string &feature, double value);
    void set_enum(const std::string &feature, const std::string &entry);
    void execute(const std::string &feature);
    // `length` bytes (1, 2, 4, 8; 4 or 8 for a float) at `address`, in the
    // transport's byte order (see the constructor). A mapped command writes 1; a mapped enumeration
    // takes its integer value.
    void map_feature(const std::string &feature, std::uint64_t address, std::uint32_t length,
                     bool is_float);
    bool is_mapped(const std::string &feature) const { return mapped_.count(feature) != 0; }
    // The kind of an XML feature (a mapped one is an integer or a float).
    feature_kind kind_of(const std::string &feature);
    // Whether the camera's description defines `feature` (or it is mapped).
    bool has(const std::string &feature);

  private:
    const register_view *mapped(const std::string &feature) const;
    register_port &port_;
    std::unique_ptr<feature_engine> engine_;
    std::map<std::string, register_view> mapped_;
    bool big_endian_ = false;
};

}  // namespace flt::sources
