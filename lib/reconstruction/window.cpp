// SPDX-License-Identifier: Apache-2.0
#include "reconstruction/window.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

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

// Built for baseline x86-64 and AVX2 (no FMA: the same roundings on every
// machine), as engine.cpp's kernels.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#  define FLT_WINDOW_KERNEL __attribute__((target_clones("avx2", "default")))
#else
#  define FLT_WINDOW_KERNEL
#endif

// A row as the window keeps it: the value where it is a sample (finite, at
// most k_max_sample, valid when a mask is given), NaN elsewhere, in double
// (out_h, out_g: this row's plain sums) and in float (keep_h, keep_g: the
// window's store, read again when the row is judged; robust_window says
// why float).
FLT_WINDOW_KERNEL void store_row(std::size_t K, const double *__restrict h,
                                 const double *__restrict g, const std::uint8_t *__restrict valid,
                                 double *__restrict out_h, double *__restrict out_g,
                                 float *__restrict keep_h, float *__restrict keep_g) {
    const double big = k_max_sample;
    for (std::size_t k = 0; k < K; ++k) {
        const double ok = valid == nullptr || valid[k] != 0 ? 1.0 : 0.0;
        const bool hok = ok != 0.0 && std::fabs(h[k]) <= big;
        const bool gok = ok != 0.0 && std::fabs(g[k]) <= big;
        out_h[k] = hok ? h[k] : k_nan;
        out_g[k] = gok ? g[k] : k_nan;
        keep_h[k] = float(out_h[k]);
        keep_g[k] = float(out_g[k]);
    }
}

// A kept row back in double.
FLT_WINDOW_KERNEL void widen_row(std::size_t K, const float *__restrict h,
                                 const float *__restrict g, double *__restrict out_h,
                                 double *__restrict out_g) {
    for (std::size_t k = 0; k < K; ++k) {
        out_h[k] = double(h[k]);
        out_g[k] = double(g[k]);
    }
}

// What a sample adds to the right-hand sides (value times its multiplier,
// 0 where the multiplier is 0: an invalid sample's value is NaN; slopes as
// Delta-d * slope, mm) and what it takes back out of the block's shared
// outer products (1 - multiplier). Returns the fibers that take any back.
FLT_WINDOW_KERNEL std::size_t weigh_values(std::size_t K, double D, const double *__restrict yh,
                                           const double *__restrict yg, const double *__restrict mh,
                                           const double *__restrict mg, double *__restrict hv,
                                           double *__restrict gv, double *__restrict dmh,
                                           double *__restrict dmg) {
    double affected = 0.0;
    for (std::size_t k = 0; k < K; ++k) {
        hv[k] = mh[k] != 0.0 ? mh[k] * yh[k] : 0.0;
        gv[k] = mg[k] != 0.0 ? mg[k] * (D * yg[k]) : 0.0;
        dmh[k] = 1.0 - mh[k];
        dmg[k] = 1.0 - mg[k];
        affected += mh[k] * mg[k] != 1.0 ? 1.0 : 0.0;
    }
    return std::size_t(affected);
}

// A plain row's multipliers: 1 for a sample, 0 for NaN.
FLT_WINDOW_KERNEL void sample_multipliers(std::size_t K, const double *__restrict h,
                                          const double *__restrict g, double *__restrict mh,
                                          double *__restrict mg) {
    for (std::size_t k = 0; k < K; ++k) {
        mh[k] = h[k] == h[k] ? 1.0 : 0.0;
        mg[k] = g[k] == g[k] ? 1.0 : 0.0;
    }
}

// rh += a * hv and rg += b * gv over the fibers.
FLT_WINDOW_KERNEL void add_rhs(std::size_t K, double a, double b, const double *__restrict hv,
                               const double *__restrict gv, double *__restrict rh,
                               double *__restrict rg) {
    for (std::size_t k = 0; k < K; ++k) {
        rh[k] += a * hv[k];
        rg[k] += b * gv[k];
    }
}

// One packed entry of the block's downdates: dh += a * dmh, dg += b * dmg.
FLT_WINDOW_KERNEL void add_down(std::size_t K, double a, double b, const double *__restrict dmh,
                                const double *__restrict dmg, double *__restrict dh,
                                double *__restrict dg) {
    for (std::size_t k = 0; k < K; ++k) {
        dh[k] += a * dmh[k];
        dg[k] += b * dmg[k];
    }
}

