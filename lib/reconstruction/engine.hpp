// SPDX-License-Identifier: Apache-2.0
// Internal: the streaming Hermite reconstruction engine behind flt_recon and
// flt_reconstruct().
//
// The math (docs/reconstruction.md has it in full):
//   Per fiber, unknowns are (z_j, m_j = L*z'_j) at knots t_j = t0 + j*L, all in
//   mm so the normal matrix is well scaled. A row at s measures, per fiber,
//     height: (z(s-D/2) + z(s+D/2))/2          weight 1/height_sigma^2
//     slope*D: z(s+D/2) - z(s-D/2)             weight 1/(D*slope_sigma)^2
//   Each row touches at most S = ceil(D/L)+2 consecutive knots, so the normal
//   matrix is banded with half-bandwidth 2S-1. Priors: a curvature term per
//   knot interval and a negligible ridge on z (1e-12 of one height sample)
//   keep it positive definite where data is missing.
//
// Streaming solve (a fixed-lag smoother):
//   Rows arrive with increasing s, so once s-D/2 of a row passes knot j, no
//   later row touches j and j is eliminated (one Cholesky step on the window
//   of the S open knots; the factor is kept in a ring). The estimate of any
//   knot given all data so far is then a small window solve plus a
//   back-substitution through the ring. Knot j is emitted when knot
//   j+lag is eliminated; rows between emitted knots are evaluated from the
//   emitted knot states (Hermite interpolation), so the output is C1.
//
// Layout and speed:
//   All per-fiber arrays are structure-of-arrays, [entry][fiber], so the inner
//   loops run over contiguous fibers and vectorise. The row contributions to
//   the normal matrix are the same for every fiber that has the sample, so
//   they are accumulated once (R) and each fiber subtracts only its invalid
//   samples (down). Everything is allocated in the constructor.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace flt {

// The largest magnitude of a measured height (mm) or slope (mm/mm) that is
// a sample: beyond it (or not finite) a sample is invalid. No sensor
// measures a kilometre, and the squares of such values would overflow the
// normal equations into NaN (fuzz_recon found -2e307).
constexpr double k_max_sample = 1.0e9;
// Its bit pattern: for a double x, |x| <= k_max_sample exactly when the
// bits of |x| (sign cleared) are at most these as unsigned integers (NaN's
// are larger), a test that vectorises as integers.
constexpr std::uint64_t k_max_sample_bits = 0x41CDCD6500000000ull;

// A row of heights relative to a level (mm): height - level, NaN where the
// height is no sample or is more than k_max_sample from the level (the
// strip's level: recon_pipeline::find_level says why heights are solved
// relative to it).
void relative_row(std::size_t K, double level, const double *height, double *out);

struct recon_params {
    double knot_spacing = 100.0;   // L, mm (resolved, > 0)
    double laser_spacing = 100.0;  // D, mm
    double height_sigma = 2.5;     // mm
    double slope_sigma = 1e-3;     // mm/mm
    double curvature_weight = 1e-3;
    double curvature_jump_weight = 10.0;
    double max_gap = 200.0;  // mm
    long lag_knots = 40;     // batch: no_lag
    // The head of a strip (after create or reset): no knot is emitted before
    // the newest row is this many knot intervals into the strip. With no
    // strip behind them, the first knots' level is known from the strip
    // ahead only, and at a short lag that is too little (docs/
    // reconstruction.md); 0: none. head_lag() gives the rule.
    long start_lag_knots = 0;
    std::size_t row_capacity = 4096;

