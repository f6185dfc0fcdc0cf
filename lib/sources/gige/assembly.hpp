// SPDX-License-Identifier: Apache-2.0
// Internal: GVSP frame assembly - GVSP packets in (already known to come
// from the camera), frames out in block order, never damaged, with resend
// requests for lost packets and every packet and frame counted. No socket
// and no clock of its own: the stream channel (stream.hpp) feeds it
// datagrams and the time, and so does the fuzzing harness
// (tests/fuzz/fuzz_gvsp.cpp), which holds it to its invariants.
//
// The rules (README.md of this folder says why):
//   * A frame opens at its leader, for a block id at most `window` ahead
//     of the newest frame (window = 4 x gige_assembly_frames). Packets of
//     a block whose leader has not come yet wait in a slot of their own
//     ("early") for the reorder window; a later leader confirms them (a
//     lost leader), else they are BAD_PACKETS.
//   * A block id further away is a BAD_PACKET, but for one the stream
//     passed not long ago (up to 4 windows behind): a very late packet,
//     PACKETS_DUPLICATE (BAD_PACKETS before the stream's first frame),
//     never a restart. A leader farther away is a candidate camera restart;
//     the next leader continuing it (1 .. window blocks on) confirms the
//     restart: the frames in assembly are dropped, the candidate's frame
//     too, and block ids go on counting from the last ones. A leader of the
//     current sequence clears the candidate.
//   * A packet is missing once a later packet of its frame, or a leader of
//     a later frame, has arrived and then either the reorder window
//     (gige_resend_timeout) has passed or 64 more packets have arrived; or
//     once its frame has been silent for gige_resend_timeout. A packet
//     merely overtaken on the way arrives within that and is no loss.
//   * Two copies of one packet that differ: one is not the camera's, the
//     frame is dropped (INCOMPLETE) and the copy is a BAD_PACKET.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sources/camera/accounting.hpp"
#include "sources/camera/pixel_format.hpp"
#include "sources/source.hpp"

namespace flt::gige {

// Where the assembler's resend requests go (the control channel; the
// fuzzing harness's scripted camera).
class resend_sink {
  public:
    virtual ~resend_sink() = default;
    // Packets first..last of block `block` (a PACKETRESEND command).
    virtual void request_resend(std::uint16_t block, std::uint32_t first, std::uint32_t last) = 0;
};

struct assembly_config {
    bool resend = false;              // the camera resends and resends are asked
    unsigned resend_attempts = 3;     // option gige_resend_attempts
    unsigned resend_timeout_ms = 20;  // option gige_resend_timeout (also the reorder window)
    unsigned assembly_frames = 8;     // option gige_assembly_frames
};

class frame_assembler {
  public:
    using clock = std::chrono::steady_clock;
    // What one datagram was.
    enum class packet_kind { bad, duplicate, taken, opened };

    // Packets a gap must be followed by before it is declared lost (or the
    // reorder window passes first).
    static constexpr std::uint32_t k_reorder_packets = 64;

    frame_assembler(sources::frame_accounting &acc, resend_sink &resend)
        : acc_(acc), resend_(resend) {}

    // The memory frames of `g` in packets of `data_bytes` payload each take
    // in `slots` slots (buffers and per-packet bookkeeping), bytes.
    static std::uint64_t slot_bytes(const sources::frame_geometry &g, std::uint32_t data_bytes);
    // Sets up frames of `g` (checked by the camera base) in packets of
    // `data_bytes` payload each (packet size - 36), in `slots` slots (the
    // caller bounds slots x slot_bytes()); forgets every earlier frame.
    void prepare(const sources::frame_geometry &g, std::uint32_t data_bytes, std::size_t slots,
                 const assembly_config &config);
    // Frees the frame buffers.
    void release() noexcept;

    // One datagram of the camera's stream, received at `now`.
    packet_kind on_packet(const std::uint8_t *p, std::size_t bytes, clock::time_point now);
    // Declares the packets the rules above give up waiting for: asks them
    // again, or gives their frame up.
    void check_missing(clock::time_point now);
    // The oldest frame when it is complete: true with `out` filled (lent
    // until return_lent() or prepare()); drops the frames ahead of it that
    // cannot complete. False while the oldest frame is coming.
    bool take(sources::raw_frame &out);
    // The frame take() lent is done with (the caller's next call).
    void return_lent();

