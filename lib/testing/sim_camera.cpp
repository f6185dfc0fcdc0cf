// SPDX-License-Identifier: Apache-2.0
// The simulated USB3 Vision camera: descriptors, a register map answering
// GenCP, a manifest with a (zipped) GenICam XML, and a stream of leader,
// payload and trailer transfers with USB bulk packet semantics and
// injectable faults. Time is virtual: waiting for nothing returns "timeout"
// at once.
#include "testing/sim_camera.hpp"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "core/error.hpp"
#include "sources/u3v/protocol.hpp"

namespace flt::testing {

using namespace u3v;  // the wire format and the transport interface

namespace {

constexpr std::uint16_t k_sim_vendor_id = 0xF1A7;  // not a registered id
constexpr std::uint8_t k_ep_control_in = 0x81, k_ep_control_out = 0x01, k_ep_event = 0x82,
                       k_ep_stream = 0x83;
constexpr std::uint32_t k_image_chunk_id = 0x00000001u;

// The camera's GenICam XML. ExposureTime goes through a Converter (a
// formula) of its raw register, PayloadSize through an IntSwissKnife.
std::string make_xml(const std::string &vendor, const std::string &model) {
    auto int_reg = [](const char *name, std::uint64_t address) {
        char text[512];
        std::snprintf(text, sizeof text,
                      "    <IntReg Name=\"%s\">\n"
                      "      <Address>0x%llx</Address>\n"
                      "      <Length>4</Length>\n"
                      "      <AccessMode>RW</AccessMode>\n"
                      "      <pPort>Device</pPort>\n"
                      "      <Sign>Unsigned</Sign>\n"
                      "      <Endianess>LittleEndian</Endianess>\n"
                      "    </IntReg>\n",
                      name, (unsigned long long)address);
        return std::string(text);
    };
    auto enumeration = [&](const char *name, const char *reg,
                           const std::vector<std::pair<const char *, std::uint32_t>> &entries) {
        std::string s = std::string("    <Enumeration Name=\"") + name +
                        "\" NameSpace=\"Standard\">\n" + "      <ToolTip>" + name + "</ToolTip>\n";
        for (const auto &e : entries) {
            char text[256];
            std::snprintf(text, sizeof text,
                          "      <EnumEntry Name=\"%s\" NameSpace=\"Standard\">\n"
                          "        <Value>0x%x</Value>\n"
                          "      </EnumEntry>\n",
                          e.first, e.second);
            s += text;
        }
        s += std::string("      <pValue>") + reg + "</pValue>\n    </Enumeration>\n";
        return s;
    };
    std::string x;
    x += "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n";
    x += "<RegisterDescription ModelName=\"" + model + "\" VendorName=\"" + vendor +
         "\" ToolTip=\"Simulated USB3 Vision camera\" StandardNameSpace=\"None\" "
         "SchemaMajorVersion=\"1\" SchemaMinorVersion=\"1\" SchemaSubMinorVersion=\"0\" "
         "MajorVersion=\"1\" MinorVersion=\"0\" SubMinorVersion=\"0\" "
         "ProductGuid=\"00000000-0000-0000-0000-000000000001\" "
         "VersionGuid=\"00000000-0000-0000-0000-000000000002\" "
         "xmlns=\"http://www.genicam.org/GenApi/Version_1_1\">\n";
    x += "  <Category Name=\"Root\" NameSpace=\"Standard\">\n"
         "    <pFeature>ImageFormatControl</pFeature>\n"
         "    <pFeature>AcquisitionControl</pFeature>\n"
         "  </Category>\n"
         "  <Category Name=\"ImageFormatControl\" NameSpace=\"Standard\">\n"
         "    <pFeature>Width</pFeature><pFeature>Height</pFeature>\n"
         "    <pFeature>OffsetY</pFeature><pFeature>PixelFormat</pFeature>\n"
         "  </Category>\n";
    x += "  <Group Comment=\"Image format\">\n";
    x += "    <Integer Name=\"Width\" NameSpace=\"Standard\">\n"
         "      <pIsLocked>TLParamsLocked</pIsLocked>\n"
         "      <pValue>WidthReg</pValue>\n      <Min>16</Min>\n"
         "      <Inc>4</Inc>\n    </Integer>\n";
    // The host's lock while it acquires (SFNC): a host-side value.
    x += "    <Integer Name=\"TLParamsLocked\" NameSpace=\"Standard\">\n"
         "      <Value>0</Value>\n    </Integer>\n";
    x += int_reg("WidthReg", sim_map::width);
    x += int_reg("Height", sim_map::height);
    char masked[512];
    std::snprintf(masked, sizeof masked,
                  "    <MaskedIntReg Name=\"OffsetY\" NameSpace=\"Standard\">\n"
                  "      <Address>0x%llx</Address>\n      <Length>4</Length>\n"
                  "      <AccessMode>RW</AccessMode>\n      <pPort>Device</pPort>\n"
                  "      <LSB>0</LSB>\n      <MSB>15</MSB>\n"
                  "      <Sign>Unsigned</Sign>\n"
                  "      <Endianess>LittleEndian</Endianess>\n"
                  "    </MaskedIntReg>\n",
                  (unsigned long long)sim_map::offset_y);
    x += masked;
    x += enumeration("PixelFormat", "PixelFormatReg",
                     {{"Mono8", k_pfnc_mono8},
                      {"Mono10", k_pfnc_mono10},
                      {"Mono12", k_pfnc_mono12},
                      {"Mono16", k_pfnc_mono16}});
    x += int_reg("PixelFormatReg", sim_map::pixel_format);
    x += "  </Group>\n";
    x += enumeration("AcquisitionMode", "AcquisitionModeReg",
                     {{"Continuous", 0}, {"SingleFrame", 1}, {"MultiFrame", 2}});
    x += int_reg("AcquisitionModeReg", sim_map::acquisition_mode);
    x += "  <Command Name=\"AcquisitionStart\" NameSpace=\"Standard\">\n"
         "    <pValue>AcquisitionStartReg</pValue>\n"
         "    <CommandValue>1</CommandValue>\n  </Command>\n";
    x += int_reg("AcquisitionStartReg", sim_map::acquisition_start);
    x += "  <Command Name=\"AcquisitionStop\" NameSpace=\"Standard\">\n"
         "    <pValue>AcquisitionStopReg</pValue>\n"
         "    <CommandValue>1</CommandValue>\n  </Command>\n";
    x += int_reg("AcquisitionStopReg", sim_map::acquisition_stop);
    x += "  <Converter Name=\"ExposureTime\" NameSpace=\"Standard\">\n"
         "    <pVariable Name=\"OFFSET\">ExposureTimeOffset</pVariable>\n"
         "    <FormulaTo>FROM - OFFSET</FormulaTo>\n"
         "    <FormulaFrom>TO + OFFSET</FormulaFrom>\n"
         "    <pValue>ExposureTimeRaw</pValue>\n"
         "    <Unit>us</Unit>\n  </Converter>\n";
    x += "  <Integer Name=\"ExposureTimeOffset\">\n    <Value>0</Value>\n  </Integer>\n";
    x += int_reg("ExposureTimeRaw", sim_map::exposure_raw);
    x +=
        enumeration("TriggerSelector", "TriggerSelectorReg", {{"FrameStart", 0}, {"LineStart", 1}});
    x += int_reg("TriggerSelectorReg", sim_map::trigger_selector);
    x += enumeration("TriggerMode", "TriggerModeReg", {{"Off", 0}, {"On", 1}});
    x += int_reg("TriggerModeReg", sim_map::trigger_mode);
    x += enumeration("TriggerSource", "TriggerSourceReg",
                     {{"Software", 0}, {"Line0", 1}, {"Encoder0", 2}});
    x += int_reg("TriggerSourceReg", sim_map::trigger_source);
    char gain[512];
    std::snprintf(gain, sizeof gain,
                  "  <Float Name=\"Gain\" NameSpace=\"Standard\">\n"
                  "    <pValue>GainReg</pValue>\n    <Unit>dB</Unit>\n  </Float>\n"
                  "  <FloatReg Name=\"GainReg\">\n    <Address>0x%llx</Address>\n"
                  "    <Length>4</Length>\n    <AccessMode>RW</AccessMode>\n"
                  "    <pPort>Device</pPort>\n"
                  "    <Endianess>LittleEndian</Endianess>\n  </FloatReg>\n",
                  (unsigned long long)sim_map::gain);
    x += gain;
    x += "  <IntSwissKnife Name=\"PayloadSize\" NameSpace=\"Standard\">\n"
         "    <pVariable Name=\"W\">Width</pVariable>\n"
         "    <pVariable Name=\"H\">Height</pVariable>\n"
         "    <Formula>W * H</Formula>\n  </IntSwissKnife>\n";
    x += "  <Port Name=\"Device\" NameSpace=\"Standard\"/>\n";
    x += "</RegisterDescription>\n";
    return x;
}

// A ZIP archive of one deflated file (local header, data, central directory).
std::vector<std::uint8_t> make_zip(const std::string &name, const std::string &text) {
    z_stream z{};
    if (deflateInit2(&z, 9, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK)
        throw std::runtime_error("deflateInit2 failed");
    std::vector<std::uint8_t> packed(deflateBound(&z, uLong(text.size())) + 16);
    z.next_in = reinterpret_cast<Bytef *>(const_cast<char *>(text.data()));
    z.avail_in = uInt(text.size());
    z.next_out = packed.data();
    z.avail_out = uInt(packed.size());
    deflate(&z, Z_FINISH);
    packed.resize(z.total_out);
    deflateEnd(&z);
    const std::uint32_t crc =
        std::uint32_t(crc32(0, reinterpret_cast<const Bytef *>(text.data()), uInt(text.size())));
    std::vector<std::uint8_t> zip(30 + name.size());
    std::uint8_t *h = zip.data();
    put_u32(h, 0x04034b50u);
    put_u16(h + 4, 20);
    put_u16(h + 6, 0);
    put_u16(h + 8, 8);  // deflate
    put_u32(h + 14, crc);
    put_u32(h + 18, std::uint32_t(packed.size()));
    put_u32(h + 22, std::uint32_t(text.size()));
    put_u16(h + 26, std::uint16_t(name.size()));
    // NOLINTNEXTLINE(bugprone-not-null-terminated-result): a ZIP name field has no NUL
    std::memcpy(h + 30, name.data(), name.size());
    zip.insert(zip.end(), packed.begin(), packed.end());
    const std::size_t central = zip.size();
    std::vector<std::uint8_t> c(46 + name.size());
    put_u32(c.data(), 0x02014b50u);
    put_u16(&c[4], 20);
    put_u16(&c[6], 20);
    put_u16(&c[10], 8);
    put_u32(&c[16], crc);
    put_u32(&c[20], std::uint32_t(packed.size()));
    put_u32(&c[24], std::uint32_t(text.size()));
    put_u16(&c[28], std::uint16_t(name.size()));
    std::memcpy(&c[46], name.data(), name.size());
    zip.insert(zip.end(), c.begin(), c.end());
    std::vector<std::uint8_t> end(22);
    put_u32(end.data(), 0x06054b50u);
    put_u16(&end[8], 1);
    put_u16(&end[10], 1);
    put_u32(&end[12], std::uint32_t(c.size()));
    put_u32(&end[16], std::uint32_t(central));
    zip.insert(zip.end(), end.begin(), end.end());
    return zip;
}

}  // namespace

// One transfer as the device sends it: a run of packets, the last one short
// unless the length is a multiple of the packet size (no zero-length packet,
// as USB3 Vision devices do). Markers model a stall and an unplug.
struct device_transfer {
    std::vector<std::uint8_t> bytes;
    std::size_t offset = 0;
    enum kind_t { data, stall, unplug } kind = data;
};

struct sim_camera {
    std::string vendor, model, serial;
    std::uint32_t sensor_width, sensor_height;
    std::vector<std::uint8_t> regs = std::vector<std::uint8_t>(0x20000, 0);
    std::string xml_text;
    std::vector<std::uint8_t> xml_file;

