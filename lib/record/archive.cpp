// SPDX-License-Identifier: Apache-2.0
// The archive's writer: sheets wait in memory (bounded by
// archive_buffer_mb) until the database took them; a failure keeps the
// sheet at the head of the queue, drops the connection and tries again
// every archive_retry_interval, so a PostgreSQL server that restarts loses
// nothing.
#include "record/archive.hpp"

#include <chrono>

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/number_text.hpp"
#include "core/options.hpp"
#include "record/recorder.hpp"  // utc_now_ns

namespace flt::record {

archive::archive(const std::string &location, const std::string &line, const flt_options *options)
    : line_(line) {
    retention_days_ = option_value(options, FLT_OPT_ARCHIVE_RETENTION_DAYS);
    retention_mb_ = option_value(options, FLT_OPT_ARCHIVE_RETENTION_MB);
    buffer_bytes_ = std::size_t(option_value(options, FLT_OPT_ARCHIVE_BUFFER_MB)) << 20;
    retry_ = std::chrono::milliseconds(long(option_value(options, FLT_OPT_ARCHIVE_RETRY_INTERVAL)));
    close_timeout_ =
        std::chrono::milliseconds(long(option_value(options, FLT_OPT_ARCHIVE_CLOSE_TIMEOUT)));
    map_quantum_ = option_value(options, FLT_OPT_ARCHIVE_MAP_QUANTUM);
    maps_ = option_value(options, FLT_OPT_ARCHIVE_MAPS) != 0.0;
    if (is_postgres_location(location)) {
        db_ = open_postgres(location);
        backend_ = 1;
    } else {
        db_ = open_sqlite(location);
    }
    db_->connect();
    ensure_archive_schema(*db_);
    if (retention_days_ > 0 || retention_mb_ > 0)
        pruned_ += prune_archive(*db_, retention_days_, retention_mb_, utc_now_ns());
    {
        std::unique_lock<std::mutex> lock(m_);
        cv_.wait_for(lock, std::chrono::nanoseconds(0));
        done_cv_.wait_for(lock, std::chrono::nanoseconds(0));
    }
    writer_ = std::thread([this] { writer_main(); });
}

archive::~archive() {
    {
        std::lock_guard<std::mutex> lock(m_);
        stop_ = true;
    }
    cv_.notify_all();
    if (writer_.joinable())
        writer_.join();
}

bool archive::add(std::unique_ptr<sheet_record> sheet) {
    const std::size_t bytes = sheet->bytes();
    {
        std::lock_guard<std::mutex> lock(m_);
        ++given_;
        if (pending_bytes_ + bytes > buffer_bytes_) {
            ++lost_;
            return false;  // the caller logs it, with the sheet's number
        }
        pending_bytes_ += bytes;
        pending_.push_back(std::move(sheet));
    }
    cv_.notify_one();
    return true;
}

void archive::store(sheet_record &r) {
    db_->execute("BEGIN");
    try {
        write_sheet(*db_, line_, r);
        db_->execute("COMMIT");
    } catch (...) {
        try {
            if (db_->connected())
                db_->execute("ROLLBACK");
        } catch (...) {
        }
        throw;
    }
}

void archive::writer_main() {
    using clock = std::chrono::steady_clock;
    std::unique_lock<std::mutex> lock(m_);
    clock::time_point stop_since{};
    bool stopping_seen = false;
    for (;;) {
        if (stop_ && !stopping_seen) {
            stopping_seen = true;
            stop_since = clock::now();
        }
        if (prune_requested_) {
            prune_requested_ = false;
            const std::uint64_t gen = prune_generation_;
            lock.unlock();
            flt_status st = FLT_OK;
            std::uint64_t removed = 0;
            std::string why;
            try {
                db_->connect();
                removed = prune_archive(*db_, retention_days_, retention_mb_, utc_now_ns());
            } catch (const error &e) {
                st = e.status;
                why = e.what();
                if (db_->lost_connection())
                    db_->disconnect();
            }
            lock.lock();
            pruned_ += removed;
            prune_removed_ = removed;
            prune_status_ = st;
            if (st != FLT_OK)
                last_error_ = why;
            pruned_generation_ = gen;
            done_cv_.notify_all();
            continue;
        }
        if (pending_.empty()) {
            if (stop_)
                break;
            cv_.wait(lock);
            continue;
        }
        if (stop_ && clock::now() - stop_since > close_timeout_) {
            // Closing, and the database is still away: what is left is lost.
            const unsigned long long left = pending_.size();
            lock.unlock();
            FLT_LOG(FLT_LOG_ERROR, "archive",
                    "closing: %llu sheets could not be stored within archive_close_timeout (%s): "
                    "they are lost",
                    left, last_error_.c_str());
            lock.lock();
            lost_ += pending_.size();
            pending_.clear();
            pending_bytes_ = 0;
            done_cv_.notify_all();
            break;
        }
        sheet_record &r = *pending_.front();
        in_store_ = true;
        lock.unlock();
        bool ok = false;
        std::string why;
        bool reconnected = false;
        try {
            if (!db_->connected()) {
                db_->connect();
                reconnected = true;
            }
            store(r);
            ok = true;
        } catch (const error &e) {
            why = e.what();
            if (db_->lost_connection() || !db_->connected())
                db_->disconnect();
        } catch (const std::exception &e) {
            why = e.what();
        }
        lock.lock();
        in_store_ = false;
        if (reconnected)
            ++reconnects_;
        if (ok && failing_since_ > 0) {
            // The database is back: say so, with what it cost.
            const unsigned long long attempts = failures_ - failing_since_ + 1,
                                     waiting = pending_.size();
            failing_since_ = 0;
            lock.unlock();
            FLT_LOG(FLT_LOG_WARNING, "archive",
                    "the database takes sheets again after %llu failed attempts%s; %llu sheets "
                    "that waited in memory are being stored",
                    attempts, reconnected ? " (connected again)" : "", waiting);
            lock.lock();
        }
        if (ok) {
            pending_bytes_ -= r.bytes();
            bytes_ += r.bytes();
            const bool ends_coil = r.ends_coil;
            pending_.pop_front();
            ++stored_;
            ++since_prune_;
            if ((retention_days_ > 0 || retention_mb_ > 0) && (ends_coil || since_prune_ >= 64)) {
                since_prune_ = 0;
                ++prune_generation_;
                prune_requested_ = true;
            }
            done_cv_.notify_all();
            continue;
        }
        ++failures_;
        last_error_ = why;
        done_cv_.notify_all();
        if (failing_since_ == 0) {
            failing_since_ = failures_;
            const unsigned long long waiting = pending_.size();
            const long long retry_ms = retry_.count();
            lock.unlock();
            FLT_LOG(FLT_LOG_WARNING, "archive",
                    "the database does not take sheets (%s): %llu sheets wait in memory "
                    "(archive_buffer_mb), trying again every %lld ms",
                    why.c_str(), waiting, retry_ms);
            lock.lock();
        }
        // Try again after the retry interval (sooner when closing ends).
        cv_.wait_for(lock, retry_);
    }
}

flt_status archive::flush(const char *fn, std::uint32_t timeout_ms) {
    std::unique_lock<std::mutex> lock(m_);
    const bool done = done_cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                                        [&] { return pending_.empty() && !in_store_; });
    if (done)
        return FLT_OK;
    return fail(FLT_ERR_TIMEOUT, "%s: %zu sheets still wait after %u ms; the database said: %s", fn,
                pending_.size(), timeout_ms,
                last_error_.empty() ? "(nothing)" : last_error_.c_str());
}

