// SPDX-License-Identifier: Apache-2.0
/* The streaming Hermite reconstructor against ground truth.
 *
 * The reference sheet (tests/c/sheet.h): 12 mm centre buckle + wavy edges,
 * periods 1800 mm along and 1500 mm across, 9000 mm long at dx = 3 mm,
 * measured by two lasers Delta-d = 100 mm apart. Fibers every 10 mm across
 * 1500 mm (151) keep the suite fast; fibers are solved independently, so the
 * pitch does not change any per-fiber number. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include <flatline/flatline.h>

#include "sheet.h"

#define REF_ROWS   3000 /* 9000 mm at 3 mm */
#define REF_DX     3.0
#define REF_PITCH  10.0
#define REF_FIBERS 151
#define LASER      100.0
/* 1/16 px of peak-detection noise at about 0.8 mm/px of height resolution
 * (2048 px over the reference field of view at 45 degrees). */
#define PEAK_SIGMA 0.05
#define VIB_SIGMA  2.5

static double *alloc_rows(size_t rows, size_t fibers) {
    double *p = malloc(rows * fibers * sizeof(double));
    assert_non_null(p);
    return p;
}

static flt_recon *make_recon(size_t fibers, flt_options *opts) {
    flt_recon *rc = NULL;
    assert_int_equal(flt_recon_create(fibers, opts, &rc), FLT_OK);
    assert_non_null(rc);
    return rc;
}

/* Pushes rows [r0, r1) one at a time, pulling as rows finish, into z/flags
 * at their row index (positions are checked to come back in order). Returns
 * the number of rows pulled. */
static size_t stream_rows(flt_recon *rc, const test_sheet *t, size_t r0, size_t r1,
                          const uint8_t *valid, double *z, uint8_t *flags, size_t *pulled) {
    size_t K = t->fibers, n = 0;
    double s_out[512];
    for (size_t r = r0; r < r1; ++r) {
        flt_status st = flt_recon_push(rc, 1, K, &t->s[r], t->height + r * K, t->slope + r * K,
                                       valid ? valid + r * K : NULL);
        if (st != FLT_OK)
            fail_msg("push of row %zu: %s", r, flt_last_error_message());
        do {
            assert_int_equal(flt_recon_pull(rc, 512, K, s_out, z + *pulled * K,
                                            flags ? flags + *pulled * K : NULL, &n),
                             FLT_OK);
            for (size_t i = 0; i < n; ++i)
                assert_true(s_out[i] == t->s[*pulled + i]);
            *pulled += n;
        } while (n == 512);
    }
    return *pulled;
}

static void finish_sheet(flt_recon *rc, const test_sheet *t, double *z, uint8_t *flags,
                         size_t *pulled) {
    size_t n = 0, K = t->fibers;
    assert_int_equal(flt_recon_end_sheet(rc), FLT_OK);
    double *s_out = malloc(t->rows * sizeof(double));
    assert_int_equal(flt_recon_pull(rc, t->rows, K, s_out, z + *pulled * K,
                                    flags ? flags + *pulled * K : NULL, &n),
                     FLT_OK);
    for (size_t i = 0; i < n; ++i)
        assert_true(s_out[i] == t->s[*pulled + i]);
    *pulled += n;
    free(s_out);
}

static double max_abs_diff(const double *a, const double *b, size_t n) {
    double m = 0;
    for (size_t i = 0; i < n; ++i)
        m = fmax(m, fabs(a[i] - b[i]));
    return m;
}

/* ---- accuracy on the noise-free reference sheet ------------------------ */

static void noise_free_reference_sheet_within_1um(void **state) {
    (void)state;
    test_sheet *t = test_sheet_make(REF_ROWS, REF_FIBERS, 0.0, REF_DX, 0.0, REF_PITCH, LASER, 1);
    double *z = alloc_rows(t->rows, t->fibers);
    uint8_t *flags = malloc(t->rows * t->fibers);
    assert_int_equal(
        flt_reconstruct(NULL, t->rows, t->fibers, t->s, t->height, t->slope, NULL, z, flags),
        FLT_OK);
    double mx, rms;
    test_error(t, z, 0, t->rows, &mx, &rms);
    print_message("batch, noise-free reference sheet: max %.3g um, rms %.3g um\n", mx * 1e3,
                  rms * 1e3);
    /* Goal: <= 1 um (the reference reached 0.64 um with ideal point data). */
    assert_true(mx <= 1e-3);
    for (size_t i = 0; i < t->rows * t->fibers; ++i)
        assert_int_equal(flags[i], 0);
    free(z);
    free(flags);
    test_sheet_free(t);
}

static void irregular_encoder_jitter_within_1um(void **state) {
    (void)state;
    /* +-20% jitter of every row position; the true positions are given. */
    test_sheet *t = test_sheet_make(REF_ROWS, 21, 0.0, REF_DX, 0.2, 75.0, LASER, 3);
    double *z = alloc_rows(t->rows, t->fibers), *zs = alloc_rows(t->rows, t->fibers);
    assert_int_equal(
        flt_reconstruct(NULL, t->rows, t->fibers, t->s, t->height, t->slope, NULL, z, NULL),
        FLT_OK);
    double mx, rms;
    test_error(t, z, 0, t->rows, &mx, &rms);
    flt_recon *rc = make_recon(t->fibers, NULL);
    size_t pulled = 0;
    stream_rows(rc, t, 0, t->rows, NULL, zs, NULL, &pulled);
    finish_sheet(rc, t, zs, NULL, &pulled);
    assert_int_equal(pulled, t->rows);
    double mxs, rmss;
    test_error(t, zs, 0, t->rows, &mxs, &rmss);
    print_message("jittered encoder: batch max %.3g um, streaming max %.3g um\n", mx * 1e3,
                  mxs * 1e3);
    assert_true(mx <= 1e-3);
    assert_true(mxs <= 1e-3);
    flt_recon_destroy(rc);
    free(z);
    free(zs);
    test_sheet_free(t);
}

/* ---- streaming against batch ------------------------------------------ */

static void streaming_equals_batch_noise_free(void **state) {
    (void)state;
    test_sheet *t = test_sheet_make(REF_ROWS, REF_FIBERS, 0.0, REF_DX, 0.0, REF_PITCH, LASER, 1);
    size_t N = t->rows * t->fibers;
    double *zb = alloc_rows(t->rows, t->fibers), *zs = alloc_rows(t->rows, t->fibers);
    assert_int_equal(
        flt_reconstruct(NULL, t->rows, t->fibers, t->s, t->height, t->slope, NULL, zb, NULL),
        FLT_OK);
    flt_recon *rc = make_recon(t->fibers, NULL);
    size_t pulled = 0;
    stream_rows(rc, t, 0, t->rows, NULL, zs, NULL, &pulled);
    /* With the default latency (a lag of 15 knots emitted in groups of 2;
     * the head's first emission once the newest row is 36 knots in) about
     * 7.1 m of the 9 m sheet is out before end_sheet: rows below about
     * 9000 - 1850 mm, some 2380. They are real lagged output. */
    print_message("rows finished before end_sheet: %zu of %zu\n", pulled, t->rows);
    assert_true(pulled >= 2300);
    finish_sheet(rc, t, zs, NULL, &pulled);
    assert_int_equal(pulled, t->rows);
    double d = max_abs_diff(zs, zb, N);
    print_message("noise-free: streaming vs batch max difference %.3g um\n", d * 1e3);
    assert_true(d <= 1e-3); /* goal: within 1 um */
    flt_recon_destroy(rc);
    free(zb);
    free(zs);
    test_sheet_free(t);
}

static void streaming_rms_within_5pct_of_batch_noisy(void **state) {
    (void)state;
    /* A 30 m strip so that most rows come out at the lag rather than at
     * end_sheet; fibers are independent, so 11 fibers suffice. Three noise
     * seeds: the ratios must hold for each. With a long lag (64 knots, 6.4 m
     * of strip) the streamed fixed-lag solution is within 5% of the whole
     * strip's; with the default latency (2 m; a fiber's level under 2.5 mm
     * of vibration averages heights over about 25 knots, more than the 15
     * knots of lag) it pays for the shorter wait: measured 1.12-1.18 times
     * the batch rms, bounded at 1.25 (docs/reconstruction.md tables the
     * price). */
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_LAG_KNOTS, 64), FLT_OK);
    for (unsigned seed = 1; seed <= 3; ++seed) {
        test_sheet *t = test_sheet_make(10000, 11, 0.0, REF_DX, 0.0, 150.0, LASER, seed);
        test_sheet_add_noise(t, VIB_SIGMA, PEAK_SIGMA, 100 + seed);
        double *zb = alloc_rows(t->rows, t->fibers), *zs = alloc_rows(t->rows, t->fibers);
        assert_int_equal(
            flt_reconstruct(NULL, t->rows, t->fibers, t->s, t->height, t->slope, NULL, zb, NULL),
            FLT_OK);
        double mxb, rmsb, mxs, rmss, rms_lagged = 0, rms_default = 0;
        test_error(t, zb, 0, t->rows, &mxb, &rmsb);
        for (int lagged = 1; lagged >= 0; --lagged) {
            flt_recon *rc = make_recon(t->fibers, lagged ? o : NULL);
            size_t pulled = 0;
            stream_rows(rc, t, 0, t->rows, NULL, zs, NULL, &pulled);
            finish_sheet(rc, t, zs, NULL, &pulled);
            test_error(t, zs, 0, t->rows, &mxs, &rmss);
            if (lagged)
                rms_lagged = rmss;
            else
                rms_default = rmss;
            flt_recon_destroy(rc);
        }
        print_message("noisy seed %u: batch rms %.4f mm, streaming rms with lag 64 %.4f mm "
                      "(ratio %.3f), at the default latency %.4f mm (ratio %.3f)\n",
                      seed, rmsb, rms_lagged, rms_lagged / rmsb, rms_default, rms_default / rmsb);
        assert_true(rms_lagged <= 1.05 * rmsb); /* goal: within 5% */
        assert_true(rms_default <= 1.25 * rmsb);
        /* And the batch itself beats the reference's 0.12 mm sigma. */
        assert_true(rmsb < 0.12);
        free(zb);
        free(zs);
        test_sheet_free(t);
    }
    flt_options_destroy(o);
}

