// SPDX-License-Identifier: Apache-2.0
// The USB3 Vision client over the transport interface.
#include "sources/u3v/camera.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <limits>

#include "core/error.hpp"
#include "sources/u3v/protocol.hpp"

namespace flt::u3v {

namespace {

[[noreturn]] void raise(flt_status status, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
void raise(flt_status status, const char *format, ...) {
    char text[400];
    va_list args;
    va_start(args, format);
    std::vsnprintf(text, sizeof text, format, args);
    va_end(args);
    throw error(status, text);
}

const char *command_name(std::uint16_t command) {
    return command == k_cmd_readmem ? "READMEM" : "WRITEMEM";
}

std::uint64_t align_up(std::uint64_t v, std::uint64_t a) {
    return (v + a - 1) / a * a;
}

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
        }
        out.push_back(std::move(e));
    }
    return out;
}

camera::camera(usb_backend &bus, const char *serial, const camera_config &config)
    : config_(config) {
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
    speed_mbps_ = chosen->desc.speed_mbps;
    if (!endpoint_of(*layout.control, true, ep_control_in_) ||
        !endpoint_of(*layout.control, false, ep_control_out_))
        raise(FLT_ERR_DEVICE,
              "camera '%s': its control interface lacks a bulk IN or OUT "
              "endpoint",
              chosen->serial.c_str());
    if (layout.stream && !endpoint_of(*layout.stream, true, ep_stream_))
        raise(FLT_ERR_DEVICE, "camera '%s': its stream interface lacks a bulk IN endpoint",
              chosen->serial.c_str());
    usb_status st = bus.open(chosen->desc, dev_);
    if (st != usb_status::ok)
        raise(FLT_ERR_DEVICE, "camera '%s' cannot be opened: %s", chosen->serial.c_str(),
              usb_status_name(st));
    if_control_ = layout.control->number;
    st = dev_->claim_interface(if_control_);
    if (st != usb_status::ok)
        raise(FLT_ERR_DEVICE, "camera '%s': cannot claim its control interface: %s",
              chosen->serial.c_str(), usb_status_name(st));
    if (layout.stream) {
        if_stream_ = layout.stream->number;
        st = dev_->claim_interface(if_stream_);
        if (st != usb_status::ok)
            raise(FLT_ERR_DEVICE, "camera '%s': cannot claim its stream interface: %s",
                  chosen->serial.c_str(), usb_status_name(st));
    }
    timeout_ms_ = std::max(config_.control_timeout_floor_ms, 1u);
    bootstrap();
    load_xml();
    recover_stream();
}

camera::~camera() {
    stop();
    if (dev_ && !disconnected_) {
        if (if_stream_ >= 0)
            dev_->release_interface(if_stream_);
        if (if_control_ >= 0)
            dev_->release_interface(if_control_);
    }
}

void camera::lost_device(const char *what) {
    if (!disconnected_)
        ++counters_[FLT_COUNT_DISCONNECTS];
    disconnected_ = true;
    raise(FLT_ERR_DEVICE, "the camera was unplugged (%s)", what);
}

// --- GenCP -------------------------------------------------------------------

