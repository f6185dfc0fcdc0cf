// SPDX-License-Identifier: Apache-2.0
// libFuzzer harness: the GenICam XML and ZIP reader of the USB3 Vision
// client (lib/sources/u3v/genicam.cpp, internal: flt::u3v::unzip_single,
// genicam_map::parse and resolve). The first byte picks the input's form:
// a ZIP archive (inflated, then parsed when it holds XML) or the XML text
// itself; then feature names are resolved: the camera's usual ones, every
// node's own name (following pValue links, possibly in cycles), and names
// from the input. Bad input must raise flt::error with FORMAT (zip, XML) or
// NOT_FOUND (resolve) - the statuses the public API turns them into. Any
// other exception would surface as FLT_ERR_INTERNAL: the harness aborts.
#include <cstdint>
#include <cstdlib>
#include <string>

#include "core/error.hpp"
#include "sources/u3v/genicam.hpp"

namespace {

void resolve_all(const flt::u3v::genicam_map &map, const std::string &extra) {
    static const char *const names[] = {"Width",           "Height",          "PixelFormat",
                                        "OffsetY",         "AcquisitionMode", "AcquisitionStart",
                                        "AcquisitionStop", "ExposureTime",    "Gain",
                                        "TriggerMode",     "TriggerSource",   ""};
    for (const char *name : names) {
        try {
            (void)map.resolve(name);
        } catch (const flt::error &e) {
            if (e.status != FLT_ERR_NOT_FOUND && e.status != FLT_ERR_FORMAT)
                std::abort();
        }
    }
    try {
        (void)map.resolve(extra);
    } catch (const flt::error &e) {
        if (e.status != FLT_ERR_NOT_FOUND && e.status != FLT_ERR_FORMAT)
            std::abort();
    }
}

void parse_and_resolve(const std::string &xml, const std::string &extra) {
    flt::u3v::genicam_map map;
    try {
        map.parse(xml);
    } catch (const flt::error &e) {
        if (e.status != FLT_ERR_FORMAT)
            std::abort();
        return;
    }
    resolve_all(map, extra);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
    if (size < 1)
        return 0;
    const std::uint8_t mode = data[0];
    ++data, --size;
    // The last up to 16 bytes name one more feature to resolve.
    const std::size_t extra_n = size < 16 ? size : 16;
    const std::string extra(reinterpret_cast<const char *>(data + size - extra_n), extra_n);
    try {
        if (mode & 1) {
            std::string inflated;
            try {
                inflated = flt::u3v::unzip_single(data, size);
            } catch (const flt::error &e) {
                if (e.status != FLT_ERR_FORMAT)
                    std::abort();
                return 0;
            }
            parse_and_resolve(inflated, extra);
        } else {
            parse_and_resolve(std::string(reinterpret_cast<const char *>(data), size), extra);
        }
    } catch (const std::bad_alloc &) {
        // A declared size the allocator refuses is FLT_ERR_OUT_OF_MEMORY.
    }
    return 0;
}
