// SPDX-License-Identifier: Apache-2.0
// Internal to libflatline_testing: a simulated USB bus with USB3 Vision
// cameras behind libflatline's transport interface (flatline/testing.h
// describes its behaviour as the tests see it). Its objects are called by
// libflatline across the library boundary: no exception may leave a
// usb_backend or usb_device method (each answers a usb_status instead).
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "flatline/testing.h"
#include "sources/u3v/transport.hpp"

namespace flt::testing {

using u3v::usb_backend;
using u3v::usb_device;
using u3v::usb_device_desc;
using u3v::usb_status;

// Register map of the simulated camera.
namespace sim_map {
constexpr std::uint64_t sbrm = 0x1000;
constexpr std::uint64_t sirm = 0x2000;
constexpr std::uint64_t manifest = 0x3000;
constexpr std::uint64_t features = 0x10000;
constexpr std::uint64_t features_size = 0x30;
constexpr std::uint64_t xml = 0x100000;
constexpr std::uint64_t width = features + 0x00, height = features + 0x04,
                        pixel_format = features + 0x08, offset_y = features + 0x0C,
                        acquisition_mode = features + 0x10, acquisition_start = features + 0x14,
                        acquisition_stop = features + 0x18, exposure_raw = features + 0x1C,
                        trigger_selector = features + 0x20, trigger_mode = features + 0x24,
                        trigger_source = features + 0x28, gain = features + 0x2C;
constexpr std::size_t packet = 512;  // bytes per USB packet of the stream
constexpr std::uint32_t leader_size = 52, trailer_size = 32;
}  // namespace sim_map

struct sim_camera;

class sim_bus final : public usb_backend {
  public:
    sim_bus();
    ~sim_bus() override;
    usb_status list(std::vector<usb_device_desc> &out) override;
    usb_status open(const usb_device_desc &desc, std::unique_ptr<usb_device> &out) override;

    std::size_t add_camera(const std::string &vendor, const std::string &model,
                           const std::string &serial, std::uint32_t width, std::uint32_t height,
                           int bits);
    std::size_t cameras() const { return cameras_.size(); }
    sim_camera &camera(std::size_t i) { return *cameras_[i]; }
    const sim_camera &camera(std::size_t i) const { return *cameras_[i]; }

  private:
    void describe(std::vector<usb_device_desc> &out) const;
    std::vector<std::unique_ptr<sim_camera>> cameras_;
};

// Parameters and inspection (the flt_u3v_sim_* entry points).
void sim_set(sim_camera &cam, flt_u3v_sim_param param, std::uint64_t value);
std::uint64_t sim_get(const sim_camera &cam, flt_u3v_sim_param param);
void sim_inject(sim_camera &cam, flt_u3v_fault fault, std::uint64_t at, std::uint32_t count);
bool sim_peek(const sim_camera &cam, std::uint64_t address, std::uint32_t &out);
void sim_set_frames(sim_camera &cam, flt_sim *sim);

}  // namespace flt::testing
