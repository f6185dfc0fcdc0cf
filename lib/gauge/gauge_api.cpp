// SPDX-License-Identifier: Apache-2.0
// The C entry points of the gauge and of its sheets: argument checks, then
// the gauge's stages (gauge_internal.hpp lists their files).
#include <cmath>
#include <cstring>
#include <memory>

#include "core/coil.hpp"
#include "core/error.hpp"
#include "core/options.hpp"
#include "flatline/gauge.h"
#include "gauge/gauge.hpp"

using namespace flt;

namespace {
constexpr std::uint32_t k_gauge_magic = 0x464c5447u;  // "FLTG"
}  // namespace

const flt_verdict *flt_sheet::verdict_handle() const {
    if (!verdict)
        return nullptr;
    return own_verdict ? own_verdict.get() : verdict->slot[slot].get();
}

struct flt_gauge {
    std::uint32_t magic = k_gauge_magic;
    std::unique_ptr<gauge> impl;
};

namespace {

flt_status check_handle(const char *fn, const flt_gauge *g) {
    if (g == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'gauge' is NULL", fn);
    if (g->magic != k_gauge_magic || !g->impl)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'gauge' is not a live flt_gauge handle",
                    fn);
    return FLT_OK;
}

flt_status check_sheet(const char *fn, const flt_sheet *s) {
    if (s == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'sheet' is NULL", fn);
    if (s->magic != k_sheet_magic)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'sheet' is not a live flt_sheet handle",
                    fn);
    return FLT_OK;
}

// A success leaves no message (inner calls the gauge handled may have).
flt_status ok() {
    clear_error();
    return FLT_OK;
}

}  // namespace

extern "C" {

FLT_API flt_status FLT_CALL flt_gauge_create(const flt_calib *calib, const flt_options *options,
                                             flt_gauge **out) {
    const char *fn = "flt_gauge_create";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        FLT_CHECK_NOT_NULL(fn, calib);
        int finished = 0;
        if (flt_calib_is_finished(calib, &finished) != FLT_OK)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'calib' is not a live flt_calib handle", fn);
        if (!finished)
            return fail(FLT_ERR_STATE, "%s: argument 'calib' is not finished", fn);
        // The gauge reads its own keys, the reconstructor's, the extractor's
        // and the flatness metrics'; a key of any other component (the
        // simulator's, a source's) would be ignored: a mistake, refused.
        if (flt_status st =
                check_option_component(fn, options,
                                       {FLT_OPT_GAUGE_WORKERS, FLT_OPT_KNOT_SPACING,
                                        FLT_OPT_EXTRACT_SG_WINDOW, FLT_OPT_FLAT_WINDOW_LENGTH}))
            return st;
        auto handle = std::make_unique<flt_gauge>();
        handle->impl = std::make_unique<gauge>(calib, options);
        *out = handle.release();
        return ok();
    });
}

FLT_API void FLT_CALL flt_gauge_destroy(flt_gauge *gauge) {
    guard_void([&] {
        if (gauge && gauge->magic == k_gauge_magic && !in_gauge_callback(gauge->impl.get())) {
            gauge->magic = 0;
            delete gauge;
        }
    });
}

FLT_API flt_status FLT_CALL flt_gauge_get_option(const flt_gauge *gauge, flt_option key,
                                                 double *out) {
    const char *fn = "flt_gauge_get_option";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (enum_arg(key) < 0 || !find_option(key))
            return fail(FLT_ERR_NOT_FOUND, "%s: unknown option key %d", fn, enum_arg(key));
        *out = gauge->impl->option(key);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_gauge_push_frame(flt_gauge *gauge, const void *frame,
                                                 flt_pixel_format format, uint32_t width,
                                                 uint32_t height, size_t stride_bytes,
                                                 double encoder_mm) {
    const char *fn = "flt_gauge_push_frame";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        flt::gauge &g = *gauge->impl;
        if (flt_status st =
                g.check_frame(fn, frame, enum_arg(format), width, height, stride_bytes, encoder_mm))
            return st;
        gauge_input in;
        in.pixels = frame;
        in.format = format;
        in.stride = stride_bytes;
        in.encoder_mm = encoder_mm;
        if (flt_status st = g.push(fn, in))
            return st;
        return ok();
    });
}

