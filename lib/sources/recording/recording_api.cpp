// SPDX-License-Identifier: Apache-2.0
// The C entry points of recordings as sources (flatline/source.h,
// "Recordings").
#include <cmath>
#include <limits>
#include <memory>

#include "core/error.hpp"
#include "core/options.hpp"
#include "flatline/recon.h"
#include "flatline/source.h"
#include "sources/recording/recording_source.hpp"
#include "sources/source_handle.hpp"

using flt::fail;
using flt::guard;

namespace {

flt_status check_frame(const char *fn, const flt_frame *frame) {
    if (frame == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'frame' is NULL", fn);
    if (frame->magic != flt::k_frame_magic)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'frame' is not a live frame", fn);
    return FLT_OK;
}

}  // namespace

extern "C" {

FLT_API flt_status FLT_CALL flt_source_open_recording(const char *path, const flt_options *options,
                                                      flt_source **out) {
    const char *fn = "flt_source_open_recording";
    if (out)
        *out = nullptr;
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, path);
        FLT_CHECK_NOT_NULL(fn, out);
        if (flt_status st = flt::check_option_component(fn, options, {FLT_OPT_SOURCE_ENCODER_MODE}))
            return st;
        if (flt::option_value(options, FLT_OPT_SOURCE_ENCODER_MODE) != FLT_ENCODER_AUTO)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: option 'source_encoder_mode' must be auto for a recording (its "
                        "positions are the recorded ones)",
                        fn);
        auto s = std::make_unique<flt_source>();
        s->encoder.configure(options, false);
        s->impl = flt::sources::make_recording_source(path);
        *out = s.release();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_frame_row(const flt_frame *frame, size_t fibers, double *height_out,
                                          double *slope_out, uint8_t *flags_out) {
    const char *fn = "flt_frame_row";
    return guard(fn, [&] {
        if (flt_status st = check_frame(fn, frame))
            return st;
        const flt::sources::recorded_frame *r = frame->recorded;
        if (!r || !r->has_row)
            return fail(FLT_ERR_NOT_FOUND, "%s: the frame has no recorded row", fn);
        if (fibers != r->block->fibers)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'fibers' is %zu (the recording has %zu)", fn, fibers,
                        r->block->fibers);
        r->row_values(fibers, height_out, slope_out, flags_out, nullptr);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_frame_event_count(const flt_frame *frame, size_t *out) {
    const char *fn = "flt_frame_event_count";
    return guard(fn, [&] {
        if (flt_status st = check_frame(fn, frame))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = frame->recorded ? frame->recorded->event_count : 0;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_frame_event(const flt_frame *frame, size_t index,
                                            flt_recorded_event *kind_out, double *encoder_mm_out,
                                            uint64_t *count_out, const flt_coil_info **coil_out) {
    const char *fn = "flt_frame_event";
    return guard(fn, [&] {
        if (flt_status st = check_frame(fn, frame))
            return st;
        const flt::sources::recorded_frame *r = frame->recorded;
        const std::size_t n = r ? r->event_count : 0;
        if (index >= n)
            return fail(FLT_ERR_NOT_FOUND, "%s: argument 'index' is %zu (the frame has %zu events)",
                        fn, index, n);
        const flt::record::recorded_event &e = r->events[index];
        flt_recorded_event kind = FLT_RECORDED_GAP;
        switch (e.kind) {
            case flt::record::recorded_event::cut:
                kind = FLT_RECORDED_CUT;
                break;
            case flt::record::recorded_event::coil:
                kind = FLT_RECORDED_COIL;
                break;
            case flt::record::recorded_event::flush:
                kind = FLT_RECORDED_FLUSH;
                break;
            case flt::record::recorded_event::note:
                kind = FLT_RECORDED_NOTE;
                break;
            default:
                break;
        }
        if (kind_out)
            *kind_out = kind;
        if (encoder_mm_out)
            *encoder_mm_out =
                kind == FLT_RECORDED_CUT ? e.encoder_mm : std::numeric_limits<double>::quiet_NaN();
        if (count_out)
            *count_out = kind == FLT_RECORDED_GAP ? e.count : 0;
        if (coil_out) {
            *coil_out = nullptr;
            if (e.coil_info)
                *coil_out = e.coil_info.get();  // lent (the reader made it so)
        }
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_frame_event_note(const flt_frame *frame, size_t index,
                                                 const char **kind_out, const char **text_out) {
    const char *fn = "flt_frame_event_note";
    return guard(fn, [&] {
        if (flt_status st = check_frame(fn, frame))
            return st;
        const flt::sources::recorded_frame *r = frame->recorded;
        const std::size_t n = r ? r->event_count : 0;
        if (index >= n)
            return fail(FLT_ERR_NOT_FOUND, "%s: argument 'index' is %zu (the frame has %zu events)",
                        fn, index, n);
        const flt::record::recorded_event &e = r->events[index];
        if (e.kind != flt::record::recorded_event::note)
            return fail(FLT_ERR_NOT_FOUND, "%s: event %zu is no note", fn, index);
        if (kind_out)
            *kind_out = e.label.c_str();
        if (text_out)
            *text_out = e.text.c_str();
        return FLT_OK;
    });
}

}  // extern "C"
