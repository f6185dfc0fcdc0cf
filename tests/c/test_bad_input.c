// SPDX-License-Identifier: Apache-2.0
/*
 * The bad-input matrix: every exported function of libflatline (and of its
 * testing library, flatline/testing.h) against the inputs a careless or
 * hostile caller gives it.
 *
 * The table at the bottom has one row per public function. Each row's
 * check runs the relevant cases for that function:
 *   - NULL handles, NULL buffers, NULL outputs;
 *   - zero, "negative" ((size_t)-1) and overflowing sizes (rows * fibers *
 *     sizeof(double) past SIZE_MAX);
 *   - NaN and infinity in options, arguments and data;
 *   - wrong pixel formats, sizes and strides;
 *   - truncated and garbage files and texts;
 *   - calls in the wrong order (pull before push, boundary before end_sheet,
 *     setters after finish, source_next before start, ...).
 * Every bad call must return the documented status, leave
 * flt_last_error_status() equal to it, and leave a message that names the
 * function and the problem (a substring is checked); then a valid call on
 * the same handle must succeed (the handle stayed usable).
 *
 * Completeness: the test reads the dynamic symbol tables of the loaded
 * libflatline and libflatline_testing (ELF .dynsym found through dladdr on
 * Linux, the PE export directory found through GetModuleHandleEx on
 * Windows) and fails when an exported function has no row, or a row names
 * a function that neither exports, or libflatline exports a test double
 * (flt_u3v_sim_*, flt_leveler_sim_*). A new public function cannot land
 * without its row.
 *
 * Known bugs: a case that returns the wrong status is written with
 * KNOWN_BUG(...) and reported, not silently dropped; it must keep failing
 * (an unexpected pass fails the test, so the mark is removed once fixed).
 * A case that crashes is written with KNOWN_CRASH(...) and only runs with
 * FLT_BAD_INPUT_CRASHERS=1 in the environment.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <zlib.h>
#ifdef _WIN32
#  include <windows.h>
#else
#  include <dlfcn.h>
#  include <elf.h>
#endif

#include "flatline/flatline.h"
#include "flatline/testing.h"
#include "test_files.h"

/* ---------------------------------------------------------------------- */
/* Checking                                                                */
/* ---------------------------------------------------------------------- */

static const char *g_fn = ""; /* the row being checked */
static int g_failures = 0;
static int g_checks = 0;
static int g_known = 0;

#define ERR(...)                                            \
  do {                                                      \
    fprintf(stderr, "FAIL %s (line %d): ", g_fn, __LINE__); \
    fprintf(stderr, __VA_ARGS__);                           \
    fputc('\n', stderr);                                    \
    ++g_failures;                                           \
  } while (0)

/* A bad call: the status, the thread's last status and a message naming
 * the function and containing `needle`. */
static int check_fail(int line, const char *expr, flt_status got, flt_status want,
                      const char *needle, int quiet) {
    const char *msg = flt_last_error_message();
    char why[512] = "", fn[128];
    /* The function that must be named: the one called, when the expression
     * is a direct call, else the row's. */
    size_t n = strcspn(expr, "( ");
    if (strncmp(expr, "flt_", 4) == 0 && n < sizeof fn && expr[n] == '(') {
        memcpy(fn, expr, n);
        fn[n] = 0;
    } else {
        snprintf(fn, sizeof fn, "%s", g_fn);
    }
    if (got != want)
        snprintf(why, sizeof why, "returned %s, expected %s", flt_status_string(got),
                 flt_status_string(want));
    else if (flt_last_error_status() != want)
        snprintf(why, sizeof why, "flt_last_error_status() = %s",
                 flt_status_string(flt_last_error_status()));
    else if (strstr(msg, fn) == NULL)
        snprintf(why, sizeof why, "message does not name %s", fn);
    else if (needle && strstr(msg, needle) == NULL)
        snprintf(why, sizeof why, "message lacks \"%s\"", needle);
    ++g_checks;
    if (why[0] && !quiet) {
        fprintf(stderr, "FAIL %s (line %d): %s\n    call: %s\n    message: \"%s\"\n", g_fn, line,
                why, expr, msg);
        ++g_failures;
    }
    return why[0] == 0;
}

static int check_ok(int line, const char *expr, flt_status got) {
    ++g_checks;
    if (got != FLT_OK) {
        fprintf(stderr, "FAIL %s (line %d): valid call returned %s: %s\n    call: %s\n", g_fn, line,
                flt_status_string(got), flt_last_error_message(), expr);
        ++g_failures;
        return 0;
    }
    if (flt_last_error_message()[0] != 0 || flt_last_error_status() != FLT_OK) {
        fprintf(stderr, "FAIL %s (line %d): success left message \"%s\"\n    call: %s\n", g_fn,
                line, flt_last_error_message(), expr);
        ++g_failures;
        return 0;
    }
    return 1;
}

#define BAD(want, needle, call) check_fail(__LINE__, #call, (call), (want), (needle), 0)
#define GOOD(call)              check_ok(__LINE__, #call, (call))

/* A case that is known to be wrong and was reported: it must still be wrong
 * (if it passes, the bug was fixed: remove the mark). */
#define KNOWN_BUG(report, want, needle, call)                                             \
  do {                                                                                    \
    ++g_known;                                                                            \
    if (check_fail(__LINE__, #call, (call), (want), (needle), 1)) {                       \
      ERR("KNOWN_BUG now passes (%s): turn it into BAD()", report);                       \
    } else {                                                                              \
      fprintf(stderr, "known bug (reported) %s line %d: %s\n    message: \"%s\"\n", g_fn, \
              __LINE__, report, flt_last_error_message());                                \
    }                                                                                     \
  } while (0)
/* An enum value outside the C++ range of its type. In C an enum argument
 * is a plain int; the library receives it as a C++ enum, whose values are
 * only those of the smallest bit-field holding every enumerator: with the
 * MAX_ENUM_ = 0x7FFFFFFF sentinel that is 0 .. 2^31 - 1, so a negative value
 * of any flt_ enum but flt_status is outside it, and so is anything above 3
 * for flt_calib_target. The library reads such arguments' bytes as an int
 * before using them as the enum (lib/core/error.hpp, enum_arg), so these
 * cases run under UBSan's -fsanitize=enum too. */
#define ENUM_UB_BAD(want, needle, call) BAD(want, needle, call)

/* A case that crashes: written, reported, run only on request. */
#define KNOWN_CRASH(report, want, needle, call)                                                    \
  do {                                                                                             \
    ++g_known;                                                                                     \
    if (getenv("FLT_BAD_INPUT_CRASHERS")) {                                                        \
      BAD(want, needle, call);                                                                     \
    } else {                                                                                       \
      fprintf(stderr, "known crash (reported, not run) %s line %d: %s\n", g_fn, __LINE__, report); \
    }                                                                                              \
  } while (0)

/* ---------------------------------------------------------------------- */
/* Fixtures                                                                */
/* ---------------------------------------------------------------------- */

/* The reference sensor read out as a 2048 x 240 px ROI around both lines
 * (rows 900..1139; the lines sit near rows 996 and 1044 at z = 0), with
 * 101 fibers 20 mm apart: small frames, the real geometry. */
enum { ROI_FIRST = 900, ROI_ROWS = 240, FIBERS = 101, WIDTH = 2048 };
static const double FIRST_X = -1000.0, PITCH = 20.0;

static flt_calib *g_calib; /* finished */
static flt_sim *g_sim;     /* over g_calib */
static uint8_t *g_frame;   /* one rendered Mono8 frame */
static double g_frame_encoder;
static char g_dir[256]; /* scratch folder */
static char g_calib_text[8192];
static size_t g_calib_text_length;

static const double NaN_ = NAN;
static const double Inf_ = INFINITY;
static const size_t NEG = (size_t)-1; /* -1 passed as size_t */
/* rows such that rows * FIBERS * sizeof(double) overflows size_t */
static size_t overflow_rows(size_t fibers) {
    return SIZE_MAX / sizeof(double) / fibers + 1;
}

static flt_options *options_with(flt_option key, double value) {
    flt_options *o = NULL;
    if (flt_options_create(&o) != FLT_OK || flt_options_set(o, key, value) != FLT_OK) {
        fprintf(stderr, "fixture: cannot set option %d = %g\n", (int)key, value);
        exit(2);
    }
    return o;
}

static void path_in_dir(char *out, size_t n, const char *name) {
    snprintf(out, n, "%s/%s", g_dir, name);
}

static void write_file(const char *path, const void *bytes, size_t n) {
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(bytes, 1, n, f) != n || fclose(f) != 0) {
        fprintf(stderr, "fixture: cannot write %s\n", path);
        exit(2);
    }
}

/* A grey 8-bit PNG (zlib-compressed IDAT), for the image sources. */
static void be32(uint8_t *p, uint32_t v) {
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
}
static void write_png(const char *path, const uint8_t *pixels, uint32_t w, uint32_t h) {
    size_t raw_n = (size_t)h * (w + 1);
    uint8_t *raw = malloc(raw_n);
    uLongf z_n = compressBound((uLong)raw_n);
    uint8_t *png = malloc(z_n + 64);
    for (uint32_t r = 0; r < h; ++r) {
        raw[r * (w + 1)] = 0;
        memcpy(raw + r * (w + 1) + 1, pixels + (size_t)r * w, w);
    }
    static const uint8_t sig[8] = {137, 80, 78, 71, 13, 10, 26, 10};
    size_t n = 0;
    memcpy(png, sig, 8);
    n = 8;
    /* IHDR */
    be32(png + n, 13);
    memcpy(png + n + 4, "IHDR", 4);
    be32(png + n + 8, w);
    be32(png + n + 12, h);
    png[n + 16] = 8;
    png[n + 17] = 0;
    png[n + 18] = 0;
    png[n + 19] = 0;
    png[n + 20] = 0;
    be32(png + n + 21, (uint32_t)crc32(0, png + n + 4, 17));
    n += 25;
    /* IDAT */
    if (compress(png + n + 8, &z_n, raw, (uLong)raw_n) != Z_OK)
        exit(2);
    be32(png + n, (uint32_t)z_n);
    memcpy(png + n + 4, "IDAT", 4);
    be32(png + n + 8 + z_n, (uint32_t)crc32(0, png + n + 4, (uInt)(z_n + 4)));
    n += 12 + z_n;
    /* IEND */
    be32(png + n, 0);
    memcpy(png + n + 4, "IEND", 4);
    be32(png + n + 8, (uint32_t)crc32(0, png + n + 4, 4));
    n += 12;
    write_file(path, png, n);
    free(raw);
    free(png);
}

static void setup(void) {
    if (tf_temp_dir(g_dir, sizeof g_dir, "bad_input") != 0)
        exit(2);
    if (flt_calib_create_reference(ROI_FIRST, ROI_ROWS, FIRST_X, PITCH, FIBERS, &g_calib) ||
        flt_sim_create(g_calib, NULL, &g_sim) ||
        flt_sim_add_defect(g_sim, FLT_SIM_CENTRE_BUCKLE, 2.0, 1500.0)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    g_frame = malloc((size_t)WIDTH * ROI_ROWS);
    if (flt_sim_next_frame(g_sim, g_frame, (size_t)WIDTH * ROI_ROWS, WIDTH, &g_frame_encoder, 0,
                           NULL, NULL, 0) ||
        flt_calib_save_text(g_calib, g_calib_text, sizeof g_calib_text, &g_calib_text_length)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
}

static void teardown(void) {
    if (tf_remove_tree(g_dir) != 0)
        fprintf(stderr, "could not remove %s\n", g_dir);
    free(g_frame);
    flt_sim_destroy(g_sim);
    flt_calib_destroy(g_calib);
}

/* A few profile rows of the simulated line. */
typedef struct rows_t {
    size_t rows;
    double s[64], h[64 * FIBERS], k[64 * FIBERS];
} rows_t;
static rows_t g_rows;
static void make_rows(size_t rows) {
    g_rows.rows = rows;
    if (flt_sim_rewind(g_sim) ||
        flt_sim_next_rows(g_sim, rows, FIBERS, NULL, g_rows.s, g_rows.h, g_rows.k, NULL, NULL)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
}

/* ---------------------------------------------------------------------- */
/* common.h                                                                */
/* ---------------------------------------------------------------------- */

static void row_status_string(void) {
    /* Never NULL, for known and unknown codes. */
    const flt_status codes[] = {FLT_OK,
                                FLT_ERR_INVALID_ARGUMENT,
                                FLT_ERR_INTERNAL,
                                (flt_status)-12345,
                                (flt_status)INT32_MIN,
                                (flt_status)INT32_MAX};
    for (size_t i = 0; i < sizeof codes / sizeof codes[0]; ++i) {
        const char *s = flt_status_string(codes[i]);
        ++g_checks;
        if (s == NULL || s[0] == 0)
            ERR("flt_status_string(%d) is empty", (int)codes[i]);
    }
    ++g_checks;
    if (strcmp(flt_status_string((flt_status)-12345), "FLT_ERR_UNKNOWN") != 0)
        ERR("unknown code gives \"%s\"", flt_status_string((flt_status)-12345));
}

static void row_last_error_message(void) {
    flt_options *o = NULL;
    g_fn = "flt_options_set";
    GOOD(flt_options_create(&o));
    BAD(FLT_ERR_INVALID_ARGUMENT, "NaN", flt_options_set(o, FLT_OPT_MAX_GAP, NaN_));
    g_fn = "flt_last_error_message";
    ++g_checks;
    if (strstr(flt_last_error_message(), "max_gap") == NULL)
        ERR("message lost: \"%s\"", flt_last_error_message());
    /* Cleared by the next successful call. */
    double v;
    g_fn = "flt_options_get";
    GOOD(flt_options_get(o, FLT_OPT_MAX_GAP, &v));
    g_fn = "flt_last_error_message";
    ++g_checks;
    if (flt_last_error_message() == NULL || flt_last_error_message()[0] != 0)
        ERR("not cleared after a success");
    flt_options_destroy(o);
}

static void row_last_error_status(void) {
    flt_options *o = NULL;
    g_fn = "flt_options_get";
    BAD(FLT_ERR_INVALID_ARGUMENT, "'options'", flt_options_get(NULL, FLT_OPT_MAX_GAP, NULL));
    g_fn = "flt_last_error_status";
    ++g_checks;
    if (flt_last_error_status() != FLT_ERR_INVALID_ARGUMENT)
        ERR("not the last status");
    g_fn = "flt_options_create";
    GOOD(flt_options_create(&o));
    g_fn = "flt_last_error_status";
    ++g_checks;
    if (flt_last_error_status() != FLT_OK)
        ERR("not FLT_OK after a success");
    flt_options_destroy(o);
}

static void row_set_last_error(void) {
    /* A failing status with a message; the message may be the library's own
     * buffer; NULL and "" give the status's name; a long one is cut;
     * FLT_OK clears; any int is a status. */
    g_fn = "flt_set_last_error";
    flt_set_last_error(FLT_ERR_DEVICE, "flt_set_last_error: relayed");
    ++g_checks;
    if (flt_last_error_status() != FLT_ERR_DEVICE ||
        strcmp(flt_last_error_message(), "flt_set_last_error: relayed") != 0)
        ERR("not recorded: %s \"%s\"", flt_status_string(flt_last_error_status()),
            flt_last_error_message());
    flt_set_last_error(FLT_ERR_TIMEOUT, flt_last_error_message());
    ++g_checks;
    if (flt_last_error_status() != FLT_ERR_TIMEOUT ||
        strcmp(flt_last_error_message(), "flt_set_last_error: relayed") != 0)
        ERR("its own message not kept: \"%s\"", flt_last_error_message());
    ++g_checks;
    flt_set_last_error(FLT_ERR_IO, NULL);
    if (flt_last_error_status() != FLT_ERR_IO ||
        strcmp(flt_last_error_message(), "failed with FLT_ERR_IO") != 0)
        ERR("NULL message: \"%s\"", flt_last_error_message());
    ++g_checks;
    flt_set_last_error((flt_status)-12345, "");
    if (flt_last_error_status() != (flt_status)-12345 ||
        strcmp(flt_last_error_message(), "failed with FLT_ERR_UNKNOWN") != 0)
        ERR("unknown status: \"%s\"", flt_last_error_message());
    char longer[2000];
    memset(longer, 'x', sizeof longer - 1);
    longer[sizeof longer - 1] = 0;
    flt_set_last_error(FLT_ERR_FORMAT, longer);
    ++g_checks;
    if (strlen(flt_last_error_message()) != 511)
        ERR("a 1999-byte message kept %zu bytes", strlen(flt_last_error_message()));
    flt_set_last_error(FLT_OK, "ignored");
    ++g_checks;
    if (flt_last_error_status() != FLT_OK || flt_last_error_message()[0] != 0)
        ERR("FLT_OK did not clear: \"%s\"", flt_last_error_message());
}

static void row_version(void) {
    ++g_checks;
    if (flt_version() != FLT_VERSION_NUMBER)
        ERR("flt_version() = %d", flt_version());
}

static void row_version_string(void) {
    ++g_checks;
    if (strcmp(flt_version_string(), FLT_VERSION_STRING) != 0)
        ERR("flt_version_string() = %s", flt_version_string());
}

static void row_options_create(void) {
    flt_options *o = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_options_create(NULL));
    GOOD(flt_options_create(&o));
    flt_options_destroy(o);
}

static void row_options_destroy(void) {
    flt_options_destroy(NULL); /* no-op */
    ++g_checks;
}

static void row_options_set(void) {
    flt_options *o = NULL;
    GOOD(flt_options_create(&o));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'options'", flt_options_set(NULL, FLT_OPT_MAX_GAP, 1.0));
    /* An unknown key: FLT_ERR_NOT_FOUND, as from flt_options_get and
     * flt_option_info. */
    BAD(FLT_ERR_NOT_FOUND, "unknown option key", flt_options_set(o, (flt_option)99, 1.0));
    BAD(FLT_ERR_NOT_FOUND, "unknown option key", flt_options_set(o, FLT_OPT_MAX_ENUM_, 1.0));
    ENUM_UB_BAD(FLT_ERR_NOT_FOUND, "unknown option key", flt_options_set(o, (flt_option)-1, 1.0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "is NaN", flt_options_set(o, FLT_OPT_LASER_SPACING, NaN_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "outside", flt_options_set(o, FLT_OPT_LASER_SPACING, Inf_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "outside", flt_options_set(o, FLT_OPT_LASER_SPACING, -Inf_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "outside", flt_options_set(o, FLT_OPT_LASER_SPACING, -100.0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "outside", flt_options_set(o, FLT_OPT_LASER_SPACING, 1e300));
    BAD(FLT_ERR_INVALID_ARGUMENT, "whole number", flt_options_set(o, FLT_OPT_LAG_KNOTS, 2.5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "outside", flt_options_set(o, FLT_OPT_ROW_CAPACITY, 1e300));
    /* The bag is unchanged by the failures. */
    double v = 0;
    GOOD(flt_options_get(o, FLT_OPT_LASER_SPACING, &v));
    ++g_checks;
    if (v != 100.0)
        ERR("laser_spacing changed to %g by failed sets", v);
    GOOD(flt_options_set(o, FLT_OPT_LASER_SPACING, 90.0));
    /* max_gap takes +infinity (its documented upper bound). */
    GOOD(flt_options_set(o, FLT_OPT_MAX_GAP, Inf_));
    flt_options_destroy(o);
}

static void row_options_get(void) {
    flt_options *o = NULL;
    double v;
    GOOD(flt_options_create(&o));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'options'", flt_options_get(NULL, FLT_OPT_MAX_GAP, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_options_get(o, FLT_OPT_MAX_GAP, NULL));
    BAD(FLT_ERR_NOT_FOUND, "unknown option key", flt_options_get(o, (flt_option)12345, &v));
    ENUM_UB_BAD(FLT_ERR_NOT_FOUND, "unknown option key -7", flt_options_get(o, (flt_option)-7, &v));
    GOOD(flt_options_get(o, FLT_OPT_MAX_GAP, &v));
    flt_options_destroy(o);
}

static void row_option_find(void) {
    flt_option k;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'name'", flt_option_find(NULL, &k));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_option_find("max_gap", NULL));
    BAD(FLT_ERR_NOT_FOUND, "no_such_key", flt_option_find("no_such_key", &k));
    BAD(FLT_ERR_NOT_FOUND, "no option", flt_option_find("", &k));
    /* A long garbage name is quoted truncated, not overflowed. */
    char longname[5000];
    memset(longname, 'x', sizeof longname - 1);
    longname[sizeof longname - 1] = 0;
    BAD(FLT_ERR_NOT_FOUND, "xxxx", flt_option_find(longname, &k));
    GOOD(flt_option_find("max_gap", &k));
}

static void row_option_info(void) {
    const char *name;
    BAD(FLT_ERR_NOT_FOUND, "unknown option key",
        flt_option_info((flt_option)0, &name, NULL, NULL, NULL, NULL));
    BAD(FLT_ERR_NOT_FOUND, "unknown option key",
        flt_option_info(FLT_OPT_MAX_ENUM_, &name, NULL, NULL, NULL, NULL));
    ENUM_UB_BAD(FLT_ERR_NOT_FOUND, "unknown option key -1",
                flt_option_info((flt_option)-1, &name, NULL, NULL, NULL, NULL));
    GOOD(flt_option_info(FLT_OPT_MAX_GAP, NULL, NULL, NULL, NULL, NULL));
}

static void row_option_choice_at(void) {
    const char *name = NULL;
    int value = -1;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'name_out'",
        flt_option_choice_at(FLT_OPT_ROBUST, 0, NULL, NULL));
    BAD(FLT_ERR_NOT_FOUND, "unknown option key",
        flt_option_choice_at((flt_option)99, 0, &name, NULL));
    BAD(FLT_ERR_NOT_FOUND, "unknown option key",
        flt_option_choice_at(FLT_OPT_MAX_ENUM_, 0, &name, NULL));
    ENUM_UB_BAD(FLT_ERR_NOT_FOUND, "unknown option key -1",
                flt_option_choice_at((flt_option)-1, 0, &name, NULL));
    BAD(FLT_ERR_NOT_FOUND, "'max_gap' is a number",
        flt_option_choice_at(FLT_OPT_MAX_GAP, 0, &name, NULL));
    BAD(FLT_ERR_NOT_FOUND, "past the last of the 3 choices",
        flt_option_choice_at(FLT_OPT_ROBUST, 3, &name, &value));
    BAD(FLT_ERR_NOT_FOUND, "past the last", flt_option_choice_at(FLT_OPT_ROBUST, NEG, &name, NULL));
    GOOD(flt_option_choice_at(FLT_OPT_ROBUST, 1, &name, &value));
    ++g_checks;
    if (strcmp(name, "huber") != 0 || value != FLT_ROBUST_HUBER)
        ERR("robust's choice 1 is '%s' = %d, expected 'huber' = 1", name, value);
    GOOD(flt_option_choice_at(FLT_OPT_ROBUST, 0, &name, NULL)); /* value_out may be NULL */
}

static void row_option_at(void) {
    flt_option k;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_option_at(0, NULL));
    BAD(FLT_ERR_NOT_FOUND, "past the last", flt_option_at(NEG, &k));
    BAD(FLT_ERR_NOT_FOUND, "past the last", flt_option_at(100000, &k));
    GOOD(flt_option_at(0, &k));
}

/* ---------------------------------------------------------------------- */
/* recon.h                                                                 */
/* ---------------------------------------------------------------------- */

static flt_recon *new_recon(void) {
    flt_recon *r = NULL;
    if (flt_recon_create(FIBERS, NULL, &r) != FLT_OK) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    return r;
}

static void row_recon_create(void) {
    flt_recon *r = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_recon_create(FIBERS, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers' is 0", flt_recon_create(0, NULL, &r));
    ++g_checks;
    if (r != NULL)
        ERR("*out not NULL after a failure");
    /* (size_t)-1 fibers times row_capacity doubles cannot exist. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "too large", flt_recon_create(NEG, NULL, &r));
    BAD(FLT_ERR_INVALID_ARGUMENT, "too large", flt_recon_create(SIZE_MAX / 8 / 8192 + 1, NULL, &r));
    /* Inconsistent options: knots far finer than the laser spacing. */
    flt_options *o = options_with(FLT_OPT_KNOT_SPACING, 0.001);
    BAD(FLT_ERR_INVALID_ARGUMENT, "knot_spacing", flt_recon_create(FIBERS, o, &r));
    flt_options_destroy(o);
    /* Another component's option: it would do nothing here. */
    o = options_with(FLT_OPT_FLAT_REFERENCE, FLT_FLAT_REFERENCE_MEAN);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flat_reference' belongs to flatness, not to the reconstructor",
        flt_recon_create(FIBERS, o, &r));
    flt_options_destroy(o);
    /* One fiber more than a real sensor could have. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "too large", flt_recon_create(FLT_MAX_FIBERS + 1, NULL, &r));
    /* Buffers beyond FLT_RECON_MAX_BYTES (1e7 rows x 2.5e3 fibers x 9 bytes
     * = 225 GB): refused before anything is allocated, whatever the
     * system's overcommit policy (an allocation granted untouched would take
     * the machine page by page once written). */
    o = options_with(FLT_OPT_ROW_CAPACITY, 1e7);
    BAD(FLT_ERR_INVALID_ARGUMENT, "GB", flt_recon_create(2500, o, &r));
    flt_options_destroy(o);
    /* lag_knots at its bound with many fibers: the knot rings alone
     * (100,000 knots x 17 doubles x 16384 fibers = 220 GB). */
    o = options_with(FLT_OPT_LAG_KNOTS, 100000);
    BAD(FLT_ERR_INVALID_ARGUMENT, "lag_knots", flt_recon_create(FLT_MAX_FIBERS, o, &r));
    flt_options_destroy(o);
    GOOD(flt_recon_create(FIBERS, NULL, &r));
    flt_recon_destroy(r);
}

static void row_recon_destroy(void) {
    flt_recon_destroy(NULL);
    ++g_checks;
}

static void row_recon_fibers(void) {
    flt_recon *r = new_recon();
    size_t n;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recon' is NULL", flt_recon_fibers(NULL, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_recon_fibers(r, NULL));
    /* A pointer to something that is not a handle is caught by the magic. */
    uint64_t junk[8] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live", flt_recon_fibers((const flt_recon *)junk, &n));
    GOOD(flt_recon_fibers(r, &n));
    flt_recon_destroy(r);
}

static void row_recon_get_option(void) {
    flt_recon *r = new_recon();
    double v;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recon'", flt_recon_get_option(NULL, FLT_OPT_MAX_GAP, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_recon_get_option(r, FLT_OPT_MAX_GAP, NULL));
    /* Another component's key is a wrong argument; an unknown one is not
     * found, as everywhere. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim_seed' belongs to the simulator, not to the reconstructor",
        flt_recon_get_option(r, FLT_OPT_SIM_SEED, &v));
    BAD(FLT_ERR_NOT_FOUND, "unknown option key", flt_recon_get_option(r, FLT_OPT_MAX_ENUM_, &v));
    BAD(FLT_ERR_NOT_FOUND, "unknown option key 199", flt_recon_get_option(r, (flt_option)199, &v));
    ENUM_UB_BAD(FLT_ERR_NOT_FOUND, "option key -2", flt_recon_get_option(r, (flt_option)-2, &v));
    GOOD(flt_recon_get_option(r, FLT_OPT_KNOT_SPACING, &v));
    flt_recon_destroy(r);
}

static void row_recon_push(void) {
    flt_recon *r = new_recon();
    make_rows(8);
    double *s = g_rows.s, *h = g_rows.h, *k = g_rows.k;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recon'", flt_recon_push(NULL, 8, FIBERS, s, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'s'", flt_recon_push(r, 8, FIBERS, NULL, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height'", flt_recon_push(r, 8, FIBERS, s, NULL, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'slope'", flt_recon_push(r, 8, FIBERS, s, h, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows' is 0", flt_recon_push(r, 0, FIBERS, s, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers' is 0", flt_recon_push(r, 8, 0, s, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_recon_push(r, 8, FIBERS + 1, s, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflows", flt_recon_push(r, NEG, FIBERS, s, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflows",
        flt_recon_push(r, overflow_rows(FIBERS), FIBERS, s, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflows", flt_recon_push(r, 8, NEG, s, h, k, NULL));
    /* Rows that fit size_t but not the capacity: BUFFER_FULL, nothing read
     * past the arrays (the count is checked before the data). */
    double s_big[1] = {0};
    (void)s_big;
    /* Positions: NaN, infinite, not increasing, a jump of more than 1e6 mm. */
    double bad_s[8];
    memcpy(bad_s, s, sizeof bad_s);
    bad_s[3] = NaN_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "not finite", flt_recon_push(r, 8, FIBERS, bad_s, h, k, NULL));
    bad_s[3] = Inf_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "not finite", flt_recon_push(r, 8, FIBERS, bad_s, h, k, NULL));
    bad_s[3] = s[1];
    BAD(FLT_ERR_INVALID_ARGUMENT, "increas", flt_recon_push(r, 8, FIBERS, bad_s, h, k, NULL));
    memcpy(bad_s, s, sizeof bad_s);
    for (int i = 4; i < 8; ++i)
        bad_s[i] = s[i] + 1e7;
    BAD(FLT_ERR_INVALID_ARGUMENT, "flt_recon_reset",
        flt_recon_push(r, 8, FIBERS, bad_s, h, k, NULL));
    /* NaN / Inf / huge data are invalid samples, not errors: they are
     * flagged (recon.h, "Validity"). */
    double *hh = malloc(sizeof(double) * 8 * FIBERS);
    memcpy(hh, h, sizeof(double) * 8 * FIBERS);
    hh[0] = NaN_;
    hh[1] = Inf_;
    hh[2] = -Inf_;
    hh[3] = 1e308;
    hh[4] = -1e308;
    GOOD(flt_recon_push(r, 8, FIBERS, s, hh, k, NULL));
    /* The block is checked whole: a bad row late in it pushes nothing. */
    double s2[8];
    for (int i = 0; i < 8; ++i)
        s2[i] = s[7] + 3.0 * (i + 1);
    s2[7] = s2[6];
    BAD(FLT_ERR_INVALID_ARGUMENT, "s[7]", flt_recon_push(r, 8, FIBERS, s2, h, k, NULL));
    /* Rows before the last pushed are refused across calls. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "increas", flt_recon_push(r, 8, FIBERS, s, h, k, NULL));
    s2[7] = s2[6] + 3.0;
    GOOD(flt_recon_push(r, 8, FIBERS, s2, h, k, NULL));
    /* Capacity: more rows than row_capacity = 16. */
    flt_recon *small = NULL;
    flt_options *o = options_with(FLT_OPT_ROW_CAPACITY, 16);
    GOOD(flt_recon_create(FIBERS, o, &small));
    double *s40 = malloc(sizeof(double) * 40), *h40 = calloc(40 * FIBERS, sizeof(double));
    for (int i = 0; i < 40; ++i)
        s40[i] = 3.0 * i;
    BAD(FLT_ERR_BUFFER_FULL, "row_capacity",
        flt_recon_push(small, 40, FIBERS, s40, h40, h40, NULL));
    GOOD(flt_recon_push(small, 16, FIBERS, s40, h40, h40, NULL));
    flt_recon_destroy(small);
    flt_options_destroy(o);
    free(s40);
    free(h40);
    free(hh);
    flt_recon_destroy(r);
}

/* push_flagged: push's cases, NULL flags, and off-strip samples pass
 * through (they are not errors). */
static void row_recon_push_flagged(void) {
    flt_recon *r = new_recon();
    make_rows(8);
    double *s = g_rows.s, *h = g_rows.h, *k = g_rows.k;
    uint8_t *flags = calloc(8 * FIBERS, 1);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recon'",
        flt_recon_push_flagged(NULL, 8, FIBERS, s, h, k, flags));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'s'", flt_recon_push_flagged(r, 8, FIBERS, NULL, h, k, flags));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height'",
        flt_recon_push_flagged(r, 8, FIBERS, s, NULL, k, flags));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'slope'",
        flt_recon_push_flagged(r, 8, FIBERS, s, h, NULL, flags));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flags'", flt_recon_push_flagged(r, 8, FIBERS, s, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows' is 0",
        flt_recon_push_flagged(r, 0, FIBERS, s, h, k, flags));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'",
        flt_recon_push_flagged(r, 8, FIBERS + 1, s, h, k, flags));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflows",
        flt_recon_push_flagged(r, NEG, FIBERS, s, h, k, flags));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflows",
        flt_recon_push_flagged(r, overflow_rows(FIBERS), FIBERS, s, h, k, flags));
    double bad_s[8];
    memcpy(bad_s, s, sizeof bad_s);
    bad_s[3] = NaN_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "not finite",
        flt_recon_push_flagged(r, 8, FIBERS, bad_s, h, k, flags));
    /* Every bit pattern is a valid flag byte: off strip, invalid, unknown
     * bits (invalid), all set. */
    for (int i = 0; i < 8 * FIBERS; ++i)
        flags[i] = (uint8_t)(i % 4 == 0   ? FLT_FLAG_OFF_STRIP
                             : i % 4 == 1 ? 0xFF
                             : i % 4 == 2 ? 1
                                          : 0);
    GOOD(flt_recon_push_flagged(r, 8, FIBERS, s, h, k, flags));
    flt_recon_destroy(r);
    free(flags);
}

