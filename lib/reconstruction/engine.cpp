// SPDX-License-Identifier: Apache-2.0
#include "reconstruction/engine.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/cpu_dispatch.hpp"
#include "core/error.hpp"
#include "flatline/recon.h"

namespace flt {
namespace {

// L^3 * integral of z''(s)^2 over one knot interval, as a quadratic form in
// (z_i, m_i, z_i+1, m_i+1) with m = L*z' (all mm): the cubic Hermite
// stiffness matrix.
constexpr double k_stiffness[4][4] = {
    {12.0, 6.0, -12.0, 6.0},
    {6.0, 4.0, -6.0, 2.0},
    {-12.0, -6.0, 12.0, -6.0},
    {6.0, 2.0, -6.0, 4.0},
};

// The ridge on every knot height: k_ridge of the strongest term of its
// fiber (a height sample, a slope sample, or a prior), so that it stays
// above that term's rounding. Only there so that a fiber with no height at
// all, or a stretch of knots without data, still has a regular system; its
// effect on measured fibers is below 1e-12 of the data at the defaults and
// below 1e-4 of one height sample per knot at the largest weights.
constexpr double k_ridge = 1e-12;

// The most a slope sample or a prior may weigh against a height sample of
// its fiber (recon.h; slope_sigma, curvature_weight, curvature_jump_weight).
// Only heights see a fiber's level: slopes and the priors are blind to it.
// When another term weighs W times more, eliminating a knot subtracts
// numbers of order W from each other to leave the heights' share, and the
// rounding (W * 2e-16) swamps it: at slope_sigma = 1e-12 (W = 1e20) every
// output was NaN, and at curvature_jump_weight = 1e10 a stretch of knots
// without rows was. At 1e8 the rounding is 2e-8 of the heights' share and
// the ridge above outweighs it 4500-fold. Slopes that precise already fit
// the shape to within 1e-8 of the heights' influence, and priors that
// strong already make the spline their own null space (a cubic, or a
// line) to within 1e-8.
constexpr double k_max_weight_ratio = 1e8;

// The smallest pivot of the Cholesky factorisations, relative to the
// largest diagonal entry of the fiber's window: below it a pivot is
// rounding (450 times the double's epsilon), and the direction it belongs
// to is not determined by the data and priors as far as double precision
// can tell. Such a pivot used to be clamped to 1e-300, whose reciprocal
// overflowed the solution into NaN (a strong curvature-jump prior over a
// stretch of knots without rows, with the curvature prior at its minimum:
// the contract suite); at the floor, that direction stays at what the
// ridge and its neighbours give it. Well-posed systems have pivots far
// above it and are solved exactly as before.
constexpr double k_pivot_floor = 1e-13;

// The weakest curvature prior, relative to the strongest sample of its
// fiber (a height, or a slope) and to the jump prior: where no row is, the
// curvature prior alone holds the knots' heights and slopes (the jump prior
// leaves one height per knot free, and slopes are seen only under rows).
// Weaker, it was rounding next to those terms: with the slopes at their
// cap, curvature_weight at its minimum (1e-12) and rows 1000 knots apart,
// or rigid_motion's deviation channel (its priors scale with (shape_sigma /
// height_sigma)^2, 1e-42 at the options' ends), the outputs were NaN (the
// contract suite). It bends a shape by 1e-8 of what the data says.
constexpr double k_min_curvature_weight = 1.0 / k_max_weight_ratio;

// Largest knot span of one row we size scratch arrays for (the API allows
// D/L <= 16, recon_api.cpp; the engine itself takes up to 64).
constexpr int k_max_unknowns = 2 * 66;

// The engine's methods that run once per fiber and knot (and relative_row)
// are built twice on Linux, for baseline x86-64 (SSE2) and for AVX2, and
// the loader picks one per machine (GCC function multiversioning; Windows
// has no such loader and runs the baseline, 2-7 % slower in bench_recon:
// these are a small share of the time, next to the kernels below, which
// are dispatched on every platform). AVX2 without FMA keeps every
// rounding identical, so results do not depend on the machine.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#  define FLT_ROW_KERNEL __attribute__((target_clones("avx2", "default")))
#else
#  define FLT_ROW_KERNEL
#endif

// The per-row kernels, built for baseline x86-64 and for AVX2; each call
// takes the AVX2 build where the CPU has it (core/cpu_dispatch.hpp).
#define FLT_KERNELS_FILE "reconstruction/engine_kernels.inc"
#include "core/cpu_dispatch_build.inc"
FLT_DISPATCH(row_is_finite)
FLT_DISPATCH(accumulate_row6)
FLT_DISPATCH(weighted_row6)
FLT_DISPATCH(weighted_row6_masked)
FLT_DISPATCH(mask_row)
FLT_DISPATCH(downdate_weights)
FLT_DISPATCH(downdate_entry)
FLT_DISPATCH(weigh_row)
FLT_DISPATCH(add_row_rhs)
FLT_DISPATCH(predict_row)
FLT_DISPATCH(evaluate_row)
FLT_DISPATCH(evaluate_row_plus)
FLT_DISPATCH(back_substitute6)
FLT_DISPATCH(factor_pivots)
FLT_DISPATCH(factor_column)
FLT_DISPATCH(add_constant)

// Cubic Hermite basis at t in [0, 1] of a knot interval: the weights of
// (z_i, m_i, z_i+1, m_i+1), m = L z'.
void hermite_weights(double t, double w[4]) {
    t = std::min(1.0, std::max(0.0, t));  // rounding at the interval ends
    const double t2 = t * t, t3 = t2 * t;
    w[0] = 2 * t3 - 3 * t2 + 1;  // h00 -> z_i
    w[1] = t3 - 2 * t2 + t;      // h10 -> m_i = L z'_i
    w[2] = -2 * t3 + 3 * t2;     // h01 -> z_i+1
    w[3] = t3 - t2;              // h11 -> m_i+1
}

}  // namespace

FLT_ROW_KERNEL void relative_row(std::size_t K, double level, const double *__restrict height,
                                 double *__restrict out) {
    const double big = k_max_sample;
    for (std::size_t k = 0; k < K; ++k) {
        const double h = height[k], d = h - level;
        out[k] = std::fabs(h) <= big && std::fabs(d) <= big
                     ? d
                     : std::numeric_limits<double>::quiet_NaN();
    }
}

double recon_engine::bytes_needed(std::size_t fibers, const recon_params &params,
                                  std::size_t knot_capacity, bool owns_rows, bool keep_rows,
                                  engine_role role) {
    // The same sizes as the constructor below.
    const double K = double(fibers);
    const double rows = keep_rows ? double(params.row_capacity) : 1.0;
    const double S = std::ceil(params.laser_spacing / params.knot_spacing - 1e-9) + 2;
    const double n = 2 * S, ntri = n * (n + 1) / 2, nf = 5 + 2 * (n - 2);
    const double hist = double(knot_capacity) + 2 * S + 4;
    double doubles_per_fiber = hist * 2  // knot states
                               + 16;     // weights, scratch, bookkeeping
    if (role == engine_role::solve)
        doubles_per_fiber += double(knot_capacity) * nf  // factor ring
                             + 3 * ntri + 2 * n;         // window, Schur, rhs
    double bytes = 8 * K * doubles_per_fiber + 10 * rows + 24 * n * n;
    if (owns_rows)
        bytes += 9 * rows * K;  // z and flags of the row ring
    return bytes;
}

recon_engine::recon_engine(std::size_t fibers, const recon_params &params,
                           std::size_t knot_capacity, double *z_store, std::uint8_t *flags_store,
                           bool keep_rows, engine_role role)
    : K_(fibers), p_(params), keep_rows_(keep_rows), has_row_ring_(keep_rows), role_(role) {
    if (!keep_rows_)
        p_.row_capacity = 1;  // no row ring
    // The row ring first: the largest buffer, so an impossible size fails
    // before anything else is touched.
    if (z_store) {
        ring_z_ = z_store;
    } else {
        own_z_.assign(p_.row_capacity * K_, 0.0);
        ring_z_ = own_z_.data();
        lazy_rows_ = true;
    }
    if (flags_store) {
        ring_flags_ = flags_store;
    } else {
        own_flags_.assign(p_.row_capacity * K_, 0);
        ring_flags_ = own_flags_.data();
        lazy_flags_ = true;
    }
    ring_s_.assign(p_.row_capacity, 0.0);
    ring_any_invalid_.assign(p_.row_capacity, 0);
    ring_zero_flags_.assign(p_.row_capacity, 0);
    L_ = p_.knot_spacing;
    D_ = p_.laser_spacing;
    // A row touches the knots around s-D/2 and s+D/2: ceil(D/L) intervals
    // apart, so ceil(D/L)+2 knots (the epsilon absorbs D/L = 1 +- rounding).
    S_ = int(std::ceil(D_ / L_ - 1e-9)) + 2;
    n_ = 2 * S_;
    if (n_ > k_max_unknowns)
        throw error(FLT_ERR_INTERNAL, "knot span too large");
    ntri_ = n_ * (n_ + 1) / 2;
    nf_ = 5 + 2 * (n_ - 2);

    w_h_ = 1.0 / (p_.height_sigma * p_.height_sigma);
    const double slope_mm = D_ * p_.slope_sigma;  // sigma of D*slope, mm
    w_g_ = std::min(1.0 / (slope_mm * slope_mm), k_max_weight_ratio * w_h_);
    // Priors are relative to one height sample: they live in Rp_ unweighted
    // and are scaled by each fiber's height weight.
    w_curv_ = std::min(p_.curvature_weight, k_max_weight_ratio);
    w_curv_jump_ = std::min(p_.curvature_jump_weight, k_max_weight_ratio);
    // The jump prior leaves one free height per knot (a C2 spline through
    // any heights), which only the curvature prior damps where no row is:
    // a jump prior 1e17 times the curvature prior (1e5 and 1e-12) over
    // knots without rows made NaN (the contract suite). The same ratio cap.
    // Relative to the height weight here; relative to the slope weight the
    // floor goes into Rg_ (add_priors_for_knot), so it follows each fiber's
    // own weights, robust mode's too.
    w_curv_ = std::max({w_curv_, w_curv_jump_ * k_min_curvature_weight, k_min_curvature_weight});
    // The ridge must stay above the rounding of the strongest term, or a
    // fiber with slopes but no height yet, or a stretch of knots without
    // rows under a strong prior, has a numerically singular level (NaN
    // knots that later heights cannot repair): k_ridge of a height sample
    // or the strongest prior (relative to a height sample, in Rp_), plus
    // k_ridge of a slope sample (in Rg_), per fiber, so it follows robust
    // mode's weights too (a laser spacing of 0.36 mm puts the slope weight
    // 5e7 times above the height weight; fuzz_recon).
    w_ridge_ = k_ridge * std::max({1.0, w_curv_, w_curv_jump_});

    factor_cap_ = knot_capacity;
    hist_cap_ = knot_capacity + 2 * std::size_t(S_) + 4;

    hist_.assign(hist_cap_ * 2 * K_, 0.0);
    if (role_ == engine_role::solve) {
        Rh_.assign(std::size_t(n_) * n_, 0.0);
        Rg_.assign(std::size_t(n_) * n_, 0.0);
        Rp_.assign(std::size_t(n_) * n_, 0.0);
        wh_.assign(K_, w_h_);
        wg_.assign(K_, w_g_);
        next_wh_.assign(K_, w_h_);
        next_wg_.assign(K_, w_g_);
        schur_.assign(std::size_t(ntri_) * K_, 0.0);
        down_.assign(std::size_t(ntri_) * K_, 0.0);
        rhs_.assign(std::size_t(n_) * K_, 0.0);
        factor_.assign(factor_cap_ * nf_ * K_, 0.0);
        work_.assign(std::size_t(ntri_) * K_, 0.0);
        xwin_.assign(std::size_t(n_) * K_, 0.0);
        hv_.assign(K_, 0.0);
        gv_.assign(K_, 0.0);
        hm_.assign(K_, 0.0);
        gm_.assign(K_, 0.0);
        ones_.assign(K_, 1.0);
        pivot_floor_.assign(K_, 0.0);
        bad_.reserve(K_);
    }
    rel_h_.assign(K_, 0.0);
    last_valid_s_.assign(K_, 0.0);
    has_height_.assign(K_, 0);
    bc_z_.assign(K_, 0.0);
    bc_m_.assign(K_, 0.0);
}

void recon_engine::basis(double p, long i, double w[4]) const {
    basis_on(t0_, p, i, w);
}

void recon_engine::basis_on(double t0, double p, long i, double w[4]) const {
    hermite_weights((p - (t0 + double(i) * L_)) / L_, w);
}

double *recon_engine::hist_at(long j) {
    return hist_.data() + (std::size_t(j) % hist_cap_) * 2 * K_;
}
const double *recon_engine::hist_at(long j) const {
    return hist_.data() + (std::size_t(j) % hist_cap_) * 2 * K_;
}

// ---------------------------------------------------------------------------
// Window management
// ---------------------------------------------------------------------------

void recon_engine::clear_shared() {
    std::fill(Rh_.begin(), Rh_.end(), 0.0);
    std::fill(Rg_.begin(), Rg_.end(), 0.0);
    std::fill(Rp_.begin(), Rp_.end(), 0.0);
}

void recon_engine::set_fiber_weights(const double *wh, const double *wg) {
    std::copy_n(wh, K_, next_wh_.data());
    for (std::size_t k = 0; k < K_; ++k)
        next_wg_[k] = std::min(wg[k], k_max_weight_ratio * wh[k]);
    weights_pending_ = true;
}

// New weights take effect when the shared matrices are empty (right after a
// knot is eliminated), so every row in them carries one weight per fiber.
void recon_engine::apply_pending_weights() {
    if (!weights_pending_)
        return;
    wh_.swap(next_wh_);
    wg_.swap(next_wg_);
    std::copy_n(wh_.data(), K_, next_wh_.data());
    std::copy_n(wg_.data(), K_, next_wg_.data());
    weights_pending_ = false;
}

// One entry of every fiber's window matrix:
//   W = schur + wh * (Rh + Rp) + wg * Rg - down.
// Its loops over the fibers, and close_knot's and solve_all's, are built
// as the row kernels are (AVX2 without FMA next to the baseline: the same
// bits, twice the vector width).
FLT_ROW_KERNEL void recon_engine::assemble_entry(int r, int c) {
    const std::size_t e = tri(r, c), rc = std::size_t(r) * n_ + c;
    const double hp = Rh_[rc] + Rp_[rc], g = Rg_[rc];
    double *__restrict w = work_.data() + e * K_;
    const double *__restrict sc = schur_.data() + e * K_;
    const double *__restrict dn = down_.data() + e * K_;
    const double *__restrict wh = wh_.data(), *__restrict wg = wg_.data();
    if (bad_fibers_seen_)
        for (std::size_t k = 0; k < K_; ++k)
            w[k] = sc[k] + wh[k] * hp + wg[k] * g - dn[k];
    else
        for (std::size_t k = 0; k < K_; ++k)
            w[k] = sc[k] + wh[k] * hp + wg[k] * g;
}

// The row's unweighted outer products over the window unknowns.
void recon_engine::add_row_geometry(const double *ch, const double *cg, int off) {
    for (int u = off; u < n_; ++u)
        for (int v = off; v < n_; ++v) {
            const std::size_t rc = std::size_t(u - off) * n_ + (v - off);
            Rh_[rc] += ch[u] * ch[v];
            Rg_[rc] += cg[u] * cg[v];
        }
}

void recon_engine::start_window(long first_knot) {
    w0_ = first_knot;
    clear_shared();
    apply_pending_weights();
    std::fill(schur_.begin(), schur_.end(), 0.0);
    std::fill(down_.begin(), down_.end(), 0.0);
    bad_fibers_seen_ = false;
    std::fill(rhs_.begin(), rhs_.end(), 0.0);
    for (long j = first_knot; j < first_knot + S_; ++j)
        add_priors_for_knot(j);
}

// Adds w * (sum_i coef[i] * x[i])^2 to the objective, x[i] being unknown
// unit[i] (0: z, 1: m) of knot[i]. Open knots enter the window matrix; carried
// boundary knots move to every fiber's right-hand side. Skipped when a knot
// is neither (before the strip, or already eliminated).
void recon_engine::add_rank1_prior(const long *knot, const int *unit, const double *coef, int count,
                                   double w) {
    int open = 0;
    for (int i = 0; i < count; ++i) {
        if (knot[i] >= w0_) {
            if (knot[i] >= w0_ + S_)
                return;
            ++open;
        } else if (knot[i] < 0 || knot[i] > fixed_upto_) {
            return;
        }
    }
    if (open == 0)
        return;
    for (int i = 0; i < count; ++i) {
        if (knot[i] < w0_)
            continue;
        const int wi = 2 * int(knot[i] - w0_) + unit[i];
        for (int q = 0; q < count; ++q) {
            if (knot[q] >= w0_) {
                const int wq = 2 * int(knot[q] - w0_) + unit[q];
                Rp_[std::size_t(wi) * n_ + wq] += w * coef[i] * coef[q];
            } else {
                const double *x = hist_at(knot[q]) + std::size_t(unit[q]) * K_;
                double *rhs = rhs_.data() + std::size_t(wi) * K_;
                const double c = w * coef[i] * coef[q];
                for (std::size_t k = 0; k < K_; ++k)
                    rhs[k] -= c * wh_[k] * x[k];
            }
        }
    }
}

void recon_engine::add_priors_for_knot(long j) {
    const int wj = 2 * int(j - w0_);
    Rp_[std::size_t(wj) * n_ + wj] += w_ridge_;  // times the height weight
    Rg_[std::size_t(wj) * n_ + wj] += k_ridge;   // times the slope weight
    {
        // The curvature-jump prior at knot j-1: z'' continuous there, which
        // for cubic Hermite pieces reads
        //   m_{j-2} + 4 m_{j-1} + m_j - 3 (z_j - z_{j-2}) = 0   (mm).
        // Why: a slope measured as a secant over Delta-d is blind to a
        // spline whose knots all share one height and one slope m != 0 (a
        // wiggle repeating every knot interval when L = Delta-d); only the
        // heights, which carry the vibration, would pin it. The wiggle has a
        // curvature jump of 6m at every knot, while a smooth shape has
        // almost none (the condition is exact for cubics; 5e-4 of m off for
        // the 1800 mm reference wave), so the prior removes the one without
        // bending the other.
        const long knot[5] = {j - 2, j - 1, j, j, j - 2};
        const int unit[5] = {1, 1, 1, 0, 0};
        const double coef[5] = {1.0, 4.0, 1.0, -3.0, 3.0};
        add_rank1_prior(knot, unit, coef, 5, w_curv_jump_);
    }
    if (j - 1 >= w0_) {
        // Curvature of interval [j-1, j], both knots open.
        const int base = wj - 2;
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) {
                const std::size_t rc = std::size_t(base + a) * n_ + base + b;
                Rp_[rc] += w_curv_ * k_stiffness[a][b];                 // times the height weight
                Rg_[rc] += k_min_curvature_weight * k_stiffness[a][b];  // times the slope weight
            }
    } else if (j - 1 <= fixed_upto_ && j - 1 >= 0) {
        // Knot j-1 is a carried boundary condition: its part moves to the
        // right-hand side of every fiber.
        const double *left = hist_at(j - 1);
        for (int a = 0; a < 2; ++a) {
            for (int b = 0; b < 2; ++b) {
                const std::size_t rc = std::size_t(wj + a) * n_ + wj + b;
                Rp_[rc] += w_curv_ * k_stiffness[2 + a][2 + b];
                Rg_[rc] += k_min_curvature_weight * k_stiffness[2 + a][2 + b];
            }
            const double cz = k_stiffness[2 + a][0], cm = k_stiffness[2 + a][1];
            const double g = k_min_curvature_weight;
            double *rhs = rhs_.data() + std::size_t(wj + a) * K_;
            for (std::size_t k = 0; k < K_; ++k)
                rhs[k] -= (wh_[k] * w_curv_ + wg_[k] * g) * (cz * left[k] + cm * left[K_ + k]);
        }
    }
}