void camera::transact(std::uint16_t command, const std::uint8_t *body, std::size_t body_bytes,
                      std::uint8_t *ack_body, std::size_t ack_bytes, std::uint64_t address) {
    if (disconnected_)
        raise(FLT_ERR_DEVICE, "the camera was unplugged");
    command_buffer_.resize(k_gencp_header + body_bytes);
    ack_buffer_.resize(std::max<std::size_t>(max_ack_, k_gencp_header + 8));
    const std::uint16_t expected_ack = std::uint16_t(command + 1);
    for (unsigned attempt = 0; attempt < config_.command_attempts; ++attempt) {
        if (attempt > 0)
            ++counters_[FLT_COUNT_COMMAND_RETRIES];
        // Request ids increase and wrap without 0; an ack carrying an older
        // id answers an earlier attempt and is discarded below.
        request_id_ = std::uint16_t(request_id_ + 1);
        if (request_id_ == 0)
            request_id_ = 1;
        std::uint8_t *c = command_buffer_.data();
        put_u32(c, k_prefix_control);
        put_u16(c + 4, k_flag_request_ack);
        put_u16(c + 6, command);
        put_u16(c + 8, std::uint16_t(body_bytes));
        put_u16(c + 10, request_id_);
        std::memcpy(c + k_gencp_header, body, body_bytes);
        std::size_t sent = 0;
        usb_status st =
            dev_->bulk_write(ep_control_out_, c, command_buffer_.size(), sent, timeout_ms_);
        if (st == usb_status::no_device)
            lost_device("control channel");
        if (st == usb_status::timeout)
            continue;
        if (st != usb_status::ok)
            raise(FLT_ERR_DEVICE, "%s at 0x%llx: sending the command failed: %s",
                  command_name(command), (unsigned long long)address, usb_status_name(st));
        auto deadline = clock::now() + std::chrono::milliseconds(timeout_ms_);
        unsigned pending = 0;
        for (;;) {
            // Whole milliseconds, rounded up: the first read waits the full
            // timeout, a late one at least 1 ms.
            const auto left_us =
                std::chrono::duration_cast<std::chrono::microseconds>(deadline - clock::now())
                    .count();
            const unsigned wait = unsigned(std::max<long long>(1, (left_us + 999) / 1000));
            std::size_t n = 0;
            st = dev_->bulk_read(ep_control_in_, ack_buffer_.data(), ack_buffer_.size(), n, wait);
            if (st == usb_status::no_device)
                lost_device("control channel");
            if (st == usb_status::timeout)
                break;  // retry with a new request id
            if (st != usb_status::ok)
                raise(FLT_ERR_DEVICE, "%s at 0x%llx: reading the acknowledge failed: %s",
                      command_name(command), (unsigned long long)address, usb_status_name(st));
            const std::uint8_t *a = ack_buffer_.data();
            if (n < k_gencp_header || get_u32(a) != k_prefix_control ||
                get_u16(a + 8) != n - k_gencp_header) {
                ++counters_[FLT_COUNT_STALE_ACKS];  // not an acknowledge: skip it
                continue;
            }
            const std::uint16_t status = get_u16(a + 4), ack_id = get_u16(a + 6);
            if (get_u16(a + 10) != request_id_) {
                ++counters_[FLT_COUNT_STALE_ACKS];
                continue;
            }
            if (ack_id == k_ack_pending) {
                ++counters_[FLT_COUNT_PENDING_ACKS];
                if (++pending > config_.pending_ack_limit)
                    raise(FLT_ERR_TIMEOUT,
                          "%s at 0x%llx: the camera sent %u pending acks, "
                          "more than the limit of %u",
                          command_name(command), (unsigned long long)address, pending,
                          config_.pending_ack_limit);
                const unsigned more = n >= k_gencp_header + 4 ? get_u16(a + 14) : 0;
                deadline = clock::now() + std::chrono::milliseconds(std::max(more, timeout_ms_));
                continue;
            }
            if (ack_id != expected_ack)
                raise(FLT_ERR_FORMAT,
                      "%s at 0x%llx: the camera answered with ack id 0x%04x, "
                      "expected 0x%04x",
                      command_name(command), (unsigned long long)address, ack_id, expected_ack);
            if (status != gencp_ok)
                raise(status == gencp_busy ? FLT_ERR_TIMEOUT : FLT_ERR_DEVICE,
                      "%s of %zu bytes at 0x%llx: the camera answered status 0x%04x (%s)",
                      command_name(command), command == k_cmd_readmem ? ack_bytes : body_bytes - 8,
                      (unsigned long long)address, status, gencp_status_name(status));
            const std::size_t got = n - k_gencp_header;
            if (command == k_cmd_readmem && got != ack_bytes)
                raise(FLT_ERR_FORMAT,
                      "READMEM at 0x%llx: the camera returned %zu bytes, "
                      "asked for %zu",
                      (unsigned long long)address, got, ack_bytes);
            if (command == k_cmd_writemem && (got < 4 || get_u16(a + 14) != body_bytes - 8))
                raise(FLT_ERR_FORMAT, "WRITEMEM at 0x%llx: the camera wrote %u of %zu bytes",
                      (unsigned long long)address, got >= 4 ? get_u16(a + 14) : 0u, body_bytes - 8);
            if (ack_body && ack_bytes)
                std::memcpy(ack_body, a + k_gencp_header, ack_bytes);
            return;
        }
    }
    raise(FLT_ERR_TIMEOUT, "%s at 0x%llx: no acknowledge within %u ms in %u attempts",
          command_name(command), (unsigned long long)address, timeout_ms_,
          config_.command_attempts);
}

void camera::read_memory(std::uint64_t address, std::uint8_t *out, std::size_t bytes) {
    // An ack carries the header and the data; the count field is 16 bits.
    const std::size_t chunk = std::min<std::size_t>(max_ack_ - k_gencp_header, 0xFFFF);
    std::uint8_t body[k_readmem_body];
    for (std::size_t done = 0; done < bytes;) {
        const std::size_t n = std::min(chunk, bytes - done);
        put_u64(body, address + done);
        put_u16(body + 8, 0);
        put_u16(body + 10, std::uint16_t(n));
        transact(k_cmd_readmem, body, sizeof body, out + done, n, address + done);
        done += n;
    }
}

void camera::write_memory(std::uint64_t address, const std::uint8_t *in, std::size_t bytes) {
    const std::size_t chunk = std::min<std::size_t>(max_command_ - k_writemem_overhead, 0xFFFF);
    std::vector<std::uint8_t> body(8 + std::min(chunk, bytes));
    for (std::size_t done = 0; done < bytes;) {
        const std::size_t n = std::min(chunk, bytes - done);
        put_u64(body.data(), address + done);
        std::memcpy(body.data() + 8, in + done, n);
        transact(k_cmd_writemem, body.data(), 8 + n, nullptr, 0, address + done);
        done += n;
    }
}

// --- bootstrap ------------------------------------------------------------------

