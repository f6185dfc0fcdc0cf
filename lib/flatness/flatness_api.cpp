// SPDX-License-Identifier: Apache-2.0
// The C entry points of the flatness metrics: argument checks, the streaming
// window buffer, and the results of the last window.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/options.hpp"
#include "flatline/flatness.h"
#include "flatness/flatness_internal.hpp"
#include "flatness/metrics.hpp"
#include "flatness/strip.hpp"

using namespace flt;

namespace {
constexpr std::uint32_t k_flatness_magic = 0x464c5446u;  // "FLTF"
constexpr double k_inf = std::numeric_limits<double>::infinity();
constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();
}  // namespace

struct flt_flatness {
    std::uint32_t magic = k_flatness_magic;
    flatness_params params{};
    fiber_layout layout;
    std::unique_ptr<flatness_engine> engine;
    strip_resampler strip;  // windows whose strip edges are known

    // Streaming: the rows of the current window, oldest first, row-major
    // (row_capacity rows allocated at create).
    std::vector<double> buffer_s, buffer_z;
    std::vector<std::uint8_t> buffer_flags;
    std::vector<double> buffer_left, buffer_right;  // the strip's edges, NaN = unknown
    std::size_t buffered = 0;
    bool grid_started = false;
    double window_end = k_inf;  // rows at or past it complete the window
    bool has_last_s = false;
    double last_s = 0.0;

    // The last result and the one being computed (swapped on success, so a
    // failed evaluate leaves the previous result readable).
    window_result results[2];
    int current = -1;
    std::size_t windows = 0;

    std::size_t fibers() const { return layout.fibers(); }
    window_result &spare() { return results[current == 0 ? 1 : 0]; }
    void publish() {
        current = current == 0 ? 1 : 0;
        results[current].index = ++windows;
    }
};

namespace {

flt_status read_params(const char *fn, const flt_options *options, flatness_params *out) {
    flatness_params p;
    p.window_length = option_value(options, FLT_OPT_FLAT_WINDOW_LENGTH);
    p.update_interval = option_value(options, FLT_OPT_FLAT_UPDATE_INTERVAL);
    if (p.update_interval == 0.0)
        p.update_interval = p.window_length;
    p.zone_width = option_value(options, FLT_OPT_FLAT_ZONE_WIDTH);
    p.reference_mean = option_value(options, FLT_OPT_FLAT_REFERENCE) != 0.0;
    p.min_length = option_value(options, FLT_OPT_FLAT_MIN_LENGTH);
    p.min_coverage = option_value(options, FLT_OPT_FLAT_MIN_COVERAGE);
    p.wave_hysteresis = option_value(options, FLT_OPT_FLAT_WAVE_HYSTERESIS);
    p.flat_limit = option_value(options, FLT_OPT_FLAT_FLAT_LIMIT);
    p.bow_limit = option_value(options, FLT_OPT_FLAT_BOW_LIMIT);
    p.crossbow_limit = option_value(options, FLT_OPT_FLAT_CROSSBOW_LIMIT);
    p.row_capacity = std::size_t(option_value(options, FLT_OPT_FLAT_ROW_CAPACITY));
    p.zone_count = std::size_t(option_value(options, FLT_OPT_FLAT_ZONE_COUNT));
    p.drive_side_high = option_value(options, FLT_OPT_FLAT_DRIVE_SIDE) != 0.0;
    p.zones_on_grid = option_value(options, FLT_OPT_FLAT_ZONES_ON) != 0.0;
    if (p.window_length > 0.0 && p.update_interval > p.window_length)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: option 'flat_update_interval' = %g mm is longer than "
                    "'flat_window_length' = %g mm: windows would skip strip",
                    fn, p.update_interval, p.window_length);
    *out = p;
    return FLT_OK;
}

flt_status check_handle(const char *fn, const flt_flatness *f) {
    if (f == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'flatness' is NULL", fn);
    if (f->magic != k_flatness_magic || !f->engine)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'flatness' is not a live flt_flatness handle", fn);
    return FLT_OK;
}

flt_status check_count(const char *fn, const char *what, std::size_t given, std::size_t expected) {
    if (given != expected)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument '%s' = %zu but the flatness handle has %zu", fn, what, given,
                    expected);
    return FLT_OK;
}

