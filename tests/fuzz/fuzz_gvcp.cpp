// SPDX-License-Identifier: Apache-2.0
// libFuzzer harness: the GigE Vision control channel's reading of a
// camera's answers (lib/sources/gige/: control.cpp, bootstrap.cpp,
// discovery.cpp, internal). The real control_channel talks to a scripted
// camera (a datagram_port whose clock moves only when it is waited on):
// for every command the input says what comes back - nothing, an
// acknowledge with fuzzed status, command, length, request id and data,
// PENDING_ACKs asking for up to 65.5 s, raw bytes - and from whom (the
// camera, or another port). The operations are READREG, WRITEREG, READMEM
// and WRITEMEM of any range, resend requests, the bootstrap read with the
// description its URL names (plain or zipped), and discovery answers.
// Checked:
//   - every failure is flt::error with a status the API documents for it
//     (TIMEOUT, DEVICE, FORMAT, INVALID_ARGUMENT) and a message;
//   - no operation waits longer than its commands may: per command the
//     attempts' timeouts plus the pending-acknowledge cap
//     (sources::k_pending_wait_cap_ms);
//   - datagrams from anyone but the camera are counted BAD_PACKETS and
//     never taken as an answer;
//   - discovery strings hold no control byte (terminal escapes).
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "sources/camera/camera.hpp"
#include "sources/gige/bootstrap.hpp"
#include "sources/gige/control.hpp"
#include "sources/gige/discovery.hpp"
#include "sources/gige/protocol.hpp"

using namespace flt::gige;

namespace {

#define CHECK(cond) \
  do {              \
    if (!(cond))    \
      std::abort(); \
  } while (0)

struct input {
    const std::uint8_t *p;
    std::size_t n;
    bool empty() const { return n == 0; }
    std::uint8_t u8() { return n ? (--n, *p++) : 0; }
    std::uint16_t u16() { return std::uint16_t((u8() << 8) | u8()); }
    std::uint32_t u32() { return (std::uint32_t(u16()) << 16) | u16(); }
};

const endpoint k_camera{0x7F000001u, 3956};

struct datagram {
    std::vector<std::uint8_t> bytes;
    endpoint from;
};

// The scripted camera. Its clock moves when the channel waits for nothing.
class scripted_camera final : public datagram_port {
  public:
    explicit scripted_camera(input &in) : in_(in) {}
    std::uint64_t sends = 0, strangers = 0;
    // The camera's memory, for answers that look right (READMEM of the
    // bootstrap block, the URL, the description).
    std::vector<std::uint8_t> memory = std::vector<std::uint8_t>(0x2000, 0);

    void send_to(const void *data, std::size_t bytes, endpoint to) override {
        CHECK(to.address == k_camera.address && to.port == k_camera.port);
        CHECK(bytes >= k_gvcp_header && bytes <= k_gvcp_header + 8 + k_memory_chunk + 16);
        ++sends;
        const auto *c = static_cast<const std::uint8_t *>(data);
        CHECK(c[0] == k_gvcp_key);
        const std::uint16_t command = get_be16(c + 2), id = get_be16(c + 6);
        if (command == k_packet_resend_cmd)
            return;  // no acknowledge
        const unsigned answers = in_.u8() % 4;
        for (unsigned i = 0; i < answers && queue_.size() < 64; ++i)
            queue_.push_back(reply(c, bytes, command, id));
    }

    bool receive(void *buffer, std::size_t capacity, std::size_t &got, endpoint *from,
                 unsigned timeout_ms) override {
        if (queue_.empty()) {
            now_ += std::chrono::milliseconds(timeout_ms);  // nothing came
            return false;
        }
        datagram d = std::move(queue_.front());
        queue_.pop_front();
        now_ += std::chrono::microseconds(in_.u8());
        got = std::min(capacity, d.bytes.size());
        if (got)
            std::memcpy(buffer, d.bytes.data(), got);
        if (from)
            *from = d.from;
        return true;
    }

    clock::time_point now() const override { return now_; }

  private:
    datagram reply(const std::uint8_t *c, std::size_t bytes, std::uint16_t command,
                   std::uint16_t id) {
        datagram d;
        const std::uint8_t kind = in_.u8();
        d.from = k_camera;
        if (kind & 0x80) {
            d.from.port = std::uint16_t(k_camera.port + 1 + (kind & 7));
            ++strangers;
        }
        std::vector<std::uint8_t> data;
        switch ((kind >> 3) & 7) {
            case 0: {  // what a camera would answer, from its memory
                if (command == k_readreg_cmd) {
                    for (std::size_t at = k_gvcp_header; at + 4 <= bytes; at += 4) {
                        const std::uint32_t a = get_be32(c + at) % (memory.size() - 4);
                        data.insert(data.end(), memory.begin() + a, memory.begin() + a + 4);
                    }
                } else if (command == k_readmem_cmd) {
                    const std::uint32_t a = get_be32(c + 8);
                    const std::size_t n = get_be16(c + 14);
                    data.resize(4 + n);
                    put_be32(data.data(), a);
                    for (std::size_t i = 0; i < n; ++i)
                        data[4 + i] = memory[(a + i) % memory.size()];
                } else {
                    data.assign(4, 0);
                }
                break;
            }
            case 1: {  // a pending acknowledge, asking for up to 65535 ms
                d.bytes.assign(k_gvcp_header + 4, 0);
                put_be16(d.bytes.data() + 2, k_pending_ack);
                put_be16(d.bytes.data() + 4, 4);
                put_be16(d.bytes.data() + 6, id);
                put_be16(d.bytes.data() + k_gvcp_header + 2, in_.u16());
                return d;
            }
            case 2: {  // raw bytes
                d.bytes.resize(in_.u8() % 64);
                for (auto &b : d.bytes)
                    b = in_.u8();
                return d;
            }
            default: {  // fuzzed data
                data.resize(in_.u8() % 600);
                for (auto &b : data)
                    b = in_.u8();
                break;
            }
        }
        d.bytes.assign(k_gvcp_header, 0);
        d.bytes.insert(d.bytes.end(), data.begin(), data.end());
        std::uint8_t *a = d.bytes.data();
        put_be16(a, kind & 1 ? in_.u16() : 0);                               // status
        put_be16(a + 2, kind & 2 ? in_.u16() : std::uint16_t(command + 1));  // answer
        put_be16(a + 4, kind & 4 ? in_.u16() : std::uint16_t(data.size()));  // length
        put_be16(a + 6, (kind & 0x40) ? in_.u16() : id);                     // request id
        return d;
    }

