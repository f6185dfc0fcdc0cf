// SPDX-License-Identifier: Apache-2.0
// The C entry points of flt_recorder and flt_recording (flatline/record.h):
// argument checks around lib/record's classes.
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "core/error.hpp"
#include "core/options.hpp"
#include "flatline/recon.h"
#include "flatline/record.h"
#include "record/recorder.hpp"
#include "record/archive.hpp"
#include "record/recording_reader.hpp"

using flt::fail;
using flt::guard;

namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

flt_status check_recorder(const char *fn, const flt_recorder *r) {
    if (r == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'recorder' is NULL", fn);
    if (r->magic != 0x52454352u || !r->impl)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'recorder' is not a live recorder", fn);
    return FLT_OK;
}

flt_status check_recording(const char *fn, const flt_recording *r) {
    if (r == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'recording' is NULL", fn);
    if (r->magic != 0x52454344u || !r->impl)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'recording' is not an open recording",
                    fn);
    return FLT_OK;
}

flt_status check_position(const char *fn, double encoder_mm) {
    if (!std::isfinite(encoder_mm) || std::fabs(encoder_mm) > 1e12)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'encoder_mm' is %g (finite, at most 1e12 in magnitude)", fn,
                    encoder_mm);
    return FLT_OK;
}

flt_status check_not_recording_gauge(const char *fn, const flt_recorder *r) {
    if (r->impl->owner.load() != nullptr)
        return fail(FLT_ERR_STATE,
                    "%s: a gauge records through this recorder (it records its own rows, cuts "
                    "and coils; detach it first)",
                    fn);
    return FLT_OK;
}

}  // namespace

extern "C" {

FLT_API flt_status FLT_CALL flt_recorder_create(const char *path, const flt_calib *calib,
                                                const flt_options *options, flt_recorder **out) {
    const char *fn = "flt_recorder_create";
    if (out)
        *out = nullptr;
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, path);
        FLT_CHECK_NOT_NULL(fn, calib);
        FLT_CHECK_NOT_NULL(fn, out);
        if (path[0] == '\0')
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'path' is empty", fn);
        if (flt_status st = flt::check_option_component(fn, options, {1000}))
            return st;
        auto r = std::make_unique<flt_recorder>();
        r->impl = std::make_unique<flt::record::recorder>(path, calib, options);
        *out = r.release();
        return FLT_OK;
    });
}

FLT_API void FLT_CALL flt_recorder_destroy(flt_recorder *recorder) {
    flt::guard_void([&] {
        if (recorder && recorder->magic == 0x52454352u) {
            recorder->magic = 0;
            delete recorder;
        }
    });
}

