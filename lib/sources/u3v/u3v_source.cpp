// SPDX-License-Identifier: Apache-2.0
// A USB3 Vision camera as a frame source: opening it and the hooks of the
// camera base (../camera/camera.hpp) over the protocol layers of this
// folder: SI control is the stream channel, SIRM and the bulk transfers
// its host side.
#include "sources/u3v/u3v_source.hpp"

#include "core/error.hpp"
#include "sources/u3v/protocol.hpp"

namespace flt::u3v {

using sources::raise;

u3v_camera::u3v_camera(usb_backend &bus, const char *serial, const camera_config &config)
    : genicam_camera("USB3 Vision", config.control.command_attempts), config_(config),
      control_(link_, acc_, config.control), stream_(link_, control_, acc_, config.stream) {
    open(bus, serial);
}

u3v_camera::u3v_camera(std::unique_ptr<usb_backend> owned_bus, const char *serial,
                       const camera_config &config)
    : genicam_camera("USB3 Vision", config.control.command_attempts),
      owned_bus_(std::move(owned_bus)), config_(config), control_(link_, acc_, config.control),
      stream_(link_, control_, acc_, config.stream) {
    open(*owned_bus_, serial);
}

u3v_camera::~u3v_camera() {
    shutdown();
}

void u3v_camera::open(usb_backend &bus, const char *serial) {
    open_camera(bus, serial, link_);
    boot_ = read_bootstrap(control_);
    set_strings(boot_.strings);
    const device_description d = read_description(control_, boot_.manifest_address);
    load_description(d.xml, d.file_bytes, d.zipped, control_, false);
    recover_stream();
}

void u3v_camera::write_si_control(std::uint32_t value) {
    std::uint8_t b[4];
    put_u32(b, value);
    control_.write(boot_.sirm_address + sirm::control, b, 4);
}

bool u3v_camera::si_enabled() {
    std::uint8_t b[4];
    control_.read(boot_.sirm_address + sirm::control, b, 4);
    return (get_u32(b) & sirm::control_enable) != 0;
}

void u3v_camera::check_link(bool starting) {
    if (link_.disconnected)
        raise(FLT_ERR_DEVICE, "the camera was unplugged");
    if (starting && (boot_.sirm_address == 0 || link_.ep_stream == 0))
        raise(FLT_ERR_DEVICE, "the camera has no stream channel (SBRM lists 0)");
}

bool u3v_camera::channel_enabled() {
    return boot_.sirm_address != 0 && si_enabled();
}

void u3v_camera::prepare_stream(const sources::frame_geometry &g) {
    stream_.prepare(boot_.sirm_address, g);
}

void u3v_camera::enable_channel() {
    write_si_control(sirm::control_enable);
}

bool u3v_camera::disable_channel() {
    // SI control = 0, read back; a stream endpoint the camera halted while
    // the channel went off is cleared for the next set-up.
    write_si_control(0);
    if (si_enabled())
        return false;
    if (link_.ep_stream)
        link_.dev->clear_halt(link_.ep_stream);
    return true;
}

bool u3v_camera::transport_value(flt_camera_value which, std::uint64_t &out) const {
    const stream_layout &l = stream_.layout();
    switch (which) {
        case FLT_CAMERA_GENCP_VERSION:
            out = boot_.gencp_version;
            return true;
        case FLT_CAMERA_U3V_VERSION:
            out = boot_.u3v_version;
            return true;
        case FLT_CAMERA_RESPONSE_TIME_MS:
            out = boot_.response_ms;
            return true;
        case FLT_CAMERA_CONTROL_TIMEOUT_MS:
            out = control_.timeout_ms();
            return true;
        case FLT_CAMERA_MAX_COMMAND_BYTES:
            out = control_.max_command();
            return true;
        case FLT_CAMERA_MAX_ACK_BYTES:
            out = control_.max_ack();
            return true;
        case FLT_CAMERA_SIRM_ADDRESS:
            out = boot_.sirm_address;
            return true;
        case FLT_CAMERA_MANIFEST_ADDRESS:
            out = boot_.manifest_address;
            return true;
        case FLT_CAMERA_SPEED_MBPS:
            out = link_.speed_mbps;
            return true;
        case FLT_CAMERA_ALIGNMENT:
            out = l.alignment;
            return true;
        case FLT_CAMERA_PAYLOAD_BYTES:
            out = l.payload_bytes;
            return true;
        case FLT_CAMERA_TRANSFER_BYTES:
            out = l.transfer_bytes;
            return true;
        case FLT_CAMERA_TRANSFER_COUNT:
            out = l.transfer_count;
            return true;
        case FLT_CAMERA_FINAL_TRANSFER_BYTES:
            out = l.final1_bytes;
            return true;
        case FLT_CAMERA_MAX_LEADER_BYTES:
            out = l.max_leader;
            return true;
        case FLT_CAMERA_MAX_TRAILER_BYTES:
            out = l.max_trailer;
            return true;
        default:
            return false;
    }
}

}  // namespace flt::u3v
