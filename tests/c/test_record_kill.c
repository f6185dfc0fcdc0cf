// SPDX-License-Identifier: Apache-2.0
/*
 * A recording survives its writer's death. A child process records rows of
 * the README's line (1,150 fibers at 2,000 rows/s, paced by the clock)
 * and is killed (no destructor, no flush) at a random moment, 20 times.
 * Every file must open, every block's CRC must verify, the rows must be
 * there without a hole from the first, decode to what was pushed, and
 * every row the child had pushed up to 1 s before the kill must be stored
 * (the recorder commits every 250 ms by default: a row waits at most one
 * block's 250 ms and one commit interval, so 1 s holds with room for a
 * slow disk). The child tells the parent, through shared memory, how many
 * rows it had pushed at which time, so the test knows what "up to 1 s
 * before" means even when the child was slowed down.
 *
 * POSIX: the child is a fork, killed with SIGKILL; the shared memory an
 * anonymous shared mapping. Windows: the child is this program started
 * again (CreateProcess, "--child FILE MAPPING"), killed with
 * TerminateProcess; the shared memory a named file mapping.
 */
#ifndef _WIN32
#  define _GNU_SOURCE
#endif
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifdef _WIN32
#  ifndef WIN32_LEAN_AND_MEAN
#    define WIN32_LEAN_AND_MEAN
#  endif
#  include <windows.h>
#else
#  include <signal.h>
#  include <sys/mman.h>
#  include <sys/wait.h>
#  include <unistd.h>
#endif

#include <cmocka.h>

#include "flatline/flatline.h"
#include "test_files.h"

#define ok(call) assert_int_equal((call), FLT_OK)

enum { FIBERS = 1150, RATE = 2000, BATCH = 20, KILLS = 20, MAX_BATCHES = 4096 };

/* What the child pushed: after each batch, the rows so far and the time. */
typedef struct progress {
    volatile int64_t ready_ns;
    volatile int32_t batches;
    volatile int64_t rows[MAX_BATCHES];
    volatile int64_t time_ns[MAX_BATCHES];
    char path[600]; /* the file the child records to (UTF-8) */
} progress;

/* The exit code of a child the test killed on Windows (128 + SIGKILL, as a
 * POSIX shell reports it): the child itself only ever exits 3 or 4. */
#define KILLED_EXIT_CODE 137u

#ifdef _WIN32
static int64_t utc_ns(void) {
    /* 100 ns ticks since 1601-01-01 to ns since 1970-01-01, the clock
     * the recorder stamps rows with. */
    FILETIME ft;
    GetSystemTimePreciseAsFileTime(&ft);
    const int64_t ticks = (int64_t)(((uint64_t)ft.dwHighDateTime << 32) | ft.dwLowDateTime);
    return (ticks - INT64_C(116444736000000000)) * 100;
}

static void sleep_ns(int64_t ns) {
    Sleep((DWORD)((ns + 999999) / 1000000));
}

static void memory_barrier(void) {
    MemoryBarrier();
}

static void exit_child(int code) {
    ExitProcess((UINT)code);
}
#else
static int64_t utc_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_REALTIME, &t);
    return (int64_t)t.tv_sec * 1000000000 + t.tv_nsec;
}

static void sleep_ns(int64_t ns) {
    struct timespec d = {(time_t)(ns / 1000000000), (long)(ns % 1000000000)};
    nanosleep(&d, NULL);
}

static void memory_barrier(void) {
    __sync_synchronize();
}

static void exit_child(int code) {
    _exit(code);
}
#endif

static double value(unsigned r, unsigned k, unsigned which) {
    uint32_t x = r * 2654435761u ^ (k + 1) * 40503u ^ (which + 7) * 97u;
    x ^= x >> 13;
    x *= 0x5bd1e995u;
    x ^= x >> 15;
    const double n = (double)(x & 0xFFFF) / 65536.0 - 0.5;
    return which == 0 ? 2.0 * sin(0.002 * r + 0.01 * k) + 0.1 * n : 0.001 * n;
}

