// SPDX-License-Identifier: Apache-2.0
/*
 * The GenICam engine on real camera descriptions: 14 files of 10 vendors
 * (USB3 Vision, GigE Vision and CoaXPress cameras) and aravis's own test
 * descriptions, read from the folder FLT_EXTERNAL_DATA names (skipped with
 * a message when it is absent; the files are not part of the repository).
 *
 * 1. Every file loads (text before the declaration, byte-order marks).
 * 2. Coverage: the features an acquisition needs, per file - resolved
 *    (value, and register where there is one, evaluated), refused (with
 *    the engine's message) or absent. Every feature a file defines must
 *    resolve. The table is printed.
 * 3. Cross-check: every feature of every file is evaluated against six
 *    register images (tests/genicam/register_image.h) by the library and by
 *    aravis's GenICam evaluator (tests/genicam/aravis_eval.c, a separate
 *    test program linking libaravis), and the facts are compared: register
 *    addresses and lengths, integer, float, enumeration, boolean and string
 *    values, the bytes a command writes, pIsImplemented and pIsAvailable.
 *    A fact both give must be equal: zero wrong resolutions. Floats agree
 *    to 1e-12 relative (both evaluate the same IEEE operations; the margin
 *    allows formulas evaluated in another but equivalent order). Where
 *    aravis is known not to evaluate a fact (aravis_eval.c says which and
 *    why) the fact is counted, not compared. Where one side gives a value
 *    and the other refuses, the count is printed: the library refuses what
 *    is not defined for those registers (division by zero, a shift by
 *    billions of bits, a boolean that is neither its on nor its off value)
 *    where aravis returns a number.
 */
#define _GNU_SOURCE /* popen, getline */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "external_data.h"
#include "flatline/genicam.h"
#include "register_image.h"

static const char *const k_files[] = {
    "genicam/adgenicam_xml/AVT_Mako_G125B.xml",
    "genicam/adgenicam_xml/Adimec_Q12A180CXP_1_1_5.xml",
    "genicam/adgenicam_xml/Allied_Vision_1800_U-811m.xml",
    "genicam/adgenicam_xml/Basler-acA1300-60gm.xml",
    "genicam/adgenicam_xml/Basler_piA640_210gm.xml",
    "genicam/adgenicam_xml/FLIR-BFS-U3-161S7M.xml",
    "genicam/adgenicam_xml/FLIR_FL3_U3_13S2C.xml",
    "genicam/adgenicam_xml/FLIR_SC6700.xml",
    "genicam/adgenicam_xml/Mikrotron_CXP_MC206xS11.xml",
    "genicam/adgenicam_xml/Orca_Fire_C16240-20UP.xml",
    "genicam/adgenicam_xml/PGR_BFS_U3_51S5M.xml",
    "genicam/adgenicam_xml/PGR_GS3_U3_23S6M.xml",
    "genicam/adgenicam_xml/Teledyne_ShadoBox.xml",
    "genicam/adgenicam_xml/ViewWorks_VNP604.xml",
    "genicam/aravis/src_arv-fake-camera.xml",
    "genicam/aravis/src_arv-gev-bootstrap.xml",
    "genicam/aravis/tests_data_genicam.xml",
};
enum { FILES = sizeof k_files / sizeof k_files[0] };

/* The features an acquisition needs. Exposure and gain have an older SFNC
 * name each, used where the file lacks the newer one. */
static const char *const k_features[][2] = {
    {"Width", NULL},           {"Height", NULL},
    {"OffsetX", NULL},         {"OffsetY", NULL},
    {"PixelFormat", NULL},     {"PayloadSize", NULL},
    {"AcquisitionMode", NULL}, {"AcquisitionStart", NULL},
    {"AcquisitionStop", NULL}, {"ExposureTime", "ExposureTimeAbs"},
    {"Gain", "GainRaw"},       {"TriggerSelector", NULL},
    {"TriggerMode", NULL},     {"TriggerSource", NULL},
    {"TLParamsLocked", NULL},  {"DeviceVendorName", NULL},
    {"DeviceModelName", NULL},
};
static const char *const k_columns[] = {"Wid",  "Hei",  "OfX",  "OfY", "PxF",  "Pay",
                                        "AcM",  "AcSt", "AcSp", "Exp", "Gain", "TSel",
                                        "TMod", "TSrc", "TLP",  "Vnd", "Mdl"};
