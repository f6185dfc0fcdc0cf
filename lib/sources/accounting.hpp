// SPDX-License-Identifier: Apache-2.0
// Internal: the frame accounting of a camera source, whatever its transport
// (USB3 Vision, GigE Vision): one counter per flt_source_counter,
// and why the last frame was dropped or lost. The protocol layers (control
// channel, stream) count into the one object their camera owns.
#pragma once

#include <array>
#include <cstdint>
#include <string>

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
    void add(flt_source_counter which, std::uint64_t n = 1) { counts[std::size_t(which)] += n; }
    // A frame that arrived damaged: its reason and DROPPED grow.
    void drop(flt_source_counter reason, const std::string &why) {
        add(reason);
        add(FLT_COUNT_DROPPED);
        stream_error = why;
    }
};

}  // namespace flt::sources
