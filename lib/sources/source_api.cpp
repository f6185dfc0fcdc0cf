// SPDX-License-Identifier: Apache-2.0
// The frame-source handle (flatline/source.h), the one public face of every
// kind of source: argument checks, the started state, the borrowed frame and
// its encoder position live here; each kind implements source_impl
// (source.hpp) in its folder: sim/, images/, u3v/, gige/. Also the camera list.
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/options.hpp"
#include "flatline/source.h"
#include "sources/camera/pixel_format.hpp"
#include "sources/encoder.hpp"
#include "sources/gige/discovery.hpp"
#include "sources/gige/gige_source.hpp"
#include "sources/gige/protocol.hpp"
#include "sources/images/image_source.hpp"
#include "sources/sim/sim_source.hpp"
#include "sources/source.hpp"
#include "sources/source_handle.hpp"
#include "sources/u3v/discovery.hpp"
#include "sources/u3v/transport_handle.hpp"
#include "sources/u3v/u3v_source.hpp"

using namespace flt;

namespace {
constexpr std::uint32_t k_list_magic = 0x464c544cu;  // "FLTL"
}  // namespace

struct flt_camera_list {
    struct entry {
        std::string vendor, model, serial, address;
        std::uint32_t speed_mbps = 0;
    };
    std::uint32_t magic = k_list_magic;
    std::vector<entry> cameras;
};

namespace {

flt_status check_source(const char *fn, const flt_source *source) {
    if (source == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'source' is NULL", fn);
    if (source->magic != k_source_magic)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'source' is not a live flt_source handle", fn);
    return FLT_OK;
}

// The backend of a flt_usb_transport (NULL: libusb; `backend` stays NULL).
flt_status check_transport(const char *fn, const flt_usb_transport *usb,
                           u3v::usb_backend *&backend) {
    backend = nullptr;
    if (usb == nullptr)
        return FLT_OK;
    if (usb->magic != u3v::k_usb_transport_magic)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'usb' is not a live flt_usb_transport (its bus destroyed?)", fn);
    if (usb->revision != u3v::k_usb_transport_revision || usb->backend == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'usb' was made for another release of libflatline (transport "
                    "revision %u, this library %u): use the testing library of the same release",
                    fn, unsigned(usb->revision), unsigned(u3v::k_usb_transport_revision));
    backend = usb->backend;
    return FLT_OK;
}

// The camera behind a source, or FLT_ERR_STATE for a kind that is none.
flt_status need_camera(const char *fn, const flt_source *source, sources::camera_device *&out) {
    if (flt_status st = check_source(fn, source))
        return st;
    out = source->impl->camera();
    if (out == nullptr)
        return fail(FLT_ERR_STATE, "%s: the source is not a camera (USB3 or GigE Vision)", fn);
    return FLT_OK;
}

// Whether a frame's rows lie in its buffer: stride >= width x bytes per
// pixel, and (height - 1) x stride + width x bytes per pixel <= bytes,
// computed without overflow.
bool frame_fits(const sources::raw_frame &f) {
    if (f.pixels == nullptr || f.width == 0 || f.height == 0)
        return false;
    const std::uint64_t row = std::uint64_t(f.width) * (f.format > 8 ? 2 : 1);
    if (f.stride < row)
        return false;
    return sources::image_size_fits(f.stride, 0, f.height - 1, row, f.bytes);
}

// Checks a raw memory range: 1 byte .. 64 MiB, not past 2^64.
flt_status check_range(const char *fn, uint64_t address, size_t bytes) {
    if (bytes == 0 || bytes > (64u << 20))
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'bytes' = %zu is outside [1, 64 MiB]",
                    fn, bytes);
    if (address > UINT64_MAX - (bytes - 1))  // the range must not wrap past 2^64
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'address' = 0x%llx + %zu bytes passes the end of the address "
                    "space",
                    fn, (unsigned long long)address, bytes);
    return FLT_OK;
}

}  // namespace

