// SPDX-License-Identifier: Apache-2.0
/** @file
 * libflatline - an offline view of a camera description (GenICam XML).
 *
 * What
 *   A GenICam description (the XML a USB3 Vision or GigE Vision camera
 *   delivers, zipped or not) lists the camera's features - Width,
 *   ExposureTime, TriggerMode, ... - and how each maps to the camera's
 *   registers: directly, through bit fields, computed addresses, selectors
 *   or formulas. This view loads such a file without a camera, lists its
 *   features with their type, access mode and register, and evaluates a
 *   feature for register contents the caller gives (a memory image or a
 *   callback), the way the library's camera clients do on a real camera.
 *   Commissioning engineers use it to see what a feature will read or
 *   write before the camera is connected (flatline-camera, tools/camera,
 *   shows a camera's tree this way, offline or live):
 *
 *       flt_genicam *g;
 *       flt_genicam_load("camera.xml", &g);        (or _load_memory)
 *       uint8_t width[4] = {0x80, 0x07, 0, 0};      (1920, little endian)
 *       flt_genicam_set_memory(g, 0x81084, width, 4);
 *       int64_t w;
 *       flt_genicam_get_int(g, "Width", &w);        (1920)
 *       uint64_t address; uint32_t length, lsb, msb; int big_endian;
 *       flt_genicam_register(g, "Width", &address, &length, &lsb, &msb,
 *                            &big_endian);
 *       flt_genicam_destroy(g);
 *
 *   Every node kind of the GenICam node map is evaluated: Integer, IntReg,
 *   MaskedIntReg, StructReg/StructEntry, Float, FloatReg, Converter,
 *   IntConverter, SwissKnife, IntSwissKnife (the standard's formula
 *   language), Enumeration with per-entry pIsImplemented/pIsAvailable,
 *   Boolean, Command, String, StringReg, Register and Port; computed
 *   addresses (pAddress, pIndex with Offset/pOffset, address formulas);
 *   selectors; pIsImplemented/pIsAvailable/pIsLocked with AccessMode and
 *   ImposedAccessMode; pMin/pMax/pInc; little- and big-endian registers.
 *   Files with text before the XML declaration, a byte-order mark or no
 *   declaration load. A value that cannot be evaluated fails with a message
 *   naming the feature and the chain of nodes to the one that failed; where
 *   the standard's implementations disagree (an integer converter whose
 *   formula gives different values in integer and floating arithmetic, a
 *   shift by 64 bits or more, a non-integral truth value) the evaluation
 *   refuses instead of guessing.
 *
 * Units
 *   Whatever the description says: flt_genicam_feature_info() gives the
 *   unit string ("us", "dB", "" when none). Addresses and lengths are
 *   bytes; bit numbers count from the least significant bit of the
 *   register's value whatever the file's numbering (big-endian files number
 *   from the most significant one).
 *
 * Memory
 *   The handle owns everything. Strings returned through `const char **`
 *   live in the handle: feature names, kinds and units until it is
 *   destroyed; values (flt_genicam_get_string(), entry names) until the next
 *   call on the same handle. Register contents: a memory image inside the
 *   handle (flt_genicam_set_memory(), at most 256 MiB in all) or the
 *   caller's callbacks (flt_genicam_set_registers()).
 *
 * Threads
 *   A handle must not be used from two threads at once. Different handles
 *   are independent.
 *
 * Reads ignore the access mode (they show what an unavailable feature's
 * registers hold; flt_genicam_get_access() says whether a camera would let it
 * be read). Writes honour it, as on a camera: a read-only, locked,
 * unavailable or unimplemented feature is refused with FLT_ERR_STATE, a
 * value outside the feature's bounds with FLT_ERR_INVALID_ARGUMENT; what a
 * write changes lands in the memory image (or goes to the write callback).
 */
#ifndef FLATLINE_GENICAM_H
#define FLATLINE_GENICAM_H

#include "flatline/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** A loaded camera description with its register contents. */
typedef struct flt_genicam flt_genicam;

