// SPDX-License-Identifier: Apache-2.0
/*
 * Simulated sensor: the sheet model, the two-laser operators of the profile
 * rows, the motion and noise model against independent formulas, rendered
 * frames against the calibration, determinism and bad input.
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

#define assert_near(a, b, tol)                                                 \
  do {                                                                         \
    const double a_ = (a), b_ = (b);                                           \
    if (!(fabs(a_ - b_) <= (tol)))                                             \
      fail_msg("%s = %.17g, expected %.17g +- %g", #a, a_, b_, (double)(tol)); \
  } while (0)

/* The reference sensor's rows 892..1147: both lines and +-50 mm of height
 * (0.48 px/mm) fit, and a frame costs an eighth of the full sensor's. */
#define ROI_FIRST 892
#define ROI_ROWS  256

static flt_calib *reference(size_t fibers, double pitch, uint32_t first, uint32_t rows) {
    flt_calib *calib = NULL;
    const double first_x = -0.5 * pitch * (double)(fibers - 1);
    assert_int_equal(flt_calib_create_reference(first, rows, first_x, pitch, fibers, &calib),
                     FLT_OK);
    return calib;
}

static flt_options *options_with(int n, const flt_option *keys, const double *values) {
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    for (int i = 0; i < n; ++i)
        assert_int_equal(flt_options_set(o, keys[i], values[i]), FLT_OK);
    return o;
}

static flt_sim *make_sim(flt_calib *calib, int n, const flt_option *keys, const double *values) {
    flt_options *o = options_with(n, keys, values);
    flt_sim *sim = NULL;
    assert_int_equal(flt_sim_create(calib, o, &sim), FLT_OK);
    flt_options_destroy(o);
    return sim;
}

typedef struct rows_t {
    size_t rows, fibers;
    double *e, *s, *h, *g, *truth;
    uint8_t *valid;
} rows_t;

static rows_t next_rows(flt_sim *sim, size_t rows) {
    rows_t r;
    r.rows = rows;
    assert_int_equal(flt_sim_fibers(sim, &r.fibers), FLT_OK);
    const size_t n = rows * r.fibers;
    r.e = malloc(rows * sizeof(double));
    r.s = malloc(rows * sizeof(double));
    r.h = malloc(n * sizeof(double));
    r.g = malloc(n * sizeof(double));
    r.truth = malloc(n * sizeof(double));
    r.valid = malloc(n);
    assert_int_equal(flt_sim_next_rows(sim, rows, r.fibers, r.e, r.s, r.h, r.g, r.valid, r.truth),
                     FLT_OK);
    return r;
}

static void free_rows(rows_t *r) {
    free(r->e), free(r->s), free(r->h), free(r->g), free(r->truth), free(r->valid);
}

static double sheet_at(const flt_sim *sim, double x, double s) {
    double z;
    assert_int_equal(flt_sim_surface(sim, 1, &x, &s, &z), FLT_OK);
    return z;
}

/* ------------------------------------------------------------------ tests */

/* The defect shapes at their defining points (sim.h): exact up to rounding. */
static void defect_shapes_match_their_definition(void **state) {
    (void)state;
    flt_sim *sim = make_sim(NULL, 0, NULL, NULL); /* W = 2000 mm */
    const double P = 1800, A = 12;
    struct {
        flt_sim_defect kind;
        double x, expect; /* at s = P/4 (sine = 1) */
    } cases[] = {
        {FLT_SIM_CENTRE_BUCKLE, 0, A},
        {FLT_SIM_CENTRE_BUCKLE, 1000, 0},
        {FLT_SIM_WAVY_EDGE_LEFT, -1000, A},
        {FLT_SIM_WAVY_EDGE_LEFT, 1000, 0},
        {FLT_SIM_WAVY_EDGE_RIGHT, 1000, A},
        {FLT_SIM_WAVY_EDGE_RIGHT, -500, 0},
        {FLT_SIM_WAVY_EDGE_BOTH, -1000, A},
        {FLT_SIM_WAVY_EDGE_BOTH, 500, A / 16},
        {FLT_SIM_QUARTER_BUCKLE, 500, A},
        {FLT_SIM_QUARTER_BUCKLE, -500, A},
        {FLT_SIM_BOW, 123, A},
        {FLT_SIM_CROSSBOW, 1000, A},
        {FLT_SIM_CROSSBOW, 500, A / 4},
        {FLT_SIM_FLAT, 10, 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        assert_int_equal(flt_sim_clear_sheet(sim), FLT_OK);
        assert_int_equal(flt_sim_add_defect(sim, cases[i].kind, A, P), FLT_OK);
        assert_near(sheet_at(sim, cases[i].x, P / 4), cases[i].expect, 1e-12);
        assert_near(sheet_at(sim, cases[i].x, P / 2), 0, 1e-11); /* sine node */
    }
    /* Defects add up; period 0 is constant along travel. */
    assert_int_equal(flt_sim_clear_sheet(sim), FLT_OK);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CROSSBOW, 2, 0), FLT_OK);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_BOW, 3, 4000), FLT_OK);
    assert_near(sheet_at(sim, 1000, 1000), 2 + 3, 1e-12);
    assert_near(sheet_at(sim, 1000, 3000), 2 - 3, 1e-12);
    flt_sim_destroy(sim);
}

