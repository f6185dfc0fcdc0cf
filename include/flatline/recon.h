// SPDX-License-Identifier: Apache-2.0
/** @file
 * libflatline - the streaming Hermite reconstructor.
 *
 * What it does
 *   Each fiber (a longitudinal line on the strip at a fixed x) is modelled as
 *   a piecewise cubic Hermite spline z(s) with knots every L mm of travel
 *   (option knot_spacing, default = laser_spacing). The unknowns are the
 *   height and slope at each knot, so z is C0 and C1 by construction.
 *
 *   Every input row is one camera frame at material position s (mm, the
 *   encoder position of the frame centre). Per fiber it carries what the two
 *   lasers, Delta-d apart (option laser_spacing), really measure:
 *     height = (z(s - Delta-d/2) + z(s + Delta-d/2)) / 2
 *     slope  = (z(s + Delta-d/2) - z(s - Delta-d/2)) / Delta-d
 *   The spline is fitted to exactly these operators by weighted least squares
 *   (weights 1/height_sigma^2 and 1/slope_sigma^2), plus a weak curvature
 *   prior (curvature_weight). The output is z at every input row.
 *   Slopes and the priors are blind to a fiber's level, which only heights
 *   give; so a slope sample weighs at most 1e8 height samples of its fiber
 *   (also the weights robust mode estimates), curvature_weight and
 *   curvature_jump_weight act as at most 1e8, and curvature_weight as at
 *   least curvature_jump_weight / 1e8 (where no row is, only the curvature
 *   prior damps the heights the jump prior leaves free): the most double
 *   precision carries (beyond it, the rounding of the other terms swamps
 *   what is left, and outputs came out NaN).
 *   Slopes that precise already fix the shape, and priors that strong
 *   already make the spline a cubic (or a line), to within 1e-8, so the
 *   caps change no result beyond that.
 *
 * Coordinates
 *   s along travel in mm, material coordinate (a point on the strip keeps its
 *   s). z up, mm. Rows must arrive with strictly increasing s; any spacing is
 *   allowed (use the true encoder positions, never an assumed grid).
 *
 * Validity
 *   A sample is used when its mask entry is non-zero (or the mask is NULL)
 *   and its value is finite and at most 1e9 in magnitude (mm, mm/mm: no
 *   measurement, and its square would overflow the sums). Heights are
 *   solved relative to the strip's level (its first valid height since
 *   create or reset; the sheet's first for flt_reconstruct()), so a result
 *   does not depend on where the strip lies; a height more than 1e9 mm from
 *   that level is not used either. Height and slope are judged separately: a
 * NaN slope with a finite height uses the height only. Output rows carry flags per fiber
 * (FLT_FLAG_*): a value is never invented silently.
 *
 * The strip's edges
 *   flt_recon_push_flagged() takes the extractor's per-fiber flags instead
 *   of a mask: FLT_FLAG_OFF_STRIP marks a fiber beyond the strip's edges in
 *   that row. Such a sample is not used, and the output row of that fiber
 *   is NaN with FLT_FLAG_OFF_STRIP (and no other bit), whatever the spline
 *   bridges there: a strip that wanders sideways, narrows at a coil change
 *   or leaves at its tail never has material invented beyond its edges.
 *   A fiber off the strip since the strip began is NO_DATA where it comes
 *   onto the strip until its first height, as any fiber without data.
 *
 * Streaming
 *   push() takes rows; pull() returns finished rows. A knot is complete once
 *   no later row can touch it (rows are increasing, so this is known after
 *   the row whose s - Delta-d/2 passes it). The estimate of knot j is emitted
 *   once knot j + lag is complete; it is the least-squares solution given
 *   every row pushed so far (a fixed-lag smoother, not a truncated window),
 *   so longer lags converge to the whole-sheet result. Knots are emitted in
 *   groups of G = 1 + lag/8 so that one back-substitution serves several.
 *   Rows between two emitted knots are finished and can be pulled.
 *
 * Latency
 *   A row is finished at most (lag + G + 1) * L + Delta-d/2 of strip behind
 *   the newest row pushed (plus one row spacing). The option latency_mm
 *   sets that bound (default 2000 mm: a lag of 15 knots at 100 mm, rows
 *   final 1850 mm behind at most, 0.9 s at 120 m/min); the reconstructor
 *   takes the longest lag that keeps it, in every mode. Rows at a strip's
 *   head (after create or reset) wait up to twice as long: with no strip
 *   behind them, their level is known from the strip ahead only. A shorter
 *   latency costs accuracy: docs/reconstruction.md tables the price
 *   (examples/bench/bench_latency). lag_knots instead sets the lag itself
 *   (as before latency_mm; no longer wait at the head).
 *   peek() returns the rows not finished yet with provisional values (the
 *   estimate given every row so far), for an early answer that the final
 *   rows replace; it changes nothing pull() returns.
 *
 *   end_sheet() finishes every pushed row now, with all data so far, and
 *   keeps the height and slope of the last emitted knot of every fiber as
 *   hard boundary conditions of the next sheet: consecutive sheets join C0
 *   and C1 exactly. The next sheet continues the same knot grid and must
 *   continue with larger s. reset() starts a new strip with no carry-over.
 *
 * Priors
 *   A weak curvature prior (curvature_weight) bridges stretches without
 *   data. A prior against curvature jumps at the knots
 *   (curvature_jump_weight) removes the one shape the lasers cannot see: a
 *   secant slope over Delta-d is blind to anything that repeats every
 *   Delta-d, and with knots every Delta-d the spline has such a wiggle.
 *
 * Rigid motion (option rigid_motion = 1)
 *   A bouncing strip moves as a rigid body: in one frame every fiber is
 *   offset along one line across the strip. Each row is split into that
 *   line (least squares across the fibers, weighted by height_sigma) and the
 *   deviations from it (weighted by shape_sigma); both are reconstructed and
 *   added. About 3x less shape error under 2.5 mm of heave. Fibers are then
 *   no longer solved independently (a dead fiber is still NaN and flagged).
 *
 * Robust mode (option robust = FLT_ROBUST_HUBER or FLT_ROBUST_TUKEY)
 *   An M-estimator for outliers such as the shear station's ringing and
 *   spurious laser peaks: a plain pass, then robust_iterations reweighted
 *   passes. Each reweighted pass judges every sample by its residual against
 *   the previous pass, in units of its fiber's own noise level, estimated
 *   from the data (no noise level needs to be given). Huber: a moderate
 *   residual enters as a pseudo-observation, the prediction plus the
 *   residual clipped at 1.345 noise levels; a gross one (beyond 4) keeps its
 *   value with a weight that bounds its pull the same way. Both reach
 *   Huber's estimate; the first costs no more than a plain sample, the
 *   second converges fast for bursts like the ringing. Tukey: weights on
 *   every sample. With rigid_motion the line across the strip, which
 *   carries the ringing, takes robust_line_iterations passes of its own.
 *   flt_reconstruct() runs the passes over the whole sheet one after the
 *   other. Streaming, every pass runs in one sliding window: each row is
 *   judged robust_iterations times (the line robust_line_iterations times)
 *   as the strip moves on, each time against the window's solution at that
 *   moment, the last time when its knots become final, so the latency is
 *   the same one lag as without robust mode (docs/reconstruction.md,
 *   "Robust mode, streaming"). Carry-over and flags work as without it.
 *   Together with rigid_motion it takes the reference article's hardest
 *   noise (shear ringing) down to 0.083 mm at most (tests/c/test_recon.c,
 *   examples/python/compare_filters.py); speed in examples/bench.
 *
 * Memory
 *   Everything is allocated by flt_recon_create(); push, pull, peek,
 *   end_sheet and reset allocate nothing (tests/c/test_recon_alloc.c
 *   counts). With K fibers, R = row_capacity, L = the lag in knots (from
 *   latency_mm, as flt_recon_get_option reports it), W = the knots a row
 *   may wait, 2 (L + L/8 + 2) with latency_mm (the strip's head), L + L/8
 *   + 1 with lag_knots set, and S = ceil(laser_spacing / knot_spacing) + 2
 *   (3 at the default knots), create takes about
 *     R x (9 + 9 K)                      the rows kept (position, heights,
 *                                        flags)
 *   + K x (W + L/8 + 12) x 8 (4 S + 3)   each fiber's knots within the wait
 *     (in robust mode, in place of that line:
 *   + R x (8 + 8 K)                      the window's raw rows, in float
 *   + K x 16 ((2S + 1)(S + 1)(W + 2S + 8) + W + L/8 + 170)
 *                                        its blocks' sums and knots)
 *   + R x 60 (92 in robust mode)         with rigid_motion: the line across
 *                                        the strip
 *   bytes, all written at create: 1,150 fibers with the defaults and 8192
 *   rows take 92 MB, 191 MB with rigid_motion and robust (the robust
 *   passes cost time, not memory). tests/c/test_memory.c checks the
 *   formula against the measured peak; FLT_RECON_MAX_BYTES refuses on it
 *   before allocating.
 *   flt_reconstruct() keeps its working memory for the next call of the
 *   same shape (fibers, rows, options): a loop of calls allocates nothing
 *   after the first. Up to 4 shapes and 256 MB are kept (a larger one is
 *   freed after its call), until flt_reconstruct_release() or until the
 *   library is unloaded.
 *
 * Threads
 *   A flt_recon must not be used from two threads at once. Separate handles
 *   are independent. flt_reconstruct() is reentrant: calls on several
 *   threads at once each take a working memory of their own.
 */
