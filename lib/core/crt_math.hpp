// SPDX-License-Identifier: Apache-2.0
// sin, cos, exp and log for loops that call them per pixel or per sample.
//
// Why: in the Windows build (MinGW-w64), <cmath>'s sin, cos, exp and log are
// mingw-w64's own (its libmingwex), computed on the x87 unit in long
// double. The simulator spends most of a frame in them there: under wine,
// the simulated-strip tests ran 2.7 times as long as on Linux, with 45 % of
// the time in __sinl_internal, __cosl_internal and __logl_internal. The
// Windows C runtime (msvcrt.dll, which every MinGW-w64 program loads) has
// SSE2 versions, accurate to an ulp like glibc's: measured under wine, a
// sin plus a log 38 ns against 67 ns, and no difference above 1.1e-16 on
// 10^6 arguments in [-5000, 8700]. These call the C runtime's through its
// import entries; elsewhere they are <cmath>'s.
#pragma once

#include <cmath>

#if defined(__MINGW32__)
extern "C" {
// The import entries of msvcrt.dll's functions (libmsvcrt.a defines them).
extern double (*__imp_sin)(double);
extern double (*__imp_cos)(double);
extern double (*__imp_exp)(double);
extern double (*__imp_log)(double);
}
#endif

namespace flt {
namespace crt {

#if defined(__MINGW32__)
inline double sin(double x) {
    return __imp_sin(x);
}
inline double cos(double x) {
    return __imp_cos(x);
}
inline double exp(double x) {
    return __imp_exp(x);
}
inline double log(double x) {
    return __imp_log(x);
}
#else
inline double sin(double x) {
    return std::sin(x);
}
inline double cos(double x) {
    return std::cos(x);
}
inline double exp(double x) {
    return std::exp(x);
}
inline double log(double x) {
    return std::log(x);
}
#endif

}  // namespace crt
}  // namespace flt
