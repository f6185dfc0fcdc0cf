// SPDX-License-Identifier: Apache-2.0
/*
 * USB3 Vision client against the simulated camera (flatline/source.h): the
 * real client code (discovery, GenCP, bootstrap, GenICam XML, SIRM set-up,
 * transfer pool and frame assembly) runs over the simulated transport.
 * Every number asserted below is what the camera's registers hold or what
 * the stream must deliver exactly: there is no noise, so tolerances are 0.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "flatline/flatline.h"
#include "flatline/source.h"
#include "flatline/testing.h"

#define ok(call) assert_int_equal((call), FLT_OK)

static void assert_error(flt_status got, flt_status want, const char *needle) {
    if (got != want)
        fail_msg("status %s, expected %s (%s)", flt_status_string(got), flt_status_string(want),
                 flt_last_error_message());
    if (needle && !strstr(flt_last_error_message(), needle))
        fail_msg("message '%s' does not mention '%s'", flt_last_error_message(), needle);
}

/* The pattern the simulated camera sends (flatline/source.h). */
static uint8_t pattern(uint64_t block, size_t i) {
    return (uint8_t)(block * 131u + i * 7u + (i >> 9));
}

/* The bus as the transport flt_source_open_u3v() and
 * flt_camera_list_create() take (NULL for a NULL bus). */
static flt_usb_transport *usb(flt_u3v_sim *bus) {
    flt_usb_transport *t = NULL;
    if (bus && flt_u3v_sim_transport(bus, &t) != FLT_OK)
        abort();
    return t;
}

/* A bus with two cameras: 100 x 30 Mono8 and 64 x 32 Mono16. */
static flt_u3v_sim *make_bus(void) {
    flt_u3v_sim *bus = NULL;
    ok(flt_u3v_sim_create(&bus));
    size_t index = 99;
    ok(flt_u3v_sim_add_camera(bus, "Flatline Vision", "Sim-100", "SN0001", 100, 30, FLT_PIXEL_MONO8,
                              &index));
    assert_int_equal(index, 0);
    ok(flt_u3v_sim_add_camera(bus, "Other Optics", "Sim-64", "SN0002", 64, 32, FLT_PIXEL_MONO16,
                              &index));
    assert_int_equal(index, 1);
    return bus;
}

static flt_source *open_camera(flt_u3v_sim *bus, const char *serial, flt_options *options) {
    flt_source *src = NULL;
    flt_status st = flt_source_open_u3v(usb(bus), serial, options, &src);
    if (st != FLT_OK)
        fail_msg("open: %s", flt_last_error_message());
    return src;
}

static uint64_t count(const flt_source *src, flt_source_counter c) {
    uint64_t v = 0;
    ok(flt_source_count(src, c, &v));
    return v;
}

static uint64_t sim_value(const flt_u3v_sim *bus, size_t cam, flt_u3v_sim_param p) {
    uint64_t v = 0;
    ok(flt_u3v_sim_get(bus, cam, p, &v));
    return v;
}

static uint32_t peek(const flt_u3v_sim *bus, size_t cam, uint64_t address) {
    uint32_t v = 0;
    ok(flt_u3v_sim_peek(bus, cam, address, &v));
    return v;
}

/* --- discovery, open, bootstrap ---------------------------------------- */

static void test_discovery_lists_cameras_only(void **state) {
    (void)state;
    flt_u3v_sim *bus = make_bus();
    ok(flt_u3v_sim_set(bus, 1, FLT_U3V_SIM_SPEED_MBPS, 480));
    flt_camera_list *list = NULL;
    ok(flt_camera_list_create(usb(bus), &list));
    size_t n = 0;
    ok(flt_camera_list_count(list, &n));
    assert_int_equal(n, 2); /* the keyboard on the bus is skipped */
    const char *vendor, *model, *serial;
    uint32_t speed = 0;
    ok(flt_camera_list_get(list, 0, &vendor, &model, &serial, &speed));
    assert_string_equal(vendor, "Flatline Vision");
    assert_string_equal(model, "Sim-100");
    assert_string_equal(serial, "SN0001");
    assert_int_equal(speed, 5000);
    ok(flt_camera_list_get(list, 1, &vendor, &model, &serial, &speed));
    assert_string_equal(serial, "SN0002");
    assert_int_equal(speed, 480);
    assert_error(flt_camera_list_get(list, 2, NULL, NULL, NULL, NULL), FLT_ERR_INVALID_ARGUMENT,
                 "'index' = 2");
    flt_camera_list_destroy(list);
    flt_camera_list_destroy(NULL);
    flt_u3v_sim_destroy(bus);
}

