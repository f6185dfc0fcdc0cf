// SPDX-License-Identifier: Apache-2.0
/* The gauge and its sheets (include/flatline/gauge.h). */
%{
#include "flatline/gauge.h"
%}

FLT_CS_HANDLE(flt_gauge, GaugeHandle)
FLT_CS_HANDLE(flt_sheet, SheetHandle)

FLT_CS_INT_ENUM(flt_sheet_value, NativeSheetValue)
FLT_CS_INT_ENUM(flt_sheet_array, NativeSheetArray)
FLT_CS_INT_ENUM(flt_gauge_counter, NativeGaugeCounter)
FLT_CS_INT_ENUM(flt_coil, NativeCoil)
FLT_CS_INT_ENUM(flt_coil_value, NativeCoilValue)
FLT_CS_INT_ENUM(flt_gauge_overflow, NativeGaugeOverflow)
%ignore FLT_GAUGE_OVERFLOW_MAX_ENUM_;
%ignore FLT_COIL_MAX_ENUM_;
%ignore FLT_COIL_VALUE_MAX_ENUM_;
/* A sheet's verdict and a coil's statistics through the helpers below. */
%ignore flt_sheet_verdict;
/* A sheet's coil and notes through the helpers below (a lent identity is
 * copied into one the SafeHandle owns). */
%ignore flt_sheet_coil;
%ignore flt_sheet_note_count;
%ignore flt_sheet_note;
FLT_CS_OUT_POINTER(void, global::System.IntPtr, const char **kind_out, const char **text_out)
FLT_CS_OUT_POINTER(double, double, double *s_mm_out)
%ignore flt_gauge_coil_stats;
%ignore FLT_SHEET_VALUE_MAX_ENUM_;
%ignore FLT_SHEET_ARRAY_MAX_ENUM_;
%ignore FLT_GAUGE_COUNT_MAX_ENUM_;

/* The callback: a function pointer the public Gauge makes from a delegate
 * it keeps alive (Marshal.GetFunctionPointerForDelegate), and its user
 * pointer, both IntPtrs. */
%typemap(ctype) flt_sheet_callback callback "flt_sheet_callback"
%typemap(imtype) flt_sheet_callback callback "global::System.IntPtr"
%typemap(cstype) flt_sheet_callback callback "global::System.IntPtr"
%typemap(in) flt_sheet_callback callback %{ $1 = ($1_ltype)$input; %}
%typemap(csin) flt_sheet_callback callback "$csinput"
%typemap(ctype) void *user "void *"
%typemap(imtype) void *user "global::System.IntPtr"
%typemap(cstype) void *user "global::System.IntPtr"
%typemap(in) void *user %{ $1 = $input; %}
%typemap(csin) void *user "$csinput"

/* A sheet is read through its raw pointer: the callback's is borrowed (no
 * SafeHandle may own it), and a polled one is read the same way while its
 * SheetHandle is held. */
