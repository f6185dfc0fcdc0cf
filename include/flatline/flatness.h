// SPDX-License-Identifier: Apache-2.0
/** @file
 * libflatline - flatness metrics: I-Units per fiber and per zone, the largest
 * wave, the shape class, bow and crossbow.
 *
 * What it measures
 *   Input is reconstructed rows (flt_recon_pull or flt_reconstruct output):
 *   per row its material position s (mm) and per fiber the height z (mm) and
 *   the reconstructor's FLT_FLAG_* bits. Fiber k lies at x[k] across the
 *   width (mm), given at create time (or taken from a calibration's fiber
 *   grid). One evaluation covers a window of rows (a sheet, or the last
 *   flat_window_length mm of strip) and gives:
 *
 *   per fiber
 *     arc length l_k (mm) of z(s) over the window, and its I-Units
 *       I_k = (l_k - l_ref) / l_ref * 1e5        (ASTM A1030 practice)
 *     with l_ref the shortest valid fiber (flat_reference = 0, default) or
 *     the mean of the valid fibers (flat_reference = 1). For a sine of
 *     peak-to-peak height H and period P, I = 2.467 (H/P)^2 1e5 for small
 *     H/P.
 *     the largest wave: peak-to-peak height H (mm), period P (mm) and
 *     steepness 100 H / P (%). Waves are found from the alternating crests
 *     and troughs of z(s) (an extremum counts once z has retreated from it
 *     by flat_wave_hysteresis mm, which rejects reconstruction noise); each
 *     crest-trough-crest or trough-crest-trough triple is one wave, with
 *     H = |mean(outer two) - middle| (a level or a linear trend of the fiber
 *     cancels) and P = the distance between the outer two. Extremum heights
 *     and positions are refined with a parabola through three rows.
 *   per zone
 *     the mean I-Units of the valid fibers in the zone. Zones are laid on
 *     the strip (see "Zones on the strip" below), or on the fiber grid when
 *     the strip's edges are not known: flat_zone_width mm wide (or
 *     flat_zone_count equal zones), laid out symmetrically about the centre
 *     and covering the width: n = ceil(width / flat_zone_width) with width
 *     = x[last] - x[0] + the mean fiber pitch for the grid; the outer two
 *     zones may hold fewer fibers. This is the profile a leveler operator
 *     reads.
 *   per window
 *     the shape class with a confidence in [0, 1] (see flt_shape), and
 *     bow_mm: coil set, from the mean longitudinal curvature kappa (1/mm) of
 *       the flattest quarter of the valid fibers (lowest I-Units: there the
 *       buckles are smallest, and coil set is common to the whole width), by
 *       a least-squares parabola in s; reported as the sagitta over the
 *       window, kappa L^2 / 8 with L its length: > 0 when the window's ends
 *       lie higher than its middle.
 *     crossbow_mm: the transverse curvature of the fibers' mean heights over
 *       the window, by a least-squares parabola in x, as the sagitta over the
 *       width: > 0 when the edges lie higher than the centre.
 *
 * Arc length
 *   Rows are about 3 mm apart and the reconstructed profile is a smooth
 *   spline, so the arc length is the sum of the chords between consecutive
 *   rows, summed as the excess over the travel, sqrt(ds^2 + dz^2) - ds =
 *   dz^2 / (sqrt(ds^2 + dz^2) + ds), which keeps the 1e-5-level differences
 *   free of cancellation. See lib/flatness/flatness.cpp for the error bound.
 *
 * Zones on the strip
 *   An operator reads the zone profile from the strip's edges, drive side
 *   and operator side, not from the sensor's: a strip narrower than the
 *   sensor, off-centre, or wandering sideways gives the same profile and
 *   class as the same strip centred. So, unless flat_zones_on = 1, a
 *   window in which the strip's edges are known is measured in strip
 *   coordinates:
 *     - per row the strip's edges in sensor x: given by the caller
 *       (flt_flatness_push_strip / flt_flatness_evaluate_strip, from
 *       flt_extractor_strip with laser 2), or else taken from the
 *       reconstructor's FLT_FLAG_OFF_STRIP bits (the edge half way between
 *       the last fiber off the strip and the first on it: to half a pitch);
 *       an edge is known in a row where it lies inside the fiber grid;
 *     - the strip's width W is the median over the rows where both edges
 *       are known; its centre line per row is the mean of the edges (or one
 *       edge -+ W / 2), smoothed along travel by a moving least-squares
 *       line over +-100 mm of strip (the edges' measurement noise would
 *       otherwise move the strip under the fibers from row to row);
 *     - strip coordinate x_s: mm from the centre line towards the
 *       operator side (flat_drive_side says which sensor side the drive
 *       side is on); result fiber k lies at x_s = (k - (K - 1) / 2) p,
 *       p the mean fiber pitch, so slot k keeps its place on the strip
 *       whatever the strip does; its heights in a row are interpolated
 *       linearly between the two sensor fibers around c_row -+ x_s
 *       (both must be usable); a slot between the strip's last usable
 *       sensor fiber and the next one, when that one is off the strip
 *       (flagged FLT_FLAG_OFF_STRIP, or outside c_row -+ W/2) or has no
 *       height within a pitch of the edge, is extrapolated linearly from
 *       the last two usable fibers, less than a pitch away, so the edge
 *       zones read the same wherever the edges fall on the fiber grid;
 *       slots beyond -+W/2 are off the strip
 *       (FLT_FIBER_OFF_STRIP with FLT_FIBER_NO_DATA);
 *     - zones: n = ceil((W - p) / flat_zone_width) zones of
 *       flat_zone_width (a strip wider than n zones by less than a pitch
 *       keeps n; its outermost fibers count in the outer zones; at most
 *       the grid's zone count, flt_flatness_zones()) or flat_zone_count
 *       zones of W / flat_zone_count, centred on the centre line, numbered
 *       from the drive side; a fiber on a zone boundary belongs to the
 *       zone nearer the centre line (so the layout reads the same from
 *       either side), on the centre line to the operator side's; the
 *       zones beyond n are FLT_ZONE_OFF_STRIP with FLT_ZONE_NO_DATA;
 *     - the shape's bands, crossbow and edges are relative to the strip:
 *       u = x_s / (W / 2); "left" is the drive side (low x_s).
 *   flt_flatness_fiber_positions() and flt_flatness_zone_positions() give
 *   each result's place in strip and in sensor coordinates (the window's
 *   mean), flt_flatness_strip() the strip's width and lateral position
 *   over the window. A window without known edges (the strip fills the
 *   grid, or nothing marks its edges) is measured on the fiber grid as
 *   before (FLT_WINDOW_ON_STRIP is set only where the strip was used):
 *   result slot k is sensor fiber k (with the drive side at low x; at high
 *   x the slots run the other way).
 *
 * Invalid data (FLT_FLAG_NO_DATA, FLT_FLAG_GAP, FLT_FLAG_OFF_STRIP,
 * non-finite z)
 *   A fiber's sample is usable when its z is finite and at most 1e9 mm in
 *   magnitude (as a reconstructor's sample: larger ones are no height, and
 *   their squares would overflow the chords), and its flags carry
 *   neither FLT_FLAG_NO_DATA, FLT_FLAG_GAP nor FLT_FLAG_OFF_STRIP (a value
 *   the reconstructor bridged over a long run without measurements is not a
 *   measurement; a fiber off the strip has none).
 *   FLT_FLAG_INVALID_INPUT alone is usable: the spline bridged a short run.
 *   Chords are summed only between two usable consecutive rows; the fiber's
 *   arc length is then its covered excess per covered mm, scaled to the
 *   window length (flag FLT_FIBER_PARTIAL). A fiber covering less than
 *   flat_min_coverage of the window is flagged FLT_FIBER_NO_DATA and takes
 *   no part in the reference, zones, shape, bow or crossbow. No wave spans an
 *   unusable row.
 *
 * NaN policy
 *   A result that cannot be computed is NaN AND flagged: NaN appears only
 *   where the matching flag (FLT_FIBER_NO_DATA, FLT_FIBER_NO_WAVE,
 *   FLT_ZONE_NO_DATA) or window flag says so. Every unflagged value is a
 *   finite number.
 *
 * Two ways to use it
 *   flt_flatness_evaluate(): one window from the caller's rows (a whole
 *   sheet). Bad input (too short, no valid fiber) is an error and the
 *   previous results stay.
 *   flt_flatness_push() / flt_flatness_finish(): streaming. The window grid
 *   starts at the first row pushed after create, finish or reset (s0):
 *   windows end at s0 + flat_window_length + j * flat_update_interval and
 *   hold the rows with s in [end - flat_window_length, end). A window is
 *   evaluated when the first row at or past its end arrives; push stops
 *   there (so no result is overwritten unseen) and tells how many rows it
 *   took. A window that would hold the same rows as the one before it
 *   (flat_update_interval shorter than the rows' spacing), or no row at all
 *   (a gap in the rows longer than flat_window_length), is skipped: the
 *   next window reported is the first with other rows. finish() evaluates
 *   the rows since the last window's start as a last window (the end of a
 *   sheet) and restarts the grid. A streamed
 *   window that is too short or has no valid fiber is still reported, with
 *   FLT_WINDOW_SHORT / FLT_WINDOW_NO_VALID_FIBER set and the affected
 *   values NaN and flagged: the stream never stops on bad material.
 *
 * Memory
 *   flt_flatness_create() allocates everything for windows of up to
 *   flat_row_capacity rows; push, finish and the result getters allocate
 *   nothing. flt_flatness_evaluate() grows its scratch when given more rows
 *   than flat_row_capacity (once; later calls of that size reuse it).
 *   With K fibers, R = flat_row_capacity and Z zones, create takes
 *     R x (97 + 18 K) + 250 K + 100 Z bytes
 *   (per row: the window's positions, heights, flags and strip edges, the
 *   copy resampled onto the strip, and the evaluation's column scratch;
 *   per fiber and zone: the two result sets), all written at create, so
 *   resident at once: the defaults (R = 4096) with 1,150 fibers take 85 MB.
 *   tests/c/test_memory.c checks the formula against the measured peak.
 *
 * Threads
 *   A flt_flatness must not be used from two threads at once. Separate
 *   handles are independent.
 */
