// SPDX-License-Identifier: Apache-2.0
// Internal: the gauge (flatline/gauge.h). lib/gauge/README.md describes the
// stages, the threads and the invariants.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/block_runner.hpp"
#include "core/coil.hpp"
#include "core/options.hpp"
#include "flatline/flatness.h"
#include "flatline/gauge.h"
#include "flatline/recon.h"
#include "record/archive.hpp"
#include "record/recorder.hpp"
#include "sources/recording/recording_source.hpp"
#include "verdict/verdict.hpp"

namespace flt {

constexpr std::uint32_t k_sheet_magic = 0x464c5453u;  // "FLTS"
constexpr int k_sheet_values = 48;                    // flt_sheet_value keys 0..47
constexpr int k_sheet_arrays = 12;                    // flt_sheet_array keys 0..11

struct sheet_pool;
struct verdict_config;
class recon_pipeline;

// A note given with flt_gauge_note (a leveler change, an operator's
// remark): where it applies along the strip.
struct sheet_note {
    std::string kind, text;
    double s = 0.0;           // mm, the row it was given before
    std::int64_t utc_ns = 0;  // when it was given
};

// Whether a flt_sheet_array has a value per fiber (else per zone).
inline bool is_fiber_array(int key) {
    return key < FLT_SHEET_ZONE_CENTRE_X || key == FLT_SHEET_FIBER_STRIP_X;
}

}  // namespace flt

// A finished sheet. Slots are allocated at create time and reused; a slot
// the caller holds keeps the pool alive past the gauge.
struct flt_sheet {
    std::uint32_t magic = 0;
    std::shared_ptr<flt::sheet_pool> pool;
    bool borrowed = false;  // inside the callback
    double value[flt::k_sheet_values] = {};
    std::vector<double> array[flt::k_sheet_arrays];
    std::size_t rows = 0, fibers = 0;
    int maps = 0;  // gauge_keep_maps
    std::vector<double> map_s, map_z, map_measured;
    std::vector<std::uint8_t> map_flags;
    std::size_t slot = 0;  // its number among the slots (its verdict's)
    // Made beyond gauge_sheet_slots (freed, not pooled, when given back);
    // it has a verdict of its own.
    bool grown = false;
    std::unique_ptr<flt_verdict> own_verdict;
    // The rules it was judged by (null: none); kept alive while the sheet
    // is (flt_sheet_verdict).
    std::shared_ptr<flt::verdict_config> verdict;

    // Its verdict handle (flt_sheet_verdict), or null without rules.
    const flt_verdict *verdict_handle() const;
    // Its coil's identity (flt_sheet_coil; lent, read-only), or null.
    std::shared_ptr<flt_coil_info> coil;
    // The notes given while its rows were taken (flt_sheet_note).
    std::vector<flt::sheet_note> notes;
};

