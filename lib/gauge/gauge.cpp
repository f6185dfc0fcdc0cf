// SPDX-License-Identifier: Apache-2.0
// The gauge: the producer (frames in), the workers (extraction), the
// sequencer (reconstructor and sheets, in frame order) and the evaluation
// (flatness per sheet, in sheet order). lib/gauge/README.md has the picture.
#include "gauge/gauge.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>

#include "calibration/calib_internal.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/number_text.hpp"
#include "flatline/extractor.h"
#include "flatline/source.h"
#include "reconstruction/recon_internal.hpp"
#include "sources/source_handle.hpp"

namespace flt {
namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();
// The reconstructor refuses larger jumps between rows (recon_api.cpp): it
// would have to bridge them knot by knot.
constexpr double k_recon_max_jump_mm = 1.0e6, k_recon_max_jump_knots = 1000.0;

thread_local const void *t_in_callback = nullptr;  // the gauge whose callback runs

// Time spent in a stage (extraction, sequencing, evaluation), added to its
// counter when the stage returns, by the monotonic clock (a vDSO read, not
// a system call: cheap per frame). A stage run inside another (a sheet
// evaluated by the sequencer while both buffers are busy) counts for
// itself only: the outer one leaves its time out.
class stage_timer {
  public:
    explicit stage_timer(std::atomic<std::uint64_t> &total)
        : total_(total), outer_(current_), t0_(std::chrono::steady_clock::now()) {
        current_ = this;
    }
    ~stage_timer() {
        const auto ns = std::uint64_t(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                          std::chrono::steady_clock::now() - t0_)
                                          .count());
        total_.fetch_add(ns - std::min(ns, nested_), std::memory_order_relaxed);
        if (outer_)
            outer_->nested_ += ns;
        current_ = outer_;
    }
    stage_timer(const stage_timer &) = delete;
    stage_timer &operator=(const stage_timer &) = delete;
    // Touches the thread-local (with MinGW's emulated TLS its first use on
    // a thread allocates: at thread start, not per frame).
    static void touch() {
        stage_timer *volatile current = current_;
        (void)current;
    }

  private:
    static thread_local stage_timer *current_;
    std::atomic<std::uint64_t> &total_;
    stage_timer *outer_;
    std::chrono::steady_clock::time_point t0_;
    std::uint64_t nested_ = 0;
};
thread_local stage_timer *stage_timer::current_ = nullptr;

// A failed call of another component: its status and message, as an
// exception the gauge's guards turn back into them.
void check(flt_status st) {
    if (st != FLT_OK)
        throw error(st, flt_last_error_message());
}

void set_option(flt_options &bag, flt_option key, double value) {
    check(flt_options_set(&bag, key, value));
}

int bytes_per_pixel(flt_pixel_format format) {
    return format == FLT_PIXEL_MONO8 ? 1 : 2;
}

// One rule's coil statistics as the FLT_COIL_* values (gauge.h), for
// flt_gauge_coil_rule and for the archive's copy at a coil's end: one
// place, so both always carry the same values.
void coil_rule_values(const coil_stats &c, const coil_stats::per_rule &p, double *a) {
    a[FLT_COIL_NUMBER] = c.coil;
    a[FLT_COIL_SHEETS] = c.sheets;
    a[FLT_COIL_SHEETS_PASSED] = c.passed;
    a[FLT_COIL_SHEETS_FAILED] = c.failed;
    a[FLT_COIL_FINISHED] = c.finished ? 1.0 : 0.0;
    a[FLT_COIL_RULES] = double(c.rules.size());
    a[FLT_COIL_RULE_PASSED] = p.count[FLT_VERDICT_PASS];
    a[FLT_COIL_RULE_FAILED] = p.count[FLT_VERDICT_FAIL];
    a[FLT_COIL_RULE_NO_BAND] = p.count[FLT_VERDICT_NO_BAND];
    a[FLT_COIL_RULE_NOT_MEASURED] = p.count[FLT_VERDICT_NOT_MEASURED];
    a[FLT_COIL_RULE_NOT_JUDGED] = p.count[FLT_VERDICT_NOT_JUDGED];
    a[FLT_COIL_SHEETS_NOT_JUDGED] = c.not_judged;
    a[FLT_COIL_SHEETS_JUDGED] = c.passed + c.failed;
    a[FLT_COIL_WORST_MIN] = p.min;
    a[FLT_COIL_WORST_MAX] = p.max;
    a[FLT_COIL_WORST_MEAN] = p.measured > 0 ? p.sum / p.measured : k_nan;
    a[FLT_COIL_WORST_SHEET] = p.worst_sheet;
    a[FLT_COIL_WORST_X] = p.worst_x;
    a[FLT_COIL_WORST_S] = p.worst_s;
    for (int h = 0; h < FLT_COIL_HISTOGRAM_BINS; ++h)
        a[FLT_COIL_HISTOGRAM + h] = p.histogram[h];
}

}  // namespace

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

// ---------------------------------------------------------------- create

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
    // closest frame spacing the gauge takes. A probe with the smallest
    // capacity tells the latency (it does not depend on the capacity).
    flt_options recon_options = component_options(options, 100);
    {
        flt_options probe_options = recon_options;
        set_option(probe_options, FLT_OPT_ROW_CAPACITY, 16);
        flt_recon *probe = nullptr;
        check(flt_recon_create_from_calib(calib, &probe_options, &probe));
        const long latency = recon_latency_knots(probe);
        double knot = 0.0, spacing = 0.0;
        flt_status st = flt_recon_get_option(probe, FLT_OPT_KNOT_SPACING, &knot);
        if (st == FLT_OK)
            st = flt_recon_get_option(probe, FLT_OPT_LASER_SPACING, &spacing);
        flt_recon_destroy(probe);
        check(st);
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
        double bytes = 64.0 * rows;                        // the row ring
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
    for (frame_slot &slot : slots_) {
        if (cfg_.workers > 0)
            slot.pixels.reset(new std::uint8_t[std::size_t(width_) * height_ * 2]);
        slot.height.assign(K_, 0.0);
        slot.slope.assign(K_, 0.0);
        slot.valid.assign(K_, 0);
        slot.flags.assign(K_, 0);
    }

    // Sequencer state.
    meta_ring_.resize(row_capacity_);
    if (cfg_.keep_maps >= 2)
        measured_ring_.assign(row_capacity_ * K_, 0.0);
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
    flag_scratch_.assign(std::max(K_, zones_), 0);

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
    for (std::condition_variable *cv : {&work_cv_, &room_cv_, &idle_cv_, &sheet_cv_})
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
    flt_flatness_destroy(flat_);
    flt_flatness_destroy(flat_short_);
    band_extractor_ = nullptr;
    calib_for_extractors_ = nullptr;
    extract_options_ = nullptr;
    recon_ = nullptr;
    flat_ = flat_short_ = nullptr;
}

