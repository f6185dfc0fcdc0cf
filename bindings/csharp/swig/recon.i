// SPDX-License-Identifier: Apache-2.0
/* The streaming Hermite reconstructor (include/flatline/recon.h). */
%{
#include "flatline/recon.h"
%}

FLT_CS_HANDLE(flt_recon, ReconHandle)

%include "flatline/recon.h"