flt_status check_has_result(const char *fn, const flt_flatness *f) {
    if (f->current < 0)
        return fail(FLT_ERR_STATE, "%s: no window has been evaluated yet", fn);
    return FLT_OK;
}

// Rows: arrays present, shape addressable, positions finite and strictly
// increasing (also after `previous` when has_previous).
flt_status check_rows(const char *fn, std::size_t rows, std::size_t fibers, const double *s,
                      const double *z, bool has_previous, double previous) {
    FLT_CHECK_NOT_NULL(fn, s);
    FLT_CHECK_NOT_NULL(fn, z);
    if (rows == 0)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'rows' is 0", fn);
    if (rows > std::numeric_limits<std::size_t>::max() / sizeof(double) / fibers)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: rows * fibers = %zu * %zu overflows the address space", fn, rows, fibers);
    for (std::size_t r = 0; r < rows; ++r) {
        // Beyond FLT_FLATNESS_MAX_S_MM a double's spacing (1e-4 mm at 1e12)
        // approaches the finest update interval, and the window grid could
        // no longer advance.
        if (!(std::fabs(s[r]) <= FLT_FLATNESS_MAX_S_MM))  // NaN too
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 's[%zu]' = %g is not finite or beyond +-%g mm", fn, r, s[r],
                        FLT_FLATNESS_MAX_S_MM);
        const bool has_prev = r > 0 || has_previous;
        const double prev = r > 0 ? s[r - 1] : previous;
        if (has_prev && !(s[r] > prev))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 's[%zu]' = %.17g does not increase (previous "
                        "row at %.17g mm)",
                        fn, r, s[r], prev);
    }
    return FLT_OK;
}

flt_status create_handle(const char *fn, std::size_t fibers, const double *x,
                         const flt_options *options, flt_flatness **out) {
    flatness_params p;
    if (flt_status st = check_option_component(fn, options, {FLT_OPT_FLAT_WINDOW_LENGTH}))
        return st;
    if (flt_status st = read_params(fn, options, &p))
        return st;
    // Sizes first, in double (no product can overflow), then allocate.
    const double zones = fiber_layout::zones_needed(x, fibers, p.zone_width, p.zone_count);
    if (p.zone_count > FLT_FLATNESS_MAX_ZONES)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: option 'flat_zone_count' = %zu is more than %d",
                    fn, p.zone_count, FLT_FLATNESS_MAX_ZONES);
    if (!(zones <= FLT_FLATNESS_MAX_ZONES))
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: option 'flat_zone_width' = %g mm divides the fibers' %g mm into %.4g "
                    "zones, more than %d; use wider zones",
                    fn, p.zone_width, x[fibers - 1] - x[0], zones, FLT_FLATNESS_MAX_ZONES);
    // flatness.h, "Memory": per row the window (position 8, heights and
    // flags 9 K, edges 16), the strip's resampled copy (9 K and seven
    // doubles of per-row edge statistics) and the evaluation's column
    // scratch (17); per fiber and zone the two result sets.
    const double K = double(fibers), rows = double(p.row_capacity);
    const double bytes = rows * (97 + 18 * K) + 250 * K + 100 * zones;
    if (!(bytes <= FLT_FLATNESS_MAX_BYTES))
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: flat_row_capacity = %zu rows of %zu fibers would take about %.3g GB, "
                    "more than %.3g GB; use a smaller flat_row_capacity",
                    fn, p.row_capacity, fibers, bytes * 1e-9, FLT_FLATNESS_MAX_BYTES * 1e-9);
    auto f = std::make_unique<flt_flatness>();
    f->params = p;
    f->layout.build(x, fibers, p.zone_width, p.zone_count);
    f->engine = std::make_unique<flatness_engine>(f->params, f->layout);
    f->strip.reserve(p.row_capacity, fibers, f->layout.zones());
    f->buffer_s.resize(p.row_capacity);
    f->buffer_z.resize(p.row_capacity * fibers);
    f->buffer_flags.resize(p.row_capacity * fibers);
    f->buffer_left.resize(p.row_capacity);
    f->buffer_right.resize(p.row_capacity);
    for (window_result &r : f->results)
        r.allocate(fibers, f->layout.zones());
    *out = f.release();
    return FLT_OK;
}