extern "C" {

FLT_API flt_status FLT_CALL flt_source_create_sim(flt_sim *sim, const flt_options *options,
                                                  flt_source **out) {
    const char *fn = "flt_source_create_sim";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        FLT_CHECK_NOT_NULL(fn, sim);
        if (flt_status st = check_option_component(fn, options, {FLT_OPT_SOURCE_ENCODER_MODE}))
            return st;
        auto s = std::make_unique<flt_source>();
        s->encoder.configure(options, false);
        s->impl = sources::make_sim_source(sim);
        *out = s.release();
        return FLT_OK;
    });
}

namespace {

flt_status create_images(const char *fn, std::vector<std::string> paths, const char *csv,
                         const flt_options *options, flt_source **out) {
    if (flt_status st = check_option_component(fn, options, {FLT_OPT_SOURCE_ENCODER_MODE}))
        return st;
    auto s = std::make_unique<flt_source>();
    s->encoder.configure(options, false);
    const int bits = int(option_value(options, FLT_OPT_SOURCE_IMAGE_BITS));
    if (bits != 0 && bits != 10 && bits != 12 && bits != 16)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: option 'source_image_bits' = %d must be 0, 10, 12 or 16", fn, bits);
    s->impl = sources::make_image_source(std::move(paths), csv, bits);
    *out = s.release();
    return FLT_OK;
}

}  // namespace

FLT_API flt_status FLT_CALL flt_source_create_images(const char *const *paths, size_t count,
                                                     const char *encoder_csv,
                                                     const flt_options *options, flt_source **out) {
    const char *fn = "flt_source_create_images";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        FLT_CHECK_NOT_NULL(fn, paths);
        if (count == 0)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'count' is 0", fn);
        std::vector<std::string> list;
        for (size_t i = 0; i < count; ++i) {
            if (!paths[i])
                return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'paths[%zu]' is NULL", fn, i);
            list.emplace_back(paths[i]);
        }
        return create_images(fn, std::move(list), encoder_csv, options, out);
    });
}

FLT_API flt_status FLT_CALL flt_source_create_image_dir(const char *directory,
                                                        const char *encoder_csv,
                                                        const flt_options *options,
                                                        flt_source **out) {
    const char *fn = "flt_source_create_image_dir";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        FLT_CHECK_NOT_NULL(fn, directory);
        return create_images(fn, sources::list_image_files(directory), encoder_csv, options, out);
    });
}

FLT_API flt_status FLT_CALL flt_camera_list_create(flt_usb_transport *usb, flt_camera_list **out) {
    const char *fn = "flt_camera_list_create";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        u3v::usb_backend *backend = nullptr;
        if (flt_status st = check_transport(fn, usb, backend))
            return st;
        auto list = std::make_unique<flt_camera_list>();
        std::vector<u3v::camera_entry> found;
        if (backend) {
            found = u3v::list_cameras(*backend);
        } else {
            auto libusb = u3v::make_libusb_backend();
            found = u3v::list_cameras(*libusb);
        }
        for (const u3v::camera_entry &c : found)
            list->cameras.push_back({c.vendor, c.model, c.serial, "", c.desc.speed_mbps});
        *out = list.release();
        return FLT_OK;
    });
}

FLT_API void FLT_CALL flt_camera_list_destroy(flt_camera_list *list) {
    guard_void([&] {
        if (list && list->magic == k_list_magic) {
            list->magic = 0;
            delete list;
        }
    });
}

