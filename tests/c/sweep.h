// SPDX-License-Identifier: Apache-2.0
/*
 * Test helper: statistical sweeps and the sanitizer builds.
 *
 * A few accuracy tests are sweeps: a figure (a classification rate, a
 * worst error) taken over many simulated sheets, all through the same
 * code that shorter tests of the same file take on one sheet. They run in
 * the dev build and under wine. The sanitizer builds (asan, tsan; CMake
 * defines FLT_TEST_SANITIZED there) check memory and undefined behaviour
 * at 5-20 times the CPU, and a sweep's hundredth sheet shows them nothing
 * its first did not, so there such a test skips (CMocka's skip()) with a
 * message saying so. A sweep calls FLT_SWEEP_NOT_UNDER_SANITIZERS() first.
 */
#ifndef FLT_TEST_SWEEP_H
#define FLT_TEST_SWEEP_H

#include <stdio.h>

#ifdef FLT_TEST_SANITIZED
#  define FLT_SWEEP_NOT_UNDER_SANITIZERS()                                                    \
    do {                                                                                      \
      fprintf(stderr, "skipped under the sanitizers: a statistical sweep (sweep.h); it runs " \
                      "in the dev and Windows stages\n");                                     \
      skip();                                                                                 \
    } while (0)
#else
#  define FLT_SWEEP_NOT_UNDER_SANITIZERS() ((void)0)
#endif

#endif
