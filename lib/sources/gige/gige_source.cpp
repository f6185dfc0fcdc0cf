// SPDX-License-Identifier: Apache-2.0
// A GigE Vision camera as a frame source: finding and opening it, the
// acquisition sequence and the camera_device calls, over the protocol
// layers of this folder.
#include "sources/gige/gige_source.hpp"

#include "core/error.hpp"
#include "sources/gige/discovery.hpp"
#include "sources/gige/protocol.hpp"
#include "sources/u3v/protocol.hpp"

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
          "no GigE Vision camera with serial number or name '%.80s' answered in %u ms (%zu "
          "camera(s) did)",
          camera, discovery_ms, found.size());
}

gige_camera::gige_camera(endpoint address, const camera_config &config)
    : config_(config), control_(address, config.control), stream_(control_, acc_, config.stream) {
    control_.take_control();
    try {
        boot_ = read_bootstrap(control_);
        const device_description d = read_description(control_, boot_.first_url);
        xml_bytes_ = d.file_bytes;
        xml_zipped_ = d.zipped;
        features_ = std::make_unique<sources::feature_layer>(
            control_, sources::make_feature_engine(d.xml, control_), true);
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
    try {
        stop();
    } catch (...) {
    }
    control_.release_control();
}

void gige_camera::check_control() {
    const std::string failure = control_.heartbeat_failure();
    if (!failure.empty())
        raise(FLT_ERR_DEVICE, "the camera at %s: %s",
              to_string(control_.camera(), k_gvcp_port).c_str(), failure.c_str());
}

// --- acquisition -----------------------------------------------------------------

void gige_camera::start() {
    if (streaming_)
        raise(FLT_ERR_STATE, "the camera is already streaming");
    check_control();
    if (features_->is_mapped("AcquisitionMode"))
        set_int("AcquisitionMode", 0);
    else if (features_->kind_of("AcquisitionMode") == sources::feature_kind::enumeration)
        set_enum("AcquisitionMode", "Continuous");
    const std::uint32_t width = std::uint32_t(get_int("Width"));
    const std::uint32_t height = std::uint32_t(get_int("Height"));
    const std::uint32_t pfnc = std::uint32_t(get_int("PixelFormat"));
    if (u3v::pfnc_bits(pfnc) == 0)
        raise(FLT_ERR_FORMAT,
              "PixelFormat 0x%08x is not Mono8, Mono10, Mono12 or Mono16 (unpacked); set one "
              "with flt_source_set_enum()",
              pfnc);
    if (width == 0 || height == 0)
        raise(FLT_ERR_DEVICE, "the camera reports a %u x %u px image", width, height);
    try {
        stream_.prepare(width, height, pfnc,
                        (boot_.capabilities & bootstrap::capability_packet_resend) != 0);
        lock_transport_params(true);
        execute("AcquisitionStart");
    } catch (...) {
        try {
            lock_transport_params(false);
        } catch (...) {
        }
        stream_.release();
        throw;
    }
    streaming_ = true;
}

// As for USB3 Vision (u3v_source.cpp): TLParamsLocked = 1 while acquiring,
// when the camera lets the host write it.
void gige_camera::lock_transport_params(bool locked) {
    if (!features_->has("TLParamsLocked"))
        return;
    try {
        features_->set_int("TLParamsLocked", locked ? 1 : 0);
    } catch (const error &e) {
        if (e.status != FLT_ERR_STATE && e.status != FLT_ERR_INVALID_ARGUMENT)
            throw;
    }
}

void gige_camera::stop() {
    if (!streaming_)
        return;
    streaming_ = false;
    try {
        execute("AcquisitionStop");
    } catch (...) {
    }
    try {
        lock_transport_params(false);
    } catch (...) {
    }
    stream_.release();
}

bool gige_camera::next(unsigned timeout_ms, sources::raw_frame &out) {
    if (!streaming_)
        raise(FLT_ERR_STATE, "the camera is not streaming; call flt_source_start()");
    check_control();
    const bool got = stream_.next(timeout_ms, out);
    if (got && boot_.tick_hz != 0 && boot_.tick_hz != 1000000000u)
        out.timestamp_ns = std::uint64_t(double(out.timestamp_ns) * (1e9 / double(boot_.tick_hz)));
    return got;
}

std::uint64_t gige_camera::count(flt_source_counter which) const {
    return acc_[which] + control_.count(int(which)) + stream_.count(int(which));
}

// --- camera_device ------------------------------------------------------------------

const std::string &gige_camera::string_of(flt_camera_string which) const {
    return boot_.strings[std::size_t(which)];
}

std::uint64_t gige_camera::value_of(flt_camera_value which) const {
    switch (which) {
        case FLT_CAMERA_CONTROL_TIMEOUT_MS:
            return control_.config().timeout_ms;
        case FLT_CAMERA_XML_BYTES:
            return xml_bytes_;
        case FLT_CAMERA_XML_ZIPPED:
            return xml_zipped_;
        case FLT_CAMERA_PAYLOAD_BYTES:
            return stream_.payload_bytes();
        case FLT_CAMERA_GEV_VERSION:
            return boot_.gev_version;
        case FLT_CAMERA_IP_ADDRESS:
            return control_.camera().address;
        case FLT_CAMERA_HEARTBEAT_TIMEOUT_MS:
            return control_.config().heartbeat_ms;
        case FLT_CAMERA_HEARTBEATS:
            return control_.heartbeats();
        case FLT_CAMERA_PACKET_SIZE:
            return stream_.packet_size();
        case FLT_CAMERA_STREAM_PORT:
            return stream_.host_port();
        case FLT_CAMERA_TIMESTAMP_HZ:
            return boot_.tick_hz;
        case FLT_CAMERA_RESEND_CAPABLE:
            return (boot_.capabilities & bootstrap::capability_packet_resend) ? 1 : 0;
        case FLT_CAMERA_RECEIVE_BUFFER_BYTES:
            return std::uint64_t(stream_.socket_buffer());
        default:
            break;
    }
    raise(FLT_ERR_INVALID_ARGUMENT, "argument 'which' = %d is no value of a GigE Vision camera",
          int(which));
}

std::int64_t gige_camera::get_int(const std::string &feature) {
    return features_->get_int(feature);
}
void gige_camera::set_int(const std::string &feature, std::int64_t value) {
    features_->set_int(feature, value);
}
double gige_camera::get_float(const std::string &feature) {
    return features_->get_float(feature);
}
void gige_camera::set_float(const std::string &feature, double value) {
    features_->set_float(feature, value);
}
void gige_camera::set_enum(const std::string &feature, const std::string &entry) {
    features_->set_enum(feature, entry);
}
void gige_camera::execute(const std::string &feature) {
    features_->execute(feature);
}
void gige_camera::map_feature(const std::string &feature, std::uint64_t address,
                              std::uint32_t length, bool is_float) {
    features_->map_feature(feature, address, length, is_float);
}
void gige_camera::read_memory(std::uint64_t address, std::uint8_t *out, std::size_t bytes) {
    control_.read(address, out, bytes);
}
void gige_camera::write_memory(std::uint64_t address, const std::uint8_t *in, std::size_t bytes) {
    control_.write(address, in, bytes);
}

}  // namespace flt::gige
