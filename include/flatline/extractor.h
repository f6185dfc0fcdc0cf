// SPDX-License-Identifier: Apache-2.0
/** @file
 * libflatline - the frame-to-profile extractor: camera frame -> one profile
 * row (height, slope and validity per fiber).
 *
 * What it does (docs/sensor.md: what one frame measures)
 *   Per camera column u and per laser L, inside that laser's band of rows
 *   (its region of interest):
 *     1. finds the strongest valid peak: the brightest pixel of the column,
 *        rejected when it is too weak (below extract_min_peak of full
 *        scale, or, unsaturated, rising less than that above its local
 *        background: a ripple on a bright background is no line) or too
 *        wide (more than extract_max_width rows at or above half its
 *        maximum; "half" is half way between the local background, the
 *        higher of the lowest pixels either side of it, and the maximum);
 *        after a rejection the next brightest peak outside the rejected
 *        one is tried (at most 8 candidates per column and laser). An
 *        unsaturated peak rejected as too wide or too weak above its
 *        background is a bright patch of background and is passed over
 *        whole (its rows at or above its half level, or within
 *        extract_min_peak of its maximum), so that a line beside a
 *        brighter patch (a target's white field) is still found.
 *        A saturated peak (at the format's full scale) is measured, not
 *        dropped: see "Saturation" below. Once the row of
 *        columns is known, a peak is also rejected when its shape departs
 *        from the line's in the other columns of its 256-column block
 *        (wider at half maximum, more light within 1.5 Savitzky-Golay
 *        half-windows, or skewed, beyond 5-7 times the frame's own
 *        column-to-column scatter: a spurious reflection overlapping the
 *        line), and, next to a saturated column or one whose brightest peak
 *        was rejected, when it is more than 0.5 px off the median of its
 *        +-12 neighbours or has fewer than 4 valid ones (a glint's fringe, a
 *        reflection away from the line). Last, the line is followed across
 *        the columns: a run of peaks that continue each other but leave the
 *        line and come back (a reflection brighter than a dim stretch of
 *        the line), with a longer run on each side (the nearest one, at
 *        most 32 columns away, or 128 where a straight line fits both
 *        runs' nearest peaks) and mostly more than 3 px off the straight
 *        line between them, is rejected; the
 *        line under it is read where it is still a peak within 0.5 px of
 *        that straight line, clear of the reflection and of the line's
 *        shape. A run of at most 8 peaks that continues neither
 *        neighbouring run within 32 columns (a speck, light on something
 *        beside the strip) is rejected too. A stretch of up to 64
 *        columns where no candidate was found at all (the line over a dark
 *        patch, rising less than extract_min_peak), between pieces of the
 *        line that agree on a straight course through it, is searched
 *        within 1.5 px of that course: a maximum there that rises 5 times
 *        the stretch's own background noise above its background, as
 *        narrow as the line and not beside something brighter, is the
 *        line, centred by a Gaussian-weighted centroid of the line's
 *        width and kept within 0.5 px of the course.
 *        lib/extraction/README.md gives the measured rates;
 *     2. refines its row to sub-pixel accuracy at the zero crossing of the
 *        Savitzky-Golay derivative (window extract_sg_window rows, polynomial
 *        order extract_sg_order) next to the maximum (a saturated peak: the
 *        middle of its plateau; a line thinner than the window's line, by
 *        the median width of its 256 columns' peaks: again with a window
 *        2.34 x that width, as the default 11 rows is for sigma 2 px; a
 *        line at least 8 px wide at half maximum,
 *        as a strip out of focus gives: Steger's detector at the line's own
 *        scale, which then reads it with less noise; docs/sensor.md,
 *        "Centre estimators");
 *     3. undistorts (u, v) and maps it through the laser's homography to
 *        (x, z) on the laser plane. The exact map is tabulated at create time
 *        (or at the first frame for an automatic band) as a polynomial in v
 *        per column, so the per-frame cost is a few multiplications;
 *     4. resamples z onto the calibration's fiber grid: a least-squares
 *        line through the columns within +-max(fiber pitch, column spacing)
 *        of the fiber, evaluated at the fiber's x. It needs a valid column
 *        on each side, and any missing peak inside that window makes the
 *        fiber invalid: nothing is interpolated across a missing peak. The
 *        line averages over that width, so a kink in the surface across the
 *        width is smoothed over about one pitch.
 *   Then per fiber, with laser L reading material s_L = e - offset_L
 *   (e = encoder_mm of the frame):
 *     height = (z_0 + z_1) / 2                       mm
 *     slope  = (z_ahead - z_behind) / Delta-d        mm/mm
 *   where "ahead" is the laser reading the larger s and Delta-d =
 *   |offset_1 - offset_0|; the row sits at s = e - (offset_0 + offset_1) / 2.
 *   A fiber is valid only when both lasers gave a valid z; otherwise its
 *   height and slope are NaN and its validity byte 0. These rows are exactly
 *   what flt_recon_push() takes; with flt_extractor_fiber_flags() they are
 *   what flt_recon_push_flagged() takes, which keeps the strip's edges.
 *
 * Saturation
 *   Bright or oiled steel drives the line past full scale. Such a peak is
 *   measured, not dropped: its plateau is the rows at full scale around the
 *   maximum (within 1/32 of it, across dips of up to 2 rows, as a
 *   compressed or noisy image ripples there; a plateau wider than
 *   extract_max_width rows is no line); its local background is the foot of
 *   the line's flank on either side (where the pixels stop falling, within
 *   2 extract_max_width rows: a saturated line glows wide, and beyond the
 *   foot may lie dark features that are no part of it), the higher of the
 *   two; its row is the middle between the two crossings of half the
 *   maximum above that background, each interpolated linearly between the
 *   pixels either side (a line that blooms into its neighbouring rows stays
 *   symmetric about its centre). Saturated peaks are checked for
 *   continuity with their neighbours, not for shape: a saturated peak
 *   vouches for its neighbours only within a run of peaks (saturated or
 *   not) that continue each other longer than the continuity window (the
 *   line); one in a shorter run (a glint off the line) is judged by the
 *   line around it, and where it does not continue that line the column's
 *   next candidate is taken if it does (the line under a glint). The frame's
 *   counts are in flt_extractor_saturation(), for an exposure controller.
 *
 * The strip's edges
 *   The sensor is sized for the widest strip; beside a narrower one the
 *   lasers fall on the roller table or on nothing. Per laser, a column
 *   holds the strip's line when it has a valid peak at least
 *   extract_strip_min_z high (a lower line is the roller table). The strip
 *   is the widest run of such columns, at least extract_min_strip_width mm
 *   across; a run continues over columns whose peak was rejected (there is
 *   light there: a reflection, a glint) and over dark stretches (no peak,
 *   or the table's line) up to extract_edge_gap mm wide (dust, scale). Each
 *   end of the run is refined to a fraction of a column: the columns there
 *   hold a share of the line's light equal to the share of their width the
 *   strip covers (clamped at 1), against the median light of the line a
 *   few columns inwards. A glint on the edge brightens the partly covered
 *   column beyond its share and pushes the edge outward (about 0.6 mm on
 *   the simulator). A glint brighter than the line (1.15 times the
 *   median light of the line a few columns inwards, in a column within 6
 *   of the edge) flags that laser's edge (FLT_STRIP_LEFT_GLINT,
 *   FLT_STRIP_RIGHT_GLINT); where the other laser's edge of that side is
 *   clean, it is taken instead (both lasers see the same edge laser
 *   spacing apart along the strip; a shift of more than 0.3 mm between
 *   the two lasers' clean far edges, a yawing strip, is carried over).
 *   With glints at 30 % of the simulator's edges the edges lie
 *   0.19-0.26 mm RMS off (before: 0.36-0.44) against 0.07-0.10 mm
 *   without; the rest are glints on a column the strip barely covers,
 *   which make it look covered without being brighter than the line, and
 *   glints on both lasers. With a glint at every edge the edges lie
 *   0.65-0.75 mm RMS off, and over 80 % of the rows' edges are flagged
 *   (tests/c/test_field.c, edges_within_a_millimetre). A run that reaches
 *   the frame's border has that edge open (not seen).
 *   Edges are in sensor x, mm, through the column map at the line's row.
 *   Fibers and the edges:
 *     - a fiber belongs to the strip when its x lies between the laser's
 *       edges; otherwise it is off the strip for that laser. A fiber is
 *       off the strip in the row (FLT_FLAG_OFF_STRIP) when it is off for
 *       either laser, or a laser sees no strip at all (a head or tail);
 *     - the partly covered edge fiber (its resampling window reaches past
 *       the edge) is fitted from the strip's columns on its own side only,
 *       the window cut at the edge, and needs 2 of them; otherwise it is
 *       invalid data (FLT_FLAG_INVALID_INPUT);
 *     - columns beyond the strip's ends take no part in any fiber, and a
 *       missing peak inside the strip still makes the fibers around it
 *       invalid.
 *   A frame that shows no line at all has no strip: every fiber is off it.
 *
 * Bands of rows
 *   Laser L's band is rows [extract_laserL_first_row, + extract_laserL_rows)
 *   of the frame. extract_laserL_rows = 0 (the default) asks for an automatic
 *   band from the first frame processed: the two brightest rows of the
 *   frame's row sums (the two lines), assigned to the lasers in the order the
 *   calibration predicts at z = 0, each band reaching halfway to the other
 *   line on both sides. A first frame with one line (one laser switched on
 *   while commissioning, a still image) places both bands too: the line is
 *   laser L's when L's plane puts it within -+extract_strip_min_z of the
 *   pass line and the other laser's does not, or puts it at least twice as
 *   far (the strip runs near the pass line; the reference sensor tells the
 *   lasers apart up to about 33 mm from it); the other laser's line is
 *   placed where the calibration puts it at the same height, and the bands
 *   are laid as for two lines (logged at FLT_LOG_INFO; flt_extractor_band()
 *   tells them). A line that could be either laser's, a frame with no line
 *   standing out of its rows (a quarter of extract_min_peak over the width)
 *   or one whose other line would fall outside the frame makes process()
 *   fail with FLT_ERR_NUMERIC, saying which, and the next frame tries
 *   again.
 *
 * Pixel formats
 *   Mono8: one byte per pixel. Mono10, Mono12, Mono16: one little-endian
 *   (host order) 16-bit word per pixel with the data in the low bits (GenICam
 *   unpacked formats); full scale is 2^bits - 1. Rows are `stride_bytes`
 *   apart (>= width * bytes per pixel; 16-bit frames need an even stride and
 *   a 2-byte aligned pointer). The frame size must equal the calibration's.
 *
 * Memory and speed
 *   Everything is allocated by flt_extractor_create(); process() allocates
 *   nothing. A frame W pixels wide and H high with K fibers takes about
 *   730 W + 60 K + 8 H bytes (per column: both lasers' peaks, shapes and
 *   mapping polynomials; 1.5 MB for a 2048-wide camera;
 *   tests/c/test_memory.c checks it), plus the wide lines' kernels: 4 KB
 *   at the default extract_max_width, at most 63 KB. The per-column search is a
 *   vectorised running maximum over the band; the Savitzky-Golay filter is
 *   evaluated only next to the maximum.
 *   examples/bench/bench_extractor.c measures frames per second.
 *
 * Threads
 *   An flt_extractor must not be used from two threads at once; separate
 *   extractors (even from the same calibration) are independent.
 */
