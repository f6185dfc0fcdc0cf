// SPDX-License-Identifier: Apache-2.0
// Reading a GenICam description (expat) into nodes: every element directly
// under RegisterDescription or a Group is a node; its child elements are
// its properties, except EnumEntry (an Enumeration's entry), StructEntry (a
// StructReg's bit field, which becomes a node with the StructReg's register
// properties under its own), an IntSwissKnife inside a register (a term of
// its address) and Extension (vendor data, skipped).
#include <expat.h>

#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "sources/genicam/nodes.hpp"
#include "sources/genicam/text.hpp"

namespace flt::genicam {

namespace {

struct kind_tag {
    const char *tag;
    kind k;
};
const kind_tag k_kinds[] = {
    {"Category", kind::category},
    {"Integer", kind::integer},
    {"IntReg", kind::int_reg},
    {"MaskedIntReg", kind::masked_int_reg},
    {"StructEntry", kind::masked_int_reg},
    {"Float", kind::float_node},
    {"FloatReg", kind::float_reg},
    {"Converter", kind::converter},
    {"IntConverter", kind::int_converter},
    {"SwissKnife", kind::swiss_knife},
    {"IntSwissKnife", kind::int_swiss_knife},
    {"Enumeration", kind::enumeration},
    {"Boolean", kind::boolean},
    {"Command", kind::command},
    {"String", kind::string_node},
    {"StringReg", kind::string_reg},
    {"Register", kind::reg},
    {"Port", kind::port},
    {"StructReg", kind::struct_reg},
};

kind kind_of_tag(const std::string &tag) {
    for (const kind_tag &k : k_kinds)
        if (tag == k.tag)
            return k.k;
    return kind::other;
}

bool is_register(kind k) {
    return k == kind::int_reg || k == kind::masked_int_reg || k == kind::float_reg ||
           k == kind::string_reg || k == kind::reg || k == kind::struct_reg;
}

// A child element of a node, recorded until the node ends (a StructReg's
// properties are applied to each of its entries).
struct property {
    std::string tag, text;
    std::vector<std::pair<std::string, std::string>> attributes;
    int inline_node = -1;  // an IntSwissKnife address term
    const std::string *attribute(const char *name) const {
        for (const auto &a : attributes)
            if (a.first == name)
                return &a.second;
        return nullptr;
    }
};

struct frame {
    enum type_t {
        root,
        group,
        node,
        struct_reg,
        struct_entry,
        inline_node,
        entry,
        prop,
        skip
    } type;
    int node_index = -1;
    property p;                        // prop: the element; entry: its Name
    std::vector<property> properties;  // of a node, entry, StructReg or StructEntry
    std::vector<std::pair<int, std::vector<property>>> struct_entries;
};

declared_access access_of(const std::string &text) {
    if (text == "RO")
        return declared_access::ro;
    if (text == "WO")
        return declared_access::wo;
    if (text == "RW")
        return declared_access::rw;
    return declared_access::none;
}

struct parser_state {
    node_map::impl &m;
    std::vector<frame> stack;
    std::string text;
    bool saw_root = false;
    XML_Parser parser = nullptr;
    std::size_t elements = 0;
    std::string refused;  // why parsing stopped early (a resource cap)

    // Stops the parser (the caller reports `why`).
    void refuse(const std::string &why) {
        if (refused.empty()) {
            refused = why;
            XML_StopParser(parser, XML_FALSE);
        }
    }

    int new_node(const std::string &tag, const char *name) {
        // One node past the cap is made (the caller needs its index) and
        // stops the parser: a description of exactly k_max_nodes loads.
        if (m.nodes.size() >= k_max_nodes)
            refuse("the GenICam XML defines more than " + std::to_string(k_max_nodes) +
                   " nodes (a real description has a few thousand)");
        node n;
        n.tag = tag;
        n.k = kind_of_tag(tag);
        if (name)
            n.name = name;
        const int index = int(m.nodes.size());
        if (name && *name) {
            auto it = m.index.find(n.name);
            if (it == m.index.end()) {
                m.index.emplace(n.name, index);
            } else {
                // Two nodes of one name: nobody can tell which one is meant.
                m.nodes[std::size_t(it->second)].broken =
                    "the description defines '" + n.name + "' twice";
            }
        }
        m.nodes.push_back(std::move(n));
        return index;
    }

    static void apply(node &n, const property &p);
    static void apply_entry(enum_entry &e, const property &p);

