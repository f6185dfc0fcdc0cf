/* SPDX-License-Identifier: Apache-2.0 */
/** @file
 * libflatline - coil identity: which coil a sheet was cut from, as the
 * mill's systems name it.
 *
 * What it does
 *   A quality record is useless without the coil's identity: a customer
 *   complains about coil 4711, not about "coil 3 since the gauge started".
 *   An flt_coil_info holds what a mill's level-2 system knows of a coil
 *   before it is processed: its id, the production order, the heat
 *   (melt), the steel grade, the customer, the nominal thickness and
 *   width, and free key/value pairs for everything else (a line name, a
 *   shift, a PLC's coil counter). The gauge (flt_gauge_set_coil,
 *   flatline/gauge.h) gives it to every sheet of the coil, to the
 *   verdicts (the nominal thickness and width choose the rule bands) and
 *   to the coil's statistics; recordings and the archive
 *   (flatline/record.h) store it.
 *
 * Text
 *   Every text is UTF-8 (checked), at most FLT_COIL_TEXT_MAX bytes, with
 *   no control characters (U+0000..U+001F, U+007F): a value goes into
 *   file names, HTML pages and SQL tables. An extra's key is 1 to 64 ASCII
 *   letters, digits, '_', '-' or '.'; a coil has at most
 *   FLT_COIL_EXTRA_MAX extras, in the order they were first set.
 *
 * Memory and threads
 *   flt_coil_info_create() and the setters allocate; the getters return
 *   text owned by the handle, valid until the handle changes or is
 *   destroyed. A handle must not be changed while another thread reads
 *   it; a handle lent by a sheet (flt_sheet_coil) is read-only.
 */
#ifndef FLATLINE_COIL_H
#define FLATLINE_COIL_H

#include "flatline/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** A coil's identity (opaque handle). */
typedef struct flt_coil_info flt_coil_info;

/** The longest text a field or an extra's value holds, bytes of UTF-8. */
#define FLT_COIL_TEXT_MAX  256
/** The most extras (free key/value pairs) a coil holds. */
#define FLT_COIL_EXTRA_MAX 64

/** The text fields of a coil's identity. */
typedef enum flt_coil_field {
    /** The coil's id as the mill numbers it ("4711"); never empty. */
    FLT_COIL_FIELD_ID = 0,
    /** The production order it belongs to. */
    FLT_COIL_FIELD_ORDER = 1,
    /** The heat (melt) it was cast from. */
    FLT_COIL_FIELD_HEAT = 2,
    /** The steel grade ("S355MC"). */
    FLT_COIL_FIELD_GRADE = 3,
    /** The customer it is made for. */
    FLT_COIL_FIELD_CUSTOMER = 4,
    /** Not a field: keeps the type int-sized whatever is added. */
    FLT_COIL_FIELD_MAX_ENUM_ = 0x7FFFFFFF
} flt_coil_field;

/** A coil identity with its id and nothing else.
 * @param coil_id the coil's id: non-empty text (see "Text").
 * @param out     receives the handle; NULL on failure.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL, empty, too long or
 *         malformed id; FLT_ERR_OUT_OF_MEMORY.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_coil_info_create(const char *coil_id,
                                                               flt_coil_info **out);

/** Frees a coil identity. NULL is a no-op; a handle lent by a sheet is
 * left alone.
 * @param info the handle, or NULL.
 */
FLT_API void FLT_CALL flt_coil_info_destroy(flt_coil_info *info);

/** A copy of a coil identity (of a lent one too), which the caller owns.
 * @param info the identity to copy.
 * @param out  receives the copy; NULL on failure.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL argument;
 *         FLT_ERR_OUT_OF_MEMORY.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_coil_info_copy(const flt_coil_info *info,
                                                             flt_coil_info **out);

/** Sets a text field; "" clears it (the id cannot be cleared).
 * @param info  the identity (not a lent one).
 * @param field which field.
 * @param value its text (see "Text").
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL argument, an unknown
 *         field, text that is too long or malformed, or an empty id;
 *         FLT_ERR_STATE for a handle lent by a sheet (read-only).
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_coil_info_set_text(flt_coil_info *info,
                                                                 flt_coil_field field,
                                                                 const char *value);

/** A text field ("" when not set).
 * @param info  the identity.
 * @param field which field.
 * @param out   receives the text, owned by the handle.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL argument or an
 *         unknown field.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_coil_info_get_text(const flt_coil_info *info,
                                                                 flt_coil_field field,
                                                                 const char **out);

/** Sets the nominal thickness and width, mm (0: not given). With rules
 * set, the gauge judges the coil's sheets in the bands these choose
 * (flt_gauge_set_coil), in place of those given to flt_gauge_set_rules.
 * @param info         the identity (not a lent one).
 * @param thickness_mm 0, or 0 < thickness <= 1000.
 * @param width_mm     0, or 0 < width <= 100000.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL info or a value out
 *         of range (NaN and infinities included); FLT_ERR_STATE for a lent
 *         handle.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_coil_info_set_nominal(flt_coil_info *info,
                                                                    double thickness_mm,
                                                                    double width_mm);

/** The nominal thickness and width, mm (0: not given). Either output may
 * be NULL.
 * @param info             the identity.
 * @param thickness_mm_out receives the thickness, or NULL.
 * @param width_mm_out     receives the width, or NULL.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL info.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_coil_info_get_nominal(const flt_coil_info *info,
                                                                    double *thickness_mm_out,
                                                                    double *width_mm_out);

/** Sets (adds or replaces) a free key/value pair, or removes it with a
 * NULL value.
 * @param info  the identity (not a lent one).
 * @param key   1..64 ASCII letters, digits, '_', '-' or '.'.
 * @param value its text (see "Text"), or NULL to remove the key.
 * @return FLT_OK (also when removing a key that is not there);
 *         FLT_ERR_INVALID_ARGUMENT for a NULL info or key, or a malformed
 *         key or value; FLT_ERR_BUFFER_FULL when FLT_COIL_EXTRA_MAX keys are
 *         set already; FLT_ERR_STATE for a lent handle.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_coil_info_set_extra(flt_coil_info *info,
                                                                  const char *key,
                                                                  const char *value);

/** The number of free key/value pairs.
 * @param info the identity.
 * @param out  receives the count.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_coil_info_extra_count(const flt_coil_info *info,
                                                                    size_t *out);

/** Free pair `index`, in the order the keys were first set. Either output
 * may be NULL.
 * @param info      the identity.
 * @param index     0 .. flt_coil_info_extra_count() - 1.
 * @param key_out   receives its key, owned by the handle, or NULL.
 * @param value_out receives its value, owned by the handle, or NULL.
 * @return FLT_OK; FLT_ERR_NOT_FOUND past the last pair;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL info.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_coil_info_extra(const flt_coil_info *info,
                                                              size_t index, const char **key_out,
                                                              const char **value_out);

/** The value of one free key.
 * @param info the identity.
 * @param key  the key.
 * @param out  receives its value, owned by the handle.
 * @return FLT_OK; FLT_ERR_NOT_FOUND when the key is not set;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_coil_info_find_extra(const flt_coil_info *info,
                                                                   const char *key,
                                                                   const char **out);

#ifdef __cplusplus
}
#endif

#endif /* FLATLINE_COIL_H */
