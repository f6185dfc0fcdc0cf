// SPDX-License-Identifier: Apache-2.0
// UDP sockets over BSD sockets or Winsock 2 (see socket.hpp).
#include "sources/gige/socket.hpp"

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <mutex>

#include "sources/source.hpp"

#ifdef _WIN32
#  include <winsock2.h>
#  include <ws2tcpip.h>
#  include <iphlpapi.h>
#  include <windows.h>
#else
#  include <arpa/inet.h>
#  include <ifaddrs.h>
#  include <net/if.h>
#  include <netinet/in.h>
#  include <poll.h>
#  include <sys/socket.h>
#  include <unistd.h>
#endif

namespace flt::gige {

using sources::raise;

namespace {

#ifdef _WIN32
using native_socket = SOCKET;
const native_socket k_invalid = INVALID_SOCKET;
int last_error() {
    return WSAGetLastError();
}
std::string error_text(int code) {
    char text[256] = {0};
    FormatMessageA(FORMAT_MESSAGE_FROM_SYSTEM | FORMAT_MESSAGE_IGNORE_INSERTS, nullptr, DWORD(code),
                   0, text, sizeof text, nullptr);
    std::string s(text);
    while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == '.'))
        s.pop_back();
    return s + " (" + std::to_string(code) + ")";
}
bool unreachable(int code) {
    return code == WSAECONNRESET || code == WSAECONNREFUSED || code == WSAENETRESET;
}
void start_winsock() {
    static std::once_flag once;
    static int result = 0;
    std::call_once(once, [] {
        WSADATA data;
        result = WSAStartup(MAKEWORD(2, 2), &data);
    });
    if (result != 0)
        raise(FLT_ERR_DEVICE, "Winsock does not start (WSAStartup: %d)", result);
}
#else
using native_socket = int;
const native_socket k_invalid = -1;
int last_error() {
    return errno;
}
std::string error_text(int code) {
    return std::string(std::strerror(code));
}
bool unreachable(int code) {
    return code == ECONNREFUSED || code == EHOSTUNREACH || code == ENETUNREACH;
}
void start_winsock() {}
#endif

native_socket native(std::intptr_t fd) {
    return native_socket(fd);
}

sockaddr_in to_native(endpoint e) {
    sockaddr_in a;
    std::memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(e.address);
    a.sin_port = htons(e.port);
    return a;
}

[[noreturn]] void socket_failure(const char *call) {
    const int code = last_error();
    raise(FLT_ERR_DEVICE, "socket %s failed: %s", call, error_text(code).c_str());
}

}  // namespace

endpoint_text format_endpoint(endpoint e, bool with_port) {
    endpoint_text t{};
    const int n = std::snprintf(t.text, sizeof t.text, "%u.%u.%u.%u", unsigned(e.address >> 24),
                                unsigned(e.address >> 16 & 0xFF), unsigned(e.address >> 8 & 0xFF),
                                unsigned(e.address & 0xFF));
    if (with_port && n > 0 && std::size_t(n) < sizeof t.text)
        (void)std::snprintf(t.text + n, sizeof t.text - std::size_t(n), ":%u", unsigned(e.port));
    return t;
}

std::string to_string(endpoint e, std::uint16_t default_port) {
    return format_endpoint(e, e.port != default_port).text;
}

bool parse_endpoint(const char *text, std::uint16_t default_port, endpoint &out) {
    if (text == nullptr)
        return false;
    const char *p = text, *end = text + std::strlen(text);
    std::uint32_t address = 0;
    for (int i = 0; i < 4; ++i) {
        unsigned part = 0;
        auto r = std::from_chars(p, end, part);
        if (r.ec != std::errc() || r.ptr == p || r.ptr - p > 3 || part > 255)
            return false;
        address = (address << 8) | part;
        p = r.ptr;
        if (i < 3) {
            if (p == end || *p != '.')
                return false;
            ++p;
        }
    }
    unsigned port = default_port;
    if (p != end) {
        if (*p != ':')
            return false;
        ++p;
        auto r = std::from_chars(p, end, port);
        if (r.ec != std::errc() || r.ptr != end || port == 0 || port > 65535)
            return false;
        p = r.ptr;
    }
    out.address = address;
    out.port = std::uint16_t(port);
    return true;
}

