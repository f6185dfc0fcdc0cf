// SPDX-License-Identifier: Apache-2.0
// Internal: the GigE Vision control channel - GVCP over UDP port 3956 as
// the register_port the bootstrap layer and the GenICam features read and
// write through, the control privilege and its heartbeat, and packet resend
// requests for the stream channel.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "sources/camera/features.hpp"
#include "sources/gige/socket.hpp"

namespace flt::gige {

struct control_config {
    unsigned timeout_ms = 200;       // option gige_control_timeout
    unsigned command_attempts = 3;   // option gige_command_attempts
    unsigned heartbeat_ms = 3000;    // option gige_heartbeat_timeout
    unsigned pending_ack_limit = 5;  // pending acks accepted per command
};

// Thread-safe: the heartbeat thread and the user's calls share it (one
// transaction at a time).
//
// Only the camera speaks: a datagram on the control socket from any other
// address or port than the camera's GVCP endpoint is counted BAD_PACKETS
// and ignored (the socket is not connected, so that such datagrams reach
// the client to be counted instead of vanishing in the system).
class control_channel final : public sources::register_port {
  public:
    // A socket talking to `camera` (its GVCP port); nothing is sent yet.
    control_channel(endpoint camera, const control_config &config);
    // The same over `port` (a scripted camera: the fuzzing harness), the
    // host's address given.
    control_channel(endpoint camera, const control_config &config,
                    std::unique_ptr<datagram_port> port, std::uint32_t host_address);
    ~control_channel() override;

    // READMEM / WRITEMEM in chunks of at most 512 bytes; unaligned ranges
    // are widened to whole 4-byte words (a write reads the words first).
    // Throw FLT_ERR_TIMEOUT (no acknowledge in any attempt, the camera
    // busy, pending acknowledges beyond gige's limit or beyond
    // sources::k_pending_wait_cap_ms), FLT_ERR_DEVICE (a GVCP error status,
    // a socket failure) or FLT_ERR_FORMAT (a malformed answer), each naming
    // the command and the address.
    void read(std::uint64_t address, std::uint8_t *out, std::size_t bytes) override;
    void write(std::uint64_t address, const std::uint8_t *in, std::size_t bytes) override;
    std::uint32_t read_register(std::uint32_t address);
    void write_register(std::uint32_t address, std::uint32_t value);

    // Takes the control privilege (CCP = control), writes the heartbeat
    // timeout and starts the heartbeat thread, which reads CCP every third
    // of it. FLT_ERR_DEVICE ("access denied") when another host controls
    // the camera.
    void take_control();
    // Stops the heartbeat and gives the privilege back (errors ignored: the
    // camera drops it by itself when the heartbeat stops).
    void release_control() noexcept;
    // Why the last heartbeat failed ("" while they get through): the camera
    // stopped answering, or it gave our control privilege away (then for
    // good).
    std::string heartbeat_failure() const;

    // A packet resend request (no acknowledge) for packets first..last of
    // block `block_id` on stream channel 0.
    void request_resend(std::uint16_t block_id, std::uint32_t first, std::uint32_t last);

    endpoint camera() const { return camera_; }
    // The host address the camera is reached from (the stream goes there).
    std::uint32_t host_address() const { return host_address_; }
    const control_config &config() const { return config_; }
    std::uint64_t count(int which) const;  // flt_source_counter of this channel
    std::uint64_t heartbeats() const { return heartbeats_.load(); }

  private:
    void transact(std::uint16_t command, const std::uint8_t *data, std::size_t data_bytes,
                  std::vector<std::uint8_t> &ack, std::uint64_t address);
    std::uint16_t next_id();
    void heartbeat_loop();

    endpoint camera_;
    control_config config_;
    std::mutex mutex_;  // one transaction at a time
    std::unique_ptr<datagram_port> socket_;
    std::uint32_t host_address_ = 0;
    std::uint16_t request_id_ = 0;
    std::vector<std::uint8_t> command_, answer_;
    std::atomic<std::uint64_t> retries_{0}, stale_{0}, pending_{0}, heartbeats_{0}, strangers_{0};

    std::thread heartbeat_;
    mutable std::mutex heartbeat_mutex_;
    std::condition_variable heartbeat_wake_;
    bool heartbeat_stop_ = false;
    std::string heartbeat_failure_;  // guarded by heartbeat_mutex_
    bool control_lost_ = false;      // guarded by heartbeat_mutex_
};

}  // namespace flt::gige
