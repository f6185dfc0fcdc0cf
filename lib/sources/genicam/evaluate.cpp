// SPDX-License-Identifier: Apache-2.0
// Evaluating the node map: values, addresses, access modes, bounds and
// writes, through the register ports, with the register cache.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <set>
#include <string>

#include "core/error.hpp"
#include "sources/genicam/node_map.hpp"
#include "sources/genicam/nodes.hpp"
#include "sources/genicam/text.hpp"

namespace flt::genicam {

namespace {

// Thrown by the node map itself: its message already names the chain, so
// an outer level passes it on unchanged.
struct chain_error : error {
    chain_error(flt_status st, const std::string &msg) : error(st, msg.c_str()) {}
};

// Nodes nested deeper than this (pValue of pValue of ...) are refused as a
// loop: real files need fewer than 12; the limit keeps the recursion (and
// the C++ stack) bounded for any input.
constexpr std::size_t k_max_chain = 48;
// Node evaluations one call may make. Real features take tens; a
// description whose formulas read the same nodes along many paths (each
// node two variables of the next level: 2^48 paths) is refused instead of
// running for hours.
constexpr long k_max_steps = 200000;
// The largest register a StringReg or Register may have, bytes.
constexpr std::int64_t k_max_register_bytes = 1 << 20;

const char *k_kind_names[] = {"Category",   "Integer",       "IntReg",      "MaskedIntReg",
                              "Float",      "FloatReg",      "Converter",   "IntConverter",
                              "SwissKnife", "IntSwissKnife", "Enumeration", "Boolean",
                              "Command",    "String",        "StringReg",   "Register",
                              "Port",       "StructReg",     "Node"};

bool int_kind(kind k) {
    return k == kind::integer || k == kind::int_reg || k == kind::masked_int_reg ||
           k == kind::int_converter || k == kind::int_swiss_knife;
}
bool float_kind(kind k) {
    return k == kind::float_node || k == kind::float_reg || k == kind::converter ||
           k == kind::swiss_knife;
}
bool register_kind(kind k) {
    return k == kind::int_reg || k == kind::masked_int_reg || k == kind::float_reg ||
           k == kind::string_reg || k == kind::reg;
}

access_mode of(declared_access a) {
    switch (a) {
        case declared_access::ro:
            return access_mode::read_only;
        case declared_access::wo:
            return access_mode::write_only;
        default:
            return access_mode::read_write;
    }
}

// The access both allow (RW with RO is RO; RO with WO is NA).
access_mode meet(access_mode a, access_mode b) {
    if (a == access_mode::not_implemented || b == access_mode::not_implemented)
        return access_mode::not_implemented;
    if (a == access_mode::not_available || b == access_mode::not_available)
        return access_mode::not_available;
    if (a == access_mode::read_write)
        return b;
    if (b == access_mode::read_write)
        return a;
    return a == b ? a : access_mode::not_available;
}

std::string hex(std::uint64_t v) {
    static const char digits[] = "0123456789abcdef";
    std::string s;
    do {
        s.insert(s.begin(), digits[v & 15]);
        v >>= 4;
    } while (v);
    return "0x" + s;
}

}  // namespace

const char *access_name(access_mode a) {
    switch (a) {
        case access_mode::not_implemented:
            return "NI";
        case access_mode::not_available:
            return "NA";
        case access_mode::write_only:
            return "WO";
        case access_mode::read_only:
            return "RO";
        case access_mode::read_write:
            return "RW";
    }
    return "?";
}

// ---------------------------------------------------------------------------
// The evaluator: member functions of a helper that works on the impl.
// ---------------------------------------------------------------------------
namespace {

struct evaluator {
    node_map::impl &m;

    // ---- errors naming the chain ----------------------------------------
    std::string chain_text() const {
        if (m.chain.empty())
            return "";
        const auto &c = m.chain;
        std::string s = "feature '" + m.nodes[std::size_t(c.front())].name + "'";
        if (c.size() > 1) {
            s += " (";
            // Long chains keep their ends: the feature and the failing node.
            for (std::size_t i = 0; i < c.size(); ++i) {
                if (c.size() > 8 && i >= 3 && i + 4 < c.size()) {
                    if (i == 3)
                        s += " > ...";
                    continue;
                }
                if (i)
                    s += " > ";
                s += m.nodes[std::size_t(c[i])].name;
            }
            s += ")";
        }
        return s + ": ";
    }
    [[noreturn]] void fail(flt_status status, const std::string &why) const {
        throw chain_error(status, chain_text() + why);
    }
    // Runs `body`; an flt::error from outside the node map (a port, a
    // formula) gets the chain named in front of its message.
    template <class F> auto wrapped(const std::string &what, F &&body) -> decltype(body()) {
        try {
            return body();
        } catch (const chain_error &) {
            throw;
        } catch (const error &e) {
            fail(e.status, what + e.what());
        }
    }

    // Puts node n on the chain for the time of a scope; a node already on
    // it is a loop. `same_ok`: a helper (bounds of the node being written)
    // working on the node at the end of the chain does not enter it twice.
    struct enter {
        node_map::impl &m;
        bool pushed = false;
        enter(const evaluator &ev, int n, bool same_ok = false) : m(ev.m) {
            if (same_ok && !m.chain.empty() && m.chain.back() == n)
                return;
            if (++m.steps > k_max_steps)
                ev.fail(FLT_ERR_FORMAT, "evaluating it takes more than " +
                                            std::to_string(k_max_steps) +
                                            " node evaluations (the description's nodes read "
                                            "each other along too many paths)");
            if (m.chain.size() >= k_max_chain)
                ev.fail(FLT_ERR_FORMAT, "the node chain is deeper than " +
                                            std::to_string(k_max_chain) + " nodes (a loop?)");
            if (std::find(m.chain.begin(), m.chain.end(), n) != m.chain.end()) {
                m.chain.push_back(n);
                const std::string loop = "node '" + m.nodes[std::size_t(n)].name +
                                         "' depends on itself (a loop in the description)";
                std::string message = ev.chain_text() + loop;
                m.chain.pop_back();
                throw chain_error(FLT_ERR_FORMAT, message);
            }
            m.chain.push_back(n);
            pushed = true;
        }
        ~enter() {
            if (pushed)
                m.chain.pop_back();
        }
        enter(const enter &) = delete;
        enter &operator=(const enter &) = delete;
    };

    node &at(int n) { return m.nodes[std::size_t(n)]; }
    const char *kind_name(int n) { return k_kind_names[int(at(n).k)]; }

    int find(const std::string &name) const {
        auto it = m.index.find(name);
        return it == m.index.end() ? -1 : it->second;
    }
    // The node a reference names; fails naming the referring property.
    int target(int from, const ref &r, const char *property) {
        const int t = find(r.name);
        if (t < 0)
            fail(FLT_ERR_FORMAT, std::string(property) + " of '" + at(from).name + "' names '" +
                                     r.name + "', which the description does not define");
        return t;
    }
    // A reference that must not name the node itself (the bounds helpers
    // accept the node at the end of the chain, so this loop needs saying).
    int other(int from, const ref &r, const char *property) {
        const int t = target(from, r, property);
        if (t == from)
            fail(FLT_ERR_FORMAT, std::string(property) + " of '" + at(from).name +
                                     "' names the node itself (a loop in the description)");
        return t;
    }
    int feature(const std::string &name) const {
        const int n = find(name);
        if (n < 0)
            throw error(FLT_ERR_NOT_FOUND,
                        ("feature '" + name + "' is not in the camera's description").c_str());
        return n;
    }
    void usable(int n) {
        if (!at(n).broken.empty())
            fail(FLT_ERR_FORMAT, "node '" + at(n).name + "': " + at(n).broken);
    }

    // ---- constants from the text ------------------------------------------
    std::int64_t int_text(int n, const std::string &text, const char *property) {
        std::int64_t v = 0;
        if (!parse_int(text, v)) {
            double d = 0.0;
            // "2.0" where an integer is meant: accepted when integral.
            if (parse_double(text, d) && d == std::trunc(d) && std::fabs(d) < 9.2e18)
                return std::int64_t(d);
            fail(FLT_ERR_FORMAT, std::string(property) + " '" + text + "' of '" + at(n).name +
                                     "' is not an integer");
        }
        return v;
    }
    double double_text(int n, const std::string &text, const char *property) {
        double v = 0.0;
        if (!parse_double(text, v))
            fail(FLT_ERR_FORMAT,
                 std::string(property) + " '" + text + "' of '" + at(n).name + "' is not a number");
        return v;
    }
    bool truth(int from, const ref &r, const char *property) {
        const int t = target(from, r, property);
        return int_value(t) != 0;
    }

