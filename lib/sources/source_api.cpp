// SPDX-License-Identifier: Apache-2.0
// The frame-source handle (flatline/source.h): simulator, image sequences
// and USB3 Vision cameras behind one interface, with encoder positions; and
// the C API of the simulated USB3 Vision bus.
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <dirent.h>

#include "core/error.hpp"
#include "core/options.hpp"
#include "flatline/source.h"
#include "sources/u3v/camera.hpp"
#include "sources/u3v/sim_camera.hpp"

using namespace flt;

namespace {
constexpr std::uint32_t k_source_magic = 0x464c5443u;  // "FLTC"
constexpr std::uint32_t k_frame_magic = 0x464c5446u;   // "FLTF"
constexpr std::uint32_t k_bus_magic = 0x464c5455u;     // "FLTU"
constexpr std::uint32_t k_list_magic = 0x464c544cu;    // "FLTL"
constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

enum encoder_mode { encoder_auto = 0, encoder_fixed = 1, encoder_host = 2, encoder_chunk = 3 };

std::uint64_t host_ns() {
    return std::uint64_t(std::chrono::duration_cast<std::chrono::nanoseconds>(
                             std::chrono::steady_clock::now().time_since_epoch())
                             .count());
}

std::string base_name(const std::string &path) {
    const std::size_t slash = path.find_last_of("/\\");
    return slash == std::string::npos ? path : path.substr(slash + 1);
}

bool has_image_suffix(const std::string &name) {
    std::string lower = name;
    std::transform(lower.begin(), lower.end(), lower.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    for (const char *s : {".png", ".tif", ".tiff"}) {
        const std::size_t n = std::strlen(s);
        if (lower.size() > n && lower.compare(lower.size() - n, n, s) == 0)
            return true;
    }
    return false;
}
}  // namespace

struct flt_frame {
    std::uint32_t magic = k_frame_magic;
    const void *pixels = nullptr;
    std::uint32_t width = 0, height = 0;
    std::size_t stride = 0;
    flt_pixel_format format = FLT_PIXEL_MONO8;
    std::uint64_t block_id = 0, timestamp_ns = 0;
    double encoder_mm = k_nan;
};

struct flt_u3v_sim {
    std::uint32_t magic = k_bus_magic;
    u3v::sim_bus bus;
};

struct flt_camera_list {
    std::uint32_t magic = k_list_magic;
    std::vector<u3v::camera_entry> cameras;
};

struct flt_source {
    std::uint32_t magic = k_source_magic;
    flt_source_kind kind = FLT_SOURCE_SIMULATOR;
    bool started = false;
    flt_frame frame;

    // encoder
    int mode = encoder_auto;
    double step = 3.0, start = 0.0, mm_per_count = 0.01;
    double host_encoder = k_nan;
    bool have_first_block = false;
    std::uint64_t first_block = 0;
    bool have_counter = false;
    std::uint64_t last_counter = 0;
    std::int64_t counter_total = 0;

    // simulator
    flt_sim *sim = nullptr;
    std::vector<std::uint8_t> pixels;
    std::uint64_t next_index = 0;

    // image sequence
    std::vector<std::string> paths;
    std::vector<double> csv_encoder;
    int image_bits = 0;
    cv::Mat image;

    // USB3 Vision
    std::unique_ptr<u3v::usb_backend> owned_bus;
    std::unique_ptr<u3v::camera> camera;