namespace flt {

struct sheet_pool {
    std::mutex m;
    std::vector<flt_sheet *> free;  // capacity reserved for every slot
    bool alive = true;
    // Sheets out of the pool: being filled, waiting or held by the caller
    // (gauge_sheet_backlog bounds the ones beyond the slots).
    std::atomic<std::size_t> out{0};
    // The gauge's session (random, per gauge): archived sheets and coils
    // are named by it and their numbers, so a sheet is stored once.
    std::string session;
    ~sheet_pool();
    // A sheet the gauge is done with or the caller gave back: into the
    // pool, or freed when it was made beyond the slots or the gauge is gone.
    void give_back(flt_sheet *sheet);
};

// A rule set in force (flt_gauge_set_rules): immutable after it is made,
// except the verdicts of the sheet slots and the straightedge's scratch,
// which only the evaluation (one sheet at a time, its blocks on the
// workers) writes.
struct verdict_config {
    std::uint64_t generation = 0;     // which set_rules made it
    flt_rules rules;                  // borrowed: flt_sheet_verdict's view
    double thickness = 0, width = 0;  // mm; width 0: the sheet's strip width
    bool needs_map = false;
    // One verdict per sheet slot (flt_sheet::slot), borrowed.
    std::vector<std::unique_ptr<flt_verdict>> slot;
    // The straightedges' lines are measured in blocks on the workers
    // (judge, verdict::judge): the room for it, reserved by set_rules.
    verdict::judge_workspace workspace;
    // The band each rule chose for the last sheet judged, and its coil
    // (the log says when a band changes within a coil); evaluation only.
    std::vector<int> last_band;
    double last_coil = 0;
};

// One coil's statistics (flt_gauge_coil_stats).
struct coil_stats {
    struct per_rule {
        double count[5];  // by flt_verdict_state
        double min, max, sum, measured;
        double worst_sheet, worst_x, worst_s;
        double histogram[FLT_COIL_HISTOGRAM_BINS];
    };
    std::uint64_t generation = 0;  // the verdict_config's (0: no rules)
    double coil = 0, sheets = 0, passed = 0, failed = 0, not_judged = 0;
    bool finished = false;
    std::vector<per_rule> rules;               // capacity reserved at set_rules
    std::shared_ptr<flt_coil_info> coil_info;  // the coil's identity, or null

    void reset(std::uint64_t gen, std::size_t n_rules);
};

struct gauge_config {
    unsigned workers = 2;
    std::size_t queue_frames = 0;  // 0: automatic (gauge.cpp, k_queue_bytes)
    int overflow = FLT_GAUGE_OVERFLOW_AUTO;
    double min_coverage = 0.95, saturation_limit = 0.05;
    std::size_t sheet_backlog = 16;
    double frame_spacing = 1.0, reversal_length = 500.0, strip_min_width = 100.0;
    double tail_length = 300.0, max_sheet_length = 6000.0;
    int keep_maps = 0;
    std::size_t sheet_slots = 4;
    double provisional_mm = 0.0;  // 0: no provisional sheets
};

// What the producer hands to the gauge: a frame or a profile row.
struct gauge_input {
    // (frames: pixels, format, stride; rows: height, slope, valid)
    const void *pixels = nullptr;  // frame, or nullptr for a row
    flt_pixel_format format = FLT_PIXEL_MONO8;
    std::size_t stride = 0;
    const double *height = nullptr, *slope = nullptr;  // row
    const std::uint8_t *valid = nullptr;
    double encoder_mm = 0.0;
    // A row replayed from a recording, with what the live gauge knew of it.
    const sources::recorded_frame *recorded = nullptr;
};

// Per row on its way through the reconstructor: what its sheet counts.
struct row_meta {
    double s = 0.0;
    // The s of the frame before it (the frames lost between lie in
    // (prev_s, s), spread evenly: a cut between them splits the count).
    double prev_s = 0.0;
    // The strip's edges in the row, sensor x mm (the extractor's, both
    // lasers' mean; NaN where not seen).
    double left = 0.0, right = 0.0;
    // When the frame was taken: host UTC ns at push, or the recording's.
    std::int64_t time_ns = 0;
    std::uint32_t skipped = 0, dropped = 0, missing = 0, saturated = 0, peaks = 0, invalid = 0;
    bool measured = true;  // the frame showed the strip (else a lost line)
};

class gauge {
  public:
    gauge(const flt_calib *calib, const flt_options *options);
    ~gauge();
    gauge(const gauge &) = delete;
    gauge &operator=(const gauge &) = delete;

    std::size_t fibers() const { return K_; }
    double option(flt_option key) const { return option_value(&effective_, key); }

