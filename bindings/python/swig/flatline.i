// SPDX-License-Identifier: Apache-2.0
/*
 * The low-level module flatline.capi (SWIG's proxy capi.py over the
 * extension _capi.so), generated from the public C headers. User code imports
 * the `flatline` package, whose classes wrap this module; flatline.capi is
 * the raw C API and may change with it. (The name has no leading underscore:
 * SWIG would name the extension __capi, which Python mangles inside the
 * proxy's class bodies.)
 *
 * Layout: this file sets up numpy and the shared error handling, then
 * includes one interface file per component. A new component adds
 * `%include "<component>.i"` at the end, and in that file:
 *   - %include its public header (plain functions with scalar arguments and
 *     `out` pointers are wrapped as they are, by the typemaps of common.i);
 *   - %ignore the functions that take arrays, and replace them by %extend
 *     methods or small helpers whose arguments follow numpy.i's patterns and
 *     that release the GIL around the C call;
 *   - declare its handle as a struct with a %extend destructor, so the
 *     Python object owns it.
 */
%module(package="flatline") capi

%{
#define SWIG_FILE_WITH_INIT
#include "flatline/flatline.h"
%}

/* numpy.i ships with numpy (Debian: python3-numpy, in numpy's include
 * directory under numpy/). */
%include "numpy.i"
%init %{
  import_array();
%}

/* 64-bit dimensions everywhere (numpy.i instantiates int only). */
%numpy_typemaps(double, NPY_DOUBLE, size_t)
%numpy_typemaps(unsigned char, NPY_UBYTE, size_t)
%numpy_typemaps(unsigned short, NPY_USHORT, size_t)  /* 10..16-bit frames */

/* uint32_t (frame sizes) as a checked unsigned int. */
%include "stdint.i"

%include "common.i"
%include "recon.i"
%include "calib.i"
%include "extractor.i"
%include "sim.i"
%include "flatness.i"
%include "source.i"
%include "verdict.i"  /* before the gauge: its sheets have verdicts */
%include "record.i"   /* before the gauge: it records, archives and names coils */
%include "gauge.i"
%include "genicam.i"
%include "advisor.i"
%include "log.i"
