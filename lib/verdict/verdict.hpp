// SPDX-License-Identifier: Apache-2.0
// Internal: a verdict (flatline/verdict.h) and the evaluation of one sheet
// against every rule, shared by flt_verdict_evaluate and the gauge, which
// judges each finished sheet (lib/gauge) without allocating.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

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

// Judging a sheet in pieces (what judge() does on one thread; the pieces
// let the lines of each straightedge rule be measured in blocks on several
// threads):
//   1. for every rule i with gap_source(...) == i: gaps[i] = map_gap{}, then
//      for blocks [a, b) covering 0 .. line_count(map, is_along(rule i)),
//      each with its own straightedge scratch and map_gap part:
//      scratch.measure_lines(map, is_along(rule i), rule i's length, a, b,
//      part), then merge(gaps[i], part) (in any order; map_gap says when
//      the result is the same bit for bit);
//   2. finish(): the rules' results from the gaps and the given measures.
// Rules sharing a straightedge measure and length share one computation.

// The rule whose map gap rule i reads: the first rule (i itself, or an
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

// The results of every rule into results[set.rules.size()] from the gaps
// measured (gaps[gap_source(i)]) and the measures given.
void finish(const rule_set &set, const given_measure *given, double thickness, double width,
            bool has_map, const map_gap *gaps, rule_result *results);

// Judges one sheet against every rule of `set` into results[set.rules.size()],
// with gaps[set.rules.size()] as scratch: the pieces above on this thread.
// thickness > 0; a width that is not > 0 (NaN: the sheet's strip was not
// seen) leaves every rule NOT_MEASURED. Allocates nothing but the
// straightedge's growth (none once it was reserved for the longest line and
// the most lines).
void judge(const rule_set &set, const given_measure *given, straightedge &se, double thickness,
           double width, const map_view &map, rule_result *results, map_gap *gaps);

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
    flt::verdict::straightedge scratch;
};