#ifndef FLATLINE_EXTRACTOR_H
#define FLATLINE_EXTRACTOR_H

#include "flatline/calib.h"
#include "flatline/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** What flt_extractor_strip() could not see (bits combine). */
enum {
    /** No strip under the laser (no run of line wide enough): a head or a
     * tail between coils, or no line at all. Both open bits are set too. */
    FLT_STRIP_NONE = 1,
    /** The strip reaches the frame's border at low sensor x: that edge lies
     * beyond the field of view and is NaN. */
    FLT_STRIP_LEFT_OPEN = 2,
    /** The same at high sensor x. */
    FLT_STRIP_RIGHT_OPEN = 4,
    /** A glint (a specular spot, brighter than the line can be) lay on the
     * edge at low sensor x, which pushes a measured edge outward (see "The
     * strip's edges" below). For one laser: its own columns held it; the
     * edge given is the other laser's where that one was clean. For the
     * row (laser 2): both lasers' edges held one, and the edge may lie up
     * to about 1.5 mm outward. The edge is still given. */
    FLT_STRIP_LEFT_GLINT = 8,
    /** The same at high sensor x. */
    FLT_STRIP_RIGHT_GLINT = 16
};

/** Pixel formats of a frame; the value is the number of significant bits. */
typedef enum flt_pixel_format {
    FLT_PIXEL_MONO8 = 8,   /**< 8 bits per pixel, one byte each */
    FLT_PIXEL_MONO10 = 10, /**< 10 significant bits in a 16-bit word */
    FLT_PIXEL_MONO12 = 12, /**< 12 significant bits in a 16-bit word */
    FLT_PIXEL_MONO16 = 16, /**< 16 bits per pixel */
    /** Not a format: makes every int a valid flt_pixel_format value. */
    FLT_PIXEL_MAX_ENUM_ = 0x7FFFFFFF
} flt_pixel_format;

