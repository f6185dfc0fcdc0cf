// SPDX-License-Identifier: Apache-2.0
/*
 * The gauge's verdicts (flatline/gauge.h, "Verdicts and coil statistics"):
 * two simulated coils whose strip waves along travel as a sine of known
 * amplitude, so that the straightedge deviation is known in closed form
 * (flatline/verdict.h, "Measures"); rules with limits below and above it
 * fail and pass; the worst values agree with the closed form within the
 * gauge's measured accuracy; the coil statistics equal the sheets'
 * verdicts; 0, 1 and 2 workers, with and without kept maps, give the same
 * verdicts bit for bit, and a sheet's kept map given to
 * flt_verdict_evaluate gives its straightedge verdicts bit for bit.
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

#include <flatline/flatline.h>

#define OK(call) assert_int_equal((call), FLT_OK)

/* The strip: z = A sin(2 pi s / P) across the whole width (the simulator's
 * BOW defect), two coils of 9 m with 1 m between them, rows every 3 mm. */
#define AMPLITUDE   2.0
#define PERIOD      1000.0
#define SPACING     3.0
#define COIL_LENGTH 9000.0
#define COIL_GAP    1000.0
#define K           51
#define ROWS        6630 /* to e = 19887: the second coil's tail is seen, no third coil */
#define RULES       7
#define SHEETS_MAX  16

static const char k_rules[] =
    "{ \"format\": \"flatline-tolerances\", \"version\": 1, \"name\": \"test\",\n"
    "  \"rules\": [\n"
    "    { \"name\": \"1/2 m tight\", \"measure\": \"straightedge_along\", \"length_mm\": 500,\n"
    "      \"bands\": [ { \"thickness_mm\": [1, 10], \"width_mm\": [0, 3000], \"limit\": 1.9 } ] "
    "},\n"
    "    { \"name\": \"1/2 m loose\", \"measure\": \"straightedge_along\", \"length_mm\": 500,\n"
    "      \"bands\": [ { \"thickness_mm\": [1, 10], \"width_mm\": [0, 3000], \"limit\": 2.1 } ] "
    "},\n"
    "    { \"name\": \"2 m tight\", \"measure\": \"straightedge_along\", \"length_mm\": 2000,\n"
    "      \"bands\": [ { \"thickness_mm\": [1, 10], \"width_mm\": [0, 3000], \"limit\": 3.9 } ] "
    "},\n"
    "    { \"name\": \"2 m loose\", \"measure\": \"straightedge_along\", \"length_mm\": 2000,\n"
    "      \"bands\": [ { \"thickness_mm\": [1, 10], \"width_mm\": [0, 3000], \"limit\": 4.1 } ] "
    "},\n"
    "    { \"name\": \"1 m across\", \"measure\": \"straightedge_across\", \"length_mm\": 1000,\n"
    "      \"bands\": [ { \"thickness_mm\": [1, 10], \"width_mm\": [0, 3000], \"limit\": 0.05 } ] "
    "},\n"
    "    { \"name\": \"I-Units\", \"measure\": \"zone_i_units\",\n"
    "      \"bands\": [ { \"thickness_mm\": [1, 10], \"width_mm\": [0, 3000], \"limit\": 1000 } ] "
    "},\n"
    "    { \"name\": \"thick only\", \"measure\": \"straightedge_along\", \"length_mm\": 500,\n"
    "      \"bands\": [ { \"thickness_mm\": [10, 20], \"width_mm\": [0, 3000], \"limit\": 1 } ] }\n"
    "  ] }\n";
/* What each rule gives on every sheet: 1 fail, 0 pass, 2 no band. */
static const int k_expect[RULES] = {FLT_VERDICT_FAIL,   FLT_VERDICT_PASS, FLT_VERDICT_FAIL,
                                    FLT_VERDICT_PASS,   FLT_VERDICT_PASS, FLT_VERDICT_PASS,
                                    FLT_VERDICT_NO_BAND};

/* The simulated rows (the same for every run). */
typedef struct line {
    double e[ROWS], s[ROWS];
    double *height, *slope, *truth;
    uint8_t *valid;
} line;

