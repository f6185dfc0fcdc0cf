// SPDX-License-Identifier: Apache-2.0
/*
 * The line in the field: the simulator's strip (width, lateral wander,
 * coils with heads and tails, the roller table, glints at the edges, lines
 * brighter than full scale), the extractor's strip edges, fiber flags and
 * saturated peaks on rendered frames, and the reconstructor passing the
 * off-strip flag through. Every figure is measured against the simulator's
 * ground truth (flt_sim_strip_edges, flt_sim_fiber_flags, flt_sim_surface).
 *
 * The sensor: the reference camera (flatline/sim.h) with a fiber grid of
 * 1251 fibers at 2 mm, x = -1250 .. 1250 mm (sized for strips up to
 * 2300 mm), reading out rows 892 .. 1147 (both lines and the roller table's
 * line of laser 1, 300 mm below the pass line at row 1121, which lies in
 * laser 0's band: the extractor must tell it from the strip by its height).
 *
 * Reference noise (docs/sensor.md): 2.5 mm rigid heave per frame, 0.5 mm roll
 * eccentricity at 50 mm, 1/16 px peak noise, the simulator's default speckle
 * (5 % per pixel) and shot noise (10000 e- well), 8-bit pixels.
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
#include "sweep.h"

#define W           2048
#define ROI_FIRST   892
#define ROI_ROWS    256
#define FIBERS      1251
#define PITCH       2.0
#define FIRST_X     (-1250.0)
/* Bands (ROI rows): laser 1's line near row 104, laser 0's near 152; laser
 * 0's band reaches past laser 1's roller table line (row 229). */
#define BAND1_FIRST 64
#define BAND1_ROWS  64
#define BAND0_FIRST 128
#define BAND0_ROWS  112

#define assert_near(a, b, tol)                                                 \
  do {                                                                         \
    const double a_ = (a), b_ = (b);                                           \
    if (!(fabs(a_ - b_) <= (tol)))                                             \
      fail_msg("%s = %.17g, expected %.17g +- %g", #a, a_, b_, (double)(tol)); \
  } while (0)

static flt_calib *field_calib(void) {
    flt_calib *calib = NULL;
    assert_int_equal(
        flt_calib_create_reference(ROI_FIRST, ROI_ROWS, FIRST_X, PITCH, FIBERS, &calib), FLT_OK);
    return calib;
}

static flt_options *options_with(int n, const flt_option *keys, const double *values) {
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    for (int i = 0; i < n; ++i)
        assert_int_equal(flt_options_set(o, keys[i], values[i]), FLT_OK);
    return o;
}

/* Extractor options: the bands above. */
static flt_extractor *field_extractor(const flt_calib *calib) {
    const flt_option keys[] = {FLT_OPT_EXTRACT_LASER0_FIRST_ROW, FLT_OPT_EXTRACT_LASER0_ROWS,
                               FLT_OPT_EXTRACT_LASER1_FIRST_ROW, FLT_OPT_EXTRACT_LASER1_ROWS};
    const double values[] = {BAND0_FIRST, BAND0_ROWS, BAND1_FIRST, BAND1_ROWS};
    flt_options *o = options_with(4, keys, values);
    flt_extractor *ex = NULL;
    assert_int_equal(flt_extractor_create(calib, o, &ex), FLT_OK);
    flt_options_destroy(o);
    return ex;
}

static double fiber_x(size_t k) {
    return FIRST_X + PITCH * (double)k;
}

/* ------------------------------------------------------------------ simulator */

/* The simulator's strip: edges at c(e) -+ W/2 with c(e) the offset plus the
 * sine plus the random walk; the walk stays within a few sigma and moves
 * slowly; coils alternate widths; a laser between coils sees no strip;
 * profile rows are NaN with valid 0 exactly off the strip; the truth is
 * the sheet in strip coordinates; rewind repeats the walk. */
static void the_simulated_strip_has_edges_coils_and_wander(void **state) {
    (void)state;
    flt_calib *calib = field_calib();
    const flt_option keys[] = {
        FLT_OPT_SIM_SURROUND,     FLT_OPT_SIM_STRIP_WIDTH,      FLT_OPT_SIM_SECOND_WIDTH,
        FLT_OPT_SIM_STRIP_OFFSET, FLT_OPT_SIM_WANDER_AMPLITUDE, FLT_OPT_SIM_WANDER_PERIOD,
        FLT_OPT_SIM_WANDER_SIGMA, FLT_OPT_SIM_WANDER_LENGTH,    FLT_OPT_SIM_COIL_LENGTH,
        FLT_OPT_SIM_COIL_GAP,     FLT_OPT_SIM_FRAME_SPACING};
    const double values[] = {2, 1500, 900, 40, 30, 20000, 10, 8000, 6000, 1000, 50};
    flt_options *o = options_with(11, keys, values);
    flt_sim *sim = NULL;
    assert_int_equal(flt_sim_create(calib, o, &sim), FLT_OK);
    flt_options_destroy(o);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, 6, 1500), FLT_OK);

    /* Edges over 3 coils: widths and presence per laser; laser 0 (offset
     * -50) reads s = e + 50, laser 1 s = e - 50. */
    enum { N = 400 };
    double e[N], l[2][N], r[2][N], lr[N], rr[N];
    uint8_t present[2][N], present_row[N];
    for (int i = 0; i < N; ++i)
        e[i] = -500 + 50.0 * i;
    for (unsigned laser = 0; laser < 2; ++laser)
        assert_int_equal(flt_sim_strip_edges(sim, laser, N, e, l[laser], r[laser], present[laser]),
                         FLT_OK);
    assert_int_equal(flt_sim_strip_edges(sim, 2, N, e, lr, rr, present_row), FLT_OK);
    double walk_lo = INFINITY, walk_hi = -INFINITY, max_step = 0;
    for (int i = 0; i < N; ++i) {
        for (unsigned laser = 0; laser < 2; ++laser) {
            const double s = e[i] - (laser ? 50 : -50);
            const double k = floor(s / 7000);
            const int in_coil = s >= 0 && s - 7000 * k < 6000;
            assert_int_equal(present[laser][i], in_coil);
            if (!in_coil) {
                assert_true(isnan(l[laser][i]) && isnan(r[laser][i]));
                continue;
            }
            const double width = fmod(k, 2) == 0 ? 1500 : 900;
            assert_near(r[laser][i] - l[laser][i], width, 1e-9);
            /* Both lasers see the same centre line: the walk is what is left
             * after the offset and the sine. */
            const double c = 0.5 * (l[laser][i] + r[laser][i]);
            const double walk = c - 40 - 30 * sin(2 * M_PI * e[i] / 20000);
            walk_lo = fmin(walk_lo, walk), walk_hi = fmax(walk_hi, walk);
            if (laser == 0 && i > 0 && present[0][i - 1])
                max_step = fmax(max_step, fabs(c - 0.5 * (l[0][i - 1] + r[0][i - 1])));
        }
        assert_int_equal(present_row[i], present[0][i] && present[1][i]);
        if (present_row[i]) {
            assert_near(lr[i], 0.5 * (l[0][i] + l[1][i]), 1e-9);
            assert_near(rr[i], 0.5 * (r[0][i] + r[1][i]), 1e-9);
        }
    }
    print_message("random walk (sigma 10 mm) over 20 m: %.1f .. %.1f mm; the centre moves at "
                  "most %.2f mm per 50 mm of travel\n",
                  walk_lo, walk_hi, max_step);
    /* 5 sigma; a 40 mm sweep per 50 mm of travel would not be a slow walk
     * (the sine alone moves 0.5 mm per 50 mm). */
    assert_true(walk_lo > -50 && walk_hi < 50 && walk_hi - walk_lo > 1);
    assert_true(max_step < 2);

    /* Rows: NaN with valid 0 exactly where flt_sim_fiber_flags says off. */
    enum { ROWS = 300 };
    double *enc = malloc(ROWS * sizeof *enc), *s = malloc(ROWS * sizeof *s),
           *h = malloc(ROWS * FIBERS * sizeof *h), *g = malloc(ROWS * FIBERS * sizeof *g),
           *truth = malloc(ROWS * FIBERS * sizeof *truth);
    uint8_t *valid = malloc(ROWS * FIBERS), flags[FIBERS];
    assert_int_equal(flt_sim_next_rows(sim, ROWS, FIBERS, enc, s, h, g, NULL, truth),
                     FLT_ERR_INVALID_ARGUMENT); /* NaNs need their flag */
    assert_int_equal(flt_sim_next_rows(sim, ROWS, FIBERS, enc, s, h, g, valid, truth), FLT_OK);
    size_t off = 0, on = 0;
    for (int row = 0; row < ROWS; ++row) {
        assert_int_equal(flt_sim_fiber_flags(sim, enc[row], FIBERS, flags), FLT_OK);
        double c0, c1;
        uint8_t p;
        assert_int_equal(flt_sim_strip_edges(sim, 2, 1, &enc[row], &c0, &c1, &p), FLT_OK);
        for (size_t k = 0; k < FIBERS; ++k) {
            const size_t i = (size_t)row * FIBERS + k;
            if (flags[k]) {
                assert_int_equal(flags[k], FLT_FLAG_OFF_STRIP);
                assert_int_equal(valid[i], 0);
                assert_true(isnan(h[i]) && isnan(g[i]) && isnan(truth[i]));
                ++off;
                continue;
            }
            ++on;
            assert_int_equal(valid[i], 1);
            assert_true(isfinite(h[i]) && isfinite(g[i]));
            /* The truth is the sheet in strip coordinates. */
            const double xs = fiber_x(k) - 0.5 * (c0 + c1);
            double z;
            assert_int_equal(flt_sim_surface(sim, 1, &xs, &s[row], &z), FLT_OK);
            assert_near(truth[i], z, 1e-9);
        }
    }
    assert_true(off > 0 && on > 0);
    /* Rewind: the same rows again (the walk restarts with the frames). */
    double *h2 = malloc(ROWS * FIBERS * sizeof *h2);
    assert_int_equal(flt_sim_rewind(sim), FLT_OK);
    assert_int_equal(flt_sim_next_rows(sim, ROWS, FIBERS, NULL, s, h2, g, valid, NULL), FLT_OK);
    for (size_t i = 0; i < (size_t)ROWS * FIBERS; ++i)
        assert_true((isnan(h[i]) && isnan(h2[i])) || h[i] == h2[i]);
    free(enc), free(s), free(h), free(g), free(truth), free(valid), free(h2);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

