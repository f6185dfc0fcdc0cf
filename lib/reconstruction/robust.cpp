#include "reconstruction/robust.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"

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
#define FLT_ROBUST_KERNEL __attribute__((target_clones("avx2", "default")))
#else
#define FLT_ROBUST_KERNEL
#endif

// Residuals of one row against the previous stage's prediction: height (mm)
// and Delta-d * slope (mm). Queued rows mark invalid samples with NaN, which
// the subtraction carries through.
FLT_ROBUST_KERNEL void row_residuals(std::size_t K, double D, const double *__restrict h,
                                     const double *__restrict g,
                                     const double *__restrict pred_h,
                                     const double *__restrict pred_g,
                                     double *__restrict res_h, double *__restrict res_g) {
    for (std::size_t k = 0; k < K; ++k) {
        res_h[k] = h[k] - pred_h[k];
        res_g[k] = D * g[k] - pred_g[k];
    }
}

// Huber: 1 inside k_huber scales, k_huber * scale / |r| outside.
FLT_ROBUST_KERNEL void huber_multipliers(std::size_t K, const double *__restrict residual,
                                         const double *__restrict sigma,
                                         double *__restrict out) {
    for (std::size_t k = 0; k < K; ++k) {
        const double a = std::fabs(residual[k]), c = k_huber * sigma[k];
        const double m = a <= c ? 1.0 : c / a;
        out[k] = residual[k] == residual[k] ? m : 0.0;
    }
}

// Tukey's biweight: (1 - (r / (k_tukey scale))^2)^2 inside, 0 outside.
FLT_ROBUST_KERNEL void tukey_multipliers(std::size_t K, const double *__restrict residual,
                                         const double *__restrict sigma,
                                         double *__restrict out) {
    for (std::size_t k = 0; k < K; ++k) {
        const double u = residual[k] / (k_tukey * sigma[k]);
        const double v = 1.0 - u * u;
        out[k] = std::fabs(u) < 1.0 ? v * v : 0.0;  // false for NaN too
    }
}

// out = in where finite, NaN elsewhere (the queues' mark of an invalid sample).
FLT_ROBUST_KERNEL void copy_finite(std::size_t K, const double *__restrict in,
                                   double *__restrict out) {
    const double big = std::numeric_limits<double>::max();
    for (std::size_t k = 0; k < K; ++k) out[k] = std::fabs(in[k]) <= big ? in[k] : k_nan;
}

// Per fiber: sum += min(|r|, 3 sigma), count += 1, over finite residuals.
FLT_ROBUST_KERNEL void accumulate_clipped(std::size_t K, const double *__restrict residual,
                                          const double *__restrict sigma,
                                          double *__restrict sum, double *__restrict count) {
    for (std::size_t k = 0; k < K; ++k) {
        const double r = residual[k];
        const double ok = r == r ? 1.0 : 0.0;  // NaN marks an invalid sample
        const double a = std::min(std::fabs(r), k_clip * sigma[k]);
        sum[k] += ok != 0.0 ? a : 0.0;
        count[k] += ok;
    }
}

}  // namespace

// ---------------------------------------------------------------------------

robust_scale::robust_scale(std::size_t fibers, std::size_t block_rows,
                           std::size_t blocks, double initial_sigma)
    : K_(fibers), block_rows_(block_rows), blocks_(blocks), initial_(initial_sigma) {
    sum_.assign(K_, 0.0);
    count_.assign(K_, 0.0);
    estimates_.assign(blocks_ * K_, k_nan);
    sigma_.assign(K_, initial_);
}

void robust_scale::reset() {
    std::fill(sum_.begin(), sum_.end(), 0.0);
    std::fill(count_.begin(), count_.end(), 0.0);
    std::fill(estimates_.begin(), estimates_.end(), k_nan);
    std::fill(sigma_.begin(), sigma_.end(), initial_);
    rows_ = 0;
    next_ = 0;
}

