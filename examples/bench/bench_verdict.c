// SPDX-License-Identifier: Apache-2.0
/*
 * What judging a sheet costs: the gauge judges every finished sheet against
 * its rules on its evaluation thread (flatline/gauge.h, "Verdicts and coil
 * statistics"), with the same code as flt_verdict_evaluate. This program
 * times that code on a sheet the size bench_gauge's line makes: 3 m of
 * strip at a row every mm (3000 rows) and 1150 fibers every 2 mm, a centre
 * buckle of 4 mm amplitude and 800 mm period with 0.05 mm of measurement
 * noise (noise defeats the straightedge's pruning of flat stretches: the
 * worst case), and prints the CPU time of one rule per direction: a 1 m
 * straightedge along every fiber (goal <= 20 ms) and across every row
 * (goal <= 50 ms), then a 2 m one along and a flatness-measure rule; the
 * median and the best of 9 evaluations each, and the median's share of
 * the 1.5 s a 3 m sheet takes at 120 m/min. One thread: pin it to a core.
 *
 *   taskset -c 1 build/release/examples/bench/bench_verdict
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "flatline/flatline.h"

#define CHECK(call)                                                        \
  do {                                                                     \
    if ((call) != FLT_OK) {                                                \
      fprintf(stderr, "%s failed: %s\n", #call, flt_last_error_message()); \
      exit(1);                                                             \
    }                                                                      \
  } while (0)

enum { ROWS = 3000, FIBERS = 1150, RUNS = 9 };
static const double SHEET_SECONDS = 1.5; /* 3 m at 120 m/min */

static int by_value(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double cpu_now(void) {
    return (double)clock() / (double)CLOCKS_PER_SEC;
}

/* One rule of `measure` ("straightedge_along", ...) and its length (0: none). */
static flt_rules *one_rule(const char *measure, double length_mm) {
    char text[512], length[64] = "";
    if (length_mm > 0)
        snprintf(length, sizeof length, "\"length_mm\": %d, ", (int)length_mm);
    snprintf(text, sizeof text,
             "{ \"format\": \"flatline-tolerances\", \"version\": 1, \"name\": \"bench\", "
             "\"rules\": [ { \"name\": \"r\", \"measure\": \"%s\", %s\"bands\": [ "
             "{ \"thickness_mm\": [0, 50], \"width_mm\": [0, 5000], \"limit\": 3 } ] } ] }",
             measure, length);
    flt_rules *r = NULL;
    CHECK(flt_rules_load_text(text, strlen(text), &r));
    return r;
}

int main(void) {
    double *s = malloc(sizeof(double) * ROWS), *x = malloc(sizeof(double) * FIBERS);
    double *z = malloc(sizeof(double) * ROWS * FIBERS);
    if (!s || !x || !z)
        return 1;
    unsigned long long state = 1;
    for (int r = 0; r < ROWS; ++r)
        s[r] = r;
    for (int k = 0; k < FIBERS; ++k)
        x[k] = -1150.0 + 2.0 * k;
    for (int r = 0; r < ROWS; ++r)
        for (int k = 0; k < FIBERS; ++k) {
            /* Uniform noise of standard deviation 0.05 mm (a 64-bit LCG). */
            state = state * 6364136223846793005ULL + 1442695040888963407ULL;
            const double u = (double)(state >> 11) / 9007199254740992.0 - 0.5;
            z[(size_t)r * FIBERS + k] = 4.0 * sin(2 * M_PI * s[r] / 800.0) *
                                            cos(M_PI * x[k] / 2300.0) * cos(M_PI * x[k] / 2300.0) +
                                        0.05 * sqrt(12.0) * u;
        }
    const struct {
        const char *measure, *what;
        double length, goal_ms; /* goal 0: none */
    } rules[] = {{"straightedge_along", "1 m along every fiber", 1000, 20},
                 {"straightedge_across", "1 m across every row", 1000, 50},
                 {"straightedge_along", "2 m along every fiber", 2000, 0},
                 {"zone_i_units", "zone I-Units (given)", 0, 0}};
    printf("bench_verdict: one sheet of %d rows x %d fibers (3 m at 1 mm, 2 mm pitch), "
           "CPU time per rule, median (best) of %d\n",
           ROWS, FIBERS, RUNS);
    double total = 0;
    for (size_t i = 0; i < sizeof rules / sizeof *rules; ++i) {
        flt_rules *r = one_rule(rules[i].measure, rules[i].length);
        flt_verdict *v = NULL;
        CHECK(flt_verdict_create(r, &v));
        CHECK(flt_verdict_set_measure(v, FLT_MEASURE_ZONE_I_UNITS, 5.0, 0.0, 1500.0));
        double t[RUNS], worst = 0;
        for (int run = 0; run < RUNS; ++run) {
            const double t0 = cpu_now();
            CHECK(flt_verdict_evaluate(v, 4.0, 2300.0, ROWS, FIBERS, s, x, z, NULL));
            t[run] = cpu_now() - t0;
        }
        qsort(t, RUNS, sizeof *t, by_value);
        const double median = t[RUNS / 2];
        CHECK(flt_verdict_get(v, 0, FLT_VERDICT_WORST, &worst));
        total += median;
        char goal[32] = "";
        if (rules[i].goal_ms > 0)
            snprintf(goal, sizeof goal, "goal <= %.0f ms", rules[i].goal_ms);
        printf("  %-24s %7.1f ms (%6.1f)  %4.1f%% of a sheet's time  worst %6.3f mm  %s\n",
               rules[i].what, 1e3 * median, 1e3 * t[0], 100.0 * median / SHEET_SECONDS, worst,
               goal);
        flt_verdict_destroy(v);
        flt_rules_destroy(r);
    }
    printf("  %-24s %7.1f ms           %4.1f%%\n", "all four", 1e3 * total,
           100.0 * total / SHEET_SECONDS);
    free(s);
    free(x);
    free(z);
    return 0;
}