std::vector<interface_address> ipv4_interfaces() {
    std::vector<interface_address> out;
#ifdef _WIN32
    start_winsock();
    ULONG size = 16384;
    std::vector<unsigned char> buffer;
    ULONG result = ERROR_BUFFER_OVERFLOW;
    for (int attempt = 0; attempt < 4 && result == ERROR_BUFFER_OVERFLOW; ++attempt) {
        buffer.resize(size);
        result = GetAdaptersAddresses(
            AF_INET, GAA_FLAG_SKIP_ANYCAST | GAA_FLAG_SKIP_MULTICAST | GAA_FLAG_SKIP_DNS_SERVER,
            nullptr, reinterpret_cast<IP_ADAPTER_ADDRESSES *>(buffer.data()), &size);
    }
    if (result != NO_ERROR)
        raise(FLT_ERR_DEVICE, "GetAdaptersAddresses failed: %s", error_text(int(result)).c_str());
    for (auto *a = reinterpret_cast<IP_ADAPTER_ADDRESSES *>(buffer.data()); a; a = a->Next) {
        if (a->OperStatus != IfOperStatusUp)
            continue;
        for (auto *u = a->FirstUnicastAddress; u; u = u->Next) {
            if (u->Address.lpSockaddr->sa_family != AF_INET)
                continue;
            interface_address i;
            i.address =
                ntohl(reinterpret_cast<sockaddr_in *>(u->Address.lpSockaddr)->sin_addr.s_addr);
            const unsigned prefix = u->OnLinkPrefixLength;
            i.netmask = prefix == 0 ? 0 : prefix >= 32 ? 0xFFFFFFFFu : ~((1u << (32 - prefix)) - 1);
            i.broadcast = i.address | ~i.netmask;
            out.push_back(i);
        }
    }
#else
    ifaddrs *list = nullptr;
    if (getifaddrs(&list) != 0)
        socket_failure("getifaddrs");
    for (ifaddrs *a = list; a; a = a->ifa_next) {
        if (!a->ifa_addr || a->ifa_addr->sa_family != AF_INET || !(a->ifa_flags & IFF_UP))
            continue;
        interface_address i;
        i.address = ntohl(reinterpret_cast<sockaddr_in *>(a->ifa_addr)->sin_addr.s_addr);
        if (a->ifa_netmask)
            i.netmask = ntohl(reinterpret_cast<sockaddr_in *>(a->ifa_netmask)->sin_addr.s_addr);
        i.broadcast = i.address | ~i.netmask;
        out.push_back(i);
    }
    freeifaddrs(list);
#endif
    return out;
}

std::uint32_t route_to(endpoint peer) {
    udp_socket probe;
    probe.bind(0, 0);
    probe.connect(peer);  // UDP: nothing is sent, the system picks a route
    return probe.local().address;
}

udp_socket::udp_socket() {
    start_winsock();
    native_socket s = ::socket(AF_INET, SOCK_DGRAM, IPPROTO_UDP);
    if (s == k_invalid)
        socket_failure("socket()");
    fd_ = std::intptr_t(s);
#ifdef _WIN32
    // A UDP socket on Windows reports an ICMP "port unreachable" as
    // WSAECONNRESET on the next receive; ignored in receive() as elsewhere.
#endif
}

udp_socket::~udp_socket() {
#ifdef _WIN32
    closesocket(native(fd_));
#else
    ::close(native(fd_));
#endif
}

// The calls below change the socket's state in the system (its address, its
// peer, its buffers, its queue), which the descriptor does not show: they
// are not const though they write no member.
// NOLINTBEGIN(readability-make-member-function-const)
void udp_socket::bind(std::uint32_t address, std::uint16_t port) {
    sockaddr_in a = to_native({address, port});
    if (::bind(native(fd_), reinterpret_cast<sockaddr *>(&a), sizeof a) != 0)
        socket_failure(("bind(" + to_string({address, port}, 0xFFFF) + ")").c_str());
}

