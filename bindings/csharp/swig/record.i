// SPDX-License-Identifier: Apache-2.0
/* Coil identities, recordings and the archive (include/flatline/coil.h,
 * include/flatline/record.h). Before gauge.i: flt_archive_add_sheet (in
 * gauge.h) takes an archive. Arrays are pinned pointers (common.i);
 * outputs raw pointers (flatness.i's FLT_CS_OUT_POINTER). */
%{
#include "flatline/coil.h"
#include "flatline/record.h"
%}

FLT_CS_HANDLE(flt_coil_info, CoilInfoHandle)
FLT_CS_HANDLE(flt_recorder, RecorderHandle)
FLT_CS_HANDLE(flt_recording, RecordingHandle)
FLT_CS_HANDLE(flt_archive, ArchiveHandle)
FLT_CS_INT_ENUM(flt_coil_field, NativeCoilField)
FLT_CS_INT_ENUM(flt_record_frames, NativeRecordFrames)
FLT_CS_INT_ENUM(flt_recorder_counter, NativeRecorderCounter)
FLT_CS_INT_ENUM(flt_recording_value, NativeRecordingValue)
FLT_CS_INT_ENUM(flt_archive_counter, NativeArchiveCounter)
%ignore FLT_COIL_FIELD_MAX_ENUM_;
%ignore FLT_RECORD_FRAMES_MAX_ENUM_;
%ignore FLT_RECORDER_COUNTER_MAX_ENUM_;
%ignore FLT_RECORDING_VALUE_MAX_ENUM_;
%ignore FLT_ARCHIVE_COUNTER_MAX_ENUM_;

FLT_CS_OUT_POINTER(void, global::System.IntPtr, const char **key_out, const char **value_out)
FLT_CS_OUT_POINTER(double, double, double *thickness_mm_out, double *width_mm_out)
FLT_CS_OUT_POINTER(uint64_t, ulong, uint64_t *bad_blocks_out, uint64_t *removed_out)

%include "flatline/coil.h"
%include "flatline/record.h"
