// SPDX-License-Identifier: Apache-2.0
/** @file
 * libflatline - the calibration model of a dual-line-laser sensor.
 *
 * What it holds
 *   - Camera intrinsics and lens distortion in OpenCV's pinhole model:
 *     fx, fy, cx, cy (px) and the distortion coefficients in OpenCV's order
 *     k1, k2, p1, p2, k3, k4, k5, k6 (radial k, tangential p; the rational
 *     terms k4..k6 are 0 unless estimated with calib_rational_distortion).
 *     Estimated from images of a planar target (chessboard or circle grid)
 *     or set directly.
 *   - One homography per laser, H_L (3x3, row-major), mapping *undistorted*
 *     image points (u, v, 1) in px to that laser plane's (x, z, 1) in mm.
 *     Estimated from image/plane correspondences: normalised DLT (Hartley),
 *     then Levenberg-Marquardt refinement of the image reprojection error
 *     (the plane points are the known target geometry; the noise is in the
 *     image), optionally inside RANSAC. Or set directly.
 *   - Sensor geometry: the frame size (px), each laser's offset along travel
 *     (mm), the encoder scale (mm per count) and the fiber grid (first x,
 *     pitch, count).
 *
 * Frames and units
 *   Image: u right, v down, px, origin at the centre of the top-left pixel
 *   (OpenCV's convention). "Raw" image points are what the camera sees
 *   (distorted); "undistorted" points are ideal pinhole points expressed in
 *   the same pixel frame through fx, fy, cx, cy.
 *   Laser plane: x across the width (mm), z up (mm). Laser L at encoder
 *   reading e sees material s = e - offset_L (mm). The laser spacing
 *   Delta-d = offset_1 - offset_0 (positive when laser 1 is further along
 *   travel). There are FLT_CALIB_LASERS = 2 lasers, numbered 0 and 1.
 *
 * Life cycle
 *   flt_calib_create() gives an empty, unfinished model. Fill it with the
 *   set_/estimate_ functions in any order (except that a homography is
 *   estimated through the intrinsics, so those come first), then
 *   flt_calib_finish() checks that every part is present and freezes it.
 *   Mapping and saving need a finished model; setters on a finished model
 *   fail with FLT_ERR_STATE. flt_calib_load() returns a finished model.
 *   A finished model of the reference sensor, without photos:
 *   flt_calib_create_reference(), declared in flatline/sim.h with the
 *   simulated sensor it describes (flatline/flatline.h includes both).
 *
 * Threads
 *   A finished flt_calib is immutable: any number of threads may map, query
 *   and save through it at once (the mapping functions allocate nothing and
 *   keep no cache). An unfinished one must not be used from two threads at
 *   once. Destroying it while another thread uses it is, as always, a bug.
 *
 * File format (flt_calib_save / flt_calib_load)
 *   JSON text, UTF-8, "\n" line ends, fixed field order, every double written
 *   with "%.17g" so values round-trip exactly and save -> load -> save is
 *   byte-identical. Version 1:
 *
 *   {
 *     "format": "flatline-calibration",
 *     "version": 1,
 *     "frame": {"width": 2048, "height": 2048},                  px, integers
 *     "camera": {"fx": .., "fy": .., "cx": .., "cy": ..,         px
 *                "distortion": {"k1": .., "k2": .., "p1": .., "p2": ..,
 *                               "k3": .., "k4": .., "k5": .., "k6": ..}},
 *     "lasers": [                                                exactly 2
 *       {"offset_mm": -50, "homography": [h11, h12, .., h33]},   row-major
 *       {"offset_mm": 50, "homography": [..]}
 *     ],
 *     "encoder_mm_per_count": 0.01,
 *     "fibers": {"first_x_mm": -1000, "pitch_mm": 2, "count": 1001}
 *   }
 *
 *   Loading is strict: a truncated file, a missing, extra or duplicated
 *   field, a wrong type (string for number, fraction for integer), a NaN or
 *   infinity, a version other than 1, a non-invertible homography, a value
 *   outside its range (see "Physically meaningful ranges" below: the file
 *   holds what the setters accept, no more), or more than
 *   FLT_CALIB_MAX_FILE_BYTES of text fails with FLT_ERR_FORMAT and a
 *   message naming the field (e.g. "lasers[1].homography[4]"). A failed load
 *   never returns an object.
 *   Newer versions of the format get a new "version" number.
 */
