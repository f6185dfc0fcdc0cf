// SPDX-License-Identifier: Apache-2.0
// The gauge: made and destroyed, and the calls that steer it (cuts, flush,
// start and stop, sheets out, coils, notes, the record). The stages are
// their own files (gauge_internal.hpp lists them); lib/gauge/README.md has
// the picture.
#include "gauge/gauge_internal.hpp"

namespace flt {

using namespace gauge_detail;

bool in_gauge_callback(const gauge *g) {
    return t_in_callback == g;
}

sheet_pool::~sheet_pool() {
    for (flt_sheet *s : free)
        delete s;
}

void sheet_pool::give_back(flt_sheet *sheet) {
    sheet->magic = 0;
    sheet->borrowed = false;
    out.fetch_sub(1);
    if (!sheet->grown) {
        std::lock_guard<std::mutex> lock(m);
        if (alive) {
            free.push_back(sheet);  // capacity reserved: no allocation
            return;
        }
    }
    delete sheet;  // made beyond the slots, or the gauge is gone
}

gauge::gauge(const flt_calib *calib, const flt_options *options) {
    // A part that refuses its options throws half way: free what was made
    // (the destructor does not run for an object whose constructor threw).
    try {
        init(calib, options);
    } catch (...) {
        {
            std::lock_guard<std::mutex> lock(m_);
            stopping_ = true;  // a thread that did start (a later one failed)
        }
        work_cv_.notify_all();
        for (std::thread &t : workers_)
            t.join();
        release_parts();
        throw;
    }
}

void gauge::init(const flt_calib *calib, const flt_options *options) {
    effective_ = options ? *options : default_options();
    flt_options &eff = effective_;
    cfg_.workers = unsigned(option_value(&eff, FLT_OPT_GAUGE_WORKERS));
    cfg_.queue_frames = std::size_t(option_value(&eff, FLT_OPT_GAUGE_QUEUE_FRAMES));
    cfg_.overflow = int(option_value(&eff, FLT_OPT_GAUGE_OVERFLOW));
    cfg_.min_coverage = option_value(&eff, FLT_OPT_GAUGE_MIN_COVERAGE);
    cfg_.sheet_backlog = std::size_t(option_value(&eff, FLT_OPT_GAUGE_SHEET_BACKLOG));
    cfg_.saturation_limit = option_value(&eff, FLT_OPT_GAUGE_SATURATION_LIMIT);
    cfg_.frame_spacing = option_value(&eff, FLT_OPT_GAUGE_FRAME_SPACING);
    cfg_.reversal_length = option_value(&eff, FLT_OPT_GAUGE_REVERSAL_LENGTH);
    cfg_.strip_min_width = option_value(&eff, FLT_OPT_GAUGE_STRIP_MIN_WIDTH);
    cfg_.tail_length = option_value(&eff, FLT_OPT_GAUGE_TAIL_LENGTH);
    cfg_.max_sheet_length = option_value(&eff, FLT_OPT_GAUGE_MAX_SHEET_LENGTH);
    cfg_.keep_maps = int(option_value(&eff, FLT_OPT_GAUGE_KEEP_MAPS));
    cfg_.sheet_slots = std::size_t(option_value(&eff, FLT_OPT_GAUGE_SHEET_SLOTS));
    cfg_.provisional_mm = option_value(&eff, FLT_OPT_GAUGE_PROVISIONAL_MM);

    // Geometry: the calibration's, never a default.
    check(flt_calib_get_frame_size(calib, &width_, &height_));
    if (cfg_.queue_frames == 0) {
        // Automatic: the frames whose slots fit in k_queue_bytes. A
        // finished sheet's evaluation holds a worker for a tenth of a
        // second or more, and meanwhile a camera's frames queue up: on
        // bench_gauge's line (2048 x 256 frames, 2000 frames/s, a sheet
        // every 1.5 s) 64 slots dropped 2 % of the frames in bursts after
        // each sheet, 128 slots 0.04 %, 256 none.
        const double slot = double(width_) * double(height_) * 2.0;
        const double frames = std::floor(double(k_queue_bytes) / slot);
        cfg_.queue_frames =
            std::size_t(std::min(std::max(frames, double(k_queue_min)), double(k_queue_max)));
        set_option(eff, FLT_OPT_GAUGE_QUEUE_FRAMES, double(cfg_.queue_frames));
    }
    double offset[2];
    for (unsigned laser = 0; laser < 2; ++laser)
        check(flt_calib_get_laser_offset(calib, laser, &offset[laser]));
    mean_offset_ = 0.5 * (offset[0] + offset[1]);
    check(flt_calib_get_fiber_grid(calib, &first_x_, &pitch_, &K_));
    fiber_x_.resize(K_);
    for (std::size_t k = 0; k < K_; ++k)
        fiber_x_[k] = first_x_ + double(k) * pitch_;

    // The reconstructor (its fibers and laser spacing from the calibration)
    // must hold every row until it is finished: its latency in rows at the
    // closest frame spacing the gauge takes. Its configuration tells the
    // latency (it does not depend on the capacity), read with the checks
    // and messages of flt_recon_create_from_calib, which makes it below.
    flt_options recon_options = component_options(options, 100);
    long latency = 0;
    {
        const char *recon_fn = "flt_recon_create_from_calib";
        double spacing = 0.0;
        check(recon_calib_laser_spacing(recon_fn, calib, &recon_options, &spacing));
        recon_config config;
        check(recon_read_config(recon_fn, &recon_options, spacing, &config));
        latency = recon_latency_knots(config);
        const double knot = config.params.knot_spacing;
        // A quarter more than the latency (rows arrive unevenly), the rows of
        // one emission group, and a fixed margin.
        const double needed =
            std::ceil(1.25 * double(latency + 4) * knot / cfg_.frame_spacing) + 256.0;
        const double given = option_value(&recon_options, FLT_OPT_ROW_CAPACITY);
        if (needed > 1.0e8)
            throw error(FLT_ERR_INVALID_ARGUMENT,
                        "the reconstructor would have to hold more than 1e8 rows (its latency "
                        "at gauge_frame_spacing); raise gauge_frame_spacing or shorten the lag");
        set_option(recon_options, FLT_OPT_ROW_CAPACITY, std::max(given, needed));
        set_option(eff, FLT_OPT_ROW_CAPACITY, std::max(given, needed));
        set_option(eff, FLT_OPT_LASER_SPACING, spacing);
        max_jump_ = std::min(k_recon_max_jump_mm, k_recon_max_jump_knots * knot);
    }
    row_capacity_ = std::size_t(option_value(&eff, FLT_OPT_ROW_CAPACITY));
    // A tail longer than the reconstructor can bridge would never be seen.
    cfg_.tail_length = std::min(cfg_.tail_length, 0.5 * max_jump_);

    // Buffers in rows: every taken frame is at least frame_spacing past the
    // one before, so a stretch of L mm holds at most L / spacing + 1 rows.
    const double sheet_rows = std::ceil(cfg_.max_sheet_length / cfg_.frame_spacing) + 2.0;
    // What the buffers will take, before anything is allocated: an absurd
    // configuration (micrometre frames, kilometre sheets) is refused with
    // its cost instead of exhausting the machine.
    {
        // The gauge's own buffers by gauge.h's "Memory" formula (the
        // reconstructor and the flatness metrics refuse on their own).
        const double K = double(K_), rows = double(row_capacity_);
        const double slots = cfg_.keep_maps >= 1 ? double(cfg_.sheet_slots) : 0.0;
        const double buffers = cfg_.provisional_mm > 0.0 ? 3.0 : 2.0;
        double bytes = (65.0 + K / 8.0) * rows;            // the row ring, off-strip bits
        bytes += buffers * sheet_rows * (88.0 + 9.0 * K);  // the sheet buffers
        bytes += slots * sheet_rows * (8.0 + 9.0 * K);     // the slots' maps
        if (cfg_.keep_maps >= 2)
            bytes += 8.0 * K * (rows + buffers * sheet_rows + slots * sheet_rows);
        if (cfg_.workers > 0)
            bytes += double(cfg_.queue_frames) * double(width_) * double(height_) * 2.0;
        constexpr double limit = 8.0 * 1024 * 1024 * 1024;
        if (bytes > limit) {
            char why[400];
            format_c(why, sizeof why,
                     "the gauge's buffers would take %.1f GB (more than 8 GiB): the "
                     "reconstructor holds %zu rows (its latency at gauge_frame_spacing = "
                     "%g mm), a sheet %.0f rows (gauge_max_sheet_length / "
                     "gauge_frame_spacing); raise gauge_frame_spacing or lower "
                     "gauge_max_sheet_length, gauge_sheet_slots, gauge_keep_maps or "
                     "gauge_queue_frames",
                     bytes / 1.0e9, row_capacity_, cfg_.frame_spacing, sheet_rows);
            throw error(FLT_ERR_INVALID_ARGUMENT, why);
        }
    }
    sheet_capacity_ = std::size_t(sheet_rows);
    hold_capacity_ = std::size_t(std::ceil(cfg_.tail_length / cfg_.frame_spacing)) + 2;
    check(flt_recon_create_from_calib(calib, &recon_options, &recon_));
    pipeline_ = &recon_pipeline_of(recon_);
    if (recon_latency_knots(recon_) != latency)
        throw error(FLT_ERR_INTERNAL, "the reconstructor's latency is not the one its "
                                      "configuration gave: its buffers are sized wrong");

    // Flatness: one window per sheet. flat_ evaluates whole sheets from the
    // gauge's buffer; flat_short_ the sheets shorter than one wave (streamed
    // push + finish, which reports them flagged where evaluate refuses).
    min_length_ = option_value(&eff, FLT_OPT_FLAT_MIN_LENGTH);
    {
        flt_options fo = component_options(options, 500);
        set_option(fo, FLT_OPT_FLAT_WINDOW_LENGTH, 0.0);
        set_option(fo, FLT_OPT_FLAT_UPDATE_INTERVAL, 0.0);
        set_option(fo, FLT_OPT_FLAT_ROW_CAPACITY, 16.0);
        check(flt_flatness_create(K_, fiber_x_.data(), &fo, &flat_));
        // A sheet's fibers are evaluated in blocks on the workers.
        flatness_use_runner(flat_, &blocks_);
        set_option(fo, FLT_OPT_FLAT_ROW_CAPACITY,
                   std::max(16.0, std::ceil(min_length_ / cfg_.frame_spacing) + 2.0));
        check(flt_flatness_create(K_, fiber_x_.data(), &fo, &flat_short_));
        check(flt_flatness_zones(flat_, &zones_));
        zone_x_.resize(zones_);
        check(flt_flatness_zone_layout(flat_, zones_, nullptr, zone_x_.data(), nullptr));
        set_option(eff, FLT_OPT_FLAT_WINDOW_LENGTH, 0.0);
        set_option(eff, FLT_OPT_FLAT_UPDATE_INTERVAL, 0.0);
        set_option(eff, FLT_OPT_FLAT_ROW_CAPACITY, double(sheet_capacity_));
    }

    // Extractors: one per worker. With automatic bands the producer finds
    // the band on the first frames (band_extractor_), and the workers'
    // extractors are made with it then, so every frame is extracted with
    // the same band whichever thread takes it.
    {
        flt_options *xo = nullptr;
        check(flt_options_create(&xo));
        *xo = component_options(options, 400);
        extract_options_ = xo;
    }
    const bool automatic = option_value(&eff, FLT_OPT_EXTRACT_LASER0_ROWS) == 0.0 &&
                           option_value(&eff, FLT_OPT_EXTRACT_LASER1_ROWS) == 0.0;
    const std::size_t n_extractors = std::max<std::size_t>(1, cfg_.workers);
    extractors_.assign(n_extractors, nullptr);
    if (cfg_.workers == 0 || !automatic) {
        // Inline, one extractor finds its own band; explicit bands need no
        // finding.
        for (flt_extractor *&ex : extractors_)
            check(flt_extractor_create(calib, extract_options_, &ex));
        band_known_ = true;
    } else {
        check(flt_extractor_create(calib, extract_options_, &band_extractor_));
    }
    // Kept (copied) for the workers' extractors made at the first frame.
    calib_for_extractors_ = copy_calib(calib);

    // The queue: inline, one slot for the row; else queue_frames slots with
    // room for the largest pixels (2 bytes).
    const std::size_t n_slots = cfg_.workers == 0 ? 1 : cfg_.queue_frames;
    slots_.resize(n_slots);
    // Each slot's pages are touched here, once: a page's first write faults
    // (the kernel maps and zeroes it), and on the first pass through an
    // untouched queue that made each push of a 2048 x 256 frame fault 128
    // times. On bench_gauge's line (2000 frames/s by the clock) the pushes
    // fell a quarter of a second behind in the first 600 frames and 188-256
    // frames were dropped at the full queue while the workers idled;
    // touched at create, none.
    for (frame_slot &slot : slots_) {
        if (cfg_.workers > 0) {
            const std::size_t bytes = std::size_t(width_) * height_ * 2;
            slot.pixels.reset(new std::uint8_t[bytes]);
            std::memset(slot.pixels.get(), 0, bytes);
        }
        slot.height.assign(K_, 0.0);
        slot.slope.assign(K_, 0.0);
        slot.valid.assign(K_, 0);
        slot.flags.assign(K_, 0);
    }

    // Sequencer state.
    meta_ring_.resize(row_capacity_);
    if (cfg_.keep_maps >= 2)
        measured_ring_.assign(row_capacity_ * K_, 0.0);
    off_strip_stride_ = (K_ + 7) / 8;
    off_strip_bits_.assign(row_capacity_ * off_strip_stride_, 0);
    off_strip_any_.assign(row_capacity_, 0);
    push_valid_.assign(K_, 0);
    held_s_.assign(hold_capacity_, 0.0);
    held_height_.assign(hold_capacity_ * K_, 0.0);
    held_slope_.assign(hold_capacity_ * K_, 0.0);
    held_flags_.assign(hold_capacity_ * K_, 0);
    held_meta_.resize(hold_capacity_);
    pull_s_.assign(k_pull_rows, 0.0);
    pull_z_.assign(k_pull_rows * K_, 0.0);
    pull_flags_.assign(k_pull_rows * K_, 0);
    for (int i = 0; i < (cfg_.provisional_mm > 0.0 ? 3 : 2); ++i) {
        sheet_buffer &b = buffers_[i];
        b.s.assign(sheet_capacity_, 0.0);
        b.z.assign(sheet_capacity_ * K_, 0.0);
        b.flags.assign(sheet_capacity_ * K_, 0);
        b.meta.resize(sheet_capacity_);
        b.left.assign(sheet_capacity_, 0.0);
        b.right.assign(sheet_capacity_, 0.0);
        if (cfg_.keep_maps >= 2)
            b.measured.assign(sheet_capacity_ * K_, 0.0);
    }
    buffer_busy_[0] = 1;  // the first sheet fills buffer 0
    current_ = 0;

    // Sheet slots.
    pool_ = std::make_shared<sheet_pool>();
    {
        // The session names this gauge's sheets and coils in an archive:
        // random, so that two gauges (two lines, or a restart) never share
        // one.
        std::random_device entropy;
        char session[40];
        std::snprintf(session, sizeof session, "%08x%08x-%llx", unsigned(entropy()),
                      unsigned(entropy()),
                      static_cast<unsigned long long>(record::utc_now_ns() / 1000000000));
        pool_->session = session;
    }
    pool_->free.reserve(cfg_.sheet_slots);
    ready_.assign(cfg_.sheet_slots, nullptr);
    for (std::size_t i = 0; i < cfg_.sheet_slots; ++i) {
        auto *sh = new flt_sheet;
        pool_->free.push_back(sh);
        sh->pool = pool_;
        sh->slot = i;
        sh->fibers = K_;
        sh->maps = cfg_.keep_maps;
        for (int a = 0; a < k_sheet_arrays; ++a)
            sh->array[a].assign(is_fiber_array(a) ? K_ : zones_, 0.0);
        if (cfg_.keep_maps >= 1) {
            sh->map_s.assign(sheet_capacity_, 0.0);
            sh->map_z.assign(sheet_capacity_ * K_, 0.0);
            sh->map_flags.assign(sheet_capacity_ * K_, 0);
        }
        if (cfg_.keep_maps >= 2)
            sh->map_measured.assign(sheet_capacity_ * K_, 0.0);
    }
    jobs_.reserve(4);

    first_use_of_sync_objects();
    for (unsigned i = 0; i < cfg_.workers; ++i)
        workers_.emplace_back([this, i] { worker_main(i); });
}

// Some threading runtimes make their objects on first use: MinGW-w64's
// winpthreads (under std::mutex and std::condition_variable on Windows)
// allocates a mutex's and a condition variable's kernel object at its
// first lock or wait, and MinGW's emulated thread-local storage allocates
// a thread's copy of a thread_local at its first access. Done here, and by
// each worker when it starts, instead of in the first frames' path, which
// allocates nothing (test_gauge_alloc). On Linux this costs a few
// uncontended locks.
void gauge::first_use_of_sync_objects() {
    touch_thread_locals();
    { std::lock_guard<std::mutex> lock(pool_->m); }
    { std::lock_guard<std::mutex> lock(deliver_m_); }
    { std::lock_guard<std::mutex> lock(rules_m_); }
    { std::lock_guard<std::mutex> lock(stats_m_); }
    std::unique_lock<std::mutex> lock(m_);
    // A wait that times out at once (a wait, not a notify, makes the
    // runtime's object).
    for (std::condition_variable *cv : {&work_cv_, &room_cv_, &idle_cv_, &sheet_cv_, &blocks_cv_})
        cv->wait_for(lock, std::chrono::nanoseconds(0));
}

void gauge::touch_thread_locals() {
    const void *volatile callback = t_in_callback;  // volatile: the read is kept
    (void)callback;
    (void)flt_last_error_message();  // the thread's error state (core/error.cpp)
    stage_timer::touch();
}

gauge::~gauge() {
    if (recorder_handle_)
        recorder_->owner.store(nullptr);
    if (archive_handle_)
        archive_->owner.store(nullptr);
    {
        std::unique_lock<std::mutex> lock(m_);
        acquisition_stop_ = true;
        stopping_ = true;
    }
    room_cv_.notify_all();
    work_cv_.notify_all();
    idle_cv_.notify_all();
    if (acquisition_.joinable())
        acquisition_.join();
    for (std::thread &t : workers_)
        t.join();
    if (source_ && source_started_ && flt_source_stop(source_) != FLT_OK)
        clear_error();
    release_parts();
    // Waiting sheets belong to the gauge; held ones to the caller, who
    // frees them later (the pool then deletes instead of keeping them).
    for (std::size_t i = 0; i < ready_count_; ++i)
        delete ready_[(ready_head_ + i) % ready_.size()];
    std::vector<flt_sheet *> free;
    {
        std::lock_guard<std::mutex> lock(pool_->m);
        pool_->alive = false;
        free.swap(pool_->free);
    }
    for (flt_sheet *s : free)
        delete s;
}

void gauge::release_parts() noexcept {
    for (flt_extractor *&ex : extractors_) {
        flt_extractor_destroy(ex);
        ex = nullptr;
    }
    flt_extractor_destroy(band_extractor_);
    flt_calib_destroy(calib_for_extractors_);
    flt_options_destroy(extract_options_);
    flt_recon_destroy(recon_);
    pipeline_ = nullptr;
    flt_flatness_destroy(flat_);
    flt_flatness_destroy(flat_short_);
    band_extractor_ = nullptr;
    calib_for_extractors_ = nullptr;
    extract_options_ = nullptr;
    recon_ = nullptr;
    flat_ = flat_short_ = nullptr;
}

void gauge::record_failure(flt_status status, const char *message) {
    bool first = false;
    {
        std::lock_guard<std::mutex> lock(m_);
        if (!failed_) {
            failed_ = true;
            first = true;
            failure_status_ = status;
            failure_message_ = message;
        }
        work_cv_.notify_all();
        room_cv_.notify_all();
        idle_cv_.notify_all();
        sheet_cv_.notify_all();
    }
    if (first)
        FLT_LOG(FLT_LOG_ERROR, "gauge", "the gauge stopped processing (%s): %s",
                flt_status_string(status), message);
}

flt_status gauge::failure(const char *fn) const {
    std::lock_guard<std::mutex> lock(m_);
    if (!failed_)
        return FLT_OK;
    return fail(failure_status_, "%s: the gauge stopped processing: %s", fn,
                failure_message_.c_str());
}

flt_status gauge::cut(const char *fn, double encoder_mm) {
    const double c = encoder_mm - mean_offset_;
    {
        std::lock_guard<std::mutex> lock(m_);
        if (failed_)
            return fail(failure_status_, "%s: the gauge stopped processing: %s", fn,
                        failure_message_.c_str());
        if (has_cut_floor_ && !(c > cut_floor_))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'encoder_mm' = %.17g does not follow the previous cut at "
                        "%.17g mm: cuts are given in increasing order (after an encoder reset, "
                        "push the first frame of the new numbering first)",
                        fn, encoder_mm, cut_floor_ + mean_offset_);
        if (cut_count_ + active_count_ >= k_cut_capacity)
            return fail(FLT_ERR_BUFFER_FULL,
                        "%s: %zu cuts wait for the strip to reach them; the strip has not "
                        "come that far (check the cut positions against the encoder)",
                        fn, cut_count_ + active_count_);
        cuts_[(cut_head_ + cut_count_) % k_cut_capacity] = cut_entry{head_, c};
        if (recorder_ != nullptr)
            recorder_->add_cut(encoder_mm, std::max<std::int64_t>(0, recorded_row(head_)));
        ++cut_count_;
        has_cut_floor_ = true;
        cut_floor_ = c;
        ++n_cuts_;
    }
    if (cfg_.workers == 0 && !in_gauge_callback(this)) {
        // Inline: a late cut splits its sheet now (from inside the
        // callback, which holds the role, with the next frame).
        acquire_sequencer();
        const bool ok = gauge_guarded(
            this,
            [&] {
                if (in_strip_) {
                    // The cuts due before the next frame (an acquisition
                    // thread may have queued one that is not sequenced yet:
                    // its cuts wait for it, as with workers).
                    std::uint64_t next;
                    {
                        std::lock_guard<std::mutex> lock(m_);
                        next = tail_;
                    }
                    activate_cuts(next);
                    if (has_output_)
                        apply_cuts(last_output_s_, nullptr);
                    run_jobs_inline();
                }
            },
            &gauge::record_failure);
        release_sequencer();
        if (!ok)
            return failure(fn);
    }
    return FLT_OK;
}

