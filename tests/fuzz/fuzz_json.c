// SPDX-License-Identifier: Apache-2.0
/* libFuzzer harness: the library's JSON data files, all read by the one
 * strict reader of lib/core (core/json.cpp): rule files
 * (flt_rules_load_text, lib/verdict), leveler files
 * (flt_advisor_load_text, lib/advisor) and calibration files
 * (flt_calib_load_text, lib/calibration). The first byte picks the reader;
 * the rest is the file. Any input must give FLT_OK or FLT_ERR_FORMAT with
 * a message and no object; what is accepted must be usable: every rule
 * read back, the advisor's sizes within the header's
 * bounds, the calibration saved and loaded again to the same text. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "flatline/flatline.h"

#define CHECK(cond) \
  do {              \
    if (!(cond))    \
      abort();      \
  } while (0)

static void refused(flt_status st, const void *object) {
    CHECK(st == FLT_ERR_FORMAT && object == NULL && flt_last_error_message()[0] != 0);
}

static void rules(const char *text, size_t n) {
    flt_rules *r = NULL;
    const flt_status st = flt_rules_load_text(text, n, &r);
    if (st != FLT_OK) {
        refused(st, r);
        return;
    }
    size_t count = 0;
    CHECK(flt_rules_count(r, &count) == FLT_OK && count >= 1);
    for (size_t i = 0; i < count; ++i) {
        const char *name = NULL;
        flt_measure measure;
        double length = -1;
        CHECK(flt_rules_rule(r, i, &name, &measure, &length) == FLT_OK);
        CHECK(name != NULL && length >= 0);
    }
    flt_rules_destroy(r);
}

static void leveler(const char *text, size_t n) {
    flt_advisor *a = NULL;
    const flt_status st = flt_advisor_load_text(text, n, NULL, &a);
    if (st != FLT_OK) {
        refused(st, a);
        return;
    }
    size_t zones = 0, actuators = 0;
    CHECK(flt_advisor_size(a, &zones, &actuators) == FLT_OK);
    CHECK(zones >= 1 && zones <= FLT_ADVISOR_MAX_ZONES);
    CHECK(actuators >= 1 && actuators <= FLT_ADVISOR_MAX_ACTUATORS);
    flt_advisor_destroy(a);
}

static void calibration(const char *text, size_t n) {
    flt_calib *c = NULL;
    const flt_status st = flt_calib_load_text(text, n, &c);
    if (st != FLT_OK) {
        refused(st, c);
        return;
    }
    size_t length = 0;
    CHECK(flt_calib_save_text(c, NULL, 0, &length) == FLT_ERR_BUFFER_FULL);
    char *a = malloc(length + 1), *b = malloc(length + 1);
    CHECK(a && b);
    size_t m = 0;
    CHECK(flt_calib_save_text(c, a, length + 1, &m) == FLT_OK && m == length);
    flt_calib *again = NULL;
    CHECK(flt_calib_load_text(a, length, &again) == FLT_OK);
    CHECK(flt_calib_save_text(again, b, length + 1, &m) == FLT_OK && m == length);
    CHECK(memcmp(a, b, length) == 0);
    flt_calib_destroy(again);
    flt_calib_destroy(c);
    free(a);
    free(b);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 1)
        return 0;
    const char *text = (const char *)data + 1;
    const size_t n = size - 1;
    switch (data[0] % 3) {
        case 0:
            rules(text, n);
            break;
        case 1:
            leveler(text, n);
            break;
        default:
            calibration(text, n);
            break;
    }
    return 0;
}