#ifndef FLATLINE_RECON_H
#define FLATLINE_RECON_H

#include "flatline/calib.h"
#include "flatline/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Output flags, one byte per row and fiber; bits combine. */
enum {
    /** This row's own sample of this fiber was invalid (height and slope both
     * missing); the value is bridged from the neighbouring samples. */
    FLT_FLAG_INVALID_INPUT = 1,
    /** The row lies in a run of invalid samples longer than max_gap: the value
     * comes from the smoothness prior alone and is not a measurement. */
    FLT_FLAG_GAP = 2,
    /** The fiber has had no valid height since the strip began (and no
     * carry-over): its level is unknown and the value is NaN. */
    FLT_FLAG_NO_DATA = 4,
    /** The fiber lies off the strip in this row (beyond its edges, or no
     * strip under a laser: flatline/extractor.h). Not invalid data: there is
     * nothing to measure. Input through flt_recon_push_flagged; the output
     * row carries this bit alone and its value is NaN: a fiber off the strip
     * is never reconstructed as strip. */
    FLT_FLAG_OFF_STRIP = 8
};

/** Values of the option "robust" (FLT_OPT_ROBUST); the bindings' names in
 * quotes. */
typedef enum flt_robust {
    /** "none": least squares (the default). */
    FLT_ROBUST_NONE = 0,
    /** "huber": Huber's M-estimator, the one to use (see "Robust mode");
     * what the bindings' robust=True means. */
    FLT_ROBUST_HUBER = 1,
    /** "tukey": Tukey's biweight; can lock onto a wrong level when a strip
     * starts inside the shear station's ringing. */
    FLT_ROBUST_TUKEY = 2,
    /** Not a value: keeps the type int-sized. */
    FLT_ROBUST_MAX_ENUM_ = 0x7FFFFFFF
} flt_robust;

