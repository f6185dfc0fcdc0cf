// SPDX-License-Identifier: Apache-2.0
#include "sources/source.hpp"

#include <cstdarg>
#include <cstdio>

#include "core/error.hpp"
#include "core/number_text.hpp"

namespace flt::sources {

// NOLINTNEXTLINE(cert-dcl50-cpp): printf-style on purpose, the format attribute checks it
void raise(flt_status status, const char *format, ...) {
    char text[400];
    va_list args;
    va_start(args, format);
    vformat_c(text, sizeof text, format, args);  // '.' whatever LC_NUMERIC says
    va_end(args);
    throw error(status, text);
}

const std::string &source_impl::stream_error() const {
    static const std::string none;
    return none;
}

}  // namespace flt::sources