bool gauge::end_strip_flushed(std::unique_lock<std::mutex> &lock) {
    sequencing_ = true;
    lock.unlock();
    const bool ok = gauge_guarded(
        this,
        [&] {
            activate_cuts(std::numeric_limits<std::uint64_t>::max());
            end_strip(FLT_SHEET_FLAG_FLUSHED);
            if (cfg_.workers == 0)
                run_jobs_inline();
        },
        &gauge::record_failure);
    lock.lock();
    sequencing_ = false;
    work_cv_.notify_all();
    return ok;
}

flt_status gauge::flush(const char *fn) {
    if (in_gauge_callback(this))
        return fail(FLT_ERR_STATE, "%s: called from inside the gauge's callback", fn);
    // The end of the input: after the frame another thread is pushing.
    const std::lock_guard<std::mutex> producer(produce_m_);
    if (flt_status st = failure(fn))
        return st;
    std::unique_lock<std::mutex> lock(m_);
    if (acquiring_)
        return fail(FLT_ERR_STATE,
                    "%s: the attached source is acquiring; call flt_gauge_stop first", fn);
    if (recorder_ != nullptr)
        recorder_->add_flush(std::max<std::int64_t>(0, recorded_row(head_)));
    // Every frame pushed so far through the sequencer, then this thread
    // takes the sequencing role to end the strip.
    idle_cv_.wait(lock, [&] { return failed_ || (tail_ == head_ && !sequencing_); });
    if (failed_) {
        lock.unlock();
        return failure(fn);
    }
    const bool ok = end_strip_flushed(lock);
    if (!ok) {
        lock.unlock();
        return failure(fn);
    }
    idle_cv_.wait(lock, [&] { return failed_ || (jobs_.empty() && !evaluating_); });
    lock.unlock();
    return failure(fn);
}