bool robust_scale::add(const double *residual) {
    accumulate_clipped(K_, residual, sigma_.data(), sum_.data(), count_.data());
    if (++rows_ < block_rows_) return false;
    double ring[64];
    for (std::size_t k = 0; k < K_; ++k) {
        estimates_[next_ * K_ + k] = count_[k] >= double(k_min_block_values)
                                         ? k_clipped_to_sigma * sum_[k] / count_[k]
                                         : k_nan;
        std::size_t m = 0;
        for (std::size_t b = 0; b < blocks_; ++b) {
            const double v = estimates_[b * K_ + k];
            if (std::isfinite(v)) ring[m++] = v;
        }
        if (m > 0) {
            std::nth_element(ring, ring + m / 2, ring + m);
            sigma_[k] = std::max(k_min_sigma_fraction * initial_, ring[m / 2]);
        }
        sum_[k] = count_[k] = 0.0;
    }
    next_ = (next_ + 1) % blocks_;
    rows_ = 0;
    return true;
}

// ---------------------------------------------------------------------------

recon_chain::recon_chain(std::size_t fibers, const recon_params &params,
                         const robust_params &robust, std::size_t knot_capacity,
                         double *z_store, std::uint8_t *flags_store,
                         double rows_per_knot_hint)
    : K_(fibers), robust_(robust), D_(params.laser_spacing) {
    const std::size_t n_stages =
        robust_.kind == robust_kind::none ? 1 : 1 + std::size_t(robust_.iterations);
    // The reweighting stages stream with a short lag, in batch use too: the
    // weights need only local context, and rows then move through short
    // queues instead of whole-sheet buffers.
    for (std::size_t i = 0; i + 1 < n_stages; ++i) {
        recon_params stage = params;
        stage.lag_knots = robust_.stage_lag_knots;
        stages_.push_back(std::make_unique<recon_engine>(K_, stage, stage.knot_capacity(),
                                                         nullptr, nullptr, false));
    }
    stages_.push_back(std::make_unique<recon_engine>(K_, params, knot_capacity,
                                                     z_store, flags_store, true));
    if (n_stages == 1) return;

    // A row waits in queue i until stage i-1 has emitted the knots under it:
    // its lag and emission group plus the row's own span, a few knots more
    // for the group's phase. Streaming use does not know the row spacing,
    // so it takes a quarter of the row capacity.
    const double knots_in_flight =
        double(robust_.stage_lag_knots + 1 + robust_.stage_lag_knots / 8) +
        2.0 * stages_[0]->knots_per_row() + 8.0;
    queue_capacity_ = rows_per_knot_hint > 0.0
                          ? std::size_t(std::ceil(1.5 * rows_per_knot_hint * knots_in_flight)) + 16
                          : std::max<std::size_t>(256, params.row_capacity / 4);
    queues_.resize(n_stages);
    h_scale_.resize(n_stages);
    g_scale_.resize(n_stages);
    for (std::size_t i = 1; i < n_stages; ++i) {
        pending &q = queues_[i];
        q.s.reset(new double[queue_capacity_]);
        q.height.reset(new double[queue_capacity_ * K_]);
        q.slope.reset(new double[queue_capacity_ * K_]);
        h_scale_[i] = std::make_unique<robust_scale>(K_, robust_.block_rows,
                                                     robust_.scale_blocks,
                                                     params.height_sigma);
        g_scale_[i] = std::make_unique<robust_scale>(K_, robust_.block_rows,
                                                     robust_.scale_blocks,
                                                     D_ * params.slope_sigma);
    }
    for (auto *v : {&pred_h_, &pred_g_, &res_h_, &res_g_, &mult_h_, &mult_g_, &wh_, &wg_})
        v->assign(K_, 0.0);
}

std::size_t recon_chain::free_rows() const {
    std::size_t free = last().free_rows();
    for (std::size_t i = 1; i < queues_.size(); ++i)
        free = std::min(free, queue_capacity_ - (queues_[i].tail - queues_[i].head));
    return free;
}

