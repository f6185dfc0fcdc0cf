// SPDX-License-Identifier: Apache-2.0
// Internal: the seam in front of every libusb call the USB3 Vision client
// makes. Two implementations: libusb-1.0 (transport_libusb.cpp) and the
// simulated bus (sim_camera.cpp), so the real client code runs in the tests.
// An interface rather than linker wrapping because libusb_fill_bulk_transfer
// is inline and cannot be intercepted.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace flt::u3v {

// Outcomes of a USB operation (the libusb errors and transfer statuses the
// client distinguishes).
enum class usb_status {
    ok = 0,
    timeout,
    overflow,   // the device sent more than the buffer could hold
    no_device,  // unplugged
    stall,      // endpoint halted
    cancelled,
    no_memory,  // e.g. usbfs memory exhausted on Linux (submit refused)
    access,     // permission denied (udev rule / WinUSB driver missing)
    busy,       // claimed by another process
    not_found,
    io,  // anything else
};

const char *usb_status_name(usb_status status);

struct usb_endpoint_desc {
    std::uint8_t address = 0;     // bit 7 set: IN
    std::uint8_t attributes = 0;  // 2 = bulk
    std::uint16_t max_packet = 0;
};

struct usb_interface_desc {
    std::uint8_t number = 0, alternate = 0;
    std::uint8_t cls = 0, subclass = 0, protocol = 0;
    std::vector<usb_endpoint_desc> endpoints;
    std::vector<std::uint8_t> extra;  // class-specific descriptors, raw
};

// One device as enumerated: the device descriptor and the interfaces of its
// active configuration.
struct usb_device_desc {
    std::uint16_t vendor_id = 0, product_id = 0;
    std::uint8_t cls = 0, subclass = 0, protocol = 0;
    std::uint8_t bus = 0, address = 0;
    std::uint32_t speed_mbps = 0;
    std::vector<usb_interface_desc> interfaces;
    std::string error;  // why the configuration could not be read, if so
};

// A completed asynchronous bulk transfer.
struct usb_completion {
    std::size_t slot = 0;
    usb_status status = usb_status::ok;
    std::size_t length = 0;  // bytes received
};

// An open device. Synchronous bulk calls for the control channel, a pool of
// asynchronous bulk IN transfers ("slots") for the stream.
class usb_device {
  public:
    virtual ~usb_device() = default;
    virtual usb_status claim_interface(int number) = 0;
    virtual usb_status release_interface(int number) = 0;
    virtual usb_status clear_halt(std::uint8_t endpoint) = 0;
    virtual usb_status string_descriptor(std::uint8_t index, std::string &out) = 0;
    virtual usb_status bulk_write(std::uint8_t endpoint, const std::uint8_t *data,
                                  std::size_t length, std::size_t &sent, unsigned timeout_ms) = 0;
    virtual usb_status bulk_read(std::uint8_t endpoint, std::uint8_t *data, std::size_t capacity,
                                 std::size_t &received, unsigned timeout_ms) = 0;

    // Prepares `slots` transfers on `endpoint`; slot i reads into
    // buffers[i] (capacity bytes each, owned by the caller, alive until
    // async_release()). Allocates; called once per stream start.
    virtual usb_status async_prepare(std::uint8_t endpoint, std::size_t slots,
                                     std::uint8_t *const *buffers, std::size_t capacity) = 0;
    // Submits slot (must not be in flight). Completions come back in
    // submission order on the one endpoint.
    virtual usb_status async_submit(std::size_t slot) = 0;
    // Waits up to timeout_ms for one completion: ok with `out` filled, or
    // timeout when none came. Allocates nothing.
    virtual usb_status async_reap(unsigned timeout_ms, usb_completion &out) = 0;
    // Cancels every slot in flight and waits until none is; then frees
    // the transfers. Safe to call when nothing was prepared.
    virtual void async_release() = 0;
};

// The bus: enumeration and opening.
class usb_backend {
  public:
    virtual ~usb_backend() = default;
    virtual usb_status list(std::vector<usb_device_desc> &out) = 0;
    virtual usb_status open(const usb_device_desc &desc, std::unique_ptr<usb_device> &out) = 0;
};

// libusb-1.0 (a fresh context per backend). Throws flt::error(FLT_ERR_DEVICE)
// when libusb cannot start.
std::unique_ptr<usb_backend> make_libusb_backend();

}  // namespace flt::u3v
