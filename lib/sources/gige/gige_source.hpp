// SPDX-License-Identifier: Apache-2.0
// Internal: a GigE Vision camera as a frame source. It stacks the protocol
// layers of this folder:
//
//   socket.*      portable UDP sockets (BSD sockets, Winsock 2)
//   discovery.*   which cameras answer on the network
//   control.*     GVCP: registers and memory (a register_port), the control
//                 privilege and its heartbeat, resend requests
//   bootstrap.*   the bootstrap registers and the GenICam file
//   ../features.* GenICam features by name over the control channel
//   stream.*      packet size, the stream socket, frame assembly and resends
//
// and owns the acquisition sequence and the frame accounting.
#pragma once

#include <memory>
#include <string>

#include "sources/accounting.hpp"
#include "sources/features.hpp"
#include "sources/gige/bootstrap.hpp"
#include "sources/gige/control.hpp"
#include "sources/gige/stream.hpp"
#include "sources/source.hpp"

namespace flt::gige {

struct camera_config {
    control_config control;
    stream_config stream;
    unsigned discovery_ms = 1000;  // option gige_discovery_timeout
};

// The camera `camera` names: NULL = the first that answers a discovery
// broadcast; "a.b.c.d" or "a.b.c.d:port" = that address (GVCP port 3956
// unless given); anything else = the serial number or user-defined name of
// a camera found by discovery. FLT_ERR_NOT_FOUND when none answers.
endpoint find_camera(const char *camera, unsigned discovery_ms);

class gige_camera final : public sources::source_impl, public sources::camera_device {
  public:
    // Takes control of the camera at `address`, reads its bootstrap
    // registers and GenICam file, and negotiates the stream packet size.
    gige_camera(endpoint address, const camera_config &config);
    ~gige_camera() override;

    // source_impl
    flt_source_kind kind() const override { return FLT_SOURCE_GIGE; }
    void start() override;
    void stop() override;
    bool next(unsigned timeout_ms, sources::raw_frame &out) override;
    std::uint64_t count(flt_source_counter which) const override;
    const std::string &stream_error() const override { return acc_.stream_error; }
    sources::camera_device *camera() override { return this; }

    // camera_device
    const std::string &string_of(flt_camera_string which) const override;
    std::uint64_t value_of(flt_camera_value which) const override;
    std::int64_t get_int(const std::string &feature) override;
    void set_int(const std::string &feature, std::int64_t value) override;
    double get_float(const std::string &feature) override;
    void set_float(const std::string &feature, double value) override;
    void set_enum(const std::string &feature, const std::string &entry) override;
    void execute(const std::string &feature) override;
    void map_feature(const std::string &feature, std::uint64_t address, std::uint32_t length,
                     bool is_float) override;
    void read_memory(std::uint64_t address, std::uint8_t *out, std::size_t bytes) override;
    void write_memory(std::uint64_t address, const std::uint8_t *in, std::size_t bytes) override;

  private:
    void lock_transport_params(bool locked);
    void check_control();

    camera_config config_;
    sources::frame_accounting acc_;
    control_channel control_;
    bootstrap_info boot_;
    std::uint64_t xml_bytes_ = 0;
    bool xml_zipped_ = false;
    std::unique_ptr<sources::feature_layer> features_;
    stream_channel stream_;
    bool streaming_ = false;
};

}  // namespace flt::gige
