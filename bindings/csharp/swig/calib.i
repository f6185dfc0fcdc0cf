// SPDX-License-Identifier: Apache-2.0
/* The calibration model (include/flatline/calib.h). */
%{
#include "flatline/calib.h"
%}

FLT_CS_HANDLE(flt_calib, CalibHandle)

/* The target enum stays internal; the public CalibrationTarget mirrors it. */
%rename(NativeTarget) flt_calib_target;

/* Intrinsics from target images: one pointer per view, each pinned by the
 * caller (src/Calibration.cs). */
%typemap(ctype) const uint8_t *const *images "const uint8_t *const *"
%typemap(imtype) const uint8_t *const *images "global::System.IntPtr*"
%typemap(cstype) const uint8_t *const *images "global::System.IntPtr*"
%typemap(in) const uint8_t *const *images %{ $1 = ($1_ltype)$input; %}
%typemap(csin) const uint8_t *const *images "$csinput"

/* flt_calib_save_text writes into a caller buffer of bytes. */
%typemap(ctype) char *text_out "char *"
%typemap(imtype) char *text_out "byte*"
%typemap(cstype) char *text_out "byte*"
%typemap(in) char *text_out %{ $1 = $input; %}
%typemap(csin) char *text_out "$csinput"

%include "flatline/calib.h"
