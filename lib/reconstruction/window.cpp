// SPDX-License-Identifier: Apache-2.0
#include "reconstruction/window.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/cpu_dispatch.hpp"
#include "core/error.hpp"

namespace flt {
namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();
// Fibers solved together: their window band (about 44 unknowns x 6
// entries for the default lag) stays in the core's cache.
constexpr std::size_t k_chunk_fibers = 64;
// The widest band of the window matrix, unknowns (2 S - 1 for the most
// knots a row may span, engine.cpp's k_max_unknowns).
constexpr int k_max_band = 2 * 66;

// The per-row kernels, built for baseline x86-64 and for AVX2; each call
// takes the AVX2 build where the CPU has it (core/cpu_dispatch.hpp).
#define FLT_KERNELS_FILE "reconstruction/window_kernels.inc"
#include "core/cpu_dispatch_build.inc"
FLT_DISPATCH(store_row)
FLT_DISPATCH(widen_row)
FLT_DISPATCH(weigh_values)
FLT_DISPATCH(sample_multipliers)
FLT_DISPATCH(add_rhs)
FLT_DISPATCH(add_down)
FLT_DISPATCH(add_prediction)
FLT_DISPATCH(predict6)
FLT_DISPATCH(accumulate6)
FLT_DISPATCH(accumulate6_first)
FLT_DISPATCH(band_solve)
FLT_DISPATCH(weigh_band)
FLT_DISPATCH(add_weighted)

// Packed index of (u, v) in an n x n upper triangle (recon_engine::tri).
inline std::size_t packed(int n, int u, int v) {
    if (u > v)
        std::swap(u, v);
    return std::size_t(u) * n - std::size_t(u) * (u - 1) / 2 + std::size_t(v - u);
}

recon_params frozen_params(const recon_params &p) {
    recon_params f = p;
    f.lag_knots = recon_params::no_lag;  // never emits: its states are not used
    return f;
}

}  // namespace

double robust_window::bytes_needed(std::size_t fibers, const recon_params &params,
                                   const robust_params &robust) {
    // The same sizes as the constructor below.
    const double K = double(fibers);
    const double S = std::ceil(params.laser_spacing / params.knot_spacing - 1e-9) + 2;
    const double n = 2 * S, ntri = n * (n + 1) / 2;
    const double span =
        double(std::max(params.lag_knots + params.emit_group(), params.start_lag_knots));
    const double ring = span + 2 * S + 8, knots = span + S + 4;
    const double chunk = std::min(K, double(k_chunk_fibers));
    double bytes = recon_engine::bytes_needed(fibers, params, params.knot_capacity(), true, true,
                                              engine_role::rows_only);
    bytes +=
        recon_engine::bytes_needed(fibers, frozen_params(params), std::size_t(S) + 4, true, false);
    bytes += 8 * K * (2 * double(robust.scale_blocks) + 16) * 2;   // scales
    bytes += 8 * ring * (2 * n * n + (2 * n + 2 * ntri + 2) * K);  // blocks, knot states
    bytes += ring * (K + 4 * (K / 8 + 1));                         // downdate lists
    bytes += 8 * knots * 2 * K;                                    // peek's solution
    bytes += double(params.row_capacity) * (8 + 2 * 4 * K);        // raw rows, in float
    bytes += 8 * (2 * knots) * n * (2 + chunk) + 8 * (2 * knots) * chunk;
    bytes += 8 * 16 * K;  // scratch
    return bytes;
}