    // parameters
    std::uint32_t response_ms = 200, max_cmd = 1024, max_ack = 1024;
    std::uint32_t alignment_log2 = 9, speed_mbps = 5000;
    bool xml_zipped = true, encoder_chunk = false;
    std::uint32_t encoder_chunk_id = 0x4E434445u, um_per_count = 10;
    flt_sim *frames = nullptr;

    // state
    bool open = false, unplugged = false, acquiring = false;
    std::uint64_t next_block = 1;
    std::uint64_t commands = 0, frames_sent = 0;
    unsigned last_read_timeout = 0;
    std::deque<std::vector<std::uint8_t>> acks;
    std::vector<std::uint8_t> held_ack;  // LATE_ACK: sent after the next command
    // Control-channel faults, by the index of the command they hit (counted
    // from 0 with `commands`): commands first..last.
    struct control_fault {
        flt_u3v_fault kind;
        std::uint64_t first, last;
        std::uint32_t count;  // PENDING_ACK: pending acks per command
    };
    std::vector<control_fault> control_faults;
    std::deque<device_transfer> fifo;
    // SUBMIT_REFUSED: the bulk submissions first..last (counted with `submits`).
    std::uint64_t submits = 0;
    std::vector<std::pair<std::uint64_t, std::uint64_t>> refused_submits;

