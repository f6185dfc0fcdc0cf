// SPDX-License-Identifier: Apache-2.0
/*
 * Threads: N threads, each with its own simulator, extractor and
 * reconstructor, all made from ONE finished calibration that they share
 * (calib.h: a finished flt_calib is immutable and may be used from any
 * number of threads at once). Each thread renders the simulated frames,
 * extracts profile rows, maps peaks through the shared calibration,
 * reconstructs the sheet with carry-over and pulls every row. The results
 * must equal the single-threaded run bit for bit: separate handles are
 * independent (common.h, "Threads"), and the library is deterministic.
 *
 * Run under ThreadSanitizer by the `tsan` preset (CMakePresets.json), where
 * any data race inside the library fails the test; in the other presets it
 * checks the bitwise agreement only. The tsan preset builds with clang: with
 * GCC, the extractor's target_clones kernels (lib/extraction/peak_kernels.hpp)
 * get IFUNC resolvers that the dynamic loader runs before the TSan runtime
 * is initialised, and the instrumented resolver crashes at load time.
 */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flatline/flatline.h"

enum {
    THREADS = 4,
    /* The reference sensor's 240-row ROI around both lines, 101 fibers 20 mm
     * apart: real geometry, small frames (TSan makes the library ~10x
     * slower). */
    ROI_FIRST = 900,
    ROI_ROWS = 240,
    WIDTH = 2048,
    FIBERS = 101,
    /* 2 sheets of 60 frames at 3 mm: 360 mm of strip, with an end_sheet
     * (carry-over) between them. */
    SHEETS = 2,
    FRAMES_PER_SHEET = 60,
    FRAMES = SHEETS * FRAMES_PER_SHEET
};

/* What one run produces: every pulled row's s and z, every extracted
 * height, and the peaks mapped through the shared calibration. */
typedef struct result {
    size_t rows;
    double s[FRAMES];
    double z[FRAMES * FIBERS];
    double height[FRAMES * FIBERS];
    double plane[FRAMES * 2 * 16]; /* 8 peaks (x, z) per frame and laser */
    flt_status status;
    char message[256];
} result;

static flt_calib *g_calib; /* shared, finished, read by every thread */

#define TRY(call)                                                                             \
  do {                                                                                        \
    flt_status st_ = (call);                                                                  \
    if (st_ != FLT_OK) {                                                                      \
      out->status = st_;                                                                      \
      snprintf(out->message, sizeof out->message, "%s: %s", #call, flt_last_error_message()); \
      goto done;                                                                              \
    }                                                                                         \
  } while (0)

static void run_line(result *out) {
    flt_sim *sim = NULL;
    flt_extractor *ex = NULL;
    flt_recon *rec = NULL;
    flt_options *opt = NULL, *recon_opt = NULL;
    uint8_t *frame = malloc((size_t)WIDTH * ROI_ROWS);
    double *peaks = malloc(sizeof(double) * 2 * WIDTH);
    double s, h[FIBERS], k[FIBERS];
    uint8_t v[FIBERS];
    memset(out, 0, sizeof *out);

    /* Every handle is made from the shared calibration, concurrently. */
    TRY(flt_options_create(&opt));
    TRY(flt_options_set(opt, FLT_OPT_SIM_PEAK_SIGMA, 1.0 / 16.0));
    TRY(flt_options_set(opt, FLT_OPT_SIM_HEAVE_SIGMA, 0.5));
    TRY(flt_options_create(&recon_opt));
    TRY(flt_options_set(recon_opt, FLT_OPT_LAG_KNOTS, 8));
    TRY(flt_sim_create(g_calib, opt, &sim));
    TRY(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 3.0, 400.0));
    TRY(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, 2.0, 250.0));
    TRY(flt_extractor_create(g_calib, NULL, &ex));
    TRY(flt_recon_create_from_calib(g_calib, recon_opt, &rec));

    for (int f = 0; f < FRAMES; ++f) {
        double encoder;
        TRY(flt_sim_next_frame(sim, frame, (size_t)WIDTH * ROI_ROWS, WIDTH, &encoder, 0, NULL, NULL,
                               0));
        TRY(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, encoder,
                                  FIBERS, &s, h, k, v));
        memcpy(out->height + (size_t)f * FIBERS, h, sizeof h);
        /* Map 8 of the frame's peaks of each laser through the shared
         * calibration directly (the mapping functions on a finished model
         * are thread-safe and allocate nothing). */
        TRY(flt_extractor_peaks(ex, WIDTH, peaks));
        for (unsigned laser = 0; laser < 2; ++laser) {
            double pts[16];
            for (int i = 0; i < 8; ++i) {
                pts[2 * i] = 100.0 + 230.0 * i;
                pts[2 * i + 1] = peaks[laser * WIDTH + 100 + 230 * i];
            }
            TRY(flt_calib_image_to_plane(g_calib, laser, 8, pts,
                                         out->plane + ((size_t)f * 2 + laser) * 16));
        }
        TRY(flt_recon_push(rec, 1, FIBERS, &s, h, k, v));
        if ((f + 1) % FRAMES_PER_SHEET == 0)
            TRY(flt_recon_end_sheet(rec));
        size_t got = 0;
        TRY(flt_recon_pull(rec, FRAMES - out->rows, FIBERS, out->s + out->rows,
                           out->z + out->rows * FIBERS, NULL, &got));
        out->rows += got;
    }