    // Knots are emitted in groups: one back-substitution through the lag
    // then serves the whole group, so its cost per knot is (lag+group)/group
    // instead of lag. Every emitted knot still has at least lag_knots
    // complete knots after it.
    long emit_group() const { return 1 + lag_knots / 8; }
    // Eliminated knots that can wait for emission at once.
    std::size_t knot_capacity() const {
        return std::size_t(std::max(lag_knots, start_lag_knots) + emit_group()) + 2;
    }
    // The head rule: the first knots of a strip wait for twice the strip a
    // row waits for at most afterwards.
    static long head_lag(long lag_knots) { return 2 * (lag_knots + 1 + lag_knots / 8 + 1); }
    // The most strip (mm) beyond a row when it is finished, past the head,
    // and in the head, each plus one row spacing (recon.h, "Latency").
    double latency_bound_mm() const {
        return double(lag_knots + emit_group() + 1) * knot_spacing + 0.5 * laser_spacing;
    }
    double head_latency_bound_mm() const {
        return std::max(double(start_lag_knots) * knot_spacing, latency_bound_mm());
    }
    // Knot intervals of strip beyond a row before it is finished, at most
    // (the head's when it is longer): what a caller must hold rows for.
    long latency_knots() const { return std::max(lag_knots + emit_group(), start_lag_knots) + 2; }

    static constexpr long no_lag = std::numeric_limits<long>::max();
};

// What an engine does with the rows it is given (see recon_engine).
enum class engine_role {
    // Solves: rows enter the normal equations, knots are eliminated and
    // emitted with the lag (the plain streaming reconstructor, batch).
    solve,
    // Keeps the rows only (the row ring, flags, gaps, the strip's level
    // bookkeeping) and evaluates them from knot states that another solver
    // computes and hands over (set_knot_state, mark_emitted): the output
    // side of robust_window. No normal equations are allocated.
    rows_only,
};

// One prior term (engine.cpp, add_priors_for_knot): weight * x^T M x over
// `count` unknowns, unknown i being unit[i] (0: z, 1: m) of knot[i].
// slope_weighted: it scales with the fiber's slope weight (the floors of
// the ridge and the curvature that follow robust mode's weights), else with
// its height weight.
struct prior_term {
    int count = 0;
    long knot[5] = {0, 0, 0, 0, 0};
    int unit[5] = {0, 0, 0, 0, 0};
    double m[5][5] = {};
    bool slope_weighted = false;
};

class recon_engine {
  public:
    // knot_capacity: the most knots that can be eliminated but not yet emitted;
    // for streaming lag_knots + 2, for batch the sheet's knot count.
    // z_store/flags_store: caller storage for the row ring (batch writes
    // straight into the caller's output), or nullptr to own it.
    // keep_rows = false: an intermediate stage of a robust chain, whose
    // rows are never pulled; it keeps no row ring at all.
    // role: engine_role::rows_only for the output side of robust_window.
    recon_engine(std::size_t fibers, const recon_params &params, std::size_t knot_capacity,
                 double *z_store = nullptr, std::uint8_t *flags_store = nullptr,
                 bool keep_rows = true, engine_role role = engine_role::solve);

    // The bytes a constructor with these arguments allocates (its large
    // buffers; an upper bound within a few hundred bytes), computed in
    // double so that no size can overflow: the API refuses configurations
    // beyond FLT_RECON_MAX_BYTES before constructing anything.
    // owns_rows: no z_store given (the engine keeps its own row ring).
    static double bytes_needed(std::size_t fibers, const recon_params &params,
                               std::size_t knot_capacity, bool owns_rows, bool keep_rows,
                               engine_role role = engine_role::solve);

    std::size_t fibers() const { return K_; }
    const recon_params &params() const { return p_; }
    int knots_per_row() const { return S_; }

    // Rows that still fit in the ring.
    std::size_t free_rows() const { return p_.row_capacity - (tail_ - head_); }
    std::size_t ready_rows() const { return ready_ - head_; }
    bool has_last_s() const { return have_t0_; }
    double last_s() const { return last_s_; }
    bool rows_since_sheet() const { return rows_in_sheet_ > 0; }
    bool pushed_since_reset() const { return have_t0_; }
    bool has_boundary() const { return fixed_upto_ >= 0 && anchored_; }