void camera::bootstrap() {
    // The transfer limits are unknown until SBRM is read: read them with
    // 8-byte requests first, which every GenCP device accepts.
    std::uint8_t b[8];
    read_memory(abrm::sbrm_address, b, 8);
    sbrm_address_ = get_u64(b);
    read_memory(sbrm_address_ + sbrm::max_command, b, 8);
    if (get_u32(b) >= k_writemem_overhead + 4 && get_u32(b + 4) >= k_gencp_header + 4) {
        max_command_ = get_u32(b);
        max_ack_ = get_u32(b + 4);
    }
    std::uint8_t s[sbrm::size];
    read_memory(sbrm_address_, s, sizeof s);
    u3v_version_ = get_u32(s + sbrm::u3v_version);
    const std::uint32_t max_command = get_u32(s + sbrm::max_command);
    const std::uint32_t max_ack = get_u32(s + sbrm::max_ack);
    if (max_command < k_writemem_overhead + 4 || max_ack < k_gencp_header + 4)
        raise(FLT_ERR_FORMAT,
              "SBRM: max command transfer %u / max ack transfer %u bytes are "
              "too small for GenCP",
              max_command, max_ack);
    max_command_ = max_command;
    max_ack_ = max_ack;
    sirm_address_ = get_u64(s + sbrm::sirm_address);
    if (get_u32(s + sbrm::stream_channels) == 0)
        sirm_address_ = 0;

    std::vector<std::uint8_t> a(abrm::size);
    read_memory(0, a.data(), a.size());
    gencp_version_ = get_u32(&a[abrm::gencp_version]);
    const std::uint64_t where[7] = {
        abrm::manufacturer,      abrm::model,  abrm::family,   abrm::device_version,
        abrm::manufacturer_info, abrm::serial, abrm::user_name};
    for (int i = 0; i < 7; ++i) {
        const char *text = reinterpret_cast<const char *>(&a[where[i]]);
        strings_[i].assign(text, strnlen(text, abrm::string_length));
    }
    response_ms_ = get_u32(&a[abrm::response_time]);
    manifest_address_ = get_u64(&a[abrm::manifest_address]);
    timeout_ms_ = std::max(config_.control_timeout_floor_ms, response_ms_);
}

void camera::load_xml() {
    std::uint8_t head[8];
    read_memory(manifest_address_, head, 8);
    const std::uint64_t entries = get_u64(head);
    if (entries == 0 || entries > 64)
        raise(FLT_ERR_FORMAT, "the manifest table at 0x%llx has %llu entries",
              (unsigned long long)manifest_address_, (unsigned long long)entries);
    // The first entry of a known file type (0 raw XML, 1 ZIP).
    for (std::uint64_t i = 0; i < entries; ++i) {
        std::uint8_t e[64];
        read_memory(manifest_address_ + 8 + 64 * i, e, 64);
        const std::uint32_t type = (get_u32(e + 4) >> 10) & 0x3F;
        const std::uint64_t address = get_u64(e + 8), size = get_u64(e + 16);
        if (type > 1)
            continue;
        if (size == 0 || size > (64u << 20))
            raise(FLT_ERR_FORMAT, "manifest entry %llu: GenICam file size %llu bytes",
                  (unsigned long long)i, (unsigned long long)size);
        std::vector<std::uint8_t> file(size);
        read_memory(address, file.data(), file.size());
        xml_bytes_ = size;
        xml_zipped_ = type == 1;
        const std::string text =
            xml_zipped_ ? unzip_single(file.data(), file.size())
                        : std::string(reinterpret_cast<const char *>(file.data()), file.size());
        xml_.parse(text);
        return;
    }
    raise(FLT_ERR_FORMAT, "the manifest lists no GenICam XML or ZIP file");
}

void camera::recover_stream() {
    if (sirm_address_ == 0)
        return;
    std::uint8_t b[4];
    read_memory(sirm_address_ + sirm::control, b, 4);
    if (!(get_u32(b) & sirm::control_enable))
        return;
    // A process died while streaming: stop the camera so it accepts a
    // new stream set-up. Either step may fail on a confused device; the
    // SI control reset is what matters.
    ++counters_[FLT_COUNT_STREAM_RECOVERIES];
    try {
        execute("AcquisitionStop");
    } catch (const error &) {
    }
    put_u32(b, 0);
    write_memory(sirm_address_ + sirm::control, b, 4);
    if (ep_stream_)
        dev_->clear_halt(ep_stream_);
}

// --- features ----------------------------------------------------------------------

const std::string &camera::string_of(flt_camera_string which) const {
    return strings_[std::size_t(which)];
}

std::uint64_t camera::value_of(flt_camera_value which) const {
    switch (which) {
        case FLT_CAMERA_GENCP_VERSION:
            return gencp_version_;
        case FLT_CAMERA_U3V_VERSION:
            return u3v_version_;
        case FLT_CAMERA_RESPONSE_TIME_MS:
            return response_ms_;
        case FLT_CAMERA_CONTROL_TIMEOUT_MS:
            return timeout_ms_;
        case FLT_CAMERA_MAX_COMMAND_BYTES:
            return max_command_;
        case FLT_CAMERA_MAX_ACK_BYTES:
            return max_ack_;
        case FLT_CAMERA_SIRM_ADDRESS:
            return sirm_address_;
        case FLT_CAMERA_MANIFEST_ADDRESS:
            return manifest_address_;
        case FLT_CAMERA_XML_BYTES:
            return xml_bytes_;
        case FLT_CAMERA_XML_ZIPPED:
            return xml_zipped_;
        case FLT_CAMERA_SPEED_MBPS:
            return speed_mbps_;
        case FLT_CAMERA_ALIGNMENT:
            return alignment_;
        case FLT_CAMERA_PAYLOAD_BYTES:
            return payload_bytes_;
        case FLT_CAMERA_TRANSFER_BYTES:
            return transfer_bytes_;
        case FLT_CAMERA_TRANSFER_COUNT:
            return transfer_count_;
        case FLT_CAMERA_FINAL_TRANSFER_BYTES:
            return final1_bytes_;
        case FLT_CAMERA_MAX_LEADER_BYTES:
            return max_leader_;
        case FLT_CAMERA_MAX_TRAILER_BYTES:
            return max_trailer_;
        default:
            break;
    }
    raise(FLT_ERR_INVALID_ARGUMENT, "argument 'which' = %d is no camera value", int(which));
}

