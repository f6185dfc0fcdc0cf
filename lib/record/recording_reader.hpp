// SPDX-License-Identifier: Apache-2.0
// Internal: reading a recording (flt_recording, and the replay source in
// lib/sources/recording). The file is untrusted: every size is checked
// against the recording's own before anything is allocated.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/coil.hpp"
#include "core/options.hpp"
#include "flatline/extractor.h"
#include "record/recording_format.hpp"
#include "record/sqlite_db.hpp"

namespace flt::record {

struct recorded_event {
    std::int64_t before_row = 0, time_ns = 0;
    enum kind_t { cut, coil, flush, gap, note, other } kind = other;
    std::string label, text;  // note
    double encoder_mm = 0.0;
    std::uint64_t count = 0;
    std::shared_ptr<flt_coil_info> coil_info;  // kind coil
};

struct block_entry {
    std::int64_t id = 0;
    std::uint64_t first_row = 0, rows = 0;
    std::int64_t first_time_ns = 0, last_time_ns = 0;
    double first_encoder_mm = 0.0, last_encoder_mm = 0.0;
};

struct frame_entry_info {
    std::int64_t id = 0;
    std::uint64_t row = 0;
};

class recording_reader {
  public:
    explicit recording_reader(const std::string &path);

    std::size_t fibers() const { return K_; }
    double quantum() const { return quantum_; }
    double spacing() const { return spacing_; }
    int version() const { return version_; }
    const std::string &calibration_text() const { return calibration_; }
    bool has_gauge_options() const { return has_options_; }
    const flt_options &gauge_options() const { return options_; }
    const std::vector<block_entry> &blocks() const { return blocks_; }
    const std::vector<recorded_event> &events() const { return events_; }
    const std::vector<frame_entry_info> &frames() const { return frames_; }
    std::uint64_t rows() const { return rows_; }
    std::uint64_t rows_lost() const { return rows_lost_; }
    std::uint64_t block_bytes() const { return block_bytes_; }

    // Block `index` (of blocks()), CRC checked, decoded into b.
    void load_block(std::size_t index, row_block &b, block_scratch &scratch);
    // Frame `index` (of frames()): its pixels (packed rows), format, size,
    // encoder position and time.
    void load_frame(std::size_t index, std::vector<std::uint8_t> &pixels, flt_pixel_format &format,
                    std::uint32_t &width, std::uint32_t &height, double &encoder_mm,
                    std::int64_t &time_ns);
    // The index of the block holding row `row`, or blocks().size().
    std::size_t block_of_row(std::uint64_t row) const;

  private:
    std::unique_ptr<sqlite_db> db_;
    std::size_t K_ = 0;
    double quantum_ = 0.0, spacing_ = 0.0;
    int version_ = 0;
    std::uint32_t frame_width_ = 0, frame_height_ = 0;
    std::string calibration_;
    bool has_options_ = false;
    flt_options options_{};
    std::vector<block_entry> blocks_;
    std::vector<recorded_event> events_;
    std::vector<frame_entry_info> frames_;
    std::uint64_t rows_ = 0, rows_lost_ = 0, block_bytes_ = 0;
    std::vector<std::uint8_t> payload_;
};

}  // namespace flt::record

struct flt_recording {
    std::uint32_t magic = 0x52454344u;  // "RECD"
    std::unique_ptr<flt::record::recording_reader> impl;
    // Decoding state of flt_recording_read_rows (one block cached).
    flt::record::row_block block;
    flt::record::block_scratch scratch;
    std::size_t cached = std::size_t(-1);
};
