// SPDX-License-Identifier: Apache-2.0
// The recording writer: the producer fills blocks of rows under a mutex
// (quantizing as it goes, no allocation), the writer thread encodes closed
// blocks and commits them with the events before them, at least every
// record_commit_interval.
#include "record/recorder.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/number_text.hpp"
#include "core/options.hpp"
#include "core/utf8_path.hpp"
#include "flatline/recon.h"
#include "record/codec.hpp"

namespace flt::record {
namespace {

void check(flt_status st) {
    if (st != FLT_OK)
        throw error(st, flt_last_error_message());
}

std::string calib_text(const flt_calib *calib) {
    std::size_t length = 0;
    flt_status st = flt_calib_save_text(calib, nullptr, 0, &length);
    if (st != FLT_OK && st != FLT_ERR_BUFFER_FULL)
        check(st);
    std::string text(length + 1, '\0');
    check(flt_calib_save_text(calib, text.data(), text.size(), &length));
    text.resize(length);
    clear_error();
    return text;
}

int bytes_per_pixel(flt_pixel_format f) {
    return f == FLT_PIXEL_MONO8 ? 1 : 2;
}

}  // namespace

std::int64_t utc_now_ns() {
    return std::int64_t(std::chrono::duration_cast<std::chrono::nanoseconds>(
                            std::chrono::system_clock::now().time_since_epoch())
                            .count());
}

recorder::recorder(const std::string &path, const flt_calib *calib, const flt_options *options) {
    int finished = 0;
    check(flt_calib_is_finished(calib, &finished));
    if (!finished)
        throw error(FLT_ERR_STATE, "the calibration is not finished (flt_calib_finish)");
    double first_x = 0.0, pitch = 0.0;
    check(flt_calib_get_fiber_grid(calib, &first_x, &pitch, &K_));
    check(flt_calib_laser_spacing(calib, &spacing_));
    std::uint32_t frame_w = 0, frame_h = 0;
    check(flt_calib_get_frame_size(calib, &frame_w, &frame_h));

    quantum_ = option_value(options, FLT_OPT_RECORD_QUANTUM);
    if (!is_power_of_two(quantum_)) {
        char why[200];
        format_c(why, sizeof why,
                 "record_quantum is %g mm: it must be a power of two (2^-8 = 0.00390625, 2^-10 "
                 "= 0.0009765625, ...) so that a replay is exact",
                 quantum_);
        throw error(FLT_ERR_INVALID_ARGUMENT, why);
    }
    commit_interval_ =
        std::chrono::milliseconds(long(option_value(options, FLT_OPT_RECORD_COMMIT_INTERVAL)));
    block_rows_ = std::size_t(option_value(options, FLT_OPT_RECORD_BLOCK_ROWS));
    const std::size_t queue = std::size_t(option_value(options, FLT_OPT_RECORD_QUEUE_BLOCKS));
    const bool sync_full = option_value(options, FLT_OPT_RECORD_SYNC) != 0.0;
    frames_mode_ = int(option_value(options, FLT_OPT_RECORD_FRAMES));
    frame_seconds_ = option_value(options, FLT_OPT_RECORD_FRAME_SECONDS);
    frame_bytes_limit_ = std::size_t(option_value(options, FLT_OPT_RECORD_FRAME_MB)) << 20;
    frames_on_fail_ = option_value(options, FLT_OPT_RECORD_FRAMES_ON_FAIL) != 0.0;
    {
        // What the buffers take, refused beyond 8 GiB before anything is made.
        const double bytes = double(queue + 2) * double(block_rows_) * double(K_) * 9.0;
        if (bytes > 8.0 * 1024 * 1024 * 1024)
            throw error(FLT_ERR_INVALID_ARGUMENT,
                        "the recorder's blocks would take more than 8 GiB: lower "
                        "record_queue_blocks or record_block_rows");
    }

    db_ = std::make_unique<sqlite_db>(path, sqlite_db::mode::create_new);
    try {
        // Large pages: a block is a few hundred KiB. WAL: a killed writer
        // leaves the last commit intact, and readers read while it writes.
        db_->exec("PRAGMA page_size = 65536");
        db_->exec("PRAGMA journal_mode = WAL");
        db_->exec(sync_full ? "PRAGMA synchronous = FULL" : "PRAGMA synchronous = NORMAL");
        db_->exec("PRAGMA application_id = 1179407442");  // "FLTR"
        db_->exec("BEGIN");
        db_->exec(k_recording_schema);
        db_->exec("PRAGMA user_version = 1");
        sqlite_statement meta(*db_, "INSERT INTO meta (key, value) VALUES (?1, ?2)");
        const std::pair<const char *, std::string> rows[] = {
            {"format", "flatline-recording"},
            {"version", std::to_string(k_recording_version)},
            {"library", flt_version_string()},
            {"created_ns", std::to_string(utc_now_ns())},
            {"fibers", std::to_string(K_)},
            {"quantum_mm", format_double(quantum_)},
            {"laser_spacing_mm", format_double(spacing_)},
            {"fiber_first_x_mm", format_double(first_x)},
            {"fiber_pitch_mm", format_double(pitch)},
            {"frame_width", std::to_string(frame_w)},
            {"frame_height", std::to_string(frame_h)},
            {"calibration", calib_text(calib)},
        };
        for (const auto &r : rows)
            meta.bind(1, std::string(r.first)).bind(2, r.second).run();
        db_->exec("COMMIT");
    } catch (...) {
        db_.reset();
        remove_file(path);
        remove_file(path + "-wal");
        remove_file(path + "-shm");
        throw;
    }

    blocks_.reserve(queue + 2);
    for (std::size_t i = 0; i < queue + 2; ++i) {
        blocks_.push_back(std::make_unique<row_block>());
        blocks_.back()->allocate(K_, block_rows_);
        free_.push_back(blocks_.back().get());
    }
    closed_.reserve(queue + 2);
    scratch_flags_.assign(K_, 0);
    scratch_q_[0].assign(K_, 0);
    scratch_q_[1].assign(K_, 0);
    if (frames_mode_ != FLT_RECORD_FRAMES_NONE) {
        const std::size_t frame_bytes = std::size_t(frame_w) * frame_h * 2;
        const std::size_t slots = std::max<std::size_t>(2, frame_bytes_limit_ / frame_bytes);
        frame_ring_.resize(slots);  // each slot's pixels are made at its first frame
    }
    // The thread's first use of the mutex and condition variables happens
    // here (see lib/gauge/README.md: winpthreads makes them on first use).
    {
        std::unique_lock<std::mutex> lock(m_);
        writer_cv_.wait_for(lock, std::chrono::nanoseconds(0));
        done_cv_.wait_for(lock, std::chrono::nanoseconds(0));
    }
    writer_ = std::thread([this] { writer_main(); });
}

recorder::~recorder() {
    {
        std::lock_guard<std::mutex> lock(m_);
        stop_ = true;
    }
    writer_cv_.notify_all();
    if (writer_.joinable())
        writer_.join();
    if (db_) {
        // Fold the WAL into the file: the recording is one file again.
        try {
            db_->exec("PRAGMA wal_checkpoint(TRUNCATE)");
        } catch (...) {
        }
    }
}

row_block *recorder::open_block_locked() {
    if (open_ && open_->rows < open_->capacity)
        return open_;
    if (open_) {
        closed_.push_back(open_);
        open_ = nullptr;
        writer_cv_.notify_one();
    }
    if (free_.empty() || failed_)
        return nullptr;
    open_ = free_.back();
    free_.pop_back();
    open_->rows = 0;
    open_->first_row = rows_given_;
    open_since_ = std::chrono::steady_clock::now();
    writer_cv_.notify_one();  // the writer times the new block
    return open_;
}

void recorder::add_row(const row_in &row, const double *height, const double *slope,
                       const std::uint8_t *flags, const std::uint8_t *valid, double *height_out,
                       double *slope_out, std::uint8_t *flags_out) {
    const double half = 0.5 * spacing_, inverse = 1.0 / quantum_;
    std::unique_lock<std::mutex> lock(m_);
    row_block *b = open_block_locked();
    const std::uint64_t number = rows_given_++;
    std::uint8_t *state = nullptr;
    std::int32_t *qb = nullptr, *qa = nullptr;
    std::size_t r = 0;
    if (b) {
        if (lost_run_ > 0) {
            event e;
            e.kind = 3;
            e.before_row = std::int64_t(lost_run_start_);
            e.count = lost_run_;
            e.time_ns = row.time_ns;
            lost_run_ = 0;
            // A gap event needs no allocation beyond the deque's own.
            events_.push_back(std::move(e));
        }
        r = b->rows;
        if (r == 0)
            b->first_row = number;
        b->encoder_mm[r] = row.encoder_mm;
        b->time_ns[r] = row.time_ns;
        b->left_mm[r] = row.left_mm;
        b->right_mm[r] = row.right_mm;
        b->saturated[r] = row.saturated;
        b->peaks[r] = row.peaks;
        b->skipped_stop[r] = row.skipped_stop;
        b->skipped_reversal[r] = row.skipped_reversal;
        b->dropped[r] = row.dropped;
        b->missing[r] = row.missing;
        b->row_flags[r] = row.row_flags;
        b->strip_flags[r] = row.strip_flags;
        state = &b->state[r * K_];
        qb = &b->q[0][r * K_];
        qa = &b->q[1][r * K_];
        ++b->rows;
    } else {
        if (lost_run_ == 0)
            lost_run_start_ = number;
        ++lost_run_;
        ++rows_lost_;
        if (lost_run_ == 1) {
            const unsigned long long lost = rows_lost_;
            const bool failed = failed_;
            // The lock is this recorder's own: no callback can need it.
            FLT_LOG(FLT_LOG_WARNING, "record",
                    "rows are not recorded from row %llu on: %s (%llu rows lost so far; the gap is "
                    "marked in the file)",
                    (unsigned long long)number,
                    failed ? "the writer stopped on an error"
                           : "the writer is behind by record_queue_blocks blocks",
                    lost);
        }
    }
    // Under the lock: the writer's timer may close the open block (a few
    // microseconds per row; the writer takes the lock rarely).
    // Per fiber: its flag, then both lasers' quantized heights (0 where
    // not measured), each in its own simple loop.
    std::uint8_t *f_out = flags_out ? flags_out : scratch_flags_.data();
    for (std::size_t k = 0; k < K_; ++k) {
        std::uint8_t f;
        if (flags)
            f = flags[k];
        else
            f = (valid == nullptr || valid[k] != 0) && std::isfinite(height[k]) &&
                        std::isfinite(slope[k])
                    ? 0
                    : std::uint8_t(FLT_FLAG_INVALID_INPUT);
        if (f == 0) {
            const double zb = height[k] - slope[k] * half, za = height[k] + slope[k] * half;
            if (!(std::fabs(zb) <= k_max_height_mm && std::fabs(za) <= k_max_height_mm))
                f = FLT_FLAG_INVALID_INPUT;  // beyond any sensor: not measured
        }
        f_out[k] = f;
    }
    std::int32_t *q0 = qb ? qb : scratch_q_[0].data(), *q1 = qa ? qa : scratch_q_[1].data();
    for (std::size_t k = 0; k < K_; ++k) {
        const bool used = f_out[k] == 0;
        const double hk = used ? height[k] : 0.0, sk = used ? slope[k] : 0.0;
        q0[k] = quantize(hk - sk * half, inverse);
        q1[k] = quantize(hk + sk * half, inverse);
    }
    if (height_out || slope_out)
        for (std::size_t k = 0; k < K_; ++k) {
            double h = height[k], sl = slope[k];
            if (f_out[k] == 0)
                dequantize(q0[k], q1[k], quantum_, spacing_, &h, &sl);
            if (height_out)
                height_out[k] = h;
            if (slope_out)
                slope_out[k] = sl;
        }
    if (state)
        for (std::size_t k = 0; k < K_; ++k) {
            const bool v = valid ? valid[k] != 0 : f_out[k] == 0;
            state[k] = std::uint8_t(f_out[k] | (v ? k_state_valid : 0));
        }
    if (b && b->rows == b->capacity) {
        closed_.push_back(b);
        open_ = nullptr;
        lock.unlock();
        writer_cv_.notify_one();
    }
}

void recorder::push_event(event &&e) {
    std::lock_guard<std::mutex> lock(m_);
    if (e.before_row < 0)
        e.before_row = std::int64_t(rows_given_);
    e.time_ns = utc_now_ns();
    events_.push_back(std::move(e));
}

void recorder::add_cut(double encoder_mm, std::int64_t before_row) {
    event e;
    e.kind = 0;
    e.encoder_mm = encoder_mm;
    e.before_row = before_row;
    push_event(std::move(e));
}

void recorder::add_coil(const flt_coil_info &coil, std::int64_t before_row) {
    event e;
    e.kind = 1;
    e.coil = std::make_unique<flt_coil_info>(coil);
    e.coil->lent = false;
    e.before_row = before_row;
    push_event(std::move(e));
}

void recorder::add_flush(std::int64_t before_row) {
    event e;
    e.kind = 2;
    e.before_row = before_row;
    push_event(std::move(e));
}

void recorder::add_note(const std::string &kind, const std::string &text, std::int64_t before_row) {
    event e;
    e.kind = 4;
    e.label = kind;
    e.text = text;
    e.before_row = before_row;
    push_event(std::move(e));
}

void recorder::set_gauge_options(const flt_options &effective) {
    std::vector<std::pair<int, double>> values;
    flt_option key;
    for (std::size_t i = 0; flt_option_at(i, &key) == FLT_OK; ++i) {
        const int hundreds = int(key) / 100;
        // The gauge's bag: the reconstructor's, the extractor's, the
        // flatness metrics' and its own keys.
        if (hundreds != 1 && hundreds != 4 && hundreds != 5 && hundreds != 7)
            continue;
        // lag_knots and latency_mm are one setting in two units, refused
        // when both are set: only the one the caller gave is recorded
        // (neither: the reconstructor's default, as live). Every other key
        // is recorded with its value, set or default, so that a replay
        // runs with the live values whatever a later version's defaults.
        if ((key == FLT_OPT_LAG_KNOTS || key == FLT_OPT_LATENCY_MM) &&
            !option_is_set(&effective, key))
            continue;
        values.emplace_back(int(key), option_value(&effective, key));
    }
    clear_error();
    std::lock_guard<std::mutex> lock(m_);
    gauge_options_.swap(values);
    options_pending_ = true;
    writer_cv_.notify_one();
}

void recorder::add_frame(const void *pixels, flt_pixel_format format, std::uint32_t width,
                         std::uint32_t height, std::size_t stride, double encoder_mm,
                         std::uint64_t row) {
    if (frames_mode_ == FLT_RECORD_FRAMES_NONE || frame_ring_.empty())
        return;
    const std::size_t row_bytes = std::size_t(width) * std::size_t(bytes_per_pixel(format));
    const std::int64_t now = utc_now_ns();
    std::unique_lock<std::mutex> lock(m_);
    // Ring: the oldest frame goes when the ring is full or it is older than
    // record_frame_seconds; "all": a full ring loses the frame.
    const std::size_t N = frame_ring_.size();
    if (frames_mode_ == FLT_RECORD_FRAMES_RING) {
        while (frame_count_ > 0) {
            frame_entry &old = frame_ring_[frame_head_];
            const bool too_old = double(now - old.time_ns) > frame_seconds_ * 1e9;
            if ((frame_count_ < N && !too_old) || old.used)
                break;
            frame_head_ = (frame_head_ + 1) % N;
            --frame_count_;
        }
    }
    if (frame_count_ == N || frame_ring_[(frame_head_ + frame_count_) % N].used) {
        ++frames_lost_;
        return;
    }
    frame_entry &f = frame_ring_[(frame_head_ + frame_count_) % N];
    f.used = true;  // the writer leaves it alone while this copies
    lock.unlock();
    f.pixels.resize(row_bytes * height);  // allocates at a slot's first frame only
    const auto *src = static_cast<const std::uint8_t *>(pixels);
    for (std::uint32_t v = 0; v < height; ++v)
        std::memcpy(f.pixels.data() + v * row_bytes, src + v * stride, row_bytes);
    f.format = format;
    f.width = width;
    f.height = height;
    f.encoder_mm = encoder_mm;
    f.time_ns = now;
    f.row = row;
    lock.lock();
    f.used = false;
    ++frame_count_;
    if (frames_mode_ == FLT_RECORD_FRAMES_ALL) {
        lock.unlock();
        writer_cv_.notify_one();
    }
}

void recorder::save_frames() {
    {
        std::lock_guard<std::mutex> lock(m_);
        save_frames_requested_ = true;
    }
    writer_cv_.notify_one();
}

flt_status recorder::sync(const char *fn, std::uint32_t timeout_ms) {
    std::unique_lock<std::mutex> lock(m_);
    if (failed_)
        return fail(failure_status_, "%s: the recorder stopped writing: %s", fn,
                    failure_message_.c_str());
    const std::uint64_t want = ++sync_generation_;
    sync_requested_ = true;
    writer_cv_.notify_one();
    const bool ok = done_cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                                      [&] { return committed_generation_ >= want || failed_; });
    if (failed_)
        return fail(failure_status_, "%s: the recorder stopped writing: %s", fn,
                    failure_message_.c_str());
    if (!ok)
        return fail(FLT_ERR_TIMEOUT, "%s: not everything was committed within %u ms", fn,
                    timeout_ms);
    return FLT_OK;
}

