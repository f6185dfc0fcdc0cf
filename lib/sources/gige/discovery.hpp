// SPDX-License-Identifier: Apache-2.0
// Internal: GigE Vision discovery - a DISCOVERY command broadcast (or sent
// to one address) on UDP port 3956 and the answers of the cameras that
// hear it, each carrying the head of its bootstrap registers.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sources/gige/socket.hpp"

namespace flt::gige {

struct camera_info {
    // flt_camera_string order: vendor, model, family (none on GigE Vision),
    // device version, manufacturer info, serial, user name.
    std::array<std::string, 7> strings;
    endpoint address;  // where it answered from (its GVCP port)
    std::uint32_t gev_version = 0;
    std::string mac;  // "00:11:22:33:44:55"
};

// The camera a discovery acknowledge (its data: the bootstrap block
// 0x0000..0x00F7) describes. FLT_ERR_FORMAT when too short.
camera_info parse_discovery(const std::uint8_t *data, std::size_t bytes, endpoint from);

// Sends a DISCOVERY command to `target` ("a.b.c.d" or "a.b.c.d:port", a
// camera or a subnet's broadcast address), or, when `target` is NULL, to
// 255.255.255.255 and to the broadcast address of every IPv4 interface,
// and gathers the answers for `timeout_ms`. One entry per camera address,
// in the order they answered. FLT_ERR_INVALID_ARGUMENT for a target that is
// no IPv4 address.
std::vector<camera_info> discover(const char *target, unsigned timeout_ms);

}  // namespace flt::gige