    double encoder_of(std::uint64_t block, double own_mm) {
        if (!have_first_block) {
            have_first_block = true;
            first_block = block;
        }
        switch (mode) {
            case encoder_fixed:
                return start + step * double(block - first_block);
            case encoder_host:
                return host_encoder;
            default:
                return own_mm;
        }
    }
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

flt_status check_bus(const char *fn, const flt_u3v_sim *bus, std::size_t camera) {
    if (bus == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'bus' is NULL", fn);
    if (bus->magic != k_bus_magic)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'bus' is not a live flt_u3v_sim", fn);
    if (camera >= bus->bus.cameras())
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'camera' = %zu but the bus has %zu camera(s)", fn, camera,
                    bus->bus.cameras());
    return FLT_OK;
}

flt_status need_camera(const char *fn, const flt_source *source) {
    if (flt_status st = check_source(fn, source))
        return st;
    if (source->kind != FLT_SOURCE_U3V)
        return fail(FLT_ERR_STATE, "%s: the source is not a USB3 Vision camera", fn);
    return FLT_OK;
}

flt_status read_encoder_options(const char *fn, const flt_options *options, flt_source &s) {
    s.mode = int(option_value(options, FLT_OPT_SOURCE_ENCODER_MODE));
    s.step = option_value(options, FLT_OPT_SOURCE_ENCODER_STEP);
    s.start = option_value(options, FLT_OPT_SOURCE_ENCODER_START);
    s.mm_per_count = option_value(options, FLT_OPT_SOURCE_ENCODER_MM_PER_COUNT);
    if (s.mode == encoder_chunk && s.kind != FLT_SOURCE_U3V)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: option 'source_encoder_mode' = 3 (chunk counter) needs a USB3 Vision "
                    "camera",
                    fn);
    return FLT_OK;
}

flt_pixel_format format_of_bits(int bits) {
    return flt_pixel_format(bits);
}

// Reads one image file into source.image and checks it.
flt_status load_image(const char *fn, flt_source &s, std::size_t index) {
    const std::string &path = s.paths[index];
    // Checked first so that OpenCV does not print its own warning.
    if (!std::ifstream(path).good())
        return fail(FLT_ERR_IO,
                    "%s: image %zu '%.200s' cannot be read (missing or not "
                    "readable)",
                    fn, index, path.c_str());
    s.image = cv::imread(path, cv::IMREAD_UNCHANGED);
    if (s.image.empty())
        return fail(FLT_ERR_IO,
                    "%s: image %zu '%.200s' cannot be read (missing, or not an "
                    "image OpenCV can decode)",
                    fn, index, path.c_str());
    if (s.image.channels() != 1)
        return fail(FLT_ERR_FORMAT,
                    "%s: image %zu '%.200s' has %d channels; a laser frame is "
                    "monochrome (1 channel)",
                    fn, index, path.c_str(), s.image.channels());
    if (s.image.depth() != CV_8U && s.image.depth() != CV_16U)
        return fail(FLT_ERR_FORMAT, "%s: image %zu '%.200s' is neither 8 nor 16 bits per pixel", fn,
                    index, path.c_str());
    return FLT_OK;
}

flt_status read_csv(const char *fn, const std::string &csv, flt_source &s) {
    std::ifstream in(csv);
    if (!in)
        return fail(FLT_ERR_IO, "%s: encoder CSV '%.200s' cannot be opened", fn, csv.c_str());
    std::string line;
    std::size_t line_no = 0;
    while (std::getline(in, line)) {
        ++line_no;
        if (!line.empty() && line.back() == '\r')
            line.pop_back();
        if (line.find_first_not_of(" \t") == std::string::npos || line[0] == '#')
            continue;
        const std::size_t comma = line.rfind(',');
        const std::string value = comma == std::string::npos ? line : line.substr(comma + 1);
        char *end = nullptr;
        const double mm = std::strtod(value.c_str(), &end);
        while (end && (*end == ' ' || *end == '\t'))
            ++end;
        const bool number = end && end != value.c_str() && *end == '\0';
        if (!number) {
            if (s.csv_encoder.empty() && line_no == 1)
                continue;  // a header
            return fail(FLT_ERR_FORMAT,
                        "%s: encoder CSV '%.200s' line %zu: '%.60s' is not a "
                        "number",
                        fn, csv.c_str(), line_no, value.c_str());
        }
        if (!std::isfinite(mm))
            return fail(FLT_ERR_FORMAT, "%s: encoder CSV '%.200s' line %zu: %g mm is not finite",
                        fn, csv.c_str(), line_no, mm);
        const std::size_t row = s.csv_encoder.size();
        if (comma != std::string::npos && row < s.paths.size()) {
            std::string name = line.substr(0, line.find(','));
            name.erase(0, name.find_first_not_of(" \t\""));
            name.erase(name.find_last_not_of(" \t\"") + 1);
            if (name != base_name(s.paths[row]))
                return fail(FLT_ERR_FORMAT,
                            "%s: encoder CSV '%.200s' line %zu names '%.80s', "
                            "but image %zu is '%.80s'",
                            fn, csv.c_str(), line_no, name.c_str(), row,
                            base_name(s.paths[row]).c_str());
        }
        s.csv_encoder.push_back(mm);
    }
    if (s.csv_encoder.size() != s.paths.size())
        return fail(FLT_ERR_FORMAT, "%s: encoder CSV '%.200s' has %zu positions for %zu images", fn,
                    csv.c_str(), s.csv_encoder.size(), s.paths.size());
    return FLT_OK;
}

flt_status create_images(const char *fn, std::vector<std::string> paths, const char *csv,
                         const flt_options *options, flt_source **out) {
    auto s = std::make_unique<flt_source>();
    s->kind = FLT_SOURCE_IMAGES;
    s->paths = std::move(paths);
    if (flt_status st = read_encoder_options(fn, options, *s))
        return st;
    const int bits = int(option_value(options, FLT_OPT_SOURCE_IMAGE_BITS));
    if (bits != 0 && bits != 10 && bits != 12 && bits != 16)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: option 'source_image_bits' = %d must be 0, "
                    "10, 12 or 16",
                    fn, bits);
    if (csv) {
        if (flt_status st = read_csv(fn, csv, *s))
            return st;
    }
    if (flt_status st = load_image(fn, *s, 0))
        return st;
    const bool wide = s->image.depth() == CV_16U;
    if (!wide && bits != 0)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: option 'source_image_bits' = %d, but '%.200s' "
                    "has 8 bits per pixel",
                    fn, bits, s->paths[0].c_str());
    s->image_bits = wide ? (bits ? bits : 16) : 8;
    s->frame.width = std::uint32_t(s->image.cols);
    s->frame.height = std::uint32_t(s->image.rows);
    s->frame.format = format_of_bits(s->image_bits);
    s->next_index = 0;
    *out = s.release();
    return FLT_OK;
}

