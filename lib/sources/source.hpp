// SPDX-License-Identifier: Apache-2.0
// Internal: the interface every kind of frame source implements behind the
// one public handle, flt_source (source_api.cpp). One implementation per
// kind, each in its folder: sim/ (the simulator), images/ (recorded image
// sequences), u3v/ (USB3 Vision cameras) and gige/ (GigE Vision cameras),
// the last two over the camera base in camera/.
//
// The public face keeps what is common to every kind: argument checks, the
// started/stopped state, the borrowed flt_frame, and the encoder position
// of each frame (encoder.hpp). An implementation delivers raw frames,
// counts what happens to them, and, for a camera, offers camera_device.
// Errors are thrown as flt::error (core/error.hpp); the C API's guard turns
// them into a status and a message prefixed with the function's name.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>

#include "core/error.hpp"
#include "flatline/source.h"

namespace flt::sources {

// Throws flt::error(status) with a printf-style message (at most 400 bytes).
[[noreturn]] void raise(flt_status status, const char *format, ...) FLT_PRINTF_FORMAT(2, 3);

struct recorded_frame;  // recording/recording_source.hpp

// One frame as a source kind delivers it; the pixels are borrowed until
// the kind's next call of next(), stop() or its destruction.
struct raw_frame {
    const void *pixels = nullptr;
    std::size_t bytes = 0;  // the size of the buffer `pixels` lies in
    std::uint32_t width = 0, height = 0;
    std::size_t stride = 0;  // bytes per row
    flt_pixel_format format = FLT_PIXEL_MONO8;
    std::uint64_t block_id = 0;
    std::uint64_t timestamp_ns = 0;
    // The kind's own strip position, mm (the simulator's, an image CSV's);
    // NaN when it has none: encoder mode 0 then follows the fixed step.
    double own_encoder_mm = std::numeric_limits<double>::quiet_NaN();
    // A camera's encoder count appended as a chunk (encoder mode 3).
    bool has_chunk_counter = false;
    std::uint64_t chunk_counter = 0;
    unsigned chunk_counter_bytes = 0;  // 4 (wraps) or 8
    // A recording's frame: its profile row and the events before it.
    const recorded_frame *recorded = nullptr;
};

class camera_device;

// One kind of source. Not thread-safe (the public handle is not either).
class source_impl {
  public:
    virtual ~source_impl() = default;
    virtual flt_source_kind kind() const = 0;
    // Frames may carry an encoder chunk (encoder mode 3): cameras.
    virtual bool has_chunks() const { return false; }

    // Starts delivering frames. Throws on failure; the source is then
    // stopped (a camera that may still stream is stopped by the next
    // start() or stop()).
    virtual void start() = 0;
    // Stops delivering frames. The host side is stopped whatever happens;
    // throws when the device could not be stopped (it may still stream).
    virtual void stop() = 0;
    // The next good frame within timeout_ms: true with `out` filled, false
    // at the end of a finite sequence. Throws flt::error(FLT_ERR_TIMEOUT)
    // when none came in time, other statuses for other failures.
    virtual bool next(unsigned timeout_ms, raw_frame &out) = 0;

    // Frame accounting (flt_source_counter), since creation.
    virtual std::uint64_t count(flt_source_counter which) const = 0;
    // Why the last frame was dropped or lost ("" if none was).
    virtual const std::string &stream_error() const;

    // The camera behind the source, or nullptr for a kind that is none.
    virtual camera_device *camera() { return nullptr; }
};

// What a camera offers whatever its transport (USB3 Vision, GigE Vision;
// camera/camera.hpp implements it once for both): its identity, values of its protocol, GenICam
// features by name and raw register access. Features and registers throw flt::error.
class camera_device {
  public:
    virtual ~camera_device() = default;
    virtual const std::string &string_of(flt_camera_string which) const = 0;
    // FLT_ERR_INVALID_ARGUMENT (thrown) for a value the transport lacks.
    virtual std::uint64_t value_of(flt_camera_value which) const = 0;

    virtual std::int64_t get_int(const std::string &feature) = 0;
    virtual void set_int(const std::string &feature, std::int64_t value) = 0;
    virtual double get_float(const std::string &feature) = 0;
    virtual void set_float(const std::string &feature, double value) = 0;
    virtual void set_enum(const std::string &feature, const std::string &entry) = 0;
    virtual void execute(const std::string &feature) = 0;
    virtual void map_feature(const std::string &feature, std::uint64_t address,
                             std::uint32_t length, bool is_float) = 0;

    virtual void read_memory(std::uint64_t address, std::uint8_t *out, std::size_t bytes) = 0;
    virtual void write_memory(std::uint64_t address, const std::uint8_t *in, std::size_t bytes) = 0;
};

}  // namespace flt::sources
