// SPDX-License-Identifier: Apache-2.0
// Internal: a rule set of flatness tolerances (flatline/verdict.h, "Rule
// files").
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "flatline/verdict.h"

namespace flt {
namespace verdict {

struct band {
    double thickness_min, thickness_max;  // mm, min <= t < max
    double width_min, width_max;          // mm, min <= w < max
    double limit;                         // the measure's unit, > 0
};

struct rule {
    std::string name;
    flt_measure measure;
    double length;  // mm, straightedge measures; 0 otherwise
    std::vector<band> bands;

    // The index of the band covering a sheet, or -1.
    int band_of(double thickness, double width) const;
};

struct rule_set {
    std::string name;
    std::vector<rule> rules;
};

// Reads a rule file's text; throws flt::error(FLT_ERR_FORMAT) naming the
// field at fault.
rule_set read_rules(const char *text, std::size_t length);

bool is_straightedge(flt_measure m);

}  // namespace verdict
}  // namespace flt

struct flt_rules {
    static constexpr unsigned k_magic = 0x464c5452u;  // "FLTR"
    unsigned magic = k_magic;
    // A sheet's rules (flt_sheet_verdict): owned by the gauge, not destroyed.
    bool borrowed = false;
    flt::verdict::rule_set set;
};
