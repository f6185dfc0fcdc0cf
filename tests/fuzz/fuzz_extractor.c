// SPDX-License-Identifier: Apache-2.0
/* libFuzzer harness: the frame-to-profile extractor fed random frames and
 * options. A frame rendered by the simulator (a window of the reference
 * sensor where both lines lie) is patched with the input's bytes (runs
 * of garbage, saturated glints, dark stripes), in Mono8 or as 12/16-bit
 * words; the options (bands, Savitzky-Golay window and order, peak limits)
 * and the encoder position (NaN, Inf, huge) come from the input too. Every
 * call must return a status with a message on failure, never crash, and a
 * valid fiber must have finite height and slope. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "flatline/flatline.h"
#include "fuzz_input.h"

/* The reference sensor cut to a 512 x 120 px window (columns 768..1279,
 * rows 960..1079) around the image centre, where both lines lie: the
 * extractor tabulates its maps per column at create time, and a narrow
 * frame makes that (and the fuzzing) 4x faster. 21 fibers 20 mm apart
 * across the centre of the strip. */
enum { ROI_FIRST = 960, ROWS = 120, COL_FIRST = 768, WIDTH = 512, FIBERS = 21 };

static flt_calib *g_calib;
static uint8_t g_frame8[WIDTH * ROWS];

static void init(void) {
    flt_calib *full = NULL, *c = NULL;
    flt_sim *sim = NULL;
    double cam[4], dist[8], h[2][9], offset[2], scale, x0, pitch;
    size_t count;
    if (flt_calib_create_reference(ROI_FIRST, ROWS, -200.0, 20.0, FIBERS, &full) ||
        flt_calib_get_intrinsics(full, cam, FLT_CALIB_CAMERA_VALUES, dist,
                                 FLT_CALIB_DISTORTION_COEFFS) ||
        flt_calib_get_encoder_scale(full, &scale) ||
        flt_calib_get_fiber_grid(full, &x0, &pitch, &count))
        abort();
    /* Moving the window right by COL_FIRST px moves the principal point
     * left, and each homography takes u + COL_FIRST: H' = H T. */
    cam[2] -= COL_FIRST;
    if (flt_calib_create(&c) || flt_calib_set_frame_size(c, WIDTH, ROWS) ||
        flt_calib_set_intrinsics(c, cam, FLT_CALIB_CAMERA_VALUES, dist,
                                 FLT_CALIB_DISTORTION_COEFFS))
        abort();
    for (unsigned l = 0; l < 2; ++l) {
        if (flt_calib_get_homography(full, l, h[l], FLT_CALIB_HOMOGRAPHY_ENTRIES) ||
            flt_calib_get_laser_offset(full, l, &offset[l]))
            abort();
        for (int r = 0; r < 3; ++r)
            h[l][3 * r + 2] += COL_FIRST * h[l][3 * r];
        if (flt_calib_set_homography(c, l, h[l], FLT_CALIB_HOMOGRAPHY_ENTRIES) ||
            flt_calib_set_laser_offset(c, l, offset[l]))
            abort();
    }
    if (flt_calib_set_encoder_scale(c, scale) || flt_calib_set_fiber_grid(c, x0, pitch, count) ||
        flt_calib_finish(c))
        abort();
    flt_calib_destroy(full);
    g_calib = c;
    if (flt_sim_create(g_calib, NULL, &sim) ||
        flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 5.0, 700.0) ||
        flt_sim_next_frame(sim, g_frame8, sizeof g_frame8, WIDTH, NULL, 0, NULL, NULL, 0))
        abort();
    flt_sim_destroy(sim);
}