void recon_engine::pivot_floors() {
    double *floor = pivot_floor_.data();
    std::fill_n(floor, K_, 0.0);
    for (int j = 0; j < n_; ++j) {
        const double *d = work_.data() + tri(j, j) * K_;
        for (std::size_t k = 0; k < K_; ++k)
            floor[k] = std::max(floor[k], d[k]);  // NaN-free: entries are finite sums
    }
    for (std::size_t k = 0; k < K_; ++k)
        floor[k] = std::max(k_pivot_floor * floor[k], 1e-300);
}

// Eliminates the two unknowns of knot w0_ from W = schur + R - down, per fiber
// (one step of a banded Cholesky), keeps the factor for back-substitution,
// and shifts the window by one knot.
FLT_ROW_KERNEL void recon_engine::close_knot() {
    if (std::size_t(w0_ - next_emit_) >= factor_cap_)
        throw error(FLT_ERR_INTERNAL, "factor ring overflow");
    double *f = factor_.data() + (std::size_t(w0_) % factor_cap_) * nf_ * K_;
    double *il00 = f, *l10 = f + K_, *il11 = f + 2 * K_, *y0 = f + 3 * K_, *y1 = f + 4 * K_;
    double *L0 = f + 5 * K_;                     // [n-2][K]
    double *L1 = L0 + std::size_t(n_ - 2) * K_;  // [n-2][K]

    // work = schur + R - down (packed upper).
    for (int r = 0; r < n_; ++r)
        for (int c = r; c < n_; ++c) {
            assemble_entry(r, c);
        }

    const double *a00 = work_.data() + tri(0, 0) * K_;
    const double *a01 = work_.data() + tri(0, 1) * K_;
    const double *a11 = work_.data() + tri(1, 1) * K_;
    const double *b0 = rhs_.data(), *b1 = rhs_.data() + K_;
    pivot_floors();
    const double *floor = pivot_floor_.data();
    factor_pivots(K_, a00, a01, a11, b0, b1, floor, il00, l10, il11, y0, y1);
    for (int c = 2; c < n_; ++c)
        factor_column(K_, work_.data() + tri(0, c) * K_, work_.data() + tri(1, c) * K_, il00, l10,
                      il11, L0 + std::size_t(c - 2) * K_, L1 + std::size_t(c - 2) * K_);
    // New Schur complement, shifted by one knot; the new last knot starts
    // empty (its priors are added below).
    for (int r = 2; r < n_; ++r)
        for (int c = r; c < n_; ++c) {
            const double *wrc = work_.data() + tri(r, c) * K_;
            const double *l0r = L0 + std::size_t(r - 2) * K_, *l1r = L1 + std::size_t(r - 2) * K_;
            const double *l0c = L0 + std::size_t(c - 2) * K_, *l1c = L1 + std::size_t(c - 2) * K_;
            double *out = schur_.data() + tri(r - 2, c - 2) * K_;
            for (std::size_t k = 0; k < K_; ++k)
                out[k] = wrc[k] - l0r[k] * l0c[k] - l1r[k] * l1c[k];
        }
    for (int r = 0; r < n_; ++r)
        for (int c = std::max(r, n_ - 2); c < n_; ++c)
            std::fill_n(schur_.data() + tri(r, c) * K_, K_, 0.0);
    // Right-hand side, forward-eliminated and shifted.
    for (int c = 2; c < n_; ++c) {
        const double *bc = rhs_.data() + std::size_t(c) * K_;
        const double *l0 = L0 + std::size_t(c - 2) * K_, *l1 = L1 + std::size_t(c - 2) * K_;
        double *out = rhs_.data() + std::size_t(c - 2) * K_;
        for (std::size_t k = 0; k < K_; ++k)
            out[k] = bc[k] - l0[k] * y0[k] - l1[k] * y1[k];
    }
    std::fill_n(rhs_.data() + std::size_t(n_ - 2) * K_, 2 * K_, 0.0);

    clear_shared();
    apply_pending_weights();
    if (!bad_fibers_seen_) {
        // down_ is all zero: nothing to clear.
    } else {
        std::fill(down_.begin(), down_.end(), 0.0);
        bad_fibers_seen_ = false;
    }
    ++w0_;
    add_priors_for_knot(w0_ + S_ - 1);
}