flt_status recorder::failure(const char *fn) const {
    std::lock_guard<std::mutex> lock(m_);
    if (!failed_)
        return FLT_OK;
    return fail(failure_status_, "%s: the recorder stopped writing: %s", fn,
                failure_message_.c_str());
}

std::uint64_t recorder::rows_given() const {
    std::lock_guard<std::mutex> lock(m_);
    return rows_given_;
}

std::uint64_t recorder::count(flt_recorder_counter which) const {
    switch (which) {
        case FLT_RECORDER_COUNT_ROWS: {
            std::lock_guard<std::mutex> lock(m_);
            return rows_given_;
        }
        case FLT_RECORDER_COUNT_ROWS_STORED:
            return rows_stored_.load();
        case FLT_RECORDER_COUNT_ROWS_LOST: {
            std::lock_guard<std::mutex> lock(m_);
            return rows_lost_;
        }
        case FLT_RECORDER_COUNT_BLOCKS:
            return blocks_stored_.load();
        case FLT_RECORDER_COUNT_COMMITS:
            return commits_.load();
        case FLT_RECORDER_COUNT_BYTES:
            return bytes_.load();
        case FLT_RECORDER_COUNT_SAMPLES:
            return samples_.load();
        case FLT_RECORDER_COUNT_FRAMES:
            return frames_stored_.load();
        case FLT_RECORDER_COUNT_FRAMES_LOST: {
            std::lock_guard<std::mutex> lock(m_);
            return frames_lost_;
        }
        case FLT_RECORDER_COUNT_EVENTS:
            return events_stored_.load();
        case FLT_RECORDER_COUNT_WRITER_NS:
            return writer_ns_.load();
        default:
            return 0;
    }
}

