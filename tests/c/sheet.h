// SPDX-License-Identifier: Apache-2.0
/*
 * Test helper: the reference's synthetic sheet and a two-laser measurement
 * of it (the reference article's synthetic sheet, docs/README.md).
 *
 * Surface: z(x, s) = A sin(2 pi s / P_s) cos(2 pi x / P_x), x centred on the
 * strip, so the centre fibers buckle while the edges wave in opposite phase:
 * a centre buckle with wavy edges, amplitude A = 12 mm, P_s = 1800 mm along
 * travel and P_x = 1500 mm across.
 */
#ifndef FLT_TEST_SHEET_H
#define FLT_TEST_SHEET_H

#include <stddef.h>
#include <stdint.h>

typedef struct test_sheet {
    size_t rows, fibers;
    double laser_spacing; /* Delta-d, mm */
    double *s;            /* [rows] */
    double *x;            /* [fibers] */
    double *truth;        /* [rows * fibers] z at (x, s) */
    double *height;       /* [rows * fibers] measured */
    double *slope;        /* [rows * fibers] measured */
    uint8_t *valid;       /* [rows * fibers] */
} test_sheet;

/* The exact surface, mm. */
double test_surface(double x, double s);

/* Rows at s0 + r * dx (+ jitter * dx * U(-1, 1) when jitter > 0), fibers at
 * pitch across width (x centred). Noise-free two-laser measurement. */
test_sheet *test_sheet_make(size_t rows, size_t fibers, double s0, double dx, double jitter,
                            double pitch, double laser_spacing, unsigned seed);

/* Adds per-frame rigid heave N(0, vib_sigma) to every height of a row and
 * independent per-laser peak noise N(0, peak_sigma) (mm) to each laser's
 * reading, which enters the height as the mean and the slope as the
 * difference over Delta-d. */
void test_sheet_add_noise(test_sheet *sheet, double vib_sigma, double peak_sigma, unsigned seed);

/* The reference's hard case, as physics has it ("model b" of
 * examples/python/compare_filters.py): after
 * every cut (at multiples of `interval` mm of material) the strip rings with
 * a damped sine, amplitude * exp(-decay * u) * sin(2 pi u / period) at u mm
 * past the cut. It travels with the material, so each laser reads it at its
 * own position s -+ Delta-d/2: the height gets the mean, the slope the
 * difference over Delta-d. Adds it to every fiber. */
void test_sheet_add_shear(test_sheet *sheet, double amplitude, double decay, double period,
                          double interval);

/* Roll eccentricity: a rigid offset amplitude * sin(2 pi s / period) of the
 * whole frame at s (both lasers alike, so only the heights see it). */
void test_sheet_add_eccentricity(test_sheet *sheet, double amplitude, double period);

void test_sheet_free(test_sheet *sheet);

/* Max and RMS of |z - truth| over the valid rows [r0, r1) and all fibers. */
void test_error(const test_sheet *sheet, const double *z, size_t r0, size_t r1, double *max_err,
                double *rms_err);

/* A small deterministic PRNG (xorshift64*) with Gaussian draws. */
typedef struct test_rng {
    uint64_t state;
} test_rng;
void test_rng_seed(test_rng *rng, unsigned seed);
double test_rng_uniform(test_rng *rng); /* [0, 1) */
double test_rng_gauss(test_rng *rng);   /* N(0, 1) */

#endif