flt_status gauge::attach(const char *fn, flt_source *source) {
    if (in_gauge_callback(this))
        return fail(FLT_ERR_STATE, "%s: called from inside the gauge's callback", fn);
    std::lock_guard<std::mutex> lock(m_);
    if (acquiring_)
        return fail(FLT_ERR_STATE, "%s: the gauge is acquiring; call flt_gauge_stop first", fn);
    if (acquisition_.joinable())
        return fail(FLT_ERR_STATE,
                    "%s: the acquisition ended by itself; call flt_gauge_stop first (it says why)",
                    fn);
    source_ = source;
    return FLT_OK;
}

flt_status gauge::start(const char *fn) {
    if (in_gauge_callback(this))
        return fail(FLT_ERR_STATE, "%s: called from inside the gauge's callback", fn);
    // Not while a frame is being pushed: from here frames come from the
    // source alone.
    const std::lock_guard<std::mutex> producer(produce_m_);
    if (flt_status st = failure(fn))
        return st;
    std::unique_lock<std::mutex> lock(m_);
    if (source_ == nullptr)
        return fail(FLT_ERR_STATE, "%s: no source is attached (flt_gauge_attach_source)", fn);
    if (acquiring_)
        return fail(FLT_ERR_STATE, "%s: the gauge is already acquiring", fn);
    if (acquisition_.joinable())
        return fail(FLT_ERR_STATE,
                    "%s: the acquisition ended by itself; call flt_gauge_stop first (it says why)",
                    fn);
    lock.unlock();
    const flt_status st = flt_source_start(source_);
    if (st != FLT_OK && st != FLT_ERR_STATE)  // STATE: the caller started it
        return fail(st, "%s: the source does not start: %s", fn,
                    std::string(flt_last_error_message()).c_str());
    clear_error();
    lock.lock();
    source_started_ = true;
    flt_source_kind kind = FLT_SOURCE_IMAGES;
    source_live_ = flt_source_kind_of(source_, &kind) == FLT_OK &&
                   (kind == FLT_SOURCE_U3V || kind == FLT_SOURCE_GIGE);
    clear_error();
    acquiring_ = true;
    acquisition_stop_ = false;
    acquisition_status_ = FLT_OK;
    acquisition_message_.clear();
    acquisition_ = std::thread([this] { acquisition_main(); });
    return FLT_OK;
}

