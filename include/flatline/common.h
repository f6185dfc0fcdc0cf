// SPDX-License-Identifier: Apache-2.0
/** @file
 * libflatline - conventions shared by every component.
 *
 * Read this header once; every other header follows it.
 *
 * Naming     Everything public starts with flt_ / FLT_. Handles are opaque
 *            (typedef struct flt_x flt_x;): the library allocates them, the
 *            caller never sees their layout, and they can grow without
 *            breaking the ABI. Nothing in these headers is a struct the caller
 *            could allocate.
 *
 * Lifetime   flt_x_create(..., flt_x **out) allocates; flt_x_destroy(flt_x *)
 *            frees and is a no-op on NULL. On failure *out is set to NULL.
 *
 * Errors     Every fallible function returns an flt_status: FLT_OK (0) on
 *            success, a negative code on failure. The code decides whether the
 *            call failed. flt_last_error_message() then explains why, naming
 *            the offending argument and its value. A failed call leaves the
 *            handle exactly as usable as before the call. No C++ exception
 *            ever leaves the library.
 *
 * Options    Settings go through one mechanism everywhere: an opaque
 *            flt_options bag of key/value pairs (keys are flt_option values,
 *            values are doubles, integer options must be whole numbers).
 *            New keys are appended in later releases; an old binary never
 *            sees a struct change. Pass NULL where a function takes options
 *            to get every default. flt_option_info() reports each key's name,
 *            bounds and default, so bindings can map keyword arguments.
 *
 * Threads    Functions on different handles may run concurrently. One handle
 *            must not be used from two threads at once, unless its header
 *            says it is immutable (a finished calibration is). The error
 *            message is thread-local.
 *
 * Arrays     Two-dimensional arrays are row-major and contiguous: rows along
 *            travel, fibers across the width, element [r * fibers + k].
 *            Every array argument comes with the sizes the caller believes it
 *            has; the library checks them against the handle.
 *
 * Units      Lengths in millimetres (mm), slopes in mm/mm, pixels in px,
 *            unless a name says otherwise.
 */
#ifndef FLATLINE_COMMON_H
#define FLATLINE_COMMON_H

#include <stddef.h>
#include <stdint.h>

#include "flatline/version.h"

/** @def FLT_API
 * Marks the exported functions; everything else in the library is hidden. */
/** @def FLT_CALL
 * Pins the calling convention on 32-bit Windows (__cdecl). */
#if defined(_WIN32) || defined(__CYGWIN__)
#  if defined(FLT_BUILDING_LIBRARY)
#    define FLT_API __declspec(dllexport)
#  elif defined(FLT_STATIC)
#    define FLT_API
#  else
#    define FLT_API __declspec(dllimport)
#  endif
#  define FLT_CALL __cdecl
#else
#  if defined(__GNUC__) && __GNUC__ >= 4
#    define FLT_API __attribute__((visibility("default")))
#  else
#    define FLT_API
#  endif
#  define FLT_CALL
#endif

/** @def FLT_NODISCARD
 * Results that must not be ignored (a warning where the compiler can). */
#if defined(__GNUC__) || defined(__clang__)
#  define FLT_NODISCARD __attribute__((warn_unused_result))
#else
#  define FLT_NODISCARD
#endif

/** The most fibers (longitudinal lines across the width) any handle takes:
 * a calibration's fiber grid, a reconstructor, a flatness handle. 16384 is
 * one per column of the widest frame a calibration accepts; a real sensor
 * has a few thousand. */
#define FLT_MAX_FIBERS 16384

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------------- */
/* Status codes                                                            */
/* ---------------------------------------------------------------------- */

/** Codes are stable: new ones are only ever added. */
typedef enum flt_status {
    /** Success. */
    FLT_OK = 0,
    /** An argument is NULL, out of range, NaN, or disagrees with the handle. */
    FLT_ERR_INVALID_ARGUMENT = -1,
    /** Memory could not be allocated. The handle is unchanged. */
    FLT_ERR_OUT_OF_MEMORY = -2,
    /** The call is not allowed in the handle's current state
     * (for example pull before any push). */
    FLT_ERR_STATE = -3,
    /** A fixed-capacity buffer is full; the message says what to do. */
    FLT_ERR_BUFFER_FULL = -4,
    /** A file could not be opened, read or written. */
    FLT_ERR_IO = -5,
    /** A file or packet is malformed; the message names the field. */
    FLT_ERR_FORMAT = -6,
    /** A camera or transport failed. */
    FLT_ERR_DEVICE = -7,
    /** A device did not answer in time. */
    FLT_ERR_TIMEOUT = -8,
    /** Something named (a device, a feature, an option) does not exist. */
    FLT_ERR_NOT_FOUND = -9,
    /** A numerical problem: a singular system or a failed estimate. */
    FLT_ERR_NUMERIC = -10,
    /** A bug in libflatline. Please report it with the message. */
    FLT_ERR_INTERNAL = -99,
    /** Not a status: makes every int a valid flt_status value, so a code from
     * a newer library is safe to hold in an older program. */
    FLT_STATUS_MAX_ENUM_ = 0x7FFFFFFF
} flt_status;

/** The enumerator name of a status, e.g. "FLT_ERR_INVALID_ARGUMENT".
 * Never NULL; an unknown code gives "FLT_ERR_UNKNOWN". Static storage.
 * @param status a status code.
 * @return its enumerator name (static storage).
 */
FLT_API const char *FLT_CALL flt_status_string(flt_status status);

/** The message of the last failed call on this thread, naming the offending
 * argument and its value. Never NULL: "" when the last call succeeded.
 * Each public call clears it on entry. The pointer stays valid until the next
 * libflatline call on this thread.
 * @return the message (thread-local; see above).
 */
FLT_API const char *FLT_CALL flt_last_error_message(void);

/** The status of the last call on this thread (FLT_OK after a success).
 * @return the status of the last call on this thread.
 */
FLT_API flt_status FLT_CALL flt_last_error_status(void);

/**
 * Records a status and a message as this thread's last error, as a failing
 * call of the library does: flt_last_error_status() and
 * flt_last_error_message() then return them. For libraries built on
 * libflatline that report through its error state (libflatline_testing,
 * flatline/testing.h, does); an application has no need to call it.
 * @param status  FLT_OK clears the error (the message is then ""); any
 *                other value is recorded as it is.
 * @param message UTF-8 text, copied and cut to 511 bytes; NULL or "" with
 *                a failing status records "failed with <status name>".
 */
FLT_API void FLT_CALL flt_set_last_error(flt_status status, const char *message);

