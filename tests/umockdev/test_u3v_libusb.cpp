// SPDX-License-Identifier: Apache-2.0
/*
 * The libusb transport (lib/sources/u3v/transport_libusb.cpp) under test:
 * the real libusb-1.0 of the system talks to an emulated USB3 Vision camera.
 *
 * umockdev (Debian's umockdev, libumockdev-dev) gives this process a sysfs
 * and udev view with one USB device, bus 1 address 2, whose descriptors
 * make it a U3V camera (class EF/02/01, control, event and stream
 * interfaces, the device-info descriptor), plus a keyboard; its usbfs node
 * /dev/bus/usb/001/002 answers the ioctls libusb sends (capabilities,
 * claim, clear halt, submit / reap / discard URB) from the handler below.
 * Behind the handler sits the testing tier's simulated camera
 * (lib/testing/sim_camera.*), as its device side: GenCP commands from bulk
 * OUT URBs, acknowledges into bulk IN URBs on the control endpoint, leader /
 * payload / trailer transfers into bulk IN URBs on the stream endpoint.
 *
 * What runs is libflatline's public API with NULL as the transport, i.e.
 * the code a vendor's HMI runs: discovery (libusb_get_device_list, the
 * configuration descriptor, string descriptors over control transfers),
 * the control channel (synchronous bulk transfers, a timeout and its retry),
 * bootstrap and the GenICam file, stream set-up, the asynchronous transfer
 * pool (submit, reap through libusb's event loop, cancel on stop) and
 * frames assembled byte for byte.
 *
 * Linux only. It must run under umockdev-wrapper (LD_PRELOAD of umockdev's
 * preload library), which ctest does; run directly it skips (exit 77).
 */
#include <dlfcn.h>
#include <errno.h>
#include <linux/usbdevice_fs.h>
#include <sys/ioctl.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

extern "C" {
#include <cmocka.h>
}
#include <umockdev.h>

#include <algorithm>
#include <cstring>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "flatline/flatline.h"
#include "testing/sim_camera.hpp"

using flt::testing::sim_bus;

