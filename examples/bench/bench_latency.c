// SPDX-License-Identifier: Apache-2.0
/*
 * What a shorter streaming latency costs: the reconstructor's accuracy
 * against its latency (docs/reconstruction.md has the table this prints).
 *
 * For each latency setting (latency_mm: the most strip a row waits for
 * before it is final), the streaming reconstructor (rigid_motion + robust
 * Huber, the gauge's options) runs row by row over a 30 m strip of the
 * reference's sheet (12 mm waves, 1800 mm along, 1500 mm across; rows every
 * 3 mm, fibers every 2 mm across 1500 mm unless --fibers says otherwise),
 * pulling rows as they finish, as the gauge does: the strip runs on across
 * the shear's cuts and ends once. Measured:
 *
 *   lag          the lag (knots) the setting gives;
 *   latency      the strip pushed beyond a row when it came out, mm: mean
 *                and max past the strip's first 3 m, and the max in them
 *                (the strip's head waits up to twice as long);
 *   noise-free   the largest error against the true surface (um), with
 *                the strip ended (end_sheet, carry-over) every 3 m: the
 *                joins and the interior;
 *   experiment 3 the reference's third experiment in its physical form
 *                (2.5 mm rigid heave per frame, 0.5 mm eccentricity of
 *                50 mm period, 0.05 mm peak noise per laser, the shear's
 *                ringing after a cut every 3 m: 50 mm envelope, decay
 *                0.07/mm, 10 mm period): MaxAE and STD (the standard
 *                deviation of |e|, the article's definition) after removing
 *                one constant per 3 m sheet (the level of a bouncing strip
 *                is not observable), the worst over --seeds seeds, over all
 *                sheets and over those after the strip's first; and the
 *                streamed output against flt_reconstruct of the whole strip
 *                with the same options (the whole-sheet robust estimate the
 *                stream converges to), RMS and max;
 *   1% peaks     spurious laser peaks (1% of the samples, 2.5-5 mm off on one
 *                laser) over the heave and peak noise: MaxAE, worst seed,
 *                all sheets and after the first;
 *   cost         microseconds per pushed row on experiment 3 (CPU time of
 *                this thread, so that other programs on the machine do not
 *                count).
 * Errors are taken over the sheets finished by the lag (the last 3 m sheet,
 * which end_sheet finishes, is left out).
 *
 * A second table gives the gauge's early answers (gauge_provisional_mm) at
 * the first latency given: each 3 m sheet as known when the strip is 300,
 * 600, 1000 or 1500 mm past its cut (its final rows and the pending ones
 * as flt_recon_peek estimates them), with the same error columns.
 *
 * Usage: bench_latency [--fibers N] [--seeds N] [--plain] [--lag-knots]
 *                      [latency_mm ...]
 *   latency in mm (default: 1000 1500 2000 3000 6000); with --lag-knots the
 *   values are lag_knots instead (the older setting); --plain: least
 *   squares per fiber instead of rigid_motion + robust.
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <flatline/flatline.h>

#define DX       3.0
#define LASER    100.0
#define WIDTH    1500.0
#define SHEET_MM 3000.0
#define SHEETS   10
#define ROWS     ((size_t)(SHEETS * SHEET_MM / DX))

static const double k_pi = 3.14159265358979323846;

static double cpu_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void check(flt_status st, const char *what) {
    if (st != FLT_OK) {
        fprintf(stderr, "bench_latency: %s failed: %s: %s\n", what, flt_status_string(st),
                flt_last_error_message());
        exit(1);
    }
}

/* xorshift64* and Box-Muller: every run measures the same strips. */
typedef struct rng {
    uint64_t state;
} rng;
static void rng_seed(rng *g, unsigned seed) {
    g->state = 0x9E3779B97F4A7C15ull ^ ((uint64_t)seed * 0xD1B54A32D192ED03ull);
}
static double uniform01(rng *g) {
    uint64_t x = g->state;
    x ^= x >> 12;
    x ^= x << 25;
    x ^= x >> 27;
    g->state = x;
    return ((double)((x * 0x2545F4914F6CDD1Dull) >> 11) + 0.5) / 9007199254740992.0;
}
static double gauss(rng *g) {
    return sqrt(-2.0 * log(uniform01(g))) * cos(2.0 * k_pi * uniform01(g));
}