robust_window::robust_window(std::size_t fibers, const recon_params &params,
                             const robust_params &robust, double *z_store,
                             std::uint8_t *flags_store)
    : K_(fibers), p_(params), robust_(robust), L_(params.lag_knots), G_(params.emit_group()),
      out_(fibers, params, params.knot_capacity(), z_store, flags_store, true,
           engine_role::rows_only),
      frozen_(fibers, frozen_params(params),
              std::size_t(std::ceil(params.laser_spacing / params.knot_spacing - 1e-9)) + 6,
              nullptr, nullptr, false, engine_role::solve),
      hs_(fibers, robust.block_rows, robust.scale_blocks, params.height_sigma),
      gs_(fibers, robust.block_rows, robust.scale_blocks,
          params.laser_spacing * params.slope_sigma) {
    if (L_ < 0 || L_ == recon_params::no_lag || robust.kind == robust_kind::none ||
        robust.iterations < 1)
        throw error(FLT_ERR_INTERNAL, "robust_window needs a finite lag and robust mode");
    S_ = out_.knots_per_row();
    n_ = 2 * S_;
    ntri_ = n_ * (n_ + 1) / 2;
    bw_ = n_ - 1;
    D_ = params.laser_spacing;
    iterations_ = robust.iterations;
    // Judgment i (1-based) when the block is (lag + 1) * i / iterations
    // knots behind the newest row: the last one in the emission that makes
    // the block's first knot final.
    for (int i = 1; i <= iterations_; ++i)
        due_distance_.push_back((long(i) * (L_ + 1) + iterations_ - 1) / iterations_);
    // The window holds at most the lag and a group of knots (or the head's
    // wait) and a row's span; the blocks reach S knots further back right
    // after a sheet's end.
    const long span = std::max(L_ + G_, params.start_lag_knots);
    ring_ = std::size_t(span) + 2 * std::size_t(S_) + 8;
    max_knots_ = int(span) + S_ + 4;
    blocks_.assign(ring_, block{});
    const std::size_t nn = std::size_t(n_) * n_;
    gh_.assign(ring_ * nn, 0.0);
    gg_.assign(ring_ * nn, 0.0);
    rh_.assign(ring_ * n_ * K_, 0.0);
    rg_.assign(ring_ * n_ * K_, 0.0);
    dh_.assign(ring_ * ntri_ * K_, 0.0);
    dg_.assign(ring_ * ntri_ * K_, 0.0);
    x_.assign(ring_ * 2 * K_, 0.0);
    // Listed up to the point where the dense subtraction costs less (as
    // add_row's own choice for a row).
    down_cap_ = K_ / 8 + 1;
    down_fibers_.assign(ring_ * down_cap_, 0);
    down_marks_.assign(ring_ * K_, 0);
    peek_x_.assign(std::size_t(max_knots_) * 2 * K_, 0.0);
    row_cap_ = params.row_capacity;
    row_s_.assign(row_cap_, 0.0);
    row_h_.assign(row_cap_ * K_, 0.0f);
    row_g_.assign(row_cap_ * K_, 0.0f);
    chunk_ = std::min(K_, k_chunk_fibers);
    const std::size_t unknowns = 2 * std::size_t(max_knots_), P = std::size_t(bw_) + 1;
    bh_.assign(unknowns * P, 0.0);
    bg_.assign(unknowns * P, 0.0);
    band_.assign(unknowns * P * chunk_, 0.0);
    brhs_.assign(unknowns * chunk_, 0.0);
    floor_.assign(chunk_, 0.0);
    for (auto *v : {&pred_h_, &pred_g_, &out_h_, &out_g_, &mult_h_, &mult_g_, &sink_sum_,
                    &sink_count_, &down_h_, &down_g_, &row_dh_, &row_dg_})
        v->assign(K_, 0.0);
    wh_.assign(K_, frozen_.default_height_weight());
    wg_.assign(K_, frozen_.default_slope_weight());
}

std::size_t robust_window::free_rows() const {
    return std::min(out_.free_rows(), row_cap_ - (row_tail_ - row_head_));
}

const double *robust_window::state(long j) const {
    if (j >= solved_w0_ && j <= solved_last_)
        return x_.data() + slot(j) * 2 * K_;
    if (j <= frozen_.fixed_upto() && j >= 0)
        return frozen_.knot_state(j);
    throw error(FLT_ERR_INTERNAL, "robust window: knot outside the solution");
}

void robust_window::start(double s) {
    started_ = true;
    head_ = true;
    frozen_.start_strip(s);
    c1_ = 0;
    last_round_ = 0;
    next_emit_ = 0;
    first_block_ = 0;
    row_head_ = row_tail_ = 0;
    solved_w0_ = 0;
    solved_last_ = -1;
    open_block(0);
}

void robust_window::open_block(long b) {
    if (std::size_t(b - first_block_) >= ring_)
        throw error(FLT_ERR_INTERNAL, "robust window: block ring overflow");
    block &bl = block_at(b);
    bl.first_row = row_tail_;
    bl.rows = 0;
    bl.judged = 0;
    bl.has_down = false;
    clear_down(bl, b);
    const std::size_t nn = std::size_t(n_) * n_;
    std::fill_n(gh(b), nn, 0.0);
    std::fill_n(gg(b), nn, 0.0);
    // In the default geometry the block's first row sets the right-hand
    // sides (accumulate6_first); a block that gets no row is cleared when
    // it is frozen.
    if (n_ != 6)
        clear_rhs(b);
}

