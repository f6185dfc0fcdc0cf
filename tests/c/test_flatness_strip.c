// SPDX-License-Identifier: Apache-2.0
/*
 * Zones on the strip (flatline/flatness.h, "Zones on the strip"): strips
 * narrower than the sensor, off-centre and wandering sideways, measured in
 * strip coordinates, against the truth computed in strip coordinates.
 *
 * The line: the simulator's strip (flatline/sim.h) 900, 1500 or 2200 mm wide
 * on a sensor sized for 2500 mm, off-centre, wandering by a 40 mm sine
 * (30 m period) plus a 10 mm random walk (the +-50 mm of the issue), under
 * the reference noise (2.5 mm heave, 0.5 mm eccentricity at 50 mm, 1/16 px
 * peak noise). Rows from flt_sim_next_rows with their off-strip fibers
 * flagged; the strip's edges per row as the extractor measures them
 * (tests/c/test_field.c: RMS 0.07-0.10 mm from rendered frames), modelled
 * as the truth (flt_sim_strip_edges, laser 2) plus 0.1 mm of Gaussian noise
 * per row and edge. Reconstruction: flt_reconstruct_flagged with
 * rigid_motion = 1 (as tests/c/test_flatness_shape.c).
 *
 * The truth in strip coordinates: result fiber k lies at strip coordinate
 * x_s(k) (flt_flatness_fiber_positions); its true profile along the
 * window is the sheet at (x_s(k), s) (flt_sim_surface: the sheet is
 * defined in strip coordinates), measured by the same I-Unit arithmetic
 * (a second flt_flatness over those profiles, the gauge's fibers without
 * data masked out), and a zone's truth is the mean over the zone's valid
 * fibers, as the gauge's.
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
#include "sheet.h"

#define ROWS 1100 /* 3300 mm at 3 mm */