/* A user height map is reproduced at its nodes exactly and bilinearly between
 * them (a bilinear function is reproduced everywhere: 1e-12). */
static void height_map_is_bilinear(void **state) {
    (void)state;
    flt_sim *sim = make_sim(NULL, 0, NULL, NULL);
    enum { R = 4, C = 5 };
    double map[R * C];
    for (int r = 0; r < R; ++r)
        for (int c = 0; c < C; ++c)
            map[r * C + c] = 0.5 * r - 0.25 * c + 0.1 * r * c;
    assert_int_equal(flt_sim_set_height_map(sim, R, C, 100, 10, -20, 5, map), FLT_OK);
    for (double s = 100; s <= 130; s += 2.5)
        for (double x = -20; x <= 0; x += 1.25) {
            const double r = (s - 100) / 10, c = (x + 20) / 5;
            assert_near(sheet_at(sim, x, s), 0.5 * r - 0.25 * c + 0.1 * r * c, 1e-12);
        }
    /* Outside: clamped to the edge. */
    assert_near(sheet_at(sim, -1000, 100), map[0], 1e-12);
    flt_sim_destroy(sim);
}

/* Noise-free profile rows are exactly the two-laser operators of the sheet:
 * height = mean of the surface at s -+ 50 mm, slope = secant over 100 mm, at
 * s = e for the reference offsets +-50; truth = surface at s. 1e-12 mm is
 * rounding. */
static void rows_are_the_two_laser_operators(void **state) {
    (void)state;
    flt_calib *calib = reference(101, 20, 0, 2048);
    const flt_option keys[] = {FLT_OPT_SIM_START, FLT_OPT_SIM_FRAME_SPACING};
    const double values[] = {1000, 3};
    flt_sim *sim = make_sim(calib, 2, keys, values);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 12, 1800), FLT_OK);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_LEFT, 5, 700), FLT_OK);
    rows_t r = next_rows(sim, 200);
    for (size_t i = 0; i < r.rows; ++i) {
        assert_near(r.e[i], 1000 + 3.0 * (double)i, 1e-9);
        assert_near(r.s[i], r.e[i], 1e-9);
        for (size_t k = 0; k < r.fibers; ++k) {
            const double x = -1000 + 20.0 * (double)k;
            const double ahead = sheet_at(sim, x, r.s[i] + 50);
            const double behind = sheet_at(sim, x, r.s[i] - 50);
            assert_near(r.h[i * r.fibers + k], 0.5 * (ahead + behind), 1e-12);
            assert_near(r.g[i * r.fibers + k], (ahead - behind) / 100, 1e-14);
            assert_near(r.truth[i * r.fibers + k], sheet_at(sim, x, r.s[i]), 1e-12);
            assert_int_equal(r.valid[i * r.fibers + k], 1);
        }
    }
    free_rows(&r);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

/* Rigid heave and roll move both lasers together: the slope is untouched
 * (1e-12) while the height moves by heave + tilt * x + eccentricity, whose
 * sample standard deviation over 4000 frames is within 5 % of the set
 * sigma (the estimate's relative error is 1/sqrt(2 * 4000) = 1.1 %, so 5 %
 * is over 4 sigma). The eccentricity term is checked exactly with heave and
 * tilt off. */
