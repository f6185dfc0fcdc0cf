// SPDX-License-Identifier: Apache-2.0
// Internal: the GigE Vision stream channel - the packet size (negotiated
// with test packets), the host socket the camera streams to, who may speak
// on it, and the frame assembler (assembly.hpp) it feeds, counted into the
// camera's frame accounting.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <vector>

#include "sources/camera/accounting.hpp"
#include "sources/camera/pixel_format.hpp"
#include "sources/gige/assembly.hpp"
#include "sources/gige/control.hpp"
#include "sources/gige/socket.hpp"
#include "sources/source.hpp"

namespace flt::gige {

struct stream_config {
    unsigned packet_size = 0;         // option gige_packet_size (0: negotiate)
    unsigned resend_attempts = 3;     // option gige_resend_attempts (0: none)
    unsigned resend_timeout_ms = 20;  // option gige_resend_timeout
    int socket_buffer = 4 << 20;      // option gige_socket_buffer, bytes
    unsigned assembly_frames = 8;     // option gige_assembly_frames
};

// Only the camera speaks: a datagram on the stream socket from another
// address than the camera's, or from another port than the camera's
// stream source port, is a BAD_PACKET and goes no further. The port is the
// one the camera reports (SCSP, when its GVSP capability register says it
// has one), else the one the first leader that opens a frame came from.
class stream_channel final : private resend_sink {
  public:
    stream_channel(control_channel &control, sources::frame_accounting &acc,
                   const stream_config &config);

    // The largest packet size (bytes of IP packet: IP + UDP + GVSP headers
    // + data) that reaches the host: with the option set, that value; else
    // test packets (SCPS "fire test packet", do not fragment) from 576 to
    // 9000 bytes, halving the interval; a camera that sends none keeps its
    // own packet size. Writes the result to SCPS.
    std::uint32_t negotiate_packet_size();

    // Sets up the host side for frames of `g` (checked by the camera base):
    // the frame slots (gige_assembly_frames + 1, fewer when that many would
    // take more than sources::k_max_buffer_bytes; FLT_ERR_DEVICE before
    // anything is allocated when not even 2 fit), and which port the camera
    // streams from. `resend` = the camera resends packets.
    void prepare(const sources::frame_geometry &g, bool resend);
    // Points the camera's stream channel at the host socket (SCDA, SCP).
    void aim();
    // SCP = 0 (the channel closed), read back: true when it reads 0.
    bool close_channel();
    // Frees the host side (the frame slots).
    void release() noexcept;

    bool next(unsigned timeout_ms, sources::raw_frame &out);

    std::uint32_t packet_size() const { return packet_size_; }
    std::uint16_t host_port() const { return host_port_; }
    std::uint64_t payload_bytes() const { return payload_; }
    int socket_buffer() const { return granted_buffer_; }
    std::size_t frame_slots() const { return assembler_.slots(); }
    // GigE counters this channel keeps (PACKETS_*, RESEND_REQUESTS).
    std::uint64_t count(int which) const;

  private:
    using clock = std::chrono::steady_clock;
    void request_resend(std::uint16_t block, std::uint32_t first, std::uint32_t last) override;
    // Whether a datagram from `from` is the camera's stream.
    bool from_camera(const endpoint &from) const;

    control_channel &control_;
    sources::frame_accounting &acc_;
    stream_config config_;
    std::unique_ptr<udp_socket> socket_;
    frame_assembler assembler_;
    std::uint32_t packet_size_ = 0;
    std::uint16_t host_port_ = 0;
    int granted_buffer_ = 0;
    std::uint64_t payload_ = 0;
    std::vector<std::uint8_t> packet_;
    bool port_known_ = false;  // the camera's stream source port is known
    std::uint16_t source_port_ = 0;
};

}  // namespace flt::gige
