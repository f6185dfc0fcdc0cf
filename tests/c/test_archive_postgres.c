// SPDX-License-Identifier: Apache-2.0
/*
 * The archive on a real PostgreSQL server that the test starts (Debian's
 * postgresql, a throwaway cluster: tests/postgres/pg_cluster.sh), stopped
 * in the middle of a coil and started again: a gauge archives every sheet
 * of the coil (flt_gauge_attach_archive); the sheets measured while the
 * server was away wait in the archive's buffer, the archive reconnects, and
 * all 10 sheets of the coil are in the database, each once, with their
 * verdicts, the coil's identity and statistics; the counters say how many
 * attempts failed and how often it reconnected, and the log says when the
 * database went away and when it came back. Skipped (with a message) where
 * no PostgreSQL server is installed.
 *
 * Windows: skipped (exit code 77, which ctest reports as skipped). The
 * server is started by a bash script from Debian's postgresql, and the
 * win64 build has no libpq.dll to load; the Windows side of loading libpq
 * (LoadLibraryW of a UTF-8 path, the clear errors when it is missing or
 * is not libpq) runs in test_archive and test_archive_libpq.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
int main(void) {
    fprintf(stderr, "skipped on Windows: the test starts a PostgreSQL server with Debian's "
                    "postgresql (pg_cluster.sh) and the win64 build has no libpq.dll; the "
                    "libpq loading of Windows is tested by test_archive and "
                    "test_archive_libpq\n");
    return 77;
}
#else
#  include <sys/wait.h>
#  include <unistd.h>

#  include <cmocka.h>

#  include "flatline/flatline.h"

#  define ok(call) assert_int_equal((call), FLT_OK)

enum { FIBERS = 201, SHEETS = 10 };
static const double SHEET_MM = 3000.0, STEP = 2.0;

static const char k_rules[] =
    "{ \"format\": \"flatline-tolerances\", \"version\": 1, \"name\": \"pg\", \"rules\": [\n"
    " { \"name\": \"largest zone I-Units\", \"measure\": \"zone_i_units\",\n"
    "   \"bands\": [ { \"thickness_mm\": [1, 12], \"width_mm\": [0, 3000], \"limit\": 5 } ] },\n"
    " { \"name\": \"straightedge 1 m along\", \"measure\": \"straightedge_along\",\n"
    "   \"length_mm\": 1000, \"bands\": [ { \"thickness_mm\": [1, 12], \"width_mm\": [0, 3000], "
    "\"limit\": 2 } ] } ] }\n";

static char g_dir[64], g_conninfo[512], g_location[600];

/* What the archive told the log. */
static int g_log_away, g_log_back;
static void FLT_CALL on_log(flt_log_level level, const char *component, const char *message,
                            void *user) {
    (void)user;
    if (strcmp(component, "archive") != 0)
        return;
    if (level >= FLT_LOG_WARNING && strstr(message, "does not take sheets"))
        ++g_log_away;
    if (strstr(message, "takes sheets again"))
        ++g_log_back;
    print_message("log [%s] %s\n", component, message);
}

