// SPDX-License-Identifier: Apache-2.0
// The GigE Vision stream channel (see stream.hpp): packet-size
// negotiation, the camera's stream channel aimed and closed, the sender
// check, and the receive loop around the frame assembler (assembly.cpp).
#include "sources/gige/stream.hpp"

#include <algorithm>
#include <cstring>

#include "core/error.hpp"
#include "core/log.hpp"
#include "sources/camera/camera.hpp"
#include "sources/gige/protocol.hpp"

namespace flt::gige {

using sources::raise;

namespace {

constexpr std::uint32_t k_min_packet = 576, k_max_packet = 9000;
constexpr unsigned k_test_packet_wait_ms = 150;

}  // namespace

stream_channel::stream_channel(control_channel &control, sources::frame_accounting &acc,
                               const stream_config &config)
    : control_(control), acc_(acc), config_(config), assembler_(acc, *this) {
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
                endpoint from;
                if (socket_->receive(packet_.data(), packet_.size(), got, &from,
                                     unsigned(left.count())) &&
                    got == size - k_ip_udp_overhead && from.address == control_.camera().address)
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

void stream_channel::prepare(const sources::frame_geometry &g, bool resend) {
    release();
    if (packet_size_ == 0)
        negotiate_packet_size();
    const std::uint32_t data_bytes = packet_size_ - std::uint32_t(k_gvsp_overhead);
    // Slots for gige_assembly_frames frames in assembly and the one lent to
    // the caller, bounded in total whatever size the camera asks for.
    const std::uint64_t per_slot = frame_assembler::slot_bytes(g, data_bytes);
    const std::uint64_t fit = sources::k_max_buffer_bytes / per_slot;
    if (fit < 2)
        raise(FLT_ERR_DEVICE,
              "a %u x %u px frame of %s takes %llu bytes a slot; 2 slots would be more than the "
              "%llu a camera source may (FLT_SOURCE_MAX_BUFFER_BYTES); lower Width or Height",
              g.width, g.height, sources::pfnc_name(g.pfnc).c_str(), (unsigned long long)per_slot,
              (unsigned long long)sources::k_max_buffer_bytes);
    const std::size_t slots =
        std::size_t(std::min<std::uint64_t>(std::max(config_.assembly_frames, 2u) + 1, fit));
    assembly_config a;
    a.resend = resend && config_.resend_attempts > 0;
    a.resend_attempts = config_.resend_attempts;
    a.resend_timeout_ms = config_.resend_timeout_ms;
    a.assembly_frames =
        std::max<unsigned>(std::min<std::size_t>(config_.assembly_frames, slots - 1), 1);
    assembler_.prepare(g, data_bytes, slots, a);
    payload_ = g.image_bytes;
    // The camera's stream source port, when it says (GigE Vision 1.1 and
    // later may: SCSP); a camera that has no such register answers with an
    // error status, which only means "no".
    port_known_ = false;
    source_port_ = 0;
    try {
        if (control_.read_register(bootstrap::gvsp_capability) & bootstrap::gvsp_capability_scsp) {
            const std::uint32_t port = control_.read_register(bootstrap::scsp) & 0xFFFFu;
            if (port != 0) {
                port_known_ = true;
                source_port_ = std::uint16_t(port);
            }
        }
    } catch (const error &e) {
        if (e.status != FLT_ERR_DEVICE)
            throw;
    }
    std::size_t got = 0;
    while (socket_->receive(packet_.data(), packet_.size(), got, nullptr, 0)) {
        // packets of an earlier stream
    }
}

bool stream_channel::close_channel() {
    control_.write_register(bootstrap::scp, 0);
    return (control_.read_register(bootstrap::scp) & 0xFFFFu) == 0;
}

void stream_channel::release() noexcept {
    assembler_.release();
}

void stream_channel::request_resend(std::uint16_t block, std::uint32_t first, std::uint32_t last) {
    control_.request_resend(block, first, last);
}

bool stream_channel::from_camera(const endpoint &from) const {
    return from.address == control_.camera().address && (!port_known_ || from.port == source_port_);
}

bool stream_channel::next(unsigned timeout_ms, sources::raw_frame &out) {
    assembler_.return_lent();
    const auto deadline = clock::now() + std::chrono::milliseconds(timeout_ms);
    const auto check = std::chrono::milliseconds(std::max(config_.resend_timeout_ms, 1u));
    for (;;) {
        if (assembler_.take(out))
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
            endpoint from;
            if (!socket_->receive(packet_.data(), packet_.size(), got, &from, wait_ms))
                break;
            wait_ms = 0;
            if (!from_camera(from)) {
                // Camera fault point: a stranger on the stream socket.
                acc_.add(FLT_COUNT_BAD_PACKETS);  // only the camera speaks
                // Said with the sender (a forger, another camera's stream
                // sent here): 5 such messages per 10 s at most (core/log).
                FLT_LOG(FLT_LOG_WARNING, "camera",
                        "a stream packet from %s, not the camera, ignored",
                        format_endpoint(from).text);
                continue;
            }
            const frame_assembler::packet_kind k =
                assembler_.on_packet(packet_.data(), got, clock::now());
            if (k == frame_assembler::packet_kind::opened && !port_known_) {
                // The first leader that opens a frame fixes the port.
                port_known_ = true;
                source_port_ = from.port;
            }
        }
        assembler_.check_missing(clock::now());
    }
}

std::uint64_t stream_channel::count(int which) const {
    switch (which) {
        case FLT_COUNT_PACKETS_MISSING:
            return assembler_.packets_missing();
        case FLT_COUNT_RESEND_REQUESTS:
            return assembler_.resend_requests();
        case FLT_COUNT_PACKETS_RESENT:
            return assembler_.packets_resent();
        case FLT_COUNT_PACKETS_DUPLICATE:
            return assembler_.packets_duplicate();
        default:
            return 0;
    }
}

}  // namespace flt::gige
