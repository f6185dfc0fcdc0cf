// SPDX-License-Identifier: Apache-2.0
/** @file
 * libflatline - the simulated sensor, the built-in default frame source.
 *
 * Vendors commission their HMI with it without a line; the tests measure
 * everything against its ground truth.
 *
 * The sheet
 *   z_sheet(x, s) in mm: the sum of parametric defects (flt_sim_add_defect)
 *   and an optional user height map (flt_sim_set_height_map). x across the
 *   width in strip coordinates (mm from the strip's centre line, width
 *   sim_strip_width, or sim_second_width for every second coil), s the
 *   material coordinate along travel (mm). This is the ground truth: what a
 *   perfect gauge would report. Motion and shear transients are
 *   disturbances, not part of it.
 *
 * The strip in the field
 *   Lateral position: in frame f (encoder e) the strip's centre line lies at
 *   sensor x = c(e) = sim_strip_offset + sim_wander_amplitude sin(2 pi e /
 *   sim_wander_period) + w(e), where w is a slow mean-reverting random walk
 *   of standard deviation sim_wander_sigma and correlation length
 *   sim_wander_length (knots every sim_wander_length / 16 of encoder
 *   travel from sim_start, each step drawn from (sim_seed, knot), joined by
 *   a C1 cubic). The strip moves sideways as a rigid body: both lasers see
 *   the same c(e), and the sheet point at strip coordinate x_s lies at
 *   sensor x = c(e) + x_s.
 *   Coils: with sim_coil_length > 0, coil k (k >= 0) is the material s in
 *   [k P, k P + sim_coil_length), P = sim_coil_length + sim_coil_gap; coil k
 *   is sim_strip_width wide, or sim_second_width for odd k when that is set
 *   (a width change at every coil change). A laser whose material s_L lies
 *   outside every coil sees no strip: heads and tails enter and leave the
 *   field of view one laser after the other.
 *   Surround (sim_surround, flt_sim_surround): the strip fills the field of
 *   view (no lateral edges), or beyond its edges c(e) -+ width / 2 the lasers
 *   fall on nothing or on the roller table: a line at z = -sim_table_depth
 *   (no motion), lit except for a sim_roller_gap wide gap in every
 *   sim_roller_pitch across the width, sim_table_brightness times as bright
 *   as the strip's line; the strip's shadow on the table is not modelled.
 *   A column partly covered by the strip gets that share of the line's
 *   light (the pixel integrates over its width). Glints at the edges
 *   (sim_edge_glints): a saturating specular spot (1.5-4 times full scale)
 *   on the line just inside the edge, 1-6 columns long.
 *   Saturation: sim_line_peak may exceed 1 (a line brighter than full
 *   scale); with sim_blooming the charge above full scale spills into the
 *   neighbouring rows of its column, half up and half down, filling the
 *   first unsaturated pixels.
 *   What real photos show besides: defocus (sim_depth_of_field: the line
 *   widens as the strip leaves the focal plane at z = 0, its sigma growing
 *   as sqrt(1 + (z / dof)^2) and its peak falling as much), dark patches of
 *   the strip (sim_dark_patches: cells 60 mm across by 150 mm along, fixed
 *   to the strip, reflecting 0.15-0.5 of the line's light; the line over
 *   them is dim), a fine texture (sim_texture: cells 2 mm square, fixed to
 *   the strip, each reflecting 1 -+ up to sim_texture of bare steel),
 *   ambient light (sim_ambient: the strip around the lines reads this
 *   fraction of full scale on bare steel, times the reflectance of the
 *   patch and cell each pixel sees, so a patch's or a cell's border is an
 *   edge in the background, across the line as well as along it) and a
 *   camera gamma (sim_gamma). A pixel's place on the strip: x as the
 *   column's lines have it, s linear in the row through the two lines'
 *   rows (laser L's line at s_L). sim_background stays a uniform offset
 *   over the whole frame (stray light, the sensor's dark level).
 *
 * Frames and lasers
 *   Frame f is taken at encoder position e_f = sim_start + f * sim_frame_spacing
 *   (mm). Laser L reads the material at s_L = e_f - offset_L (offsets from the
 *   calibration). At that instant it sees
 *     z_L(x) = z_sheet(x, s_L) + shear(s_L)                 travels with strip
 *            + heave_f + tilt_f * x + eccentricity(e_f)     rigid, same for
 *                                                           both lasers
 *   heave_f ~ N(0, sim_heave_sigma) mm and tilt_f ~ N(0, sim_tilt_sigma)
 *   mm/mm (rotation about the travel axis) are drawn per frame;
 *   eccentricity(e) = sim_eccentricity_amplitude * sin(2 pi e /
 *   sim_eccentricity_period) is a leveler roll's run-out; shear(s) is a
 *   damped sine starting at every cut position c = k * sim_shear_interval:
 *   A exp(-decay (s - c)) sin(2 pi (s - c) / period) for s >= c, with
 *   A = sim_shear_amplitude, decay = sim_shear_decay, period =
 *   sim_shear_period (reference: 50 mm, 0.07 /mm, 10 mm).
 *   Peak-detection noise, sim_peak_sigma px, is independent per laser and
 *   fiber (profile rows) or per laser and column (frames).
 *
 * Two outputs, both with the encoder position and the ground truth
 *   flt_sim_next_rows(): profile rows as the extractor would produce them,
 *   without a camera, fast: per fiber k,
 *     height = (z_behind + z_ahead) / 2,  slope = (z_ahead - z_behind) / Delta-d
 *   at s = e - (offset_0 + offset_1) / 2, where the peak noise enters z_L as
 *   sim_peak_sigma px times the calibration's local dz/dv (mm/px) there.
 *   A fiber is on the strip when its x lies between the strip's edges for
 *   both lasers (a perfect extractor's rule, flatline/extractor.h); off the
 *   strip its height and slope are NaN and its valid byte 0.
 *   flt_sim_next_frame(): camera frames rendered through the calibration:
 *   both lines as Gaussian profiles across rows (sigma sim_line_sigma px,
 *   peak sim_line_peak of full scale) centred on the exact image of z_L(x),
 *   multiplicative speckle (contrast sim_speckle), background
 *   (sim_background of full scale), shot noise (sim_full_well electrons at
 *   full scale), optional spurious reflections (sim_reflections per frame:
 *   half dim secondary reflections of the line, 15-60% of its peak, half
 *   saturating specular glints), quantised to sim_bit_depth bits.
 *   Both advance the same frame counter, and frame f has the same motion in
 *   either output.
 *
 * Determinism
 *   Every random draw of frame f comes from generators seeded with
 *   (sim_seed, f): the same seed and calls give the same bytes with the same
 *   build (another C library's exp/sin may differ in the last bit).
 *
 * Threads
 *   An flt_sim must not be used from two threads at once.
 */
