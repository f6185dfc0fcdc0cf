// SPDX-License-Identifier: Apache-2.0
/* libFuzzer harness: the gauge's sequencer fed random sequences of
 * push_row / cut / flush / next_sheet / count with random gauge and
 * reconstructor options, encoder positions that stop, back up, reverse
 * far, jump, and rows with NaN, infinite, huge or missing samples, so that
 * strips begin and end, cuts come early, late and out of order, sheets
 * split, empty sheets appear and sheet slots run out. The gauge runs
 * inline (gauge_workers = 0), so every input replays the same way. Every
 * call must return a status (no crash, no sanitizer report), every failure
 * a message and never FLT_ERR_INTERNAL, and every sheet must keep the NaN
 * policy: a NaN value only with its flag. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "flatline/gauge.h"
#include "flatline/sim.h"
#include "fuzz_input.h"

enum { MAX_FIBERS = 8 };

static void expect(flt_status st) {
    if (st != FLT_OK && flt_last_error_message()[0] == 0)
        abort(); /* silent failure */
    if (st == FLT_ERR_INTERNAL)
        abort(); /* a library bug */
}

static double value(const flt_sheet *sheet, flt_sheet_value key) {
    double v = 0;
    if (flt_sheet_get(sheet, key, &v) != FLT_OK)
        abort();
    return v;
}