flt_status next_images(const char *fn, flt_source &s, const flt_frame **out) {
    if (s.next_index >= s.paths.size()) {
        *out = nullptr;  // end of the sequence
        return FLT_OK;
    }
    const std::size_t index = std::size_t(s.next_index++);
    if (index > 0) {
        if (flt_status st = load_image(fn, s, index))
            return st;
    }
    const bool wide = s.image.depth() == CV_16U;
    if (std::uint32_t(s.image.cols) != s.frame.width ||
        std::uint32_t(s.image.rows) != s.frame.height || wide != (s.image_bits > 8))
        return fail(FLT_ERR_FORMAT,
                    "%s: image %zu '%.200s' is %d x %d, %d bits; the sequence "
                    "started with %u x %u, %d bits",
                    fn, index, s.paths[index].c_str(), s.image.cols, s.image.rows, wide ? 16 : 8,
                    s.frame.width, s.frame.height, s.image_bits > 8 ? 16 : 8);
    const double own =
        s.csv_encoder.empty() ? s.start + s.step * double(index) : s.csv_encoder[index];
    s.frame.pixels = s.image.data;
    s.frame.stride = s.image.step[0];
    s.frame.block_id = index;
    s.frame.timestamp_ns = host_ns();
    s.frame.encoder_mm = s.encoder_of(index, own);
    *out = &s.frame;
    return FLT_OK;
}

flt_status next_sim(const char *fn, flt_source &s, const flt_frame **out) {
    double encoder_mm = k_nan;
    if (flt_sim_next_frame(s.sim, s.pixels.data(), s.pixels.size(), s.frame.stride, &encoder_mm, 0,
                           nullptr, nullptr) != FLT_OK)
        return fail(flt_last_error_status(), "%s: the simulator failed: %s", fn,
                    flt_last_error_message());
    const std::uint64_t index = s.next_index++;
    s.frame.pixels = s.pixels.data();
    s.frame.block_id = index;
    s.frame.timestamp_ns = host_ns();
    s.frame.encoder_mm = s.encoder_of(index, encoder_mm);
    *out = &s.frame;
    return FLT_OK;
}