/* ---- carry-over -------------------------------------------------------- */

/* Pushes sheet rows with six masked probe rows at b-3d .. b+3d (excluding b)
 * around position b, so both splines around a join can be read. */
static void quad_extrapolate(const double z[3], double d, double *value, double *slope) {
    /* z at -d, -2d, -3d from the point (mirror for the other side):
     * quadratic through them, evaluated at 0. Exact for the cubic pieces up
     * to d^2 * z''' ~ 1e-6 * 1e-6 mm here. */
    *value = 3 * z[0] - 3 * z[1] + z[2];
    *slope = (2.5 * z[0] - 4 * z[1] + 1.5 * z[2]) / d;
}

/* Pulls every finished row of rc and copies the rows at the probe positions
 * into probe_z. Returns how many probes were found. */
static int pull_probes(flt_recon *rc, size_t K, const double probe_s[6], double probe_z[6][8]) {
    double *s = malloc(4096 * sizeof(double));
    double *z = alloc_rows(4096, K);
    size_t got = 0;
    int found = 0;
    assert_int_equal(flt_recon_pull(rc, 4096, K, s, z, NULL, &got), FLT_OK);
    for (size_t i = 0; i < got; ++i)
        for (int q = 0; q < 6; ++q)
            if (s[i] == probe_s[q]) {
                memcpy(probe_z[q], z + i * K, K * sizeof(double));
                ++found;
            }
    free(s);
    free(z);
    return found;
}

static void carry_over_sheets_join_c1(void **state) {
    (void)state;
    /* Three sheets of ~3 m of one noisy strip. At each join the previous
     * sheet's spline (left) and the next one's (right) must agree in height
     * and slope to 1e-9. They are read with masked probe rows (which add no
     * data) at b-3d, b-2d, b-d and b+d, b+2d, b+3d around the carried knot b.
     * Control: the next sheet solved by a fresh reconstructor (no carry-over)
     * shows real jumps, so the probe can see them. */
    const size_t K = 5, rows_per_sheet = 1000;
    test_sheet *t = test_sheet_make(3 * rows_per_sheet, K, 0.0, REF_DX, 0.0, 300.0, LASER, 5);
    test_sheet_add_noise(t, VIB_SIGMA, PEAK_SIGMA, 55);
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_LAG_KNOTS, 8), FLT_OK);
    for (int mode = 0; mode < 3; ++mode) {
        /* mode 0: per-fiber fit; 1: rigid_motion (three channels, each carried);
         * 2: per-fiber fit without carry-over (the control). */
        const int control = mode == 2;
        assert_int_equal(flt_options_set(o, FLT_OPT_RIGID_MOTION, mode == 1), FLT_OK);
        {
            flt_recon *rc = make_recon(K, o);
            double worst_dz = 0, worst_dg = 0;
            size_t next = 0;
            for (int sheet = 0; sheet < 3; ++sheet) {
                size_t end = (size_t)(sheet + 1) * rows_per_sheet;
                for (; next < end; ++next)
                    assert_int_equal(flt_recon_push(rc, 1, K, &t->s[next], t->height + next * K,
                                                    t->slope + next * K, NULL),
                                     FLT_OK);
                assert_int_equal(flt_recon_end_sheet(rc), FLT_OK);
                double none[6] = {0}, unused[6][8];
                (void)pull_probes(rc, K, none, unused); /* drain the sheet */
                if (sheet == 2)
                    break;
                double bs, bz[8], bg[8];
                assert_int_equal(flt_recon_boundary(rc, K, &bs, bz, bg), FLT_OK);
                /* The boundary knot lies past the last row, within one knot. */
                assert_true(bs > t->s[end - 1] + 0.01 && bs <= t->s[end - 1] + LASER + 1e-9);
                flt_recon *left = rc, *right = control ? make_recon(K, o) : rc;
                const double d = 1e-3;
                double probe_s[6] = {bs - 3 * d, bs - 2 * d, bs - d,
                                     bs + d,     bs + 2 * d, bs + 3 * d};
                double probe_z[6][8];
                uint8_t masked[8] = {0};
                double zeros[8] = {0};
                int p = 0;
                while (p < 6) {
                    if (probe_s[p] < t->s[next]) {
                        flt_recon *to = p < 3 ? left : right;
                        assert_int_equal(
                            flt_recon_push(to, 1, K, &probe_s[p], zeros, zeros, masked), FLT_OK);
                        ++p;
                    } else {
                        assert_int_equal(flt_recon_push(right, 1, K, &t->s[next],
                                                        t->height + next * K, t->slope + next * K,
                                                        NULL),
                                         FLT_OK);
                        ++next;
                    }
                }
                /* Far enough into the next sheet that the probes are finished. */
                for (size_t stop = next + 600; next < stop; ++next)
                    assert_int_equal(flt_recon_push(right, 1, K, &t->s[next], t->height + next * K,
                                                    t->slope + next * K, NULL),
                                     FLT_OK);
                int found = pull_probes(right, K, probe_s, probe_z);
                if (control) {
                    found += pull_probes(left, K, probe_s, probe_z);
                    flt_recon_destroy(left);
                    rc = right;
                }
                assert_int_equal(found, 6);
                for (size_t k = 0; k < K; ++k) {
                    double lz[3] = {probe_z[2][k], probe_z[1][k], probe_z[0][k]};
                    double rz[3] = {probe_z[3][k], probe_z[4][k], probe_z[5][k]};
                    double zl, gl, zr, gr;
                    quad_extrapolate(lz, d, &zl, &gl);
                    quad_extrapolate(rz, -d, &zr, &gr);
                    worst_dz = fmax(worst_dz, fabs(zl - zr));
                    worst_dg = fmax(worst_dg, fabs(gl - gr));
                    /* The carried values are the left spline's end. */
                    assert_true(fabs(zl - bz[k]) <= 1e-9);
                    assert_true(fabs(gl - bg[k]) <= 1e-9);
                }
            }
            print_message("%s: worst height jump %.3g mm, slope jump %.3g at the joins\n",
                          control     ? "no carry-over (control)"
                          : mode == 1 ? "carry-over, rigid_motion"
                                      : "carry-over",
                          worst_dz, worst_dg);
            if (!control) {
                assert_true(worst_dz <= 1e-9);
                assert_true(worst_dg <= 1e-9);
            } else {
                /* Independent sheets under 2.5 mm vibration disagree by far more. */
                assert_true(worst_dz > 1e-3);
            }
            flt_recon_destroy(rc);
        }
    }
    flt_options_destroy(o);
    test_sheet_free(t);
}

/* ---- invalid data ------------------------------------------------------ */

