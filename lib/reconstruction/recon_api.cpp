// SPDX-License-Identifier: Apache-2.0
// The C entry points of the reconstructor: argument checks, then the engine.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <vector>

#include "core/error.hpp"
#include "core/options.hpp"
#include "flatline/calib.h"
#include "flatline/recon.h"
#include "reconstruction/pipeline.hpp"
#include "reconstruction/recon_internal.hpp"

using namespace flt;

namespace {
constexpr std::uint32_t k_recon_magic = 0x464c5452u;  // "FLTR"
// A larger jump in s between consecutive rows is taken as a new strip that
// was not announced with reset(): bridging it would take minutes of work,
// for a stretch the spline could only extrapolate. The work is per knot (an
// elimination each), so the limit is in knots too (100 m at the default
// spacing): with fine knots a kilometre would be hundreds of thousands of
// them (fuzz_recon found such an input taking seconds per push).
constexpr double k_max_jump_mm = 1.0e6;
constexpr double k_max_jump_knots = 1000.0;
// Knots per laser spacing we support. A row spans about that many knots,
// and each elimination works on a window of twice as many unknowns, so the
// cost per mm of strip grows with its cube: 16 (6.25 mm knots with 100 mm
// between the lasers) is far finer than a flatness gauge needs (the default
// is 1) and keeps the worst case a few hundred times the default's cost.
constexpr double k_max_knots_per_laser_spacing = 16.0;
}  // namespace

// The off-strip bits of the rows held (pushed, not yet pulled), oldest
// first: the engine sees an off-strip sample as an invalid one, and pull()
// turns its output into NaN flagged FLT_FLAG_OFF_STRIP. Rows leave the
// engine in the order they came, so a FIFO of row_capacity rows (one bit per
// fiber, and one byte per row saying whether it has any) follows them.
class off_strip_fifo {
  public:
    void allocate(std::size_t rows, std::size_t fibers) {
        stride_ = (fibers + 7) / 8;
        fibers_ = fibers;
        any_.assign(rows, 0);
        bits_.assign(rows * stride_, 0);
        valid_.assign(fibers, 1);
        head_ = count_ = 0;
    }
    void clear() { head_ = count_ = 0; }
    // Appends a row; flags NULL (a plain push) has no off-strip fiber. The
    // valid mask for the engine is written to valid() (from flags).
    void push(const std::uint8_t *flags) {
        const std::size_t slot = (head_ + count_) % any_.size();
        ++count_;
        any_[slot] = 0;
        if (!flags)
            return;
        std::uint8_t *bits = &bits_[slot * stride_];
        std::memset(bits, 0, stride_);
        for (std::size_t k = 0; k < fibers_; ++k) {
            valid_[k] = flags[k] == 0 ? 1 : 0;
            if (flags[k] & FLT_FLAG_OFF_STRIP) {
                bits[k / 8] |= std::uint8_t(1u << (k % 8));
                any_[slot] = 1;
            }
        }
    }
    const std::uint8_t *valid() const { return valid_.data(); }
    // Applies the oldest `rows` rows' bits to pulled output and drops them.
    void pop(std::size_t rows, double *z, std::uint8_t *flags) {
        for (std::size_t r = 0; r < rows && count_ > 0; ++r, --count_) {
            const std::size_t slot = head_;
            head_ = (head_ + 1) % any_.size();
            if (!any_[slot])
                continue;
            const std::uint8_t *bits = &bits_[slot * stride_];
            for (std::size_t k = 0; k < fibers_; ++k)
                if (bits[k / 8] & (1u << (k % 8))) {
                    z[r * fibers_ + k] = std::numeric_limits<double>::quiet_NaN();
                    if (flags)
                        flags[r * fibers_ + k] = FLT_FLAG_OFF_STRIP;
                }
        }
    }

    // Applies the bits of `rows` rows from the `offset`-th oldest on to
    // output (peeked rows), keeping them.
    void apply(std::size_t offset, std::size_t rows, double *z, std::uint8_t *flags) const {
        for (std::size_t r = 0; r < rows && offset + r < count_; ++r) {
            const std::size_t slot = (head_ + offset + r) % any_.size();
            if (!any_[slot])
                continue;
            const std::uint8_t *bits = &bits_[slot * stride_];
            for (std::size_t k = 0; k < fibers_; ++k)
                if (bits[k / 8] & (1u << (k % 8))) {
                    z[r * fibers_ + k] = std::numeric_limits<double>::quiet_NaN();
                    if (flags)
                        flags[r * fibers_ + k] = FLT_FLAG_OFF_STRIP;
                }
        }
    }
    // Rows held (pushed, not pulled).
    std::size_t count() const { return count_; }

