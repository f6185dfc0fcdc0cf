// SPDX-License-Identifier: Apache-2.0
// libFuzzer harness: the USB3 Vision packet parsers of the client
// (lib/sources/u3v/, internal: flt::u3v::u3v_camera and its control and
// stream layers). The real client
// opens a simulated camera (lib/sources/u3v/sim_camera.cpp) through a
// transport that passes everything through until the stream is started;
// from then on the transport answers with the input's bytes:
//   - stream transfers (async_reap): leaders, payload, trailers, built from
//     templates with fuzzed fields or raw, with fuzzed lengths and transfer
//     statuses (overflow, stall, unplug), reaped by u3v_camera::next();
//   - control acknowledges (bulk_read), when the first byte says so: the
//     GenCP acks of get_int / set_int / read_memory / execute.
// Expected failures are flt::error with a status (TIMEOUT, DEVICE, FORMAT,
// ...); anything else, a crash or a sanitizer report is a finding. Every
// frame delivered must be readable in full (width x height x bytes).
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "sources/u3v/protocol.hpp"
#include "sources/u3v/u3v_source.hpp"
#include "testing/sim_camera.hpp"

using namespace flt::u3v;
using flt::testing::sim_bus;
using flt::testing::sim_set;

namespace {

struct input {
    const std::uint8_t *p;
    std::size_t n;
    std::uint8_t u8() { return n ? (--n, *p++) : 0; }
    std::uint16_t u16() { return std::uint16_t(u8() | (u8() << 8)); }
    std::uint32_t u32() { return std::uint32_t(u16() | (std::uint32_t(u16()) << 16)); }
    std::uint64_t u64() { return u32() | (std::uint64_t(u32()) << 32); }
};

class fuzz_device final : public usb_device {
  public:
    fuzz_device(std::unique_ptr<usb_device> inner, input &in, bool fuzz_control)
        : inner_(std::move(inner)), in_(in), fuzz_control_(fuzz_control) {}
    bool fuzzing = false;

