// SPDX-License-Identifier: Apache-2.0
/* "Nothing allocated per frame": counts every malloc/calloc/realloc made by
 * libflatline (and the C++ runtime under it), on every thread, while a gauge
 * with two workers takes frames and rows, cuts sheets, evaluates them and
 * hands them over. The counting allocator (alloc_count.h) sees the shared
 * library's calls on every thread, as in test_recon_alloc.c. Not built
 * under sanitizers, which own malloc. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include <flatline/flatline.h>

#include "alloc_count.h"
#include "sheet.h"

#define OK(call) assert_int_equal((call), FLT_OK)

/* Sheets are judged too: a straightedge along (the height map) and
 * across, and a flatness measure. */
static const char k_rules[] =
    "{ \"format\": \"flatline-tolerances\", \"version\": 1, \"name\": \"alloc\",\n"
    "  \"rules\": [\n"
    "    { \"name\": \"1 m\", \"measure\": \"straightedge_along\", \"length_mm\": 1000,\n"
    "      \"bands\": [ { \"thickness_mm\": [0, 50], \"width_mm\": [0, 5000], \"limit\": 3 } ] },\n"
    "    { \"name\": \"across\", \"measure\": \"straightedge_across\", \"length_mm\": 1000,\n"
    "      \"bands\": [ { \"thickness_mm\": [0, 50], \"width_mm\": [0, 5000], \"limit\": 3 } ] },\n"
    "    { \"name\": \"IU\", \"measure\": \"zone_i_units\",\n"
    "      \"bands\": [ { \"thickness_mm\": [0, 50], \"width_mm\": [0, 5000], \"limit\": 10 } ] }\n"
    "  ] }\n";

/* Sheets taken (with rules, each judged by the 3 rules, its verdict read). */
static size_t take_sheets(flt_gauge *g, double judged) {
    size_t n = 0;
    for (;;) {
        flt_sheet *sh = NULL;
        if (flt_gauge_next_sheet(g, 0, &sh) != FLT_OK || !sh)
            return n;
        double v, rules = 0, worst = NAN;
        const flt_verdict *verdict = NULL;
        if (flt_sheet_get(sh, FLT_SHEET_MAX_I_UNITS, &v) == FLT_OK &&
            flt_sheet_get(sh, FLT_SHEET_RULES, &rules) == FLT_OK && rules == judged &&
            (!judged ||
             (flt_sheet_verdict(sh, NULL, &verdict) == FLT_OK &&
              flt_verdict_get(verdict, 0, FLT_VERDICT_WORST, &worst) == FLT_OK && worst >= 0)))
            ++n;
        flt_sheet_destroy(sh);
    }
}

/* With 2 workers (the sheets' evaluation in blocks on them), 1 and 0 (the
 * blocks on the evaluating thread alone). */
static void rows_and_sheets_allocate_nothing(void **state) {
    const int workers = *(const int *)*state;
    enum { K = 51, R = 6000 };
    const double pitch = 1500.0 / (K - 1);
    test_sheet *t = test_sheet_make(R, K, 0.0, 3.0, 0.0, pitch, 100.0, 1);
    flt_calib *calib = NULL;
    OK(flt_calib_create_reference(900, 240, -750.0, pitch, K, &calib));
    flt_options *o = NULL;
    OK(flt_options_create(&o));
    OK(flt_options_set(o, FLT_OPT_GAUGE_WORKERS, workers));
    OK(flt_options_set(o, FLT_OPT_GAUGE_OVERFLOW, 1));
    OK(flt_options_set(o, FLT_OPT_GAUGE_KEEP_MAPS, 2));
    OK(flt_options_set(o, FLT_OPT_GAUGE_SHEET_SLOTS, 32));
    OK(flt_options_set(o, FLT_OPT_GAUGE_FRAME_SPACING, 2.0));
    OK(flt_options_set(o, FLT_OPT_RIGID_MOTION, 1));
    OK(flt_options_set(o, FLT_OPT_ROBUST, 1));
    /* Early answers too: a provisional sheet 300 mm past each cut. */
    OK(flt_options_set(o, FLT_OPT_GAUGE_PROVISIONAL_MM, 300.0));
    flt_gauge *g = NULL;
    atomic_store(&g_allocations, 0);
    atomic_store(&g_counting, 1);
    OK(flt_gauge_create(calib, o, &g));
    atomic_store(&g_counting, 0);
    assert_true(atomic_load(&g_allocations) >= 10); /* the counter sees the library */
    flt_rules *rules = NULL;
    OK(flt_rules_load_text(k_rules, sizeof k_rules - 1, &rules));
    OK(flt_gauge_set_rules(g, rules, 4.0, 0.0)); /* allocates here, not per sheet */
    flt_rules_destroy(rules);

    /* Warm-up: a first strip of 1 m sheets (the flatness metrics grow their
     * column scratch once, at the first sheet). */
    for (double c = 1000.0; c < 6000.0; c += 1000.0)
        OK(flt_gauge_cut(g, c));
    for (size_t r = 0; r < 2000; ++r)
        OK(flt_gauge_push_row(g, t->s[r], K, &t->height[r * K], &t->slope[r * K], NULL));
    OK(flt_gauge_flush(g));
    size_t warm = take_sheets(g, 3);
    uint64_t early_before = 0, early_after = 0;
    OK(flt_gauge_count(g, FLT_GAUGE_COUNT_PROVISIONAL, &early_before));

    /* Counted: a second strip (a long reversal starts it) of 1 m sheets,
     * a line stop, a short reversal, cuts, polling, the tail. */
    atomic_store(&g_allocations, 0);
    atomic_store(&g_counting, 1);
    /* The first row goes back 6 m (a new strip; the cuts' order starts
     * again). */
    flt_status st = flt_gauge_push_row(g, t->s[0], K, t->height, t->slope, NULL);
    for (double c = 1000.0; c < 18000.0 && st == FLT_OK; c += 1000.0)
        st = flt_gauge_cut(g, c);
    size_t sheets = 0;
    for (size_t r = 1; r < (size_t)R && st == FLT_OK; ++r) {
        st = flt_gauge_push_row(g, t->s[r], K, &t->height[r * K], &t->slope[r * K], NULL);
        if (r == 3000 && st == FLT_OK) /* a line stop and a short reversal */
            st = flt_gauge_push_row(g, t->s[r] - 9.0, K, &t->height[r * K], &t->slope[r * K], NULL);
        if (r % 500 == 0)
            sheets += take_sheets(g, 3);
    }
    if (st == FLT_OK)
        st = flt_gauge_flush(g);
    sheets += take_sheets(g, 3);
    atomic_store(&g_counting, 0);
    OK(st);
    OK(flt_gauge_count(g, FLT_GAUGE_COUNT_PROVISIONAL, &early_after));
    const size_t early = (size_t)(early_after - early_before);
    print_message("%d workers: %zu + %zu sheets (%zu of them provisional), %zu allocations "
                  "while streaming\n",
                  workers, warm, sheets, early, atomic_load(&g_allocations));
    /* Every final sheet (17 cuts and the tail). An early answer waits
     * while the one before is still being made, and is not made at all
     * when its sheet's final result comes first, which depends on the
     * threads' timing: 9-17 of 17 came in runs on an idle machine, 14
     * with two workers under the whole test suite's load. 5 is enough to
     * know that the early answers' path ran while counting. */
    assert_true(sheets - early >= 17 && early >= 5u);
    assert_int_equal(atomic_load(&g_allocations), 0);
    /* ... and the coil's statistics counted the final ones. */
    double stats[FLT_COIL_VALUES];
    OK(flt_gauge_coil_stats(g, FLT_COIL_LAST, 0, FLT_COIL_VALUES, stats));
    assert_true(stats[FLT_COIL_SHEETS] == (double)(sheets - early));
    flt_gauge_destroy(g);
    flt_options_destroy(o);
    flt_calib_destroy(calib);
    test_sheet_free(t);
}

