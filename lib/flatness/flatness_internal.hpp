// SPDX-License-Identifier: Apache-2.0
// Internal: what other components of the library (the gauge) may ask of a
// flatness handle that its public header does not say, in C++.
#pragma once

#include "flatline/flatness.h"
#include "flatness/metrics.hpp"

namespace flt {

// The last window evaluated (what flt_flatness_window, _fiber_results,
// _zone_results, _fiber_positions, _zone_positions, _shape and _strip
// report), read in place. Valid until the handle evaluates again. Throws
// flt::error (FLT_ERR_INTERNAL) when no window has been evaluated.
const window_result &flatness_result_of(const flt_flatness *flatness);

// The threads its evaluations run the fibers on, in blocks (null: the
// caller's alone). Allocates a column scratch per participant; the runner
// must outlive every later evaluation. The results do not depend on it.
void flatness_use_runner(flt_flatness *flatness, block_runner *runner);

}  // namespace flt
