// SPDX-License-Identifier: Apache-2.0
/*
 * Recordings (flatline/record.h): rows written and read back as the
 * quantization defines them (exactly: the quantum is a power of two, so
 * the tolerance is 0 against the quantized values and Q/2 against the
 * input), events and coils counted, every block's CRC checked and a
 * damaged block found, a file never overwritten, a writer that cannot
 * write counts every row it lost; coil identities.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <sqlite3.h>

#include "flatline/flatline.h"
#include "test_files.h"

#define ok(call) assert_int_equal((call), FLT_OK)

enum { FIBERS = 64, ROWS = 1500 };

static void assert_error(flt_status got, flt_status want, const char *needle) {
    if (got != want)
        fail_msg("status %s, expected %s (%s)", flt_status_string(got), flt_status_string(want),
                 flt_last_error_message());
    if (needle && !strstr(flt_last_error_message(), needle))
        fail_msg("message '%s' does not mention '%s'", flt_last_error_message(), needle);
}

static char dir[512];

static int setup(void **state) {
    (void)state;
    return tf_temp_dir(dir, sizeof dir, "record");
}

static int teardown(void **state) {
    (void)state;
    tf_remove_tree(dir);
    return 0;
}

static flt_calib *reference_calib(void) {
    flt_calib *calib = NULL;
    /* 64 fibers 30 mm apart across the reference sensor's field. */
    ok(flt_calib_create_reference(0, 2048, -945.0, 30.0, FIBERS, &calib));
    return calib;
}

/* A deterministic pseudo-random number in [-1, 1) for (row, fiber, which). */
static double noise(unsigned r, unsigned k, unsigned which) {
    uint32_t x = r * 2654435761u ^ (k + 1) * 40503u ^ (which + 7) * 97u;
    x ^= x >> 13;
    x *= 0x5bd1e995u;
    x ^= x >> 15;
    return (double)(x & 0xFFFFFF) / (double)0x800000 - 1.0;
}

/* Row r: a wavy strip with noise, fibers 0..2 off (invalid) on odd rows. */
static void make_row(unsigned r, double *h, double *s, uint8_t *v) {
    for (unsigned k = 0; k < FIBERS; ++k) {
        h[k] = 3.0 * sin(0.01 * r + 0.1 * k) + 0.08 * noise(r, k, 0);
        s[k] = 0.02 * cos(0.01 * r) + 0.001 * noise(r, k, 1);
        v[k] = !(k < 3 && (r & 1));
        if (!v[k])
            h[k] = s[k] = NAN;
    }
}

static void pause_ms(unsigned ms) {
#ifdef _WIN32
    Sleep(ms);
#else
    usleep(ms * 1000u);
#endif
}

static void path_in_dir(char *out, size_t cap, const char *name) {
    snprintf(out, cap, "%s/%s", dir, name);
}

static void write_recording(const char *path, const flt_options *opts, unsigned rows) {
    flt_calib *calib = reference_calib();
    flt_recorder *rec = NULL;
    ok(flt_recorder_create(path, calib, opts, &rec));
    flt_coil_info *coil = NULL;
    ok(flt_coil_info_create("4711", &coil));
    ok(flt_coil_info_set_text(coil, FLT_COIL_FIELD_GRADE, "S355MC"));
    ok(flt_coil_info_set_nominal(coil, 4.0, 1500.0));
    ok(flt_coil_info_set_extra(coil, "line", "CTL 2 \"Süd\""));
    ok(flt_recorder_set_coil(rec, coil));
    flt_coil_info_destroy(coil);
    double h[FIBERS], s[FIBERS];
    uint8_t v[FIBERS];
    for (unsigned r = 0; r < rows; ++r) {
        make_row(r, h, s, v);
        if (r == 700)
            ok(flt_recorder_cut(rec, 700.0 + 50.0));
        ok(flt_recorder_push_row(rec, (double)r + 0.5, FIBERS, h, s, v));
    }
    ok(flt_recorder_sync(rec, 10000));
    uint64_t n = 0;
    ok(flt_recorder_count(rec, FLT_RECORDER_COUNT_ROWS_STORED, &n));
    assert_int_equal(n, rows);
    ok(flt_recorder_count(rec, FLT_RECORDER_COUNT_ROWS_LOST, &n));
    assert_int_equal(n, 0);
    ok(flt_recorder_count(rec, FLT_RECORDER_COUNT_EVENTS, &n));
    assert_int_equal(n, 2);
    flt_recorder_destroy(rec);
    flt_calib_destroy(calib);
}