/* ------------------------------------------------------------------ edges */

typedef struct edge_run {
    double rms_edge, rms_width, worst_edge;
    size_t edges, wrong_flags, near_edge_flags, fibers_on;
    size_t glint_flags, row_glint_flags; /* FLT_STRIP_*_GLINT: per laser, and the row's */
} edge_run;

/* Rendered frames of a strip `width` wide, wandering (a 40 mm sine over
 * 30 m and a 10 mm random walk, frames 600 mm apart so 40 frames span
 * 24 m), over the roller table, under the reference noise; edge glints with
 * probability `glints` per edge and frame. Each laser's measured edges
 * against the truth; the fiber flags against flt_sim_fiber_flags (a flag
 * may differ only within 1 mm of an edge, where the edge's own error
 * decides). */
static edge_run edges_of(double width, double glints, unsigned seed) {
    flt_calib *calib = field_calib();
    const flt_option keys[] = {FLT_OPT_SIM_SURROUND,
                               FLT_OPT_SIM_STRIP_WIDTH,
                               FLT_OPT_SIM_WANDER_AMPLITUDE,
                               FLT_OPT_SIM_WANDER_PERIOD,
                               FLT_OPT_SIM_WANDER_SIGMA,
                               FLT_OPT_SIM_FRAME_SPACING,
                               FLT_OPT_SIM_HEAVE_SIGMA,
                               FLT_OPT_SIM_ECCENTRICITY_AMPLITUDE,
                               FLT_OPT_SIM_PEAK_SIGMA,
                               FLT_OPT_SIM_EDGE_GLINTS,
                               FLT_OPT_SIM_SEED};
    const double values[] = {2, width, 40, 30000, 10, 600, 2.5, 0.5, 1.0 / 16, glints, seed};
    flt_options *o = options_with(11, keys, values);
    flt_sim *sim = NULL;
    assert_int_equal(flt_sim_create(calib, o, &sim), FLT_OK);
    flt_options_destroy(o);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, 6, 1500), FLT_OK);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 4, 2100), FLT_OK);
    flt_extractor *ex = field_extractor(calib);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    edge_run run = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    double sum_edge = 0, sum_width = 0;
    size_t widths = 0;
    for (int f = 0; f < 40; ++f) {
        double e, s, h[FIBERS], g[FIBERS];
        uint8_t flags[FIBERS], truth_flags[FIBERS];
        assert_int_equal(
            flt_sim_next_frame(sim, frame, (size_t)W * ROI_ROWS, W, &e, 0, NULL, NULL, 0), FLT_OK);
        assert_int_equal(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e,
                                               FIBERS, &s, h, g, NULL),
                         FLT_OK);
        assert_int_equal(flt_extractor_fiber_flags(ex, FIBERS, flags), FLT_OK);
        assert_int_equal(flt_sim_fiber_flags(sim, e, FIBERS, truth_flags), FLT_OK);
        double tl[2], tr[2];
        for (unsigned laser = 0; laser < 2; ++laser) {
            double left, right, w, c;
            unsigned sf;
            uint8_t present;
            assert_int_equal(flt_extractor_strip(ex, laser, &left, &right, &w, &c, &sf), FLT_OK);
            assert_int_equal(
                flt_sim_strip_edges(sim, laser, 1, &e, &tl[laser], &tr[laser], &present), FLT_OK);
            assert_int_equal(present, 1);
            if (sf & ~(unsigned)(FLT_STRIP_LEFT_GLINT | FLT_STRIP_RIGHT_GLINT))
                print_message("f %d laser %u sf %u left %.2f (%.2f) right %.2f (%.2f)\n", f, laser,
                              sf, left, tl[laser], right, tr[laser]);
            /* both edges seen */
            assert_int_equal(sf & ~(unsigned)(FLT_STRIP_LEFT_GLINT | FLT_STRIP_RIGHT_GLINT), 0);
            run.glint_flags += (size_t)((sf & FLT_STRIP_LEFT_GLINT) != 0) +
                               (size_t)((sf & FLT_STRIP_RIGHT_GLINT) != 0);
            const double d[2] = {left - tl[laser], right - tr[laser]};
            for (int side = 0; side < 2; ++side) {
                sum_edge += d[side] * d[side];
                run.worst_edge = fmax(run.worst_edge, fabs(d[side]));
                ++run.edges;
            }
            const double dw = w - (tr[laser] - tl[laser]);
            sum_width += dw * dw;
            ++widths;
            assert_near(c, 0.5 * (left + right), 1e-9);
        }
        {
            double left, right, w, c;
            unsigned sf;
            assert_int_equal(flt_extractor_strip(ex, 2, &left, &right, &w, &c, &sf), FLT_OK);
            run.row_glint_flags += (size_t)((sf & FLT_STRIP_LEFT_GLINT) != 0) +
                                   (size_t)((sf & FLT_STRIP_RIGHT_GLINT) != 0);
        }
        for (size_t k = 0; k < FIBERS; ++k) {
            const double x = fiber_x(k);
            /* NaN only with a flag: a valid fiber has a finite height. */
            assert_true(flags[k] != 0 || (isfinite(h[k]) && isfinite(g[k])));
            assert_true(flags[k] == 0 || (isnan(h[k]) && isnan(g[k])));
            run.fibers_on += truth_flags[k] == 0;
            const int on_truth = truth_flags[k] == 0, on = !(flags[k] & FLT_FLAG_OFF_STRIP);
            if (on == on_truth)
                continue;
            int near = 0;
            for (unsigned laser = 0; laser < 2; ++laser)
                near |= fabs(x - tl[laser]) <= 1.0 || fabs(x - tr[laser]) <= 1.0;
            if (near)
                ++run.near_edge_flags;
            else
                ++run.wrong_flags;
        }
    }
    run.rms_edge = sqrt(sum_edge / (double)run.edges);
    run.rms_width = sqrt(sum_width / (double)widths);
    free(frame);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
    return run;
}