static void row_recon_pull(void) {
    flt_recon *r = new_recon();
    make_rows(8);
    double s_out[8], *z = malloc(sizeof(double) * 8 * FIBERS);
    uint8_t *flags = malloc(8 * FIBERS);
    size_t n = 99;
    /* Wrong order: pull before any push. */
    BAD(FLT_ERR_STATE, "nothing was pushed", flt_recon_pull(r, 8, FIBERS, s_out, z, flags, &n));
    ++g_checks;
    if (n != 0)
        ERR("rows_out = %zu after a failure", n);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recon'", flt_recon_pull(NULL, 8, FIBERS, s_out, z, flags, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows_out'",
        flt_recon_pull(r, 8, FIBERS, s_out, z, flags, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'s_out'", flt_recon_pull(r, 8, FIBERS, NULL, z, flags, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'z_out'", flt_recon_pull(r, 8, FIBERS, s_out, NULL, flags, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_recon_pull(r, 8, 3, s_out, z, flags, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflows", flt_recon_pull(r, NEG, FIBERS, s_out, z, flags, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflows",
        flt_recon_pull(r, overflow_rows(FIBERS), FIBERS, s_out, z, flags, &n));
    GOOD(flt_recon_push(r, 8, FIBERS, g_rows.s, g_rows.h, g_rows.k, NULL));
    GOOD(flt_recon_pull(r, 8, FIBERS, s_out, z, flags, &n));
    GOOD(flt_recon_pull(r, 0, FIBERS, NULL, NULL, NULL, &n)); /* max_rows 0: NULLs fine */
    /* After reset, pull is again "before push". */
    GOOD(flt_recon_reset(r));
    BAD(FLT_ERR_STATE, "reset", flt_recon_pull(r, 8, FIBERS, s_out, z, flags, &n));
    free(z);
    free(flags);
    flt_recon_destroy(r);
}

static void row_recon_ready(void) {
    flt_recon *r = new_recon();
    size_t n;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recon'", flt_recon_ready(NULL, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_recon_ready(r, NULL));
    GOOD(flt_recon_ready(r, &n));
    flt_recon_destroy(r);
}

static void row_recon_pending(void) {
    flt_recon *r = new_recon();
    size_t n = 99;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recon'", flt_recon_pending(NULL, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_recon_pending(r, NULL));
    GOOD(flt_recon_pending(r, &n));
    ++g_checks;
    if (n != 0)
        ERR("pending = %zu before any push", n);
    flt_recon_destroy(r);
}

static void row_recon_peek(void) {
    flt_recon *r = new_recon();
    make_rows(8);
    double s_out[8], *z = malloc(sizeof(double) * 8 * FIBERS);
    uint8_t *flags = malloc(8 * FIBERS);
    size_t n = 99;
    /* Wrong order: peek before any push. */
    BAD(FLT_ERR_STATE, "nothing was pushed", flt_recon_peek(r, 8, FIBERS, s_out, z, flags, &n));
    ++g_checks;
    if (n != 0)
        ERR("rows_out = %zu after a failure", n);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recon'", flt_recon_peek(NULL, 8, FIBERS, s_out, z, flags, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows_out'",
        flt_recon_peek(r, 8, FIBERS, s_out, z, flags, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'s_out'", flt_recon_peek(r, 8, FIBERS, NULL, z, flags, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'z_out'", flt_recon_peek(r, 8, FIBERS, s_out, NULL, flags, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_recon_peek(r, 8, 3, s_out, z, flags, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflows", flt_recon_peek(r, NEG, FIBERS, s_out, z, flags, &n));
    GOOD(flt_recon_push(r, 8, FIBERS, g_rows.s, g_rows.h, g_rows.k, NULL));
    GOOD(flt_recon_peek(r, 8, FIBERS, s_out, z, flags, &n));
    ++g_checks;
    if (n != 8) /* 8 rows, none finished at the default latency */
        ERR("peek gave %zu of 8 pending rows", n);
    GOOD(flt_recon_peek(r, 0, FIBERS, NULL, NULL, NULL, &n)); /* max_rows 0: NULLs fine */
    GOOD(flt_recon_peek(r, 8, FIBERS, s_out, z, NULL, &n));   /* flags optional */
    GOOD(flt_recon_reset(r));
    BAD(FLT_ERR_STATE, "reset", flt_recon_peek(r, 8, FIBERS, s_out, z, flags, &n));
    free(z);
    free(flags);
    flt_recon_destroy(r);
}

static void row_recon_end_sheet(void) {
    flt_recon *r = new_recon();
    make_rows(8);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recon'", flt_recon_end_sheet(NULL));
    /* Wrong order: end_sheet with nothing pushed, and twice in a row. */
    BAD(FLT_ERR_STATE, "no row was pushed", flt_recon_end_sheet(r));
    GOOD(flt_recon_push(r, 8, FIBERS, g_rows.s, g_rows.h, g_rows.k, NULL));
    GOOD(flt_recon_end_sheet(r));
    BAD(FLT_ERR_STATE, "no row was pushed", flt_recon_end_sheet(r));
    /* The next sheet must continue with larger s. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "increas",
        flt_recon_push(r, 8, FIBERS, g_rows.s, g_rows.h, g_rows.k, NULL));
    GOOD(flt_recon_reset(r));
    GOOD(flt_recon_push(r, 8, FIBERS, g_rows.s, g_rows.h, g_rows.k, NULL));
    GOOD(flt_recon_end_sheet(r));
    flt_recon_destroy(r);
}

static void row_recon_reset(void) {
    flt_recon *r = new_recon();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recon'", flt_recon_reset(NULL));
    GOOD(flt_recon_reset(r));
    GOOD(flt_recon_reset(r)); /* reset of a fresh or reset handle is fine */
    flt_recon_destroy(r);
}

static void row_recon_boundary(void) {
    flt_recon *r = new_recon();
    make_rows(40);
    double s0, *hb = malloc(sizeof(double) * FIBERS), *kb = malloc(sizeof(double) * FIBERS);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recon'", flt_recon_boundary(NULL, FIBERS, &s0, hb, kb));
    /* Wrong order: boundary before any end_sheet. */
    BAD(FLT_ERR_STATE, "no sheet has ended", flt_recon_boundary(r, FIBERS, &s0, hb, kb));
    GOOD(flt_recon_push(r, 40, FIBERS, g_rows.s, g_rows.h, g_rows.k, NULL));
    BAD(FLT_ERR_STATE, "no sheet has ended", flt_recon_boundary(r, FIBERS, &s0, hb, kb));
    GOOD(flt_recon_end_sheet(r));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_recon_boundary(r, 0, &s0, hb, kb));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_recon_boundary(r, NEG, &s0, hb, kb));
    GOOD(flt_recon_boundary(r, FIBERS, &s0, hb, kb));
    GOOD(flt_recon_boundary(r, FIBERS, NULL, NULL, NULL));
    /* reset drops the carry-over. */
    GOOD(flt_recon_reset(r));
    BAD(FLT_ERR_STATE, "no sheet has ended", flt_recon_boundary(r, FIBERS, &s0, hb, kb));
    free(hb);
    free(kb);
    flt_recon_destroy(r);
}

static void row_reconstruct(void) {
    make_rows(40);
    double *s = g_rows.s, *h = g_rows.h, *k = g_rows.k;
    double *z = malloc(sizeof(double) * 40 * FIBERS);
    flt_options *o = options_with(FLT_OPT_SIM_SEED, 3);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim_seed' belongs to the simulator",
        flt_reconstruct(o, 40, FIBERS, s, h, k, NULL, z, NULL));
    flt_options_destroy(o);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'s'",
        flt_reconstruct(NULL, 40, FIBERS, NULL, h, k, NULL, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height'",
        flt_reconstruct(NULL, 40, FIBERS, s, NULL, k, NULL, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'slope'",
        flt_reconstruct(NULL, 40, FIBERS, s, h, NULL, NULL, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'z_out'",
        flt_reconstruct(NULL, 40, FIBERS, s, h, k, NULL, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows' is 0",
        flt_reconstruct(NULL, 0, FIBERS, s, h, k, NULL, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers' is 0",
        flt_reconstruct(NULL, 40, 0, s, h, k, NULL, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflows",
        flt_reconstruct(NULL, NEG, FIBERS, s, h, k, NULL, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflows",
        flt_reconstruct(NULL, overflow_rows(FIBERS), FIBERS, s, h, k, NULL, z, NULL));
    double bad_s[40];
    memcpy(bad_s, s, sizeof bad_s);
    bad_s[39] = NaN_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "not finite",
        flt_reconstruct(NULL, 40, FIBERS, bad_s, h, k, NULL, z, NULL));
    bad_s[39] = bad_s[38];
    BAD(FLT_ERR_INVALID_ARGUMENT, "increas",
        flt_reconstruct(NULL, 40, FIBERS, bad_s, h, k, NULL, z, NULL));
    o = options_with(FLT_OPT_KNOT_SPACING, 0.001);
    BAD(FLT_ERR_INVALID_ARGUMENT, "knot_spacing",
        flt_reconstruct(o, 40, FIBERS, s, h, k, NULL, z, NULL));
    flt_options_destroy(o);
    GOOD(flt_reconstruct(NULL, 40, FIBERS, s, h, k, NULL, z, NULL));
    free(z);
}

static void row_reconstruct_flagged(void) {
    make_rows(40);
    double *s = g_rows.s, *h = g_rows.h, *k = g_rows.k;
    double *z = malloc(sizeof(double) * 40 * FIBERS);
    uint8_t *flags = calloc(40 * FIBERS, 1), *out = malloc(40 * FIBERS);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'s'",
        flt_reconstruct_flagged(NULL, 40, FIBERS, NULL, h, k, flags, z, out));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height'",
        flt_reconstruct_flagged(NULL, 40, FIBERS, s, NULL, k, flags, z, out));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'slope'",
        flt_reconstruct_flagged(NULL, 40, FIBERS, s, h, NULL, flags, z, out));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flags'",
        flt_reconstruct_flagged(NULL, 40, FIBERS, s, h, k, NULL, z, out));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'z_out'",
        flt_reconstruct_flagged(NULL, 40, FIBERS, s, h, k, flags, NULL, out));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows' is 0",
        flt_reconstruct_flagged(NULL, 0, FIBERS, s, h, k, flags, z, out));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflows",
        flt_reconstruct_flagged(NULL, NEG, FIBERS, s, h, k, flags, z, out));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflows",
        flt_reconstruct_flagged(NULL, overflow_rows(FIBERS), FIBERS, s, h, k, flags, z, out));
    double bad_s[40];
    memcpy(bad_s, s, sizeof bad_s);
    bad_s[39] = Inf_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "not finite",
        flt_reconstruct_flagged(NULL, 40, FIBERS, bad_s, h, k, flags, z, out));
    /* A whole fiber off the strip: NaN with its flag, never an error. */
    for (int r = 0; r < 40; ++r)
        flags[r * FIBERS + 2] = FLT_FLAG_OFF_STRIP;
    GOOD(flt_reconstruct_flagged(NULL, 40, FIBERS, s, h, k, flags, z, out));
    ++g_checks;
    if (!(isnan(z[2]) && out[2] == FLT_FLAG_OFF_STRIP))
        ERR("an off-strip sample came out %g with flags %d", z[2], out[2]);
    GOOD(flt_reconstruct_flagged(NULL, 40, FIBERS, s, h, k, flags, z, NULL));
    free(z), free(flags), free(out);
}

static void row_reconstruct_release(void) {
    make_rows(40);
    double *z = malloc(sizeof(double) * 40 * FIBERS);
    /* The working memory a call keeps is freed, and counted; then none is
     * left; NULL for the count is fine; the next call works as before. */
    GOOD(flt_reconstruct(NULL, 40, FIBERS, g_rows.s, g_rows.h, g_rows.k, NULL, z, NULL));
    double bytes = -1;
    GOOD(flt_reconstruct_release(&bytes));
    ++g_checks;
    if (!(bytes > 40.0 * FIBERS * sizeof(double)))
        ERR("freed %g bytes after a call of 40 x %d", bytes, FIBERS);
    GOOD(flt_reconstruct_release(&bytes));
    ++g_checks;
    if (bytes != 0)
        ERR("freed %g bytes from an empty pool", bytes);
    GOOD(flt_reconstruct_release(NULL));
    GOOD(flt_reconstruct(NULL, 40, FIBERS, g_rows.s, g_rows.h, g_rows.k, NULL, z, NULL));
    ++g_checks;
    if (!isfinite(z[0]))
        ERR("z[0] = %g after a release", z[0]);
    free(z);
}

/* ---------------------------------------------------------------------- */
/* calib.h                                                                 */
/* ---------------------------------------------------------------------- */

static const double CAMERA[4] = {1090.9, 1090.9, 1030.25, 119.75};
static double H0[9], H1[9];

static flt_calib *new_unfinished(void) {
    flt_calib *c = NULL;
    if (flt_calib_create(&c))
        exit(2);
    return c;
}

/* An unfinished model with everything set but the fiber grid. */
static flt_calib *almost_finished(void) {
    flt_calib *c = new_unfinished();
    if (flt_calib_set_frame_size(c, WIDTH, ROI_ROWS) ||
        flt_calib_set_intrinsics(c, CAMERA, FLT_CALIB_CAMERA_VALUES, NULL, 0) ||
        flt_calib_set_homography(c, 0, H0, FLT_CALIB_HOMOGRAPHY_ENTRIES) ||
        flt_calib_set_homography(c, 1, H1, FLT_CALIB_HOMOGRAPHY_ENTRIES) ||
        flt_calib_set_laser_offset(c, 0, -50) || flt_calib_set_laser_offset(c, 1, 50) ||
        flt_calib_set_encoder_scale(c, 0.01)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    return c;
}

static void row_calib_create(void) {
    flt_calib *c;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_calib_create(NULL));
    GOOD(flt_calib_create(&c));
    flt_calib_destroy(c);
}

static void row_calib_destroy(void) {
    flt_calib_destroy(NULL);
    ++g_checks;
}

static void row_calib_finish(void) {
    flt_calib *c = almost_finished();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_calib_finish(NULL));
    BAD(FLT_ERR_STATE, "fiber", flt_calib_finish(c)); /* names the missing part */
    GOOD(flt_calib_set_fiber_grid(c, FIRST_X, PITCH, FIBERS));
    /* Lasers 0.5 mm apart: less than FLT_CALIB_MIN_LASER_SPACING_MM. */
    GOOD(flt_calib_set_laser_offset(c, 1, -49.5));
    BAD(FLT_ERR_STATE, "apart", flt_calib_finish(c));
    GOOD(flt_calib_set_laser_offset(c, 1, 50));
    GOOD(flt_calib_finish(c));
    BAD(FLT_ERR_STATE, NULL, flt_calib_finish(c)); /* twice */
    flt_calib_destroy(c);
    c = new_unfinished();
    BAD(FLT_ERR_STATE, "lacks", flt_calib_finish(c));
    flt_calib_destroy(c);
}

static void row_calib_is_finished(void) {
    int f;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_calib_is_finished(NULL, &f));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_calib_is_finished(g_calib, NULL));
    uint64_t junk[16] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live", flt_calib_is_finished((const flt_calib *)junk, &f));
    GOOD(flt_calib_is_finished(g_calib, &f));
}

static void row_calib_set_frame_size(void) {
    flt_calib *c = new_unfinished();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_calib_set_frame_size(NULL, 10, 10));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width'", flt_calib_set_frame_size(c, 0, 10));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height'", flt_calib_set_frame_size(c, 10, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width'", flt_calib_set_frame_size(c, UINT32_MAX, 10));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height'", flt_calib_set_frame_size(c, 10, 65537));
    /* Finite but absurd: a 65536 x 65536 frame is 4.3e9 pixels (the
     * simulator would ask for 17 GB); the limit is FLT_CALIB_MAX_FRAME_SIDE. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width'",
        flt_calib_set_frame_size(c, FLT_CALIB_MAX_FRAME_SIDE + 1, 10));
    GOOD(flt_calib_set_frame_size(c, FLT_CALIB_MAX_FRAME_SIDE, FLT_CALIB_MAX_FRAME_SIDE));
    GOOD(flt_calib_set_frame_size(c, WIDTH, ROI_ROWS));
    /* Wrong order: setters after finish. */
    BAD(FLT_ERR_STATE, "finished", flt_calib_set_frame_size(g_calib, 10, 10));
    flt_calib_destroy(c);
}

static void row_calib_get_frame_size(void) {
    flt_calib *c = new_unfinished();
    uint32_t w, h;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_calib_get_frame_size(NULL, &w, &h));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width_out'", flt_calib_get_frame_size(c, NULL, &h));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height_out'", flt_calib_get_frame_size(c, &w, NULL));
    BAD(FLT_ERR_STATE, "not set", flt_calib_get_frame_size(c, &w, &h));
    GOOD(flt_calib_set_frame_size(c, 64, 64));
    GOOD(flt_calib_get_frame_size(c, &w, &h));
    flt_calib_destroy(c);
}

static void row_calib_set_intrinsics(void) {
    flt_calib *c = new_unfinished();
    double cam[4], dist[8] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'",
        flt_calib_set_intrinsics(NULL, CAMERA, FLT_CALIB_CAMERA_VALUES, NULL, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'camera'", flt_calib_set_intrinsics(c, NULL, 0, NULL, 0));
    memcpy(cam, CAMERA, sizeof cam);
    cam[0] = NaN_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "fx",
        flt_calib_set_intrinsics(c, cam, FLT_CALIB_CAMERA_VALUES, NULL, 0));
    cam[0] = -1.0;
    BAD(FLT_ERR_INVALID_ARGUMENT, "fx",
        flt_calib_set_intrinsics(c, cam, FLT_CALIB_CAMERA_VALUES, NULL, 0));
    cam[0] = CAMERA[0];
    cam[3] = Inf_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "cy",
        flt_calib_set_intrinsics(c, cam, FLT_CALIB_CAMERA_VALUES, NULL, 0));
    cam[3] = CAMERA[3];
    dist[4] = NaN_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "distortion[4]",
        flt_calib_set_intrinsics(c, cam, FLT_CALIB_CAMERA_VALUES, dist,
                                 FLT_CALIB_DISTORTION_COEFFS));
    dist[4] = 0;
    /* Finite but absurd (outside calib.h's ranges); each names its field. */
    cam[0] = 1e300;
    BAD(FLT_ERR_INVALID_ARGUMENT, "fx",
        flt_calib_set_intrinsics(c, cam, FLT_CALIB_CAMERA_VALUES, NULL, 0));
    cam[0] = CAMERA[0];
    cam[1] = 1e-300;
    BAD(FLT_ERR_INVALID_ARGUMENT, "fy",
        flt_calib_set_intrinsics(c, cam, FLT_CALIB_CAMERA_VALUES, NULL, 0));
    cam[1] = CAMERA[1];
    cam[2] = -1e9;
    BAD(FLT_ERR_INVALID_ARGUMENT, "cx",
        flt_calib_set_intrinsics(c, cam, FLT_CALIB_CAMERA_VALUES, NULL, 0));
    cam[2] = CAMERA[2];
    dist[0] = 1e200;
    BAD(FLT_ERR_INVALID_ARGUMENT, "k1",
        flt_calib_set_intrinsics(c, cam, FLT_CALIB_CAMERA_VALUES, dist,
                                 FLT_CALIB_DISTORTION_COEFFS));
    dist[0] = 0;
    dist[3] = 5;
    BAD(FLT_ERR_INVALID_ARGUMENT, "p2",
        flt_calib_set_intrinsics(c, cam, FLT_CALIB_CAMERA_VALUES, dist,
                                 FLT_CALIB_DISTORTION_COEFFS));
    dist[3] = 0;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'camera_count'", flt_calib_set_intrinsics(c, cam, 3, dist, 8));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'camera_count'", flt_calib_set_intrinsics(c, cam, 0, NULL, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'distortion_count'",
        flt_calib_set_intrinsics(c, cam, 4, dist, 5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'distortion_count'",
        flt_calib_set_intrinsics(c, cam, 4, dist, SIZE_MAX));
    GOOD(flt_calib_set_intrinsics(c, cam, FLT_CALIB_CAMERA_VALUES, dist,
                                  FLT_CALIB_DISTORTION_COEFFS));
    BAD(FLT_ERR_STATE, "finished",
        flt_calib_set_intrinsics(g_calib, CAMERA, FLT_CALIB_CAMERA_VALUES, NULL, 0));
    flt_calib_destroy(c);
}

static void row_calib_get_intrinsics(void) {
    flt_calib *c = new_unfinished();
    double cam[4], dist[8];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'",
        flt_calib_get_intrinsics(NULL, cam, FLT_CALIB_CAMERA_VALUES, dist,
                                 FLT_CALIB_DISTORTION_COEFFS));
    BAD(FLT_ERR_STATE, "not set",
        flt_calib_get_intrinsics(c, cam, FLT_CALIB_CAMERA_VALUES, dist,
                                 FLT_CALIB_DISTORTION_COEFFS));
    GOOD(flt_calib_set_intrinsics(c, CAMERA, FLT_CALIB_CAMERA_VALUES, NULL, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'camera_count'", flt_calib_get_intrinsics(c, cam, 5, dist, 8));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'distortion_count'",
        flt_calib_get_intrinsics(c, cam, 4, dist, 4));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'distortion_count'",
        flt_calib_get_intrinsics(c, NULL, 0, dist, 0));
    GOOD(flt_calib_get_intrinsics(c, cam, FLT_CALIB_CAMERA_VALUES, dist,
                                  FLT_CALIB_DISTORTION_COEFFS));
    GOOD(flt_calib_get_intrinsics(c, NULL, 0, NULL, 0));
    GOOD(flt_calib_get_intrinsics(c, cam, 4, NULL, 0));
    flt_calib_destroy(c);
}

static void row_calib_estimate_intrinsics(void) {
    flt_calib *c = new_unfinished();
    double rms;
    /* A blank 64 x 64 image: no target in it. */
    uint8_t *blank = calloc(64 * 64, 1);
    const uint8_t *views[3] = {blank, blank, blank};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'",
        flt_calib_estimate_intrinsics(NULL, 3, views, 64, FLT_TARGET_CHESSBOARD, 9, 6, 10, NULL,
                                      &rms, NULL));
    flt_options *o = options_with(FLT_OPT_ROBUST, FLT_ROBUST_HUBER);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'robust' belongs to the reconstructor, not to calibration",
        flt_calib_estimate_intrinsics(c, 3, views, 64, FLT_TARGET_CHESSBOARD, 9, 6, 10, o, &rms,
                                      NULL));
    flt_options_destroy(o);
    /* Wrong order: the frame size comes first. */
    BAD(FLT_ERR_STATE, "frame size",
        flt_calib_estimate_intrinsics(c, 3, views, 64, FLT_TARGET_CHESSBOARD, 9, 6, 10, NULL, &rms,
                                      NULL));
    GOOD(flt_calib_set_frame_size(c, 64, 64));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'views' is 0",
        flt_calib_estimate_intrinsics(c, 0, views, 64, FLT_TARGET_CHESSBOARD, 9, 6, 10, NULL, &rms,
                                      NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'images'",
        flt_calib_estimate_intrinsics(c, 3, NULL, 64, FLT_TARGET_CHESSBOARD, 9, 6, 10, NULL, &rms,
                                      NULL));
    const uint8_t *with_null[3] = {blank, NULL, blank};
    BAD(FLT_ERR_INVALID_ARGUMENT, "images[1]",
        flt_calib_estimate_intrinsics(c, 3, with_null, 64, FLT_TARGET_CHESSBOARD, 9, 6, 10, NULL,
                                      &rms, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'stride'",
        flt_calib_estimate_intrinsics(c, 3, views, 63, FLT_TARGET_CHESSBOARD, 9, 6, 10, NULL, &rms,
                                      NULL));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'target'",
                flt_calib_estimate_intrinsics(c, 3, views, 64, (flt_calib_target)7, 9, 6, 10, NULL,
                                              &rms, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'columns'",
        flt_calib_estimate_intrinsics(c, 3, views, 64, FLT_TARGET_CHESSBOARD, 2, 6, 10, NULL, &rms,
                                      NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows'",
        flt_calib_estimate_intrinsics(c, 3, views, 64, FLT_TARGET_CHESSBOARD, 9, 0, 10, NULL, &rms,
                                      NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'pitch_mm'",
        flt_calib_estimate_intrinsics(c, 3, views, 64, FLT_TARGET_CHESSBOARD, 9, 6, NaN_, NULL,
                                      &rms, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'pitch_mm'",
        flt_calib_estimate_intrinsics(c, 3, views, 64, FLT_TARGET_CHESSBOARD, 9, 6, -1, NULL, &rms,
                                      NULL));
    /* No target in any view: NUMERIC, model unchanged. */
    BAD(FLT_ERR_NUMERIC, NULL,
        flt_calib_estimate_intrinsics(c, 3, views, 64, FLT_TARGET_CHESSBOARD, 9, 6, 10, NULL, &rms,
                                      NULL));
    double cam[4];
    BAD(FLT_ERR_STATE, "not set",
        flt_calib_get_intrinsics(c, cam, FLT_CALIB_CAMERA_VALUES, NULL, 0));
    g_fn = "flt_calib_estimate_intrinsics";
    BAD(FLT_ERR_STATE, "finished",
        flt_calib_estimate_intrinsics(g_calib, 3, views, 64, FLT_TARGET_CHESSBOARD, 9, 6, 10, NULL,
                                      &rms, NULL));
    GOOD(flt_calib_set_intrinsics(c, CAMERA, FLT_CALIB_CAMERA_VALUES, NULL,
                                  0)); /* the handle is usable */
    free(blank);
    flt_calib_destroy(c);
}

static void row_calib_set_homography(void) {
    flt_calib *c = new_unfinished();
    double h[9];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'",
        flt_calib_set_homography(NULL, 0, H0, FLT_CALIB_HOMOGRAPHY_ENTRIES));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'laser'",
        flt_calib_set_homography(c, 2, H0, FLT_CALIB_HOMOGRAPHY_ENTRIES));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'laser'",
        flt_calib_set_homography(c, UINT32_MAX, H0, FLT_CALIB_HOMOGRAPHY_ENTRIES));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'h'", flt_calib_set_homography(c, 0, NULL, 0));
    memcpy(h, H0, sizeof h);
    h[4] = NaN_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "h[4]",
        flt_calib_set_homography(c, 0, h, FLT_CALIB_HOMOGRAPHY_ENTRIES));
    memset(h, 0, sizeof h);
    BAD(FLT_ERR_INVALID_ARGUMENT, "invertible",
        flt_calib_set_homography(c, 0, h, FLT_CALIB_HOMOGRAPHY_ENTRIES));
    /* Invertible but scaled beyond FLT_CALIB_MAX_HOMOGRAPHY_SCALE (1e100). */
    for (int k = 0; k < 9; ++k)
        h[k] = H0[k] * 1e200;
    BAD(FLT_ERR_INVALID_ARGUMENT, "scale",
        flt_calib_set_homography(c, 0, h, FLT_CALIB_HOMOGRAPHY_ENTRIES));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'h_count'", flt_calib_set_homography(c, 0, H0, 8));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'h_count'", flt_calib_set_homography(c, 0, H0, 0));
    GOOD(flt_calib_set_homography(c, 0, H0, FLT_CALIB_HOMOGRAPHY_ENTRIES));
    BAD(FLT_ERR_STATE, "finished",
        flt_calib_set_homography(g_calib, 0, H0, FLT_CALIB_HOMOGRAPHY_ENTRIES));
    flt_calib_destroy(c);
}

static void row_calib_get_homography(void) {
    flt_calib *c = new_unfinished();
    double h[9];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'",
        flt_calib_get_homography(NULL, 0, h, FLT_CALIB_HOMOGRAPHY_ENTRIES));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'laser'",
        flt_calib_get_homography(g_calib, 2, h, FLT_CALIB_HOMOGRAPHY_ENTRIES));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'h_out'", flt_calib_get_homography(g_calib, 0, NULL, 0));
    BAD(FLT_ERR_STATE, "not set", flt_calib_get_homography(c, 1, h, FLT_CALIB_HOMOGRAPHY_ENTRIES));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'h_count'", flt_calib_get_homography(g_calib, 1, h, 3));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'h_count'", flt_calib_get_homography(g_calib, 1, h, 10));
    GOOD(flt_calib_get_homography(g_calib, 1, h, FLT_CALIB_HOMOGRAPHY_ENTRIES));
    flt_calib_destroy(c);
}

