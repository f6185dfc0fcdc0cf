// SPDX-License-Identifier: Apache-2.0
// Internal: reading and writing integers of a given byte order from and to
// byte buffers, whatever the host's order. USB3 Vision puts every field on
// the wire little-endian, GigE Vision big-endian; a GenICam register says
// its own (Endianess). Buffers are never cast to integer types.
#pragma once

#include <cstddef>
#include <cstdint>

namespace flt::sources {

// --- little-endian --------------------------------------------------------
inline std::uint16_t get_le16(const std::uint8_t *p) {
    return std::uint16_t(p[0] | (p[1] << 8));
}
inline std::uint32_t get_le32(const std::uint8_t *p) {
    return std::uint32_t(p[0]) | (std::uint32_t(p[1]) << 8) | (std::uint32_t(p[2]) << 16) |
           (std::uint32_t(p[3]) << 24);
}
inline std::uint64_t get_le64(const std::uint8_t *p) {
    return std::uint64_t(get_le32(p)) | (std::uint64_t(get_le32(p + 4)) << 32);
}
inline void put_le16(std::uint8_t *p, std::uint16_t v) {
    p[0] = std::uint8_t(v);
    p[1] = std::uint8_t(v >> 8);
}
inline void put_le32(std::uint8_t *p, std::uint32_t v) {
    for (int i = 0; i < 4; ++i)
        p[i] = std::uint8_t(v >> (8 * i));
}
inline void put_le64(std::uint8_t *p, std::uint64_t v) {
    for (int i = 0; i < 8; ++i)
        p[i] = std::uint8_t(v >> (8 * i));
}
// An unsigned little-endian integer of 1..8 bytes.
inline std::uint64_t get_le(const std::uint8_t *p, std::size_t length) {
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < length && i < 8; ++i)
        v |= std::uint64_t(p[i]) << (8 * i);
    return v;
}
inline void put_le(std::uint8_t *p, std::size_t length, std::uint64_t v) {
    for (std::size_t i = 0; i < length && i < 8; ++i)
        p[i] = std::uint8_t(v >> (8 * i));
}

// --- big-endian -----------------------------------------------------------
inline std::uint16_t get_be16(const std::uint8_t *p) {
    return std::uint16_t((p[0] << 8) | p[1]);
}
inline std::uint32_t get_be32(const std::uint8_t *p) {
    return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) |
           std::uint32_t(p[3]);
}
inline void put_be16(std::uint8_t *p, std::uint16_t v) {
    p[0] = std::uint8_t(v >> 8);
    p[1] = std::uint8_t(v);
}
inline void put_be32(std::uint8_t *p, std::uint32_t v) {
    for (int i = 0; i < 4; ++i)
        p[i] = std::uint8_t(v >> (24 - 8 * i));
}

}  // namespace flt::sources
