// SPDX-License-Identifier: Apache-2.0
/*
 * The GenICam engine through the offline view (flatline/genicam.h): a
 * description written for this test holds every node kind, and each
 * feature is evaluated against register bytes the test puts into the
 * memory image. The expected values are worked out by hand in the comments
 * (register bytes -> value); they are exact integers or exactly
 * representable doubles unless a tolerance is given with its reason.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include <cmocka.h>

#include "flatline/flatline.h"
#include "flatline/genicam.h"

#define ok(call)                                                                        \
  do {                                                                                  \
    flt_status st_ = (call);                                                            \
    if (st_ != FLT_OK)                                                                  \
      fail_msg("%s: %s (%s)", #call, flt_status_string(st_), flt_last_error_message()); \
  } while (0)

static void assert_error(flt_status got, flt_status want, const char *needle) {
    if (got != want)
        fail_msg("status %s, expected %s (%s)", flt_status_string(got), flt_status_string(want),
                 flt_last_error_message());
    if (needle && !strstr(flt_last_error_message(), needle))
        fail_msg("message '%s' does not mention '%s'", flt_last_error_message(), needle);
}

/* ---------------------------------------------------------------------- */
/* The test camera's description                                           */
/* ---------------------------------------------------------------------- */

#define REG(name, address, length, access, endian, sign)                         \
  "<IntReg Name=\"" name "\"><Address>" address "</Address><Length>" length      \
  "</Length><AccessMode>" access "</AccessMode><pPort>Device</pPort><Sign>" sign \
  "</Sign><Endianess>" endian "</Endianess></IntReg>\n"