#ifndef FLATLINE_FLATNESS_H
#define FLATLINE_FLATNESS_H

#include "flatline/calib.h"
#include "flatline/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Per-fiber result flags (bits combine). */
enum {
    /** Less than flat_min_coverage of the window usable: arc length, I-Units
     * and the wave are NaN. */
    FLT_FIBER_NO_DATA = 1,
    /** No complete wave above flat_wave_hysteresis in the window (a flat
     * fiber, or waves longer than the window): the wave height, period and
     * steepness are NaN. */
    FLT_FIBER_NO_WAVE = 2,
    /** Some rows were unusable; the arc length is scaled from the covered
     * part (still at least flat_min_coverage). */
    FLT_FIBER_PARTIAL = 4,
    /** The result slot lies beyond the strip's edges (zones on the strip):
     * there is no strip there. FLT_FIBER_NO_DATA is set too. */
    FLT_FIBER_OFF_STRIP = 8
};

/** Per-zone result flags. */
enum {
    /** No valid fiber in the zone: I-Units NaN. */
    FLT_ZONE_NO_DATA = 1,
    /** The zone is beyond the strip's zones (a strip narrower than the
     * grid): FLT_ZONE_NO_DATA is set too. */
    FLT_ZONE_OFF_STRIP = 2
};

