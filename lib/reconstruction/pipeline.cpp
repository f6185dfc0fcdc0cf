// SPDX-License-Identifier: Apache-2.0
#include "reconstruction/pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "core/cpu_dispatch.hpp"
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

// A fiber index as a double, through a 32-bit integer: AVX2 converts those
// in one vector instruction, 64-bit ones not at all (the loops would stay
// scalar). The constructor refuses more fibers than that.
inline double fiber_index(std::size_t k) {
    return double(static_cast<std::int32_t>(k));
}

// The per-row kernels, built for baseline x86-64 and for AVX2; each call
// takes the AVX2 build where the CPU has it (core/cpu_dispatch.hpp).
#define FLT_KERNELS_FILE "reconstruction/pipeline_kernels.inc"
#include "core/cpu_dispatch_build.inc"
FLT_DISPATCH(row_complete)
FLT_DISPATCH(line_sums)
FLT_DISPATCH(line_deviations)
FLT_DISPATCH(fill_missing)
FLT_DISPATCH(missing_deviations)
using base::prefetch_row;  // a hint, the same in either build

}  // namespace

double recon_pipeline::bytes_needed(std::size_t fibers, const recon_config &config,
                                    std::size_t knot_capacity, bool batch) {
    // The channels of the constructor below; the line channels have one
    // fiber each, and parameters that do not change their sizes.
    const bool owns_rows = !batch;
    double bytes = 0.0;
    bytes += recon_chain::bytes_needed(fibers, config.params, config.robust, knot_capacity,
                                       owns_rows, batch);
    if (!config.rigid_motion)
        return bytes;
    robust_params line_robust = config.robust;
    line_robust.iterations = config.line_iterations;
    bytes +=
        2 * recon_chain::bytes_needed(1, config.params, line_robust, knot_capacity, true, batch);
    const double rows = double(config.params.row_capacity);
    bytes += 8 * (3 * rows + (batch ? 4 * rows : 0) + 10 * double(fibers));
    return bytes;
}

recon_pipeline::recon_pipeline(std::size_t fibers, const recon_config &config,
                               std::size_t knot_capacity, double *z_store,
                               std::uint8_t *flags_store, bool batch)
    : K_(fibers), config_(config) {
    rel_h_.assign(K_, 0.0);
    if (!config_.rigid_motion) {
        main_ = std::make_unique<recon_chain>(K_, config_.params, config_.robust, knot_capacity,
                                              z_store, flags_store, batch);
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
                                          flags_store, batch);

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
    // The curvature-jump prior holds the wiggle the secant slopes cannot see
    // (engine.cpp); it is relative to one height sample, and the line's
    // heights carry the heave as a single fiber's do while its slopes average
    // many fibers'. Left so, the line channels' slopes outweigh it K times
    // (the offset's) or about K/3 times (the tilt's) more than a fiber's do,
    // and a disturbance near the newest rows (the shear's ringing before it
    // is judged) moved the line's knot slopes some 20 knots back: streamed,
    // the reference's third experiment came out 0.10 mm at a 3 m latency,
    // 0.077 mm with the prior scaled to keep a single fiber's balance. It
    // bends the 1800 mm reference wave by 0.02 um more.
    offset.curvature_jump_weight *= K;
    tilt.curvature_jump_weight *= sum_xi2 / (half * half);
    robust_params line_robust = config_.robust;
    line_robust.iterations = config_.line_iterations;
    offset_ = std::make_unique<recon_chain>(1, offset, line_robust, knot_capacity, nullptr, nullptr,
                                            batch);
    tilt_ =
        std::make_unique<recon_chain>(1, tilt, line_robust, knot_capacity, nullptr, nullptr, batch);

    dev_h_.assign(K_, 0.0);
    dev_g_.assign(K_, 0.0);
    last_dev_h_.assign(K_, 0.0);
    last_dev_g_.assign(K_, 0.0);
    last_dev_s_.assign(K_, 0.0);
    has_dev_h_.assign(K_, 0);
    has_dev_g_.assign(K_, 0);
    ok_.assign(K_, 0.0);
    fill_.assign(K_, 0.0);
    line_a_.assign(config_.params.row_capacity, 0.0);
    line_b_.assign(config_.params.row_capacity, 0.0);
    line_s_.assign(config_.params.row_capacity, 0.0);
}

