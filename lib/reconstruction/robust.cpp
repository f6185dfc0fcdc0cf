// SPDX-License-Identifier: Apache-2.0
#include "reconstruction/robust.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/cpu_dispatch.hpp"
#include "core/error.hpp"
#include "reconstruction/window.hpp"

namespace flt {
namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();
// For Gaussian x: E[min(|x|, 3 sigma)] = sigma (sqrt(2/pi)(1 - e^-4.5)
// + 6 Q(3)) = 0.79713 sigma, so sigma = 1.25450 times the clipped mean.
constexpr double k_clip = 3.0;
constexpr double k_clipped_to_sigma = 1.2545;
// The classic 95%-efficiency tuning constants, in units of the scale.
constexpr double k_huber = 1.345;
constexpr double k_tukey = 4.685;
// A block median needs a few values to mean anything.
constexpr std::size_t k_min_block_values = 5;
// Scales are floored at this fraction of the option's noise level: on exact
// data the residuals are the spline's own approximation error, which is not
// noise and must not be reweighted (nor may weights overflow).
constexpr double k_min_sigma_fraction = 1e-3;

// The per-row kernels, built for baseline x86-64 and for AVX2; each call
// takes the AVX2 build where the CPU has it (core/cpu_dispatch.hpp).
#define FLT_KERNELS_FILE "reconstruction/robust_kernels.inc"
#include "core/cpu_dispatch_build.inc"
// The weigh kernels of the build this CPU runs, [tukey][masked][lined][slopes].
using weigh_table = base::weigh_kernel const[2][2][2][2];
const weigh_table &weigh_kernels() {
#if FLT_HAVE_AVX2_BUILD
    if (cpu_has_avx2())
        return avx2::k_weigh;
#endif
    return base::k_weigh;
}
FLT_DISPATCH(close_block)
FLT_DISPATCH(median9)

}  // namespace

// ---------------------------------------------------------------------------

robust_scale::robust_scale(std::size_t fibers, std::size_t block_rows, std::size_t blocks,
                           double initial_sigma)
    : K_(fibers), block_rows_(block_rows), blocks_(blocks), initial_(initial_sigma) {
    sum_.assign(K_, 0.0);
    count_.assign(K_, 0.0);
    estimates_.assign(blocks_ * K_, k_nan);
    sigma_.assign(K_, initial_);
    inv_var_.assign(K_, 1.0 / (initial_ * initial_));
    incomplete_.assign(K_, 0.0);
}

void robust_scale::reset() {
    std::fill(sum_.begin(), sum_.end(), 0.0);
    std::fill(count_.begin(), count_.end(), 0.0);
    std::fill(estimates_.begin(), estimates_.end(), k_nan);
    std::fill(sigma_.begin(), sigma_.end(), initial_);
    std::fill(inv_var_.begin(), inv_var_.end(), 1.0 / (initial_ * initial_));
    rows_ = 0;
    next_ = 0;
    filled_ = 0;
}

// The median of fiber k's finite block values, when it has any.
void robust_scale::median_scalar(std::size_t k) {
    double ring[64];
    std::size_t m = 0;
    for (std::size_t b = 0; b < blocks_ && m < 64; ++b) {
        const double v = estimates_[b * K_ + k];
        if (std::isfinite(v))
            ring[m++] = v;
    }
    if (m == 0)
        return;
    std::nth_element(ring, ring + m / 2, ring + m);
    sigma_[k] = std::max(k_min_sigma_fraction * initial_, ring[m / 2]);
}