// One window into r: on the strip where its edges are known (strip.hpp),
// else on the fiber grid; then where every result lies.
void evaluate_window(flt_flatness &f, std::size_t rows, const double *s, const double *z,
                     const std::uint8_t *flags, const double *left, const double *right,
                     window_result &r) {
    const flatness_params &p = f.params;
    const fiber_layout &grid = f.layout;
    const std::size_t fibers = grid.fibers(), zones = grid.zones();
    const int side = p.drive_side_high ? -1 : 1;
    const bool on_strip = !p.zones_on_grid && f.strip.locate(grid, rows, s, flags, left, right);
    if (!on_strip && side > 0) {
        // The grid as it is: result fiber k is sensor fiber k.
        f.engine->evaluate(rows, s, z, flags, r);
        for (int i = 0; i < 3; ++i) {
            r.strip_width[i] = 2.0 * grid.half_width;
            r.strip_centre[i] = grid.centre;
        }
        for (std::size_t k = 0; k < fibers; ++k) {
            r.fiber_strip_x[k] = grid.x[k] - grid.centre;
            r.fiber_sensor_x[k] = grid.x[k];
        }
        for (std::size_t j = 0; j < zones; ++j) {
            const double centre = grid.zone_left[j] + 0.5 * grid.zone_width;
            r.zone_strip_x[j] = centre - grid.centre;
            r.zone_sensor_x[j] = centre;
            r.zone_width_mm[j] = grid.zone_width;
            r.zone_fibers[j] = grid.zone_count[j];
        }
        return;
    }
    if (!on_strip)
        f.strip.locate_grid(grid, rows);  // the grid seen from the other side
    f.strip.resample(grid, side, rows, z, flags, p.zone_width, p.zone_count, zones,
                     f.engine->runner());
    const fiber_layout &lay = f.strip.layout();
    f.engine->use_layout(lay);
    f.engine->evaluate(rows, s, f.strip.z(), f.strip.flags(), r);
    f.engine->use_layout(grid);
    // The engine sized the zone results for the strip's zones: the rest
    // (up to the grid's count) are off the strip.
    const std::size_t used = lay.zones();
    r.zone_i_units.resize(zones, k_nan);
    r.zone_flags.resize(zones, std::uint8_t(FLT_ZONE_NO_DATA | FLT_ZONE_OFF_STRIP));
    r.zone_strip_x.assign(zones, k_nan);
    r.zone_sensor_x.assign(zones, k_nan);
    r.zone_width_mm.assign(zones, 0.0);
    r.zone_fibers.assign(zones, 0);
    const double centre = on_strip ? f.strip.mean_centre() : grid.centre;
    for (std::size_t k = 0; k < fibers; ++k) {
        r.fiber_strip_x[k] = lay.x[k];
        r.fiber_sensor_x[k] = centre + double(side) * lay.x[k];
        if (std::fabs(lay.x[k]) > lay.half_width * (1 + 1e-12))
            r.fiber_flags[k] |= FLT_FIBER_OFF_STRIP | FLT_FIBER_NO_DATA;
    }
    for (std::size_t j = 0; j < used; ++j) {
        const double middle = lay.zone_left[j] + 0.5 * lay.zone_width;
        r.zone_strip_x[j] = middle;
        r.zone_sensor_x[j] = centre + double(side) * middle;
        r.zone_width_mm[j] = lay.zone_width;
        r.zone_fibers[j] = lay.zone_count[j];
    }
    if (on_strip) {
        f.strip.statistics(r.strip_width, r.strip_centre);
        r.flags |= FLT_WINDOW_ON_STRIP;
    } else {
        for (int i = 0; i < 3; ++i) {
            r.strip_width[i] = 2.0 * grid.half_width;
            r.strip_centre[i] = grid.centre;
        }
    }
}

// Evaluates the buffered rows as one streamed window (flagged, never an
// error) and publishes the result.
void evaluate_buffer(flt_flatness &f) {
    window_result &r = f.spare();
    evaluate_window(f, f.buffered, f.buffer_s.data(), f.buffer_z.data(), f.buffer_flags.data(),
                    f.buffer_left.data(), f.buffer_right.data(), r);
    f.publish();
}

