// SPDX-License-Identifier: Apache-2.0
/* The offline view of a camera description (include/flatline/genicam.h).
 * Everything but the register callbacks (flt_genicam_set_registers: the
 * public class gives register contents as a memory image). */
%{
#include "flatline/genicam.h"
%}

FLT_CS_HANDLE(flt_genicam, GenICamHandle)
FLT_CS_INT_ENUM(flt_genicam_type, NativeGenICamType)
FLT_CS_INT_ENUM(flt_genicam_access, NativeGenICamAccess)
FLT_CS_INT_ENUM(flt_genicam_text, NativeGenICamText)
%ignore FLT_GENICAM_TYPE_MAX_ENUM_;
%ignore FLT_GENICAM_ACCESS_MAX_ENUM_;
%ignore FLT_GENICAM_TEXT_MAX_ENUM_;
%ignore flt_genicam_set_registers;
%ignore flt_genicam_read_fn;
%ignore flt_genicam_write_fn;

/* Outputs are raw pointers (&local in CameraDescription.cs). */
FLT_CS_OUT_POINTER(int, int, flt_genicam_type *type_out, flt_genicam_access *out, int *implemented_out,
                   int *available_out, int *locked_out, int *big_endian_out)
FLT_CS_OUT_POINTER(uint64_t, ulong, uint64_t *address_out)
FLT_CS_OUT_POINTER(uint32_t, uint, uint32_t *length_out, uint32_t *lsb_out, uint32_t *msb_out)
FLT_CS_OUT_POINTER(int64_t, long, int64_t *min_out, int64_t *max_out, int64_t *inc_out, int64_t *value_out)
/* (double *min_out, *max_out: common.i's `out double`.) */
FLT_CS_OUT_POINTER(void, global::System.IntPtr, const char **kind_out, const char **unit_out)

/* Byte buffers (the description, register contents): pinned byte*. */
%typemap(ctype) const void *data, const void *bytes "void *"
%typemap(imtype) const void *data, const void *bytes "byte*"
%typemap(cstype) const void *data, const void *bytes "byte*"
%typemap(in) const void *data, const void *bytes %{ $1 = ($1_ltype)$input; %}
%typemap(csin) const void *data, const void *bytes "$csinput"

%include "flatline/genicam.h"
