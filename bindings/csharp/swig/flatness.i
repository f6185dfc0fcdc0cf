// SPDX-License-Identifier: Apache-2.0
/* Flatness metrics (include/flatline/flatness.h). */
%{
#include "flatline/flatness.h"
%}

FLT_CS_HANDLE(flt_flatness, FlatnessHandle)

/* The shape class travels as its int value; the public ShapeClass enum
 * takes its values from the generated NativeShape. */
%rename(NativeShape) flt_shape;
%ignore FLT_SHAPE_MAX_ENUM_;
/* The I-Unit references stay internal; the public FlatReference mirrors them. */
%rename(NativeFlatReference) flt_flat_reference;
%ignore FLT_FLAT_REFERENCE_MAX_ENUM_;
%rename(NativeSide) flt_side;
%ignore FLT_SIDE_MAX_ENUM_;
%rename(NativeZonesOn) flt_zones_on;
%ignore FLT_ZONES_ON_MAX_ENUM_;
%typemap(ctype) flt_shape "int"
%typemap(imtype) flt_shape "int"
%typemap(cstype) flt_shape "int"
%typemap(in) flt_shape %{ $1 = (flt_shape)$input; %}
%typemap(csin) flt_shape "$csinput"

/* Outputs are raw pointers like the arrays (common.i): the public class
 * passes &local for single values and pinned arrays for per-fiber and
 * per-zone results, or null where a result is not wanted. */
%define FLT_CS_OUT_POINTER(CTYPE, CSTYPE, NAMES...)
%typemap(ctype) NAMES "CTYPE *"
%typemap(imtype) NAMES "CSTYPE*"
%typemap(cstype) NAMES "CSTYPE*"
%typemap(in) NAMES %{ $1 = ($1_ltype)$input; %}
%typemap(csin) NAMES "$csinput"
%enddef
FLT_CS_OUT_POINTER(size_t, ulong, size_t *fiber_count_out, size_t *consumed_out, size_t *index_out)
FLT_CS_OUT_POINTER(flt_shape, int, flt_shape *shape_out)
FLT_CS_OUT_POINTER(unsigned, uint, unsigned *window_flags_out, unsigned *components_out)
FLT_CS_OUT_POINTER(int, int, int *evaluated_out)
/* rows_out is an `out UIntPtr` in common.i (the recon and calib uses). */

%include "flatline/flatness.h"
