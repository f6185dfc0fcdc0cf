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
%rename(NativePixelFormat) flt_pixel_format;
%ignore FLT_PIXEL_MAX_ENUM_;

%include "flatline/extractor.h"