    // One row; arguments already validated (s increasing, sizes right).
    // mult_h, mult_g: per-fiber multipliers of this row's height and slope
    // weights in [0, 1] (robust down-weighting), or nullptr for 1.
    void push_row(double s, const double *height, const double *slope, const std::uint8_t *valid,
                  const double *mult_h = nullptr, const double *mult_g = nullptr);
    // As push_row without multipliers, for heights given raw: each height
    // is taken relative to `level` (mm) as relative_row does, as the row is
    // read (the pipeline's rows: one pass over the caller's row instead of
    // a relative copy and the passes over that).
    // next_height, next_slope: the row pushed next, if known, to be fetched
    // from memory while this one is added (batch).
    void push_row_relative(double s, const double *height, double level, const double *slope,
                           const std::uint8_t *valid, const double *next_height = nullptr,
                           const double *next_slope = nullptr);
    // Per-fiber weights 1/sigma^2 of heights (mm^-2) and of Delta-d * slope;
    // they take effect at the next knot elimination.
    void set_fiber_weights(const double *wh, const double *wg);
    double default_height_weight() const { return w_h_; }
    double default_slope_weight() const { return w_g_; }
    // Copies up to max_rows ready rows out; returns how many. add: a
    // constant (mm) added to every height as it is copied (the bits of
    // copying, then adding it), or nullptr for none.
    std::size_t pull(std::size_t max_rows, double *s_out, double *z_out, std::uint8_t *flags_out,
                     const double *add = nullptr);
    void end_sheet();
    void reset();
    // The carried boundary knot.
    void boundary(double *s_out, double *height_out, double *slope_out) const;
    // What the two lasers would measure at row position s on the current
    // estimate: height (mm) and Delta-d * slope (mm), per fiber. Possible
    // once every knot under s +- Delta-d/2 is emitted, or, right after
    // end_sheet(), solved; returns false otherwise.
    bool predict(double s, double *height_out, double *dslope_out) const;
    // True when predict(s) can never succeed any more: the knots under s
    // have left the ring of knot states (the strip moved on by more than
    // the ring holds before s could be predicted: rows much sparser than
    // the knots, or a jump in s).
    bool prediction_lost(double s) const;

    // Batch robust passes (recon_chain::batch) run one after the other in
    // one engine, each predicting from the previous pass's solution:
    // the solved knot states, saved right after end_sheet() (solution_size()
    // doubles), then predict_saved() at any row of that sheet. Keeping rows
    // (evaluating them into the row ring) is only needed in the last pass;
    // set_keep_rows() may be called right after reset().
    std::size_t solution_size() const { return hist_.size(); }
    void save_solution(double *out, double *t0_out) const;
    void predict_saved(const double *saved, double saved_t0, double s, double *height_out,
                       double *dslope_out) const;
    void set_keep_rows(bool keep);
    // Batch workspaces (recon_api.cpp) serve one call after another: the
    // caller's storage of this call for the rows (as the constructor's
    // z_store / flags_store; nullptr flags_store: the engine's own, which
    // it must have been constructed with). Resets the engine.
    void rebind_rows(double *z_store, std::uint8_t *flags_store);
    // A constant (mm) added to the heights of every row finished from now
    // on (0 by default): batch adds the sheet's level while it writes the
    // rows, instead of in a pass of its own over the whole output.
    void set_output_offset(double c) { output_offset_ = c; }

    // ---- provisional values (flt_recon_peek) ----
    // Rows held from the oldest not pulled, skipping `offset` of them: up to
    // max_rows of them into s_out, z_out, flags_out (may be nullptr); a
    // finished row as it will be pulled, a pending one evaluated from the
    // current knot states (provisional: it changes until the row is
    // finished). A solve-role engine first solves for every knot given
    // every row so far (solve_all); a rows_only one evaluates from the
    // states its solver last set. Returns the rows written.
    std::size_t peek(std::size_t offset, std::size_t max_rows, double *s_out, double *z_out,
                     std::uint8_t *flags_out);
    // Rows held (finished and pending), and pending.
    std::size_t held_rows() const { return tail_ - head_; }

