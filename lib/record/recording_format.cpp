// SPDX-License-Identifier: Apache-2.0
#include "record/recording_format.hpp"

#include <cstring>

#include "core/error.hpp"
#include "record/codec.hpp"

namespace flt::record {

const char *const k_recording_schema = R"sql(
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE gauge_options (name TEXT PRIMARY KEY, key INTEGER NOT NULL, value REAL NOT NULL);
CREATE TABLE blocks (
  block INTEGER PRIMARY KEY,
  first_row INTEGER NOT NULL,
  rows INTEGER NOT NULL,
  first_time_ns INTEGER NOT NULL,
  last_time_ns INTEGER NOT NULL,
  first_encoder_mm REAL NOT NULL,
  last_encoder_mm REAL NOT NULL,
  codec INTEGER NOT NULL,
  crc32 INTEGER NOT NULL,
  payload BLOB NOT NULL);
CREATE UNIQUE INDEX blocks_by_row ON blocks (first_row);
CREATE TABLE events (
  event INTEGER PRIMARY KEY,
  before_row INTEGER NOT NULL,
  time_ns INTEGER NOT NULL,
  kind TEXT NOT NULL,
  encoder_mm REAL,
  count INTEGER,
  label TEXT,
  text TEXT);
CREATE INDEX events_by_row ON events (before_row);
CREATE TABLE coils (
  event INTEGER PRIMARY KEY,
  coil_id TEXT NOT NULL,
  order_no TEXT NOT NULL,
  heat TEXT NOT NULL,
  grade TEXT NOT NULL,
  customer TEXT NOT NULL,
  nominal_thickness_mm REAL NOT NULL,
  nominal_width_mm REAL NOT NULL);
CREATE TABLE coil_extras (
  event INTEGER NOT NULL,
  position INTEGER NOT NULL,
  key TEXT NOT NULL,
  value TEXT NOT NULL,
  PRIMARY KEY (event, position));
CREATE TABLE frames (
  frame INTEGER PRIMARY KEY,
  row INTEGER NOT NULL,
  time_ns INTEGER NOT NULL,
  encoder_mm REAL NOT NULL,
  format INTEGER NOT NULL,
  width INTEGER NOT NULL,
  height INTEGER NOT NULL,
  codec INTEGER NOT NULL,
  crc32 INTEGER NOT NULL,
  pixels BLOB NOT NULL);
CREATE INDEX frames_by_row ON frames (row);
)sql";

void row_block::allocate(std::size_t fibers_, std::size_t capacity_) {
    fibers = fibers_;
    capacity = capacity_;
    rows = 0;
    for (auto *v : {&encoder_mm, &left_mm, &right_mm})
        v->assign(capacity, 0.0);
    time_ns.assign(capacity, 0);
    for (auto *v : {&saturated, &peaks, &skipped_stop, &skipped_reversal, &dropped, &missing})
        v->assign(capacity, 0);
    row_flags.assign(capacity, 0);
    strip_flags.assign(capacity, 0);
    state.assign(capacity * fibers, 0);
    q[0].assign(capacity * fibers, 0);
    q[1].assign(capacity * fibers, 0);
}

bool is_power_of_two(double v) {
    if (!(v > 0.0) || !std::isfinite(v))
        return false;
    int e = 0;
    return std::frexp(v, &e) == 0.5;
}

namespace {

template <class T> void put_array(std::vector<std::uint8_t> &out, const T *v, std::size_t n) {
    // Little-endian on every platform the library builds for (x86-64,
    // AArch64): the bytes as they are.
    const auto *b = reinterpret_cast<const std::uint8_t *>(v);
    out.insert(out.end(), b, b + n * sizeof(T));
}

template <class T> void get_array(byte_reader &r, T *v, std::size_t n) {
    std::memcpy(v, r.bytes(n * sizeof(T)), n * sizeof(T));
}

}  // namespace

