// SPDX-License-Identifier: Apache-2.0
/*
 * Finite but absurd values and sizes, across components: what a
 * hand-edited calibration file, an option at the edge of its documented
 * range or a size no sensor has does to the chain calibration -> extractor
 * -> reconstructor -> flatness.
 *
 * Each test is the regression test of one such defect:
 *   - a calibration whose values are finite but absurd (pitch 1e-300 mm,
 *     fx 1e300 px, ...) loaded, and the extractor's first frame wrote far
 *     out of bounds: the loader refuses every value outside calib.h's
 *     ranges, naming the field, and accepts the ranges' ends; a
 *     calibration inside the ranges whose columns map far off the fiber
 *     grid is processed without an out-of-range conversion;
 *   - the flatness zones were sized by the fibers' span without a bound
 *     (1e9 mm: 40 million zones; 1e300 mm: an undefined conversion);
 *   - slope_sigma at its documented minimum made every reconstructed
 *     value NaN without FLT_FLAG_NO_DATA, and heights of 1e8 mm in robust
 *     mode with rigid motion half of them;
 *   - sizes that passed the checks and then took the machine (a 65536 x
 *     65536 frame, 1e8 fibers, a 100 MB calibration text, buffers of
 *     terabytes), now refused before anything is allocated;
 *   - sim_full_well near its documented minimum gave NaN pixels through an
 *     undefined conversion (the asan preset, with float-cast-overflow,
 *     reports it).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#ifdef _WIN32
#  include <windows.h>
#  include <psapi.h>
#else
#  include <sys/resource.h>
#endif

#include <cmocka.h>

#include "flatline/flatline.h"

static double now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Peak resident memory of the process so far, MB. */
static double peak_rss_mb(void) {
#ifdef _WIN32
    PROCESS_MEMORY_COUNTERS counters;
    if (!GetProcessMemoryInfo(GetCurrentProcess(), &counters, sizeof counters))
        return 0.0;
    return (double)counters.PeakWorkingSetSize / (1024.0 * 1024.0);
#else
    struct rusage usage;
    getrusage(RUSAGE_SELF, &usage);
    return (double)usage.ru_maxrss / 1024.0; /* Linux: kB */
#endif
}

/* The saved text of the reference sensor's calibration (malloc'd). */
static char *reference_text(void) {
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create_reference(0, 2048, -1000.0, 2.0, 1001, &calib), FLT_OK);
    size_t length = 0;
    assert_int_equal(flt_calib_save_text(calib, NULL, 0, &length), FLT_ERR_BUFFER_FULL);
    char *text = malloc(length + 1);
    assert_int_equal(flt_calib_save_text(calib, text, length + 1, &length), FLT_OK);
    flt_calib_destroy(calib);
    return text;
}

/* `text` with the line holding `key` replaced by `line` (malloc'd). */
static char *with_line(const char *text, const char *key, const char *line) {
    const char *at = strstr(text, key);
    assert_non_null(at);
    while (at > text && at[-1] != '\n')
        --at;
    const char *end = strchr(at, '\n');
    assert_non_null(end);
    const size_t head = (size_t)(at - text);
    char *out = malloc(strlen(text) + strlen(line) + 2);
    memcpy(out, text, head);
    strcpy(out + head, line);
    strcat(out, end);
    return out;
}

/* Loads `text`; returns the model (NULL on failure) and the status. */
static flt_status load(const char *text, flt_calib **out) {
    *out = NULL;
    return flt_calib_load_text(text, strlen(text), out);
}

/* ---------------------------------------------------------------------- */
/* Calibration files                                                       */
/* ---------------------------------------------------------------------- */

typedef struct field_edit {
    const char *key;   /* a unique text on the line to replace */
    const char *line;  /* its replacement */
    const char *field; /* the field the message must name */
} field_edit;