static void motion_is_rigid_and_has_the_set_statistics(void **state) {
    (void)state;
    flt_calib *calib = reference(41, 50, 0, 2048);
    const flt_option keys[] = {FLT_OPT_SIM_HEAVE_SIGMA, FLT_OPT_SIM_TILT_SIGMA};
    const double values[] = {2.5, 0.001};
    flt_sim *clean = make_sim(calib, 0, NULL, NULL);
    flt_sim *moving = make_sim(calib, 2, keys, values);
    assert_int_equal(flt_sim_add_defect(clean, FLT_SIM_QUARTER_BUCKLE, 6, 900), FLT_OK);
    assert_int_equal(flt_sim_add_defect(moving, FLT_SIM_QUARTER_BUCKLE, 6, 900), FLT_OK);
    enum { N = 4000 };
    rows_t a = next_rows(clean, N), b = next_rows(moving, N);
    const size_t n = a.fibers, centre = n / 2;
    double sum = 0, sum2 = 0, tsum = 0, tsum2 = 0;
    for (size_t i = 0; i < N; ++i) {
        for (size_t k = 0; k < n; ++k)
            assert_near(b.g[i * n + k], a.g[i * n + k], 1e-12);
        const double d = b.h[i * n + centre] - a.h[i * n + centre]; /* x = 0: heave */
        /* the edge fiber minus the centre: tilt * x at x = 1000 */
        const double t = (b.h[i * n + n - 1] - a.h[i * n + n - 1] - d) / 1000;
        sum += d, sum2 += d * d, tsum += t, tsum2 += t * t;
    }
    assert_near(sqrt(sum2 / N - (sum / N) * (sum / N)), 2.5, 0.05 * 2.5);
    assert_near(sqrt(tsum2 / N - (tsum / N) * (tsum / N)), 0.001, 0.05 * 0.001);
    free_rows(&a), free_rows(&b);
    flt_sim_destroy(moving);

    const flt_option ekeys[] = {FLT_OPT_SIM_ECCENTRICITY_AMPLITUDE, FLT_OPT_SIM_ECCENTRICITY_PERIOD,
                                FLT_OPT_SIM_START};
    const double evalues[] = {0.5, 50, 7};
    flt_sim *ecc = make_sim(calib, 3, ekeys, evalues);
    flt_sim *ref = make_sim(calib, 1, ekeys + 2, evalues + 2);
    a = next_rows(ref, 300), b = next_rows(ecc, 300);
    for (size_t i = 0; i < 300; ++i)
        for (size_t k = 0; k < n; ++k) {
            assert_near(b.h[i * n + k] - a.h[i * n + k], 0.5 * sin(2 * PI * b.e[i] / 50), 1e-12);
            assert_near(b.g[i * n + k], a.g[i * n + k], 1e-15);
        }
    free_rows(&a), free_rows(&b);
    flt_sim_destroy(ecc), flt_sim_destroy(ref), flt_sim_destroy(clean);
    flt_calib_destroy(calib);
}

/* Shear transients travel with the strip: each laser sees the damped sine of
 * its own material position. Against the formula of sim.h written out here
 * (reference constants, a cut every 1000 mm): 1e-10 mm (the library drops a
 * cut once its envelope is below 50 exp(-30) = 5e-12 mm). */
static double shear_formula(double s) {
    double z = 0;
    for (double cut = floor(s / 1000) * 1000; s - cut < 600; cut -= 1000) {
        const double d = s - cut;
        z += 50 * exp(-0.07 * d) * sin(2 * PI * d / 10);
    }
    return z;
}