static void test_open_reads_bootstrap_registers(void **state) {
    (void)state;
    flt_u3v_sim *bus = make_bus();
    ok(flt_u3v_sim_set(bus, 1, FLT_U3V_SIM_RESPONSE_TIME_MS, 750));
    flt_source *src = open_camera(bus, "SN0002", NULL);
    assert_int_equal(sim_value(bus, 1, FLT_U3V_SIM_OPEN), 1);
    const char *s = NULL;
    ok(flt_source_camera_string(src, FLT_CAMERA_VENDOR, &s));
    assert_string_equal(s, "Other Optics");
    ok(flt_source_camera_string(src, FLT_CAMERA_MODEL, &s));
    assert_string_equal(s, "Sim-64");
    ok(flt_source_camera_string(src, FLT_CAMERA_SERIAL, &s));
    assert_string_equal(s, "SN0002");
    ok(flt_source_camera_string(src, FLT_CAMERA_FAMILY, &s));
    assert_string_equal(s, "Sim");
    ok(flt_source_camera_string(src, FLT_CAMERA_DEVICE_VERSION, &s));
    assert_string_equal(s, "1.0.0");
    uint64_t v = 0;
    ok(flt_source_camera_value(src, FLT_CAMERA_GENCP_VERSION, &v));
    assert_int_equal(v, 0x00010000);
    ok(flt_source_camera_value(src, FLT_CAMERA_U3V_VERSION, &v));
    assert_int_equal(v, 0x00010000);
    ok(flt_source_camera_value(src, FLT_CAMERA_RESPONSE_TIME_MS, &v));
    assert_int_equal(v, 750);
    /* timeout = max(floor 200 ms, response time 750 ms), and it is used */
    ok(flt_source_camera_value(src, FLT_CAMERA_CONTROL_TIMEOUT_MS, &v));
    assert_int_equal(v, 750);
    assert_int_equal(sim_value(bus, 1, FLT_U3V_SIM_LAST_READ_TIMEOUT_MS), 750);
    ok(flt_source_camera_value(src, FLT_CAMERA_MAX_COMMAND_BYTES, &v));
    assert_int_equal(v, 1024);
    ok(flt_source_camera_value(src, FLT_CAMERA_MAX_ACK_BYTES, &v));
    assert_int_equal(v, 1024);
    ok(flt_source_camera_value(src, FLT_CAMERA_SIRM_ADDRESS, &v));
    assert_int_equal(v, 0x2000);
    ok(flt_source_camera_value(src, FLT_CAMERA_MANIFEST_ADDRESS, &v));
    assert_int_equal(v, 0x3000);
    ok(flt_source_camera_value(src, FLT_CAMERA_XML_ZIPPED, &v));
    assert_int_equal(v, 1);
    ok(flt_source_camera_value(src, FLT_CAMERA_SPEED_MBPS, &v));
    assert_int_equal(v, 5000);
    flt_source_destroy(src);
    assert_int_equal(sim_value(bus, 1, FLT_U3V_SIM_OPEN), 0);

    /* NULL takes the first camera; a floor above the response time wins */
    flt_options *o = NULL;
    ok(flt_options_create(&o));
    ok(flt_options_set(o, FLT_OPT_U3V_CONTROL_TIMEOUT, 1000));
    src = open_camera(bus, NULL, o);
    ok(flt_source_camera_string(src, FLT_CAMERA_SERIAL, &s));
    assert_string_equal(s, "SN0001");
    ok(flt_source_camera_value(src, FLT_CAMERA_CONTROL_TIMEOUT_MS, &v));
    assert_int_equal(v, 1000);
    assert_int_equal(sim_value(bus, 0, FLT_U3V_SIM_LAST_READ_TIMEOUT_MS), 1000);
    /* a camera already open elsewhere is busy */
    flt_source *again = NULL;
    assert_error(flt_source_open_u3v(usb(bus), "SN0001", NULL, &again), FLT_ERR_DEVICE, "busy");
    assert_null(again);
    flt_source_destroy(src);
    flt_options_destroy(o);

    assert_error(flt_source_open_u3v(usb(bus), "NOPE-7", NULL, &src), FLT_ERR_NOT_FOUND,
                 "'NOPE-7'");
    assert_non_null(strstr(flt_last_error_message(), "SN0001"));
    assert_null(src);
    flt_u3v_sim_destroy(bus);
}

static void test_gencp_chunks_to_the_device_limits(void **state) {
    (void)state;
    /* 76-byte acks carry 64 data bytes; 64-byte commands carry 44. The
     * camera refuses anything larger, so opening only works if every read
     * and write is chunked. */
    flt_u3v_sim *bus = make_bus();
    ok(flt_u3v_sim_set(bus, 0, FLT_U3V_SIM_MAX_ACK_BYTES, 76));
    ok(flt_u3v_sim_set(bus, 0, FLT_U3V_SIM_MAX_COMMAND_BYTES, 64));
    flt_source *src = open_camera(bus, "SN0001", NULL);
    uint64_t xml_bytes = 0, ack = 0;
    ok(flt_source_camera_value(src, FLT_CAMERA_XML_BYTES, &xml_bytes));
    ok(flt_source_camera_value(src, FLT_CAMERA_MAX_ACK_BYTES, &ack));
    assert_int_equal(ack, 76);
    const uint64_t commands = sim_value(bus, 0, FLT_U3V_SIM_COMMANDS);
    /* at least one READMEM per 64 bytes of the XML file */
    assert_true(commands >= (xml_bytes + 63) / 64);
    /* a 100-byte write goes out as 44 + 44 + 12 bytes */
    uint8_t name[100], back[100];
    for (int i = 0; i < 60; ++i)
        name[i] = (uint8_t)('a' + i % 26);
    name[60] = 0;
    const uint64_t before = sim_value(bus, 0, FLT_U3V_SIM_COMMANDS);
    ok(flt_source_write_memory(src, 0x184, name, 61));
    assert_int_equal(sim_value(bus, 0, FLT_U3V_SIM_COMMANDS) - before, 2);
    ok(flt_source_read_memory(src, 0x184, back, 61));
    assert_memory_equal(name, back, 61);
    flt_source_destroy(src);

    /* an unzipped XML reads the same */
    ok(flt_u3v_sim_set(bus, 1, FLT_U3V_SIM_XML_ZIPPED, 0));
    src = open_camera(bus, "SN0002", NULL);
    uint64_t zipped = 1;
    ok(flt_source_camera_value(src, FLT_CAMERA_XML_ZIPPED, &zipped));
    assert_int_equal(zipped, 0);
    int64_t width = 0;
    ok(flt_source_get_int(src, "Width", &width));
    assert_int_equal(width, 64);
    flt_source_destroy(src);
    flt_u3v_sim_destroy(bus);
}