#ifndef FLATLINE_CALIB_H
#define FLATLINE_CALIB_H

#include "flatline/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------------- */
/* Physically meaningful ranges                                            */
/* ---------------------------------------------------------------------- */
/* Every setter and the loader refuse a value outside these ranges
 * (FLT_ERR_INVALID_ARGUMENT from a setter, FLT_ERR_FORMAT from a file, the
 * message naming the argument or field, its value and the range). They are
 * far wider than any real dual-line-laser sensor and bound what the
 * extractor, the simulator and the flatness metrics compute from a
 * calibration, so a hand-edited file can neither overflow their arithmetic
 * nor ask them for gigabytes. Estimates (flt_calib_estimate_*) that land
 * outside are refused with FLT_ERR_NUMERIC and leave the model unchanged.
 *
 *   frame width, height     1 .. FLT_CALIB_MAX_FRAME_SIDE px (16384: 2^28
 *                           pixels, more than any area-scan sensor made)
 *   fx, fy                  FLT_CALIB_MIN_FOCAL_PX .. FLT_CALIB_MAX_FOCAL_PX
 *                           (1 .. 1e6 px: a 1000 mm lens on 1 um pixels)
 *   cx, cy                  |c| <= FLT_CALIB_MAX_PRINCIPAL_PX (65536 px,
 *                           four of the largest frames from the image origin)
 *   k1, k2, k3, k4, k5, k6  |k| <= FLT_CALIB_MAX_RADIAL (1000)
 *   p1, p2                  |p| <= FLT_CALIB_MAX_TANGENTIAL (1)
 *   homography              finite, invertible (reciprocal condition number
 *                           above 1e-12), its largest |entry| in
 *                           [FLT_CALIB_MIN_HOMOGRAPHY_SCALE,
 *                            FLT_CALIB_MAX_HOMOGRAPHY_SCALE] (1e-100 .. 1e100;
 *                           a homography is defined up to scale, so any
 *                           can be scaled into that)
 *   laser offset            |offset| <= FLT_CALIB_MAX_OFFSET_MM (10 m)
 *   laser spacing           |offset_1 - offset_0| >=
 *                           FLT_CALIB_MIN_LASER_SPACING_MM (1 mm; checked by
 *                           flt_calib_finish and the loader)
 *   encoder scale           FLT_CALIB_MIN_ENCODER_MM <= |mm per count| <=
 *                           FLT_CALIB_MAX_ENCODER_MM (1e-9 .. 1e6, the
 *                           range of source_encoder_mm_per_count)
 *   fiber grid              pitch FLT_CALIB_MIN_PITCH_MM .. FLT_CALIB_MAX_PITCH_MM
 *                           (1 um .. 10 m), count 1 .. FLT_MAX_FIBERS
 *                           (16384, common.h), every fiber's |x| <=
 *                           FLT_CALIB_MAX_X_MM
 *                           (100 m: first_x_mm and the last fiber)
 *   file                    at most FLT_CALIB_MAX_FILE_BYTES (64 KiB; a
 *                           calibration is about 1.5 kB) and 256 JSON
 *                           values (a calibration has 50)
 */
