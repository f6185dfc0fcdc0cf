// SPDX-License-Identifier: Apache-2.0
// The C API of flatline/genicam.h: the offline view of a camera
// description, the node map over a memory image or the caller's callbacks.
#include "flatline/genicam.h"

#include <cfloat>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/utf8_path.hpp"
#include "sources/genicam/node_map.hpp"
#include "sources/genicam/text.hpp"

using flt::fail;
using flt::guard;
using flt::utf8_path;

namespace {

// The largest memory image, bytes (offline views of register maps are a
// few kilobytes to megabytes; this bounds what a caller can make us hold).
constexpr std::size_t k_max_image_bytes = std::size_t(256) << 20;
constexpr std::size_t k_max_set_bytes = std::size_t(64) << 20;
// A description file larger than this is refused before it is read whole.
constexpr std::size_t k_max_file_bytes = std::size_t(64) << 20;

std::string hex(std::uint64_t v) {
    char b[24];
    std::snprintf(b, sizeof b, "0x%" PRIx64, v);
    return b;
}

// Sparse memory: pages of 4 KiB with a presence mask.
class memory_image {
  public:
    static constexpr std::uint64_t page_bytes = 4096;
    void set(std::uint64_t address, const std::uint8_t *in, std::size_t n) {
        for (std::size_t i = 0; i < n; ++i) {
            page &p = pages_[(address + i) / page_bytes];
            if (p.bytes.empty()) {
                p.bytes.assign(page_bytes, 0);
                p.present.assign(page_bytes, false);
            }
            const std::size_t at = std::size_t((address + i) % page_bytes);
            p.bytes[at] = in[i];
            p.present[at] = true;
        }
    }
    // False (with `missing` set) when a byte is not in the image.
    bool get(std::uint64_t address, std::uint8_t *out, std::size_t n,
             std::uint64_t &missing) const {
        for (std::size_t i = 0; i < n; ++i) {
            auto it = pages_.find((address + i) / page_bytes);
            const std::size_t at = std::size_t((address + i) % page_bytes);
            if (it == pages_.end() || !it->second.present[at]) {
                missing = address + i;
                return false;
            }
            out[i] = it->second.bytes[at];
        }
        return true;
    }
    // Bytes of pages that `set(address, n)` would add.
    std::size_t growth(std::uint64_t address, std::size_t n) const {
        if (n == 0)
            return 0;
        std::size_t grow = 0;
        for (std::uint64_t p = address / page_bytes; p <= (address + n - 1) / page_bytes; ++p)
            if (pages_.find(p) == pages_.end())
                grow += page_bytes;
        return grow;
    }
    std::size_t bytes() const { return pages_.size() * page_bytes; }
    void clear() { pages_.clear(); }

  private:
    struct page {
        std::vector<std::uint8_t> bytes;
        std::vector<bool> present;
    };
    std::map<std::uint64_t, page> pages_;
};

}  // namespace

struct flt_genicam {
    flt::genicam::node_map map;
    memory_image image;
    flt_genicam_read_fn read = nullptr;
    flt_genicam_write_fn write = nullptr;
    void *user = nullptr;
    std::vector<std::string> features;
    std::map<std::string, std::size_t> feature_index;
    std::string vendor, model, schema;
    std::string scratch;             // the last string value handed out
    std::set<std::string> interned;  // entry names handed out (stable)

    // The node map's register port: the image or the callbacks.
    struct port : flt::genicam::register_port {
        flt_genicam &g;
        explicit port(flt_genicam &owner) : g(owner) {}
        void read(std::uint64_t address, std::uint8_t *out, std::size_t bytes) override {
            if (g.read) {
                const int rc = g.read(g.user, address, out, bytes);
                if (rc != 0)
                    throw flt::error(FLT_ERR_DEVICE, ("the read callback returned " +
                                                      std::to_string(rc) + " for " + hex(address))
                                                         .c_str());
                return;
            }
            std::uint64_t missing = 0;
            if (!g.image.get(address, out, bytes, missing))
                throw flt::error(FLT_ERR_NOT_FOUND,
                                 ("the memory image holds no byte at " + hex(missing) +
                                  " (give it with flt_genicam_set_memory)")
                                     .c_str());
        }
        void write(std::uint64_t address, const std::uint8_t *in, std::size_t bytes) override {
            if (g.read) {
                if (!g.write)
                    throw flt::error(FLT_ERR_STATE,
                                     "writes need a write callback (flt_genicam_set_registers)");
                const int rc = g.write(g.user, address, in, bytes);
                if (rc != 0)
                    throw flt::error(FLT_ERR_DEVICE, ("the write callback returned " +
                                                      std::to_string(rc) + " for " + hex(address))
                                                         .c_str());
                return;
            }
            if (g.image.bytes() + g.image.growth(address, bytes) > k_max_image_bytes)
                throw flt::error(FLT_ERR_OUT_OF_MEMORY,
                                 "the memory image would grow beyond 256 MiB");
            g.image.set(address, in, bytes);
        }
    } device{*this};