void encode_block(const row_block &b, double quantum_mm, block_scratch &s,
                  std::vector<std::uint8_t> &payload) {
    const std::size_t R = b.rows, K = b.fibers;
    payload.clear();
    put_u32(payload, k_block_magic);
    put_u32(payload, std::uint32_t(R));
    put_u32(payload, std::uint32_t(K));
    put_f64(payload, quantum_mm);
    // Side data, deflated: per row, then every fiber's state.
    s.side.clear();
    put_array(s.side, b.encoder_mm.data(), R);
    put_array(s.side, b.time_ns.data(), R);
    put_array(s.side, b.left_mm.data(), R);
    put_array(s.side, b.right_mm.data(), R);
    for (const auto *v :
         {&b.saturated, &b.peaks, &b.skipped_stop, &b.skipped_reversal, &b.dropped, &b.missing})
        put_array(s.side, v->data(), R);
    put_array(s.side, b.row_flags.data(), R);
    put_array(s.side, b.strip_flags.data(), R);
    put_array(s.side, b.state.data(), R * K);
    put_u32(payload, std::uint32_t(s.side.size()));
    const std::size_t at = payload.size();
    put_u32(payload, 0);  // deflated size, below
    deflate_append(s.side.data(), s.side.size(), 1, payload);
    const std::uint32_t deflated = std::uint32_t(payload.size() - at - 4);
    std::memcpy(&payload[at], &deflated, 4);
    // Each laser's used samples (state flag 0) in row-major order, each
    // predicted by the one before (the first by 0), zigzag, Rice.
    s.values.resize(R * K);
    for (int laser = 0; laser < 2; ++laser) {
        std::size_t n = 0;
        std::int64_t previous = 0;
        std::uint64_t sum = 0;
        const std::int32_t *q = b.q[laser].data();
        const std::uint8_t *state = b.state.data();
        std::uint64_t *values = s.values.data();
        for (std::size_t i = 0; i < R * K; ++i) {
            if ((state[i] & k_state_flag_mask) != 0)
                continue;
            const std::uint64_t u = zigzag(std::int64_t(q[i]) - previous);
            values[n++] = u;
            sum += u;  // |q| < 2^31: no value reaches 2^40
            previous = q[i];
        }
        std::uint64_t unary_bits = 0;
        const unsigned k = best_rice_k(values, n, sum, &unary_bits);
        s.unary.clear();
        s.binary.clear();
        s.escapes.clear();
        rice_encode(values, n, k, unary_bits, s.unary, s.binary, s.escapes);
        payload.push_back(std::uint8_t(k));
        put_u32(payload, std::uint32_t(n));
        put_u32(payload, std::uint32_t(s.unary.size()));
        put_u32(payload, std::uint32_t(s.binary.size()));
        put_u32(payload, std::uint32_t(s.escapes.size()));
        payload.insert(payload.end(), s.unary.begin(), s.unary.end());
        payload.insert(payload.end(), s.binary.begin(), s.binary.end());
        for (std::uint64_t e : s.escapes)
            put_u64(payload, e);
    }
}

void decode_block(const std::uint8_t *payload, std::size_t size, std::size_t fibers,
                  double quantum_mm, row_block &b, block_scratch &s, const char *what) {
    byte_reader r(payload, size, what);
    if (r.u32() != k_block_magic)
        r.malformed("no block magic");
    const std::size_t R = r.u32(), K = r.u32();
    if (R == 0 || R > k_max_block_rows)
        r.malformed("row count out of range");
    if (K != fibers)
        r.malformed("fiber count differs from the recording's");
    if (r.f64() != quantum_mm)
        r.malformed("quantum differs from the recording's");
    if (b.fibers != K || b.capacity < R)
        b.allocate(K, k_max_block_rows);
    b.rows = R;
    const std::size_t side_bytes = r.u32(), deflated = r.u32();
    const std::size_t expected = R * (8 * 4 + 4 * 6 + 2) + R * K;
    if (side_bytes != expected)
        r.malformed("side data of the wrong size");
    inflate_exact(r.bytes(deflated), deflated, side_bytes, s.side, what);
    byte_reader side(s.side.data(), s.side.size(), what);
    get_array(side, b.encoder_mm.data(), R);
    get_array(side, b.time_ns.data(), R);
    get_array(side, b.left_mm.data(), R);
    get_array(side, b.right_mm.data(), R);
    for (auto *v :
         {&b.saturated, &b.peaks, &b.skipped_stop, &b.skipped_reversal, &b.dropped, &b.missing})
        get_array(side, v->data(), R);
    get_array(side, b.row_flags.data(), R);
    get_array(side, b.strip_flags.data(), R);
    get_array(side, b.state.data(), R * K);
    std::size_t used = 0;
    for (std::size_t i = 0; i < R * K; ++i)
        used += (b.state[i] & k_state_flag_mask) == 0;
    s.values.resize(R * K);
    for (int laser = 0; laser < 2; ++laser) {
        const unsigned k = r.u8();
        const std::size_t n = r.u32(), ub = r.u32(), bb = r.u32(), ne = r.u32();
        if (n != used)
            r.malformed("height count differs from the valid samples");
        const std::uint8_t *unary = r.bytes(ub);
        const std::uint8_t *binary = r.bytes(bb);
        if (ne > n)
            r.malformed("more escapes than values");
        const std::uint8_t *esc = r.bytes(ne * 8);
        s.escapes.resize(ne);
        for (std::size_t i = 0; i < ne; ++i) {
            std::uint64_t v = 0;
            for (int j = 7; j >= 0; --j)
                v = (v << 8) | esc[i * 8 + std::size_t(j)];
            s.escapes[i] = v;
        }
        rice_decode(unary, ub, binary, bb, s.escapes.data(), ne, k, n, s.values.data(), what);
        std::int64_t previous = 0;
        std::size_t j = 0;
        std::int32_t *q = b.q[laser].data();
        for (std::size_t i = 0; i < R * K; ++i) {
            if ((b.state[i] & k_state_flag_mask) != 0) {
                q[i] = 0;
                continue;
            }
            // Unsigned: a damaged file's residual wraps instead of overflowing.
            previous =
                std::int64_t(std::uint64_t(previous) + std::uint64_t(unzigzag(s.values[j++])));
            if (previous > INT32_MAX || previous < INT32_MIN)
                r.malformed("a height beyond the recording's range");
            q[i] = std::int32_t(previous);
        }
    }
    if (r.left() != 0)
        r.malformed("bytes after the heights");
}

}  // namespace flt::record