#ifndef FLATLINE_SIM_H
#define FLATLINE_SIM_H

#include "flatline/calib.h"
#include "flatline/common.h"
#include "flatline/extractor.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Parametric defects. Each is amplitude_mm * g(x) * w(s) with
 * w(s) = sin(2 pi s / period_mm) (w = 1 when period_mm = 0) and, with
 * W the strip's width (sim_strip_width, or sim_second_width for every
 * second coil) and x in strip coordinates in [-W/2, W/2] (clamped
 * outside):
 *   FLAT                 g = 0
 *   CENTRE_BUCKLE        g = cos^2(pi x / W)        long centre, flat edges
 *   WAVY_EDGE_LEFT       g = (max(0, -2x/W))^4      x < 0 is the left edge
 *   WAVY_EDGE_RIGHT      g = (max(0, 2x/W))^4
 *   WAVY_EDGE_BOTH       g = (2x/W)^4
 *   QUARTER_BUCKLE       g = exp(-((|x| - W/4) / (W/8))^2)
 *   BOW                  g = 1          (coil set: the whole width together)
 *   CROSSBOW             g = (2x/W)^2   (period 0: a constant transverse bow)
 * Defects add up. */
typedef enum flt_sim_defect {
    FLT_SIM_FLAT = 0,            /**< no defect (g = 0) */
    FLT_SIM_CENTRE_BUCKLE = 1,   /**< long centre (profile above) */
    FLT_SIM_WAVY_EDGE_LEFT = 2,  /**< long left edge */
    FLT_SIM_WAVY_EDGE_RIGHT = 3, /**< long right edge */
    FLT_SIM_WAVY_EDGE_BOTH = 4,  /**< both edges long */
    FLT_SIM_QUARTER_BUCKLE = 5,  /**< long quarters */
    FLT_SIM_BOW = 6,             /**< coil set: the whole width together */
    FLT_SIM_CROSSBOW = 7,        /**< a constant transverse bow */
    FLT_SIM_DEFECT_MAX_ENUM_ = 0x7FFFFFFF
} flt_sim_defect;

