// SPDX-License-Identifier: Apache-2.0
// Internal: the leveler's model (its actuators, the influence matrix G, the
// target profile) and the reader of leveler files (flatline/advisor.h,
// "Leveler files").
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace flt {
namespace advisor {

struct actuator {
    std::string name, unit;  // name empty: not described yet
    double min = 0, max = 0, step = 0;
    bool described() const { return !name.empty(); }
};

struct leveler_model {
    std::size_t zones = 0;
    std::vector<actuator> actuators;
    std::vector<double> g;       // [zones * actuators], row-major
    std::vector<double> target;  // [zones]
};

// Largest name / unit in bytes (flatline/advisor.h).
constexpr std::size_t k_max_name = 63;
constexpr std::size_t k_max_unit = 15;

// Reads version 1 of a leveler file; throws flt::error(FLT_ERR_FORMAT)
// naming the field and its line.
leveler_model read_leveler(const char *text, std::size_t length);

}  // namespace advisor
}  // namespace flt
