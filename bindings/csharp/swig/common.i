// SPDX-License-Identifier: Apache-2.0
/*
 * Conventions shared by every component (include/flatline/common.h):
 * status codes, errors, strings, sizes, handles, arrays, options, version.
 */
%{
#include "flatline/common.h"
%}

/* Every generated class is internal: the public API is hand-written. */
%pragma(csharp) moduleclassmodifiers = "internal static unsafe class"
%pragma(csharp) imclassclassmodifiers = "internal unsafe class"
%typemap(csclassmodifiers) SWIGTYPE, SWIGTYPE *, SWIGTYPE &, SWIGTYPE [] "internal class"
%typemap(csclassmodifiers) enum SWIGTYPE "internal enum"
/* Constants and enum values become C# compile-time constants. */
%csconst(1);

/* The export macros are for the C compiler, not for SWIG. */
#define FLT_API
#define FLT_CALL
#define FLT_NODISCARD

/* uint8_t, uint16_t, uint32_t are their C types to SWIG (uint32_t -> uint). */
%include <stdint.i>

/* ---- status codes: one place turns a failed status into an exception ---- */
%typemap(ctype) flt_status "int"
%typemap(imtype) flt_status "int"
%typemap(cstype) flt_status "void"
%typemap(out) flt_status %{ $result = (int)$1; %}
%typemap(csout, excode=SWIGEXCODE) flt_status {
    Errors.Check($imcall);
  }
/* ...except where a status is a value: flt_last_error_status() returns one
 * and flt_status_string() takes one. */
%typemap(cstype) flt_status flt_last_error_status "int"
%typemap(csout, excode=SWIGEXCODE) flt_status flt_last_error_status {
    return $imcall;
  }
%typemap(ctype) flt_status status "int"
%typemap(imtype) flt_status status "int"
%typemap(cstype) flt_status status "int"
%typemap(in) flt_status status %{ $1 = (flt_status)$input; %}
%typemap(csin) flt_status status "$csinput"

/* The status enum is generated from the header, so new codes appear by
 * themselves; Status (public, hand-written) mirrors it and a test checks
 * that they agree. */
%rename(NativeStatus) flt_status;
/* The sentinels that make the enums span int are not values. */
%ignore FLT_STATUS_MAX_ENUM_;
%ignore FLT_OPT_MAX_ENUM_;

/* ---- sizes: size_t is 64-bit on every platform we ship ---- */
%typemap(ctype) size_t "size_t"
%typemap(imtype) size_t "global::System.UIntPtr"
%typemap(cstype) size_t "ulong"
%typemap(in) size_t %{ $1 = $input; %}
%typemap(out) size_t %{ $result = $1; %}
%typemap(csin) size_t "new global::System.UIntPtr($csinput)"
%typemap(csout, excode=SWIGEXCODE) size_t {
    return (ulong)$imcall;
  }
/* size_t outputs: `out UIntPtr` marshals as a pointer to a pointer-sized
 * integer, which is exactly a size_t *. */
%define FLT_CS_OUT_SIZE(NAMES...)
%typemap(ctype) NAMES "size_t *"
%typemap(imtype) NAMES "out global::System.UIntPtr"
%typemap(cstype) NAMES "out global::System.UIntPtr"
%typemap(in) NAMES %{ $1 = $input; %}
%typemap(csin) NAMES "out $csinput"
%enddef
FLT_CS_OUT_SIZE(size_t *out, size_t *rows_out, size_t *count_out, size_t *length_out)

/* ---- scalar outputs ---- */
%define FLT_CS_OUT_SCALAR(CTYPE, CSTYPE, NAMES...)
%typemap(ctype) NAMES "CTYPE *"
%typemap(imtype) NAMES "out CSTYPE"
%typemap(cstype) NAMES "out CSTYPE"
%typemap(in) NAMES %{ $1 = $input; %}
%typemap(csin) NAMES "out $csinput"
%enddef
FLT_CS_OUT_SCALAR(double, double, double *out, double *min_out, double *max_out,
                  double *default_out, double *bytes_out)
FLT_CS_OUT_SCALAR(int, int, int *is_integer_out, int *out, int *value_out)
FLT_CS_OUT_SCALAR(uint32_t, uint, uint32_t *width_out, uint32_t *height_out,
                  uint32_t *first_row_out, uint32_t *rows_out)

/* ---- arrays: raw pointers, pinned by the caller (`fixed` works for
 * double[] and double[,] alike, and gives NULL for a null array). Fixed-size
 * parameters (const double h[9]) are pointers too; the caller checks the
 * length. ---- */