  private:
    std::size_t stride_ = 0, fibers_ = 0, head_ = 0, count_ = 0;
    std::vector<std::uint8_t> any_, bits_, valid_;
};

struct flt_recon {
    std::uint32_t magic = k_recon_magic;
    std::unique_ptr<recon_pipeline> engine;
    off_strip_fifo off_strip;
};

namespace {

// The largest lag (knots) whose rows are finished within latency_mm of strip
// (recon_params::latency_bound_mm), or -1 if even a lag of 0 takes more.
long lag_for_latency(double latency_mm, double knot_spacing, double laser_spacing) {
    recon_params p;
    p.knot_spacing = knot_spacing;
    p.laser_spacing = laser_spacing;
    const double most = std::floor((latency_mm - 0.5 * laser_spacing) / knot_spacing);
    p.lag_knots = long(std::max(-1.0, std::min(most, 1.0e15)));
    while (p.lag_knots >= 0 && p.latency_bound_mm() > latency_mm)
        --p.lag_knots;
    return p.lag_knots;
}

// The streaming lag from lag_knots or latency_mm (they are one setting: at
// most one of them may be set), and the head's wait.
flt_status read_lag(const char *fn, const flt_options *options, recon_params &p) {
    const double lag = option_value(options, FLT_OPT_LAG_KNOTS);
    const double latency = option_value(options, FLT_OPT_LATENCY_MM);
    if (lag >= 0.0 && option_is_set(options, FLT_OPT_LATENCY_MM))
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: options 'lag_knots' = %g and 'latency_mm' = %g are both set; they are "
                    "one setting (the streaming lag), set one of them",
                    fn, lag, latency);
    if (lag >= 0.0) {
        // The lag as given, exactly (also at the strip's head), as before
        // latency_mm existed.
        p.lag_knots = long(lag);
        p.start_lag_knots = 0;
        return FLT_OK;
    }
    p.lag_knots = lag_for_latency(latency, p.knot_spacing, p.laser_spacing);
    recon_params least = p;
    least.lag_knots = 0;
    if (p.lag_knots < 0)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: option 'latency_mm' = %g mm is shorter than the least the "
                    "reconstructor can do, %g mm (a row spans %g mm of strip, and the knots "
                    "under it must be complete: 2 knots of %g mm and half the laser spacing)",
                    fn, latency, least.latency_bound_mm(), p.laser_spacing, p.knot_spacing);
    const option_spec *spec = find_option(FLT_OPT_LAG_KNOTS);
    if (double(p.lag_knots) > spec->max_value)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: option 'latency_mm' = %g mm is a lag of %ld knots of %g mm, more "
                    "than lag_knots allows (%g)",
                    fn, latency, p.lag_knots, p.knot_spacing, spec->max_value);
    p.start_lag_knots = recon_params::head_lag(p.lag_knots);
    return FLT_OK;
}

// laser_spacing: the sensor's, from a calibration, or 0 to read the option.
// streaming: read the lag (flt_reconstruct has none).
flt_status read_params(const char *fn, const flt_options *options, recon_config *out,
                       double laser_spacing = 0.0, bool streaming = true) {
    if (flt_status st = check_option_component(fn, options, {FLT_OPT_KNOT_SPACING}))
        return st;
    recon_config config;
    recon_params &p = config.params;
    p.laser_spacing =
        laser_spacing > 0.0 ? laser_spacing : option_value(options, FLT_OPT_LASER_SPACING);
    const double knot = option_value(options, FLT_OPT_KNOT_SPACING);
    p.knot_spacing = knot > 0.0 ? knot : p.laser_spacing;
    p.height_sigma = option_value(options, FLT_OPT_HEIGHT_SIGMA);
    p.slope_sigma = option_value(options, FLT_OPT_SLOPE_SIGMA);
    p.curvature_weight = option_value(options, FLT_OPT_CURVATURE_WEIGHT);
    p.curvature_jump_weight = option_value(options, FLT_OPT_CURVATURE_JUMP_WEIGHT);
    p.max_gap = option_value(options, FLT_OPT_MAX_GAP);
    p.row_capacity = std::size_t(option_value(options, FLT_OPT_ROW_CAPACITY));
    config.rigid_motion = option_value(options, FLT_OPT_RIGID_MOTION) != 0.0;
    config.shape_sigma = option_value(options, FLT_OPT_SHAPE_SIGMA);
    config.robust.kind = robust_kind(int(option_value(options, FLT_OPT_ROBUST)));
    config.robust.iterations = int(option_value(options, FLT_OPT_ROBUST_ITERATIONS));
    config.line_iterations = int(option_value(options, FLT_OPT_ROBUST_LINE_ITERATIONS));
    if (p.laser_spacing / p.knot_spacing > k_max_knots_per_laser_spacing)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: knot_spacing = %g mm is more than %g times finer than "
                    "laser_spacing = %g mm",
                    fn, p.knot_spacing, k_max_knots_per_laser_spacing, p.laser_spacing);
    if (streaming)
        if (flt_status st = read_lag(fn, options, p))
            return st;
    *out = config;
    return FLT_OK;
}

