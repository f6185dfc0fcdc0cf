// SPDX-License-Identifier: Apache-2.0
// GVSP frame assembly (see assembly.hpp for the rules). A frame is the
// packets 0 (leader), 1..n (payload, packet size - 36 bytes each but the
// last) and n + 1 (trailer) of one block id.
#include "sources/gige/assembly.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "core/error.hpp"
#include "sources/gige/protocol.hpp"

namespace flt::gige {

namespace {

// Sequence number of the first frame opened: room below for the blocks of
// a window before it.
constexpr std::uint64_t k_first_seq = std::uint64_t(1) << 20;

// Distance from block id `from` to `to` in the 16-bit id space without 0.
int block_distance(std::uint16_t from, std::uint16_t to) {
    const int a = int(from) - 1, b = int(to) - 1;  // 0..65534
    int d = (b - a) % 65535;
    if (d < 0)
        d += 65535;
    return d < 32768 ? d : d - 65535;
}

std::string block_text(std::uint16_t block) {
    return "block " + std::to_string(block);
}

// A slot taken for a new frame or early packets starts empty.
void reset_slot(std::vector<std::uint8_t> &got, std::vector<std::uint8_t> &attempts,
                std::vector<std::chrono::steady_clock::time_point> &noticed) {
    std::fill(got.begin(), got.end(), 0);
    std::fill(attempts.begin(), attempts.end(), 0);
    std::fill(noticed.begin(), noticed.end(), std::chrono::steady_clock::time_point());
}

std::string hex16(unsigned v) {
    char text[8];
    std::snprintf(text, sizeof text, "0x%04x", v & 0xFFFFu);
    return text;
}

}  // namespace

std::uint64_t frame_assembler::slot_bytes(const sources::frame_geometry &g,
                                          std::uint32_t data_bytes) {
    const std::uint64_t ids = (g.image_bytes + data_bytes - 1) / data_bytes + 2;
    const std::uint64_t per_id =
        2 + sizeof(clock::time_point) + sizeof(std::uint64_t);  // got, attempts, noticed
    return g.image_bytes + ids * per_id + sizeof(slot);
}

void frame_assembler::prepare(const sources::frame_geometry &g, std::uint32_t data_bytes,
                              std::size_t slots, const assembly_config &config) {
    release();
    geometry_ = g;
    data_bytes_ = data_bytes;
    data_packets_ = std::uint32_t((g.image_bytes + data_bytes - 1) / data_bytes);
    config_ = config;
    config_.resend_timeout_ms = std::max(config_.resend_timeout_ms, 1u);
    window_ = 4 * int(std::max(config_.assembly_frames, 2u));
    const std::size_t ids = std::size_t(data_packets_) + 2;
    slots_.resize(std::max<std::size_t>(slots, 2));
    for (slot &s : slots_) {
        // Not zero-filled: a frame is delivered only when every packet
        // wrote its part, and untouched pages cost no memory.
        s.data.reset(new std::uint8_t[std::size_t(g.image_bytes)]);
        s.got.assign(ids, 0);
        s.attempts.assign(ids, 0);
        s.noticed.assign(ids, clock::time_point());
        s.noticed_packet.assign(ids, 0);
        s.why.reserve(256);
    }
    packets_ = 0;
    delivered_ = 0;
    have_newest_ = have_final_ = have_candidate_ = false;
}

void frame_assembler::release() noexcept {
    slots_.clear();
    slots_.shrink_to_fit();
}

std::size_t frame_assembler::frames_in_assembly() const {
    std::size_t n = 0;
    for (const slot &s : slots_)
        n += s.state == slot_state::open || s.state == slot_state::early;
    return n;
}

bool frame_assembler::span(std::uint64_t &first, std::uint64_t &last) const {
    if (!have_final_)
        return false;
    first = delivered_id(first_final_);
    last = delivered_id(final_seq_);
    return true;
}

std::uint64_t frame_assembler::delivered_id(std::uint64_t seq) const {
    // The 16-bit block id unwrapped (65535 is followed by 65536, the
    // camera's 1), so block ids keep counting frames (encoder mode 1).
    return first_block_ + (seq - k_first_seq);
}

frame_assembler::slot *frame_assembler::find_open(std::uint64_t seq) {
    for (slot &s : slots_)
        if (s.state == slot_state::open && s.seq == seq)
            return &s;
    return nullptr;
}

frame_assembler::slot *frame_assembler::find_early(std::uint16_t block) {
    for (slot &s : slots_)
        if (s.state == slot_state::early && s.block == block)
            return &s;
    return nullptr;
}

frame_assembler::slot *frame_assembler::free_slot(std::size_t keep_free) {
    slot *found = nullptr;
    std::size_t n = 0;
    for (slot &s : slots_)
        if (s.state == slot_state::free) {
            found = &s;
            ++n;
        }
    return n > keep_free ? found : nullptr;
}

frame_assembler::slot *frame_assembler::oldest() {
    slot *best = nullptr;
    for (slot &s : slots_)
        if (s.state == slot_state::open && (!best || s.seq < best->seq))
            best = &s;
    return best;
}

void frame_assembler::return_lent() {
    for (slot &s : slots_)
        if (s.state == slot_state::lent)
            s.state = slot_state::free;
}

frame_assembler::slot *frame_assembler::open_frame(std::uint16_t block, std::uint64_t seq,
                                                   clock::time_point now) {
    slot *s = find_early(block);
    if (!s)
        s = free_slot(0);
    if (!s) {
        // Assembly is full: the oldest frame makes room, if it is older.
        slot *old = oldest();
        if (!old || old->seq > seq)
            return nullptr;
        drop(*old, FLT_COUNT_INCOMPLETE,
             "packets still missing when " + std::to_string(slots_.size() - 1) +
                 " later frames were in assembly (raise gige_assembly_frames, lower "
                 "gige_resend_timeout, or look at the network)");
        s = old;
    }
    if (s->state != slot_state::early) {
        reset_slot(s->got, s->attempts, s->noticed);
        s->received = s->highest = s->scan_from = 0;
        s->first_packet = now;
        s->fault = FLT_COUNT_FRAMES;
        s->why.clear();
    }
    // An early slot keeps its fault: a packet it took was marked received
    // though its bytes were refused (a payload of the wrong size), and the
    // frame must not be delivered with that part unwritten.
    s->state = slot_state::open;
    s->block = block;
    s->seq = seq;
    s->given_up = false;
    s->last_packet = now;
    return s;
}

void frame_assembler::discard_early(slot &s) {
    // Packets whose leader never came (or came too late): no frame of the
    // stream holds them.
    acc_.add(FLT_COUNT_BAD_PACKETS, s.received);
    s.state = slot_state::free;
}

void frame_assembler::confirm_early(std::uint64_t below_seq) {
    // A leader of a later block confirms the blocks before it: their
    // leaders were lost, their packets are the stream's.
    for (slot &s : slots_) {
        if (s.state != slot_state::early)
            continue;
        const int d = block_distance(newest_block_, s.block);
        if (d > window_ || d < -window_) {
            discard_early(s);
            continue;
        }
        const std::uint64_t seq = std::uint64_t(std::int64_t(newest_seq_) + d);
        if ((have_final_ && seq <= final_seq_) || seq < floor_seq_) {
            discard_early(s);
        } else if (seq < below_seq) {
            // Its fault, if any, stays (see open_frame).
            s.state = slot_state::open;
            s.seq = seq;
            s.given_up = false;
        }
    }
}

void frame_assembler::finalized(std::uint64_t seq) {
    if (have_final_ && seq <= final_seq_)
        return;
    if (have_final_ && seq > final_seq_ + 1) {
        acc_.add(FLT_COUNT_LOST, seq - final_seq_ - 1);
        acc_.stream_error = "block ids " + std::to_string(delivered_id(final_seq_ + 1)) + ".." +
                            std::to_string(delivered_id(seq - 1)) + " never arrived (lost)";
    }
    if (!have_final_)
        first_final_ = seq;
    final_seq_ = seq;
    have_final_ = true;
}

// Camera fault point: a frame of the camera is dropped (the reason goes
// to flt_source_stream_error()).
void frame_assembler::drop(slot &s, flt_source_counter reason, const std::string &why) {
    // The packets it lacks: counted missing now unless they were already
    // (declared and asked for), for a frame dropped for lacking them.
    for (std::size_t id = 0; id < s.got.size() && id <= last_packet_id(); ++id) {
        if (s.got[id])
            continue;
        if (s.attempts[id] > 0) {
            ++given_up_;
        } else if (reason == FLT_COUNT_INCOMPLETE) {
            ++missing_;
            ++given_up_;
        }
    }
    finalized(s.seq);
    acc_.drop(reason, block_text(s.block) + ": " + why);
    s.state = slot_state::free;
}

void frame_assembler::fail_frame(slot &s, flt_source_counter reason, const std::string &why) {
    if (s.fault != FLT_COUNT_FRAMES)
        return;  // the first reason stands
    s.fault = reason;
    s.why = why;
}

bool frame_assembler::leader_fits(const std::uint8_t *body, std::size_t body_bytes,
                                  std::string *why) const {
    if (body_bytes < k_image_leader_bytes ||
        get_be16(body + leader::payload_type) != k_payload_image) {
        if (why)
            *why = "the leader is no image leader";
        return false;
    }
    const std::uint32_t pfnc = get_be32(body + leader::pixel_format);
    const std::uint32_t w = get_be32(body + leader::width), h = get_be32(body + leader::height);
    const unsigned pad_x = get_be16(body + leader::padding_x);
    const unsigned pad_y = get_be16(body + leader::padding_y);
    // The payload the leader announces must be the one negotiated: the
    // same format and size, no padding.
    if (pfnc == geometry_.pfnc && w == geometry_.width && h == geometry_.height && pad_x == 0 &&
        pad_y == 0)
        return true;
    if (why)
        *why = "the leader announces " + std::to_string(w) + " x " + std::to_string(h) + " px of " +
               sources::pfnc_name(pfnc) + " (padding " + std::to_string(pad_x) + ", " +
               std::to_string(pad_y) + "), the stream was set up for " +
               std::to_string(geometry_.width) + " x " + std::to_string(geometry_.height) +
               " px of " + sources::pfnc_name(geometry_.pfnc);
    return false;
}

void frame_assembler::restart(std::uint16_t block) {
    // Camera fault point: the camera's block ids jumped (it restarted its
    // stream, or this host lost more frames than the window holds).
    const std::uint16_t old_block = newest_block_;
    const int d = block_distance(newest_block_, candidate_block_);
    while (slot *s = oldest())
        drop(*s, FLT_COUNT_INCOMPLETE,
             "the camera's block ids jumped to " + std::to_string(candidate_block_) +
                 " before it was complete");
    for (slot &s : slots_)
        if (s.state == slot_state::early)
            discard_early(s);
    // Forward, the ids still count frames: the gap is lost (and encoder
    // positions keep the camera's count); backward (a restart), they go on
    // from the last ones. A sequence no frame was delivered from may have
    // been a stray leader's: its distance counts nothing either.
    const bool forward = d > 0 && delivered_ > 0;
    std::uint64_t seq = newest_seq_ + std::uint64_t(forward ? d : 1);
    if (!forward && have_final_)
        seq = final_seq_ + 1;
    if (have_final_ && seq <= final_seq_)
        seq = final_seq_ + 1;
    // The candidate's own frame: its leader came before the jump was known
    // and was not kept.
    finalized(seq);
    acc_.drop(FLT_COUNT_INCOMPLETE,
              "block ids jumped from " + std::to_string(old_block) + " to " +
                  std::to_string(candidate_block_) + " and " + std::to_string(block) +
                  " (the camera restarted its stream, or more frames than gige_assembly_frames "
                  "x 4 were lost); block " +
                  std::to_string(candidate_block_) + " was not assembled");
    newest_block_ = candidate_block_;
    newest_seq_ = seq;
    floor_seq_ = seq;
    have_candidate_ = false;
    ++restarts_;
}

frame_assembler::packet_kind frame_assembler::far_packet(std::uint16_t block, std::uint32_t id,
                                                         const std::uint8_t *body,
                                                         std::size_t body_bytes) {
    // A leader far from the sequence that the next leader continues is a
    // new sequence; anything else there is no packet of this stream.
    if (id == 0 && body_bytes >= k_image_leader_bytes && leader_fits(body, body_bytes, nullptr)) {
        if (have_candidate_) {
            const int d = block_distance(candidate_block_, block);
            if (d >= 1 && d <= window_) {
                restart(block);
                return packet_kind::opened;  // the caller takes it again
            }
        }
        have_candidate_ = true;
        candidate_block_ = block;
    }
    acc_.add(FLT_COUNT_BAD_PACKETS);
    return packet_kind::bad;
}

frame_assembler::packet_kind frame_assembler::on_packet(const std::uint8_t *p, std::size_t bytes,
                                                        clock::time_point now) {
    ++packets_;
    if (bytes < k_gvsp_header || slots_.empty()) {
        acc_.add(FLT_COUNT_BAD_PACKETS);
        return packet_kind::bad;
    }
    const std::uint16_t status = get_be16(p), block = get_be16(p + 2);
    const std::uint8_t format = p[4] & 0x7F;
    const std::uint32_t id = get_be32(p + 4) & 0xFFFFFFu;
    if ((p[4] & 0x80) || block == 0 || id > last_packet_id()) {
        acc_.add(FLT_COUNT_BAD_PACKETS);  // extended ids, a test packet, noise
        return packet_kind::bad;
    }
    const std::uint8_t *body = p + k_gvsp_header;
    const std::size_t body_bytes = bytes - k_gvsp_header;
    const bool is_leader = id == 0 && status == 0 && format == k_format_leader;

    if (!have_newest_) {
        if (is_leader) {
            // The first frame of the stream.
            slot *s = open_frame(block, k_first_seq, now);
            if (!s) {
                acc_.add(FLT_COUNT_BAD_PACKETS);
                return packet_kind::bad;
            }
            have_newest_ = true;
            newest_block_ = block;
            newest_seq_ = k_first_seq;
            floor_seq_ = k_first_seq;
            first_block_ = block;
            // Early packets of blocks before it belong to frames this
            // stream began in the middle of.
            for (slot &e : slots_)
                if (e.state == slot_state::early && block_distance(block, e.block) <= 0)
                    discard_early(e);
            store(*s, status, format, id, body, body_bytes, now);
            return packet_kind::opened;
        }
    } else {
        int d = block_distance(newest_block_, block);
        if (d < -window_ && -d <= 4 * window_) {
            // A block this stream passed not long ago: a packet that came
            // very late (delayed, resent twice), never a new sequence; one
            // from before the stream's first frame is no packet of it.
            if (std::int64_t(newest_seq_) + d >= std::int64_t(floor_seq_)) {
                ++duplicates_;
                return packet_kind::duplicate;
            }
            acc_.add(FLT_COUNT_BAD_PACKETS);
            return packet_kind::bad;
        }
        if (d > window_ || d < -window_) {
            if (far_packet(block, id, body, body_bytes) != packet_kind::opened)
                return packet_kind::bad;
            d = block_distance(newest_block_, block);  // after the restart
        }
        const std::uint64_t seq = std::uint64_t(std::int64_t(newest_seq_) + d);
        if (have_final_ && seq <= final_seq_) {
            ++duplicates_;  // a late copy for a frame that is gone
            return packet_kind::duplicate;
        }
        if (seq < floor_seq_) {
            // A block before the stream's first frame (or before a
            // restart): the rest of a frame this stream began inside.
            acc_.add(FLT_COUNT_BAD_PACKETS);
            return packet_kind::bad;
        }
        if (slot *s = find_open(seq))
            return store(*s, status, format, id, body, body_bytes, now);
        if (is_leader || seq < newest_seq_) {
            // A leader opens its frame; a packet of a block before the
            // newest frame is confirmed by that frame's leader (its own
            // leader was lost).
            slot *s = open_frame(block, seq, now);
            if (!s) {
                acc_.add(FLT_COUNT_BAD_PACKETS);  // older than every frame in assembly
                return packet_kind::bad;
            }
            if (seq > newest_seq_) {
                newest_block_ = block;
                newest_seq_ = seq;
                confirm_early(seq);
            }
            if (is_leader)
                have_candidate_ = false;  // the sequence goes on
            const packet_kind k = store(*s, status, format, id, body, body_bytes, now);
            return is_leader && k == packet_kind::taken ? packet_kind::opened : k;
        }
    }
    // A packet ahead of its leader waits for it (within the reorder window),
    // in a slot of its own while one more stays free for the next leader.
    slot *e = find_early(block);
    if (!e) {
        e = free_slot(1);
        if (!e) {
            acc_.add(FLT_COUNT_BAD_PACKETS);
            return packet_kind::bad;
        }
        reset_slot(e->got, e->attempts, e->noticed);
        e->state = slot_state::early;
        e->block = block;
        e->received = e->highest = e->scan_from = 0;
        e->fault = FLT_COUNT_FRAMES;
        e->given_up = false;
        e->why.clear();
        e->first_packet = now;
    }
    return store(*e, status, format, id, body, body_bytes, now);
}

frame_assembler::packet_kind frame_assembler::store(slot &s, std::uint16_t status,
                                                    std::uint8_t format, std::uint32_t id,
                                                    const std::uint8_t *body,
                                                    std::size_t body_bytes, clock::time_point now) {
    s.last_packet = now;
    if (status != 0) {
        // The camera cannot deliver this packet (e.g. 0x800C: no longer in
        // its memory): the frame cannot be completed.
        if (s.state == slot_state::early) {
            acc_.add(FLT_COUNT_BAD_PACKETS);
            return packet_kind::bad;
        }
        if (!s.given_up && s.fault == FLT_COUNT_FRAMES) {
            fail_frame(s, FLT_COUNT_INCOMPLETE,
                       "the camera answered status " + hex16(status) + " for packet " +
                           std::to_string(id));
            s.given_up = true;
        }
        return packet_kind::taken;
    }
    const std::uint32_t last = last_packet_id();
    if (s.got[id]) {
        // A copy of a packet already here: the same bytes (a resend that
        // crossed the original), or one of the two is not the camera's.
        bool same = false;
        if (id == 0) {
            same = body_bytes >= s.leader.size() &&
                   std::memcmp(body, s.leader.data(), s.leader.size()) == 0;
        } else if (id == last) {
            same = body_bytes >= s.trailer.size() &&
                   std::memcmp(body, s.trailer.data(), s.trailer.size()) == 0;
        } else {
            const std::uint64_t offset = std::uint64_t(id - 1) * data_bytes_;
            const std::size_t expected =
                std::size_t(std::min<std::uint64_t>(data_bytes_, geometry_.image_bytes - offset));
            same =
                s.fault != FLT_COUNT_FRAMES ||
                (body_bytes == expected && std::memcmp(s.data.get() + offset, body, expected) == 0);
        }
        if (same) {
            ++duplicates_;
            return packet_kind::duplicate;
        }
        acc_.add(FLT_COUNT_BAD_PACKETS);
        if (s.state == slot_state::early)
            discard_early(s);
        else
            fail_frame(s, FLT_COUNT_INCOMPLETE,
                       "two different copies of packet " + std::to_string(id) +
                           " arrived; one is not the camera's");
        return packet_kind::bad;
    }
    if (id == 0) {
        std::string why;
        if (format != k_format_leader || !leader_fits(body, body_bytes, &why))
            fail_frame(s, FLT_COUNT_BAD_LEADERS,
                       format != k_format_leader ? "the leader is no image leader" : why);
        const std::size_t n = std::min(body_bytes, s.leader.size());
        std::memcpy(s.leader.data(), body, n);
        std::fill(s.leader.begin() + std::ptrdiff_t(n), s.leader.end(), 0);
        if (body_bytes >= k_image_leader_bytes)
            s.timestamp = (std::uint64_t(get_be32(body + leader::timestamp)) << 32) |
                          get_be32(body + leader::timestamp + 4);
    } else if (id == last) {
        if (format != k_format_trailer || body_bytes < k_trailer_bytes)
            fail_frame(s, FLT_COUNT_SHORT, "the trailer is malformed");
        const std::size_t n = std::min(body_bytes, s.trailer.size());
        std::memcpy(s.trailer.data(), body, n);
        std::fill(s.trailer.begin() + std::ptrdiff_t(n), s.trailer.end(), 0);
    } else {
        const std::uint64_t offset = std::uint64_t(id - 1) * data_bytes_;
        const std::size_t expected =
            std::size_t(std::min<std::uint64_t>(data_bytes_, geometry_.image_bytes - offset));
        if (format != k_format_payload || body_bytes != expected)
            fail_frame(s, FLT_COUNT_OVERFLOW,
                       "payload packet " + std::to_string(id) + " holds " +
                           std::to_string(body_bytes) + " bytes, " + std::to_string(expected) +
                           " expected");
        else
            std::memcpy(s.data.get() + offset, body, expected);
    }
    s.got[id] = 1;
    ++s.received;
    s.highest = std::max(s.highest, id);
    if (s.attempts[id] > 0)
        ++resent_;  // found missing before, here now
    while (s.scan_from <= last && s.got[s.scan_from])
        ++s.scan_from;
    return packet_kind::taken;
}

void frame_assembler::check_missing(clock::time_point now) {
    const auto timeout = std::chrono::milliseconds(config_.resend_timeout_ms);
    const std::uint32_t last = last_packet_id();
    for (slot &s : slots_) {
        if (s.state == slot_state::early) {
            if (now - s.first_packet >= timeout)
                discard_early(s);  // no leader came within the reorder window
            continue;
        }
        if (s.state != slot_state::open || s.given_up)
            continue;
        if (s.fault != FLT_COUNT_FRAMES) {
            // A damaged frame is asked nothing; once it falls silent no
            // packet will mend it: it goes (take() drops it).
            if (now - s.last_packet >= timeout)
                s.given_up = true;
            continue;
        }
        // Packets up to `known` exist: the frame's last one when a later
        // frame has begun or the frame fell silent, else the highest seen.
        const bool silent = now - s.last_packet >= timeout;
        const bool over = s.seq < newest_seq_ || silent;
        const std::uint32_t known = over ? last : s.highest;
        std::uint32_t run_first = 0, run_last = 0;
        bool in_run = false;
        auto flush = [&] {
            if (in_run)
                resend_.request_resend(s.block, run_first, run_last);
            in_run = false;
        };
        for (std::uint32_t id = s.scan_from; id <= known; ++id) {
            if (s.got[id])
                continue;
            if (s.attempts[id] == 0) {
                if (s.noticed[id] == clock::time_point()) {
                    s.noticed[id] = now;  // the gap is seen: the reorder window starts
                    s.noticed_packet[id] = packets_;
                    if (!silent)
                        continue;
                }
                const bool lost = silent || now - s.noticed[id] >= timeout ||
                                  packets_ - s.noticed_packet[id] >= k_reorder_packets;
                if (!lost)
                    continue;
                ++missing_;
            } else if (now - s.noticed[id] < timeout) {
                continue;  // asked; its answer may still come
            }
            if (!config_.resend || s.attempts[id] >= config_.resend_attempts) {
                if (s.attempts[id] == 0)
                    s.attempts[id] = 1;  // counted missing once
                s.given_up = true;
                fail_frame(s, FLT_COUNT_INCOMPLETE,
                           config_.resend
                               ? "packet " + std::to_string(id) + " still missing after " +
                                     std::to_string(config_.resend_attempts) + " resend request(s)"
                               : "packet " + std::to_string(id) +
                                     " lost (the camera does not resend packets)");
                break;
            }
            ++s.attempts[id];
            s.noticed[id] = now;  // now: when it was asked
            ++requested_;
            if (in_run && id == run_last + 1) {
                run_last = id;
            } else {
                flush();
                in_run = true;
                run_first = run_last = id;
            }
        }
        flush();
    }
}

bool frame_assembler::take(sources::raw_frame &out) {
    const std::uint32_t last = last_packet_id();
    for (;;) {
        slot *s = oldest();
        if (!s)
            return false;
        const bool complete = s->received == last + 1;
        // A damaged frame (a bad leader, a packet of the wrong size) goes
        // as soon as it is whole or a later frame has begun: no resends.
        if (s->given_up || (s->fault != FLT_COUNT_FRAMES && (complete || s->seq < newest_seq_))) {
            drop(*s, s->fault == FLT_COUNT_FRAMES ? FLT_COUNT_INCOMPLETE : s->fault, s->why);
            continue;
        }
        if (!complete)
            return false;  // the oldest frame is still coming
        finalized(s->seq);
        s->state = slot_state::lent;
        acc_.add(FLT_COUNT_FRAMES);
        ++delivered_;
        out.pixels = s->data.get();
        out.bytes = std::size_t(geometry_.image_bytes);
        out.width = geometry_.width;
        out.height = geometry_.height;
        out.stride = geometry_.row_bytes;
        out.format = flt_pixel_format(geometry_.bits);
        out.block_id = delivered_id(s->seq);
        out.timestamp_ns = s->timestamp;
        return true;
    }
}

}  // namespace flt::gige
