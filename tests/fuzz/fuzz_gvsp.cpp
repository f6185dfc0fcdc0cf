// SPDX-License-Identifier: Apache-2.0
// libFuzzer harness: GVSP frame assembly (lib/sources/gige/assembly.cpp,
// internal: flt::gige::frame_assembler), the code every datagram on a GigE
// Vision stream socket reaches. A scripted camera sends frames whose
// packets the input drops, repeats, swaps, delays, forges (same header,
// other bytes) and surrounds with strays (any header, near or 30,000 block
// ids away); the input also moves the clock, answers resend requests, and
// restarts or jumps the camera's block ids. Checked on every delivery and
// at the end:
//   - a delivered frame has the stream's size and lies in its buffer, and
//     each of its packets holds bytes some packet with that header carried
//     (the camera's, or one the script forged): never stale bytes of an
//     earlier frame, never a shifted or unwritten part;
//   - frames leave in block order;
//   - once assembly is empty: FRAMES + DROPPED + LOST = the block ids from
//     the first frame finished to the last, PACKETS_MISSING =
//     PACKETS_RESENT + the packets given up with dropped frames;
//   - without stray leaders and block-id jumps, that span is at most the
//     frames the camera sent (LOST never counts frames that were not lost).
// A crash, a sanitizer report or a failed check aborts.
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "sources/camera/accounting.hpp"
#include "sources/camera/pixel_format.hpp"
#include "sources/gige/assembly.hpp"
#include "sources/gige/protocol.hpp"

using flt::gige::frame_assembler;

namespace {

struct input {
    const std::uint8_t *p;
    std::size_t n;
    bool empty() const { return n == 0; }
    std::uint8_t u8() { return n ? (--n, *p++) : 0; }
    std::uint16_t u16() { return std::uint16_t(u8() | (u8() << 8)); }
};

#define CHECK(cond) \
  do {              \
    if (!(cond))    \
      std::abort(); \
  } while (0)

using packet = std::vector<std::uint8_t>;

struct resend_log final : flt::gige::resend_sink {
    std::vector<std::pair<std::uint16_t, std::pair<std::uint32_t, std::uint32_t>>> asked;
    void request_resend(std::uint16_t block, std::uint32_t first, std::uint32_t last) override {
        CHECK(first <= last);
        if (asked.size() < 4096)
            asked.push_back({block, {first, last}});
    }
};

struct script {
    flt::sources::frame_accounting acc;
    resend_log resend;
    frame_assembler assembler{acc, resend};
    flt::sources::frame_geometry g;
    std::uint32_t data_bytes = 0, last_id = 0;
    frame_assembler::clock::time_point now{};
    unsigned block = 0;      // the camera's last block id
    std::uint32_t sent = 0;  // frames the camera sent
    bool leaders_injected = false, jumped = false;
    // Every packet sent, by (block id, packet id): the bytes each carried.
    std::map<std::pair<unsigned, std::uint32_t>, std::set<packet>> carried;
    // The block ids of the leaders that carried each timestamp (a frame
    // number, or a stray's).
    std::map<std::uint64_t, std::set<unsigned>> leader_blocks;
    std::map<std::pair<unsigned, std::uint32_t>, packet> camera_copy;  // for resends
    std::vector<std::pair<packet, std::uint32_t>> held;  // delayed packets, their frame
    bool very_late = false;  // a leader delayed past 4 windows: a restart to the client
    bool have_previous = false;
    std::uint64_t previous = 0;
    std::uint64_t delivered = 0;

    packet make(unsigned b, std::uint32_t id, std::uint8_t format, std::size_t body) const {
        packet p(8 + body, 0);
        flt::gige::put_be16(p.data() + 2, std::uint16_t(b));
        flt::gige::put_be32(p.data() + 4, id);
        p[4] = format;
        return p;
    }
    // The camera's packet `id` of frame number `frame` (block `b`).
    packet camera_packet(unsigned b, std::uint32_t frame, std::uint32_t id) const {
        using namespace flt::gige;
        if (id == 0) {
            packet p = make(b, 0, k_format_leader, 36);
            put_be16(p.data() + 8 + leader::payload_type, k_payload_image);
            put_be32(p.data() + 8 + leader::timestamp + 4, frame);
            put_be32(p.data() + 8 + leader::pixel_format, g.pfnc);
            put_be32(p.data() + 8 + leader::width, g.width);
            put_be32(p.data() + 8 + leader::height, g.height);
            return p;
        }
        if (id == last_id) {
            packet p = make(b, id, k_format_trailer, 8);
            put_be16(p.data() + 8 + 2, k_payload_image);
            return p;
        }
        const std::size_t offset = std::size_t(id - 1) * data_bytes;
        const std::size_t n =
            std::min<std::size_t>(data_bytes, std::size_t(g.image_bytes) - offset);
        packet p = make(b, id, k_format_payload, n);
        for (std::size_t i = 0; i < n; ++i)
            p[8 + i] = std::uint8_t(frame * 131 + (offset + i) * 7 + 1);
        return p;
    }

