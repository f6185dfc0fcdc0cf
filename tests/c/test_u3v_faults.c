// SPDX-License-Identifier: Apache-2.0
/*
 * Control-channel and host faults at every step of flt_source_start() and
 * flt_source_stop(), with the camera's real state read from outside after
 * each call (flatline/testing.h: flt_u3v_sim_peek / flt_u3v_sim_get), not
 * what the host believes. The promises checked:
 *   - start returned FLT_OK  => SI control 1 and acquisition running, and
 *     frames arrive;
 *   - start failed           => the camera is stopped (SI control 0, no
 *     acquisition), unless the message says it may still be streaming;
 *   - stop returned FLT_OK   => SI control 0 and no acquisition;
 *   - stop failed            => the message says the camera may still be
 *     streaming;
 *   - whatever happened, once the faults are used up, stop and start work
 *     again (a camera left streaming is recovered, never "access denied"),
 *     and an unplugged camera gives FLT_ERR_DEVICE.
 * A case = one fault (kind and count) hitting one step: the n-th GenCP
 * command (or bulk submission) of the call, for every n the call sends and
 * one beyond. Every number asserted is a register or a status: exact.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "flatline/flatline.h"
#include "flatline/source.h"
#include "flatline/testing.h"

#define ok(call)                                           \
  do {                                                     \
    flt_status st_ = (call);                               \
    if (st_ != FLT_OK)                                     \
      fail_msg("%s: %s", #call, flt_last_error_message()); \
  } while (0)

enum { SIRM_CONTROL = 0x2004, MAX_CALLS = 12 };

typedef struct fault_spec {
    flt_u3v_fault fault;
    uint32_t count;
    const char *name;
} fault_spec;

/* Default options: 3 attempts per command, 5 pending acks allowed, 8
 * transfers. Counts below, at and beyond those limits. */
static const fault_spec k_faults[] = {
    {FLT_U3V_FAULT_PENDING_ACK, 2, "2 pending acks"},
    {FLT_U3V_FAULT_PENDING_ACK, 6, "6 pending acks (limit 5)"},
    {FLT_U3V_FAULT_CONTROL_TIMEOUT, 1, "1 command lost"},
    {FLT_U3V_FAULT_CONTROL_TIMEOUT, 3, "3 commands lost (all attempts)"},
    {FLT_U3V_FAULT_CONTROL_TIMEOUT, 9, "9 commands lost (all rounds)"},
    {FLT_U3V_FAULT_LOST_ACK, 1, "1 ack lost"},
    {FLT_U3V_FAULT_LOST_ACK, 3, "3 acks lost"},
    {FLT_U3V_FAULT_LOST_ACK, 9, "9 acks lost"},
    {FLT_U3V_FAULT_LATE_ACK, 1, "a late ack"},
    {FLT_U3V_FAULT_BUSY, 1, "1 busy answer"},
    {FLT_U3V_FAULT_BUSY, 3, "3 busy answers"},
    {FLT_U3V_FAULT_BUSY, 9, "9 busy answers"},
    {FLT_U3V_FAULT_CONTROL_UNPLUG, 1, "unplugged"},
    {FLT_U3V_FAULT_SUBMIT_REFUSED, 1, "1 submit refused"},
    {FLT_U3V_FAULT_SUBMIT_REFUSED, 8, "8 submits refused (all)"},
};
#define N_FAULTS (sizeof k_faults / sizeof k_faults[0])

typedef struct tally {
    int cases, calls, start_failed, stop_failed, may_stream;
} tally;

static flt_u3v_sim *g_bus;
static flt_source *g_src;

/* The outcome of the last start or stop, kept before the next call into the
 * libraries (which clears the thread's error). */
static flt_status g_status;
static flt_status g_last_status;
static char g_message[512];

static flt_status keep(flt_status st) {
    g_status = st;
    g_last_status = flt_last_error_status();
    snprintf(g_message, sizeof g_message, "%s", flt_last_error_message());
    return st;
}

