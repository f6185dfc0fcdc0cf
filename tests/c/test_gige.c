// SPDX-License-Identifier: Apache-2.0
/*
 * GigE Vision client (flatline/source.h) against a camera nobody here
 * wrote: aravis's fake GigE camera (arv-fake-gv-camera-0.8, Debian package
 * aravis-tools), started by this test on 127.0.0.1. Its frames are a
 * diagonal ramp, pixel (x, y) of frame id f = (x + y + f) % 255 for Mono8.
 *
 * Between the library and the camera sits a small UDP proxy (a thread of
 * this test) that plays the network: it forwards GVCP both ways and the
 * stream from the camera, drops 1 % of the stream packets and sends 1 %
 * after the packet that followed them (reordering). aravis's fake camera
 * does not implement PACKETRESEND, so the proxy answers resend requests
 * itself from the packets the camera sent (as a camera resends from its own
 * memory) and advertises that capability in the camera's GVCP capability
 * register; resent packets are dropped at the same 1 %. It also answers
 * test packets for a path of 1500-byte MTU, so the packet-size negotiation
 * has something to find. A third mode swaps two adjacent packets of 5 % of
 * the frames (k + 1 sent before k, in one sendmmsg call): every packet
 * arrives, so without resends every frame must still be delivered. Frames are checked byte for byte
 * against what the camera sent (the proxy's copy) and against the ramp formula.
 *
 * Linux only (the fake camera and the proxy use POSIX sockets and
 * processes); elsewhere the tests skip with a message. Every number asserted
 * is exact (the network is loopback, the loss is the proxy's), except where
 * a comment says why not.
 */
#ifndef _WIN32
#  define _GNU_SOURCE 1 /* sendmmsg */
#endif
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

#ifdef _WIN32

static void test_skipped_on_windows(void **state) {
    (void)state;
    print_message("aravis's fake GigE camera and the test's proxy run on Linux only\n");
    skip();
}

int main(void) {
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_skipped_on_windows)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}

#else

#  include <arpa/inet.h>
#  include <errno.h>
#  include <fcntl.h>
#  include <netinet/in.h>
#  include <poll.h>
#  include <pthread.h>
#  include <signal.h>
#  include <spawn.h>
#  include <sys/socket.h>
#  include <sys/wait.h>
#  include <time.h>
#  include <unistd.h>

extern char **environ;

#  define ok(call) assert_int_equal((call), FLT_OK)

static void assert_error(flt_status got, flt_status want, const char *needle) {
    if (got != want)
        fail_msg("status %s, expected %s (%s)", flt_status_string(got), flt_status_string(want),
                 flt_last_error_message());
    if (needle && !strstr(flt_last_error_message(), needle))
        fail_msg("message '%s' does not mention '%s'", flt_last_error_message(), needle);
}

static uint64_t count(const flt_source *src, flt_source_counter c) {
    uint64_t v = 0;
    ok(flt_source_count(src, c, &v));
    return v;
}

static uint64_t value(const flt_source *src, flt_camera_value which) {
    uint64_t v = 0;
    ok(flt_source_camera_value(src, which, &v));
    return v;
}

static void sleep_ms(unsigned ms) {
    struct timespec t = {(time_t)(ms / 1000), (long)(ms % 1000) * 1000000L};
    while (nanosleep(&t, &t) != 0 && errno == EINTR) {
    }
}

/* --- the fake camera --------------------------------------------------- */

static pid_t g_camera = 0;
static char g_serial[16];
static const char *g_skip_reason = NULL;

/* The camera's 16-bit frame id of a delivered block id (the library unwraps
 * it: 65535 is followed by 65536, the camera's 1). */
static unsigned frame_id(uint64_t block_id) {
    return (unsigned)((block_id - 1) % 65535) + 1;
}

static int start_camera(void **state) {
    (void)state;
    snprintf(g_serial, sizeof g_serial, "FLT%d", (int)getpid() % 1000000);
    char *argv[] = {"arv-fake-gv-camera-0.8", "-i", "127.0.0.1", "-s", g_serial, NULL};
    posix_spawn_file_actions_t files;
    posix_spawn_file_actions_init(&files);
    posix_spawn_file_actions_addopen(&files, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&files, 2, "/dev/null", O_WRONLY, 0);
    const int rc = posix_spawnp(&g_camera, argv[0], &files, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&files);
    if (rc != 0) {
        g_camera = 0;
        g_skip_reason = "arv-fake-gv-camera-0.8 (Debian package aravis-tools) is not installed";
        return 0;
    }
    /* Wait until it answers a discovery sent to it (it starts in ~50 ms;
     * 10 s covers a machine under heavy load). */
    for (int attempt = 0; attempt < 50; ++attempt) {
        flt_camera_list *list = NULL;
        if (flt_camera_list_create_gige("127.0.0.1", 200, &list) == FLT_OK) {
            size_t n = 0;
            const char *serial = "";
            if (flt_camera_list_count(list, &n) == FLT_OK && n > 0 &&
                flt_camera_list_get(list, 0, NULL, NULL, &serial, NULL) == FLT_OK) {
                const int ours = strcmp(serial, g_serial) == 0;
                flt_camera_list_destroy(list);
                if (ours)
                    return 0;
                g_skip_reason = "another camera answers on 127.0.0.1:3956 (a second run of "
                                "this test?)";
                return 0;
            }
            flt_camera_list_destroy(list);
        }
        int status = 0;
        if (waitpid(g_camera, &status, WNOHANG) == g_camera) {
            g_camera = 0;
            g_skip_reason = "arv-fake-gv-camera-0.8 exited at start (127.0.0.1:3956 taken?)";
            return 0;
        }
        sleep_ms(200);
    }
    g_skip_reason = "arv-fake-gv-camera-0.8 did not answer a discovery within 10 s";
    return 0;
}