    void deliver(const packet &p) {
        if (p.size() >= 8) {
            const unsigned b = flt::gige::get_be16(p.data() + 2);
            const std::uint32_t id = flt::gige::get_be32(p.data() + 4) & 0xFFFFFFu;
            if (carried[{b, id}].size() < 64)
                carried[{b, id}].insert(p);
            if (id == 0 && p.size() >= 8 + 12) {
                const std::uint64_t t = (std::uint64_t(flt::gige::get_be32(p.data() + 12)) << 32) |
                                        flt::gige::get_be32(p.data() + 16);
                if (leader_blocks[t].size() < 64)
                    leader_blocks[t].insert(b);
            }
        }
        assembler.on_packet(p.data(), p.size(), now);
    }

    void check_frame(const flt::sources::raw_frame &f) {
        CHECK(f.pixels != nullptr);
        CHECK(f.width == g.width && f.height == g.height);
        CHECK(f.stride == g.row_bytes && f.format == flt_pixel_format(g.bits));
        CHECK(f.bytes >= std::size_t(f.stride) * f.height);
        if (have_previous)
            CHECK(f.block_id > previous);
        have_previous = true;
        previous = f.block_id;
        // The leader's timestamp (the camera's frame number) names the
        // frame, and the leaders that carried it its block id (the
        // delivered id is the camera's only until a restart). Each payload
        // packet must be bytes a packet of that header carried.
        const auto *pixels = static_cast<const std::uint8_t *>(f.pixels);
        auto blocks = leader_blocks.find(f.timestamp_ns);
        CHECK(blocks != leader_blocks.end());
        bool any = false;
        for (const unsigned b : blocks->second) {
            bool all = true;
            for (std::uint32_t id = 1; all && id < last_id; ++id) {
                const std::size_t offset = std::size_t(id - 1) * data_bytes;
                const std::size_t n =
                    std::min<std::size_t>(data_bytes, std::size_t(g.image_bytes) - offset);
                auto it = carried.find({b, id});
                bool found = false;
                if (it != carried.end())
                    for (const packet &p : it->second)
                        found = found || (p.size() == 8 + n &&
                                          std::memcmp(p.data() + 8, pixels + offset, n) == 0);
                all = found;
            }
            any = any || all;
        }
        CHECK(any);
        ++delivered;
    }

    void take_all() {
        flt::sources::raw_frame f;
        for (int i = 0; i < 64; ++i) {
            assembler.return_lent();
            if (!assembler.take(f))
                break;
            check_frame(f);
        }
    }

    void advance(unsigned ms) {
        now += std::chrono::milliseconds(ms);
        assembler.check_missing(now);
    }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
    input in{data, size};
    script s;
    // The stream: a small frame in small packets, so that frames have from
    // 1 to 130 packets.
    const std::uint8_t shape = in.u8();
    const std::uint32_t width = 1 + in.u8() % 32, height = 1 + in.u8() % 8;
    const std::uint32_t pfnc =
        (shape & 1) ? flt::sources::k_pfnc_mono16 : flt::sources::k_pfnc_mono8;
    try {
        s.g = flt::sources::check_geometry(width, height, pfnc, "the fuzzed camera");
    } catch (const flt::error &) {
        std::abort();  // within the bounds by construction
    }
    s.data_bytes = 4 + in.u8() % 61;
    flt::gige::assembly_config config;
    config.resend = (shape & 2) != 0;
    config.resend_attempts = (shape >> 2) & 3;
    config.resend_timeout_ms = 1 + in.u8() % 40;
    config.assembly_frames = 2 + (shape >> 4) % 6;
    s.assembler.prepare(s.g, s.data_bytes, config.assembly_frames + 1, config);
    s.last_id = s.assembler.last_packet_id();
    s.block = 1 + in.u16() % 65535;

