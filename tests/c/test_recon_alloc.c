// SPDX-License-Identifier: Apache-2.0
/* "No allocation in per-row hot paths": counts every malloc/calloc/realloc
 * made by libflatline (and the C++ runtime under it) while a reconstructor
 * streams rows, finishes sheets and resets. The counting allocator
 * (alloc_count.h) sees the shared library's calls too. Not built under
 * sanitizers, which own malloc. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include <flatline/flatline.h>

#include "alloc_count.h"
#include "sheet.h"

static void stream_and_count(const flt_options *options);

static void streaming_allocates_nothing_after_create(void **state) {
    (void)state;
    stream_and_count(NULL);
}

static void robust_rigid_streaming_allocates_nothing_after_create(void **state) {
    (void)state;
    flt_options *o = NULL;
    assert_int_equal(flt_options_create(&o), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_ROBUST, FLT_ROBUST_HUBER), FLT_OK);
    assert_int_equal(flt_options_set(o, FLT_OPT_RIGID_MOTION, 1), FLT_OK);
    stream_and_count(o);
    flt_options_destroy(o);
}

static void stream_and_count(const flt_options *options) {
    const size_t K = 64;
    test_sheet *t = test_sheet_make(6000, K, 0.0, 3.0, 0.1, 20.0, 100.0, 1);
    test_sheet_add_noise(t, 2.5, 0.05, 2);
    /* Some invalid samples and a gap, so the slow paths run as well. */
    uint8_t *valid = malloc(t->rows * K);
    memset(valid, 1, t->rows * K);
    for (size_t r = 1000; r < 1150; ++r)
        memset(valid + r * K, 0, K / 2);
    for (size_t i = 7; i < t->rows * K; i += 13)
        valid[i] = 0;
    double *s_out = malloc(8192 * sizeof(double)), *z_out = malloc(8192 * K * sizeof(double));
    uint8_t *flags = malloc(8192 * K);
    flt_recon *rc = NULL;
    /* Control: the counter does see the library's allocations. */
    g_allocations = 0;
    g_counting = 1;
    assert_int_equal(flt_recon_create(K, options, &rc), FLT_OK);
    g_counting = 0;
    assert_true(g_allocations >= 10);

    g_allocations = 0;
    g_counting = 1;
    size_t pulled = 0, n = 0;
    for (size_t r = 0; r < t->rows; ++r) {
        const uint8_t *v = r < 3000 ? valid + r * K : NULL;
        if (flt_recon_push(rc, 1, K, &t->s[r], t->height + r * K, t->slope + r * K, v) != FLT_OK)
            break;
        if (flt_recon_pull(rc, 8192, K, s_out, z_out, flags, &n) != FLT_OK)
            break;
        pulled += n;
        if (r == 2999 || r == 4999) {
            if (flt_recon_end_sheet(rc) != FLT_OK)
                break;
        }
    }
    flt_status end = flt_recon_end_sheet(rc);
    flt_status last_pull = flt_recon_pull(rc, 8192, K, s_out, z_out, flags, &n);
    pulled += n;
    flt_status reset = flt_recon_reset(rc);
    flt_status again = flt_recon_push(rc, 1, K, &t->s[0], t->height, t->slope, NULL);
    g_counting = 0;
    assert_int_equal(end, FLT_OK);
    assert_int_equal(last_pull, FLT_OK);
    assert_int_equal(reset, FLT_OK);
    assert_int_equal(again, FLT_OK);

    print_message("%zu rows pushed and pulled, %zu allocations\n", pulled, g_allocations);
    assert_int_equal(pulled, t->rows);
    assert_int_equal(g_allocations, 0);
    flt_recon_destroy(rc);
    free(valid);
    free(s_out);
    free(z_out);
    free(flags);
    test_sheet_free(t);
}

/* The counter must be in place, or every count below would be 0. */
static int install_counter(void **state) {
    (void)state;
    return alloc_count_install() >= 1 ? 0 : -1;
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(streaming_allocates_nothing_after_create),
        cmocka_unit_test(robust_rigid_streaming_allocates_nothing_after_create),
    };
    return cmocka_run_group_tests(tests, install_counter, NULL);
}