bool robust_scale::end_row() {
    if (++rows_ < block_rows_)
        return false;
    rows_ = 0;
    close_block(K_, sum_.data(), count_.data(), estimates_.data() + next_ * K_);
    next_ = (next_ + 1) % blocks_;
    if (filled_ < blocks_)
        ++filled_;
    if (blocks_ == 9) {
        // The common case, vectorised. Until nine blocks are in (they fill
        // slots 0, 1, ... in order), the empty slots hold -inf and +inf so
        // that the median of nine is the median of the blocks in: with f
        // blocks, 4 - f/2 below them puts element f/2 of theirs in the
        // middle, as median_scalar picks. Fibers with an empty block (too
        // few valid samples) take the general path.
        if (filled_ < 9) {
            const std::size_t below = 4 - filled_ / 2;
            const double inf = std::numeric_limits<double>::infinity();
            for (std::size_t b = filled_; b < 9; ++b)
                std::fill_n(estimates_.data() + b * K_, K_, b < filled_ + below ? -inf : inf);
        }
        median9(K_, estimates_.data(), k_min_sigma_fraction * initial_, sigma_.data(),
                incomplete_.data());
        for (std::size_t k = 0; k < K_; ++k)
            if (incomplete_[k] != 0.0)
                median_scalar(k);
    } else {
        for (std::size_t k = 0; k < K_; ++k)
            median_scalar(k);
    }
    for (std::size_t k = 0; k < K_; ++k)
        inv_var_[k] = 1.0 / (sigma_[k] * sigma_[k]);
    return true;
}

// ---------------------------------------------------------------------------

void robust_scale::weights(const robust_scale &h, const robust_scale &g, double max_ratio,
                           double *wh, double *wg) {
    const double *ih = h.inv_var(), *ig = g.inv_var();
    for (std::size_t k = 0; k < h.K_; ++k) {
        wh[k] = ih[k];
        wg[k] = std::min(ig[k], max_ratio * ih[k]);
    }
}

void robust_weigh_row(robust_kind kind, std::size_t K, double D, const double *h, const double *g,
                      const std::uint8_t *valid, const double *line, const double *pred_h,
                      const double *pred_g, robust_scale &hs, robust_scale &gs, bool feed,
                      double *sink_sum, double *sink_count, double *out_h, double *out_g,
                      double *mult_h, double *mult_g) {
    static const double no_line[5] = {0, 0, 0, 0, 0};
    if (!line)
        line = no_line;
    // From the scales before this row; its residuals then join the current
    // block (or the sink).
    const int tukey = kind == robust_kind::tukey, masked = valid != nullptr;
    const int lined = line[0] != 0 || line[1] != 0 || line[2] != 0 || line[3] != 0;
    const bool gross_h = weigh_kernels()[tukey][masked][lined][0](
        K, 1.0, 1.0, h, valid, line[0], line[1], line[4], pred_h, hs.sigma(), hs.inv_var(),
        feed ? hs.sum() : sink_sum, feed ? hs.count() : sink_count, out_h, mult_h);
    const bool gross_g = weigh_kernels()[tukey][masked][lined][1](
        K, D, 1.0 / D, g, valid, line[2], line[3], line[4], pred_g, gs.sigma(), gs.inv_var(),
        feed ? gs.sum() : sink_sum, feed ? gs.count() : sink_count, out_g, mult_g);
    // Gross Huber samples keep their value and take the weight c / |r|.
    auto gross_weights = [&](const double *value, double a, double b, double scale_d,
                             const double *pred, const double *sigma, double *mult) {
        for (std::size_t k = 0; k < K; ++k) {
            if (mult[k] >= 0.0)
                continue;
            const double x = double(std::int32_t(k)) - line[4];
            const double r = scale_d * (value[k] - (a + b * x)) - pred[k];
            mult[k] = k_huber * sigma[k] / std::fabs(r);
        }
    };
    if (gross_h)
        gross_weights(h, line[0], line[1], 1.0, pred_h, hs.sigma(), mult_h);
    if (gross_g)
        gross_weights(g, line[2], line[3], D, pred_g, gs.sigma(), mult_g);
}

// ---------------------------------------------------------------------------

