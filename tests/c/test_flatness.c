// SPDX-License-Identifier: Apache-2.0
/*
 * Flatness metrics: I-Units, waves and steepness against analytic sines,
 * reference choice, zones, invalid rows, streaming windows against
 * whole-sheet evaluation, and bad input.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "flatline/flatline.h"

#define PI 3.14159265358979323846
#define DS 3.0 /* mm between rows, as the sensor's frames */

#define assert_near(a, b, tol)                                                 \
  do {                                                                         \
    const double a_ = (a), b_ = (b);                                           \
    if (!(fabs(a_ - b_) <= (tol)))                                             \
      fail_msg("%s = %.17g, expected %.17g +- %g", #a, a_, b_, (double)(tol)); \
  } while (0)

#define assert_message_has(text)                                                     \
  do {                                                                               \
    if (!strstr(flt_last_error_message(), (text)))                                   \
      fail_msg("message '%s' does not name '%s'", flt_last_error_message(), (text)); \
  } while (0)

/* Arc length of z = (H/2) sin(2 pi s / P) over [0, L], composite Simpson
 * with 2e5 intervals: the integrand is smooth and periodic, so this is
 * exact to far below 1e-12 relative. */
static double sine_arc_length(double H, double P, double L) {
    const int n = 200000;
    const double h = L / n, a = PI * H / P, k = 2 * PI / P;
    double sum = 0;
    for (int i = 0; i <= n; ++i) {
        const double d = a * cos(k * i * h);
        const double f = sqrt(1 + d * d);
        sum += (i == 0 || i == n) ? f : (i % 2 ? 4 * f : 2 * f);
    }
    return sum * h / 3;
}

static flt_options *options_with(int n, const flt_option *keys, const double *values) {
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    for (int i = 0; i < n; ++i)
        assert_int_equal(flt_options_set(o, keys[i], values[i]), FLT_OK);
    return o;
}

/* Rows 0..rows-1 at s = r * DS; fiber 0 flat at 7 mm, fiber 1 a sine of
 * height H and period P on the same level plus `tilt` mm/mm, fiber 2 the
 * sine at half height. */
static void sine_rows(size_t rows, double H, double P, double tilt, double *s, double *z) {
    for (size_t r = 0; r < rows; ++r) {
        s[r] = (double)r * DS;
        const double w = sin(2 * PI * s[r] / P);
        z[r * 3 + 0] = 7.0;
        z[r * 3 + 1] = 7.0 + 0.5 * H * w + tilt * s[r];
        z[r * 3 + 2] = 7.0 + 0.25 * H * w;
    }
}

/* I-Units within 1% of the exact arc-length value, wave height, period and
 * steepness within 1%, for gentle to steep sines (0.2% to 5% steepness). */
static void sine_i_units_and_steepness(void **state) {
    (void)state;
    const double cases[][2] = {{10, 1000}, {4, 2000}, {20, 500}, {30, 600}, {2, 1000}};
    const double x[3] = {-100, 0, 100};
    flt_flatness *f = NULL;
    assert_int_equal(flt_flatness_create(3, x, NULL, &f), FLT_OK);
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        const double H = cases[c][0], P = cases[c][1];
        const size_t rows = (size_t)(3 * P / DS) + 1; /* three whole periods */
        double *s = malloc(rows * sizeof *s), *z = malloc(rows * 3 * sizeof *z);
        sine_rows(rows, H, P, 0.0, s, z);
        assert_int_equal(flt_flatness_evaluate(f, rows, 3, s, z, NULL), FLT_OK);
        double arc[3], iu[3], wh[3], wp[3], st[3];
        uint8_t fl[3];
        assert_int_equal(flt_flatness_fiber_results(f, 3, arc, iu, wh, wp, st, fl), FLT_OK);
        const double L = s[rows - 1];
        const double exact = (sine_arc_length(H, P, L) - L) / L * 1e5;
        const double exact_half = (sine_arc_length(H / 2, P, L) - L) / L * 1e5;
        print_message("H %4.0f P %4.0f: I = %9.4f (exact %9.4f, 2.467 (H/P)^2 1e5 = %9.4f), "
                      "wave %.4f mm / %.2f mm, steepness %.4f%%\n",
                      H, P, iu[1], exact, 2.467 * (H / P) * (H / P) * 1e5, wh[1], wp[1], st[1]);
        /* The flat fiber is the shortest: the reference, 0 I-Units exactly. */
        assert_near(iu[0], 0.0, 0.0);
        assert_near(iu[1], exact, 0.01 * exact);
        assert_near(iu[2], exact_half, 0.01 * exact_half);
        assert_near(arc[1], sine_arc_length(H, P, L), 1e-6 * L);
        assert_near(wh[1], H, 0.01 * H);
        assert_near(wp[1], P, 0.01 * P);
        assert_near(st[1], 100 * H / P, 0.01 * 100 * H / P);
        assert_int_equal(fl[1], 0);
        /* The flat fiber has no wave, and says so. */
        assert_int_equal(fl[0], FLT_FIBER_NO_WAVE);
        assert_true(isnan(wh[0]));
        free(s);
        free(z);
    }
    flt_flatness_destroy(f);
}

