// SPDX-License-Identifier: Apache-2.0
/* The simulated sensor (include/flatline/sim.h). */
%{
#include "flatline/sim.h"
%}

FLT_CS_HANDLE(flt_sim, SimHandle)

%rename(NativeDefect) flt_sim_defect;
%rename(NativeSimSurround) flt_sim_surround;
%ignore FLT_SIM_SURROUND_MAX_ENUM_;
%ignore FLT_SIM_DEFECT_MAX_ENUM_;

/* Frames are written into a caller buffer pinned with `fixed` (byte[,] or
 * ushort[,], by the pixel format). */
%typemap(ctype) void *frame_out "void *"
%typemap(imtype) void *frame_out "void*"
%typemap(cstype) void *frame_out "void*"
%typemap(in) void *frame_out %{ $1 = $input; %}
%typemap(csin) void *frame_out "$csinput"

/* flt_pixel_format (extractor.h, wrapped by extractor.i before this file)
 * travels as its int value; the public PixelFormat enum carries the same
 * values (8, 10, 12, 16 bits). */
%include "flatline/sim.h"
