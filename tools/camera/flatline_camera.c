/* SPDX-License-Identifier: Apache-2.0 */
/*
 * flatline-camera: a USB3 Vision or GigE Vision camera from the command
 * line, through libflatline's public C API only (README.md beside this
 * file has every command and option):
 *
 *   flatline-camera list                       cameras on USB and the network
 *   flatline-camera features [--all]           the GenICam feature tree, with
 *                                              values, access and units
 *   flatline-camera features --xml FILE        the same offline, from a
 *                                              description file (XML or ZIP)
 *   flatline-camera get NAME...                feature values
 *   flatline-camera set NAME=VALUE...          write features (a command: NAME)
 *   flatline-camera snap -o frame.png [--overlay --calib sensor.json]
 *   flatline-camera stream --seconds N         frames, rate, drops, resends
 *
 * -c CAMERA picks the camera: u3v[:SERIAL], gige:ADDRESS|SERIAL|NAME, an
 * IPv4 address, or a serial number; without it the first one found.
 *
 * Exit status: 0 done, 1 a command failed (the message says why), 2 a
 * usage error, 3 no camera answered.
 *
 * The live camera's feature tree: the tool reads the camera's GenICam
 * description the way the library does when it opens the camera (USB3
 * Vision: the manifest table; GigE Vision: the first URL register), loads
 * it into a flt_genicam view (flatline/genicam.h) whose registers are the
 * camera's (flt_source_read_memory / flt_source_write_memory), and walks
 * its categories. Values shown are what the camera's registers hold now;
 * writes go through the source (flt_source_set_*), which checks the access
 * mode and TLParamsLocked as a stream needs.
 *
 * Built a second time as flatline-camera-sim (FLT_CAMERA_SIMULATOR, not
 * installed) with the testing tier's simulated USB3 Vision camera as the
 * camera "sim", for the tests.
 */
#include <ctype.h>
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flatline/flatline.h"
#include "png_write.h"
#ifdef FLT_CAMERA_SIMULATOR
#  include "flatline/testing.h"
#endif

#ifdef _WIN32
#  include <windows.h>
#  include <shellapi.h>
#else
#  include <time.h>
#endif

enum { EXIT_DONE = 0, EXIT_FAILED = 1, EXIT_USAGE = 2, EXIT_NO_CAMERA = 3 };

static const char k_usage[] =
    "usage: flatline-camera [-c CAMERA] COMMAND [ARGS] [OPTIONS]\n"
    "\n"
    "commands:\n"
    "  list                    USB3 Vision and GigE Vision cameras, with addresses and\n"
    "                          who controls them\n"
    "  features [--all]        the camera's GenICam feature tree: values, access, units\n"
    "                          (--all: also features not implemented or not available)\n"
    "  features --xml FILE     the same offline, from a description file (XML or ZIP)\n"
    "  get NAME...             feature values\n"
    "  set NAME=VALUE...       write features (a command feature: NAME alone)\n"
    "  snap -o FILE.png        one frame as PNG; --overlay draws the extracted lines,\n"
    "                          bands, saturated pixels and strip edges (needs --calib)\n"
    "  stream --seconds N      acquire for N s: frames, rate, drops, resends, bandwidth\n"
    "\n"
    "options:\n"
    "  -c, --camera CAMERA     u3v, u3v:SERIAL, gige:ADDRESS|SERIAL|NAME, an IPv4 address\n"
    "                          (a.b.c.d[:port]), or a serial number; default: the first\n"
    "                          camera found (USB3 Vision first)\n"
    "  --gige ADDRESS          list: where to send the GigE discovery (a camera or a\n"
    "                          subnet's broadcast address; default every interface)\n"
    "  --no-probe              list: do not open GigE cameras to see who controls them\n"
    "  --timeout MS            how long to wait for a camera to answer (default 500)\n"
    "  --frame-timeout MS      how long to wait for a frame (default 3000)\n"
    "  -o, --output FILE       snap: the PNG file\n"
    "  --overlay               snap: draw what the extractor sees (needs --calib)\n"
    "  --calib FILE            snap: the sensor's calibration file\n"
    "  --seconds N             stream: how long (default 5)\n"
    "  -h, --help              this text\n"
    "  --version               the library's version\n"
    "\n"
    "exit status: 0 done, 1 failed, 2 usage, 3 no camera answered\n";

typedef struct options {
    const char *command;
    const char *camera;
    const char *gige_address;
    int probe;
    uint32_t timeout_ms;
    uint32_t frame_timeout_ms;
    int all;
    const char *xml;
    const char *output;
    int overlay;
    const char *calib;
    double seconds;
    int argc;
    char **argv; /* positional arguments after the command */
} options;

/* ---------------------------------------------------------------------- */
/* Messages and time                                                       */
/* ---------------------------------------------------------------------- */

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static int
say_failed(int code, const char *format, ...) {
    va_list ap;
    va_start(ap, format);
    fputs("flatline-camera: ", stderr);
    vfprintf(stderr, format, ap);
    fputc('\n', stderr);
    va_end(ap);
    return code;
}

/* A library call failed: what the tool was doing, and the library's
 * message (which names the function, the argument and the value). */
static int library_failed(const char *doing, flt_status status) {
    return say_failed(EXIT_FAILED, "%s: %s (%s)", doing, flt_last_error_message(),
                      flt_status_string(status));
}

static double now_s(void) {
#ifdef _WIN32
    LARGE_INTEGER f, t;
    QueryPerformanceFrequency(&f);
    QueryPerformanceCounter(&t);
    return (double)t.QuadPart / (double)f.QuadPart;
#else
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
#endif
}

/* ---------------------------------------------------------------------- */
/* Finding and opening the camera                                          */
/* ---------------------------------------------------------------------- */

/* The USB access: the computer's bus (NULL), or in the test build the
 * testing tier's simulated bus. */
static flt_usb_transport *g_usb = NULL;

#ifdef FLT_CAMERA_SIMULATOR
static flt_u3v_sim *g_bus = NULL;
static flt_sim *g_sim = NULL;
static flt_calib *g_sim_calib = NULL;

/* The simulated sensor behind a simulated USB3 Vision camera: the
 * reference sensor's 2048 x 256 window, a 1500 mm strip on the roller
 * table (so both strip edges are in view) with a centre buckle, and a
 * line bright enough that speckle drives some of its pixels to full scale. */
static int make_simulated_camera(void) {
    flt_options *so = NULL;
    flt_status st = flt_calib_create_reference(892, 256, -1000.0, 2.0, 1001, &g_sim_calib);
    if (st == FLT_OK)
        st = flt_options_create(&so);
    if (st == FLT_OK)
        st = flt_options_set(so, FLT_OPT_SIM_SURROUND, 2);
    if (st == FLT_OK)
        st = flt_options_set(so, FLT_OPT_SIM_STRIP_WIDTH, 1500);
    if (st == FLT_OK)
        st = flt_options_set(so, FLT_OPT_SIM_STRIP_OFFSET, 100);
    if (st == FLT_OK)
        st = flt_options_set(so, FLT_OPT_SIM_LINE_PEAK, 0.95);
    if (st == FLT_OK)
        st = flt_sim_create(g_sim_calib, so, &g_sim);
    flt_options_destroy(so);
    if (st == FLT_OK)
        st = flt_sim_add_defect(g_sim, FLT_SIM_CENTRE_BUCKLE, 5.0, 1800.0);
    if (st == FLT_OK)
        st = flt_u3v_sim_create(&g_bus);
    if (st == FLT_OK)
        st = flt_u3v_sim_add_camera(g_bus, "Flatline", "Simulated sensor", "SIM-1", 2048, 256,
                                    FLT_PIXEL_MONO8, NULL);
    if (st == FLT_OK)
        st = flt_u3v_sim_set_frames(g_bus, 0, g_sim);
    if (st == FLT_OK)
        st = flt_u3v_sim_transport(g_bus, &g_usb);
    return st == FLT_OK ? 0 : library_failed("the simulated camera", st);
}
#endif

/* "a.b.c.d" or "a.b.c.d:port": an IPv4 address. */
static int is_ipv4(const char *text) {
    int parts = 0;
    const char *p = text;
    for (;;) {
        int digits = 0;
        long v = 0;
        while (isdigit((unsigned char)*p)) {
            v = v * 10 + (*p++ - '0');
            if (++digits > 3)
                return 0;
        }
        if (digits == 0 || v > 255)
            return 0;
        ++parts;
        if (parts == 4)
            break;
        if (*p++ != '.')
            return 0;
    }
    if (*p == ':') {
        ++p;
        if (!isdigit((unsigned char)*p))
            return 0;
        while (isdigit((unsigned char)*p))
            ++p;
    }
    return *p == '\0';
}