void robust_window::clear_rhs(long b) {
    std::fill_n(rh(b), std::size_t(n_) * K_, 0.0);
    std::fill_n(rg(b), std::size_t(n_) * K_, 0.0);
}

void robust_window::clear_down(block &bl, long b) {
    std::uint8_t *marks = down_marks(b);
    if (bl.dense_down) {
        std::fill_n(marks, K_, std::uint8_t(0));
    } else {
        const std::uint32_t *list = down_fibers(b);
        for (std::size_t i = 0; i < bl.down_count; ++i)
            marks[list[i]] = 0;
    }
    bl.down_count = 0;
    bl.dense_down = false;
}

void robust_window::push_row(double s, const double *height, const double *slope,
                             const std::uint8_t *valid) {
    if (!started_)
        start(s);
    const long i1 = frozen_.interval_at(s - 0.5 * D_);
    if (i1 < c1_)
        throw error(FLT_ERR_INTERNAL, "robust window: rows out of order");
    // Knots before i1 are complete: emit what the lag allows, without this
    // row (as the plain engine does).
    advance_to(i1);
    if (row_tail_ - row_head_ >= row_cap_)
        throw error(FLT_ERR_INTERNAL, "robust window: row store overflow");
    const std::size_t r = row_tail_ % row_cap_;
    row_s_[r] = s;
    double *h = row_dh_.data(), *g = row_dg_.data();
    store_row(K_, height, slope, valid, h, g, row_h_.data() + r * K_, row_g_.data() + r * K_);
    ++row_tail_;
    block &bl = block_at(i1);
    ++bl.rows;
    // The block's sums: every valid sample at full weight until it is
    // judged.
    double ch[2 * 66], cg[2 * 66];
    frozen_.coefficients(s, i1, ch, cg);
    const std::size_t nn = std::size_t(n_);
    double *bgh = gh(i1), *bgg = gg(i1);
    for (std::size_t u = 0; u < nn; ++u)
        for (std::size_t v = 0; v < nn; ++v) {
            bgh[u * nn + v] += ch[u] * ch[v];
            bgg[u * nn + v] += cg[u] * cg[v];
        }
    sample_multipliers(K_, h, g, mult_h_.data(), mult_g_.data());
    add_row(i1, r, ch, cg, h, g, mult_h_.data(), mult_g_.data(), bl.rows == 1);
    out_.push_row(s, height, slope, valid);
}

// One row of block b into the block's right-hand sides and downdates:
// values yh (mm), yg (mm/mm) with multipliers mh, mg.
void robust_window::add_row(long b, std::size_t /*r*/, const double *ch, const double *cg,
                            const double *yh, const double *yg, const double *mh, const double *mg,
                            bool first) {
    double *hv = pred_h_.data(), *gv = pred_g_.data();  // free after the prediction
    double *dmh = down_h_.data(), *dmg = down_g_.data();
    double *bh = rh(b), *bg = rg(b);
    std::size_t affected = 0;
    if (n_ == 6) {
        if (first)
            affected =
                accumulate6_first(K_, D_, ch, cg, yh, yg, mh, mg, bh, bh + K_, bh + 2 * K_,
                                  bh + 3 * K_, bh + 4 * K_, bh + 5 * K_, bg, bg + K_, bg + 2 * K_,
                                  bg + 3 * K_, bg + 4 * K_, bg + 5 * K_, dmh, dmg);
        else
            affected = accumulate6(K_, D_, ch, cg, yh, yg, mh, mg, bh, bh + K_, bh + 2 * K_,
                                   bh + 3 * K_, bh + 4 * K_, bh + 5 * K_, bg, bg + K_, bg + 2 * K_,
                                   bg + 3 * K_, bg + 4 * K_, bg + 5 * K_, dmh, dmg);
    } else {
        affected = weigh_values(K_, D_, yh, yg, mh, mg, hv, gv, dmh, dmg);
        for (int u = 0; u < n_; ++u)
            add_rhs(K_, ch[u], cg[u], hv, gv, bh + std::size_t(u) * K_, bg + std::size_t(u) * K_);
    }
    if (affected == 0)
        return;
    block &bl = block_at(b);
    double *dh_b = dh(b), *dg_b = dg(b);
    if (!bl.has_down) {
        std::fill_n(dh_b, std::size_t(ntri_) * K_, 0.0);
        std::fill_n(dg_b, std::size_t(ntri_) * K_, 0.0);
        bl.has_down = true;
    }
    if (affected * 8 > K_) {
        bl.dense_down = true;
        for (int u = 0; u < n_; ++u)
            for (int v = u; v < n_; ++v) {
                const std::size_t e = packed(n_, u, v);
                add_down(K_, ch[u] * ch[v], cg[u] * cg[v], dmh, dmg, dh_b + e * K_, dg_b + e * K_);
            }
        return;
    }
    for (std::size_t k = 0; k < K_; ++k) {
        if (dmh[k] == 0.0 && dmg[k] == 0.0)
            continue;
        mark_down(bl, b, k);
        for (int u = 0; u < n_; ++u)
            for (int v = u; v < n_; ++v) {
                const std::size_t e = packed(n_, u, v);
                dh_b[e * K_ + k] += ch[u] * ch[v] * dmh[k];
                dg_b[e * K_ + k] += cg[u] * cg[v] * dmg[k];
            }
    }
}