void recon_engine::maybe_emit() {
    if (p_.lag_knots == recon_params::no_lag)
        return;
    if (strip_head_ && w0_ < p_.start_lag_knots)
        return;  // the head of the strip waits longer
    const long last = w0_ - 1 - p_.lag_knots;
    if (last - next_emit_ + 1 >= emit_group())
        emit_upto(last);
}

// Solves for every knot from next_emit_ to the end of the window given all
// rows so far, and emits knots up to `last`.
void recon_engine::emit_upto(long last) {
    strip_head_ = false;
    solve_all();
    last_emitted_ = last;
    next_emit_ = last + 1;
    finish_rows();
}

// Every knot from next_emit_ to the end of the window, given all rows so
// far, into hist_ (emitted or not: the states of knots not emitted yet are
// provisional, overwritten by the next solve).
FLT_ROW_KERNEL void recon_engine::solve_all() {
    keep_lazy_rows(w0_ + S_ - 1);  // the newest knot state it writes
    // 1. The open window: W x = rhs, per fiber, dense Cholesky W = U^T U
    //    on the packed upper triangle.
    for (int r = 0; r < n_; ++r)
        for (int c = r; c < n_; ++c) {
            assemble_entry(r, c);
        }
    pivot_floors();
    const double *floor = pivot_floor_.data();
    for (int j = 0; j < n_; ++j) {
        double *ujj = work_.data() + tri(j, j) * K_;
        for (int i = 0; i < j; ++i) {
            const double *uij = work_.data() + tri(i, j) * K_;
            for (std::size_t k = 0; k < K_; ++k)
                ujj[k] -= uij[k] * uij[k];
        }
        for (std::size_t k = 0; k < K_; ++k)
            ujj[k] = 1.0 / std::sqrt(std::max(ujj[k], floor[k]));  // keep 1/U_jj
        for (int c = j + 1; c < n_; ++c) {
            double *ujc = work_.data() + tri(j, c) * K_;
            for (int i = 0; i < j; ++i) {
                const double *uij = work_.data() + tri(i, j) * K_;
                const double *uic = work_.data() + tri(i, c) * K_;
                for (std::size_t k = 0; k < K_; ++k)
                    ujc[k] -= uij[k] * uic[k];
            }
            for (std::size_t k = 0; k < K_; ++k)
                ujc[k] *= ujj[k];
        }
    }
    // U^T y = rhs
    for (int j = 0; j < n_; ++j) {
        double *y = xwin_.data() + std::size_t(j) * K_;
        const double *b = rhs_.data() + std::size_t(j) * K_;
        std::copy_n(b, K_, y);
        for (int i = 0; i < j; ++i) {
            const double *uij = work_.data() + tri(i, j) * K_;
            const double *yi = xwin_.data() + std::size_t(i) * K_;
            for (std::size_t k = 0; k < K_; ++k)
                y[k] -= uij[k] * yi[k];
        }
        const double *inv = work_.data() + tri(j, j) * K_;
        for (std::size_t k = 0; k < K_; ++k)
            y[k] *= inv[k];
    }
    // U x = y
    for (int j = n_ - 1; j >= 0; --j) {
        double *x = xwin_.data() + std::size_t(j) * K_;
        for (int c = j + 1; c < n_; ++c) {
            const double *ujc = work_.data() + tri(j, c) * K_;
            const double *xc = xwin_.data() + std::size_t(c) * K_;
            for (std::size_t k = 0; k < K_; ++k)
                x[k] -= ujc[k] * xc[k];
        }
        const double *inv = work_.data() + tri(j, j) * K_;
        for (std::size_t k = 0; k < K_; ++k)
            x[k] *= inv[k];
    }
    for (int j = 0; j < S_; ++j) {
        double *h = hist_at(w0_ + j);
        std::copy_n(xwin_.data() + std::size_t(2 * j) * K_, 2 * K_, h);
    }

    // 2. Back-substitution through the eliminated knots, newest first.
    for (long j = w0_ - 1; j >= next_emit_; --j) {
        const double *f = factor_.data() + (std::size_t(j) % factor_cap_) * nf_ * K_;
        const double *il00 = f, *l10 = f + K_, *il11 = f + 2 * K_, *y0 = f + 3 * K_,
                     *y1 = f + 4 * K_;
        const double *L0 = f + 5 * K_;
        const double *L1 = L0 + std::size_t(n_ - 2) * K_;
        double *out = hist_at(j);
        double *xz = out, *xm = out + K_;
        if (n_ == 6) {
            const double *xa = hist_at(j + 1), *xb = hist_at(j + 2);
            back_substitute6(K_, il00, l10, il11, y0, y1, L0, L1, xa, xa + K_, xb, xb + K_, xz, xm);
            continue;
        }
        std::copy_n(y0, K_, xz);
        std::copy_n(y1, K_, xm);
        for (int c = 2; c < n_; ++c) {
            const long knot = j + c / 2;
            const double *xc = hist_at(knot) + std::size_t(c % 2) * K_;
            const double *l0 = L0 + std::size_t(c - 2) * K_, *l1 = L1 + std::size_t(c - 2) * K_;
            for (std::size_t k = 0; k < K_; ++k) {
                xz[k] -= l0[k] * xc[k];
                xm[k] -= l1[k] * xc[k];
            }
        }
        for (std::size_t k = 0; k < K_; ++k) {
            xm[k] *= il11[k];
            xz[k] = (xz[k] - l10[k] * xm[k]) * il00[k];
        }
    }
    solved_upto_ = w0_ + S_ - 1;
    solved_fresh_ = true;
}

