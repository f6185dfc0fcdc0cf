// SPDX-License-Identifier: Apache-2.0
/*
 * The testing tier (include/flatline/testing.h, libflatline_testing) for C#:
 * a SWIG module of its own, FlatlineTestingNative, over a glue library of
 * its own, flatline_testing_csharp. P/Invoke binds a library at its first
 * call, so a program that never touches Flatline.Testing never loads
 * libflatline_testing. The main module is imported for its conventions
 * (status -> exception, handles, strings) and types, not wrapped again.
 */
%module FlatlineTestingNative

%pragma(csharp) moduleclassmodifiers = "internal static unsafe class"
%pragma(csharp) imclassclassmodifiers = "internal unsafe class"
%csconst(1);

%import "flatline.i"

%{
#include "flatline/flatline.h"
#include "flatline/testing.h"
%}

#define FLT_TESTING_API

FLT_CS_HANDLE(flt_u3v_sim, U3VSimHandle)
/* Named apart from the enums the main module generated before the testing
 * tier moved out (a stale file of theirs may linger in a build tree). */
FLT_CS_INT_ENUM(flt_u3v_sim_param, NativeSimParam)
FLT_CS_INT_ENUM(flt_u3v_fault, NativeSimFault)
%ignore FLT_U3V_SIM_PARAM_MAX_ENUM_;
%ignore FLT_U3V_FAULT_MAX_ENUM_;

FLT_CS_OUT_POINTER(uint64_t, ulong, uint64_t *out)
FLT_CS_OUT_POINTER(uint32_t, uint, uint32_t *out)
/* The transport belongs to its bus: an IntPtr, passed on to
 * flt_source_open_u3v / flt_camera_list_create while the bus lives. */
%typemap(ctype) flt_usb_transport **out "void **"
%typemap(imtype) flt_usb_transport **out "out global::System.IntPtr"
%typemap(cstype) flt_usb_transport **out "out global::System.IntPtr"
%typemap(in) flt_usb_transport **out %{ $1 = ($1_ltype)$input; %}
%typemap(csin) flt_usb_transport **out "out $csinput"

/* The hidden leveler (flt_leveler_sim) closes the advisor's loop in the C
 * tests and examples/advisor_loop; it is not bound. */
%ignore flt_leveler_sim;
%ignore flt_leveler_sim_create;
%ignore flt_leveler_sim_destroy;
%ignore flt_leveler_sim_set_settings;
%ignore flt_leveler_sim_set_incoming;
%ignore flt_leveler_sim_next_sheet;

%include "flatline/testing.h"
