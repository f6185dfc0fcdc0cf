// SPDX-License-Identifier: Apache-2.0
// Internal: robust streaming in one sliding window (docs/reconstruction.md,
// "Robust mode, streaming").
//
// An M-estimator needs the estimate to judge the samples and the judged
// samples to estimate. Streaming, the rows of the strip that are not final
// yet are kept raw in a window, and at every emission (every emit_group
// knots of strip) the window is solved again with the judgments so far:
//
//   - rows are grouped in blocks by the knot interval of their rear laser
//     reading (block b: the rows that touch knots b .. b + S - 1); a block's
//     sums (its rows' outer products, right-hand sides and the downdates of
//     its down-weighted samples) are what the solve needs of it;
//   - a block enters plain (every valid sample at full weight) and is
//     judged `iterations` times as the strip moves on: at distances
//     (lag + 1) * i / iterations knots behind the newest row, i = 1 ..
//     iterations, each time against the solution of the whole window at
//     that moment (which has the rows ahead of it, already judged fewer
//     times); its last judgment comes in the emission that makes its first
//     knot final, and feeds the running scales;
//   - a block whose first knot is final leaves the window: its sums go into
//     `frozen_`, a plain engine that eliminates knot by knot (the Schur
//     complement of everything before the window, a prior on its first S
//     knots), and its raw rows are released;
//   - the solve: the frozen engine's open window, every block's sums and the
//     priors of the knots beyond, one banded Cholesky per fiber over the
//     window's knots, in chunks of fibers that stay in cache.
//
// So every reweighting happens within one lag: a row is final lag + group +
// S knots after it whatever the number of passes (the pipelined stages this
// replaces added about 13 knots per pass). As the lag grows the result
// converges to the whole-sheet passes of flt_reconstruct (bench_latency
// measures how close it is at each lag). The output side (row ring, flags,
// gaps, knot states, carry-over) is a recon_engine in the rows_only role.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "reconstruction/engine.hpp"
#include "reconstruction/robust.hpp"

namespace flt {

class robust_window {
  public:
    // params.lag_knots must be a finite lag; robust.kind not none.
    robust_window(std::size_t fibers, const recon_params &params, const robust_params &robust,
                  double *z_store = nullptr, std::uint8_t *flags_store = nullptr);

    // The bytes the constructor allocates (as recon_engine::bytes_needed).
    static double bytes_needed(std::size_t fibers, const recon_params &params,
                               const robust_params &robust);

    std::size_t fibers() const { return K_; }
    std::size_t free_rows() const;
    std::size_t ready_rows() const { return out_.ready_rows(); }
    bool has_last_s() const { return out_.has_last_s(); }
    double last_s() const { return out_.last_s(); }
    bool rows_since_sheet() const { return out_.rows_since_sheet(); }
    bool pushed_since_reset() const { return out_.pushed_since_reset(); }
    bool has_boundary() const { return out_.has_boundary(); }
    long latency_knots() const { return p_.latency_knots() + S_ - 2; }

    void push_row(double s, const double *height, const double *slope, const std::uint8_t *valid);
    std::size_t pull(std::size_t max_rows, double *s_out, double *z_out, std::uint8_t *flags_out,
                     const double *add = nullptr) {
        return out_.pull(max_rows, s_out, z_out, flags_out, add);
    }
    // Rows held, skipping `offset`: finished ones as pull() gives them,
    // pending ones from a solve of the window now (provisional). Changes no
    // result that is or will be pulled.
    std::size_t peek(std::size_t offset, std::size_t max_rows, double *s_out, double *z_out,
                     std::uint8_t *flags_out);
    void end_sheet();
    void reset();
    void boundary(double *s_out, double *height_out, double *slope_out) const {
        out_.boundary(s_out, height_out, slope_out);
    }

  private:
    struct block {
        std::size_t first_row = 0, rows = 0;  // in the row store (monotonic)
        int judged = 0;                       // judgments so far
        bool has_down = false;                // dh / dg are not all zero
        // The fibers whose dh / dg entries are non-zero, when they are few
        // (down_fibers(b), down_count of them); dense_down: too many to
        // list, every fiber counts. A solve subtracts the downdates of the
        // listed fibers only: the others' entries are exactly 0, so the
        // result is the same to the bit, and a Huber block's downdates
        // (its gross samples) are typically a few fibers of a thousand.
        std::size_t down_count = 0;
        bool dense_down = false;
    };