    struct stream_fault {
        flt_u3v_fault kind;
        std::uint64_t at;
        std::uint32_t count;
    };
    std::vector<stream_fault> faults;

    // host side of the stream
    std::vector<std::uint8_t *> slot_buffers;
    std::size_t slot_capacity = 0;
    std::deque<std::size_t> submitted;
    std::vector<std::size_t> slot_fill;
    std::vector<std::uint8_t> render;  // scratch of the simulator's frame

    sim_camera() = default;

    std::uint32_t reg32(std::uint64_t a) const { return get_u32(&regs[a]); }
    void set_reg32(std::uint64_t a, std::uint32_t v) { put_u32(&regs[a], v); }
    static std::uint64_t sirm(std::uint64_t off) { return sim_map::sirm + off; }

    int bits() const { return pfnc_bits(reg32(sim_map::pixel_format)); }
    std::size_t image_bytes() const {
        return std::size_t(reg32(sim_map::width)) * (bits() > 8 ? 2 : 1) * reg32(sim_map::height);
    }
    std::size_t payload_bytes() const { return image_bytes() + (encoder_chunk ? 8 + 8 + 8 : 0); }
    void refresh_sirm() {
        put_u64(&regs[sirm(sirm::required_payload)], payload_bytes());
        set_reg32(sirm(sirm::info), alignment_log2 << 24);
    }

    void build() {
        // ABRM
        put_u32(&regs[abrm::gencp_version], 0x00010000u);  // GenCP 1.0
        auto str = [&](std::uint64_t a, const std::string &s) {
            std::memset(&regs[a], 0, abrm::string_length);
            std::memcpy(&regs[a], s.data(), std::min(s.size(), abrm::string_length - 1));
        };
        str(abrm::manufacturer, vendor);
        str(abrm::model, model);
        str(abrm::family, "Sim");
        str(abrm::device_version, "1.0.0");
        str(abrm::manufacturer_info, "libflatline simulated camera");
        str(abrm::serial, serial);
        str(abrm::user_name, "");
        put_u32(&regs[abrm::response_time], response_ms);
        put_u64(&regs[abrm::manifest_address], sim_map::manifest);
        put_u64(&regs[abrm::sbrm_address], sim_map::sbrm);
        // SBRM
        put_u32(&regs[sim_map::sbrm + sbrm::u3v_version], 0x00010000u);
        put_u32(&regs[sim_map::sbrm + sbrm::max_command], max_cmd);
        put_u32(&regs[sim_map::sbrm + sbrm::max_ack], max_ack);
        put_u32(&regs[sim_map::sbrm + sbrm::stream_channels], 1);
        put_u64(&regs[sim_map::sbrm + sbrm::sirm_address], sim_map::sirm);
        put_u32(&regs[sim_map::sbrm + sbrm::sirm_length], std::uint32_t(sirm::size));
        put_u32(&regs[sim_map::sbrm + sbrm::current_speed], speed_mbps >= 5000 ? 4 : 3);
        // SIRM
        set_reg32(sirm(sirm::required_leader), sim_map::leader_size);
        set_reg32(sirm(sirm::required_trailer), sim_map::trailer_size);
        refresh_sirm();
        // XML and manifest
        xml_text = make_xml(vendor, model);
        if (xml_zipped)
            xml_file = make_zip("SimCamera.xml", xml_text);
        else
            xml_file.assign(xml_text.begin(), xml_text.end());
        std::uint8_t *m = &regs[sim_map::manifest];
        std::memset(m, 0, 8 + 64);
        put_u64(m, 1);
        put_u32(m + 8, 0x01000000u);  // file version 1.0.0
        put_u32(m + 12, (xml_zipped ? 1u : 0u) << 10);
        put_u64(m + 16, sim_map::xml);
        put_u64(m + 24, xml_file.size());
    }

    // Which register ranges exist: [start, end) and whether the host may
    // write them.
    int range_of(std::uint64_t a, std::size_t n, bool &writable) const {
        struct range {
            std::uint64_t start, size;
            bool writable;
        };
        const range ranges[] = {
            {0, abrm::size, false},
            {abrm::user_name, abrm::string_length, true},
            {sim_map::sbrm, sbrm::size, false},
            {sim_map::sirm + sirm::control, 4, true},
            {sim_map::sirm, sirm::size, false},
            {sim_map::sirm + sirm::max_leader, sirm::size - sirm::max_leader, true},
            {sim_map::manifest, 8 + 64, false},
            {sim_map::features, sim_map::features_size, true},
        };
        for (const range &r : ranges)
            if (a >= r.start && a + n <= r.start + r.size) {
                writable = r.writable;
                return 1;
            }
        if (a >= sim_map::xml && a + n <= sim_map::xml + xml_file.size()) {
            writable = false;
            return 2;
        }
        return 0;
    }

    std::uint16_t read_mem(std::uint64_t a, std::size_t n, std::uint8_t *out) {
        bool w = false;
        int r = range_of(a, n, w);
        if (r == 0)
            return gencp_invalid_address;
        if (r == 2) {
            std::memcpy(out, &xml_file[a - sim_map::xml], n);
            return gencp_ok;
        }
        if (a <= sirm(sirm::required_payload) && a + n > sirm(sirm::required_payload))
            refresh_sirm();
        std::memcpy(out, &regs[a], n);
        return gencp_ok;
    }

