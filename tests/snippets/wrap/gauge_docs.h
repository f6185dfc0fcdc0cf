/* SPDX-License-Identifier: Apache-2.0 */
/* What docs/gauge.md's blocks take as given: CHECK (README.md's), a gauge
 * on the reference sensor, and sheets of a flat strip pushed as rows. */
#include <math.h>
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

enum { FIBERS = 1001 };

static inline flt_gauge *new_gauge(flt_calib **calib) {
    CHECK(flt_calib_create_reference(0, 2048, -1000.0, 2.0, FIBERS, calib));
    flt_gauge *gauge = NULL;
    CHECK(flt_gauge_create(*calib, NULL, &gauge));
    return gauge;
}

/* 4 m of a flat strip, a row every 2 mm, cut at 3 m; then the flush. */
static inline void push_flat_strip(flt_gauge *gauge) {
    static double height[FIBERS], slope[FIBERS];
    CHECK(flt_gauge_cut(gauge, 3000.0));
    for (int i = 0; i < 2000; ++i)
        CHECK(flt_gauge_push_row(gauge, 2.0 * i, FIBERS, height, slope, NULL));
    CHECK(flt_gauge_flush(gauge));
}

/* The rule file the docs load: the coil report's example rules. */
static inline void copy_example_rules(const char *to) {
    const char *source = getenv("FLT_SOURCE_DIR");
    char path[4096];
    if (!source || snprintf(path, sizeof path, "%s/tools/coil_report/example_rules.json", source) >=
                       (int)sizeof path)
        exit(1);
    FILE *in = fopen(path, "rb"), *out = fopen(to, "wb");
    if (!in || !out)
        exit(1);
    int c;
    while ((c = fgetc(in)) != EOF)
        fputc(c, out);
    fclose(in);
    fclose(out);
}
