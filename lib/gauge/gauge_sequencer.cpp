// SPDX-License-Identifier: Apache-2.0
// The gauge's sequencer: one thread at a time, frames in order. Strip
// presence (head, gaps, tail), the reconstructor, its finished rows into
// the open sheet's buffer, cuts ending sheets (and provisional answers);
// each finished sheet is a sheet_job for the evaluation.
#include "gauge/gauge_internal.hpp"

namespace flt {

using namespace gauge_detail;

void gauge::activate_cuts(std::uint64_t up_to_seq) {
    std::size_t ignored = 0;
    double last_ignored = 0.0;
    {
        std::lock_guard<std::mutex> lock(m_);
        while (cut_count_ > 0 && cuts_[cut_head_].seq <= up_to_seq) {
            const double c = cuts_[cut_head_].s;
            cut_head_ = (cut_head_ + 1) % k_cut_capacity;
            --cut_count_;
            if (in_strip_ && c <= sheet_start_) {
                ++n_cuts_ignored_;
                ++ignored;
                last_ignored = c;
                continue;
            }
            active_[(active_head_ + active_count_) % k_cut_capacity] = c;
            ++active_count_;
        }
    }
    log_cuts_ignored(ignored, last_ignored, "at or before the open sheet's start");
}

void gauge::log_cuts_ignored(std::size_t n, double s, const char *why) const {
    if (n > 0)
        FLT_LOG(FLT_LOG_WARNING, "gauge",
                "%zu cut%s ignored, the last at encoder %.1f mm: %s (its sheet was already "
                "finished, or no strip reached it)",
                n, n == 1 ? "" : "s", s + mean_offset_, why);
}

void gauge::drop_active_cuts(double up_to, bool all) {
    std::size_t ignored = 0;
    double last_ignored = 0.0;
    {
        std::lock_guard<std::mutex> lock(m_);
        while (active_count_ > 0 && (all || active_[active_head_] <= up_to)) {
            last_ignored = active_[active_head_];
            active_head_ = (active_head_ + 1) % k_cut_capacity;
            --active_count_;
            ++n_cuts_ignored_;
            ++ignored;
        }
    }
    log_cuts_ignored(ignored, last_ignored,
                     all ? "the strip ended (a reversal or a jump of the encoder)"
                         : "before the strip's head");
}

void gauge::sequence(frame_slot &slot) {
    const stage_timer timer(ns_sequence_);
    if (slot.new_strip) {
        // The encoder went back by more than gauge_reversal_length: what was
        // measured is finished, and cuts given in the old numbering go.
        end_strip(FLT_SHEET_FLAG_NEW_STRIP);
        drop_active_cuts(0.0, true);
    }
    activate_cuts(slot.seq);
    apply_pending(slot.seq, slot.s);
    if (recorder_ != nullptr && slot.seq >= rec_seq0_)
        record_row(slot);  // before the row is used: it becomes the recorded one
    pending_row_skipped_ += slot.skipped_before;
    pending_row_dropped_ += slot.dropped_before;
    pending_row_missing_ += slot.missing_before;
    std::uint32_t valid = 0;
    for (std::size_t k = 0; k < K_; ++k)
        valid += slot.valid[k] != 0;
    // The strip is there when enough fibers measured it and the extractor
    // found it (a frame with no run of line wide enough is no strip).
    const bool present = valid > 0 && double(valid) * pitch_ >= cfg_.strip_min_width &&
                         !(slot.strip_flags & FLT_STRIP_NONE);
    const double s = slot.s;

    if (in_strip_ && pushed_ && s - last_pushed_s_ > max_jump_) {
        // Farther than the reconstructor bridges (frames dropped, an encoder
        // that jumped): the strip so far is finished; this row may begin
        // the next one.
        end_strip(FLT_SHEET_FLAG_NEW_STRIP);
        std::lock_guard<std::mutex> lock(m_);
        ++n_reversals_;
    }
    const double prev_s = has_last_seen_ ? last_seen_s_ : s;
    has_last_seen_ = true;
    last_seen_s_ = s;
    if (!in_strip_) {
        if (!present) {
            std::lock_guard<std::mutex> lock(m_);
            ++n_no_strip_;
            pending_row_skipped_ = pending_row_dropped_ = pending_row_missing_ = 0;
            return;
        }
        begin_strip(s);
    }
    // Late cuts: a cut given after the strip passed it splits the open
    // sheet now that it is known.
    if (has_output_)
        apply_cuts(last_output_s_, nullptr);

    row_meta meta;
    meta.s = s;
    meta.prev_s = prev_s;
    meta.skipped = pending_row_skipped_;
    meta.dropped = pending_row_dropped_;
    meta.missing = pending_row_missing_;
    meta.invalid = std::uint32_t(K_ - valid);
    meta.left = slot.left;
    meta.right = slot.right;
    meta.saturated = slot.saturated;
    meta.peaks = slot.peaks;
    meta.time_ns = slot.time_ns;
    meta.measured = present;
    pending_row_skipped_ = pending_row_dropped_ = pending_row_missing_ = 0;
    if (present) {
        release_held();
        push_row(s, slot.height.data(), slot.slope.data(), slot.flags.data(), meta);
        return;
    }
    // Perhaps the tail: hold the row until the strip shows again (a gap
    // inside it) or gauge_tail_length has passed without it (the tail).
    held_s_[held_] = s;
    std::memcpy(&held_height_[held_ * K_], slot.height.data(), K_ * sizeof(double));
    std::memcpy(&held_slope_[held_ * K_], slot.slope.data(), K_ * sizeof(double));
    std::memcpy(&held_flags_[held_ * K_], slot.flags.data(), K_);
    held_meta_[held_] = meta;
    ++held_;
    if (s - held_s_[0] >= cfg_.tail_length || held_ == hold_capacity_)
        end_strip(FLT_SHEET_FLAG_TAIL);
}

void gauge::begin_strip(double s) {
    // The identity given for the next coil is this strip's; without one
    // the strip has none.
    strip_coil_ = next_coil_given_ ? std::move(next_coil_) : nullptr;
    next_coil_.reset();
    next_coil_given_ = false;
    in_strip_ = true;
    pushed_ = false;
    has_output_ = false;
    ++coil_;
    sheet_in_coil_ = 0;
    sheet_start_ = s;
    sheet_flags_ = FLT_SHEET_FLAG_HEAD;
    has_provisional_cut_ = false;
    buffers_[current_].rows = 0;
    {
        std::lock_guard<std::mutex> lock(m_);
        ++n_strips_;
    }
    FLT_LOG(FLT_LOG_INFO, "gauge", "coil %llu: the strip's head at s = %.1f mm",
            (unsigned long long)coil_, s);
    // Cuts at or before the head were for strip that never came.
    drop_active_cuts(s, false);
}

void gauge::release_held() {
    for (std::size_t i = 0; i < held_; ++i)
        push_row(held_s_[i], &held_height_[i * K_], &held_slope_[i * K_], &held_flags_[i * K_],
                 held_meta_[i]);
    held_ = 0;
}

// The reconstructor is called through its C++ side (recon_pipeline_of),
// without the public API's argument checks and status conversions: the
// sequencer keeps the API's contract itself (rows in strictly increasing s
// within a strip, bridged jumps, room in the ring; K_ fibers by
// construction), and does what flt_recon_push_flagged and flt_recon_pull
// add to the engine: a row's flags become the engine's valid mask (a sample
// without any flag is valid), and its off-strip fibers leave the
// reconstructor as NaN flagged FLT_FLAG_OFF_STRIP (mask_off_strip).
void gauge::push_row(double s, const double *height, const double *slope, const std::uint8_t *flags,
                     const row_meta &meta) {
    if (meta_count_ == row_capacity_)
        throw error(FLT_ERR_INTERNAL, "the gauge's row ring is full");
    recon_pipeline &recon = *pipeline_;
    if (!std::isfinite(s) ||
        (recon.has_last_s() && (!(s > recon.last_s()) || s - recon.last_s() > max_jump_))) {
        char why[200];
        format_c(why, sizeof why,
                 "the reconstructor's row at s = %.17g mm does not follow the last at %.17g mm "
                 "(s must increase, by at most %g mm)",
                 s, recon.has_last_s() ? recon.last_s() : k_nan, max_jump_);
        throw error(FLT_ERR_INVALID_ARGUMENT, why);
    }
    if (recon.free_rows() == 0) {
        char why[200];
        format_c(why, sizeof why,
                 "the reconstructor's row ring is full: row_capacity = %zu, %zu finished rows "
                 "wait to be pulled",
                 row_capacity_, recon.ready_rows());
        throw error(FLT_ERR_BUFFER_FULL, why);
    }
    const std::size_t at = (meta_head_ + meta_count_) % row_capacity_;
    std::uint8_t *bits = &off_strip_bits_[at * off_strip_stride_];
    std::memset(bits, 0, off_strip_stride_);
    std::uint8_t any = 0;
    for (std::size_t k = 0; k < K_; ++k) {
        push_valid_[k] = flags[k] == 0 ? 1 : 0;
        if (flags[k] & FLT_FLAG_OFF_STRIP) {
            bits[k / 8] |= std::uint8_t(1u << (k % 8));
            any = 1;
        }
    }
    off_strip_any_[at] = any;
    recon.push_row(s, height, slope, push_valid_.data());
    meta_ring_[at] = meta;
    if (cfg_.keep_maps >= 2)
        for (std::size_t k = 0; k < K_; ++k)
            measured_ring_[at * K_ + k] = flags[k] == 0 ? height[k] : k_nan;
    ++meta_count_;
    pushed_ = true;
    last_pushed_s_ = s;
    last_pushed_time_ns_ = meta.time_ns;
    pull_all();
    if (cfg_.provisional_mm > 0.0)
        publish_provisional();
}

void gauge::pull_all() {
    if (!pushed_)
        return;
    for (;;) {
        const std::size_t got =
            pipeline_->pull(k_pull_rows, pull_s_.data(), pull_z_.data(), pull_flags_.data());
        if (got == 0)
            return;
        for (std::size_t r = 0; r < got; ++r) {
            if (meta_count_ == 0 || meta_ring_[meta_head_].s != pull_s_[r])
                throw error(FLT_ERR_INTERNAL, "the reconstructor's rows and the gauge's disagree");
            const std::size_t at = meta_head_;
            mask_off_strip(at, &pull_z_[r * K_], &pull_flags_[r * K_]);
            meta_head_ = (meta_head_ + 1) % row_capacity_;
            --meta_count_;
            output_row(pull_s_[r], &pull_z_[r * K_], &pull_flags_[r * K_], meta_ring_[at],
                       cfg_.keep_maps >= 2 ? &measured_ring_[at * K_] : nullptr);
        }
    }
}

void gauge::mask_off_strip(std::size_t at, double *z, std::uint8_t *flags) const {
    if (!off_strip_any_[at])
        return;
    const std::uint8_t *bits = &off_strip_bits_[at * off_strip_stride_];
    for (std::size_t k = 0; k < K_; ++k)
        if (bits[k / 8] & (1u << (k % 8))) {
            z[k] = k_nan;
            flags[k] = FLT_FLAG_OFF_STRIP;
        }
}

void gauge::output_row(double s, const double *z, const std::uint8_t *flags, const row_meta &meta,
                       const double *measured) {
    // Cuts at or before this row end the sheet before it joins.
    apply_cuts(s, &meta);
    if (buffers_[current_].rows > 0 &&
        (s - sheet_start_ >= cfg_.max_sheet_length || buffers_[current_].rows == sheet_capacity_))
        split(s, FLT_SHEET_FLAG_SPLIT, false, &meta);
    sheet_buffer &b = buffers_[current_];
    const std::size_t r = b.rows;
    b.s[r] = s;
    std::memcpy(&b.z[r * K_], z, K_ * sizeof(double));
    std::memcpy(&b.flags[r * K_], flags, K_);
    b.meta[r] = meta;
    b.left[r] = meta.left;
    b.right[r] = meta.right;
    if (measured)
        std::memcpy(&b.measured[r * K_], measured, K_ * sizeof(double));
    ++b.rows;
    has_output_ = true;
    last_output_s_ = s;
}

void gauge::apply_cuts(double s_limit, const row_meta *incoming) {
    for (;;) {
        double c;
        bool ignored = false;
        {
            std::lock_guard<std::mutex> lock(m_);
            if (active_count_ == 0 || !(active_[active_head_] <= s_limit))
                return;
            c = active_[active_head_];
            active_head_ = (active_head_ + 1) % k_cut_capacity;
            --active_count_;
            if (c <= sheet_start_) {
                ++n_cuts_ignored_;
                ignored = true;
            }
        }
        if (ignored) {
            log_cuts_ignored(1, c, "at or before the open sheet's start");
            continue;
        }
        // An early answer that fell due but could not be made before its
        // final (the evaluator still busy with the previous one: a machine
        // too slow for the line) is said, not skipped in silence.
        if (cfg_.provisional_mm > 0.0 && !(has_provisional_cut_ && provisional_cut_ == c) &&
            last_pushed_s_ - c >= cfg_.provisional_mm)
            FLT_LOG(FLT_LOG_WARNING, "gauge",
                    "sheet %llu: no early answer: the evaluator was still busy with the "
                    "previous one until the final result at %.0f mm past the cut",
                    static_cast<unsigned long long>(sheet_ids_ + 1), last_pushed_s_ - c);
        split(c, 0, false, incoming);
    }
}

std::int64_t gauge::cut_time_ns(const sheet_buffer &b, std::size_t i, double s_at,
                                const row_meta *incoming) const {
    // The rows on either side of the cut: the last of the sheet and the
    // first after it (in the buffer, or the row arriving now).
    const row_meta *before = i > 0 ? &b.meta[i - 1] : nullptr;
    const row_meta *after = i < b.rows ? &b.meta[i] : incoming;
    if (before && after && after->s > before->s) {
        // The strip moves at a steady speed between two frames (1 mm apart
        // on a typical line): interpolate, clamped to the two frames.
        const double f = std::clamp((s_at - before->s) / (after->s - before->s), 0.0, 1.0);
        return before->time_ns + std::int64_t(f * double(after->time_ns - before->time_ns));
    }
    if (before)
        return before->time_ns;
    if (after)
        return after->time_ns;
    return last_pushed_time_ns_;  // an empty sheet: the newest frame's time
}

void gauge::copy_rows(sheet_buffer &to, std::size_t to_row, const sheet_buffer &from,
                      std::size_t from_row, std::size_t n) const {
    std::memcpy(to.s.data() + to_row, from.s.data() + from_row, n * sizeof(double));
    std::memcpy(to.z.data() + to_row * K_, from.z.data() + from_row * K_, n * K_ * sizeof(double));
    std::memcpy(to.flags.data() + to_row * K_, from.flags.data() + from_row * K_, n * K_);
    std::copy(from.meta.begin() + long(from_row), from.meta.begin() + long(from_row + n),
              to.meta.begin() + long(to_row));
    std::memcpy(to.left.data() + to_row, from.left.data() + from_row, n * sizeof(double));
    std::memcpy(to.right.data() + to_row, from.right.data() + from_row, n * sizeof(double));
    if (cfg_.keep_maps >= 2)
        std::memcpy(to.measured.data() + to_row * K_, from.measured.data() + from_row * K_,
                    n * K_ * sizeof(double));
}

gauge::sheet_job gauge::open_sheet_job(int buffer, const sheet_buffer &b, std::size_t rows,
                                       double s_end, unsigned end_flags,
                                       const row_meta *incoming) const {
    sheet_job job;
    job.buffer = buffer;
    job.rows = rows;
    job.s_start = sheet_start_;
    job.s_end = s_end;
    job.flags = sheet_flags_ | end_flags;
    job.coil = coil_;
    // The numbers of the next final sheet.
    job.index = sheet_in_coil_ + 1;
    job.id = sheet_ids_ + 1;
    job.lookahead = std::max(0.0, last_pushed_s_ - s_end);
    job.cut_time_ns = cut_time_ns(b, rows, s_end, incoming);
    // The clocks are the host's UTC (or a recording's): one set back must
    // not give a negative latency.
    job.latency_s = job.lookahead > 0.0
                        ? std::max(0.0, 1e-9 * double(last_pushed_time_ns_ - job.cut_time_ns))
                        : 0.0;
    job.coil_info = strip_coil_;
    // The row after the sheet's end: the buffer's next, or the one arriving.
    if (rows < b.rows) {
        job.has_after = true;
        job.after = b.meta[rows];
    } else if (incoming) {
        job.has_after = true;
        job.after = *incoming;
    }
    return job;
}

void gauge::split(double s_at, unsigned end_flags, bool all_rows, const row_meta *incoming) {
    sheet_buffer &old = buffers_[current_];
    const std::size_t i =
        all_rows
            ? old.rows
            : std::size_t(std::lower_bound(old.s.begin(), old.s.begin() + long(old.rows), s_at) -
                          old.s.begin());
    sheet_job job = open_sheet_job(current_, old, i, s_at, end_flags, incoming);
    ++sheet_in_coil_;
    ++sheet_ids_;
    // The notes given before s_at go with this sheet; later ones wait.
    for (auto it = open_notes_.begin(); it != open_notes_.end();) {
        if (all_rows || it->s < s_at) {
            job.notes.push_back(std::move(*it));
            it = open_notes_.erase(it);
        } else {
            ++it;
        }
    }
    const int next = free_buffer_or_wait();
    sheet_buffer &nb = buffers_[next];
    const std::size_t rest = old.rows - i;
    copy_rows(nb, 0, old, i, rest);
    nb.rows = rest;
    old.rows = i;
    {
        std::lock_guard<std::mutex> lock(m_);
        jobs_.push_back(job);
    }
    work_cv_.notify_all();
    current_ = next;
    sheet_start_ = s_at;
    sheet_flags_ = 0;
}

void gauge::publish_provisional() {
    double c = 0.0;
    {
        std::lock_guard<std::mutex> lock(m_);
        if (active_count_ == 0 || buffer_busy_[2])
            return;  // no cut ahead, or the last early answer is still being made
        c = active_[active_head_];
    }
    // Once per cut; a cut inside the open sheet (the final split has not
    // come: it would have taken the cut from the ring), passed by
    // gauge_provisional_mm of strip.
    if ((has_provisional_cut_ && c == provisional_cut_) || !(c > sheet_start_) ||
        !(last_pushed_s_ - c >= cfg_.provisional_mm))
        return;
    has_provisional_cut_ = true;
    provisional_cut_ = c;
    const sheet_buffer &cur = buffers_[current_];
    sheet_buffer &pb = buffers_[2];
    // The open sheet's final rows (all before the cut: it is not applied
    // yet), then the rows not final yet as the reconstructor estimates
    // them now (its peek changes nothing it will emit), after the finished
    // ones (none: pull_all took them), as flt_recon_peek gives them.
    const std::size_t r0 = cur.rows;
    copy_rows(pb, 0, cur, 0, r0);
    const std::size_t ready = pipeline_->ready_rows();
    const std::size_t max_rows = sheet_capacity_ - r0;
    std::size_t got = 0;
    if (max_rows > 0 && meta_count_ > ready)
        got = pipeline_->peek(ready, max_rows, pb.s.data() + r0, pb.z.data() + r0 * K_,
                              pb.flags.data() + r0 * K_);
    std::size_t rows = r0;
    bool has_after = false;
    row_meta after;
    for (std::size_t j = 0; j < got; ++j) {
        // The pending rows' metadata wait in the ring in the same order.
        const std::size_t at = (meta_head_ + ready + j) % row_capacity_;
        if (ready + j >= meta_count_ || meta_ring_[at].s != pb.s[r0 + j])
            throw error(FLT_ERR_INTERNAL,
                        "the reconstructor's pending rows and the gauge's disagree");
        mask_off_strip(at, &pb.z[(r0 + j) * K_], &pb.flags[(r0 + j) * K_]);
        if (!(pb.s[r0 + j] < c)) {
            has_after = true;
            after = meta_ring_[at];
            break;
        }
        pb.meta[rows] = meta_ring_[at];
        pb.left[rows] = meta_ring_[at].left;
        pb.right[rows] = meta_ring_[at].right;
        if (cfg_.keep_maps >= 2)
            std::memcpy(&pb.measured[rows * K_], &measured_ring_[at * K_], K_ * sizeof(double));
        ++rows;
    }
    pb.rows = rows;
    // The final sheet will have these numbers (unless the strip ends or the
    // sheet is split before the cut: then its final has other ends). The
    // lookahead is at least gauge_provisional_mm here.
    sheet_job job =
        open_sheet_job(2, pb, rows, c, FLT_SHEET_FLAG_PROVISIONAL, has_after ? &after : nullptr);
    job.provisional = true;
    for (const sheet_note &n : open_notes_)
        if (n.s < c)
            job.notes.push_back(n);  // allocates only for notes
    {
        std::lock_guard<std::mutex> lock(m_);
        buffer_busy_[2] = 1;
        jobs_.push_back(job);
    }
    work_cv_.notify_all();
}

int gauge::free_buffer_or_wait() {
    const int other = 1 - current_;
    std::unique_lock<std::mutex> lock(m_);
    for (;;) {
        if (!buffer_busy_[other]) {
            buffer_busy_[other] = 1;
            return other;
        }
        if (failed_ || stopping_)
            throw error(failed_ ? failure_status_ : FLT_ERR_STATE, "the gauge is stopping");
        if (!evaluating_ && !jobs_.empty()) {
            // Nobody evaluates the waiting sheet: do it here.
            evaluating_ = true;
            const sheet_job job = jobs_.front();
            jobs_.erase(jobs_.begin());
            lock.unlock();
            try {
                evaluate(job);
            } catch (...) {
                lock.lock();
                evaluating_ = false;
                throw;
            }
            lock.lock();
            buffer_busy_[job.buffer] = 0;
            evaluating_ = false;
            idle_cv_.notify_all();
            continue;
        }
        idle_cv_.wait(lock);
    }
}

void gauge::end_strip(unsigned flag) {
    if (!in_strip_)
        return;
    if (pushed_) {
        // The strip ends here: nothing lies beyond, so its last rows are
        // finished with what there is.
        if (!pipeline_->rows_since_sheet())
            throw error(FLT_ERR_STATE, "the reconstructor has no row to end a sheet with");
        pipeline_->end_sheet();
        pull_all();
    }
    {
        std::lock_guard<std::mutex> lock(m_);
        n_no_strip_ += held_;
    }
    held_ = 0;
    if (buffers_[current_].rows > 0) {
        const sheet_buffer &b = buffers_[current_];
        split(b.s[b.rows - 1], flag, true, nullptr);
    }
    if (pushed_)
        pipeline_->reset();
    FLT_LOG(FLT_LOG_INFO, "gauge", "coil %llu: %s at s = %.1f mm, %llu sheets",
            (unsigned long long)coil_,
            flag == FLT_SHEET_FLAG_TAIL      ? "the strip's tail"
            : flag == FLT_SHEET_FLAG_FLUSHED ? "the strip ended by a flush"
                                             : "the strip ended by a reversal or a jump",
            last_output_s_, (unsigned long long)sheet_in_coil_);
    pushed_ = false;
    in_strip_ = false;
    has_output_ = false;
    strip_coil_.reset();
    pending_row_skipped_ = pending_row_dropped_ = pending_row_missing_ = 0;
}

void gauge::apply_pending(std::uint64_t up_to_seq, double s) {
    std::lock_guard<std::mutex> lock(m_);
    while (!coils_pending_.empty() && coils_pending_.front().seq <= up_to_seq) {
        coil_entry &c = coils_pending_.front();
        if (in_strip_ && !strip_coil_) {
            strip_coil_ = std::move(c.info);  // at its head: this strip's
        } else {
            next_coil_ = std::move(c.info);
            next_coil_given_ = true;
        }
        coils_pending_.pop_front();
    }
    while (!notes_pending_.empty() && notes_pending_.front().seq <= up_to_seq) {
        sheet_note n = std::move(notes_pending_.front().note);
        n.s = s;
        notes_pending_.pop_front();
        open_notes_.push_back(std::move(n));  // allocates only for notes
    }
}

void gauge::record_row(frame_slot &slot) {
    record::row_in row;
    row.encoder_mm = slot.encoder_mm;
    row.time_ns = slot.time_ns;
    row.left_mm = slot.left;
    row.right_mm = slot.right;
    row.saturated = slot.saturated;
    row.peaks = slot.peaks;
    row.skipped_stop = slot.skipped_stop_before;
    row.skipped_reversal = slot.skipped_rev_before;
    row.dropped = slot.dropped_before;
    row.missing = slot.missing_before;
    row.row_flags = std::uint8_t((slot.new_strip ? record::k_row_new_strip : 0) |
                                 (slot.from_frame ? record::k_row_from_frame : 0) |
                                 (slot.extract_error ? record::k_row_extract_error : 0));
    row.strip_flags = std::uint8_t(slot.strip_flags);
    // The row becomes the recorded one (each laser's height quantized): the
    // gauge measures what a replay will give it.
    recorder_->add_row(row, slot.height.data(), slot.slope.data(), slot.flags.data(),
                       slot.valid.data(), slot.height.data(), slot.slope.data(), slot.flags.data());
}

}  // namespace flt
