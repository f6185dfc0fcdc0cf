// SPDX-License-Identifier: Apache-2.0
// The USB3 Vision stream: SIRM set-up, the transfer pool, and frame
// assembly with accounting. A frame is a leader, payload transfers and a
// trailer; a trailer that shares the host transfer with the final payload
// is split off.
#include "sources/u3v/stream.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>

#include "core/error.hpp"
#include "sources/camera/camera.hpp"
#include "sources/u3v/control.hpp"
#include "sources/u3v/protocol.hpp"

namespace flt::u3v {

using sources::raise;
using sources::raw_frame;

namespace {

std::uint64_t align_up(std::uint64_t v, std::uint64_t a) {
    return (v + a - 1) / a * a;
}

}  // namespace

void stream_channel::prepare(std::uint64_t sirm_address, const sources::frame_geometry &g) {
    release();
    stream_layout &l = layout_;
    std::uint8_t s[sirm::size];
    control_.read(sirm_address, s, sizeof s);
    const std::uint32_t shift = get_u32(s + sirm::info) >> 24;
    if (shift > 20)
        raise(FLT_ERR_FORMAT, "SIRM: alignment 2^%u bytes", shift);
    l.alignment = 1u << shift;
    l.payload_bytes = get_u64(s + sirm::required_payload);
    const std::uint32_t leader = get_u32(s + sirm::required_leader);
    l.required_trailer = get_u32(s + sirm::required_trailer);
    if (l.payload_bytes == 0 || l.payload_bytes > (std::uint64_t(1) << 31))
        raise(FLT_ERR_FORMAT, "SIRM: required payload size %llu bytes",
              (unsigned long long)l.payload_bytes);
    // A leader or trailer is a few dozen bytes; a camera asking for more
    // than a transfer would make every buffer of the pool that large.
    if (leader < k_leader_image_size || l.required_trailer < k_trailer_min_size ||
        leader > k_max_leader_trailer || l.required_trailer > k_max_leader_trailer)
        raise(FLT_ERR_FORMAT,
              "SIRM: leader %u / trailer %u bytes are outside the U3V range (%zu / %zu .. %u)",
              leader, l.required_trailer, k_leader_image_size, k_trailer_min_size,
              unsigned(k_max_leader_trailer));
    width_ = g.width;
    height_ = g.height;
    bits_ = g.bits;
    image_bytes_ = std::size_t(g.image_bytes);
    if (l.payload_bytes < g.image_bytes)
        raise(FLT_ERR_FORMAT, "SIRM: payload %llu bytes is less than Width x Height = %u x %u",
              (unsigned long long)l.payload_bytes, g.width, g.height);
    // The transfer size: a multiple of the alignment, at most the option.
    const std::uint64_t cap = std::max<std::uint64_t>(l.alignment, config_.max_transfer_bytes /
                                                                       l.alignment * l.alignment);
    std::uint64_t size = std::min<std::uint64_t>(cap, l.payload_bytes / l.alignment * l.alignment);
    if (size == 0)
        size = l.alignment;
    l.transfer_bytes = std::uint32_t(size);
    l.transfer_count = std::uint32_t(l.payload_bytes / size);
    l.final1_bytes = std::uint32_t(align_up(l.payload_bytes % size, l.alignment));
    l.max_leader = std::uint32_t(align_up(leader, l.alignment));
    l.max_trailer = std::uint32_t(align_up(l.required_trailer, l.alignment));
    std::uint8_t w[4];
    const std::pair<std::uint64_t, std::uint32_t> set_up[] = {
        {sirm::max_leader, l.max_leader},
        {sirm::transfer_size, l.transfer_bytes},
        {sirm::transfer_count, l.transfer_count},
        {sirm::final1_size, l.final1_bytes},
        {sirm::final2_size, 0},
        {sirm::max_trailer, l.max_trailer}};
    for (const auto &r : set_up) {
        put_u32(w, r.second);
        control_.write(sirm_address + r.first, w, 4);
    }

    // Host buffers: one size fits every transfer (a leader, a payload
    // transfer, the final one or a trailer), in one block; with the frame,
    // bounded in total before anything is allocated.
    slot_bytes_ = std::max({std::size_t(l.transfer_bytes), std::size_t(l.final1_bytes),
                            std::size_t(l.max_leader), std::size_t(l.max_trailer)});
    const std::size_t slots = std::max<std::size_t>(2, config_.transfers);
    const std::uint64_t pool_bytes = std::uint64_t(slots) * slot_bytes_;
    const std::uint64_t frame_bytes = l.payload_bytes + l.alignment;
    const std::uint64_t stream_bytes = pool_bytes + frame_bytes;
    if (stream_bytes > sources::k_max_buffer_bytes)
        raise(FLT_ERR_DEVICE,
              "the stream would take %llu bytes (a %llu-byte frame and %zu transfers of %zu), "
              "more than the %llu a camera source may (FLT_SOURCE_MAX_BUFFER_BYTES); lower "
              "Width or Height, u3v_transfers or u3v_transfer_size",
              (unsigned long long)stream_bytes, (unsigned long long)frame_bytes, slots, slot_bytes_,
              (unsigned long long)sources::k_max_buffer_bytes);
    pool_.assign(slots * slot_bytes_, 0);
    slot_buffers_.resize(slots);
    for (std::size_t i = 0; i < slots; ++i)
        slot_buffers_[i] = pool_.data() + i * slot_bytes_;
    frame_.assign(std::size_t(l.payload_bytes) + l.alignment, 0);
    waiting_.clear();
    in_flight_ = 0;
    frame_open_ = frame_damaged_ = false;
    discarding_ = true;  // until the first leader
    have_last_block_ = false;

    usb_status st = link_.dev->clear_halt(link_.ep_stream);
    if (st == usb_status::no_device)
        lost_device(link_, acc_, "stream set-up");
    st = link_.dev->async_prepare(link_.ep_stream, slots, slot_buffers_.data(), slot_bytes_);
    if (st != usb_status::ok)
        raise(FLT_ERR_DEVICE, "cannot prepare %zu bulk transfers: %s", slots, usb_status_name(st));
    prepared_ = true;
    for (std::size_t i = 0; i < slots; ++i)
        waiting_.push_back(1);
    submit_waiting();
    if (in_flight_ == 0) {
        release();
        raise(FLT_ERR_DEVICE,
              "no bulk transfer of %zu bytes could be submitted (on Linux, "
              "usbfs memory: raise /sys/module/usbcore/parameters/usbfs_memory_mb "
              "or lower u3v_transfers)",
              slot_bytes_);
    }
}

void stream_channel::release() noexcept {
    if (!prepared_)
        return;
    prepared_ = false;
    link_.dev->async_release();
    in_flight_ = 0;
    waiting_.clear();
    frame_open_ = false;
    if (!link_.disconnected)
        link_.dev->clear_halt(link_.ep_stream);
}

// Camera fault point: a frame of the camera is dropped (the reason goes to
// flt_source_stream_error()).
void stream_channel::drop(flt_source_counter reason, const std::string &why) {
    acc_.drop(reason, why);
    frame_open_ = false;
    frame_damaged_ = false;
    discarding_ = true;  // the rest of this frame, if any, is not garbage
}

void stream_channel::submit_waiting() {
    for (std::size_t slot = 0; slot < waiting_.size(); ++slot) {
        if (!waiting_[slot])
            continue;
        const usb_status st = link_.dev->async_submit(slot);
        if (st == usb_status::ok) {
            waiting_[slot] = 0;
            ++in_flight_;
            continue;
        }
        if (st == usb_status::no_device)
            lost_device(link_, acc_, "stream");
        // Refused (usbfs memory on Linux): while fewer transfers wait, the
        // camera may send data nobody receives, so the frame in progress,
        // or the next one, cannot be trusted.
        acc_.add(FLT_COUNT_SUBMIT_REFUSED);
        acc_.stream_error =
            std::string("a bulk transfer submission was refused: ") + usb_status_name(st);
        frame_damaged_ = true;  // the open frame, or the next one to open
    }
}

void stream_channel::resubmit(std::size_t slot) {
    waiting_[slot] = 1;
    submit_waiting();
}

std::size_t stream_channel::merged_trailer_at(const std::uint8_t *p, std::size_t n) const {
    // A final transfer that is a whole number of packets does not end the
    // host's transfer, so the trailer can arrive in the same buffer.
    const std::size_t sizes[3] = {layout_.required_trailer, k_trailer_min_size,
                                  layout_.max_trailer};
    for (std::size_t t : sizes)
        if (n > t && get_u32(p + n - t) == k_magic_trailer && get_u64(p + n - t + 8) == block_id_)
            return n - t;
    return n;
}

bool stream_channel::on_leader(const std::uint8_t *p, std::size_t n) {
    const std::uint64_t block = get_u64(p + 8);
    if (frame_open_) {
        char text[200];
        std::snprintf(text, sizeof text,
                      "block %llu: a new leader (block %llu) arrived after "
                      "%zu of its payload bytes; dropped",
                      (unsigned long long)block_id_, (unsigned long long)block, received_);
        const bool damaged = frame_damaged_;
        drop(FLT_COUNT_INCOMPLETE, text);
        frame_damaged_ = damaged;
    }
    if (have_last_block_ && block > last_block_ + 1) {
        acc_.add(FLT_COUNT_LOST, block - last_block_ - 1);
        char text[160];
        std::snprintf(text, sizeof text, "block ids %llu..%llu never arrived (lost)",
                      static_cast<unsigned long long>(last_block_) + 1,
                      static_cast<unsigned long long>(block) - 1);
        acc_.stream_error = text;
    }
    last_block_ = block;
    have_last_block_ = true;
    const std::uint16_t type = get_u16(p + 18);
    const std::uint32_t pfnc = get_u32(p + 28), w = get_u32(p + 32), h = get_u32(p + 36);
    const std::uint16_t pad = get_u16(p + 48);
    const int bits = pfnc_bits(pfnc);
    const std::uint64_t payload = layout_.payload_bytes;
    char text[200] = {0};
    if (n < k_leader_image_size)
        std::snprintf(text, sizeof text, "block %llu: leader of %zu bytes, an image leader has %zu",
                      (unsigned long long)block, n, k_leader_image_size);
    else if (type != k_payload_image && type != k_payload_image_chunk)
        std::snprintf(text, sizeof text, "block %llu: payload type 0x%04x is not an image",
                      (unsigned long long)block, type);
    else if (bits == 0)
        std::snprintf(text, sizeof text, "block %llu: pixel format 0x%08x is not Mono8/10/12/16",
                      (unsigned long long)block, pfnc);
    else if (w == 0 || h == 0 || w > sources::k_max_frame_side || h > sources::k_max_frame_side ||
             !sources::image_size_fits(std::uint64_t(w) * sources::bytes_per_pixel(bits), pad, h, 0,
                                       payload))
        std::snprintf(text, sizeof text,
                      "block %llu: a %u x %u image does not fit the %llu "
                      "payload bytes the stream was set up for",
                      (unsigned long long)block, w, h, (unsigned long long)payload);
    if (text[0]) {
        acc_.add(FLT_COUNT_BAD_LEADERS);
        acc_.add(FLT_COUNT_DROPPED);
        acc_.stream_error = text;
        return false;
    }
    frame_open_ = true;
    discarding_ = false;
    block_id_ = block;
    timestamp_ = get_u64(p + 20);
    width_ = w;
    height_ = h;
    bits_ = bits;
    padding_x_ = pad;
    image_bytes_ = (std::size_t(w) * sources::bytes_per_pixel(bits) + pad) * h;  // <= payload
    received_ = 0;
    return true;
}

void stream_channel::on_payload(const std::uint8_t *p, std::size_t n) {
    if (received_ + n > frame_.size()) {
        char text[200];
        std::snprintf(text, sizeof text,
                      "block %llu: %zu payload bytes overflow the %llu the "
                      "stream was set up for",
                      (unsigned long long)block_id_, received_ + n,
                      (unsigned long long)layout_.payload_bytes);
        drop(FLT_COUNT_OVERFLOW, text);
        return;
    }
    std::memcpy(frame_.data() + received_, p, n);
    received_ += n;
}

bool stream_channel::on_trailer(const std::uint8_t *p, std::size_t n, raw_frame &out) {
    const std::uint64_t block = get_u64(p + 8);
    const std::uint16_t status = get_u16(p + 16);
    const std::uint64_t valid = n >= 28 ? get_u64(p + 20) : 0;
    char text[240] = {0};
    flt_source_counter reason = FLT_COUNT_SHORT;
    if (frame_damaged_) {
        reason = FLT_COUNT_SUBMIT_DROPPED;
        std::snprintf(text, sizeof text,
                      "block %llu: dropped, a bulk submission was refused while it streamed",
                      (unsigned long long)block_id_);
    } else if (block != block_id_)
        std::snprintf(text, sizeof text, "block %llu: the trailer is of block %llu",
                      (unsigned long long)block_id_, (unsigned long long)block);
    else if (status != 0)
        std::snprintf(text, sizeof text, "block %llu: trailer status 0x%04x (%s)",
                      (unsigned long long)block_id_, status, gencp_status_name(status));
    else if (received_ < valid || valid < image_bytes_ || valid > layout_.payload_bytes)
        std::snprintf(text, sizeof text,
                      "block %llu: short frame, %zu payload bytes arrived, "
                      "the trailer says %llu valid, the image needs %zu",
                      (unsigned long long)block_id_, received_, (unsigned long long)valid,
                      image_bytes_);
    if (text[0]) {
        drop(reason, text);
        return false;
    }
    frame_open_ = false;
    out.pixels = frame_.data();
    out.bytes = frame_.size();
    out.width = width_;
    out.height = height_;
    out.stride = std::size_t(width_) * (bits_ > 8 ? 2 : 1) + padding_x_;
    out.format = flt_pixel_format(bits_);
    out.block_id = block_id_;
    out.timestamp_ns = timestamp_;
    out.has_chunk_counter = false;
    if (config_.want_chunk && valid > image_bytes_) {
        // Chunks are walked from the end: data, then id and length (u32 LE).
        std::size_t end = std::size_t(valid);
        for (int guard = 0; guard < 64 && end >= image_bytes_ + 8; ++guard) {
            const std::uint32_t id = get_u32(&frame_[end - 8]);
            const std::uint32_t length = get_u32(&frame_[end - 4]);
            if (length > end - 8)
                break;
            if (id == config_.chunk_id && (length == 4 || length == 8)) {
                out.has_chunk_counter = true;
                out.chunk_counter = get_uint(&frame_[end - 8 - length], length);
                out.chunk_counter_bytes = length;
                break;
            }
            end -= 8 + length;
        }
    }
    acc_.add(FLT_COUNT_FRAMES);
    return true;
}

bool stream_channel::on_transfer(const usb_completion &c, raw_frame &out) {
    const std::uint8_t *p = slot_buffers_[c.slot];
    std::size_t n = c.length;
    switch (c.status) {
        case usb_status::ok:
            break;
        case usb_status::no_device:
            lost_device(link_, acc_, "stream");
        case usb_status::overflow: {
            char text[200];
            std::snprintf(text, sizeof text,
                          "block %llu: a bulk transfer overflowed its %zu-byte "
                          "buffer (the camera sent more than the stream set-up allows)",
                          (unsigned long long)block_id_, slot_bytes_);
            if (frame_open_) {
                drop(FLT_COUNT_OVERFLOW, text);
            } else if (!discarding_) {
                acc_.add(FLT_COUNT_OVERFLOW);
                acc_.stream_error = text;
            }
            return false;
        }
        default: {
            if (c.status == usb_status::stall)
                link_.dev->clear_halt(link_.ep_stream);
            const std::string why =
                std::string("bulk transfer failed: ") + usb_status_name(c.status);
            if (frame_open_)
                drop(FLT_COUNT_SHORT, why);
            else {
                acc_.add(FLT_COUNT_BAD_PACKETS);
                acc_.stream_error = why;
            }
            return false;
        }
    }
    if (n >= 12 && get_u32(p) == k_magic_leader && get_u16(p + 6) <= n) {
        on_leader(p, n);
        return false;
    }
    if (n >= k_trailer_min_size && get_u32(p) == k_magic_trailer && frame_open_)
        return on_trailer(p, n, out);
    if (!frame_open_ && discarding_)
        return false;  // remains of a dropped frame
    if (!frame_open_) {
        acc_.add(FLT_COUNT_BAD_PACKETS);
        char text[160];
        std::snprintf(text, sizeof text,
                      "a %zu-byte transfer outside any frame (no leader before it) was discarded",
                      n);
        acc_.stream_error = text;
        return false;
    }
    const std::size_t split = merged_trailer_at(p, n);
    on_payload(p, split);
    if (split < n && frame_open_)
        return on_trailer(p + split, n - split, out);
    return false;
}

bool stream_channel::next(unsigned timeout_ms, raw_frame &out) {
    using clock = std::chrono::steady_clock;
    if (link_.disconnected)
        raise(FLT_ERR_DEVICE, "the camera was unplugged");
    if (!prepared_)
        raise(FLT_ERR_STATE, "the camera is not streaming; call flt_source_start()");
    const auto deadline = clock::now() + std::chrono::milliseconds(timeout_ms);
    for (;;) {
        submit_waiting();
        if (in_flight_ == 0)
            raise(FLT_ERR_DEVICE, "no bulk transfer can be submitted (on Linux, usbfs memory: "
                                  "raise /sys/module/usbcore/parameters/usbfs_memory_mb or "
                                  "lower u3v_transfers); the next call tries again");
        const auto left =
            std::chrono::duration_cast<std::chrono::milliseconds>(deadline - clock::now()).count();
        usb_completion c;
        const usb_status st = link_.dev->async_reap(unsigned(std::max<long long>(0, left)), c);
        if (st == usb_status::timeout) {
            acc_.add(FLT_COUNT_TIMEOUTS);
            char text[160];
            if (frame_open_) {
                std::snprintf(text, sizeof text,
                              "block %llu: no data for %u ms after %zu payload bytes; dropped",
                              (unsigned long long)block_id_, timeout_ms, received_);
                drop(FLT_COUNT_TIMEOUT_DROPPED, text);
            } else {
                std::snprintf(text, sizeof text, "no frame within %u ms", timeout_ms);
                acc_.stream_error = text;
            }
            throw error(FLT_ERR_TIMEOUT, text);
        }
        if (st == usb_status::no_device)
            lost_device(link_, acc_, "stream");
        if (st != usb_status::ok)
            raise(FLT_ERR_DEVICE, "waiting for the stream failed: %s", usb_status_name(st));
        --in_flight_;
        bool done = false;
        try {
            done = on_transfer(c, out);
        } catch (...) {
            waiting_[c.slot] = 1;
            throw;
        }
        // The frame buffer holds the payload now: the slot can go again.
        resubmit(c.slot);
        if (done)
            return true;
    }
}

}  // namespace flt::u3v