/* Rows come back as the quantization defines them: each laser's height
 * rounded to the quantum (2^-8 mm by default). */
static void test_round_trip(void **state) {
    (void)state;
    char path[600];
    path_in_dir(path, sizeof path, "round_trip.flrec");
    write_recording(path, NULL, ROWS);

    flt_recording *rd = NULL;
    ok(flt_recording_open(path, &rd));
    double v = 0;
    ok(flt_recording_info(rd, FLT_RECORDING_ROWS, &v));
    assert_true(v == ROWS);
    ok(flt_recording_info(rd, FLT_RECORDING_FIBERS, &v));
    assert_true(v == FIBERS);
    ok(flt_recording_info(rd, FLT_RECORDING_EVENTS, &v));
    assert_true(v == 2);
    double quantum = 0, spacing = 0;
    ok(flt_recording_info(rd, FLT_RECORDING_QUANTUM, &quantum));
    assert_true(quantum == 1.0 / 256);
    uint64_t bad = 99;
    ok(flt_recording_verify(rd, &bad));
    assert_int_equal(bad, 0);
    flt_calib *calib = NULL;
    ok(flt_recording_calib(rd, &calib));
    ok(flt_calib_laser_spacing(calib, &spacing));
    flt_calib_destroy(calib);

    static double e[ROWS], t[ROWS], h[ROWS * FIBERS], s[ROWS * FIBERS];
    static uint8_t f[ROWS * FIBERS];
    size_t got = 0;
    ok(flt_recording_read_rows(rd, 0, ROWS, FIBERS, e, t, h, s, f, &got));
    assert_int_equal(got, ROWS);
    double worst_behind = 0, worst_ahead = 0;
    for (unsigned r = 0; r < ROWS; ++r) {
        double hi[FIBERS], si[FIBERS];
        uint8_t vi[FIBERS];
        make_row(r, hi, si, vi);
        assert_true(e[r] == (double)r + 0.5); /* encoder positions are stored as they are */
        assert_true(t[r] > 1.6e9);            /* a UTC time after 2020 */
        for (unsigned k = 0; k < FIBERS; ++k) {
            const size_t i = (size_t)r * FIBERS + k;
            if (!vi[k]) {
                assert_int_equal(f[i], FLT_FLAG_INVALID_INPUT);
                assert_true(isnan(h[i]) && isnan(s[i]));
                continue;
            }
            assert_int_equal(f[i], 0);
            /* The exact value: the laser heights rounded to the quantum. */
            const double zb = hi[k] - si[k] * spacing / 2, za = hi[k] + si[k] * spacing / 2;
            const double qb = llround(zb / quantum) * quantum, qa = llround(za / quantum) * quantum;
            assert_true(h[i] == (qb + qa) * 0.5);
            assert_true(s[i] == (qa - qb) / spacing);
            const double rb = h[i] - s[i] * spacing / 2, ra = h[i] + s[i] * spacing / 2;
            worst_behind = fmax(worst_behind, fabs(rb - zb));
            worst_ahead = fmax(worst_ahead, fabs(ra - za));
        }
    }
    /* Rounding: at most half a quantum per laser (plus the arithmetic's
     * rounding of h and s, far below 1e-9 mm). */
    assert_true(worst_behind <= quantum / 2 + 1e-9);
    assert_true(worst_ahead <= quantum / 2 + 1e-9);
    print_message("round trip: %d rows x %d fibers, largest laser error %.6f / %.6f mm "
                  "(quantum %.6f)\n",
                  ROWS, FIBERS, worst_behind, worst_ahead, quantum);

    /* Reading from the middle, and past the end. */
    ok(flt_recording_read_rows(rd, ROWS - 10, 100, FIBERS, e, NULL, NULL, NULL, NULL, &got));
    assert_int_equal(got, 10);
    assert_true(e[0] == (double)(ROWS - 10) + 0.5);
    ok(flt_recording_read_rows(rd, ROWS + 5, 10, FIBERS, e, NULL, NULL, NULL, NULL, &got));
    assert_int_equal(got, 0);
    flt_recording_destroy(rd);
}