    void load(const std::uint8_t *data, std::size_t bytes) {
        std::string text = flt::genicam::looks_zipped(data, bytes)
                               ? flt::genicam::unzip_single(data, bytes)
                               : std::string(reinterpret_cast<const char *>(data), bytes);
        map.load(flt::genicam::xml_document(std::move(text)));
        map.bind(&device);
        // The register contents belong to the caller: nothing is cached
        // across calls (each call starts with map.invalidate()).
        features = map.feature_names();
        for (std::size_t i = 0; i < features.size(); ++i)
            feature_index.emplace(features[i], i);
        vendor = map.description_attribute("VendorName");
        model = map.description_attribute("ModelName");
        const int v = map.schema_version();
        schema = v ? std::to_string(v / 10000) + "." + std::to_string(v / 100 % 100) + "." +
                         std::to_string(v % 100)
                   : std::string();
    }
};

namespace {

flt_status check_feature(const char *fn, const flt_genicam *g, const char *feature) {
    if (!g)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'description' is NULL", fn);
    if (!feature)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'feature' is NULL", fn);
    if (g->feature_index.find(feature) == g->feature_index.end() && !g->map.has(feature))
        return fail(FLT_ERR_NOT_FOUND, "%s: feature '%.200s' is not in the description", fn,
                    feature);
    return FLT_OK;
}

flt_genicam_type type_of(flt::genicam::interface_kind k) {
    using flt::genicam::interface_kind;
    switch (k) {
        case interface_kind::integer:
            return FLT_GENICAM_INTEGER;
        case interface_kind::floating:
            return FLT_GENICAM_FLOAT;
        case interface_kind::enumeration:
            return FLT_GENICAM_ENUMERATION;
        case interface_kind::boolean:
            return FLT_GENICAM_BOOLEAN;
        case interface_kind::command:
            return FLT_GENICAM_COMMAND;
        case interface_kind::string:
            return FLT_GENICAM_STRING;
        case interface_kind::reg:
            return FLT_GENICAM_REGISTER;
        case interface_kind::category:
            return FLT_GENICAM_CATEGORY;
        default:
            break;
    }
    return FLT_GENICAM_TYPE_MAX_ENUM_;
}

// Every evaluating call: the handle and the feature are checked, and the
// register cache starts empty (the caller may have changed the registers).
#define FLT_GENICAM_CALL(name, body)                           \
  const char *fn = name;                                       \
  return guard(fn, [&] {                                       \
  if (flt_status st = check_feature(fn, description, feature)) \
    return st;                                                 \
  description->map.invalidate();                               \
  body;                                                        \
  return FLT_OK;                                               \
  })

}  // namespace