static void test_absurd_calibration_values_are_refused_naming_the_field(void **state) {
    (void)state;
    char *ref = reference_text();
    /* The reported values first, then one past each range of calib.h. */
    static const field_edit edits[] = {
        {"\"pitch_mm\"", "    \"pitch_mm\": 1e-300,", "fibers.pitch_mm"},
        {"\"fx\"", "    \"fx\": 1e300,", "camera.fx"},
        {"\"width\"", "    \"width\": 65536,", "frame.width"},
        {"\"count\"", "    \"count\": 100000000", "fibers.count"},
        {"\"pitch_mm\"", "    \"pitch_mm\": 4294967296,", "fibers.pitch_mm"},
        {"\"height\"", "    \"height\": 16385", "frame.height"},
        {"\"fy\"", "    \"fy\": 0.5,", "camera.fy"},
        {"\"cx\"", "    \"cx\": 70000,", "camera.cx"},
        {"\"cy\"", "    \"cy\": -1e200,", "camera.cy"},
        {"\"k1\"", "      \"k1\": 1001,", "camera.distortion.k1"},
        {"\"k6\"", "      \"k6\": -1e300", "camera.distortion.k6"},
        {"\"p2\"", "      \"p2\": 1.5,", "camera.distortion.p2"},
        {"\"offset_mm\": -50", "      \"offset_mm\": -10001,", "lasers[0].offset_mm"},
        {"\"offset_mm\": 50", "      \"offset_mm\": -49.5,", "lasers[0].offset_mm"},
        {"\"encoder_mm_per_count\"", "  \"encoder_mm_per_count\": 1e-300,", "encoder_mm_per_count"},
        {"\"encoder_mm_per_count\"", "  \"encoder_mm_per_count\": -2e6,", "encoder_mm_per_count"},
        {"\"first_x_mm\"", "    \"first_x_mm\": 1e300,", "fibers.first_x_mm"},
        {"\"first_x_mm\"", "    \"first_x_mm\": 99000,", "fibers.first_x_mm"},
        {"\"count\"", "    \"count\": 16385", "fibers.count"},
    };
    for (size_t i = 0; i < sizeof edits / sizeof edits[0]; ++i) {
        char *text = with_line(ref, edits[i].key, edits[i].line);
        flt_calib *calib = (flt_calib *)ref; /* not NULL: must be cleared */
        const flt_status st = flt_calib_load_text(text, strlen(text), &calib);
        print_message("%-40s -> %s\n", edits[i].line, flt_last_error_message());
        assert_int_equal(st, FLT_ERR_FORMAT);
        assert_null(calib);
        assert_non_null(strstr(flt_last_error_message(), edits[i].field));
        free(text);
    }
    /* A homography scaled by 1e200: invertible (the identity's condition),
     * but beyond FLT_CALIB_MAX_HOMOGRAPHY_SCALE. */
    const char *h = strstr(ref, "\"homography\": [");
    assert_non_null(h);
    h += strlen("\"homography\": [");
    const char *close = strchr(h, ']');
    char *scaled = malloc(strlen(ref) + 128);
    memcpy(scaled, ref, (size_t)(h - ref));
    sprintf(scaled + (h - ref), "1e200, 0, 0, 0, 1e200, 0, 0, 0, 1e200%s", close);
    flt_calib *calib = NULL;
    assert_int_equal(load(scaled, &calib), FLT_ERR_FORMAT);
    print_message("scaled homography -> %s\n", flt_last_error_message());
    assert_non_null(strstr(flt_last_error_message(), "lasers[0].homography"));
    assert_non_null(strstr(flt_last_error_message(), "largest |entry|"));
    free(scaled);
    free(ref);
}

/* The ends of the ranges load, and the whole chain runs on them: an
 * extractor and a simulator are created and a frame is processed (under
 * the asan preset: without an out-of-range conversion or access). */
static void test_calibration_at_the_ends_of_its_ranges_runs_the_chain(void **state) {
    (void)state;
    char *ref = reference_text();
    char line[128];
    /* The finest pitch and the most fibers, at the grid's left limit. */
    snprintf(line, sizeof line, "    \"first_x_mm\": %.17g,", -FLT_CALIB_MAX_X_MM);
    char *a = with_line(ref, "\"first_x_mm\"", line);
    snprintf(line, sizeof line, "    \"pitch_mm\": %.17g,", FLT_CALIB_MIN_PITCH_MM);
    char *b = with_line(a, "\"pitch_mm\"", line);
    snprintf(line, sizeof line, "    \"count\": %d", FLT_MAX_FIBERS);
    char *text = with_line(b, "\"count\"", line);
    flt_calib *calib = NULL;
    assert_int_equal(load(text, &calib), FLT_OK);
    flt_extractor *ex = NULL;
    assert_int_equal(flt_extractor_create(calib, NULL, &ex), FLT_OK);
    size_t fibers = 0;
    assert_int_equal(flt_extractor_fibers(ex, &fibers), FLT_OK);
    assert_int_equal(fibers, FLT_MAX_FIBERS);

    /* A frame of the reference sensor (its lines are where this model's
     * homographies put them; the grid is far off to the left, so every
     * fiber is invalid). */
    flt_sim *sim = NULL;
    assert_int_equal(flt_sim_create(NULL, NULL, &sim), FLT_OK);
    uint8_t *frame = malloc(2048 * 2048);
    assert_int_equal(flt_sim_next_frame(sim, frame, 2048 * 2048, 2048, NULL, 0, NULL, NULL, 0),
                     FLT_OK);
    double *height = malloc(fibers * sizeof(double)), *slope = malloc(fibers * sizeof(double));
    const double t0 = now_s();
    assert_int_equal(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, 2048, 2048, 2048, 0.0,
                                           fibers, NULL, height, slope, NULL),
                     FLT_OK);
    const double seconds = now_s() - t0;
    size_t valid = 0;
    for (size_t k = 0; k < fibers; ++k)
        valid += height[k] == height[k];
    print_message("grid at x = -1e5 mm, pitch 1 um: %zu valid fibers, %.3f s\n", valid, seconds);
    /* The camera sees about x in [-1500, 1500] mm; the grid ends at
     * -1e5 + 16.4 mm. */
    assert_int_equal(valid, 0);
    /* About 10 ms on the development machine (the automatic band search
     * and the column maps); 2 s bounds it with room for the asan build. */
    assert_true(seconds < 2.0);
    flt_extractor_destroy(ex);
    flt_calib_destroy(calib);
    free(a), free(b), free(text);

    /* The largest frame and focal length: loads, and the extractor builds
     * its maps (fixed bands). */
    snprintf(line, sizeof line, "    \"width\": %d,", FLT_CALIB_MAX_FRAME_SIDE);
    a = with_line(ref, "\"width\"", line);
    snprintf(line, sizeof line, "    \"fx\": %.17g,", FLT_CALIB_MAX_FOCAL_PX);
    text = with_line(a, "\"fx\"", line);
    assert_int_equal(load(text, &calib), FLT_OK);
    flt_options *options = NULL;
    assert_int_equal(flt_options_create(&options), FLT_OK);
    assert_int_equal(flt_options_set(options, FLT_OPT_EXTRACT_LASER0_FIRST_ROW, 900), FLT_OK);
    assert_int_equal(flt_options_set(options, FLT_OPT_EXTRACT_LASER0_ROWS, 100), FLT_OK);
    assert_int_equal(flt_options_set(options, FLT_OPT_EXTRACT_LASER1_FIRST_ROW, 1000), FLT_OK);
    assert_int_equal(flt_options_set(options, FLT_OPT_EXTRACT_LASER1_ROWS, 100), FLT_OK);
    assert_int_equal(flt_extractor_create(calib, options, &ex), FLT_OK);
    flt_extractor_destroy(ex);
    flt_options_destroy(options);
    flt_calib_destroy(calib);
    free(a), free(text);

    free(height), free(slope), free(frame);
    flt_sim_destroy(sim);
    free(ref);
}