/* Edges to RMS <= 1 mm and widths to <= 2 mm at 2 mm fiber pitch, from
 * rendered frames with the reference noise, for strips 900, 1500 and
 * 2200 mm wide wandering over the roller table. No fiber more than 1 mm
 * from the true edge gets the wrong side. With glints at the edges the
 * same bounds hold.
 *   Glints at 30 % of the edges (per laser and frame): a laser's edge with
 *   a glint takes the other laser's where that one is clean. Clean edges
 *   lie 0.065-0.10 mm RMS off; the glinting runs 0.19-0.26 mm (0.36-0.44
 *   before the other laser's edge was taken): bound 0.3 mm. The rest are
 *   glints on a column the strip barely covers, which make it look well
 *   covered without being brighter than the line: no light measure tells
 *   them, and on both lasers (9 % of the edges) nothing replaces them.
 *   Glints at every edge: no clean edge to take, so the edges stay
 *   0.65-0.75 mm RMS off (about 0.6 mm outward); the row's edges say so
 *   (FLT_STRIP_*_GLINT): at least 80 % of them flagged. */
static void edges_within_a_millimetre(void **state) {
    (void)state;
    const double widths[] = {900, 1500, 2200};
    const double glints[] = {0, 0.3, 1.0};
    for (int g = 0; g < 3; ++g)
        for (int i = 0; i < 3; ++i) {
            const edge_run r = edges_of(widths[i], glints[g], 7u + (unsigned)i);
            print_message("strip %4.0f mm, glints at %3.0f %% of the edges: edges RMS %.3f mm "
                          "(worst %.2f, %zu edges), width RMS %.3f mm; fibers on the wrong side "
                          "of the strip: %zu beyond 1 mm of an edge, %zu within (of %zu on the "
                          "strip); edges flagged with a glint: %zu of the lasers', %zu of %zu of "
                          "the rows'\n",
                          widths[i], 100 * glints[g], r.rms_edge, r.worst_edge, r.edges,
                          r.rms_width, r.wrong_flags, r.near_edge_flags, r.fibers_on, r.glint_flags,
                          r.row_glint_flags, r.edges / 2);
            assert_true(r.rms_edge <= 1.0);
            assert_true(r.rms_width <= 2.0);
            assert_int_equal(r.wrong_flags, 0);
            if (g == 0)
                assert_int_equal(r.glint_flags, 0);
            if (g == 1)
                assert_true(r.rms_edge <= 0.3);
            if (g == 2)
                assert_true((double)r.row_glint_flags >= 0.8 * (double)(r.edges / 2));
        }
}

/* ------------------------------------------------------------------ saturation */

/* Lines at 1.5 times full scale, blooming into their neighbouring rows, on a
 * 1500 mm strip over the roller table: the targets are >= 99 % of
 * the fibers on the strip valid and each laser's height within 2 sigma <=
 * 0.15 mm of the sheet. As for the unsaturated bound (test_extractor.c:
 * 2 sigma <= 0.1 mm) the frames carry their own noise only (speckle, shot
 * noise, quantisation) and no motion: the simulator's sim_peak_sigma would
 * move the rendered line away from the sheet and count as the extractor's
 * error. The saturation fraction is reported per frame (nearly every peak
 * of the strip's line here). */
static void saturated_lines_are_measured(void **state) {
    (void)state;
    flt_calib *calib = field_calib();
    const flt_option keys[] = {FLT_OPT_SIM_SURROUND, FLT_OPT_SIM_STRIP_WIDTH, FLT_OPT_SIM_LINE_PEAK,
                               FLT_OPT_SIM_BLOOMING, FLT_OPT_SIM_FRAME_SPACING};
    const double values[] = {2, 1500, 1.5, 1.0, 37};
    flt_options *o = options_with(5, keys, values);
    flt_sim *sim = NULL;
    assert_int_equal(flt_sim_create(calib, o, &sim), FLT_OK);
    flt_options_destroy(o);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 12, 1800), FLT_OK);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, 8, 900), FLT_OK);
    flt_extractor *ex = field_extractor(calib);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    double sum = 0, sum2 = 0, lowest_fraction = 1;
    size_t on = 0, valid = 0, points = 0;
    for (int f = 0; f < 20; ++f) {
        double e, s, h[FIBERS], g[FIBERS], z[2 * FIBERS], fraction;
        uint8_t flags[FIBERS], truth_flags[FIBERS];
        size_t peaks, saturated;
        assert_int_equal(
            flt_sim_next_frame(sim, frame, (size_t)W * ROI_ROWS, W, &e, 0, NULL, NULL, 0), FLT_OK);
        assert_int_equal(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e,
                                               FIBERS, &s, h, g, NULL),
                         FLT_OK);
        assert_int_equal(flt_extractor_fiber_flags(ex, FIBERS, flags), FLT_OK);
        assert_int_equal(flt_sim_fiber_flags(sim, e, FIBERS, truth_flags), FLT_OK);
        assert_int_equal(flt_extractor_laser_profiles(ex, FIBERS, z), FLT_OK);
        assert_int_equal(flt_extractor_saturation(ex, 2, &peaks, &saturated, &fraction), FLT_OK);
        assert_near(fraction, (double)saturated / (double)peaks, 1e-12);
        lowest_fraction = fmin(lowest_fraction, fraction);
        for (size_t k = 0; k < FIBERS; ++k) {
            if (truth_flags[k])
                continue;
            ++on;
            if (flags[k])
                continue;
            ++valid;
            for (unsigned laser = 0; laser < 2; ++laser) {
                const double x = fiber_x(k), sl = e - (laser ? 50 : -50);
                double zt;
                assert_int_equal(flt_sim_surface(sim, 1, &x, &sl, &zt), FLT_OK);
                const double d = z[laser * FIBERS + k] - zt;
                sum += d, sum2 += d * d, ++points;
            }
        }
    }
    const double mean = sum / (double)points, sigma = sqrt(sum2 / (double)points - mean * mean);
    print_message("lines at 1.5 x full scale: %.2f%% of the %zu fibers on the strip valid, height "
                  "error mean %.4f mm, 2 sigma %.4f mm; saturated share of the peaks >= %.3f per "
                  "frame\n",
                  100.0 * (double)valid / (double)on, on, mean, 2 * sigma, lowest_fraction);
    assert_true(valid >= 0.99 * (double)on);
    assert_true(2 * sigma <= 0.15);
    assert_true(fabs(mean) <= 0.075); /* no bias beyond half the bound */
    assert_true(lowest_fraction > 0.9);
    free(frame);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