static const char k_xml[] =
    "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
    "<RegisterDescription ModelName=\"TestCam\" VendorName=\"Flatline\" "
    "SchemaMajorVersion=\"1\" SchemaMinorVersion=\"1\" SchemaSubMinorVersion=\"0\" "
    "xmlns=\"http://www.genicam.org/GenApi/Version_1_1\">\n"
    "<Category Name=\"Root\"><pFeature>Width</pFeature></Category>\n"
    "<Port Name=\"Device\"/>\n"
    "<Port Name=\"ChunkPort\"><ChunkID>1234</ChunkID></Port>\n"
    "<Port Name=\"EventPort\"><EventID>9000</EventID></Port>\n"
    /* Integer through a register, bounds from a node and constants */
    "<Integer Name=\"Width\"><pValue>WidthReg</pValue><pMin>WidthMin</pMin><Max>4096</Max>"
    "<Inc>16</Inc><Extension><Integer Name=\"NotANode\"><Value>1</Value></Integer></Extension>"
    "</Integer>\n" REG(
        "WidthReg", "0x1000", "4", "RW", "LittleEndian",
        "Unsigned") "<Integer Name=\"WidthMin\"><Value>32</Value></Integer>\n"
                    "<Group Comment=\"registers of other shapes\">\n" REG("BigReg", "0x1010", "4", "RW", "BigEndian", "Signed") REG(
                        "Wide",
                        "0x1018", "8", "RO", "LittleEndian",
                        "Unsigned") "<MaskedIntReg "
                                    "Name=\"LeBits\"><Address>0x1020</Address><Length>4</"
                                    "Length>"
                                    "<AccessMode>RW</AccessMode><pPort>Device</pPort><LSB>4</"
                                    "LSB><MSB>11</MSB>"
                                    "<Sign>Unsigned</Sign><Endianess>LittleEndian</Endianess></"
                                    "MaskedIntReg>\n"
                                    "<MaskedIntReg "
                                    "Name=\"SignedBits\"><Address>0x1020</Address><Length>4</"
                                    "Length>"
                                    "<AccessMode>RW</AccessMode><pPort>Device</pPort><LSB>0</"
                                    "LSB><MSB>3</MSB>"
                                    "<Sign>Signed</Sign><Endianess>LittleEndian</Endianess></"
                                    "MaskedIntReg>\n"
                                    "<MaskedIntReg "
                                    "Name=\"BeBits\"><Address>0x1030</Address><Length>4</"
                                    "Length>"
                                    "<AccessMode>RW</AccessMode><pPort>Device</pPort><LSB>31</"
                                    "LSB><MSB>24</MSB>"
                                    "<Sign>Unsigned</Sign><Endianess>BigEndian</Endianess></"
                                    "MaskedIntReg>\n"
                                    "</Group>\n"
                                    /* StructReg: its elements are every entry's, entries
                                       override */
                                    "<StructReg "
                                    "Comment=\"Status\"><Address>0x1040</Address><Length>4</"
                                    "Length>"
                                    "<AccessMode>RO</AccessMode><pPort>Device</"
                                    "pPort><pIsImplemented>One</pIsImplemented>"
                                    "<Endianess>LittleEndian</Endianess>"
                                    "<StructEntry "
                                    "Name=\"StatusReady\"><Bit>0</Bit></StructEntry>"
                                    "<StructEntry "
                                    "Name=\"StatusCount\"><LSB>8</LSB><MSB>15</"
                                    "MSB><AccessMode>RW</AccessMode>"
                                    "</StructEntry></StructReg>\n"
                                    "<StructReg "
                                    "Comment=\"Gone\"><Address>0x1044</Address><Length>4</"
                                    "Length>"
                                    "<AccessMode>RO</AccessMode><pPort>Device</"
                                    "pPort><pIsImplemented>Zero</pIsImplemented>"
                                    "<Endianess>LittleEndian</Endianess><StructEntry "
                                    "Name=\"GoneBit\"><Bit>1</Bit>"
                                    "</StructEntry></StructReg>\n"
                                    "<Integer Name=\"One\"><Value>1</Value></Integer>\n"
                                    "<Integer Name=\"Zero\"><Value>0</Value></Integer>\n"
                                    /* floats */
                                    "<Float "
                                    "Name=\"Gain\"><pValue>GainReg</pValue><Min>0</"
                                    "Min><Max>24</Max><Unit>dB</Unit>"
                                    "</Float>\n"
                                    "<FloatReg "
                                    "Name=\"GainReg\"><Address>0x1050</Address><Length>4</"
                                    "Length>"
                                    "<AccessMode>RW</AccessMode><pPort>Device</"
                                    "pPort><Endianess>LittleEndian</Endianess>"
                                    "</FloatReg>\n"
                                    "<FloatReg "
                                    "Name=\"BigDouble\"><Address>0x1058</Address><Length>8</"
                                    "Length>"
                                    "<AccessMode>RO</AccessMode><pPort>Device</"
                                    "pPort><Endianess>BigEndian</Endianess>"
                                    "</FloatReg>\n"
                                    "<Float Name=\"Ratio\"><Value>1.5</Value></Float>\n"
                                    /* converters */
                                    "<Converter Name=\"ExposureTime\"><FormulaTo>FROM / "
                                    "1.024</FormulaTo>"
                                    "<FormulaFrom>TO * "
                                    "1.024</FormulaFrom><pValue>ExposureRaw</pValue><Unit>us</"
                                    "Unit>"
                                    "</Converter>\n" REG(
                                        "ExposureRaw", "0x1060",
                                        "4", "RW", "LittleEndian",
                                        "Unsigned") "<IntConverter "
                                                    "Name=\"Halved\"><FormulaTo>FROM * "
                                                    "2</FormulaTo>"
                                                    "<FormulaFrom>TO / "
                                                    "2.0</FormulaFrom><pValue>ExposureRaw</"
                                                    "pValue></IntConverter>\n"
                                                    "<IntConverter "
                                                    "Name=\"Ambiguous\"><FormulaTo>FROM</"
                                                    "FormulaTo>"
                                                    "<FormulaFrom>(TO / 4) * "
                                                    "4</FormulaFrom><pValue>ExposureRaw</"
                                                    "pValue></IntConverter>\n"
                                                    "<SwissKnife Name=\"Twice\"><pVariable "
                                                    "Name=\"W\">Width</pVariable>"
                                                    "<Constant "
                                                    "Name=\"K\">0.5</Constant><Expression "
                                                    "Name=\"DOUBLE\">W * 2</Expression>"
                                                    "<Formula>DOUBLE * K + PI - "
                                                    "PI</Formula></SwissKnife>\n"
                                                    /* selectors, computed addresses, tables */
                                                    "<Enumeration "
                                                    "Name=\"GainSelector\"><EnumEntry "
                                                    "Name=\"All\"><Value>0</Value></EnumEntry>"
                                                    "<EnumEntry "
                                                    "Name=\"Red\"><Value>1</Value></EnumEntry>"
                                                    "<EnumEntry "
                                                    "Name=\"Blue\"><Value>2</"
                                                    "Value><pIsAvailable>Zero</pIsAvailable></"
                                                    "EnumEntry>"
                                                    "<EnumEntry "
                                                    "Name=\"Green\"><Value>3</"
                                                    "Value><pIsImplemented>Zero</"
                                                    "pIsImplemented>"
                                                    "</EnumEntry><pValue>GainSelectorReg</"
                                                    "pValue><pSelected>GainRaw</pSelected>"
                                                    "</Enumeration>\n" REG(
                                                        "GainSelectorReg",
                                                        "0x1070", "4", "RW",
                                                        "LittleEndian",
                                                        "Unsigned") "<IntReg "
                                                                    "Name=\"GainRaw\"><Address>"
                                                                    "0x1100</"
                                                                    "Address><pIndex>"
                                                                    "GainSelector</pIndex>"
                                                                    "<Length>4</"
                                                                    "Length><AccessMode>RW</"
                                                                    "AccessMode><pPort>Device</"
                                                                    "pPort><Sign>Unsigned</"
                                                                    "Sign>"
                                                                    "<Endianess>LittleEndian</"
                                                                    "Endianess></IntReg>\n"
                                                                    "<IntReg "
                                                                    "Name=\"OffsetTable\"><"
                                                                    "Address>0x1200</Address>"
                                                                    "<pIndex "
                                                                    "Offset=\"0x10\">"
                                                                    "GainSelector</"
                                                                    "pIndex><Length>4</"
                                                                    "Length><AccessMode>RW</"
                                                                    "AccessMode>"
                                                                    "<pPort>Device</"
                                                                    "pPort><Sign>Unsigned</"
                                                                    "Sign><Endianess>"
                                                                    "LittleEndian</Endianess></"
                                                                    "IntReg>\n"
                                                                    "<IntReg "
                                                                    "Name=\"StrideTable\"><"
                                                                    "Address>0x1300</Address>"
                                                                    "<pIndex "
                                                                    "pOffset=\"Stride\">"
                                                                    "GainSelector</"
                                                                    "pIndex><Length>2</Length>"
                                                                    "<AccessMode>RW</"
                                                                    "AccessMode><pPort>Device</"
                                                                    "pPort><Sign>Unsigned</"
                                                                    "Sign>"
                                                                    "<Endianess>LittleEndian</"
                                                                    "Endianess></IntReg>\n"
                                                                    "<Integer "
                                                                    "Name=\"Stride\"><Value>8</"
                                                                    "Value></Integer>\n"
                                                                    "<IntReg "
                                                                    "Name=\"Indirect\"><"
                                                                    "pAddress>Base</"
                                                                    "pAddress><Address>0x8</"
                                                                    "Address><Length>4</Length>"
                                                                    "<AccessMode>RO</"
                                                                    "AccessMode><pPort>Device</"
                                                                    "pPort><Sign>Unsigned</"
                                                                    "Sign>"
                                                                    "<Endianess>LittleEndian</"
                                                                    "Endianess></IntReg>\n"
                                                                    "<Integer "
                                                                    "Name=\"Base\"><Value>"
                                                                    "0x2000</Value></Integer>\n"
                                                                    "<IntReg "
                                                                    "Name=\"FormulaAddressed\">"
                                                                    "<Address>0x3000</Address>"
                                                                    "<IntSwissKnife "
                                                                    "Name=\"FormulaOffset\"><"
                                                                    "pVariable "
                                                                    "Name=\"S\">GainSelector</"
                                                                    "pVariable>"
                                                                    "<Formula>S * "
                                                                    "0x100</Formula></"
                                                                    "IntSwissKnife><Length>4</"
                                                                    "Length><AccessMode>RO</"
                                                                    "AccessMode>"
                                                                    "<pPort>Device</"
                                                                    "pPort><Sign>Unsigned</"
                                                                    "Sign><Endianess>"
                                                                    "LittleEndian</Endianess></"
                                                                    "IntReg>\n"
                                                                    "<Integer "
                                                                    "Name=\"Lookup\"><pIndex>"
                                                                    "GainSelector</pIndex>"
                                                                    "<ValueIndexed "
                                                                    "Index=\"0\">10</"
                                                                    "ValueIndexed><"
                                                                    "ValueIndexed "
                                                                    "Index=\"1\">20</"
                                                                    "ValueIndexed>"
                                                                    "<ValueDefault>99</"
                                                                    "ValueDefault></Integer>\n"
                                                                    /* booleans, commands,
                                                                       strings, raw registers */
                                                                    "<Boolean "
                                                                    "Name=\"ReverseX\"><pValue>"
                                                                    "ReverseReg</"
                                                                    "pValue><OnValue>3</"
                                                                    "OnValue>"
                                                                    "<OffValue>0</OffValue></"
                                                                    "Boolean>\n" REG(
                                                                        "ReverseReg",
                                                                        "0x1080", "4", "RW",
                                                                        "LittleEndian",
                                                                        "Unsigned") "<Command "
                                                                                    "Name="
                                                                                    "\"Acquisit"
                                                                                    "ionStart\""
                                                                                    "><pValue>"
                                                                                    "AcqReg</"
                                                                                    "pValue><"
                                                                                    "CommandVal"
                                                                                    "ue>1</"
                                                                                    "CommandVal"
                                                                                    "ue>"
                                                                                    "</"
                                                                                    "Command>\n"
                                                                                    "<Command "
                                                                                    "Name="
                                                                                    "\"Acquisit"
                                                                                    "ionStop\">"
                                                                                    "<pValue>"
                                                                                    "AcqReg</"
                                                                                    "pValue>"
                                                                                    "<pCommandV"
                                                                                    "alue>"
                                                                                    "StopValue<"
                                                                                    "/pCommandV"
                                                                                    "alue></"
                                                                                    "Command>\n"
                                                                                    "<Integer "
                                                                                    "Name="
                                                                                    "\"StopValu"
                                                                                    "e\"><"
                                                                                    "Value>2</"
                                                                                    "Value></"
                                                                                    "Integer>"
                                                                                    "\n" REG(
                                                                                        "AcqRe"
                                                                                        "g",
                                                                                        "0x109"
                                                                                        "0",
                                                                                        "4",
                                                                                        "WO",
                                                                                        "Little"
                                                                                        "Endia"
                                                                                        "n",
                                                                                        "Unsign"
                                                                                        "ed") "<Str"
                                                                                              "ingR"
                                                                                              "eg "
                                                                                              "Name"
                                                                                              "=\"D"
                                                                                              "evic"
                                                                                              "eVen"
                                                                                              "dorN"
                                                                                              "ame"
                                                                                              "\"><"
                                                                                              "Addr"
                                                                                              "ess>"
                                                                                              "0x14"
                                                                                              "00</"
                                                                                              "Addr"
                                                                                              "ess>"
                                                                                              "<Len"
                                                                                              "gth>"
                                                                                              "16</"
                                                                                              "Leng"
                                                                                              "th>"
                                                                                              "<Acc"
                                                                                              "essM"
                                                                                              "ode>"
                                                                                              "RW</"
                                                                                              "Acce"
                                                                                              "ssMo"
                                                                                              "de><"
                                                                                              "pPor"
                                                                                              "t>"
                                                                                              "Devi"
                                                                                              "ce</"
                                                                                              "pPor"
                                                                                              "t></"
                                                                                              "Stri"
                                                                                              "ngRe"
                                                                                              "g>\n"
                                                                                              "<Str"
                                                                                              "ing "
                                                                                              "Name"
                                                                                              "=\"L"
                                                                                              "abel"
                                                                                              "\"><"
                                                                                              "Valu"
                                                                                              "e>"
                                                                                              "line"
                                                                                              " 1</"
                                                                                              "Valu"
                                                                                              "e></"
                                                                                              "Stri"
                                                                                              "ng>"
                                                                                              "\n"
                                                                                              "<Reg"
                                                                                              "iste"
                                                                                              "r "
                                                                                              "Name"
                                                                                              "=\"B"
                                                                                              "lob"
                                                                                              "\"><"
                                                                                              "Addr"
                                                                                              "ess>"
                                                                                              "0x15"
                                                                                              "00</"
                                                                                              "Addr"
                                                                                              "ess>"
                                                                                              "<Len"
                                                                                              "gth>"
                                                                                              "8</"
                                                                                              "Leng"
                                                                                              "th>"
                                                                                              "<Acc"
                                                                                              "essM"
                                                                                              "ode>"
                                                                                              "RO</"
                                                                                              "Acce"
                                                                                              "ssMo"
                                                                                              "de><"
                                                                                              "pPor"
                                                                                              "t>"
                                                                                              "Devi"
                                                                                              "ce</"
                                                                                              "pPor"
                                                                                              "t></"
                                                                                              "Regi"
                                                                                              "ster"
                                                                                              ">\n"
                                                                                              /* access
                                                                                                 modes
                                                                                               */
                                                                                              "<Int"
                                                                                              "eger"
                                                                                              " Nam"
                                                                                              "e="
                                                                                              "\"Lo"
                                                                                              "cked"
                                                                                              "\"><"
                                                                                              "pVal"
                                                                                              "ue>"
                                                                                              "Lock"
                                                                                              "edRe"
                                                                                              "g</"
                                                                                              "pVal"
                                                                                              "ue><"
                                                                                              "pIsL"
                                                                                              "ocke"
                                                                                              "d>"
                                                                                              "TLPa"
                                                                                              "rams"
                                                                                              "Lock"
                                                                                              "ed</"
                                                                                              "pIsL"
                                                                                              "ocke"
                                                                                              "d>"
                                                                                              "</"
                                                                                              "Inte"
                                                                                              "ger>"
                                                                                              "\n" REG(
                                                                                                  "LockedReg",
                                                                                                  "0x10A0",
                                                                                                  "4",
                                                                                                  "RW",
                                                                                                  "LittleEndian",
                                                                                                  "Unsigned") "<Integer Name=\"TLParamsLocked\"><Value>0</Value></Integer>\n"
                                                                                                              "<Integer Name=\"Hidden\"><pValue>WidthReg</pValue><pIsImplemented>Zero</pIsImplemented>"
                                                                                                              "</Integer>\n"
                                                                                                              "<Integer Name=\"Busy\"><pValue>WidthReg</pValue><pIsAvailable>Zero</pIsAvailable>"
                                                                                                              "</Integer>\n"
                                                                                                              "<Integer Name=\"Imposed\"><pValue>WidthReg</pValue><ImposedAccessMode>RO</ImposedAccessMode>"
                                                                                                              "</Integer>\n"
                                                                                                              "<Integer Name=\"Contradicts\"><pValue>AcqReg</pValue><ImposedAccessMode>RO"
                                                                                                              "</ImposedAccessMode></Integer>\n"
                                                                                                              /* ports that only frames and events have */
                                                                                                              "<IntReg Name=\"ChunkValue\"><Address>0</Address><Length>4</Length><AccessMode>RO</AccessMode>"
                                                                                                              "<pPort>ChunkPort</pPort><Sign>Unsigned</Sign><Endianess>LittleEndian</Endianess></IntReg>\n"
                                                                                                              "<IntReg Name=\"EventValue\"><Address>0</Address><Length>4</Length><AccessMode>RO</AccessMode>"
                                                                                                              "<pPort>EventPort</pPort><Sign>Unsigned</Sign><Endianess>LittleEndian</Endianess></IntReg>\n"
                                                                                                              /* what a description may get wrong */
                                                                                                              "<Integer Name=\"Dangling\"><pValue>Nowhere</pValue></Integer>\n"
                                                                                                              "<Integer Name=\"SelfLoop\"><pValue>SelfLoop</pValue></Integer>\n"
                                                                                                              "<Integer Name=\"LoopA\"><pValue>LoopB</pValue></Integer>\n"
                                                                                                              "<Integer Name=\"LoopB\"><pValue>LoopA</pValue></Integer>\n"
                                                                                                              "<IntReg Name=\"BadAddress\"><Address>0xZZ</Address><Length>4</Length>"
                                                                                                              "<AccessMode>RO</AccessMode><pPort>Device</pPort></IntReg>\n"
                                                                                                              "<SwissKnife Name=\"BadFormula\"><Formula>1 +</Formula></SwissKnife>\n"
                                                                                                              "</RegisterDescription>\n";