/* --- GenICam features ------------------------------------------------------ */

static void test_features_resolve_from_the_xml(void **state) {
    (void)state;
    flt_u3v_sim *bus = make_bus();
    flt_source *src = open_camera(bus, "SN0001", NULL);
    int64_t v = 0;
    ok(flt_source_get_int(src, "Width", &v)); /* Integer -> pValue -> IntReg */
    assert_int_equal(v, 100);
    ok(flt_source_set_int(src, "Height", 24)); /* IntReg */
    assert_int_equal(peek(bus, 0, 0x10004), 24);
    ok(flt_source_set_int(src, "OffsetY", 6)); /* MaskedIntReg bits 0..15 */
    assert_int_equal(peek(bus, 0, 0x1000C), 6);
    ok(flt_source_get_int(src, "OffsetY", &v));
    assert_int_equal(v, 6);
    assert_error(flt_source_set_int(src, "OffsetY", 70000), FLT_ERR_INVALID_ARGUMENT, "16-bit");
    ok(flt_source_set_enum(src, "PixelFormat", "Mono12"));
    assert_int_equal(peek(bus, 0, 0x10008), 0x01100005);
    ok(flt_source_set_enum(src, "PixelFormat", "Mono8"));
    ok(flt_source_set_enum(src, "TriggerSelector", "FrameStart"));
    ok(flt_source_set_enum(src, "TriggerMode", "On"));
    ok(flt_source_set_enum(src, "TriggerSource", "Encoder0"));
    assert_int_equal(peek(bus, 0, 0x10024), 1);
    assert_int_equal(peek(bus, 0, 0x10028), 2);
    assert_error(flt_source_set_enum(src, "TriggerMode", "Sometimes"), FLT_ERR_NOT_FOUND,
                 "entries: Off, On");
    ok(flt_source_set_float(src, "Gain", 6.5)); /* Float -> FloatReg (float32) */
    double g = 0;
    ok(flt_source_get_float(src, "Gain", &g));
    assert_true(g == 6.5); /* 6.5 is exact in float32 */

    /* the camera's own checks come back as GenCP statuses */
    assert_error(flt_source_set_int(src, "Height", 1000), FLT_ERR_DEVICE,
                 "0x8002 (invalid parameter)");
    /* features behind formulas: ExposureTime is a Converter (FROM - OFFSET
     * with OFFSET 0) of ExposureTimeRaw, PayloadSize an IntSwissKnife W * H */
    ok(flt_source_set_float(src, "ExposureTime", 250.0));
    assert_int_equal(peek(bus, 0, 0x1001C), 250);
    double e = 0;
    ok(flt_source_get_float(src, "ExposureTime", &e));
    assert_true(e == 250.0);
    ok(flt_source_get_int(src, "PayloadSize", &v));
    assert_int_equal(v, 100 * 24);
    /* a feature the camera lacks: named, with the way out; a register by
     * address then stands in for it */
    assert_error(flt_source_get_int(src, "Bogus", &v), FLT_ERR_NOT_FOUND,
                 "'Bogus' is not in the camera's description");
    assert_non_null(strstr(flt_last_error_message(), "flt_source_map_feature"));
    ok(flt_source_map_feature(src, "Bogus", 0x1001C, 4, 0));
    ok(flt_source_set_int(src, "Bogus", 300));
    assert_int_equal(peek(bus, 0, 0x1001C), 300);
    ok(flt_source_get_float(src, "ExposureTime", &e)); /* the engine reads it afresh */
    assert_true(e == 300.0);
    assert_error(flt_source_map_feature(src, "X", 0x10000, 3, 0), FLT_ERR_INVALID_ARGUMENT,
                 "'length' = 3");
    assert_error(flt_source_execute(src, "Width"), FLT_ERR_INVALID_ARGUMENT, "not a Command");
    /* a register that does not exist */
    uint8_t b[4];
    assert_error(flt_source_read_memory(src, 0x900000, b, 4), FLT_ERR_DEVICE,
                 "0x8003 (invalid address)");
    ok(flt_source_get_int(src, "Width", &v)); /* still usable */
    flt_source_destroy(src);
    flt_u3v_sim_destroy(bus);
}