done:
    flt_recon_destroy(rec);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_options_destroy(opt);
    flt_options_destroy(recon_opt);
    free(peaks);
    free(frame);
}

static void *thread_main(void *arg) {
    run_line((result *)arg);
    return NULL;
}

/* Bitwise comparison that treats two NaNs as equal only if their bits are
 * (memcmp does exactly that). */
static int same_bits(const void *a, const void *b, size_t bytes) {
    return memcmp(a, b, bytes) == 0;
}

int main(void) {
    int failures = 0;
    if (flt_calib_create_reference(ROI_FIRST, ROI_ROWS, -1000.0, 20.0, FIBERS, &g_calib)) {
        fprintf(stderr, "reference calibration: %s\n", flt_last_error_message());
        return 1;
    }
    result *reference = malloc(sizeof *reference);
    result *results = malloc(sizeof *results * THREADS);
    run_line(reference);
    if (reference->status != FLT_OK) {
        fprintf(stderr, "single-threaded run failed: %s\n", reference->message);
        return 1;
    }
    /* The reference itself must be a real reconstruction: every row out,
     * finite heights where the extractor saw both lines. */
    size_t valid = 0;
    for (size_t i = 0; i < (size_t)FRAMES * FIBERS; ++i)
        valid += isfinite(reference->height[i]);
    printf("reference: %zu rows pulled of %d, %zu of %d extracted samples valid\n", reference->rows,
           FRAMES, valid, FRAMES * FIBERS);
    if (reference->rows != FRAMES || valid < (size_t)FRAMES * FIBERS * 9 / 10) {
        fprintf(stderr, "reference run is not a usable reconstruction\n");
        return 1;
    }

    pthread_t threads[THREADS];
    for (int t = 0; t < THREADS; ++t)
        if (pthread_create(&threads[t], NULL, thread_main, &results[t]) != 0) {
            fprintf(stderr, "pthread_create failed\n");
            return 1;
        }
    for (int t = 0; t < THREADS; ++t)
        pthread_join(threads[t], NULL);

    for (int t = 0; t < THREADS; ++t) {
        const result *r = &results[t];
        if (r->status != FLT_OK) {
            fprintf(stderr, "thread %d failed: %s\n", t, r->message);
            ++failures;
            continue;
        }
        int ok_rows = r->rows == reference->rows;
        int ok_s = ok_rows && same_bits(r->s, reference->s, sizeof(double) * r->rows);
        int ok_z = ok_rows && same_bits(r->z, reference->z, sizeof(double) * r->rows * FIBERS);
        int ok_h = same_bits(r->height, reference->height, sizeof r->height);
        int ok_p = same_bits(r->plane, reference->plane, sizeof r->plane);
        printf("thread %d: %zu rows; s %s, z %s, extracted heights %s, mapped peaks %s\n", t,
               r->rows, ok_s ? "identical" : "DIFFER", ok_z ? "identical" : "DIFFER",
               ok_h ? "identical" : "DIFFER", ok_p ? "identical" : "DIFFER");
        failures += !(ok_s && ok_z && ok_h && ok_p);
    }
    printf("%d threads sharing one calibration: %s\n", THREADS,
           failures ? "FAILED" : "bit-for-bit equal to the single-threaded run");
    free(results);
    free(reference);
    flt_calib_destroy(g_calib);
    return failures ? 1 : 0;
}