/* ------------------------------------------------------------------ head and tail */

/* Coils 4 m long, 1.5 m apart, alternately 1500 and 1000 mm wide, wandering,
 * over the roller table: frames every 20 mm through two tails and two
 * heads. Per frame: a fiber off the strip (for either laser, by the truth)
 * is never reported on it, except within 1 mm of a lateral edge of the
 * strip (where the measured edge's error decides); a frame in which a laser
 * sees no strip has every fiber off it; heights are NaN exactly where the
 * flags say so. Then the same rows through the reconstructor with their
 * flags: every output NaN carries FLT_FLAG_NO_DATA or FLT_FLAG_OFF_STRIP,
 * and every off-strip input comes out NaN flagged FLT_FLAG_OFF_STRIP. */
static void heads_and_tails_never_report_strip_where_there_is_none(void **state) {
    (void)state;
    enum { FRAMES = 620 };
    flt_calib *calib = field_calib();
    const flt_option keys[] = {
        FLT_OPT_SIM_SURROUND,    FLT_OPT_SIM_STRIP_WIDTH,      FLT_OPT_SIM_SECOND_WIDTH,
        FLT_OPT_SIM_COIL_LENGTH, FLT_OPT_SIM_COIL_GAP,         FLT_OPT_SIM_FRAME_SPACING,
        FLT_OPT_SIM_START,       FLT_OPT_SIM_WANDER_AMPLITUDE, FLT_OPT_SIM_WANDER_PERIOD,
        FLT_OPT_SIM_HEAVE_SIGMA, FLT_OPT_SIM_PEAK_SIGMA};
    /* Frames from e = 3000 mm: coil 0's tail (s = 4000) passes, coil 1
     * (5500 .. 9500, 1000 mm wide) comes and goes, coil 2 arrives. */
    const double values[] = {2, 1500, 1000, 4000, 1500, 20, 3000, 40, 9000, 2.5, 1.0 / 16};
    flt_options *o = options_with(11, keys, values);
    flt_sim *sim = NULL;
    assert_int_equal(flt_sim_create(calib, o, &sim), FLT_OK);
    flt_options_destroy(o);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 5, 1500), FLT_OK);
    flt_extractor *ex = field_extractor(calib);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    double *s = malloc(FRAMES * sizeof *s), *h = malloc(FRAMES * FIBERS * sizeof *h),
           *g = malloc(FRAMES * FIBERS * sizeof *g);
    uint8_t *flags = malloc(FRAMES * FIBERS), *truth = malloc(FRAMES * FIBERS);
    size_t strip_frames[4] = {0, 0, 0, 0}, near_edge = 0, none_frames = 0;
    for (int f = 0; f < FRAMES; ++f) {
        double e;
        double *hf = h + (size_t)f * FIBERS, *gf = g + (size_t)f * FIBERS;
        uint8_t *ff = flags + (size_t)f * FIBERS, *tf = truth + (size_t)f * FIBERS;
        assert_int_equal(
            flt_sim_next_frame(sim, frame, (size_t)W * ROI_ROWS, W, &e, 0, NULL, NULL, 0), FLT_OK);
        assert_int_equal(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e,
                                               FIBERS, &s[f], hf, gf, NULL),
                         FLT_OK);
        assert_int_equal(flt_extractor_fiber_flags(ex, FIBERS, ff), FLT_OK);
        assert_int_equal(flt_sim_fiber_flags(sim, e, FIBERS, tf), FLT_OK);
        double tl[2], tr[2];
        uint8_t present[2];
        unsigned seen = 0;
        for (unsigned laser = 0; laser < 2; ++laser) {
            assert_int_equal(
                flt_sim_strip_edges(sim, laser, 1, &e, &tl[laser], &tr[laser], &present[laser]),
                FLT_OK);
            unsigned sf;
            assert_int_equal(flt_extractor_strip(ex, laser, NULL, NULL, NULL, NULL, &sf), FLT_OK);
            /* The extractor sees a strip exactly where there is one. */
            assert_int_equal(!(sf & FLT_STRIP_NONE), present[laser]);
            seen |= present[laser] << laser;
        }
        ++strip_frames[seen];
        for (size_t k = 0; k < FIBERS; ++k) {
            assert_true(ff[k] != 0 || (isfinite(hf[k]) && isfinite(gf[k])));
            assert_true(ff[k] == 0 || (isnan(hf[k]) && isnan(gf[k])));
            if (!tf[k] || (ff[k] & FLT_FLAG_OFF_STRIP))
                continue;
            /* Reported on the strip, but off it: only next to a lateral
             * edge of a strip both lasers see. */
            assert_int_equal(seen, 3);
            const double x = fiber_x(k);
            int near = 0;
            for (unsigned laser = 0; laser < 2; ++laser)
                near |= fabs(x - tl[laser]) <= 1.0 || fabs(x - tr[laser]) <= 1.0;
            assert_true(near);
            ++near_edge;
        }
        if (seen != 3) {
            for (size_t k = 0; k < FIBERS; ++k)
                assert_int_equal(ff[k], FLT_FLAG_OFF_STRIP);
            ++none_frames;
        }
    }
    print_message("heads and tails: %zu frames with both lasers on a strip, %zu with laser 0 "
                  "only, %zu with laser 1 only, %zu with none; %zu fibers within 1 mm of an edge "
                  "on the other side of it\n",
                  strip_frames[3], strip_frames[1], strip_frames[2], strip_frames[0], near_edge);
    /* Each head and tail: 5 frames (100 mm) with one laser on the strip. */
    assert_true(strip_frames[1] >= 10 && strip_frames[2] >= 10 && strip_frames[0] >= 100);

    /* The reconstructor: a new strip at each coil (reset), as a gauge does;
     * here one batch over all the rows shows the flags pass through. */
    double *z = malloc(FRAMES * FIBERS * sizeof *z);
    uint8_t *out_flags = malloc(FRAMES * FIBERS);
    assert_int_equal(flt_reconstruct_flagged(NULL, FRAMES, FIBERS, s, h, g, flags, z, out_flags),
                     FLT_OK);
    for (size_t i = 0; i < (size_t)FRAMES * FIBERS; ++i) {
        if (flags[i] & FLT_FLAG_OFF_STRIP) {
            assert_int_equal(out_flags[i], FLT_FLAG_OFF_STRIP);
            assert_true(isnan(z[i]));
        } else {
            assert_false(out_flags[i] & FLT_FLAG_OFF_STRIP);
        }
        if (isnan(z[i]))
            assert_true(out_flags[i] & (FLT_FLAG_NO_DATA | FLT_FLAG_OFF_STRIP));
    }
    free(z), free(out_flags);
    free(frame), free(s), free(h), free(g), free(flags), free(truth);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

/* ------------------------------------------------------------------ reconstructor */

/* The off-strip flag passes through the streaming reconstructor: rows of a
 * narrow wandering strip (its edge fibers come and go) pushed with their
 * flags in blocks, pulled as they finish, with an end_sheet in the middle
 * and a reset (a new coil) after it: every off-strip input comes out NaN
 * with FLT_FLAG_OFF_STRIP alone; every other output is finite unless
 * FLT_FLAG_NO_DATA; and on the strip the streamed heights are those of
 * flt_reconstruct_flagged over the same sheets to rounding (1 nm). */