flt_status gauge::stop(const char *fn) {
    if (in_gauge_callback(this))
        return fail(FLT_ERR_STATE, "%s: called from inside the gauge's callback", fn);
    {
        std::lock_guard<std::mutex> lock(m_);
        acquisition_stop_ = true;
    }
    room_cv_.notify_all();
    if (acquisition_.joinable())
        acquisition_.join();
    if (source_ && source_started_) {
        if (flt_source_stop(source_) != FLT_OK)
            clear_error();
        source_started_ = false;
    }
    std::unique_lock<std::mutex> lock(m_);
    idle_cv_.wait(lock, [&] { return failed_ || (tail_ == head_ && !sequencing_); });
    if (failed_) {
        lock.unlock();
        return failure(fn);
    }
    const flt_status st = acquisition_status_;
    if (st != FLT_OK) {
        const std::string message = acquisition_message_;
        acquisition_status_ = FLT_OK;
        acquisition_message_.clear();
        return fail(st, "%s: the acquisition ended with: %s", fn, message.c_str());
    }
    return FLT_OK;
}

flt_status gauge::wait(const char *fn, std::uint32_t timeout_ms) {
    if (in_gauge_callback(this))
        return fail(FLT_ERR_STATE, "%s: called from inside the gauge's callback", fn);
    {
        std::unique_lock<std::mutex> lock(m_);
        if (!acquiring_ && !acquisition_.joinable())
            return fail(FLT_ERR_STATE,
                        "%s: no acquisition to wait for: attach a source "
                        "(flt_gauge_attach_source) and start it (flt_gauge_start)",
                        fn);
        const auto ended = [&] {
            return !acquiring_ || failed_;
        };
        if (timeout_ms == FLT_GAUGE_WAIT_FOREVER)
            idle_cv_.wait(lock, ended);
        else if (!idle_cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms), ended))
            return fail(FLT_ERR_TIMEOUT,
                        "%s: the source still delivers frames after %u ms (a camera never "
                        "ends: flt_gauge_stop ends its acquisition)",
                        fn, unsigned(timeout_ms));
    }
    // The source is exhausted: its frames through, the strip ended, every
    // sheet out; an error that ended the acquisition is said after that.
    const flt_status stopped = stop(fn);
    std::string why;
    if (stopped != FLT_OK)
        why = flt_last_error_message();
    const flt_status flushed = flush(fn);
    if (stopped != FLT_OK)
        return fail(stopped, "%s", why.c_str());
    return flushed;
}

