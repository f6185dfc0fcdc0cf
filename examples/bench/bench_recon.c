// SPDX-License-Identifier: Apache-2.0
/*
 * Benchmark of the Hermite reconstructor on the reference's production sheet:
 * 6000 mm x 2300 mm at 3 mm x 2 mm, i.e. 2000 rows x 1150 fibers
 * (the reference article needed 350 ms for it).
 *
 * Prints, single-threaded, wall-clock time and the CPU time of this thread
 * (which other programs on a loaded machine do not inflate):
 *   - batch: milliseconds per sheet with flt_reconstruct: the first call
 *     (which sets up the working memory flt_reconstruct keeps for the next
 *     call of the same size), then `calls` calls in a loop (median and
 *     mean), on the noise-free sheet; then every mode (plain, rigid_motion, robust)
 *     on the same sheet with the noise of the article's third experiment
 *     (vibration, eccentricity, peak noise, shear ringing), with each mode's
 *     largest error after removing one constant (a sanity check, not the
 *     accuracy study: examples/python/compare_filters.py is);
 *   - streaming: microseconds per pushed row, amortised over a long strip
 *     pushed one row at a time and pulled as rows finish (default options;
 *     then rigid_motion + robust with experiment 3's noise).
 *
 * Usage: bench_recon [runs] [calls]   (defaults 15 and 100)
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <flatline/flatline.h>

#define ROWS   2000
#define FIBERS 1150
#define DX     3.0
#define PITCH  2.0
#define LASER  100.0

static double now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double cpu_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The reference surface: 12 mm waves, 1800 mm along, 1500 mm across. */
static double surface(double x, double s) {
    const double pi = 3.14159265358979323846;
    return 12.0 * sin(2 * pi * s / 1800.0) * cos(2 * pi * x / 1500.0);
}

/* A small deterministic generator (xorshift64*) and Box-Muller normals, so
 * that every run measures the same noisy sheet. */
static unsigned long long g_state = 0x9E3779B97F4A7C15ull;
static double uniform01(void) {
    g_state ^= g_state >> 12;
    g_state ^= g_state << 25;
    g_state ^= g_state >> 27;
    return ((double)((g_state * 0x2545F4914F6CDD1Dull) >> 11) + 0.5) / 9007199254740992.0;
}
static double normal(double sigma) {
    const double pi = 3.14159265358979323846;
    return sigma * sqrt(-2.0 * log(uniform01())) * cos(2.0 * pi * uniform01());
}

/* The shear station's ringing at material position x (mm): a damped sine
 * (50 mm envelope, decay 0.07/mm, period 10 mm) after every cut, a cut
 * every 3000 mm from 0 (the article's third experiment). */
static double shear(double x) {
    const double pi = 3.14159265358979323846;
    if (x < 0)
        return 0.0;
    double u = fmod(x, 3000.0);
    return 50.0 * exp(-0.07 * u) * sin(2 * pi * u / 10.0);
}

/* Experiment 3's noise in its physical form on the rows: per frame a rigid
 * heave (2.5 mm) and the roll's eccentricity (0.5 mm sine, 50 mm period)
 * on both lasers and every fiber; per laser and fiber 0.05 mm peak noise;
 * the shear ringing where each laser looks. What robust mode is for: its
 * cost depends on how many samples it must take out. */
static void add_noise(size_t rows, const double *s, double *h, double *g) {
    const double pi = 3.14159265358979323846;
    for (size_t r = 0; r < rows; ++r) {
        double common = normal(2.5) + 0.5 * sin(2 * pi * s[r] / 50.0);
        double sa = shear(s[r] - 0.5 * LASER), sb = shear(s[r] + 0.5 * LASER);
        for (size_t k = 0; k < FIBERS; ++k) {
            double na = common + sa + normal(0.05), nb = common + sb + normal(0.05);
            h[r * FIBERS + k] += 0.5 * (na + nb);
            g[r * FIBERS + k] += (nb - na) / LASER;
        }
    }
}

static void measure_rows(size_t r0, size_t rows, double *s, double *h, double *g) {
    for (size_t r = 0; r < rows; ++r) {
        s[r] = (double)(r0 + r) * DX;
        for (size_t k = 0; k < FIBERS; ++k) {
            double x = ((double)k - 0.5 * (FIBERS - 1)) * PITCH;
            double a = surface(x, s[r] - 0.5 * LASER), b = surface(x, s[r] + 0.5 * LASER);
            h[r * FIBERS + k] = 0.5 * (a + b);
            g[r * FIBERS + k] = (b - a) / LASER;
        }
    }
}

