/* SPDX-License-Identifier: Apache-2.0 */
/* docs/record.md, recording a line: a gauge and its calibration;
 * afterwards the recording opens and holds the strip's rows. */
#include "gauge_docs.h"

int main(void) {
    /* A recorder never overwrites: the file of an earlier run goes. */
    remove("line-2024-05-17.flrec");
    remove("line-2024-05-17.flrec-wal");
    remove("line-2024-05-17.flrec-shm");
    flt_calib *calib = NULL;
    flt_gauge *gauge = new_gauge(&calib);
    /* SNIPPET */
    flt_recording *recording = NULL;
    double rows = 0;
    CHECK(flt_recording_open("line-2024-05-17.flrec", &recording));
    CHECK(flt_recording_info(recording, FLT_RECORDING_ROWS, &rows));
    flt_recording_destroy(recording);
    flt_gauge_destroy(gauge);
    flt_calib_destroy(calib);
    return rows == 2000 ? 0 : 1; /* push_flat_strip's rows */
}