// pred_h += a * x, pred_g += b * x: one unknown's share of the two lasers'
// view of the current solution.
FLT_WINDOW_KERNEL void add_prediction(std::size_t K, double a, double b, const double *__restrict x,
                                      double *__restrict pred_h, double *__restrict pred_g) {
    for (std::size_t k = 0; k < K; ++k) {
        pred_h[k] += a * x[k];
        pred_g[k] += b * x[k];
    }
}

// The default geometry (knots every laser spacing: a row spans three knots,
// six unknowns) in one pass over the fibers each, where the general loops
// above take one pass per unknown:
// the two lasers' view of the solution from the six unknowns' states x0..x5,
FLT_WINDOW_KERNEL void predict6(std::size_t K, const double *a, const double *b,
                                const double *__restrict x0, const double *__restrict x1,
                                const double *__restrict x2, const double *__restrict x3,
                                const double *__restrict x4, const double *__restrict x5,
                                double *__restrict pred_h, double *__restrict pred_g) {
    const double a0 = a[0], a1 = a[1], a2 = a[2], a3 = a[3], a4 = a[4], a5 = a[5];
    const double b0 = b[0], b1 = b[1], b2 = b[2], b3 = b[3], b4 = b[4], b5 = b[5];
    for (std::size_t k = 0; k < K; ++k) {
        pred_h[k] = a0 * x0[k] + a1 * x1[k] + a2 * x2[k] + a3 * x3[k] + a4 * x4[k] + a5 * x5[k];
        pred_g[k] = b0 * x0[k] + b1 * x1[k] + b2 * x2[k] + b3 * x3[k] + b4 * x4[k] + b5 * x5[k];
    }
}

// and a sample's share of the block's right-hand sides (weigh_values and
// add_rhs for the six unknowns at once). Returns the fibers that take any
// weight back (their complements in dmh, dmg). The twelve right-hand sides
// are restrict parameters and the count an integer: GCC vectorises the
// loop only so (restrict locals, or a floating-point count, leave it
// scalar).
#define FLT_ACCUMULATE6_PARAMS                                                               \
  std::size_t K, double D, const double *__restrict a, const double *__restrict b,           \
      const double *__restrict yh, const double *__restrict yg, const double *__restrict mh, \
      const double *__restrict mg, double *__restrict rh0, double *__restrict rh1,           \
      double *__restrict rh2, double *__restrict rh3, double *__restrict rh4,                \
      double *__restrict rh5, double *__restrict rg0, double *__restrict rg1,                \
      double *__restrict rg2, double *__restrict rg3, double *__restrict rg4,                \
      double *__restrict rg5, double *__restrict dmh, double *__restrict dmg
// RH(r) is the right-hand side an entry adds to: the entry itself, or for
// a block's first row 0.0 (accumulate6_first: the bits of adding to a
// cleared block, without clearing it first or reading it back).
#define FLT_ACCUMULATE6_BODY(RH)                                                 \
  const double a0 = a[0], a1 = a[1], a2 = a[2], a3 = a[3], a4 = a[4], a5 = a[5]; \
  const double b0 = b[0], b1 = b[1], b2 = b[2], b3 = b[3], b4 = b[4], b5 = b[5]; \
  std::size_t affected = 0;                                                      \
  for (std::size_t k = 0; k < K; ++k) {                                          \
    const double hv = mh[k] != 0.0 ? mh[k] * yh[k] : 0.0;                        \
    const double gv = mg[k] != 0.0 ? mg[k] * (D * yg[k]) : 0.0;                  \
    rh0[k] = RH(rh0[k]) + a0 * hv;                                               \
    rh1[k] = RH(rh1[k]) + a1 * hv;                                               \
    rh2[k] = RH(rh2[k]) + a2 * hv;                                               \
    rh3[k] = RH(rh3[k]) + a3 * hv;                                               \
    rh4[k] = RH(rh4[k]) + a4 * hv;                                               \
    rh5[k] = RH(rh5[k]) + a5 * hv;                                               \
    rg0[k] = RH(rg0[k]) + b0 * gv;                                               \
    rg1[k] = RH(rg1[k]) + b1 * gv;                                               \
    rg2[k] = RH(rg2[k]) + b2 * gv;                                               \
    rg3[k] = RH(rg3[k]) + b3 * gv;                                               \
    rg4[k] = RH(rg4[k]) + b4 * gv;                                               \
    rg5[k] = RH(rg5[k]) + b5 * gv;                                               \
    dmh[k] = 1.0 - mh[k];                                                        \
    dmg[k] = 1.0 - mg[k];                                                        \
    affected += std::size_t(mh[k] * mg[k] != 1.0);                               \
  }                                                                              \
  return affected;
