// SPDX-License-Identifier: Apache-2.0
/*
 * Coil identity through the gauge (flatline/gauge.h, flt_gauge_set_coil):
 * two simulated coils (an encoder reset between them); the identity given
 * before the first frame belongs to coil 1, one given in the middle of
 * coil 1 belongs to coil 2 (coil 1 has its identity already), every sheet
 * carries its coil's identity, the coil's
 * statistics carry it (flt_gauge_coil_info), and the nominal thickness
 * chooses the rule band: rules whose bands split at 3 mm judge coil 1
 * (nominal 2 mm) and coil 2 (nominal 4 mm) by different bands although
 * flt_gauge_set_rules was given 2 mm for both. Notes go to the sheet whose
 * rows begin where they were given.
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

#define OK(call) assert_int_equal((call), FLT_OK)

enum { K = 51, ROWS = 1000 }; /* per coil: 3000 mm at 3 mm */
static const double STEP = 3.0;

static const char k_rules[] =
    "{ \"format\": \"flatline-tolerances\", \"version\": 1, \"name\": \"bands\", \"rules\": [\n"
    " { \"name\": \"I-Units\", \"measure\": \"zone_i_units\", \"bands\": [\n"
    "   { \"thickness_mm\": [1, 3], \"width_mm\": [0, 3000], \"limit\": 1000 },\n"
    "   { \"thickness_mm\": [3, 10], \"width_mm\": [0, 3000], \"limit\": 2000 } ] } ] }\n";

static flt_coil_info *coil(const char *id, double thickness) {
    flt_coil_info *c = NULL;
    OK(flt_coil_info_create(id, &c));
    OK(flt_coil_info_set_nominal(c, thickness, 0));
    return c;
}

