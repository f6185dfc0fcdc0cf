// SPDX-License-Identifier: Apache-2.0
/* "No allocation in per-row hot paths": counts every malloc/calloc/realloc
 * made by libflatline (and the C++ runtime under it) while a reconstructor
 * streams rows, peeks at its pending rows, finishes sheets and resets. The counting allocator
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
    double *s_peek = malloc(8192 * sizeof(double)), *z_peek = malloc(8192 * K * sizeof(double));
    uint8_t *flags = malloc(8192 * K), *flags_peek = malloc(8192 * K);
    flt_recon *rc = NULL;
    /* Control: the counter does see the library's allocations. */
    g_allocations = 0;
    g_counting = 1;
    assert_int_equal(flt_recon_create(K, options, &rc), FLT_OK);
    g_counting = 0;
    assert_true(g_allocations >= 10);

    g_allocations = 0;
    g_counting = 1;
    size_t pulled = 0, n = 0, peeks = 0, peeked = 0;
    for (size_t r = 0; r < t->rows; ++r) {
        const uint8_t *v = r < 3000 ? valid + r * K : NULL;
        if (flt_recon_push(rc, 1, K, &t->s[r], t->height + r * K, t->slope + r * K, v) != FLT_OK)
            break;
        if (flt_recon_pull(rc, 8192, K, s_out, z_out, flags, &n) != FLT_OK)
            break;
        pulled += n;
        if (r % 97 == 0) { /* a provisional look, as at a sheet's cut */
            size_t pending = 0;
            if (flt_recon_pending(rc, &pending) != FLT_OK ||
                flt_recon_peek(rc, 8192, K, s_peek, z_peek, flags_peek, &n) != FLT_OK ||
                n != pending)
                break;
            ++peeks;
            peeked += n;
        }
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

    print_message("%zu rows pushed and pulled, %zu peeks at %zu pending rows, %zu allocations\n",
                  pulled, peeks, peeked, g_allocations);
    assert_int_equal(pulled, t->rows);
    assert_int_equal(peeks, (t->rows + 96) / 97); /* every peek worked */
    assert_true(peeked > 0);
    assert_int_equal(g_allocations, 0);
    flt_recon_destroy(rc);
    free(valid);
    free(s_out);
    free(z_out);
    free(flags);
    free(s_peek);
    free(z_peek);
    free(flags_peek);
    test_sheet_free(t);
}

/* flt_reconstruct keeps its working memory for the next call of the same
 * shape: the reference's production sheet (2000 rows x 1150 fibers),
 * reconstructed again and again, allocates nothing after the first call,
 * in every mode, with flags out or not, with the extractor's flags in, and
 * after a sheet of another shape in between; with no options at all too.
 * Control: the first call of each allocates. */
static void batch_allocates_nothing_after_the_first_call(void **state) {
    (void)state;
    const size_t R = 2000, K = 1150;
    test_sheet *t = test_sheet_make(R, K, 0.0, 3.0, 0.0, 2.0, 100.0, 3);
    test_sheet_add_noise(t, 2.5, 0.05, 4);
    double *z = malloc(R * K * sizeof(double));
    uint8_t *flags = malloc(R * K), *in_flags = calloc(R * K, 1);
    assert_non_null(z);
    assert_non_null(flags);
    assert_non_null(in_flags);
    for (size_t r = 0; r < R; ++r)
        in_flags[r * K + 7] = FLT_FLAG_OFF_STRIP;
    test_sheet *other = test_sheet_make(300, 20, 0.0, 3.0, 0.0, 10.0, 100.0, 5);
    double *z_other = malloc(300 * 20 * sizeof(double));
    for (int mode = 0; mode < 4; ++mode) {
        /* 0 plain, 1 rigid_motion + robust, 2 plain without flags out,
         * 3 plain with the extractor's flags in. */
        flt_options *o = NULL;
        assert_int_equal(flt_options_create(&o), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_RIGID_MOTION, mode == 1), FLT_OK);
        assert_int_equal(flt_options_set(o, FLT_OPT_ROBUST, mode == 1 ? FLT_ROBUST_HUBER : 0),
                         FLT_OK);
        uint8_t *out_flags = mode == 2 ? NULL : flags;
#define CALL()                                                                                     \
  (mode == 3 ? flt_reconstruct_flagged(o, R, K, t->s, t->height, t->slope, in_flags, z, out_flags) \
             : flt_reconstruct(o, R, K, t->s, t->height, t->slope, NULL, z, out_flags))
        g_allocations = 0;
        g_counting = 1;
        flt_status first = CALL();
        g_counting = 0;
        assert_int_equal(first, FLT_OK);
        const size_t first_allocations = g_allocations;
        /* The control: the counter sees them (mode 3 solves in mode 0's
         * workspace, and adds its mask of the flags in). */
        assert_true(first_allocations >= (mode == 3 ? 1u : 5u));
        g_allocations = 0;
        g_counting = 1;
        flt_status again = CALL();
        flt_status between = flt_reconstruct(NULL, 300, 20, other->s, other->height, other->slope,
                                             NULL, z_other, NULL);
        flt_status third = CALL();
        g_counting = 0;
        const size_t later = g_allocations;
        g_allocations = 0;
        g_counting = 1;
        flt_status fourth = CALL();
        g_counting = 0;
        assert_int_equal(again, FLT_OK);
        assert_int_equal(between, FLT_OK);
        assert_int_equal(third, FLT_OK);
        assert_int_equal(fourth, FLT_OK);
        print_message("mode %d: first call %zu allocations; then %zu (with a sheet of another "
                      "shape's first call between), then %zu\n",
                      mode, first_allocations, later, g_allocations);
        /* The sheet between is new: its own workspace's allocations only. */
        assert_true(later < first_allocations + 20);
        assert_int_equal(g_allocations, 0);
        if (mode == 0) {
            /* No options at all (every default: what bench_recon and the
             * Python binding pass) is the same configuration: it solves in
             * the workspace of the call before, allocating nothing. */
            g_allocations = 0;
            g_counting = 1;
            flt_status defaults =
                flt_reconstruct(NULL, R, K, t->s, t->height, t->slope, NULL, z, out_flags);
            g_counting = 0;
            assert_int_equal(defaults, FLT_OK);
            assert_int_equal(g_allocations, 0);
            /* flt_reconstruct_release frees what the calls kept: at least
             * this sheet's workspace, which recon.h puts at about 20 doubles
             * per fiber and knot (knots 100 mm apart over the sheet; half of
             * that as the bound, the header's "about"), and the next call
             * of the shape allocates it again, as the first did. */
            double freed = 0;
            assert_int_equal(flt_reconstruct_release(&freed), FLT_OK);
            const double knots = (t->s[R - 1] - t->s[0] + 100.0) / 100.0 + 4;
            print_message("flt_reconstruct_release: %.1f MB freed (%.0f knots x %zu fibers)\n",
                          freed / 1e6, knots, K);
            assert_true(freed >= 10.0 * 8.0 * knots * (double)K);
            g_allocations = 0;
            g_counting = 1;
            flt_status after = CALL();
            g_counting = 0;
            assert_int_equal(after, FLT_OK);
            assert_true(g_allocations >= 5u);
        }
#undef CALL
        flt_options_destroy(o);
    }
    free(z);
    free(flags);
    free(in_flags);
    free(z_other);
    test_sheet_free(other);
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
        cmocka_unit_test(batch_allocates_nothing_after_the_first_call),
    };
    return cmocka_run_group_tests(tests, install_counter, NULL);
}