static void the_off_strip_flag_passes_through_the_reconstructor(void **state) {
    (void)state;
    enum { ROWS = 3000, K = 301, BLOCK = 25 };
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create_reference(0, 2048, -1500, 10.0, K, &calib), FLT_OK);
    const flt_option keys[] = {FLT_OPT_SIM_SURROUND, FLT_OPT_SIM_STRIP_WIDTH,
                               FLT_OPT_SIM_WANDER_AMPLITUDE, FLT_OPT_SIM_WANDER_PERIOD,
                               FLT_OPT_SIM_PEAK_SIGMA};
    const double values[] = {1, 1200, 60, 2500, 1.0 / 16};
    flt_options *o = options_with(5, keys, values);
    flt_sim *sim = NULL;
    assert_int_equal(flt_sim_create(calib, o, &sim), FLT_OK);
    flt_options_destroy(o);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_QUARTER_BUCKLE, 5, 1200), FLT_OK);
    const size_t n = (size_t)ROWS * K;
    double *s = malloc(ROWS * sizeof *s), *h = malloc(n * sizeof *h), *g = malloc(n * sizeof *g),
           *z_batch = malloc(n * sizeof *z_batch), *z = malloc(n * sizeof *z),
           *s_out = malloc(ROWS * sizeof *s_out);
    uint8_t *valid = malloc(n), *flags = malloc(n), *f_batch = malloc(n), *f_out = malloc(n);
    assert_int_equal(flt_sim_next_rows(sim, ROWS, K, NULL, s, h, g, valid, NULL), FLT_OK);
    for (size_t i = 0; i < n; ++i)
        flags[i] = valid[i] ? 0 : FLT_FLAG_OFF_STRIP;
    /* Sheets: rows [0, 1500) and [1500, 3000), a new strip after the first.
     * A lag of 64 knots is longer than a sheet (45 knots): every row is
     * finished by end_sheet, solved with the whole sheet, so the streamed
     * values are the batch's to rounding. (With a shorter lag, as the
     * default latency_mm's, the rows next to long stretches off the strip,
     * bridged by the prior alone, keep changing while data arrives beyond
     * them.) */
    flt_options *ro = NULL;
    assert_int_equal(flt_options_create(&ro), FLT_OK);
    assert_int_equal(flt_options_set(ro, FLT_OPT_LAG_KNOTS, 64), FLT_OK);
    for (int sheet = 0; sheet < 2; ++sheet)
        assert_int_equal(flt_reconstruct_flagged(
                             ro, ROWS / 2, K, s + sheet * ROWS / 2, h + (size_t)sheet * n / 2,
                             g + (size_t)sheet * n / 2, flags + (size_t)sheet * n / 2,
                             z_batch + (size_t)sheet * n / 2, f_batch + (size_t)sheet * n / 2),
                         FLT_OK);
    flt_recon *recon = NULL;
    assert_int_equal(flt_recon_create(K, ro, &recon), FLT_OK);
    size_t pulled = 0;
    for (size_t r = 0; r < ROWS; r += BLOCK) {
        assert_int_equal(
            flt_recon_push_flagged(recon, BLOCK, K, s + r, h + r * K, g + r * K, flags + r * K),
            FLT_OK);
        if (r + BLOCK == ROWS / 2 || r + BLOCK == ROWS)
            assert_int_equal(flt_recon_end_sheet(recon), FLT_OK);
        size_t got = 0;
        assert_int_equal(flt_recon_pull(recon, ROWS - pulled, K, s_out + pulled, z + pulled * K,
                                        f_out + pulled * K, &got),
                         FLT_OK);
        pulled += got;
        if (r + BLOCK == ROWS / 2) {
            assert_int_equal(pulled, ROWS / 2);
            assert_int_equal(flt_recon_reset(recon), FLT_OK); /* the next coil */
        }
    }
    assert_int_equal(pulled, ROWS);
    size_t off = 0;
    double worst = 0;
    for (size_t i = 0; i < n; ++i) {
        if (flags[i]) {
            assert_int_equal(f_out[i], FLT_FLAG_OFF_STRIP);
            assert_true(isnan(z[i]));
            ++off;
            continue;
        }
        assert_false(f_out[i] & FLT_FLAG_OFF_STRIP);
        if (isnan(z[i])) {
            assert_true(f_out[i] & FLT_FLAG_NO_DATA);
            continue;
        }
        assert_int_equal(f_out[i], f_batch[i]);
        worst = fmax(worst, fabs(z[i] - z_batch[i]));
    }
    print_message("reconstructor: %zu of %zu samples off the strip passed through; streamed vs "
                  "whole sheet on the strip within %.2g mm\n",
                  off, n, worst);
    assert_true(off > n / 10);
    assert_true(worst <= 1e-6);
    /* A plain push after flagged rows: no stale flag (the FIFO stays in
     * step). */
    assert_int_equal(flt_recon_reset(recon), FLT_OK);
    assert_int_equal(flt_recon_push(recon, ROWS, K, s, h, g, valid), FLT_OK);
    assert_int_equal(flt_recon_end_sheet(recon), FLT_OK);
    size_t got = 0;
    assert_int_equal(flt_recon_pull(recon, ROWS, K, s_out, z, f_out, &got), FLT_OK);
    assert_int_equal(got, ROWS);
    for (size_t i = 0; i < n; ++i)
        assert_false(f_out[i] & FLT_FLAG_OFF_STRIP);
    flt_recon_destroy(recon);
    flt_options_destroy(ro);
    free(s), free(h), free(g), free(z_batch), free(z), free(s_out);
    free(valid), free(flags), free(f_batch), free(f_out);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

/* ------------------------------------------------------------------ field frames */

/* The background of column u around a line at row c: the median of the
 * 20 pixels 15-24 rows away on either side (c - 24 >= 0, c + 24 < ROI_ROWS). */
static double line_background(const uint8_t *frame, long u, long c) {
    int around[20];
    for (int j = 0; j < 10; ++j) {
        around[j] = frame[(size_t)(c - 15 - j) * W + (size_t)u];
        around[10 + j] = frame[(size_t)(c + 15 + j) * W + (size_t)u];
    }
    for (int i = 1; i < 20; ++i) /* insertion sort, for the median */
        for (int j = i; j > 0 && around[j - 1] > around[j]; --j) {
            const int x = around[j];
            around[j] = around[j - 1], around[j - 1] = x;
        }
    return 0.5 * (around[9] + around[10]);
}

/* The extractor's peaks in one field condition: frames of a 1500 mm strip
 * over the roller table with 6 mm wavy edges and a 4 mm centre buckle
 * (the line stays in its band), frames 150 mm apart. A column's line is
 * "strong" where its brightest pixel within a row of the true centre
 * (flt_sim_next_frame) rises at least 0.2 of full scale above the column's
 * background (the median of the 20 pixels 15-24 rows away on either side).
 * A kept peak is "wrong" more than 1 mm of height off the truth (both rows
 * through the calibration). A peak below extract_strip_min_z is the roller
 * table's line in a column the strip's edge crosses: the extractor leaves
 * it out of the strip (no fiber reads it), and so does the count. */
typedef struct field_figures {
    size_t strong, strong_kept, dim, dim_kept, kept, wrong;
    double rms_px, dim_rms_px, worst_mm;
} field_figures;