/* --- streaming ------------------------------------------------------------------ */

static void test_streams_1000_frames_byte_exact(void **state) {
    (void)state;
    flt_u3v_sim *bus = make_bus();
    flt_options *o = NULL;
    ok(flt_options_create(&o));
    /* 3000-byte payload in 1024-byte transfers: 2 transfers + a final one
     * of 952 bytes padded to 1024 (512-byte alignment), which is whole
     * packets, so the trailer lands in the same host transfer. */
    ok(flt_options_set(o, FLT_OPT_U3V_TRANSFER_SIZE, 1024));
    ok(flt_options_set(o, FLT_OPT_SOURCE_ENCODER_STEP, 2.5));
    ok(flt_options_set(o, FLT_OPT_SOURCE_ENCODER_START, 100.0));
    flt_source *src = open_camera(bus, "SN0001", o);
    ok(flt_source_start(src));
    /* While streaming the host holds TLParamsLocked = 1, and Width (its
     * pIsLocked) refuses a change that would break the stream. */
    int64_t locked = 0;
    ok(flt_source_get_int(src, "TLParamsLocked", &locked));
    assert_int_equal(locked, 1);
    assert_error(flt_source_set_int(src, "Width", 64), FLT_ERR_STATE, "locked");
    uint64_t v = 0;
    ok(flt_source_camera_value(src, FLT_CAMERA_PAYLOAD_BYTES, &v));
    assert_int_equal(v, 3000);
    ok(flt_source_camera_value(src, FLT_CAMERA_ALIGNMENT, &v));
    assert_int_equal(v, 512);
    ok(flt_source_camera_value(src, FLT_CAMERA_TRANSFER_BYTES, &v));
    assert_int_equal(v, 1024);
    assert_int_equal(peek(bus, 0, 0x2000 + 0x1C), 1024);
    ok(flt_source_camera_value(src, FLT_CAMERA_TRANSFER_COUNT, &v));
    assert_int_equal(v, 2);
    assert_int_equal(peek(bus, 0, 0x2000 + 0x20), 2);
    ok(flt_source_camera_value(src, FLT_CAMERA_FINAL_TRANSFER_BYTES, &v));
    assert_int_equal(v, 1024);
    assert_int_equal(peek(bus, 0, 0x2000 + 0x24), 1024);
    assert_int_equal(peek(bus, 0, 0x2000 + 0x18), 512); /* max leader: 52 -> 512 */
    assert_int_equal(peek(bus, 0, 0x2000 + 0x2C), 512); /* max trailer: 32 -> 512 */
    assert_int_equal(peek(bus, 0, 0x2000 + 0x04), 1);   /* SI control */
    assert_int_equal(sim_value(bus, 0, FLT_U3V_SIM_ACQUIRING), 1);

    for (uint64_t k = 1; k <= 1000; ++k) {
        const flt_frame *f = NULL;
        ok(flt_source_next(src, 100, &f));
        const void *pixels;
        uint32_t w, h;
        size_t stride;
        flt_pixel_format format;
        uint64_t block, ts;
        double enc;
        ok(flt_frame_info(f, &pixels, &w, &h, &stride, &format, &block, &ts, &enc));
        assert_int_equal(block, k);
        assert_int_equal(w, 100);
        assert_int_equal(h, 30);
        assert_int_equal(stride, 100);
        assert_int_equal(format, FLT_PIXEL_MONO8);
        assert_int_equal(ts, k * 1000000ull);
        /* fixed step: 100 + 2.5 (block - 1), exact in binary */
        assert_true(enc == 100.0 + 2.5 * (double)(k - 1));
        const uint8_t *p = pixels;
        for (size_t i = 0; i < 3000; ++i)
            if (p[i] != pattern(k, i))
                fail_msg("frame %llu byte %zu", (unsigned long long)k, i);
    }
    assert_int_equal(count(src, FLT_COUNT_FRAMES), 1000);
    assert_int_equal(count(src, FLT_COUNT_DROPPED), 0);
    assert_int_equal(count(src, FLT_COUNT_LOST), 0);
    assert_int_equal(count(src, FLT_COUNT_BAD_PACKETS), 0);
    assert_string_equal(flt_source_stream_error(src), "");
    ok(flt_source_stop(src));
    assert_int_equal(peek(bus, 0, 0x2000 + 0x04), 0);
    assert_int_equal(sim_value(bus, 0, FLT_U3V_SIM_ACQUIRING), 0);
    ok(flt_source_stop(src));                               /* a no-op */
    ok(flt_source_get_int(src, "TLParamsLocked", &locked)); /* released */
    assert_int_equal(locked, 0);
    ok(flt_source_set_int(src, "Width", 100));
    const flt_frame *f = NULL;
    assert_error(flt_source_next(src, 10, &f), FLT_ERR_STATE, "not started");
    flt_source_destroy(src);
    flt_options_destroy(o);
    flt_u3v_sim_destroy(bus);
}

