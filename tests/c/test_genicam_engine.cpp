// SPDX-License-Identifier: Apache-2.0
/*
 * The GenICam engine's register cache (lib/sources/genicam/node_map.hpp,
 * internal): what a camera client sees through its port. A counting port
 * records every read and write; each test says how many transactions a
 * sequence of feature reads and writes must cost, and that a value read
 * after an invalidating write is the device's new one, not a stale copy.
 */
#include <cstdint>
#include <cstring>
#include <map>
#include <string>

#include "sources/genicam/node_map.hpp"

// CMocka last: it defines a macro fail() that the library's headers must not see.
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

extern "C" {  // this CMocka's header has no C++ guards
#include <cmocka.h>
}

namespace {

using flt::genicam::node_map;

// Device memory with counters; the device itself may change a register
// (poke) the way a camera changes PayloadSize when Width is written.
struct counting_port : flt::genicam::register_port {
    std::map<std::uint64_t, std::uint8_t> memory;
    int reads = 0, writes = 0;
    void read(std::uint64_t a, std::uint8_t *out, std::size_t n) override {
        ++reads;
        for (std::size_t i = 0; i < n; ++i)
            out[i] = memory.count(a + i) ? memory[a + i] : 0;
    }
    void write(std::uint64_t a, const std::uint8_t *in, std::size_t n) override {
        ++writes;
        for (std::size_t i = 0; i < n; ++i)
            memory[a + i] = in[i];
    }
    void poke32(std::uint64_t a, std::uint32_t v) {
        for (int i = 0; i < 4; ++i)
            memory[a + i] = std::uint8_t(v >> (8 * i));
    }
};

#define REG(name, address, extra)                                                  \
  "<IntReg Name=\"" name "\"><Address>" address "</Address><Length>4</Length>"     \
  "<AccessMode>RW</AccessMode><pPort>Device</pPort>" extra "<Sign>Unsigned</Sign>" \
  "<Endianess>LittleEndian</Endianess></IntReg>"

const char k_xml[] =
    "<RegisterDescription SchemaMajorVersion=\"1\" SchemaMinorVersion=\"0\">"
    "<Port Name=\"Device\"/>" REG("Width", "0x100", "") REG("Payload", "0x104",
                                                            "<pInvalidator>Width</pInvalidator>")
        REG("PayloadCopy", "0x108", "<pInvalidator>Payload</pInvalidator>") REG(
            "Status", "0x10C", "<Cachable>NoCache</Cachable>")
            REG("Temperature", "0x110", "<PollingTime>1000</PollingTime>") REG(
                "Around", "0x114",
                "<Cachable>WriteAround</Cachable>") "<MaskedIntReg "
                                                    "Name=\"Low\"><Address>0x118</"
                                                    "Address><Length>4</Length>"
                                                    "<AccessMode>RW</AccessMode><pPort>Device</"
                                                    "pPort><LSB>0</LSB><MSB>7</MSB>"
                                                    "<Endianess>LittleEndian</Endianess></"
                                                    "MaskedIntReg>"
                                                    "<MaskedIntReg "
                                                    "Name=\"High\"><Address>0x118</"
                                                    "Address><Length>4</Length>"
                                                    "<AccessMode>RW</AccessMode><pPort>Device</"
                                                    "pPort><LSB>8</LSB><MSB>15</MSB>"
                                                    "<Endianess>LittleEndian</Endianess></"
                                                    "MaskedIntReg>"
                                                    "<Enumeration Name=\"Selector\"><EnumEntry "
                                                    "Name=\"A\"><Value>0</Value></EnumEntry>"
                                                    "<EnumEntry "
                                                    "Name=\"B\"><Value>1</Value></"
                                                    "EnumEntry><pValue>SelectorReg</pValue>"
                                                    "<pSelected>Selected</pSelected></"
                                                    "Enumeration>" REG("SelectorReg", "0x120", "")
                                                        REG("Selected", "0x130",
                                                            "") "<Command "
                                                                "Name=\"Start\"><pValue>"
                                                                "StartReg</"
                                                                "pValue><CommandValue>1</"
                                                                "CommandValue></"
                                                                "Command>" REG("StartReg", "0x140",
                                                                               "") "</"
                                                                                   "Registe"
                                                                                   "rDescri"
                                                                                   "ption>";

struct fixture {
    counting_port port;
    node_map map;
    fixture() {
        map.load(k_xml);
        map.bind(&port);
    }
};

void test_a_cached_register_is_read_once(void **) {
    fixture f;
    f.port.poke32(0x100, 640);
    assert_int_equal(f.map.get_int("Width"), 640);
    assert_int_equal(f.map.get_int("Width"), 640);
    assert_int_equal(f.port.reads, 1);
    // NoCache and polled registers are read every time.
    f.map.get_int("Status");
    f.map.get_int("Status");
    f.map.get_int("Temperature");
    f.map.get_int("Temperature");
    assert_int_equal(f.port.reads, 5);
    // invalidate() forgets; caching off reads every time
    f.map.invalidate();
    f.map.get_int("Width");
    assert_int_equal(f.port.reads, 6);
    f.map.set_caching(false);
    f.map.get_int("Width");
    f.map.get_int("Width");
    assert_int_equal(f.port.reads, 8);
}

void test_writes_update_or_drop_the_cache(void **) {
    fixture f;
    f.map.set_int("Width", 800);  // WriteThrough: the written value is cached
    assert_int_equal(f.port.writes, 1);
    assert_int_equal(f.map.get_int("Width"), 800);
    assert_int_equal(f.port.reads, 0);
    f.map.set_int("Around", 5);  // WriteAround: read back from the device
    f.port.poke32(0x114, 6);     // (which may have adjusted it)
    assert_int_equal(f.map.get_int("Around"), 6);
    assert_int_equal(f.port.reads, 1);
}

void test_invalidators_drop_what_a_write_changes(void **) {
    fixture f;
    f.port.poke32(0x104, 1000);
    f.port.poke32(0x108, 1000);
    assert_int_equal(f.map.get_int("Payload"), 1000);
    assert_int_equal(f.map.get_int("PayloadCopy"), 1000);
    // The camera changes Payload when Width is written (and PayloadCopy
    // follows Payload): both are read again, transitively.
    f.map.set_int("Width", 320);
    f.port.poke32(0x104, 500);
    f.port.poke32(0x108, 500);
    const int before = f.port.reads;
    assert_int_equal(f.map.get_int("Payload"), 500);
    assert_int_equal(f.map.get_int("PayloadCopy"), 500);
    assert_int_equal(f.port.reads, before + 2);
}

void test_overlapping_bit_fields_and_selectors(void **) {
    fixture f;
    f.port.poke32(0x118, 0x1234);
    assert_int_equal(f.map.get_int("Low"), 0x34);
    assert_int_equal(f.map.get_int("High"), 0x12);
    // Writing Low rewrites the word: High is read again and unchanged.
    f.map.set_int("Low", 0x56);
    assert_int_equal(f.port.memory[0x118], 0x56);
    assert_int_equal(f.map.get_int("High"), 0x12);
    assert_int_equal(f.map.get_int("Low"), 0x56);
    // A selector changes what its selected registers show.
    f.port.poke32(0x130, 7);
    assert_int_equal(f.map.get_int("Selected"), 7);
    f.map.set_enum("Selector", "B");
    f.port.poke32(0x130, 8);
    assert_int_equal(f.map.get_int("Selected"), 8);
}

void test_commands_and_their_completion(void **) {
    fixture f;
    f.map.execute("Start");
    assert_int_equal(f.port.memory[0x140], 1);
    // Done when the register no longer reads the command value: polled
    // from the device even though the write went through the cache.
    assert_false(f.map.is_done("Start"));
    f.port.poke32(0x140, 0);
    assert_true(f.map.is_done("Start"));
}

void test_schema_version(void **) {
    fixture f;
    // 1.0: a GigE Vision port reads 4-byte registers big-endian (GenICam 2.0, appendix 3)
    assert_int_equal(f.map.schema_version(), 10000);
}

}  // namespace

int main() {
    const CMUnitTest tests[] = {
        cmocka_unit_test(test_a_cached_register_is_read_once),
        cmocka_unit_test(test_writes_update_or_drop_the_cache),
        cmocka_unit_test(test_invalidators_drop_what_a_write_changes),
        cmocka_unit_test(test_overlapping_bit_fields_and_selectors),
        cmocka_unit_test(test_commands_and_their_completion),
        cmocka_unit_test(test_schema_version),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