/* A record is never overwritten. */
static void test_refuses_existing_file(void **state) {
    (void)state;
    char path[600];
    path_in_dir(path, sizeof path, "exists.flrec");
    FILE *fp = tf_fopen(path, "wb");
    assert_non_null(fp);
    fputs("not a recording", fp);
    fclose(fp);
    flt_calib *calib = reference_calib();
    flt_recorder *rec = NULL;
    assert_error(flt_recorder_create(path, calib, NULL, &rec), FLT_ERR_IO, "exists");
    assert_null(rec);
    /* ... and a file that is no recording does not open as one. */
    flt_recording *rd = NULL;
    flt_status st = flt_recording_open(path, &rd);
    assert_true(st == FLT_ERR_FORMAT || st == FLT_ERR_IO);
    assert_null(rd);
    flt_calib_destroy(calib);
}

/* A damaged block is found by its checksum, named, and reading it fails
 * cleanly; the others still read. */
static void test_damaged_block(void **state) {
    (void)state;
    char path[600];
    path_in_dir(path, sizeof path, "damaged.flrec");
    flt_options *o = NULL;
    ok(flt_options_create(&o));
    ok(flt_options_set(o, FLT_OPT_RECORD_BLOCK_ROWS, 100)); /* 15 blocks */
    write_recording(path, o, ROWS);
    flt_options_destroy(o);

    sqlite3 *db = NULL;
    assert_int_equal(sqlite3_open(path, &db), SQLITE_OK);
    /* One byte of block 4's payload changed (the 200th). */
    sqlite3_stmt *q = NULL;
    assert_int_equal(
        sqlite3_prepare_v2(db, "SELECT payload FROM blocks WHERE block = 4", -1, &q, NULL),
        SQLITE_OK);
    assert_int_equal(sqlite3_step(q), SQLITE_ROW);
    const int n = sqlite3_column_bytes(q, 0);
    assert_true(n > 200);
    uint8_t *payload = malloc((size_t)n);
    memcpy(payload, sqlite3_column_blob(q, 0), (size_t)n);
    sqlite3_finalize(q);
    payload[199] ^= 1;
    assert_int_equal(
        sqlite3_prepare_v2(db, "UPDATE blocks SET payload = ?1 WHERE block = 4", -1, &q, NULL),
        SQLITE_OK);
    sqlite3_bind_blob(q, 1, payload, n, SQLITE_STATIC);
    assert_int_equal(sqlite3_step(q), SQLITE_DONE);
    sqlite3_finalize(q);
    free(payload);
    sqlite3_close(db);

    flt_recording *rd = NULL;
    ok(flt_recording_open(path, &rd));
    uint64_t bad = 0;
    assert_error(flt_recording_verify(rd, &bad), FLT_ERR_FORMAT, "block 4");
    assert_int_equal(bad, 1);
    double e[100];
    size_t got = 0;
    ok(flt_recording_read_rows(rd, 0, 100, FIBERS, e, NULL, NULL, NULL, NULL, &got));
    assert_int_equal(got, 100);
    assert_error(flt_recording_read_rows(rd, 300, 100, FIBERS, e, NULL, NULL, NULL, NULL, &got),
                 FLT_ERR_FORMAT, "CRC");
    ok(flt_recording_read_rows(rd, 400, 100, FIBERS, e, NULL, NULL, NULL, NULL, &got));
    assert_true(e[0] == 400.5);
    flt_recording_destroy(rd);
}

