/* SPDX-License-Identifier: Apache-2.0 */
/** @file
 * libflatline - the leveler advisor: what to change on the leveler so that
 * the next sheets come out flat.
 *
 * What it does
 *   A leveler's actuators (entry and exit roll gap, tilt, the backup-roll
 *   flights that bend the work rolls across the width, ...) change the
 *   strip's zone profile, the I-Units per zone across the width that the
 *   gauge measures (flatline/flatness.h, zone 0 at the smallest x). Near a
 *   working point the change is linear:
 *
 *       delta(zone profile) = G delta(u)
 *
 *   with u the actuator settings and G the influence matrix, zones x
 *   actuators (I-Units per actuator unit). An advisor (flt_advisor) holds
 *   the leveler's model: each actuator's name, unit, range [min, max] of
 *   its setting and step limit (the most it may move from one sheet to the
 *   next), and G. G comes from the leveler's vendor (a file, "Leveler
 *   files" below, or an array: flt_advisor_set_influence()) or is
 *   identified from logged pairs of setting changes and the profile
 *   changes they caused (flt_advisor_identify()).
 *
 * Profiles are compared without their mean
 *   I-Units are measured against a reference fiber (the shortest, or the
 *   mean of all): a change of every fiber's length by the same amount is no
 *   flatness defect and no gauge shows it. So the advisor removes the mean
 *   over the zones from every profile, target and column of G before it
 *   compares them (P below: P v = v - mean(v)). "Flat" is a profile equal
 *   to its mean.
 *
 * The advice (flt_advisor_advise())
 *   Given the measured profile p of a sheet, the settings u_sheet that
 *   sheet went through, the settings now u_now (already changed since,
 *   when the leveler is a sheet ahead of the gauge) and the target t
 *   (flt_advisor_set_target(); flat by default), the deviation expected
 *   at the current settings is
 *       r = P (p - t + G (u_now - u_sheet))
 *   and the advice is the change d of the settings minimising
 *       | P G d + gain r |^2 + lambda |d|^2
 *   subject to, for every actuator j,
 *       min_j <= u_now_j + d_j <= max_j   and   |d_j| <= step_j.
 *   gain (option "advisor_gain", 0.01..1, default 0.5) is the share of
 *   the deviation one advice sets out to remove: with the leveler a sheet
 *   ahead of the gauge a full correction overshoots whenever G
 *   understates the leveler's effect, a partial one converges without
 *   growing oscillations (docs/advisor.md shows the loop). lambda =
 *   damping * trace((P G)^T (P G)) / actuators (option
 *   "advisor_damping", default 0.01), so damping is relative to the mean
 *   squared effect of a unit step, whatever the units; it keeps
 *   actuators with little effect from large moves and makes the solution
 *   unique (lambda is at least 1e-12 times that mean, also with damping
 *   0). The bounded least-squares problem is solved exactly (to rounding)
 *   by an active-set method: its result satisfies the problem's
 *   Karush-Kuhn-Tucker conditions. A setting moved to its range's end
 *   lands on it exactly (u_now + d is never outside [min, max] after
 *   rounding, |d| never above step).
 *   The predicted profile is p + P G (u_now + d - u_sheet): the measured
 *   profile with the effect of every change since that sheet (its mean is
 *   kept: the model says nothing about it).
 *   The confidence in [0, 1] is q (1 - a / (2 n)): q the model's quality
 *   (1 for a G set from a file or an array, the identification's R^2
 *   otherwise), a the number of actuators whose advice sits on a bound
 *   (range or step limit) out of n: a step cut short by its limits
 *   removes less of the deviation than the model would like.
 *
 * Identification (flt_advisor_identify())
 *   From `steps` logged pairs (delta u_k, delta p_k) (a change of the
 *   settings between two sheets and the change of their zone profiles), G
 *   is the ridge-regularised least-squares fit
 *       G = argmin sum_k |P delta p_k - G delta u_k|^2 + rho |G|_F^2,
 *   rho = ridge * trace(U^T U) / actuators with U the steps x actuators
 *   matrix of setting changes (ridge is relative, like damping). Its fit
 *   quality over the data: R^2 = 1 - SS_res / SS_tot (SS_tot = sum_k
 *   |P delta p_k|^2, the profile changes have no offset to remove) and the
 *   RMS residual sqrt(SS_res / (steps zones)) in I-Units. The advisor
 *   refuses an identification that does not explain the data: fewer steps
 *   than actuators + 1, steps whose changes do not span every actuator
 *   (smallest singular value of U below 1e-6 of the largest), or R^2 below
 *   FLT_ADVISOR_MIN_R_SQUARED. It then returns FLT_ERR_NUMERIC saying
 *   why, keeps G as it was, and advise refuses (FLT_ERR_STATE) until an
 *   identification is accepted or G is set again. A sheet-to-sheet noise
 *   of sigma I-Units per zone leaves about sigma sqrt(2) of residual RMS;
 *   step the actuators far enough that their effect is several times that.
 *
 * Leveler files
 *   UTF-8 JSON:
 *     { "format": "flatline-leveler", "version": 1,
 *       "name": "13-roll leveler, line 2 (free text)",
 *       "zones": 3,
 *       "actuators": [
 *         { "name": "entry gap", "unit": "mm", "min": -3, "max": 3,
 *           "step": 0.5 },
 *         { "name": "tilt", "unit": "mm", "min": -2, "max": 2, "step": 0.3 } ],
 *       "influence": [ [ 4.0, -6.0 ], [ -8.0, 0.0 ], [ 4.0, 6.0 ] ],
 *       "target": [ 0, 2, 0 ] }
 *   influence: one row per zone (zone 0 first), one I-Units-per-unit
 *   number per actuator in the order of "actuators". min < max, step > 0,
 *   all finite; "target" (optional) the vendor's zone profile (I-Units)
 *   to aim at instead of flat. 1 <= zones <= FLT_ADVISOR_MAX_ZONES,
 *   1 <= actuators <= FLT_ADVISOR_MAX_ACTUATORS. Every error names the
 *   field and its line; unknown fields are errors; numbers are read
 *   without the process's locale. A file is at most 16 MiB and holds at
 *   most as many JSON values as the largest valid one can (about 68,000:
 *   1024 zones of 64 actuators, a target, the actuators' fields); more is
 *   refused while it is read, so the cost of a file is bounded before it
 *   is parsed to its end.
 *
 * Units
 *   Profiles and targets in I-Units; settings, ranges and steps in each
 *   actuator's own unit; G in I-Units per unit.
 *
 * Memory
 *   Create and load allocate everything advise needs: flt_advisor_advise()
 *   allocates nothing. flt_advisor_identify() allocates its scratch. With Z
 *   zones and A actuators an advisor takes about
 *   8 (3 Z A + 3.5 A^2 + 2 Z) + 1500 bytes (420 KB for 200 zones and 64
 *   actuators; tests/c/test_memory.c checks it).
 *
 * Threads
 *   An advisor must not be used from two threads at once.
 */
