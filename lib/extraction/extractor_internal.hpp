// SPDX-License-Identifier: Apache-2.0
// Internal: what other components of the library (the gauge) may ask of an
// extractor that its public header does not say, in C++.
#pragma once

#include <cstddef>
#include <cstdint>

#include "flatline/extractor.h"

namespace flt {

// What the last frame processed showed besides its profile row: the values
// flt_extractor_fiber_flags, flt_extractor_strip(laser 2) and
// flt_extractor_saturation(laser 2) give, read at once without the API's
// checks. The caller keeps the API's contract: a frame was processed
// successfully since the extractor was made.
struct extractor_frame_view {
    const std::uint8_t *fiber_flags = nullptr;  // per fiber: 0, INVALID_INPUT or OFF_STRIP
    double left_mm = 0.0, right_mm = 0.0;       // the row's strip edges, sensor x (NaN: not seen)
    unsigned strip_flags = 0;                   // FLT_STRIP_* of the row
    std::size_t peaks = 0, saturated = 0;       // both lasers' peaks on the strip
};
extractor_frame_view extractor_frame_of(const flt_extractor *extractor);

}  // namespace flt