/* Nothing answered at `address`: the message a commissioning engineer
 * needs, before the library's open would time out on each of its steps. */
static int check_gige_answers(const char *address, uint32_t timeout_ms) {
    flt_camera_list *list = NULL;
    flt_status st = flt_camera_list_create_gige(address, timeout_ms, &list);
    if (st != FLT_OK)
        return library_failed("GigE Vision discovery", st);
    size_t n = 0;
    st = flt_camera_list_count(list, &n);
    flt_camera_list_destroy(list);
    if (st != FLT_OK)
        return library_failed("GigE Vision discovery", st);
    if (n == 0)
        return say_failed(EXIT_NO_CAMERA,
                          "nothing answered at %s within %u ms; is the camera on this subnet? "
                          "(a GigE Vision camera answers a discovery on UDP port 3956: check "
                          "its address with 'flatline-camera list', the cable, and that the "
                          "firewall lets its UDP packets in)",
                          address, (unsigned)timeout_ms);
    return 0;
}

static int open_u3v(const char *serial, flt_source **out) {
    flt_status st = flt_source_open_u3v(g_usb, serial, NULL, out);
    if (st == FLT_ERR_NOT_FOUND && serial)
        return say_failed(EXIT_NO_CAMERA, "no USB3 Vision camera with serial '%s': %s", serial,
                          flt_last_error_message());
    if (st == FLT_ERR_NOT_FOUND)
        return say_failed(EXIT_NO_CAMERA, "%s", flt_last_error_message());
    if (st != FLT_OK)
        return library_failed("opening the USB3 Vision camera", st);
    return 0;
}

/* The address of the GigE Vision camera whose serial number or
 * user-defined name is `name`, from a discovery (where --gige says, else
 * every interface): the address its answer came from. */
static int find_gige(const char *name, const options *o, char *address, size_t size) {
    flt_camera_list *list = NULL;
    flt_status st = flt_camera_list_create_gige(o->gige_address, o->timeout_ms, &list);
    if (st != FLT_OK)
        return library_failed("GigE Vision discovery", st);
    size_t n = 0;
    int found = 0;
    if (flt_camera_list_count(list, &n) != FLT_OK)
        n = 0;
    for (size_t i = 0; i < n && !found; ++i) {
        const char *serial = "", *at = "";
        if (flt_camera_list_get(list, i, NULL, NULL, &serial, NULL) != FLT_OK ||
            flt_camera_list_address(list, i, &at) != FLT_OK)
            continue;
        if (strcmp(serial, name) == 0) {
            snprintf(address, size, "%s", at);
            found = 1;
        }
    }
    flt_camera_list_destroy(list);
    if (found)
        return 0;
    /* not a serial number: the library looks for a user-defined name */
    snprintf(address, size, "%s", name);
    return 0;
}

static int open_gige(const char *camera, const options *o, flt_source **out) {
    char address[256];
    if (camera && !is_ipv4(camera)) {
        int rc = find_gige(camera, o, address, sizeof address);
        if (rc)
            return rc;
        camera = address;
    }
    const int answered = camera && is_ipv4(camera);
    if (answered) {
        int rc = check_gige_answers(camera, o->timeout_ms);
        if (rc)
            return rc;
    }
    flt_options *go = NULL;
    flt_status st = flt_options_create(&go);
    if (st == FLT_OK)
        st = flt_options_set(go, FLT_OPT_GIGE_DISCOVERY_TIMEOUT, o->timeout_ms);
    if (st == FLT_OK)
        st = flt_source_open_gige(camera, go, out);
    flt_options_destroy(go);
    if (st == FLT_ERR_TIMEOUT && answered)
        /* it answered the discovery, so it is there: a camera that does
         * not acknowledge our request for control is held by another
         * application (GigE Vision lets one control it at a time) */
        return say_failed(EXIT_FAILED,
                          "the camera at %s answers, but did not give us control: another "
                          "application probably controls it ('flatline-camera list' shows "
                          "who). %s",
                          camera, flt_last_error_message());
    if (st == FLT_ERR_NOT_FOUND || st == FLT_ERR_TIMEOUT)
        return say_failed(EXIT_NO_CAMERA, "%s", flt_last_error_message());
    if (st != FLT_OK)
        return library_failed("opening the GigE Vision camera", st);
    return 0;
}

/* Opens the camera -c names, or the first one found. */
static int open_camera(const options *o, flt_source **out) {
    *out = NULL;
    const char *sel = o->camera;
#ifdef FLT_CAMERA_SIMULATOR
    if (sel && strcmp(sel, "sim") == 0)
        return open_u3v("SIM-1", out);
#endif
    if (sel && strcmp(sel, "u3v") == 0)
        return open_u3v(NULL, out);
    if (sel && strncmp(sel, "u3v:", 4) == 0)
        return open_u3v(sel + 4, out);
    if (sel && strncmp(sel, "gige:", 5) == 0)
        return open_gige(sel + 5, o, out);
    if (sel && is_ipv4(sel))
        return open_gige(sel, o, out);

    /* A serial number (or nothing): USB3 Vision first, then the network. */
    flt_camera_list *list = NULL;
    size_t n = 0;
    if (flt_camera_list_create(g_usb, &list) == FLT_OK) {
        if (flt_camera_list_count(list, &n) != FLT_OK)
            n = 0;
        for (size_t i = 0; i < n; ++i) {
            const char *serial = "";
            if (flt_camera_list_get(list, i, NULL, NULL, &serial, NULL) == FLT_OK &&
                (!sel || strcmp(serial, sel) == 0)) {
                flt_camera_list_destroy(list);
                return open_u3v(sel, out);
            }
        }
        flt_camera_list_destroy(list);
    }
    if (sel)
        return open_gige(sel, o, out);
    flt_status st = flt_camera_list_create_gige(NULL, o->timeout_ms, &list);
    if (st != FLT_OK)
        return library_failed("GigE Vision discovery", st);
    n = 0;
    const char *address = "";
    if (flt_camera_list_count(list, &n) == FLT_OK && n > 0 &&
        flt_camera_list_address(list, 0, &address) == FLT_OK) {
        char first[64];
        snprintf(first, sizeof first, "%s", address);
        flt_camera_list_destroy(list);
        return open_gige(first, o, out);
    }
    flt_camera_list_destroy(list);
    return say_failed(EXIT_NO_CAMERA,
                      "no camera found: no USB3 Vision camera on USB (on Linux the udev rule "
                      "of lib/sources/deploy must let this user open it), and no GigE Vision "
                      "camera answered a discovery broadcast within %u ms",
                      (unsigned)o->timeout_ms);
}

/* ---------------------------------------------------------------------- */
/* The camera's description through its registers                          */
/* ---------------------------------------------------------------------- */

static int FLT_CALL read_camera(void *user, uint64_t address, void *out, size_t bytes) {
    return flt_source_read_memory((flt_source *)user, address, out, bytes) == FLT_OK ? 0 : 1;
}

static int FLT_CALL write_camera(void *user, uint64_t address, const void *in, size_t bytes) {
    return flt_source_write_memory((flt_source *)user, address, in, bytes) == FLT_OK ? 0 : 1;
}

static uint64_t get_le(const uint8_t *p, int bytes) {
    uint64_t v = 0;
    for (int i = bytes - 1; i >= 0; --i)
        v = (v << 8) | p[i];
    return v;
}

/* Reads `size` bytes of the camera's description file at `address`. */
static int read_file_bytes(flt_source *src, uint64_t address, uint64_t size, uint8_t **out) {
    if (size == 0 || size > (64u << 20))
        return say_failed(EXIT_FAILED, "the camera announces a description of %" PRIu64 " bytes",
                          size);
    *out = malloc((size_t)size);
    if (!*out)
        return say_failed(EXIT_FAILED, "out of memory for a %" PRIu64 "-byte description", size);
    flt_status st = flt_source_read_memory(src, address, *out, (size_t)size);
    if (st != FLT_OK) {
        free(*out);
        *out = NULL;
        return library_failed("reading the camera's description", st);
    }
    return 0;
}

