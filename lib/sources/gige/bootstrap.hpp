// SPDX-License-Identifier: Apache-2.0
// Internal: the GigE Vision bootstrap registers (identity, capabilities,
// heartbeat, timestamp clock) and the device description the first URL
// register points to, read through the control channel.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "sources/gige/control.hpp"

namespace flt::gige {

struct bootstrap_info {
    std::array<std::string, 7> strings;  // flt_camera_string order
    std::uint32_t gev_version = 0;       // major << 16 | minor
    std::uint32_t capabilities = 0;      // GVCP capability register
    std::uint32_t stream_channels = 0;
    std::uint64_t tick_hz = 0;  // timestamp ticks per second (0: unknown)
    std::string first_url;
};

bootstrap_info read_bootstrap(control_channel &control);

struct device_description {
    std::string xml;               // the GenICam XML, unzipped
    std::uint64_t file_bytes = 0;  // the file as stored (zipped size)
    bool zipped = false;
};

// The GenICam file a "Local:name;address;length" URL names (hexadecimal
// address and length; a name ending in .zip is a ZIP). FLT_ERR_FORMAT for
// another kind of URL (a file on the host or a web address: not read) or
// one that makes no sense.
device_description read_description(sources::register_port &port, const std::string &url);

}  // namespace flt::gige