FLT_API flt_status FLT_CALL flt_recorder_push_row(flt_recorder *recorder, double encoder_mm,
                                                  size_t fibers, const double *height,
                                                  const double *slope, const uint8_t *valid) {
    const char *fn = "flt_recorder_push_row";
    return guard(fn, [&] {
        if (flt_status st = check_recorder(fn, recorder))
            return st;
        if (flt_status st = check_position(fn, encoder_mm))
            return st;
        FLT_CHECK_NOT_NULL(fn, height);
        FLT_CHECK_NOT_NULL(fn, slope);
        flt::record::recorder &rec = *recorder->impl;
        if (fibers != rec.fibers())
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'fibers' is %zu (the calibration has %zu)", fn, fibers,
                        rec.fibers());
        if (flt_status st = check_not_recording_gauge(fn, recorder))
            return st;
        if (flt_status st = rec.failure(fn))
            return st;
        flt::record::row_in row;
        row.encoder_mm = encoder_mm;
        row.time_ns = flt::record::utc_now_ns();
        row.left_mm = row.right_mm = k_nan;
        rec.add_row(row, height, slope, nullptr, valid, nullptr, nullptr, nullptr);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recorder_cut(flt_recorder *recorder, double encoder_mm) {
    const char *fn = "flt_recorder_cut";
    return guard(fn, [&] {
        if (flt_status st = check_recorder(fn, recorder))
            return st;
        if (flt_status st = check_position(fn, encoder_mm))
            return st;
        if (flt_status st = check_not_recording_gauge(fn, recorder))
            return st;
        recorder->impl->add_cut(encoder_mm);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recorder_set_coil(flt_recorder *recorder,
                                                  const flt_coil_info *coil) {
    const char *fn = "flt_recorder_set_coil";
    return guard(fn, [&] {
        if (flt_status st = check_recorder(fn, recorder))
            return st;
        FLT_CHECK_NOT_NULL(fn, coil);
        if (!flt::is_coil_info(coil))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'coil' is not a coil identity", fn);
        if (flt_status st = check_not_recording_gauge(fn, recorder))
            return st;
        recorder->impl->add_coil(*coil);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recorder_sync(flt_recorder *recorder, uint32_t timeout_ms) {
    const char *fn = "flt_recorder_sync";
    return guard(fn, [&] {
        if (flt_status st = check_recorder(fn, recorder))
            return st;
        return recorder->impl->sync(fn, timeout_ms);
    });
}

FLT_API flt_status FLT_CALL flt_recorder_save_frames(flt_recorder *recorder) {
    const char *fn = "flt_recorder_save_frames";
    return guard(fn, [&] {
        if (flt_status st = check_recorder(fn, recorder))
            return st;
        recorder->impl->save_frames();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recorder_count(const flt_recorder *recorder,
                                               flt_recorder_counter counter, uint64_t *out) {
    const char *fn = "flt_recorder_count";
    return guard(fn, [&] {
        if (flt_status st = check_recorder(fn, recorder))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        const int c = flt::enum_arg(counter);
        if (c < 0 || c > FLT_RECORDER_COUNT_WRITER_NS)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'counter' is %d (0..%d)", fn, c,
                        int(FLT_RECORDER_COUNT_WRITER_NS));
        *out = recorder->impl->count(flt_recorder_counter(c));
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recording_open(const char *path, flt_recording **out) {
    const char *fn = "flt_recording_open";
    if (out)
        *out = nullptr;
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, path);
        FLT_CHECK_NOT_NULL(fn, out);
        auto r = std::make_unique<flt_recording>();
        r->impl = std::make_unique<flt::record::recording_reader>(path);
        *out = r.release();
        return FLT_OK;
    });
}

FLT_API void FLT_CALL flt_recording_destroy(flt_recording *recording) {
    flt::guard_void([&] {
        if (recording && recording->magic == 0x52454344u) {
            recording->magic = 0;
            delete recording;
        }
    });
}

FLT_API flt_status FLT_CALL flt_recording_info(const flt_recording *recording,
                                               flt_recording_value key, double *out) {
    const char *fn = "flt_recording_info";
    return guard(fn, [&] {
        if (flt_status st = check_recording(fn, recording))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        const flt::record::recording_reader &r = *recording->impl;
        const auto &blocks = r.blocks();
        const int k = flt::enum_arg(key);
        switch (k) {
            case FLT_RECORDING_VERSION_OF:
                *out = r.version();
                break;
            case FLT_RECORDING_FIBERS:
                *out = double(r.fibers());
                break;
            case FLT_RECORDING_ROWS:
                *out = double(r.rows());
                break;
            case FLT_RECORDING_BLOCKS:
                *out = double(blocks.size());
                break;
            case FLT_RECORDING_FRAMES:
                *out = double(r.frames().size());
                break;
            case FLT_RECORDING_EVENTS:
                *out = double(r.events().size());
                break;
            case FLT_RECORDING_QUANTUM:
                *out = r.quantum();
                break;
            case FLT_RECORDING_FIRST_TIME:
                *out = blocks.empty() ? k_nan : 1e-9 * double(blocks.front().first_time_ns);
                break;
            case FLT_RECORDING_LAST_TIME:
                *out = blocks.empty() ? k_nan : 1e-9 * double(blocks.back().last_time_ns);
                break;
            case FLT_RECORDING_FIRST_ENCODER:
                *out = blocks.empty() ? k_nan : blocks.front().first_encoder_mm;
                break;
            case FLT_RECORDING_LAST_ENCODER:
                *out = blocks.empty() ? k_nan : blocks.back().last_encoder_mm;
                break;
            case FLT_RECORDING_ROWS_LOST:
                *out = double(r.rows_lost());
                break;
            case FLT_RECORDING_BYTES:
                *out = double(r.block_bytes());
                break;
            case FLT_RECORDING_HAS_OPTIONS:
                *out = r.has_gauge_options() ? 1.0 : 0.0;
                break;
            default:
                return fail(FLT_ERR_NOT_FOUND, "%s: argument 'key' is %d (0..%d)", fn, k,
                            int(FLT_RECORDING_HAS_OPTIONS));
        }
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recording_calib(const flt_recording *recording, flt_calib **out) {
    const char *fn = "flt_recording_calib";
    if (out)
        *out = nullptr;
    return guard(fn, [&] {
        if (flt_status st = check_recording(fn, recording))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        const std::string &text = recording->impl->calibration_text();
        const flt_status st = flt_calib_load_text(text.data(), text.size(), out);
        if (st != FLT_OK)
            return fail(FLT_ERR_FORMAT, "%s: the recorded calibration does not load: %s", fn,
                        flt_last_error_message());
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recording_options(const flt_recording *recording,
                                                  flt_options **out) {
    const char *fn = "flt_recording_options";
    if (out)
        *out = nullptr;
    return guard(fn, [&] {
        if (flt_status st = check_recording(fn, recording))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        flt_options *bag = nullptr;
        if (flt_status st = flt_options_create(&bag))
            return st;
        *bag = recording->impl->gauge_options();
        *out = bag;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recording_verify(const flt_recording *recording,
                                                 uint64_t *bad_blocks_out) {
    const char *fn = "flt_recording_verify";
    return guard(fn, [&] {
        if (flt_status st = check_recording(fn, recording))
            return st;
        FLT_CHECK_NOT_NULL(fn, bad_blocks_out);
        *bad_blocks_out = 0;
        auto *r = const_cast<flt_recording *>(recording);  // the decoding cache only
        std::string first;
        for (std::size_t i = 0; i < r->impl->blocks().size(); ++i) {
            try {
                r->impl->load_block(i, r->block, r->scratch);
            } catch (const flt::error &e) {
                if (first.empty())
                    first = e.what();
                ++*bad_blocks_out;
            }
        }
        r->cached = std::size_t(-1);
        if (*bad_blocks_out > 0)
            return fail(FLT_ERR_FORMAT, "%s: %llu bad blocks, the first: %s", fn,
                        (unsigned long long)*bad_blocks_out, first.c_str());
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_recording_read_rows(const flt_recording *recording, uint64_t first,
                                                    size_t count, size_t fibers,
                                                    double *encoder_mm_out, double *time_s_out,
                                                    double *height_out, double *slope_out,
                                                    uint8_t *flags_out, size_t *rows_out) {
    const char *fn = "flt_recording_read_rows";
    if (rows_out)
        *rows_out = 0;
    return guard(fn, [&] {
        if (flt_status st = check_recording(fn, recording))
            return st;
        FLT_CHECK_NOT_NULL(fn, rows_out);
        auto *r = const_cast<flt_recording *>(recording);  // the decoding cache only
        const flt::record::recording_reader &rd = *r->impl;
        if (fibers != rd.fibers())
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'fibers' is %zu (the recording has %zu)", fn, fibers,
                        rd.fibers());
        if (count > 0 && (height_out || slope_out || flags_out) &&
            count > SIZE_MAX / fibers / sizeof(double))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'count' is %zu (too large)", fn,
                        count);
        // Rows are numbered in the order they were given; lost rows leave
        // holes: read the stored rows from the n-th stored one.
        std::size_t got = 0;
        std::uint64_t skip = first;
        const auto &blocks = rd.blocks();
        std::size_t bi = 0;
        while (bi < blocks.size() && skip >= blocks[bi].rows) {
            skip -= blocks[bi].rows;
            ++bi;
        }
        const std::size_t K = fibers;
        for (; bi < blocks.size() && got < count; ++bi, skip = 0) {
            if (r->cached != bi) {
                r->cached = std::size_t(-1);
                r->impl->load_block(bi, r->block, r->scratch);
                r->cached = bi;
            }
            const flt::record::row_block &b = r->block;
            for (std::size_t i = std::size_t(skip); i < b.rows && got < count; ++i, ++got) {
                if (encoder_mm_out)
                    encoder_mm_out[got] = b.encoder_mm[i];
                if (time_s_out)
                    time_s_out[got] = 1e-9 * double(b.time_ns[i]);
                for (std::size_t k = 0; k < K; ++k) {
                    const std::size_t at = i * K + k, to = got * K + k;
                    const std::uint8_t flag = b.state[at] & flt::record::k_state_flag_mask;
                    double h = k_nan, s = k_nan;
                    if (flag == 0)
                        flt::record::dequantize(b.q[0][at], b.q[1][at], rd.quantum(), rd.spacing(),
                                                &h, &s);
                    if (height_out)
                        height_out[to] = h;
                    if (slope_out)
                        slope_out[to] = s;
                    if (flags_out)
                        flags_out[to] = flag;
                }
            }
        }
        *rows_out = got;
        return FLT_OK;
    });
}

}  // extern "C"

// ---------------------------------------------------------------- archive

namespace {

flt_status check_archive(const char *fn, const flt_archive *a) {
    if (a == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'archive' is NULL", fn);
    if (a->magic != 0x41524348u || !a->impl)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'archive' is not an open archive", fn);
    return FLT_OK;
}

}  // namespace

extern "C" {

FLT_API flt_status FLT_CALL flt_archive_open(const char *location, const char *line,
                                             const flt_options *options, flt_archive **out) {
    const char *fn = "flt_archive_open";
    if (out)
        *out = nullptr;
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, location);
        FLT_CHECK_NOT_NULL(fn, line);
        FLT_CHECK_NOT_NULL(fn, out);
        if (location[0] == '\0')
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'location' is empty", fn);
        const std::string why = flt::coil_text_problem(line);
        if (!why.empty())
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'line' %s", fn, why.c_str());
        if (flt_status st = flt::check_option_component(fn, options, {1000}))
            return st;
        auto a = std::make_unique<flt_archive>();
        a->impl = std::make_unique<flt::record::archive>(location, line, options);
        *out = a.release();
        return FLT_OK;
    });
}

FLT_API void FLT_CALL flt_archive_destroy(flt_archive *archive) {
    flt::guard_void([&] {
        if (archive && archive->magic == 0x41524348u) {
            archive->magic = 0;
            delete archive;
        }
    });
}

FLT_API flt_status FLT_CALL flt_archive_flush(flt_archive *archive, uint32_t timeout_ms) {
    const char *fn = "flt_archive_flush";
    return guard(fn, [&] {
        if (flt_status st = check_archive(fn, archive))
            return st;
        return archive->impl->flush(fn, timeout_ms);
    });
}

FLT_API flt_status FLT_CALL flt_archive_prune(flt_archive *archive, uint64_t *removed_out) {
    const char *fn = "flt_archive_prune";
    return guard(fn, [&] {
        if (flt_status st = check_archive(fn, archive))
            return st;
        return archive->impl->prune(fn, removed_out);
    });
}

FLT_API flt_status FLT_CALL flt_archive_count(const flt_archive *archive,
                                              flt_archive_counter counter, uint64_t *out) {
    const char *fn = "flt_archive_count";
    return guard(fn, [&] {
        if (flt_status st = check_archive(fn, archive))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        const int c = flt::enum_arg(counter);
        if (c < 0 || c > FLT_ARCHIVE_COUNT_PENDING_BYTES)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'counter' is %d (0..%d)", fn, c,
                        int(FLT_ARCHIVE_COUNT_PENDING_BYTES));
        *out = archive->impl->count(flt_archive_counter(c));
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_archive_backend(const flt_archive *archive, int *out) {
    const char *fn = "flt_archive_backend";
    return guard(fn, [&] {
        if (flt_status st = check_archive(fn, archive))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = archive->impl->backend();
        return FLT_OK;
    });
}

}  // extern "C"