static void invalid_samples_and_gap_are_bridged_and_flagged(void **state) {
    (void)state;
    const size_t K = 21;
    test_sheet *t = test_sheet_make(REF_ROWS, K, 0.0, REF_DX, 0.0, 75.0, LASER, 9);
    size_t N = t->rows * K;
    uint8_t *valid = malloc(N);
    test_rng rng;
    test_rng_seed(&rng, 99);
    for (size_t i = 0; i < N; ++i)
        valid[i] = test_rng_uniform(&rng) >= 0.10;
    /* A 300 mm gap in every fiber: rows with s in [4000, 4300). */
    const double gap_a = 4000.0, gap_b = 4300.0;
    for (size_t r = 0; r < t->rows; ++r)
        if (t->s[r] >= gap_a && t->s[r] < gap_b)
            memset(valid + r * K, 0, K);
    /* NaN where the mask says valid: counted as invalid too. */
    t->height[5 * K + 3] = NAN;
    t->slope[5 * K + 3] = NAN;

    double *z = alloc_rows(t->rows, K), *zs = alloc_rows(t->rows, K);
    uint8_t *flags = malloc(N), *flags_s = malloc(N);
    assert_int_equal(flt_reconstruct(NULL, t->rows, K, t->s, t->height, t->slope, valid, z, flags),
                     FLT_OK);
    flt_recon *rc = make_recon(K, NULL);
    size_t pulled = 0;
    stream_rows(rc, t, 0, t->rows, valid, zs, flags_s, &pulled);
    finish_sheet(rc, t, zs, flags_s, &pulled);

    /* Expected flags, from the runs of invalid rows of each fiber: a run is
     * a gap when its valid neighbours are more than max_gap = 200 mm apart
     * (random invalid rows next to the 300 mm hole lengthen its run). */
    valid[5 * K + 3] = 0;
    uint8_t *expect = calloc(N, 1);
    for (size_t k = 0; k < K; ++k) {
        size_t r = 0;
        while (r < t->rows) {
            if (valid[r * K + k]) {
                ++r;
                continue;
            }
            size_t a = r;
            while (r < t->rows && !valid[r * K + k])
                ++r;
            double before = a > 0 ? t->s[a - 1] : t->s[0];
            double after = r < t->rows ? t->s[r] : t->s[t->rows - 1];
            for (size_t q = a; q < r; ++q)
                expect[q * K + k] =
                    (uint8_t)(FLT_FLAG_INVALID_INPUT | (after - before > 200.0 ? FLT_FLAG_GAP : 0));
        }
    }
    double worst_out = 0, worst_gap = 0;
    size_t wrong_flags = 0, gap_rows = 0, gap_flags = 0;
    for (size_t r = 0; r < t->rows; ++r) {
        int in_gap = t->s[r] >= gap_a && t->s[r] < gap_b;
        gap_rows += in_gap;
        for (size_t k = 0; k < K; ++k) {
            size_t i = r * K + k;
            assert_true(isfinite(z[i]) && isfinite(zs[i]));
            double e = fabs(z[i] - t->truth[i]);
            if (in_gap)
                worst_gap = fmax(worst_gap, e);
            else
                worst_out = fmax(worst_out, e);
            if (in_gap)
                assert_true(flags[i] & FLT_FLAG_GAP);
            gap_flags += (flags[i] & FLT_FLAG_GAP) != 0;
            wrong_flags += flags[i] != expect[i];
            wrong_flags += flags_s[i] != expect[i];
        }
    }
    free(expect);
    /* Only the hole (and invalid rows touching it) is a gap. */
    assert_true(gap_flags >= gap_rows * K && gap_flags <= gap_rows * K + 4 * K);
    print_message("10%% invalid + 300 mm gap: max error %.3g um outside, %.3g mm in the gap; "
                  "%zu gap rows; %zu wrong flags\n",
                  worst_out * 1e3, worst_gap, gap_rows, wrong_flags);
    assert_int_equal(gap_rows, 100);
    assert_int_equal(wrong_flags, 0);
    /* Losing 10% of noise-free samples costs little: still within 1 um. */
    assert_true(worst_out <= 1e-3);
    /* Across the hole the fit is a cubic pinned by the data at its edges:
     * no worse than cubic Hermite interpolation over 300 mm of the 12 mm,
     * 1800 mm wave, h^4/384 * max|z''''| = 300^4/384 * 12 (2 pi/1800)^4
     * = 0.0375 mm. */
    assert_true(worst_gap <= 0.0375);
    flt_recon_destroy(rc);
    free(valid);
    free(z);
    free(zs);
    free(flags);
    free(flags_s);
    test_sheet_free(t);
}

static void dead_fiber_is_nan_and_does_not_touch_others(void **state) {
    (void)state;
    const size_t K = 7;
    test_sheet *t = test_sheet_make(1000, K, 0.0, REF_DX, 0.0, 200.0, LASER, 2);
    test_sheet_add_noise(t, VIB_SIGMA, PEAK_SIGMA, 3);
    size_t N = t->rows * K;
    uint8_t *valid = malloc(N);
    memset(valid, 1, N);
    for (size_t r = 0; r < t->rows; ++r)
        valid[r * K + 2] = 0; /* fiber 2 never seen */
    double *z1 = alloc_rows(t->rows, K), *z2 = alloc_rows(t->rows, K);
    uint8_t *flags = malloc(N);
    assert_int_equal(flt_reconstruct(NULL, t->rows, K, t->s, t->height, t->slope, NULL, z1, NULL),
                     FLT_OK);
    assert_int_equal(flt_reconstruct(NULL, t->rows, K, t->s, t->height, t->slope, valid, z2, flags),
                     FLT_OK);
    for (size_t r = 0; r < t->rows; ++r)
        for (size_t k = 0; k < K; ++k) {
            size_t i = r * K + k;
            if (k == 2) {
                assert_true(isnan(z2[i]));
                assert_true(flags[i] & FLT_FLAG_NO_DATA);
            } else {
                /* Fibers are solved independently: bit for bit the same. */
                assert_memory_equal(&z1[i], &z2[i], sizeof(double));
                assert_int_equal(flags[i], 0);
            }
        }
    free(valid);
    free(z1);
    free(z2);
    free(flags);
    test_sheet_free(t);
}

static void height_only_or_slope_only_samples_are_used(void **state) {
    (void)state;
    /* Every other row loses its slope, every third its height: the fit must
     * stay within 1 um and no row is flagged (each still has one reading). */
    const size_t K = 3;
    test_sheet *t = test_sheet_make(REF_ROWS, K, 0.0, REF_DX, 0.0, 300.0, LASER, 4);
    for (size_t r = 0; r < t->rows; ++r)
        for (size_t k = 0; k < K; ++k) {
            if (r % 2 == 0)
                t->slope[r * K + k] = NAN;
            else if (r % 3 == 0)
                t->height[r * K + k] = INFINITY;
        }
    double *z = alloc_rows(t->rows, K);
    uint8_t *flags = malloc(t->rows * K);
    assert_int_equal(flt_reconstruct(NULL, t->rows, K, t->s, t->height, t->slope, NULL, z, flags),
                     FLT_OK);
    double mx, rms;
    test_error(t, z, 0, t->rows, &mx, &rms);
    assert_true(mx <= 1e-3);
    for (size_t i = 0; i < t->rows * K; ++i)
        assert_int_equal(flags[i], 0);
    free(z);
    free(flags);
    test_sheet_free(t);
}

/* ---- state machine ----------------------------------------------------- */

static void reset_starts_a_fresh_strip(void **state) {
    (void)state;
    const size_t K = 4;
    test_sheet *t = test_sheet_make(800, K, 1000.0, REF_DX, 0.0, 100.0, LASER, 8);
    double *za = alloc_rows(t->rows, K), *zb = alloc_rows(t->rows, K);
    flt_recon *used = make_recon(K, NULL), *fresh = make_recon(K, NULL);
    /* Dirty the first handle with another strip further along, then reset. */
    test_sheet *other = test_sheet_make(300, K, 50000.0, REF_DX, 0.0, 100.0, LASER, 9);
    size_t pulled = 0;
    double *zo = alloc_rows(other->rows, K);
    stream_rows(used, other, 0, other->rows, NULL, zo, NULL, &pulled);
    assert_int_equal(flt_recon_reset(used), FLT_OK);
    /* Positions may restart lower after a reset. */
    size_t pa = 0, pb = 0;
    stream_rows(used, t, 0, t->rows, NULL, za, NULL, &pa);
    finish_sheet(used, t, za, NULL, &pa);
    stream_rows(fresh, t, 0, t->rows, NULL, zb, NULL, &pb);
    finish_sheet(fresh, t, zb, NULL, &pb);
    assert_int_equal(pa, t->rows);
    assert_memory_equal(za, zb, t->rows * K * sizeof(double));
    assert_int_equal(flt_recon_boundary(used, K, NULL, NULL, NULL), FLT_OK);
    assert_int_equal(flt_recon_reset(used), FLT_OK);
    assert_int_equal(flt_recon_boundary(used, K, NULL, NULL, NULL), FLT_ERR_STATE);
    flt_recon_destroy(used);
    flt_recon_destroy(fresh);
    free(za);
    free(zb);
    free(zo);
    test_sheet_free(t);
    test_sheet_free(other);
}

