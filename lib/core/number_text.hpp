// SPDX-License-Identifier: Apache-2.0
// Internal: number text that does not depend on the locale.
//
// printf's %g/%f, strtod, atof and iostreams follow LC_NUMERIC: a process
// (an HMI) that sets a German locale gets "1090,909" from them, and strtod
// stops at the '.' of "1090.909". Files, protocol text and messages of the
// library must read and write the same text in every process, so every
// number the library turns into text or reads from text goes through here:
// std::to_chars / std::from_chars, which are specified to use the C
// locale's syntax whatever the process locale is.
#pragma once

#include <cstdarg>
#include <cstddef>
#include <string>
#include <string_view>

namespace flt {

// The shortest text that reads back as exactly `v` ("0.1", "1090.909090909091",
// "1e-300"); '.' as the decimal point, no thousands separator. NaN and
// infinities come out as "nan", "-inf", "inf".
std::string format_double(double v);

// Reads a whole text as one finite double in the C syntax: optional sign,
// digits with an optional '.', optional exponent ("-1.5", "+2e-3", "7").
// Nothing may come before or after it (no space, no ','); "nan", "inf" and
// hexadecimal are refused. Returns false (out unchanged) if the text is not
// such a number or does not fit a double.
bool parse_double(std::string_view text, double &out);

// snprintf/vsnprintf whose floating conversions (%e %f %g %a, upper case
// too, with flags, width and precision) always write '.' as the decimal
// point; every other conversion is the C library's. Same return value and
// truncation as vsnprintf. Does not allocate (error messages are recorded
// with it, also on out-of-memory).
int vformat_c(char *out, std::size_t size, const char *format, va_list args);
int format_c(char *out, std::size_t size, const char *format, ...)
#if defined(__MINGW32__)  // MinGW's C99 printf (__USE_MINGW_ANSI_STDIO) is gnu_printf
    __attribute__((format(__MINGW_PRINTF_FORMAT, 3, 4)))
#elif defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

}  // namespace flt
