/* SPDX-License-Identifier: Apache-2.0 */
/* docs/record.md, the archive: a gauge; afterwards the archive
 * is a file (what it holds: tests/c/test_archive.c). */
#include "gauge_docs.h"

int main(void) {
    flt_calib *calib = NULL;
    flt_gauge *gauge = new_gauge(&calib);
    /* SNIPPET */
    /* The archive's file is there (test_archive.c reads sheets back). */
    FILE *file = fopen("quality.sqlite", "rb");
    if (!file)
        return 1;
    fclose(file);
    flt_gauge_destroy(gauge);
    flt_calib_destroy(calib);
    return 0;
}
