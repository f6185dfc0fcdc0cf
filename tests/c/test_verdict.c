// SPDX-License-Identifier: Apache-2.0
/*
 * Verdicts (flatline/verdict.h): the straightedge deviation against closed
 * forms (a sine under a straightedge shorter and longer than its period)
 * and against its definition evaluated by brute force, on profiles and on
 * every line of maps; rule files and their errors; a sheet judged against
 * rules by thickness and width band.
 */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include <flatline/flatline.h>

#include "test_files.h"

#define OK(call) assert_int_equal((call), FLT_OK)

static const double PI = 3.14159265358979323846;

static flt_rules *load(const char *text);
static double get(const flt_verdict *v, size_t rule, flt_verdict_value key);

/* The sine's straightedge deviation: a straightedge of length L <= P rests
 * on the two samples L/2 either side of a trough (the highest pair it can
 * bridge) and shows A (1 - cos(pi L / P)); one of L >= P bridges two crests
 * and shows the full height 2 A. */
static double sine_deviation(double amplitude, double period, double length) {
    return length >= period ? 2.0 * amplitude : amplitude * (1.0 - cos(PI * length / period));
}

/* The definition, by brute force: every pair of samples at most `length`
 * apart with every sample between on or below their segment; the largest
 * gap between. O(n^3), for short profiles. */
static double brute_deviation(const double *p, const double *z, size_t n, double length) {
    double best = 0;
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i + 1; j < n && p[j] - p[i] <= length * (1 + 1e-9); ++j) {
            const double m = (z[j] - z[i]) / (p[j] - p[i]);
            double gap = 0;
            int rests = 1;
            for (size_t k = i + 1; k < j && rests; ++k) {
                const double g = z[i] + m * (p[k] - p[i]) - z[k];
                /* Below the segment within rounding (1e-12 mm): the
                 * library decides the same pairs with exact comparisons of
                 * products; a sample on the segment neither blocks nor
                 * gaps. */
                if (g < -1e-12)
                    rests = 0;
                else if (g > gap)
                    gap = g;
            }
            if (rests && gap > best)
                best = gap;
        }
    return best;
}

/* A sine of amplitude 2 mm and period 500 mm over 3 m, a sample every mm,
 * crests at s = 0, 500, ... and troughs at 250, 750, ... on samples. */
static void sine_under_short_and_long_straightedges(void **state) {
    (void)state;
    enum { N = 3001 };
    const double A = 2.0, P = 500.0;
    double *p = malloc(N * sizeof *p), *z = malloc(N * sizeof *z);
    for (size_t i = 0; i < N; ++i) {
        p[i] = (double)i;
        z[i] = A * cos(2.0 * PI * p[i] / P);
    }
    const double lengths[] = {50, 100, 250, 400, 498, 500, 700, 1000, 2000};
    for (size_t t = 0; t < sizeof lengths / sizeof lengths[0]; ++t) {
        const double L = lengths[t];
        double d = -1, at = -1;
        OK(flt_straightedge_profile(p, z, N, L, &d, &at));
        /* The closed form's contacts lie on samples (L/2 is whole), so the
         * samples reach it exactly; the tolerance is cos()'s rounding on
         * heights of 2 mm. */
        print_message("L = %4.0f mm: deviation %.15f mm, closed form %.15f mm, deepest at %.0f\n",
                      L, d, sine_deviation(A, P, L), at);
        assert_true(fabs(d - sine_deviation(A, P, L)) < 1e-12);
        /* The deepest point is a trough. */
        assert_true(fabs(A * cos(2.0 * PI * at / P) + A) < 1e-12);
    }
    /* Off the samples' grid (phase 0.3 rad): the samples lie on the sine,
     * so the deviation never exceeds the closed form (the largest over
     * every resting position on the continuous profile); and samples lie
     * within 0.5 mm of the true contacts and trough, so it falls short by
     * at most what the sine changes over 0.5 mm at each of the three:
     * 3 x 0.5 x A 2 pi / P (its steepest slope) = 0.038 mm. */
    for (size_t i = 0; i < N; ++i)
        z[i] = A * cos(2.0 * PI * p[i] / P + 0.3);
    const double bound = 3 * 0.5 * A * 2 * PI / P;
    for (size_t t = 0; t < sizeof lengths / sizeof lengths[0]; ++t) {
        const double L = lengths[t];
        double d;
        OK(flt_straightedge_profile(p, z, N, L, &d, NULL));
        assert_true(d <= sine_deviation(A, P, L) + 1e-12);
        assert_true(d >= sine_deviation(A, P, L) - bound);
    }
    free(p);
    free(z);
}

/* Random profiles (waves, steps and noise, uneven spacing, NaN holes):
 * the hull algorithm equals the definition evaluated by brute force. */
