/* SPDX-License-Identifier: Apache-2.0 */
/** @file
 * libflatline - the log: what the library tells while it works.
 *
 * What it does
 *   Counters say how much was lost; the log says when and why, as it
 *   happens: frames dropped at a full queue, rows lost and incomplete
 *   sheets, cuts ignored, saturated laser peaks, a strip's head and tail,
 *   the laser bands found and a rule's band changing, camera faults and
 *   recoveries, a gauge that stopped on a failure. One process-wide
 *   callback receives every message at or above a level; without one the
 *   library says nothing and a message costs one atomic load.
 *
 * Rate
 *   Each place in the library that logs passes at most 5 messages in any
 *   10 s; the next one that passes says how many it held back ("(12 more
 *   like this held back)"), so a flood of dropped frames cannot flood the
 *   caller. Installing a callback starts every place's count afresh: the
 *   new listener has heard nothing yet.
 *
 * Threads
 *   Messages come from whichever thread the event happens on (a gauge
 *   worker, an acquisition thread, the caller's), one at a time: the
 *   callback is never called twice at once. flt_log_set_callback() may be
 *   called from any thread; it returns once no call of the previous
 *   callback is in progress, so the previous user data may be freed then.
 *   The callback must not call flt_log_set_callback() (FLT_ERR_STATE);
 *   a message the callback's own libflatline calls would log is dropped.
 *   It should record the message and return: it may run while the library
 *   holds a lock of the handle that speaks, so a call on that handle from
 *   the callback may wait for ever.
 *
 * Memory
 *   A message is formatted into a fixed buffer on the logging thread's
 *   stack (at most 511 bytes of UTF-8): logging allocates nothing.
 */
#ifndef FLATLINE_LOG_H
#define FLATLINE_LOG_H

#include "flatline/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** How much a message matters (the values are Python's logging levels). */
typedef enum flt_log_level {
    FLT_LOG_DEBUG = 10,   /**< detail for whoever debugs the line */
    FLT_LOG_INFO = 20,    /**< the line's course: a head, a tail, a band found */
    FLT_LOG_WARNING = 30, /**< something was lost or not judged: a result is affected */
    FLT_LOG_ERROR = 40,   /**< something stopped: a gauge failed, a camera was unplugged */
    FLT_LOG_LEVEL_MAX_ENUM_ = 0x7FFFFFFF
} flt_log_level;

/** Receives one message.
 * @param level     its flt_log_level.
 * @param component what speaks: "gauge", "camera" (static storage).
 * @param message   the text, UTF-8, without a final newline (valid during
 *                  the call only).
 * @param user      the pointer given to flt_log_set_callback(). */
typedef void(FLT_CALL *flt_log_callback)(flt_log_level level, const char *component,
                                         const char *message, void *user);

/** Installs the process-wide log callback (NULL: no log), receiving every
 * message at or above min_level. Replaces the previous one, and returns
 * when no call of it is in progress.
 * @param callback the callback, or NULL.
 * @param user passed to the callback as is.
 * @param min_level the least level passed (FLT_LOG_DEBUG .. FLT_LOG_ERROR).
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a level that is none of
 *         the four; FLT_ERR_STATE from inside the callback.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_log_set_callback(flt_log_callback callback,
                                                               void *user, flt_log_level min_level);

#ifdef __cplusplus
}
#endif

#endif /* FLATLINE_LOG_H */
