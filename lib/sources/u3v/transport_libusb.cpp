// SPDX-License-Identifier: Apache-2.0
// The transport over libusb-1.0. Every libusb call of the library is here.
#include <libusb.h>

#include <chrono>
#include <cstring>

#include "core/error.hpp"
#include "sources/u3v/transport.hpp"

namespace flt::u3v {

const char *usb_status_name(usb_status status) {
    switch (status) {
        case usb_status::ok:
            return "ok";
        case usb_status::timeout:
            return "timeout";
        case usb_status::overflow:
            return "overflow";
        case usb_status::no_device:
            return "no device (unplugged)";
        case usb_status::stall:
            return "endpoint stalled";
        case usb_status::cancelled:
            return "cancelled";
        case usb_status::no_memory:
            return "out of memory (usbfs limit?)";
        case usb_status::access:
            return "access denied (udev rule or WinUSB driver missing?)";
        case usb_status::busy:
            return "busy (claimed by another process)";
        case usb_status::not_found:
            return "not found";
        case usb_status::io:
            return "I/O error";
    }
    return "unknown";
}

namespace {

usb_status from_error(int code) {
    switch (code) {
        case LIBUSB_SUCCESS:
            return usb_status::ok;
        case LIBUSB_ERROR_TIMEOUT:
            return usb_status::timeout;
        case LIBUSB_ERROR_OVERFLOW:
            return usb_status::overflow;
        case LIBUSB_ERROR_NO_DEVICE:
            return usb_status::no_device;
        case LIBUSB_ERROR_PIPE:
            return usb_status::stall;
        case LIBUSB_ERROR_NO_MEM:
            return usb_status::no_memory;
        case LIBUSB_ERROR_ACCESS:
            return usb_status::access;
        case LIBUSB_ERROR_BUSY:
            return usb_status::busy;
        case LIBUSB_ERROR_NOT_FOUND:
            return usb_status::not_found;
        default:
            return usb_status::io;
    }
}

usb_status from_transfer(libusb_transfer_status status) {
    switch (status) {
        case LIBUSB_TRANSFER_COMPLETED:
            return usb_status::ok;
        case LIBUSB_TRANSFER_TIMED_OUT:
            return usb_status::timeout;
        case LIBUSB_TRANSFER_CANCELLED:
            return usb_status::cancelled;
        case LIBUSB_TRANSFER_STALL:
            return usb_status::stall;
        case LIBUSB_TRANSFER_NO_DEVICE:
            return usb_status::no_device;
        case LIBUSB_TRANSFER_OVERFLOW:
            return usb_status::overflow;
        default:
            return usb_status::io;
    }
}

std::uint32_t speed_mbps(int speed) {
    switch (speed) {
        case LIBUSB_SPEED_LOW:
            return 1;
        case LIBUSB_SPEED_FULL:
            return 12;
        case LIBUSB_SPEED_HIGH:
            return 480;
        case LIBUSB_SPEED_SUPER:
            return 5000;
#if defined(LIBUSB_API_VERSION) && LIBUSB_API_VERSION >= 0x01000106
        case LIBUSB_SPEED_SUPER_PLUS:
            return 10000;
#endif
        default:
            return 0;
    }
}

class libusb_device_impl final : public usb_device {
  public:
    libusb_device_impl(libusb_context *ctx, libusb_device_handle *handle)
        : ctx_(ctx), handle_(handle) {}
    ~libusb_device_impl() override {
        async_release();
        libusb_close(handle_);
    }

