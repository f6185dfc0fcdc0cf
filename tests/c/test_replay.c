// SPDX-License-Identifier: Apache-2.0
/*
 * A recorded coil replays bit for bit (flatline/gauge.h, "Coils,
 * recordings and the archive"): a simulated coil of 10 sheets, camera
 * frames through a gauge with 2 workers (rigid motion, robust mode, rules,
 * a coil identity, a leveler note, a line stop), recorded; the recording
 * replayed as a source through new gauges with the recorded options (2
 * workers and 0 workers) gives the same sheets: every value (but the time
 * it was finished), every array, every height map and every rule's result
 * equal to the last bit (tolerance 0: the same doubles through the same
 * code), the same coil and notes. With other options (no robust mode) the
 * replay answers "what if": the same 10 sheets, other values.
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

#include "flatline/flatline.h"
#include "test_files.h"

#define OK(call) assert_int_equal((call), FLT_OK)

enum { ROI_FIRST = 900, ROI_ROWS = 240, WIDTH = 2048, FK = 151, SHEETS = 10, MAX_SHEETS = 16 };
static const double PITCH = 10.0, FIRST_X = -750.0, STEP = 10.0, SHEET_MM = 500.0;
enum { N_VALUES = FLT_SHEET_CUT_TIME + 1, N_ARRAYS = 12, RULES = 2 };

static const char k_rules[] =
    "{ \"format\": \"flatline-tolerances\", \"version\": 1, \"name\": \"replay\", \"rules\": [\n"
    " { \"name\": \"I-Units\", \"measure\": \"zone_i_units\",\n"
    "   \"bands\": [ { \"thickness_mm\": [1, 10], \"width_mm\": [0, 3000], \"limit\": 50 } ] },\n"
    " { \"name\": \"straightedge 250 mm\", \"measure\": \"straightedge_along\", \"length_mm\": "
    "250,\n"
    "   \"bands\": [ { \"thickness_mm\": [1, 10], \"width_mm\": [0, 3000], \"limit\": 1.5 } ] }\n"
    "] }\n";

typedef struct sheet_copy {
    double value[N_VALUES];
    double *array[N_ARRAYS];
    size_t array_n[N_ARRAYS];
    size_t rows;
    double *s, *z;
    uint8_t *flags;
    double verdict[RULES][FLT_VERDICT_LENGTH + 1];
    char coil_id[64];
    char note[128];
} sheet_copy;

typedef struct sheet_list {
    sheet_copy sheet[MAX_SHEETS];
    size_t n;
} sheet_list;

static void copy_sheet(const flt_sheet *sh, sheet_copy *c) {
    memset(c, 0, sizeof *c);
    for (int k = 0; k < N_VALUES; ++k)
        OK(flt_sheet_get(sh, (flt_sheet_value)k, &c->value[k]));
    double fibers = 0, zones = 0;
    OK(flt_sheet_get(sh, FLT_SHEET_FIBERS, &fibers));
    OK(flt_sheet_get(sh, FLT_SHEET_ZONES, &zones));
    for (int a = 0; a < N_ARRAYS; ++a) {
        const int per_fiber = a < FLT_SHEET_ZONE_CENTRE_X || a == FLT_SHEET_FIBER_STRIP_X;
        c->array_n[a] = (size_t)(per_fiber ? fibers : zones);
        c->array[a] = malloc(sizeof(double) * (c->array_n[a] + 1));
        OK(flt_sheet_get_array(sh, (flt_sheet_array)a, c->array_n[a], c->array[a]));
    }
    c->rows = (size_t)c->value[FLT_SHEET_ROWS];
    c->s = malloc(sizeof(double) * (c->rows + 1));
    c->z = malloc(sizeof(double) * (c->rows * FK + 1));
    c->flags = malloc(c->rows * FK + 1);
    OK(flt_sheet_height_map(sh, c->rows, FK, c->s, c->z, c->flags));
    const flt_rules *r = NULL;
    const flt_verdict *v = NULL;
    OK(flt_sheet_verdict(sh, &r, &v));
    for (size_t i = 0; i < RULES; ++i)
        for (int k = 0; k <= FLT_VERDICT_LENGTH; ++k)
            OK(flt_verdict_get(v, i, (flt_verdict_value)k, &c->verdict[i][k]));
    const flt_coil_info *coil = NULL;
    if (flt_sheet_coil(sh, &coil) == FLT_OK) {
        const char *id = NULL;
        OK(flt_coil_info_get_text(coil, FLT_COIL_FIELD_ID, &id));
        snprintf(c->coil_id, sizeof c->coil_id, "%s", id);
    }
    size_t notes = 0;
    OK(flt_sheet_note_count(sh, &notes));
    if (notes > 0) {
        const char *kind = NULL, *text = NULL;
        double s = 0;
        OK(flt_sheet_note(sh, 0, &kind, &text, &s));
        snprintf(c->note, sizeof c->note, "%s: %s at %.17g", kind, text, s);
    }
}

static void free_list(sheet_list *l) {
    for (size_t i = 0; i < l->n; ++i) {
        for (int a = 0; a < N_ARRAYS; ++a)
            free(l->sheet[i].array[a]);
        free(l->sheet[i].s);
        free(l->sheet[i].z);
        free(l->sheet[i].flags);
    }
    l->n = 0;
}

static void drain(flt_gauge *g, sheet_list *l) {
    for (;;) {
        flt_sheet *sh = NULL;
        OK(flt_gauge_next_sheet(g, 0, &sh));
        if (!sh)
            return;
        assert_true(l->n < MAX_SHEETS);
        copy_sheet(sh, &l->sheet[l->n++]);
        flt_sheet_destroy(sh);
    }
}

/* Bit for bit: the same doubles (a NaN equals a NaN of the same bits). */
static int same(const void *a, const void *b, size_t bytes) {
    return memcmp(a, b, bytes) == 0;
}