static void test_stream_with_fine_alignment_and_encoder_chunk(void **state) {
    (void)state;
    /* 8-byte alignment: the final transfer is exactly the 952 remaining
     * bytes plus the 24-byte encoder chunk, a short packet. Mono16 frame. */
    flt_u3v_sim *bus = make_bus();
    ok(flt_u3v_sim_set(bus, 1, FLT_U3V_SIM_ALIGNMENT_LOG2, 3));
    ok(flt_u3v_sim_set(bus, 1, FLT_U3V_SIM_ENCODER_CHUNK, 1));
    flt_options *o = NULL;
    ok(flt_options_create(&o));
    ok(flt_options_set(o, FLT_OPT_SOURCE_ENCODER_MODE, FLT_ENCODER_CHUNK));
    ok(flt_options_set(o, FLT_OPT_U3V_TRANSFER_SIZE, 1000));
    flt_source *src = open_camera(bus, "SN0002", o);
    ok(flt_source_start(src));
    uint64_t v = 0;
    ok(flt_source_camera_value(src, FLT_CAMERA_PAYLOAD_BYTES, &v));
    assert_int_equal(v, 64 * 32 * 2 + 24);
    ok(flt_source_camera_value(src, FLT_CAMERA_TRANSFER_BYTES, &v));
    assert_int_equal(v, 1000);
    ok(flt_source_camera_value(src, FLT_CAMERA_FINAL_TRANSFER_BYTES, &v));
    assert_int_equal(v, 120); /* 4120 - 4 * 1000 = 120, a multiple of 8 */
    for (uint64_t k = 1; k <= 200; ++k) {
        const flt_frame *f = NULL;
        ok(flt_source_next(src, 100, &f));
        const void *pixels;
        size_t stride;
        flt_pixel_format format;
        uint64_t block;
        double enc;
        ok(flt_frame_info(f, &pixels, NULL, NULL, &stride, &format, &block, NULL, &enc));
        assert_int_equal(block, k);
        assert_int_equal(format, FLT_PIXEL_MONO16);
        assert_int_equal(stride, 128);
        /* chunk counter = block * 3 mm / 10 um; 0.01 mm per count */
        assert_true(fabs(enc - 3.0 * (double)k) < 1e-9);
        const uint8_t *p = pixels;
        for (size_t i = 0; i < 64 * 32 * 2; ++i)
            if (p[i] != pattern(k, i))
                fail_msg("frame %llu byte %zu", (unsigned long long)k, i);
    }
    assert_int_equal(count(src, FLT_COUNT_DROPPED), 0);
    flt_source_destroy(src);
    flt_options_destroy(o);
    flt_u3v_sim_destroy(bus);
}

/* --- failure modes ------------------------------------------------------------ */

typedef struct fault_case {
    flt_u3v_fault fault;
    uint32_t count;
    flt_source_counter counter; /* the counter that must grow by `grows` */
    uint64_t grows;
    uint64_t dropped;    /* DROPPED grows by this */
    int frames_missing;  /* frames at `at` .. not delivered */
    int timeouts;        /* next() calls that time out */
    const char *message; /* in flt_source_stream_error() */
} fault_case;

