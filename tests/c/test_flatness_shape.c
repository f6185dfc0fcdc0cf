// SPDX-License-Identifier: Apache-2.0
/*
 * Flatness shape classes on simulated sheets: every defect of the
 * simulator (flatline/sim.h) under the reference noise, reconstructed and
 * classified, 5 seeds per class; and zone profiles from streamed windows
 * against whole-sheet evaluation of the same material.
 *
 * Reference noise (the reference article's second experiment): 2.5 mm
 * rigid heave per frame, 0.5 mm roll eccentricity at 50 mm, 1/16 px
 * peak-detection noise per laser.
 *
 * Reconstruction: flt_reconstruct with rigid_motion = 1. The heave moves
 * every fiber of a frame together; rigid_motion models exactly that and
 * takes it out of the fibers' shape (3x less shape error, tests/c/
 * test_recon.c). Fitted fiber by fiber (rigid_motion = 0), each fiber keeps
 * its own share of the heave as slow level wander, which adds noise
 * I-Units that differ from fiber to fiber; the measured noise profile is
 * printed by flat_sheets_stay_below_the_flat_limit for both settings.
 *
 * Fibers: 101 across the 2000 mm strip (20 mm pitch) instead of the
 * sensor's 1001 (2 mm). The defects vary across the width on scales of
 * W/8 = 250 mm and more (the quarter buckle's width), so 20 mm samples
 * them finely, and 50 mm zones still hold 2-3 fibers; the rigid-motion line
 * of each frame is fitted through 101 fibers, plenty for two parameters.
 * It keeps the 45 sheets of this test to a few seconds.
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

#define FIBERS 101
#define PITCH  20.0
#define WIDTH  2000.0
#define ROWS   1100 /* 3300 mm at 3 mm */
#define SEEDS  5

#define assert_near(a, b, tol)                                                 \
  do {                                                                         \
    const double a_ = (a), b_ = (b);                                           \
    if (!(fabs(a_ - b_) <= (tol)))                                             \
      fail_msg("%s = %.17g, expected %.17g +- %g", #a, a_, b_, (double)(tol)); \
  } while (0)

/* Test classes: the shape classes, plus bow and crossbow (a flat class with
 * the HAS_BOW / HAS_CROSSBOW bit, since they leave fiber lengths equal). */
enum {
    C_FLAT,
    C_CENTRE,
    C_EDGE_LEFT,
    C_EDGE_RIGHT,
    C_EDGE_BOTH,
    C_QUARTER,
    C_MIX,
    C_BOW,
    C_CROSSBOW,
    C_OTHER,
    C_COUNT
};
static const char *class_name[C_COUNT] = {"flat",    "centre", "edge L", "edge R", "edges",
                                          "quarter", "mix",    "bow",    "xbow",   "other"};

typedef struct sheet_result {
    int label;
    flt_shape shape;
    double confidence, bow, crossbow, peak_i;
    unsigned components;
} sheet_result;

static flt_options *options_with(int n, const flt_option *keys, const double *values) {
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    for (int i = 0; i < n; ++i)
        assert_int_equal(flt_options_set(o, keys[i], values[i]), FLT_OK);
    return o;
}

static flt_sim *make_sim(unsigned seed) {
    flt_calib *calib = NULL;
    assert_int_equal(
        flt_calib_create_reference(0, 2048, -0.5 * PITCH * (FIBERS - 1), PITCH, FIBERS, &calib),
        FLT_OK);
    const flt_option keys[5] = {FLT_OPT_SIM_SEED, FLT_OPT_SIM_HEAVE_SIGMA,
                                FLT_OPT_SIM_ECCENTRICITY_AMPLITUDE, FLT_OPT_SIM_ECCENTRICITY_PERIOD,
                                FLT_OPT_SIM_PEAK_SIGMA};
    const double values[5] = {seed, 2.5, 0.5, 50.0, 1.0 / 16.0};
    flt_options *o = options_with(5, keys, values);
    flt_sim *sim = NULL;
    assert_int_equal(flt_sim_create(calib, o, &sim), FLT_OK);
    flt_options_destroy(o);
    flt_calib_destroy(calib);
    return sim;
}

/* The defects of test class c for seed index i: amplitudes 5..7 mm
 * (10..14 mm peak to peak) and periods 800..1800 mm vary with i. */
static void add_defects(flt_sim *sim, int c, int i) {
    const double A = 5.0 + 0.5 * i, P = 800.0 + 250.0 * i;
    switch (c) {
        case C_FLAT:
            break;
        case C_CENTRE:
            assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, A, P), FLT_OK);
            break;
        case C_EDGE_LEFT:
            assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_LEFT, A, P), FLT_OK);
            break;
        case C_EDGE_RIGHT:
            assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_RIGHT, A, P), FLT_OK);
            break;
        case C_EDGE_BOTH:
            assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, A, P), FLT_OK);
            break;
        case C_QUARTER:
            assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_QUARTER_BUCKLE, A, P), FLT_OK);
            break;
        case C_MIX:
            assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, A, P), FLT_OK);
            assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, -A, P), FLT_OK);
            break;
        case C_BOW:
            /* Coil set: half a sine over the 3300 mm sheet, a hump of A mm. */
            assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_BOW, A, 6600.0), FLT_OK);
            break;
        case C_CROSSBOW:
            /* Edges A mm above the centre, constant along the sheet. */
            assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CROSSBOW, A - 1.5, 0.0), FLT_OK);
            break;
        default:
            fail();
    }
}