static flt_genicam *load_test_camera(void) {
    flt_genicam *g = NULL;
    ok(flt_genicam_load_memory(k_xml, sizeof k_xml - 1, &g));
    return g;
}

static void put(flt_genicam *g, uint64_t address, const uint8_t *bytes, size_t n) {
    ok(flt_genicam_set_memory(g, address, bytes, n));
}
static void put_le32(flt_genicam *g, uint64_t address, uint32_t v) {
    const uint8_t b[4] = {(uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24)};
    put(g, address, b, 4);
}
static uint32_t get_le32(flt_genicam *g, uint64_t address) {
    uint8_t b[4];
    ok(flt_genicam_get_memory(g, address, b, 4));
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
}
static int64_t get_int(flt_genicam *g, const char *feature) {
    int64_t v = 0;
    ok(flt_genicam_get_int(g, feature, &v));
    return v;
}
static double get_float(flt_genicam *g, const char *feature) {
    double v = 0;
    ok(flt_genicam_get_float(g, feature, &v));
    return v;
}
static const char *get_string(flt_genicam *g, const char *feature) {
    const char *v = NULL;
    ok(flt_genicam_get_string(g, feature, &v));
    return v;
}
static flt_genicam_access access_of(flt_genicam *g, const char *feature) {
    flt_genicam_access a = FLT_GENICAM_ACCESS_MAX_ENUM_;
    ok(flt_genicam_get_access(g, feature, &a));
    return a;
}

/* ---------------------------------------------------------------------- */
/* Tests                                                                   */
/* ---------------------------------------------------------------------- */

static void test_lists_features_with_type_kind_and_unit(void **state) {
    (void)state;
    flt_genicam *g = load_test_camera();
    const char *text = NULL;
    ok(flt_genicam_get_text(g, FLT_GENICAM_VENDOR_NAME, &text));
    assert_string_equal(text, "Flatline");
    ok(flt_genicam_get_text(g, FLT_GENICAM_MODEL_NAME, &text));
    assert_string_equal(text, "TestCam");
    ok(flt_genicam_get_text(g, FLT_GENICAM_SCHEMA_VERSION, &text));
    assert_string_equal(text, "1.1.0");
    size_t n = 0;
    ok(flt_genicam_feature_count(g, &n));
    /* every value or command node: not the category, the ports, or the
     * Integer inside <Extension> */
    int seen_width = 0, seen_entry = 0;
    for (size_t i = 0; i < n; ++i) {
        const char *name = NULL;
        ok(flt_genicam_feature_name(g, i, &name));
        assert_string_not_equal(name, "Root");
        assert_string_not_equal(name, "Device");
        assert_string_not_equal(name, "NotANode");
        seen_width += strcmp(name, "Width") == 0;
        seen_entry += strcmp(name, "StatusCount") == 0;
    }
    assert_int_equal(seen_width, 1);
    assert_int_equal(seen_entry, 1);
    assert_int_equal(n, 57); /* the named value and command nodes above, counted by hand */
    const char *name = NULL;
    assert_error(flt_genicam_feature_name(g, n, &name), FLT_ERR_NOT_FOUND, "past the");

    flt_genicam_type type;
    const char *kind = NULL, *unit = NULL;
    ok(flt_genicam_feature_info(g, "ExposureTime", &type, &kind, &unit));
    assert_int_equal(type, FLT_GENICAM_FLOAT);
    assert_string_equal(kind, "Converter");
    assert_string_equal(unit, "us");
    ok(flt_genicam_feature_info(g, "StatusCount", &type, &kind, NULL));
    assert_int_equal(type, FLT_GENICAM_INTEGER);
    assert_string_equal(kind, "StructEntry");
    ok(flt_genicam_feature_info(g, "GainSelector", &type, NULL, NULL));
    assert_int_equal(type, FLT_GENICAM_ENUMERATION);
    ok(flt_genicam_feature_info(g, "ReverseX", &type, NULL, NULL));
    assert_int_equal(type, FLT_GENICAM_BOOLEAN);
    ok(flt_genicam_feature_info(g, "AcquisitionStart", &type, NULL, NULL));
    assert_int_equal(type, FLT_GENICAM_COMMAND);
    ok(flt_genicam_feature_info(g, "DeviceVendorName", &type, NULL, NULL));
    assert_int_equal(type, FLT_GENICAM_STRING);
    ok(flt_genicam_feature_info(g, "Blob", &type, NULL, NULL));
    assert_int_equal(type, FLT_GENICAM_REGISTER);
    assert_error(flt_genicam_feature_info(g, "NotANode", &type, NULL, NULL), FLT_ERR_NOT_FOUND,
                 "'NotANode'");
    flt_genicam_destroy(g);
}

/* The feature tree: categories hold features and categories, in the file's
 * order; an entry may name a node the file lacks, and nothing is evaluated
 * (an entry whose register the memory image lacks is still listed). */