    // The counters the assembler keeps beside the frame accounting.
    std::uint64_t packets_missing() const { return missing_; }
    std::uint64_t resend_requests() const { return requested_; }
    std::uint64_t packets_resent() const { return resent_; }
    std::uint64_t packets_duplicate() const { return duplicates_; }
    // Packets absent from frames that were dropped (the rest of
    // PACKETS_MISSING: missing = resent + given up, once no frame with a
    // declared packet is in assembly).
    std::uint64_t packets_given_up() const { return given_up_; }
    // Frames in assembly (open or early).
    std::size_t frames_in_assembly() const;
    // Block ids (unwrapped, as delivered) of the first and of the last
    // frame delivered or dropped; whether there was one.
    bool span(std::uint64_t &first, std::uint64_t &last) const;
    // Camera restarts confirmed.
    std::uint64_t restarts() const { return restarts_; }
    std::uint32_t last_packet_id() const { return data_packets_ + 1; }
    std::size_t slots() const { return slots_.size(); }

  private:
    enum class slot_state { free, early, open, lent };
    struct slot {
        slot_state state = slot_state::free;
        std::uint16_t block = 0;
        std::uint64_t seq = 0;  // block ids unwrapped (16-bit ids skip 0); open only
        std::unique_ptr<std::uint8_t[]> data;
        std::vector<std::uint8_t> got, attempts;    // per packet id
        std::vector<clock::time_point> noticed;     // gap first seen, then last asked
        std::vector<std::uint64_t> noticed_packet;  // packet count when the gap was seen
        std::uint32_t received = 0, highest = 0, scan_from = 0;
        clock::time_point first_packet, last_packet;
        bool given_up = false;
        flt_source_counter fault = FLT_COUNT_FRAMES;  // != FRAMES: why it is dropped
        std::string why;
        std::array<std::uint8_t, 36> leader{};  // leader body (duplicates compared)
        std::array<std::uint8_t, 8> trailer{};  // trailer body
        std::uint64_t timestamp = 0;
    };

    packet_kind far_packet(std::uint16_t block, std::uint32_t id, const std::uint8_t *body,
                           std::size_t body_bytes);
    void restart(std::uint16_t block);
    bool leader_fits(const std::uint8_t *body, std::size_t body_bytes, std::string *why) const;
    slot *find_open(std::uint64_t seq);
    slot *find_early(std::uint16_t block);
    slot *free_slot(std::size_t keep_free);
    slot *open_frame(std::uint16_t block, std::uint64_t seq, clock::time_point now);
    void confirm_early(std::uint64_t below_seq);
    packet_kind store(slot &s, std::uint16_t status, std::uint8_t format, std::uint32_t id,
                      const std::uint8_t *body, std::size_t body_bytes, clock::time_point now);
    slot *oldest();
    void drop(slot &s, flt_source_counter reason, const std::string &why);
    void discard_early(slot &s);
    void finalized(std::uint64_t seq);
    std::uint64_t delivered_id(std::uint64_t seq) const;
    static void fail_frame(slot &s, flt_source_counter reason, const std::string &why);

    sources::frame_accounting &acc_;
    resend_sink &resend_;
    assembly_config config_;
    sources::frame_geometry geometry_;
    std::uint32_t data_bytes_ = 0;    // payload bytes per data packet
    std::uint32_t data_packets_ = 0;  // data packets per frame
    int window_ = 32;                 // blocks ahead a frame may open
    std::vector<slot> slots_;
    std::uint64_t packets_ = 0;    // packets seen (the reorder window counts them)
    std::uint64_t delivered_ = 0;  // frames delivered since prepare()

    bool have_newest_ = false;
    std::uint16_t newest_block_ = 0;
    std::uint64_t newest_seq_ = 0;
    std::uint64_t first_block_ = 0;  // block id of the first frame opened
    std::uint64_t floor_seq_ = 0;    // no frame before this one (the first, or a restart)
    bool have_final_ = false;
    std::uint64_t first_final_ = 0, final_seq_ = 0;  // delivered or dropped
    bool have_candidate_ = false;                    // a far leader: a camera restart?
    std::uint16_t candidate_block_ = 0;

    std::uint64_t missing_ = 0, requested_ = 0, resent_ = 0, duplicates_ = 0, given_up_ = 0,
                  restarts_ = 0;
};

}  // namespace flt::gige
