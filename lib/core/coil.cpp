// SPDX-License-Identifier: Apache-2.0
// Coil identity (flatline/coil.h): text checks and the C entry points.
#include "core/coil.hpp"

#include <cmath>
#include <cstring>
#include <memory>

#include "core/error.hpp"

namespace flt {
namespace {

// The length of the UTF-8 sequence starting at s (1..4), or 0 when it is
// malformed (overlong forms, surrogates and code points past U+10FFFF are).
std::size_t utf8_sequence(const unsigned char *s, std::size_t left) {
    const unsigned c = s[0];
    if (c < 0x80)
        return 1;
    std::size_t n = 0;
    std::uint32_t cp = 0;
    if ((c & 0xE0) == 0xC0) {
        n = 2;
        cp = c & 0x1F;
    } else if ((c & 0xF0) == 0xE0) {
        n = 3;
        cp = c & 0x0F;
    } else if ((c & 0xF8) == 0xF0) {
        n = 4;
        cp = c & 0x07;
    } else {
        return 0;
    }
    if (n > left)
        return 0;
    for (std::size_t i = 1; i < n; ++i) {
        if ((s[i] & 0xC0) != 0x80)
            return 0;
        cp = (cp << 6) | (s[i] & 0x3F);
    }
    static const std::uint32_t least[5] = {0, 0, 0x80, 0x800, 0x10000};
    if (cp < least[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF))
        return 0;
    return n;
}

}  // namespace

std::string coil_text_problem(const char *text) {
    const std::size_t length = std::strlen(text);
    if (length > FLT_COIL_TEXT_MAX)
        return "is " + std::to_string(length) + " bytes long (at most " +
               std::to_string(FLT_COIL_TEXT_MAX) + ")";
    const auto *s = reinterpret_cast<const unsigned char *>(text);
    for (std::size_t i = 0; i < length;) {
        if (s[i] < 0x20 || s[i] == 0x7F)
            return "holds a control character (byte " + std::to_string(i) + ")";
        const std::size_t n = utf8_sequence(s + i, length - i);
        if (n == 0)
            return "is not UTF-8 (byte " + std::to_string(i) + ")";
        i += n;
    }
    return {};
}

std::string coil_key_problem(const char *key) {
    const std::size_t length = std::strlen(key);
    if (length == 0 || length > 64)
        return "must be 1 to 64 characters long";
    for (std::size_t i = 0; i < length; ++i) {
        const char c = key[i];
        const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                        (c >= '0' && c <= '9') || c == '_' || c == '-' || c == '.';
        if (!ok)
            return "may hold only ASCII letters, digits, '_', '-' and '.'";
    }
    return {};
}

const char *coil_field_column(int field) {
    static const char *const names[k_coil_fields] = {"coil_id", "order_no", "heat", "grade",
                                                     "customer"};
    return field >= 0 && field < k_coil_fields ? names[field] : "?";
}

}  // namespace flt

using flt::fail;
using flt::guard;

namespace {

flt_status check_info(const char *fn, const flt_coil_info *info) {
    if (info == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'info' is NULL", fn);
    if (!flt::is_coil_info(info))
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'info' is not a coil identity", fn);
    return FLT_OK;
}

flt_status check_writable(const char *fn, const flt_coil_info *info) {
    if (flt_status st = check_info(fn, info))
        return st;
    if (info->lent)
        return fail(FLT_ERR_STATE,
                    "%s: this coil identity is lent by a sheet or a gauge and is read-only "
                    "(flt_coil_info_copy makes one you can change)",
                    fn);
    return FLT_OK;
}

flt_status check_field(const char *fn, const flt_coil_field &field, int *out) {
    const int f = flt::enum_arg(field);
    if (f < 0 || f >= flt::k_coil_fields)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'field' is %d (0..%d)", fn, f,
                    flt::k_coil_fields - 1);
    *out = f;
    return FLT_OK;
}

}  // namespace

extern "C" {

FLT_API flt_status FLT_CALL flt_coil_info_create(const char *coil_id, flt_coil_info **out) {
    const char *fn = "flt_coil_info_create";
    if (out)
        *out = nullptr;
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, coil_id);
        FLT_CHECK_NOT_NULL(fn, out);
        if (coil_id[0] == '\0')
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'coil_id' is empty", fn);
        const std::string why = flt::coil_text_problem(coil_id);
        if (!why.empty())
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'coil_id' %s", fn, why.c_str());
        auto info = std::make_unique<flt_coil_info>();
        info->text[FLT_COIL_FIELD_ID] = coil_id;
        *out = info.release();
        return FLT_OK;
    });
}

FLT_API void FLT_CALL flt_coil_info_destroy(flt_coil_info *info) {
    flt::guard_void([&] {
        if (flt::is_coil_info(info) && !info->lent) {
            info->magic = 0;
            delete info;
        }
    });
}