/* A level and a slight tilt of the fiber (1 mm/m, a pass line change)
 * do not change the wave: the crest-trough-crest height cancels a trend to
 * first order (the residual is (tilt / (pi H / P))^2 / 2 = 5e-4 here). */
static void wave_ignores_level_and_tilt(void **state) {
    (void)state;
    const double x[3] = {-100, 0, 100}, H = 10, P = 1000;
    const size_t rows = 1001;
    double *s = malloc(rows * sizeof *s), *z = malloc(rows * 3 * sizeof *z);
    sine_rows(rows, H, P, 1e-3, s, z);
    flt_flatness *f = NULL;
    assert_int_equal(flt_flatness_create(3, x, NULL, &f), FLT_OK);
    assert_int_equal(flt_flatness_evaluate(f, rows, 3, s, z, NULL), FLT_OK);
    double wh[3], wp[3];
    assert_int_equal(flt_flatness_fiber_results(f, 3, NULL, NULL, wh, wp, NULL, NULL), FLT_OK);
    print_message("tilted sine: wave %.4f mm / %.2f mm\n", wh[1], wp[1]);
    assert_near(wh[1], H, 0.01 * H);
    assert_near(wp[1], P, 0.01 * P);
    flt_flatness_destroy(f);
    free(s);
    free(z);
}

/* Reference = mean of the fibers: with stretches e (flat 0, sine e1, half
 * sine e2) the sine fiber's I-Units are (e1 - m) / (1 + m) 1e5, m the mean. */
static void mean_reference(void **state) {
    (void)state;
    const double x[3] = {-100, 0, 100}, H = 10, P = 1000;
    const size_t rows = 1001;
    double *s = malloc(rows * sizeof *s), *z = malloc(rows * 3 * sizeof *z);
    sine_rows(rows, H, P, 0.0, s, z);
    const flt_option key = FLT_OPT_FLAT_REFERENCE;
    const double one = 1;
    flt_options *o = options_with(1, &key, &one);
    flt_flatness *f = NULL;
    assert_int_equal(flt_flatness_create(3, x, o, &f), FLT_OK);
    flt_options_destroy(o);
    assert_int_equal(flt_flatness_evaluate(f, rows, 3, s, z, NULL), FLT_OK);
    double iu[3];
    assert_int_equal(flt_flatness_fiber_results(f, 3, NULL, iu, NULL, NULL, NULL, NULL), FLT_OK);
    const double L = s[rows - 1];
    const double e1 = sine_arc_length(H, P, L) / L - 1, e2 = sine_arc_length(H / 2, P, L) / L - 1;
    const double m = (e1 + e2) / 3;
    print_message("mean reference: I = %.4f %.4f %.4f\n", iu[0], iu[1], iu[2]);
    assert_near(iu[1], (e1 - m) / (1 + m) * 1e5, 0.01 * fabs((e1 - m) * 1e5));
    assert_near(iu[0], -m / (1 + m) * 1e5, 0.01 * fabs(m * 1e5));
    /* The I-Units about the mean sum to zero (to first order in e). */
    assert_near(iu[0] + iu[1] + iu[2], 0.0, 1e-3);
    flt_flatness_destroy(f);
    free(s);
    free(z);
}