flt_status check_handle(const char *fn, const flt_recon *recon) {
    if (recon == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'recon' is NULL", fn);
    if (recon->magic != k_recon_magic || !recon->engine)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'recon' is not a live flt_recon handle",
                    fn);
    return FLT_OK;
}

flt_status check_fibers(const char *fn, std::size_t fibers, std::size_t expected) {
    if (fibers != expected)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'fibers' = %zu but the reconstructor has %zu", fn, fibers,
                    expected);
    return FLT_OK;
}

// A real sensor has a few thousand fibers (flatline/recon.h); the kernels
// index them with 32-bit integers, which vectorise.
constexpr std::size_t k_max_fibers = FLT_MAX_FIBERS;

// Refuses a configuration whose buffers would pass FLT_RECON_MAX_BYTES,
// before anything is allocated: beyond it, an allocation may succeed on an
// overcommitting system and then take the machine page by page.
flt_status check_bytes(const char *fn, std::size_t fibers, const recon_config &config,
                       std::size_t knots, bool batch) {
    const double bytes = recon_pipeline::bytes_needed(fibers, config, knots, batch);
    if (bytes <= FLT_RECON_MAX_BYTES)
        return FLT_OK;
    const recon_params &p = config.params;
    if (batch)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: the sheet spans %zu knots of %g mm for %zu rows x %zu fibers; "
                    "reconstructing it at once would take about %.3g GB, more than %.3g GB "
                    "(rows far sparser than the knots, or a long strip: push it through a "
                    "flt_recon, or use a larger knot_spacing)",
                    fn, knots, p.knot_spacing, p.row_capacity, fibers, bytes * 1e-9,
                    FLT_RECON_MAX_BYTES * 1e-9);
    return fail(FLT_ERR_INVALID_ARGUMENT,
                "%s: %zu fibers with row_capacity = %zu, lag_knots = %ld%s would take about "
                "%.3g GB, more than %.3g GB; use fewer fibers, a smaller row_capacity or "
                "lag_knots",
                fn, fibers, p.row_capacity, p.lag_knots,
                config.robust.kind != robust_kind::none ? " and robust mode" : "", bytes * 1e-9,
                FLT_RECON_MAX_BYTES * 1e-9);
}

// rows * fibers must be addressable as doubles.
flt_status check_shape(const char *fn, std::size_t rows, std::size_t fibers) {
    if (rows == 0)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'rows' is 0", fn);
    if (fibers == 0)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'fibers' is 0", fn);
    if (rows > std::numeric_limits<std::size_t>::max() / sizeof(double) / fibers)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: rows * fibers = %zu * %zu overflows the address space", fn, rows, fibers);
    if (fibers > k_max_fibers)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'fibers' = %zu is too large (at most %zu)", fn, fibers,
                    k_max_fibers);
    return FLT_OK;
}

// Positions finite, strictly increasing, and continuing after `previous`.
flt_status check_positions(const char *fn, std::size_t rows, const double *s, bool has_previous,
                           double previous, double knot_spacing) {
    const double max_jump = std::min(k_max_jump_mm, k_max_jump_knots * knot_spacing);
    for (std::size_t r = 0; r < rows; ++r) {
        if (!std::isfinite(s[r]))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: s[%zu] = %g is not finite", fn, r, s[r]);
        const bool has_prev = r > 0 || has_previous;
        const double prev = r > 0 ? s[r - 1] : previous;
        if (has_prev && !(s[r] > prev))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: s[%zu] = %.17g does not increase (previous row at "
                        "%.17g mm); positions must be strictly increasing",
                        fn, r, s[r], prev);
        if (has_prev && s[r] - prev > max_jump)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: s[%zu] = %g jumps %g mm past the previous row, more than "
                        "%g mm (%g knots); call flt_recon_reset() to start a new strip",
                        fn, r, s[r], s[r] - prev, max_jump, max_jump / knot_spacing);
    }
    return FLT_OK;
}

flt_status check_push_arrays(const char *fn, const double *s, const double *height,
                             const double *slope) {
    FLT_CHECK_NOT_NULL(fn, s);
    FLT_CHECK_NOT_NULL(fn, height);
    FLT_CHECK_NOT_NULL(fn, slope);
    return FLT_OK;
}

// Two values of one length agree when they differ by rounding only: the
// calibration's spacing is a difference of two offsets, each exact to a few
// ulps (written and read back with 17 digits), so 1e-9 relative is far above
// rounding and far below any real disagreement (1 um in 1 m).
bool same_length(double a, double b) {
    return std::fabs(a - b) <= 1e-9 * std::max(std::fabs(a), std::fabs(b));
}