/** What the lasers fall on beyond the strip's edges (option sim_surround). */
typedef enum flt_sim_surround {
    /** The strip fills the field of view: no lateral edge is ever seen. */
    FLT_SIM_SURROUND_STRIP = 0,
    /** Nothing: no line beyond the edges (or between coils). */
    FLT_SIM_SURROUND_NOTHING = 1,
    /** The roller table, sim_table_depth below the pass line. */
    FLT_SIM_SURROUND_ROLLER_TABLE = 2,
    FLT_SIM_SURROUND_MAX_ENUM_ = 0x7FFFFFFF
} flt_sim_surround;

/** A simulated sensor (opaque handle). */
typedef struct flt_sim flt_sim;

/** Creates a simulator of the sensor described by `calib` (finished; copied,
 * so it may be destroyed right after), or of the reference sensor when calib
 * is NULL (flt_calib_create_reference(0, 2048, -1000, 2, 1001)).
 * options: NULL for the defaults, else read for the sim_* keys. The sheet
 * starts flat. Allocates everything here: 4 W H + 170 W + 25 K bytes for
 * W x H frames and K fibers (the frame scratch, 4 bytes per pixel, and per
 * column and fiber tables; tests/c/test_memory.c checks it).
 * @param calib   a finished calibration, or NULL for the reference sensor.
 * @param options NULL, or the sim_* keys.
 * @param out     receives the handle; NULL on failure.
 * @return FLT_OK; FLT_ERR_STATE for an unfinished calibration;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument; FLT_ERR_OUT_OF_MEMORY.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sim_create(const flt_calib *calib,
                                                         const flt_options *options, flt_sim **out);

/** Frees everything. NULL is a no-op.
 * @param sim the simulator, or NULL.
 */
FLT_API void FLT_CALL flt_sim_destroy(flt_sim *sim);

/** The largest |height| a defect or a height map may give, mm (10 m, far
 * beyond any sheet; the two lasers' difference of larger ones could leave
 * the range of a double). */
#define FLT_SIM_MAX_HEIGHT_MM 1.0e4
/** The shortest defect period, mm (2 pi s / period must not overflow:
 * sin(inf) is NaN). */
#define FLT_SIM_MIN_PERIOD_MM 1.0e-3

