// SPDX-License-Identifier: Apache-2.0
// Internal: GigE Vision wire format - GVCP (control: commands, acks,
// bootstrap registers) and GVSP (stream: leader, payload, trailer) with the
// standard 16-bit block ids. Every multi-byte field is big-endian on the
// wire. README.md of this folder explains the protocol.
#pragma once

#include <cstddef>
#include <cstdint>

#include "sources/camera/byte_order.hpp"

namespace flt::gige {

// --- big-endian access (the wire order, whatever the host order) ----------
using sources::get_be16;
using sources::get_be32;
using sources::put_be16;
using sources::put_be32;

// --- GVCP -------------------------------------------------------------------
constexpr std::uint16_t k_gvcp_port = 3956;
constexpr std::size_t k_gvcp_header = 8;
constexpr std::uint8_t k_gvcp_key = 0x42;  // first byte of every command
constexpr std::uint8_t k_flag_ack_required = 0x01;
constexpr std::uint8_t k_flag_allow_broadcast_ack = 0x10;  // discovery
// Commands; the acknowledge of command c is c + 1.
constexpr std::uint16_t k_discovery_cmd = 0x0002;
constexpr std::uint16_t k_packet_resend_cmd = 0x0040;
constexpr std::uint16_t k_readreg_cmd = 0x0080;
constexpr std::uint16_t k_writereg_cmd = 0x0082;
constexpr std::uint16_t k_readmem_cmd = 0x0084;
constexpr std::uint16_t k_writemem_cmd = 0x0086;
constexpr std::uint16_t k_pending_ack = 0x0089;
// Acknowledge statuses with a meaning of their own (status_name() in
// control.cpp has the rest).
constexpr std::uint16_t k_status_busy = 0x8007;
// READMEM / WRITEMEM carry at most 536 bytes of data (a 576-byte datagram);
// 512 keeps requests and answers clear of every limit.
constexpr std::size_t k_memory_chunk = 512;
constexpr std::size_t k_discovery_data = 0xF8;  // the bootstrap block it carries

// --- bootstrap registers ----------------------------------------------------
namespace bootstrap {
constexpr std::uint32_t version = 0x0000;  // major << 16 | minor
constexpr std::uint32_t device_mode = 0x0004;
constexpr std::uint32_t mac_high = 0x0008, mac_low = 0x000C;
constexpr std::uint32_t current_ip = 0x0024;
constexpr std::uint32_t manufacturer = 0x0048;       // 32 bytes
constexpr std::uint32_t model = 0x0068;              // 32
constexpr std::uint32_t device_version = 0x0088;     // 32
constexpr std::uint32_t manufacturer_info = 0x00A8;  // 48
constexpr std::uint32_t serial = 0x00D8;             // 16
constexpr std::uint32_t user_name = 0x00E8;          // 16
constexpr std::uint32_t first_url = 0x0200;          // 512
constexpr std::uint32_t stream_channels = 0x0904;
constexpr std::uint32_t gvsp_capability = 0x092C;
constexpr std::uint32_t gvsp_capability_scsp = 1u << 31;  // SCSPx registers exist
constexpr std::uint32_t gvcp_capability = 0x0934;
constexpr std::uint32_t capability_packet_resend = 1u << 2;
constexpr std::uint32_t capability_pending_ack = 1u << 5;
constexpr std::uint32_t heartbeat_timeout = 0x0938;  // ms
constexpr std::uint32_t tick_frequency_high = 0x093C, tick_frequency_low = 0x0940;
constexpr std::uint32_t control_privilege = 0x0A00;  // CCP
constexpr std::uint32_t ccp_exclusive = 1u << 0, ccp_control = 1u << 1;
// Stream channel 0.
constexpr std::uint32_t scp = 0x0D00;   // host port (low 16 bits)
constexpr std::uint32_t scps = 0x0D04;  // packet size and flags
constexpr std::uint32_t scps_fire_test = 1u << 31;
constexpr std::uint32_t scps_do_not_fragment = 1u << 30;
constexpr std::uint32_t scps_size_mask = 0xFFFF;
constexpr std::uint32_t scpd = 0x0D08;  // inter-packet delay, ticks
constexpr std::uint32_t scda = 0x0D18;  // host address
constexpr std::uint32_t scsp = 0x0D1C;  // the camera's source port (low 16 bits; optional)
}  // namespace bootstrap

// --- GVSP -------------------------------------------------------------------
constexpr std::size_t k_gvsp_header = 8;  // status, block id, format, packet id
// IP (20) + UDP (8) + GVSP header: what a packet size counts beyond data.
constexpr std::size_t k_gvsp_overhead = 20 + 8 + k_gvsp_header;
constexpr std::size_t k_ip_udp_overhead = 20 + 8;
constexpr std::uint8_t k_format_leader = 1, k_format_trailer = 2, k_format_payload = 3;
constexpr std::uint16_t k_payload_image = 0x0001;
constexpr std::size_t k_image_leader_bytes = 36;  // after the GVSP header
constexpr std::size_t k_trailer_bytes = 8;
// Fields of an image leader, from the end of the GVSP header.
namespace leader {
constexpr std::size_t payload_type = 2;  // 16 bits
constexpr std::size_t timestamp = 4;     // 64 bits, in two words
constexpr std::size_t pixel_format = 12, width = 16, height = 20;
constexpr std::size_t padding_x = 32, padding_y = 34;  // 16 bits each
}  // namespace leader

}  // namespace flt::gige