static void buffer_full_then_pull_recovers(void **state) {
    (void)state;
    const size_t K = 2;
    test_sheet *t = test_sheet_make(400, K, 0.0, REF_DX, 0.0, 100.0, LASER, 6);
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_ROW_CAPACITY, 100), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_LAG_KNOTS, 0), FLT_OK);
    flt_recon *rc = make_recon(K, o);
    flt_options_destroy(o);
    /* 101 rows into 100 slots: refused whole, nothing pushed. */
    assert_int_equal(flt_recon_push(rc, 101, K, t->s, t->height, t->slope, NULL),
                     FLT_ERR_BUFFER_FULL);
    assert_non_null(strstr(flt_last_error_message(), "row_capacity"));
    assert_int_equal(flt_recon_push(rc, 100, K, t->s, t->height, t->slope, NULL), FLT_OK);
    assert_int_equal(
        flt_recon_push(rc, 1, K, &t->s[100], t->height + 100 * K, t->slope + 100 * K, NULL),
        FLT_ERR_BUFFER_FULL);
    size_t ready = 0, n = 0;
    assert_int_equal(flt_recon_ready(rc, &ready), FLT_OK);
    /* lag 0: 100 rows reach s = 297 mm, so s - 50 mm has closed knots 0 and
     * 1 (t_1 = 50 mm from t_0 = -50 mm); rows below t_1 are finished:
     * s = 0, 3, ..., 48, 17 rows. */
    assert_int_equal(ready, 17);
    double s_out[100], z_out[200];
    assert_int_equal(flt_recon_pull(rc, 100, K, s_out, z_out, NULL, &n), FLT_OK);
    assert_int_equal(n, ready);
    assert_int_equal(
        flt_recon_push(rc, 1, K, &t->s[100], t->height + 100 * K, t->slope + 100 * K, NULL),
        FLT_OK);
    flt_recon_destroy(rc);
    test_sheet_free(t);
}

/* ---- bad input --------------------------------------------------------- */

/* Expects `call` to fail with `status` and a message containing `needle`. */
#define EXPECT_FAIL(call, status, needle)                                      \
  do {                                                                         \
    assert_int_equal((call), (status));                                        \
    if (strstr(flt_last_error_message(), (needle)) == NULL)                    \
      fail_msg("message '%s' lacks '%s'", flt_last_error_message(), (needle)); \
  } while (0)

static void bad_input_is_rejected_and_handle_stays_usable(void **state) {
    (void)state;
    const size_t K = 3;
    test_sheet *t = test_sheet_make(600, K, 0.0, REF_DX, 0.0, 100.0, LASER, 7);
    flt_recon *rc = NULL;
    double s_out[600], z_out[600 * 3], one = 0;
    size_t n = 0;

    /* create */
    EXPECT_FAIL(flt_recon_create(0, NULL, &rc), FLT_ERR_INVALID_ARGUMENT, "'fibers' is 0");
    assert_null(rc);
    EXPECT_FAIL(flt_recon_create(K, NULL, NULL), FLT_ERR_INVALID_ARGUMENT, "'out'");
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    EXPECT_FAIL(flt_options_set(o, FLT_OPT_KNOT_SPACING, -5.0), FLT_ERR_INVALID_ARGUMENT,
                "knot_spacing");
    EXPECT_FAIL(flt_options_set(o, FLT_OPT_SLOPE_SIGMA, NAN), FLT_ERR_INVALID_ARGUMENT,
                "slope_sigma");
    assert_int_equal(flt_options_set(o, FLT_OPT_KNOT_SPACING, 1.0), FLT_OK);
    EXPECT_FAIL(flt_recon_create(K, o, &rc), FLT_ERR_INVALID_ARGUMENT, "knot_spacing = 1");
    flt_options_destroy(o);
    EXPECT_FAIL(flt_recon_create((size_t)-1 / 4, NULL, &rc), FLT_ERR_INVALID_ARGUMENT, "too large");

    rc = make_recon(K, NULL);
    /* pull before push */
    EXPECT_FAIL(flt_recon_pull(rc, 10, K, s_out, z_out, NULL, &n), FLT_ERR_STATE,
                "nothing was pushed");
    /* end_sheet with nothing pushed */
    EXPECT_FAIL(flt_recon_end_sheet(rc), FLT_ERR_STATE, "no row was pushed");
    /* NULL handle and buffers */
    EXPECT_FAIL(flt_recon_push(NULL, 1, K, t->s, t->height, t->slope, NULL),
                FLT_ERR_INVALID_ARGUMENT, "'recon'");
    EXPECT_FAIL(flt_recon_push(rc, 1, K, NULL, t->height, t->slope, NULL), FLT_ERR_INVALID_ARGUMENT,
                "'s'");
    EXPECT_FAIL(flt_recon_push(rc, 1, K, t->s, NULL, t->slope, NULL), FLT_ERR_INVALID_ARGUMENT,
                "'height'");
    EXPECT_FAIL(flt_recon_push(rc, 1, K, t->s, t->height, NULL, NULL), FLT_ERR_INVALID_ARGUMENT,
                "'slope'");
    EXPECT_FAIL(flt_recon_pull(rc, 1, K, s_out, z_out, NULL, NULL), FLT_ERR_INVALID_ARGUMENT,
                "'rows_out'");
    EXPECT_FAIL(flt_recon_ready(NULL, &n), FLT_ERR_INVALID_ARGUMENT, "'recon'");
    EXPECT_FAIL(flt_recon_end_sheet(NULL), FLT_ERR_INVALID_ARGUMENT, "'recon'");
    EXPECT_FAIL(flt_recon_reset(NULL), FLT_ERR_INVALID_ARGUMENT, "'recon'");
    EXPECT_FAIL(flt_recon_fibers(rc, NULL), FLT_ERR_INVALID_ARGUMENT, "'out'");
    EXPECT_FAIL(flt_recon_get_option(rc, (flt_option)9999, &one), FLT_ERR_NOT_FOUND, "9999");
    /* wrong sizes */
    EXPECT_FAIL(flt_recon_push(rc, 1, K + 1, t->s, t->height, t->slope, NULL),
                FLT_ERR_INVALID_ARGUMENT, "'fibers' = 4 but the reconstructor has 3");
    EXPECT_FAIL(flt_recon_push(rc, 0, K, t->s, t->height, t->slope, NULL), FLT_ERR_INVALID_ARGUMENT,
                "'rows' is 0");
    EXPECT_FAIL(flt_recon_push(rc, (size_t)-1 / 2, K, t->s, t->height, t->slope, NULL),
                FLT_ERR_INVALID_ARGUMENT, "overflows");
    EXPECT_FAIL(flt_recon_pull(rc, 10, K - 1, s_out, z_out, NULL, &n), FLT_ERR_INVALID_ARGUMENT,
                "'fibers'");
    /* positions: NaN, non-increasing within a block and across calls */
    double bad_s[3] = {0.0, NAN, 6.0};
    EXPECT_FAIL(flt_recon_push(rc, 3, K, bad_s, t->height, t->slope, NULL),
                FLT_ERR_INVALID_ARGUMENT, "s[1]");
    double flat_s[3] = {0.0, 3.0, 3.0};
    EXPECT_FAIL(flt_recon_push(rc, 3, K, flat_s, t->height, t->slope, NULL),
                FLT_ERR_INVALID_ARGUMENT, "does not increase");
    /* The failed blocks pushed nothing: the next push starts the strip. */
    assert_int_equal(flt_recon_push(rc, 300, K, t->s, t->height, t->slope, NULL), FLT_OK);
    EXPECT_FAIL(flt_recon_push(rc, 1, K, &t->s[299], t->height, t->slope, NULL),
                FLT_ERR_INVALID_ARGUMENT, "does not increase");
    double far = t->s[299] + 2e6;
    EXPECT_FAIL(flt_recon_push(rc, 1, K, &far, t->height, t->slope, NULL), FLT_ERR_INVALID_ARGUMENT,
                "reset");
    /* end_sheet twice */
    assert_int_equal(flt_recon_end_sheet(rc), FLT_OK);
    EXPECT_FAIL(flt_recon_end_sheet(rc), FLT_ERR_STATE, "no row was pushed");
    /* After all that the handle still reconstructs correctly. */
    assert_int_equal(
        flt_recon_push(rc, 300, K, t->s + 300, t->height + 300 * K, t->slope + 300 * K, NULL),
        FLT_OK);
    assert_int_equal(flt_recon_end_sheet(rc), FLT_OK);
    assert_int_equal(flt_recon_pull(rc, 600, K, s_out, z_out, NULL, &n), FLT_OK);
    assert_int_equal(n, 600);
    double mx, rms;
    test_error(t, z_out, 0, 600, &mx, &rms);
    assert_true(mx <= 1e-3);

    /* batch */
    double *z = alloc_rows(t->rows, K);
    EXPECT_FAIL(flt_reconstruct(NULL, t->rows, K, t->s, t->height, t->slope, NULL, NULL, NULL),
                FLT_ERR_INVALID_ARGUMENT, "'z_out'");
    EXPECT_FAIL(flt_reconstruct(NULL, t->rows, 0, t->s, t->height, t->slope, NULL, z, NULL),
                FLT_ERR_INVALID_ARGUMENT, "'fibers' is 0");
    t->s[10] = t->s[9];
    EXPECT_FAIL(flt_reconstruct(NULL, t->rows, K, t->s, t->height, t->slope, NULL, z, NULL),
                FLT_ERR_INVALID_ARGUMENT, "s[10]");
    free(z);

    /* A jump in s costs an elimination per knot it crosses, so the largest
     * allowed jump is 1000 knots (and 1 km): with 10 mm knots, 12 m is
     * refused (the handle stays usable), 8 m bridged. Knots finer than
     * laser_spacing / 16 are refused. */
    flt_options *fine = NULL;
    flt_recon *rc2 = NULL;
    assert_int_equal(flt_options_create(&fine), FLT_OK);
    assert_int_equal(flt_options_set(fine, FLT_OPT_KNOT_SPACING, 6.0), FLT_OK);
    EXPECT_FAIL(flt_recon_create(K, fine, &rc2), FLT_ERR_INVALID_ARGUMENT, "knot_spacing = 6");
    assert_int_equal(flt_options_set(fine, FLT_OPT_KNOT_SPACING, 10.0), FLT_OK);
    flt_recon *rf = make_recon(K, fine);
    flt_options_destroy(fine);
    double js[2] = {0.0, 12000.0}, jh[2 * 5] = {0}, jg[2 * 5] = {0};
    assert_true(K <= 5);
    EXPECT_FAIL(flt_recon_push(rf, 2, K, js, jh, jg, NULL), FLT_ERR_INVALID_ARGUMENT, "1000 knots");
    js[1] = 8000.0;
    assert_int_equal(flt_recon_push(rf, 2, K, js, jh, jg, NULL), FLT_OK);
    flt_recon_destroy(rf);

    /* destroy is a no-op on NULL */
    flt_recon_destroy(NULL);
    flt_recon_destroy(rc);
    test_sheet_free(t);
}