flt_status gauge::next_sheet(const char *fn, std::uint32_t timeout_ms, flt_sheet **out) {
    if (in_gauge_callback(this))
        return fail(FLT_ERR_STATE, "%s: called from inside the gauge's callback", fn);
    {
        std::lock_guard<std::mutex> dl(deliver_m_);
        if (callback_)
            return fail(FLT_ERR_STATE,
                        "%s: a callback receives the sheets (flt_gauge_set_callback with NULL "
                        "removes it)",
                        fn);
    }
    std::unique_lock<std::mutex> lock(m_);
    sheet_cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                       [&] { return ready_count_ > 0 || failed_; });
    if (ready_count_ > 0) {
        *out = ready_[ready_head_];
        ready_head_ = (ready_head_ + 1) % ready_.size();
        --ready_count_;
        return FLT_OK;
    }
    if (failed_) {
        lock.unlock();
        return failure(fn);
    }
    return FLT_OK;
}

flt_status gauge::set_callback(const char *fn, flt_sheet_callback callback, void *user) {
    if (in_gauge_callback(this))
        return fail(FLT_ERR_STATE, "%s: called from inside the gauge's callback", fn);
    std::lock_guard<std::mutex> dl(deliver_m_);
    callback_ = callback;
    callback_user_ = user;
    if (!callback)
        return FLT_OK;
    // The sheets already waiting go to the callback first, in order.
    for (;;) {
        flt_sheet *sh;
        {
            std::lock_guard<std::mutex> lock(m_);
            if (ready_count_ == 0)
                break;
            sh = ready_[ready_head_];
            ready_head_ = (ready_head_ + 1) % ready_.size();
            --ready_count_;
        }
        sh->borrowed = true;
        t_in_callback = this;
        callback(sh, user);
        t_in_callback = nullptr;
        pool_->give_back(sh);
    }
    return FLT_OK;
}