static void shear_transient_is_seen_at_each_lasers_material_position(void **state) {
    (void)state;
    flt_calib *calib = reference(11, 100, 0, 2048);
    const flt_option keys[] = {FLT_OPT_SIM_SHEAR_AMPLITUDE, FLT_OPT_SIM_SHEAR_INTERVAL,
                               FLT_OPT_SIM_FRAME_SPACING};
    const double values[] = {50, 1000, 0.7};
    flt_sim *sim = make_sim(calib, 3, keys, values);
    rows_t r = next_rows(sim, 3000); /* 2100 mm: two cuts */
    double biggest = 0;
    for (size_t i = 0; i < r.rows; ++i) {
        const double ahead = shear_formula(r.s[i] + 50), behind = shear_formula(r.s[i] - 50);
        assert_near(r.h[i * r.fibers + 3], 0.5 * (ahead + behind), 1e-10);
        assert_near(r.g[i * r.fibers + 3], (ahead - behind) / 100, 1e-12);
        if (fabs(r.h[i * r.fibers]) > biggest)
            biggest = fabs(r.h[i * r.fibers]);
    }
    /* It is really there: half of an envelope of 50 mm near a cut. */
    assert_true(biggest > 15);
    free_rows(&r);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

/* Peak noise is independent per laser: with sigma_px px, each laser's z gets
 * sigma_px * dz/dv mm, so the slope's standard deviation is
 * sqrt(2) sigma_px dz/dv / 100 and the height's sigma_px dz/dv / sqrt(2).
 * dz/dv comes from the calibration here. 20000 samples: 5 % is > 7 sigma. */
static void peak_noise_has_the_set_sigma_per_laser(void **state) {
    (void)state;
    flt_calib *calib = reference(21, 10, 0, 2048);
    const flt_option keys[] = {FLT_OPT_SIM_PEAK_SIGMA};
    const double values[] = {1.0 / 16};
    flt_sim *sim = make_sim(calib, 1, keys, values);
    rows_t r = next_rows(sim, 1000);
    /* dz/dv at x = 0 (fiber 10), laser 0 and laser 1 */
    double dzdv[2];
    for (unsigned laser = 0; laser < 2; ++laser) {
        double p[2] = {0, 0}, img[2];
        assert_int_equal(flt_calib_plane_to_image(calib, laser, 1, p, img), FLT_OK);
        img[1] += 1;
        assert_int_equal(flt_calib_image_to_plane(calib, laser, 1, img, p), FLT_OK);
        dzdv[laser] = fabs(p[1]);
    }
    double h2 = 0, g2 = 0;
    size_t count = 0;
    for (size_t i = 0; i < r.rows; ++i)
        for (size_t k = 0; k < r.fibers; ++k, ++count) {
            const double dh = r.h[i * r.fibers + k] - 0, dg = r.g[i * r.fibers + k];
            h2 += dh * dh, g2 += dg * dg;
        }
    const double var = (dzdv[0] * dzdv[0] + dzdv[1] * dzdv[1]) / (16.0 * 16.0);
    /* per-fiber dz/dv varies by a few % across the width; use the centre's */
    assert_near(sqrt(h2 / count), 0.5 * sqrt(var), 0.08 * 0.5 * sqrt(var));
    assert_near(sqrt(g2 / count), sqrt(var) / 100, 0.08 * sqrt(var) / 100);
    free_rows(&r);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

/* Rendered frames: the reported line centre of each column maps back through
 * the calibration onto the laser's surface (z within 2e-3 mm, the polyline
 * interpolation at half a column), and without speckle and shot noise the
 * pixel nearest the centre holds background + the Gaussian (within 0.5
 * count of rounding). */
static void frames_draw_the_lines_where_the_calibration_says(void **state) {
    (void)state;
    flt_calib *calib = reference(101, 20, ROI_FIRST, ROI_ROWS);
    const flt_option keys[] = {FLT_OPT_SIM_SPECKLE, FLT_OPT_SIM_FULL_WELL, FLT_OPT_SIM_START};
    const double values[] = {0, 0, 321};
    flt_sim *sim = make_sim(calib, 3, keys, values);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 12, 1800), FLT_OK);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CROSSBOW, -4, 0), FLT_OK);
    uint32_t w, h;
    assert_int_equal(flt_sim_frame_size(sim, &w, &h), FLT_OK);
    assert_int_equal(w, 2048);
    assert_int_equal(h, ROI_ROWS);
    uint8_t *frame = malloc((size_t)w * h);
    double *peaks = malloc(2 * w * sizeof(double));
    double e;
    assert_int_equal(
        flt_sim_next_frame(sim, frame, (size_t)w * h, w, &e, 0, NULL, peaks, 2 * (size_t)w),
        FLT_OK);
    assert_near(e, 321, 1e-12);
    size_t checked = 0;
    for (unsigned laser = 0; laser < 2; ++laser) {
        const double offset = laser == 0 ? -50 : 50;
        for (uint32_t u = 2; u < w - 2; u += 7) {
            const double v = peaks[laser * w + u];
            assert_true(v == v); /* the whole width is in the frame */
            double pt[2] = {u, v};
            assert_int_equal(flt_calib_image_to_plane(calib, laser, 1, pt, pt), FLT_OK);
            assert_near(pt[1], sheet_at(sim, pt[0], e - offset), 2e-3);
            const int row = (int)lround(v);
            const double d = row - v;
            const double expect = 0.03 * 255 + 0.6 * 255 * exp(-d * d / 8);
            assert_near(frame[(size_t)row * w + u], expect, 0.5 + 1e-9);
            ++checked;
        }
    }
    assert_true(checked > 500);
    free(frame), free(peaks);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