extern "C" {

FLT_API flt_status FLT_CALL flt_genicam_load(const char *path, flt_genicam **out) {
    const char *fn = "flt_genicam_load";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        FLT_CHECK_NOT_NULL(fn, path);
        std::error_code ec;
        if (std::filesystem::is_directory(utf8_path(path), ec))
            return fail(FLT_ERR_IO, "%s: '%.300s' is a folder, not a file", fn, path);
        std::ifstream in(utf8_path(path), std::ios::binary);
        if (!in)
            return fail(FLT_ERR_IO, "%s: cannot open '%.300s'", fn, path);
        // Read in chunks, at most 64 MiB: no size is trusted before reading.
        std::vector<std::uint8_t> bytes;
        char chunk[1 << 16];
        while (in.read(chunk, sizeof chunk) || in.gcount() > 0) {
            bytes.insert(bytes.end(), chunk, chunk + in.gcount());
            if (bytes.size() > k_max_file_bytes)
                return fail(FLT_ERR_FORMAT,
                            "%s: '%.300s' is larger than 64 MiB, which no GenICam file is", fn,
                            path);
            if (!in)
                break;
        }
        if (in.bad())
            return fail(FLT_ERR_IO, "%s: cannot read '%.300s'", fn, path);
        if (bytes.empty())
            return fail(FLT_ERR_FORMAT, "%s: '%.300s' is empty", fn, path);
        auto g = std::make_unique<flt_genicam>();
        g->load(bytes.data(), bytes.size());
        *out = g.release();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_genicam_load_memory(const void *data, size_t bytes,
                                                    flt_genicam **out) {
    const char *fn = "flt_genicam_load_memory";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        FLT_CHECK_NOT_NULL(fn, data);
        if (bytes == 0 || bytes > k_max_file_bytes)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'bytes' = %zu is not 1 .. 64 MiB",
                        fn, bytes);
        auto g = std::make_unique<flt_genicam>();
        g->load(static_cast<const std::uint8_t *>(data), bytes);
        *out = g.release();
        return FLT_OK;
    });
}

FLT_API void FLT_CALL flt_genicam_destroy(flt_genicam *description) {
    flt::guard_void([&] { delete description; });
}

FLT_API flt_status FLT_CALL flt_genicam_get_text(const flt_genicam *description,
                                                 flt_genicam_text which, const char **out) {
    const char *fn = "flt_genicam_get_text";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, description);
        FLT_CHECK_NOT_NULL(fn, out);
        switch (flt::enum_arg(which)) {
            case FLT_GENICAM_VENDOR_NAME:
                *out = description->vendor.c_str();
                return FLT_OK;
            case FLT_GENICAM_MODEL_NAME:
                *out = description->model.c_str();
                return FLT_OK;
            case FLT_GENICAM_SCHEMA_VERSION:
                *out = description->schema.c_str();
                return FLT_OK;
            default:
                return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'which' = %d is no text", fn,
                            flt::enum_arg(which));
        }
    });
}

