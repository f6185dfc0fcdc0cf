// SPDX-License-Identifier: Apache-2.0
#include "flatness/strip.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "flatline/recon.h"

namespace flt {
namespace {

constexpr double nan_value = std::numeric_limits<double>::quiet_NaN();
// Reconstructor flags that make a sample unusable (as in metrics.cpp).
constexpr std::uint8_t k_unusable = FLT_FLAG_NO_DATA | FLT_FLAG_GAP | FLT_FLAG_OFF_STRIP;

}  // namespace

void strip_resampler::reserve(std::size_t rows, std::size_t fibers, std::size_t zones) {
    if (z_.size() < rows * fibers) {
        z_.resize(rows * fibers);
        flags_.resize(rows * fibers);
    }
    if (left_.size() < rows) {
        for (std::vector<double> *v :
             {&left_, &right_, &centre_, &width_row_, &centre_smooth_, &width_smooth_, &widths_})
            v->resize(rows);
    }
    layout_.x.reserve(fibers);
    layout_.zone_of.reserve(fibers);
    layout_.zone_left.reserve(zones);
    layout_.zone_count.reserve(zones);
}

bool strip_resampler::locate(const fiber_layout &grid, std::size_t rows, const double *s,
                             const std::uint8_t *flags, const double *left, const double *right) {
    on_grid_ = false;
    rows_ = rows;
    const std::size_t K = grid.fibers();
    const double *x = grid.x.data();
    std::size_t with_width = 0;
    for (std::size_t r = 0; r < rows; ++r) {
        double l = left ? left[r] : nan_value, h = right ? right[r] : nan_value;
        bool absent = false;
        if (!(l == l) && !(h == h) && flags) {
            // From the flags: the edge lies half way between the last fiber
            // off the strip and the first on it.
            const std::uint8_t *f = flags + r * K;
            std::size_t a = 0;
            while (a < K && (f[a] & FLT_FLAG_OFF_STRIP))
                ++a;
            if (a == K) {
                absent = true;  // every fiber off the strip: no strip here
            } else {
                std::size_t b = K - 1;
                while (f[b] & FLT_FLAG_OFF_STRIP)
                    --b;
                if (a > 0)
                    l = 0.5 * (x[a - 1] + x[a]);
                if (b + 1 < K)
                    h = 0.5 * (x[b] + x[b + 1]);
            }
        }
        left_[r] = l;
        right_[r] = h;
        width_row_[r] = l == l && h == h ? h - l : nan_value;
        if (width_row_[r] == width_row_[r])
            widths_[with_width++] = width_row_[r];
        // Absent rows are marked by an infinite centre until smoothing.
        centre_[r] = absent ? std::numeric_limits<double>::infinity() : nan_value;
    }
    if (with_width == 0)
        return false;
    std::nth_element(widths_.begin(), widths_.begin() + long(with_width / 2),
                     widths_.begin() + long(with_width));
    width_ = widths_[with_width / 2];
    for (std::size_t r = 0; r < rows; ++r) {
        if (centre_[r] == centre_[r])
            continue;  // absent
        const double l = left_[r], h = right_[r];
        centre_[r] = l == l && h == h ? 0.5 * (l + h)
                     : l == l         ? l + 0.5 * width_
                     : h == h         ? h - 0.5 * width_
                                      : nan_value;
    }
    smooth(rows, s, centre_, centre_smooth_);
    smooth(rows, s, width_row_, width_smooth_);
    double sum = 0.0;
    std::size_t n = 0;
    for (std::size_t r = 0; r < rows; ++r)
        if (centre_smooth_[r] == centre_smooth_[r])
            sum += centre_smooth_[r], ++n;
    mean_centre_ = n ? sum / double(n) : nan_value;
    return n > 0;
}

void strip_resampler::locate_grid(const fiber_layout &grid, std::size_t rows) {
    on_grid_ = true;
    rows_ = rows;
    width_ = 2.0 * grid.half_width;
    mean_centre_ = grid.centre;
    std::fill(centre_smooth_.begin(), centre_smooth_.begin() + long(rows), grid.centre);
    std::fill(width_smooth_.begin(), width_smooth_.begin() + long(rows), width_);
}

// A moving least-squares line over +-k_centre_smoothing_mm of s through the
// finite values of `in`, evaluated at each row: the mean where the window
// is symmetric, and no lag behind a strip drifting sideways at the ends of
// the window (where a plain mean would trail by half the window's drift).
// NaN where the window holds no value, and where `in` is infinite (no strip
// in that row). The sums run with s relative to the first row, small
// enough that their squares keep their digits.
void strip_resampler::smooth(std::size_t rows, const double *s, const std::vector<double> &in,
                             std::vector<double> &out) {
    std::size_t lo = 0, hi = 0, count = 0;
    const double s0 = rows ? s[0] : 0.0;
    double sum = 0.0, sum_t = 0.0, sum_tt = 0.0, sum_vt = 0.0;
    auto add = [&](std::size_t j, double sign) {
        const double t = s[j] - s0, v = in[j];
        sum += sign * v, sum_t += sign * t, sum_tt += sign * t * t, sum_vt += sign * v * t;
    };
    for (std::size_t r = 0; r < rows; ++r) {
        while (hi < rows && s[hi] <= s[r] + k_centre_smoothing_mm) {
            if (std::isfinite(in[hi]))
                add(hi, 1.0), ++count;
            ++hi;
        }
        while (s[lo] < s[r] - k_centre_smoothing_mm) {
            if (std::isfinite(in[lo]))
                add(lo, -1.0), --count;
            ++lo;
        }
        if (std::isinf(in[r]) || count == 0) {
            out[r] = nan_value;
            continue;
        }
        const double n = double(count), mean_t = sum_t / n, mean_v = sum / n;
        const double var_t = sum_tt / n - mean_t * mean_t;
        // A slope needs a spread of positions: at least a few mm of strip.
        const double slope = var_t > 1.0 ? (sum_vt / n - mean_t * mean_v) / var_t : 0.0;
        out[r] = mean_v + slope * (s[r] - s0 - mean_t);
    }
}

void strip_resampler::resample(const fiber_layout &grid, int side, std::size_t rows,
                               const double *z, const std::uint8_t *flags, double zone_width,
                               std::size_t zone_count, std::size_t max_zones,
                               block_runner &runner) {
    const std::size_t K = grid.fibers();
    // Result fiber k at x_s(k) = (k - (K - 1) / 2) p, p the grid's mean
    // pitch: slot k keeps its place on the strip.
    const double pitch = 2.0 * grid.half_width / double(K);
    layout_.x.resize(K);
    for (std::size_t k = 0; k < K; ++k)
        layout_.x[k] = (double(k) - 0.5 * double(K - 1)) * pitch;
    layout_.centre = 0.0;
    layout_.half_width = 0.5 * width_;
    // Zones of zone_width: as many as cover the strip, but a strip wider
    // than n zones by less than a pitch (its measured width wanders by a
    // fraction of a millimetre) keeps n; its fibers beyond them count in
    // the outer zones.
    // The count is clamped in double before the conversion: an absurd but
    // finite width (edges given as +-1e300) must not overflow size_t.
    const double fitting =
        std::min(std::ceil((width_ - pitch) / zone_width - 1e-9), double(max_zones));
    std::size_t zones = on_grid_ ? grid.zones()
                        : zone_count > 0
                            ? zone_count
                            : std::max<std::size_t>(1, std::size_t(std::max(fitting, 1.0)));
    zones = std::min(zones, max_zones);
    layout_.lay_zones(on_grid_         ? grid.zone_width
                      : zone_count > 0 ? width_ / double(zone_count)
                                       : zone_width,
                      zones, !on_grid_);

    // Rows in blocks on the runner's threads (a fixed size: the same
    // blocks whatever the threads).
    constexpr std::size_t k_block_rows = 128;
    auto body = [&](std::size_t b, unsigned) {
        const std::size_t first = b * k_block_rows;
        resample_rows(first, std::min(rows, first + k_block_rows), grid, side, z, flags);
    };
    run_blocks(runner, (rows + k_block_rows - 1) / k_block_rows, body);
}

void strip_resampler::resample_rows(std::size_t first, std::size_t last, const fiber_layout &grid,
                                    int side, const double *z, const std::uint8_t *flags) {
    const std::size_t K = grid.fibers();
    const double *gx = grid.x.data();
    const double half = 0.5 * width_ * (1 + 1e-12);
    for (std::size_t r = first; r < last; ++r) {
        const double c = centre_smooth_[r];
        const double *zr = z + r * K;
        const std::uint8_t *fr = flags ? flags + r * K : nullptr;
        double *out = z_.data() + r * K;
        std::uint8_t *out_flags = flags_.data() + r * K;
        auto usable = [&](std::size_t i) {
            return std::fabs(zr[i]) <= 1.0e9 &&  // as metrics.cpp: larger is no height; NaN: false
                   !(fr && (fr[i] & k_unusable));
        };
        // A slot between the strip's last usable sensor fiber and the next
        // one, which is off the strip (flagged so, or outside the located
        // strip) or within a pitch of the edge without a height (the
        // extractor needs two columns of strip to fit a fiber), lies on
        // the strip less than a pitch from the usable fiber: its height is
        // extrapolated linearly from the last two usable fibers. Left
        // unread, the slot next to each edge would be measured or not
        // depending on where the edge falls on the fiber grid, and on a
        // wavy edge it is the edge zone's longest fiber. A fiber without
        // data further inside is a hole, not an edge: its slots stay unread.
        auto at_edge = [&](std::size_t unusable, std::size_t usable_one, double centre) {
            const double pitch = std::fabs(gx[unusable] - gx[usable_one]);
            return (fr && (fr[unusable] & FLT_FLAG_OFF_STRIP)) ||
                   std::fabs(gx[unusable] - centre) > half - pitch;
        };
        // Through inner fiber `in` and the next one inwards, `next`
        // (NaN when that is not usable or not on the grid).
        auto extrapolated = [&](std::size_t in, std::size_t next, double at) {
            if (next >= K || !usable(next))
                return nan_value;
            return zr[in] + (at - gx[in]) * (zr[in] - zr[next]) / (gx[in] - gx[next]);
        };
        // Sensor x grows with the walk: slots in order for side +1, in
        // reverse for side -1.
        std::size_t i = 0;
        for (std::size_t step = 0; step < K; ++step) {
            const std::size_t k = side > 0 ? step : K - 1 - step;
            const double xs = layout_.x[k];
            double value = nan_value;
            if (c == c && std::fabs(xs) <= half) {
                const double x = c + double(side) * xs;
                while (i + 2 < K && gx[i + 1] <= x)
                    ++i;
                if (x >= gx[0] && x <= gx[K - 1]) {
                    if (K == 1) {
                        if (usable(0))
                            value = zr[0];
                    } else {
                        const double w = (x - gx[i]) / (gx[i + 1] - gx[i]);
                        const bool a = usable(i), b = usable(i + 1);
                        if (w <= 1e-9 ? a : w >= 1 - 1e-9 ? b : a && b)
                            value = w <= 1e-9       ? zr[i]
                                    : w >= 1 - 1e-9 ? zr[i + 1]
                                                    : zr[i] + w * (zr[i + 1] - zr[i]);
                        else if (a != b && at_edge(a ? i + 1 : i, a ? i : i + 1, c))
                            value = a ? extrapolated(i, i - 1, x) : extrapolated(i + 1, i + 2, x);
                    }
                }
            }
            out[k] = value;
            out_flags[k] = value == value ? 0 : std::uint8_t(FLT_FLAG_NO_DATA);
        }
    }
}

void strip_resampler::statistics(double width_out[3], double centre_out[3]) const {
    for (int which = 0; which < 2; ++which) {
        const std::vector<double> &v = which == 0 ? width_smooth_ : centre_smooth_;
        double *out = which == 0 ? width_out : centre_out;
        double sum = 0.0, lo = std::numeric_limits<double>::infinity(), hi = -lo;
        std::size_t n = 0;
        for (std::size_t r = 0; r < rows_; ++r)
            if (v[r] == v[r]) {
                sum += v[r], ++n;
                lo = std::min(lo, v[r]);
                hi = std::max(hi, v[r]);
            }
        out[0] = n ? sum / double(n) : nan_value;
        out[1] = n ? lo : nan_value;
        out[2] = n ? hi : nan_value;
    }
}

}  // namespace flt