// Why heights are solved relative to the strip's level: only heights see a
// fiber's level, and the ridge that keeps a fiber without heights regular
// pulls every knot height towards 0 with a weight of up to 1e-12 of the
// strongest term (engine.cpp). With slopes at their cap (1e8 height
// samples) that is 1e-4 of a height sample per knot: a strip at 1e5 mm came
// out 0.3 mm low in robust mode, and at 1e8 mm (inside the documented 1e9)
// robust mode with rigid motion returned about 0. Relative to the first
// valid height, the pull is on the strip's shape (millimetres), and the
// result is the same wherever the strip lies. A height more than
// k_max_sample from the level counts as invalid (recon.h).
void recon_pipeline::find_level(const double *height, const std::uint8_t *valid) {
    if (has_level_)
        return;
    for (std::size_t k = 0; k < K_; ++k)
        if ((valid == nullptr || valid[k] != 0) && std::fabs(height[k]) <= k_max_sample) {
            level_ = height[k];
            has_level_ = true;
            return;
        }
}

void recon_pipeline::relative_heights(const double *height, double *out) const {
    // Invalid stays invalid (NaN here; the valid mask is passed on as it
    // is), and a height too far from the level becomes invalid.
    relative_row(K_, has_level_ ? level_ : 0.0, height, out);
}

void recon_pipeline::split(double s, const double *value, const std::uint8_t *valid, bool is_height,
                           double *a, double *b, double *dev) {
    std::vector<double> &last = is_height ? last_dev_h_ : last_dev_g_;
    std::vector<std::uint8_t> &has = is_height ? has_dev_h_ : has_dev_g_;
    const double centre = 0.5 * double(K_ - 1);
    // The line L = a + b*xi is defined as the least-squares line of the
    // completed row: the valid values, and for each missing fiber that has
    // been seen, L plus its predicted deviation. Setting the residual's
    // moments to zero gives a plain fit over the valid fibers with the
    // predicted deviations of the missing ones added to the right-hand side.
    // A complete row is an ordinary fit; the completed deviations never have
    // a line component, so nothing drifts from row to row.
    const bool complete = row_complete(K_, value, valid);
    double sums[5];
    if (complete) {
        line_sums(K_, centre, value, nullptr, sums);
    } else {
        fill_missing(K_, s, is_height, value, valid, last.data(), has.data(), last_dev_g_.data(),
                     has_dev_g_.data(), last_dev_s_.data(), ok_.data(), fill_.data());
        line_sums(K_, centre, fill_.data(), ok_.data(), sums);
    }
    const double n = sums[0], sx = sums[1], sxx = sums[2], sv = sums[3], sxv = sums[4];
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
    if (complete) {
        line_deviations(K_, centre, a0, b0, value, dev);
        std::copy_n(dev, K_, last.data());
        if (!has_all_[is_height ? 0 : 1]) {
            std::fill(has.begin(), has.end(), 1);
            has_all_[is_height ? 0 : 1] = true;
        }
        if (is_height)
            std::fill(last_dev_s_.begin(), last_dev_s_.end(), s);
        return;
    }
    missing_deviations(K_, s, is_height, centre, a0, b0, value, ok_.data(), dev, last.data(),
                       has.data(), last_dev_s_.data());
}

