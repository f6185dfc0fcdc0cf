/* SPDX-License-Identifier: Apache-2.0 */
/* docs/gauge.md, a sheet's verdict: the first sheet of a flat strip judged
 * by the example rules (4 mm thick, the measured width). */
#include "gauge_docs.h"

int main(void) {
    flt_calib *calib = NULL;
    flt_gauge *gauge = new_gauge(&calib);
    copy_example_rules("rules.json");
    flt_rules *rules = NULL;
    CHECK(flt_rules_load("rules.json", &rules));
    CHECK(flt_gauge_set_rules(gauge, rules, 4.0, FLT_GAUGE_WIDTH_MEASURED));
    flt_rules_destroy(rules);
    push_flat_strip(gauge);
    flt_sheet *sheet = NULL;
    CHECK(flt_gauge_next_sheet(gauge, 0, &sheet));
    if (!sheet)
        return 1;
    /* SNIPPET */
    const flt_rules *judged = NULL;
    const flt_verdict *v = NULL;
    if (flt_sheet_verdict(sheet, &judged, &v) != FLT_OK) { /* else the block did nothing */
        fprintf(stderr, "the sheet has no verdict: %s\n", flt_last_error_message());
        return 1;
    }
    flt_sheet_destroy(sheet);
    flt_gauge_destroy(gauge);
    flt_calib_destroy(calib);
    return 0;
}