#ifndef FLATLINE_ADVISOR_H
#define FLATLINE_ADVISOR_H

#include "flatline/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** A leveler advisor: the leveler's model and the advice (opaque). */
typedef struct flt_advisor flt_advisor;

/** @name Limits
 * @{ */
#define FLT_ADVISOR_MAX_ZONES     1024 /**< Most zones of an advisor's profile. */
#define FLT_ADVISOR_MAX_ACTUATORS 64   /**< Most actuators of a leveler. */
/** The smallest R^2 of an accepted identification: below it the model
 * explains too little of the data to act on. */
#define FLT_ADVISOR_MIN_R_SQUARED 0.8
/** The largest |value| of a setting, range, step or influence (1e9): any
 * larger is a unit mistake. */
#define FLT_ADVISOR_MAX_VALUE     1.0e9
/** @} */

/**
 * An advisor for `zones` zones and `actuators` actuators, with G = 0 and a
 * flat target. Actuators are unnamed until flt_advisor_set_actuator()
 * describes them; flt_advisor_advise() refuses until every actuator is
 * described and G is set or identified.
 * @param zones     the zone profile's length (1 .. FLT_ADVISOR_MAX_ZONES).
 * @param actuators the number of actuators (1 .. FLT_ADVISOR_MAX_ACTUATORS).
 * @param options   NULL for the defaults, else read for the advisor_* keys
 *                  (a key of another component set in it is refused).
 * @param out       receives the handle; NULL on failure.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT; FLT_ERR_OUT_OF_MEMORY.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_advisor_create(size_t zones, size_t actuators,
                                                             const flt_options *options,
                                                             flt_advisor **out);

/**
 * Reads a leveler file (see "Leveler files"): actuators, G and the
 * target; the advisor is ready to advise.
 * @param path    a UTF-8 path.
 * @param options NULL, or the advisor_* keys (as flt_advisor_create()).
 * @param out     receives the handle; NULL on failure.
 * @return FLT_OK; FLT_ERR_IO if it cannot be read; FLT_ERR_FORMAT if it is
 *         malformed (the message names the field and its line);
 *         FLT_ERR_INVALID_ARGUMENT.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_advisor_load(const char *path,
                                                           const flt_options *options,
                                                           flt_advisor **out);

/**
 * The same from `length` bytes of text (need not be NUL-terminated).
 * @param text    the file's text.
 * @param length  its length in bytes.
 * @param options NULL, or the advisor_* keys (as flt_advisor_create()).
 * @param out     receives the handle; NULL on failure.
 * @return as flt_advisor_load().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_advisor_load_text(const char *text, size_t length,
                                                                const flt_options *options,
                                                                flt_advisor **out);

/** Frees an advisor. NULL is a no-op.
 * @param advisor the advisor, or NULL. */
