// SPDX-License-Identifier: Apache-2.0
// One sheet against every rule (verdict.hpp): the straightedge measures on
// the height map (straightedge.cpp), the others from the values given.
#include "verdict/verdict.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace flt {
namespace verdict {
namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

// Whether rule r needs a map gap for this sheet: a straightedge whose band
// applies.
bool needs_gap(const rule &r, double thickness, double width, bool has_map) {
    return has_map && is_straightedge(r.measure) && width > 0 && r.band_of(thickness, width) >= 0;
}

}  // namespace

std::size_t gap_source(const rule_set &set, std::size_t i, double thickness, double width,
                       bool has_map) {
    const std::vector<rule> &rules = set.rules;
    if (!needs_gap(rules[i], thickness, width, has_map))
        return k_no_line;
    for (std::size_t j = 0; j < i; ++j)
        if (rules[j].measure == rules[i].measure && rules[j].length == rules[i].length &&
            needs_gap(rules[j], thickness, width, has_map))
            return j;
    return i;
}

bool needs_map(const rule_set &set) {
    return std::any_of(set.rules.begin(), set.rules.end(),
                       [](const rule &r) { return is_straightedge(r.measure); });
}

void judge(const rule_set &set, const given_measure *given, straightedge &se, double thickness,
           double width, const map_view &map, rule_result *results, map_gap *gaps) {
    const bool has_map = map.rows > 0 && map.fibers > 0;
    for (std::size_t i = 0; i < set.rules.size(); ++i) {
        gaps[i] = map_gap{};
        if (gap_source(set, i, thickness, width, has_map) != i)
            continue;
        const rule &r = set.rules[i];
        se.measure_lines(map, is_along(r), r.length, 0, line_count(map, is_along(r)), gaps[i]);
    }
    finish(set, given, thickness, width, has_map, gaps, results);
}

void finish(const rule_set &set, const given_measure *given, double thickness, double width,
            bool has_map, const map_gap *gaps, rule_result *results) {
    const std::vector<rule> &rules = set.rules;
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
            const std::size_t from = gap_source(set, i, thickness, width, has_map);
            if (from != k_no_line) {
                const map_gap &g = gaps[from];
                measured = g.measured();
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