static field_figures field_run(double speckle, double depth_of_field, double dark_patches,
                               double edge_glints, double reflections, double ambient,
                               double texture, int frames) {
    flt_calib *calib = field_calib();
    const flt_option keys[] = {
        FLT_OPT_SIM_SURROUND,       FLT_OPT_SIM_STRIP_WIDTH,   FLT_OPT_SIM_SPECKLE,
        FLT_OPT_SIM_DEPTH_OF_FIELD, FLT_OPT_SIM_DARK_PATCHES,  FLT_OPT_SIM_EDGE_GLINTS,
        FLT_OPT_SIM_REFLECTIONS,    FLT_OPT_SIM_FRAME_SPACING, FLT_OPT_SIM_SEED,
        FLT_OPT_SIM_AMBIENT,        FLT_OPT_SIM_TEXTURE};
    const double values[] = {2,           1500, speckle, depth_of_field, dark_patches, edge_glints,
                             reflections, 150,  11,      ambient,        texture};
    flt_options *o = options_with(11, keys, values);
    flt_sim *sim = NULL;
    assert_int_equal(flt_sim_create(calib, o, &sim), FLT_OK);
    flt_options_destroy(o);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, 6, 1500), FLT_OK);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 4, 1800), FLT_OK);
    flt_extractor *ex = field_extractor(calib);
    uint8_t *frame = malloc((size_t)W * ROI_ROWS);
    double *truth = malloc(2 * W * sizeof(double)), *peaks = malloc(2 * W * sizeof(double));
    field_figures r = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    double sum2 = 0, dim_sum2 = 0;
    size_t right = 0, dim_right = 0;
    for (int f = 0; f < frames; ++f) {
        double e, s, h[FIBERS], g[FIBERS];
        assert_int_equal(flt_sim_next_frame(sim, frame, (size_t)W * ROI_ROWS, W, &e, 0, NULL, truth,
                                            2 * (size_t)W),
                         FLT_OK);
        assert_int_equal(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e,
                                               FIBERS, &s, h, g, NULL),
                         FLT_OK);
        assert_int_equal(flt_extractor_peaks(ex, W, peaks), FLT_OK);
        for (unsigned laser = 0; laser < 2; ++laser)
            for (long u = 0; u < W; ++u) {
                const double t = truth[laser * W + (size_t)u], p = peaks[laser * W + (size_t)u];
                const long c = lround(t);
                if (!(t == t) || c - 25 < 0 || c + 25 >= ROI_ROWS)
                    continue;
                int top = 0;
                for (long v = c - 1; v <= c + 1; ++v)
                    if (frame[(size_t)v * W + (size_t)u] > top)
                        top = frame[(size_t)v * W + (size_t)u];
                const int strong = (top - line_background(frame, u, c)) / 255.0 >= 0.2;
                double pts[4] = {(double)u, t, (double)u, p}, plane[4];
                if (p == p) {
                    assert_int_equal(flt_calib_image_to_plane(calib, laser, 2, pts, plane), FLT_OK);
                    if (plane[3] < -100.0)
                        continue; /* the roller table's line */
                }
                r.strong += (size_t)strong, r.dim += (size_t)!strong;
                if (!(p == p))
                    continue;
                ++r.kept;
                r.strong_kept += (size_t)strong, r.dim_kept += (size_t)!strong;
                const double off_mm = fabs(plane[3] - plane[1]);
                r.worst_mm = fmax(r.worst_mm, off_mm);
                r.wrong += off_mm > 1.0;
                if (strong && off_mm <= 1.0) /* the wrong ones are counted apart */
                    sum2 += (p - t) * (p - t), ++right;
                else if (off_mm <= 1.0)
                    dim_sum2 += (p - t) * (p - t), ++dim_right;
            }
    }
    r.rms_px = sqrt(sum2 / (double)right);
    r.dim_rms_px = dim_right ? sqrt(dim_sum2 / (double)dim_right) : 0.0;
    free(frame), free(truth), free(peaks);
    flt_extractor_destroy(ex);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
    return r;
}

/* What real photos show that the plain simulator did not (flatline/sim.h):
 * defocus (an 8 mm depth of field: the line up to 1.3 times as wide),
 * dark patches over 30 % of the strip (the line there at 0.15-0.5 of its
 * light), glints at 30 % of the edges, spurious reflections (5 per frame,
 * half of them saturating glints), laser speckle of 15 % per pixel
 * (5 % elsewhere), and ambient light on the strip (0.1 or 0.25 of full
 * scale on bare steel) over its patches and a 2 mm texture of 20 %
 * contrast. 12 frames x 2 lasers x 2048 columns per condition.
 *
 * The targets for field frames: strong lines' peaks within 1/16 px RMS of
 * the truth, and at most 0.01 % of the kept peaks more than 1 mm off.
 * Without spurious reflections they hold: asserted, with the strong lines
 * kept >= 85 % (dark patches cost 7-8 % of the strong columns), and the
 * dim line over the dark patches (under 0.2 of full scale above them, in
 * part under extract_min_peak) kept >= 97 % within 1/12 px RMS: 98.9-99.2 %
 * and 0.051-0.058 px are measured, 89-94 % before the extractor bridged a
 * dim stretch between confident pieces of the line (bridge_dim_stretches;
 * the bridged peaks stand only 5 noise deviations out, hence the wider
 * bound than the strong lines'). With
 * reflections over dark patches a reflection outshines the dim line and is
 * taken for it (0.09-0.31 % of the kept peaks, up to 6.9 mm off: every
 * condition's worst kept peak is bounded at 10 mm, which a reflection
 * judged against the nearest longer pieces of the line across a gap of up
 * to 128 columns keeps; before, 22-30 mm), and 15 %
 * speckle puts the strong lines' error at about 1/11 px (the right peaks'
 * RMS; the wrong ones are counted apart). Under ambient light, a texture
 * under the line is a background with steps inside the line's own rows:
 * at 0.1 of full scale the strong lines keep 1/18-1/19 px, but 2 peaks
 * of 23,026 are 1.1 mm off over the patches; at 0.25 the error is about
 * 1/10 px and 0.10 % are off (1/9 and 0.16 % with the Savitzky-Golay
 * centre there: the extractor takes Steger's over such a background).
 * Those are printed, and bounded only against getting worse (1 % wrong,
 * 1/8 px), since those targets are not met yet (docs/sensor.md, "Field
 * frames"). */
