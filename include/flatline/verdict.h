/* SPDX-License-Identifier: Apache-2.0 */
/** @file
 * libflatline - verdicts: a sheet against the flatness tolerances the user
 * delivers to.
 *
 * What it does
 *   A rule set (flt_rules) holds the limits of the standard and grade a
 *   mill delivers to, entered by the user as data (a JSON file, "Rule
 *   files" below): per rule a measure and a table of limits by thickness
 *   and width band. A verdict (flt_verdict) judges one sheet at a time
 *   against every rule: pass or fail, the worst value with its position
 *   (x across the strip, s along it) and its margin to the limit.
 *
 * Measures (flt_measure)
 *   FLT_MEASURE_STRAIGHTEDGE_ALONG / _ACROSS: the straightedge deviation
 *   along every fiber / across every row of the sheet's height map, for
 *   the rule's straightedge length (mm). A straightedge rests on the sheet
 *   on two contact points at most its length apart, the sheet between them
 *   nowhere above it; its deviation is the largest gap between the
 *   straightedge and the sheet between the contacts, and the sheet's
 *   deviation is the largest over every such resting position on every
 *   line (its position: the deepest sample; on a tie between lines, on
 *   the smaller fiber or row). It is computed exactly over the samples
 *   with convex hulls (lib/verdict/README.md). A straightedge longer than
 *   a wave's period bridges it (the gap is the wave's full height); a
 *   shorter one dips into it: under a sine of amplitude A and period P
 *   the deviation is A (1 - cos(pi L / P)) for L <= P and 2 A for L >= P.
 *   The other measures are the flatness results (flatline/flatness.h) the
 *   caller gives with flt_verdict_set_measure(): FLT_MEASURE_ZONE_I_UNITS
 *   (the largest zone I-Units), _WAVE_STEEPNESS (%), _WAVE_HEIGHT (mm,
 *   peak to peak), _BOW and _CROSSBOW (mm; their magnitude is judged).
 *
 * Rule files
 *   UTF-8 JSON:
 *     { "format": "flatline-tolerances", "version": 1,
 *       "name": "what the rules are (free text)",
 *       "rules": [
 *         { "name": "straightedge 1 m along",
 *           "measure": "straightedge_along", "length_mm": 1000,
 *           "bands": [
 *             { "thickness_mm": [3, 5], "width_mm": [0, 1500], "limit": 4 },
 *             { "thickness_mm": [5, 8], "width_mm": [0, 1500], "limit": 3 } ] },
 *         { "name": "I-Units", "measure": "zone_i_units",
 *           "bands": [ { "thickness_mm": [0, 100], "width_mm": [0, 3000],
 *                        "limit": 10 } ] } ] }
 *   measure: straightedge_along, straightedge_across (both need
 *   length_mm > 0), zone_i_units, wave_steepness, wave_height, bow,
 *   crossbow (no length_mm). A band covers min <= thickness < max and
 *   min <= width < max (mm, 0 <= min < max); a rule's bands must not
 *   overlap. limit > 0, in the measure's unit; a value passes when it is
 *   at most the limit. A sheet whose thickness and width fall in none of a
 *   rule's bands is not judged by that rule (FLT_VERDICT_NO_BAND). Every
 *   error names the field and its line; unknown fields are errors.
 *
 * Units
 *   Millimetres for positions, lengths and heights; % for steepness; I-Units.
 *
 * Memory
 *   flt_rules_load*() and flt_verdict_create() allocate; a verdict keeps
 *   its own copy of the rules. flt_verdict_evaluate() allocates scratch
 *   when it meets a longer line, or more lines, than before (once per
 *   size).
 *
 * Threads
 *   A flt_rules is read-only after loading: any threads may share it. A
 *   flt_verdict must not be used from two threads at once.
 */
#ifndef FLATLINE_VERDICT_H
#define FLATLINE_VERDICT_H

#include "flatline/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** A rule set, loaded from a rule file. */
typedef struct flt_rules flt_rules;
/** One sheet's verdict against a rule set. */
typedef struct flt_verdict flt_verdict;

