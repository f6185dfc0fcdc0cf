// SPDX-License-Identifier: Apache-2.0
/*
 * What each component's create call allocates, against the formula its
 * header documents under "Memory". An integrator sizes the machine from
 * those formulas, and the limits (FLT_FLATNESS_MAX_BYTES,
 * FLT_RECON_MAX_BYTES) refuse on them before allocating: a formula that
 * undercounts lets a configuration through that takes the machine page by
 * page. Each case creates one handle and compares the peak of the heap
 * bytes held during the call (tests/c/alloc_count.h) with the documented
 * value: within 20 %, the promise the headers make. The two largest cases
 * also compare the process's resident set after the call (everything is
 * written at create), so the count cannot miss memory the allocator's
 * hooks do not see.
 *
 * Linux only: the byte count comes from glibc's malloc_usable_size.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "alloc_count.h"
#include "flatline/flatline.h"
#include "test_files.h"

#ifdef __linux__
#  include <malloc.h>
#  include <unistd.h>
#endif

/* The documented formulas promise 20 %. */
static const double k_tolerance = 0.20;

static size_t g_before;

static void start(void) {
    alloc_reset_peak();
    g_before = alloc_live_bytes();
}

static double peak_bytes(void) {
    return (double)(alloc_peak_bytes() - g_before);
}

/* Resident bytes of this process now. */
static double resident_bytes(void) {
#ifdef __linux__
    FILE *statm = fopen("/proc/self/statm", "r");
    unsigned long pages = 0, resident = 0;
    if (statm == NULL)
        return NAN;
    int got = fscanf(statm, "%lu %lu", &pages, &resident);
    fclose(statm);
    return got == 2 ? (double)resident * (double)sysconf(_SC_PAGESIZE) : NAN;
#else
    return NAN;
#endif
}

static void within(const char *what, double measured, double documented) {
    const double ratio = measured / documented;
    print_message("%-58s measured %12.0f B, documented %12.0f B (%.3f)\n", what, measured,
                  documented, ratio);
    assert_true(ratio >= 1.0 - k_tolerance);
    assert_true(ratio <= 1.0 + k_tolerance);
}

static flt_options *bag(void) {
    flt_options *options = NULL;
    assert_int_equal(flt_options_create(&options), FLT_OK);
    return options;
}

static void set(flt_options *options, int key, double value) {
    assert_int_equal(flt_options_set(options, key, value), FLT_OK);
}

/* flatness.h: R x (97 + 18 K) + 250 K + 100 Z bytes. */
static double flatness_formula(double rows, double fibers, double zones) {
    return rows * (97 + 18 * fibers) + 250 * fibers + 100 * zones;
}

static void flatness_case(size_t fibers, double rows, int check_resident) {
    double *x = malloc(fibers * sizeof *x);
    assert_non_null(x);
    for (size_t k = 0; k < fibers; ++k)
        x[k] = -1000.0 + 2.0 * (double)k;
    flt_options *options = bag();
    set(options, FLT_OPT_FLAT_ROW_CAPACITY, rows);
#ifdef __linux__
    malloc_trim(0);
#endif
    const double resident_before = resident_bytes();
    flt_flatness *flatness = NULL;
    start();
    assert_int_equal(flt_flatness_create(fibers, x, options, &flatness), FLT_OK);
    const double measured = peak_bytes();
    const double resident = resident_bytes() - resident_before;
    size_t zones = 0;
    assert_int_equal(flt_flatness_zones(flatness, &zones), FLT_OK);
    char what[96];
    snprintf(what, sizeof what, "flatness: %zu fibers, %.0f rows, %zu zones", fibers, rows, zones);
    const double documented = flatness_formula(rows, (double)fibers, (double)zones);
    within(what, measured, documented);
    if (check_resident) {
        strncat(what, " (resident)", sizeof what - strlen(what) - 1);
        within(what, resident, documented);
    }
    flt_flatness_destroy(flatness);
    flt_options_destroy(options);
    free(x);
}

