// SPDX-License-Identifier: Apache-2.0
// Internal: the flatness computation of one window (flatline/flatness.h),
// independent of how the rows arrived (whole sheet or streamed buffer).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "flatline/flatness.h"

namespace flt {

struct flatness_params {
    double window_length;    // mm, 0 = sheet mode
    double update_interval;  // mm, resolved (never 0 unless sheet mode)
    double zone_width;       // mm
    bool reference_mean;     // I-Unit reference: mean (true) or shortest
    double min_length;       // mm
    double min_coverage;     // 0..1
    double wave_hysteresis;  // mm
    double flat_limit;       // I-Units
    double bow_limit;        // mm
    double crossbow_limit;   // mm
    std::size_t row_capacity;
};

// The fiber grid and its zones: fixed at create time.
struct fiber_layout {
    std::vector<double> x;                // [fibers] mm
    double centre = 0.0;                  // mm, middle of the grid
    double half_width = 0.0;              // mm, half the covered width
    double zone_width = 0.0;              // mm
    std::vector<double> zone_left;        // [zones] mm
    std::vector<std::size_t> zone_of;     // [fibers]
    std::vector<std::size_t> zone_count;  // [zones]

    // The zone count build() makes, as a double (the API bounds it before
    // building: a wide grid of narrow zones is millions of them).
    static double zones_needed(const double *fiber_x, std::size_t fibers, double width_of_zone);
    void build(const double *fiber_x, std::size_t fibers, double width_of_zone);
    std::size_t fibers() const { return x.size(); }
    std::size_t zones() const { return zone_left.size(); }
};

// Everything one window produces.
struct window_result {
    double s_first = 0.0, s_last = 0.0;
    std::size_t rows = 0;
    unsigned flags = 0;
    std::size_t index = 0;
    std::vector<double> arc_length, i_units, wave_height, wave_period,
        steepness;                          // [fibers]
    std::vector<std::uint8_t> fiber_flags;  // [fibers]
    std::vector<double> zone_i_units;       // [zones]
    std::vector<std::uint8_t> zone_flags;   // [zones]
    flt_shape shape = FLT_SHAPE_UNDETERMINED;
    double confidence = 0.0;
    unsigned components = 0;
    double bow_mm = 0.0, crossbow_mm = 0.0;

    void allocate(std::size_t fibers, std::size_t zones);
};

// Scratch reused by every evaluation: one fiber's column and per-fiber sums.
class flatness_engine {
  public:
    flatness_engine(const flatness_params &params, const fiber_layout &layout);

    // Grows the column scratch to `rows` (the only allocation after create;
    // never on the streaming path, whose windows are capped at row_capacity).
    void reserve_rows(std::size_t rows);

    // Evaluates rows [0, rows) of a row-major block (row stride = fibers).
    // flags may be null. Writes every field of `out` except `index`.
    void evaluate(std::size_t rows, const double *s, const double *z, const std::uint8_t *flags,
                  window_result &out);

  private:
    struct wave {
        double height, period;
    };
    // Largest crest-trough-crest wave of the gathered column; false if none.
    bool largest_wave(std::size_t rows, wave &best) const;
    void classify(window_result &out);

    const flatness_params &p_;
    const fiber_layout &layout_;
    // Column of one fiber: position, height, usable.
    std::vector<double> col_s_, col_z_;
    std::vector<std::uint8_t> col_ok_;
    // Per fiber: chord excess per covered mm, longitudinal parabola
    // coefficient (sagitta over the window, mm), mean height (mm).
    std::vector<double> stretch_, bow_coef_, mean_z_;
    std::vector<std::size_t> order_;
    // Per valid zone, for the shape: I-Units above the lowest zone, fibers,
    // band across the width.
    std::vector<double> zone_value_, zone_weight_;
    std::vector<int> zone_band_;
};

}  // namespace flt
