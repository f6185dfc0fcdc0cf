// SPDX-License-Identifier: Apache-2.0
// The process-wide log callback (flatline/log.h).
#include "core/log.hpp"

#include <chrono>
#include <cstdarg>
#include <cstdio>
#include <mutex>

#include "core/number_text.hpp"

namespace flt {
namespace {

constexpr int k_per_window = 5;
constexpr std::int64_t k_window_ms = 10000;

std::atomic<int> g_min_level{0};  // 0: no callback
std::mutex g_m;                   // the callback, its user, the rate limits
flt_log_callback g_callback = nullptr;
// Counts installations: a new listener has heard nothing, so every place's
// window starts afresh for it.
std::uint64_t g_generation = 1;
void *g_user = nullptr;
thread_local bool t_in_callback = false;

std::int64_t now_ms() {
    return std::chrono::duration_cast<std::chrono::milliseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

}  // namespace

bool log_enabled(flt_log_level level) {
    const int min = g_min_level.load(std::memory_order_relaxed);
    return min != 0 && int(level) >= min;
}

// NOLINTNEXTLINE(cert-dcl50-cpp): printf-style on purpose, the format attribute checks it
void log_message(log_site &site, flt_log_level level, const char *format, ...) {
    if (t_in_callback)
        return;  // the callback's own calls: it would wait for itself
    std::lock_guard<std::mutex> lock(g_m);
    if (!g_callback || int(level) < g_min_level.load(std::memory_order_relaxed))
        return;
    const std::int64_t t = now_ms();
    if (site.generation != g_generation) {
        site.generation = g_generation;
        site.window_start_ms = -1;
        site.held_back = 0;
    }
    if (site.window_start_ms < 0 || t - site.window_start_ms >= k_window_ms) {
        site.window_start_ms = t;
        site.passed = 0;
    }
    if (site.passed >= k_per_window) {
        ++site.held_back;
        return;
    }
    ++site.passed;
    char text[512];
    va_list args;
    va_start(args, format);
    int n = vformat_c(text, sizeof text, format, args);
    va_end(args);
    if (n < 0)
        n = 0;
    if (site.held_back > 0 && std::size_t(n) < sizeof text)
        format_c(text + n, sizeof text - std::size_t(n), " (%u more like this held back)",
                 unsigned(site.held_back));
    site.held_back = 0;
    t_in_callback = true;
    g_callback(level, site.component, text, g_user);
    t_in_callback = false;
}

}  // namespace flt

FLT_API flt_status FLT_CALL flt_log_set_callback(flt_log_callback callback, void *user,
                                                 flt_log_level min_level) {
    const char *fn = "flt_log_set_callback";
    return flt::guard(fn, [&] {
        const int level = flt::enum_arg(min_level);
        if (level != FLT_LOG_DEBUG && level != FLT_LOG_INFO && level != FLT_LOG_WARNING &&
            level != FLT_LOG_ERROR)
            return flt::fail(FLT_ERR_INVALID_ARGUMENT,
                             "%s: argument 'min_level' = %d is not a flt_log_level (10, 20, 30 "
                             "or 40)",
                             fn, level);
        if (flt::t_in_callback)
            return flt::fail(FLT_ERR_STATE, "%s: called from inside the log callback", fn);
        std::lock_guard<std::mutex> lock(flt::g_m);  // waits for a call in progress
        flt::g_callback = callback;
        flt::g_user = user;
        ++flt::g_generation;
        flt::g_min_level.store(callback ? level : 0);
        return FLT_OK;
    });
}
