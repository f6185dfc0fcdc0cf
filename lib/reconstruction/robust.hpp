// SPDX-License-Identifier: Apache-2.0
// Internal: robust reconstruction, an M-estimator (Huber or Tukey) that
// streams.
//
// Stage 0 is the plain fit (the options' noise levels); stage i refits the
// same raw rows judged against stage i-1: each sample's residual against
// stage i-1's estimate (what the two lasers would have measured on it)
// gives
//   - per fiber and measurement kind, a running robust scale (a clipped mean
//     of |residual| per block of rows, the median of the last blocks': no
//     noise level needs to be given), which sets the fiber's weight
//     1/scale^2, and
//   - per sample, how it enters: Huber's moderate residuals as
//     pseudo-observations (prediction + clipped residual, no change to the
//     window matrix), gross ones and all of Tukey's with a weight multiplier
//     on the raw value (robust.cpp says why).
// Streaming, the stages are a pipeline: a row enters stage i once stage i-1
// has emitted every knot under it, so each stage adds its lag to the
// latency; intermediate stages use a short lag (stage_lag_knots), the last
// one the reconstructor's lag_knots. Every stage carries its own boundary
// across sheets, and the output, from the last stage, is C1 like the plain
// one. Batch (flt_reconstruct), the stages are passes over the whole sheet
// in one engine (recon_chain::batch). Deterministic: no randomness, a fixed
// number of stages.
#pragma once

#include <memory>
#include <vector>

#include "reconstruction/engine.hpp"

namespace flt {

enum class robust_kind { none = 0, huber = 1, tukey = 2 };

struct robust_params {
    robust_kind kind = robust_kind::none;
    int iterations = 2;            // reweighted stages after the plain one
    long stage_lag_knots = 8;      // lag of the intermediate stages
    std::size_t block_rows = 64;   // rows per scale block (192 mm at 3 mm)
    std::size_t scale_blocks = 9;  // blocks whose medians make the scale
};

// Running robust scale of one measurement kind, per fiber: per block of
// rows, the mean of |residual| clipped at 3 times the current scale (O(1) per
// sample; the clip bounds what an outlier can add), converted to a Gaussian
// sigma; the scale is the median of the last blocks' values, so a burst of
// outliers spoils at most a block or two. The caller adds each row's
// clipped residuals to sum() and count() (fused with its other per-sample
// work), then calls end_row().
class robust_scale {
  public:
    robust_scale(std::size_t fibers, std::size_t block_rows, std::size_t blocks,
                 double initial_sigma);
    double *sum() { return sum_.data(); }
    double *count() { return count_.data(); }
    // One row was added. Returns true when a block completed and the scales
    // changed.
    bool end_row();
    const double *sigma() const { return sigma_.data(); }
    const double *inv_var() const { return inv_var_.data(); }  // 1 / sigma^2
    void reset();

  private:
    void median_scalar(std::size_t k);

    std::size_t K_, block_rows_, blocks_;
    double initial_;
    std::vector<double> sum_, count_;  // per fiber, this block
    std::size_t rows_ = 0;
    std::vector<double> estimates_;  // ring [blocks][K], NaN when empty
    std::size_t next_ = 0;
    std::size_t filled_ = 0;          // blocks in the ring since reset
    std::vector<double> sigma_;       // per fiber
    std::vector<double> inv_var_;     // per fiber, 1 / sigma^2
    std::vector<double> incomplete_;  // scratch: 1 where a fiber has a NaN block
};

// Where batch pass `pass` (0, 1, ...) reads row r of the sheet: its heights
// and slopes, and validity (nullptr: every finite sample is valid), good
// until the next call. Each pass asks for rows 0, 1, ... in order.
// A reweighting pass (pass > 0) may instead get values that still carry a
// line across the strip, which it takes off as it reads them: line =
// {a_h, b_h, a_g, b_g, centre}, the value of fiber k being
// value - (a + b * (k - centre)); the first pass gets no line (all zero).
// (With rigid_motion the fibers' deviations are the caller's rows minus the
// row's line; recomputing them in a pass of their own costs as much again.)
class row_source {
  public:
    virtual void row(int pass, std::size_t r, const double **height, const double **slope,
                     const std::uint8_t **valid, double line[5]) = 0;

