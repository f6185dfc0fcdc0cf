// SPDX-License-Identifier: Apache-2.0
// Internal: USB3 Vision wire format (GenCP over USB, bootstrap registers,
// stream leader and trailer). Values from the U3V standard, summarised in
// docs/usb3vision.md; all multi-byte fields are little-endian on the wire.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "sources/camera/byte_order.hpp"
#include "sources/camera/pixel_format.hpp"

namespace flt::u3v {

// --- little-endian access (the wire order, whatever the host order) ------
// (camera/byte_order.hpp, under the names this folder has always used)
inline std::uint16_t get_u16(const std::uint8_t *p) {
    return sources::get_le16(p);
}
inline std::uint32_t get_u32(const std::uint8_t *p) {
    return sources::get_le32(p);
}
inline std::uint64_t get_u64(const std::uint8_t *p) {
    return sources::get_le64(p);
}
inline void put_u16(std::uint8_t *p, std::uint16_t v) {
    sources::put_le16(p, v);
}
inline void put_u32(std::uint8_t *p, std::uint32_t v) {
    sources::put_le32(p, v);
}
inline void put_u64(std::uint8_t *p, std::uint64_t v) {
    sources::put_le64(p, v);
}
inline std::uint64_t get_uint(const std::uint8_t *p, std::size_t length) {
    return sources::get_le(p, length);
}
inline void put_uint(std::uint8_t *p, std::size_t length, std::uint64_t v) {
    sources::put_le(p, length, v);
}

// --- USB class codes --------------------------------------------------------
constexpr std::uint8_t k_class_misc = 0xEF;
constexpr std::uint8_t k_subclass_iad = 0x02;
constexpr std::uint8_t k_protocol_iad = 0x01;
constexpr std::uint8_t k_subclass_u3v = 0x05;
constexpr std::uint8_t k_protocol_control = 0x00;
constexpr std::uint8_t k_protocol_event = 0x01;
constexpr std::uint8_t k_protocol_stream = 0x02;
constexpr std::uint8_t k_desc_device_info = 0x24;  // class-specific descriptor
constexpr std::uint8_t k_desc_subtype_info = 0x01;
constexpr std::size_t k_device_info_min_length = 20;

// --- GenCP ------------------------------------------------------------------
constexpr std::uint32_t k_prefix_control = 0x43563355u;  // "U3VC"
constexpr std::size_t k_gencp_header = 12;
constexpr std::uint16_t k_flag_request_ack = 0x4000;
constexpr std::uint16_t k_cmd_readmem = 0x0800;
constexpr std::uint16_t k_ack_readmem = 0x0801;
constexpr std::uint16_t k_cmd_writemem = 0x0802;
constexpr std::uint16_t k_ack_writemem = 0x0803;
constexpr std::uint16_t k_ack_pending = 0x0805;
constexpr std::size_t k_readmem_body = 12;       // u64 address, u16 0, u16 count
constexpr std::size_t k_writemem_overhead = 20;  // header + u64 address

enum gencp_status : std::uint16_t {
    gencp_ok = 0x0000,
    gencp_not_implemented = 0x8001,
    gencp_invalid_parameter = 0x8002,
    gencp_invalid_address = 0x8003,
    gencp_write_protect = 0x8004,
    gencp_bad_alignment = 0x8005,
    gencp_access_denied = 0x8006,
    gencp_busy = 0x8007,
    gencp_timeout = 0x800B,
    gencp_invalid_header = 0x800E,
    gencp_wrong_config = 0x800F,
    gencp_generic = 0x8FFF,
    u3v_resend_not_supported = 0xA001,
    u3v_stream_halted = 0xA002,
    u3v_payload_not_aligned = 0xA003,
    u3v_si_inconsistent = 0xA004,
    u3v_data_discarded = 0xA100,
    u3v_data_overrun = 0xA101,
};

inline const char *gencp_status_name(std::uint16_t status) {
    switch (status) {
        case gencp_ok:
            return "ok";
        case gencp_not_implemented:
            return "not implemented";
        case gencp_invalid_parameter:
            return "invalid parameter";
        case gencp_invalid_address:
            return "invalid address";
        case gencp_write_protect:
            return "write protect";
        case gencp_bad_alignment:
            return "bad alignment";
        case gencp_access_denied:
            return "access denied";
        case gencp_busy:
            return "busy";
        case gencp_timeout:
            return "timeout";
        case gencp_invalid_header:
            return "invalid header";
        case gencp_wrong_config:
            return "wrong config";
        case gencp_generic:
            return "generic error";
        case u3v_resend_not_supported:
            return "resend not supported";
        case u3v_stream_halted:
            return "stream endpoint halted";
        case u3v_payload_not_aligned:
            return "payload size not aligned";
        case u3v_si_inconsistent:
            return "SI registers inconsistent";
        case u3v_data_discarded:
            return "data discarded";
        case u3v_data_overrun:
            return "data overrun";
    }
    return "unknown status";
}

// --- bootstrap registers -------------------------------------------------------
namespace abrm {
constexpr std::uint64_t gencp_version = 0x000;
constexpr std::uint64_t manufacturer = 0x004;
constexpr std::uint64_t model = 0x044;
constexpr std::uint64_t family = 0x084;
constexpr std::uint64_t device_version = 0x0C4;
constexpr std::uint64_t manufacturer_info = 0x104;
constexpr std::uint64_t serial = 0x144;
constexpr std::uint64_t user_name = 0x184;
constexpr std::size_t string_length = 64;
constexpr std::uint64_t capability = 0x1C4;
constexpr std::uint64_t response_time = 0x1CC;
constexpr std::uint64_t manifest_address = 0x1D0;
constexpr std::uint64_t sbrm_address = 0x1D8;
constexpr std::uint64_t size = 0x210;
}  // namespace abrm

namespace sbrm {
constexpr std::uint64_t u3v_version = 0x00;
constexpr std::uint64_t max_command = 0x14;
constexpr std::uint64_t max_ack = 0x18;
constexpr std::uint64_t stream_channels = 0x1C;
constexpr std::uint64_t sirm_address = 0x20;
constexpr std::uint64_t sirm_length = 0x28;
constexpr std::uint64_t current_speed = 0x40;
constexpr std::uint64_t size = 0x44;
}  // namespace sbrm

namespace sirm {
constexpr std::uint64_t info = 0x00;
constexpr std::uint64_t control = 0x04;
constexpr std::uint64_t required_payload = 0x08;
constexpr std::uint64_t required_leader = 0x10;
constexpr std::uint64_t required_trailer = 0x14;
constexpr std::uint64_t max_leader = 0x18;
constexpr std::uint64_t transfer_size = 0x1C;
constexpr std::uint64_t transfer_count = 0x20;
constexpr std::uint64_t final1_size = 0x24;
constexpr std::uint64_t final2_size = 0x28;
constexpr std::uint64_t max_trailer = 0x2C;
constexpr std::uint64_t size = 0x30;
constexpr std::uint32_t control_enable = 1;
}  // namespace sirm

// --- stream ---------------------------------------------------------------------
constexpr std::uint32_t k_magic_leader = 0x4C563355u;   // "U3VL"
constexpr std::uint32_t k_magic_trailer = 0x54563355u;  // "U3VT"
constexpr std::size_t k_leader_image_size = 52;
constexpr std::size_t k_trailer_min_size = 32;
// The largest leader or trailer a camera may ask for in SIRM: real ones
// are 52 .. a few hundred bytes; more would size every host transfer.
constexpr std::uint32_t k_max_leader_trailer = 65536;
constexpr std::uint16_t k_payload_image = 0x0001;
constexpr std::uint16_t k_payload_image_chunk = 0x4001;  // image + chunk data
constexpr std::uint16_t k_payload_chunk = 0x4000;

// PFNC pixel formats (camera/pixel_format.hpp: the same on every transport).
using sources::k_pfnc_mono10;
using sources::k_pfnc_mono12;
using sources::k_pfnc_mono16;
using sources::k_pfnc_mono8;
using sources::pfnc_bits;
using sources::pfnc_of_bits;

}  // namespace flt::u3v
