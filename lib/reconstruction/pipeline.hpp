// SPDX-License-Identifier: Apache-2.0
// Internal: the reconstructor as the C API sees it. Wraps recon_engine with
// the rigid-motion split.
//
// Why the split: a bouncing strip moves as a rigid body. At one frame every
// fiber's height is offset by the same heave plus a roll that is linear
// across the width, so the frame's heights scatter by millimetres around a
// line across the strip while their deviations from that line carry only the
// peak-detection noise (hundredths of a millimetre). Fitting each fiber alone
// would have to treat every height as millimetres-noisy and average its level
// over metres of strip, separately per fiber.
//
// With rigid_motion on, each row is split, per measurement kind, into
//   - the least-squares line across the valid fibers, a + b*xi (xi = fiber
//     index minus the centre index), and
//   - the deviations from it,
// and three engines reconstruct them: the deviations of all fibers
// (heights weighted by shape_sigma), the line's offset a and its tilt b
// (heights weighted by the vibration, height_sigma; slopes by slope_sigma
// shrunk by the number of fibers they average). The output is the sum,
// z_k = dev_k + a + b*xi_k. All three engines see the same rows on the same
// knot grid with the same lag, so they finish the same rows at the same time,
// and each is C1 and carries its boundary across sheets, so the sum is too.
//
// The split must not depend on which fibers a row happens to have: a line
// fitted to a different subset jumps by (surface deviation of the missing
// fibers) / (fibers), and the two channels would smooth that jump
// differently. So a missing fiber that has been seen before takes part in the
// fit with its predicted deviation (its last deviation, moved on by its last
// deviation slope); see split().
#pragma once

#include <cstdint>
#include <memory>

#include "reconstruction/robust.hpp"

namespace flt {

struct recon_config {
    recon_params params;   // the main (or only) engine's parameters
    robust_params robust;  // robust reweighting of every channel
    // With rigid_motion, the reweighted stages of the line channels, which
    // carry the shear station's ringing (it hits every fiber alike); they
    // are one value per row, so their stages cost next to nothing.
    int line_iterations = 8;
    bool rigid_motion = true;
    double shape_sigma = 0.1;  // mm, sigma of a height's deviation from the frame's line
};

class recon_pipeline {
  public:
    // batch: made for batch(), whose rows go to z_store / flags_store.
    recon_pipeline(std::size_t fibers, const recon_config &config, std::size_t knot_capacity,
                   double *z_store = nullptr, std::uint8_t *flags_store = nullptr,
                   bool batch = false);

    // The bytes the constructor with these arguments allocates (see
    // recon_engine::bytes_needed); batch as in the constructor, with
    // z_store given.
    static double bytes_needed(std::size_t fibers, const recon_config &config,
                               std::size_t knot_capacity, bool batch);

    std::size_t fibers() const { return K_; }
    const recon_config &config() const { return config_; }
    std::size_t free_rows() const;
    // The channels have different latencies (the line channels run more
    // reweighted stages): a row is ready when every channel has finished it.
    std::size_t ready_rows() const;
    // Streaming: about how far behind the newest row rows are finished, in
    // knot intervals (the slowest channel's).
    long latency_knots() const;
    bool has_last_s() const { return main_->has_last_s(); }
    double last_s() const { return main_->last_s(); }
    bool rows_since_sheet() const { return main_->rows_since_sheet(); }
    bool pushed_since_reset() const { return main_->pushed_since_reset(); }
    bool has_boundary() const { return main_->has_boundary(); }

    void push_row(double s, const double *height, const double *slope, const std::uint8_t *valid);
    std::size_t pull(std::size_t max_rows, double *s_out, double *z_out, std::uint8_t *flags_out);
    // The rows held, skipping the `offset` oldest: finished ones as pull()
    // will give them, pending ones as the reconstructor estimates them now
    // (provisional, given every row pushed so far). Changes nothing that
    // pull() gives. Returns the rows written.
    std::size_t peek(std::size_t offset, std::size_t max_rows, double *s_out, double *z_out,
                     std::uint8_t *flags_out);
    void end_sheet();
    void reset();
    void boundary(double *s_out, double *height_out, double *slope_out) const;
    // Batch use (flt_reconstruct): the whole sheet, into z_store (rows
    // 0..rows-1, the row capacity) and flags_store. valid may be nullptr.
    void batch(std::size_t rows, const double *s, const double *height, const double *slope,
               const std::uint8_t *valid, double *z_store);
    // Batch: the next call's z_store / flags_store (a workspace serves one
    // call after another; flags_store nullptr only if it was constructed
    // so).
    void rebind_rows(double *z_store, std::uint8_t *flags_store) {
        main_->rebind_rows(z_store, flags_store);
    }

  private:
    // Through a 32-bit integer, which vectorises (fibers < 2^31, recon_api.cpp).
    double xi(std::size_t k) const { return double(std::int32_t(k)) - 0.5 * double(K_ - 1); }
    // Heights are solved relative to the strip's level (pipeline.cpp,
    // relative_heights): the first valid height since reset, mm.
    void find_level(const double *height, const std::uint8_t *valid);
    void relative_heights(const double *height, double *out) const;
    // Splits one kind of measurement (heights or slopes) of a row.
    void split(double s, const double *value, const std::uint8_t *valid, bool is_height, double *a,
               double *b, double *dev);
    // z += (a + b xi) + level, row by row.
    void add_lines(std::size_t rows, const double *a, const double *b, double level,
                   double *z) const;
    // batch() on heights relative to the level.
    void batch_fibers(std::size_t rows, const double *s, const double *height, const double *slope,
                      const std::uint8_t *valid, double *z_store);

    std::size_t K_;
    recon_config config_;
    std::unique_ptr<recon_chain> main_, offset_, tilt_;
    // Scratch, allocated once: one detrended row, and line channels of
    // pulled rows.
    std::vector<double> dev_h_, dev_g_, line_a_, line_b_, line_s_;
    // Per fiber: the last valid deviations and where the height one was seen.
    std::vector<double> last_dev_h_, last_dev_g_, last_dev_s_;
    std::vector<std::uint8_t> has_dev_h_, has_dev_g_;
    bool has_all_[2] = {false, false};  // has_dev_h_ / has_dev_g_ all set
    // Scratch of split() for a row with missing fibers: 1 where valid, and
    // the value or predicted deviation that enters the line's sums.
    std::vector<double> ok_, fill_;
    // Batch with rigid_motion: every row's line, heights' and slopes'.
    std::vector<double> batch_ha_, batch_hb_, batch_ga_, batch_gb_;
    bool new_strip_ = true;
    // The strip's level (mm) and one row of heights relative to it.
    double level_ = 0.0;
    bool has_level_ = false;
    std::vector<double> rel_h_;
};

}  // namespace flt
