// SPDX-License-Identifier: Apache-2.0
// Internal: frames rendered by a simulator (flt_sim), one per call.
#pragma once

#include <memory>

#include "flatline/sim.h"
#include "sources/source.hpp"

namespace flt::sources {

// `sim` is borrowed (it must outlive the source). Throws
// FLT_ERR_INVALID_ARGUMENT when the simulator cannot say its frame size.
std::unique_ptr<source_impl> make_sim_source(flt_sim *sim);

}  // namespace flt::sources