    // Argument checks of a frame and an encoder position (message set). The
    // format comes as the int the caller passed (enum_arg): a value outside
    // the enum must not be loaded as one.
    flt_status check_frame(const char *fn, const void *pixels, int format, std::uint32_t width,
                           std::uint32_t height, std::size_t stride, double encoder_mm) const;
    static flt_status check_encoder(const char *fn, double encoder_mm);
    // push_frame and push_row, input already checked: refused inside the
    // callback, while another thread pushes or flushes, or while a source
    // acquires (FLT_ERR_STATE, message set); else take().
    flt_status push(const char *fn, const gauge_input &in);
    // The producer's entry (push, the acquisition thread), input already
    // checked. Throws flt::error for a failure.
    void take(const gauge_input &in, bool from_acquisition);
    flt_status cut(const char *fn, double encoder_mm);
    flt_status flush(const char *fn);
    flt_status attach(const char *fn, flt_source *source);
    // The quality record (flatline/record.h).
    flt_status set_coil(const char *fn, const flt_coil_info *coil);
    flt_status coil_info_of(const char *fn, flt_coil which, flt_coil_info **out) const;
    flt_status note(const char *fn, const char *kind, const char *text);
    flt_status attach_recorder(const char *fn, flt_recorder *recorder);
    flt_status attach_archive(const char *fn, flt_archive *archive);
    flt_status start(const char *fn);
    flt_status stop(const char *fn);
    flt_status wait(const char *fn, std::uint32_t timeout_ms);
    flt_status next_sheet(const char *fn, std::uint32_t timeout_ms, flt_sheet **out);
    flt_status set_callback(const char *fn, flt_sheet_callback callback, void *user);
    std::uint64_t count(flt_gauge_counter counter) const;
    flt_status set_rules(const char *fn, const flt_rules *rules, double thickness, double width);
    flt_status coil_stats_of(const char *fn, flt_coil which, std::size_t rule, std::size_t count,
                             double *out) const;
    // FLT_OK, or the failure that stopped processing (message set).
    flt_status failure(const char *fn) const;
    bool acquiring() const;
    void record_failure(flt_status status, const char *message);

  private:
    void init(const flt_calib *calib, const flt_options *options);
    void release_parts() noexcept;

    // ---- the queue between acquisition and processing
    enum slot_state { slot_free, slot_filled, slot_extracting, slot_extracted };
    struct frame_slot {
        std::unique_ptr<std::uint8_t[]> pixels;  // width x height x 2 bytes (workers only)
        flt_pixel_format format = FLT_PIXEL_MONO8;
        std::size_t stride = 0;
        double encoder_mm = 0.0;
        std::uint64_t seq = 0;
        slot_state state = slot_free;
        bool new_strip = false;  // a long reversal before this frame
        std::uint32_t skipped_before = 0, dropped_before = 0, missing_before = 0;
        // For a recording: the skipped ones by kind, when it was taken
        // (host UTC, ns), whether it came as a frame, and an extractor error.
        std::uint32_t skipped_stop_before = 0, skipped_rev_before = 0;
        std::int64_t time_ns = 0;
        bool from_frame = false, extract_error = false;
        double s = 0.0;  // the profile row
        std::vector<double> height, slope;
        std::vector<std::uint8_t> valid;
        // Per fiber what flt_recon_push_flagged takes: 0, FLT_FLAG_INVALID_INPUT
        // or FLT_FLAG_OFF_STRIP.
        std::vector<std::uint8_t> flags;
        double left = 0.0, right = 0.0;  // the strip's edges (NaN: not seen)
        unsigned strip_flags = 0;        // FLT_STRIP_* of the frame
        std::uint32_t saturated = 0;     // saturated peaks on the strip
        std::uint32_t peaks = 0;         // peaks on the strip
    };
    // ---- the sheets being built and evaluated
    struct sheet_buffer {
        std::vector<double> s, z, measured, left, right;
        std::vector<std::uint8_t> flags;
        std::vector<row_meta> meta;
        std::size_t rows = 0;
    };
    struct sheet_job {
        int buffer = 0;
        std::size_t rows = 0;
        double s_start = 0, s_end = 0, lookahead = 0;
        // When the strip at s_end passed the sensor (UTC ns, the frames'
        // clock) and the strip taken beyond it in seconds of that clock.
        std::int64_t cut_time_ns = 0;
        double latency_s = 0;
        unsigned flags = 0;
        std::uint64_t id = 0, coil = 0, index = 0;
        // An early answer (FLT_SHEET_FLAG_PROVISIONAL): not counted, not
        // archived, not in the coil's statistics.
        bool provisional = false;
        // The row after the sheet's end (the next sheet's first), whose
        // lost frames may lie before the end.
        bool has_after = false;
        row_meta after;
        std::shared_ptr<flt_coil_info> coil_info;  // its strip's identity, or null
        std::vector<sheet_note> notes;
    };

