// SPDX-License-Identifier: Apache-2.0
#include "reconstruction/robust.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

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

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#  define FLT_ROBUST_KERNEL __attribute__((target_clones("avx2", "default")))
#else
#  define FLT_ROBUST_KERNEL
#endif

// The per-sample work of a reweighted stage, one pass over the row.
//
// Each sample's residual r against the previous stage's prediction (height,
// mm, and Delta-d * slope, mm) adds its clipped magnitude to the running
// scale's block sums, and decides how the sample enters the stage. Huber's
// estimate solves sum psi(r_i) x_i = 0 with psi(r) = r clipped at
// c = k_huber * scale; a reweighted stage heads for it in one of two ways
// per sample:
//   - a moderate residual (up to k_gross scales) becomes a
//     pseudo-observation, prediction + psi(r), at full weight: the window
//     matrix does not change, so the sample costs what a plain one does;
//   - a gross residual keeps its value and takes the weight psi(r) / r =
//     c / |r|: only those samples need their share of the window matrix
//     taken back out (engine.cpp's downdate), and they are few except at a
//     shear cut.
// Pseudo-observations alone converge too slowly for a burst of gross
// outliers (the shear station's ringing is a thousand scales tall and
// covers its own window: 1.7 mm left after three stages), weights alone
// cost a downdate for one sample in three on clean data (40% more time);
// together each does what it is good at, and both lead to the same
// estimate. Tukey's biweight takes weights on every sample (plain IRLS):
// its objective is not convex, and its pseudo-observations let a shifted
// level persist between shear cuts. Invalid samples (not finite, or masked
// out by valid when given; the robust window stores them as NaN) get
// multiplier 0.
// Every pointer is a restrict parameter: GCC vectorises across fibers only
// when it need not check the arrays for overlap.
constexpr double k_gross = 4.0;

// One measurement kind of one row (heights: scale 1; slopes: the residual
// is in Delta-d * slope, scale D), fibers 0..K-1. value[k] carries the line
// a + b * (k - centre), taken off as it is read (rigid_motion; 0 else).
// Writes out[k] (the value the stage takes, in value's unit) and mult[k]
// (the weight multiplier; -1 marks a gross Huber sample, whose weight the
// caller computes: one division per gross sample instead of one per
// sample). Returns whether there is any gross Huber sample. Branch-free and
// without divisions (1/sigma^2 is kept with the scale), so that it
// vectorises; one kind per loop keeps the loop's values in registers.
#define FLT_WEIGH_KIND_PARAMS                                                             \
  std::size_t K, double scale, double inv_scale, const double *__restrict value,          \
      const std::uint8_t *__restrict valid, double a, double b, double centre,            \
      const double *__restrict pred, const double *__restrict sigma,                      \
      const double *__restrict inv_var, double *__restrict sum, double *__restrict count, \
      double *__restrict out, double *__restrict mult

// The residual and the scale's sums, common to both estimators. Compiled
// per case (masked, with a line, heights or slopes) so that the loop keeps
// only what it needs in registers.
#define FLT_WEIGH_RESIDUAL(masked, lined, slopes)                           \
  double v = value[k];                                                      \
  if (lined)                                                                \
    v -= a + b * (double(std::int32_t(k)) - centre); /* vectorises */       \
  const bool fin = std::fabs(value[k]) <= big;                              \
  double ok = fin ? 1.0 : 0.0;                                              \
  if (masked)                                                               \
    ok *= valid[k] != 0 ? 1.0 : 0.0;                                        \
  const double r = (fin ? ((slopes) ? scale * v : v) - pred[k] : 0.0) * ok; \
  const double ar = std::fabs(r), sg = sigma[k], clip = k_clip * sg;        \
  sum[k] += ar < clip ? ar : clip;                                          \
  count[k] += ok;

// Huber: a pseudo-observation with psi(r) = r clipped at k_huber * sigma;
// beyond k_gross * sigma the raw value with weight k_huber * sigma / |r|.
#define FLT_WEIGH_HUBER_BODY(masked, lined, slopes)                               \
  const double big = k_max_sample;                                                \
  std::uint64_t bits = 0; /* OR of the multipliers: the sign bit says -1 */       \
  for (std::size_t k = 0; k < K; ++k) {                                           \
    FLT_WEIGH_RESIDUAL(masked, lined, slopes)                                     \
    const double c = k_huber * sg, upper = r > c ? c : r;                         \
    const double psi = upper < -c ? -c : upper;                                   \
    const double gross = ar > k_gross * sg ? 1.0 : 0.0;                           \
    const double pseudo = (slopes) ? (pred[k] + psi) * inv_scale : pred[k] + psi; \
    out[k] = ok * (1.0 - gross) != 0.0 ? pseudo : v;                              \
    const double m = ok * (gross != 0.0 ? -1.0 : 1.0); /* ok = 0: +0 */           \
    mult[k] = m;                                                                  \
    std::uint64_t u;                                                              \
    std::memcpy(&u, &m, sizeof u);                                                \
    bits |= u;                                                                    \
  }                                                                               \
  (void)inv_var;                                                                  \
  return (bits >> 63) != 0;