/** A frame-to-profile extractor (opaque handle). */
typedef struct flt_extractor flt_extractor;

/** Creates an extractor for frames of a finished calibration.
 *   calib    finished model (FLT_ERR_STATE otherwise); copied, so it may be
 *            destroyed right after this call.
 *   options  NULL for the defaults, else read for the extract_* keys
 *            (bands, extract_sg_window, extract_sg_order, extract_min_peak,
 *            extract_max_width, extract_strip_min_z, extract_edge_gap,
 *            extract_min_strip_width); copied, not kept.
 * FLT_ERR_INVALID_ARGUMENT for a band outside the frame, an even or too
 * small Savitzky-Golay window (it must be >= order + 2), or a band shorter
 * than the window.
 * @param calib   a finished calibration (see above).
 * @param options NULL, or the extract_* keys (see above).
 * @param out     receives the handle; NULL on failure.
 * @return FLT_OK; FLT_ERR_STATE for an unfinished calibration;
 *         FLT_ERR_INVALID_ARGUMENT as above; FLT_ERR_OUT_OF_MEMORY.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_extractor_create(const flt_calib *calib,
                                                               const flt_options *options,
                                                               flt_extractor **out);

/** Frees everything. NULL is a no-op.
 * @param extractor the extractor, or NULL.
 */