flt_status archive::prune(const char *fn, std::uint64_t *removed) {
    std::unique_lock<std::mutex> lock(m_);
    const std::uint64_t want = ++prune_generation_;
    prune_requested_ = true;
    cv_.notify_all();
    done_cv_.wait(lock, [&] { return pruned_generation_ >= want; });
    if (removed)
        *removed = prune_removed_;
    if (prune_status_ != FLT_OK)
        return fail(prune_status_, "%s: %s", fn, last_error_.c_str());
    return FLT_OK;
}

std::string archive::last_error() const {
    std::lock_guard<std::mutex> lock(m_);
    return last_error_;
}

std::uint64_t archive::count(flt_archive_counter which) const {
    std::lock_guard<std::mutex> lock(m_);
    switch (which) {
        case FLT_ARCHIVE_COUNT_SHEETS:
            return given_;
        case FLT_ARCHIVE_COUNT_STORED:
            return stored_;
        case FLT_ARCHIVE_COUNT_PENDING:
            return pending_.size();
        case FLT_ARCHIVE_COUNT_LOST:
            return lost_;
        case FLT_ARCHIVE_COUNT_FAILURES:
            return failures_;
        case FLT_ARCHIVE_COUNT_RECONNECTS:
            return reconnects_;
        case FLT_ARCHIVE_COUNT_PRUNED:
            return pruned_;
        case FLT_ARCHIVE_COUNT_BYTES:
            return bytes_;
        case FLT_ARCHIVE_COUNT_PENDING_BYTES:
            return pending_bytes_;
        default:
            return 0;
    }
}

}  // namespace flt::record