static void test_flatness_follows_its_formula(void **state) {
    (void)state;
    flatness_case(1, 1e5, 0);
    flatness_case(10, 1e4, 0);
    flatness_case(150, 4096, 0);   /* the defaults on a narrow sensor */
    flatness_case(1150, 4096, 0);  /* the README's line */
    flatness_case(1150, 10000, 0); /* a 3 m sheet at 0.3 mm frames */
    flatness_case(10, 1e6, 1);     /* 277 MB */
}

static void test_flatness_refuses_on_its_formula(void **state) {
    (void)state;
    /* 40,000 rows of 3,000 fibers: 2.16 GB by the formula, just over
     * FLT_FLATNESS_MAX_BYTES (2.147 GB); 39,000 rows (2.11 GB) pass the
     * check (not created here: it would take the memory). */
    const size_t fibers = 3000;
    double *x = malloc(fibers * sizeof *x);
    assert_non_null(x);
    for (size_t k = 0; k < fibers; ++k)
        x[k] = (double)k;
    assert_true(flatness_formula(40000, 3000, 1) > FLT_FLATNESS_MAX_BYTES);
    assert_true(flatness_formula(39000, 3000, 1) < FLT_FLATNESS_MAX_BYTES);
    flt_options *options = bag();
    set(options, FLT_OPT_FLAT_ROW_CAPACITY, 40000);
    flt_flatness *flatness = NULL;
    start();
    assert_int_equal(flt_flatness_create(fibers, x, options, &flatness), FLT_ERR_INVALID_ARGUMENT);
    assert_null(flatness);
    assert_non_null(strstr(flt_last_error_message(), "flat_row_capacity"));
    /* Refused before the buffers: only the option bag's copy was made. */
    assert_true(peak_bytes() < 1e6);
    flt_options_destroy(options);
    free(x);
}

/* recon.h, "Memory": the lag in knots that latency_mm gives (the longest
 * whose rows are final within it: lag + lag/8 + 2 knots and half the laser
 * spacing), the knots a row may wait (w: twice that at a strip's head; the
 * lag and its emission group with lag_knots set) and the formula. */
static double lag_for_latency(double latency_mm, double knot, double laser) {
    double lag = 0;
    while ((lag + 1 + 1 + floor((lag + 1) / 8) + 1) * knot + 0.5 * laser <= latency_mm)
        ++lag;
    return lag;
}

static double recon_formula(double fibers, double rows, double lag, double wait, double S,
                            int rigid, int robust) {
    const double K = fibers, L = lag, W = wait, R = rows;
    double bytes = R * (9 + 9 * K);
    if (!robust) {
        bytes += K * (W + floor(L / 8) + 12) * 8 * (4 * S + 3);
    } else {
        bytes += R * (8 + 8 * K);
        bytes += K * 16 * ((2 * S + 1) * (S + 1) * (W + 2 * S + 8) + W + floor(L / 8) + 170);
    }
    if (rigid)
        bytes += R * (robust ? 92 : 60);
    return bytes;
}

/* lag_knots < 0: the default latency_mm; knot_spacing 0: the default (the
 * laser spacing, 100 mm). */
