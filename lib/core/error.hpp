// SPDX-License-Identifier: Apache-2.0
// Internal: the thread-local error state and the guard that keeps C++
// exceptions from crossing the C boundary. Every extern "C" entry point of
// the library is written as
//
//     flt_status flt_x_do(...) { return flt::guard("flt_x_do", [&] { ... }); }
//
// and reports bad input with `return flt::fail(FLT_ERR_..., "...", ...)`.
#pragma once

#include <cmath>
#include <cstdarg>
#include <cstring>
#include <new>
#include <stdexcept>

#include "flatline/common.h"

namespace flt {

// printf-style format checks: MinGW's C99 printf (__USE_MINGW_ANSI_STDIO,
// set by the build) is gnu_printf there, not the msvcrt `printf` format.
#if defined(__MINGW32__)
#  define FLT_PRINTF_FORMAT(fmt, args) __attribute__((format(__MINGW_PRINTF_FORMAT, fmt, args)))
#elif defined(__GNUC__)
#  define FLT_PRINTF_FORMAT(fmt, args) __attribute__((format(printf, fmt, args)))
#else
#  define FLT_PRINTF_FORMAT(fmt, args)
#endif

// Records status and a printf-style message for this thread; returns status.
flt_status fail(flt_status status, const char *format, ...) FLT_PRINTF_FORMAT(2, 3);

// Clears the thread-local state (called on entry of every public function).
void clear_error();

// Records the outcome of a guarded call (so flt_last_error_status() is right).
void set_status(flt_status status);

// Thrown inside the library where unwinding is simpler than returning; the
// guard turns it into its status. Never escapes the library.
struct error : std::runtime_error {
    flt_status status;
    error(flt_status st, const char *msg) : std::runtime_error(msg), status(st) {}
};

void record_exception(const char *function, const std::exception &e, flt_status status);

// The int an enum argument carries. C passes any int where a flt_ enum is
// declared; in C++ an enum without a fixed underlying type only has the
// values of the smallest bit-field that holds its enumerators (0 .. 2^31-1
// with the MAX_ENUM_ sentinels), and reading a negative one as the enum is
// undefined behaviour (UBSan's -fsanitize=enum says so). Entry points read
// the argument's bytes with this, refuse a negative value, and only then
// use it as the enum.
template <class E> inline int enum_arg(const E &value) {
    static_assert(sizeof(E) == sizeof(int), "flt_ enums are int-sized (common.h)");
    int raw;
    std::memcpy(&raw, &value, sizeof raw);
    return raw;
}

// The one guard. `body` returns flt_status.
template <class Body> flt_status guard(const char *function, Body &&body) noexcept {
    clear_error();
    try {
        flt_status st = body();
        set_status(st);
        return st;
    } catch (const error &e) {
        record_exception(function, e, e.status);
        return e.status;
    } catch (const std::bad_alloc &e) {
        record_exception(function, e, FLT_ERR_OUT_OF_MEMORY);
        return FLT_ERR_OUT_OF_MEMORY;
    } catch (const std::exception &e) {
        // cv::Exception derives from std::exception and lands here too.
        record_exception(function, e, FLT_ERR_INTERNAL);
        return FLT_ERR_INTERNAL;
    } catch (...) {
        fail(FLT_ERR_INTERNAL, "%s: unknown exception", function);
        return FLT_ERR_INTERNAL;
    }
}

// The same for functions with no status to return (destroy): swallows
// everything, because a destructor must not fail.
template <class Body> void guard_void(Body &&body) noexcept {
    try {
        body();
    } catch (...) {
    }
}

// Argument checks shared by every component. Each names the function and the
// argument in the message.
#define FLT_CHECK_NOT_NULL(fn, arg)                                                        \
  do {                                                                                     \
    if ((arg) == nullptr)                                                                  \
      return ::flt::fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument '%s' is NULL", fn, #arg); \
  } while (0)

}  // namespace flt
