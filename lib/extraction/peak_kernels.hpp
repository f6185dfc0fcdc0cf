// SPDX-License-Identifier: Apache-2.0
// Internal: the extractor's per-frame kernels.
//
// band_maximum: a running maximum over the band's rows, row-major, so every
// row is one contiguous sweep across the columns that the compiler turns into
// SIMD compares and blends (AVX2 where the CPU has it). This is the only
// pass over every pixel of the band.
//
// column_peak: per column, the checks and the Savitzky-Golay derivative are
// evaluated only next to the maximum (a few rows), so their cost does not
// grow with the band. It also measures the accepted peak's shape
// (peak_shape) for the extractor's shape check, which compares it with the
// other columns' and so runs once the whole row is known.
//
// column_peaks: column_peak for eight clean columns at once, lane by lane,
// to the same bits; the columns it cannot read so go to column_peak.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "core/cpu_dispatch.hpp"

namespace flt {

// The two per-frame kernels (band_maximum, column_peaks) are built twice on
// x86-64, for the baseline (SSE2) and for AVX2, and each call takes the AVX2
// build where the CPU has it (core/cpu_dispatch.hpp says why at run time):
// the same bits either way (tests/c/test_peak_kernels.cpp).
#define FLT_PEAK_AVX2 FLT_HAVE_AVX2_BUILD
#if FLT_PEAK_AVX2
#  define FLT_TARGET_AVX2 __attribute__((target("avx2")))
#endif

template <class Pixel>
inline void band_maximum_body(const unsigned char *frame, std::size_t stride, std::uint32_t width,
                              std::uint32_t first, std::uint32_t rows,
                              std::uint16_t *__restrict best_value,
                              std::uint16_t *__restrict best_row) {
    const Pixel *row = reinterpret_cast<const Pixel *>(frame + std::size_t(first) * stride);
    for (std::uint32_t u = 0; u < width; ++u) {
        best_value[u] = row[u];
        best_row[u] = std::uint16_t(first);
    }
    for (std::uint32_t r = 1; r < rows; ++r) {
        const std::uint16_t v = std::uint16_t(first + r);
        const Pixel *__restrict p =
            reinterpret_cast<const Pixel *>(frame + std::size_t(first + r) * stride);
        for (std::uint32_t u = 0; u < width; ++u) {
            const std::uint16_t value = p[u];
            const bool brighter = value > best_value[u];  // first maximum wins ties
            best_value[u] = brighter ? value : best_value[u];
            best_row[u] = brighter ? v : best_row[u];
        }
    }
}

template <class Pixel>
inline void band_maximum_base(const unsigned char *frame, std::size_t stride, std::uint32_t width,
                              std::uint32_t first, std::uint32_t rows, std::uint16_t *best_value,
                              std::uint16_t *best_row) {
    band_maximum_body<Pixel>(frame, stride, width, first, rows, best_value, best_row);
}

#if FLT_PEAK_AVX2
template <class Pixel>
FLT_TARGET_AVX2 inline void band_maximum_avx2(const unsigned char *frame, std::size_t stride,
                                              std::uint32_t width, std::uint32_t first,
                                              std::uint32_t rows, std::uint16_t *best_value,
                                              std::uint16_t *best_row) {
    band_maximum_body<Pixel>(frame, stride, width, first, rows, best_value, best_row);
}
#endif

template <class Pixel>
inline void band_maximum(const unsigned char *frame, std::size_t stride, std::uint32_t width,
                         std::uint32_t first, std::uint32_t rows, std::uint16_t *best_value,
                         std::uint16_t *best_row) {
#if FLT_PEAK_AVX2
    if (cpu_has_avx2()) {
        band_maximum_avx2<Pixel>(frame, stride, width, first, rows, best_value, best_row);
        return;
    }
#endif
    band_maximum_base<Pixel>(frame, stride, width, first, rows, best_value, best_row);
}

// The shape of an accepted peak, which a reflection overlapping the line
// changes while a clean line keeps its neighbours' shape:
//   width  px, between the two crossings of half the maximum above the
//          local background, each interpolated linearly between the pixels
//          either side;
//   skew   px, the crossings' midpoint minus the sub-pixel row (0 for a
//          saturated peak, whose row is that midpoint);
//   area   counts x rows, the sum over rows maximum +- shape_reach of the
//          pixels minus the lowest of them (the local background).
// All NaN when the rows they need leave the frame.
//
// The local background of a peak: the higher of the lowest pixels on
// either side within +- gather_reach rows (a line on a bright or sloping
// background, as a real board or strip gives, still crosses its half level
// on both sides). Half the maximum is half way between it and the maximum.
struct peak_shape {
    double width, skew, area;
};

struct peak_params {
    int sg_half;               // window = 2 * sg_half + 1 rows
    const float *sg_taps;      // derivative taps, [2 * sg_half + 1]
    std::uint32_t min_value;   // weakest accepted maximum, counts
    std::uint32_t full_scale;  // saturation, counts
    int max_width;             // rows at or above half the maximum
    std::uint32_t frame_height;
    long shape_reach;   // rows either side of the maximum for the area
    long gather_reach;  // max(shape_reach, sg_half + 3) <= k_max_gather_reach
};

// The rows column_peak copies around a maximum: the area's and those of the
// Savitzky-Golay windows of the zero-crossing search (up to 3 rows away).
constexpr long k_max_gather_reach = 31;

// Candidate peaks column_peak tries per column, at most: the maximum and,
// after each rejection, the next brightest local maximum outside the
// rejected ones. A tall band over a board's white fields, or a lit strip
// with bright marks, holds several patches brighter than the line, each
// rejected whole as too wide or too faint above its background.
constexpr int k_max_candidates = 8;

// The sub-pixel row of the strongest valid peak of column u in rows
// [first, first + rows), NaN if there is none. `value` and `row` are the
// column's maximum from band_maximum. *suspect is set when the column's
// maximum is saturated or a brighter peak had to be rejected: the extractor
// then checks the peak's continuity with its neighbours.
//
// A saturated maximum (at full scale) is measured, not dropped, when
// accept_saturated: its row is the middle of the plateau, between the two
// crossings of half the maximum above the local background, each
// interpolated linearly between the pixels either side (the
// Savitzky-Golay derivative is zero all along a plateau). *saturated then
// says so. Without accept_saturated (a second look at a saturated column
// whose peak a continuity check refused: a glint over the line) the
// saturated peak is passed over for the next candidate.
template <class Pixel>
__attribute__((always_inline)) inline double
column_peak(const unsigned char *frame, std::size_t stride, std::uint32_t u, std::uint32_t first,
            std::uint32_t rows, std::uint32_t value, long row, const peak_params &p,
            bool accept_saturated, bool *suspect, bool *saturated_out, peak_shape *shape) {
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    auto px = [&](long v) -> std::uint32_t {
        return reinterpret_cast<const Pixel *>(frame + std::size_t(v) * stride)[u];
    };
    const long band_lo = long(first), band_hi = long(first + rows) - 1;
    const long last = long(p.frame_height) - 1;
    const long h = p.sg_half, reach = p.gather_reach;
    // The column's pixels in rows row +- reach, copied once (contiguous, so
    // the derivatives and the area below read them cheaply); NaN outside
    // the frame.
    float gathered[2 * k_max_gather_reach + 1];
    // The Savitzky-Golay derivative at row i (|i - row| <= 3), NaN where the
    // window leaves the frame. The taps are odd (tap[-j] = -tap[j], tap[0] =
    // 0, made exact at create time): half the products.
    auto derivative = [&](long i) -> float {
        const float *centre = gathered + (i - row + reach);
        float d = 0;
        for (long j = 1; j <= h; ++j)
            d += p.sg_taps[h + j] * (centre[j] - centre[-j]);
        return d;
    };
    long excluded_lo[k_max_candidates], excluded_hi[k_max_candidates];
    int excluded = 0;
    // The brightest local maxima outside the rejected peaks when the band
    // was last scanned (brightest first; of equal ones the upper row
    // first, as a scan down the rows finds them): each next candidate is
    // the first of them not rejected since, so one strided scan serves
    // several rejections; a new scan when all are used.
    std::uint32_t next_value[k_max_candidates];
    long next_row[k_max_candidates];
    int next_count = 0;
    *saturated_out = false;
    for (int candidate = 0; candidate < k_max_candidates; ++candidate) {
        if (value < p.min_value || value == 0)
            return nan;  // the rest is weaker still
        // The column's pixels around the maximum, copied once (NaN outside
        // the frame), with the area's sums and the lowest pixel on either
        // side of the maximum on the way (whole counts, exact).
        const long r = p.shape_reach;
        std::uint32_t floor_value = value, sum = 0;
        std::uint32_t low_left = value, low_right = value;
        const bool inside = row - reach >= 0 && row + reach <= last;
        if (inside) {
            const unsigned char *pixel = frame + std::size_t(row - reach) * stride;
            for (long j = -reach; j < -r; ++j, pixel += stride) {
                const std::uint32_t count = reinterpret_cast<const Pixel *>(pixel)[u];
                low_left = std::min(low_left, count);
                gathered[j + reach] = float(count);
            }
            for (long j = -r; j < 0; ++j, pixel += stride) {
                const std::uint32_t count = reinterpret_cast<const Pixel *>(pixel)[u];
                floor_value = std::min(floor_value, count);
                sum += count;
                low_left = std::min(low_left, count);
                gathered[j + reach] = float(count);
            }
            {
                const std::uint32_t count = reinterpret_cast<const Pixel *>(pixel)[u];
                floor_value = std::min(floor_value, count);
                sum += count;
                gathered[reach] = float(count);
                pixel += stride;
            }
            for (long j = 1; j <= r; ++j, pixel += stride) {
                const std::uint32_t count = reinterpret_cast<const Pixel *>(pixel)[u];
                floor_value = std::min(floor_value, count);
                sum += count;
                low_right = std::min(low_right, count);
                gathered[j + reach] = float(count);
            }
            for (long j = r + 1; j <= reach; ++j, pixel += stride) {
                const std::uint32_t count = reinterpret_cast<const Pixel *>(pixel)[u];
                low_right = std::min(low_right, count);
                gathered[j + reach] = float(count);
            }
        } else {
            for (long j = -reach; j <= reach; ++j) {
                const bool in_frame = row + j >= 0 && row + j <= last;
                const std::uint32_t count = in_frame ? px(row + j) : value;
                if (j < 0)
                    low_left = std::min(low_left, count);
                else if (j > 0)
                    low_right = std::min(low_right, count);
                gathered[j + reach] =
                    in_frame ? float(count) : std::numeric_limits<float>::quiet_NaN();
            }
        }
        // The local background: the higher of the lowest pixels on either
        // side (rows outside the frame do not count).
        const std::uint32_t background = std::max(low_left, low_right);
        // "At or above half the maximum": 2 px >= value + background.
        const std::uint32_t level2 = value + background;
        // Rows at or above half the maximum around it (the line's extent).
        long lo = row, hi = row;
        while (lo > band_lo && 2 * px(lo - 1) >= level2 && row - lo <= p.max_width)
            --lo;
        while (hi < band_hi && 2 * px(hi + 1) >= level2 && hi - row <= p.max_width)
            ++hi;
        const bool saturated = value >= p.full_scale;
        *suspect = *suspect || saturated;
        const bool too_wide = hi - lo + 1 > p.max_width;
        // An unsaturated peak must rise extract_min_peak above its local
        // background, not only above zero: on a bright background (a white
        // patch of a target, a lit strip) a ripple of a few counts is no
        // line.
        const bool faint = !saturated && value - background < p.min_value;
        if (saturated && accept_saturated) {
            // The plateau: the rows at full scale around the maximum (within
            // 1/32 of it, across dips of up to 2 rows: a compressed or
            // noisy image ripples there). Too wide a plateau is no line.
            const std::uint32_t plateau_level = p.full_scale - p.full_scale / 32;
            const long most = p.max_width + 1;
            auto plateau_end = [&](long from, long step) {
                long end = from;
                for (long v = from + step; v >= 0 && v <= last && std::labs(v - row) <= most;
                     v += step) {
                    if (px(v) >= plateau_level)
                        end = v;
                    else if (std::labs(v - end) > 2)
                        break;
                }
                return end;
            };
            const long p_lo = plateau_end(row, -1), p_hi = plateau_end(row, 1);
            // The local background on either side: the foot of the line's
            // flank, found by walking away from the plateau until the
            // pixels stop falling (less than 1/64 of full scale over 3
            // rows), at most 2 extract_max_width rows (a saturated line
            // glows wide); the higher of the two feet. Not the lowest pixel
            // around: beyond the foot the strip (or a board) may hold dark
            // features that are no part of the line.
            const long far = 2 * long(p.max_width);
            const std::uint32_t flat = std::max<std::uint32_t>(2, p.full_scale / 64);
            std::uint32_t foot[2];
            for (int side = 0; side < 2; ++side) {
                const long step = side == 0 ? -1 : 1;
                const long start = side == 0 ? p_lo : p_hi;
                std::uint32_t lowest = value;
                for (long j = 1; j <= far; ++j) {
                    const long v = start + step * j;
                    if (v < 0 || v > last)
                        break;
                    const std::uint32_t count = px(v);
                    if (j > 3) {
                        const std::uint32_t before = px(v - 3 * step);
                        if (before < count + flat)
                            break;  // flat: the foot
                    }
                    lowest = std::min(lowest, count);
                }
                foot[side] = lowest;
            }
            const std::uint32_t floor_level = std::max(foot[0], foot[1]);
            const std::uint32_t half2 = value + floor_level;  // 2 x half level
            // Its half-maximum crossings, at most `far` rows out.
            long left = p_lo, right = p_hi;
            while (left > 0 && 2 * px(left - 1) >= half2 && p_lo - left < far)
                --left;
            while (right < last && 2 * px(right + 1) >= half2 && right - p_hi < far)
                ++right;
            if (p_hi - p_lo + 1 <= p.max_width && left > 0 && right < last &&
                2 * px(left - 1) < half2 && 2 * px(right + 1) < half2) {
                const double half = 0.5 * double(half2);
                const double in_l = double(px(left)), out_l = double(px(left - 1));
                const double in_r = double(px(right)), out_r = double(px(right + 1));
                const double cross_l = double(left) - (in_l - half) / (in_l - out_l);
                const double cross_r = double(right) + (in_r - half) / (in_r - out_r);
                shape->width = cross_r - cross_l;
                shape->skew = 0;
                shape->area = inside ? double(sum) - double(2 * r + 1) * double(floor_value) : nan;
                *suspect = true;
                *saturated_out = true;
                return 0.5 * (cross_l + cross_r);
            }
        } else if (!saturated && !too_wide && !faint) {
            // Zero crossing (+ above, - below) of the derivative next to the
            // maximum: at most 2 rows away, linearly interpolated.
            long i = row;
            float d0 = derivative(i);
            double v = nan;
            if (d0 > 0) {
                float d1 = derivative(i + 1);
                for (int step = 0; step < 2 && d1 > 0; ++step)
                    d0 = d1, d1 = derivative(++i + 1);
                if (d1 <= 0)
                    v = double(i) + double(d0) / double(d0 - d1);
            } else if (d0 <= 0) {
                float dm = derivative(i - 1);
                for (int step = 0; step < 2 && dm <= 0; ++step)
                    d0 = dm, dm = derivative(--i - 1);
                if (dm > 0)
                    v = double(i - 1) + double(dm) / double(dm - d0);
            }
            if (v >= double(lo) - 1 && v <= double(hi) + 1) {
                shape->width = shape->skew = shape->area = nan;
                // Half-maximum crossings, searched past the band if need be
                // (the frame's rows are there): 2 px < value is below half.
                const long most = p.max_width + 1;
                long left = lo, right = hi;  // lo, hi stopped at half or at the band
                if (left == band_lo)
                    while (left > 0 && 2 * px(left - 1) >= level2 && row - left <= most)
                        --left;
                if (right == band_hi)
                    while (right < last && 2 * px(right + 1) >= level2 && right - row <= most)
                        ++right;
                if (left > 0 && right < last && 2 * px(left - 1) < level2 &&
                    2 * px(right + 1) < level2) {
                    const double half = 0.5 * double(level2);
                    const double in_l = double(px(left)), out_l = double(px(left - 1));
                    const double in_r = double(px(right)), out_r = double(px(right + 1));
                    const double cross_l = double(left) - (in_l - half) / (in_l - out_l);
                    const double cross_r = double(right) + (in_r - half) / (in_r - out_r);
                    shape->width = cross_r - cross_l;
                    shape->skew = 0.5 * (cross_l + cross_r) - v;
                }
                // (Near the frame's edge the area is left NaN: the shape
                // check then rejects the peak.)
                if (inside)
                    shape->area = double(sum) - double(2 * r + 1) * double(floor_value);
                // A brighter peak was rejected: this one may be a reflection.
                *suspect = *suspect || candidate > 0;
                return v;
            }
        }
        if (candidate == k_max_candidates - 1)
            break;
        // Rejected: the next brightest local maximum outside the rejected
        // peaks (a strided scan, only for the few rejected columns).
        // A peak too wide or too faint and unsaturated is a bright
        // background, not a line (a white patch of a target beside a line
        // over a dark one): all of it is passed over - the rows at or above
        // its half level (too wide), or within extract_min_peak of its
        // maximum (faint) - not only the extract_max_width rows the width
        // walk reached; else its next rows are the next candidates and the
        // line beside it is never reached. (A saturated peak keeps the
        // short range: the line under a glint lies within the glint's glow.)
        if (!saturated && (too_wide || faint)) {
            auto same_patch = [&](long v) {
                const std::uint32_t count = px(v);
                return faint ? count + p.min_value > value : 2 * count >= level2;
            };
            while (lo > band_lo && same_patch(lo - 1))
                --lo;
            while (hi < band_hi && same_patch(hi + 1))
                ++hi;
        }
        excluded_lo[excluded] = lo, excluded_hi[excluded] = hi, ++excluded;
        auto rejected = [&](long v) {
            bool within = false;
            for (int e = 0; e < excluded; ++e)
                within |= v >= excluded_lo[e] && v <= excluded_hi[e];
            return within;
        };
        int next = 0;
        while (next < next_count && rejected(next_row[next]))
            ++next;
        if (next == next_count) {
            next = next_count = 0;
            for (long v = band_lo; v <= band_hi; ++v) {
                if (rejected(v))
                    continue;
                const std::uint32_t value_v = px(v);
                if (value_v == 0 ||
                    (next_count == k_max_candidates && value_v <= next_value[next_count - 1]))
                    continue;
                if ((v > band_lo && px(v - 1) > value_v) || (v < band_hi && px(v + 1) > value_v))
                    continue;  // not a local maximum (e.g. the tail of a rejected peak)
                int at = std::min(next_count, k_max_candidates - 1);
                while (at > 0 && next_value[at - 1] < value_v) {
                    next_value[at] = next_value[at - 1], next_row[at] = next_row[at - 1];
                    --at;
                }
                next_value[at] = value_v, next_row[at] = v;
                next_count = std::min(next_count + 1, k_max_candidates);
            }
            if (next_count == 0)
                break;
        }
        value = next_value[next], row = next_row[next];
    }
    return nan;
}

// column_peak for k_peak_lanes adjacent columns at once, where a column shows
// what nearly every column of a clean line shows: one unsaturated peak, clear
// of the band's ends, that is neither faint nor too wide and whose
// derivative crosses zero next to its maximum. The pixels around each
// column's maximum are read into registers, one lane per column, and the
// background, the width walks, the area and the seven
// Savitzky-Golay derivatives are computed lane by lane with the same
// operations in the same order as column_peak, so a lane it measures holds
// the same bits column_peak gives (test_peak_kernels proves it on random
// columns). Returns the mask of the lanes measured, with row_out[lane] and
// shape[lane] set (neither suspect nor saturated); the caller gives every
// other lane to column_peak.
constexpr int k_peak_lanes = 8;

typedef float peak_lanes_f __attribute__((vector_size(4 * k_peak_lanes)));
typedef std::int32_t peak_lanes_i __attribute__((vector_size(4 * k_peak_lanes)));

template <class Pixel>
__attribute__((always_inline)) inline unsigned
column_peaks_body(const unsigned char *frame, std::size_t stride, std::uint32_t u0,
                  std::uint32_t first, std::uint32_t rows, const std::uint16_t *value,
                  const std::uint16_t *row, const peak_params &p, double *row_out,
                  peak_shape *shape) {
    constexpr int lanes = k_peak_lanes;
    const long reach = p.gather_reach, h = p.sg_half, r = p.shape_reach;
    const long band_lo = long(first), band_hi = long(first + rows) - 1;
    // Rows row - reach .. row + reach of each lane, as counts. A lane whose
    // window touches the band's ends (where column_peak searches past the
    // band) or whose maximum column_peak would pass over is left to it.
    if (reach < 3 + h || reach > k_max_gather_reach)
        return 0;  // (not with create's parameters: the derivatives need 3 + h rows)
    unsigned eligible = 0;
    long inside = -1;  // an eligible lane's first row: its window lies inside the band
    for (int l = 0; l < lanes; ++l) {
        const long rw = row[l];
        const std::uint32_t v = value[l];
        const bool ok = v >= p.min_value && v != 0 && v < p.full_scale && rw - reach > band_lo &&
                        rw + reach < band_hi;
        eligible |= unsigned(ok) << l;
        if (ok && inside < 0)
            inside = rw - reach;
    }
    if (eligible == 0)
        return 0;
    // Each lane's first row (row - reach). A lane left to column_peak reads
    // the rows of an eligible lane's window in its own column: inside the
    // band, so inside the frame, and ignored. (It once read the rows from
    // just below the band's top, which past a short band at the frame's
    // bottom left the frame: the fuzzer found it.)
    const unsigned char *top[lanes];
    for (int l = 0; l < lanes; ++l)
        top[l] = frame +
                 std::size_t(((eligible >> l) & 1u) ? long(row[l]) - reach : inside) * stride +
                 (u0 + std::uint32_t(l)) * sizeof(Pixel);
    // Each lane's rows row - reach .. row + reach as floats (counts below
    // 2^24, and their sums: exact), one row of eight lanes at a time, built
    // in registers.
    auto count = [&](int l, long j) {
        return float(*reinterpret_cast<const Pixel *>(top[l] + std::size_t(j) * stride));
    };
    peak_lanes_f t[2 * k_max_gather_reach + 1];
    for (long j = 0; j <= 2 * reach; ++j)
        t[j] = peak_lanes_f{count(0, j), count(1, j), count(2, j), count(3, j),
                            count(4, j), count(5, j), count(6, j), count(7, j)};
    const peak_lanes_f maximum = {count(0, reach), count(1, reach), count(2, reach),
                                  count(3, reach), count(4, reach), count(5, reach),
                                  count(6, reach), count(7, reach)};
    peak_lanes_f low_left = maximum, low_right = maximum, floor_value = maximum, sum = {};
    for (long j = 0; j < reach; ++j)
        low_left = t[j] < low_left ? t[j] : low_left;
    for (long j = reach + 1; j <= 2 * reach; ++j)
        low_right = t[j] < low_right ? t[j] : low_right;
    for (long j = reach - r; j <= reach + r; ++j) {
        floor_value = t[j] < floor_value ? t[j] : floor_value;
        sum += t[j];
    }
    const peak_lanes_f background = low_left < low_right ? low_right : low_left;
    const peak_lanes_f level2 = maximum + background;
    // The width walks, as column_peak takes them: one more row while it is at
    // or above half the maximum and the line is not yet max_width wide.
    // A walk that would leave the rows read is column_peak's.
    peak_lanes_i go_lo = ~peak_lanes_i{}, go_hi = ~peak_lanes_i{};
    peak_lanes_i n_lo = {}, n_hi = {};
    for (long k = 1; k <= reach; ++k) {
        if (k - 1 > long(p.max_width)) {
            go_lo = go_hi = peak_lanes_i{};
            break;
        }
        go_lo &= 2 * t[reach - k] >= level2;
        go_hi &= 2 * t[reach + k] >= level2;
        n_lo -= go_lo;
        n_hi -= go_hi;
    }
    const peak_lanes_f zero = {};
    const peak_lanes_f min_peak = zero + float(p.min_value);
    const peak_lanes_i fits = (n_lo < int(reach)) & (n_hi < int(reach)) &
                              (n_lo + n_hi + 1 <= p.max_width) & (maximum - background >= min_peak);
    // The derivative at rows row - 3 .. row + 3, in column_peak's order.
    peak_lanes_f derivative[7];
    for (long i = -3; i <= 3; ++i) {
        peak_lanes_f d = {};
        for (long j = 1; j <= h; ++j)
            d += p.sg_taps[h + j] * (t[reach + i + j] - t[reach + i - j]);
        derivative[i + 3] = d;
    }
    // Its zero crossing next to the maximum (+ above, - below), both ways
    // column_peak searches it; each lane takes the way its derivative at the
    // maximum says.
    peak_lanes_f up0 = derivative[3], up1 = derivative[4];
    peak_lanes_i up_i = {};
    {
        const peak_lanes_i step1 = up1 > zero;
        up0 = step1 ? up1 : up0, up1 = step1 ? derivative[5] : up1, up_i -= step1;
        const peak_lanes_i step2 = step1 & (up1 > zero);
        up0 = step2 ? up1 : up0, up1 = step2 ? derivative[6] : up1, up_i -= step2;
    }
    peak_lanes_f down0 = derivative[3], down_m = derivative[2];
    peak_lanes_i down_i = {};
    {
        const peak_lanes_i step1 = down_m <= zero;
        down0 = step1 ? down_m : down0, down_m = step1 ? derivative[1] : down_m, down_i += step1;
        const peak_lanes_i step2 = step1 & (down_m <= zero);
        down0 = step2 ? down_m : down0, down_m = step2 ? derivative[0] : down_m, down_i += step2;
    }
    const peak_lanes_i rising = derivative[3] > zero;
    const peak_lanes_i crossed =
        (rising & (up1 <= zero)) | (~rising & (derivative[3] <= zero) & (down_m > zero));
    const peak_lanes_i measured = fits & crossed;
    alignas(32) float sums[lanes], floors[lanes], levels[lanes];
    std::memcpy(sums, &sum, sizeof sums);
    std::memcpy(floors, &floor_value, sizeof floors);
    std::memcpy(levels, &level2, sizeof levels);
    const long last = long(p.frame_height) - 1;
    unsigned done = 0;
    for (int l = 0; l < lanes; ++l) {
        if (!((eligible >> l) & 1u) || !measured[l])
            continue;
        const long rw = row[l];
        const double v = rising[l] ? double(rw + up_i[l]) + double(up0[l]) / double(up0[l] - up1[l])
                                   : double(rw + down_i[l] - 1) +
                                         double(down_m[l]) / double(down_m[l] - down0[l]);
        const long lo = rw - n_lo[l], hi = rw + n_hi[l];
        if (!(v >= double(lo) - 1 && v <= double(hi) + 1))
            continue;  // column_peak looks for the next candidate
        // The half-maximum crossings: lo and hi stopped at half (inside the
        // rows read, clear of the band's ends), or at max_width (no width
        // then).
        auto count_at = [&](long v_row) {
            return std::uint32_t(*reinterpret_cast<const Pixel *>(
                top[l] + std::size_t(v_row - (rw - reach)) * stride));
        };
        const std::uint32_t level = std::uint32_t(levels[l]);
        peak_shape &out = shape[l];
        out.width = out.skew = std::numeric_limits<double>::quiet_NaN();
        if (lo > 0 && hi < last && 2 * count_at(lo - 1) < level && 2 * count_at(hi + 1) < level) {
            const double half = 0.5 * double(level);
            const double in_l = double(count_at(lo)), out_l = double(count_at(lo - 1));
            const double in_r = double(count_at(hi)), out_r = double(count_at(hi + 1));
            const double cross_l = double(lo) - (in_l - half) / (in_l - out_l);
            const double cross_r = double(hi) + (in_r - half) / (in_r - out_r);
            out.width = cross_r - cross_l;
            out.skew = 0.5 * (cross_l + cross_r) - v;
        }
        out.area =
            double(std::uint32_t(sums[l])) - double(2 * r + 1) * double(std::uint32_t(floors[l]));
        row_out[l] = v;
        done |= 1u << l;
    }
    return done;
}

}  // namespace flt

