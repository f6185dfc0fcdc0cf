// SPDX-License-Identifier: Apache-2.0
// The simulator as a frame source: each next() renders the simulator's next
// frame into the one buffer allocated at creation. Nothing is lost, so the
// only counter is FRAMES; block ids count frames from 0.
#include "sources/sim/sim_source.hpp"

#include <chrono>
#include <vector>

#include "core/error.hpp"

namespace flt::sources {

namespace {

std::uint64_t host_ns() {
    return std::uint64_t(std::chrono::duration_cast<std::chrono::nanoseconds>(
                             std::chrono::steady_clock::now().time_since_epoch())
                             .count());
}

class sim_source final : public source_impl {
  public:
    sim_source(flt_sim *sim, std::uint32_t width, std::uint32_t height, flt_pixel_format format)
        : sim_(sim), width_(width), height_(height), format_(format),
          stride_(std::size_t(width) * (format > 8 ? 2 : 1)), pixels_(stride_ * height, 0) {}

    flt_source_kind kind() const override { return FLT_SOURCE_SIMULATOR; }
    void start() override {}
    void stop() override {}

    bool next(unsigned /*timeout_ms*/, raw_frame &out) override {
        double encoder_mm = 0.0;
        if (flt_sim_next_frame(sim_, pixels_.data(), pixels_.size(), stride_, &encoder_mm, 0,
                               nullptr, nullptr, 0) != FLT_OK)
            raise(flt_last_error_status(), "the simulator failed: %s", flt_last_error_message());
        out.pixels = pixels_.data();
        out.bytes = pixels_.size();
        out.width = width_;
        out.height = height_;
        out.stride = stride_;
        out.format = format_;
        out.block_id = next_index_++;
        out.timestamp_ns = host_ns();
        out.own_encoder_mm = encoder_mm;
        return true;
    }

    std::uint64_t count(flt_source_counter which) const override {
        // The simulator loses nothing: only delivered frames count.
        return which == FLT_COUNT_FRAMES ? next_index_ : 0;
    }

  private:
    flt_sim *sim_;
    std::uint32_t width_, height_;
    flt_pixel_format format_;
    std::size_t stride_;
    std::vector<std::uint8_t> pixels_;
    std::uint64_t next_index_ = 0;
};

}  // namespace

std::unique_ptr<source_impl> make_sim_source(flt_sim *sim) {
    std::uint32_t w = 0, h = 0;
    flt_pixel_format format = FLT_PIXEL_MONO8;
    if (flt_sim_frame_size(sim, &w, &h) != FLT_OK || flt_sim_pixel_format(sim, &format) != FLT_OK)
        raise(FLT_ERR_INVALID_ARGUMENT, "argument 'sim': %s", flt_last_error_message());
    return std::make_unique<sim_source>(sim, w, h, format);
}

}  // namespace flt::sources
