// SPDX-License-Identifier: Apache-2.0
/*
 * The archive (flatline/record.h): the sheets of a simulated coil on the
 * README's line (1,150 fibers, a row every 1 mm, 3 m sheets, the strip's
 * heave and the camera's peak noise), judged by the example rule set, go
 * into an SQLite archive; each is stored once however often it is given;
 * the stored values, verdicts and maps are what the gauge said (the map's
 * CRC-32; tests/python decodes it against the sheet); a 3 m sheet with its
 * map at 0.001 mm takes at most 2 MB; "the failed sheets of a coil" is one
 * query; retention by bytes and by days removes the oldest sheets and
 * nothing else.
 *
 * With FLT_TEST_POSTGRES set (a libpq connection string; .ci/postgres
 * starts a throwaway server), the same runs against PostgreSQL.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cmocka.h>
#include <sqlite3.h>
#include <zlib.h>

#include "flatline/flatline.h"
#include "test_files.h"

#define ok(call) assert_int_equal((call), FLT_OK)

enum { FIBERS = 1150, ROWS = 12000, MAX_SHEETS = 8 };
static const double SHEET_MM = 3000.0;

static const char k_rules[] =
    "{ \"format\": \"flatline-tolerances\", \"version\": 1, \"name\": \"example\", \"rules\": [\n"
    " { \"name\": \"straightedge 1 m along\", \"measure\": \"straightedge_along\",\n"
    "   \"length_mm\": 1000, \"bands\": [ { \"thickness_mm\": [1.5, 12], \"width_mm\": [600, "
    "2100], \"limit\": 2.5 } ] },\n"
    " { \"name\": \"largest zone I-Units\", \"measure\": \"zone_i_units\",\n"
    "   \"bands\": [ { \"thickness_mm\": [1.5, 12], \"width_mm\": [600, 2100], \"limit\": 7 } ] "
    "},\n"
    " { \"name\": \"wave steepness\", \"measure\": \"wave_steepness\",\n"
    "   \"bands\": [ { \"thickness_mm\": [1.5, 12], \"width_mm\": [600, 2100], \"limit\": 0.8 } ] "
    "}\n"
    "] }\n";

static char dir[512], gauge_archive[600];

static int setup(void **state) {
    (void)state;
    return tf_temp_dir(dir, sizeof dir, "archive");
}

static int teardown(void **state) {
    (void)state;
    tf_remove_tree(dir);
    return 0;
}

typedef struct coil_run {
    flt_sheet *sheet[MAX_SHEETS];
    size_t sheets;
} coil_run;

/* The coil: rows of the simulated line through a gauge that keeps maps. */
static void run_coil(coil_run *run) {
    flt_calib *calib = NULL;
    ok(flt_calib_create_reference(892, 256, -1000.0, 2000.0 / (FIBERS - 1), FIBERS, &calib));
    flt_options *so = NULL;
    ok(flt_options_create(&so));
    ok(flt_options_set(so, FLT_OPT_SIM_FRAME_SPACING, 1.0));
    ok(flt_options_set(so, FLT_OPT_SIM_HEAVE_SIGMA, 0.5));
    ok(flt_options_set(so, FLT_OPT_SIM_PEAK_SIGMA, 1.0 / 16));
    flt_sim *sim = NULL;
    ok(flt_sim_create(calib, so, &sim));
    flt_options_destroy(so);
    ok(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 4.0, 1500.0));
    flt_options *go = NULL;
    ok(flt_options_create(&go));
    ok(flt_options_set(go, FLT_OPT_GAUGE_WORKERS, 0));
    ok(flt_options_set(go, FLT_OPT_GAUGE_KEEP_MAPS, 1));
    ok(flt_options_set(go, FLT_OPT_RIGID_MOTION, 1));
    ok(flt_options_set(go, FLT_OPT_ROBUST, 1));
    flt_gauge *g = NULL;
    ok(flt_gauge_create(calib, go, &g));
    flt_options_destroy(go);
    flt_rules *rules = NULL;
    ok(flt_rules_load_text(k_rules, strlen(k_rules), &rules));
    ok(flt_gauge_set_rules(g, rules, 4.0, 0.0));
    flt_rules_destroy(rules);
    /* The gauge archives its sheets itself too, with the coil's identity
     * (its nominal thickness chooses the bands) and a leveler note. */
    snprintf(gauge_archive, sizeof gauge_archive, "%s/gauge.sqlite", dir);
    flt_archive *ga = NULL;
    ok(flt_archive_open(gauge_archive, "CTL 2", NULL, &ga));
    ok(flt_gauge_attach_archive(g, ga));
    flt_coil_info *coil = NULL;
    ok(flt_coil_info_create("4711", &coil));
    ok(flt_coil_info_set_text(coil, FLT_COIL_FIELD_GRADE, "S355MC"));
    ok(flt_coil_info_set_text(coil, FLT_COIL_FIELD_CUSTOMER, "Acme"));
    ok(flt_coil_info_set_nominal(coil, 4.0, 0.0));
    ok(flt_coil_info_set_extra(coil, "shift", "B"));
    ok(flt_gauge_set_coil(g, coil));
    flt_coil_info_destroy(coil);
    for (int c = 1; c * SHEET_MM < ROWS; ++c)
        ok(flt_gauge_cut(g, c * SHEET_MM));
    double *h = malloc(sizeof(double) * FIBERS), *s = malloc(sizeof(double) * FIBERS);
    uint8_t *v = malloc(FIBERS);
    for (int r = 0; r < ROWS; ++r) {
        double e = 0, sr = 0;
        ok(flt_sim_next_rows(sim, 1, FIBERS, &e, &sr, h, s, v, NULL));
        if (r == 4000)
            ok(flt_gauge_note(g, "leveler", "roll 2 -0.10 mm"));
        ok(flt_gauge_push_row(g, e, FIBERS, h, s, v));
        flt_sheet *sh = NULL;
        ok(flt_gauge_next_sheet(g, 0, &sh));
        if (sh && run->sheets < MAX_SHEETS)
            run->sheet[run->sheets++] = sh;
        else
            flt_sheet_destroy(sh);
    }
    ok(flt_gauge_flush(g));
    for (;;) {
        flt_sheet *sh = NULL;
        ok(flt_gauge_next_sheet(g, 0, &sh));
        if (!sh)
            break;
        if (run->sheets < MAX_SHEETS)
            run->sheet[run->sheets++] = sh;
        else
            flt_sheet_destroy(sh);
    }
    free(h);
    free(s);
    free(v);
    ok(flt_gauge_attach_archive(g, NULL));
    ok(flt_archive_flush(ga, 30000));
    flt_archive_destroy(ga);
    flt_gauge_destroy(g);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