  protected:
    ~row_source() = default;
};

// One channel (a set of fibers) reconstructed robustly, or plainly when
// robust.kind is none (a single stage). Same interface as recon_engine.
//
// Batch use (flt_reconstruct) has the whole sheet at hand, so it need not
// pipeline the stages: batch() runs them as passes over the sheet, one
// after the other, in one engine, each pass predicting from the previous
// pass's whole-sheet solution (no lag at all, where streaming stages have
// 8 knots). Nothing is queued, and the memory is one engine's.
class recon_chain {
  public:
    // batch: made for batch() (a single engine, no queues), with the
    // caller's z_store / flags_store for every row of the sheet.
    recon_chain(std::size_t fibers, const recon_params &params, const robust_params &robust,
                std::size_t knot_capacity, double *z_store = nullptr,
                std::uint8_t *flags_store = nullptr, bool batch = false);

    // The bytes the constructor with these arguments allocates (see
    // recon_engine::bytes_needed).
    static double bytes_needed(std::size_t fibers, const recon_params &params,
                               const robust_params &robust, std::size_t knot_capacity,
                               bool owns_rows, bool batch);

    std::size_t fibers() const { return K_; }
    std::size_t free_rows() const;
    std::size_t ready_rows() const { return last().ready_rows(); }
    bool has_last_s() const { return first().has_last_s(); }
    double last_s() const { return first().last_s(); }
    bool rows_since_sheet() const { return first().rows_since_sheet(); }
    bool pushed_since_reset() const { return first().pushed_since_reset(); }
    bool has_boundary() const { return last().has_boundary(); }
    // Streaming: about how many knot intervals of strip a row waits in
    // this chain before it is finished (every stage's lag and emission
    // group, plus the knots a row spans).
    long latency_knots() const;

    void push_row(double s, const double *height, const double *slope, const std::uint8_t *valid);
    std::size_t pull(std::size_t max_rows, double *s_out, double *z_out, std::uint8_t *flags_out) {
        return last().pull(max_rows, s_out, z_out, flags_out);
    }
    void end_sheet();
    void reset();
    void boundary(double *s_out, double *height_out, double *slope_out) const {
        last().boundary(s_out, height_out, slope_out);
    }
    // Batch: every row of the sheet (s strictly increasing), then end of
    // sheet; the rows are in z_store / flags_store, or can be pulled.
    void batch(std::size_t rows, const double *s, row_source &source);

  private:
    recon_engine &first() const { return *stages_.front(); }
    recon_engine &last() const { return *stages_.back(); }
    // Raw rows waiting for stage i (1..iterations) to be able to take them.
    struct pending {
        // ring [capacity][K], NaN = invalid; not zero-filled: a slot is
        // written before it is read, and untouched pages cost nothing.
        std::unique_ptr<double[]> s, height, slope;
        std::size_t head = 0, tail = 0;
    };
    void enqueue(std::size_t stage, double s, const double *height, const double *slope,
                 const std::uint8_t *valid);
    void advance(std::size_t stage);  // feed stage every row it can take
    // Weighs one raw row for a reweighted stage from its residuals against
    // the previous stage's prediction (pred_h_, pred_g_): adds them to the
    // running scales `scale` (new fiber weights for `next` when a block
    // completes), and leaves what the stage takes instead of the row in
    // out_h_, out_g_ (pseudo-observations or raw values) and mult_h_,
    // mult_g_ (weight multipliers); see robust.cpp.
    // line: as row_source gives it, or nullptr for none.
    void reweigh(std::size_t scale, recon_engine &next, const double *h, const double *g,
                 const std::uint8_t *valid, const double *line);

    std::size_t K_;
    robust_params robust_;
    double D_;
    bool batch_ = false;
    std::vector<double> saved_;  // batch: the previous pass's knots
    std::vector<double> initial_wh_, initial_wg_;
    const double no_line_[5] = {0, 0, 0, 0, 0};
    std::vector<std::unique_ptr<recon_engine>> stages_;
    std::vector<pending> queues_;                                   // [stage], 0 unused
    std::vector<std::unique_ptr<robust_scale>> h_scale_, g_scale_;  // [stage]
    std::size_t queue_capacity_ = 0;
    // Scratch, one row each.
    std::vector<double> pred_h_, pred_g_, out_h_, out_g_, mult_h_, mult_g_;
};

}  // namespace flt