static void test_category_tree(void **state) {
    (void)state;
    static const char xml[] =
        "<RegisterDescription VendorName=\"V\" ModelName=\"M\">"
        "<Category Name=\"Root\"><pFeature>ImageFormatControl</pFeature>"
        "<pFeature>Gain</pFeature><pFeature>Ghost</pFeature></Category>"
        "<Category Name=\"ImageFormatControl\"><pFeature>Width</pFeature>"
        "<pFeature>PixelFormat</pFeature></Category>"
        "<IntReg Name=\"Width\"><Address>0x100</Address><Length>4</Length>"
        "<AccessMode>RW</AccessMode><pPort>Device</pPort></IntReg>"
        "<Enumeration Name=\"PixelFormat\"><EnumEntry Name=\"Mono8\"><Value>1</Value>"
        "</EnumEntry><Value>1</Value></Enumeration>"
        "<Float Name=\"Gain\"><Value>1.5</Value></Float>"
        "<Port Name=\"Device\"/>"
        "</RegisterDescription>";
    flt_genicam *g = NULL;
    ok(flt_genicam_load_memory(xml, sizeof xml - 1, &g));
    const char *want_root[] = {"ImageFormatControl", "Gain", "Ghost"};
    const char *want_format[] = {"Width", "PixelFormat"};
    const char *name = NULL;
    for (size_t i = 0; i < 3; ++i) {
        ok(flt_genicam_category_entry(g, "Root", i, &name));
        assert_string_equal(name, want_root[i]);
    }
    assert_error(flt_genicam_category_entry(g, "Root", 3, &name), FLT_ERR_NOT_FOUND,
                 "past the 3 entries");
    for (size_t i = 0; i < 2; ++i) {
        ok(flt_genicam_category_entry(g, "ImageFormatControl", i, &name));
        assert_string_equal(name, want_format[i]);
    }
    flt_genicam_type type;
    ok(flt_genicam_feature_info(g, "ImageFormatControl", &type, NULL, NULL));
    assert_int_equal(type, FLT_GENICAM_CATEGORY);
    ok(flt_genicam_feature_info(g, "Root", &type, NULL, NULL));
    assert_int_equal(type, FLT_GENICAM_CATEGORY);
    ok(flt_genicam_feature_info(g, "Width", &type, NULL, NULL));
    assert_int_equal(type, FLT_GENICAM_INTEGER);
    /* "Ghost" is listed but is no node */
    assert_error(flt_genicam_feature_info(g, "Ghost", &type, NULL, NULL), FLT_ERR_NOT_FOUND,
                 "'Ghost'");
    /* a feature or an unknown name is no category */
    assert_error(flt_genicam_category_entry(g, "Width", 0, &name), FLT_ERR_NOT_FOUND,
                 "no category");
    assert_error(flt_genicam_category_entry(g, "Nope", 0, &name), FLT_ERR_NOT_FOUND, "no category");
    /* categories are not features */
    size_t n = 0;
    ok(flt_genicam_feature_count(g, &n));
    assert_int_equal(n, 3);
    flt_genicam_destroy(g);
}

static void test_integer_registers_in_both_byte_orders(void **state) {
    (void)state;
    flt_genicam *g = load_test_camera();
    put_le32(g, 0x1000, 1920);
    assert_int_equal(get_int(g, "Width"), 1920);
    uint64_t address = 0;
    uint32_t length = 0, lsb = 99, msb = 99;
    int big = -1;
    ok(flt_genicam_register(g, "Width", &address, &length, &lsb, &msb, &big));
    assert_int_equal(address, 0x1000);
    assert_int_equal(length, 4);
    assert_int_equal(lsb, 0);
    assert_int_equal(msb, 31);
    assert_int_equal(big, 0);

    /* big endian, signed: FF FF FE 0C = 0xFFFFFE0C = -500 */
    const uint8_t be[4] = {0xFF, 0xFF, 0xFE, 0x0C};
    put(g, 0x1010, be, 4);
    assert_int_equal(get_int(g, "BigReg"), -500);
    /* 8 bytes, little endian: 0x0102030405060708 */
    const uint8_t wide[8] = {8, 7, 6, 5, 4, 3, 2, 1};
    put(g, 0x1018, wide, 8);
    assert_int_equal(get_int(g, "Wide"), 0x0102030405060708LL);

    /* 21 43 65 87 little endian = 0x87654321: bits 4..11 = 0x32, bits
     * 0..3 = 0x1 (signed: 1) */
    const uint8_t le[4] = {0x21, 0x43, 0x65, 0x87};
    put(g, 0x1020, le, 4);
    assert_int_equal(get_int(g, "LeBits"), 0x32);
    assert_int_equal(get_int(g, "SignedBits"), 1);
    put_le32(g, 0x1020, 0x0000000F); /* bits 0..3 = 1111 = -1 signed */
    assert_int_equal(get_int(g, "SignedBits"), -1);
    ok(flt_genicam_register(g, "LeBits", &address, &length, &lsb, &msb, &big));
    assert_int_equal(lsb, 4);
    assert_int_equal(msb, 11);

    /* big endian numbers bits from the top: LSB 31 .. MSB 24 is the low
     * byte of 12 34 56 78 = 0x12345678, so 0x78 */
    const uint8_t be2[4] = {0x12, 0x34, 0x56, 0x78};
    put(g, 0x1030, be2, 4);
    assert_int_equal(get_int(g, "BeBits"), 0x78);
    ok(flt_genicam_register(g, "BeBits", &address, &length, &lsb, &msb, &big));
    assert_int_equal(lsb, 0); /* in the value's own numbering */
    assert_int_equal(msb, 7);
    assert_int_equal(big, 1);

    /* writing a bit field keeps the bits around it */
    ok(flt_genicam_set_int(g, "BeBits", 0xAB));
    uint8_t back[4];
    ok(flt_genicam_get_memory(g, 0x1030, back, 4));
    assert_memory_equal(back, ((uint8_t[]){0x12, 0x34, 0x56, 0xAB}), 4);
    put(g, 0x1020, le, 4);
    ok(flt_genicam_set_int(g, "LeBits", 0xFF));
    assert_int_equal(get_le32(g, 0x1020), 0x87654FF1u);
    assert_error(flt_genicam_set_int(g, "LeBits", 256), FLT_ERR_INVALID_ARGUMENT, "8-bit");
    assert_error(flt_genicam_set_int(g, "SignedBits", 8), FLT_ERR_INVALID_ARGUMENT, "-8 .. 7");
    ok(flt_genicam_set_int(g, "SignedBits", -8));
    assert_int_equal(get_le32(g, 0x1020) & 0xF, 8);
    flt_genicam_destroy(g);
}

static void test_struct_entries_inherit_the_struct_reg(void **state) {
    (void)state;
    flt_genicam *g = load_test_camera();
    put_le32(g, 0x1040, 0x00002A01); /* ready bit 0 = 1, count bits 8..15 = 42 */
    assert_int_equal(get_int(g, "StatusReady"), 1);
    assert_int_equal(get_int(g, "StatusCount"), 42);
    /* the StructReg's AccessMode RO, overridden by the entry's RW */
    assert_int_equal(access_of(g, "StatusReady"), FLT_GENICAM_READ_ONLY);
    assert_int_equal(access_of(g, "StatusCount"), FLT_GENICAM_READ_WRITE);
    assert_error(flt_genicam_set_int(g, "StatusReady", 0), FLT_ERR_STATE, "read-only");
    ok(flt_genicam_set_int(g, "StatusCount", 7));
    assert_int_equal(get_le32(g, 0x1040), 0x00000701u);
    /* the StructReg's pIsImplemented is its entries' too */
    assert_int_equal(access_of(g, "GoneBit"), FLT_GENICAM_NOT_IMPLEMENTED);
    flt_genicam_destroy(g);
}