#define FLT_RH_ADD(x)   (x)
#define FLT_RH_FIRST(x) 0.0
FLT_WINDOW_KERNEL std::size_t accumulate6(FLT_ACCUMULATE6_PARAMS){
    FLT_ACCUMULATE6_BODY(FLT_RH_ADD)} FLT_WINDOW_KERNEL std::size_t
    accumulate6_first(FLT_ACCUMULATE6_PARAMS) {
    FLT_ACCUMULATE6_BODY(FLT_RH_FIRST)
}
#undef FLT_RH_ADD
#undef FLT_RH_FIRST

inline void sub_product(std::size_t C, double *__restrict out, const double *__restrict a,
                        const double *__restrict b) {
    for (std::size_t c = 0; c < C; ++c)
        out[c] -= a[c] * b[c];
}

// out = (out - a[0] * b[0] - a[1] * b[1] - ... - a[n-1] * b[n-1]) * scale
// over C fibers (scale nullptr: 1), subtracting in the order given: the
// bits of n sub_product passes and a multiplying pass, in one pass over
// out (the banded solve's entries gather up to bw products each, and
// their passes were its cost). Up to five products per pass, the rest in
// further passes, in order. Inlined into band_solve, so that it is built
// for each of band_solve's targets.
#if defined(__GNUC__)
#  define FLT_ALWAYS_INLINE __attribute__((always_inline)) inline
#else
#  define FLT_ALWAYS_INLINE inline
#endif
FLT_ALWAYS_INLINE void sub_products(std::size_t C, double *out, int n, const double *const *a,
                                    const double *const *b, const double *scale) {
    int i = 0;
    for (; n - i > 5; i += 5)
        for (int j = i; j < i + 5; ++j)
            sub_product(C, out, a[j], b[j]);
    const int m = n - i;
    double *__restrict o = out;
    const double *__restrict a0 = m > 0 ? a[i] : nullptr, *__restrict b0 = m > 0 ? b[i] : nullptr;
    const double *__restrict a1 = m > 1 ? a[i + 1] : nullptr, *__restrict b1 =
                                                                  m > 1 ? b[i + 1] : nullptr;
    const double *__restrict a2 = m > 2 ? a[i + 2] : nullptr, *__restrict b2 =
                                                                  m > 2 ? b[i + 2] : nullptr;
    const double *__restrict a3 = m > 3 ? a[i + 3] : nullptr, *__restrict b3 =
                                                                  m > 3 ? b[i + 3] : nullptr;
    const double *__restrict a4 = m > 4 ? a[i + 4] : nullptr, *__restrict b4 =
                                                                  m > 4 ? b[i + 4] : nullptr;
    const double *__restrict sc = scale;
#define FLT_SUB_TERMS(expr)             \
  if (sc)                               \
    for (std::size_t c = 0; c < C; ++c) \
      o[c] = (expr)*sc[c];              \
  else                                  \
    for (std::size_t c = 0; c < C; ++c) \
      o[c] = (expr);
    switch (m) {
        case 0:
            if (sc)
                for (std::size_t c = 0; c < C; ++c)
                    o[c] *= sc[c];
            break;
        case 1:
            FLT_SUB_TERMS(o[c] - a0[c] * b0[c])
            break;
        case 2:
            FLT_SUB_TERMS(o[c] - a0[c] * b0[c] - a1[c] * b1[c])
            break;
        case 3:
            FLT_SUB_TERMS(o[c] - a0[c] * b0[c] - a1[c] * b1[c] - a2[c] * b2[c])
            break;
        case 4:
            FLT_SUB_TERMS(o[c] - a0[c] * b0[c] - a1[c] * b1[c] - a2[c] * b2[c] - a3[c] * b3[c])
            break;
        default:
            FLT_SUB_TERMS(o[c] - a0[c] * b0[c] - a1[c] * b1[c] - a2[c] * b2[c] - a3[c] * b3[c] -
                          a4[c] * b4[c])
            break;
    }
#undef FLT_SUB_TERMS
}

