// SPDX-License-Identifier: Apache-2.0
// A GenICam camera as a frame source (see camera.hpp): the acquisition
// sequence with its truthful stop, TLParamsLocked, the frame bounds, the
// camera_device calls, over the hooks a transport implements.
#include "sources/camera/camera.hpp"

#include <algorithm>
#include <cstring>

#include "core/error.hpp"

namespace flt::sources {

std::string visible_text(const std::string &raw) {
    std::string out;
    out.reserve(raw.size());
    const auto *p = reinterpret_cast<const unsigned char *>(raw.data());
    const std::size_t n = raw.size();
    for (std::size_t i = 0; i < n;) {
        const unsigned char c = p[i];
        if (c < 0x80) {
            out += c < 0x20 || c == 0x7F ? '?' : char(c);
            ++i;
            continue;
        }
        // A UTF-8 sequence: its length from the lead byte, continuation
        // bytes 10xxxxxx, no overlong form, no surrogate, at most U+10FFFF.
        std::size_t len = 0;
        std::uint32_t cp = 0;
        if (c >= 0xC2 && c <= 0xDF)
            len = 2, cp = c & 0x1F;
        else if (c >= 0xE0 && c <= 0xEF)
            len = 3, cp = c & 0x0F;
        else if (c >= 0xF0 && c <= 0xF4)
            len = 4, cp = c & 0x07;
        bool valid = len != 0 && i + len <= n;
        for (std::size_t k = 1; valid && k < len; ++k) {
            valid = (p[i + k] & 0xC0) == 0x80;
            cp = (cp << 6) | (p[i + k] & 0x3F);
        }
        valid = valid && !(len == 3 && cp < 0x800) && !(len == 4 && cp < 0x10000) &&
                !(cp >= 0xD800 && cp <= 0xDFFF) && cp <= 0x10FFFF &&
                !(cp >= 0x80 && cp <= 0x9F);  // C1 controls (0x9B is a CSI)
        if (!valid) {
            out += '?';
            ++i;
            continue;
        }
        out.append(raw, i, len);
        i += len;
    }
    return out;
}

genicam_camera::genicam_camera(const char *transport, unsigned halt_rounds)
    : transport_(transport), halt_rounds_(std::max(1u, halt_rounds)) {}

void genicam_camera::set_strings(const std::array<std::string, 7> &strings) {
    for (std::size_t i = 0; i < strings.size(); ++i)
        strings_[i] = visible_text(strings[i]);
}

void genicam_camera::load_description(const std::string &xml, std::uint64_t file_bytes, bool zipped,
                                      register_port &port, bool big_endian) {
    xml_bytes_ = file_bytes;
    xml_zipped_ = zipped;
    features_ = std::make_unique<feature_layer>(port, make_feature_engine(xml, port), big_endian);
}

void genicam_camera::recover_stream() {
    if (!channel_enabled())
        return;
    // A process died while streaming: stop the camera so that it accepts a
    // new stream set-up. The channel going off is what a set-up needs; an
    // AcquisitionStop the camera refuses is left to the next start or stop.
    acc_.add(FLT_COUNT_STREAM_RECOVERIES);
    may_stream_ = true;
    halt_camera(false);
}

void genicam_camera::shutdown() noexcept {
    try {
        stop();
    } catch (...) {
        // Destroying: the camera drops a stream nobody controls (GigE
        // Vision: with the heartbeat; USB3 Vision: at the next open).
    }
    release_stream();
}

namespace {

// Failures worth another attempt: no answer, too many pending acks, busy
// (FLT_ERR_TIMEOUT) and a malformed answer (FLT_ERR_FORMAT). A status the
// camera answered (FLT_ERR_DEVICE: access denied, ...) would be answered
// again.
bool retryable(flt_status status) {
    return status == FLT_ERR_TIMEOUT || status == FLT_ERR_FORMAT;
}

}  // namespace

// Camera fault point: the camera may be left streaming. Every way out of
// here that is not a confirmed stop says so (k_may_stream).
void genicam_camera::halt_camera(bool need_acquisition_stop) {
    // AcquisitionStop, then the stream channel off (confirmed by the
    // camera); each step again (up to halt_rounds_ rounds, on top of the
    // control channel's own attempts per command) while its failure is
    // worth retrying.
    bool stopped = false, channel_off = false;
    flt_status status = FLT_OK;
    std::string why;
    for (unsigned round = 0; round < halt_rounds_ && !(stopped && channel_off); ++round) {
        bool again = false;
        if (!stopped) {
            try {
                execute("AcquisitionStop");
                stopped = true;
            } catch (const error &e) {
                if (gone())
                    throw;
                if (e.status == FLT_ERR_NOT_FOUND) {
                    stopped = true;  // no such command: the channel is all there is
                } else {
                    status = e.status;
                    why = std::string("AcquisitionStop: ") + e.what();
                    again = again || retryable(e.status);
                }
            }
        }
        if (!channel_off) {
            try {
                channel_off = disable_channel();
                if (!channel_off) {
                    status = FLT_ERR_DEVICE;
                    why = "the camera still reports its stream channel on after turning it off";
                    again = true;
                }
            } catch (const error &e) {
                if (gone())
                    throw;
                status = e.status;
                why = std::string("turning the stream channel off: ") + e.what();
                again = again || retryable(e.status);
            }
        }
        if (!again)
            break;
    }
    if (channel_off && stopped)
        may_stream_ = false;
    if (channel_off && (stopped || !need_acquisition_stop))
        return;
    raise(status == FLT_OK ? FLT_ERR_DEVICE : status,
          "the camera could not be stopped and %s (%s); flt_source_stop() or "
          "flt_source_start() tries again",
          k_may_stream, why.c_str());
}

// --- acquisition -----------------------------------------------------------------

void genicam_camera::start() {
    if (streaming_)
        raise(FLT_ERR_STATE, "the camera is already streaming");
    check_link(true);
    try {
        start_sequence();
    } catch (const error &e) {
        // A failure before an earlier failure was mended: say so.
        if (may_stream_ && !gone() && !std::strstr(e.what(), k_may_stream))
            raise(e.status,
                  "%s; the camera %s since an earlier stop or start: flt_source_stop() or "
                  "flt_source_start() tries again",
                  e.what(), k_may_stream);
        throw;
    }
}

void genicam_camera::start_sequence() {
    // A camera left streaming (by a failed stop or start, or by another
    // host since open) refuses a new stream set-up: stop it first, as open
    // does. The channel off is what the set-up needs.
    if (channel_enabled()) {
        acc_.add(FLT_COUNT_STREAM_RECOVERIES);
        may_stream_ = true;
    }
    if (may_stream_)
        halt_camera(false);
    if (features_->is_mapped("AcquisitionMode"))
        set_int("AcquisitionMode", 0);
    else if (features_->kind_of("AcquisitionMode") == feature_kind::enumeration)
        set_enum("AcquisitionMode", "Continuous");
    // The size the camera asks for, bounded before anything is allocated.
    const std::int64_t width = get_int("Width"), height = get_int("Height");
    const std::int64_t pfnc = get_int("PixelFormat");
    const std::string who = std::string("the ") + transport_ + " camera";
    geometry_ = check_geometry(width, height, pfnc, who.c_str());
    try {
        prepare_stream(geometry_);
    } catch (...) {
        release_stream();
        throw;
    }
    try {
        // From here on the camera may stream whatever the answers say.
        may_stream_ = true;
        enable_channel();
        lock_transport_params(true);
        execute("AcquisitionStart");
    } catch (const error &e) {
        release_stream();
        if (gone())
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
        release_stream();
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
void genicam_camera::lock_transport_params(bool locked) {
    if (!features_->has("TLParamsLocked"))
        return;
    try {
        features_->set_int("TLParamsLocked", locked ? 1 : 0);
    } catch (const error &e) {
        if (e.status != FLT_ERR_STATE && e.status != FLT_ERR_INVALID_ARGUMENT)
            throw;
    }
}

void genicam_camera::stop() {
    if (!streaming_ && !may_stream_)
        return;
    streaming_ = false;
    if (gone()) {
        // Gone: it streams to no one, and a replugged camera starts afresh
        // (open recovers one a host left streaming).
        may_stream_ = false;
        release_stream();
        return;
    }
    // The host side keeps receiving while the camera stops, so that what
    // it still sends is taken; it is released whatever happens.
    try {
        halt_camera(true);
    } catch (const error &) {
        release_stream();
        if (gone()) {
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
    release_stream();
}

bool genicam_camera::next(unsigned timeout_ms, raw_frame &out) {
    check_link(false);
    if (!streaming_)
        raise(FLT_ERR_STATE, "the camera is not streaming; call flt_source_start()");
    return next_frame(timeout_ms, out);
}

std::uint64_t genicam_camera::count(flt_source_counter which) const {
    return acc_[which] + transport_count(which);
}

// --- camera_device ------------------------------------------------------------------

const std::string &genicam_camera::string_of(flt_camera_string which) const {
    return strings_[std::size_t(which)];
}

std::uint64_t genicam_camera::value_of(flt_camera_value which) const {
    switch (which) {
        case FLT_CAMERA_XML_BYTES:
            return xml_bytes_;
        case FLT_CAMERA_XML_ZIPPED:
            return xml_zipped_ ? 1 : 0;
        default:
            break;
    }
    std::uint64_t v = 0;
    if (transport_value(which, v))
        return v;
    raise(FLT_ERR_INVALID_ARGUMENT, "argument 'which' = %d is no value of a %s camera", int(which),
          transport_);
}

std::int64_t genicam_camera::get_int(const std::string &feature) {
    return features_->get_int(feature);
}
void genicam_camera::set_int(const std::string &feature, std::int64_t value) {
    features_->set_int(feature, value);
}
double genicam_camera::get_float(const std::string &feature) {
    return features_->get_float(feature);
}
void genicam_camera::set_float(const std::string &feature, double value) {
    features_->set_float(feature, value);
}
void genicam_camera::set_enum(const std::string &feature, const std::string &entry) {
    features_->set_enum(feature, entry);
}
void genicam_camera::execute(const std::string &feature) {
    features_->execute(feature);
}
void genicam_camera::map_feature(const std::string &feature, std::uint64_t address,
                                 std::uint32_t length, bool is_float) {
    features_->map_feature(feature, address, length, is_float);
}
void genicam_camera::read_memory(std::uint64_t address, std::uint8_t *out, std::size_t bytes) {
    control().read(address, out, bytes);
}
void genicam_camera::write_memory(std::uint64_t address, const std::uint8_t *in,
                                  std::size_t bytes) {
    control().write(address, in, bytes);
}

}  // namespace flt::sources