void recon_chain::enqueue(std::size_t stage, double s, const double *height,
                          const double *slope, const std::uint8_t *valid) {
    pending &q = queues_[stage];
    if (q.tail - q.head >= queue_capacity_)
        throw error(FLT_ERR_BUFFER_FULL, "robust stage queue is full");
    const std::size_t r = q.tail % queue_capacity_;
    q.s[r] = s;
    // Invalid samples (masked, NaN or infinite) are stored as NaN: the
    // stages and the scale estimate then need no mask.
    double *qh = q.height.get() + r * K_, *qg = q.slope.get() + r * K_;
    copy_finite(K_, height, qh);
    copy_finite(K_, slope, qg);
    if (valid)
        for (std::size_t k = 0; k < K_; ++k)
            if (!valid[k]) qh[k] = qg[k] = k_nan;
    ++q.tail;
}

void recon_chain::advance(std::size_t stage) {
    pending &q = queues_[stage];
    recon_engine &prev = *stages_[stage - 1], &next = *stages_[stage];
    while (q.head < q.tail) {
        const std::size_t r = q.head % queue_capacity_;
        const double s = q.s[r];
        if (!prev.predict(s, pred_h_.data(), pred_g_.data())) break;
        const double *h = q.height.get() + r * K_, *g = q.slope.get() + r * K_;
        row_residuals(K_, D_, h, g, pred_h_.data(), pred_g_.data(), res_h_.data(),
                      res_g_.data());
        const bool new_h = h_scale_[stage]->add(res_h_.data());
        const bool new_g = g_scale_[stage]->add(res_g_.data());
        const double *sh = h_scale_[stage]->sigma(), *sg = g_scale_[stage]->sigma();
        if (new_h || new_g) {
            for (std::size_t k = 0; k < K_; ++k) {
                wh_[k] = 1.0 / (sh[k] * sh[k]);
                wg_[k] = 1.0 / (sg[k] * sg[k]);
            }
            next.set_fiber_weights(wh_.data(), wg_.data());
        }
        if (robust_.kind == robust_kind::huber) {
            huber_multipliers(K_, res_h_.data(), sh, mult_h_.data());
            huber_multipliers(K_, res_g_.data(), sg, mult_g_.data());
        } else {
            tukey_multipliers(K_, res_h_.data(), sh, mult_h_.data());
            tukey_multipliers(K_, res_g_.data(), sg, mult_g_.data());
        }
        next.push_row(s, h, g, nullptr, mult_h_.data(), mult_g_.data());
        ++q.head;
        // Hand the row on at once: the next stage must take rows as this
        // one emits knots, before its ring of emitted knots moves on.
        if (stage + 1 < stages_.size()) {
            enqueue(stage + 1, s, h, g, nullptr);
            advance(stage + 1);
        }
    }
}

void recon_chain::push_row(double s, const double *height, const double *slope,
                           const std::uint8_t *valid) {
    first().push_row(s, height, slope, valid);
    if (stages_.size() == 1) return;
    enqueue(1, s, height, slope, valid);
    advance(1);
}

void recon_chain::end_sheet() {
    // Each stage finishes with all its rows, which lets the next one take
    // every row still queued for it.
    for (std::size_t i = 0; i < stages_.size(); ++i) {
        if (i > 0) {
            advance(i);
            if (queues_[i].head != queues_[i].tail)
                throw error(FLT_ERR_INTERNAL, "robust stage left rows queued at end_sheet");
        }
        stages_[i]->end_sheet();
    }
}

void recon_chain::reset() {
    for (auto &stage : stages_) stage->reset();
    for (std::size_t i = 1; i < queues_.size(); ++i) {
        queues_[i].head = queues_[i].tail = 0;
        h_scale_[i]->reset();
        g_scale_[i]->reset();
    }
}

}  // namespace flt
