#include "reconstruction/pipeline.hpp"

#include <cmath>
#include <limits>

#include "core/error.hpp"

namespace flt {
namespace {
constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();
// How far a missing fiber's deviation is predicted from its last valid one,
// mm. The prediction is linear, so it is off by z''/2 * distance^2: about
// 1e-4 * 50 = 0.005 mm for the reference's 12 mm, 1800 mm waves. A fiber
// missing for longer leaves the fit (one step in the split, of its deviation
// divided by the number of fibers).
constexpr double k_max_prediction_mm = 10.0;
}

recon_pipeline::recon_pipeline(std::size_t fibers, const recon_config &config,
                               std::size_t knot_capacity, double *z_store,
                               std::uint8_t *flags_store, double rows_per_knot_hint)
    : K_(fibers), config_(config) {
    if (!config_.rigid_motion) {
        main_ = std::make_unique<recon_chain>(K_, config_.params, config_.robust,
                                              knot_capacity, z_store, flags_store,
                                              rows_per_knot_hint);
        return;
    }
    recon_params dev = config_.params;
    dev.height_sigma = config_.shape_sigma;
    // curvature_weight is relative to one height sample; the deviations'
    // heights weigh (height_sigma/shape_sigma)^2 more, so scale it back to
    // keep the prior's absolute strength: the deviations' precise heights
    // already pin what the slopes cannot see.
    const double ratio = config_.shape_sigma / config_.params.height_sigma;
    dev.curvature_weight = config_.params.curvature_weight * ratio * ratio;
    dev.curvature_jump_weight = config_.params.curvature_jump_weight * ratio * ratio;
    main_ = std::make_unique<recon_chain>(K_, dev, config_.robust, knot_capacity, z_store,
                                          flags_store, rows_per_knot_hint);

    // The offset a is the mean height of the frame: it carries the heave
    // (height_sigma); its slope averages K slopes.
    const double K = double(K_);
    recon_params offset = config_.params;
    offset.slope_sigma = config_.params.slope_sigma / std::sqrt(K);
    // The tilt b is in mm per fiber. A roll that lifts the strip's edges by
    // as much as the heave moves b by height_sigma / half the fibers; its
    // slope averages K slopes weighted by xi^2 (sum xi^2 = K(K^2-1)/12).
    recon_params tilt = config_.params;
    const double half = std::max(1.0, 0.5 * (K - 1.0));
    const double sum_xi2 = std::max(1.0, K * (K * K - 1.0) / 12.0);
    tilt.height_sigma = config_.params.height_sigma / half;
    tilt.slope_sigma = config_.params.slope_sigma / std::sqrt(sum_xi2);
    offset_ = std::make_unique<recon_chain>(1, offset, config_.robust, knot_capacity, nullptr,
                                            nullptr, rows_per_knot_hint);
    tilt_ = std::make_unique<recon_chain>(1, tilt, config_.robust, knot_capacity, nullptr,
                                          nullptr, rows_per_knot_hint);

    dev_h_.assign(K_, 0.0);
    dev_g_.assign(K_, 0.0);
    last_dev_h_.assign(K_, 0.0);
    last_dev_g_.assign(K_, 0.0);
    last_dev_s_.assign(K_, 0.0);
    has_dev_h_.assign(K_, 0);
    has_dev_g_.assign(K_, 0);
    line_a_.assign(config_.params.row_capacity, 0.0);
    line_b_.assign(config_.params.row_capacity, 0.0);
    line_s_.assign(config_.params.row_capacity, 0.0);
}

void recon_pipeline::split(double s, const double *value, const std::uint8_t *valid,
                           bool is_height, double *a, double *b, double *dev) {
    std::vector<double> &last = is_height ? last_dev_h_ : last_dev_g_;
    std::vector<std::uint8_t> &has = is_height ? has_dev_h_ : has_dev_g_;
    // The line L = a + b*xi is defined as the least-squares line of the
    // completed row: the valid values, and for each missing fiber that has
    // been seen, L plus its predicted deviation. Setting the residual's
    // moments to zero gives a plain fit over the valid fibers with the
    // predicted deviations of the missing ones added to the right-hand side.
    // A complete row is an ordinary fit; the completed deviations never have
    // a line component, so nothing drifts from row to row.
    double n = 0, sx = 0, sxx = 0, sv = 0, sxv = 0;
    for (std::size_t k = 0; k < K_; ++k) {
        const double x = xi(k);
        const bool ok = (valid == nullptr || valid[k] != 0) && std::isfinite(value[k]);
        if (ok) {
            n += 1;
            sx += x;
            sxx += x * x;
            sv += value[k];
            sxv += x * value[k];
        } else if (has[k] && s - last_dev_s_[k] <= k_max_prediction_mm) {
            double d = last[k];  // moved on by its slope deviation
            if (is_height && has_dev_g_[k]) d += last_dev_g_[k] * (s - last_dev_s_[k]);
            sv += d;
            sxv += x * d;
        }
    }
    const double det = n * sxx - sx * sx;
    if (n == 0) {
        *a = *b = k_nan;
    } else if (n < 2 || det <= 0) {
        *a = sv / n;  // one fiber: the offset only, no tilt seen
        *b = k_nan;
    } else {
        *b = (n * sxv - sx * sv) / det;
        *a = (sv - *b * sx) / n;
    }
    // A row whose tilt is unseen keeps the tilt in the deviations: b = 0
    // there, and the tilt channel gets no sample.
    const double a0 = std::isnan(*a) ? 0.0 : *a, b0 = std::isnan(*b) ? 0.0 : *b;
    for (std::size_t k = 0; k < K_; ++k) {
        const bool ok = (valid == nullptr || valid[k] != 0) && std::isfinite(value[k]);
        dev[k] = ok ? value[k] - (a0 + b0 * xi(k)) : k_nan;
        if (ok) {
            last[k] = dev[k];
            has[k] = 1;
            if (is_height) last_dev_s_[k] = s;
        }
    }
}

void recon_pipeline::push_row(double s, const double *height, const double *slope,
                              const std::uint8_t *valid) {
    if (!config_.rigid_motion) {
        main_->push_row(s, height, slope, valid);
        return;
    }
    if (new_strip_) {
        std::fill(has_dev_h_.begin(), has_dev_h_.end(), 0);
        std::fill(has_dev_g_.begin(), has_dev_g_.end(), 0);
        new_strip_ = false;
    }
    double ha, hb, ga, gb;
    // Heights first: their prediction moves on by each fiber's slope
    // deviation from before this row.
    split(s, height, valid, true, &ha, &hb, dev_h_.data());
    split(s, slope, valid, false, &ga, &gb, dev_g_.data());
    main_->push_row(s, dev_h_.data(), dev_g_.data(), nullptr);
    offset_->push_row(s, &ha, &ga, nullptr);
    tilt_->push_row(s, &hb, &gb, nullptr);
}

void recon_pipeline::add_lines(std::size_t rows, const double *a, const double *b,
                               double *z) const {
    for (std::size_t r = 0; r < rows; ++r) {
        // An unseen line (no valid sample since reset) adds nothing: the
        // fibers then carry it themselves, or are NaN with FLT_FLAG_NO_DATA.
        const double ar = std::isfinite(a[r]) ? a[r] : 0.0;
        const double br = std::isfinite(b[r]) ? b[r] : 0.0;
        double *zr = z + r * K_;
        for (std::size_t k = 0; k < K_; ++k) zr[k] += ar + br * xi(k);
    }
}

std::size_t recon_pipeline::pull(std::size_t max_rows, double *s_out, double *z_out,
                                 std::uint8_t *flags_out) {
    const std::size_t n = main_->pull(max_rows, s_out, z_out, flags_out);
    if (!config_.rigid_motion || n == 0) return n;
    // The line engines finished exactly the same rows.
    if (offset_->pull(n, line_s_.data(), line_a_.data(), nullptr) != n ||
        tilt_->pull(n, line_s_.data(), line_b_.data(), nullptr) != n)
        throw error(FLT_ERR_INTERNAL, "line channels out of step with the fibers");
    add_lines(n, line_a_.data(), line_b_.data(), z_out);
    return n;
}

void recon_pipeline::finish_in_place(std::size_t rows, double *z_store) {
    if (!config_.rigid_motion) return;
    if (offset_->pull(rows, line_s_.data(), line_a_.data(), nullptr) != rows ||
        tilt_->pull(rows, line_s_.data(), line_b_.data(), nullptr) != rows)
        throw error(FLT_ERR_INTERNAL, "line channels out of step with the fibers");
    add_lines(rows, line_a_.data(), line_b_.data(), z_store);
}

void recon_pipeline::end_sheet() {
    main_->end_sheet();
    if (offset_) offset_->end_sheet();
    if (tilt_) tilt_->end_sheet();
}

void recon_pipeline::reset() {
    new_strip_ = true;
    main_->reset();
    if (offset_) offset_->reset();
    if (tilt_) tilt_->reset();
}

void recon_pipeline::boundary(double *s_out, double *height_out, double *slope_out) const {
    main_->boundary(s_out, height_out, slope_out);
    if (!config_.rigid_motion) return;
    double a = 0, b = 0, ga = 0, gb = 0;
    offset_->boundary(nullptr, &a, &ga);
    tilt_->boundary(nullptr, &b, &gb);
    for (std::size_t k = 0; k < K_; ++k) {
        if (height_out) height_out[k] += a + b * xi(k);
        if (slope_out) slope_out[k] += ga + gb * xi(k);
    }
}

}  // namespace flt