static int stop_camera(void **state) {
    (void)state;
    if (g_camera > 0) {
        kill(g_camera, SIGTERM);
        int status = 0;
        waitpid(g_camera, &status, 0);
        g_camera = 0;
    }
    return 0;
}

#  define NEED_CAMERA()                       \
    do {                                      \
      if (g_skip_reason) {                    \
        print_message("%s\n", g_skip_reason); \
        skip();                               \
      }                                       \
    } while (0)

/* The ramp aravis fills Mono8 frames with (arvfakecamera.c). */
static int is_ramp(const uint8_t *p, uint32_t w, uint32_t h, size_t stride, unsigned id) {
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
            if (p[(size_t)y * stride + x] != (uint8_t)((x + y + id) % 255))
                return 0;
    return 1;
}

/* --- the proxy ---------------------------------------------------------- */

enum { k_store_blocks = 64, k_max_packets = 64, k_packet = 1600 };

typedef struct {
    int used;
    uint16_t block;
    uint32_t packets;  // highest packet id + 1 seen
    uint8_t have[k_max_packets];
    uint8_t dropped[k_max_packets];  // dropped on first delivery
    uint16_t length[k_max_packets];
    uint8_t data[k_max_packets][k_packet];
} stored_block;

typedef struct {
    int gvcp_in, gvcp_out, stream_in;
    uint16_t gvcp_port;  // the library opens 127.0.0.1:gvcp_port
    struct sockaddr_in host_control, host_stream;
    int have_host_control, have_host_stream;
    double loss, reorder;
    double swap;  // chance that a frame has two adjacent packets swapped
    unsigned mtu;
    int advertise_resend;
    uint64_t rng;
    pthread_mutex_t lock;
    pthread_t thread;
    int stop;  // set by the test, read by the thread (atomic builtins)
    uint16_t capability_ids[32];
    unsigned n_capability_ids;
    stored_block *store;  // [k_store_blocks]
    uint8_t held[k_packet];
    size_t held_length;
    uint16_t swap_block;  // the frame being swapped: packet swap_id waits for swap_id + 1
    uint32_t swap_id;
    int swapping;
    uint8_t swap_held[k_packet];
    size_t swap_held_length;
    /* The 16-bit block ids of which the camera sent at least one packet
     * (a bit each): a block the camera itself never sent is no loss on the
     * way, and the library rightly counts it lost. */
    uint8_t camera_sent[65536 / 8];
    // counts
    uint64_t stream_packets, dropped, resend_dropped, reordered, resent, resend_requests,
        unknown_resend, test_packets, swapped;
} proxy;

static uint16_t be16(const uint8_t *p) {
    return (uint16_t)((p[0] << 8) | p[1]);
}
static uint32_t be32(const uint8_t *p) {
    return ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | p[3];
}
static void put_be32(uint8_t *p, uint32_t v) {
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
}

/* xorshift64*: the same losses on every run. */
static double chance(proxy *p) {
    p->rng ^= p->rng >> 12;
    p->rng ^= p->rng << 25;
    p->rng ^= p->rng >> 27;
    return (double)((p->rng * 2685821657736338717ull) >> 11) / 9007199254740992.0;
}

static int udp_socket_on(uint16_t port) {
    int s = socket(AF_INET, SOCK_DGRAM, 0);
    assert_true(s >= 0);
    struct sockaddr_in a;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(port);
    assert_int_equal(bind(s, (struct sockaddr *)&a, sizeof a), 0);
    int buffer = 4 << 20;
    setsockopt(s, SOL_SOCKET, SO_RCVBUF, &buffer, sizeof buffer);
    return s;
}

static uint16_t port_of(int s) {
    struct sockaddr_in a;
    socklen_t n = sizeof a;
    getsockname(s, (struct sockaddr *)&a, &n);
    return ntohs(a.sin_port);
}

static stored_block *block_of(proxy *p, uint16_t block, int create) {
    stored_block *b = &p->store[block % k_store_blocks];
    if (b->used && b->block == block)
        return b;
    if (!create)
        return NULL;
    memset(b->have, 0, sizeof b->have);
    memset(b->dropped, 0, sizeof b->dropped);
    b->used = 1;
    b->block = block;
    b->packets = 0;
    return b;
}

static void to_host_stream(proxy *p, const uint8_t *data, size_t n) {
    if (p->have_host_stream)
        sendto(p->stream_in, data, n, 0, (struct sockaddr *)&p->host_stream, sizeof p->host_stream);
}

static void flush_held(proxy *p) {
    if (p->held_length) {
        to_host_stream(p, p->held, p->held_length);
        p->held_length = 0;
    }
}

/* A GVCP command from the library. */
static void from_library(proxy *p, uint8_t *c, size_t n) {
    if (n < 8 || c[0] != 0x42)
        return;
    const uint16_t command = be16(c + 2), id = be16(c + 6);
    if (command == 0x0040 && n >= 20) {  // PACKETRESEND: the proxy resends
        const uint16_t block = (uint16_t)be32(c + 8);
        const uint32_t first = be32(c + 12) & 0xFFFFFF, last = be32(c + 16) & 0xFFFFFF;
        ++p->resend_requests;
        stored_block *b = block_of(p, block, 0);
        for (uint32_t i = first; i <= last && i < k_max_packets; ++i) {
            if (!b || !b->have[i]) {
                ++p->unknown_resend;
                continue;
            }
            if (chance(p) < p->loss) {
                ++p->resend_dropped;
                continue;
            }
            ++p->resent;
            to_host_stream(p, b->data[i], b->length[i]);
        }
        return;
    }
    int fire_test = 0;
    unsigned test_size = 0;
    if (command == 0x0082) {  // WRITEREG: the stream goes through the proxy
        for (size_t at = 8; at + 8 <= n; at += 8) {
            const uint32_t address = be32(c + at), v = be32(c + at + 4);
            if (address == 0x0D00) {
                p->host_stream.sin_family = AF_INET;
                p->host_stream.sin_port = htons((uint16_t)v);
                p->have_host_stream = v != 0;
                if (v != 0)
                    put_be32(c + at + 4, port_of(p->stream_in));
            } else if (address == 0x0D18) {
                p->host_stream.sin_addr.s_addr = htonl(v);
            } else if (address == 0x0D04 && (v & 0x80000000u)) {
                fire_test = 1;
                test_size = v & 0xFFFF;
            }
        }
    } else if (command == 0x0080 && n >= 12 && be32(c + 8) == 0x0934) {
        p->capability_ids[p->n_capability_ids++ % 32] = id;
    }
    send(p->gvcp_out, c, n, 0);
    if (fire_test && test_size <= p->mtu && test_size > 28) {
        static uint8_t zeros[16384];
        ++p->test_packets;
        to_host_stream(p, zeros, test_size - 28);  // IP + UDP headers
    }
}