/* A model inside every range whose laser planes have their horizon on a
 * camera column: the columns beside it map to x of order 1e17 mm, far off
 * the fiber grid. The resampling used to convert (x - first_x) / pitch to
 * an integer unchecked (an out-of-bounds write when positive). */
static void test_columns_mapped_far_off_the_grid_are_skipped(void **state) {
    (void)state;
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create(&calib), FLT_OK);
    assert_int_equal(flt_calib_set_frame_size(calib, 2048, 2048), FLT_OK);
    /* No distortion, principal point on column 1000: that column's
     * undistorted u is exactly 1000. */
    const double camera[4] = {1090.909090909091, 1090.909090909091, 1000.0, 1023.5};
    assert_int_equal(flt_calib_set_intrinsics(calib, camera, FLT_CALIB_CAMERA_VALUES, NULL, 0),
                     FLT_OK);
    /* x = -100 u / (u - 1000 - 1.1e-13), z = v / (u - 1000 - 1.1e-13):
     * the denominator vanishes between columns 1000 and 1001, so column
     * 1000 maps to x = +9e17 mm. Largest entry 1000, well conditioned. */
    const double h[9] = {-100, 0, 0, 0, 1, 0, 1, 0, -nextafter(1000.0, 2000.0)};
    assert_int_equal(flt_calib_set_homography(calib, 0, h, FLT_CALIB_HOMOGRAPHY_ENTRIES), FLT_OK);
    assert_int_equal(flt_calib_set_homography(calib, 1, h, FLT_CALIB_HOMOGRAPHY_ENTRIES), FLT_OK);
    assert_int_equal(flt_calib_set_laser_offset(calib, 0, -50), FLT_OK);
    assert_int_equal(flt_calib_set_laser_offset(calib, 1, 50), FLT_OK);
    assert_int_equal(flt_calib_set_encoder_scale(calib, 0.01), FLT_OK);
    /* The finest grid, where (x - first_x) / pitch is largest. */
    assert_int_equal(flt_calib_set_fiber_grid(calib, -1000, FLT_CALIB_MIN_PITCH_MM, 4096), FLT_OK);
    assert_int_equal(flt_calib_finish(calib), FLT_OK);
    double plane[2];
    const double pixel[2] = {1000.0, 1044.0};
    assert_int_equal(flt_calib_image_to_plane(calib, 0, 1, pixel, plane), FLT_OK);
    print_message("column 1000 maps to x = %g mm\n", plane[0]);
    assert_true(plane[0] > 1e16); /* (x - first_x) / pitch > 1e19 > LONG_MAX */

    flt_extractor *ex = NULL;
    assert_int_equal(flt_extractor_create(calib, NULL, &ex), FLT_OK);
    flt_sim *sim = NULL; /* the reference sensor's frame: two bright lines */
    assert_int_equal(flt_sim_create(NULL, NULL, &sim), FLT_OK);
    uint8_t *frame = malloc(2048 * 2048);
    double *height = malloc(4096 * sizeof(double)), *slope = malloc(4096 * sizeof(double));
    for (int f = 0; f < 3; ++f) {
        assert_int_equal(flt_sim_next_frame(sim, frame, 2048 * 2048, 2048, NULL, 0, NULL, NULL, 0),
                         FLT_OK);
        assert_int_equal(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, 2048, 2048, 2048,
                                               3.0 * f, 4096, NULL, height, slope, NULL),
                         FLT_OK);
        /* A valid fiber is finite (x(u) = -100u/(u - 1000) crosses the
         * grid near u = 1111, 8 mm per column). */
        for (size_t k = 0; k < 4096; ++k)
            assert_true(height[k] != height[k] || (isfinite(height[k]) && isfinite(slope[k])));
    }
    free(frame), free(height), free(slope);
    flt_sim_destroy(sim);
    flt_extractor_destroy(ex);
    flt_calib_destroy(calib);
}