    void start(const char *tag, const char **attributes) {
        if (!refused.empty())
            return;
        if (++elements > k_max_elements) {
            refuse("the GenICam XML has more than " + std::to_string(k_max_elements) +
                   " elements (a real description has a few ten thousand)");
            return;
        }
        const std::string t = tag;
        const char *name = nullptr;
        for (int i = 0; attributes[i]; i += 2)
            if (std::strcmp(attributes[i], "Name") == 0)
                name = attributes[i + 1];
        frame f;
        if (stack.empty()) {
            saw_root = true;
            for (int i = 0; attributes[i]; i += 2)
                m.root_attributes.emplace_back(attributes[i], attributes[i + 1]);
            f.type = frame::root;
            stack.push_back(std::move(f));
            return;
        }
        const frame::type_t parent = stack.back().type;
        // The Extension branch below skips too, but only after the root/group
        // test, which must come first (bugprone-branch-clone is wrong here).
        // NOLINTNEXTLINE(bugprone-branch-clone)
        if (parent == frame::prop || parent == frame::skip) {
            f.type = frame::skip;
        } else if (parent == frame::root || parent == frame::group) {
            if (t == "Group") {
                f.type = frame::group;
            } else if (t == "StructReg") {
                f.type = frame::struct_reg;
                if (name && *name)
                    f.node_index = new_node(t, name);
            } else if (name) {
                f.type = frame::node;
                f.node_index = new_node(t, name);
            } else {
                f.type = frame::skip;
            }
        } else if (t == "Extension") {
            f.type = frame::skip;
        } else if (parent == frame::node && t == "EnumEntry" &&
                   m.nodes[std::size_t(stack.back().node_index)].k == kind::enumeration) {
            f.type = frame::entry;
            f.p.tag = name ? name : "";
        } else if (parent == frame::struct_reg && t == "StructEntry") {
            f.type = frame::struct_entry;
            f.node_index = new_node(t, name ? name : "");
        } else if (t == "IntSwissKnife" &&
                   (parent == frame::struct_reg || parent == frame::struct_entry ||
                    (parent == frame::node &&
                     is_register(m.nodes[std::size_t(stack.back().node_index)].k)))) {
            // An address term computed by a formula. It is a node of its own
            // (named if the file names it and the name is free).
            f.type = frame::inline_node;
            const bool free_name = name && *name && m.index.find(name) == m.index.end();
            f.node_index = new_node(t, free_name ? name : nullptr);
            if (!free_name)
                m.nodes[std::size_t(f.node_index)].name =
                    std::string("(address formula") + (name ? " " + std::string(name) : "") + ")";
        } else {
            f.type = frame::prop;
            f.p.tag = t;
            for (int i = 0; attributes[i]; i += 2)
                f.p.attributes.emplace_back(attributes[i], attributes[i + 1]);
            text.clear();
        }
        stack.push_back(std::move(f));
    }

