// SPDX-License-Identifier: Apache-2.0
/* Writes the seed corpus of the fuzzing harnesses into tests/fuzz/corpus/
 * (committed; rerun only to regenerate it):
 *   cc -std=c99 -Iinclude tests/fuzz/make_seeds.c -Lbuild/dev/lib -lflatline_testing \
 *      -lflatline -Wl,-rpath,build/dev/lib -o /tmp/make_seeds && /tmp/make_seeds tests/fuzz/corpus
 * Seeds are valid inputs the harnesses parse deeply (a real calibration
 * file, the simulated camera's GenICam XML plain and zipped, a well-formed
 * frame on the U3V stream, a camera's bootstrap block over GVCP, the JSON
 * files of every reader), plus small structured ones. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "flatline/flatline.h"
#include "flatline/testing.h"

static const char *g_root;

static void put(const char *harness, const char *name, const void *bytes, size_t n) {
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", g_root, harness);
    mkdir(path, 0755);
    snprintf(path, sizeof path, "%s/%s/%s", g_root, harness, name);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(bytes, 1, n, f) != n || fclose(f) != 0) {
        fprintf(stderr, "cannot write %s\n", path);
        exit(1);
    }
}

static void check(flt_status st) {
    if (st != FLT_OK) {
        fprintf(stderr, "%s\n", flt_last_error_message());
        exit(1);
    }
}

static void le16(uint8_t *p, unsigned v) {
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: make_seeds CORPUS_DIR\n");
        return 2;
    }
    g_root = argv[1];
    mkdir(g_root, 0755);

    /* calib_load: the reference sensor's file, one with a small ROI and
     * grid, and its first half. */
    static char text[8192];
    size_t n = 0;
    flt_calib *c = NULL;
    check(flt_calib_create_reference(0, 2048, -1000, 2, 1001, &c));
    check(flt_calib_save_text(c, text, sizeof text, &n));
    put("calib_load", "reference.json", text, n);
    put("calib_load", "truncated.json", text, n / 2);
    flt_calib_destroy(c);
    check(flt_calib_create_reference(900, 240, -500, 10, 101, &c));
    check(flt_calib_save_text(c, text, sizeof text, &n));
    put("calib_load", "roi.json", text, n);
    flt_calib_destroy(c);

    /* genicam: the simulated camera's XML, as stored (zipped) and plain;
     * byte 0 picks the form (odd: ZIP). */
    for (int zipped = 0; zipped < 2; ++zipped) {
        flt_u3v_sim *bus = NULL;
        flt_usb_transport *usb = NULL;
        flt_source *src = NULL;
        size_t idx;
        uint64_t bytes = 0, address = 0;
        check(flt_u3v_sim_create(&bus));
        check(flt_u3v_sim_add_camera(bus, "V", "M", "S1", 64, 32, FLT_PIXEL_MONO8, &idx));
        check(flt_u3v_sim_set(bus, idx, FLT_U3V_SIM_XML_ZIPPED, (uint64_t)zipped));
        check(flt_u3v_sim_transport(bus, &usb));
        check(flt_source_open_u3v(usb, "S1", NULL, &src));
        check(flt_source_camera_value(src, FLT_CAMERA_XML_BYTES, &bytes));
        /* The manifest's first entry holds the file's address (U3V). */
        uint8_t entry[16];
        check(flt_source_camera_value(src, FLT_CAMERA_MANIFEST_ADDRESS, &address));
        check(flt_source_read_memory(src, address + 8 + 8, entry, 8));
        uint64_t file_address = 0;
        for (int i = 7; i >= 0; --i)
            file_address = file_address << 8 | entry[i];
        uint8_t *buf = malloc(bytes + 1);
        buf[0] = (uint8_t)zipped;
        check(flt_source_read_memory(src, file_address, buf + 1, bytes));
        put("genicam", zipped ? "camera.zip" : "camera.xml", buf, bytes + 1);
        free(buf);
        flt_source_destroy(src);
        flt_u3v_sim_destroy(bus);
    }

    /* genicam: every node kind the engine evaluates (selectors, pIndex,
     * StructReg, formulas, converters, big-endian bit fields, commands),
     * with 256 bytes of registers (byte 0: bit 1 = registers follow, then
     * their length, big endian). */
    {
        static const char nodes[] =
            "<RegisterDescription SchemaMajorVersion=\"1\" SchemaMinorVersion=\"1\">"
            "<Integer Name=\"Width\"><pValue>W</pValue><pMin>Lo</pMin><Max>4096</Max>"
            "<Inc>16</Inc><pIsLocked>TLParamsLocked</pIsLocked></Integer>"
            "<IntReg Name=\"W\"><Address>0x10</Address><Length>4</Length><AccessMode>RW"
            "</AccessMode><pPort>Device</pPort><Sign>Unsigned</Sign><Endianess>BigEndian"
            "</Endianess></IntReg><Integer Name=\"Lo\"><Value>16</Value></Integer>"
            "<Integer Name=\"TLParamsLocked\"><Value>0</Value></Integer>"
            "<Enumeration Name=\"TriggerSelector\"><EnumEntry Name=\"FrameStart\"><Value>0"
            "</Value></EnumEntry><EnumEntry Name=\"LineStart\"><Value>1</Value>"
            "<pIsAvailable>Lo</pIsAvailable></EnumEntry><pValue>Sel</pValue>"
            "<pSelected>TriggerMode</pSelected></Enumeration>"
            "<MaskedIntReg Name=\"Sel\"><Address>0x20</Address><Length>4</Length>"
            "<AccessMode>RW</AccessMode><pPort>Device</pPort><LSB>31</LSB><MSB>30</MSB>"
            "<Endianess>BigEndian</Endianess></MaskedIntReg>"
            "<IntReg Name=\"TriggerMode\"><Address>0x40</Address><pIndex Offset=\"8\">"
            "TriggerSelector</pIndex><Length>4</Length><AccessMode>RW</AccessMode>"
            "<pPort>Device</pPort><Endianess>LittleEndian</Endianess></IntReg>"
            "<StructReg Comment=\"s\"><Address>0x50</Address><IntSwissKnife Name=\"Off\">"
            "<pVariable Name=\"S\">TriggerSelector</pVariable><Formula>S * 4</Formula>"
            "</IntSwissKnife><Length>4</Length><AccessMode>RO</AccessMode><pPort>Device"
            "</pPort><StructEntry Name=\"Ready\"><Bit>0</Bit></StructEntry>"
            "<StructEntry Name=\"Count\"><LSB>8</LSB><MSB>15</MSB><Sign>Signed</Sign>"
            "</StructEntry></StructReg>"
            "<Converter Name=\"ExposureTime\"><FormulaTo>FROM / 1.024</FormulaTo>"
            "<FormulaFrom>(TO &lt; 1) ? 0 : TO * 1.024</FormulaFrom><pValue>Raw</pValue>"
            "</Converter><IntConverter Name=\"Gain\"><FormulaTo>FROM * 2</FormulaTo>"
            "<FormulaFrom>(TO / 2) &amp; 0xFF</FormulaFrom><pValue>Raw</pValue></IntConverter>"
            "<IntReg Name=\"Raw\"><Address>0x60</Address><Length>2</Length><AccessMode>RW"
            "</AccessMode><pPort>Device</pPort><Sign>Signed</Sign></IntReg>"
            "<SwissKnife Name=\"PayloadSize\"><pVariable Name=\"W\">Width</pVariable>"
            "<Constant Name=\"K\">0.5</Constant><Expression Name=\"X\">W ** 2</Expression>"
            "<Formula>ROUND(SQRT(X) * K, 1) + SGN(-W) + (W &gt;&gt; 2 &lt;&lt; 1)</Formula>"
            "</SwissKnife><FloatReg Name=\"G\"><Address>0x70</Address><Length>8</Length>"
            "<AccessMode>RW</AccessMode><pPort>Device</pPort><Endianess>BigEndian"
            "</Endianess></FloatReg>"
            "<Boolean Name=\"ReverseX\"><pValue>W</pValue><OnValue>3</OnValue></Boolean>"
            "<Command Name=\"AcquisitionStart\"><pValue>Raw</pValue><CommandValue>1"
            "</CommandValue></Command><StringReg Name=\"DeviceVendorName\"><Address>0x80"
            "</Address><Length>16</Length><AccessMode>RO</AccessMode><pPort>Device</pPort>"
            "</StringReg><Integer Name=\"Table\"><pIndex>TriggerSelector</pIndex>"
            "<ValueIndexed Index=\"1\">7</ValueIndexed><ValueDefault>3</ValueDefault>"
            "</Integer></RegisterDescription>";
        uint8_t seed[3 + 256 + sizeof nodes];
        seed[0] = 2;
        seed[1] = 1;
        seed[2] = 0;
        for (int i = 0; i < 256; ++i)
            seed[3 + i] = (uint8_t)(i * 37 + 11);
        memcpy(seed + 3 + 256, nodes, sizeof nodes - 1);
        put("genicam", "nodes-with-registers", seed, 3 + 256 + sizeof nodes - 1);
    }

    /* u3v: mode 0 (stream), then transfers as the harness reads them:
     * kind, u16 length, fields. A leader (kind 1), the 2048-byte payload
     * of a 64 x 32 Mono8 frame in 512-byte transfers of a pattern (kind 0:
     * fill byte), and a trailer (kind 2); twice. */
    uint8_t s[64];
    size_t k = 0;
    uint8_t stream[256];
    s[k++] = 0; /* mode: stream, no chunk, 512-byte transfers, 2 slots */
    memcpy(stream, s, k);
    n = k;
    for (int frame = 0; frame < 2; ++frame) {
        stream[n++] = 1;
        le16(stream + n, 52);
        n += 2; /* leader */
        memset(stream + n, 0, 8 + 4 + 1);
        n += 13; /* timestamp, (pfnc), pad */
        for (int t = 0; t < 4; ++t) {
            stream[n++] = 0;
            le16(stream + n, 512);
            n += 2; /* payload */
            stream[n++] = (uint8_t)(17 * t + frame);
        }
        stream[n++] = 2;
        le16(stream + n, 32);
        n += 2; /* trailer */
        memset(stream + n, 0, 4);
        n += 4; /* size y */
    }
    put("u3v", "two_frames", stream, n);
    /* mode 1: control acks; get_int("Width") answered by a well-formed ack
     * with a 4-byte body. */
    uint8_t ctl[] = {1, 0, 1, 16, 0, 64, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    put("u3v", "control_ack", ctl, sizeof ctl);
    const uint8_t garbage[] = {0, 3, 0x40, 0, 0xFF};
    put("u3v", "garbage_then_unplug", garbage, sizeof garbage);

    /* recon: fibers, options, then operations (push with increasing rows,
     * pull, end_sheet, boundary, reset). */
    const uint8_t recon1[] = {3,  0, 1, 40, 1, 6, 0, 9, 5, 1, 2, 3, 4, 5, 6, 7, 8,  9, 3,
                              20, 4, 6, 0,  9, 5, 9, 8, 7, 6, 5, 4, 3, 2, 1, 3, 40, 5, 7};
    put("recon", "push_pull_sheet", recon1, sizeof recon1);
    const uint8_t recon2[] = {5, 2, 7, 1, 0x40, 11, 1, 2, 0, 39, 0, 0, 1, 2, 3, 4, 0, 0, 0, 0};
    put("recon", "options_nan", recon2, sizeof recon2);

    /* extractor: no options, one Mono8 frame with two patches; a Mono12
     * frame; a 16-bit frame with a NaN encoder. */
    const uint8_t ex1[] = {0, 0,   2,    2,    0x10, 0x20, 0x30, 0, 40, 2,
                           1, 255, 0x00, 0x90, 0x01, 0,    10,   1, 0,  0};
    put("extractor", "mono8_patches", ex1, sizeof ex1);
    const uint8_t ex2[] = {2, 4, 9, 5, 2, 0, 0};
    put("extractor", "mono12_window9", ex2, sizeof ex2);
    const uint8_t ex3[] = {0, 0, 5, 0, 0};
    put("extractor", "mono16_nan_encoder", ex3, sizeof ex3);
    /* chain: an 8-byte header (stages, extractor options, the synthetic
     * lines' rows, encoder) and a calibration: the reference's rows 900..1139
     * with the lines near rows 96 and 144 of the window, rendered by the
     * simulator or drawn synthetic; fixed bands; 12-bit words with junk;
     * and the finest, widest fiber grid the ranges allow. */
    static uint8_t chain[8 + sizeof text];
    const struct {
        const char *name;
        uint8_t header[8];
        double first_x, pitch;
        size_t fibers;
    } chains[] = {
        {"roi_sim_mono8", {1, 2, 102, 153, 0, 0, 0, 0}, -1000, 2, 1001},
        {"roi_synthetic_fixed_bands", {0, 2 | 4 | (3 << 3), 102, 153, 0, 0, 0, 0}, -500, 10, 101},
        {"roi_sim_mono12_junk", {1 | 2, 1, 102, 153, 100, 0, 0, 0}, -1000, 2, 1001},
        {"roi_finest_grid", {0 | 4, 3, 102, 153, 0, 0, 0, 0}, -100000, 1e-3, 16384},
    };
    for (size_t i = 0; i < sizeof chains / sizeof chains[0]; ++i) {
        check(flt_calib_create_reference(900, 240, chains[i].first_x, chains[i].pitch,
                                         chains[i].fibers, &c));
        check(flt_calib_save_text(c, text, sizeof text, &n));
        memcpy(chain, chains[i].header, 8);
        memcpy(chain + 8, text, n);
        put("chain", chains[i].name, chain, 8 + n);
        flt_calib_destroy(c);
    }
    /* source_faults: byte 0 the options (22: 3 attempts per command, 5
     * pending acks allowed, 2 transfers), then operations: 0 kind at count
     * (control fault: 0 pending, 1 lost command, 2 late, 3 lost ack, 4
     * busy), 1 kind at count (kind < 8: unplug, else refused submits),
     * 2 kind at count (stream fault), 3 start, 5 stop, 6 k (k + 1 frames),
     * 7 (a feature read). */
    {
        static const uint8_t lost_stop[] = {22, 3, 6, 2, 0, 1, 0, 11, 5, 5, 3, 6, 1, 5};
        static const uint8_t pending_at_start[] = {22, 0, 0, 13, 6, 3, 6, 1, 5, 3, 5};
        static const uint8_t busy_stop[] = {22, 3, 0, 4, 0, 11, 5, 3, 6, 1, 5};
        static const uint8_t stream_faults[] = {22, 3, 2, 0, 1, 1, 6, 3, 1, 20, 0, 3, 6, 3, 5};
        static const uint8_t unplug[] = {22, 3, 1, 0, 1, 0, 5, 3};
        put("source_faults", "lost_stop", lost_stop, sizeof lost_stop);
        put("source_faults", "pending_at_start", pending_at_start, sizeof pending_at_start);
        put("source_faults", "busy_stop", busy_stop, sizeof busy_stop);
        put("source_faults", "stream_faults", stream_faults, sizeof stream_faults);
        put("source_faults", "unplug", unplug, sizeof unplug);
    }

    /* genicam: a FloatReg holding NaN and a formula shifting into the sign
     * bit (both refused with FLT_ERR_NUMERIC); 16 register bytes. */
    {
        static const char refusals[] =
            "<RegisterDescription><FloatReg Name=\"Gain\"><Address>0</Address><Length>8"
            "</Length><AccessMode>RO</AccessMode><pPort>Device</pPort><Endianess>BigEndian"
            "</Endianess></FloatReg><IntSwissKnife Name=\"Width\"><pVariable Name=\"A\">Raw"
            "</pVariable><Formula>A &lt;&lt; 63</Formula></IntSwissKnife><IntReg Name=\"Raw\">"
            "<Address>8</Address><Length>4</Length><AccessMode>RO</AccessMode><pPort>Device"
            "</pPort></IntReg></RegisterDescription>";
        uint8_t seed[3 + 16 + sizeof refusals];
        const uint8_t registers[16] = {0x7F, 0xF8, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0};
        seed[0] = 2;
        seed[1] = 0;
        seed[2] = 16;
        memcpy(seed + 3, registers, 16);
        memcpy(seed + 3 + 16, refusals, sizeof refusals - 1);
        put("genicam", "nan_and_shift", seed, 3 + 16 + sizeof refusals - 1);
    }

    /* gvsp: shape (bit 0 Mono16, bit 1 resends, bits 2-3 attempts, bits
     * 4+ frames in assembly), width - 1, height - 1, data bytes - 4,
     * resend timeout - 1 (ms), the first block id (u16 LE); then
     * operations (fuzz_gvsp.cpp): 0..3 a frame (bit 7: a fate byte per
     * packet: 1 lost, 2 twice, 3 delayed, 4 swapped, 5 forged first),
     * 4 ms, 5 a stray, 6 the delayed ones, 7 take, 8 resends answered,
     * 9 new block ids. Frames of 32 x 4 px Mono8 in 64-byte packets: 4
     * packets each, across the block-id wrap. */
    {
        static const uint8_t clean[] = {0x20, 31, 3, 60, 9, 0xF0, 0xFF, 0,  0, 0,
                                        0,    7,  0, 0,  0, 7,    4,    30, 7};
        put("gvsp", "clean_across_wrap", clean, sizeof clean);
        static const uint8_t resends[] = {0x2A, 31, 3,    60, 9, 1,  0, 0x80, 0,  1,
                                          0,    0,  0x80, 0,  0, 1,  0, 7,    4,  12,
                                          8,    1,  1,    7,  4, 30, 7, 4,    30, 7};
        put("gvsp", "losses_and_resends", resends, sizeof resends);
        static const uint8_t hostile[] = {
            0x20, 31, 3, 60, 9, 100,  0, 0x80, 4, 0, 5, 0, 5,    1,    0, 0x80, 0, 3, 0,  0,
            6,    7,  5, 9,  1, 0x80, 0, 0,    0, 0, 7, 9, 0x34, 0x12, 0, 0,    7, 4, 40, 7};
        put("gvsp", "swaps_forgeries_strays_restart", hostile, sizeof hostile);
    }

    /* gvcp: timeout - 1 (ms), attempts - 1, pending-ack limit, preset
     * length / 8 and the camera's first bytes of memory; then operations
     * (fuzz_gvcp.cpp), each command answered as the input says (a count,
     * then per answer a kind byte: 0 = the camera's own answer). Here a
     * bootstrap block ("flatline" with an ESC in its model name), the
     * first URL at 0x200 naming a 22-byte description at 0x220, read by
     * operation 5 with every command answered once; then a READREG
     * answered by a stranger, a pending acknowledge and the camera. */
    {
        static uint8_t gvcp[16 + 0x240 + 64];
        size_t g = 0;
        gvcp[g++] = 4;
        gvcp[g++] = 1;
        gvcp[g++] = 5;
        gvcp[g++] = 0x240 / 8;
        uint8_t *memory = gvcp + g;
        memset(memory, 0, 0x240);
        memory[2] = 2; /* version 2.0 */
        memcpy(memory + 0x48, "flatline", 8);
        memcpy(memory + 0x68, "Fuzz\x1b[2J", 8);
        memcpy(memory + 0xD8, "F0001", 5);
        const char url[] = "Local:f.xml;220;16";
        memcpy(memory + 0x200, url, sizeof url - 1);
        memcpy(memory + 0x220, "<RegisterDescription/>", 22);
        g += 0x240;
        gvcp[g++] = 5;
        for (int command = 0; command < 12; ++command) {
            gvcp[g++] = 1;
            gvcp[g++] = 0;
        }
        gvcp[g++] = 0; /* READREG */
        gvcp[g++] = 0;
        gvcp[g++] = 0;
        gvcp[g++] = 0x0A;
        gvcp[g++] = 0; /* of 0x0A00 */
        gvcp[g++] = 3;
        gvcp[g++] = 0x80;
        gvcp[g++] = 0x08;
        gvcp[g++] = 0x01;
        gvcp[g++] = 0x00;
        gvcp[g++] = 0x00;
        put("gvcp", "bootstrap_pending_stranger", gvcp, g);
    }

    /* json: byte 0 picks the reader (0 rules, 1 leveler, 2 calibration). */
    {
        static const char rules[] =
            "\0{ \"format\": \"flatline-tolerances\", \"version\": 1, \"name\": \"seed\",\n"
            "  \"rules\": [\n"
            "    { \"name\": \"straightedge\", \"measure\": \"straightedge_along\", "
            "\"length_mm\": 1000,\n"
            "      \"bands\": [ { \"thickness_mm\": [1.5, 4], \"width_mm\": [600, 2100], "
            "\"limit\": 3.0 },\n"
            "                 { \"thickness_mm\": [4, 12], \"width_mm\": [600, 2100], "
            "\"limit\": 2.5 } ] },\n"
            "    { \"name\": \"crossbow\", \"measure\": \"crossbow\",\n"
            "      \"bands\": [ { \"thickness_mm\": [1.5, 12], \"width_mm\": [600, 2100], "
            "\"limit\": 1.5 } ] } ] }\n";
        put("json", "rules", rules, sizeof rules - 1);
        static const char leveler[] =
            "\1{ \"format\": \"flatline-leveler\", \"version\": 1,\n"
            "  \"name\": \"seed leveler\",\n"
            "  \"zones\": 3,\n"
            "  \"actuators\": [\n"
            "    { \"name\": \"entry gap\", \"unit\": \"mm\", \"min\": -3, \"max\": 3, "
            "\"step\": 0.5 },\n"
            "    { \"name\": \"tilt\", \"unit\": \"mm\", \"min\": -2, \"max\": 2, \"step\": 0.3 } "
            "],\n"
            "  \"influence\": [ [ 4.0, -6.0 ], [ -8.0, 0.0 ], [ 4.0, 6.0 ] ],\n"
            "  \"target\": [ 0, 2, 0 ] }\n";
        put("json", "leveler", leveler, sizeof leveler - 1);
        check(flt_calib_create_reference(0, 2048, -1000, 2, 1001, &c));
        text[0] = 2;
        check(flt_calib_save_text(c, text + 1, sizeof text - 1, &n));
        put("json", "calibration", text, n + 1);
        flt_calib_destroy(c);
    }

    printf("seeds written to %s\n", g_root);
    return 0;
}
