// SPDX-License-Identifier: Apache-2.0
/*
 * Test helper: real-world files that are not part of the repository (camera
 * description XMLs, laser and calibration photos) live in the folder named
 * by the environment variable FLT_EXTERNAL_DATA. ctest sets it from the
 * CMake cache variable of the same name for the tests registered with
 * flt_uses_external_data(); run by hand, export it yourself.
 *
 * Further photos of laser lines, which the project found in public
 * repositories after it had tuned the extractor (docs/sensor.md, "Real
 * photos"), live in a second folder, FLT_FURTHER_PHOTOS, set the same way.
 *
 * A test on such a file calls flt_external_path() and skips (CMocka's
 * skip()) with the message it printed when the file is absent, so a clone
 * without the folder still passes.
 */
#ifndef FLT_TEST_EXTERNAL_DATA_H
#define FLT_TEST_EXTERNAL_DATA_H

#include <stdio.h>
#include <stdlib.h>

/* Writes $variable/relative into path[size] (variable: the environment
 * variable that names the folder) and returns 1 when that file can be opened
 * for reading; otherwise prints why on stderr and returns 0 (the caller
 * skips). */
static inline int flt_external_path_in(const char *variable, const char *relative, char *path,
                                       size_t size) {
    const char *root = getenv(variable);
    if (root == NULL || root[0] == '\0') {
        fprintf(stderr, "skipped: %s is not set (needed for %s)\n", variable, relative);
        return 0;
    }
    int n = snprintf(path, size, "%s/%s", root, relative);
    if (n < 0 || (size_t)n >= size) {
        fprintf(stderr, "skipped: path too long: %s/%s\n", root, relative);
        return 0;
    }
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        fprintf(stderr, "skipped: %s is absent\n", path);
        return 0;
    }
    fclose(f);
    return 1;
}

/* The same under FLT_EXTERNAL_DATA. */
static inline int flt_external_path(const char *relative, char *path, size_t size) {
    return flt_external_path_in("FLT_EXTERNAL_DATA", relative, path, size);
}

#endif