static void recon_case(size_t fibers, double rows, int rigid, int robust, double lag_knots,
                       double knot_spacing, int check_resident) {
    flt_options *options = bag();
    set(options, FLT_OPT_ROW_CAPACITY, rows);
    set(options, FLT_OPT_RIGID_MOTION, rigid);
    set(options, FLT_OPT_ROBUST, robust);
    if (lag_knots >= 0)
        set(options, FLT_OPT_LAG_KNOTS, lag_knots);
    if (knot_spacing > 0)
        set(options, FLT_OPT_KNOT_SPACING, knot_spacing);
    double latency = 0, laser = 0, knot = knot_spacing > 0 ? knot_spacing : 0;
    assert_int_equal(flt_options_get(options, FLT_OPT_LATENCY_MM, &latency), FLT_OK);
    assert_int_equal(flt_options_get(options, FLT_OPT_LASER_SPACING, &laser), FLT_OK);
    if (knot == 0)
        knot = laser;
    const double S = ceil(laser / knot - 1e-9) + 2;
    double lag = lag_knots, wait = 0;
    if (lag_knots < 0) {
        lag = lag_for_latency(latency, knot, laser);
        wait = 2 * (lag + floor(lag / 8) + 2);
    } else {
        wait = lag + floor(lag / 8) + 1;
    }
#ifdef __linux__
    malloc_trim(0);
#endif
    const double resident_before = resident_bytes();
    flt_recon *recon = NULL;
    start();
    assert_int_equal(flt_recon_create(fibers, options, &recon), FLT_OK);
    const double measured = peak_bytes();
    const double resident = resident_bytes() - resident_before;
    /* The lag the formula takes is the one the reconstructor took. */
    double taken = 0;
    assert_int_equal(flt_recon_get_option(recon, FLT_OPT_LAG_KNOTS, &taken), FLT_OK);
    assert_true(taken == lag);
    char what[96];
    snprintf(what, sizeof what, "recon: %zu fibers, %.0f rows, lag %.0f, S %.0f%s%s", fibers, rows,
             lag, S, rigid ? ", rigid" : "", robust ? ", robust" : "");
    const double documented = recon_formula((double)fibers, rows, lag, wait, S, rigid, robust);
    within(what, measured, documented);
    if (check_resident) {
        strncat(what, " (resident)", sizeof what - strlen(what) - 1);
        within(what, resident, documented);
    }
    flt_recon_destroy(recon);
    flt_options_destroy(options);
}

static void test_reconstructor_follows_its_formula(void **state) {
    (void)state;
    for (int rigid = 0; rigid <= 1; ++rigid) {
        for (int robust = 0; robust <= 1; ++robust) {
            recon_case(10, 65536, rigid, robust, -1, 0, 0);
            recon_case(150, 8192, rigid, robust, -1, 0, 0);
            recon_case(1150, 8192, rigid, robust, -1, 0, 0);
            /* The older setting, a long lag, and knots closer than the
             * lasers (a row spans 4 of them). */
            recon_case(150, 8192, rigid, robust, 64, 50, 0);
        }
    }
    recon_case(1000, 65536, 0, 0, -1, 0, 1); /* 600 MB */
    recon_case(300, 16384, 1, 1, -1, 0, 1);  /* 160 MB, robust */
}

static void test_reconstructor_refuses_on_its_formula(void **state) {
    (void)state;
    /* 3000 fibers in robust mode with 40,000 rows: 2.07 GB by the formula,
     * just under FLT_RECON_MAX_BYTES (2.147 GB, not created here: it would
     * take the memory); 42,000 rows, 2.17 GB, is refused before anything
     * is allocated. */
    const double lag = lag_for_latency(2000, 100, 100), wait = 2 * (lag + floor(lag / 8) + 2);
    assert_true(recon_formula(3000, 42000, lag, wait, 3, 0, 1) > FLT_RECON_MAX_BYTES);
    assert_true(recon_formula(3000, 40000, lag, wait, 3, 0, 1) < FLT_RECON_MAX_BYTES);
    flt_options *options = bag();
    set(options, FLT_OPT_ROW_CAPACITY, 42000);
    set(options, FLT_OPT_ROBUST, 1);
    flt_recon *recon = NULL;
    start();
    assert_int_equal(flt_recon_create(3000, options, &recon), FLT_ERR_INVALID_ARGUMENT);
    assert_null(recon);
    assert_non_null(strstr(flt_last_error_message(), "row_capacity"));
    /* Refused before the buffers: only the option bag's copy was made. */
    assert_true(peak_bytes() < 1e6);
    flt_options_destroy(options);
}

/* gauge.h, "Memory": the reconstructor at the gauge's row capacity (R,
 * as flt_gauge_get_option reports it), two flatness metrics, the
 * extractors, and the gauge's own buffers: the frame queue, the row ring,
 * two sheet buffers and the sheet slots' maps, S rows each. */