    std::uint16_t write_mem(std::uint64_t a, const std::uint8_t *in, std::size_t n) {
        bool writable = false;
        // the more specific writable ranges first
        int r = range_of(a, n, writable);
        if (a >= sim_map::sirm + sirm::max_leader && a + n <= sim_map::sirm + sirm::size)
            writable = true, r = 1;
        if (a == sim_map::sirm + sirm::control && n == 4)
            writable = true, r = 1;
        if (a >= abrm::user_name && a + n <= abrm::user_name + abrm::string_length)
            writable = true, r = 1;
        if (r == 0)
            return gencp_invalid_address;
        if (!writable)
            return gencp_write_protect;
        const bool si_on = reg32(sirm(sirm::control)) & sirm::control_enable;
        if (a >= sirm(sirm::max_leader) && a < sirm(sirm::size) && si_on)
            return gencp_access_denied;  // stream set-up while streaming
        if (a >= sim_map::features && a < sim_map::features + sim_map::features_size) {
            if (n != 4 || (a - sim_map::features) % 4)
                return gencp_bad_alignment;
            const std::uint32_t v = get_u32(in);
            if (a == sim_map::width || a == sim_map::height || a == sim_map::pixel_format ||
                a == sim_map::offset_y) {
                if (acquiring)
                    return gencp_access_denied;
                std::uint32_t width = reg32(sim_map::width), height = reg32(sim_map::height),
                              offset = reg32(sim_map::offset_y);
                if (a == sim_map::width)
                    width = v;
                if (a == sim_map::height)
                    height = v;
                if (a == sim_map::offset_y)
                    offset = v;
                if (a == sim_map::pixel_format && pfnc_bits(v) == 0)
                    return gencp_invalid_parameter;
                if (frames && (a == sim_map::width || a == sim_map::height) && v != reg32(a))
                    return gencp_invalid_parameter;  // the simulator's size is fixed
                if (width < 16 || width > sensor_width || width % 4 || height < 1 ||
                    std::uint64_t(offset) + height > sensor_height)
                    return gencp_invalid_parameter;
            }
            if (a == sim_map::acquisition_start && v == 1)
                acquiring = true;
            if (a == sim_map::acquisition_stop && v == 1)
                acquiring = false;
            if (a == sim_map::acquisition_start || a == sim_map::acquisition_stop)
                return gencp_ok;
        }
        std::memcpy(&regs[a], in, n);
        if (a == sirm(sirm::control) && !(reg32(a) & sirm::control_enable))
            fifo.clear();  // disabling the stream interface flushes its FIFO
        return gencp_ok;
    }

    // --- control channel ------------------------------------------------------
    // The faults of `kind` that hit command `index`, or nullptr.
    const control_fault *control_fault_at(flt_u3v_fault kind, std::uint64_t index) const {
        for (const control_fault &f : control_faults)
            if (f.kind == kind && index >= f.first && index <= f.last)
                return &f;
        return nullptr;
    }

    // Schedules a control fault on the `count` commands after the next `at`
    // ones; faults of one kind add up (a new one starts after the last one
    // of its kind still pending).
    void schedule_control(flt_u3v_fault kind, std::uint64_t at, std::uint32_t count) {
        const bool single = kind == FLT_U3V_FAULT_PENDING_ACK || kind == FLT_U3V_FAULT_LATE_ACK ||
                            kind == FLT_U3V_FAULT_CONTROL_UNPLUG;
        const std::uint64_t n = single ? 1 : count;
        if (n == 0)
            return;
        std::uint64_t first = commands + at;
        if (!single)
            for (const control_fault &f : control_faults)
                if (f.kind == kind && f.last >= first)
                    first = f.last + 1;
        control_faults.push_back({kind, first, first + n - 1, count});
    }

    // Queues an acknowledge (a late one waits for the next command's).
    void answer(std::vector<std::uint8_t> ack, bool late) {
        if (!held_ack.empty()) {
            acks.push_back(std::move(held_ack));
            held_ack.clear();
        }
        if (late)
            held_ack = std::move(ack);
        else
            acks.push_back(std::move(ack));
    }

    void command(const std::uint8_t *p, std::size_t n) {
        const std::uint64_t index = commands++;
        // Faults that hit no later command are done with.
        control_faults.erase(std::remove_if(control_faults.begin(), control_faults.end(),
                                            [&](const control_fault &f) { return f.last < index; }),
                             control_faults.end());
        auto ack_of = [&](std::uint16_t status, std::uint16_t id, std::uint16_t request,
                          const std::uint8_t *body, std::size_t body_n) {
            std::vector<std::uint8_t> a(k_gencp_header + body_n);
            put_u32(a.data(), k_prefix_control);
            put_u16(&a[4], status);
            put_u16(&a[6], id);
            put_u16(&a[8], std::uint16_t(body_n));
            put_u16(&a[10], request);
            if (body_n)
                std::memcpy(&a[12], body, body_n);
            return a;
        };
        if (control_fault_at(FLT_U3V_FAULT_CONTROL_UNPLUG, index)) {
            unplugged = true;  // the command never arrives
            return;
        }
        if (control_fault_at(FLT_U3V_FAULT_CONTROL_TIMEOUT, index))
            return;  // lost on the way: neither executed nor answered
        const bool lost_ack = control_fault_at(FLT_U3V_FAULT_LOST_ACK, index) != nullptr;
        const bool late = control_fault_at(FLT_U3V_FAULT_LATE_ACK, index) != nullptr;
        // The answer of this command (after any pending acks), unless lost.
        auto reply = [&](std::vector<std::uint8_t> ack) {
            if (!lost_ack)
                answer(std::move(ack), late);
        };
        if (n < k_gencp_header || get_u32(p) != k_prefix_control ||
            get_u16(p + 8) != n - k_gencp_header) {
            reply(ack_of(gencp_invalid_header, 0x0801, n >= 12 ? get_u16(p + 10) : 0, nullptr, 0));
            return;
        }
        const std::uint16_t cmd = get_u16(p + 6), request = get_u16(p + 10);
        if (const control_fault *f = control_fault_at(FLT_U3V_FAULT_PENDING_ACK, index)) {
            for (std::uint32_t i = 0; i < f->count; ++i) {
                std::uint8_t body[4] = {0, 0, 0, 0};
                put_u16(body + 2, 50);  // "wait 50 ms more"
                acks.push_back(ack_of(gencp_ok, k_ack_pending, request, body, 4));
            }
        }
        if (control_fault_at(FLT_U3V_FAULT_BUSY, index)) {
            reply(ack_of(gencp_busy, std::uint16_t(cmd + 1), request, nullptr, 0));
            return;  // not executed
        }
        if (n > max_cmd) {
            reply(ack_of(gencp_invalid_parameter, std::uint16_t(cmd + 1), request, nullptr, 0));
            return;
        }
        if (cmd == k_cmd_readmem && n == k_gencp_header + k_readmem_body) {
            const std::uint64_t a = get_u64(p + 12);
            const std::uint16_t count = get_u16(p + 22);
            if (k_gencp_header + count > max_ack) {
                reply(ack_of(gencp_invalid_parameter, k_ack_readmem, request, nullptr, 0));
                return;
            }
            std::vector<std::uint8_t> data(count);
            const std::uint16_t st = read_mem(a, count, data.data());
            reply(ack_of(st, k_ack_readmem, request, st == gencp_ok ? data.data() : nullptr,
                         st == gencp_ok ? count : 0));
        } else if (cmd == k_cmd_writemem && n >= k_writemem_overhead) {
            const std::uint64_t a = get_u64(p + 12);
            const std::size_t count = n - k_writemem_overhead;
            const std::uint16_t st = write_mem(a, p + 20, count);
            std::uint8_t body[4] = {0, 0, 0, 0};
            put_u16(body + 2, std::uint16_t(st == gencp_ok ? count : 0));
            reply(ack_of(st, k_ack_writemem, request, body, 4));
        } else {
            reply(ack_of(gencp_not_implemented, std::uint16_t(cmd + 1), request, nullptr, 0));
        }
    }

