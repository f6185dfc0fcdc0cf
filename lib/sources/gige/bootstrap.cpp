// SPDX-License-Identifier: Apache-2.0
// GigE Vision bootstrap registers and the description (see bootstrap.hpp).
#include "sources/gige/bootstrap.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <vector>

#include "core/error.hpp"
#include "sources/genicam/text.hpp"
#include "sources/gige/discovery.hpp"
#include "sources/gige/protocol.hpp"
#include "sources/source.hpp"

namespace flt::gige {

using sources::raise;

bootstrap_info read_bootstrap(control_channel &control) {
    bootstrap_info b;
    std::vector<std::uint8_t> head(k_discovery_data);
    control.read(0, head.data(), head.size());
    const camera_info c = parse_discovery(head.data(), head.size(), control.camera());
    b.strings = c.strings;
    b.gev_version = c.gev_version;
    b.capabilities = control.read_register(bootstrap::gvcp_capability);
    b.stream_channels = control.read_register(bootstrap::stream_channels);
    b.tick_hz = (std::uint64_t(control.read_register(bootstrap::tick_frequency_high)) << 32) |
                control.read_register(bootstrap::tick_frequency_low);
    std::vector<std::uint8_t> url(512);
    control.read(bootstrap::first_url, url.data(), url.size());
    std::size_t n = 0;
    while (n < url.size() && url[n] != 0)
        ++n;
    b.first_url.assign(reinterpret_cast<const char *>(url.data()), n);
    return b;
}

device_description read_description(sources::register_port &port, const std::string &url) {
    // The camera's register text, untrusted: "local" alone (no ':') is no
    // URL either (substr past its end would throw out_of_range).
    const std::size_t colon = url.find(':');
    std::string scheme = url.substr(0, std::min<std::size_t>(colon, url.size()));
    std::transform(scheme.begin(), scheme.end(), scheme.begin(),
                   [](unsigned char ch) { return char(std::tolower(ch)); });
    if (scheme != "local" || colon == std::string::npos)
        raise(FLT_ERR_FORMAT,
              "the camera's description is at '%.200s': only a description in the camera's "
              "memory (a Local: URL) is read",
              url.c_str());
    // Local:name;address;length[?SchemaVersion=x.y.z]
    const std::string rest = url.substr(scheme.size() + 1);
    const std::size_t s1 = rest.find(';'),
                      s2 = s1 == std::string::npos ? s1 : rest.find(';', s1 + 1);
    if (s2 == std::string::npos)
        raise(FLT_ERR_FORMAT, "the description URL '%.200s' is not name;address;length",
              url.c_str());
    const std::string name = rest.substr(0, s1);
    std::uint64_t address = 0, length = 0;
    const char *a = rest.c_str() + s1 + 1, *a_end = rest.c_str() + s2;
    const char *l = rest.c_str() + s2 + 1, *l_end = rest.c_str() + rest.size();
    auto ra = std::from_chars(a, a_end, address, 16);
    auto rl = std::from_chars(l, l_end, length, 16);
    if (ra.ec != std::errc() || ra.ptr != a_end || rl.ec != std::errc() || rl.ptr == l ||
        (rl.ptr != l_end && *rl.ptr != '?'))
        raise(FLT_ERR_FORMAT, "the description URL '%.200s' has no hexadecimal address and length",
              url.c_str());
    if (length == 0 || length > (64u << 20))
        raise(FLT_ERR_FORMAT, "the description URL '%.200s' gives a file of %llu bytes",
              url.c_str(), (unsigned long long)length);
    std::vector<std::uint8_t> file(static_cast<std::size_t>(length));
    port.read(address, file.data(), file.size());
    std::string lower = name;
    std::transform(lower.begin(), lower.end(), lower.begin(),
                   [](unsigned char ch) { return char(std::tolower(ch)); });
    device_description d;
    d.file_bytes = length;
    d.zipped = (lower.size() > 4 && lower.compare(lower.size() - 4, 4, ".zip") == 0) ||
               genicam::looks_zipped(file.data(), file.size());
    if (d.zipped)
        d.xml = genicam::unzip_single(file.data(), file.size());
    else
        d.xml.assign(reinterpret_cast<const char *>(file.data()), file.size());
    // A description padded with NULs to its register block ends at the first.
    const std::size_t nul = d.xml.find('\0');
    if (nul != std::string::npos)
        d.xml.resize(nul);
    return d;
}

}  // namespace flt::gige