/* Zones: 20 fibers every 10 mm across 200 mm, 50 mm zones: 4 zones of 5
 * fibers, each zone the mean of its fibers. Fiber k carries a sine whose
 * I-Units grow with k. */
static void zones_average_their_fibers(void **state) {
    (void)state;
    enum { N = 20 };
    double x[N];
    for (int k = 0; k < N; ++k)
        x[k] = -95.0 + 10.0 * k;
    flt_flatness *f = NULL;
    assert_int_equal(flt_flatness_create(N, x, NULL, &f), FLT_OK);
    size_t zones = 0;
    assert_int_equal(flt_flatness_zones(f, &zones), FLT_OK);
    assert_int_equal(zones, 4);
    double left[4], centre[4];
    size_t count[4];
    assert_int_equal(flt_flatness_zone_layout(f, 4, left, centre, count), FLT_OK);
    for (int j = 0; j < 4; ++j) {
        assert_near(left[j], -100.0 + 50.0 * j, 1e-9);
        assert_near(centre[j], -75.0 + 50.0 * j, 1e-9);
        assert_int_equal(count[j], 5);
    }
    const size_t rows = 1001;
    double *s = malloc(rows * sizeof *s), *z = malloc(rows * N * sizeof *z);
    for (size_t r = 0; r < rows; ++r) {
        s[r] = DS * (double)r;
        for (int k = 0; k < N; ++k)
            z[r * N + k] = 0.5 * k * sin(2 * PI * s[r] / 1000);
    }
    assert_int_equal(flt_flatness_evaluate(f, rows, N, s, z, NULL), FLT_OK);
    double iu[N], ziu[4];
    uint8_t zfl[4];
    assert_int_equal(flt_flatness_fiber_results(f, N, NULL, iu, NULL, NULL, NULL, NULL), FLT_OK);
    assert_int_equal(flt_flatness_zone_results(f, 4, ziu, zfl), FLT_OK);
    for (int j = 0; j < 4; ++j) {
        double mean = 0;
        for (int k = 5 * j; k < 5 * j + 5; ++k)
            mean += iu[k] / 5;
        assert_near(ziu[j], mean, 1e-9 * fabs(mean) + 1e-12);
        assert_int_equal(zfl[j], 0);
    }
    /* Fiber 19: H = 19 mm over 1000 mm, 2.467 (0.019)^2 1e5 = 89 I-Units. */
    assert_near(iu[N - 1], 89.06, 0.01 * 89.06);
    flt_flatness_destroy(f);
    free(s);
    free(z);
}

/* Rows flagged FLT_FLAG_GAP or FLT_FLAG_NO_DATA (and NaN heights) are left
 * out: a sine fiber with 10% of its rows flagged keeps its I-Units within
 * 1% (the excess per covered mm is the same; the gap sits on whole periods),
 * is flagged PARTIAL, and a fiber with 30% flagged (coverage 0.7 < 0.8)
 * becomes NO_DATA with NaN values, taking no part in the reference. */