/* The reference surface and the shear's ringing at material position p. */
static double surface(double x, double s) {
    return 12.0 * sin(2 * k_pi * s / 1800.0) * cos(2 * k_pi * x / 1500.0);
}
static double ringing(double p) {
    if (p < 0)
        return 0.0;
    double u = fmod(p, SHEET_MM);
    return 50.0 * exp(-0.07 * u) * sin(2 * k_pi * u / 10.0);
}

typedef struct strip {
    size_t rows, fibers;
    double *s, *x, *truth, *height, *slope;
} strip;

static void *alloc(size_t bytes) {
    void *p = malloc(bytes);
    if (!p) {
        fprintf(stderr, "bench_latency: out of memory\n");
        exit(1);
    }
    return p;
}

/* The noise-free measurement of the strip: each laser reads the surface at
 * s -+ Delta-d/2; the height is their mean, the slope their difference over
 * Delta-d. */
static void make_strip(strip *t, size_t fibers) {
    t->rows = ROWS;
    t->fibers = fibers;
    size_t n = ROWS * fibers;
    t->s = alloc(ROWS * sizeof(double));
    t->x = alloc(fibers * sizeof(double));
    t->truth = alloc(n * sizeof(double));
    t->height = alloc(n * sizeof(double));
    t->slope = alloc(n * sizeof(double));
    for (size_t k = 0; k < fibers; ++k)
        t->x[k] = fibers > 1 ? -0.5 * WIDTH + WIDTH * (double)k / (double)(fibers - 1) : 0.0;
    for (size_t r = 0; r < ROWS; ++r)
        t->s[r] = (double)r * DX;
}

static void measure_clean(strip *t) {
    for (size_t r = 0; r < t->rows; ++r)
        for (size_t k = 0; k < t->fibers; ++k) {
            size_t i = r * t->fibers + k;
            double a = surface(t->x[k], t->s[r] - 0.5 * LASER);
            double b = surface(t->x[k], t->s[r] + 0.5 * LASER);
            t->truth[i] = surface(t->x[k], t->s[r]);
            t->height[i] = 0.5 * (a + b);
            t->slope[i] = (b - a) / LASER;
        }
}

/* Experiment 3, physical model: per frame a rigid heave and the roll's
 * eccentricity on both lasers and every fiber, peak noise per laser, and the
 * ringing on the strip where each laser looks (shear = 0: experiment 2). */
static void add_experiment3(strip *t, unsigned seed, int shear) {
    rng g;
    rng_seed(&g, seed);
    double phase = 2 * k_pi * uniform01(&g);
    for (size_t r = 0; r < t->rows; ++r) {
        double s = t->s[r];
        double frame = 2.5 * gauss(&g) + 0.5 * sin(2 * k_pi * s / 50.0 + phase);
        double ra = shear ? ringing(s - 0.5 * LASER) : 0.0;
        double rb = shear ? ringing(s + 0.5 * LASER) : 0.0;
        for (size_t k = 0; k < t->fibers; ++k) {
            double a = frame + ra + 0.05 * gauss(&g), b = frame + rb + 0.05 * gauss(&g);
            t->height[r * t->fibers + k] += 0.5 * (a + b);
            t->slope[r * t->fibers + k] += (b - a) / LASER;
        }
    }
}

/* 1% spurious peaks on the heave and peak noise (no eccentricity, no
 * ringing): one laser's reading of a sample 2.5-5 mm off. */
static void add_spurious_peaks(strip *t, unsigned seed) {
    rng g;
    rng_seed(&g, seed);
    for (size_t r = 0; r < t->rows; ++r) {
        double heave = 2.5 * gauss(&g);
        for (size_t k = 0; k < t->fibers; ++k) {
            double a = heave + 0.05 * gauss(&g), b = heave + 0.05 * gauss(&g);
            if (uniform01(&g) < 0.01) {
                double e = (2.5 + 2.5 * uniform01(&g)) * (uniform01(&g) < 0.5 ? -1 : 1);
                if (uniform01(&g) < 0.5)
                    a += e;
                else
                    b += e;
            }
            t->height[r * t->fibers + k] += 0.5 * (a + b);
            t->slope[r * t->fibers + k] += (b - a) / LASER;
        }
    }
}