static double gauge_formula(double K, double Z, double W, double H, double R, double recon,
                            double Q, double E, double S, double P, int keep_maps,
                            double short_rows) {
    double bytes = recon;
    bytes += Q * 2 * W * H;                  /* the frame queue (with workers) */
    bytes += E * (730 * W + 60 * K + 8 * H); /* the extractors */
    bytes += flatness_formula(16, K, Z) + flatness_formula(short_rows, K, Z);
    bytes += (65 + K / 8) * R;     /* the row ring, its off-strip bits */
    bytes += 2 * S * (88 + 9 * K); /* two sheet buffers */
    if (keep_maps >= 1)
        bytes += P * S * (8 + 9 * K); /* the slots' maps */
    if (keep_maps >= 2)
        bytes += 8 * K * (R + 2 * S + P * S);      /* measured heights */
    bytes += K * (100 * P + 20 * Q + 400) + 30000; /* slots' arrays, per-fiber scratch, fixed */
    return bytes;
}

static void gauge_case(size_t fibers, uint32_t rows, double workers, double queue, double sheet_mm,
                       double frame_mm, double slots, int keep_maps, int rigid, int robust) {
    flt_calib *calib = NULL;
    assert_int_equal(
        flt_calib_create_reference(0, rows, -1000.0, 2000.0 / (double)fibers, fibers, &calib),
        FLT_OK);
    uint32_t width = 0, height = 0;
    assert_int_equal(flt_calib_get_frame_size(calib, &width, &height), FLT_OK);
    flt_options *options = bag();
    set(options, FLT_OPT_GAUGE_WORKERS, workers);
    set(options, FLT_OPT_GAUGE_QUEUE_FRAMES, queue);
    set(options, FLT_OPT_GAUGE_MAX_SHEET_LENGTH, sheet_mm);
    set(options, FLT_OPT_GAUGE_FRAME_SPACING, frame_mm);
    set(options, FLT_OPT_GAUGE_SHEET_SLOTS, slots);
    set(options, FLT_OPT_GAUGE_KEEP_MAPS, keep_maps);
    set(options, FLT_OPT_RIGID_MOTION, rigid);
    set(options, FLT_OPT_ROBUST, robust);
#ifdef __linux__
    malloc_trim(0);
#endif
    flt_gauge *gauge = NULL;
    start();
    assert_int_equal(flt_gauge_create(calib, options, &gauge), FLT_OK);
    const double measured = peak_bytes();
    double R = 0, Z = 0, min_length = 0;
    assert_int_equal(flt_gauge_get_option(gauge, FLT_OPT_ROW_CAPACITY, &R), FLT_OK);
    assert_int_equal(flt_gauge_get_option(gauge, FLT_OPT_FLAT_MIN_LENGTH, &min_length), FLT_OK);
    flt_gauge_destroy(gauge);
    /* The reconstructor alone at that capacity, by its own formula. */
    double lag = 0, passes = 0, line_passes = 0;
    assert_int_equal(flt_options_get(options, FLT_OPT_LAG_KNOTS, &lag), FLT_OK);
    if (robust) {
        assert_int_equal(flt_options_get(options, FLT_OPT_ROBUST_ITERATIONS, &passes), FLT_OK);
        assert_int_equal(flt_options_get(options, FLT_OPT_ROBUST_LINE_ITERATIONS, &line_passes),
                         FLT_OK);
    }
    const double recon = recon_formula((double)fibers, R, lag, passes, rigid, robust, line_passes);
    {
        double *x = malloc(fibers * sizeof *x);
        for (size_t k = 0; k < fibers; ++k)
            x[k] = -1000.0 + 2000.0 / (double)fibers * (double)k;
        flt_flatness *flatness = NULL;
        assert_int_equal(flt_flatness_create(fibers, x, NULL, &flatness), FLT_OK);
        size_t zones = 0;
        assert_int_equal(flt_flatness_zones(flatness, &zones), FLT_OK);
        Z = (double)zones;
        flt_flatness_destroy(flatness);
        free(x);
    }
    const double S = ceil(sheet_mm / frame_mm) + 2;
    const double E = 1; /* automatic bands (or no workers): one extractor at create */
    const double documented =
        gauge_formula((double)fibers, Z, width, height, R, recon, workers > 0 ? queue : 0, E, S,
                      slots, keep_maps, fmax(16, ceil(min_length / frame_mm) + 2));
    char what[120];
    snprintf(what, sizeof what, "gauge: %zu fibers, %ux%u, %g workers, R %.0f, S %.0f, maps %d%s",
             fibers, width, height, workers, R, S, keep_maps, robust ? ", robust" : "");
    within(what, measured, documented);
    flt_options_destroy(options);
    flt_calib_destroy(calib);
}