static void equals_the_definition(void **state) {
    (void)state;
    enum { N = 300 };
    double p[N], z[N], pv[N], zv[N];
    uint64_t seed = 12345;
    for (int trial = 0; trial < 40; ++trial) {
        double pos = 0;
        size_t nv = 0;
        for (size_t i = 0; i < N; ++i) {
            seed = seed * 6364136223846793005ull + 1442695040888963407ull;
            const double u = (double)(seed >> 11) / 9007199254740992.0;
            pos += 0.5 + 2.0 * u;
            p[i] = pos;
            z[i] = 1.5 * sin(pos / (20.0 + trial)) + 0.3 * sin(pos / 3.1) + 0.2 * (u - 0.5) +
                   (pos > 200 && trial % 3 == 0 ? 1.0 : 0.0);
            if (trial % 4 == 1 && i % 17 == 5)
                z[i] = NAN; /* not measured: left out */
            if (!isnan(z[i])) {
                pv[nv] = p[i];
                zv[nv] = z[i];
                ++nv;
            }
        }
        const double lengths[] = {5, 37, 120, 400, 1000};
        for (size_t t = 0; t < 5; ++t) {
            double d;
            OK(flt_straightedge_profile(p, z, N, lengths[t], &d, NULL));
            const double want = brute_deviation(pv, zv, nv, lengths[t]);
            /* Rounding only: both evaluate the same gap formula on heights
             * of about 2 mm. */
            if (fabs(d - want) > 1e-12)
                fail_msg("trial %d, L = %g: %.17g against the definition's %.17g", trial,
                         lengths[t], d, want);
        }
    }
}

/* Hand-checked small cases. */
static void small_profiles(void **state) {
    (void)state;
    double d, at;
    /* A straight line: no gap. */
    const double p[5] = {0, 1, 2, 3, 4}, line[5] = {0, 0.5, 1, 1.5, 2};
    OK(flt_straightedge_profile(p, line, 5, 10, &d, &at));
    assert_true(d == 0.0);
    /* A V of depth 1 between contacts 4 apart: seen whole by a
     * straightedge of 4; one of 3.9 rests on (0, 1) and (3, 0.5), and the
     * sample at 2 lies 2/3 below that segment. */
    const double v[5] = {1, 0.5, 0, 0.5, 1};
    OK(flt_straightedge_profile(p, v, 5, 4, &d, &at));
    assert_true(fabs(d - 1.0) < 1e-15);
    assert_true(at == 2.0);
    OK(flt_straightedge_profile(p, v, 5, 3.9, &d, &at));
    assert_true(fabs(d - 2.0 / 3.0) < 1e-15);
    assert_true(at == 2.0);
    /* A crest: a straightedge rests on it without a gap. */
    const double crest[5] = {0, 0.5, 1, 0.5, 0};
    OK(flt_straightedge_profile(p, crest, 5, 100, &d, &at));
    assert_true(d == 0.0);
    /* Two samples: measured, no gap. */
    OK(flt_straightedge_profile(p, v, 2, 100, &d, &at));
    assert_true(d == 0.0);
}

/* The definition once more, directly and for long profiles: a left
 * contact i rests with every sample j within reach whose slope from i is
 * at least that of each sample between; the steepest such j lies highest
 * over every sample between, so the gaps from i are those under the
 * segment to the sample of largest slope from i within reach (the
 * farthest on a tie). Its O(n x samples in reach) scans use the library's
 * comparison of slopes (products, no division). depth[k] (may be NULL)
 * receives each sample's largest gap. */
static double definition(const double *p, const double *z, size_t n, double length, double *depth) {
    const double reach = length * (1 + 1e-9); /* as the library: a span of L counts */
    double best = 0;
    for (size_t k = 0; depth && k < n; ++k)
        depth[k] = 0;
    for (size_t i = 0; i + 1 < n; ++i) {
        size_t j = i + 1;
        for (size_t q = i + 2; q < n && p[q] - p[i] <= reach; ++q)
            if ((z[q] - z[i]) * (p[j] - p[i]) >= (z[j] - z[i]) * (p[q] - p[i]))
                j = q;
        const double m = (z[j] - z[i]) / (p[j] - p[i]);
        for (size_t k = i + 1; k < j; ++k) {
            const double g = m * (p[k] - p[i]) - (z[k] - z[i]);
            best = g > best ? g : best;
            if (depth && g > depth[k])
                depth[k] = g;
        }
    }
    return best;
}

static uint64_t g_seed = 20240611;

static double uniform(void) {
    g_seed = g_seed * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(g_seed >> 11) / 9007199254740992.0;
}