%define FLT_CS_ARRAY(CTYPE, CSTYPE)
%typemap(ctype) CTYPE *, const CTYPE *, CTYPE [ANY], const CTYPE [ANY] "CTYPE *"
%typemap(imtype) CTYPE *, const CTYPE *, CTYPE [ANY], const CTYPE [ANY] "CSTYPE*"
%typemap(cstype) CTYPE *, const CTYPE *, CTYPE [ANY], const CTYPE [ANY] "CSTYPE*"
%typemap(in) CTYPE *, const CTYPE *, CTYPE [ANY], const CTYPE [ANY] %{ $1 = ($1_ltype)$input; %}
%typemap(csin) CTYPE *, const CTYPE *, CTYPE [ANY], const CTYPE [ANY] "$csinput"
%enddef
FLT_CS_ARRAY(double, double)
FLT_CS_ARRAY(uint8_t, byte)
FLT_CS_ARRAY(uint16_t, ushort)

/* ---- strings: UTF-8 both ways, whatever the platform's ANSI code page ---- */
%typemap(ctype) const char * "const char *"
%typemap(imtype) const char * "byte[]"
%typemap(cstype) const char * "string"
%typemap(in) const char * %{ $1 = ($1_ltype)$input; %}
%typemap(csin) const char * "Utf8.Encode($csinput)"
/* Returned strings are static or thread-local in the library: read, not freed. */
%typemap(imtype, out="global::System.IntPtr") const char * "byte[]"
%typemap(out) const char * %{ $result = (char *)$1; %}
%typemap(csout, excode=SWIGEXCODE) const char * {
    return Utf8.Decode($imcall);
  }
/* A static name returned through an output argument. */
%typemap(ctype) const char **name, const char **name_out "const char **"
%typemap(imtype) const char **name, const char **name_out "out global::System.IntPtr"
%typemap(cstype) const char **name, const char **name_out "out global::System.IntPtr"
%typemap(in) const char **name, const char **name_out %{ $1 = ($1_ltype)$input; %}
%typemap(csin) const char **name, const char **name_out "out $csinput"

/* ---- handles: each opaque flt_x becomes a SafeHandle subclass (written in
 * ../src/Handles.cs) passed by the P/Invoke marshaller, which keeps it alive
 * and refuses it once disposed. flt_x_destroy is reached through
 * flt_x_destroy_handle(IntPtr), since SafeHandle.ReleaseHandle() cannot pass
 * the (already closed) SafeHandle itself. ---- */
%define FLT_CS_HANDLE(CTYPE, CSHANDLE)
%typemap(ctype) CTYPE *, const CTYPE * "void *"
%typemap(imtype) CTYPE *, const CTYPE * "CSHANDLE"
%typemap(cstype) CTYPE *, const CTYPE * "CSHANDLE"
%typemap(in) CTYPE *, const CTYPE * %{ $1 = ($1_ltype)$input; %}
%typemap(csin) CTYPE *, const CTYPE * "$csinput"
%typemap(ctype) CTYPE ** "void **"
%typemap(imtype) CTYPE ** "out CSHANDLE"
%typemap(cstype) CTYPE ** "out CSHANDLE"
%typemap(in) CTYPE ** %{ $1 = ($1_ltype)$input; %}
%typemap(csin) CTYPE ** "out $csinput"
%ignore CTYPE##_destroy;
%inline %{
void CTYPE##_destroy_handle(void *handle) { CTYPE##_destroy((CTYPE *)handle); }
%}
%enddef

%typemap(ctype) void *handle "void *"
%typemap(imtype) void *handle "global::System.IntPtr"
%typemap(cstype) void *handle "global::System.IntPtr"
%typemap(in) void *handle %{ $1 = $input; %}
%typemap(csin) void *handle "$csinput"

/* ---- options: keys are plain ints here; the public FlatlineOptions finds
 * them by name, so a key added to the C enum needs no binding change ---- */
%typemap(ctype) flt_option "int"
%typemap(imtype) flt_option "int"
%typemap(cstype) flt_option "int"
%typemap(in) flt_option %{ $1 = (flt_option)$input; %}
%typemap(csin) flt_option "$csinput"
%typemap(ctype) flt_option *out "int *"
%typemap(imtype) flt_option *out "out int"
%typemap(cstype) flt_option *out "out int"
%typemap(in) flt_option *out %{ $1 = (flt_option *)$input; %}
%typemap(csin) flt_option *out "out $csinput"
%rename(NativeOption) flt_option;

/* ---- pixel formats (flt_pixel_format, extractor.h; used by the simulator
 * and the extractor): plain ints, the number of significant bits; the public
 * PixelFormat enum carries the same values ---- */
%typemap(ctype) flt_pixel_format "int"
%typemap(imtype) flt_pixel_format "int"
%typemap(cstype) flt_pixel_format "int"
%typemap(in) flt_pixel_format %{ $1 = (flt_pixel_format)$input; %}
%typemap(csin) flt_pixel_format "$csinput"
%typemap(ctype) flt_pixel_format *out "int *"
%typemap(imtype) flt_pixel_format *out "out int"
%typemap(cstype) flt_pixel_format *out "out int"
%typemap(in) flt_pixel_format *out %{ $1 = (flt_pixel_format *)$input; %}
%typemap(csin) flt_pixel_format *out "out $csinput"

%{
#include "flatline/common.h"
%}
FLT_CS_HANDLE(flt_options, OptionsHandle)

%include "flatline/version.h"
%include "flatline/common.h"
