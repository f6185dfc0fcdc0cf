// SPDX-License-Identifier: Apache-2.0
// Internal: the USB3 Vision control channel - GenCP READMEM / WRITEMEM over
// the control interface's bulk endpoints, as the register_port the GenICam
// features and the bootstrap layer read and write through.
#pragma once

#include <cstdint>
#include <vector>

#include "sources/camera/accounting.hpp"
#include "sources/camera/features.hpp"
#include "sources/u3v/discovery.hpp"

namespace flt::u3v {

struct control_config {
    unsigned timeout_floor_ms = 200;  // option u3v_control_timeout
    unsigned pending_ack_limit = 5;   // option u3v_pending_ack_limit
    unsigned command_attempts = 3;    // option u3v_command_attempts
};

// The device was unplugged: counts it once, marks the link, throws
// FLT_ERR_DEVICE naming `what`.
[[noreturn]] void lost_device(usb_link &link, sources::frame_accounting &acc, const char *what);

class control_channel final : public sources::register_port {
  public:
    control_channel(usb_link &link, sources::frame_accounting &acc, const control_config &config);

    // Chunked to the device's limits (8-byte requests before they are
    // known). Throw FLT_ERR_TIMEOUT (no acknowledge in every attempt, too
    // many pending acks, device busy), FLT_ERR_DEVICE (a GenCP error status,
    // a USB failure, an unplug) or FLT_ERR_FORMAT (a malformed answer).
    void read(std::uint64_t address, std::uint8_t *out, std::size_t bytes) override;
    void write(std::uint64_t address, const std::uint8_t *in, std::size_t bytes) override;

    // From SBRM: the largest command and acknowledge, bytes.
    void set_limits(std::uint32_t max_command, std::uint32_t max_ack) {
        max_command_ = max_command;
        max_ack_ = max_ack;
    }
    // max(option u3v_control_timeout, the device's response time from ABRM).
    void set_response_time(std::uint32_t response_ms);
    std::uint32_t max_command() const { return max_command_; }
    std::uint32_t max_ack() const { return max_ack_; }
    unsigned timeout_ms() const { return timeout_ms_; }
    const control_config &config() const { return config_; }

  private:
    void transact(std::uint16_t command, const std::uint8_t *body, std::size_t body_bytes,
                  std::uint8_t *ack_body, std::size_t ack_bytes, std::uint64_t address);

    usb_link &link_;
    sources::frame_accounting &acc_;
    control_config config_;
    std::uint16_t request_id_ = 0;
    std::uint32_t max_command_ = 128, max_ack_ = 128;  // until SBRM is read
    unsigned timeout_ms_ = 200;
    std::vector<std::uint8_t> command_buffer_, ack_buffer_, write_body_;
};

}  // namespace flt::u3v