/* A GVCP answer from the camera. */
static void from_camera(proxy *p, uint8_t *a, size_t n) {
    if (n >= 12 && be16(a + 2) == 0x0081 && p->advertise_resend) {
        for (unsigned i = 0; i < 32 && i < p->n_capability_ids; ++i)
            if (p->capability_ids[i] == be16(a + 6))
                put_be32(a + 8, be32(a + 8) | 4u);  // PACKET_RESEND
    }
    if (p->have_host_control)
        sendto(p->gvcp_in, a, n, 0, (struct sockaddr *)&p->host_control, sizeof p->host_control);
}

/* Sends `first` then `second` to the library's stream port in one call. */
static void send_pair(proxy *p, const uint8_t *first, size_t first_n, const uint8_t *second,
                      size_t second_n) {
    struct iovec io[2] = {{(void *)first, first_n}, {(void *)second, second_n}};
    struct mmsghdr m[2];
    memset(m, 0, sizeof m);
    for (int i = 0; i < 2; ++i) {
        m[i].msg_hdr.msg_name = &p->host_stream;
        m[i].msg_hdr.msg_namelen = sizeof p->host_stream;
        m[i].msg_hdr.msg_iov = &io[i];
        m[i].msg_hdr.msg_iovlen = 1;
    }
    if (p->have_host_stream)
        sendmmsg(p->stream_in, m, 2, 0);
}

/* A stream packet from the camera. */
static void from_stream(proxy *p, const uint8_t *d, size_t n) {
    ++p->stream_packets;
    if (n >= 8) {
        const uint16_t sent = be16(d + 2);
        p->camera_sent[sent >> 3] |= (uint8_t)(1u << (sent & 7));
    }
    if (n >= 8 && n <= k_packet) {
        const uint16_t block = be16(d + 2);
        const uint32_t id = be32(d + 4) & 0xFFFFFF;
        if (id < k_max_packets) {
            stored_block *b = block_of(p, block, 1);
            memcpy(b->data[id], d, n);
            b->length[id] = (uint16_t)n;
            b->have[id] = 1;
            if (id + 1 > b->packets)
                b->packets = id + 1;
            if (chance(p) < p->loss) {
                b->dropped[id] = 1;
                ++p->dropped;
                return;
            }
        }
    }
    if (p->swap > 0 && n >= 8 && n <= k_packet) {
        const uint16_t block = be16(d + 2);
        const uint32_t id = be32(d + 4) & 0xFFFFFF;
        if (id == 0) {
            /* A new frame: swap packets k and k + 1 in 5 % of them (k up
             * to 23: frames of 256 x 128 px are 25 packets, ids 0..24). */
            p->swapping = chance(p) < p->swap;
            p->swap_block = block;
            p->swap_id = (uint32_t)(chance(p) * 24.0);
        }
        if (p->swapping && block == p->swap_block && id == p->swap_id) {
            memcpy(p->swap_held, d, n);
            p->swap_held_length = n;
            return;
        }
        if (p->swapping && block == p->swap_block && id == p->swap_id + 1 && p->swap_held_length) {
            send_pair(p, d, n, p->swap_held, p->swap_held_length);
            p->swap_held_length = 0;
            p->swapping = 0;
            ++p->swapped;
            return;
        }
    }
    if (!p->held_length && chance(p) < p->reorder) {
        memcpy(p->held, d, n);
        p->held_length = n;
        ++p->reordered;
        return;
    }
    to_host_stream(p, d, n);
    flush_held(p);
}

static void *proxy_thread(void *arg) {
    proxy *p = arg;
    uint8_t buffer[65536];
    while (!__atomic_load_n(&p->stop, __ATOMIC_ACQUIRE)) {
        struct pollfd fds[3] = {
            {p->gvcp_in, POLLIN, 0}, {p->gvcp_out, POLLIN, 0}, {p->stream_in, POLLIN, 0}};
        const int ready = poll(fds, 3, 2);
        pthread_mutex_lock(&p->lock);
        if (ready <= 0)
            flush_held(p);  // nothing followed the held packet
        if (ready > 0 && (fds[0].revents & POLLIN)) {
            struct sockaddr_in from;
            socklen_t length = sizeof from;
            const ssize_t n =
                recvfrom(p->gvcp_in, buffer, sizeof buffer, 0, (struct sockaddr *)&from, &length);
            if (n > 0) {
                p->host_control = from;
                p->have_host_control = 1;
                from_library(p, buffer, (size_t)n);
            }
        }
        if (ready > 0 && (fds[1].revents & POLLIN)) {
            const ssize_t n = recv(p->gvcp_out, buffer, sizeof buffer, 0);
            if (n > 0)
                from_camera(p, buffer, (size_t)n);
        }
        if (ready > 0 && (fds[2].revents & POLLIN)) {
            for (int i = 0; i < 256; ++i) {  // drain what is there
                const ssize_t n = recv(p->stream_in, buffer, sizeof buffer, MSG_DONTWAIT);
                if (n <= 0)
                    break;
                from_stream(p, buffer, (size_t)n);
            }
        }
        pthread_mutex_unlock(&p->lock);
    }
    return NULL;
}