// The strip's edges given per row: finite or NaN (unknown), left < right.
flt_status check_edges(const char *fn, std::size_t rows, const double *left, const double *right) {
    for (std::size_t r = 0; r < rows; ++r) {
        const double l = left ? left[r] : k_nan, h = right ? right[r] : k_nan;
        if (std::isinf(l))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'left_mm[%zu]' = %g is infinite (NaN means unknown)", fn, r,
                        l);
        if (std::isinf(h))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'right_mm[%zu]' = %g is infinite (NaN means unknown)", fn, r,
                        h);
        if (l == l && h == h && !(l < h))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: arguments 'left_mm[%zu]' = %g and 'right_mm[%zu]' = %g: the left "
                        "edge must lie below the right one",
                        fn, r, l, r, h);
    }
    return FLT_OK;
}

// Drops the buffered rows before s_keep (they belong to no later window).
void trim_buffer(flt_flatness &f, double s_keep) {
    std::size_t drop = 0;
    while (drop < f.buffered && f.buffer_s[drop] < s_keep)
        ++drop;
    if (drop == 0)
        return;
    const std::size_t keep = f.buffered - drop, n = f.fibers();
    std::memmove(f.buffer_s.data(), f.buffer_s.data() + drop, keep * sizeof(double));
    std::memmove(f.buffer_z.data(), f.buffer_z.data() + drop * n, keep * n * sizeof(double));
    std::memmove(f.buffer_flags.data(), f.buffer_flags.data() + drop * n, keep * n);
    std::memmove(f.buffer_left.data(), f.buffer_left.data() + drop, keep * sizeof(double));
    std::memmove(f.buffer_right.data(), f.buffer_right.data() + drop, keep * sizeof(double));
    f.buffered = keep;
}

// Moves the window grid to its first end strictly after `past` (mm). A
// window ending at or before it would hold the same rows as the last one,
// or none: evaluating each took a push call per update interval, 1e7 for
// 10 m without rows at flat_update_interval = 1 um (the contract suite).
void advance_grid(flt_flatness &f, double past) {
    // An update interval below the spacing of doubles at these positions
    // (5e-324 mm is inside the option's range) cannot move the grid: adding
    // it changed nothing, and the loop below spun forever (the contract
    // suite). The grid then steps by that spacing, which, the windows that
    // hold the same rows being skipped, still makes a window per row.
    const double at = std::max(std::fabs(f.window_end), std::fabs(past));
    const double spacing = std::nextafter(at, k_inf) - at;
    const double step = std::max(f.params.update_interval, spacing);
    const double steps = std::floor((past - f.window_end) / step);
    if (steps > 0)
        f.window_end += steps * step;
    while (!(f.window_end > past))  // rounding of the jump: a step or two
        f.window_end = std::max(f.window_end + step, std::nextafter(f.window_end, k_inf));
}

void restart_grid(flt_flatness &f) {
    f.buffered = 0;
    f.grid_started = false;
    f.window_end = k_inf;
    f.has_last_s = false;
}

flt_status evaluate_rows(const char *fn, flt_flatness *flatness, std::size_t rows,
                         std::size_t fibers, const double *s, const double *z,
                         const std::uint8_t *flags, const double *left, const double *right) {
    {
        if (flt_status st = check_handle(fn, flatness))
            return st;
        flt_flatness &f = *flatness;
        if (flt_status st = check_count(fn, "fibers", fibers, f.fibers()))
            return st;
        if (flt_status st = check_rows(fn, rows, fibers, s, z, false, 0.0))
            return st;
        if (flt_status st = check_edges(fn, rows, left, right))
            return st;
        if (rows < 2)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'rows' = %zu: a window needs at least 2 rows", fn, rows);
        const double length = s[rows - 1] - s[0];
        if (length < f.params.min_length)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 's' spans %g mm, shorter than one wave "
                        "(flat_min_length = %g mm)",
                        fn, length, f.params.min_length);
        window_result &r = f.spare();
        f.strip.reserve(rows, f.fibers(), f.layout.zones());  // grows for a long sheet
        evaluate_window(f, rows, s, z, flags, left, right, r);
        if (r.flags & FLT_WINDOW_NO_VALID_FIBER)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'z' has no fiber with usable heights over "
                        "flat_min_coverage = %g of the window (NaN, or flagged "
                        "FLT_FLAG_NO_DATA / FLT_FLAG_GAP in 'flags')",
                        fn, f.params.min_coverage);
        f.publish();
        return FLT_OK;
    }
}

