// SPDX-License-Identifier: Apache-2.0
// USB3 Vision discovery: the device class (EF/02/01 with an interface
// association), the U3V interfaces (EF/05/protocol), the device-info
// descriptor (type 0x24, subtype 1) that points at the string descriptors.
#include "sources/u3v/discovery.hpp"

#include <cstring>

#include "core/error.hpp"
#include "sources/camera/camera.hpp"
#include "sources/source.hpp"
#include "sources/u3v/protocol.hpp"

namespace flt::u3v {

using sources::raise;

namespace {

// The U3V interfaces of a device, or false if it is no U3V camera.
struct u3v_layout {
    const usb_interface_desc *control = nullptr, *stream = nullptr;
    std::uint8_t string_index[8] = {0};  // GUID, vendor, model, family, ...
};

bool layout_of(const usb_device_desc &d, u3v_layout &out) {
    const bool iad =
        d.cls == k_class_misc && d.subclass == k_subclass_iad && d.protocol == k_protocol_iad;
    for (const usb_interface_desc &i : d.interfaces) {
        if (i.cls != k_class_misc || i.subclass != k_subclass_u3v || i.alternate != 0)
            continue;
        if (i.protocol == k_protocol_control)
            out.control = &i;
        if (i.protocol == k_protocol_stream)
            out.stream = &i;
    }
    if (!iad || !out.control)
        return false;
    // the device-info descriptor among the control interface's extra bytes
    const std::vector<std::uint8_t> &x = out.control->extra;
    for (std::size_t at = 0; at + 2 <= x.size();) {
        const std::size_t length = x[at];
        if (length < 2 || at + length > x.size())
            break;
        if (x[at + 1] == k_desc_device_info && length >= k_device_info_min_length &&
            x[at + 2] == k_desc_subtype_info)
            std::memcpy(out.string_index, &x[at + 11], 8);
        at += length;
    }
    return true;
}

bool endpoint_of(const usb_interface_desc &i, bool in, std::uint8_t &out) {
    for (const usb_endpoint_desc &e : i.endpoints)
        if ((e.attributes & 3) == 2 && bool(e.address & 0x80) == in) {
            out = e.address;
            return true;
        }
    return false;
}

}  // namespace

std::vector<camera_entry> list_cameras(usb_backend &bus) {
    std::vector<usb_device_desc> devices;
    usb_status st = bus.list(devices);
    if (st != usb_status::ok)
        raise(FLT_ERR_DEVICE, "cannot list the USB devices: %s", usb_status_name(st));
    std::vector<camera_entry> out;
    for (const usb_device_desc &d : devices) {
        u3v_layout layout;
        if (!layout_of(d, layout))
            continue;
        camera_entry e;
        e.desc = d;
        std::unique_ptr<usb_device> dev;
        st = bus.open(d, dev);
        if (st != usb_status::ok) {
            e.vendor = "?";
            e.error = std::string("cannot open: ") + usb_status_name(st);
            e.model = e.error;
        } else {
            dev->string_descriptor(layout.string_index[1], e.vendor);
            dev->string_descriptor(layout.string_index[2], e.model);
            dev->string_descriptor(layout.string_index[6], e.serial);
            // The camera's words reach callers who print them.
            e.vendor = sources::visible_text(e.vendor);
            e.model = sources::visible_text(e.model);
            e.serial = sources::visible_text(e.serial);
        }
        out.push_back(std::move(e));
    }
    return out;
}

usb_link::~usb_link() {
    if (dev && !disconnected) {
        if (if_stream >= 0)
            dev->release_interface(if_stream);
        if (if_control >= 0)
            dev->release_interface(if_control);
    }
}

void open_camera(usb_backend &bus, const char *serial, usb_link &out) {
    std::vector<camera_entry> cameras = list_cameras(bus);
    const camera_entry *chosen = nullptr;
    std::string seen;
    for (const camera_entry &e : cameras) {
        if (!seen.empty())
            seen += ", ";
        seen += e.error.empty() ? "'" + e.serial + "'" : "(" + e.error + ")";
        if (!e.error.empty())
            continue;
        if (!serial || e.serial == serial) {
            chosen = &e;
            break;
        }
    }
    if (!chosen) {
        if (cameras.empty())
            raise(FLT_ERR_NOT_FOUND, "no USB3 Vision camera is connected");
        bool unreadable = false;
        for (const camera_entry &e : cameras)
            unreadable = unreadable || !e.error.empty();
        // A camera that cannot be opened may be the one asked for.
        if (serial)
            raise(unreadable ? FLT_ERR_DEVICE : FLT_ERR_NOT_FOUND,
                  "no USB3 Vision camera has serial number '%.64s' (present: %.200s)", serial,
                  seen.c_str());
        raise(FLT_ERR_DEVICE,
              "no USB3 Vision camera could be opened: %.200s; on Linux "
              "install lib/sources/deploy/70-flatline-u3v.rules, on Windows "
              "the WinUSB driver",
              seen.c_str());
    }
    u3v_layout layout;
    layout_of(chosen->desc, layout);
    out.serial = chosen->serial;
    out.speed_mbps = chosen->desc.speed_mbps;
    if (!endpoint_of(*layout.control, true, out.ep_control_in) ||
        !endpoint_of(*layout.control, false, out.ep_control_out))
        raise(FLT_ERR_DEVICE, "camera '%s': its control interface lacks a bulk IN or OUT endpoint",
              chosen->serial.c_str());
    if (layout.stream && !endpoint_of(*layout.stream, true, out.ep_stream))
        raise(FLT_ERR_DEVICE, "camera '%s': its stream interface lacks a bulk IN endpoint",
              chosen->serial.c_str());
    usb_status st = bus.open(chosen->desc, out.dev);
    if (st != usb_status::ok)
        raise(FLT_ERR_DEVICE, "camera '%s' cannot be opened: %s", chosen->serial.c_str(),
              usb_status_name(st));
    st = out.dev->claim_interface(layout.control->number);
    if (st != usb_status::ok)
        raise(FLT_ERR_DEVICE, "camera '%s': cannot claim its control interface: %s",
              chosen->serial.c_str(), usb_status_name(st));
    out.if_control = layout.control->number;
    if (layout.stream) {
        st = out.dev->claim_interface(layout.stream->number);
        if (st != usb_status::ok)
            raise(FLT_ERR_DEVICE, "camera '%s': cannot claim its stream interface: %s",
                  chosen->serial.c_str(), usb_status_name(st));
        out.if_stream = layout.stream->number;
    }
}

}  // namespace flt::u3v
