// SPDX-License-Identifier: Apache-2.0
// Internal: the recording file (docs/record.md is the reader's
// specification; keep the two in step): its tables, and one block of rows
// in memory, encoded and decoded.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace flt::record {

constexpr std::int32_t k_recording_application_id = 0x464C5452;  // "FLTR"
constexpr int k_recording_version = 1;
constexpr std::uint32_t k_block_magic = 0x42524C46u;  // "FLRB", little-endian
constexpr int k_block_codec = 1;
constexpr std::size_t k_max_block_rows = 4096;
// The largest height a recording holds, mm: 2^31 quanta of the coarsest
// quantum would be more, so every quantized value fits an int32.
constexpr double k_max_height_mm = 1.0e5;

// Row flags (the block's row_flags byte).
enum : std::uint8_t {
    k_row_new_strip = 1,      // a long reversal before it started a new strip
    k_row_from_frame = 2,     // extracted from a camera frame (else pushed as a row)
    k_row_extract_error = 4,  // the extractor refused the frame
};
// A fiber's state byte: the reconstructor's flag (0, FLT_FLAG_INVALID_INPUT
// or FLT_FLAG_OFF_STRIP) in the low bits, the extractor's validity in bit 7.
constexpr std::uint8_t k_state_valid = 0x80;
constexpr std::uint8_t k_state_flag_mask = 0x0F;

// One block of rows: what the gauge's sequencer knew of each row. The
// producer fills it; the writer encodes it; the reader decodes into it.
struct row_block {
    std::size_t fibers = 0, capacity = 0, rows = 0;
    std::uint64_t first_row = 0;
    std::vector<double> encoder_mm, left_mm, right_mm;
    std::vector<std::int64_t> time_ns;
    std::vector<std::uint32_t> saturated, peaks, skipped_stop, skipped_reversal, dropped, missing;
    std::vector<std::uint8_t> row_flags, strip_flags;
    std::vector<std::uint8_t> state;  // [capacity * fibers]
    std::vector<std::int32_t> q[2];   // [capacity * fibers]: behind, ahead
    void allocate(std::size_t fibers_, std::size_t capacity_);
};

// Scratch the encoder keeps between blocks (no allocation once grown).
struct block_scratch {
    std::vector<std::uint8_t> side, unary, binary;
    std::vector<std::uint64_t> values, escapes;
};

// The block's payload (docs/record.md, "Block payload").
void encode_block(const row_block &b, double quantum_mm, block_scratch &scratch,
                  std::vector<std::uint8_t> &payload);
// Decodes a payload into b (allocated for `fibers` and up to
// k_max_block_rows rows); throws FLT_ERR_FORMAT naming `what`.
void decode_block(const std::uint8_t *payload, std::size_t size, std::size_t fibers,
                  double quantum_mm, row_block &b, block_scratch &scratch, const char *what);

// A laser height's quantized value (|z| <= k_max_height_mm), rounded
// half away from zero; inverse_quantum = 1 / quantum (a power of two:
// exact).
inline std::int32_t quantize(double z_mm, double inverse_quantum) {
    const double t = z_mm * inverse_quantum;
    return std::int32_t(t + (t >= 0.0 ? 0.5 : -0.5));  // truncation after +-0.5
}
// The row the gauge measures from two quantized laser heights: the same
// function live and in a replay, hence the same doubles.
inline void dequantize(std::int32_t behind, std::int32_t ahead, double quantum_mm,
                       double spacing_mm, double *height, double *slope) {
    const double zb = double(behind) * quantum_mm, za = double(ahead) * quantum_mm;
    *height = (zb + za) * 0.5;
    *slope = (za - zb) / spacing_mm;
}

// True for a power of two within the option's range.
bool is_power_of_two(double v);

// The tables of a new recording (docs/record.md, "Tables").
extern const char *const k_recording_schema;

}  // namespace flt::record
