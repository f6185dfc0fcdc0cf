// SPDX-License-Identifier: Apache-2.0
/* libFuzzer harness: the chain from a calibration file to flatness, as a
 * hand-edited or damaged file would drive it. The other harnesses take one
 * component with sane neighbours; here a mutated calibration decides the
 * frame size, the lens, the laser planes and the fiber grid every later
 * stage works with.
 *
 * Input: an 8-byte header, then the calibration text.
 *   byte 0      stages and pixel format: bit 0 render the frame with the
 *               simulator (else two synthetic lines), bits 1-2 Mono8 /
 *               Mono12 (+ junk in the high bits) / Mono16 / Mono10
 *   byte 1      extractor options: bits 0-1 Savitzky-Golay window 5, 7,
 *               11, 31; bit 2 fixed bands (else automatic); bits 3-7
 *               extract_min_peak in 32ths
 *   bytes 2, 3  the two lines' rows of a synthetic frame, in 256ths of the
 *               height (and the fixed bands around them)
 *   bytes 4-7   the encoder position of the first frame (an int32, mm)
 * Then: load the text (FLT_OK or FLT_ERR_FORMAT, never another status);
 * save and load it again; create an extractor (a refusal must carry a
 * message); process two frames of the calibration's size (up to 4
 * megapixels; larger ones only create the extractor: the per-pixel code is
 * the same, and a 268-megapixel frame would take the fuzzer's time);
 * check that a valid fiber is finite and an invalid one NaN; push the rows
 * into a reconstructor for the calibration's fibers, end the sheet and
 * check that a NaN comes only with FLT_FLAG_NO_DATA; create the flatness
 * metrics from the calibration. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "flatline/flatline.h"
#include "fuzz_input.h"

/* Any status but these is a bug; a failure must leave a message. */
static void expect(flt_status st) {
    if (st == FLT_ERR_INTERNAL || (st != FLT_OK && flt_last_error_message()[0] == 0))
        abort();
}

enum { MAX_PIXELS = 4 << 20 };

/* Two Gaussian lines of sigma 2 px at rows r0, r1 over a dim background,
 * at full scale `top`, into a width x height buffer of 8- or 16-bit words. */
