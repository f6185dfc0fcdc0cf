// SPDX-License-Identifier: Apache-2.0
// Internal: robust reconstruction, an M-estimator (Huber or Tukey).
//
// A plain fit first (the options' noise levels); then each sample is judged
// by its residual against the current estimate (what the two lasers would
// have measured on it), which gives
//   - per fiber and measurement kind, a running robust scale (a clipped mean
//     of |residual| per block of rows, the median of the last blocks': no
//     noise level needs to be given), which sets the fiber's weight
//     1/scale^2, and
//   - per sample, how it enters the next solve: Huber's moderate residuals
//     as pseudo-observations (prediction + clipped residual, no change to
//     the matrix), gross ones and all of Tukey's with a weight multiplier on
//     the raw value (robust.cpp says why).
// Batch (flt_reconstruct, recon_chain::batch), the judging runs as passes
// over the whole sheet in one engine, each against the previous pass's
// solution. Streaming, it runs in one sliding window (robust_window,
// window.hpp): every row is judged a few times as the strip moves on, and
// a row is finished one lag after it, whatever the number of passes.
// Deterministic: no randomness, a fixed schedule.
#pragma once

#include <memory>
#include <vector>

#include "reconstruction/engine.hpp"

namespace flt {

enum class robust_kind { none = 0, huber = 1, tukey = 2 };

struct robust_params {
    robust_kind kind = robust_kind::none;
    int iterations = 2;            // times each sample is judged (reweighted)
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
    // The fibers' weights from the scales: 1/sigma^2 of the heights (wh)
    // and of Delta-d * slope (wg, at most max_ratio * wh, as
    // recon_engine::set_fiber_weights caps it).
    static void weights(const robust_scale &h, const robust_scale &g, double max_ratio, double *wh,
                        double *wg);

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

// Judges one row of K fibers: each sample's residual against the
// prediction (pred_h: height, mm; pred_g: Delta-d * slope, mm) decides the
// value it enters the next solve with (out_h in mm, out_g in mm/mm: a
// pseudo-observation or the raw value) and its weight multiplier (mult_h,
// mult_g in [0, 1]; 0 for an invalid sample). The residuals' clipped
// magnitudes go to the scales' current blocks when feed is set (then call
// end_row() on both), else to sink_sum / sink_count ([K], overwritten,
// never read). h, g: the row (invalid: not finite, or valid[k] == 0 when
// valid is given); line: as row_source gives it, or nullptr.
void robust_weigh_row(robust_kind kind, std::size_t K, double D, const double *h, const double *g,
                      const std::uint8_t *valid, const double *line, const double *pred_h,
                      const double *pred_g, robust_scale &hs, robust_scale &gs, bool feed,
                      double *sink_sum, double *sink_count, double *out_h, double *out_g,
                      double *mult_h, double *mult_g);

// Where batch pass `pass` (0, 1, ...) reads row r of the sheet: its heights
// and slopes, and validity (nullptr: every finite sample is valid), good
// until the next call. Each pass asks for rows 0, 1, ... in order.
// A reweighting pass (pass > 0) may instead get values that still carry a
// line across the strip, which it takes off as it reads them: line =
// {a_h, b_h, a_g, b_g, centre}, the value of fiber k being
// value - (a + b * (k - centre)); the first pass gets no line (all zero).
// (With rigid_motion the fibers' deviations are the caller's rows minus the
// row's line; recomputing them in a pass of their own costs as much again.)
// The first pass's heights may instead come raw, to be taken relative to
// a level as the engine reads them (recon_engine::push_row_relative): one
// pass over each row of the caller's sheet instead of a relative copy of it
// and the passes over that.
class row_source {
  public:
    virtual void row(int pass, std::size_t r, const double **height, const double **slope,
                     const std::uint8_t **valid, double line[5]) = 0;
    // True when pass 0's heights are raw, with the level (mm) in *level.
    virtual bool raw_first_pass(double *level) const {
        (void)level;
        return false;
    }
    // With raw_first_pass: row r of pass 0 as the caller keeps it (nullptr
    // past the last), fetched from memory while the row before it is added.
    virtual void raw_row_ahead(std::size_t r, const double **height, const double **slope) const {
        (void)r;
        *height = *slope = nullptr;
    }