/* What a test has open, so that a test that fails half-way (cmocka leaves
 * it by a long jump) does not leave the camera controlled or a proxy
 * running for the tests after it: close_leftovers(), each test's teardown,
 * closes whatever is still here. */
enum { MAX_OPEN = 4 };
static flt_source *open_sources[MAX_OPEN];
static proxy *open_proxies[MAX_OPEN];

static void remember(void **slots, void *item) {
    for (int i = 0; i < MAX_OPEN; ++i)
        if (slots[i] == NULL) {
            slots[i] = item;
            return;
        }
    fail_msg("more than %d open at once", MAX_OPEN);
}

static void forget(void **slots, const void *item) {
    for (int i = 0; i < MAX_OPEN; ++i)
        if (slots[i] == item)
            slots[i] = NULL;
}

/* Closes a source a test opened (flt_source_destroy, and forgotten). */
static void close_source(flt_source *src) {
    forget((void **)open_sources, src);
    flt_source_destroy(src);
}

static proxy *proxy_start_swapping(double loss, double reorder, double swap, int advertise_resend);
static proxy *proxy_start(double loss, double reorder, int advertise_resend) {
    return proxy_start_swapping(loss, reorder, 0.0, advertise_resend);
}

static proxy *proxy_start_swapping(double loss, double reorder, double swap, int advertise_resend) {
    proxy *p = calloc(1, sizeof *p);
    assert_non_null(p);
    p->store = calloc(k_store_blocks, sizeof *p->store);
    assert_non_null(p->store);
    p->loss = loss;
    p->reorder = reorder;
    p->swap = swap;
    p->mtu = 1500;
    p->advertise_resend = advertise_resend;
    p->rng = 0x9E3779B97F4A7C15ull;
    p->gvcp_in = udp_socket_on(0);
    p->gvcp_port = port_of(p->gvcp_in);
    p->gvcp_out = udp_socket_on(0);
    struct sockaddr_in camera;
    memset(&camera, 0, sizeof camera);
    camera.sin_family = AF_INET;
    camera.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    camera.sin_port = htons(3956);
    assert_int_equal(connect(p->gvcp_out, (struct sockaddr *)&camera, sizeof camera), 0);
    p->stream_in = udp_socket_on(0);
    pthread_mutex_init(&p->lock, NULL);
    assert_int_equal(pthread_create(&p->thread, NULL, proxy_thread, p), 0);
    remember((void **)open_proxies, p);
    return p;
}

static void proxy_stop(proxy *p) {
    forget((void **)open_proxies, p);
    __atomic_store_n(&p->stop, 1, __ATOMIC_RELEASE);
    pthread_join(p->thread, NULL);
    close(p->gvcp_in);
    close(p->gvcp_out);
    close(p->stream_in);
    pthread_mutex_destroy(&p->lock);
    free(p->store);
    free(p);
}

/* Compares a delivered frame with the payload packets the camera sent for
 * its block; returns the packets of that block the proxy dropped on first
 * delivery, or -1 if the frame differs (or the proxy no longer holds it). */
static int matches_camera(proxy *p, const uint8_t *pixels, size_t bytes, unsigned id) {
    int dropped = 0;
    pthread_mutex_lock(&p->lock);
    stored_block *b = block_of(p, (uint16_t)id, 0);
    size_t at = 0;
    int same = b != NULL && b->packets >= 2;
    for (uint32_t i = 1; same && i + 1 < b->packets; ++i) {
        const size_t n = b->length[i] - 8u;
        same = b->have[i] && at + n <= bytes && memcmp(pixels + at, b->data[i] + 8, n) == 0;
        at += n;
    }
    same = same && at == bytes;
    for (uint32_t i = 0; same && i < b->packets; ++i)
        dropped += b->dropped[i];
    pthread_mutex_unlock(&p->lock);
    return same ? dropped : -1;
}

/* Opens the camera through `p` (or directly when NULL). */
static flt_source *open_camera(proxy *p, flt_options *options) {
    char address[32];
    snprintf(address, sizeof address, "127.0.0.1:%u", p ? p->gvcp_port : 3956u);
    flt_source *src = NULL;
    const flt_status st = flt_source_open_gige(address, options, &src);
    if (st != FLT_OK)
        fail_msg("open %s: %s", address, flt_last_error_message());
    remember((void **)open_sources, src);
    return src;
}

/* Each test's teardown: the sources first (they talk through the proxy). */
static int close_leftovers(void **state) {
    (void)state;
    for (int i = 0; i < MAX_OPEN; ++i)
        if (open_sources[i] != NULL)
            close_source(open_sources[i]);
    for (int i = 0; i < MAX_OPEN; ++i)
        if (open_proxies[i] != NULL)
            proxy_stop(open_proxies[i]);
    return 0;
}

/* 256 x 128 px Mono8 frames at 50 frames/s: 24 packets of at most 1500
 * bytes, 1.6 MB/s on loopback, so that the 416 KiB a socket gets without
 * raising net.core.rmem_max hold 250 ms of a stalled reader on a loaded
 * machine. */
static void set_small_frames(flt_source *src) {
    ok(flt_source_set_int(src, "Width", 256));
    ok(flt_source_set_int(src, "Height", 128));
    ok(flt_source_set_enum(src, "PixelFormat", "Mono8"));
    ok(flt_source_set_float(src, "AcquisitionFrameRate", 50.0));
}

/* --- tests --------------------------------------------------------------- */