/* A writer that cannot write (another program holds the file's write lock
 * past SQLite's 5 s busy wait) fails; every row it did not store is counted
 * and later calls say why. The first block is given alone and the writer
 * given time to take it, so that the next blocks wait in the queue while
 * it waits for the lock: those queued rows are lost too and must be
 * counted (they once were neither stored nor counted). */
static void test_writer_failure_counts_rows(void **state) {
    (void)state;
    char path[600];
    path_in_dir(path, sizeof path, "locked.flrec");
    flt_calib *calib = reference_calib();
    flt_options *o = NULL;
    ok(flt_options_create(&o));
    ok(flt_options_set(o, FLT_OPT_RECORD_BLOCK_ROWS, 16));
    ok(flt_options_set(o, FLT_OPT_RECORD_QUEUE_BLOCKS, 2));
    flt_recorder *rec = NULL;
    ok(flt_recorder_create(path, calib, o, &rec));
    flt_options_destroy(o);
    sqlite3 *db = NULL;
    assert_int_equal(sqlite3_open(path, &db), SQLITE_OK);
    assert_int_equal(sqlite3_exec(db, "BEGIN IMMEDIATE", NULL, NULL, NULL), SQLITE_OK);
    double h[FIBERS], s[FIBERS];
    uint8_t v[FIBERS];
    const unsigned rows = 200;
    for (unsigned r = 0; r < rows; ++r) {
        if (r == 16)
            pause_ms(300); /* the writer takes block 0 and waits for the lock */
        make_row(r, h, s, v);
        flt_status st = flt_recorder_push_row(rec, (double)r, FIBERS, h, s, v);
        assert_true(st == FLT_OK || st == FLT_ERR_IO);
    }
    flt_status st = flt_recorder_sync(rec, 20000);
    assert_error(st, FLT_ERR_IO, "stopped writing");
    sqlite3_exec(db, "ROLLBACK", NULL, NULL, NULL);
    sqlite3_close(db);
    uint64_t given = 0, stored = 0, lost = 0;
    ok(flt_recorder_count(rec, FLT_RECORDER_COUNT_ROWS, &given));
    ok(flt_recorder_count(rec, FLT_RECORDER_COUNT_ROWS_STORED, &stored));
    ok(flt_recorder_count(rec, FLT_RECORDER_COUNT_ROWS_LOST, &lost));
    /* Every row pushed while the recorder still took rows is either stored
     * or counted lost: none vanished. */
    assert_true(given >= 1);
    assert_int_equal(stored, 0);
    assert_int_equal(given, lost);
    print_message("locked file: %llu rows given, %llu lost, 0 stored\n", (unsigned long long)given,
                  (unsigned long long)lost);
    flt_recorder_destroy(rec);
    flt_calib_destroy(calib);
}

/* A recording replays as a source: one frame per row, with its encoder
 * position, its row and the events recorded before it, in order; the
 * events after the last row come with one frame more. */
