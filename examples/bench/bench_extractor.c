// SPDX-License-Identifier: Apache-2.0
/*
 * Extractor throughput: frames per second on one core.
 *
 * Frames: the reference sensor's full 2048 x 2048 Mono8 frame from the
 * simulator (centre buckle, default speckle and shot noise), two 128-row
 * bands (laser 1 rows 892..1019, laser 0 rows 1020..1147), 1001 fibers at
 * 2 mm. Eight frames in turn, 32 MB: every frame's bands come from main
 * memory, as a camera's frames do.
 *
 * Printed: frames/s over the whole run and in its best quarter second (a
 * shared machine's neighbours slow some slices; the best one is the
 * figure to compare builds by), with the bands' bytes read per second.
 * Goals: >= 3300 frames/s, five times the 667 frames/s of 120 m/min at
 * 3 mm spacing; next, 8000 frames/s.
 *
 * Usage: bench_extractor [seconds]   (default 3)
 */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "flatline/flatline.h"

#define CHECK(call)                                                        \
  do {                                                                     \
    flt_status st_ = (call);                                               \
    if (st_ != FLT_OK) {                                                   \
      fprintf(stderr, "%s failed: %s\n", #call, flt_last_error_message()); \
      return 1;                                                            \
    }                                                                      \
  } while (0)

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv) {
    const double seconds = argc > 1 ? atof(argv[1]) : 3.0;
    enum { W = 2048, H = 2048, FIBERS = 1001, FRAMES = 8 };
    flt_calib *calib = NULL;
    CHECK(flt_calib_create_reference(0, H, -1000, 2, FIBERS, &calib));
    flt_sim *sim = NULL;
    CHECK(flt_sim_create(calib, NULL, &sim));
    CHECK(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 12, 1800));
    uint8_t *frames = malloc((size_t)FRAMES * W * H);
    double encoder[FRAMES];
    for (int f = 0; f < FRAMES; ++f)
        CHECK(flt_sim_next_frame(sim, frames + (size_t)f * W * H, (size_t)W * H, W, &encoder[f], 0,
                                 NULL, NULL, 0));
    flt_options *o = NULL;
    CHECK(flt_options_create(&o));
    CHECK(flt_options_set(o, FLT_OPT_EXTRACT_LASER1_FIRST_ROW, 892));
    CHECK(flt_options_set(o, FLT_OPT_EXTRACT_LASER1_ROWS, 128));
    CHECK(flt_options_set(o, FLT_OPT_EXTRACT_LASER0_FIRST_ROW, 1020));
    CHECK(flt_options_set(o, FLT_OPT_EXTRACT_LASER0_ROWS, 128));
    flt_extractor *ex = NULL;
    CHECK(flt_extractor_create(calib, o, &ex));
    static double height[FIBERS], slope[FIBERS];
    static uint8_t valid[FIBERS];
    double s;
    size_t done = 0, valid_count = 0;
    double best_rate = 0;  // frames/s in the best slice
    const double start = now();
    double elapsed = 0;
    while (elapsed < seconds) {
        const double slice_start = now();
        size_t slice_frames = 0;
        while (now() - slice_start < 0.25) {
            for (int f = 0; f < FRAMES; ++f, ++slice_frames)
                CHECK(flt_extractor_process(ex, frames + (size_t)f * W * H, FLT_PIXEL_MONO8, W, H,
                                            W, encoder[f], FIBERS, &s, height, slope, valid));
        }
        const double rate = (double)slice_frames / (now() - slice_start);
        best_rate = rate > best_rate ? rate : best_rate;
        done += slice_frames;
        elapsed = now() - start;
    }
    for (int k = 0; k < FIBERS; ++k)
        valid_count += valid[k];
    const double band_bytes = 2.0 * 128 * W;  // both bands, Mono8
    printf("extractor: %zu frames of %dx%d Mono8, two 128-row bands, %d fibers: "
           "%.0f frames/s on one core (%.1f us/frame, %.2f GB/s of bands read), "
           "best quarter second %.0f frames/s (%.2f GB/s), %.1f%% fibers valid\n",
           done, W, H, FIBERS, (double)done / elapsed, 1e6 * elapsed / (double)done,
           band_bytes * (double)done / elapsed / 1e9, best_rate, band_bytes * best_rate / 1e9,
           100.0 * (double)valid_count / FIBERS);
    flt_extractor_destroy(ex);
    flt_options_destroy(o);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
    free(frames);
    return 0;
}