#define OK(call)                                           \
  do {                                                     \
    flt_status st_ = (call);                               \
    if (st_ != FLT_OK)                                     \
      fail_msg("%s: %s", #call, flt_last_error_message()); \
  } while (0)

namespace {

constexpr std::uint8_t k_ep_control_in = 0x81, k_ep_control_out = 0x01, k_ep_stream = 0x83;
constexpr const char *k_devnode = "/dev/bus/usb/001/002";
constexpr const char *k_vendor = "Flatline Vision", *k_model = "Umockdev-64", *k_serial = "UMD-7";
constexpr std::uint32_t k_width = 64, k_height = 32;

// The pattern the simulated camera sends (flatline/testing.h).
std::uint8_t pattern(std::uint64_t block, std::size_t i) {
    return std::uint8_t(block * 131u + i * 7u + (i >> 9));
}

// The descriptors the kernel would show in sysfs ("descriptors": the
// device descriptor, then the active configuration): a USB3 Vision camera
// as the U3V standard lays it out, with string indices 2 (vendor), 3
// (model) and 7 (serial), as the simulated bus numbers them.
std::string camera_descriptors_hex() {
    std::vector<std::uint8_t> d = {
        18,   1,    0x00, 0x03, 0xEF, 0x02, 0x01, 9,  // bcdUSB 3.0, misc / IAD, ep0 2^9
        0xA7, 0xF1, 0x00, 0x01, 0x00, 0x01,           // vendor F1A7, product 0100, bcdDevice
        2,    3,    7,    1};                         // strings, 1 configuration
    std::vector<std::uint8_t> c = {9, 2, 0, 0, 3, 1, 0, 0xC0, 0};  // total length below
    const std::uint8_t iad[] = {8, 0x0B, 0, 3, 0xEF, 0x05, 0x00, 0};
    c.insert(c.end(), iad, iad + sizeof iad);
    const std::uint8_t control[] = {9, 4, 0, 0, 2, 0xEF, 0x05, 0x00, 0};
    c.insert(c.end(), control, control + sizeof control);
    // the device-info descriptor: GenCP 1.0, U3V 1.0, string indices 1..8
    std::uint8_t info[20] = {20, 0x24, 0x01, 0, 0, 1, 0, 0, 0, 1, 0, 1, 2, 3, 4, 5, 6, 7, 8, 0x0F};
    c.insert(c.end(), info, info + sizeof info);
    const std::uint8_t ep_in[] = {7, 5, k_ep_control_in, 2, 0x00, 0x04, 0};
    const std::uint8_t ep_out[] = {7, 5, k_ep_control_out, 2, 0x00, 0x04, 0};
    c.insert(c.end(), ep_in, ep_in + sizeof ep_in);
    c.insert(c.end(), ep_out, ep_out + sizeof ep_out);
    const std::uint8_t event[] = {9, 4, 1, 0, 1, 0xEF, 0x05, 0x01, 0, 7, 5, 0x82, 2, 0x00, 0x04, 0};
    c.insert(c.end(), event, event + sizeof event);
    const std::uint8_t stream[] = {9, 4, 2, 0,           1, 0xEF, 0x05, 0x02,
                                   0, 7, 5, k_ep_stream, 2, 0x00, 0x04, 0};
    c.insert(c.end(), stream, stream + sizeof stream);
    c[2] = std::uint8_t(c.size());
    c[3] = std::uint8_t(c.size() >> 8);
    d.insert(d.end(), c.begin(), c.end());
    std::string hex;
    char two[3];
    for (std::uint8_t b : d) {
        std::snprintf(two, sizeof two, "%02x", b);
        hex += two;
    }
    return hex;
}

// A keyboard on the same bus: discovery must skip it without opening it.
std::string keyboard_descriptors_hex() {
    const std::uint8_t d[] = {
        18,   1,    0x00, 0x02, 0,    0, 0,    8,    0x6D,
        0x04, 0x1C, 0xC3, 0x00, 0x01, 1, 2,    0,    1,   // device
        9,    2,    34,   0,    1,    1, 0,    0xA0, 50,  // configuration, 34 bytes in all
        9,    4,    0,    0,    1,    3, 1,    1,    0,   // interface: HID boot keyboard
        9,    0x21, 0x11, 0x01, 0,    1, 0x22, 0x3F, 0,   // HID descriptor
        7,    5,    0x81, 3,    8,    0, 10};             // interrupt IN
    std::string hex;
    char two[3];
    for (std::uint8_t b : d) {
        std::snprintf(two, sizeof two, "%02x", b);
        hex += two;
    }
    return hex;
}

// The usbfs side of the emulated camera: URBs libusb submits, answered
// from the simulated camera (its usb_device, driven as the device's side).
struct emulated_camera {
    sim_bus bus;
    std::unique_ptr<flt::u3v::usb_device> dev;
    std::deque<UMockdevIoctlData *> flying;     // submitted, not reaped (in order)
    std::deque<UMockdevIoctlData *> discarded;  // cancelled, reaped with -ENOENT
    std::mutex lock;
    bool stream_held = false;  // the camera sends nothing now (between frames)
    // what went through usbfs
    unsigned submitted = 0, reaped = 0, discards = 0, control_transfers = 0, stream_urbs = 0;
    unsigned unknown_ioctls = 0;
};

emulated_camera *g_cam = nullptr;

std::string string_of(std::uint8_t index) {
    switch (index) {
        case 2:
            return k_vendor;
        case 3:
            return k_model;
        case 4:
            return "Sim";
        case 7:
            return k_serial;
        default:
            return "";
    }
}

// A control transfer on endpoint 0: only GET_DESCRIPTOR (string) is asked
// for. The data goes after the 8 setup bytes; returns the data length, or
// -EPIPE (a stall) for anything else.
int control_transfer(std::uint8_t *buffer, int length) {
    const std::uint8_t type = buffer[0], request = buffer[1], index = buffer[2], kind = buffer[3];
    const int wanted = buffer[6] | (buffer[7] << 8);
    if (type != 0x80 || request != 6 || kind != 3 || length < 8)
        return -EPIPE;
    std::vector<std::uint8_t> s;
    if (index == 0) {
        s = {4, 3, 0x09, 0x04};  // languages: en-US
    } else {
        const std::string text = string_of(index);
        s.push_back(std::uint8_t(2 + 2 * text.size()));
        s.push_back(3);
        for (char ch : text) {
            s.push_back(std::uint8_t(ch));
            s.push_back(0);
        }
    }
    const int n = std::min<int>({int(s.size()), wanted, length - 8});
    std::memcpy(buffer + 8, s.data(), std::size_t(n));
    return n;
}

// Whether the flying URB `urb` can complete now; fills it if so.
bool try_complete(usbdevfs_urb *urb) {
    auto *buffer = static_cast<std::uint8_t *>(urb->buffer);
    if (urb->type == USBDEVFS_URB_TYPE_CONTROL) {
        const int n = control_transfer(buffer, urb->buffer_length);
        urb->status = n < 0 ? n : 0;
        urb->actual_length = n < 0 ? 0 : n;
        ++g_cam->control_transfers;
        return true;
    }
    std::size_t n = 0;
    flt::u3v::usb_status st = flt::u3v::usb_status::ok;
    if (urb->endpoint == k_ep_control_out) {
        st = g_cam->dev->bulk_write(urb->endpoint, buffer, std::size_t(urb->buffer_length), n, 0);
    } else if (urb->endpoint == k_ep_control_in) {
        st = g_cam->dev->bulk_read(urb->endpoint, buffer, std::size_t(urb->buffer_length), n, 0);
        if (st == flt::u3v::usb_status::timeout)
            return false;  // no acknowledge yet: libusb times the transfer out
    } else if (urb->endpoint == k_ep_stream) {
        if (g_cam->stream_held)
            return false;
        // One simulated slot per URB: the camera fills it with USB packet
        // semantics (a short packet ends the transfer).
        std::uint8_t *slot = buffer;
        if (g_cam->dev->async_prepare(k_ep_stream, 1, &slot, std::size_t(urb->buffer_length)) !=
                flt::u3v::usb_status::ok ||
            g_cam->dev->async_submit(0) != flt::u3v::usb_status::ok)
            return false;
        flt::u3v::usb_completion done;
        if (g_cam->dev->async_reap(0, done) != flt::u3v::usb_status::ok)
            return false;  // the camera sends nothing now (not streaming)
        st = done.status;
        n = done.length;
        ++g_cam->stream_urbs;
    } else {
        st = flt::u3v::usb_status::io;
    }
    urb->actual_length = int(n);
    urb->status = st == flt::u3v::usb_status::ok          ? 0
                  : st == flt::u3v::usb_status::overflow  ? -EOVERFLOW
                  : st == flt::u3v::usb_status::no_device ? -ENODEV
                                                          : -EPROTO;
    return true;
}

gboolean on_ioctl(UMockdevIoctlBase *, UMockdevIoctlClient *client, gpointer) {
    std::lock_guard<std::mutex> hold(g_cam->lock);
    const unsigned long request = umockdev_ioctl_client_get_request(client);
    UMockdevIoctlData *arg = umockdev_ioctl_client_get_arg(client);
    switch (request) {
        case USBDEVFS_GET_CAPABILITIES: {
            UMockdevIoctlData *d = umockdev_ioctl_data_resolve(arg, 0, sizeof(guint32), nullptr);
            // one URB per transfer, whatever its size
            *reinterpret_cast<guint32 *>(d->data) =
                USBDEVFS_CAP_NO_PACKET_SIZE_LIM | USBDEVFS_CAP_BULK_CONTINUATION |
                USBDEVFS_CAP_REAP_AFTER_DISCONNECT | USBDEVFS_CAP_ZERO_PACKET;
            umockdev_ioctl_data_unref(d);
            umockdev_ioctl_client_complete(client, 0, 0);
            return TRUE;
        }
        case USBDEVFS_CLAIMINTERFACE:
        case USBDEVFS_RELEASEINTERFACE:
        case USBDEVFS_DISCONNECT_CLAIM:
        case USBDEVFS_CLEAR_HALT:
        case USBDEVFS_RESETEP:
        case USBDEVFS_IOCTL:  // (re)attaching a kernel driver: there is none
            umockdev_ioctl_client_complete(client, 0, 0);
            return TRUE;
        case USBDEVFS_GETDRIVER:
            umockdev_ioctl_client_complete(client, -1, ENODATA);
            return TRUE;
        case USBDEVFS_SUBMITURB: {
            UMockdevIoctlData *urb_data =
                umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_urb), nullptr);
            g_cam->flying.push_back(urb_data);  // the reference is kept
            ++g_cam->submitted;
            umockdev_ioctl_client_complete(client, 0, 0);
            return TRUE;
        }
        case USBDEVFS_REAPURB:
        case USBDEVFS_REAPURBNDELAY: {
            UMockdevIoctlData *done = nullptr;
            if (!g_cam->discarded.empty()) {
                done = g_cam->discarded.front();
                g_cam->discarded.pop_front();
                reinterpret_cast<usbdevfs_urb *>(done->data)->status = -ENOENT;
            } else {
                // the first URB that can complete; on the stream endpoint
                // only its first one (completions come in order there)
                bool stream_seen = false;
                for (auto it = g_cam->flying.begin(); it != g_cam->flying.end(); ++it) {
                    auto *urb = reinterpret_cast<usbdevfs_urb *>((*it)->data);
                    const bool stream = urb->endpoint == k_ep_stream;
                    if (stream && stream_seen)
                        continue;
                    stream_seen = stream_seen || stream;
                    if (try_complete(urb)) {
                        done = *it;
                        g_cam->flying.erase(it);
                        break;
                    }
                }
            }
            if (!done) {
                umockdev_ioctl_client_complete(client, -1, EAGAIN);
                return TRUE;
            }
            UMockdevIoctlData *ptr = umockdev_ioctl_data_resolve(arg, 0, sizeof(gpointer), nullptr);
            umockdev_ioctl_data_set_ptr(ptr, 0, done);
            umockdev_ioctl_data_unref(ptr);
            umockdev_ioctl_data_unref(done);
            ++g_cam->reaped;
            umockdev_ioctl_client_complete(client, 0, 0);
            return TRUE;
        }
        case USBDEVFS_DISCARDURB: {
            void *target = *reinterpret_cast<void **>(arg->data);
            for (auto it = g_cam->flying.begin(); it != g_cam->flying.end(); ++it)
                if ((*it)->client_addr == gulong(reinterpret_cast<std::uintptr_t>(target))) {
                    g_cam->discarded.push_back(*it);
                    g_cam->flying.erase(it);
                    ++g_cam->discards;
                    umockdev_ioctl_client_complete(client, 0, 0);
                    return TRUE;
                }
            umockdev_ioctl_client_complete(client, -1, EINVAL);
            return TRUE;
        }
        default:
            ++g_cam->unknown_ioctls;
            std::fprintf(stderr, "test_u3v_libusb: unhandled usbfs ioctl 0x%lx\n", request);
            return FALSE;
    }
}