/* A random profile of n samples, of one of six kinds: a wave with noise
 * on a 1 mm grid; with uneven spacing; tilted bumps; heights on a 0.25 mm
 * grid (plateaus, and gaps equal to the last bit at many places); NaN
 * holes, single and a long one; spikes and pits. */
static void random_profile(int kind, size_t n, double *p, double *z) {
    const double amplitude = 0.1 + 4 * uniform(), period = 20 + 1500 * uniform();
    const double noise = 0.2 * uniform(), tilt = 0.02 * (uniform() - 0.5);
    double pos = 1000 * (uniform() - 0.5);
    for (size_t i = 0; i < n; ++i) {
        pos += kind == 0 ? 1.0 : 0.2 + 3 * uniform();
        p[i] = pos;
        z[i] = amplitude * sin(2 * PI * pos / period) + tilt * pos + noise * (uniform() - 0.5);
        if (kind == 2)
            z[i] = amplitude * cos(2 * PI * pos / period) * cos(PI * pos / (3.1 * period)) +
                   tilt * pos + noise * (uniform() - 0.5);
        if (kind == 3)
            z[i] = floor(z[i] * 4) / 4;
        if (kind == 4 && uniform() < 0.08)
            z[i] = NAN;
        if (kind == 5 && uniform() < 0.1)
            z[i] += (uniform() < 0.5 ? -1 : 1) * amplitude * uniform();
    }
    if (kind == 4 && n > 20)
        for (size_t i = n / 3; i < n / 2; ++i)
            z[i] = NAN;
}

/* Random profiles of every kind and many lengths, from 2 samples to 2500
 * (around the library's chunks of 16 samples), under straightedges from
 * shorter than a sample step (nothing rests with a sample between) to
 * three times the profile: the deviation equals the definition's, and it
 * is found at a sample that deep. */
static void random_profiles_equal_the_definition(void **state) {
    (void)state;
    const size_t sizes[] = {2, 3, 15, 16, 17, 33, 100, 257, 1000, 2500};
    double *p = malloc(2500 * sizeof *p), *z = malloc(2500 * sizeof *z);
    double *pv = malloc(2500 * sizeof *pv), *zv = malloc(2500 * sizeof *zv);
    double *depth = malloc(2500 * sizeof *depth);
    size_t profiles = 0, positive = 0;
    for (size_t t = 0; t < sizeof sizes / sizeof *sizes; ++t)
        for (int kind = 0; kind < 6; ++kind)
            for (int rep = 0; rep < (sizes[t] >= 1000 ? 2 : 6); ++rep) {
                const size_t n = sizes[t];
                random_profile(kind, n, p, z);
                size_t nv = 0;
                double extent = 0;
                for (size_t i = 0; i < n; ++i)
                    if (!isnan(z[i])) {
                        pv[nv] = p[i];
                        zv[nv++] = z[i];
                        extent = fabs(z[i]) > extent ? fabs(z[i]) : extent;
                    }
                const double span = p[n - 1] - p[0];
                const double lengths[] = {0.1, 5, 37, 10.0, 0.3 * span, span, 3 * span};
                for (size_t l = 0; l < sizeof lengths / sizeof *lengths; ++l) {
                    double d = -1, at = NAN;
                    const flt_status st = flt_straightedge_profile(p, z, n, lengths[l], &d, &at);
                    if (nv < 2) {
                        assert_int_equal(st, FLT_ERR_NOT_FOUND);
                        continue;
                    }
                    OK(st);
                    ++profiles;
                    const double want = definition(pv, zv, nv, lengths[l], depth);
                    /* Both evaluate the gap m (p_k - p_i) - (z_k - z_i) on the
                     * same samples; only where resting positions tie exactly
                     * may they take different contacts for the same gap, which
                     * changes its rounding: a few operations on magnitudes up
                     * to twice the largest |z|, 32 ulps of it. */
                    const double tolerance = 32 * DBL_EPSILON * extent;
                    if (fabs(d - want) > tolerance)
                        fail_msg("kind %d, n %zu, L = %g: %.17g against the definition's %.17g",
                                 kind, n, lengths[l], d, want);
                    if (want > 0) {
                        ++positive;
                        size_t k = 0;
                        while (k < nv && pv[k] != at)
                            ++k;
                        assert_true(k < nv);                             /* a measured sample ... */
                        assert_true(fabs(depth[k] - want) <= tolerance); /* ... that deep */
                    } else {
                        assert_true(d == 0.0);
                    }
                }
            }
    print_message("%zu profiles, %zu with a gap\n", profiles, positive);
    assert_true(positive > profiles / 2);
    free(p);
    free(z);
    free(pv);
    free(zv);
    free(depth);
}