/* ---------------------------------------------------------------------- */
/* Version                                                                 */
/* ---------------------------------------------------------------------- */

/** The library's FLT_VERSION_NUMBER, to compare with the headers' one.
 * @return FLT_VERSION_NUMBER of the library.
 */
FLT_API int FLT_CALL flt_version(void);
/** "MAJOR.MINOR.PATCH" of the library. Static storage, never NULL.
 * @return the library's version string.
 */
FLT_API const char *FLT_CALL flt_version_string(void);

/* ---------------------------------------------------------------------- */
/* Options                                                                 */
/* ---------------------------------------------------------------------- */

/** Option keys. Values are fixed forever; new keys are appended.
 * Each key has a name (the snake_case word in quotes, which the Python and C#
 * bindings use as the keyword), bounds and a default; see flt_option_info().
 * Keys are numbered by component, a hundred each: 100s the reconstructor,
 * 200s calibration, 300s the simulator, 400s the extractor, 500s flatness,
 * 600s frame sources, 700s the gauge, 800s quality (tolerance verdicts),
 * 900s the advisor (CONTRIBUTING.md keeps the table).
 * A component refuses a bag in which a key of another component was set
 * (FLT_ERR_INVALID_ARGUMENT, naming the key and both components): such a
 * value would have no effect, which hides a mistake. Give each component
 * a bag of its own; keys only read as their default never count.
 * An option whose value is a choice has named values: a typedef'd enum in
 * its component's header (flt_robust, flt_flat_reference,
 * flt_encoder_mode), and lower-case names for the bindings
 * (flt_option_choice_at()). On/off options (rigid_motion, calib_ransac,
 * calib_rational_distortion) take 0 or 1. */