#define assert_near(a, b, tol)                                                 \
  do {                                                                         \
    const double a_ = (a), b_ = (b);                                           \
    if (!(fabs(a_ - b_) <= (tol)))                                             \
      fail_msg("%s = %.17g, expected %.17g +- %g", #a, a_, b_, (double)(tol)); \
  } while (0)

static flt_options *options_with(int n, const flt_option *keys, const double *values) {
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    for (int i = 0; i < n; ++i)
        assert_int_equal(flt_options_set(o, keys[i], values[i]), FLT_OK);
    return o;
}

/* Flatness options: the keys given, and room for one sheet. The default
 * flat_row_capacity (4096 rows) would be nearly four times a sheet here,
 * and each create writes all of it (flatness.h, "Memory"): the room a
 * sheet needs is what this file tests, and the rest was most of its time. */
static flt_options *flat_options(int n, const flt_option *keys, const double *values) {
    flt_options *o = options_with(n, keys, values);
    assert_int_equal(flt_options_set(o, FLT_OPT_FLAT_ROW_CAPACITY, ROWS), FLT_OK);
    return o;
}

/* A sensor grid of `fibers` at `pitch` centred on x = 0. */
typedef struct grid {
    size_t fibers;
    double pitch;
    double *x;
} grid;

static grid make_grid(size_t fibers, double pitch) {
    grid g = {fibers, pitch, malloc(fibers * sizeof(double))};
    for (size_t k = 0; k < fibers; ++k)
        g.x[k] = ((double)k - 0.5 * (double)(fibers - 1)) * pitch;
    return g;
}

/* One simulated, reconstructed window of a strip `width` wide at `offset`
 * (wandering unless `still`): rows, reconstructed heights and flags, the
 * strip's measured edges per row, and the simulator (for the truth). */
typedef struct strip_sheet {
    size_t rows, fibers;
    double *s, *encoder, *z, *left, *right;
    uint8_t *flags;
    flt_sim *sim;
} strip_sheet;

typedef void (*add_defects_fn)(flt_sim *sim, int c, int i);

static strip_sheet make_sheet_with(const grid *g, double width, double offset, int still,
                                   unsigned seed, add_defects_fn add, int c, int i,
                                   double peak_sigma) {
    flt_calib *calib = NULL;
    assert_int_equal(flt_calib_create_reference(0, 2048, g->x[0], g->pitch, g->fibers, &calib),
                     FLT_OK);
    const flt_option keys[] = {FLT_OPT_SIM_SEED,
                               FLT_OPT_SIM_HEAVE_SIGMA,
                               FLT_OPT_SIM_ECCENTRICITY_AMPLITUDE,
                               FLT_OPT_SIM_ECCENTRICITY_PERIOD,
                               FLT_OPT_SIM_PEAK_SIGMA,
                               FLT_OPT_SIM_SURROUND,
                               FLT_OPT_SIM_STRIP_WIDTH,
                               FLT_OPT_SIM_STRIP_OFFSET,
                               FLT_OPT_SIM_WANDER_AMPLITUDE,
                               FLT_OPT_SIM_WANDER_SIGMA,
                               FLT_OPT_SIM_START};
    /* The start moves each seed's window to another stretch of the wander. */
    const double values[] = {seed,
                             2.5,
                             0.5,
                             50.0,
                             peak_sigma,
                             2,
                             width,
                             offset,
                             still ? 0 : 40,
                             still ? 0 : 10,
                             4000.0 * (seed % 7)};
    flt_options *o = options_with(11, keys, values);
    strip_sheet sh;
    sh.rows = ROWS;
    sh.fibers = g->fibers;
    assert_int_equal(flt_sim_create(calib, o, &sh.sim), FLT_OK);
    flt_options_destroy(o);
    flt_calib_destroy(calib);
    add(sh.sim, c, i);
    const size_t n = ROWS * g->fibers;
    sh.s = malloc(ROWS * sizeof(double));
    sh.encoder = malloc(ROWS * sizeof(double));
    sh.left = malloc(ROWS * sizeof(double));
    sh.right = malloc(ROWS * sizeof(double));
    sh.z = malloc(n * sizeof(double));
    sh.flags = malloc(n);
    double *h = malloc(n * sizeof(double)), *sl = malloc(n * sizeof(double));
    uint8_t *valid = malloc(n);
    assert_int_equal(
        flt_sim_next_rows(sh.sim, ROWS, g->fibers, sh.encoder, sh.s, h, sl, valid, NULL), FLT_OK);
    uint8_t *in_flags = malloc(n);
    for (size_t j = 0; j < n; ++j)
        in_flags[j] = valid[j] ? 0 : FLT_FLAG_OFF_STRIP;
    const flt_option key = FLT_OPT_RIGID_MOTION;
    const double one = 1.0;
    o = options_with(1, &key, &one);
    assert_int_equal(
        flt_reconstruct_flagged(o, ROWS, g->fibers, sh.s, h, sl, in_flags, sh.z, sh.flags), FLT_OK);
    flt_options_destroy(o);
    /* The measured edges: the truth plus 0.1 mm of noise. */
    assert_int_equal(flt_sim_strip_edges(sh.sim, 2, ROWS, sh.encoder, sh.left, sh.right, NULL),
                     FLT_OK);
    test_rng rng;
    test_rng_seed(&rng, seed * 31u + 5u);
    for (size_t r = 0; r < ROWS; ++r) {
        sh.left[r] += 0.1 * test_rng_gauss(&rng);
        sh.right[r] += 0.1 * test_rng_gauss(&rng);
    }
    free(h), free(sl), free(valid), free(in_flags);
    return sh;
}

static strip_sheet make_sheet(const grid *g, double width, double offset, int still, unsigned seed,
                              add_defects_fn add, int c, int i) {
    return make_sheet_with(g, width, offset, still, seed, add, c, i, 1.0 / 16);
}

static void free_sheet(strip_sheet *sh) {
    flt_sim_destroy(sh->sim);
    free(sh->s), free(sh->encoder), free(sh->z), free(sh->left), free(sh->right), free(sh->flags);
}

/* The zone I-Units of the truth in strip coordinates for the gauge's last
 * window of `f` (see the file comment) into truth[zones]. */
static void truth_zones(flt_flatness *f, const strip_sheet *sh, const flt_options *options,
                        double *truth) {
    const size_t K = sh->fibers;
    size_t zones = 0;
    assert_int_equal(flt_flatness_zones(f, &zones), FLT_OK);
    double *xs = malloc(K * sizeof(double)), *iu = malloc(K * sizeof(double));
    uint8_t *fl = malloc(K);
    assert_int_equal(flt_flatness_fiber_positions(f, K, xs, NULL), FLT_OK);
    assert_int_equal(flt_flatness_fiber_results(f, K, NULL, NULL, NULL, NULL, NULL, fl), FLT_OK);
    /* The sheet along each result fiber's strip coordinate. */
    double *zt = malloc(sh->rows * K * sizeof(double));
    uint8_t *ft = malloc(sh->rows * K);
    for (size_t r = 0; r < sh->rows; ++r)
        for (size_t k = 0; k < K; ++k) {
            double z = 0;
            if (!(fl[k] & FLT_FIBER_NO_DATA))
                assert_int_equal(flt_sim_surface(sh->sim, 1, &xs[k], &sh->s[r], &z), FLT_OK);
            zt[r * K + k] = z;
            ft[r * K + k] = fl[k] & FLT_FIBER_NO_DATA ? FLT_FLAG_NO_DATA : 0;
        }
    /* Strip coordinates increase with k: a grid in its own right. */
    flt_flatness *t = NULL;
    const flt_option key = FLT_OPT_FLAT_ZONES_ON;
    double grid_only = FLT_ZONES_ON_GRID;
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    for (size_t i = 0;; ++i) { /* copy the caller's flat_* options, then zones on the grid */
        flt_option k;
        if (flt_option_at(i, &k) != FLT_OK)
            break;
        if (k < 500 || k >= 600) /* another component's key: refused by flatness */
            continue;
        double v;
        assert_int_equal(flt_options_get(options, k, &v), FLT_OK);
        assert_int_equal(flt_options_set(o, k, v), FLT_OK);
    }
    assert_int_equal(flt_options_set(o, key, grid_only), FLT_OK);
    assert_int_equal(flt_flatness_create(K, xs, o, &t), FLT_OK);
    flt_options_destroy(o);
    assert_int_equal(flt_flatness_evaluate(t, sh->rows, K, sh->s, zt, ft), FLT_OK);
    assert_int_equal(flt_flatness_fiber_results(t, K, NULL, iu, NULL, NULL, NULL, NULL), FLT_OK);
    flt_flatness_destroy(t);
    /* Zones: the gauge's layout in strip coordinates. */
    double *centre = malloc(zones * sizeof(double)), *width = malloc(zones * sizeof(double));
    assert_int_equal(flt_flatness_zone_positions(f, zones, centre, NULL, width, NULL), FLT_OK);
    /* The flatness header's membership: the zone holding x_s; on a
     * boundary the one nearer the centre line (above it at the centre). */
    size_t used = 0;
    while (used < zones && width[used] > 0)
        ++used;
    double *sum = calloc(zones, sizeof(double));
    size_t *count = calloc(zones, sizeof(size_t));
    for (size_t k = 0; k < K; ++k) {
        if (fl[k] & FLT_FIBER_NO_DATA)
            continue;
        const double position = (xs[k] - (centre[0] - 0.5 * width[0])) / width[0];
        double j = floor(position);
        if (fabs(position - round(position)) < 1e-9)
            j = xs[k] > 0 ? round(position) - 1 : round(position);
        const size_t zj = j < 0 ? 0 : j >= (double)used ? used - 1 : (size_t)j;
        sum[zj] += iu[k], ++count[zj];
    }
    for (size_t j = 0; j < zones; ++j)
        truth[j] = count[j] ? sum[j] / (double)count[j] : NAN;
    free(sum), free(count);
    free(xs), free(iu), free(fl), free(zt), free(ft), free(centre), free(width);
}

/* ------------------------------------------------------------------ targets */

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

/* The defects of class c for seed index i, as tests/c/test_flatness_shape.c:
 * amplitudes 5..7 mm and periods 800..1800 mm. */
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
            assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_BOW, A, 6600.0), FLT_OK);
            break;
        case C_CROSSBOW:
            assert_int_equal(flt_sim_add_defect(sim, FLT_SIM_CROSSBOW, A - 1.5, 0.0), FLT_OK);
            break;
        default:
            fail();
    }
}