/** Adds a defect (see flt_sim_defect): |amplitude_mm| <=
 * FLT_SIM_MAX_HEIGHT_MM, period_mm 0 or in [FLT_SIM_MIN_PERIOD_MM, 1e12].
 * At most 64 defects.
 * @param sim the simulator.
 * @param kind         the defect.
 * @param amplitude_mm its amplitude, mm.
 * @param period_mm    its period along travel, mm (0: constant).
 * @return FLT_OK; FLT_ERR_BUFFER_FULL for a 65th defect; FLT_ERR_INVALID_ARGUMENT for a NULL or
 * wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sim_add_defect(flt_sim *sim, flt_sim_defect kind,
                                                             double amplitude_mm, double period_mm);

/** Removes every defect and the height map: the sheet is flat again.
 * @param sim the simulator.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sim_clear_sheet(flt_sim *sim);

/** Adds a user height map to the sheet (replacing a previous map):
 * heights [rows * cols] mm, row-major, row r at s = s0_mm + r * ds_mm, column
 * c at x = x0_mm + c * dx_mm (rows, cols >= 2; ds, dx > 0; all finite;
 * |heights| <= FLT_SIM_MAX_HEIGHT_MM).
 * Interpolated bilinearly; clamped to the edge values outside. Copied.
 * @param sim the simulator.
 * @param rows    rows of the map (>= 2).
 * @param cols    columns (>= 2).
 * @param s0_mm   s of row 0, mm.
 * @param ds_mm   row spacing, mm.
 * @param x0_mm   x of column 0, mm.
 * @param dx_mm   column spacing, mm.
 * @param heights [rows * cols] heights, mm.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sim_set_height_map(flt_sim *sim, size_t rows,
                                                                 size_t cols, double s0_mm,
                                                                 double ds_mm, double x0_mm,
                                                                 double dx_mm,
                                                                 const double *heights);

/** The ground truth z_sheet at count points (x[i], s[i]) (mm) into z_out.
 * @param sim the simulator.
 * @param count the number of points.
 * @param x     [count] x, mm.
 * @param s     [count] s, mm.
 * @param z_out [count] receives z_sheet, mm.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sim_surface(const flt_sim *sim, size_t count,
                                                          const double *x, const double *s,
                                                          double *z_out);

/** The fiber count (the calibration's grid) and the frame size, px.
 * @param sim the simulator.
 * @param out receives the fiber count.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sim_fibers(const flt_sim *sim, size_t *out);
/** The frame size of flt_sim_next_frame(), px.
 * @param sim the simulator.
 * @param width_out  receives the width, px.
 * @param height_out receives the height, px.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sim_frame_size(const flt_sim *sim,
                                                             uint32_t *width_out,
                                                             uint32_t *height_out);
/** The pixel format of flt_sim_next_frame (from sim_bit_depth) and the bytes
 * one frame needs at a given stride.
 * @param sim the simulator.
 * @param out receives the pixel format.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sim_pixel_format(const flt_sim *sim,
                                                               flt_pixel_format *out);

/** Generates the next `rows` profile rows (frames f .. f + rows - 1).
 *   fibers          must equal flt_sim_fibers().
 *   encoder_mm_out  [rows] each frame's encoder position (may be NULL).
 *   s_out           [rows] each row's material position, mm.
 *   height_out, slope_out  [rows * fibers] mm and mm/mm; NaN off the strip.
 *   valid_out       [rows * fibers] 1 on the strip, 0 off it. May be NULL
 *                   only while the strip fills the field of view
 *                   (sim_surround = 0 and no coils): otherwise its NaNs
 *                   need their flag, and NULL is refused.
 *   truth_out       [rows * fibers] z_sheet(x_k - c(e), s_row), mm, NaN
 *                   where the fiber is off the strip (may be NULL).
 * Allocates nothing.
 * @param sim the simulator.
 * @param rows           the number of rows.
 * @param fibers         flt_sim_fibers().
 * @param encoder_mm_out [rows] encoder positions, or NULL.
 * @param s_out          [rows] positions, mm.
 * @param height_out     [rows * fibers] heights, mm (NaN off the strip).
 * @param slope_out      [rows * fibers] slopes, mm/mm (NaN off the strip).
 * @param valid_out      [rows * fibers] validity (see above), or NULL.
 * @param truth_out      [rows * fibers] ground truth, mm, or NULL.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sim_next_rows(flt_sim *sim, size_t rows,
                                                            size_t fibers, double *encoder_mm_out,
                                                            double *s_out, double *height_out,
                                                            double *slope_out, uint8_t *valid_out,
                                                            double *truth_out);

/** Renders the next frame.
 *   frame_out       height rows of stride_bytes (>= width * bytes per
 *                   pixel; 16-bit formats: even, 2-byte aligned buffer),
 *                   capacity_bytes >= stride_bytes * height.
 *   encoder_mm_out  the frame's encoder position (may be NULL).
 *   fibers, truth_out  [fibers] z_sheet(x_k - c(e), s_row), NaN off the
 *                   strip as in flt_sim_next_rows (truth_out may be NULL,
 *                   then fibers is ignored).
 *   peak_rows_out, peak_rows_count   [peak_rows_count] = [2 * width] (may be
 *                   NULL, then peak_rows_count is ignored): the exact row of
 *                   each laser's line centre per column, [laser * width + u],
 *                   px, after the peak noise; NaN where the line is outside
 *                   the frame or the column sees no strip (the roller
 *                   table's line is not reported).
 * Allocates nothing. */
FLT_API FLT_NODISCARD flt_status FLT_CALL
flt_sim_next_frame(flt_sim *sim, void *frame_out, size_t capacity_bytes, size_t stride_bytes,
                   double *encoder_mm_out, size_t fibers, double *truth_out, double *peak_rows_out,
                   size_t peak_rows_count);