/* Maps: every fiber along and every row across, against the definition
 * line by line. Uneven positions both ways, NaN holes with
 * FLT_FLAG_NO_DATA and flagged samples that still hold a height (left out
 * all the same), a dry fiber and a dry row; a wave along, a buckle
 * across, noise. The worst value is the largest line's; its position is
 * on the smallest line that deep, at a sample that deep. */
static void maps_equal_the_definition_line_by_line(void **state) {
    (void)state;
    enum { R = 211, K = 97 };
    double s[R], x[K], line_p[R], line_z[R], depth[R];
    double *z = malloc((size_t)R * K * sizeof *z);
    uint8_t *flags = calloc((size_t)R * K, 1);
    double pos = 0;
    for (size_t r = 0; r < R; ++r)
        s[r] = pos += 3 + 4 * uniform();
    pos = -500;
    for (size_t k = 0; k < K; ++k)
        x[k] = pos += 5 + 10 * uniform();
    for (size_t r = 0; r < R; ++r)
        for (size_t k = 0; k < K; ++k) {
            const size_t at = r * K + k;
            z[at] = 1.5 * sin(2 * PI * s[r] / 300) * cos(PI * x[k] / 1200) +
                    0.8 * cos(2 * PI * x[k] / 700) + 0.05 * (uniform() - 0.5);
            const double u = uniform();
            if (u < 0.03 || k == 40 || (r == 100 && k > 3)) {
                z[at] = NAN;
                flags[at] = FLT_FLAG_NO_DATA;
            } else if (u < 0.05) {
                flags[at] = FLT_FLAG_NO_DATA | FLT_FLAG_GAP; /* a height, unused */
            } else if (u < 0.07) {
                flags[at] = FLT_FLAG_GAP; /* another flag: used */
            }
        }
    static const char rules[] =
        "{ \"format\": \"flatline-tolerances\", \"version\": 1, \"name\": \"maps\",\n"
        "  \"rules\": [\n"
        "    { \"name\": \"a\", \"measure\": \"straightedge_along\", \"length_mm\": 40,\n"
        "      \"bands\": [ { \"thickness_mm\": [0, 10], \"width_mm\": [0, 5000], \"limit\": 1 } ] "
        "},\n"
        "    { \"name\": \"b\", \"measure\": \"straightedge_along\", \"length_mm\": 250,\n"
        "      \"bands\": [ { \"thickness_mm\": [0, 10], \"width_mm\": [0, 5000], \"limit\": 1 } ] "
        "},\n"
        "    { \"name\": \"c\", \"measure\": \"straightedge_across\", \"length_mm\": 60,\n"
        "      \"bands\": [ { \"thickness_mm\": [0, 10], \"width_mm\": [0, 5000], \"limit\": 1 } ] "
        "},\n"
        "    { \"name\": \"d\", \"measure\": \"straightedge_across\", \"length_mm\": 500,\n"
        "      \"bands\": [ { \"thickness_mm\": [0, 10], \"width_mm\": [0, 5000], \"limit\": 1 } ] "
        "}\n"
        "  ] }\n";
    flt_rules *set = load(rules);
    flt_verdict *v = NULL;
    OK(flt_verdict_create(set, &v));
    for (int round = 0; round < 2; ++round) { /* with the flags, then heights alone */
        const uint8_t *f = round == 0 ? flags : NULL;
        OK(flt_verdict_evaluate(v, 2.0, 1000.0, R, K, s, x, z, f));
        for (size_t rule = 0; rule < 4; ++rule) {
            double length = 0;
            flt_measure measure;
            OK(flt_rules_rule(set, rule, NULL, &measure, &length));
            const int along = measure == FLT_MEASURE_STRAIGHTEDGE_ALONG;
            const size_t lines = along ? K : R, samples = along ? R : K;
            const double worst = get(v, rule, FLT_VERDICT_WORST);
            const double wx = get(v, rule, FLT_VERDICT_X), ws = get(v, rule, FLT_VERDICT_S);
            double best = -1, extent = 0;
            size_t best_line = 0;
            int found = 0;
            for (size_t l = 0; l < lines; ++l) {
                size_t n = 0;
                for (size_t j = 0; j < samples; ++j) {
                    const size_t at = along ? j * K + l : l * K + j;
                    if (isnan(z[at]) || (f && (f[at] & FLT_FLAG_NO_DATA)))
                        continue;
                    line_p[n] = along ? s[j] : x[j];
                    line_z[n++] = z[at];
                    extent = fabs(z[at]) > extent ? fabs(z[at]) : extent;
                }
                if (n < 2)
                    continue;
                const double d = definition(line_p, line_z, n, length, depth);
                if (d > best) {
                    best = d;
                    best_line = l;
                }
                /* the reported position's line: its sample is that deep */
                if ((along ? x[l] : s[l]) == (along ? wx : ws)) {
                    found = 1;
                    assert_true(fabs(d - worst) <= 32 * DBL_EPSILON * extent);
                    size_t k = 0;
                    while (k < n && line_p[k] != (along ? ws : wx))
                        ++k;
                    assert_true(k < n);
                    assert_true(fabs(depth[k] - worst) <= 32 * DBL_EPSILON * extent);
                }
            }
            print_message("rule %zu (%s %3.0f mm): worst %.6f mm on line %zu\n", rule,
                          along ? "along " : "across", length, worst, best_line);
            assert_true(found);
            /* as the tolerance in random_profiles_equal_the_definition */
            assert_true(fabs(worst - best) <= 32 * DBL_EPSILON * extent);
            assert_true((along ? x[best_line] : s[best_line]) == (along ? wx : ws));
            assert_int_equal(get(v, rule, FLT_VERDICT_STATE),
                             worst <= 1.0 ? FLT_VERDICT_PASS : FLT_VERDICT_FAIL);
        }
    }
    flt_verdict_destroy(v);
    flt_rules_destroy(set);
    free(z);
    free(flags);
}

