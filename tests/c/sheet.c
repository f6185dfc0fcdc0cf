// SPDX-License-Identifier: Apache-2.0
#include "sheet.h"

#include <math.h>
#include <stdlib.h>

static const double k_pi = 3.14159265358979323846;

void test_rng_seed(test_rng *rng, unsigned seed) {
    rng->state = 0x9E3779B97F4A7C15ull ^ ((uint64_t)seed * 0xD1B54A32D192ED03ull);
    if (rng->state == 0)
        rng->state = 1;
}

double test_rng_uniform(test_rng *rng) {
    uint64_t x = rng->state;
    x ^= x >> 12;
    x ^= x << 25;
    x ^= x >> 27;
    rng->state = x;
    return (double)((x * 0x2545F4914F6CDD1Dull) >> 11) * (1.0 / 9007199254740992.0);
}

double test_rng_gauss(test_rng *rng) {
    double u1 = test_rng_uniform(rng), u2 = test_rng_uniform(rng);
    if (u1 < 1e-300)
        u1 = 1e-300;
    return sqrt(-2.0 * log(u1)) * cos(2.0 * k_pi * u2);
}

double test_surface(double x, double s) {
    return 12.0 * sin(2.0 * k_pi * s / 1800.0) * cos(2.0 * k_pi * x / 1500.0);
}

test_sheet *test_sheet_make(size_t rows, size_t fibers, double s0, double dx, double jitter,
                            double pitch, double laser_spacing, unsigned seed) {
    test_sheet *t = calloc(1, sizeof *t);
    test_rng rng;
    test_rng_seed(&rng, seed);
    t->rows = rows;
    t->fibers = fibers;
    t->laser_spacing = laser_spacing;
    t->s = malloc(rows * sizeof(double));
    t->x = malloc(fibers * sizeof(double));
    t->truth = malloc(rows * fibers * sizeof(double));
    t->height = malloc(rows * fibers * sizeof(double));
    t->slope = malloc(rows * fibers * sizeof(double));
    t->valid = malloc(rows * fibers);
    for (size_t k = 0; k < fibers; ++k)
        t->x[k] = ((double)k - 0.5 * (double)(fibers - 1)) * pitch;
    for (size_t r = 0; r < rows; ++r) {
        double j = jitter > 0 ? jitter * dx * (2.0 * test_rng_uniform(&rng) - 1.0) : 0.0;
        t->s[r] = s0 + (double)r * dx + j;
    }
    const double h = 0.5 * laser_spacing;
    for (size_t r = 0; r < rows; ++r)
        for (size_t k = 0; k < fibers; ++k) {
            double x = t->x[k], s = t->s[r];
            double behind = test_surface(x, s - h), ahead = test_surface(x, s + h);
            t->truth[r * fibers + k] = test_surface(x, s);
            t->height[r * fibers + k] = 0.5 * (behind + ahead);
            t->slope[r * fibers + k] = (ahead - behind) / laser_spacing;
            t->valid[r * fibers + k] = 1;
        }
    return t;
}

void test_sheet_add_noise(test_sheet *t, double vib_sigma, double peak_sigma, unsigned seed) {
    test_rng rng;
    test_rng_seed(&rng, seed);
    for (size_t r = 0; r < t->rows; ++r) {
        double heave = vib_sigma * test_rng_gauss(&rng);
        for (size_t k = 0; k < t->fibers; ++k) {
            double ea = peak_sigma * test_rng_gauss(&rng);
            double eb = peak_sigma * test_rng_gauss(&rng);
            t->height[r * t->fibers + k] += heave + 0.5 * (ea + eb);
            t->slope[r * t->fibers + k] += (ea - eb) / t->laser_spacing;
        }
    }
}

static double shear_wave(double p, double amplitude, double decay, double period, double interval) {
    double cut = floor(p / interval) * interval;
    if (cut <= 0.0)
        return 0.0;
    double u = p - cut;
    return amplitude * exp(-decay * u) * sin(2.0 * k_pi * u / period);
}

void test_sheet_add_shear(test_sheet *t, double amplitude, double decay, double period,
                          double interval) {
    const double h = 0.5 * t->laser_spacing;
    for (size_t r = 0; r < t->rows; ++r) {
        double behind = shear_wave(t->s[r] - h, amplitude, decay, period, interval);
        double ahead = shear_wave(t->s[r] + h, amplitude, decay, period, interval);
        for (size_t k = 0; k < t->fibers; ++k) {
            t->height[r * t->fibers + k] += 0.5 * (behind + ahead);
            t->slope[r * t->fibers + k] += (ahead - behind) / t->laser_spacing;
        }
    }
}

void test_sheet_add_eccentricity(test_sheet *t, double amplitude, double period) {
    for (size_t r = 0; r < t->rows; ++r) {
        double e = amplitude * sin(2.0 * k_pi * t->s[r] / period);
        for (size_t k = 0; k < t->fibers; ++k)
            t->height[r * t->fibers + k] += e;
    }
}

void test_sheet_free(test_sheet *t) {
    if (!t)
        return;
    free(t->s);
    free(t->x);
    free(t->truth);
    free(t->height);
    free(t->slope);
    free(t->valid);
    free(t);
}

void test_error(const test_sheet *t, const double *z, size_t r0, size_t r1, double *max_err,
                double *rms_err) {
    double mx = 0, sum = 0;
    size_t n = 0;
    for (size_t r = r0; r < r1; ++r)
        for (size_t k = 0; k < t->fibers; ++k) {
            double e = fabs(z[r * t->fibers + k] - t->truth[r * t->fibers + k]);
            if (e > mx || isnan(e))
                mx = isnan(e) ? INFINITY : e;
            sum += e * e;
            ++n;
        }
    *max_err = mx;
    *rms_err = sqrt(sum / (double)(n ? n : 1));
}