FLT_API flt_status FLT_CALL flt_coil_info_copy(const flt_coil_info *info, flt_coil_info **out) {
    const char *fn = "flt_coil_info_copy";
    if (out)
        *out = nullptr;
    return guard(fn, [&] {
        if (flt_status st = check_info(fn, info))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        auto copy = std::make_unique<flt_coil_info>(*info);
        copy->lent = false;
        *out = copy.release();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_coil_info_set_text(flt_coil_info *info, flt_coil_field field,
                                                   const char *value) {
    const char *fn = "flt_coil_info_set_text";
    return guard(fn, [&] {
        if (flt_status st = check_writable(fn, info))
            return st;
        int f = 0;
        if (flt_status st = check_field(fn, field, &f))
            return st;
        FLT_CHECK_NOT_NULL(fn, value);
        const std::string why = flt::coil_text_problem(value);
        if (!why.empty())
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'value' (%s) %s", fn,
                        flt::coil_field_column(f), why.c_str());
        if (f == FLT_COIL_FIELD_ID && value[0] == '\0')
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: the coil id cannot be empty", fn);
        info->text[f] = value;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_coil_info_get_text(const flt_coil_info *info, flt_coil_field field,
                                                   const char **out) {
    const char *fn = "flt_coil_info_get_text";
    return guard(fn, [&] {
        if (flt_status st = check_info(fn, info))
            return st;
        int f = 0;
        if (flt_status st = check_field(fn, field, &f))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = info->text[f].c_str();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_coil_info_set_nominal(flt_coil_info *info, double thickness_mm,
                                                      double width_mm) {
    const char *fn = "flt_coil_info_set_nominal";
    return guard(fn, [&] {
        if (flt_status st = check_writable(fn, info))
            return st;
        if (!(thickness_mm == 0.0 || (thickness_mm > 0.0 && thickness_mm <= 1000.0)))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'thickness_mm' is %g (0 for not given, else 0 < t <= 1000)",
                        fn, thickness_mm);
        if (!(width_mm == 0.0 || (width_mm > 0.0 && width_mm <= 100000.0)))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'width_mm' is %g (0 for not given, else 0 < w <= 100000)", fn,
                        width_mm);
        info->thickness_mm = thickness_mm;
        info->width_mm = width_mm;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_coil_info_get_nominal(const flt_coil_info *info,
                                                      double *thickness_mm_out,
                                                      double *width_mm_out) {
    const char *fn = "flt_coil_info_get_nominal";
    return guard(fn, [&] {
        if (flt_status st = check_info(fn, info))
            return st;
        if (thickness_mm_out)
            *thickness_mm_out = info->thickness_mm;
        if (width_mm_out)
            *width_mm_out = info->width_mm;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_coil_info_set_extra(flt_coil_info *info, const char *key,
                                                    const char *value) {
    const char *fn = "flt_coil_info_set_extra";
    return guard(fn, [&] {
        if (flt_status st = check_writable(fn, info))
            return st;
        FLT_CHECK_NOT_NULL(fn, key);
        const std::string why = flt::coil_key_problem(key);
        if (!why.empty())
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'key' %s", fn, why.c_str());
        auto &extras = info->extras;
        auto it = extras.begin();
        while (it != extras.end() && it->first != key)
            ++it;
        if (value == nullptr) {
            if (it != extras.end())
                extras.erase(it);
            return FLT_OK;
        }
        const std::string vwhy = flt::coil_text_problem(value);
        if (!vwhy.empty())
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'value' (key '%s') %s", fn, key,
                        vwhy.c_str());
        if (it != extras.end()) {
            it->second = value;
            return FLT_OK;
        }
        if (extras.size() >= FLT_COIL_EXTRA_MAX)
            return fail(FLT_ERR_BUFFER_FULL, "%s: the coil has %d extras already (the most)", fn,
                        FLT_COIL_EXTRA_MAX);
        extras.emplace_back(key, value);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_coil_info_extra_count(const flt_coil_info *info, size_t *out) {
    const char *fn = "flt_coil_info_extra_count";
    return guard(fn, [&] {
        if (flt_status st = check_info(fn, info))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = info->extras.size();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_coil_info_extra(const flt_coil_info *info, size_t index,
                                                const char **key_out, const char **value_out) {
    const char *fn = "flt_coil_info_extra";
    return guard(fn, [&] {
        if (flt_status st = check_info(fn, info))
            return st;
        if (index >= info->extras.size())
            return fail(FLT_ERR_NOT_FOUND, "%s: argument 'index' is %zu (the coil has %zu extras)",
                        fn, index, info->extras.size());
        if (key_out)
            *key_out = info->extras[index].first.c_str();
        if (value_out)
            *value_out = info->extras[index].second.c_str();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_coil_info_find_extra(const flt_coil_info *info, const char *key,
                                                     const char **out) {
    const char *fn = "flt_coil_info_find_extra";
    return guard(fn, [&] {
        if (flt_status st = check_info(fn, info))
            return st;
        FLT_CHECK_NOT_NULL(fn, key);
        FLT_CHECK_NOT_NULL(fn, out);
        for (const auto &e : info->extras)
            if (e.first == key) {
                *out = e.second.c_str();
                return FLT_OK;
            }
        return fail(FLT_ERR_NOT_FOUND, "%s: the coil has no extra '%.64s'", fn, key);
    });
}

}  // extern "C"