static void test_floats_and_converters(void **state) {
    (void)state;
    flt_genicam *g = load_test_camera();
    const float gain = 6.25f;
    uint8_t b[4];
    memcpy(b, &gain, 4); /* the host is little endian, as the register */
    put(g, 0x1050, b, 4);
    assert_true(get_float(g, "Gain") == 6.25);
    /* 8-byte big-endian double 2.5 = 0x4004000000000000 */
    const uint8_t d[8] = {0x40, 0x04, 0, 0, 0, 0, 0, 0};
    put(g, 0x1058, d, 8);
    assert_true(get_float(g, "BigDouble") == 2.5);
    /* A float register holding NaN or an infinity is refused, never read
     * as a number. */
    const uint8_t nan8[8] = {0x7F, 0xF8, 0, 0, 0, 0, 0, 0},
                  inf8[8] = {0x7F, 0xF0, 0, 0, 0, 0, 0, 0};
    double x = 0;
    put(g, 0x1058, nan8, 8);
    assert_error(flt_genicam_get_float(g, "BigDouble", &x), FLT_ERR_NUMERIC, "holds NaN");
    put(g, 0x1058, inf8, 8);
    assert_error(flt_genicam_get_float(g, "BigDouble", &x), FLT_ERR_NUMERIC, "an infinity");
    const uint8_t nan4[4] = {0, 0, 0xC0, 0x7F}; /* little-endian float NaN */
    put(g, 0x1050, nan4, 4);
    assert_error(flt_genicam_get_float(g, "Gain", &x), FLT_ERR_NUMERIC, "'GainReg' holds NaN");
    put(g, 0x1050, b, 4);
    put(g, 0x1058, d, 8);
    assert_true(get_float(g, "Ratio") == 1.5);
    ok(flt_genicam_set_float(g, "Gain", 12.5));
    memcpy(b, &(float){12.5f}, 4);
    uint8_t back[4];
    ok(flt_genicam_get_memory(g, 0x1050, back, 4));
    assert_memory_equal(back, b, 4);
    assert_error(flt_genicam_set_float(g, "Gain", 25.0), FLT_ERR_INVALID_ARGUMENT, "outside");
    double lo = 0, hi = 0;
    ok(flt_genicam_float_bounds(g, "Gain", &lo, &hi));
    assert_true(lo == 0.0 && hi == 24.0);

    /* ExposureTime = raw * 1.024 us: raw 1000 -> 1024 us (1.024 * 1000 is
     * 1024 to within one rounding of a double: 1e-9 relative) */
    put_le32(g, 0x1060, 1000);
    assert_float_equal(get_float(g, "ExposureTime"), 1024.0, 1024.0 * 1e-12);
    /* writing: 1000 us / 1.024 = 976.5625 raw, rounded to the nearest
     * count 977; read back 977 * 1.024 = 1000.448 */
    ok(flt_genicam_set_float(g, "ExposureTime", 1000.0));
    assert_int_equal(get_le32(g, 0x1060), 977);
    assert_float_equal(get_float(g, "ExposureTime"), 1000.448, 1000.448 * 1e-12);
    uint32_t lsb = 0, msb = 0;
    uint64_t address = 0;
    ok(flt_genicam_register(g, "ExposureTime", &address, NULL, &lsb, &msb, NULL));
    assert_int_equal(address, 0x1060); /* the raw register behind the formula */
    /* bounds through the formula: the register's 0 .. 2^32-1 counts */
    ok(flt_genicam_float_bounds(g, "ExposureTime", &lo, &hi));
    assert_true(lo == 0.0);
    assert_float_equal(hi, 4294967295.0 * 1.024, 1.0);

    /* IntConverter: TO / 2.0 of raw 977 is 488.5 in doubles, 488 in
     * integers: both readings truncate to 488 */
    assert_int_equal(get_int(g, "Halved"), 488);
    ok(flt_genicam_set_int(g, "Halved", 600));
    assert_int_equal(get_le32(g, 0x1060), 1200);
    /* (TO / 4) * 4: 1201 in integers is 1200, in doubles 1201: refused */
    put_le32(g, 0x1060, 1201);
    int64_t v = 0;
    assert_error(flt_genicam_get_int(g, "Ambiguous", &v), FLT_ERR_NUMERIC, "ambiguous");
    put_le32(g, 0x1060, 1200);
    assert_int_equal(get_int(g, "Ambiguous"), 1200);

    /* SwissKnife with a Constant, an Expression and PI: Width again */
    put_le32(g, 0x1000, 640);
    assert_float_equal(get_float(g, "Twice"), 640.0, 1e-9); /* + PI - PI: one rounding */
    flt_genicam_destroy(g);
}

static void test_selectors_computed_addresses_and_tables(void **state) {
    (void)state;
    flt_genicam *g = load_test_camera();
    put_le32(g, 0x1070, 1); /* GainSelector = Red */
    assert_string_equal(get_string(g, "GainSelector"), "Red");
    uint64_t address = 0;
    ok(flt_genicam_register(g, "GainRaw", &address, NULL, NULL, NULL, NULL));
    assert_int_equal(address, 0x1104); /* pIndex without Offset: its Length, 4 */
    ok(flt_genicam_register(g, "OffsetTable", &address, NULL, NULL, NULL, NULL));
    assert_int_equal(address, 0x1210); /* Offset 0x10 */
    ok(flt_genicam_register(g, "StrideTable", &address, NULL, NULL, NULL, NULL));
    assert_int_equal(address, 0x1308); /* pOffset Stride = 8 */
    ok(flt_genicam_register(g, "FormulaAddressed", &address, NULL, NULL, NULL, NULL));
    assert_int_equal(address, 0x3100); /* IntSwissKnife term S * 0x100 */
    ok(flt_genicam_register(g, "Indirect", &address, NULL, NULL, NULL, NULL));
    assert_int_equal(address, 0x2008); /* pAddress Base + 8 */
    assert_int_equal(get_int(g, "Lookup"), 20);
    put_le32(g, 0x1104, 77);
    assert_int_equal(get_int(g, "GainRaw"), 77);

    /* the selector moves the selected register */
    ok(flt_genicam_set_string(g, "GainSelector", "All"));
    assert_int_equal(get_le32(g, 0x1070), 0);
    ok(flt_genicam_register(g, "GainRaw", &address, NULL, NULL, NULL, NULL));
    assert_int_equal(address, 0x1100);
    assert_int_equal(get_int(g, "Lookup"), 10);
    put_le32(g, 0x1070, 2);
    assert_int_equal(get_int(g, "Lookup"), 99); /* ValueDefault */

    /* entries: availability per entry; the unavailable one is refused */
    size_t n = 0;
    ok(flt_genicam_enum_count(g, "GainSelector", &n));
    assert_int_equal(n, 4);
    const char *name = NULL;
    int64_t value = 0;
    int available = -1;
    ok(flt_genicam_enum_entry(g, "GainSelector", 2, &name, &value, &available));
    assert_string_equal(name, "Blue");
    assert_int_equal(value, 2);
    assert_int_equal(available, 0);
    ok(flt_genicam_enum_entry(g, "GainSelector", 1, &name, &value, &available));
    assert_int_equal(available, 1);
    assert_error(flt_genicam_enum_entry(g, "GainSelector", 4, &name, NULL, NULL), FLT_ERR_NOT_FOUND,
                 "past the");
    assert_error(flt_genicam_set_string(g, "GainSelector", "Blue"), FLT_ERR_STATE, "not available");
    assert_error(flt_genicam_set_string(g, "GainSelector", "Green"), FLT_ERR_STATE,
                 "not implemented");
    assert_error(flt_genicam_set_string(g, "GainSelector", "Purple"), FLT_ERR_NOT_FOUND,
                 "All, Red, Blue, Green");
    put_le32(g, 0x1070, 7);
    const char *entry = NULL;
    assert_error(flt_genicam_get_string(g, "GainSelector", &entry), FLT_ERR_NUMERIC,
                 "reads 7, which none of its entries has");
    assert_int_equal(get_int(g, "GainSelector"), 7);
    flt_genicam_destroy(g);
}

static void test_booleans_commands_strings_registers(void **state) {
    (void)state;
    flt_genicam *g = load_test_camera();
    put_le32(g, 0x1080, 3);
    assert_int_equal(get_int(g, "ReverseX"), 1);
    put_le32(g, 0x1080, 0);
    assert_int_equal(get_int(g, "ReverseX"), 0);
    put_le32(g, 0x1080, 5);
    int64_t v = 0;
    assert_error(flt_genicam_get_int(g, "ReverseX", &v), FLT_ERR_NUMERIC,
                 "neither its OnValue 3 nor its OffValue 0");
    ok(flt_genicam_set_int(g, "ReverseX", 1));
    assert_int_equal(get_le32(g, 0x1080), 3);

    ok(flt_genicam_execute(g, "AcquisitionStart"));
    assert_int_equal(get_le32(g, 0x1090), 1);
    ok(flt_genicam_execute(g, "AcquisitionStop")); /* pCommandValue */
    assert_int_equal(get_le32(g, 0x1090), 2);
    assert_int_equal(access_of(g, "AcquisitionStart"), FLT_GENICAM_WRITE_ONLY);
    assert_error(flt_genicam_execute(g, "Width"), FLT_ERR_INVALID_ARGUMENT, "not a Command");

    put(g, 0x1400, (const uint8_t *)"Flatline\0garbage", 16);
    assert_string_equal(get_string(g, "DeviceVendorName"), "Flatline");
    ok(flt_genicam_set_string(g, "DeviceVendorName", "Acme"));
    uint8_t s[16];
    ok(flt_genicam_get_memory(g, 0x1400, s, 16));
    assert_memory_equal(s, "Acme\0\0\0\0\0\0\0\0\0\0\0\0", 16);
    assert_error(flt_genicam_set_string(g, "DeviceVendorName", "seventeen bytes!!"),
                 FLT_ERR_INVALID_ARGUMENT, "does not fit");
    assert_string_equal(get_string(g, "Label"), "line 1");
    ok(flt_genicam_set_string(g, "Label", "line 2")); /* a host-side value */
    assert_string_equal(get_string(g, "Label"), "line 2");
    flt_genicam_type type;
    ok(flt_genicam_feature_info(g, "Blob", &type, NULL, NULL));
    uint64_t address = 0;
    uint32_t length = 0;
    ok(flt_genicam_register(g, "Blob", &address, &length, NULL, NULL, NULL));
    assert_int_equal(address, 0x1500);
    assert_int_equal(length, 8);
    flt_genicam_destroy(g);
}

