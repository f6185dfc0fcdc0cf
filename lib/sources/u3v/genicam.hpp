// SPDX-License-Identifier: Apache-2.0
// Internal: the GenICam XML of a camera - unzipping it, parsing it (expat)
// and resolving a feature name to a register for the simple node kinds.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace flt::u3v {

// The one file of a ZIP archive, inflated (stored or deflated entry; the
// CRC-32 is checked). Throws flt::error(FLT_ERR_FORMAT) naming the problem.
std::string unzip_single(const std::uint8_t *zip, std::size_t bytes);

// One XML node, with the properties the client understands.
struct genicam_node {
    std::string kind;  // element name: IntReg, Enumeration, Converter, ...
    std::string name;
    std::uint64_t address = 0;
    bool has_address = false;
    std::uint32_t length = 0;
    bool little_endian = true, is_signed = false;
    int lsb = -1, msb = -1;  // MaskedIntReg / StructEntry bits
    std::string p_value, p_command_value;
    bool has_value = false;
    std::int64_t value = 0;
    double float_value = 0.0;
    bool has_command_value = false;
    std::int64_t command_value = 1;
    std::int64_t on_value = 1, off_value = 0;
    std::vector<std::pair<std::string, std::int64_t>> entries;  // EnumEntry
    std::string formula;      // Converter / SwissKnife, for the message
    std::string unsupported;  // why this node cannot be resolved, if so
};

// How to reach a feature's value: a register, or a constant.
struct feature_access {
    enum kind_t { int_register, float_register, constant } kind = int_register;
    std::uint64_t address = 0;
    std::uint32_t length = 4;
    bool little_endian = true, is_signed = false;
    int lsb = 0, msb = 63;  // bits of the register holding the value
    std::int64_t constant_value = 0;
    double constant_float = 0.0;
    // Enumeration entries, Command value, Boolean on/off
    const genicam_node *node = nullptr;
};

class genicam_map {
  public:
    // Throws flt::error(FLT_ERR_FORMAT) with expat's message and line.
    void parse(const std::string &xml);
    const genicam_node *find(const std::string &name) const;
    std::size_t size() const { return nodes_.size(); }
    // Resolves `feature` to a register or constant, following pValue links.
    // Throws flt::error(FLT_ERR_NOT_FOUND) naming the feature and the node
    // that stopped the resolution.
    feature_access resolve(const std::string &feature) const;

  private:
    std::map<std::string, genicam_node> nodes_;
};

}  // namespace flt::u3v
