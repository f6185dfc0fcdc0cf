// SPDX-License-Identifier: Apache-2.0
/* Frame sources (include/flatline/source.h). The simulated USB3 Vision bus
 * of the testing tier is the module FlatlineTestingNative (testing.i). */
%{
#include "flatline/source.h"
%}

FLT_CS_HANDLE(flt_source, SourceHandle)
FLT_CS_HANDLE(flt_camera_list, CameraListHandle)
/* The USB transport: IntPtr.Zero for the real USB bus (libusb), else the
 * transport of a testing-tier bus (Flatline.Testing.U3VSimBus), which the
 * source holds alive through the bus's handle. */
%typemap(ctype) flt_usb_transport * "void *"
%typemap(imtype) flt_usb_transport * "global::System.IntPtr"
%typemap(cstype) flt_usb_transport * "global::System.IntPtr"
%typemap(in) flt_usb_transport * %{ $1 = ($1_ltype)$input; %}
%typemap(csin) flt_usb_transport * "$csinput"

/* The enums travel as their int values; the public enums take their values
 * from the generated Native* enums. */
%define FLT_CS_INT_ENUM(CTYPE, CSNAME)
%rename(CSNAME) CTYPE;
%typemap(ctype) CTYPE "int"
%typemap(imtype) CTYPE "int"
%typemap(cstype) CTYPE "int"
%typemap(in) CTYPE %{ $1 = (CTYPE)$input; %}
%typemap(csin) CTYPE "$csinput"
%enddef
FLT_CS_INT_ENUM(flt_source_kind, NativeSourceKind)
FLT_CS_INT_ENUM(flt_recorded_event, NativeRecordedEvent)
%ignore FLT_RECORDED_EVENT_MAX_ENUM_;
/* A recording's rows and events: read by Recording (Record.cs) and the
 * gauge's replay, not through a borrowed frame. */
%ignore flt_frame_row;
%ignore flt_frame_event_count;
%ignore flt_frame_event;
%ignore flt_frame_event_note;
FLT_CS_INT_ENUM(flt_source_counter, NativeCounter)
FLT_CS_INT_ENUM(flt_camera_string, NativeCameraString)
FLT_CS_INT_ENUM(flt_camera_value, NativeCameraValue)
FLT_CS_INT_ENUM(flt_encoder_mode, NativeEncoderMode)
%ignore FLT_ENCODER_MODE_MAX_ENUM_;
%ignore FLT_SOURCE_KIND_MAX_ENUM_;
%ignore FLT_COUNT_MAX_ENUM_;
%ignore FLT_CAMERA_STRING_MAX_ENUM_;
%ignore FLT_CAMERA_VALUE_MAX_ENUM_;

/* Outputs are raw pointers (&local in the public classes). */
FLT_CS_OUT_POINTER(int, int, flt_source_kind *out)
FLT_CS_OUT_POINTER(uint64_t, ulong, uint64_t *out, uint64_t *block_id_out, uint64_t *timestamp_ns_out)
FLT_CS_OUT_POINTER(int64_t, long, int64_t *out)
FLT_CS_OUT_POINTER(uint32_t, uint, uint32_t *speed_mbps_out)
/* (uint32_t *width_out, *height_out: common.i's `out uint`.) */
FLT_CS_OUT_POINTER(size_t, ulong, size_t *stride_bytes_out)
FLT_CS_OUT_POINTER(int, int, flt_pixel_format *format_out)
/* Library-owned strings and the borrowed frame and its pixels: IntPtrs. */
FLT_CS_OUT_POINTER(void, global::System.IntPtr,
                   const char **vendor_out, const char **model_out, const char **serial_out,
                   const char **out, const void **pixels_out, const flt_frame **out)
%typemap(ctype) const flt_frame *frame "const flt_frame *"
%typemap(imtype) const flt_frame *frame "global::System.IntPtr"
%typemap(cstype) const flt_frame *frame "global::System.IntPtr"
%typemap(in) const flt_frame *frame %{ $1 = ($1_ltype)$input; %}
%typemap(csin) const flt_frame *frame "$csinput"

/* Image paths: one pointer per NUL-terminated UTF-8 path, pinned by the
 * caller (src/FrameSource.cs). */
%typemap(ctype) const char *const *paths "const char *const *"
%typemap(imtype) const char *const *paths "global::System.IntPtr*"
%typemap(cstype) const char *const *paths "global::System.IntPtr*"
%typemap(in) const char *const *paths %{ $1 = ($1_ltype)$input; %}
%typemap(csin) const char *const *paths "$csinput"

/* Raw register access: caller byte buffers, pinned. */
%typemap(ctype) void *out, const void *bytes_in "void *"
%typemap(imtype) void *out, const void *bytes_in "byte*"
%typemap(cstype) void *out, const void *bytes_in "byte*"
%typemap(in) void *out, const void *bytes_in %{ $1 = ($1_ltype)$input; %}
%typemap(csin) void *out, const void *bytes_in "$csinput"

%include "flatline/source.h"