    usb_status claim_interface(int number) override {
        // Linux: a kernel driver (none for U3V normally) would block the claim.
        libusb_set_auto_detach_kernel_driver(handle_, 1);
        return from_error(libusb_claim_interface(handle_, number));
    }
    usb_status release_interface(int number) override {
        return from_error(libusb_release_interface(handle_, number));
    }
    usb_status clear_halt(std::uint8_t endpoint) override {
        return from_error(libusb_clear_halt(handle_, endpoint));
    }
    usb_status string_descriptor(std::uint8_t index, std::string &out) override {
        out.clear();
        if (index == 0)
            return usb_status::ok;
        unsigned char text[256];
        int n = libusb_get_string_descriptor_ascii(handle_, index, text, sizeof text);
        if (n < 0)
            return from_error(n);
        out.assign(reinterpret_cast<char *>(text), std::size_t(n));
        return usb_status::ok;
    }
    usb_status bulk_write(std::uint8_t endpoint, const std::uint8_t *data, std::size_t length,
                          std::size_t &sent, unsigned timeout_ms) override {
        int done = 0;
        int rc = libusb_bulk_transfer(handle_, endpoint, const_cast<std::uint8_t *>(data),
                                      int(length), &done, timeout_ms);
        sent = std::size_t(done);
        return from_error(rc);
    }
    usb_status bulk_read(std::uint8_t endpoint, std::uint8_t *data, std::size_t capacity,
                         std::size_t &received, unsigned timeout_ms) override {
        int done = 0;
        int rc = libusb_bulk_transfer(handle_, endpoint, data, int(capacity), &done, timeout_ms);
        received = std::size_t(done);
        return from_error(rc);
    }

    usb_status async_prepare(std::uint8_t endpoint, std::size_t slots, std::uint8_t *const *buffers,
                             std::size_t capacity) override {
        async_release();
        slots_.resize(slots);
        done_.assign(slots, 0);
        queue_.assign(slots, 0);
        head_ = tail_ = count_ = 0;
        for (std::size_t i = 0; i < slots; ++i) {
            slot &s = slots_[i];
            s.owner = this;
            s.index = i;
            s.transfer = libusb_alloc_transfer(0);
            if (!s.transfer) {
                async_release();
                return usb_status::no_memory;
            }
            // Timeout 0: a stream transfer waits for the camera as long as it
            // takes; flt_source_next()'s timeout bounds the wait instead.
            libusb_fill_bulk_transfer(s.transfer, handle_, endpoint, buffers[i], int(capacity),
                                      &libusb_device_impl::on_done, &s, 0);
        }
        return usb_status::ok;
    }
    usb_status async_submit(std::size_t index) override {
        slot &s = slots_.at(index);
        int rc = libusb_submit_transfer(s.transfer);
        if (rc == 0)
            s.in_flight = true;
        return from_error(rc);
    }
    usb_status async_reap(unsigned timeout_ms, usb_completion &out) override {
        using clock = std::chrono::steady_clock;
        const auto deadline = clock::now() + std::chrono::milliseconds(timeout_ms);
        while (count_ == 0) {
            const auto now = clock::now();
            if (now >= deadline)
                return usb_status::timeout;
            const auto left = std::chrono::duration_cast<std::chrono::microseconds>(deadline - now);
            timeval tv;
            tv.tv_sec = long(left.count() / 1000000);
            tv.tv_usec = long(left.count() % 1000000);
            int rc = libusb_handle_events_timeout_completed(ctx_, &tv, nullptr);
            if (rc < 0 && rc != LIBUSB_ERROR_INTERRUPTED)
                return from_error(rc);
        }
        const std::size_t index = queue_[head_];
        head_ = (head_ + 1) % queue_.size();
        --count_;
        libusb_transfer *t = slots_[index].transfer;
        out.slot = index;
        out.status = from_transfer(t->status);
        out.length = std::size_t(t->actual_length);
        return usb_status::ok;
    }
    void async_release() override {
        bool any = false;
        for (slot &s : slots_)
            if (s.in_flight) {
                libusb_cancel_transfer(s.transfer);
                any = true;
            }
        // Cancellation completes asynchronously: run the event loop until
        // every callback came back (bounded: a vanished device returns at
        // once, a live one within a few ms).
        for (int round = 0; any && round < 200; ++round) {
            timeval tv{0, 10000};
            libusb_handle_events_timeout_completed(ctx_, &tv, nullptr);
            any = false;
            for (slot &s : slots_)
                any = any || s.in_flight;
        }
        for (slot &s : slots_)
            if (s.transfer && !s.in_flight)
                libusb_free_transfer(s.transfer);
        slots_.clear();
        head_ = tail_ = count_ = 0;
    }

  private:
    struct slot {
        libusb_device_impl *owner = nullptr;
        std::size_t index = 0;
        libusb_transfer *transfer = nullptr;
        bool in_flight = false;
    };
    static void LIBUSB_CALL on_done(libusb_transfer *t) {
        slot *s = static_cast<slot *>(t->user_data);
        s->in_flight = false;
        libusb_device_impl *self = s->owner;
        // Completions of one endpoint arrive in submission order; the ring
        // holds at most one entry per slot, so it cannot overflow.
        self->queue_[self->tail_] = s->index;
        self->tail_ = (self->tail_ + 1) % self->queue_.size();
        ++self->count_;
    }