/* A text of 100 MB used to be parsed (6.4 GB, 8 s) before being refused. */
static void test_oversized_calibration_text_is_refused_before_parsing(void **state) {
    (void)state;
    const size_t big = 100u << 20;
    char *text = malloc(big);
    memset(text, ' ', big);
    text[0] = '{';
    const double rss0 = peak_rss_mb(), t0 = now_s();
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_load_text(text, big, &calib), FLT_ERR_FORMAT);
    const double seconds = now_s() - t0, grown = peak_rss_mb() - rss0;
    print_message("100 MB text: %s (%.4f s, +%.1f MB)\n", flt_last_error_message(), seconds, grown);
    assert_null(calib);
    assert_non_null(strstr(flt_last_error_message(), "65536 bytes"));
    /* Refused at its length: microseconds, no memory. 0.1 s and 1 MB leave
     * room for a loaded machine; parsing it took 8 s and 6.4 GB. */
    assert_true(seconds < 0.1);
    assert_true(grown < 1.0);
    free(text);

    /* The limit itself: the reference padded with spaces to exactly
     * FLT_CALIB_MAX_FILE_BYTES loads; one byte more does not. */
    char *ref = reference_text();
    char *padded = malloc(FLT_CALIB_MAX_FILE_BYTES + 2);
    memset(padded, ' ', FLT_CALIB_MAX_FILE_BYTES + 1);
    memcpy(padded, ref, strlen(ref));
    assert_int_equal(flt_calib_load_text(padded, FLT_CALIB_MAX_FILE_BYTES, &calib), FLT_OK);
    flt_calib_destroy(calib);
    assert_int_equal(flt_calib_load_text(padded, FLT_CALIB_MAX_FILE_BYTES + 1, &calib),
                     FLT_ERR_FORMAT);
    free(padded);
    free(ref);
}

/* ---------------------------------------------------------------------- */
/* Flatness zones                                                          */
/* ---------------------------------------------------------------------- */

static void test_flatness_zone_count_is_bounded(void **state) {
    (void)state;
    flt_flatness *f = NULL;
    double x[3];
    /* The reported spans: 1e9 mm (40 million zones of 50 mm) and 1e300 mm
     * (the count overflowed its conversion and came out as 1 zone); both
     * now fail on the positions, beyond FLT_CALIB_MAX_X_MM. */
    x[0] = -5e8, x[1] = 0, x[2] = 5e8;
    assert_int_equal(flt_flatness_create(3, x, NULL, &f), FLT_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(flt_last_error_message(), "fiber_x[0]"));
    x[0] = -5e299, x[1] = 0, x[2] = 5e299;
    assert_int_equal(flt_flatness_create(3, x, NULL, &f), FLT_ERR_INVALID_ARGUMENT);
    /* Inside the positions' range, narrow zones: 2e5 mm / 1 mm (3 fibers
     * cover 1.5 times their span) = 300,000 zones > FLT_FLATNESS_MAX_ZONES. */
    x[0] = -FLT_CALIB_MAX_X_MM, x[1] = 0, x[2] = FLT_CALIB_MAX_X_MM;
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_FLAT_ZONE_WIDTH, 1.0), FLT_OK);
    double t0 = now_s();
    assert_int_equal(flt_flatness_create(3, x, o, &f), FLT_ERR_INVALID_ARGUMENT);
    print_message("%s\n", flt_last_error_message());
    assert_non_null(strstr(flt_last_error_message(), "zones"));
    assert_null(f);
    /* The limit itself: 3 fibers 1024 mm apart cover 3072 mm; 0.1875 mm
     * zones make exactly 16384 of them. */
    x[0] = -1024, x[1] = 0, x[2] = 1024;
    assert_int_equal(flt_options_set(o, FLT_OPT_FLAT_ZONE_WIDTH, 0.1875), FLT_OK);
    assert_int_equal(flt_flatness_create(3, x, o, &f), FLT_OK);
    size_t zones = 0;
    assert_int_equal(flt_flatness_zones(f, &zones), FLT_OK);
    assert_int_equal(zones, FLT_FLATNESS_MAX_ZONES);
    flt_flatness_destroy(f);
    assert_int_equal(flt_options_set(o, FLT_OPT_FLAT_ZONE_WIDTH, 0.1874), FLT_OK);
    assert_int_equal(flt_flatness_create(3, x, o, &f), FLT_ERR_INVALID_ARGUMENT);
    /* Each call returns at once (the 1e9 mm grid took 1.3 s and 1.1 GB):
     * 0.5 s bounds all of them together with room for the asan build. */
    assert_true(now_s() - t0 < 0.5);
    flt_options_destroy(o);
}

/* A gap in the rows with the finest update interval: every window of the
 * gap used to be evaluated, one push call each (10 m of gap at 1 um: 1e7
 * calls for one row; found by the contract suite). Windows holding the same
 * rows as the one before, or none, are skipped now. */
static void test_flatness_stream_crosses_a_gap_in_few_calls(void **state) {
    (void)state;
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_FLAT_WINDOW_LENGTH, 30), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_FLAT_UPDATE_INTERVAL, 1e-3), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_FLAT_MIN_LENGTH, 1e-3), FLT_OK);
    const double x[2] = {0, 2};
    flt_flatness *f = NULL;
    assert_int_equal(flt_flatness_create(2, x, o, &f), FLT_OK);
    double s[11], z[22];
    for (int r = 0; r < 10; ++r)
        s[r] = 3.0 * r, z[2 * r] = z[2 * r + 1] = 0.1 * r;
    s[10] = 10030.0, z[20] = z[21] = 1.0;
    size_t taken = 0, calls = 0, windows = 0, consumed = 0;
    int evaluated = 0;
    const double t0 = now_s();
    while (taken < 11 && calls < 100000) {
        assert_int_equal(flt_flatness_push(f, 11 - taken, 2, s + taken, z + 2 * taken, NULL,
                                           &consumed, &evaluated),
                         FLT_OK);
        taken += consumed, windows += (size_t)evaluated, ++calls;
    }
    print_message("11 rows, the last 10 m on: %zu push calls, %zu windows, %.4f s\n", calls,
                  windows, now_s() - t0);
    /* One window as each of the 10 rows drops out of the 30 mm window (a
     * row every 3 mm, windows every 1 um: the 2999 between hold the same
     * rows), then the empty ones are skipped: 10 windows, 11 calls. */
    assert_int_equal(taken, 11);
    assert_int_equal(windows, 10);
    assert_int_equal(calls, 11);
    flt_flatness_destroy(f);
    flt_options_destroy(o);
}

