// SPDX-License-Identifier: Apache-2.0
/* "No allocation in the advise call after create" (flatline/advisor.h):
 * counts every malloc/calloc/realloc (c/alloc_count.h) while an advisor of
 * 20 zones and 8 actuators advises 200 times, with the bounds active and
 * not and a zone without data now and then, an accepted identification in
 * between; a control checks that the counter sees the allocations of
 * create. */
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

enum { Z = 20, A = 8, S = 24 };

static double uniform(uint64_t *state) {
    *state = *state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}

static void advise_allocates_nothing(void **unused) {
    (void)unused;
    uint64_t rng = 9;
    assert_int_equal(alloc_count_install() > 0, 1);
    flt_advisor *a = NULL;
    g_allocations = 0;
    g_counting = 1;
    assert_int_equal(flt_advisor_create(Z, A, NULL, &a), FLT_OK);
    g_counting = 0;
    assert_true(g_allocations >= 3); /* control: the handle and its buffers */

    double g[Z * A], du[S * A], dp[S * Z];
    for (size_t i = 0; i < Z * A; ++i)
        g[i] = 20 * uniform(&rng) - 10;
    for (size_t j = 0; j < A; ++j)
        assert_int_equal(flt_advisor_set_actuator(a, j, "flight", "mm", -1, 1, 0.3), FLT_OK);
    assert_int_equal(flt_advisor_set_influence(a, g, Z * A), FLT_OK);

    double p[Z], us[A], un[A], d[A], pred[Z], conf;
    for (int round = 0; round < 2; ++round) {
        g_allocations = 0;
        g_counting = 1;
        for (int k = 0; k < 100; ++k) {
            for (size_t z = 0; z < Z; ++z)
                p[z] = 40 * uniform(&rng) * (k % 3); /* 0 .. 80: bounds on or off */
            if (k % 5 == 0)
                p[3] = NAN; /* a zone without data: the matrices over the others */
            for (size_t j = 0; j < A; ++j)
                us[j] = un[j] = 2 * uniform(&rng) - 1;
            if (flt_advisor_advise(a, p, Z, us, A, un, A, d, A, pred, Z, &conf) != FLT_OK)
                break;
        }
        g_counting = 0;
        assert_int_equal(g_allocations, 0);
        /* An identification (which may allocate) between the rounds. */
        for (size_t k = 0; k < S; ++k) {
            for (size_t j = 0; j < A; ++j)
                du[k * A + j] = 2 * uniform(&rng) - 1;
            for (size_t z = 0; z < Z; ++z) {
                double v = 0;
                for (size_t j = 0; j < A; ++j)
                    v += g[z * A + j] * du[k * A + j];
                dp[k * Z + z] = v;
            }
        }
        assert_int_equal(flt_advisor_identify(a, S, du, S * A, dp, S * Z, 1e-6), FLT_OK);
    }
    flt_advisor_destroy(a);
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(advise_allocates_nothing)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
