// SPDX-License-Identifier: Apache-2.0
/*
 * Endurance run (not a CI test): the simulated line streamed for
 * the equivalent of one hour of production at 120 m/min, 2.4 million rows
 * 3 mm apart (7.2 km of strip), through the streaming
 * reconstructor with carry-over at every sheet end, checking that
 *   - memory stays flat: the resident set (from /proc/self/statm) after the
 *     warm-up grows by less than --rss-slack-kb, and
 *   - every sheet's accuracy stays within bounds: the RMS and the largest
 *     |z - truth| over the sheet's rows and fibers, after removing each
 *     fiber's mean offset over the sheet (a fiber's absolute level under
 *     rigid heave is only known to the heave's averaged noise; flatness is
 *     about shape), below --max-rms-mm and --max-err-mm.
 *
 *   flatline_soak [--rows N] [--fibers N] [--sheet-mm L] [--frames] [--gauge]
 *                 [--report-every N] [--max-rms-mm X] [--max-err-mm X]
 *                 [--rss-slack-kb K]
 *
 * Default: 2 400 000 profile rows from flt_sim_next_rows (reference sensor,
 * reference noise: 1/16 px peak noise per laser, 0.5 mm heave), 101 fibers
 * 20 mm apart, sheets of 3 000 mm (1 000 rows). --frames renders every row
 * as a camera frame (a 2048 x 240 px window of the reference sensor) and
 * extracts it: the whole chain, about 50x slower (rendering dominates).
 * Figures of the runs: README.md here.
 * Prints progress with the RSS, every sheet's accuracy, and a summary; exit
 * status 0 only if every check held.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "flatline/flatline.h"

static long rss_kb(void) {
    FILE *f = fopen("/proc/self/statm", "r");
    long size = 0, resident = 0;
    if (!f)
        return -1;
    if (fscanf(f, "%ld %ld", &size, &resident) != 2)
        resident = -1;
    fclose(f);
    return resident < 0 ? -1 : resident * (sysconf(_SC_PAGESIZE) / 1024);
}

static double now_s(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void check(flt_status st, const char *what) {
    if (st != FLT_OK) {
        fprintf(stderr, "soak: %s: %s (%s)\n", what, flt_last_error_message(),
                flt_status_string(st));
        exit(2);
    }
}

int main(int argc, char **argv) {
    size_t total_rows = 2400000, fibers = 101, report_every = 100000;
    double sheet_mm = 3000.0, max_rms = 0.25, max_err = 1.5;
    long rss_slack_kb = 1024;
    int frames = 0, gauge = 0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : "0";
        if (!strcmp(a, "--rows"))
            total_rows = strtoull(v, NULL, 10), ++i;
        else if (!strcmp(a, "--fibers"))
            fibers = strtoull(v, NULL, 10), ++i;
        else if (!strcmp(a, "--sheet-mm"))
            sheet_mm = atof(v), ++i;
        else if (!strcmp(a, "--report-every"))
            report_every = strtoull(v, NULL, 10), ++i;
        else if (!strcmp(a, "--max-rms-mm"))
            max_rms = atof(v), ++i;
        else if (!strcmp(a, "--max-err-mm"))
            max_err = atof(v), ++i;
        else if (!strcmp(a, "--rss-slack-kb"))
            rss_slack_kb = atol(v), ++i;
        else if (!strcmp(a, "--frames"))
            frames = 1;
        else if (!strcmp(a, "--gauge"))
            gauge = 1;
        else {
            fprintf(stderr,
                    "usage: %s [--rows N] [--fibers N] [--sheet-mm L] [--frames] [--gauge] "
                    "[--report-every N] [--max-rms-mm X] [--max-err-mm X] "
                    "[--rss-slack-kb K]\n",
                    argv[0]);
            return 2;
        }
    }
    if (fibers < 2 || total_rows < 1 || !(sheet_mm > 0))
        return 2;
    const double pitch = 2000.0 / (double)(fibers - 1);
    const double frame_mm = 3.0; /* sim_frame_spacing: 120 m/min at 666.7 frames/s */
    const size_t sheet_rows = (size_t)(sheet_mm / frame_mm + 0.5);

    /* The sensor: the reference, whole (rows) or a 240-row window (frames). */
    flt_calib *calib = NULL;
    enum { ROI_FIRST = 900, ROI_ROWS = 240, WIDTH = 2048 };
    check(frames ? flt_calib_create_reference(ROI_FIRST, ROI_ROWS, -1000.0, pitch, fibers, &calib)
                 : flt_calib_create_reference(0, 2048, -1000.0, pitch, fibers, &calib),
          "calibration");
    flt_options *opt = NULL;
    check(flt_options_create(&opt), "options");
    check(flt_options_set(opt, FLT_OPT_SIM_PEAK_SIGMA, 1.0 / 16.0), "sim_peak_sigma");
    check(flt_options_set(opt, FLT_OPT_SIM_HEAVE_SIGMA, 0.5), "sim_heave_sigma");
    check(flt_options_set(opt, FLT_OPT_SIM_FRAME_SPACING, frame_mm), "sim_frame_spacing");
    flt_sim *sim = NULL;
    check(flt_sim_create(calib, opt, &sim), "simulator");
    /* A sheet with the classic defects: a centre buckle, wavy edges, a
     * quarter buckle, slowly varying along the strip. */
    check(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 4.0, 1800.0), "defect");
    check(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, 3.0, 700.0), "defect");
    check(flt_sim_add_defect(sim, FLT_SIM_QUARTER_BUCKLE, 1.5, 1100.0), "defect");
    flt_extractor *ex = NULL;
    if (frames)
        check(flt_extractor_create(calib, NULL, &ex), "extractor");
    flt_recon *rec = NULL;
    flt_gauge *g = NULL;
    if (gauge) {
        /* The gauge: its own extractors (frames) and reconstructor, two
         * workers, a cut at every sheet end, the sheets' height maps kept to
         * check them. Rendered frames may wait for it. */
        flt_options *go = NULL;
        check(flt_options_create(&go), "options");
        check(flt_options_set(go, FLT_OPT_GAUGE_WORKERS, 2), "gauge_workers");
        check(flt_options_set(go, FLT_OPT_GAUGE_OVERFLOW, 1), "gauge_overflow");
        check(flt_options_set(go, FLT_OPT_GAUGE_KEEP_MAPS, 1), "gauge_keep_maps");
        check(flt_options_set(go, FLT_OPT_GAUGE_FRAME_SPACING, 0.8 * frame_mm),
              "gauge_frame_spacing");
        check(flt_options_set(go, FLT_OPT_GAUGE_MAX_SHEET_LENGTH, sheet_mm + 1000.0),
              "gauge_max_sheet_length");
        check(flt_options_set(go, FLT_OPT_GAUGE_SHEET_SLOTS, 8), "gauge_sheet_slots");
        check(flt_gauge_create(calib, go, &g), "gauge");
        flt_options_destroy(go);
    } else {
        check(flt_recon_create_from_calib(calib, NULL, &rec), "reconstructor");
    }

    /* Everything per row is allocated here, once: the rows of the block
     * being pushed, and a ring of truth rows waiting for their output (the
     * reconstructor's latency is under 100 knots = 10 m = 3 400 rows). */
    enum { BLOCK = 64 };
    const size_t ring = 8192;
    double *s = malloc(sizeof(double) * BLOCK), *h = malloc(sizeof(double) * BLOCK * fibers);
    double *k = malloc(sizeof(double) * BLOCK * fibers);
    uint8_t *valid = malloc((size_t)BLOCK * fibers);
    double *truth_ring = malloc(sizeof(double) * ring * fibers);
    double *s_out = malloc(sizeof(double) * ring), *z_out = malloc(sizeof(double) * ring * fibers);
    uint8_t *frame = frames ? malloc((size_t)WIDTH * ROI_ROWS) : NULL;
    /* The gauge's sheets: a map of up to a sheet and a row. */
    const size_t map_rows = sheet_rows + 2;
    double *map_s = malloc(sizeof(double) * map_rows),
           *map_z = malloc(sizeof(double) * map_rows * fibers);
    memset(map_z, 0, sizeof(double) * map_rows * fibers);
    /* Per sheet and fiber: sums for the mean offset and the error. */
    double *sum_e = calloc(fibers, sizeof(double)), *sum_e2 = calloc(fibers, sizeof(double));
    double *min_e = malloc(sizeof(double) * fibers), *max_e = malloc(sizeof(double) * fibers);
    size_t *count_e = calloc(fibers, sizeof(size_t));
    for (size_t f = 0; f < fibers; ++f)
        min_e[f] = INFINITY, max_e[f] = -INFINITY;
    /* Touched now, so that the RSS measures the library, not this program. */
    memset(truth_ring, 0, sizeof(double) * ring * fibers);
    memset(z_out, 0, sizeof(double) * ring * fibers);
    memset(s_out, 0, sizeof(double) * ring);

    size_t pushed = 0, pulled = 0, sheets = 0, bad_sheets = 0, in_sheet = 0;
    double worst_rms = 0.0, worst_err = 0.0, sum_rms = 0.0;
    long rss_start = rss_kb(), rss_after_warmup = -1, rss_max = rss_start;
    /* The warm-up: 5% of the rows, at least 20 000: the reconstructor's
     * buffers (row_capacity = 8192 rows) are touched page by page as they
     * first fill. A shorter run cannot judge the memory. */
    const size_t warmup = total_rows / 20 > 20000 ? total_rows / 20 : 20000;
    const double t0 = now_s();
    printf("soak: %zu rows (%.1f km of strip, %.1f min at 120 m/min), %zu fibers, sheets of "
           "%zu rows, %s; RSS %ld kB\n",
           total_rows, total_rows * frame_mm / 1e6, total_rows * frame_mm / 2000.0 / 60.0, fibers,
           sheet_rows,
           gauge    ? (frames ? "rendered frames into a gauge" : "profile rows into a gauge")
           : frames ? "rendered frames + extractor"
                    : "profile rows",
           rss_start);

