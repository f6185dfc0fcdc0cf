// SPDX-License-Identifier: Apache-2.0
/* Links the installed libflatline_testing from plain C: a simulated camera
 * on a simulated bus, opened through libflatline, streams 10 frames. */
#include <stdio.h>

#include <flatline/flatline.h>
#include <flatline/testing.h>

static int failed(const char *what) {
    printf("testing consumer: %s: %s\n", what, flt_last_error_message());
    return 1;
}

int main(void) {
    flt_u3v_sim *bus = NULL;
    flt_usb_transport *usb = NULL;
    flt_source *src = NULL;
    if (flt_u3v_sim_create(&bus) != FLT_OK)
        return failed("bus");
    if (flt_u3v_sim_add_camera(bus, "Vendor", "Model", "SN1", 64, 32, FLT_PIXEL_MONO8, NULL) !=
            FLT_OK ||
        flt_u3v_sim_transport(bus, &usb) != FLT_OK)
        return failed("camera");
    if (flt_source_open_u3v(usb, "SN1", NULL, &src) != FLT_OK || flt_source_start(src) != FLT_OK)
        return failed("open");
    uint64_t last = 0;
    for (int i = 0; i < 10; ++i) {
        const flt_frame *f = NULL;
        if (flt_source_next(src, 100, &f) != FLT_OK ||
            flt_frame_info(f, NULL, NULL, NULL, NULL, NULL, &last, NULL, NULL) != FLT_OK)
            return failed("next");
    }
    flt_source_destroy(src);
    flt_u3v_sim_destroy(bus);
    printf("testing consumer: 10 simulated frames, last block %llu OK\n", (unsigned long long)last);
    return last == 10 ? 0 : 1;
}