// Evaluates every pending row whose knot interval is fully emitted.
void recon_engine::evaluate_into(double s, double *z, const double *c) const {
    const long i = interval_of(s);
    double w[4];
    basis(s, i, w);
    const double *a = hist_at(i), *b = hist_at(i + 1);
    if (c)
        evaluate_row_plus(K_, w, a, a + K_, b, b + K_, *c, z);
    else
        evaluate_row(K_, w, a, a + K_, b, b + K_, z);
}

void recon_engine::materialise_rows() {
    const std::size_t cap = p_.row_capacity;
    for (; evaluated_ < ready_; ++evaluated_) {
        const std::size_t r = evaluated_ % cap;
        evaluate_into(ring_s_[r], ring_z_ + r * K_, nullptr);
    }
}

void recon_engine::finish_rows() {
    if (!keep_rows_)
        return;
    const std::size_t cap = p_.row_capacity;
    while (ready_ < tail_) {
        const std::size_t r = ready_ % cap;
        const double s = ring_s_[r];
        const long i = interval_of(s);
        if (i + 1 > last_emitted_)
            break;
        const bool flagged = ring_any_invalid_[r] || no_height_fibers_ > 0;
        if (lazy_rows_ && !flagged && output_offset_ == 0.0) {
            ++ready_;  // pull() evaluates it (materialise_rows)
            continue;
        }
        materialise_rows();  // the rows before it, in order
        double *z = ring_z_ + r * K_;
        evaluate_into(s, z, output_offset_ != 0.0 ? &output_offset_ : nullptr);
        std::uint8_t *fl = ring_flags_ + r * K_;
        if (flagged) {
            if (ring_zero_flags_[r]) {
                std::memset(fl, 0, K_);
                ring_zero_flags_[r] = 0;
            }
            for (std::size_t k = 0; k < K_; ++k) {
                const double last = std::max(last_valid_s_[k], all_valid_s_);
                if ((fl[k] & FLT_FLAG_INVALID_INPUT) && last < s && last_s_ - last > p_.max_gap)
                    fl[k] |= FLT_FLAG_GAP;  // the run is still open and long
                if (!has_height_[k]) {
                    z[k] = std::numeric_limits<double>::quiet_NaN();
                    fl[k] |= FLT_FLAG_NO_DATA;
                }
            }
        }
        ++ready_;
        evaluated_ = ready_;
    }
}