#define FLT_CALIB_MAX_FRAME_SIDE       16384    /**< Largest frame width or height, px. */
#define FLT_CALIB_MIN_FOCAL_PX         1.0      /**< Smallest fx, fy, px. */
#define FLT_CALIB_MAX_FOCAL_PX         1.0e6    /**< Largest fx, fy, px. */
#define FLT_CALIB_MAX_PRINCIPAL_PX     65536.0  /**< Largest |cx|, |cy|, px. */
#define FLT_CALIB_MAX_RADIAL           1.0e3    /**< Largest |k1| .. |k6|. */
#define FLT_CALIB_MAX_TANGENTIAL       1.0      /**< Largest |p1|, |p2|. */
#define FLT_CALIB_MIN_HOMOGRAPHY_SCALE 1.0e-100 /**< Smallest largest |entry| of a homography. */
#define FLT_CALIB_MAX_HOMOGRAPHY_SCALE 1.0e100  /**< Largest |entry| of a homography. */
#define FLT_CALIB_MAX_OFFSET_MM        1.0e4    /**< Largest |laser offset|, mm. */
#define FLT_CALIB_MIN_LASER_SPACING_MM \
  1.0 /**< Smallest distance between the lasers along travel, mm. */
#define FLT_CALIB_MIN_ENCODER_MM 1.0e-9 /**< Smallest |encoder scale|, mm per count. */
#define FLT_CALIB_MAX_ENCODER_MM 1.0e6  /**< Largest |encoder scale|, mm per count. */
#define FLT_CALIB_MIN_PITCH_MM   1.0e-3 /**< Smallest fiber pitch, mm. */
#define FLT_CALIB_MAX_PITCH_MM   1.0e4  /**< Largest fiber pitch, mm. */
#define FLT_CALIB_MAX_X_MM       1.0e5  /**< Largest |x| of a fiber, mm. */
#define FLT_CALIB_MAX_FILE_BYTES 65536  /**< Largest calibration text, bytes. */

/** Number of lasers (and homographies) of the sensor. */
#define FLT_CALIB_LASERS             2
/** Number of distortion coefficients, OpenCV order k1 k2 p1 p2 k3 k4 k5 k6. */
#define FLT_CALIB_DISTORTION_COEFFS  8
/** Values of the camera: fx, fy, cx, cy (flt_calib_set_intrinsics). */
#define FLT_CALIB_CAMERA_VALUES      4
/** Entries of a homography: 3 x 3, row-major. */
#define FLT_CALIB_HOMOGRAPHY_ENTRIES 9
/** The version of the file format flt_calib_save() writes. */
#define FLT_CALIB_FORMAT_VERSION     1

/** A calibration model (opaque handle; immutable once finished). */
typedef struct flt_calib flt_calib;

/** Calibration target kinds for flt_calib_estimate_intrinsics(). */
typedef enum flt_calib_target {
    /** Chessboard; columns x rows counts the *inner* corners. */
    FLT_TARGET_CHESSBOARD = 0,
    /** Symmetric grid of dark circles on white; columns x rows circles. */
    FLT_TARGET_CIRCLE_GRID = 1,
    /** Asymmetric circle grid (OpenCV's layout); pitch is the distance
     * between neighbouring circles of one row divided by two. */
    FLT_TARGET_ASYMMETRIC_CIRCLE_GRID = 2
} flt_calib_target;

/* ---------------------------------------------------------------------- */
/* Life cycle                                                              */
/* ---------------------------------------------------------------------- */

/** Allocates an empty, unfinished model. *out is NULL on failure.
 * @param out receives the model.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL out; FLT_ERR_OUT_OF_MEMORY.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_create(flt_calib **out);
/** Frees a model; NULL is a no-op.
 * @param calib the model, or NULL.
 */
FLT_API void FLT_CALL flt_calib_destroy(flt_calib *calib);
/** Checks that intrinsics, frame size, both homographies, both laser
 * offsets (at least FLT_CALIB_MIN_LASER_SPACING_MM apart), the encoder
 * scale and the fiber grid are set, then freezes the model. FLT_ERR_STATE
 * names the first missing part or the offsets (the model stays unfinished
 * and usable). Finishing twice is FLT_ERR_STATE.
 * @param calib the model.
 * @return FLT_OK; FLT_ERR_STATE as above; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_finish(flt_calib *calib);
/** *out = 1 if finished, else 0.
 * @param calib the model.
 * @param out receives 1 or 0.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_is_finished(const flt_calib *calib, int *out);

/* ---------------------------------------------------------------------- */
/* Camera                                                                  */
/* ---------------------------------------------------------------------- */