static void flagged_rows_are_excluded(void **state) {
    (void)state;
    enum { N = 4 };
    const double x[N] = {0, 10, 20, 30}, H = 10, P = 600;
    const size_t rows = 2001; /* 6000 mm, 10 periods */
    double *s = malloc(rows * sizeof *s), *z = malloc(rows * N * sizeof *z);
    uint8_t *flags = calloc(rows * N, 1);
    for (size_t r = 0; r < rows; ++r) {
        s[r] = DS * (double)r;
        const double w = 0.5 * H * sin(2 * PI * s[r] / P);
        z[r * N + 0] = 0;
        z[r * N + 1] = w;
        z[r * N + 2] = w;
        z[r * N + 3] = w;
        /* fiber 2: one whole period (600 mm, 10%) flagged GAP */
        if (s[r] > 1200 && s[r] < 1800)
            flags[r * N + 2] = FLT_FLAG_GAP;
        /* fiber 3: 1800 mm (30%) without data */
        if (s[r] > 3000 && s[r] < 4800) {
            flags[r * N + 3] = FLT_FLAG_NO_DATA;
            z[r * N + 3] = NAN;
        }
        /* fiber 0: bridged samples are usable */
        if (r % 7 == 0)
            flags[r * N + 0] = FLT_FLAG_INVALID_INPUT;
    }
    flt_flatness *f = NULL;
    assert_int_equal(flt_flatness_create(N, x, NULL, &f), FLT_OK);
    assert_int_equal(flt_flatness_evaluate(f, rows, N, s, z, flags), FLT_OK);
    double iu[N], arc[N], wh[N];
    uint8_t fl[N];
    assert_int_equal(flt_flatness_fiber_results(f, N, arc, iu, wh, NULL, NULL, fl), FLT_OK);
    print_message("flagged: I = %.4f %.4f %.4f %.4f, flags %d %d %d %d\n", iu[0], iu[1], iu[2],
                  iu[3], fl[0], fl[1], fl[2], fl[3]);
    assert_int_equal(fl[0], FLT_FIBER_NO_WAVE);
    assert_int_equal(fl[1], 0);
    assert_int_equal(fl[2], FLT_FIBER_PARTIAL);
    assert_int_equal(fl[3], FLT_FIBER_NO_DATA | FLT_FIBER_NO_WAVE);
    assert_near(iu[2], iu[1], 0.01 * iu[1]);
    assert_near(wh[2], H, 0.01 * H);
    assert_true(isnan(iu[3]) && isnan(arc[3]) && isnan(wh[3]));
    assert_near(iu[0], 0.0, 0.0);
    flt_flatness_destroy(f);
    free(s);
    free(z);
    free(flags);
}

/* Streaming: the same rows pushed in blocks of 1, 7 and 1000 give the same
 * windows, each equal (to rounding) to flt_flatness_evaluate over the rows
 * of that window: [s0 + j * interval, s0 + j * interval + length). */