// ---------------------------------------------------------------------------
// Rows
// ---------------------------------------------------------------------------

template <class HeightOk, class SlopeOk>
void recon_engine::finish_row(double s, std::size_t nbad, HeightOk h_ok, SlopeOk g_ok) {
    if (!keep_rows_) {
        last_s_ = s;
        ++rows_in_sheet_;
        solved_fresh_ = false;
        if (role_ == engine_role::solve)
            maybe_emit();
        return;
    }

    // The row joins the ring as pending. The API checks the room first; a
    // full ring here would overwrite a row nobody pulled yet.
    const std::size_t cap = p_.row_capacity;
    if (tail_ - head_ >= cap)
        throw error(FLT_ERR_INTERNAL, "row ring overflow");
    const std::size_t r = tail_ % cap;
    ring_s_[r] = s;
    std::uint8_t *fl = ring_flags_ + r * K_;
    bool any_invalid = false;
    if (nbad > 0 || !lazy_flags_) {
        std::memset(fl, 0, K_);
        if (nbad > 0)
            for (std::size_t k = 0; k < K_; ++k)
                if (!h_ok(k) && !g_ok(k)) {
                    fl[k] = FLT_FLAG_INVALID_INPUT;
                    any_invalid = true;
                }
    }
    ring_any_invalid_[r] = any_invalid;
    ring_zero_flags_[r] = lazy_flags_ && nbad == 0;

    // Gap and level bookkeeping. last valid position of fiber k is
    // max(last_valid_s_[k], all_valid_s_): a fully valid row only moves the
    // scalar.
    if (nbad == 0) {
        if (!(prev_row_all_valid_ && s - all_valid_s_ <= p_.max_gap))
            for (std::size_t k = 0; k < K_; ++k) {
                const double last = std::max(last_valid_s_[k], all_valid_s_);
                if (s - last > p_.max_gap)
                    mark_gap(k, last);
            }
        all_valid_s_ = s;
        prev_row_all_valid_ = true;
        if (no_height_fibers_ > 0) {
            std::fill(has_height_.begin(), has_height_.end(), 1);
            no_height_fibers_ = 0;
        }
    } else {
        for (std::size_t k = 0; k < K_; ++k) {
            const bool hok = h_ok(k);
            if (!(hok || g_ok(k)))
                continue;
            const double last = std::max(last_valid_s_[k], all_valid_s_);
            if (s - last > p_.max_gap)
                mark_gap(k, last);
            last_valid_s_[k] = s;
            if (hok && !has_height_[k]) {
                has_height_[k] = 1;
                --no_height_fibers_;
            }
        }
        prev_row_all_valid_ = false;
    }
    ++tail_;
    last_s_ = s;
    ++rows_in_sheet_;
    solved_fresh_ = false;

    if (role_ == engine_role::solve)
        maybe_emit();
    finish_rows();
}

void recon_engine::begin_strip(double s) {
    // A new strip: the knot grid starts at the first row's rear laser.
    materialise_rows();  // on the grid of the strip before
    have_t0_ = true;
    t0_ = s - 0.5 * D_;
    fixed_upto_ = -1;
    anchored_ = false;
    next_emit_ = 0;
    last_emitted_ = -1;
    strip_head_ = true;
    if (role_ == engine_role::solve)
        start_window(0);
    const double before = std::nextafter(s, -std::numeric_limits<double>::infinity());
    std::fill(last_valid_s_.begin(), last_valid_s_.end(), before);
    all_valid_s_ = before;
    prev_row_all_valid_ = false;
    std::fill(has_height_.begin(), has_height_.end(), 0);
    no_height_fibers_ = K_;
}

void recon_engine::row_coefficients(double s, long i1, double *ch, double *cg) const {
    const double p1 = s - 0.5 * D_, p2 = s + 0.5 * D_;
    const long i2 = std::min(interval_of(p2), i1 + S_ - 2);
    std::fill_n(ch, n_, 0.0);
    std::fill_n(cg, n_, 0.0);
    double b1[4], b2[4];
    basis(p1, i1, b1);
    basis(p2, i2, b2);
    const int o2 = 2 * int(i2 - i1);
    for (int a = 0; a < 4; ++a) {
        ch[a] += 0.5 * b1[a];
        cg[a] -= b1[a];
        ch[o2 + a] += 0.5 * b2[a];
        cg[o2 + a] += b2[a];
    }
}

void recon_engine::push_row(double s, const double *height, const double *slope,
                            const std::uint8_t *valid, const double *mult_h, const double *mult_g) {
    add_row(s, height, nullptr, slope, valid, mult_h, mult_g, nullptr, nullptr);
}

void recon_engine::push_row_relative(double s, const double *height, double level,
                                     const double *slope, const std::uint8_t *valid,
                                     const double *next_height, const double *next_slope) {
    add_row(s, height, &level, slope, valid, nullptr, nullptr, next_height, next_slope);
}