    usb_status claim_interface(int i) override { return inner_->claim_interface(i); }
    usb_status release_interface(int i) override { return inner_->release_interface(i); }
    usb_status clear_halt(std::uint8_t ep) override { return inner_->clear_halt(ep); }
    usb_status string_descriptor(std::uint8_t i, std::string &out) override {
        return inner_->string_descriptor(i, out);
    }
    usb_status bulk_write(std::uint8_t ep, const std::uint8_t *d, std::size_t n, std::size_t &sent,
                          unsigned t) override {
        if (fuzzing && fuzz_control_) {
            // Keep the request id the client expects in the ack template.
            if (n >= 12)
                last_request_id_ = get_u16(d + 10), last_command_ = get_u16(d + 6);
            sent = n;
            return usb_status::ok;
        }
        return inner_->bulk_write(ep, d, n, sent, t);
    }
    usb_status bulk_read(std::uint8_t ep, std::uint8_t *d, std::size_t cap, std::size_t &got,
                         unsigned t) override {
        if (!(fuzzing && fuzz_control_))
            return inner_->bulk_read(ep, d, cap, got, t);
        if (in_.n == 0)
            return usb_status::timeout;
        const std::uint8_t kind = in_.u8();
        if (kind == 0xFF)
            return usb_status::no_device;
        if (kind >= 0xF0)
            return usb_status::timeout;
        std::size_t n = std::min<std::size_t>(cap, in_.u16() % (cap + 16));
        for (std::size_t i = 0; i < n; ++i)
            d[i] = in_.u8();
        if ((kind & 3) != 0 && n >= 12) {  // an ack-shaped packet with fuzzed fields
            put_u32(d, k_prefix_control);
            put_u16(d + 4, kind & 4 ? std::uint16_t(0x8000 | in_.u8()) : 0);
            put_u16(d + 6, kind & 8 ? k_ack_pending : std::uint16_t(last_command_ + 1));
            put_u16(d + 8, kind & 16 ? in_.u16() : std::uint16_t(n - 12));
            put_u16(d + 10, kind & 32 ? in_.u16() : last_request_id_);
        }
        got = n;
        return usb_status::ok;
    }
    usb_status async_prepare(std::uint8_t ep, std::size_t slots, std::uint8_t *const *buffers,
                             std::size_t capacity) override {
        buffers_.assign(buffers, buffers + slots);
        capacity_ = capacity;
        queue_.clear();
        return inner_->async_prepare(ep, slots, buffers, capacity);
    }
    usb_status async_submit(std::size_t slot) override {
        queue_.push_back(slot);
        return fuzzing ? usb_status::ok : inner_->async_submit(slot);
    }
    usb_status async_reap(unsigned t, usb_completion &out) override {
        if (!fuzzing)
            return inner_->async_reap(t, out);
        if (in_.n == 0 || queue_.empty())
            return usb_status::timeout;
        out.slot = queue_.front();
        queue_.pop_front();
        std::uint8_t *d = buffers_[out.slot];
        const std::uint8_t kind = in_.u8();
        out.status = usb_status::ok;
        if (kind == 0xFF)
            out.status = usb_status::no_device;
        else if (kind == 0xFE)
            out.status = usb_status::stall;
        else if (kind == 0xFD)
            out.status = usb_status::overflow;
        std::size_t n = in_.u16() % (capacity_ + 1);
        if (kind % 4 == 1) {  // a leader with fuzzed fields
            n = std::max<std::size_t>(n, 52);
            std::memset(d, 0, n);
            put_u32(d, k_magic_leader);
            put_u16(d + 6, kind & 16 ? in_.u16() : 52);        // leader size
            put_u64(d + 8, kind & 32 ? in_.u64() : ++block_);  // block id
            put_u16(d + 18, kind & 64 ? in_.u16() : k_payload_image);
            put_u64(d + 20, in_.u64());  // timestamp
            put_u32(d + 28, kind & 128 ? in_.u32() : k_pfnc_mono8);
            put_u32(d + 32, kind & 8 ? in_.u32() : 64);  // width
            put_u32(d + 36, kind & 8 ? in_.u32() : 32);  // height
            put_u16(d + 48, in_.u8() % 4);               // padding x
        } else if (kind % 4 == 2) {                      // a trailer with fuzzed fields
            n = std::max<std::size_t>(n, 32);
            std::memset(d, 0, n);
            put_u32(d, k_magic_trailer);
            put_u16(d + 6, kind & 16 ? in_.u16() : 32);
            put_u64(d + 8, kind & 32 ? in_.u64() : block_);
            put_u16(d + 16, kind & 64 ? in_.u16() : 0);         // status
            put_u64(d + 20, kind & 128 ? in_.u64() : 64 * 32);  // valid payload size
            put_u32(d + 28, in_.u32());                         // size y
        } else {                                                // raw bytes (payload, garbage)
            const std::uint8_t fill = in_.u8();
            for (std::size_t i = 0; i < n; ++i)
                d[i] = kind & 4 ? in_.u8() : fill;
        }
        n = std::min(n, capacity_);
        out.length = n;
        return usb_status::ok;
    }
    void async_release() override {
        queue_.clear();
        inner_->async_release();
    }

