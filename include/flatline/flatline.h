// SPDX-License-Identifier: Apache-2.0
/** @file
 * libflatline - online flatness gauge for steel strip from a dual-line-laser
 * and camera sensor. This umbrella header includes every public header.
 */
#ifndef FLATLINE_FLATLINE_H
#define FLATLINE_FLATLINE_H

#include "flatline/version.h"
#include "flatline/common.h"
#include "flatline/recon.h"
#include "flatline/calib.h"
#include "flatline/extractor.h"
#include "flatline/sim.h"
#include "flatline/flatness.h"
#include "flatline/source.h"
#include "flatline/gauge.h"
#include "flatline/genicam.h"
#include "flatline/verdict.h"
#include "flatline/advisor.h"
#include "flatline/log.h"
#include "flatline/coil.h"
#include "flatline/record.h"

#endif /* FLATLINE_FLATLINE_H */