bool recorder::record_failure_locked(flt_status st, const char *message) {
    if (failed_)
        return false;
    failed_ = true;
    failure_status_ = st;
    failure_message_ = message;
    return true;
}

void recorder::writer_main() {
    std::vector<row_block *> blocks;
    std::vector<event> events;
    std::vector<frame_entry *> frames;
    blocks.reserve(blocks_.size());
    frames.reserve(frame_ring_.size());
    std::unique_lock<std::mutex> lock(m_);
    for (;;) {
        const auto due = open_since_ + commit_interval_;
        const bool open_due = open_ && open_->rows > 0 && std::chrono::steady_clock::now() >= due;
        const bool frames_due =
            (frames_mode_ == FLT_RECORD_FRAMES_ALL && frame_count_ > 0) || save_frames_requested_;
        const std::int64_t events_end =
            open_ ? std::int64_t(open_->first_row) : std::int64_t(rows_given_);
        const bool events_due = !events_.empty() && events_.front().before_row <= events_end;
        // Closed blocks wait for the next commit (one every
        // record_commit_interval: each costs a sync to the disk) unless
        // half the queue is taken.
        const auto commit_due = last_commit_ + commit_interval_;
        const bool closed_due =
            !closed_.empty() && (std::chrono::steady_clock::now() >= commit_due ||
                                 2 * closed_.size() >= blocks_.size());
        const bool work = closed_due || open_due || sync_requested_ || options_pending_ ||
                          frames_due || stop_ || events_due;
        if (!work || failed_) {
            if (stop_)
                break;
            if (!closed_.empty())
                writer_cv_.wait_until(lock, std::min(commit_due, due));
            else if (open_ && open_->rows > 0)
                writer_cv_.wait_until(lock, due);
            else
                writer_cv_.wait(lock);
            continue;
        }
        // Everything given so far that can be written: closed blocks, the
        // open one when it is due (or asked), events before the open block.
        if (open_ && open_->rows > 0 && (open_due || sync_requested_ || stop_)) {
            closed_.push_back(open_);
            open_ = nullptr;
        }
        blocks.assign(closed_.begin(), closed_.end());
        closed_.clear();
        const std::int64_t writable_end =
            open_ ? std::int64_t(open_->first_row) : std::int64_t(rows_given_);
        while (!events_.empty() && (events_.front().before_row <= writable_end || stop_)) {
            events.push_back(std::move(events_.front()));
            events_.pop_front();
        }
        frames.clear();
        if (frames_due) {
            for (std::size_t i = 0; i < frame_count_; ++i) {
                frame_entry &f = frame_ring_[(frame_head_ + i) % frame_ring_.size()];
                if (f.used)
                    break;
                f.used = true;
                frames.push_back(&f);
            }
            save_frames_requested_ = false;
        }
        const std::uint64_t generation = sync_generation_;
        sync_requested_ = false;
        const bool stopping = stop_;
        lock.unlock();
        const auto t0 = std::chrono::steady_clock::now();
        last_commit_ = t0;
        bool ok = true;
        // The failure is made known (sync returns, counters are read) only
        // once every row it loses is counted, under the same lock below.
        flt_status fail_status = FLT_OK;
        const char *fail_message = "out of memory";
        std::string fail_text;  // (allocates only on failure)
        try {
            write_round(blocks, events, frames);
        } catch (const error &e) {
            fail_status = e.status;
            fail_text = e.what();
            fail_message = fail_text.c_str();
            ok = false;
        } catch (const std::bad_alloc &) {
            fail_status = FLT_ERR_OUT_OF_MEMORY;
            ok = false;
        } catch (const std::exception &e) {
            fail_status = FLT_ERR_INTERNAL;
            fail_text = e.what();
            fail_message = fail_text.c_str();
            ok = false;
        }
        writer_ns_ += std::uint64_t(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::steady_clock::now() - t0)
                                        .count());
        events.clear();
        lock.lock();
        const bool newly_failed = !ok && record_failure_locked(fail_status, fail_message);
        for (row_block *b : blocks) {
            if (!ok)
                rows_lost_ += b->rows;
            b->rows = 0;
            free_.push_back(b);
        }
        blocks.clear();
        if (failed_) {
            // Nothing is written after a failure: the rows still waiting
            // (blocks closed while this round wrote, and the open one) are
            // lost now, and counted; later rows find no block and are
            // counted as they come. Left queued they would be neither
            // stored nor lost.
            for (row_block *b : closed_) {
                rows_lost_ += b->rows;
                b->rows = 0;
                free_.push_back(b);
            }
            closed_.clear();
            if (open_) {
                rows_lost_ += open_->rows;
                open_->rows = 0;
                free_.push_back(open_);
                open_ = nullptr;
            }
        }
        // Frames written leave the ring (they are the oldest).
        for (frame_entry *f : frames) {
            f->used = false;
            if (frame_count_ > 0 && &frame_ring_[frame_head_] == f) {
                frame_head_ = (frame_head_ + 1) % frame_ring_.size();
                --frame_count_;
            }
        }
        if (ok)
            committed_generation_ = std::max(committed_generation_, generation);
        done_cv_.notify_all();
        if (newly_failed) {  // logged without the lock: a log callback may call us
            lock.unlock();
            FLT_LOG(FLT_LOG_ERROR, "record",
                    "the recording stopped: %s (later rows are counted lost)", fail_message);
            lock.lock();
        }
        if (stopping && closed_.empty() && (!open_ || open_->rows == 0) && events_.empty())
            break;
    }
}