flt_status push_rows(const char *fn, flt_flatness *flatness, std::size_t rows, std::size_t fibers,
                     const double *s, const double *z, const std::uint8_t *flags,
                     const double *left, const double *right, std::size_t *consumed_out,
                     int *evaluated_out) {
    {
        if (flt_status st = check_handle(fn, flatness))
            return st;
        flt_flatness &f = *flatness;
        FLT_CHECK_NOT_NULL(fn, consumed_out);
        FLT_CHECK_NOT_NULL(fn, evaluated_out);
        *consumed_out = 0;
        *evaluated_out = 0;
        if (flt_status st = check_count(fn, "fibers", fibers, f.fibers()))
            return st;
        if (flt_status st = check_rows(fn, rows, fibers, s, z, f.has_last_s, f.last_s))
            return st;
        if (flt_status st = check_edges(fn, rows, left, right))
            return st;
        const flatness_params &p = f.params;
        for (std::size_t r = 0; r < rows; ++r) {
            if (!f.grid_started) {
                f.grid_started = true;
                f.window_end = p.window_length > 0.0 ? s[r] + p.window_length : k_inf;
            }
            if (s[r] >= f.window_end && f.buffered == 0)
                // Every window ending at or before s[r] is empty (the rows
                // before them were trimmed): skip to the first one row r
                // falls in.
                advance_grid(f, s[r]);
            if (s[r] >= f.window_end) {
                // Row r belongs to a later window: evaluate this one first and
                // hand control back so its results can be read. The windows
                // after it that hold the same rows (before row r comes in or
                // the oldest row drops out) are skipped.
                evaluate_buffer(f);
                const double oldest = f.buffer_s[0] + p.window_length;
                advance_grid(f, std::max(f.window_end, std::min(s[r], oldest)));
                trim_buffer(f, f.window_end - p.window_length);
                *evaluated_out = 1;
                return FLT_OK;
            }
            if (f.buffered == p.row_capacity)
                return fail(FLT_ERR_BUFFER_FULL,
                            "%s: row %zu does not fit: the window already holds "
                            "flat_row_capacity = %zu rows (%zu of %zu rows taken); "
                            "create with a larger flat_row_capacity or a shorter "
                            "flat_window_length",
                            fn, r, p.row_capacity, r, rows);
            const std::size_t n = f.fibers(), at = f.buffered;
            f.buffer_s[at] = s[r];
            std::memcpy(&f.buffer_z[at * n], z + r * n, n * sizeof(double));
            if (flags)
                std::memcpy(&f.buffer_flags[at * n], flags + r * n, n);
            else
                std::memset(&f.buffer_flags[at * n], 0, n);
            f.buffer_left[at] = left ? left[r] : k_nan;
            f.buffer_right[at] = right ? right[r] : k_nan;
            ++f.buffered;
            f.has_last_s = true;
            f.last_s = s[r];
            *consumed_out = r + 1;
        }
        return FLT_OK;
    }
}

}  // namespace

void flt::flatness_use_runner(flt_flatness *flatness, block_runner *runner) {
    flatness->engine->use_runner(runner);
}

const window_result &flt::flatness_result_of(const flt_flatness *flatness) {
    if (flatness->current < 0)
        throw error(FLT_ERR_INTERNAL, "no flatness window has been evaluated");
    return flatness->results[flatness->current];
}

