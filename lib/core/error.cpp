// SPDX-License-Identifier: Apache-2.0
#include "core/error.hpp"

#include <cstdio>
#include <string>

#include "core/number_text.hpp"

namespace flt {
namespace {
// Fixed-size per-thread storage: recording an error must not allocate (it is
// also how out-of-memory is reported).
struct thread_error {
    flt_status status = FLT_OK;
    char message[512] = {0};
};
thread_local thread_error t_error;
}  // namespace

// NOLINTNEXTLINE(cert-dcl50-cpp): printf-style on purpose, the format attribute checks it
flt_status fail(flt_status status, const char *format, ...) {
    va_list args;
    va_start(args, format);
    // Numbers in messages are written the same under every LC_NUMERIC.
    vformat_c(t_error.message, sizeof t_error.message, format, args);
    va_end(args);
    t_error.status = status;
    return status;
}

void clear_error() {
    t_error.status = FLT_OK;
    t_error.message[0] = '\0';
}

void set_status(flt_status status) {
    t_error.status = status;
    if (status != FLT_OK && t_error.message[0] == '\0')
        std::snprintf(t_error.message, sizeof t_error.message, "failed with %s",
                      flt_status_string(status));
}

void record_exception(const char *function, const std::exception &e, flt_status status) {
    fail(status, "%s: %s", function, e.what());
}

}  // namespace flt

extern "C" {

FLT_API const char *FLT_CALL flt_status_string(flt_status status) {
    switch (status) {
        case FLT_OK:
            return "FLT_OK";
        case FLT_ERR_INVALID_ARGUMENT:
            return "FLT_ERR_INVALID_ARGUMENT";
        case FLT_ERR_OUT_OF_MEMORY:
            return "FLT_ERR_OUT_OF_MEMORY";
        case FLT_ERR_STATE:
            return "FLT_ERR_STATE";
        case FLT_ERR_BUFFER_FULL:
            return "FLT_ERR_BUFFER_FULL";
        case FLT_ERR_IO:
            return "FLT_ERR_IO";
        case FLT_ERR_FORMAT:
            return "FLT_ERR_FORMAT";
        case FLT_ERR_DEVICE:
            return "FLT_ERR_DEVICE";
        case FLT_ERR_TIMEOUT:
            return "FLT_ERR_TIMEOUT";
        case FLT_ERR_NOT_FOUND:
            return "FLT_ERR_NOT_FOUND";
        case FLT_ERR_NUMERIC:
            return "FLT_ERR_NUMERIC";
        case FLT_ERR_INTERNAL:
            return "FLT_ERR_INTERNAL";
        case FLT_STATUS_MAX_ENUM_:
            break;
    }
    return "FLT_ERR_UNKNOWN";
}

FLT_API const char *FLT_CALL flt_last_error_message(void) {
    return flt::t_error.message;
}

FLT_API flt_status FLT_CALL flt_last_error_status(void) {
    return flt::t_error.status;
}

FLT_API void FLT_CALL flt_set_last_error(flt_status status, const char *message) {
    if (status == FLT_OK) {
        flt::clear_error();
        return;
    }
    // The message may be flt_last_error_message() itself: copy it first.
    char text[sizeof flt::t_error.message] = {0};
    if (message)
        std::snprintf(text, sizeof text, "%s", message);
    flt::t_error.message[0] = '\0';
    if (text[0])
        flt::fail(status, "%s", text);
    flt::set_status(status);
}

FLT_API int FLT_CALL flt_version(void) {
    return FLT_VERSION_NUMBER;
}

FLT_API const char *FLT_CALL flt_version_string(void) {
    return FLT_VERSION_STRING;
}

}  // extern "C"