double recon_chain::bytes_needed(std::size_t fibers, const recon_params &params,
                                 const robust_params &robust, std::size_t knot_capacity,
                                 bool owns_rows, bool batch) {
    // The same sizes as the constructor below.
    const bool robust_on = robust.kind != robust_kind::none;
    const double K = double(fibers);
    if (!batch && robust_on)
        return robust_window::bytes_needed(fibers, params, robust);
    const double engine =
        recon_engine::bytes_needed(fibers, params, knot_capacity, owns_rows, true);
    if (!batch || !robust_on)
        return engine;
    // Batch passes: the running scales (a ring of blocks, a few more per
    // fiber), the per-fiber residual scratch, the previous pass's knots.
    const double scales = 8 * K * (2 * double(robust.scale_blocks) + 16);
    return engine + 8 * K * 2 * (double(knot_capacity) + 200) + scales;
}

recon_chain::recon_chain(std::size_t fibers, const recon_params &params,
                         const robust_params &robust, std::size_t knot_capacity, double *z_store,
                         std::uint8_t *flags_store, bool batch)
    : K_(fibers), robust_(robust), D_(params.laser_spacing), batch_(batch) {
    const bool robust_on = robust_.kind != robust_kind::none;
    if (!batch_ && robust_on) {
        window_ = std::make_unique<robust_window>(K_, params, robust_, z_store, flags_store);
        return;
    }
    engine_ = std::make_unique<recon_engine>(K_, params, knot_capacity, z_store, flags_store, true);
    if (!batch_ || !robust_on)
        return;
    // Batch passes: one engine for every pass, and one pair of running
    // scales.
    for (auto *v : {&pred_h_, &pred_g_, &out_h_, &out_g_, &mult_h_, &mult_g_})
        v->assign(K_, 0.0);
    saved_.assign(engine_->solution_size(), 0.0);
    initial_wh_.assign(K_, engine_->default_height_weight());
    initial_wg_.assign(K_, engine_->default_slope_weight());
    h_scale_ = std::make_unique<robust_scale>(K_, robust_.block_rows, robust_.scale_blocks,
                                              params.height_sigma);
    g_scale_ = std::make_unique<robust_scale>(K_, robust_.block_rows, robust_.scale_blocks,
                                              D_ * params.slope_sigma);
}

recon_chain::~recon_chain() = default;

long recon_chain::latency_knots() const {
    if (window_)
        return window_->latency_knots();
    const recon_params &p = engine_->params();
    if (p.lag_knots == recon_params::no_lag)
        return recon_params::no_lag;
    return p.latency_knots() + engine_->knots_per_row() - 2;
}

std::size_t recon_chain::free_rows() const {
    return window_ ? window_->free_rows() : engine_->free_rows();
}
std::size_t recon_chain::ready_rows() const {
    return window_ ? window_->ready_rows() : engine_->ready_rows();
}
bool recon_chain::has_last_s() const {
    return window_ ? window_->has_last_s() : engine_->has_last_s();
}
double recon_chain::last_s() const {
    return window_ ? window_->last_s() : engine_->last_s();
}
bool recon_chain::rows_since_sheet() const {
    return window_ ? window_->rows_since_sheet() : engine_->rows_since_sheet();
}
bool recon_chain::pushed_since_reset() const {
    return window_ ? window_->pushed_since_reset() : engine_->pushed_since_reset();
}
bool recon_chain::has_boundary() const {
    return window_ ? window_->has_boundary() : engine_->has_boundary();
}

void recon_chain::push_row(double s, const double *height, const double *slope,
                           const std::uint8_t *valid) {
    if (window_)
        window_->push_row(s, height, slope, valid);
    else
        engine_->push_row(s, height, slope, valid);
}

void recon_chain::push_row_relative(double s, const double *height, double level,
                                    const double *slope, const std::uint8_t *valid) {
    if (window_)
        throw error(FLT_ERR_INTERNAL, "raw rows pushed into a robust window");
    engine_->push_row_relative(s, height, level, slope, valid);
}