// The window band of a chunk of C fibers, [unknown][0..bw][C] (entry (i,
// i + d) of the symmetric matrix), factored in place as U^T U with U upper
// (keeping 1/U_ii on the diagonal), then U^T U x = y solved in place. A
// pivot below floor[c] is taken as floor[c] (engine.cpp's pivot floor).
FLT_WINDOW_KERNEL void band_solve(int N, int bw, std::size_t C, double *__restrict A,
                                  double *__restrict y, const double *__restrict floor) {
    const int P = bw + 1;
    auto at = [&](int i, int d) {
        return A + (std::size_t(i) * P + std::size_t(d)) * C;
    };
    // Each entry gathers its products (in the order of the plain loops:
    // m, or d, ascending) and is written once (sub_products).
    const double *ta[k_max_band], *tb[k_max_band];
    for (int i = 0; i < N; ++i) {
        double *aii = at(i, 0);
        int t = 0;
        for (int m = std::max(0, i - bw); m < i; ++m, ++t)
            ta[t] = tb[t] = at(m, i - m);
        sub_products(C, aii, t, ta, tb, nullptr);
        for (std::size_t c = 0; c < C; ++c)
            aii[c] = 1.0 / std::sqrt(std::max(aii[c], floor[c]));
        for (int d = 1; d <= bw && i + d < N; ++d) {
            const int j = i + d;
            t = 0;
            for (int m = std::max(0, j - bw); m < i; ++m, ++t) {
                ta[t] = at(m, i - m);
                tb[t] = at(m, j - m);
            }
            sub_products(C, at(i, d), t, ta, tb, aii);
        }
    }
    // U^T z = y
    for (int i = 0; i < N; ++i) {
        int t = 0;
        for (int m = std::max(0, i - bw); m < i; ++m, ++t) {
            ta[t] = at(m, i - m);
            tb[t] = y + std::size_t(m) * C;
        }
        sub_products(C, y + std::size_t(i) * C, t, ta, tb, at(i, 0));
    }
    // U x = z
    for (int i = N - 1; i >= 0; --i) {
        int t = 0;
        for (int d = 1; d <= bw && i + d < N; ++d, ++t) {
            ta[t] = at(i, d);
            tb[t] = y + std::size_t(i + d) * C;
        }
        sub_products(C, y + std::size_t(i) * C, t, ta, tb, at(i, 0));
    }
}

// The chunk's band from the shared (unweighted) bands and the fibers'
// weights: A = wh * bh + wg * bg, entry by entry.
FLT_WINDOW_KERNEL void weigh_band(std::size_t entries, std::size_t C, const double *__restrict bh,
                                  const double *__restrict bg, const double *__restrict wh,
                                  const double *__restrict wg, double *__restrict A) {
    for (std::size_t e = 0; e < entries; ++e) {
        const double a = bh[e], b = bg[e];
        double *out = A + e * C;
        for (std::size_t c = 0; c < C; ++c)
            out[c] = wh[c] * a + wg[c] * b;
    }
}

// out += wh * a + wg * b (sign +1) or out -= ... (sign -1).
FLT_WINDOW_KERNEL void add_weighted(std::size_t C, double sign, const double *__restrict wh,
                                    const double *__restrict wg, const double *__restrict a,
                                    const double *__restrict b, double *__restrict out) {
    for (std::size_t c = 0; c < C; ++c)
        out[c] += sign * (wh[c] * a[c] + wg[c] * b[c]);
}

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
        affected = (first ? accumulate6_first : accumulate6)(
            K_, D_, ch, cg, yh, yg, mh, mg, bh, bh + K_, bh + 2 * K_, bh + 3 * K_, bh + 4 * K_,
            bh + 5 * K_, bg, bg + K_, bg + 2 * K_, bg + 3 * K_, bg + 4 * K_, bg + 5 * K_, dmh, dmg);
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