static void buffer_full_with_nothing_finished_says_why(void **state) {
    (void)state;
    /* At the head of a strip a row waits up to twice latency_mm (3.6 m of
     * strip by default) before it is finished. Rows every 1 mm into 2048
     * slots fill the ring before any is finished; the refusal must say so,
     * with the latency and what to do, and the handle must stay usable:
     * end_sheet finishes what it holds. rigid_motion + robust: every
     * channel's window holds the rows too. */
    const size_t K = 3;
    test_sheet *t = test_sheet_make(5000, K, 0.0, 1.0, 0.0, 100.0, LASER, 7);
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_ROW_CAPACITY, 2048), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_RIGID_MOTION, 1), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_ROBUST, FLT_ROBUST_HUBER), FLT_OK);
    flt_recon *rc = make_recon(K, o);
    flt_options_destroy(o);
    size_t r = 0;
    flt_status st = FLT_OK;
    for (; r < t->rows; ++r) {
        st = flt_recon_push(rc, 1, K, &t->s[r], t->height + r * K, t->slope + r * K, NULL);
        if (st != FLT_OK)
            break;
    }
    assert_int_equal(st, FLT_ERR_BUFFER_FULL);
    print_message("full after %zu rows: %s\n", r, flt_last_error_message());
    assert_non_null(strstr(flt_last_error_message(), "no row is finished yet"));
    assert_non_null(strstr(flt_last_error_message(), "larger row_capacity"));
    size_t ready = 1, n = 0;
    assert_int_equal(flt_recon_ready(rc, &ready), FLT_OK);
    assert_int_equal(ready, 0);
    assert_int_equal(flt_recon_end_sheet(rc), FLT_OK);
    double *s_out = malloc(r * sizeof(double)), *z = alloc_rows(r, K);
    assert_int_equal(flt_recon_pull(rc, r, K, s_out, z, NULL, &n), FLT_OK);
    assert_int_equal(n, r);
    free(s_out);
    free(z);
    flt_recon_destroy(rc);
    test_sheet_free(t);
}

static void robust_streaming_with_rows_sparser_than_knots(void **state) {
    (void)state;
    /* Rows 20 knots apart: the window moves on over knots without rows, a
     * row may be judged only once before its knots are final, and end_sheet
     * finishes every row (fuzz_recon once found rows left queued, an
     * internal error, in the pipelined stages robust mode had before).
     * Laser and knots 3 mm apart. */
    const size_t K = 2;
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_ROBUST, FLT_ROBUST_HUBER), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_LASER_SPACING, 3.0), FLT_OK);
    flt_recon *rc = make_recon(K, o);
    flt_options_destroy(o);
    const double s[5] = {64.25, 128.5, 129.5, 190.0, 250.0};
    double h[5 * 2], g[5 * 2];
    for (int i = 0; i < 10; ++i) {
        h[i] = 0.1 * i;
        g[i] = 0.0;
    }
    for (int r = 0; r < 5; ++r)
        assert_int_equal(flt_recon_push(rc, 1, K, &s[r], h + 2 * r, g + 2 * r, NULL), FLT_OK);
    assert_int_equal(flt_recon_end_sheet(rc), FLT_OK);
    double s_out[5], z[10];
    size_t n = 0;
    assert_int_equal(flt_recon_pull(rc, 5, K, s_out, z, NULL, &n), FLT_OK);
    assert_int_equal(n, 5);
    for (int i = 0; i < 10; ++i)
        assert_true(isfinite(z[i]));
    flt_recon_destroy(rc);
}

static void absurd_values_are_invalid_samples(void **state) {
    (void)state;
    /* A finite but absurd reading (beyond 1e9 mm or mm/mm) is no sample:
     * it is flagged and bridged like a NaN, in every mode (its square
     * would overflow the sums into NaN output; fuzz_recon found -2e307). */
    const size_t K = 5;
    test_sheet *t = test_sheet_make(1000, K, 0.0, REF_DX, 0.0, 200.0, LASER, 21);
    /* From the 11th row on: a fiber missing before it was ever seen leaves
     * the rigid split's line (recon.h), a different, documented effect. */
    for (size_t i = 10 * K + 1; i < t->rows * K; i += 97) {
        t->height[i] = (i % 2) ? 2e307 : -3e9;
        t->slope[i] = (i % 3) ? -1e300 : 5e9;
    }
    for (int mode = 0; mode < 3; ++mode) {
        flt_options *o = NULL;
        assert_int_equal(flt_options_create(&o), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_RIGID_MOTION, mode >= 1), FLT_OK);
        assert_int_equal(
            flt_options_set(o, FLT_OPT_ROBUST, mode == 2 ? FLT_ROBUST_HUBER : FLT_ROBUST_NONE),
            FLT_OK);
        double *z = alloc_rows(t->rows, K);
        uint8_t *flags = malloc(t->rows * K);
        assert_int_equal(flt_reconstruct(o, t->rows, K, t->s, t->height, t->slope, NULL, z, flags),
                         FLT_OK);
        flt_options_destroy(o);
        size_t flagged = 0;
        for (size_t i = 0; i < t->rows * K; ++i) {
            assert_true(isfinite(z[i]));
            flagged += (flags[i] & FLT_FLAG_INVALID_INPUT) != 0;
        }
        double mx, rms;
        test_error(t, z, 0, t->rows, &mx, &rms);
        print_message("absurd values, mode %d: %zu samples flagged, max error %.3g mm\n", mode,
                      flagged, mx);
        assert_int_equal(flagged, (t->rows * K - (10 * K + 1) + 96) / 97);
        /* Bridged like missing samples: exact without rigid_motion, within
         * its missing-fiber bound (0.03 mm) with it. */
        assert_true(mx <= (mode ? 0.03 : 1e-3));
        free(z);
        free(flags);
    }
    test_sheet_free(t);
}

static void slopes_before_heights_with_close_lasers_stay_finite(void **state) {
    (void)state;
    /* Lasers 0.36 mm apart weigh a slope 5e7 times a height: a fiber with
     * only slopes so far had a numerically singular level, its knots went
     * NaN, and the height that came later could not repair them (a NaN
     * without a flag; fuzz_recon). The ridge now scales with the stronger
     * weight. Fiber 0: a slope at row 0, a height at row 1, both at row 2;
     * rows 178 and 65 knots apart. */
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_LASER_SPACING, 0.3598211333155632), FLT_OK);
    flt_recon *rc = make_recon(2, o);
    flt_options_destroy(o);
    const double s[3] = {0.5, 64.75, 88.25};
    const double h[6] = {-INFINITY, 0.4, 9.6093749860301614, 0.18037682399153709, 0.92, 0.92};
    const double g[6] = {1e-4, 0.004, INFINITY, -INFINITY, 0.0092, 0.0092};
    assert_int_equal(flt_recon_push(rc, 3, 2, s, h, g, NULL), FLT_OK);
    assert_int_equal(flt_recon_end_sheet(rc), FLT_OK);
    double s_out[3], z[6];
    uint8_t flags[6];
    size_t n = 0;
    assert_int_equal(flt_recon_pull(rc, 3, 2, s_out, z, flags, &n), FLT_OK);
    assert_int_equal(n, 3);
    for (int i = 0; i < 6; ++i) {
        print_message("row %d fiber %d: z %g flags %d\n", i / 2, i % 2, z[i], flags[i]);
        assert_true(isfinite(z[i]) || (flags[i] & FLT_FLAG_NO_DATA));
    }
    /* The height the fiber has is reproduced where it was measured. */
    assert_true(isfinite(z[2]));
    flt_recon_destroy(rc);
}

