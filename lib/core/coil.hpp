// SPDX-License-Identifier: Apache-2.0
// Internal: a coil's identity (flatline/coil.h), a value the gauge, the
// recordings and the archive copy around.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "flatline/coil.h"

namespace flt {

constexpr std::uint32_t k_coil_magic = 0x434f494cu;  // "COIL"
constexpr int k_coil_fields = 5;                     // flt_coil_field values

// Checks a field's or an extra's text: UTF-8, no control characters, at
// most FLT_COIL_TEXT_MAX bytes. Empty when it is fine, else why not.
std::string coil_text_problem(const char *text);
// The same for an extra's key.
std::string coil_key_problem(const char *key);

// The field's name as the recordings and the archive spell their columns
// ("coil_id", "order_no", "heat", "grade", "customer").
const char *coil_field_column(int field);

}  // namespace flt

struct flt_coil_info {
    std::uint32_t magic = flt::k_coil_magic;
    // Lent by a sheet or a gauge: read-only for the caller, and not freed
    // by flt_coil_info_destroy.
    bool lent = false;
    // std::array, not a C array: the copy a gauge makes of an identity is
    // then a plain member-wise copy (clang-tidy flags the loop variable
    // the compiler invents for a C array's implicit copy).
    std::array<std::string, flt::k_coil_fields> text;
    double thickness_mm = 0.0, width_mm = 0.0;  // 0: not given
    std::vector<std::pair<std::string, std::string>> extras;

    bool operator==(const flt_coil_info &o) const {
        return text == o.text && thickness_mm == o.thickness_mm && width_mm == o.width_mm &&
               extras == o.extras;
    }
    bool operator!=(const flt_coil_info &o) const { return !(*this == o); }
};

namespace flt {
// A live handle the caller passed (its magic checked).
inline bool is_coil_info(const flt_coil_info *info) {
    return info != nullptr && info->magic == k_coil_magic;
}
}  // namespace flt
