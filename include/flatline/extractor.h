// SPDX-License-Identifier: Apache-2.0
/** @file
 * libflatline - the frame-to-profile extractor: camera frame -> one profile
 * row (height, slope and validity per fiber).
 *
 * What it does (docs/sensor.md: what one frame measures)
 *   Per camera column u and per laser L, inside that laser's band of rows
 *   (its region of interest):
 *     1. finds the strongest valid peak: the brightest pixel of the column,
 *        rejected when it is saturated (the format's full scale), too weak
 *        (below extract_min_peak of full scale) or too wide (more than
 *        extract_max_width rows at or above half its maximum); after a
 *        rejection the next brightest peak outside the rejected one is tried
 *        (at most 3 candidates per column and laser). Once the row of
 *        columns is known, a peak is also rejected when its shape departs
 *        from the line's in the other columns of its 256-column block
 *        (wider at half maximum, more light within 1.5 Savitzky-Golay
 *        half-windows, or skewed, beyond 5-7 times the frame's own
 *        column-to-column scatter: a spurious reflection overlapping the
 *        line), and, next to a saturated column or one whose brightest peak
 *        was rejected, when it is more than 0.5 px off the median of its
 *        +-12 neighbours or has fewer than 4 valid ones (a glint's fringe, a
 *        reflection away from the line). lib/extraction/README.md gives
 *        the measured rates;
 *     2. refines its row to sub-pixel accuracy at the zero crossing of the
 *        Savitzky-Golay derivative (window extract_sg_window rows, polynomial
 *        order extract_sg_order) next to the maximum;
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
 *   what flt_recon_push() takes.
 *
 * Bands of rows
 *   Laser L's band is rows [extract_laserL_first_row, + extract_laserL_rows)
 *   of the frame. extract_laserL_rows = 0 (the default) asks for an automatic
 *   band from the first frame processed: the two brightest rows of the
 *   frame's row sums (the two lines), assigned to the lasers in the order the
 *   calibration predicts at z = 0, each band reaching halfway to the other
 *   line on both sides. If the first frame shows no two lines, process()
 *   fails with FLT_ERR_NUMERIC and the next frame tries again.
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
 *   nothing. The per-column search is a vectorised running maximum over the
 *   band; the Savitzky-Golay filter is evaluated only next to the maximum.
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
 *            extract_max_width); copied, not kept.
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
