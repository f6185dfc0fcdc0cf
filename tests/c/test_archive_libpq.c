// SPDX-License-Identifier: Apache-2.0
/*
 * libpq is loaded when a PostgreSQL archive is opened, from the file the
 * environment variable FLT_LIBPQ names (UTF-8, as every path the library
 * takes; on Windows converted for LoadLibraryW). Here FLT_LIBPQ names a
 * shared library that is not libpq (a copy of tests/c/not_libpq.c's, which
 * depends on nothing that could bring libpq along) in a folder named
 * "Jürgen": the library must load it from exactly that path
 * (the narrow, ANSI-code-page call would look for "JÃ¼rgen") and refuse it
 * with FLT_ERR_NOT_FOUND, naming the file and the first libpq function it
 * lacks, instead of calling into it. One load per process (libpq is loaded
 * once and kept), so this is a program of its own.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "flatline/flatline.h"
#include "test_files.h"

#ifndef _WIN32
#  define NOT_LIBPQ_NAME "not_libpq.so"
#else
#  define NOT_LIBPQ_NAME "not_libpq.dll"
#endif

/* The shared library copied: beside the test program on Windows (the
 * build puts the DLLs there; its path at build time is a Linux one under
 * wine), by its path elsewhere. */
static int source_library(char *out, size_t cap) {
#ifdef _WIN32
    wchar_t exe[MAX_PATH];
    const DWORD n = GetModuleFileNameW(NULL, exe, MAX_PATH);
    if (n == 0 || n >= MAX_PATH)
        return -1;
    wchar_t *slash = wcsrchr(exe, L'\\');
    if (!slash)
        return -1;
    slash[1] = 0;
    char dir[4 * MAX_PATH];
    if (WideCharToMultiByte(CP_UTF8, 0, exe, -1, dir, (int)sizeof dir, NULL, NULL) <= 0)
        return -1;
    return snprintf(out, cap, "%s%s", dir, FLT_NOT_LIBPQ_NAME) < (int)cap ? 0 : -1;
#else
    return snprintf(out, cap, "%s", FLT_NOT_LIBPQ) < (int)cap ? 0 : -1;
#endif
}

static int copy_file(const char *from, const char *to) {
    FILE *in = tf_fopen(from, "rb"), *out = tf_fopen(to, "wb");
    int status = in && out ? 0 : -1;
    char buf[65536];
    size_t n;
    while (status == 0 && (n = fread(buf, 1, sizeof buf, in)) > 0)
        if (fwrite(buf, 1, n, out) != n)
            status = -1;
    if (in)
        fclose(in);
    if (out && fclose(out) != 0)
        status = -1;
    return status;
}

static void test_not_libpq_refused(void **state) {
    (void)state;
    char dir[512], folder[600], path[700], from[1024];
    assert_int_equal(tf_temp_dir(dir, sizeof dir, "libpq"), 0);
    snprintf(folder, sizeof folder, "%s/J\xC3\xBCrgen", dir);
    assert_int_equal(tf_mkdir(folder), 0);
    snprintf(path, sizeof path, "%s/" NOT_LIBPQ_NAME, folder);
    assert_int_equal(source_library(from, sizeof from), 0);
    if (copy_file(from, path) != 0)
        fail_msg("cannot copy %s to %s", from, path);
#ifdef _WIN32
    assert_int_equal(_putenv_s("FLT_LIBPQ", path), 0);
#else
    assert_int_equal(setenv("FLT_LIBPQ", path, 1), 0);
#endif
    flt_archive *ar = NULL;
    const flt_status st =
        flt_archive_open("pg:host=127.0.0.1 port=1 dbname=none connect_timeout=1", "", NULL, &ar);
    if (st != FLT_ERR_NOT_FOUND)
        fail_msg("status %s, expected FLT_ERR_NOT_FOUND: %s", flt_status_string(st),
                 flt_last_error_message());
    assert_null(ar);
    const char *m = flt_last_error_message();
    print_message("%s\n", m);
    /* Loaded (from the "Jürgen" folder: a wrong path would not load) and
     * refused for what it lacks. */
    if (!strstr(m, "was loaded but has no function PQconnectdb"))
        fail_msg("the message does not say the file was loaded and lacks PQconnectdb: %s", m);
    if (!strstr(m, "J\xC3\xBCrgen"))
        fail_msg("the message does not name the file (UTF-8): %s", m);
    /* The library stays loaded (as libpq would): Windows keeps a loaded
     * DLL's file, so there the folder may stay behind in the temp folder. */
    tf_remove_tree(dir);
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_not_libpq_refused)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
