// SPDX-License-Identifier: Apache-2.0
// Internal: the flatness computation of one window (flatline/flatness.h),
// independent of how the rows arrived (whole sheet or streamed buffer).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/block_runner.hpp"
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
    std::size_t zone_count;  // 0 = zones of zone_width
    bool drive_side_high;    // the drive side is at high sensor x
    bool zones_on_grid;      // never lay zones on the strip
};

// Fibers across the width and their zones: the sensor's fiber grid (fixed
// at create time), or a window's fibers in strip coordinates (strip.hpp).
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
    static double zones_needed(const double *fiber_x, std::size_t fibers, double width_of_zone,
                               std::size_t count_of_zones);
    // The grid: zones of zone_width, or zone_count equal zones (> 0).
    void build(const double *fiber_x, std::size_t fibers, double width_of_zone,
               std::size_t count_of_zones);
    // `zones` zones of zone_width centred on `centre`, the fibers already
    // in x; fibers beyond the half width belong to no zone's count (they
    // are off the strip). A fiber on a zone boundary belongs to the zone
    // above it, or with ties_to_centre to the one nearer the centre (the
    // strip's layouts: the same from the drive and the operator side).
    // Reuses the capacity: no allocation once reserved.
    void lay_zones(double width_of_zone, std::size_t zones, bool ties_to_centre = false);
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
    // Where the results lie (flt_flatness_fiber_positions/zone_positions)
    // and the strip over the window (flt_flatness_strip).
    std::vector<double> fiber_strip_x, fiber_sensor_x;               // [fibers] mm
    std::vector<double> zone_strip_x, zone_sensor_x, zone_width_mm;  // [zones] mm
    std::vector<std::size_t> zone_fibers;                            // [zones]
    double strip_width[3] = {0, 0, 0}, strip_centre[3] = {0, 0, 0};  // mean, min, max

    void allocate(std::size_t fibers, std::size_t zones);
};

// Scratch reused by every evaluation: one fiber's column and per-fiber sums.
class flatness_engine {
  public:
    // layout: the grid; zone scratch is sized for its zones (the most any
    // layout given to evaluate may have).
    flatness_engine(const flatness_params &params, const fiber_layout &layout);
    // The fibers and zones the next evaluations use (the grid, or a
    // window's strip layout with the same fiber count). Kept by reference.
    void use_layout(const fiber_layout &layout) { layout_ = &layout; }

    // Grows the column scratch to `rows` (the only allocation after create;
    // never on the streaming path, whose windows are capped at row_capacity).
    void reserve_rows(std::size_t rows);

    // The threads the fibers are evaluated on, in blocks (by default the
    // caller's alone). Makes a column scratch per participant (allocates).
    // The runner must outlive the engine's evaluations. Each fiber's
    // results are its own, so they are the same bit for bit whatever runs
    // the blocks.
    void use_runner(block_runner *runner);
    // The runner evaluations use (the window's other blocks run on it too).
    block_runner &runner() const { return *runner_; }

    // Evaluates rows [0, rows) of a row-major block (row stride = fibers).
    // flags may be null. Writes every field of `out` except `index`.
    void evaluate(std::size_t rows, const double *s, const double *z, const std::uint8_t *flags,
                  window_result &out);

  private:
    struct wave {
        double height, period;
    };
    // Column of one fiber: position, height, usable (one per participant
    // of the runner).
    struct column {
        std::vector<double> s, z;
        std::vector<std::uint8_t> ok;
    };
    // Largest crest-trough-crest wave of the gathered column; false if none.
    bool largest_wave(const column &c, std::size_t rows, wave &best) const;
    // Fibers [first, last) of the rows: each one's stretch, bow, mean and
    // largest wave, or its NO_DATA flag.
    void evaluate_fibers(std::size_t first, std::size_t last, column &c, std::size_t rows,
                         const double *s, const double *z, const std::uint8_t *flags,
                         window_result &out);
    void classify(window_result &out);

    const flatness_params &p_;
    const fiber_layout *layout_;
    inline_block_runner inline_runner_;
    block_runner *runner_ = &inline_runner_;
    std::vector<column> columns_;
    std::size_t column_rows_ = 0;
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
