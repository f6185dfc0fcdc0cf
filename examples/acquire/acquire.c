// SPDX-License-Identifier: Apache-2.0
/*
 * Acquisition loop: a real USB3 Vision camera when one is connected,
 * otherwise a simulated U3V camera rendering the simulated sensor, both
 * through the same flt_source calls. The simulated camera comes from the
 * testing library (flatline/testing.h, libflatline_testing): a production
 * program links libflatline only and passes NULL as the transport. Prints throughput and the frame
 * accounting (dropped, lost, timeouts) once a second and at the end.
 *
 *     flatline_acquire [frames] [serial]      (default 300 frames, first camera)
 */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "flatline/flatline.h"
#include "flatline/source.h"
#include "flatline/testing.h"

static double now_s(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Reporting calls that cannot fail on a live handle; say so if one does. */
static void report_error(void) {
    fprintf(stderr, "%s\n", flt_last_error_message());
}

static int check(flt_status st, const char *what) {
    if (st == FLT_OK)
        return 0;
    fprintf(stderr, "%s: %s (%s)\n", what, flt_status_string(st), flt_last_error_message());
    return 1;
}

static void report(const flt_source *src, double seconds, double megabytes) {
    uint64_t frames = 0, dropped = 0, lost = 0, timeouts = 0;
    if (flt_source_count(src, FLT_COUNT_FRAMES, &frames) != FLT_OK)
        report_error();
    if (flt_source_count(src, FLT_COUNT_DROPPED, &dropped) != FLT_OK)
        report_error();
    if (flt_source_count(src, FLT_COUNT_LOST, &lost) != FLT_OK)
        report_error();
    if (flt_source_count(src, FLT_COUNT_TIMEOUTS, &timeouts) != FLT_OK)
        report_error();
    printf("%8.2f s  %6llu frames  %7.1f frames/s  %7.1f MB/s  dropped %llu  lost %llu  "
           "timeouts %llu\n",
           seconds, (unsigned long long)frames, (double)frames / seconds, megabytes / seconds,
           (unsigned long long)dropped, (unsigned long long)lost, (unsigned long long)timeouts);
    const char *why = flt_source_stream_error(src);
    if (why[0])
        printf("          last stream error: %s\n", why);
}

int main(int argc, char **argv) {
    const long wanted = argc > 1 ? atol(argv[1]) : 300;
    const char *serial = argc > 2 ? argv[2] : NULL;
    flt_source *src = NULL;
    flt_u3v_sim *bus = NULL;
    flt_usb_transport *usb = NULL;
    flt_sim *sim = NULL;
    flt_calib *calib = NULL;

    /* A real camera first. */
    flt_camera_list *list = NULL;
    size_t cameras = 0;
    if (flt_camera_list_create(NULL, &list) == FLT_OK) {
        if (flt_camera_list_count(list, &cameras) != FLT_OK)
            report_error();
        for (size_t i = 0; i < cameras; ++i) {
            const char *vendor, *model, *sn;
            uint32_t speed;
            if (flt_camera_list_get(list, i, &vendor, &model, &sn, &speed) == FLT_OK)
                printf("camera %zu: %s %s, serial '%s', %u Mbit/s\n", i, vendor, model, sn, speed);
        }
        flt_camera_list_destroy(list);
    }
    if (cameras > 0 && flt_source_open_u3v(NULL, serial, NULL, &src) != FLT_OK) {
        fprintf(stderr, "cannot open the camera: %s\n", flt_last_error_message());
        src = NULL;
    }
    if (!src) {
        /* The simulator behind a simulated USB3 Vision camera: the same
         * client code path as a real camera, down to the USB transfers. */
        printf("no camera: using a simulated USB3 Vision camera rendering the simulator\n");
        if (check(flt_calib_create_reference(892, 256, -1000.0, 2.0, 1001, &calib), "calib") ||
            check(flt_sim_create(calib, NULL, &sim), "sim") ||
            check(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 5.0, 1800.0), "defect") ||
            check(flt_u3v_sim_create(&bus), "bus") ||
            check(flt_u3v_sim_add_camera(bus, "Flatline", "Simulated sensor", "SIM-1", 2048, 256,
                                         FLT_PIXEL_MONO8, NULL),
                  "camera") ||
            check(flt_u3v_sim_set_frames(bus, 0, sim), "frames") ||
            check(flt_u3v_sim_transport(bus, &usb), "transport") ||
            check(flt_source_open_u3v(usb, NULL, NULL, &src), "open"))
            return 1;
    }
    const char *vendor = "", *model = "";
    if (flt_source_camera_string(src, FLT_CAMERA_VENDOR, &vendor) != FLT_OK)
        report_error();
    if (flt_source_camera_string(src, FLT_CAMERA_MODEL, &model) != FLT_OK)
        report_error();
    printf("streaming from %s %s\n", vendor, model);
    if (check(flt_source_start(src), "start"))
        return 1;

    const double t0 = now_s();
    double last_print = t0, megabytes = 0.0;
    for (long n = 0; n < wanted;) {
        const flt_frame *frame = NULL;
        flt_status st = flt_source_next(src, 1000, &frame);
        if (st == FLT_ERR_TIMEOUT) {
            fprintf(stderr, "timeout: %s\n", flt_last_error_message());
            continue;
        }
        if (check(st, "next"))
            break;
        uint32_t h = 0;
        size_t stride = 0;
        if (flt_frame_info(frame, NULL, NULL, &h, &stride, NULL, NULL, NULL, NULL) != FLT_OK)
            report_error();
        megabytes += (double)stride * h / 1e6;
        ++n;
        const double t = now_s();
        if (t - last_print >= 1.0) {
            report(src, t - t0, megabytes);
            last_print = t;
        }
    }
    report(src, now_s() - t0, megabytes);
    flt_source_destroy(src); /* stops the camera: AcquisitionStop, SI control 0 */
    flt_u3v_sim_destroy(bus);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
    return 0;
}