static coil_run g_run;

static int64_t scalar(sqlite3 *db, const char *sql) {
    sqlite3_stmt *q = NULL;
    if (sqlite3_prepare_v2(db, sql, -1, &q, NULL) != SQLITE_OK)
        fail_msg("%s: %s", sql, sqlite3_errmsg(db));
    int64_t v = -1;
    if (sqlite3_step(q) == SQLITE_ROW)
        v = sqlite3_column_int64(q, 0);
    sqlite3_finalize(q);
    return v;
}

static void test_sheets_stored_once(void **state) {
    (void)state;
    if (g_run.sheets == 0)
        run_coil(&g_run);
    assert_int_equal(g_run.sheets, 4); /* 3 cuts, then the flush */
    char path[600];
    snprintf(path, sizeof path, "%s/archive.sqlite", dir);
    flt_archive *ar = NULL;
    ok(flt_archive_open(path, "CTL 2", NULL, &ar));
    int backend = -1;
    ok(flt_archive_backend(ar, &backend));
    assert_int_equal(backend, 0);
    for (size_t i = 0; i < g_run.sheets; ++i)
        ok(flt_archive_add_sheet(ar, g_run.sheet[i]));
    ok(flt_archive_add_sheet(ar, g_run.sheet[1])); /* twice: stored once */
    ok(flt_archive_flush(ar, 30000));
    uint64_t n = 0;
    ok(flt_archive_count(ar, FLT_ARCHIVE_COUNT_SHEETS, &n));
    assert_int_equal(n, 5);
    ok(flt_archive_count(ar, FLT_ARCHIVE_COUNT_STORED, &n));
    assert_int_equal(n, 5);
    ok(flt_archive_count(ar, FLT_ARCHIVE_COUNT_LOST, &n));
    assert_int_equal(n, 0);
    flt_archive_destroy(ar);

    sqlite3 *db = NULL;
    assert_int_equal(sqlite3_open(path, &db), SQLITE_OK);
    assert_int_equal(scalar(db, "SELECT count(*) FROM sheets"), 4);
    assert_int_equal(scalar(db, "SELECT count(*) FROM coils"), 1);
    assert_int_equal(scalar(db, "SELECT sheets FROM coils"), 4);
    assert_int_equal(scalar(db, "SELECT count(*) FROM verdicts"), 4 * 3);
    /* The values are the gauge's, bit for bit (REAL columns are doubles). */
    for (size_t i = 0; i < g_run.sheets; ++i) {
        double id = 0, iu = 0, rows = 0, failed = 0;
        ok(flt_sheet_get(g_run.sheet[i], FLT_SHEET_ID, &id));
        ok(flt_sheet_get(g_run.sheet[i], FLT_SHEET_MAX_I_UNITS, &iu));
        ok(flt_sheet_get(g_run.sheet[i], FLT_SHEET_ROWS, &rows));
        ok(flt_sheet_get(g_run.sheet[i], FLT_SHEET_RULES_FAILED, &failed));
        char sql[200];
        snprintf(sql, sizeof sql,
                 "SELECT max_i_units, rows, rules_failed, length(map), map_crc32, "
                 "map FROM sheets WHERE sheet_id = %d",
                 (int)id);
        sqlite3_stmt *q = NULL;
        assert_int_equal(sqlite3_prepare_v2(db, sql, -1, &q, NULL), SQLITE_OK);
        assert_int_equal(sqlite3_step(q), SQLITE_ROW);
        assert_true(sqlite3_column_double(q, 0) == iu);
        assert_true(sqlite3_column_int64(q, 1) == (int64_t)rows);
        assert_true(sqlite3_column_int64(q, 2) == (int64_t)failed);
        const int bytes = sqlite3_column_int(q, 3);
        const uLong crc = crc32(0, sqlite3_column_blob(q, 5), (uInt)bytes);
        assert_true((int64_t)crc == sqlite3_column_int64(q, 4));
        const double samples = rows * FIBERS;
        print_message("sheet %d: %.0f rows x %d fibers, map %.3f MB at 0.001 mm (%.3f bytes "
                      "per sample), largest I-Units %.2f, %.0f rules failed\n",
                      (int)id, rows, FIBERS, bytes / 1e6, bytes / samples, iu, failed);
        /* A 3 m sheet (a row every mm) with its map: at most 2 MB. */
        if (rows >= 2900)
            assert_true(bytes <= 2000000);
        sqlite3_finalize(q);
    }
    /* "The failed sheets of coil 4711" and "every sheet of grade S355MC
     * last week" are one query each. */
    const int64_t failed_count = scalar(db, "SELECT count(*) FROM sheets WHERE coil_id = '4711' "
                                            "AND verdict = 'fail'");
    const int64_t fails = scalar(db, "SELECT count(*) FROM sheets WHERE rules_failed > 0");
    assert_int_equal(failed_count, fails);
    char week[200];
    snprintf(week, sizeof week,
             "SELECT count(*) FROM sheets WHERE grade = 'S355MC' AND utc_ns > %lld",
             (long long)time(NULL) * 1000000000LL - 7LL * 86400 * 1000000000LL);
    assert_int_equal(scalar(db, week), 4);
    sqlite3_close(db);
}