/* A configuration whose own buffers pass 8 GiB (4,000 fibers, 100 m
 * sheets at 1 mm, measured heights kept): refused, naming what to lower,
 * before its buffers are allocated (only the reconstructor's probe of 16
 * rows, some 40 MB, is made). */
static void test_gauge_refuses_on_its_formula(void **state) {
    (void)state;
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create_reference(0, 256, -1000.0, 0.5, 4000, &calib), FLT_OK);
    flt_options *options = bag();
    set(options, FLT_OPT_GAUGE_MAX_SHEET_LENGTH, 100000);
    set(options, FLT_OPT_GAUGE_FRAME_SPACING, 1);
    set(options, FLT_OPT_GAUGE_KEEP_MAPS, 2);
    flt_gauge *gauge = NULL;
    start();
    assert_int_equal(flt_gauge_create(calib, options, &gauge), FLT_ERR_INVALID_ARGUMENT);
    assert_null(gauge);
    assert_non_null(strstr(flt_last_error_message(), "gauge_max_sheet_length"));
    print_message("refused after a peak of %.0f B: %s\n", peak_bytes(), flt_last_error_message());
    assert_true(peak_bytes() < 100e6);
    flt_options_destroy(options);
    flt_calib_destroy(calib);
}

static void test_gauge_follows_its_formula(void **state) {
    (void)state;
    gauge_case(1150, 256, 2, 8, 6000, 3, 4, 0, 0, 0);
    gauge_case(1150, 256, 2, 8, 6000, 3, 4, 1, 1, 1);
    gauge_case(1150, 256, 0, 8, 6000, 3, 4, 2, 1, 1);
    gauge_case(150, 1024, 2, 32, 12000, 1, 8, 1, 0, 0);
    gauge_case(150, 64, 1, 4, 2000, 10, 2, 0, 1, 1);
    gauge_case(4000, 256, 2, 8, 6000, 3, 16, 1, 1, 0);
}

/* extractor.h and sim.h, "Memory": per column of the frame, per pixel
 * (the simulator's frame scratch) and per fiber. */
static void test_extractor_and_simulator_follow_their_formulas(void **state) {
    (void)state;
    const uint32_t rows[] = {64, 256, 2048};
    const size_t fibers[] = {11, 1001, 4096};
    for (size_t r = 0; r < sizeof rows / sizeof rows[0]; ++r) {
        for (size_t f = 0; f < sizeof fibers / sizeof fibers[0]; ++f) {
            flt_calib *calib = NULL;
            assert_int_equal(flt_calib_create_reference(0, rows[r], -1000.0,
                                                        2000.0 / (double)fibers[f], fibers[f],
                                                        &calib),
                             FLT_OK);
            uint32_t width = 0, height = 0;
            assert_int_equal(flt_calib_get_frame_size(calib, &width, &height), FLT_OK);
            const double W = width, H = height, K = (double)fibers[f];
            char what[96];

            flt_extractor *extractor = NULL;
            start();
            assert_int_equal(flt_extractor_create(calib, NULL, &extractor), FLT_OK);
            snprintf(what, sizeof what, "extractor: %u x %u, %zu fibers", width, height, fibers[f]);
            within(what, peak_bytes(), 730 * W + 60 * K + 8 * H);
            flt_extractor_destroy(extractor);

            flt_sim *sim = NULL;
            start();
            assert_int_equal(flt_sim_create(calib, NULL, &sim), FLT_OK);
            snprintf(what, sizeof what, "simulator: %u x %u, %zu fibers", width, height, fibers[f]);
            within(what, peak_bytes(), 4 * W * H + 170 * W + 25 * K);
            flt_sim_destroy(sim);
            flt_calib_destroy(calib);
        }
    }
}