// The calibration's laser spacing (mm) and fibers, as a reconstructor made
// from it takes them: the calibration live and finished, its spacing within
// laser_spacing's bounds, and a laser_spacing option, if set, agreeing.
flt_status calib_geometry(const char *fn, const flt_calib *calib, const flt_options *options,
                          double *spacing_out, std::size_t *fibers_out) {
    FLT_CHECK_NOT_NULL(fn, calib);
    int finished = 0;
    if (flt_calib_is_finished(calib, &finished) != FLT_OK)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'calib' is not a live flt_calib handle",
                    fn);
    if (!finished)
        return fail(FLT_ERR_STATE, "%s: argument 'calib' is not finished", fn);
    // A finished calibration has both offsets, distinct, and a grid.
    double offset[FLT_CALIB_LASERS] = {0.0, 0.0}, first = 0.0, pitch = 0.0;
    std::size_t fibers = 0;
    if (flt_calib_get_laser_offset(calib, 0, &offset[0]) != FLT_OK ||
        flt_calib_get_laser_offset(calib, 1, &offset[1]) != FLT_OK ||
        flt_calib_get_fiber_grid(calib, &first, &pitch, &fibers) != FLT_OK)
        return fail(FLT_ERR_INTERNAL, "%s: a finished calibration lacks its geometry", fn);
    // The distance between the lines, whichever laser leads: the
    // extractor measures the slope over the same distance.
    const double spacing = std::fabs(offset[1] - offset[0]);
    const option_spec *spec = find_option(FLT_OPT_LASER_SPACING);
    if (!(spacing >= spec->min_value && spacing <= spec->max_value))
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'calib' has %g mm between its lasers, outside "
                    "laser_spacing's [%g, %g] mm",
                    fn, spacing, spec->min_value, spec->max_value);
    // The sensor decides. A laser_spacing option the caller set must say
    // the same: a disagreement is a mistake in one or the other, and
    // either choice would give wrong shapes without a word.
    if (option_is_set(options, FLT_OPT_LASER_SPACING)) {
        const double asked = option_value(options, FLT_OPT_LASER_SPACING);
        if (!same_length(asked, spacing))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: option 'laser_spacing' = %.17g mm disagrees with the %.17g mm "
                        "between the lasers of argument 'calib'; leave the option unset",
                        fn, asked, spacing);
    }
    *spacing_out = spacing;
    *fibers_out = fibers;
    return FLT_OK;
}

flt_status create(const char *fn, std::size_t fibers, const flt_options *options,
                  double laser_spacing, flt_recon **out) {
    if (fibers == 0)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'fibers' is 0", fn);
    if (fibers > k_max_fibers)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'fibers' = %zu is too large (at most %zu)", fn, fibers,
                    k_max_fibers);
    recon_config config;
    if (flt_status st = read_params(fn, options, &config, laser_spacing))
        return st;
    const recon_params &p = config.params;
    if (check_shape(fn, p.row_capacity, fibers) != FLT_OK)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: row_capacity * fibers = %zu * %zu is too large",
                    fn, p.row_capacity, fibers);
    if (flt_status st = check_bytes(fn, fibers, config, p.knot_capacity(), false))
        return st;
    auto handle = std::make_unique<flt_recon>();
    handle->engine = std::make_unique<recon_pipeline>(fibers, config, p.knot_capacity());
    handle->off_strip.allocate(p.row_capacity, fibers);
    *out = handle.release();
    return FLT_OK;
}

}  // namespace