static void test_discovery_finds_the_camera(void **state) {
    (void)state;
    NEED_CAMERA();
    flt_camera_list *list = NULL;
    ok(flt_camera_list_create_gige("127.0.0.1", 500, &list));
    size_t n = 0;
    ok(flt_camera_list_count(list, &n));
    assert_int_equal(n, 1);
    const char *vendor, *model, *serial, *address;
    uint32_t speed = 99;
    ok(flt_camera_list_get(list, 0, &vendor, &model, &serial, &speed));
    assert_string_equal(vendor, "Aravis");
    assert_string_equal(model, "Fake");
    assert_string_equal(serial, g_serial);
    assert_int_equal(speed, 0);
    ok(flt_camera_list_address(list, 0, &address));
    assert_string_equal(address, "127.0.0.1");
    assert_error(flt_camera_list_address(list, 1, &address), FLT_ERR_INVALID_ARGUMENT,
                 "'index' = 1");
    flt_camera_list_destroy(list);
    /* An address nobody answers on: an empty list, not an error. */
    ok(flt_camera_list_create_gige("127.0.0.1:9", 100, &list));
    ok(flt_camera_list_count(list, &n));
    assert_int_equal(n, 0);
    flt_camera_list_destroy(list);
}

static void test_open_reads_bootstrap_and_features(void **state) {
    (void)state;
    NEED_CAMERA();
    flt_source *src = open_camera(NULL, NULL);
    flt_source_kind kind = FLT_SOURCE_SIMULATOR;
    ok(flt_source_kind_of(src, &kind));
    assert_int_equal(kind, FLT_SOURCE_GIGE);
    const char *s = NULL;
    ok(flt_source_camera_string(src, FLT_CAMERA_VENDOR, &s));
    assert_string_equal(s, "Aravis");
    ok(flt_source_camera_string(src, FLT_CAMERA_MODEL, &s));
    assert_string_equal(s, "Fake");
    ok(flt_source_camera_string(src, FLT_CAMERA_SERIAL, &s));
    assert_string_equal(s, g_serial);
    ok(flt_source_camera_string(src, FLT_CAMERA_FAMILY, &s));
    assert_string_equal(s, "");
    assert_int_equal(value(src, FLT_CAMERA_IP_ADDRESS), 0x7F000001u);
    assert_int_equal(value(src, FLT_CAMERA_TIMESTAMP_HZ), 1000000000u); /* aravis: ns */
    assert_int_equal(value(src, FLT_CAMERA_HEARTBEAT_TIMEOUT_MS), 3000);
    assert_int_equal(value(src, FLT_CAMERA_XML_ZIPPED), 0);
    assert_true(value(src, FLT_CAMERA_XML_BYTES) > 10000); /* the whole XML was read */
    /* aravis's fake camera sends no test packets: its own 1400 bytes stay. */
    assert_int_equal(value(src, FLT_CAMERA_PACKET_SIZE), 1400);
    assert_int_equal(value(src, FLT_CAMERA_RESEND_CAPABLE), 0);
    assert_error(flt_source_camera_value(src, FLT_CAMERA_SIRM_ADDRESS, &(uint64_t){0}),
                 FLT_ERR_INVALID_ARGUMENT, "GigE");

    /* Features through the GenICam engine over big-endian registers. */
    int64_t v = 0;
    ok(flt_source_get_int(src, "SensorWidth", &v));
    assert_int_equal(v, 2048);
    ok(flt_source_set_int(src, "Width", 320));
    ok(flt_source_get_int(src, "Width", &v));
    assert_int_equal(v, 320);
    ok(flt_source_set_int(src, "Height", 200));
    ok(flt_source_get_int(src, "PayloadSize", &v));
    assert_int_equal(v, 320 * 200);
    assert_error(flt_source_set_int(src, "Width", 4096), FLT_ERR_INVALID_ARGUMENT, "Width");
    double rate = 0;
    ok(flt_source_set_float(src, "AcquisitionFrameRate", 50.0));
    ok(flt_source_get_float(src, "AcquisitionFrameRate", &rate));
    assert_true(rate == 50.0); /* period 20000 us, exactly representable back */

    /* Raw registers: the test register holds 0x12345678, big-endian. */
    uint8_t raw[4] = {0};
    ok(flt_source_read_memory(src, 0x1F0, raw, 4));
    assert_int_equal(raw[0], 0x12);
    assert_int_equal(raw[3], 0x78);
    ok(flt_source_read_memory(src, 0x1F1, raw, 2)); /* unaligned: widened to words */
    assert_int_equal(raw[0], 0x34);
    assert_int_equal(raw[1], 0x56);
    /* A feature mapped by address reads big-endian on GigE Vision. */
    ok(flt_source_map_feature(src, "TestRegister", 0x1F0, 4, 0));
    ok(flt_source_get_int(src, "TestRegister", &v));
    assert_int_equal(v, 0x12345678);
    ok(flt_source_set_int(src, "Width", 512));
    ok(flt_source_set_int(src, "Height", 512));
    close_source(src);
}

static void test_heartbeat_keeps_control(void **state) {
    (void)state;
    NEED_CAMERA();
    flt_options *fast = NULL;
    ok(flt_options_create(&fast));
    ok(flt_options_set(fast, FLT_OPT_GIGE_HEARTBEAT_TIMEOUT, 1000));
    flt_source *a = open_camera(NULL, fast);
    assert_int_equal(value(a, FLT_CAMERA_HEARTBEAT_TIMEOUT_MS), 1000);
    /* 2.5 heartbeat timeouts without any call: the camera would have given
     * the privilege away without heartbeats. */
    sleep_ms(2500);
    /* One every 333 ms: 7 in 2.5 s; at least 4 under a loaded machine. */
    assert_true(value(a, FLT_CAMERA_HEARTBEATS) >= 4);
    /* A second host cannot take control (the camera ignores its writes). */
    flt_options *quick = NULL;
    ok(flt_options_create(&quick));
    ok(flt_options_set(quick, FLT_OPT_GIGE_CONTROL_TIMEOUT, 100));
    ok(flt_options_set(quick, FLT_OPT_GIGE_COMMAND_ATTEMPTS, 2));
    flt_source *b = NULL;
    assert_error(flt_source_open_gige("127.0.0.1", quick, &b), FLT_ERR_TIMEOUT, "control");
    assert_null(b);
    int64_t v = 0;
    ok(flt_source_get_int(a, "Width", &v)); /* the first host still works */
    ok(flt_source_set_int(a, "Width", (int)v));
    /* Released on destroy: the second host opens at once. */
    close_source(a);
    ok(flt_source_open_gige("127.0.0.1", quick, &b));
    remember((void **)open_sources, b);
    close_source(b);
    flt_options_destroy(fast);
    flt_options_destroy(quick);
}

