// SPDX-License-Identifier: Apache-2.0
// Internal: the pixel formats a camera source delivers (PFNC codes, the
// same on every GenICam transport) and the size of a frame, computed
// without overflow and held to the library's frame bounds before anything
// is allocated or delivered.
//
// A camera reports Width, Height and PixelFormat itself; a wrong or hostile
// one can report any 32-bit value. Width x Height x bytes per pixel of two
// such values wraps in 64 bits (2147549185 x 4294836226 x 2 is 4 mod 2^64),
// so sizes are computed in steps that are each checked against the bounds:
// a side of 1 .. FLT_CALIB_MAX_FRAME_SIDE px (the largest frame the
// calibration, the extractor and the simulator take) and at most 2 bytes
// per pixel, which keeps every product below 2^30.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "flatline/calib.h"
#include "flatline/extractor.h"

namespace flt::sources {

// PFNC codes of the formats delivered (monochrome, unpacked: Mono10 and
// Mono12 in the low bits of 16-bit words).
constexpr std::uint32_t k_pfnc_mono8 = 0x01080001u;
constexpr std::uint32_t k_pfnc_mono10 = 0x01100003u;
constexpr std::uint32_t k_pfnc_mono12 = 0x01100005u;
constexpr std::uint32_t k_pfnc_mono16 = 0x01100007u;

// The flt_pixel_format (its value is the significant bits) of a PFNC code,
// 0 when the format is not delivered.
inline int pfnc_bits(std::uint32_t pfnc) {
    switch (pfnc) {
        case k_pfnc_mono8:
            return 8;
        case k_pfnc_mono10:
            return 10;
        case k_pfnc_mono12:
            return 12;
        case k_pfnc_mono16:
            return 16;
        default:
            return 0;
    }
}
inline std::uint32_t pfnc_of_bits(int bits) {
    switch (bits) {
        case 8:
            return k_pfnc_mono8;
        case 10:
            return k_pfnc_mono10;
        case 12:
            return k_pfnc_mono12;
        case 16:
            return k_pfnc_mono16;
        default:
            return 0;
    }
}
// Bytes per pixel of a delivered format: 1 for Mono8, 2 for the others.
inline std::size_t bytes_per_pixel(int bits) {
    return bits > 8 ? 2 : 1;
}

// The largest frame side a source delivers, px.
constexpr std::uint32_t k_max_frame_side = FLT_CALIB_MAX_FRAME_SIDE;
// The largest frame, bytes: both sides at their bound, 2 bytes a pixel
// (512 MiB).
constexpr std::uint64_t k_max_frame_bytes = std::uint64_t(k_max_frame_side) * k_max_frame_side * 2;

// A frame's size as the camera describes it, checked.
struct frame_geometry {
    std::uint32_t width = 0, height = 0;  // px
    std::uint32_t pfnc = 0;
    int bits = 0;                   // flt_pixel_format
    std::size_t row_bytes = 0;      // width x bytes per pixel
    std::uint64_t image_bytes = 0;  // row_bytes x height
};

// Checks a camera's Width, Height and PixelFormat (as the 64-bit values its
// features gave) and computes the frame's size. Throws flt::error:
// FLT_ERR_FORMAT for a pixel format that is not delivered (naming it),
// FLT_ERR_DEVICE for a side of 0 or beyond k_max_frame_side (naming both
// sides and the bound). `who` names the camera in the message.
frame_geometry check_geometry(std::int64_t width, std::int64_t height, std::int64_t pfnc,
                              const char *who);

// Whether `rows` rows of `row_bytes` bytes plus `padding` bytes after each
// row and `tail` bytes at the end make exactly `expected` bytes, computed
// without overflow for any 32-bit inputs.
bool image_size_is(std::uint64_t row_bytes, std::uint64_t padding, std::uint64_t rows,
                   std::uint64_t tail, std::uint64_t expected);
// Whether they fit in `capacity` bytes (the same, <=).
bool image_size_fits(std::uint64_t row_bytes, std::uint64_t padding, std::uint64_t rows,
                     std::uint64_t tail, std::uint64_t capacity);

// The name of a PFNC code ("Mono8", ..., or "0x%08x").
std::string pfnc_name(std::uint32_t pfnc);

}  // namespace flt::sources