/** Sizes a real sensor never reaches: the most bytes a reconstructor's
 * buffers may take (2 GiB). A reconstructor takes at most FLT_MAX_FIBERS
 * fibers (common.h). flt_recon_create() and flt_reconstruct() refuse, with
 * FLT_ERR_INVALID_ARGUMENT and a message giving the estimate, a
 * configuration whose buffers would take more: many fibers with a large
 * row_capacity or latency_mm (lag_knots), or a sheet for
 * flt_reconstruct() whose rows are so sparse that it spans far more knots
 * than it has rows (a long strip is streamed through flt_recon_push
 * instead, which keeps only its lag). */
#define FLT_RECON_MAX_BYTES 2147483648.0

/** A streaming reconstructor (opaque handle). */
typedef struct flt_recon flt_recon;

/** Creates a streaming reconstructor for `fibers` fibers (1 to
 * FLT_MAX_FIBERS), for lasers laser_spacing mm apart (default 100 mm: the
 * reference sensor's). With a calibration, use
 * flt_recon_create_from_calib(), which takes both from it.
 * options: NULL for the defaults, else read for the FLT_OPT_* keys of the
 * reconstructor (knot_spacing, laser_spacing, height_sigma, slope_sigma,
 * curvature_weight, curvature_jump_weight, latency_mm or lag_knots, max_gap,
 * row_capacity, rigid_motion, shape_sigma, robust, robust_iterations,
 * robust_line_iterations); copied, not kept.
 * Fails with FLT_ERR_INVALID_ARGUMENT if fibers is 0 or too many, the
 * options are inconsistent or set a key of another component (common.h),
 * or the buffers would pass FLT_RECON_MAX_BYTES; FLT_ERR_OUT_OF_MEMORY if
 * they do not fit in memory.
 * @param fibers  the number of fibers (>= 1).
 * @param options NULL, or the bag described above.
 * @param out     receives the handle; NULL on failure.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT or FLT_ERR_OUT_OF_MEMORY as above.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recon_create(size_t fibers,
                                                           const flt_options *options,
                                                           flt_recon **out);

/**
 * Creates a streaming reconstructor for the sensor a calibration describes:
 * the way to create one for a real sensor.
 *
 * The fiber count is the calibration's fiber grid (flt_calib_get_fiber_grid)
 * and the laser spacing Delta-d is the distance between its two laser lines,
 * |offset_1 - offset_0| (the magnitude of flt_calib_laser_spacing; either
 * laser may lead), the same distance the
 * extractor divides by when it measures a slope. The laser_spacing option
 * would otherwise default to 100 mm, which gives wrong shapes without a word
 * on any other sensor.
 *
 * @param calib    a finished calibration; only read during the call.
 * @param options  NULL for the defaults, else read as for flt_recon_create().
 *                 knot_spacing 0 (the default) follows the calibration's
 *                 spacing. Leave laser_spacing unset: if it is set, it must
 *                 equal the calibration's spacing (to 1e-9 relative, i.e.
 *                 up to rounding), else the call fails with
 *                 FLT_ERR_INVALID_ARGUMENT naming both values, because a
 *                 disagreement is a mistake in one of them and neither
 *                 choice would be safe to make silently.
 * @param out      receives the handle; NULL on failure.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or dead argument, a
 *         disagreeing laser_spacing, a spacing outside laser_spacing's
 *         bounds or inconsistent options; FLT_ERR_STATE if calib is not
 *         finished; FLT_ERR_OUT_OF_MEMORY if the buffers do not fit.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recon_create_from_calib(const flt_calib *calib,
                                                                      const flt_options *options,
                                                                      flt_recon **out);

/** Frees everything. NULL is a no-op.
 * @param recon the reconstructor, or NULL.
 */
