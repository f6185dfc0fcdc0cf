// SPDX-License-Identifier: Apache-2.0
// Pixel formats and frame sizes (see pixel_format.hpp).
#include "sources/camera/pixel_format.hpp"

#include <cstdio>

#include "sources/source.hpp"

namespace flt::sources {

frame_geometry check_geometry(std::int64_t width, std::int64_t height, std::int64_t pfnc,
                              const char *who) {
    const int bits = pfnc >= 0 && pfnc <= 0xFFFFFFFF ? pfnc_bits(std::uint32_t(pfnc)) : 0;
    if (bits == 0)
        raise(FLT_ERR_FORMAT,
              "%s reports PixelFormat %s, which is not Mono8, Mono10, Mono12 or Mono16 "
              "(unpacked); set one with flt_source_set_enum()",
              who, pfnc_name(std::uint32_t(pfnc)).c_str());
    // Each side is bounded before any product is formed.
    if (width < 1 || height < 1 || width > std::int64_t(k_max_frame_side) ||
        height > std::int64_t(k_max_frame_side))
        raise(FLT_ERR_DEVICE,
              "%s reports a %lld x %lld px image; a frame source takes 1 .. %u px a side "
              "(FLT_CALIB_MAX_FRAME_SIDE)",
              who, (long long)width, (long long)height, unsigned(k_max_frame_side));
    frame_geometry g;
    g.width = std::uint32_t(width);
    g.height = std::uint32_t(height);
    g.pfnc = std::uint32_t(pfnc);
    g.bits = bits;
    g.row_bytes = std::size_t(g.width) * bytes_per_pixel(bits);  // <= 2^15
    g.image_bytes = std::uint64_t(g.row_bytes) * g.height;       // <= 2^29
    return g;
}

namespace {

// row_bytes x rows + padding x rows + tail, or false when it passes
// `limit` (every step is checked before the next is formed).
bool image_size(std::uint64_t row_bytes, std::uint64_t padding, std::uint64_t rows,
                std::uint64_t tail, std::uint64_t limit, std::uint64_t &out) {
    if (row_bytes > limit || padding > limit - row_bytes)
        return false;
    const std::uint64_t stride = row_bytes + padding;
    if (rows != 0 && stride > limit / rows)
        return false;
    const std::uint64_t body = stride * rows;
    if (tail > limit - body)
        return false;
    out = body + tail;
    return true;
}

}  // namespace

bool image_size_is(std::uint64_t row_bytes, std::uint64_t padding, std::uint64_t rows,
                   std::uint64_t tail, std::uint64_t expected) {
    std::uint64_t total = 0;
    return image_size(row_bytes, padding, rows, tail, expected, total) && total == expected;
}

bool image_size_fits(std::uint64_t row_bytes, std::uint64_t padding, std::uint64_t rows,
                     std::uint64_t tail, std::uint64_t capacity) {
    std::uint64_t total = 0;
    return image_size(row_bytes, padding, rows, tail, capacity, total);
}

std::string pfnc_name(std::uint32_t pfnc) {
    switch (pfnc) {
        case k_pfnc_mono8:
            return "Mono8";
        case k_pfnc_mono10:
            return "Mono10";
        case k_pfnc_mono12:
            return "Mono12";
        case k_pfnc_mono16:
            return "Mono16";
        default: {
            char text[16];
            std::snprintf(text, sizeof text, "0x%08x", unsigned(pfnc));
            return text;
        }
    }
}

}  // namespace flt::sources
