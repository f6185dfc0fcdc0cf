// SPDX-License-Identifier: Apache-2.0
// libFuzzer harness: the GenICam engine (lib/sources/genicam/, internal:
// flt::genicam::unzip_single, xml_document, node_map). The first byte picks
// the input's form:
//   bit 0   a ZIP archive (inflated, then loaded when it holds XML), else
//           the description's text itself;
//   bit 1   the next two bytes give a length n (big endian, at most 4096)
//           and the n bytes after them are the camera's registers; without
//           it the registers are the input's own bytes.
// Registers repeat: address a reads register byte a % n. Then features are
// evaluated - the camera's usual ones, the first 64 of the description and
// a name made of the input's last 16 bytes: values, access, flags, bounds,
// entries, the register behind them, and writes. The same description is
// then read the way a camera source reads it (lib/sources/camera/
// features.cpp: the engine behind feature_layer, a register mapped by
// address in front of it, both byte orders). Bad input must raise
// flt::error with a status the public API documents for it (FORMAT,
// NOT_FOUND, NUMERIC, STATE, INVALID_ARGUMENT) or std::bad_alloc; any other
// exception, or FLT_ERR_INTERNAL, would reach a caller as an internal
// error: the harness aborts. A float value read without an error must be
// finite (a NaN only ever appears with its flag, and features have none).
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "sources/camera/features.hpp"
#include "sources/genicam/node_map.hpp"
#include "sources/genicam/text.hpp"

namespace {

struct fuzz_port : flt::genicam::register_port {
    const std::uint8_t *bytes = nullptr;
    std::size_t n = 0;
    void read(std::uint64_t address, std::uint8_t *out, std::size_t count) override {
        for (std::size_t i = 0; i < count; ++i)
            out[i] = n ? bytes[(address + i) % n] : 0;
    }
    void write(std::uint64_t, const std::uint8_t *, std::size_t) override {}
};

bool allowed(flt_status s) {
    return s == FLT_ERR_FORMAT || s == FLT_ERR_NOT_FOUND || s == FLT_ERR_NUMERIC ||
           s == FLT_ERR_STATE || s == FLT_ERR_INVALID_ARGUMENT;
}

template <class F> void expect(F &&call) {
    try {
        call();
    } catch (const flt::error &e) {
        if (!allowed(e.status) || e.what()[0] == '\0')
            std::abort();
    }
}

void evaluate(flt::genicam::node_map &map, const std::string &name) {
    using flt::genicam::interface_kind;
    expect([&] { (void)map.access(name); });
    expect([&] { (void)map.flags(name); });
    expect([&] {
        flt::genicam::register_info r;
        (void)map.register_of(name, r);
    });
    interface_kind kind = interface_kind::none;
    expect([&] { kind = map.interface_of(name); });
    expect([&] { (void)map.get_int(name, false); });
    expect([&] {
        if (!std::isfinite(map.get_float(name, false)))
            std::abort();
    });
    expect([&] { (void)map.get_string(name, false); });
    expect([&] { (void)map.int_min(name); });
    expect([&] { (void)map.int_max(name); });
    expect([&] { (void)map.int_inc(name); });
    expect([&] { (void)map.float_min(name); });
    expect([&] { (void)map.float_max(name); });
    if (kind == interface_kind::enumeration) {
        expect([&] {
            const auto entries = map.enum_entries(name);
            if (!entries.empty())
                map.set_enum(name, entries.back().name);
        });
    }
    expect([&] { map.set_int(name, 16); });
    expect([&] { map.set_float(name, 1.5); });
    expect([&] { map.set_string(name, "x"); });
    if (kind == interface_kind::command) {
        expect([&] { map.execute(name, false); });
        expect([&] { (void)map.is_done(name); });
    }
}

void load_and_evaluate(const std::string &text, fuzz_port &port, const std::string &extra) {
    flt::genicam::node_map map;
    try {
        map.load(flt::genicam::xml_document(text));
    } catch (const flt::error &e) {
        if (e.status != FLT_ERR_FORMAT)
            std::abort();
        return;
    }
    map.bind(&port);
    static const char *const usual[] = {"Width",
                                        "Height",
                                        "OffsetX",
                                        "OffsetY",
                                        "PixelFormat",
                                        "PayloadSize",
                                        "AcquisitionMode",
                                        "AcquisitionStart",
                                        "AcquisitionStop",
                                        "ExposureTime",
                                        "Gain",
                                        "TriggerSelector",
                                        "TriggerMode",
                                        "TriggerSource",
                                        "TLParamsLocked",
                                        "DeviceVendorName",
                                        "DeviceModelName",
                                        ""};
    for (const char *name : usual)
        evaluate(map, name);
    const std::vector<std::string> names = map.feature_names();
    for (std::size_t i = 0; i < names.size() && i < 64; ++i)
        evaluate(map, names[i]);
    evaluate(map, extra);

    // The camera's path: the engine behind feature_layer, with a register
    // mapped by address (what flt_source_map_feature does).
    std::unique_ptr<flt::sources::feature_layer> layer;
    expect([&] {
        layer = std::make_unique<flt::sources::feature_layer>(
            port, flt::sources::make_feature_engine(text, port), (port.n & 1) != 0);
    });
    if (!layer)
        return;
    const std::uint32_t lengths[] = {1, 2, 4, 8};
    expect([&] {
        layer->map_feature("Mapped", port.n, lengths[port.n % 4],
                           port.n % 3 == 0 && port.n % 4 >= 2);
    });
    for (const std::string &name : {std::string("Mapped"), extra, std::string("Width"),
                                    names.empty() ? std::string() : names.front()}) {
        expect([&] { (void)layer->get_int(name); });
        expect([&] {
            if (!std::isfinite(layer->get_float(name)))
                std::abort();
        });
        expect([&] { layer->set_int(name, 7); });
        expect([&] { layer->set_float(name, 0.25); });
        expect([&] { (void)layer->kind_of(name); });
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size) {
    if (size < 1)
        return 0;
    const std::uint8_t mode = data[0];
    ++data, --size;
    fuzz_port port;
    if ((mode & 2) && size >= 2) {
        std::size_t n = (std::size_t(data[0]) << 8) | data[1];
        data += 2, size -= 2;
        n = n > 4096 ? 4096 : n;
        n = n > size ? size : n;
        port.bytes = data;
        port.n = n;
        data += n, size -= n;
    } else {
        port.bytes = data;
        port.n = size;
    }
    // The last up to 16 bytes name one more feature to evaluate.
    const std::size_t extra_n = size < 16 ? size : 16;
    const std::string extra(reinterpret_cast<const char *>(data + size - extra_n), extra_n);
    try {
        if (mode & 1) {
            std::string inflated;
            try {
                inflated = flt::genicam::unzip_single(data, size);
            } catch (const flt::error &e) {
                if (e.status != FLT_ERR_FORMAT)
                    std::abort();
                return 0;
            }
            load_and_evaluate(inflated, port, extra);
        } else {
            load_and_evaluate(std::string(reinterpret_cast<const char *>(data), size), port, extra);
        }
    } catch (const std::bad_alloc &) {
        // A size the allocator refuses is FLT_ERR_OUT_OF_MEMORY.
    }
    return 0;
}
