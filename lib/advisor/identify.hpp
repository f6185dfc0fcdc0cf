// SPDX-License-Identifier: Apache-2.0
// Internal: G identified from logged steps by ridge-regularised least
// squares (flatline/advisor.h, "Identification").
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace flt {
namespace advisor {

struct identification {
    bool accepted = false;
    std::string why;        // the reason of a refusal
    std::vector<double> g;  // [zones * actuators], row-major, when computed
    double r_squared = 0, rms = 0;
    bool fitted = false;  // false: refused before fitting (too few steps, degenerate)
};

// du [steps * actuators], dp [steps * zones]; ridge relative (>= 0).
identification identify(std::size_t zones, std::size_t actuators, std::size_t steps,
                        const double *du, const double *dp, double ridge, double min_r_squared);

}  // namespace advisor
}  // namespace flt