static int label_of(flt_shape shape, unsigned components) {
    switch (shape) {
        case FLT_SHAPE_FLAT:
            if (components & FLT_SHAPE_HAS_BOW)
                return C_BOW;
            if (components & FLT_SHAPE_HAS_CROSSBOW)
                return C_CROSSBOW;
            return C_FLAT;
        case FLT_SHAPE_CENTRE_BUCKLE:
            return C_CENTRE;
        case FLT_SHAPE_WAVY_EDGE_LEFT:
            return C_EDGE_LEFT;
        case FLT_SHAPE_WAVY_EDGE_RIGHT:
            return C_EDGE_RIGHT;
        case FLT_SHAPE_WAVY_EDGE_BOTH:
            return C_EDGE_BOTH;
        case FLT_SHAPE_QUARTER_BUCKLE:
            return C_QUARTER;
        case FLT_SHAPE_MIX:
            return C_MIX;
        default:
            return C_OTHER;
    }
}

/* Simulates, reconstructs (whole sheet) and evaluates one sheet. */
static sheet_result run_sheet(int c, int i, unsigned seed, int rigid_motion) {
    flt_sim *sim = make_sim(seed);
    add_defects(sim, c, i);
    const size_t n = (size_t)ROWS * FIBERS;
    double *s = malloc(ROWS * sizeof *s), *h = malloc(n * sizeof *h), *g = malloc(n * sizeof *g),
           *z = malloc(n * sizeof *z);
    uint8_t *flags = malloc(n);
    assert_int_equal(flt_sim_next_rows(sim, ROWS, FIBERS, NULL, s, h, g, NULL, NULL), FLT_OK);
    const flt_option key = FLT_OPT_RIGID_MOTION;
    const double value = rigid_motion;
    flt_options *o = options_with(1, &key, &value);
    assert_int_equal(flt_reconstruct(o, ROWS, FIBERS, s, h, g, NULL, z, flags), FLT_OK);
    flt_options_destroy(o);

    double x[FIBERS];
    for (int k = 0; k < FIBERS; ++k)
        x[k] = -0.5 * PITCH * (FIBERS - 1) + PITCH * k;
    flt_flatness *f = NULL;
    assert_int_equal(flt_flatness_create(FIBERS, x, NULL, &f), FLT_OK);
    assert_int_equal(flt_flatness_evaluate(f, ROWS, FIBERS, s, z, flags), FLT_OK);
    sheet_result r;
    assert_int_equal(
        flt_flatness_shape(f, &r.shape, &r.confidence, &r.components, &r.bow, &r.crossbow), FLT_OK);
    size_t zones = 0;
    assert_int_equal(flt_flatness_zones(f, &zones), FLT_OK);
    double *ziu = malloc(zones * sizeof *ziu);
    assert_int_equal(flt_flatness_zone_results(f, zones, ziu, NULL), FLT_OK);
    double lo = INFINITY, hi = -INFINITY;
    for (size_t j = 0; j < zones; ++j) {
        lo = fmin(lo, ziu[j]);
        hi = fmax(hi, ziu[j]);
    }
    r.peak_i = hi - lo;
    r.label = label_of(r.shape, r.components);
    free(ziu);
    flt_flatness_destroy(f);
    free(s);
    free(h);
    free(g);
    free(z);
    free(flags);
    flt_sim_destroy(sim);
    return r;
}