// ---------------------------------------------------------------- failures

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

// Runs body; an exception becomes the gauge's failure. Returns false then.
template <class Body>
bool gauge_guarded(gauge *g, Body &&body, void (gauge::*rec)(flt_status, const char *)) {
    try {
        body();
        return true;
    } catch (const error &e) {
        (g->*rec)(e.status, e.what());
    } catch (const std::bad_alloc &) {
        (g->*rec)(FLT_ERR_OUT_OF_MEMORY, "out of memory");
    } catch (const std::exception &e) {
        (g->*rec)(FLT_ERR_INTERNAL, e.what());
    } catch (...) {
        (g->*rec)(FLT_ERR_INTERNAL, "unknown exception");
    }
    return false;
}

// ---------------------------------------------------------------- producer

void gauge::extract(frame_slot &slot, const void *pixels, flt_pixel_format format,
                    std::size_t stride, flt_extractor *extractor, bool *error_out) const {
    const stage_timer timer(ns_extract_);
    const flt_status st = flt_extractor_process(extractor, pixels, format, width_, height_, stride,
                                                slot.encoder_mm, K_, &slot.s, slot.height.data(),
                                                slot.slope.data(), slot.valid.data());
    if (st == FLT_OK) {
        *error_out = false;
        // The strip in the frame: per fiber on or off it, its edges (the
        // profile row's: both lasers' mean) and its saturated peaks. These
        // calls fail only before a successful process, which this was.
        std::size_t peaks = 0, saturated = 0;
        if (flt_extractor_fiber_flags(extractor, K_, slot.flags.data()) != FLT_OK ||
            flt_extractor_strip(extractor, 2, &slot.left, &slot.right, nullptr, nullptr,
                                &slot.strip_flags) != FLT_OK ||
            flt_extractor_saturation(extractor, 2, &peaks, &saturated, nullptr) != FLT_OK)
            throw error(FLT_ERR_INTERNAL, flt_last_error_message());
        slot.saturated = std::uint32_t(saturated);
        slot.peaks = std::uint32_t(peaks);
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

// ---------------------------------------------------------------- workers

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
    // 2. A finished sheet's flatness (the next sheet is being built).
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
    // 3. Extraction, oldest frame first.
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

// ---------------------------------------------------------------- sequencer

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

void gauge::push_row(double s, const double *height, const double *slope, const std::uint8_t *flags,
                     const row_meta &meta) {
    if (meta_count_ == row_capacity_)
        throw error(FLT_ERR_INTERNAL, "the gauge's row ring is full");
    check(flt_recon_push_flagged(recon_, 1, K_, &s, height, slope, flags));
    const std::size_t at = (meta_head_ + meta_count_) % row_capacity_;
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
        std::size_t got = 0;
        check(flt_recon_pull(recon_, k_pull_rows, K_, pull_s_.data(), pull_z_.data(),
                             pull_flags_.data(), &got));
        if (got == 0)
            return;
        for (std::size_t r = 0; r < got; ++r) {
            if (meta_count_ == 0 || meta_ring_[meta_head_].s != pull_s_[r])
                throw error(FLT_ERR_INTERNAL, "the reconstructor's rows and the gauge's disagree");
            const std::size_t at = meta_head_;
            meta_head_ = (meta_head_ + 1) % row_capacity_;
            --meta_count_;
            output_row(pull_s_[r], &pull_z_[r * K_], &pull_flags_[r * K_], meta_ring_[at],
                       cfg_.keep_maps >= 2 ? &measured_ring_[at * K_] : nullptr);
        }
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
    // them now (flt_recon_peek changes nothing it will emit).
    const std::size_t r0 = cur.rows;
    copy_rows(pb, 0, cur, 0, r0);
    std::size_t got = 0;
    check(flt_recon_peek(recon_, sheet_capacity_ - r0, K_, pb.s.data() + r0, pb.z.data() + r0 * K_,
                         pb.flags.data() + r0 * K_, &got));
    std::size_t rows = r0;
    bool has_after = false;
    row_meta after;
    for (std::size_t j = 0; j < got; ++j) {
        // The pending rows' metadata wait in the ring in the same order.
        if (j >= meta_count_ || meta_ring_[(meta_head_ + j) % row_capacity_].s != pb.s[r0 + j])
            throw error(FLT_ERR_INTERNAL,
                        "the reconstructor's pending rows and the gauge's disagree");
        const std::size_t at = (meta_head_ + j) % row_capacity_;
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
        check(flt_recon_end_sheet(recon_));
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
        check(flt_recon_reset(recon_));
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

// ---------------------------------------------------------------- evaluation

flt_sheet *gauge::take_slot(std::size_t rows) {
    {
        std::lock_guard<std::mutex> lock(pool_->m);
        if (!pool_->free.empty()) {
            flt_sheet *sh = pool_->free.back();
            pool_->free.pop_back();
            pool_->out.fetch_add(1);
            return sh;
        }
    }
    if (cfg_.sheet_backlog == 0) {
        // The caller chose to keep no backlog: the oldest waiting sheet
        // makes room for the newest.
        std::unique_lock<std::mutex> lock(m_);
        ++n_sheets_dropped_;
        const unsigned long long dropped = n_sheets_dropped_;
        if (ready_count_ == 0) {
            lock.unlock();
            FLT_LOG(FLT_LOG_WARNING, "gauge",
                    "a finished sheet was dropped: every sheet slot is held by the caller "
                    "(gauge_sheet_backlog = 0; %llu sheets dropped so far)",
                    dropped);
            return nullptr;  // every slot is held by the caller: this sheet is lost
        }
        flt_sheet *sh = ready_[ready_head_];
        ready_head_ = (ready_head_ + 1) % ready_.size();
        --ready_count_;
        return sh;
    }
    // Every slot is taken: a sheet of its own (maps of its rows only),
    // freed when it is given back. Never a finished sheet dropped.
    auto sh = std::make_unique<flt_sheet>();
    sh->pool = pool_;
    sh->grown = true;
    sh->fibers = K_;
    sh->maps = cfg_.keep_maps;
    for (int a = 0; a < k_sheet_arrays; ++a)
        sh->array[a].assign(is_fiber_array(a) ? K_ : zones_, 0.0);
    if (cfg_.keep_maps >= 1) {
        sh->map_s.assign(rows, 0.0);
        sh->map_z.assign(rows * K_, 0.0);
        sh->map_flags.assign(rows * K_, 0);
    }
    if (cfg_.keep_maps >= 2)
        sh->map_measured.assign(rows * K_, 0.0);
    pool_->out.fetch_add(1);
    unsigned long long grown = 0;
    {
        std::lock_guard<std::mutex> lock(m_);
        grown = ++n_sheets_grown_;
    }
    FLT_LOG(FLT_LOG_INFO, "gauge",
            "every one of the %zu sheet slots is taken: another sheet made (%llu so far; read "
            "the sheets sooner, or raise gauge_sheet_slots)",
            cfg_.sheet_slots, grown);
    return sh.release();
}

namespace {

// How many of `lost` frames spread evenly over (prev_s, s) lie in [a, b):
// frame k (1..lost) lies at prev_s + k (s - prev_s) / (lost + 1).
double lost_between(std::uint32_t lost, double prev_s, double s, double a, double b) {
    if (lost == 0)
        return 0.0;
    const double step = (s - prev_s) / (double(lost) + 1.0);
    if (!(step > 0.0))
        return 0.0;
    const double first = std::max(1.0, std::ceil((a - prev_s) / step));
    const double last = std::min(double(lost), std::ceil((b - prev_s) / step) - 1.0);
    return std::max(0.0, last - first + 1.0);
}

}  // namespace

void gauge::evaluate(const sheet_job &job) {
    const stage_timer timer(ns_evaluate_);
    {
        std::lock_guard<std::mutex> lock(m_);
        ++(job.provisional ? n_provisional_ : n_sheets_);
    }
    flt_sheet *sh = take_slot(job.rows);
    if (sh == nullptr)
        return;
    const sheet_buffer &b = buffers_[job.buffer];
    const std::size_t n = job.rows;
    double *v = sh->value;
    std::fill(v, v + k_sheet_values, 0.0);
    v[FLT_SHEET_ID] = double(job.id);
    v[FLT_SHEET_COIL] = double(job.coil);
    v[FLT_SHEET_INDEX] = double(job.index);
    v[FLT_SHEET_S_START] = job.s_start;
    v[FLT_SHEET_S_END] = job.s_end;
    v[FLT_SHEET_ROWS] = double(n);
    v[FLT_SHEET_LOOKAHEAD] = job.lookahead;
    v[FLT_SHEET_LATENCY] = job.latency_s;
    v[FLT_SHEET_CUT_TIME] = 1e-9 * double(job.cut_time_ns);
    v[FLT_SHEET_FIBERS] = double(K_);
    v[FLT_SHEET_ZONES] = double(zones_);
    sh->coil = job.coil_info;  // a reference more: no allocation
    sh->notes = job.notes;     // allocates only when there are notes
    // Frames lost before a row lie between it and the frame before, spread
    // evenly: a sheet counts those in [s_start, s_end), its first row's and
    // the next sheet's first row's included.
    double skipped = 0, dropped = 0, missing = 0, saturated = 0, peaks = 0, invalid = 0;
    double measured = 0;
    const auto count_lost = [&](const row_meta &m) {
        dropped += lost_between(m.dropped, m.prev_s, m.s, job.s_start, job.s_end);
        missing += lost_between(m.missing, m.prev_s, m.s, job.s_start, job.s_end);
    };
    for (std::size_t r = 0; r < n; ++r) {
        const row_meta &m = b.meta[r];
        skipped += m.skipped;
        saturated += m.saturated;
        peaks += m.peaks;
        invalid += m.invalid;
        measured += m.measured ? 1 : 0;
        count_lost(m);
    }
    if (job.has_after)
        count_lost(job.after);
    const double lost_lines = double(n) - measured;
    const double expected = double(n) + dropped + missing;
    const double coverage = expected > 0 ? measured / expected : 0.0;
    v[FLT_SHEET_FRAMES] = double(n);
    v[FLT_SHEET_SKIPPED] = skipped;
    v[FLT_SHEET_DROPPED] = dropped;
    v[FLT_SHEET_SATURATED] = saturated;
    v[FLT_SHEET_PEAKS] = peaks;
    v[FLT_SHEET_INVALID] = invalid;
    v[FLT_SHEET_MISSING] = missing;
    v[FLT_SHEET_LOST_LINES] = lost_lines;
    v[FLT_SHEET_ROWS_MEASURED] = measured;
    v[FLT_SHEET_ROWS_EXPECTED] = expected;
    v[FLT_SHEET_COVERAGE] = coverage;
    unsigned flags = job.flags;
    v[FLT_SHEET_S_FIRST] = n ? b.s[0] : k_nan;
    v[FLT_SHEET_S_LAST] = n ? b.s[n - 1] : k_nan;
    if (n == 0)
        flags |= FLT_SHEET_FLAG_EMPTY;
    if (dropped + missing + lost_lines > 0)
        flags |= FLT_SHEET_FLAG_LOST_ROWS;
    // (a NaN-safe comparison: a sheet expected to hold nothing is incomplete)
    const bool incomplete = !(coverage >= cfg_.min_coverage) || n == 0;
    if (incomplete)
        flags |= FLT_SHEET_FLAG_INCOMPLETE;
    if (!job.provisional) {
        // (an early answer's rows are counted with its final sheet)
        std::lock_guard<std::mutex> lock(m_);
        n_missing_ += std::uint64_t(missing);
        n_lost_lines_ += std::uint64_t(lost_lines);
        n_incomplete_ += incomplete ? 1 : 0;
    }
    const auto id = (unsigned long long)job.id, coil = (unsigned long long)job.coil;
    if (job.provisional)
        FLT_LOG(FLT_LOG_DEBUG, "gauge",
                "sheet %llu (coil %llu): provisional result %.0f mm past its cut", id, coil,
                job.lookahead);
    else if (dropped + missing + lost_lines > 0)
        FLT_LOG(FLT_LOG_WARNING, "gauge",
                "sheet %llu (coil %llu) lost rows: %.0f dropped at a full queue, %.0f missing by "
                "the encoder, %.0f lost lines; %.0f of %.0f rows measured (coverage %.1f %%)",
                id, coil, dropped, missing, lost_lines, measured, expected, 100.0 * coverage);
    if (incomplete && !job.provisional)
        FLT_LOG(FLT_LOG_WARNING, "gauge",
                "sheet %llu (coil %llu) is incomplete: coverage %.1f %% is below "
                "gauge_min_coverage %.1f %%; its shape and verdict are \"not judged\"",
                id, coil, 100.0 * coverage, 100.0 * cfg_.min_coverage);
    if (!job.provisional && peaks > 0 && saturated > cfg_.saturation_limit * peaks)
        FLT_LOG(FLT_LOG_WARNING, "gauge",
                "sheet %llu (coil %llu): %.1f %% of the laser peaks on the strip are saturated "
                "(gauge_saturation_limit %.1f %%): lower the exposure or the laser power",
                id, coil, 100.0 * saturated / peaks, 100.0 * cfg_.saturation_limit);

    // The flatness of the rows: whole sheets through evaluate (which
    // refuses a sheet shorter than one wave or without a valid fiber), short
    // ones through the streamed finish (which reports them flagged).
    flt_flatness *f = nullptr;
    if (n >= 2 && b.s[n - 1] - b.s[0] >= min_length_) {
        const flt_status st = flt_flatness_evaluate_strip(
            flat_, n, K_, b.s.data(), b.z.data(), b.flags.data(), b.left.data(), b.right.data());
        if (st == FLT_OK)
            f = flat_;
        else if (st != FLT_ERR_INVALID_ARGUMENT)
            check(st);
        clear_error();
    } else if (n >= 2) {
        check(flt_flatness_reset(flat_short_));
        std::size_t used = 0;
        int evaluated = 0;
        check(flt_flatness_push_strip(flat_short_, n, K_, b.s.data(), b.z.data(), b.flags.data(),
                                      b.left.data(), b.right.data(), &used, &evaluated));
        check(flt_flatness_finish(flat_short_, &evaluated));
        if (used != n || !evaluated)
            throw error(FLT_ERR_INTERNAL, "a short sheet was not evaluated whole");
        f = flat_short_;
    }
    double *fx = sh->array[FLT_SHEET_FIBER_X].data();
    double *fiu = sh->array[FLT_SHEET_FIBER_I_UNITS].data();
    double *farc = sh->array[FLT_SHEET_FIBER_ARC_LENGTH].data();
    double *fwh = sh->array[FLT_SHEET_FIBER_WAVE_HEIGHT].data();
    double *fwp = sh->array[FLT_SHEET_FIBER_WAVE_PERIOD].data();
    double *fst = sh->array[FLT_SHEET_FIBER_STEEPNESS].data();
    double *ffl = sh->array[FLT_SHEET_FIBER_FLAGS].data();
    double *zx = sh->array[FLT_SHEET_ZONE_CENTRE_X].data();
    double *ziu = sh->array[FLT_SHEET_ZONE_I_UNITS].data();
    double *zfl = sh->array[FLT_SHEET_ZONE_FLAGS].data();
    double *fsx = sh->array[FLT_SHEET_FIBER_STRIP_X].data();
    double *zsx = sh->array[FLT_SHEET_ZONE_STRIP_X].data();
    std::copy(fiber_x_.begin(), fiber_x_.end(), fx);
    std::copy(zone_x_.begin(), zone_x_.end(), zx);
    unsigned window_flags = 0;
    if (f) {
        check(flt_flatness_window(f, nullptr, nullptr, nullptr, &window_flags, nullptr));
        check(flt_flatness_fiber_results(f, K_, farc, fiu, fwh, fwp, fst, flag_scratch_.data()));
        for (std::size_t k = 0; k < K_; ++k)
            ffl[k] = flag_scratch_[k];
        check(flt_flatness_zone_results(f, zones_, ziu, flag_scratch_.data()));
        for (std::size_t j = 0; j < zones_; ++j)
            zfl[j] = flag_scratch_[j];
        // Where the results lie: on the strip (from its edges) or, without
        // edges, on the fiber grid; in strip and in sensor coordinates.
        check(flt_flatness_fiber_positions(f, K_, fsx, fx));
        check(flt_flatness_zone_positions(f, zones_, zsx, zx, nullptr, nullptr));
        flt_shape shape = FLT_SHAPE_UNDETERMINED;
        double confidence = 0, bow = 0, crossbow = 0;
        unsigned components = 0;
        check(flt_flatness_shape(f, &shape, &confidence, &components, &bow, &crossbow));
        // An incomplete sheet gets no class as if it were whole.
        v[FLT_SHEET_SHAPE] = double(incomplete ? FLT_SHAPE_NOT_JUDGED : shape);
        v[FLT_SHEET_CONFIDENCE] = incomplete ? 0.0 : confidence;
        v[FLT_SHEET_COMPONENTS] = incomplete ? 0.0 : double(components);
        v[FLT_SHEET_BOW] = bow;
        v[FLT_SHEET_CROSSBOW] = crossbow;
    } else {
        // No valid fiber, one row, or none: every value NaN and flagged.
        window_flags = FLT_WINDOW_NO_VALID_FIBER | FLT_WINDOW_NO_BOW | FLT_WINDOW_NO_CROSSBOW;
        if (n < 2 || b.s[n - 1] - b.s[0] < min_length_)
            window_flags |= FLT_WINDOW_SHORT;
        for (std::size_t k = 0; k < K_; ++k) {
            fiu[k] = farc[k] = fwh[k] = fwp[k] = fst[k] = fsx[k] = k_nan;
            ffl[k] = double(FLT_FIBER_NO_DATA | FLT_FIBER_NO_WAVE);
        }
        for (std::size_t j = 0; j < zones_; ++j) {
            ziu[j] = zsx[j] = k_nan;
            zfl[j] = double(FLT_ZONE_NO_DATA);
        }
        v[FLT_SHEET_SHAPE] = double(incomplete ? FLT_SHAPE_NOT_JUDGED : FLT_SHAPE_UNDETERMINED);
        v[FLT_SHEET_CONFIDENCE] = 0.0;
        v[FLT_SHEET_COMPONENTS] = 0.0;
        v[FLT_SHEET_BOW] = k_nan;
        v[FLT_SHEET_CROSSBOW] = k_nan;
    }
    v[FLT_SHEET_WINDOW_FLAGS] = double(window_flags);

    // The strip's width and lateral position: from the extractor's edges
    // where the flatness window had them (smoothed along the sheet: mean,
    // min and max over its rows); else the outer fibers with data.
    if (f && (window_flags & FLT_WINDOW_ON_STRIP)) {
        double width[3], centre[3];
        check(flt_flatness_strip(f, width, centre));
        v[FLT_SHEET_STRIP_WIDTH] = width[0];
        v[FLT_SHEET_STRIP_WIDTH_MIN] = width[1];
        v[FLT_SHEET_STRIP_WIDTH_MAX] = width[2];
        v[FLT_SHEET_STRIP_CENTRE] = centre[0];
        v[FLT_SHEET_STRIP_CENTRE_MIN] = centre[1];
        v[FLT_SHEET_STRIP_CENTRE_MAX] = centre[2];
        v[FLT_SHEET_STRIP_LEFT] = centre[0] - 0.5 * width[0];
        v[FLT_SHEET_STRIP_RIGHT] = centre[0] + 0.5 * width[0];
    } else {
        long first = -1, last = -1;
        for (std::size_t k = 0; k < K_; ++k)
            if (!(unsigned(ffl[k]) & FLT_FIBER_NO_DATA)) {
                if (first < 0)
                    first = long(k);
                last = long(k);
            }
        if (first >= 0) {
            v[FLT_SHEET_STRIP_LEFT] = fx[first] - 0.5 * pitch_;
            v[FLT_SHEET_STRIP_RIGHT] = fx[last] + 0.5 * pitch_;
        } else {
            flags |= FLT_SHEET_FLAG_NO_EDGES;
            v[FLT_SHEET_STRIP_LEFT] = v[FLT_SHEET_STRIP_RIGHT] = k_nan;
        }
        v[FLT_SHEET_STRIP_WIDTH] = v[FLT_SHEET_STRIP_WIDTH_MIN] = v[FLT_SHEET_STRIP_WIDTH_MAX] =
            v[FLT_SHEET_STRIP_RIGHT] - v[FLT_SHEET_STRIP_LEFT];
        v[FLT_SHEET_STRIP_CENTRE] = v[FLT_SHEET_STRIP_CENTRE_MIN] = v[FLT_SHEET_STRIP_CENTRE_MAX] =
            0.5 * (v[FLT_SHEET_STRIP_LEFT] + v[FLT_SHEET_STRIP_RIGHT]);
    }
    // The largest wave over the fibers.
    long wave = -1;
    for (std::size_t k = 0; k < K_; ++k)
        if (!(unsigned(ffl[k]) & (FLT_FIBER_NO_DATA | FLT_FIBER_NO_WAVE)) &&
            (wave < 0 || fwh[k] > fwh[wave]))
            wave = long(k);
    if (wave >= 0) {
        v[FLT_SHEET_WAVE_HEIGHT] = fwh[wave];
        v[FLT_SHEET_WAVE_PERIOD] = fwp[wave];
        v[FLT_SHEET_WAVE_STEEPNESS] = fst[wave];
        v[FLT_SHEET_WAVE_X] = fx[wave];
    } else {
        flags |= FLT_SHEET_FLAG_NO_WAVE;
        v[FLT_SHEET_WAVE_HEIGHT] = v[FLT_SHEET_WAVE_PERIOD] = k_nan;
        v[FLT_SHEET_WAVE_STEEPNESS] = v[FLT_SHEET_WAVE_X] = k_nan;
    }
    double max_iu = k_nan;
    for (std::size_t j = 0; j < zones_; ++j)
        if (!(unsigned(zfl[j]) & FLT_ZONE_NO_DATA) && !(ziu[j] <= max_iu))
            max_iu = ziu[j];
    v[FLT_SHEET_MAX_I_UNITS] = max_iu;
    v[FLT_SHEET_FLAGS] = double(flags);

    // The verdict, from the sheet buffer's map (kept whatever
    // gauge_keep_maps says) and the values above.
    judge(sh, b, n);
    // Evaluated and judged: the time it is handed out (FINISHED_TIME less
    // CUT_TIME is then the whole wait for a verdict).
    v[FLT_SHEET_FINISHED_TIME] = 1e-9 * double(record::utc_now_ns());

    sh->rows = n;
    if (cfg_.keep_maps >= 1) {
        std::memcpy(sh->map_s.data(), b.s.data(), n * sizeof(double));
        std::memcpy(sh->map_z.data(), b.z.data(), n * K_ * sizeof(double));
        std::memcpy(sh->map_flags.data(), b.flags.data(), n * K_);
    }
    if (cfg_.keep_maps >= 2)
        std::memcpy(sh->map_measured.data(), b.measured.data(), n * K_ * sizeof(double));
    sh->magic = k_sheet_magic;
    // The record keeps final sheets only (the early answer's final follows).
    if (archive_ != nullptr && !job.provisional)
        archive_sheet(*sh, b, n);
    if (recorder_ != nullptr && !job.provisional && recorder_->frames_on_fail() &&
        sh->value[FLT_SHEET_VERDICT] == FLT_VERDICT_FAIL)
        recorder_->save_frames();  // the frames that showed the failure
    deliver(sh);
}

void gauge::judge(flt_sheet *sh, const sheet_buffer &b, std::size_t n) {
    std::shared_ptr<verdict_config> vc;
    {
        std::lock_guard<std::mutex> lock(rules_m_);
        vc = verdict_;  // a reference more: no allocation
    }
    double *v = sh->value;
    sh->verdict = vc;  // may free a replaced rule set (never allocates)
    v[FLT_SHEET_RULES] = 0;
    v[FLT_SHEET_RULES_FAILED] = 0;
    v[FLT_SHEET_VERDICT] = FLT_VERDICT_NOT_JUDGED;  // no rules: nothing judged it
    if (!vc)
        return;
    if (sh->grown && !sh->own_verdict) {
        // A sheet made beyond the slots has no verdict among the slots'.
        auto own = std::make_unique<flt_verdict>();
        own->borrowed = true;
        own->set = vc->rules.set;
        const std::size_t rules = own->set.rules.size();
        own->results.resize(rules);
        own->pending.resize(rules);
        own->gaps.resize(rules);
        sh->own_verdict = std::move(own);
    }
    flt_verdict &vd = sh->own_verdict ? *sh->own_verdict : *vc->slot[sh->slot];
    // The flatness measures and where they are: s the sheet's middle; x
    // the largest zone's centre, the largest wave's fiber, the strip's
    // centre for bow and crossbow (the sensor's centre without edges).
    const double s_mid = n ? 0.5 * (b.s[0] + b.s[n - 1]) : k_nan;
    const double x_centre = std::isnan(v[FLT_SHEET_STRIP_CENTRE])
                                ? 0.5 * (fiber_x_.front() + fiber_x_.back())
                                : v[FLT_SHEET_STRIP_CENTRE];
    const auto give = [&](flt_measure m, double value, double x) {
        verdict::given_measure &g = vd.given[m];
        g = verdict::given_measure{};
        if (!std::isnan(value) && !std::isnan(x) && !std::isnan(s_mid)) {
            g.value = value;
            g.x = x;
            g.s = s_mid;
        }
    };
    const double *ziu = sh->array[FLT_SHEET_ZONE_I_UNITS].data();
    const double *zfl = sh->array[FLT_SHEET_ZONE_FLAGS].data();
    const double *zx = sh->array[FLT_SHEET_ZONE_CENTRE_X].data();
    long zone = -1;
    for (std::size_t j = 0; j < zones_; ++j)
        if (!(unsigned(zfl[j]) & FLT_ZONE_NO_DATA) && (zone < 0 || ziu[j] > ziu[zone]))
            zone = long(j);
    give(FLT_MEASURE_ZONE_I_UNITS, zone >= 0 ? ziu[zone] : k_nan, zone >= 0 ? zx[zone] : k_nan);
    give(FLT_MEASURE_WAVE_STEEPNESS, v[FLT_SHEET_WAVE_STEEPNESS], v[FLT_SHEET_WAVE_X]);
    give(FLT_MEASURE_WAVE_HEIGHT, v[FLT_SHEET_WAVE_HEIGHT], v[FLT_SHEET_WAVE_X]);
    give(FLT_MEASURE_BOW, v[FLT_SHEET_BOW], x_centre);
    give(FLT_MEASURE_CROSSBOW, v[FLT_SHEET_CROSSBOW], x_centre);
    // The coil's nominal thickness and width, where given, choose the bands.
    const double thickness =
        sh->coil && sh->coil->thickness_mm > 0 ? sh->coil->thickness_mm : vc->thickness;
    const double width = sh->coil && sh->coil->width_mm > 0 ? sh->coil->width_mm
                         : vc->width > 0                    ? vc->width
                                                            : v[FLT_SHEET_STRIP_WIDTH];
    verdict::map_view map;
    if (n > 0 && vc->needs_map) {
        map.rows = n;
        map.fibers = K_;
        map.s = b.s.data();
        map.x = fiber_x_.data();
        map.z = b.z.data();
        map.flags = b.flags.data();
    }
    if (unsigned(v[FLT_SHEET_FLAGS]) & FLT_SHEET_FLAG_INCOMPLETE) {
        // Not judged: an incomplete sheet's measures are those of the rows
        // it has, not the sheet's. Each rule says which band would apply.
        for (std::size_t i = 0; i < vd.results.size(); ++i) {
            const verdict::rule &r = vd.set.rules[i];
            double *out = vd.results[i].value;
            std::fill(out, out + verdict::k_values, k_nan);
            out[FLT_VERDICT_STATE] = FLT_VERDICT_NOT_JUDGED;
            out[FLT_VERDICT_MEASURE] = double(r.measure);
            out[FLT_VERDICT_LENGTH] = r.length;
            const int band = width > 0 ? r.band_of(thickness, width) : -1;
            out[FLT_VERDICT_BAND] = band;
            if (band >= 0)
                out[FLT_VERDICT_LIMIT] = r.bands[std::size_t(band)].limit;
        }
    } else {
        verdict::judge(vd.set, vd.given, vc->scratch, thickness, width, map, vd.results.data(),
                       vd.gaps.data());
    }
    const bool provisional = unsigned(v[FLT_SHEET_FLAGS]) & FLT_SHEET_FLAG_PROVISIONAL;
    if (!(unsigned(v[FLT_SHEET_FLAGS]) & FLT_SHEET_FLAG_INCOMPLETE) && !provisional) {
        // A band that changes within a coil (a measured width crossing a
        // band's edge) changes the limit: worth telling.
        const double coil = v[FLT_SHEET_COIL];
        for (std::size_t i = 0; i < vd.results.size() && i < vc->last_band.size(); ++i) {
            const int band = int(vd.results[i].value[FLT_VERDICT_BAND]);
            if (vc->last_coil == coil && band != vc->last_band[i])
                FLT_LOG(FLT_LOG_INFO, "gauge",
                        "sheet %.0f: rule '%s' is judged by band %d, was %d (thickness %g mm, "
                        "width %.0f mm)",
                        v[FLT_SHEET_ID], vd.set.rules[i].name.c_str(), band, vc->last_band[i],
                        thickness, width);
            vc->last_band[i] = band;
        }
        vc->last_coil = coil;
    }
    vd.evaluated = true;
    double failed = 0, unjudged = 0;
    for (const verdict::rule_result &r : vd.results) {
        const double state = r.value[FLT_VERDICT_STATE];
        failed += state == FLT_VERDICT_FAIL ? 1 : 0;
        unjudged += state != FLT_VERDICT_FAIL && state != FLT_VERDICT_PASS ? 1 : 0;
    }
    v[FLT_SHEET_RULES] = double(vd.results.size());
    v[FLT_SHEET_RULES_FAILED] = failed;
    // A failure is certain whatever else could not be judged; a pass needs
    // every rule judged.
    v[FLT_SHEET_VERDICT] = failed > 0                           ? FLT_VERDICT_FAIL
                           : unjudged > 0 || vd.results.empty() ? FLT_VERDICT_NOT_JUDGED
                                                                : FLT_VERDICT_PASS;
    if (!provisional)  // the coil's statistics count final verdicts only
        count_in_coil(*vc, *sh);
}

void coil_stats::reset(std::uint64_t gen, std::size_t n_rules) {
    generation = gen;
    coil = sheets = passed = failed = not_judged = 0;
    finished = false;
    coil_info.reset();
    per_rule zero{};
    zero.min = zero.max = zero.worst_sheet = zero.worst_x = zero.worst_s = k_nan;
    rules.assign(n_rules, zero);  // within the capacity set_rules reserved
}

void gauge::count_in_coil(const verdict_config &vc, const flt_sheet &sh) {
    const flt_verdict &vd = sh.own_verdict ? *sh.own_verdict : *vc.slot[sh.slot];
    const double *v = sh.value;
    std::lock_guard<std::mutex> lock(stats_m_);
    coil_stats &c = coil_current_;
    if (c.generation != vc.generation)
        return;  // judged by rules replaced since (their statistics restarted)
    const double coil = v[FLT_SHEET_COIL];
    const auto finish = [&] {
        c.finished = true;
        std::swap(coil_last_, coil_current_);  // moves: no allocation
        coil_current_.reset(coil_last_.generation, coil_last_.rules.size());
    };
    if (c.sheets > 0 && c.coil != coil)
        finish();  // the previous coil's last sheet was not judged (lost)
    c.coil = coil;
    c.sheets += 1;
    if (c.sheets == 1)
        c.coil_info = sh.coil;  // a reference more: no allocation
    // By the sheet's verdict: a sheet no rule could judge is not passed.
    const double verdict = v[FLT_SHEET_VERDICT];
    (verdict == FLT_VERDICT_FAIL   ? c.failed
     : verdict == FLT_VERDICT_PASS ? c.passed
                                   : c.not_judged) += 1;
    for (std::size_t i = 0; i < c.rules.size() && i < vd.results.size(); ++i) {
        const double *r = vd.results[i].value;
        coil_stats::per_rule &p = c.rules[i];
        const int state = int(r[FLT_VERDICT_STATE]);
        if (state >= 0 && state < 5)
            p.count[state] += 1;
        if (state != FLT_VERDICT_PASS && state != FLT_VERDICT_FAIL)
            continue;
        const double worst = r[FLT_VERDICT_WORST];
        p.measured += 1;
        p.sum += worst;
        if (!(worst >= p.min))
            p.min = worst;
        if (!(worst <= p.max)) {
            p.max = worst;
            p.worst_sheet = v[FLT_SHEET_ID];
            p.worst_x = r[FLT_VERDICT_X];
            p.worst_s = r[FLT_VERDICT_S];
        }
        // Bin i holds worst / limit in (i / 10, (i + 1) / 10]: passes in
        // 0-9, failures in 10-19 whatever the rounding of the ratio.
        const double ratio = worst / r[FLT_VERDICT_LIMIT];
        long bin = long(std::ceil(std::min(ratio, 100.0) * 10.0)) - 1;
        bin = std::max(0L, std::min(long(FLT_COIL_HISTOGRAM_BINS) - 1, bin));
        if (state == FLT_VERDICT_PASS)
            bin = std::min(bin, 9L);
        else
            bin = std::max(bin, 10L);
        p.histogram[bin] += 1;
    }
    const unsigned flags = unsigned(v[FLT_SHEET_FLAGS]);
    if (flags & (FLT_SHEET_FLAG_TAIL | FLT_SHEET_FLAG_NEW_STRIP | FLT_SHEET_FLAG_FLUSHED))
        finish();
}

flt_status gauge::set_rules(const char *fn, const flt_rules *rules, double thickness,
                            double width) {
    std::shared_ptr<verdict_config> vc;
    std::size_t n = 0;
    if (rules) {
        vc = std::make_shared<verdict_config>();
        vc->rules.set = rules->set;
        vc->rules.borrowed = true;
        vc->thickness = thickness;
        vc->width = width;
        vc->needs_map = verdict::needs_map(rules->set);
        n = rules->set.rules.size();
        vc->last_band.assign(n, -1);
        vc->slot.resize(cfg_.sheet_slots);
        for (std::unique_ptr<flt_verdict> &vd : vc->slot) {
            vd = std::make_unique<flt_verdict>();
            vd->borrowed = true;
            vd->set = rules->set;
            vd->results.resize(n);
            vd->pending.resize(n);
            vd->gaps.resize(n);
        }
        // The straightedge over the longest line it will meet: a fiber of
        // the longest sheet, or a row of every fiber.
        if (vc->needs_map)
            vc->scratch.reserve(std::max(sheet_capacity_, K_));
    }
    {
        std::lock_guard<std::mutex> stats_lock(stats_m_);
        coil_current_.rules.reserve(n);
        coil_last_.rules.reserve(n);
        std::lock_guard<std::mutex> lock(rules_m_);
        const std::uint64_t gen = vc ? ++rules_generation_ : 0;
        if (vc)
            vc->generation = gen;
        verdict_.swap(vc);
        coil_current_.reset(gen, n);
    }
    (void)fn;
    return FLT_OK;  // the replaced rules (vc) are freed here, unless a sheet holds them
}

flt_status gauge::coil_stats_of(const char *fn, flt_coil which, std::size_t rule, std::size_t count,
                                double *out) const {
    std::lock_guard<std::mutex> lock(stats_m_);
    const coil_stats &c = which == FLT_COIL_LAST ? coil_last_ : coil_current_;
    if (c.generation == 0)
        return fail(FLT_ERR_STATE,
                    which == FLT_COIL_LAST
                        ? "%s: no coil has finished under rules yet (flt_gauge_set_rules)"
                        : "%s: the gauge has no rules (flt_gauge_set_rules)",
                    fn);
    if (rule >= c.rules.size())
        return fail(FLT_ERR_NOT_FOUND, "%s: argument 'rule' = %zu is past the last of %zu rules",
                    fn, rule, c.rules.size());
    const coil_stats::per_rule &p = c.rules[rule];
    double all[FLT_COIL_VALUES];
    coil_rule_values(c, p, all);
    std::copy(all, all + count, out);
    return FLT_OK;
}

void gauge::deliver(flt_sheet *sheet) {
    std::lock_guard<std::mutex> dl(deliver_m_);
    if (callback_) {
        sheet->borrowed = true;
        t_in_callback = this;
        callback_(sheet, callback_user_);
        t_in_callback = nullptr;
        pool_->give_back(sheet);
        return;
    }
    std::lock_guard<std::mutex> lock(m_);
    if (ready_count_ == ready_.size()) {
        // More sheets wait than there are slots (they were made beyond
        // them): a longer ring, in order.
        std::vector<flt_sheet *> longer(2 * ready_.size(), nullptr);
        for (std::size_t i = 0; i < ready_count_; ++i)
            longer[i] = ready_[(ready_head_ + i) % ready_.size()];
        ready_.swap(longer);
        ready_head_ = 0;
    }
    ready_[(ready_head_ + ready_count_) % ready_.size()] = sheet;
    ++ready_count_;
    sheet_cv_.notify_all();
}

// ---------------------------------------------------------------- calls

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

void gauge::acquisition_main() {
    flt_status status = FLT_OK;
    std::string message;
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
            try {
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
            } catch (const error &e) {
                status = e.status;
                message = e.what();
                break;
            } catch (const std::exception &e) {
                status = FLT_ERR_INTERNAL;
                message = e.what();
                break;
            }
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
        try {
            take(in, true);
        } catch (const error &e) {
            status = e.status;
            message = e.what();
            break;
        } catch (const std::exception &e) {
            status = FLT_ERR_INTERNAL;
            message = e.what();
            break;
        }
    }
    std::lock_guard<std::mutex> lock(m_);
    acquisition_status_ = status;
    acquisition_message_ = message;
    acquiring_ = false;
    idle_cv_.notify_all();
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

}  // namespace flt

namespace flt {

// ---------------------------------------------------------------- the record

std::unique_ptr<record::sheet_record>
archive_record_of(const flt_sheet &sh, const record::archive &ar, const std::string &session,
                  std::size_t rows, const double *s, const double *z, const std::uint8_t *flags);

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

void gauge::archive_sheet(const flt_sheet &sh, const sheet_buffer &b, std::size_t n) {
    std::unique_ptr<record::sheet_record> r =
        archive_record_of(sh, *archive_, pool_->session, n, b.s.data(), b.z.data(), b.flags.data());
    const unsigned flags = unsigned(sh.value[FLT_SHEET_FLAGS]);
    if (flags & (FLT_SHEET_FLAG_TAIL | FLT_SHEET_FLAG_NEW_STRIP | FLT_SHEET_FLAG_FLUSHED)) {
        // The coil's last sheet: its statistics go with it.
        r->ends_coil = true;
        std::lock_guard<std::mutex> lock(stats_m_);
        const coil_stats &c = coil_last_;
        if (c.generation != 0 && c.coil == sh.value[FLT_SHEET_COIL] && sh.verdict) {
            for (std::size_t i = 0; i < c.rules.size(); ++i) {
                record::coil_rule_stats st;
                const char *name = "";
                if (flt_rules_rule(&sh.verdict->rules, i, &name, nullptr, nullptr) == FLT_OK)
                    st.name = name;
                st.values.resize(FLT_COIL_VALUES);
                const coil_stats::per_rule &p = c.rules[i];
                coil_rule_values(c, p, st.values.data());
                r->coil_stats.push_back(std::move(st));
            }
            clear_error();
        }
    }
    if (!archive_->add(std::move(r)))
        FLT_LOG(FLT_LOG_ERROR, "archive",
                "sheet %.0f (coil %.0f) is not archived: archive_buffer_mb is full of sheets the "
                "database has not taken (%s)",
                sh.value[FLT_SHEET_ID], sh.value[FLT_SHEET_COIL], archive_->last_error().c_str());
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