static void row_calib_estimate_homography(void) {
    flt_calib *c = new_unfinished();
    /* Four correspondences of the reference's laser 0 (plane square of
     * 200 mm side mapped into the image). */
    double plane[8] = {-100, -50, 100, -50, 100, 50, -100, 50}, image[8];
    GOOD(flt_calib_plane_to_image(g_calib, 0, 4, plane, image));
    g_fn = "flt_calib_estimate_homography";
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'",
        flt_calib_estimate_homography(NULL, 0, 4, image, plane, NULL, NULL, NULL, NULL, NULL,
                                      NULL));
    flt_options *o = options_with(FLT_OPT_SIM_SEED, 2);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim_seed' belongs to the simulator, not to calibration",
        flt_calib_estimate_homography(c, 0, 4, image, plane, o, NULL, NULL, NULL, NULL, NULL));
    flt_options_destroy(o);
    /* Wrong order: intrinsics first. */
    BAD(FLT_ERR_STATE, "intrinsics",
        flt_calib_estimate_homography(c, 0, 4, image, plane, NULL, NULL, NULL, NULL, NULL, NULL));
    GOOD(flt_calib_set_intrinsics(c, CAMERA, FLT_CALIB_CAMERA_VALUES, NULL, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'laser'",
        flt_calib_estimate_homography(c, 5, 4, image, plane, NULL, NULL, NULL, NULL, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'image_px'",
        flt_calib_estimate_homography(c, 0, 4, NULL, plane, NULL, NULL, NULL, NULL, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'plane_mm'",
        flt_calib_estimate_homography(c, 0, 4, image, NULL, NULL, NULL, NULL, NULL, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count'",
        flt_calib_estimate_homography(c, 0, 3, image, plane, NULL, NULL, NULL, NULL, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, NULL,
        flt_calib_estimate_homography(c, 0, NEG, image, plane, NULL, NULL, NULL, NULL, NULL, NULL));
    double bad[8];
    memcpy(bad, image, sizeof bad);
    bad[5] = NaN_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "image_px",
        flt_calib_estimate_homography(c, 0, 4, bad, plane, NULL, NULL, NULL, NULL, NULL, NULL));
    memcpy(bad, plane, sizeof bad);
    bad[2] = Inf_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "plane_mm",
        flt_calib_estimate_homography(c, 0, 4, image, bad, NULL, NULL, NULL, NULL, NULL, NULL));
    /* Degenerate: all four plane points on one line. */
    double line[8] = {0, 0, 1, 0, 2, 0, 3, 0};
    BAD(FLT_ERR_NUMERIC, NULL,
        flt_calib_estimate_homography(c, 0, 4, image, line, NULL, NULL, NULL, NULL, NULL, NULL));
    GOOD(flt_calib_estimate_homography(c, 0, 4, image, plane, NULL, NULL, NULL, NULL, NULL, NULL));
    BAD(FLT_ERR_STATE, "finished",
        flt_calib_estimate_homography(g_calib, 0, 4, image, plane, NULL, NULL, NULL, NULL, NULL,
                                      NULL));
    flt_calib_destroy(c);
}

static void row_calib_set_laser_offset(void) {
    flt_calib *c = new_unfinished();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_calib_set_laser_offset(NULL, 0, 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'laser'", flt_calib_set_laser_offset(c, 2, 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'offset_mm'", flt_calib_set_laser_offset(c, 0, NaN_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'offset_mm'", flt_calib_set_laser_offset(c, 0, -Inf_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'offset_mm'", flt_calib_set_laser_offset(c, 0, 1e300));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'offset_mm'",
        flt_calib_set_laser_offset(c, 0, -FLT_CALIB_MAX_OFFSET_MM * 1.001));
    GOOD(flt_calib_set_laser_offset(c, 0, -50));
    BAD(FLT_ERR_STATE, "finished", flt_calib_set_laser_offset(g_calib, 0, 1));
    flt_calib_destroy(c);
}

static void row_calib_get_laser_offset(void) {
    flt_calib *c = new_unfinished();
    double v;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_calib_get_laser_offset(NULL, 0, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'laser'", flt_calib_get_laser_offset(g_calib, 9, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_calib_get_laser_offset(g_calib, 0, NULL));
    BAD(FLT_ERR_STATE, "not set", flt_calib_get_laser_offset(c, 0, &v));
    GOOD(flt_calib_get_laser_offset(g_calib, 0, &v));
    flt_calib_destroy(c);
}

static void row_calib_laser_spacing(void) {
    flt_calib *c = new_unfinished();
    double v;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_calib_laser_spacing(NULL, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_calib_laser_spacing(g_calib, NULL));
    GOOD(flt_calib_set_laser_offset(c, 0, -50));
    BAD(FLT_ERR_STATE, "both laser offsets", flt_calib_laser_spacing(c, &v));
    GOOD(flt_calib_laser_spacing(g_calib, &v));
    flt_calib_destroy(c);
}

static void row_calib_set_encoder_scale(void) {
    flt_calib *c = new_unfinished();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_calib_set_encoder_scale(NULL, 0.01));
    BAD(FLT_ERR_INVALID_ARGUMENT, "encoder_mm_per_count", flt_calib_set_encoder_scale(c, 0.0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "encoder_mm_per_count", flt_calib_set_encoder_scale(c, NaN_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "encoder_mm_per_count", flt_calib_set_encoder_scale(c, Inf_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "encoder_mm_per_count", flt_calib_set_encoder_scale(c, 1e-300));
    BAD(FLT_ERR_INVALID_ARGUMENT, "encoder_mm_per_count", flt_calib_set_encoder_scale(c, -1e300));
    GOOD(flt_calib_set_encoder_scale(c, -0.01)); /* counting down is allowed */
    BAD(FLT_ERR_STATE, "finished", flt_calib_set_encoder_scale(g_calib, 0.01));
    flt_calib_destroy(c);
}

static void row_calib_get_encoder_scale(void) {
    flt_calib *c = new_unfinished();
    double v;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_calib_get_encoder_scale(NULL, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_calib_get_encoder_scale(g_calib, NULL));
    BAD(FLT_ERR_STATE, "not set", flt_calib_get_encoder_scale(c, &v));
    GOOD(flt_calib_get_encoder_scale(g_calib, &v));
    flt_calib_destroy(c);
}

static void row_calib_set_fiber_grid(void) {
    flt_calib *c = new_unfinished();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_calib_set_fiber_grid(NULL, 0, 1, 10));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'first_x_mm'", flt_calib_set_fiber_grid(c, NaN_, 1, 10));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'pitch_mm'", flt_calib_set_fiber_grid(c, 0, 0, 10));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'pitch_mm'", flt_calib_set_fiber_grid(c, 0, -2, 10));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'pitch_mm'", flt_calib_set_fiber_grid(c, 0, Inf_, 10));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count'", flt_calib_set_fiber_grid(c, 0, 1, 0));
    /* Finite but absurd: a pitch of 1e-300 mm (the extractor's resampling
     * index overflowed), 2^32 mm (the flatness zones asked for 138 GB), 1e8
     * fibers (11 s and 5.6 GB per extractor), a grid 1e300 mm off centre,
     * a last fiber beyond FLT_CALIB_MAX_X_MM, (size_t)-1 fibers. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "'pitch_mm'", flt_calib_set_fiber_grid(c, 0, 1e-300, 10));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'pitch_mm'", flt_calib_set_fiber_grid(c, 0, 4294967296.0, 10));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count'", flt_calib_set_fiber_grid(c, 0, 1, 100000000));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count'", flt_calib_set_fiber_grid(c, 0, 1, NEG));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'first_x_mm'", flt_calib_set_fiber_grid(c, 1e300, 1, 10));
    BAD(FLT_ERR_INVALID_ARGUMENT, "last fiber",
        flt_calib_set_fiber_grid(c, 0, FLT_CALIB_MAX_PITCH_MM, FLT_MAX_FIBERS));
    GOOD(flt_calib_set_fiber_grid(c, -FLT_CALIB_MAX_X_MM, FLT_CALIB_MIN_PITCH_MM, FLT_MAX_FIBERS));
    GOOD(flt_calib_set_fiber_grid(c, 0, 1, 10));
    BAD(FLT_ERR_STATE, "finished", flt_calib_set_fiber_grid(g_calib, 0, 1, 10));
    flt_calib_destroy(c);
}

static void row_calib_get_fiber_grid(void) {
    flt_calib *c = new_unfinished();
    double a, b;
    size_t n;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_calib_get_fiber_grid(NULL, &a, &b, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'first_x_mm_out'",
        flt_calib_get_fiber_grid(g_calib, NULL, &b, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'pitch_mm_out'",
        flt_calib_get_fiber_grid(g_calib, &a, NULL, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count_out'", flt_calib_get_fiber_grid(g_calib, &a, &b, NULL));
    BAD(FLT_ERR_STATE, "not set", flt_calib_get_fiber_grid(c, &a, &b, &n));
    GOOD(flt_calib_get_fiber_grid(g_calib, &a, &b, &n));
    flt_calib_destroy(c);
}

/* image_to_plane, plane_to_image, undistort share their argument checks. */
typedef flt_status (*map_fn)(const flt_calib *, unsigned, size_t, const double *, double *);
static flt_status undistort_as_map(const flt_calib *c, unsigned laser, size_t n, const double *in,
                                   double *out) {
    (void)laser;
    return flt_calib_undistort(c, n, in, out);
}

static void check_map(map_fn f, const char *in_name, const char *out_name, int needs_finish) {
    flt_calib *c = almost_finished();
    double in[4] = {1000, 100, NaN_, Inf_}, out[4];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", f(NULL, 0, 2, in, out));
    if (f != undistort_as_map)
        BAD(FLT_ERR_INVALID_ARGUMENT, "'laser'", f(g_calib, 2, 2, in, out));
    BAD(FLT_ERR_INVALID_ARGUMENT, in_name, f(g_calib, 0, 2, NULL, out));
    BAD(FLT_ERR_INVALID_ARGUMENT, out_name, f(g_calib, 0, 2, in, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count'", f(g_calib, 0, NEG, in, out));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count'", f(g_calib, 0, SIZE_MAX / 16 + 1, in, out));
    if (needs_finish)
        BAD(FLT_ERR_STATE, "finished", f(c, 0, 2, in, out));
    GOOD(f(g_calib, 0, 0, NULL, NULL)); /* count 0 does nothing */
    GOOD(f(g_calib, 0, 2, in, out));    /* NaN / Inf points give NaN */
    ++g_checks;
    if (!isnan(out[2]) || !isnan(out[3]))
        ERR("a non-finite point mapped to (%g, %g), not NaN", out[2], out[3]);
    flt_calib_destroy(c);
}

static void row_calib_image_to_plane(void) {
    check_map(flt_calib_image_to_plane, "'image_px'", "'plane_out'", 1);
}
static void row_calib_plane_to_image(void) {
    check_map(flt_calib_plane_to_image, "'plane_mm'", "'image_out'", 1);
}
static void row_calib_undistort(void) {
    check_map(undistort_as_map, "'image_px'", "'undistorted_out'", 0);
    flt_calib *c = new_unfinished();
    double in[2] = {1, 1}, out[2];
    BAD(FLT_ERR_STATE, "intrinsics", flt_calib_undistort(c, 1, in, out));
    flt_calib_destroy(c);
}

static void row_calib_save(void) {
    char path[300];
    flt_calib *c = almost_finished();
    path_in_dir(path, sizeof path, "calib.json");
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_calib_save(NULL, path));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'path'", flt_calib_save(g_calib, NULL));
    BAD(FLT_ERR_STATE, "finished", flt_calib_save(c, path));
    BAD(FLT_ERR_IO, "no_such_dir", flt_calib_save(g_calib, "/nonexistent/no_such_dir/c.json"));
    BAD(FLT_ERR_IO, NULL, flt_calib_save(g_calib, ""));
    GOOD(flt_calib_save(g_calib, path));
    flt_calib_destroy(c);
}

static void row_calib_save_text(void) {
    flt_calib *c = almost_finished();
    char buf[16];
    size_t n = 0;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_calib_save_text(NULL, buf, sizeof buf, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'length_out'",
        flt_calib_save_text(g_calib, buf, sizeof buf, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'text_out'", flt_calib_save_text(g_calib, NULL, 10, &n));
    BAD(FLT_ERR_STATE, "finished", flt_calib_save_text(c, buf, sizeof buf, &n));
    BAD(FLT_ERR_BUFFER_FULL, NULL, flt_calib_save_text(g_calib, buf, sizeof buf, &n));
    ++g_checks;
    if (n != g_calib_text_length)
        ERR("length_out = %zu on BUFFER_FULL", n);
    /* Asking for the size: BUFFER_FULL with the length (calib.h). */
    n = 0;
    BAD(FLT_ERR_BUFFER_FULL, NULL, flt_calib_save_text(g_calib, NULL, 0, &n));
    ++g_checks;
    if (n != g_calib_text_length)
        ERR("length_out = %zu when asking for the size", n);
    GOOD(flt_calib_save_text(g_calib, g_calib_text, sizeof g_calib_text, &n));
    flt_calib_destroy(c);
}

static void row_calib_load_text(void) {
    flt_calib *c = (flt_calib *)1;
    const char *t = g_calib_text;
    const size_t n = g_calib_text_length;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_calib_load_text(t, n, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'text'", flt_calib_load_text(NULL, n, &c));
    ++g_checks;
    if (c != NULL)
        ERR("*out not NULL after a failure");
    BAD(FLT_ERR_FORMAT, NULL, flt_calib_load_text(t, 0, &c));
    /* Truncated at every 97th byte: always FORMAT, never an object. */
    for (size_t cut = 1; cut < n; cut += 97) {
        c = (flt_calib *)1;
        if (!BAD(FLT_ERR_FORMAT, NULL, flt_calib_load_text(t, cut, &c)))
            break;
        ++g_checks;
        if (c != NULL) {
            ERR("truncated at %zu gave an object", cut);
            break;
        }
    }
    /* Garbage: binary noise, deep nesting, a huge number, NaN spelled out. */
    char garbage[4096];
    uint32_t x = 12345;
    for (size_t i = 0; i < sizeof garbage; ++i) {
        x = x * 1103515245u + 12345u;
        garbage[i] = (char)(x >> 16);
    }
    BAD(FLT_ERR_FORMAT, NULL, flt_calib_load_text(garbage, sizeof garbage, &c));
    memset(garbage, '[', sizeof garbage);
    BAD(FLT_ERR_FORMAT, NULL, flt_calib_load_text(garbage, sizeof garbage, &c));
    memset(garbage, '{', sizeof garbage);
    BAD(FLT_ERR_FORMAT, NULL, flt_calib_load_text(garbage, sizeof garbage, &c));
    /* Field-level damage is named (calib.h, "File format"). */
    char *edit = malloc(n + 64);
    const char *at = strstr(t, "\"fx\": ");
    if (at) {
        size_t head = (size_t)(at - t) + 6;
        memcpy(edit, t, head);
        const char *rest = strchr(at + 6, ',');
        size_t m = head + (size_t)sprintf(edit + head, "NaN");
        memcpy(edit + m, rest, n - (size_t)(rest - t));
        BAD(FLT_ERR_FORMAT, "fx", flt_calib_load_text(edit, m + n - (size_t)(rest - t), &c));
        m = head + (size_t)sprintf(edit + head, "1e999");
        memcpy(edit + m, rest, n - (size_t)(rest - t));
        BAD(FLT_ERR_FORMAT, "fx", flt_calib_load_text(edit, m + n - (size_t)(rest - t), &c));
    } else {
        ERR("fixture text has no \"fx\"");
    }
    at = strstr(t, "\"version\": 1");
    if (at) {
        memcpy(edit, t, n);
        edit[(at - t) + 11] = '7';
        BAD(FLT_ERR_FORMAT, "version", flt_calib_load_text(edit, n, &c));
    }
    /* Embedded NUL in the middle. */
    memcpy(edit, t, n);
    edit[n / 2] = 0;
    BAD(FLT_ERR_FORMAT, NULL, flt_calib_load_text(edit, n, &c));
    free(edit);
    GOOD(flt_calib_load_text(t, n, &c));
    flt_calib_destroy(c);
}

static void row_calib_load(void) {
    flt_calib *c = (flt_calib *)1;
    char path[300], trunc_path[300];
    path_in_dir(path, sizeof path, "load.json");
    write_file(path, g_calib_text, g_calib_text_length);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_calib_load(path, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'path'", flt_calib_load(NULL, &c));
    BAD(FLT_ERR_IO, "no_such_file", flt_calib_load("/nonexistent/no_such_file.json", &c));
    BAD(FLT_ERR_IO, NULL, flt_calib_load(g_dir, &c)); /* a directory */
    path_in_dir(trunc_path, sizeof trunc_path, "truncated.json");
    write_file(trunc_path, g_calib_text, g_calib_text_length / 3);
    BAD(FLT_ERR_FORMAT, "truncated.json", flt_calib_load(trunc_path, &c));
    write_file(trunc_path, "", 0);
    BAD(FLT_ERR_FORMAT, NULL, flt_calib_load(trunc_path, &c));
    write_file(trunc_path, "\x89PNG\r\n\x1a\n\0\0\0", 11);
    BAD(FLT_ERR_FORMAT, NULL, flt_calib_load(trunc_path, &c));
    ++g_checks;
    if (c != NULL)
        ERR("*out not NULL after a failure");
    GOOD(flt_calib_load(path, &c));
    flt_calib_destroy(c);
}

/* sim.h declares it. */
static void row_calib_create_reference(void) {
    flt_calib *c = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'",
        flt_calib_create_reference(0, 2048, -1000, 2, 1001, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows'", flt_calib_create_reference(0, 0, -1000, 2, 1001, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, NULL, flt_calib_create_reference(2000, 100, -1000, 2, 1001, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, NULL,
        flt_calib_create_reference(UINT32_MAX, 2, -1000, 2, 1001, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'pitch_mm'",
        flt_calib_create_reference(0, 2048, -1000, 0, 1001, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'pitch_mm'",
        flt_calib_create_reference(0, 2048, -1000, NaN_, 1001, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'first_x_mm'",
        flt_calib_create_reference(0, 2048, Inf_, 2, 1001, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers' is 0",
        flt_calib_create_reference(0, 2048, -1000, 2, 0, &c));
    GOOD(flt_calib_create_reference(0, 2048, -1000, 2, 1001, &c));
    flt_calib_destroy(c);
}

/* ---------------------------------------------------------------------- */
/* extractor.h                                                             */
/* ---------------------------------------------------------------------- */

static flt_extractor *new_extractor(void) {
    flt_extractor *e = NULL;
    if (flt_extractor_create(g_calib, NULL, &e)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    return e;
}

static void row_extractor_create(void) {
    flt_extractor *e = NULL;
    flt_calib *c = almost_finished();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_extractor_create(g_calib, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_extractor_create(NULL, NULL, &e));
    BAD(FLT_ERR_STATE, "not finished", flt_extractor_create(c, NULL, &e));
    flt_options *o = options_with(FLT_OPT_SIM_LINE_SIGMA, 1.5);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim_line_sigma' belongs to the simulator, not to the extractor",
        flt_extractor_create(g_calib, o, &e));
    flt_options_destroy(o);
    o = options_with(FLT_OPT_EXTRACT_SG_WINDOW, 10);
    BAD(FLT_ERR_INVALID_ARGUMENT, "extract_sg_window", flt_extractor_create(g_calib, o, &e));
    GOOD(flt_options_set(o, FLT_OPT_EXTRACT_SG_WINDOW, 5));
    GOOD(flt_options_set(o, FLT_OPT_EXTRACT_SG_ORDER, 6));
    BAD(FLT_ERR_INVALID_ARGUMENT, "extract_sg_order", flt_extractor_create(g_calib, o, &e));
    flt_options_destroy(o);
    o = options_with(FLT_OPT_EXTRACT_LASER0_ROWS, 100);
    GOOD(flt_options_set(o, FLT_OPT_EXTRACT_LASER0_FIRST_ROW, 200));
    GOOD(flt_options_set(o, FLT_OPT_EXTRACT_LASER1_ROWS, 100));
    BAD(FLT_ERR_INVALID_ARGUMENT, "frame height", flt_extractor_create(g_calib, o, &e));
    GOOD(flt_options_set(o, FLT_OPT_EXTRACT_LASER0_FIRST_ROW, 0));
    GOOD(flt_options_set(o, FLT_OPT_EXTRACT_LASER1_ROWS, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "both bands", flt_extractor_create(g_calib, o, &e));
    GOOD(flt_options_set(o, FLT_OPT_EXTRACT_LASER0_ROWS, 5));
    GOOD(flt_options_set(o, FLT_OPT_EXTRACT_LASER1_ROWS, 5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "Savitzky-Golay window", flt_extractor_create(g_calib, o, &e));
    flt_options_destroy(o);
    ++g_checks;
    if (e != NULL)
        ERR("*out not NULL after a failure");
    GOOD(flt_extractor_create(g_calib, NULL, &e));
    flt_extractor_destroy(e);
    flt_calib_destroy(c);
}

static void row_extractor_destroy(void) {
    flt_extractor_destroy(NULL);
    ++g_checks;
}

static void row_extractor_fibers(void) {
    flt_extractor *e = new_extractor();
    size_t n;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'extractor' is NULL", flt_extractor_fibers(NULL, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_extractor_fibers(e, NULL));
    uint64_t junk[16] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live",
        flt_extractor_fibers((const flt_extractor *)junk, &n));
    GOOD(flt_extractor_fibers(e, &n));
    flt_extractor_destroy(e);
}

static void row_extractor_band(void) {
    flt_extractor *e = new_extractor();
    uint32_t a, b;
    double h[FIBERS], k[FIBERS];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'extractor'", flt_extractor_band(NULL, 0, &a, &b));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'laser'", flt_extractor_band(e, 2, &a, &b));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'first_row_out'", flt_extractor_band(e, 0, NULL, &b));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows_out'", flt_extractor_band(e, 0, &a, NULL));
    /* Wrong order: an automatic band before the first frame. */
    BAD(FLT_ERR_STATE, "no frame", flt_extractor_band(e, 0, &a, &b));
    GOOD(flt_extractor_process(e, g_frame, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, g_frame_encoder,
                               FIBERS, NULL, h, k, NULL));
    GOOD(flt_extractor_band(e, 1, &a, &b));
    flt_extractor_destroy(e);
}

static void row_extractor_process(void) {
    flt_extractor *e = new_extractor();
    double s, h[FIBERS], k[FIBERS];
    uint8_t v[FIBERS];
    const void *f = g_frame;
#define PROC(fr, fmt, w, hh, st, enc, fib, ho, ko) \
  flt_extractor_process(e, fr, fmt, w, hh, st, enc, fib, &s, ho, ko, v)
    BAD(FLT_ERR_INVALID_ARGUMENT, "'extractor'",
        flt_extractor_process(NULL, f, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, 0, FIBERS, &s, h, k,
                              v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'frame'",
        PROC(NULL, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, 0, FIBERS, h, k));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height_out'",
        PROC(f, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, 0, FIBERS, NULL, k));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'slope_out'",
        PROC(f, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, 0, FIBERS, h, NULL));
    /* Pixel formats: unknown values, and the sentinel. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "'format'",
        PROC(f, (flt_pixel_format)0, WIDTH, ROI_ROWS, WIDTH, 0, FIBERS, h, k));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'format'",
        PROC(f, (flt_pixel_format)9, WIDTH, ROI_ROWS, WIDTH, 0, FIBERS, h, k));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'format'",
                PROC(f, (flt_pixel_format)-8, WIDTH, ROI_ROWS, WIDTH, 0, FIBERS, h, k));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'format'",
        PROC(f, FLT_PIXEL_MAX_ENUM_, WIDTH, ROI_ROWS, WIDTH, 0, FIBERS, h, k));
    /* Sizes other than the calibration's. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width'",
        PROC(f, FLT_PIXEL_MONO8, 0, ROI_ROWS, WIDTH, 0, FIBERS, h, k));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width'",
        PROC(f, FLT_PIXEL_MONO8, WIDTH, 0, WIDTH, 0, FIBERS, h, k));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width'",
        PROC(f, FLT_PIXEL_MONO8, UINT32_MAX, UINT32_MAX, WIDTH, 0, FIBERS, h, k));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width'",
        PROC(f, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS + 1, WIDTH, 0, FIBERS, h, k));
    /* Strides: too short, zero, odd for 16-bit, misaligned 16-bit buffer. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "'stride_bytes'",
        PROC(f, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH - 1, 0, FIBERS, h, k));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'stride_bytes'",
        PROC(f, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, 0, 0, FIBERS, h, k));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'stride_bytes'",
        PROC(f, FLT_PIXEL_MONO16, WIDTH, ROI_ROWS, WIDTH, 0, FIBERS, h, k));
    uint8_t *frame16 = calloc((size_t)WIDTH * 2 * ROI_ROWS + 2, 1);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'stride_bytes'",
        PROC(frame16, FLT_PIXEL_MONO12, WIDTH, ROI_ROWS, 2 * WIDTH + 1, 0, FIBERS, h, k));
    BAD(FLT_ERR_INVALID_ARGUMENT, "aligned",
        PROC(frame16 + 1, FLT_PIXEL_MONO12, WIDTH, ROI_ROWS, 2 * WIDTH, 0, FIBERS, h, k));
    /* A stride whose height * stride overflows size_t cannot describe any
     * buffer and must be refused (the caller vouches for a buffer of
     * height * stride bytes; only an overflow is detectable). */
    BAD(FLT_ERR_INVALID_ARGUMENT, "'stride_bytes'",
        PROC(f, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, SIZE_MAX / 2, 0, FIBERS, h, k));
    /* Encoder position: NaN, infinities. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'",
        PROC(f, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, NaN_, FIBERS, h, k));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'",
        PROC(f, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, Inf_, FIBERS, h, k));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'",
        PROC(f, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, -Inf_, FIBERS, h, k));
    /* Fibers. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'",
        PROC(f, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, 0, 0, h, k));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'",
        PROC(f, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, 0, NEG, h, k));
    /* A dark frame (no lines) for an automatic band: NUMERIC, and the next
     * frame tries again. */
    BAD(FLT_ERR_NUMERIC, NULL,
        PROC(frame16, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, 0, FIBERS, h, k));
    /* Valid calls: the rendered frame, then a saturated white frame (every
     * peak rejected: all fibers invalid, no error). */
    GOOD(PROC(f, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, g_frame_encoder, FIBERS, h, k));
    uint8_t *white = malloc((size_t)WIDTH * ROI_ROWS);
    memset(white, 255, (size_t)WIDTH * ROI_ROWS);
    GOOD(PROC(white, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, 1e9, FIBERS, h, k));
    /* A 16-bit frame of the 8-bit data with the high bits set beyond the
     * format's range (garbage above bit 12): no crash, any result. */
    uint16_t *w16 = (uint16_t *)frame16;
    for (size_t i = 0; i < (size_t)WIDTH * ROI_ROWS; ++i)
        w16[i] = (uint16_t)(g_frame[i] * 16 | 0xF000);
    flt_status st = PROC(frame16, FLT_PIXEL_MONO12, WIDTH, ROI_ROWS, 2 * WIDTH, 0, FIBERS, h, k);
    ++g_checks;
    if (st != FLT_OK && st != FLT_ERR_NUMERIC)
        ERR("out-of-range 12-bit pixels gave %s", flt_status_string(st));
    GOOD(PROC(f, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, g_frame_encoder, FIBERS, h, k));
#undef PROC
    free(white);
    free(frame16);
    flt_extractor_destroy(e);
}

static void row_extractor_peaks(void) {
    flt_extractor *e = new_extractor();
    double *rows = malloc(sizeof(double) * 2 * WIDTH), h[FIBERS], k[FIBERS];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'extractor'", flt_extractor_peaks(NULL, WIDTH, rows));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows_out'", flt_extractor_peaks(e, WIDTH, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width'", flt_extractor_peaks(e, WIDTH - 1, rows));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width'", flt_extractor_peaks(e, NEG, rows));
    BAD(FLT_ERR_STATE, "no frame", flt_extractor_peaks(e, WIDTH, rows));
    GOOD(flt_extractor_process(e, g_frame, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, g_frame_encoder,
                               FIBERS, NULL, h, k, NULL));
    GOOD(flt_extractor_peaks(e, WIDTH, rows));
    free(rows);
    flt_extractor_destroy(e);
}

static void row_extractor_laser_profiles(void) {
    flt_extractor *e = new_extractor();
    double z[2 * FIBERS], h[FIBERS], k[FIBERS];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'extractor'", flt_extractor_laser_profiles(NULL, FIBERS, z));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'z_out'", flt_extractor_laser_profiles(e, FIBERS, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_extractor_laser_profiles(e, FIBERS + 1, z));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_extractor_laser_profiles(e, NEG, z));
    BAD(FLT_ERR_STATE, "no frame", flt_extractor_laser_profiles(e, FIBERS, z));
    GOOD(flt_extractor_process(e, g_frame, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, g_frame_encoder,
                               FIBERS, NULL, h, k, NULL));
    GOOD(flt_extractor_laser_profiles(e, FIBERS, z));
    flt_extractor_destroy(e);
}

static void row_extractor_fiber_flags(void) {
    flt_extractor *e = new_extractor();
    uint8_t flags[FIBERS];
    double h[FIBERS], k[FIBERS];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'extractor'", flt_extractor_fiber_flags(NULL, FIBERS, flags));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flags_out'", flt_extractor_fiber_flags(e, FIBERS, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_extractor_fiber_flags(e, FIBERS + 1, flags));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_extractor_fiber_flags(e, NEG, flags));
    BAD(FLT_ERR_STATE, "no frame", flt_extractor_fiber_flags(e, FIBERS, flags));
    GOOD(flt_extractor_process(e, g_frame, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, g_frame_encoder,
                               FIBERS, NULL, h, k, NULL));
    GOOD(flt_extractor_fiber_flags(e, FIBERS, flags));
    flt_extractor_destroy(e);
}

static void row_extractor_strip(void) {
    flt_extractor *e = new_extractor();
    double l, r, w, c, h[FIBERS], k[FIBERS];
    unsigned sf;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'extractor'", flt_extractor_strip(NULL, 0, &l, &r, &w, &c, &sf));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'laser'", flt_extractor_strip(e, 3, &l, &r, &w, &c, &sf));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'laser'",
        flt_extractor_strip(e, (unsigned)-1, &l, &r, &w, &c, &sf));
    BAD(FLT_ERR_STATE, "no frame", flt_extractor_strip(e, 0, &l, &r, &w, &c, &sf));
    GOOD(flt_extractor_process(e, g_frame, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, g_frame_encoder,
                               FIBERS, NULL, h, k, NULL));
    for (unsigned laser = 0; laser <= 2; ++laser)
        GOOD(flt_extractor_strip(e, laser, &l, &r, &w, &c, &sf));
    GOOD(flt_extractor_strip(e, 2, NULL, NULL, NULL, NULL, NULL));
    flt_extractor_destroy(e);
}

static void row_extractor_saturation(void) {
    flt_extractor *e = new_extractor();
    size_t peaks, saturated;
    double fraction, h[FIBERS], k[FIBERS];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'extractor'",
        flt_extractor_saturation(NULL, 0, &peaks, &saturated, &fraction));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'laser'",
        flt_extractor_saturation(e, 3, &peaks, &saturated, &fraction));
    BAD(FLT_ERR_STATE, "no frame", flt_extractor_saturation(e, 2, &peaks, &saturated, &fraction));
    GOOD(flt_extractor_process(e, g_frame, FLT_PIXEL_MONO8, WIDTH, ROI_ROWS, WIDTH, g_frame_encoder,
                               FIBERS, NULL, h, k, NULL));
    GOOD(flt_extractor_saturation(e, 2, &peaks, &saturated, &fraction));
    ++g_checks;
    if (!(fraction >= 0 && fraction <= 1))
        ERR("saturation fraction %g outside [0, 1]", fraction);
    GOOD(flt_extractor_saturation(e, 0, NULL, NULL, NULL));
    flt_extractor_destroy(e);
}

/* ---------------------------------------------------------------------- */
/* sim.h                                                                   */
/* ---------------------------------------------------------------------- */

static flt_sim *new_sim(void) {
    flt_sim *s = NULL;
    if (flt_sim_create(g_calib, NULL, &s)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    return s;
}

static void row_sim_create(void) {
    flt_sim *s = NULL;
    flt_calib *c = almost_finished();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_sim_create(g_calib, NULL, NULL));
    BAD(FLT_ERR_STATE, "not finished", flt_sim_create(c, NULL, &s));
    uint64_t junk[16] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_sim_create((const flt_calib *)junk, NULL, &s));
    flt_options *o = options_with(FLT_OPT_EXTRACT_SG_WINDOW, 9);
    BAD(FLT_ERR_INVALID_ARGUMENT,
        "'extract_sg_window' belongs to the extractor, not to the simulator",
        flt_sim_create(g_calib, o, &s));
    flt_options_destroy(o);
    ++g_checks;
    if (s != NULL)
        ERR("*out not NULL after a failure");
    GOOD(flt_sim_create(g_calib, NULL, &s));
    flt_sim_destroy(s);
    /* A roller table that would be all gap. */
    o = options_with(FLT_OPT_SIM_ROLLER_GAP, 300);
    BAD(FLT_ERR_INVALID_ARGUMENT, "sim_roller_gap", flt_sim_create(g_calib, o, &s));
    /* Every field feature at once, at its extremes: a valid simulator. */
    GOOD(flt_options_set(o, FLT_OPT_SIM_ROLLER_GAP, 0));
    GOOD(flt_options_set(o, FLT_OPT_SIM_SURROUND, 2));
    GOOD(flt_options_set(o, FLT_OPT_SIM_STRIP_WIDTH, 1.0));
    GOOD(flt_options_set(o, FLT_OPT_SIM_STRIP_OFFSET, -1e5));
    GOOD(flt_options_set(o, FLT_OPT_SIM_COIL_LENGTH, 1e9));
    GOOD(flt_options_set(o, FLT_OPT_SIM_LINE_PEAK, 10));
    GOOD(flt_options_set(o, FLT_OPT_SIM_BLOOMING, 1));
    GOOD(flt_options_set(o, FLT_OPT_SIM_EDGE_GLINTS, 1));
    GOOD(flt_sim_create(g_calib, o, &s));
    uint8_t *frame = malloc((size_t)WIDTH * ROI_ROWS);
    GOOD(flt_sim_next_frame(s, frame, (size_t)WIDTH * ROI_ROWS, WIDTH, NULL, 0, NULL, NULL, 0));
    free(frame);
    flt_sim_destroy(s);
    flt_options_destroy(o);
    flt_calib_destroy(c);
}

static void row_sim_destroy(void) {
    flt_sim_destroy(NULL);
    ++g_checks;
}

static void row_sim_add_defect(void) {
    flt_sim *s = new_sim();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim'", flt_sim_add_defect(NULL, FLT_SIM_BOW, 1, 100));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'kind'", flt_sim_add_defect(s, (flt_sim_defect)8, 1, 100));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'kind'",
                flt_sim_add_defect(s, (flt_sim_defect)-1, 1, 100));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'kind'",
        flt_sim_add_defect(s, FLT_SIM_DEFECT_MAX_ENUM_, 1, 100));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'amplitude_mm'", flt_sim_add_defect(s, FLT_SIM_BOW, NaN_, 100));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'amplitude_mm'", flt_sim_add_defect(s, FLT_SIM_BOW, Inf_, 100));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'period_mm'", flt_sim_add_defect(s, FLT_SIM_BOW, 1, -1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'period_mm'", flt_sim_add_defect(s, FLT_SIM_BOW, 1, Inf_));
    /* Finite but absurd: 2 pi s / 7e-307 overflowed and sin(inf) made the
     * rows NaN (found by the contract suite); 1e300 mm of amplitude made
     * the two lasers' difference infinite. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "'period_mm'", flt_sim_add_defect(s, FLT_SIM_BOW, 1, 7e-307));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'amplitude_mm'", flt_sim_add_defect(s, FLT_SIM_BOW, 1e300, 100));
    for (int i = 0; i < 64; ++i)
        GOOD(flt_sim_add_defect(s, FLT_SIM_BOW, 0.01, 1000));
    BAD(FLT_ERR_BUFFER_FULL, "defects", flt_sim_add_defect(s, FLT_SIM_BOW, 1, 100));
    GOOD(flt_sim_clear_sheet(s));
    GOOD(flt_sim_add_defect(s, FLT_SIM_BOW, 1, 100));
    flt_sim_destroy(s);
}

static void row_sim_clear_sheet(void) {
    flt_sim *s = new_sim();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim'", flt_sim_clear_sheet(NULL));
    GOOD(flt_sim_clear_sheet(s));
    flt_sim_destroy(s);
}

static void row_sim_set_height_map(void) {
    flt_sim *s = new_sim();
    double hm[6] = {0, 1, 2, 3, 4, 5};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim'", flt_sim_set_height_map(NULL, 2, 3, 0, 1, 0, 1, hm));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'heights'", flt_sim_set_height_map(s, 2, 3, 0, 1, 0, 1, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows'", flt_sim_set_height_map(s, 1, 3, 0, 1, 0, 1, hm));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'cols'", flt_sim_set_height_map(s, 2, 0, 0, 1, 0, 1, hm));
    BAD(FLT_ERR_INVALID_ARGUMENT, NULL, flt_sim_set_height_map(s, NEG, 3, 0, 1, 0, 1, hm));
    BAD(FLT_ERR_INVALID_ARGUMENT, NULL,
        flt_sim_set_height_map(s, SIZE_MAX / 16, 3, 0, 1, 0, 1, hm));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'ds_mm'", flt_sim_set_height_map(s, 2, 3, 0, 0, 0, 1, hm));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'dx_mm'", flt_sim_set_height_map(s, 2, 3, 0, 1, 0, -1, hm));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'s0_mm'", flt_sim_set_height_map(s, 2, 3, NaN_, 1, 0, 1, hm));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'x0_mm'", flt_sim_set_height_map(s, 2, 3, 0, 1, Inf_, 1, hm));
    hm[4] = NaN_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "heights[4]", flt_sim_set_height_map(s, 2, 3, 0, 1, 0, 1, hm));
    hm[4] = -1.7e308; /* beside +1.7e308 the lasers' difference would be infinite */
    BAD(FLT_ERR_INVALID_ARGUMENT, "heights[4]", flt_sim_set_height_map(s, 2, 3, 0, 1, 0, 1, hm));
    hm[4] = 4;
    GOOD(flt_sim_set_height_map(s, 2, 3, 0, 1, 0, 1, hm));
    flt_sim_destroy(s);
}

static void row_sim_surface(void) {
    double x[2] = {0, 1}, sv[2] = {0, NaN_}, z[2];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim'", flt_sim_surface(NULL, 2, x, sv, z));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'x'", flt_sim_surface(g_sim, 2, NULL, sv, z));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'s'", flt_sim_surface(g_sim, 2, x, NULL, z));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'z_out'", flt_sim_surface(g_sim, 2, x, sv, NULL));
    /* Fixed in this commit (lib/simulation/sim.cpp): count = (size_t)-1 read
     * and wrote wild memory (SIGSEGV). */
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count'", flt_sim_surface(g_sim, NEG, x, sv, z));
    GOOD(flt_sim_surface(g_sim, 0, NULL, NULL, NULL));
    GOOD(flt_sim_surface(g_sim, 1, x, sv, z));
    /* A NaN position: NaN out or an error, never a crash. */
    flt_status st = flt_sim_surface(g_sim, 2, x, sv, z);
    ++g_checks;
    if (st == FLT_OK && !isnan(z[1]))
        ERR("NaN position gave z = %g", z[1]);
}

static void row_sim_fibers(void) {
    size_t n;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim'", flt_sim_fibers(NULL, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_sim_fibers(g_sim, NULL));
    uint64_t junk[16] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live", flt_sim_fibers((const flt_sim *)junk, &n));
    GOOD(flt_sim_fibers(g_sim, &n));
}

static void row_sim_frame_size(void) {
    uint32_t w, h;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim'", flt_sim_frame_size(NULL, &w, &h));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width_out'", flt_sim_frame_size(g_sim, NULL, &h));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height_out'", flt_sim_frame_size(g_sim, &w, NULL));
    GOOD(flt_sim_frame_size(g_sim, &w, &h));
}

static void row_sim_pixel_format(void) {
    flt_pixel_format f;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim'", flt_sim_pixel_format(NULL, &f));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_sim_pixel_format(g_sim, NULL));
    GOOD(flt_sim_pixel_format(g_sim, &f));
}

static void row_sim_next_rows(void) {
    flt_sim *s = new_sim();
    double e[4], sv[4], h[4 * FIBERS], k[4 * FIBERS];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim'",
        flt_sim_next_rows(NULL, 4, FIBERS, e, sv, h, k, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'s_out'",
        flt_sim_next_rows(s, 4, FIBERS, e, NULL, h, k, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height_out'",
        flt_sim_next_rows(s, 4, FIBERS, e, sv, NULL, k, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'slope_out'",
        flt_sim_next_rows(s, 4, FIBERS, e, sv, h, NULL, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows' is 0",
        flt_sim_next_rows(s, 0, FIBERS, e, sv, h, k, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'",
        flt_sim_next_rows(s, 4, FIBERS - 1, e, sv, h, k, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_sim_next_rows(s, 4, 0, e, sv, h, k, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflows",
        flt_sim_next_rows(s, NEG, FIBERS, e, sv, h, k, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflows",
        flt_sim_next_rows(s, overflow_rows(FIBERS), FIBERS, e, sv, h, k, NULL, NULL));
    GOOD(flt_sim_next_rows(s, 4, FIBERS, NULL, sv, h, k, NULL, NULL));
    flt_sim_destroy(s);
}

static void row_sim_next_frame(void) {
    flt_sim *s = new_sim();
    const size_t cap = (size_t)WIDTH * ROI_ROWS;
    uint8_t *buf = malloc(cap + 2);
    double enc, truth[FIBERS];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim'",
        flt_sim_next_frame(NULL, buf, cap, WIDTH, &enc, 0, NULL, NULL, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'frame_out'",
        flt_sim_next_frame(s, NULL, cap, WIDTH, &enc, 0, NULL, NULL, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'stride_bytes'",
        flt_sim_next_frame(s, buf, cap, WIDTH - 1, &enc, 0, NULL, NULL, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'stride_bytes'",
        flt_sim_next_frame(s, buf, cap, 0, &enc, 0, NULL, NULL, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'capacity_bytes'",
        flt_sim_next_frame(s, buf, cap - 1, WIDTH, &enc, 0, NULL, NULL, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'capacity_bytes'",
        flt_sim_next_frame(s, buf, 0, WIDTH, &enc, 0, NULL, NULL, 0));
    /* stride * height overflows size_t: refused, never written. */
    BAD(FLT_ERR_INVALID_ARGUMENT, NULL,
        flt_sim_next_frame(s, buf, cap, SIZE_MAX / 8, &enc, 0, NULL, NULL, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'",
        flt_sim_next_frame(s, buf, cap, WIDTH, &enc, FIBERS + 1, truth, NULL, 0));
    GOOD(flt_sim_next_frame(s, buf, cap, WIDTH, &enc, FIBERS, truth, NULL, 0));
    GOOD(flt_sim_next_frame(s, buf, cap, WIDTH, NULL, 0, NULL, NULL, 0));
    double *peaks = malloc(sizeof(double) * 2 * WIDTH);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'peak_rows_count'",
        flt_sim_next_frame(s, buf, cap, WIDTH, &enc, 0, NULL, peaks, WIDTH));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'peak_rows_count'",
        flt_sim_next_frame(s, buf, cap, WIDTH, &enc, 0, NULL, peaks, 2 * WIDTH + 1));
    GOOD(flt_sim_next_frame(s, buf, cap, WIDTH, &enc, 0, NULL, peaks, 2 * WIDTH));
    free(peaks);
    flt_sim_destroy(s);
    /* 16-bit output: odd stride, misaligned buffer. */
    flt_options *o = options_with(FLT_OPT_SIM_BIT_DEPTH, 12);
    GOOD(flt_sim_create(g_calib, o, &s));
    uint8_t *buf16 = malloc(2 * cap + 4);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'stride_bytes'",
        flt_sim_next_frame(s, buf16, 2 * cap + 4, 2 * WIDTH + 1, &enc, 0, NULL, NULL, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "align",
        flt_sim_next_frame(s, buf16 + 1, 2 * cap, 2 * WIDTH, &enc, 0, NULL, NULL, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'capacity_bytes'",
        flt_sim_next_frame(s, buf16, cap, 2 * WIDTH, &enc, 0, NULL, NULL, 0));
    GOOD(flt_sim_next_frame(s, buf16, 2 * cap, 2 * WIDTH, &enc, 0, NULL, NULL, 0));
    flt_sim_destroy(s);
    flt_options_destroy(o);
    free(buf);
    free(buf16);
}

static void row_sim_rewind(void) {
    flt_sim *s = new_sim();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim'", flt_sim_rewind(NULL));
    GOOD(flt_sim_rewind(s));
    flt_sim_destroy(s);
}

static void row_sim_strip_edges(void) {
    flt_sim *s = new_sim();
    double e[3] = {0, 100, -5e8}, l[3], r[3];
    uint8_t p[3];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim'", flt_sim_strip_edges(NULL, 0, 3, e, l, r, p));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'laser'", flt_sim_strip_edges(s, 3, 3, e, l, r, p));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'", flt_sim_strip_edges(s, 0, 3, NULL, l, r, p));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'left_mm_out'", flt_sim_strip_edges(s, 0, 3, e, NULL, r, p));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'right_mm_out'", flt_sim_strip_edges(s, 0, 3, e, l, NULL, p));
    double bad[3] = {0, NaN_, 1};
    BAD(FLT_ERR_INVALID_ARGUMENT, "encoder_mm[1]", flt_sim_strip_edges(s, 0, 3, bad, l, r, p));
    bad[1] = Inf_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "encoder_mm[1]", flt_sim_strip_edges(s, 2, 3, bad, l, r, p));
    GOOD(flt_sim_strip_edges(s, 0, 0, NULL, NULL, NULL, NULL)); /* nothing asked */
    GOOD(flt_sim_strip_edges(s, 2, 3, e, l, r, NULL));
    flt_sim_destroy(s);
    /* A random walk far from the start (a long way to step) stays finite. */
    flt_options *o = options_with(FLT_OPT_SIM_WANDER_SIGMA, 10);
    GOOD(flt_options_set(o, FLT_OPT_SIM_WANDER_LENGTH, 100));
    GOOD(flt_sim_create(g_calib, o, &s));
    double far_mm = 1e6; /* (not "far": a macro of windows.h) */
    GOOD(flt_sim_strip_edges(s, 1, 1, &far_mm, l, r, p));
    ++g_checks;
    if (!(isfinite(l[0]) && isfinite(r[0]) && p[0] == 1))
        ERR("edges at 1 km: %g, %g, present %d", l[0], r[0], p[0]);
    flt_sim_destroy(s);
    flt_options_destroy(o);
}

static void row_sim_fiber_flags(void) {
    flt_sim *s = new_sim();
    uint8_t flags[FIBERS];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim'", flt_sim_fiber_flags(NULL, 0, FIBERS, flags));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flags_out'", flt_sim_fiber_flags(s, 0, FIBERS, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_sim_fiber_flags(s, 0, FIBERS + 1, flags));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'", flt_sim_fiber_flags(s, NaN_, FIBERS, flags));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'", flt_sim_fiber_flags(s, -Inf_, FIBERS, flags));
    GOOD(flt_sim_fiber_flags(s, 1e9, FIBERS, flags));
    flt_sim_destroy(s);
}

/* ---------------------------------------------------------------------- */
/* flatness.h                                                              */
/* ---------------------------------------------------------------------- */

static double g_x[FIBERS];

static flt_flatness *new_flatness(void) {
    flt_flatness *f = NULL;
    if (flt_flatness_create(FIBERS, g_x, NULL, &f)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    return f;
}

/* A flat 1.2 m sheet: 400 rows 3 mm apart. */
enum { FROWS = 400 };
static double g_fs[FROWS], g_fz[FROWS * FIBERS];
static void make_flat_sheet(void) {
    for (int i = 0; i < FIBERS; ++i)
        g_x[i] = FIRST_X + PITCH * i;
    for (int r = 0; r < FROWS; ++r) {
        g_fs[r] = 3.0 * r;
        for (int k = 0; k < FIBERS; ++k)
            g_fz[r * FIBERS + k] =
                2.0 * sin(2 * M_PI * g_fs[r] / 600.0) * cos(M_PI * g_x[k] / 2020.0);
    }
}

static void row_shape_string(void) {
    const flt_shape v[] = {FLT_SHAPE_FLAT, FLT_SHAPE_UNDETERMINED, (flt_shape)99,
                           (flt_shape)-1, /* see ENUM_UB_BAD */
                           FLT_SHAPE_MAX_ENUM_};
    for (size_t i = 0; i < sizeof v / sizeof v[0]; ++i) {
        ++g_checks;
        if (flt_shape_string(v[i]) == NULL)
            ERR("NULL for %d", (int)v[i]);
    }
    ++g_checks;
    if (strcmp(flt_shape_string((flt_shape)99), "unknown") != 0)
        ERR("unknown shape is \"%s\"", flt_shape_string((flt_shape)99));
}

static void row_flatness_create(void) {
    flt_flatness *f = NULL;
    double x[3] = {0, 1, 1};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_flatness_create(FIBERS, g_x, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fiber_x'", flt_flatness_create(FIBERS, NULL, NULL, &f));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers' is 0", flt_flatness_create(0, g_x, NULL, &f));
    BAD(FLT_ERR_INVALID_ARGUMENT, "fiber_x[2]", flt_flatness_create(3, x, NULL, &f));
    flt_options *foreign = options_with(FLT_OPT_ROBUST, FLT_ROBUST_TUKEY);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'robust' belongs to the reconstructor, not to flatness",
        flt_flatness_create(FIBERS, g_x, foreign, &f));
    flt_options_destroy(foreign);
    x[2] = NaN_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "fiber_x[2]", flt_flatness_create(3, x, NULL, &f));
    x[2] = Inf_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "fiber_x[2]", flt_flatness_create(3, x, NULL, &f));
    /* fibers * 8 bytes overflows: refused before fiber_x is read. Fixed in
     * this commit (lib/flatness/flatness_api.cpp): fiber_x[101..] was read
     * (ASan: global-buffer-overflow). */
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_flatness_create(NEG, g_x, NULL, &f));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_flatness_create(SIZE_MAX / 8 + 1, g_x, NULL, &f));
    BAD(FLT_ERR_INVALID_ARGUMENT, "too large",
        flt_flatness_create(FLT_MAX_FIBERS + 1, g_x, NULL, &f));
    flt_options *o = options_with(FLT_OPT_FLAT_UPDATE_INTERVAL, 5000);
    BAD(FLT_ERR_INVALID_ARGUMENT, "flat_update_interval", flt_flatness_create(FIBERS, g_x, o, &f));
    flt_options_destroy(o);
    /* Finite but absurd: fibers spanning 2e300 mm (the zone count
     * overflowed its conversion to an integer) and 1e9 mm (40 million
     * zones, gigabytes). */
    x[0] = -1e300, x[1] = 0, x[2] = 1e300;
    BAD(FLT_ERR_INVALID_ARGUMENT, "fiber_x[0]", flt_flatness_create(3, x, NULL, &f));
    x[0] = -5e4, x[1] = 0, x[2] = 5e4;
    o = options_with(FLT_OPT_FLAT_ZONE_WIDTH, 1e-3);
    BAD(FLT_ERR_INVALID_ARGUMENT, "zones", flt_flatness_create(3, x, o, &f));
    flt_options_destroy(o);
    /* flat_row_capacity at its bound: 1e8 rows x 101 fibers x 9 bytes =
     * 91 GB, refused before allocating. */
    o = options_with(FLT_OPT_FLAT_ROW_CAPACITY, 1e8);
    BAD(FLT_ERR_INVALID_ARGUMENT, "GB", flt_flatness_create(FIBERS, g_x, o, &f));
    flt_options_destroy(o);
    ++g_checks;
    if (f != NULL)
        ERR("*out not NULL after a failure");
    GOOD(flt_flatness_create(FIBERS, g_x, NULL, &f));
    flt_flatness_destroy(f);
}

static void row_flatness_create_from_calib(void) {
    flt_flatness *f = NULL;
    flt_calib *c = new_unfinished();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_flatness_create_from_calib(g_calib, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_flatness_create_from_calib(NULL, NULL, &f));
    BAD(FLT_ERR_INVALID_ARGUMENT, "fiber grid", flt_flatness_create_from_calib(c, NULL, &f));
    flt_options *o = options_with(FLT_OPT_LASER_SPACING, 80);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'laser_spacing' belongs to the reconstructor",
        flt_flatness_create_from_calib(g_calib, o, &f));
    flt_options_destroy(o);
    GOOD(flt_flatness_create_from_calib(g_calib, NULL, &f));
    flt_flatness_destroy(f);
    flt_calib_destroy(c);
}

static void row_recon_create_from_calib(void) {
    flt_recon *r = NULL;
    flt_calib *c = new_unfinished();
    uint64_t junk[16] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_recon_create_from_calib(g_calib, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib' is NULL", flt_recon_create_from_calib(NULL, NULL, &r));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live",
        flt_recon_create_from_calib((const flt_calib *)junk, NULL, &r));
    BAD(FLT_ERR_STATE, "not finished", flt_recon_create_from_calib(c, NULL, &r));
    flt_calib_destroy(c);
    ++g_checks;
    if (r != NULL)
        ERR("*out not NULL after a failure");
    /* The sensor has 100 mm between its lasers: a laser_spacing option
     * that says otherwise is a mistake, not a choice. */
    flt_options *o = options_with(FLT_OPT_LASER_SPACING, 80.0);
    BAD(FLT_ERR_INVALID_ARGUMENT, "disagrees", flt_recon_create_from_calib(g_calib, o, &r));
    GOOD(flt_options_set(o, FLT_OPT_LASER_SPACING, 100.0 + 1e-6));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'laser_spacing' = 100.000001",
        flt_recon_create_from_calib(g_calib, o, &r));
    GOOD(flt_options_set(o, FLT_OPT_LASER_SPACING, 100.0)); /* agrees: fine */
    GOOD(flt_recon_create_from_calib(g_calib, o, &r));
    flt_recon_destroy(r);
    r = NULL;
    flt_options_destroy(o);
    /* Inconsistent options, as for flt_recon_create. */
    o = options_with(FLT_OPT_KNOT_SPACING, 0.001);
    BAD(FLT_ERR_INVALID_ARGUMENT, "knot_spacing", flt_recon_create_from_calib(g_calib, o, &r));
    flt_options_destroy(o);
    o = options_with(FLT_OPT_EXTRACT_SG_WINDOW, 9);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'extract_sg_window' belongs to the extractor",
        flt_recon_create_from_calib(g_calib, o, &r));
    flt_options_destroy(o);
    /* Lasers 1 nm apart: no spacing the reconstructor can work with. A
     * calibration cannot be finished so (FLT_CALIB_MIN_LASER_SPACING_MM),
     * so every finished one has a spacing inside laser_spacing's range. */
    c = almost_finished();
    if (flt_calib_set_laser_offset(c, 1, -50.0 + 1e-6) ||
        flt_calib_set_fiber_grid(c, FIRST_X, PITCH, FIBERS)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    BAD(FLT_ERR_STATE, "apart", flt_calib_finish(c));
    BAD(FLT_ERR_STATE, "not finished", flt_recon_create_from_calib(c, NULL, &r));
    flt_calib_destroy(c);
    GOOD(flt_recon_create_from_calib(g_calib, NULL, &r));
    size_t n = 0;
    double spacing = 0;
    GOOD(flt_recon_fibers(r, &n));
    GOOD(flt_recon_get_option(r, FLT_OPT_LASER_SPACING, &spacing));
    ++g_checks;
    if (n != FIBERS || spacing != 100.0)
        ERR("from the calibration: %zu fibers, %g mm; expected %d, 100", n, spacing, FIBERS);
    flt_recon_destroy(r);
}

static void row_flatness_destroy(void) {
    flt_flatness_destroy(NULL);
    ++g_checks;
}

static void row_flatness_fibers(void) {
    flt_flatness *f = new_flatness();
    size_t n;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness' is NULL", flt_flatness_fibers(NULL, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_flatness_fibers(f, NULL));
    uint64_t junk[16] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live",
        flt_flatness_fibers((const flt_flatness *)junk, &n));
    GOOD(flt_flatness_fibers(f, &n));
    flt_flatness_destroy(f);
}

static void row_flatness_zones(void) {
    flt_flatness *f = new_flatness();
    size_t n;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness'", flt_flatness_zones(NULL, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_flatness_zones(f, NULL));
    GOOD(flt_flatness_zones(f, &n));
    flt_flatness_destroy(f);
}

static void row_flatness_zone_layout(void) {
    flt_flatness *f = new_flatness();
    size_t zones;
    GOOD(flt_flatness_zones(f, &zones));
    double *a = malloc(sizeof(double) * zones);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness'",
        flt_flatness_zone_layout(NULL, zones, a, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'zones'", flt_flatness_zone_layout(f, zones + 1, a, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'zones'", flt_flatness_zone_layout(f, NEG, a, NULL, NULL));
    GOOD(flt_flatness_zone_layout(f, zones, a, NULL, NULL));
    free(a);
    flt_flatness_destroy(f);
}

static void row_flatness_evaluate(void) {
    flt_flatness *f = new_flatness();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness'",
        flt_flatness_evaluate(NULL, FROWS, FIBERS, g_fs, g_fz, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'s'", flt_flatness_evaluate(f, FROWS, FIBERS, NULL, g_fz, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'z'", flt_flatness_evaluate(f, FROWS, FIBERS, g_fs, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows' is 0",
        flt_flatness_evaluate(f, 0, FIBERS, g_fs, g_fz, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows'", flt_flatness_evaluate(f, 1, FIBERS, g_fs, g_fz, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'",
        flt_flatness_evaluate(f, FROWS, FIBERS - 1, g_fs, g_fz, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, NULL, flt_flatness_evaluate(f, NEG, FIBERS, g_fs, g_fz, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, NULL,
        flt_flatness_evaluate(f, overflow_rows(FIBERS), FIBERS, g_fs, g_fz, NULL));
    double s[FROWS];
    memcpy(s, g_fs, sizeof s);
    s[10] = NaN_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "s[10]", flt_flatness_evaluate(f, FROWS, FIBERS, s, g_fz, NULL));
    s[10] = s[9];
    BAD(FLT_ERR_INVALID_ARGUMENT, "s[10]", flt_flatness_evaluate(f, FROWS, FIBERS, s, g_fz, NULL));
    /* Too short: 100 rows = 297 mm < flat_min_length = 500 mm. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "flat_min_length",
        flt_flatness_evaluate(f, 100, FIBERS, g_fs, g_fz, NULL));
    /* All heights NaN: no valid fiber. */
    double *zn = malloc(sizeof g_fz);
    for (size_t i = 0; i < FROWS * FIBERS; ++i)
        zn[i] = NaN_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "fiber", flt_flatness_evaluate(f, FROWS, FIBERS, g_fs, zn, NULL));
    /* Infinite and huge heights in one fiber: that fiber is unusable or
     * large, the call succeeds, results stay flagged-or-finite. */
    memcpy(zn, g_fz, sizeof g_fz);
    for (int r = 0; r < FROWS; ++r)
        zn[r * FIBERS + 3] = (r % 2) ? Inf_ : -1e300;
    GOOD(flt_flatness_evaluate(f, FROWS, FIBERS, g_fs, zn, NULL));
    free(zn);
    GOOD(flt_flatness_evaluate(f, FROWS, FIBERS, g_fs, g_fz, NULL));
    flt_flatness_destroy(f);
}

static void row_flatness_push(void) {
    flt_flatness *f = new_flatness();
    size_t used;
    int ev;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness'",
        flt_flatness_push(NULL, 10, FIBERS, g_fs, g_fz, NULL, &used, &ev));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'s'",
        flt_flatness_push(f, 10, FIBERS, NULL, g_fz, NULL, &used, &ev));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'z'",
        flt_flatness_push(f, 10, FIBERS, g_fs, NULL, NULL, &used, &ev));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'consumed_out'",
        flt_flatness_push(f, 10, FIBERS, g_fs, g_fz, NULL, NULL, &ev));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'evaluated_out'",
        flt_flatness_push(f, 10, FIBERS, g_fs, g_fz, NULL, &used, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows' is 0",
        flt_flatness_push(f, 0, FIBERS, g_fs, g_fz, NULL, &used, &ev));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'",
        flt_flatness_push(f, 10, 1, g_fs, g_fz, NULL, &used, &ev));
    BAD(FLT_ERR_INVALID_ARGUMENT, NULL,
        flt_flatness_push(f, NEG, FIBERS, g_fs, g_fz, NULL, &used, &ev));
    double s[10];
    memcpy(s, g_fs, sizeof s);
    s[5] = Inf_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "s[5]",
        flt_flatness_push(f, 10, FIBERS, s, g_fz, NULL, &used, &ev));
    GOOD(flt_flatness_push(f, 10, FIBERS, g_fs, g_fz, NULL, &used, &ev));
    /* Rows must keep increasing across calls. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "s[0]",
        flt_flatness_push(f, 10, FIBERS, g_fs, g_fz, NULL, &used, &ev));
    GOOD(flt_flatness_push(f, 10, FIBERS, g_fs + 10, g_fz + 10 * FIBERS, NULL, &used, &ev));
    /* Capacity: a window longer than flat_row_capacity rows. */
    flt_options *o = options_with(FLT_OPT_FLAT_ROW_CAPACITY, 16);
    GOOD(flt_options_set(o, FLT_OPT_FLAT_WINDOW_LENGTH, 0));
    flt_flatness *g = NULL;
    GOOD(flt_flatness_create(FIBERS, g_x, o, &g));
    BAD(FLT_ERR_BUFFER_FULL, "flat_row_capacity",
        flt_flatness_push(g, 40, FIBERS, g_fs, g_fz, NULL, &used, &ev));
    ++g_checks;
    if (used != 16)
        ERR("consumed %zu rows before BUFFER_FULL, expected 16", used);
    GOOD(flt_flatness_reset(g));
    GOOD(flt_flatness_push(g, 10, FIBERS, g_fs, g_fz, NULL, &used, &ev));
    flt_flatness_destroy(g);
    flt_options_destroy(o);
    flt_flatness_destroy(f);
}