static line *make_line(const flt_calib *calib) {
    flt_options *o = NULL;
    OK(flt_options_create(&o));
    OK(flt_options_set(o, FLT_OPT_SIM_FRAME_SPACING, SPACING));
    OK(flt_options_set(o, FLT_OPT_SIM_COIL_LENGTH, COIL_LENGTH));
    OK(flt_options_set(o, FLT_OPT_SIM_COIL_GAP, COIL_GAP));
    flt_sim *sim = NULL;
    OK(flt_sim_create(calib, o, &sim));
    flt_options_destroy(o);
    OK(flt_sim_add_defect(sim, FLT_SIM_BOW, AMPLITUDE, PERIOD));
    line *l = calloc(1, sizeof *l);
    l->height = malloc(sizeof(double) * ROWS * K);
    l->slope = malloc(sizeof(double) * ROWS * K);
    l->truth = malloc(sizeof(double) * ROWS * K);
    l->valid = malloc((size_t)ROWS * K);
    OK(flt_sim_next_rows(sim, ROWS, K, l->e, l->s, l->height, l->slope, l->valid, l->truth));
    flt_sim_destroy(sim);
    return l;
}

static void free_line(line *l) {
    free(l->height);
    free(l->slope);
    free(l->truth);
    free(l->valid);
    free(l);
}

/* One sheet's verdict, copied. */
typedef struct judged {
    double id, coil, flags, rows, s_first, max_i_units, failed;
    double value[RULES][9];
    double error;    /* max |z - truth| over its map (keep_maps 1), mm */
    double truth[4]; /* the deviation of the true heights, rules 0-3 */
    /* Every value but the times (from FLT_SHEET_FINISHED_TIME on: the
     * host's clock, which two runs do not share), and every array (per
     * fiber, or per zone in the first zones entries): the flatness of the
     * fibers and the straightedges' lines are evaluated in blocks on the
     * workers, and must not depend on how many there are. */
    double sheet_value[FLT_SHEET_FINISHED_TIME];
    double array[12][K];
} judged;

typedef struct run {
    judged sheet[SHEETS_MAX];
    size_t sheets;
    double coil[2][RULES][FLT_COIL_VALUES]; /* the LAST coil after each coil */
    double current_between[FLT_COIL_VALUES];
} run;