/* USB3 Vision: the manifest table (an entry count, then 64-byte entries:
 * file info at +4 with the file type in bits 10..15, 0 XML and 1 ZIP,
 * the address at +8 and the size at +16, little-endian). */
static int read_u3v_description(flt_source *src, uint8_t **file, size_t *size) {
    uint64_t manifest = 0;
    flt_status st = flt_source_camera_value(src, FLT_CAMERA_MANIFEST_ADDRESS, &manifest);
    uint8_t head[8];
    if (st == FLT_OK)
        st = flt_source_read_memory(src, manifest, head, sizeof head);
    if (st != FLT_OK)
        return library_failed("reading the camera's manifest", st);
    const uint64_t entries = get_le(head, 8);
    for (uint64_t i = 0; i < entries && i < 64; ++i) {
        uint8_t e[64];
        st = flt_source_read_memory(src, manifest + 8 + 64 * i, e, sizeof e);
        if (st != FLT_OK)
            return library_failed("reading the camera's manifest", st);
        const uint32_t type = (uint32_t)(get_le(e + 4, 4) >> 10) & 0x3F;
        if (type > 1)
            continue;
        const uint64_t n = get_le(e + 16, 8);
        if (read_file_bytes(src, get_le(e + 8, 8), n, file))
            return EXIT_FAILED;
        *size = (size_t)n;
        return 0;
    }
    return say_failed(EXIT_FAILED, "the camera's manifest lists no GenICam XML or ZIP file");
}

/* GigE Vision: the first URL register (bootstrap 0x0200, 512 bytes),
 * "Local:name;address;length" with hexadecimal address and length. */
static int read_gige_description(flt_source *src, uint8_t **file, size_t *size) {
    char url[513];
    flt_status st = flt_source_read_memory(src, 0x0200, url, 512);
    if (st != FLT_OK)
        return library_failed("reading the camera's description URL", st);
    url[512] = '\0';
    if (strncmp(url, "Local:", 6) != 0 && strncmp(url, "local:", 6) != 0)
        return say_failed(EXIT_FAILED,
                          "the camera's description is at '%.200s': only a description in "
                          "the camera's memory (a Local: URL) is read",
                          url);
    const char *s1 = strchr(url + 6, ';');
    const char *s2 = s1 ? strchr(s1 + 1, ';') : NULL;
    char *end1 = NULL, *end2 = NULL;
    const uint64_t address = s2 ? strtoull(s1 + 1, &end1, 16) : 0;
    const uint64_t length = s2 ? strtoull(s2 + 1, &end2, 16) : 0;
    if (!s2 || end1 != s2 || end2 == s2 + 1)
        return say_failed(EXIT_FAILED, "the description URL '%.200s' is not name;address;length",
                          url);
    if (read_file_bytes(src, address, length, file))
        return EXIT_FAILED;
    *size = (size_t)length;
    /* An XML file padded with NULs to its register block ends at the
     * first (a ZIP archive starts with "PK"). */
    if (*size >= 2 && !((*file)[0] == 'P' && (*file)[1] == 'K')) {
        const uint8_t *nul = memchr(*file, 0, *size);
        if (nul)
            *size = (size_t)(nul - *file);
    }
    return 0;
}

/* The camera's description as a flt_genicam view of its live registers. */
static int open_description(flt_source *src, flt_genicam **out) {
    flt_source_kind kind;
    flt_status st = flt_source_kind_of(src, &kind);
    if (st != FLT_OK)
        return library_failed("the source", st);
    uint8_t *file = NULL;
    size_t size = 0;
    int rc = kind == FLT_SOURCE_GIGE ? read_gige_description(src, &file, &size)
                                     : read_u3v_description(src, &file, &size);
    if (rc)
        return rc;
    st = flt_genicam_load_memory(file, size, out);
    free(file);
    if (st != FLT_OK)
        return library_failed("loading the camera's description", st);
    st = flt_genicam_set_registers(*out, read_camera, write_camera, src);
    if (st != FLT_OK) {
        flt_genicam_destroy(*out);
        *out = NULL;
        return library_failed("the description's registers", st);
    }
    return 0;
}

/* ---------------------------------------------------------------------- */
/* Feature values as text                                                  */
/* ---------------------------------------------------------------------- */

static const char *type_name(flt_genicam_type t) {
    switch (t) {
        case FLT_GENICAM_INTEGER:
            return "Integer";
        case FLT_GENICAM_FLOAT:
            return "Float";
        case FLT_GENICAM_ENUMERATION:
            return "Enumeration";
        case FLT_GENICAM_BOOLEAN:
            return "Boolean";
        case FLT_GENICAM_COMMAND:
            return "Command";
        case FLT_GENICAM_STRING:
            return "String";
        case FLT_GENICAM_REGISTER:
            return "Register";
        case FLT_GENICAM_CATEGORY:
            return "Category";
        default:
            return "?";
    }
}

static const char *access_name(flt_genicam_access a) {
    switch (a) {
        case FLT_GENICAM_NOT_IMPLEMENTED:
            return "NI";
        case FLT_GENICAM_NOT_AVAILABLE:
            return "NA";
        case FLT_GENICAM_WRITE_ONLY:
            return "WO";
        case FLT_GENICAM_READ_ONLY:
            return "RO";
        case FLT_GENICAM_READ_WRITE:
            return "RW";
        default:
            return "??";
    }
}

/* The feature's value as text into buf, "" with status for a failure (the
 * library's message then says why). */
static flt_status value_text(flt_genicam *g, const char *name, flt_genicam_type type, char *buf,
                             size_t size) {
    flt_status st = FLT_OK;
    buf[0] = '\0';
    switch (type) {
        case FLT_GENICAM_INTEGER: {
            int64_t v = 0;
            st = flt_genicam_get_int(g, name, &v);
            if (st == FLT_OK)
                snprintf(buf, size, "%" PRId64, v);
            break;
        }
        case FLT_GENICAM_BOOLEAN: {
            int64_t v = 0;
            st = flt_genicam_get_int(g, name, &v);
            if (st == FLT_OK)
                snprintf(buf, size, "%s", v ? "true" : "false");
            break;
        }
        case FLT_GENICAM_FLOAT: {
            double v = 0;
            st = flt_genicam_get_float(g, name, &v);
            if (st == FLT_OK)
                snprintf(buf, size, "%.9g", v);
            break;
        }
        case FLT_GENICAM_ENUMERATION:
        case FLT_GENICAM_STRING: {
            const char *v = NULL;
            st = flt_genicam_get_string(g, name, &v);
            if (st == FLT_OK)
                snprintf(buf, size, type == FLT_GENICAM_STRING ? "\"%s\"" : "%s", v);
            break;
        }
        case FLT_GENICAM_COMMAND:
            snprintf(buf, size, "(command)");
            break;
        case FLT_GENICAM_REGISTER:
            snprintf(buf, size, "(register)");
            break;
        default:
            snprintf(buf, size, "-");
            break;
    }
    return st;
}

/* Bounds or entries, as a hint after the value: "[16 .. 4096 step 16]",
 * "{Off, On}". Only what evaluates; "" otherwise. */
static void range_text(flt_genicam *g, const char *name, flt_genicam_type type, char *buf,
                       size_t size) {
    buf[0] = '\0';
    if (type == FLT_GENICAM_INTEGER) {
        int64_t lo, hi, inc;
        if (flt_genicam_int_bounds(g, name, &lo, &hi, &inc) == FLT_OK &&
            (lo != INT64_MIN || hi != INT64_MAX)) {
            if (inc > 1)
                snprintf(buf, size, "[%" PRId64 " .. %" PRId64 " step %" PRId64 "]", lo, hi, inc);
            else
                snprintf(buf, size, "[%" PRId64 " .. %" PRId64 "]", lo, hi);
        }
    } else if (type == FLT_GENICAM_FLOAT) {
        double lo, hi;
        if (flt_genicam_float_bounds(g, name, &lo, &hi) == FLT_OK && (lo > -1e300 || hi < 1e300))
            snprintf(buf, size, "[%.6g .. %.6g]", lo, hi);
    } else if (type == FLT_GENICAM_ENUMERATION) {
        size_t n = 0;
        if (flt_genicam_enum_count(g, name, &n) != FLT_OK)
            return;
        size_t used = 0;
        for (size_t i = 0; i < n && used + 2 < size; ++i) {
            const char *entry = NULL;
            int available = 0;
            if (flt_genicam_enum_entry(g, name, i, &entry, NULL, &available) != FLT_OK ||
                !available)
                continue;
            int w = snprintf(buf + used, size - used, "%s%s", used ? ", " : "{", entry);
            if (w < 0 || (size_t)w >= size - used) {
                buf[used] = '\0';
                break;
            }
            used += (size_t)w;
        }
        if (used && used + 2 <= size)
            strcat(buf, "}");
    }
}

