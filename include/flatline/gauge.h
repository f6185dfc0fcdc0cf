// SPDX-License-Identifier: Apache-2.0
/** @file
 * libflatline - the gauge: one handle that runs a measuring line. Camera
 * frames and the shear's cut signal go in, measured sheets come out.
 *
 * What it does
 *   A gauge owns the chain an integrator would otherwise wire by hand:
 *   extractors (frame -> profile row, flatline/extractor.h), the streaming
 *   reconstructor (rows -> the strip's shape, flatline/recon.h) and the
 *   flatness metrics (a sheet's shape -> I-Units, waves, shape class, bow,
 *   crossbow, flatline/flatness.h). It is created from a finished
 *   calibration, which gives every geometric constant: the frame size, the
 *   laser offsets (the reconstructor's laser_spacing) and the fiber grid.
 *   One options bag configures the parts (extract_*, the reconstructor's
 *   keys, flat_*) and the gauge (gauge_*).
 *
 * Input
 *   Frames, in the order they were taken, either pushed by the caller
 *   (flt_gauge_push_frame: pixels, format, size, stride and the encoder
 *   position) or acquired by the gauge itself from an attached flt_source
 *   on a thread of its own (flt_gauge_attach_source, flt_gauge_start,
 *   flt_gauge_stop). A sensor that measures profiles itself can push
 *   profile rows instead (flt_gauge_push_row). Pushed pixels are copied;
 *   the caller's buffer is free when the call returns.
 *
 * Positions
 *   encoder_mm is the strip's position when the frame was taken (mm, the
 *   frame's encoder reading, as in flatline/source.h). A frame's profile row
 *   lies at s = encoder_mm - (offset_0 + offset_1) / 2 on the strip (the
 *   point midway between the lasers; flatline/extractor.h). Sheets are
 *   reported in s.
 *
 * Line stops and reversals
 *   A frame whose encoder position is not at least gauge_frame_spacing past
 *   the furthest frame the gauge took is skipped and counted: a line stop
 *   (the encoder did not advance) or a short reversal (the strip backed up:
 *   every frame is skipped until the strip passes its furthest position
 *   again, so the reconstructor sees each stretch of strip once, in order).
 *   A reversal of more than gauge_reversal_length mm behind the furthest
 *   position, or a jump forward farther than the reconstructor can bridge
 *   (1000 knots, 100 m at the default spacing), ends the strip: what was
 *   measured is finished as it stands (its last sheet flagged
 *   FLT_SHEET_FLAG_NEW_STRIP) and a new strip starts from the frame, as
 *   after a new coil's head (an encoder reset for a new coil is such a
 *   reversal).
 *
 * Head and tail
 *   The strip begins when it appears under the sensor: the first frame whose
 *   valid fibers span at least gauge_strip_min_width mm (both lasers must
 *   see a fiber for it to be valid). It ends when no frame has shown it over
 *   gauge_tail_length mm of travel: frames without it inside the strip (a
 *   burst of lost lines) are a gap the reconstructor bridges and flags, and
 *   the last ones, after the tail, are dropped. A new strip starts afresh:
 *   nothing carries over from one coil to the next. Every strip has a coil
 *   number; sheets are numbered along the gauge's life and within their
 *   coil. A frame shows the strip when the extractor finds it
 *   (flt_extractor_strip: not FLT_STRIP_NONE) and its valid fibers span
 *   gauge_strip_min_width; a profile row pushed by the caller, when its
 *   valid fibers do.
 *
 * The strip's edges
 *   A strip narrower than the sensor leaves fibers beside it: the
 *   extractor flags them FLT_FLAG_OFF_STRIP, the reconstructor never
 *   reconstructs them (NaN with that bit alone in the height map), and the
 *   flatness metrics lay their fibers and zones on the strip from its
 *   edges (flatline/flatness.h), so a strip that wanders sideways keeps its
 *   zones. The sheet reports the strip's width and position (mean, min,
 *   max) and where its fibers and zones lie in sensor and strip
 *   coordinates.
 *
 * Cuts
 *   flt_gauge_cut(encoder_mm) tells the gauge where the shear cut: the
 *   encoder reading at which the cut line lies midway between the lasers
 *   (a shear D mm downstream of the sensor that fires at encoder reading e
 *   cut at e - D; one upstream at e + D). A cut may be given before the
 *   strip reaches it or after it passed (as long as its sheet is still
 *   open, see below). A sheet ends exactly at its cut: it holds the rows
 *   with s before the cut, the next sheet those at or after it. The
 *   reconstructor runs on across cuts, so a sheet's rows are finished only
 *   once the reconstructor has seen as much strip beyond the cut as inside
 *   a sheet (its latency: FLT_SHEET_LOOKAHEAD in mm, FLT_SHEET_LATENCY in
 *   seconds; the reconstructor's latency_mm sets it): a join is as
 *   accurate as the inside of a sheet. Where that is too late (stacker
 *   gates close to the shear), gauge_provisional_mm hands out an early,
 *   provisional result first (FLT_SHEET_FLAG_PROVISIONAL), its final one
 *   later with the same id. (flt_recon_end_sheet() instead finishes at once
 *   without that look-ahead; tests/c/test_gauge.c measures the difference.)
 *   Cuts are given in increasing order; after a long reversal (an encoder
 *   reset) the order starts again. A cut at or before the start of the
 *   open sheet (its sheet is already finished, or no strip reached it) is
 *   ignored and counted. A sheet that grows to gauge_max_sheet_length
 *   without a cut is ended there (FLT_SHEET_FLAG_SPLIT); the strip's tail,
 *   a long reversal and flt_gauge_flush() end the last sheet of a strip.
 *
 * Sheets
 *   Each sheet is an opaque flt_sheet: its id, coil, s range, the strip's
 *   width and position, zone and per-fiber I-Units, the largest wave, shape
 *   class and confidence, bow, crossbow, flags and counters (frames,
 *   skipped, dropped, saturated, invalid), and with gauge_keep_maps its
 *   reconstructed (and measured) height map. Read them with
 *   flt_sheet_get() (scalars by key), flt_sheet_get_array() (per fiber and
 *   per zone) and flt_sheet_height_map(). They arrive in order, either by
 *   polling (flt_gauge_next_sheet) or through a callback
 *   (flt_gauge_set_callback). A NaN value always comes with its flag.
 *   No finished sheet is ever dropped unless the caller chose it
 *   (gauge_sheet_backlog = 0): when more sheets exist at once than the
 *   gauge_sheet_slots made at create time (a caller who reads them late,
 *   several sheets that finish together at a flush), another is made for
 *   each. Up to gauge_sheet_backlog of those may exist; then pushed
 *   frames are refused (FLT_ERR_BUFFER_FULL, nothing taken) until the
 *   caller reads or frees sheets, and an attached source waits.
 *   flt_gauge_flush and the end of a strip finish every sheet whatever
 *   the backlog.
 *
 * Lost rows
 *   Every row a sheet should hold and does not is counted on the sheet
 *   and flags it (FLT_SHEET_FLAG_LOST_ROWS): frames dropped at a full
 *   queue (FLT_SHEET_DROPPED), frames the encoder says are missing (a step
 *   wider than 1.5 frame pitches, FLT_SHEET_MISSING: a camera or a
 *   recording lost them before the gauge saw them) and lost lines (frames
 *   inside the strip that did not show it, FLT_SHEET_LOST_LINES). Frames
 *   lost between two rows are spread evenly over that step, so a burst
 *   across a cut counts on both sheets for its share. The sheet's coverage
 *   is the rows that measured the strip over the rows expected (its rows
 *   plus the frames dropped and missing in its stretch). A sheet whose
 *   coverage is below gauge_min_coverage (0.95 by default) is
 *   FLT_SHEET_FLAG_INCOMPLETE: it is not given a shape class
 *   (FLT_SHAPE_NOT_JUDGED) or a verdict (FLT_VERDICT_NOT_JUDGED), as if
 *   it were whole; its values describe the rows it has.
 *
 * Verdicts and coil statistics
 *   With a rule set (flt_gauge_set_rules, flatline/verdict.h) every
 *   finished sheet is judged against the tolerances as part of its
 *   evaluation: the straightedge rules on its reconstructed height map
 *   (kept for the verdict whatever gauge_keep_maps says), the others from
 *   its flatness results (the largest zone I-Units at its zone's centre,
 *   the largest wave's steepness and height at its fiber, bow and crossbow
 *   at the strip's centre; s the sheet's middle). The sheet's thickness is
 *   the caller's; its width, the caller's nominal width or the sheet's
 *   measured strip width (FLT_SHEET_STRIP_WIDTH); they choose each rule's
 *   band. flt_sheet_verdict() gives the sheet's rules and verdict as
 *   read-only handles for flt_rules_rule() and flt_verdict_get().
 *   A sheet's verdict (FLT_SHEET_VERDICT) is FAIL when a rule failed,
 *   PASS only when every rule judged it and it passed each, and
 *   FLT_VERDICT_NOT_JUDGED otherwise: a rule whose band does not cover its
 *   thickness and width (NO_BAND), a measure that is missing
 *   (NOT_MEASURED), or an incomplete sheet. A sheet no rule could judge is
 *   never counted as passed.
 *   Per coil the gauge counts the sheets passed, failed and not judged, and
 *   per rule the outcomes and the distribution of the worst values: min,
 *   max, mean, where the largest was, and a histogram of worst / limit in
 *   FLT_COIL_HISTOGRAM_BINS bins of a tenth of the limit (no percentiles:
 *   they would need every value kept). flt_gauge_coil_stats() reads them
 *   for the coil being measured and for the last finished one.
 *
 * Threads
 *   gauge_workers threads process the frames (0: the thread that pushes a
 *   frame, or the acquisition thread, processes it before the call
 *   returns). Each worker has its own extractor (frames are independent);
 *   the reconstructor and the flatness metrics take the rows in order, one
 *   worker at a time, and a finished sheet is evaluated while the next one
 *   is being built. Between acquisition and processing sits a queue of
 *   gauge_queue_frames frames: when it is full, the thread that delivers a
 *   frame waits for room (frames pushed by the caller, an attached image
 *   sequence or simulator), or, for an attached camera, which cannot wait,
 *   the frame is dropped, counted and flagged on its sheet
 *   (gauge_overflow, flt_gauge_overflow: "auto" by default; "drop" and
 *   "wait" for every source). Results do not depend on the number of
 *   workers: with no frame dropped, every sheet is identical bit for bit
 *   (tests/c/test_gauge.c checks 0, 1 and 2 workers).
 *   The calls of one gauge may come from any threads. Frames come from one
 *   producer at a time, in order: push_frame and push_row from a thread
 *   while another thread pushes or flushes return FLT_ERR_STATE at once
 *   (nothing taken; the gauge stays usable), and so do they while an
 *   attached source acquires. flt_gauge_flush and flt_gauge_start wait
 *   for a push in progress to end. cut() may come from any thread.
 *
 * Inside the callback
 *   The callback runs on a gauge thread (or the thread whose push, cut or
 *   flush finished the sheet, with 0 workers), and no call of its own
 *   gauge made there waits for itself or hangs. There flt_gauge_cut (the
 *   cut is queued: it takes effect with the next frame),
 *   flt_gauge_count, flt_gauge_get_option, flt_gauge_set_rules and
 *   flt_gauge_coil_stats work; flt_gauge_push_frame, flt_gauge_push_row,
 *   flt_gauge_flush, flt_gauge_wait, flt_gauge_attach_source,
 *   flt_gauge_start, flt_gauge_stop, flt_gauge_next_sheet and
 *   flt_gauge_set_callback return FLT_ERR_STATE (the message says why);
 *   flt_gauge_destroy is ignored (it would wait for itself).
 *   tests/c/test_gauge.c calls each of them from the callback with 0, 1
 *   and 2 workers.
 *
 * Coils, recordings and the archive
 *   flt_gauge_set_coil() names the coil a strip is (flatline/coil.h): its
 *   sheets, statistics and verdicts carry it, and its nominal thickness
 *   and width choose the rule bands. flt_gauge_note() marks a moment on
 *   the line (a leveler change). flt_gauge_attach_recorder() records the
 *   gauge's input (flatline/record.h); a recording replays through a
 *   gauge as a source (flt_source_open_recording, flt_gauge_attach_source,
 *   flt_gauge_start, flt_gauge_wait): with the recording's options
 *   (flt_recording_options) the sheets are the live ones bit for bit
 *   (tests/c/test_replay.c), with others they answer "what if". The
 *   replay takes each recorded row with what the live gauge counted
 *   before it (frames skipped, dropped, missing) and applies the recorded
 *   cuts, coils, notes and flushes where they were given.
 *   flt_gauge_attach_archive() archives every finished sheet.
 *
 * Memory
 *   Everything is allocated by flt_gauge_create() (and flt_gauge_set_rules()
 *   for the verdicts), except, once, the
 *   workers' extractors when the bands are automatic (when the first frame
 *   has shown the two lines) and the flatness metrics' column scratch (at
 *   the first sheet longer than any before). Frames, cuts and sheets
 *   allocate nothing (tests/c/test_gauge_alloc.c counts) while no more
 *   than gauge_sheet_slots sheets exist at once. With K fibers, Z zones, a
 *   W x H frame, R = row_capacity (as flt_gauge_get_option() reports it:
 *   the reconstructor's latency at gauge_frame_spacing, a quarter more and
 *   256 rows), S = gauge_max_sheet_length / gauge_frame_spacing + 2 rows
 *   of a sheet, Q = gauge_queue_frames as flt_gauge_get_option() reports
 *   it (0 without workers), P =
 *   gauge_sheet_slots (0 with gauge_keep_maps 0), B = 2 sheet buffers (3
 *   with gauge_provisional_mm) and E extractors (1 at
 *   create with automatic bands or no workers, else one per worker),
 *   create takes about
 *     the reconstructor at R rows (recon.h, "Memory")
 *   + two flatness metrics (flatness.h), at 16 rows and at
 *     flat_min_length / gauge_frame_spacing + 2 rows
 *   + E x the extractor (extractor.h)
 *   + Q x 2 W H                         the frame queue
 *   + (65 + K / 8) R                    the row ring (off-strip bits too)
 *   + B S (88 + 9 K) + P S (8 + 9 K)    B sheet buffers, the slots' maps
 *   + 8 K (R + B S + P S)               with gauge_keep_maps 2 (measured)
 *   + K (100 P + 20 Q + 400) + 30 kB    per-fiber arrays
 *   bytes: 1,150 fibers, a 2048 x 256 frame and the defaults take about
 *   160 MB, 320 MB with rigid_motion, robust and gauge_keep_maps 1.
 *   tests/c/test_memory.c checks the formula against the measured peak.
 *   flt_gauge_create() refuses a configuration whose own buffers (the
 *   gauge's lines above) pass 8 GiB, before allocating them; the
 *   reconstructor and the metrics refuse on their own formulas.
 *   A sheet made beyond the slots costs 8 x (8 K + 4 Z) bytes, and with
 *   gauge_keep_maps 9 (17) bytes x K x its own rows; at most
 *   gauge_sheet_backlog of them exist while frames are pushed, and a flush
 *   adds at most the sheets in flight (the cuts waiting, at most 256, and
 *   the strip the reconstructor holds over gauge_max_sheet_length).
 */