/** The interface a feature offers. */
typedef enum flt_genicam_type {
    FLT_GENICAM_INTEGER =
        1, /**< Integer, IntReg, MaskedIntReg, StructEntry, IntConverter, IntSwissKnife */
    FLT_GENICAM_FLOAT = 2,       /**< Float, FloatReg, Converter, SwissKnife */
    FLT_GENICAM_ENUMERATION = 3, /**< Enumeration: an entry name over an integer */
    FLT_GENICAM_BOOLEAN = 4,     /**< Boolean */
    FLT_GENICAM_COMMAND = 5,     /**< Command */
    FLT_GENICAM_STRING = 6,      /**< String, StringReg */
    FLT_GENICAM_REGISTER = 7,    /**< Register: raw bytes */
    /** Category: a node of the feature tree holding features and other
     * categories (flt_genicam_category_entry()); it has no value. */
    FLT_GENICAM_CATEGORY = 8,
    FLT_GENICAM_TYPE_MAX_ENUM_ = 0x7FFFFFFF
} flt_genicam_type;

/** A feature's access mode for the current register contents. */
typedef enum flt_genicam_access {
    FLT_GENICAM_NOT_IMPLEMENTED = 0, /**< NI: pIsImplemented is false */
    FLT_GENICAM_NOT_AVAILABLE =
        1,                      /**< NA: pIsAvailable is false (now), or modes exclude each other */
    FLT_GENICAM_WRITE_ONLY = 2, /**< WO */
    FLT_GENICAM_READ_ONLY = 3,  /**< RO (also a RW feature while pIsLocked is true) */
    FLT_GENICAM_READ_WRITE = 4, /**< RW */
    FLT_GENICAM_ACCESS_MAX_ENUM_ = 0x7FFFFFFF
} flt_genicam_access;

/** What the description says about itself (attributes of its root element). */
typedef enum flt_genicam_text {
    FLT_GENICAM_VENDOR_NAME = 1, /**< VendorName */
    FLT_GENICAM_MODEL_NAME = 2,  /**< ModelName */
    FLT_GENICAM_SCHEMA_VERSION =
        3, /**< "major.minor.subminor" of the GenApi schema ("" if absent) */
    FLT_GENICAM_TEXT_MAX_ENUM_ = 0x7FFFFFFF
} flt_genicam_text;

/**
 * Reads the reader's registers: `bytes` bytes at `address` into `out`.
 * @return 0 on success; anything else fails the evaluation with
 *         FLT_ERR_DEVICE naming the address and the value returned.
 */
typedef int(FLT_CALL *flt_genicam_read_fn)(void *user, uint64_t address, void *out, size_t bytes);
/** Writes `bytes` bytes at `address`; 0 on success (as flt_genicam_read_fn). */
typedef int(FLT_CALL *flt_genicam_write_fn)(void *user, uint64_t address, const void *in,
                                            size_t bytes);

/* ---------------------------------------------------------------------- */
/* Loading                                                                 */
/* ---------------------------------------------------------------------- */

/**
 * Loads a description from a file: GenICam XML, or a ZIP archive holding
 * it (as cameras store it), told apart by content.
 * @param path UTF-8 file name.
 * @param out  receives the handle; destroy it with flt_genicam_destroy().
 * @return FLT_OK; FLT_ERR_IO (the file cannot be read); FLT_ERR_FORMAT
 *         (not a ZIP, deflate or XML file that holds GenICam nodes; the
 *         message says why and where); FLT_ERR_INVALID_ARGUMENT.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_load(const char *path, flt_genicam **out);

/**
 * Loads a description from memory (XML text or a ZIP archive, e.g. as read
 * from a camera's manifest). The bytes are copied.
 * @return as flt_genicam_load() (without FLT_ERR_IO).
 * @param data  the XML text or ZIP archive.
 * @param bytes its length in bytes.
 * @param out   receives the handle; destroy it with flt_genicam_destroy().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_load_memory(const void *data, size_t bytes,
                                                                  flt_genicam **out);

/** Frees the handle; NULL is a no-op.
 * @param description the handle, or NULL.
 */
FLT_API void FLT_CALL flt_genicam_destroy(flt_genicam *description);