    void end() {
        frame f = std::move(stack.back());
        stack.pop_back();
        switch (f.type) {
            case frame::prop:
                f.p.text = std::string(trim(text));
                text.clear();
                if (!stack.empty())
                    stack.back().properties.push_back(std::move(f.p));
                break;
            case frame::node:
            case frame::inline_node: {
                node &n = m.nodes[std::size_t(f.node_index)];
                for (const property &p : f.properties)
                    apply(n, p);
                if (f.type == frame::inline_node && !stack.empty()) {
                    property term;
                    term.tag = "(inline IntSwissKnife)";
                    term.inline_node = f.node_index;
                    stack.back().properties.push_back(std::move(term));
                }
                break;
            }
            case frame::entry: {
                if (stack.empty() || stack.back().node_index < 0)
                    break;
                enum_entry e;
                e.name = f.p.tag;
                for (const property &p : f.properties)
                    apply_entry(e, p);
                m.nodes[std::size_t(stack.back().node_index)].entries.push_back(std::move(e));
                break;
            }
            case frame::struct_entry:
                if (!stack.empty())
                    stack.back().struct_entries.emplace_back(f.node_index, std::move(f.properties));
                break;
            case frame::struct_reg:
                // Each entry: the StructReg's register properties, then its own.
                for (auto &entry : f.struct_entries) {
                    node &n = m.nodes[std::size_t(entry.first)];
                    for (const property &p : f.properties)
                        apply(n, p);
                    for (const property &p : entry.second)
                        apply(n, p);
                }
                if (f.node_index >= 0)
                    for (const property &p : f.properties)
                        apply(m.nodes[std::size_t(f.node_index)], p);
                break;
            default:
                break;
        }
    }
};

void parser_state::apply_entry(enum_entry &e, const property &p) {
    const std::string &t = p.tag;
    if (t == "Value")
        e.value_text = p.text;
    else if (t == "DisplayName")
        e.display_name = p.text;
    else if (t == "pIsImplemented")
        e.is_implemented.name = p.text;
    else if (t == "pIsAvailable")
        e.is_available.name = p.text;
    else if (t == "pIsLocked")
        e.is_locked.name = p.text;
}

void parser_state::apply(node &n, const property &p) {
    const std::string &t = p.tag;
    const std::string &v = p.text;
    auto bad = [&](const std::string &why) {
        if (n.broken.empty())
            n.broken = why;
    };
    if (p.inline_node >= 0) {
        address_term a;
        a.type = address_term::node;
        a.inline_node = p.inline_node;
        n.address.push_back(a);
    } else if (t == "DisplayName") {
        n.display_name = v;
    } else if (t == "Description" || (t == "ToolTip" && n.description.empty())) {
        n.description = v;
    } else if (t == "Unit") {
        n.unit = v;
    } else if (t == "pIsImplemented") {
        n.is_implemented.name = v;
    } else if (t == "pIsAvailable") {
        n.is_available.name = v;
    } else if (t == "pIsLocked") {
        n.is_locked.name = v;
    } else if (t == "AccessMode") {
        // Anything but RO, WO, RW (a file says "R") is read-only: the safe
        // reading, and the value itself does not depend on it.
        n.access = access_of(v);
        if (n.access == declared_access::none)
            n.access = declared_access::ro;
    } else if (t == "ImposedAccessMode") {
        n.imposed = access_of(v);
    } else if (t == "pInvalidator") {
        n.invalidators.push_back(ref{v});
    } else if (t == "pSelected") {
        n.selected.push_back(ref{v});
    } else if (t == "pFeature") {
        n.features.push_back(ref{v});
    } else if (t == "pValueCopy") {
        n.value_copies.push_back(ref{v});
    } else if (t == "Value") {
        n.has_value = true;
        n.value_text = v;
    } else if (t == "pValue") {
        n.p_value.name = v;
    } else if (t == "pIndex") {
        if (n.k == kind::integer || n.k == kind::float_node) {
            n.p_index.name = v;
        } else {
            address_term a;
            a.type = address_term::index;
            a.target.name = v;
            if (const std::string *offset = p.attribute("Offset")) {
                a.has_offset = true;
                if (!parse_int(*offset, a.value))
                    bad("pIndex Offset '" + *offset + "' is not a number");
            } else if (const std::string *p_offset = p.attribute("pOffset")) {
                a.has_offset = true;
                a.p_offset.name = *p_offset;
            }
            n.address.push_back(a);
        }
    } else if (t == "ValueIndexed" || t == "pValueIndexed") {
        indexed_value iv;
        const std::string *index = p.attribute("Index");
        if (!index || !parse_int(*index, iv.index))
            bad(t + " has no numeric Index attribute");
        if (t == "ValueIndexed")
            iv.text = v;
        else
            iv.target.name = v;
        n.indexed.push_back(iv);
    } else if (t == "ValueDefault") {
        n.has_default = true;
        n.default_text = v;
    } else if (t == "pValueDefault") {
        n.p_default.name = v;
    } else if (t == "Min") {
        n.has_min = true;
        n.min_text = v;
    } else if (t == "Max") {
        n.has_max = true;
        n.max_text = v;
    } else if (t == "Inc") {
        n.has_inc = true;
        n.inc_text = v;
    } else if (t == "pMin") {
        n.p_min.name = v;
    } else if (t == "pMax") {
        n.p_max.name = v;
    } else if (t == "pInc") {
        n.p_inc.name = v;
    } else if (t == "Address") {
        address_term a;
        if (!parse_int(v, a.value))
            bad("Address '" + v + "' is not a number");
        n.address.push_back(a);
    } else if (t == "pAddress") {
        address_term a;
        a.type = address_term::node;
        a.target.name = v;
        n.address.push_back(a);
    } else if (t == "Length") {
        n.has_length = true;
        n.length_text = v;
    } else if (t == "pLength") {
        n.p_length.name = v;
    } else if (t == "pPort") {
        n.p_port.name = v;
    } else if (t == "Cachable") {
        if (v == "NoCache")
            n.cachable = cache_mode::no_cache;
        else if (v == "WriteAround")
            n.cachable = cache_mode::write_around;
        else if (v == "WriteThrough")
            n.cachable = cache_mode::write_through;
        else
            bad("Cachable '" + v + "' is not NoCache, WriteThrough or WriteAround");
    } else if (t == "PollingTime") {
        n.polled = true;
    } else if (t == "Sign") {
        if (v == "Signed")
            n.is_signed = true;
        else if (v == "Unsigned")
            n.is_signed = false;
        else
            bad("Sign '" + v + "' is not Signed or Unsigned");
    } else if (t == "Endianess" || t == "Endianness") {
        if (v == "BigEndian")
            n.big_endian = true;
        else if (v == "LittleEndian")
            n.big_endian = false;
        else
            bad("Endianess '" + v + "' is not BigEndian or LittleEndian");
    } else if (t == "LSB" || t == "MSB" || t == "Bit") {
        std::int64_t bit = 0;
        if (!parse_int(v, bit) || bit < 0 || bit > 63) {
            bad(t + " '" + v + "' is not a bit number 0..63");
        } else {
            if (t != "MSB")
                n.lsb = int(bit);
            if (t != "LSB")
                n.msb = int(bit);
        }
    } else if (t == "pVariable" || t == "Constant" || t == "Expression") {
        const std::string *name = p.attribute("Name");
        if (!name || name->empty()) {
            bad(t + " without a Name attribute");
        } else if (t == "pVariable") {
            n.variables.push_back(named_ref{*name, ref{v}});
        } else if (t == "Constant") {
            n.constants.push_back(named_text{*name, v});
        } else {
            n.expressions.push_back(named_text{*name, v});
        }
    } else if (t == "Formula") {
        n.has_formula = true;
        n.formula_text = v;
    } else if (t == "FormulaTo") {
        n.has_formula_to = true;
        n.formula_to_text = v;
    } else if (t == "FormulaFrom") {
        n.has_formula_from = true;
        n.formula_from_text = v;
    } else if (t == "Slope") {
        n.slope = v;
    } else if (t == "OnValue") {
        n.on_text = v;
    } else if (t == "OffValue") {
        n.off_text = v;
    } else if (t == "CommandValue") {
        n.has_command_value = true;
        n.command_value_text = v;
    } else if (t == "pCommandValue") {
        n.p_command_value.name = v;
    } else if (t == "ChunkID" || t == "pChunkID") {
        n.has_chunk_id = true;
    } else if (t == "EventID" && n.k == kind::port) {
        n.has_event_id = true;
    }
    // Everything else (ToolTip, Visibility, Streamable, Representation,
    // DisplayNotation, EventID, pAlias, ...) changes no value.
}

void XMLCALL on_start(void *user, const XML_Char *tag, const XML_Char **attributes) {
    static_cast<parser_state *>(user)->start(tag, attributes);
}
void XMLCALL on_end(void *user, const XML_Char * /*tag*/) {
    parser_state &s = *static_cast<parser_state *>(user);
    if (s.refused.empty())
        s.end();
}
void XMLCALL on_text(void *user, const XML_Char *text, int length) {
    parser_state &s = *static_cast<parser_state *>(user);
    if (!s.refused.empty())
        return;
    // Only a property's text is kept (a description's prose is not needed
    // for anything but the property it belongs to).
    if (!s.stack.empty() && s.stack.back().type == frame::prop)
        s.text.append(text, std::size_t(length));
}

}  // namespace

void node_map::impl::parse(const std::string &xml) {
    nodes.clear();
    index.clear();
    cache.clear();
    root_attributes.clear();
    parser_state s{*this, {}, {}, false, nullptr, 0, {}};
    XML_Parser p = XML_ParserCreate(nullptr);
    if (!p)
        throw std::bad_alloc();
    s.parser = p;
    XML_SetUserData(p, &s);
    XML_SetElementHandler(p, on_start, on_end);
    XML_SetCharacterDataHandler(p, on_text);
    std::string message;
    // expat takes an int length; a description is at most 64 MiB (text.cpp).
    const XML_Status rc = XML_Parse(p, xml.data(), int(xml.size()), 1);
    if (!s.refused.empty())
        message = s.refused;
    else if (rc != XML_STATUS_OK)
        message = std::string("the GenICam XML is malformed: ") +
                  XML_ErrorString(XML_GetErrorCode(p)) + " at line " +
                  std::to_string(XML_GetCurrentLineNumber(p));
    XML_ParserFree(p);
    if (!message.empty()) {
        nodes.clear();
        index.clear();
        throw error(FLT_ERR_FORMAT, message.c_str());
    }
    if (index.empty())
        throw error(FLT_ERR_FORMAT, "the GenICam XML defines no node");

    // Who invalidates whom: a write through node k drops the cached
    // registers of every node whose pInvalidator names k.
    invalidated_by.assign(nodes.size(), {});
    for (std::size_t i = 0; i < nodes.size(); ++i)
        for (const ref &r : nodes[i].invalidators) {
            auto it = index.find(r.name);
            if (it != index.end())
                invalidated_by[std::size_t(it->second)].push_back(int(i));
        }
}

}  // namespace flt::genicam