  protected:
    ~row_source() = default;
};

class robust_window;

// One channel (a set of fibers): a plain engine, or in robust mode the
// one-stage robust window (streaming) or the passes of batch().
//
// Batch use (flt_reconstruct) has the whole sheet at hand: batch() runs the
// passes over the sheet one after the other, in one engine, each pass
// predicting from the previous pass's whole-sheet solution. Nothing is
// queued, and the memory is one engine's.
class recon_chain {
  public:
    // batch: made for batch() (a single engine), with the caller's
    // z_store / flags_store for every row of the sheet.
    recon_chain(std::size_t fibers, const recon_params &params, const robust_params &robust,
                std::size_t knot_capacity, double *z_store = nullptr,
                std::uint8_t *flags_store = nullptr, bool batch = false);
    ~recon_chain();
    recon_chain(const recon_chain &) = delete;
    recon_chain &operator=(const recon_chain &) = delete;

    // The bytes the constructor with these arguments allocates (see
    // recon_engine::bytes_needed).
    static double bytes_needed(std::size_t fibers, const recon_params &params,
                               const robust_params &robust, std::size_t knot_capacity,
                               bool owns_rows, bool batch);

    std::size_t fibers() const { return K_; }
    std::size_t free_rows() const;
    std::size_t ready_rows() const;
    bool has_last_s() const;
    double last_s() const;
    bool rows_since_sheet() const;
    bool pushed_since_reset() const;
    bool has_boundary() const;
    // Streaming: about how many knot intervals of strip a row waits before
    // it is finished (the lag and emission group, plus the knots a row
    // spans).
    long latency_knots() const;

    void push_row(double s, const double *height, const double *slope, const std::uint8_t *valid);
    // Streaming without robust mode (takes_raw_rows()): a row of raw
    // heights, taken relative to `level` as the engine reads them
    // (recon_engine::push_row_relative).
    bool takes_raw_rows() const { return window_ == nullptr; }
    void push_row_relative(double s, const double *height, double level, const double *slope,
                           const std::uint8_t *valid);
    // add: as recon_engine::pull.
    std::size_t pull(std::size_t max_rows, double *s_out, double *z_out, std::uint8_t *flags_out,
                     const double *add = nullptr);
    // Rows held, skipping `offset`: finished ones as pull() gives them,
    // pending ones provisional (recon_engine::peek).
    std::size_t peek(std::size_t offset, std::size_t max_rows, double *s_out, double *z_out,
                     std::uint8_t *flags_out);
    void end_sheet();
    void reset();
    void boundary(double *s_out, double *height_out, double *slope_out) const;
    // Batch: every row of the sheet (s strictly increasing), then end of
    // sheet; the rows are in z_store / flags_store, or can be pulled.
    void batch(std::size_t rows, const double *s, row_source &source);
    // Batch: this call's storage for the rows (recon_engine::rebind_rows).
    void rebind_rows(double *z_store, std::uint8_t *flags_store) {
        engine_->rebind_rows(z_store, flags_store);
    }
    // Batch: a constant added to every row's heights as they are written
    // (recon_engine::set_output_offset).
    void set_output_offset(double c) { engine_->set_output_offset(c); }

  private:
    // Weighs one raw row for a batch pass from its residuals against the
    // previous pass's prediction (pred_h_, pred_g_): adds them to the running
    // scales (new fiber weights for `next` when a block completes), and
    // leaves what the pass takes instead of the row in out_h_, out_g_ and
    // mult_h_, mult_g_ (robust_weigh_row). line: as row_source gives it.
    void reweigh(recon_engine &next, const double *h, const double *g, const std::uint8_t *valid,
                 const double *line);

    std::size_t K_;
    robust_params robust_;
    double D_;
    bool batch_ = false;
    std::unique_ptr<recon_engine> engine_;   // plain streaming, or batch
    std::unique_ptr<robust_window> window_;  // streaming in robust mode
    std::vector<double> saved_;              // batch: the previous pass's knots
    std::vector<double> initial_wh_, initial_wg_;
    std::unique_ptr<robust_scale> h_scale_, g_scale_;  // batch
    // Scratch, one row each.
    std::vector<double> pred_h_, pred_g_, out_h_, out_g_, mult_h_, mult_g_;
};

}  // namespace flt