static void free_strip(strip *t) {
    free(t->s);
    free(t->x);
    free(t->truth);
    free(t->height);
    free(t->slope);
}

typedef struct setting {
    double value;  /* latency_mm, or lag_knots with --lag-knots */
    int lag_knots; /* the value is lag_knots */
    int rigid, robust;
} setting;

static flt_options *make_options(const setting *set) {
    flt_options *o = NULL;
    check(flt_options_create(&o), "flt_options_create");
    check(flt_options_set(o, FLT_OPT_RIGID_MOTION, set->rigid), "rigid_motion");
    check(flt_options_set(o, FLT_OPT_ROBUST, set->robust), "robust");
    check(flt_options_set(o, FLT_OPT_ROW_CAPACITY, 16384), "row_capacity");
    if (set->lag_knots)
        check(flt_options_set(o, FLT_OPT_LAG_KNOTS, set->value), "lag_knots");
    else
        check(flt_options_set(o, FLT_OPT_LATENCY_MM, set->value), "latency_mm");
    return o;
}

typedef struct stream_result {
    double latency_mean, latency_max; /* mm, rows past the first sheet */
    double head_max;                  /* mm, rows of the first sheet */
    size_t before_end;                /* rows finished before the end */
    double us_per_row;                /* CPU */
    double lag_knots;                 /* the lag the reconstructor took */
} stream_result;

/* Streams the strip row by row, pulling as rows finish, into z; end_sheet
 * every `sheet_rows` rows (0: once, at the end). */
static stream_result stream(const strip *t, const setting *set, size_t sheet_rows, double *z) {
    size_t K = t->fibers;
    flt_options *o = make_options(set);
    flt_recon *rc = NULL;
    check(flt_recon_create(K, o, &rc), "flt_recon_create");
    flt_options_destroy(o);
    double *s_out = alloc(t->rows * sizeof(double));
    stream_result res = {0, 0, 0, 0, 0, 0};
    check(flt_recon_get_option(rc, FLT_OPT_LAG_KNOTS, &res.lag_knots), "lag_knots");
    size_t pulled = 0, got = 0, steady = 0;
    double sum = 0, t0 = cpu_s();
    for (size_t r = 0; r < t->rows; ++r) {
        check(flt_recon_push(rc, 1, K, &t->s[r], t->height + r * K, t->slope + r * K, NULL),
              "flt_recon_push");
        check(flt_recon_pull(rc, t->rows - pulled, K, s_out, z + pulled * K, NULL, &got),
              "flt_recon_pull");
        for (size_t i = 0; i < got; ++i) {
            double behind = t->s[r] - s_out[i];
            if (s_out[i] < SHEET_MM) {
                res.head_max = fmax(res.head_max, behind);
                continue;
            }
            sum += behind;
            ++steady;
            res.latency_max = fmax(res.latency_max, behind);
        }
        pulled += got;
        if (sheet_rows && (r + 1) % sheet_rows == 0 && r + 1 < t->rows) {
            check(flt_recon_end_sheet(rc), "flt_recon_end_sheet");
            check(flt_recon_pull(rc, t->rows - pulled, K, s_out, z + pulled * K, NULL, &got),
                  "flt_recon_pull");
            pulled += got;
        }
    }
    res.before_end = pulled;
    res.latency_mean = steady ? sum / (double)steady : 0.0;
    check(flt_recon_end_sheet(rc), "flt_recon_end_sheet");
    check(flt_recon_pull(rc, t->rows - pulled, K, s_out, z + pulled * K, NULL, &got),
          "flt_recon_pull");
    pulled += got;
    res.us_per_row = 1e6 * (cpu_s() - t0) / (double)t->rows;
    if (pulled != t->rows) {
        fprintf(stderr, "bench_latency: %zu of %zu rows came out\n", pulled, t->rows);
        exit(1);
    }
    flt_recon_destroy(rc);
    free(s_out);
    return res;
}

/* MaxAE and STD of |e| after removing one constant per 3 m sheet, over the
 * sheets [0, sheets). */