flt_status next_camera(flt_source &s, std::uint32_t timeout_ms, const flt_frame **out) {
    u3v::frame_view view;
    const flt_status st = s.camera->next(timeout_ms, view);
    if (st != FLT_OK)
        return st;
    s.frame.pixels = view.pixels;
    s.frame.width = view.width;
    s.frame.height = view.height;
    s.frame.stride = view.stride;
    s.frame.format = format_of_bits(view.bits);
    s.frame.block_id = view.block_id;
    s.frame.timestamp_ns = view.timestamp_ns;
    double own = k_nan;
    if (s.mode == encoder_chunk && view.has_chunk_counter) {
        // Unroll wraps of a 32-bit counter (a 64-bit one never wraps).
        const std::uint64_t c = view.chunk_counter;
        if (!s.have_counter) {
            s.counter_total =
                view.chunk_counter_bytes == 4 ? std::int64_t(std::int32_t(c)) : std::int64_t(c);
        } else if (view.chunk_counter_bytes == 4) {
            s.counter_total += std::int64_t(std::int32_t(std::uint32_t(c - s.last_counter)));
        } else {
            s.counter_total = std::int64_t(c);
        }
        s.have_counter = true;
        s.last_counter = c;
        own = s.start + s.mm_per_count * double(s.counter_total);
    } else if (s.mode == encoder_auto) {
        own = s.start +
              s.step * double(view.block_id - (s.have_first_block ? s.first_block : view.block_id));
    }
    s.frame.encoder_mm = s.mode == encoder_chunk ? own : s.encoder_of(view.block_id, own);
    *out = &s.frame;
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
        auto s = std::make_unique<flt_source>();
        s->kind = FLT_SOURCE_SIMULATOR;
        if (flt_status st = read_encoder_options(fn, options, *s))
            return st;
        std::uint32_t w = 0, h = 0;
        flt_pixel_format format = FLT_PIXEL_MONO8;
        if (flt_sim_frame_size(sim, &w, &h) != FLT_OK ||
            flt_sim_pixel_format(sim, &format) != FLT_OK)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'sim': %s", fn,
                        flt_last_error_message());
        s->sim = sim;
        s->frame.width = w;
        s->frame.height = h;
        s->frame.format = format;
        s->frame.stride = std::size_t(w) * (format > 8 ? 2 : 1);
        s->pixels.assign(s->frame.stride * h, 0);
        *out = s.release();
        return FLT_OK;
    });
}

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
        DIR *dir = opendir(directory);
        if (!dir)
            return fail(FLT_ERR_IO, "%s: directory '%.200s' cannot be opened", fn, directory);
        std::vector<std::string> names;
        while (dirent *e = readdir(dir))
            if (has_image_suffix(e->d_name))
                names.emplace_back(e->d_name);
        closedir(dir);
        if (names.empty())
            return fail(FLT_ERR_NOT_FOUND,
                        "%s: directory '%.200s' holds no .png, .tif or .tiff "
                        "file",
                        fn, directory);
        std::sort(names.begin(), names.end());
        std::string folder(directory);
        if (folder.back() != '/')
            folder += '/';
        for (std::string &n : names)
            n = folder + n;
        return create_images(fn, std::move(names), encoder_csv, options, out);
    });
}

FLT_API flt_status FLT_CALL flt_camera_list_create(flt_u3v_sim *bus, flt_camera_list **out) {
    const char *fn = "flt_camera_list_create";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        if (bus && bus->magic != k_bus_magic)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'bus' is not a live flt_u3v_sim",
                        fn);
        auto list = std::make_unique<flt_camera_list>();
        if (bus) {
            list->cameras = u3v::list_cameras(bus->bus);
        } else {
            auto usb = u3v::make_libusb_backend();
            list->cameras = u3v::list_cameras(*usb);
        }
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
        const u3v::camera_entry &e = list->cameras[index];
        if (vendor)
            *vendor = e.vendor.c_str();
        if (model)
            *model = e.model.c_str();
        if (serial)
            *serial = e.serial.c_str();
        if (speed_mbps)
            *speed_mbps = e.desc.speed_mbps;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_source_open_u3v(flt_u3v_sim *bus, const char *serial,
                                                const flt_options *options, flt_source **out) {
    const char *fn = "flt_source_open_u3v";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        if (bus && bus->magic != k_bus_magic)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'bus' is not a live flt_u3v_sim",
                        fn);
        auto s = std::make_unique<flt_source>();
        s->kind = FLT_SOURCE_U3V;
        if (flt_status st = read_encoder_options(fn, options, *s))
            return st;
        u3v::camera_config config;
        config.control_timeout_floor_ms =
            unsigned(option_value(options, FLT_OPT_U3V_CONTROL_TIMEOUT));
        config.pending_ack_limit = unsigned(option_value(options, FLT_OPT_U3V_PENDING_ACK_LIMIT));
        config.command_attempts = unsigned(option_value(options, FLT_OPT_U3V_COMMAND_ATTEMPTS));
        config.transfers = std::size_t(option_value(options, FLT_OPT_U3V_TRANSFERS));
        config.max_transfer_bytes = std::size_t(option_value(options, FLT_OPT_U3V_TRANSFER_SIZE));
        config.want_chunk = s->mode == encoder_chunk;
        config.chunk_id = std::uint32_t(option_value(options, FLT_OPT_SOURCE_ENCODER_CHUNK_ID));
        u3v::usb_backend *backend = nullptr;
        if (bus) {
            backend = &bus->bus;
        } else {
            s->owned_bus = u3v::make_libusb_backend();
            backend = s->owned_bus.get();
        }
        s->camera = std::make_unique<u3v::camera>(*backend, serial, config);
        *out = s.release();
        return FLT_OK;
    });
}