static void test_each_failure_mode_is_counted_and_recovers(void **state) {
    (void)state;
    const fault_case cases[] = {
        {FLT_U3V_FAULT_SHORT_FRAME, 0, FLT_COUNT_SHORT, 1, 1, 1, 0, "short frame"},
        {FLT_U3V_FAULT_LEADER_MID_FRAME, 0, FLT_COUNT_INCOMPLETE, 1, 1, 1, 0, "new leader"},
        {FLT_U3V_FAULT_OVERFLOW, 0, FLT_COUNT_OVERFLOW, 1, 1, 1, 0, "overflowed its 1000-byte"},
        {FLT_U3V_FAULT_SKIP_BLOCK_IDS, 3, FLT_COUNT_LOST, 3, 0, 3, 0, "never arrived"},
        {FLT_U3V_FAULT_STREAM_TIMEOUT, 0, FLT_COUNT_TIMEOUT_DROPPED, 1, 1, 1, 1, "no data"},
        {FLT_U3V_FAULT_GARBAGE, 0, FLT_COUNT_BAD_PACKETS, 1, 0, 0, 0, "outside any frame"},
        {FLT_U3V_FAULT_TRAILER_STATUS, 0, FLT_COUNT_SHORT, 1, 1, 1, 0, "0xa101"},
        {FLT_U3V_FAULT_SUBMIT_REFUSED, 1, FLT_COUNT_SUBMIT_REFUSED, 1, 1, 1, 0, "refused"},
    };
    /* 8-byte alignment, 1000-byte transfers: host buffers of 1000 bytes
     * are no whole number of 512-byte packets, so a transfer one packet
     * too long overflows on the host as in the field. */
    flt_u3v_sim *bus = make_bus();
    ok(flt_u3v_sim_set(bus, 0, FLT_U3V_SIM_ALIGNMENT_LOG2, 3));
    flt_options *o = NULL;
    ok(flt_options_create(&o));
    ok(flt_options_set(o, FLT_OPT_U3V_TRANSFER_SIZE, 1000));
    flt_source *src = open_camera(bus, "SN0001", o);
    ok(flt_source_start(src));
    uint64_t block = 0;
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        const fault_case *fc = &cases[c];
        /* settle: two good frames, and find where the stream is */
        for (int i = 0; i < 2; ++i) {
            const flt_frame *f = NULL;
            ok(flt_source_next(src, 100, &f));
            ok(flt_frame_info(f, NULL, NULL, NULL, NULL, NULL, &block, NULL, NULL));
        }
        uint64_t before[FLT_COUNT_STREAM_RECOVERIES + 1];
        for (int k = 0; k <= FLT_COUNT_STREAM_RECOVERIES; ++k)
            before[k] = count(src, (flt_source_counter)k);
        const uint64_t at = block + 3; /* beyond what the transfers hold now */
        if (fc->fault == FLT_U3V_FAULT_SUBMIT_REFUSED) {
            /* refused on the resubmission after the next completion, a
             * leader: that frame is the one dropped */
            const flt_frame *f = NULL;
            ok(flt_source_next(src, 100, &f));
            ok(flt_frame_info(f, NULL, NULL, NULL, NULL, NULL, &block, NULL, NULL));
        }
        const uint64_t fault_at = fc->fault == FLT_U3V_FAULT_SUBMIT_REFUSED ? block + 1 : at;
        /* stream faults hit block `at`; a host fault the next operations */
        ok(flt_u3v_sim_inject(bus, 0, fc->fault, fc->fault >= FLT_U3V_FAULT_SUBMIT_REFUSED ? 0 : at,
                              fc->count));
        uint8_t seen[4096] = {0};
        int timeouts = 0;
        size_t delivered = 0;
        for (int guard = 0; guard < 100; ++guard) {
            const flt_frame *f = NULL;
            flt_status st = flt_source_next(src, 100, &f);
            if (st == FLT_ERR_TIMEOUT) {
                ++timeouts;
                continue;
            }
            if (st != FLT_OK)
                fail_msg("case %zu: %s", c, flt_last_error_message());
            const void *pixels;
            ok(flt_frame_info(f, &pixels, NULL, NULL, NULL, NULL, &block, NULL, NULL));
            const uint8_t *p = pixels;
            for (size_t i = 0; i < 3000; ++i)
                if (p[i] != pattern(block, i))
                    fail_msg("case %zu block %llu byte %zu", c, (unsigned long long)block, i);
            seen[block % 4096] = 1;
            ++delivered;
            if (block >= fault_at + 4)
                break;
        }
        /* the frames after the damaged one arrive, the damaged one not */
        int missing = 0;
        for (uint64_t b = fault_at; b <= fault_at + 4; ++b)
            missing += !seen[b % 4096];
        if (missing != fc->frames_missing)
            fail_msg("case %zu: %d frames missing, expected %d", c, missing, fc->frames_missing);
        assert_true(seen[(fault_at + fc->frames_missing) % 4096]); /* next good frame */
        assert_int_equal(timeouts, fc->timeouts);
        assert_int_equal(count(src, fc->counter) - before[fc->counter], fc->grows);
        assert_int_equal(count(src, FLT_COUNT_DROPPED) - before[FLT_COUNT_DROPPED], fc->dropped);
        if (fc->timeouts)
            assert_int_equal(count(src, FLT_COUNT_TIMEOUTS) - before[FLT_COUNT_TIMEOUTS], 1);
        if (!strstr(flt_source_stream_error(src), fc->message))
            fail_msg("case %zu: stream error '%s' lacks '%s'", c, flt_source_stream_error(src),
                     fc->message);
        /* no other counter moved */
        for (int k = 0; k <= FLT_COUNT_STREAM_RECOVERIES; ++k) {
            if (k == FLT_COUNT_FRAMES || k == (int)fc->counter || k == FLT_COUNT_DROPPED ||
                k == FLT_COUNT_TIMEOUTS || k == FLT_COUNT_SUBMIT_DROPPED)
                continue;
            if (count(src, (flt_source_counter)k) != before[k])
                fail_msg("case %zu: counter %d moved from %llu to %llu", c, k,
                         (unsigned long long)before[k],
                         (unsigned long long)count(src, (flt_source_counter)k));
        }
    }
    flt_source_destroy(src);
    flt_options_destroy(o);
    flt_u3v_sim_destroy(bus);
}