static void copy_sheet(const flt_sheet *sh, const line *l, const flt_rules *rules, judged *j,
                       int maps) {
    OK(flt_sheet_get(sh, FLT_SHEET_ID, &j->id));
    OK(flt_sheet_get(sh, FLT_SHEET_COIL, &j->coil));
    OK(flt_sheet_get(sh, FLT_SHEET_FLAGS, &j->flags));
    OK(flt_sheet_get(sh, FLT_SHEET_ROWS, &j->rows));
    OK(flt_sheet_get(sh, FLT_SHEET_S_FIRST, &j->s_first));
    OK(flt_sheet_get(sh, FLT_SHEET_MAX_I_UNITS, &j->max_i_units));
    double n = 0;
    OK(flt_sheet_get(sh, FLT_SHEET_RULES, &n));
    assert_int_equal((int)n, RULES);
    OK(flt_sheet_get(sh, FLT_SHEET_RULES_FAILED, &j->failed));
    const flt_rules *sr = NULL;
    const flt_verdict *v = NULL;
    OK(flt_sheet_verdict(sh, &sr, &v));
    size_t count = 0;
    OK(flt_rules_count(sr, &count));
    assert_int_equal(count, RULES);
    for (size_t i = 0; i < RULES; ++i) {
        const char *name = NULL, *given = NULL;
        OK(flt_rules_rule(sr, i, &name, NULL, NULL));
        OK(flt_rules_rule(rules, i, &given, NULL, NULL));
        assert_string_equal(name, given);
        for (int k = 0; k < 9; ++k)
            OK(flt_verdict_get(v, i, (flt_verdict_value)k, &j->value[i][k]));
    }
    for (int k = 0; k < FLT_SHEET_FINISHED_TIME; ++k)
        OK(flt_sheet_get(sh, (flt_sheet_value)k, &j->sheet_value[k]));
    const size_t zones = (size_t)j->sheet_value[FLT_SHEET_ZONES];
    assert_true(zones >= 1 && zones <= K);
    for (int a = 0; a < 12; ++a) {
        const int per_fiber = a < FLT_SHEET_ZONE_CENTRE_X || a == FLT_SHEET_FIBER_STRIP_X;
        OK(flt_sheet_get_array(sh, (flt_sheet_array)a, per_fiber ? K : zones, j->array[a]));
    }
    size_t failed = 0;
    OK(flt_verdict_failed(v, &failed));
    assert_int_equal(failed, (size_t)j->failed);
    /* Read-only: the sheet's verdict is the gauge's. */
    assert_int_equal(flt_verdict_set_measure((flt_verdict *)v, FLT_MEASURE_BOW, 1.0, 0, 0),
                     FLT_ERR_STATE);
    j->error = NAN;
    if (!maps)
        return;
    /* The map against the truth (rows are every SPACING mm from s = e_0:
     * the row index is s / SPACING), and the deviation of the true heights
     * on the same samples. */
    const size_t rows = (size_t)j->rows;
    double *s = malloc(sizeof(double) * rows), *z = malloc(sizeof(double) * rows * K);
    double *t = malloc(sizeof(double) * rows * K);
    uint8_t *f = malloc(rows * K);
    OK(flt_sheet_height_map(sh, rows, K, s, z, f));
    double err = 0;
    for (size_t r = 0; r < rows; ++r) {
        const size_t row = (size_t)lround((s[r] - l->s[0]) / SPACING);
        assert_true(fabs(l->s[row] - s[r]) < 1e-9);
        for (size_t k = 0; k < K; ++k) {
            t[r * K + k] = l->truth[row * K + k];
            if (!(f[r * K + k] & FLT_FLAG_NO_DATA))
                err = fmax(err, fabs(z[r * K + k] - t[r * K + k]));
        }
    }
    j->error = err;
    double x[K];
    OK(flt_sheet_get_array(sh, FLT_SHEET_FIBER_X, K, x));
    flt_verdict *tv = NULL;
    OK(flt_verdict_create(rules, &tv));
    OK(flt_verdict_evaluate(tv, 4.0, 1500.0, rows, K, s, x, t, f));
    for (size_t i = 0; i < 4; ++i)
        OK(flt_verdict_get(tv, i, FLT_VERDICT_WORST, &j->truth[i]));
    /* The sheet's own map given to flt_verdict_evaluate, with the width the
     * gauge judged it at (set_rules' 0: the measured strip width): its
     * straightedge rules (every rule but the I-Units', which the gauge
     * takes from its flatness on the strip) give the gauge's values bit for
     * bit, all nine of each. The two share the judging code and cut the
     * lines into the same blocks, whatever the gauge's workers. */
    if (!((unsigned)j->flags & FLT_SHEET_FLAG_INCOMPLETE)) {
        OK(flt_verdict_evaluate(tv, 4.0, j->sheet_value[FLT_SHEET_STRIP_WIDTH], rows, K, s, x, z,
                                f));
        for (size_t i = 0; i < RULES; ++i) {
            if (i == 5) /* "I-Units": zone_i_units */
                continue;
            for (int k = 0; k < 9; ++k) {
                double direct = 0;
                OK(flt_verdict_get(tv, i, (flt_verdict_value)k, &direct));
                assert_memory_equal(&direct, &j->value[i][k], sizeof direct);
            }
        }
    }
    flt_verdict_destroy(tv);
    free(s);
    free(z);
    free(t);
    free(f);
}

static void drain(flt_gauge *g, const line *l, const flt_rules *rules, run *out, int maps) {
    for (;;) {
        flt_sheet *sh = NULL;
        OK(flt_gauge_next_sheet(g, 0, &sh));
        if (!sh)
            return;
        assert_true(out->sheets < SHEETS_MAX);
        copy_sheet(sh, l, rules, &out->sheet[out->sheets++], maps);
        flt_sheet_destroy(sh);
    }
}

