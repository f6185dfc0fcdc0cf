// SPDX-License-Identifier: Apache-2.0
#include "sources/u3v/bootstrap.hpp"

#include <cstring>
#include <vector>

#include "core/error.hpp"
#include "sources/source.hpp"
#include "sources/genicam/text.hpp"
#include "sources/u3v/protocol.hpp"

namespace flt::u3v {

using sources::raise;

bootstrap_info read_bootstrap(control_channel &control) {
    bootstrap_info info;
    // The transfer limits are unknown until SBRM is read: read them with
    // 8-byte requests first, which every GenCP device accepts.
    std::uint8_t b[8];
    control.read(abrm::sbrm_address, b, 8);
    info.sbrm_address = get_u64(b);
    control.read(info.sbrm_address + sbrm::max_command, b, 8);
    if (get_u32(b) >= k_writemem_overhead + 4 && get_u32(b + 4) >= k_gencp_header + 4)
        control.set_limits(get_u32(b), get_u32(b + 4));
    std::uint8_t s[sbrm::size];
    control.read(info.sbrm_address, s, sizeof s);
    info.u3v_version = get_u32(s + sbrm::u3v_version);
    const std::uint32_t max_command = get_u32(s + sbrm::max_command);
    const std::uint32_t max_ack = get_u32(s + sbrm::max_ack);
    if (max_command < k_writemem_overhead + 4 || max_ack < k_gencp_header + 4)
        raise(FLT_ERR_FORMAT,
              "SBRM: max command transfer %u / max ack transfer %u bytes are too small for GenCP",
              max_command, max_ack);
    control.set_limits(max_command, max_ack);
    info.sirm_address = get_u64(s + sbrm::sirm_address);
    if (get_u32(s + sbrm::stream_channels) == 0)
        info.sirm_address = 0;

    std::vector<std::uint8_t> a(abrm::size);
    control.read(0, a.data(), a.size());
    info.gencp_version = get_u32(&a[abrm::gencp_version]);
    const std::uint64_t where[7] = {
        abrm::manufacturer,      abrm::model,  abrm::family,   abrm::device_version,
        abrm::manufacturer_info, abrm::serial, abrm::user_name};
    for (int i = 0; i < 7; ++i) {
        const char *text = reinterpret_cast<const char *>(&a[where[i]]);
        info.strings[i].assign(text, strnlen(text, abrm::string_length));
    }
    info.response_ms = get_u32(&a[abrm::response_time]);
    info.manifest_address = get_u64(&a[abrm::manifest_address]);
    control.set_response_time(info.response_ms);
    return info;
}

device_description read_description(sources::register_port &port, std::uint64_t manifest_address) {
    std::uint8_t head[8];
    port.read(manifest_address, head, 8);
    const std::uint64_t entries = get_u64(head);
    if (entries == 0 || entries > 64)
        raise(FLT_ERR_FORMAT, "the manifest table at 0x%llx has %llu entries",
              (unsigned long long)manifest_address, (unsigned long long)entries);
    // The first entry of a known file type (0 raw XML, 1 ZIP).
    for (std::uint64_t i = 0; i < entries; ++i) {
        std::uint8_t e[64];
        port.read(manifest_address + 8 + 64 * i, e, 64);
        const std::uint32_t type = (get_u32(e + 4) >> 10) & 0x3F;
        const std::uint64_t address = get_u64(e + 8), size = get_u64(e + 16);
        if (type > 1)
            continue;
        if (size == 0 || size > (64u << 20))
            raise(FLT_ERR_FORMAT, "manifest entry %llu: GenICam file size %llu bytes",
                  (unsigned long long)i, (unsigned long long)size);
        std::vector<std::uint8_t> file(size);
        port.read(address, file.data(), file.size());
        device_description d;
        d.file_bytes = size;
        d.zipped = type == 1;
        d.xml = d.zipped ? genicam::unzip_single(file.data(), file.size())
                         : std::string(reinterpret_cast<const char *>(file.data()), file.size());
        return d;
    }
    raise(FLT_ERR_FORMAT, "the manifest lists no GenICam XML or ZIP file");
}

}  // namespace flt::u3v