/* How many values of b differ from a (0 for a bit-for-bit replay). */
static size_t compare(const sheet_list *a, const sheet_list *b) {
    size_t differ = 0;
    assert_int_equal(a->n, b->n);
    for (size_t i = 0; i < a->n; ++i) {
        const sheet_copy *x = &a->sheet[i], *y = &b->sheet[i];
        for (int k = 0; k < N_VALUES; ++k)
            if (k != FLT_SHEET_FINISHED_TIME && !same(&x->value[k], &y->value[k], sizeof(double)))
                ++differ;
        for (int aa = 0; aa < N_ARRAYS; ++aa) {
            assert_int_equal(x->array_n[aa], y->array_n[aa]);
            differ += !same(x->array[aa], y->array[aa], sizeof(double) * x->array_n[aa]);
        }
        if (x->rows != y->rows) {
            ++differ;
            continue;
        }
        differ += !same(x->s, y->s, sizeof(double) * x->rows);
        differ += !same(x->z, y->z, sizeof(double) * x->rows * FK);
        differ += !same(x->flags, y->flags, x->rows * FK);
        differ += !same(x->verdict, y->verdict, sizeof x->verdict);
        assert_string_equal(x->coil_id, y->coil_id);
        assert_string_equal(x->note, y->note);
    }
    return differ;
}

static char dir[512], path[600];

static flt_options *live_options(int workers) {
    flt_options *o = NULL;
    OK(flt_options_create(&o));
    OK(flt_options_set(o, FLT_OPT_RIGID_MOTION, 1));
    OK(flt_options_set(o, FLT_OPT_ROBUST, 1));
    OK(flt_options_set(o, FLT_OPT_LAG_KNOTS, 16));
    OK(flt_options_set(o, FLT_OPT_GAUGE_FRAME_SPACING, 8.0));
    OK(flt_options_set(o, FLT_OPT_GAUGE_TAIL_LENGTH, 100.0));
    OK(flt_options_set(o, FLT_OPT_GAUGE_KEEP_MAPS, 1));
    OK(flt_options_set(o, FLT_OPT_GAUGE_SHEET_SLOTS, 16));
    OK(flt_options_set(o, FLT_OPT_GAUGE_WORKERS, workers));
    return o;
}