static void options_are_reported_back(void **state) {
    (void)state;
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_LASER_SPACING, 120.0), FLT_OK);
    flt_recon *rc = make_recon(5, o);
    flt_options_destroy(o); /* the handle kept its copy */
    double v = 0;
    size_t k = 0;
    assert_int_equal(flt_recon_get_option(rc, FLT_OPT_KNOT_SPACING, &v), FLT_OK);
    assert_true(v == 120.0); /* knot spacing defaults to the laser spacing */
    /* The lag from the default latency_mm (2000): the longest with lag +
     * lag/8 + 2 knots of 120 mm and 60 mm within it, 13 knots (1980 mm). */
    assert_int_equal(flt_recon_get_option(rc, FLT_OPT_LAG_KNOTS, &v), FLT_OK);
    assert_true(v == 13.0);
    assert_int_equal(flt_recon_get_option(rc, FLT_OPT_LATENCY_MM, &v), FLT_OK);
    assert_true(v == 1980.0);
    assert_int_equal(flt_recon_fibers(rc, &k), FLT_OK);
    assert_int_equal(k, 5);
    /* The robust passes' defaults, and one set. */
    assert_int_equal(flt_recon_get_option(rc, FLT_OPT_ROBUST_ITERATIONS, &v), FLT_OK);
    assert_true(v == 2.0);
    assert_int_equal(flt_recon_get_option(rc, FLT_OPT_ROBUST_LINE_ITERATIONS, &v), FLT_OK);
    assert_true(v == 8.0);
    flt_recon_destroy(rc);
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_ROBUST_LINE_ITERATIONS, 5.0), FLT_OK);
    EXPECT_FAIL(flt_options_set(o, FLT_OPT_ROBUST_LINE_ITERATIONS, 0.0), FLT_ERR_INVALID_ARGUMENT,
                "robust_line_iterations");
    EXPECT_FAIL(flt_options_set(o, FLT_OPT_ROBUST_LINE_ITERATIONS, 33.0), FLT_ERR_INVALID_ARGUMENT,
                "robust_line_iterations");
    rc = make_recon(5, o);
    flt_options_destroy(o);
    assert_int_equal(flt_recon_get_option(rc, FLT_OPT_ROBUST_LINE_ITERATIONS, &v), FLT_OK);
    assert_true(v == 5.0);
    flt_recon_destroy(rc);
}

static void finer_knots_than_laser_spacing_stay_exact(void **state) {
    (void)state;
    /* L = 50 mm with Delta-d = 100 mm: each row spans four knots. */
    test_sheet *t = test_sheet_make(REF_ROWS, 5, 0.0, REF_DX, 0.0, 300.0, LASER, 12);
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_KNOT_SPACING, 50.0), FLT_OK);
    double *z = alloc_rows(t->rows, t->fibers);
    assert_int_equal(
        flt_reconstruct(o, t->rows, t->fibers, t->s, t->height, t->slope, NULL, z, NULL), FLT_OK);
    double mx, rms;
    test_error(t, z, 0, t->rows, &mx, &rms);
    print_message("knots every 50 mm: max error %.3g um\n", mx * 1e3);
    /* Halving L shrinks the cubic's approximation error 16-fold. */
    assert_true(mx <= 1e-4);
    flt_options_destroy(o);
    free(z);
    test_sheet_free(t);
}

/* ---- rigid_motion ------------------------------------------------------ */

/* Max |e| and std of e after removing its mean over the whole sheet. */
static void error_minus_constant(const test_sheet *t, const double *z, double *max_out,
                                 double *std_out) {
    size_t n = t->rows * t->fibers;
    double mean = 0, sq = 0, mx = 0;
    for (size_t i = 0; i < n; ++i)
        mean += z[i] - t->truth[i];
    mean /= (double)n;
    for (size_t i = 0; i < n; ++i) {
        double e = z[i] - t->truth[i] - mean;
        sq += e * e;
        mx = fmax(mx, fabs(e));
    }
    *max_out = mx;
    *std_out = sqrt(sq / (double)n);
}

static double *reconstruct_with(const test_sheet *t, const uint8_t *valid, int rigid) {
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_RIGID_MOTION, rigid), FLT_OK);
    double *z = alloc_rows(t->rows, t->fibers);
    assert_int_equal(
        flt_reconstruct(o, t->rows, t->fibers, t->s, t->height, t->slope, valid, z, NULL), FLT_OK);
    flt_options_destroy(o);
    return z;
}

static void rigid_motion_removes_the_vibration(void **state) {
    (void)state;
    /* The reference sheet under 2.5 mm of rigid heave per frame. The level
     * of a bouncing strip is only known as an average, so errors are taken
     * after removing one constant for the sheet (as the reference's tables
     * should be read); the shape must improve at least twofold, per seed. */
    for (unsigned seed = 1; seed <= 3; ++seed) {
        test_sheet *t = test_sheet_make(REF_ROWS, 101, 0.0, REF_DX, 0.0, 15.0, LASER, seed);
        test_sheet_add_noise(t, VIB_SIGMA, PEAK_SIGMA, 200 + seed);
        double *plain = reconstruct_with(t, NULL, 0), *rigid = reconstruct_with(t, NULL, 1);
        double mp, sp, mr, sr;
        error_minus_constant(t, plain, &mp, &sp);
        error_minus_constant(t, rigid, &mr, &sr);
        print_message("seed %u, vibration 2.5 mm: per-fiber std %.4f max %.4f mm; "
                      "rigid_motion std %.4f max %.4f mm\n",
                      seed, sp, mp, sr, mr);
        assert_true(sr <= 0.6 * sp); /* measured 0.27 and 0.44 times */
        assert_true(mr <= 0.5 * mp);
        /* The reference's experiment 2 reached sigma 0.12 mm, max 0.35 mm. */
        assert_true(sr < 0.03 && mr < 0.15);
        free(plain);
        free(rigid);
        test_sheet_free(t);
    }
}

static void rigid_motion_is_exact_on_noise_free_data(void **state) {
    (void)state;
    test_sheet *t = test_sheet_make(REF_ROWS, REF_FIBERS, 0.0, REF_DX, 0.0, REF_PITCH, LASER, 1);
    double *zb = reconstruct_with(t, NULL, 1);
    double mx, rms;
    test_error(t, zb, 0, t->rows, &mx, &rms);
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_RIGID_MOTION, 1), FLT_OK);
    flt_recon *rc = make_recon(t->fibers, o);
    flt_options_destroy(o);
    double *zs = alloc_rows(t->rows, t->fibers);
    size_t pulled = 0;
    stream_rows(rc, t, 0, t->rows, NULL, zs, NULL, &pulled);
    finish_sheet(rc, t, zs, NULL, &pulled);
    double d = max_abs_diff(zs, zb, t->rows * t->fibers);
    print_message("rigid_motion, noise-free: batch max %.3g um, streaming vs batch %.3g um\n",
                  mx * 1e3, d * 1e3);
    assert_true(mx <= 1e-3);
    assert_true(d <= 1e-3);
    flt_recon_destroy(rc);
    free(zb);
    free(zs);
    test_sheet_free(t);
}

static void rigid_motion_tolerates_missing_samples(void **state) {
    (void)state;
    /* 10% of samples missing at random: a missing fiber enters its row's
     * line with a predicted deviation (linear in s, off by z''/2 * ds^2),
     * which costs a little shape accuracy where samples are missing. Bound:
     * 0.03 mm, a tenth of the reference's 0.35 mm under vibration. */
    const size_t K = 151;
    test_sheet *t = test_sheet_make(REF_ROWS, K, 0.0, REF_DX, 0.0, REF_PITCH, LASER, 11);
    uint8_t *valid = malloc(t->rows * K);
    test_rng rng;
    test_rng_seed(&rng, 12);
    for (size_t i = 0; i < t->rows * K; ++i)
        valid[i] = test_rng_uniform(&rng) >= 0.10;
    double *z = reconstruct_with(t, valid, 1);
    double mx, rms;
    test_error(t, z, 0, t->rows, &mx, &rms);
    print_message("rigid_motion, 10%% missing, noise-free: max %.4f mm, rms %.4f mm\n", mx, rms);
    assert_true(mx <= 0.03);
    for (size_t i = 0; i < t->rows * K; ++i)
        assert_true(isfinite(z[i]));
    free(valid);
    free(z);
    test_sheet_free(t);
}

/* ---- robust ------------------------------------------------------------ */

static double *reconstruct_modes(const test_sheet *t, int rigid, int robust) {
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_RIGID_MOTION, rigid), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_ROBUST, robust), FLT_OK);
    double *z = alloc_rows(t->rows, t->fibers);
    assert_int_equal(
        flt_reconstruct(o, t->rows, t->fibers, t->s, t->height, t->slope, NULL, z, NULL), FLT_OK);
    flt_options_destroy(o);
    return z;
}