static void streaming_windows_match_whole_sheet_rows(void **state) {
    (void)state;
    enum { N = 3 };
    const double x[N] = {-100, 0, 100};
    const size_t rows = 3000; /* 9000 mm */
    double *s = malloc(rows * sizeof *s), *z = malloc(rows * N * sizeof *z);
    for (size_t r = 0; r < rows; ++r) {
        s[r] = 1000.0 + DS * (double)r + 0.4 * sin(0.37 * (double)r); /* uneven rows */
        for (int k = 0; k < N; ++k)
            z[r * N + k] = (k + 1) * 2.0 * sin(2 * PI * s[r] / (800.0 + 300 * k));
    }
    const flt_option keys[2] = {FLT_OPT_FLAT_WINDOW_LENGTH, FLT_OPT_FLAT_UPDATE_INTERVAL};
    const double values[2] = {2000, 700};
    flt_options *o = options_with(2, keys, values);
    flt_flatness *whole = NULL;
    assert_int_equal(flt_flatness_create(N, x, o, &whole), FLT_OK);
    const size_t blocks[3] = {1, 7, 1000};
    size_t windows_seen[3] = {0, 0, 0};
    for (int b = 0; b < 3; ++b) {
        flt_flatness *f = NULL;
        assert_int_equal(flt_flatness_create(N, x, o, &f), FLT_OK);
        size_t next = 0;
        while (next < rows) {
            const size_t n = rows - next < blocks[b] ? rows - next : blocks[b];
            size_t used = 0;
            int evaluated = 0;
            assert_int_equal(
                flt_flatness_push(f, n, N, s + next, z + next * N, NULL, &used, &evaluated),
                FLT_OK);
            next += used;
            if (!evaluated)
                continue;
            ++windows_seen[b];
            double first, last, iu[N];
            size_t wrows, index;
            unsigned wflags;
            assert_int_equal(flt_flatness_window(f, &first, &last, &wrows, &wflags, &index),
                             FLT_OK);
            assert_int_equal(index, windows_seen[b]);
            assert_int_equal(wflags, 0);
            const double start = s[0] + 700.0 * (double)(index - 1);
            assert_true(first >= start && first < start + 4.0);
            assert_true(last < start + 2000.0 && last > start + 2000.0 - 4.0);
            assert_int_equal(flt_flatness_fiber_results(f, N, NULL, iu, NULL, NULL, NULL, NULL),
                             FLT_OK);
            size_t r0 = 0;
            while (s[r0] < first)
                ++r0;
            assert_int_equal(flt_flatness_evaluate(whole, wrows, N, s + r0, z + r0 * N, NULL),
                             FLT_OK);
            double iu_whole[N];
            assert_int_equal(
                flt_flatness_fiber_results(whole, N, NULL, iu_whole, NULL, NULL, NULL, NULL),
                FLT_OK);
            for (int k = 0; k < N; ++k)
                assert_near(iu[k], iu_whole[k], 1e-9 * fabs(iu_whole[k]));
        }
        /* Windows end at s0 + 2000 + 700 j <= s0 + 8997: j = 0..9, 10 windows. */
        assert_int_equal(windows_seen[b], 10);
        int evaluated = 0;
        assert_int_equal(flt_flatness_finish(f, &evaluated), FLT_OK);
        assert_int_equal(evaluated, 1);
        flt_flatness_destroy(f);
    }
    flt_options_destroy(o);
    flt_flatness_destroy(whole);
    free(s);
    free(z);
}

/* Bad input: a clear status, a message naming the argument, and the handle
 * (with its previous results) still usable. */