    // Producer side.
    void fill_slot(frame_slot &slot, const gauge_input &in) const;
    void extract(frame_slot &slot, const void *pixels, flt_pixel_format format, std::size_t stride,
                 flt_extractor *extractor, bool *error_out) const;
    void resolve_band(frame_slot &slot);
    // Workers.
    void first_use_of_sync_objects();
    static void touch_thread_locals();
    void worker_main(unsigned index);
    bool run_one(std::unique_lock<std::mutex> &lock, unsigned index);
    void run_inline();
    void run_jobs_inline();
    void acquire_sequencer();
    void release_sequencer();
    // The sequencer (one thread at a time, frames in order).
    void sequence(frame_slot &slot);
    void activate_cuts(std::uint64_t up_to_seq);
    void drop_active_cuts(double up_to, bool all);
    void log_cuts_ignored(std::size_t n, double s, const char *why) const;
    void begin_strip(double s);
    void end_strip(unsigned flag);
    void push_row(double s, const double *height, const double *slope, const std::uint8_t *flags,
                  const row_meta &meta);
    void release_held();
    void pull_all();
    // A row leaving the reconstructor (pulled or peeked), at ring position
    // `at`: its off-strip fibers NaN, flagged FLT_FLAG_OFF_STRIP.
    void mask_off_strip(std::size_t at, double *z, std::uint8_t *flags) const;
    void output_row(double s, const double *z, const std::uint8_t *flags, const row_meta &meta,
                    const double *measured);
    // Cuts at or before s_limit end their sheets; `incoming` is the row
    // about to join the open sheet (null: none).
    void apply_cuts(double s_limit, const row_meta *incoming);
    // Ends the open sheet at s_at: the rows before it (all rows with
    // all_rows), the rest begin the next sheet. `incoming` as above.
    void split(double s_at, unsigned end_flags, bool all_rows, const row_meta *incoming);
    // Copies n rows (heights, flags, metadata, edges, measured) from one
    // sheet buffer to another.
    void copy_rows(sheet_buffer &to, std::size_t to_row, const sheet_buffer &from,
                   std::size_t from_row, std::size_t n) const;
    // The job of the open sheet ending at s_end after its first `rows` rows
    // in b (the numbers of the next final sheet; notes not taken).
    sheet_job open_sheet_job(int buffer, const sheet_buffer &b, std::size_t rows, double s_end,
                             unsigned end_flags, const row_meta *incoming) const;
    // The open sheet's early answer, when the strip is gauge_provisional_mm
    // past its cut and its last rows are not final yet.
    void publish_provisional();
    // When the strip at s_at passed the sensor, by the frame times of the
    // rows beside it (i: the first row of b at or after s_at).
    std::int64_t cut_time_ns(const sheet_buffer &b, std::size_t i, double s_at,
                             const row_meta *incoming) const;
    // Frames the encoder says are missing before a frame that advanced by
    // `advance` mm past the furthest (0 while the pitch is unknown).
    std::uint32_t frames_missing(double advance);
    // True when gauge_sheet_backlog sheets exist beyond the slots.
    bool backlog_full() const;
    int free_buffer_or_wait();
    // Evaluation (one thread at a time, sheets in order).
    void evaluate(const sheet_job &job);
    // The verdict of a sheet being evaluated (its values set), and the
    // coil's statistics.
    void judge(flt_sheet *sh, const sheet_buffer &b, std::size_t n);
    void count_in_coil(const verdict_config &vc, const flt_sheet &sh);
    void deliver(flt_sheet *sheet);
    // Blocks of a sheet's evaluation, run by the thread that evaluates and
    // by the workers that are free (block_runner::run).
    void run_block_task(std::size_t blocks, block_runner::block_fn fn, void *context);
    // With m_ held: runs blocks of the open task until none is left.
    void work_on_blocks(std::unique_lock<std::mutex> &lock);
    flt_sheet *take_slot(std::size_t rows);
    void acquisition_main();