FLT_API flt_status FLT_CALL flt_gauge_push_row(flt_gauge *gauge, double encoder_mm, size_t fibers,
                                               const double *height, const double *slope,
                                               const uint8_t *valid) {
    const char *fn = "flt_gauge_push_row";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        flt::gauge &g = *gauge->impl;
        FLT_CHECK_NOT_NULL(fn, height);
        FLT_CHECK_NOT_NULL(fn, slope);
        if (fibers != g.fibers())
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'fibers' = %zu but the calibration has %zu", fn, fibers,
                        g.fibers());
        if (flt_status st = flt::gauge::check_encoder(fn, encoder_mm))
            return st;
        gauge_input in;
        in.height = height;
        in.slope = slope;
        in.valid = valid;
        in.encoder_mm = encoder_mm;
        if (flt_status st = g.push(fn, in))
            return st;
        return ok();
    });
}

FLT_API flt_status FLT_CALL flt_gauge_cut(flt_gauge *gauge, double encoder_mm) {
    const char *fn = "flt_gauge_cut";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        if (flt_status st = flt::gauge::check_encoder(fn, encoder_mm))
            return st;
        if (flt_status st = gauge->impl->cut(fn, encoder_mm))
            return st;
        return ok();
    });
}

FLT_API flt_status FLT_CALL flt_gauge_flush(flt_gauge *gauge) {
    const char *fn = "flt_gauge_flush";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        if (flt_status st = gauge->impl->flush(fn))
            return st;
        return ok();
    });
}

FLT_API flt_status FLT_CALL flt_gauge_attach_source(flt_gauge *gauge, flt_source *source) {
    const char *fn = "flt_gauge_attach_source";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        if (source != nullptr) {
            flt_source_kind kind;
            if (flt_source_kind_of(source, &kind) != FLT_OK)
                return fail(FLT_ERR_INVALID_ARGUMENT,
                            "%s: argument 'source' is not a live flt_source handle", fn);
        }
        return gauge->impl->attach(fn, source);
    });
}

FLT_API flt_status FLT_CALL flt_gauge_start(flt_gauge *gauge) {
    const char *fn = "flt_gauge_start";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        return gauge->impl->start(fn);
    });
}

FLT_API flt_status FLT_CALL flt_gauge_stop(flt_gauge *gauge) {
    const char *fn = "flt_gauge_stop";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        if (flt_status st = gauge->impl->stop(fn))
            return st;
        return ok();
    });
}

FLT_API flt_status FLT_CALL flt_gauge_wait(flt_gauge *gauge, uint32_t timeout_ms) {
    const char *fn = "flt_gauge_wait";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        if (flt_status st = gauge->impl->wait(fn, timeout_ms))
            return st;
        return ok();
    });
}

FLT_API flt_status FLT_CALL flt_gauge_next_sheet(flt_gauge *gauge, uint32_t timeout_ms,
                                                 flt_sheet **out) {
    const char *fn = "flt_gauge_next_sheet";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        if (flt_status st = check_handle(fn, gauge))
            return st;
        return gauge->impl->next_sheet(fn, timeout_ms, out);
    });
}

FLT_API flt_status FLT_CALL flt_gauge_set_callback(flt_gauge *gauge, flt_sheet_callback callback,
                                                   void *user) {
    const char *fn = "flt_gauge_set_callback";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        return gauge->impl->set_callback(fn, callback, user);
    });
}

FLT_API flt_status FLT_CALL flt_gauge_count(const flt_gauge *gauge, flt_gauge_counter counter,
                                            uint64_t *out) {
    const char *fn = "flt_gauge_count";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        const int raw = enum_arg(counter);
        if (raw < 0 || raw > FLT_GAUGE_COUNT_QUEUE_HIGH_WATER)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'counter' = %d is not a flt_gauge_counter", fn, raw);
        *out = gauge->impl->count(counter);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_gauge_set_rules(flt_gauge *gauge, const flt_rules *rules,
                                                double thickness_mm, double width_mm) {
    const char *fn = "flt_gauge_set_rules";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        if (rules != nullptr && rules->magic != flt_rules::k_magic)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'rules' is not a live flt_rules handle", fn);
        // The same bounds as flt_verdict_evaluate: beyond them, a unit
        // mistake.
        if (!(thickness_mm > 0) || !(thickness_mm <= 1000.0))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'thickness_mm' = %g must be > 0 and <= 1000 (mm)", fn,
                        thickness_mm);
        if (!(width_mm == 0) && !(width_mm > 0 && width_mm <= 100000.0))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'width_mm' = %g must be 0 (the measured strip width) or "
                        "> 0 and <= 100000 (mm)",
                        fn, width_mm);
        return gauge->impl->set_rules(fn, rules, thickness_mm, width_mm);
    });
}

