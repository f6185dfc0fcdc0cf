/* SPDX-License-Identifier: Apache-2.0 */
/* docs/gauge.md, running a recording: a gauge and read_sheets. */
#include "gauge_docs.h"

static void read_sheets(flt_gauge *gauge) {
    flt_sheet *sheet = NULL;
    do {
        CHECK(flt_gauge_next_sheet(gauge, 0, &sheet));
        flt_sheet_destroy(sheet);
    } while (sheet);
}

int main(void) {
    flt_calib *calib = NULL;
    flt_gauge *gauge = new_gauge(&calib);
    /* SNIPPET */
    flt_gauge_destroy(gauge);
    flt_calib_destroy(calib);
    return 0;
}