/** Frame size in px (each 1 .. FLT_CALIB_MAX_FRAME_SIDE). Needed before
 * estimating intrinsics.
 * @param calib the model.
 * @param width  frame width, px.
 * @param height frame height, px.
 * @return FLT_OK; FLT_ERR_STATE on a finished model; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong
 * argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_set_frame_size(flt_calib *calib, uint32_t width,
                                                                   uint32_t height);
/** The frame size, px. FLT_ERR_STATE if unset.
 * @param calib the model.
 * @param width_out  receives the width, px.
 * @param height_out receives the height, px.
 * @return FLT_OK; FLT_ERR_STATE as above; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_get_frame_size(const flt_calib *calib,
                                                                   uint32_t *width_out,
                                                                   uint32_t *height_out);

/** Sets the intrinsics directly, copying both arrays; each value within its
 * range (see "Physically meaningful ranges").
 *   camera, camera_count   {fx, fy, cx, cy} px; camera_count must be
 *            FLT_CALIB_CAMERA_VALUES.
 *   distortion, distortion_count   the FLT_CALIB_DISTORTION_COEFFS
 *            coefficients (OpenCV order; distortion_count must be that), or
 *            NULL (distortion_count ignored) for none. */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_set_intrinsics(flt_calib *calib,
                                                                   const double *camera,
                                                                   size_t camera_count,
                                                                   const double *distortion,
                                                                   size_t distortion_count);
/** Copies the intrinsics out: camera_out[camera_count] = {fx, fy, cx, cy}
 * (camera_count = FLT_CALIB_CAMERA_VALUES) and
 * distortion_out[distortion_count] (= FLT_CALIB_DISTORTION_COEFFS); either
 * array may be NULL (its count is then ignored). FLT_ERR_STATE if none are
 * set. */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_get_intrinsics(const flt_calib *calib,
                                                                   double *camera_out,
                                                                   size_t camera_count,
                                                                   double *distortion_out,
                                                                   size_t distortion_count);

/** Estimates the intrinsics from `views` images of a planar target, with
 * OpenCV's detection, sub-pixel corner refinement and calibrateCamera, and
 * stores them in the model (the frame size must be set; every image has that
 * size).
 *   images[i]   8-bit grey image i, rows of `stride` bytes (>= width),
 *               frame-size height rows. Not retained.
 *   target, columns, rows, pitch_mm   the target layout (columns, rows >= 3;
 *               pitch = square side or circle spacing, mm).
 *   options     calib_rational_distortion (NULL = defaults).
 *   rms_px_out  overall RMS reprojection error, px (may be NULL).
 *   view_rms_px_out  `views` doubles (may be NULL): each view's RMS
 *               reprojection error in px, NaN where the target was not found.
 * Views without a detected target are skipped; fewer than 3 usable views is
 * FLT_ERR_NUMERIC and leaves the model unchanged.
 * @param calib the model.
 * @param views the number of images.
 * @param images [views] the images.
 * @param stride bytes from one image row to the next.
 * @param target the target kind.
 * @param columns target columns.
 * @param rows target rows.
 * @param pitch_mm target pitch, mm.
 * @param options NULL, or calib_rational_distortion.
 * @param rms_px_out overall RMS error, px, or NULL.
 * @param view_rms_px_out [views] per-view RMS errors, px, or NULL.
 * @return FLT_OK; FLT_ERR_NUMERIC as above; FLT_ERR_STATE on a finished model
 *         or without a frame size; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_estimate_intrinsics(
    flt_calib *calib, size_t views, const uint8_t *const *images, size_t stride,
    flt_calib_target target, uint32_t columns, uint32_t rows, double pitch_mm,
    const flt_options *options, double *rms_px_out, double *view_rms_px_out);

/* ---------------------------------------------------------------------- */
/* Laser planes                                                            */
/* ---------------------------------------------------------------------- */