/** Per-window flags. */
enum {
    /** Shorter than flat_min_length (shorter than one flatness wave):
     * I-Units are still the arc-length ratios of that material, but no wave
     * is reported and the shape is FLT_SHAPE_UNDETERMINED. */
    FLT_WINDOW_SHORT = 1,
    /** No fiber is valid: every value is NaN and flagged. */
    FLT_WINDOW_NO_VALID_FIBER = 2,
    /** No valid fiber has 3 usable rows for a parabola: bow_mm is NaN. */
    FLT_WINDOW_NO_BOW = 4,
    /** Fewer than 3 valid fibers: crossbow_mm is NaN. */
    FLT_WINDOW_NO_CROSSBOW = 8,
    /** The strip's edges were known in the window: fibers and zones lie on
     * the strip (see "Zones on the strip"). Without it they lie on the
     * fiber grid, as for a strip filling it, and flt_flatness_strip()
     * reports the grid's width and centre. */
    FLT_WINDOW_ON_STRIP = 16
};

/** Where zones are laid (option flat_zones_on). */
typedef enum flt_zones_on {
    /** On the strip, from its edges, where they are known (the default). */
    FLT_ZONES_ON_STRIP = 0,
    /** On the sensor's fiber grid, whatever the strip does. */
    FLT_ZONES_ON_GRID = 1,
    FLT_ZONES_ON_MAX_ENUM_ = 0x7FFFFFFF
} flt_zones_on;