/* ---------------------------------------------------------------------- */
/* Rule files                                                              */
/* ---------------------------------------------------------------------- */

static const char k_rules[] =
    "{\n"
    "  \"format\": \"flatline-tolerances\",\n"
    "  \"version\": 1,\n"
    "  \"name\": \"test grade\",\n"
    "  \"rules\": [\n"
    "    { \"name\": \"straightedge 1 m along\", \"measure\": \"straightedge_along\",\n"
    "      \"length_mm\": 1000,\n"
    "      \"bands\": [\n"
    "        { \"thickness_mm\": [1, 3], \"width_mm\": [0, 2000], \"limit\": 3.5 },\n"
    "        { \"thickness_mm\": [3, 6], \"width_mm\": [0, 2000], \"limit\": 5 } ] },\n"
    "    { \"name\": \"straightedge 250 mm along\", \"measure\": \"straightedge_along\",\n"
    "      \"length_mm\": 250,\n"
    "      \"bands\": [ { \"thickness_mm\": [1, 6], \"width_mm\": [0, 2000], \"limit\": 1.5 } ] "
    "},\n"
    "    { \"name\": \"straightedge 1 m across\", \"measure\": \"straightedge_across\",\n"
    "      \"length_mm\": 1000,\n"
    "      \"bands\": [ { \"thickness_mm\": [1, 6], \"width_mm\": [0, 2000], \"limit\": 1 } ] },\n"
    "    { \"name\": \"I-Units\", \"measure\": \"zone_i_units\",\n"
    "      \"bands\": [ { \"thickness_mm\": [1, 6], \"width_mm\": [0, 2000], \"limit\": 20 } ] },\n"
    "    { \"name\": \"bow\", \"measure\": \"bow\",\n"
    "      \"bands\": [ { \"thickness_mm\": [1, 6], \"width_mm\": [0, 2000], \"limit\": 2 } ] },\n"
    "    { \"name\": \"crossbow, wide strip only\", \"measure\": \"crossbow\",\n"
    "      \"bands\": [ { \"thickness_mm\": [1, 6], \"width_mm\": [1800, 3000], \"limit\": 2 } ] "
    "}\n"
    "  ]\n"
    "}\n";

static flt_rules *load(const char *text) {
    flt_rules *r = NULL;
    OK(flt_rules_load_text(text, strlen(text), &r));
    return r;
}

static void rule_file_is_read(void **state) {
    (void)state;
    flt_rules *r = load(k_rules);
    size_t n = 0;
    OK(flt_rules_count(r, &n));
    assert_int_equal(n, 6);
    const char *name = NULL;
    flt_measure m;
    double len = -1;
    OK(flt_rules_rule(r, 1, &name, &m, &len));
    assert_string_equal(name, "straightedge 250 mm along");
    assert_int_equal(m, FLT_MEASURE_STRAIGHTEDGE_ALONG);
    assert_true(len == 250.0);
    OK(flt_rules_rule(r, 4, &name, &m, &len));
    assert_int_equal(m, FLT_MEASURE_BOW);
    assert_true(len == 0.0);
    flt_rules_destroy(r);

    /* The same from a file, named by a UTF-8 path outside any ANSI code
     * page ("Prüfregeln 測.json" in "Toleranz-Größe"): on Windows the file
     * is created by its UTF-16 name, which a narrow fopen of the UTF-8
     * bytes would not find. */
    char dir[512], sub[600], path[700];
    assert_int_equal(tf_temp_dir(dir, sizeof dir, "verdict"), 0);
    snprintf(sub, sizeof sub,
             "%s/Toleranz-Gr\xc3\xb6\xc3\x9f"
             "e",
             dir);
    assert_int_equal(tf_mkdir(sub), 0);
    snprintf(path, sizeof path,
             "%s/Pr\xc3\xbc"
             "fregeln \xe6\xb8\xac.json",
             sub);
    FILE *f = tf_fopen(path, "wb");
    assert_non_null(f);
    fwrite(k_rules, 1, sizeof k_rules - 1, f);
    fclose(f);
    r = NULL;
    OK(flt_rules_load(path, &r));
    OK(flt_rules_count(r, &n));
    assert_int_equal(n, 6);
    flt_rules_destroy(r);
    assert_int_equal(tf_remove(path), 0);
    assert_int_equal(tf_remove(sub), 0);
    assert_int_equal(tf_remove(dir), 0);
}