UMockdevTestbed *g_testbed = nullptr;
UMockdevIoctlBase *g_handler = nullptr;

int set_up(void **) {
    g_cam = new emulated_camera;
    const std::size_t index =
        g_cam->bus.add_camera(k_vendor, k_model, k_serial, k_width, k_height, 8);
    std::vector<flt::u3v::usb_device_desc> devices;
    if (g_cam->bus.list(devices) != flt::u3v::usb_status::ok)
        return -1;
    for (const auto &d : devices)
        if (d.vendor_id == 0xF1A7 && d.product_id == 0x0100 + index)
            if (g_cam->bus.open(d, g_cam->dev) != flt::u3v::usb_status::ok)
                return -1;
    if (!g_cam->dev)
        return -1;

    g_testbed = umockdev_testbed_new();
    g_handler = UMOCKDEV_IOCTL_BASE(g_object_new(UMOCKDEV_TYPE_IOCTL_BASE, nullptr));
    g_signal_connect(g_handler, "handle-ioctl", G_CALLBACK(on_ioctl), nullptr);
    // The handler first, so the node answers as soon as the device appears.
    if (!umockdev_testbed_attach_ioctl(g_testbed, k_devnode, g_handler, nullptr))
        return -1;
    const std::string camera = std::string("P: /devices/usb1/1-1\n"
                                           "N: bus/usb/001/002\n"
                                           "E: SUBSYSTEM=usb\n"
                                           "E: DEVTYPE=usb_device\n"
                                           "E: DRIVER=usb\n"
                                           "E: BUSNUM=001\n"
                                           "E: DEVNUM=002\n"
                                           "E: DEVNAME=/dev/bus/usb/001/002\n"
                                           "A: busnum=1\\n\n"
                                           "A: devnum=2\\n\n"
                                           "A: speed=5000\\n\n"
                                           "A: bConfigurationValue=1\\n\n"
                                           "H: descriptors=") +
                               camera_descriptors_hex() + "\n\n" +
                               "P: /devices/usb1/1-2\n"
                               "N: bus/usb/001/003\n"
                               "E: SUBSYSTEM=usb\n"
                               "E: DEVTYPE=usb_device\n"
                               "E: DRIVER=usb\n"
                               "E: BUSNUM=001\n"
                               "E: DEVNUM=003\n"
                               "E: DEVNAME=/dev/bus/usb/001/003\n"
                               "A: busnum=1\\n\n"
                               "A: devnum=3\\n\n"
                               "A: speed=12\\n\n"
                               "A: bConfigurationValue=1\\n\n"
                               "H: descriptors=" +
                               keyboard_descriptors_hex() + "\n";
    GError *error = nullptr;
    if (!umockdev_testbed_add_from_string(g_testbed, camera.c_str(), &error)) {
        std::fprintf(stderr, "umockdev: %s\n", error ? error->message : "?");
        return -1;
    }
    return 0;
}

