// SPDX-License-Identifier: Apache-2.0
// From a gauge's sheet to the archive's neutral record (lib/record), and the
// C entry point that archives a sheet the caller holds. The archive sits
// below the gauge and knows nothing of flt_sheet; this file is where the
// two meet.
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>

#include "core/error.hpp"
#include "flatline/gauge.h"
#include "flatline/verdict.h"
#include "gauge/gauge.hpp"
#include "record/archive.hpp"
#include "record/codec.hpp"
#include "record/recorder.hpp"

namespace flt {
namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

}  // namespace

// The archive's record of a sheet: its values, arrays, verdict, coil,
// notes and (when the archive keeps maps and there is one: `rows` > 0) its
// height map, encoded here.
std::unique_ptr<record::sheet_record>
archive_record_of(const flt_sheet &sh, const record::archive &ar, const std::string &session,
                  std::size_t rows, const double *s, const double *z, const std::uint8_t *flags) {
    auto r = std::make_unique<record::sheet_record>();
    r->values.assign(sh.value, sh.value + k_sheet_values);
    for (int a = 0; a < k_sheet_arrays; ++a)
        r->arrays.emplace_back(a, sh.array[a]);
    const auto id = std::int64_t(sh.value[FLT_SHEET_ID]);
    const auto coil = std::int64_t(sh.value[FLT_SHEET_COIL]);
    r->sheet_id = id;
    r->gauge_coil = coil;
    r->sheet_index = std::int64_t(sh.value[FLT_SHEET_INDEX]);
    r->sheet_uid = session + "-s" + std::to_string(id);
    r->coil_uid = session + "-c" + std::to_string(coil);
    const double finished = sh.value[FLT_SHEET_FINISHED_TIME];
    r->utc_ns = finished > 0 ? std::int64_t(finished * 1e9) : record::utc_now_ns();
    if (sh.coil) {
        r->coil = *sh.coil;
        r->coil.lent = false;
    }
    for (const sheet_note &n : sh.notes) {
        record::note_record nr;
        nr.kind = n.kind;
        nr.text = n.text;
        nr.s_mm = n.s;
        nr.utc_ns = n.utc_ns;
        r->notes.push_back(std::move(nr));
    }
    const double verdict = sh.value[FLT_SHEET_VERDICT];
    r->thickness_mm = r->width_mm = k_nan;
    const flt_rules *rules = nullptr;
    const flt_verdict *vd = nullptr;
    if (flt_sheet_verdict(&sh, &rules, &vd) == FLT_OK && rules && vd) {
        std::size_t n = 0;
        if (flt_rules_count(rules, &n) != FLT_OK)
            n = 0;
        r->rules = std::int64_t(n);
        for (std::size_t i = 0; i < n; ++i) {
            record::rule_record rr;
            const char *name = "";
            flt_measure measure = FLT_MEASURE_ZONE_I_UNITS;
            double length = 0;
            if (flt_rules_rule(rules, i, &name, &measure, &length) != FLT_OK)
                continue;
            rr.name = name;
            rr.measure = int(measure);
            rr.length_mm = length;
            double v[FLT_VERDICT_LENGTH + 1];
            for (int k = 0; k <= FLT_VERDICT_LENGTH; ++k)
                if (flt_verdict_get(vd, i, flt_verdict_value(k), &v[k]) != FLT_OK)
                    v[k] = k_nan;
            rr.state = int(v[FLT_VERDICT_STATE]);
            rr.worst = v[FLT_VERDICT_WORST];
            rr.limit = v[FLT_VERDICT_LIMIT];
            rr.margin = v[FLT_VERDICT_MARGIN];
            rr.x_mm = v[FLT_VERDICT_X];
            rr.s_mm = v[FLT_VERDICT_S];
            rr.band = int(v[FLT_VERDICT_BAND]);
            if (rr.state == FLT_VERDICT_FAIL)
                ++r->rules_failed;
            r->rule_results.push_back(std::move(rr));
        }
        r->verdict = verdict == FLT_VERDICT_FAIL   ? "fail"
                     : verdict == FLT_VERDICT_PASS ? "pass"
                                                   : "not_judged";
        // What chose the bands: the coil's nominal values, else the rules'.
        r->thickness_mm =
            sh.coil && sh.coil->thickness_mm > 0 ? sh.coil->thickness_mm : sh.verdict->thickness;
        r->width_mm = sh.coil && sh.coil->width_mm > 0 ? sh.coil->width_mm
                      : sh.verdict->width > 0          ? sh.verdict->width
                                                       : sh.value[FLT_SHEET_STRIP_WIDTH];
    }
    clear_error();
    if (ar.wants_maps() && rows > 0) {
        record::encode_map(rows, sh.fibers, s, z, flags, ar.map_quantum(), r->map);
        r->map_crc = record::crc32_of(r->map.data(), r->map.size());
    }
    return r;
}

}  // namespace flt

extern "C" {

FLT_API flt_status FLT_CALL flt_archive_add_sheet(flt_archive *archive, const flt_sheet *sheet) {
    const char *fn = "flt_archive_add_sheet";
    return flt::guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, archive);
        FLT_CHECK_NOT_NULL(fn, sheet);
        if (archive->magic != 0x41524348u || !archive->impl)
            return flt::fail(FLT_ERR_INVALID_ARGUMENT,
                             "%s: argument 'archive' is not an open archive", fn);
        if (sheet->magic != flt::k_sheet_magic)
            return flt::fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'sheet' is not a live sheet",
                             fn);
        // The map the sheet kept (gauge_keep_maps >= 1), if any.
        const bool map = sheet->maps >= 1 && sheet->rows > 0;
        auto r = flt::archive_record_of(*sheet, *archive->impl, sheet->pool->session,
                                        map ? sheet->rows : 0, sheet->map_s.data(),
                                        sheet->map_z.data(), sheet->map_flags.data());
        if (!archive->impl->add(std::move(r)))
            return flt::fail(FLT_ERR_BUFFER_FULL,
                             "%s: the archive's buffer (archive_buffer_mb) is full: the database "
                             "has not taken sheets for a while (%s); this sheet is not archived",
                             fn, archive->impl->last_error().c_str());
        return FLT_OK;
    });
}

}  // extern "C"
