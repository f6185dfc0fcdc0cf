// SPDX-License-Identifier: Apache-2.0
/* libFuzzer harness: the calibration file loader, flt_calib_load_text().
 * Any input must give FLT_OK or FLT_ERR_FORMAT (never a crash, never
 * another status); an accepted model must save and load again to the same
 * text (calib.h: save -> load -> save is byte-identical). */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "flatline/calib.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    flt_calib *c = NULL;
    flt_status st = flt_calib_load_text((const char *)data, size, &c);
    if (st != FLT_OK) {
        if (st != FLT_ERR_FORMAT || c != NULL || flt_last_error_message()[0] == 0)
            abort();
        return 0;
    }
    size_t n = 0;
    if (flt_calib_save_text(c, NULL, 0, &n) != FLT_ERR_BUFFER_FULL)
        abort();
    char *a = malloc(n + 1), *b = malloc(n + 1);
    size_t m = 0;
    if (flt_calib_save_text(c, a, n + 1, &m) != FLT_OK || m != n)
        abort();
    flt_calib *again = NULL;
    if (flt_calib_load_text(a, n, &again) != FLT_OK)
        abort();
    if (flt_calib_save_text(again, b, n + 1, &m) != FLT_OK || m != n || memcmp(a, b, n) != 0)
        abort();
    flt_calib_destroy(again);
    flt_calib_destroy(c);
    free(a);
    free(b);
    return 0;
}
