// SPDX-License-Identifier: Apache-2.0
// Internal to the GenICam engine: one node of a description as parsed, and
// the map's state (node_map.cpp parses into it, evaluate.cpp reads it).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "sources/genicam/formula.hpp"
#include "sources/genicam/node_map.hpp"
#include "sources/genicam/port.hpp"

namespace flt::genicam {

enum class kind : std::uint8_t {
    category,
    integer,
    int_reg,
    masked_int_reg,  // also StructEntry
    float_node,
    float_reg,
    converter,
    int_converter,
    swiss_knife,
    int_swiss_knife,
    enumeration,
    boolean,
    command,
    string_node,
    string_reg,
    reg,
    port,
    struct_reg,  // a named StructReg: a container, no value
    other,       // a node kind nothing evaluates (ConfRom, TextDesc, Node, ...)
};

// A reference to another node by name (pValue, pAddress, pVariable, ...).
struct ref {
    std::string name;
    bool set() const { return !name.empty(); }
};

enum class declared_access : std::uint8_t { none, ro, wo, rw };
enum class cache_mode : std::uint8_t { write_through, write_around, no_cache };

// One term of a register's address; the address is their sum.
struct address_term {
    enum type_t : std::uint8_t { constant, node, index } type = constant;
    std::int64_t value = 0;  // constant; the Offset of a pIndex
    int inline_node = -1;    // an IntSwissKnife element inside the register
    ref target;              // pAddress, or the pIndex node
    bool has_offset = false;
    ref p_offset;  // pIndex's pOffset attribute
};

struct named_ref {
    std::string name;
    ref target;
};
struct named_text {
    std::string name, text;
};
// ValueIndexed / pValueIndexed of an Integer or Float with pIndex.
struct indexed_value {
    std::int64_t index = 0;
    std::string text;
    ref target;
};

struct enum_entry {
    std::string name, display_name, value_text;
    ref is_implemented, is_available, is_locked;
};

struct node {
    kind k = kind::other;
    std::string tag;  // element name, "StructEntry" for a StructReg's entry
    std::string name;
    std::string display_name, description, unit;
    std::string broken;  // why the node cannot be used, if it cannot
    declared_access access = declared_access::none, imposed = declared_access::none;
    ref is_implemented, is_available, is_locked;
    std::vector<ref> invalidators, selected, features, value_copies;

    // Value / pValue, selected by pIndex (ValueIndexed) for Integer/Float
    bool has_value = false;
    std::string value_text;
    ref p_value, p_index;
    std::vector<indexed_value> indexed;
    bool has_default = false;
    std::string default_text;
    ref p_default;

    bool has_min = false, has_max = false, has_inc = false;
    std::string min_text, max_text, inc_text;
    ref p_min, p_max, p_inc;

    // registers
    std::vector<address_term> address;
    bool has_length = false;
    std::string length_text;
    ref p_length, p_port;
    cache_mode cachable = cache_mode::write_through;
    bool polled = false;
    bool is_signed = false, big_endian = false;
    int lsb = -1, msb = -1;

    // formulas
    std::vector<named_ref> variables;
    std::vector<named_text> constants, expressions;
    std::string formula_text, formula_to_text, formula_from_text, slope;
    bool has_formula = false, has_formula_to = false, has_formula_from = false;
    std::shared_ptr<formula> f, f_to, f_from;  // parsed on first use
    std::map<std::string, std::shared_ptr<formula>> f_expressions;

    std::vector<enum_entry> entries;
    std::string on_text = "1", off_text = "0";
    bool has_command_value = false;
    std::string command_value_text;
    ref p_command_value;
    bool has_chunk_id = false, has_event_id = false;  // Port: data of frames / events

    // A Value-only node written by the host keeps the value here.
    bool local_set = false;
    number local;
    std::string local_string;
};

struct cache_entry {
    register_port *port = nullptr;
    std::vector<std::uint8_t> bytes;
};

// Bounded work on any description: the largest of 32 real ones (10+
// vendors) has about 4,000 nodes in 24,000 elements; a description beyond
// these caps is refused (FLT_ERR_FORMAT) while it is read, before its nodes
// cost more memory (a node is about 1.5 KB).
constexpr std::size_t k_max_nodes = 65536;
constexpr std::size_t k_max_elements = 1000000;

struct node_map::impl {
    std::vector<node> nodes;
    std::unordered_map<std::string, int> index;
    register_port *device = nullptr;
    std::unordered_map<std::string, register_port *> ports;
    bool caching = true;
    std::map<std::pair<int, std::uint64_t>, cache_entry> cache;  // (register node, address)
    std::vector<std::vector<int>> invalidated_by;  // node -> nodes naming it in pInvalidator
    std::vector<int> chain;                        // the nodes being evaluated, outermost first
    std::vector<std::pair<std::string, std::string>> root_attributes;  // RegisterDescription
    int expression_depth = 0;
    long steps = 0;  // node evaluations of the current call

    void parse(const std::string &xml);
};

}  // namespace flt::genicam