    input &in_;
    std::deque<datagram> queue_;
    clock::time_point now_{};
};

bool documented(flt_status s) {
    return s == FLT_ERR_TIMEOUT || s == FLT_ERR_DEVICE || s == FLT_ERR_FORMAT ||
           s == FLT_ERR_INVALID_ARGUMENT;
}

// Runs one operation: a failure must be documented and explained; its
// time at most what its commands may take.
template <class F> void operation(scripted_camera &cam, const control_config &config, F &&call) {
    const auto t0 = cam.now();
    const std::uint64_t sends0 = cam.sends;
    try {
        call();
    } catch (const flt::error &e) {
        CHECK(documented(e.status) && e.what()[0] != '\0');
    } catch (const std::bad_alloc &) {
    }
    const auto took = std::chrono::duration_cast<std::chrono::milliseconds>(cam.now() - t0);
    // Each send is one attempt of one command: its timeout, and at most
    // once per command the pending cap (counted per send: an upper bound).
    const std::uint64_t sends = cam.sends - sends0;
    const std::uint64_t bound =
        sends * (2ull * config.timeout_ms + flt::sources::k_pending_wait_cap_ms) + 1;
    CHECK(std::uint64_t(took.count()) <= bound);
}

bool visible(const std::string &s) {
    for (std::size_t i = 0; i < s.size(); ++i) {
        const auto c = static_cast<unsigned char>(s[i]);
        if (c < 0x20 || c == 0x7F)
            return false;
        if (c == 0xC2 && i + 1 < s.size() && static_cast<unsigned char>(s[i + 1]) >= 0x80 &&
            static_cast<unsigned char>(s[i + 1]) <= 0x9F)
            return false;  // a C1 control
    }
    return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
    input in{data, size};
    control_config config;
    config.timeout_ms = 1 + in.u8() % 20;
    config.command_attempts = 1 + in.u8() % 3;
    config.pending_ack_limit = in.u8() % 8;
    auto owned = std::make_unique<scripted_camera>(in);
    scripted_camera &cam = *owned;
    // The camera's memory: a bootstrap block, a URL and a small file.
    const std::size_t preset = std::min<std::size_t>(in.u8() * 8u, in.n);
    for (std::size_t i = 0; i < preset; ++i)
        cam.memory[i] = in.u8();
    control_channel control(k_camera, config, std::move(owned), 0x7F000001u);

    for (int op = 0; op < 64 && !in.empty(); ++op) {
        const std::uint8_t what = in.u8();
        switch (what % 8) {
            case 0:
                operation(cam, config, [&] { (void)control.read_register(in.u32()); });
                break;
            case 1:
                operation(cam, config, [&] { control.write_register(in.u32(), in.u32()); });
                break;
            case 2: {
                std::vector<std::uint8_t> out(in.u16() % 2048 + 1);
                const std::uint64_t address = what & 0x80 ? 0xFFFFFF00ull + in.u8() : in.u32();
                operation(cam, config, [&] { control.read(address, out.data(), out.size()); });
                break;
            }
            case 3: {
                std::vector<std::uint8_t> bytes(in.u16() % 1100 + 1, 0xA5);
                operation(cam, config,
                          [&] { control.write(in.u32(), bytes.data(), bytes.size()); });
                break;
            }
            case 4:
                operation(cam, config, [&] { control.request_resend(in.u16(), in.u8(), in.u8()); });
                break;
            case 5:
                operation(cam, config, [&] {
                    const bootstrap_info b = read_bootstrap(control);
                    for (const std::string &s : b.strings)
                        CHECK(visible(s));
                    (void)read_description(control, b.first_url);
                });
                break;
            case 6: {  // a URL of the input's choosing
                std::string url(in.u8() % 80, ' ');
                for (char &ch : url)
                    ch = char(in.u8());
                if (what & 0x80)
                    url = "Local:x.zip;" + std::to_string(in.u8()) + ";" + std::to_string(in.u16());
                operation(cam, config, [&] { (void)read_description(control, url); });
                break;
            }
            default: {  // a discovery answer's data
                std::vector<std::uint8_t> d(in.u16() % 400);
                for (auto &b : d)
                    b = in.u8();
                try {
                    const camera_info c = parse_discovery(d.data(), d.size(), k_camera);
                    for (const std::string &s : c.strings)
                        CHECK(visible(s));
                } catch (const flt::error &e) {
                    CHECK(e.status == FLT_ERR_FORMAT && e.what()[0] != '\0');
                }
                break;
            }
        }
    }
    // Strangers are counted, never more than the script sent.
    CHECK(control.count(FLT_COUNT_BAD_PACKETS) <= cam.strangers);
    return 0;
}