int tear_down(void **) {
    if (g_testbed) {
        umockdev_testbed_detach_ioctl(g_testbed, k_devnode, nullptr);
        g_object_unref(g_handler);
        g_object_unref(g_testbed);
    }
    for (UMockdevIoctlData *d : g_cam->flying)
        umockdev_ioctl_data_unref(d);
    for (UMockdevIoctlData *d : g_cam->discarded)
        umockdev_ioctl_data_unref(d);
    delete g_cam;
    return 0;
}

unsigned counter(std::mutex &m, const unsigned &value) {
    std::lock_guard<std::mutex> hold(m);
    return value;
}

void test_discovery_through_libusb(void **) {
    flt_camera_list *list = nullptr;
    OK(flt_camera_list_create(nullptr, &list));  // NULL: the USB bus, libusb
    std::size_t n = 0;
    OK(flt_camera_list_count(list, &n));
    assert_int_equal(n, 1);  // the keyboard is no camera
    const char *vendor = nullptr, *model = nullptr, *serial = nullptr;
    std::uint32_t speed = 0;
    OK(flt_camera_list_get(list, 0, &vendor, &model, &serial, &speed));
    assert_string_equal(vendor, k_vendor);  // string descriptors over ep 0
    assert_string_equal(model, k_model);
    assert_string_equal(serial, k_serial);
    assert_int_equal(speed, 5000);  // sysfs speed, through libusb_get_device_speed
    flt_camera_list_destroy(list);
    assert_true(counter(g_cam->lock, g_cam->control_transfers) >= 3);
}