enum { FEATURES = sizeof k_features / sizeof k_features[0] };

/* ---------------------------------------------------------------------- */
/* Facts: "NAME\tWHAT" -> status ("ok"/"err") and value                    */
/* ---------------------------------------------------------------------- */

typedef struct fact {
    char *key, *status, *value;
} fact;
typedef struct facts {
    fact *v;
    size_t n, cap;
} facts;

static char *dup_n(const char *s, size_t n) {
    char *d = malloc(n + 1);
    assert_non_null(d);
    memcpy(d, s, n);
    d[n] = 0;
    return d;
}
static void add_fact(facts *f, const char *name, const char *what, const char *status,
                     const char *value) {
    if (f->n == f->cap) {
        f->cap = f->cap ? 2 * f->cap : 4096;
        f->v = realloc(f->v, f->cap * sizeof *f->v);
        assert_non_null(f->v);
    }
    char key[512];
    snprintf(key, sizeof key, "%s\t%s", name, what);
    f->v[f->n].key = dup_n(key, strlen(key));
    f->v[f->n].status = dup_n(status, strlen(status));
    f->v[f->n].value = dup_n(value, strlen(value));
    ++f->n;
}
static int by_key(const void *a, const void *b) {
    return strcmp(((const fact *)a)->key, ((const fact *)b)->key);
}
static void sort_facts(facts *f) {
    qsort(f->v, f->n, sizeof *f->v, by_key);
}
static const fact *find_fact(const facts *f, const char *name, const char *what) {
    char key[512];
    snprintf(key, sizeof key, "%s\t%s", name, what);
    fact probe = {key, NULL, NULL};
    return f->n ? bsearch(&probe, f->v, f->n, sizeof *f->v, by_key) : NULL;
}
static void free_facts(facts *f) {
    for (size_t i = 0; i < f->n; ++i) {
        free(f->v[i].key);
        free(f->v[i].status);
        free(f->v[i].value);
    }
    free(f->v);
    memset(f, 0, sizeof *f);
}

/* ---------------------------------------------------------------------- */
/* The library's side: the registers of one image, writes kept aside        */
/* ---------------------------------------------------------------------- */

typedef struct registers {
    unsigned image;
    uint64_t written_at[256];
    uint8_t written[256];
    size_t writes;
    char log[4096];
} registers;

static int FLT_CALL read_image(void *user, uint64_t address, void *out, size_t bytes) {
    registers *r = user;
    uint8_t *o = out;
    for (size_t i = 0; i < bytes; ++i) {
        o[i] = flt_image_byte(r->image, address + i);
        for (size_t w = 0; w < r->writes; ++w)
            if (r->written_at[w] == address + i)
                o[i] = r->written[w];
    }
    return 0;
}
static int FLT_CALL write_image(void *user, uint64_t address, const void *in, size_t bytes) {
    registers *r = user;
    const uint8_t *b = in;
    size_t n = strlen(r->log);
    n += (size_t)snprintf(r->log + n, sizeof r->log - n, "%s%llx=", n ? ";" : "",
                          (unsigned long long)address);
    for (size_t i = 0; i < bytes; ++i) {
        if (r->writes < 256) {
            r->written_at[r->writes] = address + i;
            r->written[r->writes++] = b[i];
        }
        n += (size_t)snprintf(r->log + n, sizeof r->log - n, "%02x", b[i]);
    }
    return 0;
}

static void add_error(facts *f, const char *name, const char *what) {
    add_fact(f, name, what, "err", flt_last_error_message());
}

