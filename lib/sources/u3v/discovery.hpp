// SPDX-License-Identifier: Apache-2.0
// Internal: USB3 Vision discovery - which USB devices are U3V cameras, their
// strings, and opening one: its control and stream interfaces claimed, their
// bulk endpoints found.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "sources/u3v/transport.hpp"

namespace flt::u3v {

struct camera_entry {
    usb_device_desc desc;
    std::string vendor, model, serial;
    std::string error;  // why the camera could not be opened to read its strings
};

// The U3V cameras on a bus (strings read from the descriptors). Throws
// FLT_ERR_DEVICE when the bus cannot be listed.
std::vector<camera_entry> list_cameras(usb_backend &bus);

// An opened camera: its interfaces claimed (released by the destructor
// unless the device is gone).
struct usb_link {
    std::unique_ptr<usb_device> dev;
    std::uint8_t ep_control_in = 0, ep_control_out = 0;
    std::uint8_t ep_stream = 0;  // 0: the camera has no stream interface
    int if_control = -1, if_stream = -1;
    std::uint32_t speed_mbps = 0;
    std::string serial;
    bool disconnected = false;  // the device was unplugged

    usb_link() = default;
    usb_link(const usb_link &) = delete;
    usb_link &operator=(const usb_link &) = delete;
    ~usb_link();
};

// Opens the camera with serial number `serial` (NULL: the first that opens).
// Throws FLT_ERR_NOT_FOUND (no such serial, no camera) or FLT_ERR_DEVICE
// (cannot be opened or claimed: permissions, busy, odd descriptors).
void open_camera(usb_backend &bus, const char *serial, usb_link &out);

}  // namespace flt::u3v