static void test_access_modes_and_bounds(void **state) {
    (void)state;
    flt_genicam *g = load_test_camera();
    put_le32(g, 0x1000, 640);
    put_le32(g, 0x10A0, 5);
    assert_int_equal(access_of(g, "Width"), FLT_GENICAM_READ_WRITE);
    assert_int_equal(access_of(g, "Hidden"), FLT_GENICAM_NOT_IMPLEMENTED);
    assert_int_equal(access_of(g, "Busy"), FLT_GENICAM_NOT_AVAILABLE);
    assert_int_equal(access_of(g, "Imposed"), FLT_GENICAM_READ_ONLY);
    assert_int_equal(access_of(g, "Contradicts"), FLT_GENICAM_NOT_AVAILABLE); /* RO with WO */
    assert_int_equal(access_of(g, "Twice"), FLT_GENICAM_READ_ONLY);
    /* reads show what the registers hold whatever the access mode */
    assert_int_equal(get_int(g, "Hidden"), 640);
    assert_error(flt_genicam_set_int(g, "Hidden", 1), FLT_ERR_STATE, "pIsImplemented 'Zero'");
    assert_error(flt_genicam_set_int(g, "Busy", 1), FLT_ERR_STATE, "pIsAvailable 'Zero'");
    assert_error(flt_genicam_set_int(g, "Imposed", 1), FLT_ERR_STATE, "read-only");

    /* pIsLocked: the host's TLParamsLocked = 1 locks, as while streaming */
    assert_int_equal(access_of(g, "Locked"), FLT_GENICAM_READ_WRITE);
    ok(flt_genicam_set_int(g, "Locked", 6));
    ok(flt_genicam_set_int(g, "TLParamsLocked", 1));
    assert_int_equal(access_of(g, "Locked"), FLT_GENICAM_READ_ONLY);
    assert_error(flt_genicam_set_int(g, "Locked", 7), FLT_ERR_STATE, "locked");
    assert_int_equal(get_int(g, "Locked"), 6);

    /* bounds: pMin 32, Max 4096, Inc 16 */
    int64_t lo = 0, hi = 0, inc = 0;
    ok(flt_genicam_int_bounds(g, "Width", &lo, &hi, &inc));
    assert_int_equal(lo, 32);
    assert_int_equal(hi, 4096);
    assert_int_equal(inc, 16);
    ok(flt_genicam_set_int(g, "Width", 48));
    assert_int_equal(get_le32(g, 0x1000), 48);
    assert_error(flt_genicam_set_int(g, "Width", 16), FLT_ERR_INVALID_ARGUMENT,
                 "outside 32 .. 4096");
    assert_error(flt_genicam_set_int(g, "Width", 50), FLT_ERR_INVALID_ARGUMENT, "multiple of 16");
    /* a register's own range */
    ok(flt_genicam_int_bounds(g, "LeBits", &lo, &hi, &inc));
    assert_int_equal(lo, 0);
    assert_int_equal(hi, 255);
    ok(flt_genicam_int_bounds(g, "SignedBits", &lo, &hi, NULL));
    assert_int_equal(lo, -8);
    assert_int_equal(hi, 7);
    flt_genicam_destroy(g);
}

static void test_failures_name_the_node_chain(void **state) {
    (void)state;
    flt_genicam *g = load_test_camera();
    int64_t v = 0;
    double d = 0;
    /* a byte the image does not hold: the feature, the chain, the address */
    assert_error(flt_genicam_get_int(g, "Width", &v), FLT_ERR_NOT_FOUND,
                 "feature 'Width' (Width > WidthReg): register 0x1000 (4 bytes): the memory "
                 "image holds no byte at 0x1000");
    assert_error(flt_genicam_get_int(g, "Dangling", &v), FLT_ERR_FORMAT,
                 "pValue of 'Dangling' names 'Nowhere', which the description does not define");
    assert_error(flt_genicam_get_int(g, "SelfLoop", &v), FLT_ERR_FORMAT, "depends on itself");
    assert_error(flt_genicam_get_int(g, "LoopA", &v), FLT_ERR_FORMAT,
                 "(LoopA > LoopB > LoopA): node 'LoopA' depends on itself");
    assert_error(flt_genicam_get_int(g, "BadAddress", &v), FLT_ERR_FORMAT,
                 "Address '0xZZ' is not a number");
    assert_error(flt_genicam_get_float(g, "BadFormula", &d), FLT_ERR_FORMAT,
                 "formula '1 +': an operand is missing");
    assert_error(flt_genicam_get_int(g, "ChunkValue", &v), FLT_ERR_NOT_FOUND, "chunk port");
    assert_error(flt_genicam_get_int(g, "EventValue", &v), FLT_ERR_NOT_FOUND, "event port");
    assert_error(flt_genicam_get_int(g, "NoSuchFeature", &v), FLT_ERR_NOT_FOUND,
                 "'NoSuchFeature' is not in the description");
    assert_error(flt_genicam_get_int(g, "Label", &v), FLT_ERR_INVALID_ARGUMENT, "no integer value");
    assert_error(flt_genicam_get_float(g, "Root", &d), FLT_ERR_INVALID_ARGUMENT, "Category");
    assert_error(flt_genicam_register(g, "Twice", NULL, NULL, NULL, NULL, NULL), FLT_ERR_NOT_FOUND,
                 "no single register");
    /* the handle stays usable */
    put_le32(g, 0x1000, 800);
    assert_int_equal(get_int(g, "Width"), 800);
    flt_genicam_destroy(g);
}

/* ---- the formula language --------------------------------------------- */

static flt_genicam *formula_camera(const char *kind, const char *formula) {
    /* the formula as XML text: & and < escaped */
    char escaped[1400];
    size_t e = 0;
    for (const char *p = formula; *p && e + 6 < sizeof escaped; ++p) {
        const char *with = *p == '&' ? "&amp;" : *p == '<' ? "&lt;" : NULL;
        if (with) {
            memcpy(escaped + e, with, strlen(with));
            e += strlen(with);
        } else {
            escaped[e++] = *p;
        }
    }
    escaped[e] = 0;
    formula = escaped;
    char xml[2048];
    snprintf(xml, sizeof xml,
             "<RegisterDescription>"
             "<Integer Name=\"A\"><Value>5</Value></Integer>"
             "<Float Name=\"B\"><Value>2.5</Value></Float>"
             "<Integer Name=\"N\"><Value>-7</Value></Integer>"
             "<%s Name=\"F\"><pVariable Name=\"A\">A</pVariable><pVariable Name=\"B\">B</pVariable>"
             "<pVariable Name=\"N\">N</pVariable><Formula>%s</Formula></%s>"
             "</RegisterDescription>",
             kind, formula, kind);
    flt_genicam *g = NULL;
    ok(flt_genicam_load_memory(xml, strlen(xml), &g));
    return g;
}
static double swiss(const char *formula) {
    flt_genicam *g = formula_camera("SwissKnife", formula);
    double v = 0;
    if (flt_genicam_get_float(g, "F", &v) != FLT_OK)
        fail_msg("'%s': %s", formula, flt_last_error_message());
    flt_genicam_destroy(g);
    return v;
}
static int64_t int_swiss(const char *formula) {
    flt_genicam *g = formula_camera("IntSwissKnife", formula);
    int64_t v = 0;
    if (flt_genicam_get_int(g, "F", &v) != FLT_OK)
        fail_msg("'%s': %s", formula, flt_last_error_message());
    flt_genicam_destroy(g);
    return v;
}
static void refused(const char *kind, const char *formula, flt_status want, const char *needle) {
    flt_genicam *g = formula_camera(kind, formula);
    double v = 0;
    assert_error(flt_genicam_get_float(g, "F", &v), want, needle);
    flt_genicam_destroy(g);
}