FLT_API void FLT_CALL flt_source_destroy(flt_source *source) {
    guard_void([&] {
        if (source && source->magic == k_source_magic) {
            source->magic = 0;
            source->frame.magic = 0;
            source->camera.reset();  // stops the stream, releases the camera
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
        *out = source->kind;
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
        if (source->kind == FLT_SOURCE_U3V)
            source->camera->start();
        if (source->kind == FLT_SOURCE_IMAGES && source->next_index > 0) {
            source->next_index = 0;
            if (flt_status st = load_image(fn, *source, 0))
                return st;
        }
        source->have_first_block = false;
        source->have_counter = false;
        source->started = true;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_source_stop(flt_source *source) {
    const char *fn = "flt_source_stop";
    return guard(fn, [&] {
        if (flt_status st = check_source(fn, source))
            return st;
        if (source->kind == FLT_SOURCE_U3V)
            source->camera->stop();
        source->started = false;
        source->frame.pixels = nullptr;
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
        switch (source->kind) {
            case FLT_SOURCE_SIMULATOR:
                return next_sim(fn, *source, out);
            case FLT_SOURCE_IMAGES:
                return next_images(fn, *source, out);
            case FLT_SOURCE_U3V:
                return next_camera(*source, timeout_ms, out);
            default:
                break;
        }
        return fail(FLT_ERR_INTERNAL, "%s: unknown source kind", fn);
    });
}

FLT_API flt_status FLT_CALL flt_frame_info(const flt_frame *frame, const void **pixels,
                                           uint32_t *width, uint32_t *height, size_t *stride_bytes,
                                           flt_pixel_format *format, uint64_t *block_id,
                                           uint64_t *timestamp_ns, double *encoder_mm) {
    const char *fn = "flt_frame_info";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, frame);
        if (frame->magic != k_frame_magic || !frame->pixels)
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
        if (source->mode != encoder_host)
            return fail(FLT_ERR_STATE, "%s: option 'source_encoder_mode' is %d, not 2 (host)", fn,
                        source->mode);
        if (!std::isfinite(encoder_mm))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'encoder_mm' = %g is not finite",
                        fn, encoder_mm);
        source->host_encoder = encoder_mm;
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
        if (enum_arg(counter) < 0 || enum_arg(counter) > int(FLT_COUNT_STREAM_RECOVERIES))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'counter' = %d is no counter", fn,
                        enum_arg(counter));
        if (source->camera) {
            *out = source->camera->counter(counter);
        } else {
            // Simulator and images lose nothing: only delivered frames count.
            *out = counter == FLT_COUNT_FRAMES ? source->next_index : 0;
        }
        return FLT_OK;
    });
}

FLT_API const char *FLT_CALL flt_source_stream_error(const flt_source *source) {
    if (!source || source->magic != k_source_magic || !source->camera)
        return "";
    return source->camera->stream_error().c_str();
}