std::size_t recon_chain::pull(std::size_t max_rows, double *s_out, double *z_out,
                              std::uint8_t *flags_out, const double *add) {
    return window_ ? window_->pull(max_rows, s_out, z_out, flags_out, add)
                   : engine_->pull(max_rows, s_out, z_out, flags_out, add);
}

std::size_t recon_chain::peek(std::size_t offset, std::size_t max_rows, double *s_out,
                              double *z_out, std::uint8_t *flags_out) {
    return window_ ? window_->peek(offset, max_rows, s_out, z_out, flags_out)
                   : engine_->peek(offset, max_rows, s_out, z_out, flags_out);
}

void recon_chain::end_sheet() {
    if (window_)
        window_->end_sheet();
    else
        engine_->end_sheet();
}

void recon_chain::reset() {
    if (window_)
        window_->reset();
    else
        engine_->reset();
}

void recon_chain::boundary(double *s_out, double *height_out, double *slope_out) const {
    if (window_)
        window_->boundary(s_out, height_out, slope_out);
    else
        engine_->boundary(s_out, height_out, slope_out);
}

void recon_chain::reweigh(recon_engine &next, const double *h, const double *g,
                          const std::uint8_t *valid, const double *line) {
    robust_scale &hs = *h_scale_, &gs = *g_scale_;
    robust_weigh_row(robust_.kind, K_, D_, h, g, valid, line, pred_h_.data(), pred_g_.data(), hs,
                     gs, true, nullptr, nullptr, out_h_.data(), out_g_.data(), mult_h_.data(),
                     mult_g_.data());
    const bool new_h = hs.end_row();
    const bool new_g = gs.end_row();
    // A completed block sets the fibers' weights, 1 / sigma^2.
    if (new_h || new_g)
        next.set_fiber_weights(hs.inv_var(), gs.inv_var());
}

void recon_chain::batch(std::size_t rows, const double *s, row_source &source) {
    if (!batch_)
        throw error(FLT_ERR_INTERNAL, "batch() on a streaming chain");
    recon_engine &e = *engine_;
    const int passes = robust_.kind == robust_kind::none ? 1 : 1 + robust_.iterations;
    double saved_t0 = 0.0;
    double level = 0.0;
    const bool raw = source.raw_first_pass(&level);
    for (int pass = 0; pass < passes; ++pass) {
        // Every pass starts a strip; the first one too, as a workspace may
        // have served an earlier sheet (recon_api.cpp).
        if (pass > 0)
            e.save_solution(saved_.data(), &saved_t0);
        e.reset();
        if (passes > 1) {
            h_scale_->reset();
            g_scale_->reset();
            e.set_fiber_weights(initial_wh_.data(), initial_wg_.data());
        }
        // Only the last pass's rows are wanted.
        e.set_keep_rows(pass + 1 == passes);
        for (std::size_t r = 0; r < rows; ++r) {
            const double *h, *g;
            const std::uint8_t *valid;
            double line[5] = {0, 0, 0, 0, 0};
            source.row(pass, r, &h, &g, &valid, line);
            if (pass == 0) {
                if (line[0] != 0 || line[1] != 0 || line[2] != 0 || line[3] != 0)
                    throw error(FLT_ERR_INTERNAL, "a first pass's row must come without a line");
                if (raw) {
                    const double *next_h, *next_g;
                    source.raw_row_ahead(r + 1, &next_h, &next_g);
                    e.push_row_relative(s[r], h, level, g, valid, next_h, next_g);
                } else
                    e.push_row(s[r], h, g, valid);
                continue;
            }
            e.predict_saved(saved_.data(), saved_t0, s[r], pred_h_.data(), pred_g_.data());
            reweigh(e, h, g, valid, line);
            e.push_row(s[r], out_h_.data(), out_g_.data(), valid, mult_h_.data(), mult_g_.data());
        }
        e.end_sheet();
    }
}

}  // namespace flt