FLT_API flt_status FLT_CALL flt_camera_list_count(const flt_camera_list *list, size_t *out) {
    const char *fn = "flt_camera_list_count";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, list);
        FLT_CHECK_NOT_NULL(fn, out);
        if (list->magic != k_list_magic)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'list' is not a live list", fn);
        *out = list->cameras.size();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_camera_list_get(const flt_camera_list *list, size_t index,
                                                const char **vendor, const char **model,
                                                const char **serial, uint32_t *speed_mbps) {
    const char *fn = "flt_camera_list_get";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, list);
        if (list->magic != k_list_magic)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'list' is not a live list", fn);
        if (index >= list->cameras.size())
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'index' = %zu but the list has "
                        "%zu camera(s)",
                        fn, index, list->cameras.size());
        const flt_camera_list::entry &e = list->cameras[index];
        if (vendor)
            *vendor = e.vendor.c_str();
        if (model)
            *model = e.model.c_str();
        if (serial)
            *serial = e.serial.c_str();
        if (speed_mbps)
            *speed_mbps = e.speed_mbps;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_camera_list_create_gige(const char *address, uint32_t timeout_ms,
                                                        flt_camera_list **out) {
    const char *fn = "flt_camera_list_create_gige";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        if (timeout_ms < 1 || timeout_ms > 60000)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'timeout_ms' = %u is outside [1, 60000]", fn, timeout_ms);
        gige::endpoint e;
        if (address && !gige::parse_endpoint(address, gige::k_gvcp_port, e))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'address' = '%.80s' is no IPv4 address (a.b.c.d or "
                        "a.b.c.d:port)",
                        fn, address);
        auto list = std::make_unique<flt_camera_list>();
        for (const gige::camera_info &c : gige::discover(address, timeout_ms))
            list->cameras.push_back({c.strings[FLT_CAMERA_VENDOR], c.strings[FLT_CAMERA_MODEL],
                                     c.strings[FLT_CAMERA_SERIAL],
                                     gige::to_string(c.address, gige::k_gvcp_port), 0});
        *out = list.release();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_camera_list_address(const flt_camera_list *list, size_t index,
                                                    const char **out) {
    const char *fn = "flt_camera_list_address";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, list);
        FLT_CHECK_NOT_NULL(fn, out);
        if (list->magic != k_list_magic)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'list' is not a live list", fn);
        if (index >= list->cameras.size())
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'index' = %zu but the list has %zu camera(s)", fn, index,
                        list->cameras.size());
        *out = list->cameras[index].address.c_str();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_source_open_gige(const char *camera, const flt_options *options,
                                                 flt_source **out) {
    const char *fn = "flt_source_open_gige";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        if (camera && camera[0] == '\0')
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'camera' is empty (NULL takes the first camera)", fn);
        if (flt_status st = check_option_component(fn, options, {FLT_OPT_SOURCE_ENCODER_MODE}))
            return st;
        const unsigned packet = unsigned(option_value(options, FLT_OPT_GIGE_PACKET_SIZE));
        if (packet != 0 && packet < 576)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: option 'gige_packet_size' = %u must be 0 (negotiate) or at least "
                        "576",
                        fn, packet);
        auto s = std::make_unique<flt_source>();
        s->encoder.configure(options, true);
        if (s->encoder.mode() == sources::encoder_chunk)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: option 'source_encoder_mode' = 3 (chunk counter) is not available "
                        "for GigE Vision cameras yet; use 1 (fixed step) or 2 (host)",
                        fn);
        gige::camera_config config;
        config.control.timeout_ms = unsigned(option_value(options, FLT_OPT_GIGE_CONTROL_TIMEOUT));
        config.control.command_attempts =
            unsigned(option_value(options, FLT_OPT_GIGE_COMMAND_ATTEMPTS));
        config.control.heartbeat_ms =
            unsigned(option_value(options, FLT_OPT_GIGE_HEARTBEAT_TIMEOUT));
        config.stream.packet_size = packet;
        config.stream.resend_attempts =
            unsigned(option_value(options, FLT_OPT_GIGE_RESEND_ATTEMPTS));
        config.stream.resend_timeout_ms =
            unsigned(option_value(options, FLT_OPT_GIGE_RESEND_TIMEOUT));
        config.stream.socket_buffer = int(option_value(options, FLT_OPT_GIGE_SOCKET_BUFFER));
        config.discovery_ms = unsigned(option_value(options, FLT_OPT_GIGE_DISCOVERY_TIMEOUT));
        config.stream.assembly_frames =
            unsigned(option_value(options, FLT_OPT_GIGE_ASSEMBLY_FRAMES));
        const gige::endpoint address = gige::find_camera(camera, config.discovery_ms);
        s->impl = std::make_unique<gige::gige_camera>(address, config);
        *out = s.release();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_source_open_u3v(flt_usb_transport *usb, const char *serial,
                                                const flt_options *options, flt_source **out) {
    const char *fn = "flt_source_open_u3v";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        u3v::usb_backend *backend = nullptr;
        if (flt_status st = check_transport(fn, usb, backend))
            return st;
        if (flt_status st = check_option_component(fn, options, {FLT_OPT_SOURCE_ENCODER_MODE}))
            return st;
        auto s = std::make_unique<flt_source>();
        s->encoder.configure(options, true);
        u3v::camera_config config;
        config.control.timeout_floor_ms =
            unsigned(option_value(options, FLT_OPT_U3V_CONTROL_TIMEOUT));
        config.control.pending_ack_limit =
            unsigned(option_value(options, FLT_OPT_U3V_PENDING_ACK_LIMIT));
        config.control.command_attempts =
            unsigned(option_value(options, FLT_OPT_U3V_COMMAND_ATTEMPTS));
        config.stream.transfers = std::size_t(option_value(options, FLT_OPT_U3V_TRANSFERS));
        config.stream.max_transfer_bytes =
            std::size_t(option_value(options, FLT_OPT_U3V_TRANSFER_SIZE));
        config.stream.want_chunk = s->encoder.mode() == sources::encoder_chunk;
        config.stream.chunk_id =
            std::uint32_t(option_value(options, FLT_OPT_SOURCE_ENCODER_CHUNK_ID));
        if (backend)
            s->impl = std::make_unique<u3v::u3v_camera>(*backend, serial, config);
        else
            s->impl = std::make_unique<u3v::u3v_camera>(u3v::make_libusb_backend(), serial, config);
        *out = s.release();
        return FLT_OK;
    });
}