static void frames_allocate_nothing(void **state) {
    (void)state;
    enum { K = 151, W = 2048, H = 240, FRAMES = 60 };
    flt_calib *calib = NULL;
    OK(flt_calib_create_reference(900, H, -750.0, 10.0, K, &calib));
    flt_options *o = NULL;
    OK(flt_options_create(&o));
    OK(flt_options_set(o, FLT_OPT_SIM_FRAME_SPACING, 10.0));
    flt_sim *sim = NULL;
    OK(flt_sim_create(calib, o, &sim));
    flt_options_destroy(o);
    OK(flt_options_create(&o));
    OK(flt_options_set(o, FLT_OPT_GAUGE_WORKERS, 2));
    OK(flt_options_set(o, FLT_OPT_GAUGE_OVERFLOW, 1));
    OK(flt_options_set(o, FLT_OPT_GAUGE_FRAME_SPACING, 8.0));
    OK(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 4.0, 800.0));
    uint8_t *frames = malloc((size_t)FRAMES * W * H);
    double e[FRAMES];
    for (int f = 0; f < FRAMES; ++f)
        OK(flt_sim_next_frame(sim, frames + (size_t)f * W * H, (size_t)W * H, W, &e[f], 0, NULL,
                              NULL, 0));
    flt_gauge *g = NULL;
    OK(flt_gauge_create(calib, o, &g));
    /* The first frame shows the lines: the workers' extractors are made
     * with their band then (once). */
    OK(flt_gauge_push_frame(g, frames, FLT_PIXEL_MONO8, W, H, W, e[0]));
    OK(flt_gauge_push_frame(g, frames + (size_t)W * H, FLT_PIXEL_MONO8, W, H, W, e[1]));
    atomic_store(&g_allocations, 0);
    atomic_store(&g_counting, 1);
    flt_status st = flt_gauge_cut(g, 300.0);
    for (int f = 2; f < FRAMES && st == FLT_OK; ++f)
        st = flt_gauge_push_frame(g, frames + (size_t)f * W * H, FLT_PIXEL_MONO8, W, H, W, e[f]);
    if (st == FLT_OK)
        st = flt_gauge_flush(g);
    atomic_store(&g_counting, 0);
    OK(st);
    uint64_t extracted = 0;
    OK(flt_gauge_count(g, FLT_GAUGE_COUNT_EXTRACTED, &extracted));
    print_message("%llu frames extracted by 2 workers, %zu allocations\n",
                  (unsigned long long)extracted, atomic_load(&g_allocations));
    assert_int_equal(extracted, FRAMES);
    assert_int_equal(take_sheets(g, 0), 2);
    assert_int_equal(atomic_load(&g_allocations), 0);
    flt_gauge_destroy(g);
    free(frames);
    flt_sim_destroy(sim);
    flt_options_destroy(o);
    flt_calib_destroy(calib);
}

/* The counter must be in place, or every count below would be 0. */
static int install_counter(void **state) {
    (void)state;
    return alloc_count_install() >= 1 ? 0 : -1;
}

static const int k_two = 2, k_one = 1, k_none = 0;

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_prestate(rows_and_sheets_allocate_nothing, (void *)&k_two),
        cmocka_unit_test_prestate(rows_and_sheets_allocate_nothing, (void *)&k_one),
        cmocka_unit_test_prestate(rows_and_sheets_allocate_nothing, (void *)&k_none),
        cmocka_unit_test(frames_allocate_nothing),
    };
    return cmocka_run_group_tests(tests, install_counter, NULL);
}