feature_access camera::access(const std::string &feature) const {
    auto it = mapped_.find(feature);
    if (it != mapped_.end())
        return it->second;
    return xml_.resolve(feature);
}

std::uint64_t camera::read_register(const feature_access &a) {
    std::uint8_t b[8] = {0};
    read_memory(a.address, b, a.length);
    if (!a.little_endian)
        std::reverse(b, b + a.length);
    std::uint64_t raw = get_uint(b, a.length);
    const int width = a.msb - a.lsb + 1;
    raw >>= a.lsb;
    if (width < 64)
        raw &= (std::uint64_t(1) << width) - 1;
    return raw;
}

void camera::write_register(const feature_access &a, std::uint64_t raw) {
    std::uint8_t b[8] = {0};
    const int width = a.msb - a.lsb + 1;
    const bool whole = a.lsb == 0 && width == int(8 * a.length);
    std::uint64_t word = 0;
    if (!whole) {
        // read-modify-write of a bit field
        read_memory(a.address, b, a.length);
        if (!a.little_endian)
            std::reverse(b, b + a.length);
        word = get_uint(b, a.length);
        const std::uint64_t mask = (width < 64 ? (std::uint64_t(1) << width) - 1 : ~0ull) << a.lsb;
        word = (word & ~mask) | ((raw << a.lsb) & mask);
    } else {
        word = raw;
    }
    put_uint(b, a.length, word);
    if (!a.little_endian)
        std::reverse(b, b + a.length);
    write_memory(a.address, b, a.length);
}

std::int64_t camera::get_int(const std::string &feature) {
    const feature_access a = access(feature);
    if (a.kind == feature_access::constant)
        return a.constant_value;
    if (a.kind == feature_access::float_register)
        return std::int64_t(std::llround(get_float(feature)));
    std::uint64_t raw = read_register(a);
    const int width = a.msb - a.lsb + 1;
    if (a.is_signed && width < 64 && (raw >> (width - 1)) & 1)
        raw |= ~0ull << width;
    return std::int64_t(raw);
}

void camera::set_int(const std::string &feature, std::int64_t value) {
    const feature_access a = access(feature);
    if (a.kind == feature_access::constant)
        raise(FLT_ERR_INVALID_ARGUMENT, "feature '%s' is a constant (%lld) and cannot be set",
              feature.c_str(), (long long)a.constant_value);
    if (a.kind == feature_access::float_register)
        return set_float(feature, double(value));
    const int width = a.msb - a.lsb + 1;
    if (width < 64) {
        const std::int64_t lo = a.is_signed ? -(std::int64_t(1) << (width - 1)) : 0;
        const std::int64_t hi = a.is_signed ? (std::int64_t(1) << (width - 1)) - 1
                                            : std::int64_t((std::uint64_t(1) << width) - 1);
        if (value < lo || value > hi)
            raise(FLT_ERR_INVALID_ARGUMENT,
                  "feature '%s': value %lld does not fit its %d-bit "
                  "register",
                  feature.c_str(), (long long)value, width);
    }
    write_register(a, std::uint64_t(value));
}

double camera::get_float(const std::string &feature) {
    const feature_access a = access(feature);
    if (a.kind == feature_access::constant)
        return a.constant_float;
    if (a.kind == feature_access::int_register)
        return double(get_int(feature));
    std::uint8_t b[8] = {0};
    read_memory(a.address, b, a.length);
    if (!a.little_endian)
        std::reverse(b, b + a.length);
    if (a.length == 4) {
        float f;
        const std::uint32_t bits = get_u32(b);
        std::memcpy(&f, &bits, 4);
        return f;
    }
    double d;
    const std::uint64_t bits = get_u64(b);
    std::memcpy(&d, &bits, 8);
    return d;
}