/** Sets laser `laser`'s homography directly: h[h_count], 3 x 3 row-major
 * (h_count = FLT_CALIB_HOMOGRAPHY_ENTRIES), maps undistorted (u, v, 1) px
 * to (x, z, 1) mm. It must be finite, invertible and within the scale range
 * (FLT_ERR_INVALID_ARGUMENT otherwise). Copied. */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_set_homography(flt_calib *calib, unsigned laser,
                                                                   const double *h, size_t h_count);
/** Copies laser `laser`'s homography into h_out[h_count], h_count =
 * FLT_CALIB_HOMOGRAPHY_ENTRIES. FLT_ERR_STATE if unset. */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_get_homography(const flt_calib *calib,
                                                                   unsigned laser, double *h_out,
                                                                   size_t h_count);

/** Estimates laser `laser`'s homography from `count` correspondences and
 * stores it (the intrinsics must be set: the image points are undistorted
 * through them first).
 *   image_px  count x 2 raw image points (u, v), px.
 *   plane_mm  count x 2 laser-plane points (x, z), mm.
 *   options   calib_ransac, calib_ransac_threshold, calib_ransac_iterations,
 *             calib_ransac_seed (NULL = defaults: no RANSAC).
 *   residual_px_out  count doubles (may be NULL): distance in px between
 *             each undistorted image point and its plane point mapped into
 *             the image through the estimate.
 *   residual_mm_out  count doubles (may be NULL): distance in mm between
 *             each image point mapped onto the plane and its plane point.
 *   inlier_out  count bytes (may be NULL): 1 where the point was used in the
 *             final fit (all 1 without RANSAC).
 *   rms_px_out, rms_mm_out  RMS of the residuals over the inliers (may be
 *             NULL).
 * Needs count >= 4 with no three plane points collinear in practice;
 * a degenerate set is FLT_ERR_NUMERIC and leaves the model unchanged.
 * The estimation is deterministic (RANSAC draws from calib_ransac_seed).
 * @param calib the model.
 * @param laser 0 or 1.
 * @param count the number of correspondences.
 * @param image_px [count * 2] image points, px.
 * @param plane_mm [count * 2] plane points, mm.
 * @param options NULL, or the calib_ransac* keys.
 * @param residual_px_out [count] residuals, px, or NULL.
 * @param residual_mm_out [count] residuals, mm, or NULL.
 * @param inlier_out [count] inlier marks, or NULL.
 * @param rms_px_out RMS over the inliers, px, or NULL.
 * @param rms_mm_out RMS over the inliers, mm, or NULL.
 * @return FLT_OK; FLT_ERR_NUMERIC as above; FLT_ERR_STATE on a finished model
 *         or without intrinsics; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_estimate_homography(
    flt_calib *calib, unsigned laser, size_t count, const double *image_px, const double *plane_mm,
    const flt_options *options, double *residual_px_out, double *residual_mm_out,
    uint8_t *inlier_out, double *rms_px_out, double *rms_mm_out);

/* ---------------------------------------------------------------------- */
/* Sensor geometry                                                         */
/* ---------------------------------------------------------------------- */