static void test_stream_is_aravis_ramp(void **state) {
    (void)state;
    NEED_CAMERA();
    flt_source *src = open_camera(NULL, NULL);
    set_small_frames(src);
    ok(flt_source_start(src));
    assert_int_equal(value(src, FLT_CAMERA_PAYLOAD_BYTES), 256 * 128);
    uint64_t previous = 0, first = 0, before = 0;
    for (int i = 0; i < 200; ++i) {
        const flt_frame *f = NULL;
        const flt_status st = flt_source_next(src, 2000, &f);
        if (st != FLT_OK)
            fail_msg("frame %d: %s", i, flt_last_error_message());
        const void *pixels;
        uint32_t w, h;
        size_t stride;
        flt_pixel_format format;
        uint64_t block;
        ok(flt_frame_info(f, &pixels, &w, &h, &stride, &format, &block, NULL, NULL));
        assert_int_equal(w, 256);
        assert_int_equal(h, 128);
        assert_int_equal(stride, 256);
        assert_int_equal(format, FLT_PIXEL_MONO8);
        if (i > 0) {
            assert_true(block > previous); /* unwrapped across 65535 -> 1 */
        } else {
            first = block;
            before = count(src, FLT_COUNT_DROPPED) + count(src, FLT_COUNT_LOST);
        }
        previous = block;
        if (!is_ramp(pixels, w, h, stride, frame_id(block)))
            fail_msg("frame %d (block %llu) is not aravis's ramp", i, (unsigned long long)block);
    }
    /* aravis starts its frame ids at 65401 (this is the first stream of
     * the camera): 200 frames cross the wrap to 1. */
    assert_true(first < 65535 && previous > 65535);
    assert_int_equal(count(src, FLT_COUNT_FRAMES), 200);
    /* Loopback loses nothing unless this process stalls long enough for its
     * socket buffer to overflow (a loaded machine); then the camera, which
     * does not resend, costs frames: each one is accounted for. */
    const uint64_t dropped = count(src, FLT_COUNT_DROPPED), lost = count(src, FLT_COUNT_LOST);
    assert_int_equal(previous - first + 1, 200 + dropped + lost - before);
    if (dropped + lost > 0)
        print_message("loopback lost %llu frame(s) (a stalled reader)\n",
                      (unsigned long long)(dropped + lost));
    /* TLParamsLocked = 1 while streaming (aravis's camera keeps it as a
     * value and ties nothing to it). */
    int64_t locked = 0;
    ok(flt_source_get_int(src, "TLParamsLocked", &locked));
    assert_int_equal(locked, 1);
    ok(flt_source_stop(src));
    ok(flt_source_get_int(src, "TLParamsLocked", &locked));
    assert_int_equal(locked, 0);
    close_source(src);
}