    libusb_context *ctx_;
    libusb_device_handle *handle_;
    std::vector<slot> slots_;
    std::vector<std::uint8_t> done_;
    std::vector<std::size_t> queue_;
    std::size_t head_ = 0, tail_ = 0, count_ = 0;
};

class libusb_backend final : public usb_backend {
  public:
    libusb_backend() {
        int rc = libusb_init(&ctx_);
        if (rc != 0)
            throw error(FLT_ERR_DEVICE,
                        (std::string("libusb_init failed: ") + libusb_error_name(rc)).c_str());
    }
    ~libusb_backend() override { libusb_exit(ctx_); }

    usb_status list(std::vector<usb_device_desc> &out) override {
        out.clear();
        libusb_device **devices = nullptr;
        ssize_t n = libusb_get_device_list(ctx_, &devices);
        if (n < 0)
            return from_error(int(n));
        for (ssize_t i = 0; i < n; ++i)
            out.push_back(describe(devices[i]));
        libusb_free_device_list(devices, 1);
        return usb_status::ok;
    }

    usb_status open(const usb_device_desc &desc, std::unique_ptr<usb_device> &out) override {
        libusb_device **devices = nullptr;
        ssize_t n = libusb_get_device_list(ctx_, &devices);
        if (n < 0)
            return from_error(int(n));
        usb_status st = usb_status::not_found;
        for (ssize_t i = 0; i < n; ++i) {
            libusb_device *d = devices[i];
            if (libusb_get_bus_number(d) != desc.bus ||
                libusb_get_device_address(d) != desc.address)
                continue;
            libusb_device_handle *h = nullptr;
            st = from_error(libusb_open(d, &h));
            if (st == usb_status::ok)
                out = std::make_unique<libusb_device_impl>(ctx_, h);
            break;
        }
        libusb_free_device_list(devices, 1);
        return st;
    }

  private:
    static usb_device_desc describe(libusb_device *d) {
        usb_device_desc desc;
        desc.bus = libusb_get_bus_number(d);
        desc.address = libusb_get_device_address(d);
        desc.speed_mbps = speed_mbps(libusb_get_device_speed(d));
        libusb_device_descriptor dd;
        if (libusb_get_device_descriptor(d, &dd) != 0) {
            desc.error = "device descriptor unreadable";
            return desc;
        }
        desc.vendor_id = dd.idVendor;
        desc.product_id = dd.idProduct;
        desc.cls = dd.bDeviceClass;
        desc.subclass = dd.bDeviceSubClass;
        desc.protocol = dd.bDeviceProtocol;
        libusb_config_descriptor *config = nullptr;
        int rc = libusb_get_active_config_descriptor(d, &config);
        if (rc != 0) {
            desc.error = std::string("configuration unreadable: ") + libusb_error_name(rc);
            return desc;
        }
        for (int i = 0; i < config->bNumInterfaces; ++i) {
            const libusb_interface &itf = config->interface[i];
            for (int a = 0; a < itf.num_altsetting; ++a) {
                const libusb_interface_descriptor &id = itf.altsetting[a];
                usb_interface_desc out;
                out.number = id.bInterfaceNumber;
                out.alternate = id.bAlternateSetting;
                out.cls = id.bInterfaceClass;
                out.subclass = id.bInterfaceSubClass;
                out.protocol = id.bInterfaceProtocol;
                for (int e = 0; e < id.bNumEndpoints; ++e) {
                    const libusb_endpoint_descriptor &ed = id.endpoint[e];
                    out.endpoints.push_back(
                        {ed.bEndpointAddress, ed.bmAttributes, ed.wMaxPacketSize});
                }
                if (id.extra && id.extra_length > 0)
                    out.extra.assign(id.extra, id.extra + id.extra_length);
                desc.interfaces.push_back(std::move(out));
            }
        }
        libusb_free_config_descriptor(config);
        return desc;
    }

    libusb_context *ctx_ = nullptr;
};

}  // namespace

std::unique_ptr<usb_backend> make_libusb_backend() {
    return std::make_unique<libusb_backend>();
}

}  // namespace flt::u3v
