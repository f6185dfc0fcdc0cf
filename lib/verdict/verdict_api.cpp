// SPDX-License-Identifier: Apache-2.0
// The C API of verdicts (flatline/verdict.h).
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/utf8_path.hpp"
#include "flatline/recon.h"
#include "flatline/verdict.h"
#include "verdict/rules.hpp"
#include "verdict/straightedge.hpp"
#include "verdict/verdict.hpp"

using namespace flt;
using flt::verdict::given_measure;
using flt::verdict::k_measures;
using flt::verdict::k_values;
using flt::verdict::rule;
using flt::verdict::rule_result;
using flt::verdict::straightedge;
using flt::verdict::straightedge_gap;

namespace {

// The largest sheet thickness and width a verdict takes (mm): anything
// beyond is a unit mistake, not a sheet.
constexpr double k_max_thickness = 1000.0;
constexpr double k_max_width = 100000.0;
// A straightedge longer than 10 km is a unit mistake.
constexpr double k_max_length = 1.0e7;

flt_status check_rules(const char *fn, const flt_rules *r) {
    if (r == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'rules' is NULL", fn);
    if (r->magic != flt_rules::k_magic)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'rules' is not a live flt_rules handle",
                    fn);
    return FLT_OK;
}

flt_status check_verdict(const char *fn, const flt_verdict *v) {
    if (v == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'verdict' is NULL", fn);
    if (v->magic != flt_verdict::k_magic)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'verdict' is not a live flt_verdict handle", fn);
    return FLT_OK;
}

// A sheet's verdict is the gauge's: read it, do not change it.
flt_status check_writable(const char *fn, const flt_verdict *v) {
    if (v->borrowed)
        return fail(FLT_ERR_STATE,
                    "%s: argument 'verdict' is a sheet's verdict (flt_sheet_verdict): read-only",
                    fn);
    return FLT_OK;
}

flt_status check_length(const char *fn, double length) {
    if (!(length > 0) || !(length <= k_max_length))
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'length_mm' = %g must be > 0 and <= %g (mm)", fn, length,
                    k_max_length);
    return FLT_OK;
}

// Strictly increasing finite positions.
flt_status check_positions(const char *fn, const char *name, const double *p, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(p[i]))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument '%s'[%zu] = %g is not finite", fn,
                        name, i, p[i]);
        if (i > 0 && !(p[i] > p[i - 1]))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument '%s'[%zu] = %.17g does not follow %.17g: positions must "
                        "increase strictly",
                        fn, name, i, p[i], p[i - 1]);
    }
    return FLT_OK;
}

// Heights: NaN is "not measured"; an infinity is an error.
flt_status check_heights(const char *fn, const char *name, const double *z, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i)
        if (std::isinf(z[i]))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument '%s'[%zu] is infinite", fn, name,
                        i);
    return FLT_OK;
}

flt_status read_file(const char *fn, const char *path, std::string &text) {
    std::FILE *f = flt::open_file(path, "rb");  // UTF-8 path, on Windows too
    if (f == nullptr)
        return fail(FLT_ERR_IO, "%s: cannot open '%.300s': %s", fn, path, std::strerror(errno));
    char chunk[4096];
    std::size_t got;
    // A rule set is a few kB; refuse anything absurd before reading it.
    constexpr std::size_t k_max_bytes = 1 << 20;
    while ((got = std::fread(chunk, 1, sizeof chunk, f)) > 0) {
        text.append(chunk, got);
        if (text.size() > k_max_bytes) {
            std::fclose(f);
            return fail(FLT_ERR_FORMAT, "%s: '%.300s' is larger than %zu bytes; not a rule file",
                        fn, path, k_max_bytes);
        }
    }
    const bool read_error = std::ferror(f) != 0;
    std::fclose(f);
    if (read_error)
        return fail(FLT_ERR_IO, "%s: cannot read '%.300s'", fn, path);
    return FLT_OK;
}

flt_status load(const char *fn, const char *text, std::size_t length, flt_rules **out) {
    auto r = std::make_unique<flt_rules>();
    try {
        r->set = flt::verdict::read_rules(text, length);
    } catch (const error &e) {
        return fail(e.status, "%s: %s", fn, e.what());
    }
    *out = r.release();
    return FLT_OK;
}

}  // namespace

// ------------------------------------------------------------------ rules

FLT_API flt_status FLT_CALL flt_rules_load(const char *path, flt_rules **out) {
    const char *fn = "flt_rules_load";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        FLT_CHECK_NOT_NULL(fn, path);
        std::string text;
        if (flt_status st = read_file(fn, path, text))
            return st;
        return load(fn, text.data(), text.size(), out);
    });
}

