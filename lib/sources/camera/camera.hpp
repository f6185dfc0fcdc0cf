// SPDX-License-Identifier: Apache-2.0
// Internal: a GenICam camera as a frame source, whatever its transport -
// the one place where a camera's features, its acquisition start and stop,
// TLParamsLocked, the frame bounds and the frame accounting live. USB3
// Vision (../u3v/) and GigE Vision (../gige/) derive from it and implement
// its hooks, as a transport backend does for a device class: the hooks say
// how to reach the camera's stream channel, the base says what to do with
// it and when (README.md of this folder lists the hooks and the contract
// each keeps).
//
// Why one base: the start and stop sequence is where a camera can be left
// streaming while the host believes it stopped. Written once, a fix (a stop
// that says OK only when the camera took it) holds for every transport.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "sources/camera/accounting.hpp"
#include "sources/camera/features.hpp"
#include "sources/camera/pixel_format.hpp"
#include "sources/source.hpp"

namespace flt::sources {

// Every frame buffer a camera source allocates (frame slots, transfer
// pools) together, at most: FLT_SOURCE_MAX_BUFFER_BYTES (1 GiB), whatever
// size the camera asks for (flatline/source.h, "Frame bounds").
constexpr std::uint64_t k_max_buffer_bytes = FLT_SOURCE_MAX_BUFFER_BYTES;

// The longest a command waits on a camera that keeps answering "pending"
// (the camera's pending acknowledges each name a wait, up to 65535 ms; a
// hostile one can send them for ever): 10 s after the first pending
// acknowledge, on top of the control timeout per attempt. The number of
// pending acknowledges is bounded by the transport's option too.
constexpr unsigned k_pending_wait_cap_ms = 10000;

// What a message says when the camera may be left streaming (the tests
// look for it).
constexpr const char *k_may_stream = "may still be streaming";

// `raw` with every byte that would act on a terminal or a log replaced by
// '?': C0 controls (ESC starts a terminal's escape sequence), DEL, the C1
// controls (U+0080..U+009F) and bytes that are not UTF-8. Camera strings
// come from the camera and reach callers who print them.
std::string visible_text(const std::string &raw);

class genicam_camera : public source_impl, public camera_device {
  public:
    ~genicam_camera() override = default;

    // source_impl: the acquisition sequence (README.md of this folder).
    void start() final;
    void stop() final;
    bool next(unsigned timeout_ms, raw_frame &out) final;
    std::uint64_t count(flt_source_counter which) const final;
    const std::string &stream_error() const final { return acc_.stream_error; }
    camera_device *camera() final { return this; }

    // camera_device: features through the GenICam engine and mapped
    // registers; raw memory through the control channel.
    const std::string &string_of(flt_camera_string which) const final;
    std::uint64_t value_of(flt_camera_value which) const final;
    std::int64_t get_int(const std::string &feature) final;
    void set_int(const std::string &feature, std::int64_t value) final;
    double get_float(const std::string &feature) final;
    void set_float(const std::string &feature, double value) final;
    void set_enum(const std::string &feature, const std::string &entry) final;
    void execute(const std::string &feature) final;
    void map_feature(const std::string &feature, std::uint64_t address, std::uint32_t length,
                     bool is_float) final;
    void read_memory(std::uint64_t address, std::uint8_t *out, std::size_t bytes) final;
    void write_memory(std::uint64_t address, const std::uint8_t *in, std::size_t bytes) final;

    // The host side is streaming (start succeeded, no stop since).
    bool streaming() const { return streaming_; }

  protected:
    // `transport` names the camera's kind in messages ("GigE Vision");
    // `halt_rounds`: how often a stop step whose failure is worth retrying
    // is tried again (the transport's command attempts).
    genicam_camera(const char *transport, unsigned halt_rounds);

    // For the derived constructor, in this order once the control channel
    // works: the camera's strings (made visible_text), its description
    // (the engine is built over `port`; registers mapped by address are
    // big-endian when `big_endian`), then recover_stream().
    void set_strings(const std::array<std::string, 7> &strings);
    void load_description(const std::string &xml, std::uint64_t file_bytes, bool zipped,
                          register_port &port, bool big_endian);
    // A camera whose stream channel is on (a process died streaming) is
    // stopped: AcquisitionStop and the channel off (FLT_COUNT_STREAM_
    // RECOVERIES). A failure is left to the next start or stop.
    void recover_stream();
    // For the derived destructor: stop, errors ignored (the hooks are
    // virtual, so the base destructor cannot call them).
    void shutdown() noexcept;

    // --- hooks (README.md of this folder) -----------------------------------
    // The control channel (raw memory access).
    virtual register_port &control() = 0;
    // Throws when the camera cannot be used now (FLT_ERR_DEVICE: unplugged,
    // control privilege lost; with `starting`, also a camera without a
    // stream channel).
    virtual void check_link(bool starting) = 0;
    // The camera is gone for good (unplugged): it streams to no one.
    virtual bool gone() const { return false; }
    // Whether the camera's stream channel is on as far as the camera says
    // (a transport that cannot tell answers false).
    virtual bool channel_enabled() { return false; }
    // Sets up the host side (and the camera's stream set-up registers) for
    // frames of `g`, checked by the base against the frame bounds; allocates
    // the buffers, at most k_max_buffer_bytes in all. The stream channel
    // stays off.
    virtual void prepare_stream(const frame_geometry &g) = 0;
    // Turns the camera's stream channel on (towards the prepared host side).
    virtual void enable_channel() = 0;
    // Turns it off; true once the camera confirms it is off. Throws
    // flt::error for a command that failed.
    virtual bool disable_channel() = 0;
    // Frees the host side's stream (cancels transfers); safe when nothing
    // is prepared.
    virtual void release_stream() noexcept = 0;
    // The next good frame within timeout_ms (source_impl::next); `bytes` of
    // the frame is the size of the buffer its pixels lie in.
    virtual bool next_frame(unsigned timeout_ms, raw_frame &out) = 0;
    // Counters the transport keeps itself (atomics of a heartbeat thread).
    virtual std::uint64_t transport_count(flt_source_counter /*which*/) const { return 0; }
    // A flt_camera_value of the transport; false for one it lacks.
    virtual bool transport_value(flt_camera_value which, std::uint64_t &out) const = 0;

    frame_accounting acc_;     // the transports count into it too
    frame_geometry geometry_;  // of the last start

  private:
    void start_sequence();
    void halt_camera(bool need_acquisition_stop);
    void lock_transport_params(bool locked);

    const char *transport_;
    unsigned halt_rounds_;
    std::array<std::string, 7> strings_;
    std::uint64_t xml_bytes_ = 0;
    bool xml_zipped_ = false;
    std::unique_ptr<feature_layer> features_;
    bool streaming_ = false;  // the host side: the stream is set up
    // The camera may be streaming although the host is not: a stop or start
    // failed between the channel going on and a confirmed stop. The next
    // start or stop stops it first.
    bool may_stream_ = false;
};

}  // namespace flt::sources