/* One sheet's accuracy, from the sums of its pulled rows. */
#define CLOSE_SHEET()                                                                           \
  do {                                                                                          \
    double se2 = 0.0, worst = 0.0;                                                              \
    size_t n = 0;                                                                               \
    for (size_t f = 0; f < fibers; ++f) {                                                       \
      if (!count_e[f])                                                                          \
        continue;                                                                               \
      const double mean = sum_e[f] / (double)count_e[f];                                        \
      se2 += sum_e2[f] - mean * sum_e[f];                                                       \
      n += count_e[f];                                                                          \
      worst = fmax(worst, fmax(max_e[f] - mean, mean - min_e[f]));                              \
      sum_e[f] = sum_e2[f] = 0.0, count_e[f] = 0;                                               \
      min_e[f] = INFINITY, max_e[f] = -INFINITY;                                                \
    }                                                                                           \
    if (n) {                                                                                    \
      const double rms = sqrt(fmax(0.0, se2) / (double)n);                                      \
      ++sheets;                                                                                 \
      sum_rms += rms;                                                                           \
      if (rms > worst_rms)                                                                      \
        worst_rms = rms;                                                                        \
      if (worst > worst_err)                                                                    \
        worst_err = worst;                                                                      \
      const int ok = rms <= max_rms && worst <= max_err;                                        \
      bad_sheets += !ok;                                                                        \
      if (!ok || sheets <= 3 || sheets % 200 == 0)                                              \
        printf("  sheet %zu: %zu samples, rms %.4f mm, max %.4f mm%s\n", sheets, n, rms, worst, \
               ok ? "" : "  OUT OF BOUNDS");                                                    \
    }                                                                                           \
  } while (0)

    while (gauge && pushed < total_rows) {
        /* One row (or frame) at a time into the gauge; the cut of the sheet
         * that begins is given ahead of the strip. */
        double *truth = truth_ring + (pushed % ring) * fibers;
        if (in_sheet == 0)
            check(flt_gauge_cut(g, sheet_mm * (double)(pushed / sheet_rows + 1)), "cut");
        if (frames) {
            double encoder;
            check(flt_sim_next_frame(sim, frame, (size_t)WIDTH * ROI_ROWS, WIDTH, &encoder, fibers,
                                     truth, NULL, 0),
                  "frame");
            check(flt_gauge_push_frame(g, frame, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, encoder),
                  "push_frame");
        } else {
            double encoder;
            check(flt_sim_next_rows(sim, 1, fibers, &encoder, s, h, k, valid, truth), "rows");
            check(flt_gauge_push_row(g, encoder, fibers, h, k, valid), "push_row");
        }
        ++pushed;
        in_sheet = in_sheet + 1 == sheet_rows ? 0 : in_sheet + 1;
        if (pushed == total_rows)
            check(flt_gauge_flush(g), "flush");
        for (;;) {
            flt_sheet *sheet = NULL;
            check(flt_gauge_next_sheet(g, 0, &sheet), "next_sheet");
            if (!sheet)
                break;
            double rows_d = 0;
            check(flt_sheet_get(sheet, FLT_SHEET_ROWS, &rows_d), "sheet rows");
            const size_t rows = (size_t)rows_d;
            if (rows > map_rows) {
                fprintf(stderr, "soak: a sheet of %zu rows, more than %zu\n", rows, map_rows);
                return 2;
            }
            check(flt_sheet_height_map(sheet, rows, fibers, map_s, map_z, NULL), "height map");
            flt_sheet_destroy(sheet);
            for (size_t r = 0; r < rows; ++r, ++pulled) {
                /* Row i of the strip lies at s = i * frame_mm. */
                const size_t i = (size_t)llround(map_s[r] / frame_mm);
                if (pushed - i > ring) {
                    fprintf(stderr, "soak: a sheet's row %zu is older than the truth ring\n", i);
                    return 2;
                }
                const double *row_truth = truth_ring + (i % ring) * fibers;
                for (size_t f = 0; f < fibers; ++f) {
                    const double e = map_z[r * fibers + f] - row_truth[f];
                    if (!isfinite(e))
                        continue;
                    sum_e[f] += e, sum_e2[f] += e * e, ++count_e[f];
                    if (e < min_e[f])
                        min_e[f] = e;
                    if (e > max_e[f])
                        max_e[f] = e;
                }
            }
            CLOSE_SHEET();
        }
        const long rss = rss_kb();
        if (rss > rss_max)
            rss_max = rss;
        if (rss_after_warmup < 0 && pushed >= warmup)
            rss_after_warmup = rss;
        if (pushed % report_every == 0 || pushed == total_rows) {
            const double t = now_s() - t0, strip_s = pushed * frame_mm / 2000.0;
            printf("  %8zu rows  %6.2f km  %5.1f min of line  RSS %ld kB  sheets %zu  worst "
                   "rms %.4f mm  %.0f rows/s (%.1fx real time)\n",
                   pushed, pushed * frame_mm / 1e6, strip_s / 60.0, rss, sheets, worst_rms,
                   pushed / t, strip_s / t);
            fflush(stdout);
        }
    }
    while (!gauge && pushed < total_rows) {
        /* Rows up to the end of the block or of the sheet. */
        size_t rows = BLOCK;
        if (rows > sheet_rows - in_sheet)
            rows = sheet_rows - in_sheet;
        if (rows > total_rows - pushed)
            rows = total_rows - pushed;
        for (size_t r = 0; r < rows; ++r) {
            double *truth = truth_ring + ((pushed + r) % ring) * fibers;
            if (frames) {
                double encoder;
                check(flt_sim_next_frame(sim, frame, (size_t)WIDTH * ROI_ROWS, WIDTH, &encoder,
                                         fibers, truth, NULL, 0),
                      "frame");
                check(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH,
                                            encoder, fibers, s + r, h + r * fibers, k + r * fibers,
                                            valid + r * fibers),
                      "extract");
            } else {
                check(flt_sim_next_rows(sim, 1, fibers, NULL, s + r, h + r * fibers, k + r * fibers,
                                        valid + r * fibers, truth),
                      "rows");
            }
        }
        check(flt_recon_push(rec, rows, fibers, s, h, k, valid), "push");
        pushed += rows;
        in_sheet += rows;
        const int sheet_end = in_sheet == sheet_rows || pushed == total_rows;
        if (sheet_end)
            check(flt_recon_end_sheet(rec), "end_sheet");
        size_t got = 0;
        check(flt_recon_pull(rec, ring, fibers, s_out, z_out, NULL, &got), "pull");
        for (size_t r = 0; r < got; ++r, ++pulled) {
            const double *truth = truth_ring + (pulled % ring) * fibers;
            for (size_t f = 0; f < fibers; ++f) {
                const double e = z_out[r * fibers + f] - truth[f];
                if (!isfinite(e))
                    continue;
                sum_e[f] += e, sum_e2[f] += e * e, ++count_e[f];
                if (e < min_e[f])
                    min_e[f] = e;
                if (e > max_e[f])
                    max_e[f] = e;
            }
        }
        if (pushed - pulled > ring) {
            fprintf(stderr, "soak: %zu rows pending, more than the truth ring\n", pushed - pulled);
            return 2;
        }
        if (sheet_end) {
            if (pulled != pushed) {
                fprintf(stderr, "soak: end_sheet left %zu rows unpulled\n", pushed - pulled);
                return 2;
            }
            CLOSE_SHEET();
            in_sheet = 0;
        }
        const long rss = rss_kb();
        if (rss > rss_max)
            rss_max = rss;
        if (rss_after_warmup < 0 && pushed >= warmup)
            rss_after_warmup = rss;
        if (pushed % report_every < rows || pushed == total_rows) {
            const double t = now_s() - t0, strip_s = pushed * frame_mm / 2000.0;
            printf("  %8zu rows  %6.2f km  %5.1f min of line  RSS %ld kB  sheets %zu  worst "
                   "rms %.4f mm  %.0f rows/s (%.1fx real time)\n",
                   pushed, pushed * frame_mm / 1e6, strip_s / 60.0, rss, sheets, worst_rms,
                   pushed / t, strip_s / t);
            fflush(stdout);
        }
    }
    const long rss_end = rss_kb();
    const int judged = rss_after_warmup >= 0 && total_rows >= 2 * warmup;
    const long growth = judged ? rss_end - rss_after_warmup : 0;
    const int memory_ok = !judged || growth < rss_slack_kb;
    const double t = now_s() - t0;
    printf("soak: %zu rows, %zu sheets in %.0f s (%.1fx real time)\n", pushed, sheets, t,
           pushed * frame_mm / 2000.0 / t);
    printf("  accuracy: mean sheet rms %.4f mm, worst sheet rms %.4f mm (bound %.3f), largest "
           "|error| %.4f mm (bound %.3f), %zu sheets out of bounds\n",
           sheets ? sum_rms / sheets : 0.0, worst_rms, max_rms, worst_err, max_err, bad_sheets);
    printf("  memory: RSS %ld kB at start, %ld kB after the warm-up (%zu rows), %ld kB at the "
           "end, peak %ld kB: growth %+ld kB after the warm-up (bound %ld) %s\n",
           rss_start, rss_after_warmup, warmup, rss_end, rss_max, growth, rss_slack_kb,
           !judged     ? "(run too short to judge: give --rows >= 40000)"
           : memory_ok ? "flat"
                       : "GROWING");
    flt_recon_destroy(rec);
    flt_gauge_destroy(g);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_options_destroy(opt);
    flt_calib_destroy(calib);
    free(s), free(h), free(k), free(valid), free(truth_ring), free(s_out), free(z_out);
    free(frame), free(sum_e), free(sum_e2), free(min_e), free(max_e), free(count_e);
    free(map_s), free(map_z);
    const int ok = memory_ok && bad_sheets == 0 && sheets > 0;
    printf("soak: %s\n", ok ? "OK" : "FAILED");
    return ok ? 0 : 1;
}
