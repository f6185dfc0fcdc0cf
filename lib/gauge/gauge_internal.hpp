// SPDX-License-Identifier: Apache-2.0
// Internal to lib/gauge: what the gauge's stages share (the stage timer,
// the failure guard, small helpers). Each stage is one file:
// gauge_acquisition.cpp (the producer), gauge_workers.cpp (the roles and
// the extraction), gauge_sequencer.cpp (reconstruction and sheets in frame
// order), gauge_evaluation.cpp (flatness, verdicts, coil statistics);
// gauge.cpp makes the gauge and answers the calls. README.md has the
// picture.
#pragma once

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
#include "extraction/extractor_internal.hpp"
#include "flatline/extractor.h"
#include "flatness/flatness_internal.hpp"
#include "flatline/source.h"
#include "reconstruction/recon_internal.hpp"
#include "sources/source_handle.hpp"

namespace flt {
namespace gauge_detail {

inline constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();
// The reconstructor refuses larger jumps between rows (recon_api.cpp): it
// would have to bridge them knot by knot.
inline constexpr double k_recon_max_jump_mm = 1.0e6, k_recon_max_jump_knots = 1000.0;
// gauge_queue_frames 0 (the default): as many frame slots (width x height
// x 2 bytes each) as fit in k_queue_bytes, at least k_queue_min and at most
// k_queue_max (the option's own limit).
inline constexpr std::size_t k_queue_bytes = std::size_t(256) << 20;  // 256 MiB
inline constexpr std::size_t k_queue_min = 16, k_queue_max = 4096;

// The gauge whose callback runs on this thread (in_gauge_callback).
inline thread_local const void *t_in_callback = nullptr;

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
    static inline thread_local stage_timer *current_ = nullptr;
    std::atomic<std::uint64_t> &total_;
    stage_timer *outer_;
    std::chrono::steady_clock::time_point t0_;
    std::uint64_t nested_ = 0;
};

// A failed call of another component: its status and message, as an
// exception the gauge's guards turn back into them.
inline void check(flt_status st) {
    if (st != FLT_OK)
        throw error(st, flt_last_error_message());
}

inline void set_option(flt_options &bag, flt_option key, double value) {
    check(flt_options_set(&bag, key, value));
}

inline int bytes_per_pixel(flt_pixel_format format) {
    return format == FLT_PIXEL_MONO8 ? 1 : 2;
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

}  // namespace gauge_detail
}  // namespace flt