static int is_register_kind(const char *kind) {
    return !strcmp(kind, "IntReg") || !strcmp(kind, "MaskedIntReg") ||
           !strcmp(kind, "StructEntry") || !strcmp(kind, "FloatReg") ||
           !strcmp(kind, "StringReg") || !strcmp(kind, "Register");
}

/* The library's facts about every feature of `g` for one image. */
static void evaluate_all(flt_genicam *g, registers *r, facts *out) {
    size_t count = 0;
    assert_int_equal(flt_genicam_feature_count(g, &count), FLT_OK);
    char text[256];
    for (size_t i = 0; i < count; ++i) {
        const char *name = NULL, *kind = NULL;
        flt_genicam_type type;
        assert_int_equal(flt_genicam_feature_name(g, i, &name), FLT_OK);
        assert_int_equal(flt_genicam_feature_info(g, name, &type, &kind, NULL), FLT_OK);
        if (is_register_kind(kind)) {
            uint64_t address = 0;
            uint32_t length = 0;
            if (flt_genicam_register(g, name, &address, &length, NULL, NULL, NULL) == FLT_OK) {
                snprintf(text, sizeof text, "%llx\t%u", (unsigned long long)address, length);
                add_fact(out, name, "addr", "ok", text);
            } else {
                add_error(out, name, "addr");
            }
        }
        int64_t iv = 0;
        double dv = 0;
        const char *sv = NULL;
        switch (type) {
            case FLT_GENICAM_ENUMERATION:
            case FLT_GENICAM_INTEGER:
            case FLT_GENICAM_BOOLEAN:
                if (flt_genicam_get_int(g, name, &iv) == FLT_OK) {
                    snprintf(text, sizeof text, "%lld", (long long)iv);
                    add_fact(out, name, type == FLT_GENICAM_BOOLEAN ? "bool" : "int", "ok", text);
                } else {
                    add_error(out, name, type == FLT_GENICAM_BOOLEAN ? "bool" : "int");
                }
                if (type == FLT_GENICAM_ENUMERATION) {
                    if (flt_genicam_get_string(g, name, &sv) == FLT_OK)
                        add_fact(out, name, "enum", "ok", sv);
                    else
                        add_error(out, name, "enum");
                }
                break;
            case FLT_GENICAM_FLOAT:
                if (flt_genicam_get_float(g, name, &dv) == FLT_OK) {
                    snprintf(text, sizeof text, "%.17g", dv);
                    add_fact(out, name, "float", "ok", text);
                } else {
                    add_error(out, name, "float");
                }
                break;
            case FLT_GENICAM_STRING:
                if (flt_genicam_get_string(g, name, &sv) == FLT_OK) {
                    const size_t len = strlen(sv);
                    char *hex = malloc(2 * len + 1);
                    assert_non_null(hex);
                    for (size_t k = 0; k < len; ++k)
                        snprintf(hex + 2 * k, 3, "%02x", (unsigned char)sv[k]);
                    hex[2 * len] = 0;
                    add_fact(out, name, "string", "ok", hex);
                    free(hex);
                } else {
                    add_error(out, name, "string");
                }
                break;
            case FLT_GENICAM_COMMAND:
                r->log[0] = 0;
                r->writes = 0;
                if (flt_genicam_execute(g, name) == FLT_OK)
                    add_fact(out, name, "exec", "ok", r->log);
                else
                    add_error(out, name, "exec"); /* also: the access mode forbids it */
                r->writes = 0;                    /* back to the image, as aravis_eval does */
                break;
            default:
                break;
        }
        int implemented = 0, available = 0;
        if (flt_genicam_get_flags(g, name, &implemented, &available, NULL) == FLT_OK) {
            add_fact(out, name, "imp", "ok", implemented ? "1" : "0");
            add_fact(out, name, "avl", "ok", available ? "1" : "0");
        } else {
            add_error(out, name, "imp");
            add_error(out, name, "avl");
        }
    }
}