/** Back to frame 0: the following output repeats the first bytes exactly.
 * @param sim the simulator.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sim_rewind(flt_sim *sim);

/**
 * Ground truth of the strip's edges: where laser `laser` sees them at the
 * given encoder positions (any order; no frame is generated).
 *
 * @param sim           the simulator.
 * @param laser         0 or 1, or 2 for a profile row: the mean of the two
 *                      lasers' edges (the strip at the row's material
 *                      position), present only where both lasers see it.
 * @param count         number of encoder positions (0 is a no-op).
 * @param encoder_mm    [count] encoder positions, mm, finite.
 * @param left_mm_out   [count] the edge at the lower sensor x, mm.
 * @param right_mm_out  [count] the edge at the higher sensor x, mm.
 * @param present_out   [count] 1 where the laser sees the strip, 0 where
 *                      its material lies outside every coil: both edges
 *                      are NaN there, flagged by this 0 (may be NULL). With
 *                      sim_surround = 0 the edges are the strip's nominal
 *                      ones, c(e) -+ width / 2, which the field of view
 *                      never shows.
 * @return FLT_OK, or FLT_ERR_INVALID_ARGUMENT for a NULL array, a laser
 *         above 2 or a non-finite position.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL
flt_sim_strip_edges(const flt_sim *sim, unsigned laser, size_t count, const double *encoder_mm,
                    double *left_mm_out, double *right_mm_out, uint8_t *present_out);

/**
 * Ground truth of a frame's fiber flags: what a perfect extractor reports
 * for a frame at `encoder_mm` (flt_extractor_fiber_flags): 0 for a fiber on
 * the strip for both lasers, FLT_FLAG_OFF_STRIP (flatline/recon.h)
 * otherwise. All 0 with sim_surround = 0 while a coil is under both lasers.
 *
 * @param sim         the simulator.
 * @param encoder_mm  the frame's encoder position, mm, finite.
 * @param fibers      must equal flt_sim_fibers().
 * @param flags_out   [fibers] FLT_FLAG_* bits.
 * @return FLT_OK or FLT_ERR_INVALID_ARGUMENT.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_sim_fiber_flags(const flt_sim *sim, double encoder_mm,
                                                              size_t fibers, uint8_t *flags_out);

/** The reference sensor (docs/sensor.md) as a finished calibration,
 * for the simulator, tests and demos: a 2048 x 2048 camera, f = 6 mm lens,
 * 5.5 um pixels (fx = fy = 1090.9 px), principal point (1030.25, 1019.75),
 * the barrel distortion of a 6 mm lens (k1 = -0.08, k2 = 0.012, p1 = 1.5e-4,
 * p2 = -1e-4, k3 = -0.002), mounted 1140 mm above the strip and 1140 mm
 * behind the lasers, looking down at 45 degrees; vertical laser planes at
 * offsets -50 and +50 mm (Delta-d = 100 mm); encoder 0.01 mm per count.
 * The homographies are the exact pinhole maps (the same camera as
 * tests/c/calib_synth.c). At z = 0 the lines lie near rows 996 (laser 1) and
 * 1044 (laser 0); a height of +1 mm moves them about 0.48 px up.
 *   first_row, rows  the rows read out (an ROI, as line-scan-rate cameras
 *                    do): first_row + rows <= 2048; 0, 2048 for the whole
 *                    sensor. The principal point moves with the ROI.
 *   first_x_mm, pitch_mm, fibers  the fiber grid (pitch > 0, fibers >= 1).
 * Declared here because the simulator is its user; it builds on the public
 * calibration API only.
 * @param first_row  the first row read out.
 * @param rows       the rows read out.
 * @param first_x_mm x of fiber 0, mm.
 * @param pitch_mm   fiber pitch, mm.
 * @param fibers     the fiber count.
 * @param out        receives the finished calibration.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_create_reference(uint32_t first_row,
                                                                     uint32_t rows,
                                                                     double first_x_mm,
                                                                     double pitch_mm, size_t fibers,
                                                                     flt_calib **out);

#ifdef __cplusplus
}
#endif

#endif /* FLATLINE_SIM_H */