%typemap(ctype) void *sheet "void *"
%typemap(imtype) void *sheet "global::System.IntPtr"
%typemap(cstype) void *sheet "global::System.IntPtr"
%typemap(in) void *sheet %{ $1 = $input; %}
%typemap(csin) void *sheet "$csinput"
%inline %{
flt_status flt_cs_sheet_get(void *sheet, int key, double *out) {
    return flt_sheet_get((const flt_sheet *)sheet, (flt_sheet_value)key, out);
}
flt_status flt_cs_sheet_get_array(void *sheet, int key, size_t count, double *values) {
    return flt_sheet_get_array((const flt_sheet *)sheet, (flt_sheet_array)key, count, values);
}
flt_status flt_cs_sheet_height_map(void *sheet, size_t rows, size_t fibers, double *s_values,
                                   double *z_values, uint8_t *flag_values) {
    return flt_sheet_height_map((const flt_sheet *)sheet, rows, fibers, s_values, z_values,
                                flag_values);
}
flt_status flt_cs_sheet_measured_map(void *sheet, size_t rows, size_t fibers,
                                     double *height_values) {
    return flt_sheet_measured_map((const flt_sheet *)sheet, rows, fibers, height_values);
}
/* The sheet's verdict: rule `rule` of the rules it was judged by (name
 * owned by the sheet) and one of its results (flt_verdict_value). */
flt_status flt_cs_sheet_rule(void *sheet, size_t rule, const char **name_out,
                             flt_measure *measure_out, double *length_mm_out) {
    const flt_rules *rules = NULL;
    flt_status st = flt_sheet_verdict((const flt_sheet *)sheet, &rules, NULL);
    return st != FLT_OK ? st : flt_rules_rule(rules, rule, name_out, measure_out, length_mm_out);
}
flt_status flt_cs_sheet_verdict_get(void *sheet, size_t rule, int key, double *out) {
    const flt_verdict *verdict = NULL;
    flt_status st = flt_sheet_verdict((const flt_sheet *)sheet, NULL, &verdict);
    return st != FLT_OK ? st : flt_verdict_get(verdict, rule, (flt_verdict_value)key, out);
}
/* A coil's statistics for one rule into values[count]. */
flt_status flt_cs_gauge_coil_stats(const flt_gauge *gauge, int which, size_t rule, size_t count,
                                   double *values) {
    return flt_gauge_coil_stats(gauge, (flt_coil)which, rule, count, values);
}
/* flt_gauge_wait's status as it is: FLT_ERR_TIMEOUT is no error to
 * RunAsync, which waits in short steps to notice a cancellation. */
int flt_cs_gauge_wait(flt_gauge *gauge, uint32_t timeout_ms) {
    return (int)flt_gauge_wait(gauge, timeout_ms);
}
/* The sheet's coil, copied (0 with FLT_ERR_NOT_FOUND's status when none). */
int flt_cs_sheet_has_coil(void *sheet) {
    const flt_coil_info *c = NULL;
    const int has = flt_sheet_coil((const flt_sheet *)sheet, &c) == FLT_OK;
    return has;
}
flt_status flt_cs_sheet_coil_copy(void *sheet, flt_coil_info **out) {
    const flt_coil_info *c = NULL;
    flt_status st = flt_sheet_coil((const flt_sheet *)sheet, &c);
    *out = NULL;
    return st != FLT_OK ? st : flt_coil_info_copy(c, out);
}
flt_status flt_cs_sheet_note_count(void *sheet, size_t *count_out) {
    return flt_sheet_note_count((const flt_sheet *)sheet, count_out);
}
flt_status flt_cs_sheet_note(void *sheet, size_t index, const char **kind_out,
                             const char **text_out, double *s_mm_out) {
    return flt_sheet_note((const flt_sheet *)sheet, index, kind_out, text_out, s_mm_out);
}
/* No more recorder or archive (a null SafeHandle cannot be passed). */
flt_status flt_cs_gauge_detach_recorder(flt_gauge *gauge) {
    return flt_gauge_attach_recorder(gauge, NULL);
}
flt_status flt_cs_gauge_detach_archive(flt_gauge *gauge) {
    return flt_gauge_attach_archive(gauge, NULL);
}
flt_status flt_cs_gauge_clear_coil(flt_gauge *gauge) {
    return flt_gauge_set_coil(gauge, NULL);
}
/* No more rules (a null SafeHandle cannot be passed). */
flt_status flt_cs_gauge_clear_rules(flt_gauge *gauge) {
    return flt_gauge_set_rules(gauge, NULL, 1.0, 0.0);
}
/* Destroys a gauge after removing its callback, so that no sheet reaches a
 * delegate while the gauge shuts down (its finalizer may run after the
 * managed Gauge is gone). */
void flt_cs_gauge_release(void *handle) {
    if (handle && flt_gauge_set_callback((flt_gauge *)handle, NULL, NULL) != FLT_OK) {
        /* not a live gauge: destroy ignores it too */
    }
    flt_gauge_destroy((flt_gauge *)handle);
}
%}

%include "flatline/gauge.h"
