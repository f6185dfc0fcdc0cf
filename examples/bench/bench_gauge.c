// SPDX-License-Identifier: Apache-2.0
/*
 * The gauge at line speed: frames/s, real-time factor, and the latency from
 * a cut to its sheet's result.
 *
 * The line: the reference sensor read out over rows 892..1147 (2048 x 256
 * Mono8 frames, two 128-row bands), 1150 fibers across 2000 mm, a frame
 * every 1 mm of strip (2000 frames/s at 120 m/min), a shear cut every
 * 3000 mm; the reconstructor with rigid_motion and robust (Huber) on; the
 * gauge with 2 workers. Goal: the gauge sustains >= 2000 frames/s on this
 * project's 2-core machine.
 *
 * The frames are rendered once by the simulator (400 frames, a centre
 * buckle and wavy edges repeating every 400 mm, heave and peak noise) and
 * replayed with advancing encoder positions, so the figures measure the
 * gauge, not the renderer.
 *
 * First the extractor alone, on one thread, over the same frames: the
 * yardstick the gauge's threads must beat (goal: the gauge with 2 workers
 * >= 1.8x the extractor alone). Then three runs of the gauge:
 *   1. throughput: frames pushed as fast as the gauge takes them
 *      (gauge_overflow = 1: the pushing thread waits for room), over the
 *      whole strip; frames/s from the first push to the last sheet, the
 *      real-time factor at 2000 frames/s, and the process CPU time per frame;
 *   2. real time: frames pushed at 2000 per second by the clock, as a
 *      camera delivers them (gauge_overflow = 0: a full queue drops and
 *      counts); the frames dropped, and per cut the time from pushing the
 *      frame whose row reaches the cut to the callback with the sheet that
 *      ends there, and how much strip the reconstructor had taken beyond
 *      the cut (its look-ahead: the latency is that strip at line speed).
 * Each run also prints where the time went (the gauge's stage counters:
 * extraction, sequencing, evaluation per frame), how busy the workers were
 * and the frame queue's high-water mark;
 *   3. throughput with verdicts: run 1 with a rule set judging every sheet
 *      (default: the coil report's example, seven rules with both 1 m
 *      straightedges; 3 mm sheets, the strip's measured width).
 * Both figures depend on the machine being otherwise idle: the bench prints
 * the load average so a reader can tell.
 *
 * Usage: bench_gauge [metres [rules.json]]   (strip per run, default 40)
 */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "flatline/flatline.h"