/* ---------------------------------------------------------------------- */
/* features                                                                */
/* ---------------------------------------------------------------------- */

typedef struct tree_walk {
    flt_genicam *g;
    int live; /* registers behind it: values and access evaluate */
    int all;
    size_t shown, hidden, failed;
    /* categories entered (a file listing a category inside itself must not
     * loop); the features shown (for --all: those under no category) */
    const char **entered;
    size_t entered_n, entered_cap;
    char *listed; /* per feature index: shown under a category */
} tree_walk;

static int entered_before(tree_walk *w, const char *name) {
    for (size_t i = 0; i < w->entered_n; ++i)
        if (strcmp(w->entered[i], name) == 0)
            return 1;
    if (w->entered_n == w->entered_cap) {
        size_t cap = w->entered_cap ? 2 * w->entered_cap : 64;
        const char **grown = realloc((void *)w->entered, cap * sizeof *grown);
        if (!grown)
            return 1; /* out of memory: do not descend */
        w->entered = grown;
        w->entered_cap = cap;
    }
    w->entered[w->entered_n++] = name;
    return 0;
}

static void mark_listed(tree_walk *w, const char *name) {
    size_t n = 0;
    if (flt_genicam_feature_count(w->g, &n) != FLT_OK)
        return;
    for (size_t i = 0; i < n; ++i) {
        const char *f = NULL;
        if (flt_genicam_feature_name(w->g, i, &f) == FLT_OK && strcmp(f, name) == 0) {
            w->listed[i] = 1;
            return;
        }
    }
}

/* One feature's line: name, access, value and unit, range. Returns 1 when
 * shown. */
static int show_feature(tree_walk *w, const char *name, int depth) {
    flt_genicam_type type;
    const char *kind = "", *unit = "";
    if (flt_genicam_feature_info(w->g, name, &type, &kind, &unit) != FLT_OK) {
        if (w->all)
            printf("%*s%-36s ??  (listed in its category, but the description lacks it)\n",
                   2 * depth, "", name);
        return 0;
    }
    char value[256], range[256];
    /* The access mode evaluates pIsImplemented, pIsAvailable, pIsLocked:
     * offline, without registers, only where they are constants ("--"
     * where the file leaves it to the registers). */
    flt_genicam_access a = FLT_GENICAM_READ_WRITE;
    const flt_status access_status = flt_genicam_get_access(w->g, name, &a);
    const char *access = access_status == FLT_OK ? access_name(a) : w->live ? "??" : "--";
    if (access_status == FLT_OK && !w->all &&
        (a == FLT_GENICAM_NOT_IMPLEMENTED || a == FLT_GENICAM_NOT_AVAILABLE)) {
        ++w->hidden;
        return 0;
    }
    if (w->live) {
        if (a == FLT_GENICAM_NOT_IMPLEMENTED || a == FLT_GENICAM_WRITE_ONLY) {
            snprintf(value, sizeof value, type == FLT_GENICAM_COMMAND ? "(command)" : "-");
        } else if (value_text(w->g, name, type, value, sizeof value) != FLT_OK) {
            ++w->failed;
            snprintf(value, sizeof value, "? %.200s", flt_last_error_message());
        }
        range_text(w->g, name, type, range, sizeof range);
    } else {
        /* offline: what the file declares */
        snprintf(value, sizeof value, "%s (%s)", type_name(type), kind);
        range[0] = '\0';
        if (type == FLT_GENICAM_ENUMERATION)
            range_text(w->g, name, type, range, sizeof range);
    }
    printf("%*s%-36s %-2s  %s%s%s%s%s\n", 2 * depth, "", name, access, value, unit[0] ? " " : "",
           unit, range[0] ? "  " : "", range);
    ++w->shown;
    mark_listed(w, name);
    return 1;
}

static void walk_category(tree_walk *w, const char *category, int depth) {
    for (size_t i = 0;; ++i) {
        const char *entry = NULL;
        if (flt_genicam_category_entry(w->g, category, i, &entry) != FLT_OK)
            break;
        flt_genicam_type type;
        if (flt_genicam_feature_info(w->g, entry, &type, NULL, NULL) == FLT_OK &&
            type == FLT_GENICAM_CATEGORY) {
            printf("%*s%s\n", 2 * depth, "", entry);
            if (!entered_before(w, entry))
                walk_category(w, entry, depth + 1);
            continue;
        }
        show_feature(w, entry, depth);
    }
}

static int print_tree(flt_genicam *g, int live, int all) {
    tree_walk w = {g, live, all, 0, 0, 0, NULL, 0, 0, NULL};
    size_t count = 0;
    if (flt_genicam_feature_count(g, &count) != FLT_OK)
        return library_failed("the description", FLT_ERR_INTERNAL);
    w.listed = calloc(count + 1, 1);
    if (!w.listed)
        return say_failed(EXIT_FAILED, "out of memory");
    const char *vendor = "", *model = "", *schema = "";
    if (flt_genicam_get_text(g, FLT_GENICAM_VENDOR_NAME, &vendor) != FLT_OK ||
        flt_genicam_get_text(g, FLT_GENICAM_MODEL_NAME, &model) != FLT_OK ||
        flt_genicam_get_text(g, FLT_GENICAM_SCHEMA_VERSION, &schema) != FLT_OK)
        vendor = model = schema = "";
    printf("# %s %s: GenICam description (schema %s), %zu features%s\n", vendor, model,
           schema[0] ? schema : "?", count, live ? "" : ", offline (no camera: declarations only)");
    printf("# name                                 access  value unit  [bounds] {entries}\n");
    flt_genicam_type root_type;
    if (flt_genicam_feature_info(g, "Root", &root_type, NULL, NULL) == FLT_OK &&
        root_type == FLT_GENICAM_CATEGORY) {
        entered_before(&w, "Root");
        walk_category(&w, "Root", 0);
    }
    /* Features under no category: all of them when the file has no tree,
     * else with --all. */
    int header = 0;
    for (size_t i = 0; i < count; ++i) {
        if (w.listed[i])
            continue;
        const char *name = NULL;
        if (flt_genicam_feature_name(g, i, &name) != FLT_OK)
            continue;
        if (!all && w.shown > 0) {
            ++w.hidden;
            continue;
        }
        if (!header) {
            printf("(not in any category)\n");
            header = 1;
        }
        show_feature(&w, name, 1);
    }
    if (w.hidden)
        printf("# %zu more feature%s not implemented, not available now, or in no category: "
               "--all shows them\n",
               w.hidden, w.hidden == 1 ? "" : "s");
    if (w.failed)
        printf("# %zu feature%s could not be read (the message after '?' says why)\n", w.failed,
               w.failed == 1 ? "" : "s");
    free(w.listed);
    free((void *)w.entered);
    return EXIT_DONE;
}

static int cmd_features(const options *o) {
    if (o->xml) {
        flt_genicam *g = NULL;
        flt_status st = flt_genicam_load(o->xml, &g);
        if (st != FLT_OK)
            return library_failed("loading the description", st);
        int rc = print_tree(g, 0, o->all);
        flt_genicam_destroy(g);
        return rc;
    }
    flt_source *src = NULL;
    int rc = open_camera(o, &src);
    if (rc)
        return rc;
    flt_genicam *g = NULL;
    rc = open_description(src, &g);
    if (!rc)
        rc = print_tree(g, 1, o->all);
    flt_genicam_destroy(g);
    flt_source_destroy(src);
    return rc;
}

/* ---------------------------------------------------------------------- */
/* get and set                                                             */
/* ---------------------------------------------------------------------- */

static int print_value(flt_genicam *g, const char *name) {
    flt_genicam_type type;
    const char *unit = "";
    flt_status st = flt_genicam_feature_info(g, name, &type, NULL, &unit);
    if (st != FLT_OK)
        return say_failed(EXIT_FAILED, "%s", flt_last_error_message());
    if (type == FLT_GENICAM_CATEGORY)
        return say_failed(EXIT_FAILED, "'%s' is a category: 'features' lists what it holds", name);
    char value[512];
    st = value_text(g, name, type, value, sizeof value);
    if (st != FLT_OK)
        return library_failed(name, st);
    printf("%s = %s%s%s\n", name, value, unit[0] ? " " : "", unit);
    return 0;
}