/* What real photos show besides, rendered as sim.h says, noise-free (no
 * speckle, no shot noise) so that every checked pixel is the formula to
 * its rounding (0.5 counts): a line of peak 0.6 and sigma 2 px over a
 * background of 0.03 of full scale, under a 12 mm centre buckle and a
 * -4 mm crossbow.
 *   depth of field 10 mm: sigma grows by g = sqrt(1 + (z / 10)^2), z the
 *     line's height there, and the peak falls by g;
 *   dark patches 0.5: each column's line carries a reflectance r, 1 or in
 *     [0.15, 0.5], measured as (pixel - background) / (peak profile); the
 *     dark share of the columns 0.5 within 0.15 (cells 60 mm across and
 *     150 mm along: about 30 cells per line and frame, 8 lines);
 *   gamma 2.2: a pixel reads full scale times (I / full scale)^(1 / 2.2). */
static void field_effects_render_as_documented(void **state) {
    (void)state;
    flt_calib *calib = reference(101, 20, ROI_FIRST, ROI_ROWS);
    for (int effect = 0; effect < 3; ++effect) {
        const flt_option keys[] = {FLT_OPT_SIM_SPECKLE, FLT_OPT_SIM_FULL_WELL, FLT_OPT_SIM_START,
                                   effect == 0   ? FLT_OPT_SIM_DEPTH_OF_FIELD
                                   : effect == 1 ? FLT_OPT_SIM_DARK_PATCHES
                                                 : FLT_OPT_SIM_GAMMA};
        const double values[] = {0, 0, 321, effect == 0 ? 10 : effect == 1 ? 0.5 : 2.2};
        flt_sim *sim = make_sim(calib, 4, keys, values);
        assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 12, 1800), FLT_OK);
        assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CROSSBOW, -4, 0), FLT_OK);
        const uint32_t w = 2048;
        uint8_t *frame = malloc((size_t)w * ROI_ROWS);
        double *peaks = malloc(2 * w * sizeof(double));
        size_t checked = 0, dark = 0;
        double widest = 1;
        for (int f = 0; f < 4; ++f) {
            double e;
            assert_int_equal(flt_sim_next_frame(sim, frame, (size_t)w * ROI_ROWS, w, &e, 0, NULL,
                                                peaks, 2 * (size_t)w),
                             FLT_OK);
            for (unsigned laser = 0; laser < 2; ++laser)
                for (uint32_t u = 2; u < w - 2; u += 7) {
                    const double v = peaks[laser * w + u];
                    assert_true(v == v);
                    double pt[2] = {u, v};
                    assert_int_equal(flt_calib_image_to_plane(calib, laser, 1, pt, pt), FLT_OK);
                    const double z = pt[1];
                    const int row = (int)lround(v);
                    const double d = row - v;
                    const double pixel = frame[(size_t)row * w + u];
                    const double bg = 0.03 * 255;
                    if (effect == 0) {
                        const double g = sqrt(1 + (z / 10) * (z / 10));
                        widest = fmax(widest, g);
                        assert_near(pixel, bg + 0.6 * 255 / g * exp(-d * d / (8 * g * g)),
                                    0.5 + 1e-9);
                    } else if (effect == 1) {
                        const double line = 0.6 * 255 * exp(-d * d / 8);
                        const double r = (pixel - bg) / line, slack = 0.5 / line + 1e-9;
                        if (fabs(r - 1) <= slack)
                            continue;
                        assert_true(r >= 0.15 - slack && r <= 0.5 + slack);
                        ++dark;
                    } else {
                        const double linear = bg + 0.6 * 255 * exp(-d * d / 8);
                        assert_near(pixel, 255 * pow(linear / 255, 1 / 2.2), 0.5 + 1e-4);
                    }
                    ++checked;
                }
        }
        if (effect == 0) {
            print_message("depth of field 10 mm: the line up to %.2f times as wide\n", widest);
            assert_true(widest > 1.3); /* the buckle takes the line out of focus */
        }
        if (effect == 1) {
            const size_t all = 4 * 2 * ((w - 4 + 6) / 7);
            print_message("dark patches 0.5: %zu of %zu columns dark\n", dark, all);
            assert_near((double)dark / (double)all, 0.5, 0.15);
        }
        assert_true(checked > 500);
        free(frame), free(peaks);
        flt_sim_destroy(sim);
    }
    flt_calib_destroy(calib);
}