/** The sensor side of the leveler's drive side (option flat_drive_side). */
typedef enum flt_side {
    /** The drive side is at the sensor's low x (the default). */
    FLT_SIDE_LOW_X = 0,
    /** The drive side is at the sensor's high x. */
    FLT_SIDE_HIGH_X = 1,
    FLT_SIDE_MAX_ENUM_ = 0x7FFFFFFF
} flt_side;

/** The shape class of a window, from its zone I-Unit profile p (minus its
 * minimum). Let peak = max p. Below flat_flat_limit I-Units the window is
 * FLAT. Otherwise the "long" material is the part of p above peak / 2; its
 * share in each band of u = (x - centre) / (width / 2) decides:
 *   centre |u| < 0.3, quarters 0.3 <= |u| < 0.7, left edge u <= -0.7,
 *   right edge u >= 0.7.
 * A band holding at least 15% of the long material is a component of the
 * shape (flt_shape_component bits). One component group (centre, quarters,
 * edges) gives its class; the edges give LEFT, RIGHT or BOTH; two or more
 * groups give MIX. Confidence: FLAT 1 - peak / (2 limit) (1 for a perfectly
 * flat window, 0.5 at the limit); any other class a * e, with the amplitude
 * margin a = min(1, peak / (2 limit)) (0.5 at the limit, 1 from twice the
 * limit) and e the share of the long material in the named components. */
typedef enum flt_shape {
    FLT_SHAPE_FLAT = 0,           /**< below flat_flat_limit I-Units */
    FLT_SHAPE_CENTRE_BUCKLE = 1,  /**< the centre is long */
    FLT_SHAPE_WAVY_EDGE_LEFT = 2, /**< the left edge is long (x < centre is left: the drive side) */
    FLT_SHAPE_WAVY_EDGE_RIGHT = 3, /**< the right edge is long */
    /** The same two by the operator's names (flat_drive_side). */
    FLT_SHAPE_WAVY_EDGE_DRIVE_SIDE = 2,
    FLT_SHAPE_WAVY_EDGE_OPERATOR_SIDE = 3, /**< see FLT_SHAPE_WAVY_EDGE_DRIVE_SIDE */
    FLT_SHAPE_WAVY_EDGE_BOTH = 4,          /**< both edges are long */
    FLT_SHAPE_QUARTER_BUCKLE = 5,          /**< the quarters are long */
    FLT_SHAPE_MIX = 6,                     /**< several of the above: see the component bits */
    /** Too short a window, no valid fiber, or fewer than 5 valid zones. */
    FLT_SHAPE_UNDETERMINED = 7,
    /** Not judged: the sheet is incomplete (the gauge, flatline/gauge.h,
     * FLT_SHEET_FLAG_INCOMPLETE); the flatness metrics never give it. */
    FLT_SHAPE_NOT_JUDGED = 8,
    FLT_SHAPE_MAX_ENUM_ = 0x7FFFFFFF
} flt_shape;

/** Components of a shape (bits combine). BOW and CROSSBOW are set when
 * |bow_mm| >= flat_bow_limit and |crossbow_mm| >= flat_crossbow_limit; they
 * do not change the class, which is about fiber lengths only. */