    // ---- rows_only role (robust_window's output) ----
    // The state of knot j (z, m per fiber; fibers [k0, k1) of it), final
    // once mark_emitted covers it; states of later knots may be set for
    // peek(). Also for carry_over() in either role.
    void set_knot_state(long j, const double *z, const double *m) {
        set_knot_state(j, z, m, 0, K_);
    }
    void set_knot_state(long j, const double *z, const double *m, std::size_t k0, std::size_t k1);
    // Knots up to `last` have their final states: the rows between them are
    // finished.
    void mark_emitted(long last);
    // The first knot not emitted yet.
    long next_emit() const { return next_emit_; }

    // ---- solve role, as robust_window's frozen part ----
    // The strip starts with a row at s (the knot grid: s - Delta-d/2),
    // as the first push_row would.
    void start_strip(double s);
    // A block of rows that all start in knot interval i1 (their rear laser
    // reading there), given by its sums over the rows, each unweighted (the
    // engine weighs them with its current fiber weights): gh, gg (n x n,
    // shared) the outer products of the rows' height and Delta-d * slope
    // coefficients over the knots i1 .. i1 + S - 1; rh, rg ([n][K]) the
    // coefficients times each sample's value and weight multiplier; dh, dg
    // ([packed n x n][K], or nullptr for none) what each fiber's samples
    // take back out of gh, gg (the multipliers' complements). The knots
    // before i1 are eliminated first (as push_row does).
    void add_block(long i1, const double *gh, const double *gg, const double *rh, const double *rg,
                   const double *dh, const double *dg);
    // The open window: the first open knot, and every fiber's assembled
    // window matrix (packed upper, window_entry(r, c) per fiber) and
    // right-hand side ([n][K]), good until the next call that changes the
    // engine.
    long first_open_knot() const { return w0_; }
    const double *open_window_matrix();
    const double *open_window_rhs() const { return rhs_.data(); }
    std::size_t window_entry(int r, int c) const { return tri(r, c); }
    // Knots up to fixed_upto() (and from 0) are hard boundary conditions
    // carried from the previous sheet; knot_state(j) is their state.
    long fixed_upto() const { return fixed_upto_; }
    const double *knot_state(long j) const { return hist_at(j); }
    // Eliminated knots up to `last` will never be solved for: their factors
    // may be dropped (robust_window keeps the states it emits itself).
    void forget_upto(long last);
    // Both roles: ends the sheet with knots up to e_end final, with the
    // states last set (set_knot_state; at least those of knots e_end - S +
    // 1 .. e_end, which the next sheet's rows and priors touch): the
    // carry-over of end_sheet() without a solve of this engine's own.
    void carry_over(long e_end);
    // The prior terms that complete with knot j (engine.cpp): fills out
    // (at most 5) and returns how many.
    int knot_priors(long j, prior_term *out) const;
    // Interval and Hermite basis of a position on this strip's grid.
    long interval_at(double p) const { return interval_of(p); }
    void basis_at(double p, long i, double w[4]) const { basis(p, i, w); }
    // The row's coefficients over the knots i1 .. i1 + S - 1 (as push_row).
    void coefficients(double s, long i1, double *ch, double *cg) const {
        row_coefficients(s, i1, ch, cg);
    }
    double laser_spacing() const { return D_; }
    double knot_spacing() const { return L_; }
    bool strip_started() const { return have_t0_; }
    double strip_origin() const { return t0_; }
    // The caps on the weights (engine.cpp): a slope sample weighs at most
    // this many height samples of its fiber.
    static double max_weight_ratio();
    // The pivot floor of the factorisations, relative to the largest
    // diagonal entry of a fiber's matrix.
    static double pivot_floor();

