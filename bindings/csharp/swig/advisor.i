// SPDX-License-Identifier: Apache-2.0
/* The leveler advisor (include/flatline/advisor.h). Arrays are pinned
 * pointers (common.i); scalar outputs `out` parameters. */
%{
#include "flatline/advisor.h"
%}

FLT_CS_HANDLE(flt_advisor, AdvisorHandle)
FLT_CS_OUT_SIZE(size_t *zones_out, size_t *actuators_out, size_t *steps_out)
FLT_CS_OUT_SCALAR(double, double, double *min_out, double *max_out, double *step_out,
                  double *r_squared_out, double *rms_out, double *confidence_out)
%typemap(ctype) const char **unit_out "const char **"
%typemap(imtype) const char **unit_out "out global::System.IntPtr"
%typemap(cstype) const char **unit_out "out global::System.IntPtr"
%typemap(in) const char **unit_out %{ $1 = ($1_ltype)$input; %}
%typemap(csin) const char **unit_out "out $csinput"

%include "flatline/advisor.h"
