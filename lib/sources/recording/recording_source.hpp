// SPDX-License-Identifier: Apache-2.0
// Internal: kind 5, a recording (lib/record) replayed as a frame source.
// Each recorded row is a frame; the gauge reads the row and everything the
// live gauge knew of it (edges, counters, flags) through recorded_frame.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "record/recording_format.hpp"
#include "record/recording_reader.hpp"
#include "sources/source.hpp"

namespace flt::sources {

struct recorded_frame {
    bool has_row = false;
    std::uint64_t row = 0;                     // its number in the recording
    const record::row_block *block = nullptr;  // the decoded block holding it
    std::size_t index = 0;                     // its row in the block
    double quantum = 0.0, spacing = 0.0;
    const record::recorded_event *events = nullptr;  // before this frame
    std::size_t event_count = 0;

    // The row as the gauge measured it (height, slope NaN where its flag
    // is not 0); any output may be nullptr.
    void row_values(std::size_t fibers, double *height, double *slope, std::uint8_t *flags,
                    std::uint8_t *valid) const;
};

std::unique_ptr<source_impl> make_recording_source(const std::string &path);
// The fiber count of a recording source's rows.
std::size_t recording_fibers(const source_impl &impl);

}  // namespace flt::sources