// Tukey: the raw value with weight (1 - u^2)^2, u = r / (k_tukey sigma),
// 0 outside (plain IRLS).
#define FLT_WEIGH_TUKEY_BODY(masked, lined, slopes)                     \
  const double big = k_max_sample;                                      \
  for (std::size_t k = 0; k < K; ++k) {                                 \
    FLT_WEIGH_RESIDUAL(masked, lined, slopes)                           \
    const double u2 = r * r * inv_var[k] * (1.0 / (k_tukey * k_tukey)); \
    const double w = 1.0 - u2;                                          \
    out[k] = v;                                                         \
    mult[k] = ok * (u2 < 1.0 ? w * w : 0.0);                            \
  }                                                                     \
  (void)inv_scale;                                                      \
  return false;

#define FLT_WEIGH_VARIANTS(name, body, masked)                                             \
  FLT_ROBUST_KERNEL bool name##_h(FLT_WEIGH_KIND_PARAMS){                                  \
      body(masked, false, false)} FLT_ROBUST_KERNEL bool name##_g(FLT_WEIGH_KIND_PARAMS){  \
      body(masked, false, true)} FLT_ROBUST_KERNEL bool name##_lh(FLT_WEIGH_KIND_PARAMS){  \
      body(masked, true, false)} FLT_ROBUST_KERNEL bool name##_lg(FLT_WEIGH_KIND_PARAMS) { \
    body(masked, true, true)                                                               \
  }
FLT_WEIGH_VARIANTS(weigh_huber, FLT_WEIGH_HUBER_BODY, false)
FLT_WEIGH_VARIANTS(weigh_huber_masked, FLT_WEIGH_HUBER_BODY, true)
FLT_WEIGH_VARIANTS(weigh_tukey, FLT_WEIGH_TUKEY_BODY, false)
FLT_WEIGH_VARIANTS(weigh_tukey_masked, FLT_WEIGH_TUKEY_BODY, true)

using weigh_kernel = bool (*)(FLT_WEIGH_KIND_PARAMS);
// [tukey][masked][lined][slopes]
const weigh_kernel k_weigh[2][2][2][2] = {
    {{{weigh_huber_h, weigh_huber_g}, {weigh_huber_lh, weigh_huber_lg}},
     {{weigh_huber_masked_h, weigh_huber_masked_g},
      {weigh_huber_masked_lh, weigh_huber_masked_lg}}},
    {{{weigh_tukey_h, weigh_tukey_g}, {weigh_tukey_lh, weigh_tukey_lg}},
     {{weigh_tukey_masked_h, weigh_tukey_masked_g},
      {weigh_tukey_masked_lh, weigh_tukey_masked_lg}}},
};

// A completed block's estimate per fiber: the clipped mean as a Gaussian
// sigma, NaN with too few values; the block's sums restart.
FLT_ROBUST_KERNEL void close_block(std::size_t K, double *__restrict sum, double *__restrict count,
                                   double *__restrict estimate) {
    for (std::size_t k = 0; k < K; ++k) {
        estimate[k] =
            count[k] >= double(k_min_block_values) ? k_clipped_to_sigma * sum[k] / count[k] : k_nan;
        sum[k] = 0.0;
        count[k] = 0.0;
    }
}

// The median of nine blocks per fiber, a sorting network of min/max
// (vectorised across fibers), floored; incomplete[k] = 1 where one of the
// nine is NaN (the network's result is then meaningless there).
FLT_ROBUST_KERNEL void median9(std::size_t K, const double *__restrict e, double floor,
                               double *__restrict sigma, double *__restrict incomplete) {
    for (std::size_t k = 0; k < K; ++k) {
        double p[9];
        bool nan = false;
        for (int i = 0; i < 9; ++i) {
            p[i] = e[std::size_t(i) * K + k];
            nan = nan | (p[i] != p[i]);
        }
        // Compare-exchange (a, b): afterwards p[a] <= p[b].
        auto cx = [&p](int a, int b) {
            const double lo = std::min(p[a], p[b]), hi = std::max(p[a], p[b]);
            p[a] = lo;
            p[b] = hi;
        };
        // A 19-exchange median-of-9 network (sorts rows of three, then
        // columns, then the diagonal through the middle).
        cx(1, 2);
        cx(4, 5);
        cx(7, 8);
        cx(0, 1);
        cx(3, 4);
        cx(6, 7);
        cx(1, 2);
        cx(4, 5);
        cx(7, 8);
        cx(0, 3);
        cx(5, 8);
        cx(4, 7);
        cx(3, 6);
        cx(1, 4);
        cx(2, 5);
        cx(4, 7);
        cx(4, 2);
        cx(6, 4);
        cx(4, 2);
        sigma[k] = std::max(floor, p[4]);
        incomplete[k] = nan ? 1.0 : 0.0;
    }
}

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
    const bool gross_h = k_weigh[tukey][masked][lined][0](
        K, 1.0, 1.0, h, valid, line[0], line[1], line[4], pred_h, hs.sigma(), hs.inv_var(),
        feed ? hs.sum() : sink_sum, feed ? hs.count() : sink_count, out_h, mult_h);
    const bool gross_g = k_weigh[tukey][masked][lined][1](
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