  private:
    std::unique_ptr<usb_device> inner_;
    input &in_;
    bool fuzz_control_;
    std::vector<std::uint8_t *> buffers_;
    std::size_t capacity_ = 0;
    std::deque<std::size_t> queue_;
    std::uint64_t block_ = 0;
    std::uint16_t last_request_id_ = 0, last_command_ = 0;
};

class fuzz_backend final : public usb_backend {
  public:
    fuzz_backend(sim_bus &bus, input &in, bool fuzz_control)
        : bus_(bus), in_(in), fuzz_control_(fuzz_control) {}
    fuzz_device *device = nullptr;
    usb_status list(std::vector<usb_device_desc> &out) override { return bus_.list(out); }
    usb_status open(const usb_device_desc &desc, std::unique_ptr<usb_device> &out) override {
        std::unique_ptr<usb_device> inner;
        const usb_status st = bus_.open(desc, inner);
        if (st != usb_status::ok)
            return st;
        auto dev = std::make_unique<fuzz_device>(std::move(inner), in_, fuzz_control_);
        device = dev.get();
        out = std::move(dev);
        return usb_status::ok;
    }

  private:
    sim_bus &bus_;
    input &in_;
    bool fuzz_control_;
};

// The statuses feature_engine (lib/sources/camera/features.hpp) and the
// channels document. FLT_ERR_NUMERIC is a register whose bytes are no value:
// a float register that holds NaN or an infinity, a formula that fails for
// what the camera answered.
bool expected(flt_status st) {
    return st == FLT_ERR_TIMEOUT || st == FLT_ERR_DEVICE || st == FLT_ERR_FORMAT ||
           st == FLT_ERR_STATE || st == FLT_ERR_NOT_FOUND || st == FLT_ERR_INVALID_ARGUMENT ||
           st == FLT_ERR_NUMERIC || st == FLT_ERR_OUT_OF_MEMORY;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
    input in{data, size};
    const std::uint8_t mode = in.u8();
    const bool fuzz_control = mode & 1;
    sim_bus bus;
    const std::size_t index = bus.add_camera("Vendor", "Model", "S1", 64, 32, 8);
    if (mode & 2)
        sim_set(bus.camera(index), FLT_U3V_SIM_ENCODER_CHUNK, 1);
    fuzz_backend backend(bus, in, fuzz_control);
    camera_config config;
    config.stream.transfers = 2 + (mode >> 4) % 4;
    config.stream.max_transfer_bytes = 512u << ((mode >> 2) & 3);  // several transfers per frame
    config.stream.want_chunk = mode & 2;
    config.stream.chunk_id = 0x4E434445u;
    config.control.command_attempts = 1;
    try {
        u3v_camera cam(backend, "S1", config);
        cam.start();
        backend.device->fuzzing = true;
        for (int i = 0; i < 64 && in.n > 0; ++i) {
            try {
                if (fuzz_control) {
                    switch (in.u8() % 5) {
                        case 0:
                            (void)cam.get_int("Width");
                            break;
                        case 1:
                            cam.set_int("Height", 16);
                            break;
                        case 2: {
                            std::uint8_t buf[600];
                            cam.read_memory(0x1000 + in.u8(), buf, 1 + in.u16() % sizeof buf);
                            break;
                        }
                        case 3:
                            cam.execute("AcquisitionStop");
                            break;
                        default:
                            (void)cam.get_float("Gain");
                            break;
                    }
                } else {
                    flt::sources::raw_frame f;
                    if (cam.next(0, f)) {
                        // Read the whole image: ASan catches a frame that
                        // claims more than its buffer holds.
                        const std::size_t row = std::size_t(f.width) * (f.format > 8 ? 2 : 1);
                        if (f.stride < row || f.pixels == nullptr)
                            std::abort();
                        const auto *pixels = static_cast<const std::uint8_t *>(f.pixels);
                        unsigned sum = 0;
                        for (std::uint32_t r = 0; r < f.height; ++r)
                            for (std::size_t b = 0; b < row; ++b)
                                sum += pixels[r * f.stride + b];
                        if (sum == 0xFFFFFFFFu)
                            std::abort();  // keeps the loop
                    }
                }
            } catch (const flt::error &e) {
                if (!expected(e.status))
                    std::abort();
            }
        }
        cam.stop();
    } catch (const flt::error &e) {
        if (!expected(e.status))
            std::abort();
    } catch (const std::bad_alloc &) {
    }
    return 0;
}