extern "C" {

FLT_API const char *FLT_CALL flt_shape_string(flt_shape shape) {
    if (enum_arg(shape) < 0)
        return "unknown";
    switch (shape) {
        case FLT_SHAPE_FLAT:
            return "flat";
        case FLT_SHAPE_CENTRE_BUCKLE:
            return "centre buckle";
        case FLT_SHAPE_WAVY_EDGE_LEFT:
            return "wavy edge left";
        case FLT_SHAPE_WAVY_EDGE_RIGHT:
            return "wavy edge right";
        case FLT_SHAPE_WAVY_EDGE_BOTH:
            return "wavy edges";
        case FLT_SHAPE_QUARTER_BUCKLE:
            return "quarter buckle";
        case FLT_SHAPE_MIX:
            return "mix";
        case FLT_SHAPE_UNDETERMINED:
            return "undetermined";
        case FLT_SHAPE_NOT_JUDGED:
            return "not judged: incomplete";
        default:
            return "unknown";
    }
}

FLT_API flt_status FLT_CALL flt_flatness_create(size_t fibers, const double *fiber_x,
                                                const flt_options *options, flt_flatness **out) {
    const char *fn = "flt_flatness_create";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        if (fibers == 0)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'fibers' is 0", fn);
        if (fibers > FLT_MAX_FIBERS)  // before reading
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'fibers' = %zu is too large (at most %d)", fn, fibers,
                        FLT_MAX_FIBERS);
        FLT_CHECK_NOT_NULL(fn, fiber_x);
        for (std::size_t k = 0; k < fibers; ++k) {
            if (!std::isfinite(fiber_x[k]))
                return fail(FLT_ERR_INVALID_ARGUMENT,
                            "%s: argument 'fiber_x[%zu]' = %g is not finite", fn, k, fiber_x[k]);
            if (std::fabs(fiber_x[k]) > FLT_CALIB_MAX_X_MM)
                return fail(FLT_ERR_INVALID_ARGUMENT,
                            "%s: argument 'fiber_x[%zu]' = %g is outside [%g, %g] mm", fn, k,
                            fiber_x[k], -FLT_CALIB_MAX_X_MM, FLT_CALIB_MAX_X_MM);
            if (k > 0 && !(fiber_x[k] > fiber_x[k - 1]))
                return fail(FLT_ERR_INVALID_ARGUMENT,
                            "%s: argument 'fiber_x[%zu]' = %g does not increase "
                            "(fiber_x[%zu] = %g)",
                            fn, k, fiber_x[k], k - 1, fiber_x[k - 1]);
        }
        return create_handle(fn, fibers, fiber_x, options, out);
    });
}

FLT_API flt_status FLT_CALL flt_flatness_create_from_calib(const flt_calib *calib,
                                                           const flt_options *options,
                                                           flt_flatness **out) {
    const char *fn = "flt_flatness_create_from_calib";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        FLT_CHECK_NOT_NULL(fn, calib);
        double first = 0.0, pitch = 0.0;
        std::size_t count = 0;
        if (flt_calib_get_fiber_grid(calib, &first, &pitch, &count) != FLT_OK) {
            // Copied: fail() writes the buffer that message points into.
            const std::string why = flt_last_error_message();
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'calib' has no fiber grid (%s)", fn,
                        why.c_str());
        }
        std::vector<double> x(count);
        for (std::size_t k = 0; k < count; ++k)
            x[k] = first + double(k) * pitch;
        return create_handle(fn, count, x.data(), options, out);
    });
}

FLT_API void FLT_CALL flt_flatness_destroy(flt_flatness *flatness) {
    guard_void([&] {
        if (flatness && flatness->magic == k_flatness_magic) {
            flatness->magic = 0;
            delete flatness;
        }
    });
}

FLT_API flt_status FLT_CALL flt_flatness_fibers(const flt_flatness *flatness, size_t *out) {
    const char *fn = "flt_flatness_fibers";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, flatness))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = flatness->fibers();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_flatness_zones(const flt_flatness *flatness, size_t *out) {
    const char *fn = "flt_flatness_zones";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, flatness))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = flatness->layout.zones();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_flatness_zone_layout(const flt_flatness *flatness, size_t zones,
                                                     double *left_x_out, double *centre_x_out,
                                                     size_t *fiber_count_out) {
    const char *fn = "flt_flatness_zone_layout";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, flatness))
            return st;
        const fiber_layout &l = flatness->layout;
        if (flt_status st = check_count(fn, "zones", zones, l.zones()))
            return st;
        for (std::size_t j = 0; j < zones; ++j) {
            if (left_x_out)
                left_x_out[j] = l.zone_left[j];
            if (centre_x_out)
                centre_x_out[j] = l.zone_left[j] + 0.5 * l.zone_width;
            if (fiber_count_out)
                fiber_count_out[j] = l.zone_count[j];
        }
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_flatness_evaluate(flt_flatness *flatness, size_t rows,
                                                  size_t fibers, const double *s, const double *z,
                                                  const uint8_t *flags) {
    const char *fn = "flt_flatness_evaluate";
    return guard(fn, [&] {
        return evaluate_rows(fn, flatness, rows, fibers, s, z, flags, nullptr, nullptr);
    });
}

