// SPDX-License-Identifier: Apache-2.0
// Internal: a verdict (flatline/verdict.h) and the evaluation of one sheet
// against every rule, shared by flt_verdict_evaluate and the gauge, which
// judges each finished sheet (lib/gauge) without allocating.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/block_runner.hpp"
#include "flatline/verdict.h"
#include "verdict/rules.hpp"
#include "verdict/straightedge.hpp"

namespace flt {
namespace verdict {

constexpr int k_measures = 7;  // flt_measure values
constexpr int k_values = 9;    // flt_verdict_value keys

struct rule_result {
    double value[k_values];
};

// A flatness measure given for the next evaluation (NaN: not measured).
struct given_measure {
    double value = std::numeric_limits<double>::quiet_NaN();
    double x = std::numeric_limits<double>::quiet_NaN();
    double s = std::numeric_limits<double>::quiet_NaN();
};

// Rules sharing a straightedge measure and length share one computation:
// the rule whose map gap rule i reads is the first rule (i itself, or an
// earlier one) of the same straightedge measure and length whose band
// applies to the sheet; k_no_line when rule i needs no map gap (not a
// straightedge, no map, no band, width unknown).
std::size_t gap_source(const rule_set &set, std::size_t i, double thickness, double width,
                       bool has_map);

// Whether rule i's straightedge lies along the strip (over fibers) rather
// than across it (over rows).
inline bool is_along(const rule &r) {
    return r.measure == FLT_MEASURE_STRAIGHTEDGE_ALONG;
}

// The room judge() works in: a straightedge per participant of the block
// runner, and per block of lines its rule, its lines [first, last) and its
// partial gap. reserve() makes room for the longest line and the most
// blocks; judge() then allocates nothing (it grows what is short, for a
// caller that did not reserve: flt_verdict_evaluate).
struct judge_workspace {
    struct line_block {
        std::size_t rule, first, last;
    };
    std::vector<straightedge> scratch;  // [participants]
    std::vector<line_block> blocks;
    std::vector<map_gap> block_gaps;  // [blocks]

    // For `rules` rules, lines of up to `longest_line` samples, and
    // `participants` blocks at a time.
    void reserve(std::size_t rules, std::size_t longest_line, unsigned participants);
};

// Judges one sheet against every rule of `set` into results[set.rules.size()],
// with gaps[set.rules.size()] as scratch. Each straightedge rule's lines
// are measured in blocks through `runner` (on whatever threads it has;
// inline_block_runner: this one), merged in block order, so the results
// are the same bit for bit whatever the runner; then every rule's result
// from the gaps and the measures given. thickness > 0; a width that is not
// > 0 (NaN: the sheet's strip was not seen) leaves every rule NOT_MEASURED.
void judge(const rule_set &set, const given_measure *given, judge_workspace &ws,
           block_runner &runner, double thickness, double width, const map_view &map,
           rule_result *results, map_gap *gaps);

// Whether any rule of the set needs the height map.
bool needs_map(const rule_set &set);

}  // namespace verdict
}  // namespace flt

struct flt_verdict {
    static constexpr unsigned k_magic = 0x464c5456u;  // "FLTV"
    unsigned magic = k_magic;
    // A sheet's verdict (flt_sheet_verdict): read-only, owned by the gauge.
    bool borrowed = false;
    flt::verdict::rule_set set;
    flt::verdict::given_measure given[flt::verdict::k_measures];
    std::vector<flt::verdict::rule_result> results, pending;  // [rules] each
    std::vector<flt::verdict::map_gap> gaps;                  // [rules]
    bool evaluated = false;
    flt::verdict::judge_workspace workspace;
};