namespace flt {

template <class Pixel>
inline unsigned column_peaks_base(const unsigned char *frame, std::size_t stride, std::uint32_t u0,
                                  std::uint32_t first, std::uint32_t rows,
                                  const std::uint16_t *value, const std::uint16_t *row,
                                  const peak_params &p, double *row_out, peak_shape *shape) {
    return column_peaks_body<Pixel>(frame, stride, u0, first, rows, value, row, p, row_out, shape);
}

#if FLT_PEAK_AVX2
template <class Pixel>
FLT_TARGET_AVX2 inline unsigned column_peaks_avx2(const unsigned char *frame, std::size_t stride,
                                                  std::uint32_t u0, std::uint32_t first,
                                                  std::uint32_t rows, const std::uint16_t *value,
                                                  const std::uint16_t *row, const peak_params &p,
                                                  double *row_out, peak_shape *shape) {
    return column_peaks_body<Pixel>(frame, stride, u0, first, rows, value, row, p, row_out, shape);
}
#endif

template <class Pixel>
inline unsigned column_peaks(const unsigned char *frame, std::size_t stride, std::uint32_t u0,
                             std::uint32_t first, std::uint32_t rows, const std::uint16_t *value,
                             const std::uint16_t *row, const peak_params &p, double *row_out,
                             peak_shape *shape) {
#if FLT_PEAK_AVX2
    if (cpu_has_avx2())
        return column_peaks_avx2<Pixel>(frame, stride, u0, first, rows, value, row, p, row_out,
                                        shape);
#endif
    return column_peaks_base<Pixel>(frame, stride, u0, first, rows, value, row, p, row_out, shape);
}

}  // namespace flt