namespace {

// flt_recon_push and flt_recon_push_flagged: `valid` a mask (plain push) or
// `flags` the extractor's FLT_FLAG_* bits (one of the two, or neither).
flt_status push_rows(const char *fn, flt_recon *recon, std::size_t rows, std::size_t fibers,
                     const double *s, const double *height, const double *slope,
                     const std::uint8_t *valid, const std::uint8_t *flags, bool flagged) {
    {
        if (flt_status st = check_handle(fn, recon))
            return st;
        recon_pipeline &e = *recon->engine;
        if (flt_status st = check_push_arrays(fn, s, height, slope))
            return st;
        if (flagged)
            FLT_CHECK_NOT_NULL(fn, flags);
        if (flt_status st = check_shape(fn, rows, fibers))
            return st;
        if (flt_status st = check_fibers(fn, fibers, e.fibers()))
            return st;
        if (flt_status st = check_positions(fn, rows, s, e.has_last_s(), e.last_s(),
                                            e.config().params.knot_spacing))
            return st;
        if (rows > e.free_rows()) {
            if (e.ready_rows() == 0 && e.free_rows() < rows) {
                // Nothing to pull: the rows held are all waiting for the
                // strip the reconstructor needs beyond them.
                const long knots = e.latency_knots();
                return fail(FLT_ERR_BUFFER_FULL,
                            "%s: %zu rows do not fit, and no row is finished yet: a row is "
                            "finished up to about %ld knots (%.0f mm) of strip after it (at a "
                            "strip's head), and row_capacity = %zu; create the reconstructor "
                            "with a larger row_capacity or a shorter latency_mm, or end the "
                            "sheet",
                            fn, rows, knots, double(knots) * e.config().params.knot_spacing,
                            e.config().params.row_capacity);
            }
            return fail(FLT_ERR_BUFFER_FULL,
                        "%s: %zu rows do not fit: %zu of row_capacity = %zu are "
                        "free (%zu finished rows wait to be pulled)",
                        fn, rows, e.free_rows(), e.config().params.row_capacity, e.ready_rows());
        }
        for (std::size_t r = 0; r < rows; ++r) {
            const std::uint8_t *row_flags = flagged ? flags + r * fibers : nullptr;
            recon->off_strip.push(row_flags);
            const std::uint8_t *mask =
                flagged ? recon->off_strip.valid() : (valid ? valid + r * fibers : nullptr);
            e.push_row(s[r], height + r * fibers, slope + r * fibers, mask);
        }
        return FLT_OK;
    }
}

}  // namespace

namespace {

// flt_reconstruct's working memory, kept for the next call: a sheet of the
// same shape (fibers, rows, options) is solved in the same buffers, without
// allocating (mapping and faulting in tens of megabytes per call cost more
// than the solve). Calls on several threads each take a workspace of their
// own. Up to k_batch_keep workspaces and k_batch_keep_bytes are kept; a
// larger one is freed after its call.
constexpr std::size_t k_batch_keep = 4;
constexpr double k_batch_keep_bytes = 256.0 * 1024 * 1024;

struct batch_workspace {
    std::size_t fibers = 0, rows = 0, knots = 0;
    bool own_flags = false;  // constructed without flags_out: keeps its own
    recon_config config;
    double bytes = 0.0;
    std::unique_ptr<recon_pipeline> pipeline;
    std::vector<std::uint8_t> mask;  // flt_reconstruct_flagged's validity
};

// Exact equality of everything but the sizes: the engines precompute their
// weights from the options.
bool same_options(const recon_config &a, const recon_config &b) {
    const recon_params &p = a.params, &q = b.params;
    return p.knot_spacing == q.knot_spacing && p.laser_spacing == q.laser_spacing &&
           p.height_sigma == q.height_sigma && p.slope_sigma == q.slope_sigma &&
           p.curvature_weight == q.curvature_weight &&
           p.curvature_jump_weight == q.curvature_jump_weight && p.max_gap == q.max_gap &&
           p.lag_knots == q.lag_knots && p.start_lag_knots == q.start_lag_knots &&
           a.robust.kind == b.robust.kind && a.robust.iterations == b.robust.iterations &&
           a.robust.block_rows == b.robust.block_rows &&
           a.robust.scale_blocks == b.robust.scale_blocks &&
           a.line_iterations == b.line_iterations && a.rigid_motion == b.rigid_motion &&
           a.shape_sigma == b.shape_sigma;
}

class batch_pool {
  public:
    // A kept workspace that fits (the same options and fibers, at least the
    // rows and knots, flags kept the same way), or nullptr.
    std::unique_ptr<batch_workspace> take(std::size_t fibers, const recon_config &config,
                                          std::size_t rows, std::size_t knots, bool own_flags) {
        std::lock_guard<std::mutex> lock(m_);
        for (auto it = idle_.begin(); it != idle_.end(); ++it) {
            batch_workspace &w = **it;
            if (w.fibers == fibers && w.rows >= rows && w.knots >= knots &&
                w.own_flags == own_flags && same_options(w.config, config)) {
                std::unique_ptr<batch_workspace> found = std::move(*it);
                idle_.erase(it);
                return found;
            }
        }
        return nullptr;
    }
    // Keeps a workspace for the next call (the most recent first), freeing
    // the oldest beyond the limits.
    void give(std::unique_ptr<batch_workspace> w) {
        if (w->bytes > k_batch_keep_bytes)
            return;
        std::vector<std::unique_ptr<batch_workspace>> dropped;
        std::lock_guard<std::mutex> lock(m_);
        idle_.insert(idle_.begin(), std::move(w));
        double bytes = 0.0;
        for (std::size_t i = 0; i < idle_.size(); ++i) {
            bytes += idle_[i]->bytes;
            if (i >= k_batch_keep || bytes > k_batch_keep_bytes) {
                for (std::size_t j = i; j < idle_.size(); ++j)
                    dropped.push_back(std::move(idle_[j]));
                idle_.resize(i);
                break;
            }
        }
    }

