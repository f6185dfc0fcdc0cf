// SPDX-License-Identifier: Apache-2.0
// Internal: the USB3 Vision bootstrap registers (ABRM, SBRM) and the
// device description (the manifest table and the GenICam file it points
// to), read through the control channel.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "sources/u3v/control.hpp"

namespace flt::u3v {

struct bootstrap_info {
    std::array<std::string, 7> strings;  // flt_camera_string order
    std::uint32_t gencp_version = 0, u3v_version = 0, response_ms = 0;
    std::uint64_t manifest_address = 0, sbrm_address = 0;
    std::uint64_t sirm_address = 0;  // 0: no stream channel
};

// Reads SBRM (transfer limits first, with 8-byte requests) and ABRM, and
// gives the control channel the device's limits and response time. Throws
// FLT_ERR_FORMAT for limits too small for GenCP.
bootstrap_info read_bootstrap(control_channel &control);

struct device_description {
    std::string xml;               // the GenICam XML, unzipped
    std::uint64_t file_bytes = 0;  // the file as stored (zipped size)
    bool zipped = false;
};

// The first GenICam file of the manifest table (raw XML or ZIP). Throws
// FLT_ERR_FORMAT for a table or file that makes no sense.
device_description read_description(sources::register_port &port, std::uint64_t manifest_address);

}  // namespace flt::u3v
