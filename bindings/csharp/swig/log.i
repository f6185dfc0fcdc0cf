// SPDX-License-Identifier: Apache-2.0
/* The log (include/flatline/log.h): the callback is a function pointer the
 * public FlatlineLog makes from a delegate it keeps alive, the level an
 * int. */
%{
#include "flatline/log.h"
%}

FLT_CS_INT_ENUM(flt_log_level, NativeLogLevel)
%ignore FLT_LOG_LEVEL_MAX_ENUM_;
%typemap(ctype) flt_log_callback callback "flt_log_callback"
%typemap(imtype) flt_log_callback callback "global::System.IntPtr"
%typemap(cstype) flt_log_callback callback "global::System.IntPtr"
%typemap(in) flt_log_callback callback %{ $1 = ($1_ltype)$input; %}
%typemap(csin) flt_log_callback callback "$csinput"

%include "flatline/log.h"
