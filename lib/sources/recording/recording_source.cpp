// SPDX-License-Identifier: Apache-2.0
#include "sources/recording/recording_source.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/error.hpp"

namespace flt::sources {
namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

class recording_source final : public source_impl {
  public:
    explicit recording_source(const std::string &path)
        : reader_(std::make_unique<record::recording_reader>(path)) {
        const auto &frames = reader_->frames();
        for (std::size_t i = 0; i < frames.size(); ++i)
            frame_order_.push_back(i);
        std::stable_sort(
            frame_order_.begin(), frame_order_.end(),
            [&](std::size_t a, std::size_t b) { return frames[a].row < frames[b].row; });
    }
    flt_source_kind kind() const override { return FLT_SOURCE_RECORDING; }
    void start() override {
        block_ = 0;
        in_block_ = 0;
        loaded_ = std::size_t(-1);
        event_ = 0;
        frame_at_ = 0;
        ended_ = false;
        delivered_ = 0;
    }
    void stop() override {}
    bool next(unsigned /*timeout_ms*/, raw_frame &out) override {
        const auto &blocks = reader_->blocks();
        const auto &events = reader_->events();
        while (block_ < blocks.size() && in_block_ >= blocks[block_].rows) {
            ++block_;
            in_block_ = 0;
        }
        current_ = recorded_frame{};
        current_.quantum = reader_->quantum();
        current_.spacing = reader_->spacing();
        out = raw_frame{};
        out.recorded = &current_;
        if (block_ >= blocks.size()) {
            // After the last row: the events recorded after it, once.
            if (ended_ || event_ >= events.size())
                return false;
            ended_ = true;
            current_.events = &events[event_];
            current_.event_count = events.size() - event_;
            event_ = events.size();
            out.own_encoder_mm = last_encoder_;
            out.block_id = next_row_;
            out.timestamp_ns = std::uint64_t(std::max<std::int64_t>(0, last_time_));
            return true;
        }
        if (loaded_ != block_) {
            loaded_ = std::size_t(-1);
            reader_->load_block(block_, rows_, scratch_);
            loaded_ = block_;
        }
        const std::uint64_t row = blocks[block_].first_row + in_block_;
        std::size_t first_event = event_;
        while (event_ < events.size() && events[event_].before_row <= std::int64_t(row))
            ++event_;
        current_.has_row = true;
        current_.row = row;
        current_.block = &rows_;
        current_.index = in_block_;
        current_.events = event_ > first_event ? &events[first_event] : nullptr;
        current_.event_count = event_ - first_event;
        out.own_encoder_mm = rows_.encoder_mm[in_block_];
        out.block_id = row;
        out.timestamp_ns = std::uint64_t(std::max<std::int64_t>(0, rows_.time_ns[in_block_]));
        last_encoder_ = out.own_encoder_mm;
        last_time_ = rows_.time_ns[in_block_];
        next_row_ = row + 1;
        // The camera frame of this row, when the recorder kept it.
        const auto &frames = reader_->frames();
        while (frame_at_ < frame_order_.size() && frames[frame_order_[frame_at_]].row < row)
            ++frame_at_;
        if (frame_at_ < frame_order_.size() && frames[frame_order_[frame_at_]].row == row) {
            double e = 0;
            std::int64_t t = 0;
            reader_->load_frame(frame_order_[frame_at_], pixels_, format_, width_, height_, e, t);
            out.pixels = pixels_.data();
            out.width = width_;
            out.height = height_;
            out.format = format_;
            out.stride = std::size_t(width_) * (format_ == FLT_PIXEL_MONO8 ? 1 : 2);
            ++frame_at_;
        }
        ++in_block_;
        ++delivered_;
        return true;
    }
    std::uint64_t count(flt_source_counter which) const override {
        return which == FLT_COUNT_FRAMES ? delivered_ : 0;
    }
    std::size_t fibers() const { return reader_->fibers(); }

  private:
    std::unique_ptr<record::recording_reader> reader_;
    std::vector<std::size_t> frame_order_;
    record::row_block rows_;
    record::block_scratch scratch_;
    std::size_t block_ = 0, in_block_ = 0, loaded_ = std::size_t(-1), event_ = 0, frame_at_ = 0;
    bool ended_ = false;
    std::uint64_t delivered_ = 0, next_row_ = 0;
    double last_encoder_ = k_nan;
    std::int64_t last_time_ = 0;
    recorded_frame current_;
    std::vector<std::uint8_t> pixels_;
    flt_pixel_format format_ = FLT_PIXEL_MONO8;
    std::uint32_t width_ = 0, height_ = 0;
};

}  // namespace

void recorded_frame::row_values(std::size_t fibers, double *height, double *slope,
                                std::uint8_t *flags, std::uint8_t *valid) const {
    const std::size_t base = index * fibers;
    for (std::size_t k = 0; k < fibers; ++k) {
        const std::uint8_t state = block->state[base + k];
        const std::uint8_t flag = state & record::k_state_flag_mask;
        double h = k_nan, s = k_nan;
        if (flag == 0)
            record::dequantize(block->q[0][base + k], block->q[1][base + k], quantum, spacing, &h,
                               &s);
        if (height)
            height[k] = h;
        if (slope)
            slope[k] = s;
        if (flags)
            flags[k] = flag;
        if (valid)
            valid[k] = (state & record::k_state_valid) ? 1 : 0;
    }
}

std::unique_ptr<source_impl> make_recording_source(const std::string &path) {
    return std::make_unique<recording_source>(path);
}

std::size_t recording_fibers(const source_impl &impl) {
    return static_cast<const recording_source &>(impl).fibers();
}

}  // namespace flt::sources