typedef enum flt_option {
    /* --- reconstructor (flatline/recon.h) --- */
    /** "knot_spacing": distance L between spline knots along travel, mm.
     * 0 (the default) means "equal to laser_spacing"; at least
     * laser_spacing / 16 (a row spans about laser_spacing / L knots, and
     * the cost per mm of strip grows with the cube of that). */
    FLT_OPT_KNOT_SPACING = 100,
    /** "laser_spacing": distance between the two laser lines along travel,
     * Delta-d, mm. Default 100. */
    FLT_OPT_LASER_SPACING = 101,
    /** "height_sigma": standard deviation of one measured height, mm.
     * Default 2.5 (a vibrating strip: rigid bouncing moves both lines). */
    FLT_OPT_HEIGHT_SIGMA = 102,
    /** "slope_sigma": standard deviation of one measured slope, mm/mm.
     * Default 0.001 (bouncing cancels between the lines; what is left is
     * peak-detection noise divided by the laser spacing). A slope sample
     * weighs at most 1e8 height samples: a slope_sigma below
     * height_sigma / (1e4 laser_spacing) acts as that value (only heights
     * see a fiber's level, and double precision carries their share of
     * the normal equations no further; flatline/recon.h). */
    FLT_OPT_SLOPE_SIGMA = 103,
    /** "curvature_weight": weight of the smoothness prior (the integral of
     * z'' squared), dimensionless, relative to one height sample: 1 means
     * bending one knot interval by 1 mm costs as much as one height sample
     * 1 mm off. It bridges stretches without data and keeps the system
     * regular. Default 1e-3. Above 1e8 it acts as 1e8, and below
     * curvature_jump_weight / 1e8 as that (flatline/recon.h: the most
     * double precision carries). */
    FLT_OPT_CURVATURE_WEIGHT = 104,
    /** "lag_knots": the streaming lag in knots (integer): a knot is
     * emitted once this many knots beyond it are complete. -1 (the
     * default) derives it from latency_mm, the way to set it; lag_knots and
     * latency_mm are one setting, so a bag may set one of them only
     * (flt_recon_create fails with FLT_ERR_INVALID_ARGUMENT otherwise). A
     * lag set here is taken as it is, at a strip's head too (latency_mm's
     * longer wait there does not apply). flt_recon_get_option reports the
     * lag in use. */
    FLT_OPT_LAG_KNOTS = 105,
    /** "max_gap": rows in a run of invalid samples whose valid neighbours are
     * more than this far apart are flagged FLT_FLAG_GAP, mm. Default 200. */
    FLT_OPT_MAX_GAP = 106,
    /** "row_capacity": rows the streaming reconstructor can hold, pending
     * and finished-but-not-pulled together (integer). It costs 9 bytes per
     * row and fiber, and robust mode keeps the raw rows of its window in as
     * many slots again (8 bytes per row and fiber). Default 8192: enough
     * for the default latency (3.6 m at a strip's head) at rows every
     * 0.5 mm. A push that does not fit while no row is finished says so. */
    FLT_OPT_ROW_CAPACITY = 107,
    /** "rigid_motion": 1 to model the strip's vibration as what it is, a
     * rigid heave and roll of each frame: every fiber of a frame is offset
     * along one line across the strip. The reconstructor then splits each
     * row into that line (weighted by height_sigma) and the deviations from
     * it (weighted by shape_sigma), which takes the vibration out of the
     * fibers' shape: about 3x less shape error under 2.5 mm of heave
     * (tests/c/test_recon.c). Fibers are then no longer solved independently,
     * and the streamed level converges to the whole-sheet one only at lags
     * of about 150 knots. 0 (the default) fits every fiber on its own.
     * (integer 0 or 1) */
    FLT_OPT_RIGID_MOTION = 108,
    /** "shape_sigma": with rigid_motion, the standard deviation of a height's
     * deviation from its frame's line across the strip, mm: the peak
     * detection noise of the two lasers. Default 0.1. */
    FLT_OPT_SHAPE_SIGMA = 109,
    /** "curvature_jump_weight": weight of the prior against jumps of z'' at
     * the knots, relative to one height sample (the jump is measured as
     * m_{j-1} + 4 m_j + m_{j+1} - 3 (z_{j+1} - z_{j-1}), mm, m = L z').
     * A slope measured as a secant over Delta-d is blind to any shape that
     * repeats every Delta-d; with knots every Delta-d the spline has one:
     * all knots at one height with one slope, a wiggle whose curvature jumps
     * at every knot. Only the heights, which carry the vibration, would pin
     * it. A smooth shape has almost no curvature jumps, so this prior
     * removes the wiggle without bending the shape: under 2.5 mm of
     * vibration it cuts the error about 2.8-fold and costs 0.02 um on the
     * noise-free reference sheet. Default 10. Above 1e8 it acts as 1e8
     * (flatline/recon.h). */
    FLT_OPT_CURVATURE_JUMP_WEIGHT = 110,
    /** "robust" (flt_robust, recon.h): FLT_ROBUST_NONE (0, the default) for
     * least squares; FLT_ROBUST_HUBER (1) for Huber and FLT_ROBUST_TUKEY (2)
     * for Tukey, an M-estimator that takes outliers such as the shear station's
     * ringing and spurious laser peaks out. Its noise levels are estimated
     * from the data, per fiber and per measurement kind (a running median of
     * absolute residuals), so height_sigma and slope_sigma only seed the
     * first pass. Huber is the one to use: Tukey's weights can lock onto a
     * wrong level when a strip starts inside the ringing (1.4 mm against
     * Huber's 0.08 on the reference's sheet). See flatline/recon.h for how
     * it streams. (integer 0..2) */
    FLT_OPT_ROBUST = 111,
    /** "robust_iterations": reweighted passes over the fibers after the plain
     * one (integer 1..10). Each costs about 15 ms per 2000 x 1150 sheet;
     * streaming, the times each row is judged within the one lag (at most
     * once per emission group; no latency of its own). Default 2. With rigid_motion the
     * fibers' deviations carry the peak noise and isolated spurious peaks
     * (the ringing hits every fiber alike, so it lives in the line across
     * the strip, see robust_line_iterations): with 1% of samples 2.5-5 mm
     * off, 1 pass leaves 0.20 mm, 2 leave 0.12 mm, 3 leave 0.09 mm (least
     * squares: 0.40). Without rigid_motion the fibers carry the ringing
     * too: 2 passes leave 0.53 mm of it, 3 leave 0.39, 4 leave 0.32. */
    FLT_OPT_ROBUST_ITERATIONS = 112,
    /** "robust_line_iterations": with rigid_motion and robust, the reweighted
     * passes over the line across the strip (its offset and tilt), which
     * carries the shear station's ringing (integer 1..32). The line is one
     * value per row, so a pass costs about 0.5 ms per sheet; streaming, as
     * robust_iterations (within the lag). Default 8: 4 passes leave
     * 0.12 mm of ringing on the reference's sheet, 6 leave 0.09 mm, 8 leave
     * 0.08 mm (examples/python/compare_filters.py). */
    FLT_OPT_ROBUST_LINE_ITERATIONS = 113,
    /** "latency_mm": the most strip, mm, the streaming reconstructor may take
     * beyond a row before the row is final (plus one row spacing): rows are
     * finished at most this far behind the newest row pushed, in every mode
     * (robust mode's reweighting happens within it). The reconstructor takes
     * the longest lag that keeps it: lag_knots + lag_knots/8 + 2 knots and
     * half the laser spacing; flt_recon_get_option reports that bound.
     * The first rows of a strip (after create or reset) wait up to twice as
     * long: with no strip behind them their level is known from the strip
     * ahead only. Default 2000 (1 s at 120 m/min; with the default spacing
     * a lag of 15 knots, rows final 1.85 m behind, 3.6 m at a strip's
     * head). Shorter costs accuracy, longer costs time: the price is
     * tabled in docs/reconstruction.md (examples/bench/bench_latency).
     * At least 2 knots and half the laser spacing (250 mm by default). */
    FLT_OPT_LATENCY_MM = 114,

    /* --- calibration (flatline/calib.h) --- */
    /** "calib_ransac": 1 to estimate laser homographies inside RANSAC
     * (integer 0 or 1). Default 0. */
    FLT_OPT_CALIB_RANSAC = 200,
    /** "calib_ransac_threshold": a correspondence is an inlier when its
     * reprojection error is below this, px. Default 1 (20 sigma of a 1/16 px
     * peak detector, far below a mis-identified target point). */
    FLT_OPT_CALIB_RANSAC_THRESHOLD = 201,
    /** "calib_ransac_iterations": minimal samples drawn (integer). Default
     * 1000: with 30% outliers a clean 4-point sample is missed with
     * probability (1 - 0.7^4)^1000 < 1e-100. */
    FLT_OPT_CALIB_RANSAC_ITERATIONS = 202,
    /** "calib_ransac_seed": seed of RANSAC's random draws, so a calibration
     * is reproducible (integer). Default 1. */
    FLT_OPT_CALIB_RANSAC_SEED = 203,
    /** "calib_rational_distortion": 1 to estimate the rational radial terms
     * k4..k6 as well as k1, k2, k3, p1, p2 (integer 0 or 1). Default 0. */
    FLT_OPT_CALIB_RATIONAL_DISTORTION = 204,
    /* --- simulated sensor (flatline/sim.h) --- */
    /** "sim_seed": seed of every random draw (integer). Default 1. */
    FLT_OPT_SIM_SEED = 300,
    /** "sim_frame_spacing": encoder travel between frames, mm. Default 3. */
    FLT_OPT_SIM_FRAME_SPACING = 301,
    /** "sim_start": encoder position of frame 0, mm. Default 0. */
    FLT_OPT_SIM_START = 302,
    /** "sim_strip_width": strip width W, mm: the defect shapes' width and,
     * with sim_surround != 0, the strip's edges at its centre line -+ W / 2
     * (see flatline/sim.h). Default 2000. */
    FLT_OPT_SIM_STRIP_WIDTH = 303,
    /** "sim_heave_sigma": rigid vertical motion per frame, mm. Default 0. */
    FLT_OPT_SIM_HEAVE_SIGMA = 304,
    /** "sim_tilt_sigma": rigid roll per frame (rotation about the travel
     * axis, z += tilt * x), mm/mm. Default 0. */
    FLT_OPT_SIM_TILT_SIGMA = 305,
    /** "sim_eccentricity_amplitude": leveler roll run-out, a sine of the
     * encoder position, mm. Default 0 (reference 0.5). */
    FLT_OPT_SIM_ECCENTRICITY_AMPLITUDE = 306,
    /** "sim_eccentricity_period": its period along travel, mm. Default 50. */
    FLT_OPT_SIM_ECCENTRICITY_PERIOD = 307,
    /** "sim_shear_amplitude": initial envelope of the shear-station damped
     * sine, mm. Default 0 (off; reference 50). */
    FLT_OPT_SIM_SHEAR_AMPLITUDE = 308,
    /** "sim_shear_decay": its envelope decay, 1/mm. Default 0.07. */
    FLT_OPT_SIM_SHEAR_DECAY = 309,
    /** "sim_shear_period": its period along the strip, mm. Default 10. */
    FLT_OPT_SIM_SHEAR_PERIOD = 310,
    /** "sim_shear_interval": distance between cuts, mm. Default 3000. */
    FLT_OPT_SIM_SHEAR_INTERVAL = 311,
    /** "sim_peak_sigma": laser peak-detection noise, px, independent per
     * laser. Default 0 (reference 1/16). */
    FLT_OPT_SIM_PEAK_SIGMA = 312,
    /** "sim_bit_depth": bits per pixel of rendered frames, 8 (Mono8), 10, 12
     * or 16 (16-bit words) (integer). Default 8. */
    FLT_OPT_SIM_BIT_DEPTH = 313,
    /** "sim_line_sigma": laser line profile across rows, Gaussian sigma, px.
     * Default 2. */
    FLT_OPT_SIM_LINE_SIGMA = 314,
    /** "sim_line_peak": line peak intensity, fraction of full scale.
     * Default 0.6. */
    FLT_OPT_SIM_LINE_PEAK = 315,
    /** "sim_background": background level, fraction of full scale.
     * Default 0.03. */
    FLT_OPT_SIM_BACKGROUND = 316,
    /** "sim_speckle": speckle contrast, the standard deviation of the
     * multiplicative per-pixel intensity factor. Default 0.05: a blue laser
     * (the reference's 450 nm, chosen against speckle) imaged so each pixel
     * integrates several speckle grains. */
    FLT_OPT_SIM_SPECKLE = 317,
    /** "sim_full_well": electrons at full scale (shot noise); 0 = none.
     * Default 10000. */
    FLT_OPT_SIM_FULL_WELL = 318,
    /** "sim_reflections": mean number of spurious reflections per frame.
     * Default 0. */
    FLT_OPT_SIM_REFLECTIONS = 319,
    /** "sim_surround": what the lasers fall on beyond the strip's edges, an
     * flt_sim_surround (flatline/sim.h): 0 the strip fills the field of
     * view (no edges; the default), 1 nothing, 2 the roller table
     * (integer 0..2). */
    FLT_OPT_SIM_SURROUND = 320,
    /** "sim_strip_offset": the mean lateral position of the strip's centre
     * line, x of the sensor, mm. Default 0. */
    FLT_OPT_SIM_STRIP_OFFSET = 321,
    /** "sim_wander_amplitude": amplitude of the sine in the strip's lateral
     * wander, mm. Default 0. */
    FLT_OPT_SIM_WANDER_AMPLITUDE = 322,
    /** "sim_wander_period": its period in encoder travel, mm. Default 30000. */
    FLT_OPT_SIM_WANDER_PERIOD = 323,
    /** "sim_wander_sigma": standard deviation of the slow random walk in the
     * lateral wander (a mean-reverting walk, so it stays bounded), mm.
     * Default 0. */
    FLT_OPT_SIM_WANDER_SIGMA = 324,
    /** "sim_wander_length": the encoder travel over which the random walk
     * forgets its position (its correlation length), mm. Default 20000. */
    FLT_OPT_SIM_WANDER_LENGTH = 325,
    /** "sim_coil_length": length of each coil's strip along travel, mm;
     * 0 (the default) is one endless strip. Coil k occupies material
     * positions [k (sim_coil_length + sim_coil_gap), + sim_coil_length). */
    FLT_OPT_SIM_COIL_LENGTH = 326,
    /** "sim_coil_gap": travel between one coil's tail and the next coil's
     * head, mm (0: the coils follow each other directly, welded). Default
     * 5000. */
    FLT_OPT_SIM_COIL_GAP = 327,
    /** "sim_second_width": width of every second coil (coils 1, 3, 5, ...),
     * mm; 0 (the default) = sim_strip_width for every coil. */
    FLT_OPT_SIM_SECOND_WIDTH = 328,
    /** "sim_table_depth": the roller table's top below the pass line (z = 0),
     * mm. Default 300. */
    FLT_OPT_SIM_TABLE_DEPTH = 329,
    /** "sim_roller_pitch": the table's lit segments repeat every this many
     * mm across the width. Default 200. */
    FLT_OPT_SIM_ROLLER_PITCH = 330,
    /** "sim_roller_gap": the laser falls through a gap this wide (mm) in
     * every sim_roller_pitch. Default 60. */
    FLT_OPT_SIM_ROLLER_GAP = 331,
    /** "sim_table_brightness": the table line's peak intensity relative to
     * the strip's line. Default 0.5 (dull rollers). */
    FLT_OPT_SIM_TABLE_BRIGHTNESS = 332,
    /** "sim_edge_glints": probability of a specular glint at each strip
     * edge, per laser and frame (the burr of a sheared edge), 0..1.
     * Default 0. */
    FLT_OPT_SIM_EDGE_GLINTS = 333,
    /** "sim_blooming": share of the charge above full scale that spills into
     * the neighbouring rows of its column (half up, half down), 0..1.
     * Default 0: clipped at full scale. */
    FLT_OPT_SIM_BLOOMING = 334,
    /** "sim_depth_of_field": the height (mm) from the focal plane (the pass
     * line, z = 0) at which the line's width has grown by sqrt(2): out of
     * focus its sigma grows as sqrt(1 + (z / dof)^2) and its peak falls as
     * much (the same light). 0..1e4; default 0: always in focus. */
    FLT_OPT_SIM_DEPTH_OF_FIELD = 335,
    /** "sim_dark_patches": share of the strip's surface under dark patches
     * (coated, oiled or scaled), 0..1: cells 60 mm across by 150 mm along,
     * fixed to the strip, each dark with this probability and then
     * reflecting 0.15-0.5 of the line's light. Default 0. */
    FLT_OPT_SIM_DARK_PATCHES = 336,
    /** "sim_gamma": the camera's response, a pixel reads full scale times
     * (signal / full scale)^(1 / gamma), 0.2..5. Default 1: linear. */
    FLT_OPT_SIM_GAMMA = 337,
    /** "sim_ambient": ambient light on the strip as the camera sees it: the
     * surface around the lines reads this fraction of full scale where it
     * is bare steel, times its reflectance (sim_dark_patches, sim_texture),
     * 0..10. Default 0: the strip is dark but for the lasers' lines. */
    FLT_OPT_SIM_AMBIENT = 338,
    /** "sim_texture": contrast of the strip's fine texture, 0..1: cells
     * 2 mm across by 2 mm along, fixed to the strip, each reflecting
     * 1 -+ up to this share of what bare steel does (the line's light and
     * the ambient light alike). Default 0: uniform. */
    FLT_OPT_SIM_TEXTURE = 339,

    /* --- frame-to-profile extractor (flatline/extractor.h) --- */
    /** "extract_laser0_first_row", "extract_laser0_rows": laser 0's band of
     * rows (integers); rows = 0 (default) = automatic from the first frame. */
    FLT_OPT_EXTRACT_LASER0_FIRST_ROW = 400,
    FLT_OPT_EXTRACT_LASER0_ROWS = 401, /**< "extract_laser0_rows": see above */
    /** "extract_laser1_first_row", "extract_laser1_rows": the same, laser 1. */
    FLT_OPT_EXTRACT_LASER1_FIRST_ROW = 402,
    FLT_OPT_EXTRACT_LASER1_ROWS = 403, /**< "extract_laser1_rows": see above */
    /** "extract_sg_window": Savitzky-Golay window, rows, odd (integer).
     * Default 11, about 5 line sigmas for a line of sigma 2 px: shorter
     * windows use too few of the line's pixels and are noisier under speckle
     * (tests/c/test_extractor.c uses 9, 11, 15 for sigma 1.5, 2, 3 px). */
    FLT_OPT_EXTRACT_SG_WINDOW = 404,
    /** "extract_sg_order": Savitzky-Golay polynomial order (integer).
     * Default 2. */
    FLT_OPT_EXTRACT_SG_ORDER = 405,
    /** "extract_min_peak": weakest accepted peak, fraction of full scale:
     * the least maximum, and the least rise of an unsaturated peak above
     * its local background (flatline/extractor.h). Default 0.1. */
    FLT_OPT_EXTRACT_MIN_PEAK = 406,
    /** "extract_max_width": widest accepted line, rows at or above half the
     * peak, px. Default 12. */
    FLT_OPT_EXTRACT_MAX_WIDTH = 407,
    /** "extract_strip_min_z": a line lower than this is not on the strip
     * (the roller table below the pass line), mm. Default -100. */
    FLT_OPT_EXTRACT_STRIP_MIN_Z = 408,
    /** "extract_edge_gap": the widest stretch across the strip without any
     * light (dust, scale) that is not taken for the strip's end, mm.
     * Default 50. */
    FLT_OPT_EXTRACT_EDGE_GAP = 409,
    /** "extract_min_strip_width": the narrowest run of line taken for the
     * strip, mm. Default 100 (a glint or a reflection is narrower). */
    FLT_OPT_EXTRACT_MIN_STRIP_WIDTH = 410,

    /* --- flatness metrics (flatline/flatness.h) --- */
    /** "flat_window_length": streamed evaluation window, the last N mm of
     * strip. 0 = no automatic windows (only flt_flatness_finish evaluates,
     * one window per sheet). Default 3000: at least one period of the
     * longest flatness waves (500-3000 mm). */
    FLT_OPT_FLAT_WINDOW_LENGTH = 500,
    /** "flat_update_interval": strip between two streamed evaluations, mm,
     * at most flat_window_length; 0 = flat_window_length (windows side by
     * side). Default 1000 (0.5 s at 120 m/min). */
    FLT_OPT_FLAT_UPDATE_INTERVAL = 501,
    /** "flat_zone_width": width of an I-Unit zone across the strip, mm.
     * Default 50. */
    FLT_OPT_FLAT_ZONE_WIDTH = 502,
    /** "flat_reference" (flt_flat_reference, flatness.h): the I-Unit
     * reference length, FLT_FLAT_REFERENCE_SHORTEST (0, the default) the
     * shortest valid fiber, FLT_FLAT_REFERENCE_MEAN (1) the mean of the
     * valid fibers. */
    FLT_OPT_FLAT_REFERENCE = 503,
    /** "flat_min_length": shortest window the metrics accept, mm: one
     * flatness wave. Default 500 (the shortest defect waves). */
    FLT_OPT_FLAT_MIN_LENGTH = 504,
    /** "flat_min_coverage": the least share of a window a fiber's usable
     * rows must cover for the fiber to count, 0..1. Default 0.8. */
    FLT_OPT_FLAT_MIN_COVERAGE = 505,
    /** "flat_wave_hysteresis": a crest or trough counts once the profile has
     * retreated from it by this much, mm. Default 0.3: three times the
     * reconstruction noise under the reference vibration (0.1 mm rms). */
    FLT_OPT_FLAT_WAVE_HYSTERESIS = 506,
    /** "flat_flat_limit": a window whose zone profile spans less than this
     * is flat, I-Units. Default 5. */
    FLT_OPT_FLAT_FLAT_LIMIT = 507,
    /** "flat_bow_limit": |bow| from which FLT_SHAPE_HAS_BOW is set, mm of
     * sagitta over the window. Default 2. */
    FLT_OPT_FLAT_BOW_LIMIT = 508,
    /** "flat_crossbow_limit": |crossbow| from which FLT_SHAPE_HAS_CROSSBOW
     * is set, mm of sagitta over the width. Default 2. */
    FLT_OPT_FLAT_CROSSBOW_LIMIT = 509,
    /** "flat_row_capacity": rows one streamed window (or sheet) may hold
     * (integer). It costs 9 bytes per row and fiber. Default 4096 (12 m of
     * strip at 3 mm rows). */
    FLT_OPT_FLAT_ROW_CAPACITY = 510,
    /** "flat_zone_count": zones across the strip, each a flat_zone_count-th
     * of its width (integer); 0 (the default) lays zones of
     * flat_zone_width. */
    FLT_OPT_FLAT_ZONE_COUNT = 511,
    /** "flat_drive_side": the sensor side of the leveler's drive side, an
     * flt_side (flatline/flatness.h): 0 at low x (the default), 1 at high
     * x. Strip coordinates, fibers and zones run from the drive side to the
     * operator side (integer 0 or 1). */
    FLT_OPT_FLAT_DRIVE_SIDE = 512,
    /** "flat_zones_on": where zones are laid, an flt_zones_on
     * (flatline/flatness.h): 0 on the strip, from its edges (the default),
     * 1 on the sensor's fiber grid whatever the strip does (integer 0 or
     * 1). */
    FLT_OPT_FLAT_ZONES_ON = 513,

    /* --- frame sources (flatline/source.h) --- */
    /** "source_encoder_mode" (flt_encoder_mode, source.h): where a frame's
     * encoder position comes from: FLT_ENCODER_AUTO (0, the default),
     * FLT_ENCODER_FIXED_STEP (1), FLT_ENCODER_HOST (2,
     * flt_source_set_encoder), FLT_ENCODER_CHUNK (3, the camera's chunk
     * counter); see flatline/source.h. */
    FLT_OPT_SOURCE_ENCODER_MODE = 600,
    /** "source_encoder_step": travel per frame (per block id) in fixed-step
     * mode, mm. Default 3 (the reference sensor's frame spacing). */
    FLT_OPT_SOURCE_ENCODER_STEP = 601,
    /** "source_encoder_start": encoder position of the first frame (fixed
     * step) or of count 0 (chunk counter), mm. Default 0. */
    FLT_OPT_SOURCE_ENCODER_START = 602,
    /** "source_encoder_mm_per_count": travel per encoder count of a chunk
     * counter, mm. Default 0.01 (the reference sensor's encoder). */
    FLT_OPT_SOURCE_ENCODER_MM_PER_COUNT = 603,
    /** "source_encoder_chunk_id": the chunk id of the camera's encoder
     * counter (integer; camera specific, see its XML's ChunkID). Default
     * 0x4E434445, the simulated camera's. */
    FLT_OPT_SOURCE_ENCODER_CHUNK_ID = 604,
    /** "source_image_bits": significant bits of 16-bit image files: 0 (the
     * default) = Mono16, or 10 or 12 (integer). */
    FLT_OPT_SOURCE_IMAGE_BITS = 605,
    /** "u3v_transfers": asynchronous bulk transfers kept in flight (integer).
     * Default 8: 8 MiB at the default size, half of Linux's default 16 MB
     * usbfs memory. */
    FLT_OPT_U3V_TRANSFERS = 606,
    /** "u3v_transfer_size": largest payload transfer, bytes (integer; rounded
     * down to the camera's alignment). Default 1048576 (1 MiB). */
    FLT_OPT_U3V_TRANSFER_SIZE = 607,
    /** "u3v_control_timeout": floor of the control channel timeout, ms
     * (integer); the camera's max device response time is used when
     * larger. Default 200. */
    FLT_OPT_U3V_CONTROL_TIMEOUT = 608,
    /** "u3v_pending_ack_limit": pending acknowledges accepted for one command
     * before giving up (integer). Default 5. */
    FLT_OPT_U3V_PENDING_ACK_LIMIT = 609,
    /** "u3v_command_attempts": times a command is sent when no acknowledge
     * comes (integer). Default 3. */
    FLT_OPT_U3V_COMMAND_ATTEMPTS = 610,
    /* --- GigE Vision cameras (flt_source_open_gige) --- */
    /** "gige_packet_size": stream packet size, bytes of IP packet (IP, UDP
     * and GVSP headers + data), 576..16384 (integer); 0 (the default)
     * negotiates it with test packets up to 9000 (jumbo frames), keeping the
     * camera's own when it sends none. */
    FLT_OPT_GIGE_PACKET_SIZE = 640,
    /** "gige_control_timeout": wait for a GVCP acknowledge, ms (integer).
     * Default 200. */
    FLT_OPT_GIGE_CONTROL_TIMEOUT = 641,
    /** "gige_command_attempts": times a GVCP command is sent when no
     * acknowledge comes (integer). Default 3. */
    FLT_OPT_GIGE_COMMAND_ATTEMPTS = 642,
    /** "gige_heartbeat_timeout": the camera drops our control privilege after
     * this long without a heartbeat, ms (integer 500..600000); the host sends
     * one every third of it. Default 3000. */
    FLT_OPT_GIGE_HEARTBEAT_TIMEOUT = 643,
    /** "gige_resend_attempts": times a lost packet is asked again before its
     * frame is dropped (integer 0..32; 0 never asks). Default 3. */
    FLT_OPT_GIGE_RESEND_ATTEMPTS = 644,
    /** "gige_resend_timeout": wait for a packet asked again before asking
     * once more; the reorder window (a gap must last this long, or 64 more
     * packets, before its packet counts as missing: packets that overtake
     * each other are no loss); and the silence after which a frame's
     * remaining packets count as missing, ms (integer). Default 20. */
    FLT_OPT_GIGE_RESEND_TIMEOUT = 645,
    /** "gige_socket_buffer": receive buffer asked for the stream socket,
     * bytes (integer; Linux grants at most net.core.rmem_max). Default
     * 4194304 (4 MiB: 16 frames of 512 x 512 Mono8). */
    FLT_OPT_GIGE_SOCKET_BUFFER = 646,
    /** "gige_discovery_timeout": how long flt_source_open_gige() waits for
     * cameras answering a discovery broadcast, ms (integer). Default 1000. */
    FLT_OPT_GIGE_DISCOVERY_TIMEOUT = 647,
    /** "gige_assembly_frames": frames assembled at once while packets of the
     * older ones are asked again (integer 2..64); a frame still incomplete
     * when this many later frames arrive is dropped; a packet more than 4
     * times this many block ids from the newest frame is no packet of the
     * stream. Costs one frame buffer each; fewer are assembled when that
     * many would pass FLT_SOURCE_MAX_BUFFER_BYTES (source.h, "Frame
     * bounds"). Default 8 (80 ms at 100 frames/s for resends to come). */
    FLT_OPT_GIGE_ASSEMBLY_FRAMES = 648,
    /* --- the gauge (flatline/gauge.h) --- */
    /** "gauge_workers": threads that process the frames (integer 0..64); 0
     * processes each frame on the thread that delivers it. Default 2. */
    FLT_OPT_GAUGE_WORKERS = 700,
    /** "gauge_queue_frames": frames the queue between acquisition and
     * processing holds (integer 0..4096); it costs width x height x 2 bytes
     * each. Default 0: as many as fit in 256 MiB, at least 16 (256 frames
     * of 2048 x 256 px, 128 ms at 2000 frames/s; 32 of 2048 x 2048 px);
     * flt_gauge_get_option() reports the count. A finished sheet's
     * evaluation holds a worker for a tenth of a second or more, and a
     * camera's frames queue up meanwhile. */
    FLT_OPT_GAUGE_QUEUE_FRAMES = 701,
    /** "gauge_overflow" (flt_gauge_overflow, gauge.h): what a full queue
     * does with the next frame: FLT_GAUGE_OVERFLOW_DROP (0) drops it and
     * counts it, on the frame's sheet too (a live camera cannot wait);
     * FLT_GAUGE_OVERFLOW_WAIT (1) makes the pushing thread wait for room;
     * FLT_GAUGE_OVERFLOW_AUTO (2, the default) waits for pushed frames and
     * for an attached image sequence or simulator, and drops for an
     * attached camera (USB3 Vision, GigE Vision): nothing is lost unless
     * the frames come from a camera that cannot wait. */
    FLT_OPT_GAUGE_OVERFLOW = 702,
    /** "gauge_frame_spacing": the least encoder advance past the furthest
     * frame taken for a frame to be taken, mm; closer frames are a line
     * stop and skipped. It sizes the buffers (rows per mm of strip), so set
     * it near the real spacing. Default 1 (1 mm frames at 120 m/min are
     * 2000 frames/s). */
    FLT_OPT_GAUGE_FRAME_SPACING = 703,
    /** "gauge_reversal_length": a strip that backs up by more than this, mm,
     * behind its furthest position starts a new strip (an encoder reset for
     * a new coil is such a reversal); a shorter reversal is skipped until
     * the strip is past its furthest position again. Default 500. */
    FLT_OPT_GAUGE_REVERSAL_LENGTH = 704,
    /** "gauge_strip_min_width": a frame shows the strip when its valid
     * fibers span at least this, mm. Default 100. */
    FLT_OPT_GAUGE_STRIP_MIN_WIDTH = 705,
    /** "gauge_tail_length": the strip has left (its tail passed) when no
     * frame showed it over this much travel, mm; shorter runs of frames
     * without it are a gap inside the strip. Default 300 (more than the
     * reconstructor's max_gap, 200). */
    FLT_OPT_GAUGE_TAIL_LENGTH = 706,
    /** "gauge_max_sheet_length": a sheet that grows this long without a cut
     * is ended there, mm. It sizes the sheet buffers. Default 6000. */
    FLT_OPT_GAUGE_MAX_SHEET_LENGTH = 707,
    /** "gauge_keep_maps": what each sheet keeps of its rows (integer): 0
     * nothing (the default), 1 the reconstructed height map, 2 that and the
     * measured heights. */
    FLT_OPT_GAUGE_KEEP_MAPS = 708,
    /** "gauge_sheet_slots": sheets made at create time, which waiting and
     * held sheets use without allocating (integer 1..1024). Default 4. */
    FLT_OPT_GAUGE_SHEET_SLOTS = 709,
    /** "gauge_min_coverage": a sheet whose rows measured are less than
     * this share of the rows its length should hold is flagged
     * FLT_SHEET_FLAG_INCOMPLETE and not judged (0..1). Default 0.95: a
     * stretch the reconstructor bridges instead of measuring hides the
     * waves inside it, so a sheet missing more than 5 % of its rows could
     * read up to 5 % of its I-Units short. */
    FLT_OPT_GAUGE_MIN_COVERAGE = 710,
    /** "gauge_sheet_backlog": sheets that may exist beyond
     * gauge_sheet_slots (waiting to be read or held), each made when
     * needed (integer 0..65536). When that many exist, flt_gauge_push_frame
     * and flt_gauge_push_row refuse the frame (FLT_ERR_BUFFER_FULL) until
     * the caller reads or frees sheets, and an attached source waits (or
     * drops, with gauge_overflow dropping); flt_gauge_flush and the end of
     * a strip never drop one. 0 drops the oldest waiting sheet instead
     * when every slot is taken (FLT_GAUGE_COUNT_SHEETS_DROPPED), for a
     * caller who only wants the newest. Default 16 (gauge.h, "Memory",
     * gives what a sheet costs). */
    FLT_OPT_GAUGE_SHEET_BACKLOG = 711,
    /** "gauge_saturation_limit": a sheet whose share of saturated laser
     * peaks on the strip exceeds this is logged (flatline/log.h) as
     * overexposed (0..1). Default 0.05: beyond a few percent the
     * plateaus' middles, not the lines' centres, carry the heights. */
    FLT_OPT_GAUGE_SATURATION_LIMIT = 712,
    /** "gauge_provisional_mm": an early answer, for a line whose gates are
     * closer to the shear than the reconstructor's latency_mm: once the
     * strip is this far past a cut (mm, 0..1e6), the gauge hands out the
     * open sheet's provisional result (FLT_SHEET_FLAG_PROVISIONAL), its
     * last rows as the reconstructor estimates them then (flt_recon_peek);
     * its final result follows when the rows are final, with the same id.
     * Provisional sheets are not counted in FLT_GAUGE_COUNT_SHEETS, the
     * coil's statistics or the archive. Default 0: none. A value at or
     * above the latency gives none either (the final comes first).
     * docs/gauge.md, "Early answers", tables what it costs in accuracy. */
    FLT_OPT_GAUGE_PROVISIONAL_MM = 713,

    /* ---- leveler advisor (flatline/advisor.h) ---- */
    /** "advisor_damping": lambda of the advice, |P G d + gain r|^2 +
     * lambda |d|^2, relative to the mean squared effect of a unit step
     * (trace((P G)^T P G) / actuators), so that it does not depend on the
     * actuators' units; 0..1e6. Default 0.01: it only holds back actuators
     * with little effect. */
    FLT_OPT_ADVISOR_DAMPING = 900,
    /** "advisor_gain": the share of the expected deviation one advice sets
     * out to remove, 0.01..1. Default 0.5: with the leveler a sheet ahead
     * of the gauge, the loop stays stable while G understates the leveler's
     * effect by up to a factor 1 + 1/gain = 3, and does not overshoot when
     * G overstates it (docs/advisor.md). */
    FLT_OPT_ADVISOR_GAIN = 901,
    /* ---- the quality record: recordings and the archive (flatline/record.h) ---- */
    /** "record_quantum": the height quantum of a recording, mm: each laser's
     * height at each fiber is rounded to it (a power of two from 2^-12 to
     * 2^-4). Default 2^-8 = 0.00390625 (an error of at most 0.002 mm, 2 %
     * of the reference sensor's noise; docs/record.md has the bytes per
     * sample it costs). */
    FLT_OPT_RECORD_QUANTUM = 1000,
    /** "record_commit_interval": the longest a row waits before the writer
     * commits it, ms (integer 20..1000). A killed process or a power cut
     * loses at most about twice this. Default 250. */
    FLT_OPT_RECORD_COMMIT_INTERVAL = 1001,
    /** "record_sync": 1 makes every commit reach the disk before the next
     * (safe against a power cut), 0 leaves it to the operating system (safe
     * against a killed process only); integer. Default 1. */
    FLT_OPT_RECORD_SYNC = 1002,
    /** "record_queue_blocks": blocks of rows waiting for the writer thread
     * before rows are not recorded and counted lost (integer 2..1024).
     * Default 16 (2 s at the default block size and 2000 rows/s). */
    FLT_OPT_RECORD_QUEUE_BLOCKS = 1003,
    /** "record_block_rows": the most rows in one block (integer 16..4096);
     * a block also closes after record_commit_interval. Default 256 (0.13 s
     * at 2000 rows/s). */
    FLT_OPT_RECORD_BLOCK_ROWS = 1004,
    /** "record_frames": raw camera frames kept (flt_record_frames: "none",
     * "all", "ring"). Default 0 (none). */
    FLT_OPT_RECORD_FRAMES = 1005,
    /** "record_frame_seconds": how much the ring keeps, s of frames
     * (0.1..3600). Default 10. */
    FLT_OPT_RECORD_FRAME_SECONDS = 1006,
    /** "record_frame_mb": the most memory the ring (or, for "all", the
     * frames waiting for the writer) may take, MiB (integer 1..65536).
     * Default 512. */
    FLT_OPT_RECORD_FRAME_MB = 1007,
    /** "record_frames_on_fail": 1 saves the ring when a sheet fails a rule
     * (integer 0..1). Default 1. */
    FLT_OPT_RECORD_FRAMES_ON_FAIL = 1008,
    /** "archive_retention_days": sheets older than this are removed, days
     * (0..36500; 0 keeps them for ever). Default 0. */
    FLT_OPT_ARCHIVE_RETENTION_DAYS = 1050,
    /** "archive_retention_mb": the oldest sheets are removed while the
     * archive's sheet data exceed this, MiB (0..1e9; 0: no limit).
     * Default 0. */
    FLT_OPT_ARCHIVE_RETENTION_MB = 1051,
    /** "archive_buffer_mb": sheets kept in memory while the database is
     * away (a server restart), MiB (integer 1..65536); beyond it a sheet
     * is counted lost and logged. Default 256 (about 300 sheets of 3 m). */
    FLT_OPT_ARCHIVE_BUFFER_MB = 1052,
    /** "archive_retry_interval": wait between attempts to reach the
     * database again, ms (integer 10..600000). Default 1000. */
    FLT_OPT_ARCHIVE_RETRY_INTERVAL = 1053,
    /** "archive_close_timeout": how long flt_archive_destroy() keeps trying
     * to store pending sheets, ms (integer 0..600000). Default 10000. */
    FLT_OPT_ARCHIVE_CLOSE_TIMEOUT = 1054,
    /** "archive_map_quantum": the resolution of the archived height maps,
     * mm (1e-6..1). Default 0.001. */
    FLT_OPT_ARCHIVE_MAP_QUANTUM = 1055,
    /** "archive_maps": 1 stores each sheet's reconstructed height map
     * (the gauge keeps it for the archive), 0 only its results (integer).
     * Default 1. */
    FLT_OPT_ARCHIVE_MAPS = 1056,
    /** Not an option: keeps the type int-sized whatever is added. Any int
     * can be passed as a key (the library reads an enum argument as the int
     * it is) and an unknown one is refused with a message. New keys go
     * above this line. */
    FLT_OPT_MAX_ENUM_ = 0x7FFFFFFF
} flt_option;

