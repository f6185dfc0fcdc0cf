// SPDX-License-Identifier: Apache-2.0
#include "flatness/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "flatline/recon.h"

namespace flt {
namespace {

constexpr double nan_value = std::numeric_limits<double>::quiet_NaN();
// Reconstructor flags that mark a value as not measured (flatline/recon.h).
constexpr std::uint8_t k_unusable = FLT_FLAG_NO_DATA | FLT_FLAG_GAP | FLT_FLAG_OFF_STRIP;
// The largest |z| that is a height (mm), as for the reconstructor's
// samples: no strip is a kilometre high, and the squares of larger heights
// overflow the chord lengths (z = 1e300 made an arc length infinite
// without a flag; found by the contract suite).
constexpr double k_max_height = 1.0e9;
// Shape bands in u = (x - centre) / half width (flatline/flatness.h).
constexpr double k_centre_band = 0.3, k_edge_band = 0.7;
// A crest makes its band a component of the shape when it stands out of the
// zone profile by this share of the profile's span.
constexpr double k_crest_prominence = 0.25;
// Fewer valid zones than this cannot tell centre, quarters and edges apart.
constexpr std::size_t k_min_zones_for_shape = 5;

// Least-squares parabola a + b t + c t^2 through (t_i, z_i) from the sums
// S_k = sum t^k (k = 0..4) and T_k = sum z t^k (k = 0..2); returns c, or NaN
// when the points cannot determine a parabola. Cramer's rule on the 3x3
// normal equations: callers scale t to [-1, 1], where they are well
// conditioned.
double parabola_c(const double S[5], const double T[3]) {
    const double a00 = S[0], a01 = S[1], a02 = S[2], a11 = S[2], a12 = S[3], a22 = S[4];
    const double det = a00 * (a11 * a22 - a12 * a12) - a01 * (a01 * a22 - a12 * a02) +
                       a02 * (a01 * a12 - a11 * a02);
    const double scale = S[0] * S[2] * S[4];
    if (!(std::fabs(det) > 1e-12 * scale))
        return nan_value;
    // Replace the third column by T.
    const double det_c = a00 * (a11 * T[2] - T[1] * a12) - a01 * (a01 * T[2] - T[1] * a02) +
                         T[0] * (a01 * a12 - a11 * a02);
    return det_c / det;
}

// Vertex of the parabola through three points (s0 < s1 < s2), or the middle
// point when they are collinear. Newton form: z0 + d1 (s - s0) + a (s - s0)
// (s - s1).
void refine_extremum(double s0, double z0, double s1, double z1, double s2, double z2,
                     double &s_out, double &z_out) {
    const double d1 = (z1 - z0) / (s1 - s0);
    const double d2 = (z2 - z1) / (s2 - s1);
    const double a = (d2 - d1) / (s2 - s0);
    s_out = s1;
    z_out = z1;
    if (a == 0.0)
        return;
    double v = 0.5 * (s0 + s1) - d1 / (2.0 * a);
    v = std::min(std::max(v, s0), s2);
    s_out = v;
    z_out = z0 + d1 * (v - s0) + a * (v - s0) * (v - s1);
}

}  // namespace

namespace {
// Each fiber stands for one pitch of strip, so the grid covers its span
// plus one pitch (one fiber: its zones).
double covered_width(const double *x, std::size_t fibers, double width_of_zone,
                     std::size_t count_of_zones) {
    return fibers >= 2          ? (x[fibers - 1] - x[0]) * double(fibers) / double(fibers - 1)
           : count_of_zones > 0 ? double(count_of_zones) * width_of_zone
                                : width_of_zone;
}
}  // namespace

double fiber_layout::zones_needed(const double *fiber_x, std::size_t fibers, double width_of_zone,
                                  std::size_t count_of_zones) {
    if (count_of_zones > 0)
        return double(count_of_zones);
    return std::max(
        1.0, std::ceil(covered_width(fiber_x, fibers, width_of_zone, 0) / width_of_zone - 1e-9));
}

void fiber_layout::build(const double *fiber_x, std::size_t fibers, double width_of_zone,
                         std::size_t count_of_zones) {
    x.assign(fiber_x, fiber_x + fibers);
    const double first = x.front(), last = x.back();
    const double covered = covered_width(fiber_x, fibers, width_of_zone, count_of_zones);
    centre = 0.5 * (first + last);
    half_width = 0.5 * covered;
    // Bounded by the caller (flatness_api.cpp), so the conversion is exact.
    const std::size_t zones =
        std::size_t(zones_needed(fiber_x, fibers, width_of_zone, count_of_zones));
    lay_zones(count_of_zones > 0 ? covered / double(count_of_zones) : width_of_zone, zones);
}

void fiber_layout::lay_zones(double width_of_zone, std::size_t zones, bool ties_to_centre) {
    zone_width = width_of_zone;
    const double left0 = centre - 0.5 * double(zones) * zone_width;
    zone_left.resize(zones);
    for (std::size_t j = 0; j < zones; ++j)
        zone_left[j] = left0 + double(j) * zone_width;
    const std::size_t fibers = x.size();
    zone_of.resize(fibers);
    zone_count.assign(zones, 0);
    for (std::size_t k = 0; k < fibers; ++k) {
        const double position = (x[k] - left0) / zone_width;
        double j = std::floor(position);
        // A fiber on a boundary (to rounding): in the zone nearer the
        // centre, so that the layout seen from either side is the same.
        const double nearest = std::round(position);
        if (ties_to_centre && std::fabs(position - nearest) < 1e-9)
            j = x[k] > centre ? nearest - 1 : nearest;
        const std::size_t zj = j > 0.0 ? std::size_t(std::min(double(zones - 1), j)) : 0;
        zone_of[k] = zj;
        // A fiber beyond the covered width is off the strip (strip layouts).
        if (std::fabs(x[k] - centre) <= half_width * (1 + 1e-12))
            ++zone_count[zj];
    }
}

void window_result::allocate(std::size_t fibers, std::size_t zones) {
    fiber_strip_x.assign(fibers, nan_value);
    fiber_sensor_x.assign(fibers, nan_value);
    zone_strip_x.assign(zones, nan_value);
    zone_sensor_x.assign(zones, nan_value);
    zone_width_mm.assign(zones, 0.0);
    zone_fibers.assign(zones, 0);
    for (int i = 0; i < 3; ++i)
        strip_width[i] = strip_centre[i] = nan_value;
    arc_length.assign(fibers, nan_value);
    i_units.assign(fibers, nan_value);
    wave_height.assign(fibers, nan_value);
    wave_period.assign(fibers, nan_value);
    steepness.assign(fibers, nan_value);
    fiber_flags.assign(fibers, 0);
    zone_i_units.assign(zones, nan_value);
    zone_flags.assign(zones, 0);
}

flatness_engine::flatness_engine(const flatness_params &params, const fiber_layout &layout)
    : p_(params), layout_(&layout) {
    const std::size_t fibers = layout.fibers();
    stretch_.resize(fibers);
    bow_coef_.resize(fibers);
    mean_z_.resize(fibers);
    order_.resize(fibers);
    zone_value_.resize(layout.zones());
    zone_weight_.resize(layout.zones());
    zone_band_.resize(layout.zones());
    columns_.resize(1);
    reserve_rows(params.row_capacity);
}

void flatness_engine::reserve_rows(std::size_t rows) {
    if (column_rows_ >= rows)
        return;
    for (column &c : columns_) {
        c.s.resize(rows);
        c.z.resize(rows);
        c.ok.resize(rows);
    }
    column_rows_ = rows;
}

void flatness_engine::use_runner(block_runner *runner) {
    runner_ = runner ? runner : &inline_runner_;
    columns_.resize(std::max(1u, runner_->participants()));
    const std::size_t rows = column_rows_;
    column_rows_ = 0;
    reserve_rows(rows);
}

// Crests and troughs by hysteresis ("zigzag"): an extremum candidate is
// confirmed once the profile has moved back from it by the hysteresis, so
// reconstruction noise smaller than that never makes a wave. The first
// extremum of a run of usable rows must also have risen (fallen) by the
// hysteresis from the run's start, so a window edge is never taken for a
// crest. Each new extremum closes a triple with the two before it.
bool flatness_engine::largest_wave(const column &c, std::size_t rows, wave &best) const {
    const double h = p_.wave_hysteresis;
    const double *s = c.s.data(), *z = c.z.data();
    const std::uint8_t *ok = c.ok.data();
    bool found = false;
    best = {0.0, 0.0};

    struct extremum {
        double s, z;
    };
    extremum e[2];
    int have = 0;  // extrema of the current run held in e (0..2)
    int dir = 0;   // 0 = first extremum not known, +1 seek crest, -1 trough
    std::size_t first = 0, cand = 0, cand_max = 0, cand_min = 0;
    double rise_to_max = 0.0, fall_to_min = 0.0, run_min = 0.0, run_max = 0.0;
    bool in_run = false;

    auto emit = [&](std::size_t i) {
        double es = s[i], ez = z[i];
        // i + 1 is usable (the retreat came after i); i - 1 when i > first.
        if (i > first)
            refine_extremum(s[i - 1], z[i - 1], s[i], z[i], s[i + 1], z[i + 1], es, ez);
        if (have == 2) {
            const double height = std::fabs(0.5 * (e[0].z + ez) - e[1].z);
            if (!found || height > best.height) {
                best = {height, es - e[0].s};
                found = true;
            }
            e[0] = e[1];
            e[1] = {es, ez};
        } else {
            e[have++] = {es, ez};
        }
    };

    for (std::size_t r = 0; r < rows; ++r) {
        if (!ok[r]) {
            in_run = false;
            continue;
        }
        if (!in_run) {
            in_run = true;
            first = cand_max = cand_min = r;
            run_min = run_max = z[r];
            rise_to_max = fall_to_min = 0.0;
            dir = 0;
            have = 0;
            continue;
        }
        const double v = z[r];
        if (dir == 0) {
            if (v > z[cand_max]) {
                cand_max = r;
                rise_to_max = v - run_min;
            }
            if (v < z[cand_min]) {
                cand_min = r;
                fall_to_min = run_max - v;
            }
            run_min = std::min(run_min, v);
            run_max = std::max(run_max, v);
            if (z[cand_max] - v >= h) {
                if (rise_to_max >= h)
                    emit(cand_max);
                dir = -1;
                cand = r;
            } else if (v - z[cand_min] >= h) {
                if (fall_to_min >= h)
                    emit(cand_min);
                dir = +1;
                cand = r;
            }
        } else if (dir > 0) {
            if (v > z[cand]) {
                cand = r;
            } else if (z[cand] - v >= h) {
                emit(cand);
                dir = -1;
                cand = r;
            }
        } else {
            if (v < z[cand]) {
                cand = r;
            } else if (v - z[cand] >= h) {
                emit(cand);
                dir = +1;
                cand = r;
            }
        }
    }
    return found;
}

namespace {
// How far ahead evaluate_fibers asks for a fiber's samples, rows: about the
// rows it takes (a square root and a division each, some 30 ns) to cover
// a miss to the last-level cache.
constexpr std::size_t k_prefetch_rows = 8;
}  // namespace

void flatness_engine::evaluate_fibers(std::size_t first, std::size_t last, column &c,
                                      std::size_t rows, const double *s, const double *z,
                                      const std::uint8_t *flags, window_result &out) {
    const std::size_t fibers = layout_->fibers();
    const double length = rows >= 2 ? s[rows - 1] - s[0] : 0.0;
    const bool is_short = !(length >= p_.min_length);
    const double mid = rows ? 0.5 * (s[0] + s[rows - 1]) : 0.0;
    const double half = 0.5 * length;
    // The rows' positions are every fiber's: copied once, not per fiber.
    std::copy(s, s + rows, c.s.begin());
    for (std::size_t k = first; k < last; ++k) {
        double excess = 0.0, covered = 0.0, z_sum = 0.0;
        double S[5] = {0, 0, 0, 0, 0}, T[3] = {0, 0, 0};
        std::size_t usable = 0;
        for (std::size_t r = 0; r < rows; ++r) {
#if defined(__GNUC__)
            // A fiber's samples lie a map row apart (9 KB at 1150 fibers):
            // no hardware prefetcher follows that, and each load would wait
            // for the last-level cache. Asked for k_prefetch_rows ahead.
            if (r + k_prefetch_rows < rows) {
                __builtin_prefetch(z + (r + k_prefetch_rows) * fibers + k, 0, 3);
                if (flags)
                    __builtin_prefetch(flags + (r + k_prefetch_rows) * fibers + k, 0, 3);
            }
#endif
            const double zk = z[r * fibers + k];
            const bool ok = std::fabs(zk) <= k_max_height &&  // NaN: false
                            !(flags && (flags[r * fibers + k] & k_unusable));
            c.z[r] = zk;
            c.ok[r] = ok;
            if (!ok)
                continue;
            ++usable;
            z_sum += zk;
            if (half > 0.0) {
                const double t = (s[r] - mid) / half, t2 = t * t;
                S[0] += 1.0;
                S[1] += t;
                S[2] += t2;
                S[3] += t2 * t;
                S[4] += t2 * t2;
                T[0] += zk;
                T[1] += zk * t;
                T[2] += zk * t2;
            }
            if (r > 0 && c.ok[r - 1]) {
                const double ds = s[r] - s[r - 1], dz = zk - c.z[r - 1];
                excess += dz * dz / (std::hypot(ds, dz) + ds);
                covered += ds;
            }
        }
        const bool fiber_ok = length > 0.0 && covered > 0.0 && covered >= p_.min_coverage * length;
        if (!fiber_ok) {
            out.fiber_flags[k] = FLT_FIBER_NO_DATA | FLT_FIBER_NO_WAVE;
            stretch_[k] = nan_value;
            continue;
        }
        if (usable < rows)
            out.fiber_flags[k] |= FLT_FIBER_PARTIAL;
        stretch_[k] = excess / covered;
        mean_z_[k] = z_sum / double(usable);
        // t spans [-1, 1], so the t^2 coefficient is the sagitta: the ends'
        // height above the middle, mm.
        bow_coef_[k] = parabola_c(S, T);
        wave w;
        if (!is_short && largest_wave(c, rows, w)) {
            out.wave_height[k] = w.height;
            out.wave_period[k] = w.period;
            out.steepness[k] = 100.0 * w.height / w.period;
        } else {
            out.fiber_flags[k] |= FLT_FIBER_NO_WAVE;
        }
    }
}

// Arc length: the rows are samples of the reconstructed spline about
// Delta-s = 3 mm apart, and the chord of a segment with curvature kappa is
// shorter than its arc by Delta-s^3 kappa^2 / 24. For a wave z = (H/2)
// sin(k s) the arc's excess over the travel is (k H / 2)^2 / 4 per mm and the
// chords miss (Delta-s)^2 (k^2 H / 2)^2 / 48 per mm of it: a relative error
// of (Delta-s k)^2 / 12 on the I-Units, 1.2e-4 for a 1000 mm wave and 0.3%
// for a 100 mm wave (the shortest the spline with 100 mm knots can show).
// Flatness waves are 500-3000 mm, so chord sums are exact enough, cost one
// square root per sample, and need nothing but the rows.
void flatness_engine::evaluate(std::size_t rows, const double *s, const double *z,
                               const std::uint8_t *flags, window_result &out) {
    const std::size_t fibers = layout_->fibers();
    const std::size_t zones = layout_->zones();
    reserve_rows(rows);
    out.allocate(fibers, zones);
    out.rows = rows;
    out.flags = 0;
    out.shape = FLT_SHAPE_UNDETERMINED;
    out.confidence = 0.0;
    out.components = 0;
    out.bow_mm = out.crossbow_mm = nan_value;
    out.s_first = rows ? s[0] : nan_value;
    out.s_last = rows ? s[rows - 1] : nan_value;
    const double length = rows >= 2 ? s[rows - 1] - s[0] : 0.0;
    const bool is_short = !(length >= p_.min_length);
    if (is_short)
        out.flags |= FLT_WINDOW_SHORT;

    // Per fiber (in blocks, on the runner's threads): gather the column,
    // sum the chord excess over usable segments, fit the longitudinal
    // parabola, find the largest wave. A fixed block size: the blocks do
    // not depend on the threads (nor do the results: each fiber's are its
    // own).
    constexpr std::size_t k_block_fibers = 32;
    const std::size_t blocks = (fibers + k_block_fibers - 1) / k_block_fibers;
    auto body = [&](std::size_t b, unsigned participant) {
        const std::size_t first = b * k_block_fibers;
        evaluate_fibers(first, std::min(fibers, first + k_block_fibers), columns_[participant],
                        rows, s, z, flags, out);
    };
    run_blocks(*runner_, blocks, body);
    std::size_t valid = 0;
    for (std::size_t k = 0; k < fibers; ++k)
        valid += (out.fiber_flags[k] & FLT_FIBER_NO_DATA) ? 0 : 1;
    if (valid == 0) {
        out.flags |= FLT_WINDOW_NO_VALID_FIBER | FLT_WINDOW_NO_BOW | FLT_WINDOW_NO_CROSSBOW;
        for (std::size_t j = 0; j < zones; ++j)
            out.zone_flags[j] = FLT_ZONE_NO_DATA;
        return;
    }

    // Reference and I-Units. The stretch e = excess / covered is the arc
    // length per mm of travel minus 1, so (l_k - l_ref) / l_ref =
    // (e_k - e_ref) / (1 + e_ref) without subtracting two near-equal lengths.
    double ref = p_.reference_mean ? 0.0 : std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < fibers; ++k) {
        if (out.fiber_flags[k] & FLT_FIBER_NO_DATA)
            continue;
        if (p_.reference_mean)
            ref += stretch_[k];
        else
            ref = std::min(ref, stretch_[k]);
    }
    if (p_.reference_mean)
        ref /= double(valid);
    for (std::size_t k = 0; k < fibers; ++k) {
        if (out.fiber_flags[k] & FLT_FIBER_NO_DATA)
            continue;
        out.arc_length[k] = (1.0 + stretch_[k]) * length;
        out.i_units[k] = (stretch_[k] - ref) / (1.0 + ref) * 1e5;
    }