enum {
    FLT_SHAPE_HAS_CENTRE = 1,     /**< long centre */
    FLT_SHAPE_HAS_EDGE_LEFT = 2,  /**< long left edge (the drive side) */
    FLT_SHAPE_HAS_EDGE_RIGHT = 4, /**< long right edge */
    FLT_SHAPE_HAS_QUARTER = 8,    /**< long quarters */
    FLT_SHAPE_HAS_BOW = 16,       /**< bow at or above flat_bow_limit */
    FLT_SHAPE_HAS_CROSSBOW = 32   /**< crossbow at or above flat_crossbow_limit */
};

/** A lower-case English name of a shape, e.g. "centre buckle". Never NULL;
 * "unknown" for a value outside the enum. Static storage.
 * @param shape a shape class.
 * @return its name (static storage).
 */
FLT_API const char *FLT_CALL flt_shape_string(flt_shape shape);

/** Values of the option "flat_reference" (FLT_OPT_FLAT_REFERENCE): the
 * length I-Units are measured against; the bindings' names in quotes. */
typedef enum flt_flat_reference {
    /** "shortest": the shortest valid fiber (the default; ASTM A1030). */
    FLT_FLAT_REFERENCE_SHORTEST = 0,
    /** "mean": the mean of the valid fibers. */
    FLT_FLAT_REFERENCE_MEAN = 1,
    /** Not a value: keeps the type int-sized. */
    FLT_FLAT_REFERENCE_MAX_ENUM_ = 0x7FFFFFFF
} flt_flat_reference;

/** A flatness evaluator (opaque handle). */
typedef struct flt_flatness flt_flatness;

/** @name Sizes a real sensor never reaches
 * A flatness handle takes at most FLT_MAX_FIBERS fibers (common.h) at
 * positions |x| <= FLT_CALIB_MAX_X_MM (calib.h), in at most
 * FLT_FLATNESS_MAX_ZONES zones (a zone narrower than the fiber pitch holds
 * no fiber), and refuses options whose buffers would take more than
 * FLT_FLATNESS_MAX_BYTES by the formula under "Memory" (before allocating).
 * @{ */
#define FLT_FLATNESS_MAX_ZONES 16384        /**< Most zones of a flatness handle. */
#define FLT_FLATNESS_MAX_BYTES 2147483648.0 /**< Most bytes of its buffers (2 GiB). */
/** The largest |s| of a row, mm (1e6 km; a double's spacing there is
 * 1e-4 mm). */
#define FLT_FLATNESS_MAX_S_MM  1.0e12
/** @} */

/** Creates the metrics for `fibers` fibers (1 .. FLT_MAX_FIBERS) at
 * fiber_x [fibers] (mm, finite, strictly increasing, |x| <=
 * FLT_CALIB_MAX_X_MM; copied).
 * options: NULL for the defaults, else read for the flat_* keys; copied.
 * Fails with FLT_ERR_INVALID_ARGUMENT for NULL, zero or too many fibers,
 * bad positions, inconsistent options (flat_update_interval >
 * flat_window_length), more than FLT_FLATNESS_MAX_ZONES zones
 * (flat_zone_width too narrow for the grid's width) or buffers beyond
 * FLT_FLATNESS_MAX_BYTES.
 * @param fibers  the number of fibers (>= 1).
 * @param fiber_x [fibers] fiber positions across the strip, mm.
 * @param options NULL, or the flat_* keys.
 * @param out     receives the handle; NULL on failure.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT as above; FLT_ERR_OUT_OF_MEMORY.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_flatness_create(size_t fibers, const double *fiber_x,
                                                              const flt_options *options,
                                                              flt_flatness **out);

/** The same with the fiber grid of a calibration (flt_calib_get_fiber_grid);
 * calib is only read during the call.
 * @param calib   a finished calibration.
 * @param options NULL, or the flat_* keys.
 * @param out     receives the handle; NULL on failure.
 * @return as flt_flatness_create(); FLT_ERR_INVALID_ARGUMENT also for a
 *         calibration without a fiber grid.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_flatness_create_from_calib(const flt_calib *calib,
                                                                         const flt_options *options,
                                                                         flt_flatness **out);

/** Frees everything. NULL is a no-op.
 * @param flatness the handle, or NULL.
 */
FLT_API void FLT_CALL flt_flatness_destroy(flt_flatness *flatness);

