// SPDX-License-Identifier: Apache-2.0
// Internal: a window's rows in strip coordinates (flatline/flatness.h,
// "Zones on the strip").
//
// The sensor's fibers stay where they are while the strip moves under them
// (it wanders sideways, narrows at a coil change, sits off-centre). An
// operator reads zones from the strip's edges, so a window in which the
// edges are known is resampled onto fibers fixed to the strip: per row,
// result fiber k lies at strip coordinate x_s(k) = (k - (K - 1) / 2) p (mm
// from the strip's centre line, towards the operator side), that is at
// sensor x = c_row + side * x_s(k), and its height is interpolated
// linearly between the two sensor fibers around that x. The flatness engine
// then measures these fibers exactly as it measures the grid's.
//
// The centre line c_row is smoothed along travel (a moving mean over
// +-k_centre_smoothing_mm of strip): the edges come from the extractor with
// a fraction of a millimetre of noise per row, and a fiber that jumped
// sideways by that much from row to row would pick up the cross slope of
// the strip as a longitudinal wiggle, which the arc length turns into
// I-Units (0.05 mm of jitter on a 0.1 cross slope: about 1 I-Unit).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "flatness/metrics.hpp"

namespace flt {

// Half the window of the moving mean of the strip's centre line and width
// along travel, mm of strip.
constexpr double k_centre_smoothing_mm = 100.0;

class strip_resampler {
  public:
    // Scratch for windows of up to `rows` rows of `fibers` fibers with
    // `zones` zones at most (the only allocation; evaluate() grows it for
    // larger sheets, the streaming path never does).
    void reserve(std::size_t rows, std::size_t fibers, std::size_t zones);

    // Finds the strip in rows [0, rows): per row its edges from left/right
    // (NaN = unknown; either array may be null) or else from the flags'
    // FLT_FLAG_OFF_STRIP bits (flags may be null). False when no row knows
    // both edges: the window is measured on the grid.
    bool locate(const fiber_layout &grid, std::size_t rows, const double *s,
                const std::uint8_t *flags, const double *left, const double *right);

    // The fiber grid itself as the strip (no edges known), for windows
    // measured from the high-x side.
    void locate_grid(const fiber_layout &grid, std::size_t rows);

    // Resamples the located window onto fibers in strip coordinates, with
    // `side` = +1 (drive side at low sensor x) or -1, and lays zones of
    // zone_width or zone_count (> 0) zones, at most max_zones. The layout
    // and the rows are then ready for the flatness engine. The rows are
    // resampled in blocks on `runner` (each row's result is its own: the
    // same whatever runs them).
    void resample(const fiber_layout &grid, int side, std::size_t rows, const double *z,
                  const std::uint8_t *flags, double zone_width, std::size_t zone_count,
                  std::size_t max_zones, block_runner &runner);

    const fiber_layout &layout() const { return layout_; }
    const double *z() const { return z_.data(); }
    const std::uint8_t *flags() const { return flags_.data(); }
    double width() const { return width_; }
    // Over the located rows: {mean, min, max} of the smoothed width and
    // centre line, mm.
    void statistics(double width_out[3], double centre_out[3]) const;
    double mean_centre() const { return mean_centre_; }

  private:
    static void smooth(std::size_t rows, const double *s, const std::vector<double> &in,
                       std::vector<double> &out);
    // Rows [first, last) of resample.
    void resample_rows(std::size_t first, std::size_t last, const fiber_layout &grid, int side,
                       const double *z, const std::uint8_t *flags);

    fiber_layout layout_;
    std::vector<double> z_;            // [rows * fibers] mm, NaN where unusable
    std::vector<std::uint8_t> flags_;  // [rows * fibers] FLT_FLAG_NO_DATA where unusable
    std::vector<double> left_, right_, centre_, width_row_;  // [rows] per row
    std::vector<double> centre_smooth_, width_smooth_;       // [rows]
    std::vector<double> widths_;                             // median scratch
    std::size_t rows_ = 0;
    bool on_grid_ = false;  // locate_grid: the grid's own zones
    double width_ = 0.0, mean_centre_ = 0.0;
};

}  // namespace flt