#ifndef FLATLINE_GAUGE_H
#define FLATLINE_GAUGE_H

#include "flatline/calib.h"
#include "flatline/common.h"
#include "flatline/extractor.h"
#include "flatline/flatness.h" /* FLT_WINDOW_*, FLT_FIBER_*, FLT_ZONE_*, flt_shape */
#include "flatline/recon.h"    /* FLT_FLAG_* of the height maps */
#include "flatline/record.h"   /* flt_recorder, flt_archive */
#include "flatline/source.h"
#include "flatline/verdict.h" /* flt_rules, flt_verdict */

#ifdef __cplusplus
extern "C" {
#endif

/** A gauge: a whole measuring line (opaque handle). */
typedef struct flt_gauge flt_gauge;
/** One measured sheet (see "Sheets"). */
typedef struct flt_sheet flt_sheet;

/** Scalar results of a sheet, read with flt_sheet_get(). Values are doubles;
 * counts and ids are whole numbers (exact up to 2^53). */
typedef enum flt_sheet_value {
    /** The sheet's number along the gauge's life, 1, 2, ... */
    FLT_SHEET_ID = 0,
    /** The number of its strip (coil), 1, 2, ... */
    FLT_SHEET_COIL = 1,
    /** Its number within the coil, 1, 2, ... */
    FLT_SHEET_INDEX = 2,
    /** Where it starts and ends along the strip, s in mm: its cuts, or the
     * first row of its strip (FLT_SHEET_FLAG_HEAD), or the last row of its
     * strip (TAIL, NEW_STRIP, FLUSHED), or where it was split (SPLIT). */
    FLT_SHEET_S_START = 3,
    FLT_SHEET_S_END = 4, /**< end, s in mm (see FLT_SHEET_S_START) */
    /** Rows (frames) in the sheet, and the s of its first and last row, mm
     * (NaN with FLT_SHEET_FLAG_EMPTY when it has none). */
    FLT_SHEET_ROWS = 5,
    FLT_SHEET_S_FIRST = 6, /**< s of the first row, mm */
    FLT_SHEET_S_LAST = 7,  /**< s of the last row, mm */
    /** The strip's edges, width and centre across the sensor, mm (sensor
     * x, as the fiber grid's): where the extractor saw the strip's edges
     * (flt_extractor_strip; FLT_WINDOW_ON_STRIP in the window flags), the
     * mean over the sheet of the flatness metrics' smoothed per-row strip
     * (flt_flatness_strip), left and right = centre -+ width / 2; else the
     * outer fibers with enough valid data, plus half a pitch. NaN with
     * FLT_SHEET_FLAG_NO_EDGES. */
    FLT_SHEET_STRIP_LEFT = 8,
    FLT_SHEET_STRIP_RIGHT = 9,   /**< right edge, mm */
    FLT_SHEET_STRIP_WIDTH = 10,  /**< width, mm */
    FLT_SHEET_STRIP_CENTRE = 11, /**< centre, mm */
    /** Shape class (an flt_shape value), its confidence in [0, 1] and its
     * FLT_SHAPE_HAS_* component bits (flatline/flatness.h). */
    FLT_SHEET_SHAPE = 12,
    FLT_SHEET_CONFIDENCE = 13, /**< confidence of the class, [0, 1] */
    FLT_SHEET_COMPONENTS = 14, /**< FLT_SHAPE_HAS_* bits */
    /** Bow (coil set) and crossbow sagittas, mm (flatline/flatness.h); NaN
     * with FLT_WINDOW_NO_BOW / FLT_WINDOW_NO_CROSSBOW in the window flags. */
    FLT_SHEET_BOW = 15,
    FLT_SHEET_CROSSBOW = 16, /**< crossbow sagitta, mm */
    /** The largest wave over the fibers: peak-to-peak height (mm), period
     * (mm), steepness (%) and the x of its fiber (mm). NaN with
     * FLT_SHEET_FLAG_NO_WAVE. */
    FLT_SHEET_WAVE_HEIGHT = 17,
    FLT_SHEET_WAVE_PERIOD = 18,    /**< its period, mm */
    FLT_SHEET_WAVE_STEEPNESS = 19, /**< its steepness, % */
    FLT_SHEET_WAVE_X = 20,         /**< x of its fiber, mm */
    /** The largest zone I-Units (NaN with FLT_WINDOW_NO_VALID_FIBER). */
    FLT_SHEET_MAX_I_UNITS = 21,
    /** FLT_SHEET_FLAG_* bits, and the flatness window's FLT_WINDOW_* bits. */
    FLT_SHEET_FLAGS = 22,
    FLT_SHEET_WINDOW_FLAGS = 23, /**< FLT_WINDOW_* bits */
    /** Counters over the sheet's stretch of strip: frames measured (its
     * rows), frames skipped (line stops, short reversals), frames dropped
     * (the queue was full), saturated peaks on the strip (both lasers,
     * flt_extractor_saturation; 0 for pushed rows) and invalid samples
     * (row and fiber without a measurement, fibers beside a narrower strip
     * included). */
    FLT_SHEET_FRAMES = 24,
    FLT_SHEET_SKIPPED = 25,   /**< frames skipped */
    FLT_SHEET_DROPPED = 26,   /**< frames dropped */
    FLT_SHEET_SATURATED = 27, /**< saturated peaks */
    FLT_SHEET_INVALID = 28,   /**< invalid samples */
    /** Strip the reconstructor had taken beyond S_END when the sheet's last
     * row was finished, mm (0 when the strip ended there). */
    FLT_SHEET_LOOKAHEAD = 29,
    /** The sizes of the per-fiber and per-zone arrays. */
    FLT_SHEET_FIBERS = 30,
    FLT_SHEET_ZONES = 31, /**< zone count */
    /** The strip's width over the sheet's rows: smallest (mm; equal to the
     * mean without edges). A strip that narrows shows here. */
    FLT_SHEET_STRIP_WIDTH_MIN = 32,
    FLT_SHEET_STRIP_WIDTH_MAX = 33, /**< largest width over the rows, mm */
    /** The strip's centre over the sheet's rows: smallest (mm, sensor x).
     * A strip that wanders sideways shows here. */
    FLT_SHEET_STRIP_CENTRE_MIN = 34,
    FLT_SHEET_STRIP_CENTRE_MAX = 35, /**< largest centre over the rows, mm */
    /** The number of rules the sheet was judged by (0: the gauge had no
     * rules, flt_gauge_set_rules) and how many of them it failed
     * (flt_sheet_verdict has each rule's result). */
    FLT_SHEET_RULES = 36,
    FLT_SHEET_RULES_FAILED = 37, /**< rules failed (FLT_VERDICT_FAIL) */
    /** The sheet's coverage, 0..1: FLT_SHEET_ROWS_MEASURED over
     * FLT_SHEET_ROWS_EXPECTED (0 for a sheet expected to hold no row).
     * Below gauge_min_coverage the sheet is FLT_SHEET_FLAG_INCOMPLETE (see
     * "Lost rows"). */
    FLT_SHEET_COVERAGE = 38,
    /** The rows its length should hold: its rows, and the frames lost
     * between them and at its ends (FLT_SHEET_DROPPED + FLT_SHEET_MISSING). */
    FLT_SHEET_ROWS_EXPECTED = 39,
    /** Its rows that measured the strip (FLT_SHEET_ROWS less
     * FLT_SHEET_LOST_LINES). */
    FLT_SHEET_ROWS_MEASURED = 40,
    /** Rows inside the strip whose frame did not show it (lost lines: the
     * reconstructor bridges them). */
    FLT_SHEET_LOST_LINES = 41,
    /** Frames missing by the encoder: a step between two frames wider than
     * 1.5 times the recent frame pitch counts the frames that should lie
     * in it (a camera or a recording that lost them before the gauge). */
    FLT_SHEET_MISSING = 42,
    /** The sheet's verdict (an flt_verdict_state, flatline/verdict.h):
     * FLT_VERDICT_FAIL when a rule failed; FLT_VERDICT_PASS when every
     * rule was judged and passed; else FLT_VERDICT_NOT_JUDGED (no rules,
     * a rule whose band does not cover the sheet or whose measure is
     * missing, or an incomplete sheet): never counted as passed. */
    FLT_SHEET_VERDICT = 43,
    /** Laser peaks found on the strip over the sheet's rows (both lasers;
     * 0 for pushed rows): FLT_SHEET_SATURATED's denominator. */
    FLT_SHEET_PEAKS = 44,
    /** When the sheet was finished (evaluated and judged, as it is handed
     * out), host UTC, s since 1970-01-01. */
    FLT_SHEET_FINISHED_TIME = 45,
    /** The sheet's latency in seconds: FLT_SHEET_LOOKAHEAD at the measured
     * line speed, i.e. the time between the strip at S_END passing the
     * sensor and the newest frame the reconstructor had taken when it
     * finished the sheet's last row, by the frames' times (host UTC when
     * pushed, or the recording's on a replay). 0 when the lookahead is 0.
     * The verdict comes this much after the cut, plus the sheet's
     * evaluation: FLT_SHEET_FINISHED_TIME less FLT_SHEET_CUT_TIME is the
     * whole wait on a live line. */
    FLT_SHEET_LATENCY = 46,
    /** When the strip at S_END passed the sensor (interpolated between the
     * frames on either side), host UTC, s since 1970-01-01; on a replay the
     * recording's time. */
    FLT_SHEET_CUT_TIME = 47,
    /** Not a key: keeps the type int-sized whatever is added. */
    FLT_SHEET_VALUE_MAX_ENUM_ = 0x7FFFFFFF
} flt_sheet_value;

/** Per-fiber and per-zone results, read with flt_sheet_get_array(). */
typedef enum flt_sheet_array {
    /** Per fiber (FLT_SHEET_FIBERS values): x (mm, sensor x: the result
     * fiber's mean position over the sheet; on the strip a result fiber
     * keeps its place on the strip, flatline/flatness.h "Zones on the
     * strip"), I-Units, arc length (mm), largest wave height (mm), period
     * (mm), steepness (%), and the FLT_FIBER_* flag bits as whole numbers
     * (flatline/flatness.h). */
    FLT_SHEET_FIBER_X = 0,
    FLT_SHEET_FIBER_I_UNITS = 1,     /**< I-Units per fiber */
    FLT_SHEET_FIBER_ARC_LENGTH = 2,  /**< arc length per fiber, mm */
    FLT_SHEET_FIBER_WAVE_HEIGHT = 3, /**< largest wave height per fiber, mm */
    FLT_SHEET_FIBER_WAVE_PERIOD = 4, /**< its period, mm */
    FLT_SHEET_FIBER_STEEPNESS = 5,   /**< its steepness, % */
    FLT_SHEET_FIBER_FLAGS = 6,       /**< FLT_FIBER_* bits */
    /** Per zone (FLT_SHEET_ZONES values): centre x (mm, sensor x, the mean
     * over the sheet), I-Units, and the FLT_ZONE_* flag bits as whole
     * numbers. */
    FLT_SHEET_ZONE_CENTRE_X = 7,
    FLT_SHEET_ZONE_I_UNITS = 8, /**< I-Units per zone */
    FLT_SHEET_ZONE_FLAGS = 9,   /**< FLT_ZONE_* bits */
    /** Strip coordinates (mm from the strip's centre line towards the
     * operator side, flatline/flatness.h) per result fiber
     * (FLT_SHEET_FIBERS values): beyond the strip's half width for a fiber
     * flagged FLT_FIBER_OFF_STRIP; NaN when the sheet has no flatness
     * window (every fiber FLT_FIBER_NO_DATA). */
    FLT_SHEET_FIBER_STRIP_X = 10,
    /** The same per zone centre (FLT_SHEET_ZONES values); NaN for a zone
     * beyond what the strip holds (FLT_ZONE_NO_DATA | FLT_ZONE_OFF_STRIP). */
    FLT_SHEET_ZONE_STRIP_X = 11,
    FLT_SHEET_ARRAY_MAX_ENUM_ = 0x7FFFFFFF
} flt_sheet_array;

/** Sheet flags (FLT_SHEET_FLAGS; bits combine). */
enum {
    /** Starts at the head of its strip, not at a cut. */
    FLT_SHEET_FLAG_HEAD = 1,
    /** Ends at the tail of its strip (the strip left the sensor). */
    FLT_SHEET_FLAG_TAIL = 2,
    /** Ended by flt_gauge_flush() (the end of the input). */
    FLT_SHEET_FLAG_FLUSHED = 4,
    /** Ended by the gauge at gauge_max_sheet_length: no cut came. */
    FLT_SHEET_FLAG_SPLIT = 8,
    /** Ended because the encoder reversed or jumped: a new strip began. */
    FLT_SHEET_FLAG_NEW_STRIP = 16,
    /** The strip's edges are unknown: FLT_SHEET_STRIP_* are NaN. */
    FLT_SHEET_FLAG_NO_EDGES = 32,
    /** No fiber has a wave: FLT_SHEET_WAVE_* are NaN. */
    FLT_SHEET_FLAG_NO_WAVE = 64,
    /** No row: every result is NaN and flagged (two cuts with no frame
     * between them). */
    FLT_SHEET_FLAG_EMPTY = 128,
    /** Its coverage (FLT_SHEET_COVERAGE) is below gauge_min_coverage: its
     * shape is FLT_SHAPE_NOT_JUDGED and its verdict FLT_VERDICT_NOT_JUDGED
     * ("not judged: incomplete"); its other values describe the rows it
     * has. */
    FLT_SHEET_FLAG_INCOMPLETE = 256,
    /** It lost rows: frames dropped at a full queue, missing by the
     * encoder, or lost lines (FLT_SHEET_DROPPED, _MISSING, _LOST_LINES). */
    FLT_SHEET_FLAG_LOST_ROWS = 512,
    /** An early answer (gauge_provisional_mm): its last rows are the
     * reconstructor's estimate before they were final, and its values and
     * verdict may still change; the final sheet with the same id follows.
     * Not counted, not archived, not in the coil's statistics. */
    FLT_SHEET_FLAG_PROVISIONAL = 1024
};

/** What a full frame queue does (option gauge_overflow). */
typedef enum flt_gauge_overflow {
    /** Drop the frame, count it (FLT_GAUGE_COUNT_DROPPED) and flag the
     * sheet it belonged to (FLT_SHEET_FLAG_LOST_ROWS). */
    FLT_GAUGE_OVERFLOW_DROP = 0,
    /** Make the thread that delivers the frame wait for room. */
    FLT_GAUGE_OVERFLOW_WAIT = 1,
    /** Wait for frames pushed by the caller and for an attached image
     * sequence or simulator; drop for an attached camera. The default. */
    FLT_GAUGE_OVERFLOW_AUTO = 2,
    FLT_GAUGE_OVERFLOW_MAX_ENUM_ = 0x7FFFFFFF
} flt_gauge_overflow;

/** flt_gauge_set_rules()'s width_mm for "each sheet's measured strip
 * width" (FLT_SHEET_STRIP_WIDTH). */
#define FLT_GAUGE_WIDTH_MEASURED 0.0

/** Which coil's statistics flt_gauge_coil_stats() reads. */
typedef enum flt_coil {
    /** The coil being measured: the sheets judged since its first (none
     * yet after a coil's last sheet: FLT_COIL_NUMBER is then 0). */
    FLT_COIL_CURRENT = 0,
    /** The last finished coil: its last sheet (FLT_SHEET_FLAG_TAIL,
     * _NEW_STRIP or _FLUSHED) was judged, or the next coil's first was. */
    FLT_COIL_LAST = 1,
    FLT_COIL_MAX_ENUM_ = 0x7FFFFFFF
} flt_coil;

/** The histogram of a rule's worst values over a coil: bin i counts the
 * sheets whose worst / limit lies in (i / 10, (i + 1) / 10] (bin 0 from
 * 0, the last bin everything above 1.9): bins 0-9 passed, 10-19 failed. */
#define FLT_COIL_HISTOGRAM_BINS 20

/** A coil's statistics for one rule, read with flt_gauge_coil_stats() as an
 * array indexed by these keys. Counts are whole numbers as doubles. */
typedef enum flt_coil_value {
    /** The coil's number (FLT_SHEET_COIL; 0: no sheet judged yet). */
    FLT_COIL_NUMBER = 0,
    /** Sheets of the coil evaluated under the rules: judged or not. */
    FLT_COIL_SHEETS = 1,
    /** Sheets whose verdict (FLT_SHEET_VERDICT) is PASS: every rule judged
     * them and they passed every one ... */
    FLT_COIL_SHEETS_PASSED = 2,
    /** ... FAIL: they failed at least one rule (FLT_COIL_SHEETS_NOT_JUDGED
     * are the rest). */
    FLT_COIL_SHEETS_FAILED = 3,
    /** 1 once the coil's last sheet was judged, else 0. */
    FLT_COIL_FINISHED = 4,
    /** The number of rules the statistics are over (the rule set in force
     * when the coil's statistics began). */
    FLT_COIL_RULES = 5,
    /** This rule's outcomes over the coil's sheets (FLT_VERDICT_PASS,
     * _FAIL, _NO_BAND, _NOT_MEASURED, and FLT_COIL_RULE_NOT_JUDGED for
     * incomplete sheets): they add up to FLT_COIL_SHEETS. */
    FLT_COIL_RULE_PASSED = 6,
    FLT_COIL_RULE_FAILED = 7,       /**< sheets that failed the rule */
    FLT_COIL_RULE_NO_BAND = 8,      /**< sheets no band of the rule covers */
    FLT_COIL_RULE_NOT_MEASURED = 9, /**< sheets the measure was missing on */
    /** The worst values (FLT_VERDICT_WORST) of the sheets that passed or
     * failed: smallest, largest, mean (the measure's unit; NaN when no
     * sheet was measured). */
    FLT_COIL_WORST_MIN = 10,
    FLT_COIL_WORST_MAX = 11,  /**< largest worst value */
    FLT_COIL_WORST_MEAN = 12, /**< mean worst value */
    /** Where the largest is: the sheet's FLT_SHEET_ID, x and s (mm). */
    FLT_COIL_WORST_SHEET = 13,
    FLT_COIL_WORST_X = 14, /**< x of the largest, mm */
    FLT_COIL_WORST_S = 15, /**< s of the largest, mm */
    /** The first of FLT_COIL_HISTOGRAM_BINS counts (worst / limit). */
    FLT_COIL_HISTOGRAM = 16,
    /** Sheets not judged: their verdict is FLT_VERDICT_NOT_JUDGED (a rule
     * whose band does not cover them or whose measure is missing, and no
     * rule failed; or incomplete). Never counted as passed. */
    FLT_COIL_SHEETS_NOT_JUDGED = 16 + FLT_COIL_HISTOGRAM_BINS,
    /** Sheets judged: passed + failed. */
    FLT_COIL_SHEETS_JUDGED = 17 + FLT_COIL_HISTOGRAM_BINS,
    /** This rule's FLT_VERDICT_NOT_JUDGED outcomes (incomplete sheets). */
    FLT_COIL_RULE_NOT_JUDGED = 18 + FLT_COIL_HISTOGRAM_BINS,
    /** The number of values (the array's size). */
    FLT_COIL_VALUES = 19 + FLT_COIL_HISTOGRAM_BINS,
    FLT_COIL_VALUE_MAX_ENUM_ = 0x7FFFFFFF
} flt_coil_value;

/** Gauge counters, since it was created (flt_gauge_count()). */
typedef enum flt_gauge_counter {
    /** Frames (and rows) pushed or acquired. */
    FLT_GAUGE_COUNT_FRAMES = 0,
    /** Frames turned into profile rows. */
    FLT_GAUGE_COUNT_EXTRACTED = 1,
    /** Frames skipped: the encoder did not advance (line stop) ... */
    FLT_GAUGE_COUNT_SKIPPED_STOP = 2,
    /** ... or went back (short reversal). */
    FLT_GAUGE_COUNT_SKIPPED_REVERSAL = 3,
    /** Frames dropped because the queue was full. */
    FLT_GAUGE_COUNT_DROPPED = 4,
    /** Frames without the strip (before a head, after a tail). */
    FLT_GAUGE_COUNT_NO_STRIP = 5,
    /** Strips (coils) begun. */
    FLT_GAUGE_COUNT_STRIPS = 6,
    /** Sheets finished. */
    FLT_GAUGE_COUNT_SHEETS = 7,
    /** Sheets dropped because every sheet slot was taken: only with
     * gauge_sheet_backlog = 0 (else a sheet is never dropped). */
    FLT_GAUGE_COUNT_SHEETS_DROPPED = 8,
    /** Cuts given, and those ignored (at or before the open sheet's start). */
    FLT_GAUGE_COUNT_CUTS = 9,
    FLT_GAUGE_COUNT_CUTS_IGNORED = 10, /**< cuts ignored */
    /** Strips ended by a long reversal or a jump of the encoder. */
    FLT_GAUGE_COUNT_REVERSALS = 11,
    /** Frames the extractor refused (their rows count as invalid). */
    FLT_GAUGE_COUNT_EXTRACT_ERRORS = 12,
    /** Frames waiting in the queue now. */
    FLT_GAUGE_COUNT_QUEUED = 13,
    /** 1 while the acquisition thread runs, else 0. */
    FLT_GAUGE_COUNT_ACQUIRING = 14,
    /** Sheets waiting for flt_gauge_next_sheet(). */
    FLT_GAUGE_COUNT_SHEETS_WAITING = 15,
    /** Sheets made beyond gauge_sheet_slots (each allocated when needed). */
    FLT_GAUGE_COUNT_SHEETS_GROWN = 16,
    /** Sheets flagged FLT_SHEET_FLAG_INCOMPLETE. */
    FLT_GAUGE_COUNT_SHEETS_INCOMPLETE = 17,
    /** Frames missing by the encoder (FLT_SHEET_MISSING). */
    FLT_GAUGE_COUNT_MISSING = 18,
    /** Frames inside a strip that did not show it (FLT_SHEET_LOST_LINES). */
    FLT_GAUGE_COUNT_LOST_LINES = 19,
    /** Frames and rows push_frame / push_row refused because
     * gauge_sheet_slots + gauge_sheet_backlog sheets existed. */
    FLT_GAUGE_COUNT_REFUSED = 20,
    /** Provisional sheets handed out (gauge_provisional_mm); the other
     * counters count final sheets only. */
    FLT_GAUGE_COUNT_PROVISIONAL = 21,
    /** Where the time goes: nanoseconds spent so far (wall time on the
     * threads that ran the stage, every thread together: on a machine with
     * more busy threads than cores, waiting for a core counts too),
     * extracting frames (the workers, or the pushing thread with
     * 0 workers), sequencing rows (the reconstructor and the sheets, in
     * frame order) and evaluating sheets (flatness, verdicts; with the
     * blocks of a sheet the workers share, each thread's own part, not
     * the evaluating thread's wait for the others). A stage run
     * inside another counts for itself only. Over a run's wall time and
     * gauge_workers they give the workers' utilisation
     * (examples/bench/bench_gauge prints it). */
    FLT_GAUGE_COUNT_EXTRACT_NS = 22,
    FLT_GAUGE_COUNT_SEQUENCE_NS = 23, /**< ns sequencing rows */
    FLT_GAUGE_COUNT_EVALUATE_NS = 24, /**< ns evaluating sheets */
    /** The most frames that waited in the queue at once (of
     * gauge_queue_frames): near it, frames are about to be dropped. */
    FLT_GAUGE_COUNT_QUEUE_HIGH_WATER = 25,
    FLT_GAUGE_COUNT_MAX_ENUM_ = 0x7FFFFFFF
} flt_gauge_counter;

/** Called once per sheet, in order, on a gauge thread. `sheet` is borrowed:
 * valid until the callback returns (read what you need, do not destroy
 * it). `user` is the pointer given to flt_gauge_set_callback(). */
typedef void(FLT_CALL *flt_sheet_callback)(const flt_sheet *sheet, void *user);

/* ---------------------------------------------------------------------- */
/* Life cycle                                                              */
/* ---------------------------------------------------------------------- */

/** Creates a gauge for the sensor of a finished calibration.
 * @param calib    finished calibration (FLT_ERR_STATE otherwise); copied.
 * @param options  NULL for the defaults; read for the extract_*, the
 *                 reconstructor's, the flat_* and the gauge_* keys (each part
 *                 gets its own); copied. A key set for another component
 *                 (the simulator's, a source's) is refused: it would be
 *                 ignored. The reconstructor is made with
 *                 flt_recon_create_from_calib (a laser_spacing set otherwise
 *                 is refused); its row_capacity is raised to hold its latency
 *                 at gauge_frame_spacing; flat_window_length and
 *                 flat_row_capacity are the gauge's (one window per sheet).
 * @param out      the gauge; NULL on failure.
 * @return FLT_ERR_INVALID_ARGUMENT for inconsistent options (naming the
 *         part that refused them) or buffers beyond 8 GiB (naming what to
 *         change), FLT_ERR_OUT_OF_MEMORY when they do not fit. The worker
 *         threads start here. */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_create(const flt_calib *calib,
                                                           const flt_options *options,
                                                           flt_gauge **out);

/** Stops the acquisition thread and the workers, drops what is not
 * finished, and frees everything. Sheets the caller holds stay valid until
 * destroyed. NULL is a no-op, and so is a call from inside the gauge's own
 * callback (it would wait for itself).
 * @param gauge the gauge, or NULL.
 */
FLT_API void FLT_CALL flt_gauge_destroy(flt_gauge *gauge);

/** The effective value of an option: the gauge's keys, and the
 * reconstructor's as the gauge set them (laser_spacing, row_capacity).
 * FLT_ERR_NOT_FOUND for an unknown key.
 * @param gauge the gauge.
 * @param key an option key.
 * @param out receives its value.
 * @return FLT_OK; FLT_ERR_NOT_FOUND for an unknown key;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_get_option(const flt_gauge *gauge,
                                                               flt_option key, double *out);

/* ---------------------------------------------------------------------- */
/* Input                                                                   */
/* ---------------------------------------------------------------------- */

/** Pushes one frame.
 * @param gauge         the gauge.
 * @param frame         height rows of stride_bytes, `format` pixels (as in
 *                      flt_extractor_process); copied.
 * @param format        its pixel format.
 * @param width, height must equal the calibration's frame size.
 * @param stride_bytes  bytes from one row to the next (at least width
 *                      times the bytes per pixel).
 * @param encoder_mm    the strip position of the frame, mm (finite, at
 *                      most 1e12 in magnitude).
 * @return FLT_OK also when the frame was skipped (line stop, reversal) or
 *         dropped (full queue, gauge_overflow "drop"): the counters say
 *         so. FLT_ERR_INVALID_ARGUMENT for a frame the gauge cannot take
 *         (nothing is counted); FLT_ERR_BUFFER_FULL when
 *         gauge_sheet_slots + gauge_sheet_backlog sheets exist (read or
 *         free sheets; the frame was not taken: push it again);
 *         FLT_ERR_STATE while an attached source is acquiring, while
 *         another thread pushes or flushes, or from inside the callback
 *         (nothing taken); a failure of processing (which stops the gauge)
 *         is returned by every later call. */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_push_frame(flt_gauge *gauge, const void *frame,
                                                               flt_pixel_format format,
                                                               uint32_t width, uint32_t height,
                                                               size_t stride_bytes,
                                                               double encoder_mm);

/** Pushes one profile row instead of a frame (a sensor that extracts its
 * own profiles, or recorded rows): what flt_extractor_process() gives for
 * a frame taken at encoder_mm.
 * @param gauge   the gauge.
 * @param encoder_mm the strip position of the row, mm (as for a frame).
 * @param fibers  must equal the calibration's fiber count.
 * @param height, slope  [fibers] mm and mm/mm (NaN where not measured).
 * @param valid   [fibers] non-zero where valid, or NULL (then finite values
 *                are valid).
 * Counted, skipped and dropped like a frame.
 * @return as flt_gauge_push_frame().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_push_row(flt_gauge *gauge, double encoder_mm,
                                                             size_t fibers, const double *height,
                                                             const double *slope,
                                                             const uint8_t *valid);

/** The shear cut the strip at encoder_mm (see "Cuts"): finite, at most
 * 1e12 in magnitude, beyond the previous cut unless the encoder went back
 * since. FLT_ERR_BUFFER_FULL when 256 cuts wait for strip (the strip has
 * not reached them). Any thread, the callback too (queued there).
 * @param gauge the gauge.
 * @param encoder_mm where the shear cut, mm of encoder position.
 * @return FLT_OK; FLT_ERR_BUFFER_FULL as above; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong
 * argument (a position not finite, too large, or not beyond the previous cut).
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_cut(flt_gauge *gauge, double encoder_mm);

/** The end of the input so far: waits until every frame pushed before the
 * call is processed, then ends the strip under the sensor (its last sheet
 * is finished at its last row, FLT_SHEET_FLAG_FLUSHED) and waits until that
 * sheet is delivered. The next frame may begin a new strip. FLT_ERR_STATE
 * while an attached source is acquiring (stop it first) or from inside the
 * callback.
 * @param gauge the gauge.
 * @return FLT_OK; FLT_ERR_STATE as above; a failure of processing.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_flush(flt_gauge *gauge);

/** Attaches a frame source (borrowed: it must outlive the gauge or be
 * detached with NULL first). FLT_ERR_STATE while acquiring or from inside
 * the callback.
 * @param gauge the gauge.
 * @param source the source, or NULL to detach it.
 * @return FLT_OK; FLT_ERR_STATE while acquiring; FLT_ERR_INVALID_ARGUMENT
 *         for a NULL gauge or a source that is not a live handle.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_attach_source(flt_gauge *gauge,
                                                                  flt_source *source);

/** Starts the attached source (flt_source_start) and the acquisition
 * thread, which takes every frame the source delivers as push_frame would
 * (frames the source dropped on the way are counted by the source,
 * flt_source_count). The thread ends by itself at the end of an image
 * sequence or when the source fails. FLT_ERR_STATE without a source,
 * while acquiring or from inside the callback; the source's own error if
 * it does not start.
 * @param gauge the gauge.
 * @return FLT_OK; FLT_ERR_STATE as above; the source's status if it
 *         does not start.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_start(flt_gauge *gauge);

/** Stops the acquisition thread and the source (flt_source_stop), and waits
 * until the frames it queued are processed (the strip stays open: flush
 * ends it). Stopping a stopped gauge is a no-op. Returns the error that
 * ended the acquisition by itself (e.g. FLT_ERR_DEVICE for an unplugged
 * camera, with its message), else FLT_OK. FLT_ERR_STATE from inside the
 * callback.
 * @param gauge the gauge.
 * @return the status that ended the acquisition, else FLT_OK;
 *         FLT_ERR_STATE from inside the callback.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_stop(flt_gauge *gauge);

/** flt_gauge_wait()'s timeout for "as long as it takes". */
#define FLT_GAUGE_WAIT_FOREVER UINT32_MAX

/** Runs an attached, started finite source to its end: waits until the
 * acquisition ends by itself (the end of an image sequence, or a failure
 * of the source), then ends the input as flt_gauge_stop() and
 * flt_gauge_flush() do, and returns when every sheet is out (delivered to
 * the callback or waiting for flt_gauge_next_sheet). With a camera, which
 * never ends, it returns FLT_ERR_TIMEOUT after timeout_ms and changes
 * nothing: the acquisition goes on (call again, or flt_gauge_stop).
 * Without a callback, read the sheets between calls with a short
 * timeout (the sheets waiting count towards gauge_sheet_backlog, and the
 * source waits while the backlog is full):
 *
 *     flt_gauge_attach_source(gauge, images);
 *     flt_gauge_start(gauge);
 *     flt_status st;
 *     while ((st = flt_gauge_wait(gauge, 100)) == FLT_ERR_TIMEOUT)
 *         take_sheets(gauge);                  // flt_gauge_next_sheet(gauge, 0, ...)
 *     take_sheets(gauge);                      // the rest, after the flush
 *
 * @param gauge the gauge.
 * @param timeout_ms how long to wait for the source's end, ms
 *        (FLT_GAUGE_WAIT_FOREVER: as long as it takes); the flush after it
 *        is waited for whatever the timeout.
 * @return FLT_OK; FLT_ERR_TIMEOUT when the source still delivers;
 *         FLT_ERR_STATE when no acquisition was started (flt_gauge_start)
 *         or from inside the callback; the error that ended the
 *         acquisition (e.g. FLT_ERR_DEVICE for an unplugged camera) after
 *         its sheets were finished all the same; a failure of processing.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_wait(flt_gauge *gauge, uint32_t timeout_ms);

/* ---------------------------------------------------------------------- */
/* Output                                                                  */
/* ---------------------------------------------------------------------- */

/** Takes the next finished sheet, waiting up to timeout_ms for one.
 * *out is the sheet (the caller owns it: flt_sheet_destroy), or NULL when
 * none came in time (FLT_OK). Sheets wait until they are taken (see
 * "Sheets"; with gauge_sheet_backlog = 0 the oldest waiting one is dropped
 * when every slot is taken, FLT_GAUGE_COUNT_SHEETS_DROPPED).
 * FLT_ERR_STATE while a callback is set.
 * @param gauge the gauge.
 * @param timeout_ms how long to wait, ms (0: do not wait).
 * @param out receives the sheet, or NULL.
 * @return FLT_OK (also when none came); FLT_ERR_STATE while a callback is
 *         set; a failure of processing.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_next_sheet(flt_gauge *gauge,
                                                               uint32_t timeout_ms,
                                                               flt_sheet **out);

/** Sets (or, with NULL, removes) the callback that receives every sheet
 * instead of flt_gauge_next_sheet(); sheets already waiting are handed to
 * it first. The callback must not block for long: the next sheet waits.
 * @param gauge the gauge.
 * @param callback called with each sheet, or NULL.
 * @param user passed to the callback as is.
 * @return FLT_OK; FLT_ERR_STATE from inside the callback;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL gauge.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_set_callback(flt_gauge *gauge,
                                                                 flt_sheet_callback callback,
                                                                 void *user);

/** A counter (flt_gauge_counter).
 * @param gauge the gauge.
 * @param counter which counter.
 * @param out receives its value.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL argument or an
 *         unknown counter.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_count(const flt_gauge *gauge,
                                                          flt_gauge_counter counter, uint64_t *out);

/** Sets the rule set every sheet is judged by from now on (see "Verdicts
 * and coil statistics"), or with NULL judges no more. The gauge copies what
 * it needs: the caller may destroy the rules after the call. Allowed at any
 * time and from any thread (the callback too): a sheet is judged by the
 * rules in force when its evaluation begins, which with workers may come
 * after later frames were pushed, so set them before a coil's first frame.
 * The current coil's statistics restart; the last coil's stay.
 * Allocates: a verdict per sheet slot, and room for the straightedge over
 * the longest sheet and the widest row; judging allocates nothing.
 * @param gauge the gauge.
 * @param rules the rule set (flatline/verdict.h), or NULL.
 * @param thickness_mm the sheets' thickness, mm (> 0, <= 1000): chooses
 *        each rule's band, with the width. Required: there is no default
 *        thickness (a wrong one puts every sheet outside the bands, where
 *        it is not judged).
 * @param width_mm the sheets' nominal width, mm (> 0, <= 100000), or
 *        FLT_GAUGE_WIDTH_MEASURED (0) for each sheet's measured strip width
 *        (FLT_SHEET_STRIP_WIDTH; a sheet without it is NOT_MEASURED by every
 *        rule).
 * The sheets of a coil whose identity gives a nominal thickness or width
 * (flt_gauge_set_coil) are judged with the coil's value in place of the
 * one given here; a value the coil does not give (0) is taken from here.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL gauge, rules that are
 *         not a live handle, or a thickness or width out of range (the
 *         rules in force stay).
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_set_rules(flt_gauge *gauge,
                                                              const flt_rules *rules,
                                                              double thickness_mm, double width_mm);

/** A coil's statistics for one rule (see "Verdicts and coil statistics"),
 * copied out at once (consistent with each other): out[k] for the keys
 * k < count of flt_coil_value.
 * @param gauge the gauge.
 * @param which FLT_COIL_CURRENT or FLT_COIL_LAST.
 * @param rule the rule, 0 .. FLT_COIL_RULES - 1.
 * @param count how many values to copy, 1 .. FLT_COIL_VALUES.
 * @param out receives `count` values.
 * @return FLT_OK; FLT_ERR_STATE when that coil has no statistics (no rules
 *         were set, or no coil finished yet); FLT_ERR_NOT_FOUND for a rule
 *         past the last; FLT_ERR_INVALID_ARGUMENT for a NULL argument, an
 *         unknown `which` or a count out of range.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_coil_stats(const flt_gauge *gauge,
                                                               flt_coil which, size_t rule,
                                                               size_t count, double *out);

/* ---------------------------------------------------------------------- */
/* Sheets                                                                  */
/* ---------------------------------------------------------------------- */

/** Gives a sheet from flt_gauge_next_sheet() back. NULL is a no-op; a
 * borrowed sheet (inside the callback) is left alone.
 * @param sheet the sheet, or NULL.
 */
FLT_API void FLT_CALL flt_sheet_destroy(flt_sheet *sheet);

/** One scalar result (flt_sheet_value). FLT_ERR_NOT_FOUND for an unknown
 * key.
 * @param sheet the sheet.
 * @param key which result.
 * @param out receives it.
 * @return FLT_OK; FLT_ERR_NOT_FOUND for an unknown key;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sheet_get(const flt_sheet *sheet, flt_sheet_value key,
                                                        double *out);

/** One array (flt_sheet_array) into out[count]; count must equal its size
 * (FLT_SHEET_FIBERS or FLT_SHEET_ZONES).
 * @param sheet the sheet.
 * @param key which array.
 * @param count its size as the caller believes it.
 * @param out receives `count` values.
 * @return FLT_OK; FLT_ERR_NOT_FOUND for an unknown key;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL argument or a wrong count.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sheet_get_array(const flt_sheet *sheet,
                                                              flt_sheet_array key, size_t count,
                                                              double *out);

/** The reconstructed height map (gauge_keep_maps >= 1): rows = FLT_SHEET_ROWS
 * and fibers = FLT_SHEET_FIBERS must match; s_out [rows] (mm), z_out
 * [rows * fibers] (mm, NaN only where FLT_FLAG_NO_DATA), flags_out
 * [rows * fibers] FLT_FLAG_* bits. Any output may be NULL. FLT_ERR_STATE
 * when the gauge keeps no maps.
 * @param sheet the sheet.
 * @param rows its rows (FLT_SHEET_ROWS).
 * @param fibers its fibers (FLT_SHEET_FIBERS).
 * @param s_out [rows] positions, mm, or NULL.
 * @param z_out [rows * fibers] heights, mm, or NULL.
 * @param flags_out [rows * fibers] FLT_FLAG_* bits, or NULL.
 * @return FLT_OK; FLT_ERR_STATE as above; FLT_ERR_INVALID_ARGUMENT for a
 *         NULL sheet or sizes that do not match.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sheet_height_map(const flt_sheet *sheet, size_t rows,
                                                               size_t fibers, double *s_out,
                                                               double *z_out, uint8_t *flags_out);

/** The measured heights of the same rows (gauge_keep_maps = 2): what the
 * extractor gave, height_out [rows * fibers] mm, NaN where the sample was
 * invalid. FLT_ERR_STATE unless the gauge keeps them.
 * @param sheet the sheet.
 * @param rows its rows (FLT_SHEET_ROWS).
 * @param fibers its fibers (FLT_SHEET_FIBERS).
 * @param height_out [rows * fibers] measured heights, mm.
 * @return FLT_OK; FLT_ERR_STATE as above; FLT_ERR_INVALID_ARGUMENT for a
 *         NULL argument or sizes that do not match.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sheet_measured_map(const flt_sheet *sheet,
                                                                 size_t rows, size_t fibers,
                                                                 double *height_out);

/** The sheet's verdict: the rules it was judged by and its results, as
 * read-only handles owned by the sheet (valid while it lives; do not
 * destroy them). Read them with flt_rules_count(), flt_rules_rule(),
 * flt_verdict_get() and flt_verdict_failed(); flt_verdict_set_measure()
 * and flt_verdict_evaluate() refuse them (FLT_ERR_STATE).
 * @param sheet the sheet.
 * @param rules_out receives its rules, or NULL.
 * @param verdict_out receives its verdict, or NULL.
 * @return FLT_OK; FLT_ERR_STATE when the gauge had no rules when it
 *         judged the sheet (FLT_SHEET_RULES = 0); FLT_ERR_INVALID_ARGUMENT
 *         for a NULL or dead sheet.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sheet_verdict(const flt_sheet *sheet,
                                                            const flt_rules **rules_out,
                                                            const flt_verdict **verdict_out);

/* ---------------------------------------------------------------------- */
/* The quality record (flatline/record.h)                                  */
/* ---------------------------------------------------------------------- */

/** The coil the next strip is (see "Coils, recordings and the archive"):
 * its identity is copied and given to every sheet of that coil
 * (flt_sheet_coil), its statistics (flt_gauge_coil_info) and, when rules
 * are set, its verdicts: the coil's nominal thickness and width, where
 * given (non-zero), choose the rule bands of its sheets in place of those
 * given to flt_gauge_set_rules. It takes effect with the next frame pushed
 * (as a cut does): for the strip under the sensor when that strip has no
 * identity yet (given at its head; its sheets already cut off keep none),
 * else for the next strip. NULL: the next strip has no identity. Any
 * thread, the callback too.
 * @param gauge the gauge.
 * @param coil  the identity (copied), or NULL.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL gauge or a coil that
 *         is not a live handle.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_set_coil(flt_gauge *gauge,
                                                             const flt_coil_info *coil);

/** The identity of the coil whose statistics flt_gauge_coil_stats() reads
 * (FLT_COIL_CURRENT or FLT_COIL_LAST), as a new handle.
 * @param gauge the gauge.
 * @param which FLT_COIL_CURRENT or FLT_COIL_LAST.
 * @param out   receives a copy (flt_coil_info_destroy).
 * @return FLT_OK; FLT_ERR_NOT_FOUND when that coil has no identity (or no
 *         statistics); FLT_ERR_INVALID_ARGUMENT for a NULL argument or an
 *         unknown `which`.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_coil_info(const flt_gauge *gauge,
                                                              flt_coil which, flt_coil_info **out);

/** A note about the line from now on (a leveler setting changed, an
 * operator's remark): it takes effect with the next frame pushed (as a cut
 * does) and is given to the sheet whose rows begin there (flt_sheet_note),
 * recorded and archived. The coil report marks notes of kind "leveler" on
 * its run chart. Any thread, the callback too.
 * @param gauge the gauge.
 * @param kind  what it is: 1..64 ASCII letters, digits, '_', '-', '.'
 *              ("leveler").
 * @param text  what it says: UTF-8 text as in flatline/coil.h.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or malformed
 *         argument; FLT_ERR_BUFFER_FULL when 256 notes wait for a frame.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_note(flt_gauge *gauge, const char *kind,
                                                         const char *text);

/** Records the gauge's input into a recorder from the next frame on (or
 * stops recording, with NULL). The gauge writes its options and any cuts
 * and coil waiting into the recording, then every row it takes, with its
 * cuts, coils, notes, flushes and (record_frames) camera frames; the rows
 * it measures are the recording's quantized ones (flatline/record.h,
 * "Quantization"). Borrowed: the recorder must outlive the gauge or be
 * detached first. Only while the gauge is idle: no frame in its queue and
 * no acquisition (attach before the first frame, or after flt_gauge_flush).
 * @param gauge    the gauge.
 * @param recorder the recorder, or NULL to detach.
 * @return FLT_OK; FLT_ERR_STATE while frames are queued, while acquiring,
 *         from inside the callback, or when another gauge records through
 *         the recorder; FLT_ERR_INVALID_ARGUMENT for a NULL gauge, a dead
 *         recorder or one of another fiber count.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_attach_recorder(flt_gauge *gauge,
                                                                    flt_recorder *recorder);

/** Archives every sheet the gauge finishes from now on (or no more, with
 * NULL): its values, verdict, coil identity and statistics, notes and (with
 * archive_maps) its height map, which the gauge has whatever
 * gauge_keep_maps says. The map is encoded on the gauge's evaluation
 * thread; the archive's writer stores it. Borrowed: the archive must
 * outlive the gauge or be detached first. Only while the gauge is idle (as
 * flt_gauge_attach_recorder).
 * @param gauge   the gauge.
 * @param archive the archive, or NULL to detach.
 * @return FLT_OK; FLT_ERR_STATE as flt_gauge_attach_recorder();
 *         FLT_ERR_INVALID_ARGUMENT for a NULL gauge or a dead archive.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_gauge_attach_archive(flt_gauge *gauge,
                                                                   flt_archive *archive);

/** The identity of a sheet's coil, lent by the sheet (valid while it lives;
 * read-only).
 * @param sheet the sheet.
 * @param out   receives the identity.
 * @return FLT_OK; FLT_ERR_NOT_FOUND when its coil had none
 *         (flt_gauge_set_coil); FLT_ERR_INVALID_ARGUMENT for a NULL
 *         argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sheet_coil(const flt_sheet *sheet,
                                                         const flt_coil_info **out);

/** The number of notes a sheet carries (flt_gauge_note).
 * @param sheet the sheet.
 * @param out   receives the count.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sheet_note_count(const flt_sheet *sheet, size_t *out);

/** Note `index` of a sheet. Any output may be NULL.
 * @param sheet     the sheet.
 * @param index     0 .. flt_sheet_note_count() - 1.
 * @param kind_out  receives its kind, owned by the sheet.
 * @param text_out  receives its text, owned by the sheet.
 * @param s_mm_out  receives where it took effect along the strip, s in mm.
 * @return FLT_OK; FLT_ERR_NOT_FOUND past the last note;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL sheet.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sheet_note(const flt_sheet *sheet, size_t index,
                                                         const char **kind_out,
                                                         const char **text_out, double *s_mm_out);

/** Queues a copy of a sheet for the archive (its values, arrays, verdict
 * and, when the archive keeps maps, its height map; a sheet of a gauge
 * with gauge_keep_maps = 0 has none and is stored without, map_codec 0 in
 * docs/record.md). The map is encoded on the calling thread (about 30 ms
 * for a 3 m sheet of 1,150 fibers); the archive's writer stores the copy.
 * A sheet added twice is one row in the archive (both adds count as
 * stored: FLT_ARCHIVE_COUNT_SHEETS = stored + pending + lost).
 * @param archive the archive (flatline/record.h).
 * @param sheet   the sheet (one the caller holds, or the callback's).
 * @return FLT_OK; FLT_ERR_BUFFER_FULL when archive_buffer_mb is taken by
 *         sheets the database has not taken yet (the sheet is counted
 *         lost, FLT_ARCHIVE_COUNT_LOST); FLT_ERR_INVALID_ARGUMENT for a
 *         NULL or dead handle.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_archive_add_sheet(flt_archive *archive,
                                                                const flt_sheet *sheet);

#ifdef __cplusplus
}
#endif

#endif /* FLATLINE_GAUGE_H */