    // --- stream -------------------------------------------------------------------
    bool streaming() const {
        return acquiring && (reg32(sirm(sirm::control)) & sirm::control_enable);
    }

    const stream_fault *fault_at(flt_u3v_fault kind, std::uint64_t block) const {
        for (const stream_fault &f : faults)
            if (f.kind == kind && f.at == block)
                return &f;
        return nullptr;
    }

    void push(std::vector<std::uint8_t> bytes) {
        device_transfer t;
        t.bytes = std::move(bytes);
        fifo.push_back(std::move(t));
    }

    // Queues the next frame's transfers, as the SIRM registers say.
    void emit_frame() {
        if (const stream_fault *f = fault_at(FLT_U3V_FAULT_SKIP_BLOCK_IDS, next_block))
            next_block += f->count;
        const std::uint64_t block = next_block++;
        const std::size_t image = image_bytes();
        const std::size_t payload = payload_bytes();
        const std::uint32_t width = reg32(sim_map::width), height = reg32(sim_map::height);
        std::vector<std::uint8_t> body(payload);
        double encoder_mm = double(block) * 3.0;
        if (frames) {
            if (flt_sim_next_frame(frames, body.data(), image,
                                   std::size_t(width) * (bits() > 8 ? 2 : 1), &encoder_mm, 0,
                                   nullptr, nullptr, 0) != FLT_OK)
                throw std::runtime_error(std::string("simulated camera: ") +
                                         flt_last_error_message());
        } else {
            for (std::size_t i = 0; i < image; ++i)
                body[i] = std::uint8_t(block * 131u + i * 7u + (i >> 9));
        }
        if (encoder_chunk) {
            std::uint8_t *c = &body[image];
            put_u32(c, k_image_chunk_id);
            put_u32(c + 4, std::uint32_t(image));
            const long long counts = std::llround(encoder_mm * 1000.0 / um_per_count);
            put_u64(c + 8, std::uint64_t(counts));
            put_u32(c + 16, encoder_chunk_id);
            put_u32(c + 20, 8);
        }
        if (fault_at(FLT_U3V_FAULT_GARBAGE, block)) {
            std::vector<std::uint8_t> junk(100);
            for (std::size_t i = 0; i < junk.size(); ++i)
                junk[i] = std::uint8_t(i * 37 + 11);
            push(std::move(junk));
        }
        std::vector<std::uint8_t> leader(sim_map::leader_size, 0);
        put_u32(leader.data(), k_magic_leader);
        put_u16(&leader[6], std::uint16_t(sim_map::leader_size));
        put_u64(&leader[8], block);
        put_u16(&leader[18], encoder_chunk ? k_payload_image_chunk : k_payload_image);
        put_u64(&leader[20], block * 1000000ull);  // 1 ms per frame, ns
        put_u32(&leader[28], reg32(sim_map::pixel_format));
        put_u32(&leader[32], width);
        put_u32(&leader[36], height);
        put_u32(&leader[44], reg32(sim_map::offset_y));
        push(std::move(leader));
        ++frames_sent;
        if (fault_at(FLT_U3V_FAULT_UNPLUG, block)) {
            device_transfer t;
            t.kind = device_transfer::unplug;
            fifo.push_back(std::move(t));
            return;
        }
        if (fault_at(FLT_U3V_FAULT_STREAM_TIMEOUT, block)) {
            device_transfer t;
            t.kind = device_transfer::stall;
            fifo.push_back(std::move(t));
            return;  // the camera abandons the frame
        }
        // Payload transfers as configured by the host in SIRM.
        const std::size_t size = reg32(sirm(sirm::transfer_size));
        const std::size_t count = reg32(sirm(sirm::transfer_count));
        const std::size_t final1 = reg32(sirm(sirm::final1_size));
        std::vector<std::vector<std::uint8_t>> parts;
        std::size_t sent = 0;
        for (std::size_t i = 0; i < count && sent < payload; ++i) {
            const std::size_t n = std::min(size, payload - sent);
            const auto from = body.begin() + std::ptrdiff_t(sent);
            parts.emplace_back(from, from + std::ptrdiff_t(n));
            sent += n;
        }
        if (final1 > 0 && sent < payload) {
            // the remainder, padded to the aligned final transfer size
            std::vector<std::uint8_t> last(body.begin() + std::ptrdiff_t(sent), body.end());
            last.resize(std::max(final1, last.size()), 0);
            parts.push_back(std::move(last));
            sent = payload;
        }
        if (fault_at(FLT_U3V_FAULT_OVERFLOW, block) && !parts.empty())
            parts.back().resize(parts.back().size() + sim_map::packet, 0xEE);
        if (fault_at(FLT_U3V_FAULT_SHORT_FRAME, block) && !parts.empty())
            parts.pop_back();
        const bool mid = fault_at(FLT_U3V_FAULT_LEADER_MID_FRAME, block) != nullptr;
        if (mid)
            parts.resize(parts.size() / 2);
        for (auto &p : parts)
            push(std::move(p));
        if (mid)
            return;  // no trailer: the next leader arrives mid-frame
        std::vector<std::uint8_t> trailer(sim_map::trailer_size, 0);
        put_u32(trailer.data(), k_magic_trailer);
        put_u16(&trailer[6], std::uint16_t(sim_map::trailer_size));
        put_u64(&trailer[8], block);
        put_u16(&trailer[16],
                fault_at(FLT_U3V_FAULT_TRAILER_STATUS, block) ? u3v_data_overrun : gencp_ok);
        put_u64(&trailer[20], payload);
        put_u32(&trailer[28], height);
        push(std::move(trailer));
    }