void robust_window::advance_to(long i1) {
    while (c1_ < i1) {
        ++c1_;
        open_block(c1_);
        // A round every emission group of strip: the blocks due are judged
        // (also before the first emission of a strip or sheet, so that the
        // first blocks are judged as often as any), and knots are emitted
        // once the lag allows (as the plain engine emits).
        const long last = c1_ - 1 - L_;
        const bool head = head_ && c1_ < p_.start_lag_knots;  // waits longer
        if (last - next_emit_ + 1 >= G_ && !head)
            emit(last);
        else if (c1_ - last_round_ >= G_)
            round();
    }
}

void robust_window::round() {
    last_round_ = c1_;
    bool any = false;
    for (long b = first_block_; b <= c1_ && !any; ++b)
        any = due(b);
    if (!any)
        return;
    solve();
    for (long b = first_block_; b <= c1_; ++b)
        if (due(b))
            judge(b, false);
}

bool robust_window::due(long b) const {
    const block &bl = blocks_[slot(b)];
    // In the strip's head every block up to start - lag - 1 is emitted at
    // once, when the newest row reaches start: its judgments are spaced over
    // the lag before that emission, as any block's are before its own.
    long from = b;
    if (head_)
        from = std::max(b, p_.start_lag_knots - L_ - 1);
    return bl.judged < iterations_ && c1_ - from >= due_distance_[std::size_t(bl.judged)];
}

void robust_window::emit(long last) {
    last_round_ = c1_;
    // The blocks due are judged against the window solved with every row
    // so far. (Judging against the previous emission's solution, an
    // emission group older, would save one solve in two but costs accuracy:
    // bench_latency measured 0.096 against 0.075 mm MaxAE on the third
    // experiment at the default latency, 0.130 against 0.073 at 3000 mm.)
    solve();
    bool judged = false;
    for (long b = first_block_; b <= c1_; ++b)
        if (due(b)) {
            judge(b, b <= last);  // its last judgment feeds the scales
            judged = true;
        }
    head_ = false;
    if (judged)
        solve();
    emit_states(last);
    freeze_upto(last);
}

// The states of knots next_emit_ .. last become final, knot by knot: the
// output's ring of knot states need not hold them all at once (the first
// emission of a strip, or an end of sheet, may emit many).
void robust_window::emit_states(long last) {
    for (; next_emit_ <= last; ++next_emit_) {
        const double *x = state(next_emit_);
        out_.set_knot_state(next_emit_, x, x + K_);
        out_.mark_emitted(next_emit_);
    }
}

