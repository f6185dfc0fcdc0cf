// SPDX-License-Identifier: Apache-2.0
/*
 * libFuzzer harness: a USB3 Vision source driven through random sequences
 * of start / stop / next / feature calls while the simulated camera
 * (flatline/testing.h) injects control-channel faults (pending, lost, late
 * and busy acknowledges, lost commands, an unplug), refused bulk
 * submissions and stream faults. After every call the camera's real state
 * is read from outside (flt_u3v_sim_peek, flt_u3v_sim_get) and checked
 * against what the call returned:
 *   - stop returned FLT_OK   => SI control 0, no acquisition;
 *   - stop failed            => its message says the camera may still be
 *                               streaming;
 *   - start returned FLT_OK  => SI control 1, acquisition running;
 *   - start failed           => the camera is stopped, unless the message
 *                               says it may still be streaming;
 *   - with no fault pending, start (on a stopped source) and stop succeed;
 *   - no start or stop is ever refused with "access denied" (0x8006, the
 *     answer of a camera left streaming);
 *   - every failure has a status and a message.
 * At the end the faults are used up and the source must stop cleanly.
 *
 * Input: byte 0 sets the options (u3v_command_attempts 1..3,
 * u3v_pending_ack_limit 0..5, transfers 2..5); then up to 64 operations,
 * each an opcode byte and its argument bytes (see the switch).
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flatline/flatline.h"
#include "flatline/testing.h"

typedef struct input {
    const uint8_t *p;
    size_t n;
} input;

static uint8_t u8(input *in) {
    if (in->n == 0)
        return 0;
    --in->n;
    return *in->p++;
}

static flt_u3v_sim *g_bus;
static flt_source *g_src;

static void die(const char *why, const char *message) {
    fprintf(stderr, "fuzz_source_faults: %s (last message: '%s')\n", why, message);
    abort();
}

static uint64_t sim(flt_u3v_sim_param p) {
    uint64_t v = 0;
    if (flt_u3v_sim_get(g_bus, 0, p, &v) != FLT_OK)
        die("flt_u3v_sim_get failed", flt_last_error_message());
    return v;
}

static uint32_t si_control(void) {
    uint32_t v = 0;
    if (flt_u3v_sim_peek(g_bus, 0, 0x2004, &v) != FLT_OK)
        die("flt_u3v_sim_peek failed", flt_last_error_message());
    return v;
}

/* The outcome of a call, kept before the next call clears it. */
static char g_message[512];

static flt_status keep(flt_status st) {
    snprintf(g_message, sizeof g_message, "%s", flt_last_error_message());
    if (st != FLT_OK && (g_message[0] == 0 || flt_last_error_status() != st))
        die("a failure without its status or message", g_message);
    return st;
}

static int may_still_stream(void) {
    return strstr(g_message, "may still be streaming") != NULL;
}

static int streaming(void) {
    return si_control() == 1 && sim(FLT_U3V_SIM_ACQUIRING) == 1;
}
static int stopped(void) {
    return si_control() == 0 && sim(FLT_U3V_SIM_ACQUIRING) == 0;
}

static const flt_u3v_fault k_control[] = {FLT_U3V_FAULT_PENDING_ACK, FLT_U3V_FAULT_CONTROL_TIMEOUT,
                                          FLT_U3V_FAULT_LATE_ACK, FLT_U3V_FAULT_LOST_ACK,
                                          FLT_U3V_FAULT_BUSY};