/* 1,000 frames at 1 % loss and 1 % reordering, with resends. */
static void test_thousand_frames_through_lossy_network(void **state) {
    (void)state;
    NEED_CAMERA();
    proxy *p = proxy_start(0.01, 0.01, 1);
    flt_options *options = NULL;
    ok(flt_options_create(&options));
    /* The proxy answers within a millisecond when the machine is idle;
     * 8 attempts 25 ms apart and 32 frames in assembly (320 ms at 100
     * frames/s) leave room for a shared, loaded machine. */
    ok(flt_options_set(options, FLT_OPT_GIGE_RESEND_TIMEOUT, 25));
    ok(flt_options_set(options, FLT_OPT_GIGE_RESEND_ATTEMPTS, 8));
    ok(flt_options_set(options, FLT_OPT_GIGE_ASSEMBLY_FRAMES, 32));
    flt_source *src = open_camera(p, options);
    assert_int_equal(value(src, FLT_CAMERA_RESEND_CAPABLE), 1);
    /* Negotiated against the proxy's 1500-byte path. */
    assert_int_equal(value(src, FLT_CAMERA_PACKET_SIZE), 1500);
    pthread_mutex_lock(&p->lock);
    const uint64_t test_packets = p->test_packets;
    pthread_mutex_unlock(&p->lock);
    assert_true(test_packets >= 1);
    set_small_frames(src);
    ok(flt_source_start(src));
    uint64_t previous = 0, dropped_in_delivered = 0, camera_skipped = 0;
    for (int i = 0; i < 1000; ++i) {
        const flt_frame *f = NULL;
        const flt_status st = flt_source_next(src, 3000, &f);
        if (st != FLT_OK)
            fail_msg("frame %d: %s", i, flt_last_error_message());
        const void *pixels;
        uint32_t w, h;
        size_t stride;
        uint64_t block;
        ok(flt_frame_info(f, &pixels, &w, &h, &stride, NULL, &block, NULL, NULL));
        if (i > 0 && block != previous + 1) {
            /* A gap is a failure unless the camera never sent the blocks
             * in it: aravis's fake camera, starved of CPU on a loaded
             * machine, skips a frame's id now and then. Those the library
             * must count lost (asserted below). */
            pthread_mutex_lock(&p->lock);
            for (uint64_t b = previous + 1; b < block && block - previous < 64; ++b) {
                const unsigned id = frame_id(b);
                if (p->camera_sent[id >> 3] & (1u << (id & 7)))
                    camera_skipped = UINT64_MAX; /* sent, and lost on the way */
                else if (camera_skipped != UINT64_MAX)
                    ++camera_skipped;
            }
            pthread_mutex_unlock(&p->lock);
            if (camera_skipped == UINT64_MAX || block - previous >= 64)
                fail_msg("frame %d: block %llu after %llu (%s)", i, (unsigned long long)block,
                         (unsigned long long)previous, flt_source_stream_error(src));
            print_message("the camera skipped block ids %llu..%llu (never sent)\n",
                          (unsigned long long)previous + 1, (unsigned long long)block - 1);
        }
        previous = block;
        const int dropped = matches_camera(p, pixels, (size_t)w * h, frame_id(block));
        if (dropped < 0)
            fail_msg("frame %d (block %llu) differs from what the camera sent", i,
                     (unsigned long long)block);
        if (!is_ramp(pixels, w, h, stride, frame_id(block)))
            fail_msg("frame %d is not aravis's ramp", i);
        dropped_in_delivered += (uint64_t)dropped;
    }
    ok(flt_source_stop(src));
    pthread_mutex_lock(&p->lock);
    const uint64_t proxy_dropped = p->dropped, resend_dropped = p->resend_dropped,
                   reordered = p->reordered, resent = p->resent, packets = p->stream_packets;
    pthread_mutex_unlock(&p->lock);
    const uint64_t missing = count(src, FLT_COUNT_PACKETS_MISSING),
                   recovered = count(src, FLT_COUNT_PACKETS_RESENT),
                   requests = count(src, FLT_COUNT_RESEND_REQUESTS),
                   duplicates = count(src, FLT_COUNT_PACKETS_DUPLICATE);
    print_message("GigE 1000 frames: proxy saw %llu packets, dropped %llu (+%llu resent ones), "
                  "reordered %llu, resent %llu; library: missing %llu, requested %llu, "
                  "recovered %llu, duplicates %llu, dropped frames %llu\n",
                  (unsigned long long)packets, (unsigned long long)proxy_dropped,
                  (unsigned long long)resend_dropped, (unsigned long long)reordered,
                  (unsigned long long)resent, (unsigned long long)missing,
                  (unsigned long long)requests, (unsigned long long)recovered,
                  (unsigned long long)duplicates,
                  (unsigned long long)count(src, FLT_COUNT_DROPPED));
    assert_int_equal(count(src, FLT_COUNT_FRAMES), 1000);
    assert_int_equal(count(src, FLT_COUNT_DROPPED), 0);
    /* Lost: only the blocks the camera never sent (none on an idle machine). */
    assert_int_equal(count(src, FLT_COUNT_LOST), camera_skipped);
    /* About 1 % of ~26 packets x 1000 frames were dropped on the way. */
    assert_true(dropped_in_delivered >= 100);
    /* Every loss counted: each packet the proxy dropped from a delivered
     * frame was found missing, and came back after a request. The library
     * may also count packets of frames after the 1000th, and packets the
     * machine's load delayed past the resend timeout (then asked again:
     * they arrive twice), hence >=. */
    assert_true(missing >= dropped_in_delivered);
    assert_true(recovered >= dropped_in_delivered);
    assert_true(missing <= proxy_dropped + reordered);
    assert_true(requests >= missing);
    close_source(src);
    flt_options_destroy(options);
    proxy_stop(p);
}

/* Without resends every frame that lost a packet is dropped, never
 * delivered damaged, and every frame is accounted for. */
static void test_without_resends_losses_drop_frames(void **state) {
    (void)state;
    NEED_CAMERA();
    proxy *p = proxy_start(0.01, 0.0, 0);
    flt_source *src = open_camera(p, NULL);
    assert_int_equal(value(src, FLT_CAMERA_RESEND_CAPABLE), 0);
    set_small_frames(src);
    ok(flt_source_start(src));
    uint64_t first = 0, last = 0, before = 0;
    for (int i = 0; i < 200; ++i) {
        const flt_frame *f = NULL;
        const flt_status st = flt_source_next(src, 3000, &f);
        if (st != FLT_OK)
            fail_msg("frame %d: %s", i, flt_last_error_message());
        const void *pixels;
        uint32_t w, h;
        size_t stride;
        uint64_t block;
        ok(flt_frame_info(f, &pixels, &w, &h, &stride, NULL, &block, NULL, NULL));
        if (i == 0) {
            first = block;
            /* frames dropped before the first delivered one */
            before = count(src, FLT_COUNT_DROPPED) + count(src, FLT_COUNT_LOST);
        }
        last = block;
        if (matches_camera(p, pixels, (size_t)w * h, frame_id(block)) != 0)
            fail_msg("frame %d (block %llu) is damaged or lost packets", i,
                     (unsigned long long)block);
    }
    /* Blocks first..last: 200 delivered, the others dropped or lost. */
    const uint64_t dropped = count(src, FLT_COUNT_DROPPED);
    assert_int_equal(last - first + 1, 200 + dropped + count(src, FLT_COUNT_LOST) - before);
    assert_int_equal(dropped, count(src, FLT_COUNT_INCOMPLETE));
    /* 1 - 0.99^26 = 23 % of the frames lose a packet; >= 10 of ~260. */
    assert_true(dropped >= 10);
    assert_int_equal(count(src, FLT_COUNT_RESEND_REQUESTS), 0);
    assert_non_null(strstr(flt_source_stream_error(src), "does not resend"));
    close_source(src);
    proxy_stop(p);
}

/* Packets dropped by the system because the socket of `port` (the
 * library's stream socket) was full: /proc/net/udp's last column. A
 * stalled reader on a loaded machine loses packets there, not in the
 * library. */
