// SPDX-License-Identifier: Apache-2.0
/* Links the installed libflatline from plain C and reconstructs a sine. */
#include <math.h>
#include <stdio.h>

#include <flatline/flatline.h>

#define ROWS   200
#define FIBERS 3

int main(void) {
    static double s[ROWS], h[ROWS * FIBERS], g[ROWS * FIBERS], z[ROWS * FIBERS];
    const double pi = 3.14159265358979323846, period = 1800.0, half = 50.0;
    for (int r = 0; r < ROWS; ++r) {
        s[r] = 3.0 * r;
        for (int k = 0; k < FIBERS; ++k) {
            double a = 5.0 * sin(2 * pi * (s[r] - half) / period);
            double b = 5.0 * sin(2 * pi * (s[r] + half) / period);
            h[r * FIBERS + k] = 0.5 * (a + b);
            g[r * FIBERS + k] = (b - a) / (2 * half);
        }
    }
    if (flt_reconstruct(NULL, ROWS, FIBERS, s, h, g, NULL, z, NULL) != FLT_OK) {
        printf("consumer: %s\n", flt_last_error_message());
        return 1;
    }
    double worst = 0;
    for (int r = 0; r < ROWS; ++r)
        for (int k = 0; k < FIBERS; ++k)
            worst = fmax(worst, fabs(z[r * FIBERS + k] - 5.0 * sin(2 * pi * s[r] / period)));
    /* 1 um: the noise-free accuracy the reconstructor promises. */
    printf("consumer: flatline %s reconstructed %d rows, max error %.3g mm %s\n",
           flt_version_string(), ROWS, worst, worst < 1e-3 ? "OK" : "FAIL");
    return worst < 1e-3 ? 0 : 1;
}