/* ---------------------------------------------------------------------- */
/* aravis's side                                                            */
/* ---------------------------------------------------------------------- */

#ifdef FLT_ARAVIS_EVAL
static int aravis_facts(const char *path, unsigned image, facts *out) {
    char command[1200];
    snprintf(command, sizeof command, "'%s' '%s' %u", FLT_ARAVIS_EVAL, path, image);
    FILE *p = popen(command, "r");
    if (!p)
        return 0;
    char *line = NULL;
    size_t cap = 0;
    ssize_t len;
    while ((len = getline(&line, &cap, p)) > 0) {
        while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r'))
            line[--len] = 0;
        char *tab1 = strchr(line, '\t');
        char *tab2 = tab1 ? strchr(tab1 + 1, '\t') : NULL;
        if (!tab1 || !tab2)
            continue;
        *tab1 = *tab2 = 0;
        if (!strcmp(tab1 + 1, "limit")) {
            char what[64];
            snprintf(what, sizeof what, "limit-%s", tab2 + 1);
            add_fact(out, line, what, "ok", "");
            continue;
        }
        char *tab3 = strchr(tab2 + 1, '\t');
        if (tab3)
            *tab3 = 0;
        add_fact(out, line, tab1 + 1, tab2 + 1, tab3 ? tab3 + 1 : "");
    }
    free(line);
    return pclose(p) == 0;
}
#endif

/* ---------------------------------------------------------------------- */
/* The test                                                                */
/* ---------------------------------------------------------------------- */

typedef struct tally {
    long compared, agree, wrong, we_refuse, aravis_refuses, both_refuse, both_no_entry, limited,
        only_ours, only_aravis;
} tally;

static int same_value(const char *what, const char *a, const char *b) {
    if (!strcmp(a, b))
        return 1;
    if (!strcmp(what, "float")) {
        const double x = strtod(a, NULL), y = strtod(b, NULL);
        return x == y || fabs(x - y) <= 1e-12 * fmax(fabs(x), fabs(y)) || (isnan(x) && isnan(y));
    }
    return 0;
}

static int limited_for(const facts *a, const char *name, const char *what) {
    const int flags = !strcmp(what, "imp") || !strcmp(what, "avl");
    if (flags)
        return find_fact(a, name, "limit-flags") || find_fact(a, name, "limit-struct") ||
               find_fact(a, name, "limit-swallowed-flags");
    return find_fact(a, name, "limit-value") || find_fact(a, name, "limit-swallowed-value");
}

static void compare(const char *file, unsigned image, const facts *ours, const facts *theirs,
                    tally *t) {
    for (size_t i = 0; i < ours->n; ++i) {
        const fact *o = &ours->v[i];
        char name[256];
        const char *tab = strchr(o->key, '\t');
        snprintf(name, sizeof name, "%.*s", (int)(tab - o->key), o->key);
        const char *what = tab + 1;
        const fact *a = find_fact(theirs, name, what);
        if (!a) {
            ++t->only_ours;
            continue;
        }
        if (limited_for(theirs, name, what)) {
            ++t->limited;
            continue;
        }
        ++t->compared;
        const int a_ok = !strcmp(a->status, "ok"), o_ok = !strcmp(o->status, "ok");
        if (a_ok && o_ok) {
            if (same_value(what, a->value, o->value)) {
                ++t->agree;
            } else {
                ++t->wrong;
                print_error("WRONG %s image %u: %s %s: aravis %s, library %s\n", file, image, name,
                            what, a->value, o->value);
            }
        } else if (a_ok) {
            if (!strcmp(what, "enum") && !a->value[0])
                ++t->both_no_entry; /* aravis's "" is its "no entry" */
            else
                ++t->we_refuse;
        } else if (o_ok) {
            ++t->aravis_refuses;
        } else {
            ++t->both_refuse;
        }
    }
    for (size_t i = 0; i < theirs->n; ++i) {
        const char *tab = strchr(theirs->v[i].key, '\t');
        if (strncmp(tab + 1, "limit", 5) == 0)
            continue;
        char name[256];
        snprintf(name, sizeof name, "%.*s", (int)(tab - theirs->v[i].key), theirs->v[i].key);
        if (!find_fact(ours, name, tab + 1))
            ++t->only_aravis;
    }
}