void camera::set_float(const std::string &feature, double value) {
    if (!std::isfinite(value))
        raise(FLT_ERR_INVALID_ARGUMENT, "feature '%s': value %g is not finite", feature.c_str(),
              value);
    const feature_access a = access(feature);
    if (a.kind == feature_access::constant)
        raise(FLT_ERR_INVALID_ARGUMENT, "feature '%s' is a constant and cannot be set",
              feature.c_str());
    if (a.kind == feature_access::int_register) {
        if (std::fabs(value) > 9.0e18)
            raise(FLT_ERR_INVALID_ARGUMENT, "feature '%s': value %g is out of range",
                  feature.c_str(), value);
        return set_int(feature, std::llround(value));
    }
    std::uint8_t b[8] = {0};
    if (a.length == 4) {
        // Converting a double beyond float's range is undefined behaviour.
        if (std::fabs(value) > double(std::numeric_limits<float>::max()))
            raise(FLT_ERR_INVALID_ARGUMENT,
                  "feature '%s': value %g is out of the range of its "
                  "32-bit float register",
                  feature.c_str(), value);
        const float f = float(value);
        std::uint32_t bits;
        std::memcpy(&bits, &f, 4);
        put_u32(b, bits);
    } else {
        std::uint64_t bits;
        std::memcpy(&bits, &value, 8);
        put_u64(b, bits);
    }
    if (!a.little_endian)
        std::reverse(b, b + a.length);
    write_memory(a.address, b, a.length);
}

void camera::set_enum(const std::string &feature, const std::string &entry) {
    const feature_access a = access(feature);
    const genicam_node *n = a.node;
    if (mapped_.count(feature) || !n || n->kind != "Enumeration")
        raise(FLT_ERR_INVALID_ARGUMENT,
              "feature '%s' is not an XML Enumeration; set its "
              "integer value with flt_source_set_int()",
              feature.c_str());
    for (const auto &e : n->entries)
        if (e.first == entry)
            return set_int(feature, e.second);
    std::string names;
    for (const auto &e : n->entries)
        names += (names.empty() ? "" : ", ") + e.first;
    raise(FLT_ERR_NOT_FOUND, "feature '%s' has no entry '%.64s' (entries: %.200s)", feature.c_str(),
          entry.c_str(), names.c_str());
}

void camera::execute(const std::string &feature) {
    const feature_access a = access(feature);
    std::int64_t value = 1;
    if (!mapped_.count(feature)) {
        if (!a.node || a.node->kind != "Command")
            raise(FLT_ERR_INVALID_ARGUMENT, "feature '%s' is a %s, not a Command", feature.c_str(),
                  a.node ? a.node->kind.c_str() : "constant");
        if (!a.node->p_command_value.empty())
            value = get_int(a.node->p_command_value);
        else
            value = a.node->command_value;
    }
    set_int(feature, value);
}

void camera::map_feature(const std::string &feature, std::uint64_t address, std::uint32_t length,
                         bool is_float) {
    feature_access a;
    a.kind = is_float ? feature_access::float_register : feature_access::int_register;
    a.address = address;
    a.length = length;
    a.lsb = 0;
    a.msb = int(8 * length) - 1;
    mapped_[feature] = a;
}

// --- streaming -----------------------------------------------------------------------