    // Frees every kept workspace (those of calls in progress stay theirs and
    // are kept when their call ends); returns the bytes freed.
    double release() {
        std::vector<std::unique_ptr<batch_workspace>> dropped;
        {
            std::lock_guard<std::mutex> lock(m_);
            dropped.swap(idle_);
        }
        double bytes = 0.0;
        for (const auto &w : dropped)
            bytes += w->bytes;
        return bytes;  // freed as `dropped` goes, outside the lock
    }

  private:
    std::mutex m_;
    std::vector<std::unique_ptr<batch_workspace>> idle_;
};

batch_pool &workspaces() {
    static batch_pool pool;
    return pool;
}

flt_status reconstruct_sheet(const char *fn, const flt_options *options, std::size_t rows,
                             std::size_t fibers, const double *s, const double *height,
                             const double *slope, const std::uint8_t *valid,
                             const std::uint8_t *flags, bool flagged, double *z_out,
                             std::uint8_t *flags_out) {
    {
        if (flt_status st = check_push_arrays(fn, s, height, slope))
            return st;
        if (flagged)
            FLT_CHECK_NOT_NULL(fn, flags);
        FLT_CHECK_NOT_NULL(fn, z_out);
        if (flt_status st = check_shape(fn, rows, fibers))
            return st;
        recon_config config;
        if (flt_status st = read_params(fn, options, &config, 0.0, false))
            return st;
        recon_params &p = config.params;
        if (flt_status st = check_positions(fn, rows, s, false, 0.0, p.knot_spacing))
            return st;
        p.lag_knots = recon_params::no_lag;  // one solve with every row
        p.row_capacity = rows;
        // Every knot of the sheet stays open until the end.
        const double span = s[rows - 1] - s[0] + p.laser_spacing;
        const std::size_t knots = std::size_t(span / p.knot_spacing) + 4;
        if (flt_status st = check_bytes(fn, fibers, config, knots, true))
            return st;
        const bool own_flags = flags_out == nullptr;
        std::unique_ptr<batch_workspace> w =
            workspaces().take(fibers, config, rows, knots, own_flags);
        if (w) {
            w->pipeline->rebind_rows(z_out, flags_out);
        } else {
            w = std::make_unique<batch_workspace>();
            w->fibers = fibers;
            w->rows = rows;
            w->knots = knots;
            w->own_flags = own_flags;
            w->config = config;
            w->bytes = recon_pipeline::bytes_needed(fibers, config, knots, true) +
                       (own_flags ? double(rows) * double(fibers) : 0.0);
            w->pipeline =
                std::make_unique<recon_pipeline>(fibers, config, knots, z_out, flags_out, true);
        }
        if (flagged) {
            if (w->mask.size() < rows * fibers) {
                w->bytes += double(rows * fibers - w->mask.size());
                w->mask.resize(rows * fibers);
            }
            for (std::size_t i = 0; i < rows * fibers; ++i)
                w->mask[i] = flags[i] == 0 ? 1 : 0;
            valid = w->mask.data();
        }
        w->pipeline->batch(rows, s, height, slope, valid, z_out);
        workspaces().give(std::move(w));
        if (flagged)
            for (std::size_t i = 0; i < rows * fibers; ++i)
                if (flags[i] & FLT_FLAG_OFF_STRIP) {
                    z_out[i] = std::numeric_limits<double>::quiet_NaN();
                    if (flags_out)
                        flags_out[i] = FLT_FLAG_OFF_STRIP;
                }
        return FLT_OK;
    }
}

}  // namespace

extern "C" {

FLT_API flt_status FLT_CALL flt_recon_create(size_t fibers, const flt_options *options,
                                             flt_recon **out) {
    const char *fn = "flt_recon_create";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        return create(fn, fibers, options, 0.0, out);
    });
}

FLT_API flt_status FLT_CALL flt_recon_create_from_calib(const flt_calib *calib,
                                                        const flt_options *options,
                                                        flt_recon **out) {
    const char *fn = "flt_recon_create_from_calib";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        double spacing = 0.0;
        std::size_t fibers = 0;
        if (flt_status st = calib_geometry(fn, calib, options, &spacing, &fibers))
            return st;
        return create(fn, fibers, options, spacing, out);
    });
}

FLT_API void FLT_CALL flt_recon_destroy(flt_recon *recon) {
    guard_void([&] {
        if (recon && recon->magic == k_recon_magic) {
            recon->magic = 0;
            delete recon;
        }
    });
}