/* Every value of a sheet, and the NaN policy of gauge.h. */
static void check_sheet(const flt_sheet *sheet, int maps) {
    /* (isnan is only "nonzero" for a NaN: MinGW-w64's is not 1, so it is
     * compared through !!.) */
    const unsigned flags = (unsigned)value(sheet, FLT_SHEET_FLAGS);
    const unsigned window = (unsigned)value(sheet, FLT_SHEET_WINDOW_FLAGS);
    if (!!isnan(value(sheet, FLT_SHEET_S_FIRST)) != !!(flags & FLT_SHEET_FLAG_EMPTY))
        abort();
    if (!!isnan(value(sheet, FLT_SHEET_STRIP_WIDTH)) != !!(flags & FLT_SHEET_FLAG_NO_EDGES))
        abort();
    if (!!isnan(value(sheet, FLT_SHEET_WAVE_HEIGHT)) != !!(flags & FLT_SHEET_FLAG_NO_WAVE))
        abort();
    if (isnan(value(sheet, FLT_SHEET_BOW)) && !(window & FLT_WINDOW_NO_BOW))
        abort();
    if (isnan(value(sheet, FLT_SHEET_CROSSBOW)) && !(window & FLT_WINDOW_NO_CROSSBOW))
        abort();
    if (isnan(value(sheet, FLT_SHEET_MAX_I_UNITS)) && !(window & FLT_WINDOW_NO_VALID_FIBER))
        abort();
    for (int key = 0; key <= FLT_SHEET_ZONES; ++key)
        if (isinf(value(sheet, (flt_sheet_value)key)))
            abort();
    if (!(value(sheet, FLT_SHEET_S_START) < value(sheet, FLT_SHEET_S_END)) &&
        !(flags & (FLT_SHEET_FLAG_TAIL | FLT_SHEET_FLAG_FLUSHED | FLT_SHEET_FLAG_NEW_STRIP)))
        abort(); /* a sheet ended by a cut or a split has a length */
    const size_t fibers = (size_t)value(sheet, FLT_SHEET_FIBERS);
    const size_t zones = (size_t)value(sheet, FLT_SHEET_ZONES);
    const size_t rows = (size_t)value(sheet, FLT_SHEET_ROWS);
    const size_t n = fibers > zones ? fibers : zones;
    double *a = malloc(n * sizeof(double)), *b = malloc(n * sizeof(double));
    if (!a || !b)
        abort();
    if (flt_sheet_get_array(sheet, FLT_SHEET_FIBER_FLAGS, fibers, b) != FLT_OK ||
        flt_sheet_get_array(sheet, FLT_SHEET_FIBER_I_UNITS, fibers, a) != FLT_OK)
        abort();
    for (size_t k = 0; k < fibers; ++k)
        if (isnan(a[k]) && !((unsigned)b[k] & FLT_FIBER_NO_DATA))
            abort();
    if (flt_sheet_get_array(sheet, FLT_SHEET_ZONE_FLAGS, zones, b) != FLT_OK ||
        flt_sheet_get_array(sheet, FLT_SHEET_ZONE_I_UNITS, zones, a) != FLT_OK)
        abort();
    for (size_t j = 0; j < zones; ++j)
        if (isnan(a[j]) && !((unsigned)b[j] & FLT_ZONE_NO_DATA))
            abort();
    free(a);
    free(b);
    if (maps < 1)
        return;
    double *s = malloc((rows + 1) * sizeof(double)),
           *z = malloc((rows * fibers + 1) * sizeof(double));
    uint8_t *f = malloc(rows * fibers + 1);
    if (!s || !z || !f)
        abort();
    if (flt_sheet_height_map(sheet, rows, fibers, s, z, f) != FLT_OK)
        abort();
    for (size_t r = 0; r < rows; ++r) {
        if (r > 0 && !(s[r] > s[r - 1]))
            abort(); /* rows in order */
        if (!(s[r] >= value(sheet, FLT_SHEET_S_START) && s[r] <= value(sheet, FLT_SHEET_S_END)))
            abort(); /* inside the sheet */
    }
    for (size_t i = 0; i < rows * fibers; ++i)
        if (!isfinite(z[i]) && !(f[i] & FLT_FLAG_NO_DATA))
            abort();
    free(s);
    free(z);
    free(f);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    fuzz_input in = {data, size};
    const size_t fibers = 2 + fuzz_u8(&in) % (MAX_FIBERS - 1);
    flt_calib *calib = NULL;
    if (flt_calib_create_reference(900, 240, -100.0, 200.0 / (double)(fibers - 1), fibers,
                                   &calib) != FLT_OK)
        abort();
    flt_options *opt = NULL;
    if (flt_options_create(&opt) != FLT_OK)
        abort();
    expect(flt_options_set(opt, FLT_OPT_GAUGE_WORKERS, 0));
    /* Small buffers and short sheets, so that splits and full slots come. */
    static const flt_option keys[] = {FLT_OPT_GAUGE_FRAME_SPACING,    FLT_OPT_GAUGE_REVERSAL_LENGTH,
                                      FLT_OPT_GAUGE_STRIP_MIN_WIDTH,  FLT_OPT_GAUGE_TAIL_LENGTH,
                                      FLT_OPT_GAUGE_MAX_SHEET_LENGTH, FLT_OPT_GAUGE_KEEP_MAPS,
                                      FLT_OPT_GAUGE_SHEET_SLOTS,      FLT_OPT_LAG_KNOTS,
                                      FLT_OPT_RIGID_MOTION,           FLT_OPT_ROBUST,
                                      FLT_OPT_KNOT_SPACING,           FLT_OPT_MAX_GAP,
                                      FLT_OPT_FLAT_MIN_LENGTH,        FLT_OPT_FLAT_ZONE_WIDTH};
    const int n_opts = fuzz_u8(&in) % 6;
    for (int i = 0; i < n_opts; ++i) {
        flt_option key = keys[fuzz_u8(&in) % (sizeof keys / sizeof keys[0])];
        double v = fuzz_u8(&in) & 1 ? (double)(fuzz_u8(&in) % 64) : fuzz_double(&in, 3000.0);
        expect(flt_options_set(opt, key, v));
    }
    /* Frames 0.5 .. 26 mm apart at least and sheets up to 5 m: the buffers
     * stay small (finer frames cost memory by design, see gauge.h). */
    expect(flt_options_set(opt, FLT_OPT_GAUGE_FRAME_SPACING, 0.5 + 0.1 * fuzz_u8(&in)));
    expect(flt_options_set(opt, FLT_OPT_GAUGE_MAX_SHEET_LENGTH, 100.0 + 20.0 * fuzz_u8(&in)));
    if (fuzz_u8(&in) & 1)
        expect(flt_options_set(opt, FLT_OPT_ROW_CAPACITY, 16 + fuzz_u8(&in)));
    double maps = 0;
    expect(flt_options_get(opt, FLT_OPT_GAUGE_KEEP_MAPS, &maps));

    flt_gauge *g = NULL;
    flt_status st = flt_gauge_create(calib, opt, &g);
    expect(st);
    flt_options_destroy(opt);
    flt_calib_destroy(calib);
    if (st != FLT_OK)
        return 0;

    double h[MAX_FIBERS], k[MAX_FIBERS], e = 0.0, c = 0.0;
    uint8_t valid[MAX_FIBERS];
    uint64_t pushed = 0;
    for (int op = 0; op < 256 && in.n > 0; ++op) {
        switch (fuzz_u8(&in) % 10) {
            default: { /* a few rows, mostly advancing */
                const int rows = 1 + fuzz_u8(&in) % 16, mode = fuzz_u8(&in);
                for (int r = 0; r < rows; ++r) {
                    const uint8_t how = fuzz_u8(&in);
                    e += (mode & 7)  ? 0.5 * (how & 15) + 1.0       /* advance, maybe stop */
                         : (how & 1) ? -(double)fuzz_u8(&in) * 10.0 /* back up */
                                     : fuzz_double(&in, 2.0e5);     /* anything */
                    for (size_t f = 0; f < fibers; ++f) {
                        const uint8_t w = (mode & 8) ? fuzz_u8(&in) : 0;
                        h[f] = (w & 1) ? fuzz_double(&in, 30.0) : 2.0 * sin(e / 300.0 + (double)f);
                        k[f] = (w & 2) ? fuzz_double(&in, 0.1) : cos(e / 300.0) / 150.0;
                        valid[f] = (w & 12) != 12 && !(mode & 16);
                    }
                    st = flt_gauge_push_row(g, e, fibers, h, k, (mode & 32) ? valid : NULL);
                    expect(st);
                    pushed += st == FLT_OK;
                    if (!isfinite(e) || fabs(e) > 1e12)
                        e = 0.0;
                }
                break;
            }
            case 6: /* a cut near the strip, ahead of it or behind it */
                c = e + ((fuzz_u8(&in) & 1) ? 1.0 : -1.0) * 5.0 * fuzz_u8(&in);
                if (fuzz_u8(&in) == 0)
                    c = fuzz_double(&in, 1e6);
                expect(flt_gauge_cut(g, c));
                break;
            case 7:
                expect(flt_gauge_flush(g));
                break;
            case 8: {
                flt_sheet *sheet = NULL;
                expect(flt_gauge_next_sheet(g, 0, &sheet));
                if (sheet) {
                    check_sheet(sheet, (int)maps);
                    flt_sheet_destroy(sheet);
                }
                break;
            }
        }
    }
    expect(flt_gauge_flush(g));
    uint64_t frames = 0;
    expect(flt_gauge_count(g, FLT_GAUGE_COUNT_FRAMES, &frames));
    if (frames != pushed)
        abort(); /* every accepted row counted, nothing else */
    for (;;) {
        flt_sheet *sheet = NULL;
        expect(flt_gauge_next_sheet(g, 0, &sheet));
        if (!sheet)
            break;
        check_sheet(sheet, (int)maps);
        flt_sheet_destroy(sheet);
    }
    flt_gauge_destroy(g);
    return 0;
}
