// SPDX-License-Identifier: Apache-2.0
// The gauge's acquisition: the producer (push_frame, push_row, the
// acquisition thread), one at a time and frames in order. It skips line
// stops and reversals, counts dropped and missing frames, and fills the
// queue's frame slots the workers take.
#include "gauge/gauge_internal.hpp"

namespace flt {

using namespace gauge_detail;

void gauge::fill_slot(frame_slot &slot, const gauge_input &in) const {
    slot.encoder_mm = in.encoder_mm;
    if (in.recorded != nullptr) {
        // A recorded row: what the live gauge had for this frame, edges,
        // validity and flags included (the heights are the recorded,
        // quantized ones).
        const sources::recorded_frame &r = *in.recorded;
        const record::row_block &b = *r.block;
        slot.s = in.encoder_mm - mean_offset_;
        r.row_values(K_, slot.height.data(), slot.slope.data(), slot.flags.data(),
                     slot.valid.data());
        slot.left = b.left_mm[r.index];
        slot.right = b.right_mm[r.index];
        slot.strip_flags = b.strip_flags[r.index];
        slot.saturated = b.saturated[r.index];
        slot.peaks = b.peaks[r.index];
        return;
    }
    if (in.pixels == nullptr) {
        // A profile row: what the extractor would give for this frame.
        slot.s = in.encoder_mm - mean_offset_;
        for (std::size_t k = 0; k < K_; ++k) {
            const bool ok = (in.valid == nullptr || in.valid[k] != 0) &&
                            std::isfinite(in.height[k]) && std::isfinite(in.slope[k]);
            slot.height[k] = in.height[k];
            slot.slope[k] = in.slope[k];
            slot.valid[k] = ok ? 1 : 0;
            slot.flags[k] = ok ? 0 : std::uint8_t(FLT_FLAG_INVALID_INPUT);
        }
        // A row from the caller says nothing of the strip's edges.
        slot.left = slot.right = k_nan;
        slot.strip_flags = 0;
        slot.saturated = slot.peaks = 0;
        return;
    }
    if (cfg_.workers == 0)
        return;  // extracted straight from the caller's pixels
    // Copied row by row into a packed frame (the stride may be larger).
    const std::size_t row_bytes = std::size_t(width_) * bytes_per_pixel(in.format);
    const auto *src = static_cast<const std::uint8_t *>(in.pixels);
    for (std::uint32_t v = 0; v < height_; ++v)
        std::memcpy(slot.pixels.get() + v * row_bytes, src + v * in.stride, row_bytes);
    slot.format = in.format;
    slot.stride = row_bytes;
}

flt_status gauge::push(const char *fn, const gauge_input &in) {
    // A frame from inside the callback would wait for the thread that runs
    // the callback (its own queue, its own sequencer): refused, not hung.
    if (in_gauge_callback(this))
        return fail(FLT_ERR_STATE,
                    "%s: called from inside the gauge's callback (push frames from another "
                    "thread; flt_gauge_cut works there)",
                    fn);
    std::unique_lock<std::mutex> producer(produce_m_, std::try_to_lock);
    if (!producer.owns_lock())
        return fail(FLT_ERR_STATE,
                    "%s: another thread is pushing frames or flushing this gauge: frames come "
                    "from one thread at a time, in order (nothing was taken)",
                    fn);
    if (acquiring())
        return fail(FLT_ERR_STATE,
                    "%s: the attached source is acquiring: frames come from it "
                    "(flt_gauge_stop first)",
                    fn);
    if (flt_status st = failure(fn))
        return st;
    take(in, false);
    return FLT_OK;
}

bool gauge::backlog_full() const {
    return cfg_.sheet_backlog > 0 && pool_->out.load() >= cfg_.sheet_slots + cfg_.sheet_backlog;
}

std::uint32_t gauge::frames_missing(double advance) {
    // The pitch: the median of the last advances that were no gap. A step
    // wider than 1.5 pitches holds round(step / pitch) - 1 frames that
    // never came; it is not a pitch. Until 4 advances are known, none.
    const std::size_t n = std::min(n_advances_, k_pitch_window);
    if (n >= 4) {
        double sorted[k_pitch_window];
        std::copy(advances_, advances_ + n, sorted);
        std::nth_element(sorted, sorted + n / 2, sorted + n);
        const double pitch = sorted[n / 2];
        if (advance > 1.5 * pitch) {
            // A jump the reconstructor cannot bridge starts a new strip:
            // nothing is missing from a sheet then.
            if (advance > max_jump_)
                return 0;
            return std::uint32_t(std::min(1.0e6, std::floor(advance / pitch + 0.5) - 1.0));
        }
    }
    advances_[n_advances_ % k_pitch_window] = advance;
    ++n_advances_;
    return 0;
}

void gauge::take(const gauge_input &in, bool from_acquisition) {
    std::unique_lock<std::mutex> lock(m_);
    if (failed_)
        throw error(failure_status_, failure_message_.c_str());
    if (!from_acquisition && backlog_full()) {
        ++n_refused_;
        char why[400];
        format_c(why, sizeof why,
                 "%zu sheets wait to be read or are held (gauge_sheet_slots %zu + "
                 "gauge_sheet_backlog %zu): read them (flt_gauge_next_sheet) and free them "
                 "(flt_sheet_destroy), or set a callback; the frame was not taken, push it again",
                 pool_->out.load(), cfg_.sheet_slots, cfg_.sheet_backlog);
        throw error(FLT_ERR_BUFFER_FULL, why);
    }
    ++n_frames_;
    std::uint8_t recorded_flags = 0;
    if (in.recorded != nullptr) {
        // What the live gauge counted before this row, as it counted it:
        // frames skipped and dropped (their positions are not recorded),
        // frames missing by the encoder.
        const record::row_block &b = *in.recorded->block;
        const std::size_t i = in.recorded->index;
        const std::uint32_t stop = b.skipped_stop[i], rev = b.skipped_reversal[i];
        n_frames_ += std::uint64_t(stop) + rev + b.dropped[i];
        n_skipped_stop_ += stop;
        n_skipped_rev_ += rev;
        pending_skipped_ += stop + rev;
        pending_skipped_stop_ += stop;
        pending_skipped_rev_ += rev;
        n_dropped_ += b.dropped[i];
        pending_dropped_ += b.dropped[i];
        pending_missing_ += b.missing[i];
        recorded_flags = b.row_flags[i];
    }
    // Line stops and reversals, from the encoder alone (in frame order).
    const double e = in.encoder_mm;
    if (has_furthest_) {
        const double advance = e - furthest_;
        if (advance < cfg_.frame_spacing) {
            if (-advance <= cfg_.reversal_length) {
                const bool reversal = advance < -cfg_.frame_spacing;
                ++(reversal ? n_skipped_rev_ : n_skipped_stop_);
                ++(reversal ? pending_skipped_rev_ : pending_skipped_stop_);
                ++pending_skipped_;
                return;
            }
            // A long reversal: a new strip, and the cuts' order starts again.
            pending_new_strip_ = true;
            ++n_reversals_;
            has_cut_floor_ = false;
        }
    }
    // (A recorded row carries the missing frames the live gauge counted.)
    if (has_furthest_ && !pending_new_strip_ && in.recorded == nullptr)
        pending_missing_ += frames_missing(e - furthest_);
    has_furthest_ = true;
    furthest_ = e;
    // A full queue (or, for an attached source, a full sheet backlog): the
    // frame waits for room, or is dropped where the caller chose it or a
    // camera cannot wait.
    const bool drop =
        cfg_.overflow == FLT_GAUGE_OVERFLOW_DROP ||
        (cfg_.overflow == FLT_GAUGE_OVERFLOW_AUTO && from_acquisition && source_live_);
    for (;;) {
        const bool queue_full = head_ - tail_ >= slots_.size();
        const bool sheets_full = from_acquisition && backlog_full();
        if (!queue_full && !sheets_full)
            break;
        if (drop) {
            ++n_dropped_;
            ++pending_dropped_;
            const unsigned long long dropped = n_dropped_;
            lock.unlock();
            FLT_LOG(FLT_LOG_WARNING, "gauge",
                    "frame at encoder %.1f mm dropped: %s (gauge_overflow drops; %llu dropped so "
                    "far)",
                    e, queue_full ? "the frame queue is full" : "gauge_sheet_backlog is reached",
                    dropped);
            return;
        }
        if (queue_full)
            room_cv_.wait(lock);
        else  // sheets are freed by the caller, who tells nobody: look again
            room_cv_.wait_for(lock, std::chrono::milliseconds(10));
        if (failed_)
            throw error(failure_status_, failure_message_.c_str());
        if (stopping_ || (from_acquisition && acquisition_stop_))
            return;
    }
    frame_slot &slot = slots_[head_ % slots_.size()];
    slot.seq = head_;
    slot.new_strip = pending_new_strip_;
    slot.skipped_before = pending_skipped_;
    slot.dropped_before = pending_dropped_;
    slot.missing_before = pending_missing_;
    slot.skipped_stop_before = pending_skipped_stop_;
    slot.skipped_rev_before = pending_skipped_rev_;
    slot.time_ns =
        in.recorded ? in.recorded->block->time_ns[in.recorded->index] : record::utc_now_ns();
    slot.from_frame = in.pixels != nullptr || (recorded_flags & record::k_row_from_frame);
    slot.extract_error = (recorded_flags & record::k_row_extract_error) != 0;
    pending_new_strip_ = false;
    pending_skipped_ = pending_dropped_ = pending_missing_ = 0;
    pending_skipped_stop_ = pending_skipped_rev_ = 0;
    record::recorder *const rec = recorder_;
    const std::int64_t row = recorded_row(slot.seq);
    if (in.recorded != nullptr) {
        if (slot.from_frame)
            ++n_extracted_;
        if (slot.extract_error)
            ++n_extract_errors_;
    }
    lock.unlock();

    // The camera frame, when the recorder keeps frames (copied there).
    if (rec && in.pixels != nullptr && rec->wants_frames() && row >= 0)
        rec->add_frame(in.pixels, in.format, width_, height_, in.stride, e, std::uint64_t(row));
    fill_slot(slot, in);
    bool ready = in.pixels == nullptr, extract_error = false;
    if (!ready && cfg_.workers == 0) {
        extract(slot, in.pixels, in.format, in.stride, extractors_[0], &extract_error);
        slot.extract_error = extract_error;
        ready = true;
    } else if (!ready && !band_known_) {
        resolve_band(slot);
        ready = true;
    }

    lock.lock();
    if (in.pixels != nullptr && ready)
        ++n_extracted_;
    if (extract_error)
        ++n_extract_errors_;
    slot.state = ready ? slot_extracted : slot_filled;
    ++head_;
    queue_high_ = std::max(queue_high_, head_ - tail_);
    if (cfg_.workers > 0) {
        work_cv_.notify_all();
        return;
    }
    // Inline: this thread is the whole gauge.
    lock.unlock();
    run_inline();
}

void gauge::acquisition_main() {
    flt_status status = FLT_OK;
    std::string message;
    // Runs a step of taking a frame; a step that throws ends the
    // acquisition, its status and message kept for flt_gauge_stop.
    const auto stops_on_failure = [&](auto &&step) {
        try {
            step();
            return true;
        } catch (const error &e) {
            status = e.status;
            message = e.what();
        } catch (const std::exception &e) {
            status = FLT_ERR_INTERNAL;
            message = e.what();
        }
        return false;
    };
    for (;;) {
        {
            std::lock_guard<std::mutex> lock(m_);
            if (acquisition_stop_)
                break;
        }
        const flt_frame *frame = nullptr;
        flt_status st = flt_source_next(source_, 50, &frame);
        if (st == FLT_ERR_TIMEOUT)
            continue;
        if (st != FLT_OK) {
            status = st;
            message = flt_last_error_message();
            break;
        }
        if (frame == nullptr)
            break;  // the end of an image sequence
        const sources::recorded_frame *recorded = frame->recorded;
        if (recorded != nullptr) {
            // A recording: its events before the row, then the row with what
            // the live gauge knew of it (its pixels, if kept, are not
            // extracted again: the recorded row is the measurement).
            const bool taken = stops_on_failure([&] {
                if (recorded->has_row && recorded->block->fibers != K_)
                    throw error(FLT_ERR_INVALID_ARGUMENT,
                                "the recording's rows have another fiber count than the "
                                "gauge's calibration (flt_recording_calib gives its own)");
                replay_events(*recorded);
                if (recorded->has_row) {
                    gauge_input in;
                    in.recorded = recorded;
                    in.encoder_mm = frame->encoder_mm;
                    if (flt_status cst = check_encoder("flt_gauge_start (replay)", in.encoder_mm))
                        throw error(cst, flt_last_error_message());
                    take(in, true);
                }
            });
            if (!taken)
                break;
            continue;
        }
        gauge_input in;
        std::uint32_t w = 0, h = 0;
        st = flt_frame_info(frame, &in.pixels, &w, &h, &in.stride, &in.format, nullptr, nullptr,
                            &in.encoder_mm);
        if (st == FLT_OK)
            st = check_frame("flt_gauge_start (acquisition)", in.pixels, enum_arg(in.format), w, h,
                             in.stride, in.encoder_mm);
        if (st != FLT_OK) {
            status = st;
            message = flt_last_error_message();
            break;
        }
        if (!stops_on_failure([&] { take(in, true); }))
            break;
    }
    std::lock_guard<std::mutex> lock(m_);
    acquisition_status_ = status;
    acquisition_message_ = message;
    acquiring_ = false;
    idle_cv_.notify_all();
}

void gauge::flush_from_producer() {
    // A flush recorded in a recording: as flt_gauge_flush, from the
    // acquisition thread (the producer) while it acquires.
    std::unique_lock<std::mutex> lock(m_);
    if (recorder_ != nullptr)
        recorder_->add_flush(std::max<std::int64_t>(0, recorded_row(head_)));
    idle_cv_.wait(lock, [&] { return failed_ || stopping_ || (tail_ == head_ && !sequencing_); });
    if (failed_)
        throw error(failure_status_, failure_message_.c_str());
    if (stopping_)
        return;
    const bool ok = end_strip_flushed(lock);
    idle_cv_.notify_all();
    if (!ok)
        throw error(failure_status_, failure_message_.c_str());
}

void gauge::replay_events(const sources::recorded_frame &r) {
    for (std::size_t i = 0; i < r.event_count; ++i) {
        const record::recorded_event &e = r.events[i];
        switch (e.kind) {
            case record::recorded_event::cut:
                if (cut("flt_gauge_start (replay)", e.encoder_mm) != FLT_OK) {
                    FLT_LOG(FLT_LOG_WARNING, "gauge", "a recorded cut is refused: %s",
                            flt_last_error_message());
                    clear_error();
                }
                break;
            case record::recorded_event::coil:
                if (set_coil("flt_gauge_start (replay)", e.coil_info.get()) != FLT_OK)
                    throw error(flt_last_error_status(), flt_last_error_message());
                break;
            case record::recorded_event::note:
                if (note("flt_gauge_start (replay)", e.label.c_str(), e.text.c_str()) != FLT_OK)
                    throw error(flt_last_error_status(), flt_last_error_message());
                break;
            case record::recorded_event::flush:
                flush_from_producer();
                break;
            case record::recorded_event::gap:
                FLT_LOG(FLT_LOG_WARNING, "gauge",
                        "the recording lost %llu rows before this one (its writer was behind): the "
                        "replay sees the gap the encoder shows",
                        (unsigned long long)e.count);
                break;
            default:
                break;
        }
    }
}

}  // namespace flt
