// SPDX-License-Identifier: Apache-2.0
#include "record/codec.hpp"

#include <cstring>
#include <limits>
#include <string>

#include <zlib.h>

#include "core/error.hpp"
#include "core/number_text.hpp"

namespace flt::record {
namespace {

[[noreturn]] void format_error(const char *what, const char *why) {
    char message[300];
    format_c(message, sizeof message, "%s: %s", what, why);
    throw error(FLT_ERR_FORMAT, message);
}

}  // namespace

void bit_writer::put(std::uint64_t bits, unsigned count) {
    if (count == 0)
        return;
    if (count > 32) {  // the accumulator takes at most 32 + 31 bits
        put(bits, 32);
        put(bits >> 32, count - 32);
        return;
    }
    acc_ |= (bits & ((std::uint64_t(1) << count) - 1)) << n_;
    n_ += count;
    if (n_ >= 32) {
        // Four bytes at once: the accumulator holds at most 57 + 7 bits.
        const std::size_t at = out_.size();
        out_.resize(at + 4);
        for (int i = 0; i < 4; ++i)
            out_[at + std::size_t(i)] = std::uint8_t(acc_ >> (8 * i));
        acc_ >>= 32;
        n_ -= 32;
    }
}

void bit_writer::put_zeros(std::uint64_t count) {
    while (count >= 32) {
        put(0, 32);
        count -= 32;
    }
    put(0, unsigned(count));
}

void bit_writer::finish() {
    while (n_ > 0) {
        out_.push_back(std::uint8_t(acc_));
        acc_ >>= 8;
        n_ = n_ >= 8 ? n_ - 8 : 0;
    }
    acc_ = 0;
}

unsigned best_rice_k(const std::uint64_t *values, std::size_t count, std::uint64_t sum,
                     std::uint64_t *unary_bits_out) {
    *unary_bits_out = 0;
    if (count == 0)
        return 0;
    // The optimum is near log2 of the mean; the exact cost of the three
    // around it decides (the cost is convex in k). Escapes are rare enough
    // to leave out of the estimate.
    const std::uint64_t mean = sum / count;
    unsigned guess = 0;
    while (guess < 31 && (std::uint64_t(1) << (guess + 1)) <= mean)
        ++guess;
    const unsigned lo = guess > 0 ? guess - 1 : 0, hi = std::min(31u, guess + 1);
    std::uint64_t shifted[3] = {0, 0, 0};
    for (std::size_t i = 0; i < count; ++i) {
        const std::uint64_t v = std::min<std::uint64_t>(values[i], std::uint64_t(1) << 40);
        shifted[0] += v >> lo;
        shifted[1] += v >> (lo + 1);
        shifted[2] += v >> hi;
    }
    unsigned best = lo;
    std::uint64_t best_bits = ~std::uint64_t(0);
    for (unsigned j = 0; j < 3; ++j) {
        const unsigned k = j == 2 ? hi : lo + j;
        if (k > hi)
            break;
        const std::uint64_t bits = shifted[j] + std::uint64_t(count) * (k + 1);
        if (bits < best_bits) {
            best_bits = bits;
            best = k;
            // Bounds the stream: an escape's unary part (48 zeros) is
            // shorter than its capped value's (2^40 >> k >= 512).
            *unary_bits_out = shifted[j] + count;
        }
    }
    return best;
}

namespace {

// Appends bits least significant first through a raw pointer into a
// buffer sized beforehand (with 8 bytes of slack): whole bytes leave the
// accumulator after every value, 8 at a time.
struct fast_bits {
    std::uint8_t *p;
    std::uint64_t acc = 0;
    unsigned n = 0;
    // count <= 56.
    void put(std::uint64_t bits, unsigned count) {
        acc |= bits << n;
        n += count;
        std::memcpy(p, &acc, 8);
        const unsigned bytes = n >> 3;
        p += bytes;
        acc = bytes == 8 ? 0 : acc >> (8 * bytes);
        n &= 7;
    }
    std::uint8_t *finish() {
        if (n > 0) {
            *p++ = std::uint8_t(acc);
            n = 0;
        }
        return p;
    }
};

}  // namespace

void rice_encode(const std::uint64_t *values, std::size_t count, unsigned k,
                 std::uint64_t unary_bits, std::vector<std::uint8_t> &unary,
                 std::vector<std::uint8_t> &binary, std::vector<std::uint64_t> &escapes) {
    // A value's unary part is min(v >> k, escape) zeros and a one, its
    // binary part k bits: room for the bound, trimmed after.
    const std::uint64_t ubits = unary_bits;
    const std::size_t u0 = unary.size(), b0 = binary.size();
    unary.resize(u0 + std::size_t((ubits + 7) / 8) + 8);
    binary.resize(b0 + (count * k + 7) / 8 + 8);
    fast_bits u{unary.data() + u0}, b{binary.data() + b0};
    const std::uint64_t mask = k ? (std::uint64_t(1) << k) - 1 : 0;
    for (std::size_t i = 0; i < count; ++i) {
        const std::uint64_t v = values[i];
        const std::uint64_t q = v >> k;
        if (q >= k_rice_escape) {
            u.put(std::uint64_t(1) << k_rice_escape, k_rice_escape + 1);
            b.put(0, k);
            escapes.push_back(v);
            continue;
        }
        // q zeros and a one: at most 48 bits, in one call.
        u.put(std::uint64_t(1) << q, unsigned(q) + 1);
        b.put(v & mask, k);
    }
    unary.resize(std::size_t(u.finish() - unary.data()));
    binary.resize(std::size_t(b.finish() - binary.data()));
}

void rice_decode(const std::uint8_t *unary, std::size_t unary_bytes, const std::uint8_t *binary,
                 std::size_t binary_bytes, const std::uint64_t *escapes, std::size_t escape_count,
                 unsigned k, std::size_t count, std::uint64_t *values, const char *what) {
    if (k > 31)
        format_error(what, "Rice parameter above 31");
    if (binary_bytes != (count * k + 7) / 8)
        format_error(what, "the binary stream's size does not match its values");
    std::size_t ubit = 0, bbit = 0, esc = 0;
    const std::size_t ubits = unary_bytes * 8;
    for (std::size_t i = 0; i < count; ++i) {
        std::uint64_t q = 0;
        for (;;) {
            if (ubit >= ubits)
                format_error(what, "the unary stream ends early");
            // Whole zero bytes at once (long runs are escapes, rare).
            if ((ubit & 7) == 0 && unary[ubit >> 3] == 0) {
                q += 8;
                ubit += 8;
                if (q > k_rice_escape)
                    format_error(what, "a unary run longer than the escape");
                continue;
            }
            const bool bit = (unary[ubit >> 3] >> (ubit & 7)) & 1;
            ++ubit;
            if (bit)
                break;
            if (++q > k_rice_escape)
                format_error(what, "a unary run longer than the escape");
        }
        std::uint64_t r = 0;
        for (unsigned j = 0; j < k;) {
            const unsigned take = std::min<unsigned>(k - j, 8 - unsigned(bbit & 7));
            const std::uint64_t byte = binary[bbit >> 3] >> (bbit & 7);
            r |= (byte & ((1u << take) - 1)) << j;
            j += take;
            bbit += take;
        }
        if (q == k_rice_escape) {
            if (esc >= escape_count)
                format_error(what, "more escapes than the escape list holds");
            values[i] = escapes[esc++];
            if ((values[i] >> k) < k_rice_escape)
                format_error(what, "an escape of a value that needed none");
        } else {
            values[i] = (q << k) | r;
        }
    }
    if (esc != escape_count)
        format_error(what, "escapes left over");
    if ((ubit + 7) / 8 != unary_bytes)
        format_error(what, "the unary stream is longer than its values");
}

void deflate_append(const std::uint8_t *data, std::size_t size, int level,
                    std::vector<std::uint8_t> &out) {
    const uLong bound = compressBound(uLong(size));
    const std::size_t at = out.size();
    out.resize(at + bound);
    uLongf written = bound;
    if (compress2(out.data() + at, &written, data, uLong(size), level) != Z_OK)
        throw error(FLT_ERR_INTERNAL, "zlib refused to compress");
    out.resize(at + written);
}

void inflate_exact(const std::uint8_t *data, std::size_t size, std::size_t expected_bytes,
                   std::vector<std::uint8_t> &out, const char *what) {
    out.resize(expected_bytes);
    uLongf got = uLongf(expected_bytes);
    uLong used = uLong(size);
    // One byte more than expected would not fit: uncompress2 says
    // Z_BUF_ERROR, which is a malformed block here.
    const int st = uncompress2(out.data(), &got, data, &used);
    if (st != Z_OK || got != expected_bytes || used != size)
        format_error(what, "the deflated data do not decode to their stated size");
}

std::uint32_t crc32_of(const std::uint8_t *data, std::size_t size) {
    uLong crc = crc32(0L, Z_NULL, 0);
    while (size > 0) {
        const uInt n = uInt(std::min<std::size_t>(size, 1u << 30));
        crc = crc32(crc, data, n);
        data += n;
        size -= n;
    }
    return std::uint32_t(crc);
}

void put_u32(std::vector<std::uint8_t> &out, std::uint32_t v) {
    for (int i = 0; i < 4; ++i)
        out.push_back(std::uint8_t(v >> (8 * i)));
}

void put_u64(std::vector<std::uint8_t> &out, std::uint64_t v) {
    for (int i = 0; i < 8; ++i)
        out.push_back(std::uint8_t(v >> (8 * i)));
}

void put_f64(std::vector<std::uint8_t> &out, double v) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    put_u64(out, bits);
}

void byte_reader::malformed(const char *why) const {
    format_error(what_, why);
}

const std::uint8_t *byte_reader::bytes(std::size_t n) {
    if (n > left())
        malformed("it ends early");
    const std::uint8_t *at = p_;
    p_ += n;
    return at;
}

std::uint8_t byte_reader::u8() {
    return *bytes(1);
}

std::uint32_t byte_reader::u32() {
    const std::uint8_t *b = bytes(4);
    return std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 |
           std::uint32_t(b[3]) << 24;
}

std::uint64_t byte_reader::u64() {
    const std::uint8_t *b = bytes(8);
    std::uint64_t v = 0;
    for (int i = 7; i >= 0; --i)
        v = (v << 8) | b[i];
    return v;
}

double byte_reader::f64() {
    const std::uint64_t bits = u64();
    double v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
}

}  // namespace flt::record