void robust_window::judge(long b, bool feed) {
    block &bl = block_at(b);
    if (n_ != 6 || bl.rows == 0)
        clear_rhs(b);  // else the first row sets them
    bl.has_down = false;
    clear_down(bl, b);
    const double *xs[2 * 66];
    for (int u = 0; u < n_; ++u)
        xs[u] = state(b + u / 2) + std::size_t(u % 2) * K_;
    double ch[2 * 66], cg[2 * 66];
    for (std::size_t i = 0; i < bl.rows; ++i) {
        const std::size_t r = (bl.first_row + i) % row_cap_;
        const double s = row_s_[r];
        const double *h = row_dh_.data(), *g = row_dg_.data();
        widen_row(K_, row_h_.data() + r * K_, row_g_.data() + r * K_, row_dh_.data(),
                  row_dg_.data());
        frozen_.coefficients(s, b, ch, cg);
        // What the two lasers would see on the current solution.
        if (n_ == 6) {
            predict6(K_, ch, cg, xs[0], xs[1], xs[2], xs[3], xs[4], xs[5], pred_h_.data(),
                     pred_g_.data());
        } else {
            std::fill(pred_h_.begin(), pred_h_.end(), 0.0);
            std::fill(pred_g_.begin(), pred_g_.end(), 0.0);
            for (int u = 0; u < n_; ++u)
                if (ch[u] != 0.0 || cg[u] != 0.0)
                    add_prediction(K_, ch[u], cg[u], xs[u], pred_h_.data(), pred_g_.data());
        }
        robust_weigh_row(robust_.kind, K_, D_, h, g, nullptr, nullptr, pred_h_.data(),
                         pred_g_.data(), hs_, gs_, feed, sink_sum_.data(), sink_count_.data(),
                         out_h_.data(), out_g_.data(), mult_h_.data(), mult_g_.data());
        if (feed) {
            const bool new_h = hs_.end_row(), new_g = gs_.end_row();
            if (new_h || new_g)
                update_weights();
        }
        add_row(b, r, ch, cg, out_h_.data(), out_g_.data(), mult_h_.data(), mult_g_.data(), i == 0);
    }
    ++bl.judged;
}

void robust_window::update_weights() {
    robust_scale::weights(hs_, gs_, recon_engine::max_weight_ratio(), wh_.data(), wg_.data());
    frozen_.set_fiber_weights(wh_.data(), wg_.data());
}

void robust_window::freeze_upto(long last) {
    for (; first_block_ <= last; ++first_block_) {
        const long b = first_block_;
        const block &bl = block_at(b);
        if (bl.rows == 0 && n_ == 6)
            clear_rhs(b);  // no first row set them (open_block)
        frozen_.add_block(b, gh(b), gg(b), rh(b), rg(b), bl.has_down ? dh(b) : nullptr,
                          bl.has_down ? dg(b) : nullptr);
        frozen_.forget_upto(frozen_.first_open_knot() - 1);
        row_head_ = std::max(row_head_, bl.first_row + bl.rows);
    }
}

void robust_window::solve(bool provisional) {
    const long w0 = frozen_.first_open_knot();
    // The newest row's knots, and at least the frozen engine's window (right
    // after a sheet's end the new rows may still touch carried knots only).
    const long last_knot = std::max(c1_, w0) + S_ - 1;
    const int knots = int(last_knot - w0 + 1);
    if (knots < S_ || knots > max_knots_)
        throw error(FLT_ERR_INTERNAL, "robust window: too many knots to solve");
    const int N = 2 * knots, P = bw_ + 1;
    // The shared (unweighted) part: the blocks' outer products and the
    // priors of the knots beyond the frozen engine's window.
    std::fill_n(bh_.data(), std::size_t(N) * P, 0.0);
    std::fill_n(bg_.data(), std::size_t(N) * P, 0.0);
    for (long b = first_block_; b <= c1_; ++b) {
        if (block_at(b).rows == 0)
            continue;
        const int base = 2 * int(b - w0);
        const double *a = gh(b), *c = gg(b);
        for (int u = 0; u < n_; ++u) {
            const int iu = base + u;
            if (iu < 0)
                continue;  // a carried knot: solve_chunk moves it
            for (int v = u; v < n_; ++v) {
                const std::size_t at = std::size_t(iu) * P + std::size_t(v - u);
                bh_[at] += a[u * n_ + v];
                bg_[at] += c[u * n_ + v];
            }
        }
    }
    prior_term terms[5];
    for (long j = w0 + S_; j <= last_knot; ++j) {
        const int count = frozen_.knot_priors(j, terms);
        for (int t = 0; t < count; ++t) {
            const prior_term &pt = terms[t];
            std::vector<double> &band = pt.slope_weighted ? bg_ : bh_;
            for (int a = 0; a < pt.count; ++a)
                for (int c = 0; c < pt.count; ++c) {
                    const int ia = 2 * int(pt.knot[a] - w0) + pt.unit[a];
                    const int ic = 2 * int(pt.knot[c] - w0) + pt.unit[c];
                    if (ia < ic || a == c)
                        band[std::size_t(ia) * P + std::size_t(ic - ia)] += pt.m[a][c];
                }
        }
    }
    const double *W = frozen_.open_window_matrix();
    const double *R0 = frozen_.open_window_rhs();
    // A provisional solve (peek) goes to peek_x_, [knot - w0][2][K], and
    // leaves the solution the next emission judges by as it was.
    double *out = provisional ? peek_x_.data() : nullptr;
    for (std::size_t k0 = 0; k0 < K_; k0 += chunk_)
        solve_chunk(w0, knots, k0, std::min(K_, k0 + chunk_), W, R0, out);
    if (provisional)
        return;
    solved_w0_ = w0;
    solved_last_ = last_knot;
}