    // Fills host slot `slot` from the FIFO with USB bulk semantics. Returns
    // true when the transfer completed (status in `st`), false when it must
    // keep waiting.
    bool fill(std::size_t slot, usb_status &st) {
        std::uint8_t *buffer = slot_buffers[slot];
        std::size_t &filled = slot_fill[slot];
        for (;;) {
            if (fifo.empty()) {
                if (!streaming())
                    return false;
                emit_frame();
                continue;
            }
            device_transfer &t = fifo.front();
            if (t.kind == device_transfer::unplug) {
                unplugged = true;
                st = usb_status::no_device;
                return true;
            }
            if (t.kind == device_transfer::stall) {
                fifo.pop_front();
                return false;  // nothing comes: the host's wait times out
            }
            const std::size_t left = t.bytes.size() - t.offset;
            const std::size_t space = slot_capacity - filled;
            const std::size_t packet = std::min(left, sim_map::packet);
            if (packet > space) {
                // the packet does not fit: libusb reports an overflow
                std::memcpy(buffer + filled, t.bytes.data() + t.offset, space);
                filled += space;
                t.offset += packet;
                if (t.offset >= t.bytes.size())
                    fifo.pop_front();
                st = usb_status::overflow;
                return true;
            }
            // whole packets at once, as many as fit
            std::size_t n = packet;
            if (packet == sim_map::packet) {
                const std::size_t full = std::min(left / sim_map::packet, space / sim_map::packet);
                n = std::max<std::size_t>(1, full) * sim_map::packet;
            }
            std::memcpy(buffer + filled, t.bytes.data() + t.offset, n);
            filled += n;
            t.offset += n;
            const bool short_packet = (n % sim_map::packet) != 0 || t.bytes.empty();
            if (t.offset >= t.bytes.size())
                fifo.pop_front();
            if (short_packet || filled == slot_capacity) {
                st = usb_status::ok;
                return true;
            }
        }
    }

    void left_streaming() {
        // What a killed host leaves behind: stream set up and enabled,
        // acquisition running, half a frame in the FIFO.
        set_reg32(sirm(sirm::transfer_size), 4096);
        set_reg32(sirm(sirm::transfer_count), std::uint32_t(payload_bytes() / 4096));
        set_reg32(sirm(sirm::final1_size), 0);
        set_reg32(sirm(sirm::control), sirm::control_enable);
        acquiring = true;
        std::vector<std::uint8_t> half(3000, 0x5A);
        push(std::move(half));
    }
};

// The host's handle on one camera.
class sim_device final : public usb_device {
  public:
    explicit sim_device(sim_camera &cam) : cam_(cam) { cam_.open = true; }
    ~sim_device() override {
        async_release();
        cam_.open = false;
    }
    usb_status claim_interface(int number) override {
        if (cam_.unplugged)
            return usb_status::no_device;
        return number >= 0 && number <= 2 ? usb_status::ok : usb_status::not_found;
    }
    usb_status release_interface(int /*number*/) override {
        return cam_.unplugged ? usb_status::no_device : usb_status::ok;
    }
    usb_status clear_halt(std::uint8_t /*endpoint*/) override {
        return cam_.unplugged ? usb_status::no_device : usb_status::ok;
    }
    usb_status string_descriptor(std::uint8_t index, std::string &out) override {
        if (cam_.unplugged)
            return usb_status::no_device;
        switch (index) {
            case 2:
                out = cam_.vendor;
                break;
            case 3:
                out = cam_.model;
                break;
            case 4:
                out = "Sim";
                break;
            case 7:
                out = cam_.serial;
                break;
            default:
                out.clear();
        }
        return usb_status::ok;
    }
    usb_status bulk_write(std::uint8_t endpoint, const std::uint8_t *data, std::size_t length,
                          std::size_t &sent, unsigned /*timeout_ms*/) override {
        sent = 0;
        if (cam_.unplugged)
            return usb_status::no_device;
        if (endpoint != k_ep_control_out)
            return usb_status::io;
        try {
            cam_.command(data, length);
        } catch (...) {  // out of memory: nothing may cross into libflatline
            return usb_status::no_memory;
        }
        sent = length;
        return usb_status::ok;
    }
    usb_status bulk_read(std::uint8_t endpoint, std::uint8_t *data, std::size_t capacity,
                         std::size_t &received, unsigned timeout_ms) override {
        received = 0;
        if (cam_.unplugged)
            return usb_status::no_device;
        if (endpoint != k_ep_control_in)
            return usb_status::io;
        cam_.last_read_timeout = timeout_ms;
        if (cam_.acks.empty())
            return usb_status::timeout;
        std::vector<std::uint8_t> ack = std::move(cam_.acks.front());
        cam_.acks.pop_front();
        const std::size_t n = std::min(capacity, ack.size());
        std::memcpy(data, ack.data(), n);
        received = n;
        return ack.size() > capacity ? usb_status::overflow : usb_status::ok;
    }
    usb_status async_prepare(std::uint8_t endpoint, std::size_t slots, std::uint8_t *const *buffers,
                             std::size_t capacity) override {
        if (cam_.unplugged)
            return usb_status::no_device;
        if (endpoint != k_ep_stream)
            return usb_status::io;
        try {
            cam_.slot_buffers.assign(buffers, buffers + slots);
            cam_.slot_fill.assign(slots, 0);
        } catch (...) {
            return usb_status::no_memory;
        }
        cam_.slot_capacity = capacity;
        cam_.submitted.clear();
        return usb_status::ok;
    }
    usb_status async_submit(std::size_t slot) override {
        if (cam_.unplugged)
            return usb_status::no_device;
        const std::uint64_t index = cam_.submits++;
        for (const auto &r : cam_.refused_submits)
            if (index >= r.first && index <= r.second)
                return usb_status::no_memory;
        if (slot >= cam_.slot_fill.size())
            return usb_status::io;
        try {
            cam_.submitted.push_back(slot);
        } catch (...) {
            return usb_status::no_memory;
        }
        cam_.slot_fill[slot] = 0;
        return usb_status::ok;
    }
    usb_status async_reap(unsigned /*timeout_ms*/, usb_completion &out) override {
        if (cam_.submitted.empty())
            return usb_status::timeout;
        const std::size_t slot = cam_.submitted.front();
        usb_status st = usb_status::ok;
        if (cam_.unplugged) {
            st = usb_status::no_device;
        } else {
            try {
                if (!cam_.fill(slot, st))
                    return usb_status::timeout;
            } catch (...) {
                // The simulator could not render the frame (or memory ran
                // out): an I/O error, as a broken device would give.
                return usb_status::io;
            }
        }
        cam_.submitted.pop_front();
        out.slot = slot;
        out.status = st;
        out.length = cam_.slot_fill[slot];
        return usb_status::ok;
    }
    void async_release() override {
        cam_.submitted.clear();
        cam_.slot_buffers.clear();
        cam_.slot_fill.clear();
    }