static void set_rules(flt_gauge *g) {
    flt_rules *rules = NULL;
    OK(flt_rules_load_text(k_rules, strlen(k_rules), &rules));
    OK(flt_gauge_set_rules(g, rules, 4.0, FLT_GAUGE_WIDTH_MEASURED));
    flt_rules_destroy(rules);
}

static sheet_list live;

/* The live coil: frames of the simulated strip (20 blank, 500 with the
 * strip, 20 blank: its tail), a line stop of 5 frames at frame 230, cuts
 * every 500 mm, the coil's identity and a leveler note at frame 300. */
static int record_live(void **state) {
    (void)state;
    if (tf_temp_dir(dir, sizeof dir, "replay"))
        return -1;
    snprintf(path, sizeof path, "%s/coil.flrec", dir);
    flt_calib *calib = NULL;
    OK(flt_calib_create_reference(ROI_FIRST, ROI_ROWS, FIRST_X, PITCH, FK, &calib));
    flt_options *so = NULL;
    OK(flt_options_create(&so));
    OK(flt_options_set(so, FLT_OPT_SIM_FRAME_SPACING, STEP));
    OK(flt_options_set(so, FLT_OPT_SIM_START, -200.0));
    OK(flt_options_set(so, FLT_OPT_SIM_STRIP_WIDTH, 1300.0));
    OK(flt_options_set(so, FLT_OPT_SIM_HEAVE_SIGMA, 0.5));
    OK(flt_options_set(so, FLT_OPT_SIM_PEAK_SIGMA, 1.0 / 16));
    flt_sim *sim = NULL;
    OK(flt_sim_create(calib, so, &sim));
    flt_options_destroy(so);
    OK(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 3.0, 700.0));
    OK(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, -2.0, 400.0));

    flt_options *o = live_options(2);
    flt_gauge *g = NULL;
    OK(flt_gauge_create(calib, o, &g));
    flt_options_destroy(o);
    set_rules(g);
    flt_recorder *rec = NULL;
    OK(flt_recorder_create(path, calib, NULL, &rec));
    OK(flt_gauge_attach_recorder(g, rec));
    assert_int_equal(flt_recorder_cut(rec, 1.0), FLT_ERR_STATE); /* the gauge records */
    flt_coil_info *coil = NULL;
    OK(flt_coil_info_create("4711", &coil));
    OK(flt_coil_info_set_text(coil, FLT_COIL_FIELD_GRADE, "S355MC"));
    OK(flt_coil_info_set_nominal(coil, 4.0, 0.0));
    OK(flt_gauge_set_coil(g, coil));
    flt_coil_info_destroy(coil);
    for (int c = 1; c < SHEETS; ++c)
        OK(flt_gauge_cut(g, SHEET_MM * c));
    uint8_t *frame = malloc((size_t)WIDTH * ROI_ROWS);
    uint8_t *blank = calloc((size_t)WIDTH * ROI_ROWS, 1);
    const int n_frames = 20 + 500 + 20;
    for (int f = 0; f < n_frames; ++f) {
        double e = 0;
        OK(flt_sim_next_frame(sim, frame, (size_t)WIDTH * ROI_ROWS, WIDTH, &e, 0, NULL, NULL, 0));
        const uint8_t *px = f >= 20 && f < 520 ? frame : blank;
        if (f == 300)
            OK(flt_gauge_note(g, "leveler", "roll 3 +0.20 mm"));
        OK(flt_gauge_push_frame(g, px, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, e));
        if (f == 230)
            for (int stop = 0; stop < 5; ++stop) /* the line stops: the encoder stands */
                OK(flt_gauge_push_frame(g, px, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, e));
        drain(g, &live);
    }
    OK(flt_gauge_flush(g));
    drain(g, &live);
    uint64_t stops = 0;
    OK(flt_gauge_count(g, FLT_GAUGE_COUNT_SKIPPED_STOP, &stops));
    assert_int_equal(stops, 5);
    OK(flt_gauge_attach_recorder(g, NULL));
    OK(flt_recorder_sync(rec, 20000));
    uint64_t lost = 1, rows = 0;
    OK(flt_recorder_count(rec, FLT_RECORDER_COUNT_ROWS_LOST, &lost));
    OK(flt_recorder_count(rec, FLT_RECORDER_COUNT_ROWS, &rows));
    assert_int_equal(lost, 0);
    assert_int_equal(rows, n_frames); /* every taken frame; the 5 stopped ones as counts */
    flt_recorder_destroy(rec);
    flt_gauge_destroy(g);
    free(frame);
    free(blank);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
    return 0;
}