/** What a rule measures (see "Measures"). */
typedef enum flt_measure {
    FLT_MEASURE_STRAIGHTEDGE_ALONG = 0,  /**< along every fiber, mm */
    FLT_MEASURE_STRAIGHTEDGE_ACROSS = 1, /**< across every row, mm */
    FLT_MEASURE_ZONE_I_UNITS = 2,        /**< the largest zone I-Units */
    FLT_MEASURE_WAVE_STEEPNESS = 3,      /**< the largest wave's steepness, % */
    FLT_MEASURE_WAVE_HEIGHT = 4,         /**< the largest wave's height, mm peak to peak */
    FLT_MEASURE_BOW = 5,                 /**< bow (coil set), mm; its magnitude is judged */
    FLT_MEASURE_CROSSBOW = 6,            /**< crossbow, mm; its magnitude is judged */
    /** Not a measure: keeps the type int-sized whatever is added. */
    FLT_MEASURE_MAX_ENUM_ = 0x7FFFFFFF
} flt_measure;

/** A rule's outcome (FLT_VERDICT_STATE). */
typedef enum flt_verdict_state {
    /** The worst value is at most the limit. */
    FLT_VERDICT_PASS = 0,
    /** The worst value exceeds the limit. */
    FLT_VERDICT_FAIL = 1,
    /** No band of the rule covers the sheet's thickness and width. */
    FLT_VERDICT_NO_BAND = 2,
    /** The measure is missing: no line of the map has two samples, or the
     * value was not given (NaN). */
    FLT_VERDICT_NOT_MEASURED = 3,
    /** Not judged: the gauge's sheet is incomplete (flatline/gauge.h,
     * FLT_SHEET_FLAG_INCOMPLETE); also a whole sheet's verdict
     * (FLT_SHEET_VERDICT) when a rule could not judge it.
     * flt_verdict_evaluate() never gives it to a rule. */
    FLT_VERDICT_NOT_JUDGED = 4,
    FLT_VERDICT_STATE_MAX_ENUM_ = 0x7FFFFFFF
} flt_verdict_state;

/** A rule's results, read with flt_verdict_get(). Values are doubles;
 * positions and values are NaN unless the state is PASS or FAIL, the
 * limit is NaN with NO_BAND. */
typedef enum flt_verdict_value {
    /** flt_verdict_state. */
    FLT_VERDICT_STATE = 0,
    /** The rule's measure (flt_measure). */
    FLT_VERDICT_MEASURE = 1,
    /** The worst value found (the measure's unit; bow and crossbow as
     * magnitudes). */
    FLT_VERDICT_WORST = 2,
    /** The limit of the band that applies. */
    FLT_VERDICT_LIMIT = 3,
    /** limit - worst: >= 0 passes, < 0 fails by that much. */
    FLT_VERDICT_MARGIN = 4,
    /** Where the worst value is: x across the strip (mm); for a
     * straightedge, its deepest point. */
    FLT_VERDICT_X = 5,
    /** ... and s along it (mm). */
    FLT_VERDICT_S = 6,
    /** The band that applies (its index in the rule file), -1 with NO_BAND. */
    FLT_VERDICT_BAND = 7,
    /** The straightedge's length (mm; 0 for the other measures). */
    FLT_VERDICT_LENGTH = 8,
    FLT_VERDICT_VALUE_MAX_ENUM_ = 0x7FFFFFFF
} flt_verdict_value;

/* ---------------------------------------------------------------------- */
/* Rule sets                                                               */
/* ---------------------------------------------------------------------- */

/** Reads a rule file (see "Rule files"). FLT_ERR_IO if it cannot be read,
 * FLT_ERR_FORMAT if it is malformed (the message names the field). */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_rules_load(const char *path, flt_rules **out);

/** The same from `length` bytes of text (need not be NUL-terminated). */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_rules_load_text(const char *text, size_t length,
                                                              flt_rules **out);

/** Frees a rule set. NULL is a no-op. */
FLT_API void FLT_CALL flt_rules_destroy(flt_rules *rules);