void recorder::write_round(std::vector<row_block *> &blocks, std::vector<event> &events,
                           std::vector<frame_entry *> &frames) {
    // Scratch kept across rounds: no allocation once grown.
    static thread_local block_scratch scratch;
    static thread_local std::vector<std::uint8_t> payload, pixels;
    db_->exec("BEGIN");
    try {
        if (options_pending_) {
            std::vector<std::pair<int, double>> values;
            {
                std::lock_guard<std::mutex> lock(m_);
                values = gauge_options_;
                options_pending_ = false;
            }
            db_->exec("DELETE FROM gauge_options");
            sqlite_statement ins(
                *db_, "INSERT INTO gauge_options (name, key, value) VALUES (?1, ?2, ?3)");
            for (const auto &kv : values) {
                const char *name = "";
                if (flt_option_info(flt_option(kv.first), &name, nullptr, nullptr, nullptr,
                                    nullptr) != FLT_OK)
                    continue;
                ins.bind(1, std::string(name))
                    .bind(2, std::int64_t(kv.first))
                    .bind(3, kv.second)
                    .run();
            }
        }
        std::uint64_t rows = 0, bytes = 0, samples = 0;
        if (!blocks.empty()) {
            sqlite_statement ins(*db_,
                                 "INSERT INTO blocks (first_row, rows, first_time_ns, "
                                 "last_time_ns, first_encoder_mm, last_encoder_mm, codec, crc32, "
                                 "payload) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)");
            for (row_block *b : blocks) {
                encode_block(*b, quantum_, scratch, payload);
                const std::size_t n = b->rows;
                ins.bind(1, std::int64_t(b->first_row))
                    .bind(2, std::int64_t(n))
                    .bind(3, b->time_ns[0])
                    .bind(4, b->time_ns[n - 1])
                    .bind(5, b->encoder_mm[0])
                    .bind(6, b->encoder_mm[n - 1])
                    .bind(7, std::int64_t(k_block_codec))
                    .bind(8, std::int64_t(crc32_of(payload.data(), payload.size())))
                    .bind_blob(9, payload.data(), payload.size())
                    .run();
                rows += n;
                bytes += payload.size();
                samples += n * K_;
            }
        }
        if (!events.empty()) {
            sqlite_statement ins(*db_, "INSERT INTO events (before_row, time_ns, kind, encoder_mm, "
                                       "count, label, text) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)");
            sqlite_statement coil(*db_,
                                  "INSERT INTO coils (event, coil_id, order_no, heat, grade, "
                                  "customer, nominal_thickness_mm, nominal_width_mm) VALUES (?1, "
                                  "?2, ?3, ?4, ?5, ?6, ?7, ?8)");
            sqlite_statement extra(
                *db_,
                "INSERT INTO coil_extras (event, position, key, value) VALUES (?1, ?2, ?3, ?4)");
            static const char *const kinds[] = {"cut", "coil", "flush", "gap", "note"};
            for (const event &e : events) {
                ins.bind(1, e.before_row).bind(2, e.time_ns).bind(3, std::string(kinds[e.kind]));
                if (e.kind == 0)
                    ins.bind(4, e.encoder_mm);
                if (e.kind == 3)
                    ins.bind(5, std::int64_t(e.count));
                if (e.kind == 4)
                    ins.bind(6, e.label).bind(7, e.text);
                ins.run();
                const std::int64_t id = db_->last_insert_rowid();
                if (e.kind == 1 && e.coil) {
                    coil.bind(1, id);
                    for (int f = 0; f < k_coil_fields; ++f)
                        coil.bind(2 + f, e.coil->text[f]);
                    coil.bind(7, e.coil->thickness_mm).bind(8, e.coil->width_mm).run();
                    for (std::size_t i = 0; i < e.coil->extras.size(); ++i)
                        extra.bind(1, id)
                            .bind(2, std::int64_t(i))
                            .bind(3, e.coil->extras[i].first)
                            .bind(4, e.coil->extras[i].second)
                            .run();
                }
            }
        }
        if (!frames.empty()) {
            sqlite_statement ins(*db_,
                                 "INSERT INTO frames (row, time_ns, encoder_mm, format, width, "
                                 "height, codec, crc32, pixels) VALUES (?1, ?2, ?3, ?4, ?5, ?6, "
                                 "1, ?7, ?8)");
            for (const frame_entry *f : frames) {
                pixels.clear();
                deflate_append(f->pixels.data(), f->pixels.size(), 1, pixels);
                ins.bind(1, std::int64_t(f->row))
                    .bind(2, f->time_ns)
                    .bind(3, f->encoder_mm)
                    .bind(4, std::int64_t(f->format))
                    .bind(5, std::int64_t(f->width))
                    .bind(6, std::int64_t(f->height))
                    .bind(7, std::int64_t(crc32_of(pixels.data(), pixels.size())))
                    .bind_blob(8, pixels.data(), pixels.size())
                    .run();
            }
        }
        db_->exec("COMMIT");
        rows_stored_ += rows;
        blocks_stored_ += blocks.size();
        bytes_ += bytes;
        samples_ += samples;
        events_stored_ += events.size();
        frames_stored_ += frames.size();
        ++commits_;
    } catch (...) {
        try {
            db_->exec("ROLLBACK");
        } catch (...) {
        }
        throw;
    }
}

}  // namespace flt::record
