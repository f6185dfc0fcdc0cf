// SPDX-License-Identifier: Apache-2.0
/*
 * SWIG interface of the C# binding: the main module.
 *
 * SWIG generates an internal layer (namespace Flatline): the P/Invoke class
 * FlatlineNativePINVOKE, the module class FlatlineNative with one static
 * method per C function, and the C glue (flatline_wrap.c, built into
 * libflatline_csharp). Nothing generated is public: the public classes
 * (Reconstructor, FlatlineOptions, Library, ...) are hand-written in
 * ../src/ over this layer.
 *
 * Conventions of the generated layer, set in common.i:
 *   - a function returning flt_status returns void and throws the typed
 *     FlatlineException that Errors.Check() maps from the status and
 *     flt_last_error_message() (one place for every function);
 *   - handles are SafeHandle subclasses (FLT_CS_HANDLE);
 *   - arrays are raw pointers (double*, byte*) pinned by the caller with
 *     `fixed`, so double[,] passes without a copy;
 *   - size_t is ulong, strings are UTF-8 in both directions.
 *
 * One .i per component, in dependency order (recon.h uses calib.h, as do
 * extractor.h, sim.h and flatness.h; source.h extractor.h and sim.h, and
 * flatness.i defines FLT_CS_OUT_POINTER, which source.i uses; gauge.h uses
 * source.h, and source.i's FLT_CS_INT_ENUM and uint64_t outputs; genicam.i
 * uses source.i's FLT_CS_INT_ENUM and its `void *out` buffers).
 */
%module FlatlineNative

%include "common.i"
%include "calib.i"
%include "recon.i"
%include "extractor.i"
%include "sim.i"
%include "flatness.i"
%include "source.i"
%include "verdict.i"  /* before the gauge: its sheets have verdicts */
%include "record.i"   /* before the gauge: it archives into an flt_archive */
%include "gauge.i"
%include "genicam.i"
%include "advisor.i"
%include "log.i"