static void expect(flt_status st) {
    if (st != FLT_OK && flt_last_error_message()[0] == 0)
        abort();
    if (st == FLT_ERR_INTERNAL)
        abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static uint16_t frame16[WIDTH * ROWS];
    static uint8_t frame8[WIDTH * ROWS];
    if (!g_calib)
        init();
    fuzz_input in = {data, size};

    flt_options *opt = NULL;
    if (flt_options_create(&opt) != FLT_OK)
        abort();
    static const flt_option keys[] = {FLT_OPT_EXTRACT_LASER0_FIRST_ROW, FLT_OPT_EXTRACT_LASER0_ROWS,
                                      FLT_OPT_EXTRACT_LASER1_FIRST_ROW, FLT_OPT_EXTRACT_LASER1_ROWS,
                                      FLT_OPT_EXTRACT_SG_WINDOW,        FLT_OPT_EXTRACT_SG_ORDER,
                                      FLT_OPT_EXTRACT_MIN_PEAK,         FLT_OPT_EXTRACT_MAX_WIDTH};
    const int n_opts = fuzz_u8(&in) % 6;
    for (int i = 0; i < n_opts; ++i) {
        const int which = fuzz_u8(&in) % 8;
        const double v =
            which < 6 ? (double)(fuzz_u8(&in) % (which < 4 ? 140 : 35)) : fuzz_double(&in, 1.5);
        expect(flt_options_set(opt, keys[which], v));
    }
    flt_extractor *ex = NULL;
    flt_status st = flt_extractor_create(g_calib, opt, &ex);
    expect(st);
    flt_options_destroy(opt);
    if (st != FLT_OK)
        return 0;

    const int frames = 1 + fuzz_u8(&in) % 3;
    for (int f = 0; f < frames; ++f) {
        const uint8_t mode = fuzz_u8(&in);
        const int bits = (mode & 3) == 0 ? 12 : (mode & 3) == 1 ? 16 : 8;
        memcpy(frame8, g_frame8, sizeof frame8);
        /* Patches: (offset, length, kind, value). */
        const int patches = fuzz_u8(&in) % 16;
        for (int p = 0; p < patches && in.n > 0; ++p) {
            const uint32_t at = fuzz_u32(&in) % (WIDTH * ROWS);
            uint32_t len = 1 + fuzz_u8(&in) * (1u + fuzz_u8(&in) % 64);
            if (len > WIDTH * ROWS - at)
                len = WIDTH * ROWS - at;
            const uint8_t kind = fuzz_u8(&in), value = fuzz_u8(&in);
            for (uint32_t i = 0; i < len; ++i)
                frame8[at + i] = kind & 1 ? value : (uint8_t)(fuzz_u8(&in) ^ frame8[at + i]);
        }
        const double encoder = mode & 4 ? fuzz_double(&in, 1e6) : 3.0 * f;
        double s, h[FIBERS], k[FIBERS];
        uint8_t v[FIBERS];
        const void *frame = frame8;
        size_t stride = WIDTH;
        flt_pixel_format format = FLT_PIXEL_MONO8;
        if (bits != 8) {
            /* 16-bit words; the high bits beyond the format may be garbage. */
            const uint16_t junk =
                mode & 8 ? (uint16_t)(0xF000u & ((unsigned)fuzz_u8(&in) << 8)) : 0;
            for (size_t i = 0; i < sizeof frame8; ++i)
                frame16[i] = (uint16_t)((frame8[i] << (bits - 8)) | (bits == 12 ? junk : 0));
            frame = frame16;
            stride = 2 * WIDTH;
            format = bits == 12 ? FLT_PIXEL_MONO12 : FLT_PIXEL_MONO16;
        }
        st = flt_extractor_process(ex, frame, format, WIDTH, ROWS, stride, encoder, FIBERS, &s, h,
                                   k, v);
        expect(st);
        if (st == FLT_OK)
            for (int i = 0; i < FIBERS; ++i)
                if (v[i] && (!isfinite(h[i]) || !isfinite(k[i])))
                    abort();
        uint32_t first, rows;
        expect(flt_extractor_band(ex, 0, &first, &rows));
    }
    flt_extractor_destroy(ex);
    return 0;
}