/* Resolved: on some image the value (and the register, for a feature that
 * has one) evaluates; a command: its register evaluates. */
static const char *coverage_cell(flt_genicam *g, registers *r, const char *feature, char *why,
                                 size_t why_size) {
    flt_genicam_type type;
    if (flt_genicam_feature_info(g, feature, &type, NULL, NULL) != FLT_OK)
        return "-";
    why[0] = 0;
    for (unsigned image = 0; image < FLT_REGISTER_IMAGES; ++image) {
        r->image = image;
        r->writes = 0;
        int64_t iv;
        double dv;
        const char *sv;
        flt_status st = FLT_OK;
        switch (type) {
            case FLT_GENICAM_INTEGER:
            case FLT_GENICAM_ENUMERATION:
            case FLT_GENICAM_BOOLEAN:
                st = flt_genicam_get_int(g, feature, &iv);
                break;
            case FLT_GENICAM_FLOAT:
                st = flt_genicam_get_float(g, feature, &dv);
                break;
            case FLT_GENICAM_STRING:
                st = flt_genicam_get_string(g, feature, &sv);
                break;
            default:
                break;
        }
        if (st == FLT_OK) {
            flt_status reg = flt_genicam_register(g, feature, NULL, NULL, NULL, NULL, NULL);
            /* NOT_FOUND: a formula or a constant, which has no register */
            if (reg == FLT_OK || (reg == FLT_ERR_NOT_FOUND && type != FLT_GENICAM_COMMAND &&
                                  strstr(flt_last_error_message(), "no single register")))
                return "ok";
        }
        if (!why[0])
            snprintf(why, why_size, "%s", flt_last_error_message());
    }
    return "REF";
}

