// SPDX-License-Identifier: Apache-2.0
/* Rule sets of flatness tolerances, the straightedge deviation and
 * verdicts (include/flatline/verdict.h). Arrays are pinned pointers
 * (common.i); outputs raw pointers (flatness.i's FLT_CS_OUT_POINTER). */
%{
#include "flatline/verdict.h"
%}

FLT_CS_HANDLE(flt_rules, RulesHandle)
FLT_CS_HANDLE(flt_verdict, VerdictHandle)
FLT_CS_INT_ENUM(flt_measure, NativeMeasure)
FLT_CS_INT_ENUM(flt_verdict_state, NativeVerdictState)
FLT_CS_INT_ENUM(flt_verdict_value, NativeVerdictValue)
%ignore FLT_MEASURE_MAX_ENUM_;
%ignore FLT_VERDICT_STATE_MAX_ENUM_;
%ignore FLT_VERDICT_VALUE_MAX_ENUM_;

FLT_CS_OUT_POINTER(int, int, flt_measure *measure_out)
FLT_CS_OUT_POINTER(double, double, double *length_mm_out, double *deviation_mm_out, double *at_mm_out)

%include "flatline/verdict.h"
