// SPDX-License-Identifier: Apache-2.0
// Internal: kernels built twice on x86-64, for the baseline (SSE2) and for
// AVX2, the AVX2 build taken at run time where the CPU has it.
//
// Why not GCC's target_clones: it needs the ELF loader's ifunc, so the
// Windows DLL (two of our three users) ran the baseline on every machine,
// and the baseline is 1.7-2.7 times slower in the extractor's and the
// reconstructor's kernels (below) (SSE2 has two doubles a register, and lacks
// unsigned 32-bit min and max and blends, which the compiler then spells
// out per lane). Without FMA (never enabled here) AVX2 rounds every
// operation as the baseline does, so results do not depend on the machine.
//
// A file's kernels live in a file of their own, built twice, in namespaces
// base and avx2, by core/cpu_dispatch_build.inc:
//
//   #define FLT_KERNELS_FILE "reconstruction/window_kernels.inc"
//   #include "core/cpu_dispatch_build.inc"
//   FLT_DISPATCH(store_row)   // store_row(...) calls avx2:: or base::
//
// Measured with the choice forced (bench_extractor, bench_recon, one core):
// the extractor 1,340 against 3,600 frames/s; flt_reconstruct of 2000 x
// 1150 15.4 against 6.6 ms of CPU; streaming 10.5 against 6.0 us per row,
// with rigid_motion and robust 77 against 39. Results are the same bits.
#pragma once

#include <utility>

#if (defined(__GNUC__) || defined(__clang__)) && defined(__x86_64__)
#  define FLT_HAVE_AVX2_BUILD 1
#else
#  define FLT_HAVE_AVX2_BUILD 0
#endif

namespace flt {

// Whether this CPU runs AVX2 (asked once; false where there is no AVX2
// build).
inline bool cpu_has_avx2() {
#if FLT_HAVE_AVX2_BUILD
    static const bool has = [] {
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx2") != 0;
    }();
    return has;
#else
    return false;
#endif
}

}  // namespace flt

// The functions defined between FLT_AVX2_BEGIN and FLT_AVX2_END are built
// for AVX2 (without FMA).
#if FLT_HAVE_AVX2_BUILD && defined(__clang__)
#  define FLT_AVX2_BEGIN \
    _Pragma("clang attribute push(__attribute__((target(\"avx2\"))), apply_to = function)")
#  define FLT_AVX2_END _Pragma("clang attribute pop")
#elif FLT_HAVE_AVX2_BUILD
#  define FLT_AVX2_BEGIN _Pragma("GCC push_options") _Pragma("GCC target(\"avx2\")")
#  define FLT_AVX2_END   _Pragma("GCC pop_options")
#endif

// name(...) calls avx2::name(...) where the CPU has AVX2, else
// base::name(...), with the same arguments.
#if FLT_HAVE_AVX2_BUILD
#  define FLT_DISPATCH(name)                                                  \
    template <class... Args> inline auto name(Args &&...args) {               \
      return ::flt::cpu_has_avx2() ? avx2::name(std::forward<Args>(args)...)  \
                                   : base::name(std::forward<Args>(args)...); \
    }
#else
#  define FLT_DISPATCH(name)                                    \
    template <class... Args> inline auto name(Args &&...args) { \
      return base::name(std::forward<Args>(args)...);           \
    }
#endif
