// SPDX-License-Identifier: Apache-2.0
// GigE Vision discovery (see discovery.hpp).
#include "sources/gige/discovery.hpp"

#include <chrono>
#include <cstdio>

#include "core/error.hpp"
#include "sources/camera/camera.hpp"
#include "sources/gige/protocol.hpp"
#include "sources/source.hpp"

namespace flt::gige {

using sources::raise;

namespace {

// A fixed-size bootstrap string: NUL-padded, not always NUL-terminated;
// the camera's words, which reach callers who print them, with control
// bytes (a terminal's escape sequences) replaced.
std::string field(const std::uint8_t *data, std::size_t offset, std::size_t size) {
    std::size_t n = 0;
    while (n < size && data[offset + n] != 0)
        ++n;
    return sources::visible_text(std::string(reinterpret_cast<const char *>(data + offset), n));
}

}  // namespace

camera_info parse_discovery(const std::uint8_t *d, std::size_t bytes, endpoint from) {
    if (bytes < k_discovery_data)
        raise(FLT_ERR_FORMAT, "discovery acknowledge from %s holds %zu bytes of %zu",
              to_string(from, k_gvcp_port).c_str(), bytes, k_discovery_data);
    camera_info c;
    c.address = from;
    c.gev_version = get_be32(d + bootstrap::version);
    c.strings[0] = field(d, bootstrap::manufacturer, 32);
    c.strings[1] = field(d, bootstrap::model, 32);
    c.strings[3] = field(d, bootstrap::device_version, 32);
    c.strings[4] = field(d, bootstrap::manufacturer_info, 48);
    c.strings[5] = field(d, bootstrap::serial, 16);
    c.strings[6] = field(d, bootstrap::user_name, 16);
    char mac[18];
    const std::uint8_t *m = d + bootstrap::mac_high + 2;  // the low 16 bits of MAC high
    std::snprintf(mac, sizeof mac, "%02x:%02x:%02x:%02x:%02x:%02x", m[0], m[1], m[2], m[3], m[4],
                  m[5]);
    c.mac = mac;
    return c;
}

std::vector<camera_info> discover(const char *target, unsigned timeout_ms) {
    using clock = std::chrono::steady_clock;
    std::vector<endpoint> targets;
    if (target) {
        endpoint e;
        if (!parse_endpoint(target, k_gvcp_port, e))
            raise(FLT_ERR_INVALID_ARGUMENT, "'%s' is no IPv4 address (a.b.c.d or a.b.c.d:port)",
                  target);
        targets.push_back(e);
    } else {
        targets.push_back({0xFFFFFFFFu, k_gvcp_port});
        for (const interface_address &i : ipv4_interfaces())
            if (i.broadcast != 0xFFFFFFFFu && i.broadcast != i.address)
                targets.push_back({i.broadcast, k_gvcp_port});
    }
    udp_socket socket;
    socket.bind(0, 0);
    socket.set_broadcast(true);
    std::uint8_t command[k_gvcp_header];
    command[0] = k_gvcp_key;
    command[1] = k_flag_ack_required | k_flag_allow_broadcast_ack;
    put_be16(command + 2, k_discovery_cmd);
    put_be16(command + 4, 0);
    put_be16(command + 6, 1);
    bool sent = false;
    std::string last_failure;
    for (const endpoint &t : targets) {
        try {
            socket.send_to(command, sizeof command, t);
            sent = true;
        } catch (const error &e) {
            last_failure = e.what();  // an interface without a route: try the others
        }
    }
    if (!sent)
        raise(FLT_ERR_DEVICE, "the discovery command could not be sent: %s", last_failure.c_str());
    std::vector<camera_info> cameras;
    std::vector<std::uint8_t> answer(1500);
    const auto deadline = clock::now() + std::chrono::milliseconds(timeout_ms);
    for (;;) {
        const auto left =
            std::chrono::duration_cast<std::chrono::milliseconds>(deadline - clock::now());
        if (left.count() <= 0)
            break;
        std::size_t got = 0;
        endpoint from;
        if (!socket.receive(answer.data(), answer.size(), got, &from, unsigned(left.count())))
            continue;
        const std::uint8_t *a = answer.data();
        if (got < k_gvcp_header || get_be16(a) != 0 || get_be16(a + 2) != k_discovery_cmd + 1 ||
            get_be16(a + 6) != 1)
            continue;  // not a discovery acknowledge to us
        bool known = false;
        for (const camera_info &c : cameras)
            known = known || c.address.address == from.address;
        if (known)
            continue;  // the same camera heard two broadcasts
        try {
            cameras.push_back(parse_discovery(a + k_gvcp_header, got - k_gvcp_header, from));
        } catch (const error &) {
            // a malformed answer names no camera
        }
    }
    return cameras;
}

}  // namespace flt::gige
