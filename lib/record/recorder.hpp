// SPDX-License-Identifier: Apache-2.0
// Internal: the recording writer (flt_recorder). lib/record/README.md draws
// its buffers and its thread.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/coil.hpp"
#include "flatline/calib.h"
#include "flatline/extractor.h"
#include "flatline/record.h"
#include "record/recording_format.hpp"
#include "record/sqlite_db.hpp"

namespace flt::record {

// One row as its producer took it (besides the heights).
struct row_in {
    double encoder_mm = 0.0;
    std::int64_t time_ns = 0;  // host UTC, ns since 1970
    double left_mm = 0.0, right_mm = 0.0;
    std::uint32_t saturated = 0, peaks = 0, skipped_stop = 0, skipped_reversal = 0, dropped = 0,
                  missing = 0;
    std::uint8_t row_flags = 0, strip_flags = 0;
};

// The host's UTC clock, ns since 1970.
std::int64_t utc_now_ns();

class recorder {
  public:
    recorder(const std::string &path, const flt_calib *calib, const flt_options *options);
    ~recorder();
    recorder(const recorder &) = delete;
    recorder &operator=(const recorder &) = delete;

    std::size_t fibers() const { return K_; }
    double quantum() const { return quantum_; }
    double spacing() const { return spacing_; }

    // The row that follows. `flags` are the reconstructor's per fiber (0,
    // FLT_FLAG_INVALID_INPUT, FLT_FLAG_OFF_STRIP; nullptr: 0 where `valid`
    // is non-zero and height and slope are finite, else INVALID_INPUT),
    // `valid` the extractor's validity (nullptr: where the flag is 0). The
    // outputs (each may be nullptr, or alias the inputs) receive what the
    // recording holds: the heights and slopes quantized, the flags with
    // FLT_FLAG_INVALID_INPUT where a height is beyond k_max_height_mm.
    // No allocation. A row that finds no free block is counted lost.
    void add_row(const row_in &row, const double *height, const double *slope,
                 const std::uint8_t *flags, const std::uint8_t *valid, double *height_out,
                 double *slope_out, std::uint8_t *flags_out);
    // Events before the next row (before_row: the row number they precede,
    // or -1 for "the next row").
    void add_cut(double encoder_mm, std::int64_t before_row = -1);
    void add_coil(const flt_coil_info &coil, std::int64_t before_row = -1);
    void add_flush(std::int64_t before_row = -1);
    void add_note(const std::string &kind, const std::string &text, std::int64_t before_row = -1);
    // The options of the gauge that records (stored once; replaced).
    void set_gauge_options(const flt_options &effective);
    // Raw frames (record_frames), `row`: the row number of its profile.
    bool wants_frames() const { return frames_mode_ != FLT_RECORD_FRAMES_NONE; }
    void add_frame(const void *pixels, flt_pixel_format format, std::uint32_t width,
                   std::uint32_t height, std::size_t stride, double encoder_mm, std::uint64_t row);
    void save_frames();
    bool frames_on_fail() const { return frames_on_fail_; }

    // Waits until everything given is committed; FLT_ERR_TIMEOUT, or the
    // writer's failure (message set).
    flt_status sync(const char *fn, std::uint32_t timeout_ms);
    // FLT_OK, or the writer's failure (message set).
    flt_status failure(const char *fn) const;
    std::uint64_t count(flt_recorder_counter which) const;
    std::uint64_t rows_given() const;

    // A gauge that records through this recorder (one at a time).
    std::atomic<const void *> owner{nullptr};

  private:
    struct event {
        std::int64_t before_row = 0, time_ns = 0;
        int kind = 0;             // 0 cut, 1 coil, 2 flush, 3 gap, 4 note
        std::string label, text;  // note
        double encoder_mm = 0.0;
        std::uint64_t count = 0;
        std::unique_ptr<flt_coil_info> coil;
    };
    struct frame_entry {
        std::vector<std::uint8_t> pixels;  // packed rows
        flt_pixel_format format = FLT_PIXEL_MONO8;
        std::uint32_t width = 0, height = 0;
        double encoder_mm = 0.0;
        std::int64_t time_ns = 0;
        std::uint64_t row = 0;
        bool used = false;
    };

    void writer_main();
    void write_round(std::vector<row_block *> &blocks, std::vector<event> &events,
                     std::vector<frame_entry *> &frames);
    // With m_ held: the first failure's status and message (false when the
    // recorder had failed already).
    bool record_failure_locked(flt_status st, const char *message);
    void push_event(event &&e);
    row_block *open_block_locked();

    // configuration
    std::size_t K_ = 0, block_rows_ = 0;
    double quantum_ = 0.0, spacing_ = 0.0;
    std::chrono::milliseconds commit_interval_{250};
    int frames_mode_ = FLT_RECORD_FRAMES_NONE;
    double frame_seconds_ = 10.0;
    std::size_t frame_bytes_limit_ = 0;
    bool frames_on_fail_ = true;

    std::unique_ptr<sqlite_db> db_;

    mutable std::mutex m_;
    std::condition_variable writer_cv_, done_cv_;
    std::vector<std::unique_ptr<row_block>> blocks_;
    std::vector<row_block *> free_, closed_;
    row_block *open_ = nullptr;
    std::chrono::steady_clock::time_point open_since_{}, last_commit_{};
    std::deque<event> events_;
    // A row that finds no block (or whose caller wants no flags back) is
    // worked out here, under the lock.
    std::vector<std::uint8_t> scratch_flags_;
    std::vector<std::int32_t> scratch_q_[2];
    std::uint64_t rows_given_ = 0, rows_lost_ = 0, lost_run_start_ = 0, lost_run_ = 0;
    bool stop_ = false, sync_requested_ = false, save_frames_requested_ = false;
    std::uint64_t sync_generation_ = 0, committed_generation_ = 0;
    bool failed_ = false;
    flt_status failure_status_ = FLT_OK;
    std::string failure_message_;
    bool options_pending_ = false;
    std::vector<std::pair<int, double>> gauge_options_;
    // frames: a ring of entries (ring or all)
    std::vector<frame_entry> frame_ring_;
    std::size_t frame_head_ = 0, frame_count_ = 0;
    std::uint64_t frames_lost_ = 0;
    // counters (also read without the lock)
    std::atomic<std::uint64_t> rows_stored_{0}, blocks_stored_{0}, commits_{0}, bytes_{0},
        samples_{0}, frames_stored_{0}, events_stored_{0}, writer_ns_{0};

    std::thread writer_;
};

}  // namespace flt::record

struct flt_recorder {
    std::uint32_t magic = 0x52454352u;  // "RECR"
    std::unique_ptr<flt::record::recorder> impl;
};