static void child(progress *p) {
    flt_calib *calib = NULL;
    flt_recorder *rec = NULL;
    if (flt_calib_create_reference(892, 256, -1000.0, 2000.0 / (FIBERS - 1), FIBERS, &calib) ||
        flt_recorder_create(p->path, calib, NULL, &rec))
        exit_child(3);
    static double h[FIBERS], s[FIBERS];
    const int64_t t0 = utc_ns();
    p->ready_ns = t0;
    for (unsigned r = 0;; ++r) {
        if (r % BATCH == 0) {
            const int64_t due = t0 + (int64_t)r * 1000000000 / RATE, left = due - utc_ns();
            if (left > 0)
                sleep_ns(left);
        }
        for (unsigned k = 0; k < FIBERS; ++k) {
            h[k] = value(r, k, 0);
            s[k] = value(r, k, 1);
        }
        if (flt_recorder_push_row(rec, (double)r, FIBERS, h, s, NULL))
            exit_child(4);
        if ((r + 1) % BATCH == 0 && p->batches < MAX_BATCHES) {
            const int32_t b = p->batches;
            p->rows[b] = r + 1;
            p->time_ns[b] = utc_ns();
            memory_barrier();
            p->batches = b + 1;
        }
    }
}

/* The child process and the memory it shares with the parent. */
#ifdef _WIN32
static char mapping_name[64];
static HANDLE mapping;

static progress *shared_progress(void) {
    snprintf(mapping_name, sizeof mapping_name, "Local\\flt_record_kill_%lu",
             (unsigned long)GetCurrentProcessId());
    mapping = CreateFileMappingA(INVALID_HANDLE_VALUE, NULL, PAGE_READWRITE, 0,
                                 (DWORD)sizeof(progress), mapping_name);
    if (!mapping)
        return NULL;
    return MapViewOfFile(mapping, FILE_MAP_ALL_ACCESS, 0, 0, sizeof(progress));
}

static void release_progress(progress *p) {
    UnmapViewOfFile(p);
    CloseHandle(mapping);
}

typedef HANDLE writer;

/* This program again, as "--child MAPPING": main() sends it to child(). */
static writer start_writer(progress *p) {
    (void)p;
    wchar_t exe[MAX_PATH], line[MAX_PATH + 128];
    const DWORD n = GetModuleFileNameW(NULL, exe, MAX_PATH);
    assert_true(n > 0 && n < MAX_PATH);
    _snwprintf(line, sizeof line / sizeof *line, L"\"%ls\" --child %hs", exe, mapping_name);
    STARTUPINFOW si;
    PROCESS_INFORMATION pi;
    memset(&si, 0, sizeof si);
    si.cb = sizeof si;
    if (!CreateProcessW(exe, line, NULL, NULL, FALSE, 0, NULL, NULL, &si, &pi))
        fail_msg("CreateProcessW failed (error %lu)", (unsigned long)GetLastError());
    CloseHandle(pi.hThread);
    return pi.hProcess;
}

/* 1 (and its exit code) when the child has ended by itself. */
static int writer_ended(writer w, int *code) {
    if (WaitForSingleObject(w, 0) != WAIT_OBJECT_0)
        return 0;
    DWORD c = 0;
    GetExitCodeProcess(w, &c);
    *code = (int)c;
    return 1;
}

static void kill_writer(writer w) {
    assert_true(TerminateProcess(w, KILLED_EXIT_CODE));
    assert_int_equal(WaitForSingleObject(w, INFINITE), WAIT_OBJECT_0);
    DWORD code = 0;
    assert_true(GetExitCodeProcess(w, &code));
    assert_int_equal(code, KILLED_EXIT_CODE);
    CloseHandle(w);
}

static int run_child(int argc, char **argv) {
    if (argc != 3 || strcmp(argv[1], "--child") != 0)
        return 0;
    HANDLE m = OpenFileMappingA(FILE_MAP_ALL_ACCESS, FALSE, argv[2]);
    progress *p = m ? MapViewOfFile(m, FILE_MAP_ALL_ACCESS, 0, 0, sizeof(progress)) : NULL;
    if (!p)
        exit_child(5);
    child(p);
    return 1;
}
#else
static progress *shared_progress(void) {
    progress *p = mmap(NULL, sizeof *p, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    return p == MAP_FAILED ? NULL : p;
}

static void release_progress(progress *p) {
    munmap(p, sizeof *p);
}

typedef pid_t writer;

static writer start_writer(progress *p) {
    const pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0)
        child(p);
    return pid;
}

static int writer_ended(writer w, int *code) {
    return waitpid(w, code, WNOHANG) == w;
}