FLT_API flt_status FLT_CALL flt_recon_fibers(const flt_recon *recon, size_t *out) {
    const char *fn = "flt_recon_fibers";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, recon))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = recon->engine->fibers();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recon_get_option(const flt_recon *recon, flt_option key,
                                                 double *out) {
    const char *fn = "flt_recon_get_option";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, recon))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        // Unknown keys: FLT_ERR_NOT_FOUND, as from flt_options_get; keys of
        // other components: the argument is wrong, as in a bag at create.
        const option_spec *spec = enum_arg(key) < 0 ? nullptr : find_option(key);
        if (!spec)
            return fail(FLT_ERR_NOT_FOUND, "%s: unknown option key %d", fn, enum_arg(key));
        if (enum_arg(key) / 100 != FLT_OPT_KNOT_SPACING / 100)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: option '%s' belongs to %s, not to %s", fn,
                        spec->name, option_component(enum_arg(key)),
                        option_component(FLT_OPT_KNOT_SPACING));
        const recon_config &c = recon->engine->config();
        const recon_params &p = c.params;
        switch (key) {
            case FLT_OPT_KNOT_SPACING:
                *out = p.knot_spacing;
                break;
            case FLT_OPT_LASER_SPACING:
                *out = p.laser_spacing;
                break;
            case FLT_OPT_HEIGHT_SIGMA:
                *out = p.height_sigma;
                break;
            case FLT_OPT_SLOPE_SIGMA:
                *out = p.slope_sigma;
                break;
            case FLT_OPT_CURVATURE_WEIGHT:
                *out = p.curvature_weight;
                break;
            case FLT_OPT_CURVATURE_JUMP_WEIGHT:
                *out = p.curvature_jump_weight;
                break;
            case FLT_OPT_LAG_KNOTS:
                *out = double(p.lag_knots);
                break;
            case FLT_OPT_LATENCY_MM:
                *out = p.latency_bound_mm();
                break;
            case FLT_OPT_MAX_GAP:
                *out = p.max_gap;
                break;
            case FLT_OPT_ROW_CAPACITY:
                *out = double(p.row_capacity);
                break;
            case FLT_OPT_RIGID_MOTION:
                *out = c.rigid_motion ? 1.0 : 0.0;
                break;
            case FLT_OPT_SHAPE_SIGMA:
                *out = c.shape_sigma;
                break;
            case FLT_OPT_ROBUST:
                *out = double(int(c.robust.kind));
                break;
            case FLT_OPT_ROBUST_ITERATIONS:
                *out = double(c.robust.iterations);
                break;
            case FLT_OPT_ROBUST_LINE_ITERATIONS:
                *out = double(c.line_iterations);
                break;
            default:  // a reconstructor key registered but not reported here
                return fail(FLT_ERR_INTERNAL, "%s: option '%s' has no effective value", fn,
                            spec->name);
        }
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recon_push(flt_recon *recon, size_t rows, size_t fibers,
                                           const double *s, const double *height,
                                           const double *slope, const uint8_t *valid) {
    const char *fn = "flt_recon_push";
    return guard(fn, [&] {
        return push_rows(fn, recon, rows, fibers, s, height, slope, valid, nullptr, false);
    });
}

FLT_API flt_status FLT_CALL flt_recon_push_flagged(flt_recon *recon, size_t rows, size_t fibers,
                                                   const double *s, const double *height,
                                                   const double *slope, const uint8_t *flags) {
    const char *fn = "flt_recon_push_flagged";
    return guard(fn, [&] {
        return push_rows(fn, recon, rows, fibers, s, height, slope, nullptr, flags, true);
    });
}

