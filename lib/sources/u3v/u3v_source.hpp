// SPDX-License-Identifier: Apache-2.0
// Internal: a USB3 Vision camera as a frame source. It stacks the protocol
// layers of this folder:
//
//   discovery.*   which USB devices are cameras; open and claim one
//   control.*     GenCP over the control endpoints (a register_port)
//   bootstrap.*   ABRM / SBRM, the manifest and the GenICam file
//   ../features.* GenICam features by name over the control channel
//   stream.*      SIRM set-up, the transfer pool, frame assembly
//
// under the camera base (../camera/), which owns the acquisition sequence
// (start, stop, recovery of a camera left streaming) and the frame
// accounting they count into.
#pragma once

#include <memory>
#include <string>

#include "sources/camera/camera.hpp"
#include "sources/u3v/bootstrap.hpp"
#include "sources/u3v/control.hpp"
#include "sources/u3v/discovery.hpp"
#include "sources/u3v/stream.hpp"
#include "sources/u3v/transport.hpp"

namespace flt::u3v {

struct camera_config {
    control_config control;
    stream_config stream;
};

// The acquisition sequence, features and frame accounting are the camera
// base's (../camera/camera.hpp); this class implements its hooks over SIRM
// (SI control is the stream channel) and the bulk stream endpoint.
class u3v_camera final : public sources::genicam_camera {
  public:
    // Opens the camera with `serial` (NULL: the first) on `bus` (which must
    // outlive the camera), reads the bootstrap registers and the GenICam
    // file, and stops a stream a dead process left running.
    u3v_camera(usb_backend &bus, const char *serial, const camera_config &config);
    // The same on the USB bus through libusb-1.0 (the camera owns it).
    u3v_camera(std::unique_ptr<usb_backend> owned_bus, const char *serial,
               const camera_config &config);
    ~u3v_camera() override;

    flt_source_kind kind() const override { return FLT_SOURCE_U3V; }
    bool has_chunks() const override { return true; }

  private:
    void open(usb_backend &bus, const char *serial);
    void write_si_control(std::uint32_t value);
    bool si_enabled();

    // hooks of genicam_camera
    sources::register_port &control() override { return control_; }
    void check_link(bool starting) override;
    bool gone() const override { return link_.disconnected; }
    bool channel_enabled() override;
    void prepare_stream(const sources::frame_geometry &g) override;
    void enable_channel() override;
    bool disable_channel() override;
    void release_stream() noexcept override { stream_.release(); }
    bool next_frame(unsigned timeout_ms, sources::raw_frame &out) override {
        return stream_.next(timeout_ms, out);
    }
    bool transport_value(flt_camera_value which, std::uint64_t &out) const override;

    std::unique_ptr<usb_backend> owned_bus_;  // declared first: destroyed last
    camera_config config_;
    usb_link link_;
    control_channel control_;
    stream_channel stream_;
    bootstrap_info boot_;
};

}  // namespace flt::u3v