    // Zones: the mean I-Units of their valid fibers. Fibers are sorted by x,
    // so each zone's fibers are consecutive.
    {
        std::size_t k = 0;
        for (std::size_t j = 0; j < zones; ++j) {
            std::size_t n = 0;
            double sum = 0.0;
            for (; k < fibers && layout_->zone_of[k] == j; ++k) {
                if (out.fiber_flags[k] & FLT_FIBER_NO_DATA)
                    continue;
                sum += out.i_units[k];
                ++n;
            }
            if (n == 0) {
                out.zone_flags[j] = FLT_ZONE_NO_DATA;
            } else {
                out.zone_i_units[j] = sum / double(n);
            }
        }
    }

    // Bow: the mean longitudinal sagitta of the flattest quarter of the
    // valid fibers (coil set is common to the whole width; the buckles are
    // smallest on the shortest fibers).
    {
        std::size_t n = 0;
        for (std::size_t k = 0; k < fibers; ++k)
            if (!(out.fiber_flags[k] & FLT_FIBER_NO_DATA) && std::isfinite(bow_coef_[k]))
                order_[n++] = k;
        if (n == 0) {
            out.flags |= FLT_WINDOW_NO_BOW;
        } else {
            const std::size_t take = std::max<std::size_t>(1, n / 4);
            std::nth_element(order_.begin(), order_.begin() + std::ptrdiff_t(take - 1),
                             order_.begin() + std::ptrdiff_t(n), [&](std::size_t a, std::size_t b) {
                                 return out.i_units[a] < out.i_units[b];
                             });
            double sum = 0.0;
            for (std::size_t i = 0; i < take; ++i)
                sum += bow_coef_[order_[i]];
            out.bow_mm = sum / double(take);
        }
    }