/** The fiber count.
 * @param flatness the flatness handle.
 * @param out receives the fiber count.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_flatness_fibers(const flt_flatness *flatness,
                                                              size_t *out);
/** The zone count: the grid's (or flat_zone_count); a window on a
 * narrower strip uses the first ones.
 * @param flatness the flatness handle.
 * @param out receives the zone count.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_flatness_zones(const flt_flatness *flatness,
                                                             size_t *out);

/** The zone layout on the fiber grid (fixed at create; a window on the
 * strip has its own, flt_flatness_zone_positions): zone j covers
 * [left_x[j], left_x[j] + zone width) mm, centre_x[j] its middle,
 * fiber_count[j] the fibers in it. `zones` must equal flt_flatness_zones().
 * Any output may be NULL.
 * @param flatness the flatness handle.
 * @param zones           flt_flatness_zones().
 * @param left_x_out      [zones] left edges, mm, or NULL.
 * @param centre_x_out    [zones] centres, mm, or NULL.
 * @param fiber_count_out [zones] fibers per zone, or NULL.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_flatness_zone_layout(const flt_flatness *flatness,
                                                                   size_t zones, double *left_x_out,
                                                                   double *centre_x_out,
                                                                   size_t *fiber_count_out);

/** Evaluates one window from the caller's rows (a whole sheet):
 *   s      [rows]          material position, mm, finite, strictly
 *                          increasing, |s| <= FLT_FLATNESS_MAX_S_MM.
 *   z      [rows * fibers] reconstructed heights, mm (NaN allowed where
 *                          flagged or invalid).
 *   flags  [rows * fibers] FLT_FLAG_* bits from the reconstructor, or NULL.
 * `fibers` must equal the handle's. Independent of the streaming state.
 * Fails with FLT_ERR_INVALID_ARGUMENT, keeping the previous results, for
 * NULL arrays, rows < 2, non-increasing s, a window shorter than
 * flat_min_length, or no fiber with flat_min_coverage of usable data.
 * @param flatness the flatness handle.
 * @param rows   rows of the window (>= 2).
 * @param fibers the handle's fiber count.
 * @param s      [rows] positions, mm.
 * @param z      [rows * fibers] heights, mm.
 * @param flags  [rows * fibers] reconstructor flags, or NULL.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT as above.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_flatness_evaluate(flt_flatness *flatness, size_t rows,
                                                                size_t fibers, const double *s,
                                                                const double *z,
                                                                const uint8_t *flags);

/** Streaming: takes rows (arrays as in flt_flatness_evaluate; s continues to
 * increase across calls) until a window completes. *consumed_out: the rows
 * taken (all of them unless a window completed first); *evaluated_out: 1 if
 * a window was evaluated (its results are now readable), else 0. Call again
 * with the rest. Fails with FLT_ERR_BUFFER_FULL when a window would hold
 * more than flat_row_capacity rows (create with a larger capacity); the
 * rows taken before are kept and counted in *consumed_out. Any other failure
 * takes no row. flat_window_length = 0 means no automatic windows: only
 * finish() evaluates, and a sheet must fit in flat_row_capacity rows.
 * @param flatness the flatness handle.
 * @param rows          rows in the block.
 * @param fibers        the handle's fiber count.
 * @param s             [rows] positions, mm.
 * @param z             [rows * fibers] heights, mm.
 * @param flags         [rows * fibers] reconstructor flags, or NULL.
 * @param consumed_out  receives the rows taken.
 * @param evaluated_out receives 1 when a window was evaluated, else 0.
 * @return FLT_OK; FLT_ERR_BUFFER_FULL as above; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong
 * argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_flatness_push(flt_flatness *flatness, size_t rows,
                                                            size_t fibers, const double *s,
                                                            const double *z, const uint8_t *flags,
                                                            size_t *consumed_out,
                                                            int *evaluated_out);

/** Ends the current sheet: evaluates the rows since the current window's
 * start as one window (*evaluated_out = 1; flagged FLT_WINDOW_SHORT if
 * shorter than flat_min_length), or does nothing (*evaluated_out = 0) when
 * fewer than 2 rows are pending. The next row pushed starts a new grid.
 * @param flatness the flatness handle.
 * @param evaluated_out receives 1 when a window was evaluated, else 0.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_flatness_finish(flt_flatness *flatness,
                                                              int *evaluated_out);

/** Drops the pending rows and restarts the window grid; results stay.
 * @param flatness the flatness handle.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_flatness_reset(flt_flatness *flatness);

/** The last evaluated window: its first and last row's s (mm), its row
 * count, FLT_WINDOW_* flags and its sequence number (1 for the first window
 * since create). Any output may be NULL. FLT_ERR_STATE before the first
 * window.
 * @param flatness the flatness handle.
 * @param s_first_out      first row's s, mm, or NULL.
 * @param s_last_out       last row's s, mm, or NULL.
 * @param rows_out         its row count, or NULL.
 * @param window_flags_out its FLT_WINDOW_* bits, or NULL.
 * @param index_out        its sequence number, or NULL.
 * @return FLT_OK; FLT_ERR_STATE before the first window; FLT_ERR_INVALID_ARGUMENT for a NULL or
 * wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_flatness_window(const flt_flatness *flatness,
                                                              double *s_first_out,
                                                              double *s_last_out, size_t *rows_out,
                                                              unsigned *window_flags_out,
                                                              size_t *index_out);

/** Per-fiber results of the last window, [fibers] each (mm, I-Units, mm, mm,
 * %, FLT_FIBER_* bits). Any output may be NULL. FLT_ERR_STATE before the
 * first window.
 * @param flatness the flatness handle.
 * @param fibers the fiber count.
 * @param arc_length_out        [fibers] arc lengths, mm, or NULL.
 * @param i_units_out           [fibers] I-Units, or NULL.
 * @param wave_height_out       [fibers] largest wave heights, mm, or NULL.
 * @param wave_period_out       [fibers] their periods, mm, or NULL.
 * @param steepness_percent_out [fibers] their steepness, %, or NULL.
 * @param flags_out             [fibers] FLT_FIBER_* bits, or NULL.
 * @return FLT_OK; FLT_ERR_STATE before the first window; FLT_ERR_INVALID_ARGUMENT for a NULL or
 * wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL
flt_flatness_fiber_results(const flt_flatness *flatness, size_t fibers, double *arc_length_out,
                           double *i_units_out, double *wave_height_out, double *wave_period_out,
                           double *steepness_percent_out, uint8_t *flags_out);

/** The zone profile of the last window, [zones] I-Units and FLT_ZONE_* bits.
 * Either output may be NULL. FLT_ERR_STATE before the first window.
 * @param flatness the flatness handle.
 * @param zones       the zone count.
 * @param i_units_out [zones] I-Units, or NULL.
 * @param flags_out   [zones] FLT_ZONE_* bits, or NULL.
 * @return FLT_OK; FLT_ERR_STATE before the first window; FLT_ERR_INVALID_ARGUMENT for a NULL or
 * wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_flatness_zone_results(const flt_flatness *flatness,
                                                                    size_t zones,
                                                                    double *i_units_out,
                                                                    uint8_t *flags_out);

/**
 * flt_flatness_evaluate with the strip's edges per row (see "Zones on the
 * strip").
 *
 * @param flatness  the handle.
 * @param rows      rows in the window (>= 2).
 * @param fibers    must equal the handle's.
 * @param s         [rows] material positions, mm, strictly increasing.
 * @param z         [rows * fibers] reconstructed heights, mm.
 * @param flags     [rows * fibers] FLT_FLAG_* bits, or NULL.
 * @param left_mm   [rows] the strip's edge at low sensor x, mm, NaN where
 *                  not known (beyond the view, or no strip); NULL: all
 *                  unknown (then the flags' FLT_FLAG_OFF_STRIP bits tell).
 * @param right_mm  [rows] the edge at high x, likewise. Where both are
 *                  finite, left < right. Infinities are refused.
 * @return as flt_flatness_evaluate; FLT_ERR_INVALID_ARGUMENT for a bad
 *         edge (named with its row).
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_flatness_evaluate_strip(
    flt_flatness *flatness, size_t rows, size_t fibers, const double *s, const double *z,
    const uint8_t *flags, const double *left_mm, const double *right_mm);

/**
 * flt_flatness_push with the strip's edges per row (arrays as in
 * flt_flatness_evaluate_strip; NULL: unknown). Rows pushed through
 * flt_flatness_push have unknown edges.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL
flt_flatness_push_strip(flt_flatness *flatness, size_t rows, size_t fibers, const double *s,
                        const double *z, const uint8_t *flags, const double *left_mm,
                        const double *right_mm, size_t *consumed_out, int *evaluated_out);

/**
 * The strip over the last window: its width and the sensor x of its centre
 * line, each as {mean, min, max} over the rows (mm, from the smoothed
 * per-row values). Without FLT_WINDOW_ON_STRIP: the fiber grid's covered
 * width and centre.
 *
 * @param flatness       the handle.
 * @param width_mm_out   [3] or NULL.
 * @param centre_mm_out  [3] or NULL.
 * @return FLT_OK; FLT_ERR_STATE before the first window.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_flatness_strip(const flt_flatness *flatness,
                                                             double *width_mm_out,
                                                             double *centre_mm_out);

/**
 * Where the last window's zones lie: each zone's centre in strip
 * coordinates (mm from the centre line towards the operator side) and in
 * sensor x (at the window's mean strip position), its width (mm) and the
 * result fibers it holds on the strip. On the grid (no
 * FLT_WINDOW_ON_STRIP) the strip coordinate is measured from the grid's
 * centre. Zones off the strip: NaN positions (FLT_ZONE_OFF_STRIP), width 0, no fiber.
 *
 * @param flatness              the handle.
 * @param zones                 must equal flt_flatness_zones().
 * @param strip_centre_mm_out   [zones] or NULL: centre in strip
 *                              coordinates, mm.
 * @param sensor_centre_mm_out  [zones] or NULL: centre in sensor x, mm.
 * @param width_mm_out          [zones] or NULL: zone width, mm.
 * @param fiber_count_out       [zones] or NULL: result fibers in the zone.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT; FLT_ERR_STATE before the first
 *         window.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_flatness_zone_positions(
    const flt_flatness *flatness, size_t zones, double *strip_centre_mm_out,
    double *sensor_centre_mm_out, double *width_mm_out, size_t *fiber_count_out);

/**
 * Where the last window's result fibers lie: strip coordinate x_s (mm from
 * the centre line towards the operator side) and sensor x at the window's
 * mean strip position.
 *
 * @param flatness         the handle.
 * @param fibers           must equal flt_flatness_fibers().
 * @param strip_x_mm_out   [fibers] or NULL: strip coordinate x_s, mm.
 * @param sensor_x_mm_out  [fibers] or NULL: sensor x, mm.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT; FLT_ERR_STATE before the first
 *         window.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_flatness_fiber_positions(const flt_flatness *flatness,
                                                                       size_t fibers,
                                                                       double *strip_x_mm_out,
                                                                       double *sensor_x_mm_out);

/** The shape of the last window: class, confidence in [0, 1],
 * FLT_SHAPE_HAS_* bits, bow and crossbow sagittas (mm; NaN only with
 * FLT_WINDOW_NO_BOW / FLT_WINDOW_NO_CROSSBOW). Any output may be NULL. FLT_ERR_STATE before
 * the first window.
 * @param flatness the flatness handle.
 * @param shape_out      the shape class, or NULL.
 * @param confidence_out its confidence, or NULL.
 * @param components_out FLT_SHAPE_HAS_* bits, or NULL.
 * @param bow_mm_out     bow sagitta, mm, or NULL.
 * @param crossbow_mm_out crossbow sagitta, mm, or NULL.
 * @return FLT_OK; FLT_ERR_STATE before the first window; FLT_ERR_INVALID_ARGUMENT for a NULL or
 * wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL
flt_flatness_shape(const flt_flatness *flatness, flt_shape *shape_out, double *confidence_out,
                   unsigned *components_out, double *bow_mm_out, double *crossbow_mm_out);

#ifdef __cplusplus
}
#endif

#endif /* FLATLINE_FLATNESS_H */