static void test_unplug_mid_stream(void **state) {
    (void)state;
    flt_u3v_sim *bus = make_bus();
    flt_source *src = open_camera(bus, "SN0001", NULL);
    ok(flt_source_start(src));
    ok(flt_u3v_sim_inject(bus, 0, FLT_U3V_FAULT_UNPLUG, 5, 0));
    int frames = 0;
    flt_status st = FLT_OK;
    for (int i = 0; i < 10 && st == FLT_OK; ++i) {
        const flt_frame *f = NULL;
        st = flt_source_next(src, 100, &f);
        if (st == FLT_OK)
            ++frames;
    }
    assert_int_equal(frames, 4); /* blocks 1..4 */
    assert_error(st, FLT_ERR_DEVICE, "unplugged");
    assert_int_equal(count(src, FLT_COUNT_DISCONNECTS), 1);
    const flt_frame *f = NULL;
    assert_error(flt_source_next(src, 100, &f), FLT_ERR_DEVICE, "unplugged");
    int64_t w = 0;
    assert_error(flt_source_get_int(src, "Width", &w), FLT_ERR_DEVICE, "unplugged");
    assert_int_equal(count(src, FLT_COUNT_DISCONNECTS), 1);
    flt_source_destroy(src); /* closing a vanished camera is clean */
    flt_camera_list *list = NULL;
    ok(flt_camera_list_create(usb(bus), &list));
    size_t n = 0;
    ok(flt_camera_list_count(list, &n));
    assert_int_equal(n, 1);
    flt_camera_list_destroy(list);
    flt_u3v_sim_destroy(bus);
}

static void test_open_recovers_a_camera_left_streaming(void **state) {
    (void)state;
    flt_u3v_sim *bus = make_bus();
    ok(flt_u3v_sim_set(bus, 0, FLT_U3V_SIM_LEFT_STREAMING, 1));
    assert_int_equal(sim_value(bus, 0, FLT_U3V_SIM_SI_CONTROL), 1);
    flt_source *src = open_camera(bus, "SN0001", NULL);
    assert_int_equal(count(src, FLT_COUNT_STREAM_RECOVERIES), 1);
    assert_int_equal(sim_value(bus, 0, FLT_U3V_SIM_SI_CONTROL), 0);
    assert_int_equal(sim_value(bus, 0, FLT_U3V_SIM_ACQUIRING), 0);
    ok(flt_source_start(src));
    const uint64_t first = sim_value(bus, 0, FLT_U3V_SIM_FRAMES_SENT);
    (void)first;
    for (int i = 0; i < 20; ++i) {
        const flt_frame *f = NULL;
        ok(flt_source_next(src, 100, &f));
    }
    /* the half frame the dead process left in the FIFO was flushed */
    assert_int_equal(count(src, FLT_COUNT_BAD_PACKETS), 0);
    assert_int_equal(count(src, FLT_COUNT_DROPPED), 0);
    flt_source_destroy(src);
    assert_int_equal(sim_value(bus, 0, FLT_U3V_SIM_SI_CONTROL), 0);
    assert_int_equal(sim_value(bus, 0, FLT_U3V_SIM_ACQUIRING), 0);
    flt_u3v_sim_destroy(bus);
}

/* --- control channel: pending acks, timeouts, stale acks ------------------- */

static void test_pending_acks_and_timeouts(void **state) {
    (void)state;
    flt_u3v_sim *bus = make_bus();
    flt_source *src = open_camera(bus, "SN0001", NULL);
    int64_t w = 0;
    /* 3 pending acks: within the limit of 5, the read succeeds */
    ok(flt_u3v_sim_inject(bus, 0, FLT_U3V_FAULT_PENDING_ACK, 0, 3));
    ok(flt_source_get_int(src, "Width", &w));
    assert_int_equal(w, 100);
    assert_int_equal(count(src, FLT_COUNT_PENDING_ACKS), 3);
    /* 6 pending acks: the client gives up after the 6th */
    ok(flt_u3v_sim_inject(bus, 0, FLT_U3V_FAULT_PENDING_ACK, 0, 6));
    assert_error(flt_source_get_int(src, "Width", &w), FLT_ERR_TIMEOUT, "6 pending acks");
    assert_int_equal(count(src, FLT_COUNT_PENDING_ACKS), 9);
    /* the late real answer to that command is discarded as stale */
    ok(flt_source_get_int(src, "Height", &w));
    assert_int_equal(w, 30);
    assert_int_equal(count(src, FLT_COUNT_STALE_ACKS), 1);

    /* one lost answer: the command is sent again and succeeds */
    ok(flt_u3v_sim_inject(bus, 0, FLT_U3V_FAULT_CONTROL_TIMEOUT, 0, 1));
    ok(flt_source_get_int(src, "Width", &w));
    assert_int_equal(count(src, FLT_COUNT_COMMAND_RETRIES), 1);
    /* three lost answers: all 3 attempts time out */
    ok(flt_u3v_sim_inject(bus, 0, FLT_U3V_FAULT_CONTROL_TIMEOUT, 0, 3));
    assert_error(flt_source_get_int(src, "Width", &w), FLT_ERR_TIMEOUT,
                 "no acknowledge within 200 ms in 3 attempts");
    assert_int_equal(count(src, FLT_COUNT_COMMAND_RETRIES), 3);
    ok(flt_source_get_int(src, "Width", &w)); /* usable again */

    /* a late ack: it arrives after the retry was sent, with the previous
     * request id, and is discarded */
    const uint64_t stale = count(src, FLT_COUNT_STALE_ACKS);
    ok(flt_u3v_sim_inject(bus, 0, FLT_U3V_FAULT_LATE_ACK, 0, 1));
    ok(flt_source_get_int(src, "Height", &w));
    assert_int_equal(w, 30);
    assert_int_equal(count(src, FLT_COUNT_STALE_ACKS), stale + 1);
    assert_int_equal(count(src, FLT_COUNT_COMMAND_RETRIES), 4);
    flt_source_destroy(src);

    /* with a limit of 0 pending acks, the first one fails the command */
    flt_options *o = NULL;
    ok(flt_options_create(&o));
    ok(flt_options_set(o, FLT_OPT_U3V_PENDING_ACK_LIMIT, 0));
    src = open_camera(bus, "SN0001", o);
    ok(flt_u3v_sim_inject(bus, 0, FLT_U3V_FAULT_PENDING_ACK, 0, 1));
    assert_error(flt_source_get_int(src, "Width", &w), FLT_ERR_TIMEOUT, "1 pending acks");
    flt_source_destroy(src);
    flt_options_destroy(o);
    flt_u3v_sim_destroy(bus);
}