/* 9 classes x 5 seeds, all classified correctly. */
static void simulated_sheets_are_classified(void **state) {
    (void)state;
    int confusion[C_COUNT][C_COUNT];
    memset(confusion, 0, sizeof confusion);
    for (int c = 0; c <= C_CROSSBOW; ++c) {
        for (int i = 0; i < SEEDS; ++i) {
            const sheet_result r = run_sheet(c, i, 1000u * (unsigned)c + 17u * (unsigned)i + 1u, 1);
            ++confusion[c][r.label];
            /* Bow and crossbow are reported only where they are. */
            if (c != C_BOW)
                assert_false(r.components & FLT_SHAPE_HAS_BOW);
            if (c != C_CROSSBOW)
                assert_false(r.components & FLT_SHAPE_HAS_CROSSBOW);
            print_message("%-8s seed %d: %-15s conf %.2f  zone span %7.2f IU  bow %6.2f mm  "
                          "crossbow %6.2f mm  components 0x%02x\n",
                          class_name[c], i, flt_shape_string(r.shape), r.confidence, r.peak_i,
                          r.bow, r.crossbow, r.components);
        }
    }
    char line[256];
    int at = snprintf(line, sizeof line, "%-8s", "true \\ got");
    for (int p = 0; p < C_COUNT; ++p)
        at += snprintf(line + at, sizeof line - at, "%8s", class_name[p]);
    print_message("%s\n", line);
    for (int c = 0; c <= C_CROSSBOW; ++c) {
        at = snprintf(line, sizeof line, "%-10s", class_name[c]);
        for (int p = 0; p < C_COUNT; ++p)
            at += snprintf(line + at, sizeof line - at, "%8d", confusion[c][p]);
        print_message("%s\n", line);
    }
    for (int c = 0; c <= C_CROSSBOW; ++c)
        assert_int_equal(confusion[c][c], SEEDS);
}

/* The noise floor: flat sheets under the reference noise span far less
 * than the flat limit (5 I-Units) in their zone profile, reconstructed
 * either way. Printed for both reconstructor settings. */
static void flat_sheets_stay_below_the_flat_limit(void **state) {
    (void)state;
    for (int rigid = 0; rigid <= 1; ++rigid) {
        double worst = 0.0, worst_bow = 0.0, worst_crossbow = 0.0;
        for (int i = 0; i < SEEDS; ++i) {
            const sheet_result r = run_sheet(C_FLAT, i, 77u + (unsigned)i, rigid);
            worst = fmax(worst, r.peak_i);
            worst_bow = fmax(worst_bow, fabs(r.bow));
            worst_crossbow = fmax(worst_crossbow, fabs(r.crossbow));
            assert_int_equal(r.shape, FLT_SHAPE_FLAT);
        }
        print_message("rigid_motion %d: flat sheets' zone span up to %.3f I-Units, |bow| up to "
                      "%.3f mm, |crossbow| up to %.3f mm\n",
                      rigid, worst, worst_bow, worst_crossbow);
        /* A tenth of the flat limit and of the bow limits: the classes above
         * are decided by the sheet, not by the noise. */
        assert_true(worst < 0.5);
        assert_true(worst_bow < 0.2 && worst_crossbow < 0.2);
    }
}

/* Streaming use against whole-sheet use on the same material. A 15000 mm
 * strip with the reference's defects (12 mm peak-to-peak centre buckle with
 * opposite wavy edges, 1800 mm along) and the reference noise streams
 * through flt_recon (push and pull, default lag) into flt_flatness_push with
 * 3000 mm windows every 1000 mm. Each window's zone profile must agree with
 * flt_flatness_evaluate over the same rows of flt_reconstruct's whole-strip
 * solution within 1% of the profile's span. The two differ only by the
 * reconstructor's finite lag (the metrics of the same rows agree to
 * rounding: test_flatness.c). */