FLT_API flt_status FLT_CALL flt_rules_load_text(const char *text, size_t length, flt_rules **out) {
    const char *fn = "flt_rules_load_text";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        FLT_CHECK_NOT_NULL(fn, text);
        if (length > (std::size_t(1) << 20))
            return fail(FLT_ERR_FORMAT,
                        "%s: argument 'length' = %zu is larger than %zu bytes; "
                        "not a rule file",
                        fn, length, std::size_t(1) << 20);
        return load(fn, text, length, out);
    });
}

FLT_API void FLT_CALL flt_rules_destroy(flt_rules *rules) {
    guard_void([&] {
        if (rules != nullptr && rules->magic == flt_rules::k_magic && !rules->borrowed) {
            rules->magic = 0;
            delete rules;
        }
    });
}

FLT_API flt_status FLT_CALL flt_rules_count(const flt_rules *rules, size_t *out) {
    const char *fn = "flt_rules_count";
    return guard(fn, [&] {
        if (flt_status st = check_rules(fn, rules))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = rules->set.rules.size();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_rules_rule(const flt_rules *rules, size_t index, const char **name,
                                           flt_measure *measure, double *length_mm) {
    const char *fn = "flt_rules_rule";
    return guard(fn, [&] {
        if (flt_status st = check_rules(fn, rules))
            return st;
        if (index >= rules->set.rules.size())
            return fail(FLT_ERR_NOT_FOUND,
                        "%s: argument 'index' = %zu is past the last of %zu rules", fn, index,
                        rules->set.rules.size());
        const rule &r = rules->set.rules[index];
        if (name)
            *name = r.name.c_str();
        if (measure)
            *measure = r.measure;
        if (length_mm)
            *length_mm = r.length;
        return FLT_OK;
    });
}

// ------------------------------------------------------------- straightedge

FLT_API flt_status FLT_CALL flt_straightedge_profile(const double *position_mm,
                                                     const double *height_mm, size_t count,
                                                     double length_mm, double *deviation_mm,
                                                     double *at_mm) {
    const char *fn = "flt_straightedge_profile";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, deviation_mm);
        if (count > 0) {
            FLT_CHECK_NOT_NULL(fn, position_mm);
            FLT_CHECK_NOT_NULL(fn, height_mm);
        }
        if (count > std::numeric_limits<std::size_t>::max() / (4 * sizeof(double)))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'count' = %zu is too large", fn,
                        count);
        if (flt_status st = check_length(fn, length_mm))
            return st;
        if (flt_status st = check_positions(fn, "position_mm", position_mm, count))
            return st;
        if (flt_status st = check_heights(fn, "height_mm", height_mm, count))
            return st;
        straightedge se;
        const straightedge_gap g =
            se.measure(position_mm, height_mm, nullptr, count, 1, 0, length_mm, -1.0);
        if (!g.measured)
            return fail(FLT_ERR_NOT_FOUND,
                        "%s: fewer than 2 of the %zu samples are measured; nothing can rest on "
                        "them",
                        fn, count);
        *deviation_mm = g.deviation;
        if (at_mm)
            *at_mm = g.at;
        return FLT_OK;
    });
}

// ----------------------------------------------------------------- verdicts

FLT_API flt_status FLT_CALL flt_verdict_create(const flt_rules *rules, flt_verdict **out) {
    const char *fn = "flt_verdict_create";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        if (flt_status st = check_rules(fn, rules))
            return st;
        auto v = std::make_unique<flt_verdict>();
        v->set = rules->set;
        const std::size_t n = v->set.rules.size();
        v->results.resize(n);
        v->pending.resize(n);
        v->gaps.resize(n);
        *out = v.release();
        return FLT_OK;
    });
}

FLT_API void FLT_CALL flt_verdict_destroy(flt_verdict *verdict) {
    guard_void([&] {
        if (verdict != nullptr && verdict->magic == flt_verdict::k_magic && !verdict->borrowed) {
            verdict->magic = 0;
            delete verdict;
        }
    });
}