std::uint64_t gauge::count(flt_gauge_counter counter) const {
    std::lock_guard<std::mutex> lock(m_);
    switch (counter) {
        case FLT_GAUGE_COUNT_FRAMES:
            return n_frames_;
        case FLT_GAUGE_COUNT_EXTRACTED:
            return n_extracted_;
        case FLT_GAUGE_COUNT_SKIPPED_STOP:
            return n_skipped_stop_;
        case FLT_GAUGE_COUNT_SKIPPED_REVERSAL:
            return n_skipped_rev_;
        case FLT_GAUGE_COUNT_DROPPED:
            return n_dropped_;
        case FLT_GAUGE_COUNT_NO_STRIP:
            return n_no_strip_;
        case FLT_GAUGE_COUNT_STRIPS:
            return n_strips_;
        case FLT_GAUGE_COUNT_SHEETS:
            return n_sheets_;
        case FLT_GAUGE_COUNT_SHEETS_DROPPED:
            return n_sheets_dropped_;
        case FLT_GAUGE_COUNT_CUTS:
            return n_cuts_;
        case FLT_GAUGE_COUNT_CUTS_IGNORED:
            return n_cuts_ignored_;
        case FLT_GAUGE_COUNT_REVERSALS:
            return n_reversals_;
        case FLT_GAUGE_COUNT_EXTRACT_ERRORS:
            return n_extract_errors_;
        case FLT_GAUGE_COUNT_QUEUED:
            return head_ - tail_;
        case FLT_GAUGE_COUNT_ACQUIRING:
            return acquiring_ ? 1 : 0;
        case FLT_GAUGE_COUNT_SHEETS_WAITING:
            return ready_count_;
        case FLT_GAUGE_COUNT_SHEETS_GROWN:
            return n_sheets_grown_;
        case FLT_GAUGE_COUNT_SHEETS_INCOMPLETE:
            return n_incomplete_;
        case FLT_GAUGE_COUNT_MISSING:
            return n_missing_;
        case FLT_GAUGE_COUNT_LOST_LINES:
            return n_lost_lines_;
        case FLT_GAUGE_COUNT_REFUSED:
            return n_refused_;
        case FLT_GAUGE_COUNT_PROVISIONAL:
            return n_provisional_;
        case FLT_GAUGE_COUNT_EXTRACT_NS:
            return ns_extract_.load(std::memory_order_relaxed);
        case FLT_GAUGE_COUNT_SEQUENCE_NS:
            return ns_sequence_.load(std::memory_order_relaxed);
        case FLT_GAUGE_COUNT_EVALUATE_NS:
            return ns_evaluate_.load(std::memory_order_relaxed);
        case FLT_GAUGE_COUNT_QUEUE_HIGH_WATER:
            return queue_high_;
        default:
            return 0;
    }
}