static int cmd_get(const options *o) {
    if (o->argc == 0)
        return say_failed(EXIT_USAGE, "get: name at least one feature (e.g. 'get Width')");
    flt_source *src = NULL;
    int rc = open_camera(o, &src);
    if (rc)
        return rc;
    flt_genicam *g = NULL;
    rc = open_description(src, &g);
    for (int i = 0; !rc && i < o->argc; ++i)
        rc = print_value(g, o->argv[i]);
    flt_genicam_destroy(g);
    flt_source_destroy(src);
    return rc;
}

/* A whole number in decimal or 0x hex, nothing after it. */
static int parse_int(const char *text, int64_t *out) {
    char *end = NULL;
    errno = 0;
    const long long v = strtoll(text, &end, 0);
    if (errno || end == text || *end)
        return -1;
    *out = (int64_t)v;
    return 0;
}

/* A finite number (the tool never calls setlocale: strtod reads '.'). */
static int parse_double(const char *text, double *out) {
    char *end = NULL;
    errno = 0;
    const double v = strtod(text, &end);
    if (errno || end == text || *end || !isfinite(v))
        return -1;
    *out = v;
    return 0;
}

static int set_one(flt_source *src, flt_genicam *g, const char *assignment) {
    char name[256];
    const char *eq = strchr(assignment, '=');
    const size_t name_len = eq ? (size_t)(eq - assignment) : strlen(assignment);
    if (name_len == 0 || name_len >= sizeof name)
        return say_failed(EXIT_USAGE, "set: '%s' is not NAME=VALUE", assignment);
    memcpy(name, assignment, name_len);
    name[name_len] = '\0';
    const char *value = eq ? eq + 1 : NULL;
    flt_genicam_type type;
    flt_status st = flt_genicam_feature_info(g, name, &type, NULL, NULL);
    if (st != FLT_OK)
        return say_failed(EXIT_FAILED, "%s", flt_last_error_message());
    if (type == FLT_GENICAM_COMMAND) {
        if (value && *value)
            return say_failed(EXIT_USAGE, "set: '%s' is a command: write 'set %s' alone", name,
                              name);
        st = flt_source_execute(src, name);
        if (st != FLT_OK)
            return library_failed(name, st);
        printf("%s executed\n", name);
        return 0;
    }
    if (!value)
        return say_failed(EXIT_USAGE, "set: '%s' needs a value: 'set %s=VALUE'", name, name);
    int64_t i = 0;
    double d = 0;
    switch (type) {
        case FLT_GENICAM_INTEGER:
            if (parse_int(value, &i))
                return say_failed(EXIT_USAGE, "set: %s is an integer; '%s' is not one", name,
                                  value);
            st = flt_source_set_int(src, name, i);
            break;
        case FLT_GENICAM_BOOLEAN:
            if (strcmp(value, "true") == 0 || strcmp(value, "1") == 0)
                i = 1;
            else if (strcmp(value, "false") == 0 || strcmp(value, "0") == 0)
                i = 0;
            else
                return say_failed(EXIT_USAGE, "set: %s is a boolean: true or false, not '%s'", name,
                                  value);
            st = flt_source_set_int(src, name, i);
            break;
        case FLT_GENICAM_FLOAT:
            if (parse_double(value, &d))
                return say_failed(EXIT_USAGE, "set: %s is a number; '%s' is not one", name, value);
            st = flt_source_set_float(src, name, d);
            break;
        case FLT_GENICAM_ENUMERATION:
            st = flt_source_set_enum(src, name, value);
            break;
        case FLT_GENICAM_STRING:
            /* the source has no string writer: through the description */
            st = flt_genicam_set_string(g, name, value);
            break;
        default:
            return say_failed(EXIT_FAILED, "set: %s is a %s, which the tool cannot write", name,
                              type_name(type));
    }
    if (st != FLT_OK)
        return library_failed(name, st);
    return print_value(g, name); /* read back: what the camera holds now */
}

static int cmd_set(const options *o) {
    if (o->argc == 0)
        return say_failed(EXIT_USAGE,
                          "set: give NAME=VALUE (e.g. 'set ExposureTime=5000'), or a command's "
                          "NAME");
    flt_source *src = NULL;
    int rc = open_camera(o, &src);
    if (rc)
        return rc;
    flt_genicam *g = NULL;
    rc = open_description(src, &g);
    for (int i = 0; !rc && i < o->argc; ++i)
        rc = set_one(src, g, o->argv[i]);
    flt_genicam_destroy(g);
    flt_source_destroy(src);
    return rc;
}

/* ---------------------------------------------------------------------- */
/* list                                                                    */
/* ---------------------------------------------------------------------- */

/* Who controls a GigE Vision camera: opening it takes its control
 * privilege, which the camera refuses while another application holds it
 * (and gives back when the source is destroyed). */
static const char *gige_control(const char *address, char *why, size_t size) {
    flt_options *go = NULL;
    flt_source *src = NULL;
    flt_status st = flt_options_create(&go);
    /* a fixed packet size: no negotiation, the probe stays short */
    if (st == FLT_OK)
        st = flt_options_set(go, FLT_OPT_GIGE_PACKET_SIZE, 1400);
    if (st == FLT_OK)
        st = flt_source_open_gige(address, go, &src);
    flt_options_destroy(go);
    flt_source_destroy(src);
    if (st == FLT_OK)
        return "free";
    snprintf(why, size, "%.300s", flt_last_error_message());
    /* It answered the discovery: a refusal, or silence, when asked for
     * control means that another application holds it (cameras answer the
     * request of a second application either way). */
    if (st == FLT_ERR_DEVICE || (st == FLT_ERR_TIMEOUT && strstr(why, "taking control")))
        return "controlled by another application";
    return "cannot tell";
}

static int cmd_list(const options *o) {
    int found = 0;
    flt_camera_list *list = NULL;
    size_t n = 0;
    flt_status st = flt_camera_list_create(g_usb, &list);
    printf("USB3 Vision:\n");
    if (st != FLT_OK) {
        printf("  (USB not available: %s)\n", flt_last_error_message());
    } else {
        if (flt_camera_list_count(list, &n) != FLT_OK)
            n = 0;
        for (size_t i = 0; i < n; ++i) {
            const char *vendor = "", *model = "", *serial = "";
            uint32_t speed = 0;
            if (flt_camera_list_get(list, i, &vendor, &model, &serial, &speed) != FLT_OK)
                continue;
            if (strcmp(vendor, "?") == 0) {
                /* could not be opened: the reason is the model string */
                printf("  [%zu] cannot be opened: %s (another program may hold it, or this "
                       "user may not open it)\n",
                       i, model);
                continue;
            }
            printf("  [%zu] %s %s  serial %s  %u Mbit/s  control: free  (-c u3v:%s)\n", i, vendor,
                   model, serial, (unsigned)speed, serial);
            ++found;
        }
        if (n == 0)
            printf("  none found\n");
        flt_camera_list_destroy(list);
    }

    printf("GigE Vision (discovery %s, %u ms):\n",
           o->gige_address ? o->gige_address : "on every IPv4 interface", (unsigned)o->timeout_ms);
    st = flt_camera_list_create_gige(o->gige_address, o->timeout_ms, &list);
    if (st != FLT_OK)
        return library_failed("GigE Vision discovery", st);
    n = 0;
    if (flt_camera_list_count(list, &n) != FLT_OK)
        n = 0;
    for (size_t i = 0; i < n; ++i) {
        const char *vendor = "", *model = "", *serial = "", *address = "";
        if (flt_camera_list_get(list, i, &vendor, &model, &serial, NULL) != FLT_OK ||
            flt_camera_list_address(list, i, &address) != FLT_OK)
            continue;
        char why[400] = "";
        const char *control = o->probe ? gige_control(address, why, sizeof why) : "not probed";
        printf("  [%zu] %s  %s %s  serial %s  control: %s  (-c %s)\n", i, address, vendor, model,
               serial, control, address);
        if (why[0] && strcmp(control, "free") != 0)
            printf("        %s\n", why);
        ++found;
    }
    if (n == 0)
        printf("  nothing answered within %u ms\n", (unsigned)o->timeout_ms);
    flt_camera_list_destroy(list);
    if (!found)
        return say_failed(EXIT_NO_CAMERA,
                          "no camera answered (USB3 Vision: is it plugged in, and may this user "
                          "open it? GigE Vision: is it on this subnet, and does the firewall "
                          "let UDP port 3956 through?)");
    return EXIT_DONE;
}