/* Replaces the first `from` in k_rules with `to`; loading must fail with
 * FLT_ERR_FORMAT and a message holding `needle`. */
static void refused(const char *from, const char *to, const char *needle) {
    char text[4096];
    const char *at = strstr(k_rules, from);
    assert_non_null(at);
    const size_t head = (size_t)(at - k_rules);
    snprintf(text, sizeof text, "%.*s%s%s", (int)head, k_rules, to, at + strlen(from));
    flt_rules *r = (flt_rules *)1;
    assert_int_equal(flt_rules_load_text(text, strlen(text), &r), FLT_ERR_FORMAT);
    assert_null(r);
    const char *msg = flt_last_error_message();
    if (!strstr(msg, needle))
        fail_msg("'%s' -> '%s': message \"%s\" lacks \"%s\"", from, to, msg, needle);
    assert_non_null(strstr(msg, "flt_rules_load_text"));
}

static void rule_file_errors_name_the_field(void **state) {
    (void)state;
    refused("flatline-tolerances", "flatline-calibration", "is not \"flatline-tolerances\"");
    refused("\"version\": 1", "\"version\": 2", "cannot read");
    refused("\"straightedge_along\"", "\"straightedge\"", "'rules[0].measure' = \"straightedge\"");
    refused("\"length_mm\": 1000,\n      \"bands\": [\n", "\"bands\": [\n",
            "missing field 'rules[0].length_mm'");
    refused("\"measure\": \"zone_i_units\",", "\"measure\": \"zone_i_units\", \"length_mm\": 5,",
            "'rules[3].length_mm'");
    refused("\"length_mm\": 250", "\"length_mm\": 0", "'rules[1].length_mm' = 0 must be > 0");
    refused("\"length_mm\": 250", "\"length_mm\": -inf", "'rules[1].length_mm' is infinite");
    refused("[3, 6]", "[2, 6]", "'rules[0].bands[1]' (line 10) overlaps 'rules[0].bands[0]'");
    refused("[3, 6]", "[6, 3]", "'rules[0].bands[1].thickness_mm'");
    refused("[3, 6]", "[-1, 6]", "'rules[0].bands[1].thickness_mm[0]' = -1 must be >= 0");
    refused("[3, 6]", "[3]", "a band is [min, max]");
    refused("\"limit\": 5", "\"limit\": 0", "'rules[0].bands[1].limit' = 0 must be > 0");
    refused("\"limit\": 5", "\"limit\": \"5\"",
            "'rules[0].bands[1].limit' (line 10) must be a number");
    refused("\"limit\": 5", "\"limit\": 5, \"limt\": 4", "unknown field 'rules[0].bands[1].limt'");
    refused("\"bands\": [ { \"thickness_mm\": [1, 6], \"width_mm\": [0, 2000], \"limit\": 20 } ]",
            "\"bands\": []", "'rules[3].bands' (line 18) is empty");
    refused("\"name\": \"bow\",", "", "missing field 'rules[4].name'");
    refused("  ]\n}", "  ]\n", "ends early (truncated?)");
    refused("\"rules\": [", "\"rules\": 3, \"x\": [", "unknown field 'x' (line 5)");
    refused("\"test grade\"", "7", "field 'name' (line 4) must be a string, found a number");
}

/* ---------------------------------------------------------------------- */
/* A sheet judged                                                          */
/* ---------------------------------------------------------------------- */

static double get(const flt_verdict *v, size_t rule, flt_verdict_value key) {
    double d = -12345;
    OK(flt_verdict_get(v, rule, key, &d));
    return d;
}

/* A 3 m sheet, 41 fibers 1500 mm wide: a wave along of amplitude 1 mm and
 * period 800 mm on every fiber, times a crossbow-like cosine across
 * (1 + 0.2 cos(2 pi x / 1600)) so the fibers differ; a hole of samples
 * without data. */