    // ---- registers ---------------------------------------------------------
    std::uint64_t address(int n) {
        node &x = at(n);
        if (x.address.empty())
            fail(FLT_ERR_FORMAT, "register '" + x.name + "' has no Address");
        std::uint64_t sum = 0;  // modulo 2^64, as a register address is
        for (const address_term &a : x.address) {
            switch (a.type) {
                case address_term::constant:
                    sum += std::uint64_t(a.value);
                    break;
                case address_term::node:
                    sum += std::uint64_t(int_value(
                        a.inline_node >= 0 ? a.inline_node : target(n, a.target, "pAddress")));
                    break;
                case address_term::index: {
                    const std::int64_t i = int_value(target(n, a.target, "pIndex"));
                    std::int64_t offset = 0;
                    if (!a.has_offset)
                        offset = length(n);  // registers of its Length, one after another
                    else if (a.p_offset.set())
                        offset = int_value(target(n, a.p_offset, "pOffset"));
                    else
                        offset = a.value;
                    std::int64_t product = 0;
                    if (__builtin_mul_overflow(i, offset, &product))
                        fail(FLT_ERR_NUMERIC, "pIndex " + std::to_string(i) + " x offset " +
                                                  std::to_string(offset) + " overflows");
                    sum += std::uint64_t(product);
                    break;
                }
            }
        }
        return sum;
    }
    std::int64_t length(int n) {
        node &x = at(n);
        std::int64_t len = 0;
        if (x.p_length.set())
            len = int_value(target(n, x.p_length, "pLength"));
        else if (x.has_length)
            len = int_text(n, x.length_text, "Length");
        else
            fail(FLT_ERR_FORMAT, "register '" + x.name + "' has no Length");
        if (len < 1 || len > k_max_register_bytes)
            fail(FLT_ERR_FORMAT, "register '" + x.name + "' has Length " + std::to_string(len));
        return len;
    }
    register_port *port_of(int n, std::string &port_name) {
        node &x = at(n);
        port_name = x.p_port.set() ? x.p_port.name : "Device";
        auto bound = m.ports.find(port_name);
        if (bound != m.ports.end() && bound->second)
            return bound->second;
        const int p = find(port_name);
        if (p >= 0 && at(p).k != kind::port)
            fail(FLT_ERR_FORMAT, "pPort of '" + x.name + "' names '" + port_name +
                                     "', which is a " + kind_name(p) + ", not a Port");
        if (p >= 0 && at(p).has_chunk_id)
            fail(FLT_ERR_NOT_FOUND, "register '" + x.name + "' is on the chunk port '" + port_name +
                                        "', which only a frame's chunk data has");
        if (p >= 0 && at(p).has_event_id)
            fail(FLT_ERR_NOT_FOUND, "register '" + x.name + "' is on the event port '" + port_name +
                                        "', which only an event's data has");
        if (!m.device)
            fail(FLT_ERR_STATE, "no register port is bound to port '" + port_name + "'");
        return m.device;
    }
    bool cachable(int n) {
        return m.caching && at(n).cachable != cache_mode::no_cache && !at(n).polled;
    }
    static std::string where(std::uint64_t a, std::int64_t len, const std::string &port) {
        return "register " + hex(a) + " (" + std::to_string(len) + " bytes" +
               (port == "Device" ? std::string() : " on port '" + port + "'") + "): ";
    }
    // The register's bytes in device order (cached as its Cachable says).
    std::vector<std::uint8_t> read_bytes(int n, std::uint64_t &a, std::int64_t &len) {
        a = address(n);
        len = length(n);
        std::string port_name;
        register_port *port = port_of(n, port_name);
        const auto key = std::make_pair(n, a);
        if (cachable(n)) {
            auto it = m.cache.find(key);
            if (it != m.cache.end() && it->second.bytes.size() == std::size_t(len))
                return it->second.bytes;
        }
        std::vector<std::uint8_t> bytes(std::size_t(len), 0);
        wrapped(where(a, len, port_name), [&] { port->read(a, bytes.data(), bytes.size()); });
        if (cachable(n))
            m.cache[key] = cache_entry{port, bytes};
        return bytes;
    }
    void write_bytes(int n, std::uint64_t a, const std::vector<std::uint8_t> &bytes) {
        std::string port_name;
        register_port *port = port_of(n, port_name);
        wrapped(where(a, std::int64_t(bytes.size()), port_name),
                [&] { port->write(a, bytes.data(), bytes.size()); });
        // Whatever overlaps the bytes just written on this port is stale.
        const std::uint64_t end = a + bytes.size();
        for (auto it = m.cache.begin(); it != m.cache.end();) {
            const std::uint64_t b = it->first.second, e = b + it->second.bytes.size();
            if (it->second.port == port && b < end && a < e)
                it = m.cache.erase(it);
            else
                ++it;
        }
        if (cachable(n) && at(n).cachable == cache_mode::write_through)
            m.cache[std::make_pair(n, a)] = cache_entry{port, bytes};
        invalidate_after_write(n);
    }
    // Drops what the write through the current chain (and `n`) invalidates:
    // registers whose pInvalidator names a written node, transitively; all
    // registers when a selector or a Port-level invalidator is involved.
    void invalidate_after_write(int n) {
        std::vector<int> work(m.chain.begin(), m.chain.end());
        work.push_back(n);
        std::vector<bool> seen(m.nodes.size(), false);
        std::vector<int> dropped;
        while (!work.empty()) {
            const int k = work.back();
            work.pop_back();
            if (!at(k).selected.empty()) {
                // A selector changes what the selected registers show.
                m.cache.clear();
                return;
            }
            for (int j : m.invalidated_by[std::size_t(k)]) {
                if (seen[std::size_t(j)])
                    continue;
                seen[std::size_t(j)] = true;
                if (!register_kind(at(j).k)) {
                    // A Port (or a feature) invalidated: every register.
                    m.cache.clear();
                    return;
                }
                dropped.push_back(j);
                work.push_back(j);
            }
        }
        for (auto it = m.cache.begin(); it != m.cache.end();) {
            if (std::find(dropped.begin(), dropped.end(), it->first.first) != dropped.end())
                it = m.cache.erase(it);
            else
                ++it;
        }
    }

