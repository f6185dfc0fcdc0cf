// SPDX-License-Identifier: Apache-2.0
// Internal: the frame accounting of a camera source, whatever its transport
// (USB3 Vision, GigE Vision): one counter per flt_source_counter,
// and why the last frame was dropped or lost. The protocol layers (control
// channel, stream) count into the one object their camera owns.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "core/log.hpp"
#include "flatline/source.h"

namespace flt::sources {

// Counters known to this build (a transport that adds counters appends
// them to flt_source_counter and this size follows).
constexpr std::size_t k_counters = std::size_t(FLT_COUNT_PACKETS_DUPLICATE) + 1;

struct frame_accounting {
    std::array<std::uint64_t, k_counters> counts{};
    std::string stream_error;  // why the last frame was dropped or lost

    std::uint64_t operator[](flt_source_counter which) const {
        return std::size_t(which) < counts.size() ? counts[std::size_t(which)] : 0;
    }
    void add(flt_source_counter which, std::uint64_t n = 1) {
        counts[std::size_t(which)] += n;
        // The faults and recoveries a log reader wants (flatline/log.h).
        if (which == FLT_COUNT_LOST)
            FLT_LOG(FLT_LOG_WARNING, "camera", "%llu frames lost (block ids skipped)",
                    (unsigned long long)n);
        else if (which == FLT_COUNT_DISCONNECTS)
            FLT_LOG(FLT_LOG_ERROR, "camera", "the camera was unplugged");
        else if (which == FLT_COUNT_STREAM_RECOVERIES)
            FLT_LOG(FLT_LOG_INFO, "camera", "recovered a camera found streaming");
        else if (which == FLT_COUNT_COMMAND_RETRIES)
            FLT_LOG(FLT_LOG_INFO, "camera", "a command got no answer: sent again");
    }
    // A frame that arrived damaged: its reason and DROPPED grow.
    void drop(flt_source_counter reason, const std::string &why) {
        add(reason);
        add(FLT_COUNT_DROPPED);
        stream_error = why;
        FLT_LOG(FLT_LOG_WARNING, "camera", "frame dropped: %s", why.c_str());
    }
};

}  // namespace flt::sources
