// SPDX-License-Identifier: Apache-2.0
// GVCP: an 8-byte header (key 0x42, flags, command, data length, request
// id) and big-endian data; the acknowledge echoes the request id and
// carries a status (0 = success, 0x8xxx = an error). A command without an
// answer is sent again with a new request id; an answer carrying another
// id is stale and discarded; a PENDING_ACK extends the deadline (bounded).
#include "sources/gige/control.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>

#include "core/error.hpp"
#include "core/log.hpp"
#include "sources/camera/camera.hpp"
#include "sources/gige/protocol.hpp"
#include "sources/source.hpp"

namespace flt::gige {

using sources::raise;

namespace {

const char *command_name(std::uint16_t command) {
    switch (command) {
        case k_readreg_cmd:
            return "READREG";
        case k_writereg_cmd:
            return "WRITEREG";
        case k_readmem_cmd:
            return "READMEM";
        case k_writemem_cmd:
            return "WRITEMEM";
        default:
            return "command";
    }
}

// GigE Vision's status codes (the standard's table) as words.
const char *status_name(std::uint16_t status) {
    switch (status) {
        case 0x8001:
            return "not implemented";
        case 0x8002:
            return "invalid parameter";
        case 0x8003:
            return "invalid address";
        case 0x8004:
            return "write protect";
        case 0x8005:
            return "bad alignment";
        case 0x8006:
            return "access denied";
        case 0x8007:
            return "busy";
        case 0x800C:
            return "packet unavailable";
        case 0x800D:
            return "data overrun";
        case 0x800E:
            return "invalid header";
        case 0x800F:
            return "wrong configuration";
        case 0x8FFF:
            return "error";
        default:
            return "unknown status";
    }
}

std::uint32_t address32(std::uint64_t address, std::size_t bytes, const char *what) {
    if (address > 0xFFFFFFFFull || bytes > 0x100000000ull - address)
        raise(FLT_ERR_INVALID_ARGUMENT,
              "%s at 0x%llx (%zu bytes) is beyond GigE Vision's 32-bit register space", what,
              (unsigned long long)address, bytes);
    return std::uint32_t(address);
}

}  // namespace

control_channel::control_channel(endpoint camera, const control_config &config)
    : control_channel(camera, config, nullptr, 0) {}

control_channel::control_channel(endpoint camera, const control_config &config,
                                 std::unique_ptr<datagram_port> port, std::uint32_t host_address)
    : camera_(camera), config_(config), socket_(std::move(port)), host_address_(host_address) {
    config_.timeout_ms = std::max(config_.timeout_ms, 1u);
    config_.command_attempts = std::max(config_.command_attempts, 1u);
    if (!socket_) {
        auto s = std::make_unique<udp_socket>();
        s->bind(0, 0);
        socket_ = std::move(s);
        // The address the system routes to the camera from: where the
        // camera must send the stream.
        host_address_ = route_to(camera);
    }
    command_.reserve(k_gvcp_header + 8 + k_memory_chunk);
    answer_.resize(1500);
}

control_channel::~control_channel() {
    release_control();
}

std::uint16_t control_channel::next_id() {
    // Request ids increase and wrap without 0 (0 is reserved).
    request_id_ = std::uint16_t(request_id_ + 1);
    if (request_id_ == 0)
        request_id_ = 1;
    return request_id_;
}

// Camera fault point: a command the camera does not answer, answers with
// an error, or keeps pending.
void control_channel::transact(std::uint16_t command, const std::uint8_t *data,
                               std::size_t data_bytes, std::vector<std::uint8_t> &ack,
                               std::uint64_t address) {
    using clock = datagram_port::clock;
    std::lock_guard<std::mutex> lock(mutex_);
    command_.assign(k_gvcp_header + data_bytes, 0);
    const std::uint16_t expected = std::uint16_t(command + 1);
    // The pending acknowledges of this command may extend its wait to this
    // at most (set by the first one).
    bool pending_capped = false;
    clock::time_point pending_end;
    unsigned pending = 0;
    for (unsigned attempt = 0; attempt < config_.command_attempts; ++attempt) {
        if (attempt > 0) {
            ++retries_;
            // Counted (FLT_COUNT_COMMAND_RETRIES) and said: a camera that
            // needs retries is on a lossy or overloaded link.
            FLT_LOG(FLT_LOG_INFO, "camera",
                    "%s at 0x%llx got no answer in %u ms: sent again (%u of %u)",
                    command_name(command), (unsigned long long)address, config_.timeout_ms,
                    attempt + 1, config_.command_attempts);
        }
        const std::uint16_t id = next_id();
        std::uint8_t *c = command_.data();
        c[0] = k_gvcp_key;
        c[1] = k_flag_ack_required;
        put_be16(c + 2, command);
        put_be16(c + 4, std::uint16_t(data_bytes));
        put_be16(c + 6, id);
        if (data_bytes)
            std::memcpy(c + k_gvcp_header, data, data_bytes);
        socket_->send_to(c, command_.size(), camera_);
        auto deadline = socket_->now() + std::chrono::milliseconds(config_.timeout_ms);
        if (pending_capped)
            deadline = std::min(deadline, pending_end);
        for (;;) {
            const auto left =
                std::chrono::duration_cast<std::chrono::milliseconds>(deadline - socket_->now());
            if (left.count() <= 0)
                break;
            std::size_t got = 0;
            endpoint from;
            if (!socket_->receive(answer_.data(), answer_.size(), got, &from,
                                  unsigned(left.count())))
                continue;  // timed out (the loop ends) or an ICMP error
            if (from.address != camera_.address || from.port != camera_.port) {
                ++strangers_;  // only the camera speaks
                FLT_LOG(FLT_LOG_WARNING, "camera",
                        "a control packet from %s, not the camera, ignored",
                        format_endpoint(from).text);
                continue;
            }
            const std::uint8_t *a = answer_.data();
            if (got < k_gvcp_header || get_be16(a + 6) != id) {
                ++stale_;  // an answer to an earlier attempt, or noise
                continue;
            }
            const std::uint16_t status = get_be16(a), answer = get_be16(a + 2);
            const std::size_t length = get_be16(a + 4);
            if (answer == k_pending_ack && got >= k_gvcp_header + 4) {
                ++pending_;
                if (++pending > config_.pending_ack_limit)
                    raise(FLT_ERR_TIMEOUT,
                          "%s at 0x%llx: the camera answered %u pending acknowledges and no "
                          "result",
                          command_name(command), (unsigned long long)address, pending - 1);
                const auto now = socket_->now();
                if (!pending_capped) {
                    pending_capped = true;
                    pending_end = now + std::chrono::milliseconds(sources::k_pending_wait_cap_ms);
                }
                if (now >= pending_end)
                    raise(FLT_ERR_TIMEOUT,
                          "%s at 0x%llx: the camera kept the command pending for more than %u ms",
                          command_name(command), (unsigned long long)address,
                          sources::k_pending_wait_cap_ms);
                // The time it asks for (ms), at least the timeout, at most
                // what is left of the cap.
                const unsigned wait_ms = get_be16(a + k_gvcp_header + 2);
                deadline =
                    std::min(now + std::chrono::milliseconds(std::max(wait_ms, config_.timeout_ms)),
                             pending_end);
                continue;
            }
            if (status == k_status_busy)
                raise(FLT_ERR_TIMEOUT, "%s at 0x%llx: the camera answered status 0x%04x (busy)",
                      command_name(command), (unsigned long long)address, status);
            if (status != 0)
                raise(FLT_ERR_DEVICE, "%s at 0x%llx: the camera answered status 0x%04x (%s)",
                      command_name(command), (unsigned long long)address, status,
                      status_name(status));
            if (answer != expected || k_gvcp_header + length > got)
                raise(FLT_ERR_FORMAT,
                      "%s at 0x%llx: malformed acknowledge (command 0x%04x, %zu of %zu bytes)",
                      command_name(command), (unsigned long long)address, answer, got,
                      k_gvcp_header + length);
            ack.assign(a + k_gvcp_header, a + k_gvcp_header + length);
            return;
        }
        // (A wait's end is reached to the millisecond: on Windows a timed
        // receive may return a fraction of one early, so the cap counts as
        // reached within 1 ms.)
        if (pending_capped && socket_->now() + std::chrono::milliseconds(1) >= pending_end)
            raise(FLT_ERR_TIMEOUT,
                  "%s at 0x%llx: the camera kept the command pending for more than %u ms",
                  command_name(command), (unsigned long long)address,
                  sources::k_pending_wait_cap_ms);
    }
    raise(FLT_ERR_TIMEOUT,
          "%s at 0x%llx: no acknowledge from the camera at %s in %u attempt(s) "
          "of %u ms",
          command_name(command), (unsigned long long)address,
          to_string(camera_, k_gvcp_port).c_str(), config_.command_attempts, config_.timeout_ms);
}

void control_channel::read(std::uint64_t address, std::uint8_t *out, std::size_t bytes) {
    if (bytes == 0)
        return;
    address32(address, bytes, "READMEM");
    // Whole 4-byte words: GVCP reads and writes memory in words.
    const std::uint64_t first = address & ~std::uint64_t(3);
    const std::uint64_t end = (address + bytes + 3) & ~std::uint64_t(3);
    std::vector<std::uint8_t> ack;
    std::uint8_t request[8];
    for (std::uint64_t at = first; at < end;) {
        const std::size_t n = std::size_t(std::min<std::uint64_t>(k_memory_chunk, end - at));
        put_be32(request, std::uint32_t(at));
        put_be16(request + 4, 0);
        put_be16(request + 6, std::uint16_t(n));
        transact(k_readmem_cmd, request, sizeof request, ack, at);
        if (ack.size() < 4 + n || get_be32(ack.data()) != std::uint32_t(at))
            raise(FLT_ERR_FORMAT, "READMEM at 0x%llx: the acknowledge holds %zu bytes of %zu",
                  (unsigned long long)at, ack.size() >= 4 ? ack.size() - 4 : 0, n);
        // Copy the part of [at, at + n) that lies inside [address, address + bytes).
        const std::uint64_t lo = std::max<std::uint64_t>(at, address);
        const std::uint64_t hi = std::min<std::uint64_t>(at + n, address + bytes);
        if (hi > lo)
            std::memcpy(out + (lo - address), ack.data() + 4 + (lo - at), std::size_t(hi - lo));
        at += n;
    }
}

void control_channel::write(std::uint64_t address, const std::uint8_t *in, std::size_t bytes) {
    if (bytes == 0)
        return;
    address32(address, bytes, "WRITEMEM");
    const std::uint64_t first = address & ~std::uint64_t(3);
    const std::uint64_t end = (address + bytes + 3) & ~std::uint64_t(3);
    std::vector<std::uint8_t> words(std::size_t(end - first));
    if (first != address || end != address + bytes)
        read(first, words.data(), words.size());  // keep the bytes around the range
    std::memcpy(words.data() + (address - first), in, bytes);
    std::vector<std::uint8_t> request, ack;
    for (std::uint64_t at = first; at < end;) {
        const std::size_t n = std::size_t(std::min<std::uint64_t>(k_memory_chunk, end - at));
        request.assign(4 + n, 0);
        put_be32(request.data(), std::uint32_t(at));
        std::memcpy(request.data() + 4, words.data() + (at - first), n);
        transact(k_writemem_cmd, request.data(), request.size(), ack, at);
        at += n;
    }
}

std::uint32_t control_channel::read_register(std::uint32_t address) {
    std::uint8_t request[4];
    put_be32(request, address);
    std::vector<std::uint8_t> ack;
    transact(k_readreg_cmd, request, sizeof request, ack, address);
    if (ack.size() < 4)
        raise(FLT_ERR_FORMAT, "READREG at 0x%x: the acknowledge holds no value", address);
    return get_be32(ack.data());
}

void control_channel::write_register(std::uint32_t address, std::uint32_t value) {
    std::uint8_t request[8];
    put_be32(request, address);
    put_be32(request + 4, value);
    std::vector<std::uint8_t> ack;
    transact(k_writereg_cmd, request, sizeof request, ack, address);
}

void control_channel::take_control() {
    try {
        write_register(bootstrap::control_privilege, bootstrap::ccp_control);
    } catch (const error &e) {
        raise(e.status,
              "taking control of the camera at %s failed (another application may control "
              "it): %s",
              to_string(camera_, k_gvcp_port).c_str(), e.what());
    }
    write_register(bootstrap::heartbeat_timeout, config_.heartbeat_ms);
    {
        std::lock_guard<std::mutex> lock(heartbeat_mutex_);
        heartbeat_stop_ = false;
        heartbeat_failure_.clear();
    }
    heartbeat_ = std::thread([this] { heartbeat_loop(); });
}

void control_channel::heartbeat_loop() {
    // A third of the timeout: two heartbeats may be lost before the camera
    // gives the privilege away.
    const auto period = std::chrono::milliseconds(std::max(config_.heartbeat_ms / 3, 50u));
    std::unique_lock<std::mutex> lock(heartbeat_mutex_);
    while (!heartbeat_wake_.wait_for(lock, period, [this] { return heartbeat_stop_; })) {
        lock.unlock();
        std::string failure;
        try {
            const std::uint32_t ccp = read_register(bootstrap::control_privilege);
            ++heartbeats_;
            if (!(ccp & (bootstrap::ccp_control | bootstrap::ccp_exclusive)))
                failure = "the camera gave our control privilege away (CCP = 0)";

        } catch (const error &e) {
            failure = std::string("the heartbeat failed: ") + e.what();
        } catch (const std::exception &e) {
            failure = std::string("the heartbeat failed: ") + e.what();
        }
        lock.lock();
        // A heartbeat lost on the way is forgotten when the next one gets
        // through; a privilege the camera gave away is not regained.
        if (failure.find("CCP = 0") != std::string::npos)
            control_lost_ = true;
        if (!control_lost_ || heartbeat_failure_.empty())
            heartbeat_failure_ = failure;
    }
}

void control_channel::release_control() noexcept {
    bool running = false;
    {
        std::lock_guard<std::mutex> lock(heartbeat_mutex_);
        heartbeat_stop_ = true;
        running = heartbeat_.joinable();
    }
    if (!running)
        return;
    heartbeat_wake_.notify_all();
    heartbeat_.join();
    try {
        write_register(bootstrap::control_privilege, 0);
    } catch (...) {
        // The camera drops the privilege itself once the heartbeat stops.
    }
}

std::string control_channel::heartbeat_failure() const {
    std::lock_guard<std::mutex> lock(heartbeat_mutex_);
    return heartbeat_failure_;
}

void control_channel::request_resend(std::uint16_t block_id, std::uint32_t first,
                                     std::uint32_t last) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::uint8_t c[k_gvcp_header + 12];
    c[0] = k_gvcp_key;
    c[1] = 0;  // no acknowledge: the packets are the answer
    put_be16(c + 2, k_packet_resend_cmd);
    put_be16(c + 4, 12);
    put_be16(c + 6, next_id());
    put_be32(c + 8, block_id);  // stream channel 0 (high half), block id
    put_be32(c + 12, first & 0xFFFFFFu);
    put_be32(c + 16, last & 0xFFFFFFu);
    socket_->send_to(c, sizeof c, camera_);
}

std::uint64_t control_channel::count(int which) const {
    switch (which) {
        case FLT_COUNT_COMMAND_RETRIES:
            return retries_.load();
        case FLT_COUNT_STALE_ACKS:
            return stale_.load();
        case FLT_COUNT_PENDING_ACKS:
            return pending_.load();
        case FLT_COUNT_BAD_PACKETS:
            return strangers_.load();
        default:
            return 0;
    }
}

}  // namespace flt::gige