  private:
    void solve_all();  // every knot from next_emit_ on, given every row
    void end_sheet_common(long e_end);
    // ---- geometry ----
    long interval_of(double p) const { return interval_on(t0_, p); }  // knot interval of p
    double knot_pos(long j) const { return t0_ + double(j) * L_; }
    // The same on the grid of a strip starting at t0 (a saved solution's).
    long interval_on(double t0, double p) const { return long(std::floor((p - t0) / L_)); }
    void basis_on(double t0, double p, long i, double w[4]) const;
    // Hermite basis at p on interval i: weights of (z_i, m_i, z_i+1, m_i+1).
    void basis(double p, long i, double w[4]) const;

    // ---- rows ----
    void begin_strip(double s);  // the first row of a strip is at s
    // push_row and push_row_relative: level nullptr for heights that are
    // samples already; next_height, next_slope as push_row_relative's.
    void add_row(double s, const double *height, const double *level, const double *slope,
                 const std::uint8_t *valid, const double *mult_h, const double *mult_g,
                 const double *next_height, const double *next_slope);
    // The row's coefficients over the window's unknowns (its knots i1 ..
    // i1+S-1): height ch and Delta-d * slope cg.
    void row_coefficients(double s, long i1, double *ch, double *cg) const;
    // Everything after the row's samples are in the window: the row ring,
    // flags, gaps and emission. hok(k) / gok(k): fiber k's height / slope
    // sample is valid (asked only when nbad > 0).
    template <class HeightOk, class SlopeOk>
    void finish_row(double s, std::size_t nbad, HeightOk h_ok, SlopeOk g_ok);

    // ---- window management ----
    void start_window(long first_knot);  // empty window at first_knot
    void add_priors_for_knot(long j);    // priors that complete with knot j
    void clear_shared();
    void apply_pending_weights();
    void assemble_entry(int r, int c);  // work = W(r, c) for every fiber
    void add_row_geometry(const double *ch, const double *cg, int off);
    void add_rank1_prior(const long *knot, const int *unit, const double *coef, int count,
                         double weight);
    // pivot_floor_[k] = k_pivot_floor times the largest diagonal entry of
    // fiber k's assembled window matrix (work_).
    void pivot_floors();
    void close_knot();  // eliminate knot w0_
    void maybe_emit();  // emit knots whose lag is reached
    long emit_group() const { return p_.emit_group(); }
    void emit_upto(long last);  // solve and emit knots <= last
    void finish_rows();         // evaluate rows now determined
    // Finished rows [evaluated_, ready_) are not evaluated into the ring
    // yet: pull() evaluates them from the knot states straight into the
    // caller's rows (the ring's row is memory untouched for row_capacity
    // rows; writing it, then copying it out, cost more than the
    // evaluation). Only rows finished without a flag or NaN to set, with
    // the engine's own row ring and no output offset; they are evaluated
    // into the ring (materialise_rows) before a knot state they need can
    // be overwritten (its ring slot reused by knot j_max: keep_lazy_rows)
    // or the grid moves (a new strip).
    void materialise_rows();
    void keep_lazy_rows(long j_max) {
        if (evaluated_ < ready_ &&
            j_max >= interval_of(ring_s_[evaluated_ % p_.row_capacity]) + long(hist_cap_))
            materialise_rows();
    }
    // Row at (ring index r, position s) from the knot states into z (+ c).
    void evaluate_into(double s, double *z, const double *c) const;
    void mark_gap(std::size_t k, double from);
    double *hist_at(long j);  // state (z, m) of knot j, [2][K]
    const double *hist_at(long j) const;

    // Per-fiber symmetric window matrix W = schur + R - down, packed upper.
    std::size_t tri(int r, int c) const {
        return std::size_t(r) * n_ - std::size_t(r) * (r - 1) / 2 + std::size_t(c - r);
    }