static void sheet_errors(const strip *t, const double *z, size_t sheets, double *max_out,
                         double *std_out) {
    size_t K = t->fibers, per = (size_t)(SHEET_MM / DX);
    double mx = 0, sum = 0, sq = 0;
    size_t n = 0;
    for (size_t sh = 0; sh < sheets; ++sh) {
        double mean = 0;
        for (size_t i = sh * per * K; i < (sh + 1) * per * K; ++i)
            mean += z[i] - t->truth[i];
        mean /= (double)(per * K);
        for (size_t i = sh * per * K; i < (sh + 1) * per * K; ++i) {
            double e = fabs(z[i] - t->truth[i] - mean);
            mx = fmax(mx, e);
            sum += e;
            sq += e * e;
            ++n;
        }
    }
    double mean_abs = sum / (double)n;
    *max_out = mx;
    *std_out = sqrt(fmax(0.0, sq / (double)n - mean_abs * mean_abs));
}

/* The error of z against the truth: MaxAE and STD over sheets [first,
 * SHEETS - 1) (the last one is finished by end_sheet, not by the lag). */
static void errors_from(const strip *t, const double *z, size_t first, double *max_out,
                        double *std_out) {
    size_t per = (size_t)(SHEET_MM / DX) * t->fibers;
    strip part = *t;
    part.truth = t->truth + first * per;
    sheet_errors(&part, z + first * per, SHEETS - 1 - first, max_out, std_out);
}

/* The gauge's early answers (gauge_provisional_mm): streams the strip as
 * stream() does and, when the newest row first lies `ahead` mm past a cut,
 * takes that sheet as known then: its rows final so far and the pending
 * ones as flt_recon_peek estimates them. zp receives every sheet but the
 * last so (the last has no cut). */
static void provisional(const strip *t, const setting *set, double ahead, double *zp) {
    size_t K = t->fibers, per = (size_t)(SHEET_MM / DX);
    flt_options *o = make_options(set);
    flt_recon *rc = NULL;
    check(flt_recon_create(K, o, &rc), "flt_recon_create");
    flt_options_destroy(o);
    double *s_out = alloc(t->rows * sizeof(double));
    double *zf = alloc(t->rows * K * sizeof(double)), *zq = alloc(t->rows * K * sizeof(double));
    size_t pulled = 0, got = 0, next_cut = 1;
    for (size_t r = 0; r < t->rows && next_cut < SHEETS; ++r) {
        check(flt_recon_push(rc, 1, K, &t->s[r], t->height + r * K, t->slope + r * K, NULL),
              "flt_recon_push");
        check(flt_recon_pull(rc, t->rows - pulled, K, s_out, zf + pulled * K, NULL, &got),
              "flt_recon_pull");
        pulled += got;
        while (next_cut < SHEETS && t->s[r] >= (double)next_cut * SHEET_MM + ahead) {
            size_t lo = (next_cut - 1) * per, hi = next_cut * per;
            size_t final_end = pulled < hi ? pulled : hi;
            if (final_end > lo)
                memcpy(zp + lo * K, zf + lo * K, (final_end - lo) * K * sizeof(double));
            if (pulled < hi) {
                check(flt_recon_peek(rc, t->rows - pulled, K, s_out, zq, NULL, &got),
                      "flt_recon_peek");
                if (pulled + got < hi) {
                    fprintf(stderr, "bench_latency: %zu rows pending, %zu wanted\n", got,
                            hi - pulled);
                    exit(1);
                }
                size_t from = pulled > lo ? pulled : lo;
                memcpy(zp + from * K, zq + (from - pulled) * K, (hi - from) * K * sizeof(double));
            }
            ++next_cut;
        }
    }
    flt_recon_destroy(rc);
    free(s_out);
    free(zf);
    free(zq);
}