/* The strip variants: the plain calls' cases (shared code), and the edges:
 * infinite, crossed, NaN (unknown: fine), NULL (unknown: fine). */
static void row_flatness_evaluate_strip(void) {
    flt_flatness *f = new_flatness();
    double left[FROWS], right[FROWS];
    for (int r = 0; r < FROWS; ++r)
        left[r] = FIRST_X + 3, right[r] = FIRST_X + PITCH * (FIBERS - 1) - 3;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness'",
        flt_flatness_evaluate_strip(NULL, FROWS, FIBERS, g_fs, g_fz, NULL, left, right));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'s'",
        flt_flatness_evaluate_strip(f, FROWS, FIBERS, NULL, g_fz, NULL, left, right));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows' is 0",
        flt_flatness_evaluate_strip(f, 0, FIBERS, g_fs, g_fz, NULL, left, right));
    BAD(FLT_ERR_INVALID_ARGUMENT, NULL,
        flt_flatness_evaluate_strip(f, NEG, FIBERS, g_fs, g_fz, NULL, left, right));
    left[7] = -Inf_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "left_mm[7]",
        flt_flatness_evaluate_strip(f, FROWS, FIBERS, g_fs, g_fz, NULL, left, right));
    left[7] = right[7] + 1;
    BAD(FLT_ERR_INVALID_ARGUMENT, "left_mm[7]",
        flt_flatness_evaluate_strip(f, FROWS, FIBERS, g_fs, g_fz, NULL, left, right));
    left[7] = NaN_;
    right[9] = Inf_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "right_mm[9]",
        flt_flatness_evaluate_strip(f, FROWS, FIBERS, g_fs, g_fz, NULL, left, right));
    right[9] = right[8];
    GOOD(flt_flatness_evaluate_strip(f, FROWS, FIBERS, g_fs, g_fz, NULL, left, right));
    GOOD(flt_flatness_evaluate_strip(f, FROWS, FIBERS, g_fs, g_fz, NULL, NULL, right));
    GOOD(flt_flatness_evaluate_strip(f, FROWS, FIBERS, g_fs, g_fz, NULL, NULL, NULL));
    /* Absurd but finite edges (a strip far beyond the grid): measured as a
     * strip no fiber sees: no valid fiber, an error that names it. */
    for (int r = 0; r < FROWS; ++r)
        left[r] = 1e12, right[r] = 1e12 + 1000;
    BAD(FLT_ERR_INVALID_ARGUMENT, "fiber",
        flt_flatness_evaluate_strip(f, FROWS, FIBERS, g_fs, g_fz, NULL, left, right));
    for (int r = 0; r < FROWS; ++r)
        left[r] = -1e300, right[r] = 1e300;
    GOOD(flt_flatness_evaluate_strip(f, FROWS, FIBERS, g_fs, g_fz, NULL, left, right));
    flt_flatness_destroy(f);
}

static void row_flatness_push_strip(void) {
    flt_flatness *f = new_flatness();
    size_t used;
    int ev;
    double left[FROWS], right[FROWS];
    for (int r = 0; r < FROWS; ++r)
        left[r] = FIRST_X + 3, right[r] = FIRST_X + PITCH * (FIBERS - 1) - 3;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness'",
        flt_flatness_push_strip(NULL, 10, FIBERS, g_fs, g_fz, NULL, left, right, &used, &ev));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'consumed_out'",
        flt_flatness_push_strip(f, 10, FIBERS, g_fs, g_fz, NULL, left, right, NULL, &ev));
    right[3] = -Inf_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "right_mm[3]",
        flt_flatness_push_strip(f, 10, FIBERS, g_fs, g_fz, NULL, left, right, &used, &ev));
    ++g_checks;
    if (used != 0)
        ERR("a bad edge took %zu rows", used);
    right[3] = right[2];
    GOOD(flt_flatness_push_strip(f, 10, FIBERS, g_fs, g_fz, NULL, left, right, &used, &ev));
    GOOD(flt_flatness_push_strip(f, 10, FIBERS, g_fs + 10, g_fz + 10 * FIBERS, NULL, NULL, NULL,
                                 &used, &ev));
    flt_flatness_destroy(f);
}

static void row_flatness_finish(void) {
    flt_flatness *f = new_flatness();
    int ev = -1;
    size_t used;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness'", flt_flatness_finish(NULL, &ev));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'evaluated_out'", flt_flatness_finish(f, NULL));
    GOOD(flt_flatness_finish(f, &ev)); /* nothing pending: evaluates nothing */
    ++g_checks;
    if (ev != 0)
        ERR("finish with no rows evaluated");
    GOOD(flt_flatness_push(f, FROWS, FIBERS, g_fs, g_fz, NULL, &used, &ev));
    GOOD(flt_flatness_finish(f, &ev));
    flt_flatness_destroy(f);
}

static void row_flatness_reset(void) {
    flt_flatness *f = new_flatness();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness'", flt_flatness_reset(NULL));
    GOOD(flt_flatness_reset(f));
    flt_flatness_destroy(f);
}

/* The four result getters: STATE before any window, then fine. */
static void row_flatness_window(void) {
    flt_flatness *f = new_flatness();
    double a, b;
    size_t n, idx;
    unsigned fl;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness'", flt_flatness_window(NULL, &a, &b, &n, &fl, &idx));
    BAD(FLT_ERR_STATE, "no window", flt_flatness_window(f, &a, &b, &n, &fl, &idx));
    GOOD(flt_flatness_evaluate(f, FROWS, FIBERS, g_fs, g_fz, NULL));
    GOOD(flt_flatness_window(f, NULL, NULL, NULL, NULL, NULL));
    flt_flatness_destroy(f);
}

static void row_flatness_fiber_results(void) {
    flt_flatness *f = new_flatness();
    double arc[FIBERS];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness'",
        flt_flatness_fiber_results(NULL, FIBERS, arc, NULL, NULL, NULL, NULL, NULL));
    BAD(FLT_ERR_STATE, "no window",
        flt_flatness_fiber_results(f, FIBERS, arc, NULL, NULL, NULL, NULL, NULL));
    GOOD(flt_flatness_evaluate(f, FROWS, FIBERS, g_fs, g_fz, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'",
        flt_flatness_fiber_results(f, FIBERS + 1, arc, NULL, NULL, NULL, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'",
        flt_flatness_fiber_results(f, NEG, arc, NULL, NULL, NULL, NULL, NULL));
    GOOD(flt_flatness_fiber_results(f, FIBERS, arc, NULL, NULL, NULL, NULL, NULL));
    flt_flatness_destroy(f);
}

static void row_flatness_zone_results(void) {
    flt_flatness *f = new_flatness();
    size_t zones;
    GOOD(flt_flatness_zones(f, &zones));
    double *iu = malloc(sizeof(double) * zones);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness'", flt_flatness_zone_results(NULL, zones, iu, NULL));
    BAD(FLT_ERR_STATE, "no window", flt_flatness_zone_results(f, zones, iu, NULL));
    GOOD(flt_flatness_evaluate(f, FROWS, FIBERS, g_fs, g_fz, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'zones'", flt_flatness_zone_results(f, zones - 1, iu, NULL));
    GOOD(flt_flatness_zone_results(f, zones, iu, NULL));
    free(iu);
    flt_flatness_destroy(f);
}

static void row_flatness_shape(void) {
    flt_flatness *f = new_flatness();
    flt_shape sh;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness'",
        flt_flatness_shape(NULL, &sh, NULL, NULL, NULL, NULL));
    BAD(FLT_ERR_STATE, "no window", flt_flatness_shape(f, &sh, NULL, NULL, NULL, NULL));
    GOOD(flt_flatness_evaluate(f, FROWS, FIBERS, g_fs, g_fz, NULL));
    GOOD(flt_flatness_shape(f, &sh, NULL, NULL, NULL, NULL));
    flt_flatness_destroy(f);
}

static void row_flatness_strip(void) {
    flt_flatness *f = new_flatness();
    double w[3], c[3];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness'", flt_flatness_strip(NULL, w, c));
    BAD(FLT_ERR_STATE, "no window", flt_flatness_strip(f, w, c));
    GOOD(flt_flatness_evaluate(f, FROWS, FIBERS, g_fs, g_fz, NULL));
    GOOD(flt_flatness_strip(f, w, c));
    GOOD(flt_flatness_strip(f, NULL, NULL));
    ++g_checks;
    if (!(isfinite(w[0]) && isfinite(c[2])))
        ERR("the grid's strip is not finite: %g, %g", w[0], c[2]);
    flt_flatness_destroy(f);
}

static void row_flatness_zone_positions(void) {
    flt_flatness *f = new_flatness();
    size_t zones;
    GOOD(flt_flatness_zones(f, &zones));
    double *a = malloc(sizeof(double) * zones);
    size_t *n = malloc(sizeof(size_t) * zones);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness'",
        flt_flatness_zone_positions(NULL, zones, a, NULL, NULL, n));
    BAD(FLT_ERR_STATE, "no window", flt_flatness_zone_positions(f, zones, a, NULL, NULL, n));
    GOOD(flt_flatness_evaluate(f, FROWS, FIBERS, g_fs, g_fz, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'zones'",
        flt_flatness_zone_positions(f, zones + 1, a, NULL, NULL, n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'zones'", flt_flatness_zone_positions(f, NEG, a, NULL, NULL, n));
    GOOD(flt_flatness_zone_positions(f, zones, a, a, a, n));
    free(a), free(n);
    flt_flatness_destroy(f);
}

static void row_flatness_fiber_positions(void) {
    flt_flatness *f = new_flatness();
    double xs[FIBERS], x[FIBERS];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flatness'", flt_flatness_fiber_positions(NULL, FIBERS, xs, x));
    BAD(FLT_ERR_STATE, "no window", flt_flatness_fiber_positions(f, FIBERS, xs, x));
    GOOD(flt_flatness_evaluate(f, FROWS, FIBERS, g_fs, g_fz, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_flatness_fiber_positions(f, FIBERS - 1, xs, x));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_flatness_fiber_positions(f, NEG, xs, x));
    GOOD(flt_flatness_fiber_positions(f, FIBERS, xs, x));
    flt_flatness_destroy(f);
}

/* ---------------------------------------------------------------------- */
/* source.h                                                                */
/* ---------------------------------------------------------------------- */

static flt_source *new_sim_source(void) {
    flt_source *s = NULL;
    if (flt_source_create_sim(g_sim, NULL, &s)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    return s;
}

/* The bus as the transport flt_source_open_u3v() and
 * flt_camera_list_create() take (NULL for a NULL bus). */
static flt_usb_transport *usb(flt_u3v_sim *bus) {
    flt_usb_transport *t = NULL;
    if (bus && flt_u3v_sim_transport(bus, &t) != FLT_OK)
        abort();
    return t;
}

/* A simulated bus with one small Mono8 camera, serial "S1". */
static flt_u3v_sim *new_bus(void) {
    flt_u3v_sim *bus = NULL;
    size_t idx;
    if (flt_u3v_sim_create(&bus) ||
        flt_u3v_sim_add_camera(bus, "Vendor", "Model", "S1", 64, 32, FLT_PIXEL_MONO8, &idx)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    return bus;
}

static flt_source *open_camera(flt_u3v_sim *bus) {
    flt_source *s = NULL;
    if (flt_source_open_u3v(usb(bus), "S1", NULL, &s)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    return s;
}

static void row_source_create_sim(void) {
    flt_source *s = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_source_create_sim(g_sim, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim'", flt_source_create_sim(NULL, NULL, &s));
    flt_options *o = options_with(FLT_OPT_SOURCE_ENCODER_MODE, FLT_ENCODER_CHUNK);
    BAD(FLT_ERR_INVALID_ARGUMENT, "source_encoder_mode", flt_source_create_sim(g_sim, o, &s));
    flt_options_destroy(o);
    /* The simulator's own options go to flt_sim_create, not here. */
    o = options_with(FLT_OPT_SIM_SEED, 5);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim_seed' belongs to the simulator, not to frame sources",
        flt_source_create_sim(g_sim, o, &s));
    flt_options_destroy(o);
    ++g_checks;
    if (s != NULL)
        ERR("*out not NULL after a failure");
    GOOD(flt_source_create_sim(g_sim, NULL, &s));
    flt_source_destroy(s);
}

static void row_source_create_images(void) {
    flt_source *s = NULL;
    char png[300], junk[300], other[300], csv[300];
    path_in_dir(png, sizeof png, "a.png");
    path_in_dir(junk, sizeof junk, "junk.png");
    path_in_dir(other, sizeof other, "small.png");
    path_in_dir(csv, sizeof csv, "enc.csv");
    uint8_t px[64 * 32];
    for (size_t i = 0; i < sizeof px; ++i)
        px[i] = (uint8_t)i;
    write_png(png, px, 64, 32);
    write_png(other, px, 32, 16);
    write_file(junk, "not an image at all", 19);
    const char *one[1] = {png}, *with_null[2] = {png, NULL}, *garbage[1] = {junk},
               *mixed[2] = {png, other}, *missing[1] = {"/nonexistent/x.png"};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_source_create_images(one, 1, NULL, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'paths'", flt_source_create_images(NULL, 1, NULL, NULL, &s));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count'", flt_source_create_images(one, 0, NULL, NULL, &s));
    BAD(FLT_ERR_INVALID_ARGUMENT, "paths[1]",
        flt_source_create_images(with_null, 2, NULL, NULL, &s));
    BAD(FLT_ERR_IO, "x.png", flt_source_create_images(missing, 1, NULL, NULL, &s));
    /* OpenCV cannot tell "unreadable" from "not an image": IO, named. */
    BAD(FLT_ERR_IO, "junk.png", flt_source_create_images(garbage, 1, NULL, NULL, &s));
    /* CSV: wrong row count, a bad number, NaN. */
    write_file(csv, "1.0\n2.0\n", 8);
    BAD(FLT_ERR_FORMAT, "enc.csv", flt_source_create_images(one, 1, csv, NULL, &s));
    write_file(csv, "abc\n", 4);
    BAD(FLT_ERR_FORMAT, "enc.csv", flt_source_create_images(one, 1, csv, NULL, &s));
    write_file(csv, "encoder_mm\nnan\n", 15);
    BAD(FLT_ERR_FORMAT, "enc.csv", flt_source_create_images(one, 1, csv, NULL, &s));
    BAD(FLT_ERR_IO, "no_such.csv",
        flt_source_create_images(one, 1, "/nonexistent/no_such.csv", NULL, &s));
    write_file(csv, "12.5\n", 5);
    flt_options *o = options_with(FLT_OPT_U3V_TRANSFERS, 4); /* source options are fine */
    GOOD(flt_options_set(o, FLT_OPT_FLAT_ZONE_WIDTH, 100));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'flat_zone_width' belongs to flatness, not to frame sources",
        flt_source_create_images(one, 1, csv, o, &s));
    flt_options_destroy(o);
    GOOD(flt_source_create_images(one, 1, csv, NULL, &s));
    flt_source_destroy(s);
    /* The second image has another size: found when it is read. */
    GOOD(flt_source_create_images(mixed, 2, NULL, NULL, &s));
    const flt_frame *fr;
    GOOD(flt_source_start(s));
    GOOD(flt_source_next(s, 0, &fr));
    g_fn = "flt_source_next";
    BAD(FLT_ERR_FORMAT, "small.png", flt_source_next(s, 0, &fr));
    g_fn = "flt_source_create_images";
    flt_source_destroy(s);
}

static void row_source_create_image_dir(void) {
    flt_source *s = NULL;
    char empty[300], d[300], png[400];
    path_in_dir(empty, sizeof empty, "empty");
    path_in_dir(d, sizeof d, "images");
    tf_mkdir(empty);
    tf_mkdir(d);
    snprintf(png, sizeof png, "%s/0001.png", d);
    uint8_t px[64 * 32] = {0};
    write_png(png, px, 64, 32);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_source_create_image_dir(d, NULL, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'directory'", flt_source_create_image_dir(NULL, NULL, NULL, &s));
    BAD(FLT_ERR_NOT_FOUND, "empty", flt_source_create_image_dir(empty, NULL, NULL, &s));
    BAD(FLT_ERR_IO, "no_such_dir",
        flt_source_create_image_dir("/nonexistent/no_such_dir", NULL, NULL, &s));
    flt_options *o = options_with(FLT_OPT_SIM_SEED, 4);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim_seed' belongs to the simulator",
        flt_source_create_image_dir(d, NULL, o, &s));
    flt_options_destroy(o);
    GOOD(flt_source_create_image_dir(d, NULL, NULL, &s));
    flt_source_destroy(s);
}

static void row_source_destroy(void) {
    flt_source_destroy(NULL);
    ++g_checks;
}

static void row_source_kind_of(void) {
    flt_source *s = new_sim_source();
    flt_source_kind k;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'source'", flt_source_kind_of(NULL, &k));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_source_kind_of(s, NULL));
    uint64_t junk[32] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live", flt_source_kind_of((const flt_source *)junk, &k));
    GOOD(flt_source_kind_of(s, &k));
    flt_source_destroy(s);
}

static void row_source_start(void) {
    flt_source *s = new_sim_source();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'source'", flt_source_start(NULL));
    GOOD(flt_source_start(s));
    BAD(FLT_ERR_STATE, "started", flt_source_start(s));
    GOOD(flt_source_stop(s));
    GOOD(flt_source_start(s));
    flt_source_destroy(s);
}

static void row_source_stop(void) {
    flt_source *s = new_sim_source();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'source'", flt_source_stop(NULL));
    GOOD(flt_source_stop(s)); /* stopping a stopped source is a no-op */
    flt_source_destroy(s);
}

static void row_source_next(void) {
    flt_source *s = new_sim_source();
    const flt_frame *f;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'source'", flt_source_next(NULL, 0, &f));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_source_next(s, 0, NULL));
    /* Wrong order: next before start, and after stop. */
    BAD(FLT_ERR_STATE, "start", flt_source_next(s, 0, &f));
    GOOD(flt_source_start(s));
    GOOD(flt_source_next(s, 0, &f));
    GOOD(flt_source_stop(s));
    BAD(FLT_ERR_STATE, "start", flt_source_next(s, 0, &f));
    flt_source_destroy(s);
}

static void row_frame_info(void) {
    flt_source *s = new_sim_source();
    const flt_frame *f;
    const void *px;
    GOOD(flt_source_start(s));
    GOOD(flt_source_next(s, 0, &f));
    g_fn = "flt_frame_info";
    BAD(FLT_ERR_INVALID_ARGUMENT, "'frame'",
        flt_frame_info(NULL, &px, NULL, NULL, NULL, NULL, NULL, NULL, NULL));
    GOOD(flt_frame_info(f, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL));
    GOOD(flt_frame_info(f, &px, NULL, NULL, NULL, NULL, NULL, NULL, NULL));
    flt_source_destroy(s);
}

static void row_source_set_encoder(void) {
    flt_source *s = new_sim_source();
    flt_options *o = options_with(FLT_OPT_SOURCE_ENCODER_MODE, 2);
    flt_source *host = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'source'", flt_source_set_encoder(NULL, 1.0));
    /* Wrong mode. */
    BAD(FLT_ERR_STATE, "mode", flt_source_set_encoder(s, 1.0));
    GOOD(flt_source_create_sim(g_sim, o, &host));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'", flt_source_set_encoder(host, NaN_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'", flt_source_set_encoder(host, Inf_));
    GOOD(flt_source_set_encoder(host, 1.0));
    flt_source_destroy(host);
    flt_options_destroy(o);
    flt_source_destroy(s);
}

static void row_source_count(void) {
    flt_source *s = new_sim_source();
    uint64_t v;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'source'", flt_source_count(NULL, FLT_COUNT_FRAMES, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_source_count(s, FLT_COUNT_FRAMES, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'counter'", flt_source_count(s, (flt_source_counter)21, &v));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'counter'",
                flt_source_count(s, (flt_source_counter)-1, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'counter'", flt_source_count(s, FLT_COUNT_MAX_ENUM_, &v));
    GOOD(flt_source_count(s, FLT_COUNT_FRAMES, &v));
    flt_source_destroy(s);
}

static void row_source_stream_error(void) {
    flt_source *s = new_sim_source();
    ++g_checks;
    if (flt_source_stream_error(NULL) == NULL)
        ERR("NULL for a NULL source");
    ++g_checks;
    if (flt_source_stream_error(s) == NULL || flt_source_stream_error(s)[0] != 0)
        ERR("not \"\" for a fresh source");
    flt_source_destroy(s);
}

static void row_source_camera_string(void) {
    flt_source *s = new_sim_source();
    flt_u3v_sim *bus = new_bus();
    flt_source *cam = open_camera(bus);
    const char *str;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'source'",
        flt_source_camera_string(NULL, FLT_CAMERA_VENDOR, &str));
    BAD(FLT_ERR_STATE, "camera", flt_source_camera_string(s, FLT_CAMERA_VENDOR, &str));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_source_camera_string(cam, FLT_CAMERA_VENDOR, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'which'",
        flt_source_camera_string(cam, (flt_camera_string)7, &str));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'which'",
                flt_source_camera_string(cam, (flt_camera_string)-1, &str));
    GOOD(flt_source_camera_string(cam, FLT_CAMERA_SERIAL, &str));
    flt_source_destroy(cam);
    flt_u3v_sim_destroy(bus);
    flt_source_destroy(s);
}

static void row_source_camera_value(void) {
    flt_source *s = new_sim_source();
    flt_u3v_sim *bus = new_bus();
    flt_source *cam = open_camera(bus);
    uint64_t v;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'source'",
        flt_source_camera_value(NULL, FLT_CAMERA_U3V_VERSION, &v));
    BAD(FLT_ERR_STATE, "camera", flt_source_camera_value(s, FLT_CAMERA_U3V_VERSION, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'",
        flt_source_camera_value(cam, FLT_CAMERA_U3V_VERSION, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'which'",
        flt_source_camera_value(cam, (flt_camera_value)18, &v));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'which' = -1",
                flt_source_camera_value(cam, (flt_camera_value)-1, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'which'",
        flt_source_camera_value(cam, FLT_CAMERA_VALUE_MAX_ENUM_, &v));
    GOOD(flt_source_camera_value(cam, FLT_CAMERA_U3V_VERSION, &v));
    flt_source_destroy(cam);
    flt_u3v_sim_destroy(bus);
    flt_source_destroy(s);
}

/* The six feature accessors share their checks. */
static void check_feature_access(int which) {
    flt_source *s = new_sim_source();
    flt_u3v_sim *bus = new_bus();
    flt_source *cam = open_camera(bus);
    int64_t iv;
    double dv;
#define CALL(src, name)                                        \
  (which == 0   ? flt_source_get_int(src, name, &iv)           \
   : which == 1 ? flt_source_set_int(src, name, 32)            \
   : which == 2 ? flt_source_get_float(src, name, &dv)         \
   : which == 3 ? flt_source_set_float(src, name, 1.5)         \
   : which == 4 ? flt_source_set_enum(src, name, "Continuous") \
                : flt_source_execute(src, name))
    static const char *const good_feature[6] = {"Width", "Height",          "Gain",
                                                "Gain",  "AcquisitionMode", "AcquisitionStop"};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'source'", CALL(NULL, good_feature[which]));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'feature'", CALL(cam, NULL));
    BAD(FLT_ERR_STATE, "camera", CALL(s, good_feature[which]));
    BAD(FLT_ERR_NOT_FOUND, "NoSuchFeature", CALL(cam, "NoSuchFeature"));
    BAD(FLT_ERR_NOT_FOUND, NULL, CALL(cam, ""));
    char longname[3000];
    memset(longname, 'Q', sizeof longname - 1);
    longname[sizeof longname - 1] = 0;
    BAD(FLT_ERR_NOT_FOUND, "QQQQ", CALL(cam, longname));
    if (which == 0)
        BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_source_get_int(cam, "Width", NULL));
    if (which == 2)
        BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_source_get_float(cam, "Gain", NULL));
    if (which == 3)
        BAD(FLT_ERR_INVALID_ARGUMENT, "not finite", flt_source_set_float(cam, "Gain", NaN_));
    if (which == 4) {
        BAD(FLT_ERR_INVALID_ARGUMENT, "'entry'", flt_source_set_enum(cam, "AcquisitionMode", NULL));
        BAD(FLT_ERR_NOT_FOUND, "NoSuchEntry",
            flt_source_set_enum(cam, "AcquisitionMode", "NoSuchEntry"));
    }
    GOOD(CALL(cam, good_feature[which]));
#undef CALL
    flt_source_destroy(cam);
    flt_u3v_sim_destroy(bus);
    flt_source_destroy(s);
}
static void row_source_get_int(void) {
    check_feature_access(0);
}
static void row_source_set_int(void) {
    check_feature_access(1);
}
static void row_source_get_float(void) {
    check_feature_access(2);
}
static void row_source_set_float(void) {
    check_feature_access(3);
}
static void row_source_set_enum(void) {
    check_feature_access(4);
}
static void row_source_execute(void) {
    check_feature_access(5);
}

static void row_source_map_feature(void) {
    flt_source *s = new_sim_source();
    flt_u3v_sim *bus = new_bus();
    flt_source *cam = open_camera(bus);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'source'", flt_source_map_feature(NULL, "X", 0x10000, 4, 0));
    BAD(FLT_ERR_STATE, "camera", flt_source_map_feature(s, "X", 0x10000, 4, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'feature'", flt_source_map_feature(cam, NULL, 0x10000, 4, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'length'", flt_source_map_feature(cam, "X", 0x10000, 3, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'length'", flt_source_map_feature(cam, "X", 0x10000, 0, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'length'", flt_source_map_feature(cam, "X", 0x10000, 2, 1));
    GOOD(flt_source_map_feature(cam, "ExposureTime", 0x1001C, 4, 0));
    flt_source_destroy(cam);
    flt_u3v_sim_destroy(bus);
    flt_source_destroy(s);
}

static void row_source_read_memory(void) {
    flt_source *s = new_sim_source();
    flt_u3v_sim *bus = new_bus();
    flt_source *cam = open_camera(bus);
    uint8_t buf[64];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'source'", flt_source_read_memory(NULL, 0, buf, 4));
    BAD(FLT_ERR_STATE, "camera", flt_source_read_memory(s, 0, buf, 4));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_source_read_memory(cam, 0, NULL, 4));
    /* An address the camera does not map: its GenCP status, named. */
    BAD(FLT_ERR_DEVICE, "invalid address", flt_source_read_memory(cam, 0xFFFFFFFF0000ull, buf, 4));
    /* Address + bytes past 2^64. Fixed in this commit
     * (lib/sources/source_api.cpp): the range wrapped to address 2 and was
     * read; the same write corrupted the simulated camera's heap. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "'address'", flt_source_read_memory(cam, UINT64_MAX - 1, buf, 4));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bytes'", flt_source_read_memory(cam, 0, buf, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bytes'", flt_source_read_memory(cam, 0, buf, NEG));
    GOOD(flt_source_read_memory(cam, 0, buf, 4));
    flt_source_destroy(cam);
    flt_u3v_sim_destroy(bus);
    flt_source_destroy(s);
}

static void row_source_write_memory(void) {
    flt_source *s = new_sim_source();
    flt_u3v_sim *bus = new_bus();
    flt_source *cam = open_camera(bus);
    uint8_t buf[4] = {32, 0, 0, 0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'source'", flt_source_write_memory(NULL, 0x10000, buf, 4));
    BAD(FLT_ERR_STATE, "camera", flt_source_write_memory(s, 0x10000, buf, 4));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bytes_in'", flt_source_write_memory(cam, 0x10000, NULL, 4));
    BAD(FLT_ERR_DEVICE, NULL, flt_source_write_memory(cam, 0x0, buf, 4)); /* read-only ABRM */
    BAD(FLT_ERR_INVALID_ARGUMENT, "'address'",
        flt_source_write_memory(cam, UINT64_MAX - 1, buf, 4));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bytes'", flt_source_write_memory(cam, 0x10000, buf, 0));
    GOOD(flt_source_write_memory(cam, 0x10000, buf, 4));
    flt_source_destroy(cam);
    flt_u3v_sim_destroy(bus);
    flt_source_destroy(s);
}

static void row_source_open_u3v(void) {
    flt_u3v_sim *bus = new_bus();
    flt_source *s = NULL;
    flt_camera_list *l = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_source_open_u3v(usb(bus), "S1", NULL, NULL));
    BAD(FLT_ERR_NOT_FOUND, "NOPE", flt_source_open_u3v(usb(bus), "NOPE", NULL, &s));
    flt_options *o = options_with(FLT_OPT_EXTRACT_MIN_PEAK, 0.2);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'extract_min_peak' belongs to the extractor",
        flt_source_open_u3v(usb(bus), "S1", o, &s));
    flt_options_destroy(o);
    flt_u3v_sim *empty = NULL;
    GOOD(flt_u3v_sim_create(&empty));
    BAD(FLT_ERR_NOT_FOUND, NULL, flt_source_open_u3v(usb(empty), NULL, NULL, &s));
    flt_u3v_sim_destroy(empty);
    /* A transport that is no live one, and one made for another release
     * (the handle's first fields: magic "FLTX", revision, backend). */
    struct {
        uint32_t magic, revision;
        void *backend;
    } fake = {0, 0, NULL};
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live flt_usb_transport",
        flt_source_open_u3v((flt_usb_transport *)&fake, NULL, NULL, &s));
    fake.magic = 0x464c5458u;
    fake.revision = 7;
    fake.backend = &fake;
    BAD(FLT_ERR_INVALID_ARGUMENT, "another release",
        flt_source_open_u3v((flt_usb_transport *)&fake, NULL, NULL, &s));
    BAD(FLT_ERR_INVALID_ARGUMENT, "another release",
        flt_camera_list_create((flt_usb_transport *)&fake, &l));
    GOOD(flt_source_open_u3v(usb(bus), NULL, NULL, &s));
    /* Wrong order: the same camera opened twice. */
    flt_source *again = NULL;
    BAD(FLT_ERR_DEVICE, NULL, flt_source_open_u3v(usb(bus), "S1", NULL, &again));
    flt_source_destroy(s);
    GOOD(flt_source_open_u3v(usb(bus), "S1", NULL, &s));
    flt_source_destroy(s);
    flt_u3v_sim_destroy(bus);
}