/**
 * A text of the description itself (vendor, model, schema version).
 * @param description the description.
 * @param which       the text wanted.
 * @param out receives a string owned by the handle ("" when the file has none).
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL argument or an
 *         unknown `which`.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_get_text(const flt_genicam *description,
                                                               flt_genicam_text which,
                                                               const char **out);

/* ---------------------------------------------------------------------- */
/* Features                                                                */
/* ---------------------------------------------------------------------- */

/** The number of features (value and command nodes; not categories or ports).
 * @param description the description.
 * @param out receives the number of features.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_feature_count(const flt_genicam *description,
                                                                    size_t *out);

/**
 * Feature `index` (0 .. count-1, in document order).
 * @param description the description.
 * @param index       0 .. count-1.
 * @param out receives its name, owned by the handle.
 * @return FLT_OK; FLT_ERR_NOT_FOUND past the last one;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_feature_name(const flt_genicam *description,
                                                                   size_t index, const char **out);

/**
 * What a feature is, without evaluating anything.
 * @param description the description.
 * @param feature the feature's name.
 * @param type_out  its interface (may be NULL).
 * @param kind_out  the XML element: "IntReg", "SwissKnife", "StructEntry", ... (may be NULL).
 * @param unit_out  its Unit, "" if none (may be NULL).
 * @return FLT_ERR_NOT_FOUND for a name the description does not define.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_feature_info(const flt_genicam *description,
                                                                   const char *feature,
                                                                   flt_genicam_type *type_out,
                                                                   const char **kind_out,
                                                                   const char **unit_out);

/**
 * Entry `index` of a category of the feature tree: a feature or a
 * sub-category, in the description's order. The tree starts at the
 * category "Root" (GenICam's name for the top); flt_genicam_feature_info()
 * tells a sub-category (FLT_GENICAM_CATEGORY) from a feature. An entry
 * names what the file wrote, which may be a node the file lacks
 * (flt_genicam_feature_info() then fails with FLT_ERR_NOT_FOUND).
 * Nothing is evaluated: a category lists its entries whatever their access
 * mode.
 * @param description the description.
 * @param category    the category's name ("Root" for the top).
 * @param index       0 .. its entries - 1.
 * @param out receives the entry's name, owned by the handle (valid until
 *            it is destroyed).
 * @return FLT_OK; FLT_ERR_NOT_FOUND past the last entry, or for a name that
 *         is no category of the description (the message says which);
 *         FLT_ERR_INVALID_ARGUMENT for a NULL argument.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_category_entry(const flt_genicam *description,
                                                                     const char *category,
                                                                     size_t index,
                                                                     const char **out);

/* ---------------------------------------------------------------------- */
/* Register contents                                                       */
/* ---------------------------------------------------------------------- */

/**
 * Puts `count` bytes at `address` into the handle's memory image (bytes in
 * device order: as the camera's memory holds them). Later bytes replace
 * earlier ones. Evaluations read the image; reading a byte it does not hold
 * fails with FLT_ERR_NOT_FOUND naming the register.
 * @return FLT_ERR_INVALID_ARGUMENT for more than 64 MiB in one call, a range
 *         past 2^64, or an image beyond 256 MiB.
 * @param description the description.
 * @param address the device address of the first byte.
 * @param bytes   the bytes.
 * @param count   how many.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_set_memory(flt_genicam *description,
                                                                 uint64_t address,
                                                                 const void *bytes, size_t count);

/**
 * Reads `count` bytes of the memory image (e.g. what a write put there).
 * @return FLT_ERR_NOT_FOUND when the image lacks one of them.
 * @param description the description.
 * @param address the device address of the first byte.
 * @param out     receives `count` bytes.
 * @param count   how many.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_get_memory(const flt_genicam *description,
                                                                 uint64_t address, void *out,
                                                                 size_t count);

/** Empties the memory image.
 * @param description the description.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL handle.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_clear_memory(flt_genicam *description);

/**
 * Reads registers through callbacks instead of the memory image (a live
 * transport, a recorded dump). `write` may be NULL (writes then fail with
 * FLT_ERR_STATE); `read` NULL returns to the memory image. The callbacks
 * are called from the thread calling into the handle, only during calls.
 * @param description the description.
 * @param read  reads registers, or NULL for the memory image.
 * @param write writes registers, or NULL.
 * @param user  passed to both callbacks as is.
 * @return FLT_OK; FLT_ERR_INVALID_ARGUMENT for a NULL handle, or a write
 *         callback without a read one.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_set_registers(flt_genicam *description,
                                                                    flt_genicam_read_fn read,
                                                                    flt_genicam_write_fn write,
                                                                    void *user);

/* ---------------------------------------------------------------------- */
/* Evaluation for the current register contents                            */
/* ---------------------------------------------------------------------- */