void robust_window::solve_chunk(long w0, int knots, std::size_t k0, std::size_t k1, const double *W,
                                const double *R0, double *out) {
    const std::size_t C = k1 - k0;
    const int N = 2 * knots, P = bw_ + 1;
    double *A = band_.data(), *y = brhs_.data();
    const double *wh = wh_.data() + k0, *wg = wg_.data() + k0;
    auto at = [&](int i, int d) {
        return A + (std::size_t(i) * P + std::size_t(d)) * C;
    };
    weigh_band(std::size_t(N) * P, C, bh_.data(), bg_.data(), wh, wg, A);
    std::fill_n(y, std::size_t(N) * C, 0.0);
    // The frozen engine's open window: its first S knots.
    for (int r = 0; r < n_; ++r) {
        for (int c = r; c < n_; ++c) {
            const double *w = W + frozen_.window_entry(r, c) * K_ + k0;
            double *a = at(r, c - r);
            for (std::size_t i = 0; i < C; ++i)
                a[i] += w[i];
        }
        const double *b = R0 + std::size_t(r) * K_ + k0;
        double *yr = y + std::size_t(r) * C;
        for (std::size_t i = 0; i < C; ++i)
            yr[i] += b[i];
    }
    // The blocks' right-hand sides and downdates.
    for (long b = first_block_; b <= c1_; ++b) {
        const block &bl = block_at(b);
        if (bl.rows == 0)
            continue;
        const int base = 2 * int(b - w0);
        const double *bh = rh(b), *bg = rg(b), *dh_b = dh(b), *dg_b = dg(b);
        const bool dense = bl.has_down && bl.dense_down;
        for (int u = 0; u < n_; ++u) {
            const int iu = base + u;
            if (iu < 0)
                continue;
            add_weighted(C, 1.0, wh, wg, bh + std::size_t(u) * K_ + k0,
                         bg + std::size_t(u) * K_ + k0, y + std::size_t(iu) * C);
            if (dense)
                for (int v = u; v < n_; ++v) {
                    const std::size_t e = packed(n_, u, v);
                    add_weighted(C, -1.0, wh, wg, dh_b + e * K_ + k0, dg_b + e * K_ + k0,
                                 at(iu, v - u));
                }
        }
        if (bl.has_down && !dense) {
            // The listed fibers only (block::down_count): the same
            // subtraction, entry by entry, as add_weighted's.
            const std::uint32_t *list = down_fibers_.data() + slot(b) * down_cap_;
            for (std::size_t l = 0; l < bl.down_count; ++l) {
                const std::size_t k = list[l];
                if (k < k0 || k >= k1)
                    continue;
                const std::size_t c = k - k0;
                for (int u = std::max(0, -base); u < n_; ++u)
                    for (int v = u; v < n_; ++v) {
                        const std::size_t e = packed(n_, u, v);
                        at(base + u, v - u)[c] +=
                            -1.0 * (wh[c] * dh_b[e * K_ + k] + wg[c] * dg_b[e * K_ + k]);
                    }
            }
        }
        if (base >= 0)
            continue;
        // Knots before the window: carried boundary conditions (right after
        // end_sheet); their part moves to the right-hand side.
        const double *ga = gh(b), *gc = gg(b);
        for (int u = -base; u < n_; ++u) {
            double *yu = y + std::size_t(base + u) * C;
            for (int q = 0; q < -base; ++q) {
                const double *x = state(b + q / 2) + std::size_t(q % 2) * K_ + k0;
                const std::size_t e = packed(n_, u, q);
                for (std::size_t i = 0; i < C; ++i) {
                    double a = wh[i] * ga[u * n_ + q] + wg[i] * gc[u * n_ + q];
                    if (bl.has_down)
                        a -= wh[i] * dh_b[e * K_ + k0 + i] + wg[i] * dg_b[e * K_ + k0 + i];
                    yu[i] -= a * x[i];
                }
            }
        }
    }
    // Pivot floors, relative to each fiber's largest diagonal entry.
    double *floor = floor_.data();
    std::fill_n(floor, C, 0.0);
    for (int i = 0; i < N; ++i) {
        const double *d = at(i, 0);
        for (std::size_t c = 0; c < C; ++c)
            floor[c] = std::max(floor[c], d[c]);
    }
    for (std::size_t c = 0; c < C; ++c)
        floor[c] = std::max(recon_engine::pivot_floor() * floor[c], 1e-300);
    band_solve(N, bw_, C, A, y, floor);
    for (int i = 0; i < N; ++i) {
        const long j = w0 + i / 2;
        double *x = out ? out + std::size_t(i / 2) * 2 * K_ : x_.data() + slot(j) * 2 * K_;
        std::copy_n(y + std::size_t(i) * C, C, x + std::size_t(i % 2) * K_ + k0);
    }
}