FLT_API flt_status FLT_CALL flt_gauge_coil_stats(const flt_gauge *gauge, flt_coil which,
                                                 size_t rule, size_t count, double *out) {
    const char *fn = "flt_gauge_coil_stats";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        const int raw = enum_arg(which);
        if (raw != FLT_COIL_CURRENT && raw != FLT_COIL_LAST)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'which' = %d is not a flt_coil (0 or 1)", fn, raw);
        if (count < 1 || count > FLT_COIL_VALUES)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'count' = %zu must be 1 .. FLT_COIL_VALUES (%d)", fn, count,
                        int(FLT_COIL_VALUES));
        return gauge->impl->coil_stats_of(fn, flt_coil(raw), rule, count, out);
    });
}

FLT_API void FLT_CALL flt_sheet_destroy(flt_sheet *sheet) {
    guard_void([&] {
        if (!sheet || sheet->magic != k_sheet_magic || sheet->borrowed)
            return;
        // A local reference keeps the pool alive while it is locked.
        const std::shared_ptr<sheet_pool> pool = sheet->pool;
        pool->give_back(sheet);
    });
}

FLT_API flt_status FLT_CALL flt_sheet_get(const flt_sheet *sheet, flt_sheet_value key,
                                          double *out) {
    const char *fn = "flt_sheet_get";
    return guard(fn, [&] {
        if (flt_status st = check_sheet(fn, sheet))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        const int raw = enum_arg(key);
        if (raw < 0 || raw >= k_sheet_values)
            return fail(FLT_ERR_NOT_FOUND, "%s: argument 'key' = %d is not a flt_sheet_value", fn,
                        raw);
        *out = sheet->value[raw];
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sheet_get_array(const flt_sheet *sheet, flt_sheet_array key,
                                                size_t count, double *out) {
    const char *fn = "flt_sheet_get_array";
    return guard(fn, [&] {
        if (flt_status st = check_sheet(fn, sheet))
            return st;
        const int raw = enum_arg(key);
        if (raw < 0 || raw >= k_sheet_arrays)
            return fail(FLT_ERR_NOT_FOUND, "%s: argument 'key' = %d is not a flt_sheet_array", fn,
                        raw);
        FLT_CHECK_NOT_NULL(fn, out);
        const std::vector<double> &a = sheet->array[raw];
        if (count != a.size())
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'count' = %zu but the array has %zu values (%s)", fn, count,
                        a.size(), is_fiber_array(raw) ? "FLT_SHEET_FIBERS" : "FLT_SHEET_ZONES");
        std::memcpy(out, a.data(), count * sizeof(double));
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sheet_height_map(const flt_sheet *sheet, size_t rows, size_t fibers,
                                                 double *s_out, double *z_out, uint8_t *flags_out) {
    const char *fn = "flt_sheet_height_map";
    return guard(fn, [&] {
        if (flt_status st = check_sheet(fn, sheet))
            return st;
        if (sheet->maps < 1)
            return fail(FLT_ERR_STATE,
                        "%s: the gauge keeps no height maps (option gauge_keep_maps = 0)", fn);
        if (rows != sheet->rows || fibers != sheet->fibers)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: arguments 'rows' x 'fibers' = %zu x %zu but the sheet has %zu x %zu",
                        fn, rows, fibers, sheet->rows, sheet->fibers);
        if (s_out)
            std::memcpy(s_out, sheet->map_s.data(), rows * sizeof(double));
        if (z_out)
            std::memcpy(z_out, sheet->map_z.data(), rows * fibers * sizeof(double));
        if (flags_out)
            std::memcpy(flags_out, sheet->map_flags.data(), rows * fibers);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sheet_measured_map(const flt_sheet *sheet, size_t rows,
                                                   size_t fibers, double *height_out) {
    const char *fn = "flt_sheet_measured_map";
    return guard(fn, [&] {
        if (flt_status st = check_sheet(fn, sheet))
            return st;
        FLT_CHECK_NOT_NULL(fn, height_out);
        if (sheet->maps < 2)
            return fail(FLT_ERR_STATE,
                        "%s: the gauge keeps no measured heights (option gauge_keep_maps < 2)", fn);
        if (rows != sheet->rows || fibers != sheet->fibers)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: arguments 'rows' x 'fibers' = %zu x %zu but the sheet has %zu x %zu",
                        fn, rows, fibers, sheet->rows, sheet->fibers);
        std::memcpy(height_out, sheet->map_measured.data(), rows * fibers * sizeof(double));
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sheet_verdict(const flt_sheet *sheet, const flt_rules **rules_out,
                                              const flt_verdict **verdict_out) {
    const char *fn = "flt_sheet_verdict";
    return guard(fn, [&] {
        if (rules_out)
            *rules_out = nullptr;
        if (verdict_out)
            *verdict_out = nullptr;
        if (flt_status st = check_sheet(fn, sheet))
            return st;
        if (!sheet->verdict)
            return fail(FLT_ERR_STATE,
                        "%s: the gauge had no rules when it judged this sheet "
                        "(flt_gauge_set_rules)",
                        fn);
        if (rules_out)
            *rules_out = &sheet->verdict->rules;
        if (verdict_out)
            *verdict_out = sheet->verdict_handle();
        return FLT_OK;
    });
}

// ---------------------------------------------------------------- the record

FLT_API flt_status FLT_CALL flt_gauge_set_coil(flt_gauge *gauge, const flt_coil_info *coil) {
    const char *fn = "flt_gauge_set_coil";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        if (coil != nullptr && !is_coil_info(coil))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'coil' is not a coil identity", fn);
        if (flt_status st = gauge->impl->set_coil(fn, coil))
            return st;
        return ok();
    });
}

FLT_API flt_status FLT_CALL flt_gauge_coil_info(const flt_gauge *gauge, flt_coil which,
                                                flt_coil_info **out) {
    const char *fn = "flt_gauge_coil_info";
    if (out)
        *out = nullptr;
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        const int w = enum_arg(which);
        if (w != FLT_COIL_CURRENT && w != FLT_COIL_LAST)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'which' is %d (0 current, 1 last)",
                        fn, w);
        return gauge->impl->coil_info_of(fn, flt_coil(w), out);
    });
}

FLT_API flt_status FLT_CALL flt_gauge_note(flt_gauge *gauge, const char *kind, const char *text) {
    const char *fn = "flt_gauge_note";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        FLT_CHECK_NOT_NULL(fn, kind);
        FLT_CHECK_NOT_NULL(fn, text);
        std::string why = coil_key_problem(kind);
        if (!why.empty())
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'kind' %s", fn, why.c_str());
        why = coil_text_problem(text);
        if (!why.empty())
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'text' %s", fn, why.c_str());
        return gauge->impl->note(fn, kind, text);
    });
}

FLT_API flt_status FLT_CALL flt_gauge_attach_recorder(flt_gauge *gauge, flt_recorder *recorder) {
    const char *fn = "flt_gauge_attach_recorder";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        if (recorder != nullptr && (recorder->magic != 0x52454352u || !recorder->impl))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'recorder' is not a live recorder",
                        fn);
        return gauge->impl->attach_recorder(fn, recorder);
    });
}