    std::size_t slot(long j) const { return std::size_t(j) % ring_; }
    block &block_at(long b) { return blocks_[slot(b)]; }
    double *gh(long b) { return gh_.data() + slot(b) * std::size_t(n_) * n_; }
    double *gg(long b) { return gg_.data() + slot(b) * std::size_t(n_) * n_; }
    double *rh(long b) { return rh_.data() + slot(b) * std::size_t(n_) * K_; }
    double *rg(long b) { return rg_.data() + slot(b) * std::size_t(n_) * K_; }
    double *dh(long b) { return dh_.data() + slot(b) * std::size_t(ntri_) * K_; }
    double *dg(long b) { return dg_.data() + slot(b) * std::size_t(ntri_) * K_; }
    std::uint32_t *down_fibers(long b) { return down_fibers_.data() + slot(b) * down_cap_; }
    std::uint8_t *down_marks(long b) { return down_marks_.data() + slot(b) * K_; }
    // Fiber k of block b has a non-zero downdate (block::down_count).
    void mark_down(block &bl, long b, std::size_t k) {
        if (bl.dense_down)
            return;
        std::uint8_t &m = down_marks(b)[k];
        if (m)
            return;
        m = 1;
        if (bl.down_count == down_cap_)
            bl.dense_down = true;
        else
            down_fibers(b)[bl.down_count++] = std::uint32_t(k);
    }
    void clear_down(block &bl, long b);  // no downdates in block b
    // The window solution's state of knot j (z then m, [2][K]); a carried
    // knot's before the window.
    const double *state(long j) const;

    void start(double s);
    void open_block(long b);        // an empty block b
    void advance_to(long i1);       // knots before i1 are complete
    void emit(long last);           // judge, solve, emit up to last, freeze
    void round();                   // judge the blocks due, emitting nothing
    void emit_states(long last);    // knots up to last are final
    bool due(long b) const;         // block b is due for a judgment
    void judge(long b, bool feed);  // recompute block b's sums from its rows
    // first: the block's first row, which in the default geometry sets
    // the right-hand sides instead of adding to them (they are not cleared
    // for it: open_block, judge).
    void add_row(long b, std::size_t r, const double *ch, const double *cg, const double *yh,
                 const double *yg, const double *mh, const double *mg, bool first);
    void clear_rhs(long b);       // the block's right-hand sides to 0
    void freeze_upto(long last);  // blocks up to last leave the window
    // The window, every fiber; provisional: into peek_x_ (peek), leaving
    // the solution (x_, solved_*) as it was.
    void solve(bool provisional = false);
    void solve_chunk(long w0, int knots, std::size_t k0, std::size_t k1, const double *W,
                     const double *R0, double *out);
    void update_weights();  // from the scales

    std::size_t K_;
    recon_params p_;
    robust_params robust_;
    long L_, G_;        // lag and emission group, knots
    int S_, n_, ntri_;  // knots per row, unknowns per block, packed entries
    int bw_;            // half-bandwidth of the window matrix, unknowns
    double D_;
    int iterations_;
    std::vector<long> due_distance_;  // [judgment]: knots behind the newest row
    recon_engine out_;                // rows, flags, emitted states (rows_only)
    recon_engine frozen_;             // blocks that left the window (solve)
    robust_scale hs_, gs_;
    std::vector<double> wh_, wg_;  // the fibers' current weights

    bool started_ = false;
    bool head_ = false;     // no knot emitted since the strip began
    long c1_ = 0;           // the newest row's block: knots before it are complete
    long last_round_ = 0;   // c1_ at the last judging round
    long next_emit_ = 0;    // first knot not final
    long first_block_ = 0;  // oldest block in the window
    std::size_t ring_;      // blocks and knot states held
    std::vector<block> blocks_;
    std::vector<double> gh_, gg_, rh_, rg_, dh_, dg_;
    // Per block: the listed fibers with downdates ([ring][down_cap]) and a
    // mark per fiber ([ring][K]) so that each is listed once.
    std::size_t down_cap_;
    std::vector<std::uint32_t> down_fibers_;
    std::vector<std::uint8_t> down_marks_;
    // The raw rows of the window's blocks: [row_cap][K] each, invalid NaN.
    // In float: they are only read again to be judged (their residual
    // against the window's solution), and heights relative to the strip's
    // level (recon_pipeline) and slopes keep 24 bits: 1e-6 mm on a 12 mm
    // wave, a thousandth of the spline's own error. Every row's plain sums,
    // which carry it until it is judged, come from its double values.
    // Half the memory of doubles, and as many slots as row_capacity (the
    // rows of the window are all pending in the output's ring).
    std::size_t row_cap_;
    std::size_t row_head_ = 0, row_tail_ = 0;
    std::vector<double> row_s_;
    std::vector<float> row_h_, row_g_;
    std::vector<double> x_;  // knot states of the last solve, [ring][2][K]
    long solved_w0_ = 0, solved_last_ = -1;
    std::vector<double> peek_x_;  // peek's provisional solve, [knot - w0][2][K]

    // Scratch of the solve: shared bands [2 knots][bw + 1], a chunk's band
    // [2 knots][bw + 1][chunk] and right-hand side [2 knots][chunk].
    int max_knots_;
    std::size_t chunk_;
    std::vector<double> bh_, bg_, band_, brhs_, floor_;
    // Scratch, one row each.
    std::vector<double> pred_h_, pred_g_, out_h_, out_g_, mult_h_, mult_g_, sink_sum_, sink_count_,
        down_h_, down_g_, row_dh_, row_dg_;
};

}  // namespace flt