static void bad_input(void **state) {
    (void)state;
    enum { N = 3 };
    const double x[N] = {-100, 0, 100};
    flt_flatness *f = NULL;
    assert_int_equal(flt_flatness_create(N, NULL, NULL, &f), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("fiber_x");
    assert_null(f);
    assert_int_equal(flt_flatness_create(0, x, NULL, &f), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("fibers");
    assert_int_equal(flt_flatness_create(N, x, NULL, NULL), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("out");
    const double bad_x[N] = {0, NAN, 2};
    assert_int_equal(flt_flatness_create(N, bad_x, NULL, &f), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("fiber_x[1]");
    const double unsorted_x[N] = {0, 2, 1};
    assert_int_equal(flt_flatness_create(N, unsorted_x, NULL, &f), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("fiber_x[2]");
    {
        const flt_option keys[2] = {FLT_OPT_FLAT_WINDOW_LENGTH, FLT_OPT_FLAT_UPDATE_INTERVAL};
        const double values[2] = {1000, 2000};
        flt_options *o = options_with(2, keys, values);
        assert_int_equal(flt_flatness_create(N, x, o, &f), FLT_ERR_INVALID_ARGUMENT);
        assert_message_has("flat_update_interval");
        flt_options_destroy(o);
    }
    flt_flatness_destroy(NULL);

    assert_int_equal(flt_flatness_create(N, x, NULL, &f), FLT_OK);
    double iu[N];
    assert_int_equal(flt_flatness_fiber_results(f, N, NULL, iu, NULL, NULL, NULL, NULL),
                     FLT_ERR_STATE);
    assert_int_equal(flt_flatness_shape(f, NULL, NULL, NULL, NULL, NULL), FLT_ERR_STATE);

    const size_t rows = 1001;
    double *s = malloc(rows * sizeof *s), *z = malloc(rows * N * sizeof *z);
    sine_rows(rows, 10, 1000, 0, s, z);
    assert_int_equal(flt_flatness_evaluate(f, rows, N, s, z, NULL), FLT_OK);
    double good[N];
    assert_int_equal(flt_flatness_fiber_results(f, N, NULL, good, NULL, NULL, NULL, NULL), FLT_OK);

    assert_int_equal(flt_flatness_evaluate(NULL, rows, N, s, z, NULL), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("flatness");
    assert_int_equal(flt_flatness_evaluate(f, rows, N, NULL, z, NULL), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("'s'");
    assert_int_equal(flt_flatness_evaluate(f, rows, N, s, NULL, NULL), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("'z'");
    assert_int_equal(flt_flatness_evaluate(f, 0, N, s, z, NULL), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("rows");
    assert_int_equal(flt_flatness_evaluate(f, 1, N, s, z, NULL), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("rows");
    assert_int_equal(flt_flatness_evaluate(f, rows, 0, s, z, NULL), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("fibers");
    assert_int_equal(flt_flatness_evaluate(f, rows, N + 1, s, z, NULL), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("fibers");
    /* A NaN position, and positions that do not increase. */
    const double keep = s[10];
    s[10] = NAN;
    assert_int_equal(flt_flatness_evaluate(f, rows, N, s, z, NULL), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("s[10]");
    s[10] = s[9];
    assert_int_equal(flt_flatness_evaluate(f, rows, N, s, z, NULL), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("s[10]");
    s[10] = keep;
    /* Shorter than one wave: 100 rows span 297 mm < flat_min_length 500. */
    assert_int_equal(flt_flatness_evaluate(f, 100, N, s, z, NULL), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("flat_min_length");
    assert_message_has("'s'");
    /* All fibers invalid: NaN heights, then every row flagged NO_DATA. */
    double *z_nan = malloc(rows * N * sizeof *z_nan);
    for (size_t i = 0; i < rows * N; ++i)
        z_nan[i] = NAN;
    assert_int_equal(flt_flatness_evaluate(f, rows, N, s, z_nan, NULL), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("'z'");
    uint8_t *no_data = malloc(rows * N);
    memset(no_data, FLT_FLAG_NO_DATA, rows * N);
    assert_int_equal(flt_flatness_evaluate(f, rows, N, s, z, no_data), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("flat_min_coverage");

    /* The previous results survived every failure, and the handle works. */
    double after[N];
    assert_int_equal(flt_flatness_fiber_results(f, N, NULL, after, NULL, NULL, NULL, NULL), FLT_OK);
    for (int k = 0; k < N; ++k)
        assert_near(after[k], good[k], 0.0);
    assert_int_equal(flt_flatness_fiber_results(f, N + 1, NULL, after, NULL, NULL, NULL, NULL),
                     FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("fibers");
    assert_int_equal(flt_flatness_zone_results(f, 99, NULL, NULL), FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("zones");

    /* Streaming bad input takes no row; streamed bad material is flagged,
     * not an error: a window of NaN heights reports NO_VALID_FIBER. */
    size_t used = 99;
    int evaluated = 7;
    assert_int_equal(flt_flatness_push(f, rows, N, s, z, NULL, NULL, &evaluated),
                     FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("consumed_out");
    s[10] = NAN;
    assert_int_equal(flt_flatness_push(f, rows, N, s, z, NULL, &used, &evaluated),
                     FLT_ERR_INVALID_ARGUMENT);
    assert_message_has("s[10]");
    assert_int_equal(used, 0);
    assert_int_equal(evaluated, 0);
    s[10] = keep;
    /* rows - 1 rows span 2997 mm, inside the default 3000 mm window. */
    assert_int_equal(flt_flatness_push(f, rows - 1, N, s, z_nan, NULL, &used, &evaluated), FLT_OK);
    assert_int_equal(used, rows - 1);
    assert_int_equal(evaluated, 0);
    assert_int_equal(flt_flatness_finish(f, &evaluated), FLT_OK);
    assert_int_equal(evaluated, 1);
    unsigned wflags = 0;
    assert_int_equal(flt_flatness_window(f, NULL, NULL, NULL, &wflags, NULL), FLT_OK);
    assert_int_equal(wflags,
                     FLT_WINDOW_NO_VALID_FIBER | FLT_WINDOW_NO_BOW | FLT_WINDOW_NO_CROSSBOW);
    flt_shape shape = FLT_SHAPE_FLAT;
    double bow = 0;
    assert_int_equal(flt_flatness_shape(f, &shape, NULL, NULL, &bow, NULL), FLT_OK);
    assert_int_equal(shape, FLT_SHAPE_UNDETERMINED);
    assert_true(isnan(bow));
    /* A short streamed sheet is evaluated, flagged SHORT, with no wave. */
    assert_int_equal(flt_flatness_push(f, 100, N, s, z, NULL, &used, &evaluated), FLT_OK);
    assert_int_equal(flt_flatness_finish(f, &evaluated), FLT_OK);
    assert_int_equal(evaluated, 1);
    uint8_t fl[N];
    assert_int_equal(flt_flatness_window(f, NULL, NULL, NULL, &wflags, NULL), FLT_OK);
    assert_int_equal(wflags, FLT_WINDOW_SHORT);
    assert_int_equal(flt_flatness_fiber_results(f, N, NULL, iu, NULL, NULL, NULL, fl), FLT_OK);
    assert_int_equal(fl[1], FLT_FIBER_NO_WAVE);
    assert_true(isfinite(iu[1]) && iu[1] > 0);
    /* finish with nothing pending evaluates nothing. */
    assert_int_equal(flt_flatness_finish(f, &evaluated), FLT_OK);
    assert_int_equal(evaluated, 0);
    /* And the handle still evaluates a good sheet to the same numbers. */
    assert_int_equal(flt_flatness_evaluate(f, rows, N, s, z, NULL), FLT_OK);
    assert_int_equal(flt_flatness_fiber_results(f, N, NULL, after, NULL, NULL, NULL, NULL), FLT_OK);
    for (int k = 0; k < N; ++k)
        assert_near(after[k], good[k], 0.0);

    /* Buffer full: a window longer than flat_row_capacity rows. */
    {
        const flt_option keys[2] = {FLT_OPT_FLAT_ROW_CAPACITY, FLT_OPT_FLAT_WINDOW_LENGTH};
        const double values[2] = {100, 0};
        flt_options *o = options_with(2, keys, values);
        flt_flatness *small = NULL;
        assert_int_equal(flt_flatness_create(N, x, o, &small), FLT_OK);
        flt_options_destroy(o);
        assert_int_equal(flt_flatness_push(small, 150, N, s, z, NULL, &used, &evaluated),
                         FLT_ERR_BUFFER_FULL);
        assert_message_has("flat_row_capacity");
        assert_int_equal(used, 100);
        flt_flatness_destroy(small);
    }
    assert_string_equal(flt_shape_string(FLT_SHAPE_CENTRE_BUCKLE), "centre buckle");
    assert_string_equal(flt_shape_string((flt_shape)1234), "unknown");
    free(no_data);
    free(z_nan);
    free(s);
    free(z);
    flt_flatness_destroy(f);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(sine_i_units_and_steepness),
        cmocka_unit_test(wave_ignores_level_and_tilt),
        cmocka_unit_test(mean_reference),
        cmocka_unit_test(zones_average_their_fibers),
        cmocka_unit_test(flagged_rows_are_excluded),
        cmocka_unit_test(streaming_windows_match_whole_sheet_rows),
        cmocka_unit_test(bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