static int check(flt_status st, const char *what) {
    if (st != FLT_OK) {
        fprintf(stderr, "bench_recon: %s failed: %s: %s\n", what, flt_status_string(st),
                flt_last_error_message());
        exit(1);
    }
    return 0;
}

int main(int argc, char **argv) {
    int runs = argc > 1 ? atoi(argv[1]) : 15;
    if (runs < 1)
        runs = 1;
    size_t n = (size_t)ROWS * FIBERS;
    double *s = malloc(ROWS * sizeof(double));
    double *h = malloc(n * sizeof(double)), *g = malloc(n * sizeof(double));
    double *z = malloc(n * sizeof(double));
    uint8_t *flags = malloc(n);
    if (!s || !h || !g || !z || !flags)
        return 1;
    measure_rows(0, ROWS, s, h, g);

    printf("libflatline %s reconstructor benchmark: %d rows x %d fibers "
           "(%.0f mm x %.0f mm at %.0f mm x %.0f mm), one thread\n",
           flt_version_string(), ROWS, FIBERS, ROWS * DX, FIBERS * PITCH, DX, PITCH);

    /* Batch: the first call, then calls in a loop. */
    int calls = argc > 2 ? atoi(argv[2]) : 100;
    if (calls < 1)
        calls = 1;
    double t0 = now_s(), c0 = cpu_s();
    check(flt_reconstruct(NULL, ROWS, FIBERS, s, h, g, NULL, z, flags), "flt_reconstruct");
    double first_wall = now_s() - t0, first_cpu = cpu_s() - c0;
    double *t_batch = malloc((size_t)(runs > calls ? runs : calls) * sizeof(double));
    double sum_wall = 0, sum_cpu = 0;
    for (int i = 0; i < calls; ++i) {
        t0 = now_s();
        c0 = cpu_s();
        check(flt_reconstruct(NULL, ROWS, FIBERS, s, h, g, NULL, z, flags), "flt_reconstruct");
        t_batch[i] = now_s() - t0;
        sum_wall += t_batch[i];
        sum_cpu += cpu_s() - c0;
        if ((i + 1) % 10 == 0)
            fprintf(stderr, "\rbatch call %d/%d", i + 1, calls);
    }
    fprintf(stderr, "\n");
    qsort(t_batch, (size_t)calls, sizeof(double), cmp_double);
    double worst = 0;
    for (size_t r = 0; r < ROWS; ++r)
        for (size_t k = 0; k < FIBERS; ++k) {
            double x = ((double)k - 0.5 * (FIBERS - 1)) * PITCH;
            worst = fmax(worst, fabs(z[r * FIBERS + k] - surface(x, s[r])));
        }
    printf("batch:     first call %.2f ms (CPU %.2f ms); then %d calls: median %.2f ms, mean "
           "%.2f ms, CPU %.2f ms per call   [goal <= 7 ms; reference 350 ms]   max error "
           "%.2g um\n",
           1e3 * first_wall, 1e3 * first_cpu, calls, 1e3 * t_batch[calls / 2],
           1e3 * sum_wall / calls, 1e3 * sum_cpu / calls, worst * 1e3);

    /* The other modes, on the same sheet with experiment 3's noise (robust
     * mode's cost depends on the outliers it meets): rigid_motion (the line
     * across the strip split off each row, two one-value channels), robust
     * Huber (a plain pass and two reweighted ones over the whole sheet),
     * both together (the line channels take eight reweighted passes), and
     * Tukey. */
    add_noise(ROWS, s, h, g);
    const struct {
        const char *name, *goal;
        int rigid;
        flt_robust robust;
    } modes[] = {
        {"plain", "", 0, FLT_ROBUST_NONE},
        {"rigid_motion", "", 1, FLT_ROBUST_NONE},
        {"robust (Huber)", "   [goal <= 60 ms]", 0, FLT_ROBUST_HUBER},
        {"rigid_motion + robust (Huber)", "   [goal <= 60 ms]", 1, FLT_ROBUST_HUBER},
        {"rigid_motion + robust (Tukey)", "", 1, FLT_ROBUST_TUKEY},
    };
    printf("experiment 3 noise (2.5 mm heave, 0.5 mm eccentricity, 0.05 mm peak noise, "
           "shear ringing every 3 m):\n");
    for (size_t m = 0; m < sizeof modes / sizeof modes[0]; ++m) {
        flt_options *o = NULL;
        check(flt_options_create(&o), "flt_options_create");
        check(flt_options_set(o, FLT_OPT_RIGID_MOTION, modes[m].rigid), "flt_options_set");
        check(flt_options_set(o, FLT_OPT_ROBUST, modes[m].robust), "flt_options_set");
        double cpu = 0;
        for (int i = 0; i < runs; ++i) {
            t0 = now_s();
            c0 = cpu_s();
            check(flt_reconstruct(o, ROWS, FIBERS, s, h, g, NULL, z, flags), "flt_reconstruct");
            t_batch[i] = now_s() - t0;
            cpu += cpu_s() - c0;
        }
        qsort(t_batch, (size_t)runs, sizeof(double), cmp_double);
        double mean = 0, worst_mode = 0;
        for (size_t r = 0; r < ROWS; ++r)
            for (size_t k = 0; k < FIBERS; ++k) {
                double x = ((double)k - 0.5 * (FIBERS - 1)) * PITCH;
                mean += z[r * FIBERS + k] - surface(x, s[r]);
            }
        mean /= (double)n;
        for (size_t r = 0; r < ROWS; ++r)
            for (size_t k = 0; k < FIBERS; ++k) {
                double x = ((double)k - 0.5 * (FIBERS - 1)) * PITCH;
                worst_mode = fmax(worst_mode, fabs(z[r * FIBERS + k] - surface(x, s[r]) - mean));
            }
        printf("  batch, %s: %.2f ms per sheet (median of %d; min %.2f ms; CPU %.2f ms)%s   "
               "max error %.3f mm\n",
               modes[m].name, 1e3 * t_batch[runs / 2], runs, 1e3 * t_batch[0], 1e3 * cpu / runs,
               modes[m].goal, worst_mode);
        flt_options_destroy(o);
    }

    /* Streaming: a 5-sheet strip (30 m), one row per push, pulled as it goes,
     * end_sheet every 2000 rows. Row data is prepared up front. Default
     * options on the noise-free strip (goal: <= 5 us per row), then
     * rigid_motion + robust on the strip with experiment 3's noise. */
    double *s_out = malloc(ROWS * sizeof(double));
    for (int mode = 0; mode < 2; ++mode) {
        flt_options *o = NULL;
        check(flt_options_create(&o), "flt_options_create");
        check(flt_options_set(o, FLT_OPT_RIGID_MOTION, mode), "flt_options_set");
        check(flt_options_set(o, FLT_OPT_ROBUST, mode ? FLT_ROBUST_HUBER : FLT_ROBUST_NONE),
              "flt_options_set");
        flt_recon *rc = NULL;
        check(flt_recon_create(FIBERS, o, &rc), "flt_recon_create");
        flt_options_destroy(o);
        const int sheets = 5;
        double total = 0, total_cpu = 0;
        size_t pushed = 0, pulled = 0;
        for (int sh = 0; sh < sheets; ++sh) {
            measure_rows((size_t)sh * ROWS, ROWS, s, h, g);
            if (mode)
                add_noise(ROWS, s, h, g);
            t0 = now_s();
            c0 = cpu_s();
            for (size_t r = 0; r < ROWS; ++r) {
                size_t got = 0;
                check(flt_recon_push(rc, 1, FIBERS, &s[r], h + r * FIBERS, g + r * FIBERS, NULL),
                      "flt_recon_push");
                check(flt_recon_pull(rc, ROWS, FIBERS, s_out, z, flags, &got), "flt_recon_pull");
                pulled += got;
            }
            check(flt_recon_end_sheet(rc), "flt_recon_end_sheet");
            size_t got = 0;
            check(flt_recon_pull(rc, ROWS, FIBERS, s_out, z, flags, &got), "flt_recon_pull");
            pulled += got;
            total += now_s() - t0;
            total_cpu += cpu_s() - c0;
            pushed += ROWS;
            fprintf(stderr, "\rstreaming sheet %d/%d", sh + 1, sheets);
        }
        fprintf(stderr, "\n");
        if (mode == 0)
            printf("streaming: %.2f us per pushed row, CPU %.2f us (%zu rows, %zu pulled, "
                   "end_sheet every %d rows)   [goal <= 5 us]\n",
                   1e6 * total / (double)pushed, 1e6 * total_cpu / (double)pushed, pushed, pulled,
                   ROWS);
        else
            printf("streaming, rigid_motion + robust, experiment 3 noise: %.2f us per pushed "
                   "row, CPU %.2f us   [goal <= 40 us]\n",
                   1e6 * total / (double)pushed, 1e6 * total_cpu / (double)pushed);
        flt_recon_destroy(rc);
    }
    printf("line speed: one row per %.0f us at 120 m/min with 3 mm rows\n", 1e6 * 0.003 / 2.0);
    free(s);
    free(h);
    free(g);
    free(z);
    free(flags);
    free(s_out);
    free(t_batch);
    return 0;
}