void recon_pipeline::push_row(double s, const double *raw_height, const double *slope,
                              const std::uint8_t *valid) {
    // The slopes are read right after the heights: asked for now, they
    // come from memory while the heights are made relative (a caller's
    // row that is not in the cache costs a microsecond per pass that
    // waits for it).
    prefetch_row(slope, K_);
    find_level(raw_height, valid);
    if (!config_.rigid_motion && main_->takes_raw_rows()) {
        main_->push_row_relative(s, raw_height, has_level_ ? level_ : 0.0, slope, valid);
        return;
    }
    relative_heights(raw_height, rel_h_.data());
    const double *height = rel_h_.data();
    if (!config_.rigid_motion) {
        main_->push_row(s, height, slope, valid);
        return;
    }
    if (new_strip_) {
        std::fill(has_dev_h_.begin(), has_dev_h_.end(), 0);
        std::fill(has_dev_g_.begin(), has_dev_g_.end(), 0);
        has_all_[0] = has_all_[1] = false;
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

void recon_pipeline::add_lines(std::size_t rows, const double *a, const double *b, double level,
                               double *z) const {
    for (std::size_t r = 0; r < rows; ++r) {
        // An unseen line (no valid sample since reset) adds nothing: the
        // fibers then carry it themselves, or are NaN with FLT_FLAG_NO_DATA.
        const double ar = std::isfinite(a[r]) ? a[r] : 0.0;
        const double br = std::isfinite(b[r]) ? b[r] : 0.0;
        double *zr = z + r * K_;
        for (std::size_t k = 0; k < K_; ++k)
            zr[k] = (zr[k] + (ar + br * xi(k))) + level;
    }
}

void recon_pipeline::batch(std::size_t rows, const double *s, const double *raw_height,
                           const double *slope, const std::uint8_t *valid, double *z_store) {
    const std::size_t K = K_;
    // A workspace may serve many calls (recon_api.cpp): every channel starts
    // a new strip.
    reset();
    // The sheet's heights relative to its level (find_level says why); each
    // row is taken relative as it is read, into a row of scratch, so that
    // no copy of the sheet is made.
    for (std::size_t r = 0; r < rows && !has_level_; ++r)
        find_level(raw_height + r * K, valid ? valid + r * K : nullptr);
    // The level goes back on as the rows are written (NaN stays NaN): by the
    // engine, or with rigid_motion with the line across the strip.
    batch_fibers(rows, s, raw_height, slope, valid, z_store);
}

void recon_pipeline::batch_fibers(std::size_t rows, const double *s, const double *raw_height,
                                  const double *slope, const std::uint8_t *valid, double *z_store) {
    const std::size_t K = K_;
    if (!config_.rigid_motion) {
        struct raw_rows final : row_source {
            const recon_pipeline *self;
            const double *h, *g;
            const std::uint8_t *v;
            double *rel;
            std::size_t K, rows;
            void row(int pass, std::size_t r, const double **ho, const double **go,
                     const std::uint8_t **vo, double * /*line*/) override {
                if (pass == 0) {
                    *ho = h + r * K;  // raw_first_pass
                } else {
                    if (r + 1 < rows) {
                        prefetch_row(h + (r + 1) * K, K);
                        prefetch_row(g + (r + 1) * K, K);
                    }
                    self->relative_heights(h + r * K, rel);
                    *ho = rel;
                }
                *go = g + r * K;
                *vo = v ? v + r * K : nullptr;
            }
            bool raw_first_pass(double *level) const override {
                *level = self->has_level_ ? self->level_ : 0.0;
                return true;
            }
            void raw_row_ahead(std::size_t r, const double **ho, const double **go) const override {
                *ho = r < rows ? h + r * K : nullptr;
                *go = r < rows ? g + r * K : nullptr;
            }
        } source;
        source.self = this;
        source.h = raw_height;
        source.g = slope;
        source.v = valid;
        source.rel = rel_h_.data();
        source.K = K;
        source.rows = rows;
        main_->set_output_offset(has_level_ ? level_ : 0.0);
        main_->batch(rows, s, source);
        return;
    }
    // The fibers' passes: the first splits each row (in order: split()
    // keeps the state its predictions of missing fibers need) and keeps its
    // lines; the later ones read the caller's rows and take the lines off
    // as they weigh them (cheaper than keeping a whole sheet of deviations,
    // or recomputing them in a pass of their own). Then the line channels
    // take the lines.
    for (auto *v : {&batch_ha_, &batch_hb_, &batch_ga_, &batch_gb_})
        v->assign(rows, 0.0);
    has_all_[0] = has_all_[1] = false;
    std::fill(has_dev_h_.begin(), has_dev_h_.end(), 0);
    std::fill(has_dev_g_.begin(), has_dev_g_.end(), 0);
    struct deviation_rows final : row_source {
        recon_pipeline *self;
        const double *h, *g;
        const std::uint8_t *v;
        const double *s;
        void row(int pass, std::size_t r, const double **ho, const double **go,
                 const std::uint8_t **vo, double *line) override {
            recon_pipeline &p = *self;
            const std::size_t K = p.K_;
            const std::uint8_t *vr = v ? v + r * K : nullptr;
            p.relative_heights(h + r * K, p.rel_h_.data());
            if (pass == 0) {
                p.split(s[r], p.rel_h_.data(), vr, true, &p.batch_ha_[r], &p.batch_hb_[r],
                        p.dev_h_.data());
                p.split(s[r], g + r * K, vr, false, &p.batch_ga_[r], &p.batch_gb_[r],
                        p.dev_g_.data());
                *ho = p.dev_h_.data();
                *go = p.dev_g_.data();
                *vo = nullptr;  // invalid samples are NaN
                return;
            }
            // The caller's row, and its line to take off (NaN: unseen, 0).
            auto or0 = [](double x) {
                return std::isnan(x) ? 0.0 : x;
            };
            line[0] = or0(p.batch_ha_[r]);
            line[1] = or0(p.batch_hb_[r]);
            line[2] = or0(p.batch_ga_[r]);
            line[3] = or0(p.batch_gb_[r]);
            line[4] = 0.5 * double(K - 1);
            *ho = p.rel_h_.data();
            *go = g + r * K;
            *vo = vr;
        }
    } fiber_rows;
    fiber_rows.self = this;
    fiber_rows.h = raw_height;
    fiber_rows.g = slope;
    fiber_rows.v = valid;
    fiber_rows.s = s;
    main_->batch(rows, s, fiber_rows);

    struct line_rows final : row_source {
        const double *h, *g;
        void row(int /*pass*/, std::size_t r, const double **ho, const double **go,
                 const std::uint8_t **vo, double * /*line*/) override {
            *ho = h + r;  // one fiber; NaN where the line is unseen
            *go = g + r;
            *vo = nullptr;
        }
    } offset_rows, tilt_rows;
    offset_rows.h = batch_ha_.data();
    offset_rows.g = batch_ga_.data();
    tilt_rows.h = batch_hb_.data();
    tilt_rows.g = batch_gb_.data();
    offset_->batch(rows, s, offset_rows);
    tilt_->batch(rows, s, tilt_rows);

    if (offset_->pull(rows, line_s_.data(), line_a_.data(), nullptr) != rows ||
        tilt_->pull(rows, line_s_.data(), line_b_.data(), nullptr) != rows)
        throw error(FLT_ERR_INTERNAL, "line channels out of step with the fibers");
    add_lines(rows, line_a_.data(), line_b_.data(), has_level_ ? level_ : 0.0, z_store);
}

std::size_t recon_pipeline::free_rows() const {
    std::size_t n = main_->free_rows();
    if (offset_)
        n = std::min({n, offset_->free_rows(), tilt_->free_rows()});
    return n;
}

long recon_pipeline::latency_knots() const {
    long knots = main_->latency_knots();
    if (offset_)
        knots = std::max({knots, offset_->latency_knots(), tilt_->latency_knots()});
    return knots;
}

std::size_t recon_pipeline::ready_rows() const {
    std::size_t n = main_->ready_rows();
    if (offset_)
        n = std::min({n, offset_->ready_rows(), tilt_->ready_rows()});
    return n;
}

std::size_t recon_pipeline::pull(std::size_t max_rows, double *s_out, double *z_out,
                                 std::uint8_t *flags_out) {
    // Without rigid_motion the level is added as the rows are copied out
    // (one pass over them, not two).
    const bool plain_level = !config_.rigid_motion && has_level_;
    const std::size_t n = main_->pull(std::min(max_rows, ready_rows()), s_out, z_out, flags_out,
                                      plain_level ? &level_ : nullptr);
    if (config_.rigid_motion && n > 0) {
        // The line engines have finished these rows too (ready_rows).
        if (offset_->pull(n, line_s_.data(), line_a_.data(), nullptr) != n ||
            tilt_->pull(n, line_s_.data(), line_b_.data(), nullptr) != n)
            throw error(FLT_ERR_INTERNAL, "line channels out of step with the fibers");
        // With the level, in one pass (NaN stays NaN).
        add_lines(n, line_a_.data(), line_b_.data(), has_level_ ? level_ : 0.0, z_out);
    }
    return n;
}

std::size_t recon_pipeline::peek(std::size_t offset, std::size_t max_rows, double *s_out,
                                 double *z_out, std::uint8_t *flags_out) {
    const std::size_t n = main_->peek(offset, max_rows, s_out, z_out, flags_out);
    if (config_.rigid_motion && n > 0) {
        // The line channels hold the same rows (they see every row the
        // fibers see, on the same knots with the same lag).
        if (offset_->peek(offset, n, line_s_.data(), line_a_.data(), nullptr) != n ||
            tilt_->peek(offset, n, line_s_.data(), line_b_.data(), nullptr) != n)
            throw error(FLT_ERR_INTERNAL, "line channels out of step with the fibers");
        // With the level, in one pass (NaN stays NaN).
        add_lines(n, line_a_.data(), line_b_.data(), has_level_ ? level_ : 0.0, z_out);
    } else if (has_level_) {
        for (std::size_t i = 0; i < n * K_; ++i)
            z_out[i] += level_;  // NaN stays NaN
    }
    return n;
}

void recon_pipeline::end_sheet() {
    main_->end_sheet();
    if (offset_)
        offset_->end_sheet();
    if (tilt_)
        tilt_->end_sheet();
}

void recon_pipeline::reset() {
    new_strip_ = true;
    has_level_ = false;
    level_ = 0.0;
    main_->reset();
    if (offset_)
        offset_->reset();
    if (tilt_)
        tilt_->reset();
}

void recon_pipeline::boundary(double *s_out, double *height_out, double *slope_out) const {
    main_->boundary(s_out, height_out, slope_out);
    if (height_out && has_level_)
        for (std::size_t k = 0; k < K_; ++k)
            height_out[k] += level_;
    if (!config_.rigid_motion)
        return;
    double a = 0, b = 0, ga = 0, gb = 0;
    offset_->boundary(nullptr, &a, &ga);
    tilt_->boundary(nullptr, &b, &gb);
    for (std::size_t k = 0; k < K_; ++k) {
        if (height_out)
            height_out[k] += a + b * xi(k);
        if (slope_out)
            slope_out[k] += ga + gb * xi(k);
    }
}

}  // namespace flt
