// SPDX-License-Identifier: Apache-2.0
// Internal: the codecs of the quality record (docs/record.md gives the
// byte layouts; examples/python/read_recording.py decodes them with
// numpy alone).
//
// Heights are quantized to integers and predicted; the residuals are
// zigzag-mapped to unsigned numbers and Rice-coded with the unary parts and
// the binary parts in two separate bit streams (least significant bit
// first), which a vectorised reader decodes without a loop: the unary
// stream's set bits end the values, the binary stream is k bits per value.
// A value whose unary part would reach k_rice_escape is written as
// k_rice_escape zeros and a one, with its whole value in an escape list of
// 64-bit numbers. Everything else (per-row numbers, flags) is deflated
// with zlib, which every language's standard library reads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace flt::record {

// A unary part this long or longer is an escape (see above).
constexpr std::uint32_t k_rice_escape = 48;

// Appends bits least significant first.
class bit_writer {
  public:
    explicit bit_writer(std::vector<std::uint8_t> &out) : out_(out) {}
    void put(std::uint64_t bits, unsigned count);  // count <= 64
    void put_zeros(std::uint64_t count);
    void finish();  // flushes the last partial byte
  private:
    std::vector<std::uint8_t> &out_;
    std::uint64_t acc_ = 0;
    unsigned n_ = 0;
};

inline std::uint64_t zigzag(std::int64_t v) {
    return (std::uint64_t(v) << 1) ^ std::uint64_t(v >> 63);
}
inline std::int64_t unzigzag(std::uint64_t u) {
    return std::int64_t(u >> 1) ^ -std::int64_t(u & 1);
}

// The Rice parameter that codes `values` in the fewest bits (0..31), given
// their sum (each value counted at most 2^40); *unary_bits_out receives an
// upper bound of the unary stream's bits with it.
unsigned best_rice_k(const std::uint64_t *values, std::size_t count, std::uint64_t sum,
                     std::uint64_t *unary_bits_out);

// Rice-codes count values with parameter k into the two streams and the
// escape list (appended); unary_bits: best_rice_k's bound.
void rice_encode(const std::uint64_t *values, std::size_t count, unsigned k,
                 std::uint64_t unary_bits, std::vector<std::uint8_t> &unary,
                 std::vector<std::uint8_t> &binary, std::vector<std::uint64_t> &escapes);

// Decodes count values; every stream is bounded by its size. Throws
// flt::error(FLT_ERR_FORMAT) naming `what` when the streams run short or
// hold more than they should.
void rice_decode(const std::uint8_t *unary, std::size_t unary_bytes, const std::uint8_t *binary,
                 std::size_t binary_bytes, const std::uint64_t *escapes, std::size_t escape_count,
                 unsigned k, std::size_t count, std::uint64_t *values, const char *what);

// zlib (RFC 1950) at `level`; inflate refuses more than max_bytes of output
// (FLT_ERR_FORMAT naming `what`) and input that does not decode.
void deflate_append(const std::uint8_t *data, std::size_t size, int level,
                    std::vector<std::uint8_t> &out);
void inflate_exact(const std::uint8_t *data, std::size_t size, std::size_t expected_bytes,
                   std::vector<std::uint8_t> &out, const char *what);

// CRC-32 (ISO-HDLC, zlib's crc32; Python's zlib.crc32).
std::uint32_t crc32_of(const std::uint8_t *data, std::size_t size);

// Little-endian appends and reads of fixed-size numbers.
void put_u32(std::vector<std::uint8_t> &out, std::uint32_t v);
void put_u64(std::vector<std::uint8_t> &out, std::uint64_t v);
void put_f64(std::vector<std::uint8_t> &out, double v);

// Reads fixed-size numbers from a bounded buffer; every read past its end
// throws FLT_ERR_FORMAT naming `what`.
class byte_reader {
  public:
    byte_reader(const std::uint8_t *data, std::size_t size, const char *what)
        : p_(data), end_(data + size), what_(what) {}
    std::uint8_t u8();
    std::uint32_t u32();
    std::uint64_t u64();
    double f64();
    const std::uint8_t *bytes(std::size_t n);
    std::size_t left() const { return std::size_t(end_ - p_); }
    [[noreturn]] void malformed(const char *why) const;

  private:
    const std::uint8_t *p_, *end_;
    const char *what_;
};

}  // namespace flt::record
