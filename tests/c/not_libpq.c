// SPDX-License-Identifier: Apache-2.0
/* A shared library that is not libpq, with no dependency that could bring
 * libpq's functions along (test_archive_libpq loads it as FLT_LIBPQ). */
#ifdef _WIN32
#  define NOT_LIBPQ_EXPORT __declspec(dllexport)
#else
#  define NOT_LIBPQ_EXPORT __attribute__((visibility("default")))
#endif

NOT_LIBPQ_EXPORT int flt_not_libpq(void);

int flt_not_libpq(void) {
    return 42;
}