static void sheet_against_rules(void **state) {
    (void)state;
    enum { R = 3001, K = 41 };
    const double A = 1.0, P = 800.0;
    double *s = malloc(R * sizeof *s), x[K];
    double *z = malloc((size_t)R * K * sizeof *z);
    uint8_t *flags = calloc((size_t)R * K, 1);
    for (size_t k = 0; k < K; ++k)
        x[k] = -750.0 + 37.5 * (double)k;
    for (size_t r = 0; r < R; ++r) {
        s[r] = 1000.0 + (double)r;
        for (size_t k = 0; k < K; ++k)
            z[r * K + k] = A * (1.0 + 0.2 * cos(2.0 * PI * x[k] / 1600.0)) *
                           cos(2.0 * PI * (s[r] - 1000.0) / P);
    }
    /* A hole at one trough (s = 2200) of the fiber at x = 0 (k = 20): NaN
     * with FLT_FLAG_NO_DATA, left out; the other troughs still show the
     * wave. */
    for (size_t r = 1150; r < 1250; ++r) {
        z[r * K + 20] = NAN;
        flags[r * K + 20] = FLT_FLAG_NO_DATA;
    }
    flt_rules *rules = load(k_rules);
    flt_verdict *v = NULL;
    OK(flt_verdict_create(rules, &v));
    flt_rules_destroy(rules); /* the verdict keeps its own copy */
    size_t failed = 99;
    assert_int_equal(flt_verdict_failed(v, &failed), FLT_ERR_STATE);
    OK(flt_verdict_set_measure(v, FLT_MEASURE_ZONE_I_UNITS, 12.5, -300.0, 2500.0));
    OK(flt_verdict_set_measure(v, FLT_MEASURE_BOW, -2.5, 0.0, 2500.0));
    OK(flt_verdict_set_measure(v, FLT_MEASURE_CROSSBOW, 0.4, 0.0, 2500.0));
    OK(flt_verdict_evaluate(v, 2.0, 1500.0, R, K, s, x, z, flags));

    /* Rule 0, 1 m along (band 0, limit 3.5): the straightedge bridges the
     * 800 mm wave on the fiber of largest amplitude, x = 0 (1.2 mm): 2.4 mm
     * deep, at a trough (s - 1000 = 400 + 800 j). */
    const double a0 = 1.2 * A;
    assert_int_equal(get(v, 0, FLT_VERDICT_STATE), FLT_VERDICT_PASS);
    assert_int_equal(get(v, 0, FLT_VERDICT_BAND), 0);
    assert_true(get(v, 0, FLT_VERDICT_LIMIT) == 3.5);
    assert_true(get(v, 0, FLT_VERDICT_LENGTH) == 1000.0);
    assert_int_equal(get(v, 0, FLT_VERDICT_MEASURE), FLT_MEASURE_STRAIGHTEDGE_ALONG);
    /* Tolerance: cos()'s rounding on heights of about 1 mm. */
    assert_true(fabs(get(v, 0, FLT_VERDICT_WORST) - 2.0 * a0) < 1e-12);
    assert_true(fabs(get(v, 0, FLT_VERDICT_MARGIN) - (3.5 - 2.0 * a0)) < 1e-12);
    assert_true(get(v, 0, FLT_VERDICT_X) == 0.0);
    const double s0 = get(v, 0, FLT_VERDICT_S);
    assert_true(fabs(cos(2.0 * PI * (s0 - 1000.0) / P) + 1.0) < 1e-12);
    /* Not at the trough in the hole. */
    assert_true(s0 != 2200.0);

    /* Rule 1, 250 mm along (limit 1.5): shorter than the period, it dips
     * into the wave: 1.2 (1 - cos(pi 250 / 800)) = 0.5952 mm. */
    const double d1 = a0 * (1.0 - cos(PI * 250.0 / P));
    assert_int_equal(get(v, 1, FLT_VERDICT_STATE), FLT_VERDICT_PASS);
    assert_true(fabs(get(v, 1, FLT_VERDICT_WORST) - d1) < 1e-12);

    /* Rule 2, 1 m across (limit 1 mm): a row is c (1 + 0.2 cos(2 pi x /
     * 1600)) with c = cos(2 pi (s - 1000) / 800): a valley across where
     * c = -1 (the troughs along), 0.2 deep at x = 0. The straightedge of
     * 1000 mm bridges the fibers about +-500 mm from the centre: the gap is
     * close to 0.2 (1 - cos(pi 1000 / 1600)) = 0.2765 mm (the fibers lie
     * every 37.5 mm, not at +-500). Checked against the profile function
     * on the row at s = 1400 (c = -1), and the worst row is a trough. */
    assert_int_equal(get(v, 2, FLT_VERDICT_STATE), FLT_VERDICT_PASS);
    {
        double row[K], d = 0;
        for (size_t k = 0; k < K; ++k)
            row[k] = z[400 * K + k];
        OK(flt_straightedge_profile(x, row, K, 1000.0, &d, NULL));
        assert_true(fabs(d - 0.2 * (1 - cos(PI * 1000.0 / 1600.0))) < 0.01);
        /* Rounding of c = -1 between the trough rows. */
        assert_true(fabs(get(v, 2, FLT_VERDICT_WORST) - d) < 1e-12);
        const double s2 = get(v, 2, FLT_VERDICT_S);
        assert_true(fabs(cos(2.0 * PI * (s2 - 1000.0) / P) + 1.0) < 1e-12);
        assert_true(fabs(get(v, 2, FLT_VERDICT_X)) < 37.5);
    }

    /* Rule 3, I-Units 12.5 <= 20 at the position given. */
    assert_int_equal(get(v, 3, FLT_VERDICT_STATE), FLT_VERDICT_PASS);
    assert_true(get(v, 3, FLT_VERDICT_WORST) == 12.5);
    assert_true(get(v, 3, FLT_VERDICT_MARGIN) == 7.5);
    assert_true(get(v, 3, FLT_VERDICT_X) == -300.0);
    assert_true(get(v, 3, FLT_VERDICT_S) == 2500.0);
    assert_true(get(v, 3, FLT_VERDICT_LENGTH) == 0.0);
    /* Rule 4, bow: its magnitude 2.5 > 2 fails by 0.5. */
    assert_int_equal(get(v, 4, FLT_VERDICT_STATE), FLT_VERDICT_FAIL);
    assert_true(get(v, 4, FLT_VERDICT_WORST) == 2.5);
    assert_true(get(v, 4, FLT_VERDICT_MARGIN) == -0.5);
    /* Rule 5, crossbow: only for strip 1800 mm and wider. */
    assert_int_equal(get(v, 5, FLT_VERDICT_STATE), FLT_VERDICT_NO_BAND);
    assert_true(get(v, 5, FLT_VERDICT_BAND) == -1.0);
    assert_true(isnan(get(v, 5, FLT_VERDICT_LIMIT)));
    assert_true(isnan(get(v, 5, FLT_VERDICT_WORST)));
    OK(flt_verdict_failed(v, &failed));
    assert_int_equal(failed, 1);

    /* 4 mm thick: band 1 of rule 0 (limit 5); 1.9 m wide: rule 5 applies
     * and bow, no longer measured, is NOT_MEASURED; without a map the
     * straightedges are not measured either. */
    OK(flt_verdict_set_measure(v, FLT_MEASURE_BOW, NAN, NAN, NAN));
    OK(flt_verdict_evaluate(v, 4.0, 1900.0, R, K, s, x, z, flags));
    assert_int_equal(get(v, 0, FLT_VERDICT_BAND), 1);
    assert_true(get(v, 0, FLT_VERDICT_LIMIT) == 5.0);
    assert_int_equal(get(v, 4, FLT_VERDICT_STATE), FLT_VERDICT_NOT_MEASURED);
    assert_int_equal(get(v, 5, FLT_VERDICT_STATE), FLT_VERDICT_PASS);
    assert_true(get(v, 5, FLT_VERDICT_WORST) == 0.4);
    OK(flt_verdict_failed(v, &failed));
    assert_int_equal(failed, 0);
    OK(flt_verdict_evaluate(v, 4.0, 1900.0, 0, 0, NULL, NULL, NULL, NULL));
    assert_int_equal(get(v, 0, FLT_VERDICT_STATE), FLT_VERDICT_NOT_MEASURED);
    assert_true(isnan(get(v, 0, FLT_VERDICT_WORST)));
    /* Thinner than every band: nothing applies. */
    OK(flt_verdict_evaluate(v, 0.5, 1500.0, R, K, s, x, z, flags));
    for (size_t i = 0; i < 6; ++i)
        assert_int_equal(get(v, i, FLT_VERDICT_STATE), FLT_VERDICT_NO_BAND);

    flt_verdict_destroy(v);
    free(s);
    free(z);
    free(flags);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(sine_under_short_and_long_straightedges),
        cmocka_unit_test(equals_the_definition),
        cmocka_unit_test(small_profiles),
        cmocka_unit_test(random_profiles_equal_the_definition),
        cmocka_unit_test(maps_equal_the_definition_line_by_line),
        cmocka_unit_test(rule_file_is_read),
        cmocka_unit_test(rule_file_errors_name_the_field),
        cmocka_unit_test(sheet_against_rules),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
