/* SPDX-License-Identifier: Apache-2.0 */
/* docs/gauge.md, rules: a gauge and the rule file; then a flat strip's
 * sheets must each carry a verdict. */
#include "gauge_docs.h"

int main(void) {
    flt_calib *calib = NULL;
    flt_gauge *gauge = new_gauge(&calib);
    copy_example_rules("grade-s355.json");
    /* SNIPPET */
    push_flat_strip(gauge);
    flt_sheet *sheet = NULL;
    CHECK(flt_gauge_next_sheet(gauge, 0, &sheet));
    if (!sheet)
        return 1;
    double rules_count = 0;
    CHECK(flt_sheet_get(sheet, FLT_SHEET_RULES, &rules_count));
    flt_sheet_destroy(sheet);
    flt_gauge_destroy(gauge);
    flt_calib_destroy(calib);
    return rules_count > 0 ? 0 : 1;
}