    for (int op = 0; op < 3000 && !in.empty(); ++op) {
        const std::uint8_t what = in.u8();
        switch (what % 11) {
            case 0:
            case 1:
            case 2:
            case 3: {  // the camera's next frame, each packet's fate from the input
                s.block = s.block % 65535 + 1;
                const std::uint32_t frame = s.sent++;
                std::vector<packet> out;
                for (std::uint32_t id = 0; id <= s.last_id; ++id) {
                    packet p = s.camera_packet(s.block, frame, id);
                    s.camera_copy[{s.block, id}] = p;
                    const std::uint8_t fate = (what & 0x80) ? in.u8() : 0;
                    switch (fate % 8) {
                        case 1:
                            break;  // lost
                        case 2:
                            out.push_back(p);
                            out.push_back(p);  // twice
                            break;
                        case 3:
                            if (s.held.size() < 256)
                                s.held.push_back({p, frame});  // delayed
                            break;
                        case 4:
                            if (!out.empty()) {  // swapped with the one before
                                out.push_back(out.back());
                                out[out.size() - 2] = p;
                            } else {
                                out.push_back(p);
                            }
                            break;
                        case 5: {  // a forged copy first (same header, other bytes)
                            packet f = p;
                            if (id != 0)  // a leader forged the same is no forgery
                                for (std::size_t i = 8; i < f.size(); ++i)
                                    f[i] ^= 0x5A;
                            out.push_back(f);
                            out.push_back(p);
                            break;
                        }
                        default:
                            out.push_back(p);
                    }
                }
                for (const packet &p : out)
                    s.deliver(p);
                break;
            }
            case 4:  // time passes
                s.advance(in.u8());
                break;
            case 5: {  // a stray packet: near or far, any header
                const std::uint8_t kind = in.u8();
                unsigned b = kind & 1 ? (s.block + 30000 - 1) % 65535 + 1
                                      : (s.block + (in.u8() % 16) + 65535 - 8 - 1) % 65535 + 1;
                if (b == 0)
                    b = 1;
                const std::uint32_t id = kind & 2 ? in.u8() % (s.last_id + 2) : 1;
                packet p = s.make(b, id, std::uint8_t(in.u8() % 4), in.u8() % 70);
                for (std::size_t i = 8; i < p.size(); ++i)
                    p[i] = in.u8();
                if (kind & 4)
                    flt::gige::put_be16(p.data(), in.u16());  // a status
                if (id == 0 && (p[4] & 0x7F) == flt::gige::k_format_leader)
                    s.leaders_injected = true;
                if (kind & 8) {  // a well-formed leader far away (a restart candidate)
                    p = s.camera_packet(b, 0xFFFF0000u | in.u8(), 0);
                    s.leaders_injected = true;
                }
                s.deliver(p);
                break;
            }
            case 6:  // the delayed packets arrive
                for (const auto &h : s.held) {
                    // Later than the client remembers the stream's blocks
                    // (4 windows), two leaders make a restart.
                    const std::uint32_t window = 4 * std::max(config.assembly_frames, 2u);
                    if (s.sent - h.second > 4 * window && h.first.size() > 7 &&
                        flt::gige::get_be32(h.first.data() + 4) == (1u << 24))
                        s.very_late = true;
                    s.deliver(h.first);
                }
                s.held.clear();
                break;
            case 7:
                s.take_all();
                break;
            case 8: {  // the camera answers the resend requests it can
                for (const auto &r : s.resend.asked)
                    for (std::uint32_t id = r.second.first;
                         id <= r.second.second && id <= s.last_id; ++id) {
                        auto it = s.camera_copy.find({r.first, id});
                        if (it != s.camera_copy.end() && (in.u8() & 3) != 0)
                            s.deliver(it->second);
                    }
                s.resend.asked.clear();
                break;
            }
            case 9:  // the camera restarts or jumps its block ids
                s.block = 1 + in.u16() % 65535;
                s.jumped = true;
                break;
            default:
                s.take_all();
                s.advance(1);
                break;
        }
        if (s.camera_copy.size() > 4096)
            s.camera_copy.clear();
    }
    // Let everything finish: time for every resend to be asked and given
    // up, then every frame taken or dropped.
    s.take_all();
    for (unsigned round = 0; round < 8 + config.resend_attempts * 2; ++round) {
        s.advance(config.resend_timeout_ms + 1);
        s.take_all();
    }
    CHECK(s.assembler.frames_in_assembly() == 0);
    std::uint64_t first = 0, last = 0;
    if (s.assembler.span(first, last)) {
        const std::uint64_t span = last - first + 1;
        CHECK(s.acc[FLT_COUNT_FRAMES] == s.delivered);
        CHECK(s.delivered + s.acc[FLT_COUNT_DROPPED] + s.acc[FLT_COUNT_LOST] == span);
        if (!s.leaders_injected && !s.jumped && !s.very_late)
            CHECK(span <= s.sent);
    } else {
        CHECK(s.delivered == 0);
    }
    CHECK(s.assembler.packets_missing() ==
          s.assembler.packets_resent() + s.assembler.packets_given_up());
    CHECK(s.acc[FLT_COUNT_DROPPED] >= s.acc[FLT_COUNT_INCOMPLETE]);
    return 0;
}