static void synthetic_frame(void *frame, int bytes, uint32_t width, uint32_t height, double r0,
                            double r1, unsigned top, unsigned junk) {
    for (uint32_t v = 0; v < height; ++v) {
        const double d0 = ((double)v - r0) / 2.0, d1 = ((double)v - r1) / 2.0;
        const double level = 0.03 + 0.6 * exp(-0.5 * d0 * d0) + 0.6 * exp(-0.5 * d1 * d1);
        const unsigned value = (unsigned)(fmin(level, 1.0) * top);
        for (uint32_t u = 0; u < width; ++u) {
            const size_t i = (size_t)v * width + u;
            if (bytes == 1)
                ((uint8_t *)frame)[i] = (uint8_t)value;
            else
                ((uint16_t *)frame)[i] = (uint16_t)(value | junk);
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    fuzz_input in = {data, size < 8 ? size : 8};
    const uint8_t stages = fuzz_u8(&in), extract = fuzz_u8(&in);
    const uint8_t row0 = fuzz_u8(&in), row1 = fuzz_u8(&in);
    const double encoder0 = (double)(int32_t)fuzz_u32(&in);
    const char *text = size > 8 ? (const char *)data + 8 : "";
    const size_t length = size > 8 ? size - 8 : 0;

    flt_calib *calib = NULL;
    flt_status st = flt_calib_load_text(text, length, &calib);
    if (st != FLT_OK) {
        if (st != FLT_ERR_FORMAT || calib != NULL || flt_last_error_message()[0] == 0)
            abort();
        return 0;
    }
    uint32_t width = 0, height = 0;
    double first_x = 0, pitch = 0;
    size_t fibers = 0;
    if (flt_calib_get_frame_size(calib, &width, &height) != FLT_OK ||
        flt_calib_get_fiber_grid(calib, &first_x, &pitch, &fibers) != FLT_OK)
        abort();

    /* Extractor options from byte 1. */
    static const double windows[4] = {5, 7, 11, 31};
    flt_options *options = NULL;
    if (flt_options_create(&options) != FLT_OK)
        abort();
    const double window = windows[extract & 3];
    expect(flt_options_set(options, FLT_OPT_EXTRACT_SG_WINDOW, window));
    expect(flt_options_set(options, FLT_OPT_EXTRACT_MIN_PEAK, (extract >> 3) / 32.0));
    const double r0 = (height - 1) * (row0 / 255.0), r1 = (height - 1) * (row1 / 255.0);
    if (extract & 4) { /* fixed bands of 2 windows around each line */
        const double rows[2] = {r0, r1};
        const flt_option first[2] = {FLT_OPT_EXTRACT_LASER0_FIRST_ROW,
                                     FLT_OPT_EXTRACT_LASER1_FIRST_ROW};
        const flt_option count[2] = {FLT_OPT_EXTRACT_LASER0_ROWS, FLT_OPT_EXTRACT_LASER1_ROWS};
        for (int l = 0; l < 2; ++l) {
            const double start = fmax(0.0, floor(rows[l] - window));
            expect(flt_options_set(options, first[l], start));
            expect(flt_options_set(options, count[l], fmin(2 * window, height - start)));
        }
    }
    flt_extractor *ex = NULL;
    st = flt_extractor_create(calib, options, &ex);
    expect(st);
    flt_options_destroy(options);

    /* The frames: the simulator's through this calibration, or synthetic. */
    const int mode = (stages >> 1) & 3;
    static const flt_pixel_format formats[4] = {FLT_PIXEL_MONO8, FLT_PIXEL_MONO12, FLT_PIXEL_MONO16,
                                                FLT_PIXEL_MONO10};
    const flt_pixel_format format = formats[mode];
    const int bytes = format == FLT_PIXEL_MONO8 ? 1 : 2;
    const size_t pixels = (size_t)width * height;
    double *height_mm = malloc(fibers * sizeof(double)), *slope = malloc(fibers * sizeof(double));
    double *rows_s = malloc(2 * sizeof(double)), *z = malloc(2 * fibers * sizeof(double));
    double *heights = malloc(2 * fibers * sizeof(double));
    double *slopes = malloc(2 * fibers * sizeof(double));
    uint8_t *valid = malloc(fibers), *valids = malloc(2 * fibers), *flags = malloc(2 * fibers);
    int processed = 0;
    if (st == FLT_OK && pixels <= MAX_PIXELS) {
        void *frame = malloc(pixels * (size_t)bytes);
        flt_sim *sim = NULL;
        if (stages & 1) {
            flt_options *sim_options = NULL;
            if (flt_options_create(&sim_options) != FLT_OK)
                abort();
            expect(flt_options_set(sim_options, FLT_OPT_SIM_BIT_DEPTH, format));
            st = flt_sim_create(calib, sim_options, &sim);
            expect(st);
            flt_options_destroy(sim_options);
        }
        for (int f = 0; f < 2; ++f) {
            double encoder = encoder0 + 3.0 * f;
            if (sim) {
                st = flt_sim_next_frame(sim, frame, pixels * (size_t)bytes, (size_t)width * bytes,
                                        &encoder, 0, NULL, NULL, 0);
                expect(st);
                if (st != FLT_OK)
                    break;
            } else {
                const unsigned top = (1u << (format == FLT_PIXEL_MONO8 ? 8 : format)) - 1u;
                const unsigned junk = format == FLT_PIXEL_MONO12 ? 0xF000u : 0;
                synthetic_frame(frame, bytes, width, height, r0, r1, top, junk);
            }
            double s = NAN;
            st = flt_extractor_process(ex, frame, format, width, height, (size_t)width * bytes,
                                       encoder, fibers, &s, height_mm, slope, valid);
            expect(st);
            if (st != FLT_OK)
                continue;
            for (size_t k = 0; k < fibers; ++k) {
                const int finite = isfinite(height_mm[k]) && isfinite(slope[k]);
                const int nan = isnan(height_mm[k]) && isnan(slope[k]);
                if (valid[k] ? !finite : !nan) /* extractor.h */
                    abort();
            }
            if (!isfinite(s))
                abort();
            if (processed == 0 || s > rows_s[processed - 1]) {
                rows_s[processed] = s;
                memcpy(heights + processed * fibers, height_mm, fibers * sizeof(double));
                memcpy(slopes + processed * fibers, slope, fibers * sizeof(double));
                memcpy(valids + processed * fibers, valid, fibers);
                ++processed;
            }
        }
        flt_sim_destroy(sim);
        free(frame);
    }

    /* The rows into a reconstructor of the calibration's fibers. */
    if (processed > 0) {
        /* The smallest buffers (16 rows, no lag): up to 16384 fibers of the
         * defaults would take 1.3 GB, beyond the fuzzer's memory limit. */
        flt_options *recon_options = NULL;
        if (flt_options_create(&recon_options) != FLT_OK ||
            flt_options_set(recon_options, FLT_OPT_ROW_CAPACITY, 16) != FLT_OK ||
            flt_options_set(recon_options, FLT_OPT_LAG_KNOTS, 0) != FLT_OK)
            abort();
        flt_recon *recon = NULL;
        st = flt_recon_create(fibers, recon_options, &recon);
        expect(st);
        flt_options_destroy(recon_options);
        if (st == FLT_OK) {
            st = flt_recon_push(recon, (size_t)processed, fibers, rows_s, heights, slopes, valids);
            expect(st);
            if (st == FLT_OK) {
                expect(flt_recon_end_sheet(recon));
                size_t got = 0;
                expect(flt_recon_pull(recon, 2, fibers, rows_s, z, flags, &got));
                for (size_t i = 0; i < got * fibers; ++i)
                    if (isnan(z[i]) && !(flags[i] & FLT_FLAG_NO_DATA)) /* recon.h */
                        abort();
            }
            flt_recon_destroy(recon);
        }
    }
    flt_options *flat_options = NULL; /* 16 rows, for the same reason */
    if (flt_options_create(&flat_options) != FLT_OK ||
        flt_options_set(flat_options, FLT_OPT_FLAT_ROW_CAPACITY, 16) != FLT_OK)
        abort();
    flt_flatness *flatness = NULL;
    st = flt_flatness_create_from_calib(calib, flat_options, &flatness);
    expect(st);
    flt_flatness_destroy(flatness);
    flt_options_destroy(flat_options);

    free(height_mm), free(slope), free(rows_s), free(z), free(heights), free(slopes);
    free(valid), free(valids), free(flags);
    flt_extractor_destroy(ex);
    flt_calib_destroy(calib);
    return 0;
}
