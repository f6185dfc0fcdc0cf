// SPDX-License-Identifier: Apache-2.0
// The gauge's workers: the roles a thread takes (the sequencer, the
// evaluation of a finished sheet, the extraction of the oldest waiting
// frame), inline with 0 workers, and the extraction of a frame into its
// profile row, fiber flags, edges and saturation.
#include "gauge/gauge_internal.hpp"

namespace flt {

using namespace gauge_detail;

void gauge::extract(frame_slot &slot, const void *pixels, flt_pixel_format format,
                    std::size_t stride, flt_extractor *extractor, bool *error_out) const {
    const stage_timer timer(ns_extract_);
    const flt_status st = flt_extractor_process(extractor, pixels, format, width_, height_, stride,
                                                slot.encoder_mm, K_, &slot.s, slot.height.data(),
                                                slot.slope.data(), slot.valid.data());
    if (st == FLT_OK) {
        *error_out = false;
        // The strip in the frame: per fiber on or off it, its edges (the
        // profile row's: both lasers' mean) and its saturated peaks.
        const extractor_frame_view frame = extractor_frame_of(extractor);
        std::memcpy(slot.flags.data(), frame.fiber_flags, K_);
        slot.left = frame.left_mm;
        slot.right = frame.right_mm;
        slot.strip_flags = frame.strip_flags;
        slot.saturated = std::uint32_t(frame.saturated);
        slot.peaks = std::uint32_t(frame.peaks);
        return;
    }
    // A frame without the two lines while the band is automatic is a frame
    // without the strip, not an error; anything else the extractor refuses
    // is counted. Either way the row has no valid fiber.
    *error_out = st != FLT_ERR_NUMERIC;
    slot.s = slot.encoder_mm - mean_offset_;
    std::fill(slot.height.begin(), slot.height.end(), k_nan);
    std::fill(slot.slope.begin(), slot.slope.end(), k_nan);
    std::fill(slot.valid.begin(), slot.valid.end(), std::uint8_t(0));
    std::fill(slot.flags.begin(), slot.flags.end(), std::uint8_t(FLT_FLAG_INVALID_INPUT));
    slot.left = slot.right = k_nan;
    slot.strip_flags = FLT_STRIP_NONE | FLT_STRIP_LEFT_OPEN | FLT_STRIP_RIGHT_OPEN;
    slot.saturated = slot.peaks = 0;
    clear_error();
}

void gauge::resolve_band(frame_slot &slot) {
    bool error = false;
    extract(slot, slot.pixels.get(), slot.format, slot.stride, band_extractor_, &error);
    slot.extract_error = error;
    if (error) {
        std::lock_guard<std::mutex> lock(m_);
        ++n_extract_errors_;
    }
    std::uint32_t first[2], rows[2];
    for (unsigned laser = 0; laser < 2; ++laser)
        if (flt_extractor_band(band_extractor_, laser, &first[laser], &rows[laser]) != FLT_OK) {
            clear_error();  // not found yet: the next frame tries again
            return;
        }
    const flt_option first_key[2] = {FLT_OPT_EXTRACT_LASER0_FIRST_ROW,
                                     FLT_OPT_EXTRACT_LASER1_FIRST_ROW};
    const flt_option rows_key[2] = {FLT_OPT_EXTRACT_LASER0_ROWS, FLT_OPT_EXTRACT_LASER1_ROWS};
    for (unsigned laser = 0; laser < 2; ++laser) {
        set_option(*extract_options_, first_key[laser], first[laser]);
        set_option(*extract_options_, rows_key[laser], rows[laser]);
    }
    // Published to the workers by the queue's mutex with the next frame.
    for (flt_extractor *&ex : extractors_)
        check(flt_extractor_create(calib_for_extractors_, extract_options_, &ex));
    band_known_ = true;
    FLT_LOG(FLT_LOG_INFO, "gauge",
            "laser bands found: laser 0 in rows %u..%u, laser 1 in rows %u..%u; every frame is "
            "extracted with them",
            first[0], first[0] + rows[0] - 1, first[1], first[1] + rows[1] - 1);
}

// Inline (0 workers), the thread that works holds the sequencing role as
// the workers do: a frame from the acquisition thread and a cut or flush
// from another thread take turns.
void gauge::acquire_sequencer() {
    std::unique_lock<std::mutex> lock(m_);
    idle_cv_.wait(lock, [&] { return !sequencing_; });
    sequencing_ = true;
}

void gauge::release_sequencer() {
    {
        std::lock_guard<std::mutex> lock(m_);
        sequencing_ = false;
    }
    idle_cv_.notify_all();
}

void gauge::run_inline() {
    frame_slot &slot = slots_[0];
    acquire_sequencer();
    const bool ok = gauge_guarded(
        this,
        [&] {
            if (slot.state == slot_extracted)
                sequence(slot);
            run_jobs_inline();
        },
        &gauge::record_failure);
    {
        std::lock_guard<std::mutex> lock(m_);
        slot.state = slot_free;
        tail_ = head_;
    }
    release_sequencer();
    if (!ok) {
        std::lock_guard<std::mutex> lock(m_);
        throw error(failure_status_, failure_message_.c_str());
    }
}

void gauge::run_jobs_inline() {
    for (;;) {
        sheet_job job;
        {
            std::lock_guard<std::mutex> lock(m_);
            if (jobs_.empty())
                return;
            job = jobs_.front();
            jobs_.erase(jobs_.begin());
            evaluating_ = true;
        }
        evaluate(job);
        std::lock_guard<std::mutex> lock(m_);
        buffer_busy_[job.buffer] = 0;
        evaluating_ = false;
    }
}

void gauge::worker_main(unsigned index) {
    touch_thread_locals();
    std::unique_lock<std::mutex> lock(m_);
    while (!stopping_) {
        if (failed_ || !run_one(lock, index))
            work_cv_.wait(lock);
    }
}

// With the lock held: one piece of work, most urgent first. Returns false
// when there is none.
bool gauge::run_one(std::unique_lock<std::mutex> &lock, unsigned index) {
    const std::size_t Q = slots_.size();
    // 1. The sequencer: rows in frame order into the reconstructor. First,
    // because it frees queue slots and sheets wait on it.
    if (!sequencing_ && tail_ < head_ && slots_[tail_ % Q].state == slot_extracted) {
        sequencing_ = true;
        bool ok = true;
        while (ok && !failed_ && !stopping_ && tail_ < head_ &&
               slots_[tail_ % Q].state == slot_extracted) {
            frame_slot &slot = slots_[tail_ % Q];
            lock.unlock();
            ok = gauge_guarded(
                this, [&] { sequence(slot); }, &gauge::record_failure);
            lock.lock();
            slot.state = slot_free;
            ++tail_;
            room_cv_.notify_all();
        }
        sequencing_ = false;
        work_cv_.notify_all();
        idle_cv_.notify_all();
        return true;
    }
    // 2. Blocks of the sheet being evaluated (its fibers' flatness, its
    // straightedges' lines): the evaluating thread waits for them.
    if (block_task_.open && block_task_.next < block_task_.blocks) {
        work_on_blocks(lock);
        return true;
    }
    // 3. A finished sheet's flatness (the next sheet is being built).
    if (!evaluating_ && !jobs_.empty()) {
        evaluating_ = true;
        const sheet_job job = jobs_.front();
        jobs_.erase(jobs_.begin());
        lock.unlock();
        gauge_guarded(
            this, [&] { evaluate(job); }, &gauge::record_failure);
        lock.lock();
        buffer_busy_[job.buffer] = 0;
        evaluating_ = false;
        work_cv_.notify_all();
        idle_cv_.notify_all();
        return true;
    }
    // 4. Extraction, oldest frame first.
    while (claim_ < head_ && (claim_ < tail_ || slots_[claim_ % Q].state != slot_filled))
        ++claim_;
    if (claim_ < head_) {
        frame_slot &slot = slots_[claim_ % Q];
        ++claim_;
        slot.state = slot_extracting;
        lock.unlock();
        bool error = false;
        extract(slot, slot.pixels.get(), slot.format, slot.stride, extractors_[index], &error);
        slot.extract_error = error;
        lock.lock();
        slot.state = slot_extracted;
        ++n_extracted_;
        if (error)
            ++n_extract_errors_;
        work_cv_.notify_all();
        return true;
    }
    return false;
}

void gauge::run_block_task(std::size_t blocks, block_runner::block_fn fn, void *context) {
    std::unique_lock<std::mutex> lock(m_);
    block_task &t = block_task_;
    t.fn = fn;
    t.context = context;
    t.blocks = blocks;
    t.next = t.done = 0;
    t.joined = 0;
    t.error = nullptr;
    // The workers join when they are free (run_one); this thread runs
    // blocks too, so it never waits for a block nobody took.
    t.open = cfg_.workers > 0 && blocks > 1;
    if (t.open)
        work_cv_.notify_all();
    work_on_blocks(lock);
    {
        // Waiting for the blocks other threads took: their time counts on
        // their threads, so the wait leaves the evaluation's count (a
        // timer of its own, nested in the evaluation's).
        const stage_timer waiting(ns_block_wait_);
        blocks_cv_.wait(lock, [&] { return t.done == t.blocks; });
    }
    t.open = false;
    if (t.error) {
        std::exception_ptr e = t.error;
        t.error = nullptr;
        lock.unlock();
        std::rethrow_exception(e);
    }
}

void gauge::work_on_blocks(std::unique_lock<std::mutex> &lock) {
    block_task &t = block_task_;
    // At most every worker and the evaluating thread (workers + 1
    // participants, the scratch the components made): each joins once,
    // and leaves only when no block is left.
    const unsigned participant = t.joined++;
    const block_runner::block_fn fn = t.fn;
    void *const context = t.context;
    while (t.next < t.blocks) {
        const std::size_t b = t.next++;
        lock.unlock();
        std::exception_ptr error;
        try {
            // Evaluation time, on whichever thread (inside the evaluating
            // thread's own timer it counts once: stage_timer nests).
            const stage_timer timer(ns_evaluate_);
            fn(context, b, participant);
        } catch (...) {
            error = std::current_exception();  // rethrown by run_block_task
        }
        lock.lock();
        if (error && !t.error)
            t.error = error;
        if (++t.done == t.blocks)
            blocks_cv_.notify_all();
    }
}

}  // namespace flt