FLT_API flt_status FLT_CALL flt_genicam_feature_count(const flt_genicam *description, size_t *out) {
    const char *fn = "flt_genicam_feature_count";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, description);
        FLT_CHECK_NOT_NULL(fn, out);
        *out = description->features.size();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_genicam_feature_name(const flt_genicam *description, size_t index,
                                                     const char **out) {
    const char *fn = "flt_genicam_feature_name";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, description);
        FLT_CHECK_NOT_NULL(fn, out);
        if (index >= description->features.size())
            return fail(FLT_ERR_NOT_FOUND, "%s: argument 'index' = %zu is past the %zu features",
                        fn, index, description->features.size());
        *out = description->features[index].c_str();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_genicam_feature_info(const flt_genicam *description,
                                                     const char *feature, flt_genicam_type *type,
                                                     const char **kind, const char **unit) {
    const char *fn = "flt_genicam_feature_info";
    return guard(fn, [&] {
        if (flt_status st = check_feature(fn, description, feature))
            return st;
        if (type)
            *type = type_of(description->map.interface_of(feature));
        if (kind)
            *kind = description->map.kind_of(feature).c_str();
        if (unit)
            *unit = description->map.unit(feature).c_str();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_genicam_category_entry(const flt_genicam *description,
                                                       const char *category, size_t index,
                                                       const char **out) {
    const char *fn = "flt_genicam_category_entry";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, description);
        FLT_CHECK_NOT_NULL(fn, category);
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        if (!description->map.has(category) ||
            description->map.interface_of(category) != flt::genicam::interface_kind::category)
            return fail(FLT_ERR_NOT_FOUND, "%s: '%.200s' is no category of the description", fn,
                        category);
        const std::size_t n = description->map.category_size(category);
        if (index >= n)
            return fail(FLT_ERR_NOT_FOUND,
                        "%s: argument 'index' = %zu is past the %zu entries of category "
                        "'%.200s'",
                        fn, index, n, category);
        *out = description->map.category_feature(category, index).c_str();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_genicam_set_memory(flt_genicam *description, uint64_t address,
                                                   const void *bytes, size_t count) {
    const char *fn = "flt_genicam_set_memory";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, description);
        FLT_CHECK_NOT_NULL(fn, bytes);
        if (count == 0 || count > k_max_set_bytes)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'count' = %zu is not 1 .. 64 MiB",
                        fn, count);
        if (address > std::numeric_limits<std::uint64_t>::max() - (count - 1))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: %zu bytes at address 0x%" PRIx64 " run past 2^64", fn, count, address);
        memory_image &image = description->image;
        if (image.bytes() + image.growth(address, count) > k_max_image_bytes)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: the memory image would grow beyond 256 MiB",
                        fn);
        image.set(address, static_cast<const std::uint8_t *>(bytes), count);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_genicam_get_memory(const flt_genicam *description, uint64_t address,
                                                   void *out, size_t count) {
    const char *fn = "flt_genicam_get_memory";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, description);
        FLT_CHECK_NOT_NULL(fn, out);
        if (count == 0 || count > k_max_set_bytes)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'count' = %zu is not 1 .. 64 MiB",
                        fn, count);
        if (address > std::numeric_limits<std::uint64_t>::max() - (count - 1))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: %zu bytes at address 0x%" PRIx64 " run past 2^64", fn, count, address);
        std::uint64_t missing = 0;
        if (!description->image.get(address, static_cast<std::uint8_t *>(out), count, missing))
            return fail(FLT_ERR_NOT_FOUND, "%s: the memory image holds no byte at 0x%" PRIx64, fn,
                        missing);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_genicam_clear_memory(flt_genicam *description) {
    const char *fn = "flt_genicam_clear_memory";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, description);
        description->image.clear();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_genicam_set_registers(flt_genicam *description,
                                                      flt_genicam_read_fn read,
                                                      flt_genicam_write_fn write, void *user) {
    const char *fn = "flt_genicam_set_registers";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, description);
        if (!read && write)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'write' is set but 'read' is NULL",
                        fn);
        description->read = read;
        description->write = read ? write : nullptr;
        description->user = read ? user : nullptr;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_genicam_get_access(flt_genicam *description, const char *feature,
                                                   flt_genicam_access *out) {
    FLT_GENICAM_CALL("flt_genicam_get_access", {
        FLT_CHECK_NOT_NULL(fn, out);
        using flt::genicam::access_mode;
        switch (description->map.access(feature)) {
            case access_mode::not_implemented:
                *out = FLT_GENICAM_NOT_IMPLEMENTED;
                break;
            case access_mode::not_available:
                *out = FLT_GENICAM_NOT_AVAILABLE;
                break;
            case access_mode::write_only:
                *out = FLT_GENICAM_WRITE_ONLY;
                break;
            case access_mode::read_only:
                *out = FLT_GENICAM_READ_ONLY;
                break;
            case access_mode::read_write:
                *out = FLT_GENICAM_READ_WRITE;
                break;
        }
    });
}

FLT_API flt_status FLT_CALL flt_genicam_get_flags(flt_genicam *description, const char *feature,
                                                  int *implemented, int *available, int *locked) {
    FLT_GENICAM_CALL("flt_genicam_get_flags", {
        const auto f = description->map.flags(feature);
        if (implemented)
            *implemented = f.implemented ? 1 : 0;
        if (available)
            *available = f.available ? 1 : 0;
        if (locked)
            *locked = f.locked ? 1 : 0;
    });
}

FLT_API flt_status FLT_CALL flt_genicam_register(flt_genicam *description, const char *feature,
                                                 uint64_t *address, uint32_t *length, uint32_t *lsb,
                                                 uint32_t *msb, int *big_endian) {
    FLT_GENICAM_CALL("flt_genicam_register", {
        flt::genicam::register_info r;
        if (!description->map.register_of(feature, r))
            return fail(FLT_ERR_NOT_FOUND,
                        "%s: feature '%.200s' is a %s: its value is no single register's", fn,
                        feature, description->map.kind_of(feature).c_str());
        if (address)
            *address = r.address;
        if (length)
            *length = r.length;
        if (lsb)
            *lsb = std::uint32_t(r.lsb);
        if (msb)
            *msb = std::uint32_t(r.msb);
        if (big_endian)
            *big_endian = r.big_endian ? 1 : 0;
    });
}

FLT_API flt_status FLT_CALL flt_genicam_get_int(flt_genicam *description, const char *feature,
                                                int64_t *out) {
    FLT_GENICAM_CALL("flt_genicam_get_int", {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = description->map.get_int(feature, false);
    });
}