FLT_API void FLT_CALL flt_recon_destroy(flt_recon *recon);

/** The number of fibers the handle was created with.
 * @param recon the reconstructor.
 * @param out receives the fiber count.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recon_fibers(const flt_recon *recon, size_t *out);

/** The effective value of an option (knot_spacing resolved to mm).
 * FLT_ERR_NOT_FOUND for an unknown key, FLT_ERR_INVALID_ARGUMENT for a key
 * of another component.
 * @param recon the reconstructor.
 * @param key an option key.
 * @param out receives its effective value.
 * @return FLT_OK; FLT_ERR_NOT_FOUND for an unknown key; FLT_ERR_INVALID_ARGUMENT for a NULL or
 * wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recon_get_option(const flt_recon *recon,
                                                               flt_option key, double *out);

/** Pushes `rows` rows (>= 1).
 *   s       [rows]          material position of each row, mm, strictly
 *                           increasing, also across calls and sheets, by
 *                           at most 1 km and 1000 knot intervals from one
 *                           row to the next (a larger jump is a new strip:
 *                           flt_recon_reset() first; bridging it would
 *                           take an elimination per knot).
 *   height  [rows * fibers] measured heights, mm.
 *   slope   [rows * fibers] measured slopes, mm/mm.
 *   valid   [rows * fibers] or NULL: non-zero where the sample is valid.
 * `fibers` must equal the handle's. The block is checked whole before any
 * row is taken: on failure nothing was pushed. Fails with
 * FLT_ERR_BUFFER_FULL when the rows do not fit in row_capacity: pull
 * finished rows, push smaller blocks, or create with a larger capacity.
 * @param recon the reconstructor.
 * @param rows   rows in the block (>= 1).
 * @param fibers the handle's fiber count.
 * @param s      [rows] positions, mm.
 * @param height [rows * fibers] heights, mm.
 * @param slope  [rows * fibers] slopes, mm/mm.
 * @param valid  [rows * fibers] validity, or NULL.
 * @return FLT_OK; FLT_ERR_BUFFER_FULL as above; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong
 * argument (the message names it); nothing was pushed on failure.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recon_push(flt_recon *recon, size_t rows,
                                                         size_t fibers, const double *s,
                                                         const double *height, const double *slope,
                                                         const uint8_t *valid);

/**
 * Pushes `rows` rows with the extractor's per-fiber flags
 * (flt_extractor_fiber_flags) instead of a validity mask: otherwise as
 * flt_recon_push.
 *
 * @param recon   the reconstructor.
 * @param rows    rows in the block (>= 1).
 * @param fibers  must equal the handle's.
 * @param s       [rows] material positions, mm (as flt_recon_push).
 * @param height  [rows * fibers] measured heights, mm.
 * @param slope   [rows * fibers] measured slopes, mm/mm.
 * @param flags  [rows * fibers] FLT_FLAG_* bits per sample: 0 a valid
 *               sample, FLT_FLAG_INVALID_INPUT an invalid one (bridged as
 *               with a 0 mask entry), FLT_FLAG_OFF_STRIP a fiber off the
 *               strip (not used; its output is NaN flagged
 *               FLT_FLAG_OFF_STRIP). Any other bit set makes the sample
 *               invalid. Not NULL.
 * @return as flt_recon_push; FLT_ERR_INVALID_ARGUMENT for NULL flags.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recon_push_flagged(flt_recon *recon, size_t rows,
                                                                 size_t fibers, const double *s,
                                                                 const double *height,
                                                                 const double *slope,
                                                                 const uint8_t *flags);

/** Pulls up to max_rows finished rows, oldest first.
 *   s_out     [max_rows]          their positions, mm.
 *   z_out     [max_rows * fibers] reconstructed heights, mm (NaN only where
 *                                 FLT_FLAG_NO_DATA or FLT_FLAG_OFF_STRIP
 *                                 is set).
 *   flags_out [max_rows * fibers] FLT_FLAG_* bits, or NULL if unwanted.
 *   rows_out  the number of rows written (0 when none is finished yet).
 * FLT_ERR_STATE if nothing was pushed since create or reset.
 * @param recon the reconstructor.
 * @param max_rows  rows the outputs can hold.
 * @param fibers    the handle's fiber count.
 * @param s_out     [max_rows] positions, mm.
 * @param z_out     [max_rows * fibers] heights, mm.
 * @param flags_out [max_rows * fibers] flags, or NULL.
 * @param rows_out  receives the number of rows written.
 * @return FLT_OK (also when no row is finished); FLT_ERR_STATE as above;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recon_pull(flt_recon *recon, size_t max_rows,
                                                         size_t fibers, double *s_out,
                                                         double *z_out, uint8_t *flags_out,
                                                         size_t *rows_out);

/** The number of finished rows waiting to be pulled.
 * @param recon the reconstructor.
 * @param out receives the number of finished rows.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recon_ready(const flt_recon *recon, size_t *out);

/** The number of rows pushed and not finished yet (their values are
 * provisional: flt_recon_peek).
 * @param recon the reconstructor.
 * @param out receives the number of pending rows.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recon_pending(const flt_recon *recon, size_t *out);

/**
 * The rows pushed and not finished yet, as the reconstructor estimates them
 * now: provisional values, given every row pushed so far (a row is final
 * only when flt_recon_pull returns it, latency_mm of strip later). For an
 * early answer that a final one replaces later, e.g. a sheet's provisional
 * verdict at its cut. Copies up to max_rows of them, oldest first, without
 * taking them: finished rows not pulled yet are skipped (pull them first),
 * and nothing that flt_recon_pull returns changes. Costs a solve of the
 * reconstructor's window (about one emission's work) per call.
 *
 * @param recon     the reconstructor.
 * @param max_rows  rows the outputs can hold (flt_recon_pending tells how
 *                  many there are).
 * @param fibers    the handle's fiber count.
 * @param s_out     [max_rows] positions, mm.
 * @param z_out     [max_rows * fibers] provisional heights, mm (NaN only
 *                  with FLT_FLAG_NO_DATA or FLT_FLAG_OFF_STRIP, as pull).
 * @param flags_out [max_rows * fibers] FLT_FLAG_* bits as known now, or
 *                  NULL.
 * @param rows_out  receives the number of rows written.
 * @return FLT_OK (also when no row is pending); FLT_ERR_STATE if nothing was
 *         pushed since create or reset; FLT_ERR_INVALID_ARGUMENT for a NULL
 *         or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recon_peek(flt_recon *recon, size_t max_rows,
                                                         size_t fibers, double *s_out,
                                                         double *z_out, uint8_t *flags_out,
                                                         size_t *rows_out);

/** Finishes the current sheet: every pushed row becomes ready to pull, solved
 * with all data so far, and the last emitted knot becomes the hard boundary
 * condition of the next sheet (carry-over). FLT_ERR_STATE if no row was
 * pushed since the last end_sheet, create or reset.
 * @param recon the reconstructor.
 * @return FLT_OK; FLT_ERR_STATE as above; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recon_end_sheet(flt_recon *recon);

/** Starts a new strip: drops every row not pulled yet and the carry-over.
 * @param recon the reconstructor.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recon_reset(flt_recon *recon);

/** The boundary condition carried into the next sheet: the knot position
 * (mm), and per fiber its height (mm) and slope (mm/mm). Any output may be
 * NULL. FLT_ERR_STATE before the first end_sheet of a strip.
 * @param recon the reconstructor.
 * @param fibers     the handle's fiber count.
 * @param s_out      receives the knot position, mm, or NULL.
 * @param height_out [fibers] heights, mm, or NULL.
 * @param slope_out  [fibers] slopes, mm/mm, or NULL.
 * @return FLT_OK; FLT_ERR_STATE as above; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_recon_boundary(const flt_recon *recon, size_t fibers,
                                                             double *s_out, double *height_out,
                                                             double *slope_out);

/** Reconstructs one whole sheet in one call: the least-squares spline of all
 * rows at once (no lag, no carry-over). Arguments as in flt_recon_push;
 * z_out [rows * fibers] and flags_out [rows * fibers] (or NULL) as in
 * flt_recon_pull. Its working memory (about 20 doubles per fiber and knot at
 * the default knot spacing, up to about 80 at the finest; at most
 * FLT_RECON_MAX_BYTES, else FLT_ERR_INVALID_ARGUMENT) is allocated by the
 * first call of a shape and kept for the next calls of that shape (see
 * "Memory" above); reentrant.
 * @param options   NULL, or the reconstructor's options.
 * @param rows      rows of the sheet (>= 1).
 * @param fibers    fibers (>= 1).
 * @param s         [rows] positions, mm, strictly increasing.
 * @param height    [rows * fibers] heights, mm.
 * @param slope     [rows * fibers] slopes, mm/mm.
 * @param valid     [rows * fibers] validity, or NULL.
 * @param z_out     [rows * fibers] reconstructed heights, mm.
 * @param flags_out [rows * fibers] flags, or NULL.
 * @return FLT_OK; FLT_ERR_OUT_OF_MEMORY; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_reconstruct(const flt_options *options, size_t rows,
                                                          size_t fibers, const double *s,
                                                          const double *height, const double *slope,
                                                          const uint8_t *valid, double *z_out,
                                                          uint8_t *flags_out);

/**
 * flt_reconstruct with the extractor's per-fiber flags instead of a mask
 * (as flt_recon_push_flagged): off-strip samples come out NaN flagged
 * FLT_FLAG_OFF_STRIP.
 *
 * @param options    NULL for the defaults, else the recon keys.
 * @param rows       rows (>= 1).
 * @param fibers     fibers per row (>= 1).
 * @param s          [rows] material positions, mm, strictly increasing.
 * @param height     [rows * fibers] measured heights, mm.
 * @param slope      [rows * fibers] measured slopes, mm/mm.
 * @param flags      [rows * fibers] FLT_FLAG_* input bits, not NULL.
 * @param z_out      [rows * fibers] mm.
 * @param flags_out  [rows * fibers] or NULL.
 * @return as flt_reconstruct.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_reconstruct_flagged(
    const flt_options *options, size_t rows, size_t fibers, const double *s, const double *height,
    const double *slope, const uint8_t *flags, double *z_out, uint8_t *flags_out);

/**
 * Frees the working memory flt_reconstruct() and flt_reconstruct_flagged()
 * keep for the next call of a shape (see "Memory" above): after a one-off
 * sheet much larger than the usual ones, say, or before a long idle time.
 * The next call of each shape allocates again. A call in progress on
 * another thread keeps its memory and leaves it kept when it ends.
 * @param bytes_out the bytes freed (as the "Memory" formula counts them),
 *                  or NULL.
 * @return FLT_OK.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_reconstruct_release(double *bytes_out);

#ifdef __cplusplus
}
#endif

#endif /* FLATLINE_RECON_H */
