// SPDX-License-Identifier: Apache-2.0
/*
 * Recording the README's line: what it costs in CPU and in bytes.
 *
 * The line: the reference sensor over rows 892..1147 (2048 x 256 frames,
 * two 128-row bands), 1150 fibers across 2000 mm, a frame every 1 mm
 * (2000 rows/s at 120 m/min), the strip's heave (0.5 mm) and the camera's
 * peak noise (1/16 px), a centre buckle and wavy edges: the bench renders
 * 400 frames, extracts their rows once, and replays those rows with
 * advancing encoder positions, so it measures the recorder, not the
 * renderer or the extractor.
 *
 * Two runs:
 *   1. real time: rows pushed at 2000 per second by the clock for the given
 *      seconds (flt_recorder_push_row, which quantizes and queues, then the
 *      writer thread encodes, checksums and commits every 250 ms with a
 *      sync to the disk); the process's CPU time over the run, as a share
 *      of one core (goal <= 5 %), and the rows lost (goal 0);
 *   2. throughput: the same rows as fast as they go; CPU per row.
 * Then the bytes stored per sample (one fiber of one row: both lasers'
 * heights and the fiber's state), from the writer's count and from the
 * file's size (goal <= 2).
 *
 * Usage: bench_record [seconds] [folder]   (default 20 s, the system's
 * temporary folder)
 */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "flatline/flatline.h"

#define CHECK(call)                                                        \
  do {                                                                     \
    flt_status st_ = (call);                                               \
    if (st_ != FLT_OK) {                                                   \
      fprintf(stderr, "%s failed: %s\n", #call, flt_last_error_message()); \
      exit(1);                                                             \
    }                                                                      \
  } while (0)

enum { W = 2048, H = 256, FIBERS = 1150, FRAMES = 400 };
static const double RATE = 2000.0; /* rows/s */

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double cpu_now(void) {
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double load_average(void) {
    double l = -1;
    FILE *f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fscanf(f, "%lf", &l) != 1)
            l = -1;
        fclose(f);
    }
    return l;
}

static double file_size(const char *path) {
    struct stat st;
    return stat(path, &st) == 0 ? (double)st.st_size : 0.0;
}

static double *heights, *slopes;
static uint8_t *valid;

static void run(const flt_calib *calib, const char *path, double seconds, int paced) {
    remove(path);
    flt_recorder *rec = NULL;
    CHECK(flt_recorder_create(path, calib, NULL, &rec));
    const size_t rows = (size_t)(seconds * RATE);
    const double t0 = now(), c0 = cpu_now();
    for (size_t r = 0; r < rows; ++r) {
        if (paced && r % 100 == 0) {
            /* 100 rows every 50 ms: a sleep, not a spin, between them. */
            const double due = t0 + (double)r / RATE, left = due - now();
            if (left > 0) {
                struct timespec d = {(time_t)left, (long)((left - (double)(time_t)left) * 1e9)};
                nanosleep(&d, NULL);
            }
        }
        const size_t f = r % FRAMES;
        CHECK(flt_recorder_push_row(rec, (double)r, FIBERS, heights + f * FIBERS,
                                    slopes + f * FIBERS, valid + f * FIBERS));
        if (r % 4000 == 0)
            fprintf(stderr, "\r  %s: %5.1f of %.0f s of rows", paced ? "real time " : "throughput",
                    (double)r / RATE, seconds);
    }
    CHECK(flt_recorder_sync(rec, 60000));
    const double t1 = now(), c1 = cpu_now();
    fprintf(stderr, "\r%60s\r", "");
    uint64_t lost = 0, stored = 0, bytes = 0, samples = 0, writer_ns = 0, commits = 0;
    CHECK(flt_recorder_count(rec, FLT_RECORDER_COUNT_ROWS_LOST, &lost));
    CHECK(flt_recorder_count(rec, FLT_RECORDER_COUNT_ROWS_STORED, &stored));
    CHECK(flt_recorder_count(rec, FLT_RECORDER_COUNT_BYTES, &bytes));
    CHECK(flt_recorder_count(rec, FLT_RECORDER_COUNT_SAMPLES, &samples));
    CHECK(flt_recorder_count(rec, FLT_RECORDER_COUNT_WRITER_NS, &writer_ns));
    CHECK(flt_recorder_count(rec, FLT_RECORDER_COUNT_COMMITS, &commits));
    flt_recorder_destroy(rec);
    const double cpu = c1 - c0, wall = t1 - t0;
    if (paced) {
        printf("real time, %.0f rows/s x %d fibers for %.1f s: CPU %.2f s = %.2f %% of one core "
               "(goal <= 5 %%); %llu rows stored, %llu lost; %llu commits\n",
               RATE, FIBERS, wall, cpu, 100.0 * cpu / wall, (unsigned long long)stored,
               (unsigned long long)lost, (unsigned long long)commits);
        printf("  writer thread busy %.2f s (encoding, CRC, SQLite, sync)\n", 1e-9 * writer_ns);
        printf("bytes per sample (one fiber of one row, both lasers and its state): %.3f "
               "stored in blocks, %.3f by the file's size (goal <= 2); %.2f MB per minute of "
               "line\n",
               (double)bytes / (double)samples, file_size(path) / (double)samples,
               file_size(path) / wall * 60.0 / 1e6);
    } else {
        printf("throughput: %zu rows in %.2f s = %.0f rows/s; CPU %.1f us per row (%.2f %% of "
               "one core at %.0f rows/s)\n",
               rows, wall, (double)rows / wall, 1e6 * cpu / (double)rows,
               100.0 * cpu / (double)rows * RATE, RATE);
    }
}