#define CHECK(call)                                                        \
  do {                                                                     \
    flt_status st_ = (call);                                               \
    if (st_ != FLT_OK) {                                                   \
      fprintf(stderr, "%s failed: %s\n", #call, flt_last_error_message()); \
      exit(1);                                                             \
    }                                                                      \
  } while (0)

enum { W = 2048, H = 256, FIBERS = 1150, FRAMES = 400, MAX_CUTS = 1024 };
static const double STEP = 1.0, SHEET = 3000.0, RATE = 2000.0; /* mm, mm, frames/s */

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

static void sleep_until(double t) {
    for (;;) {
        const double left = t - now();
        if (left <= 0)
            return;
        if (left > 2e-4) {
            struct timespec d = {0, (long)((left - 1e-4) * 1e9)};
            nanosleep(&d, NULL);
        }
    }
}

/* The 1-minute load average where the system tells it (Linux), else -1. */
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

/* Per cut: when the strip reached it and when its sheet came. */
typedef struct timing {
    double reached[MAX_CUTS], arrived[MAX_CUTS], lookahead[MAX_CUTS];
    /* The sheet's own account: its latency in seconds (the look-ahead at
     * the frames' pace) and from the cut's time to its evaluation. */
    double latency[MAX_CUTS], waited[MAX_CUTS];
    int sheets;
    int verdicts[FLT_VERDICT_NOT_JUDGED + 1]; /* sheets by their verdict */
} timing;

static void on_sheet(const flt_sheet *sheet, void *user) {
    timing *t = user;
    double end = 0, flags = 0, lookahead = 0, latency = 0, cut_time = 0, finished = 0;
    CHECK(flt_sheet_get(sheet, FLT_SHEET_S_END, &end));
    CHECK(flt_sheet_get(sheet, FLT_SHEET_FLAGS, &flags));
    CHECK(flt_sheet_get(sheet, FLT_SHEET_LOOKAHEAD, &lookahead));
    CHECK(flt_sheet_get(sheet, FLT_SHEET_LATENCY, &latency));
    CHECK(flt_sheet_get(sheet, FLT_SHEET_CUT_TIME, &cut_time));
    CHECK(flt_sheet_get(sheet, FLT_SHEET_FINISHED_TIME, &finished));
    ++t->sheets;
    double verdict = FLT_VERDICT_NOT_JUDGED;
    CHECK(flt_sheet_get(sheet, FLT_SHEET_VERDICT, &verdict));
    if (verdict >= 0 && verdict <= FLT_VERDICT_NOT_JUDGED)
        ++t->verdicts[(int)verdict];
    const int cut = (int)(end / SHEET + 0.5) - 1;
    if (((int)flags & FLT_SHEET_FLAG_FLUSHED) || cut < 0 || cut >= MAX_CUTS)
        return;
    t->arrived[cut] = now();
    t->lookahead[cut] = lookahead;
    t->latency[cut] = latency;
    t->waited[cut] = finished - cut_time;
}

/* The gauge's extraction options: two 128-row bands, the upper one laser 1. */
static void set_bands(flt_options *o) {
    CHECK(flt_options_set(o, FLT_OPT_EXTRACT_LASER1_FIRST_ROW, 0));
    CHECK(flt_options_set(o, FLT_OPT_EXTRACT_LASER1_ROWS, 128));
    CHECK(flt_options_set(o, FLT_OPT_EXTRACT_LASER0_FIRST_ROW, 128));
    CHECK(flt_options_set(o, FLT_OPT_EXTRACT_LASER0_ROWS, 128));
}

/* The extractor alone on one thread over `frames` of the rendered frames:
 * frames/s (wall time; the pushing thread of the gauge runs the same). */
static double extractor_alone(const flt_calib *calib, const uint8_t *pixels, size_t frames) {
    flt_options *o = NULL;
    CHECK(flt_options_create(&o));
    set_bands(o);
    flt_extractor *x = NULL;
    CHECK(flt_extractor_create(calib, o, &x));
    flt_options_destroy(o);
    size_t fibers = 0;
    CHECK(flt_extractor_fibers(x, &fibers));
    double *h = malloc(fibers * sizeof(double)), *sl = malloc(fibers * sizeof(double));
    uint8_t *valid = malloc(fibers);
    if (!h || !sl || !valid)
        exit(1);
    double s = 0;
    const double t0 = now(), c0 = cpu_now();
    for (size_t f = 0; f < frames; ++f)
        CHECK(flt_extractor_process(x, pixels + (f % FRAMES) * (size_t)W * H, FLT_PIXEL_MONO8, W, H,
                                    W, STEP * (double)f, fibers, &s, h, sl, valid));
    const double t1 = now(), c1 = cpu_now();
    const double fps = (double)frames / (t1 - t0);
    printf("extractor alone, one thread: %zu frames in %.2f s = %.0f frames/s, CPU %.0f us per "
           "frame\n",
           frames, t1 - t0, fps, 1e6 * (c1 - c0) / (double)frames);
    free(h), free(sl), free(valid);
    flt_extractor_destroy(x);
    return fps;
}

/* One run over `frames` frames; paced at RATE frames/s when `paced`; the
 * sheets judged by `rules` (3 mm, the measured width) unless NULL.
 * Returns frames/s from the first push to the last sheet. */
static double run(const flt_calib *calib, const uint8_t *pixels, size_t frames, int paced,
                  const flt_rules *rules) {
    flt_options *o = NULL;
    CHECK(flt_options_create(&o));
    CHECK(flt_options_set(o, FLT_OPT_RIGID_MOTION, 1));
    CHECK(flt_options_set(o, FLT_OPT_ROBUST, 1));
    set_bands(o);
    CHECK(flt_options_set(o, FLT_OPT_GAUGE_WORKERS, 2));
    CHECK(flt_options_set(o, FLT_OPT_GAUGE_FRAME_SPACING, STEP));
    CHECK(flt_options_set(o, FLT_OPT_GAUGE_OVERFLOW, paced ? 0 : 1));
    flt_gauge *g = NULL;
    CHECK(flt_gauge_create(calib, o, &g));
    flt_options_destroy(o);
    static timing t;
    memset(&t, 0, sizeof t);
    CHECK(flt_gauge_set_callback(g, on_sheet, &t));
    if (rules)
        CHECK(flt_gauge_set_rules(g, rules, 3.0, FLT_GAUGE_WIDTH_MEASURED));
    const size_t cuts = (size_t)((double)frames * STEP / SHEET);
    for (size_t c = 1; c <= cuts && c <= MAX_CUTS; ++c)
        CHECK(flt_gauge_cut(g, SHEET * (double)c));

    const double t0 = now(), c0 = cpu_now();
    size_t next_cut = 0;
    for (size_t f = 0; f < frames; ++f) {
        const double e = STEP * (double)f;
        if (paced)
            sleep_until(t0 + (double)f / RATE);
        CHECK(flt_gauge_push_frame(g, pixels + (f % FRAMES) * (size_t)W * H, FLT_PIXEL_MONO8, W, H,
                                   W, e));
        if (next_cut < MAX_CUTS && e >= SHEET * (double)(next_cut + 1))
            t.reached[next_cut++] = now();
        if (f % 2000 == 0)
            fprintf(stderr, "\r  %s: %5.1f of %.0f m", paced ? "real time " : "throughput",
                    e / 1000, (double)frames * STEP / 1000);
    }
    const double pushed = now();
    CHECK(flt_gauge_flush(g));
    const double t1 = now(), c1 = cpu_now();
    fprintf(stderr, "\r%60s\r", "");
    uint64_t dropped = 0, skipped = 0, sheets = 0;
    CHECK(flt_gauge_count(g, FLT_GAUGE_COUNT_DROPPED, &dropped));
    CHECK(flt_gauge_count(g, FLT_GAUGE_COUNT_SKIPPED_STOP, &skipped));
    CHECK(flt_gauge_count(g, FLT_GAUGE_COUNT_SHEETS, &sheets));
    double row_capacity = 0, queue_frames = 0;
    CHECK(flt_gauge_get_option(g, FLT_OPT_ROW_CAPACITY, &row_capacity));
    CHECK(flt_gauge_get_option(g, FLT_OPT_GAUGE_QUEUE_FRAMES, &queue_frames));
    /* Where the time went, on every thread together. */
    uint64_t ns[3] = {0, 0, 0}, high = 0;
    CHECK(flt_gauge_count(g, FLT_GAUGE_COUNT_EXTRACT_NS, &ns[0]));
    CHECK(flt_gauge_count(g, FLT_GAUGE_COUNT_SEQUENCE_NS, &ns[1]));
    CHECK(flt_gauge_count(g, FLT_GAUGE_COUNT_EVALUATE_NS, &ns[2]));
    CHECK(flt_gauge_count(g, FLT_GAUGE_COUNT_QUEUE_HIGH_WATER, &high));
    const double busy = 1e-9 * (double)(ns[0] + ns[1] + ns[2]);
    const double fps = (double)frames / (t1 - t0);
    if (!paced) {
        printf("throughput%s: %zu frames (%.0f m) in %.2f s = %.0f frames/s, real-time factor "
               "%.2f at 120 m/min\n  (pushing took %.2f s, %.0f frames/s; the rest is the "
               "reconstructor's last %.0f m and the last sheet)\n"
               "  CPU %.0f us per frame on all threads: two idle cores sustain %.0f frames/s\n",
               rules ? " with verdicts" : "", frames, (double)frames * STEP / 1000, t1 - t0, fps,
               fps / RATE, pushed - t0, (double)frames / (pushed - t0),
               row_capacity * STEP / 1000 / 1.25, 1e6 * (c1 - c0) / (double)frames,
               2.0 * (double)frames / (c1 - c0));
        printf("  per frame by stage (wall time on the threads that ran it; a loaded machine "
               "adds waits for a core): extraction %.0f us, sequencing (reconstruction, sheets) "
               "%.0f us, evaluation (flatness, verdicts) %.0f us; the 2 workers busy %.0f %% of "
               "the run; queue high-water %llu of %.0f frames\n",
               1e-3 * (double)ns[0] / (double)frames, 1e-3 * (double)ns[1] / (double)frames,
               1e-3 * (double)ns[2] / (double)frames, 100.0 * busy / (2.0 * (t1 - t0)),
               (unsigned long long)high, queue_frames);
    } else {
        double sum = 0, max = 0, ahead = 0, latency = 0, latency_max = 0, waited = 0;
        int n = 0;
        for (int c = 0; c < MAX_CUTS; ++c)
            if (t.reached[c] > 0 && t.arrived[c] > 0) {
                const double d = t.arrived[c] - t.reached[c];
                sum += d;
                max = d > max ? d : max;
                ahead += t.lookahead[c];
                latency += t.latency[c];
                latency_max = t.latency[c] > latency_max ? t.latency[c] : latency_max;
                waited += t.waited[c];
                ++n;
            }
        printf("real time at %.0f frames/s (120 m/min): %zu frames, %llu dropped at the full "
               "queue (%.3f%%), %llu skipped\n",
               RATE, frames, (unsigned long long)dropped, 100.0 * (double)dropped / (double)frames,
               (unsigned long long)skipped);
        printf("  the 2 workers busy %.0f %% of the run; queue high-water %llu of %.0f frames\n",
               100.0 * busy / (2.0 * (t1 - t0)), (unsigned long long)high, queue_frames);
        if (n > 0)
            printf("  latency from a cut to its sheet's result: mean %.2f s, max %.2f s over %d "
                   "cuts\n  (the reconstructor had taken %.1f m of strip beyond the cut: "
                   "%.2f s at 2 m/s; the rest is the queue and the sheet's evaluation)\n",
                   sum / n, max, n, ahead / n / 1000, ahead / n / 1000 / 2.0);
        if (n > 0)
            printf("  the sheets' own account: FLT_SHEET_LATENCY mean %.2f s, max %.2f s; "
                   "FLT_SHEET_FINISHED_TIME - FLT_SHEET_CUT_TIME mean %.2f s\n",
                   latency / n, latency_max, waited / n);
        else
            printf("  no sheet finished before the end of the strip: run a longer strip\n");
    }
    if (rules) /* the verdicts were given, not skipped */
        printf("  verdicts of the %d sheets: %d PASS, %d FAIL, %d NO_BAND, %d NOT_MEASURED, %d "
               "NOT_JUDGED\n",
               t.sheets, t.verdicts[FLT_VERDICT_PASS], t.verdicts[FLT_VERDICT_FAIL],
               t.verdicts[FLT_VERDICT_NO_BAND], t.verdicts[FLT_VERDICT_NOT_MEASURED],
               t.verdicts[FLT_VERDICT_NOT_JUDGED]);
    flt_gauge_destroy(g);
    return fps;
}

int main(int argc, char **argv) {
    const double metres = argc > 1 ? atof(argv[1]) : 40.0;
    if (!(metres >= 4 && metres <= 1000) || argc > 3) {
        fprintf(stderr, "usage: bench_gauge [metres [rules.json]]   (4..1000 m, default 40; "
                        "rules: default the coil report's example)\n");
        return 2;
    }
    const char *rules_path = argc > 2 ? argv[2] : FLT_EXAMPLE_RULES;
    flt_rules *rules = NULL;
    CHECK(flt_rules_load(rules_path, &rules));
    const size_t frames = (size_t)(metres * 1000.0 / STEP);
    flt_calib *calib = NULL;
    CHECK(flt_calib_create_reference(892, H, -1000.0, 2000.0 / (FIBERS - 1), FIBERS, &calib));
    flt_options *so = NULL;
    CHECK(flt_options_create(&so));
    CHECK(flt_options_set(so, FLT_OPT_SIM_FRAME_SPACING, STEP));
    CHECK(flt_options_set(so, FLT_OPT_SIM_HEAVE_SIGMA, 0.5));
    CHECK(flt_options_set(so, FLT_OPT_SIM_PEAK_SIGMA, 1.0 / 16));
    flt_sim *sim = NULL;
    CHECK(flt_sim_create(calib, so, &sim));
    flt_options_destroy(so);
    CHECK(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 6.0, FRAMES * STEP));
    CHECK(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, -6.0, FRAMES * STEP));
    uint8_t *pixels = malloc((size_t)FRAMES * W * H);
    if (!pixels)
        return 1;
    for (int f = 0; f < FRAMES; ++f) {
        CHECK(flt_sim_next_frame(sim, pixels + (size_t)f * W * H, (size_t)W * H, W, NULL, 0, NULL,
                                 NULL, 0));
        if (f % 20 == 0)
            fprintf(stderr, "\r  rendering frames %3d of %d", f, FRAMES);
    }
    fprintf(stderr, "\r%60s\r", "");
    printf("bench_gauge: %dx%d Mono8 frames, two 128-row bands, %d fibers, a frame every "
           "%.0f mm, rigid_motion + robust, cuts every %.0f m, 2 workers",
           W, H, FIBERS, STEP, SHEET / 1000);
    const double load = load_average();
    if (load >= 0)
        printf(" (load average %.1f)", load);
    printf("\n");
    const double alone = extractor_alone(calib, pixels, frames < 8000 ? frames : 8000);
    const double plain = run(calib, pixels, frames, 0, NULL);
    printf("  the gauge with 2 workers: %.2fx the extractor alone (goal >= 1.8x)\n", plain / alone);
    run(calib, pixels, frames, 1, NULL);
    const double judged = run(calib, pixels, frames, 0, rules);
    printf("  with verdicts: %.0f frames/s, %.2fx the extractor alone (goal >= 5000 frames/s, "
           "300 m/min at 1 mm)\n  rules: %s\n",
           judged, judged / alone, rules_path);
    flt_rules_destroy(rules);
    free(pixels);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
    return 0;
}
