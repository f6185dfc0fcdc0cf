// SPDX-License-Identifier: Apache-2.0
// Internal: what other components of the library may ask of a calibration
// that its public header does not say, in C++.
#pragma once

#include "flatline/calib.h"

namespace flt {

// A private copy of a calibration (the whole model, finished as it is), so
// that a component never depends on the caller's handle staying alive:
// the same numbers, without a trip through the text form. Throws
// std::bad_alloc; freed with flt_calib_destroy.
flt_calib *copy_calib(const flt_calib *calib);

}  // namespace flt