/* Ambient light on the strip (sim.h), noise-free as above, the strip
 * filling the view, a background of 0.03 and ambient 0.2 of full scale.
 * Away from the lines (12 rows: 6 line sigmas) a pixel reads background +
 * 0.2 * r of full scale, r the strip's reflectance there:
 *   ambient alone: r = 1 everywhere, to the pixel's rounding (0.5 counts);
 *   texture 0.3: r uniform in [0.7, 1.3] per 2 mm cell: every r inside,
 *     their mean 1 and standard deviation 0.3 / sqrt(3) = 0.173, each
 *     within 0.02 (thousands of cells; a row is about 2 mm of strip);
 *   dark patches 0.5: r = 1 or in [0.15, 0.5], the dark share of the
 *     pixels 0.5 within 0.15 (about 30 cells 60 x 150 mm per frame). */
static void ambient_light_renders_as_documented(void **state) {
    (void)state;
    flt_calib *calib = reference(101, 20, ROI_FIRST, ROI_ROWS);
    for (int effect = 0; effect < 3; ++effect) {
        const flt_option keys[] = {FLT_OPT_SIM_SPECKLE, FLT_OPT_SIM_FULL_WELL, FLT_OPT_SIM_START,
                                   FLT_OPT_SIM_AMBIENT,
                                   effect == 2 ? FLT_OPT_SIM_DARK_PATCHES : FLT_OPT_SIM_TEXTURE};
        const double values[] = {0, 0, 321, 0.2, effect == 0 ? 0 : effect == 1 ? 0.3 : 0.5};
        flt_sim *sim = make_sim(calib, 5, keys, values);
        const uint32_t w = 2048;
        uint8_t *frame = malloc((size_t)w * ROI_ROWS);
        double *peaks = malloc(2 * w * sizeof(double));
        size_t checked = 0, dark = 0;
        double sum = 0, sum2 = 0;
        const double bg = 0.03 * 255, ambient = 0.2 * 255, slack = 0.5 / ambient + 1e-9;
        for (int f = 0; f < 4; ++f) {
            double e;
            assert_int_equal(flt_sim_next_frame(sim, frame, (size_t)w * ROI_ROWS, w, &e, 0, NULL,
                                                peaks, 2 * (size_t)w),
                             FLT_OK);
            for (uint32_t u = 2; u < w - 2; u += 7) {
                const double v0 = peaks[u], v1 = peaks[w + u];
                assert_true(v0 == v0 && v1 == v1);
                for (long v = 0; v < ROI_ROWS; v += 3) {
                    if (fabs((double)v - v0) < 12 || fabs((double)v - v1) < 12)
                        continue;
                    const double r = (frame[(size_t)v * w + u] - bg) / ambient;
                    if (effect == 0) {
                        assert_near(r, 1.0, slack);
                    } else if (effect == 1) {
                        assert_true(r >= 0.7 - slack && r <= 1.3 + slack);
                        sum += r, sum2 += r * r;
                    } else if (fabs(r - 1) > slack) {
                        assert_true(r >= 0.15 - slack && r <= 0.5 + slack);
                        ++dark;
                    }
                    ++checked;
                }
            }
        }
        assert_true(checked > 10000);
        if (effect == 1) {
            const double mean = sum / (double)checked;
            const double sd = sqrt(sum2 / (double)checked - mean * mean);
            print_message("texture 0.3: reflectance mean %.4f, sd %.4f (uniform: 1, %.4f)\n", mean,
                          sd, 0.3 / sqrt(3));
            assert_near(mean, 1.0, 0.02);
            assert_near(sd, 0.3 / sqrt(3), 0.02);
        }
        if (effect == 2) {
            print_message("dark patches 0.5 under ambient light: %zu of %zu pixels dark\n", dark,
                          checked);
            assert_near((double)dark / (double)checked, 0.5, 0.15);
        }
        free(frame), free(peaks);
        flt_sim_destroy(sim);
    }
    flt_calib_destroy(calib);
}