static void test_formula_operators_and_precedence(void **state) {
    (void)state;
    /* Exact results: every value below is an integer or a dyadic fraction,
     * exactly representable, so == is the right comparison. */
    assert_true(swiss("1 + 2 * 3") == 7);
    assert_true(swiss("(1 + 2) * 3") == 9);
    assert_true(swiss("7 / 2") == 3.5);       /* SwissKnife: doubles */
    assert_int_equal(int_swiss("7 / 2"), 3);  /* IntSwissKnife: integers */
    assert_int_equal(int_swiss("N / 2"), -3); /* truncation toward zero */
    assert_int_equal(int_swiss("N % 3"), -1);
    assert_true(swiss("2 ** 3 ** 2") == 512);      /* right to left */
    assert_true(swiss("-2 ** 2") == 4);            /* unary minus binds tighter */
    assert_int_equal(int_swiss("1 << 4 + 1"), 32); /* + before << */
    assert_int_equal(int_swiss("0x100 >> 4"), 16);
    assert_int_equal(int_swiss("6 & 3 = 2"), 0); /* = before &: 6 & 0 */
    assert_int_equal(int_swiss("(6 & 3) = 2"), 1);
    assert_int_equal(int_swiss("6 | 1 ^ 3"), 6 | (1 ^ 3));
    assert_int_equal(int_swiss("~0"), -1);
    assert_int_equal(int_swiss("A > 4 && A < 6"), 1);
    assert_int_equal(int_swiss("A <> 5 || A >= 5"), 1);
    assert_int_equal(int_swiss("A <= 4"), 0);
    assert_int_equal(int_swiss("A = 5 ? 10 : 20"), 10);
    assert_int_equal(int_swiss("0 ? 1 : 0 ? 2 : 3"), 3); /* right to left */
    assert_int_equal(int_swiss("( A = 0 ? 1 : 0 ) && 1"), 0);
    assert_true(swiss("B * 2") == 5.0);
    assert_int_equal(int_swiss("B * 2"), 4); /* a Float variable truncated: 2 * 2 */
    /* bitwise operators truncate toward zero, as files rely on */
    assert_int_equal(int_swiss("5"), 5);
    assert_true(swiss("(B + 0.5) & 0xFFFF") == 3.0);
    /* functions, any case */
    assert_true(swiss("SGN(N)") == -1);
    assert_true(swiss("NEG(A)") == -5);
    assert_true(swiss("ABS(N)") == 7);
    assert_int_equal(int_swiss("ABS(N)"), 7);
    assert_true(swiss("TRUNC(-2.5)") == -2);
    assert_true(swiss("FLOOR(-2.5)") == -3);
    assert_true(swiss("CEIL(-2.5)") == -2);
    assert_true(swiss("ROUND(2.5)") == 3); /* half away from zero */
    assert_true(swiss("round(-2.5)") == -3);
    assert_true(swiss("ROUND(1.25, 1)") == 1.3); /* 12.5 -> 13, / 10: 1.3 as a double */
    assert_true(swiss("SQRT(16)") == 4);
    assert_true(swiss("EXP(0)") == 1);
    assert_true(swiss("LN(1)") == 0);
    assert_true(swiss("LG(1000)") == 3);
    /* transcendental: libm to within 4 ulp of the exact value */
    assert_float_equal(swiss("SIN(PI / 2)"), 1.0, 1e-15);
    assert_float_equal(swiss("COS(0) + TAN(0) + ATAN(1) * 4"), 1.0 + M_PI, 1e-15);
    assert_float_equal(swiss("ASIN(1) + ACOS(1)"), M_PI / 2, 1e-15);
    assert_float_equal(swiss("E"), M_E, 1e-15);
    assert_true(swiss("1.5e3 + 0x10") == 1516);
}

static void test_formula_refusals(void **state) {
    (void)state;
    refused("SwissKnife", "A / 0", FLT_ERR_NUMERIC, "division by zero");
    refused("IntSwissKnife", "A % 0", FLT_ERR_NUMERIC, "division by zero");
    refused("IntSwissKnife", "1 << 64", FLT_ERR_NUMERIC, "shift by 64");
    /* 1 << 63 would wrap to the most negative value; -1 << 63 is that
     * value and fits. */
    refused("IntSwissKnife", "1 << 63", FLT_ERR_NUMERIC, "overflows");
    refused("IntSwissKnife", "0xFFFFFFFF << 32", FLT_ERR_NUMERIC, "overflows");
    assert_int_equal(int_swiss("(0 - 1) << 63"), INT64_MIN);
    assert_int_equal(int_swiss("1 << 62"), INT64_C(1) << 62);
    refused("IntSwissKnife", "0x7FFFFFFFFFFFFFFF + 1", FLT_ERR_NUMERIC, "overflow");
    refused("IntSwissKnife", "2 ** 64", FLT_ERR_NUMERIC, "overflow");
    refused("SwissKnife", "0.5 && 1", FLT_ERR_NUMERIC, "a condition needs an integer");
    refused("SwissKnife", "B % 2", FLT_ERR_NUMERIC, "% needs an integer");
    refused("IntSwissKnife", "A * 0.5", FLT_ERR_NUMERIC, "integer formula");
    refused("SwissKnife", "SQRT(N)", FLT_ERR_NUMERIC, "not a finite number");
    refused("SwissKnife", "LN(0)", FLT_ERR_NUMERIC, "not a finite number");
    refused("SwissKnife", "010", FLT_ERR_FORMAT, "'010' is not a number");
    refused("SwissKnife", "Q + 1", FLT_ERR_FORMAT, "uses 'Q'");
    refused("SwissKnife", "(1 + 2", FLT_ERR_FORMAT, "without its ')'");
    refused("SwissKnife", "1 ? 2", FLT_ERR_FORMAT, "without its ':'");
    refused("SwissKnife", "FOO(1)", FLT_ERR_FORMAT, "no function");
    refused("SwissKnife", "1 $ 2", FLT_ERR_FORMAT, "unexpected '$'");
    refused("SwissKnife", " ", FLT_ERR_FORMAT, "empty");
    /* nesting beyond the limit is refused, not a deep recursion */
    char deep[600];
    size_t n = 0;
    for (int i = 0; i < 200; ++i)
        deep[n++] = '(';
    deep[n++] = '1';
    for (int i = 0; i < 200; ++i)
        deep[n++] = ')';
    deep[n] = 0;
    refused("SwissKnife", deep, FLT_ERR_FORMAT, "nested deeper");
}

/* ---- what real files carry -------------------------------------------- */

static const char k_small[] = "<RegisterDescription><Integer Name=\"X\"><Value>42</Value>"
                              "</Integer></RegisterDescription>";

static int64_t load_and_read_x(const void *bytes, size_t n) {
    flt_genicam *g = NULL;
    ok(flt_genicam_load_memory(bytes, n, &g));
    int64_t v = get_int(g, "X");
    flt_genicam_destroy(g);
    return v;
}

static void put16(uint8_t *p, uint16_t v) {
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}
static void put32(uint8_t *p, uint32_t v) {
    put16(p, (uint16_t)v);
    put16(p + 2, (uint16_t)(v >> 16));
}
/* A ZIP archive holding `data` in one stored (method 0) or deflated entry. */
static size_t make_zip(uint8_t *out, const void *data, size_t n, int deflated) {
    memset(out, 0, 30);
    put32(out, 0x04034b50u);
    put16(out + 4, 20);
    put16(out + 8, deflated ? 8 : 0);
    put32(out + 14, (uint32_t)crc32(0, data, (uInt)n));
    put32(out + 22, (uint32_t)n);
    put16(out + 26, 5);
    memcpy(out + 30, "x.xml", 5);
    size_t packed = n;
    if (deflated) {
        z_stream z;
        memset(&z, 0, sizeof z);
        assert_int_equal(deflateInit2(&z, 9, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY), Z_OK);
        z.next_in = (Bytef *)data;
        z.avail_in = (uInt)n;
        z.next_out = out + 35;
        z.avail_out = 4096;
        assert_int_equal(deflate(&z, Z_FINISH), Z_STREAM_END);
        packed = z.total_out;
        deflateEnd(&z);
    } else {
        memcpy(out + 35, data, n);
    }
    put32(out + 18, (uint32_t)packed);
    return 35 + packed;
}

