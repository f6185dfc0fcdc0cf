// SPDX-License-Identifier: Apache-2.0
// A USB3 Vision camera as a frame source: opening, the acquisition sequence
// and the camera_device calls, over the protocol layers of this folder.
#include "sources/u3v/u3v_source.hpp"

#include <algorithm>
#include <cstring>

#include "core/error.hpp"
#include "sources/u3v/protocol.hpp"

namespace flt::u3v {

using sources::raise;

u3v_camera::u3v_camera(usb_backend &bus, const char *serial, const camera_config &config)
    : config_(config), control_(link_, acc_, config.control),
      stream_(link_, control_, acc_, config.stream) {
    open(bus, serial);
}

u3v_camera::u3v_camera(std::unique_ptr<usb_backend> owned_bus, const char *serial,
                       const camera_config &config)
    : owned_bus_(std::move(owned_bus)), config_(config), control_(link_, acc_, config.control),
      stream_(link_, control_, acc_, config.stream) {
    open(*owned_bus_, serial);
}

u3v_camera::~u3v_camera() {
    try {
        stop();
    } catch (...) {
    }
    stream_.release();
}

void u3v_camera::open(usb_backend &bus, const char *serial) {
    open_camera(bus, serial, link_);
    boot_ = read_bootstrap(control_);
    const device_description d = read_description(control_, boot_.manifest_address);
    xml_bytes_ = d.file_bytes;
    xml_zipped_ = d.zipped;
    features_ = std::make_unique<sources::feature_layer>(
        control_, sources::make_feature_engine(d.xml, control_));
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

void u3v_camera::recover_stream() {
    if (boot_.sirm_address == 0)
        return;
    if (!si_enabled())
        return;
    // A process died while streaming: stop the camera so it accepts a new
    // stream set-up. The SI control reset is what a new set-up needs: an
    // AcquisitionStop the camera refuses is left to the next start or stop.
    acc_.add(FLT_COUNT_STREAM_RECOVERIES);
    may_stream_ = true;
    halt_camera(false);
}

namespace {

// What a message says when the camera may be left streaming (the tests
// look for it).
constexpr const char *k_may_stream = "may still be streaming";

// Failures worth another attempt: no answer, too many pending acks, busy
// (FLT_ERR_TIMEOUT) and a malformed answer (FLT_ERR_FORMAT). A status the
// camera answered (FLT_ERR_DEVICE) would be answered again.
bool retryable(flt_status status) {
    return status == FLT_ERR_TIMEOUT || status == FLT_ERR_FORMAT;
}

}  // namespace

void u3v_camera::halt_camera(bool need_acquisition_stop) {
    // AcquisitionStop, then SI control = 0 read back as 0; each step again
    // (up to u3v_command_attempts rounds, on top of the control channel's
    // own attempts per command) while its failure is worth retrying.
    bool stopped = false, si_off = false;
    flt_status status = FLT_OK;
    std::string why;
    const unsigned rounds = std::max(1u, config_.control.command_attempts);
    for (unsigned round = 0; round < rounds && !(stopped && si_off); ++round) {
        bool again = false;
        if (!stopped) {
            try {
                execute("AcquisitionStop");
                stopped = true;
            } catch (const error &e) {
                if (link_.disconnected)
                    throw;
                if (e.status == FLT_ERR_NOT_FOUND) {
                    stopped = true;  // no such command: SI control is all there is
                } else {
                    status = e.status;
                    why = std::string("AcquisitionStop: ") + e.what();
                    again = again || retryable(e.status);
                }
            }
        }
        if (!si_off) {
            try {
                write_si_control(0);
                si_off = !si_enabled();
                if (!si_off) {
                    status = FLT_ERR_DEVICE;
                    why = "SI control still reads 1 after writing 0";
                    again = true;
                }
            } catch (const error &e) {
                if (link_.disconnected)
                    throw;
                status = e.status;
                why = std::string("SI control = 0: ") + e.what();
                again = again || retryable(e.status);
            }
        }
        if (!again)
            break;
    }
    if (si_off && link_.ep_stream)
        link_.dev->clear_halt(link_.ep_stream);
    if (si_off && stopped)
        may_stream_ = false;
    if (si_off && (stopped || !need_acquisition_stop))
        return;
    raise(status == FLT_OK ? FLT_ERR_DEVICE : status,
          "the camera could not be stopped and %s (%s); flt_source_stop() or "
          "flt_source_start() tries again",
          k_may_stream, why.c_str());
}

// --- acquisition -----------------------------------------------------------------

void u3v_camera::start() {
    if (streaming_)
        raise(FLT_ERR_STATE, "the camera is already streaming");
    if (link_.disconnected)
        raise(FLT_ERR_DEVICE, "the camera was unplugged");
    if (boot_.sirm_address == 0 || link_.ep_stream == 0)
        raise(FLT_ERR_DEVICE, "the camera has no stream channel (SBRM lists 0)");
    try {
        start_sequence();
    } catch (const error &e) {
        // A failure before an earlier failure was mended: say so.
        if (may_stream_ && !link_.disconnected && !std::strstr(e.what(), k_may_stream))
            raise(e.status,
                  "%s; the camera %s since an earlier stop or start: flt_source_stop() or "
                  "flt_source_start() tries again",
                  e.what(), k_may_stream);
        throw;
    }
}

void u3v_camera::start_sequence() {
    // A camera left streaming (by a failed stop or start, or by another
    // host since open) refuses a new stream set-up: stop it first, as open
    // does. SI control = 0 is what the set-up needs.
    if (si_enabled()) {
        acc_.add(FLT_COUNT_STREAM_RECOVERIES);
        may_stream_ = true;
    }
    if (may_stream_)
        halt_camera(false);
    if (features_->is_mapped("AcquisitionMode"))
        set_int("AcquisitionMode", 0);
    else if (features_->kind_of("AcquisitionMode") == sources::feature_kind::enumeration)
        set_enum("AcquisitionMode", "Continuous");
    const std::uint32_t width = std::uint32_t(get_int("Width"));
    const std::uint32_t height = std::uint32_t(get_int("Height"));
    const std::uint32_t pfnc = std::uint32_t(get_int("PixelFormat"));
    const int bits = pfnc_bits(pfnc);
    if (bits == 0)
        raise(FLT_ERR_FORMAT,
              "PixelFormat 0x%08x is not Mono8, Mono10, Mono12 or Mono16 "
              "(unpacked); set one with flt_source_set_enum()",
              pfnc);
    try {
        stream_.prepare(boot_.sirm_address, width, height, bits);
    } catch (...) {
        stream_.release();
        throw;
    }
    try {
        // From here on the camera may stream whatever the answers say.
        may_stream_ = true;
        write_si_control(sirm::control_enable);
        lock_transport_params(true);
        execute("AcquisitionStart");
    } catch (const error &e) {
        stream_.release();
        if (link_.disconnected)
            throw;
        // Undo what may have reached the camera, so that a failed start
        // leaves it stopped; else the next start or stop stops it.
        std::string undo;
        try {
            halt_camera(true);
        } catch (const error &u) {
            undo = std::string("; stopping it again failed too: ") + u.what();
        }
        try {
            lock_transport_params(false);
        } catch (...) {
        }
        raise(e.status, "%s%s", e.what(), undo.c_str());
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

// SFNC: the host locks the transport-layer parameters (TLParamsLocked = 1)
// while it acquires, and cameras tie the features that change the payload
// (Width, Height, PixelFormat, ...) to it through pIsLocked: changing them
// mid-stream is refused with "locked" instead of breaking the stream. A
// camera whose TLParamsLocked the host cannot write (read-only, as some
// describe it, or not available) manages it itself: that is no error. What
// the camera answers on the wire is.
void u3v_camera::lock_transport_params(bool locked) {
    if (!features_->has("TLParamsLocked"))
        return;
    try {
        features_->set_int("TLParamsLocked", locked ? 1 : 0);
    } catch (const error &e) {
        if (e.status != FLT_ERR_STATE && e.status != FLT_ERR_INVALID_ARGUMENT)
            throw;
    }
}

void u3v_camera::stop() {
    if (!streaming_ && !may_stream_)
        return;
    streaming_ = false;
    if (link_.disconnected) {
        // Gone: it streams to no one, and a replugged camera starts afresh
        // (open recovers one a host left streaming).
        may_stream_ = false;
        stream_.release();
        return;
    }
    // The transfers stay in flight while the camera stops, so that what it
    // still sends is taken; they are cancelled whatever happens.
    try {
        halt_camera(true);
    } catch (const error &) {
        stream_.release();
        if (link_.disconnected) {
            may_stream_ = false;
            return;
        }
        try {
            lock_transport_params(false);
        } catch (...) {
        }
        throw;
    }
    try {
        lock_transport_params(false);
    } catch (...) {
    }
    stream_.release();
}

bool u3v_camera::next(unsigned timeout_ms, sources::raw_frame &out) {
    if (link_.disconnected)
        raise(FLT_ERR_DEVICE, "the camera was unplugged");
    if (!streaming_)
        raise(FLT_ERR_STATE, "the camera is not streaming; call flt_source_start()");
    return stream_.next(timeout_ms, out);
}

// --- camera_device ------------------------------------------------------------------

const std::string &u3v_camera::string_of(flt_camera_string which) const {
    return boot_.strings[std::size_t(which)];
}

std::uint64_t u3v_camera::value_of(flt_camera_value which) const {
    const stream_layout &l = stream_.layout();
    switch (which) {
        case FLT_CAMERA_GENCP_VERSION:
            return boot_.gencp_version;
        case FLT_CAMERA_U3V_VERSION:
            return boot_.u3v_version;
        case FLT_CAMERA_RESPONSE_TIME_MS:
            return boot_.response_ms;
        case FLT_CAMERA_CONTROL_TIMEOUT_MS:
            return control_.timeout_ms();
        case FLT_CAMERA_MAX_COMMAND_BYTES:
            return control_.max_command();
        case FLT_CAMERA_MAX_ACK_BYTES:
            return control_.max_ack();
        case FLT_CAMERA_SIRM_ADDRESS:
            return boot_.sirm_address;
        case FLT_CAMERA_MANIFEST_ADDRESS:
            return boot_.manifest_address;
        case FLT_CAMERA_XML_BYTES:
            return xml_bytes_;
        case FLT_CAMERA_XML_ZIPPED:
            return xml_zipped_;
        case FLT_CAMERA_SPEED_MBPS:
            return link_.speed_mbps;
        case FLT_CAMERA_ALIGNMENT:
            return l.alignment;
        case FLT_CAMERA_PAYLOAD_BYTES:
            return l.payload_bytes;
        case FLT_CAMERA_TRANSFER_BYTES:
            return l.transfer_bytes;
        case FLT_CAMERA_TRANSFER_COUNT:
            return l.transfer_count;
        case FLT_CAMERA_FINAL_TRANSFER_BYTES:
            return l.final1_bytes;
        case FLT_CAMERA_MAX_LEADER_BYTES:
            return l.max_leader;
        case FLT_CAMERA_MAX_TRAILER_BYTES:
            return l.max_trailer;
        default:
            break;
    }
    raise(FLT_ERR_INVALID_ARGUMENT, "argument 'which' = %d is no camera value", int(which));
}

std::int64_t u3v_camera::get_int(const std::string &feature) {
    return features_->get_int(feature);
}
void u3v_camera::set_int(const std::string &feature, std::int64_t value) {
    features_->set_int(feature, value);
}
double u3v_camera::get_float(const std::string &feature) {
    return features_->get_float(feature);
}
void u3v_camera::set_float(const std::string &feature, double value) {
    features_->set_float(feature, value);
}
void u3v_camera::set_enum(const std::string &feature, const std::string &entry) {
    features_->set_enum(feature, entry);
}
void u3v_camera::execute(const std::string &feature) {
    features_->execute(feature);
}
void u3v_camera::map_feature(const std::string &feature, std::uint64_t address,
                             std::uint32_t length, bool is_float) {
    features_->map_feature(feature, address, length, is_float);
}
void u3v_camera::read_memory(std::uint64_t address, std::uint8_t *out, std::size_t bytes) {
    control_.read(address, out, bytes);
}
void u3v_camera::write_memory(std::uint64_t address, const std::uint8_t *in, std::size_t bytes) {
    control_.write(address, in, bytes);
}

}  // namespace flt::u3v