FLT_API flt_status FLT_CALL flt_verdict_set_measure(flt_verdict *verdict, flt_measure measure,
                                                    double value, double x_mm, double s_mm) {
    const char *fn = "flt_verdict_set_measure";
    return guard(fn, [&] {
        if (flt_status st = check_verdict(fn, verdict))
            return st;
        if (flt_status st = check_writable(fn, verdict))
            return st;
        const int m = enum_arg(measure);
        if (m < 0 || m >= k_measures)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'measure' = %d is not a flt_measure", fn, m);
        if (flt::verdict::is_straightedge(flt_measure(m)))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'measure' = %d is a straightedge: flt_verdict_evaluate "
                        "measures it on the height map",
                        fn, m);
        given_measure &g = verdict->given[m];
        if (std::isnan(value)) {
            g = given_measure{};
            return FLT_OK;
        }
        if (!std::isfinite(value))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'value' is infinite", fn);
        const bool signed_measure = m == FLT_MEASURE_BOW || m == FLT_MEASURE_CROSSBOW;
        if (!signed_measure && value < 0)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'value' = %g is negative; measure %d is never below 0", fn,
                        value, m);
        if (!std::isfinite(x_mm) || !std::isfinite(s_mm))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: arguments 'x_mm' = %g, 's_mm' = %g: a measured value needs a finite "
                        "position",
                        fn, x_mm, s_mm);
        g.value = value;
        g.x = x_mm;
        g.s = s_mm;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_verdict_evaluate(flt_verdict *verdict, double thickness_mm,
                                                 double width_mm, size_t rows, size_t fibers,
                                                 const double *s_mm, const double *x_mm,
                                                 const double *z_mm, const uint8_t *flags) {
    const char *fn = "flt_verdict_evaluate";
    return guard(fn, [&] {
        if (flt_status st = check_verdict(fn, verdict))
            return st;
        if (flt_status st = check_writable(fn, verdict))
            return st;
        if (!(thickness_mm > 0) || !(thickness_mm <= k_max_thickness))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'thickness_mm' = %g must be > 0 and <= %g", fn, thickness_mm,
                        k_max_thickness);
        if (!(width_mm > 0) || !(width_mm <= k_max_width))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'width_mm' = %g must be > 0 and <= %g", fn, width_mm,
                        k_max_width);
        if ((rows == 0) != (fibers == 0))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: arguments 'rows' = %zu, 'fibers' = %zu: both 0 (no map) or neither",
                        fn, rows, fibers);
        const bool has_map = rows > 0;
        if (has_map) {
            FLT_CHECK_NOT_NULL(fn, s_mm);
            FLT_CHECK_NOT_NULL(fn, x_mm);
            FLT_CHECK_NOT_NULL(fn, z_mm);
            if (rows > std::numeric_limits<std::size_t>::max() / sizeof(double) / fibers)
                return fail(FLT_ERR_INVALID_ARGUMENT,
                            "%s: arguments 'rows' = %zu x 'fibers' = %zu overflow a map", fn, rows,
                            fibers);
            if (flt_status st = check_positions(fn, "s_mm", s_mm, rows))
                return st;
            if (flt_status st = check_positions(fn, "x_mm", x_mm, fibers))
                return st;
            if (flt_status st = check_heights(fn, "z_mm", z_mm, rows * fibers))
                return st;
        }
        flt::verdict::map_view map;
        map.rows = rows;
        map.fibers = fibers;
        map.s = s_mm;
        map.x = x_mm;
        map.z = z_mm;
        map.flags = flags;
        flt::inline_block_runner runner;  // the caller's thread
        flt::verdict::judge(verdict->set, verdict->given, verdict->workspace, runner, thickness_mm,
                            width_mm, map, verdict->pending.data(), verdict->gaps.data());
        verdict->results.swap(verdict->pending);
        verdict->evaluated = true;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_verdict_get(const flt_verdict *verdict, size_t rule,
                                            flt_verdict_value key, double *out) {
    const char *fn = "flt_verdict_get";
    return guard(fn, [&] {
        if (flt_status st = check_verdict(fn, verdict))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (!verdict->evaluated)
            return fail(FLT_ERR_STATE, "%s: no sheet was evaluated yet (flt_verdict_evaluate)", fn);
        if (rule >= verdict->results.size())
            return fail(FLT_ERR_NOT_FOUND,
                        "%s: argument 'rule' = %zu is past the last of %zu rules", fn, rule,
                        verdict->results.size());
        const int k = enum_arg(key);
        if (k < 0 || k >= k_values)
            return fail(FLT_ERR_NOT_FOUND, "%s: argument 'key' = %d is not a flt_verdict_value", fn,
                        k);
        *out = verdict->results[rule].value[k];
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_verdict_failed(const flt_verdict *verdict, size_t *out) {
    const char *fn = "flt_verdict_failed";
    return guard(fn, [&] {
        if (flt_status st = check_verdict(fn, verdict))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (!verdict->evaluated)
            return fail(FLT_ERR_STATE, "%s: no sheet was evaluated yet (flt_verdict_evaluate)", fn);
        std::size_t n = 0;
        for (const rule_result &r : verdict->results)
            n += r.value[FLT_VERDICT_STATE] == FLT_VERDICT_FAIL ? 1 : 0;
        *out = n;
        return FLT_OK;
    });
}