  private:
    sim_camera &cam_;
};

sim_bus::sim_bus() = default;
sim_bus::~sim_bus() = default;

std::size_t sim_bus::add_camera(const std::string &vendor, const std::string &model,
                                const std::string &serial, std::uint32_t width,
                                std::uint32_t height, int bits) {
    auto cam = std::make_unique<sim_camera>();
    cam->vendor = vendor;
    cam->model = model;
    cam->serial = serial;
    cam->sensor_width = width;
    cam->sensor_height = height;
    cam->set_reg32(sim_map::width, width);
    cam->set_reg32(sim_map::height, height);
    cam->set_reg32(sim_map::pixel_format, pfnc_of_bits(bits));
    cam->set_reg32(sim_map::exposure_raw, 100);
    cam->build();
    cameras_.push_back(std::move(cam));
    return cameras_.size() - 1;
}

usb_status sim_bus::list(std::vector<usb_device_desc> &out) {
    try {
        describe(out);
    } catch (...) {  // out of memory: nothing may cross into libflatline
        return usb_status::no_memory;
    }
    return usb_status::ok;
}

void sim_bus::describe(std::vector<usb_device_desc> &out) const {
    out.clear();
    // A device that is not a camera (a keyboard), which discovery must skip.
    usb_device_desc keyboard;
    keyboard.vendor_id = 0x046D;
    keyboard.product_id = 0xC31C;
    keyboard.bus = 1;
    keyboard.address = 1;
    keyboard.speed_mbps = 12;
    usb_interface_desc hid;
    hid.cls = 3;
    hid.subclass = 1;
    hid.protocol = 1;
    hid.endpoints.push_back({0x81, 3, 8});
    keyboard.interfaces.push_back(hid);
    out.push_back(keyboard);
    for (std::size_t i = 0; i < cameras_.size(); ++i) {
        const sim_camera &cam = *cameras_[i];
        if (cam.unplugged)
            continue;
        usb_device_desc d;
        d.vendor_id = k_sim_vendor_id;
        d.product_id = std::uint16_t(0x0100 + i);
        d.cls = k_class_misc;
        d.subclass = k_subclass_iad;
        d.protocol = k_protocol_iad;
        d.bus = 2;
        d.address = std::uint8_t(10 + i);
        d.speed_mbps = cam.speed_mbps;
        usb_interface_desc control;
        control.number = 0;
        control.cls = k_class_misc;
        control.subclass = k_subclass_u3v;
        control.protocol = k_protocol_control;
        control.endpoints = {{k_ep_control_in, 2, 1024}, {k_ep_control_out, 2, 1024}};
        control.extra.assign(20, 0);
        std::uint8_t *e = control.extra.data();
        e[0] = 20;
        e[1] = k_desc_device_info;
        e[2] = k_desc_subtype_info;
        put_u32(e + 3, 0x00010000u);
        put_u32(e + 7, 0x00010000u);
        for (int s = 0; s < 8; ++s)
            e[11 + s] = std::uint8_t(1 + s);  // GUID=1 .. user=8
        e[19] = 0x0F;
        usb_interface_desc event;
        event.number = 1;
        event.cls = k_class_misc;
        event.subclass = k_subclass_u3v;
        event.protocol = k_protocol_event;
        event.endpoints = {{k_ep_event, 2, 1024}};
        usb_interface_desc stream;
        stream.number = 2;
        stream.cls = k_class_misc;
        stream.subclass = k_subclass_u3v;
        stream.protocol = k_protocol_stream;
        stream.endpoints = {{k_ep_stream, 2, 1024}};
        d.interfaces = {control, event, stream};
        out.push_back(d);
    }
}

usb_status sim_bus::open(const usb_device_desc &desc, std::unique_ptr<usb_device> &out) {
    if (desc.vendor_id != k_sim_vendor_id)
        return usb_status::access;
    const std::size_t i = desc.product_id - 0x0100u;
    if (i >= cameras_.size() || cameras_[i]->unplugged)
        return usb_status::no_device;
    if (cameras_[i]->open)
        return usb_status::busy;
    try {
        out = std::make_unique<sim_device>(*cameras_[i]);
    } catch (...) {
        return usb_status::no_memory;
    }
    return usb_status::ok;
}

void sim_set(sim_camera &cam, flt_u3v_sim_param param, std::uint64_t value) {
    auto need_closed = [&] {
        if (cam.open)
            throw error(FLT_ERR_STATE, "this parameter cannot change while the camera is open");
    };
    auto in_range = [&](std::uint64_t lo, std::uint64_t hi) {
        if (value < lo || value > hi) {
            char text[160];
            std::snprintf(text, sizeof text, "value %llu is outside [%llu, %llu]",
                          (unsigned long long)value, (unsigned long long)lo,
                          (unsigned long long)hi);
            throw error(FLT_ERR_INVALID_ARGUMENT, text);
        }
    };
    switch (param) {
        case FLT_U3V_SIM_RESPONSE_TIME_MS:
            need_closed();
            in_range(1, 60000);
            cam.response_ms = std::uint32_t(value);
            break;
        case FLT_U3V_SIM_MAX_COMMAND_BYTES:
            need_closed();
            in_range(64, 65536);
            cam.max_cmd = std::uint32_t(value);
            break;
        case FLT_U3V_SIM_MAX_ACK_BYTES:
            need_closed();
            in_range(76, 65536);
            cam.max_ack = std::uint32_t(value);
            break;
        case FLT_U3V_SIM_ALIGNMENT_LOG2:
            need_closed();
            in_range(0, 12);
            cam.alignment_log2 = std::uint32_t(value);
            break;
        case FLT_U3V_SIM_XML_ZIPPED:
            need_closed();
            in_range(0, 1);
            cam.xml_zipped = value != 0;
            break;
        case FLT_U3V_SIM_ENCODER_CHUNK:
            need_closed();
            in_range(0, 1);
            cam.encoder_chunk = value != 0;
            break;
        case FLT_U3V_SIM_ENCODER_CHUNK_ID:
            need_closed();
            in_range(0, 0xFFFFFFFFu);
            cam.encoder_chunk_id = std::uint32_t(value);
            break;
        case FLT_U3V_SIM_ENCODER_MM_PER_COUNT_UM:
            need_closed();
            in_range(1, 1000000);
            cam.um_per_count = std::uint32_t(value);
            break;
        case FLT_U3V_SIM_SPEED_MBPS:
            need_closed();
            in_range(480, 20000);
            cam.speed_mbps = std::uint32_t(value);
            break;
        case FLT_U3V_SIM_LEFT_STREAMING:
            need_closed();
            in_range(1, 1);
            cam.left_streaming();
            return;
        default:
            throw error(FLT_ERR_INVALID_ARGUMENT, "the parameter is unknown or read-only");
    }
    cam.build();
}

std::uint64_t sim_get(const sim_camera &cam, flt_u3v_sim_param param) {
    switch (param) {
        case FLT_U3V_SIM_RESPONSE_TIME_MS:
            return cam.response_ms;
        case FLT_U3V_SIM_MAX_COMMAND_BYTES:
            return cam.max_cmd;
        case FLT_U3V_SIM_MAX_ACK_BYTES:
            return cam.max_ack;
        case FLT_U3V_SIM_ALIGNMENT_LOG2:
            return cam.alignment_log2;
        case FLT_U3V_SIM_XML_ZIPPED:
            return cam.xml_zipped;
        case FLT_U3V_SIM_ENCODER_CHUNK:
            return cam.encoder_chunk;
        case FLT_U3V_SIM_ENCODER_CHUNK_ID:
            return cam.encoder_chunk_id;
        case FLT_U3V_SIM_ENCODER_MM_PER_COUNT_UM:
            return cam.um_per_count;
        case FLT_U3V_SIM_SPEED_MBPS:
            return cam.speed_mbps;
        case FLT_U3V_SIM_LEFT_STREAMING:
        case FLT_U3V_SIM_SI_CONTROL:
            return cam.reg32(sim_camera::sirm(sirm::control));
        case FLT_U3V_SIM_ACQUIRING:
            return cam.acquiring;
        case FLT_U3V_SIM_COMMANDS:
            return cam.commands;
        case FLT_U3V_SIM_LAST_READ_TIMEOUT_MS:
            return cam.last_read_timeout;
        case FLT_U3V_SIM_FRAMES_SENT:
            return cam.frames_sent;
        case FLT_U3V_SIM_OPEN:
            return cam.open;
        case FLT_U3V_SIM_FAULTS_PENDING: {
            std::uint64_t pending = 0;
            for (const auto &f : cam.control_faults)
                pending += f.last >= cam.commands;
            for (const auto &r : cam.refused_submits)
                pending += r.second >= cam.submits;
            return pending;
        }
        case FLT_U3V_SIM_UNPLUGGED:
            return cam.unplugged;
        default:
            break;
    }
    throw error(FLT_ERR_INVALID_ARGUMENT, "the parameter is unknown");
}

void sim_inject(sim_camera &cam, flt_u3v_fault fault, std::uint64_t at, std::uint32_t count) {
    switch (fault) {
        case FLT_U3V_FAULT_SHORT_FRAME:
        case FLT_U3V_FAULT_LEADER_MID_FRAME:
        case FLT_U3V_FAULT_OVERFLOW:
        case FLT_U3V_FAULT_STREAM_TIMEOUT:
        case FLT_U3V_FAULT_UNPLUG:
        case FLT_U3V_FAULT_GARBAGE:
        case FLT_U3V_FAULT_TRAILER_STATUS:
            cam.faults.push_back({fault, at, count});
            return;
        case FLT_U3V_FAULT_SKIP_BLOCK_IDS:
            if (count == 0)
                throw error(FLT_ERR_INVALID_ARGUMENT, "count is 0: nothing to skip");
            cam.faults.push_back({fault, at, count});
            return;
        case FLT_U3V_FAULT_SUBMIT_REFUSED: {
            if (count == 0)
                return;
            std::uint64_t first = cam.submits + at;
            for (const auto &r : cam.refused_submits)  // faults add up
                if (r.second >= first)
                    first = r.second + 1;
            cam.refused_submits.emplace_back(first, first + count - 1);
            return;
        }
        case FLT_U3V_FAULT_PENDING_ACK:
        case FLT_U3V_FAULT_CONTROL_TIMEOUT:
        case FLT_U3V_FAULT_LATE_ACK:
        case FLT_U3V_FAULT_LOST_ACK:
        case FLT_U3V_FAULT_BUSY:
        case FLT_U3V_FAULT_CONTROL_UNPLUG:
            cam.schedule_control(fault, at, count);
            return;
        default:
            break;
    }
    throw error(FLT_ERR_INVALID_ARGUMENT, "the fault is unknown");
}

bool sim_peek(const sim_camera &cam, std::uint64_t address, std::uint32_t &out) {
    if (address > cam.regs.size() || cam.regs.size() - address < 4)
        return false;  // no wrap
    out = cam.reg32(address);
    return true;
}

void sim_set_frames(sim_camera &cam, flt_sim *sim) {
    if (cam.open)
        throw error(FLT_ERR_STATE, "the camera is open");
    cam.frames = sim;
    if (!sim)
        return;
    std::uint32_t w = 0, h = 0;
    flt_pixel_format format = FLT_PIXEL_MONO8;
    if (flt_sim_frame_size(sim, &w, &h) != FLT_OK || flt_sim_pixel_format(sim, &format) != FLT_OK)
        throw error(FLT_ERR_INVALID_ARGUMENT, flt_last_error_message());
    cam.sensor_width = w;
    cam.sensor_height = h;
    cam.set_reg32(sim_map::width, w);
    cam.set_reg32(sim_map::height, h);
    cam.set_reg32(sim_map::offset_y, 0);
    cam.set_reg32(sim_map::pixel_format, pfnc_of_bits(int(format)));
    cam.build();
}

}  // namespace flt::testing