    // ---- sizes ----
    std::size_t K_;
    recon_params p_;
    double L_, D_;
    int S_;     // knots touched by one row
    int n_;     // unknowns in the window, 2*S_
    int ntri_;  // packed entries of the window matrix
    int nf_;    // doubles per fiber and eliminated knot in the factor ring
    double w_h_, w_g_, w_curv_, w_ridge_, w_curv_jump_;

    // ---- knot state ----
    bool have_t0_ = false;
    double t0_ = 0.0;
    long w0_ = 0;         // first open knot (window start)
    long next_emit_ = 0;  // first knot not emitted yet
    long last_emitted_ = -1;
    long fixed_upto_ = -1;     // knots <= this are hard boundary conditions
    bool anchored_ = false;    // a boundary condition has been carried
    bool strip_head_ = false;  // no knot emitted since the strip began

    // Shared, unweighted contributions since the last elimination, n x n
    // dense: the rows' height and slope outer products, and the priors (in
    // units of one height sample). Each fiber weighs them with its own
    // wh_, wg_ when its window matrix is assembled.
    std::vector<double> Rh_, Rg_, Rp_;
    std::vector<double> wh_, wg_, next_wh_, next_wg_;
    bool weights_pending_ = false;
    std::vector<double> schur_;     // [ntri][K]
    std::vector<double> down_;      // [ntri][K]
    std::vector<double> rhs_;       // [n][K]
    bool bad_fibers_seen_ = false;  // down_ is non-zero

    std::size_t factor_cap_;
    std::vector<double> factor_;  // ring [factor_cap][nf][K]
    std::size_t hist_cap_;
    std::vector<double> hist_;  // ring of knot states [hist_cap][2][K]

    // ---- scratch (allocated once) ----
    std::vector<double> work_;     // [ntri][K]
    std::vector<double> xwin_;     // [n][K]
    std::vector<double> hv_, gv_;  // per fiber masked measurements
    std::vector<double> hm_, gm_;  // per fiber effective weight multipliers
    std::vector<double> rel_h_;    // a row of relative heights (add_row)
    std::vector<double> ones_;
    std::vector<double> pivot_floor_;  // per fiber, see pivot_floors()
    std::vector<int> bad_;             // fibers with an invalid sample this row

    // ---- per fiber bookkeeping ----
    double bc_s_ = 0.0;  // carried boundary knot
    std::vector<double> bc_z_, bc_m_;
    std::vector<double> last_valid_s_;  // see all_valid_s_
    double all_valid_s_ = 0.0;          // last row with every fiber valid
    bool prev_row_all_valid_ = false;
    std::vector<std::uint8_t> has_height_;  // a valid height since reset
    std::size_t no_height_fibers_ = 0;

    // ---- row ring ----
    std::vector<double> ring_s_;
    std::vector<std::uint8_t> ring_any_invalid_;
    // Rows whose flags are all 0 and were not written to the ring (a row
    // with every sample valid, the common one): pull and peek give zeros
    // for them, and the ring's bytes are written only if a flag is set
    // later. Only with the engine's own flag ring (lazy_flags_): a
    // caller's storage (batch) is written as rows finish.
    std::vector<std::uint8_t> ring_zero_flags_;
    bool lazy_flags_ = false;
    std::vector<double> own_z_;
    std::vector<std::uint8_t> own_flags_;
    double *ring_z_;
    std::uint8_t *ring_flags_;
    std::size_t head_ = 0, ready_ = 0, tail_ = 0;  // monotonic counters
    std::size_t evaluated_ = 0;                    // see materialise_rows
    bool lazy_rows_ = false;                       // own row ring (z)
    bool keep_rows_ = true;
    double output_offset_ = 0.0;  // set_output_offset
    bool has_row_ring_ = true;    // constructed with keep_rows
    engine_role role_ = engine_role::solve;
    long solved_upto_ = -1;      // knots in hist_ solved at the last solve
    bool solved_fresh_ = false;  // no row pushed since that solve
    double last_s_ = 0.0;
    std::size_t rows_in_sheet_ = 0;
};

}  // namespace flt