/* The smallest update interval the option takes (5e-324 mm, the smallest
 * positive double) is below the spacing of doubles at any row position past
 * 1e-308 mm: adding it to the window grid changed nothing, and push spun
 * forever (found by the contract suite). A window per row now, as for any
 * interval finer than the rows. */
static void test_flatness_stream_with_a_denormal_update_interval_ends(void **state) {
    (void)state;
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_FLAT_UPDATE_INTERVAL, 4.9406564584124654e-324),
                     FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_FLAT_MIN_LENGTH, 1e-3), FLT_OK);
    const double x[2] = {0, 2};
    flt_flatness *f = NULL;
    assert_int_equal(flt_flatness_create(2, x, o, &f), FLT_OK);
    enum { N = 2000 };
    double s[N], z[2 * N];
    for (int r = 0; r < N; ++r)
        s[r] = 10000.0 + 3.0 * r, z[2 * r] = z[2 * r + 1] = sin(0.01 * r);
    size_t taken = 0, calls = 0, windows = 0, consumed = 0;
    int evaluated = 0;
    const double t0 = now_s();
    while (taken < N && calls < 10 * N) {
        assert_int_equal(flt_flatness_push(f, N - taken, 2, s + taken, z + 2 * taken, NULL,
                                           &consumed, &evaluated),
                         FLT_OK);
        taken += consumed, windows += (size_t)evaluated, ++calls;
    }
    const double seconds = now_s() - t0;
    print_message("%d rows at 5e-324 mm updates: %zu push calls, %zu windows, %.3f s\n", N, calls,
                  windows, seconds);
    /* The 3000 mm window fills after 1000 rows; from then on every row
     * starts a window: 1000 windows (one per row past the first window's
     * end), a call each, and one more for the rows before. */
    assert_int_equal(taken, N);
    assert_int_equal(windows, N - 1000);
    assert_int_equal(calls, N - 1000 + 1);
    flt_flatness_destroy(f);
    flt_options_destroy(o);
}

/* ---------------------------------------------------------------------- */
/* Reconstructor                                                           */
/* ---------------------------------------------------------------------- */

/* A sine of 3 mm and 1885 mm period on a 5 mm level, seen by two lasers
 * 100 mm apart, with 1 mm of height noise and 1e-6 of slope noise, rows 1
 * to 5 mm apart. */
enum { ROWS = 2000, K = 8 };
static void noisy_sheet(double *s, double *h, double *g) {
    uint64_t state = 88172645463325252ull;
    double pos = 0;
    for (int r = 0; r < ROWS; ++r) {
        state ^= state << 13, state ^= state >> 7, state ^= state << 17;
        pos += 1.0 + 4.0 * (double)(state >> 11) / 9007199254740992.0;
        s[r] = pos;
        const double z0 = 5 + 3 * sin((pos - 50) / 300), z1 = 5 + 3 * sin((pos + 50) / 300);
        for (int k = 0; k < K; ++k) {
            /* Irwin-Hall: the sum of 12 uniforms minus 6 is about N(0, 1). */
            double n = -6;
            for (int i = 0; i < 12; ++i) {
                state ^= state << 13, state ^= state >> 7, state ^= state << 17;
                n += (double)(state >> 11) / 9007199254740992.0;
            }
            h[r * K + k] = 0.5 * (z0 + z1) + n;
            g[r * K + k] = (z1 - z0) / 100 + 1e-6 * n;
        }
    }
}

static void test_slope_sigma_at_its_minimum_gives_no_unflagged_nan(void **state) {
    (void)state;
    double *s = malloc(ROWS * sizeof(double)), *h = malloc(ROWS * K * sizeof(double));
    double *g = malloc(ROWS * K * sizeof(double));
    double *z = malloc(ROWS * K * sizeof(double)), *ref = malloc(ROWS * K * sizeof(double));
    uint8_t *flags = malloc(ROWS * K);
    noisy_sheet(s, h, g);
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    /* The reference: slopes weighed 1e8 times the heights (the most the
     * reconstructor carries; recon.h). */
    assert_int_equal(flt_options_set(o, FLT_OPT_SLOPE_SIGMA, 2.5e-6), FLT_OK);
    assert_int_equal(flt_reconstruct(o, ROWS, K, s, h, g, NULL, ref, NULL), FLT_OK);
    double min_slope_sigma = 0;
    assert_int_equal(flt_option_info(FLT_OPT_SLOPE_SIGMA, NULL, &min_slope_sigma, NULL, NULL, NULL),
                     FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_SLOPE_SIGMA, min_slope_sigma), FLT_OK);
    for (int rigid = 0; rigid <= 1; ++rigid) {
        assert_int_equal(flt_options_set(o, FLT_OPT_RIGID_MOTION, rigid), FLT_OK);
        assert_int_equal(flt_reconstruct(o, ROWS, K, s, h, g, NULL, z, flags), FLT_OK);
        double worst = 0;
        for (int i = 0; i < ROWS * K; ++i) {
            assert_true(isfinite(z[i])); /* every fiber has heights: no NaN at all */
            assert_int_equal(flags[i] & FLT_FLAG_NO_DATA, 0);
            worst = fmax(worst, fabs(z[i] - ref[i]));
        }
        print_message("slope_sigma = %g, rigid_motion = %d: batch within %.3g mm of the capped "
                      "weights\n",
                      min_slope_sigma, rigid, worst);
        /* Without rigid motion the two are the same least-squares problem
         * (the slope weight is capped at 1e8 heights): equal to rounding,
         * 1e-6 mm on a 5 mm level. With it the line channels' slope
         * weights (slope_sigma shrunk by the fibers) are capped at their
         * own ratio, a different weighting: 0.05 mm (the heights carry 1 mm
         * of noise). */
        assert_true(worst < (rigid ? 0.05 : 1e-6));

        /* Streaming, in blocks of 100 rows. */
        flt_recon *r = NULL;
        assert_int_equal(flt_recon_create(K, o, &r), FLT_OK);
        size_t pulled = 0;
        for (int r0 = 0; r0 < ROWS; r0 += 100) {
            assert_int_equal(flt_recon_push(r, 100, K, s + r0, h + r0 * K, g + r0 * K, NULL),
                             FLT_OK);
            if (r0 + 100 == ROWS)
                assert_int_equal(flt_recon_end_sheet(r), FLT_OK);
            size_t got = 0;
            assert_int_equal(flt_recon_pull(r, ROWS - pulled, K, s + pulled, z + pulled * K,
                                            flags + pulled * K, &got),
                             FLT_OK);
            pulled += got;
        }
        assert_int_equal(pulled, ROWS);
        for (int i = 0; i < ROWS * K; ++i)
            assert_true(isfinite(z[i]) && (flags[i] & FLT_FLAG_NO_DATA) == 0);
        flt_recon_destroy(r);
    }
    flt_options_destroy(o);
    free(s), free(h), free(g), free(z), free(ref), free(flags);
}