FLT_API void FLT_CALL flt_advisor_destroy(flt_advisor *advisor);

/**
 * The advisor's sizes.
 * @param advisor       the advisor.
 * @param zones_out     receives the number of zones (may be NULL).
 * @param actuators_out receives the number of actuators (may be NULL).
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_advisor_size(const flt_advisor *advisor,
                                                           size_t *zones_out,
                                                           size_t *actuators_out);

/**
 * Describes actuator `index`.
 * @param advisor the advisor.
 * @param index   0 .. actuators - 1.
 * @param name    its name (UTF-8, 1..63 bytes, copied), e.g. "entry gap".
 * @param unit    its unit (UTF-8, 0..15 bytes, copied), e.g. "mm".
 * @param min     the smallest setting.
 * @param max     the largest setting (> min; both |.| <= FLT_ADVISOR_MAX_VALUE).
 * @param step    the most the setting may move in one advice (> 0).
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT naming the argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_advisor_set_actuator(flt_advisor *advisor,
                                                                   size_t index, const char *name,
                                                                   const char *unit, double min,
                                                                   double max, double step);

/**
 * Actuator `index` as described. Any output may be NULL; the strings are
 * owned by the advisor (valid until it is destroyed or the actuator is
 * described again). An actuator not described yet has the name "" and
 * NaN range and step.
 * @param advisor  the advisor.
 * @param index    0 .. actuators - 1.
 * @param name_out its name.
 * @param unit_out its unit.
 * @param min_out  its smallest setting.
 * @param max_out  its largest setting.
 * @param step_out its step limit.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT; FLT_ERR_NOT_FOUND past the last.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_advisor_actuator(const flt_advisor *advisor,
                                                               size_t index, const char **name_out,
                                                               const char **unit_out,
                                                               double *min_out, double *max_out,
                                                               double *step_out);

/**
 * Sets G from an array (a vendor's matrix); its quality counts as 1.
 * @param advisor   the advisor.
 * @param g         [zones * actuators] row-major (zone by zone), I-Units
 *                  per unit, finite, |.| <= FLT_ADVISOR_MAX_VALUE; copied.
 * @param g_count   its element count, zones * actuators.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_advisor_set_influence(flt_advisor *advisor,
                                                                    const double *g,
                                                                    size_t g_count);

/**
 * Copies G (as set, loaded or identified; identified columns have zero
 * mean over the zones).
 * @param advisor the advisor.
 * @param g_out   [zones * actuators] receives G, row-major.
 * @param g_count its element count, zones * actuators.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_advisor_influence(const flt_advisor *advisor,
                                                                double *g_out, size_t g_count);

/**
 * Sets the target profile, or flat with NULL.
 * @param advisor      the advisor.
 * @param target       [zones] I-Units (finite), or NULL for flat; copied.
 * @param target_count its element count (zones; 0 with NULL).
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_advisor_set_target(flt_advisor *advisor,
                                                                 const double *target,
                                                                 size_t target_count);

/**
 * Identifies G from logged steps (see "Identification").
 * @param advisor          the advisor.
 * @param steps            the number of pairs.
 * @param delta_u          [steps * actuators] the setting changes, row-major
 *                         (step by step), finite.
 * @param delta_u_count    its element count, steps * actuators.
 * @param delta_p          [steps * zones] the zone profile changes they
 *                         caused, I-Units, finite.
 * @param delta_p_count    its element count, steps * zones.
 * @param ridge            the relative ridge weight, 0 .. 1e6.
 * @return FLT_OK (G replaced, flt_advisor_fit() tells its quality);
 *         FLT_ERR_NUMERIC when the identification is refused (too few or
 *         degenerate steps, or R^2 < FLT_ADVISOR_MIN_R_SQUARED: the message
 *         says which; advise then refuses); FLT_ERR_INVALID_ARGUMENT;
 *         FLT_ERR_OUT_OF_MEMORY.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_advisor_identify(flt_advisor *advisor, size_t steps,
                                                               const double *delta_u,
                                                               size_t delta_u_count,
                                                               const double *delta_p,
                                                               size_t delta_p_count, double ridge);

/**
 * The quality of the model: after an identification (accepted or refused
 * for its R^2) its R^2 and RMS residual (I-Units) over the data and the
 * number of steps; for a G set from a file or an array 1, 0 and 0; before
 * any G, or after a refusal for too few or degenerate steps, NaN, NaN and
 * the steps given. Any output may be NULL.
 * @param advisor        the advisor.
 * @param r_squared_out  R^2.
 * @param rms_out        RMS residual, I-Units.
 * @param steps_out      the number of steps.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_advisor_fit(const flt_advisor *advisor,
                                                          double *r_squared_out, double *rms_out,
                                                          size_t *steps_out);

/**
 * Advises a change of the settings (see "The advice"). Allocates nothing.
 * @param advisor          the advisor.
 * @param profile          [zones] the measured zone profile of a sheet,
 *                         I-Units; NaN for a zone without data
 *                         (FLT_ZONE_NO_DATA): it takes no part (every mean
 *                         is over the measured zones) and its predicted
 *                         value is NaN. At least 2 zones measured.
 * @param profile_count    zones.
 * @param settings_sheet   [actuators] the settings that sheet went through.
 * @param settings_sheet_count actuators.
 * @param settings_now     [actuators] the settings now, each within its
 *                         actuator's [min, max].
 * @param settings_now_count actuators.
 * @param delta_out        [actuators] receives the advised change d.
 * @param delta_count      actuators.
 * @param predicted_out    [zones] receives the predicted profile, or NULL.
 * @param predicted_count  zones (0 with NULL).
 * @param confidence_out   receives the confidence in [0, 1], or NULL.
 * @return FLT_OK; FLT_ERR_STATE when an actuator is not described, no G
 *         is set, or the last identification was refused (the message
 *         says which); FLT_ERR_INVALID_ARGUMENT. On an error the outputs
 *         are not written.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_advisor_advise(
    flt_advisor *advisor, const double *profile, size_t profile_count, const double *settings_sheet,
    size_t settings_sheet_count, const double *settings_now, size_t settings_now_count,
    double *delta_out, size_t delta_count, double *predicted_out, size_t predicted_count,
    double *confidence_out);

#ifdef __cplusplus
}
#endif

#endif /* FLATLINE_ADVISOR_H */
