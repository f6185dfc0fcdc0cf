// SPDX-License-Identifier: Apache-2.0
/* libFuzzer harness: the quality record's decoders, which read bytes from
 * files and databases (lib/record): a recording's block of rows
 * (decode_block) and an archived height map (decode_map).
 *
 * Input: byte 0 chooses (bit 0: block or map); for a block, byte 1 gives
 * the recording's fiber count (1..64: the decoder's logic does not depend
 * on the width, and a block is allocated for 4096 rows of them), byte 2 is
 * unused and byte 3 gives its quantum (2^-4 .. 2^-12 mm); the rest is the
 * payload. Any payload must decode or be
 * refused with flt::error(FLT_ERR_FORMAT) (never a crash, never another
 * error); an accepted one must encode and decode again to the same values
 * (the formats have one meaning per payload). */
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "core/error.hpp"
#include "record/archive_format.hpp"
#include "record/recording_format.hpp"

namespace {

using namespace flt::record;

void fuzz_block(const std::uint8_t *data, std::size_t size) {
    if (size < 4)
        return;
    const std::size_t fibers = 1 + (std::size_t(data[1]) % 64);
    const double quantum = std::ldexp(1.0, -4 - int(data[3] % 9));
    row_block b, again;
    block_scratch scratch;
    try {
        decode_block(data + 4, size - 4, fibers, quantum, b, scratch, "fuzzed block");
    } catch (const flt::error &e) {
        if (e.status != FLT_ERR_FORMAT || e.what()[0] == 0)
            abort();
        return;
    }
    // Encode what was decoded and decode it again: the same rows.
    std::vector<std::uint8_t> payload;
    encode_block(b, quantum, scratch, payload);
    try {
        decode_block(payload.data(), payload.size(), fibers, quantum, again, scratch, "again");
    } catch (const flt::error &) {
        abort();  // the encoder's own output must decode
    }
    const std::size_t R = b.rows, n = R * fibers;
    if (again.rows != R || std::memcmp(again.state.data(), b.state.data(), n) != 0 ||
        std::memcmp(again.q[0].data(), b.q[0].data(), n * 4) != 0 ||
        std::memcmp(again.q[1].data(), b.q[1].data(), n * 4) != 0 ||
        std::memcmp(again.encoder_mm.data(), b.encoder_mm.data(), R * 8) != 0 ||
        std::memcmp(again.time_ns.data(), b.time_ns.data(), R * 8) != 0 ||
        std::memcmp(again.row_flags.data(), b.row_flags.data(), R) != 0 ||
        std::memcmp(again.missing.data(), b.missing.data(), R * 4) != 0)
        abort();
}

void fuzz_map(const std::uint8_t *data, std::size_t size) {
    std::size_t rows = 0, fibers = 0;
    std::vector<double> s, z;
    std::vector<std::uint8_t> flags;
    try {
        // 2^22 samples: the bound the archive's readers use scaled down,
        // so one input cannot take more than ~50 MB here.
        decode_map(data + 1, size - 1, std::size_t(1) << 22, &rows, &fibers, s, z, flags);
    } catch (const flt::error &e) {
        if (e.status != FLT_ERR_FORMAT || e.what()[0] == 0)
            abort();
        return;
    }
    if (s.size() != rows || z.size() != rows * fibers || flags.size() != rows * fibers)
        abort();
    // The quantum is in the payload (bytes 12..19 after the magic and size).
    double quantum = 0;
    std::memcpy(&quantum, data + 1 + 12, 8);
    for (double v : z)
        if (std::isfinite(v) && std::fabs(v) > 1.0e5)
            return;  // beyond what the encoder stores (it writes NaN): no round trip
    std::vector<std::uint8_t> map;
    encode_map(rows, fibers, s.data(), z.data(), flags.data(), quantum, map);
    std::size_t rows2 = 0, fibers2 = 0;
    std::vector<double> s2, z2;
    std::vector<std::uint8_t> flags2;
    try {
        decode_map(map.data(), map.size(), std::size_t(1) << 22, &rows2, &fibers2, s2, z2, flags2);
    } catch (const flt::error &) {
        abort();
    }
    if (rows2 != rows || fibers2 != fibers || flags2 != flags ||
        std::memcmp(s2.data(), s.data(), rows * 8) != 0)
        abort();
    for (std::size_t i = 0; i < z.size(); ++i) {
        const bool nan1 = std::isnan(z[i]), nan2 = std::isnan(z2[i]);
        // The heights were multiples of the quantum: they come back within
        // a rounding of the division (1e-9 of the quantum is far above it).
        if (nan1 != nan2 || (!nan1 && std::fabs(z[i] - z2[i]) > 1e-9 * quantum))
            abort();
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
    if (size < 1)
        return 0;
    try {
        if (data[0] & 1)
            fuzz_map(data, size);
        else
            fuzz_block(data, size);
    } catch (const std::bad_alloc &) {
        abort();  // the sizes are bounded before anything is allocated
    }
    return 0;
}
