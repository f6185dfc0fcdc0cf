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

// The lines per block: at least k_min_block_lines (a block is worth handing
// to another thread), and at most k_max_line_blocks blocks per rule (what
// reserve() makes room for). Fixed numbers, whatever the runner: the
// blocks, and so the results bit for bit, are the same on any number of
// threads (map_gap). Each block starts without the floor the lines
// measured before it would give (a line that cannot beat the worst so far
// is skipped), so more blocks cost more CPU.
constexpr std::size_t k_min_block_lines = 16, k_max_line_blocks = 8;

std::size_t lines_per_block(std::size_t lines) {
    return std::max(k_min_block_lines, (lines + k_max_line_blocks - 1) / k_max_line_blocks);
}

// The results of every rule into results[set.rules.size()] from the gaps
// measured (gaps[gap_source(i)]) and the measures given.
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

void judge_workspace::reserve(std::size_t rules, std::size_t longest_line, unsigned participants) {
    scratch.resize(std::max(1u, participants));
    for (straightedge &se : scratch)
        se.reserve(longest_line);
    blocks.reserve(rules * k_max_line_blocks);
    block_gaps.resize(std::max(block_gaps.size(), rules * k_max_line_blocks));
}

void judge(const rule_set &set, const given_measure *given, judge_workspace &ws,
           block_runner &runner, double thickness, double width, const map_view &map,
           rule_result *results, map_gap *gaps) {
    const bool has_map = map.rows > 0 && map.fibers > 0;
    ws.blocks.clear();  // capacity kept
    for (std::size_t i = 0; i < set.rules.size(); ++i) {
        gaps[i] = map_gap{};
        if (gap_source(set, i, thickness, width, has_map) != i)
            continue;
        const std::size_t lines = line_count(map, is_along(set.rules[i]));
        const std::size_t per = lines_per_block(lines);
        for (std::size_t a = 0; a < lines; a += per)
            ws.blocks.push_back({i, a, std::min(lines, a + per)});
    }
    if (ws.block_gaps.size() < ws.blocks.size())
        ws.block_gaps.resize(ws.blocks.size());
    if (ws.scratch.size() < runner.participants())
        ws.scratch.resize(runner.participants());
    auto body = [&](std::size_t b, unsigned participant) {
        const judge_workspace::line_block &lb = ws.blocks[b];
        const rule &r = set.rules[lb.rule];
        map_gap &part = ws.block_gaps[b];
        part = map_gap{};
        ws.scratch[participant].measure_lines(map, is_along(r), r.length, lb.first, lb.last, part);
    };
    run_blocks(runner, ws.blocks.size(), body);
    for (std::size_t b = 0; b < ws.blocks.size(); ++b)
        merge(gaps[ws.blocks[b].rule], ws.block_gaps[b]);
    finish(set, given, thickness, width, has_map, gaps, results);
}

}  // namespace verdict
}  // namespace flt
