// SPDX-License-Identifier: Apache-2.0
// Internal: the USB3 Vision stream channel - the streaming interface
// registers (SIRM) set up for the image size, a pool of bulk IN transfers
// of one size, and each completion classified (leader, payload, trailer)
// and assembled into the frame buffer, with every failure mode counted
// (flatline/source.h, "Frame accounting").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sources/camera/accounting.hpp"
#include "sources/camera/features.hpp"
#include "sources/camera/pixel_format.hpp"
#include "sources/source.hpp"
#include "sources/u3v/discovery.hpp"

namespace flt::u3v {

struct stream_config {
    std::size_t transfers = 8;                  // option u3v_transfers
    std::size_t max_transfer_bytes = 1u << 20;  // option u3v_transfer_size
    bool want_chunk = false;                    // encoder mode 3
    std::uint32_t chunk_id = 0;                 // option source_encoder_chunk_id
};

// What the set-up chose (flt_camera_value ALIGNMENT .. MAX_TRAILER_BYTES).
struct stream_layout {
    std::uint32_t alignment = 1;
    std::uint64_t payload_bytes = 0;
    std::uint32_t transfer_bytes = 0, transfer_count = 0, final1_bytes = 0;
    std::uint32_t max_leader = 0, max_trailer = 0, required_trailer = 0;
};

class stream_channel {
  public:
    stream_channel(usb_link &link, sources::register_port &control, sources::frame_accounting &acc,
                   const stream_config &config)
        : link_(link), control_(control), acc_(acc), config_(config) {}

    // Reads SIRM at `sirm_address`, writes the transfer set-up for images
    // of `g` (checked against the frame bounds by the camera base),
    // allocates the host buffers (the frame and the transfer pool, at most
    // k_max_buffer_bytes together: FLT_ERR_DEVICE naming both before
    // anything is allocated), clears a halt of the stream endpoint and
    // submits the transfers. The stream interface stays disabled (SI
    // control is the caller's).
    void prepare(std::uint64_t sirm_address, const sources::frame_geometry &g);
    // Cancels every transfer in flight and clears the endpoint's halt
    // (unless the device is gone). Safe to call when nothing is prepared.
    void release() noexcept;
    bool prepared() const { return prepared_; }

    // The next good frame within timeout_ms (see source_impl::next).
    bool next(unsigned timeout_ms, sources::raw_frame &out);

    const stream_layout &layout() const { return layout_; }

  private:
    bool on_transfer(const usb_completion &c, sources::raw_frame &out);
    bool on_leader(const std::uint8_t *p, std::size_t n);
    void on_payload(const std::uint8_t *p, std::size_t n);
    bool on_trailer(const std::uint8_t *p, std::size_t n, sources::raw_frame &out);
    void drop(flt_source_counter reason, const std::string &why);
    void resubmit(std::size_t slot);
    void submit_waiting();
    std::size_t merged_trailer_at(const std::uint8_t *p, std::size_t n) const;

    usb_link &link_;
    sources::register_port &control_;
    sources::frame_accounting &acc_;
    stream_config config_;
    stream_layout layout_;
    bool prepared_ = false;

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
};

}  // namespace flt::u3v