static void row_camera_list_create(void) {
    flt_u3v_sim *bus = new_bus();
    flt_camera_list *l = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_camera_list_create(usb(bus), NULL));
    GOOD(flt_camera_list_create(usb(bus), &l));
    flt_camera_list_destroy(l);
    flt_u3v_sim_destroy(bus);
}

static void row_camera_list_destroy(void) {
    flt_camera_list_destroy(NULL);
    ++g_checks;
}

static void row_camera_list_count(void) {
    flt_u3v_sim *bus = new_bus();
    flt_camera_list *l = NULL;
    size_t n;
    GOOD(flt_camera_list_create(usb(bus), &l));
    g_fn = "flt_camera_list_count";
    BAD(FLT_ERR_INVALID_ARGUMENT, "'list'", flt_camera_list_count(NULL, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_camera_list_count(l, NULL));
    GOOD(flt_camera_list_count(l, &n));
    flt_camera_list_destroy(l);
    flt_u3v_sim_destroy(bus);
}

static void row_camera_list_get(void) {
    flt_u3v_sim *bus = new_bus();
    flt_camera_list *l = NULL;
    const char *v;
    GOOD(flt_camera_list_create(usb(bus), &l));
    g_fn = "flt_camera_list_get";
    BAD(FLT_ERR_INVALID_ARGUMENT, "'list'", flt_camera_list_get(NULL, 0, &v, NULL, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'index'", flt_camera_list_get(l, 1, &v, NULL, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'index'", flt_camera_list_get(l, NEG, &v, NULL, NULL, NULL));
    GOOD(flt_camera_list_get(l, 0, &v, NULL, NULL, NULL));
    GOOD(flt_camera_list_get(l, 0, NULL, NULL, NULL, NULL));
    flt_camera_list_destroy(l);
    flt_u3v_sim_destroy(bus);
}

static void row_camera_list_create_gige(void) {
    flt_camera_list *l = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_camera_list_create_gige("127.0.0.1", 10, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'address'", flt_camera_list_create_gige("camera", 10, &l));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'address'", flt_camera_list_create_gige("1.2.3.4:0", 10, &l));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'address'", flt_camera_list_create_gige("256.1.1.1", 10, &l));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'timeout_ms'", flt_camera_list_create_gige(NULL, 0, &l));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'timeout_ms'", flt_camera_list_create_gige(NULL, 60001, &l));
    /* The discard port of loopback: nobody answers, an empty list. */
    GOOD(flt_camera_list_create_gige("127.0.0.1:9", 1, &l));
    size_t n = 1;
    GOOD(flt_camera_list_count(l, &n));
    if (n != 0)
        ERR("a list of %zu cameras from a port nobody answers on\n", n);
    flt_camera_list_destroy(l);
}

static void row_camera_list_address(void) {
    flt_u3v_sim *bus = new_bus();
    flt_camera_list *l = NULL;
    const char *a = NULL;
    GOOD(flt_camera_list_create(usb(bus), &l));
    g_fn = "flt_camera_list_address";
    BAD(FLT_ERR_INVALID_ARGUMENT, "'list'", flt_camera_list_address(NULL, 0, &a));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_camera_list_address(l, 0, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'index'", flt_camera_list_address(l, 1, &a));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'index'", flt_camera_list_address(l, NEG, &a));
    GOOD(flt_camera_list_address(l, 0, &a));
    if (!a || a[0] != '\0')
        ERR("a USB3 Vision camera has address '%s', expected ''\n", a ? a : "(null)");
    flt_camera_list_destroy(l);
    flt_u3v_sim_destroy(bus);
}

/* Without a camera on the network: every refusal (the good path is
 * test_gige's, against aravis's fake camera). */
static void row_source_open_gige(void) {
    flt_source *s = NULL;
    flt_options *o = NULL;
    GOOD(flt_options_create(&o));
    GOOD(flt_options_set(o, FLT_OPT_GIGE_CONTROL_TIMEOUT, 10));
    GOOD(flt_options_set(o, FLT_OPT_GIGE_COMMAND_ATTEMPTS, 1));
    GOOD(flt_options_set(o, FLT_OPT_GIGE_DISCOVERY_TIMEOUT, 1));
    g_fn = "flt_source_open_gige";
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_source_open_gige("127.0.0.1", o, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'camera'", flt_source_open_gige("", o, &s));
    BAD(FLT_ERR_TIMEOUT, "127.0.0.1:9", flt_source_open_gige("127.0.0.1:9", o, &s));
    BAD(FLT_ERR_NOT_FOUND, "NO-SUCH-SERIAL", flt_source_open_gige("NO-SUCH-SERIAL", o, &s));
    GOOD(flt_options_set(o, FLT_OPT_GIGE_PACKET_SIZE, 575));
    BAD(FLT_ERR_INVALID_ARGUMENT, "gige_packet_size", flt_source_open_gige("127.0.0.1", o, &s));
    GOOD(flt_options_set(o, FLT_OPT_GIGE_PACKET_SIZE, 0));
    GOOD(flt_options_set(o, FLT_OPT_SOURCE_ENCODER_MODE, 3));
    BAD(FLT_ERR_INVALID_ARGUMENT, "source_encoder_mode", flt_source_open_gige("127.0.0.1", o, &s));
    if (s)
        ERR("a refused open returned a source\n");
    flt_options_destroy(o);
}

static void row_u3v_sim_create(void) {
    flt_u3v_sim *bus = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_u3v_sim_create(NULL));
    GOOD(flt_u3v_sim_create(&bus));
    flt_u3v_sim_destroy(bus);
}

static void row_u3v_sim_transport(void) {
    flt_u3v_sim *bus = new_bus();
    flt_usb_transport *t = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_u3v_sim_transport(bus, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bus'", flt_u3v_sim_transport(NULL, &t));
    uint32_t garbage[8] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bus'", flt_u3v_sim_transport((flt_u3v_sim *)garbage, &t));
    GOOD(flt_u3v_sim_transport(bus, &t));
    flt_source *s = NULL;
    GOOD(flt_source_open_u3v(t, "S1", NULL, &s));
    flt_source_destroy(s);
    flt_u3v_sim_destroy(bus);
}

static void row_u3v_sim_destroy(void) {
    flt_u3v_sim_destroy(NULL);
    ++g_checks;
}

static void row_u3v_sim_add_camera(void) {
    flt_u3v_sim *bus = NULL;
    size_t idx;
    GOOD(flt_u3v_sim_create(&bus));
    g_fn = "flt_u3v_sim_add_camera";
    char longs[100];
    memset(longs, 'L', sizeof longs - 1);
    longs[sizeof longs - 1] = 0;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bus'",
        flt_u3v_sim_add_camera(NULL, "V", "M", "S", 64, 32, FLT_PIXEL_MONO8, &idx));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'vendor'",
        flt_u3v_sim_add_camera(bus, NULL, "M", "S", 64, 32, FLT_PIXEL_MONO8, &idx));
    BAD(FLT_ERR_INVALID_ARGUMENT, "longer than 63",
        flt_u3v_sim_add_camera(bus, "V", "M", longs, 64, 32, FLT_PIXEL_MONO8, &idx));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width'",
        flt_u3v_sim_add_camera(bus, "V", "M", "S", 8, 32, FLT_PIXEL_MONO8, &idx));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height'",
        flt_u3v_sim_add_camera(bus, "V", "M", "S", 64, 9000, FLT_PIXEL_MONO8, &idx));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'format'",
        flt_u3v_sim_add_camera(bus, "V", "M", "S", 64, 32, (flt_pixel_format)11, &idx));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'format' = -8",
                flt_u3v_sim_add_camera(bus, "V", "M", "S", 64, 32, (flt_pixel_format)-8, &idx));
    for (int i = 0; i < 8; ++i)
        GOOD(flt_u3v_sim_add_camera(bus, "V", "M", "S", 64, 32, FLT_PIXEL_MONO8, &idx));
    BAD(FLT_ERR_BUFFER_FULL, NULL,
        flt_u3v_sim_add_camera(bus, "V", "M", "S", 64, 32, FLT_PIXEL_MONO8, &idx));
    uint64_t v;
    GOOD(flt_u3v_sim_get(bus, 7, FLT_U3V_SIM_COMMANDS, &v));
    flt_u3v_sim_destroy(bus);
}

static void row_u3v_sim_set_frames(void) {
    flt_u3v_sim *bus = new_bus();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bus'", flt_u3v_sim_set_frames(NULL, 0, g_sim));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'camera'", flt_u3v_sim_set_frames(bus, 1, g_sim));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'camera'", flt_u3v_sim_set_frames(bus, NEG, g_sim));
    GOOD(flt_u3v_sim_set_frames(bus, 0, g_sim));
    GOOD(flt_u3v_sim_set_frames(bus, 0, NULL));
    flt_u3v_sim_destroy(bus);
}

static void row_u3v_sim_set(void) {
    flt_u3v_sim *bus = new_bus();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bus'", flt_u3v_sim_set(NULL, 0, FLT_U3V_SIM_XML_ZIPPED, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'camera'", flt_u3v_sim_set(bus, 3, FLT_U3V_SIM_XML_ZIPPED, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "parameter is unknown",
        flt_u3v_sim_set(bus, 0, (flt_u3v_sim_param)15, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "parameter is unknown",
        flt_u3v_sim_set(bus, 0, FLT_U3V_SIM_FRAMES_SENT, 0)); /* read-only */
    BAD(FLT_ERR_INVALID_ARGUMENT, "parameter is unknown",
        flt_u3v_sim_set(bus, 0, FLT_U3V_SIM_PARAM_MAX_ENUM_, 0));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'param' = -1",
                flt_u3v_sim_set(bus, 0, (flt_u3v_sim_param)-1, 0));
    GOOD(flt_u3v_sim_set(bus, 0, FLT_U3V_SIM_XML_ZIPPED, 0));
    flt_u3v_sim_destroy(bus);
}

static void row_u3v_sim_get(void) {
    flt_u3v_sim *bus = new_bus();
    uint64_t v;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bus'", flt_u3v_sim_get(NULL, 0, FLT_U3V_SIM_COMMANDS, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'camera'", flt_u3v_sim_get(bus, 1, FLT_U3V_SIM_COMMANDS, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_u3v_sim_get(bus, 0, FLT_U3V_SIM_COMMANDS, NULL));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "parameter is unknown",
                flt_u3v_sim_get(bus, 0, (flt_u3v_sim_param)-3, &v));
    GOOD(flt_u3v_sim_get(bus, 0, FLT_U3V_SIM_COMMANDS, &v));
    flt_u3v_sim_destroy(bus);
}

static void row_u3v_sim_inject(void) {
    flt_u3v_sim *bus = new_bus();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bus'",
        flt_u3v_sim_inject(NULL, 0, FLT_U3V_FAULT_SHORT_FRAME, 1, 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'camera'",
        flt_u3v_sim_inject(bus, 2, FLT_U3V_FAULT_SHORT_FRAME, 1, 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "fault is unknown",
        flt_u3v_sim_inject(bus, 0, (flt_u3v_fault)8, 1, 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "fault is unknown",
        flt_u3v_sim_inject(bus, 0, FLT_U3V_FAULT_MAX_ENUM_, 1, 1));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'fault' = -4",
                flt_u3v_sim_inject(bus, 0, (flt_u3v_fault)-4, 1, 1));
    GOOD(flt_u3v_sim_inject(bus, 0, FLT_U3V_FAULT_SHORT_FRAME, 1, 1));
    flt_u3v_sim_destroy(bus);
}

static void row_u3v_sim_peek(void) {
    flt_u3v_sim *bus = new_bus();
    uint32_t v;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bus'", flt_u3v_sim_peek(NULL, 0, 0, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'camera'", flt_u3v_sim_peek(bus, 5, 0, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_u3v_sim_peek(bus, 0, 0, NULL));
    /* Fixed in this commit (lib/sources/u3v/sim_camera.cpp, sim_peek):
     * address + 4 wrapped and the register was read out of bounds. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "'address'", flt_u3v_sim_peek(bus, 0, UINT64_MAX, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'address'", flt_u3v_sim_peek(bus, 0, UINT64_MAX - 2, &v));
    GOOD(flt_u3v_sim_peek(bus, 0, 0x10000, &v));
    flt_u3v_sim_destroy(bus);
}

/* ---------------------------------------------------------------------- */
/* gauge.h                                                                 */
/* ---------------------------------------------------------------------- */

/* A gauge over the fixture calibration; workers 0 (every call finishes its
 * work before returning) unless options say otherwise. */
static flt_gauge *new_gauge(int keep_maps) {
    flt_options *o = options_with(FLT_OPT_GAUGE_WORKERS, 0);
    flt_gauge *g = NULL;
    if (flt_options_set(o, FLT_OPT_GAUGE_KEEP_MAPS, keep_maps) ||
        flt_options_set(o, FLT_OPT_GAUGE_FRAME_SPACING, 3) || flt_gauge_create(g_calib, o, &g)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    flt_options_destroy(o);
    return g;
}

/* One flat sheet of 300 rows (900 mm from `start`) through a gauge, left
 * waiting for the caller. */
static void make_waiting_sheet(flt_gauge *g, double start) {
    double h[FIBERS] = {0}, k[FIBERS] = {0};
    for (int r = 0; r < 300; ++r)
        if (flt_gauge_push_row(g, start + 3.0 * r, FIBERS, h, k, NULL)) {
            fprintf(stderr, "fixture: %s\n", flt_last_error_message());
            exit(2);
        }
    if (flt_gauge_flush(g)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
}

/* The same, taken by polling. */
static flt_sheet *new_sheet(flt_gauge *g) {
    flt_sheet *sh = NULL;
    make_waiting_sheet(g, 0.0);
    if (flt_gauge_next_sheet(g, 0, &sh) || !sh) {
        fprintf(stderr, "fixture: no sheet: %s\n", flt_last_error_message());
        exit(2);
    }
    return sh;
}

static void row_gauge_create(void) {
    flt_gauge *g = NULL;
    flt_calib *c = almost_finished();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_gauge_create(g_calib, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_gauge_create(NULL, NULL, &g));
    BAD(FLT_ERR_STATE, "not finished", flt_gauge_create(c, NULL, &g));
    uint64_t junk[32] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live",
        flt_gauge_create((const flt_calib *)junk, NULL, &g));
    /* Options a part refuses: named, with the part. */
    flt_options *o = options_with(FLT_OPT_EXTRACT_SG_WINDOW, 10);
    BAD(FLT_ERR_INVALID_ARGUMENT, "extract_sg_window", flt_gauge_create(g_calib, o, &g));
    flt_options_destroy(o);
    o = options_with(FLT_OPT_KNOT_SPACING, 1);
    BAD(FLT_ERR_INVALID_ARGUMENT, "knot_spacing", flt_gauge_create(g_calib, o, &g));
    flt_options_destroy(o);
    /* Geometry is the calibration's: a laser spacing set otherwise. */
    o = options_with(FLT_OPT_LASER_SPACING, 80);
    BAD(FLT_ERR_INVALID_ARGUMENT, "laser_spacing", flt_gauge_create(g_calib, o, &g));
    flt_options_destroy(o);
    /* A key of a component the gauge does not run would be ignored. */
    o = options_with(FLT_OPT_SIM_SEED, 7);
    BAD(FLT_ERR_INVALID_ARGUMENT, "sim_seed", flt_gauge_create(g_calib, o, &g));
    flt_options_destroy(o);
    /* Absurd but in bounds: a reconstructor latency of 6.4 m at 1 um
     * frames, and sheets of 10 km at 1 um. */
    o = options_with(FLT_OPT_GAUGE_FRAME_SPACING, 1e-3);
    BAD(FLT_ERR_INVALID_ARGUMENT, "gauge_frame_spacing", flt_gauge_create(g_calib, o, &g));
    GOOD(flt_options_set(o, FLT_OPT_LAG_KNOTS, 0));
    GOOD(flt_options_set(o, FLT_OPT_GAUGE_MAX_SHEET_LENGTH, 1e7));
    BAD(FLT_ERR_INVALID_ARGUMENT, "gauge_max_sheet_length", flt_gauge_create(g_calib, o, &g));
    flt_options_destroy(o);
    ++g_checks;
    if (g != NULL)
        ERR("*out not NULL after a failure");
    GOOD(flt_gauge_create(g_calib, NULL, &g));
    flt_gauge_destroy(g);
    flt_calib_destroy(c);
}

static void row_gauge_destroy(void) {
    flt_gauge_destroy(NULL);
    uint64_t junk[32] = {0};
    flt_gauge_destroy((flt_gauge *)junk); /* not a gauge: left alone */
    g_checks += 2;
}

static void row_gauge_get_option(void) {
    flt_gauge *g = new_gauge(0);
    double v;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_get_option(NULL, FLT_OPT_GAUGE_WORKERS, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_gauge_get_option(g, FLT_OPT_GAUGE_WORKERS, NULL));
    BAD(FLT_ERR_NOT_FOUND, "99999", flt_gauge_get_option(g, (flt_option)99999, &v));
    ENUM_UB_BAD(FLT_ERR_NOT_FOUND, "-3", flt_gauge_get_option(g, (flt_option)-3, &v));
    GOOD(flt_gauge_get_option(g, FLT_OPT_LASER_SPACING, &v));
    ++g_checks;
    if (v != 100.0)
        ERR("laser_spacing %g is not the calibration's 100 mm", v);
    flt_gauge_destroy(g);
}

static void row_gauge_push_frame(void) {
    flt_gauge *g = new_gauge(0);
    const void *f = g_frame;
    const flt_pixel_format M8 = FLT_PIXEL_MONO8;
    const double e = g_frame_encoder;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'",
        flt_gauge_push_frame(NULL, f, M8, WIDTH, ROI_ROWS, WIDTH, e));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'pixels'",
        flt_gauge_push_frame(g, NULL, M8, WIDTH, ROI_ROWS, WIDTH, e));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'format' = 7",
        flt_gauge_push_frame(g, f, (flt_pixel_format)7, WIDTH, ROI_ROWS, WIDTH, e));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'format' = -8",
                flt_gauge_push_frame(g, f, (flt_pixel_format)-8, WIDTH, ROI_ROWS, WIDTH, e));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width'",
        flt_gauge_push_frame(g, f, M8, WIDTH - 1, ROI_ROWS, WIDTH, e));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height'", flt_gauge_push_frame(g, f, M8, WIDTH, 0, WIDTH, e));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'stride_bytes'",
        flt_gauge_push_frame(g, f, M8, WIDTH, ROI_ROWS, WIDTH - 1, e));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflows",
        flt_gauge_push_frame(g, f, M8, WIDTH, ROI_ROWS, SIZE_MAX / 2, e));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'stride_bytes'",
        flt_gauge_push_frame(g, f, FLT_PIXEL_MONO16, WIDTH, ROI_ROWS, 2 * WIDTH + 1, e));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'",
        flt_gauge_push_frame(g, f, M8, WIDTH, ROI_ROWS, WIDTH, NaN_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'",
        flt_gauge_push_frame(g, f, M8, WIDTH, ROI_ROWS, WIDTH, Inf_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'",
        flt_gauge_push_frame(g, f, M8, WIDTH, ROI_ROWS, WIDTH, 1e300));
    uint64_t n = 1;
    GOOD(flt_gauge_count(g, FLT_GAUGE_COUNT_FRAMES, &n));
    ++g_checks;
    if (n != 0)
        ERR("refused frames were counted: %llu", (unsigned long long)n);
    GOOD(flt_gauge_push_frame(g, f, M8, WIDTH, ROI_ROWS, WIDTH, e));
    /* Wrong order: frames while a source acquires. */
    flt_source *s = new_sim_source();
    GOOD(flt_gauge_attach_source(g, s));
    GOOD(flt_gauge_start(g));
    BAD(FLT_ERR_STATE, "acquiring", flt_gauge_push_frame(g, f, M8, WIDTH, ROI_ROWS, WIDTH, e));
    GOOD(flt_gauge_stop(g));
    GOOD(flt_gauge_attach_source(g, NULL));
    flt_source_destroy(s);
    GOOD(flt_gauge_push_frame(g, f, M8, WIDTH, ROI_ROWS, WIDTH, 1e6));
    flt_gauge_destroy(g);
}

static void row_gauge_push_row(void) {
    flt_gauge *g = new_gauge(0);
    double h[FIBERS] = {0}, k[FIBERS] = {0}, nan_row[FIBERS];
    for (size_t i = 0; i < FIBERS; ++i)
        nan_row[i] = NAN;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_push_row(NULL, 0.0, FIBERS, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height'", flt_gauge_push_row(g, 0.0, FIBERS, NULL, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'slope'", flt_gauge_push_row(g, 0.0, FIBERS, h, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_gauge_push_row(g, 0.0, FIBERS + 1, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_gauge_push_row(g, 0.0, NEG, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'", flt_gauge_push_row(g, NaN_, FIBERS, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'", flt_gauge_push_row(g, -Inf_, FIBERS, h, k, NULL));
    /* NaN data is not a bad call: an invalid row (no strip). */
    GOOD(flt_gauge_push_row(g, 0.0, FIBERS, nan_row, nan_row, NULL));
    GOOD(flt_gauge_push_row(g, 3.0, FIBERS, h, k, NULL));
    flt_gauge_destroy(g);
}

static void row_gauge_cut(void) {
    flt_gauge *g = new_gauge(0);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_cut(NULL, 1.0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'", flt_gauge_cut(g, NaN_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'", flt_gauge_cut(g, Inf_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'", flt_gauge_cut(g, -2e12));
    GOOD(flt_gauge_cut(g, 1000.0));
    /* Wrong order: cuts go forward. */
    BAD(FLT_ERR_INVALID_ARGUMENT, "previous cut", flt_gauge_cut(g, 1000.0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "previous cut", flt_gauge_cut(g, 999.0));
    /* Too many cuts the strip never reaches. */
    flt_status st = FLT_OK;
    for (int i = 1; i <= 300 && st == FLT_OK; ++i)
        st = flt_gauge_cut(g, 1000.0 + i);
    BAD(FLT_ERR_BUFFER_FULL, "wait", st);
    flt_gauge_destroy(g);
    g = new_gauge(0);
    GOOD(flt_gauge_cut(g, 1000.0));
    flt_gauge_destroy(g);
}

static void row_gauge_flush(void) {
    flt_gauge *g = new_gauge(0);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_flush(NULL));
    GOOD(flt_gauge_flush(g)); /* nothing pushed: nothing to end */
    flt_source *s = new_sim_source();
    GOOD(flt_gauge_attach_source(g, s));
    GOOD(flt_gauge_start(g));
    BAD(FLT_ERR_STATE, "acquiring", flt_gauge_flush(g));
    GOOD(flt_gauge_stop(g));
    GOOD(flt_gauge_flush(g));
    flt_gauge_destroy(g);
    flt_source_destroy(s);
}

static void row_gauge_attach_source(void) {
    flt_gauge *g = new_gauge(0);
    flt_source *s = new_sim_source();
    uint64_t junk[32] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_attach_source(NULL, s));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live", flt_gauge_attach_source(g, (flt_source *)junk));
    GOOD(flt_gauge_attach_source(g, s));
    GOOD(flt_gauge_start(g));
    BAD(FLT_ERR_STATE, "acquiring", flt_gauge_attach_source(g, NULL));
    GOOD(flt_gauge_stop(g));
    GOOD(flt_gauge_attach_source(g, NULL));
    flt_gauge_destroy(g);
    flt_source_destroy(s);
}

static void row_gauge_start(void) {
    flt_gauge *g = new_gauge(0);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_start(NULL));
    BAD(FLT_ERR_STATE, "no source", flt_gauge_start(g));
    /* A source of frames of another size: the acquisition ends, stop says
     * why. */
    flt_sim *other = NULL;
    flt_source *s = NULL;
    GOOD(flt_sim_create(NULL, NULL, &other)); /* the 2048 x 2048 reference */
    GOOD(flt_source_create_sim(other, NULL, &s));
    GOOD(flt_gauge_attach_source(g, s));
    GOOD(flt_gauge_start(g));
    uint64_t acquiring = 1;
    for (int i = 0; i < 5000 && acquiring; ++i) {
        GOOD(flt_gauge_count(g, FLT_GAUGE_COUNT_ACQUIRING, &acquiring));
        struct timespec ms = {0, 1000000};
        nanosleep(&ms, NULL);
    }
    g_fn = "flt_gauge_stop";
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width'", flt_gauge_stop(g));
    g_fn = "flt_gauge_start";
    GOOD(flt_gauge_attach_source(g, NULL));
    flt_source_destroy(s);
    flt_sim_destroy(other);
    s = new_sim_source();
    GOOD(flt_gauge_attach_source(g, s));
    GOOD(flt_gauge_start(g));
    BAD(FLT_ERR_STATE, "already", flt_gauge_start(g));
    GOOD(flt_gauge_stop(g));
    flt_gauge_destroy(g);
    flt_source_destroy(s);
}

static void row_gauge_stop(void) {
    flt_gauge *g = new_gauge(0);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_stop(NULL));
    GOOD(flt_gauge_stop(g)); /* stopping a stopped gauge is a no-op */
    flt_gauge_destroy(g);
}

static void row_gauge_wait(void) {
    flt_gauge *g = new_gauge(0);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_wait(NULL, 0));
    /* Wrong order: nothing started. */
    BAD(FLT_ERR_STATE, "flt_gauge_start", flt_gauge_wait(g, 0));
    BAD(FLT_ERR_STATE, "flt_gauge_start", flt_gauge_wait(g, FLT_GAUGE_WAIT_FOREVER));
    /* A source that never ends: a timeout, then stopped by hand. */
    flt_source *s = new_sim_source();
    GOOD(flt_gauge_attach_source(g, s));
    GOOD(flt_gauge_start(g));
    BAD(FLT_ERR_TIMEOUT, "still delivers", flt_gauge_wait(g, 10));
    GOOD(flt_gauge_stop(g));
    BAD(FLT_ERR_STATE, "flt_gauge_start", flt_gauge_wait(g, 0));
    GOOD(flt_gauge_attach_source(g, NULL));
    flt_source_destroy(s);
    flt_gauge_destroy(g);
}

static void ignore_log(flt_log_level level, const char *component, const char *message,
                       void *user) {
    (void)level, (void)component, (void)message, (void)user;
}

static void row_log_set_callback(void) {
    BAD(FLT_ERR_INVALID_ARGUMENT, "'min_level'", flt_log_set_callback(ignore_log, NULL, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'min_level'",
        flt_log_set_callback(ignore_log, NULL, (flt_log_level)-1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'min_level'",
        flt_log_set_callback(ignore_log, NULL, (flt_log_level)41));
    GOOD(flt_log_set_callback(ignore_log, NULL, FLT_LOG_DEBUG));
    GOOD(flt_log_set_callback(NULL, NULL, FLT_LOG_ERROR));
}

static int g_callback_calls;
static void count_callback(const flt_sheet *sheet, void *user) {
    (void)sheet;
    (void)user;
    ++g_callback_calls;
}

static void row_gauge_next_sheet(void) {
    flt_gauge *g = new_gauge(0);
    flt_sheet *sh = (flt_sheet *)g;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_gauge_next_sheet(g, 0, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_next_sheet(NULL, 0, &sh));
    ++g_checks;
    if (sh != NULL)
        ERR("*out not NULL after a failure");
    GOOD(flt_gauge_set_callback(g, count_callback, NULL));
    BAD(FLT_ERR_STATE, "callback", flt_gauge_next_sheet(g, 0, &sh));
    GOOD(flt_gauge_set_callback(g, NULL, NULL));
    GOOD(flt_gauge_next_sheet(g, 0, &sh)); /* none: NULL after the timeout */
    ++g_checks;
    if (sh != NULL)
        ERR("a sheet from nothing");
    flt_gauge_destroy(g);
}

static void row_gauge_set_callback(void) {
    flt_gauge *g = new_gauge(0);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_set_callback(NULL, count_callback, NULL));
    make_waiting_sheet(g, 0.0); /* waiting: handed to the callback when it is set */
    g_callback_calls = 0;
    GOOD(flt_gauge_set_callback(g, count_callback, NULL));
    ++g_checks;
    if (g_callback_calls != 1)
        ERR("the waiting sheet went to the callback %d times", g_callback_calls);
    GOOD(flt_gauge_set_callback(g, NULL, NULL));
    flt_gauge_destroy(g);
}

static void row_gauge_count(void) {
    flt_gauge *g = new_gauge(0);
    uint64_t v;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_count(NULL, FLT_GAUGE_COUNT_FRAMES, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_gauge_count(g, FLT_GAUGE_COUNT_FRAMES, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'counter' = 26", flt_gauge_count(g, (flt_gauge_counter)26, &v));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'counter' = -1",
                flt_gauge_count(g, (flt_gauge_counter)-1, &v));
    GOOD(flt_gauge_count(g, FLT_GAUGE_COUNT_SHEETS_WAITING, &v));
    flt_gauge_destroy(g);
}

static void row_sheet_destroy(void) {
    flt_sheet_destroy(NULL);
    uint64_t junk[32] = {0};
    flt_sheet_destroy((flt_sheet *)junk); /* not a sheet: left alone */
    g_checks += 2;
}

static void row_sheet_get(void) {
    flt_gauge *g = new_gauge(0);
    flt_sheet *sh = new_sheet(g);
    double v;
    uint64_t junk[64] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sheet'", flt_sheet_get(NULL, FLT_SHEET_ID, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live", flt_sheet_get((flt_sheet *)junk, FLT_SHEET_ID, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_sheet_get(sh, FLT_SHEET_ID, NULL));
    BAD(FLT_ERR_NOT_FOUND, "'key' = 48", flt_sheet_get(sh, (flt_sheet_value)48, &v));
    ENUM_UB_BAD(FLT_ERR_NOT_FOUND, "'key' = -1", flt_sheet_get(sh, (flt_sheet_value)-1, &v));
    GOOD(flt_sheet_get(sh, FLT_SHEET_ROWS, &v));
    ++g_checks;
    if (v != 300.0)
        ERR("the fixture sheet has %g rows, not 300", v);
    /* A destroyed sheet is no longer live (until its slot is reused). */
    flt_sheet_destroy(sh);
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live", flt_sheet_get(sh, FLT_SHEET_ID, &v));
    flt_gauge_destroy(g);
}

static void row_sheet_get_array(void) {
    flt_gauge *g = new_gauge(0);
    flt_sheet *sh = new_sheet(g);
    double a[FIBERS];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sheet'",
        flt_sheet_get_array(NULL, FLT_SHEET_FIBER_I_UNITS, FIBERS, a));
    BAD(FLT_ERR_NOT_FOUND, "'key' = 12", flt_sheet_get_array(sh, (flt_sheet_array)12, FIBERS, a));
    ENUM_UB_BAD(FLT_ERR_NOT_FOUND, "'key' = -2",
                flt_sheet_get_array(sh, (flt_sheet_array)-2, FIBERS, a));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'",
        flt_sheet_get_array(sh, FLT_SHEET_FIBER_I_UNITS, FIBERS, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count'",
        flt_sheet_get_array(sh, FLT_SHEET_FIBER_I_UNITS, FIBERS - 1, a));
    BAD(FLT_ERR_INVALID_ARGUMENT, "FLT_SHEET_ZONES",
        flt_sheet_get_array(sh, FLT_SHEET_ZONE_I_UNITS, FIBERS, a));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count'", flt_sheet_get_array(sh, FLT_SHEET_FIBER_X, NEG, a));
    GOOD(flt_sheet_get_array(sh, FLT_SHEET_FIBER_I_UNITS, FIBERS, a));
    flt_sheet_destroy(sh);
    flt_gauge_destroy(g);
}

static void row_sheet_height_map(void) {
    flt_gauge *g = new_gauge(0);
    flt_sheet *sh = new_sheet(g);
    static double s[300], z[300 * FIBERS];
    static uint8_t f[300 * FIBERS];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sheet'", flt_sheet_height_map(NULL, 300, FIBERS, s, z, f));
    /* Wrong state: the gauge keeps no maps. */
    BAD(FLT_ERR_STATE, "gauge_keep_maps", flt_sheet_height_map(sh, 300, FIBERS, s, z, f));
    flt_sheet_destroy(sh);
    flt_gauge_destroy(g);
    g = new_gauge(1);
    sh = new_sheet(g);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows'", flt_sheet_height_map(sh, 299, FIBERS, s, z, f));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_sheet_height_map(sh, 300, FIBERS + 1, s, z, f));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows'", flt_sheet_height_map(sh, NEG, FIBERS, s, z, f));
    GOOD(flt_sheet_height_map(sh, 300, FIBERS, NULL, NULL, NULL));
    GOOD(flt_sheet_height_map(sh, 300, FIBERS, s, z, f));
    flt_sheet_destroy(sh);
    flt_gauge_destroy(g);
}

static void row_sheet_measured_map(void) {
    flt_gauge *g = new_gauge(1);
    flt_sheet *sh = new_sheet(g);
    static double h[300 * FIBERS];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sheet'", flt_sheet_measured_map(NULL, 300, FIBERS, h));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height_out'", flt_sheet_measured_map(sh, 300, FIBERS, NULL));
    BAD(FLT_ERR_STATE, "gauge_keep_maps", flt_sheet_measured_map(sh, 300, FIBERS, h));
    flt_sheet_destroy(sh);
    flt_gauge_destroy(g);
    g = new_gauge(2);
    sh = new_sheet(g);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows'", flt_sheet_measured_map(sh, 1, FIBERS, h));
    GOOD(flt_sheet_measured_map(sh, 300, FIBERS, h));
    flt_sheet_destroy(sh);
    flt_gauge_destroy(g);
}

/* ---------------------------------------------------------------------- */
/* verdict.h                                                               */
/* ---------------------------------------------------------------------- */

static const char g_rules_text[] =
    "{ \"format\": \"flatline-tolerances\", \"version\": 1, \"name\": \"bad input\",\n"
    "  \"rules\": [\n"
    "    { \"name\": \"1 m\", \"measure\": \"straightedge_along\", \"length_mm\": 1000,\n"
    "      \"bands\": [ { \"thickness_mm\": [0, 50], \"width_mm\": [0, 5000], \"limit\": 3 } ] },\n"
    "    { \"name\": \"IU\", \"measure\": \"zone_i_units\",\n"
    "      \"bands\": [ { \"thickness_mm\": [0, 50], \"width_mm\": [0, 5000], \"limit\": 10 } ] }\n"
    "  ] }\n";

static flt_rules *new_rules(void) {
    flt_rules *r = NULL;
    if (flt_rules_load_text(g_rules_text, sizeof g_rules_text - 1, &r)) {
        ERR("fixture rules: %s", flt_last_error_message());
        exit(2);
    }
    return r;
}

static flt_verdict *new_verdict(void) {
    flt_rules *r = new_rules();
    flt_verdict *v = NULL;
    if (flt_verdict_create(r, &v)) {
        ERR("fixture verdict: %s", flt_last_error_message());
        exit(2);
    }
    flt_rules_destroy(r);
    return v;
}

static void row_rules_load(void) {
    flt_rules *r = (flt_rules *)1;
    char path[300], bad_path[300];
    path_in_dir(path, sizeof path, "rules.json");
    write_file(path, g_rules_text, sizeof g_rules_text - 1);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_rules_load(path, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'path'", flt_rules_load(NULL, &r));
    BAD(FLT_ERR_IO, "no_such_file", flt_rules_load("/nonexistent/no_such_file.json", &r));
    BAD(FLT_ERR_IO, NULL, flt_rules_load(g_dir, &r)); /* a directory */
    path_in_dir(bad_path, sizeof bad_path, "rules_truncated.json");
    write_file(bad_path, g_rules_text, (sizeof g_rules_text - 1) / 3);
    BAD(FLT_ERR_FORMAT, "truncated", flt_rules_load(bad_path, &r));
    write_file(bad_path, "", 0);
    BAD(FLT_ERR_FORMAT, "empty", flt_rules_load(bad_path, &r));
    write_file(bad_path, "\x89PNG\r\n\x1a\n\0\0\0", 11);
    BAD(FLT_ERR_FORMAT, NULL, flt_rules_load(bad_path, &r));
    ++g_checks;
    if (r != NULL)
        ERR("*out not NULL after a failure");
    GOOD(flt_rules_load(path, &r));
    flt_rules_destroy(r);
}

static void row_rules_load_text(void) {
    flt_rules *r = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_rules_load_text(g_rules_text, 10, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'text'", flt_rules_load_text(NULL, 10, &r));
    BAD(FLT_ERR_FORMAT, "empty", flt_rules_load_text(g_rules_text, 0, &r));
    BAD(FLT_ERR_FORMAT, "'length'", flt_rules_load_text(g_rules_text, (size_t)-1, &r));
    BAD(FLT_ERR_FORMAT, "truncated", flt_rules_load_text(g_rules_text, 40, &r));
    static const char nan_limit[] =
        "{ \"format\": \"flatline-tolerances\", \"version\": 1, \"name\": \"x\", \"rules\": [\n"
        "  { \"name\": \"b\", \"measure\": \"bow\", \"bands\": [\n"
        "    { \"thickness_mm\": [0, 5], \"width_mm\": [0, 5], \"limit\": NaN } ] } ] }";
    BAD(FLT_ERR_FORMAT, "rules[0].bands[0].limit' is NaN",
        flt_rules_load_text(nan_limit, sizeof nan_limit - 1, &r));
    GOOD(flt_rules_load_text(g_rules_text, sizeof g_rules_text - 1, &r));
    flt_rules_destroy(r);
}

static void row_rules_destroy(void) {
    flt_rules_destroy(NULL);
    uint64_t junk[32] = {0};
    flt_rules_destroy((flt_rules *)junk); /* not a rule set: left alone */
    g_checks += 2;
}

static void row_rules_count(void) {
    flt_rules *r = new_rules();
    size_t n;
    uint64_t junk[32] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rules'", flt_rules_count(NULL, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live", flt_rules_count((flt_rules *)junk, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_rules_count(r, NULL));
    GOOD(flt_rules_count(r, &n));
    flt_rules_destroy(r);
}

static void row_rules_rule(void) {
    flt_rules *r = new_rules();
    const char *name;
    flt_measure m;
    double len;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rules'", flt_rules_rule(NULL, 0, &name, &m, &len));
    BAD(FLT_ERR_NOT_FOUND, "'index' = 2", flt_rules_rule(r, 2, &name, &m, &len));
    BAD(FLT_ERR_NOT_FOUND, "'index'", flt_rules_rule(r, (size_t)-1, &name, &m, &len));
    GOOD(flt_rules_rule(r, 1, NULL, NULL, NULL));
    GOOD(flt_rules_rule(r, 0, &name, &m, &len));
    flt_rules_destroy(r);
}

static void row_straightedge_profile(void) {
    const double p[4] = {0, 1, 2, 3}, z[4] = {0, -1, 0, 0.5};
    const double bad_p[4] = {0, 1, 1, 3}, nan_p[4] = {0, NaN_, 2, 3};
    const double inf_z[4] = {0, Inf_, 0, 0}, nan_z[4] = {NaN_, NaN_, NaN_, 1};
    double d, at;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'deviation_mm'",
        flt_straightedge_profile(p, z, 4, 2, NULL, &at));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'position_mm'",
        flt_straightedge_profile(NULL, z, 4, 2, &d, &at));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height_mm'", flt_straightedge_profile(p, NULL, 4, 2, &d, &at));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count'",
        flt_straightedge_profile(p, z, (size_t)-1, 2, &d, &at));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'length_mm'", flt_straightedge_profile(p, z, 4, 0, &d, &at));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'length_mm'", flt_straightedge_profile(p, z, 4, -1, &d, &at));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'length_mm'", flt_straightedge_profile(p, z, 4, NaN_, &d, &at));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'length_mm'", flt_straightedge_profile(p, z, 4, Inf_, &d, &at));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'length_mm'", flt_straightedge_profile(p, z, 4, 1e300, &d, &at));
    BAD(FLT_ERR_INVALID_ARGUMENT, "increase strictly",
        flt_straightedge_profile(bad_p, z, 4, 2, &d, &at));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'position_mm'[1]",
        flt_straightedge_profile(nan_p, z, 4, 2, &d, &at));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height_mm'[1] is infinite",
        flt_straightedge_profile(p, inf_z, 4, 2, &d, &at));
    BAD(FLT_ERR_NOT_FOUND, "fewer than 2", flt_straightedge_profile(p, nan_z, 4, 2, &d, &at));
    BAD(FLT_ERR_NOT_FOUND, "fewer than 2", flt_straightedge_profile(NULL, NULL, 0, 2, &d, &at));
    GOOD(flt_straightedge_profile(p, z, 4, 2, &d, NULL));
    ++g_checks;
    if (d != 1.0) /* contacts 0 and 2 at height 0, the sample between at -1 */
        ERR("deviation %g, not 1", d);
}