void recon_engine::add_row(double s, const double *height, const double *level, const double *slope,
                           const std::uint8_t *valid, const double *mult_h, const double *mult_g,
                           const double *next_height, const double *next_slope) {
    if (!have_t0_)
        begin_strip(s);
    // Heights given raw are made relative in a row of scratch, except in the
    // default geometry's common row below, which takes them relative as it
    // reads them.
    auto make_relative = [&] {
        if (level) {
            relative_row(K_, *level, height, rel_h_.data());
            height = rel_h_.data();
        }
    };
    if (role_ == engine_role::rows_only) {
        make_relative();
        // Only the bookkeeping: which samples are valid (as below).
        const double big = k_max_sample;
        auto ok_h = [&](std::size_t k) {
            return (valid == nullptr || valid[k] != 0) && std::fabs(height[k]) <= big;
        };
        auto ok_g = [&](std::size_t k) {
            return (valid == nullptr || valid[k] != 0) && std::fabs(slope[k]) <= big;
        };
        std::size_t nbad = 0;
        if (valid != nullptr || !row_is_finite(K_, 0.0, height, slope))
            for (std::size_t k = 0; k < K_; ++k)
                nbad += !(ok_h(k) && ok_g(k));
        finish_row(s, nbad, ok_h, ok_g);
        return;
    }

    const double p1 = s - 0.5 * D_;
    const long i1 = interval_of(p1);
    while (w0_ < i1) {
        close_knot();
        maybe_emit();
    }

    // Coefficients over the 2S unknowns of knots i1 .. i1+S-1.
    double ch[k_max_unknowns], cg[k_max_unknowns];
    row_coefficients(s, i1, ch, cg);
    // Knots before the window (off > 0) are carried boundary conditions.
    const int off = 2 * int(w0_ - i1);
    if (off > 0 && i1 + off / 2 - 1 > fixed_upto_)
        throw error(FLT_ERR_INTERNAL, "row touches an eliminated knot");

    // Masked measurements. The common row has every sample valid: this loop
    // vectorises and the bookkeeping below is O(1) for it.
    const double big = k_max_sample;
    auto h_ok = [&](std::size_t k) {
        return (valid == nullptr || valid[k] != 0) && std::fabs(height[k]) <= big;
    };
    auto g_ok = [&](std::size_t k) {
        return (valid == nullptr || valid[k] != 0) && std::fabs(slope[k]) <= big;
    };
    std::size_t nbad = 0;
    // The default geometry with a mask or multipliers: one fused pass; its
    // downdate weights are left in dh6, dg6 (affected6 fibers lose weight).
    bool fused6 = false;
    std::size_t affected6 = 0;
    double *dh6 = hv_.data(), *dg6 = gv_.data();
    // The common case (common6): the default geometry (knot spacing = laser
    // spacing, so a row spans three knots), no mask, every sample valid,
    // heights taken relative as they are read. Same arithmetic as the paths
    // after it, which read a relative copy.
    const double lvl = level ? *level : 0.0;
    const bool common6 = off == 0 && n_ == 6 && valid == nullptr && !mult_h && !mult_g &&
                         row_is_finite(K_, lvl, height, slope);
    if (!common6)
        make_relative();
    if (common6) {
        double *r = rhs_.data();
        accumulate_row6(K_, lvl, height, slope, D_, wh_.data(), wg_.data(), ch, cg, r, r + K_,
                        r + 2 * K_, r + 3 * K_, r + 4 * K_, r + 5 * K_, next_height, next_slope);
        add_row_geometry(ch, cg, 0);
    } else if (off == 0 && n_ == 6) {
        double *r = rhs_.data();
        std::size_t counts[2];
        const double *mh = mult_h ? mult_h : ones_.data(), *mg = mult_g ? mult_g : ones_.data();
        if (valid)
            weighted_row6_masked(K_, D_, height, slope, valid, mh, mg, wh_.data(), wg_.data(), ch,
                                 cg, r, r + K_, r + 2 * K_, r + 3 * K_, r + 4 * K_, r + 5 * K_, dh6,
                                 dg6, counts);
        else
            weighted_row6(K_, D_, height, slope, valid, mh, mg, wh_.data(), wg_.data(), ch, cg, r,
                          r + K_, r + 2 * K_, r + 3 * K_, r + 4 * K_, r + 5 * K_, dh6, dg6, counts);
        nbad = counts[0];
        affected6 = counts[1];
        fused6 = true;
        add_row_geometry(ch, cg, 0);
    } else {
        // Effective multipliers: 0 where the sample is invalid.
        double *hm = hm_.data(), *gm = gm_.data();
        if (valid == nullptr) {
            nbad = mask_row(K_, D_, height, slope, mult_h ? mult_h : ones_.data(),
                            mult_g ? mult_g : ones_.data(), hm, gm, hv_.data(), gv_.data());
        } else {
            for (std::size_t k = 0; k < K_; ++k) {
                const bool hok = h_ok(k), gok = g_ok(k);
                hm[k] = hok ? (mult_h ? mult_h[k] : 1.0) : 0.0;
                gm[k] = gok ? (mult_g ? mult_g[k] : 1.0) : 0.0;
                hv_[k] = hok ? height[k] : 0.0;
                gv_[k] = gok ? D_ * slope[k] : 0.0;
                nbad += !(hok && gok);
            }
        }
        // Knots before the window are carried boundary conditions (only
        // right after end_sheet): their part of the prediction moves to the
        // measurement, per fiber.
        for (int u = 0; u < off; ++u) {
            const double *x = hist_at(i1 + u / 2) + std::size_t(u % 2) * K_;
            const double chu = ch[u], cgu = cg[u];
            for (std::size_t k = 0; k < K_; ++k) {
                hv_[k] -= hm[k] != 0.0 ? chu * x[k] : 0.0;
                gv_[k] -= gm[k] != 0.0 ? cgu * x[k] : 0.0;
            }
        }
        weigh_row(K_, hm, gm, wh_.data(), wg_.data(), hv_.data(), gv_.data());
        for (int u = off; u < n_; ++u)
            add_row_rhs(K_, ch[u], cg[u], hv_.data(), gv_.data(),
                        rhs_.data() + std::size_t(u - off) * K_);
        add_row_geometry(ch, cg, off);
    }
    // Fibers whose sample is missing or down-weighted take (that part of)
    // its contribution back out of the shared matrices.
    bad_.clear();
    if (nbad > 0 || mult_h || mult_g) {
        // (the fast path above only runs with every multiplier 1)
        const int m = n_ - off;
        // The row's unknowns off..n-1 are window unknowns 0..m-1; their
        // packed entries in the n-wide window triangle:
        double chh[k_max_unknowns * (k_max_unknowns + 1) / 2];
        double cgg[k_max_unknowns * (k_max_unknowns + 1) / 2];
        std::size_t entry[k_max_unknowns * (k_max_unknowns + 1) / 2];
        int entries = 0;
        for (int u = 0; u < m; ++u)
            for (int v = u; v < m; ++v, ++entries) {
                chh[entries] = ch[off + u] * ch[off + v];
                cgg[entries] = cg[off + u] * cg[off + v];
                entry[entries] = tri(u, v);
            }
        // How much of each fiber's sample comes back out: dh, dg (0 for a
        // full-weight sample). Many affected fibers (robust reweighting):
        // one dense, vectorised pass; few (an occasional dropout): per fiber.
        double *dh = hv_.data(), *dg = gv_.data();  // the rhs is done with them
        const std::size_t affected =
            fused6 ? affected6
                   : downdate_weights(K_, hm_.data(), gm_.data(), wh_.data(), wg_.data(), dh, dg);
        if (affected * 8 > K_) {
            for (int e = 0; e < entries; ++e)
                downdate_entry(K_, chh[e], cgg[e], dh, dg, down_.data() + entry[e] * K_);
            bad_.push_back(-1);  // marks "some fiber": only emptiness is read
        } else if (affected > 0) {
            for (std::size_t k = 0; k < K_; ++k) {
                if (dh[k] == 0.0 && dg[k] == 0.0)
                    continue;
                bad_.push_back(int(k));
                for (int e = 0; e < entries; ++e)
                    down_[entry[e] * K_ + k] += dh[k] * chh[e] + dg[k] * cgg[e];
            }
        }
        if (!bad_.empty())
            bad_fibers_seen_ = true;
    }

    finish_row(s, nbad, h_ok, g_ok);
}