static uint64_t sim_get(flt_u3v_sim_param p) {
    uint64_t v = 0;
    ok(flt_u3v_sim_get(g_bus, 0, p, &v));
    return v;
}

static uint32_t si_control(void) {
    uint32_t v = 0;
    ok(flt_u3v_sim_peek(g_bus, 0, SIRM_CONTROL, &v));
    return v;
}

static void open_camera(void) {
    flt_usb_transport *usb = NULL;
    ok(flt_u3v_sim_create(&g_bus));
    ok(flt_u3v_sim_add_camera(g_bus, "Flatline", "Faults", "F1", 64, 32, FLT_PIXEL_MONO8, NULL));
    ok(flt_u3v_sim_transport(g_bus, &usb));
    ok(flt_source_open_u3v(usb, "F1", NULL, &g_src));
}

static void close_camera(void) {
    flt_source_destroy(g_src);
    flt_u3v_sim_destroy(g_bus);
    g_src = NULL;
    g_bus = NULL;
}

/* The camera as the last call left it, or a failure naming the case. */
static void expect_streaming(const char *what) {
    if (si_control() != 1 || sim_get(FLT_U3V_SIM_ACQUIRING) != 1)
        fail_msg("%s: start returned FLT_OK, but SI control = %u, acquiring = %llu", what,
                 si_control(), (unsigned long long)sim_get(FLT_U3V_SIM_ACQUIRING));
    const flt_frame *f = NULL;
    uint64_t block = 0;
    flt_status st = flt_source_next(g_src, 100, &f);
    if (st != FLT_OK)
        fail_msg("%s: no frame after a successful start: %s", what, flt_last_error_message());
    ok(flt_frame_info(f, NULL, NULL, NULL, NULL, NULL, &block, NULL, NULL));
    assert_true(block >= 1);
}

static void expect_stopped(const char *what, const char *call) {
    if (si_control() != 0 || sim_get(FLT_U3V_SIM_ACQUIRING) != 0)
        fail_msg("%s: %s, but SI control = %u, acquiring = %llu (last message: %s)", what, call,
                 si_control(), (unsigned long long)sim_get(FLT_U3V_SIM_ACQUIRING), g_message);
}

static int may_still_stream(void) {
    return strstr(g_message, "may still be streaming") != NULL;
}

/* A failed start or stop: a status, a message, never the camera refusing a
 * stream set-up because it was left streaming. */
static void check_failure(const char *what, flt_status st, tally *t) {
    if (st == FLT_OK || g_message[0] == 0 || g_last_status != st)
        fail_msg("%s: a failure without its status or message ('%s')", what, g_message);
    if (strstr(g_message, "0x8006"))
        fail_msg("%s: the camera refused access (left streaming?): %s", what, g_message);
    t->may_stream += may_still_stream();
}

static flt_status start(tally *t) {
    ++t->calls;
    return keep(flt_source_start(g_src));
}
static flt_status stop(tally *t) {
    ++t->calls;
    return keep(flt_source_stop(g_src));
}

/* After the case's call: start (and stop) again until they succeed, the
 * faults being used up; the camera's state checked after each call. */
/* An unplugged camera: stop is done on the host side, start says why not. */
static void gone(const char *what, tally *t) {
    assert_int_equal(stop(t), FLT_OK);
    flt_status st = start(t);
    if (st != FLT_ERR_DEVICE || !strstr(g_message, "unplugged"))
        fail_msg("%s: start after an unplug gave %s: %s", what, flt_status_string(st), g_message);
}

