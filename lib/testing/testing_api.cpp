// SPDX-License-Identifier: Apache-2.0
// The C API of libflatline_testing (flatline/testing.h): the simulated USB
// bus of simulated USB3 Vision cameras, and its transport for libflatline.
#include <cstring>

#include "core/error.hpp"
#include "flatline/testing.h"
#include "sources/u3v/transport_handle.hpp"
#include "testing/sim_camera.hpp"

using namespace flt;

namespace {
constexpr std::uint32_t k_bus_magic = 0x464c5455u;  // "FLTU"

flt_status check_bus(const char *fn, const flt_u3v_sim *bus);
flt_status check_camera(const char *fn, const flt_u3v_sim *bus, std::size_t camera);
}  // namespace

struct flt_u3v_sim {
    std::uint32_t magic = k_bus_magic;
    testing::sim_bus bus;
    flt_usb_transport transport;
    flt_u3v_sim() { transport.backend = &bus; }
};

namespace {

flt_status check_bus(const char *fn, const flt_u3v_sim *bus) {
    if (bus == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'bus' is NULL", fn);
    if (bus->magic != k_bus_magic)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'bus' is not a live flt_u3v_sim", fn);
    return FLT_OK;
}

flt_status check_camera(const char *fn, const flt_u3v_sim *bus, std::size_t camera) {
    if (flt_status st = check_bus(fn, bus))
        return st;
    if (camera >= bus->bus.cameras())
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'camera' = %zu but the bus has %zu camera(s)", fn, camera,
                    bus->bus.cameras());
    return FLT_OK;
}

}  // namespace

extern "C" {

FLT_TESTING_API flt_status FLT_CALL flt_u3v_sim_create(flt_u3v_sim **out) {
    const char *fn = "flt_u3v_sim_create";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = new flt_u3v_sim;
        return FLT_OK;
    });
}

FLT_TESTING_API void FLT_CALL flt_u3v_sim_destroy(flt_u3v_sim *bus) {
    guard_void([&] {
        if (bus && bus->magic == k_bus_magic) {
            bus->magic = 0;
            bus->transport.magic = 0;
            delete bus;
        }
    });
}

FLT_TESTING_API flt_status FLT_CALL flt_u3v_sim_transport(flt_u3v_sim *bus,
                                                          flt_usb_transport **out) {
    const char *fn = "flt_u3v_sim_transport";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        if (flt_status st = check_bus(fn, bus))
            return st;
        *out = &bus->transport;
        return FLT_OK;
    });
}

FLT_TESTING_API flt_status FLT_CALL flt_u3v_sim_add_camera(flt_u3v_sim *bus, const char *vendor,
                                                           const char *model, const char *serial,
                                                           uint32_t width, uint32_t height,
                                                           flt_pixel_format format,
                                                           size_t *index_out) {
    const char *fn = "flt_u3v_sim_add_camera";
    return guard(fn, [&] {
        if (flt_status st = check_bus(fn, bus))
            return st;
        FLT_CHECK_NOT_NULL(fn, vendor);
        FLT_CHECK_NOT_NULL(fn, model);
        FLT_CHECK_NOT_NULL(fn, serial);
        for (const char *s : {vendor, model, serial})
            if (std::strlen(s) > 63)
                return fail(FLT_ERR_INVALID_ARGUMENT,
                            "%s: string '%.80s...' is longer than 63 bytes", fn, s);
        if (bus->bus.cameras() >= 8)
            return fail(FLT_ERR_BUFFER_FULL, "%s: the bus already holds 8 cameras", fn);
        if (width < 16 || width > 8192)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'width' = %u is outside [16, 8192]",
                        fn, width);
        if (height < 16 || height > 8192)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'height' = %u is outside [16, 8192]", fn, height);
        const int raw_format = enum_arg(format);
        if (raw_format != FLT_PIXEL_MONO8 && raw_format != FLT_PIXEL_MONO10 &&
            raw_format != FLT_PIXEL_MONO12 && raw_format != FLT_PIXEL_MONO16)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'format' = %d is not a pixel format", fn, raw_format);
        const std::size_t index =
            bus->bus.add_camera(vendor, model, serial, width, height, raw_format);
        if (index_out)
            *index_out = index;
        return FLT_OK;
    });
}

FLT_TESTING_API flt_status FLT_CALL flt_u3v_sim_set_frames(flt_u3v_sim *bus, size_t camera,
                                                           flt_sim *sim) {
    const char *fn = "flt_u3v_sim_set_frames";
    return guard(fn, [&] {
        if (flt_status st = check_camera(fn, bus, camera))
            return st;
        testing::sim_set_frames(bus->bus.camera(camera), sim);
        return FLT_OK;
    });
}

FLT_TESTING_API flt_status FLT_CALL flt_u3v_sim_set(flt_u3v_sim *bus, size_t camera,
                                                    flt_u3v_sim_param param, uint64_t value) {
    const char *fn = "flt_u3v_sim_set";
    return guard(fn, [&] {
        if (flt_status st = check_camera(fn, bus, camera))
            return st;
        if (enum_arg(param) < 0)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'param' = %d: the parameter is unknown", fn, enum_arg(param));
        testing::sim_set(bus->bus.camera(camera), param, value);
        return FLT_OK;
    });
}

FLT_TESTING_API flt_status FLT_CALL flt_u3v_sim_get(const flt_u3v_sim *bus, size_t camera,
                                                    flt_u3v_sim_param param, uint64_t *out) {
    const char *fn = "flt_u3v_sim_get";
    return guard(fn, [&] {
        if (flt_status st = check_camera(fn, bus, camera))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (enum_arg(param) < 0)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'param' = %d: the parameter is unknown", fn, enum_arg(param));
        *out = testing::sim_get(bus->bus.camera(camera), param);
        return FLT_OK;
    });
}

FLT_TESTING_API flt_status FLT_CALL flt_u3v_sim_inject(flt_u3v_sim *bus, size_t camera,
                                                       flt_u3v_fault fault, uint64_t at,
                                                       uint32_t count) {
    const char *fn = "flt_u3v_sim_inject";
    return guard(fn, [&] {
        if (flt_status st = check_camera(fn, bus, camera))
            return st;
        if (enum_arg(fault) < 0)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'fault' = %d: the fault is unknown",
                        fn, enum_arg(fault));
        testing::sim_inject(bus->bus.camera(camera), fault, at, count);
        return FLT_OK;
    });
}

FLT_TESTING_API flt_status FLT_CALL flt_u3v_sim_peek(const flt_u3v_sim *bus, size_t camera,
                                                     uint64_t address, uint32_t *out) {
    const char *fn = "flt_u3v_sim_peek";
    return guard(fn, [&] {
        if (flt_status st = check_camera(fn, bus, camera))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (!testing::sim_peek(bus->bus.camera(camera), address, *out))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'address' = 0x%llx is outside the register map", fn,
                        (unsigned long long)address);
        return FLT_OK;
    });
}

}  // extern "C"