static int cluster(const char *cmd, char *out, size_t cap) {
    char line[400];
    snprintf(line, sizeof line, "bash '%s' %s '%s'", FLT_PG_CLUSTER, cmd, g_dir);
    FILE *p = popen(line, "r");
    if (!p)
        return -1;
    if (out && cap) {
        out[0] = 0;
        if (!fgets(out, (int)cap, p))
            out[0] = 0;
        out[strcspn(out, "\n")] = 0;
    }
    const int st = pclose(p);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/* One number from the database, through psql. */
static long psql_number(const char *sql) {
    char line[1200];
    snprintf(line, sizeof line, "psql '%s' -Atc \"%s\"", g_conninfo, sql);
    FILE *p = popen(line, "r");
    if (!p)
        return -1;
    long v = -1;
    if (fscanf(p, "%ld", &v) != 1)
        v = -1;
    pclose(p);
    return v;
}

static int setup(void **state) {
    (void)state;
    snprintf(g_dir, sizeof g_dir, "/tmp/fltpg.%d", (int)getpid());
    const int st = cluster("start", g_conninfo, sizeof g_conninfo);
    if (st != 0 || g_conninfo[0] == 0) {
        fprintf(stderr, "no PostgreSQL server to start (pg_cluster.sh: %d)\n", st);
        g_conninfo[0] = 0;
        return 0;
    }
    snprintf(g_location, sizeof g_location, "pg:%s", g_conninfo);
    return 0;
}

static int teardown(void **state) {
    (void)state;
    if (g_conninfo[0])
        cluster("remove", NULL, 0);
    return 0;
}

static void test_server_restart_mid_coil(void **state) {
    (void)state;
    if (!g_conninfo[0])
        skip();
    flt_options *ao = NULL;
    ok(flt_options_create(&ao));
    ok(flt_options_set(ao, FLT_OPT_ARCHIVE_RETRY_INTERVAL, 200));
    flt_archive *ar = NULL;
    ok(flt_archive_open(g_location, "line 2", ao, &ar));
    flt_options_destroy(ao);
    int backend = -1;
    ok(flt_archive_backend(ar, &backend));
    assert_int_equal(backend, 1);

    flt_calib *calib = NULL;
    ok(flt_calib_create_reference(0, 2048, -1000.0, 10.0, FIBERS, &calib));
    flt_options *so = NULL;
    ok(flt_options_create(&so));
    ok(flt_options_set(so, FLT_OPT_SIM_FRAME_SPACING, STEP));
    ok(flt_options_set(so, FLT_OPT_SIM_PEAK_SIGMA, 1.0 / 16));
    flt_sim *sim = NULL;
    ok(flt_sim_create(calib, so, &sim));
    flt_options_destroy(so);
    ok(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, 3.0, 2000.0));
    flt_options *go = NULL;
    ok(flt_options_create(&go));
    ok(flt_options_set(go, FLT_OPT_GAUGE_WORKERS, 0));
    ok(flt_options_set(go, FLT_OPT_GAUGE_KEEP_MAPS, 1));
    ok(flt_options_set(go, FLT_OPT_GAUGE_FRAME_SPACING, STEP));
    flt_gauge *g = NULL;
    ok(flt_gauge_create(calib, go, &g));
    flt_options_destroy(go);
    flt_rules *rules = NULL;
    ok(flt_rules_load_text(k_rules, strlen(k_rules), &rules));
    ok(flt_gauge_set_rules(g, rules, 4.0, 0.0));
    flt_rules_destroy(rules);
    flt_coil_info *coil = NULL;
    ok(flt_coil_info_create("4711", &coil));
    ok(flt_coil_info_set_text(coil, FLT_COIL_FIELD_GRADE, "S355MC"));
    ok(flt_gauge_set_coil(g, coil));
    flt_coil_info_destroy(coil);
    ok(flt_gauge_attach_archive(g, ar));
    ok(flt_log_set_callback(on_log, NULL, FLT_LOG_WARNING));
    for (int c = 1; c < SHEETS; ++c)
        ok(flt_gauge_cut(g, c * SHEET_MM));

    double h[FIBERS], s[FIBERS];
    uint8_t v[FIBERS];
    int added = 0, down_while = 0;
    uint64_t failures_while_down = 0, pending_while_down = 0;
    const int rows = (int)(SHEETS * SHEET_MM / STEP);
    for (int r = 0; r <= rows; ++r) {
        double e = 0, sr = 0;
        ok(flt_sim_next_rows(sim, 1, FIBERS, &e, &sr, h, s, v, NULL));
        ok(flt_gauge_push_row(g, e, FIBERS, h, s, v));
        for (;;) {
            flt_sheet *sh = NULL;
            ok(flt_gauge_next_sheet(g, 0, &sh));
            if (!sh)
                break;
            flt_sheet_destroy(sh); /* archived by the gauge before it came out */
            ++added;
            if (added == 4) {
                /* Four sheets stored; then the server goes away. */
                ok(flt_archive_flush(ar, 20000));
                assert_int_equal(cluster("stop", NULL, 0), 0);
            }
            if (added >= 5 && added <= 7) {
                ++down_while;
                usleep(300000); /* the archive tries (every 200 ms) and fails */
            }
            if (added == 7) {
                ok(flt_archive_count(ar, FLT_ARCHIVE_COUNT_FAILURES, &failures_while_down));
                ok(flt_archive_count(ar, FLT_ARCHIVE_COUNT_PENDING, &pending_while_down));
                char ignored[512];
                assert_int_equal(cluster("start", ignored, sizeof ignored), 0);
            }
        }
    }
    ok(flt_gauge_flush(g));
    for (;;) {
        flt_sheet *sh = NULL;
        ok(flt_gauge_next_sheet(g, 0, &sh));
        if (!sh)
            break;
        flt_sheet_destroy(sh);
        ++added;
    }
    assert_int_equal(added, SHEETS);
    ok(flt_archive_flush(ar, 30000));
    uint64_t stored = 0, lost = 0, reconnects = 0, failures = 0;
    ok(flt_archive_count(ar, FLT_ARCHIVE_COUNT_STORED, &stored));
    ok(flt_archive_count(ar, FLT_ARCHIVE_COUNT_LOST, &lost));
    ok(flt_archive_count(ar, FLT_ARCHIVE_COUNT_RECONNECTS, &reconnects));
    ok(flt_archive_count(ar, FLT_ARCHIVE_COUNT_FAILURES, &failures));
    print_message("server stopped after sheet 4 and started after sheet 7: %llu failed attempts "
                  "and %llu sheets waiting while it was away; at the end %llu stored, %llu lost, "
                  "%llu reconnects\n",
                  (unsigned long long)failures_while_down, (unsigned long long)pending_while_down,
                  (unsigned long long)stored, (unsigned long long)lost,
                  (unsigned long long)reconnects);
    assert_true(failures_while_down >= 1);
    assert_true(pending_while_down >= 1);
    assert_int_equal(stored, SHEETS);
    assert_int_equal(lost, 0);
    assert_true(reconnects >= 1);
    ok(flt_gauge_attach_archive(g, NULL));
    flt_archive_destroy(ar);
    ok(flt_log_set_callback(NULL, NULL, FLT_LOG_WARNING));
    /* The log said the database went away, and that it came back. */
    assert_int_equal(g_log_away, 1);
    assert_int_equal(g_log_back, 1);

    assert_int_equal(psql_number("SELECT count(*) FROM sheets"), SHEETS);
    assert_int_equal(psql_number("SELECT count(DISTINCT sheet_index) FROM sheets"), SHEETS);
    assert_int_equal(psql_number("SELECT count(*) FROM verdicts"), 2 * SHEETS);
    assert_int_equal(psql_number("SELECT sheets FROM coils"), SHEETS);
    assert_int_equal(psql_number("SELECT count(*) FROM coils WHERE coil_id = '4711' AND grade = "
                                 "'S355MC' AND finished = 1"),
                     1);
    assert_int_equal(psql_number("SELECT count(*) FROM coil_stats"), 2);
    assert_int_equal(psql_number("SELECT count(*) FROM sheets WHERE coil_id = '4711'"), SHEETS);
    assert_int_equal(psql_number("SELECT count(*) FROM sheets WHERE map IS NOT NULL AND "
                                 "octet_length(map) > 1000"),
                     SHEETS);
    flt_gauge_destroy(g);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_server_restart_mid_coil)};
    return cmocka_run_group_tests(tests, setup, teardown);
}
#endif