static void test_source_replays_rows(void **state) {
    (void)state;
    char path[600];
    path_in_dir(path, sizeof path, "replay.flrec");
    write_recording(path, NULL, 900);
    flt_source *src = NULL;
    flt_options *o = NULL;
    ok(flt_options_create(&o));
    ok(flt_options_set(o, FLT_OPT_SOURCE_ENCODER_MODE, FLT_ENCODER_FIXED_STEP));
    assert_error(flt_source_open_recording(path, o, &src), FLT_ERR_INVALID_ARGUMENT, "auto");
    flt_options_destroy(o);
    ok(flt_source_open_recording(path, NULL, &src));
    flt_source_kind kind;
    ok(flt_source_kind_of(src, &kind));
    assert_int_equal(kind, FLT_SOURCE_RECORDING);
    ok(flt_source_start(src));
    flt_recording *rd = NULL;
    ok(flt_recording_open(path, &rd));
    static double eh[900 * FIBERS];
    size_t got = 0;
    ok(flt_recording_read_rows(rd, 0, 900, FIBERS, NULL, NULL, eh, NULL, NULL, &got));
    flt_recording_destroy(rd);
    unsigned frames = 0, cuts = 0, coils = 0;
    for (;;) {
        const flt_frame *f = NULL;
        ok(flt_source_next(src, 0, &f));
        if (!f)
            break;
        double e = 0, h[FIBERS];
        uint64_t block = 0;
        const void *pixels = (const void *)1;
        uint32_t w = 9;
        ok(flt_frame_info(f, &pixels, &w, NULL, NULL, NULL, &block, NULL, &e));
        assert_null(pixels); /* rows only: no camera frames were kept */
        assert_int_equal(w, 0);
        size_t events = 0;
        ok(flt_frame_event_count(f, &events));
        for (size_t i = 0; i < events; ++i) {
            flt_recorded_event k;
            double at = 0;
            const flt_coil_info *coil = NULL;
            ok(flt_frame_event(f, i, &k, &at, NULL, &coil));
            if (k == FLT_RECORDED_CUT) {
                ++cuts;
                assert_int_equal(block, 700); /* recorded before row 700 */
                assert_true(at == 750.0);
            } else if (k == FLT_RECORDED_COIL) {
                ++coils;
                assert_int_equal(block, 0);
                const char *id = NULL, *v = NULL;
                ok(flt_coil_info_get_text(coil, FLT_COIL_FIELD_ID, &id));
                assert_string_equal(id, "4711");
                ok(flt_coil_info_find_extra(coil, "line", &v));
                assert_string_equal(v, "CTL 2 \"Süd\"");
                assert_int_equal(
                    flt_coil_info_set_text((flt_coil_info *)coil, FLT_COIL_FIELD_HEAT, "x"),
                    FLT_ERR_STATE); /* lent: read-only */
            }
        }
        assert_error(flt_frame_event(f, events, NULL, NULL, NULL, NULL), FLT_ERR_NOT_FOUND,
                     "index");
        assert_true(e == (double)frames + 0.5);
        assert_int_equal(block, frames);
        ok(flt_frame_row(f, FIBERS, h, NULL, NULL));
        for (unsigned k = 0; k < FIBERS; ++k) {
            const double want = eh[(size_t)frames * FIBERS + k];
            assert_true(h[k] == want || (isnan(h[k]) && isnan(want)));
        }
        ++frames;
    }
    assert_int_equal(frames, 900);
    assert_int_equal(cuts, 1);
    assert_int_equal(coils, 1);
    /* Started again: the first row again. */
    ok(flt_source_stop(src));
    ok(flt_source_start(src));
    const flt_frame *f = NULL;
    ok(flt_source_next(src, 0, &f));
    double e = -1;
    ok(flt_frame_info(f, NULL, NULL, NULL, NULL, NULL, NULL, NULL, &e));
    assert_true(e == 0.5);
    flt_source_destroy(src);
}