/* The same seed gives the same bytes (rows and 8- and 16-bit frames), also
 * after rewind; another seed does not. */
static void same_seed_same_bytes(void **state) {
    (void)state;
    flt_calib *calib = reference(101, 20, ROI_FIRST, ROI_ROWS);
    for (int depth = 8; depth <= 16; depth += 8) {
        const flt_option keys[] = {FLT_OPT_SIM_HEAVE_SIGMA, FLT_OPT_SIM_PEAK_SIGMA,
                                   FLT_OPT_SIM_REFLECTIONS, FLT_OPT_SIM_BIT_DEPTH,
                                   FLT_OPT_SIM_SEED};
        double values[] = {2.5, 0.0625, 5, depth, 7};
        flt_sim *a = make_sim(calib, 5, keys, values);
        flt_sim *b = make_sim(calib, 5, keys, values);
        values[4] = 8;
        flt_sim *c = make_sim(calib, 5, keys, values);
        const size_t bytes = 2048 * ROI_ROWS * (depth / 8);
        uint8_t *fa = malloc(bytes), *fb = malloc(bytes), *fc = malloc(bytes);
        for (int f = 0; f < 3; ++f) {
            assert_int_equal(
                flt_sim_next_frame(a, fa, bytes, 2048 * (depth / 8), NULL, 0, NULL, NULL, 0),
                FLT_OK);
            assert_int_equal(
                flt_sim_next_frame(b, fb, bytes, 2048 * (depth / 8), NULL, 0, NULL, NULL, 0),
                FLT_OK);
            assert_int_equal(
                flt_sim_next_frame(c, fc, bytes, 2048 * (depth / 8), NULL, 0, NULL, NULL, 0),
                FLT_OK);
            assert_memory_equal(fa, fb, bytes);
            assert_memory_not_equal(fa, fc, bytes);
        }
        rows_t ra = next_rows(a, 50), rb = next_rows(b, 50);
        assert_memory_equal(ra.h, rb.h, 50 * ra.fibers * sizeof(double));
        assert_memory_equal(ra.g, rb.g, 50 * ra.fibers * sizeof(double));
        /* rewind: frame 0 again */
        assert_int_equal(flt_sim_rewind(a), FLT_OK);
        assert_int_equal(flt_sim_rewind(b), FLT_OK);
        assert_int_equal(
            flt_sim_next_frame(a, fa, bytes, 2048 * (depth / 8), NULL, 0, NULL, NULL, 0), FLT_OK);
        assert_int_equal(flt_sim_rewind(b), FLT_OK);
        assert_int_equal(
            flt_sim_next_frame(b, fb, bytes, 2048 * (depth / 8), NULL, 0, NULL, NULL, 0), FLT_OK);
        assert_memory_equal(fa, fb, bytes);
        free_rows(&ra), free_rows(&rb);
        free(fa), free(fb), free(fc);
        flt_sim_destroy(a), flt_sim_destroy(b), flt_sim_destroy(c);
    }
    flt_calib_destroy(calib);
}

static void expect_error(flt_status st, flt_status code, const char *needle) {
    assert_int_equal(st, code);
    if (!strstr(flt_last_error_message(), needle))
        fail_msg("message '%s' lacks '%s'", flt_last_error_message(), needle);
}

/* Bad input: the status, a message naming the argument, and a handle that
 * still works afterwards. */