    // ---- configuration (immutable after create)
    gauge_config cfg_;
    flt_options effective_{};
    std::size_t K_ = 0;
    std::uint32_t width_ = 0, height_ = 0;
    double mean_offset_ = 0.0, pitch_ = 1.0, first_x_ = 0.0;
    double max_jump_ = 0.0;
    std::size_t row_capacity_ = 0, sheet_capacity_ = 0, hold_capacity_ = 0;
    std::size_t zones_ = 0;
    std::vector<double> fiber_x_, zone_x_;
    double min_length_ = 0.0;
    flt_options *extract_options_ = nullptr;
    flt_calib *calib_for_extractors_ = nullptr;

    // ---- parts
    std::vector<flt_extractor *> extractors_;  // one per worker (one inline)
    flt_extractor *band_extractor_ = nullptr;  // automatic bands, until known
    bool band_known_ = false;                  // producer-side
    flt_recon *recon_ = nullptr;
    // Its C++ side (recon_pipeline_of), which the sequencer calls per row
    // without the public API's checks: the sequencer keeps its contract.
    recon_pipeline *pipeline_ = nullptr;
    flt_flatness *flat_ = nullptr, *flat_short_ = nullptr;

    // ---- the producer role: held by push (tried: a second pusher is
    // refused), flush and start (waited for)
    std::mutex produce_m_;

    // ---- shared state, under m_
    mutable std::mutex m_;
    std::condition_variable work_cv_, room_cv_, idle_cv_, sheet_cv_;
    std::vector<frame_slot> slots_;
    std::uint64_t head_ = 0, claim_ = 0, tail_ = 0;  // seq: next to fill / extract / sequence
    bool sequencing_ = false, evaluating_ = false, stopping_ = false;
    bool failed_ = false;
    flt_status failure_status_ = FLT_OK;
    std::string failure_message_;
    std::vector<sheet_job> jobs_;  // FIFO, at most 2
    // 1 while filled, queued or evaluated; buffer 2 holds a provisional
    // sheet (only with gauge_provisional_mm).
    int buffer_busy_[3] = {0, 0, 0};
    std::vector<flt_sheet *> ready_;  // ring of sheets for next_sheet
    std::size_t ready_head_ = 0, ready_count_ = 0;
    // Cuts announced (with the seq of the next frame when given), then
    // active (the sequencer reached them), each a ring.
    static constexpr std::size_t k_cut_capacity = 256;
    struct cut_entry {
        std::uint64_t seq;
        double s;
    };
    cut_entry cuts_[k_cut_capacity] = {};
    std::size_t cut_head_ = 0, cut_count_ = 0;
    double active_[k_cut_capacity] = {};
    std::size_t active_head_ = 0, active_count_ = 0;
    bool has_cut_floor_ = false;
    double cut_floor_ = 0.0;
    // Producer state (one producer at a time; under m_ for the counters).
    bool has_furthest_ = false;
    double furthest_ = 0.0;
    std::uint32_t pending_skipped_ = 0, pending_dropped_ = 0, pending_missing_ = 0;
    std::uint32_t pending_skipped_stop_ = 0, pending_skipped_rev_ = 0;
    bool pending_new_strip_ = false;
    // The last advances between frames taken (mm), for the frame pitch.
    static constexpr std::size_t k_pitch_window = 9;
    double advances_[k_pitch_window] = {};
    std::size_t n_advances_ = 0;
    bool source_live_ = false;  // the attached source is a camera
    // counters
    std::uint64_t n_frames_ = 0, n_extracted_ = 0, n_skipped_stop_ = 0, n_skipped_rev_ = 0,
                  n_dropped_ = 0, n_no_strip_ = 0, n_strips_ = 0, n_sheets_ = 0,
                  n_sheets_dropped_ = 0, n_cuts_ = 0, n_cuts_ignored_ = 0, n_reversals_ = 0,
                  n_extract_errors_ = 0, n_sheets_grown_ = 0, n_incomplete_ = 0, n_missing_ = 0,
                  n_lost_lines_ = 0, n_refused_ = 0, n_provisional_ = 0;
    std::uint64_t queue_high_ = 0;  // the most frames queued at once
    // Time spent in each stage on every thread, ns (stage_timer).
    mutable std::atomic<std::uint64_t> ns_extract_{0};
    std::atomic<std::uint64_t> ns_sequence_{0}, ns_evaluate_{0};
    // The evaluating thread's waits for blocks on other threads (left out
    // of ns_evaluate_; not reported).
    std::atomic<std::uint64_t> ns_block_wait_{0};