/** Laser `laser`'s offset along travel, mm (|offset| <=
 * FLT_CALIB_MAX_OFFSET_MM). flt_calib_finish() also wants the two offsets
 * at least FLT_CALIB_MIN_LASER_SPACING_MM apart.
 * @param calib the model.
 * @param laser 0 or 1.
 * @param offset_mm its offset along travel, mm.
 * @return FLT_OK; FLT_ERR_STATE on a finished model; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong
 * argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_set_laser_offset(flt_calib *calib,
                                                                     unsigned laser,
                                                                     double offset_mm);
/** Laser `laser`'s offset along travel, mm. FLT_ERR_STATE if unset.
 * @param calib the model.
 * @param laser 0 or 1.
 * @param out receives the offset, mm.
 * @return FLT_OK; FLT_ERR_STATE as above; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_get_laser_offset(const flt_calib *calib,
                                                                     unsigned laser, double *out);
/** Delta-d = offset_1 - offset_0, mm. FLT_ERR_STATE unless both are set.
 * @param calib the model.
 * @param out receives Delta-d, mm.
 * @return FLT_OK; FLT_ERR_STATE as above; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_laser_spacing(const flt_calib *calib,
                                                                  double *out);

/** Encoder scale, mm of travel per count (its magnitude in
 * [FLT_CALIB_MIN_ENCODER_MM, FLT_CALIB_MAX_ENCODER_MM]; negative when the
 * encoder counts down as the strip moves forward).
 * @param calib the model.
 * @param encoder_mm_per_count mm of travel per count.
 * @return FLT_OK; FLT_ERR_STATE on a finished model; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong
 * argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_set_encoder_scale(flt_calib *calib,
                                                                      double encoder_mm_per_count);
/** The encoder scale, mm per count. FLT_ERR_STATE if unset.
 * @param calib the model.
 * @param out receives mm per count.
 * @return FLT_OK; FLT_ERR_STATE as above; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_get_encoder_scale(const flt_calib *calib,
                                                                      double *out);

/** Fiber grid: fiber k sits at x = first_x_mm + k * pitch_mm, k < count
 * (pitch in [FLT_CALIB_MIN_PITCH_MM, FLT_CALIB_MAX_PITCH_MM], count in
 * [1, FLT_MAX_FIBERS], every fiber's |x| <= FLT_CALIB_MAX_X_MM).
 * @param calib the model.
 * @param first_x_mm x of fiber 0, mm.
 * @param pitch_mm   fiber pitch, mm.
 * @param count      the number of fibers.
 * @return FLT_OK; FLT_ERR_STATE on a finished model; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong
 * argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_set_fiber_grid(flt_calib *calib,
                                                                   double first_x_mm,
                                                                   double pitch_mm, size_t count);
/** The fiber grid: first x (mm), pitch (mm), count. FLT_ERR_STATE if unset.
 * @param calib the model.
 * @param first_x_mm_out receives x of fiber 0, mm.
 * @param pitch_mm_out   receives the pitch, mm.
 * @param count_out      receives the fiber count.
 * @return FLT_OK; FLT_ERR_STATE as above; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_get_fiber_grid(const flt_calib *calib,
                                                                   double *first_x_mm_out,
                                                                   double *pitch_mm_out,
                                                                   size_t *count_out);

/* ---------------------------------------------------------------------- */
/* Mapping (finished model only; thread-safe; no allocation)               */
/* ---------------------------------------------------------------------- */