void test_control_channel_and_frames_through_libusb(void **) {
    flt_options *o = nullptr;
    OK(flt_options_create(&o));
    // 2048-byte frames in 1024-byte transfers: two payload URBs, the
    // leader and the trailer in URBs of their own.
    OK(flt_options_set(o, FLT_OPT_U3V_TRANSFER_SIZE, 1024));
    OK(flt_options_set(o, FLT_OPT_U3V_TRANSFERS, 4));
    flt_source *src = nullptr;
    OK(flt_source_open_u3v(nullptr, k_serial, o, &src));
    flt_options_destroy(o);

    // bootstrap and GenICam file read over GenCP through libusb
    const char *s = nullptr;
    OK(flt_source_camera_string(src, FLT_CAMERA_MODEL, &s));
    assert_string_equal(s, k_model);
    std::uint64_t v = 0;
    OK(flt_source_camera_value(src, FLT_CAMERA_XML_BYTES, &v));
    assert_true(v > 500);  // the zipped XML: many 1012-byte READMEMs
    OK(flt_source_camera_value(src, FLT_CAMERA_SPEED_MBPS, &v));
    assert_int_equal(v, 5000);
    std::int64_t width = 0;
    OK(flt_source_get_int(src, "Width", &width));
    assert_int_equal(width, k_width);
    OK(flt_source_set_int(src, "Height", k_height));

    // A lost acknowledge: libusb's synchronous read times out (200 ms, the
    // URB is discarded) and the command goes again.
    OK(flt_source_write_memory(src, 0x184, reinterpret_cast<const std::uint8_t *>("umockdev"), 9));
    const unsigned discards = counter(g_cam->lock, g_cam->discards);
    {
        std::lock_guard<std::mutex> hold(g_cam->lock);
        flt::testing::sim_inject(g_cam->bus.camera(0), FLT_U3V_FAULT_CONTROL_TIMEOUT, 0, 1);
    }
    char name[9] = {0};
    OK(flt_source_read_memory(src, 0x184, name, 9));
    assert_string_equal(name, "umockdev");
    OK(flt_source_count(src, FLT_COUNT_COMMAND_RETRIES, &v));
    assert_int_equal(v, 1);
    assert_int_equal(counter(g_cam->lock, g_cam->discards), discards + 1);

    // A few frames through the asynchronous pool, byte for byte.
    OK(flt_source_start(src));
    for (std::uint64_t k = 1; k <= 20; ++k) {
        const flt_frame *f = nullptr;
        OK(flt_source_next(src, 2000, &f));
        const void *pixels = nullptr;
        std::uint32_t w = 0, h = 0;
        std::size_t stride = 0;
        std::uint64_t block = 0;
        OK(flt_frame_info(f, &pixels, &w, &h, &stride, nullptr, &block, nullptr, nullptr));
        assert_int_equal(block, k);
        assert_int_equal(w, k_width);
        assert_int_equal(h, k_height);
        const auto *p = static_cast<const std::uint8_t *>(pixels);
        for (std::size_t i = 0; i < std::size_t(k_width) * k_height; ++i)
            if (p[i] != pattern(k, i))
                fail_msg("frame %llu byte %zu: %u, expected %u", (unsigned long long)k, i, p[i],
                         pattern(k, i));
    }
    OK(flt_source_count(src, FLT_COUNT_FRAMES, &v));
    assert_int_equal(v, 20);
    OK(flt_source_count(src, FLT_COUNT_DROPPED, &v));
    assert_int_equal(v, 0);
    // Stop while the camera is between frames (it holds its next one), so
    // that stream transfers are in flight: stop sends AcquisitionStop and SI
    // control 0, and cancels those transfers through libusb (DISCARDURB,
    // reaped as cancelled). Without the hold the camera would fill every
    // transfer while stop's control transfers run libusb's event loop, and
    // nothing would be left to cancel.
    unsigned before_stop = 0, stream_flying = 0;
    {
        std::lock_guard<std::mutex> hold(g_cam->lock);
        g_cam->stream_held = true;
        before_stop = g_cam->discards;
    }
    // With nothing coming, the pool puts every transfer in flight.
    const flt_frame *none = nullptr;
    assert_int_equal(flt_source_next(src, 300, &none), FLT_ERR_TIMEOUT);
    {
        std::lock_guard<std::mutex> hold(g_cam->lock);
        for (UMockdevIoctlData *d : g_cam->flying)
            if (reinterpret_cast<usbdevfs_urb *>(d->data)->endpoint == k_ep_stream)
                ++stream_flying;
    }
    std::printf("stream transfers in flight at stop: %u\n", stream_flying);
    assert_int_equal(stream_flying, 4);  // FLT_OPT_U3V_TRANSFERS
    OK(flt_source_stop(src));
    {
        std::lock_guard<std::mutex> hold(g_cam->lock);
        assert_int_equal(g_cam->discards, before_stop + stream_flying);
        assert_true(g_cam->flying.empty());     // nothing left with the "device"
        assert_true(g_cam->discarded.empty());  // every cancelled URB reaped
        assert_int_equal(g_cam->submitted, g_cam->reaped);
        g_cam->stream_held = false;
    }
    std::uint32_t si = 1;
    {
        std::lock_guard<std::mutex> hold(g_cam->lock);
        assert_true(flt::testing::sim_peek(g_cam->bus.camera(0), 0x2004, si));
    }
    assert_int_equal(si, 0);
    flt_source_destroy(src);

    std::lock_guard<std::mutex> hold(g_cam->lock);
    std::printf("through usbfs: %u URBs submitted, %u reaped, %u discarded, %u stream URBs, "
                "%u control transfers, %u ioctls not handled\n",
                g_cam->submitted, g_cam->reaped, g_cam->discards, g_cam->stream_urbs,
                g_cam->control_transfers, g_cam->unknown_ioctls);
    assert_true(g_cam->stream_urbs >= 20 * 4);  // leader, 2 payload, trailer each
    assert_int_equal(g_cam->unknown_ioctls, 0);
}

}  // namespace

int main() {
    // umockdev's preload library must be in the process (LD_PRELOAD): it is
    // what redirects sysfs and the usbfs node to the test bed.
    // (umockdev_in_mock_environment() is not used: in Debian 12's umockdev
    // 0.17 it answers false even under umockdev-wrapper.)
    void *preload = dlopen("libumockdev-preload.so.0", RTLD_NOW | RTLD_NOLOAD);
    if (!preload) {
        std::printf("SKIP: run under umockdev-wrapper (it emulates usbfs for libusb)\n");
        return 77;
    }
    dlclose(preload);
    const CMUnitTest tests[] = {
        cmocka_unit_test(test_discovery_through_libusb),
        cmocka_unit_test(test_control_channel_and_frames_through_libusb),
    };
    return cmocka_run_group_tests(tests, set_up, tear_down);
}