static void streamed_windows_agree_with_whole_sheet(void **state) {
    (void)state;
    enum { STRIP_ROWS = 5000, BLOCK = 10 };
    flt_sim *sim = make_sim(4242);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 6.0, 1800.0), FLT_OK);
    assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, -6.0, 1800.0), FLT_OK);
    const size_t n = (size_t)STRIP_ROWS * FIBERS;
    double *s = malloc(STRIP_ROWS * sizeof *s), *h = malloc(n * sizeof *h),
           *g = malloc(n * sizeof *g), *z_whole = malloc(n * sizeof *z_whole),
           *z_stream = malloc(n * sizeof *z_stream), *s_stream = malloc(STRIP_ROWS * sizeof *s);
    uint8_t *fl_whole = malloc(n), *fl_stream = malloc(n);
    assert_int_equal(flt_sim_next_rows(sim, STRIP_ROWS, FIBERS, NULL, s, h, g, NULL, NULL), FLT_OK);
    const flt_option key = FLT_OPT_RIGID_MOTION;
    const double one = 1.0;
    flt_options *o = options_with(1, &key, &one);
    assert_int_equal(flt_reconstruct(o, STRIP_ROWS, FIBERS, s, h, g, NULL, z_whole, fl_whole),
                     FLT_OK);

    double x[FIBERS];
    for (int k = 0; k < FIBERS; ++k)
        x[k] = -0.5 * PITCH * (FIBERS - 1) + PITCH * k;
    flt_flatness *stream = NULL, *whole = NULL;
    assert_int_equal(flt_flatness_create(FIBERS, x, NULL, &stream), FLT_OK);
    assert_int_equal(flt_flatness_create(FIBERS, x, NULL, &whole), FLT_OK);
    size_t zones = 0;
    assert_int_equal(flt_flatness_zones(stream, &zones), FLT_OK);
    double *zi_stream = malloc(zones * sizeof(double)), *zi_whole = malloc(zones * sizeof(double));

    flt_recon *recon = NULL;
    assert_int_equal(flt_recon_create(FIBERS, o, &recon), FLT_OK);
    flt_options_destroy(o);
    size_t pulled = 0, fed = 0, windows = 0;
    double worst = 0.0;
    for (size_t pushed = 0; pushed <= STRIP_ROWS; pushed += BLOCK) {
        if (pushed < STRIP_ROWS) {
            assert_int_equal(flt_recon_push(recon, BLOCK, FIBERS, s + pushed, h + pushed * FIBERS,
                                            g + pushed * FIBERS, NULL),
                             FLT_OK);
            if (pushed + BLOCK == STRIP_ROWS)
                assert_int_equal(flt_recon_end_sheet(recon), FLT_OK);
        }
        size_t got = 0;
        assert_int_equal(flt_recon_pull(recon, STRIP_ROWS - pulled, FIBERS, s_stream + pulled,
                                        z_stream + pulled * FIBERS, fl_stream + pulled * FIBERS,
                                        &got),
                         FLT_OK);
        pulled += got;
        int last_round = pushed >= STRIP_ROWS;
        for (;;) {
            size_t used = 0;
            int evaluated = 0;
            if (fed < pulled) {
                assert_int_equal(flt_flatness_push(stream, pulled - fed, FIBERS, s_stream + fed,
                                                   z_stream + fed * FIBERS,
                                                   fl_stream + fed * FIBERS, &used, &evaluated),
                                 FLT_OK);
                fed += used;
            } else if (last_round) {
                assert_int_equal(flt_flatness_finish(stream, &evaluated), FLT_OK);
                last_round = 0;
            }
            if (!evaluated) {
                if (fed == pulled && !last_round)
                    break;
                continue;
            }
            ++windows;
            double first, last;
            size_t rows;
            assert_int_equal(flt_flatness_window(stream, &first, &last, &rows, NULL, NULL), FLT_OK);
            size_t r0 = 0;
            while (s[r0] < first)
                ++r0;
            assert_near(s[r0 + rows - 1], last, 0.0);
            assert_int_equal(flt_flatness_evaluate(whole, rows, FIBERS, s + r0,
                                                   z_whole + r0 * FIBERS, fl_whole + r0 * FIBERS),
                             FLT_OK);
            assert_int_equal(flt_flatness_zone_results(stream, zones, zi_stream, NULL), FLT_OK);
            assert_int_equal(flt_flatness_zone_results(whole, zones, zi_whole, NULL), FLT_OK);
            double lo = INFINITY, hi = -INFINITY, diff = 0.0;
            for (size_t j = 0; j < zones; ++j) {
                lo = fmin(lo, zi_whole[j]);
                hi = fmax(hi, zi_whole[j]);
                diff = fmax(diff, fabs(zi_stream[j] - zi_whole[j]));
            }
            print_message("window %zu [%.0f, %.0f] mm: zone span %.2f I-Units, largest "
                          "streamed - whole difference %.4f I-Units (%.3f%%)\n",
                          windows, first, last, hi - lo, diff, 100 * diff / (hi - lo));
            worst = fmax(worst, diff / (hi - lo));
        }
        if (pushed >= STRIP_ROWS)
            break;
    }
    /* Windows end every 1000 mm from 3000 mm to the strip's 14997 mm (12),
     * and finish() adds the last 2997 mm: 13 windows. */
    assert_int_equal(windows, 13);
    assert_int_equal(fed, STRIP_ROWS);
    assert_true(worst <= 0.01);
    flt_recon_destroy(recon);
    flt_flatness_destroy(stream);
    flt_flatness_destroy(whole);
    flt_sim_destroy(sim);
    free(zi_stream);
    free(zi_whole);
    free(s);
    free(h);
    free(g);
    free(z_whole);
    free(z_stream);
    free(s_stream);
    free(fl_whole);
    free(fl_stream);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(simulated_sheets_are_classified),
        cmocka_unit_test(flat_sheets_stay_below_the_flat_limit),
        cmocka_unit_test(streamed_windows_agree_with_whole_sheet),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