    // An integer register's value: all bits, or the MaskedIntReg's bits.
    struct bitfield {
        int lsb = 0, msb = 63;
        bool big_endian = false, is_signed = false;
        std::int64_t len = 4;
    };
    bitfield bits_of(int n, std::int64_t len) {
        node &x = at(n);
        bitfield b;
        b.len = len;
        b.big_endian = x.big_endian;
        b.is_signed = x.is_signed;
        b.lsb = 0;
        b.msb = int(8 * len) - 1;
        if (x.k == kind::masked_int_reg) {
            if (x.lsb < 0 && x.msb < 0)
                fail(FLT_ERR_FORMAT, "'" + x.name + "' has no LSB/MSB or Bit");
            int lo = x.lsb >= 0 ? x.lsb : x.msb, hi = x.msb >= 0 ? x.msb : x.lsb;
            const int top = int(8 * len) - 1;
            // Bits beyond the register, in either numbering (fuzz_genicam: a
            // big-endian LSB 63 of a 4-byte register made a negative shift).
            if (lo > top || hi > top)
                fail(FLT_ERR_FORMAT, "'" + x.name + "' has bits beyond its " + std::to_string(len) +
                                         "-byte register");
            if (x.big_endian) {
                // Big-endian registers number their bits from the most
                // significant one: bit 0 is the top bit of the value.
                lo = top - lo;
                hi = top - hi;
            }
            if (lo > hi)
                fail(FLT_ERR_FORMAT, "'" + x.name + "' has its LSB above its MSB");
            if (hi > top)
                fail(FLT_ERR_FORMAT, "'" + x.name + "' has bits beyond its " + std::to_string(len) +
                                         "-byte register");
            b.lsb = lo;
            b.msb = hi;
        }
        return b;
    }
    static std::uint64_t word_of(const std::vector<std::uint8_t> &bytes, bool big_endian) {
        std::uint64_t w = 0;
        const std::size_t n = bytes.size();
        for (std::size_t i = 0; i < n; ++i)
            w |= std::uint64_t(bytes[big_endian ? n - 1 - i : i]) << (8 * i);
        return w;
    }
    static std::vector<std::uint8_t> bytes_of(std::uint64_t w, std::size_t n, bool big_endian) {
        std::vector<std::uint8_t> bytes(n);
        for (std::size_t i = 0; i < n; ++i)
            bytes[big_endian ? n - 1 - i : i] = std::uint8_t(w >> (8 * i));
        return bytes;
    }
    std::int64_t read_int_register(int n) {
        std::uint64_t a = 0;
        std::int64_t len = 0;
        const std::vector<std::uint8_t> bytes = read_bytes(n, a, len);
        if (len > 8)
            fail(FLT_ERR_FORMAT, "integer register '" + at(n).name + "' has Length " +
                                     std::to_string(len) + " (at most 8)");
        const bitfield b = bits_of(n, len);
        std::uint64_t w = word_of(bytes, b.big_endian) >> b.lsb;
        const int width = b.msb - b.lsb + 1;
        if (width < 64) {
            w &= (std::uint64_t(1) << width) - 1;
            if (b.is_signed && ((w >> (width - 1)) & 1))
                w |= ~std::uint64_t(0) << width;
        }
        return std::int64_t(w);
    }
    void write_int_register(int n, std::int64_t value) {
        const std::uint64_t a = address(n);
        const std::int64_t len = length(n);
        if (len > 8)
            fail(FLT_ERR_FORMAT, "integer register '" + at(n).name + "' has Length " +
                                     std::to_string(len) + " (at most 8)");
        const bitfield b = bits_of(n, len);
        const int width = b.msb - b.lsb + 1;
        if (width < 64) {
            const std::int64_t lo = b.is_signed ? -(std::int64_t(1) << (width - 1)) : 0;
            const std::int64_t hi = b.is_signed ? (std::int64_t(1) << (width - 1)) - 1
                                                : std::int64_t((std::uint64_t(1) << width) - 1);
            if (value < lo || value > hi)
                fail(FLT_ERR_INVALID_ARGUMENT,
                     "value " + std::to_string(value) + " does not fit its " +
                         std::to_string(width) + "-bit " + (b.is_signed ? "signed" : "unsigned") +
                         " field (" + std::to_string(lo) + " .. " + std::to_string(hi) + ")");
        }
        std::uint64_t w = std::uint64_t(value);
        if (width < int(8 * len)) {
            // Read-modify-write of the bits around the field.
            std::uint64_t a2 = 0;
            std::int64_t len2 = 0;
            const std::uint64_t old = word_of(read_bytes(n, a2, len2), b.big_endian);
            const std::uint64_t mask =
                (width < 64 ? (std::uint64_t(1) << width) - 1 : ~std::uint64_t(0)) << b.lsb;
            w = (old & ~mask) | ((w << b.lsb) & mask);
        }
        write_bytes(n, a, bytes_of(w, std::size_t(len), b.big_endian));
    }
    double read_float_register(int n) {
        std::uint64_t a = 0;
        std::int64_t len = 0;
        const std::vector<std::uint8_t> bytes = read_bytes(n, a, len);
        if (len != 4 && len != 8)  // (fuzz_genicam: a 9-byte FloatReg shifted by 64)
            fail(FLT_ERR_FORMAT, "float register '" + at(n).name + "' has Length " +
                                     std::to_string(len) + " (4 or 8)");
        const std::uint64_t w = word_of(bytes, at(n).big_endian);
        double d;
        if (len == 4) {
            const std::uint32_t b32 = std::uint32_t(w);
            float f;
            std::memcpy(&f, &b32, 4);
            d = double(f);
        } else {
            std::memcpy(&d, &w, 8);
        }
        // A register holding NaN or an infinity has no value a caller can
        // use: refused, never passed on as a number.
        if (!std::isfinite(d))
            fail(FLT_ERR_NUMERIC, "float register '" + at(n).name + "' holds " +
                                      (d != d ? std::string("NaN") : std::string("an infinity")) +
                                      ", not a value");
        return d;
    }
    void write_float_register(int n, double value) {
        const std::uint64_t a = address(n);
        const std::int64_t len = length(n);
        std::uint64_t w = 0;
        if (len == 4) {
            // Converting a double beyond float's range is undefined behaviour.
            if (std::fabs(value) > double(std::numeric_limits<float>::max()))
                fail(FLT_ERR_INVALID_ARGUMENT,
                     "value " + format_double(value) + " is beyond a 32-bit float register");
            const float f = float(value);
            std::uint32_t b32;
            std::memcpy(&b32, &f, 4);
            w = b32;
        } else if (len == 8) {
            std::memcpy(&w, &value, 8);
        } else {
            fail(FLT_ERR_FORMAT, "float register '" + at(n).name + "' has Length " +
                                     std::to_string(len) + " (4 or 8)");
        }
        write_bytes(n, a, bytes_of(w, std::size_t(len), at(n).big_endian));
    }

    // ---- formulas ------------------------------------------------------------
    formula &parsed(std::shared_ptr<formula> &slot, const std::string &text, const char *what) {
        if (!slot)
            slot = std::make_shared<formula>(
                wrapped(std::string(what) + ": ", [&] { return formula(text); }));
        return *slot;
    }
    // A formula of node n with TO or FROM bound to `io` (converters).
    number run(int n, formula &f, formula::mode mode, const char *io_name, const number *io) {
        node &x = at(n);
        std::vector<number> values(f.identifiers().size());
        std::vector<bool> known(values.size(), false);
        auto lookup = [&](std::size_t k) -> number {
            if (known[k])
                return values[k];
            const std::string &id = f.identifiers()[k];
            number v;
            bool found = false;
            if (io && id == io_name) {
                v = *io;
                found = true;
            }
            for (std::size_t i = 0; !found && i < x.variables.size(); ++i)
                if (x.variables[i].name == id) {
                    v = numeric(target(n, x.variables[i].target, "pVariable"));
                    found = true;
                }
            for (std::size_t i = 0; !found && i < x.constants.size(); ++i)
                if (x.constants[i].name == id) {
                    std::int64_t iv = 0;
                    if (parse_int(x.constants[i].text, iv))
                        v = number::of(iv);
                    else
                        v = number::of(double_text(n, x.constants[i].text, "Constant"));
                    found = true;
                }
            for (std::size_t i = 0; !found && i < x.expressions.size(); ++i)
                if (x.expressions[i].name == id) {
                    if (++m.expression_depth > 16) {
                        m.expression_depth = 0;
                        fail(FLT_ERR_FORMAT, "Expressions of '" + x.name + "' nest too deep");
                    }
                    formula &sub = parsed(x.f_expressions[id], x.expressions[i].text, "Expression");
                    struct depth_guard {
                        int &d;
                        ~depth_guard() {
                            if (d > 0)
                                --d;
                        }
                    } guard{m.expression_depth};
                    v = run(n, sub, mode, io_name, io);
                    found = true;
                }
            if (!found && (id == "PI" || id == "E")) {
                v = number::of(id == "PI" ? 3.14159265358979323846 : 2.71828182845904523536);
                found = true;
            }
            if (!found)
                fail(FLT_ERR_FORMAT, "the formula of '" + x.name + "' uses '" + id +
                                         "', which no pVariable, Constant or Expression defines");
            known[k] = true;
            values[k] = v;
            return v;
        };
        return wrapped("", [&] { return f.evaluate(mode, lookup); });
    }
    // An IntConverter's formula: the standard's reference evaluates it in
    // integers, aravis in doubles then truncates; the value is given only
    // where both agree (or where the integer reading is not defined at all,
    // e.g. a fractional constant, and the double one is).
    std::int64_t run_int_converter(int n, formula &f, const char *io_name, const number *io) {
        const number d = run(n, f, formula::mode::floating, io_name, io);
        const double x = d.as_double();
        if (!std::isfinite(x) || std::fabs(x) >= 9.2e18)
            fail(FLT_ERR_NUMERIC, "the formula of '" + at(n).name + "' gives " + format_double(x) +
                                      ", which is no 64-bit integer");
        const std::int64_t truncated = d.is_int ? d.i : std::int64_t(std::trunc(x));
        number i;
        bool integer_ok = true;
        try {
            i = run(n, f, formula::mode::integer, io_name, io);
        } catch (const error &e) {
            if (e.status != FLT_ERR_NUMERIC)
                throw;
            integer_ok = false;
        }
        if (integer_ok && i.i != truncated)
            fail(FLT_ERR_NUMERIC, "the formula '" + f.text() + "' gives " + std::to_string(i.i) +
                                      " in integer arithmetic and " + format_double(x) +
                                      " in floating point: the value is ambiguous");
        return truncated;
    }

