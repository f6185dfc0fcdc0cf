// SPDX-License-Identifier: Apache-2.0
// The error state of libflatline_testing: its own copy of the functions
// core/error.hpp declares (hidden in this library), writing through
// flt_set_last_error() into libflatline's thread-local state, so that
// flt_last_error_message() reports a failing flt_u3v_sim_* call as it does
// libflatline's own. (libflatline's copies are hidden in libflatline.)
#include <cstdarg>
#include <cstdio>

#include "core/error.hpp"

namespace flt {

// NOLINTNEXTLINE(cert-dcl50-cpp): printf-style on purpose, the format attribute checks it
flt_status fail(flt_status status, const char *format, ...) {
    char text[512];
    va_list args;
    va_start(args, format);
    std::vsnprintf(text, sizeof text, format, args);
    va_end(args);
    flt_set_last_error(status, text);
    return status;
}

void clear_error() {
    flt_set_last_error(FLT_OK, nullptr);
}

void set_status(flt_status status) {
    if (status == FLT_OK)
        flt_set_last_error(FLT_OK, nullptr);
    else if (flt_last_error_status() != status || flt_last_error_message()[0] == '\0')
        flt_set_last_error(status, flt_last_error_message());
}

void record_exception(const char *function, const std::exception &e, flt_status status) {
    fail(status, "%s: %s", function, e.what());
}

}  // namespace flt