static void row_verdict_create(void) {
    flt_rules *r = new_rules();
    flt_verdict *v = (flt_verdict *)1;
    uint64_t junk[32] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_verdict_create(r, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rules'", flt_verdict_create(NULL, &v));
    ++g_checks;
    if (v != NULL)
        ERR("*out not NULL after a failure");
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live", flt_verdict_create((flt_rules *)junk, &v));
    GOOD(flt_verdict_create(r, &v));
    flt_rules_destroy(r);
    flt_verdict_destroy(v);
}

static void row_verdict_destroy(void) {
    flt_verdict_destroy(NULL);
    uint64_t junk[32] = {0};
    flt_verdict_destroy((flt_verdict *)junk); /* not a verdict: left alone */
    g_checks += 2;
}

static void row_verdict_set_measure(void) {
    flt_verdict *v = new_verdict();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'verdict'",
        flt_verdict_set_measure(NULL, FLT_MEASURE_BOW, 1, 0, 0));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'measure' = -1",
                flt_verdict_set_measure(v, (flt_measure)-1, 1, 0, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'measure' = 7",
        flt_verdict_set_measure(v, (flt_measure)7, 1, 0, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "straightedge",
        flt_verdict_set_measure(v, FLT_MEASURE_STRAIGHTEDGE_ALONG, 1, 0, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'value' is infinite",
        flt_verdict_set_measure(v, FLT_MEASURE_BOW, Inf_, 0, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "negative",
        flt_verdict_set_measure(v, FLT_MEASURE_ZONE_I_UNITS, -1, 0, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'x_mm'",
        flt_verdict_set_measure(v, FLT_MEASURE_BOW, 1, NaN_, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'s_mm'",
        flt_verdict_set_measure(v, FLT_MEASURE_BOW, 1, 0, Inf_));
    GOOD(flt_verdict_set_measure(v, FLT_MEASURE_BOW, -1, 0, 0));
    GOOD(flt_verdict_set_measure(v, FLT_MEASURE_BOW, NaN_, NaN_, NaN_));
    flt_verdict_destroy(v);
}

static void row_verdict_evaluate(void) {
    flt_verdict *v = new_verdict();
    enum { R = 3, K = 2 };
    const double s[R] = {0, 1, 2}, x[K] = {0, 10}, z[R * K] = {0, 0, -1, -1, 0, 0};
    const double bad_s[R] = {0, 2, 1}, inf_z[R * K] = {0, 0, Inf_, 0, 0, 0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'verdict'",
        flt_verdict_evaluate(NULL, 2, 1000, R, K, s, x, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'thickness_mm'",
        flt_verdict_evaluate(v, 0, 1000, R, K, s, x, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'thickness_mm'",
        flt_verdict_evaluate(v, NaN_, 1000, R, K, s, x, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'thickness_mm'",
        flt_verdict_evaluate(v, 1e6, 1000, R, K, s, x, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width_mm'",
        flt_verdict_evaluate(v, 2, -5, R, K, s, x, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width_mm'",
        flt_verdict_evaluate(v, 2, Inf_, R, K, s, x, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows'", flt_verdict_evaluate(v, 2, 1000, 0, K, s, x, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'s_mm'",
        flt_verdict_evaluate(v, 2, 1000, R, K, NULL, x, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'x_mm'",
        flt_verdict_evaluate(v, 2, 1000, R, K, s, NULL, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'z_mm'",
        flt_verdict_evaluate(v, 2, 1000, R, K, s, x, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "overflow",
        flt_verdict_evaluate(v, 2, 1000, (size_t)-1, (size_t)-1, s, x, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "increase strictly",
        flt_verdict_evaluate(v, 2, 1000, R, K, bad_s, x, z, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'z_mm'[2] is infinite",
        flt_verdict_evaluate(v, 2, 1000, R, K, s, x, inf_z, NULL));
    GOOD(flt_verdict_evaluate(v, 2, 1000, R, K, s, x, z, NULL));
    GOOD(flt_verdict_evaluate(v, 2, 1000, 0, 0, NULL, NULL, NULL, NULL));
    flt_verdict_destroy(v);
}

static void row_verdict_get(void) {
    flt_verdict *v = new_verdict();
    double d;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'verdict'", flt_verdict_get(NULL, 0, FLT_VERDICT_STATE, &d));
    BAD(FLT_ERR_STATE, "no sheet", flt_verdict_get(v, 0, FLT_VERDICT_STATE, &d));
    const double s[2] = {0, 1}, x[2] = {0, 1}, z[4] = {0, 0, 0, 0};
    if (flt_verdict_evaluate(v, 2, 1000, 2, 2, s, x, z, NULL))
        ERR("evaluate: %s", flt_last_error_message());
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_verdict_get(v, 0, FLT_VERDICT_STATE, NULL));
    BAD(FLT_ERR_NOT_FOUND, "'rule' = 2", flt_verdict_get(v, 2, FLT_VERDICT_STATE, &d));
    ENUM_UB_BAD(FLT_ERR_NOT_FOUND, "'key' = -1", flt_verdict_get(v, 0, (flt_verdict_value)-1, &d));
    BAD(FLT_ERR_NOT_FOUND, "'key' = 9", flt_verdict_get(v, 0, (flt_verdict_value)9, &d));
    GOOD(flt_verdict_get(v, 0, FLT_VERDICT_MARGIN, &d));
    flt_verdict_destroy(v);
}

static void row_verdict_failed(void) {
    flt_verdict *v = new_verdict();
    size_t n;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'verdict'", flt_verdict_failed(NULL, &n));
    BAD(FLT_ERR_STATE, "no sheet", flt_verdict_failed(v, &n));
    if (flt_verdict_evaluate(v, 2, 1000, 0, 0, NULL, NULL, NULL, NULL))
        ERR("evaluate: %s", flt_last_error_message());
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_verdict_failed(v, NULL));
    GOOD(flt_verdict_failed(v, &n));
    flt_verdict_destroy(v);
}

/* The gauge's verdicts (gauge.h, "Verdicts and coil statistics"). */

static void row_gauge_set_rules(void) {
    flt_gauge *g = new_gauge(0);
    flt_rules *r = new_rules();
    uint64_t junk[32] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_set_rules(NULL, r, 4.0, 0.0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live",
        flt_gauge_set_rules(g, (const flt_rules *)junk, 4.0, 0.0));
    const double thickness[] = {0.0, -1.0, NAN, INFINITY, 1e300, 1000.5};
    for (size_t i = 0; i < sizeof thickness / sizeof *thickness; ++i)
        BAD(FLT_ERR_INVALID_ARGUMENT, "'thickness_mm'",
            flt_gauge_set_rules(g, r, thickness[i], 0.0));
    const double width[] = {-1.0, NAN, INFINITY, -INFINITY, 1e300, -0.0 - 1e-300};
    for (size_t i = 0; i < sizeof width / sizeof *width; ++i)
        BAD(FLT_ERR_INVALID_ARGUMENT, "'width_mm'", flt_gauge_set_rules(g, r, 4.0, width[i]));
    GOOD(flt_gauge_set_rules(g, r, 4.0, 1500.0));
    GOOD(flt_gauge_set_rules(g, NULL, 4.0, 0.0));
    GOOD(flt_gauge_set_rules(g, r, 4.0, 0.0));
    flt_rules_destroy(r); /* the gauge keeps its own copy */
    flt_sheet *sh = new_sheet(g);
    double n = 0;
    GOOD(flt_sheet_get(sh, FLT_SHEET_RULES, &n));
    ++g_checks;
    if (n != 2.0)
        ERR("the sheet was judged by %g rules, not 2", n);
    flt_sheet_destroy(sh);
    flt_gauge_destroy(g);
}

static void row_gauge_coil_stats(void) {
    flt_gauge *g = new_gauge(0);
    double v[FLT_COIL_VALUES + 1];
    BAD(FLT_ERR_STATE, "flt_gauge_set_rules", flt_gauge_coil_stats(g, FLT_COIL_CURRENT, 0, 1, v));
    flt_rules *r = new_rules();
    GOOD(flt_gauge_set_rules(g, r, 4.0, 0.0));
    flt_rules_destroy(r);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_coil_stats(NULL, FLT_COIL_CURRENT, 0, 1, v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_gauge_coil_stats(g, FLT_COIL_CURRENT, 0, 1, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'which' = 2", flt_gauge_coil_stats(g, (flt_coil)2, 0, 1, v));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'which' = -1",
                flt_gauge_coil_stats(g, (flt_coil)-1, 0, 1, v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count' = 0",
        flt_gauge_coil_stats(g, FLT_COIL_CURRENT, 0, 0, v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count'", flt_gauge_coil_stats(g, FLT_COIL_CURRENT, 0, NEG, v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count'",
        flt_gauge_coil_stats(g, FLT_COIL_CURRENT, 0, FLT_COIL_VALUES + 1, v));
    BAD(FLT_ERR_NOT_FOUND, "'rule' = 2", flt_gauge_coil_stats(g, FLT_COIL_CURRENT, 2, 1, v));
    BAD(FLT_ERR_NOT_FOUND, "'rule'", flt_gauge_coil_stats(g, FLT_COIL_CURRENT, NEG, 1, v));
    BAD(FLT_ERR_STATE, "no coil", flt_gauge_coil_stats(g, FLT_COIL_LAST, 0, 1, v));
    GOOD(flt_gauge_coil_stats(g, FLT_COIL_CURRENT, 1, FLT_COIL_VALUES, v));
    /* One flushed strip: a finished coil of one sheet. */
    make_waiting_sheet(g, 0.0);
    GOOD(flt_gauge_coil_stats(g, FLT_COIL_LAST, 0, FLT_COIL_VALUES, v));
    ++g_checks;
    if (v[FLT_COIL_SHEETS] != 1.0 || v[FLT_COIL_FINISHED] != 1.0)
        ERR("the finished coil has %g sheets (finished %g), not 1 (1)", v[FLT_COIL_SHEETS],
            v[FLT_COIL_FINISHED]);
    flt_gauge_destroy(g);
}

static void row_sheet_verdict(void) {
    flt_gauge *g = new_gauge(0);
    flt_sheet *sh = new_sheet(g);
    const flt_rules *rules = NULL;
    const flt_verdict *v = NULL;
    uint64_t junk[64] = {0};
    BAD(FLT_ERR_STATE, "flt_gauge_set_rules", flt_sheet_verdict(sh, &rules, &v));
    flt_sheet_destroy(sh);
    flt_rules *r = new_rules();
    GOOD(flt_gauge_set_rules(g, r, 4.0, 0.0));
    flt_rules_destroy(r);
    sh = new_sheet(g);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sheet'", flt_sheet_verdict(NULL, &rules, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live",
        flt_sheet_verdict((const flt_sheet *)junk, &rules, &v));
    GOOD(flt_sheet_verdict(sh, NULL, NULL));
    GOOD(flt_sheet_verdict(sh, &rules, &v));
    /* The sheet's handles are read-only and not the caller's to free. */
    BAD(FLT_ERR_STATE, "read-only",
        flt_verdict_evaluate((flt_verdict *)v, 4.0, 1000.0, 0, 0, NULL, NULL, NULL, NULL));
    BAD(FLT_ERR_STATE, "read-only",
        flt_verdict_set_measure((flt_verdict *)v, FLT_MEASURE_BOW, 1.0, 0.0, 0.0));
    flt_verdict_destroy((flt_verdict *)v);
    flt_rules_destroy((flt_rules *)rules);
    double st = -1;
    size_t n = 0;
    GOOD(flt_verdict_get(v, 0, FLT_VERDICT_STATE, &st));
    GOOD(flt_rules_count(rules, &n));
    ++g_checks;
    if (n != 2 || !(st == FLT_VERDICT_PASS))
        ERR("the flat sheet's verdict: %zu rules, state %g (want 2, PASS)", n, st);
    flt_sheet_destroy(sh);
    flt_gauge_destroy(g);
}

/* ---------------------------------------------------------------------- */
/* advisor.h                                                               */
/* ---------------------------------------------------------------------- */

static const char g_leveler_text[] =
    "{ \"format\": \"flatline-leveler\", \"version\": 1, \"zones\": 3,\n"
    "  \"actuators\": [ { \"name\": \"tilt\", \"unit\": \"mm\", \"min\": -2, \"max\": 2,\n"
    "                   \"step\": 0.5 } ],\n"
    "  \"influence\": [ [ -5 ], [ 0 ], [ 5 ] ] }\n";

/* A ready advisor: 3 zones, 1 actuator (tilt, [-2, 2] mm, step 0.5). */
static flt_advisor *new_advisor(void) {
    flt_advisor *a = NULL;
    if (flt_advisor_load_text(g_leveler_text, sizeof g_leveler_text - 1, NULL, &a)) {
        ERR("fixture advisor: %s", flt_last_error_message());
        exit(2);
    }
    return a;
}

static void row_advisor_create(void) {
    flt_advisor *a = (flt_advisor *)1;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_advisor_create(3, 2, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'zones' = 0", flt_advisor_create(0, 2, NULL, &a));
    ++g_checks;
    if (a != NULL)
        ERR("*out not NULL after a failure");
    BAD(FLT_ERR_INVALID_ARGUMENT, "'zones'", flt_advisor_create(NEG, 2, NULL, &a));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'zones' = 1025", flt_advisor_create(1025, 2, NULL, &a));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'actuators' = 0", flt_advisor_create(3, 0, NULL, &a));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'actuators' = 65", flt_advisor_create(3, 65, NULL, &a));
    /* another component's key; the advisor's own out of range is refused
     * by flt_options_set already */
    flt_options *other = options_with(FLT_OPT_FLAT_ZONE_WIDTH, 100);
    BAD(FLT_ERR_INVALID_ARGUMENT, "flat_zone_width", flt_advisor_create(3, 2, other, &a));
    flt_options_destroy(other);
    flt_options *o = NULL;
    GOOD(flt_options_create(&o));
    BAD(FLT_ERR_INVALID_ARGUMENT, "advisor_gain", flt_options_set(o, FLT_OPT_ADVISOR_GAIN, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "advisor_damping",
        flt_options_set(o, FLT_OPT_ADVISOR_DAMPING, NaN_));
    GOOD(flt_options_set(o, FLT_OPT_ADVISOR_GAIN, 1));
    GOOD(flt_advisor_create(1024, 64, o, &a));
    flt_options_destroy(o);
    flt_advisor_destroy(a);
}

static void row_advisor_load(void) {
    char path[300], bad_path[300];
    flt_advisor *a = NULL;
    path_in_dir(path, sizeof path, "leveler.json");
    write_file(path, g_leveler_text, sizeof g_leveler_text - 1);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_advisor_load(path, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'path'", flt_advisor_load(NULL, NULL, &a));
    BAD(FLT_ERR_IO, "no_such_file", flt_advisor_load("/nonexistent/no_such_file.json", NULL, &a));
    BAD(FLT_ERR_IO, "directory", flt_advisor_load(g_dir, NULL, &a));
    path_in_dir(bad_path, sizeof bad_path, "leveler_truncated.json");
    write_file(bad_path, g_leveler_text, (sizeof g_leveler_text - 1) / 2);
    BAD(FLT_ERR_FORMAT, "leveler file", flt_advisor_load(bad_path, NULL, &a));
    write_file(bad_path, "", 0);
    BAD(FLT_ERR_FORMAT, NULL, flt_advisor_load(bad_path, NULL, &a));
    flt_options *other = options_with(FLT_OPT_GAUGE_WORKERS, 1);
    BAD(FLT_ERR_INVALID_ARGUMENT, "gauge_workers", flt_advisor_load(path, other, &a));
    flt_options_destroy(other);
    GOOD(flt_advisor_load(path, NULL, &a));
    flt_advisor_destroy(a);
}

static void row_advisor_load_text(void) {
    flt_advisor *a = NULL;
    const size_t n = sizeof g_leveler_text - 1;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_advisor_load_text(g_leveler_text, n, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'text'", flt_advisor_load_text(NULL, n, NULL, &a));
    BAD(FLT_ERR_FORMAT, NULL, flt_advisor_load_text(g_leveler_text, 0, NULL, &a));
    BAD(FLT_ERR_FORMAT, "'length'", flt_advisor_load_text(g_leveler_text, NEG, NULL, &a));
    BAD(FLT_ERR_FORMAT, NULL, flt_advisor_load_text(g_leveler_text, 40, NULL, &a));
    static const char nan_g[] =
        "{ \"format\": \"flatline-leveler\", \"version\": 1, \"zones\": 1,\n"
        "  \"actuators\": [ { \"name\": \"t\", \"unit\": \"\", \"min\": 0, \"max\": 1, "
        "\"step\": 1 } ],\n"
        "  \"influence\": [ [ NaN ] ] }";
    BAD(FLT_ERR_FORMAT, "'influence[0][0]' is NaN (line 3)",
        flt_advisor_load_text(nan_g, sizeof nan_g - 1, NULL, &a));
    flt_options *other = options_with(FLT_OPT_SIM_SEED, 3);
    BAD(FLT_ERR_INVALID_ARGUMENT, "sim_seed", flt_advisor_load_text(g_leveler_text, n, other, &a));
    flt_options_destroy(other);
    GOOD(flt_advisor_load_text(g_leveler_text, n, NULL, &a));
    flt_advisor_destroy(a);
}

static void row_advisor_destroy(void) {
    flt_advisor_destroy(NULL);
    uint64_t junk[32] = {0};
    flt_advisor_destroy((flt_advisor *)junk); /* not an advisor: left alone */
    g_checks += 2;
}

static void row_advisor_size(void) {
    flt_advisor *a = new_advisor();
    uint64_t junk[32] = {0};
    size_t z = 0, n = 0;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'advisor'", flt_advisor_size(NULL, &z, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live", flt_advisor_size((flt_advisor *)junk, &z, &n));
    GOOD(flt_advisor_size(a, NULL, NULL));
    GOOD(flt_advisor_size(a, &z, &n));
    ++g_checks;
    if (z != 3 || n != 1)
        ERR("size %zu x %zu, not 3 x 1", z, n);
    flt_advisor_destroy(a);
}

static void row_advisor_set_actuator(void) {
    flt_advisor *a = new_advisor();
    char long_name[80];
    memset(long_name, 'n', sizeof long_name - 1);
    long_name[sizeof long_name - 1] = 0;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'advisor'",
        flt_advisor_set_actuator(NULL, 0, "tilt", "mm", -1, 1, 0.5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'index' = 1",
        flt_advisor_set_actuator(a, 1, "tilt", "mm", -1, 1, 0.5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'index'",
        flt_advisor_set_actuator(a, NEG, "tilt", "mm", -1, 1, 0.5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'name'", flt_advisor_set_actuator(a, 0, NULL, "mm", -1, 1, 0.5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'name'", flt_advisor_set_actuator(a, 0, "", "mm", -1, 1, 0.5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'name'",
        flt_advisor_set_actuator(a, 0, long_name, "mm", -1, 1, 0.5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'unit'",
        flt_advisor_set_actuator(a, 0, "tilt", NULL, -1, 1, 0.5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'unit'",
        flt_advisor_set_actuator(a, 0, "tilt", long_name, -1, 1, 0.5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'min'",
        flt_advisor_set_actuator(a, 0, "tilt", "mm", NaN_, 1, 0.5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'min'",
        flt_advisor_set_actuator(a, 0, "tilt", "mm", -1e300, 1, 0.5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'max'",
        flt_advisor_set_actuator(a, 0, "tilt", "mm", -1, Inf_, 0.5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "greater than min",
        flt_advisor_set_actuator(a, 0, "tilt", "mm", 1, 1, 0.5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'step'", flt_advisor_set_actuator(a, 0, "tilt", "mm", -1, 1, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'step'",
        flt_advisor_set_actuator(a, 0, "tilt", "mm", -1, 1, NaN_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'step'",
        flt_advisor_set_actuator(a, 0, "tilt", "mm", -1, 1, 1e12));
    GOOD(flt_advisor_set_actuator(a, 0, "tilt", "", -1, 1, 0.5));
    flt_advisor_destroy(a);
}

static void row_advisor_actuator(void) {
    flt_advisor *a = new_advisor();
    const char *name = NULL, *unit = NULL;
    double mn = 0, mx = 0, st = 0;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'advisor'",
        flt_advisor_actuator(NULL, 0, &name, &unit, &mn, &mx, &st));
    BAD(FLT_ERR_NOT_FOUND, "'index' = 1", flt_advisor_actuator(a, 1, &name, &unit, &mn, &mx, &st));
    BAD(FLT_ERR_NOT_FOUND, "'index'", flt_advisor_actuator(a, NEG, &name, &unit, &mn, &mx, &st));
    GOOD(flt_advisor_actuator(a, 0, NULL, NULL, NULL, NULL, NULL));
    GOOD(flt_advisor_actuator(a, 0, &name, &unit, &mn, &mx, &st));
    ++g_checks;
    if (strcmp(name, "tilt") != 0 || mn != -2 || mx != 2 || st != 0.5)
        ERR("actuator 0 is %s [%g, %g] %g", name, mn, mx, st);
    flt_advisor_destroy(a);
}

static void row_advisor_set_influence(void) {
    flt_advisor *a = new_advisor();
    const double g[3] = {-4, 0, 4}, nan_g[3] = {0, NaN_, 0}, big_g[3] = {0, 1e10, 0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'advisor'", flt_advisor_set_influence(NULL, g, 3));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'g'", flt_advisor_set_influence(a, NULL, 3));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'g_count' = 2", flt_advisor_set_influence(a, g, 2));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'g_count'", flt_advisor_set_influence(a, g, NEG));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'g'[1]", flt_advisor_set_influence(a, nan_g, 3));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'g'[1]", flt_advisor_set_influence(a, big_g, 3));
    GOOD(flt_advisor_set_influence(a, g, 3));
    flt_advisor_destroy(a);
}

static void row_advisor_influence(void) {
    flt_advisor *a = new_advisor();
    double g[3] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'advisor'", flt_advisor_influence(NULL, g, 3));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'g_out'", flt_advisor_influence(a, NULL, 3));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'g_count' = 4", flt_advisor_influence(a, g, 4));
    GOOD(flt_advisor_influence(a, g, 3));
    ++g_checks;
    if (g[0] != -5 || g[2] != 5)
        ERR("G = [%g %g %g]", g[0], g[1], g[2]);
    flt_advisor_destroy(a);
}

static void row_advisor_set_target(void) {
    flt_advisor *a = new_advisor();
    const double t[3] = {0, 1, 0}, inf_t[3] = {0, Inf_, 0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'advisor'", flt_advisor_set_target(NULL, t, 3));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'target_count' = 3", flt_advisor_set_target(a, NULL, 3));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'target_count' = 2", flt_advisor_set_target(a, t, 2));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'target'[1]", flt_advisor_set_target(a, inf_t, 3));
    GOOD(flt_advisor_set_target(a, t, 3));
    GOOD(flt_advisor_set_target(a, NULL, 0));
    flt_advisor_destroy(a);
}

static void row_advisor_identify(void) {
    flt_advisor *a = new_advisor();
    /* 3 steps of the one actuator, the profile following G = (-5, 0, 5) */
    const double du[3] = {0.5, -0.5, 0.25};
    const double dp[9] = {-2.5, 0, 2.5, 2.5, 0, -2.5, -1.25, 0, 1.25};
    const double nan_du[3] = {0.5, NaN_, 0.25};
    const double flat_dp[9] = {1, 1, 1, 2, 2, 2, 3, 3, 3};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'advisor'", flt_advisor_identify(NULL, 3, du, 3, dp, 9, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'delta_u'", flt_advisor_identify(a, 3, NULL, 3, dp, 9, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'delta_p'", flt_advisor_identify(a, 3, du, 3, NULL, 9, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'steps' = 0", flt_advisor_identify(a, 0, du, 0, dp, 0, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'steps'", flt_advisor_identify(a, NEG, du, 3, dp, 9, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'delta_u_count' = 2",
        flt_advisor_identify(a, 3, du, 2, dp, 9, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'delta_p_count' = 8",
        flt_advisor_identify(a, 3, du, 3, dp, 8, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'ridge'", flt_advisor_identify(a, 3, du, 3, dp, 9, -1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'ridge'", flt_advisor_identify(a, 3, du, 3, dp, 9, NaN_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'delta_u'[1]", flt_advisor_identify(a, 3, nan_du, 3, dp, 9, 0));
    BAD(FLT_ERR_NUMERIC, "at least 2", flt_advisor_identify(a, 1, du, 1, dp, 3, 0));
    BAD(FLT_ERR_NUMERIC, "all zero", flt_advisor_identify(a, 3, du, 3, flat_dp, 9, 0));
    GOOD(flt_advisor_identify(a, 3, du, 3, dp, 9, 0));
    flt_advisor_destroy(a);
}

static void row_advisor_fit(void) {
    flt_advisor *a = new_advisor();
    double r2 = 0, rms = 0;
    size_t steps = 9;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'advisor'", flt_advisor_fit(NULL, &r2, &rms, &steps));
    GOOD(flt_advisor_fit(a, NULL, NULL, NULL));
    GOOD(flt_advisor_fit(a, &r2, &rms, &steps));
    ++g_checks;
    if (r2 != 1 || rms != 0 || steps != 0)
        ERR("a file's G: fit %g %g %zu, not 1 0 0", r2, rms, steps);
    flt_advisor_destroy(a);
}

static void row_advisor_advise(void) {
    flt_advisor *a = new_advisor();
    const double p[3] = {10, 5, 0}, u[1] = {0}, out_of_range[1] = {3};
    const double inf_p[3] = {0, Inf_, 0}, one_p[3] = {NaN_, 5, NaN_}, gap_p[3] = {10, NaN_, 0};
    double d[1], pred[3], c;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'advisor'",
        flt_advisor_advise(NULL, p, 3, u, 1, u, 1, d, 1, pred, 3, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'profile'",
        flt_advisor_advise(a, NULL, 3, u, 1, u, 1, d, 1, pred, 3, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'settings_sheet'",
        flt_advisor_advise(a, p, 3, NULL, 1, u, 1, d, 1, pred, 3, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'settings_now'",
        flt_advisor_advise(a, p, 3, u, 1, NULL, 1, d, 1, pred, 3, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'delta_out'",
        flt_advisor_advise(a, p, 3, u, 1, u, 1, NULL, 1, pred, 3, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'profile_count' = 2",
        flt_advisor_advise(a, p, 2, u, 1, u, 1, d, 1, pred, 3, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'settings_sheet_count'",
        flt_advisor_advise(a, p, 3, u, NEG, u, 1, d, 1, pred, 3, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'settings_now_count'",
        flt_advisor_advise(a, p, 3, u, 1, u, 0, d, 1, pred, 3, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'delta_count'",
        flt_advisor_advise(a, p, 3, u, 1, u, 1, d, 2, pred, 3, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'predicted_count'",
        flt_advisor_advise(a, p, 3, u, 1, u, 1, d, 1, pred, 2, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'predicted_count'",
        flt_advisor_advise(a, p, 3, u, 1, u, 1, d, 1, NULL, 3, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'profile'[1]",
        flt_advisor_advise(a, inf_p, 3, u, 1, u, 1, d, 1, pred, 3, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "1 measured zone",
        flt_advisor_advise(a, one_p, 3, u, 1, u, 1, d, 1, pred, 3, &c));
    /* a zone without data (NaN) takes no part; its prediction is NaN */
    GOOD(flt_advisor_advise(a, gap_p, 3, u, 1, u, 1, d, 1, pred, 3, &c));
    ++g_checks;
    if (!isnan(pred[1]) || isnan(pred[0]) || isnan(pred[2]))
        ERR("predicted %g %g %g: NaN only where the profile is", pred[0], pred[1], pred[2]);
    BAD(FLT_ERR_INVALID_ARGUMENT, "outside the range",
        flt_advisor_advise(a, p, 3, u, 1, out_of_range, 1, d, 1, pred, 3, &c));
    /* wrong order: no G yet, an actuator not described */
    flt_advisor *empty = NULL;
    GOOD(flt_advisor_create(3, 1, NULL, &empty));
    BAD(FLT_ERR_STATE, "not described",
        flt_advisor_advise(empty, p, 3, u, 1, u, 1, d, 1, NULL, 0, NULL));
    GOOD(flt_advisor_set_actuator(empty, 0, "tilt", "mm", -1, 1, 0.5));
    BAD(FLT_ERR_STATE, "no influence matrix",
        flt_advisor_advise(empty, p, 3, u, 1, u, 1, d, 1, NULL, 0, NULL));
    flt_advisor_destroy(empty);
    GOOD(flt_advisor_advise(a, p, 3, u, 1, u, 1, d, 1, pred, 3, &c));
    GOOD(flt_advisor_advise(a, p, 3, u, 1, u, 1, d, 1, NULL, 0, NULL));
    ++g_checks;
    /* p leans to zone 0 (+5 against the mean): G's -5 on zone 0 says move
     * tilt up, by at most the step. */
    if (!(d[0] > 0 && d[0] <= 0.5))
        ERR("advice %g, not in (0, 0.5]", d[0]);
    flt_advisor_destroy(a);
}

/* testing.h: the hidden leveler */

static flt_leveler_sim *new_leveler(void) {
    const double g[3] = {-5, 0, 5}, e0[3] = {10, 0, 0};
    flt_leveler_sim *l = NULL;
    if (flt_leveler_sim_create(3, 1, -100, 100, g, 3, e0, 3, 0.1, 1, &l)) {
        ERR("fixture leveler: %s", flt_last_error_message());
        exit(2);
    }
    return l;
}

static void row_leveler_sim_create(void) {
    const double g[3] = {-5, 0, 5}, e0[3] = {10, 0, 0}, nan_e[3] = {0, NaN_, 0};
    flt_leveler_sim *l = (flt_leveler_sim *)1;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'",
        flt_leveler_sim_create(3, 1, -100, 100, g, 3, e0, 3, 0.1, 1, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'zones'",
        flt_leveler_sim_create(0, 1, -100, 100, g, 3, e0, 3, 0.1, 1, &l));
    ++g_checks;
    if (l != NULL)
        ERR("*out not NULL after a failure");
    BAD(FLT_ERR_INVALID_ARGUMENT, "'actuators'",
        flt_leveler_sim_create(3, 65, -100, 100, g, 3, e0, 3, 0.1, 1, &l));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'zone_x0_mm'",
        flt_leveler_sim_create(3, 1, NaN_, 100, g, 3, e0, 3, 0.1, 1, &l));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'zone_width_mm'",
        flt_leveler_sim_create(3, 1, -100, 0, g, 3, e0, 3, 0.1, 1, &l));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'g_true'",
        flt_leveler_sim_create(3, 1, -100, 100, NULL, 3, e0, 3, 0.1, 1, &l));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'g_count'",
        flt_leveler_sim_create(3, 1, -100, 100, g, 2, e0, 3, 0.1, 1, &l));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'incoming'",
        flt_leveler_sim_create(3, 1, -100, 100, g, 3, NULL, 3, 0.1, 1, &l));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'incoming_count'",
        flt_leveler_sim_create(3, 1, -100, 100, g, 3, e0, NEG, 0.1, 1, &l));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'incoming'[1]",
        flt_leveler_sim_create(3, 1, -100, 100, g, 3, nan_e, 3, 0.1, 1, &l));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'noise_iu'",
        flt_leveler_sim_create(3, 1, -100, 100, g, 3, e0, 3, -1, 1, &l));
    GOOD(flt_leveler_sim_create(3, 1, -100, 100, g, 3, e0, 3, 0.1, 1, &l));
    flt_leveler_sim_destroy(l);
}

static void row_leveler_sim_destroy(void) {
    flt_leveler_sim_destroy(NULL);
    uint64_t junk[32] = {0};
    flt_leveler_sim_destroy((flt_leveler_sim *)junk); /* not a leveler: left alone */
    g_checks += 2;
}

static void row_leveler_sim_set_settings(void) {
    flt_leveler_sim *l = new_leveler();
    const double u[1] = {0.5}, inf_u[1] = {Inf_};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'leveler'", flt_leveler_sim_set_settings(NULL, u, 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'settings'", flt_leveler_sim_set_settings(l, NULL, 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'settings_count'", flt_leveler_sim_set_settings(l, u, 2));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'settings'[0]", flt_leveler_sim_set_settings(l, inf_u, 1));
    GOOD(flt_leveler_sim_set_settings(l, u, 1));
    flt_leveler_sim_destroy(l);
}

static void row_leveler_sim_set_incoming(void) {
    flt_leveler_sim *l = new_leveler();
    const double e[3] = {0, 5, 0}, nan_e[3] = {NaN_, 0, 0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'leveler'", flt_leveler_sim_set_incoming(NULL, e, 3));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'incoming'", flt_leveler_sim_set_incoming(l, NULL, 3));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'incoming_count'", flt_leveler_sim_set_incoming(l, e, 4));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'incoming'[0]", flt_leveler_sim_set_incoming(l, nan_e, 3));
    GOOD(flt_leveler_sim_set_incoming(l, e, 3));
    flt_leveler_sim_destroy(l);
}

static void row_leveler_sim_next_sheet(void) {
    flt_leveler_sim *l = new_leveler();
    double e[3], u[1];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'leveler'",
        flt_leveler_sim_next_sheet(NULL, g_sim, 0, 3000, 500, e, 3, u, 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sim'",
        flt_leveler_sim_next_sheet(l, NULL, 0, 3000, 500, e, 3, u, 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'s0_mm'",
        flt_leveler_sim_next_sheet(l, g_sim, NaN_, 3000, 500, e, 3, u, 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'length_mm'",
        flt_leveler_sim_next_sheet(l, g_sim, 0, 0, 500, e, 3, u, 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'length_mm'",
        flt_leveler_sim_next_sheet(l, g_sim, 0, 1e300, 500, e, 3, u, 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'period_mm'",
        flt_leveler_sim_next_sheet(l, g_sim, 0, 3000, 1e-3, e, 3, u, 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'period_mm'",
        flt_leveler_sim_next_sheet(l, g_sim, 0, 3000, 4000, e, 3, u, 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'elongation_count'",
        flt_leveler_sim_next_sheet(l, g_sim, 0, 3000, 500, e, 2, u, 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'settings_count'",
        flt_leveler_sim_next_sheet(l, g_sim, 0, 3000, 500, e, 3, u, 0));
    GOOD(flt_leveler_sim_next_sheet(l, g_sim, 0, 3000, 500, e, 3, u, 1));
    GOOD(flt_leveler_sim_next_sheet(l, g_sim, 3000, 3000, 500, NULL, 0, NULL, 0));
    GOOD(flt_sim_clear_sheet(g_sim)); /* leave the shared simulator flat */
    flt_leveler_sim_destroy(l);
}

/* ---------------------------------------------------------------------- */
/* genicam.h                                                               */
/* ---------------------------------------------------------------------- */

static const char k_genicam_xml[] =
    "<RegisterDescription VendorName=\"V\" ModelName=\"M\">"
    "<Category Name=\"Root\"><pFeature>Width</pFeature><pFeature>Gain</pFeature></Category>"
    "<Integer Name=\"Width\"><pValue>WidthReg</pValue><Min>16</Min><Max>4096</Max></Integer>"
    "<IntReg Name=\"WidthReg\"><Address>0x100</Address><Length>4</Length>"
    "<AccessMode>RW</AccessMode><pPort>Device</pPort><Endianess>LittleEndian</Endianess>"
    "</IntReg>"
    "<Float Name=\"Gain\"><Value>1.5</Value><Min>0</Min><Max>24</Max></Float>"
    "<Enumeration Name=\"Mode\"><EnumEntry Name=\"Off\"><Value>0</Value></EnumEntry>"
    "<EnumEntry Name=\"On\"><Value>1</Value></EnumEntry><Value>0</Value></Enumeration>"
    "<String Name=\"Label\"><Value>x</Value></String>"
    "<Command Name=\"Start\"><pValue>WidthReg</pValue><CommandValue>32</CommandValue></Command>"
    "<SwissKnife Name=\"Twice\"><pVariable Name=\"W\">Width</pVariable><Formula>W * 2</Formula>"
    "</SwissKnife>"
    "</RegisterDescription>";

/* A description with Width = 640 in its memory image. */
static flt_genicam *new_genicam(void) {
    flt_genicam *g = NULL;
    const uint8_t width[4] = {0x80, 0x02, 0, 0};
    if (flt_genicam_load_memory(k_genicam_xml, sizeof k_genicam_xml - 1, &g) != FLT_OK ||
        flt_genicam_set_memory(g, 0x100, width, 4) != FLT_OK) {
        fprintf(stderr, "fixture: genicam: %s\n", flt_last_error_message());
        exit(2);
    }
    return g;
}

static void row_genicam_load(void) {
    char path[300], garbage[300];
    path_in_dir(path, sizeof path, "camera.xml");
    write_file(path, k_genicam_xml, sizeof k_genicam_xml - 1);
    path_in_dir(garbage, sizeof garbage, "garbage.xml");
    write_file(garbage, "PK\x03\x04garbage", 11);
    flt_genicam *g = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_genicam_load(path, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'path'", flt_genicam_load(NULL, &g));
    BAD(FLT_ERR_IO, "cannot open", flt_genicam_load("/nonexistent/x.xml", &g));
    BAD(FLT_ERR_FORMAT, "ZIP", flt_genicam_load(garbage, &g));
    BAD(FLT_ERR_IO, NULL, flt_genicam_load(g_dir, &g)); /* a folder */
    GOOD(flt_genicam_load(path, &g));
    flt_genicam_destroy(g);
}

static void row_genicam_load_memory(void) {
    flt_genicam *g = NULL;
    const char *x = k_genicam_xml;
    const size_t n = sizeof k_genicam_xml - 1;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_genicam_load_memory(x, n, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'data'", flt_genicam_load_memory(NULL, n, &g));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bytes'", flt_genicam_load_memory(x, 0, &g));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bytes'", flt_genicam_load_memory(x, NEG, &g));
    BAD(FLT_ERR_FORMAT, "malformed", flt_genicam_load_memory(x, n / 2, &g)); /* truncated */
    BAD(FLT_ERR_FORMAT, "no node", flt_genicam_load_memory("<a/>", 4, &g));
    BAD(FLT_ERR_FORMAT, NULL, flt_genicam_load_memory("\x01\x02\x03 \xff<", 6, &g));
    GOOD(flt_genicam_load_memory(x, n, &g));
    flt_genicam_destroy(g);
}

static void row_genicam_destroy(void) {
    flt_genicam_destroy(NULL);
    ++g_checks;
}

static void row_genicam_get_text(void) {
    flt_genicam *g = new_genicam();
    const char *t;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'description'",
        flt_genicam_get_text(NULL, FLT_GENICAM_VENDOR_NAME, &t));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_genicam_get_text(g, FLT_GENICAM_VENDOR_NAME, NULL));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'which' = -1",
                flt_genicam_get_text(g, (flt_genicam_text)-1, &t));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'which' = 4", flt_genicam_get_text(g, (flt_genicam_text)4, &t));
    GOOD(flt_genicam_get_text(g, FLT_GENICAM_MODEL_NAME, &t));
    flt_genicam_destroy(g);
}

static void row_genicam_feature_count(void) {
    flt_genicam *g = new_genicam();
    size_t n;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'description'", flt_genicam_feature_count(NULL, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_genicam_feature_count(g, NULL));
    GOOD(flt_genicam_feature_count(g, &n));
    flt_genicam_destroy(g);
}

static void row_genicam_feature_name(void) {
    flt_genicam *g = new_genicam();
    const char *name;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'description'", flt_genicam_feature_name(NULL, 0, &name));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_genicam_feature_name(g, 0, NULL));
    BAD(FLT_ERR_NOT_FOUND, "'index' = 7", flt_genicam_feature_name(g, 7, &name));
    BAD(FLT_ERR_NOT_FOUND, "'index'", flt_genicam_feature_name(g, NEG, &name));
    GOOD(flt_genicam_feature_name(g, 6, &name));
    flt_genicam_destroy(g);
}

static void row_genicam_feature_info(void) {
    flt_genicam *g = new_genicam();
    flt_genicam_type type;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'description'",
        flt_genicam_feature_info(NULL, "Width", &type, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'feature'",
        flt_genicam_feature_info(g, NULL, &type, NULL, NULL));
    BAD(FLT_ERR_NOT_FOUND, "'Nope'", flt_genicam_feature_info(g, "Nope", &type, NULL, NULL));
    BAD(FLT_ERR_NOT_FOUND, NULL, flt_genicam_feature_info(g, "", &type, NULL, NULL));
    GOOD(flt_genicam_feature_info(g, "Width", NULL, NULL, NULL));
    flt_genicam_destroy(g);
}

static void row_genicam_category_entry(void) {
    flt_genicam *g = new_genicam();
    const char *name;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'description'",
        flt_genicam_category_entry(NULL, "Root", 0, &name));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'category'", flt_genicam_category_entry(g, NULL, 0, &name));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_genicam_category_entry(g, "Root", 0, NULL));
    BAD(FLT_ERR_NOT_FOUND, "'index' = 2", flt_genicam_category_entry(g, "Root", 2, &name));
    BAD(FLT_ERR_NOT_FOUND, "'index'", flt_genicam_category_entry(g, "Root", NEG, &name));
    BAD(FLT_ERR_NOT_FOUND, "'Width' is no category",
        flt_genicam_category_entry(g, "Width", 0, &name));
    BAD(FLT_ERR_NOT_FOUND, "no category", flt_genicam_category_entry(g, "Nope", 0, &name));
    BAD(FLT_ERR_NOT_FOUND, NULL, flt_genicam_category_entry(g, "", 0, &name));
    GOOD(flt_genicam_category_entry(g, "Root", 1, &name));
    flt_genicam_destroy(g);
}

static void row_genicam_set_memory(void) {
    flt_genicam *g = new_genicam();
    const uint8_t b[4] = {1, 2, 3, 4};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'description'", flt_genicam_set_memory(NULL, 0, b, 4));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bytes'", flt_genicam_set_memory(g, 0, NULL, 4));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count' = 0", flt_genicam_set_memory(g, 0, b, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count'", flt_genicam_set_memory(g, 0, b, NEG));
    BAD(FLT_ERR_INVALID_ARGUMENT, "past 2^64", flt_genicam_set_memory(g, UINT64_MAX, b, 4));
    GOOD(flt_genicam_set_memory(g, UINT64_MAX - 3, b, 4));
    flt_genicam_destroy(g);
}

static void row_genicam_get_memory(void) {
    flt_genicam *g = new_genicam();
    uint8_t b[4];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'description'", flt_genicam_get_memory(NULL, 0x100, b, 4));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_genicam_get_memory(g, 0x100, NULL, 4));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count' = 0", flt_genicam_get_memory(g, 0x100, b, 0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "past 2^64", flt_genicam_get_memory(g, UINT64_MAX, b, 4));
    BAD(FLT_ERR_NOT_FOUND, "0x104", flt_genicam_get_memory(g, 0x102, b, 4));
    GOOD(flt_genicam_get_memory(g, 0x100, b, 4));
    flt_genicam_destroy(g);
}

static void row_genicam_clear_memory(void) {
    flt_genicam *g = new_genicam();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'description'", flt_genicam_clear_memory(NULL));
    GOOD(flt_genicam_clear_memory(g));
    flt_genicam_destroy(g);
}

static int FLT_CALL bad_input_read(void *user, uint64_t address, void *out, size_t bytes) {
    (void)user;
    (void)address;
    memset(out, 0, bytes);
    return 0;
}

static void row_genicam_set_registers(void) {
    flt_genicam *g = new_genicam();
    BAD(FLT_ERR_INVALID_ARGUMENT, "'description'",
        flt_genicam_set_registers(NULL, bad_input_read, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'read' is NULL",
        flt_genicam_set_registers(g, NULL, (flt_genicam_write_fn)bad_input_read, NULL));
    GOOD(flt_genicam_set_registers(g, bad_input_read, NULL, NULL));
    int64_t v;
    /* writes without a write callback */
    BAD(FLT_ERR_STATE, "write callback", flt_genicam_set_int(g, "Width", 32));
    GOOD(flt_genicam_get_int(g, "Width", &v));
    GOOD(flt_genicam_set_registers(g, NULL, NULL, NULL));
    flt_genicam_destroy(g);
}

/* The checks every evaluating function shares: handle, feature name. */
#define GENICAM_FEATURE_CHECKS(call_null_handle, call_null_feature, call_unknown) \
  do {                                                                            \
    BAD(FLT_ERR_INVALID_ARGUMENT, "'description'", call_null_handle);             \
    BAD(FLT_ERR_INVALID_ARGUMENT, "'feature'", call_null_feature);                \
    BAD(FLT_ERR_NOT_FOUND, "'Nope'", call_unknown);                               \
  } while (0)

static void row_genicam_get_access(void) {
    flt_genicam *g = new_genicam();
    flt_genicam_access a;
    GENICAM_FEATURE_CHECKS(flt_genicam_get_access(NULL, "Width", &a),
                           flt_genicam_get_access(g, NULL, &a),
                           flt_genicam_get_access(g, "Nope", &a));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_genicam_get_access(g, "Width", NULL));
    GOOD(flt_genicam_get_access(g, "Width", &a));
    flt_genicam_destroy(g);
}

static void row_genicam_get_flags(void) {
    flt_genicam *g = new_genicam();
    int i, a, l;
    GENICAM_FEATURE_CHECKS(flt_genicam_get_flags(NULL, "Width", &i, &a, &l),
                           flt_genicam_get_flags(g, NULL, &i, &a, &l),
                           flt_genicam_get_flags(g, "Nope", &i, &a, &l));
    GOOD(flt_genicam_get_flags(g, "Width", NULL, NULL, NULL));
    flt_genicam_destroy(g);
}

static void row_genicam_register(void) {
    flt_genicam *g = new_genicam();
    uint64_t address;
    GENICAM_FEATURE_CHECKS(flt_genicam_register(NULL, "Width", &address, NULL, NULL, NULL, NULL),
                           flt_genicam_register(g, NULL, &address, NULL, NULL, NULL, NULL),
                           flt_genicam_register(g, "Nope", &address, NULL, NULL, NULL, NULL));
    BAD(FLT_ERR_NOT_FOUND, "no single register",
        flt_genicam_register(g, "Twice", &address, NULL, NULL, NULL, NULL));
    GOOD(flt_genicam_register(g, "Width", &address, NULL, NULL, NULL, NULL));
    flt_genicam_destroy(g);
}

static void row_genicam_get_int(void) {
    flt_genicam *g = new_genicam();
    int64_t v;
    GENICAM_FEATURE_CHECKS(flt_genicam_get_int(NULL, "Width", &v), flt_genicam_get_int(g, NULL, &v),
                           flt_genicam_get_int(g, "Nope", &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_genicam_get_int(g, "Width", NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "no integer value", flt_genicam_get_int(g, "Label", &v));
    BAD(FLT_ERR_NUMERIC, "1.5", flt_genicam_get_int(g, "Gain", &v)); /* not integral */
    GOOD(flt_genicam_get_int(g, "Width", &v));
    flt_genicam_destroy(g);
}

static void row_genicam_get_float(void) {
    flt_genicam *g = new_genicam();
    double v;
    GENICAM_FEATURE_CHECKS(flt_genicam_get_float(NULL, "Gain", &v),
                           flt_genicam_get_float(g, NULL, &v),
                           flt_genicam_get_float(g, "Nope", &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_genicam_get_float(g, "Gain", NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "no number value", flt_genicam_get_float(g, "Start", &v));
    GOOD(flt_genicam_get_float(g, "Twice", &v));
    flt_genicam_destroy(g);
}

static void row_genicam_get_string(void) {
    flt_genicam *g = new_genicam();
    const char *v;
    GENICAM_FEATURE_CHECKS(flt_genicam_get_string(NULL, "Label", &v),
                           flt_genicam_get_string(g, NULL, &v),
                           flt_genicam_get_string(g, "Nope", &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_genicam_get_string(g, "Label", NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "no string value", flt_genicam_get_string(g, "Width", &v));
    GOOD(flt_genicam_get_string(g, "Mode", &v));
    flt_genicam_destroy(g);
}

static void row_genicam_int_bounds(void) {
    flt_genicam *g = new_genicam();
    int64_t lo, hi, inc;
    GENICAM_FEATURE_CHECKS(flt_genicam_int_bounds(NULL, "Width", &lo, &hi, &inc),
                           flt_genicam_int_bounds(g, NULL, &lo, &hi, &inc),
                           flt_genicam_int_bounds(g, "Nope", &lo, &hi, &inc));
    GOOD(flt_genicam_int_bounds(g, "Width", NULL, NULL, NULL));
    flt_genicam_destroy(g);
}

static void row_genicam_float_bounds(void) {
    flt_genicam *g = new_genicam();
    double lo, hi;
    GENICAM_FEATURE_CHECKS(flt_genicam_float_bounds(NULL, "Gain", &lo, &hi),
                           flt_genicam_float_bounds(g, NULL, &lo, &hi),
                           flt_genicam_float_bounds(g, "Nope", &lo, &hi));
    GOOD(flt_genicam_float_bounds(g, "Gain", &lo, NULL));
    flt_genicam_destroy(g);
}

static void row_genicam_enum_count(void) {
    flt_genicam *g = new_genicam();
    size_t n;
    GENICAM_FEATURE_CHECKS(flt_genicam_enum_count(NULL, "Mode", &n),
                           flt_genicam_enum_count(g, NULL, &n),
                           flt_genicam_enum_count(g, "Nope", &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_genicam_enum_count(g, "Mode", NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not an Enumeration", flt_genicam_enum_count(g, "Width", &n));
    GOOD(flt_genicam_enum_count(g, "Mode", &n));
    flt_genicam_destroy(g);
}

static void row_genicam_enum_entry(void) {
    flt_genicam *g = new_genicam();
    const char *name;
    GENICAM_FEATURE_CHECKS(flt_genicam_enum_entry(NULL, "Mode", 0, &name, NULL, NULL),
                           flt_genicam_enum_entry(g, NULL, 0, &name, NULL, NULL),
                           flt_genicam_enum_entry(g, "Nope", 0, &name, NULL, NULL));
    BAD(FLT_ERR_NOT_FOUND, "'index' = 2", flt_genicam_enum_entry(g, "Mode", 2, &name, NULL, NULL));
    BAD(FLT_ERR_NOT_FOUND, "'index'", flt_genicam_enum_entry(g, "Mode", NEG, &name, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not an Enumeration",
        flt_genicam_enum_entry(g, "Width", 0, &name, NULL, NULL));
    GOOD(flt_genicam_enum_entry(g, "Mode", 1, NULL, NULL, NULL));
    flt_genicam_destroy(g);
}

static void row_genicam_set_int(void) {
    flt_genicam *g = new_genicam();
    GENICAM_FEATURE_CHECKS(flt_genicam_set_int(NULL, "Width", 32), flt_genicam_set_int(g, NULL, 32),
                           flt_genicam_set_int(g, "Nope", 32));
    BAD(FLT_ERR_INVALID_ARGUMENT, "outside 16 .. 4096", flt_genicam_set_int(g, "Width", INT64_MIN));
    BAD(FLT_ERR_INVALID_ARGUMENT, "outside", flt_genicam_set_int(g, "Width", INT64_MAX));
    BAD(FLT_ERR_STATE, "read-only", flt_genicam_set_int(g, "Twice", 1));
    BAD(FLT_ERR_INVALID_ARGUMENT, "takes no integer", flt_genicam_set_int(g, "Label", 1));
    GOOD(flt_genicam_set_int(g, "Width", 32));
    flt_genicam_destroy(g);
}

static void row_genicam_set_float(void) {
    flt_genicam *g = new_genicam();
    GENICAM_FEATURE_CHECKS(flt_genicam_set_float(NULL, "Gain", 1.0),
                           flt_genicam_set_float(g, NULL, 1.0),
                           flt_genicam_set_float(g, "Nope", 1.0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'value' = nan", flt_genicam_set_float(g, "Gain", NaN_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'value' = inf", flt_genicam_set_float(g, "Gain", Inf_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "outside", flt_genicam_set_float(g, "Gain", 1e300));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not an integer", flt_genicam_set_float(g, "Width", 32.5));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not an integer", flt_genicam_set_float(g, "Width", -1e300));
    GOOD(flt_genicam_set_float(g, "Gain", 2.0));
    flt_genicam_destroy(g);
}

static void row_genicam_set_string(void) {
    flt_genicam *g = new_genicam();
    GENICAM_FEATURE_CHECKS(flt_genicam_set_string(NULL, "Mode", "On"),
                           flt_genicam_set_string(g, NULL, "On"),
                           flt_genicam_set_string(g, "Nope", "On"));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'value'", flt_genicam_set_string(g, "Mode", NULL));
    BAD(FLT_ERR_NOT_FOUND, "no entry 'Maybe'", flt_genicam_set_string(g, "Mode", "Maybe"));
    BAD(FLT_ERR_INVALID_ARGUMENT, "takes no string", flt_genicam_set_string(g, "Width", "1"));
    GOOD(flt_genicam_set_string(g, "Mode", "On"));
    flt_genicam_destroy(g);
}

static void row_genicam_execute(void) {
    flt_genicam *g = new_genicam();
    GENICAM_FEATURE_CHECKS(flt_genicam_execute(NULL, "Start"), flt_genicam_execute(g, NULL),
                           flt_genicam_execute(g, "Nope"));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a Command", flt_genicam_execute(g, "Width"));
    GOOD(flt_genicam_execute(g, "Start"));
    flt_genicam_destroy(g);
}

/* ---------------------------------------------------------------------- */
/* coil.h, record.h and the record's functions of gauge.h and source.h     */
/* ---------------------------------------------------------------------- */

static flt_coil_info *new_coil(const char *id) {
    flt_coil_info *c = NULL;
    if (flt_coil_info_create(id, &c) || flt_coil_info_set_nominal(c, 4.0, 1500.0) ||
        flt_coil_info_set_extra(c, "line", "CTL 2")) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    return c;
}

/* A sheet of a gauge that was told its coil (and a note) before its rows:
 * the sheet lends the identity, read-only. */
static flt_sheet *new_coil_sheet(flt_gauge *g) {
    flt_coil_info *c = new_coil("C-1");
    if (flt_gauge_set_coil(g, c) || flt_gauge_note(g, "leveler", "roll gap 1 -> 2")) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    flt_coil_info_destroy(c);
    return new_sheet(g);
}

static void row_coil_info_create(void) {
    flt_coil_info *c = (flt_coil_info *)1;
    char long_id[300];
    memset(long_id, 'x', sizeof long_id - 1);
    long_id[sizeof long_id - 1] = 0;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'coil_id'", flt_coil_info_create(NULL, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_coil_info_create("C-1", NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'coil_id' is empty", flt_coil_info_create("", &c));
    ++g_checks;
    if (c != NULL)
        ERR("a failed create left *out = %p", (void *)c);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'coil_id'", flt_coil_info_create(long_id, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'coil_id'", flt_coil_info_create("a\nb", &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'coil_id'", flt_coil_info_create("\xff\xfe", &c));
    GOOD(flt_coil_info_create("C-1 Süd", &c));
    flt_coil_info_destroy(c);
}

static void row_coil_info_destroy(void) {
    uint64_t junk[8] = {0};
    flt_coil_info_destroy(NULL);
    flt_coil_info_destroy((flt_coil_info *)junk); /* not a coil: left alone */
    /* A lent identity (the sheet's) is not freed by it. */
    flt_gauge *g = new_gauge(0);
    flt_sheet *sh = new_coil_sheet(g);
    const flt_coil_info *lent = NULL;
    GOOD(flt_sheet_coil(sh, &lent));
    flt_coil_info_destroy((flt_coil_info *)lent);
    const char *id = NULL;
    GOOD(flt_coil_info_get_text(lent, FLT_COIL_FIELD_ID, &id));
    ++g_checks;
    if (strcmp(id, "C-1") != 0)
        ERR("the sheet's coil reads \"%s\" after a destroy of the lent handle", id);
    flt_sheet_destroy(sh);
    flt_gauge_destroy(g);
    g_checks += 2;
}

static void row_coil_info_copy(void) {
    flt_coil_info *c = new_coil("C-1"), *copy = (flt_coil_info *)1;
    uint64_t junk[8] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'info'", flt_coil_info_copy(NULL, &copy));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a coil",
        flt_coil_info_copy((const flt_coil_info *)junk, &copy));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_coil_info_copy(c, NULL));
    GOOD(flt_coil_info_copy(c, &copy));
    /* A copy of a lent identity can be changed. */
    flt_gauge *g = new_gauge(0);
    flt_sheet *sh = new_coil_sheet(g);
    const flt_coil_info *lent = NULL;
    flt_coil_info *mine = NULL;
    GOOD(flt_sheet_coil(sh, &lent));
    GOOD(flt_coil_info_copy(lent, &mine));
    GOOD(flt_coil_info_set_text(mine, FLT_COIL_FIELD_GRADE, "S355MC"));
    flt_coil_info_destroy(mine);
    flt_sheet_destroy(sh);
    flt_gauge_destroy(g);
    flt_coil_info_destroy(copy);
    flt_coil_info_destroy(c);
}

static void row_coil_info_set_text(void) {
    flt_coil_info *c = new_coil("C-1");
    uint64_t junk[8] = {0};
    char long_text[300];
    memset(long_text, 'y', sizeof long_text - 1);
    long_text[sizeof long_text - 1] = 0;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'info'", flt_coil_info_set_text(NULL, FLT_COIL_FIELD_HEAT, "h"));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a coil",
        flt_coil_info_set_text((flt_coil_info *)junk, FLT_COIL_FIELD_HEAT, "h"));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'field' is 5",
        flt_coil_info_set_text(c, (flt_coil_field)5, "h"));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'field' is -1",
                flt_coil_info_set_text(c, (flt_coil_field)-1, "h"));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'value'", flt_coil_info_set_text(c, FLT_COIL_FIELD_HEAT, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'value'",
        flt_coil_info_set_text(c, FLT_COIL_FIELD_HEAT, long_text));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'value'",
        flt_coil_info_set_text(c, FLT_COIL_FIELD_GRADE, "a\tb"));
    BAD(FLT_ERR_INVALID_ARGUMENT, "empty", flt_coil_info_set_text(c, FLT_COIL_FIELD_ID, ""));
    GOOD(flt_coil_info_set_text(c, FLT_COIL_FIELD_HEAT, "H 88"));
    GOOD(flt_coil_info_set_text(c, FLT_COIL_FIELD_HEAT, "")); /* cleared */
    /* Wrong state: a lent identity is read-only. */
    flt_gauge *g = new_gauge(0);
    flt_sheet *sh = new_coil_sheet(g);
    const flt_coil_info *lent = NULL;
    GOOD(flt_sheet_coil(sh, &lent));
    BAD(FLT_ERR_STATE, "read-only",
        flt_coil_info_set_text((flt_coil_info *)lent, FLT_COIL_FIELD_HEAT, "h"));
    flt_sheet_destroy(sh);
    flt_gauge_destroy(g);
    flt_coil_info_destroy(c);
}

static void row_coil_info_get_text(void) {
    flt_coil_info *c = new_coil("C-1");
    const char *t = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'info'", flt_coil_info_get_text(NULL, FLT_COIL_FIELD_ID, &t));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'field'", flt_coil_info_get_text(c, (flt_coil_field)99, &t));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_coil_info_get_text(c, FLT_COIL_FIELD_ID, NULL));
    GOOD(flt_coil_info_get_text(c, FLT_COIL_FIELD_CUSTOMER, &t));
    ++g_checks;
    if (strcmp(t, "") != 0)
        ERR("an unset field reads \"%s\"", t);
    flt_coil_info_destroy(c);
}

static void row_coil_info_set_nominal(void) {
    flt_coil_info *c = new_coil("C-1");
    BAD(FLT_ERR_INVALID_ARGUMENT, "'info'", flt_coil_info_set_nominal(NULL, 4.0, 1500.0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'thickness_mm'", flt_coil_info_set_nominal(c, NaN_, 1500.0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'thickness_mm'", flt_coil_info_set_nominal(c, -4.0, 1500.0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'thickness_mm'", flt_coil_info_set_nominal(c, 1e9, 1500.0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width_mm'", flt_coil_info_set_nominal(c, 4.0, Inf_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'width_mm'", flt_coil_info_set_nominal(c, 4.0, -0.5));
    GOOD(flt_coil_info_set_nominal(c, 0.0, 0.0)); /* not given */
    GOOD(flt_coil_info_set_nominal(c, 12.5, 2000.0));
    flt_coil_info_destroy(c);
}

static void row_coil_info_get_nominal(void) {
    flt_coil_info *c = new_coil("C-1");
    double t = 0, w = 0;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'info'", flt_coil_info_get_nominal(NULL, &t, &w));
    GOOD(flt_coil_info_get_nominal(c, NULL, NULL));
    GOOD(flt_coil_info_get_nominal(c, &t, &w));
    ++g_checks;
    if (t != 4.0 || w != 1500.0)
        ERR("nominal reads %g x %g, not 4 x 1500", t, w);
    flt_coil_info_destroy(c);
}

static void row_coil_info_set_extra(void) {
    flt_coil_info *c = new_coil("C-1");
    char key[16];
    BAD(FLT_ERR_INVALID_ARGUMENT, "'info'", flt_coil_info_set_extra(NULL, "k", "v"));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'key'", flt_coil_info_set_extra(c, NULL, "v"));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'key'", flt_coil_info_set_extra(c, "", "v"));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'key'", flt_coil_info_set_extra(c, "bad key", "v"));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'value'", flt_coil_info_set_extra(c, "k", "x\x01y"));
    GOOD(flt_coil_info_set_extra(c, "k", NULL)); /* removing a key not there */
    /* Full: FLT_COIL_EXTRA_MAX keys (one is set by new_coil). */
    for (int i = 1; i < FLT_COIL_EXTRA_MAX; ++i) {
        snprintf(key, sizeof key, "k%d", i);
        GOOD(flt_coil_info_set_extra(c, key, "v"));
    }
    BAD(FLT_ERR_BUFFER_FULL, "extras", flt_coil_info_set_extra(c, "one_more", "v"));
    GOOD(flt_coil_info_set_extra(c, "k1", "replaced")); /* replacing still works */
    GOOD(flt_coil_info_set_extra(c, "k1", NULL));
    GOOD(flt_coil_info_set_extra(c, "one_more", "v"));
    flt_coil_info_destroy(c);
}

static void row_coil_info_extra_count(void) {
    flt_coil_info *c = new_coil("C-1");
    size_t n = 0;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'info'", flt_coil_info_extra_count(NULL, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_coil_info_extra_count(c, NULL));
    GOOD(flt_coil_info_extra_count(c, &n));
    ++g_checks;
    if (n != 1)
        ERR("%zu extras, not 1", n);
    flt_coil_info_destroy(c);
}

static void row_coil_info_extra(void) {
    flt_coil_info *c = new_coil("C-1");
    const char *k = NULL, *v = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'info'", flt_coil_info_extra(NULL, 0, &k, &v));
    BAD(FLT_ERR_NOT_FOUND, "'index' is 1", flt_coil_info_extra(c, 1, &k, &v));
    BAD(FLT_ERR_NOT_FOUND, "'index'", flt_coil_info_extra(c, NEG, &k, &v));
    GOOD(flt_coil_info_extra(c, 0, NULL, NULL));
    GOOD(flt_coil_info_extra(c, 0, &k, &v));
    ++g_checks;
    if (strcmp(k, "line") != 0 || strcmp(v, "CTL 2") != 0)
        ERR("extra 0 is %s = %s", k, v);
    flt_coil_info_destroy(c);
}

static void row_coil_info_find_extra(void) {
    flt_coil_info *c = new_coil("C-1");
    const char *v = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'info'", flt_coil_info_find_extra(NULL, "line", &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'key'", flt_coil_info_find_extra(c, NULL, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_coil_info_find_extra(c, "line", NULL));
    BAD(FLT_ERR_NOT_FOUND, "'nope'", flt_coil_info_find_extra(c, "nope", &v));
    GOOD(flt_coil_info_find_extra(c, "line", &v));
    flt_coil_info_destroy(c);
}

/* A recording of 40 simulated rows (a cut after row 20, the coil at the
 * start), written with flt_recorder_push_row. */
static void make_recording(const char *path) {
    flt_recorder *r = NULL;
    flt_coil_info *c = new_coil("R-1");
    make_rows(40);
    tf_remove(path);
    if (flt_recorder_create(path, g_calib, NULL, &r) || flt_recorder_set_coil(r, c)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    for (size_t i = 0; i < 40; ++i)
        if (flt_recorder_push_row(r, g_rows.s[i], FIBERS, g_rows.h + i * FIBERS,
                                  g_rows.k + i * FIBERS, NULL) ||
            (i == 20 && flt_recorder_cut(r, g_rows.s[i]))) {
            fprintf(stderr, "fixture: %s\n", flt_last_error_message());
            exit(2);
        }
    flt_recorder_destroy(r);
    flt_coil_info_destroy(c);
}

static flt_recorder *new_recorder(const char *name) {
    char path[300];
    flt_recorder *r = NULL;
    path_in_dir(path, sizeof path, name);
    tf_remove(path);
    if (flt_recorder_create(path, g_calib, NULL, &r)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    return r;
}

static flt_recording *new_recording(void) {
    char path[300];
    flt_recording *r = NULL;
    path_in_dir(path, sizeof path, "fixture.flrec");
    if (!tf_exists(path))
        make_recording(path);
    if (flt_recording_open(path, &r)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    return r;
}

static void row_recorder_create(void) {
    char path[300], dir_path[300];
    flt_recorder *r = (flt_recorder *)1;
    flt_calib *unfinished = NULL;
    flt_options *o = options_with(FLT_OPT_RECORD_QUANTUM, 0.003); /* not a power of two */
    flt_options *other = options_with(FLT_OPT_MAX_GAP, 10.0);     /* the reconstructor's */
    path_in_dir(path, sizeof path, "create.flrec");
    snprintf(dir_path, sizeof dir_path, "%s/no_such_dir/x.flrec", g_dir);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'path'", flt_recorder_create(NULL, g_calib, NULL, &r));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'calib'", flt_recorder_create(path, NULL, NULL, &r));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_recorder_create(path, g_calib, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'path' is empty", flt_recorder_create("", g_calib, NULL, &r));
    ++g_checks;
    if (r != NULL)
        ERR("a failed create left *out = %p", (void *)r);
    BAD(FLT_ERR_INVALID_ARGUMENT, "record_quantum", flt_recorder_create(path, g_calib, o, &r));
    BAD(FLT_ERR_INVALID_ARGUMENT, "max_gap", flt_recorder_create(path, g_calib, other, &r));
    BAD(FLT_ERR_IO, NULL, flt_recorder_create(dir_path, g_calib, NULL, &r));
    /* Wrong state: an unfinished calibration. */
    GOOD(flt_calib_create(&unfinished));
    BAD(FLT_ERR_STATE, NULL, flt_recorder_create(path, unfinished, NULL, &r));
    GOOD(flt_recorder_create(path, g_calib, NULL, &r));
    flt_recorder *again = NULL;
    BAD(FLT_ERR_IO, "exists", flt_recorder_create(path, g_calib, NULL, &again));
    flt_recorder_destroy(r);
    flt_calib_destroy(unfinished);
    flt_options_destroy(other);
    flt_options_destroy(o);
}

static void row_recorder_destroy(void) {
    uint64_t junk[8] = {0};
    flt_recorder_destroy(NULL);
    flt_recorder_destroy((flt_recorder *)junk); /* not a recorder: left alone */
    flt_recorder_destroy(new_recorder("destroy.flrec"));
    g_checks += 3;
}

static void row_recorder_push_row(void) {
    flt_recorder *r = new_recorder("push.flrec");
    uint64_t junk[8] = {0};
    make_rows(2);
    const double *h = g_rows.h, *k = g_rows.k;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recorder'",
        flt_recorder_push_row(NULL, 0.0, FIBERS, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live",
        flt_recorder_push_row((flt_recorder *)junk, 0.0, FIBERS, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'",
        flt_recorder_push_row(r, NaN_, FIBERS, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'",
        flt_recorder_push_row(r, 1e15, FIBERS, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'height'", flt_recorder_push_row(r, 0.0, FIBERS, NULL, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'slope'", flt_recorder_push_row(r, 0.0, FIBERS, h, NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'",
        flt_recorder_push_row(r, 0.0, FIBERS - 1, h, k, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_recorder_push_row(r, 0.0, NEG, h, k, NULL));
    GOOD(flt_recorder_push_row(r, 0.0, FIBERS, h, k, NULL));
    /* Wrong state: a gauge records through it. */
    flt_gauge *g = new_gauge(0);
    GOOD(flt_gauge_attach_recorder(g, r));
    BAD(FLT_ERR_STATE, "detach", flt_recorder_push_row(r, 1.0, FIBERS, h, k, NULL));
    GOOD(flt_gauge_attach_recorder(g, NULL));
    GOOD(flt_recorder_push_row(r, 1.0, FIBERS, h, k, NULL));
    flt_gauge_destroy(g);
    flt_recorder_destroy(r);
}

static void row_recorder_cut(void) {
    flt_recorder *r = new_recorder("cut.flrec");
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recorder'", flt_recorder_cut(NULL, 1.0));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'", flt_recorder_cut(r, Inf_));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'encoder_mm'", flt_recorder_cut(r, -2e12));
    GOOD(flt_recorder_cut(r, 1.0));
    flt_gauge *g = new_gauge(0);
    GOOD(flt_gauge_attach_recorder(g, r));
    BAD(FLT_ERR_STATE, "detach", flt_recorder_cut(r, 2.0));
    GOOD(flt_gauge_attach_recorder(g, NULL));
    flt_gauge_destroy(g);
    flt_recorder_destroy(r);
}

static void row_recorder_set_coil(void) {
    flt_recorder *r = new_recorder("coil.flrec");
    flt_coil_info *c = new_coil("C-1");
    uint64_t junk[8] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recorder'", flt_recorder_set_coil(NULL, c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'coil'", flt_recorder_set_coil(r, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'coil'", flt_recorder_set_coil(r, (flt_coil_info *)junk));
    GOOD(flt_recorder_set_coil(r, c));
    flt_gauge *g = new_gauge(0);
    GOOD(flt_gauge_attach_recorder(g, r));
    BAD(FLT_ERR_STATE, "detach", flt_recorder_set_coil(r, c));
    GOOD(flt_gauge_attach_recorder(g, NULL));
    flt_gauge_destroy(g);
    flt_coil_info_destroy(c);
    flt_recorder_destroy(r);
}

static void row_recorder_sync(void) {
    flt_recorder *r = new_recorder("sync.flrec");
    make_rows(1);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recorder'", flt_recorder_sync(NULL, 1000));
    GOOD(flt_recorder_push_row(r, 0.0, FIBERS, g_rows.h, g_rows.k, NULL));
    GOOD(flt_recorder_sync(r, 10000));
    uint64_t stored = 0;
    GOOD(flt_recorder_count(r, FLT_RECORDER_COUNT_ROWS_STORED, &stored));
    ++g_checks;
    if (stored != 1)
        ERR("%llu rows stored after a sync, not 1", (unsigned long long)stored);
    flt_recorder_destroy(r);
}

static void row_recorder_save_frames(void) {
    flt_recorder *r = new_recorder("frames.flrec");
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recorder'", flt_recorder_save_frames(NULL));
    GOOD(flt_recorder_save_frames(r)); /* no ring: nothing to do */
    flt_recorder_destroy(r);
}

static void row_recorder_count(void) {
    flt_recorder *r = new_recorder("count.flrec");
    uint64_t v;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recorder'",
        flt_recorder_count(NULL, FLT_RECORDER_COUNT_ROWS, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_recorder_count(r, FLT_RECORDER_COUNT_ROWS, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'counter'", flt_recorder_count(r, (flt_recorder_counter)11, &v));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'counter'",
                flt_recorder_count(r, (flt_recorder_counter)-1, &v));
    GOOD(flt_recorder_count(r, FLT_RECORDER_COUNT_WRITER_NS, &v));
    flt_recorder_destroy(r);
}

static void row_recording_open(void) {
    char path[300], bad[300], not_sqlite[300];
    flt_recording *r = (flt_recording *)1;
    path_in_dir(path, sizeof path, "fixture.flrec");
    if (!tf_exists(path))
        make_recording(path);
    path_in_dir(bad, sizeof bad, "no_such.flrec");
    path_in_dir(not_sqlite, sizeof not_sqlite, "garbage.flrec");
    write_file(not_sqlite, "not a database at all, just text padded out to a page....", 58);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'path'", flt_recording_open(NULL, &r));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_recording_open(path, NULL));
    BAD(FLT_ERR_IO, NULL, flt_recording_open(bad, &r));
    ++g_checks;
    if (r != NULL)
        ERR("a failed open left *out = %p", (void *)r);
    BAD(FLT_ERR_FORMAT, NULL, flt_recording_open(not_sqlite, &r));
    GOOD(flt_recording_open(path, &r));
    flt_recording_destroy(r);
}

static void row_recording_destroy(void) {
    uint64_t junk[8] = {0};
    flt_recording_destroy(NULL);
    flt_recording_destroy((flt_recording *)junk);
    flt_recording_destroy(new_recording());
    g_checks += 3;
}

static void row_recording_info(void) {
    flt_recording *r = new_recording();
    double v = 0;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recording'", flt_recording_info(NULL, FLT_RECORDING_ROWS, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_recording_info(r, FLT_RECORDING_ROWS, NULL));
    BAD(FLT_ERR_NOT_FOUND, "'key'", flt_recording_info(r, (flt_recording_value)14, &v));
    ENUM_UB_BAD(FLT_ERR_NOT_FOUND, "'key'", flt_recording_info(r, (flt_recording_value)-1, &v));
    GOOD(flt_recording_info(r, FLT_RECORDING_ROWS, &v));
    ++g_checks;
    if (v != 40.0)
        ERR("the fixture recording has %g rows, not 40", v);
    flt_recording_destroy(r);
}

static void row_recording_calib(void) {
    flt_recording *r = new_recording();
    flt_calib *c = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recording'", flt_recording_calib(NULL, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_recording_calib(r, NULL));
    GOOD(flt_recording_calib(r, &c));
    flt_calib_destroy(c);
    flt_recording_destroy(r);
}

static void row_recording_options(void) {
    flt_recording *r = new_recording();
    flt_options *o = NULL;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recording'", flt_recording_options(NULL, &o));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_recording_options(r, NULL));
    GOOD(flt_recording_options(r, &o));
    flt_options_destroy(o);
    flt_recording_destroy(r);
}

static void row_recording_verify(void) {
    flt_recording *r = new_recording();
    uint64_t bad = 99;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recording'", flt_recording_verify(NULL, &bad));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'bad_blocks_out'", flt_recording_verify(r, NULL));
    GOOD(flt_recording_verify(r, &bad));
    ++g_checks;
    if (bad != 0)
        ERR("%llu bad blocks in a good recording", (unsigned long long)bad);
    flt_recording_destroy(r);
}

static void row_recording_read_rows(void) {
    flt_recording *r = new_recording();
    static double e[40], t[40], h[40 * FIBERS], k[40 * FIBERS];
    static uint8_t f[40 * FIBERS];
    size_t n = 99;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recording'",
        flt_recording_read_rows(NULL, 0, 40, FIBERS, e, t, h, k, f, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'rows_out'",
        flt_recording_read_rows(r, 0, 40, FIBERS, e, t, h, k, f, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'",
        flt_recording_read_rows(r, 0, 40, FIBERS + 1, e, t, h, k, f, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'count'",
        flt_recording_read_rows(r, 0, overflow_rows(FIBERS), FIBERS, e, t, h, k, f, &n));
    GOOD(flt_recording_read_rows(r, 1000, 40, FIBERS, e, t, h, k, f, &n)); /* past the end */
    ++g_checks;
    if (n != 0)
        ERR("%zu rows read past the end", n);
    GOOD(flt_recording_read_rows(r, 30, 40, FIBERS, NULL, NULL, NULL, NULL, NULL, &n));
    ++g_checks;
    if (n != 10)
        ERR("%zu rows read from row 30 of 40, not 10 (clipped)", n);
    GOOD(flt_recording_read_rows(r, 0, 40, FIBERS, e, t, h, k, f, &n));
    flt_recording_destroy(r);
}

static flt_archive *new_archive(const char *name) {
    char path[300];
    flt_archive *a = NULL;
    path_in_dir(path, sizeof path, name);
    if (flt_archive_open(path, "line 1", NULL, &a)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    return a;
}

static void row_archive_open(void) {
    char path[300], dir_path[300], not_sqlite[300];
    flt_archive *a = (flt_archive *)1;
    flt_options *other = options_with(FLT_OPT_MAX_GAP, 10.0);
    path_in_dir(path, sizeof path, "open.db");
    snprintf(dir_path, sizeof dir_path, "%s/no_such_dir/a.db", g_dir);
    path_in_dir(not_sqlite, sizeof not_sqlite, "garbage.db");
    write_file(not_sqlite, "not a database at all, just text padded out to a page....", 58);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'location'", flt_archive_open(NULL, "", NULL, &a));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'line'", flt_archive_open(path, NULL, NULL, &a));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_archive_open(path, "", NULL, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'location' is empty", flt_archive_open("", "", NULL, &a));
    ++g_checks;
    if (a != NULL)
        ERR("a failed open left *out = %p", (void *)a);
    BAD(FLT_ERR_INVALID_ARGUMENT, "'line'", flt_archive_open(path, "a\nb", NULL, &a));
    BAD(FLT_ERR_INVALID_ARGUMENT, "max_gap", flt_archive_open(path, "", other, &a));
    BAD(FLT_ERR_IO, NULL, flt_archive_open(dir_path, "", NULL, &a));
    BAD(FLT_ERR_FORMAT, "not a database", flt_archive_open(not_sqlite, "", NULL, &a));
    GOOD(flt_archive_open(path, "line 1", NULL, &a));
    flt_archive_destroy(a);
    flt_options_destroy(other);
}

static void row_archive_destroy(void) {
    uint64_t junk[8] = {0};
    flt_archive_destroy(NULL);
    flt_archive_destroy((flt_archive *)junk);
    flt_archive_destroy(new_archive("destroy.db"));
    g_checks += 3;
}

static void row_archive_flush(void) {
    flt_archive *a = new_archive("flush.db");
    BAD(FLT_ERR_INVALID_ARGUMENT, "'archive'", flt_archive_flush(NULL, 100));
    GOOD(flt_archive_flush(a, 0)); /* nothing pending */
    flt_archive_destroy(a);
}

static void row_archive_prune(void) {
    flt_archive *a = new_archive("prune.db");
    uint64_t removed = 99;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'archive'", flt_archive_prune(NULL, &removed));
    GOOD(flt_archive_prune(a, NULL));
    GOOD(flt_archive_prune(a, &removed));
    ++g_checks;
    if (removed != 0)
        ERR("%llu sheets pruned without limits", (unsigned long long)removed);
    flt_archive_destroy(a);
}

static void row_archive_count(void) {
    flt_archive *a = new_archive("count.db");
    uint64_t v;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'archive'",
        flt_archive_count(NULL, FLT_ARCHIVE_COUNT_SHEETS, &v));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_archive_count(a, FLT_ARCHIVE_COUNT_SHEETS, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'counter'", flt_archive_count(a, (flt_archive_counter)9, &v));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'counter'",
                flt_archive_count(a, (flt_archive_counter)-1, &v));
    GOOD(flt_archive_count(a, FLT_ARCHIVE_COUNT_PENDING_BYTES, &v));
    flt_archive_destroy(a);
}

static void row_archive_backend(void) {
    flt_archive *a = new_archive("backend.db");
    int b = 9;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'archive'", flt_archive_backend(NULL, &b));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_archive_backend(a, NULL));
    GOOD(flt_archive_backend(a, &b));
    ++g_checks;
    if (b != 0)
        ERR("an SQLite file reports backend %d", b);
    flt_archive_destroy(a);
}

static void row_archive_add_sheet(void) {
    flt_archive *a = new_archive("add.db");
    flt_gauge *g = new_gauge(1);
    flt_sheet *sh = new_coil_sheet(g);
    uint64_t junk[64] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'archive'", flt_archive_add_sheet(NULL, sh));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sheet'", flt_archive_add_sheet(a, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not an open archive",
        flt_archive_add_sheet((flt_archive *)junk, sh));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live", flt_archive_add_sheet(a, (flt_sheet *)junk));
    GOOD(flt_archive_add_sheet(a, sh));
    GOOD(flt_archive_add_sheet(a, sh)); /* twice: one row (tests/c/test_archive.c) */
    GOOD(flt_archive_flush(a, 10000));
    /* Each add is accounted for: sheets = stored + pending + lost. */
    uint64_t given = 0, stored = 0;
    GOOD(flt_archive_count(a, FLT_ARCHIVE_COUNT_SHEETS, &given));
    GOOD(flt_archive_count(a, FLT_ARCHIVE_COUNT_STORED, &stored));
    ++g_checks;
    if (given != 2 || stored != 2)
        ERR("2 adds: %llu given, %llu stored", (unsigned long long)given,
            (unsigned long long)stored);
    flt_sheet_destroy(sh);
    flt_gauge_destroy(g);
    flt_archive_destroy(a);
}

static void row_gauge_set_coil(void) {
    flt_gauge *g = new_gauge(0);
    flt_coil_info *c = new_coil("C-1");
    uint64_t junk[8] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_set_coil(NULL, c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'coil'", flt_gauge_set_coil(g, (flt_coil_info *)junk));
    GOOD(flt_gauge_set_coil(g, c));
    GOOD(flt_gauge_set_coil(g, NULL)); /* the next strip has none */
    flt_coil_info_destroy(c);
    flt_gauge_destroy(g);
}

static void row_gauge_coil_info(void) {
    flt_gauge *g = new_gauge(0);
    flt_coil_info *c = (flt_coil_info *)1;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_coil_info(NULL, FLT_COIL_CURRENT, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_gauge_coil_info(g, FLT_COIL_CURRENT, NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'which'", flt_gauge_coil_info(g, (flt_coil)2, &c));
    ENUM_UB_BAD(FLT_ERR_INVALID_ARGUMENT, "'which'", flt_gauge_coil_info(g, (flt_coil)-1, &c));
    /* No coil named yet. */
    BAD(FLT_ERR_NOT_FOUND, "identity", flt_gauge_coil_info(g, FLT_COIL_CURRENT, &c));
    ++g_checks;
    if (c != NULL)
        ERR("a failed call left *out = %p", (void *)c);
    /* Judged (statistics are kept with rules): the coil has its identity. */
    flt_rules *rules = new_rules();
    GOOD(flt_gauge_set_rules(g, rules, 4.0, 0.0));
    flt_sheet *sh = new_coil_sheet(g); /* flushed: the coil ended, the last one */
    GOOD(flt_gauge_coil_info(g, FLT_COIL_LAST, &c));
    const char *id = NULL;
    GOOD(flt_coil_info_get_text(c, FLT_COIL_FIELD_ID, &id));
    ++g_checks;
    if (strcmp(id, "C-1") != 0)
        ERR("the last coil is \"%s\", not C-1", id);
    flt_coil_info_destroy(c);
    flt_sheet_destroy(sh);
    flt_rules_destroy(rules);
    flt_gauge_destroy(g);
}

static void row_gauge_note(void) {
    flt_gauge *g = new_gauge(0);
    char long_text[300];
    memset(long_text, 'n', sizeof long_text - 1);
    long_text[sizeof long_text - 1] = 0;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_note(NULL, "leveler", "x"));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'kind'", flt_gauge_note(g, NULL, "x"));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'text'", flt_gauge_note(g, "leveler", NULL));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'kind'", flt_gauge_note(g, "", "x"));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'kind'", flt_gauge_note(g, "two words", "x"));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'text'", flt_gauge_note(g, "leveler", long_text));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'text'", flt_gauge_note(g, "leveler", "a\x7f"));
    /* Full: 256 notes waiting for a frame. */
    for (int i = 0; i < 256; ++i)
        if (flt_gauge_note(g, "operator", "x") != FLT_OK)
            ERR("note %d refused: %s", i, flt_last_error_message());
    BAD(FLT_ERR_BUFFER_FULL, "256", flt_gauge_note(g, "operator", "one more"));
    flt_gauge_destroy(g);
    g = new_gauge(0);
    GOOD(flt_gauge_note(g, "leveler", "roll gap 2.1 mm"));
    flt_gauge_destroy(g);
}

static void row_gauge_attach_recorder(void) {
    flt_gauge *g = new_gauge(0), *other = new_gauge(0);
    flt_recorder *r = new_recorder("attach.flrec");
    uint64_t junk[8] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_attach_recorder(NULL, r));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'recorder'", flt_gauge_attach_recorder(g, (flt_recorder *)junk));
    GOOD(flt_gauge_attach_recorder(g, r));
    /* Wrong state: another gauge records through it already. */
    BAD(FLT_ERR_STATE, NULL, flt_gauge_attach_recorder(other, r));
    /* Wrong state: while acquiring. */
    flt_source *s = new_sim_source();
    GOOD(flt_gauge_attach_source(g, s));
    GOOD(flt_gauge_start(g));
    BAD(FLT_ERR_STATE, NULL, flt_gauge_attach_recorder(g, NULL));
    GOOD(flt_gauge_stop(g));
    GOOD(flt_gauge_attach_source(g, NULL));
    flt_source_destroy(s);
    GOOD(flt_gauge_flush(g));
    GOOD(flt_gauge_attach_recorder(g, NULL));
    GOOD(flt_gauge_attach_recorder(other, r));
    GOOD(flt_gauge_attach_recorder(other, NULL));
    flt_recorder_destroy(r);
    flt_gauge_destroy(other);
    flt_gauge_destroy(g);
}

static void row_gauge_attach_archive(void) {
    flt_gauge *g = new_gauge(0);
    flt_archive *a = new_archive("attach.db");
    uint64_t junk[8] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'gauge'", flt_gauge_attach_archive(NULL, a));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'archive'", flt_gauge_attach_archive(g, (flt_archive *)junk));
    GOOD(flt_gauge_attach_archive(g, a));
    flt_source *s = new_sim_source();
    GOOD(flt_gauge_attach_source(g, s));
    GOOD(flt_gauge_start(g));
    BAD(FLT_ERR_STATE, NULL, flt_gauge_attach_archive(g, NULL));
    GOOD(flt_gauge_stop(g));
    GOOD(flt_gauge_attach_source(g, NULL));
    flt_source_destroy(s);
    GOOD(flt_gauge_flush(g));
    GOOD(flt_gauge_attach_archive(g, NULL));
    flt_archive_destroy(a);
    flt_gauge_destroy(g);
}

static void row_sheet_coil(void) {
    flt_gauge *g = new_gauge(0);
    flt_sheet *plain = new_sheet(g);
    flt_sheet *sh = new_coil_sheet(g);
    const flt_coil_info *c = NULL;
    uint64_t junk[64] = {0};
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sheet'", flt_sheet_coil(NULL, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "not a live", flt_sheet_coil((flt_sheet *)junk, &c));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_sheet_coil(sh, NULL));
    BAD(FLT_ERR_NOT_FOUND, "no identity", flt_sheet_coil(plain, &c));
    GOOD(flt_sheet_coil(sh, &c));
    flt_sheet_destroy(sh);
    flt_sheet_destroy(plain);
    flt_gauge_destroy(g);
}

static void row_sheet_note_count(void) {
    flt_gauge *g = new_gauge(0);
    flt_sheet *sh = new_coil_sheet(g);
    size_t n = 0;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sheet'", flt_sheet_note_count(NULL, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_sheet_note_count(sh, NULL));
    GOOD(flt_sheet_note_count(sh, &n));
    ++g_checks;
    if (n != 1)
        ERR("the sheet carries %zu notes, not 1", n);
    flt_sheet_destroy(sh);
    flt_gauge_destroy(g);
}

static void row_sheet_note(void) {
    flt_gauge *g = new_gauge(0);
    flt_sheet *sh = new_coil_sheet(g);
    const char *kind = NULL, *text = NULL;
    double s = NaN_;
    BAD(FLT_ERR_INVALID_ARGUMENT, "'sheet'", flt_sheet_note(NULL, 0, &kind, &text, &s));
    BAD(FLT_ERR_NOT_FOUND, "'index' is 1", flt_sheet_note(sh, 1, &kind, &text, &s));
    BAD(FLT_ERR_NOT_FOUND, "'index'", flt_sheet_note(sh, NEG, &kind, &text, &s));
    GOOD(flt_sheet_note(sh, 0, NULL, NULL, NULL));
    GOOD(flt_sheet_note(sh, 0, &kind, &text, &s));
    ++g_checks;
    if (strcmp(kind, "leveler") != 0 || !isfinite(s))
        ERR("note 0 is %s at s = %g", kind, s);
    flt_sheet_destroy(sh);
    flt_gauge_destroy(g);
}

static flt_source *new_recording_source(void) {
    char path[300];
    flt_source *s = NULL;
    path_in_dir(path, sizeof path, "fixture.flrec");
    if (!tf_exists(path))
        make_recording(path);
    if (flt_source_open_recording(path, NULL, &s)) {
        fprintf(stderr, "fixture: %s\n", flt_last_error_message());
        exit(2);
    }
    return s;
}

static void row_source_open_recording(void) {
    char path[300], bad[300];
    flt_source *s = (flt_source *)1;
    flt_options *fixed = options_with(FLT_OPT_SOURCE_ENCODER_MODE, 1);
    path_in_dir(path, sizeof path, "fixture.flrec");
    if (!tf_exists(path))
        make_recording(path);
    path_in_dir(bad, sizeof bad, "no_such.flrec");
    BAD(FLT_ERR_INVALID_ARGUMENT, "'path'", flt_source_open_recording(NULL, NULL, &s));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_source_open_recording(path, NULL, NULL));
    BAD(FLT_ERR_IO, NULL, flt_source_open_recording(bad, NULL, &s));
    ++g_checks;
    if (s != NULL)
        ERR("a failed open left *out = %p", (void *)s);
    BAD(FLT_ERR_INVALID_ARGUMENT, "source_encoder_mode",
        flt_source_open_recording(path, fixed, &s));
    GOOD(flt_source_open_recording(path, NULL, &s));
    flt_source_destroy(s);
    flt_options_destroy(fixed);
}

static void row_frame_row(void) {
    flt_source *s = new_recording_source(), *sim = new_sim_source();
    const flt_frame *f = NULL, *sim_frame = NULL;
    double h[FIBERS], k[FIBERS];
    uint8_t fl[FIBERS];
    GOOD(flt_source_start(s));
    GOOD(flt_source_next(s, 0, &f));
    GOOD(flt_source_start(sim));
    GOOD(flt_source_next(sim, 0, &sim_frame));
    g_fn = "flt_frame_row";
    BAD(FLT_ERR_INVALID_ARGUMENT, "'frame'", flt_frame_row(NULL, FIBERS, h, k, fl));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_frame_row(f, FIBERS - 1, h, k, fl));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'fibers'", flt_frame_row(f, NEG, h, k, fl));
    BAD(FLT_ERR_NOT_FOUND, NULL, flt_frame_row(sim_frame, FIBERS, h, k, fl));
    GOOD(flt_frame_row(f, FIBERS, NULL, NULL, NULL));
    GOOD(flt_frame_row(f, FIBERS, h, k, fl));
    flt_source_destroy(sim);
    flt_source_destroy(s);
}

static void row_frame_event_count(void) {
    flt_source *s = new_recording_source();
    const flt_frame *f = NULL;
    size_t n = 99;
    GOOD(flt_source_start(s));
    GOOD(flt_source_next(s, 0, &f));
    g_fn = "flt_frame_event_count";
    BAD(FLT_ERR_INVALID_ARGUMENT, "'frame'", flt_frame_event_count(NULL, &n));
    BAD(FLT_ERR_INVALID_ARGUMENT, "'out'", flt_frame_event_count(f, NULL));
    GOOD(flt_frame_event_count(f, &n));
    ++g_checks;
    if (n != 1)
        ERR("the first recorded frame carries %zu events, not 1 (its coil)", n);
    flt_source_destroy(s);
}

static void row_frame_event(void) {
    flt_source *s = new_recording_source();
    const flt_frame *f = NULL;
    flt_recorded_event kind = FLT_RECORDED_CUT;
    double e = 0;
    uint64_t count = 9;
    const flt_coil_info *coil = NULL;
    GOOD(flt_source_start(s));
    GOOD(flt_source_next(s, 0, &f));
    g_fn = "flt_frame_event";
    BAD(FLT_ERR_INVALID_ARGUMENT, "'frame'", flt_frame_event(NULL, 0, &kind, &e, &count, &coil));
    BAD(FLT_ERR_NOT_FOUND, "'index'", flt_frame_event(f, 1, &kind, &e, &count, &coil));
    BAD(FLT_ERR_NOT_FOUND, "'index'", flt_frame_event(f, NEG, &kind, &e, &count, &coil));
    GOOD(flt_frame_event(f, 0, NULL, NULL, NULL, NULL));
    GOOD(flt_frame_event(f, 0, &kind, &e, &count, &coil));
    ++g_checks;
    if (kind != FLT_RECORDED_COIL || coil == NULL || !isnan(e) || count != 0)
        ERR("event 0 is kind %d, coil %p, e %g, count %llu", (int)kind, (const void *)coil, e,
            (unsigned long long)count);
    flt_source_destroy(s);
}

static void row_frame_event_note(void) {
    flt_source *s = new_recording_source();
    const flt_frame *f = NULL;
    const char *kind = NULL, *text = NULL;
    GOOD(flt_source_start(s));
    GOOD(flt_source_next(s, 0, &f));
    g_fn = "flt_frame_event_note";
    BAD(FLT_ERR_INVALID_ARGUMENT, "'frame'", flt_frame_event_note(NULL, 0, &kind, &text));
    BAD(FLT_ERR_NOT_FOUND, "'index'", flt_frame_event_note(f, 1, &kind, &text));
    BAD(FLT_ERR_NOT_FOUND, "no note", flt_frame_event_note(f, 0, &kind, &text)); /* a coil */
    flt_source_destroy(s);
    /* A recording with a note: the gauge records its own. */
    char path[300];
    path_in_dir(path, sizeof path, "note.flrec");
    tf_remove(path);
    flt_recorder *r = NULL;
    flt_gauge *g = new_gauge(0);
    GOOD(flt_recorder_create(path, g_calib, NULL, &r));
    GOOD(flt_gauge_attach_recorder(g, r));
    GOOD(flt_gauge_note(g, "leveler", "entry gap 3.2"));
    make_waiting_sheet(g, 0.0);
    GOOD(flt_gauge_attach_recorder(g, NULL));
    flt_recorder_destroy(r);
    flt_gauge_destroy(g);
    GOOD(flt_source_open_recording(path, NULL, &s));
    GOOD(flt_source_start(s));
    GOOD(flt_source_next(s, 0, &f));
    g_fn = "flt_frame_event_note";
    size_t n = 0;
    GOOD(flt_frame_event_count(f, &n));
    size_t note = n;
    for (size_t i = 0; i < n && note == n; ++i) {
        flt_recorded_event k = FLT_RECORDED_CUT;
        GOOD(flt_frame_event(f, i, &k, NULL, NULL, NULL));
        if (k == FLT_RECORDED_NOTE)
            note = i;
    }
    ++g_checks;
    if (note == n) {
        ERR("the recorded note is not on the first frame's events");
    } else {
        GOOD(flt_frame_event_note(f, note, NULL, NULL));
        GOOD(flt_frame_event_note(f, note, &kind, &text));
        ++g_checks;
        if (strcmp(kind, "leveler") != 0 || strcmp(text, "entry gap 3.2") != 0)
            ERR("the recorded note reads %s: %s", kind, text);
    }
    flt_source_destroy(s);
}

/* ---------------------------------------------------------------------- */
/* The table                                                               */
/* ---------------------------------------------------------------------- */

typedef struct row {
    const char *function;
    void (*check)(void);
} row;

#define ROW(name) \
  { "flt_" #name, row_##name }
static const row k_rows[] = {
    /* common.h */
    ROW(status_string),
    ROW(last_error_message),
    ROW(last_error_status),
    ROW(set_last_error),
    ROW(version),
    ROW(version_string),
    ROW(options_create),
    ROW(options_destroy),
    ROW(options_set),
    ROW(options_get),
    ROW(option_find),
    ROW(option_info),
    ROW(option_choice_at),
    ROW(option_at),
    /* recon.h */
    ROW(recon_create),
    ROW(recon_create_from_calib),
    ROW(recon_destroy),
    ROW(recon_fibers),
    ROW(recon_get_option),
    ROW(recon_push),
    ROW(recon_push_flagged),
    ROW(recon_pull),
    ROW(recon_ready),
    ROW(recon_pending),
    ROW(recon_peek),
    ROW(recon_end_sheet),
    ROW(recon_reset),
    ROW(recon_boundary),
    ROW(reconstruct),
    ROW(reconstruct_flagged),
    ROW(reconstruct_release),
    /* calib.h */
    ROW(calib_create),
    ROW(calib_destroy),
    ROW(calib_finish),
    ROW(calib_is_finished),
    ROW(calib_set_frame_size),
    ROW(calib_get_frame_size),
    ROW(calib_set_intrinsics),
    ROW(calib_get_intrinsics),
    ROW(calib_estimate_intrinsics),
    ROW(calib_set_homography),
    ROW(calib_get_homography),
    ROW(calib_estimate_homography),
    ROW(calib_set_laser_offset),
    ROW(calib_get_laser_offset),
    ROW(calib_laser_spacing),
    ROW(calib_set_encoder_scale),
    ROW(calib_get_encoder_scale),
    ROW(calib_set_fiber_grid),
    ROW(calib_get_fiber_grid),
    ROW(calib_image_to_plane),
    ROW(calib_plane_to_image),
    ROW(calib_undistort),
    ROW(calib_save),
    ROW(calib_save_text),
    ROW(calib_load),
    ROW(calib_load_text),
    /* extractor.h */
    ROW(extractor_create),
    ROW(extractor_destroy),
    ROW(extractor_fibers),
    ROW(extractor_band),
    ROW(extractor_process),
    ROW(extractor_peaks),
    ROW(extractor_laser_profiles),
    ROW(extractor_fiber_flags),
    ROW(extractor_strip),
    ROW(extractor_saturation),
    /* sim.h */
    ROW(sim_create),
    ROW(sim_destroy),
    ROW(sim_add_defect),
    ROW(sim_clear_sheet),
    ROW(sim_set_height_map),
    ROW(sim_surface),
    ROW(sim_fibers),
    ROW(sim_frame_size),
    ROW(sim_pixel_format),
    ROW(sim_next_rows),
    ROW(sim_next_frame),
    ROW(sim_rewind),
    ROW(sim_strip_edges),
    ROW(sim_fiber_flags),
    ROW(calib_create_reference),
    /* flatness.h */
    ROW(shape_string),
    ROW(flatness_create),
    ROW(flatness_create_from_calib),
    ROW(flatness_destroy),
    ROW(flatness_fibers),
    ROW(flatness_zones),
    ROW(flatness_zone_layout),
    ROW(flatness_evaluate),
    ROW(flatness_push),
    ROW(flatness_evaluate_strip),
    ROW(flatness_push_strip),
    ROW(flatness_strip),
    ROW(flatness_zone_positions),
    ROW(flatness_fiber_positions),
    ROW(flatness_finish),
    ROW(flatness_reset),
    ROW(flatness_window),
    ROW(flatness_fiber_results),
    ROW(flatness_zone_results),
    ROW(flatness_shape),
    /* source.h */
    ROW(source_create_sim),
    ROW(source_create_images),
    ROW(source_create_image_dir),
    ROW(camera_list_create),
    ROW(camera_list_destroy),
    ROW(camera_list_count),
    ROW(camera_list_get),
    ROW(source_open_u3v),
    ROW(camera_list_create_gige),
    ROW(camera_list_address),
    ROW(source_open_gige),
    ROW(source_destroy),
    ROW(source_kind_of),
    ROW(source_start),
    ROW(source_stop),
    ROW(source_next),
    ROW(frame_info),
    ROW(source_set_encoder),
    ROW(source_count),
    ROW(source_stream_error),
    ROW(source_camera_string),
    ROW(source_camera_value),
    ROW(source_get_int),
    ROW(source_set_int),
    ROW(source_get_float),
    ROW(source_set_float),
    ROW(source_set_enum),
    ROW(source_execute),
    ROW(source_map_feature),
    ROW(source_read_memory),
    ROW(source_write_memory),
    /* testing.h (libflatline_testing) */
    ROW(u3v_sim_create),
    ROW(u3v_sim_destroy),
    ROW(u3v_sim_transport),
    ROW(u3v_sim_add_camera),
    ROW(u3v_sim_set_frames),
    ROW(u3v_sim_set),
    ROW(u3v_sim_get),
    ROW(u3v_sim_inject),
    ROW(u3v_sim_peek),
    /* gauge.h */
    ROW(gauge_create),
    ROW(gauge_destroy),
    ROW(gauge_get_option),
    ROW(gauge_push_frame),
    ROW(gauge_push_row),
    ROW(gauge_cut),
    ROW(gauge_flush),
    ROW(gauge_attach_source),
    ROW(gauge_start),
    ROW(gauge_stop),
    ROW(gauge_wait),
    ROW(log_set_callback),
    ROW(gauge_next_sheet),
    ROW(gauge_set_callback),
    ROW(gauge_count),
    ROW(sheet_destroy),
    ROW(sheet_get),
    ROW(sheet_get_array),
    ROW(sheet_height_map),
    ROW(sheet_measured_map),
    ROW(gauge_set_rules),
    ROW(gauge_coil_stats),
    ROW(sheet_verdict),
    /* genicam.h */
    ROW(genicam_load),
    ROW(genicam_load_memory),
    ROW(genicam_destroy),
    ROW(genicam_get_text),
    ROW(genicam_feature_count),
    ROW(genicam_feature_name),
    ROW(genicam_feature_info),
    ROW(genicam_category_entry),
    ROW(genicam_set_memory),
    ROW(genicam_get_memory),
    ROW(genicam_clear_memory),
    ROW(genicam_set_registers),
    ROW(genicam_get_access),
    ROW(genicam_get_flags),
    ROW(genicam_register),
    ROW(genicam_get_int),
    ROW(genicam_get_float),
    ROW(genicam_get_string),
    ROW(genicam_int_bounds),
    ROW(genicam_float_bounds),
    ROW(genicam_enum_count),
    ROW(genicam_enum_entry),
    ROW(genicam_set_int),
    ROW(genicam_set_float),
    ROW(genicam_set_string),
    ROW(genicam_execute),
    /* verdict.h */
    ROW(rules_load),
    ROW(rules_load_text),
    ROW(rules_destroy),
    ROW(rules_count),
    ROW(rules_rule),
    ROW(straightedge_profile),
    ROW(verdict_create),
    ROW(verdict_destroy),
    ROW(verdict_set_measure),
    ROW(verdict_evaluate),
    ROW(verdict_get),
    ROW(verdict_failed),
    /* advisor.h */
    ROW(advisor_create),
    ROW(advisor_load),
    ROW(advisor_load_text),
    ROW(advisor_destroy),
    ROW(advisor_size),
    ROW(advisor_set_actuator),
    ROW(advisor_actuator),
    ROW(advisor_set_influence),
    ROW(advisor_influence),
    ROW(advisor_set_target),
    ROW(advisor_identify),
    ROW(advisor_fit),
    ROW(advisor_advise),
    /* coil.h */
    ROW(coil_info_create),
    ROW(coil_info_destroy),
    ROW(coil_info_copy),
    ROW(coil_info_set_text),
    ROW(coil_info_get_text),
    ROW(coil_info_set_nominal),
    ROW(coil_info_get_nominal),
    ROW(coil_info_set_extra),
    ROW(coil_info_extra_count),
    ROW(coil_info_extra),
    ROW(coil_info_find_extra),
    /* record.h */
    ROW(recorder_create),
    ROW(recorder_destroy),
    ROW(recorder_push_row),
    ROW(recorder_cut),
    ROW(recorder_set_coil),
    ROW(recorder_sync),
    ROW(recorder_save_frames),
    ROW(recorder_count),
    ROW(recording_open),
    ROW(recording_destroy),
    ROW(recording_info),
    ROW(recording_calib),
    ROW(recording_options),
    ROW(recording_verify),
    ROW(recording_read_rows),
    ROW(archive_open),
    ROW(archive_destroy),
    ROW(archive_flush),
    ROW(archive_prune),
    ROW(archive_count),
    ROW(archive_backend),
    /* the record's functions of gauge.h and source.h */
    ROW(archive_add_sheet),
    ROW(gauge_set_coil),
    ROW(gauge_coil_info),
    ROW(gauge_note),
    ROW(gauge_attach_recorder),
    ROW(gauge_attach_archive),
    ROW(sheet_coil),
    ROW(sheet_note_count),
    ROW(sheet_note),
    ROW(source_open_recording),
    ROW(frame_row),
    ROW(frame_event_count),
    ROW(frame_event),
    ROW(frame_event_note),
    /* testing.h (libflatline_testing): the hidden leveler */
    ROW(leveler_sim_create),
    ROW(leveler_sim_destroy),
    ROW(leveler_sim_set_settings),
    ROW(leveler_sim_set_incoming),
    ROW(leveler_sim_next_sheet),
};
#define N_ROWS (sizeof k_rows / sizeof k_rows[0])

/* ---------------------------------------------------------------------- */
/* The exported functions, from the library's ELF dynamic symbol table     */
/* (Linux) or PE export table (Windows)                                    */
/* ---------------------------------------------------------------------- */

#ifdef _WIN32
/* The names in the export directory of the module holding `symbol`, whose
 * address lies in an executable section (functions, not data), appended to
 * names[*count]; forwarders (an address inside the export directory) are
 * skipped. NULL on failure. */
static char **exported_functions(void *symbol, char **names, size_t *count) {
    HMODULE module = NULL;
    if (!GetModuleHandleExA(GET_MODULE_HANDLE_EX_FLAG_FROM_ADDRESS |
                                GET_MODULE_HANDLE_EX_FLAG_UNCHANGED_REFCOUNT,
                            (LPCSTR)symbol, &module))
        return NULL;
    const unsigned char *base = (const unsigned char *)module;
    const IMAGE_DOS_HEADER *dos = (const IMAGE_DOS_HEADER *)base;
    const IMAGE_NT_HEADERS64 *nt = (const IMAGE_NT_HEADERS64 *)(base + dos->e_lfanew);
    if (dos->e_magic != IMAGE_DOS_SIGNATURE || nt->Signature != IMAGE_NT_SIGNATURE ||
        nt->OptionalHeader.Magic != IMAGE_NT_OPTIONAL_HDR64_MAGIC)
        return NULL;
    const IMAGE_DATA_DIRECTORY dir = nt->OptionalHeader.DataDirectory[IMAGE_DIRECTORY_ENTRY_EXPORT];
    if (dir.VirtualAddress == 0)
        return NULL;
    const IMAGE_EXPORT_DIRECTORY *exports =
        (const IMAGE_EXPORT_DIRECTORY *)(base + dir.VirtualAddress);
    const DWORD *name_rvas = (const DWORD *)(base + exports->AddressOfNames);
    const WORD *ordinals = (const WORD *)(base + exports->AddressOfNameOrdinals);
    const DWORD *functions = (const DWORD *)(base + exports->AddressOfFunctions);
    const IMAGE_SECTION_HEADER *sections = IMAGE_FIRST_SECTION(nt);
    names = realloc(names, sizeof(char *) * (*count + exports->NumberOfNames + 1));
    for (DWORD i = 0; i < exports->NumberOfNames; ++i) {
        const DWORD rva = functions[ordinals[i]];
        if (rva >= dir.VirtualAddress && rva < dir.VirtualAddress + dir.Size)
            continue; /* a forwarder */
        int code = 0;
        for (WORD k = 0; k < nt->FileHeader.NumberOfSections; ++k)
            if (rva >= sections[k].VirtualAddress &&
                rva < sections[k].VirtualAddress + sections[k].Misc.VirtualSize)
                code = (sections[k].Characteristics & IMAGE_SCN_MEM_EXECUTE) != 0;
        if (code)
            names[(*count)++] = strdup((const char *)(base + name_rvas[i]));
    }
    return names;
}
#else
/* The functions exported by the loaded library that holds `symbol`,
 * appended to names[*count] (NULL on failure). */
static char **exported_functions(void *symbol, char **names, size_t *count) {
    Dl_info info;
    if (!dladdr(symbol, &info) || !info.dli_fname)
        return NULL;
    FILE *f = fopen(info.dli_fname, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *elf = malloc((size_t)n);
    if (fread(elf, 1, (size_t)n, f) != (size_t)n) {
        fclose(f);
        free(elf);
        return NULL;
    }
    fclose(f);
    const Elf64_Ehdr *eh = (const Elf64_Ehdr *)elf;
    if (memcmp(eh->e_ident, ELFMAG, SELFMAG) != 0 || eh->e_ident[EI_CLASS] != ELFCLASS64) {
        free(elf);
        return NULL;
    }
    const Elf64_Shdr *sh = (const Elf64_Shdr *)(elf + eh->e_shoff);
    size_t cap = *count;
    for (int i = 0; i < eh->e_shnum; ++i) {
        if (sh[i].sh_type != SHT_DYNSYM)
            continue;
        const Elf64_Sym *sym = (const Elf64_Sym *)(elf + sh[i].sh_offset);
        const char *str = (const char *)(elf + sh[sh[i].sh_link].sh_offset);
        size_t nsym = sh[i].sh_size / sizeof(Elf64_Sym);
        for (size_t k = 0; k < nsym; ++k) {
            int type = ELF64_ST_TYPE(sym[k].st_info), bind = ELF64_ST_BIND(sym[k].st_info);
            if (sym[k].st_shndx == SHN_UNDEF)
                continue;
            if (bind != STB_GLOBAL && bind != STB_WEAK)
                continue;
            if (type != STT_FUNC && type != STT_GNU_IFUNC)
                continue;
            if (*count >= cap)
                names = realloc(names, sizeof(char *) * (cap = *count ? 2 * *count : 256));
            names[(*count)++] = strdup(str + sym[k].st_name);
        }
    }
    free(elf);
    return names;
}
#endif

int main(void) {
    size_t n_exported = 0;
    setvbuf(stdout, NULL, _IONBF, 0);
    /* libflatline, then libflatline_testing (flatline/testing.h): both
     * check their arguments the same way. */
    char **exported = exported_functions((void *)flt_version, NULL, &n_exported);
    const size_t n_production = n_exported;
    if (exported)
        exported = exported_functions((void *)flt_u3v_sim_create, exported, &n_exported);
    g_fn = "completeness";
    if (!exported || n_production == 0 || n_exported == n_production) {
        ERR("cannot read the exported functions of the loaded libflatline and "
            "libflatline_testing");
        return 1;
    }
    /* The test doubles stay out of the production library. */
    for (size_t i = 0; i < n_production; ++i) {
        ++g_checks;
        if (strncmp(exported[i], "flt_u3v_sim_", 12) == 0 ||
            strncmp(exported[i], "flt_leveler_sim_", 16) == 0)
            ERR("libflatline exports the test double %s (it belongs to libflatline_testing)",
                exported[i]);
    }
    /* Every exported function has a row; every row is exported. */
    for (size_t i = 0; i < n_exported; ++i) {
        int found = 0;
        for (size_t r = 0; r < N_ROWS && !found; ++r)
            found = strcmp(exported[i], k_rows[r].function) == 0;
        ++g_checks;
        if (!found)
            ERR("exported function %s has no row in the bad-input matrix "
                "(tests/c/test_bad_input.c): add one",
                exported[i]);
    }
    for (size_t r = 0; r < N_ROWS; ++r) {
        int found = 0;
        for (size_t i = 0; i < n_exported && !found; ++i)
            found = strcmp(exported[i], k_rows[r].function) == 0;
        ++g_checks;
        if (!found)
            ERR("row %s names a function the library does not export", k_rows[r].function);
    }

    setup();
    /* Homographies of the fixture calibration for the unfinished models. */
    if (flt_calib_get_homography(g_calib, 0, H0, FLT_CALIB_HOMOGRAPHY_ENTRIES) ||
        flt_calib_get_homography(g_calib, 1, H1, FLT_CALIB_HOMOGRAPHY_ENTRIES))
        return 2;
    make_flat_sheet();
    for (size_t r = 0; r < N_ROWS; ++r) {
        g_fn = k_rows[r].function;
        int before = g_failures;
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        k_rows[r].check();
        clock_gettime(CLOCK_MONOTONIC, &t1);
        printf("%-34s %-6s %7.1f ms\n", k_rows[r].function, g_failures == before ? "ok" : "FAILED",
               (t1.tv_sec - t0.tv_sec) * 1e3 + (t1.tv_nsec - t0.tv_nsec) * 1e-6);
    }
    teardown();
    for (size_t i = 0; i < n_exported; ++i)
        free(exported[i]);
    free(exported);
    printf("bad-input matrix: %zu exported functions (%zu libflatline, %zu "
           "libflatline_testing), %zu rows, %d checks, %d failures, %d known bugs (reported)\n",
           n_exported, n_production, n_exported - n_production, (size_t)N_ROWS, g_checks,
           g_failures, g_known);
    return g_failures ? 1 : 0;
}