void camera::start() {
    if (streaming_)
        raise(FLT_ERR_STATE, "the camera is already streaming");
    if (disconnected_)
        raise(FLT_ERR_DEVICE, "the camera was unplugged");
    if (sirm_address_ == 0 || ep_stream_ == 0)
        raise(FLT_ERR_DEVICE, "the camera has no stream channel (SBRM lists 0)");
    {
        const feature_access mode = access("AcquisitionMode");
        if (mapped_.count("AcquisitionMode"))
            set_int("AcquisitionMode", 0);
        else if (mode.node && mode.node->kind == "Enumeration")
            set_enum("AcquisitionMode", "Continuous");
    }
    width_ = std::uint32_t(get_int("Width"));
    height_ = std::uint32_t(get_int("Height"));
    const std::uint32_t pfnc = std::uint32_t(get_int("PixelFormat"));
    bits_ = pfnc_bits(pfnc);
    if (bits_ == 0)
        raise(FLT_ERR_FORMAT,
              "PixelFormat 0x%08x is not Mono8, Mono10, Mono12 or Mono16 "
              "(unpacked); set one with flt_source_set_enum()",
              pfnc);

    std::uint8_t s[sirm::size];
    read_memory(sirm_address_, s, sizeof s);
    const std::uint32_t shift = get_u32(s + sirm::info) >> 24;
    if (shift > 20)
        raise(FLT_ERR_FORMAT, "SIRM: alignment 2^%u bytes", shift);
    alignment_ = 1u << shift;
    payload_bytes_ = get_u64(s + sirm::required_payload);
    const std::uint32_t leader = get_u32(s + sirm::required_leader);
    required_trailer_ = get_u32(s + sirm::required_trailer);
    if (payload_bytes_ == 0 || payload_bytes_ > (std::uint64_t(1) << 31))
        raise(FLT_ERR_FORMAT, "SIRM: required payload size %llu bytes",
              (unsigned long long)payload_bytes_);
    if (leader < k_leader_image_size || required_trailer_ < k_trailer_min_size)
        raise(FLT_ERR_FORMAT, "SIRM: leader %u / trailer %u bytes are below the U3V minimum",
              leader, required_trailer_);
    image_bytes_ = std::size_t(width_) * (bits_ > 8 ? 2 : 1) * height_;
    if (payload_bytes_ < image_bytes_)
        raise(FLT_ERR_FORMAT, "SIRM: payload %llu bytes is less than Width x Height = %u x %u",
              (unsigned long long)payload_bytes_, width_, height_);
    // The transfer size: a multiple of the alignment, at most the option.
    const std::uint64_t cap =
        std::max<std::uint64_t>(alignment_, config_.max_transfer_bytes / alignment_ * alignment_);
    std::uint64_t size = std::min<std::uint64_t>(cap, payload_bytes_ / alignment_ * alignment_);
    if (size == 0)
        size = alignment_;
    transfer_bytes_ = std::uint32_t(size);
    transfer_count_ = std::uint32_t(payload_bytes_ / size);
    final1_bytes_ = std::uint32_t(align_up(payload_bytes_ % size, alignment_));
    max_leader_ = std::uint32_t(align_up(leader, alignment_));
    max_trailer_ = std::uint32_t(align_up(required_trailer_, alignment_));
    std::uint8_t w[4];
    const std::pair<std::uint64_t, std::uint32_t> set_up[] = {
        {sirm::max_leader, max_leader_},
        {sirm::transfer_size, transfer_bytes_},
        {sirm::transfer_count, transfer_count_},
        {sirm::final1_size, final1_bytes_},
        {sirm::final2_size, 0},
        {sirm::max_trailer, max_trailer_}};
    for (const auto &r : set_up) {
        put_u32(w, r.second);
        write_memory(sirm_address_ + r.first, w, 4);
    }

    // Host buffers: one size fits every transfer (a leader, a payload
    // transfer, the final one or a trailer), in one block.
    slot_bytes_ = std::max({std::size_t(transfer_bytes_), std::size_t(final1_bytes_),
                            std::size_t(max_leader_), std::size_t(max_trailer_)});
    const std::size_t slots = std::max<std::size_t>(2, config_.transfers);
    pool_.assign(slots * slot_bytes_, 0);
    slot_buffers_.resize(slots);
    for (std::size_t i = 0; i < slots; ++i)
        slot_buffers_[i] = pool_.data() + i * slot_bytes_;
    frame_.assign(std::size_t(payload_bytes_) + alignment_, 0);
    waiting_.clear();
    in_flight_ = 0;
    frame_open_ = frame_damaged_ = false;
    discarding_ = true;  // until the first leader
    have_last_block_ = false;

    usb_status st = dev_->clear_halt(ep_stream_);
    if (st == usb_status::no_device)
        lost_device("stream set-up");
    st = dev_->async_prepare(ep_stream_, slots, slot_buffers_.data(), slot_bytes_);
    if (st != usb_status::ok)
        raise(FLT_ERR_DEVICE, "cannot prepare %zu bulk transfers: %s", slots, usb_status_name(st));
    for (std::size_t i = 0; i < slots; ++i)
        waiting_.push_back(1);
    submit_waiting();
    if (in_flight_ == 0) {
        dev_->async_release();
        raise(FLT_ERR_DEVICE,
              "no bulk transfer of %zu bytes could be submitted (on Linux, "
              "usbfs memory: raise /sys/module/usbcore/parameters/usbfs_memory_mb "
              "or lower u3v_transfers)",
              slot_bytes_);
    }
    put_u32(w, sirm::control_enable);
    write_memory(sirm_address_ + sirm::control, w, 4);
    execute("AcquisitionStart");
    streaming_ = true;
}

void camera::stop() noexcept {
    if (!streaming_)
        return;
    streaming_ = false;
    if (!disconnected_) {
        try {
            execute("AcquisitionStop");
        } catch (...) {
        }
        try {
            std::uint8_t w[4] = {0, 0, 0, 0};
            write_memory(sirm_address_ + sirm::control, w, 4);
        } catch (...) {
        }
    }
    dev_->async_release();
    in_flight_ = 0;
    waiting_.clear();
    frame_open_ = false;
    if (!disconnected_)
        dev_->clear_halt(ep_stream_);
}

void camera::drop(flt_source_counter reason, const std::string &why) {
    ++counters_[reason];
    ++counters_[FLT_COUNT_DROPPED];
    stream_error_ = why;
    frame_open_ = false;
    frame_damaged_ = false;
    discarding_ = true;  // the rest of this frame, if any, is not garbage
}

void camera::submit_waiting() {
    for (std::size_t slot = 0; slot < waiting_.size(); ++slot) {
        if (!waiting_[slot])
            continue;
        const usb_status st = dev_->async_submit(slot);
        if (st == usb_status::ok) {
            waiting_[slot] = 0;
            ++in_flight_;
            continue;
        }
        if (st == usb_status::no_device)
            lost_device("stream");
        // Refused (usbfs memory on Linux): while fewer transfers wait, the
        // camera may send data nobody receives, so the frame in progress,
        // or the next one, cannot be trusted.
        ++counters_[FLT_COUNT_SUBMIT_REFUSED];
        stream_error_ =
            std::string("a bulk transfer submission was refused: ") + usb_status_name(st);
        frame_damaged_ = true;  // the open frame, or the next one to open
    }
}

void camera::resubmit(std::size_t slot) {
    waiting_[slot] = 1;
    submit_waiting();
}

std::size_t camera::merged_trailer_at(const std::uint8_t *p, std::size_t n) const {
    // A final transfer that is a whole number of packets does not end the
    // host's transfer, so the trailer can arrive in the same buffer.
    const std::size_t sizes[3] = {required_trailer_, k_trailer_min_size, max_trailer_};
    for (std::size_t t : sizes)
        if (n > t && get_u32(p + n - t) == k_magic_trailer && get_u64(p + n - t + 8) == block_id_)
            return n - t;
    return n;
}

