/* SPDX-License-Identifier: Apache-2.0 */
/* README.md's reconstructor: the sensor file it loads (the reference sensor,
 * 1001 fibers) and one row of a flat strip, 1 m along. */
#include <stdint.h>

int main(void) {
    flt_calib *reference = NULL;
    if (flt_calib_create_reference(0, 2048, -1000.0, 2.0, 1001, &reference) != FLT_OK ||
        flt_calib_save(reference, "sensor.json") != FLT_OK)
        return 1;
    flt_calib_destroy(reference);
    enum { FIBERS = 1001, MAX_ROWS = 16 };
    size_t fibers = FIBERS, max_rows = MAX_ROWS, rows = 0;
    double s = 1000.0;
    static double height[FIBERS], slope[FIBERS];
    static double s_out[MAX_ROWS], z_out[MAX_ROWS * FIBERS];
    static uint8_t flags_out[MAX_ROWS * FIBERS];
    /* SNIPPET */
    (void)rows;
    return 0;
}