/** An opaque bag of option values. Keys not set keep their default. */
typedef struct flt_options flt_options;

/** Allocates a bag holding every default.
 * @param out receives the bag; NULL on failure.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL out;
 *         FLT_ERR_OUT_OF_MEMORY.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_options_create(flt_options **out);
/** Frees a bag; NULL is a no-op. Handles created from it keep their own copy
 * of the values, so the bag may be freed right after use.
 * @param options the bag, or NULL.
 */
FLT_API void FLT_CALL flt_options_destroy(flt_options *options);
/** Sets one value and marks the key as set (see the component rule above).
 * Fails, leaving the bag unchanged, with FLT_ERR_NOT_FOUND for an unknown
 * key (as flt_options_get and flt_option_info do), and with
 * FLT_ERR_INVALID_ARGUMENT for a NaN, a value outside the key's bounds or
 * a fraction for an integer key.
 * @param options the bag.
 * @param key    the option key.
 * @param value  its new value.
 * @return FLT_OK; FLT_ERR_NOT_FOUND or FLT_ERR_INVALID_ARGUMENT as above.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_options_set(flt_options *options, flt_option key,
                                                          double value);
/** Reads one value (the default if never set). FLT_ERR_NOT_FOUND for an
 * unknown key.
 * @param options the bag.
 * @param key    the option key.
 * @param out    receives its value.
 * @return FLT_OK; FLT_ERR_NOT_FOUND as above; FLT_ERR_INVALID_ARGUMENT
 *         for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_options_get(const flt_options *options,
                                                          flt_option key, double *out);

/** Looks a key up by its name (e.g. "knot_spacing"). FLT_ERR_NOT_FOUND if no
 * key has that name.
 * @param name the key's name.
 * @param out  receives the key.
 * @return FLT_OK; FLT_ERR_NOT_FOUND as above; FLT_ERR_INVALID_ARGUMENT
 *         for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_option_find(const char *name, flt_option *out);

/** Describes a key: its name (static storage), inclusive bounds, default and
 * whether it takes whole numbers only. Any output pointer may be NULL.
 * FLT_ERR_NOT_FOUND for an unknown key. */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_option_info(flt_option key, const char **name_out,
                                                          double *min_out, double *max_out,
                                                          double *default_out, int *is_integer_out);

/**
 * Names the values of an option whose value is a choice: the index-th
 * choice of `key` (index 0, 1, ... in the order of their values).
 *
 * @param key        an option key, e.g. FLT_OPT_ROBUST.
 * @param index      which choice.
 * @param name_out   receives its lower-case name, e.g. "huber" (static
 *                   storage), which the Python binding accepts as the value.
 * @param value_out  receives its value (the C enumerator), or NULL.
 * @return FLT_OK; FLT_ERR_NOT_FOUND for an unknown key, a key whose value is
 *         a number (it has no choices) or an index past the last choice;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL name_out.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_option_choice_at(flt_option key, size_t index,
                                                               const char **name_out,
                                                               int *value_out);

/** Enumerates the keys: the index-th key for index 0, 1, ...;
 * FLT_ERR_NOT_FOUND past the last one.
 * @param index 0, 1, ...
 * @param out   receives the key.
 * @return FLT_OK; FLT_ERR_NOT_FOUND past the last key;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL out.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_option_at(size_t index, flt_option *out);

#ifdef __cplusplus
}
#endif

#endif /* FLATLINE_COMMON_H */