/** The feature's access mode (evaluates pIsImplemented, pIsAvailable, pIsLocked).
 * @param description the description.
 * @param feature the feature's name.
 * @param out receives the access mode.
 * @return FLT_OK, or a status as for flt_genicam_get_int().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_get_access(flt_genicam *description,
                                                                 const char *feature,
                                                                 flt_genicam_access *out);

/**
 * The feature's own pIsImplemented, pIsAvailable and pIsLocked, evaluated
 * now (1/1/0 where it has none). flt_genicam_get_access() combines them with
 * the access modes of the nodes the feature reads. Any output may be NULL.
 * @param description the description.
 * @param feature the feature's name.
 * @param implemented_out 1 when implemented.
 * @param available_out   1 when available.
 * @param locked_out      1 when locked.
 * @return FLT_OK, or a status as for flt_genicam_get_int().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_get_flags(flt_genicam *description,
                                                                const char *feature,
                                                                int *implemented_out,
                                                                int *available_out,
                                                                int *locked_out);

/**
 * The register holding the feature's value: the register node at the end of
 * its pValue chain (through Converters), its address evaluated now.
 * @param description the description.
 * @param feature    the feature's name.
 * @param address_out    bytes; @param length_out bytes;
 * @param lsb_out, msb_out the bits of the register's value holding the feature;
 * @param big_endian_out 1 for a big-endian register. Any output may be NULL.
 * @return FLT_ERR_NOT_FOUND when the value is no single register's (a
 *         SwissKnife formula of several, a constant, a pIndex table); the
 *         message says which.
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_register(
    flt_genicam *description, const char *feature, uint64_t *address_out, uint32_t *length_out,
    uint32_t *lsb_out, uint32_t *msb_out, int *big_endian_out);

/**
 * The value of an integer, enumeration (its integer), boolean (0/1) or
 * float (when integral) feature.
 * @param description the description.
 * @param feature the feature's name.
 * @param out receives the value.
 * @return FLT_OK; FLT_ERR_NOT_FOUND for a feature the description does not
 *         define or a register byte the memory image lacks;
 *         FLT_ERR_INVALID_ARGUMENT for a NULL argument or a feature without
 *         such a value; FLT_ERR_FORMAT for a node the description gets wrong,
 *         FLT_ERR_DEVICE when the read callback fails (the message names the
 *         chain of nodes).
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_get_int(flt_genicam *description,
                                                              const char *feature, int64_t *out);

/** The value of a float or integer feature.
 * @param description the description.
 * @param feature the feature's name.
 * @param out receives the value.
 * @return FLT_OK, or a status as for flt_genicam_get_int().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_get_float(flt_genicam *description,
                                                                const char *feature, double *out);

/**
 * The value of a string feature, or the entry name of an enumeration.
 * @param description the description.
 * @param feature the feature's name.
 * @param out receives a string valid until the next call on the handle.
 * @return FLT_OK, or a status as for flt_genicam_get_int().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_get_string(flt_genicam *description,
                                                                 const char *feature,
                                                                 const char **out);

/**
 * An integer feature's bounds (pMin/pMax/pInc, or its register's range).
 * Without a bound: INT64_MIN / INT64_MAX, inc 1. Any output may be NULL.
 * @param description the description.
 * @param feature the feature's name.
 * @param min_out receives the minimum.
 * @param max_out receives the maximum.
 * @param inc_out receives the increment.
 * @return FLT_OK, or a status as for flt_genicam_get_int().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_int_bounds(flt_genicam *description,
                                                                 const char *feature,
                                                                 int64_t *min_out, int64_t *max_out,
                                                                 int64_t *inc_out);

/** A float feature's bounds; without a bound -DBL_MAX / DBL_MAX.
 * @param description the description.
 * @param feature the feature's name.
 * @param min_out receives the minimum.
 * @param max_out receives the maximum.
 * @return FLT_OK, or a status as for flt_genicam_get_int().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_float_bounds(flt_genicam *description,
                                                                   const char *feature,
                                                                   double *min_out,
                                                                   double *max_out);

/** The number of entries of an enumeration.
 * @param description the description.
 * @param feature the enumeration's name.
 * @param out receives the number of entries.
 * @return FLT_OK, or a status as for flt_genicam_get_int().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_enum_count(flt_genicam *description,
                                                                 const char *feature, size_t *out);

/**
 * Entry `index` of an enumeration.
 * @param description the description.
 * @param feature   the enumeration's name.
 * @param index     0 .. count-1 (flt_genicam_enum_count()).
 * @param name_out      owned by the handle, valid until it is destroyed;
 * @param value_out     the entry's integer;
 * @param available_out 1 when the entry is implemented and available now.
 * Any output may be NULL. FLT_ERR_NOT_FOUND past the last entry.
 * @return FLT_OK, or a status as for flt_genicam_get_int().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_enum_entry(flt_genicam *description,
                                                                 const char *feature, size_t index,
                                                                 const char **name_out,
                                                                 int64_t *value_out,
                                                                 int *available_out);

/* ---------------------------------------------------------------------- */
/* Writes (into the memory image or through the write callback)            */
/* ---------------------------------------------------------------------- */