    // Crossbow: parabola across the width through the fibers' mean heights,
    // u = (x - centre) / half width in [-1, 1], so its u^2 coefficient is
    // the edges' height above the centre, mm.
    if (valid >= 3) {
        double S[5] = {0, 0, 0, 0, 0}, T[3] = {0, 0, 0};
        for (std::size_t k = 0; k < fibers; ++k) {
            if (out.fiber_flags[k] & FLT_FIBER_NO_DATA)
                continue;
            const double u = (layout_->x[k] - layout_->centre) / layout_->half_width;
            const double u2 = u * u, zk = mean_z_[k];
            S[0] += 1.0;
            S[1] += u;
            S[2] += u2;
            S[3] += u2 * u;
            S[4] += u2 * u2;
            T[0] += zk;
            T[1] += zk * u;
            T[2] += zk * u2;
        }
        out.crossbow_mm = parabola_c(S, T);
    }
    if (!std::isfinite(out.crossbow_mm)) {
        out.crossbow_mm = nan_value;
        out.flags |= FLT_WINDOW_NO_CROSSBOW;
    }
    if (std::isfinite(out.bow_mm) && std::fabs(out.bow_mm) >= p_.bow_limit)
        out.components |= FLT_SHAPE_HAS_BOW;
    if (std::isfinite(out.crossbow_mm) && std::fabs(out.crossbow_mm) >= p_.crossbow_limit)
        out.components |= FLT_SHAPE_HAS_CROSSBOW;