// A run of invalid samples of fiber k after `from` has just closed and is
// longer than max_gap: flags its rows that are still in the ring.
void recon_engine::mark_gap(std::size_t k, double from) {
    const std::size_t cap = p_.row_capacity;
    for (std::size_t i = tail_; i > head_; --i) {
        const std::size_t r = (i - 1) % cap;
        if (ring_s_[r] <= from)
            break;
        if (ring_zero_flags_[r])
            continue;  // no invalid sample in that row
        std::uint8_t &f = ring_flags_[r * K_ + k];
        if (f & FLT_FLAG_INVALID_INPUT)
            f |= FLT_FLAG_GAP;
    }
}

std::size_t recon_engine::pull(std::size_t max_rows, double *s_out, double *z_out,
                               std::uint8_t *flags_out, const double *add) {
    const std::size_t cap = p_.row_capacity;
    const std::size_t n = std::min(max_rows, ready_ - head_);
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t r = (head_ + i) % cap;
        s_out[i] = ring_s_[r];
        if (head_ + i >= evaluated_)
            evaluate_into(ring_s_[r], z_out + i * K_, add);  // the bits of evaluating, adding
        else if (add)
            add_constant(K_, ring_z_ + r * K_, *add, z_out + i * K_);
        else
            std::copy_n(ring_z_ + r * K_, K_, z_out + i * K_);
        if (flags_out && ring_zero_flags_[r])
            std::memset(flags_out + i * K_, 0, K_);
        else if (flags_out)
            std::copy_n(ring_flags_ + r * K_, K_, flags_out + i * K_);
    }
    head_ += n;
    evaluated_ = std::max(evaluated_, head_);
    return n;
}

void recon_engine::end_sheet() {
    if (role_ != engine_role::solve)
        throw error(FLT_ERR_INTERNAL, "end_sheet() on an engine that does not solve");
    const long e_end = interval_of(last_s_) + 1;
    emit_upto(e_end);
    end_sheet_common(e_end);
}

// Carry-over: knots up to e_end are now hard boundary conditions, with the
// states in hist_.
void recon_engine::end_sheet_common(long e_end) {
    strip_head_ = false;
    fixed_upto_ = e_end;
    anchored_ = true;
    bc_s_ = knot_pos(e_end);
    const double *h = hist_at(e_end);
    std::copy_n(h, K_, bc_z_.data());
    std::copy_n(h + K_, K_, bc_m_.data());
    rows_in_sheet_ = 0;
    last_emitted_ = std::max(last_emitted_, e_end);
    next_emit_ = e_end + 1;
    if (role_ == engine_role::solve) {
        bad_fibers_seen_ = false;
        start_window(e_end + 1);
    }
}

void recon_engine::reset() {
    have_t0_ = false;
    head_ = ready_ = tail_ = evaluated_ = 0;
    rows_in_sheet_ = 0;
    fixed_upto_ = -1;
    anchored_ = false;
}

bool recon_engine::predict(double s, double *height_out, double *dslope_out) const {
    if (!have_t0_)
        return false;
    const double p1 = s - 0.5 * D_, p2 = s + 0.5 * D_;
    const long i1 = interval_of(p1);
    const long i2 = std::min(interval_of(p2), i1 + S_ - 2);
    const long needed = i2 + 1;
    if (needed > last_emitted_ && !(solved_fresh_ && needed <= solved_upto_))
        return false;
    if (i1 <= w0_ + S_ - 1 - long(hist_cap_))
        return false;  // overwritten in the ring
    double b1[4], b2[4];
    basis(p1, i1, b1);
    basis(p2, i2, b2);
    predict_row(K_, b1, b2, hist_at(i1), hist_at(i1 + 1), hist_at(i2), hist_at(i2 + 1), height_out,
                dslope_out);
    return true;
}

bool recon_engine::prediction_lost(double s) const {
    return have_t0_ && interval_of(s - 0.5 * D_) <= w0_ + S_ - 1 - long(hist_cap_);
}

void recon_engine::save_solution(double *out, double *t0_out) const {
    std::copy(hist_.begin(), hist_.end(), out);
    *t0_out = t0_;
}

void recon_engine::predict_saved(const double *saved, double saved_t0, double s, double *height_out,
                                 double *dslope_out) const {
    // The saved sheet's knot grid: the same as predict() on it, without the
    // checks (every knot under a row of that sheet was solved at its end).
    const double p1 = s - 0.5 * D_, p2 = s + 0.5 * D_;
    const long i1 = interval_on(saved_t0, p1);
    const long i2 = std::min(interval_on(saved_t0, p2), i1 + S_ - 2);
    if (i1 < 0)
        throw error(FLT_ERR_INTERNAL, "predict_saved before the saved sheet");
    double b1[4], b2[4];
    basis_on(saved_t0, p1, i1, b1);
    basis_on(saved_t0, p2, i2, b2);
    auto at = [&](long j) {
        return saved + (std::size_t(j) % hist_cap_) * 2 * K_;
    };
    predict_row(K_, b1, b2, at(i1), at(i1 + 1), at(i2), at(i2 + 1), height_out, dslope_out);
}

void recon_engine::set_keep_rows(bool keep) {
    if (have_t0_ || (keep && !has_row_ring_))
        throw error(FLT_ERR_INTERNAL, "set_keep_rows needs a reset engine with a row ring");
    keep_rows_ = keep;
}

void recon_engine::rebind_rows(double *z_store, std::uint8_t *flags_store) {
    if (!z_store || (!flags_store && own_flags_.empty()))
        throw error(FLT_ERR_INTERNAL, "rebind_rows needs row storage");
    reset();  // the rows held were the previous storage's
    ring_z_ = z_store;
    lazy_rows_ = false;
    ring_flags_ = flags_store ? flags_store : own_flags_.data();
    lazy_flags_ = flags_store == nullptr;
}

void recon_engine::boundary(double *s_out, double *height_out, double *slope_out) const {
    if (s_out)
        *s_out = bc_s_;
    if (height_out)
        std::copy_n(bc_z_.data(), K_, height_out);
    if (slope_out)
        for (std::size_t k = 0; k < K_; ++k)
            slope_out[k] = bc_m_[k] / L_;
}

// ---------------------------------------------------------------------------
// Provisional values
// ---------------------------------------------------------------------------

