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
// and owns the acquisition sequence (start, stop, recovery of a camera
// left streaming) and the frame accounting they count into.
#pragma once

#include <memory>
#include <string>

#include "sources/accounting.hpp"
#include "sources/features.hpp"
#include "sources/source.hpp"
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

class u3v_camera final : public sources::source_impl, public sources::camera_device {
  public:
    // Opens the camera with `serial` (NULL: the first) on `bus` (which must
    // outlive the camera), reads the bootstrap registers and the GenICam
    // file, and stops a stream a dead process left running.
    u3v_camera(usb_backend &bus, const char *serial, const camera_config &config);
    // The same on the USB bus through libusb-1.0 (the camera owns it).
    u3v_camera(std::unique_ptr<usb_backend> owned_bus, const char *serial,
               const camera_config &config);
    ~u3v_camera() override;

    // source_impl
    flt_source_kind kind() const override { return FLT_SOURCE_U3V; }
    bool has_chunks() const override { return true; }
    void start() override;
    void stop() override;
    bool next(unsigned timeout_ms, sources::raw_frame &out) override;
    std::uint64_t count(flt_source_counter which) const override { return acc_[which]; }
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

    bool streaming() const { return streaming_; }

  private:
    void open(usb_backend &bus, const char *serial);
    void start_sequence();
    void recover_stream();
    void write_si_control(std::uint32_t value);
    bool si_enabled();
    // Stops the camera: AcquisitionStop, SI control = 0 read back, retried
    // while worth it. Throws (the camera may still stream) unless SI control
    // is off and, with need_acquisition_stop, AcquisitionStop was taken.
    void halt_camera(bool need_acquisition_stop);
    void lock_transport_params(bool locked);

    std::unique_ptr<usb_backend> owned_bus_;  // declared first: destroyed last
    camera_config config_;
    sources::frame_accounting acc_;
    usb_link link_;
    control_channel control_;
    stream_channel stream_;
    bootstrap_info boot_;
    std::uint64_t xml_bytes_ = 0;
    bool xml_zipped_ = false;
    std::unique_ptr<sources::feature_layer> features_;
    bool streaming_ = false;  // the host side: the stream is set up
    // The camera may be streaming although the host is not: a stop or start
    // failed between SI control = 1 and a confirmed stop. The next start or
    // stop stops it first.
    bool may_stream_ = false;
};

}  // namespace flt::u3v
