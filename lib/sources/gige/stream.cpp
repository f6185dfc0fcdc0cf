// SPDX-License-Identifier: Apache-2.0
// GVSP frame assembly with packet resends (see stream.hpp). A frame is the
// packets 0 (leader), 1..n (payload, packet_size - 36 bytes each but the
// last) and n + 1 (trailer) of one block id. Up to gige_assembly_frames
// frames are assembled at once, so packets of the next frame may arrive before the
// resent ones of this frame; frames leave in block order. A packet is known
// missing when a later packet of its frame, or a packet of a later frame,
// has arrived and the socket holds nothing more (so a packet merely
// overtaken on the way is not asked for), or when its frame has been silent
// for the resend timeout. A missing packet is asked for again (PACKETRESEND)
// at most gige_resend_attempts times, gige_resend_timeout apart; a frame
// still missing packets after that is dropped, never delivered damaged.
#include "sources/gige/stream.hpp"

#include <algorithm>
#include <cstring>

#include "core/error.hpp"
#include "sources/gige/protocol.hpp"
#include "sources/u3v/protocol.hpp"

namespace flt::gige {

using sources::raise;

namespace {

constexpr std::uint32_t k_min_packet = 576, k_max_packet = 9000;
constexpr unsigned k_test_packet_wait_ms = 150;
// Sequence number of the first block seen: room below for late packets of
// blocks sent before it.
constexpr std::uint64_t k_first_seq = std::uint64_t(1) << 20;

std::string block_text(std::uint16_t block) {
    return "block " + std::to_string(block);
}

// Distance from block id `from` to `to` in the 16-bit id space without 0.
int block_distance(std::uint16_t from, std::uint16_t to) {
    const int a = int(from) - 1, b = int(to) - 1;  // 0..65534
    int d = (b - a) % 65535;
    if (d < 0)
        d += 65535;
    return d < 32768 ? d : d - 65535;
}

}  // namespace

stream_channel::stream_channel(control_channel &control, sources::frame_accounting &acc,
                               const stream_config &config)
    : control_(control), acc_(acc), config_(config) {
    socket_ = std::make_unique<udp_socket>();
    socket_->bind(control_.host_address(), 0);
    host_port_ = socket_->local().port;
    granted_buffer_ = socket_->set_receive_buffer(config_.socket_buffer);
    packet_.resize(65536);
}

void stream_channel::aim() {
    control_.write_register(bootstrap::scda, control_.host_address());
    control_.write_register(bootstrap::scp, host_port_);
}

std::uint32_t stream_channel::negotiate_packet_size() {
    aim();
    const std::uint32_t current =
        control_.read_register(bootstrap::scps) & bootstrap::scps_size_mask;
    std::uint32_t chosen = current;
    if (config_.packet_size != 0) {
        chosen = config_.packet_size;
    } else {
        // Does a test packet of `size` bytes reach us?
        auto fits = [&](std::uint32_t size) {
            std::size_t got = 0;
            while (socket_->receive(packet_.data(), packet_.size(), got, nullptr, 0)) {
            }
            control_.write_register(bootstrap::scps, bootstrap::scps_fire_test |
                                                         bootstrap::scps_do_not_fragment | size);
            const auto deadline = clock::now() + std::chrono::milliseconds(k_test_packet_wait_ms);
            for (;;) {
                const auto left =
                    std::chrono::duration_cast<std::chrono::milliseconds>(deadline - clock::now());
                if (left.count() <= 0)
                    return false;
                if (socket_->receive(packet_.data(), packet_.size(), got, nullptr,
                                     unsigned(left.count())) &&
                    got == size - k_ip_udp_overhead)
                    return true;
            }
        };
        if (fits(k_min_packet)) {
            std::uint32_t lo = k_min_packet, hi = k_max_packet + 4;  // lo fits, hi does not
            if (fits(k_max_packet))
                lo = k_max_packet;
            while (hi - lo > 4) {
                const std::uint32_t mid = (lo + (hi - lo) / 2) & ~3u;
                if (fits(mid))
                    lo = mid;
                else
                    hi = mid;
            }
            chosen = lo;
        }
        // else: no test packets; the camera's own packet size stays.
    }
    if (chosen < k_min_packet || chosen > 0xFFFF)
        raise(FLT_ERR_DEVICE, "the stream packet size would be %u bytes (camera: %u)", chosen,
              current);
    control_.write_register(bootstrap::scps, bootstrap::scps_do_not_fragment | chosen);
    packet_size_ = chosen;
    return chosen;
}

void stream_channel::prepare(std::uint32_t width, std::uint32_t height, std::uint32_t pfnc,
                             bool resend) {
    if (packet_size_ == 0)
        negotiate_packet_size();
    bits_ = u3v::pfnc_bits(pfnc);
    width_ = width;
    height_ = height;
    pfnc_ = pfnc;
    payload_ = std::uint64_t(width) * height * (bits_ > 8 ? 2 : 1);
    data_bytes_ = packet_size_ - std::uint32_t(k_gvsp_overhead);
    data_packets_ = std::uint32_t((payload_ + data_bytes_ - 1) / data_bytes_);
    resend_ = resend && config_.resend_attempts > 0;
    const std::size_t ids = std::size_t(data_packets_) + 2;
    slots_.assign(std::size_t(std::max(config_.assembly_frames, 2u)) + 1, slot());
    for (slot &s : slots_) {
        s.data.assign(std::size_t(payload_), 0);
        s.got.assign(ids, 0);
        s.attempts.assign(ids, 0);
        s.asked.assign(ids, clock::time_point());
    }
    have_newest_ = have_final_ = false;
    std::size_t got = 0;
    while (socket_->receive(packet_.data(), packet_.size(), got, nullptr, 0)) {
        // packets of an earlier stream
    }
    aim();
}

void stream_channel::release() noexcept {
    try {
        control_.write_register(bootstrap::scp, 0);
    } catch (...) {
        // The camera stops streaming with the acquisition anyway.
    }
    for (slot &s : slots_)
        s.state = slot_state::free;
}

stream_channel::slot *stream_channel::oldest() {
    slot *best = nullptr;
    for (slot &s : slots_)
        if (s.state == slot_state::open && (!best || s.seq < best->seq))
            best = &s;
    return best;
}

void stream_channel::drop(slot &s, flt_source_counter reason, const std::string &why) {
    acc_.drop(reason, block_text(s.block) + ": " + why);
    if (!have_final_ || s.seq > final_seq_) {
        if (have_final_ && s.seq > final_seq_ + 1)
            acc_.add(FLT_COUNT_LOST, s.seq - final_seq_ - 1);
        final_seq_ = s.seq;
        have_final_ = true;
    }
    s.state = slot_state::free;
}

stream_channel::slot *stream_channel::slot_for(std::uint16_t block, clock::time_point now) {
    std::uint64_t seq = 0;
    if (!have_newest_) {
        seq = k_first_seq;
        first_block_ = block;
        have_newest_ = true;
        newest_block_ = block;
        newest_seq_ = seq;
    } else {
        const int d = block_distance(newest_block_, block);
        if (d < 0 && std::uint64_t(-d) >= newest_seq_)
            return nullptr;
        seq = std::uint64_t(std::int64_t(newest_seq_) + d);
        if (d > 0) {
            newest_block_ = block;
            newest_seq_ = seq;
        }
    }
    for (slot &s : slots_)
        if (s.state == slot_state::open && s.seq == seq)
            return &s;
    if (have_final_ && seq <= final_seq_)
        return nullptr;  // a frame already delivered or dropped
    // A new frame: take a free slot, or drop the oldest open one.
    slot *free_slot = nullptr;
    for (slot &s : slots_)
        if (s.state == slot_state::free)
            free_slot = &s;
    if (!free_slot) {
        slot *old = oldest();
        if (!old || old->seq > seq)
            return nullptr;  // older than every frame in assembly
        drop(*old, FLT_COUNT_INCOMPLETE,
             "packets still missing when " + std::to_string(slots_.size() - 1) +
                 " later frames were in assembly (raise gige_assembly_frames, lower "
                 "gige_resend_timeout, or look at the network)");
        free_slot = old;
    }
    slot &s = *free_slot;
    s.state = slot_state::open;
    s.block = block;
    s.seq = seq;
    std::fill(s.got.begin(), s.got.end(), 0);
    std::fill(s.attempts.begin(), s.attempts.end(), 0);
    s.received = s.highest = 0;
    s.leader = s.trailer = s.given_up = false;
    s.fault = FLT_COUNT_FRAMES;
    s.why.clear();
    s.last_packet = now;
    return &s;
}

void stream_channel::handle(const std::uint8_t *p, std::size_t bytes, clock::time_point now) {
    if (bytes < k_gvsp_header) {
        acc_.add(FLT_COUNT_BAD_PACKETS);
        return;
    }
    const std::uint16_t status = get_be16(p), block = get_be16(p + 2);
    const std::uint8_t format = p[4] & 0x7F;
    const std::uint32_t id = get_be32(p + 4) & 0xFFFFFFu;
    if ((p[4] & 0x80) || block == 0 || id > last_packet_id()) {
        acc_.add(FLT_COUNT_BAD_PACKETS);  // extended ids, a test packet, noise
        return;
    }
    slot *s = slot_for(block, now);
    if (!s) {
        ++duplicates_;  // a late copy for a frame that is gone
        return;
    }
    s->last_packet = now;
    if (status != 0) {
        // The camera cannot deliver this packet (e.g. 0x800C: no longer in
        // its memory): the frame cannot be completed.
        if (!s->given_up) {
            s->given_up = true;
            s->fault = FLT_COUNT_INCOMPLETE;
            s->why = "the camera answered status 0x" + std::to_string(status) + " for packet " +
                     std::to_string(id);
        }
        return;
    }
    if (s->got[id]) {
        ++duplicates_;
        return;
    }
    const std::size_t body = bytes - k_gvsp_header;
    const std::uint8_t *d = p + k_gvsp_header;
    if (id == 0) {
        if (format != k_format_leader || body < k_image_leader_bytes ||
            get_be16(d + 2) != k_payload_image) {
            s->fault = FLT_COUNT_BAD_LEADERS;
            s->why = "the leader is no image leader";
        } else {
            s->timestamp = (std::uint64_t(get_be32(d + 4)) << 32) | get_be32(d + 8);
            s->pfnc = get_be32(d + 12);
            s->width = get_be32(d + 16);
            s->height = get_be32(d + 20);
            if (s->pfnc != pfnc_ || s->width != width_ || s->height != height_) {
                s->fault = FLT_COUNT_BAD_LEADERS;
                s->why = "the leader announces " + std::to_string(s->width) + " x " +
                         std::to_string(s->height) + " px of format " + std::to_string(s->pfnc) +
                         ", the stream was set up for " + std::to_string(width_) + " x " +
                         std::to_string(height_) + " px of " + std::to_string(pfnc_);
            }
        }
        s->leader = true;
    } else if (id == last_packet_id()) {
        if (format != k_format_trailer || body < k_trailer_bytes) {
            s->fault = FLT_COUNT_SHORT;
            s->why = "the trailer is malformed";
        }
        s->trailer = true;
    } else {
        const std::uint64_t offset = std::uint64_t(id - 1) * data_bytes_;
        const std::size_t expected =
            std::size_t(std::min<std::uint64_t>(data_bytes_, payload_ - offset));
        if (format != k_format_payload || body != expected) {
            s->fault = FLT_COUNT_OVERFLOW;
            s->why = "payload packet " + std::to_string(id) + " holds " + std::to_string(body) +
                     " bytes, " + std::to_string(expected) + " expected";
        } else {
            std::memcpy(s->data.data() + offset, d, body);
        }
    }
    s->got[id] = 1;
    ++s->received;
    s->highest = std::max(s->highest, id);
    if (s->attempts[id] > 0)
        ++resent_;
}

void stream_channel::request_missing(clock::time_point now) {
    const auto timeout = std::chrono::milliseconds(std::max(config_.resend_timeout_ms, 1u));
    for (slot &s : slots_) {
        if (s.state != slot_state::open || s.given_up || s.fault != FLT_COUNT_FRAMES)
            continue;
        // Packets up to `known` are missing if not here: the frame's last
        // packet when a later frame has begun or the frame fell silent,
        // else the highest packet seen.
        const bool over = s.seq < newest_seq_ || now - s.last_packet >= timeout;
        const std::uint32_t known = over ? last_packet_id() : s.highest;
        std::uint32_t run_first = 0, run_last = 0;
        bool in_run = false;
        auto flush = [&] {
            if (in_run)
                control_.request_resend(s.block, run_first, run_last);
            in_run = false;
        };
        for (std::uint32_t id = 0; id <= known; ++id) {
            if (s.got[id])
                continue;
            bool ask = false;
            if (s.attempts[id] == 0) {
                ++missing_;
                ask = true;
            } else if (now - s.asked[id] >= timeout) {
                ask = true;
            }
            if (!ask)
                continue;
            if (!resend_ || s.attempts[id] >= config_.resend_attempts) {
                s.given_up = true;
                s.fault = FLT_COUNT_INCOMPLETE;
                s.why = resend_ ? "packet " + std::to_string(id) + " still missing after " +
                                      std::to_string(config_.resend_attempts) + " resend request(s)"
                                : "packet " + std::to_string(id) +
                                      " lost (the camera does not resend packets)";
                if (s.attempts[id] == 0)
                    s.attempts[id] = 1;  // counted missing once
                break;
            }
            ++s.attempts[id];
            s.asked[id] = now;
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

bool stream_channel::finalize(sources::raw_frame &out) {
    for (;;) {
        slot *s = oldest();
        if (!s)
            return false;
        const bool complete = s->received == last_packet_id() + 1;
        // A damaged frame (a bad leader, a packet of the wrong size) goes
        // as soon as it is whole or a later frame has begun: no resends.
        if (s->given_up || (s->fault != FLT_COUNT_FRAMES && (complete || s->seq < newest_seq_))) {
            drop(*s, s->fault == FLT_COUNT_FRAMES ? FLT_COUNT_INCOMPLETE : s->fault, s->why);
            continue;
        }
        if (!complete)
            return false;  // the oldest frame is still coming
        if (have_final_ && s->seq > final_seq_ + 1)
            acc_.add(FLT_COUNT_LOST, s->seq - final_seq_ - 1);
        final_seq_ = s->seq;
        have_final_ = true;
        s->state = slot_state::lent;
        acc_.add(FLT_COUNT_FRAMES);
        out.pixels = s->data.data();
        out.width = width_;
        out.height = height_;
        out.stride = std::size_t(width_) * (bits_ > 8 ? 2 : 1);
        out.format = flt_pixel_format(bits_);
        // The 16-bit block id unwrapped (65535 is followed by 65536, the
        // camera's 1), so block ids keep counting frames (encoder mode 1).
        out.block_id = first_block_ + (s->seq - k_first_seq);
        out.timestamp_ns = s->timestamp;
        return true;
    }
}

bool stream_channel::next(unsigned timeout_ms, sources::raw_frame &out) {
    for (slot &s : slots_)
        if (s.state == slot_state::lent)
            s.state = slot_state::free;
    const auto deadline = clock::now() + std::chrono::milliseconds(timeout_ms);
    const auto check = std::chrono::milliseconds(std::max(config_.resend_timeout_ms, 1u));
    for (;;) {
        if (finalize(out))
            return true;
        const auto now = clock::now();
        if (now >= deadline) {
            acc_.add(FLT_COUNT_TIMEOUTS);
            raise(FLT_ERR_TIMEOUT, "no complete frame within %u ms", timeout_ms);
        }
        const auto wait =
            std::min(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now),
                     std::chrono::duration_cast<std::chrono::milliseconds>(check));
        std::size_t got = 0;
        unsigned wait_ms = unsigned(std::max<long long>(wait.count(), 1));
        // Everything the socket holds, then the gaps it leaves.
        for (unsigned n = 0; n < 4096; ++n) {
            if (!socket_->receive(packet_.data(), packet_.size(), got, nullptr, wait_ms))
                break;
            handle(packet_.data(), got, clock::now());
            wait_ms = 0;
        }
        request_missing(clock::now());
    }
}

std::uint64_t stream_channel::count(int which) const {
    switch (which) {
        case FLT_COUNT_PACKETS_MISSING:
            return missing_;
        case FLT_COUNT_RESEND_REQUESTS:
            return requested_;
        case FLT_COUNT_PACKETS_RESENT:
            return resent_;
        case FLT_COUNT_PACKETS_DUPLICATE:
            return duplicates_;
        default:
            return 0;
    }
}

}  // namespace flt::gige