void udp_socket::connect(endpoint peer) {
    sockaddr_in a = to_native(peer);
    if (::connect(native(fd_), reinterpret_cast<sockaddr *>(&a), sizeof a) != 0)
        socket_failure(("connect(" + to_string(peer, 0xFFFF) + ")").c_str());
}

endpoint udp_socket::local() const {
    sockaddr_in a;
    std::memset(&a, 0, sizeof a);
    socklen_t length = sizeof a;
    if (::getsockname(native(fd_), reinterpret_cast<sockaddr *>(&a), &length) != 0)
        socket_failure("getsockname()");
    return {ntohl(a.sin_addr.s_addr), ntohs(a.sin_port)};
}

void udp_socket::set_broadcast(bool on) {
    int value = on ? 1 : 0;
    if (::setsockopt(native(fd_), SOL_SOCKET, SO_BROADCAST, reinterpret_cast<const char *>(&value),
                     sizeof value) != 0)
        socket_failure("setsockopt(SO_BROADCAST)");
}

int udp_socket::set_receive_buffer(int bytes) {
    // Refusal is no error: the system keeps its size, which is reported.
    ::setsockopt(native(fd_), SOL_SOCKET, SO_RCVBUF, reinterpret_cast<const char *>(&bytes),
                 sizeof bytes);
    int granted = 0;
    socklen_t length = sizeof granted;
    if (::getsockopt(native(fd_), SOL_SOCKET, SO_RCVBUF, reinterpret_cast<char *>(&granted),
                     &length) != 0)
        socket_failure("getsockopt(SO_RCVBUF)");
    return granted;
}

void udp_socket::send_to(const void *data, std::size_t bytes, endpoint to) {
    sockaddr_in a = to_native(to);
    const auto sent = ::sendto(native(fd_), static_cast<const char *>(data), int(bytes), 0,
                               reinterpret_cast<sockaddr *>(&a), sizeof a);
    if (sent < 0)
        socket_failure(("sendto(" + to_string(to, 0xFFFF) + ")").c_str());
}

void udp_socket::send(const void *data, std::size_t bytes) {
    const auto sent = ::send(native(fd_), static_cast<const char *>(data), int(bytes), 0);
    if (sent < 0) {
        if (unreachable(last_error()))
            return;  // an earlier datagram's ICMP error; this one is gone anyway
        socket_failure("send()");
    }
}

bool udp_socket::receive(void *buffer, std::size_t capacity, std::size_t &got, endpoint *from,
                         unsigned timeout_ms) {
    got = 0;
#ifdef _WIN32
    fd_set read_set;
    FD_ZERO(&read_set);
    FD_SET(native(fd_), &read_set);
    timeval tv;
    tv.tv_sec = long(timeout_ms / 1000);
    tv.tv_usec = long(timeout_ms % 1000) * 1000;
    const int ready = ::select(0, &read_set, nullptr, nullptr, &tv);
#else
    pollfd p;
    p.fd = native(fd_);
    p.events = POLLIN;
    p.revents = 0;
    int ready = ::poll(&p, 1, int(timeout_ms));
    if (ready < 0 && errno == EINTR)
        ready = 0;  // a signal: the caller's loop waits again
#endif
    if (ready < 0)
        socket_failure("poll()");
    if (ready == 0)
        return false;
    sockaddr_in a;
    std::memset(&a, 0, sizeof a);
    socklen_t length = sizeof a;
    const auto n = ::recvfrom(native(fd_), static_cast<char *>(buffer), int(capacity), 0,
                              reinterpret_cast<sockaddr *>(&a), &length);
    if (n < 0) {
        const int code = last_error();
#ifdef _WIN32
        if (code == WSAEMSGSIZE) {  // cut to the buffer, as on POSIX
            got = capacity;
            if (from)
                *from = {ntohl(a.sin_addr.s_addr), ntohs(a.sin_port)};
            return true;
        }
#endif
        if (unreachable(code))
            return false;
        socket_failure("recvfrom()");
    }
    got = std::size_t(n);
    if (from)
        *from = {ntohl(a.sin_addr.s_addr), ntohs(a.sin_port)};
    return true;
}
// NOLINTEND(readability-make-member-function-const)

}  // namespace flt::gige
