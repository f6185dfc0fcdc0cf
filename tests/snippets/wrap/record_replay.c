/* SPDX-License-Identifier: Apache-2.0 */
/* docs/record.md, replaying a recording: first a recording of a flat
 * strip (gauge_docs.h); afterwards the replay gave its two sheets. */
#include "gauge_docs.h"

int main(void) {
    /* A recorder never overwrites: the file of an earlier run goes. */
    remove("line-2024-05-17.flrec");
    remove("line-2024-05-17.flrec-wal");
    remove("line-2024-05-17.flrec-shm");
    {
        flt_calib *live_calib = NULL;
        flt_gauge *live = new_gauge(&live_calib);
        flt_recorder *recorder = NULL;
        CHECK(flt_recorder_create("line-2024-05-17.flrec", live_calib, NULL, &recorder));
        CHECK(flt_gauge_attach_recorder(live, recorder));
        push_flat_strip(live);
        CHECK(flt_gauge_attach_recorder(live, NULL));
        flt_recorder_destroy(recorder);
        flt_gauge_destroy(live);
        flt_calib_destroy(live_calib);
    }
    /* SNIPPET */
    int sheets = 0;
    flt_sheet *sheet = NULL;
    do {
        CHECK(flt_gauge_next_sheet(g, 0, &sheet));
        sheets += sheet != NULL;
        flt_sheet_destroy(sheet);
    } while (sheet);
    CHECK(flt_gauge_attach_source(g, NULL));
    flt_source_destroy(src);
    flt_gauge_destroy(g);
    flt_calib_destroy(calib);
    flt_options_destroy(same);
    flt_recording_destroy(r);
    return sheets == 2 ? 0 : 1; /* cut at 3 m of 4 m, then the flush */
}