    // ---- values ----------------------------------------------------------------
    // Integer/Float value sources: pIndex tables, pValue, Value, a host value.
    const ref *indexed_target(int n, std::string &text, bool &is_text) {
        node &x = at(n);
        const std::int64_t i = int_value(target(n, x.p_index, "pIndex"));
        for (const indexed_value &iv : x.indexed)
            if (iv.index == i) {
                is_text = !iv.target.set();
                text = iv.text;
                return is_text ? nullptr : &iv.target;
            }
        if (x.p_default.set()) {
            is_text = false;
            return &x.p_default;
        }
        if (x.has_default) {
            is_text = true;
            text = x.default_text;
            return nullptr;
        }
        fail(FLT_ERR_NUMERIC, "pIndex '" + x.p_index.name + "' is " + std::to_string(i) +
                                  ", for which '" + x.name + "' has no value and no default");
    }

    number numeric(int n) {
        const kind k = at(n).k;
        if (float_kind(k))
            return number::of(float_value(n));
        return number::of(int_value(n));
    }

    std::int64_t int_value(int n) {
        // Kinds that delegate on the same node do so before entering it (a
        // node entered twice is a loop).
        if (float_kind(at(n).k)) {
            const double d = float_value(n);
            if (!std::isfinite(d) || d != std::trunc(d) || std::fabs(d) >= 9.2e18) {
                enter e(*this, n);
                fail(FLT_ERR_NUMERIC, "'" + at(n).name + "' is " + format_double(d) +
                                          ", where an integer is needed");
            }
            return std::int64_t(d);
        }
        if (at(n).k == kind::boolean)
            return get_bool(n) ? 1 : 0;
        enter e(*this, n);
        usable(n);
        node &x = at(n);
        switch (x.k) {
            case kind::integer:
            case kind::enumeration: {
                if (x.local_set)
                    return x.local.i;
                if (x.k == kind::integer && x.p_index.set()) {
                    std::string text;
                    bool is_text = false;
                    const ref *r = indexed_target(n, text, is_text);
                    if (is_text)
                        return int_text(n, text, "ValueIndexed");
                    return int_value(target(n, *r, "pValueIndexed"));
                }
                if (x.p_value.set())
                    return int_value(target(n, x.p_value, "pValue"));
                if (x.has_value)
                    return int_text(n, x.value_text, "Value");
                fail(FLT_ERR_FORMAT, "'" + x.name + "' has neither pValue nor Value");
            }
            case kind::int_reg:
            case kind::masked_int_reg:
                return read_int_register(n);
            case kind::int_swiss_knife: {
                if (!x.has_formula)
                    fail(FLT_ERR_FORMAT, "'" + x.name + "' has no Formula");
                formula &f = parsed(x.f, x.formula_text, "Formula");
                return run(n, f, formula::mode::integer, nullptr, nullptr).i;
            }
            case kind::int_converter: {
                if (!x.has_formula_from)
                    fail(FLT_ERR_FORMAT, "'" + x.name + "' has no FormulaFrom");
                formula &f = parsed(x.f_from, x.formula_from_text, "FormulaFrom");
                const number to = numeric(target(n, x.p_value, "pValue"));
                return run_int_converter(n, f, "TO", &to);
            }
            default:
                fail(FLT_ERR_INVALID_ARGUMENT,
                     "'" + x.name + "' is a " + kind_name(n) + ", which has no numeric value");
        }
    }

    double float_value(int n) {
        if (!float_kind(at(n).k))
            return double(int_value(n));
        enter e(*this, n);
        usable(n);
        node &x = at(n);
        switch (x.k) {
            case kind::float_node: {
                if (x.local_set)
                    return x.local.as_double();
                if (x.p_index.set()) {
                    std::string text;
                    bool is_text = false;
                    const ref *r = indexed_target(n, text, is_text);
                    if (is_text)
                        return double_text(n, text, "ValueIndexed");
                    return float_value(target(n, *r, "pValueIndexed"));
                }
                if (x.p_value.set())
                    return float_value(target(n, x.p_value, "pValue"));
                if (x.has_value)
                    return double_text(n, x.value_text, "Value");
                fail(FLT_ERR_FORMAT, "'" + x.name + "' has neither pValue nor Value");
            }
            case kind::float_reg:
                return read_float_register(n);
            case kind::swiss_knife: {
                if (!x.has_formula)
                    fail(FLT_ERR_FORMAT, "'" + x.name + "' has no Formula");
                formula &f = parsed(x.f, x.formula_text, "Formula");
                return run(n, f, formula::mode::floating, nullptr, nullptr).as_double();
            }
            case kind::converter: {
                if (!x.has_formula_from)
                    fail(FLT_ERR_FORMAT, "'" + x.name + "' has no FormulaFrom");
                formula &f = parsed(x.f_from, x.formula_from_text, "FormulaFrom");
                const number to = numeric(target(n, x.p_value, "pValue"));
                return run(n, f, formula::mode::floating, "TO", &to).as_double();
            }
            default:
                fail(FLT_ERR_INTERNAL, "float_value of a non-float node");
        }
    }

    bool get_bool(int n) {
        if (at(n).k != kind::boolean)
            return int_value(n) != 0;
        enter e(*this, n);
        usable(n);
        node &x = at(n);
        std::int64_t v = 0;
        if (x.local_set)
            v = x.local.i;
        else if (x.p_value.set())
            v = int_value(target(n, x.p_value, "pValue"));
        else if (x.has_value)
            v = int_text(n, x.value_text, "Value");
        else
            fail(FLT_ERR_FORMAT, "'" + x.name + "' has neither pValue nor Value");
        const std::int64_t on = int_text(n, x.on_text, "OnValue");
        const std::int64_t off = int_text(n, x.off_text, "OffValue");
        if (v == on)
            return true;
        if (v == off)
            return false;
        fail(FLT_ERR_NUMERIC, "'" + x.name + "' reads " + std::to_string(v) +
                                  ", neither its OnValue " + std::to_string(on) +
                                  " nor its OffValue " + std::to_string(off));
    }

    std::string get_enum(int n) {
        if (at(n).k != kind::enumeration) {
            enter e(*this, n);
            fail(FLT_ERR_INVALID_ARGUMENT,
                 "'" + at(n).name + "' is a " + kind_name(n) + ", not an Enumeration");
        }
        const std::int64_t v = int_value(n);
        enter e(*this, n);
        node &x = at(n);
        const enum_entry *match = nullptr;
        int matches = 0;
        for (const enum_entry &en : x.entries) {
            std::int64_t ev = 0;
            if (!parse_int(en.value_text, ev))
                continue;
            if (ev == v) {
                ++matches;
                if (!match)
                    match = &en;
            }
        }
        if (matches > 1) {
            // Entries sharing a value: only the one implemented can be meant.
            const enum_entry *implemented = nullptr;
            int count = 0;
            for (const enum_entry &en : x.entries) {
                std::int64_t ev = 0;
                if (!parse_int(en.value_text, ev) || ev != v)
                    continue;
                if (!en.is_implemented.set() || truth(n, en.is_implemented, "pIsImplemented")) {
                    implemented = &en;
                    ++count;
                }
            }
            if (count != 1)
                fail(FLT_ERR_FORMAT, "'" + x.name + "' reads " + std::to_string(v) +
                                         ", the value of " + std::to_string(matches) +
                                         " of its entries");
            match = implemented;
        }
        if (!match)
            fail(FLT_ERR_NUMERIC,
                 "'" + x.name + "' reads " + std::to_string(v) + ", which none of its entries has");
        return match->name;
    }

