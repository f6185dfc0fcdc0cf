// SPDX-License-Identifier: Apache-2.0
// Internal: the GenICam node map - a camera description parsed into nodes,
// evaluated on demand through register ports. Shared by the USB3 Vision
// client, the GigE Vision client and the offline view (flatline/genicam.h).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "sources/genicam/formula.hpp"
#include "sources/genicam/port.hpp"

namespace flt::genicam {

// What a feature offers (the GenICam interface of its node).
enum class interface_kind {
    integer,      // Integer, IntReg, MaskedIntReg, StructEntry, IntConverter, IntSwissKnife
    floating,     // Float, FloatReg, Converter, SwissKnife
    enumeration,  // Enumeration
    boolean,      // Boolean
    command,      // Command
    string,       // String, StringReg
    reg,          // Register
    category,     // Category
    port,         // Port
    none,         // a node kind nothing reads (ConfRom, TextDesc, ... of old schemas)
};

// Effective access (pIsImplemented, pIsAvailable, pIsLocked, AccessMode,
// ImposedAccessMode and the access of what the node reads, combined).
enum class access_mode { not_implemented, not_available, write_only, read_only, read_write };

const char *access_name(access_mode a);  // "NI", "NA", "WO", "RO", "RW"

// The register holding a feature's value, where there is one: the
// register node at the end of the feature's pValue chain (through
// Converters, not through SwissKnives, which combine several).
struct register_info {
    std::string node;  // the register node's name
    std::string port;  // the Port node's name (as pPort says)
    std::uint64_t address = 0;
    std::uint32_t length = 0;
    bool big_endian = false, is_signed = false;
    // Bits of the register's value holding the feature, 0 = least
    // significant whatever the XML's numbering; 0..8*length-1 for a whole
    // register.
    int lsb = 0, msb = 0;
};

// An Enumeration's entry with its availability now.
struct enum_entry_info {
    std::string name, display_name;
    std::int64_t value = 0;
    bool implemented = true, available = true;
};

class node_map {
  public:
    node_map();
    ~node_map();
    node_map(const node_map &) = delete;
    node_map &operator=(const node_map &) = delete;

    // Parses a description (the XML text; see text.hpp: xml_document for the
    // tolerated wrappers). Throws flt::error(FLT_ERR_FORMAT) with expat's
    // message and line for malformed XML, or when no node is defined. A node
    // that is wrong in itself (an Address that is no number, a formula that
    // does not parse) does not fail the load: using it fails, naming it.
    void load(const std::string &xml);

    // The port that every <Port> node without a ChunkID reaches (and a pPort
    // naming no node, as minimal files have); not owned, may be null.
    void bind(register_port *device);
    // A port for one <Port> node by name (a chunk port, say).
    void bind(const std::string &port_node, register_port *port);

    // Register caching (on by default): a cached register is read from its
    // port once until a write invalidates it: its own write, a write to an
    // overlapping register on the same port, a write through a node its
    // pInvalidator names (transitively), or a write to a selector. NoCache
    // and polled registers are always read.
    void set_caching(bool on);
    void invalidate();  // forgets every cached register

    // An attribute of the document's RegisterDescription element
    // ("VendorName", "ModelName", "SchemaMajorVersion", ...), "" if absent.
    std::string description_attribute(const std::string &name) const;
    // SchemaMajorVersion.SchemaMinorVersion.SchemaSubMinorVersion as one
    // number major * 10000 + minor * 100 + subminor (0 when absent, as in
    // schema 1.0 files). A GigE Vision client reads 4-byte registers of a
    // description older than 1.1 as big endian whatever they say (GenICam
    // 2.0, appendix 3); its port knows from this.
    int schema_version() const;

    // ---- the nodes ----------------------------------------------------------
    bool has(const std::string &name) const;
    std::size_t size() const;
    // Names of the features in document order: nodes of a kind with a value
    // or an action (not categories, ports, or nodes nothing reads).
    std::vector<std::string> feature_names() const;
    interface_kind interface_of(const std::string &feature) const;
    const std::string &kind_of(const std::string &feature) const;  // "IntReg", ...
    const std::string &display_name(const std::string &feature) const;
    const std::string &unit(const std::string &feature) const;
    const std::string &description(const std::string &feature) const;
    // The pFeature entries of a Category node, in document order, as
    // written (an entry may name a node the file lacks): how many, and
    // entry `index` (a string that lives as long as the map). Both throw
    // FLT_ERR_NOT_FOUND for a name that is no Category node.
    std::size_t category_size(const std::string &category) const;
    const std::string &category_feature(const std::string &category, std::size_t index) const;
    // The access mode as declared, without evaluating anything (ImposedAccessMode
    // and AccessMode along the pValue chain): what the file says.
    access_mode declared_access(const std::string &feature) const;

    // ---- evaluation (reads registers through the ports) ---------------------
    // Errors (flt::error) name the feature and the node chain, e.g.
    // "feature 'ExposureTime' (ExposureTime > ExposureTime_Val > Exp_Reg):
    // register 0x1234 (4 bytes): <the port's message>". Statuses:
    // NOT_FOUND no such feature or entry; FORMAT the description is wrong or
    // uses what this engine refuses to guess (named); NUMERIC a formula
    // fails for these values (division by zero, overflow, ...); STATE the
    // access mode forbids it; INVALID_ARGUMENT a value outside the feature's
    // range or a type the feature does not have; whatever the port threw.
    // `checked` = false reads a value whatever the access mode says (the
    // offline view shows values of unavailable features that way).
    access_mode access(const std::string &feature);
    // The node's own pIsImplemented / pIsAvailable / pIsLocked (true /
    // true / false where it has none); access() combines them with the rest.
    struct state {
        bool implemented = true, available = true, locked = false;
    };
    state flags(const std::string &feature);
    std::int64_t get_int(const std::string &feature, bool checked = true);
    double get_float(const std::string &feature, bool checked = true);
    bool get_bool(const std::string &feature, bool checked = true);
    std::string get_enum(const std::string &feature, bool checked = true);  // entry name
    std::string get_string(const std::string &feature, bool checked = true);
    std::vector<std::uint8_t> get_register(const std::string &feature, bool checked = true);
    // Integer/float bounds (Min/pMin ...; a register's own range; a
    // Converter's through its formula). Integers without a bound give
    // INT64_MIN / INT64_MAX, floats -DBL_MAX / DBL_MAX; inc 1 / 0.
    std::int64_t int_min(const std::string &feature);
    std::int64_t int_max(const std::string &feature);
    std::int64_t int_inc(const std::string &feature);
    double float_min(const std::string &feature);
    double float_max(const std::string &feature);
    std::vector<enum_entry_info> enum_entries(const std::string &feature);
    // The register at the end of the pValue chain, its address evaluated
    // now; false when the value comes from a formula of several nodes or a
    // constant.
    bool register_of(const std::string &feature, register_info &out);

    void set_int(const std::string &feature, std::int64_t value);
    void set_float(const std::string &feature, double value);
    void set_bool(const std::string &feature, bool value);
    void set_enum(const std::string &feature, const std::string &entry);
    void set_string(const std::string &feature, const std::string &value);
    void execute(const std::string &feature, bool checked = true);
    // A command is done when its register no longer reads its command value.
    bool is_done(const std::string &feature);

    struct impl;

  private:
    std::unique_ptr<impl> d_;
};

}  // namespace flt::genicam
