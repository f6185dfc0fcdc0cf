// SPDX-License-Identifier: Apache-2.0
// GenCP over USB: a 12-byte header (prefix "U3VC", flags, command id, body
// length, request id) and a body; acknowledges echo the request id. Pending
// acks extend the deadline (bounded); a command without answer is sent
// again with a new request id; an ack of an older request is stale.
#include "sources/u3v/control.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>

#include "core/error.hpp"
#include "sources/camera/camera.hpp"
#include "sources/source.hpp"
#include "sources/u3v/protocol.hpp"

namespace flt::u3v {

using sources::raise;

namespace {

const char *command_name(std::uint16_t command) {
    return command == k_cmd_readmem ? "READMEM" : "WRITEMEM";
}

}  // namespace

void lost_device(usb_link &link, sources::frame_accounting &acc, const char *what) {
    if (!link.disconnected)
        acc.add(FLT_COUNT_DISCONNECTS);
    link.disconnected = true;
    raise(FLT_ERR_DEVICE, "the camera was unplugged (%s)", what);
}

control_channel::control_channel(usb_link &link, sources::frame_accounting &acc,
                                 const control_config &config)
    : link_(link), acc_(acc), config_(config), timeout_ms_(std::max(config.timeout_floor_ms, 1u)) {}

void control_channel::set_response_time(std::uint32_t response_ms) {
    timeout_ms_ = std::max(std::max(config_.timeout_floor_ms, 1u), unsigned(response_ms));
}

void control_channel::transact(std::uint16_t command, const std::uint8_t *body,
                               std::size_t body_bytes, std::uint8_t *ack_body,
                               std::size_t ack_bytes, std::uint64_t address) {
    using clock = std::chrono::steady_clock;
    if (link_.disconnected)
        raise(FLT_ERR_DEVICE, "the camera was unplugged");
    command_buffer_.resize(k_gencp_header + body_bytes);
    ack_buffer_.resize(std::max<std::size_t>(max_ack_, k_gencp_header + 8));
    const std::uint16_t expected_ack = std::uint16_t(command + 1);
    // The pending acknowledges of this command may extend its wait to this
    // at most (set by the first one; ../camera/camera.hpp).
    bool pending_capped = false;
    clock::time_point pending_end;
    for (unsigned attempt = 0; attempt < config_.command_attempts; ++attempt) {
        if (attempt > 0)
            acc_.add(FLT_COUNT_COMMAND_RETRIES);
        // Request ids increase and wrap without 0; an ack carrying an older
        // id answers an earlier attempt and is discarded below.
        request_id_ = std::uint16_t(request_id_ + 1);
        if (request_id_ == 0)
            request_id_ = 1;
        std::uint8_t *c = command_buffer_.data();
        put_u32(c, k_prefix_control);
        put_u16(c + 4, k_flag_request_ack);
        put_u16(c + 6, command);
        put_u16(c + 8, std::uint16_t(body_bytes));
        put_u16(c + 10, request_id_);
        std::memcpy(c + k_gencp_header, body, body_bytes);
        std::size_t sent = 0;
        usb_status st = link_.dev->bulk_write(link_.ep_control_out, c, command_buffer_.size(), sent,
                                              timeout_ms_);
        if (st == usb_status::no_device)
            lost_device(link_, acc_, "control channel");
        if (st == usb_status::timeout)
            continue;
        if (st != usb_status::ok)
            raise(FLT_ERR_DEVICE, "%s at 0x%llx: sending the command failed: %s",
                  command_name(command), (unsigned long long)address, usb_status_name(st));
        auto deadline = clock::now() + std::chrono::milliseconds(timeout_ms_);
        if (pending_capped)
            deadline = std::min(deadline, pending_end);
        unsigned pending = 0;
        for (;;) {
            // Whole milliseconds, rounded up: the first read waits the full
            // timeout, a late one at least 1 ms.
            const auto left_us =
                std::chrono::duration_cast<std::chrono::microseconds>(deadline - clock::now())
                    .count();
            const unsigned wait = unsigned(std::max<long long>(1, (left_us + 999) / 1000));
            std::size_t n = 0;
            st = link_.dev->bulk_read(link_.ep_control_in, ack_buffer_.data(), ack_buffer_.size(),
                                      n, wait);
            if (st == usb_status::no_device)
                lost_device(link_, acc_, "control channel");
            if (st == usb_status::timeout) {
                if (pending_capped && clock::now() >= pending_end)
                    raise(FLT_ERR_TIMEOUT,
                          "%s at 0x%llx: the camera kept the command pending for more than %u ms",
                          command_name(command), (unsigned long long)address,
                          sources::k_pending_wait_cap_ms);
                break;  // retry with a new request id
            }
            if (st != usb_status::ok)
                raise(FLT_ERR_DEVICE, "%s at 0x%llx: reading the acknowledge failed: %s",
                      command_name(command), (unsigned long long)address, usb_status_name(st));
            const std::uint8_t *a = ack_buffer_.data();
            if (n < k_gencp_header || get_u32(a) != k_prefix_control ||
                get_u16(a + 8) != n - k_gencp_header) {
                acc_.add(FLT_COUNT_STALE_ACKS);  // not an acknowledge: skip it
                continue;
            }
            const std::uint16_t status = get_u16(a + 4), ack_id = get_u16(a + 6);
            if (get_u16(a + 10) != request_id_) {
                acc_.add(FLT_COUNT_STALE_ACKS);
                continue;
            }
            if (ack_id == k_ack_pending) {
                acc_.add(FLT_COUNT_PENDING_ACKS);
                if (++pending > config_.pending_ack_limit)
                    raise(FLT_ERR_TIMEOUT,
                          "%s at 0x%llx: the camera sent %u pending acks, more than the limit "
                          "of %u",
                          command_name(command), (unsigned long long)address, pending,
                          config_.pending_ack_limit);
                const auto now = clock::now();
                if (!pending_capped) {
                    pending_capped = true;
                    pending_end = now + std::chrono::milliseconds(sources::k_pending_wait_cap_ms);
                }
                if (now >= pending_end)
                    raise(FLT_ERR_TIMEOUT,
                          "%s at 0x%llx: the camera kept the command pending for more than %u ms",
                          command_name(command), (unsigned long long)address,
                          sources::k_pending_wait_cap_ms);
                const unsigned more = n >= k_gencp_header + 4 ? get_u16(a + 14) : 0;
                deadline = std::min(now + std::chrono::milliseconds(std::max(more, timeout_ms_)),
                                    pending_end);
                continue;
            }
            if (ack_id != expected_ack)
                raise(FLT_ERR_FORMAT,
                      "%s at 0x%llx: the camera answered with ack id 0x%04x, expected 0x%04x",
                      command_name(command), (unsigned long long)address, ack_id, expected_ack);
            if (status != gencp_ok)
                raise(status == gencp_busy ? FLT_ERR_TIMEOUT : FLT_ERR_DEVICE,
                      "%s of %zu bytes at 0x%llx: the camera answered status 0x%04x (%s)",
                      command_name(command), command == k_cmd_readmem ? ack_bytes : body_bytes - 8,
                      (unsigned long long)address, status, gencp_status_name(status));
            const std::size_t got = n - k_gencp_header;
            if (command == k_cmd_readmem && got != ack_bytes)
                raise(FLT_ERR_FORMAT,
                      "READMEM at 0x%llx: the camera returned %zu bytes, asked for %zu",
                      (unsigned long long)address, got, ack_bytes);
            if (command == k_cmd_writemem && (got < 4 || get_u16(a + 14) != body_bytes - 8))
                raise(FLT_ERR_FORMAT, "WRITEMEM at 0x%llx: the camera wrote %u of %zu bytes",
                      (unsigned long long)address, got >= 4 ? get_u16(a + 14) : 0u, body_bytes - 8);
            if (ack_body && ack_bytes)
                std::memcpy(ack_body, a + k_gencp_header, ack_bytes);
            return;
        }
    }
    raise(FLT_ERR_TIMEOUT, "%s at 0x%llx: no acknowledge within %u ms in %u attempts",
          command_name(command), (unsigned long long)address, timeout_ms_,
          config_.command_attempts);
}

void control_channel::read(std::uint64_t address, std::uint8_t *out, std::size_t bytes) {
    // An ack carries the header and the data; the count field is 16 bits.
    const std::size_t chunk = std::min<std::size_t>(max_ack_ - k_gencp_header, 0xFFFF);
    std::uint8_t body[k_readmem_body];
    for (std::size_t done = 0; done < bytes;) {
        const std::size_t n = std::min(chunk, bytes - done);
        put_u64(body, address + done);
        put_u16(body + 8, 0);
        put_u16(body + 10, std::uint16_t(n));
        transact(k_cmd_readmem, body, sizeof body, out + done, n, address + done);
        done += n;
    }
}

void control_channel::write(std::uint64_t address, const std::uint8_t *in, std::size_t bytes) {
    const std::size_t chunk = std::min<std::size_t>(max_command_ - k_writemem_overhead, 0xFFFF);
    write_body_.resize(8 + std::min(chunk, bytes));
    for (std::size_t done = 0; done < bytes;) {
        const std::size_t n = std::min(chunk, bytes - done);
        put_u64(write_body_.data(), address + done);
        std::memcpy(write_body_.data() + 8, in + done, n);
        transact(k_cmd_writemem, write_body_.data(), 8 + n, nullptr, 0, address + done);
        done += n;
    }
}

}  // namespace flt::u3v
