// SPDX-License-Identifier: Apache-2.0
// Internal: the strip position of each frame (encoder_mm, mm of travel), the
// same for every kind of source. The modes are those of the option
// "source_encoder_mode" (flatline/source.h, "Encoder positions").
#pragma once

#include <cstdint>
#include <limits>

#include "flatline/common.h"
#include "sources/source.hpp"

namespace flt::sources {

enum encoder_mode { encoder_auto = 0, encoder_fixed = 1, encoder_host = 2, encoder_chunk = 3 };

class encoder_positions {
  public:
    // Reads source_encoder_mode/step/start/mm_per_count. Mode 3 (chunk)
    // needs a kind whose frames carry chunks: else throws
    // FLT_ERR_INVALID_ARGUMENT.
    void configure(const flt_options *options, bool kind_has_chunks);
    int mode() const { return mode_; }
    double mm_per_count() const { return mm_per_count_; }

    // Encoder mode 2: the position the next frames carry.
    void set_host(double encoder_mm) { host_mm_ = encoder_mm; }
    // A new acquisition: the fixed step counts from its first block again,
    // the chunk counter unrolls from its first value again.
    void restart() {
        have_first_block_ = false;
        have_counter_ = false;
    }
    // The position of `frame`, mm (NaN: mode 2 before the first
    // set_host(), mode 3 for a frame without the chunk).
    double position_of(const raw_frame &frame);

  private:
    int mode_ = encoder_auto;
    double step_ = 3.0, start_ = 0.0, mm_per_count_ = 0.01;
    double host_mm_ = std::numeric_limits<double>::quiet_NaN();
    bool have_first_block_ = false;
    std::uint64_t first_block_ = 0;
    bool have_counter_ = false;
    std::uint64_t last_counter_ = 0;
    std::int64_t counter_total_ = 0;
};

}  // namespace flt::sources
