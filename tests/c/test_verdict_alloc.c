// SPDX-License-Identifier: Apache-2.0
/* "Nothing allocated per sheet": counts every malloc/calloc/realloc made by
 * libflatline (and the C++ runtime under it) while a verdict judges sheets
 * against straightedge rules along and across, once it has judged a sheet
 * of the largest size (flatline/verdict.h, "Memory": the scratch grows to
 * the longest line and the most lines once). The counting allocator
 * (alloc_count.h) sees the shared library's calls too. Not built under
 * sanitizers, which own malloc. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include <flatline/flatline.h>

#include "alloc_count.h"

#define OK(call) assert_int_equal((call), FLT_OK)

static const char k_rules[] =
    "{ \"format\": \"flatline-tolerances\", \"version\": 1, \"name\": \"alloc\",\n"
    "  \"rules\": [\n"
    "    { \"name\": \"1 m along\", \"measure\": \"straightedge_along\", \"length_mm\": 1000,\n"
    "      \"bands\": [ { \"thickness_mm\": [0, 50], \"width_mm\": [0, 5000], \"limit\": 3 } ] },\n"
    "    { \"name\": \"200 mm along\", \"measure\": \"straightedge_along\", \"length_mm\": 200,\n"
    "      \"bands\": [ { \"thickness_mm\": [0, 50], \"width_mm\": [0, 5000], \"limit\": 3 } ] },\n"
    "    { \"name\": \"1 m across\", \"measure\": \"straightedge_across\", \"length_mm\": 1000,\n"
    "      \"bands\": [ { \"thickness_mm\": [0, 50], \"width_mm\": [0, 5000], \"limit\": 1 } ] },\n"
    "    { \"name\": \"IU\", \"measure\": \"zone_i_units\",\n"
    "      \"bands\": [ { \"thickness_mm\": [0, 50], \"width_mm\": [0, 5000], \"limit\": 10 } ] }\n"
    "  ] }\n";

/* A sheet: a wave along (period `period` mm), a buckle across, noise,
 * holes with FLT_FLAG_NO_DATA. */
static void make_sheet(size_t rows, size_t fibers, double period, double *s, double *x, double *z,
                       uint8_t *flags) {
    uint64_t seed = 5;
    for (size_t r = 0; r < rows; ++r)
        s[r] = 1000.0 + 2.0 * (double)r;
    for (size_t k = 0; k < fibers; ++k)
        x[k] = -1000.0 + 2000.0 * (double)k / (double)(fibers - 1);
    for (size_t r = 0; r < rows; ++r)
        for (size_t k = 0; k < fibers; ++k) {
            seed = seed * 6364136223846793005ull + 1442695040888963407ull;
            const double u = (double)(seed >> 11) / 9007199254740992.0;
            const size_t at = r * fibers + k;
            z[at] = 3.0 * sin(2 * 3.14159265358979 * s[r] / period) *
                        cos(3.14159265358979 * x[k] / 2000.0) +
                    0.1 * (u - 0.5);
            flags[at] = 0;
            if (u < 0.02) {
                z[at] = NAN;
                flags[at] = FLT_FLAG_NO_DATA;
            }
        }
}

static void judging_sheets_allocates_nothing(void **state) {
    (void)state;
    enum { R = 1500, K = 400 };
    assert_true(alloc_count_install() >= 1);
    double *s = malloc(R * sizeof *s), *x = malloc(K * sizeof *x);
    double *z = malloc((size_t)R * K * sizeof *z);
    uint8_t *flags = malloc((size_t)R * K);
    flt_rules *rules = NULL;
    OK(flt_rules_load_text(k_rules, sizeof k_rules - 1, &rules));
    flt_verdict *v = NULL;
    atomic_store(&g_allocations, 0);
    atomic_store(&g_counting, 1);
    OK(flt_verdict_create(rules, &v));
    atomic_store(&g_counting, 0);
    assert_true(atomic_load(&g_allocations) >= 1); /* the counter sees the library */
    OK(flt_verdict_set_measure(v, FLT_MEASURE_ZONE_I_UNITS, 4.0, 0.0, 1500.0));

    /* The first sheet of the largest size grows the scratch. */
    make_sheet(R, K, 700.0, s, x, z, flags);
    OK(flt_verdict_evaluate(v, 3.0, 2000.0, R, K, s, x, z, flags));

    /* Counted: that sheet again, other waves, smaller sheets, no flags. */
    atomic_store(&g_allocations, 0);
    atomic_store(&g_counting, 1);
    size_t failed = 0, judged = 0;
    flt_status st = flt_verdict_evaluate(v, 3.0, 2000.0, R, K, s, x, z, flags);
    /* It judged: a 1 m straightedge bridges the 700 mm wave of 3 mm
     * amplitude on the middle fibers, nearly 6 mm deep, over the 3 mm
     * limit. */
    double worst = 0;
    if (st == FLT_OK)
        st = flt_verdict_get(v, 0, FLT_VERDICT_WORST, &worst);
    const double periods[] = {300.0, 1200.0, 2500.0};
    for (size_t i = 0; i < 3 && st == FLT_OK; ++i) {
        atomic_store(&g_counting, 0); /* the test's own sheet, not counted */
        make_sheet(R, K, periods[i], s, x, z, flags);
        atomic_store(&g_counting, 1);
        st = flt_verdict_evaluate(v, 3.0, 2000.0, R, K, s, x, z, i == 1 ? NULL : flags);
        if (st == FLT_OK)
            st = flt_verdict_evaluate(v, 3.0, 2000.0, R / 3, K / 2, s, x, z, flags);
        if (st == FLT_OK)
            st = flt_verdict_failed(v, &failed);
        judged += st == FLT_OK ? 2 : 0;
    }
    atomic_store(&g_counting, 0);
    OK(st);
    print_message("%zu sheets judged, %zu allocations\n", judged + 1, atomic_load(&g_allocations));
    assert_int_equal(judged, 6);
    assert_int_equal(atomic_load(&g_allocations), 0);
    /* 2 x 3 mm on the middle fiber (within 2.5 mm of x = 0, where the
     * cosine across is 1 within 1e-5); the contacts and the trough carry
     * up to 0.05 mm of noise each. */
    assert_true(fabs(worst - 6.0) <= 0.15);

    flt_verdict_destroy(v);
    flt_rules_destroy(rules);
    free(s);
    free(x);
    free(z);
    free(flags);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(judging_sheets_allocates_nothing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
