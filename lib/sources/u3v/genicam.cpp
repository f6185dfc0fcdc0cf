// SPDX-License-Identifier: Apache-2.0
// The GenICam XML: ZIP reader (one deflated entry, through zlib's raw
// inflate), expat parser, feature resolution for the simple node kinds.
#include "sources/u3v/genicam.hpp"

#include <expat.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <iterator>
#include <string>

#include "core/error.hpp"
#include "core/number_text.hpp"
#include "sources/u3v/protocol.hpp"

namespace flt::u3v {

namespace {

[[noreturn]] void raise(flt_status status, const std::string &text) {
    throw error(status, text.c_str());
}

bool parse_int(const std::string &text, std::int64_t &out) {
    std::size_t b = text.find_first_not_of(" \t\r\n");
    if (b == std::string::npos)
        return false;
    std::size_t e = text.find_last_not_of(" \t\r\n");
    const std::string t = text.substr(b, e - b + 1);
    char *end = nullptr;
    errno = 0;
    if (t.size() > 2 && t[0] == '0' && (t[1] == 'x' || t[1] == 'X'))
        out = std::int64_t(std::strtoull(t.c_str() + 2, &end, 16));
    else
        out = std::strtoll(t.c_str(), &end, 10);
    return errno == 0 && end && *end == '\0';
}

// A float Value's integer view, saturated: converting a double outside
// int64's range (or NaN) is undefined behaviour, and a camera file may say
// anything (fuzz_genicam found <Value>0xfff...f2</Value>, 5e92).
std::int64_t saturated_int64(double f) {
    if (!(f == f))
        return 0;
    if (f >= 9223372036854775808.0)
        return std::numeric_limits<std::int64_t>::max();
    if (f < -9223372036854775808.0)
        return std::numeric_limits<std::int64_t>::min();
    return std::int64_t(f);
}

// In the C syntax whatever LC_NUMERIC says (strtod would read "1.5" as 1
// under a decimal-comma locale); white space around it is allowed.
bool parse_float(const std::string &text, double &out) {
    const std::size_t b = text.find_first_not_of(" \t\r\n");
    if (b == std::string::npos)
        return false;
    const std::size_t e = text.find_last_not_of(" \t\r\n");
    return parse_double(std::string_view(text).substr(b, e - b + 1), out);
}

// The node kinds whose elements carry a Name attribute and start a node.
bool is_node_kind(const char *tag) {
    static const char *kinds[] = {
        "Node",      "Category",    "Integer",   "IntReg",       "MaskedIntReg",   "Float",
        "FloatReg",  "Enumeration", "EnumEntry", "Command",      "Boolean",        "String",
        "StringReg", "Register",    "Converter", "IntConverter", "SwissKnife",     "IntSwissKnife",
        "Port",      "ConfRom",     "TextDesc",  "IntKey",       "AdvFeatureLock", "SmartFeature",
        "StructReg", "StructEntry"};
    return std::any_of(std::begin(kinds), std::end(kinds),
                       [tag](const char *k) { return std::strcmp(k, tag) == 0; });
}

struct parser_state {
    std::map<std::string, genicam_node> *nodes;
    std::vector<std::string> open_nodes;  // names of the nodes being parsed
    std::vector<bool> element_is_node;
    std::string text;
    std::string enum_entry;  // the EnumEntry being parsed
    std::int64_t enum_entry_value = 0;
    genicam_node struct_reg;  // the StructReg being parsed
    std::vector<std::string> struct_entries;
    std::string error;
};

genicam_node *current(parser_state &s) {
    if (s.open_nodes.empty())
        return nullptr;
    auto it = s.nodes->find(s.open_nodes.back());
    return it == s.nodes->end() ? nullptr : &it->second;
}

void XMLCALL on_start(void *user, const XML_Char *tag, const XML_Char **attributes) {
    parser_state &s = *static_cast<parser_state *>(user);
    s.text.clear();
    const char *name = nullptr;
    for (int i = 0; attributes[i]; i += 2)
        if (std::strcmp(attributes[i], "Name") == 0)
            name = attributes[i + 1];
    const bool node = name && is_node_kind(tag);
    s.element_is_node.push_back(node);
    if (!node)
        return;
    if (std::strcmp(tag, "EnumEntry") == 0) {
        s.enum_entry = name;
        s.enum_entry_value = 0;
        s.open_nodes.push_back("");  // properties of the entry are not the node's
        return;
    }
    genicam_node n;
    n.kind = tag;
    n.name = name;
    if (std::strcmp(tag, "StructEntry") == 0) {
        n.kind = "MaskedIntReg";  // a bit field of the enclosing StructReg
        s.struct_entries.push_back(name);
    }
    if (std::strcmp(tag, "StructReg") == 0)
        s.struct_entries.clear();
    (*s.nodes)[name] = n;
    s.open_nodes.push_back(name);
}

void set_property(parser_state &s, genicam_node &n, const std::string &tag,
                  const std::string &text) {
    std::int64_t v = 0;
    if (tag == "Address") {
        if (!parse_int(text, v)) {
            s.error = "node '" + n.name + "': Address '" + text + "' is not a number";
            return;
        }
        n.address += std::uint64_t(v);  // several Address elements add up
        n.has_address = true;
    } else if (tag == "pAddress" || tag == "IntSwissKnife" || tag == "pIndex" || tag == "pLength") {
        n.unsupported = "its register address or length is computed (" + tag + ")";
    } else if (tag == "Length") {
        if (parse_int(text, v))
            n.length = std::uint32_t(v);  // 1..8 for integers; StringReg etc. longer
    } else if (tag == "Endianess") {
        n.little_endian = text.find("Big") == std::string::npos;
    } else if (tag == "Sign") {
        n.is_signed = text.find("Signed") == 0;
    } else if (tag == "LSB" && parse_int(text, v)) {
        n.lsb = int(v);
    } else if (tag == "MSB" && parse_int(text, v)) {
        n.msb = int(v);
    } else if (tag == "Bit" && parse_int(text, v)) {
        n.lsb = n.msb = int(v);
    } else if (tag == "pValue") {
        n.p_value = text;
    } else if (tag == "Value") {
        if (parse_int(text, v)) {
            n.value = v;
            n.float_value = double(v);
            n.has_value = true;
        } else if (parse_float(text, n.float_value)) {
            n.value = saturated_int64(n.float_value);
            n.has_value = true;
        }
    } else if (tag == "CommandValue" && parse_int(text, v)) {
        n.command_value = v;
        n.has_command_value = true;
    } else if (tag == "pCommandValue") {
        n.p_command_value = text;
    } else if (tag == "OnValue" && parse_int(text, v)) {
        n.on_value = v;
    } else if (tag == "OffValue" && parse_int(text, v)) {
        n.off_value = v;
    } else if (tag == "Formula" || tag == "FormulaFrom" || tag == "FormulaTo") {
        if (n.formula.empty())
            n.formula = text;
    }
}

void XMLCALL on_end(void *user, const XML_Char *tag) {
    parser_state &s = *static_cast<parser_state *>(user);
    const bool node = s.element_is_node.back();
    s.element_is_node.pop_back();
    if (node) {
        if (std::strcmp(tag, "EnumEntry") == 0) {
            s.open_nodes.pop_back();
            if (genicam_node *e = current(s))
                e->entries.emplace_back(s.enum_entry, s.enum_entry_value);
            s.enum_entry.clear();
        } else {
            if (std::strcmp(tag, "StructReg") == 0) {
                // the entries share the register of their StructReg
                const genicam_node reg = (*s.nodes)[s.open_nodes.back()];
                for (const std::string &e : s.struct_entries) {
                    genicam_node &entry = (*s.nodes)[e];
                    entry.address = reg.address;
                    entry.has_address = reg.has_address;
                    entry.length = reg.length;
                    entry.little_endian = reg.little_endian;
                    if (entry.unsupported.empty())
                        entry.unsupported = reg.unsupported;
                }
            }
            s.open_nodes.pop_back();
        }
        s.text.clear();
        return;
    }
    if (!s.enum_entry.empty() && !s.open_nodes.empty() && s.open_nodes.back().empty()) {
        std::int64_t v = 0;
        if (std::strcmp(tag, "Value") == 0 && parse_int(s.text, v))
            s.enum_entry_value = v;
        s.text.clear();
        return;
    }
    if (genicam_node *n = current(s)) {
        std::string text = s.text;
        const std::size_t b = text.find_first_not_of(" \t\r\n");
        const std::size_t e = text.find_last_not_of(" \t\r\n");
        text = b == std::string::npos ? std::string() : text.substr(b, e - b + 1);
        set_property(s, *n, tag, text);
        if (!s.error.empty())
            return;
        // a StructReg's own register properties also go to the parent node
    }
    s.text.clear();
}

void XMLCALL on_text(void *user, const XML_Char *text, int length) {
    static_cast<parser_state *>(user)->text.append(text, std::size_t(length));
}

}  // namespace

// The largest inflated GenICam XML accepted, bytes.
constexpr std::size_t k_max_xml_bytes = std::size_t(64) << 20;

std::string unzip_single(const std::uint8_t *zip, std::size_t bytes) {
    // Local file header: signature, version, flags, method, time, date,
    // crc-32, compressed size, size, name length, extra length (30 bytes).
    if (bytes < 30 || get_u32(zip) != 0x04034b50u)
        raise(FLT_ERR_FORMAT, "the GenICam ZIP file has no local file header "
                              "(signature 0x04034b50) at its start");
    const std::uint16_t flags = get_u16(zip + 6), method = get_u16(zip + 8);
    const std::uint32_t crc = get_u32(zip + 14);
    std::size_t packed = get_u32(zip + 18), size = get_u32(zip + 22);
    const std::size_t header = 30 + std::size_t(get_u16(zip + 26)) + get_u16(zip + 28);
    if (header > bytes)
        raise(FLT_ERR_FORMAT, "the GenICam ZIP header runs past the file");
    if (flags & 1)
        raise(FLT_ERR_FORMAT, "the GenICam ZIP entry is encrypted");
    // With flag bit 3 the sizes follow the data; inflate finds the end itself.
    const bool sizes_known = !(flags & 8);
    if (!sizes_known)
        packed = bytes - header;
    if (packed > bytes - header)
        raise(FLT_ERR_FORMAT, "the GenICam ZIP entry's compressed size " + std::to_string(packed) +
                                  " runs past the file (" + std::to_string(bytes) + " bytes)");
    // A GenICam description is a few megabytes; a header declaring more is
    // refused before anything is allocated for it (a fuzzed 2 GB size did).
    if (sizes_known && size > k_max_xml_bytes)
        raise(FLT_ERR_FORMAT, "the GenICam ZIP entry declares " + std::to_string(size) +
                                  " bytes, more than the " + std::to_string(k_max_xml_bytes) +
                                  " a GenICam file may have");
    std::string out;
    if (method == 0) {
        if (!sizes_known)
            raise(FLT_ERR_FORMAT, "a stored ZIP entry without sizes");
        out.assign(reinterpret_cast<const char *>(zip + header), packed);
    } else if (method == 8) {
        z_stream z{};
        if (inflateInit2(&z, -15) != Z_OK)
            raise(FLT_ERR_INTERNAL, "inflateInit2 failed");
        z.next_in = const_cast<Bytef *>(zip + header);
        z.avail_in = uInt(packed);
        out.resize(sizes_known && size ? size : packed * 4 + 1024);
        int rc = Z_OK;
        for (;;) {
            z.next_out = reinterpret_cast<Bytef *>(&out[z.total_out]);
            z.avail_out = uInt(out.size() - z.total_out);
            rc = inflate(&z, Z_FINISH);
            if (rc == Z_STREAM_END)
                break;
            if ((rc == Z_BUF_ERROR || rc == Z_OK) && z.avail_out == 0 &&
                out.size() < k_max_xml_bytes) {
                out.resize(out.size() * 2);
                continue;
            }
            inflateEnd(&z);
            raise(FLT_ERR_FORMAT, std::string("the GenICam ZIP entry does not inflate: ") +
                                      (z.msg ? z.msg : "truncated data"));
        }
        out.resize(z.total_out);
        inflateEnd(&z);
    } else {
        raise(FLT_ERR_FORMAT, "the GenICam ZIP entry uses compression method " +
                                  std::to_string(method) +
                                  "; only 0 (stored) and 8 (deflate) exist here");
    }
    if (sizes_known) {
        if (out.size() != size)
            raise(FLT_ERR_FORMAT, "the GenICam ZIP entry inflates to " +
                                      std::to_string(out.size()) + " bytes, its header says " +
                                      std::to_string(size));
        const std::uint32_t actual =
            std::uint32_t(crc32(0, reinterpret_cast<const Bytef *>(out.data()), uInt(out.size())));
        if (actual != crc)
            raise(FLT_ERR_FORMAT, "the GenICam ZIP entry fails its CRC-32 check");
    }
    return out;
}

void genicam_map::parse(const std::string &xml) {
    nodes_.clear();
    parser_state s;
    s.nodes = &nodes_;
    XML_Parser p = XML_ParserCreate(nullptr);
    if (!p)
        throw std::bad_alloc();
    XML_SetUserData(p, &s);
    XML_SetElementHandler(p, on_start, on_end);
    XML_SetCharacterDataHandler(p, on_text);
    const XML_Status rc = XML_Parse(p, xml.data(), int(xml.size()), 1);
    std::string message;
    if (rc != XML_STATUS_OK)
        message = std::string("the GenICam XML is malformed: ") +
                  XML_ErrorString(XML_GetErrorCode(p)) + " at line " +
                  std::to_string(XML_GetCurrentLineNumber(p));
    XML_ParserFree(p);
    if (!message.empty())
        raise(FLT_ERR_FORMAT, message);
    if (!s.error.empty())
        raise(FLT_ERR_FORMAT, "the GenICam XML: " + s.error);
    if (nodes_.empty())
        raise(FLT_ERR_FORMAT, "the GenICam XML has no feature nodes");
}

const genicam_node *genicam_map::find(const std::string &name) const {
    auto it = nodes_.find(name);
    return it == nodes_.end() ? nullptr : &it->second;
}

feature_access genicam_map::resolve(const std::string &feature) const {
    const genicam_node *n = find(feature);
    if (!n)
        raise(FLT_ERR_NOT_FOUND, "feature '" + feature +
                                     "' is not in the camera's GenICam XML; "
                                     "give its register with flt_source_map_feature()");
    const genicam_node *top = n;
    std::string path = feature;
    for (int depth = 0; depth < 16; ++depth) {
        auto cannot = [&](const std::string &why) {
            std::string message = "feature '";
            message += feature;
            message += "' cannot be resolved: node '";
            message += n->name;
            message += "' (";
            message += n->kind;
            message += ") ";
            message += why;
            message += "; give its register with flt_source_map_feature()";
            raise(FLT_ERR_NOT_FOUND, message);
        };
        if (!n->unsupported.empty())
            cannot(n->unsupported);
        const std::string &k = n->kind;
        if (k == "IntReg" || k == "MaskedIntReg" || k == "FloatReg") {
            if (!n->has_address)
                cannot("has no constant Address");
            if (n->length == 0 || n->length > 8)
                cannot("has a Length other than 1..8");
            feature_access a;
            a.kind =
                k == "FloatReg" ? feature_access::float_register : feature_access::int_register;
            if (a.kind == feature_access::float_register && n->length != 4 && n->length != 8)
                cannot("is a float of " + std::to_string(n->length) + " bytes");
            a.address = n->address;
            a.length = n->length;
            a.little_endian = n->little_endian;
            a.is_signed = n->is_signed;
            a.lsb = 0;
            a.msb = int(8 * n->length) - 1;
            if (k == "MaskedIntReg") {
                if (n->lsb < 0)
                    cannot("has no LSB/MSB or Bit");
                a.lsb = std::min(n->lsb, n->msb < 0 ? n->lsb : n->msb);
                a.msb = std::max(n->lsb, n->msb);
                if (!n->little_endian) {
                    // GenICam numbers big-endian register bits from the MSB
                    const int top_bit = int(8 * n->length) - 1;
                    const int lo = top_bit - a.msb, hi = top_bit - a.lsb;
                    a.lsb = lo;
                    a.msb = hi;
                }
                if (a.msb >= int(8 * n->length))
                    cannot("has bits beyond its Length");
            }
            a.node = top;
            return a;
        }
        if (k == "Integer" || k == "Float" || k == "Enumeration" || k == "Command" ||
            k == "Boolean") {
            if (!n->p_value.empty()) {
                const genicam_node *next = find(n->p_value);
                if (!next)
                    cannot("points to '" + n->p_value + "', which is not in the XML");
                n = next;
                continue;
            }
            if (n->has_value && (k == "Integer" || k == "Float")) {
                feature_access a;
                a.kind = feature_access::constant;
                a.constant_value = n->value;
                a.constant_float = n->float_value;
                a.node = top;
                return a;
            }
            cannot("has neither pValue nor Value");
        }
        if (k == "Converter" || k == "IntConverter" || k == "SwissKnife" || k == "IntSwissKnife")
            cannot("is a formula ('" + n->formula + "'), which this client does not evaluate");
        cannot("is of a kind this client does not read");
    }
    raise(FLT_ERR_NOT_FOUND, "feature '" + feature +
                                 "' cannot be resolved: its pValue chain is "
                                 "longer than 16 nodes (a loop?)");
}

}  // namespace flt::u3v