static uint64_t system_drops(uint16_t port) {
    FILE *f = fopen("/proc/net/udp", "r");
    if (!f)
        return 0;
    char line[512];
    uint64_t drops = 0;
    while (fgets(line, sizeof line, f)) {
        unsigned local_port = 0;
        char *colon = strchr(line, ':'); /* "sl: address:port ..." */
        colon = colon ? strchr(colon + 1, ':') : NULL;
        if (!colon || sscanf(colon + 1, "%x", &local_port) != 1 || local_port != port)
            continue;
        const char *last = strrchr(line, ' ');
        if (last)
            drops = strtoull(last + 1, NULL, 10);
    }
    fclose(f);
    return drops;
}

/* Two packets of a frame overtaking each other is no loss: 1,000 frames
 * through a proxy that swaps adjacent packets in 5 % of them, from a
 * camera that cannot resend: all 1,000 delivered, byte-exact, in order. */
static void test_swapped_packets_are_no_loss(void **state) {
    (void)state;
    NEED_CAMERA();
    proxy *p = proxy_start_swapping(0.0, 0.0, 0.05, 0);
    flt_source *src = open_camera(p, NULL);
    assert_int_equal(value(src, FLT_CAMERA_RESEND_CAPABLE), 0);
    set_small_frames(src);
    ok(flt_source_start(src));
    const uint16_t port = (uint16_t)value(src, FLT_CAMERA_STREAM_PORT);
    uint64_t previous = 0;
    int delivered = 0, in_order = 1, exact = 1;
    for (int i = 0; i < 1000; ++i) {
        const flt_frame *f = NULL;
        const flt_status st = flt_source_next(src, 3000, &f);
        if (st != FLT_OK) {
            print_message("frame %d: %s\n", i, flt_last_error_message());
            break;
        }
        const void *pixels;
        uint32_t w, h;
        size_t stride;
        uint64_t block;
        ok(flt_frame_info(f, &pixels, &w, &h, &stride, NULL, &block, NULL, NULL));
        in_order = in_order && (i == 0 || block == previous + 1);
        previous = block;
        exact = exact && matches_camera(p, pixels, (size_t)w * h, frame_id(block)) == 0 &&
                is_ramp(pixels, w, h, stride, frame_id(block));
        ++delivered;
    }
    ok(flt_source_stop(src));
    pthread_mutex_lock(&p->lock);
    const uint64_t swapped = p->swapped;
    pthread_mutex_unlock(&p->lock);
    const uint64_t dropped = count(src, FLT_COUNT_DROPPED), lost = count(src, FLT_COUNT_LOST),
                   missing = count(src, FLT_COUNT_PACKETS_MISSING), drops = system_drops(port);
    print_message("GigE swaps: %llu frames had two packets swapped; library: %d of 1000 "
                  "delivered, %llu dropped, %llu lost, %llu packets missing; the system dropped "
                  "%llu packets (last drop: '%s')\n",
                  (unsigned long long)swapped, delivered, (unsigned long long)dropped,
                  (unsigned long long)lost, (unsigned long long)missing, (unsigned long long)drops,
                  flt_source_stream_error(src));
    /* 5 % of ~1,000 frames: 50, binomial sd 7; 20 is 4 sd below. */
    assert_true(swapped >= 20);
    assert_true(exact); /* never a damaged frame, whatever happened */
    if (drops == 0) {
        /* Every packet reached the socket: the target, exactly. */
        assert_int_equal(delivered, 1000);
        assert_true(in_order);
        assert_int_equal(dropped, 0);
        assert_int_equal(lost, 0);
        assert_int_equal(missing, 0);
    } else {
        /* A stalled reader (a loaded machine) overflowed the socket: each
         * packet the system dropped costs at most its frame. */
        assert_true(dropped + lost <= drops);
    }
    close_source(src);
    proxy_stop(p);
}

static void test_bad_arguments(void **state) {
    (void)state;
    flt_source *src = (flt_source *)1;
    assert_error(flt_source_open_gige("", NULL, &src), FLT_ERR_INVALID_ARGUMENT, "'camera'");
    assert_null(src);
    flt_camera_list *list = NULL;
    assert_error(flt_camera_list_create_gige("camera.local", 100, &list), FLT_ERR_INVALID_ARGUMENT,
                 "'address'");
    assert_error(flt_camera_list_create_gige("127.0.0.1", 0, &list), FLT_ERR_INVALID_ARGUMENT,
                 "'timeout_ms'");
    flt_options *o = NULL;
    ok(flt_options_create(&o));
    ok(flt_options_set(o, FLT_OPT_GIGE_PACKET_SIZE, 100));
    assert_error(flt_source_open_gige("127.0.0.1", o, &src), FLT_ERR_INVALID_ARGUMENT,
                 "gige_packet_size");
    flt_options_destroy(o);
    /* An address where nothing answers: a timeout naming it. */
    ok(flt_options_create(&o));
    ok(flt_options_set(o, FLT_OPT_GIGE_CONTROL_TIMEOUT, 50));
    ok(flt_options_set(o, FLT_OPT_GIGE_COMMAND_ATTEMPTS, 1));
    assert_error(flt_source_open_gige("127.0.0.1:9", o, &src), FLT_ERR_TIMEOUT, "127.0.0.1:9");
    flt_options_destroy(o);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_bad_arguments, close_leftovers),
        cmocka_unit_test_teardown(test_discovery_finds_the_camera, close_leftovers),
        cmocka_unit_test_teardown(test_open_reads_bootstrap_and_features, close_leftovers),
        cmocka_unit_test_teardown(test_heartbeat_keeps_control, close_leftovers),
        cmocka_unit_test_teardown(test_stream_is_aravis_ramp, close_leftovers),
        cmocka_unit_test_teardown(test_thousand_frames_through_lossy_network, close_leftovers),
        cmocka_unit_test_teardown(test_without_resends_losses_drop_frames, close_leftovers),
        cmocka_unit_test_teardown(test_swapped_packets_are_no_loss, close_leftovers),
    };
    return cmocka_run_group_tests(tests, start_camera, stop_camera);
}

#endif