/* The gauge's own archive: the coil's identity on its row and its sheets',
 * its statistics at its end, the note on the sheet it was given in. */
static void test_gauge_archives_coil(void **state) {
    (void)state;
    if (g_run.sheets == 0)
        run_coil(&g_run);
    sqlite3 *db = NULL;
    assert_int_equal(sqlite3_open(gauge_archive, &db), SQLITE_OK);
    assert_int_equal(scalar(db, "SELECT count(*) FROM sheets WHERE coil_id = '4711' AND grade = "
                                "'S355MC'"),
                     4);
    assert_int_equal(scalar(db, "SELECT count(*) FROM coils WHERE coil_id = '4711' AND "
                                "customer = 'Acme' AND finished = 1 AND sheets = 4"),
                     1);
    assert_int_equal(scalar(db, "SELECT count(*) FROM coil_extras WHERE key = 'shift' AND "
                                "value = 'B'"),
                     1);
    assert_int_equal(scalar(db, "SELECT count(*) FROM coil_stats"), 3);
    /* The note: given at row 4000 (s ~ 4000 mm), on the second sheet. */
    assert_int_equal(scalar(db, "SELECT s.sheet_index FROM notes n JOIN sheets s ON s.sheet_uid = "
                                "n.sheet_uid WHERE n.kind = 'leveler'"),
                     2);
    /* The bands were chosen by the coil's nominal thickness. */
    assert_int_equal(scalar(db, "SELECT count(*) FROM sheets WHERE thickness_mm = 4.0"), 4);
    /* The verdicts agree with the sheets the caller read. */
    for (size_t i = 0; i < g_run.sheets; ++i) {
        double id = 0, verdict = 0;
        ok(flt_sheet_get(g_run.sheet[i], FLT_SHEET_ID, &id));
        ok(flt_sheet_get(g_run.sheet[i], FLT_SHEET_VERDICT, &verdict));
        char sql[160];
        snprintf(sql, sizeof sql,
                 "SELECT count(*) FROM sheets WHERE sheet_id = %d AND verdict = '%s'", (int)id,
                 verdict == FLT_VERDICT_FAIL   ? "fail"
                 : verdict == FLT_VERDICT_PASS ? "pass"
                                               : "not_judged");
        assert_int_equal(scalar(db, sql), 1);
    }
    sqlite3_close(db);
}

