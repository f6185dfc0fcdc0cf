// SPDX-License-Identifier: Apache-2.0
// Internal: the public handles of the frame sources (flatline/source.h),
// shared by source_api.cpp and the kinds with public functions of their own
// (recording/recording_api.cpp).
#pragma once

#include <cstdint>
#include <limits>
#include <memory>

#include "flatline/source.h"
#include "sources/encoder.hpp"
#include "sources/source.hpp"

namespace flt {
constexpr std::uint32_t k_source_magic = 0x464c5443u;  // "FLTC"
constexpr std::uint32_t k_frame_magic = 0x464c5446u;   // "FLTF"
}  // namespace flt

struct flt_frame {
    std::uint32_t magic = flt::k_frame_magic;
    const void *pixels = nullptr;
    std::uint32_t width = 0, height = 0;
    std::size_t stride = 0;
    flt_pixel_format format = FLT_PIXEL_MONO8;
    std::uint64_t block_id = 0, timestamp_ns = 0;
    double encoder_mm = std::numeric_limits<double>::quiet_NaN();
    // A recording's frame: its profile row and events (else nullptr).
    const flt::sources::recorded_frame *recorded = nullptr;
};

struct flt_source {
    std::uint32_t magic = flt::k_source_magic;
    std::unique_ptr<flt::sources::source_impl> impl;
    flt::sources::encoder_positions encoder;
    bool started = false;
    flt_frame frame;
};
