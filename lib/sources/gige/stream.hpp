// SPDX-License-Identifier: Apache-2.0
// Internal: the GigE Vision stream channel - the packet size (negotiated
// with test packets), the host socket the camera streams to, and frame
// assembly from GVSP leader / payload / trailer packets with resend
// requests for lost packets, in block order, counted into the camera's
// frame accounting.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sources/accounting.hpp"
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

class stream_channel {
  public:
    stream_channel(control_channel &control, sources::frame_accounting &acc,
                   const stream_config &config);

    // The largest packet size (bytes of IP packet: IP + UDP + GVSP headers
    // + data) that reaches the host: with the option set, that value; else
    // test packets (SCPS "fire test packet", do not fragment) from 576 to
    // 9000 bytes, halving the interval; a camera that sends none keeps its
    // own packet size. Writes the result to SCPS.
    std::uint32_t negotiate_packet_size();

    // Points the camera's stream channel at the host socket (SCDA, SCP).
    void aim();
    // Sets up a stream of width x height frames of `pfnc` (Mono8..16): the
    // frame slots, and the camera's stream channel aimed at the host socket.
    // `resend` = the camera resends packets.
    void prepare(std::uint32_t width, std::uint32_t height, std::uint32_t pfnc, bool resend);
    // Closes the host side (SCP = 0 first, errors ignored).
    void release() noexcept;

    bool next(unsigned timeout_ms, sources::raw_frame &out);

    std::uint32_t packet_size() const { return packet_size_; }
    std::uint16_t host_port() const { return host_port_; }
    std::uint64_t payload_bytes() const { return payload_; }
    int socket_buffer() const { return granted_buffer_; }
    // GigE counters this channel keeps (PACKETS_*, RESEND_REQUESTS).
    std::uint64_t count(int which) const;

  private:
    using clock = std::chrono::steady_clock;
    enum class slot_state { free, open, lent };
    struct slot {
        slot_state state = slot_state::free;
        std::uint16_t block = 0;
        std::uint64_t seq = 0;  // block ids unwrapped (16-bit ids skip 0)
        std::vector<std::uint8_t> data;
        std::vector<std::uint8_t> got, attempts;  // per packet id
        std::vector<clock::time_point> asked;     // last request per packet id
        std::uint32_t received = 0, highest = 0;
        clock::time_point last_packet;
        bool leader = false, trailer = false, given_up = false;
        flt_source_counter fault = FLT_COUNT_FRAMES;  // != FRAMES: why it is dropped
        std::string why;
        std::uint32_t width = 0, height = 0, pfnc = 0;
        std::uint64_t timestamp = 0;
    };

    void handle(const std::uint8_t *p, std::size_t bytes, clock::time_point now);
    slot *slot_for(std::uint16_t block, clock::time_point now);
    slot *oldest();
    bool finalize(sources::raw_frame &out);
    void request_missing(clock::time_point now);
    void drop(slot &s, flt_source_counter reason, const std::string &why);
    std::uint32_t last_packet_id() const { return data_packets_ + 1; }

    control_channel &control_;
    sources::frame_accounting &acc_;
    stream_config config_;
    std::unique_ptr<udp_socket> socket_;
    std::uint32_t packet_size_ = 0;
    std::uint16_t host_port_ = 0;
    int granted_buffer_ = 0;
    std::uint32_t width_ = 0, height_ = 0, pfnc_ = 0;
    int bits_ = 0;
    std::uint64_t payload_ = 0;
    std::uint32_t data_bytes_ = 0;    // payload bytes per data packet
    std::uint32_t data_packets_ = 0;  // data packets per frame
    bool resend_ = false;
    std::vector<slot> slots_;
    std::vector<std::uint8_t> packet_;
    bool have_newest_ = false;
    std::uint16_t newest_block_ = 0;
    std::uint64_t newest_seq_ = 0;
    std::uint64_t first_block_ = 0;  // block id of the first block seen
    bool have_final_ = false;
    std::uint64_t final_seq_ = 0;  // the last block delivered or dropped
    std::uint64_t missing_ = 0, requested_ = 0, resent_ = 0, duplicates_ = 0;
};

}  // namespace flt::gige
