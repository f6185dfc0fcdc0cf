// SPDX-License-Identifier: Apache-2.0
// Internal: what other components of the library (the gauge) may ask of a
// reconstructor that its public header does not say, in C++.
#pragma once

#include "flatline/recon.h"
#include "reconstruction/pipeline.hpp"

namespace flt {

// About how many knot intervals of strip the reconstructor takes beyond a
// row before the row is finished, at most (its lag and emission group, the
// knots a row spans; at a strip's head its longer wait): the gauge sizes its
// buffers with it.
long recon_latency_knots(const flt_recon *recon);
// The same for a reconstructor not made yet, from its configuration
// (recon_read_config).
long recon_latency_knots(const recon_config &config);

// The laser spacing (mm) flt_recon_create_from_calib takes from calib, with
// its checks and messages (fn names the caller): the calibration finished,
// the spacing within laser_spacing's bounds, the option (if set) agreeing.
flt_status recon_calib_laser_spacing(const char *fn, const flt_calib *calib,
                                     const flt_options *options, double *out);

// The reconstructor's configuration as flt_recon_create would read it from
// options (and a calibration's laser spacing, or 0 for the option's), with
// its checks and messages (fn names the caller): its latency
// (config.params.latency_bound_mm(), head_latency_bound_mm(); in knots
// recon_latency_knots(config)) without creating one.
flt_status recon_read_config(const char *fn, const flt_options *options, double laser_spacing,
                             recon_config *out);

// The handle's C++ side: push_row, pull, peek (a pending row's provisional
// value), ready_rows, end_sheet, without the public API's checks and
// status conversions. The caller keeps the API's contract (rows in order,
// fibers right, room in the ring); the off-strip bits of
// flt_recon_push_flagged are the API's (recon_api.cpp), so a caller that
// needs them masks its own output.
recon_pipeline &recon_pipeline_of(flt_recon *recon);

}  // namespace flt