static void test_retention(void **state) {
    (void)state;
    char path[600];
    snprintf(path, sizeof path, "%s/archive.sqlite", dir);
    sqlite3 *db = NULL;
    assert_int_equal(sqlite3_open(path, &db), SQLITE_OK);
    /* Sheet 1 was finished ten days ago. */
    assert_int_equal(sqlite3_exec(db,
                                  "UPDATE sheets SET utc_ns = utc_ns - 864000000000000 WHERE "
                                  "sheet_id = 1",
                                  NULL, NULL, NULL),
                     SQLITE_OK);
    const int64_t total = scalar(db, "SELECT sum(bytes) FROM sheets");
    const int64_t last = scalar(db, "SELECT bytes FROM sheets WHERE sheet_id = 4");
    sqlite3_close(db);

    flt_options *o = NULL;
    ok(flt_options_create(&o));
    ok(flt_options_set(o, FLT_OPT_ARCHIVE_RETENTION_DAYS, 5));
    flt_archive *ar = NULL;
    ok(flt_archive_open(path, "CTL 2", o, &ar)); /* opening applies the limits */
    uint64_t pruned = 0;
    ok(flt_archive_count(ar, FLT_ARCHIVE_COUNT_PRUNED, &pruned));
    assert_int_equal(pruned, 1);
    flt_archive_destroy(ar);
    /* By bytes: room for the newest sheet only (its bytes, in MiB). */
    ok(flt_options_set(o, FLT_OPT_ARCHIVE_RETENTION_DAYS, 0));
    ok(flt_options_set(o, FLT_OPT_ARCHIVE_RETENTION_MB, (double)last / 1048576.0 + 1e-6));
    ok(flt_archive_open(path, "CTL 2", o, &ar));
    uint64_t removed = 0;
    ok(flt_archive_prune(ar, &removed));
    assert_int_equal(removed, 0); /* already done at open */
    ok(flt_archive_count(ar, FLT_ARCHIVE_COUNT_PRUNED, &pruned));
    assert_int_equal(pruned, 2);
    flt_archive_destroy(ar);
    flt_options_destroy(o);

    assert_int_equal(sqlite3_open(path, &db), SQLITE_OK);
    assert_int_equal(scalar(db, "SELECT count(*) FROM sheets"), 1);
    assert_int_equal(scalar(db, "SELECT sheet_id FROM sheets"), 4);
    assert_int_equal(scalar(db, "SELECT count(*) FROM verdicts"), 3);
    assert_int_equal(scalar(db, "SELECT count(*) FROM coils"), 1);
    print_message("retention: %lld bytes in 4 sheets; 10 days old removed at 5 days, then the "
                  "oldest until %lld bytes fit\n",
                  (long long)total, (long long)last);
    sqlite3_close(db);
}

static void test_archive_refuses(void **state) {
    (void)state;
    char path[600];
    snprintf(path, sizeof path, "%s/not_an_archive.sqlite", dir);
    sqlite3 *db = NULL;
    assert_int_equal(sqlite3_open(path, &db), SQLITE_OK);
    assert_int_equal(sqlite3_exec(db,
                                  "CREATE TABLE archive_meta (key TEXT, value TEXT); INSERT INTO "
                                  "archive_meta VALUES ('format', 'flatline-archive'), "
                                  "('version', '99')",
                                  NULL, NULL, NULL),
                     SQLITE_OK);
    sqlite3_close(db);
    flt_archive *ar = NULL;
    assert_int_equal(flt_archive_open(path, "", NULL, &ar), FLT_ERR_FORMAT);
    assert_non_null(strstr(flt_last_error_message(), "version"));
    assert_null(ar);
    assert_int_equal(flt_archive_open(path, "bad\nline", NULL, &ar), FLT_ERR_INVALID_ARGUMENT);
    /* A PostgreSQL location without a server: a clear error, no hang
     * beyond libpq's connect timeout. */
    const flt_status st =
        flt_archive_open("postgresql://nobody@127.0.0.1:1/none?connect_timeout=2", "", NULL, &ar);
    assert_true(st == FLT_ERR_IO || st == FLT_ERR_NOT_FOUND);
    assert_null(ar);
    print_message("no server: %s\n", flt_last_error_message());
}

static int free_run(void **state) {
    (void)state;
    for (size_t i = 0; i < g_run.sheets; ++i)
        flt_sheet_destroy(g_run.sheet[i]);
    return teardown(state);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sheets_stored_once),
        cmocka_unit_test(test_gauge_archives_coil),
        cmocka_unit_test(test_retention),
        cmocka_unit_test(test_archive_refuses),
    };
    return cmocka_run_group_tests(tests, setup, free_run);
}