static void test_identity_bands_and_notes(void **state) {
    (void)state;
    flt_calib *calib = NULL;
    OK(flt_calib_create_reference(0, 2048, -500.0, 20.0, K, &calib));
    flt_options *so = NULL;
    OK(flt_options_create(&so));
    OK(flt_options_set(so, FLT_OPT_SIM_FRAME_SPACING, STEP));
    flt_sim *sim = NULL;
    OK(flt_sim_create(calib, so, &sim));
    flt_options_destroy(so);
    OK(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 2.0, 1000.0));
    static double e[ROWS], s[ROWS], h[ROWS * K], sl[ROWS * K];
    static uint8_t v[ROWS * K];
    OK(flt_sim_next_rows(sim, ROWS, K, e, s, h, sl, v, NULL));
    flt_sim_destroy(sim);

    flt_options *o = NULL;
    OK(flt_options_create(&o));
    OK(flt_options_set(o, FLT_OPT_GAUGE_WORKERS, 0));
    OK(flt_options_set(o, FLT_OPT_GAUGE_FRAME_SPACING, STEP));
    flt_gauge *g = NULL;
    OK(flt_gauge_create(calib, o, &g));
    flt_options_destroy(o);
    flt_rules *rules = NULL;
    OK(flt_rules_load_text(k_rules, strlen(k_rules), &rules));
    OK(flt_gauge_set_rules(g, rules, 2.0, FLT_GAUGE_WIDTH_MEASURED));
    flt_rules_destroy(rules);
    flt_coil_info *a = coil("A-1", 2.0), *b = coil("B-2", 4.0);
    OK(flt_gauge_set_coil(g, a));
    assert_int_equal(flt_gauge_set_coil(g, (const flt_coil_info *)g), FLT_ERR_INVALID_ARGUMENT);
    char seen_id[8][16];
    double band[8], index[8];
    int notes[8], sheets = 0;
    for (int c = 0; c < 2; ++c) {
        /* Coil 1 from encoder 0, coil 2 after a reset to 0 (a long
         * reversal: a new strip); cuts every 1000 mm, given after the
         * first frame of the new numbering. */
        if (c == 0)
            for (int k = 1; k < 3; ++k)
                OK(flt_gauge_cut(g, 1000.0 * k));
        for (int r = 0; r < ROWS; ++r) {
            if (c == 0 && r == 500) {
                OK(flt_gauge_set_coil(g, b)); /* coil 1 has its identity: for coil 2 */
                OK(flt_gauge_note(g, "leveler", "entry roll +0.1 mm"));
            }
            OK(flt_gauge_push_row(g, e[r], K, &h[(size_t)r * K], &sl[(size_t)r * K],
                                  &v[(size_t)r * K]));
            if (c == 1 && r == 0) {
                for (int k = 1; k < 3; ++k)
                    OK(flt_gauge_cut(g, 1000.0 * k));
                /* The reversal ended coil 1 (0 workers: at once); its
                 * statistics carry its identity. */
                flt_coil_info *prev = NULL;
                OK(flt_gauge_coil_info(g, FLT_COIL_LAST, &prev));
                const char *pid = NULL;
                OK(flt_coil_info_get_text(prev, FLT_COIL_FIELD_ID, &pid));
                assert_string_equal(pid, "A-1");
                flt_coil_info_destroy(prev);
            }
            for (;;) {
                flt_sheet *sh = NULL;
                OK(flt_gauge_next_sheet(g, 0, &sh));
                if (!sh)
                    break;
                const flt_coil_info *ci = NULL;
                OK(flt_sheet_coil(sh, &ci));
                const char *id = NULL;
                OK(flt_coil_info_get_text(ci, FLT_COIL_FIELD_ID, &id));
                assert_int_equal(
                    flt_coil_info_set_text((flt_coil_info *)ci, FLT_COIL_FIELD_HEAT, "x"),
                    FLT_ERR_STATE); /* lent: read-only */
                snprintf(seen_id[sheets], sizeof seen_id[0], "%s", id);
                const flt_rules *sr = NULL;
                const flt_verdict *vd = NULL;
                OK(flt_sheet_verdict(sh, &sr, &vd));
                OK(flt_verdict_get(vd, 0, FLT_VERDICT_BAND, &band[sheets]));
                OK(flt_sheet_get(sh, FLT_SHEET_INDEX, &index[sheets]));
                size_t n = 0;
                OK(flt_sheet_note_count(sh, &n));
                notes[sheets] = (int)n;
                if (n) {
                    const char *kind = NULL, *text = NULL;
                    double at = 0;
                    OK(flt_sheet_note(sh, 0, &kind, &text, &at));
                    assert_string_equal(kind, "leveler");
                    assert_string_equal(text, "entry roll +0.1 mm");
                    assert_true(fabs(at - (e[500] - 0.0)) < 60.0); /* s of the row it preceded */
                }
                ++sheets;
                flt_sheet_destroy(sh);
            }
        }
    }
    OK(flt_gauge_flush(g));
    for (;;) {
        flt_sheet *sh = NULL;
        OK(flt_gauge_next_sheet(g, 0, &sh));
        if (!sh)
            break;
        const flt_coil_info *ci = NULL;
        OK(flt_sheet_coil(sh, &ci));
        const char *id = NULL;
        OK(flt_coil_info_get_text(ci, FLT_COIL_FIELD_ID, &id));
        snprintf(seen_id[sheets], sizeof seen_id[0], "%s", id);
        const flt_rules *sr = NULL;
        const flt_verdict *vd = NULL;
        OK(flt_sheet_verdict(sh, &sr, &vd));
        OK(flt_verdict_get(vd, 0, FLT_VERDICT_BAND, &band[sheets]));
        OK(flt_sheet_get(sh, FLT_SHEET_INDEX, &index[sheets]));
        size_t n = 0;
        OK(flt_sheet_note_count(sh, &n));
        notes[sheets++] = (int)n;
        flt_sheet_destroy(sh);
    }
    assert_int_equal(sheets, 6);
    int note_total = 0;
    for (int i = 0; i < sheets; ++i) {
        const int second = i >= 3;
        assert_string_equal(seen_id[i], second ? "B-2" : "A-1");
        /* Band 0 (thickness 1..3) for coil 1's 2 mm, band 1 for coil 2's 4 mm. */
        assert_true(band[i] == (second ? 1 : 0));
        note_total += notes[i];
    }
    assert_int_equal(note_total, 1);
    assert_int_equal(notes[1], 1); /* row 500 lies in coil 1's second sheet */
    flt_coil_info *last = NULL;
    OK(flt_gauge_coil_info(g, FLT_COIL_LAST, &last));
    const char *id = NULL;
    OK(flt_coil_info_get_text(last, FLT_COIL_FIELD_ID, &id));
    assert_string_equal(id, "B-2");
    flt_coil_info_destroy(last);
    flt_coil_info_destroy(a);
    flt_coil_info_destroy(b);
    flt_gauge_destroy(g);
    flt_calib_destroy(calib);
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_identity_bands_and_notes)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
