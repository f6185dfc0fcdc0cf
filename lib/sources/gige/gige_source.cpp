// SPDX-License-Identifier: Apache-2.0
// A GigE Vision camera as a frame source: finding and opening it, and the
// hooks of the camera base (../camera/camera.hpp) over the protocol layers
// of this folder.
#include "sources/gige/gige_source.hpp"

#include "core/error.hpp"
#include "sources/gige/discovery.hpp"
#include "sources/gige/protocol.hpp"

namespace flt::gige {

using sources::raise;

endpoint find_camera(const char *camera, unsigned discovery_ms) {
    endpoint e;
    if (camera && parse_endpoint(camera, k_gvcp_port, e))
        return e;
    const std::vector<camera_info> found = discover(nullptr, discovery_ms);
    for (const camera_info &c : found)
        if (!camera || c.strings[FLT_CAMERA_SERIAL] == camera ||
            c.strings[FLT_CAMERA_USER_NAME] == camera)
            return c.address;
    if (!camera)
        raise(FLT_ERR_NOT_FOUND, "no GigE Vision camera answered a discovery broadcast in %u ms",
              discovery_ms);
    raise(FLT_ERR_NOT_FOUND,
          "no GigE Vision camera with serial number or name '%s' answered in %u ms (%zu "
          "camera(s) did)",
          sources::visible_text(std::string(camera).substr(0, 80)).c_str(), discovery_ms,
          found.size());
}

gige_camera::gige_camera(endpoint address, const camera_config &config)
    : genicam_camera("GigE Vision", config.control.command_attempts), config_(config),
      control_(address, config.control), stream_(control_, acc_, config.stream) {
    control_.take_control();
    try {
        boot_ = read_bootstrap(control_);
        set_strings(boot_.strings);
        const device_description d = read_description(control_, boot_.first_url);
        load_description(d.xml, d.file_bytes, d.zipped, control_, true);
        if (boot_.stream_channels == 0)
            raise(FLT_ERR_DEVICE, "the camera at %s has no stream channel",
                  to_string(address, k_gvcp_port).c_str());
        stream_.negotiate_packet_size();
    } catch (...) {
        control_.release_control();
        throw;
    }
}

gige_camera::~gige_camera() {
    shutdown();
    control_.release_control();
}

void gige_camera::check_link(bool /*starting*/) {
    const std::string failure = control_.heartbeat_failure();
    if (!failure.empty())
        raise(FLT_ERR_DEVICE, "the camera at %s: %s",
              to_string(control_.camera(), k_gvcp_port).c_str(), failure.c_str());
}

void gige_camera::prepare_stream(const sources::frame_geometry &g) {
    stream_.prepare(g, (boot_.capabilities & bootstrap::capability_packet_resend) != 0);
}

bool gige_camera::next_frame(unsigned timeout_ms, sources::raw_frame &out) {
    const bool got = stream_.next(timeout_ms, out);
    if (got && boot_.tick_hz != 0 && boot_.tick_hz != 1000000000u)
        out.timestamp_ns = std::uint64_t(double(out.timestamp_ns) * (1e9 / double(boot_.tick_hz)));
    return got;
}

std::uint64_t gige_camera::transport_count(flt_source_counter which) const {
    return control_.count(int(which)) + stream_.count(int(which));
}

bool gige_camera::transport_value(flt_camera_value which, std::uint64_t &out) const {
    switch (which) {
        case FLT_CAMERA_CONTROL_TIMEOUT_MS:
            out = control_.config().timeout_ms;
            return true;
        case FLT_CAMERA_PAYLOAD_BYTES:
            out = stream_.payload_bytes();
            return true;
        case FLT_CAMERA_GEV_VERSION:
            out = boot_.gev_version;
            return true;
        case FLT_CAMERA_IP_ADDRESS:
            out = control_.camera().address;
            return true;
        case FLT_CAMERA_HEARTBEAT_TIMEOUT_MS:
            out = control_.config().heartbeat_ms;
            return true;
        case FLT_CAMERA_HEARTBEATS:
            out = control_.heartbeats();
            return true;
        case FLT_CAMERA_PACKET_SIZE:
            out = stream_.packet_size();
            return true;
        case FLT_CAMERA_STREAM_PORT:
            out = stream_.host_port();
            return true;
        case FLT_CAMERA_TIMESTAMP_HZ:
            out = boot_.tick_hz;
            return true;
        case FLT_CAMERA_RESEND_CAPABLE:
            out = (boot_.capabilities & bootstrap::capability_packet_resend) ? 1 : 0;
            return true;
        case FLT_CAMERA_RECEIVE_BUFFER_BYTES:
            out = std::uint64_t(stream_.socket_buffer());
            return true;
        default:
            return false;
    }
}

}  // namespace flt::gige