    // ---- sequencer state (the thread holding the sequencing role)
    bool in_strip_ = false, pushed_ = false, has_output_ = false;
    double last_pushed_s_ = 0.0, last_output_s_ = 0.0;
    std::int64_t last_pushed_time_ns_ = 0;  // the frame time of that row
    std::uint64_t coil_ = 0, sheet_in_coil_ = 0, sheet_ids_ = 0;
    double sheet_start_ = 0.0;
    unsigned sheet_flags_ = 0;
    int current_ = 0;               // the sheet buffer being filled
    sheet_buffer buffers_[3];       // two for final sheets, one for a provisional
    double provisional_cut_ = 0.0;  // the cut the last provisional sheet ended at
    bool has_provisional_cut_ = false;
    // Rows inside the reconstructor, oldest first (ring of row_capacity_).
    std::vector<row_meta> meta_ring_;
    std::vector<double> measured_ring_;  // [row_capacity_ * K_], keep_maps 2
    // Their off-strip fibers, one bit each ([row_capacity_ * off_strip_stride_]),
    // and whether a row has any: the engine takes them as invalid samples,
    // and they leave it masked (mask_off_strip), as flt_recon_push_flagged
    // and flt_recon_pull do.
    std::vector<std::uint8_t> off_strip_bits_, off_strip_any_;
    std::size_t off_strip_stride_ = 0;
    std::vector<std::uint8_t> push_valid_;  // [K_] the row's mask for the engine
    std::size_t meta_head_ = 0, meta_count_ = 0;
    // Held rows: the strip may have left (always emptied whole).
    std::vector<double> held_s_, held_height_, held_slope_;
    std::vector<std::uint8_t> held_flags_;
    std::vector<row_meta> held_meta_;
    std::size_t held_ = 0;
    std::uint32_t pending_row_skipped_ = 0, pending_row_dropped_ = 0, pending_row_missing_ = 0;
    bool has_last_seen_ = false;
    double last_seen_s_ = 0.0;  // the s of the last frame sequenced
    static constexpr std::size_t k_pull_rows = 64;
    std::vector<double> pull_s_, pull_z_;
    std::vector<std::uint8_t> pull_flags_;

