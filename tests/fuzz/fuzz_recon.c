// SPDX-License-Identifier: Apache-2.0
/* libFuzzer harness: the streaming reconstructor fed random sequences of
 * push / pull / end_sheet / reset / boundary / ready with random options and
 * random values (NaN, Inf, huge, negative, any bit pattern), and the
 * whole-sheet flt_reconstruct. Every call must return a status (no crash,
 * no sanitizer report), every failure a message, and pulled rows must be
 * finite or flagged FLT_FLAG_NO_DATA (recon.h). */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "flatline/recon.h"
#include "fuzz_input.h"

enum { MAX_FIBERS = 6, MAX_ROWS = 40 };

static void expect(flt_status st) {
    if (st != FLT_OK && flt_last_error_message()[0] == 0)
        abort(); /* silent failure */
    if (st == FLT_ERR_INTERNAL)
        abort(); /* a library bug */
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    fuzz_input in = {data, size};
    const size_t fibers = 1 + fuzz_u8(&in) % MAX_FIBERS;
    flt_options *opt = NULL;
    if (flt_options_create(&opt) != FLT_OK)
        abort();
    /* A few options; out-of-range values are refused by options_set. */
    static const flt_option keys[] = {
        FLT_OPT_KNOT_SPACING, FLT_OPT_LASER_SPACING,     FLT_OPT_HEIGHT_SIGMA,
        FLT_OPT_SLOPE_SIGMA,  FLT_OPT_CURVATURE_WEIGHT,  FLT_OPT_LAG_KNOTS,
        FLT_OPT_MAX_GAP,      FLT_OPT_ROW_CAPACITY,      FLT_OPT_RIGID_MOTION,
        FLT_OPT_ROBUST,       FLT_OPT_ROBUST_ITERATIONS, FLT_OPT_CURVATURE_JUMP_WEIGHT};
    const int n_opts = fuzz_u8(&in) % 5;
    for (int i = 0; i < n_opts; ++i) {
        flt_option key = keys[fuzz_u8(&in) % (sizeof keys / sizeof keys[0])];
        double v = fuzz_u8(&in) & 1 ? (double)(fuzz_u8(&in) % 130) : fuzz_double(&in, 200.0);
        expect(flt_options_set(opt, key, v));
    }
    /* Small capacities so that BUFFER_FULL is reached. */
    if (fuzz_u8(&in) & 1)
        expect(flt_options_set(opt, FLT_OPT_ROW_CAPACITY, 16 + fuzz_u8(&in)));
    if (fuzz_u8(&in) & 1)
        expect(flt_options_set(opt, FLT_OPT_LAG_KNOTS, fuzz_u8(&in) % 12));

    static double s[MAX_ROWS], h[MAX_ROWS * MAX_FIBERS], k[MAX_ROWS * MAX_FIBERS];
    static double s_out[MAX_ROWS], z_out[MAX_ROWS * MAX_FIBERS];
    static uint8_t valid[MAX_ROWS * MAX_FIBERS], flags[MAX_ROWS * MAX_FIBERS];
    double last_s = 0.0;

    flt_recon *r = NULL;
    flt_status st = flt_recon_create(fibers, opt, &r);
    expect(st);
    if (st != FLT_OK) {
        flt_options_destroy(opt);
        return 0;
    }
    for (int op = 0; op < 64 && in.n > 0; ++op) {
        switch (fuzz_u8(&in) % 8) {
            case 0:
            case 1:
            case 2: { /* push */
                size_t rows = 1 + fuzz_u8(&in) % MAX_ROWS;
                int mode = fuzz_u8(&in);
                for (size_t i = 0; i < rows; ++i) {
                    /* Mostly increasing positions (so that data gets in), with
                     * occasional garbage. */
                    double step = (mode & 3) ? 0.5 + fuzz_u8(&in) * 0.25 : fuzz_double(&in, 500.0);
                    last_s += step;
                    s[i] = last_s;
                    for (size_t f = 0; f < fibers; ++f) {
                        uint8_t how = fuzz_u8(&in);
                        h[i * fibers + f] = how & 1 ? fuzz_double(&in, 30.0) : 0.01 * (int8_t)how;
                        k[i * fibers + f] = how & 2 ? fuzz_double(&in, 0.1) : 0.0001 * (int8_t)how;
                        valid[i * fibers + f] = (how & 12) != 12;
                    }
                }
                expect(flt_recon_push(r, rows, fibers, s, h, k, (mode & 4) ? valid : NULL));
                break;
            }
            case 3: { /* pull */
                size_t got = 0, max_rows = fuzz_u8(&in) % (MAX_ROWS + 1);
                st = flt_recon_pull(r, max_rows, fibers, s_out, z_out, flags, &got);
                expect(st);
                if (st == FLT_OK) {
                    if (got > max_rows)
                        abort();
                    for (size_t i = 0; i < got * fibers; ++i)
                        if (!isfinite(z_out[i]) && !(flags[i] & FLT_FLAG_NO_DATA))
                            abort();
                }
                break;
            }
            case 4:
                expect(flt_recon_end_sheet(r));
                break;
            case 5:
                expect(flt_recon_reset(r));
                break;
            case 6: {
                double bs, bh[MAX_FIBERS], bk[MAX_FIBERS];
                expect(flt_recon_boundary(r, fibers, &bs, bh, bk));
                break;
            }
            default: {
                size_t ready = 0;
                expect(flt_recon_ready(r, &ready));
                break;
            }
        }
    }
    flt_recon_destroy(r);

    /* The whole-sheet form on the last rows pushed. */
    size_t rows = 2 + fuzz_u8(&in) % (MAX_ROWS - 1);
    double pos = 0.0;
    for (size_t i = 0; i < rows; ++i) {
        pos += 1.0 + fuzz_u8(&in);
        s[i] = pos;
    }
    expect(flt_reconstruct(opt, rows, fibers, s, h, k, valid, z_out, flags));
    flt_options_destroy(opt);
    return 0;
}