static int label_of(flt_shape shape, unsigned components) {
    switch (shape) {
        case FLT_SHAPE_FLAT:
            return components & FLT_SHAPE_HAS_BOW        ? C_BOW
                   : components & FLT_SHAPE_HAS_CROSSBOW ? C_CROSSBOW
                                                         : C_FLAT;
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

static const double k_widths[3] = {900, 1500, 2200};
static const double k_offsets[3] = {137, -211, 31}; /* mm, the strip's mean position */

/* The issue's zone target: strips 900, 1500 and 2200 mm wide, off-centre
 * and wandering +-50 mm, zone I-Units within 0.1 I-Unit of the truth in
 * strip coordinates. Sensor: 1251 fibers at 2 mm (x = -1250 .. 1250 mm).
 * Sheets: a centre buckle with opposite wavy edges (the reference's shape),
 * a quarter buckle, a wavy drive-side edge; 2 seeds each. Zones of 50 mm.
 * Both I-Unit references (the shortest fiber, the default, and the mean
 * fiber). */
static void zones_on_wandering_strips_match_the_truth(void **state) {
    (void)state;
    FLT_SWEEP_NOT_UNDER_SANITIZERS();
    grid g = make_grid(1251, 2.0);
    /* One flatness per reference, evaluating every sheet in turn: a handle
     * is reused from sheet to sheet (and each create writes its whole
     * window, flatness.h, "Memory"). */
    flt_options *judge_options[2];
    flt_flatness *judge[2];
    for (int reference = 0; reference < 2; ++reference) {
        const flt_option key = FLT_OPT_FLAT_REFERENCE;
        const double value = reference;
        judge_options[reference] = flat_options(1, &key, &value);
        assert_int_equal(
            flt_flatness_create(g.fibers, g.x, judge_options[reference], &judge[reference]),
            FLT_OK);
    }
    double worst[2] = {0, 0};
    for (int w = 0; w < 3; ++w) {
        double width_worst[2] = {0, 0}, span = 0;
        for (int sheet = 0; sheet < 6; ++sheet) {
            static const int classes[3] = {C_MIX, C_QUARTER, C_EDGE_LEFT};
            const int c = classes[sheet / 2], i = 2 * (sheet % 2);
            strip_sheet sh =
                make_sheet(&g, k_widths[w], k_offsets[w], 0,
                           101u + 13u * (unsigned)sheet + 7u * (unsigned)w, add_defects, c, i);
            for (int reference = 0; reference < 2; ++reference) {
                flt_options *o = judge_options[reference];
                flt_flatness *f = judge[reference];
                assert_int_equal(flt_flatness_evaluate_strip(f, sh.rows, g.fibers, sh.s, sh.z,
                                                             sh.flags, sh.left, sh.right),
                                 FLT_OK);
                unsigned wf = 0;
                assert_int_equal(flt_flatness_window(f, NULL, NULL, NULL, &wf, NULL), FLT_OK);
                assert_true(wf & FLT_WINDOW_ON_STRIP);
                size_t zones = 0;
                assert_int_equal(flt_flatness_zones(f, &zones), FLT_OK);
                double *gz = malloc(zones * sizeof(double)), *tz = malloc(zones * sizeof(double));
                uint8_t *zf = malloc(zones);
                assert_int_equal(flt_flatness_zone_results(f, zones, gz, zf), FLT_OK);
                truth_zones(f, &sh, o, tz);
                size_t used = 0;
                for (size_t j = 0; j < zones; ++j) {
                    if (zf[j] & FLT_ZONE_OFF_STRIP) {
                        assert_true(isnan(gz[j]) && (zf[j] & FLT_ZONE_NO_DATA));
                        continue;
                    }
                    ++used;
                    assert_int_equal(zf[j], 0);
                    width_worst[reference] = fmax(width_worst[reference], fabs(gz[j] - tz[j]));
                    span = fmax(span, fabs(tz[j]));
                }
                /* 50 mm zones on the strip: W / 50 of them. */
                assert_int_equal(used, (size_t)ceil(k_widths[w] / 50 - 1e-9));
                free(gz), free(tz), free(zf);
            }
            free_sheet(&sh);
        }
        print_message("strip %4.0f mm wandering: zones within %.3f I-Units of the truth in strip "
                      "coordinates (reference: the shortest fiber; %.3f with the mean fiber); "
                      "profiles up to %.1f I-Units\n",
                      k_widths[w], width_worst[0], width_worst[1], span);
        for (int reference = 0; reference < 2; ++reference)
            worst[reference] = fmax(worst[reference], width_worst[reference]);
    }
    assert_true(worst[0] <= 0.1 && worst[1] <= 0.1);
    for (int reference = 0; reference < 2; ++reference) {
        flt_flatness_destroy(judge[reference]);
        flt_options_destroy(judge_options[reference]);
    }
    free(g.x);
}

/* One sheet's class on the strip of width w, by the flatness f (on g's
 * fibers, default options), reused from sheet to sheet. */
static int classify(flt_flatness *f, const grid *g, int w, int c, int i, unsigned seed, int still) {
    strip_sheet sh =
        make_sheet(g, k_widths[w], still ? 0 : k_offsets[w], still, seed, add_defects, c, i);
    assert_int_equal(
        flt_flatness_evaluate_strip(f, sh.rows, g->fibers, sh.s, sh.z, sh.flags, sh.left, sh.right),
        FLT_OK);
    flt_shape shape;
    unsigned components;
    assert_int_equal(flt_flatness_shape(f, &shape, NULL, &components, NULL, NULL), FLT_OK);
    free_sheet(&sh);
    return label_of(shape, components);
}

/* The 9 shape classes x 5 seeds of test_flatness_shape.c stay on the
 * diagonal for each width, off-centre and wandering. Sensor: 251 fibers at
 * 10 mm (the defects vary across the width on scales of W/8 = 112 mm and
 * more; 50 mm zones hold 5 fibers), x = -1250 .. 1250 mm. */
static void shape_classes_on_wandering_strips(void **state) {
    (void)state;
    FLT_SWEEP_NOT_UNDER_SANITIZERS();
    grid g = make_grid(251, 10.0);
    flt_options *o = flat_options(0, NULL, NULL);
    flt_flatness *f = NULL;
    assert_int_equal(flt_flatness_create(g.fibers, g.x, o, &f), FLT_OK);
    flt_options_destroy(o);
    for (int w = 0; w < 3; ++w) {
        int confusion[C_COUNT][C_COUNT];
        memset(confusion, 0, sizeof confusion);
        for (int c = 0; c <= C_CROSSBOW; ++c)
            for (int i = 0; i < 5; ++i)
                ++confusion[c][classify(f, &g, w, c, i,
                                        1000u * (unsigned)c + 17u * (unsigned)i + 1u, 0)];
        char line[256];
        int at = snprintf(line, sizeof line, "strip %4.0f  ", k_widths[w]);
        for (int p = 0; p < C_COUNT; ++p)
            at += snprintf(line + at, sizeof line - (size_t)at, "%8s", class_name[p]);
        print_message("%s\n", line);
        for (int c = 0; c <= C_CROSSBOW; ++c) {
            at = snprintf(line, sizeof line, "%-12s", class_name[c]);
            for (int p = 0; p < C_COUNT; ++p)
                at += snprintf(line + at, sizeof line - (size_t)at, "%8d", confusion[c][p]);
            print_message("%s\n", line);
        }
        for (int c = 0; c <= C_CROSSBOW; ++c)
            assert_int_equal(confusion[c][c], 5);
    }
    flt_flatness_destroy(f);
    free(g.x);
}

/* Streaming with the edges (flt_flatness_push_strip) gives each window what
 * flt_flatness_evaluate_strip gives over the same rows, bitwise; the strip's
 * width and position per window match the truth; the same rows with the
 * edges taken from the off-strip flags alone (no edge arrays) still land
 * on the strip, to within half a pitch; with the drive side at high x the
 * zones come in the other order. */
static void streaming_flags_and_drive_side(void **state) {
    (void)state;
    grid g = make_grid(251, 10.0);
    strip_sheet sh = make_sheet(&g, 1500, -211, 0, 4242u, add_defects, C_MIX, 2);
    flt_flatness *stream = NULL, *whole = NULL;
    flt_options *room = flat_options(0, NULL, NULL);
    assert_int_equal(flt_flatness_create(g.fibers, g.x, room, &stream), FLT_OK);
    assert_int_equal(flt_flatness_create(g.fibers, g.x, room, &whole), FLT_OK);
    size_t zones = 0;
    assert_int_equal(flt_flatness_zones(stream, &zones), FLT_OK);
    double *a = malloc(zones * sizeof(double)), *b = malloc(zones * sizeof(double));
    size_t fed = 0, windows = 0;
    while (fed < sh.rows) {
        size_t used = 0;
        int evaluated = 0;
        assert_int_equal(flt_flatness_push_strip(stream, sh.rows - fed, g.fibers, sh.s + fed,
                                                 sh.z + fed * g.fibers, sh.flags + fed * g.fibers,
                                                 sh.left + fed, sh.right + fed, &used, &evaluated),
                         FLT_OK);
        fed += used;
        if (!evaluated)
            continue;
        ++windows;
        double first, last;
        size_t rows;
        assert_int_equal(flt_flatness_window(stream, &first, &last, &rows, NULL, NULL), FLT_OK);
        size_t r0 = 0;
        while (sh.s[r0] < first)
            ++r0;
        assert_int_equal(flt_flatness_evaluate_strip(whole, rows, g.fibers, sh.s + r0,
                                                     sh.z + r0 * g.fibers, sh.flags + r0 * g.fibers,
                                                     sh.left + r0, sh.right + r0),
                         FLT_OK);
        assert_int_equal(flt_flatness_zone_results(stream, zones, a, NULL), FLT_OK);
        assert_int_equal(flt_flatness_zone_results(whole, zones, b, NULL), FLT_OK);
        assert_memory_equal(a, b, zones * sizeof(double));
        /* The strip over the window against the truth's edges. */
        double width[3], centre[3];
        assert_int_equal(flt_flatness_strip(stream, width, centre), FLT_OK);
        double lo = INFINITY, hi = -INFINITY, sum = 0;
        for (size_t r = r0; r < r0 + rows; ++r) {
            double l, rr;
            assert_int_equal(flt_sim_strip_edges(sh.sim, 2, 1, &sh.encoder[r], &l, &rr, NULL),
                             FLT_OK);
            const double c = 0.5 * (l + rr);
            lo = fmin(lo, c), hi = fmax(hi, c), sum += c;
        }
        /* The edges' 0.1 mm noise averages out; the moving mean over
         * +-100 mm cannot follow the wander's turns exactly. */
        assert_near(width[0], 1500, 0.05);
        assert_near(centre[0], sum / (double)rows, 0.05);
        assert_near(centre[1], lo, 0.2);
        assert_near(centre[2], hi, 0.2);
    }
    assert_int_equal(windows, 1); /* 3000 mm window, 3297 mm of rows */

    /* Edges from the flags alone, and the drive side at high x. */
    assert_int_equal(flt_flatness_evaluate_strip(whole, sh.rows, g.fibers, sh.s, sh.z, sh.flags,
                                                 sh.left, sh.right),
                     FLT_OK);
    assert_int_equal(flt_flatness_zone_results(whole, zones, a, NULL), FLT_OK);
    flt_flatness *from_flags = NULL, *mirrored = NULL;
    assert_int_equal(flt_flatness_create(g.fibers, g.x, room, &from_flags), FLT_OK);
    flt_options_destroy(room);
    assert_int_equal(flt_flatness_evaluate(from_flags, sh.rows, g.fibers, sh.s, sh.z, sh.flags),
                     FLT_OK);
    unsigned wf = 0;
    assert_int_equal(flt_flatness_window(from_flags, NULL, NULL, NULL, &wf, NULL), FLT_OK);
    assert_true(wf & FLT_WINDOW_ON_STRIP);
    double width[3], centre[3];
    assert_int_equal(flt_flatness_strip(from_flags, width, centre), FLT_OK);
    print_message("edges from the off-strip flags alone (10 mm pitch): width %.1f mm (true "
                  "1500), centre %.1f mm\n",
                  width[0], centre[0]);
    assert_near(width[0], 1500, 0.5 * g.pitch);
    assert_int_equal(flt_flatness_zone_results(from_flags, zones, b, NULL), FLT_OK);
    double diff = 0;
    for (size_t j = 0; j < 30; ++j)
        diff = fmax(diff, fabs(a[j] - b[j]));
    print_message("  zones from the flags' edges differ from the measured edges' by up to %.3f "
                  "I-Units\n",
                  diff);
    const flt_option key = FLT_OPT_FLAT_DRIVE_SIDE;
    const double high = FLT_SIDE_HIGH_X;
    flt_options *o = flat_options(1, &key, &high);
    assert_int_equal(flt_flatness_create(g.fibers, g.x, o, &mirrored), FLT_OK);
    flt_options_destroy(o);
    assert_int_equal(flt_flatness_evaluate_strip(mirrored, sh.rows, g.fibers, sh.s, sh.z, sh.flags,
                                                 sh.left, sh.right),
                     FLT_OK);
    assert_int_equal(flt_flatness_zone_results(mirrored, zones, b, NULL), FLT_OK);
    /* 30 zones on the 1500 mm strip; zone j from the other side is zone
     * 29 - j: the same fibers (the result fibers lie symmetric about the
     * centre line, and a fiber on a zone boundary belongs to the zone
     * nearer the centre) in the same zones, so to rounding. Except the two
     * middle zones: the fiber on the centre line, on their boundary,
     * belongs to the operator side's, which changes sides. */
    double mirror_diff = 0;
    for (size_t j = 0; j < 30; ++j)
        if (j != 14 && j != 15)
            mirror_diff = fmax(mirror_diff, fabs(a[j] - b[29 - j]));
    print_message("  drive side at high x: zones mirrored within %.3f I-Units\n", mirror_diff);
    assert_true(mirror_diff <= 1e-9);
    double sx[251], sensor[251];
    assert_int_equal(flt_flatness_fiber_positions(mirrored, g.fibers, sx, sensor), FLT_OK);
    assert_near(sensor[0] - sensor[1], 10.0, 1e-9); /* slots run towards low x */
    assert_near(sx[125], 0.0, 1e-9);
    flt_flatness_destroy(mirrored);
    flt_flatness_destroy(from_flags);
    flt_flatness_destroy(stream);
    flt_flatness_destroy(whole);
    free(a), free(b);
    free_sheet(&sh);
    free(g.x);
}

/* The case that motivated zones on the strip: a 1200 mm strip on a sensor
 * sized for 2000 mm (201 fibers at 10 mm), centred and moved 317 mm
 * sideways, with wavy edges and with a centre buckle. On the fiber grid
 * (flat_zones_on = 1, as before) the wavy edges read as a quarter buckle
 * centred and as a mix moved; the profile read from the strip's edge moved
 * by up to 1.7 I-Units, and the centre buckle's confidence dropped. On the
 * strip, centred and moved give the same class, the same confidence and the
 * same profile (the same material, the noise drawn alike: the peak noise
 * moves with the fibers, so within 0.1 I-Unit). */
static void an_off_centre_strip_reads_as_the_centred_one(void **state) {
    (void)state;
    grid g = make_grid(201, 10.0);
    const int classes[2] = {C_EDGE_BOTH, C_CENTRE};
    for (int ci = 0; ci < 2; ++ci) {
        double profile[2][64], confidence[2];
        int label[2], grid_label[2];
        size_t zones = 0;
        for (int moved = 0; moved < 2; ++moved) {
            strip_sheet sh =
                make_sheet(&g, 1200, moved ? 317 : 0, 1, 77u, add_defects, classes[ci], 2);
            for (int on_grid = 0; on_grid < 2; ++on_grid) {
                const flt_option key = FLT_OPT_FLAT_ZONES_ON;
                const double value = on_grid;
                flt_options *o = flat_options(1, &key, &value);
                flt_flatness *f = NULL;
                assert_int_equal(flt_flatness_create(g.fibers, g.x, o, &f), FLT_OK);
                flt_options_destroy(o);
                assert_int_equal(flt_flatness_evaluate_strip(f, sh.rows, g.fibers, sh.s, sh.z,
                                                             sh.flags, sh.left, sh.right),
                                 FLT_OK);
                flt_shape shape;
                unsigned components;
                double conf;
                assert_int_equal(flt_flatness_shape(f, &shape, &conf, &components, NULL, NULL),
                                 FLT_OK);
                if (on_grid) {
                    grid_label[moved] = label_of(shape, components);
                } else {
                    label[moved] = label_of(shape, components);
                    confidence[moved] = conf;
                    assert_int_equal(flt_flatness_zones(f, &zones), FLT_OK);
                    assert_true(zones <= 64);
                    assert_int_equal(flt_flatness_zone_results(f, zones, profile[moved], NULL),
                                     FLT_OK);
                }
                flt_flatness_destroy(f);
            }
            free_sheet(&sh);
        }
        double diff = 0;
        for (size_t j = 0; j < 24; ++j) /* 1200 mm: 24 zones */
            diff = fmax(diff, fabs(profile[0][j] - profile[1][j]));
        print_message("%s, 1200 mm strip centred / moved 317 mm: on the grid %s / %s; on the "
                      "strip %s / %s, confidence %.2f / %.2f, zone profiles within %.3f "
                      "I-Units\n",
                      class_name[classes[ci]], class_name[grid_label[0]], class_name[grid_label[1]],
                      class_name[label[0]], class_name[label[1]], confidence[0], confidence[1],
                      diff);
        assert_int_equal(label[0], classes[ci]);
        assert_int_equal(label[1], classes[ci]);
        assert_near(confidence[1], confidence[0], 0.05);
        assert_true(diff <= 0.1);
        assert_true(isnan(profile[0][24]) && isnan(profile[1][24])); /* off the strip */
    }
    free(g.x);
}

/* Where the strip's edge falls between two sensor fibers, the outermost
 * result fiber lies between the last fiber on the strip and the first off
 * it. Interpolation needs both, so it read nothing there, and each edge zone
 * lost the fiber nearest the edge: on a wavy edge its longest. The result
 * fibers next to an edge are extrapolated from the two sensor fibers inside
 * it (flatline/flatness.h, "Zones on the strip"), so the edge zones read the
 * same wherever the edges fall on the grid.
 *
 * Strips 1200 and 1207 mm wide with wavy edges, still, on 201 fibers at
 * 10 mm, centred and moved 300 .. 310 mm in steps of 1.25 mm (an eighth of
 * a pitch: every place of an edge between two fibers), and on 1001 fibers
 * at 2 mm (316 .. 317.5 mm in steps of 0.5 mm). The 1200 mm strip's
 * outermost slots lie on its edges, the 1207 mm strip's 3.5 mm inside. The
 * sensor's peak noise is off: each sheet is the same material measured with
 * the same rigid motion, so what differs between the offsets is only where
 * the edges fall on the grid (with noise, the noise itself moves with the
 * fibers: up to 0.1 I-Units, an_off_centre_strip_reads_as_the_centred_one).
 * Bound: 0.05 I-Units on every zone. Without the extrapolation the 1207 mm
 * strip's edge zones moved by up to 1.15 I-Units on the 10 mm grid. */
static void edge_zones_do_not_depend_on_the_fiber_grid(void **state) {
    (void)state;
    FLT_SWEEP_NOT_UNDER_SANITIZERS();
    const struct {
        size_t fibers;
        double pitch, first_offset, step;
        int offsets;
    } grids[2] = {{201, 10.0, 300.0, 1.25, 9}, {1001, 2.0, 316.0, 0.5, 4}};
    const double widths[2] = {1200.0, 1207.0};
    for (int case_ = 0; case_ < 4; ++case_) {
        const int gi = case_ / 2;
        const double width = widths[case_ % 2];
        grid g = make_grid(grids[gi].fibers, grids[gi].pitch);
        flt_options *o = flat_options(0, NULL, NULL);
        flt_flatness *f = NULL;
        assert_int_equal(flt_flatness_create(g.fibers, g.x, o, &f), FLT_OK);
        flt_options_destroy(o);
        double centred[64];
        size_t zones_centred = 0;
        double worst = 0, worst_offset = 0;
        for (int j = -1; j < grids[gi].offsets; ++j) {
            const double offset = j < 0 ? 0.0 : grids[gi].first_offset + grids[gi].step * j;
            strip_sheet sh =
                make_sheet_with(&g, width, offset, 1, 77u, add_defects, C_EDGE_BOTH, 2, 0.0);
            assert_int_equal(flt_flatness_evaluate_strip(f, sh.rows, g.fibers, sh.s, sh.z, sh.flags,
                                                         sh.left, sh.right),
                             FLT_OK);
            size_t zones = 0;
            assert_int_equal(flt_flatness_zones(f, &zones), FLT_OK);
            assert_true(zones >= 24 && zones <= 64);
            double profile[64];
            uint8_t zf[64];
            assert_int_equal(flt_flatness_zone_results(f, zones, profile, zf), FLT_OK);
            free_sheet(&sh);
            if (j < 0) {
                memcpy(centred, profile, sizeof profile);
                zones_centred = zones;
                continue;
            }
            assert_int_equal(zones, zones_centred);
            /* The zones on the strip: ceil((W - pitch) / 50 mm), 24 but for
             * the 1207 mm strip on the 2 mm grid (25: its outer zones reach
             * past the edges). */
            double diff = 0;
            size_t on_strip = 0;
            for (size_t z = 0; z < zones; ++z) {
                if (zf[z] & FLT_ZONE_OFF_STRIP)
                    continue;
                assert_int_equal(zf[z], 0);
                ++on_strip;
                diff = fmax(diff, fabs(profile[z] - centred[z]));
            }
            assert_int_equal(on_strip, (size_t)ceil((width - g.pitch) / 50.0 - 1e-9));
            print_message("%zu fibers at %.0f mm, %.0f mm strip moved %.2f mm: zones within "
                          "%.3f I-Units of the centred strip's (edge zones %.2f / %.2f, centred "
                          "%.2f / %.2f)\n",
                          g.fibers, g.pitch, width, offset, diff, profile[0], profile[on_strip - 1],
                          centred[0], centred[on_strip - 1]);
            if (diff > worst)
                worst = diff, worst_offset = offset;
        }
        print_message("%zu fibers at %.0f mm, %.0f mm strip: worst %.3f I-Units at %.2f mm\n",
                      g.fibers, g.pitch, width, worst, worst_offset);
        assert_true(worst <= 0.05);
        flt_flatness_destroy(f);
        free(g.x);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(zones_on_wandering_strips_match_the_truth),
        cmocka_unit_test(shape_classes_on_wandering_strips),
        cmocka_unit_test(streaming_flags_and_drive_side),
        cmocka_unit_test(an_off_centre_strip_reads_as_the_centred_one),
        cmocka_unit_test(edge_zones_do_not_depend_on_the_fiber_grid),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