/** The number of rules. */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_rules_count(const flt_rules *rules, size_t *out);

/**
 * Rule `index`.
 * @param rules     the rule set;
 * @param index     0 .. flt_rules_count() - 1;
 * @param name_out      the rule's name, owned by the rule set;
 * @param measure_out   its flt_measure;
 * @param length_mm_out its straightedge length (0 for other measures).
 * Any output may be NULL. FLT_ERR_NOT_FOUND past the last rule.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_rules_rule(const flt_rules *rules, size_t index,
                                                         const char **name_out,
                                                         flt_measure *measure_out,
                                                         double *length_mm_out);

/* ---------------------------------------------------------------------- */
/* Straightedge                                                            */
/* ---------------------------------------------------------------------- */

/**
 * The straightedge deviation of one profile (see "Measures").
 * @param position_mm [count] strictly increasing positions (mm);
 * @param height_mm   [count] heights (mm); a NaN sample is left out (not
 *                    measured), an infinite one is an error;
 * @param count       samples;
 * @param length_mm   the straightedge (mm, > 0);
 * @param deviation_mm_out the deviation (mm, >= 0; 0 when no gap);
 * @param at_mm_out       the position of its deepest point (may be NULL).
 * @return FLT_OK, or FLT_ERR_NOT_FOUND when fewer than 2 samples are
 *         measured (nothing can rest on them).
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_straightedge_profile(const double *position_mm,
                                                                   const double *height_mm,
                                                                   size_t count, double length_mm,
                                                                   double *deviation_mm_out,
                                                                   double *at_mm_out);

/* ---------------------------------------------------------------------- */
/* Verdicts                                                                */
/* ---------------------------------------------------------------------- */

/** A verdict over a copy of `rules`, with every measure not given. */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_verdict_create(const flt_rules *rules,
                                                             flt_verdict **out);

/** Frees a verdict. NULL is a no-op. */
FLT_API void FLT_CALL flt_verdict_destroy(flt_verdict *verdict);

/**
 * Gives one of the flatness measures (not a straightedge one) for the next
 * flt_verdict_evaluate(): its value and where it is (x, s in mm; e.g. the
 * zone's centre, the wave's fiber, the sheet's middle). A value stays
 * until it is given again; NaN says "not measured" (the position is then
 * ignored).
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_verdict_set_measure(flt_verdict *verdict,
                                                                  flt_measure measure, double value,
                                                                  double x_mm, double s_mm);

/**
 * Judges one sheet against every rule.
 * @param verdict                 the verdict;
 * @param thickness_mm, width_mm  the sheet's (choose each rule's band);
 * @param rows, fibers            the height map's size (both 0: no map,
 *                                straightedge rules are NOT_MEASURED);
 * @param s_mm   [rows] strictly increasing row positions;
 * @param x_mm   [fibers] strictly increasing fiber positions;
 * @param z_mm   [rows * fibers] heights, row-major; NaN = not measured;
 * @param flags  [rows * fibers] FLT_FLAG_* bits of the map or NULL: a
 *               sample with FLT_FLAG_NO_DATA is left out.
 * The previous results are replaced; on an error they are kept.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_verdict_evaluate(
    flt_verdict *verdict, double thickness_mm, double width_mm, size_t rows, size_t fibers,
    const double *s_mm, const double *x_mm, const double *z_mm, const uint8_t *flags);

/** One result of rule `rule` (flt_verdict_value). FLT_ERR_NOT_FOUND past
 * the last rule or for an unknown key; FLT_ERR_STATE before the first
 * evaluation. */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_verdict_get(const flt_verdict *verdict, size_t rule,
                                                          flt_verdict_value key, double *out);

/** The number of rules that failed in the last evaluation (0: the sheet
 * passes every rule that applies to it). FLT_ERR_STATE before the first. */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_verdict_failed(const flt_verdict *verdict,
                                                             size_t *out);

#ifdef __cplusplus
}
#endif

#endif /* FLATLINE_VERDICT_H */