    std::string get_string(int n) {
        if (at(n).k == kind::enumeration)
            return get_enum(n);
        enter e(*this, n);
        usable(n);
        node &x = at(n);
        if (x.k == kind::string_node) {
            if (x.local_set)
                return x.local_string;
            if (x.p_value.set())
                return get_string(target(n, x.p_value, "pValue"));
            if (x.has_value)
                return x.value_text;
            fail(FLT_ERR_FORMAT, "'" + x.name + "' has neither pValue nor Value");
        }
        if (x.k == kind::string_reg) {
            std::uint64_t a = 0;
            std::int64_t len = 0;
            const std::vector<std::uint8_t> bytes = read_bytes(n, a, len);
            std::size_t end = 0;
            while (end < bytes.size() && bytes[end] != 0)
                ++end;
            return std::string(bytes.begin(), bytes.begin() + std::ptrdiff_t(end));
        }
        fail(FLT_ERR_INVALID_ARGUMENT,
             "'" + x.name + "' is a " + kind_name(n) + ", which has no string value");
    }

    // ---- access --------------------------------------------------------------
    access_mode access(int n) {
        enter e(*this, n);
        node &x = at(n);
        if (x.is_implemented.set() && !truth(n, x.is_implemented, "pIsImplemented"))
            return access_mode::not_implemented;
        if (x.is_available.set() && !truth(n, x.is_available, "pIsAvailable"))
            return access_mode::not_available;
        access_mode a = access_mode::read_write;
        switch (x.k) {
            case kind::int_reg:
            case kind::masked_int_reg:
            case kind::float_reg:
            case kind::string_reg:
            case kind::reg:
                // A register without AccessMode is read-only (schema default).
                a = x.access == declared_access::none ? access_mode::read_only : of(x.access);
                break;
            case kind::swiss_knife:
            case kind::int_swiss_knife:
            case kind::category:
                a = access_mode::read_only;
                break;
            case kind::integer:
            case kind::float_node:
                if (x.p_index.set())
                    a = access_mode::read_only;  // a table of values
                else if (x.p_value.set())
                    a = access(target(n, x.p_value, "pValue"));
                break;
            case kind::enumeration:
            case kind::boolean:
            case kind::command:
            case kind::string_node:
            case kind::converter:
            case kind::int_converter:
                if (x.p_value.set())
                    a = access(target(n, x.p_value, "pValue"));
                break;
            default:
                break;
        }
        if (x.imposed != declared_access::none)
            a = meet(a, of(x.imposed));
        if (x.is_locked.set() && (a == access_mode::read_write || a == access_mode::write_only) &&
            truth(n, x.is_locked, "pIsLocked"))
            a = a == access_mode::read_write ? access_mode::read_only : access_mode::not_available;
        return a;
    }
    // Why a read or write is refused, or nothing.
    void check(int n, bool writing) {
        const access_mode a = access(n);
        node &x = at(n);
        const bool ok = writing ? (a == access_mode::read_write || a == access_mode::write_only)
                                : (a == access_mode::read_write || a == access_mode::read_only);
        if (ok)
            return;
        enter e(*this, n);
        switch (a) {
            case access_mode::not_implemented:
                fail(FLT_ERR_STATE, "not implemented on this camera (pIsImplemented '" +
                                        x.is_implemented.name + "' is 0)");
            case access_mode::not_available:
                if (x.is_available.set() && !truth(n, x.is_available, "pIsAvailable"))
                    fail(FLT_ERR_STATE,
                         "not available now (pIsAvailable '" + x.is_available.name + "' is 0)");
                fail(FLT_ERR_STATE, "not available now (what it reads is not, or its access "
                                    "modes exclude each other)");
            case access_mode::write_only:
                fail(FLT_ERR_STATE, "write-only: it cannot be read");
            default:
                if (x.is_locked.set() && truth(n, x.is_locked, "pIsLocked"))
                    fail(FLT_ERR_STATE, "locked (pIsLocked '" + x.is_locked.name +
                                            "' is set, e.g. while streaming)");
                fail(FLT_ERR_STATE, "read-only: it cannot be written");
        }
    }

    // ---- bounds --------------------------------------------------------------
    std::int64_t int_bound(int n, int which) {  // 0 min, 1 max, 2 inc
        enter e(*this, n, true);
        node &x = at(n);
        const ref &p = which == 0 ? x.p_min : which == 1 ? x.p_max : x.p_inc;
        const bool has = which == 0 ? x.has_min : which == 1 ? x.has_max : x.has_inc;
        const std::string &text = which == 0 ? x.min_text : which == 1 ? x.max_text : x.inc_text;
        const char *names[] = {"pMin", "pMax", "pInc"};
        if (x.k == kind::integer) {
            if (p.set())
                return int_value(target(n, p, names[which]));
            if (has)
                return int_text(n, text, names[which] + 1);
            if (x.p_value.set() && !x.p_index.set())
                return int_bound(other(n, x.p_value, "pValue"), which);
        } else if (x.k == kind::int_reg || x.k == kind::masked_int_reg) {
            if (which == 2)
                return 1;
            const bitfield b = bits_of(n, length(n));
            const int width = b.msb - b.lsb + 1;
            if (width >= 64)
                return which == 0 ? (b.is_signed ? std::numeric_limits<std::int64_t>::min() : 0)
                                  : std::numeric_limits<std::int64_t>::max();
            if (b.is_signed)
                return which == 0 ? -(std::int64_t(1) << (width - 1))
                                  : (std::int64_t(1) << (width - 1)) - 1;
            return which == 0 ? 0 : std::int64_t((std::uint64_t(1) << width) - 1);
        } else if (x.k == kind::int_converter && which != 2) {
            // The converted bounds of pValue, in order (the formula may fall).
            const int t = other(n, x.p_value, "pValue");
            formula &f = parsed(x.f_from, x.formula_from_text, "FormulaFrom");
            const number lo = number::of(int_bound(t, 0)), hi = number::of(int_bound(t, 1));
            if (lo.i == std::numeric_limits<std::int64_t>::min() ||
                hi.i == std::numeric_limits<std::int64_t>::max())
                return which == 0 ? std::numeric_limits<std::int64_t>::min()
                                  : std::numeric_limits<std::int64_t>::max();
            const std::int64_t a = run_int_converter(n, f, "TO", &lo);
            const std::int64_t b = run_int_converter(n, f, "TO", &hi);
            return which == 0 ? std::min(a, b) : std::max(a, b);
        }
        if (which == 2)
            return 1;
        return which == 0 ? std::numeric_limits<std::int64_t>::min()
                          : std::numeric_limits<std::int64_t>::max();
    }
    double float_bound(int n, int which) {  // 0 min, 1 max
        enter e(*this, n, true);
        node &x = at(n);
        const ref &p = which == 0 ? x.p_min : x.p_max;
        const bool has = which == 0 ? x.has_min : x.has_max;
        const std::string &text = which == 0 ? x.min_text : x.max_text;
        if (x.k == kind::float_node) {
            if (p.set())
                return float_value(target(n, p, which == 0 ? "pMin" : "pMax"));
            if (has)
                return double_text(n, text, which == 0 ? "Min" : "Max");
            if (x.p_value.set() && !x.p_index.set())
                return float_bound(other(n, x.p_value, "pValue"), which);
        } else if (x.k == kind::converter) {
            const int t = other(n, x.p_value, "pValue");
            const double lo = float_bound(t, 0), hi = float_bound(t, 1);
            if (lo <= -DBL_MAX || hi >= DBL_MAX || lo <= -9.2e18 || hi >= 9.2e18)
                return which == 0 ? -DBL_MAX : DBL_MAX;
            formula &f = parsed(x.f_from, x.formula_from_text, "FormulaFrom");
            const bool ints = int_kind(at(t).k);
            const number nlo = ints ? number::of(std::int64_t(lo)) : number::of(lo);
            const number nhi = ints ? number::of(std::int64_t(hi)) : number::of(hi);
            const double a = run(n, f, formula::mode::floating, "TO", &nlo).as_double();
            const double b = run(n, f, formula::mode::floating, "TO", &nhi).as_double();
            if (x.slope == "Varying")
                fail(FLT_ERR_FORMAT, "'" + x.name +
                                         "' has Slope Varying: its bounds are not "
                                         "the converted bounds of its pValue");
            return which == 0 ? std::min(a, b) : std::max(a, b);
        } else if (int_kind(x.k)) {
            const std::int64_t b = int_bound(n, which);
            if (b == std::numeric_limits<std::int64_t>::min())
                return -DBL_MAX;
            if (b == std::numeric_limits<std::int64_t>::max())
                return DBL_MAX;
            return double(b);
        }
        return which == 0 ? -DBL_MAX : DBL_MAX;
    }