/** Writes an integer, enumeration (by integer), boolean or float feature.
 * @param description the description.
 * @param feature the feature's name.
 * @param value the value.
 * @return FLT_OK; FLT_ERR_STATE for a feature a camera would not let be
 *         written now (read-only, locked, unavailable, unimplemented), or
 *         with a read callback but no write one; FLT_ERR_INVALID_ARGUMENT for a value
 *         outside its bounds or a feature of another type; otherwise as
 *         flt_genicam_get_int().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_set_int(flt_genicam *description,
                                                              const char *feature, int64_t value);

/** Writes a float feature (through its Converter formula if it has one).
 * @param description the description.
 * @param feature the feature's name.
 * @param value the value.
 * @return FLT_OK; FLT_ERR_STATE for a feature a camera would not let be
 *         written now (read-only, locked, unavailable, unimplemented), or
 *         with a read callback but no write one; FLT_ERR_INVALID_ARGUMENT for a value
 *         outside its bounds or a feature of another type; otherwise as
 *         flt_genicam_get_int().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_set_float(flt_genicam *description,
                                                                const char *feature, double value);

/** Writes a string feature, or an enumeration by entry name.
 * @param description the description.
 * @param feature the feature's name.
 * @param value the string, or the entry name.
 * @return FLT_OK; FLT_ERR_STATE for a feature a camera would not let be
 *         written now (read-only, locked, unavailable, unimplemented), or
 *         with a read callback but no write one; FLT_ERR_INVALID_ARGUMENT for a value
 *         outside its bounds or a feature of another type; otherwise as
 *         flt_genicam_get_int().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_set_string(flt_genicam *description,
                                                                 const char *feature,
                                                                 const char *value);

/** Executes a command (writes its command value).
 * @param description the description.
 * @param feature the command's name.
 * @return FLT_OK; FLT_ERR_STATE for a feature a camera would not let be
 *         written now (read-only, locked, unavailable, unimplemented), or
 *         with a read callback but no write one; FLT_ERR_INVALID_ARGUMENT for a value
 *         outside its bounds or a feature of another type; otherwise as
 *         flt_genicam_get_int().
 */
FLT_API FLT_NODISCARD flt_status FLT_CALL flt_genicam_execute(flt_genicam *description,
                                                              const char *feature);

#ifdef __cplusplus
}
#endif

#endif /* FLATLINE_GENICAM_H */