/* ---------------------------------------------------------------------- */
/* Frames: snap and stream                                                 */
/* ---------------------------------------------------------------------- */

static int pixel_bytes(flt_pixel_format f) {
    return f == FLT_PIXEL_MONO8 ? 1 : 2;
}

/* A frame copied out of the source. */
typedef struct frame_copy {
    uint8_t *pixels; /* height rows of width * pixel_bytes */
    uint32_t width, height;
    size_t stride;
    flt_pixel_format format;
    uint64_t block_id;
    double encoder_mm;
} frame_copy;

static int grab_frame(flt_source *src, uint32_t timeout_ms, frame_copy *out) {
    flt_status st = flt_source_start(src);
    if (st != FLT_OK)
        return library_failed("starting acquisition", st);
    const flt_frame *frame = NULL;
    st = flt_source_next(src, timeout_ms, &frame);
    int rc = 0;
    if (st == FLT_ERR_TIMEOUT)
        rc = say_failed(EXIT_FAILED,
                        "no frame within %u ms (%s); a triggered camera waits for its trigger: "
                        "try --frame-timeout or 'set TriggerMode=Off'",
                        (unsigned)timeout_ms, flt_last_error_message());
    else if (st != FLT_OK)
        rc = library_failed("waiting for a frame", st);
    else if (!frame)
        rc = say_failed(EXIT_FAILED, "the source has no frame");
    if (!rc) {
        const void *pixels = NULL;
        size_t stride = 0;
        st = flt_frame_info(frame, &pixels, &out->width, &out->height, &stride, &out->format,
                            &out->block_id, NULL, &out->encoder_mm);
        if (st != FLT_OK) {
            rc = library_failed("the frame", st);
        } else {
            out->stride = (size_t)out->width * (size_t)pixel_bytes(out->format);
            out->pixels = malloc(out->stride * out->height);
            if (!out->pixels)
                rc = say_failed(EXIT_FAILED, "out of memory for a %ux%u frame",
                                (unsigned)out->width, (unsigned)out->height);
            else
                for (uint32_t y = 0; y < out->height; ++y)
                    memcpy(out->pixels + (size_t)y * out->stride,
                           (const uint8_t *)pixels + (size_t)y * stride, out->stride);
        }
    }
    st = flt_source_stop(src);
    if (!rc && st != FLT_OK)
        rc = library_failed("stopping acquisition", st);
    return rc;
}

static unsigned pixel_at(const frame_copy *f, uint32_t x, uint32_t y) {
    const uint8_t *row = f->pixels + (size_t)y * f->stride;
    if (f->format == FLT_PIXEL_MONO8)
        return row[x];
    uint16_t v;
    memcpy(&v, row + 2 * (size_t)x, 2);
    return v;
}

static void put_rgb(uint8_t *rgb, const frame_copy *f, int64_t x, int64_t y, const uint8_t c[3]) {
    if (x < 0 || y < 0 || x >= (int64_t)f->width || y >= (int64_t)f->height)
        return;
    uint8_t *p = rgb + 3 * ((size_t)y * f->width + (size_t)x);
    p[0] = c[0];
    p[1] = c[1];
    p[2] = c[2];
}

/* The overlay colours (README.md has the legend). */
static const uint8_t k_line_colour[2][3] = {{0, 255, 0}, {0, 170, 255}};
static const uint8_t k_band_colour[2][3] = {{0, 120, 0}, {0, 80, 140}};
static const uint8_t k_saturated[3] = {255, 0, 0};
static const uint8_t k_edge[3] = {255, 150, 0};

/* The image column of the strip's edge at sensor x = x_mm on laser
 * `laser`'s line: the edge point on the laser plane, at the height of the
 * line's column nearest it (the strip's own, inside the edge), mapped into
 * the image. -1 when the line has no column to take the height from. */
static double edge_column(const flt_calib *calib, unsigned laser, const double *rows,
                          uint32_t width, double x_mm) {
    double best_dx = INFINITY, z = NAN;
    for (uint32_t u = 0; u < width; ++u) {
        const double row = rows[(size_t)laser * width + u];
        if (isnan(row))
            continue;
        const double image[2] = {(double)u, row};
        double plane[2];
        if (flt_calib_image_to_plane(calib, laser, 1, image, plane) != FLT_OK || isnan(plane[0]))
            continue;
        if (fabs(plane[0] - x_mm) < best_dx) {
            best_dx = fabs(plane[0] - x_mm);
            z = plane[1];
        }
    }
    if (isnan(z))
        return -1;
    const double plane[2] = {x_mm, z};
    double image[2];
    if (flt_calib_plane_to_image(calib, laser, 1, plane, image) != FLT_OK || isnan(image[0]))
        return -1;
    return image[0];
}

/* Per laser over the columns with a peak: the line's level and the
 * background's, as a fraction of full scale (median over the columns of
 * the pixel at the peak, and of the mean of the band's pixels 8..16 rows
 * away from it), for an operator setting exposure and laser power. */
static void line_contrast(const frame_copy *f, const double *rows, unsigned laser,
                          uint32_t band_first, uint32_t band_rows, double full_scale,
                          double *line_out, double *background_out) {
    double *line = malloc(sizeof(double) * f->width);
    double *back = malloc(sizeof(double) * f->width);
    size_t n = 0;
    *line_out = *background_out = NAN;
    if (!line || !back) {
        free(line);
        free(back);
        return;
    }
    for (uint32_t u = 0; u < f->width; ++u) {
        const double row = rows[(size_t)laser * f->width + u];
        if (isnan(row))
            continue;
        const int64_t r = (int64_t)floor(row + 0.5);
        double sum = 0;
        int count = 0;
        for (int d = 8; d <= 16; ++d)
            for (int s = -1; s <= 1; s += 2) {
                const int64_t y = r + s * d;
                if (y >= (int64_t)band_first && y < (int64_t)band_first + band_rows &&
                    y < (int64_t)f->height) {
                    sum += pixel_at(f, u, (uint32_t)y);
                    ++count;
                }
            }
        if (r < 0 || r >= (int64_t)f->height || count == 0)
            continue;
        line[n] = pixel_at(f, u, (uint32_t)r) / full_scale;
        back[n] = sum / count / full_scale;
        ++n;
    }
    if (n > 0) {
        /* medians by insertion sort: a frame has a few thousand columns */
        for (int k = 0; k < 2; ++k) {
            double *v = k ? back : line;
            for (size_t i = 1; i < n; ++i) {
                const double x = v[i];
                size_t j = i;
                while (j > 0 && v[j - 1] > x) {
                    v[j] = v[j - 1];
                    --j;
                }
                v[j] = x;
            }
        }
        *line_out = line[n / 2];
        *background_out = back[n / 2];
    }
    free(line);
    free(back);
}

/* Draws the overlay into rgb (the frame in grey, then bands, saturated
 * pixels, lines and edges) and prints what it shows. */