/* advisor.h, "Memory": Z zones, A actuators. */
static void test_advisor_follows_its_formula(void **state) {
    (void)state;
    const size_t zones[] = {5, 40, 200};
    const size_t actuators[] = {4, 16, 64};
    for (size_t z = 0; z < 3; ++z) {
        for (size_t a = 0; a < 3; ++a) {
            const double Z = (double)zones[z], A = (double)actuators[a];
            flt_advisor *advisor = NULL;
            start();
            assert_int_equal(flt_advisor_create(zones[z], actuators[a], NULL, &advisor), FLT_OK);
            char what[96];
            snprintf(what, sizeof what, "advisor: %zu zones, %zu actuators", zones[z],
                     actuators[a]);
            within(what, peak_bytes(), 8 * (3 * Z * A + 3.5 * A * A + 2 * Z) + 1500);
            flt_advisor_destroy(advisor);
        }
    }
}

/* record.h, "Memory": (record_queue_blocks + 2) blocks of
 * record_block_rows rows, (9 K + 58) bytes a row, and 1.5 MB for SQLite's
 * connection and page cache (64 KiB pages) when the file is made. */
static void test_recorder_follows_its_formula(void **state) {
    (void)state;
    /* fibers, rows a block, blocks queued: the smallest, the defaults at
     * two widths (the README's line is the second), long blocks. */
    const double cases[][3] = {{10, 16, 2}, {150, 256, 16}, {1150, 256, 16}, {10, 4096, 64}};
    char dir[256], path[300];
    assert_int_equal(tf_temp_dir(dir, sizeof dir, "memory"), 0);
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        const double K = cases[c][0], B = cases[c][1], Q = cases[c][2];
        flt_calib *calib = NULL;
        assert_int_equal(
            flt_calib_create_reference(900, 240, -1150.0, 2300.0 / K, (size_t)K, &calib), FLT_OK);
        flt_options *options = bag();
        set(options, FLT_OPT_RECORD_QUEUE_BLOCKS, Q);
        set(options, FLT_OPT_RECORD_BLOCK_ROWS, B);
        snprintf(path, sizeof path, "%s/r%zu.flrec", dir, c);
        flt_recorder *recorder = NULL;
        start();
        assert_int_equal(flt_recorder_create(path, calib, options, &recorder), FLT_OK);
        const double measured = peak_bytes();
        char what[96];
        snprintf(what, sizeof what, "recorder: %.0f fibers, %.0f rows a block, %.0f queued", K, B,
                 Q);
        within(what, measured, (Q + 2) * B * (9 * K + 58) + 1.5e6);
        flt_recorder_destroy(recorder);
        flt_options_destroy(options);
        flt_calib_destroy(calib);
    }
    assert_int_equal(tf_remove_tree(dir), 0);
}

static void test_the_count_sees_allocations(void **state) {
    (void)state;
    /* The control: a hook that saw nothing would pass every formula's
     * refusal case and fail the others; this names the cause. */
    start();
    void *block = malloc(1 << 20);
    assert_non_null(block);
    memset(block, 1, 1 << 20);
    assert_true(peak_bytes() >= (double)(1 << 20));
    free(block);
}

int main(void) {
#ifndef __linux__
    print_message("test_memory: Linux only (the byte count needs glibc's malloc_usable_size)\n");
    return 0;
#else
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_count_sees_allocations),
        cmocka_unit_test(test_flatness_follows_its_formula),
        cmocka_unit_test(test_flatness_refuses_on_its_formula),
        cmocka_unit_test(test_reconstructor_follows_its_formula),
        cmocka_unit_test(test_reconstructor_refuses_on_its_formula),
        cmocka_unit_test(test_extractor_and_simulator_follow_their_formulas),
        cmocka_unit_test(test_advisor_follows_its_formula),
        cmocka_unit_test(test_gauge_follows_its_formula),
        cmocka_unit_test(test_gauge_refuses_on_its_formula),
        cmocka_unit_test(test_recorder_follows_its_formula),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
#endif
}