static const flt_u3v_fault k_stream[] = {
    FLT_U3V_FAULT_SHORT_FRAME,    FLT_U3V_FAULT_LEADER_MID_FRAME, FLT_U3V_FAULT_OVERFLOW,
    FLT_U3V_FAULT_SKIP_BLOCK_IDS, FLT_U3V_FAULT_STREAM_TIMEOUT,   FLT_U3V_FAULT_GARBAGE,
    FLT_U3V_FAULT_TRAILER_STATUS};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    input in = {data, size};
    const uint8_t mode = u8(&in);
    flt_options *o = NULL;
    flt_usb_transport *usb = NULL;
    if (flt_options_create(&o) != FLT_OK ||
        flt_options_set(o, FLT_OPT_U3V_COMMAND_ATTEMPTS, 1 + mode % 3) != FLT_OK ||
        flt_options_set(o, FLT_OPT_U3V_PENDING_ACK_LIMIT, (mode >> 2) % 6) != FLT_OK ||
        flt_options_set(o, FLT_OPT_U3V_TRANSFERS, 2 + (mode >> 5) % 4) != FLT_OK ||
        flt_options_set(o, FLT_OPT_U3V_TRANSFER_SIZE, 1024) != FLT_OK ||
        flt_u3v_sim_create(&g_bus) != FLT_OK ||
        flt_u3v_sim_add_camera(g_bus, "Fuzz", "Faults", "F1", 64, 32, FLT_PIXEL_MONO8, NULL) !=
            FLT_OK ||
        flt_u3v_sim_transport(g_bus, &usb) != FLT_OK ||
        flt_source_open_u3v(usb, "F1", o, &g_src) != FLT_OK)
        die("set-up failed", flt_last_error_message());
    flt_options_destroy(o);

    int started = 0; /* as the host sees it */
    for (int op = 0; op < 64 && in.n > 0; ++op) {
        const int unplugged = (int)sim(FLT_U3V_SIM_UNPLUGGED);
        const uint64_t pending = sim(FLT_U3V_SIM_FAULTS_PENDING);
        switch (u8(&in) % 8) {
            case 0: { /* a control-channel fault */
                const flt_u3v_fault f = k_control[u8(&in) % 5];
                const uint8_t at = u8(&in) % 24, count = u8(&in) % 12;
                if (flt_u3v_sim_inject(g_bus, 0, f, at, count) != FLT_OK)
                    die("inject failed", flt_last_error_message());
                break;
            }
            case 1: { /* refused bulk submissions, or (rarely) an unplug */
                const uint8_t kind = u8(&in), at = u8(&in) % 16, count = u8(&in) % 10;
                const flt_u3v_fault f =
                    kind < 8 ? FLT_U3V_FAULT_CONTROL_UNPLUG : FLT_U3V_FAULT_SUBMIT_REFUSED;
                if (flt_u3v_sim_inject(g_bus, 0, f, at, count) != FLT_OK)
                    die("inject failed", flt_last_error_message());
                break;
            }
            case 2: { /* a stream fault a few frames ahead */
                const flt_u3v_fault f = k_stream[u8(&in) % 7];
                const uint64_t at = sim(FLT_U3V_SIM_FRAMES_SENT) + 1 + u8(&in) % 4;
                if (flt_u3v_sim_inject(g_bus, 0, f, at, 1 + u8(&in) % 3) != FLT_OK)
                    die("inject failed", flt_last_error_message());
                break;
            }
            case 3:
            case 4: { /* start */
                const flt_status st = keep(flt_source_start(g_src));
                if (strstr(g_message, "0x8006"))
                    die("start refused with access denied", g_message);
                if (unplugged || sim(FLT_U3V_SIM_UNPLUGGED))
                    break;
                if (st == FLT_OK) {
                    if (!streaming())
                        die("start returned FLT_OK but the camera does not stream", g_message);
                    started = 1;
                } else if (st == FLT_ERR_STATE) {
                    if (!started)
                        die("start of a stopped source refused as already started", g_message);
                } else {
                    if (!may_still_stream() && !stopped())
                        die("start failed saying nothing streams, but the camera streams",
                            g_message);
                    if (pending == 0 && !started)
                        die("start failed with no fault pending", g_message);
                }
                break;
            }
            case 5: { /* stop */
                const flt_status st = keep(flt_source_stop(g_src));
                started = 0;
                if (strstr(g_message, "0x8006"))
                    die("stop refused with access denied", g_message);
                if (unplugged || sim(FLT_U3V_SIM_UNPLUGGED))
                    break;
                if (st == FLT_OK) {
                    if (!stopped())
                        die("stop returned FLT_OK but the camera streams", g_message);
                } else {
                    if (!may_still_stream())
                        die("stop failed without saying the camera may stream", g_message);
                    if (pending == 0)
                        die("stop failed with no fault pending", g_message);
                }
                break;
            }
            case 6: { /* frames */
                for (int k = 1 + u8(&in) % 4; k > 0; --k) {
                    const flt_frame *f = NULL;
                    const flt_status st = keep(flt_source_next(g_src, 0, &f));
                    if (st == FLT_OK && f == NULL)
                        die("next returned FLT_OK without a frame", g_message);
                }
                break;
            }
            default: { /* a feature access over the faulty channel */
                int64_t width = 0;
                (void)keep(flt_source_get_int(g_src, "Width", &width));
                break;
            }
        }
    }

    /* The faults used up (commands by register reads, submissions by
     * start and next), the source stops cleanly. */
    for (int i = 0; i < 400 && sim(FLT_U3V_SIM_FAULTS_PENDING) != 0; ++i) {
        uint8_t b[4];
        const flt_frame *f = NULL;
        if (sim(FLT_U3V_SIM_UNPLUGGED))
            break;
        if (i % 2 == 0) {
            (void)keep(flt_source_read_memory(g_src, 0x10000, b, 4));
        } else {
            (void)keep(flt_source_start(g_src));
            (void)keep(flt_source_next(g_src, 0, &f));
            (void)keep(flt_source_stop(g_src));
        }
    }
    const flt_status st = keep(flt_source_stop(g_src));
    if (!sim(FLT_U3V_SIM_UNPLUGGED)) {
        if (sim(FLT_U3V_SIM_FAULTS_PENDING) != 0)
            die("faults still pending after 400 rounds of commands and submissions", g_message);
        if (st != FLT_OK || !stopped())
            die("the final stop left the camera streaming or failed", g_message);
    } else if (st != FLT_OK) {
        die("stop of an unplugged camera failed", g_message);
    }
    flt_source_destroy(g_src);
    flt_u3v_sim_destroy(g_bus);
    g_src = NULL;
    g_bus = NULL;
    return 0;
}
