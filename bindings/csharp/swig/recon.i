// SPDX-License-Identifier: Apache-2.0
/* The streaming Hermite reconstructor (include/flatline/recon.h). */
%{
#include "flatline/recon.h"
%}

FLT_CS_HANDLE(flt_recon, ReconHandle)

/* The robust modes stay internal; the public RobustMode mirrors them. */
%rename(NativeRobust) flt_robust;
%ignore FLT_ROBUST_MAX_ENUM_;

%include "flatline/recon.h"