static int teardown(void **state) {
    (void)state;
    free_list(&live);
    tf_remove_tree(dir);
    return 0;
}

/* Replays the recording through a gauge made from its own calibration and
 * options (changed by `change`, or none). */
static void replay(int workers, flt_option change, double value, sheet_list *out) {
    flt_recording *rd = NULL;
    OK(flt_recording_open(path, &rd));
    flt_calib *calib = NULL;
    flt_options *o = NULL;
    OK(flt_recording_calib(rd, &calib));
    OK(flt_recording_options(rd, &o));
    double has = 0;
    OK(flt_recording_info(rd, FLT_RECORDING_HAS_OPTIONS, &has));
    assert_true(has == 1);
    flt_recording_destroy(rd);
    OK(flt_options_set(o, FLT_OPT_GAUGE_WORKERS, workers));
    if ((int)change >= 0)
        OK(flt_options_set(o, change, value));
    flt_gauge *g = NULL;
    OK(flt_gauge_create(calib, o, &g));
    flt_options_destroy(o);
    set_rules(g);
    flt_source *src = NULL;
    OK(flt_source_open_recording(path, NULL, &src));
    OK(flt_gauge_attach_source(g, src));
    OK(flt_gauge_start(g));
    flt_status st;
    while ((st = flt_gauge_wait(g, 20)) == FLT_ERR_TIMEOUT)
        drain(g, out);
    OK(st);
    drain(g, out);
    uint64_t stops = 0;
    OK(flt_gauge_count(g, FLT_GAUGE_COUNT_SKIPPED_STOP, &stops));
    assert_int_equal(stops, 5); /* the live line stop, as the recording counted it */
    OK(flt_gauge_attach_source(g, NULL));
    flt_gauge_destroy(g);
    flt_source_destroy(src);
    flt_calib_destroy(calib);
}

static void test_replay_is_bit_for_bit(void **state) {
    (void)state;
    assert_int_equal(live.n, SHEETS);
    assert_string_equal(live.sheet[0].coil_id, "4711");
    int with_note = 0;
    for (size_t i = 0; i < live.n; ++i)
        with_note += live.sheet[i].note[0] != 0;
    assert_int_equal(with_note, 1);
    for (int workers = 0; workers <= 2; workers += 2) {
        sheet_list again;
        memset(&again, 0, sizeof again);
        replay(workers, (flt_option)-1, 0, &again);
        const size_t differ = compare(&live, &again);
        print_message("replay with %d workers: %zu sheets, %zu values differ from the live run\n",
                      workers, again.n, differ);
        assert_int_equal(differ, 0);
        free_list(&again);
    }
}

static void test_replay_answers_what_if(void **state) {
    (void)state;
    sheet_list other;
    memset(&other, 0, sizeof other);
    replay(2, FLT_OPT_ROBUST, 0, &other); /* least squares instead of Huber */
    assert_int_equal(other.n, SHEETS);
    size_t changed = 0;
    for (size_t i = 0; i < other.n; ++i)
        changed += other.sheet[i].value[FLT_SHEET_MAX_I_UNITS] !=
                   live.sheet[i].value[FLT_SHEET_MAX_I_UNITS];
    print_message("replay without robust mode: %zu of %d sheets' largest I-Units differ\n", changed,
                  SHEETS);
    assert_true(changed > 0);
    free_list(&other);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_replay_is_bit_for_bit),
        cmocka_unit_test(test_replay_answers_what_if),
    };
    return cmocka_run_group_tests(tests, record_live, teardown);
}
