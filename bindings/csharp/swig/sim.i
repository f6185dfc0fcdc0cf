/* The simulated sensor (include/flatline/sim.h). */
%{
#include "flatline/sim.h"
%}

FLT_CS_HANDLE(flt_sim, SimHandle)

%rename(NativeDefect) flt_sim_defect;
%ignore FLT_SIM_DEFECT_MAX_ENUM_;

/* Frames are written into a caller buffer pinned with `fixed` (byte[,] or
 * ushort[,], by the pixel format). */
%typemap(ctype) void *frame_out "void *"
%typemap(imtype) void *frame_out "void*"
%typemap(cstype) void *frame_out "void*"
%typemap(in) void *frame_out %{ $1 = $input; %}
%typemap(csin) void *frame_out "$csinput"

/* sim.h includes extractor.h for flt_pixel_format only: %import gives SWIG
 * the type without wrapping the extractor's functions (that is
 * extractor.i's business). The format travels as its int value; the public
 * PixelFormat enum carries the same values (8, 10, 12, 16 bits). */
%import "flatline/extractor.h"

%include "flatline/sim.h"
