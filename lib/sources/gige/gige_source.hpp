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
//   stream.*      packet size, the stream socket, who may speak on it
//   assembly.*    frame assembly and resends
//
// under the camera base (../camera/), which owns the acquisition sequence
// and the frame accounting.
#pragma once

#include <memory>
#include <string>

#include "sources/camera/camera.hpp"
#include "sources/gige/bootstrap.hpp"
#include "sources/gige/control.hpp"
#include "sources/gige/stream.hpp"

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

// The acquisition sequence, features and frame accounting are the camera
// base's (../camera/camera.hpp); this class implements its hooks over GVCP
// (the stream channel is on while SCP names the host's port) and GVSP.
class gige_camera final : public sources::genicam_camera {
  public:
    // Takes control of the camera at `address`, reads its bootstrap
    // registers and GenICam file, and negotiates the stream packet size.
    gige_camera(endpoint address, const camera_config &config);
    ~gige_camera() override;

    flt_source_kind kind() const override { return FLT_SOURCE_GIGE; }

  private:
    // hooks of genicam_camera
    sources::register_port &control() override { return control_; }
    void check_link(bool starting) override;
    void prepare_stream(const sources::frame_geometry &g) override;
    void enable_channel() override { stream_.aim(); }
    bool disable_channel() override { return stream_.close_channel(); }
    void release_stream() noexcept override { stream_.release(); }
    bool next_frame(unsigned timeout_ms, sources::raw_frame &out) override;
    std::uint64_t transport_count(flt_source_counter which) const override;
    bool transport_value(flt_camera_value which, std::uint64_t &out) const override;

    camera_config config_;
    control_channel control_;
    bootstrap_info boot_;
    stream_channel stream_;
};

}  // namespace flt::gige