std::size_t robust_window::peek(std::size_t offset, std::size_t max_rows, double *s_out,
                                double *z_out, std::uint8_t *flags_out) {
    if (!started_)
        return 0;
    if (out_.held_rows() > out_.ready_rows()) {
        // Pending rows: the window solved now, without judging, into a
        // buffer of its own (nothing final depends on this solve: the
        // window's own solution, which the next emission judges by, stays
        // as it was).
        const long w0 = frozen_.first_open_knot();
        solve(true);
        const long last_knot = std::max(c1_, w0) + S_ - 1;
        for (long j = std::max(next_emit_, w0); j <= last_knot; ++j) {
            const double *x = peek_x_.data() + std::size_t(j - w0) * 2 * K_;
            out_.set_knot_state(j, x, x + K_);
        }
    }
    return out_.peek(offset, max_rows, s_out, z_out, flags_out);
}

void robust_window::end_sheet() {
    if (!started_)
        return;
    const long e_end = out_.interval_at(out_.last_s()) + 1;
    // The remaining blocks, judged against the whole window as batch passes
    // are against the whole sheet; the last pass feeds the scales.
    for (int pass = 0; pass < iterations_; ++pass) {
        solve();
        for (long b = first_block_; b <= c1_; ++b)
            judge(b, pass + 1 == iterations_);
    }
    solve();
    if (e_end > solved_last_ || e_end < next_emit_ - 1)
        throw error(FLT_ERR_INTERNAL, "robust window: sheet end outside the window");
    emit_states(e_end);
    // The knots the next sheet touches become its hard boundary conditions,
    // in the frozen engine (for the solves) and the output (for its rows).
    for (long j = std::max(0L, e_end - S_ + 1); j <= e_end; ++j) {
        const double *x = j >= solved_w0_ ? state(j) : out_.knot_state(j);
        frozen_.set_knot_state(j, x, x + K_);
    }
    frozen_.carry_over(e_end);
    out_.carry_over(e_end);
    head_ = false;
    // The sheet's rows are done; its blocks leave the window.
    row_head_ = row_tail_;
    first_block_ = c1_;
    open_block(c1_);
    solved_w0_ = 0;
    solved_last_ = -1;
}

void robust_window::reset() {
    out_.reset();
    frozen_.reset();
    hs_.reset();
    gs_.reset();
    std::fill(wh_.begin(), wh_.end(), frozen_.default_height_weight());
    std::fill(wg_.begin(), wg_.end(), frozen_.default_slope_weight());
    frozen_.set_fiber_weights(wh_.data(), wg_.data());
    started_ = false;
    c1_ = next_emit_ = first_block_ = 0;
    row_head_ = row_tail_ = 0;
    solved_w0_ = 0;
    solved_last_ = -1;
}

}  // namespace flt