static void robust_mode_removes_shear_transients(void **state) {
    (void)state;
    /* The article's third experiment in its physical form (model b of
     * examples/python/compare_filters.py): the reference
     * sheet, 2.5 mm rigid heave per frame, 0.5 mm eccentricity at 50 mm,
     * 1/16 px peak noise, and the shear station's ringing (50 mm envelope,
     * decay 0.07/mm, 10 mm period) after a cut every 3000 mm. No noise
     * level is given. Targets (after removing one constant for the sheet):
     * MaxAE <= 0.30 mm and STD <= 0.06 mm, against the reference's 1.15 and
     * 0.38; the plain fit is the control. 31 fibers: the transient and the
     * motion are the same on every fiber, more fibers change nothing. */
    for (unsigned seed = 1; seed <= 3; ++seed) {
        test_sheet *t = test_sheet_make(REF_ROWS, 31, 0.0, REF_DX, 0.0, 50.0, LASER, seed);
        test_sheet_add_noise(t, VIB_SIGMA, PEAK_SIGMA, 300 + seed);
        test_sheet_add_eccentricity(t, 0.5, 50.0);
        test_sheet_add_shear(t, 50.0, 0.07, 10.0, 3000.0);
        double *plain = reconstruct_modes(t, 0, 0), *robust = reconstruct_modes(t, 1, 1);
        double mp, sp, mr, sr;
        error_minus_constant(t, plain, &mp, &sp);
        error_minus_constant(t, robust, &mr, &sr);
        print_message("seed %u, shear transients: plain MaxAE %.3f STD %.4f mm; "
                      "rigid_motion + robust MaxAE %.3f STD %.4f mm\n",
                      seed, mp, sp, mr, sr);
        assert_true(mp > 0.5); /* the control: least squares follows the ringing */
        assert_true(mr <= 0.30);
        assert_true(sr <= 0.06);
        if (seed == 1) {
            /* Streamed row by row, pulled as rows finish, at the default
             * latency (2 m, 3.6 m at the strip's head): each row is judged
             * against the window's solution, which sees a lag ahead where
             * the batch passes see the whole sheet, so the bounds are the
             * targets themselves (measured 0.065 mm, 0.022 mm). */
            flt_options *o = NULL;
            assert_int_equal(flt_options_create(&o), FLT_OK);
            assert_int_equal(flt_options_set(o, FLT_OPT_RIGID_MOTION, 1), FLT_OK);
            assert_int_equal(flt_options_set(o, FLT_OPT_ROBUST, FLT_ROBUST_HUBER), FLT_OK);
            flt_recon *rc = make_recon(t->fibers, o);
            flt_options_destroy(o);
            double *zs = alloc_rows(t->rows, t->fibers);
            size_t pulled = 0;
            stream_rows(rc, t, 0, t->rows, NULL, zs, NULL, &pulled);
            finish_sheet(rc, t, zs, NULL, &pulled);
            assert_int_equal(pulled, t->rows);
            double ms, ss;
            error_minus_constant(t, zs, &ms, &ss);
            print_message("seed 1 streamed: rigid_motion + robust MaxAE %.3f STD %.4f mm\n", ms,
                          ss);
            assert_true(ms <= 0.30);
            assert_true(ss <= 0.06);
            flt_recon_destroy(rc);
            free(zs);
        }
        free(plain);
        free(robust);
        test_sheet_free(t);
    }
}

static void robust_mode_is_exact_and_streams_like_batch(void **state) {
    (void)state;
    /* On exact data the robust passes must change nothing that matters:
     * within 1 um of the truth, and the streamed output (every pass in one
     * window) within 1 um of the batch one (passes over the whole sheet).
     * Deterministic: a second run (in the workspace the first one left) is
     * bit-identical. 18 m, so that most rows come out at the lag. */
    test_sheet *t = test_sheet_make(2 * REF_ROWS, 21, 0.0, REF_DX, 0.0, 75.0, LASER, 14);
    double *zb = reconstruct_modes(t, 0, 1), *zb2 = reconstruct_modes(t, 0, 1);
    assert_memory_equal(zb, zb2, t->rows * t->fibers * sizeof(double));
    double mx, rms;
    test_error(t, zb, 0, t->rows, &mx, &rms);
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_ROBUST, FLT_ROBUST_HUBER), FLT_OK);
    flt_recon *rc = make_recon(t->fibers, o);
    flt_options_destroy(o);
    double *zs = alloc_rows(t->rows, t->fibers);
    size_t pulled = 0;
    stream_rows(rc, t, 0, t->rows, NULL, zs, NULL, &pulled);
    size_t before_end = pulled;
    finish_sheet(rc, t, zs, NULL, &pulled);
    assert_int_equal(pulled, t->rows);
    double d = max_abs_diff(zs, zb, t->rows * t->fibers);
    print_message("robust, noise-free: max error %.3g um, streaming vs batch %.3g um, "
                  "%zu rows out before end_sheet\n",
                  mx * 1e3, d * 1e3, before_end);
    assert_true(mx <= 1e-3);
    assert_true(d <= 1e-3);
    /* Latency at most 1850 mm (3.6 m at the strip's head): rows below
     * about 18000 - 1850 mm are out before end_sheet, 5383 of 6000. */
    assert_true(before_end >= 5300);
    flt_recon_destroy(rc);
    free(zb);
    free(zb2);
    free(zs);
    test_sheet_free(t);
}

static void robust_mode_with_invalid_samples_and_carry_over(void **state) {
    (void)state;
    /* Masked samples and sheet joins go through every stage: 10% invalid,
     * three sheets with carry-over, noise-free: within 1 um everywhere, and
     * every row comes out once. */
    const size_t K = 7;
    test_sheet *t = test_sheet_make(3000, K, 0.0, REF_DX, 0.0, 200.0, LASER, 15);
    uint8_t *valid = malloc(t->rows * K);
    test_rng rng;
    test_rng_seed(&rng, 16);
    for (size_t i = 0; i < t->rows * K; ++i)
        valid[i] = test_rng_uniform(&rng) >= 0.10;
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_ROBUST, FLT_ROBUST_TUKEY), FLT_OK);
    flt_recon *rc = make_recon(K, o);
    flt_options_destroy(o);
    double *z = alloc_rows(t->rows, K);
    size_t pulled = 0;
    for (int sheet = 0; sheet < 3; ++sheet) {
        stream_rows(rc, t, (size_t)sheet * 1000, (size_t)(sheet + 1) * 1000, valid, z, NULL,
                    &pulled);
        finish_sheet(rc, t, z, NULL, &pulled);
    }
    assert_int_equal(pulled, t->rows);
    double mx, rms;
    test_error(t, z, 0, t->rows, &mx, &rms);
    print_message("robust (Tukey), 10%% invalid, 3 sheets: max error %.3g um\n", mx * 1e3);
    assert_true(mx <= 1e-3);
    flt_recon_destroy(rc);
    free(valid);
    free(z);
    test_sheet_free(t);
}

static void robust_mode_takes_out_spurious_peaks(void **state) {
    (void)state;
    /* A spurious peak (a reflection the extractor let through) puts one
     * laser's reading of one fiber 2.5-5 mm off: the height takes half of
     * it, Delta-d * slope all of it, with the sign of the laser. 1% of the
     * samples, on the reference sheet with its vibration and peak noise,
     * reconstructed with rigid_motion. Least squares spreads each peak over
     * its knots; robust mode (default passes) must take them out: measured
     * 0.40 mm against 0.12 mm with 301 fibers (the figures in common.h).
     * Bounds: robust MaxAE at most half of least squares' and within 0.2 mm,
     * its STD at most 0.6 of least squares'. */
    for (unsigned seed = 1; seed <= 2; ++seed) {
        test_sheet *t = test_sheet_make(REF_ROWS, 61, 0.0, REF_DX, 0.0, 25.0, LASER, 40 + seed);
        test_sheet_add_noise(t, VIB_SIGMA, PEAK_SIGMA, 50 + seed);
        test_rng rng;
        test_rng_seed(&rng, 60 + seed);
        size_t peaks = 0;
        for (size_t i = 0; i < t->rows * t->fibers; ++i) {
            if (test_rng_uniform(&rng) >= 0.01)
                continue;
            double e =
                (2.5 + 2.5 * test_rng_uniform(&rng)) * (test_rng_uniform(&rng) < 0.5 ? -1 : 1);
            double laser = test_rng_uniform(&rng) < 0.5 ? -1.0 : 1.0; /* rear or front */
            t->height[i] += 0.5 * e;
            t->slope[i] += laser * e / LASER;
            ++peaks;
        }
        double *plain = reconstruct_modes(t, 1, 0), *robust = reconstruct_modes(t, 1, 1);
        double mp, sp, mr, sr;
        error_minus_constant(t, plain, &mp, &sp);
        error_minus_constant(t, robust, &mr, &sr);
        print_message("seed %u, %zu spurious peaks: rigid_motion MaxAE %.3f STD %.4f mm; "
                      "+ robust MaxAE %.3f STD %.4f mm\n",
                      seed, peaks, mp, sp, mr, sr);
        assert_true(mr <= 0.5 * mp);
        assert_true(mr <= 0.2);
        assert_true(sr <= 0.6 * sp); /* measured 0.27 and 0.44 times */
        free(plain);
        free(robust);
        test_sheet_free(t);
    }
}