    // ---- evaluation state (the thread holding the evaluating role)
    std::shared_ptr<sheet_pool> pool_;
    // The evaluation's blocks (flatness per fiber block, straightedge
    // lines per block) on the workers: the runner the components are
    // given, and the open task (under m_; one at a time: only the
    // evaluating role opens one). Participants: the evaluating thread and
    // every worker, so scratch is made for workers + 1.
    class worker_blocks final : public block_runner {
      public:
        explicit worker_blocks(gauge &g) : g_(&g) {}
        void run(std::size_t blocks, block_fn fn, void *context) override {
            g_->run_block_task(blocks, fn, context);
        }
        unsigned participants() const override { return g_->cfg_.workers + 1; }

      private:
        gauge *g_;
    };
    worker_blocks blocks_{*this};
    struct block_task {
        block_runner::block_fn fn = nullptr;
        void *context = nullptr;
        std::size_t blocks = 0, next = 0, done = 0;
        unsigned joined = 0;  // participants so far (each names its scratch)
        bool open = false;    // workers may join
        std::exception_ptr error;
    };
    block_task block_task_;
    std::condition_variable blocks_cv_;  // the open task's last block is done

    // ---- verdicts: the rules in force (replaced whole by set_rules) and
    // the coils' statistics, each under its own mutex (never both held by
    // the evaluation; set_rules takes stats_m_ then rules_m_).
    mutable std::mutex rules_m_, stats_m_;
    std::shared_ptr<verdict_config> verdict_;
    std::uint64_t rules_generation_ = 0;
    coil_stats coil_current_, coil_last_;

    // ---- output
    std::mutex deliver_m_;
    flt_sheet_callback callback_ = nullptr;
    void *callback_user_ = nullptr;

    // ---- the quality record. Coils and notes given wait (with the seq of
    // the next frame, as cuts do) until the sequencer reaches them; the
    // recorder and the archive are attached while the gauge is idle and
    // read by the roles (under m_ when they take them).
    struct coil_entry {
        std::uint64_t seq;
        std::shared_ptr<flt_coil_info> info;  // null: no identity
    };
    struct note_entry {
        std::uint64_t seq;
        sheet_note note;
    };
    std::deque<coil_entry> coils_pending_;                   // under m_
    std::deque<note_entry> notes_pending_;                   // under m_
    std::shared_ptr<flt_coil_info> strip_coil_, next_coil_;  // sequencer
    bool next_coil_given_ = false;                           // sequencer
    std::vector<sheet_note> open_notes_;                     // sequencer
    record::recorder *recorder_ = nullptr;
    flt_recorder *recorder_handle_ = nullptr;
    std::uint64_t rec_seq0_ = 0;  // the seq of the recording's row 0
    record::archive *archive_ = nullptr;
    flt_archive *archive_handle_ = nullptr;
    void apply_pending(std::uint64_t up_to_seq, double s);
    void record_row(frame_slot &slot);
    void archive_sheet(const flt_sheet &sh, const sheet_buffer &b, std::size_t n);
    void flush_from_producer();
    // With m_ held through `lock` and the queue drained: takes the
    // sequencing role, ends the strip as a flush does (pending cuts first,
    // the last sheet flagged FLT_SHEET_FLAG_FLUSHED) and gives the role
    // back. False when that failed (record_failure has the reason).
    bool end_strip_flushed(std::unique_lock<std::mutex> &lock);
    void replay_events(const sources::recorded_frame &r);
    std::int64_t recorded_row(std::uint64_t seq) const {
        return std::int64_t(seq) - std::int64_t(rec_seq0_);
    }

    // ---- acquisition
    flt_source *source_ = nullptr;
    std::thread acquisition_;
    bool acquiring_ = false, acquisition_stop_ = false, source_started_ = false;
    flt_status acquisition_status_ = FLT_OK;
    std::string acquisition_message_;

    std::vector<std::thread> workers_;
};

// True on a thread inside this gauge's callback (flush, stop, destroy,
// next_sheet and set_callback refuse there).
bool in_gauge_callback(const gauge *g);

}  // namespace flt
