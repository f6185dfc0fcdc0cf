/* SPDX-License-Identifier: Apache-2.0 */
/* README.md's gauge: the reference sensor, default options and one frame
 * rendered by the simulated line. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <flatline/flatline.h>

#define CHECK(call)                                      \
  do {                                                   \
    if ((call) != FLT_OK) {                              \
      fprintf(stderr, "%s\n", flt_last_error_message()); \
      exit(1);                                           \
    }                                                    \
  } while (0)

int main(void) {
    flt_calib *calib = NULL;
    CHECK(flt_calib_create_reference(0, 2048, -1000.0, 2.0, 1001, &calib));
    flt_options *opts = NULL;
    CHECK(flt_options_create(&opts));
    flt_sim *sim = NULL;
    CHECK(flt_sim_create(calib, opts, &sim));
    uint32_t width = 0, height = 0;
    CHECK(flt_sim_frame_size(sim, &width, &height));
    size_t stride = width;
    uint8_t *pixels = malloc(stride * height);
    double encoder_mm = 0;
    if (!pixels)
        return 1;
    CHECK(flt_sim_next_frame(sim, pixels, stride * height, stride, &encoder_mm, 0, NULL, NULL, 0));
    static double zone_i_units[1024];
    /* SNIPPET */
    free(pixels);
    flt_sim_destroy(sim);
    flt_options_destroy(opts);
    flt_calib_destroy(calib);
    return 0;
}