bool gauge::acquiring() const {
    std::lock_guard<std::mutex> lock(m_);
    return acquiring_;
}

flt_status gauge::check_frame(const char *fn, const void *pixels, int format, std::uint32_t width,
                              std::uint32_t height, std::size_t stride, double encoder_mm) const {
    FLT_CHECK_NOT_NULL(fn, pixels);
    const int raw = format;
    if (raw != FLT_PIXEL_MONO8 && raw != FLT_PIXEL_MONO10 && raw != FLT_PIXEL_MONO12 &&
        raw != FLT_PIXEL_MONO16)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'format' = %d is not a flt_pixel_format (8, 10, 12 or 16)", fn,
                    raw);
    if (width != width_ || height != height_)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: arguments 'width' x 'height' = %u x %u but the calibration's frames are "
                    "%u x %u px",
                    fn, width, height, width_, height_);
    const int bytes = raw == FLT_PIXEL_MONO8 ? 1 : 2;
    if (stride < std::size_t(width) * bytes)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'stride_bytes' = %zu is less than width %u x %d bytes per pixel",
                    fn, stride, width, bytes);
    if (height > 0 && stride > std::numeric_limits<std::size_t>::max() / height)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'stride_bytes' = %zu times height %u overflows the address space",
                    fn, stride, height);
    if (bytes == 2 && (stride % 2 != 0 || reinterpret_cast<std::uintptr_t>(pixels) % 2 != 0))
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: 16-bit frames need an even 'stride_bytes' (= %zu) and a 2-byte aligned "
                    "'frame'",
                    fn, stride);
    return check_encoder(fn, encoder_mm);
}

flt_status gauge::check_encoder(const char *fn, double encoder_mm) {
    if (!std::isfinite(encoder_mm) || std::fabs(encoder_mm) > 1.0e12)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'encoder_mm' = %g is not a position (finite, at most 1e12 mm)",
                    fn, encoder_mm);
    return FLT_OK;
}

flt_status gauge::set_coil(const char *fn, const flt_coil_info *coil) {
    std::shared_ptr<flt_coil_info> copy;
    if (coil != nullptr) {
        copy = std::make_shared<flt_coil_info>(*coil);
        copy->lent = true;  // read-only for whoever gets it from a sheet
    }
    std::lock_guard<std::mutex> lock(m_);
    if (failed_)
        return fail(failure_status_, "%s: the gauge stopped processing: %s", fn,
                    failure_message_.c_str());
    if (coils_pending_.size() >= k_cut_capacity)
        return fail(FLT_ERR_BUFFER_FULL, "%s: %zu coil identities wait for a frame", fn,
                    coils_pending_.size());
    if (recorder_ != nullptr && copy)
        recorder_->add_coil(*copy, std::max<std::int64_t>(0, recorded_row(head_)));
    coils_pending_.push_back(coil_entry{head_, std::move(copy)});
    return FLT_OK;
}