/* Knots without rows under strong or lopsided weights (found by the
 * contract suite): a curvature-jump prior 1e17 times the curvature prior,
 * slopes weighing 1e8 heights beside a curvature prior of 1e-12, and
 * rigid_motion's deviation channel, whose priors scale with (shape_sigma /
 * height_sigma)^2, each made every output NaN without a flag. Rows up to
 * 1000 knots apart, zeros and a few ones. */
static void test_knots_without_rows_under_extreme_weights_give_no_nan(void **state) {
    (void)state;
    static const struct {
        double laser, jump, curvature, slope_sigma, height_sigma;
        int rigid;
    } cases[] = {
        {1.0, 1e5, 1e-12, 1.0, 2.5, 0},   {100, 1e12, 1e-12, 1e-12, 2.5, 0},
        {0.001, 1e5, 1e-12, 1.0, 2.5, 0}, {0.001, 1e-11, 1e-12, 1e-3, 0.1, 0},
        {0.001, 10, 1e-3, 1e-3, 1e6, 1},  {0.001, 10, 1e-3, 1e-6, 1e5, 1},
        {100, 0, 1e-12, 1e3, 2.5, 0},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        flt_options *o = NULL;
        assert_int_equal(flt_options_create(&o), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_LASER_SPACING, cases[c].laser), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_CURVATURE_JUMP_WEIGHT, cases[c].jump), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_CURVATURE_WEIGHT, cases[c].curvature), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_SLOPE_SIGMA, cases[c].slope_sigma), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_HEIGHT_SIGMA, cases[c].height_sigma), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_RIGID_MOTION, cases[c].rigid), FLT_OK);
        for (int spread = 0; spread < 3; ++spread) {
            /* Rows 1, 10 or 1000 knots apart (knots = laser spacing). */
            const double gap = cases[c].laser * (spread == 0 ? 1 : spread == 1 ? 10 : 1000);
            const double s[5] = {0, gap, 2 * gap, 2 * gap + 0.5 * cases[c].laser, 3 * gap};
            double h[10] = {0, 0, 1, 1, 0, 0, 2, 2, 0, 0}, g[10] = {0}, z[10];
            uint8_t flags[10];
            assert_int_equal(flt_reconstruct(o, 5, 2, s, h, g, NULL, z, flags), FLT_OK);
            for (int i = 0; i < 10; ++i)
                if (!isfinite(z[i])) {
                    print_message("case %zu, rows %g mm apart: z[%d] = %g, flags %d\n", c, gap, i,
                                  z[i], flags[i]);
                    fail();
                }
        }
        flt_options_destroy(o);
    }
}

/* Heights of 1e8 mm (inside the documented 1e9) in robust Tukey mode with
 * rigid motion: half of the outputs were NaN without a flag; once the
 * weights were capped they came out about 0, and robust mode's level was
 * off by 2.6e-6 of the strip's height (0.3 mm at 1e5 mm): the ridge pulled
 * every knot height towards 0. The same noisy sheet lifted by 1e3, 1e5 and
 * 1e8 mm must come out lifted by as much, in every mode, batch and
 * streaming, with no NaN (every fiber has heights). */
