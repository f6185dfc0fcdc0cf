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

// The worst straightedge gap of a map for one rule (shared by the rules of
// the same measure and length).
struct map_gap {
    double deviation = 0, x = 0, s = 0;
    bool measured = false, computed = false;
};

// A sheet's height map (rows == 0: none), already checked: positions
// strictly increasing, heights finite or NaN.
struct map_view {
    std::size_t rows = 0, fibers = 0;
    const double *s = nullptr, *x = nullptr, *z = nullptr;
    const std::uint8_t *flags = nullptr;
};

// Judges one sheet against every rule of `set` into results[set.rules.size()],
// with gaps[set.rules.size()] as scratch. thickness > 0; a width that is
// not > 0 (NaN: the sheet's strip was not seen) leaves every rule
// NOT_MEASURED. Allocates nothing but the straightedge's growth (none once
// it was reserved for the longest line).
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