static void robust_batch_with_a_mask_is_exact(void **state) {
    (void)state;
    /* flt_reconstruct's robust passes read the caller's mask (and, with
     * rigid_motion, take each row's line off as they read): on noise-free
     * data with 10% of the samples masked out, every masked-out sample
     * flagged, and within 1 um of the truth; with rigid_motion within
     * 0.03 mm, the bound of rigid_motion_tolerates_missing_samples (a
     * missing fiber enters its row's line with a predicted deviation). */
    const size_t K = 15;
    test_sheet *t = test_sheet_make(REF_ROWS, K, 0.0, REF_DX, 0.0, 100.0, LASER, 17);
    uint8_t *valid = malloc(t->rows * K), *flags = malloc(t->rows * K);
    assert_non_null(valid);
    assert_non_null(flags);
    test_rng rng;
    test_rng_seed(&rng, 18);
    for (size_t i = 0; i < t->rows * K; ++i)
        valid[i] = test_rng_uniform(&rng) >= 0.10;
    for (int rigid = 0; rigid <= 1; ++rigid) {
        flt_options *o = NULL;
        assert_int_equal(flt_options_create(&o), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_ROBUST, FLT_ROBUST_HUBER), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_RIGID_MOTION, rigid), FLT_OK);
        double *z = alloc_rows(t->rows, K);
        assert_int_equal(flt_reconstruct(o, t->rows, K, t->s, t->height, t->slope, valid, z, flags),
                         FLT_OK);
        flt_options_destroy(o);
        double mx, rms;
        test_error(t, z, 0, t->rows, &mx, &rms);
        size_t wrong = 0;
        for (size_t i = 0; i < t->rows * K; ++i)
            wrong += ((flags[i] & FLT_FLAG_INVALID_INPUT) != 0) != (valid[i] == 0);
        print_message("robust batch, rigid_motion %d, 10%% masked: max error %.3g um, "
                      "%zu wrong flags\n",
                      rigid, mx * 1e3, wrong);
        assert_true(mx <= (rigid ? 0.03 : 1e-3));
        assert_int_equal(wrong, 0);
        free(z);
    }
    free(valid);
    free(flags);
    test_sheet_free(t);
}

/* ---- provisional rows ------------------------------------------------ */

static void peek_is_provisional_and_changes_nothing(void **state) {
    (void)state;
    /* Every mode: one reconstructor peeks at its pending rows every 40 rows,
     * a twin never does; what they pull must be identical bit for bit
     * (peek solves the window, but nothing final may depend on it). On
     * noise-free data the provisional rows are already the spline (within
     * 1 um of the truth: the fit is exact up to the spline's own 0.25 um
     * wherever rows are, and the newest rows are measured by both lasers),
     * and each comes out of pull later with the value peek gave to within
     * 1 um. The fiber off the strip is NaN flagged in peek as in pull. */
    const size_t K = 9;
    test_sheet *t = test_sheet_make(2400, K, 0.0, REF_DX, 0.0, 150.0, LASER, 21);
    uint8_t *in_flags = calloc(t->rows * K, 1);
    for (size_t r = 0; r < t->rows; ++r)
        in_flags[r * K + 3] = FLT_FLAG_OFF_STRIP;
    for (int mode = 0; mode < 3; ++mode) {
        flt_options *o = NULL;
        assert_int_equal(flt_options_create(&o), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_RIGID_MOTION, mode == 2), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_ROBUST, mode ? FLT_ROBUST_HUBER : 0), FLT_OK);
        flt_recon *a = make_recon(K, o), *b = make_recon(K, o);
        flt_options_destroy(o);
        double *za = alloc_rows(t->rows, K), *zb = alloc_rows(t->rows, K);
        double *zp = alloc_rows(t->rows, K), *sp = malloc(t->rows * sizeof(double));
        double *peeked = alloc_rows(t->rows, K); /* the first provisional value of each row */
        uint8_t *fp = malloc(t->rows * K), *seen = calloc(t->rows, 1);
        size_t na = 0, nb = 0, n = 0, peeks = 0;
        double worst_truth = 0;
        double s_out[64];
        for (size_t r = 0; r < t->rows; ++r) {
            const double *h = t->height + r * K, *g = t->slope + r * K;
            const uint8_t *f = in_flags + r * K;
            assert_int_equal(flt_recon_push_flagged(a, 1, K, &t->s[r], h, g, f), FLT_OK);
            assert_int_equal(flt_recon_push_flagged(b, 1, K, &t->s[r], h, g, f), FLT_OK);
            do {
                assert_int_equal(flt_recon_pull(a, 64, K, s_out, za + na * K, NULL, &n), FLT_OK);
                na += n;
            } while (n == 64);
            do {
                assert_int_equal(flt_recon_pull(b, 64, K, s_out, zb + nb * K, NULL, &n), FLT_OK);
                nb += n;
            } while (n == 64);
            if (r % 40 != 39)
                continue;
            size_t pending = 0;
            assert_int_equal(flt_recon_pending(a, &pending), FLT_OK);
            assert_int_equal(pending, r + 1 - na);
            assert_int_equal(flt_recon_peek(a, t->rows, K, sp, zp, fp, &n), FLT_OK);
            assert_int_equal(n, pending);
            ++peeks;
            for (size_t i = 0; i < n; ++i) {
                const size_t row = na + i;
                assert_true(sp[i] == t->s[row]);
                for (size_t k = 0; k < K; ++k) {
                    const double v = zp[i * K + k];
                    if (k == 3) {
                        assert_true(isnan(v) && fp[i * K + k] == FLT_FLAG_OFF_STRIP);
                        continue;
                    }
                    assert_true(isfinite(v) && fp[i * K + k] == 0);
                    worst_truth = fmax(worst_truth, fabs(v - t->truth[row * K + k]));
                    if (!seen[row])
                        peeked[row * K + k] = v;
                }
                seen[row] = 1;
            }
        }
        finish_sheet(a, t, za, NULL, &na);
        finish_sheet(b, t, zb, NULL, &nb);
        assert_int_equal(na, t->rows);
        assert_int_equal(nb, t->rows);
        assert_memory_equal(za, zb, t->rows * K * sizeof(double));
        double worst_final = 0;
        for (size_t row = 0; row < t->rows; ++row)
            for (size_t k = 0; seen[row] && k < K; ++k)
                if (k != 3)
                    worst_final = fmax(worst_final, fabs(peeked[row * K + k] - za[row * K + k]));
        print_message("mode %d: %zu peeks, provisional rows within %.3g um of the truth and "
                      "%.3g um of their final values; pulls identical\n",
                      mode, peeks, worst_truth * 1e3, worst_final * 1e3);
        assert_true(worst_truth <= 1e-3);
        assert_true(worst_final <= 1e-3);
        flt_recon_destroy(a);
        flt_recon_destroy(b);
        free(za), free(zb), free(zp), free(sp), free(peeked), free(fp), free(seen);
    }
    free(in_flags);
    test_sheet_free(t);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(noise_free_reference_sheet_within_1um),
        cmocka_unit_test(irregular_encoder_jitter_within_1um),
        cmocka_unit_test(streaming_equals_batch_noise_free),
        cmocka_unit_test(streaming_rms_within_5pct_of_batch_noisy),
        cmocka_unit_test(carry_over_sheets_join_c1),
        cmocka_unit_test(invalid_samples_and_gap_are_bridged_and_flagged),
        cmocka_unit_test(dead_fiber_is_nan_and_does_not_touch_others),
        cmocka_unit_test(height_only_or_slope_only_samples_are_used),
        cmocka_unit_test(reset_starts_a_fresh_strip),
        cmocka_unit_test(buffer_full_then_pull_recovers),
        cmocka_unit_test(buffer_full_with_nothing_finished_says_why),
        cmocka_unit_test(robust_streaming_with_rows_sparser_than_knots),
        cmocka_unit_test(absurd_values_are_invalid_samples),
        cmocka_unit_test(slopes_before_heights_with_close_lasers_stay_finite),
        cmocka_unit_test(bad_input_is_rejected_and_handle_stays_usable),
        cmocka_unit_test(options_are_reported_back),
        cmocka_unit_test(finer_knots_than_laser_spacing_stay_exact),
        cmocka_unit_test(rigid_motion_removes_the_vibration),
        cmocka_unit_test(rigid_motion_is_exact_on_noise_free_data),
        cmocka_unit_test(rigid_motion_tolerates_missing_samples),
        cmocka_unit_test(robust_mode_removes_shear_transients),
        cmocka_unit_test(robust_mode_is_exact_and_streams_like_batch),
        cmocka_unit_test(robust_mode_with_invalid_samples_and_carry_over),
        cmocka_unit_test(robust_mode_takes_out_spurious_peaks),
        cmocka_unit_test(robust_batch_with_a_mask_is_exact),
        cmocka_unit_test(peek_is_provisional_and_changes_nothing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
