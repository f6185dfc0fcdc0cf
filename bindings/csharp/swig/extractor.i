// SPDX-License-Identifier: Apache-2.0
/* The frame-to-profile extractor (include/flatline/extractor.h). */
%{
#include "flatline/extractor.h"
%}

FLT_CS_HANDLE(flt_extractor, ExtractorHandle)

/* The frame: a byte[,] or ushort[,] pinned by the caller with `fixed`. */
%typemap(ctype) const void *frame "const void *"
%typemap(imtype) const void *frame "void*"
%typemap(cstype) const void *frame "void*"
%typemap(in) const void *frame %{ $1 = ($1_ltype)$input; %}
%typemap(csin) const void *frame "$csinput"

/* flt_pixel_format travels as an int (common.i); the public PixelFormat
 * takes its values from the generated enum. */
/* The strip's flags and the saturation counts: raw pointers the public
 * class passes as &local (flatness.i's FLT_CS_OUT_POINTER pattern; that
 * macro is defined after this file). */
%typemap(ctype) unsigned *strip_flags_out "unsigned *"
%typemap(imtype) unsigned *strip_flags_out "uint*"
%typemap(cstype) unsigned *strip_flags_out "uint*"
%typemap(in) unsigned *strip_flags_out %{ $1 = ($1_ltype)$input; %}
%typemap(csin) unsigned *strip_flags_out "$csinput"
%typemap(ctype) size_t *peaks_out, size_t *saturated_out "size_t *"
%typemap(imtype) size_t *peaks_out, size_t *saturated_out "ulong*"
%typemap(cstype) size_t *peaks_out, size_t *saturated_out "ulong*"
%typemap(in) size_t *peaks_out, size_t *saturated_out %{ $1 = ($1_ltype)$input; %}
%typemap(csin) size_t *peaks_out, size_t *saturated_out "$csinput"

%rename(NativePixelFormat) flt_pixel_format;
%ignore FLT_PIXEL_MAX_ENUM_;

%include "flatline/extractor.h"