static void push(flt_gauge *g, const line *l, size_t r0, size_t r1) {
    for (size_t r = r0; r < r1; ++r)
        OK(flt_gauge_push_row(g, l->e[r], K, &l->height[r * K], &l->slope[r * K],
                              &l->valid[r * K]));
}

static void read_coil(const flt_gauge *g, flt_coil which, double out[RULES][FLT_COIL_VALUES]) {
    for (size_t i = 0; i < RULES; ++i)
        OK(flt_gauge_coil_stats(g, which, i, FLT_COIL_VALUES, out[i]));
}

static void run_line(const flt_calib *calib, const line *l, const flt_rules *rules, int workers,
                     int maps, run *out) {
    flt_options *o = NULL;
    OK(flt_options_create(&o));
    OK(flt_options_set(o, FLT_OPT_GAUGE_WORKERS, workers));
    OK(flt_options_set(o, FLT_OPT_GAUGE_OVERFLOW, 1));
    OK(flt_options_set(o, FLT_OPT_GAUGE_KEEP_MAPS, maps));
    OK(flt_options_set(o, FLT_OPT_GAUGE_SHEET_SLOTS, 32));
    OK(flt_options_set(o, FLT_OPT_GAUGE_FRAME_SPACING, 2.0));
    flt_gauge *g = NULL;
    OK(flt_gauge_create(calib, o, &g));
    flt_options_destroy(o);
    double v[FLT_COIL_VALUES];
    assert_int_equal(flt_gauge_coil_stats(g, FLT_COIL_CURRENT, 0, 1, v), FLT_ERR_STATE);
    /* A copy of the rules is kept: these may go at once. */
    flt_rules *copy = NULL;
    OK(flt_rules_load_text(k_rules, sizeof k_rules - 1, &copy));
    OK(flt_gauge_set_rules(g, copy, 4.0, 0.0));
    flt_rules_destroy(copy);
    /* Cuts every 3 m inside each coil (s = e: the lasers sit at -+50 mm). */
    const double cuts[] = {3000, 6000, 13000, 16000};
    for (size_t c = 0; c < 4; ++c)
        OK(flt_gauge_cut(g, cuts[c]));
    memset(out, 0, sizeof *out);
    /* The first coil and its tail (rows to e = 9900), then the second. */
    const size_t first = (size_t)((COIL_LENGTH + 0.9 * COIL_GAP) / SPACING);
    push(g, l, 0, first);
    OK(flt_gauge_flush(g));
    drain(g, l, rules, out, maps);
    read_coil(g, FLT_COIL_LAST, out->coil[0]);
    OK(flt_gauge_coil_stats(g, FLT_COIL_CURRENT, 0, FLT_COIL_VALUES, out->current_between));
    assert_int_equal(flt_gauge_coil_stats(g, FLT_COIL_LAST, RULES, 1, v), FLT_ERR_NOT_FOUND);
    push(g, l, first, ROWS);
    OK(flt_gauge_flush(g));
    drain(g, l, rules, out, maps);
    read_coil(g, FLT_COIL_LAST, out->coil[1]);
    flt_gauge_destroy(g);
}