int main(int argc, char **argv) {
    size_t fibers = 751;
    unsigned seeds = 5;
    setting base = {0, 0, 1, FLT_ROBUST_HUBER};
    double values[32];
    size_t n_values = 0;
    for (int a = 1; a < argc; ++a) {
        if (!strcmp(argv[a], "--fibers") && a + 1 < argc)
            fibers = (size_t)atoi(argv[++a]);
        else if (!strcmp(argv[a], "--seeds") && a + 1 < argc)
            seeds = (unsigned)atoi(argv[++a]);
        else if (!strcmp(argv[a], "--lag-knots"))
            base.lag_knots = 1;
        else if (!strcmp(argv[a], "--plain"))
            base.rigid = 0, base.robust = FLT_ROBUST_NONE;
        else if (n_values < 32 && atof(argv[a]) >= 0 && argv[a][0] != '-')
            values[n_values++] = atof(argv[a]);
        else
            fibers = 0; /* unknown argument: usage */
    }
    if (fibers < 2 || seeds < 1) {
        fprintf(stderr, "usage: bench_latency [--fibers N>=2] [--seeds N>=1] [--plain] "
                        "[--lag-knots] [latency_mm ...]\n");
        return 2;
    }
    if (n_values == 0) {
        const double defaults[] = {1000, 1500, 2000, 3000, 6000};
        for (size_t i = 0; i < sizeof defaults / sizeof defaults[0]; ++i)
            values[n_values++] = defaults[i];
    }

    strip t;
    make_strip(&t, fibers);
    size_t n = t.rows * fibers;
    double *z = alloc(n * sizeof(double)), *zb = alloc(n * sizeof(double));
    printf("libflatline %s: streaming latency against accuracy, %s, %zu fibers, %u seeds, "
           "%.0f m strip, rows every %.0f mm, a cut every %.0f m\n",
           flt_version_string(), base.rigid ? "rigid_motion + robust (Huber)" : "plain", fibers,
           seeds, ROWS * DX / 1000.0, DX, SHEET_MM / 1000.0);
    printf("(MaxAE and STD: all sheets / past the strip's first sheet; latency: past the "
           "first sheet, and its max there)\n\n");
    printf("| %s | lag, knots | latency mean / max, mm | head max, mm | noise-free max, um "
           "| exp. 3 MaxAE, mm | exp. 3 STD, mm | vs whole strip RMS / max, mm "
           "| 1%% peaks MaxAE, mm | CPU per row, us |\n",
           base.lag_knots ? "lag_knots" : "latency_mm");
    printf("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
    double whole_max = 0, whole_std = 0, whole_rest = 0;
    for (size_t v = 0; v < n_values; ++v) {
        setting set = base;
        set.value = values[v];
        /* Noise-free, carry-over joins every 3 m. */
        measure_clean(&t);
        stream(&t, &set, (size_t)(SHEET_MM / DX), z);
        double clean_max = 0;
        for (size_t i = 0; i < n; ++i)
            clean_max = fmax(clean_max, fabs(z[i] - t.truth[i]));
        /* Experiment 3, every seed, and the whole strip at once. */
        double e3_max = 0, e3_std = 0, e3_rest = 0, e3_std_rest = 0;
        double diff_rms = 0, diff_max = 0, cost = 0;
        double batch_max = 0, batch_std = 0, batch_rest = 0;
        stream_result lat = {0, 0, 0, 0, 0, 0};
        for (unsigned seed = 1; seed <= seeds; ++seed) {
            fprintf(stderr, "\r%g: experiment 3, seed %u/%u   ", set.value, seed, seeds);
            measure_clean(&t);
            add_experiment3(&t, 300 + seed, 1);
            stream_result res = stream(&t, &set, 0, z);
            if (seed == 1)
                lat = res;
            cost += res.us_per_row / seeds;
            double mx, sd;
            errors_from(&t, z, 0, &mx, &sd);
            e3_max = fmax(e3_max, mx);
            e3_std = fmax(e3_std, sd);
            errors_from(&t, z, 1, &mx, &sd);
            e3_rest = fmax(e3_rest, mx);
            e3_std_rest = fmax(e3_std_rest, sd);
            flt_options *o = make_options(&set);
            check(flt_reconstruct(o, t.rows, fibers, t.s, t.height, t.slope, NULL, zb, NULL),
                  "flt_reconstruct");
            flt_options_destroy(o);
            double sq = 0;
            size_t m = (SHEETS - 1) * (size_t)(SHEET_MM / DX) * fibers;
            for (size_t i = 0; i < m; ++i) {
                double d = z[i] - zb[i];
                sq += d * d;
                diff_max = fmax(diff_max, fabs(d));
            }
            diff_rms = fmax(diff_rms, sqrt(sq / (double)m));
            errors_from(&t, zb, 0, &mx, &sd);
            batch_max = fmax(batch_max, mx);
            batch_std = fmax(batch_std, sd);
            errors_from(&t, zb, 1, &mx, &sd);
            batch_rest = fmax(batch_rest, mx);
        }
        /* 1% spurious peaks, every seed. */
        double peaks_max = 0, peaks_rest = 0;
        for (unsigned seed = 1; seed <= seeds; ++seed) {
            fprintf(stderr, "\r%g: 1%% peaks, seed %u/%u       ", set.value, seed, seeds);
            measure_clean(&t);
            add_spurious_peaks(&t, 40 + seed);
            stream(&t, &set, 0, z);
            double mx, sd;
            errors_from(&t, z, 0, &mx, &sd);
            peaks_max = fmax(peaks_max, mx);
            errors_from(&t, z, 1, &mx, &sd);
            peaks_rest = fmax(peaks_rest, mx);
        }
        fprintf(stderr, "\r%60s\r", "");
        printf("| %g | %.0f | %.0f / %.0f | %.0f | %.3f | %.3f / %.3f | %.4f / %.4f "
               "| %.4f / %.3f | %.3f / %.3f | %.1f |\n",
               set.value, lat.lag_knots, lat.latency_mean, lat.latency_max, lat.head_max,
               clean_max * 1e3, e3_max, e3_rest, e3_std, e3_std_rest, diff_rms, diff_max, peaks_max,
               peaks_rest, cost);
        if (v == 0)
            whole_max = batch_max, whole_std = batch_std, whole_rest = batch_rest;
        fflush(stdout);
    }
    printf("\nthe whole strip at once (flt_reconstruct, the same options), experiment 3: "
           "MaxAE %.3f / %.3f mm, STD %.4f mm\n",
           whole_max, whole_rest, whole_std);

    /* Early answers at the first setting's latency: each sheet as known
     * when the strip is gauge_provisional_mm past its cut. */
    setting set = base;
    set.value = values[0];
    printf("\nearly answers (the gauge's gauge_provisional_mm) at %s %g: each sheet as known "
           "that far past its cut\n\n",
           base.lag_knots ? "lag_knots" : "latency_mm", set.value);
    printf("| gauge_provisional_mm | noise-free max, um | exp. 3 MaxAE, mm | exp. 3 STD, mm "
           "| 1%% peaks MaxAE, mm |\n| --- | --- | --- | --- | --- |\n");
    const double aheads[] = {300, 600, 1000, 1500};
    for (size_t a = 0; a < sizeof aheads / sizeof aheads[0]; ++a) {
        measure_clean(&t);
        provisional(&t, &set, aheads[a], z);
        double clean_max = 0;
        for (size_t i = 0; i < (SHEETS - 1) * (size_t)(SHEET_MM / DX) * fibers; ++i)
            clean_max = fmax(clean_max, fabs(z[i] - t.truth[i]));
        double e3_max = 0, e3_rest = 0, e3_std = 0, e3_std_rest = 0, pk_max = 0, pk_rest = 0;
        for (unsigned seed = 1; seed <= seeds; ++seed) {
            fprintf(stderr, "\rearly %g: seed %u/%u   ", aheads[a], seed, seeds);
            double mx, sd;
            measure_clean(&t);
            add_experiment3(&t, 300 + seed, 1);
            provisional(&t, &set, aheads[a], z);
            errors_from(&t, z, 0, &mx, &sd);
            e3_max = fmax(e3_max, mx);
            e3_std = fmax(e3_std, sd);
            errors_from(&t, z, 1, &mx, &sd);
            e3_rest = fmax(e3_rest, mx);
            e3_std_rest = fmax(e3_std_rest, sd);
            measure_clean(&t);
            add_spurious_peaks(&t, 40 + seed);
            provisional(&t, &set, aheads[a], z);
            errors_from(&t, z, 0, &mx, &sd);
            pk_max = fmax(pk_max, mx);
            errors_from(&t, z, 1, &mx, &sd);
            pk_rest = fmax(pk_rest, mx);
        }
        fprintf(stderr, "\r%60s\r", "");
        printf("| %g | %.3f | %.3f / %.3f | %.4f / %.4f | %.3f / %.3f |\n", aheads[a],
               clean_max * 1e3, e3_max, e3_rest, e3_std, e3_std_rest, pk_max, pk_rest);
        fflush(stdout);
    }
    free(z);
    free(zb);
    free_strip(&t);
    return 0;
}