bool camera::on_leader(const std::uint8_t *p, std::size_t n) {
    const std::uint64_t block = get_u64(p + 8);
    if (frame_open_) {
        char text[200];
        std::snprintf(text, sizeof text,
                      "block %llu: a new leader (block %llu) arrived after "
                      "%zu of its payload bytes; dropped",
                      (unsigned long long)block_id_, (unsigned long long)block, received_);
        const bool damaged = frame_damaged_;
        drop(FLT_COUNT_INCOMPLETE, text);
        frame_damaged_ = damaged;
    }
    if (have_last_block_ && block > last_block_ + 1) {
        counters_[FLT_COUNT_LOST] += block - last_block_ - 1;
        char text[160];
        std::snprintf(text, sizeof text, "block ids %llu..%llu never arrived (lost)",
                      (unsigned long long)(last_block_ + 1), (unsigned long long)(block - 1));
        stream_error_ = text;
    }
    last_block_ = block;
    have_last_block_ = true;
    const std::uint16_t type = get_u16(p + 18);
    const std::uint32_t pfnc = get_u32(p + 28), w = get_u32(p + 32), h = get_u32(p + 36);
    const std::uint16_t pad = get_u16(p + 48);
    const int bits = pfnc_bits(pfnc);
    char text[200] = {0};
    if (n < k_leader_image_size)
        std::snprintf(text, sizeof text,
                      "block %llu: leader of %zu bytes, an image leader has "
                      "%zu",
                      (unsigned long long)block, n, k_leader_image_size);
    else if (type != k_payload_image && type != k_payload_image_chunk)
        std::snprintf(text, sizeof text, "block %llu: payload type 0x%04x is not an image",
                      (unsigned long long)block, type);
    else if (bits == 0)
        std::snprintf(text, sizeof text, "block %llu: pixel format 0x%08x is not Mono8/10/12/16",
                      (unsigned long long)block, pfnc);
    else if (w == 0 || h == 0 || (std::uint64_t(w) * (bits > 8 ? 2 : 1) + pad) * h > payload_bytes_)
        std::snprintf(text, sizeof text,
                      "block %llu: a %u x %u image does not fit the %llu "
                      "payload bytes the stream was set up for",
                      (unsigned long long)block, w, h, (unsigned long long)payload_bytes_);
    if (text[0]) {
        ++counters_[FLT_COUNT_BAD_LEADERS];
        ++counters_[FLT_COUNT_DROPPED];
        stream_error_ = text;
        return false;
    }
    frame_open_ = true;
    discarding_ = false;
    block_id_ = block;
    timestamp_ = get_u64(p + 20);
    width_ = w;
    height_ = h;
    bits_ = bits;
    padding_x_ = pad;
    image_bytes_ = (std::size_t(w) * (bits > 8 ? 2 : 1) + pad) * h;
    received_ = 0;
    return true;
}

void camera::on_payload(const std::uint8_t *p, std::size_t n) {
    if (received_ + n > frame_.size()) {
        char text[200];
        std::snprintf(text, sizeof text,
                      "block %llu: %zu payload bytes overflow the %llu the "
                      "stream was set up for",
                      (unsigned long long)block_id_, received_ + n,
                      (unsigned long long)payload_bytes_);
        drop(FLT_COUNT_OVERFLOW, text);
        return;
    }
    std::memcpy(frame_.data() + received_, p, n);
    received_ += n;
}

bool camera::on_trailer(const std::uint8_t *p, std::size_t n, frame_view &out) {
    const std::uint64_t block = get_u64(p + 8);
    const std::uint16_t status = get_u16(p + 16);
    const std::uint64_t valid = n >= 28 ? get_u64(p + 20) : 0;
    char text[240] = {0};
    flt_source_counter reason = FLT_COUNT_SHORT;
    if (frame_damaged_) {
        reason = FLT_COUNT_SUBMIT_DROPPED;
        std::snprintf(text, sizeof text,
                      "block %llu: dropped, a bulk submission was refused "
                      "while it streamed",
                      (unsigned long long)block_id_);
    } else if (block != block_id_)
        std::snprintf(text, sizeof text, "block %llu: the trailer is of block %llu",
                      (unsigned long long)block_id_, (unsigned long long)block);
    else if (status != 0)
        std::snprintf(text, sizeof text, "block %llu: trailer status 0x%04x (%s)",
                      (unsigned long long)block_id_, status, gencp_status_name(status));
    else if (received_ < valid || valid < image_bytes_ || valid > payload_bytes_)
        std::snprintf(text, sizeof text,
                      "block %llu: short frame, %zu payload bytes arrived, "
                      "the trailer says %llu valid, the image needs %zu",
                      (unsigned long long)block_id_, received_, (unsigned long long)valid,
                      image_bytes_);
    if (text[0]) {
        drop(reason, text);
        return false;
    }
    frame_open_ = false;
    out.pixels = frame_.data();
    out.width = width_;
    out.height = height_;
    out.stride = std::size_t(width_) * (bits_ > 8 ? 2 : 1) + padding_x_;
    out.bits = bits_;
    out.block_id = block_id_;
    out.timestamp_ns = timestamp_;
    out.has_chunk_counter = false;
    if (config_.want_chunk && valid > image_bytes_) {
        // Chunks are walked from the end: data, then id and length (u32 LE).
        std::size_t end = std::size_t(valid);
        for (int guard = 0; guard < 64 && end >= image_bytes_ + 8; ++guard) {
            const std::uint32_t id = get_u32(&frame_[end - 8]);
            const std::uint32_t length = get_u32(&frame_[end - 4]);
            if (length > end - 8)
                break;
            if (id == config_.chunk_id && (length == 4 || length == 8)) {
                out.has_chunk_counter = true;
                out.chunk_counter = get_uint(&frame_[end - 8 - length], length);
                out.chunk_counter_bytes = length;
                break;
            }
            end -= 8 + length;
        }
    }
    ++counters_[FLT_COUNT_FRAMES];
    return true;
}