static void reconstruct_both_ways(flt_options *o, const double *s, const double *h, const double *g,
                                  double *z, double *z_stream, uint8_t *flags) {
    assert_int_equal(flt_reconstruct(o, ROWS, K, s, h, g, NULL, z, flags), FLT_OK);
    for (int i = 0; i < ROWS * K; ++i)
        assert_true(isfinite(z[i]) && (flags[i] & FLT_FLAG_NO_DATA) == 0);
    flt_recon *r = NULL;
    assert_int_equal(flt_recon_create(K, o, &r), FLT_OK);
    double s_out[100];
    size_t pulled = 0;
    for (int r0 = 0; r0 < ROWS; r0 += 100) {
        assert_int_equal(flt_recon_push(r, 100, K, s + r0, h + r0 * K, g + r0 * K, NULL), FLT_OK);
        if (r0 + 100 == ROWS)
            assert_int_equal(flt_recon_end_sheet(r), FLT_OK);
        size_t got = 0;
        do {
            const size_t room = ROWS - pulled < 100 ? ROWS - pulled : 100;
            assert_int_equal(
                flt_recon_pull(r, room, K, s_out, z_stream + pulled * K, flags + pulled * K, &got),
                FLT_OK);
            pulled += got;
        } while (got > 0);
    }
    assert_int_equal(pulled, ROWS);
    for (int i = 0; i < ROWS * K; ++i)
        assert_true(isfinite(z_stream[i]) && (flags[i] & FLT_FLAG_NO_DATA) == 0);
    flt_recon_destroy(r);
}

static void test_huge_heights_come_out_as_lifted_in_every_mode(void **state) {
    (void)state;
    double *s = malloc(ROWS * sizeof(double)), *h = malloc(ROWS * K * sizeof(double));
    double *g = malloc(ROWS * K * sizeof(double)), *lifted = malloc(ROWS * K * sizeof(double));
    double *z0 = malloc(ROWS * K * sizeof(double)), *zs0 = malloc(ROWS * K * sizeof(double));
    double *z = malloc(ROWS * K * sizeof(double)), *zs = malloc(ROWS * K * sizeof(double));
    uint8_t *flags = malloc(ROWS * K);
    noisy_sheet(s, h, g);
    static const double lifts[] = {1e3, 1e5, 1e8};
    for (int robust = 0; robust <= 2; ++robust)
        for (int rigid = 0; rigid <= 1; ++rigid) {
            flt_options *o = NULL;
            assert_int_equal(flt_options_create(&o), FLT_OK);
            assert_int_equal(flt_options_set(o, FLT_OPT_ROBUST, robust), FLT_OK);
            assert_int_equal(flt_options_set(o, FLT_OPT_RIGID_MOTION, rigid), FLT_OK);
            reconstruct_both_ways(o, s, h, g, z0, zs0, flags);
            for (size_t l = 0; l < sizeof lifts / sizeof lifts[0]; ++l) {
                for (int i = 0; i < ROWS * K; ++i)
                    lifted[i] = h[i] + lifts[l];
                reconstruct_both_ways(o, s, lifted, g, z, zs, flags);
                double worst = 0;
                for (int i = 0; i < ROWS * K; ++i) {
                    worst = fmax(worst, fabs(z[i] - lifts[l] - z0[i]));
                    worst = fmax(worst, fabs(zs[i] - lifts[l] - zs0[i]));
                }
                print_message("robust %d, rigid %d, lifted %g mm: off by %.3g mm\n", robust, rigid,
                              lifts[l], worst);
                /* Lifting a height by L rounds it by up to L * 1.1e-16
                 * (7.5e-9 mm at 1e8), and the fit adds up such errors over
                 * its window: 1e-5 mm, a hundredth of a micrometre, is
                 * three orders above that and two below the old 2.6e-6 * L
                 * at 1e5 mm. */
                assert_true(worst < 1e-5);
            }
            flt_options_destroy(o);
        }
    free(s), free(h), free(g), free(lifted), free(z0), free(zs0), free(z), free(zs), free(flags);
}

/* Robust mode with a small row_capacity: rows waiting in the reweighting
 * stages' queues did not count against the capacity, so a push could take
 * more rows than the ring holds, and end_sheet wrote the last over the
 * first (a pulled row at s = 99 first, then 6, 9, ...; the contract
 * suite). */
static void test_robust_queues_count_against_the_row_capacity(void **state) {
    (void)state;
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_ROBUST, 2), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_ROBUST_ITERATIONS, 1), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_ROW_CAPACITY, 32), FLT_OK);
    flt_recon *r = NULL;
    assert_int_equal(flt_recon_create(1, o, &r), FLT_OK);
    double s[40], zero[40] = {0}, s_out[40], z[40];
    for (int i = 0; i < 40; ++i)
        s[i] = 3.0 * (i + 1);
    assert_int_equal(flt_recon_push(r, 3, 1, s, zero, zero, NULL), FLT_OK);
    assert_int_equal(flt_recon_push(r, 30, 1, s + 3, zero, zero, NULL), FLT_ERR_BUFFER_FULL);
    assert_int_equal(flt_recon_push(r, 29, 1, s + 3, zero, zero, NULL), FLT_OK);
    assert_int_equal(flt_recon_end_sheet(r), FLT_OK);
    size_t got = 0;
    assert_int_equal(flt_recon_pull(r, 40, 1, s_out, z, NULL, &got), FLT_OK);
    assert_int_equal(got, 32);
    for (int i = 0; i < 32; ++i)
        assert_true(s_out[i] == s[i]); /* every row, in order, once */
    flt_recon_destroy(r);
    flt_options_destroy(o);
}