FLT_API flt_status FLT_CALL flt_genicam_get_float(flt_genicam *description, const char *feature,
                                                  double *out) {
    FLT_GENICAM_CALL("flt_genicam_get_float", {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = description->map.get_float(feature, false);
    });
}

FLT_API flt_status FLT_CALL flt_genicam_get_string(flt_genicam *description, const char *feature,
                                                   const char **out) {
    FLT_GENICAM_CALL("flt_genicam_get_string", {
        FLT_CHECK_NOT_NULL(fn, out);
        description->scratch = description->map.get_string(feature, false);
        *out = description->scratch.c_str();
    });
}

FLT_API flt_status FLT_CALL flt_genicam_int_bounds(flt_genicam *description, const char *feature,
                                                   int64_t *min, int64_t *max, int64_t *inc) {
    FLT_GENICAM_CALL("flt_genicam_int_bounds", {
        const std::int64_t lo = description->map.int_min(feature);
        const std::int64_t hi = description->map.int_max(feature);
        const std::int64_t step = description->map.int_inc(feature);
        if (min)
            *min = lo;
        if (max)
            *max = hi;
        if (inc)
            *inc = step;
    });
}

FLT_API flt_status FLT_CALL flt_genicam_float_bounds(flt_genicam *description, const char *feature,
                                                     double *min, double *max) {
    FLT_GENICAM_CALL("flt_genicam_float_bounds", {
        const double lo = description->map.float_min(feature);
        const double hi = description->map.float_max(feature);
        if (min)
            *min = lo;
        if (max)
            *max = hi;
    });
}

FLT_API flt_status FLT_CALL flt_genicam_enum_count(flt_genicam *description, const char *feature,
                                                   size_t *out) {
    FLT_GENICAM_CALL("flt_genicam_enum_count", {
        FLT_CHECK_NOT_NULL(fn, out);
        if (description->map.interface_of(feature) != flt::genicam::interface_kind::enumeration)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: feature '%.200s' is a %s, not an Enumeration", fn, feature,
                        description->map.kind_of(feature).c_str());
        *out = description->map.enum_entries(feature).size();
    });
}

FLT_API flt_status FLT_CALL flt_genicam_enum_entry(flt_genicam *description, const char *feature,
                                                   size_t index, const char **name, int64_t *value,
                                                   int *available) {
    FLT_GENICAM_CALL("flt_genicam_enum_entry", {
        if (description->map.interface_of(feature) != flt::genicam::interface_kind::enumeration)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: feature '%.200s' is a %s, not an Enumeration", fn, feature,
                        description->map.kind_of(feature).c_str());
        const auto entries = description->map.enum_entries(feature);
        if (index >= entries.size())
            return fail(FLT_ERR_NOT_FOUND, "%s: argument 'index' = %zu is past the %zu entries", fn,
                        index, entries.size());
        const auto &e = entries[index];
        if (name)
            *name = description->interned.insert(e.name).first->c_str();
        if (value)
            *value = e.value;
        if (available)
            *available = e.implemented && e.available ? 1 : 0;
    });
}

FLT_API flt_status FLT_CALL flt_genicam_set_int(flt_genicam *description, const char *feature,
                                                int64_t value) {
    FLT_GENICAM_CALL("flt_genicam_set_int", description->map.set_int(feature, value));
}

FLT_API flt_status FLT_CALL flt_genicam_set_float(flt_genicam *description, const char *feature,
                                                  double value) {
    FLT_GENICAM_CALL("flt_genicam_set_float", {
        if (!std::isfinite(value))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'value' = %s is not finite", fn,
                        flt::genicam::format_double(value).c_str());
        description->map.set_float(feature, value);
    });
}

FLT_API flt_status FLT_CALL flt_genicam_set_string(flt_genicam *description, const char *feature,
                                                   const char *value) {
    FLT_GENICAM_CALL("flt_genicam_set_string", {
        FLT_CHECK_NOT_NULL(fn, value);
        description->map.set_string(feature, value);
    });
}

FLT_API flt_status FLT_CALL flt_genicam_execute(flt_genicam *description, const char *feature) {
    FLT_GENICAM_CALL("flt_genicam_execute", description->map.execute(feature));
}

}  // extern "C"
