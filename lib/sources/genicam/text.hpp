// SPDX-License-Identifier: Apache-2.0
// Internal: the text of a GenICam description - numbers as the XML writes
// them (locale-proof), the ZIP container, and what real files carry before
// the XML itself.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace flt::genicam {

// `text` without leading and trailing XML white space.
std::string_view trim(std::string_view text);

// An integer as GenICam writes it: optional sign, then decimal digits or
// 0x/0X and hex digits, surrounded by white space. False for anything else
// (also a decimal with a leading zero such as "010", which C reads as octal
// and the schema as decimal: such a file is ambiguous, not guessed at) and
// for values outside int64 (hex up to 0xFFFFFFFFFFFFFFFF is read as its
// two's complement bits, as registers and masks are written).
bool parse_int(std::string_view text, std::int64_t &out);

// A floating-point number ("1.5", "-2e-3", "0x10", "INF" is refused): the
// C locale's syntax whatever LC_NUMERIC says. Integers are accepted too.
bool parse_double(std::string_view text, double &out);

// Shortest text that reads back to the same double (std::to_chars).
std::string format_double(double value);

// The one file of a ZIP archive, inflated (stored or deflated entry; the
// CRC-32 is checked; at most 64 MiB). Throws flt::error(FLT_ERR_FORMAT)
// naming the problem.
std::string unzip_single(const std::uint8_t *zip, std::size_t bytes);

// True when `bytes` start like a ZIP archive (a local file header).
bool looks_zipped(const std::uint8_t *data, std::size_t bytes);

// The XML document in a description as devices and dumps deliver it: a
// UTF-8 byte-order mark, text before the XML declaration (a dump's "vendor
// serial (USB3)" line), or no declaration at all are tolerated; the result
// starts at the declaration or at the first '<'. Throws
// flt::error(FLT_ERR_FORMAT) for UTF-16 text and for text without any '<'.
std::string xml_document(std::string text);

}  // namespace flt::genicam