    if (!is_short)
        classify(out);
}

// The shape class from the zone profile (flatline/flatness.h, flt_shape).
void flatness_engine::classify(window_result &out) {
    const std::size_t zones = layout_->zones();
    std::size_t valid_zones = 0;
    double low = std::numeric_limits<double>::infinity(), high = -low;
    for (std::size_t j = 0; j < zones; ++j) {
        if (out.zone_flags[j] & FLT_ZONE_NO_DATA)
            continue;
        ++valid_zones;
        low = std::min(low, out.zone_i_units[j]);
        high = std::max(high, out.zone_i_units[j]);
    }
    if (valid_zones < k_min_zones_for_shape)
        return;  // undetermined
    const double peak = high - low;
    const double limit = p_.flat_limit;
    if (peak < limit) {
        out.shape = FLT_SHAPE_FLAT;
        out.confidence = limit > 0.0 ? 1.0 - 0.5 * peak / limit : 1.0;
        return;
    }
    // The valid zones in order across the width: value above the lowest
    // zone (I-Units) and band.
    enum { centre, quarter, left, right, bands };
    std::size_t n = 0;
    for (std::size_t j = 0; j < zones; ++j) {
        if (out.zone_flags[j] & FLT_ZONE_NO_DATA)
            continue;
        const double centre_x = layout_->zone_left[j] + 0.5 * layout_->zone_width;
        const double u = (centre_x - layout_->centre) / layout_->half_width;
        const double a = std::fabs(u);
        zone_value_[n] = out.zone_i_units[j] - low;
        zone_weight_[n] = double(layout_->zone_count[j]);
        zone_band_[n] = a < k_centre_band ? centre
                        : a < k_edge_band ? quarter
                        : u < 0.0         ? left
                                          : right;
        ++n;
    }
    // Components: bands holding a crest of the profile, a zone higher than
    // its neighbours (outside the strip counts as lower), above half the
    // peak and standing out of the profile by a quarter of the peak
    // (topographic prominence: its height above the higher of the two
    // lowest points that separate it from a higher zone on either side).
    // Crests, not areas, because a wavy edge is narrow: it holds little of
    // the width but is as long as a centre buckle.
    bool has[bands] = {false, false, false, false};
    for (std::size_t i = 0; i < n; ++i) {
        const double v = zone_value_[i];
        const bool crest =
            (i == 0 || v > zone_value_[i - 1]) && (i + 1 == n || v >= zone_value_[i + 1]);
        if (!crest || v < 0.5 * peak)
            continue;
        double col = 0.0;  // the lowest zone is 0
        bool bounded = false;
        double lowest = v;
        for (std::size_t l = i; l-- > 0;) {
            lowest = std::min(lowest, zone_value_[l]);
            if (zone_value_[l] > v) {
                col = lowest;
                bounded = true;
                break;
            }
        }
        lowest = v;
        for (std::size_t r = i + 1; r < n; ++r) {
            lowest = std::min(lowest, zone_value_[r]);
            if (zone_value_[r] > v || (zone_value_[r] == v && r > i)) {
                if (!bounded || lowest > col)
                    col = lowest;
                bounded = true;
                break;
            }
        }
        if (v - col >= k_crest_prominence * peak)
            has[zone_band_[i]] = true;
    }
    // Confidence: the share of the long material (the profile above half its
    // peak, weighted by the fibers a zone holds) in the named bands.
    double mass[bands] = {0, 0, 0, 0}, total = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        const double above = zone_value_[i] - 0.5 * peak;
        if (above <= 0.0)
            continue;
        mass[zone_band_[i]] += above * zone_weight_[i];
        total += above * zone_weight_[i];
    }
    double explained = 0.0;
    int groups = 0;
    if (has[centre]) {
        out.components |= FLT_SHAPE_HAS_CENTRE;
        explained += mass[centre];
        ++groups;
    }
    if (has[quarter]) {
        out.components |= FLT_SHAPE_HAS_QUARTER;
        explained += mass[quarter];
        ++groups;
    }
    if (has[left]) {
        out.components |= FLT_SHAPE_HAS_EDGE_LEFT;
        explained += mass[left];
    }
    if (has[right]) {
        out.components |= FLT_SHAPE_HAS_EDGE_RIGHT;
        explained += mass[right];
    }
    if (has[left] || has[right])
        ++groups;
    if (groups == 0 || !(total > 0.0))
        return;  // cannot happen: the top zone is a crest
    if (groups > 1)
        out.shape = FLT_SHAPE_MIX;
    else if (has[centre])
        out.shape = FLT_SHAPE_CENTRE_BUCKLE;
    else if (has[quarter])
        out.shape = FLT_SHAPE_QUARTER_BUCKLE;
    else if (has[left] && has[right])
        out.shape = FLT_SHAPE_WAVY_EDGE_BOTH;
    else if (has[left])
        out.shape = FLT_SHAPE_WAVY_EDGE_LEFT;
    else
        out.shape = FLT_SHAPE_WAVY_EDGE_RIGHT;
    const double margin = limit > 0.0 ? std::min(1.0, 0.5 * peak / limit) : 1.0;
    // explained <= total, but the two sums round differently: the ratio
    // came out 1.0000000000000002 (the contract suite); flatness.h
    // promises [0, 1].
    out.confidence = std::min(1.0, margin * explained / total);
}

}  // namespace flt