/** Raw image points -> laser `laser`'s plane.
 *   image_px   count x 2 (u, v), px.   plane_out  count x 2 (x, z), mm.
 * A NaN input point gives a NaN output point (an invalid peak stays
 * invalid); so does a point whose ray is parallel to the plane. count = 0 is
 * allowed and does nothing. In-place (plane_out == image_px) is allowed.
 * @param calib the model.
 * @param laser 0 or 1.
 * @param count     the number of points.
 * @param image_px  [count * 2] image points, px.
 * @param plane_out [count * 2] plane points, mm.
 * @return FLT_OK; FLT_ERR_STATE on an unfinished model; FLT_ERR_INVALID_ARGUMENT for a NULL or
 * wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_image_to_plane(const flt_calib *calib,
                                                                   unsigned laser, size_t count,
                                                                   const double *image_px,
                                                                   double *plane_out);

/** Laser `laser`'s plane -> raw image points (the inverse of the above; for
 * the simulator and diagnostics).
 *   plane_mm   count x 2 (x, z), mm.   image_out  count x 2 (u, v), px.
 * A point behind the camera or at infinity gives NaN. In-place allowed.
 * @param calib the model.
 * @param laser 0 or 1.
 * @param count     the number of points.
 * @param plane_mm  [count * 2] plane points, mm.
 * @param image_out [count * 2] image points, px.
 * @return FLT_OK; FLT_ERR_STATE on an unfinished model; FLT_ERR_INVALID_ARGUMENT for a NULL or
 * wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_plane_to_image(const flt_calib *calib,
                                                                   unsigned laser, size_t count,
                                                                   const double *plane_mm,
                                                                   double *image_out);

/** Raw image points -> undistorted image points, both count x 2 px.
 * The inverse of the distortion model is solved by damped Newton
 * iteration to about 1e-9 px (tests/c/test_calib.c measures it); a point
 * where it does not converge gives NaN. Needs only the
 * intrinsics (works on an unfinished model too; then it is not
 * thread-safe against concurrent setters).
 * @param calib the model.
 * @param count           the number of points.
 * @param image_px        [count * 2] raw image points, px.
 * @param undistorted_out [count * 2] undistorted points, px.
 * @return FLT_OK; FLT_ERR_STATE without intrinsics; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong
 * argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_undistort(const flt_calib *calib, size_t count,
                                                              const double *image_px,
                                                              double *undistorted_out);

/* ---------------------------------------------------------------------- */
/* Save and load                                                           */
/* ---------------------------------------------------------------------- */

/** Writes a finished model to `path` (see "File format"), through a
 * temporary file renamed into place, so a crash never leaves a half file.
 * FLT_ERR_IO if it cannot be written.
 * @param calib the model.
 * @param path UTF-8 file name.
 * @return FLT_OK; FLT_ERR_IO as above; FLT_ERR_STATE on an unfinished model;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_save(const flt_calib *calib, const char *path);

/** Writes the same text into text_out[capacity] with a terminating NUL.
 * *length_out = the text's length without the NUL, also when the buffer is
 * too small (then FLT_ERR_BUFFER_FULL; text_out may be NULL with capacity 0
 * to ask for the size).
 * @param calib the model.
 * @param text_out   the buffer, or NULL with capacity 0.
 * @param capacity   its size in bytes.
 * @param length_out receives the text's length.
 * @return FLT_OK; FLT_ERR_BUFFER_FULL as above; FLT_ERR_STATE on an
 *         unfinished model; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_save_text(const flt_calib *calib,
                                                              char *text_out, size_t capacity,
                                                              size_t *length_out);

/** Reads a model from `path` and returns it finished in *out (NULL on any
 * failure). FLT_ERR_IO if the file cannot be read, FLT_ERR_FORMAT if it is
 * malformed, a value is outside its range, or the file is larger than
 * FLT_CALIB_MAX_FILE_BYTES.
 * @param path UTF-8 file name.
 * @param out  receives the finished model.
 * @return FLT_OK; FLT_ERR_IO or FLT_ERR_FORMAT as above; FLT_ERR_INVALID_ARGUMENT for a NULL or
 * wrong argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_load(const char *path, flt_calib **out);

/** The same from `length` bytes of text (need not be NUL-terminated;
 * length <= FLT_CALIB_MAX_FILE_BYTES, else FLT_ERR_FORMAT).
 * @param text   the text.
 * @param length its length in bytes.
 * @param out    receives the finished model.
 * @return FLT_OK; FLT_ERR_FORMAT if it is malformed; FLT_ERR_INVALID_ARGUMENT for a NULL or wrong
 * argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_calib_load_text(const char *text, size_t length,
                                                              flt_calib **out);

#ifdef __cplusplus
}
#endif

#endif /* FLATLINE_CALIB_H */