static void kill_writer(writer w) {
    kill(w, SIGKILL);
    int status = 0;
    waitpid(w, &status, 0);
    assert_true(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
}

static int run_child(int argc, char **argv) {
    (void)argc;
    (void)argv;
    return 0;
}
#endif

static void test_killed_writer(void **state) {
    (void)state;
    char dir[512];
    assert_int_equal(tf_temp_dir(dir, sizeof dir, "record_kill"), 0);
    progress *p = shared_progress();
    assert_non_null(p);
    srand((unsigned)time(NULL));
    double worst_margin = 1e9, worst_lag = 0;
    for (int kill_no = 0; kill_no < KILLS; ++kill_no) {
        char path[600];
        memset(p, 0, sizeof *p);
        snprintf(path, sizeof path, "%s/killed_%02d.flrec", dir, kill_no);
        snprintf(p->path, sizeof p->path, "%s", path);
        const writer w = start_writer(p);
        while (p->ready_ns == 0) {
            int status = 0;
            if (writer_ended(w, &status))
                fail_msg("the child ended before it recorded (status %d)", status);
            sleep_ns(1000000);
        }
        /* A random moment 0.2 .. 2.2 s after the first row. */
        const double delay = 0.2 + 2.0 * (double)rand() / RAND_MAX;
        sleep_ns((int64_t)(delay * 1e9));
        const int64_t kill_ns = utc_ns();
        kill_writer(w);

        /* What the child had pushed up to 1 s before the kill. */
        int64_t required = 0, pushed = 0;
        for (int32_t b = 0; b < p->batches; ++b) {
            pushed = p->rows[b];
            if (p->time_ns[b] <= kill_ns - 1000000000)
                required = p->rows[b];
        }

        flt_recording *rd = NULL;
        ok(flt_recording_open(path, &rd));
        uint64_t bad = 1;
        ok(flt_recording_verify(rd, &bad));
        assert_int_equal(bad, 0);
        double rows = 0, lost = 0;
        ok(flt_recording_info(rd, FLT_RECORDING_ROWS, &rows));
        ok(flt_recording_info(rd, FLT_RECORDING_ROWS_LOST, &lost));
        assert_true(lost == 0);
        if (rows < (double)required)
            fail_msg("kill %d at %.2f s: %.0f rows stored, but %lld were pushed 1 s before",
                     kill_no, delay, rows, (long long)required);
        assert_true(rows <= (double)pushed + BATCH);
        /* Rows from the first without a hole, as pushed: the encoder
         * position is the row's number; the last row's heights decode to
         * the pushed ones within half a quantum per laser. */
        const size_t n = (size_t)rows;
        double *e = malloc(sizeof(double) * (n + 1)), *t = malloc(sizeof(double) * (n + 1));
        static double h[FIBERS];
        size_t got = 0;
        ok(flt_recording_read_rows(rd, 0, n, FIBERS, e, t, NULL, NULL, NULL, &got));
        assert_int_equal(got, n);
        for (size_t i = 0; i < n; ++i)
            assert_true(e[i] == (double)i);
        if (n > 0) {
            ok(flt_recording_read_rows(rd, n - 1, 1, FIBERS, NULL, NULL, h, NULL, NULL, &got));
            for (unsigned k = 0; k < FIBERS; ++k)
                assert_true(fabs(h[k] - value((unsigned)(n - 1), k, 0)) <= 1.0 / 512 + 1e-9);
            /* How far behind the kill the last stored row was. */
            const double lag = 1e-9 * (double)kill_ns - t[n - 1];
            worst_lag = fmax(worst_lag, lag);
        }
        /* The margin to the 1 s promise: rows stored beyond those required. */
        worst_margin = fmin(worst_margin, (rows - (double)required) / RATE);
        free(e);
        free(t);
        flt_recording_destroy(rd);
        print_message("kill %2d after %.2f s: %6.0f rows stored, %6lld pushed, %6lld required\n",
                      kill_no, delay, rows, (long long)pushed, (long long)required);
    }
    print_message("%d kills: every file opened and verified; the last stored row was at most "
                  "%.3f s older than the kill (promise: 1 s); at least %.3f s of rows were "
                  "stored beyond those pushed 1 s before the kill\n",
                  KILLS, worst_lag, worst_margin);
    assert_true(worst_lag < 1.0);
    release_progress(p);
    tf_remove_tree(dir);
}

int main(int argc, char **argv) {
    if (run_child(argc, argv))
        return 0;
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_killed_writer)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