FLT_API flt_status FLT_CALL flt_source_camera_string(const flt_source *source,
                                                     flt_camera_string which, const char **out) {
    const char *fn = "flt_source_camera_string";
    return guard(fn, [&] {
        if (flt_status st = need_camera(fn, source))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (enum_arg(which) < 0 || enum_arg(which) > int(FLT_CAMERA_USER_NAME))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'which' = %d is no camera string",
                        fn, enum_arg(which));
        *out = source->camera->string_of(which).c_str();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_source_camera_value(const flt_source *source,
                                                    flt_camera_value which, uint64_t *out) {
    const char *fn = "flt_source_camera_value";
    return guard(fn, [&] {
        if (flt_status st = need_camera(fn, source))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (enum_arg(which) < 0)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'which' = %d is no camera value",
                        fn, enum_arg(which));
        *out = source->camera->value_of(which);
        return FLT_OK;
    });
}

#define FLT_FEATURE_CALL(name, body)           \
  const char *fn = name;                       \
  return guard(fn, [&] {                       \
  if (flt_status st = need_camera(fn, source)) \
    return st;                                 \
  FLT_CHECK_NOT_NULL(fn, feature);             \
  body;                                        \
  return FLT_OK;                               \
  })

FLT_API flt_status FLT_CALL flt_source_get_int(flt_source *source, const char *feature,
                                               int64_t *out) {
    FLT_FEATURE_CALL("flt_source_get_int", {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = source->camera->get_int(feature);
    });
}
FLT_API flt_status FLT_CALL flt_source_set_int(flt_source *source, const char *feature,
                                               int64_t value) {
    FLT_FEATURE_CALL("flt_source_set_int", source->camera->set_int(feature, value));
}
FLT_API flt_status FLT_CALL flt_source_get_float(flt_source *source, const char *feature,
                                                 double *out) {
    FLT_FEATURE_CALL("flt_source_get_float", {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = source->camera->get_float(feature);
    });
}
FLT_API flt_status FLT_CALL flt_source_set_float(flt_source *source, const char *feature,
                                                 double value) {
    FLT_FEATURE_CALL("flt_source_set_float", source->camera->set_float(feature, value));
}
FLT_API flt_status FLT_CALL flt_source_set_enum(flt_source *source, const char *feature,
                                                const char *entry) {
    FLT_FEATURE_CALL("flt_source_set_enum", {
        FLT_CHECK_NOT_NULL(fn, entry);
        source->camera->set_enum(feature, entry);
    });
}
FLT_API flt_status FLT_CALL flt_source_execute(flt_source *source, const char *feature) {
    FLT_FEATURE_CALL("flt_source_execute", source->camera->execute(feature));
}
FLT_API flt_status FLT_CALL flt_source_map_feature(flt_source *source, const char *feature,
                                                   uint64_t address, uint32_t length,
                                                   int is_float) {
    FLT_FEATURE_CALL("flt_source_map_feature", {
        if (length != 1 && length != 2 && length != 4 && length != 8)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'length' = %u must be 1, 2, 4 "
                        "or 8 bytes",
                        fn, length);
        if (is_float && length != 4 && length != 8)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'length' = %u: a float register "
                        "has 4 or 8 bytes",
                        fn, length);
        source->camera->map_feature(feature, address, length, is_float != 0);
    });
}

FLT_API flt_status FLT_CALL flt_source_read_memory(flt_source *source, uint64_t address, void *out,
                                                   size_t bytes) {
    const char *fn = "flt_source_read_memory";
    return guard(fn, [&] {
        if (flt_status st = need_camera(fn, source))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (bytes == 0 || bytes > (64u << 20))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'bytes' = %zu is outside "
                        "[1, 64 MiB]",
                        fn, bytes);
        if (address > UINT64_MAX - (bytes - 1))  // the range must not wrap past 2^64
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'address' = 0x%llx + %zu "
                        "bytes passes the end of the address space",
                        fn, (unsigned long long)address, bytes);
        source->camera->read_memory(address, static_cast<std::uint8_t *>(out), bytes);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_source_write_memory(flt_source *source, uint64_t address,
                                                    const void *bytes_in, size_t bytes) {
    const char *fn = "flt_source_write_memory";
    return guard(fn, [&] {
        if (flt_status st = need_camera(fn, source))
            return st;
        FLT_CHECK_NOT_NULL(fn, bytes_in);
        if (bytes == 0 || bytes > (64u << 20))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'bytes' = %zu is outside "
                        "[1, 64 MiB]",
                        fn, bytes);
        if (address > UINT64_MAX - (bytes - 1))  // the range must not wrap past 2^64
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'address' = 0x%llx + %zu "
                        "bytes passes the end of the address space",
                        fn, (unsigned long long)address, bytes);
        source->camera->write_memory(address, static_cast<const std::uint8_t *>(bytes_in), bytes);
        return FLT_OK;
    });
}

// --- simulated bus ------------------------------------------------------------------

FLT_API flt_status FLT_CALL flt_u3v_sim_create(flt_u3v_sim **out) {
    const char *fn = "flt_u3v_sim_create";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = new flt_u3v_sim;
        return FLT_OK;
    });
}