static void test_real_descriptions(void **state) {
    (void)state;
    char path[1024];
    if (!flt_external_path(k_files[0], path, sizeof path))
        skip(); /* the helper said why */
    const char *root = getenv("FLT_EXTERNAL_DATA");

    const char *cell[FILES][FEATURES];
    char why[FILES][FEATURES][200];
    int defined = 0, resolved = 0, refused = 0;
    tally total;
    memset(&total, 0, sizeof total);
    int cross_checked = 0;

    for (size_t f = 0; f < FILES; ++f) {
        snprintf(path, sizeof path, "%s/%s", root, k_files[f]);
        flt_genicam *g = NULL;
        if (flt_genicam_load(path, &g) != FLT_OK)
            fail_msg("%s does not load: %s", k_files[f], flt_last_error_message());
        registers r;
        memset(&r, 0, sizeof r);
        assert_int_equal(flt_genicam_set_registers(g, read_image, write_image, &r), FLT_OK);

        for (size_t c = 0; c < FEATURES; ++c) {
            const char *feature = k_features[c][0];
            flt_genicam_type type;
            if (k_features[c][1] &&
                flt_genicam_feature_info(g, feature, &type, NULL, NULL) != FLT_OK)
                feature = k_features[c][1];
            cell[f][c] = coverage_cell(g, &r, feature, why[f][c], sizeof why[f][c]);
            if (strcmp(cell[f][c], "-") != 0) {
                ++defined;
                resolved += !strcmp(cell[f][c], "ok");
                refused += !strcmp(cell[f][c], "REF");
            }
        }
        flt_genicam_destroy(g);

#ifdef FLT_ARAVIS_EVAL
        tally t;
        memset(&t, 0, sizeof t);
        for (unsigned image = 0; image < FLT_REGISTER_IMAGES; ++image) {
            /* a fresh handle per image: commands change host-side values */
            assert_int_equal(flt_genicam_load(path, &g), FLT_OK);
            memset(&r, 0, sizeof r);
            r.image = image;
            assert_int_equal(flt_genicam_set_registers(g, read_image, write_image, &r), FLT_OK);
            facts ours = {0}, theirs = {0};
            evaluate_all(g, &r, &ours);
            flt_genicam_destroy(g);
            if (!aravis_facts(path, image, &theirs))
                fail_msg("aravis_eval failed on %s image %u", k_files[f], image);
            sort_facts(&ours);
            sort_facts(&theirs);
            compare(k_files[f], image, &ours, &theirs, &t);
            free_facts(&ours);
            free_facts(&theirs);
        }
        const char *base = strrchr(k_files[f], '/') + 1;
        print_message("cross-check %-30s facts %7ld agree %7ld WRONG %ld | library refuses %5ld "
                      "aravis refuses %4ld both %5ld | aravis limits %5ld\n",
                      base, t.compared, t.agree + t.both_no_entry, t.wrong, t.we_refuse,
                      t.aravis_refuses, t.both_refuse, t.limited);
        total.compared += t.compared;
        total.agree += t.agree;
        total.wrong += t.wrong;
        total.we_refuse += t.we_refuse;
        total.aravis_refuses += t.aravis_refuses;
        total.both_refuse += t.both_refuse;
        total.both_no_entry += t.both_no_entry;
        total.limited += t.limited;
        total.only_ours += t.only_ours;
        total.only_aravis += t.only_aravis;
        cross_checked = 1;
#endif
    }

    /* The coverage table. */
    print_message("\ncoverage of the features an acquisition needs (ok resolved, REF refused, "
                  "- absent; Exp = ExposureTime or ExposureTimeAbs, Gain = Gain or GainRaw):\n");
    print_message("%-32s", "file");
    for (size_t c = 0; c < FEATURES; ++c)
        print_message(" %-4s", k_columns[c]);
    print_message("\n");
    for (size_t f = 0; f < FILES; ++f) {
        print_message("%-32s", strrchr(k_files[f], '/') + 1);
        for (size_t c = 0; c < FEATURES; ++c)
            print_message(" %-4s", cell[f][c]);
        print_message("\n");
    }
    print_message("defined %d, resolved %d, refused %d\n", defined, resolved, refused);
    for (size_t f = 0; f < FILES; ++f)
        for (size_t c = 0; c < FEATURES; ++c)
            if (!strcmp(cell[f][c], "REF"))
                print_error("refused: %s %s: %s\n", strrchr(k_files[f], '/') + 1, k_features[c][0],
                            why[f][c]);

    if (cross_checked) {
        print_message("\ncross-check with aravis, %d files x %d register images: %ld facts "
                      "compared, %ld agree (%ld of them enumerations both find no entry for), "
                      "%ld WRONG; the library refuses %ld where aravis gives a value, aravis "
                      "refuses %ld where the library gives one, both refuse %ld; %ld facts "
                      "aravis cannot evaluate (not compared); facts only one side lists: "
                      "library %ld, aravis %ld\n",
                      FILES, FLT_REGISTER_IMAGES, total.compared, total.agree + total.both_no_entry,
                      total.both_no_entry, total.wrong, total.we_refuse, total.aravis_refuses,
                      total.both_refuse, total.limited, total.only_ours, total.only_aravis);
        /* aravis lists no fact the library does not (it would be a node the
         * library does not know). */
        assert_int_equal(total.only_aravis, 0);
        assert_int_equal(total.wrong, 0);
        /* a meaningful comparison: the bulk of the facts agree */
        assert_true(total.agree > 100000);
    } else {
        print_message("\ncross-check with aravis skipped: aravis_eval was not built "
                      "(libaravis-dev is absent)\n");
    }
    assert_int_equal(refused, 0);
    assert_int_equal(resolved, defined);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_real_descriptions),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