static void bad_input_is_rejected_by_name(void **state) {
    (void)state;
    flt_calib *calib = reference(11, 100, ROI_FIRST, ROI_ROWS);
    flt_sim *sim = make_sim(calib, 0, NULL, NULL);
    flt_sim *none = NULL;
    double d[16];
    uint8_t frame[64];
    expect_error(flt_sim_create(calib, NULL, NULL), FLT_ERR_INVALID_ARGUMENT, "'out'");
    expect_error(flt_sim_add_defect(NULL, FLT_SIM_BOW, 1, 1), FLT_ERR_INVALID_ARGUMENT, "'sim'");
    expect_error(flt_sim_add_defect(sim, (flt_sim_defect)99, 1, 1), FLT_ERR_INVALID_ARGUMENT,
                 "'kind' = 99");
    expect_error(flt_sim_add_defect(sim, FLT_SIM_BOW, NAN, 1), FLT_ERR_INVALID_ARGUMENT,
                 "'amplitude_mm'");
    expect_error(flt_sim_add_defect(sim, FLT_SIM_BOW, 1, -5), FLT_ERR_INVALID_ARGUMENT,
                 "'period_mm' = -5");
    expect_error(flt_sim_next_rows(sim, 1, 12, d, d, d, d, NULL, NULL), FLT_ERR_INVALID_ARGUMENT,
                 "'fibers' = 12");
    expect_error(flt_sim_next_rows(sim, 1, 11, d, NULL, d, d, NULL, NULL), FLT_ERR_INVALID_ARGUMENT,
                 "'s_out'");
    expect_error(flt_sim_next_frame(sim, frame, sizeof frame, 2047, NULL, 0, NULL, NULL, 0),
                 FLT_ERR_INVALID_ARGUMENT, "'stride_bytes' = 2047");
    expect_error(flt_sim_next_frame(sim, frame, sizeof frame, 2048, NULL, 0, NULL, NULL, 0),
                 FLT_ERR_INVALID_ARGUMENT, "'capacity_bytes' = 64");
    expect_error(flt_sim_set_height_map(sim, 1, 5, 0, 1, 0, 1, d), FLT_ERR_INVALID_ARGUMENT,
                 "'rows' = 1");
    double map[4] = {0, 1, NAN, 3};
    expect_error(flt_sim_set_height_map(sim, 2, 2, 0, 1, 0, 1, map), FLT_ERR_INVALID_ARGUMENT,
                 "'heights[2]'");
    expect_error(flt_sim_set_height_map(sim, 2, 2, 0, 0, 0, 1, map), FLT_ERR_INVALID_ARGUMENT,
                 "'ds_mm' = 0");
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    expect_error(flt_options_set(o, FLT_OPT_SIM_SPECKLE, NAN), FLT_ERR_INVALID_ARGUMENT,
                 "'sim_speckle' is NaN");
    assert_int_equal(flt_options_set(o, FLT_OPT_SIM_BIT_DEPTH, 9), FLT_OK);
    expect_error(flt_sim_create(calib, o, &none), FLT_ERR_INVALID_ARGUMENT, "'sim_bit_depth' = 9");
    assert_null(none);
    flt_options_destroy(o);
    flt_calib *cnone = NULL;
    expect_error(flt_calib_create_reference(2000, 100, 0, 1, 1, &cnone), FLT_ERR_INVALID_ARGUMENT,
                 "'first_row' = 2000");
    expect_error(flt_calib_create_reference(0, 100, 0, NAN, 1, &cnone), FLT_ERR_INVALID_ARGUMENT,
                 "'pitch_mm'");
    assert_null(cnone);
    /* still usable, and the message clears on success */
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_BOW, 1, 1000), FLT_OK);
    assert_string_equal(flt_last_error_message(), "");
    double s[1], h[11], g[11];
    assert_int_equal(flt_sim_next_rows(sim, 1, 11, NULL, s, h, g, NULL, NULL), FLT_OK);
    flt_sim_destroy(NULL);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(defect_shapes_match_their_definition),
        cmocka_unit_test(height_map_is_bilinear),
        cmocka_unit_test(rows_are_the_two_laser_operators),
        cmocka_unit_test(motion_is_rigid_and_has_the_set_statistics),
        cmocka_unit_test(shear_transient_is_seen_at_each_lasers_material_position),
        cmocka_unit_test(peak_noise_has_the_set_sigma_per_laser),
        cmocka_unit_test(frames_draw_the_lines_where_the_calibration_says),
        cmocka_unit_test(field_effects_render_as_documented),
        cmocka_unit_test(ambient_light_renders_as_documented),
        cmocka_unit_test(same_seed_same_bytes),
        cmocka_unit_test(bad_input_is_rejected_by_name),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