FLT_API flt_status FLT_CALL flt_flatness_evaluate_strip(flt_flatness *flatness, size_t rows,
                                                        size_t fibers, const double *s,
                                                        const double *z, const uint8_t *flags,
                                                        const double *left_mm,
                                                        const double *right_mm) {
    const char *fn = "flt_flatness_evaluate_strip";
    return guard(fn, [&] {
        return evaluate_rows(fn, flatness, rows, fibers, s, z, flags, left_mm, right_mm);
    });
}

FLT_API flt_status FLT_CALL flt_flatness_push(flt_flatness *flatness, size_t rows, size_t fibers,
                                              const double *s, const double *z,
                                              const uint8_t *flags, size_t *consumed_out,
                                              int *evaluated_out) {
    const char *fn = "flt_flatness_push";
    return guard(fn, [&] {
        return push_rows(fn, flatness, rows, fibers, s, z, flags, nullptr, nullptr, consumed_out,
                         evaluated_out);
    });
}

FLT_API flt_status FLT_CALL flt_flatness_push_strip(flt_flatness *flatness, size_t rows,
                                                    size_t fibers, const double *s, const double *z,
                                                    const uint8_t *flags, const double *left_mm,
                                                    const double *right_mm, size_t *consumed_out,
                                                    int *evaluated_out) {
    const char *fn = "flt_flatness_push_strip";
    return guard(fn, [&] {
        return push_rows(fn, flatness, rows, fibers, s, z, flags, left_mm, right_mm, consumed_out,
                         evaluated_out);
    });
}