FLT_API void FLT_CALL flt_source_destroy(flt_source *source) {
    guard_void([&] {
        if (source && source->magic == k_source_magic) {
            source->magic = 0;
            source->frame.magic = 0;
            source->impl.reset();  // stops a streaming camera, releases it
            delete source;
        }
    });
}

FLT_API flt_status FLT_CALL flt_source_kind_of(const flt_source *source, flt_source_kind *out) {
    const char *fn = "flt_source_kind_of";
    return guard(fn, [&] {
        if (flt_status st = check_source(fn, source))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = source->impl->kind();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_source_start(flt_source *source) {
    const char *fn = "flt_source_start";
    return guard(fn, [&] {
        if (flt_status st = check_source(fn, source))
            return st;
        if (source->started)
            return fail(FLT_ERR_STATE, "%s: the source is already started", fn);
        source->impl->start();
        source->encoder.restart();
        source->started = true;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_source_stop(flt_source *source) {
    const char *fn = "flt_source_stop";
    return guard(fn, [&] {
        if (flt_status st = check_source(fn, source))
            return st;
        // Stopped on the host side whatever the device answers.
        source->started = false;
        source->frame.pixels = nullptr;
        source->impl->stop();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_source_next(flt_source *source, uint32_t timeout_ms,
                                            const flt_frame **out) {
    const char *fn = "flt_source_next";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        if (flt_status st = check_source(fn, source))
            return st;
        if (!source->started)
            return fail(FLT_ERR_STATE, "%s: the source is not started; call flt_source_start()",
                        fn);
        sources::raw_frame raw;
        if (!source->impl->next(timeout_ms, raw))
            return FLT_OK;  // the end of an image sequence
        // Every kind checks what it delivers; this is the promise of
        // flt_frame_info() kept in one place: `height` rows of
        // `stride_bytes` (the last one `width` pixels) lie in the buffer.
        // A recording's row whose camera frame was not kept has no pixels
        // and a size of 0 (flt_frame_info says so); pixels a frame has fit.
        const bool row_only =
            raw.recorded != nullptr && raw.pixels == nullptr && raw.width == 0 && raw.height == 0;
        if (!row_only && !frame_fits(raw))
            return fail(FLT_ERR_INTERNAL,
                        "%s: a %u x %u px frame of stride %zu does not fit its %zu-byte buffer "
                        "(not delivered)",
                        fn, raw.width, raw.height, raw.stride, raw.bytes);
        flt_frame &f = source->frame;
        f.pixels = raw.pixels;
        f.width = raw.width;
        f.height = raw.height;
        f.stride = raw.stride;
        f.format = raw.format;
        f.block_id = raw.block_id;
        f.timestamp_ns = raw.timestamp_ns;
        f.encoder_mm = source->encoder.position_of(raw);
        f.recorded = raw.recorded;
        *out = &f;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_frame_info(const flt_frame *frame, const void **pixels,
                                           uint32_t *width, uint32_t *height, size_t *stride_bytes,
                                           flt_pixel_format *format, uint64_t *block_id,
                                           uint64_t *timestamp_ns, double *encoder_mm) {
    const char *fn = "flt_frame_info";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, frame);
        // A recording's frame may have no pixels (only its profile row).
        if (frame->magic != k_frame_magic || (!frame->pixels && !frame->recorded))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'frame' is not a live frame "
                        "(its source was destroyed or stopped?)",
                        fn);
        if (pixels)
            *pixels = frame->pixels;
        if (width)
            *width = frame->width;
        if (height)
            *height = frame->height;
        if (stride_bytes)
            *stride_bytes = frame->stride;
        if (format)
            *format = frame->format;
        if (block_id)
            *block_id = frame->block_id;
        if (timestamp_ns)
            *timestamp_ns = frame->timestamp_ns;
        if (encoder_mm)
            *encoder_mm = frame->encoder_mm;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_source_set_encoder(flt_source *source, double encoder_mm) {
    const char *fn = "flt_source_set_encoder";
    return guard(fn, [&] {
        if (flt_status st = check_source(fn, source))
            return st;
        if (source->encoder.mode() != sources::encoder_host)
            return fail(FLT_ERR_STATE, "%s: option 'source_encoder_mode' is %d, not 2 (host)", fn,
                        source->encoder.mode());
        if (!std::isfinite(encoder_mm))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'encoder_mm' = %g is not finite",
                        fn, encoder_mm);
        source->encoder.set_host(encoder_mm);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_source_count(const flt_source *source, flt_source_counter counter,
                                             uint64_t *out) {
    const char *fn = "flt_source_count";
    return guard(fn, [&] {
        if (flt_status st = check_source(fn, source))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (enum_arg(counter) < 0 || enum_arg(counter) > int(FLT_COUNT_PACKETS_DUPLICATE))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'counter' = %d is no counter", fn,
                        enum_arg(counter));
        *out = source->impl->count(counter);
        return FLT_OK;
    });
}

FLT_API const char *FLT_CALL flt_source_stream_error(const flt_source *source) {
    if (!source || source->magic != k_source_magic)
        return "";
    return source->impl->stream_error().c_str();
}

FLT_API flt_status FLT_CALL flt_source_camera_string(const flt_source *source,
                                                     flt_camera_string which, const char **out) {
    const char *fn = "flt_source_camera_string";
    return guard(fn, [&] {
        sources::camera_device *camera = nullptr;
        if (flt_status st = need_camera(fn, source, camera))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (enum_arg(which) < 0 || enum_arg(which) > int(FLT_CAMERA_USER_NAME))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'which' = %d is no camera string",
                        fn, enum_arg(which));
        *out = camera->string_of(which).c_str();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_source_camera_value(const flt_source *source,
                                                    flt_camera_value which, uint64_t *out) {
    const char *fn = "flt_source_camera_value";
    return guard(fn, [&] {
        sources::camera_device *camera = nullptr;
        if (flt_status st = need_camera(fn, source, camera))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (enum_arg(which) < 0)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'which' = %d is no camera value",
                        fn, enum_arg(which));
        *out = camera->value_of(which);
        return FLT_OK;
    });
}

// A feature call: the source must be a camera, the feature name given.
#define FLT_FEATURE_CALL(name, body)                   \
  const char *fn = name;                               \
  return guard(fn, [&] {                               \
  sources::camera_device *camera = nullptr;            \
  if (flt_status st = need_camera(fn, source, camera)) \
    return st;                                         \
  FLT_CHECK_NOT_NULL(fn, feature);                     \
  body;                                                \
  return FLT_OK;                                       \
  })

FLT_API flt_status FLT_CALL flt_source_get_int(flt_source *source, const char *feature,
                                               int64_t *out) {
    FLT_FEATURE_CALL("flt_source_get_int", {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = camera->get_int(feature);
    });
}
FLT_API flt_status FLT_CALL flt_source_set_int(flt_source *source, const char *feature,
                                               int64_t value) {
    FLT_FEATURE_CALL("flt_source_set_int", camera->set_int(feature, value));
}
FLT_API flt_status FLT_CALL flt_source_get_float(flt_source *source, const char *feature,
                                                 double *out) {
    FLT_FEATURE_CALL("flt_source_get_float", {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = camera->get_float(feature);
    });
}
FLT_API flt_status FLT_CALL flt_source_set_float(flt_source *source, const char *feature,
                                                 double value) {
    FLT_FEATURE_CALL("flt_source_set_float", camera->set_float(feature, value));
}
FLT_API flt_status FLT_CALL flt_source_set_enum(flt_source *source, const char *feature,
                                                const char *entry) {
    FLT_FEATURE_CALL("flt_source_set_enum", {
        FLT_CHECK_NOT_NULL(fn, entry);
        camera->set_enum(feature, entry);
    });
}
FLT_API flt_status FLT_CALL flt_source_execute(flt_source *source, const char *feature) {
    FLT_FEATURE_CALL("flt_source_execute", camera->execute(feature));
}
FLT_API flt_status FLT_CALL flt_source_map_feature(flt_source *source, const char *feature,
                                                   uint64_t address, uint32_t length,
                                                   int is_float) {
    FLT_FEATURE_CALL("flt_source_map_feature", {
        if (length != 1 && length != 2 && length != 4 && length != 8)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'length' = %u must be 1, 2, 4 or 8 bytes", fn, length);
        if (is_float && length != 4 && length != 8)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'length' = %u: a float register has 4 or 8 bytes", fn,
                        length);
        camera->map_feature(feature, address, length, is_float != 0);
    });
}

FLT_API flt_status FLT_CALL flt_source_read_memory(flt_source *source, uint64_t address, void *out,
                                                   size_t bytes) {
    const char *fn = "flt_source_read_memory";
    return guard(fn, [&] {
        sources::camera_device *camera = nullptr;
        if (flt_status st = need_camera(fn, source, camera))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (flt_status st = check_range(fn, address, bytes))
            return st;
        camera->read_memory(address, static_cast<std::uint8_t *>(out), bytes);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_source_write_memory(flt_source *source, uint64_t address,
                                                    const void *bytes_in, size_t bytes) {
    const char *fn = "flt_source_write_memory";
    return guard(fn, [&] {
        sources::camera_device *camera = nullptr;
        if (flt_status st = need_camera(fn, source, camera))
            return st;
        FLT_CHECK_NOT_NULL(fn, bytes_in);
        if (flt_status st = check_range(fn, address, bytes))
            return st;
        camera->write_memory(address, static_cast<const std::uint8_t *>(bytes_in), bytes);
        return FLT_OK;
    });
}

}  // extern "C"