static void field_frames_sub_pixel_accuracy(void **state) {
    (void)state;
    FLT_SWEEP_NOT_UNDER_SANITIZERS();
    const struct {
        const char *name;
        double speckle, depth_of_field, dark_patches, edge_glints, reflections, ambient, texture;
        int meets_targets;
    } conditions[] = {
        {"defocus", 0.05, 8, 0, 0, 0, 0, 0, 1},
        {"dark patches", 0.05, 0, 0.3, 0, 0, 0, 0, 1},
        {"defocus, dark patches, edge glints", 0.05, 8, 0.3, 0.3, 0, 0, 0, 1},
        {"... and reflections", 0.05, 8, 0.3, 0.3, 5, 0, 0, 0},
        {"... and 15 % speckle", 0.15, 8, 0.3, 0.3, 5, 0, 0, 0},
        {"texture 20 % under ambient 0.1", 0.05, 0, 0, 0, 0, 0.1, 0.2, 1},
        {"ambient 0.1, patches, defocus, glints", 0.05, 8, 0.3, 0.3, 0, 0.1, 0, 1},
        {"... and texture 20 %", 0.05, 8, 0.3, 0.3, 0, 0.1, 0.2, 0},
        {"... and ambient 0.25", 0.05, 8, 0.3, 0.3, 0, 0.25, 0.2, 0},
    };
    for (size_t i = 0; i < sizeof conditions / sizeof conditions[0]; ++i) {
        const field_figures r =
            field_run(conditions[i].speckle, conditions[i].depth_of_field,
                      conditions[i].dark_patches, conditions[i].edge_glints,
                      conditions[i].reflections, conditions[i].ambient, conditions[i].texture, 12);
        print_message(
            "field frames, %-36s strong lines %5zu, %5.1f %% kept, RMS %.4f px "
            "(1/%.0f); dim %4zu, %5.1f %% kept, RMS %.3f px; %3zu of %zu kept peaks > 1 mm off "
            "(%.3f %%, worst %.2f mm)\n",
            conditions[i].name, r.strong, 100.0 * (double)r.strong_kept / (double)r.strong,
            r.rms_px, 1 / r.rms_px, r.dim, r.dim ? 100.0 * (double)r.dim_kept / (double)r.dim : 0.0,
            r.dim_rms_px, r.wrong, r.kept, 100.0 * (double)r.wrong / (double)r.kept, r.worst_mm);
        assert_true(r.worst_mm <= 10.0);
        if (conditions[i].meets_targets) {
            assert_true(r.rms_px <= 1.0 / 16);
            assert_true((double)r.wrong <= 1e-4 * (double)r.kept);
            assert_true(r.strong_kept >= 0.85 * (double)r.strong);
            if (r.dim >= 1000) { /* the dark patches' dim line */
                assert_true(r.dim_kept >= 0.97 * (double)r.dim);
                assert_true(r.dim_rms_px <= 1.0 / 12);
            }
        } else {
            assert_true(r.rms_px <= 0.125);
            assert_true((double)r.wrong <= 1e-2 * (double)r.kept);
        }
    }
}

/* ------------------------------------------------------------- centre estimators */

/* Peer estimators of a column's line centre, on the same pixels the
 * extractor saw. Each starts from the column's brightest pixel within 4
 * rows of the truth (the line, not a reflection) and its background b (the
 * median of the pixels 15-24 rows away on either side, as field_run). */
typedef struct column_view {
    const uint8_t *frame;
    long u, top; /* the column, the brightest row */
    double background;
} column_view;

static double pixel(const column_view *c, long v) {
    if (v < 0 || v >= ROI_ROWS)
        return NAN;
    return (double)c->frame[(size_t)v * W + (size_t)c->u];
}

/* Centroid of the rows at or above half the maximum above b, contiguous
 * with the maximum, each weighted by its light above b. */
static double centroid_centre(const column_view *c) {
    const double half = 0.5 * (pixel(c, c->top) - c->background);
    double sum = 0, weight = 0;
    for (int dir = -1; dir <= 1; dir += 2)
        for (long v = dir < 0 ? c->top : c->top + 1; v >= 0 && v < ROI_ROWS; v += dir) {
            const double light = pixel(c, v) - c->background;
            if (!(light >= half))
                break;
            sum += light * (double)v, weight += light;
        }
    return weight > 0 ? sum / weight : NAN;
}

/* Gaussian 3-point: the vertex of the parabola through the logarithms of
 * the maximum and its two neighbours above b (NaN on a plateau). */
static double gaussian3_centre(const column_view *c) {
    const double lm = log(fmax(pixel(c, c->top - 1) - c->background, 0.5));
    const double l0 = log(fmax(pixel(c, c->top) - c->background, 0.5));
    const double lp = log(fmax(pixel(c, c->top + 1) - c->background, 0.5));
    const double curvature = lm - 2 * l0 + lp;
    if (!(curvature < 0))
        return NAN;
    return (double)c->top + 0.5 * (lm - lp) / curvature;
}

/* Steger's line centre in one dimension: the profile above b smoothed by a
 * Gaussian of the line's own scale (its width at half maximum / 2.355, at
 * least 1 px); the centre is where the smoothed profile's first derivative
 * vanishes, -r'/r'' at the row of the maximum (or its neighbour, when the
 * step leaves that pixel). The kernels are Steger's: the Gaussian's first
 * and second derivatives integrated over each pixel, out to 4 scales. */
static double gauss_density(double x, double s) {
    return exp(-0.5 * x * x / (s * s)) / (s * sqrt(2 * M_PI));
}

static double steger_centre(const column_view *c) {
    const double half = c->background + 0.5 * (pixel(c, c->top) - c->background);
    long lo = c->top, hi = c->top;
    while (lo > 0 && pixel(c, lo - 1) >= half)
        --lo;
    while (hi < ROI_ROWS - 1 && pixel(c, hi + 1) >= half)
        ++hi;
    const double scale = fmax(1.0, (double)(hi - lo + 1) / 2.355);
    const long reach = (long)ceil(4 * scale);
    /* -r'/r'' at row v (NaN where the profile is not concave there). */
    double offset[2] = {NAN, NAN};
    long rows[2] = {c->top, c->top};
    for (int step = 0; step < 2; ++step) {
        const long v0 = rows[step];
        if (v0 - 2 * reach < 0 || v0 + 2 * reach >= ROI_ROWS)
            return NAN;
        double d1 = 0, d2 = 0;
        for (long k = -reach; k <= reach; ++k) {
            /* r(v) = sum_k I(v - k) g(k), so r' and r'' take the derivative
             * kernels; each integrated over the pixel k -+ 1/2. */
            const double a = (double)k - 0.5, b = (double)k + 0.5;
            const double g1 = gauss_density(b, scale) - gauss_density(a, scale);
            const double g2 = -b / (scale * scale) * gauss_density(b, scale) +
                              a / (scale * scale) * gauss_density(a, scale);
            const double light = pixel(c, v0 - k) - c->background;
            d1 += light * g1, d2 += light * g2;
        }
        offset[step] = d2 < 0 ? -d1 / d2 : NAN;
        if (!(fabs(offset[0]) > 0.5))
            break; /* within the maximum's pixel (or not concave: NaN) */
        rows[1] = c->top + (offset[0] > 0 ? 1 : -1);
    }
    /* The row whose step is the shorter (the Taylor expansion is best
     * near its row). */
    const int best = fabs(offset[1]) < fabs(offset[0]) ? 1 : 0;
    return fabs(offset[best]) <= 1.0 ? (double)rows[best] + offset[best] : NAN;
}

typedef struct estimator_error {
    double sum, sum2;
    size_t n, missing;
} estimator_error;

static void add_error(estimator_error *e, double estimate, double truth) {
    if (!(estimate == estimate)) {
        ++e->missing;
        return;
    }
    e->sum += estimate - truth, e->sum2 += (estimate - truth) * (estimate - truth), ++e->n;
}

static double rms_of(const estimator_error *e) {
    return sqrt(e->sum2 / (double)e->n);
}

/* The extractor's sub-pixel centres against a centroid, a Gaussian 3-point
 * fit and Steger's detector, on the same columns of the same frames, for
 * lines from thin (sigma 0.8 px) to wide (5 px), saturated, and speckled.
 * (The extractor itself takes Steger's detector for lines at least 8 px
 * wide at half maximum: most columns of the sigma 4 and 5 px lines.)
 * Error = estimate - the simulator's true centre, over the columns where
 * the extractor kept a peak within 1 px of the truth (its wrong peaks are
 * counted by field_frames_sub_pixel_accuracy) and the line lies whole in
 * the frame. The figures are in docs/sensor.md ("Centre estimators"). */
