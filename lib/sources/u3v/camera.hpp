// SPDX-License-Identifier: Apache-2.0
// Internal: the USB3 Vision client - discovery, GenCP control channel,
// bootstrap registers, GenICam features, stream set-up and the transfer
// pool assembled into frames with accounting of every failure mode.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "flatline/source.h"
#include "sources/u3v/genicam.hpp"
#include "sources/u3v/transport.hpp"

namespace flt::u3v {

struct camera_entry {
    usb_device_desc desc;
    std::string vendor, model, serial, error;
};

// The U3V cameras on a bus (strings read from the descriptors).
std::vector<camera_entry> list_cameras(usb_backend &bus);

struct camera_config {
    unsigned control_timeout_floor_ms = 200;
    unsigned pending_ack_limit = 5;
    unsigned command_attempts = 3;
    std::size_t transfers = 8;
    std::size_t max_transfer_bytes = 1u << 20;
    bool want_chunk = false;
    std::uint32_t chunk_id = 0;
};

// A frame assembled in the camera's frame buffer (valid until next()).
struct frame_view {
    const std::uint8_t *pixels = nullptr;
    std::uint32_t width = 0, height = 0;
    std::size_t stride = 0;
    int bits = 8;
    std::uint64_t block_id = 0, timestamp_ns = 0;
    bool has_chunk_counter = false;
    std::uint64_t chunk_counter = 0;
    unsigned chunk_counter_bytes = 0;
};

class camera {
  public:
    // Opens the camera with `serial` (or the first), reads the bootstrap
    // registers and the XML, and stops a stream a dead process left running.
    camera(usb_backend &bus, const char *serial, const camera_config &config);
    ~camera();

    const std::string &string_of(flt_camera_string which) const;
    std::uint64_t value_of(flt_camera_value which) const;
    std::uint64_t counter(flt_source_counter which) const { return counters_[which]; }
    const std::string &stream_error() const { return stream_error_; }

    void read_memory(std::uint64_t address, std::uint8_t *out, std::size_t bytes);
    void write_memory(std::uint64_t address, const std::uint8_t *in, std::size_t bytes);

    std::int64_t get_int(const std::string &feature);
    void set_int(const std::string &feature, std::int64_t value);
    double get_float(const std::string &feature);
    void set_float(const std::string &feature, double value);
    void set_enum(const std::string &feature, const std::string &entry);
    void execute(const std::string &feature);
    void map_feature(const std::string &feature, std::uint64_t address, std::uint32_t length,
                     bool is_float);

    void start();
    void stop() noexcept;  // best effort: also after an unplug
    bool streaming() const { return streaming_; }
    // FLT_OK with `out` filled, FLT_ERR_TIMEOUT, or throws (FLT_ERR_DEVICE).
    flt_status next(unsigned timeout_ms, frame_view &out);

  private:
    using clock = std::chrono::steady_clock;
    void transact(std::uint16_t command, const std::uint8_t *body, std::size_t body_bytes,
                  std::uint8_t *ack_body, std::size_t ack_bytes, std::uint64_t address);
    void bootstrap();
    void load_xml();
    void recover_stream();
    feature_access access(const std::string &feature) const;
    std::uint64_t read_register(const feature_access &a);
    void write_register(const feature_access &a, std::uint64_t raw);
    [[noreturn]] void lost_device(const char *what);

    // stream assembly
    void drop(flt_source_counter reason, const std::string &why);
    bool on_transfer(const usb_completion &c, frame_view &out);
    bool on_leader(const std::uint8_t *p, std::size_t n);
    void on_payload(const std::uint8_t *p, std::size_t n);
    bool on_trailer(const std::uint8_t *p, std::size_t n, frame_view &out);
    void resubmit(std::size_t slot);
    void submit_waiting();
    std::size_t merged_trailer_at(const std::uint8_t *p, std::size_t n) const;

    camera_config config_;
    std::unique_ptr<usb_device> dev_;
    std::uint8_t ep_control_in_ = 0, ep_control_out_ = 0, ep_stream_ = 0;
    int if_control_ = -1, if_stream_ = -1;
    std::uint32_t speed_mbps_ = 0;
    bool disconnected_ = false;

    // control channel
    std::uint16_t request_id_ = 0;
    std::uint32_t max_command_ = 128, max_ack_ = 128;  // until SBRM is read
    unsigned timeout_ms_ = 200;
    std::vector<std::uint8_t> command_buffer_, ack_buffer_;

    // bootstrap
    std::array<std::string, 7> strings_;
    std::uint32_t gencp_version_ = 0, u3v_version_ = 0, response_ms_ = 0;
    std::uint64_t manifest_address_ = 0, sbrm_address_ = 0, sirm_address_ = 0;
    std::uint64_t xml_bytes_ = 0;
    bool xml_zipped_ = false;
    genicam_map xml_;
    std::map<std::string, feature_access> mapped_;

    // stream
    bool streaming_ = false;
    std::uint32_t alignment_ = 1;
    std::uint64_t payload_bytes_ = 0;
    std::uint32_t transfer_bytes_ = 0, transfer_count_ = 0, final1_bytes_ = 0;
    std::uint32_t max_leader_ = 0, max_trailer_ = 0, required_trailer_ = 0;
    std::vector<std::uint8_t> pool_;
    std::vector<std::uint8_t *> slot_buffers_;
    std::size_t slot_bytes_ = 0;
    std::vector<std::uint8_t> waiting_;  // slots whose submission was refused
    std::size_t in_flight_ = 0;
    std::vector<std::uint8_t> frame_;  // payload of the frame being assembled
    bool frame_open_ = false, frame_damaged_ = false;
    bool discarding_ = false;  // dropping the rest of a frame until a leader
    std::size_t received_ = 0;
    std::uint64_t block_id_ = 0, timestamp_ = 0, last_block_ = 0;
    bool have_last_block_ = false;
    std::uint32_t width_ = 0, height_ = 0, padding_x_ = 0;
    int bits_ = 8;
    std::size_t image_bytes_ = 0;

    std::array<std::uint64_t, 17> counters_{};
    std::string stream_error_;
};

}  // namespace flt::u3v
