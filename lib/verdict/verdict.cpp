// SPDX-License-Identifier: Apache-2.0
// One sheet against every rule (verdict.hpp): the straightedge measures on
// the height map, the others from the values given.
#include "verdict/verdict.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "flatline/recon.h"  // FLT_FLAG_NO_DATA

namespace flt {
namespace verdict {
namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

// The worst straightedge gap of a map for one measure and length: over
// every fiber (along) or every row (across).
map_gap straightedge_of_map(straightedge &se, flt_measure measure, double length,
                            const map_view &m) {
    map_gap out;
    out.computed = true;
    // The tallest lines first (straightedge::order_lines): same result,
    // most lines skipped. Ties keep the line order, so the position
    // reported is the first line (in that order) with the largest gap.
    if (measure == FLT_MEASURE_STRAIGHTEDGE_ALONG) {
        const std::vector<std::size_t> &order =
            se.order_lines(m.z, m.flags, m.fibers, 1, m.rows, m.fibers, FLT_FLAG_NO_DATA);
        for (std::size_t k : order) {
            const straightedge_gap g =
                se.measure(m.s, m.z + k, m.flags ? m.flags + k : nullptr, m.rows, m.fibers,
                           FLT_FLAG_NO_DATA, length, out.measured ? out.deviation : -1.0);
            if (g.measured && (!out.measured || g.deviation > out.deviation)) {
                out.measured = true;
                out.deviation = g.deviation;
                out.x = m.x[k];
                out.s = g.at;
            }
        }
    } else {
        const std::vector<std::size_t> &order =
            se.order_lines(m.z, m.flags, m.rows, m.fibers, m.fibers, 1, FLT_FLAG_NO_DATA);
        for (std::size_t r : order) {
            const straightedge_gap g = se.measure(
                m.x, m.z + r * m.fibers, m.flags ? m.flags + r * m.fibers : nullptr, m.fibers, 1,
                FLT_FLAG_NO_DATA, length, out.measured ? out.deviation : -1.0);
            if (g.measured && (!out.measured || g.deviation > out.deviation)) {
                out.measured = true;
                out.deviation = g.deviation;
                out.x = g.at;
                out.s = m.s[r];
            }
        }
    }
    return out;
}

}  // namespace

bool needs_map(const rule_set &set) {
    return std::any_of(set.rules.begin(), set.rules.end(),
                       [](const rule &r) { return is_straightedge(r.measure); });
}

void judge(const rule_set &set, const given_measure *given, straightedge &se, double thickness,
           double width, const map_view &map, rule_result *results, map_gap *gaps) {
    const std::vector<rule> &rules = set.rules;
    const bool has_map = map.rows > 0 && map.fibers > 0;
    for (std::size_t i = 0; i < rules.size(); ++i)
        gaps[i] = map_gap{};
    for (std::size_t i = 0; i < rules.size(); ++i) {
        const rule &r = rules[i];
        double *out = results[i].value;
        for (int k = 0; k < k_values; ++k)
            out[k] = k_nan;
        out[FLT_VERDICT_MEASURE] = double(r.measure);
        out[FLT_VERDICT_LENGTH] = r.length;
        if (!(width > 0)) {
            // The sheet's width is unknown (no strip seen): no band can be
            // chosen, nothing was measured.
            out[FLT_VERDICT_BAND] = -1;
            out[FLT_VERDICT_STATE] = FLT_VERDICT_NOT_MEASURED;
            continue;
        }
        const int band = r.band_of(thickness, width);
        out[FLT_VERDICT_BAND] = band;
        if (band < 0) {
            out[FLT_VERDICT_STATE] = FLT_VERDICT_NO_BAND;
            continue;
        }
        const double limit = r.bands[std::size_t(band)].limit;
        out[FLT_VERDICT_LIMIT] = limit;
        bool measured = false;
        double worst = 0, x = 0, s = 0;
        if (is_straightedge(r.measure)) {
            if (has_map) {
                // Rules sharing a straightedge measure and length share its
                // result.
                std::size_t from = i;
                for (std::size_t j = 0; j < i; ++j)
                    if (gaps[j].computed && rules[j].measure == r.measure &&
                        rules[j].length == r.length)
                        from = j;
                if (from == i)
                    gaps[i] = straightedge_of_map(se, r.measure, r.length, map);
                const map_gap &g = gaps[from];
                measured = g.measured;
                worst = g.deviation;
                x = g.x;
                s = g.s;
            }
        } else {
            const given_measure &g = given[r.measure];
            measured = !std::isnan(g.value);
            worst = std::fabs(g.value);
            x = g.x;
            s = g.s;
        }
        if (!measured) {
            out[FLT_VERDICT_STATE] = FLT_VERDICT_NOT_MEASURED;
            continue;
        }
        out[FLT_VERDICT_WORST] = worst;
        out[FLT_VERDICT_MARGIN] = limit - worst;
        out[FLT_VERDICT_X] = x;
        out[FLT_VERDICT_S] = s;
        out[FLT_VERDICT_STATE] = worst <= limit ? FLT_VERDICT_PASS : FLT_VERDICT_FAIL;
    }
}

}  // namespace verdict
}  // namespace flt