static void test_loads_what_real_files_carry(void **state) {
    (void)state;
    char text[512];
    /* plain */
    assert_int_equal(load_and_read_x(k_small, sizeof k_small - 1), 42);
    /* a byte-order mark, then a declaration */
    int n = snprintf(text, sizeof text, "\xEF\xBB\xBF<?xml version=\"1.0\"?>\n%s", k_small);
    assert_int_equal(load_and_read_x(text, (size_t)n), 42);
    /* a dump's header line before the declaration */
    n = snprintf(text, sizeof text,
                 "Vendor-0123456789 (USB3)\r\n<?xml version=\"1.0\" "
                 "encoding=\"utf-8\"?>\n%s",
                 k_small);
    assert_int_equal(load_and_read_x(text, (size_t)n), 42);
    /* text and no declaration */
    n = snprintf(text, sizeof text, "garbage < 3\n%s", k_small);
    assert_int_equal(load_and_read_x(text, (size_t)n), 42);
    /* zipped, stored and deflated */
    uint8_t zip[4096];
    size_t z = make_zip(zip, k_small, sizeof k_small - 1, 0);
    assert_int_equal(load_and_read_x(zip, z), 42);
    z = make_zip(zip, k_small, sizeof k_small - 1, 1);
    assert_int_equal(load_and_read_x(zip, z), 42);

    flt_genicam *g = NULL;
    zip[20] ^= 1; /* the compressed size no longer matches */
    assert_error(flt_genicam_load_memory(zip, z, &g), FLT_ERR_FORMAT, "ZIP");
    assert_null(g);
    const char *bad = "<RegisterDescription><Integer Name=\"X\">";
    assert_error(flt_genicam_load_memory(bad, strlen(bad), &g), FLT_ERR_FORMAT, "malformed");
    const char *empty = "<RegisterDescription></RegisterDescription>";
    assert_error(flt_genicam_load_memory(empty, strlen(empty), &g), FLT_ERR_FORMAT, "no node");
    const char utf16[] = "\xFF\xFE<\0R\0";
    assert_error(flt_genicam_load_memory(utf16, sizeof utf16 - 1, &g), FLT_ERR_FORMAT, "UTF-16");
    assert_error(flt_genicam_load_memory("no markup", 9, &g), FLT_ERR_FORMAT, "no XML element");
    assert_error(flt_genicam_load("/nonexistent/camera.xml", &g), FLT_ERR_IO, "cannot open");
    const char *twice = "<RegisterDescription><Integer Name=\"X\"><Value>1</Value></Integer>"
                        "<Integer Name=\"X\"><Value>2</Value></Integer></RegisterDescription>";
    ok(flt_genicam_load_memory(twice, strlen(twice), &g));
    int64_t v = 0;
    assert_error(flt_genicam_get_int(g, "X", &v), FLT_ERR_FORMAT, "defines 'X' twice");
    flt_genicam_destroy(g);
}

/* ---- registers through callbacks ---------------------------------------- */

struct fake_device {
    uint8_t memory[0x2000];
    int reads, writes, fail_at;
};
static int FLT_CALL read_fake(void *user, uint64_t address, void *out, size_t bytes) {
    struct fake_device *d = user;
    ++d->reads;
    if (d->fail_at && address == (uint64_t)d->fail_at)
        return -3;
    if (address + bytes > sizeof d->memory)
        return -1;
    memcpy(out, d->memory + address, bytes);
    return 0;
}
static int FLT_CALL write_fake(void *user, uint64_t address, const void *in, size_t bytes) {
    struct fake_device *d = user;
    ++d->writes;
    if (address + bytes > sizeof d->memory)
        return -1;
    memcpy(d->memory + address, in, bytes);
    return 0;
}

static void test_registers_through_callbacks(void **state) {
    (void)state;
    flt_genicam *g = load_test_camera();
    struct fake_device dev;
    memset(&dev, 0, sizeof dev);
    dev.memory[0x1000] = 0x80; /* Width 0x280 = 640 */
    dev.memory[0x1001] = 0x02;
    ok(flt_genicam_set_registers(g, read_fake, NULL, &dev));
    assert_int_equal(get_int(g, "Width"), 640);
    assert_error(flt_genicam_set_int(g, "Width", 800), FLT_ERR_STATE, "write callback");
    ok(flt_genicam_set_registers(g, read_fake, write_fake, &dev));
    ok(flt_genicam_set_int(g, "Width", 800));
    assert_int_equal(dev.memory[0x1000] | (dev.memory[0x1001] << 8), 800);
    assert_int_equal(get_int(g, "Width"), 800);
    dev.fail_at = 0x1000;
    int64_t v = 0;
    assert_error(flt_genicam_get_int(g, "Width", &v), FLT_ERR_DEVICE,
                 "the read callback returned -3 for 0x1000");
    /* back to the (empty) memory image */
    ok(flt_genicam_set_registers(g, NULL, NULL, NULL));
    assert_error(flt_genicam_get_int(g, "Width", &v), FLT_ERR_NOT_FOUND, "memory image");
    assert_error(flt_genicam_set_registers(g, NULL, write_fake, &dev), FLT_ERR_INVALID_ARGUMENT,
                 "'read' is NULL");
    flt_genicam_destroy(g);
}

static void test_memory_image_limits(void **state) {
    (void)state;
    flt_genicam *g = load_test_camera();
    uint8_t b[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    assert_error(flt_genicam_set_memory(g, UINT64_MAX - 2, b, 8), FLT_ERR_INVALID_ARGUMENT,
                 "past 2^64");
    ok(flt_genicam_set_memory(g, UINT64_MAX - 7, b, 8)); /* the last 8 bytes */
    uint8_t back[8];
    ok(flt_genicam_get_memory(g, UINT64_MAX - 7, back, 8));
    assert_memory_equal(back, b, 8);
    assert_error(flt_genicam_set_memory(g, 0, b, 0), FLT_ERR_INVALID_ARGUMENT, "'count' = 0");
    assert_error(flt_genicam_get_memory(g, 0x10, back, 4), FLT_ERR_NOT_FOUND, "0x10");
    ok(flt_genicam_clear_memory(g));
    assert_error(flt_genicam_get_memory(g, UINT64_MAX - 7, back, 8), FLT_ERR_NOT_FOUND, NULL);
    flt_genicam_destroy(g);
    flt_genicam_destroy(NULL);
}

/* A description's size is bounded while it is read: more than 65536 nodes
 * or 1,000,000 elements is refused (the largest real one has about 4,000
 * nodes in 24,000 elements) before its nodes cost gigabytes. */
static char *repeated(const char *head, const char *item, size_t count, const char *tail) {
    const size_t n = strlen(head) + strlen(item) * count + strlen(tail) + 1;
    char *text = malloc(n);
    assert_non_null(text);
    char *p = text;
    p += sprintf(p, "%s", head);
    for (size_t i = 0; i < count; ++i)
        p += sprintf(p, "%s", item);
    sprintf(p, "%s", tail);
    return text;
}

static void test_description_size_is_capped(void **state) {
    (void)state;
    flt_genicam *g = NULL;
    char *nodes =
        repeated("<RegisterDescription>", "<Integer Name=\"N\"><Value>1</Value></Integer>", 65537,
                 "</RegisterDescription>");
    /* (all named N: the cap comes before the duplicate-name check can
     * matter, which marks nodes broken without refusing the file) */
    assert_error(flt_genicam_load_memory(nodes, strlen(nodes), &g), FLT_ERR_FORMAT,
                 "more than 65536 nodes");
    assert_null(g);
    free(nodes);
    char *elements = repeated("<RegisterDescription><Integer Name=\"X\"><Value>1</Value>",
                              "<ToolTip/>", 1000000, "</Integer></RegisterDescription>");
    assert_error(flt_genicam_load_memory(elements, strlen(elements), &g), FLT_ERR_FORMAT,
                 "more than 1000000 elements");
    free(elements);
    /* Exactly at the node cap loads (X and 65535 N: 65536 nodes; the
     * duplicates are its own problem). */
    char *many =
        repeated("<RegisterDescription><Integer Name=\"X\"><Value>42</Value></Integer>",
                 "<Integer Name=\"N\"><Value>1</Value></Integer>", 65535, "</RegisterDescription>");
    ok(flt_genicam_load_memory(many, strlen(many), &g));
    assert_int_equal(get_int(g, "X"), 42);
    flt_genicam_destroy(g);
    free(many);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lists_features_with_type_kind_and_unit),
        cmocka_unit_test(test_category_tree),
        cmocka_unit_test(test_integer_registers_in_both_byte_orders),
        cmocka_unit_test(test_struct_entries_inherit_the_struct_reg),
        cmocka_unit_test(test_floats_and_converters),
        cmocka_unit_test(test_selectors_computed_addresses_and_tables),
        cmocka_unit_test(test_booleans_commands_strings_registers),
        cmocka_unit_test(test_access_modes_and_bounds),
        cmocka_unit_test(test_failures_name_the_node_chain),
        cmocka_unit_test(test_formula_operators_and_precedence),
        cmocka_unit_test(test_formula_refusals),
        cmocka_unit_test(test_loads_what_real_files_carry),
        cmocka_unit_test(test_registers_through_callbacks),
        cmocka_unit_test(test_memory_image_limits),
        cmocka_unit_test(test_description_size_is_capped),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