static void recover(const char *what, tally *t) {
    int started = 0;
    for (int call = 0; call < MAX_CALLS && !started; ++call) {
        if (sim_get(FLT_U3V_SIM_UNPLUGGED))
            return gone(what, t);
        flt_status st = start(t);
        if (sim_get(FLT_U3V_SIM_UNPLUGGED))
            return gone(what, t);
        if (st == FLT_ERR_STATE) { /* still started from the case's call */
            ++call;
            st = stop(t);
            if (sim_get(FLT_U3V_SIM_UNPLUGGED))
                return gone(what, t);
            if (st == FLT_OK)
                expect_stopped(what, "stop returned FLT_OK");
            else
                check_failure(what, st, t);
            continue;
        }
        if (st == FLT_OK) {
            expect_streaming(what);
            started = 1;
        } else {
            check_failure(what, st, t);
            if (!may_still_stream())
                expect_stopped(what, "start failed saying nothing streams");
        }
    }
    if (!started)
        fail_msg("%s: start still fails after %d calls: %s", what, MAX_CALLS, g_message);
    for (int call = 0;; ++call) {
        flt_status st = stop(t);
        if (sim_get(FLT_U3V_SIM_UNPLUGGED))
            return gone(what, t);
        if (st == FLT_OK)
            break;
        check_failure(what, st, t);
        if (call == MAX_CALLS)
            fail_msg("%s: stop still fails after %d calls: %s", what, MAX_CALLS, g_message);
    }
    expect_stopped(what, "stop returned FLT_OK");
    if (sim_get(FLT_U3V_SIM_FAULTS_PENDING) != 0)
        fail_msg("%s: %llu faults still pending after recovery", what,
                 (unsigned long long)sim_get(FLT_U3V_SIM_FAULTS_PENDING));
}

/* Commands a clean start (stop) sends, and bulk submissions of a start. */
static void measure(uint64_t *start_commands, uint64_t *stop_commands) {
    open_camera();
    uint64_t before = sim_get(FLT_U3V_SIM_COMMANDS);
    ok(flt_source_start(g_src));
    *start_commands = sim_get(FLT_U3V_SIM_COMMANDS) - before;
    before = sim_get(FLT_U3V_SIM_COMMANDS);
    ok(flt_source_stop(g_src));
    *stop_commands = sim_get(FLT_U3V_SIM_COMMANDS) - before;
    close_camera();
}

static void test_every_fault_at_every_step_of_start(void **state) {
    (void)state;
    uint64_t n_start = 0, n_stop = 0;
    measure(&n_start, &n_stop);
    /* SI control read, AcquisitionMode, Width, Height, PixelFormat, SIRM
     * read, 6 SIRM writes, SI control = 1, AcquisitionStart */
    assert_int_equal(n_start, 14);
    tally t = {0};
    for (size_t k = 0; k < N_FAULTS; ++k) {
        const fault_spec *fs = &k_faults[k];
        const int submits = fs->fault == FLT_U3V_FAULT_SUBMIT_REFUSED;
        /* each step of the call, and the first one after it */
        const uint64_t steps = submits ? 8 + 1 : n_start + 1;
        for (uint64_t step = 0; step < steps; ++step) {
            char what[160];
            snprintf(what, sizeof what, "start, %s at %s %llu", fs->name,
                     submits ? "submission" : "command", (unsigned long long)step);
            open_camera();
            ++t.cases;
            ok(flt_u3v_sim_inject(g_bus, 0, fs->fault, step, fs->count));
            flt_status st = start(&t);
            if (st == FLT_OK) {
                if (!sim_get(FLT_U3V_SIM_UNPLUGGED))
                    expect_streaming(what);
            } else {
                ++t.start_failed;
                check_failure(what, st, &t);
                if (!may_still_stream() && !sim_get(FLT_U3V_SIM_UNPLUGGED))
                    expect_stopped(what, "start failed saying nothing streams");
            }
            recover(what, &t);
            close_camera();
        }
    }
    printf("start: %d cases (%zu faults x every step), %d calls; start failed in %d, "
           "%d failures said the camera may still stream; every camera recovered\n",
           t.cases, N_FAULTS, t.calls, t.start_failed, t.may_stream);
}

