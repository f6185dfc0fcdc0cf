// SPDX-License-Identifier: Apache-2.0
/* A shared library that is not libpq, with no dependency that could bring
 * libpq's functions along (test_archive_libpq loads it as FLT_LIBPQ). */
#ifdef _WIN32
__declspec(dllexport)
#else
__attribute__((visibility("default")))
#endif
int flt_not_libpq(void) {
    return 42;
}