FLT_API void FLT_CALL flt_u3v_sim_destroy(flt_u3v_sim *bus) {
    guard_void([&] {
        if (bus && bus->magic == k_bus_magic) {
            bus->magic = 0;
            delete bus;
        }
    });
}

FLT_API flt_status FLT_CALL flt_u3v_sim_add_camera(flt_u3v_sim *bus, const char *vendor,
                                                   const char *model, const char *serial,
                                                   uint32_t width, uint32_t height,
                                                   flt_pixel_format format, size_t *index_out) {
    const char *fn = "flt_u3v_sim_add_camera";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, bus);
        if (bus->magic != k_bus_magic)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'bus' is not a live flt_u3v_sim",
                        fn);
        FLT_CHECK_NOT_NULL(fn, vendor);
        FLT_CHECK_NOT_NULL(fn, model);
        FLT_CHECK_NOT_NULL(fn, serial);
        for (const char *s : {vendor, model, serial})
            if (std::strlen(s) > 63)
                return fail(FLT_ERR_INVALID_ARGUMENT,
                            "%s: string '%.80s...' is longer than 63 "
                            "bytes",
                            fn, s);
        if (bus->bus.cameras() >= 8)
            return fail(FLT_ERR_BUFFER_FULL, "%s: the bus already holds 8 cameras", fn);
        if (width < 16 || width > 8192)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'width' = %u is outside "
                        "[16, 8192]",
                        fn, width);
        if (height < 16 || height > 8192)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'height' = %u is outside "
                        "[16, 8192]",
                        fn, height);
        const int raw_format = enum_arg(format);
        if (raw_format != FLT_PIXEL_MONO8 && raw_format != FLT_PIXEL_MONO10 &&
            raw_format != FLT_PIXEL_MONO12 && raw_format != FLT_PIXEL_MONO16)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'format' = %d is not a pixel "
                        "format",
                        fn, raw_format);
        const std::size_t index =
            bus->bus.add_camera(vendor, model, serial, width, height, raw_format);
        if (index_out)
            *index_out = index;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_u3v_sim_set_frames(flt_u3v_sim *bus, size_t camera, flt_sim *sim) {
    const char *fn = "flt_u3v_sim_set_frames";
    return guard(fn, [&] {
        if (flt_status st = check_bus(fn, bus, camera))
            return st;
        u3v::sim_set_frames(bus->bus.camera(camera), sim);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_u3v_sim_set(flt_u3v_sim *bus, size_t camera,
                                            flt_u3v_sim_param param, uint64_t value) {
    const char *fn = "flt_u3v_sim_set";
    return guard(fn, [&] {
        if (flt_status st = check_bus(fn, bus, camera))
            return st;
        if (enum_arg(param) < 0)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'param' = %d: the parameter is "
                        "unknown",
                        fn, enum_arg(param));
        u3v::sim_set(bus->bus.camera(camera), param, value);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_u3v_sim_get(const flt_u3v_sim *bus, size_t camera,
                                            flt_u3v_sim_param param, uint64_t *out) {
    const char *fn = "flt_u3v_sim_get";
    return guard(fn, [&] {
        if (flt_status st = check_bus(fn, bus, camera))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (enum_arg(param) < 0)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'param' = %d: the parameter is "
                        "unknown",
                        fn, enum_arg(param));
        *out = u3v::sim_get(bus->bus.camera(camera), param);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_u3v_sim_inject(flt_u3v_sim *bus, size_t camera, flt_u3v_fault fault,
                                               uint64_t at, uint32_t count) {
    const char *fn = "flt_u3v_sim_inject";
    return guard(fn, [&] {
        if (flt_status st = check_bus(fn, bus, camera))
            return st;
        if (enum_arg(fault) < 0)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'fault' = %d: the fault is "
                        "unknown",
                        fn, enum_arg(fault));
        u3v::sim_inject(bus->bus.camera(camera), fault, at, count);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_u3v_sim_peek(const flt_u3v_sim *bus, size_t camera,
                                             uint64_t address, uint32_t *out) {
    const char *fn = "flt_u3v_sim_peek";
    return guard(fn, [&] {
        if (flt_status st = check_bus(fn, bus, camera))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        if (!u3v::sim_peek(bus->bus.camera(camera), address, *out))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'address' = 0x%llx is outside "
                        "the register map",
                        fn, (unsigned long long)address);
        return FLT_OK;
    });
}

}  // extern "C"