FLT_API flt_status FLT_CALL flt_flatness_finish(flt_flatness *flatness, int *evaluated_out) {
    const char *fn = "flt_flatness_finish";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, flatness))
            return st;
        FLT_CHECK_NOT_NULL(fn, evaluated_out);
        flt_flatness &f = *flatness;
        *evaluated_out = 0;
        if (f.buffered >= 2) {
            evaluate_buffer(f);
            *evaluated_out = 1;
        }
        restart_grid(f);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_flatness_reset(flt_flatness *flatness) {
    const char *fn = "flt_flatness_reset";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, flatness))
            return st;
        restart_grid(*flatness);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_flatness_window(const flt_flatness *flatness, double *s_first_out,
                                                double *s_last_out, size_t *rows_out,
                                                unsigned *window_flags_out, size_t *index_out) {
    const char *fn = "flt_flatness_window";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, flatness))
            return st;
        if (flt_status st = check_has_result(fn, flatness))
            return st;
        const window_result &r = flatness->results[flatness->current];
        if (s_first_out)
            *s_first_out = r.s_first;
        if (s_last_out)
            *s_last_out = r.s_last;
        if (rows_out)
            *rows_out = r.rows;
        if (window_flags_out)
            *window_flags_out = r.flags;
        if (index_out)
            *index_out = r.index;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_flatness_fiber_results(const flt_flatness *flatness, size_t fibers,
                                                       double *arc_length_out, double *i_units_out,
                                                       double *wave_height_out,
                                                       double *wave_period_out,
                                                       double *steepness_percent_out,
                                                       uint8_t *flags_out) {
    const char *fn = "flt_flatness_fiber_results";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, flatness))
            return st;
        if (flt_status st = check_count(fn, "fibers", fibers, flatness->fibers()))
            return st;
        if (flt_status st = check_has_result(fn, flatness))
            return st;
        const window_result &r = flatness->results[flatness->current];
        auto copy = [&](double *dst, const std::vector<double> &src) {
            if (dst)
                std::copy(src.begin(), src.end(), dst);
        };
        copy(arc_length_out, r.arc_length);
        copy(i_units_out, r.i_units);
        copy(wave_height_out, r.wave_height);
        copy(wave_period_out, r.wave_period);
        copy(steepness_percent_out, r.steepness);
        if (flags_out)
            std::copy(r.fiber_flags.begin(), r.fiber_flags.end(), flags_out);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_flatness_zone_results(const flt_flatness *flatness, size_t zones,
                                                      double *i_units_out, uint8_t *flags_out) {
    const char *fn = "flt_flatness_zone_results";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, flatness))
            return st;
        if (flt_status st = check_count(fn, "zones", zones, flatness->layout.zones()))
            return st;
        if (flt_status st = check_has_result(fn, flatness))
            return st;
        const window_result &r = flatness->results[flatness->current];
        if (i_units_out)
            std::copy(r.zone_i_units.begin(), r.zone_i_units.end(), i_units_out);
        if (flags_out)
            std::copy(r.zone_flags.begin(), r.zone_flags.end(), flags_out);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_flatness_strip(const flt_flatness *flatness, double *width_mm_out,
                                               double *centre_mm_out) {
    const char *fn = "flt_flatness_strip";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, flatness))
            return st;
        if (flt_status st = check_has_result(fn, flatness))
            return st;
        const window_result &r = flatness->results[flatness->current];
        for (int i = 0; i < 3; ++i) {
            if (width_mm_out)
                width_mm_out[i] = r.strip_width[i];
            if (centre_mm_out)
                centre_mm_out[i] = r.strip_centre[i];
        }
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_flatness_zone_positions(const flt_flatness *flatness, size_t zones,
                                                        double *strip_centre_mm_out,
                                                        double *sensor_centre_mm_out,
                                                        double *width_mm_out,
                                                        size_t *fiber_count_out) {
    const char *fn = "flt_flatness_zone_positions";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, flatness))
            return st;
        if (flt_status st = check_count(fn, "zones", zones, flatness->layout.zones()))
            return st;
        if (flt_status st = check_has_result(fn, flatness))
            return st;
        const window_result &r = flatness->results[flatness->current];
        for (std::size_t j = 0; j < zones; ++j) {
            if (strip_centre_mm_out)
                strip_centre_mm_out[j] = r.zone_strip_x[j];
            if (sensor_centre_mm_out)
                sensor_centre_mm_out[j] = r.zone_sensor_x[j];
            if (width_mm_out)
                width_mm_out[j] = r.zone_width_mm[j];
            if (fiber_count_out)
                fiber_count_out[j] = r.zone_fibers[j];
        }
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_flatness_fiber_positions(const flt_flatness *flatness,
                                                         size_t fibers, double *strip_x_mm_out,
                                                         double *sensor_x_mm_out) {
    const char *fn = "flt_flatness_fiber_positions";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, flatness))
            return st;
        if (flt_status st = check_count(fn, "fibers", fibers, flatness->fibers()))
            return st;
        if (flt_status st = check_has_result(fn, flatness))
            return st;
        const window_result &r = flatness->results[flatness->current];
        for (std::size_t k = 0; k < fibers; ++k) {
            if (strip_x_mm_out)
                strip_x_mm_out[k] = r.fiber_strip_x[k];
            if (sensor_x_mm_out)
                sensor_x_mm_out[k] = r.fiber_sensor_x[k];
        }
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_flatness_shape(const flt_flatness *flatness, flt_shape *shape_out,
                                               double *confidence_out, unsigned *components_out,
                                               double *bow_mm_out, double *crossbow_mm_out) {
    const char *fn = "flt_flatness_shape";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, flatness))
            return st;
        if (flt_status st = check_has_result(fn, flatness))
            return st;
        const window_result &r = flatness->results[flatness->current];
        if (shape_out)
            *shape_out = r.shape;
        if (confidence_out)
            *confidence_out = r.confidence;
        if (components_out)
            *components_out = r.components;
        if (bow_mm_out)
            *bow_mm_out = r.bow_mm;
        if (crossbow_mm_out)
            *crossbow_mm_out = r.crossbow_mm;
        return FLT_OK;
    });
}

}  // extern "C"