static void test_every_fault_at_every_step_of_stop(void **state) {
    (void)state;
    uint64_t n_start = 0, n_stop = 0;
    measure(&n_start, &n_stop);
    /* AcquisitionStop, SI control = 0, SI control read back */
    assert_int_equal(n_stop, 3);
    tally t = {0};
    for (size_t k = 0; k < N_FAULTS; ++k) {
        const fault_spec *fs = &k_faults[k];
        if (fs->fault == FLT_U3V_FAULT_SUBMIT_REFUSED)
            continue; /* stop submits nothing */
        for (uint64_t step = 0; step < n_stop + 1; ++step) {
            char what[160];
            snprintf(what, sizeof what, "stop, %s at command %llu", fs->name,
                     (unsigned long long)step);
            open_camera();
            ++t.cases;
            ok(flt_source_start(g_src));
            expect_streaming(what);
            ok(flt_u3v_sim_inject(g_bus, 0, fs->fault, step, fs->count));
            flt_status st = stop(&t);
            if (st == FLT_OK) {
                if (!sim_get(FLT_U3V_SIM_UNPLUGGED))
                    expect_stopped(what, "stop returned FLT_OK");
            } else {
                ++t.stop_failed;
                check_failure(what, st, &t);
                if (!may_still_stream())
                    fail_msg("%s: stop failed without saying the camera may stream: %s", what,
                             g_message);
                /* stopped on the host side whatever the camera answered */
                const flt_frame *f = NULL;
                assert_int_equal(flt_source_next(g_src, 10, &f), FLT_ERR_STATE);
            }
            recover(what, &t);
            close_camera();
        }
    }
    printf("stop: %d cases (%zu faults x every step), %d calls; stop failed in %d, "
           "%d failures said the camera may still stream; every camera recovered\n",
           t.cases, N_FAULTS - 1, t.calls, t.stop_failed, t.may_stream);
}

/* The field report: after control faults a stop returned FLT_OK with the
 * camera still streaming, and every later start failed with "access
 * denied". One such sequence, step by step. */
static void test_stop_after_lost_stop_commands_reports_and_start_recovers(void **state) {
    (void)state;
    tally t = {0};
    open_camera();
    ok(flt_source_start(g_src));
    expect_streaming("start");
    /* every AcquisitionStop and SI control write of the stop is lost */
    ok(flt_u3v_sim_inject(g_bus, 0, FLT_U3V_FAULT_CONTROL_TIMEOUT, 0, 100));
    flt_status st = stop(&t);
    assert_int_equal(st, FLT_ERR_TIMEOUT);
    assert_true(may_still_stream());
    assert_int_equal(si_control(), 1); /* the camera really streams on */
    assert_int_equal(sim_get(FLT_U3V_SIM_ACQUIRING), 1);
    /* a stop while the faults last fails again, and says so */
    st = stop(&t);
    assert_int_equal(st, FLT_ERR_TIMEOUT);
    assert_true(may_still_stream());
    /* the faults end: the next start stops the camera first, then starts */
    while (sim_get(FLT_U3V_SIM_FAULTS_PENDING) != 0) {
        uint8_t b[4];
        if (flt_source_read_memory(g_src, 0x10000, b, 4) == FLT_OK) /* uses them up */
            break;
    }
    uint64_t recoveries = 0;
    ok(flt_source_start(g_src));
    ok(flt_source_count(g_src, FLT_COUNT_STREAM_RECOVERIES, &recoveries));
    assert_int_equal(recoveries, 1);
    expect_streaming("start after the faults");
    ok(flt_source_stop(g_src));
    expect_stopped("stop", "stop returned FLT_OK");
    /* and a stop of a stopped camera is a no-op again */
    const uint64_t commands = sim_get(FLT_U3V_SIM_COMMANDS);
    ok(flt_source_stop(g_src));
    assert_int_equal(sim_get(FLT_U3V_SIM_COMMANDS), commands);
    close_camera();
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stop_after_lost_stop_commands_reports_and_start_recovers),
        cmocka_unit_test(test_every_fault_at_every_step_of_start),
        cmocka_unit_test(test_every_fault_at_every_step_of_stop),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