int main(int argc, char **argv) {
    const double seconds = argc > 1 ? atof(argv[1]) : 20.0;
    if (!(seconds >= 1 && seconds <= 3600)) {
        fprintf(stderr, "usage: bench_record [seconds] [folder]   (1..3600, default 20)\n");
        return 2;
    }
    const char *folder = argc > 2 ? argv[2] : (getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    char path[1024];
    snprintf(path, sizeof path, "%s/bench_record_%d.flrec", folder, (int)getpid());

    flt_calib *calib = NULL;
    CHECK(flt_calib_create_reference(892, H, -1000.0, 2000.0 / (FIBERS - 1), FIBERS, &calib));
    flt_options *so = NULL;
    CHECK(flt_options_create(&so));
    CHECK(flt_options_set(so, FLT_OPT_SIM_FRAME_SPACING, 1.0));
    CHECK(flt_options_set(so, FLT_OPT_SIM_HEAVE_SIGMA, 0.5));
    CHECK(flt_options_set(so, FLT_OPT_SIM_PEAK_SIGMA, 1.0 / 16));
    flt_sim *sim = NULL;
    CHECK(flt_sim_create(calib, so, &sim));
    flt_options_destroy(so);
    CHECK(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 6.0, FRAMES));
    CHECK(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, -6.0, FRAMES));
    flt_options *xo = NULL;
    CHECK(flt_options_create(&xo));
    CHECK(flt_options_set(xo, FLT_OPT_EXTRACT_LASER1_FIRST_ROW, 0));
    CHECK(flt_options_set(xo, FLT_OPT_EXTRACT_LASER1_ROWS, 128));
    CHECK(flt_options_set(xo, FLT_OPT_EXTRACT_LASER0_FIRST_ROW, 128));
    CHECK(flt_options_set(xo, FLT_OPT_EXTRACT_LASER0_ROWS, 128));
    flt_extractor *ex = NULL;
    CHECK(flt_extractor_create(calib, xo, &ex));
    flt_options_destroy(xo);
    uint8_t *pixels = malloc((size_t)W * H);
    heights = malloc(sizeof(double) * FRAMES * FIBERS);
    slopes = malloc(sizeof(double) * FRAMES * FIBERS);
    valid = malloc(FRAMES * FIBERS);
    if (!pixels || !heights || !slopes || !valid)
        return 1;
    size_t valid_count = 0;
    for (int f = 0; f < FRAMES; ++f) {
        double s = 0;
        CHECK(flt_sim_next_frame(sim, pixels, (size_t)W * H, W, NULL, 0, NULL, NULL, 0));
        CHECK(flt_extractor_process(ex, pixels, FLT_PIXEL_MONO8, W, H, W, (double)f, FIBERS, &s,
                                    heights + (size_t)f * FIBERS, slopes + (size_t)f * FIBERS,
                                    valid + (size_t)f * FIBERS));
        for (int k = 0; k < FIBERS; ++k)
            valid_count += valid[(size_t)f * FIBERS + (size_t)k] != 0;
        if (f % 20 == 0)
            fprintf(stderr, "\r  rendering and extracting frames %3d of %d", f, FRAMES);
    }
    fprintf(stderr, "\r%60s\r", "");
    printf("bench_record: %d fibers, %.0f rows/s, rows of the simulated line (heave 0.5 mm, "
           "peak noise 1/16 px; %.1f %% of samples valid), quantum 2^-8 mm, file in %s",
           FIBERS, RATE, 100.0 * (double)valid_count / (FRAMES * FIBERS), folder);
    const double load = load_average();
    if (load >= 0)
        printf(" (load average %.1f)", load);
    printf("\n");
    run(calib, path, seconds, 1);
    run(calib, path, seconds / 2, 0);
    remove(path);
    free(pixels);
    free(heights);
    free(slopes);
    free(valid);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
    return 0;
}