/* The coil statistics recomputed from the sheets' own verdicts. */
static void check_coil(const run *r, double coil, const double stats[RULES][FLT_COIL_VALUES]) {
    for (size_t i = 0; i < RULES; ++i) {
        const double *c = stats[i];
        double sheets = 0, passed = 0, failed = 0, state[5] = {0, 0, 0, 0, 0}, n = 0, sum = 0;
        double lo = INFINITY, hi = -INFINITY, hi_id = NAN, hist[FLT_COIL_HISTOGRAM_BINS] = {0};
        for (size_t k = 0; k < r->sheets; ++k) {
            const judged *j = &r->sheet[k];
            if (j->coil != coil)
                continue;
            sheets += 1;
            /* A sheet passes only when every rule judged it and passed. */
            int judged_all = 1;
            for (size_t q = 0; q < RULES; ++q)
                judged_all &= j->value[q][FLT_VERDICT_STATE] == FLT_VERDICT_PASS ||
                              j->value[q][FLT_VERDICT_STATE] == FLT_VERDICT_FAIL;
            failed += j->failed > 0;
            passed += j->failed == 0 && judged_all;
            const int st = (int)j->value[i][FLT_VERDICT_STATE];
            state[st] += 1;
            if (st != FLT_VERDICT_PASS && st != FLT_VERDICT_FAIL)
                continue;
            const double w = j->value[i][FLT_VERDICT_WORST];
            n += 1;
            sum += w;
            lo = fmin(lo, w);
            if (w > hi) {
                hi = w;
                hi_id = j->id;
            }
            const double ratio = w / j->value[i][FLT_VERDICT_LIMIT];
            int bin = (int)ceil(ratio * 10.0) - 1;
            bin = bin < 0 ? 0 : bin > 19 ? 19 : bin;
            hist[bin] += 1;
        }
        assert_true(sheets >= 3);
        assert_true(c[FLT_COIL_NUMBER] == coil);
        assert_true(c[FLT_COIL_FINISHED] == 1);
        assert_true(c[FLT_COIL_RULES] == RULES);
        assert_true(c[FLT_COIL_SHEETS] == sheets);
        assert_true(c[FLT_COIL_SHEETS_PASSED] == passed);
        assert_true(c[FLT_COIL_SHEETS_FAILED] == failed);
        assert_true(c[FLT_COIL_SHEETS_NOT_JUDGED] == sheets - passed - failed);
        assert_true(c[FLT_COIL_SHEETS_JUDGED] == passed + failed);
        assert_true(c[FLT_COIL_RULE_NOT_JUDGED] == state[4]);
        assert_true(c[FLT_COIL_RULE_PASSED] == state[0]);
        assert_true(c[FLT_COIL_RULE_FAILED] == state[1]);
        assert_true(c[FLT_COIL_RULE_NO_BAND] == state[2]);
        assert_true(c[FLT_COIL_RULE_NOT_MEASURED] == state[3]);
        if (n == 0) {
            assert_true(isnan(c[FLT_COIL_WORST_MIN]) && isnan(c[FLT_COIL_WORST_MEAN]));
            continue;
        }
        /* The same values summed in the same (sheet) order: exact. */
        assert_true(c[FLT_COIL_WORST_MIN] == lo);
        assert_true(c[FLT_COIL_WORST_MAX] == hi);
        assert_true(c[FLT_COIL_WORST_MEAN] == sum / n);
        assert_true(c[FLT_COIL_WORST_SHEET] == hi_id);
        for (int b = 0; b < FLT_COIL_HISTOGRAM_BINS; ++b)
            assert_true(c[FLT_COIL_HISTOGRAM + b] == hist[b]);
    }
}

