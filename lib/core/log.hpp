// SPDX-License-Identifier: Apache-2.0
// Internal: logging (flatline/log.h). A place that logs writes
//
//     FLT_LOG(FLT_LOG_WARNING, "gauge", "sheet %llu: ...", ...);
//
// which costs one atomic load when nobody listens, and otherwise formats
// into the stack (no allocation) under the place's own rate limit. Never
// log while holding a lock the callback's own calls could need (a gauge's
// m_): the callback may call back into the library.
#pragma once

#include <atomic>
#include <cstdint>

#include "core/error.hpp"
#include "flatline/log.h"

namespace flt {

// One place that logs: its rate limit (5 messages per 10 s window).
struct log_site {
    const char *component;
    std::int64_t window_start_ms = -1;
    int passed = 0;
    std::uint32_t held_back = 0;
    std::uint64_t generation = 0;  // the callback installation it counted for
    explicit constexpr log_site(const char *c) : component(c) {}
};

// True when a callback listens at this level.
bool log_enabled(flt_log_level level);

void log_message(log_site &site, flt_log_level level, const char *format, ...)
    FLT_PRINTF_FORMAT(3, 4);

}  // namespace flt

#define FLT_LOG(level, component, ...)                       \
  do {                                                       \
    if (::flt::log_enabled(level)) {                         \
      static ::flt::log_site flt_log_site_{component};       \
      ::flt::log_message(flt_log_site_, level, __VA_ARGS__); \
    }                                                        \
  } while (0)
