// SPDX-License-Identifier: Apache-2.0
/*
 * The loop: simulated sensor -> simulated USB3 Vision camera (leader,
 * payload in USB transfers, encoder chunk, trailer) -> flt_source ->
 * extractor -> reconstructor gives the same profile rows, bit for bit, as
 * the direct path simulator -> extractor -> reconstructor for the same
 * frames. Both simulators have the same seed, so the frames are the same
 * bytes; any difference would be a byte lost, reordered or mislabelled on
 * the way through the camera path (tolerance 0).
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
#include "flatline/source.h"
#include "flatline/testing.h"

#define ok(call)                                           \
  do {                                                     \
    flt_status st_ = (call);                               \
    if (st_ != FLT_OK)                                     \
      fail_msg("%s: %s", #call, flt_last_error_message()); \
  } while (0)

enum { FRAMES = 120, FIBERS = 201, WIDTH = 2048, ROWS = 256 };

/* The bus as the transport flt_source_open_u3v() and
 * flt_camera_list_create() take (NULL for a NULL bus). */
static flt_usb_transport *usb(flt_u3v_sim *bus) {
    flt_usb_transport *t = NULL;
    if (bus && flt_u3v_sim_transport(bus, &t) != FLT_OK)
        abort();
    return t;
}

static flt_sim *make_sim(const flt_calib *calib) {
    flt_sim *sim = NULL;
    ok(flt_sim_create(calib, NULL, &sim));
    ok(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 6.0, 1800.0));
    ok(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, 4.0, 1200.0));
    return sim;
}

static void test_camera_path_gives_the_direct_path_rows(void **state) {
    (void)state;
    flt_calib *calib = NULL;
    /* rows 892..1147 of the reference sensor hold both lines */
    ok(flt_calib_create_reference(892, ROWS, -1000.0, 10.0, FIBERS, &calib));
    flt_sim *direct_sim = make_sim(calib), *camera_sim = make_sim(calib);

    /* camera path: the encoder count travels as a chunk, 0.5 mm per count
     * (exact in binary, like the simulator's 3 mm frame spacing) */
    flt_u3v_sim *bus = NULL;
    ok(flt_u3v_sim_create(&bus));
    ok(flt_u3v_sim_add_camera(bus, "Flatline", "Loop", "LOOP-1", 64, 64, FLT_PIXEL_MONO8, NULL));
    ok(flt_u3v_sim_set_frames(bus, 0, camera_sim));
    ok(flt_u3v_sim_set(bus, 0, FLT_U3V_SIM_ENCODER_CHUNK, 1));
    ok(flt_u3v_sim_set(bus, 0, FLT_U3V_SIM_ENCODER_MM_PER_COUNT_UM, 500));
    flt_options *o = NULL;
    ok(flt_options_create(&o));
    ok(flt_options_set(o, FLT_OPT_SOURCE_ENCODER_MODE, FLT_ENCODER_CHUNK));
    ok(flt_options_set(o, FLT_OPT_SOURCE_ENCODER_MM_PER_COUNT, 0.5));
    flt_source *src = NULL;
    ok(flt_source_open_u3v(usb(bus), "LOOP-1", o, &src));
    ok(flt_source_start(src));

    flt_extractor *ex_direct = NULL, *ex_camera = NULL;
    ok(flt_extractor_create(calib, NULL, &ex_direct));
    ok(flt_extractor_create(calib, NULL, &ex_camera));
    flt_recon *rc_direct = NULL, *rc_camera = NULL;
    ok(flt_recon_create(FIBERS, NULL, &rc_direct));
    ok(flt_recon_create(FIBERS, NULL, &rc_camera));

    uint8_t *frame = malloc((size_t)WIDTH * ROWS);
    double h1[FIBERS], g1[FIBERS], h2[FIBERS], g2[FIBERS];
    uint8_t v1[FIBERS], v2[FIBERS];
    size_t valid = 0;
    for (int f = 0; f < FRAMES; ++f) {
        double e1 = 0, s1 = 0, s2 = 0;
        ok(flt_sim_next_frame(direct_sim, frame, (size_t)WIDTH * ROWS, WIDTH, &e1, 0, NULL, NULL,
                              0));
        ok(flt_extractor_process(ex_direct, frame, FLT_PIXEL_MONO8, WIDTH, ROWS, WIDTH, e1, FIBERS,
                                 &s1, h1, g1, v1));
        const flt_frame *cf = NULL;
        ok(flt_source_next(src, 1000, &cf));
        const void *pixels;
        uint32_t w, h;
        size_t stride;
        flt_pixel_format format;
        double e2 = 0;
        ok(flt_frame_info(cf, &pixels, &w, &h, &stride, &format, NULL, NULL, &e2));
        assert_int_equal(w, WIDTH);
        assert_int_equal(h, ROWS);
        assert_true(e2 == e1); /* 0.5 mm x (6 f counts) == 3 f mm */
        assert_memory_equal(pixels, frame, (size_t)WIDTH * ROWS);
        ok(flt_extractor_process(ex_camera, pixels, format, w, h, stride, e2, FIBERS, &s2, h2, g2,
                                 v2));
        assert_true(s1 == s2);
        for (int k = 0; k < FIBERS; ++k) {
            assert_int_equal(v1[k], v2[k]);
            if (v1[k]) {
                ++valid;
                assert_true(h1[k] == h2[k] && g1[k] == g2[k]);
            }
        }
        ok(flt_recon_push(rc_direct, 1, FIBERS, &s1, h1, g1, v1));
        ok(flt_recon_push(rc_camera, 1, FIBERS, &s2, h2, g2, v2));
    }
    /* the comparison is not vacuous: most fibers carry a profile */
    assert_true(valid > (size_t)(0.9 * FRAMES * FIBERS));
    ok(flt_recon_end_sheet(rc_direct));
    ok(flt_recon_end_sheet(rc_camera));
    size_t n1 = 0, n2 = 0;
    ok(flt_recon_ready(rc_direct, &n1));
    ok(flt_recon_ready(rc_camera, &n2));
    assert_int_equal(n1, FRAMES);
    assert_int_equal(n2, FRAMES);
    double *sa = malloc(sizeof(double) * FRAMES), *sb = malloc(sizeof(double) * FRAMES);
    double *za = malloc(sizeof(double) * FRAMES * FIBERS);
    double *zb = malloc(sizeof(double) * FRAMES * FIBERS);
    ok(flt_recon_pull(rc_direct, FRAMES, FIBERS, sa, za, NULL, &n1));
    ok(flt_recon_pull(rc_camera, FRAMES, FIBERS, sb, zb, NULL, &n2));
    assert_int_equal(n1, n2);
    assert_memory_equal(sa, sb, sizeof(double) * n1);
    assert_memory_equal(za, zb, sizeof(double) * n1 * FIBERS);
    uint64_t dropped = 1;
    ok(flt_source_count(src, FLT_COUNT_DROPPED, &dropped));
    assert_int_equal(dropped, 0);

    free(sa);
    free(sb);
    free(za);
    free(zb);
    free(frame);
    flt_recon_destroy(rc_direct);
    flt_recon_destroy(rc_camera);
    flt_extractor_destroy(ex_direct);
    flt_extractor_destroy(ex_camera);
    flt_source_destroy(src);
    flt_options_destroy(o);
    flt_u3v_sim_destroy(bus);
    flt_sim_destroy(direct_sim);
    flt_sim_destroy(camera_sim);
    flt_calib_destroy(calib);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_camera_path_gives_the_direct_path_rows),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
