// SPDX-License-Identifier: Apache-2.0
// Numbers, the ZIP container and the XML document of a GenICam description.
#include "sources/genicam/text.hpp"

#include <zlib.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <string>
#include <system_error>

#include "core/error.hpp"

namespace flt::genicam {

namespace {

[[noreturn]] void raise(flt_status status, const std::string &text) {
    throw error(status, text.c_str());
}

bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

std::uint16_t u16_at(const std::uint8_t *p) {
    return std::uint16_t(p[0] | (p[1] << 8));
}
std::uint32_t u32_at(const std::uint8_t *p) {
    return std::uint32_t(p[0]) | (std::uint32_t(p[1]) << 8) | (std::uint32_t(p[2]) << 16) |
           (std::uint32_t(p[3]) << 24);
}

}  // namespace

std::string_view trim(std::string_view text) {
    std::size_t b = 0, e = text.size();
    while (b < e && is_space(text[b]))
        ++b;
    while (e > b && is_space(text[e - 1]))
        --e;
    return text.substr(b, e - b);
}

bool parse_int(std::string_view text, std::int64_t &out) {
    std::string_view t = trim(text);
    bool negative = false;
    if (!t.empty() && (t[0] == '-' || t[0] == '+')) {
        negative = t[0] == '-';
        t.remove_prefix(1);
    }
    if (t.empty())
        return false;
    std::uint64_t magnitude = 0;
    const char *first = t.data(), *last = t.data() + t.size();
    std::from_chars_result r{};
    if (t.size() > 2 && t[0] == '0' && (t[1] == 'x' || t[1] == 'X')) {
        // Hex is a bit pattern: 0xFFFFFFFFFFFFFFFF is -1 as an int64.
        r = std::from_chars(first + 2, last, magnitude, 16);
        if (r.ec != std::errc() || r.ptr != last || t.size() > 18)
            return false;
    } else {
        if (t.size() > 1 && t[0] == '0')
            return false;  // "010": octal to C, decimal to the schema
        r = std::from_chars(first, last, magnitude, 10);
        if (r.ec != std::errc() || r.ptr != last)
            return false;
        if (magnitude > (negative ? std::uint64_t(1) << 63 : (std::uint64_t(1) << 63) - 1))
            return false;
    }
    // Two's complement negation in unsigned arithmetic (defined behaviour).
    out = std::int64_t(negative ? ~magnitude + 1 : magnitude);
    return true;
}

bool parse_double(std::string_view text, double &out) {
    std::int64_t i = 0;
    if (parse_int(text, i)) {
        out = double(i);
        return true;
    }
    std::string_view t = trim(text);
    if (!t.empty() && t[0] == '+')
        t.remove_prefix(1);
    if (t.empty())
        return false;
    // from_chars reads the C locale's syntax whatever LC_NUMERIC says; it
    // also reads "inf" and "nan", which no GenICam number is.
    for (char c : t)
        if (!((c >= '0' && c <= '9') || c == '.' || c == '-' || c == 'e' || c == 'E' || c == '+'))
            return false;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), out);
    return r.ec == std::errc() && r.ptr == t.data() + t.size() && std::isfinite(out);
}

std::string format_double(double value) {
    char buffer[64];
    const auto r = std::to_chars(buffer, buffer + sizeof buffer, value);
    return std::string(buffer, r.ptr);
}

// The largest inflated GenICam XML accepted, bytes.
constexpr std::size_t k_max_xml_bytes = std::size_t(64) << 20;

bool looks_zipped(const std::uint8_t *data, std::size_t bytes) {
    return bytes >= 4 && u32_at(data) == 0x04034b50u;
}

std::string unzip_single(const std::uint8_t *zip, std::size_t bytes) {
    // Local file header: signature, version, flags, method, time, date,
    // crc-32, compressed size, size, name length, extra length (30 bytes).
    if (bytes < 30 || !looks_zipped(zip, bytes))
        raise(FLT_ERR_FORMAT, "the GenICam ZIP file has no local file header "
                              "(signature 0x04034b50) at its start");
    const std::uint16_t flags = u16_at(zip + 6), method = u16_at(zip + 8);
    const std::uint32_t crc = u32_at(zip + 14);
    std::size_t packed = u32_at(zip + 18), size = u32_at(zip + 22);
    const std::size_t header = 30 + std::size_t(u16_at(zip + 26)) + u16_at(zip + 28);
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
        for (;;) {
            z.next_out = reinterpret_cast<Bytef *>(&out[z.total_out]);
            z.avail_out = uInt(out.size() - z.total_out);
            const int rc = inflate(&z, Z_FINISH);
            if (rc == Z_STREAM_END)
                break;
            if ((rc == Z_BUF_ERROR || rc == Z_OK) && z.avail_out == 0 &&
                out.size() < k_max_xml_bytes) {
                out.resize(std::min(out.size() * 2, k_max_xml_bytes));
                continue;
            }
            inflateEnd(&z);
            raise(FLT_ERR_FORMAT, std::string("the GenICam ZIP entry does not inflate: ") +
                                      (z.msg ? z.msg : "truncated data or more than 64 MiB"));
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

std::string xml_document(std::string text) {
    if (text.size() >= 2 && ((std::uint8_t(text[0]) == 0xFF && std::uint8_t(text[1]) == 0xFE) ||
                             (std::uint8_t(text[0]) == 0xFE && std::uint8_t(text[1]) == 0xFF)))
        raise(FLT_ERR_FORMAT, "the GenICam XML is UTF-16 text; GenICam files are UTF-8");
    // The declaration, wherever it is: a device dump may put a line such as
    // "Vendor-Serial (USB3)" before it, and a byte-order mark may precede it.
    std::size_t start = text.find("<?xml");
    if (start == std::string::npos) {
        // No declaration: the document starts at its first markup.
        start = 0;
        while (start < text.size()) {
            start = text.find('<', start);
            if (start == std::string::npos || start + 1 >= text.size())
                break;
            const char next = text[start + 1];
            if ((next >= 'A' && next <= 'Z') || (next >= 'a' && next <= 'z') || next == '!' ||
                next == '_')
                break;
            ++start;
        }
        if (start == std::string::npos || start >= text.size())
            raise(FLT_ERR_FORMAT, "the GenICam file holds no XML element");
    }
    if (start > 0)
        text.erase(0, start);
    return text;
}

}  // namespace flt::genicam