FLT_API flt_status FLT_CALL flt_recon_pull(flt_recon *recon, size_t max_rows, size_t fibers,
                                           double *s_out, double *z_out, uint8_t *flags_out,
                                           size_t *rows_out) {
    const char *fn = "flt_recon_pull";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, recon))
            return st;
        recon_pipeline &e = *recon->engine;
        FLT_CHECK_NOT_NULL(fn, rows_out);
        *rows_out = 0;
        if (flt_status st = check_fibers(fn, fibers, e.fibers()))
            return st;
        if (max_rows > 0) {
            FLT_CHECK_NOT_NULL(fn, s_out);
            FLT_CHECK_NOT_NULL(fn, z_out);
            if (flt_status st = check_shape(fn, max_rows, fibers))
                return st;
        }
        if (!e.pushed_since_reset())
            return fail(FLT_ERR_STATE,
                        "%s: nothing was pushed since the reconstructor was "
                        "created or reset",
                        fn);
        *rows_out = e.pull(max_rows, s_out, z_out, flags_out);
        recon->off_strip.pop(*rows_out, z_out, flags_out);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recon_ready(const flt_recon *recon, size_t *out) {
    const char *fn = "flt_recon_ready";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, recon))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = recon->engine->ready_rows();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recon_pending(const flt_recon *recon, size_t *out) {
    const char *fn = "flt_recon_pending";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, recon))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = recon->off_strip.count() - recon->engine->ready_rows();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recon_peek(flt_recon *recon, size_t max_rows, size_t fibers,
                                           double *s_out, double *z_out, uint8_t *flags_out,
                                           size_t *rows_out) {
    const char *fn = "flt_recon_peek";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, recon))
            return st;
        recon_pipeline &e = *recon->engine;
        FLT_CHECK_NOT_NULL(fn, rows_out);
        *rows_out = 0;
        if (flt_status st = check_fibers(fn, fibers, e.fibers()))
            return st;
        if (max_rows > 0) {
            FLT_CHECK_NOT_NULL(fn, s_out);
            FLT_CHECK_NOT_NULL(fn, z_out);
            if (flt_status st = check_shape(fn, max_rows, fibers))
                return st;
        }
        if (!e.pushed_since_reset())
            return fail(FLT_ERR_STATE,
                        "%s: nothing was pushed since the reconstructor was "
                        "created or reset",
                        fn);
        const std::size_t ready = e.ready_rows();
        if (max_rows == 0 || recon->off_strip.count() <= ready)
            return FLT_OK;
        *rows_out = e.peek(ready, max_rows, s_out, z_out, flags_out);
        recon->off_strip.apply(ready, *rows_out, z_out, flags_out);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recon_end_sheet(flt_recon *recon) {
    const char *fn = "flt_recon_end_sheet";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, recon))
            return st;
        if (!recon->engine->rows_since_sheet())
            return fail(FLT_ERR_STATE,
                        "%s: no row was pushed since the last end_sheet, create "
                        "or reset",
                        fn);
        recon->engine->end_sheet();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recon_reset(flt_recon *recon) {
    const char *fn = "flt_recon_reset";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, recon))
            return st;
        recon->engine->reset();
        recon->off_strip.clear();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recon_boundary(const flt_recon *recon, size_t fibers, double *s_out,
                                               double *height_out, double *slope_out) {
    const char *fn = "flt_recon_boundary";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, recon))
            return st;
        const recon_pipeline &e = *recon->engine;
        if (flt_status st = check_fibers(fn, fibers, e.fibers()))
            return st;
        if (!e.has_boundary())
            return fail(FLT_ERR_STATE,
                        "%s: no sheet has ended since the strip began, so "
                        "there is no boundary condition",
                        fn);
        e.boundary(s_out, height_out, slope_out);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_reconstruct(const flt_options *options, size_t rows, size_t fibers,
                                            const double *s, const double *height,
                                            const double *slope, const uint8_t *valid,
                                            double *z_out, uint8_t *flags_out) {
    const char *fn = "flt_reconstruct";
    return guard(fn, [&] {
        return reconstruct_sheet(fn, options, rows, fibers, s, height, slope, valid, nullptr, false,
                                 z_out, flags_out);
    });
}

FLT_API flt_status FLT_CALL flt_reconstruct_flagged(const flt_options *options, size_t rows,
                                                    size_t fibers, const double *s,
                                                    const double *height, const double *slope,
                                                    const uint8_t *flags, double *z_out,
                                                    uint8_t *flags_out) {
    const char *fn = "flt_reconstruct_flagged";
    return guard(fn, [&] {
        return reconstruct_sheet(fn, options, rows, fibers, s, height, slope, nullptr, flags, true,
                                 z_out, flags_out);
    });
}

FLT_API flt_status FLT_CALL flt_reconstruct_release(double *bytes_out) {
    const char *fn = "flt_reconstruct_release";
    return guard(fn, [&] {
        const double bytes = workspaces().release();
        if (bytes_out)
            *bytes_out = bytes;
        return FLT_OK;
    });
}

}  // extern "C"

long flt::recon_latency_knots(const flt_recon *recon) {
    return recon->engine->latency_knots();
}

flt_status flt::recon_calib_laser_spacing(const char *fn, const flt_calib *calib,
                                          const flt_options *options, double *out) {
    std::size_t fibers = 0;
    return calib_geometry(fn, calib, options, out, &fibers);
}

long flt::recon_latency_knots(const recon_config &config) {
    // What recon_pipeline::latency_knots() gives for this configuration: its
    // channels share the knot grid and the lag, and each adds to the lag
    // the knots a row spans beyond two, ceil(D/L) + 2 (engine.cpp).
    const recon_params &p = config.params;
    return p.latency_knots() + long(std::ceil(p.laser_spacing / p.knot_spacing - 1e-9));
}

flt_status flt::recon_read_config(const char *fn, const flt_options *options, double laser_spacing,
                                  recon_config *out) {
    return read_params(fn, options, out, laser_spacing);
}

flt::recon_pipeline &flt::recon_pipeline_of(flt_recon *recon) {
    return *recon->engine;
}
