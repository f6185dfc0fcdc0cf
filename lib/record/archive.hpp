// SPDX-License-Identifier: Apache-2.0
// Internal: the archive (flt_archive): a queue of sheets and a writer
// thread that stores them, keeps them while the database is away and
// tries again, and applies the retention limits.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "flatline/record.h"
#include "record/archive_format.hpp"
#include "record/database.hpp"

namespace flt::record {

class archive {
  public:
    archive(const std::string &location, const std::string &line, const flt_options *options);
    ~archive();
    archive(const archive &) = delete;
    archive &operator=(const archive &) = delete;

    // Queues a sheet. When archive_buffer_mb would be exceeded the sheet is
    // not kept: counted lost, false returned (the caller logs it).
    bool add(std::unique_ptr<sheet_record> sheet);
    flt_status flush(const char *fn, std::uint32_t timeout_ms);
    flt_status prune(const char *fn, std::uint64_t *removed);
    std::uint64_t count(flt_archive_counter which) const;
    int backend() const { return backend_; }
    bool wants_maps() const { return maps_; }
    double map_quantum() const { return map_quantum_; }
    const std::string &line() const { return line_; }
    // The last failure of the database ("" when none), for the log.
    std::string last_error() const;

    // A gauge that archives into this archive (one at a time).
    std::atomic<const void *> owner{nullptr};

  private:
    void writer_main();
    void store(sheet_record &r);

    std::unique_ptr<database> db_;
    std::string line_;
    int backend_ = 0;
    double retention_days_ = 0, retention_mb_ = 0, map_quantum_ = 0.001;
    std::size_t buffer_bytes_ = 0;
    std::chrono::milliseconds retry_{1000}, close_timeout_{10000};
    bool maps_ = true;

    mutable std::mutex m_;
    std::condition_variable cv_, done_cv_;
    std::deque<std::unique_ptr<sheet_record>> pending_;
    std::size_t pending_bytes_ = 0;
    bool stop_ = false, prune_requested_ = false, in_store_ = false;
    std::uint64_t prune_generation_ = 0, pruned_generation_ = 0, prune_removed_ = 0;
    flt_status prune_status_ = FLT_OK;
    std::string last_error_;
    std::uint64_t given_ = 0, stored_ = 0, lost_ = 0, failures_ = 0, reconnects_ = 0, pruned_ = 0,
                  bytes_ = 0, since_prune_ = 0;
    std::uint64_t failing_since_ = 0;  // failures_ at the first failure of a run; 0: fine
    std::thread writer_;
};

}  // namespace flt::record

struct flt_archive {
    std::uint32_t magic = 0x41524348u;  // "ARCH"
    std::unique_ptr<flt::record::archive> impl;
};