static void test_coil_info(void **state) {
    (void)state;
    flt_coil_info *c = NULL;
    assert_error(flt_coil_info_create("", &c), FLT_ERR_INVALID_ARGUMENT, "empty");
    assert_error(flt_coil_info_create("a\nb", &c), FLT_ERR_INVALID_ARGUMENT, "control");
    assert_error(flt_coil_info_create("\xC3\x28", &c), FLT_ERR_INVALID_ARGUMENT, "UTF-8");
    ok(flt_coil_info_create("C-4711/Süd", &c));
    const char *t = NULL;
    ok(flt_coil_info_get_text(c, FLT_COIL_FIELD_ID, &t));
    assert_string_equal(t, "C-4711/Süd");
    ok(flt_coil_info_get_text(c, FLT_COIL_FIELD_HEAT, &t));
    assert_string_equal(t, "");
    ok(flt_coil_info_set_text(c, FLT_COIL_FIELD_HEAT, "H 88123"));
    assert_error(flt_coil_info_set_text(c, FLT_COIL_FIELD_ID, ""), FLT_ERR_INVALID_ARGUMENT,
                 "empty");
    assert_error(flt_coil_info_set_text(c, (flt_coil_field)9, "x"), FLT_ERR_INVALID_ARGUMENT,
                 "field");
    char longer[FLT_COIL_TEXT_MAX + 2];
    memset(longer, 'x', sizeof longer - 1);
    longer[sizeof longer - 1] = 0;
    assert_error(flt_coil_info_set_text(c, FLT_COIL_FIELD_ORDER, longer), FLT_ERR_INVALID_ARGUMENT,
                 "257 bytes");
    assert_error(flt_coil_info_set_nominal(c, NAN, 0), FLT_ERR_INVALID_ARGUMENT, "thickness");
    assert_error(flt_coil_info_set_nominal(c, 4, -1), FLT_ERR_INVALID_ARGUMENT, "width");
    assert_error(flt_coil_info_set_nominal(c, 1001, 0), FLT_ERR_INVALID_ARGUMENT, "thickness");
    ok(flt_coil_info_set_nominal(c, 2.5, 0));
    double th = 0, w = 1;
    ok(flt_coil_info_get_nominal(c, &th, &w));
    assert_true(th == 2.5 && w == 0);
    assert_error(flt_coil_info_set_extra(c, "bad key", "x"), FLT_ERR_INVALID_ARGUMENT, "key");
    ok(flt_coil_info_set_extra(c, "shift", "B"));
    ok(flt_coil_info_set_extra(c, "line", "2"));
    ok(flt_coil_info_set_extra(c, "shift", "C")); /* replaced, keeps its place */
    size_t n = 0;
    ok(flt_coil_info_extra_count(c, &n));
    assert_int_equal(n, 2);
    const char *k = NULL, *v = NULL;
    ok(flt_coil_info_extra(c, 0, &k, &v));
    assert_string_equal(k, "shift");
    assert_string_equal(v, "C");
    assert_error(flt_coil_info_extra(c, 2, &k, &v), FLT_ERR_NOT_FOUND, "index");
    ok(flt_coil_info_find_extra(c, "line", &v));
    assert_string_equal(v, "2");
    ok(flt_coil_info_set_extra(c, "line", NULL));
    assert_error(flt_coil_info_find_extra(c, "line", &v), FLT_ERR_NOT_FOUND, "line");
    char key[16];
    for (int i = 1; i < FLT_COIL_EXTRA_MAX; ++i) {
        snprintf(key, sizeof key, "k%d", i);
        ok(flt_coil_info_set_extra(c, key, "v"));
    }
    assert_error(flt_coil_info_set_extra(c, "one_more", "v"), FLT_ERR_BUFFER_FULL, "64");
    flt_coil_info *copy = NULL;
    ok(flt_coil_info_copy(c, &copy));
    ok(flt_coil_info_get_text(copy, FLT_COIL_FIELD_HEAT, &t));
    assert_string_equal(t, "H 88123");
    flt_coil_info_destroy(copy);
    flt_coil_info_destroy(c);
    flt_coil_info_destroy(NULL);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_refuses_existing_file),
        cmocka_unit_test(test_damaged_block),
        cmocka_unit_test(test_writer_failure_counts_rows),
        cmocka_unit_test(test_source_replays_rows),
        cmocka_unit_test(test_coil_info),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