bool camera::on_transfer(const usb_completion &c, frame_view &out) {
    const std::uint8_t *p = slot_buffers_[c.slot];
    std::size_t n = c.length;
    switch (c.status) {
        case usb_status::ok:
            break;
        case usb_status::no_device:
            lost_device("stream");
        case usb_status::overflow: {
            char text[200];
            std::snprintf(text, sizeof text,
                          "block %llu: a bulk transfer overflowed its %zu-byte "
                          "buffer (the camera sent more than the stream set-up allows)",
                          (unsigned long long)block_id_, slot_bytes_);
            if (frame_open_) {
                drop(FLT_COUNT_OVERFLOW, text);
            } else if (!discarding_) {
                ++counters_[FLT_COUNT_OVERFLOW];
                stream_error_ = text;
            }
            return false;
        }
        default: {
            if (c.status == usb_status::stall)
                dev_->clear_halt(ep_stream_);
            const std::string why =
                std::string("bulk transfer failed: ") + usb_status_name(c.status);
            if (frame_open_)
                drop(FLT_COUNT_SHORT, why);
            else {
                ++counters_[FLT_COUNT_BAD_PACKETS];
                stream_error_ = why;
            }
            return false;
        }
    }
    if (n >= 12 && get_u32(p) == k_magic_leader && get_u16(p + 6) <= n) {
        on_leader(p, n);
        return false;
    }
    if (n >= k_trailer_min_size && get_u32(p) == k_magic_trailer && frame_open_)
        return on_trailer(p, n, out);
    if (!frame_open_ && discarding_)
        return false;  // remains of a dropped frame
    if (!frame_open_) {
        ++counters_[FLT_COUNT_BAD_PACKETS];
        char text[160];
        std::snprintf(text, sizeof text,
                      "a %zu-byte transfer outside any frame (no leader "
                      "before it) was discarded",
                      n);
        stream_error_ = text;
        return false;
    }
    const std::size_t split = merged_trailer_at(p, n);
    on_payload(p, split);
    if (split < n && frame_open_)
        return on_trailer(p + split, n - split, out);
    return false;
}

flt_status camera::next(unsigned timeout_ms, frame_view &out) {
    if (disconnected_)
        raise(FLT_ERR_DEVICE, "the camera was unplugged");
    if (!streaming_)
        raise(FLT_ERR_STATE, "the camera is not streaming; call flt_source_start()");
    const auto deadline = clock::now() + std::chrono::milliseconds(timeout_ms);
    for (;;) {
        submit_waiting();
        if (in_flight_ == 0)
            raise(FLT_ERR_DEVICE, "no bulk transfer can be submitted (on Linux, usbfs memory: "
                                  "raise /sys/module/usbcore/parameters/usbfs_memory_mb or "
                                  "lower u3v_transfers); the next call tries again");
        const auto left =
            std::chrono::duration_cast<std::chrono::milliseconds>(deadline - clock::now()).count();
        usb_completion c;
        const usb_status st = dev_->async_reap(unsigned(std::max<long long>(0, left)), c);
        if (st == usb_status::timeout) {
            ++counters_[FLT_COUNT_TIMEOUTS];
            char text[160];
            if (frame_open_) {
                std::snprintf(text, sizeof text,
                              "block %llu: no data for %u ms after %zu "
                              "payload bytes; dropped",
                              (unsigned long long)block_id_, timeout_ms, received_);
                drop(FLT_COUNT_TIMEOUT_DROPPED, text);
            } else {
                std::snprintf(text, sizeof text, "no frame within %u ms", timeout_ms);
                stream_error_ = text;
            }
            throw error(FLT_ERR_TIMEOUT, text);
        }
        if (st == usb_status::no_device)
            lost_device("stream");
        if (st != usb_status::ok)
            raise(FLT_ERR_DEVICE, "waiting for the stream failed: %s", usb_status_name(st));
        --in_flight_;
        bool done = false;
        try {
            done = on_transfer(c, out);
        } catch (...) {
            waiting_[c.slot] = 1;
            throw;
        }
        // The frame buffer holds the payload now: the slot can go again.
        resubmit(c.slot);
        if (done)
            return FLT_OK;
    }
}

}  // namespace flt::u3v
