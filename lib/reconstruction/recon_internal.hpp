// SPDX-License-Identifier: Apache-2.0
// Internal: what other components of the library may ask a flt_recon that
// its public header does not say.
#pragma once

#include "flatline/recon.h"

namespace flt {

// About how many knot intervals of strip the reconstructor takes beyond a
// row before the row is finished (its lag, emission groups and, in robust
// mode, every reweighted stage): the gauge sizes its buffers with it.
long recon_latency_knots(const flt_recon *recon);

}  // namespace flt