flt_status gauge::coil_info_of(const char *fn, flt_coil which, flt_coil_info **out) const {
    std::shared_ptr<flt_coil_info> info;
    {
        std::lock_guard<std::mutex> lock(stats_m_);
        info = which == FLT_COIL_LAST ? coil_last_.coil_info : coil_current_.coil_info;
    }
    if (!info)
        return fail(FLT_ERR_NOT_FOUND, "%s: the %s coil has no identity (flt_gauge_set_coil)", fn,
                    which == FLT_COIL_LAST ? "last" : "current");
    auto copy = std::make_unique<flt_coil_info>(*info);
    copy->lent = false;
    *out = copy.release();
    return FLT_OK;
}

flt_status gauge::note(const char *fn, const char *kind, const char *text) {
    sheet_note n;
    n.kind = kind;
    n.text = text;
    n.utc_ns = record::utc_now_ns();
    std::lock_guard<std::mutex> lock(m_);
    if (notes_pending_.size() >= k_cut_capacity)
        return fail(FLT_ERR_BUFFER_FULL, "%s: %zu notes wait for a frame", fn,
                    notes_pending_.size());
    if (recorder_ != nullptr)
        recorder_->add_note(n.kind, n.text, std::max<std::int64_t>(0, recorded_row(head_)));
    notes_pending_.push_back(note_entry{head_, std::move(n)});
    return FLT_OK;
}

namespace {

// Idle: no frame in flight, no role taken, no sheet waiting to be evaluated,
// no acquisition (under m_).
const char *busy_reason(bool acquiring, bool queued, bool roles) {
    if (acquiring)
        return "the attached source is acquiring (flt_gauge_stop first)";
    if (queued)
        return "frames are in the gauge's queue (flt_gauge_flush first)";
    if (roles)
        return "a sheet is being built or evaluated (flt_gauge_flush first)";
    return nullptr;
}

}  // namespace

flt_status gauge::attach_recorder(const char *fn, flt_recorder *recorder) {
    if (in_gauge_callback(this))
        return fail(FLT_ERR_STATE, "%s: called from inside the gauge's callback", fn);
    const std::lock_guard<std::mutex> producer(produce_m_);
    std::lock_guard<std::mutex> lock(m_);
    if (const char *why =
            busy_reason(acquiring_, head_ != tail_, sequencing_ || evaluating_ || !jobs_.empty()))
        return fail(FLT_ERR_STATE, "%s: %s", fn, why);
    if (recorder_handle_ != nullptr) {
        recorder_->owner.store(nullptr);
        recorder_handle_ = nullptr;
        recorder_ = nullptr;
    }
    if (recorder == nullptr)
        return FLT_OK;
    record::recorder &rec = *recorder->impl;
    if (rec.fibers() != K_)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: the recorder's calibration has %zu fibers, the gauge's %zu", fn,
                    rec.fibers(), K_);
    const void *expected = nullptr;
    if (!rec.owner.compare_exchange_strong(expected, this))
        return fail(FLT_ERR_STATE, "%s: another gauge records through this recorder", fn);
    rec_seq0_ = head_;
    rec.set_gauge_options(effective_);
    // What waits for the strip belongs to the recording: the cuts given
    // (announced or active) and the coil identities not applied yet.
    for (std::size_t i = 0; i < active_count_; ++i)
        rec.add_cut(active_[(active_head_ + i) % k_cut_capacity] + mean_offset_, 0);
    for (std::size_t i = 0; i < cut_count_; ++i)
        rec.add_cut(cuts_[(cut_head_ + i) % k_cut_capacity].s + mean_offset_, 0);
    if (next_coil_given_ && next_coil_)
        rec.add_coil(*next_coil_, 0);
    for (const coil_entry &c : coils_pending_)
        if (c.info)
            rec.add_coil(*c.info, 0);
    for (const note_entry &n : notes_pending_)
        rec.add_note(n.note.kind, n.note.text, 0);
    recorder_ = &rec;
    recorder_handle_ = recorder;
    return FLT_OK;
}

flt_status gauge::attach_archive(const char *fn, flt_archive *archive) {
    if (in_gauge_callback(this))
        return fail(FLT_ERR_STATE, "%s: called from inside the gauge's callback", fn);
    const std::lock_guard<std::mutex> producer(produce_m_);
    std::lock_guard<std::mutex> lock(m_);
    if (const char *why =
            busy_reason(acquiring_, head_ != tail_, sequencing_ || evaluating_ || !jobs_.empty()))
        return fail(FLT_ERR_STATE, "%s: %s", fn, why);
    if (archive_handle_ != nullptr) {
        archive_->owner.store(nullptr);
        archive_handle_ = nullptr;
        archive_ = nullptr;
    }
    if (archive == nullptr)
        return FLT_OK;
    const void *expected = nullptr;
    if (!archive->impl->owner.compare_exchange_strong(expected, this))
        return fail(FLT_ERR_STATE, "%s: another gauge archives into this archive", fn);
    archive_ = archive->impl.get();
    archive_handle_ = archive;
    return FLT_OK;
}

}  // namespace flt
