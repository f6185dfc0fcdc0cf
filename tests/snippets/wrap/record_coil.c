/* SPDX-License-Identifier: Apache-2.0 */
/* docs/record.md, coils and notes: a gauge; afterwards the gauge names
 * the coil it was given. */
#include <string.h>

#include "gauge_docs.h"

int main(void) {
    flt_calib *calib = NULL;
    flt_gauge *gauge = new_gauge(&calib);
    /* SNIPPET */
    push_flat_strip(gauge); /* the identity takes effect with the next row */
    const flt_coil_info *named = NULL;
    const char *id = NULL;
    flt_sheet *sheet = NULL;
    CHECK(flt_gauge_next_sheet(gauge, 0, &sheet));
    if (!sheet)
        return 1;
    CHECK(flt_sheet_coil(sheet, &named));
    CHECK(flt_coil_info_get_text(named, FLT_COIL_FIELD_ID, &id));
    if (strcmp(id, "4711") != 0)
        return 1;
    flt_sheet_destroy(sheet);
    flt_gauge_destroy(gauge);
    flt_calib_destroy(calib);
    return 0;
}