FLT_API flt_status FLT_CALL flt_gauge_attach_archive(flt_gauge *gauge, flt_archive *archive) {
    const char *fn = "flt_gauge_attach_archive";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, gauge))
            return st;
        if (archive != nullptr && (archive->magic != 0x41524348u || !archive->impl))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'archive' is not an open archive",
                        fn);
        return gauge->impl->attach_archive(fn, archive);
    });
}

FLT_API flt_status FLT_CALL flt_sheet_coil(const flt_sheet *sheet, const flt_coil_info **out) {
    const char *fn = "flt_sheet_coil";
    return guard(fn, [&] {
        if (flt_status st = check_sheet(fn, sheet))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = sheet->coil.get();
        if (!sheet->coil)
            return fail(FLT_ERR_NOT_FOUND, "%s: the sheet's coil has no identity", fn);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sheet_note_count(const flt_sheet *sheet, size_t *out) {
    const char *fn = "flt_sheet_note_count";
    return guard(fn, [&] {
        if (flt_status st = check_sheet(fn, sheet))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = sheet->notes.size();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sheet_note(const flt_sheet *sheet, size_t index,
                                           const char **kind_out, const char **text_out,
                                           double *s_mm_out) {
    const char *fn = "flt_sheet_note";
    return guard(fn, [&] {
        if (flt_status st = check_sheet(fn, sheet))
            return st;
        if (index >= sheet->notes.size())
            return fail(FLT_ERR_NOT_FOUND, "%s: argument 'index' is %zu (the sheet has %zu notes)",
                        fn, index, sheet->notes.size());
        const sheet_note &n = sheet->notes[index];
        if (kind_out)
            *kind_out = n.kind.c_str();
        if (text_out)
            *text_out = n.text.c_str();
        if (s_mm_out)
            *s_mm_out = n.s;
        return FLT_OK;
    });
}

}  // extern "C"