static void sine_sheets_pass_and_fail(void **state) {
    (void)state;
    const double pitch = 1500.0 / (K - 1);
    flt_calib *calib = NULL;
    OK(flt_calib_create_reference(900, 240, -750.0, pitch, K, &calib));
    line *l = make_line(calib);
    flt_rules *rules = NULL;
    OK(flt_rules_load_text(k_rules, sizeof k_rules - 1, &rules));

    run *runs = calloc(3, sizeof *runs);
    run_line(calib, l, rules, 0, 1, &runs[0]);
    run_line(calib, l, rules, 1, 0, &runs[1]);
    run_line(calib, l, rules, 2, 0, &runs[2]);
    const run *r = &runs[0];
    assert_int_equal(r->sheets, 6); /* 3 per coil: head, 2 cuts, tail */

    /* The gauge's accuracy on these sheets, and the closed form (lib/verdict
     * /README.md): L = 500 <= P: A (1 - cos(pi L / P)) = A; L = 2000 >= P:
     * 2 A. On samples every h = 3 mm the contacts lie up to h closer than
     * L and the trough up to h / 2 from a sample: at most A pi h / P + A
     * (pi h / P)^2 / 2 less (0.019 mm). */
    const double h_err =
        AMPLITUDE * M_PI * SPACING / PERIOD + AMPLITUDE * pow(M_PI * SPACING / PERIOD, 2) / 2;
    const double closed[4] = {AMPLITUDE * (1 - cos(M_PI * 500 / PERIOD)),
                              AMPLITUDE * (1 - cos(M_PI * 500 / PERIOD)), 2 * AMPLITUDE,
                              2 * AMPLITUDE};
    double worst_err = 0, worst_gap = 0, worst_closed = 0;
    for (size_t k = 0; k < r->sheets; ++k) {
        const judged *j = &r->sheet[k];
        worst_err = fmax(worst_err, j->error);
        for (size_t i = 0; i < RULES; ++i)
            assert_int_equal((int)j->value[i][FLT_VERDICT_STATE], k_expect[i]);
        assert_true(j->failed == 2);
        for (size_t i = 0; i < 4; ++i) {
            const double w = j->value[i][FLT_VERDICT_WORST];
            /* Each height within e of the truth: a straightedge resting on
             * the same samples moves by at most e, the sample under it by
             * at most e. */
            assert_true(fabs(w - j->truth[i]) <= 2 * j->error + 1e-9);
            worst_gap = fmax(worst_gap, fabs(w - j->truth[i]));
            assert_true(j->truth[i] <= closed[i] + 1e-9);
            assert_true(j->truth[i] >= closed[i] - h_err);
            worst_closed = fmax(worst_closed, fabs(w - closed[i]));
            /* Worst value, margin and where it is. */
            assert_true(fabs(j->value[i][FLT_VERDICT_MARGIN] -
                             (j->value[i][FLT_VERDICT_LIMIT] - w)) < 1e-12);
            assert_true(j->value[i][FLT_VERDICT_S] >= j->s_first);
            assert_true(j->value[i][FLT_VERDICT_X] >= -750.0 &&
                        j->value[i][FLT_VERDICT_X] <= 750.0);
        }
        /* A flat row: nothing under a straightedge across but the error. */
        assert_true(j->value[4][FLT_VERDICT_WORST] <= 2 * j->error + 1e-9);
        /* I-Units: the sheet's largest zone. */
        assert_true(j->value[5][FLT_VERDICT_WORST] == j->max_i_units);
        assert_true(isnan(j->value[6][FLT_VERDICT_WORST]));
    }
    print_message("6 sheets, 2 coils: height error max %.2e mm; straightedge vs the true "
                  "heights' %.2e mm, vs the closed form %.4f mm (sampling bound %.4f)\n",
                  worst_err, worst_gap, worst_closed, h_err + 2 * worst_err);
    /* Noise-free rows: the gauge is accurate to micrometres (README, "In
     * numbers"); a millimetre would be a broken map, not a tolerance. */
    assert_true(worst_err < 0.01);

    /* The coils' statistics are the sheets' verdicts. */
    check_coil(r, 1, r->coil[0]);
    check_coil(r, 2, r->coil[1]);
    /* Between coils the current one has no sheet. */
    assert_true(r->current_between[FLT_COIL_NUMBER] == 0);
    assert_true(r->current_between[FLT_COIL_SHEETS] == 0);
    /* The tight rules fail by their margin: every sheet in bin 10
     * (worst / limit = 2 / 1.9 and 4 / 3.9 in (1, 1.1]). */
    assert_true(r->coil[0][0][FLT_COIL_HISTOGRAM + 10] == 3);
    assert_true(r->coil[0][2][FLT_COIL_HISTOGRAM + 10] == 3);

    /* 1 and 2 workers, without maps: the same verdicts, values and arrays,
     * bit for bit (unused array entries are 0 in every run: calloc). */
    for (int w = 1; w <= 2; ++w) {
        const run *o = &runs[w];
        assert_int_equal(o->sheets, r->sheets);
        for (size_t k = 0; k < r->sheets; ++k) {
            assert_memory_equal(o->sheet[k].value, r->sheet[k].value, sizeof r->sheet[k].value);
            assert_memory_equal(o->sheet[k].sheet_value, r->sheet[k].sheet_value,
                                sizeof r->sheet[k].sheet_value);
            assert_memory_equal(o->sheet[k].array, r->sheet[k].array, sizeof r->sheet[k].array);
        }
        assert_memory_equal(o->coil, r->coil, sizeof r->coil);
    }
    free(runs);
    flt_rules_destroy(rules);
    free_line(l);
    flt_calib_destroy(calib);
}