/* Buffers of a size no sensor needs are refused before allocation. */
static void test_reconstructor_sizes_are_bounded(void **state) {
    (void)state;
    flt_recon *r = NULL;
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    const double rss0 = peak_rss_mb();
    /* 1e8 fibers (a calibration with that many used to load). */
    assert_int_equal(flt_recon_create(100000000, NULL, &r), FLT_ERR_INVALID_ARGUMENT);
    /* row_capacity and lag_knots at their bounds with 1000 fibers: 900 GB
     * of row ring, then 110 GB of knot rings. */
    assert_int_equal(flt_options_set(o, FLT_OPT_ROW_CAPACITY, 1e8), FLT_OK);
    assert_int_equal(flt_recon_create(1000, o, &r), FLT_ERR_INVALID_ARGUMENT);
    print_message("%s\n", flt_last_error_message());
    assert_non_null(strstr(flt_last_error_message(), "row_capacity = 100000000"));
    assert_int_equal(flt_options_set(o, FLT_OPT_ROW_CAPACITY, 8192), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_LAG_KNOTS, 100000), FLT_OK);
    assert_int_equal(flt_recon_create(1000, o, &r), FLT_ERR_INVALID_ARGUMENT);
    assert_null(r);
    /* A batch whose rows lie 1000 knots apart: 24 GB of knots for 2000
     * rows of 100 fibers (1.6 MB of input). */
    double *s = malloc(2000 * sizeof(double)), *hg = calloc(2000 * 100, sizeof(double));
    double *z = malloc(2000 * 100 * sizeof(double));
    for (int i = 0; i < 2000; ++i)
        s[i] = 1e5 * i;
    assert_int_equal(flt_reconstruct(NULL, 2000, 100, s, hg, hg, NULL, z, NULL),
                     FLT_ERR_INVALID_ARGUMENT);
    print_message("%s\n", flt_last_error_message());
    assert_non_null(strstr(flt_last_error_message(), "knots"));
    /* Nothing of that was allocated: 64 MB covers the test's own arrays
     * (4.8 MB) and allocator slack. */
    assert_true(peak_rss_mb() - rss0 < 64.0);
    /* A real sensor's configuration is well inside: robust mode with rigid
     * motion at the defaults takes 0.16 GB per 1000 fibers (4000 would be
     * 0.6 GB of the 2.1 allowed). */
    assert_int_equal(flt_options_set(o, FLT_OPT_LAG_KNOTS, 64), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_ROBUST, 1), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_RIGID_MOTION, 1), FLT_OK);
    assert_int_equal(flt_recon_create(1000, o, &r), FLT_OK);
    flt_recon_destroy(r);
    flt_options_destroy(o);
    free(s), free(hg), free(z);
}

/* ---------------------------------------------------------------------- */
/* Simulator                                                               */
/* ---------------------------------------------------------------------- */

static void test_tiny_full_well_gives_clipped_pixels(void **state) {
    (void)state;
    for (int bits = 8; bits <= 16; bits += 8) {
        flt_options *o = NULL;
        assert_int_equal(flt_options_create(&o), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_SIM_FULL_WELL, 1e-30), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_SIM_BIT_DEPTH, bits), FLT_OK);
        flt_calib *calib = NULL; /* a 256-row window keeps the frame small */
        assert_int_equal(flt_calib_create_reference(900, 256, -1000, 2, 1001, &calib), FLT_OK);
        flt_sim *sim = NULL;
        assert_int_equal(flt_sim_create(calib, o, &sim), FLT_OK);
        const size_t bytes = bits / 8, pixels = 2048 * 256;
        void *frame = malloc(pixels * bytes);
        assert_int_equal(
            flt_sim_next_frame(sim, frame, pixels * bytes, 2048 * bytes, NULL, 0, NULL, NULL, 0),
            FLT_OK);
        const unsigned top = (1u << bits) - 1;
        size_t high = 0, between = 0;
        for (size_t i = 0; i < pixels; ++i) {
            const unsigned p = bits == 8 ? ((uint8_t *)frame)[i] : ((uint16_t *)frame)[i];
            high += p == top;
            between += p != 0 && p != top;
        }
        print_message("%d bits, full well 1e-30: %.4f at full scale, %zu pixels between\n", bits,
                      (double)high / (double)pixels, between);
        /* The shot noise of every pixel (at least the 3 % background) is
         * beyond full scale: it clips to 0 or full scale with odds 1:1 (the
         * noise is symmetric). 0.5 +- 0.01 is 14 sigma of 524,288 draws. A
         * pixel stays between only when its draw is exactly 0, about 1e-5
         * of them: at most 1e-3. */
        assert_true(fabs((double)high / (double)pixels - 0.5) < 0.01);
        assert_true((double)between / (double)pixels < 1e-3);
        free(frame);
        flt_sim_destroy(sim);
        flt_calib_destroy(calib);
        flt_options_destroy(o);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_absurd_calibration_values_are_refused_naming_the_field),
        cmocka_unit_test(test_calibration_at_the_ends_of_its_ranges_runs_the_chain),
        cmocka_unit_test(test_columns_mapped_far_off_the_grid_are_skipped),
        cmocka_unit_test(test_oversized_calibration_text_is_refused_before_parsing),
        cmocka_unit_test(test_flatness_zone_count_is_bounded),
        cmocka_unit_test(test_flatness_stream_crosses_a_gap_in_few_calls),
        cmocka_unit_test(test_flatness_stream_with_a_denormal_update_interval_ends),
        cmocka_unit_test(test_slope_sigma_at_its_minimum_gives_no_unflagged_nan),
        cmocka_unit_test(test_knots_without_rows_under_extreme_weights_give_no_nan),
        cmocka_unit_test(test_huge_heights_come_out_as_lifted_in_every_mode),
        cmocka_unit_test(test_robust_queues_count_against_the_row_capacity),
        cmocka_unit_test(test_reconstructor_sizes_are_bounded),
        cmocka_unit_test(test_tiny_full_well_gives_clipped_pixels),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
