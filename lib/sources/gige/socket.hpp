// SPDX-License-Identifier: Apache-2.0
// Internal: the UDP sockets GigE Vision runs on, one portable face over
// BSD sockets (Linux, macOS) and Winsock 2 (Windows; WSAStartup once per
// process). Addresses are IPv4 in host order. Nothing else in gige/
// includes a system socket header.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace flt::gige {

struct endpoint {
    std::uint32_t address = 0;  // IPv4, host order
    std::uint16_t port = 0;
};

// "a.b.c.d" (and ":port" when the port is not `default_port`).
std::string to_string(endpoint e, std::uint16_t default_port = 0);
// "a.b.c.d:port" (or "a.b.c.d") in a value, without allocating: the receive
// loops log a stranger's address with it, and a flood of strangers must not
// cost the heap. `text` holds "255.255.255.255:65535" and its NUL.
struct endpoint_text {
    char text[24];
};
endpoint_text format_endpoint(endpoint e, bool with_port = true);
// Parses "a.b.c.d" or "a.b.c.d:port" (port 1..65535); false for anything
// else (no host names: a camera is named by its address).
bool parse_endpoint(const char *text, std::uint16_t default_port, endpoint &out);

// A host IPv4 interface: its address, netmask and broadcast address.
struct interface_address {
    std::uint32_t address = 0, netmask = 0, broadcast = 0;
};
// The host's IPv4 interfaces that are up (loopback included). Throws
// FLT_ERR_DEVICE when the system cannot list them.
std::vector<interface_address> ipv4_interfaces();
// The host address the system would send to `peer` from (a connected
// socket's own address, the socket then closed).
std::uint32_t route_to(endpoint peer);

// What the control channel sends and receives datagrams through, and the
// clock it measures its timeouts by: a UDP socket (udp_socket below), or a
// scripted camera in the fuzzing harnesses, whose clock moves only when it
// is waited on (tests/fuzz/fuzz_gvcp.cpp).
class datagram_port {
  public:
    using clock = std::chrono::steady_clock;
    virtual ~datagram_port() = default;
    virtual void send_to(const void *data, std::size_t bytes, endpoint to) = 0;
    // As udp_socket::receive.
    virtual bool receive(void *buffer, std::size_t capacity, std::size_t &got, endpoint *from,
                         unsigned timeout_ms) = 0;
    virtual clock::time_point now() const { return clock::now(); }
};

// One UDP socket. Errors throw flt::error(FLT_ERR_DEVICE) naming the call
// and the system's reason.
class udp_socket final : public datagram_port {
  public:
    udp_socket();
    ~udp_socket() override;
    udp_socket(const udp_socket &) = delete;
    udp_socket &operator=(const udp_socket &) = delete;

    // Binds to `address` (0: any) and `port` (0: the system picks).
    void bind(std::uint32_t address, std::uint16_t port);
    // Sends to and receives from `peer` only.
    void connect(endpoint peer);
    endpoint local() const;
    void set_broadcast(bool on);
    // Asks for a receive buffer of `bytes`; returns what the system granted
    // (Linux caps it at net.core.rmem_max and reports twice the size).
    int set_receive_buffer(int bytes);

    void send_to(const void *data, std::size_t bytes, endpoint to) override;
    void send(const void *data, std::size_t bytes);  // connected sockets
    // Waits up to timeout_ms (0: only what is already there) for one
    // datagram: true with `got` bytes (a datagram longer than `capacity` is
    // cut) and its sender in `from` (may be NULL), false when none came.
    // An ICMP "port unreachable" reported on the socket counts as nothing.
    bool receive(void *buffer, std::size_t capacity, std::size_t &got, endpoint *from,
                 unsigned timeout_ms) override;

  private:
    std::intptr_t fd_;  // SOCKET on Windows, int elsewhere
};

}  // namespace flt::gige