    // ---- the register behind a feature ----------------------------------------
    int register_node(int n, std::string &why) {
        enter e(*this, n);
        node &x = at(n);
        if (register_kind(x.k))
            return n;
        switch (x.k) {
            case kind::integer:
            case kind::float_node:
            case kind::enumeration:
            case kind::boolean:
            case kind::command:
            case kind::string_node:
            case kind::converter:
            case kind::int_converter:
                if (x.p_index.set()) {
                    why = "its value is chosen by pIndex '" + x.p_index.name + "'";
                    return -1;
                }
                if (x.local_set || !x.p_value.set()) {
                    why = "its value is a constant of the description";
                    return -1;
                }
                return register_node(target(n, x.p_value, "pValue"), why);
            default:
                why = std::string("it is a ") + kind_name(n);
                return -1;
        }
    }

    // ---- writes ----------------------------------------------------------------
    void check_int_range(int n, std::int64_t v) {
        const std::int64_t lo = int_bound(n, 0), hi = int_bound(n, 1), inc = int_bound(n, 2);
        if (v < lo || v > hi)
            fail(FLT_ERR_INVALID_ARGUMENT, "value " + std::to_string(v) + " is outside " +
                                               std::to_string(lo) + " .. " + std::to_string(hi));
        if (inc > 1 && lo != std::numeric_limits<std::int64_t>::min() && (v - lo) % inc != 0)
            fail(FLT_ERR_INVALID_ARGUMENT, "value " + std::to_string(v) + " is not " +
                                               std::to_string(lo) + " plus a multiple of " +
                                               std::to_string(inc));
    }
    void copy_value(int n, const number &v) {
        for (const ref &r : at(n).value_copies) {
            const int t = target(n, r, "pValueCopy");
            if (float_kind(at(t).k))
                set_float(t, v.as_double());
            else
                set_int(t, v.is_int ? v.i : std::int64_t(std::llround(v.d)));
        }
    }
    void set_int(int n, std::int64_t v) {
        if (float_kind(at(n).k)) {
            set_float(n, double(v));
            return;
        }
        if (at(n).k == kind::boolean) {
            set_bool(n, v != 0);
            return;
        }
        enter e(*this, n);
        usable(n);
        node &x = at(n);
        switch (x.k) {
            case kind::integer:
            case kind::enumeration: {
                if (x.k == kind::integer)
                    check_int_range(n, v);
                if (x.k == kind::integer && x.p_index.set()) {
                    std::string text;
                    bool is_text = false;
                    const ref *r = indexed_target(n, text, is_text);
                    if (is_text)
                        fail(FLT_ERR_STATE, "the value for this index is a constant");
                    set_int(target(n, *r, "pValueIndexed"), v);
                } else if (x.p_value.set()) {
                    set_int(target(n, x.p_value, "pValue"), v);
                } else {
                    x.local_set = true;
                    x.local = number::of(v);
                    invalidate_after_write(n);
                }
                copy_value(n, number::of(v));
                return;
            }
            case kind::int_reg:
            case kind::masked_int_reg:
                write_int_register(n, v);
                return;
            case kind::int_converter: {
                if (!x.has_formula_to)
                    fail(FLT_ERR_FORMAT, "'" + x.name + "' has no FormulaTo");
                formula &f = parsed(x.f_to, x.formula_to_text, "FormulaTo");
                const number from = number::of(v);
                const int t = target(n, x.p_value, "pValue");
                if (float_kind(at(t).k))
                    set_float(t, run(n, f, formula::mode::floating, "FROM", &from).as_double());
                else
                    set_int(t, run_int_converter(n, f, "FROM", &from));
                return;
            }
            default:
                fail(FLT_ERR_INVALID_ARGUMENT,
                     "'" + x.name + "' is a " + kind_name(n) + ", which takes no integer value");
        }
    }
    void set_float(int n, double v) {
        if (!float_kind(at(n).k) && (int_kind(at(n).k) || at(n).k == kind::boolean)) {
            if (v != std::trunc(v) || std::fabs(v) >= 9.2e18) {
                enter e(*this, n);
                fail(FLT_ERR_INVALID_ARGUMENT, "value " + format_double(v) +
                                                   " is not an integer, which '" + at(n).name +
                                                   "' needs");
            }
            set_int(n, std::int64_t(v));
            return;
        }
        enter e(*this, n);
        usable(n);
        node &x = at(n);
        if (!std::isfinite(v))
            fail(FLT_ERR_INVALID_ARGUMENT, "value " + format_double(v) + " is not finite");
        switch (x.k) {
            case kind::float_node: {
                const double lo = float_bound(n, 0), hi = float_bound(n, 1);
                if (v < lo || v > hi)
                    fail(FLT_ERR_INVALID_ARGUMENT, "value " + format_double(v) + " is outside " +
                                                       format_double(lo) + " .. " +
                                                       format_double(hi));
                if (x.p_index.set()) {
                    std::string text;
                    bool is_text = false;
                    const ref *r = indexed_target(n, text, is_text);
                    if (is_text)
                        fail(FLT_ERR_STATE, "the value for this index is a constant");
                    set_float(target(n, *r, "pValueIndexed"), v);
                } else if (x.p_value.set()) {
                    set_float(target(n, x.p_value, "pValue"), v);
                } else {
                    x.local_set = true;
                    x.local = number::of(v);
                    invalidate_after_write(n);
                }
                copy_value(n, number::of(v));
                return;
            }
            case kind::float_reg:
                write_float_register(n, v);
                return;
            case kind::converter: {
                if (!x.has_formula_to)
                    fail(FLT_ERR_FORMAT, "'" + x.name + "' has no FormulaTo");
                formula &f = parsed(x.f_to, x.formula_to_text, "FormulaTo");
                const number from = number::of(v);
                const double to = run(n, f, formula::mode::floating, "FROM", &from).as_double();
                const int t = target(n, x.p_value, "pValue");
                if (float_kind(at(t).k)) {
                    set_float(t, to);
                } else {
                    // The nearest integer (the register takes whole counts).
                    if (!std::isfinite(to) || std::fabs(to) >= 9.2e18)
                        fail(FLT_ERR_INVALID_ARGUMENT,
                             "value " + format_double(v) + " converts to " + format_double(to));
                    set_int(t, std::llround(to));
                }
                return;
            }
            default:
                fail(FLT_ERR_INVALID_ARGUMENT,
                     "'" + x.name + "' is a " + kind_name(n) + ", which takes no number");
        }
    }
    void set_bool(int n, bool b) {
        if (at(n).k != kind::boolean) {
            set_int(n, b ? 1 : 0);
            return;
        }
        enter e(*this, n);
        usable(n);
        node &x = at(n);
        const std::int64_t v = int_text(n, b ? x.on_text : x.off_text, b ? "OnValue" : "OffValue");
        if (x.p_value.set()) {
            set_int(target(n, x.p_value, "pValue"), v);
        } else {
            x.local_set = true;
            x.local = number::of(v);
            invalidate_after_write(n);
        }
    }
    void set_enum(int n, const std::string &entry) {
        set_int(n, entry_value(n, entry));  // set_int enters n itself
    }
    std::int64_t entry_value(int n, const std::string &entry) {
        enter e(*this, n);
        usable(n);
        node &x = at(n);
        if (x.k != kind::enumeration)
            fail(FLT_ERR_INVALID_ARGUMENT,
                 "'" + x.name + "' is a " + kind_name(n) + ", not an Enumeration");
        for (const enum_entry &en : x.entries) {
            if (en.name != entry)
                continue;
            if (en.is_implemented.set() && !truth(n, en.is_implemented, "pIsImplemented"))
                fail(FLT_ERR_STATE, "entry '" + entry + "' is not implemented on this camera");
            if (en.is_available.set() && !truth(n, en.is_available, "pIsAvailable"))
                fail(FLT_ERR_STATE, "entry '" + entry + "' is not available now");
            return int_text(n, en.value_text, "EnumEntry Value");
        }
        std::string names;
        for (const enum_entry &en : x.entries)
            if (names.size() < 200)
                names += (names.empty() ? "" : ", ") + en.name;
        fail(FLT_ERR_NOT_FOUND, "no entry '" + entry + "' (entries: " + names + ")");
    }
    void set_string(int n, const std::string &value) {
        if (at(n).k == kind::enumeration) {
            set_enum(n, value);
            return;
        }
        enter e(*this, n);
        usable(n);
        node &x = at(n);
        if (x.k == kind::string_node) {
            if (x.p_value.set()) {
                set_string(target(n, x.p_value, "pValue"), value);
            } else {
                x.local_set = true;
                x.local_string = value;
                invalidate_after_write(n);
            }
        } else if (x.k == kind::string_reg) {
            const std::uint64_t a = address(n);
            const std::int64_t len = length(n);
            if (std::int64_t(value.size()) > len)
                fail(FLT_ERR_INVALID_ARGUMENT, "a string of " + std::to_string(value.size()) +
                                                   " bytes does not fit its " +
                                                   std::to_string(len) + "-byte register");
            std::vector<std::uint8_t> bytes(std::size_t(len), 0);
            std::memcpy(bytes.data(), value.data(), value.size());
            write_bytes(n, a, bytes);
        } else {
            fail(FLT_ERR_INVALID_ARGUMENT,
                 "'" + x.name + "' is a " + kind_name(n) + ", which takes no string");
        }
    }
    std::int64_t command_value(int n) {
        node &x = at(n);
        if (x.p_command_value.set())
            return int_value(target(n, x.p_command_value, "pCommandValue"));
        if (x.has_command_value)
            return int_text(n, x.command_value_text, "CommandValue");
        fail(FLT_ERR_FORMAT, "'" + x.name + "' has neither CommandValue nor pCommandValue");
    }
    void execute(int n) {
        enter e(*this, n);
        usable(n);
        node &x = at(n);
        if (x.k != kind::command)
            fail(FLT_ERR_INVALID_ARGUMENT,
                 "'" + x.name + "' is a " + kind_name(n) + ", not a Command");
        if (!x.p_value.set())
            fail(FLT_ERR_FORMAT, "'" + x.name + "' has no pValue to write");
        set_int(target(n, x.p_value, "pValue"), command_value(n));
    }
    bool is_done(int n) {
        enter e(*this, n);
        usable(n);
        node &x = at(n);
        if (x.k != kind::command)
            fail(FLT_ERR_INVALID_ARGUMENT,
                 "'" + x.name + "' is a " + kind_name(n) + ", not a Command");
        const int t = target(n, x.p_value, "pValue");
        // A write-only command register cannot be polled: it is done once written.
        if (access(t) == access_mode::write_only)
            return true;
        // The register is read from the device, never from the cache.
        const bool caching = m.caching;
        m.caching = false;
        struct restore {
            bool &flag;
            bool value;
            ~restore() { flag = value; }
        } r{m.caching, caching};
        return int_value(t) != command_value(n);
    }
};

}  // namespace

// ---------------------------------------------------------------------------
// node_map
// ---------------------------------------------------------------------------

node_map::node_map() : d_(new impl) {}
node_map::~node_map() = default;

void node_map::load(const std::string &xml) {
    if (xml.size() > (std::size_t(64) << 20))
        throw error(FLT_ERR_FORMAT, "the GenICam XML is larger than 64 MiB");
    d_->parse(xml);
}

void node_map::bind(register_port *device) {
    d_->device = device;
    d_->cache.clear();
}
void node_map::bind(const std::string &port_node, register_port *port) {
    d_->ports[port_node] = port;
    d_->cache.clear();
}
void node_map::set_caching(bool on) {
    d_->caching = on;
    if (!on)
        d_->cache.clear();
}
void node_map::invalidate() {
    d_->cache.clear();
}

std::string node_map::description_attribute(const std::string &name) const {
    for (const auto &a : d_->root_attributes)
        if (a.first == name)
            return a.second;
    return std::string();
}

int node_map::schema_version() const {
    auto part = [&](const char *name) {
        std::int64_t v = 0;
        if (!parse_int(description_attribute(name), v) || v < 0 || v > 99)
            return 0;
        return int(v);
    };
    return part("SchemaMajorVersion") * 10000 + part("SchemaMinorVersion") * 100 +
           part("SchemaSubMinorVersion");
}

bool node_map::has(const std::string &name) const {
    return d_->index.count(name) != 0;
}
std::size_t node_map::size() const {
    return d_->index.size();
}

namespace {
interface_kind interface_of_kind(kind k) {
    switch (k) {
        case kind::integer:
        case kind::int_reg:
        case kind::masked_int_reg:
        case kind::int_converter:
        case kind::int_swiss_knife:
            return interface_kind::integer;
        case kind::float_node:
        case kind::float_reg:
        case kind::converter:
        case kind::swiss_knife:
            return interface_kind::floating;
        case kind::enumeration:
            return interface_kind::enumeration;
        case kind::boolean:
            return interface_kind::boolean;
        case kind::command:
            return interface_kind::command;
        case kind::string_node:
        case kind::string_reg:
            return interface_kind::string;
        case kind::reg:
            return interface_kind::reg;
        case kind::category:
            return interface_kind::category;
        case kind::port:
            return interface_kind::port;
        default:
            return interface_kind::none;
    }
}
}  // namespace

std::vector<std::string> node_map::feature_names() const {
    std::vector<std::string> names;
    for (const node &n : d_->nodes) {
        const interface_kind i = interface_of_kind(n.k);
        if (n.name.empty() || n.name[0] == '(' || i == interface_kind::category ||
            i == interface_kind::port || i == interface_kind::none)
            continue;
        names.push_back(n.name);
    }
    return names;
}

namespace {
const node &named(const node_map::impl &m, const std::string &name) {
    auto it = m.index.find(name);
    if (it == m.index.end())
        throw error(FLT_ERR_NOT_FOUND,
                    ("feature '" + name + "' is not in the camera's description").c_str());
    return m.nodes[std::size_t(it->second)];
}
}  // namespace

interface_kind node_map::interface_of(const std::string &feature) const {
    return interface_of_kind(named(*d_, feature).k);
}
const std::string &node_map::kind_of(const std::string &feature) const {
    return named(*d_, feature).tag;
}
const std::string &node_map::display_name(const std::string &feature) const {
    return named(*d_, feature).display_name;
}
const std::string &node_map::unit(const std::string &feature) const {
    return named(*d_, feature).unit;
}
const std::string &node_map::description(const std::string &feature) const {
    return named(*d_, feature).description;
}

namespace {
const node &category_named(const node_map::impl &m, const std::string &name) {
    const node &n = named(m, name);
    if (interface_of_kind(n.k) != interface_kind::category)
        throw error(FLT_ERR_NOT_FOUND, ("'" + name + "' is no category").c_str());
    return n;
}
}  // namespace

std::size_t node_map::category_size(const std::string &category) const {
    return category_named(*d_, category).features.size();
}
const std::string &node_map::category_feature(const std::string &category,
                                              std::size_t index) const {
    const node &n = category_named(*d_, category);
    if (index >= n.features.size())
        throw error(FLT_ERR_NOT_FOUND, ("category '" + category + "' has " +
                                        std::to_string(n.features.size()) + " entries")
                                           .c_str());
    return n.features[index].name;
}

access_mode node_map::declared_access(const std::string &feature) const {
    // Follows pValue without evaluating anything; a loop ends the walk.
    const node *n = &named(*d_, feature);
    access_mode a = access_mode::read_write;
    for (int depth = 0; depth < int(k_max_chain); ++depth) {
        if (n->imposed != declared_access::none)
            a = meet(a, of(n->imposed));
        if (register_kind(n->k)) {
            a = meet(a,
                     n->access == declared_access::none ? access_mode::read_only : of(n->access));
            break;
        }
        if (n->k == kind::swiss_knife || n->k == kind::int_swiss_knife || n->k == kind::category) {
            a = meet(a, access_mode::read_only);
            break;
        }
        if (n->p_index.set()) {
            a = meet(a, access_mode::read_only);
            break;
        }
        if (!n->p_value.set())
            break;
        auto it = d_->index.find(n->p_value.name);
        if (it == d_->index.end())
            break;
        n = &d_->nodes[std::size_t(it->second)];
    }
    return a;
}

// Every evaluating entry point starts with an empty chain (a previous
// failure unwound its guards) and names the feature.
#define FLT_GENICAM_EVAL(feature_name, body) \
  do {                                       \
    evaluator ev{*d_};                       \
    d_->chain.clear();                       \
    d_->expression_depth = 0;                \
    d_->steps = 0;                           \
    const int n = ev.feature(feature_name);  \
    (void)n;                                 \
    body;                                    \
  } while (0)

access_mode node_map::access(const std::string &feature) {
    access_mode a = access_mode::not_available;
    FLT_GENICAM_EVAL(feature, a = ev.access(n));
    return a;
}

node_map::state node_map::flags(const std::string &feature) {
    state st;
    FLT_GENICAM_EVAL(feature, {
        evaluator::enter e(ev, n);
        const node &x = d_->nodes[std::size_t(n)];
        if (x.is_implemented.set())
            st.implemented = ev.truth(n, x.is_implemented, "pIsImplemented");
        if (x.is_available.set())
            st.available = ev.truth(n, x.is_available, "pIsAvailable");
        if (x.is_locked.set())
            st.locked = ev.truth(n, x.is_locked, "pIsLocked");
    });
    return st;
}

std::int64_t node_map::get_int(const std::string &feature, bool checked) {
    std::int64_t v = 0;
    FLT_GENICAM_EVAL(feature, {
        if (checked)
            ev.check(n, false);
        const kind k = d_->nodes[std::size_t(n)].k;
        if (!int_kind(k) && !float_kind(k) && k != kind::enumeration && k != kind::boolean) {
            evaluator::enter e(ev, n);
            ev.fail(FLT_ERR_INVALID_ARGUMENT,
                    std::string("it is a ") + ev.kind_name(n) + ", which has no integer value");
        }
        v = ev.int_value(n);
    });
    return v;
}

double node_map::get_float(const std::string &feature, bool checked) {
    double v = 0.0;
    FLT_GENICAM_EVAL(feature, {
        if (checked)
            ev.check(n, false);
        const kind k = d_->nodes[std::size_t(n)].k;
        if (!int_kind(k) && !float_kind(k)) {
            evaluator::enter e(ev, n);
            ev.fail(FLT_ERR_INVALID_ARGUMENT,
                    std::string("it is a ") + ev.kind_name(n) + ", which has no number value");
        }
        v = ev.float_value(n);
    });
    return v;
}

bool node_map::get_bool(const std::string &feature, bool checked) {
    bool v = false;
    FLT_GENICAM_EVAL(feature, {
        if (checked)
            ev.check(n, false);
        const kind k = d_->nodes[std::size_t(n)].k;
        if (k != kind::boolean && !int_kind(k)) {
            evaluator::enter e(ev, n);
            ev.fail(FLT_ERR_INVALID_ARGUMENT,
                    std::string("it is a ") + ev.kind_name(n) + ", not a Boolean");
        }
        v = ev.get_bool(n);
    });
    return v;
}

std::string node_map::get_enum(const std::string &feature, bool checked) {
    std::string v;
    FLT_GENICAM_EVAL(feature, {
        if (checked)
            ev.check(n, false);
        v = ev.get_enum(n);
    });
    return v;
}

std::string node_map::get_string(const std::string &feature, bool checked) {
    std::string v;
    FLT_GENICAM_EVAL(feature, {
        if (checked)
            ev.check(n, false);
        v = ev.get_string(n);
    });
    return v;
}

std::vector<std::uint8_t> node_map::get_register(const std::string &feature, bool checked) {
    std::vector<std::uint8_t> v;
    FLT_GENICAM_EVAL(feature, {
        if (checked)
            ev.check(n, false);
        evaluator::enter e(ev, n);
        ev.usable(n);
        if (!register_kind(d_->nodes[std::size_t(n)].k))
            ev.fail(FLT_ERR_INVALID_ARGUMENT,
                    std::string("it is a ") + ev.kind_name(n) + ", not a register");
        std::uint64_t a = 0;
        std::int64_t len = 0;
        v = ev.read_bytes(n, a, len);
    });
    return v;
}

std::int64_t node_map::int_min(const std::string &feature) {
    std::int64_t v = 0;
    FLT_GENICAM_EVAL(feature, v = ev.int_bound(n, 0));
    return v;
}
std::int64_t node_map::int_max(const std::string &feature) {
    std::int64_t v = 0;
    FLT_GENICAM_EVAL(feature, v = ev.int_bound(n, 1));
    return v;
}
std::int64_t node_map::int_inc(const std::string &feature) {
    std::int64_t v = 0;
    FLT_GENICAM_EVAL(feature, v = ev.int_bound(n, 2));
    return v;
}
double node_map::float_min(const std::string &feature) {
    double v = 0;
    FLT_GENICAM_EVAL(feature, v = ev.float_bound(n, 0));
    return v;
}
double node_map::float_max(const std::string &feature) {
    double v = 0;
    FLT_GENICAM_EVAL(feature, v = ev.float_bound(n, 1));
    return v;
}

std::vector<enum_entry_info> node_map::enum_entries(const std::string &feature) {
    std::vector<enum_entry_info> out;
    FLT_GENICAM_EVAL(feature, {
        evaluator::enter e(ev, n);
        const node &x = d_->nodes[std::size_t(n)];
        if (x.k != kind::enumeration)
            ev.fail(FLT_ERR_INVALID_ARGUMENT,
                    std::string("it is a ") + ev.kind_name(n) + ", not an Enumeration");
        for (const enum_entry &en : x.entries) {
            enum_entry_info info;
            info.name = en.name;
            info.display_name = en.display_name;
            info.value = ev.int_text(n, en.value_text, "EnumEntry Value");
            info.implemented =
                !en.is_implemented.set() || ev.truth(n, en.is_implemented, "pIsImplemented");
            info.available = info.implemented && (!en.is_available.set() ||
                                                  ev.truth(n, en.is_available, "pIsAvailable"));
            out.push_back(info);
        }
    });
    return out;
}

bool node_map::register_of(const std::string &feature, register_info &out) {
    bool found = false;
    FLT_GENICAM_EVAL(feature, {
        std::string why;
        const int r = ev.register_node(n, why);
        if (r >= 0) {
            evaluator::enter e(ev, n);
            std::unique_ptr<evaluator::enter> e2;
            if (r != n)
                e2.reset(new evaluator::enter(ev, r));
            ev.usable(r);
            const node &x = d_->nodes[std::size_t(r)];
            out = register_info{};
            out.node = x.name;
            out.port = x.p_port.set() ? x.p_port.name : "Device";
            out.address = ev.address(r);
            const std::int64_t len = ev.length(r);
            out.length = std::uint32_t(len);
            out.big_endian = x.big_endian;
            out.is_signed = x.is_signed;
            if (x.k == kind::int_reg || x.k == kind::masked_int_reg) {
                if (len > 8)
                    ev.fail(FLT_ERR_FORMAT, "integer register '" + x.name + "' has Length " +
                                                std::to_string(len) + " (at most 8)");
                const auto b = ev.bits_of(r, len);
                out.lsb = b.lsb;
                out.msb = b.msb;
            } else {
                out.lsb = 0;
                out.msb = int(8 * std::min<std::int64_t>(len, 8)) - 1;
            }
            found = true;
        }
    });
    return found;
}

void node_map::set_int(const std::string &feature, std::int64_t value) {
    FLT_GENICAM_EVAL(feature, {
        ev.check(n, true);
        ev.set_int(n, value);
    });
}
void node_map::set_float(const std::string &feature, double value) {
    FLT_GENICAM_EVAL(feature, {
        ev.check(n, true);
        ev.set_float(n, value);
    });
}
void node_map::set_bool(const std::string &feature, bool value) {
    FLT_GENICAM_EVAL(feature, {
        ev.check(n, true);
        ev.set_bool(n, value);
    });
}
void node_map::set_enum(const std::string &feature, const std::string &entry) {
    FLT_GENICAM_EVAL(feature, {
        ev.check(n, true);
        ev.set_enum(n, entry);
    });
}
void node_map::set_string(const std::string &feature, const std::string &value) {
    FLT_GENICAM_EVAL(feature, {
        ev.check(n, true);
        ev.set_string(n, value);
    });
}
void node_map::execute(const std::string &feature, bool checked) {
    FLT_GENICAM_EVAL(feature, {
        if (checked)
            ev.check(n, true);
        ev.execute(n);
    });
}
bool node_map::is_done(const std::string &feature) {
    bool done = false;
    FLT_GENICAM_EVAL(feature, done = ev.is_done(n));
    return done;
}

}  // namespace flt::genicam