std::size_t recon_engine::peek(std::size_t offset, std::size_t max_rows, double *s_out,
                               double *z_out, std::uint8_t *flags_out) {
    if (!keep_rows_ || !have_t0_)
        return 0;
    const std::size_t held = tail_ - head_;
    if (offset >= held)
        return 0;
    const std::size_t n = std::min(max_rows, held - offset);
    bool solved = role_ != engine_role::solve;
    const std::size_t cap = p_.row_capacity;
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t at = head_ + offset + i, r = at % cap;
        const double s = ring_s_[r];
        s_out[i] = s;
        double *z = z_out + i * K_;
        std::uint8_t *fl = flags_out ? flags_out + i * K_ : nullptr;
        if (at < ready_) {  // finished: as pull() will give it
            if (at >= evaluated_)
                evaluate_into(s, z, nullptr);
            else
                std::copy_n(ring_z_ + r * K_, K_, z);
            if (fl && ring_zero_flags_[r])
                std::memset(fl, 0, K_);
            else if (fl)
                std::copy_n(ring_flags_ + r * K_, K_, fl);
            continue;
        }
        if (!solved) {
            solve_all();
            solved = true;
        }
        const long iv = interval_of(s);
        double w[4];
        basis(s, iv, w);
        const double *a = hist_at(iv), *b = hist_at(iv + 1);
        if (output_offset_ != 0.0)
            evaluate_row_plus(K_, w, a, a + K_, b, b + K_, output_offset_, z);
        else
            evaluate_row(K_, w, a, a + K_, b, b + K_, z);
        // The flags as finish_rows() would set them now.
        const std::uint8_t *own = ring_flags_ + r * K_;
        const bool zero = ring_zero_flags_[r] != 0;
        for (std::size_t k = 0; k < K_; ++k) {
            std::uint8_t f = zero ? std::uint8_t(0) : own[k];
            const double last = std::max(last_valid_s_[k], all_valid_s_);
            if ((f & FLT_FLAG_INVALID_INPUT) && last < s && last_s_ - last > p_.max_gap)
                f |= FLT_FLAG_GAP;
            if (!has_height_[k]) {
                z[k] = std::numeric_limits<double>::quiet_NaN();
                f |= FLT_FLAG_NO_DATA;
            }
            if (fl)
                fl[k] = f;
        }
    }
    return n;
}

// ---------------------------------------------------------------------------
// rows_only role and robust_window's frozen part
// ---------------------------------------------------------------------------

void recon_engine::set_knot_state(long j, const double *z, const double *m, std::size_t k0,
                                  std::size_t k1) {
    keep_lazy_rows(j);
    double *h = hist_at(j);
    std::copy(z + k0, z + k1, h + k0);
    std::copy(m + k0, m + k1, h + K_ + k0);
}

void recon_engine::mark_emitted(long last) {
    if (last < next_emit_)
        return;
    last_emitted_ = last;
    next_emit_ = last + 1;
    finish_rows();
}

void recon_engine::carry_over(long e_end) {
    end_sheet_common(e_end);
}

void recon_engine::start_strip(double s) {
    if (!have_t0_)
        begin_strip(s);
}

void recon_engine::forget_upto(long last) {
    next_emit_ = std::max(next_emit_, std::min(last + 1, w0_));
}

const double *recon_engine::open_window_matrix() {
    for (int r = 0; r < n_; ++r)
        for (int c = r; c < n_; ++c)
            assemble_entry(r, c);
    return work_.data();
}

void recon_engine::add_block(long i1, const double *gh, const double *gg, const double *rh,
                             const double *rg, const double *dh, const double *dg) {
    if (!have_t0_)
        throw error(FLT_ERR_INTERNAL, "add_block before the strip started");
    while (w0_ < i1)
        close_knot();
    // The block's unknowns off..n-1 are window unknowns 0..n-1-off; its
    // knots before the window are carried boundary conditions.
    const int off = 2 * int(w0_ - i1);
    if (off > 0 && i1 + off / 2 - 1 > fixed_upto_)
        throw error(FLT_ERR_INTERNAL, "block touches an eliminated knot");
    const int m = n_ - off;
    for (int u = 0; u < m; ++u)
        for (int v = 0; v < m; ++v) {
            const std::size_t at = std::size_t(u) * n_ + v;
            const std::size_t from = std::size_t(u + off) * n_ + (v + off);
            Rh_[at] += gh[from];
            Rg_[at] += gg[from];
        }
    const std::size_t ntri = std::size_t(n_) * (n_ + 1) / 2;
    // Packed index of (u, v), u <= v, in an n x n triangle (as tri()).
    auto packed = [&](int u, int v) {
        if (u > v)
            std::swap(u, v);
        return std::size_t(u) * n_ - std::size_t(u) * (u - 1) / 2 + std::size_t(v - u);
    };
    for (int u = 0; u < m; ++u) {
        const double *bh = rh + std::size_t(u + off) * K_, *bg = rg + std::size_t(u + off) * K_;
        double *r = rhs_.data() + std::size_t(u) * K_;
        for (std::size_t k = 0; k < K_; ++k)
            r[k] += wh_[k] * bh[k] + wg_[k] * bg[k];
        // The carried knots' part moves to the right-hand side, per fiber.
        for (int q = 0; q < off; ++q) {
            const double *x = hist_at(i1 + q / 2) + std::size_t(q % 2) * K_;
            const std::size_t at = std::size_t(u + off) * n_ + q;
            const std::size_t e = packed(u + off, q);
            for (std::size_t k = 0; k < K_; ++k) {
                double a = wh_[k] * gh[at] + wg_[k] * gg[at];
                if (dh)
                    a -= wh_[k] * dh[e * K_ + k] + wg_[k] * dg[e * K_ + k];
                r[k] -= a * x[k];
            }
        }
    }
    if (dh) {
        for (int u = 0; u < m; ++u)
            for (int v = u; v < m; ++v) {
                const std::size_t e = packed(u + off, v + off);
                const double *a = dh + e * K_, *b = dg + e * K_;
                double *d = down_.data() + tri(u, v) * K_;
                for (std::size_t k = 0; k < K_; ++k)
                    d[k] += wh_[k] * a[k] + wg_[k] * b[k];
            }
        bad_fibers_seen_ = true;
    }
    (void)ntri;
}

int recon_engine::knot_priors(long j, prior_term *out) const {
    // The same terms as add_priors_for_knot(j), which the engine itself uses.
    int count = 0;
    {
        prior_term &t = out[count++];  // ridge, relative to a height sample
        t.count = 1;
        t.knot[0] = j;
        t.unit[0] = 0;
        t.m[0][0] = w_ridge_;
        t.slope_weighted = false;
        prior_term &g = out[count++];  // and to a slope sample
        g = t;
        g.m[0][0] = k_ridge;
        g.slope_weighted = true;
    }
    if (j - 2 >= 0) {
        prior_term &t = out[count++];  // curvature jump at j - 1
        const long knot[5] = {j - 2, j - 1, j, j, j - 2};
        const int unit[5] = {1, 1, 1, 0, 0};
        const double coef[5] = {1.0, 4.0, 1.0, -3.0, 3.0};
        t.count = 5;
        for (int a = 0; a < 5; ++a) {
            t.knot[a] = knot[a];
            t.unit[a] = unit[a];
            for (int b = 0; b < 5; ++b)
                t.m[a][b] = w_curv_jump_ * coef[a] * coef[b];
        }
        t.slope_weighted = false;
    }
    if (j - 1 >= 0) {
        prior_term &t = out[count++];  // curvature of [j - 1, j]
        t.count = 4;
        const long knot[4] = {j - 1, j - 1, j, j};
        const int unit[4] = {0, 1, 0, 1};
        for (int a = 0; a < 4; ++a) {
            t.knot[a] = knot[a];
            t.unit[a] = unit[a];
            for (int b = 0; b < 4; ++b)
                t.m[a][b] = w_curv_ * k_stiffness[a][b];
        }
        t.slope_weighted = false;
        prior_term &g = out[count++];
        g = t;
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b)
                g.m[a][b] = k_min_curvature_weight * k_stiffness[a][b];
        g.slope_weighted = true;
    }
    return count;
}

double recon_engine::max_weight_ratio() {
    return k_max_weight_ratio;
}

double recon_engine::pivot_floor() {
    return k_pivot_floor;
}

}  // namespace flt