static int draw_overlay(const frame_copy *f, const flt_calib *calib, uint8_t *rgb) {
    const int bits = (int)f->format;
    const double full_scale = (double)((1u << bits) - 1u);
    size_t saturated_pixels = 0;
    for (uint32_t y = 0; y < f->height; ++y)
        for (uint32_t x = 0; x < f->width; ++x) {
            const unsigned v = pixel_at(f, x, y);
            const uint8_t g = (uint8_t)(bits == 8 ? v : v >> (bits - 8));
            const uint8_t grey[3] = {g, g, g};
            put_rgb(rgb, f, x, y, grey);
            if (v >= (unsigned)full_scale)
                ++saturated_pixels;
        }
    if (!calib) {
        for (uint32_t y = 0; y < f->height; ++y)
            for (uint32_t x = 0; x < f->width; ++x)
                if (pixel_at(f, x, y) >= (unsigned)full_scale)
                    put_rgb(rgb, f, x, y, k_saturated);
        printf("overlay: saturated pixels only (%zu; no --calib: the lines, bands and edges need "
               "the sensor's calibration)\n",
               saturated_pixels);
        return 0;
    }
    uint32_t cw = 0, ch = 0;
    flt_status st = flt_calib_get_frame_size(calib, &cw, &ch);
    if (st != FLT_OK)
        return library_failed("the calibration", st);
    if (cw != f->width || ch != f->height)
        return say_failed(EXIT_FAILED,
                          "the frame is %ux%u px but the calibration is for %ux%u: set the "
                          "camera's Width, Height (and OffsetY) to the sensor's window",
                          (unsigned)f->width, (unsigned)f->height, (unsigned)cw, (unsigned)ch);
    flt_extractor *ex = NULL;
    st = flt_extractor_create(calib, NULL, &ex);
    if (st != FLT_OK)
        return library_failed("the extractor", st);
    size_t fibers = 0;
    st = flt_extractor_fibers(ex, &fibers);
    double *height = malloc(sizeof(double) * (fibers + 1));
    double *slope = malloc(sizeof(double) * (fibers + 1));
    double *rows = malloc(sizeof(double) * 2 * (size_t)f->width);
    if (!height || !slope || !rows) {
        free(height);
        free(slope);
        free(rows);
        flt_extractor_destroy(ex);
        return say_failed(EXIT_FAILED, "out of memory");
    }
    if (st == FLT_OK)
        st = flt_extractor_process(ex, f->pixels, f->format, f->width, f->height, f->stride,
                                   isfinite(f->encoder_mm) ? f->encoder_mm : 0.0, fibers, NULL,
                                   height, slope, NULL);
    int rc = 0;
    if (st != FLT_OK) {
        /* e.g. an automatic band that finds no line to place it from:
         * the frame is still worth seeing */
        printf("overlay: the extractor could not read this frame: %s\n", flt_last_error_message());
        for (uint32_t y = 0; y < f->height; ++y)
            for (uint32_t x = 0; x < f->width; ++x)
                if (pixel_at(f, x, y) >= (unsigned)full_scale)
                    put_rgb(rgb, f, x, y, k_saturated);
    } else if ((st = flt_extractor_peaks(ex, f->width, rows)) != FLT_OK) {
        rc = library_failed("the extractor's peaks", st);
    } else {
        for (unsigned laser = 0; laser < 2; ++laser) {
            uint32_t first = 0, n = 0;
            if (flt_extractor_band(ex, laser, &first, &n) != FLT_OK)
                continue;
            /* the band's border rows, dashed every 8 px */
            for (uint32_t x = 0; x < f->width; ++x)
                if ((x / 8) % 2 == 0) {
                    put_rgb(rgb, f, x, first, k_band_colour[laser]);
                    put_rgb(rgb, f, x, (int64_t)first + n - 1, k_band_colour[laser]);
                }
            double left = NAN, right = NAN;
            unsigned strip_flags = 0;
            size_t peaks = 0, sat = 0;
            double fraction = 0, line = NAN, back = NAN;
            if (flt_extractor_strip(ex, laser, &left, &right, NULL, NULL, &strip_flags) != FLT_OK)
                strip_flags = FLT_STRIP_NONE;
            if (flt_extractor_saturation(ex, laser, &peaks, &sat, &fraction) != FLT_OK)
                peaks = sat = 0;
            line_contrast(f, rows, laser, first, n, full_scale, &line, &back);
            /* saturated pixels inside the band */
            for (uint32_t y = first; y < first + n && y < f->height; ++y)
                for (uint32_t x = 0; x < f->width; ++x)
                    if (pixel_at(f, x, y) >= (unsigned)full_scale)
                        put_rgb(rgb, f, x, y, k_saturated);
            /* the line: the sub-pixel peak row of every column */
            for (uint32_t u = 0; u < f->width; ++u) {
                const double r = rows[(size_t)laser * f->width + u];
                if (!isnan(r))
                    put_rgb(rgb, f, u, (int64_t)floor(r + 0.5), k_line_colour[laser]);
            }
            /* the strip's edges: a vertical mark across the band */
            double edge_u[2] = {-1, -1};
            const double edge_x[2] = {left, right};
            for (int e = 0; e < 2; ++e) {
                if (isnan(edge_x[e]))
                    continue;
                edge_u[e] = edge_column(calib, laser, rows, f->width, edge_x[e]);
                if (edge_u[e] < 0)
                    continue;
                const int64_t u = (int64_t)floor(edge_u[e] + 0.5);
                for (uint32_t y = first; y < first + n; ++y)
                    for (int64_t du = -1; du <= 1; ++du)
                        put_rgb(rgb, f, u + du, y, k_edge);
            }
            printf("laser %u: band rows %u..%u, %zu columns with a peak, %zu saturated "
                   "(%.1f %%), line %.0f %% / background %.0f %% of full scale",
                   laser, (unsigned)first, (unsigned)(first + n - 1), peaks, sat, 100.0 * fraction,
                   100.0 * line, 100.0 * back);
            if (strip_flags & FLT_STRIP_NONE)
                printf(", no strip\n");
            else
                printf(", strip %s%.1f mm (column %.0f) .. %s%.1f mm (column %.0f)\n",
                       (strip_flags & FLT_STRIP_LEFT_OPEN) ? "open " : "", left, edge_u[0],
                       (strip_flags & FLT_STRIP_RIGHT_OPEN) ? "open " : "", right, edge_u[1]);
        }
        printf("overlay: line 0 green, line 1 blue, bands dashed, saturated pixels red, strip "
               "edges orange (%zu saturated pixels in the frame)\n",
               saturated_pixels);
    }
    free(height);
    free(slope);
    free(rows);
    flt_extractor_destroy(ex);
    return rc;
}

static int cmd_snap(const options *o) {
    if (!o->output)
        return say_failed(EXIT_USAGE, "snap: name the PNG file with -o FILE.png");
    flt_calib *calib = NULL;
    if (o->calib) {
        flt_status st = flt_calib_load(o->calib, &calib);
        if (st != FLT_OK)
            return library_failed("loading the calibration", st);
    }
    flt_source *src = NULL;
    int rc = open_camera(o, &src);
#ifdef FLT_CAMERA_SIMULATOR
    /* the simulated camera's own sensor, when no file is named */
    const flt_calib *use_calib = calib ? calib : g_sim_calib;
#else
    const flt_calib *use_calib = calib;
#endif
    frame_copy f = {0};
    if (!rc)
        rc = grab_frame(src, o->frame_timeout_ms, &f);
    flt_source_destroy(src);
    char why[400];
    if (!rc && o->overlay) {
        uint8_t *rgb = malloc((size_t)f.width * f.height * 3);
        if (!rgb) {
            rc = say_failed(EXIT_FAILED, "out of memory");
        } else {
            rc = draw_overlay(&f, use_calib, rgb);
            png_image_desc im = {rgb, f.width, f.height, (size_t)f.width * 3, 3, 8, 0};
            if (!rc && png_write(o->output, &im, why, sizeof why))
                rc = say_failed(EXIT_FAILED, "%s", why);
            free(rgb);
        }
    } else if (!rc) {
        png_image_desc im = {f.pixels,     f.width, f.height,
                             f.stride,     1,       f.format == FLT_PIXEL_MONO8 ? 8 : 16,
                             (int)f.format};
        if (png_write(o->output, &im, why, sizeof why))
            rc = say_failed(EXIT_FAILED, "%s", why);
    }
    if (!rc)
        printf("wrote %s: %ux%u Mono%d, block %" PRIu64 "%s\n", o->output, (unsigned)f.width,
               (unsigned)f.height, (int)f.format, f.block_id, o->overlay ? ", with overlay" : "");
    free(f.pixels);
    flt_calib_destroy(calib);
    return rc;
}

static uint64_t counter(const flt_source *src, flt_source_counter c) {
    uint64_t v = 0;
    if (flt_source_count(src, c, &v) != FLT_OK)
        return 0;
    return v;
}

