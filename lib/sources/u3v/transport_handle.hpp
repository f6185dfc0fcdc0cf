// SPDX-License-Identifier: Apache-2.0
// Internal: the opaque flt_usb_transport of flatline/source.h - a
// usb_backend (transport.hpp) made outside libflatline, by a companion
// library of the same release (libflatline_testing's simulated bus). The
// two libraries meet only through this struct and the virtual calls of
// usb_backend / usb_device, so they must agree on both: the handle carries
// the release and the revision of the interface it was made for, and
// libflatline refuses any other. No exception crosses that boundary (the
// backend answers usb_status).
#pragma once

#include <cstdint>

#include "flatline/version.h"
#include "sources/u3v/transport.hpp"

namespace flt::u3v {
constexpr std::uint32_t k_usb_transport_magic = 0x464c5458u;  // "FLTX"
// Bump the last digit when transport.hpp or this struct changes.
constexpr std::uint32_t k_usb_transport_revision = std::uint32_t(FLT_VERSION_NUMBER) * 16u + 1u;
}  // namespace flt::u3v

struct flt_usb_transport {
    std::uint32_t magic = flt::u3v::k_usb_transport_magic;
    std::uint32_t revision = flt::u3v::k_usb_transport_revision;
    flt::u3v::usb_backend *backend = nullptr;
};
