// SPDX-License-Identifier: Apache-2.0
#include "sources/encoder.hpp"

#include <cmath>

#include "core/error.hpp"
#include "core/options.hpp"

namespace flt::sources {

void encoder_positions::configure(const flt_options *options, bool kind_has_chunks) {
    mode_ = int(option_value(options, FLT_OPT_SOURCE_ENCODER_MODE));
    step_ = option_value(options, FLT_OPT_SOURCE_ENCODER_STEP);
    start_ = option_value(options, FLT_OPT_SOURCE_ENCODER_START);
    mm_per_count_ = option_value(options, FLT_OPT_SOURCE_ENCODER_MM_PER_COUNT);
    if (mode_ == encoder_chunk && !kind_has_chunks)
        raise(FLT_ERR_INVALID_ARGUMENT,
              "option 'source_encoder_mode' = 3 (chunk counter) needs a camera");
}

double encoder_positions::position_of(const raw_frame &frame) {
    if (mode_ == encoder_chunk) {
        if (!frame.has_chunk_counter)
            return std::numeric_limits<double>::quiet_NaN();
        // Unroll wraps of a 32-bit counter (a 64-bit one never wraps).
        const std::uint64_t c = frame.chunk_counter;
        if (!have_counter_) {
            counter_total_ =
                frame.chunk_counter_bytes == 4 ? std::int64_t(std::int32_t(c)) : std::int64_t(c);
        } else if (frame.chunk_counter_bytes == 4) {
            counter_total_ += std::int64_t(std::int32_t(std::uint32_t(c - last_counter_)));
        } else {
            counter_total_ = std::int64_t(c);
        }
        have_counter_ = true;
        last_counter_ = c;
        return start_ + mm_per_count_ * double(counter_total_);
    }
    if (!have_first_block_) {
        have_first_block_ = true;
        first_block_ = frame.block_id;
    }
    // Block ids count every frame the camera took, so frames lost on the
    // way keep their travel.
    const double fixed = start_ + step_ * double(frame.block_id - first_block_);
    switch (mode_) {
        case encoder_fixed:
            return fixed;
        case encoder_host:
            return host_mm_;
        default:
            return std::isnan(frame.own_encoder_mm) ? fixed : frame.own_encoder_mm;
    }
}

}  // namespace flt::sources