/* A nominal width chooses the band; without rules a sheet has no verdict. */
static void nominal_width_and_no_rules(void **state) {
    (void)state;
    const double pitch = 1500.0 / (K - 1);
    flt_calib *calib = NULL;
    OK(flt_calib_create_reference(900, 240, -750.0, pitch, K, &calib));
    line *l = make_line(calib);
    flt_rules *rules = NULL;
    OK(flt_rules_load_text(k_rules, sizeof k_rules - 1, &rules));
    flt_options *o = NULL;
    OK(flt_options_create(&o));
    OK(flt_options_set(o, FLT_OPT_GAUGE_WORKERS, 0));
    OK(flt_options_set(o, FLT_OPT_GAUGE_FRAME_SPACING, 2.0));
    flt_gauge *g = NULL;
    OK(flt_gauge_create(calib, o, &g));
    flt_options_destroy(o);
    /* The bands end at 3000 mm: a nominal 3500 mm sheet is in none. */
    OK(flt_gauge_set_rules(g, rules, 4.0, 3500.0));
    push(g, l, 0, 1100);
    OK(flt_gauge_flush(g));
    flt_sheet *sh = NULL;
    OK(flt_gauge_next_sheet(g, 0, &sh));
    assert_non_null(sh);
    const flt_verdict *v = NULL;
    OK(flt_sheet_verdict(sh, NULL, &v));
    for (size_t i = 0; i < RULES; ++i) {
        double st = 0;
        OK(flt_verdict_get(v, i, FLT_VERDICT_STATE, &st));
        assert_int_equal((int)st, FLT_VERDICT_NO_BAND);
    }
    /* No rule could judge it: not judged, never passed; the coil counts it
     * so (it failed no rule, which is not the same as passing). */
    double verdict = -1;
    OK(flt_sheet_get(sh, FLT_SHEET_VERDICT, &verdict));
    assert_int_equal((int)verdict, FLT_VERDICT_NOT_JUDGED);
    double coil[FLT_COIL_VALUES];
    OK(flt_gauge_coil_stats(g, FLT_COIL_LAST, 0, FLT_COIL_VALUES, coil));
    assert_true(coil[FLT_COIL_SHEETS] == 1 && coil[FLT_COIL_SHEETS_NOT_JUDGED] == 1);
    assert_true(coil[FLT_COIL_SHEETS_PASSED] == 0 && coil[FLT_COIL_SHEETS_FAILED] == 0);
    assert_true(coil[FLT_COIL_SHEETS_JUDGED] == 0 && coil[FLT_COIL_RULE_NO_BAND] == 1);
    flt_sheet_destroy(sh);
    /* Rules off: the next sheet has none, the statistics are gone. */
    OK(flt_gauge_set_rules(g, NULL, 4.0, 0.0));
    push(g, l, 1100, 2000);
    OK(flt_gauge_flush(g));
    OK(flt_gauge_next_sheet(g, 0, &sh));
    assert_non_null(sh);
    double n = -1;
    OK(flt_sheet_get(sh, FLT_SHEET_RULES, &n));
    assert_true(n == 0);
    const flt_rules *sr = (const flt_rules *)1;
    assert_int_equal(flt_sheet_verdict(sh, &sr, NULL), FLT_ERR_STATE);
    assert_null(sr);
    flt_sheet_destroy(sh);
    double c = 0;
    assert_int_equal(flt_gauge_coil_stats(g, FLT_COIL_CURRENT, 0, 1, &c), FLT_ERR_STATE);
    /* A bad thickness keeps what is in force (nothing) and says why. */
    assert_int_equal(flt_gauge_set_rules(g, rules, 0.0, 0.0), FLT_ERR_INVALID_ARGUMENT);
    assert_non_null(strstr(flt_last_error_message(), "thickness_mm"));
    flt_gauge_destroy(g);
    flt_rules_destroy(rules);
    free_line(l);
    flt_calib_destroy(calib);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(sine_sheets_pass_and_fail),
        cmocka_unit_test(nominal_width_and_no_rules),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