/* --- bad input -------------------------------------------------------------------- */

static void test_bad_input_names_the_problem(void **state) {
    (void)state;
    flt_source *src = NULL;
    assert_error(flt_source_open_u3v(NULL, "x", NULL, NULL), FLT_ERR_INVALID_ARGUMENT,
                 "'out' is NULL");
    flt_u3v_sim *bus = make_bus();
    assert_error(flt_u3v_sim_inject(bus, 5, FLT_U3V_FAULT_SHORT_FRAME, 1, 0),
                 FLT_ERR_INVALID_ARGUMENT, "'camera' = 5");
    assert_error(flt_u3v_sim_inject(bus, 0, (flt_u3v_fault)77, 1, 0), FLT_ERR_INVALID_ARGUMENT,
                 "unknown");
    assert_error(flt_u3v_sim_add_camera(bus, "v", "m", "s", 8, 30, FLT_PIXEL_MONO8, NULL),
                 FLT_ERR_INVALID_ARGUMENT, "'width' = 8");
    assert_error(flt_u3v_sim_add_camera(bus, "v", "m", "s", 64, 30, (flt_pixel_format)9, NULL),
                 FLT_ERR_INVALID_ARGUMENT, "'format' = 9");
    assert_error(flt_u3v_sim_set(bus, 0, FLT_U3V_SIM_MAX_ACK_BYTES, 10), FLT_ERR_INVALID_ARGUMENT,
                 "outside");
    src = open_camera(bus, "SN0001", NULL);
    assert_error(flt_u3v_sim_set(bus, 0, FLT_U3V_SIM_MAX_ACK_BYTES, 512), FLT_ERR_STATE, "open");
    const flt_frame *f = NULL;
    assert_error(flt_source_next(src, 10, &f), FLT_ERR_STATE, "flt_source_start");
    assert_error(flt_source_next(NULL, 10, &f), FLT_ERR_INVALID_ARGUMENT, "'source' is NULL");
    assert_error(flt_source_next(src, 10, NULL), FLT_ERR_INVALID_ARGUMENT, "'out' is NULL");
    assert_error(flt_source_set_encoder(src, 1.0), FLT_ERR_STATE, "not 2 (host)");
    assert_error(flt_source_get_int(src, NULL, NULL), FLT_ERR_INVALID_ARGUMENT,
                 "'feature' is NULL");
    assert_error(flt_source_count(src, (flt_source_counter)99, NULL), FLT_ERR_INVALID_ARGUMENT,
                 "NULL");
    uint64_t v;
    assert_error(flt_source_count(src, (flt_source_counter)99, &v), FLT_ERR_INVALID_ARGUMENT,
                 "'counter' = 99");
    assert_error(flt_source_camera_value(src, (flt_camera_value)99, &v), FLT_ERR_INVALID_ARGUMENT,
                 "'which' = 99");
    assert_error(flt_frame_info(NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL),
                 FLT_ERR_INVALID_ARGUMENT, "'frame' is NULL");
    ok(flt_source_start(src));
    assert_error(flt_source_start(src), FLT_ERR_STATE, "already");
    ok(flt_source_next(src, 10, &f));
    ok(flt_frame_info(f, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL));
    assert_string_equal(flt_source_stream_error(NULL), "");
    flt_source_destroy(src);
    flt_source_destroy(NULL);
    flt_u3v_sim_destroy(NULL);
    flt_u3v_sim_destroy(bus);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_discovery_lists_cameras_only),
        cmocka_unit_test(test_open_reads_bootstrap_registers),
        cmocka_unit_test(test_gencp_chunks_to_the_device_limits),
        cmocka_unit_test(test_features_resolve_from_the_xml),
        cmocka_unit_test(test_streams_1000_frames_byte_exact),
        cmocka_unit_test(test_stream_with_fine_alignment_and_encoder_chunk),
        cmocka_unit_test(test_each_failure_mode_is_counted_and_recovers),
        cmocka_unit_test(test_unplug_mid_stream),
        cmocka_unit_test(test_open_recovers_a_camera_left_streaming),
        cmocka_unit_test(test_pending_acks_and_timeouts),
        cmocka_unit_test(test_bad_input_names_the_problem),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