static void stream_line(const flt_source *src, int gige, double seconds, uint64_t frames,
                        double megabytes) {
    printf("%7.2f s  %7" PRIu64 " frames  %8.1f frames/s  %8.1f MB/s  dropped %" PRIu64
           "  lost %" PRIu64 "  timeouts %" PRIu64,
           seconds, frames, seconds > 0 ? (double)frames / seconds : 0.0,
           seconds > 0 ? megabytes / seconds : 0.0, counter(src, FLT_COUNT_DROPPED),
           counter(src, FLT_COUNT_LOST), counter(src, FLT_COUNT_TIMEOUTS));
    if (gige)
        printf("  packets missing %" PRIu64 " resent %" PRIu64 " (requests %" PRIu64 ")",
               counter(src, FLT_COUNT_PACKETS_MISSING), counter(src, FLT_COUNT_PACKETS_RESENT),
               counter(src, FLT_COUNT_RESEND_REQUESTS));
    printf("\n");
    fflush(stdout);
}

static int cmd_stream(const options *o) {
    flt_source *src = NULL;
    int rc = open_camera(o, &src);
    if (rc)
        return rc;
    flt_source_kind kind = FLT_SOURCE_U3V;
    if (flt_source_kind_of(src, &kind) != FLT_OK)
        kind = FLT_SOURCE_U3V;
    const int gige = kind == FLT_SOURCE_GIGE;
    flt_status st = flt_source_start(src);
    if (st != FLT_OK) {
        flt_source_destroy(src);
        return library_failed("starting acquisition", st);
    }
    const double t0 = now_s();
    double last = t0, megabytes = 0;
    uint64_t frames = 0;
    printf("streaming for %.3g s\n", o->seconds);
    while (now_s() - t0 < o->seconds) {
        const flt_frame *frame = NULL;
        st = flt_source_next(src, o->frame_timeout_ms, &frame);
        if (st == FLT_ERR_TIMEOUT) {
            printf("  no frame within %u ms: %s\n", (unsigned)o->frame_timeout_ms,
                   flt_last_error_message());
            continue;
        }
        if (st != FLT_OK) {
            rc = library_failed("acquisition", st);
            break;
        }
        if (!frame)
            break;
        uint32_t h = 0;
        size_t stride = 0;
        if (flt_frame_info(frame, NULL, NULL, &h, &stride, NULL, NULL, NULL, NULL) == FLT_OK)
            megabytes += (double)stride * h / 1e6;
        ++frames;
        const double t = now_s();
        if (t - last >= 1.0) {
            stream_line(src, gige, t - t0, frames, megabytes);
            last = t;
        }
    }
    const double seconds = now_s() - t0;
    st = flt_source_stop(src);
    if (!rc && st != FLT_OK)
        rc = library_failed("stopping acquisition", st);
    printf("total:\n");
    stream_line(src, gige, seconds, frames, megabytes);
    const char *why = flt_source_stream_error(src);
    if (why[0])
        printf("last frame dropped or lost: %s\n", why);
    flt_source_destroy(src);
    if (!rc && frames == 0)
        rc = say_failed(EXIT_FAILED, "no frame in %.3g s", seconds);
    return rc;
}

/* ---------------------------------------------------------------------- */
/* Arguments                                                               */
/* ---------------------------------------------------------------------- */

static int parse_ms(const char *flag, const char *text, uint32_t *out) {
    int64_t v = 0;
    if (!text || parse_int(text, &v) || v < 1 || v > 600000)
        return say_failed(EXIT_USAGE, "%s wants milliseconds, 1 .. 600000 (not '%s')", flag,
                          text ? text : "");
    *out = (uint32_t)v;
    return 0;
}

static int parse_args(int argc, char **argv, options *o, char **positional) {
    memset(o, 0, sizeof *o);
    o->probe = 1;
    o->timeout_ms = 500;
    o->frame_timeout_ms = 3000;
    o->seconds = 5;
    o->argv = positional;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *next = i + 1 < argc ? argv[i + 1] : NULL;
#define NEEDS_VALUE()                                                    \
  do {                                                                   \
    if (!next)                                                           \
      return say_failed(EXIT_USAGE, "%s needs a value (see --help)", a); \
    ++i;                                                                 \
  } while (0)
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            fputs(k_usage, stdout);
            exit(EXIT_DONE);
        } else if (strcmp(a, "--version") == 0) {
            printf("flatline-camera (libflatline %s)\n", flt_version_string());
            exit(EXIT_DONE);
        } else if (strcmp(a, "-c") == 0 || strcmp(a, "--camera") == 0) {
            NEEDS_VALUE();
            o->camera = next;
        } else if (strcmp(a, "--gige") == 0) {
            NEEDS_VALUE();
            o->gige_address = next;
        } else if (strcmp(a, "--no-probe") == 0) {
            o->probe = 0;
        } else if (strcmp(a, "--timeout") == 0) {
            NEEDS_VALUE();
            if (parse_ms(a, next, &o->timeout_ms))
                return EXIT_USAGE;
        } else if (strcmp(a, "--frame-timeout") == 0) {
            NEEDS_VALUE();
            if (parse_ms(a, next, &o->frame_timeout_ms))
                return EXIT_USAGE;
        } else if (strcmp(a, "--all") == 0) {
            o->all = 1;
        } else if (strcmp(a, "--xml") == 0) {
            NEEDS_VALUE();
            o->xml = next;
        } else if (strcmp(a, "-o") == 0 || strcmp(a, "--output") == 0) {
            NEEDS_VALUE();
            o->output = next;
        } else if (strcmp(a, "--overlay") == 0) {
            o->overlay = 1;
        } else if (strcmp(a, "--calib") == 0) {
            NEEDS_VALUE();
            o->calib = next;
        } else if (strcmp(a, "--seconds") == 0) {
            NEEDS_VALUE();
            if (parse_double(next, &o->seconds) || o->seconds <= 0 || o->seconds > 86400)
                return say_failed(EXIT_USAGE, "--seconds wants 0 < N <= 86400 (not '%s')", next);
        } else if (a[0] == '-' && a[1] != '\0') {
            return say_failed(EXIT_USAGE, "unknown option '%s' (see --help)", a);
        } else if (!o->command) {
            o->command = a;
        } else {
            positional[o->argc++] = argv[i];
        }
#undef NEEDS_VALUE
    }
    if (!o->command) {
        fputs(k_usage, stderr);
        return EXIT_USAGE;
    }
    return 0;
}

#ifdef _WIN32
/* The arguments as UTF-8 (argv holds them in the ANSI code page, which
 * cannot spell every file name). */
static char **utf8_argv(int *argc) {
    wchar_t **wide = CommandLineToArgvW(GetCommandLineW(), argc);
    if (!wide)
        return NULL;
    char **out = calloc((size_t)*argc + 1, sizeof *out);
    for (int i = 0; out && i < *argc; ++i) {
        const int n = WideCharToMultiByte(CP_UTF8, 0, wide[i], -1, NULL, 0, NULL, NULL);
        out[i] = malloc((size_t)(n > 0 ? n : 1));
        if (!out[i] || n <= 0 ||
            !WideCharToMultiByte(CP_UTF8, 0, wide[i], -1, out[i], n, NULL, NULL)) {
            if (out[i])
                out[i][0] = '\0';
        }
    }
    LocalFree(wide);
    return out;
}
#endif

int main(int argc, char **argv) {
#ifdef _WIN32
    char **wide_argv = utf8_argv(&argc);
    if (wide_argv)
        argv = wide_argv;
#endif
    char **positional = calloc((size_t)argc + 1, sizeof *positional);
    if (!positional)
        return say_failed(EXIT_FAILED, "out of memory");
    options o;
    int rc = parse_args(argc, argv, &o, positional);
#ifdef FLT_CAMERA_SIMULATOR
    /* the test build's USB bus: one simulated camera, "SIM-1" */
    if (!rc && make_simulated_camera())
        rc = EXIT_FAILED;
#endif
    if (!rc) {
        if (strcmp(o.command, "list") == 0)
            rc = cmd_list(&o);
        else if (strcmp(o.command, "features") == 0)
            rc = cmd_features(&o);
        else if (strcmp(o.command, "get") == 0)
            rc = cmd_get(&o);
        else if (strcmp(o.command, "set") == 0)
            rc = cmd_set(&o);
        else if (strcmp(o.command, "snap") == 0)
            rc = cmd_snap(&o);
        else if (strcmp(o.command, "stream") == 0)
            rc = cmd_stream(&o);
        else
            rc = say_failed(EXIT_USAGE, "unknown command '%s' (see --help)", o.command);
    }
#ifdef FLT_CAMERA_SIMULATOR
    flt_u3v_sim_destroy(g_bus);
    flt_sim_destroy(g_sim);
    flt_calib_destroy(g_sim_calib);
#endif
    free(positional);
    return rc;
}