FLT_API void FLT_CALL flt_extractor_destroy(flt_extractor *extractor);

/** The number of fibers of a profile row (the calibration's fiber count).
 * @param extractor the extractor.
 * @param out receives the fiber count.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_extractor_fibers(const flt_extractor *extractor,
                                                               size_t *out);

/** Laser `laser`'s band of rows: first row and row count (px). FLT_ERR_STATE
 * while an automatic band waits for its first frame.
 * @param extractor the extractor.
 * @param laser         0 or 1.
 * @param first_row_out receives the band's first row, px.
 * @param rows_out      receives its row count.
 * @return FLT_OK; FLT_ERR_STATE as above; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_extractor_band(const flt_extractor *extractor,
                                                             unsigned laser,
                                                             uint32_t *first_row_out,
                                                             uint32_t *rows_out);

/** Turns one frame into one profile row.
 *   frame          width x height pixels of `format`, rows stride_bytes
 *                  apart. Not retained.
 *   encoder_mm     the encoder position of the frame, mm (finite).
 *   fibers         must equal flt_extractor_fibers().
 *   s_out          the row's material position, mm (may be NULL).
 *   height_out     [fibers] mm, NaN where invalid.
 *   slope_out      [fibers] mm/mm, NaN where invalid.
 *   valid_out      [fibers] 1 where valid, else 0 (may be NULL).
 * A wrong size, format or stride fails with FLT_ERR_INVALID_ARGUMENT naming
 * the argument; the extractor stays usable. Allocates nothing.
 * @param extractor the extractor.
 * @param frame        the pixels (see above).
 * @param format       their pixel format.
 * @param width        frame width, px (the calibration's).
 * @param height       frame height, px (the calibration's).
 * @param stride_bytes bytes from one row to the next.
 * @param encoder_mm   the frame's encoder position, mm.
 * @param fibers       flt_extractor_fibers().
 * @param s_out        the row's position, mm, or NULL.
 * @param height_out   [fibers] heights, mm.
 * @param slope_out    [fibers] slopes, mm/mm.
 * @param valid_out    [fibers] validity, or NULL.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument (the message names it).
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_extractor_process(
    flt_extractor *extractor, const void *frame, flt_pixel_format format, uint32_t width,
    uint32_t height, size_t stride_bytes, double encoder_mm, size_t fibers, double *s_out,
    double *height_out, double *slope_out, uint8_t *valid_out);

/** Diagnostics of the last processed frame: the sub-pixel peak row of every
 * column, rows_out[laser * width + u] (px, raw image rows), NaN where the
 * column has no valid peak. `width` must equal the frame width.
 * FLT_ERR_STATE before the first successful process().
 * @param extractor the extractor.
 * @param width    the frame width, px.
 * @param rows_out [2 * width] peak rows, px.
 * @return FLT_OK; FLT_ERR_STATE as above; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_extractor_peaks(const flt_extractor *extractor,
                                                              size_t width, double *rows_out);

/**
 * The last processed frame's flags per fiber: what flt_recon_push_flagged()
 * takes. 0 for a valid fiber, FLT_FLAG_OFF_STRIP (flatline/recon.h) for a
 * fiber off the strip (see "The strip's edges"), FLT_FLAG_INVALID_INPUT for
 * a fiber on the strip without a valid z from both lasers.
 *
 * @param extractor  the extractor.
 * @param fibers     must equal flt_extractor_fibers().
 * @param flags_out  [fibers] FLT_FLAG_* bits.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT; FLT_ERR_STATE before the first
 *         successful process().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_extractor_fiber_flags(const flt_extractor *extractor,
                                                                    size_t fibers,
                                                                    uint8_t *flags_out);

/**
 * Where the last processed frame shows the strip: its edges across the
 * width, width and centre, in sensor x (mm), to a fraction of a column.
 *
 * @param extractor        the extractor.
 * @param laser            0 or 1; 2 for the profile row: the mean of the
 *                         two lasers' edges (the strip at the row's
 *                         material position s), an edge seen only where
 *                         both lasers see it.
 * @param left_mm_out      the edge at low x, NaN when FLT_STRIP_LEFT_OPEN.
 * @param right_mm_out     the edge at high x, NaN when FLT_STRIP_RIGHT_OPEN.
 * @param width_mm_out     right - left, NaN unless both edges are seen.
 * @param centre_mm_out    (left + right) / 2, NaN unless both are seen.
 * @param strip_flags_out  FLT_STRIP_* bits: which values are NaN and why.
 *                         Any output may be NULL.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a laser above 2;
 *         FLT_ERR_STATE before the first successful process().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_extractor_strip(
    const flt_extractor *extractor, unsigned laser, double *left_mm_out, double *right_mm_out,
    double *width_mm_out, double *centre_mm_out, unsigned *strip_flags_out);

/**
 * The last processed frame's saturation: the strip's columns with a valid
 * peak (the roller table's line and anything beside the strip do not
 * count) and how many of those peaks were saturated (measured as a
 * plateau), for an exposure controller.
 *
 * @param extractor      the extractor.
 * @param laser          0 or 1; 2 for both lasers together.
 * @param peaks_out      columns with a valid peak.
 * @param saturated_out  of those, the saturated ones.
 * @param fraction_out   saturated / peaks, 0 when there is no peak. Any
 *                       output may be NULL.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a laser above 2;
 *         FLT_ERR_STATE before the first successful process().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_extractor_saturation(const flt_extractor *extractor,
                                                                   unsigned laser,
                                                                   size_t *peaks_out,
                                                                   size_t *saturated_out,
                                                                   double *fraction_out);

/** Diagnostics of the last processed frame: each laser's z on the fiber grid,
 * z_out[laser * fibers + k] (mm), NaN where invalid. The material position
 * of laser L's reading is s = encoder_mm - offset_L.
 * @param extractor the extractor.
 * @param fibers the fiber count.
 * @param z_out  [2 * fibers] heights, mm.
 * @return FLT_OK; FLT_ERR_STATE before the first successful process();
 *         FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL
flt_extractor_laser_profiles(const flt_extractor *extractor, size_t fibers, double *z_out);

#ifdef __cplusplus
}
#endif

#endif /* FLATLINE_EXTRACTOR_H */