static void estimators_against_the_truth(void **state) {
    (void)state;
    FLT_SWEEP_NOT_UNDER_SANITIZERS();
    /* rms_bound: the extractor's RMS, px (1/16 px, the target, where it is
     * met; else the measured figure with about a tenth's margin). The thin
     * line's is tighter: 0.022 px, 12 % above its 0.0197 px with a window
     * the line's size and 12 % below the 0.0251 px of the 11-row window
     * (the RMS of 24,000 columns is good to about 0.5 %).
     * steger_ratio: the extractor's RMS over Steger's, at most (1: the
     * extractor is the better; above, the measured ratio with a margin:
     * 1.06, 1.16, 1.17 and 1.01 on the four after the plain widths).
     * The last six lie over a textured background: 2 mm cells of 20 %
     * contrast under ambient light of 0.05-0.25 of full scale (sim.h).
     * Where its pixel noise exceeds 0.03 of the line's height (ambient
     * 0.25: 0.048 on the 0.6 line, 0.097 on the 0.3 line) the extractor
     * takes Steger's centre; the Savitzky-Golay window read 0.110, 0.091
     * and 0.214 px there. Bounds: the measured RMS plus about a tenth. */
    const struct {
        const char *name;
        double line_sigma, line_peak, speckle, rms_bound, steger_ratio, ambient, texture;
    } conditions[] = {
        {"thin, sigma 0.8 px", 0.8, 0.6, 0.05, 0.022, 1.0, 0, 0},
        {"sigma 1.2 px", 1.2, 0.6, 0.05, 1.0 / 16, 1.0, 0, 0},
        {"sigma 2 px (default)", 2.0, 0.6, 0.05, 1.0 / 16, 1.0, 0, 0},
        {"sigma 3 px", 3.0, 0.6, 0.05, 1.0 / 16, 1.0, 0, 0},
        {"wide, sigma 4 px", 4.0, 0.6, 0.05, 0.08, 1.15, 0, 0},
        {"wide, sigma 5 px", 5.0, 0.6, 0.05, 0.1, 1.25, 0, 0},
        {"saturated, sigma 2 px", 2.0, 2.0, 0.05, 1.0 / 16, 1.3, 0, 0},
        {"wide and speckled", 4.0, 0.6, 0.15, 0.25, 1.1, 0, 0},
        {"textured, ambient 0.25", 2.0, 0.6, 0.05, 0.098, 1.0, 0.25, 0.2},
        {"thin, textured", 1.0, 0.6, 0.05, 0.073, 1.0, 0.25, 0.2},
        {"dim, textured", 2.0, 0.3, 0.05, 0.176, 1.0, 0.25, 0.2},
        {"textured, ambient 0.1", 2.0, 0.6, 0.05, 0.058, 1.0, 0.1, 0.2},
        {"textured, ambient 0.05", 2.0, 0.6, 0.05, 0.042, 1.0, 0.05, 0.2},
        {"thin, ambient 0.1", 1.0, 0.6, 0.05, 0.041, 1.0, 0.1, 0.2},
    };
    for (size_t i = 0; i < sizeof conditions / sizeof conditions[0]; ++i) {
        flt_calib *calib = field_calib();
        const flt_option keys[] = {FLT_OPT_SIM_LINE_SIGMA, FLT_OPT_SIM_LINE_PEAK,
                                   FLT_OPT_SIM_SPECKLE,    FLT_OPT_SIM_FRAME_SPACING,
                                   FLT_OPT_SIM_SEED,       FLT_OPT_SIM_AMBIENT,
                                   FLT_OPT_SIM_TEXTURE};
        const double values[] = {
            conditions[i].line_sigma, conditions[i].line_peak, conditions[i].speckle, 150, 5,
            conditions[i].ambient,    conditions[i].texture};
        flt_options *o = options_with(7, keys, values);
        flt_sim *sim = NULL;
        assert_int_equal(flt_sim_create(calib, o, &sim), FLT_OK);
        flt_options_destroy(o);
        assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 4, 1800), FLT_OK);
        flt_extractor *ex = field_extractor(calib);
        uint8_t *frame = malloc((size_t)W * ROI_ROWS);
        double *truth = malloc(2 * W * sizeof(double)), *peaks = malloc(2 * W * sizeof(double));
        estimator_error err[4];
        memset(err, 0, sizeof err);
        size_t columns = 0;
        for (int f = 0; f < 6; ++f) {
            double e, s, h[FIBERS], g[FIBERS];
            assert_int_equal(flt_sim_next_frame(sim, frame, (size_t)W * ROI_ROWS, W, &e, 0, NULL,
                                                truth, 2 * (size_t)W),
                             FLT_OK);
            assert_int_equal(flt_extractor_process(ex, frame, FLT_PIXEL_MONO8, W, ROI_ROWS, W, e,
                                                   FIBERS, &s, h, g, NULL),
                             FLT_OK);
            assert_int_equal(flt_extractor_peaks(ex, W, peaks), FLT_OK);
            for (size_t j = 0; j < 2 * (size_t)W; ++j) {
                const double t = truth[j], p = peaks[j];
                const long c = lround(t);
                if (!(t == t) || !(p == p) || fabs(p - t) > 1 || c - 30 < 0 || c + 30 >= ROI_ROWS)
                    continue;
                column_view view = {frame, (long)(j % W), c, 0};
                for (long v = c - 4; v <= c + 4; ++v)
                    if (pixel(&view, v) > pixel(&view, view.top))
                        view.top = v;
                view.background = line_background(frame, view.u, c);
                ++columns;
                add_error(&err[0], p, t);
                add_error(&err[1], centroid_centre(&view), t);
                add_error(&err[2], gaussian3_centre(&view), t);
                add_error(&err[3], steger_centre(&view), t);
            }
        }
        print_message("%-22s %5zu columns | bias / RMS px: extractor %+.4f / %.4f | centroid "
                      "%+.4f / %.4f | Gaussian 3-point %+.4f / %.4f (%zu unmeasured) | Steger "
                      "%+.4f / %.4f (%zu unmeasured)\n",
                      conditions[i].name, columns, err[0].sum / (double)err[0].n, rms_of(&err[0]),
                      err[1].sum / (double)err[1].n, rms_of(&err[1]), err[2].sum / (double)err[2].n,
                      rms_of(&err[2]), err[2].missing, err[3].sum / (double)err[3].n,
                      rms_of(&err[3]), err[3].missing);
        /* No estimator here is biased by more than a hundredth of a pixel
         * (a convention error between pixel rows and the truth would show
         * half a pixel); the extractor's error is within its bound, below
         * the better of a centroid and a Gaussian 3-point fit, and within
         * steger_ratio of Steger's. */
        const double rms = rms_of(&err[0]);
        const double peer =
            err[2].n > columns / 2 ? fmin(rms_of(&err[1]), rms_of(&err[2])) : rms_of(&err[1]);
        assert_true(columns > 20000 && err[0].n == columns && err[3].n > columns * 9 / 10);
        assert_true(err[1].n == columns); /* the centroid reads every column */
        assert_true(fabs(err[0].sum / (double)err[0].n) <= 0.01);
        assert_true(rms <= conditions[i].rms_bound);
        assert_true(rms <= peer);
        assert_true(rms <= conditions[i].steger_ratio * rms_of(&err[3]));
        free(frame), free(truth), free(peaks);
        flt_extractor_destroy(ex);
        flt_sim_destroy(sim);
        flt_calib_destroy(calib);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(the_simulated_strip_has_edges_coils_and_wander),
        cmocka_unit_test(edges_within_a_millimetre),
        cmocka_unit_test(saturated_lines_are_measured),
        cmocka_unit_test(heads_and_tails_never_report_strip_where_there_is_none),
        cmocka_unit_test(the_off_strip_flag_passes_through_the_reconstructor),
        cmocka_unit_test(field_frames_sub_pixel_accuracy),
        cmocka_unit_test(estimators_against_the_truth),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
